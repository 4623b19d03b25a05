//! The `Device` as one CANopen node on virtual time: timestamped frame traces against the fixture
//! EDS of the checker (`base.eds`, node 5) and a real EDS of the corpus (CANopenNode's
//! `DS301_profile.eds`, node 10).

use canopener_can::Core;
use std::cell::RefCell;
use std::rc::Rc;

use canopener_can::{CanFrame, Instant};
use canopener_device::application::{AppChanges, Application, NoApplication};
use canopener_device::device::{self, Device, DeviceEvent};
use canopener_device::nmt_slave::NmtSlaveState;
use canopener_device::od_build::build_od;
use canopener_od::{DynamicOd, ObjectKey};
use proptest::prelude::*;

#[path = "common/bus.rs"]
mod bus;

use bus::{BASE, DS301, DeviceBus, booted, download, eds, ms};

fn base_device(node: u8) -> Device {
    Device::from_eds(&eds(BASE), node, Box::new(NoApplication)).expect("device")
}

fn ds301_device(node: u8) -> Device {
    Device::from_eds(&eds(&*DS301), node, Box::new(NoApplication)).expect("device")
}

#[test]
fn boot_up_then_heartbeats_at_the_1017h_period() {
    let mut built = build_od(&eds(BASE), 5).expect("builds");
    built
        .od
        .set_value(ObjectKey::new(0x1017, 0), &100u16.to_le_bytes())
        .expect("1017h");
    let mut bus = booted(Device::new(built.od, 5, Box::new(NoApplication)).expect("device"));
    assert_eq!(bus.core.state(), NmtSlaveState::PreOperational);
    bus.advance(ms(250));
    assert_eq!(bus.sent(), ["0.000 705#00", "100.000 705#7F", "200.000 705#7F"]);
}

#[test]
fn nmt_commands_through_frames() {
    let mut bus = booted(base_device(5));
    bus.rx(ms(0), &download(5, 0x1017, 0, &50u16.to_le_bytes()));
    bus.rx(ms(10), "000#0105");
    assert_eq!(bus.core.state(), NmtSlaveState::Operational);
    bus.rx(ms(20), "000#0205");
    assert_eq!(bus.core.state(), NmtSlaveState::Stopped);
    // SDO does not run in Stopped: no answer.
    bus.rx(ms(30), &download(5, 0x1017, 0, &60u16.to_le_bytes()));
    bus.rx(ms(40), "000#8000");
    assert_eq!(bus.core.state(), NmtSlaveState::PreOperational);
    // A command for another node changes nothing.
    bus.rx(ms(45), "000#0106");
    assert_eq!(bus.core.state(), NmtSlaveState::PreOperational);
    assert_eq!(
        bus.sent(),
        [
            "0.000 705#00",
            "0.000 585#6017100000000000",
            "10.000 705#05",
            // Entering Operational sends the event-driven TPDO once.
            "10.000 185#00",
            "20.000 705#04",
            "40.000 705#7F",
        ]
    );
    // Reset communication: 1017h goes back to its default 0, boot-up, no more heartbeats.
    bus.rx(ms(50), "000#8205");
    bus.advance(ms(500));
    assert_eq!(bus.sent(), ["50.000 705#00"]);
    assert_eq!(bus.value(0x1017, 0), [0, 0]);
    bus.rx(ms(600), "000#8105");
    assert_eq!(bus.sent(), ["600.000 705#00"]);
    let events = bus.take_events();
    assert!(events.contains(&DeviceEvent::Nmt(
        canopener_device::nmt_slave::NmtEvent::ResetApplication
    )));
}

#[test]
fn sdo_expedited_read_of_1018h_sub_1() {
    let mut bus = booted(base_device(5));
    bus.rx(ms(1), "605#4018100100000000");
    assert_eq!(bus.sent(), ["0.000 705#00", "1.000 585#43181001BC0A0000"]);
}

#[test]
fn sdo_write_to_1017h_changes_the_heartbeat_period() {
    let mut bus = booted(base_device(5));
    bus.rx(ms(0), &download(5, 0x1017, 0, &100u16.to_le_bytes()));
    bus.advance(ms(250));
    bus.rx(ms(250), &download(5, 0x1017, 0, &20u16.to_le_bytes()));
    bus.advance(ms(300));
    assert_eq!(
        bus.sent(),
        [
            "0.000 705#00",
            "0.000 585#6017100000000000",
            "100.000 705#7F",
            "200.000 705#7F",
            "250.000 585#6017100000000000",
            "270.000 705#7F",
            "290.000 705#7F",
        ]
    );
    assert!(bus.take_events().iter().any(|e| matches!(
        e,
        DeviceEvent::Sdo {
            server: 0x1200,
            event: canopener_device::sdo_server::Event::Written { .. }
        }
    )));
}

#[test]
fn pdo_remapped_over_sdo_then_sent_on_sync() {
    let mut bus = booted(base_device(5));
    // The input 6000h:01 (ro), mapped again after clearing the mapping. (The output 6200h:01 is rww,
    // which only an RPDO may map.)
    bus.core
        .od_mut()
        .set_value(ObjectKey::new(0x6000, 1), &[0x5A])
        .expect("6000h");
    // CiA 301 mapping procedure: invalidate, clear, map, count, type 1 (every SYNC), validate.
    bus.rx(ms(1), &download(5, 0x1800, 1, &0x8000_0185u32.to_le_bytes()));
    bus.rx(ms(2), &download(5, 0x1A00, 0, &[0]));
    bus.rx(ms(3), &download(5, 0x1A00, 1, &0x6000_0108u32.to_le_bytes()));
    bus.rx(ms(4), &download(5, 0x1A00, 0, &[1]));
    bus.rx(ms(5), &download(5, 0x1800, 2, &[1]));
    bus.rx(ms(6), &download(5, 0x1800, 1, &0x0000_0185u32.to_le_bytes()));
    let sent = bus.sent();
    assert_eq!(sent.len(), 7, "{sent:?}");
    assert!(sent[1..].iter().all(|s| s.contains(" 585#60")), "{sent:?}");
    bus.rx(ms(10), "000#0105");
    bus.rx(ms(20), "080#");
    bus.rx(ms(30), "080#");
    assert_eq!(bus.sent(), ["20.000 185#5A", "30.000 185#5A"]);
}

#[test]
fn pdo_mapping_refusals_are_abort_codes() {
    let mut bus = booted(base_device(5));
    // Mapping written while the TPDO is valid: 0601 0000h (CANopenNode, CCT set).
    bus.rx(ms(1), &download(5, 0x1A00, 1, &0x6200_0108u32.to_le_bytes()));
    bus.rx(ms(2), &download(5, 0x1800, 1, &0x8000_0185u32.to_le_bytes()));
    bus.rx(ms(3), &download(5, 0x1A00, 0, &[0]));
    // 2000h is not mappable: 0604 0041h.
    bus.rx(ms(4), &download(5, 0x1A00, 1, &0x2000_0010u32.to_le_bytes()));
    let sent = bus.sent();
    assert_eq!(sent[1], "1.000 585#80001A0100000106");
    assert_eq!(sent[4], "4.000 585#80001A0141000406");
}

/// Records what the device tells the application.
struct Recorder(Rc<RefCell<Vec<ObjectKey>>>);

impl Application for Recorder {
    fn reset(&mut self, _now: Instant, _od: &mut DynamicOd) -> AppChanges {
        AppChanges::none()
    }
    fn on_write(&mut self, _now: Instant, key: ObjectKey, _od: &mut DynamicOd) -> AppChanges {
        self.0.borrow_mut().push(key);
        AppChanges::none()
    }
    fn handle_timeout(&mut self, _now: Instant, _od: &mut DynamicOd) -> AppChanges {
        AppChanges::none()
    }
    fn poll_timeout(&self) -> Option<Instant> {
        None
    }
}

#[test]
fn rpdo_is_written_into_the_od_and_told_to_the_application() {
    let writes = Rc::new(RefCell::new(Vec::new()));
    let dev = Device::from_eds(&eds(BASE), 5, Box::new(Recorder(writes.clone()))).expect("device");
    let mut bus = booted(dev);
    // Not in Pre-operational.
    bus.rx(ms(1), "205#AB");
    assert_eq!(bus.value(0x6200, 1), [0]);
    bus.rx(ms(2), "000#0105");
    bus.rx(ms(3), "205#AB");
    assert_eq!(bus.value(0x6200, 1), [0xAB]);
    assert_eq!(*writes.borrow(), [ObjectKey::new(0x6200, 1)]);
    // Too short: not processed, EMCY 8210h with the communication error bit.
    bus.rx(ms(4), "205#");
    assert_eq!(
        bus.sent(),
        ["0.000 705#00", "2.000 185#00", "4.000 085#1082110100000000"]
    );
    // The right length again clears it: error reset EMCY.
    bus.rx(ms(5), "205#01");
    assert_eq!(bus.sent(), ["5.000 085#0000000000000000"]);
}

#[test]
fn application_change_sends_the_event_driven_tpdo() {
    let mut bus = booted(base_device(5));
    bus.rx(ms(1), "000#0105");
    bus.advance(ms(1));
    bus.core
        .od_mut()
        .set_value(ObjectKey::new(0x6000, 1), &[0x0F])
        .expect("6000h");
    bus.core
        .app_changed(Instant::from_millis(2), &[ObjectKey::new(0x6000, 1)]);
    bus.advance(ms(3));
    assert_eq!(bus.sent(), ["0.000 705#00", "1.000 185#00", "2.000 185#0F"]);
}

#[test]
fn emcy_when_a_consumed_heartbeat_is_lost() {
    let mut bus = booted(ds301_device(10));
    bus.rx(ms(0), &download(10, 0x1016, 1, &0x0003_0064u32.to_le_bytes()));
    bus.rx(ms(10), "703#05");
    bus.advance(ms(200));
    bus.rx(ms(300), "703#05");
    assert_eq!(
        bus.sent(),
        [
            "0.000 70A#00",
            "0.000 58A#6016100100000000",
            "110.000 08A#3081110300000000",
            "300.000 08A#0000000000000000",
        ]
    );
    assert_eq!(bus.value(0x1001, 0), [0]);
    assert_eq!(bus.value(0x1003, 0), [1]);
    // Error code in bits 15..0, the first two manufacturer bytes (the node-ID lost) above.
    assert_eq!(bus.value(0x1003, 1), 0x0003_8130u32.to_le_bytes());
    let events = bus.take_events();
    assert!(events.iter().any(|e| matches!(
        e,
        DeviceEvent::EmcySent {
            code: 0x8130,
            register: 0x11,
            ..
        }
    )));
}

#[test]
fn device_check_refusals() {
    let mut bus = booted(ds301_device(10));
    // 1016h: the same node twice, 0604 0043h.
    bus.rx(ms(1), &download(10, 0x1016, 1, &0x0003_0064u32.to_le_bytes()));
    bus.rx(ms(2), &download(10, 0x1016, 2, &0x0003_0064u32.to_le_bytes()));
    // 1014h with a restricted CAN-ID (after invalidating): 0609 0030h.
    bus.rx(ms(3), &download(10, 0x1014, 0, &0x8000_008Au32.to_le_bytes()));
    bus.rx(ms(4), &download(10, 0x1014, 0, &0x0000_0701u32.to_le_bytes()));
    // 1010h:01 without the signature: 0800 0020h.
    bus.rx(ms(5), &download(10, 0x1010, 1, b"wron"));
    // 1003h:01 with no error stored: 0800 0024h.
    bus.rx(ms(6), "60A#4003100100000000");
    // 1003h:00 = 1: 0609 0030h.
    bus.rx(ms(7), &download(10, 0x1003, 0, &[1]));
    // 1019h reserved value 1: 0609 0030h.
    bus.rx(ms(8), &download(10, 0x1019, 0, &[1]));
    // 1012h with a 29-bit CAN-ID: 0609 0030h.
    bus.rx(ms(9), &download(10, 0x1012, 0, &0x2000_0100u32.to_le_bytes()));
    let sent = bus.sent();
    assert_eq!(
        sent[1..],
        [
            "1.000 58A#6016100100000000",
            "2.000 58A#8016100243000406",
            "3.000 58A#6014100000000000",
            "4.000 58A#8014100030000906",
            "5.000 58A#8010100120000008",
            "6.000 58A#8003100124000008",
            "7.000 58A#8003100030000906",
            "8.000 58A#8019100030000906",
            "9.000 58A#8012100030000906",
        ]
    );
}

#[test]
fn store_keeps_a_value_over_reset_node_and_restore_reverts_it() {
    let mut bus = booted(ds301_device(10));
    bus.rx(ms(1), &download(10, 0x1017, 0, &500u16.to_le_bytes()));
    bus.rx(ms(2), &download(10, 0x1010, 1, b"save"));
    bus.rx(ms(3), "000#810A");
    assert_eq!(bus.value(0x1017, 0), 500u16.to_le_bytes());
    // 1010h:01 reads the capability, not the signature.
    assert_eq!(bus.value(0x1010, 1), 1u32.to_le_bytes());
    bus.rx(ms(4), &download(10, 0x1011, 1, b"load"));
    // Restore takes effect at the next reset, not at once.
    assert_eq!(bus.value(0x1017, 0), 500u16.to_le_bytes());
    bus.rx(ms(5), "000#810A");
    assert_eq!(bus.value(0x1017, 0), [0, 0]);
    let sent = bus.sent();
    assert!(sent.contains(&"3.000 70A#00".to_string()), "{sent:?}");
    assert!(sent.contains(&"5.000 70A#00".to_string()), "{sent:?}");
}

#[test]
fn store_on_reset_communication_keeps_communication_parameters() {
    let mut bus = booted(ds301_device(10));
    bus.rx(ms(1), &download(10, 0x1017, 0, &100u16.to_le_bytes()));
    bus.rx(ms(2), &download(10, 0x1010, 2, b"save"));
    bus.rx(ms(3), &download(10, 0x1017, 0, &0u16.to_le_bytes()));
    bus.rx(ms(4), "000#820A");
    bus.advance(ms(104));
    let sent = bus.sent();
    assert_eq!(sent[sent.len() - 2..], ["4.000 70A#00", "104.000 70A#7F"]);
}

#[test]
fn lss_configured_node_id_takes_effect_at_reset_communication() {
    let mut bus = booted(base_device(5));
    bus.rx(ms(1), "7E5#0401000000000000");
    bus.rx(ms(2), "7E5#1120000000000000");
    bus.rx(ms(3), "7E5#0400000000000000");
    assert_eq!(bus.core.node_id().get(), 5);
    bus.rx(ms(4), "000#8205");
    assert_eq!(bus.core.node_id().get(), 0x20);
    assert_eq!(
        bus.sent(),
        ["0.000 705#00", "2.000 7E4#1100000000000000", "4.000 720#00"]
    );
    // The default SDO server and the $NODEID defaults follow the new node-ID.
    bus.rx(ms(5), "620#4018100100000000");
    assert_eq!(bus.sent(), ["5.000 5A0#43181001BC0A0000"]);
    assert_eq!(bus.value(0x1800, 1), 0x1A0u32.to_le_bytes());
    assert!(
        bus.take_events()
            .iter()
            .any(|e| matches!(e, DeviceEvent::NodeIdChanged { .. }))
    );
}

#[test]
fn build_notes_are_kept() {
    let dev = ds301_device(10);
    // Whatever the file departs in, the notes are readable.
    for note in dev.notes() {
        assert!(!note.to_string().is_empty());
    }
    assert!(Device::from_eds(&eds(BASE), 0, Box::new(NoApplication)).is_err());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn arbitrary_frames_never_panic(
        frames in proptest::collection::vec(
            (0u16..0x800, proptest::bool::ANY, proptest::collection::vec(any::<u8>(), 0..=8), 0u64..50),
            0..60,
        )
    ) {
        for dev in [base_device(5), ds301_device(10)] {
            let mut bus = booted(dev);
            let mut t = 0;
            bus.rx(ms(0), "000#0100");
            for (id, remote, data, dt) in &frames {
                t += dt;
                bus.advance(ms(t));
                let id = canopener_can::StandardId::new(*id).expect("11-bit");
                let frame = if *remote {
                    CanFrame::remote(id, data.len() as u8).expect("dlc")
                } else {
                    CanFrame::new(id, data).expect("<= 8")
                };
                bus.core.handle_frame(bus.now, &frame);
                bus.drain();
            }
            bus.advance(ms(t + 5_000));
        }
    }
}

/// A device from the EDS at `path` with `extra` entries added to its dictionary.
fn device_with(path: &str, node: u8, extra: Vec<canopener_od::Entry>) -> Device {
    let od = build_od(&eds(path), node).expect("od").od;
    let capacity = od.len() + extra.len();
    let od = DynamicOd::from_entries(capacity, od.iter().cloned().chain(extra)).expect("dictionary");
    Device::new(od, node, Box::new(NoApplication)).expect("device")
}

fn u8_array(index: u16, values: &[u8]) -> Vec<canopener_od::Entry> {
    use canopener_od::{Access, DataType, Entry};
    let count = u8::try_from(values.len()).expect("few subs");
    let mut entries = vec![
        Entry::new(
            ObjectKey::new(index, 0),
            DataType::UNSIGNED8,
            Access::Const,
            &[count],
        )
        .expect("sub 0"),
    ];
    for (sub, value) in (1..).zip(values) {
        entries.push(
            Entry::new(
                ObjectKey::new(index, sub),
                DataType::UNSIGNED8,
                Access::Rw,
                &[*value],
            )
            .expect("entry"),
        );
    }
    entries
}

#[test]
fn unconfigured_device_is_silent_except_lss_until_fastscan_and_configuration() {
    let dev = Device::from_eds(&eds(BASE), device::UNCONFIGURED, Box::new(NoApplication)).expect("device");
    let mut bus = booted(dev);
    assert!(!bus.core.is_configured());
    // No boot-up, no heartbeat, no NMT, no SDO: the node has no node-ID (CiA 305).
    bus.rx(ms(10), "000#0100");
    bus.rx(ms(20), "601#4018100100000000");
    bus.advance(ms(5_000));
    assert_eq!(bus.sent(), Vec::<String>::new());
    assert_eq!(bus.core.state(), NmtSlaveState::Initialisation);
    // Identify non-configured remote slave, and the fastscan probe, are answered.
    bus.rx(ms(5_001), "7E5#4C00000000000000");
    bus.rx(ms(5_002), "7E5#5100000000800000");
    assert_eq!(
        bus.sent(),
        ["5001.000 7E4#5000000000000000", "5002.000 7E4#4F00000000000000"]
    );
    // Configuration: switch state global, configure node-ID 20h, store, back to waiting.
    bus.rx(ms(5_003), "7E5#0401000000000000");
    bus.rx(ms(5_004), "7E5#1120000000000000");
    bus.rx(ms(5_005), "7E5#1700000000000000");
    bus.rx(ms(5_006), "7E5#0400000000000000");
    assert!(bus.core.is_configured());
    assert_eq!(bus.core.node_id().get(), 0x20);
    assert_eq!(
        bus.sent(),
        [
            "5004.000 7E4#1100000000000000",
            "5005.000 7E4#1700000000000000",
            "5006.000 720#00"
        ]
    );
    assert!(bus.take_events().iter().any(|e| matches!(
        e,
        DeviceEvent::NodeIdChanged { from: None, to } if to.get() == 0x20
    )));
    // Now a node like any other: SDO on 620h/5A0h with the $NODEID defaults of node 20h.
    bus.rx(ms(5_010), "620#4018100100000000");
    assert_eq!(bus.sent(), ["5010.000 5A0#43181001BC0A0000"]);
    assert_eq!(bus.value(0x1800, 1), 0x1A0u32.to_le_bytes());
}

#[test]
fn unconfigured_start_needs_lss_and_a_serial_number_override_sets_the_lss_address() {
    let mut od = build_od(&eds(BASE), 1).expect("od").od;
    od.remove(ObjectKey::new(0x1018, 1));
    let refused = Device::new(od, device::UNCONFIGURED, Box::new(NoApplication)).unwrap_err();
    assert!(refused.to_string().contains("1018h"), "{refused}");

    let dev = Device::from_eds(&eds(BASE), device::UNCONFIGURED, Box::new(NoApplication))
        .expect("device")
        .with_value(ObjectKey::new(0x1018, 4), &0x0001_2345u32.to_le_bytes())
        .expect("serial");
    let mut bus = booted(dev);
    bus.rx(ms(1), "7E5#0401000000000000");
    bus.rx(ms(2), "7E5#5D00000000000000");
    assert_eq!(bus.sent(), ["2.000 7E4#5D45230100000000"]);
    // The override survives the rebuilt defaults of the node-ID LSS gives.
    bus.rx(ms(3), "7E5#1107000000000000");
    bus.rx(ms(4), "7E5#0400000000000000");
    bus.rx(ms(5), "607#4018100400000000");
    assert_eq!(
        bus.sent(),
        [
            "3.000 7E4#1100000000000000",
            "4.000 707#00",
            "5.000 587#4318100445230100"
        ]
    );
}

#[test]
fn nmt_startup_1f80h_bit_2_clear_makes_the_device_start_on_its_own() {
    use canopener_od::{Access, DataType, Entry};
    for (value, state) in [
        (0x0000_0000u32, NmtSlaveState::Operational),
        (0x0000_0004, NmtSlaveState::PreOperational),
    ] {
        let entry = Entry::new(
            ObjectKey::new(0x1F80, 0),
            DataType::UNSIGNED32,
            Access::Rw,
            &value.to_le_bytes(),
        );
        let dev = device_with(BASE, 5, vec![entry.expect("entry")]);
        let bus = booted(dev);
        assert_eq!(bus.core.state(), state, "1F80h = {value:#x}");
    }
    // Without 1F80h the device waits for the NMT master.
    assert_eq!(booted(base_device(5)).core.state(), NmtSlaveState::PreOperational);
}

#[test]
fn error_behaviour_1029h_on_a_lost_heartbeat() {
    for (reaction, after) in [
        (0u8, NmtSlaveState::PreOperational),
        (1, NmtSlaveState::Operational),
        (2, NmtSlaveState::Stopped),
    ] {
        let dev = device_with(&DS301, 10, u8_array(0x1029, &[reaction, 1]));
        let mut bus = booted(dev);
        bus.rx(ms(0), "000#010A");
        bus.rx(ms(1), &download(10, 0x1016, 1, &0x0003_0064u32.to_le_bytes()));
        bus.rx(ms(10), "703#05");
        assert_eq!(bus.core.state(), NmtSlaveState::Operational);
        bus.advance(ms(200));
        assert_eq!(bus.core.state(), after, "1029h sub 1 = {reaction}");
        assert!(bus.sent().iter().any(|f| f.ends_with("08A#3081110300000000")));
    }
}

/// CiA 301 1029h: a device that detects a communication error while operational enters
/// pre-operational by default; 1029h only makes the reaction configurable. CCT Heartbeat 07 expects
/// EMCY 8130h and that change from a device without 1029h.
#[test]
fn a_missing_1029h_enters_pre_operational_on_a_lost_heartbeat() {
    let mut bus = booted(ds301_device(10));
    assert!(
        bus.core.od().object(0x1029).is_empty(),
        "the fixture has no 1029h"
    );
    bus.rx(ms(0), "000#010A");
    bus.rx(ms(1), &download(10, 0x1016, 1, &0x0003_0064u32.to_le_bytes()));
    bus.rx(ms(10), "703#05");
    assert_eq!(bus.core.state(), NmtSlaveState::Operational);
    bus.advance(ms(200));
    assert_eq!(bus.core.state(), NmtSlaveState::PreOperational);
    let sent = bus.sent();
    assert!(
        sent.contains(&"110.000 08A#3081110300000000".to_string()),
        "{sent:?}"
    );
    // A lost heartbeat in pre-operational or stopped changes nothing.
    for command in ["000#800A", "000#020A"] {
        let mut bus = booted(ds301_device(10));
        bus.rx(ms(0), &download(10, 0x1016, 1, &0x0003_0064u32.to_le_bytes()));
        bus.rx(ms(1), command);
        let before = bus.core.state();
        bus.rx(ms(10), "703#05");
        bus.advance(ms(200));
        assert_eq!(bus.core.state(), before, "after {command}");
    }
}

#[test]
fn an_extension_adds_the_cia401_test_registers_to_a_real_cia401_eds_and_survives_a_new_node_id() {
    let io = eds(canopener_testkit::corpus::eds(
        "CANopenNode__CANopenNode__example__IO.eds",
    ));
    let plain = Device::from_eds(&io, 5, Box::new(NoApplication)).expect("device");
    assert!(!plain.od().object(0x6000).is_empty(), "a CiA 401 EDS");
    assert!(
        plain.od().object(0x2001).is_empty(),
        "without the factory test registers"
    );
    let extended = Device::from_eds_extended(&io, 5, Box::new(NoApplication), |od, node| {
        canopener_device::cia401::install_objects(od, node)
            .map(drop)
            .map_err(|err| err.to_string())
    })
    .expect("device");
    let mut bus = booted(extended);
    for index in [0x2000, 0x2001, 0x2002] {
        assert!(!bus.core.od().object(index).is_empty(), "{index:04X}h added");
    }
    // LSS gives node-ID 9: the power-on dictionary is rebuilt for it, the registers stay.
    bus.rx(ms(1), "7E5#0401000000000000");
    bus.rx(ms(2), "7E5#1109000000000000");
    bus.rx(ms(3), "7E5#0400000000000000");
    bus.rx(ms(4), "000#8205");
    assert_eq!(bus.core.node_id().get(), 9);
    assert!(!bus.core.od().object(0x2001).is_empty());
    bus.rx(ms(5), "609#4001200000000000");
    assert!(
        bus.sent().iter().any(|f| f.starts_with("5.000 589#4")),
        "2001h answered"
    );
}

#[test]
fn a_time_producer_sends_the_time_its_driver_gives() {
    use canopener_wire::TimeOfDay;
    let time = TimeOfDay {
        millis: 0x0123_4567,
        days: 0x3A98,
    };
    let mut bus = booted(ds301_device(10));
    assert!(!bus.core.is_time_producer(), "1012h = 100h: no producer");
    assert!(bus.core.produce_time(bus.now, time).is_err());
    // 1012h bit 30: this node produces TIME (CiA 301); TIME runs in Pre-operational.
    bus.rx(ms(1), &download(10, 0x1012, 0, &0x4000_0100u32.to_le_bytes()));
    assert!(bus.core.is_time_producer());
    bus.sent();
    bus.core.produce_time(bus.now, time).expect("producer");
    assert_eq!(bus.sent(), ["1.000 100#67452301983A"]);
    // Stopped runs no TIME.
    bus.rx(ms(2), "000#020A");
    assert!(bus.core.produce_time(bus.now, time).is_err());
}

/// CiA 301 §7.2.5.1 and 1007h: synchronous RPDOs that arrive after the synchronous window has closed
/// are discarded until the next SYNC (lely's RPDO does so); one inside the window is written at the
/// next SYNC.
#[test]
fn a_synchronous_rpdo_after_the_window_is_discarded_until_the_next_sync() {
    use canopener_od::{Access, DataType, Entry};
    let window = Entry::new(
        ObjectKey::new(0x1007, 0),
        DataType::UNSIGNED32,
        Access::Rw,
        &5_000u32.to_le_bytes(),
    )
    .expect("1007h");
    let mut bus = booted(device_with(BASE, 5, vec![window]));
    // RPDO1 (200h + 5, 6200h:01) synchronous, then Operational.
    bus.rx(ms(0), &download(5, 0x1400, 2, &[1]));
    bus.rx(ms(1), "000#0105");
    bus.rx(ms(10), "080#");
    bus.rx(ms(12), "205#AA");
    bus.rx(ms(20), "080#");
    assert_eq!(
        bus.value(0x6200, 1),
        [0xAA],
        "inside the window: written at the next SYNC"
    );
    // The window after the SYNC at 20 ms closed at 25 ms.
    bus.rx(ms(26), "205#55");
    bus.rx(ms(30), "080#");
    assert_eq!(bus.value(0x6200, 1), [0xAA], "after the window: discarded");
    // The SYNC at 30 ms opened a new window: RPDOs count again.
    bus.rx(ms(31), "205#0F");
    bus.rx(ms(40), "080#");
    assert_eq!(bus.value(0x6200, 1), [0x0F]);
    let events = bus.take_events();
    assert!(
        events.iter().any(|e| matches!(
            e,
            DeviceEvent::Pdo(canopener_device::pdo::PdoEvent::RpdoLate { number: 1 })
        )),
        "{events:?}"
    );
}

/// The mapping refusals that used 0604 0043h answer with a code of the set CiA's CCT accepts for
/// that mapping step (reference §3.4, CCT PDO 23–32): sub-index 0 = FEh/FFh (MPDO) is a count the
/// device cannot take, 0604 0042h; a mapping length of 0 and a variable-length object are entries
/// that cannot be mapped, 0604 0041h.
#[test]
fn pdo_mapping_refusals_use_codes_the_cct_accepts() {
    use canopener_od::{Access, DataType, Entry};
    let text = Entry::new(
        ObjectKey::new(0x2100, 0),
        DataType::VISIBLE_STRING,
        Access::Rw,
        b"abcd",
    )
    .expect("entry")
    .with_pdo_mapping(true);
    let mut bus = booted(device_with(BASE, 5, vec![text]));
    bus.rx(ms(1), &download(5, 0x1800, 1, &0x8000_0185u32.to_le_bytes()));
    bus.rx(ms(2), &download(5, 0x1A00, 0, &[0]));
    bus.rx(ms(3), &download(5, 0x1A00, 0, &[0xFE]));
    bus.rx(ms(4), &download(5, 0x1A00, 0, &[0xFF]));
    bus.rx(ms(5), &download(5, 0x1A00, 1, &0x6000_0100u32.to_le_bytes()));
    bus.rx(ms(6), &download(5, 0x1A00, 1, &0x2100_0020u32.to_le_bytes()));
    let sent = bus.sent();
    assert_eq!(
        sent[3..],
        [
            "3.000 585#80001A0042000406",
            "4.000 585#80001A0042000406",
            "5.000 585#80001A0141000406",
            "6.000 585#80001A0141000406",
        ]
    );
}

/// CiA 305 store configuration with the default (in-memory) storage: the stored node-ID is what
/// the device starts with again after NMT reset node, its power cycle, even when another node-ID
/// was configured (and not stored) since.
#[test]
fn an_lss_stored_node_id_survives_reset_node_in_the_default_storage() {
    let mut bus = booted(base_device(5));
    bus.rx(ms(1), "7E5#0401000000000000");
    bus.rx(ms(2), "7E5#1120000000000000");
    bus.rx(ms(3), "7E5#1700000000000000");
    bus.rx(ms(4), "7E5#1130000000000000");
    bus.rx(ms(5), "7E5#0400000000000000");
    assert_eq!(
        bus.sent()[1..],
        [
            "2.000 7E4#1100000000000000",
            "3.000 7E4#1700000000000000",
            "4.000 7E4#1100000000000000",
        ]
    );
    bus.rx(ms(6), "000#8105");
    assert_eq!(
        bus.core.node_id().get(),
        0x20,
        "the stored node-ID, not the pending 30h"
    );
    assert_eq!(bus.sent(), ["6.000 720#00"]);
    // Reset communication keeps the stored one (nothing new pending).
    bus.rx(ms(7), "000#8220");
    assert_eq!(bus.core.node_id().get(), 0x20);
}

/// A device that takes SDO downloads only outside Operational refuses them there with 0800 0022h
/// (data cannot be transferred or stored because of the present device state), in every transfer
/// mode; uploads still work, and Pre-operational takes downloads again.
#[test]
fn a_device_locked_in_operational_refuses_downloads_with_0800_0022h() {
    let mut bus = booted(base_device(5).with_downloads_refused_in_operational());
    bus.rx(ms(1), &download(5, 0x1017, 0, &100u16.to_le_bytes()));
    bus.rx(ms(2), "000#0105");
    bus.rx(ms(3), &download(5, 0x1017, 0, &200u16.to_le_bytes()));
    bus.rx(ms(4), "605#2117100002000000");
    bus.rx(ms(5), "605#C617100002000000");
    bus.rx(ms(6), "605#4017100000000000");
    bus.rx(ms(7), "000#8005");
    bus.rx(ms(8), &download(5, 0x1017, 0, &0u16.to_le_bytes()));
    let sdo: Vec<String> = bus.sent().into_iter().filter(|f| f.contains(" 585#")).collect();
    assert_eq!(
        sdo,
        [
            "1.000 585#6017100000000000",
            "3.000 585#8017100022000008",
            "4.000 585#8017100022000008",
            "5.000 585#8017100022000008",
            "6.000 585#4B17100064000000",
            "8.000 585#6017100000000000",
        ]
    );
}

#[test]
fn a_sync_consumer_that_misses_its_sync_raises_emcy_8100h_and_clears_it_on_the_next() {
    // CANopenNode's SYNC timeout: 1.5 × 1006h after the last SYNC, EMCY 8100h with the
    // communication bit, recorded in 1003h; the next SYNC resets it.
    let mut bus = booted(ds301_device(10));
    bus.rx(ms(1), &download(10, 0x1006, 0, &10_000u32.to_le_bytes()));
    bus.rx(ms(2), "080#");
    bus.advance(ms(30));
    bus.rx(ms(30), "080#");
    let sent = bus.sent();
    assert!(
        sent.contains(&"17.000 08A#0081110000000000".to_owned()),
        "{sent:?}"
    );
    assert!(
        sent.contains(&"30.000 08A#0000000000000000".to_owned()),
        "{sent:?}"
    );
    assert_eq!(bus.value(0x1003, 1)[..2], [0x00, 0x81]);
}

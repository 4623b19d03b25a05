//! The fault catalogue on the wire: every fault of [`Fault::ALL`] shown as a timestamped frame
//! trace on virtual time, next to the same scenario on a device without the fault. Devices are
//! built from the checker's fixture `base.eds` (node 5), and from CANopenNode's
//! `DS301_profile.eds` (node 10) where a fault needs objects `base.eds` lacks (SYNC producer,
//! store/restore).

use canopener_can::Core;
use std::time::Duration;

use canopener_can::{CanFrame, Instant};
use canopener_device::application::NoApplication;
use canopener_device::device::{Device, DeviceEvent};
use canopener_device::faults::{Fault, FaultSet};
use canopener_device::nmt_slave::NmtSlaveState;
use canopener_od::ObjectKey;

#[path = "common/bus.rs"]
mod bus;

use bus::{BASE, Bus, DS301, DeviceBus, booted, download, eds, ms};

fn device(path: &str, node: u8, faults: FaultSet) -> Device {
    Device::from_eds(&eds(path), node, Box::new(NoApplication))
        .expect("device")
        .with_faults(faults)
}

/// Runs `scenario` on a correct device and on one with `fault`; returns both traces.
fn both(path: &str, node: u8, fault: Fault, scenario: impl Fn(&mut Bus)) -> (Vec<String>, Vec<String>) {
    let mut traces = [FaultSet::none(), FaultSet::from(fault)].map(|faults| {
        let mut bus = booted(device(path, node, faults));
        assert_eq!(bus.core.faults(), faults);
        scenario(&mut bus);
        bus.sent()
    });
    let faulty = std::mem::take(&mut traces[1]);
    (std::mem::take(&mut traces[0]), faulty)
}

fn base(fault: Fault, scenario: impl Fn(&mut Bus)) -> (Vec<String>, Vec<String>) {
    both(BASE, 5, fault, scenario)
}

fn hb(period_ms: u16) -> String {
    download(5, 0x1017, 0, &period_ms.to_le_bytes())
}

#[test]
fn every_fault_has_a_test_here() {
    let text =
        canopener_testkit::fixture::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/faults.rs"))
            .expect("this file");
    for fault in Fault::ALL {
        let name = format!("fn {}(", fault.name().replace('-', "_"));
        assert!(text.contains(&name), "no test `{name}`");
    }
}

#[test]
fn no_boot_up() {
    let (ok, bad) = base(Fault::NoBootUp, |bus| bus.rx(ms(10), "000#8205"));
    assert_eq!(ok, ["0.000 705#00", "10.000 705#00"]);
    assert_eq!(bad, Vec::<String>::new());
}

#[test]
fn boot_up_wrong_id() {
    let (ok, bad) = base(Fault::BootUpWrongId, |bus| bus.rx(ms(10), "000#8105"));
    assert_eq!(ok, ["0.000 705#00", "10.000 705#00"]);
    assert_eq!(bad, ["0.000 706#00", "10.000 706#00"]);
}

#[test]
fn heartbeat_state_wrong() {
    let (ok, bad) = base(Fault::HeartbeatStateWrong, |bus| {
        bus.rx(ms(0), &hb(100));
        bus.advance(ms(150));
        bus.rx(ms(150), "000#0105");
        bus.advance(ms(250));
        bus.rx(ms(260), "000#0205");
        bus.advance(ms(360));
    });
    let heartbeats = |trace: Vec<String>| -> Vec<String> {
        trace
            .into_iter()
            .skip(1)
            .filter(|s| s.contains(" 705#"))
            .collect()
    };
    // A state change sends a heartbeat at once and restarts the period.
    assert_eq!(
        heartbeats(ok),
        [
            "100.000 705#7F",
            "150.000 705#05",
            "250.000 705#05",
            "260.000 705#04",
            "360.000 705#04"
        ]
    );
    // A wrong but valid state in every NMT state (a state table read one row off): a consumer sees
    // the node in the wrong state, never a frame it must drop as invalid.
    assert_eq!(
        heartbeats(bad),
        [
            "100.000 705#05",
            "150.000 705#04",
            "250.000 705#04",
            "260.000 705#7F",
            "360.000 705#7F"
        ]
    );
}

#[test]
fn heartbeat_state_wrong_guarding_answers_keep_the_toggle_bit() {
    let (ok, bad) = base(Fault::HeartbeatStateWrong, |bus| {
        bus.rx(ms(10), "705#R1");
        bus.rx(ms(20), "705#R1");
        bus.rx(ms(30), "000#0105");
        bus.rx(ms(40), "705#R1");
    });
    let answers = |trace: Vec<String>| -> Vec<String> {
        trace
            .into_iter()
            .skip(1)
            .filter(|s| s.contains(" 705#"))
            .collect()
    };
    assert_eq!(answers(ok), ["10.000 705#7F", "20.000 705#FF", "40.000 705#05"]);
    assert_eq!(answers(bad), ["10.000 705#05", "20.000 705#85", "40.000 705#04"]);
}

#[test]
fn heartbeat_too_fast() {
    let (ok, bad) = base(Fault::HeartbeatTooFast, |bus| {
        bus.rx(ms(0), &hb(100));
        bus.advance(ms(250));
    });
    assert_eq!(ok[2..], ["100.000 705#7F", "200.000 705#7F"]);
    assert_eq!(
        bad[2..],
        [
            "100.000 705#7F",
            "101.000 705#7F",
            "200.000 705#7F",
            "201.000 705#7F"
        ]
    );
}

#[test]
fn heartbeat_jitter() {
    let (ok, bad) = base(Fault::HeartbeatJitter, |bus| {
        bus.rx(ms(0), &hb(100));
        bus.advance(ms(450));
    });
    assert_eq!(
        ok[2..],
        [
            "100.000 705#7F",
            "200.000 705#7F",
            "300.000 705#7F",
            "400.000 705#7F"
        ]
    );
    assert_eq!(
        bad[2..],
        [
            "100.000 705#7F",
            "240.000 705#7F",
            "300.000 705#7F",
            "440.000 705#7F"
        ]
    );
}

#[test]
fn guarding_and_heartbeat() {
    let (ok, bad) = base(Fault::GuardingAndHeartbeat, |bus| {
        // Guarding alone is answered by both.
        bus.rx(ms(1), "705#R1");
        bus.rx(ms(2), &hb(100));
        bus.rx(ms(50), "705#R1");
        bus.rx(ms(60), "705#R1");
    });
    assert_eq!(ok, ["0.000 705#00", "1.000 705#7F", "2.000 585#6017100000000000"]);
    assert_eq!(
        bad,
        [
            "0.000 705#00",
            "1.000 705#7F",
            "2.000 585#6017100000000000",
            "50.000 705#7F",
            "60.000 705#FF",
        ]
    );
}

#[test]
fn ignores_nmt_stop() {
    let (ok, bad) = base(Fault::IgnoresNmtStop, |bus| {
        bus.rx(ms(1), "000#0205");
        bus.rx(ms(2), "605#4018100100000000");
        bus.rx(ms(3), "000#0200");
    });
    assert_eq!(ok, ["0.000 705#00"]);
    assert_eq!(bad, ["0.000 705#00", "2.000 585#43181001BC0A0000"]);
    let mut stopped = booted(device(BASE, 5, FaultSet::none()));
    stopped.rx(ms(1), "000#0205");
    assert_eq!(stopped.core.state(), NmtSlaveState::Stopped);
    let mut faulty = booted(device(BASE, 5, Fault::IgnoresNmtStop.into()));
    faulty.rx(ms(1), "000#0205");
    assert_eq!(faulty.core.state(), NmtSlaveState::PreOperational);
}

#[test]
fn nmt_broadcast_ignored() {
    let (ok, bad) = base(Fault::NmtBroadcastIgnored, |bus| {
        bus.rx(ms(1), "000#0100");
        bus.rx(ms(2), "205#AB");
        bus.rx(ms(3), "000#0105");
        bus.rx(ms(4), "205#CD");
    });
    // Operational from the broadcast: the RPDO at 2 ms is taken, 6200h:01 = ABh (no frame).
    assert_eq!(ok, ["0.000 705#00", "1.000 185#00"]);
    // Only the addressed command works.
    assert_eq!(bad, ["0.000 705#00", "3.000 185#00"]);
}

#[test]
fn sdo_toggle_ignored() {
    let scenario = |bus: &mut Bus| {
        // Segmented download of 1017h, 2 bytes in two 1-byte segments, both with toggle 0.
        bus.rx(ms(1), "605#2117100002000000");
        bus.rx(ms(2), "605#0C64000000000000");
        bus.rx(ms(3), "605#0D00000000000000");
    };
    let (ok, bad) = base(Fault::SdoToggleIgnored, scenario);
    assert_eq!(
        ok,
        [
            "0.000 705#00",
            "1.000 585#6017100000000000",
            "2.000 585#2000000000000000",
            "3.000 585#8017100000000305",
        ]
    );
    assert_eq!(
        bad,
        [
            "0.000 705#00",
            "1.000 585#6017100000000000",
            "2.000 585#2000000000000000",
            "3.000 585#3000000000000000",
        ]
    );
    let mut faulty = booted(device(BASE, 5, Fault::SdoToggleIgnored.into()));
    scenario(&mut faulty);
    assert_eq!(faulty.value(0x1017, 0), [0x64, 0]);
}

#[test]
fn sdo_slow() {
    let scenario = |bus: &mut Bus| {
        bus.rx(ms(1), "605#4018100100000000");
        bus.advance(ms(1_000));
    };
    let (ok, bad) = base(Fault::SdoSlow, scenario);
    assert_eq!(ok, ["0.000 705#00", "1.000 585#43181001BC0A0000"]);
    assert_eq!(bad, ["0.000 705#00", "601.000 585#43181001BC0A0000"]);
    // The delay is configurable.
    let faults = FaultSet::from(Fault::SdoSlow).with_sdo_delay(Duration::from_millis(50));
    let mut bus = booted(device(BASE, 5, faults));
    scenario(&mut bus);
    assert_eq!(bus.sent(), ["0.000 705#00", "51.000 585#43181001BC0A0000"]);
}

#[test]
fn sdo_expedited_size_wrong() {
    let (ok, bad) = base(Fault::SdoExpeditedSizeWrong, |bus| {
        bus.rx(ms(1), "605#4017100000000000");
        bus.rx(ms(2), "605#4018100100000000");
    });
    assert_eq!(
        ok[1..],
        ["1.000 585#4B17100000000000", "2.000 585#43181001BC0A0000"]
    );
    assert_eq!(
        bad[1..],
        ["1.000 585#4317100000000000", "2.000 585#43181001BC0A0000"]
    );
}

#[test]
fn wrong_abort_code() {
    let (ok, bad) = base(Fault::WrongAbortCode, |bus| {
        bus.rx(ms(1), "605#4000300000000000");
        bus.rx(ms(2), &download(5, 0x1000, 0, &[0, 0, 0, 0]));
    });
    assert_eq!(
        ok[1..],
        ["1.000 585#8000300000000206", "2.000 585#8000100002000106"]
    );
    assert_eq!(
        bad[1..],
        ["1.000 585#8000300000000008", "2.000 585#8000100000000008"]
    );
}

#[test]
fn sdo_bad_command_silent() {
    let (ok, bad) = base(Fault::SdoBadCommandSilent, |bus| {
        bus.rx(ms(1), "605#E000000000000000");
        bus.rx(ms(2), "605#4018100100000000");
    });
    assert_eq!(
        ok[1..],
        ["1.000 585#8000000001000405", "2.000 585#43181001BC0A0000"]
    );
    assert_eq!(bad[1..], ["2.000 585#43181001BC0A0000"]);
}

#[test]
fn block_crc_wrong() {
    let scenario = |bus: &mut Bus| {
        // Block upload of 1018h:01 with CRC, protocol switch threshold 0.
        bus.rx(ms(1), "605#A41810017F000000");
        bus.rx(ms(2), "605#A300000000000000");
        bus.rx(ms(3), "605#A2017F0000000000");
        bus.rx(ms(4), "605#A100000000000000");
    };
    let (ok, bad) = base(Fault::BlockCrcWrong, scenario);
    assert_eq!(ok.len(), 4, "{ok:?}");
    assert_eq!(ok[..3], bad[..3]);
    let (good_end, bad_end) = (&ok[3], &bad[3]);
    assert!(good_end.starts_with("3.000 585#CD"), "{good_end}");
    let crc = |s: &str| u16::from_str_radix(&format!("{}{}", &s[14..16], &s[12..14]), 16).unwrap();
    // CRC-16-CCITT (XModem) of BC 0A 00 00.
    assert_eq!(crc(good_end), 0x7922, "{good_end}");
    assert_eq!(crc(bad_end), !0x7922, "{bad_end}");
}

/// How an SDO download is carried out.
#[derive(Debug, Clone, Copy)]
enum Mode {
    Expedited,
    Segmented,
    Block,
}

const MODES: [Mode; 3] = [Mode::Expedited, Mode::Segmented, Mode::Block];

/// The client's frames of a download of `data` (at most 7 bytes) to node 5 in `mode`: segmented
/// and block downloads carry it in one segment, the block download without CRC.
fn requests(mode: Mode, index: u16, sub: u8, data: &[u8]) -> Vec<String> {
    let frame = |mut bytes: Vec<u8>| {
        bytes.resize(8, 0);
        let hex: String = bytes.iter().map(|b| format!("{b:02X}")).collect();
        format!("605#{hex}")
    };
    let initiate = |command: u8| {
        let mut bytes = vec![command, index as u8, (index >> 8) as u8, sub];
        bytes.extend((data.len() as u32).to_le_bytes());
        frame(bytes)
    };
    let unused = 7 - data.len() as u8;
    match mode {
        Mode::Expedited => vec![download(5, index, sub, data)],
        Mode::Segmented => vec![initiate(0x21), frame([&[unused << 1 | 1][..], data].concat())],
        Mode::Block => vec![
            initiate(0xC2),
            frame([&[0x81][..], data].concat()),
            frame(vec![0xC1 | unused << 2]),
        ],
    }
}

/// Carries out the download on `bus` from time `at` (one frame a millisecond); returns the
/// server's last answer.
fn download_in(bus: &mut Bus, at: u64, mode: Mode, index: u16, sub: u8, data: &[u8]) -> String {
    for (i, request) in (0..).zip(requests(mode, index, sub, data)) {
        bus.rx(ms(at + i), &request);
    }
    let answers: Vec<String> = bus.sent().into_iter().filter(|f| f.contains(" 585#")).collect();
    let last = answers.last().expect("an answer");
    last.split_once(' ').expect("stamped").1.to_string()
}

/// What the server answers when it took the download in `mode`.
fn confirmed(mode: Mode) -> &'static str {
    match mode {
        Mode::Expedited => "585#60",
        Mode::Segmented => "585#20",
        Mode::Block => "585#A1",
    }
}

/// A fault that makes the device accept a download it must refuse holds in every transfer mode:
/// `prepare` writes what the refused download needs (expedited), then the download goes in each
/// mode to a correct device (refused with `abort`) and to the faulty one (confirmed and stored).
fn accepted_in_every_mode(fault: Fault, prepare: &[(u16, u8, &[u8])], refused: (u16, u8, &[u8]), abort: u32) {
    let (index, sub, data) = refused;
    for mode in MODES {
        for faults in [FaultSet::none(), FaultSet::from(fault)] {
            let mut bus = booted(device(BASE, 5, faults));
            for (i, (index, sub, data)) in (1..).zip(prepare) {
                bus.rx(ms(i), &download(5, *index, *sub, data));
            }
            let answer = download_in(&mut bus, 10, mode, index, sub, data);
            if faults.is_empty() {
                let code: String = abort.to_le_bytes().iter().map(|b| format!("{b:02X}")).collect();
                assert!(
                    answer.starts_with("585#80") && answer.ends_with(&code),
                    "{mode:?}: {answer}"
                );
            } else {
                assert!(answer.starts_with(confirmed(mode)), "{fault} {mode:?}: {answer}");
                assert_eq!(bus.value(index, sub), data, "{fault} {mode:?}");
            }
        }
    }
}

#[test]
fn limit_not_enforced_in_every_transfer_mode() {
    accepted_in_every_mode(
        Fault::LimitNotEnforced,
        &[],
        (0x2000, 0, &2000u16.to_le_bytes()),
        0x0609_0031,
    );
}

#[test]
fn unmappable_accepted_in_every_transfer_mode() {
    accepted_in_every_mode(
        Fault::UnmappableAccepted,
        &[(0x1800, 1, &0x8000_0185u32.to_le_bytes()), (0x1A00, 0, &[0])],
        (0x1A00, 1, &0x2000_0010u32.to_le_bytes()),
        0x0604_0041,
    );
}

#[test]
fn pdo_cob_id_unchecked_in_every_transfer_mode() {
    accepted_in_every_mode(
        Fault::PdoCobIdUnchecked,
        &[(0x1800, 1, &0x8000_0185u32.to_le_bytes())],
        (0x1800, 1, &0x701u32.to_le_bytes()),
        0x0609_0030,
    );
}

#[test]
fn limit_not_enforced() {
    let scenario = |bus: &mut Bus| bus.rx(ms(1), &download(5, 0x2000, 0, &2000u16.to_le_bytes()));
    let (ok, bad) = base(Fault::LimitNotEnforced, scenario);
    assert_eq!(ok[1..], ["1.000 585#8000200031000906"]);
    assert_eq!(bad[1..], ["1.000 585#6000200000000000"]);
    let mut faulty = booted(device(BASE, 5, Fault::LimitNotEnforced.into()));
    scenario(&mut faulty);
    faulty.sent();
    assert_eq!(faulty.value(0x2000, 0), 2000u16.to_le_bytes());
    // Writes within the limits are unchanged.
    faulty.rx(ms(2), &download(5, 0x2000, 0, &500u16.to_le_bytes()));
    assert_eq!(faulty.sent(), ["2.000 585#6000200000000000"]);
    assert_eq!(faulty.value(0x2000, 0), 500u16.to_le_bytes());
}

#[test]
fn unmappable_accepted() {
    let scenario = |bus: &mut Bus| {
        bus.rx(ms(1), &download(5, 0x1800, 1, &0x8000_0185u32.to_le_bytes()));
        bus.rx(ms(2), &download(5, 0x1A00, 0, &[0]));
        bus.rx(ms(3), &download(5, 0x1A00, 1, &0x2000_0010u32.to_le_bytes()));
    };
    let (ok, bad) = base(Fault::UnmappableAccepted, scenario);
    assert_eq!(ok[3], "3.000 585#80001A0141000406");
    assert_eq!(bad[3], "3.000 585#60001A0100000000");
    let mut faulty = booted(device(BASE, 5, Fault::UnmappableAccepted.into()));
    scenario(&mut faulty);
    assert_eq!(faulty.value(0x1A00, 1), 0x2000_0010u32.to_le_bytes());
}

#[test]
fn pdo_cob_id_unchecked() {
    let scenario = |bus: &mut Bus| {
        bus.rx(ms(1), &download(5, 0x1800, 1, &0x8000_0185u32.to_le_bytes()));
        bus.rx(ms(2), &download(5, 0x1800, 1, &0x0000_0701u32.to_le_bytes()));
    };
    let (ok, bad) = base(Fault::PdoCobIdUnchecked, scenario);
    assert_eq!(ok[2], "2.000 585#8000180130000906");
    assert_eq!(bad[2], "2.000 585#6000180100000000");
    let mut faulty = booted(device(BASE, 5, Fault::PdoCobIdUnchecked.into()));
    scenario(&mut faulty);
    assert_eq!(faulty.value(0x1800, 1), 0x701u32.to_le_bytes());
}

#[test]
fn no_tpdo_rtr() {
    let (ok, bad) = base(Fault::NoTpdoRtr, |bus| {
        bus.rx(ms(1), "000#0105");
        bus.rx(ms(2), "185#R1");
        // Node guarding (also a remote frame) still works.
        bus.rx(ms(3), "705#R1");
    });
    assert_eq!(
        ok,
        ["0.000 705#00", "1.000 185#00", "2.000 185#00", "3.000 705#05"]
    );
    assert_eq!(bad, ["0.000 705#00", "1.000 185#00", "3.000 705#05"]);
}

/// Operational, then an RPDO too short (EMCY 8210h) and one of the right length (error reset).
fn rpdo_length_error(bus: &mut Bus) {
    bus.rx(ms(1), "000#0105");
    bus.rx(ms(2), "205#");
    bus.rx(ms(3), "205#01");
}

#[test]
fn no_emcy() {
    let (ok, bad) = base(Fault::NoEmcy, rpdo_length_error);
    assert_eq!(
        ok,
        [
            "0.000 705#00",
            "1.000 185#00",
            "2.000 085#1082110100000000",
            "3.000 085#0000000000000000",
        ]
    );
    assert_eq!(bad, ["0.000 705#00", "1.000 185#00"]);
    // The error is still recorded.
    let mut faulty = booted(device(BASE, 5, Fault::NoEmcy.into()));
    faulty.rx(ms(1), "000#0105");
    faulty.rx(ms(2), "205#");
    assert_eq!(faulty.value(0x1001, 0), [0x11]);
    assert!(
        !faulty
            .take_events()
            .iter()
            .any(|e| matches!(e, DeviceEvent::EmcySent { .. }))
    );
}

#[test]
fn emcy_no_error_reset() {
    let (ok, bad) = base(Fault::EmcyNoErrorReset, rpdo_length_error);
    assert_eq!(
        ok[2..],
        ["2.000 085#1082110100000000", "3.000 085#0000000000000000"]
    );
    assert_eq!(bad[2..], ["2.000 085#1082110100000000"]);
}

#[test]
fn store_ignored() {
    let scenario = |bus: &mut Bus| {
        bus.rx(ms(1), &download(10, 0x1017, 0, &500u16.to_le_bytes()));
        bus.rx(ms(2), &download(10, 0x1010, 1, b"save"));
        bus.rx(ms(3), "000#810A");
    };
    let (ok, bad) = both(&DS301, 10, Fault::StoreIgnored, scenario);
    // Both confirm the save.
    assert_eq!(ok[2], "2.000 58A#6010100100000000");
    assert_eq!(bad[2], "2.000 58A#6010100100000000");
    // Only the correct device heartbeats at 500 ms after the reset.
    let mut correct = booted(device(&DS301, 10, FaultSet::none()));
    scenario(&mut correct);
    correct.advance(ms(600));
    let mut faulty = booted(device(&DS301, 10, Fault::StoreIgnored.into()));
    scenario(&mut faulty);
    faulty.advance(ms(600));
    assert_eq!(correct.value(0x1017, 0), 500u16.to_le_bytes());
    assert_eq!(faulty.value(0x1017, 0), [0, 0]);
    assert_eq!(correct.sent().last().map(String::as_str), Some("503.000 70A#7F"));
    assert_eq!(faulty.sent().last().map(String::as_str), Some("3.000 70A#00"));
}

#[test]
fn sync_counter_missing() {
    let (ok, bad) = both(&DS301, 10, Fault::SyncCounterMissing, |bus| {
        bus.rx(ms(1), &download(10, 0x1019, 0, &[3]));
        bus.rx(ms(2), &download(10, 0x1006, 0, &10_000u32.to_le_bytes()));
        bus.rx(ms(3), &download(10, 0x1005, 0, &0x4000_0080u32.to_le_bytes()));
        bus.advance(ms(45));
    });
    assert_eq!(
        ok[4..],
        ["13.000 080#01", "23.000 080#02", "33.000 080#03", "43.000 080#01"]
    );
    assert_eq!(
        bad[4..],
        ["13.000 080#", "23.000 080#", "33.000 080#", "43.000 080#"]
    );
}

#[test]
fn no_lss() {
    let (ok, bad) = base(Fault::NoLss, |bus| {
        bus.rx(ms(1), "7E5#0401000000000000");
        bus.rx(ms(2), "7E5#5E00000000000000");
    });
    assert_eq!(ok[1..], ["2.000 7E4#5E05000000000000"]);
    assert_eq!(bad[1..], Vec::<String>::new());
}

#[test]
fn lss_state_not_changed() {
    let scenario = |bus: &mut Bus| {
        // Switch state selective with 1018h of base.eds, then configure node-ID 20h.
        bus.rx(ms(1), "7E5#40BC0A0000000000");
        bus.rx(ms(2), "7E5#4101040000000000");
        bus.rx(ms(3), "7E5#4202000100000000");
        bus.rx(ms(4), "7E5#4300000000000000");
        bus.rx(ms(5), "7E5#1120000000000000");
    };
    let (ok, bad) = base(Fault::LssStateNotChanged, scenario);
    assert_eq!(
        ok[1..],
        ["4.000 7E4#4400000000000000", "5.000 7E4#1100000000000000"]
    );
    assert_eq!(bad[1..], Vec::<String>::new());
    // Switch state global is ignored as well.
    let (ok, bad) = base(Fault::LssStateNotChanged, |bus| {
        bus.rx(ms(1), "7E5#0401000000000000");
        bus.rx(ms(2), "7E5#1120000000000000");
    });
    assert_eq!(ok[1..], ["2.000 7E4#1100000000000000"]);
    assert_eq!(bad[1..], Vec::<String>::new());
}

/// An event timer of 10 ms on TPDO1 (185h, type FFh), set in pre-operational.
fn tpdo_event_timer(bus: &mut Bus) {
    bus.rx(ms(1), &download(5, 0x1800, 5, &10u16.to_le_bytes()));
}

#[test]
fn tpdo_in_pre_operational() {
    let (ok, bad) = base(Fault::TpdoInPreOperational, |bus| {
        tpdo_event_timer(bus);
        bus.advance(ms(25));
        // An RPDO in pre-operational is still ignored.
        bus.rx(ms(26), "205#AB");
    });
    assert_eq!(ok, ["0.000 705#00", "1.000 585#6000180500000000"]);
    assert_eq!(
        bad,
        [
            "0.000 705#00",
            "0.000 185#00",
            "1.000 585#6000180500000000",
            "1.000 185#00",
            "11.000 185#00",
            "21.000 185#00",
        ]
    );
    let mut faulty = booted(device(BASE, 5, Fault::TpdoInPreOperational.into()));
    faulty.rx(ms(1), "205#AB");
    assert_eq!(faulty.value(0x6200, 1), [0]);
}

#[test]
fn rpdo_in_pre_operational() {
    let (ok, bad) = base(Fault::RpdoInPreOperational, |bus| {
        tpdo_event_timer(bus);
        bus.rx(ms(2), "205#AB");
        bus.advance(ms(25));
    });
    // No TPDO either way: only the RPDO is taken.
    assert_eq!(ok, bad);
    for (faults, value) in [
        (FaultSet::none(), 0x00),
        (Fault::RpdoInPreOperational.into(), 0xAB),
    ] {
        let mut bus = booted(device(BASE, 5, faults));
        bus.rx(ms(1), "205#AB");
        assert_eq!(bus.value(0x6200, 1), [value]);
        assert_eq!(bus.core.state(), NmtSlaveState::PreOperational);
    }
}

#[test]
fn pdo_in_stopped() {
    let (ok, bad) = base(Fault::PdoInStopped, |bus| {
        bus.rx(ms(1), "000#0105");
        bus.rx(ms(2), "000#0205");
        bus.rx(ms(3), "185#R1");
        bus.rx(ms(4), "205#CD");
    });
    assert_eq!(ok, ["0.000 705#00", "1.000 185#00"]);
    assert_eq!(ok[..], bad[..2]);
    assert_eq!(bad[2..], ["3.000 185#00"]);
    let mut faulty = booted(device(BASE, 5, Fault::PdoInStopped.into()));
    faulty.rx(ms(1), "000#0205");
    faulty.rx(ms(2), "205#CD");
    assert_eq!(faulty.value(0x6200, 1), [0xCD]);
    assert_eq!(faulty.core.state(), NmtSlaveState::Stopped);
}

#[test]
fn nmt_other_node_obeyed() {
    let (ok, bad) = base(Fault::NmtOtherNodeObeyed, |bus| {
        bus.rx(ms(1), "000#0106");
        bus.rx(ms(2), "000#817F");
    });
    assert_eq!(ok, ["0.000 705#00"]);
    // Started by the command to node 6 (TPDO1 on entering operational), reset by the one to 127.
    assert_eq!(bad, ["0.000 705#00", "1.000 185#00", "2.000 705#00"]);
}

#[test]
fn tpdo_invalid_sent() {
    let (ok, bad) = base(Fault::TpdoInvalidSent, |bus| {
        bus.rx(ms(1), &download(5, 0x1800, 1, &0x8000_0185u32.to_le_bytes()));
        tpdo_event_timer(bus);
        bus.rx(ms(2), "000#0105");
        bus.advance(ms(25));
    });
    assert_eq!(
        ok,
        [
            "0.000 705#00",
            "1.000 585#6000180100000000",
            "1.000 585#6000180500000000",
        ]
    );
    assert_eq!(ok[..], bad[..3]);
    assert_eq!(bad[3..], ["2.000 185#00", "12.000 185#00", "22.000 185#00"]);
    // The dictionary still holds what was written.
    let mut faulty = booted(device(BASE, 5, Fault::TpdoInvalidSent.into()));
    faulty.rx(ms(1), &download(5, 0x1800, 1, &0x8000_0185u32.to_le_bytes()));
    assert_eq!(faulty.value(0x1800, 1), 0x8000_0185u32.to_le_bytes());
}

#[test]
fn error_register_not_updated() {
    let (ok, bad) = base(Fault::ErrorRegisterNotUpdated, rpdo_length_error);
    assert_eq!(
        ok[2..],
        ["2.000 085#1082110100000000", "3.000 085#0000000000000000"]
    );
    assert_eq!(
        bad[2..],
        ["2.000 085#1082000100000000", "3.000 085#0000000000000000"]
    );
    for (faults, register) in [
        (FaultSet::none(), 0x11),
        (Fault::ErrorRegisterNotUpdated.into(), 0),
    ] {
        let mut bus = booted(device(BASE, 5, faults));
        bus.rx(ms(1), "000#0105");
        bus.rx(ms(2), "205#");
        assert_eq!(bus.value(0x1001, 0), [register]);
        // The EMCY producer itself keeps the register right: the fault acts around it.
        assert_eq!(bus.core.emcy().error_register(), 0x11);
    }
}

/// DS301_profile (node 10) consuming node 11's heartbeat with 1016h:01 = 100 ms; one heartbeat of
/// node 11 starts the monitoring, then the node is stopped and the heartbeat stays away.
fn consumer_lost_in_stopped(bus: &mut Bus) {
    bus.rx(ms(1), &download(10, 0x1016, 1, &0x000B_0064u32.to_le_bytes()));
    bus.rx(ms(2), "70B#05");
    bus.rx(ms(3), "000#020A");
    bus.advance(ms(250));
}

#[test]
fn emcy_in_stopped() {
    let (ok, bad) = both(&DS301, 10, Fault::EmcyInStopped, consumer_lost_in_stopped);
    assert_eq!(ok[1..], ["1.000 58A#6016100100000000"]);
    assert_eq!(ok[..], bad[..2]);
    assert_eq!(bad[2..], ["102.000 08A#3081110B00000000"]);
    // The correct device sends it once it may: in pre-operational.
    let mut correct = booted(device(&DS301, 10, FaultSet::none()));
    consumer_lost_in_stopped(&mut correct);
    correct.sent();
    correct.rx(ms(260), "000#800A");
    assert_eq!(correct.sent(), ["260.000 08A#3081110B00000000"]);
}

#[test]
fn sync_producer_in_stopped() {
    let (ok, bad) = both(&DS301, 10, Fault::SyncProducerInStopped, |bus| {
        bus.rx(ms(1), &download(10, 0x1006, 0, &10_000u32.to_le_bytes()));
        bus.rx(ms(2), &download(10, 0x1005, 0, &0x4000_0080u32.to_le_bytes()));
        bus.advance(ms(25));
        bus.rx(ms(25), "000#020A");
        bus.advance(ms(50));
    });
    assert_eq!(ok[3..], ["12.000 080#", "22.000 080#"]);
    assert_eq!(ok[..], bad[..5]);
    assert_eq!(bad[5..], ["32.000 080#", "42.000 080#"]);
}

#[test]
fn sdo_in_stopped() {
    let (ok, bad) = base(Fault::SdoInStopped, |bus| {
        bus.rx(ms(1), "000#0205");
        bus.rx(ms(2), "605#4018100100000000");
    });
    assert_eq!(ok, ["0.000 705#00"]);
    assert_eq!(bad, ["0.000 705#00", "2.000 585#43181001BC0A0000"]);
}

/// 2000h (DefaultValue 10) = 20 and 1017h (DefaultValue 0) = 100 ms, then `reset`.
fn values_then(reset: &'static str) -> impl Fn(&mut Bus) {
    move |bus: &mut Bus| {
        bus.rx(ms(1), &download(5, 0x2000, 0, &20u16.to_le_bytes()));
        bus.rx(ms(2), &hb(100));
        bus.rx(ms(3), reset);
    }
}

/// The values of 2000h and 1017h after `scenario` on a device with `faults`.
fn kept(faults: FaultSet, scenario: impl Fn(&mut Bus)) -> (Vec<u8>, Vec<u8>) {
    let mut bus = booted(device(BASE, 5, faults));
    scenario(&mut bus);
    (bus.value(0x2000, 0), bus.value(0x1017, 0))
}

#[test]
fn reset_communication_restores_application() {
    let fault = Fault::ResetCommunicationRestoresApplication;
    let scenario = values_then("000#8205");
    assert_eq!(kept(FaultSet::none(), &scenario), (vec![20, 0], vec![0, 0]));
    assert_eq!(kept(fault.into(), &scenario), (vec![10, 0], vec![0, 0]));
    // Reset node restores both areas either way.
    assert_eq!(
        kept(fault.into(), values_then("000#8105")),
        (vec![10, 0], vec![0, 0])
    );
}

#[test]
fn reset_communication_keeps_values() {
    let fault = Fault::ResetCommunicationKeepsValues;
    let (ok, bad) = base(fault, |bus| {
        values_then("000#8205")(bus);
        bus.advance(ms(250));
    });
    // The faulty device keeps its heartbeat of 100 ms after the boot-up.
    assert_eq!(ok[ok.len() - 1], "3.000 705#00");
    assert_eq!(
        bad[bad.len() - 3..],
        ["3.000 705#00", "103.000 705#7F", "203.000 705#7F"]
    );
    assert_eq!(
        kept(fault.into(), values_then("000#8205")),
        (vec![20, 0], vec![100, 0])
    );
    assert_eq!(
        kept(fault.into(), values_then("000#8105")),
        (vec![10, 0], vec![0, 0])
    );
}

#[test]
fn reset_node_as_reset_communication() {
    let fault = Fault::ResetNodeAsResetCommunication;
    let scenario = values_then("000#8105");
    assert_eq!(kept(FaultSet::none(), &scenario), (vec![10, 0], vec![0, 0]));
    assert_eq!(kept(fault.into(), &scenario), (vec![20, 0], vec![0, 0]));
}

#[test]
fn tpdo_config_silent() {
    let scenario = |bus: &mut Bus| {
        bus.rx(ms(1), &download(5, 0x1800, 1, &0x8000_0185u32.to_le_bytes()));
        bus.rx(ms(2), &download(5, 0x1800, 2, &[0xFE]));
        bus.rx(ms(3), &download(5, 0x1800, 5, &100u16.to_le_bytes()));
    };
    let (ok, bad) = base(Fault::TpdoConfigSilent, scenario);
    assert_eq!(
        ok[1..],
        [
            "1.000 585#6000180100000000",
            "2.000 585#6000180200000000",
            "3.000 585#6000180500000000"
        ]
    );
    // The COB-ID (sub-index 1) is still served; the settings get no answer and stay as they were.
    assert_eq!(bad[1..], ["1.000 585#6000180100000000"]);
    let mut faulty = booted(device(BASE, 5, Fault::TpdoConfigSilent.into()));
    scenario(&mut faulty);
    assert_eq!(faulty.value(0x1800, 2), [0xFF]);
}

#[test]
fn tpdo_config_refused() {
    let (ok, bad) = base(Fault::TpdoConfigRefused, |bus| {
        bus.rx(ms(1), &download(5, 0x1800, 1, &0x8000_0185u32.to_le_bytes()));
        bus.rx(ms(2), &download(5, 0x1800, 2, &[0xFE]));
        bus.rx(ms(3), &download(5, 0x1800, 3, &[0, 0]));
    });
    assert_eq!(
        ok[2..],
        ["2.000 585#6000180200000000", "3.000 585#6000180300000000"]
    );
    // The general error, which does not say the value is unsupported.
    assert_eq!(
        bad[1..],
        [
            "1.000 585#6000180100000000",
            "2.000 585#8000180200000008",
            "3.000 585#8000180300000008"
        ]
    );
}

#[test]
fn mapping_not_applied() {
    // TPDO1 mapped to 1001h:00 instead of 6000h:01 with the mapping procedure, then an error sets
    // 1001h to 11h, and a remote frame asks for TPDO1.
    let scenario = |bus: &mut Bus| {
        bus.rx(ms(1), &download(5, 0x1800, 1, &0x8000_0185u32.to_le_bytes()));
        bus.rx(ms(2), &download(5, 0x1A00, 0, &[0]));
        bus.rx(ms(3), &download(5, 0x1A00, 1, &0x1001_0008u32.to_le_bytes()));
        bus.rx(ms(4), &download(5, 0x1A00, 0, &[1]));
        bus.rx(ms(5), &download(5, 0x1800, 1, &0x0000_0185u32.to_le_bytes()));
        bus.rx(ms(6), "000#0105");
        bus.rx(ms(7), "205#");
        bus.rx(ms(8), "185#R1");
    };
    let (ok, bad) = base(Fault::MappingNotApplied, scenario);
    let tpdos =
        |trace: &[String]| -> Vec<String> { trace.iter().filter(|s| s.contains(" 185#")).cloned().collect() };
    assert_eq!(tpdos(&ok), ["6.000 185#00", "8.000 185#11"]);
    // Every write was confirmed and reads back, yet TPDO1 still carries 6000h:01.
    assert_eq!(ok[1..6], bad[1..6]);
    assert_eq!(tpdos(&bad), ["6.000 185#00", "8.000 185#00"]);
    let mut faulty = booted(device(BASE, 5, Fault::MappingNotApplied.into()));
    scenario(&mut faulty);
    assert_eq!(faulty.value(0x1A00, 1), 0x1001_0008u32.to_le_bytes());
    // A reset communication applies what is stored.
    faulty.sent();
    faulty.rx(ms(10), "000#8205");
    faulty.rx(ms(11), "000#0105");
    faulty.rx(ms(12), "185#R1");
    assert!(
        faulty
            .sent()
            .iter()
            .any(|s| s.starts_with("11.000 185#") || s.starts_with("12.000 185#")),
        "TPDO1 after the reset"
    );
}

#[test]
fn sync_producer_fast() {
    let (ok, bad) = both(&DS301, 10, Fault::SyncProducerFast, |bus| {
        bus.rx(ms(1), &download(10, 0x1019, 0, &[3]));
        bus.rx(ms(2), &download(10, 0x1006, 0, &10_000u32.to_le_bytes()));
        bus.rx(ms(3), &download(10, 0x1005, 0, &0x4000_0080u32.to_le_bytes()));
        bus.advance(ms(45));
    });
    let syncs =
        |trace: &[String]| -> Vec<String> { trace.iter().filter(|s| s.contains(" 080#")).cloned().collect() };
    assert_eq!(
        syncs(&ok),
        ["13.000 080#01", "23.000 080#02", "33.000 080#03", "43.000 080#01"]
    );
    // Every 5 ms, the counter still right.
    assert_eq!(
        syncs(&bad),
        [
            "8.000 080#01",
            "13.000 080#02",
            "18.000 080#03",
            "23.000 080#01",
            "28.000 080#02",
            "33.000 080#03",
            "38.000 080#01",
            "43.000 080#02"
        ]
    );
}

#[test]
fn tpdo_event_timer_fast() {
    let (ok, bad) = base(Fault::TpdoEventTimerFast, |bus| {
        bus.rx(ms(1), &download(5, 0x1800, 5, &100u16.to_le_bytes()));
        bus.rx(ms(2), "000#0105");
        bus.advance(ms(305));
    });
    let tpdos =
        |trace: &[String]| -> Vec<String> { trace.iter().filter(|s| s.contains(" 185#")).cloned().collect() };
    assert_eq!(
        tpdos(&ok),
        [
            "2.000 185#00",
            "102.000 185#00",
            "202.000 185#00",
            "302.000 185#00"
        ]
    );
    assert_eq!(tpdos(&bad).len(), 7, "{:?}", tpdos(&bad));
    assert_eq!(tpdos(&bad)[1], "52.000 185#00");
    let mut faulty = booted(device(BASE, 5, Fault::TpdoEventTimerFast.into()));
    faulty.rx(ms(1), &download(5, 0x1800, 5, &100u16.to_le_bytes()));
    assert_eq!(faulty.value(0x1800, 5), 100u16.to_le_bytes());
}

#[test]
fn emcy_generic_bit_clear() {
    let (ok, bad) = base(Fault::EmcyGenericBitClear, rpdo_length_error);
    assert_eq!(
        ok[2..],
        ["2.000 085#1082110100000000", "3.000 085#0000000000000000"]
    );
    // 10h as CANopenNode sends it: the communication bit without the generic bit.
    assert_eq!(
        bad[2..],
        ["2.000 085#1082100100000000", "3.000 085#0000000000000000"]
    );
    let mut faulty = booted(device(BASE, 5, Fault::EmcyGenericBitClear.into()));
    faulty.rx(ms(1), "000#0105");
    faulty.rx(ms(2), "205#");
    assert_eq!(faulty.value(0x1001, 0), [0x11]);
}

/// CANopenNode's demo device with the optional objects (1020h, sub-index FFh): the conformance
/// suite's `test_data/cia401_full_io.eds`.
const FULL_IO: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../canopener-conformance/test_data/cia401_full_io.eds"
);

/// The server's answers (585h) in a trace, without their time stamps.
fn answers(trace: &[String]) -> Vec<&str> {
    trace
        .iter()
        .filter_map(|f| f.split_once(' ').map(|(_, frame)| frame))
        .filter(|f| f.starts_with("585#") || f.starts_with("58A#"))
        .collect()
}

#[test]
fn device_type_byte_order() {
    let (ok, bad) = base(Fault::DeviceTypeByteOrder, |bus| {
        bus.rx(ms(1), "605#4000100000000000");
        // Other entries keep their byte order.
        bus.rx(ms(2), "605#4018100100000000");
    });
    assert_eq!(answers(&ok), ["585#4300100091010F00", "585#43181001BC0A0000"]);
    assert_eq!(answers(&bad), ["585#43001000000F0191", "585#43181001BC0A0000"]);
}

#[test]
fn segment_unused_wrong() {
    // 2120h:02 (UNSIGNED64) of the full demo device, segment by segment: 7 bytes, then 1 byte with
    // n = 6 unused, which the fault turns into n = 0.
    let (ok, bad) = both(FULL_IO, 5, Fault::SegmentUnusedWrong, |bus| {
        bus.rx(ms(1), "605#4020210200000000");
        bus.rx(ms(2), "605#6000000000000000");
        bus.rx(ms(3), "605#7000000000000000");
    });
    assert_eq!(answers(&ok)[..2], answers(&bad)[..2]);
    assert_eq!(answers(&ok)[2], "585#1D12000000000000");
    assert_eq!(answers(&bad)[2], "585#1112000000000000");
    // Expedited answers are not touched.
    let (ok, bad) = both(FULL_IO, 5, Fault::SegmentUnusedWrong, |bus| {
        bus.rx(ms(1), "605#4018100100000000");
    });
    assert_eq!(answers(&ok), answers(&bad));
}

#[test]
fn block_crc_required() {
    // Block upload of 1018h:01 without CRC (A0): refused; with CRC (A4): served as before.
    let (ok, bad) = base(Fault::BlockCrcRequired, |bus| {
        bus.rx(ms(1), "605#A01810017F000000");
        bus.rx(ms(2), "605#8018100100000008");
    });
    assert!(answers(&ok)[0].starts_with("585#C"), "{ok:?}");
    assert_eq!(answers(&bad)[0], "585#8018100101000405");
    let (ok, bad) = base(Fault::BlockCrcRequired, |bus| {
        bus.rx(ms(1), "605#A41810017F000000")
    });
    assert_eq!(answers(&ok), answers(&bad));
    // Block download of 1017h without CRC (C2): refused.
    let (ok, bad) = base(Fault::BlockCrcRequired, |bus| {
        bus.rx(ms(1), "605#C217100002000000")
    });
    assert!(answers(&ok)[0].starts_with("585#A"), "{ok:?}");
    assert_eq!(answers(&bad)[0], "585#8017100001000405");
}

#[test]
fn error_count_unchecked() {
    let (ok, bad) = both(&DS301, 10, Fault::ErrorCountUnchecked, |bus| {
        bus.rx(ms(1), &download(10, 0x1003, 0, &[1]));
        bus.rx(ms(2), &download(10, 0x1003, 0, &[0]));
    });
    assert_eq!(answers(&ok), ["58A#8003100030000906", "58A#6003100000000000"]);
    assert_eq!(answers(&bad), ["58A#6003100000000000", "58A#6003100000000000"]);
}

#[test]
fn structure_entry_wrong() {
    let (ok, bad) = both(FULL_IO, 5, Fault::StructureEntryWrong, |bus| {
        bus.rx(ms(1), "605#401810FF00000000");
        bus.rx(ms(2), "605#4018100000000000");
    });
    assert_eq!(answers(&ok), ["585#431810FF09230000", "585#4F18100004000000"]);
    assert_eq!(answers(&bad), ["585#431810FF23090000", "585#4F18100004000000"]);
}

#[test]
fn process_output_refused() {
    // ISD860's RPDO1: 6040h (controlword, rww, PDOMapping=1) mapped again by the procedure.
    let isd860 = canopener_testkit::corpus::eds(
        "ros-industrial__ros_canopen__canopen_chain_node__test__eds__ISD860.eds",
    )
    .display()
    .to_string();
    let scenario = |bus: &mut Bus| {
        bus.rx(ms(1), &download(5, 0x1400, 1, &0x8000_0205u32.to_le_bytes()));
        bus.rx(ms(2), &download(5, 0x1600, 0, &[0]));
        bus.rx(ms(3), &download(5, 0x1600, 1, &0x6040_0010u32.to_le_bytes()));
    };
    let (ok, bad) = both(&isd860, 5, Fault::ProcessOutputRefused, scenario);
    assert_eq!(answers(&ok)[2], "585#6000160100000000");
    assert_eq!(answers(&bad)[2], "585#8000160141000406");
    // A TPDO mapping is not affected.
    let (ok, bad) = both(&isd860, 5, Fault::ProcessOutputRefused, |bus| {
        bus.rx(ms(1), &download(5, 0x1800, 1, &0x8000_0185u32.to_le_bytes()));
        bus.rx(ms(2), &download(5, 0x1A00, 0, &[0]));
    });
    assert_eq!(answers(&ok), answers(&bad));
}

#[test]
fn mapping_procedure_unchecked() {
    // 1A00h:01 while TPDO1 is valid, then while 1A00h:00 is not 0: refused, unless the fault.
    let (ok, bad) = base(Fault::MappingProcedureUnchecked, |bus| {
        bus.rx(ms(1), &download(5, 0x1A00, 1, &0x6000_0108u32.to_le_bytes()));
        bus.rx(ms(2), &download(5, 0x1800, 1, &0x8000_0185u32.to_le_bytes()));
        bus.rx(ms(3), &download(5, 0x1A00, 1, &0x6000_0108u32.to_le_bytes()));
        // The entry itself is still checked: 2000h has PDOMapping=0.
        bus.rx(ms(4), &download(5, 0x1A00, 1, &0x2000_0010u32.to_le_bytes()));
    });
    let ok = answers(&ok);
    let bad = answers(&bad);
    assert!(
        ok[0].starts_with("585#80001A01") && ok[2].starts_with("585#80001A01"),
        "{ok:?}"
    );
    assert_eq!(bad[0], "585#60001A0100000000");
    assert_eq!(bad[2], "585#60001A0100000000");
    // The correct device refuses it for the procedure (0601 0000h), the faulty one for the entry.
    assert_eq!(ok[3], "585#80001A0100000106");
    assert_eq!(bad[3], "585#80001A0141000406");
}

#[test]
fn mapping_size_unchecked() {
    // 1A00h has one entry: sub-index 0 = 2 asks for too many objects.
    let (ok, bad) = base(Fault::MappingSizeUnchecked, |bus| {
        bus.rx(ms(1), &download(5, 0x1800, 1, &0x8000_0185u32.to_le_bytes()));
        bus.rx(ms(2), &download(5, 0x1A00, 0, &[0]));
        bus.rx(ms(3), &download(5, 0x1A00, 0, &[2]));
    });
    assert_eq!(answers(&ok)[2], "585#80001A0042000406");
    assert_eq!(answers(&bad)[2], "585#60001A0000000000");
}

#[test]
fn signature_unchecked() {
    let scenario = |bus: &mut Bus| {
        bus.rx(ms(1), &download(10, 0x1017, 0, &500u16.to_le_bytes()));
        bus.rx(ms(2), &download(10, 0x1010, 1, b"wron"));
        bus.rx(ms(3), "000#810A");
    };
    let (ok, bad) = both(&DS301, 10, Fault::SignatureUnchecked, scenario);
    assert_eq!(answers(&ok)[1], "58A#8010100120000008");
    assert_eq!(answers(&bad)[1], "58A#6010100100000000");
    // The faulty device saved: 1017h survives the reset.
    let mut faulty = booted(device(&DS301, 10, Fault::SignatureUnchecked.into()));
    scenario(&mut faulty);
    assert_eq!(faulty.value(0x1017, 0), 500u16.to_le_bytes());
}

#[test]
fn restore_ignored() {
    let scenario = |bus: &mut Bus| {
        bus.rx(ms(1), &download(10, 0x1017, 0, &500u16.to_le_bytes()));
        bus.rx(ms(2), &download(10, 0x1010, 1, b"save"));
        bus.rx(ms(3), &download(10, 0x1011, 1, b"load"));
        bus.rx(ms(4), "000#810A");
    };
    let (ok, bad) = both(&DS301, 10, Fault::RestoreIgnored, scenario);
    // Both confirm the restore.
    assert_eq!(answers(&ok)[2], "58A#6011100100000000");
    assert_eq!(answers(&bad)[2], "58A#6011100100000000");
    let mut correct = booted(device(&DS301, 10, FaultSet::none()));
    scenario(&mut correct);
    let mut faulty = booted(device(&DS301, 10, Fault::RestoreIgnored.into()));
    scenario(&mut faulty);
    assert_eq!(correct.value(0x1017, 0), [0, 0]);
    assert_eq!(faulty.value(0x1017, 0), 500u16.to_le_bytes());
}

#[test]
fn verify_configuration_not_stored() {
    let scenario = |bus: &mut Bus| {
        bus.rx(ms(1), &download(5, 0x1020, 1, &14_610u32.to_le_bytes()));
        bus.rx(ms(2), &download(5, 0x1017, 0, &500u16.to_le_bytes()));
        bus.rx(ms(3), &download(5, 0x1010, 1, b"save"));
        bus.rx(ms(4), "000#8105");
    };
    let mut correct = booted(device(FULL_IO, 5, FaultSet::none()));
    scenario(&mut correct);
    let mut faulty = booted(device(FULL_IO, 5, Fault::VerifyConfigurationNotStored.into()));
    scenario(&mut faulty);
    assert_eq!(correct.value(0x1020, 1), 14_610u32.to_le_bytes());
    assert_eq!(faulty.value(0x1020, 1), [0; 4]);
    // The rest was saved.
    assert_eq!(faulty.value(0x1017, 0), 500u16.to_le_bytes());
}

#[test]
fn tpdo_rtr_in_pre_operational() {
    // TPDO1 of base.eds (185h, RTR allowed, type 255) requested in pre-operational, then in
    // operational.
    let (ok, bad) = base(Fault::TpdoRtrInPreOperational, |bus| {
        bus.rx(ms(1), "185#R1");
        bus.rx(ms(2), "000#0105");
        bus.rx(ms(3), "185#R1");
    });
    let tpdos =
        |trace: &[String]| -> Vec<String> { trace.iter().filter(|f| f.contains(" 185#")).cloned().collect() };
    assert_eq!(tpdos(&ok), ["2.000 185#00", "3.000 185#00"]);
    assert_eq!(tpdos(&bad), ["1.000 185#00", "2.000 185#00", "3.000 185#00"]);
}

#[test]
fn without_faults_nothing_changes() {
    let mut plain = booted(Device::from_eds(&eds(BASE), 5, Box::new(NoApplication)).expect("device"));
    let mut none = booted(device(BASE, 5, FaultSet::none()));
    for bus in [&mut plain, &mut none] {
        bus.rx(ms(0), &hb(100));
        bus.rx(ms(1), "000#0105");
        bus.rx(ms(2), "605#4018100100000000");
        bus.advance(ms(250));
    }
    assert_eq!(plain.sent(), none.sent());
    assert!(plain.core.faults().is_empty());
    let _ = (Instant::ZERO, ObjectKey::new(0, 0));
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

    #[test]
    fn arbitrary_frames_never_panic_with_every_fault(
        frames in proptest::collection::vec(
            (
                0u16..0x800,
                proptest::bool::ANY,
                proptest::collection::vec(proptest::prelude::any::<u8>(), 0..=8),
                0u64..50,
            ),
            0..60,
        ),
        mask in 0u64..(1 << Fault::ALL.len()),
    ) {
        let faults: FaultSet = Fault::ALL
            .into_iter()
            .enumerate()
            .filter(|(i, _)| mask & (1 << i) != 0)
            .map(|(_, f)| f)
            .collect();
        for (path, node) in [(BASE, 5), (DS301.as_str(), 10)] {
            let mut bus = booted(device(path, node, faults));
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
            // Delayed frames drain: nothing is stuck in the fault layer.
            let until = bus.now.as_micros() / 1000 + 2_000;
            bus.advance(ms(until));
        }
    }
}

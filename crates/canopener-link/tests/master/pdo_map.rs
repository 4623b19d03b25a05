//! `pdo_map`: the CiA 301 §7.2.2 mapping procedure step by step against a device.

use std::time::Duration;

use canopener_link::pdo_map::{ReadCobIdError, execute, read_cob_id};
use canopener_link::sdo_session::SdoSession;
use canopener_master::pdo_config::{Direction, PdoConfig};
use canopener_master::pdo_map_report::{MapReport, StepOutcome};
use canopener_master::value::parse_mapping;
use canopener_wire::NodeId;

use crate::common::{BASE_EDS, IO_EDS, Node, bus, device, trace, value};

const SDO: [u32; 2] = [0x605, 0x585];

fn config(direction: Direction, number: u16, mapping: &[&str]) -> PdoConfig {
    PdoConfig::new(
        direction,
        number,
        mapping
            .iter()
            .map(|text| parse_mapping(text).expect("mapping"))
            .collect(),
    )
}

/// Maps `config` on node 5 behind `link`: the step lines, then the state left or the summary.
fn map(link: &mut canopener_link::virtual_link::VirtualLink<Node>, config: &PdoConfig) -> Vec<String> {
    let node = NodeId::new(5).expect("node");
    let mut session = SdoSession::new(link, 5, Duration::from_secs(1)).expect("session");
    let current = read_cob_id(&mut session, config).expect("COB-ID");
    let writes = config.plan(node, Some(current)).expect("plan");
    let mut report = MapReport::new(node, config, current, writes);
    let mut lines = Vec::new();
    execute(&mut session, &mut report, |report, step| {
        lines.push(report.step_line(step));
    })
    .expect("no bus error");
    for step in report.first_not_run()..report.steps.len() {
        lines.push(report.step_line(step));
    }
    match report.failure() {
        Some(failed) => lines.push(format!("left: {}", report.left_state(failed))),
        None => lines.push(report.summary()),
    }
    lines
}

#[test]
fn maps_a_tpdo_with_the_cia_301_procedure_as_a_frame_trace() {
    let (mut link, stations) = bus(vec![Node::Device(Box::new(device(IO_EDS, 5)))]);
    let mut config = config(Direction::Tpdo, 1, &["6000:01:8", "6401:01:16"]);
    config.transmission_type = Some(255);
    config.event_timer_ms = Some(100);
    trace(&mut link, &[]);
    assert_eq!(
        map(&mut link, &config),
        [
            "1/8 1800h:01 = 80000185h (make the PDO invalid while it changes): ok",
            "2/8 1A00h:00 = 00h (disable the mapping while its entries change): ok",
            "3/8 1A00h:01 = 60000108h (map 6000:01:8): ok",
            "4/8 1A00h:02 = 64010110h (map 6401:01:16): ok",
            "5/8 1A00h:00 = 02h (enable the mapping with its number of entries): ok",
            "6/8 1800h:02 = FFh (transmission type): ok",
            "7/8 1800h:05 = 0064h (event timer in ms): ok",
            "8/8 1800h:01 = 00000185h (make the PDO valid with its COB-ID): ok",
            "TPDO1 of node 5 configured: 6000:01:8 6401:01:16 (24 bits) on COB-ID 00000185h, valid",
        ]
    );
    assert_eq!(
        trace(&mut link, &SDO),
        [
            "0 605#4000180100000000",
            "0 585#4300180185010000",
            "0 605#2300180185010080",
            "0 585#6000180100000000",
            "0 605#2F001A0000000000",
            "0 585#60001A0000000000",
            "0 605#23001A0108010060",
            "0 585#60001A0100000000",
            "0 605#23001A0210010164",
            "0 585#60001A0200000000",
            "0 605#2F001A0002000000",
            "0 585#60001A0000000000",
            "0 605#2F001802FF000000",
            "0 585#6000180200000000",
            "0 605#2B00180564000000",
            "0 585#6000180500000000",
            "0 605#2300180185010000",
            "0 585#6000180100000000",
        ]
    );
    let station = stations[0];
    assert_eq!(value(&link, station, 0x1A00, 0), [2]);
    assert_eq!(value(&link, station, 0x1A00, 2), 0x6401_0110u32.to_le_bytes());
    assert_eq!(value(&link, station, 0x1800, 5), [100, 0]);
    assert_eq!(value(&link, station, 0x1800, 1), 0x185u32.to_le_bytes());
}

#[test]
fn a_refused_entry_stops_the_plan_and_says_what_state_the_pdo_is_in() {
    let (mut link, stations) = bus(vec![Node::Device(Box::new(device(IO_EDS, 5)))]);
    let lines = map(
        &mut link,
        &config(Direction::Tpdo, 1, &["6000:01:8", "1017:00:16"]),
    );
    assert_eq!(
        lines,
        [
            "1/6 1800h:01 = 80000185h (make the PDO invalid while it changes): ok",
            "2/6 1A00h:00 = 00h (disable the mapping while its entries change): ok",
            "3/6 1A00h:01 = 60000108h (map 6000:01:8): ok",
            "4/6 1A00h:02 = 10170010h (map 1017:00:16): SDO abort 0x06040041 from the server: Object cannot \
             be mapped to the PDO",
            "5/6 1A00h:00 = 02h (enable the mapping with its number of entries): not run",
            "6/6 1800h:01 = 00000185h (make the PDO valid with its COB-ID): not run",
            "left: TPDO1 is left invalid (COB-ID 80000185h) with its mapping disabled (1A00h:00 = 0, 1 of 2 \
             entries written)",
        ]
    );
    // The device is where the report says.
    let station = stations[0];
    assert_eq!(value(&link, station, 0x1800, 1), 0x8000_0185u32.to_le_bytes());
    assert_eq!(value(&link, station, 0x1A00, 0), [0]);
    assert_eq!(value(&link, station, 0x1A00, 1), 0x6000_0108u32.to_le_bytes());
}

#[test]
fn a_mapping_longer_than_the_device_takes_is_refused_by_the_device() {
    // base.eds: 1A00h has one entry only.
    let (mut link, _) = bus(vec![Node::Device(Box::new(device(BASE_EDS, 5)))]);
    let lines = map(
        &mut link,
        &config(Direction::Tpdo, 1, &["6000:01:8", "6000:01:8"]),
    );
    assert_eq!(
        lines[3],
        "4/6 1A00h:02 = 60000108h (map 6000:01:8): SDO abort 0x06090011 from the server: Sub-index does not \
         exist"
    );
}

#[test]
fn an_rpdo_is_mapped_through_1400h_and_1600h() {
    let (mut link, stations) = bus(vec![Node::Device(Box::new(device(IO_EDS, 5)))]);
    let mut config = config(Direction::Rpdo, 1, &["6200:01:8", "6200:02:8"]);
    config.transmission_type = Some(254);
    assert_eq!(
        map(&mut link, &config),
        [
            "1/7 1400h:01 = 80000205h (make the PDO invalid while it changes): ok",
            "2/7 1600h:00 = 00h (disable the mapping while its entries change): ok",
            "3/7 1600h:01 = 62000108h (map 6200:01:8): ok",
            "4/7 1600h:02 = 62000208h (map 6200:02:8): ok",
            "5/7 1600h:00 = 02h (enable the mapping with its number of entries): ok",
            "6/7 1400h:02 = FEh (transmission type): ok",
            "7/7 1400h:01 = 00000205h (make the PDO valid with its COB-ID): ok",
            "RPDO1 of node 5 configured: 6200:01:8 6200:02:8 (16 bits) on COB-ID 00000205h, valid",
        ]
    );
    assert_eq!(value(&link, stations[0], 0x1600, 2), 0x6200_0208u32.to_le_bytes());
}

#[test]
fn a_device_falling_silent_mid_plan_times_out_naming_the_step() {
    // Answers the COB-ID read and the first two writes, then nothing.
    let silent = Node::SilentAfter {
        device: Box::new(device(IO_EDS, 5)),
        answered: 3,
    };
    let (mut link, _) = bus(vec![silent]);
    let lines = map(&mut link, &config(Direction::Tpdo, 1, &["6000:01:8"]));
    assert_eq!(
        lines[2],
        "3/5 1A00h:01 = 60000108h (map 6000:01:8): timed out after 1s waiting for the initiate download \
         response (abort 0x05040000 sent to the server)"
    );
    assert_eq!(
        lines[5],
        "left: TPDO1 is left invalid (COB-ID 80000185h) with its mapping disabled (1A00h:00 = 0, 0 of 1 \
         entries written)"
    );
    // The abort goes out when the timeout runs out, one second after the request.
    let frames = trace(&mut link, &SDO);
    assert_eq!(
        frames[frames.len() - 2..],
        ["0 605#23001A0108010060", "1000 605#80001A0100000405"]
    );
}

#[test]
fn garbage_instead_of_the_cob_id_aborts_before_anything_is_written() {
    let (mut link, _) = bus(vec![Node::Garbage(Default::default())]);
    let config = config(Direction::Tpdo, 1, &["6000:01:8"]);
    let mut session = SdoSession::new(&mut link, 5, Duration::from_secs(1)).expect("session");
    let err = read_cob_id(&mut session, &config).expect_err("garbage");
    assert_eq!(
        err.to_string(),
        "node 5, reading the COB-ID of TPDO1 (1800h:01): SDO transfer aborted by the client with 0x05040001 \
         (client/server command specifier not valid or unknown): the server answered with DLC 3 (585#600018); \
         CiA 301 SDO frames have 8 bytes; nothing was written"
    );
    assert_eq!(
        trace(&mut link, &SDO).last().map(String::as_str),
        Some("0 605#8000180101000405")
    );
}

#[test]
fn a_pdo_the_device_lacks_is_named_and_a_cancelled_step_is_recorded() {
    let (mut link, _) = bus(vec![Node::Device(Box::new(device(IO_EDS, 5)))]);
    let mut lacking = config(Direction::Tpdo, 9, &["6000:01:8"]);
    lacking.cob_id = Some(0x1A5);
    let mut session = SdoSession::new(&mut link, 5, Duration::from_secs(1)).expect("session");
    let err = read_cob_id(&mut session, &lacking).expect_err("no TPDO9");
    assert!(matches!(err, ReadCobIdError::Refused { .. }));
    assert_eq!(
        err.to_string(),
        "node 5, reading the COB-ID of TPDO9 (1808h:01): SDO abort 0x06020000 from the server: Object does not \
         exist in the object dictionary (the device has no TPDO9); nothing was written"
    );

    let cancel = canopener_link::cancel::Cancel::new();
    let (link, _) = bus(vec![Node::Device(Box::new(device(IO_EDS, 5)))]);
    let mut link = link.with_cancel(cancel.clone());
    let config = config(Direction::Tpdo, 1, &["6000:01:8"]);
    let node = NodeId::new(5).expect("node");
    let mut session = SdoSession::new(&mut link, 5, Duration::from_secs(1)).expect("session");
    let current = read_cob_id(&mut session, &config).expect("COB-ID");
    let mut report = MapReport::new(
        node,
        &config,
        current,
        config.plan(node, Some(current)).expect("plan"),
    );
    execute(&mut session, &mut report, |_, step| {
        if step == 0 {
            cancel.cancel();
        }
    })
    .expect("no bus error");
    assert_eq!(report.steps[1].1, StepOutcome::Interrupted);
    assert_eq!(report.failure(), Some(1));
    assert_eq!(report.steps[2].1, StepOutcome::NotRun);
}

//! `node_info`, `node_scan` and `node_dump` against devices.

use std::path::Path;
use std::time::{Duration, UNIX_EPOCH};

use canopener_link::link::Link;
use canopener_link::node_dump::{DumpError, read_entries};
use canopener_link::node_info::{NodeInfoError, read};
use canopener_link::node_scan::scan;
use canopener_link::sdo_session::SdoSession;
use canopener_master::dcf_dump::{DcfOptions, Reading, build_dcf, plan};
use canopener_master::node_info::Field;
use canopener_master::node_scan::identify;
use canopener_wire::NmtState;

use crate::common::{BASE_EDS, IO_EDS, Node, bus, device, eds};

#[test]
fn info_reads_identity_names_and_the_heartbeat_state() {
    let (mut link, _) = bus(vec![Node::Device(Box::new(device(IO_EDS, 5)))]);
    let mut session = SdoSession::new(&mut link, 5, Duration::from_millis(500)).expect("session");
    session
        .write(0x1017, 0, 100u16.to_le_bytes().to_vec())
        .expect("heartbeat on");
    let device_type = session.read(0x1000, 0).expect("1000h");
    let info = read(&mut session).expect("info");
    assert_eq!(info.node, 5);
    assert_eq!(info.device_type.raw.to_le_bytes().to_vec(), device_type);
    assert!(matches!(info.error_register, Field::Value(_)));
    assert!(matches!(info.identity[0], Field::Value(_)));
    assert!(matches!(info.names[0], Field::Value(ref name) if !name.is_empty()));
    assert_eq!(info.heartbeat_time, Field::Value(100));
    let seen = info.heartbeat.expect("waited for a heartbeat");
    assert_eq!(seen.waited, Duration::from_millis(150));
    let (state, after) = seen.state.expect("a heartbeat came");
    assert!(matches!(state, NmtState::Operational | NmtState::PreOperational));
    assert!(after <= Duration::from_millis(100), "{after:?}");
}

#[test]
fn info_of_a_silent_node_names_the_device_type_and_the_wait() {
    let (mut link, _) = bus(vec![]);
    let mut session = SdoSession::new(&mut link, 9, Duration::from_millis(200)).expect("session");
    let err = read(&mut session).expect_err("nobody answers");
    assert!(matches!(err, NodeInfoError::DeviceType { node: 9, .. }));
    assert!(
        err.to_string()
            .starts_with("node 9, 1000h:00 (Device type): timed out after 200ms"),
        "{err}"
    );
}

#[test]
fn a_scan_identifies_the_answering_nodes_in_one_timeout_per_round() {
    let (mut link, _) = bus(vec![
        Node::Device(Box::new(device(BASE_EDS, 5))),
        Node::Device(Box::new(device(BASE_EDS, 7))),
    ]);
    let nodes: Vec<u8> = (1..=10).collect();
    let scanned = scan(&mut link, &nodes, 10, Duration::from_millis(100)).expect("scan");
    assert_eq!(scanned.ended, None);
    // The eight silent node-IDs time out together; the identity reads take no time on an ideal bus.
    assert_eq!(scanned.elapsed, Duration::from_millis(100));
    let rows = identify(&scanned.results);
    let found: Vec<(u8, Option<u32>)> = rows.iter().map(|row| (row.node, row.identity[0])).collect();
    assert_eq!(found, [(5, Some(0xABC)), (7, Some(0xABC))]);
    assert_eq!(rows[0].device_type, Ok(0x000F_0191));
    assert!(
        scan(&mut link, &nodes, 10, Duration::ZERO).is_err(),
        "zero timeouts are refused"
    );
}

#[test]
fn a_dump_reads_every_readable_entry_into_a_dcf_that_loads_back() {
    let io = eds(IO_EDS);
    let (mut link, _) = bus(vec![Node::Device(Box::new(device(IO_EDS, 5)))]);
    let mut session = SdoSession::new(&mut link, 5, Duration::from_millis(500)).expect("session");
    let plan = plan(&io);
    let mut asked = 0;
    let readings = read_entries(&mut session, &plan, |_| asked += 1).expect("readings");
    assert_eq!(readings.len(), plan.len());
    assert_eq!(asked, plan.iter().filter(|entry| entry.skip.is_none()).count());
    assert!(
        readings
            .iter()
            .any(|reading| matches!(reading, Reading::Value(_)))
    );
    let options = DcfOptions {
        node: 5,
        bitrate: Some(250),
        eds_path: Path::new("io.eds"),
        output: Some(Path::new("node5.dcf")),
        now: UNIX_EPOCH + Duration::from_secs(1_778_838_300),
    };
    let dcf = build_dcf(&io, None, &plan, &readings, options).expect("DCF");
    assert!(dcf.summary.read > 20, "{:?}", dcf.summary);
    let loaded = canopener_eds::load(&dcf.bytes);
    assert_eq!(loaded.eds.node_id(), Some(5));
    assert_eq!(
        loaded.eds.file_info.modification_date.as_deref(),
        Some("05-15-2026")
    );
}

#[test]
fn a_dump_of_a_silent_node_stops_at_the_first_entry() {
    let io = eds(IO_EDS);
    let (mut link, _) = bus(vec![]);
    let mut session = SdoSession::new(&mut link, 5, Duration::from_millis(100)).expect("session");
    let err = read_entries(&mut session, &plan(&io), |_| {}).expect_err("silent");
    assert!(matches!(err, DumpError::Silent { node: 5, .. }), "{err}");
    assert_eq!(session.link_mut().now(), canopener_can::Instant::from_millis(100));
}

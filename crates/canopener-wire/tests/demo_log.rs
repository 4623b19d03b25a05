//! The embedded demo session (`test_data/demo.log`) is correct CANopen from start to end.

use std::collections::BTreeSet;

use canopener_can::candump::{LogEvent, parse_log};
use canopener_wire::{CrcCheck, Decoded, Decoder, Payload, Service};

const DEMO_LOG: &str = include_str!("../test_data/demo.log");

/// Every record of the demo log with its decoded frame.
fn decode_demo() -> Vec<(usize, canopener_can::Instant, Decoded)> {
    let (records, problems) = parse_log(DEMO_LOG);
    assert!(problems.is_empty(), "demo.log does not parse: {problems:?}");
    let mut decoder = Decoder::new();
    records
        .into_iter()
        .map(|(line, record)| {
            assert_eq!(record.interface, "can0", "line {line}");
            let LogEvent::Frame(frame) = record.event else {
                panic!("line {line} is an error frame")
            };
            (line, record.timestamp, decoder.decode(&frame))
        })
        .collect()
}

#[test]
fn demo_log_has_no_anomalies() {
    let decoded = decode_demo();
    assert!((300..=600).contains(&decoded.len()), "{} frames", decoded.len());
    let anomalies: Vec<String> = decoded
        .iter()
        .filter(|(_, _, decoded)| !decoded.anomalies.is_empty())
        .map(|(line, _, decoded)| format!("line {line}: {decoded}"))
        .collect();
    assert!(anomalies.is_empty(), "anomalies:\n{}", anomalies.join("\n"));
}

#[test]
fn demo_log_timestamps_increase() {
    let decoded = decode_demo();
    for pair in decoded.windows(2) {
        assert!(
            pair[0].1 < pair[1].1,
            "line {} is not later than line {}",
            pair[1].0,
            pair[0].0
        );
    }
}

#[test]
fn demo_log_shows_every_service() {
    let decoded = decode_demo();
    let seen: BTreeSet<Service> = decoded.iter().map(|(_, _, decoded)| decoded.service).collect();
    let expected = [
        Service::Nmt,
        Service::Sync,
        Service::Emcy,
        Service::Time,
        Service::Tpdo(1),
        Service::Tpdo(2),
        Service::Rpdo(1),
        Service::SdoTx,
        Service::SdoRx,
        Service::ErrorControl,
        Service::Lss,
    ];
    for service in expected {
        assert!(seen.contains(&service), "{service} missing from demo.log");
    }
    assert!(!seen.contains(&Service::Unknown));
}

#[test]
fn demo_log_contains_the_promised_scenes() {
    let lines: Vec<String> = decode_demo()
        .iter()
        .map(|(_, _, decoded)| decoded.to_string())
        .collect();
    let has = |text: &str| lines.iter().any(|line| line.contains(text));
    let scenes = [
        "Boot-up node 5",
        "NMT Reset Communication -> all nodes",
        "NMT Start Remote Node -> all nodes",
        "SDO tx node 10: upload 1018h:04 = 0x2025B033 (4 bytes)",
        "SDO tx node 5: upload segment toggle=0 last 4 bytes (18/18) of 1008h:00",
        "SDO rx node 6: download segment toggle=0 last 4 bytes (18/18) of 2100h:00",
        "SDO tx node 10: end block upload of 1021h:00 (115 bytes) crc=0x",
        "SDO rx node 5: download 1A00h:03 = 0x64010110 (4 bytes)",
        "SDO tx node 6: ABORT 6100h:01 0x06020000 (object does not exist in the object dictionary)",
        "EMCY node 6: 0x2310 (output current too high, overload) reg 0x03 (generic, current)",
        "EMCY node 6: 0x0000 (error reset or no error) reg 0x00",
        "Node guarding response node 10: OPERATIONAL toggle=1",
        "Heartbeat node 6: OPERATIONAL",
        "LSS slave: serial number = 0x2025A105",
        "LSS slave: node-id = 5",
        "TIME 2025-01-15 08:30:01",
        "SYNC counter 1",
        "RPDO1 node 10 (6 bytes)",
    ];
    for scene in scenes {
        assert!(has(scene), "no line contains {scene:?}");
    }
    let block_end = decode_demo()
        .into_iter()
        .find_map(|(_, _, decoded)| match decoded.payload {
            Payload::Sdo(sdo) if sdo.crc.is_some() => sdo.crc,
            _ => None,
        });
    assert!(matches!(block_end, Some(CrcCheck::Match(_))), "{block_end:?}");
}

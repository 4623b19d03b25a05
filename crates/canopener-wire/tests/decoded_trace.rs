//! A trace that touches every service, decoded line by line and pinned with an insta snapshot.
//!
//! The frames are written in the can-utils compact form; comments say what each group shows. A few
//! frames are deliberately wrong so that the snapshot also pins how anomalies print.

use canopener_can::candump::parse_compact_frame;
use canopener_wire::Decoder;

const TRACE: &[&str] = &[
    // NMT: every command, broadcast and addressed.
    "000#8200",
    "000#8105",
    "000#0105",
    "000#0205",
    "000#8005",
    "000#0100",
    // Boot-up, heartbeat states.
    "705#00",
    "705#7F",
    "705#05",
    "705#04",
    // Node guarding with the toggle bit.
    "70A#R1",
    "70A#7F",
    "70A#R1",
    "70A#FF",
    // SYNC without and with counter, TIME.
    "080#",
    "080#07",
    "100#002E93021239",
    // EMCY: error, vendor bytes, reset.
    "083#3081110000000000",
    "083#1023030300000000",
    "083#0000000000000000",
    // PDOs, including a TPDO remote request.
    "185#01020304",
    "285#0102030405060708",
    "385#01",
    "485#",
    "205#FF",
    "305#0001",
    "405#000102",
    "505#00010203",
    "181#R4",
    // SDO expedited upload and download.
    "622#4018100100000000",
    "5A2#4318100178563412",
    "605#2B17100064000000",
    "585#6017100000000000",
    // SDO segmented download of 10 bytes.
    "605#210120000A000000",
    "585#6001200000000000",
    "605#0030313233343536",
    "585#2000000000000000",
    "605#1937383900000000",
    "585#3000000000000000",
    // SDO block download of 9 bytes with CRC.
    "605#C602200009000000",
    "585#A402200004000000",
    "605#0131323334353637",
    "605#8238390000000000",
    "585#A202040000000000",
    "605#D5C3310000000000",
    "585#A100000000000000",
    // SDO abort.
    "622#4000600000000000",
    "5A2#8000600000000206",
    // LSS.
    "7E5#0401000000000000",
    "7E5#1107000000000000",
    "7E4#1100000000000000",
    "7E5#1300030000000000",
    "7E4#1300000000000000",
    "7E5#1564000000000000",
    "7E5#1700000000000000",
    "7E4#1701000000000000",
    "7E5#4C00000000000000",
    "7E4#5000000000000000",
    "7E5#51000000001F0000",
    "7E4#4F00000000000000",
    "7E5#4AA1052520000000",
    "7E5#0400000000000000",
    // Not CANopen.
    "7E0#0102",
    "18DAF110#0201",
    // Anomalies: NMT to node 200, heartbeat with DLC 2, a wrong toggle, node-id 0, an SDO with DLC 4.
    "000#01C8",
    "706#0500",
    "606#210120000E000000",
    "586#6001200000000000",
    "606#0030313233343536",
    "586#2000000000000000",
    "606#0137383930313233",
    "180#01",
    "607#40001000",
];

#[test]
fn every_service_decodes_to_one_line() {
    let mut decoder = Decoder::new();
    let lines: Vec<String> = TRACE
        .iter()
        .map(|compact| {
            let frame = parse_compact_frame(compact).unwrap();
            format!("{compact:<24} {}", decoder.decode(&frame))
        })
        .collect();
    insta::assert_snapshot!(lines.join("\n"));
}

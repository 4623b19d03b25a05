//! A CiA 301 communication profile dictionary served the way an SDO server uses it: each line of a
//! script is one upload or download and the expected data or abort code.

use canopener_od::{Access, DataType, DynamicOd, Entry, ObjFlags, ObjectKey};

fn key(index: u16, sub: u8) -> ObjectKey {
    ObjectKey::new(index, sub)
}

/// Objects a simple I/O device has, as its EDS would describe them.
fn device() -> DynamicOd {
    let entries = vec![
        Entry::new(
            key(0x1000, 0),
            DataType::UNSIGNED32,
            Access::Ro,
            &0x000F_0191u32.to_le_bytes(),
        ),
        Entry::new(key(0x1001, 0), DataType::UNSIGNED8, Access::Ro, &[0]).map(|e| e.with_pdo_mapping(true)),
        Entry::new(
            key(0x1008, 0),
            DataType::VISIBLE_STRING,
            Access::Const,
            b"canopener io",
        ),
        Entry::new(key(0x1010, 1), DataType::UNSIGNED32, Access::Rw, &[1, 0, 0, 0])
            .map(|e| e.with_obj_flags(ObjFlags::REFUSE_READ_ON_SCAN)),
        Entry::new(key(0x1017, 0), DataType::UNSIGNED16, Access::Rw, &[0, 0]),
        Entry::new(key(0x1018, 0), DataType::UNSIGNED8, Access::Const, &[4]),
        Entry::new(
            key(0x1018, 1),
            DataType::UNSIGNED32,
            Access::Ro,
            &0x360u32.to_le_bytes(),
        ),
        Entry::new(key(0x1018, 2), DataType::UNSIGNED32, Access::Ro, &[2, 0, 0, 0]),
        Entry::new(key(0x1018, 3), DataType::UNSIGNED32, Access::Ro, &[3, 0, 0, 0]),
        Entry::new(key(0x1018, 4), DataType::UNSIGNED32, Access::Ro, &[4, 0, 0, 0]),
        Entry::new(key(0x1F51, 1), DataType::UNSIGNED8, Access::Wo, &[0]),
        Entry::new(key(0x2000, 0), DataType::INTEGER24, Access::Rww, &[0, 0, 0]).and_then(|e| {
            e.with_pdo_mapping(true).with_limits(
                Some(&(-1000i32).to_le_bytes()[..3]),
                Some(&1000i32.to_le_bytes()[..3]),
            )
        }),
        Entry::new(key(0x2001, 0), DataType::UNSIGNED40, Access::Rwr, &[0; 5])
            .and_then(|e| e.with_limits(None, Some(&0x10_0000_0000u64.to_le_bytes()[..5]))),
        Entry::new(key(0x2002, 0), DataType::VISIBLE_STRING, Access::Rw, b"label")
            .and_then(|e| e.with_max_len(16)),
    ];
    let entries: Vec<Entry> = entries.into_iter().collect::<Result<_, _>>().unwrap();
    // Inserted in reverse so the dictionary has to sort them.
    let mut od = DynamicOd::with_capacity(32);
    for entry in entries.into_iter().rev() {
        assert_eq!(od.insert(entry), Ok(None));
    }
    od
}

/// Runs a script of `up INDEX SUB` and `down INDEX SUB BYTES` lines, each followed by `->` and the
/// expected bytes, `ok`, or `abort CODE`.
#[track_caller]
fn check(od: &mut DynamicOd, script: &str) {
    for line in script.lines().map(str::trim).filter(|line| !line.is_empty()) {
        let (request, expected) = line.split_once("->").unwrap();
        let words: Vec<&str> = request.split_whitespace().collect();
        let index = u16::from_str_radix(words[1], 16).unwrap();
        let sub = u8::from_str_radix(words[2], 16).unwrap();
        let data: Vec<u8> = words[3..]
            .iter()
            .map(|byte| u8::from_str_radix(byte, 16).unwrap())
            .collect();
        let outcome = match words[0] {
            "up" => od.read(key(index, sub)).map(hex),
            "down" => od.write(key(index, sub), &data).map(|()| "ok".to_owned()),
            other => panic!("unknown request {other}"),
        };
        let actual = match outcome {
            Ok(text) => text,
            Err(err) => format!("abort {:08X}", err.abort_code()),
        };
        assert_eq!(actual, expected.trim(), "{line}");
    }
}

fn hex(bytes: &[u8]) -> String {
    bytes
        .iter()
        .map(|byte| format!("{byte:02X}"))
        .collect::<Vec<_>>()
        .join(" ")
}

#[test]
fn uploads() {
    check(
        &mut device(),
        "
        up 1000 0 -> 91 01 0F 00
        up 1008 0 -> 63 61 6E 6F 70 65 6E 65 72 20 69 6F
        up 1018 0 -> 04
        up 1018 1 -> 60 03 00 00
        up 1018 5 -> abort 06090011
        up 1019 0 -> abort 06020000
        up 1F51 1 -> abort 06010001
        up 1F51 0 -> abort 06090011
        ",
    );
}

#[test]
fn downloads_respect_access_length_and_limits() {
    check(
        &mut device(),
        "
        down 1017 0 E8 03 -> ok
        up 1017 0 -> E8 03
        down 1017 0 E8 -> abort 06070013
        down 1017 0 E8 03 00 00 -> abort 06070012
        down 1000 0 00 00 00 00 -> abort 06010002
        down 1018 0 05 -> abort 06010002
        down 1008 0 41 -> abort 06010002
        down 1F51 1 01 -> ok
        down 2000 0 E8 03 00 -> ok
        down 2000 0 E9 03 00 -> abort 06090031
        down 2000 0 18 FC FF -> ok
        down 2000 0 17 FC FF -> abort 06090032
        up 2000 0 -> 18 FC FF
        down 2001 0 00 00 00 00 10 -> ok
        down 2001 0 01 00 00 00 10 -> abort 06090031
        down 2002 0 41 42 -> ok
        up 2002 0 -> 41 42
        down 2002 0 30 31 32 33 34 35 36 37 38 39 41 42 43 44 45 46 -> ok
        down 2002 0 30 31 32 33 34 35 36 37 38 39 41 42 43 44 45 46 47 -> abort 06070012
        down 3000 0 00 -> abort 06020000
        ",
    );
}

#[test]
fn objects_come_out_whole_and_in_order() {
    let od = device();
    let identity: Vec<u8> = od.object(0x1018).iter().map(|e| e.key().sub).collect();
    assert_eq!(identity, [0, 1, 2, 3, 4]);
    let indices: Vec<u16> = od.iter().map(|e| e.key().index).collect();
    let mut sorted = indices.clone();
    sorted.sort();
    assert_eq!(indices, sorted);
    assert_eq!(od.len(), 14);
}

#[test]
fn pdo_mappability_follows_access_and_pdo_mapping() {
    let od = device();
    let tpdo: Vec<ObjectKey> = od.iter().filter(|e| e.tpdo_mappable()).map(Entry::key).collect();
    let rpdo: Vec<ObjectKey> = od.iter().filter(|e| e.rpdo_mappable()).map(Entry::key).collect();
    assert_eq!(tpdo, [key(0x1001, 0)]);
    assert_eq!(rpdo, [key(0x2000, 0)]);
}

#[test]
fn the_application_updates_read_only_process_values() {
    let mut od = device();
    // The device raises a generic error in its error register; the network cannot.
    assert_eq!(od.set_value(key(0x1001, 0), &[0x01]), Ok(()));
    check(&mut od, "up 1001 0 -> 01\ndown 1001 0 00 -> abort 06010002");
}

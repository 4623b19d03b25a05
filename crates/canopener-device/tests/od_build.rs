//! The runtime object dictionary built from real EDS and DCF files: the whole corpus, exact values of
//! known files, and a property over generated files.

use std::collections::BTreeMap;
use std::path::PathBuf;

use canopener_testkit::corpus::{self, Kind};

use canopener_device::od_build::{BuiltOd, NoteKind, build_od};
use canopener_od::{Access, DataType, DynamicOd, ObjectKey};
use proptest::prelude::*;

fn corpus_files() -> Vec<PathBuf> {
    corpus::eds_files().into_iter().map(|file| file.path).collect()
}

fn build_file(name: &str, node_id: u8) -> BuiltOd {
    let bytes = canopener_testkit::fixture::read(corpus::eds(name)).expect("corpus file");
    build_od(&canopener_eds::load(&bytes).eds, node_id).expect("builds")
}

fn read(od: &DynamicOd, index: u16, sub: u8) -> Vec<u8> {
    od.read(ObjectKey::new(index, sub))
        .unwrap_or_else(|err| panic!("{index:04X}sub{sub}: {err}"))
        .to_vec()
}

fn abort(od: &mut DynamicOd, index: u16, sub: u8, data: &[u8]) -> Result<(), u32> {
    od.write(ObjectKey::new(index, sub), data)
        .map_err(|err| err.abort_code())
}

/// Every entry holds a value of its declared type's size, within its maximum for variable-length types.
fn check_sizes(built: &BuiltOd) -> Result<(), String> {
    for entry in built.od.iter() {
        let len = entry.value().len();
        match entry.data_type().byte_size() {
            Some(size) if len != size => {
                return Err(format!(
                    "{} holds {len} bytes, {} takes {size}",
                    entry.key(),
                    entry.data_type()
                ));
            }
            Some(_) => {}
            None if !entry.data_type().is_variable_length() => {
                return Err(format!(
                    "{} has non-basic type {}",
                    entry.key(),
                    entry.data_type()
                ));
            }
            None => match entry.max_len() {
                Some(max) if len <= max as usize => {}
                other => return Err(format!("{} holds {len} bytes, maximum {other:?}", entry.key())),
            },
        }
    }
    if built.od.len() != built.od.capacity() {
        return Err(format!(
            "capacity {} for {} entries",
            built.od.capacity(),
            built.od.len()
        ));
    }
    Ok(())
}

#[test]
fn every_corpus_file_builds() {
    let files = corpus_files();
    assert_eq!(
        files.len(),
        corpus::expected_count(Kind::Eds),
        "corpus size changed"
    );
    let (mut entries, mut notes, mut noted_files) = (0, 0, 0);
    let mut by_kind: BTreeMap<String, usize> = BTreeMap::new();
    for path in &files {
        let bytes = canopener_testkit::fixture::read(path).expect("corpus file");
        let eds = canopener_eds::load(&bytes).eds;
        for node_id in [1, 5, 127] {
            let built = build_od(&eds, node_id).unwrap_or_else(|err| panic!("{}: {err}", path.display()));
            check_sizes(&built).unwrap_or_else(|err| panic!("{}: {err}", path.display()));
            if node_id == 5 {
                entries += built.od.len();
                notes += built.notes.len();
                noted_files += usize::from(!built.notes.is_empty());
                for note in &built.notes {
                    *by_kind.entry(format!("{:?}", note.kind)).or_default() += 1;
                }
            }
        }
    }
    println!(
        "{} files, {entries} entries, {notes} notes in {noted_files} files: {by_kind:?}",
        files.len()
    );
    assert!(entries > 10_000, "only {entries} entries");
}

#[test]
fn identity_and_nodeid_cob_ids_of_a_canopennode_eds() {
    let built = build_file(
        "CANopenNode__CanOpenSTM32__Elcom e-RIO 8xx CANopen Profile.eds",
        5,
    );
    let od = &built.od;
    assert_eq!(read(od, 0x1018, 1), 0x46Au32.to_le_bytes());
    assert_eq!(
        od.get(ObjectKey::new(0x1018, 1)).map(|e| e.data_type()),
        Some(DataType::UNSIGNED32)
    );
    // DefaultValue=0x580+$NODEID and $NODEID+0x180 for node 5.
    assert_eq!(read(od, 0x1200, 2), 0x585u32.to_le_bytes());
    assert_eq!(read(od, 0x1800, 1), 0x185u32.to_le_bytes());
    let other_node = build_file(
        "CANopenNode__CanOpenSTM32__Elcom e-RIO 8xx CANopen Profile.eds",
        0x22,
    );
    assert_eq!(read(&other_node.od, 0x1800, 1), 0x1A2u32.to_le_bytes());
}

#[test]
fn limits_of_a_known_file_are_enforced_on_write() {
    let mut built = build_file(
        "CANopenNode__CanOpenSTM32__Elcom e-RIO 8xx CANopen Profile.eds",
        5,
    );
    // [2000sub1] Node ID: rw UNSIGNED8, LowLimit=1, HighLimit=127, DefaultValue=0x10.
    assert_eq!(read(&built.od, 0x2000, 1), [0x10]);
    assert_eq!(abort(&mut built.od, 0x2000, 1, &[128]), Err(0x0609_0031));
    assert_eq!(abort(&mut built.od, 0x2000, 1, &[0]), Err(0x0609_0032));
    assert_eq!(
        read(&built.od, 0x2000, 1),
        [0x10],
        "a refused write changes nothing"
    );
    assert_eq!(abort(&mut built.od, 0x2000, 1, &[127]), Ok(()));
    assert_eq!(read(&built.od, 0x2000, 1), [127]);

    // [1600sub0] of a modm test EDS: rw UNSIGNED8 with HighLimit=8.
    let mut modm = build_file("Javask__modm-canopen__examples__src__simple-linux__test.eds", 5);
    assert_eq!(abort(&mut modm.od, 0x1600, 0, &[9]), Err(0x0609_0031));
    assert_eq!(abort(&mut modm.od, 0x1600, 0, &[8]), Ok(()));
}

#[test]
fn access_types_of_a_known_file() {
    let mut built = build_file("christiansandberg__canopen__test__sample.eds", 5);
    let access = |od: &DynamicOd, index, sub| od.get(ObjectKey::new(index, sub)).map(|e| e.access());
    assert_eq!(access(&built.od, 0x1017, 0), Some(Access::Rw));
    assert_eq!(access(&built.od, 0x1008, 0), Some(Access::Const));
    assert_eq!(access(&built.od, 0x1018, 1), Some(Access::Ro));
    // rw accepts a write; ro and const refuse it with 0601 0002h.
    assert_eq!(abort(&mut built.od, 0x1017, 0, &1000u16.to_le_bytes()), Ok(()));
    assert_eq!(read(&built.od, 0x1017, 0), [0xE8, 0x03]);
    assert_eq!(abort(&mut built.od, 0x1018, 1, &[0; 4]), Err(0x0601_0002));
    assert_eq!(abort(&mut built.od, 0x1008, 0, b"X"), Err(0x0601_0002));
    // The DCF-style ParameterValue=1 of 1018h sub 1 is the value (it has no DefaultValue).
    assert_eq!(read(&built.od, 0x1018, 1), 1u32.to_le_bytes());
    assert_eq!(read(&built.od, 0x1008, 0), b"TEST DEVICE");
    // DefaultValue=$NODEID+512 of the RPDO 1 COB-ID.
    assert_eq!(read(&built.od, 0x1400, 1), 0x205u32.to_le_bytes());
    assert_eq!(
        built.od.get(ObjectKey::new(0x1400, 1)).map(|e| e.data_type()),
        Some(DataType::UNSIGNED32)
    );
}

#[test]
fn a_dcf_parameter_value_wins_over_the_default() {
    let text = "[FileInfo]\nFileName=t.dcf\n[DeviceInfo]\nVendorName=v\n[DeviceComissioning]\nNodeID=5\n\
                [1017]\nParameterName=hb\nObjectType=0x7\nDataType=0x0006\nAccessType=rw\n\
                DefaultValue=0\nParameterValue=250\n\
                [1014]\nParameterName=emcy\nObjectType=0x7\nDataType=0x0007\nAccessType=rw\n\
                DefaultValue=$NODEID+0x80\nParameterValue=0x81\n";
    let eds = canopener_eds::load(text.as_bytes()).eds;
    let built = build_od(&eds, 5).expect("builds");
    assert_eq!(read(&built.od, 0x1017, 0), 250u16.to_le_bytes());
    assert_eq!(read(&built.od, 0x1014, 0), 0x81u32.to_le_bytes());
    assert!(built.notes.is_empty(), "{:?}", built.notes);
}

#[test]
fn compact_pdo_objects_are_generated() {
    // CompactPDO implies the communication and mapping objects NrOfRXPDO/NrOfTXPDO promise.
    let text =
        "[FileInfo]\nFileName=t.eds\n[DeviceInfo]\nVendorName=v\nNrOfRXPDO=1\nNrOfTXPDO=1\nCompactPDO=0x3F\n";
    let eds = canopener_eds::load(text.as_bytes()).eds;
    let built = build_od(&eds, 7).expect("builds");
    assert!(!built.od.object(0x1400).is_empty() && !built.od.object(0x1A00).is_empty());
    check_sizes(&built).expect("sizes");
}

const TYPES: [(&str, u16); 25] = [
    ("BOOLEAN", 0x01),
    ("INTEGER8", 0x02),
    ("INTEGER16", 0x03),
    ("INTEGER32", 0x04),
    ("UNSIGNED8", 0x05),
    ("UNSIGNED16", 0x06),
    ("UNSIGNED32", 0x07),
    ("REAL32", 0x08),
    ("VISIBLE_STRING", 0x09),
    ("OCTET_STRING", 0x0A),
    ("UNICODE_STRING", 0x0B),
    ("TIME_OF_DAY", 0x0C),
    ("TIME_DIFFERENCE", 0x0D),
    ("DOMAIN", 0x0F),
    ("INTEGER24", 0x10),
    ("REAL64", 0x11),
    ("INTEGER40", 0x12),
    ("INTEGER48", 0x13),
    ("INTEGER56", 0x14),
    ("INTEGER64", 0x15),
    ("UNSIGNED24", 0x16),
    ("UNSIGNED40", 0x18),
    ("UNSIGNED48", 0x19),
    ("UNSIGNED56", 0x1A),
    ("UNSIGNED64", 0x1B),
];

/// Access tokens, valid and not.
const ACCESS: [&str; 8] = ["ro", "wo", "rw", "rwr", "rww", "const", "", "xx"];

/// Value texts of every flavour: valid numbers in all notations, formulas, garbage.
fn value_text() -> impl Strategy<Value = String> {
    prop_oneof![
        any::<i64>().prop_map(|v| v.to_string()),
        any::<u64>().prop_map(|v| format!("0x{v:X}")),
        any::<u8>().prop_map(|v| v.to_string()),
        (0u16..0x800).prop_map(|v| format!("$NODEID+0x{v:X}")),
        (0u16..0x800).prop_map(|v| format!("0x{v:X}+$NODEID")),
        any::<f32>().prop_map(|v| v.to_string()),
        "[0-9A-Fa-f]{0,12}",
        "[ -~]{0,20}",
        Just(String::new()),
    ]
}

proptest! {
    /// Whatever an EDS says, every entry of the built dictionary reads back a value of its declared
    /// type's size (fixed-size types) or within its maximum (variable-length types).
    #[test]
    fn every_entry_reads_back_its_types_size(
        node_id in 1u8..=127,
        objects in prop::collection::vec(
            (0usize..TYPES.len(), value_text(), prop::option::of(value_text()),
             prop::option::of(value_text()), prop::sample::select(ACCESS.to_vec())),
            1..12,
        ),
    ) {
        let mut text = String::from("[FileInfo]\nFileName=p.eds\n[DeviceInfo]\nVendorName=v\n");
        for (n, (type_idx, default, low, high, access)) in objects.iter().enumerate() {
            let (_, code) = TYPES[*type_idx];
            text.push_str(&format!(
                "[{:04X}]\nParameterName=p\nObjectType=0x7\nDataType=0x{code:04X}\n\
                 AccessType={access}\nDefaultValue={default}\n",
                0x2000 + n
            ));
            if let Some(low) = low { text.push_str(&format!("LowLimit={low}\n")); }
            if let Some(high) = high { text.push_str(&format!("HighLimit={high}\n")); }
        }
        let eds = canopener_eds::load(text.as_bytes()).eds;
        let built = build_od(&eds, node_id).expect("a valid node-ID always builds");
        prop_assert_eq!(built.od.len(), objects.len());
        if let Err(err) = check_sizes(&built) { prop_assert!(false, "{}", err); }
        for entry in built.od.iter() {
            let (name, code) = TYPES[objects[usize::from(entry.key().index - 0x2000)].0];
            // The declared type is kept; a written type is never replaced by another.
            prop_assert_eq!(entry.data_type(), DataType(code), "{}", name);
            if entry.access().readable() {
                prop_assert_eq!(built.od.read(entry.key()).map(<[u8]>::len), Ok(entry.value().len()));
            }
        }
        prop_assert!(built.notes.iter().all(|n| n.kind != NoteKind::UnknownDataType));
    }
}

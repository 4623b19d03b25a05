//! Synthetic EDS files of any size, for the load benchmarks and the side-by-side timing against
//! python canopen.
//!
//! There is exactly one generator so that the criterion benchmark (`benches/load.rs`), our timing
//! program (`examples/load_timing.rs --generate`) and python canopen (through `bench/eds_load.py`)
//! all read the identical file. The file follows CiA 306 §4 in the style vendor tools write it:
//! CR/LF line endings, `[FileInfo]`, `[DeviceInfo]`, `[DummyUsage]`, `[Comments]`, the three object
//! lists, then object sections `[xxxx]` with sub-object sections `[xxxxsubN]`. Objects cycle through
//! a fixed mix of ten kinds (VARs of eight CiA 301 basic types, one ARRAY and one RECORD), with
//! decimal, hex and negative values, limits and `$NODEID` formulas, so every code path of the value
//! readers is exercised in realistic proportions. The output is deterministic.

use std::fmt::Write as _;

/// The mandatory objects of CiA 301 §7.5.2 (device type, error register, identity), always first.
const MANDATORY: [u16; 3] = [0x1000, 0x1001, 0x1018];

/// The first index handed out after the mandatory objects: the manufacturer-specific area.
const FIRST_GENERATED_INDEX: u16 = 0x2000;

/// The largest object count the generator can produce: the mandatory objects plus every index from
/// 2000h to FFFFh.
pub(crate) const MAX_OBJECTS: usize = MANDATORY.len() + (0x1_0000 - FIRST_GENERATED_INDEX as usize);

/// A generated EDS file and what it contains.
#[derive(Debug, Clone)]
pub(crate) struct SyntheticEds {
    /// The file contents (ASCII, CR/LF line endings).
    pub(crate) text: String,
    /// Number of object sections `[xxxx]`.
    pub(crate) objects: usize,
    /// Number of sub-object sections `[xxxxsubN]`.
    pub(crate) sub_objects: usize,
}

/// Generates an EDS with `objects` objects (at most [`MAX_OBJECTS`]; larger requests are clamped, and
/// the returned `objects` says how many were written).
pub(crate) fn synthetic_eds(objects: usize) -> SyntheticEds {
    let objects = objects.min(MAX_OBJECTS);
    let indices: Vec<u16> = MANDATORY
        .iter()
        .copied()
        .chain(FIRST_GENERATED_INDEX..=u16::MAX)
        .take(objects)
        .collect();
    let mut out = Out {
        text: String::with_capacity(objects * 200 + 2048),
        sub_objects: 0,
    };
    write_header(&mut out, objects);
    write_object_lists(&mut out, &indices);
    for (position, &index) in indices.iter().enumerate() {
        match index {
            0x1000 => out.var(index, "Device type", "0x0007", "ro", Some("0x00000191"), &[]),
            0x1001 => out.var(
                index,
                "Error register",
                "0x0005",
                "ro",
                Some("0"),
                &[("PDOMapping", "1")],
            ),
            0x1018 => out.record(
                index,
                "Identity object",
                &[
                    ("Vendor-ID", "0x0007", "ro", "0x00000000"),
                    ("Product code", "0x0007", "ro", "0x00000001"),
                    ("Revision number", "0x0007", "ro", "0x00010000"),
                    ("Serial number", "0x0007", "ro", "0"),
                ],
            ),
            _ => write_generated(&mut out, index, position),
        }
    }
    SyntheticEds {
        text: out.text,
        objects,
        sub_objects: out.sub_objects,
    }
}

/// The file being written; `writeln!` into a `String` cannot fail, so its results are ignored.
struct Out {
    text: String,
    sub_objects: usize,
}

impl Out {
    fn line(&mut self, args: std::fmt::Arguments<'_>) {
        let _ = self.text.write_fmt(args);
        self.text.push_str("\r\n");
    }

    /// A VAR object (CiA 306 §4.6.3, ObjectType 7) with optional extra keys.
    fn var(
        &mut self,
        index: u16,
        name: &str,
        data_type: &str,
        access: &str,
        default: Option<&str>,
        extra: &[(&str, &str)],
    ) {
        self.line(format_args!("[{index:04X}]"));
        self.line(format_args!("ParameterName={name}"));
        self.line(format_args!("ObjectType=0x7"));
        self.line(format_args!("DataType={data_type}"));
        self.line(format_args!("AccessType={access}"));
        if let Some(default) = default {
            self.line(format_args!("DefaultValue={default}"));
        }
        let mut pdo_mapping_written = false;
        for (key, value) in extra {
            pdo_mapping_written |= *key == "PDOMapping";
            self.line(format_args!("{key}={value}"));
        }
        if !pdo_mapping_written {
            self.line(format_args!("PDOMapping=0"));
        }
        self.line(format_args!(""));
    }

    /// The object section of an ARRAY or RECORD and its sub-index 0 (the highest sub-index supported).
    fn aggregate(&mut self, index: u16, name: &str, object_type: u8, members: usize) {
        self.line(format_args!("[{index:04X}]"));
        self.line(format_args!("ParameterName={name}"));
        self.line(format_args!("ObjectType=0x{object_type:X}"));
        self.line(format_args!("SubNumber={}", members + 1));
        self.line(format_args!(""));
        self.sub(
            index,
            0,
            "Highest sub-index supported",
            "0x0005",
            "ro",
            &members.to_string(),
        );
    }

    fn sub(&mut self, index: u16, sub: usize, name: &str, data_type: &str, access: &str, default: &str) {
        self.line(format_args!("[{index:04X}sub{sub:X}]"));
        self.line(format_args!("ParameterName={name}"));
        self.line(format_args!("ObjectType=0x7"));
        self.line(format_args!("DataType={data_type}"));
        self.line(format_args!("AccessType={access}"));
        self.line(format_args!("DefaultValue={default}"));
        self.line(format_args!("PDOMapping=0"));
        self.line(format_args!(""));
        self.sub_objects += 1;
    }

    /// A RECORD (ObjectType 9): `members` are (name, data type, access, default) of sub-indices 1...
    fn record(&mut self, index: u16, name: &str, members: &[(&str, &str, &str, &str)]) {
        self.aggregate(index, name, 9, members.len());
        for (sub, (member, data_type, access, default)) in (1..).zip(members) {
            self.sub(index, sub, member, data_type, access, default);
        }
    }
}

fn write_header(out: &mut Out, objects: usize) {
    out.line(format_args!(
        "; synthetic object dictionary of {objects} objects for canopener's load benchmarks"
    ));
    out.line(format_args!("[FileInfo]"));
    out.line(format_args!("FileName=synthetic_{objects}.eds"));
    out.line(format_args!("FileVersion=1"));
    out.line(format_args!("FileRevision=0"));
    out.line(format_args!("EDSVersion=4.0"));
    out.line(format_args!(
        "Description=Synthetic device with {objects} objects"
    ));
    out.line(format_args!("CreationTime=09:00AM"));
    out.line(format_args!("CreationDate=01-15-2025"));
    out.line(format_args!("CreatedBy=canopener synthetic_eds"));
    out.line(format_args!("ModificationTime=09:00AM"));
    out.line(format_args!("ModificationDate=01-15-2025"));
    out.line(format_args!("ModifiedBy=canopener synthetic_eds"));
    out.line(format_args!(""));
    out.line(format_args!("[DeviceInfo]"));
    out.line(format_args!("VendorName=canopener"));
    out.line(format_args!("VendorNumber=0x00000000"));
    out.line(format_args!("ProductName=Synthetic {objects}"));
    out.line(format_args!("ProductNumber=0x00000001"));
    out.line(format_args!("RevisionNumber=0x00010000"));
    out.line(format_args!("OrderCode=SYN-{objects}"));
    for rate in [10, 20, 50, 125, 250, 500, 800, 1000] {
        out.line(format_args!("BaudRate_{rate}=1"));
    }
    out.line(format_args!("SimpleBootUpMaster=0"));
    out.line(format_args!("SimpleBootUpSlave=1"));
    out.line(format_args!("Granularity=8"));
    out.line(format_args!("DynamicChannelsSupported=0"));
    out.line(format_args!("GroupMessaging=0"));
    out.line(format_args!("NrOfRXPDO=0"));
    out.line(format_args!("NrOfTXPDO=0"));
    out.line(format_args!("LSS_Supported=0"));
    out.line(format_args!(""));
    out.line(format_args!("[DummyUsage]"));
    for dummy in 1..=7 {
        out.line(format_args!("Dummy{dummy:04}=0"));
    }
    out.line(format_args!(""));
    out.line(format_args!("[Comments]"));
    out.line(format_args!("Lines=1"));
    out.line(format_args!(
        "Line1=generated; every tenth object is an ARRAY, every tenth a RECORD"
    ));
    out.line(format_args!(""));
}

/// CiA 306 §4.6.2: mandatory objects, optional objects (communication and profile areas) and
/// manufacturer-specific objects (2000h..5FFFh), each list numbered from 1.
fn write_object_lists(out: &mut Out, indices: &[u16]) {
    let mandatory: Vec<u16> = indices
        .iter()
        .copied()
        .filter(|i| MANDATORY.contains(i))
        .collect();
    let manufacturer: Vec<u16> = indices
        .iter()
        .copied()
        .filter(|i| (0x2000..=0x5FFF).contains(i))
        .collect();
    let optional: Vec<u16> = indices
        .iter()
        .copied()
        .filter(|i| !MANDATORY.contains(i) && !(0x2000..=0x5FFF).contains(i))
        .collect();
    for (name, list) in [
        ("MandatoryObjects", mandatory),
        ("OptionalObjects", optional),
        ("ManufacturerObjects", manufacturer),
    ] {
        out.line(format_args!("[{name}]"));
        out.line(format_args!("SupportedObjects={}", list.len()));
        for (number, index) in (1..).zip(&list) {
            out.line(format_args!("{number}=0x{index:04X}"));
        }
        out.line(format_args!(""));
    }
}

/// One object of the repeating mix; `position` picks the kind so neighbours differ.
fn write_generated(out: &mut Out, index: u16, position: usize) {
    let n = position % 1000;
    match position % 10 {
        0 => out.var(
            index,
            &format!("Mode {n}"),
            "0x0005",
            "rw",
            Some(&format!("0x{:02X}", n % 256)),
            &[("PDOMapping", "1")],
        ),
        1 => out.var(
            index,
            &format!("Speed limit {n}"),
            "0x0006",
            "rw",
            Some(&(n * 3).to_string()),
            &[("LowLimit", "0"), ("HighLimit", "0xFFFF"), ("PDOMapping", "1")],
        ),
        2 => out.var(
            index,
            &format!("COB-ID {n}"),
            "0x0007",
            "rw",
            Some("$NODEID+0x180"),
            &[],
        ),
        3 => out.var(
            index,
            &format!("Offset {n}"),
            "0x0003",
            "rw",
            Some(&format!("-{}", n % 300)),
            &[("LowLimit", "-300"), ("HighLimit", "300")],
        ),
        4 => out.var(
            index,
            &format!("Position {n}"),
            "0x0004",
            "rwr",
            Some("0x00000000"),
            &[("PDOMapping", "1")],
        ),
        5 => out.var(index, &format!("Gain {n}"), "0x0008", "rw", Some("1.5"), &[]),
        6 => out.var(
            index,
            &format!("Label {n}"),
            "0x0009",
            "const",
            Some(&format!("Channel {n}")),
            &[],
        ),
        7 => {
            out.aggregate(index, &format!("Sensor values {n}"), 8, 4);
            for sub in 1..=4 {
                out.sub(
                    index,
                    sub,
                    &format!("Sensor {sub}"),
                    "0x0007",
                    "ro",
                    &format!("0x{:08X}", n + sub),
                );
            }
        }
        8 => out.record(
            index,
            &format!("Channel parameter {n}"),
            &[
                ("COB-ID used", "0x0007", "rw", "$NODEID+0x200"),
                ("Transmission type", "0x0005", "rw", "0xFE"),
                ("Inhibit time", "0x0006", "rw", "0"),
            ],
        ),
        _ => out.var(index, &format!("Firmware block {n}"), "0x000F", "rw", None, &[]),
    }
}

#[cfg(test)]
mod tests {
    use canopener_eds::{ObjectType, Severity};
    use proptest::prelude::*;

    use super::*;

    #[test]
    fn canopener_loads_exactly_what_was_generated() {
        let eds = synthetic_eds(1000);
        let loaded = canopener_eds::load(eds.text.as_bytes());
        let errors: Vec<_> = loaded
            .diagnostics
            .iter()
            .filter(|d| d.severity == Severity::Error)
            .collect();
        assert!(
            errors.is_empty(),
            "the synthetic file departs from CiA 306: {errors:?}"
        );
        assert_eq!(loaded.eds.objects.len(), 1000);
        assert_eq!(eds.objects, 1000);
        let subs: usize = loaded.eds.objects.values().map(|o| o.subs.len()).sum();
        assert_eq!(subs, eds.sub_objects);
        // The kind follows the position in the file (0..1000): the 100 positions ending in 7 are
        // ARRAYs with 5 sub-objects, the 100 ending in 8 RECORDs with 4; the identity record has 5.
        assert_eq!(eds.sub_objects, 100 * 5 + 100 * 4 + 5);
    }

    #[test]
    fn the_mix_has_every_object_kind_and_resolvable_node_id_formulas() {
        let loaded = canopener_eds::load(synthetic_eds(20).text.as_bytes());
        let kinds: Vec<_> = loaded.eds.objects.values().map(|o| o.object_type()).collect();
        for kind in [ObjectType::Var, ObjectType::Array, ObjectType::Record] {
            assert!(kinds.contains(&Some(kind)), "no {kind:?} in {kinds:?}");
        }
        // Position 12 (index 2009h) is a COB-ID of `$NODEID+0x180`; position 8 (2005h) a RECORD
        // whose sub 1 is `$NODEID+0x200`.
        let cob_id = loaded.eds.default_value(0x2009, None).and_then(|v| v.resolve(5));
        assert_eq!(cob_id, Some(0x185));
        let record_cob_id = loaded
            .eds
            .default_value(0x2005, Some(1))
            .and_then(|v| v.resolve(0x10));
        assert_eq!(record_cob_id, Some(0x210));
    }

    #[test]
    fn object_lists_name_every_object_once() {
        let loaded = canopener_eds::load(synthetic_eds(20_000).text.as_bytes());
        let mut listed: Vec<u16> = loaded
            .eds
            .object_lists
            .values()
            .flat_map(|list| list.indices())
            .collect();
        listed.sort_unstable();
        let defined: Vec<u16> = loaded.eds.objects.keys().copied().collect();
        assert_eq!(listed, defined);
    }

    #[test]
    fn requests_beyond_the_index_space_are_clamped() {
        let eds = synthetic_eds(MAX_OBJECTS + 10);
        assert_eq!(eds.objects, MAX_OBJECTS);
        let loaded = canopener_eds::load(eds.text.as_bytes());
        assert_eq!(loaded.eds.objects.len(), MAX_OBJECTS);
        assert!(loaded.eds.objects.contains_key(&0xFFFF));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]

        #[test]
        fn any_size_loads_losslessly_with_the_promised_counts(objects in 0usize..400) {
            let eds = synthetic_eds(objects);
            prop_assert_eq!(&eds.text, &synthetic_eds(objects).text, "the generator is deterministic");
            let loaded = canopener_eds::load(eds.text.as_bytes());
            prop_assert_eq!(loaded.document.to_bytes().unwrap(), eds.text.as_bytes());
            prop_assert_eq!(loaded.eds.objects.len(), objects);
            let subs: usize = loaded.eds.objects.values().map(|o| o.subs.len()).sum();
            prop_assert_eq!(subs, eds.sub_objects);
            prop_assert!(loaded.diagnostics.iter().all(|d| d.severity != Severity::Error));
        }
    }
}

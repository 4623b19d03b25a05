//! The quirk matrix of the tools survey (§1c) as tests, plus encoding and line-ending fixtures.
//!
//! `test_data/quirks/baseline.eds` is a valid CiA 306 file that loads without a diagnostic; every other
//! fixture changes one thing (see `test_data/quirks/README.md`). Each test checks three things:
//! what canopener reads (the CiA 306 reading, not what a peer tool happens to do), the exact
//! diagnostics with their lines, and that the document writes back byte-identical. Where possible
//! the whole model is compared with the baseline's plus the one expected change, so a quirk cannot
//! silently damage anything else.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use canopener_eds::model::{ObjectList, Properties, Property, typed};
use canopener_eds::syntax::LineEnding;
use canopener_eds::text::Encoding;
use canopener_eds::value::{Radix, RealNotation, Value};
use canopener_eds::{
    Attributes, Code, DataType, Diagnostic, Eds, Loaded, Object, ObjectListKind, Origin, Severity, SubObject,
    load,
};
use proptest::prelude::*;

/// Every fixture in `test_data/quirks`, each covered by a test below.
const FIXTURES: &[&str] = &[
    "access-type-readwrite",
    "baseline",
    "bom",
    "crlf",
    "dummy-usage-partial",
    "duplicate-key",
    "duplicate-section",
    "empty",
    "hex-suffix",
    "inline-comment",
    "int16-hex-low-limit",
    "latin1",
    "listed-object-missing",
    "mixed-endings",
    "name-gap",
    "no-final-newline",
    "nodeid-spaces",
    "nodeid-suffix",
    "nodeid-three-terms",
    "object-links",
    "octal-leading-zero",
    "orphan-sub",
    "pdo-mapping-missing",
    "real32-bit-pattern",
    "real32-decimal",
    "sub-number-too-high",
    "sub-upper-case",
    "u8-out-of-range",
    "unlisted-object",
    "var-without-access-type",
];

fn quirks_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("test_data/quirks")
}

fn read_fixture(name: &str) -> Vec<u8> {
    let path = quirks_dir().join(format!("{name}.eds"));
    canopener_testkit::fixture::read(&path)
        .unwrap_or_else(|e| panic!("cannot read fixture {}: {e}", path.display()))
}

/// A loaded fixture whose lossless round trip has been checked.
struct Quirk {
    name: &'static str,
    bytes: Vec<u8>,
    loaded: Loaded,
}

impl Quirk {
    fn load(name: &'static str) -> Self {
        let bytes = read_fixture(name);
        let loaded = load(&bytes);
        let written = loaded
            .document
            .to_bytes()
            .expect("an unedited document encodes in its own encoding");
        assert!(written == bytes, "{name}.eds does not write back byte-identical");
        Self { name, bytes, loaded }
    }

    fn eds(&self) -> &Eds {
        &self.loaded.eds
    }

    /// The 1-based numbers of the lines whose content (without line ending) is exactly `content`.
    fn lines_of(&self, content: impl AsRef<[u8]>) -> Vec<u32> {
        let content = content.as_ref();
        let bytes = self.bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&self.bytes);
        let mut found = Vec::new();
        for (n, line) in bytes.split(|&b| b == b'\n').enumerate() {
            if line.strip_suffix(b"\r").unwrap_or(line) == content {
                found.push(u32::try_from(n + 1).expect("fixtures are short"));
            }
        }
        found
    }

    /// The number of the one line whose content is exactly `content`.
    fn line_of(&self, content: impl AsRef<[u8]>) -> u32 {
        let content = content.as_ref();
        match self.lines_of(content).as_slice() {
            [line] => *line,
            lines => panic!(
                "{}.eds has {content:?} on lines {lines:?}, expected exactly one",
                self.name
            ),
        }
    }

    /// The diagnostics as (code, severity, line), in the loader's order.
    fn diagnostics(&self) -> Vec<(Code, Severity, u32)> {
        self.loaded
            .diagnostics
            .iter()
            .map(|d| (d.code, d.severity, d.span.line))
            .collect()
    }

    fn assert_diagnostics(&self, expected: &[(Code, Severity, u32)]) {
        assert_eq!(
            self.diagnostics(),
            expected,
            "diagnostics of {}.eds:\n{}",
            self.name,
            self.listing()
        );
    }

    /// The model must be the baseline's with exactly the change `edit` makes.
    fn assert_model_is_baseline_with(&self, edit: impl FnOnce(&mut Eds)) {
        let mut expected = Quirk::load("baseline").loaded.eds;
        edit(&mut expected);
        assert_eq!(self.loaded.eds, expected, "model of {}.eds", self.name);
    }

    fn default_value(&self, index: u16, sub: Option<u8>) -> Option<Value> {
        self.eds().default_value(index, sub)
    }

    fn listing(&self) -> String {
        self.loaded.diagnostics.iter().map(|d| format!("{d}\n")).collect()
    }
}

/// The attributes of an object (`sub` `None`) or sub-object that the baseline has.
fn attributes(eds: &mut Eds, index: u16, sub: Option<u8>) -> &mut Attributes {
    let object = eds
        .objects
        .get_mut(&index)
        .unwrap_or_else(|| panic!("no object {index:04X}h"));
    match sub {
        None => &mut object.attributes,
        Some(s) => {
            &mut object
                .subs
                .get_mut(&s)
                .unwrap_or_else(|| panic!("no sub {s} of {index:04X}h"))
                .attributes
        }
    }
}

fn properties(entries: &[(&str, &str)]) -> Properties {
    Properties(
        entries
            .iter()
            .map(|(k, v)| Property {
                key: (*k).to_owned(),
                value: (*v).to_owned(),
            })
            .collect(),
    )
}

fn sub_names(eds: &Eds, index: u16) -> Vec<(u8, String)> {
    eds.objects[&index]
        .subs
        .iter()
        .map(|(s, o)| (*s, o.attributes.parameter_name.clone().unwrap_or_default()))
        .collect()
}

fn int(value: i128, radix: Radix) -> Value {
    Value::Integer { value, radix }
}

fn node_relative(offset: i128) -> Value {
    Value::NodeRelative {
        offset,
        radix: Radix::Hex,
    }
}

#[test]
fn baseline_is_valid_cia306_and_loads_without_diagnostics() {
    let q = Quirk::load("baseline");
    q.assert_diagnostics(&[]);
    let indices: Vec<u16> = q.eds().objects.keys().copied().collect();
    assert_eq!(
        indices,
        [
            0x1000, 0x1001, 0x1017, 0x1018, 0x1800, 0x1A00, 0x2000, 0x2001, 0x2002
        ]
    );
    assert!(q.eds().objects.values().all(|o| o.origin == Origin::Explicit));
    assert_eq!(
        q.eds().objects[&0x1018].subs.keys().copied().collect::<Vec<_>>(),
        [0, 1, 2, 3, 4]
    );
    assert_eq!(q.default_value(0x1018, Some(1)), Some(int(0xABCD, Radix::Hex)));
    assert_eq!(q.eds().device_info.vendor_number.as_deref(), Some("0x0000ABCD"));
    assert_eq!(
        q.eds().dummy_usage.as_ref().and_then(|d| d.get("Dummy0007")),
        Some("1")
    );
    // The mapping entry 0x20000108 is index 2000h, sub 1, 8 bits; that sub exists only through CompactSubObj.
    assert_eq!(
        q.default_value(0x1A00, Some(1)),
        Some(int(0x2000_0108, Radix::Hex))
    );
    let mapped = &q.eds().objects[&0x2000].subs[&1].attributes;
    assert_eq!(mapped.data_type(), Some(DataType::UNSIGNED8));
    let lists: Vec<(ObjectListKind, Vec<u16>)> = q
        .eds()
        .object_lists
        .iter()
        .map(|(k, l)| (*k, l.indices()))
        .collect();
    assert_eq!(
        lists,
        [
            (ObjectListKind::Mandatory, vec![0x1000, 0x1001, 0x1018]),
            (ObjectListKind::Optional, vec![0x1017, 0x1800, 0x1A00]),
            (ObjectListKind::Manufacturer, vec![0x2000, 0x2001, 0x2002]),
        ]
    );
}

/// Survey row "`CompactSubObj=3`, no Name section": the baseline itself (CiA 306 §4.6.3.4.2).
#[test]
fn compact_sub_obj_without_name_section_creates_sub_0_to_3_with_spec_names() {
    let q = Quirk::load("baseline");
    let names = sub_names(q.eds(), 0x2000);
    assert_eq!(
        names,
        [
            (0, "NrOfObjects".to_owned()),
            (1, "Analog input1".to_owned()),
            (2, "Analog input2".to_owned()),
            (3, "Analog input3".to_owned()),
        ]
    );
    let object = &q.eds().objects[&0x2000];
    assert!(object.subs.values().all(|s| s.origin == Origin::CompactSubObj));
    let sub0 = &object.subs[&0].attributes;
    assert_eq!(sub0.data_type(), Some(DataType::UNSIGNED8));
    assert_eq!(sub0.access_type.as_deref(), Some("ro"));
    assert!(!sub0.pdo_mapping());
    assert_eq!(q.default_value(0x2000, Some(0)), Some(int(3, Radix::Decimal)));
    for sub in 1..=3 {
        let a = &object.subs[&sub].attributes;
        assert_eq!(a.data_type(), Some(DataType::UNSIGNED8), "sub {sub}");
        assert_eq!(a.access_type.as_deref(), Some("ro"), "sub {sub}");
        assert!(a.pdo_mapping(), "sub {sub}");
        assert_eq!(
            q.default_value(0x2000, Some(sub)),
            Some(int(0, Radix::Decimal)),
            "sub {sub}"
        );
    }
}

/// Survey row "`[2000Name]` with gap": CiA 306 §4.6.3.4.2 allows a sparse list; sub 2 keeps its
/// default name.
#[test]
fn sparse_name_section_names_sub_1_and_3_and_sub_2_keeps_the_default() {
    let q = Quirk::load("name-gap");
    q.assert_diagnostics(&[]);
    let names: Vec<String> = sub_names(q.eds(), 0x2000).into_iter().map(|(_, n)| n).collect();
    assert_eq!(names, ["NrOfObjects", "Channel A", "Analog input2", "Channel C"]);
    q.assert_model_is_baseline_with(|eds| {
        let object = eds.objects.get_mut(&0x2000).unwrap();
        object.names = Some(properties(&[
            ("NrOfEntries", "2"),
            ("1", "Channel A"),
            ("3", "Channel C"),
        ]));
        attributes(eds, 0x2000, Some(1)).parameter_name = Some("Channel A".to_owned());
        attributes(eds, 0x2000, Some(3)).parameter_name = Some("Channel C".to_owned());
    });
}

/// Survey row "`DefaultValue=0254`": CiA 306 §4.2 reads a leading zero as octal, so 0254 = 172.
#[test]
fn leading_zero_reads_as_octal() {
    let q = Quirk::load("octal-leading-zero");
    assert_eq!(q.default_value(0x1800, Some(2)), Some(int(0o254, Radix::Octal)));
    assert_eq!(0o254, 172);
    q.assert_diagnostics(&[(
        Code::OctalLeadingZero,
        Severity::Warning,
        q.line_of("DefaultValue=0254"),
    )]);
    q.assert_model_is_baseline_with(|eds| {
        attributes(eds, 0x1800, Some(2)).default_value = Some("0254".to_owned());
    });
}

/// Survey row "`0x180+$NODEID`": CiA 306 §4.2 wants `$NODEID` first; the meaning is still node-ID + 0x180.
#[test]
fn nodeid_after_the_offset_reads_as_nodeid_plus_offset() {
    let q = Quirk::load("nodeid-suffix");
    let value = q.default_value(0x1800, Some(1));
    assert_eq!(value, Some(node_relative(0x180)));
    assert_eq!(value.and_then(|v| v.resolve(5)), Some(0x185));
    q.assert_diagnostics(&[(
        Code::NodeIdFormula,
        Severity::Error,
        q.line_of("DefaultValue=0x180+$NODEID"),
    )]);
    q.assert_model_is_baseline_with(|eds| {
        attributes(eds, 0x1800, Some(1)).default_value = Some("0x180+$NODEID".to_owned());
    });
}

/// Survey row "`$NODEID + 0x180` (spaces)": fine for every peer, reported as a spelling hint.
#[test]
fn nodeid_formula_with_spaces_reads_as_nodeid_plus_offset() {
    let q = Quirk::load("nodeid-spaces");
    let value = q.default_value(0x1800, Some(1));
    assert_eq!(value, Some(node_relative(0x180)));
    assert_eq!(value.and_then(|v| v.resolve(5)), Some(0x185));
    q.assert_diagnostics(&[(
        Code::NodeIdSpelling,
        Severity::Info,
        q.line_of("DefaultValue=$NODEID + 0x180"),
    )]);
    q.assert_model_is_baseline_with(|eds| {
        attributes(eds, 0x1800, Some(1)).default_value = Some("$NODEID + 0x180".to_owned());
    });
}

/// Survey row "`0x40000000+$NODEID+0x180`": both constants are summed (bit 30 of a TPDO COB-ID = no RTR).
#[test]
fn nodeid_between_two_offsets_sums_both_offsets() {
    let q = Quirk::load("nodeid-three-terms");
    let value = q.default_value(0x1800, Some(1));
    assert_eq!(value, Some(node_relative(0x4000_0180)));
    assert_eq!(value.and_then(|v| v.resolve(5)), Some(0x4000_0185));
    q.assert_diagnostics(&[(
        Code::NodeIdFormula,
        Severity::Error,
        q.line_of("DefaultValue=0x40000000+$NODEID+0x180"),
    )]);
    q.assert_model_is_baseline_with(|eds| {
        attributes(eds, 0x1800, Some(1)).default_value = Some("0x40000000+$NODEID+0x180".to_owned());
    });
}

/// Survey row "`[DummyUsage]` lacks `Dummy0007`": CiA 306 §4.6.2 entries are per data type and a missing
/// key means the same as an empty one, so UNSIGNED32 is simply not a dummy; the file is valid.
#[test]
fn dummy_usage_without_dummy0007_loads_the_other_entries() {
    let q = Quirk::load("dummy-usage-partial");
    q.assert_diagnostics(&[]);
    let dummy = q.eds().dummy_usage.as_ref().expect("the section is present");
    assert_eq!(dummy.get("Dummy0007"), None);
    assert_eq!(dummy.get("Dummy0006"), Some("1"));
    assert_eq!(dummy.0.len(), 6);
    q.assert_model_is_baseline_with(|eds| {
        let dummy = eds.dummy_usage.as_mut().unwrap();
        dummy.0.retain(|p| p.key != "Dummy0007");
    });
}

/// Survey row "duplicate section": the first `[1017]` is used and both lines are named.
#[test]
fn duplicate_section_keeps_the_first_and_names_both_lines() {
    let q = Quirk::load("duplicate-section");
    let headers = q.lines_of("[1017]");
    assert_eq!(headers.len(), 2);
    q.assert_diagnostics(&[(Code::DuplicateSection, Severity::Error, headers[1])]);
    assert!(
        q.loaded.diagnostics[0]
            .message
            .contains(&format!("line {}", headers[0])),
        "{}",
        q.loaded.diagnostics[0].message
    );
    assert_eq!(q.eds().objects[&0x1017].name(), "Producer heartbeat time");
    assert_eq!(q.default_value(0x1017, None), Some(int(1000, Radix::Decimal)));
    q.assert_model_is_baseline_with(|_| {});
}

/// Survey row "duplicate key": the first `DefaultValue` is used and both lines are named.
#[test]
fn duplicate_key_keeps_the_first_value_and_names_both_lines() {
    let q = Quirk::load("duplicate-key");
    q.assert_diagnostics(&[(
        Code::DuplicateKey,
        Severity::Error,
        q.line_of("DefaultValue=2000"),
    )]);
    let first = q.line_of("DefaultValue=1000");
    assert!(
        q.loaded.diagnostics[0].message.contains(&format!("line {first}")),
        "{}",
        q.loaded.diagnostics[0].message
    );
    assert_eq!(q.default_value(0x1017, None), Some(int(1000, Radix::Decimal)));
    q.assert_model_is_baseline_with(|_| {});
}

/// Survey row "`[2000ObjectLinks]`": defined by CiA 306 §4.6.4, so it is kept on its object, silently.
#[test]
fn object_links_section_is_kept_on_its_object() {
    let q = Quirk::load("object-links");
    q.assert_diagnostics(&[]);
    let links = q.eds().objects[&0x2000]
        .object_links
        .as_ref()
        .expect("links are kept");
    assert_eq!(links.get("ObjectLinks"), Some("2"));
    assert_eq!(
        links.numbered().collect::<Vec<_>>(),
        [(1, "0x2001"), (2, "0x2002")]
    );
    q.assert_model_is_baseline_with(|eds| {
        eds.objects.get_mut(&0x2000).unwrap().object_links = Some(properties(&[
            ("ObjectLinks", "2"),
            ("1", "0x2001"),
            ("2", "0x2002"),
        ]));
    });
}

/// Survey row "`[1018SUB1]`": section names are case-insensitive (CiA 306 §4.2), so this is sub 1.
#[test]
fn upper_case_sub_section_is_sub_1_of_1018() {
    let q = Quirk::load("sub-upper-case");
    assert_eq!(q.default_value(0x1018, Some(1)), Some(int(0xABCD, Radix::Hex)));
    assert_eq!(
        q.eds().objects[&0x1018].subs[&1]
            .attributes
            .parameter_name
            .as_deref(),
        Some("Vendor-ID")
    );
    q.assert_diagnostics(&[(
        Code::NonCanonicalSectionName,
        Severity::Warning,
        q.line_of("[1018SUB1]"),
    )]);
    q.assert_model_is_baseline_with(|_| {});
}

/// Survey row "sub-section without parent `[3000sub1]`": kept as an orphan, not dropped.
#[test]
fn orphan_sub_section_is_kept_as_an_orphan() {
    let q = Quirk::load("orphan-sub");
    let orphan = &q.eds().objects[&0x3000];
    assert_eq!(orphan.origin, Origin::Orphan);
    assert_eq!(
        orphan.subs[&1].attributes.parameter_name.as_deref(),
        Some("Orphan value")
    );
    assert_eq!(q.default_value(0x3000, Some(1)), Some(int(7, Radix::Decimal)));
    q.assert_diagnostics(&[(Code::OrphanSubObject, Severity::Error, q.line_of("[3000sub1]"))]);
    q.assert_model_is_baseline_with(|eds| {
        let mut sub = Attributes::default();
        for (key, value) in [
            ("ParameterName", "Orphan value"),
            ("ObjectType", "0x7"),
            ("DataType", "0x0005"),
            ("AccessType", "ro"),
            ("DefaultValue", "7"),
            ("PDOMapping", "0"),
        ] {
            sub.set(key, value);
        }
        let mut object = Object {
            origin: Origin::Orphan,
            ..Object::default()
        };
        object.subs.insert(
            1,
            SubObject {
                attributes: sub,
                origin: Origin::Explicit,
            },
        );
        eds.objects.insert(0x3000, object);
    });
}

/// Survey row "VAR without `AccessType`": CiA 306 §4.6.3.2 makes it mandatory; the object stays with
/// every other key.
#[test]
fn var_without_access_type_is_kept_with_its_other_keys() {
    let q = Quirk::load("var-without-access-type");
    let object = &q.eds().objects[&0x1017];
    assert_eq!(object.name(), "Producer heartbeat time");
    assert_eq!(object.attributes.access_type, None);
    assert_eq!(object.attributes.data_type(), Some(DataType::UNSIGNED16));
    assert_eq!(q.default_value(0x1017, None), Some(int(1000, Radix::Decimal)));
    q.assert_diagnostics(&[(Code::MissingKey, Severity::Error, q.line_of("[1017]"))]);
    q.assert_model_is_baseline_with(|eds| attributes(eds, 0x1017, None).access_type = None);
}

/// Survey row "`FEh`": not a CiA 306 §4.2 number; the evident meaning 0xFE is read and reported.
#[test]
fn hex_suffix_reads_as_hex_and_is_an_error() {
    let q = Quirk::load("hex-suffix");
    assert_eq!(q.default_value(0x1800, Some(2)), Some(int(0xFE, Radix::Hex)));
    q.assert_diagnostics(&[(Code::HexSuffix, Severity::Error, q.line_of("DefaultValue=FEh"))]);
    q.assert_model_is_baseline_with(|eds| {
        attributes(eds, 0x1800, Some(2)).default_value = Some("FEh".to_owned())
    });
}

/// Survey row "object listed in `[OptionalObjects]` but section missing" (CiA 306 §4.6.3.1).
#[test]
fn listed_object_without_a_section_is_reported_at_its_list_entry() {
    let q = Quirk::load("listed-object-missing");
    assert!(!q.eds().objects.contains_key(&0x1008));
    assert_eq!(
        q.eds().object_lists[&ObjectListKind::Optional].indices(),
        [0x1017, 0x1800, 0x1A00, 0x1008]
    );
    q.assert_diagnostics(&[(Code::ListedObjectMissing, Severity::Error, q.line_of("4=0x1008"))]);
    q.assert_model_is_baseline_with(|eds| {
        eds.object_lists.insert(
            ObjectListKind::Optional,
            ObjectList::from_indices([0x1017, 0x1800, 0x1A00, 0x1008]),
        );
    });
}

/// Survey row "section present but not listed": loaded, and reported because lely would ignore it.
#[test]
fn unlisted_object_is_loaded_and_reported() {
    let q = Quirk::load("unlisted-object");
    assert_eq!(q.default_value(0x1017, None), Some(int(1000, Radix::Decimal)));
    q.assert_diagnostics(&[(Code::UnlistedObject, Severity::Error, q.line_of("[1017]"))]);
    q.assert_model_is_baseline_with(|eds| {
        eds.object_lists.insert(
            ObjectListKind::Optional,
            ObjectList::from_indices([0x1800, 0x1A00]),
        );
    });
}

/// Survey row "UNSIGNED8 `DefaultValue=300`": kept as 300 (never truncated to 44) and reported.
#[test]
fn unsigned8_300_is_kept_as_300_and_reported() {
    let q = Quirk::load("u8-out-of-range");
    assert_eq!(q.default_value(0x1800, Some(2)), Some(int(300, Radix::Decimal)));
    q.assert_diagnostics(&[(Code::OutOfRange, Severity::Error, q.line_of("DefaultValue=300"))]);
    q.assert_model_is_baseline_with(|eds| {
        attributes(eds, 0x1800, Some(2)).default_value = Some("300".to_owned())
    });
}

/// Survey row "`SubNumber` > sub-sections present" (CiA 306 §4.6.3.2: SubNumber counts implemented subs).
#[test]
fn sub_number_above_the_sub_sections_present_is_reported() {
    let q = Quirk::load("sub-number-too-high");
    assert_eq!(q.eds().objects[&0x1018].attributes.sub_number(), Some(6));
    assert_eq!(q.eds().objects[&0x1018].subs.len(), 5);
    q.assert_diagnostics(&[(Code::SubNumberMismatch, Severity::Error, q.line_of("SubNumber=6"))]);
    q.assert_model_is_baseline_with(|eds| attributes(eds, 0x1018, None).sub_number = Some("6".to_owned()));
}

/// Survey row "`AccessType=readwrite`": not one of the six CiA 306 §4.6.3.2 tokens; kept as written.
#[test]
fn access_type_readwrite_is_kept_verbatim_and_reported() {
    let q = Quirk::load("access-type-readwrite");
    let a = &q.eds().objects[&0x1017].attributes;
    assert_eq!(a.access_type.as_deref(), Some("readwrite"));
    assert_eq!(a.access_type(), None);
    assert_eq!(q.default_value(0x1017, None), Some(int(1000, Radix::Decimal)));
    q.assert_diagnostics(&[(
        Code::UnknownAccessType,
        Severity::Error,
        q.line_of("AccessType=readwrite"),
    )]);
    q.assert_model_is_baseline_with(|eds| {
        attributes(eds, 0x1017, None).access_type = Some("readwrite".to_owned())
    });
}

/// Survey row "REAL32 `DefaultValue=0x3F800000`": the IEEE 754 bit pattern of 1.0, notation remembered.
#[test]
fn real32_bit_pattern_reads_as_1_0() {
    let q = Quirk::load("real32-bit-pattern");
    assert_eq!(
        q.default_value(0x2001, None),
        Some(Value::Real {
            value: 1.0,
            notation: RealNotation::BitPattern
        })
    );
    q.assert_diagnostics(&[(
        Code::RealNotation,
        Severity::Info,
        q.line_of("DefaultValue=0x3F800000"),
    )]);
    q.assert_model_is_baseline_with(|eds| {
        attributes(eds, 0x2001, None).default_value = Some("0x3F800000".to_owned());
    });
}

/// Survey row "REAL32 `DefaultValue=1.5`": CiA 306 V1.3 does not specify REALs; decimal is read as 1.5.
#[test]
fn real32_decimal_reads_as_1_5() {
    let q = Quirk::load("real32-decimal");
    assert_eq!(
        q.default_value(0x2001, None),
        Some(Value::Real {
            value: 1.5,
            notation: RealNotation::Decimal
        })
    );
    q.assert_diagnostics(&[(Code::RealNotation, Severity::Info, q.line_of("DefaultValue=1.5"))]);
    q.assert_model_is_baseline_with(|eds| {
        attributes(eds, 0x2001, None).default_value = Some("1.5".to_owned())
    });
}

/// Survey row "INTEGER16 `LowLimit=0x8000`": the two's complement bit pattern of -32768, not an overflow.
#[test]
fn integer16_low_limit_0x8000_reads_as_minus_32768() {
    let q = Quirk::load("int16-hex-low-limit");
    let a = &q.eds().objects[&0x2002].attributes;
    assert_eq!(a.data_type(), Some(DataType::INTEGER16));
    assert_eq!(
        typed(a.low_limit.as_deref(), a.data_type()).value,
        Some(int(-32768, Radix::Hex))
    );
    assert_eq!(
        typed(a.high_limit.as_deref(), a.data_type()).value,
        Some(int(100, Radix::Decimal))
    );
    q.assert_diagnostics(&[(
        Code::TwosComplement,
        Severity::Warning,
        q.line_of("LowLimit=0x8000"),
    )]);
    q.assert_model_is_baseline_with(|eds| {
        attributes(eds, 0x2002, None).low_limit = Some("0x8000".to_owned())
    });
}

/// Survey row "inline `; comment` after value": CiA 306 §4.2 has whole-line comments only; 254 is read.
#[test]
fn inline_comment_after_a_value_reads_the_value() {
    let q = Quirk::load("inline-comment");
    assert_eq!(q.default_value(0x1800, Some(2)), Some(int(254, Radix::Decimal)));
    q.assert_diagnostics(&[(
        Code::InlineComment,
        Severity::Warning,
        q.line_of("DefaultValue=254 ; async"),
    )]);
    // The model keeps the text as written, so the lossless writer can reproduce it.
    q.assert_model_is_baseline_with(|eds| {
        attributes(eds, 0x1800, Some(2)).default_value = Some("254 ; async".to_owned());
    });
}

/// Survey row "`dcfchk` without `-n`": an EDS has no node-ID, so `$NODEID` formulas stay symbolic and
/// resolve for whichever node-ID the caller gives.
#[test]
fn nodeid_formula_stays_symbolic_without_a_node_id() {
    let q = Quirk::load("baseline");
    assert_eq!(q.eds().node_id(), None);
    let value = q
        .default_value(0x1800, Some(1))
        .expect("the COB-ID has a default");
    assert_eq!(value, node_relative(0x180));
    assert_eq!(value.resolve(5), Some(0x185));
    assert_eq!(value.resolve(127), Some(0x1FF));
}

/// Survey row "TPDO comm 1800 present, mapping 1A00 missing": CiA 301 PDOs need both objects.
#[test]
fn tpdo_without_its_mapping_object_is_reported_at_the_communication_object() {
    let q = Quirk::load("pdo-mapping-missing");
    assert!(q.eds().objects.contains_key(&0x1800));
    assert!(!q.eds().objects.contains_key(&0x1A00));
    q.assert_diagnostics(&[(Code::PdoPairIncomplete, Severity::Error, q.line_of("[1800]"))]);
    q.assert_model_is_baseline_with(|eds| {
        eds.objects.remove(&0x1A00);
        eds.object_lists.insert(
            ObjectListKind::Optional,
            ObjectList::from_indices([0x1017, 0x1800]),
        );
    });
}

/// A UTF-8 byte order mark: CiA 306 §4.2 wants ASCII; the content is read as without it.
#[test]
fn utf8_bom_is_kept_and_the_content_reads_as_the_baseline() {
    let q = Quirk::load("bom");
    assert!(q.bytes.starts_with(b"\xEF\xBB\xBF[FileInfo]"));
    assert_eq!(q.loaded.document.encoding(), Encoding::Utf8Bom);
    q.assert_diagnostics(&[(Code::ByteOrderMark, Severity::Error, 1)]);
    q.assert_model_is_baseline_with(|_| {});
}

/// A Windows-1252 `°` (byte B0h) in a ParameterName: decoded, reported at the byte, written back as B0h.
#[test]
fn latin1_degree_sign_is_decoded_as_windows_1252() {
    let q = Quirk::load("latin1");
    let line = q.line_of(b"ParameterName=Temperature setpoint \xB0C");
    assert_eq!(q.loaded.document.encoding(), Encoding::Windows1252);
    assert_eq!(q.eds().objects[&0x2001].name(), "Temperature setpoint \u{B0}C");
    q.assert_diagnostics(&[(Code::Windows1252, Severity::Error, line)]);
    let column = u32::try_from("ParameterName=Temperature setpoint ".len() + 1).unwrap();
    assert_eq!(q.loaded.diagnostics[0].span.column, column);
    q.assert_model_is_baseline_with(|eds| {
        attributes(eds, 0x2001, None).parameter_name = Some("Temperature setpoint \u{B0}C".to_owned());
    });
}

/// The empty file loads to an empty model and writes back as zero bytes.
#[test]
fn empty_file_loads_to_an_empty_model() {
    let q = Quirk::load("empty");
    assert!(q.bytes.is_empty());
    assert_eq!(q.eds(), &Eds::default());
    assert!(q.loaded.document.sections().is_empty());
}

/// An empty file lacks every section CiA 306 §4.4–§4.6 makes mandatory ([FileInfo], [DeviceInfo], the
/// object lists, objects 1000h, 1001h and 1018h), so loading must say so.
#[test]
fn empty_file_is_diagnosed() {
    let q = Quirk::load("empty");
    q.assert_diagnostics(&[(Code::MissingSection, Severity::Error, 1)]);
    assert_eq!(q.loaded.diagnostics[0].message, "the file is empty");
}

/// CR/LF line endings are allowed by CiA 306 §4.2.
#[test]
fn crlf_file_reads_as_the_baseline_without_diagnostics() {
    let q = Quirk::load("crlf");
    assert!(
        q.loaded
            .document
            .lines()
            .iter()
            .all(|l| l.ending == LineEnding::CrLf)
    );
    q.assert_diagnostics(&[]);
    q.assert_model_is_baseline_with(|_| {});
}

/// LF and CR/LF in one file (a section pasted in from another editor): each ending is kept.
#[test]
fn mixed_line_endings_are_kept_and_reported_once() {
    let q = Quirk::load("mixed-endings");
    let header = q.line_of("[1017]");
    q.assert_diagnostics(&[(Code::MixedLineEndings, Severity::Info, header)]);
    // The seven lines of [1017] end in CR/LF, every other line in LF.
    let crlf_lines: Vec<u32> = (1..)
        .zip(q.loaded.document.lines())
        .filter(|(_, l)| l.ending == LineEnding::CrLf)
        .map(|(n, _)| n)
        .collect();
    assert_eq!(crlf_lines, (header..header + 7).collect::<Vec<u32>>());
    assert!(
        q.loaded
            .document
            .lines()
            .iter()
            .all(|l| matches!(l.ending, LineEnding::Lf | LineEnding::CrLf))
    );
    q.assert_model_is_baseline_with(|_| {});
}

/// A missing final newline is kept; the last entry still reads.
#[test]
fn missing_final_newline_is_kept() {
    let q = Quirk::load("no-final-newline");
    assert!(q.bytes.ends_with(b"PDOMapping=0"));
    assert_eq!(
        q.loaded.document.lines().last().map(|l| l.ending),
        Some(LineEnding::None)
    );
    q.assert_diagnostics(&[]);
    q.assert_model_is_baseline_with(|_| {});
}

/// Guards the fixture set: every file is listed above, round-trips, and has a row in the README table.
#[test]
fn every_fixture_is_listed_round_trips_and_is_documented() {
    let on_disk: BTreeSet<String> = canopener_testkit::fixture::list(quirks_dir())
        .expect("the fixture directory is readable")
        .iter()
        .filter_map(|path| {
            path.file_name()?
                .to_str()?
                .strip_suffix(".eds")
                .map(str::to_owned)
        })
        .collect();
    let listed: BTreeSet<String> = FIXTURES.iter().map(|s| (*s).to_owned()).collect();
    assert_eq!(on_disk, listed);
    let readme = canopener_testkit::fixture::read_to_string(quirks_dir().join("README.md"))
        .expect("README.md is readable");
    for name in FIXTURES {
        Quirk::load(name);
        assert!(
            readme.contains(&format!("`{name}.eds`")),
            "README.md has no row for {name}.eds"
        );
    }
}

/// Every fixture's diagnostics with their messages, as a reviewed listing.
#[test]
fn diagnostics_of_every_fixture() {
    let mut listing = String::new();
    for name in FIXTURES {
        let q = Quirk::load(name);
        listing.push_str(&format!("{name}.eds\n"));
        for d in &q.loaded.diagnostics {
            listing.push_str(&format!("  {d}\n"));
        }
    }
    insta::assert_snapshot!(listing);
}

/// Fixtures written with LF only, so their line endings, BOM and final newline can be varied.
const LF_FIXTURES: &[&str] = &[
    "access-type-readwrite",
    "baseline",
    "dummy-usage-partial",
    "duplicate-key",
    "duplicate-section",
    "hex-suffix",
    "inline-comment",
    "int16-hex-low-limit",
    "latin1",
    "listed-object-missing",
    "name-gap",
    "no-final-newline",
    "nodeid-spaces",
    "nodeid-suffix",
    "nodeid-three-terms",
    "object-links",
    "octal-leading-zero",
    "orphan-sub",
    "pdo-mapping-missing",
    "real32-bit-pattern",
    "real32-decimal",
    "sub-number-too-high",
    "sub-upper-case",
    "u8-out-of-range",
    "unlisted-object",
    "var-without-access-type",
];

/// A fixture rewritten with a chosen line layout, and which endings it ended up using.
struct Layout {
    bytes: Vec<u8>,
    uses_lf: bool,
    uses_crlf: bool,
}

/// Rewrites LF-only `bytes` with the ending `crlf[i]` picks for line `i` (LF beyond the vector), an
/// optional BOM and an optional final newline.
fn with_layout(bytes: &[u8], crlf: &[bool], bom: bool, final_newline: bool) -> Layout {
    let body = bytes.strip_suffix(b"\n").unwrap_or(bytes);
    let lines: Vec<&[u8]> = body.split(|&b| b == b'\n').collect();
    let mut layout = Layout {
        bytes: Vec::with_capacity(bytes.len() + lines.len() + 3),
        uses_lf: false,
        uses_crlf: false,
    };
    if bom {
        layout.bytes.extend_from_slice(b"\xEF\xBB\xBF");
    }
    for (i, line) in lines.iter().enumerate() {
        layout.bytes.extend_from_slice(line);
        let is_last = i + 1 == lines.len();
        if is_last && !final_newline {
            continue;
        }
        if crlf.get(i).copied().unwrap_or(false) {
            layout.bytes.extend_from_slice(b"\r\n");
            layout.uses_crlf = true;
        } else {
            layout.bytes.push(b'\n');
            layout.uses_lf = true;
        }
    }
    layout
}

proptest! {
    /// CiA 306 §4.2 lets lines end in LF or CR/LF: the layout of a file never changes its model or its
    /// other diagnostics, only adds P002 for a BOM and P003 when both endings occur, and always
    /// writes back byte-identical.
    #[test]
    fn line_endings_bom_and_final_newline_change_nothing_else(
        fixture in 0..LF_FIXTURES.len(),
        crlf in proptest::collection::vec(any::<bool>(), 240),
        bom in any::<bool>(),
        final_newline in any::<bool>(),
    ) {
        let name = LF_FIXTURES[fixture];
        let original = read_fixture(name);
        // A BOM announces UTF-8, which a Windows-1252 file is not; that combination is a different quirk.
        let bom = bom && name != "latin1";
        let layout = with_layout(&original, &crlf, bom, final_newline);
        let reference = load(&original);
        let loaded = load(&layout.bytes);
        prop_assert_eq!(loaded.document.to_bytes().unwrap(), layout.bytes);
        prop_assert_eq!(&loaded.eds, &reference.eds);
        let is_layout = |d: &&Diagnostic| matches!(d.code, Code::ByteOrderMark | Code::MixedLineEndings);
        let other: Vec<_> = loaded.diagnostics.iter().filter(|d| !is_layout(d)).collect();
        let expected: Vec<_> = reference.diagnostics.iter().filter(|d| !is_layout(d)).collect();
        prop_assert_eq!(other, expected);
        let codes: Vec<Code> = loaded.diagnostics.iter().filter(|d| is_layout(d)).map(|d| d.code).collect();
        let mut expected_codes = Vec::new();
        if bom {
            expected_codes.push(Code::ByteOrderMark);
        }
        if layout.uses_lf && layout.uses_crlf {
            expected_codes.push(Code::MixedLineEndings);
        }
        prop_assert_eq!(codes, expected_codes);
    }
}

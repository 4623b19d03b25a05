//! The shipped pack `packs/seed-paper.toml`: every rule trips on a small file that breaks it and stays
//! quiet on a near miss, its fixes edit the expected lines, and on real corpus files it reports what
//! those files really contain.

use std::collections::{BTreeMap, BTreeSet};

use canopener_check::fix::{self, Edit, Fix};
use canopener_check::{Context, Finding, Selection};
use canopener_rules::{RulePack, parse_pack};
use canopener_testkit::corpus::{self, Kind};

const PACK: &str = include_str!("../packs/seed-paper.toml");

/// A file every rule of the pack accepts.
const BASE: &str = "\
[FileInfo]
FileName=t.eds
[DeviceInfo]
VendorName=ACME
VendorNumber=0x1234
BaudRate_125=1
BaudRate_250=1
BaudRate_500=1
BaudRate_1000=0
[MandatoryObjects]
SupportedObjects=2
1=0x1000
2=0x1018
[1000]
ParameterName=Device_type
ObjectType=0x7
DataType=0x0007
AccessType=ro
DefaultValue=0x00000191
[1018]
ParameterName=Identity
ObjectType=0x9
SubNumber=2
[1018sub0]
ParameterName=Highest_sub_index
DataType=0x0005
AccessType=ro
DefaultValue=1
[1018sub1]
ParameterName=Vendor_ID
DataType=0x0007
AccessType=ro
DefaultValue=0x1234
[OptionalObjects]
SupportedObjects=2
1=0x1005
2=0x1017
[1005]
ParameterName=COB_ID_SYNC
DataType=0x0007
AccessType=rw
DefaultValue=0x00000080
[1017]
ParameterName=Producer_heartbeat_time
DataType=0x0006
AccessType=rw
DefaultValue=1000
[ManufacturerObjects]
SupportedObjects=1
1=0x2000
[2000]
ParameterName=Gain
ObjectType=0x7
DataType=0x0006
AccessType=rw
DefaultValue=10
LowLimit=0
HighLimit=100
";

fn pack() -> RulePack {
    parse_pack(PACK, "packs/seed-paper.toml").unwrap_or_else(|e| panic!("{e}"))
}

/// `BASE` with each `(from, to)` replaced (each `from` must occur exactly once).
fn edited(edits: &[(&str, &str)]) -> String {
    let mut text = BASE.to_owned();
    for (from, to) in edits {
        assert_eq!(text.matches(from).count(), 1, "`{from}` must occur once");
        text = text.replacen(from, to, 1);
    }
    text
}

fn check_with(pack: &RulePack, text: &str) -> Vec<Finding> {
    let loaded = canopener_eds::load(text.as_bytes());
    let cx = Context::new(&loaded, Some("t.eds"));
    pack.check(&cx, &Selection::default())
}

fn check(text: &str) -> Vec<Finding> {
    check_with(&pack(), text)
}

fn of<'a>(findings: &'a [Finding], code: &str) -> Vec<&'a Finding> {
    findings.iter().filter(|f| f.diagnostic.code == code).collect()
}

fn fixes(text: &str, code: &str) -> Vec<Fix> {
    let loaded = canopener_eds::load(text.as_bytes());
    let cx = Context::new(&loaded, Some("t.eds"));
    let selection = Selection {
        only: vec![code.to_owned()],
        ..Selection::default()
    };
    pack().fixes(&cx, &selection)
}

/// The file after applying fixes once, as text.
fn applied(text: &str, fixes: &[Fix]) -> String {
    let loaded = canopener_eds::load(text.as_bytes());
    let result = fix::apply(&loaded.document, fixes);
    assert!(result.skipped.is_empty(), "skipped: {:?}", result.skipped);
    String::from_utf8(result.document.to_bytes().unwrap_or_default()).unwrap_or_default()
}

#[test]
fn the_pack_has_the_papers_checks_and_the_policies() {
    assert_eq!(
        pack().rule_ids(),
        [
            "paper/no-blank-names",
            "paper/unique-object-names",
            "paper/unique-sub-names",
            "paper/required-baud-rates",
            "paper/sync-cob-id",
            "policy/vendor-id-set",
            "policy/heartbeat-enabled",
            "policy/writable-limits",
        ]
    );
}

#[test]
fn the_base_file_passes_every_rule() {
    assert_eq!(check(BASE), Vec::<Finding>::new());
}

#[test]
fn blanks_in_names_are_found_in_objects_and_sub_objects() {
    let found = check(&edited(&[
        ("ParameterName=Gain", "ParameterName=Motor  gain"),
        ("=Vendor_ID", "=Vendor ID"),
    ]));
    let blanks = of(&found, "paper/no-blank-names");
    assert_eq!(blanks.len(), 2, "{found:#?}");
    assert_eq!(
        blanks[0].diagnostic.message,
        "ParameterName 'Vendor ID' contains 1 blank(s)"
    );
    assert_eq!(blanks[0].diagnostic.section.as_deref(), Some("1018sub1"));
    assert_eq!(blanks[0].diagnostic.key.as_deref(), Some("ParameterName"));
    assert_eq!(
        (blanks[0].diagnostic.span.line, blanks[0].diagnostic.span.column),
        (30, 15)
    );
    assert!(blanks[0].fixable);
    assert_eq!(
        blanks[1].diagnostic.message,
        "ParameterName 'Motor  gain' contains 2 blank(s)"
    );
    assert_eq!(
        blanks[1].diagnostic.help.as_deref(),
        Some("write 'Motor__gain' instead, or let `canopener eds fix` do it")
    );
    // Underscores and other punctuation are fine.
    assert!(
        of(
            &check(&edited(&[("=Gain", "=Motor_gain-2.0")])),
            "paper/no-blank-names"
        )
        .is_empty()
    );
}

#[test]
fn the_blank_fix_replaces_blanks_and_says_it_changes_meaning() {
    let text = edited(&[("ParameterName=Gain", "ParameterName=Motor gain")]);
    let planned = fixes(&text, "paper/no-blank-names");
    assert_eq!(planned.len(), 1);
    assert_eq!(planned[0].code, "paper/no-blank-names");
    assert_eq!(
        planned[0].description,
        "[2000] ParameterName: Motor gain -> Motor_gain"
    );
    assert!(planned[0].changes_meaning);
    assert_eq!(
        planned[0].edits,
        [Edit::SetValue {
            line: 51,
            value: "Motor_gain".to_owned()
        }]
    );
    let fixed = applied(&text, &planned);
    assert_eq!(
        fixed,
        edited(&[("ParameterName=Gain", "ParameterName=Motor_gain")])
    );
    assert!(check(&fixed).is_empty());
}

#[test]
fn duplicate_object_names_are_found_file_wide() {
    let found = check(&edited(&[("ParameterName=Gain", "ParameterName=Identity")]));
    let dups = of(&found, "paper/unique-object-names");
    let sections: Vec<_> = dups.iter().map(|f| f.diagnostic.section.as_deref()).collect();
    assert_eq!(sections, [Some("1018"), Some("2000")]);
    assert_eq!(
        dups[0].diagnostic.message,
        "ParameterName 'Identity' is also used by [2000]"
    );
    assert_eq!(
        dups[1].diagnostic.help.as_deref(),
        Some("give each object a distinct name, e.g. 'Identity_2000'")
    );
    // An object may share its name with a sub-object: only objects are compared.
    assert!(check(&edited(&[("ParameterName=Gain", "ParameterName=Vendor_ID")])).is_empty());
}

#[test]
fn the_unique_name_fix_appends_the_index() {
    let text = edited(&[("ParameterName=Gain", "ParameterName=Identity")]);
    let planned = fixes(&text, "paper/unique-object-names");
    let descriptions: Vec<_> = planned.iter().map(|f| f.description.as_str()).collect();
    assert_eq!(
        descriptions,
        [
            "[1018] ParameterName: Identity -> Identity_1018",
            "[2000] ParameterName: Identity -> Identity_2000"
        ]
    );
    assert!(check(&applied(&text, &planned)).is_empty());
}

#[test]
fn duplicate_sub_object_names_are_found_per_object() {
    let found = check(&edited(&[("=Vendor_ID", "=Highest_sub_index")]));
    let dups = of(&found, "paper/unique-sub-names");
    assert_eq!(dups.len(), 2);
    assert_eq!(
        dups[0].diagnostic.message,
        "ParameterName 'Highest_sub_index' is used by 2 sub-objects of [1018] 'Identity'"
    );
    let planned = fixes(
        &edited(&[("=Vendor_ID", "=Highest_sub_index")]),
        "paper/unique-sub-names",
    );
    let descriptions: Vec<_> = planned.iter().map(|f| f.description.as_str()).collect();
    assert_eq!(
        descriptions,
        [
            "[1018sub0] ParameterName: Highest_sub_index -> Highest_sub_index_0",
            "[1018sub1] ParameterName: Highest_sub_index -> Highest_sub_index_1"
        ]
    );
    // A sub-object may share its name with another object's sub-object or with an object.
    let extra = "[2001]\nParameterName=Pair\nObjectType=0x9\nSubNumber=1\n\
                 [2001sub0]\nParameterName=Highest_sub_index\nDataType=0x0005\nAccessType=ro\nDefaultValue=0\n";
    let text = edited(&[("=Vendor_ID", "=Gain"), ("1=0x2000\n", "1=0x2000\n")]) + extra;
    let text = text.replace(
        "SupportedObjects=1\n1=0x2000",
        "SupportedObjects=2\n1=0x2000\n2=0x2001",
    );
    assert_eq!(check(&text), Vec::<Finding>::new());
}

#[test]
fn missing_baud_rates_are_named() {
    let found = check(&edited(&[
        ("BaudRate_250=1", "BaudRate_250=0"),
        ("BaudRate_500=1\n", ""),
    ]));
    let baud = of(&found, "paper/required-baud-rates");
    assert_eq!(baud.len(), 1);
    assert_eq!(
        baud[0].diagnostic.message,
        "required baud rate(s) not supported: 250 kbit/s, 500 kbit/s"
    );
    assert_eq!(baud[0].diagnostic.section.as_deref(), Some("DeviceInfo"));
    assert_eq!(
        (baud[0].diagnostic.span.line, baud[0].diagnostic.span.column),
        (3, 1)
    );
    assert!(!baud[0].fixable, "declaring a baud rate would be false");
    assert_eq!(baud[0].diagnostic.severity, canopener_eds::Severity::Error);
    // A rate the project does not require may be missing; `0x1` is read as an EDS number.
    assert!(
        check(&edited(&[
            ("BaudRate_1000=0\n", ""),
            ("BaudRate_125=1", "BaudRate_125=0x1")
        ]))
        .is_empty()
    );
}

#[test]
fn the_required_baud_rates_are_a_parameter() {
    let only_125 = parse_pack(
        &PACK.replace("value = [125, 250, 500]", "value = [125]"),
        "p.toml",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let text = edited(&[("BaudRate_250=1", "BaudRate_250=0")]);
    assert!(of(&check_with(&only_125, &text), "paper/required-baud-rates").is_empty());
    let with_1000 = parse_pack(
        &PACK.replace("value = [125, 250, 500]", "value = [1000]"),
        "p.toml",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let found = check_with(&with_1000, BASE);
    assert_eq!(
        of(&found, "paper/required-baud-rates")[0].diagnostic.message,
        "required baud rate(s) not supported: 1000 kbit/s"
    );
}

#[test]
fn the_sync_cob_id_must_carry_can_id_0x80() {
    let sync = |value: &str| {
        let found = check(&edited(&[(
            "DefaultValue=0x00000080",
            &format!("DefaultValue={value}"),
        )]));
        of(&found, "paper/sync-cob-id")
            .iter()
            .map(|f| f.diagnostic.message.clone())
            .collect::<Vec<_>>()
    };
    assert_eq!(
        sync("0x00000081"),
        ["COB-ID SYNC 0x00000081 has CAN-ID 0x081; the project uses CAN-ID 0x080"]
    );
    assert_eq!(
        sync("0x20000080"),
        ["COB-ID SYNC 0x20000080 has CAN-ID 0x080 in a 29-bit frame; the project uses CAN-ID 0x080"]
    );
    assert_eq!(
        sync("junk"),
        ["COB-ID SYNC junk is not an integer; the project uses CAN-ID 0x080"]
    );
    // `$NODEID` resolves with node 1 in an EDS.
    assert_eq!(sync("$NODEID+0x80").len(), 1);
    // A SYNC producer (bit 30) and the decimal spelling pass.
    assert!(sync("0x40000080").is_empty());
    assert!(sync("128").is_empty());
}

#[test]
fn the_sync_fix_keeps_the_producer_bit() {
    let text = edited(&[("DefaultValue=0x00000080", "DefaultValue=0x40000181")]);
    let planned = fixes(&text, "paper/sync-cob-id");
    assert_eq!(planned.len(), 1);
    assert_eq!(
        planned[0].description,
        "[1005] DefaultValue: 0x40000181 -> 0x40000080"
    );
    assert!(planned[0].changes_meaning);
    let text = edited(&[("DefaultValue=0x00000080", "DefaultValue=0x20000080")]);
    assert_eq!(
        fixes(&text, "paper/sync-cob-id")[0].description,
        "[1005] DefaultValue: 0x20000080 -> 0x00000080"
    );
    assert!(check(&applied(&text, &fixes(&text, "paper/sync-cob-id"))).is_empty());
}

#[test]
fn a_zero_vendor_id_is_found() {
    let found = check(&edited(&[("DefaultValue=0x1234", "DefaultValue=0x00000000")]));
    let vendor = of(&found, "policy/vendor-id-set");
    assert_eq!(vendor.len(), 1);
    assert_eq!(
        vendor[0].diagnostic.message,
        "Vendor-ID 0x00000000 is not a CiA-assigned vendor-ID"
    );
    assert_eq!(vendor[0].diagnostic.section.as_deref(), Some("1018sub1"));
    assert_eq!(vendor[0].diagnostic.key.as_deref(), Some("DefaultValue"));
    assert!(check(&edited(&[("DefaultValue=0x1234", "DefaultValue=1")])).is_empty());
    // No DefaultValue at all is no vendor-ID either.
    let missing = check(&edited(&[("DefaultValue=0x1234\n", "")]));
    assert_eq!(
        of(&missing, "policy/vendor-id-set")[0].diagnostic.message,
        "Vendor-ID (no DefaultValue) is not a CiA-assigned vendor-ID"
    );
}

#[test]
fn a_disabled_heartbeat_is_information_and_fixable() {
    let text = edited(&[("DefaultValue=1000", "DefaultValue=0")]);
    let found = check(&text);
    let heartbeat = of(&found, "policy/heartbeat-enabled");
    assert_eq!(heartbeat.len(), 1);
    assert_eq!(heartbeat[0].diagnostic.severity, canopener_eds::Severity::Info);
    assert_eq!(
        fixes(&text, "policy/heartbeat-enabled")[0].description,
        "[1017] DefaultValue: 0 -> 1000"
    );
    assert!(check(&edited(&[("DefaultValue=1000", "DefaultValue=1")])).is_empty());
    // Without a DefaultValue the fix adds one at the end of the section.
    let text = edited(&[("DefaultValue=1000\n", "")]);
    let planned = fixes(&text, "policy/heartbeat-enabled");
    assert_eq!(planned[0].description, "[1017] add DefaultValue=1000");
    assert_eq!(
        planned[0].edits,
        [Edit::AppendEntry {
            section: 9,
            key: "DefaultValue".to_owned(),
            value: "1000".to_owned()
        }]
    );
    let fixed = applied(&text, &planned);
    assert!(
        fixed.contains("AccessType=rw\nDefaultValue=1000\n[ManufacturerObjects]"),
        "{fixed}"
    );
}

#[test]
fn writable_manufacturer_integers_need_limits() {
    let found = check(&edited(&[("HighLimit=100\n", "")]));
    let limits = of(&found, "policy/writable-limits");
    assert_eq!(limits.len(), 1);
    assert_eq!(
        limits[0].diagnostic.message,
        "writable UNSIGNED16 'Gain' has no HighLimit"
    );
    let found = check(&edited(&[("LowLimit=0\nHighLimit=100\n", "")]));
    assert_eq!(
        of(&found, "policy/writable-limits")[0].diagnostic.message,
        "writable UNSIGNED16 'Gain' has no LowLimit and HighLimit"
    );
    // Keys compare case-insensitively; read-only and non-integer parameters need no limits.
    assert!(check(&edited(&[("HighLimit=100", "highlimit=100")])).is_empty());
    let gain = "DataType=0x0006\nAccessType=rw\nDefaultValue=10\nLowLimit=0\nHighLimit=100\n";
    let read_only = "DataType=0x0006\nAccessType=ro\nDefaultValue=10\n";
    assert!(check(&edited(&[(gain, read_only)])).is_empty());
    let text = "DataType=0x0009\nAccessType=rw\nDefaultValue=x\n";
    assert!(check(&edited(&[(gain, text)])).is_empty());
}

#[test]
fn selection_by_id_slug_and_tag() {
    let text = edited(&[("ParameterName=Gain", "ParameterName=Identity x")]);
    let loaded = canopener_eds::load(text.as_bytes());
    let cx = Context::new(&loaded, None);
    let pack = pack();
    let codes = |selection: Selection| {
        let mut codes: Vec<String> = pack
            .check(&cx, &selection)
            .into_iter()
            .map(|f| f.diagnostic.code)
            .collect();
        codes.dedup();
        codes
    };
    assert_eq!(codes(Selection::default()), ["paper/no-blank-names"]);
    let only_slug = Selection {
        only: vec!["unique-object-names".to_owned()],
        ..Selection::default()
    };
    assert!(codes(only_slug).is_empty(), "'Identity x' is unique");
    let skip = Selection {
        skip: vec!["PAPER/NO-BLANK-NAMES".to_owned()],
        ..Selection::default()
    };
    assert!(codes(skip).is_empty());
    let tag = |t: &str| Selection {
        tags: vec![t.to_owned()],
        ..Selection::default()
    };
    assert_eq!(codes(tag("naming")), ["paper/no-blank-names"]);
    assert_eq!(codes(tag("rules")), ["paper/no-blank-names"]);
    assert!(codes(tag("policy")).is_empty());
}

#[test]
fn descriptions_list_every_rule_with_its_pack() {
    let described = pack().describe();
    assert_eq!(described.len(), 8);
    let blank = &described[0];
    assert_eq!(blank.code, "paper/no-blank-names");
    assert_eq!(blank.slug, "no-blank-names");
    assert_eq!(blank.group, canopener_check::Group::Rules);
    assert_eq!(
        blank.title,
        "ParameterName contains no blanks (project naming policy)"
    );
    assert_eq!(blank.tags, ["naming", "paper", "rules"]);
    assert_eq!(blank.origin, "packs/seed-paper.toml");
    assert!(blank.fixable);
    assert!(blank.explanation.starts_with("Checks that no ParameterName"));
    assert!(!described[3].fixable, "required baud rates have no fix");
    for d in &described {
        // What is checked and why it matters, then why this severity and how to fix it.
        assert!(
            d.explanation.split("\n\n").count() >= 2,
            "{}: {}",
            d.code,
            d.explanation
        );
        assert!(
            !d.explanation.contains("Checks every"),
            "{} has a written explanation",
            d.code
        );
    }
}

// --- Real files -------------------------------------------------------------------------------

fn corpus_findings(name: &str) -> (Vec<Finding>, BTreeMap<String, usize>) {
    let path = corpus::eds(name);
    let bytes = canopener_testkit::fixture::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let loaded = canopener_eds::load(&bytes);
    let cx = Context::new(&loaded, Some(name));
    let found = pack().check(&cx, &Selection::default());
    let mut counts = BTreeMap::new();
    for f in &found {
        *counts.entry(f.diagnostic.code.clone()).or_insert(0) += 1;
    }
    (found, counts)
}

fn message_at<'a>(found: &'a [Finding], code: &str, section: &str) -> Option<&'a str> {
    found
        .iter()
        .find(|f| f.diagnostic.code == code && f.diagnostic.section.as_deref() == Some(section))
        .map(|f| f.diagnostic.message.as_str())
}

#[test]
fn canopennode_demo_device() {
    let (found, counts) = corpus_findings("CANopenNode__CANopenDemo__demo__demoDevice.eds");
    let expected: BTreeMap<String, usize> = [
        ("paper/no-blank-names", 219),
        ("paper/unique-object-names", 16),
        ("paper/unique-sub-names", 112),
        ("policy/heartbeat-enabled", 1),
        ("policy/vendor-id-set", 1),
        ("policy/writable-limits", 51),
    ]
    .into_iter()
    .map(|(c, n)| (c.to_owned(), n))
    .collect();
    assert_eq!(counts, expected);
    assert_eq!(
        message_at(&found, "paper/unique-object-names", "1400"),
        Some("ParameterName 'RPDO communication parameter' is also used by [1401], [1402], [1403]")
    );
    assert_eq!(
        message_at(&found, "paper/unique-sub-names", "1003sub1"),
        Some(
            "ParameterName 'Standard error field' is used by 16 sub-objects of [1003] 'Pre-defined error field'"
        )
    );
    assert_eq!(
        message_at(&found, "policy/vendor-id-set", "1018sub1"),
        Some("Vendor-ID 0x00000000 is not a CiA-assigned vendor-ID")
    );
    assert_eq!(
        message_at(&found, "policy/writable-limits", "2110sub1"),
        Some("writable INTEGER32 'int32' has no LowLimit and HighLimit")
    );
}

#[test]
fn modm_test_device_has_a_zero_sync_cob_id() {
    let (found, counts) = corpus_findings("Javask__modm-canopen__examples__src__simple-linux__test.eds");
    assert_eq!(counts.get("paper/sync-cob-id"), Some(&1));
    assert_eq!(counts.get("paper/no-blank-names"), Some(&147));
    assert_eq!(counts.get("paper/required-baud-rates"), None);
    let sync = found.iter().find(|f| f.diagnostic.code == "paper/sync-cob-id");
    assert_eq!(
        sync.map(|f| (f.diagnostic.span.line, f.diagnostic.span.column)),
        Some((106, 14))
    );
    assert_eq!(
        sync.map(|f| f.diagnostic.message.as_str()),
        Some("COB-ID SYNC 0 has CAN-ID 0x000; the project uses CAN-ID 0x080")
    );
}

#[test]
fn a_file_without_baud_rates_fails_the_baud_rate_rule() {
    let (found, counts) = corpus_findings("Daxbot__node-canopen__test__sample.eds");
    assert_eq!(counts.len(), 1, "{counts:?}");
    assert_eq!(
        message_at(&found, "paper/required-baud-rates", "DeviceInfo"),
        Some("required baud rate(s) not supported: 125 kbit/s, 250 kbit/s, 500 kbit/s")
    );
}

fn corpus_files() -> Vec<(String, Vec<u8>)> {
    corpus::eds_files()
        .into_iter()
        .map(|file| {
            let bytes =
                canopener_testkit::fixture::read(&file.path).unwrap_or_else(|e| panic!("{}: {e}", file.name));
            (file.name, bytes)
        })
        .collect()
}

#[test]
fn every_corpus_file_is_checked_without_evaluation_errors() {
    let files = corpus_files();
    assert_eq!(files.len(), corpus::expected_count(Kind::Eds));
    let vendored: BTreeSet<String> = corpus::vendored_files(Kind::Eds)
        .into_iter()
        .map(|file| file.name)
        .collect();
    let pack = pack();
    let (mut total, mut vendored_total) = (BTreeMap::new(), BTreeMap::new());
    for (name, bytes) in &files {
        let loaded = canopener_eds::load(bytes);
        let findings = pack.check(&Context::new(&loaded, Some(name)), &Selection::default());
        assert!(
            findings.iter().all(|f| f.diagnostic.code != "R000"),
            "{name}: {findings:#?}"
        );
        for f in findings {
            if vendored.contains(name) {
                *vendored_total.entry(f.diagnostic.code.clone()).or_insert(0) += 1;
            }
            *total.entry(f.diagnostic.code).or_insert(0) += 1;
        }
    }
    // The vendored files alone, which every checkout has.
    let vendored_expected: BTreeMap<String, usize> = [
        ("paper/no-blank-names", 22581),
        ("paper/required-baud-rates", 15),
        ("paper/sync-cob-id", 2),
        ("paper/unique-object-names", 1346),
        ("paper/unique-sub-names", 1285),
        ("policy/heartbeat-enabled", 58),
        ("policy/vendor-id-set", 54),
        ("policy/writable-limits", 3725),
    ]
    .into_iter()
    .map(|(c, n)| (c.to_owned(), n))
    .collect();
    assert_eq!(vendored_total, vendored_expected, "the vendored files");
    if corpus::extended_root().is_none() {
        return;
    }
    // The numbers the crate README gives for the whole corpus.
    let expected: BTreeMap<String, usize> = [
        ("paper/no-blank-names", 30693),
        ("paper/required-baud-rates", 24),
        ("paper/sync-cob-id", 4),
        ("paper/unique-object-names", 1565),
        ("paper/unique-sub-names", 1456),
        ("policy/heartbeat-enabled", 79),
        ("policy/vendor-id-set", 70),
        ("policy/writable-limits", 7271),
    ]
    .into_iter()
    .map(|(c, n)| (c.to_owned(), n))
    .collect();
    assert_eq!(total, expected);
}

#[test]
fn fixing_real_files_converges_and_is_idempotent() {
    let pack = pack();
    let selection = Selection::default();
    let names = [
        "CANopenNode__CANopenDemo__demo__demoDevice.eds",
        "Javask__modm-canopen__examples__src__simple-linux__test.eds",
        "Daxbot__node-canopen__test__common__test.eds",
    ];
    for name in names {
        let bytes =
            canopener_testkit::fixture::read(corpus::eds(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        let outcome = fix::fix_file(&bytes, Some(name), &selection, &|cx| pack.fixes(cx, &selection));
        assert!(outcome.changed, "{name}");
        assert!(outcome.errors_after <= outcome.errors_before, "{name}");
        // Blanks and uniqueness fix the same ParameterName lines: a round each, then nothing is left.
        let refixed = canopener_eds::load(&outcome.bytes);
        let left = pack.check(&Context::new(&refixed, Some(name)), &selection);
        let fixable_left: Vec<_> = left.iter().filter(|f| f.fixable).collect();
        assert!(fixable_left.is_empty(), "{name}: {fixable_left:#?}");
        assert!(
            left.iter().all(|f| f.diagnostic.code != "paper/no-blank-names"
                && !f.diagnostic.code.starts_with("paper/unique"))
        );
        let again = fix::fix_file(&outcome.bytes, Some(name), &selection, &|cx| {
            pack.fixes(cx, &selection)
        });
        assert!(
            !again.changed,
            "{name}: fixing twice changed the file: {:?}",
            again.fixes
        );
    }
}

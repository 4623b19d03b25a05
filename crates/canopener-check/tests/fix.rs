//! The fix engine on small files: each built-in fix with exact bytes before and after, conflicts
//! between fixes, selection, line endings and encodings kept, and the `--dry-run` diff.

use canopener_check::fix::{self, Edit, Fix, FixOutcome};
use canopener_check::{Context, Selection};

/// A small EDS the loader reads without a complaint about lists, sub-numbers or names.
const BASE: &str = "\
[FileInfo]
FileName=t.eds
EDSVersion=4.0

[DeviceInfo]
VendorNumber=0x1

[MandatoryObjects]
SupportedObjects=2
1=0x1000
2=0x1018

[1000]
ParameterName=Device type
DataType=0x0007
AccessType=ro
DefaultValue=0

[1018]
ParameterName=Identity
ObjectType=0x9
SubNumber=2

[1018sub0]
ParameterName=Highest sub-index
DataType=0x0005
AccessType=ro
DefaultValue=1

[1018sub1]
ParameterName=Vendor-ID
DataType=0x0007
AccessType=ro
DefaultValue=0x1
";

/// Objects 1005h and 1017h, for the optional list.
const OPTIONAL_OBJECTS: &str = "
[1005]
ParameterName=COB-ID SYNC
DataType=0x0007
AccessType=rw
DefaultValue=0x80

[1017]
ParameterName=Producer heartbeat time
DataType=0x0006
AccessType=rw
DefaultValue=0
";

fn no_extra(_: &Context<'_>) -> Vec<Fix> {
    Vec::new()
}

fn only(codes: &[&str]) -> Selection {
    Selection {
        only: codes.iter().map(|c| (*c).to_owned()).collect(),
        ..Selection::default()
    }
}

/// The built-in fixes of one code planned on `text`, applied in one round.
fn plan_and_apply(text: &str, code: &str) -> (String, Vec<Fix>) {
    let loaded = canopener_eds::load(text.as_bytes());
    let cx = Context::new(&loaded, Some("t.eds"));
    let fixes = fix::plan(&cx, &only(&[code]));
    assert!(fixes.iter().all(|f| f.code == code), "{fixes:?}");
    let applied = fix::apply(&loaded.document, &fixes);
    assert!(applied.skipped.is_empty(), "{:?}", applied.skipped);
    let bytes = applied.document.to_bytes().expect("encodable");
    (String::from_utf8(bytes).expect("utf-8"), fixes)
}

fn codes(text: &str) -> Vec<&'static str> {
    canopener_eds::load(text.as_bytes())
        .diagnostics
        .iter()
        .map(|d| d.code.as_str())
        .collect()
}

fn fix_text(text: &str, selection: &Selection) -> (String, FixOutcome) {
    let outcome = fix::fix_file(text.as_bytes(), Some("t.eds"), selection, &no_extra);
    (String::from_utf8(outcome.bytes.clone()).expect("utf-8"), outcome)
}

#[test]
fn the_base_file_needs_no_fix() {
    let (after, outcome) = fix_text(&format!("{BASE}{OPTIONAL_OBJECTS}"), &only(&["P045"]));
    assert!(!outcome.changed && outcome.fixes.is_empty() && outcome.skipped.is_empty());
    assert_eq!(after, format!("{BASE}{OPTIONAL_OBJECTS}"));
    let (_, all) = fix_text(BASE, &Selection::default());
    assert!(!all.changed, "{:?}", all.fixes);
}

#[test]
fn p045_sets_sub_number_to_the_sub_sections_present() {
    let before = BASE.replace("SubNumber=2", "SubNumber=5");
    assert!(codes(&before).contains(&"P045"));
    let (after, fixes) = plan_and_apply(&before, "P045");
    assert_eq!(after, BASE);
    assert_eq!(fixes.len(), 1);
    assert_eq!(
        fixes[0].description,
        "[1018] SubNumber: 5 -> 2 (the number of sub-object sections present)"
    );
    assert!(!fixes[0].changes_meaning);
    // Hex notation, its width and an inline comment are kept.
    let before = BASE.replace("SubNumber=2", "SubNumber = 0x05 ; five");
    let (after, _) = plan_and_apply(&before, "P045");
    assert_eq!(after, BASE.replace("SubNumber=2", "SubNumber = 0x02 ; five"));
}

#[test]
fn p045_counts_sub0_and_not_ffh() {
    let with_ff = BASE.replace(
        "[1018sub1]",
        "[1018subFF]\nParameterName=Structure\nDataType=0x0007\nAccessType=ro\nDefaultValue=0x0923\n\n[1018sub1]",
    );
    assert!(
        !codes(&with_ff).contains(&"P045"),
        "FFh is not counted by SubNumber"
    );
    let (after, fixes) = plan_and_apply(&with_ff.replace("SubNumber=2", "SubNumber=3"), "P045");
    assert_eq!(after, with_ff);
    assert_eq!(fixes.len(), 1);
}

#[test]
fn p044_recounts_a_list() {
    let before = format!(
        "{}{OPTIONAL_OBJECTS}",
        BASE.replace("SupportedObjects=2", "SupportedObjects=0x7")
    );
    assert!(codes(&before).contains(&"P044"));
    let (after, fixes) = plan_and_apply(&before, "P044");
    assert_eq!(
        after,
        format!("{BASE}{OPTIONAL_OBJECTS}").replace("SupportedObjects=2", "SupportedObjects=0x2")
    );
    assert_eq!(
        fixes[0].description,
        "[MandatoryObjects] SupportedObjects: 0x7 -> 0x2"
    );
}

#[test]
fn p044_renumbers_and_removes_repeated_entries() {
    let list = "\n[OptionalObjects]\nSupportedObjects=3\n1=0x1005\n3=0x1017\n4=0x1005\n";
    let before = format!("{BASE}{list}{OPTIONAL_OBJECTS}");
    assert!(codes(&before).contains(&"P044"));
    let (after, fixes) = plan_and_apply(&before, "P044");
    let fixed = "\n[OptionalObjects]\nSupportedObjects=2\n1=0x1005\n2=0x1017\n";
    assert_eq!(after, format!("{BASE}{fixed}{OPTIONAL_OBJECTS}"));
    assert_eq!(
        fixes[0].description,
        "[OptionalObjects] remove 4=0x1005 (repeats 1005h); renumber entries 3 -> 2; SupportedObjects: 3 -> 2"
    );
    assert!(!codes(&after).contains(&"P044"));
}

#[test]
fn p044_keeps_an_index_listed_twice_in_the_list_cia306_assigns_it() {
    // 1018h belongs in [MandatoryObjects]; the copy in [OptionalObjects] goes.
    let list = "\n[OptionalObjects]\nSupportedObjects=3\n1=0x1018\n2=0x1005\n3=0x1017\n";
    let before = format!("{BASE}{list}{OPTIONAL_OBJECTS}");
    assert!(codes(&before).contains(&"P044"));
    let (after, fixes) = plan_and_apply(&before, "P044");
    let fixed = "\n[OptionalObjects]\nSupportedObjects=2\n1=0x1005\n2=0x1017\n";
    assert_eq!(after, format!("{BASE}{fixed}{OPTIONAL_OBJECTS}"));
    assert_eq!(fixes.len(), 1);
    assert!(
        fixes[0]
            .description
            .starts_with("[OptionalObjects] remove 1=0x1018 (also in [MandatoryObjects])")
    );
}

#[test]
fn p044_renumbers_keys_with_leading_zeros_and_keeps_what_is_not_an_index() {
    let list = "\n[OptionalObjects]\nSupportedObjects=3\n01=0x1005\n02=junk\n03=0x1017\n";
    let before = format!("{BASE}{list}{OPTIONAL_OBJECTS}");
    let (after, _) = plan_and_apply(&before, "P044");
    let fixed = "\n[OptionalObjects]\nSupportedObjects=3\n1=0x1005\n2=junk\n3=0x1017\n";
    assert_eq!(after, format!("{BASE}{fixed}{OPTIONAL_OBJECTS}"));
    // The entry that names no index is still reported; fixing again changes nothing.
    assert!(codes(&after).contains(&"P044"));
    let loaded = canopener_eds::load(after.as_bytes());
    assert!(fix::plan(&Context::new(&loaded, None), &only(&["P044"])).is_empty());
}

#[test]
fn p042_removes_entries_without_an_object_and_renumbers() {
    let list = "\n[OptionalObjects]\nSupportedObjects=3\n1=0x1005\n2=0x6505\n3=0x1017\n";
    let before = format!("{BASE}{list}{OPTIONAL_OBJECTS}");
    assert!(codes(&before).contains(&"P042"));
    let (after, fixes) = plan_and_apply(&before, "P042");
    let fixed = "\n[OptionalObjects]\nSupportedObjects=2\n1=0x1005\n2=0x1017\n";
    assert_eq!(after, format!("{BASE}{fixed}{OPTIONAL_OBJECTS}"));
    assert_eq!(
        fixes[0].description,
        "[OptionalObjects] remove 2=0x6505 (no such object section); renumber entries 3 -> 2; SupportedObjects: 3 -> 2"
    );
    assert!(!codes(&after).contains(&"P042"));
}

#[test]
fn p043_appends_to_the_list_cia306_assigns() {
    // The new entry goes after the last entry, not after the comment that introduces [1005].
    let list = "\n[OptionalObjects]\nSupportedObjects=1\n1=0x1005\n\n; communication objects\n";
    let before = format!("{BASE}{list}{OPTIONAL_OBJECTS}");
    assert!(codes(&before).contains(&"P043"));
    let (after, fixes) = plan_and_apply(&before, "P043");
    let fixed = "\n[OptionalObjects]\nSupportedObjects=2\n1=0x1005\n2=0x1017\n\n; communication objects\n";
    assert_eq!(after, format!("{BASE}{fixed}{OPTIONAL_OBJECTS}"));
    assert_eq!(
        fixes[0].description,
        "[OptionalObjects] add 2=0x1017; SupportedObjects: 1 -> 2"
    );
    assert!(!codes(&after).contains(&"P043"));
}

#[test]
fn p043_creates_a_missing_list_at_the_end_of_the_file() {
    let manufacturer = "\n[2000]\nParameterName=Speed\nDataType=0x0006\nAccessType=rw\nDefaultValue=0\n";
    let before = format!("{BASE}{OPTIONAL_OBJECTS}{manufacturer}");
    let (after, fixes) = plan_and_apply(&before, "P043");
    assert_eq!(
        after,
        format!(
            "{before}\n[OptionalObjects]\nSupportedObjects=2\n1=0x1005\n2=0x1017\n\n\
             [ManufacturerObjects]\nSupportedObjects=1\n1=0x2000\n"
        )
    );
    let descriptions: Vec<&str> = fixes.iter().map(|f| f.description.as_str()).collect();
    assert_eq!(
        descriptions,
        [
            "create [OptionalObjects] listing 1005h, 1017h",
            "create [ManufacturerObjects] listing 2000h"
        ]
    );
    assert!(!codes(&after).contains(&"P043"));
}

#[test]
fn p043_waits_for_a_malformed_list() {
    let list = "\n[OptionalObjects]\nSupportedObjects=1\n1=0x1005\n3=0x1005\n";
    let before = format!("{BASE}{list}{OPTIONAL_OBJECTS}");
    // Alone, P043 refuses: a new entry number could collide.
    let (after, outcome) = fix_text(&before, &only(&["P043"]));
    assert_eq!(after, before);
    assert!(!outcome.changed);
    assert_eq!(outcome.skipped.len(), 1);
    assert_eq!(outcome.skipped[0].0.code, "P043");
    assert!(
        outcome.skipped[0].1.contains("fix that first (P044)"),
        "{}",
        outcome.skipped[0].1
    );
    // With P044 the list is repaired first, then the object added in the next round.
    let (after, outcome) = fix_text(&before, &only(&["P043", "P044"]));
    let fixed = "\n[OptionalObjects]\nSupportedObjects=2\n1=0x1005\n2=0x1017\n";
    assert_eq!(after, format!("{BASE}{fixed}{OPTIONAL_OBJECTS}"));
    let order: Vec<&str> = outcome.fixes.iter().map(|f| f.code.as_str()).collect();
    assert_eq!(order, ["P044", "P043"]);
    assert!(outcome.skipped.is_empty(), "{:?}", outcome.skipped);
}

#[test]
fn p031_rewrites_headers_to_the_canonical_name() {
    let before = BASE
        .replace("[1018sub1]", "[1018sub01]")
        .replace("[1018sub0]", "[1018Sub0]")
        .replace("[1000]", "[01000]");
    assert_eq!(codes(&before).iter().filter(|c| **c == "P031").count(), 3);
    let (after, fixes) = plan_and_apply(&before, "P031");
    assert_eq!(after, BASE);
    let descriptions: Vec<&str> = fixes.iter().map(|f| f.description.as_str()).collect();
    assert_eq!(
        descriptions,
        [
            "[01000] -> [1000]",
            "[1018Sub0] -> [1018sub0]",
            "[1018sub01] -> [1018sub1]"
        ]
    );
}

#[test]
fn p031_spells_the_commissioning_section_as_cia306_does() {
    let before = format!("{BASE}\n[DeviceCommissioning]\nNodeID=5\n");
    let (after, _) = plan_and_apply(&before, "P031");
    assert_eq!(after, format!("{BASE}\n[DeviceComissioning]\nNodeID=5\n"));
}

#[test]
fn p031_refuses_a_rename_onto_an_existing_section() {
    // The first of the two is the one the loader reads (and reports as P031); the second repeats it.
    let before = format!(
        "{}\n[1018sub1]\nParameterName=Again\n",
        BASE.replace("[1018sub1]", "[1018sub01]")
    );
    let (after, outcome) = fix_text(&before, &only(&["P031"]));
    assert_eq!(after, before);
    assert_eq!(outcome.skipped.len(), 1);
    assert_eq!(outcome.skipped[0].0.description, "[1018sub01] -> [1018sub1]");
    assert!(
        outcome.skipped[0].1.contains("[1018sub1] on line 36"),
        "{}",
        outcome.skipped[0].1
    );
}

#[test]
fn p032_rewrites_every_key_of_one_spelling_and_keeps_values() {
    let before = BASE
        .replace("ParameterName=Device type", "Parametername = Device type ")
        .replace("ParameterName=Vendor-ID", "Parametername=Vendor-ID")
        .replace("DataType=0x0005", "DATATYPE=0x0005");
    let (after, fixes) = plan_and_apply(&before, "P032");
    let expected = BASE.replace("ParameterName=Device type", "ParameterName = Device type ");
    assert_eq!(after, expected);
    let descriptions: Vec<&str> = fixes.iter().map(|f| f.description.as_str()).collect();
    assert_eq!(
        descriptions,
        [
            "[1000] key Parametername -> ParameterName (and 1 more line(s))",
            "[1018sub0] key DATATYPE -> DataType"
        ]
    );
}

#[test]
fn c537_sets_sub0_to_the_highest_sub_index_and_says_it_changes_meaning() {
    let before = BASE.replace("SubNumber=2", "SubNumber=3").replace(
        "DefaultValue=0x1\n",
        "DefaultValue=0x1\n\n[1018sub4]\nParameterName=Serial number\nDataType=0x0007\nAccessType=ro\nDefaultValue=0\n",
    );
    let loaded = canopener_eds::load(before.as_bytes());
    let found = canopener_check::check(&loaded, Some("t.eds"), &only(&["C537"])).findings;
    assert_eq!(found.len(), 1, "{found:?}");
    let (after, fixes) = plan_and_apply(&before, "C537");
    assert_eq!(
        after,
        before.replace(
            "Highest sub-index\nDataType=0x0005\nAccessType=ro\nDefaultValue=1",
            "Highest sub-index\nDataType=0x0005\nAccessType=ro\nDefaultValue=4"
        )
    );
    assert!(fixes[0].changes_meaning);
    assert!(
        fixes[0]
            .description
            .starts_with("[1018sub0] DefaultValue: 1 -> 4")
    );
    assert!(
        fixes[0]
            .description
            .contains("changes the value the device reports")
    );
}

#[test]
fn c537_does_not_lower_sub0_below_what_the_device_may_have() {
    // Sub 0 says 4 but only sub 1 is described: the file leaves entries out, the fix refuses.
    let before = BASE.replace(
        "Highest sub-index\nDataType=0x0005\nAccessType=ro\nDefaultValue=1",
        "Highest sub-index\nDataType=0x0005\nAccessType=ro\nDefaultValue=4",
    );
    let (after, outcome) = fix_text(&before, &only(&["C537"]));
    assert_eq!(after, before);
    assert!(outcome.fixes.is_empty());
    // The check marks this finding as not fixable, so the engine plans nothing for it.
    let loaded = canopener_eds::load(before.as_bytes());
    let finding = canopener_check::check(&loaded, None, &only(&["C537"]))
        .findings
        .into_iter()
        .find(|f| f.diagnostic.code == "C537")
        .expect("C537 is reported");
    assert!(!finding.fixable, "{finding:?}");
}

#[test]
fn selection_by_only_skip_and_slug() {
    let before = BASE
        .replace("SubNumber=2", "SubNumber=5")
        .replace("[1018sub1]", "[1018sub01]");
    let planned = |selection: Selection| -> Vec<String> {
        let loaded = canopener_eds::load(before.as_bytes());
        fix::plan(&Context::new(&loaded, None), &selection)
            .into_iter()
            .map(|f| f.code)
            .collect()
    };
    assert_eq!(planned(Selection::default()), ["P031", "P045"]);
    assert_eq!(planned(only(&["P045"])), ["P045"]);
    assert_eq!(planned(only(&["sub-number-mismatch"])), ["P045"]);
    assert_eq!(planned(only(&["p031"])), ["P031"]);
    let skip = Selection {
        skip: vec!["P045".to_owned()],
        ..Selection::default()
    };
    assert_eq!(planned(skip), ["P031"]);
    assert!(planned(only(&["C301"])).is_empty());
}

#[test]
fn conflicting_fixes_apply_first_come_first_served() {
    let (document, _) = canopener_eds::Document::parse(BASE.as_bytes());
    let line = 8; // SupportedObjects=2
    assert_eq!(document.line_text(line), "SupportedObjects=2");
    let set = |value: &str| Fix {
        code: "X1".to_owned(),
        description: format!("SupportedObjects -> {value}"),
        changes_meaning: false,
        edits: vec![Edit::SetValue {
            line,
            value: value.to_owned(),
        }],
    };
    let delete_both = Fix {
        code: "X2".to_owned(),
        description: "delete two lines".to_owned(),
        changes_meaning: false,
        edits: vec![Edit::DeleteLine { line: 9 }, Edit::DeleteLine { line }],
    };
    let fixes = [set("3"), delete_both, set("4")];
    let applied = fix::apply(&document, &fixes);
    assert_eq!(applied.applied, [0]);
    assert_eq!(applied.skipped.len(), 2);
    assert_eq!(applied.skipped[0].0, 1);
    assert_eq!(
        applied.skipped[0].1,
        "line 9 is already changed by X1 fix `SupportedObjects -> 3`"
    );
    assert_eq!(applied.skipped[1].0, 2);
    let text = String::from_utf8(applied.document.to_bytes().expect("utf-8")).expect("utf-8");
    assert_eq!(text, BASE.replace("SupportedObjects=2", "SupportedObjects=3"));
}

#[test]
fn invalid_edits_are_skipped_with_a_reason_not_a_panic() {
    let (document, _) = canopener_eds::Document::parse(BASE.as_bytes());
    let fix = |edits: Vec<Edit>| Fix {
        code: "X".to_owned(),
        description: "x".to_owned(),
        changes_meaning: false,
        edits,
    };
    let fixes = [
        fix(vec![Edit::DeleteLine { line: 10_000 }]),
        fix(vec![Edit::SetValue {
            line: 0,
            value: "1".to_owned(),
        }]),
        fix(vec![Edit::ReplaceLine {
            line: 1,
            content: "A=1\nB=2".to_owned(),
        }]),
        fix(vec![Edit::AppendEntry {
            section: 99,
            key: "K".to_owned(),
            value: "V".to_owned(),
        }]),
        fix(vec![Edit::AppendEntry {
            section: 0,
            key: "K=1".to_owned(),
            value: "V".to_owned(),
        }]),
        fix(vec![Edit::SetValue {
            line: 1,
            value: "t.eds".to_owned(),
        }]),
        fix(Vec::new()),
        fix(vec![
            Edit::SetValue {
                line: 1,
                value: "a.eds".to_owned(),
            },
            Edit::DeleteLine { line: 1 },
        ]),
    ];
    let applied = fix::apply(&document, &fixes);
    assert!(applied.applied.is_empty());
    let reasons: Vec<&str> = applied.skipped.iter().map(|(_, r)| r.as_str()).collect();
    assert_eq!(
        reasons,
        [
            "line 10001 does not exist",
            "line 1 is not a `key=value` entry",
            "the new text \"A=1\\nB=2\" contains a line break",
            "the document has no section number 99",
            "`K=1` cannot be written as a key",
            "the fix changes nothing",
            "the fix has no edits",
            "two edits of the fix change line 2",
        ]
    );
    assert_eq!(applied.document, document);
}

#[test]
fn crlf_endings_and_a_missing_final_newline_are_kept() {
    let before = format!(
        "{}{}",
        BASE.replace("SubNumber=2", "SubNumber=5"),
        OPTIONAL_OBJECTS
    )
    .trim_end()
    .replace('\n', "\r\n");
    let (after, outcome) = fix_text(&before, &only(&["P045", "P043"]));
    assert_eq!(outcome.fixes.len(), 2);
    let expected = format!(
        "{}\r\n\r\n[OptionalObjects]\r\nSupportedObjects=2\r\n1=0x1005\r\n2=0x1017",
        before.replace("SubNumber=5", "SubNumber=2")
    );
    assert_eq!(after, expected);
}

#[test]
fn windows_1252_is_kept_and_unencodable_text_is_refused() {
    let mut before = BASE
        .replace("SubNumber=2", "SubNumber=5")
        .replace("ParameterName=Device type", "ParameterName=Device type X")
        .into_bytes();
    // `°` as the single Windows-1252 byte B0, which makes the file invalid UTF-8.
    let at = before.iter().position(|&b| b == b'X').expect("marker");
    before[at] = 0xB0;
    let rename = |cx: &Context<'_>| -> Vec<Fix> {
        let section = cx.document.section("1000").expect("[1000]");
        let line = cx.document.find_entry(section, "ParameterName").expect("name");
        vec![Fix {
            code: "R1".to_owned(),
            description: "rename".to_owned(),
            changes_meaning: true,
            edits: vec![Edit::SetValue {
                line,
                value: "Device type Ω".to_owned(),
            }],
        }]
    };
    let outcome = fix::fix_file(&before, Some("t.eds"), &Selection::default(), &rename);
    let codes: Vec<&str> = outcome.fixes.iter().map(|f| f.code.as_str()).collect();
    assert_eq!(codes, ["P045"]);
    let mut expected = before.clone();
    let at = expected
        .windows(11)
        .position(|w| w == b"SubNumber=5")
        .expect("SubNumber");
    expected[at + 10] = b'2';
    assert_eq!(outcome.bytes, expected);
    assert_eq!(outcome.skipped.len(), 1);
    assert_eq!(outcome.skipped[0].0.code, "R1");
    assert!(
        outcome.skipped[0].1.contains("Windows-1252"),
        "{}",
        outcome.skipped[0].1
    );
}

#[test]
fn a_fix_that_raises_the_error_count_is_not_kept() {
    let before = BASE.replace("SubNumber=2", "SubNumber=5");
    // A rule-pack fix that deletes the `[1018sub1]` header: its keys then repeat those of sub 0.
    let harmful = |cx: &Context<'_>| -> Vec<Fix> {
        let Some(section) = cx.document.section("1018sub1") else {
            return Vec::new();
        };
        vec![Fix {
            code: "R2".to_owned(),
            description: "delete [1018sub1] header".to_owned(),
            changes_meaning: true,
            edits: vec![Edit::DeleteLine {
                line: section.header_line,
            }],
        }]
    };
    let outcome = fix::fix_file(before.as_bytes(), Some("t.eds"), &Selection::default(), &harmful);
    assert_eq!(String::from_utf8(outcome.bytes.clone()).expect("utf-8"), BASE);
    assert_eq!(outcome.fixes.len(), 1);
    assert_eq!(outcome.fixes[0].code, "P045");
    assert_eq!(outcome.skipped.len(), 1);
    assert_eq!(outcome.skipped[0].0.code, "R2");
    assert!(
        outcome.skipped[0]
            .1
            .starts_with("would raise the number of errors from"),
        "{}",
        outcome.skipped[0].1
    );
    assert!(outcome.errors_after <= outcome.errors_before);
}

#[test]
fn fixes_that_undo_each_other_stop_after_a_bounded_number_of_rounds() {
    let flip = |cx: &Context<'_>| -> Vec<Fix> {
        let Some(section) = cx.document.section("1000") else {
            return Vec::new();
        };
        let Some(line) = cx.document.find_entry(section, "ParameterName") else {
            return Vec::new();
        };
        let lower = cx.document.entry(line).is_some_and(|(_, v)| v == "Device type");
        let next = if lower { "Device Type" } else { "Device type" };
        vec![Fix {
            code: "R3".to_owned(),
            description: format!("[1000] ParameterName -> {next}"),
            changes_meaning: true,
            edits: vec![Edit::SetValue {
                line,
                value: next.to_owned(),
            }],
        }]
    };
    let outcome = fix::fix_file(BASE.as_bytes(), Some("t.eds"), &Selection::default(), &flip);
    assert_eq!(outcome.fixes.len(), 8);
    assert_eq!(outcome.skipped.len(), 1);
    assert_eq!(
        outcome.skipped[0].0.description,
        "[1000] ParameterName -> Device Type"
    );
    assert!(
        outcome.skipped[0].1.starts_with("still pending after 8 rounds"),
        "{}",
        outcome.skipped[0].1
    );
    // Eight flips bring the name back.
    assert_eq!(outcome.bytes, BASE.as_bytes());
    assert!(!outcome.changed);
}

#[test]
fn fixing_is_idempotent_and_counts_errors() {
    let list = "\n[OptionalObjects]\nSupportedObjects=5\n1=0x1005\n2=0x6505\n";
    let before = format!(
        "{}{list}{OPTIONAL_OBJECTS}",
        BASE.replace("SubNumber=2", "SubNumber=5")
            .replace("[1018sub1]", "[1018sub01]")
    );
    let (after, outcome) = fix_text(&before, &Selection::default());
    assert!(outcome.changed);
    assert!(
        outcome.errors_before >= 2,
        "P042 and P044 are errors: {outcome:#?}"
    );
    assert!(outcome.errors_after < outcome.errors_before);
    let fixed = "\n[OptionalObjects]\nSupportedObjects=2\n1=0x1005\n2=0x1017\n";
    assert_eq!(after, format!("{BASE}{fixed}{OPTIONAL_OBJECTS}"));
    let (again, second) = fix_text(&after, &Selection::default());
    assert_eq!(again, after);
    assert!(!second.changed && second.fixes.is_empty());
    assert_eq!(second.errors_before, outcome.errors_after);
}

#[test]
fn unified_diff_shows_the_changed_lines_with_context() {
    let old = "a\nb\nc\nd\ne\nf\ng\nh\n";
    let new = "a\nb\nc\nd\nE\nf\ng\nh\n";
    assert_eq!(
        fix::unified_diff(old.as_bytes(), new.as_bytes(), "t.eds", "t.eds (fixed)"),
        "--- t.eds\n+++ t.eds (fixed)\n@@ -2,7 +2,7 @@\n b\n c\n d\n-e\n+E\n f\n g\n h\n"
    );
    assert_eq!(fix::unified_diff(old.as_bytes(), old.as_bytes(), "a", "b"), "");
    let no_newline = fix::unified_diff(b"k=1", b"k=2", "a", "b");
    assert_eq!(
        no_newline,
        "--- a\n+++ b\n@@ -1 +1 @@\n-k=1\n\\ No newline at end of file\n+k=2\n\\ No newline at end of file\n"
    );
    // Windows-1252 bytes are shown as the characters they stand for.
    let latin = fix::unified_diff(b"Unit=\xB0C\nk=1\n", b"Unit=\xB0C\nk=2\n", "a", "b");
    assert!(latin.contains(" Unit=°C\n"), "{latin}");
}

//! SARIF reports validated against the OASIS SARIF 2.1.0 schema, and what code scanning relies on.

use canopener_eds::Severity;
use canopener_report::{FileReport, Report, sarif};
use serde_json::Value;

use crate::fixture::{checks, finding, report};

/// The stray `]` of the official schema's `language` patterns (on `run` and `toolComponent`).
const BROKEN_PATTERN: &str = "^[a-zA-Z]{2}|^[a-zA-Z]{2}-[a-zA-Z]{2}]?$";

/// The official schema, with one repair: its two `language` patterns
/// `^[a-zA-Z]{2}|^[a-zA-Z]{2}-[a-zA-Z]{2}]?$` have a stray `]`, which ECMA-262 reads as a literal
/// only outside unicode mode, so the draft-07 meta-schema's `regex` format check rejects the schema.
/// We escape that `]` (the meaning of the lenient reading); our reports never set `language`.
fn schema() -> Value {
    let text = include_str!("../../test_data/sarif-schema-2.1.0.json");
    let mut schema: Value = serde_json::from_str(text).expect("the schema parses");
    for owner in ["run", "toolComponent"] {
        let pointer = format!("/definitions/{owner}/properties/language/pattern");
        let pattern = schema.pointer_mut(&pointer).expect("language has a pattern");
        assert_eq!(pattern, BROKEN_PATTERN, "the schema file changed at {pointer}");
        *pattern = Value::from(BROKEN_PATTERN.replace("]?$", "\\]?$"));
    }
    assert!(
        !schema.to_string().contains(BROKEN_PATTERN),
        "the schema has other broken patterns"
    );
    schema
}

fn validate(report: &Report) -> Value {
    // Draft 7 asserts formats (`uri`, `uri-reference`, `date-time`); say so explicitly anyway.
    let validator = jsonschema::options()
        .should_validate_formats(true)
        .build(&schema())
        .expect("the schema compiles");
    let text = sarif(report);
    let log: Value = serde_json::from_str(&text).expect("the SARIF report parses");
    let errors: Vec<String> = validator
        .iter_errors(&log)
        .map(|e| format!("{} at {}", e, e.instance_path()))
        .collect();
    assert!(
        errors.is_empty(),
        "SARIF schema violations:\n{}\n{text}",
        errors.join("\n")
    );
    log
}

#[test]
fn empty_report_is_valid() {
    let log = validate(&Report::default());
    assert_eq!(log["version"], "2.1.0");
    assert_eq!(log["runs"].as_array().map(Vec::len), Some(1));
    assert_eq!(log["runs"][0]["results"], Value::Array(Vec::new()));
}

#[test]
fn report_with_findings_problems_and_unicode_is_valid() {
    let report = report();
    let log = validate(&report);
    assert!(
        log["$schema"]
            .as_str()
            .is_some_and(|s| s.ends_with("sarif-schema-2.1.0.json"))
    );
    let run = &log["runs"][0];
    assert_eq!(run["columnKind"], "unicodeCodePoints");
    let driver = &run["tool"]["driver"];
    assert_eq!(driver["name"], "canopener");
    assert_eq!(driver["version"], "0.1.0");
    assert!(
        driver["informationUri"]
            .as_str()
            .is_some_and(|u| u.starts_with("https://"))
    );

    let rules = driver["rules"].as_array().expect("rules");
    // The 7 described checks, then P020 which has findings but no description.
    assert_eq!(rules.len(), 8);
    assert_eq!(rules[0]["id"], "C301");
    assert_eq!(rules[0]["name"], "vendor-number-mismatch");
    assert_eq!(
        rules[0]["shortDescription"]["text"],
        "VendorNumber agrees with 1018sub1"
    );
    assert!(
        rules[0]["fullDescription"]["text"]
            .as_str()
            .is_some_and(|t| t.contains("1018h rejects"))
    );
    assert_eq!(
        rules[0]["helpUri"],
        "https://github.com/canopener/canopener/blob/main/docs/checks.md#c301"
    );
    assert_eq!(rules[0]["defaultConfiguration"]["level"], "error");
    let t004 = rules.iter().find(|r| r["id"] == "T004").expect("T004 rule");
    assert_eq!(t004["defaultConfiguration"]["level"], "note");
    let pack = rules
        .iter()
        .find(|r| r["id"] == "naming.no-blanks")
        .expect("rule-pack rule");
    assert!(
        pack.get("helpUri").is_none(),
        "rule-pack checks have no page in docs/checks.md"
    );
    assert_eq!(rules[7]["id"], "P020");

    let artifacts = run["artifacts"].as_array().expect("artifacts");
    let uris: Vec<&str> = artifacts
        .iter()
        .filter_map(|a| a["location"]["uri"].as_str())
        .collect();
    assert_eq!(
        uris,
        [
            "eds/motor%20drive.eds",
            "eds/clean.eds",
            "dcf/node5.dcf",
            "eds/missing.eds"
        ]
    );

    let results = run["results"].as_array().expect("results");
    assert_eq!(results.len(), report.findings_total());
    for result in results {
        let index = result["ruleIndex"]
            .as_u64()
            .and_then(|i| usize::try_from(i).ok())
            .expect("ruleIndex");
        assert_eq!(
            rules[index]["id"], result["ruleId"],
            "ruleIndex points at the rule"
        );
        let location = &result["locations"][0]["physicalLocation"];
        let artifact = location["artifactLocation"]["index"]
            .as_u64()
            .and_then(|i| usize::try_from(i).ok());
        let artifact = artifact.expect("artifact index");
        assert_eq!(
            artifacts[artifact]["location"]["uri"],
            location["artifactLocation"]["uri"]
        );
        assert!(location["region"]["startLine"].as_u64().is_some_and(|l| l >= 1));
    }
    let first = &results[0];
    assert_eq!(first["level"], "error");
    assert_eq!(
        first["message"]["text"],
        "VendorNumber 0x123 differs from 1018sub1 DefaultValue 0x124\nhelp: set VendorNumber to 0x124, or correct 1018sub1"
    );
    let region = &first["locations"][0]["physicalLocation"]["region"];
    assert_eq!(
        (region["startLine"].as_u64(), region["startColumn"].as_u64()),
        (Some(12), Some(14))
    );
    assert_eq!(region["endColumn"], 19);
    assert_eq!(region["snippet"]["text"], "0x123");
    // Columns count characters: "Größe" starts at character 24 of the line.
    let blanks = results
        .iter()
        .find(|r| r["ruleId"] == "naming.no-blanks")
        .expect("rule-pack result");
    let region = &blanks["locations"][0]["physicalLocation"]["region"];
    assert_eq!(region["snippet"]["text"], "Drehzahl Größe");
    // A point finding covers the rest of its line.
    let c412 = results
        .iter()
        .find(|r| r["ruleId"] == "C412")
        .expect("C412 result");
    assert!(
        c412["locations"][0]["physicalLocation"]["region"]
            .get("endColumn")
            .is_none()
    );

    let invocation = &run["invocations"][0];
    assert_eq!(invocation["executionSuccessful"], false);
    let notes = invocation["toolExecutionNotifications"]
        .as_array()
        .expect("notifications");
    assert_eq!(notes.len(), 1);
    assert_eq!(notes[0]["level"], "error");
    assert!(
        notes[0]["message"]["text"]
            .as_str()
            .is_some_and(|t| t.starts_with("eds/missing.eds: No such file"))
    );
}

fn fingerprint(report: &Report, result: usize) -> String {
    let log: Value = serde_json::from_str(&sarif(report)).expect("parses");
    log["runs"][0]["results"][result]["partialFingerprints"]["canopenerFindingHash/v1"]
        .as_str()
        .expect("fingerprint")
        .to_owned()
}

#[test]
fn fingerprints_survive_line_moves_but_not_other_changes() {
    let base = report();
    let original = fingerprint(&base, 0);
    let mut moved = base.clone();
    moved.files[0].findings[0].diagnostic.span.line += 7;
    moved.files[0].findings[0].diagnostic.span.column += 2;
    assert_eq!(fingerprint(&moved, 0), original);
    let mut reworded = base.clone();
    reworded.files[0].findings[0].diagnostic.message.push('!');
    assert_ne!(fingerprint(&reworded, 0), original);
    let mut other_key = base.clone();
    other_key.files[0].findings[0].diagnostic.key = Some("ProductNumber".into());
    assert_ne!(fingerprint(&other_key, 0), original);
    // The value is fixed across releases: changing the hash would reopen every alert.
    assert_eq!(original, "86ca412607de9f8a:1");
}

#[test]
fn identical_findings_get_distinct_fingerprints() {
    let same = finding(
        "C301",
        Severity::Error,
        "same",
        (3, 1, 2),
        Some("S"),
        Some("K"),
        None,
        false,
    );
    let report = Report {
        tool_version: "1.2.3".into(),
        checks: checks(),
        files: vec![FileReport {
            path: "a.eds".into(),
            findings: vec![same.clone(), same],
            ..FileReport::default()
        }],
    };
    validate(&report);
    let (a, b) = (fingerprint(&report, 0), fingerprint(&report, 1));
    assert_ne!(a, b);
    assert_eq!(a.split(':').next(), b.split(':').next());
}

#[test]
fn odd_paths_and_text_stay_valid() {
    let weird = finding(
        "C301",
        Severity::Warning,
        "value \u{0}\u{1b}[31m \"quoted\" <x> 日本語 😀",
        (1, 3, 4),
        None,
        None,
        Some("help with \\ backslash"),
        false,
    );
    let report = Report {
        tool_version: String::new(),
        checks: Vec::new(),
        files: vec![
            FileReport {
                path: "C:\\Geräte\\my dev#1.eds".into(),
                findings: vec![weird.clone()],
                source: [(1, "😀=日本語 and more".to_owned())].into_iter().collect(),
                problem: None,
            },
            FileReport {
                path: "/abs/path with space/x.eds".into(),
                findings: vec![weird],
                ..FileReport::default()
            },
            FileReport::unreadable("./rel/?.eds", "permission denied"),
        ],
    };
    let log = validate(&report);
    let uris: Vec<&str> = log["runs"][0]["artifacts"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|a| a["location"]["uri"].as_str())
        .collect();
    assert_eq!(
        uris,
        [
            "file:///C:/Ger%C3%A4te/my%20dev%231.eds",
            "file:///abs/path%20with%20space/x.eds",
            "rel/%3F.eds"
        ]
    );
    let region = &log["runs"][0]["results"][0]["locations"][0]["physicalLocation"]["region"];
    assert_eq!(region["snippet"]["text"], "日本語 ");
    assert_eq!(log["runs"][0]["tool"]["driver"].get("version"), None);
}

#[test]
fn the_schema_check_catches_invalid_logs() {
    let validator = jsonschema::options()
        .should_validate_formats(true)
        .build(&schema())
        .expect("the schema compiles");
    let mut log: Value = serde_json::from_str(&sarif(&report())).expect("parses");
    assert!(validator.is_valid(&log));
    let result = &mut log["runs"][0]["results"][0];
    result["level"] = Value::from("info");
    result["locations"][0]["physicalLocation"]["region"]["startLine"] = Value::from(0);
    assert_eq!(
        validator.iter_errors(&log).count(),
        2,
        "a bad level and a line 0 are both reported"
    );
    let mut bad_uri: Value = serde_json::from_str(&sarif(&report())).expect("parses");
    bad_uri["runs"][0]["tool"]["driver"]["informationUri"] = Value::from("not a uri");
    assert!(!validator.is_valid(&bad_uri), "formats are asserted");
}

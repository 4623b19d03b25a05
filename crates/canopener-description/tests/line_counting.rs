//! Issue 22 item 7: lines are counted one way everywhere (`canopener_eds::lines`: LF, CR LF and a lone
//! CR each end a line). For XML and for EDS text alike, every finding's position lies in the file, and
//! the line a report shows under it (human text, JSON, SARIF) is the line that position counts.
//!
//! `test_data/fuzz-findings/xdd-finding-past-end-of-file.xdd` is the fuzz finding that showed the two
//! disagreeing: its C537 at 241:46 is the `defaultValue` attribute only when a lone CR ends a line,
//! and the report showed an empty line 241 (the file has 178 LFs).

use canopener_description::{Checker, Selection};
use canopener_eds::lines::LineIndex;
use canopener_report::{FileReport, HumanOptions, Report};

const FINDING: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/test_data/fuzz-findings/xdd-finding-past-end-of-file.xdd"
);

fn checked(name: &str, bytes: &[u8]) -> Report {
    let checker = Checker::new(Vec::new(), Selection::default()).expect("no names to check");
    Report {
        tool_version: "test".to_owned(),
        checks: checker.selected(),
        files: vec![checker.check(name, Some(name), bytes)],
    }
}

/// Every finding lies in the text and its shown line is the line its position counts; in SARIF the
/// context snippet is that line too. Returns the number of findings checked.
fn agrees(report: &Report, text: &str) -> usize {
    let lines = LineIndex::new(text);
    let file: &FileReport = &report.files[0];
    assert_eq!(file.problem, None);
    for finding in &file.findings {
        let line = finding.diagnostic.span.line;
        assert!(
            usize::try_from(line).is_ok_and(|l| (1..=lines.count()).contains(&l)),
            "{finding:?} lies outside the {} lines",
            lines.count()
        );
        assert_eq!(
            file.source.get(&line).map(String::as_str),
            lines.line(line),
            "{finding:?}"
        );
    }
    let sarif: serde_json::Value =
        serde_json::from_str(&canopener_report::sarif(report)).expect("SARIF is JSON");
    let results = sarif["runs"][0]["results"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    assert_eq!(results.len(), file.findings.len());
    for result in &results {
        let location = &result["locations"][0]["physicalLocation"];
        let line = location["region"]["startLine"]
            .as_u64()
            .and_then(|l| u32::try_from(l).ok());
        let shown = location["contextRegion"]["snippet"]["text"].as_str();
        assert_eq!(shown, line.and_then(|l| lines.line(l)), "{result}");
    }
    let json: serde_json::Value =
        serde_json::from_str(&canopener_report::json(report)).expect("the JSON report parses");
    let json_lines: Vec<u64> = json["files"][0]["findings"]
        .as_array()
        .map(|f| f.iter().filter_map(|f| f["line"].as_u64()).collect())
        .unwrap_or_default();
    let positions: Vec<u64> = file
        .findings
        .iter()
        .map(|f| u64::from(f.diagnostic.span.line))
        .collect();
    assert_eq!(json_lines, positions);
    file.findings.len()
}

#[test]
fn the_xml_fuzz_finding_shows_the_attribute_its_position_names() {
    let bytes = canopener_testkit::fixture::read(FINDING).expect("the fuzz finding");
    let text = canopener_xdd::decode(&bytes).expect("UTF-8");
    assert_eq!(text.matches('\n').count(), 178, "the file as the fuzzer left it");
    let report = checked("finding.xdd", &bytes);
    assert!(agrees(&report, &text) > 10);
    let c537 = report.files[0]
        .findings
        .iter()
        .find(|f| f.diagnostic.code == "C537" && f.diagnostic.span.line == 241)
        .expect("sub 0 of 6200h says 16 sub-objects");
    assert_eq!(c537.diagnostic.span.column, 46);
    let shown = report.files[0].source.get(&241).cloned().unwrap_or_default();
    let at: String = shown.chars().skip(45).collect();
    assert!(at.starts_with(r#"defaultValue="16""#), "{shown:?}");
    let human = canopener_report::human(&report, &HumanOptions::default());
    assert!(
        human.contains(&format!("241 | {shown}")),
        "the human report shows the attribute under 241:46:\n{human}"
    );
}

#[test]
fn eds_text_with_lone_crs_is_counted_the_same_way() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../canopener-check/test_data/checks/base.eds"
    );
    let base = canopener_testkit::fixture::read_to_string(path).expect("base.eds");
    // Old Mac line ends for the first half of the file, and a default that C602 reports after them.
    let half = base.len() / 2;
    let cut = base[..half].rfind('\n').unwrap_or(0);
    let mixed = format!("{}{}", base[..cut].replace('\n', "\r"), &base[cut..]).replacen(
        "DefaultValue=10\n",
        "DefaultValue=5000\n",
        1,
    );
    assert!(
        mixed.contains("DefaultValue=5000"),
        "base.eds has a default of 10 after the cut"
    );
    let report = checked("base.eds", mixed.as_bytes());
    assert!(agrees(&report, &mixed) >= 2, "{:?}", report.files[0].findings);
    let findings = &report.files[0].findings;
    assert!(
        findings.iter().any(|f| f.diagnostic.code == "P004"),
        "a bare CR is reported"
    );
    let c602 = findings
        .iter()
        .find(|f| f.diagnostic.code == "C602")
        .expect("5000 is above the limits");
    let line = report.files[0].source.get(&c602.diagnostic.span.line);
    assert_eq!(line.map(String::as_str), Some("DefaultValue=5000"));
}

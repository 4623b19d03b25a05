//! The whole path the CLI takes: load an EDS, check it, build the report, write every format.

use canopener_check::{CheckInfo, Finding, Selection, check, registry};
use canopener_eds::Severity;
use canopener_report::{FileReport, HumanOptions, Report, html, human, json, junit, sarif};
use serde_json::Value;

/// A small EDS with problems the loader reports (duplicate key, inline comment, unlisted object)
/// and markup characters in a name.
const EDS: &str = "[FileInfo]\r\nFileName=test.eds\r\nFileVersion=1\r\nFileRevision=1\r\nEDSVersion=4.0\r\n\
Description=<b>test</b> & \"quotes\"\r\n\r\n[DeviceInfo]\r\nVendorName=ACME\r\nVendorNumber=0x123\r\n\
VendorNumber=0x124\r\n\r\n[MandatoryObjects]\r\nSupportedObjects=1\r\n1=0x1000\r\n\r\n[1000]\r\n\
ParameterName=Device type <x>\r\nObjectType=0x7\r\nDataType=0x0007 ; UNSIGNED32\r\nAccessType=ro\r\n\
DefaultValue=0x191\r\nPDOMapping=0\r\n\r\n[2000]\r\nParameterName=Unlisted\r\nObjectType=0x7\r\n\
DataType=0x0005\r\nAccessType=rw\r\n";

fn report() -> Report {
    let loaded = canopener_eds::load(EDS.as_bytes());
    let mut findings = check(&loaded, Some("test.eds"), &Selection::default()).findings;
    // The loading diagnostics are reported as findings by the checker; add any it did not (yet)
    // report so the test does not depend on which checks exist.
    for diagnostic in &loaded.diagnostics {
        let finding = Finding::from_diagnostic(diagnostic, false);
        if !findings.iter().any(|f| {
            f.diagnostic.code == finding.diagnostic.code && f.diagnostic.span == finding.diagnostic.span
        }) {
            findings.push(finding);
        }
    }
    Report {
        tool_version: "0.1.0".into(),
        checks: registry::builtin().into_iter().map(CheckInfo::describe).collect(),
        files: vec![FileReport::from_document("test.eds", findings, &loaded.document)],
    }
}

#[test]
fn source_lines_come_from_the_document() {
    let report = report();
    let file = &report.files[0];
    assert!(
        !file.findings.is_empty(),
        "the loader reports the duplicate key at least"
    );
    let lines: Vec<&str> = EDS.split("\r\n").collect();
    for finding in &file.findings {
        let line = file
            .source
            .get(&finding.diagnostic.span.line)
            .expect("source line of every finding");
        let index = usize::try_from(finding.diagnostic.span.line).expect("small") - 1;
        assert_eq!(Some(&line.as_str()), lines.get(index), "{finding:?}");
    }
    let from_text = FileReport::from_text("test.eds", file.findings.clone(), EDS);
    assert_eq!(from_text.source, file.source);
}

#[test]
fn every_format_accepts_a_real_check() {
    let report = report();
    let total = report.findings_total();
    let text = human(&report, &HumanOptions::default());
    assert_eq!(
        text.matches("\n --> test.eds:").count() + text.matches("\n  --> test.eds:").count(),
        total
    );
    let doc: Value = serde_json::from_str(&json(&report)).expect("JSON parses");
    assert_eq!(doc["files"][0]["findings"].as_array().map(Vec::len), Some(total));
    let log: Value = serde_json::from_str(&sarif(&report)).expect("SARIF parses");
    assert_eq!(log["runs"][0]["results"].as_array().map(Vec::len), Some(total));
    let xml = junit(&report);
    let parsed = roxmltree::Document::parse(&xml).expect("JUnit parses");
    let cases = parsed
        .descendants()
        .filter(|n| n.has_tag_name("testcase"))
        .count();
    assert!(cases >= report.checks.len(), "one test case per check at least");
    let page = html(&report);
    assert_eq!(page.matches("<article class=\"finding").count(), total);
    assert!(!page.contains("<x>"));
}

#[test]
fn a_file_report_counts_its_findings_by_severity() {
    let report = report();
    let file = &report.files[0];
    let total: usize = [Severity::Error, Severity::Warning, Severity::Info]
        .into_iter()
        .map(|s| file.count(s))
        .sum();
    assert_eq!(total, file.findings.len());
    assert!(file.count(Severity::Error) > 0, "the duplicate key is an error");
    assert_eq!(
        FileReport::unreadable("gone.eds", "no such file").count(Severity::Error),
        0
    );
}

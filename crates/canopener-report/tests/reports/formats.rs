//! Golden snapshots of the human, JSON and JUnit reports and structural checks of each format.

use canopener_eds::Severity;
use canopener_report::{HumanOptions, Report, human, json, junit};
use serde_json::Value;

use crate::fixture::report;

/// Runs `f` with snapshots stored in `tests/snapshots`.
fn golden(f: impl FnOnce()) {
    let mut settings = insta::Settings::clone_current();
    settings.set_snapshot_path("../snapshots");
    settings.set_prepend_module_to_snapshot(false);
    settings.bind(f);
}

#[test]
fn human_snapshot() {
    let text = human(
        &report(),
        &HumanOptions {
            color: false,
            summary_table: true,
        },
    );
    golden(|| insta::assert_snapshot!("human", text));
}

#[test]
fn json_snapshot() {
    golden(|| insta::assert_snapshot!("json", json(&report())));
}

#[test]
fn junit_snapshot() {
    golden(|| insta::assert_snapshot!("junit", junit(&report())));
}

#[test]
fn summary_counts_and_order() {
    let summary = report().summary();
    assert_eq!(
        (
            summary.files,
            summary.files_with_errors,
            summary.errors,
            summary.warnings,
            summary.infos,
            summary.problems
        ),
        (4, 2, 3, 3, 2, 1)
    );
    let order: Vec<(&str, usize, usize)> = summary
        .by_code
        .iter()
        .map(|c| (c.code.as_str(), c.count, c.files))
        .collect();
    assert_eq!(
        order,
        [
            ("C301", 1, 1),
            ("C520", 1, 1),
            ("C801", 1, 1),
            ("C412", 1, 1),
            ("P020", 1, 1),
            ("naming.no-blanks", 1, 1),
            ("T004", 2, 2)
        ]
    );
    let p020 = summary
        .by_code
        .iter()
        .find(|c| c.code == "P020")
        .map(|c| c.title.as_str());
    assert_eq!(p020, Some(""), "a code without a description has an empty title");
    assert_eq!(report().findings_total(), 8);
}

#[test]
fn human_without_summary_ends_with_the_last_finding() {
    let text = human(&report(), &HumanOptions::default());
    assert!(!text.contains("severity  count"), "{text}");
    assert!(!text.contains(" in 4 files"), "{text}");
    assert!(
        text.ends_with("error: eds/missing.eds: No such file or directory (os error 2)\n\n"),
        "{text}"
    );
    // The tab before the inline comment is expanded so the carets stay under the comment.
    let expected = format!(
        "20 | DataType=0x0007 ; UNSIGNED32\n   | {}{}\n",
        " ".repeat(15),
        "^".repeat(13)
    );
    assert!(text.contains(&expected), "{text}");
}

#[test]
fn json_has_every_mandatory_member() {
    let report = report();
    let doc: Value = serde_json::from_str(&json(&report)).expect("the JSON report parses");
    assert_eq!(doc["version"], 1);
    let files = doc["files"].as_array().expect("files is an array");
    assert_eq!(files.len(), report.files.len());
    for (file, expected) in files.iter().zip(&report.files) {
        assert_eq!(file["path"], expected.path.as_str());
        assert_eq!(
            file.get("problem").and_then(Value::as_str),
            expected.problem.as_deref()
        );
        let findings = file["findings"].as_array().expect("findings is an array");
        assert_eq!(findings.len(), expected.findings.len());
        for (f, e) in findings.iter().zip(&expected.findings) {
            for member in [
                "code", "severity", "message", "line", "column", "section", "key", "fixable",
            ] {
                assert!(f.get(member).is_some(), "{member} missing in {f}");
            }
            assert!(
                ["error", "warning", "info"].contains(&f["severity"].as_str().unwrap_or("")),
                "{f}"
            );
            assert_eq!(f["line"], e.diagnostic.span.line);
            assert_eq!(f["column"], e.diagnostic.span.column);
            assert_eq!(f["section"].as_str(), e.diagnostic.section.as_deref());
            assert_eq!(f["key"].as_str(), e.diagnostic.key.as_deref());
            assert_eq!(f["fixable"], e.fixable);
            assert_eq!(
                f.get("help").and_then(Value::as_str),
                e.diagnostic.help.as_deref()
            );
            assert_eq!(f["message"], e.diagnostic.message.as_str());
        }
    }
    let summary = &doc["summary"];
    for (member, value) in [
        ("files", 4),
        ("errors", 3),
        ("warnings", 3),
        ("infos", 2),
        ("problems", 1),
    ] {
        assert_eq!(summary[member], value, "summary.{member}");
    }
    assert_eq!(summary["by_code"].as_array().map(Vec::len), Some(7));
    assert_eq!(summary["by_code"][0]["code"], "C301");
    assert_eq!(summary["by_code"][0]["severity"], "error");
}

#[test]
fn json_of_an_empty_report() {
    let doc: Value = serde_json::from_str(&json(&Report::default())).expect("parses");
    assert_eq!(doc["files"], Value::Array(Vec::new()));
    assert_eq!(doc["summary"]["errors"], 0);
    assert_eq!(doc["summary"]["by_code"], Value::Array(Vec::new()));
}

fn attr(node: roxmltree::Node<'_, '_>, name: &str) -> String {
    node.attribute(name).unwrap_or_default().to_owned()
}

fn count(node: roxmltree::Node<'_, '_>, name: &str) -> usize {
    attr(node, name).parse().unwrap_or(usize::MAX)
}

#[test]
fn junit_parses_and_its_counts_are_right() {
    let report = report();
    let xml = junit(&report);
    let doc = roxmltree::Document::parse(&xml).expect("the JUnit report is well-formed XML");
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "testsuites");
    let suites: Vec<_> = root.children().filter(|n| n.has_tag_name("testsuite")).collect();
    assert_eq!(suites.len(), report.files.len());
    let (mut tests, mut failures, mut errors) = (0, 0, 0);
    for (suite, file) in suites.iter().zip(&report.files) {
        assert_eq!(attr(*suite, "name"), file.path);
        let cases: Vec<_> = suite.children().filter(|n| n.has_tag_name("testcase")).collect();
        let failed = cases
            .iter()
            .filter(|c| c.children().any(|n| n.has_tag_name("failure")))
            .count();
        let errored = cases
            .iter()
            .filter(|c| c.children().any(|n| n.has_tag_name("error")))
            .count();
        assert_eq!(count(*suite, "tests"), cases.len());
        assert_eq!(count(*suite, "failures"), failed);
        assert_eq!(count(*suite, "errors"), errored);
        for case in &cases {
            assert_eq!(attr(*case, "classname"), file.path);
        }
        tests += cases.len();
        failures += failed;
        errors += errored;
    }
    assert_eq!((tests, failures, errors), (8 + 7 + 7 + 1, 5 + 1, 1));
    assert_eq!(
        (
            count(root, "tests"),
            count(root, "failures"),
            count(root, "errors")
        ),
        (23, 6, 1)
    );

    let motor = suites[0];
    let case = |name: &str| {
        motor
            .children()
            .find(|n| n.has_tag_name("testcase") && attr(*n, "name") == name)
            .unwrap_or_else(|| panic!("no test case {name}"))
    };
    let c301 = case("C301 VendorNumber agrees with 1018sub1");
    let failure = c301
        .children()
        .find(|n| n.has_tag_name("failure"))
        .expect("C301 fails");
    assert_eq!(attr(failure, "type"), "error");
    assert_eq!(
        attr(failure, "message"),
        "VendorNumber 0x123 differs from 1018sub1 DefaultValue 0x124"
    );
    let body = failure.text().unwrap_or_default();
    assert!(body.contains("eds/motor drive.eds:12:14: error[C301]:"), "{body}");
    assert!(body.contains("    help: set VendorNumber to 0x124"), "{body}");
    // Infos do not fail: they are in system-out, with the markup characters intact.
    let t004 = case("T004 Names python canopen shows differently <rpm> & \"quoted\"");
    assert!(!t004.children().any(|n| n.has_tag_name("failure")));
    let out = t004
        .children()
        .find(|n| n.has_tag_name("system-out"))
        .expect("T004 system-out");
    assert!(out.text().unwrap_or_default().contains("\"Speed <rpm> & 'max'\""));
    // A warning fails; a control character is replaced, `]]>` survives as text.
    assert_eq!(
        attr(
            case("C412 SupportedObjects matches the listed entries")
                .first_element_child()
                .expect("failure"),
            "type"
        ),
        "warning"
    );
    let c520 = case("C520 Every object has a ParameterName");
    assert!(
        c520.children()
            .any(|n| n.text().unwrap_or_default().contains("[2001sub1] \u{FFFD}]]>"))
    );
    // Codes without a description get a test case of their own; checks without findings pass.
    assert!(case("P020").children().any(|n| n.has_tag_name("failure")));
    assert!(!case("C999 A check that finds nothing here").has_children());

    let missing = suites[3];
    let error = missing
        .descendants()
        .find(|n| n.has_tag_name("error"))
        .expect("error element");
    assert_eq!(attr(error, "message"), "No such file or directory (os error 2)");
}

#[test]
fn junit_of_an_empty_report_is_valid() {
    let xml = junit(&Report::default());
    let doc = roxmltree::Document::parse(&xml).expect("well-formed");
    assert_eq!(count(doc.root_element(), "tests"), 0);
}

#[test]
fn html_is_self_contained_and_escaped() {
    let page = canopener_report::html(&report());
    // No network: nothing is loaded from elsewhere.
    for forbidden in ["<link", " src=", "@import", "url(", "http://", "fetch("] {
        assert!(!page.contains(forbidden), "the page contains {forbidden}");
    }
    assert!(!page.contains("<rpm>"), "file content must be escaped");
    assert!(page.contains("Speed &lt;rpm&gt; &amp; &apos;max&apos;"));
    assert!(page.contains("A&amp;B"));
    assert!(!page.contains('\u{1}'));
    // Every link to an explanation has its target.
    let mut rest = page.as_str();
    let mut links = 0;
    while let Some(at) = rest.find("href=\"#check-") {
        rest = &rest[at + 7..];
        let end = rest.find('"').expect("closing quote");
        let id = &rest[..end];
        assert!(page.contains(&format!("id=\"{id}\"")), "no target for #{id}");
        links += 1;
    }
    // 8 findings and 7 rows of the per-code table.
    assert_eq!(links, 8 + 7);
    for code in [
        "C301",
        "C412",
        "C520",
        "C801",
        "C999",
        "T004",
        "naming.no-blanks",
        "P020",
    ] {
        assert!(
            page.contains(&format!("<details class=\"check\" id=\"check-{code}\">")),
            "{code}"
        );
    }
    let severity_of = |severity: Severity| {
        page.matches(&format!("data-severity=\"{severity}\" data-code"))
            .count()
    };
    assert_eq!(
        (
            severity_of(Severity::Error),
            severity_of(Severity::Warning),
            severity_of(Severity::Info)
        ),
        (3, 3, 2)
    );
}

//! JUnit XML, for CI systems that show test results (GitLab, Jenkins, Azure, GitHub test reporters).

use std::collections::BTreeSet;
use std::fmt::Write as _;

use canopener_check::Finding;
use canopener_eds::Severity;

use crate::text::xml_escape;
use crate::{FileReport, Report};

/// The report as JUnit XML: one `<testsuite>` per file and in it one `<testcase
/// classname="path" name="CODE title">` per selected check (plus one per code that has findings but
/// is not among the report's checks).
///
/// A test case fails (`<failure>`, `type` the most serious severity) when its check found errors or
/// warnings: warnings fail too because CI users read a JUnit report as "what needs attention", and
/// `--deny warnings` is the usual CI setting. Infos never fail: they go to the test case's
/// `<system-out>`. A file that could not be read is one test case `read file` with an `<error>`.
/// Finding text lists `path:line:column: severity[CODE]: message`, then the help line.
pub fn junit(report: &Report) -> String {
    let mut suites = String::new();
    let (mut tests, mut failures, mut errors) = (0usize, 0usize, 0usize);
    for file in &report.files {
        let suite = suite(report, file);
        tests += suite.tests;
        failures += suite.failures;
        errors += suite.errors;
        suites.push_str(&suite.xml);
    }
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let _ = writeln!(
        out,
        "<testsuites name=\"canopener eds check\" tests=\"{tests}\" failures=\"{failures}\" \
         errors=\"{errors}\" skipped=\"0\">"
    );
    out.push_str(&suites);
    out.push_str("</testsuites>\n");
    out
}

struct Suite {
    xml: String,
    tests: usize,
    failures: usize,
    errors: usize,
}

fn suite(report: &Report, file: &FileReport) -> Suite {
    let path = xml_escape(&file.path, true);
    let mut cases = String::new();
    let (mut tests, mut failures, mut errors) = (0usize, 0usize, 0usize);
    if let Some(problem) = &file.problem {
        tests += 1;
        errors += 1;
        let _ = writeln!(
            cases,
            "    <testcase classname=\"{path}\" name=\"read file\">\n      <error type=\"io\" \
             message=\"{}\">{}</error>\n    </testcase>",
            xml_escape(problem, true),
            xml_escape(problem, false)
        );
    } else {
        let mut seen = BTreeSet::new();
        let mut codes: Vec<(&str, &str)> = Vec::new();
        for check in &report.checks {
            if seen.insert(check.code.as_str()) {
                codes.push((&check.code, &check.title));
            }
        }
        let extra: BTreeSet<&str> = file
            .findings
            .iter()
            .map(|f| f.diagnostic.code.as_str())
            .filter(|c| !seen.contains(c))
            .collect();
        codes.extend(extra.into_iter().map(|c| (c, "")));
        for (code, title) in codes {
            tests += 1;
            let name = if title.is_empty() {
                code.to_owned()
            } else {
                format!("{code} {title}")
            };
            let found: Vec<&Finding> = file
                .findings
                .iter()
                .filter(|f| f.diagnostic.code == code)
                .collect();
            let failing: Vec<&Finding> = found
                .iter()
                .copied()
                .filter(|f| f.diagnostic.severity != Severity::Info)
                .collect();
            let infos: Vec<&Finding> = found
                .iter()
                .copied()
                .filter(|f| f.diagnostic.severity == Severity::Info)
                .collect();
            let open = format!(
                "    <testcase classname=\"{path}\" name=\"{}\"",
                xml_escape(&name, true)
            );
            if found.is_empty() {
                let _ = writeln!(cases, "{open}/>");
                continue;
            }
            let _ = writeln!(cases, "{open}>");
            if let Some(first) = failing.first() {
                failures += 1;
                let worst = failing
                    .iter()
                    .map(|f| f.diagnostic.severity)
                    .max()
                    .unwrap_or(Severity::Warning);
                let message = if failing.len() > 1 {
                    format!("{} (and {} more)", first.diagnostic.message, failing.len() - 1)
                } else {
                    first.diagnostic.message.clone()
                };
                let _ = writeln!(
                    cases,
                    "      <failure type=\"{worst}\" message=\"{}\">{}</failure>",
                    xml_escape(&message, true),
                    xml_escape(&listing(file, &failing), false)
                );
            }
            if !infos.is_empty() {
                let _ = writeln!(
                    cases,
                    "      <system-out>{}</system-out>",
                    xml_escape(&listing(file, &infos), false)
                );
            }
            cases.push_str("    </testcase>\n");
        }
    }
    let mut xml = String::new();
    let _ = writeln!(
        xml,
        "  <testsuite name=\"{path}\" tests=\"{tests}\" failures=\"{failures}\" errors=\"{errors}\" \
         skipped=\"0\">"
    );
    xml.push_str(&cases);
    xml.push_str("  </testsuite>\n");
    Suite {
        xml,
        tests,
        failures,
        errors,
    }
}

/// The findings as text lines, one per finding plus an indented help line.
fn listing(file: &FileReport, findings: &[&Finding]) -> String {
    let mut text = String::new();
    for f in findings {
        let _ = writeln!(
            text,
            "{}:{}:{}: {}[{}]: {}",
            file.path,
            f.diagnostic.span.line,
            f.diagnostic.span.column,
            f.diagnostic.severity,
            f.diagnostic.code,
            f.diagnostic.message
        );
        if let Some(help) = &f.diagnostic.help {
            let _ = writeln!(text, "    help: {help}");
        }
    }
    text
}

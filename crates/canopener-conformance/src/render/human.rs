//! The human report: a CCT-like summary per group (`SDO Test (17): 16 passed, 1 failed`), then each
//! failure and undecided test with its analysis and a log excerpt.

use std::fmt::Write as _;

use crate::catalogue::GROUPS;
use crate::model::{Report, TestReport, Verdict};

/// What the summaries call a pass no criterion judged.
pub const MEASURED: &str = "measured, no criterion";

/// How many telegrams of a failing test the human report shows (the rest are in `--log DIR`).
pub const EXCERPT: usize = 12;

/// The human report.
pub fn render(report: &Report) -> String {
    let mut out = String::new();
    let node = report.device.node.map_or("-".to_owned(), |n| n.to_string());
    let _ = writeln!(
        out,
        "canopener test: node {node} on {}, EDS {}",
        report.bus.spec, report.device.eds
    );
    if let Some(identity) = report.device.identity {
        let hexed = |v: Option<u32>| v.map_or("?".to_owned(), |v| format!("{v:#010X}"));
        let _ = writeln!(
            out,
            "identity: vendor {}, product {}, revision {}, serial {}",
            hexed(identity.vendor_id),
            hexed(identity.product_code),
            hexed(identity.revision),
            hexed(identity.serial)
        );
    }
    let _ = writeln!(out);
    for (group, name) in GROUPS {
        let tests: Vec<&TestReport> = report.tests.iter().filter(|t| t.group == *group).collect();
        if tests.is_empty() {
            continue;
        }
        let count = |v: Verdict| tests.iter().filter(|t| t.verdict == v).count();
        let measured = tests.iter().filter(|t| t.measured_no_criterion()).count();
        let mut parts = vec![format!("{} passed", count(Verdict::Pass) - measured)];
        if measured > 0 {
            parts.push(format!("{measured} {MEASURED}"));
        }
        for (verdict, label) in [
            (Verdict::Fail, "failed"),
            (Verdict::Inconclusive, "inconclusive"),
            (Verdict::NotApplicable, "not applicable"),
        ] {
            if count(verdict) > 0 {
                parts.push(format!("{} {label}", count(verdict)));
            }
        }
        let _ = writeln!(out, "{name} ({}): {}", tests.len(), parts.join(", "));
    }
    for test in report
        .tests
        .iter()
        .filter(|t| matches!(t.verdict, Verdict::Fail | Verdict::Inconclusive))
    {
        let _ = writeln!(
            out,
            "\n{} {} — {}",
            test.verdict.as_str().to_uppercase(),
            test.id,
            test.title
        );
        let _ = writeln!(out, "  {}", test.reason);
        let _ = writeln!(out, "  References: {}", test.references.join("; "));
        for line in test.analysis.lines() {
            let _ = writeln!(out, "  {line}");
        }
        if test.verdict == Verdict::Fail {
            let _ = writeln!(
                out,
                "  Telegrams ({} of {}):",
                test.telegrams.len().min(EXCERPT),
                test.telegrams.len()
            );
            for telegram in test.telegrams.iter().rev().take(EXCERPT).rev() {
                let _ = writeln!(
                    out,
                    "    {:10.6} {} {} [{}] {}  {}",
                    telegram.t,
                    match telegram.dir {
                        crate::model::Direction::Tx => "tx",
                        crate::model::Direction::Rx => "rx",
                    },
                    telegram.id,
                    telegram.frame.dlc(),
                    telegram.data,
                    telegram.meaning
                );
            }
        }
    }
    let measured: Vec<&str> = report
        .tests
        .iter()
        .filter(|t| t.measured_no_criterion())
        .map(|t| t.id.as_str())
        .collect();
    if !measured.is_empty() {
        let _ = writeln!(
            out,
            "\n{} (not conformance passes: no criterion was given, see --criteria): {}",
            upper_first(MEASURED),
            measured.join(", ")
        );
    }
    if report.interrupted {
        let _ = writeln!(
            out,
            "\nINTERRUPTED: the tests after the last one listed did not run."
        );
    }
    for left in &report.left_modified {
        let _ = writeln!(out, "left modified: {left}");
    }
    let s = report.summary;
    let _ = writeln!(
        out,
        "\n{} tests: {} passed, {}{} failed, {} inconclusive, {} not applicable ({:.1} s)",
        report.tests.len(),
        s.conformance_passes(),
        if s.measured_no_criterion > 0 {
            format!("{} {MEASURED}, ", s.measured_no_criterion)
        } else {
            String::new()
        },
        s.fail,
        s.inconclusive,
        s.not_applicable,
        report.duration_s
    );
    out
}

fn upper_first(text: &str) -> String {
    let mut chars = text.chars();
    chars
        .next()
        .map_or(String::new(), |c| c.to_uppercase().chain(chars).collect())
}

//! The report as JUnit XML: one test case per test, the telegram log as `system-out`.

use std::fmt::Write as _;

use crate::model::{Report, Verdict};

/// The JUnit XML of `report`.
pub fn render(report: &Report) -> String {
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let s = report.summary;
    let _ = writeln!(
        out,
        "<testsuite name=\"canopener test\" tests=\"{}\" failures=\"{}\" errors=\"{}\" skipped=\"{}\" time=\"{:.6}\" timestamp=\"{}\">",
        report.tests.len(),
        s.fail,
        s.inconclusive,
        s.not_applicable,
        report.duration_s,
        escape(&report.started)
    );
    for test in &report.tests {
        let _ = writeln!(
            out,
            "  <testcase classname=\"{}.{}\" name=\"{}\" time=\"{:.6}\">",
            escape(&test.suite),
            escape(&test.group),
            escape(&format!("{} {}", test.id, test.title)),
            test.duration_s
        );
        match test.verdict {
            Verdict::Fail => {
                let _ = writeln!(
                    out,
                    "    <failure message=\"{}\">{}</failure>",
                    escape(&test.reason),
                    escape(&test.analysis)
                );
            }
            Verdict::Inconclusive => {
                let _ = writeln!(out, "    <error message=\"{}\"/>", escape(&test.reason));
            }
            Verdict::NotApplicable => {
                let _ = writeln!(out, "    <skipped message=\"{}\"/>", escape(&test.reason));
            }
            Verdict::Pass => {}
        }
        let log: String = test
            .telegrams
            .iter()
            .map(|t| format!("{:.6} {:?} {} {}  {}\n", t.t, t.dir, t.id, t.data, t.meaning))
            .collect();
        let _ = writeln!(out, "    <system-out>{}</system-out>", escape(&log));
        let _ = writeln!(out, "  </testcase>");
    }
    out.push_str("</testsuite>\n");
    out
}

/// Escapes the five XML special characters and drops the control characters XML 1.0 forbids.
fn escape(text: &str) -> String {
    text.chars()
        .filter(|c| !c.is_control() || matches!(c, '\n' | '\t' | '\r'))
        .map(|c| match c {
            '&' => "&amp;".to_owned(),
            '<' => "&lt;".to_owned(),
            '>' => "&gt;".to_owned(),
            '"' => "&quot;".to_owned(),
            '\'' => "&apos;".to_owned(),
            c => c.to_string(),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markup_in_reasons_is_escaped() {
        assert_eq!(escape("a<b & \"c\"\u{1}"), "a&lt;b &amp; &quot;c&quot;");
    }
}

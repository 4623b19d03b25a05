//! The report as JUnit XML: one test case per test, the telegram log as `system-out`.

use std::fmt::Write as _;

use canopener_eds::xml_text::{self, XmlPlace, XmlStyle};

use crate::model::{Report, Verdict};

/// The JUnit XML of `report`.
pub fn render(report: &Report) -> String {
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let s = report.summary;
    // A measurement no criterion judged is no conformance pass: it is reported as skipped, with
    // the counts apart in the suite's properties.
    let _ = writeln!(
        out,
        "<testsuite name=\"canopener test\" tests=\"{}\" failures=\"{}\" errors=\"{}\" skipped=\"{}\" time=\"{:.6}\" timestamp=\"{}\">",
        report.tests.len(),
        s.fail,
        s.inconclusive,
        s.not_applicable + s.measured_no_criterion,
        report.duration_s,
        attr(&report.started)
    );
    out.push_str("  <properties>\n");
    for (name, value) in [
        ("passed", s.conformance_passes()),
        ("measured_no_criterion", s.measured_no_criterion),
        ("not_applicable", s.not_applicable),
    ] {
        let _ = writeln!(out, "    <property name=\"{name}\" value=\"{value}\"/>");
    }
    out.push_str("  </properties>\n");
    for test in &report.tests {
        let _ = writeln!(
            out,
            "  <testcase classname=\"{}.{}\" name=\"{}\" time=\"{:.6}\">",
            attr(&test.suite),
            attr(&test.group),
            attr(&format!("{} {}", test.id, test.title)),
            test.duration_s
        );
        match test.verdict {
            Verdict::Fail => {
                let _ = writeln!(
                    out,
                    "    <failure message=\"{}\">{}</failure>",
                    attr(&test.reason),
                    content(&test.analysis)
                );
            }
            Verdict::Inconclusive => {
                let _ = writeln!(out, "    <error message=\"{}\"/>", attr(&test.reason));
            }
            Verdict::NotApplicable => {
                let _ = writeln!(out, "    <skipped message=\"{}\"/>", attr(&test.reason));
            }
            Verdict::Pass if test.no_criterion => {
                let _ = writeln!(
                    out,
                    "    <skipped message=\"{}\"/>",
                    attr(&format!("measured, no criterion: {}", test.reason))
                );
            }
            Verdict::Pass => {}
        }
        let log: String = test
            .telegrams
            .iter()
            .map(|t| format!("{:.6} {:?} {} {}  {}\n", t.t, t.dir, t.id, t.data, t.meaning))
            .collect();
        let _ = writeln!(out, "    <system-out>{}</system-out>", content(&log));
        let _ = writeln!(out, "  </testcase>");
    }
    out.push_str("</testsuite>\n");
    out
}

fn attr(text: &str) -> String {
    xml_text::escape(text, XmlPlace::Attribute, XmlStyle::DECIMAL)
}

fn content(text: &str) -> String {
    xml_text::escape(text, XmlPlace::Content, XmlStyle::DECIMAL)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markup_in_reasons_is_escaped() {
        assert_eq!(attr("a<b & \"c\""), "a&lt;b &amp; &quot;c&quot;");
        assert_eq!(content("x < y"), "x &lt; y");
    }
}

//! Checker reports for people and CI: compiler-style text, JSON, SARIF 2.1.0, JUnit XML and one
//! self-contained HTML page.
//!
//! The caller (the CLI) runs the checks and builds a [`Report`]; every format is a pure function from
//! the report to a `String`. This crate performs no IO.
//!
//! - [`human`]: `error[C301]: message`, ` --> path:line:column`, the source line and a caret, like rustc;
//! - [`json`]: the `version` 1 document described in `docs/check-json.md`;
//! - [`sarif`]: SARIF 2.1.0 for GitHub and GitLab code scanning;
//! - [`junit`]: one test case per selected check per file;
//! - [`html`]: one page with a summary, filters (also from the URL hash) and the explanations.

#![warn(missing_docs)]
// A file or a frame must never panic this library: no unwrap, expect or unchecked index outside tests
// (as rustls does).
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)
)]

mod html;
mod human;
mod json;
mod junit;
mod sarif;
mod summary;
mod text;

use std::collections::BTreeMap;

use canopener_check::{CheckDescription, Finding};
use canopener_eds::Severity;
use canopener_eds::lines::LineIndex;
use canopener_eds::syntax::Document;

pub use html::html;
pub use human::{HumanOptions, human};
pub use json::json;
pub use junit::junit;
pub use sarif::sarif;
pub use summary::{CodeCount, ReportTotals};

/// Everything a report shows: the tool version, the selected checks and the results per file.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Report {
    /// The canopener version that produced the findings.
    pub tool_version: String,
    /// The selected checks (built-in and rule packs), with their explanations.
    pub checks: Vec<CheckDescription>,
    /// The checked files, in the order they are shown.
    pub files: Vec<FileReport>,
}

/// The result for one file.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct FileReport {
    /// The path as the user gave it (reports show it unchanged; SARIF turns it into a URI).
    pub path: String,
    /// The findings, in the order they are shown.
    pub findings: Vec<Finding>,
    /// The text of the lines findings point at (1-based line number), without line endings.
    pub source: BTreeMap<u32, String>,
    /// The file could not be read: the IO error message. There are no findings then.
    pub problem: Option<String>,
}

impl FileReport {
    /// The report of a checked file, taking the lines the findings point at from the parsed document.
    pub fn from_document(path: impl Into<String>, findings: Vec<Finding>, document: &Document) -> Self {
        let source = findings
            .iter()
            .filter_map(|f| {
                let index = usize::try_from(f.diagnostic.span.line).ok()?.checked_sub(1)?;
                document
                    .lines()
                    .get(index)
                    .map(|_| (f.diagnostic.span.line, document.line_text(index).to_owned()))
            })
            .collect();
        Self {
            path: path.into(),
            findings,
            source,
            problem: None,
        }
    }

    /// The report of a checked file, taking the lines the findings point at from its decoded text,
    /// counted as every position is ([`canopener_eds::lines`]: LF, CR LF and a lone CR end a line).
    pub fn from_text(path: impl Into<String>, findings: Vec<Finding>, text: &str) -> Self {
        let lines = LineIndex::new(text);
        let source = findings
            .iter()
            .filter_map(|f| {
                let number = f.diagnostic.span.line;
                Some((number, lines.line(number)?.to_owned()))
            })
            .collect();
        Self {
            path: path.into(),
            findings,
            source,
            problem: None,
        }
    }

    /// How many findings have this severity.
    pub fn count(&self, severity: Severity) -> usize {
        self.findings
            .iter()
            .filter(|f| f.diagnostic.severity == severity)
            .count()
    }

    /// The report of a file that could not be read.
    pub fn unreadable(path: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            path: path.into(),
            findings: Vec::new(),
            source: BTreeMap::new(),
            problem: Some(message.into()),
        }
    }
}

impl Report {
    /// Counts by severity and by code.
    pub fn summary(&self) -> ReportTotals {
        summary::summarize(self)
    }

    /// The number of findings in all files.
    pub fn findings_total(&self) -> usize {
        self.files.iter().map(|f| f.findings.len()).sum()
    }

    /// The description of a check by code (exact match first, then case-insensitive).
    pub(crate) fn check(&self, code: &str) -> Option<&CheckDescription> {
        self.checks
            .iter()
            .find(|c| c.code == code)
            .or_else(|| self.checks.iter().find(|c| c.code.eq_ignore_ascii_case(code)))
    }
}

#[cfg(test)]
mod tests {
    use canopener_eds::{Diagnostic, Span};

    use super::*;

    fn finding(line: u32) -> Finding {
        Finding {
            diagnostic: Diagnostic::from_parts(
                "N001".to_owned(),
                Severity::Error,
                Span::new(line, 1, 0),
                "m",
            ),
            fixable: false,
        }
    }

    /// The source lines come from the text by the rule positions are counted by: a lone CR ends a line.
    #[test]
    fn source_lines_are_counted_as_positions_are() {
        let text = "<a>\r<b/>\r\n<c/>\n";
        let report = FileReport::from_text(
            "n.graphml",
            vec![finding(2), finding(3), finding(4), finding(9)],
            text,
        );
        let source: Vec<(u32, &str)> = report.source.iter().map(|(n, l)| (*n, l.as_str())).collect();
        assert_eq!(source, [(2, "<b/>"), (3, "<c/>"), (4, "")]);
    }
}

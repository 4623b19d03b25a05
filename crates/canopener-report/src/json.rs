//! The JSON report, version 1 (documented in `docs/check-json.md`).

use canopener_eds::Severity;
use serde::Serialize;

use crate::{Report, ReportTotals};

/// The version of the JSON document; bumped only when a member changes meaning or disappears.
pub(crate) const JSON_VERSION: u32 = 1;

#[derive(Serialize)]
struct Document<'a> {
    version: u32,
    tool: Tool<'a>,
    files: Vec<File<'a>>,
    summary: ReportTotals,
}

#[derive(Serialize)]
struct Tool<'a> {
    name: &'static str,
    version: &'a str,
}

#[derive(Serialize)]
struct File<'a> {
    path: &'a str,
    #[serde(skip_serializing_if = "Option::is_none")]
    problem: Option<&'a str>,
    findings: Vec<Finding<'a>>,
}

#[derive(Serialize)]
struct Finding<'a> {
    code: &'a str,
    severity: Severity,
    message: &'a str,
    line: u32,
    column: u32,
    /// Characters covered from `column` (0 for a point).
    length: u32,
    section: Option<&'a str>,
    key: Option<&'a str>,
    fixable: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    help: Option<&'a str>,
}

/// The report as one JSON document:
/// `{"version":1,"tool":{…},"files":[{"path":…,"findings":[{"code","severity","message","line",
/// "column","length","section","key","fixable","help"?}]}],"summary":{…}}`, pretty-printed, ending
/// with a newline. `problem` appears on a file only when it could not be read; `help` on a finding
/// only when the check says how to fix it.
pub fn json(report: &Report) -> String {
    let document = Document {
        version: JSON_VERSION,
        tool: Tool {
            name: "canopener",
            version: &report.tool_version,
        },
        files: report
            .files
            .iter()
            .map(|file| File {
                path: &file.path,
                problem: file.problem.as_deref(),
                findings: file
                    .findings
                    .iter()
                    .map(|f| Finding {
                        code: &f.diagnostic.code,
                        severity: f.diagnostic.severity,
                        message: &f.diagnostic.message,
                        line: f.diagnostic.span.line,
                        column: f.diagnostic.span.column,
                        length: f.diagnostic.span.len,
                        section: f.diagnostic.section.as_deref(),
                        key: f.diagnostic.key.as_deref(),
                        fixable: f.fixable,
                        help: f.diagnostic.help.as_deref(),
                    })
                    .collect(),
            })
            .collect(),
        summary: report.summary(),
    };
    // Serialising plain structs of strings, numbers and enums into a String cannot fail.
    let mut text = serde_json::to_string_pretty(&document).unwrap_or_default();
    text.push('\n');
    text
}

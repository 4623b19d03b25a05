//! Counting findings by severity and by code.

use std::collections::BTreeMap;

use canopener_eds::Severity;
use serde::Serialize;

use crate::Report;

/// The totals of a report.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct ReportTotals {
    /// Files in the report, including the ones that could not be read.
    pub files: usize,
    /// Files with at least one finding of severity error (unreadable files are counted in `problems`).
    pub files_with_errors: usize,
    /// Findings of severity error.
    pub errors: usize,
    /// Findings of severity warning.
    pub warnings: usize,
    /// Findings of severity info.
    pub infos: usize,
    /// Files that could not be read.
    pub problems: usize,
    /// One row per code that has findings: errors first, then by count (descending), then by code.
    pub by_code: Vec<CodeCount>,
}

/// The findings of one code.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct CodeCount {
    /// The code (`C301`, `P020`, a rule id).
    pub code: String,
    /// The most serious severity among its findings (a check may lower it case by case).
    pub severity: Severity,
    /// The check's title; empty when the check is not among the report's checks.
    pub title: String,
    /// Number of findings.
    pub count: usize,
    /// Number of files with at least one finding of this code.
    pub files: usize,
}

impl ReportTotals {
    /// The number of findings of a severity.
    pub fn count(&self, severity: Severity) -> usize {
        match severity {
            Severity::Error => self.errors,
            Severity::Warning => self.warnings,
            Severity::Info => self.infos,
        }
    }

    /// One line: "3 errors, 12 warnings, 1 info in 2 files (1 could not be read)".
    pub fn total_line(&self) -> String {
        let mut line = format!(
            "{}, {}, {} in {}",
            plural(self.errors, "error", "errors"),
            plural(self.warnings, "warning", "warnings"),
            plural(self.infos, "info", "infos"),
            plural(self.files, "file", "files"),
        );
        if self.problems > 0 {
            line.push_str(&format!(" ({} could not be read)", self.problems));
        }
        line
    }
}

fn plural(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

pub(crate) fn summarize(report: &Report) -> ReportTotals {
    let mut summary = ReportTotals {
        files: report.files.len(),
        ..ReportTotals::default()
    };
    // code -> (severity, count, files)
    let mut codes: BTreeMap<&str, (Severity, usize, usize)> = BTreeMap::new();
    for file in &report.files {
        if file.problem.is_some() {
            summary.problems += 1;
        }
        let mut has_error = false;
        let mut seen: Vec<&str> = Vec::new();
        for finding in &file.findings {
            match finding.diagnostic.severity {
                Severity::Error => {
                    summary.errors += 1;
                    has_error = true;
                }
                Severity::Warning => summary.warnings += 1,
                Severity::Info => summary.infos += 1,
            }
            let entry =
                codes
                    .entry(finding.diagnostic.code.as_str())
                    .or_insert((finding.diagnostic.severity, 0, 0));
            entry.0 = entry.0.max(finding.diagnostic.severity);
            entry.1 += 1;
            if !seen.contains(&finding.diagnostic.code.as_str()) {
                seen.push(&finding.diagnostic.code);
                entry.2 += 1;
            }
        }
        if has_error {
            summary.files_with_errors += 1;
        }
    }
    summary.by_code = codes
        .into_iter()
        .map(|(code, (severity, count, files))| CodeCount {
            code: code.to_owned(),
            severity,
            title: report.check(code).map(|c| c.title.clone()).unwrap_or_default(),
            count,
            files,
        })
        .collect();
    summary
        .by_code
        .sort_by(|a, b| (b.severity, b.count, &a.code).cmp(&(a.severity, a.count, &b.code)));
    summary
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn total_line_uses_singular_and_plural() {
        let summary = ReportTotals {
            files: 2,
            errors: 3,
            warnings: 12,
            infos: 1,
            problems: 1,
            ..ReportTotals::default()
        };
        assert_eq!(
            summary.total_line(),
            "3 errors, 12 warnings, 1 info in 2 files (1 could not be read)"
        );
        let one = ReportTotals {
            files: 1,
            errors: 1,
            warnings: 1,
            infos: 2,
            ..ReportTotals::default()
        };
        assert_eq!(one.total_line(), "1 error, 1 warning, 2 infos in 1 file");
    }
}

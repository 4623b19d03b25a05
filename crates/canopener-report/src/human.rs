//! Compiler-style text for a terminal, like rustc and ruff.

use std::fmt::Write as _;

use canopener_check::Finding;
use canopener_eds::Severity;

use crate::text::{snippet, terminal_safe};
use crate::{FileReport, Report};

/// How to print the human report.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct HumanOptions {
    /// Use ANSI colors.
    pub color: bool,
    /// End with a table of the findings per code (code, severity, count, files, title) and the
    /// one-line total.
    pub summary_table: bool,
}

const RESET: &str = "\x1b[0m";
const BOLD: &str = "\x1b[1m";
const BLUE: &str = "\x1b[1;34m";

fn severity_color(severity: Severity) -> &'static str {
    match severity {
        Severity::Error => "\x1b[1;31m",
        Severity::Warning => "\x1b[1;33m",
        Severity::Info => "\x1b[1;36m",
    }
}

/// Styles text when colors are on.
struct Paint {
    color: bool,
}

impl Paint {
    fn paint(&self, style: &str, text: &str) -> String {
        if self.color {
            format!("{style}{text}{RESET}")
        } else {
            text.to_owned()
        }
    }
}

/// The report as compiler-style diagnostics: for each finding `severity[CODE]: message`, then
/// ` --> path:line:column`, the source line under a line-number gutter with carets under the span and
/// `= help: …` when the check says how to fix it. A file that could not be read prints as
/// `error: path: message`. With [`HumanOptions::summary_table`] the report ends with a table per
/// code and the one-line total ("3 errors, 12 warnings, 1 info in 2 files (1 could not be read)").
///
/// Text from the files (source lines, values in messages) has its control characters replaced, so
/// a file cannot send escape sequences to the terminal.
pub fn human(report: &Report, options: &HumanOptions) -> String {
    let paint = Paint { color: options.color };
    let mut out = String::new();
    for file in &report.files {
        if let Some(problem) = &file.problem {
            let _ = writeln!(
                out,
                "{}: {}: {}",
                paint.paint(severity_color(Severity::Error), "error"),
                terminal_safe(&file.path),
                terminal_safe(problem)
            );
            out.push('\n');
        }
        for finding in &file.findings {
            write_finding(&mut out, &paint, file, finding);
            out.push('\n');
        }
    }
    if !options.summary_table {
        return out;
    }
    let summary = report.summary();
    if !summary.by_code.is_empty() {
        write_table(&mut out, &paint, &summary.by_code);
        out.push('\n');
    }
    let style = if summary.errors > 0 || summary.problems > 0 {
        severity_color(Severity::Error)
    } else if summary.warnings > 0 {
        severity_color(Severity::Warning)
    } else {
        BOLD
    };
    let _ = writeln!(out, "{}", paint.paint(style, &summary.total_line()));
    out
}

fn write_finding(out: &mut String, paint: &Paint, file: &FileReport, finding: &Finding) {
    let color = severity_color(finding.diagnostic.severity);
    let _ = writeln!(
        out,
        "{}{}",
        paint.paint(
            color,
            &format!(
                "{}[{}]",
                finding.diagnostic.severity,
                terminal_safe(&finding.diagnostic.code)
            )
        ),
        paint.paint(BOLD, &format!(": {}", terminal_safe(&finding.diagnostic.message)))
    );
    let span = finding.diagnostic.span;
    let number = span.line.to_string();
    let gutter = " ".repeat(number.len());
    let location = if span.line == 0 {
        terminal_safe(&file.path)
    } else {
        format!(
            "{}:{}:{}",
            terminal_safe(&file.path),
            span.line,
            span.column.max(1)
        )
    };
    let _ = writeln!(out, "{gutter}{} {location}", paint.paint(BLUE, "-->"));
    let source = if span.line == 0 {
        None
    } else {
        file.source.get(&span.line)
    };
    if let Some(line) = source {
        let snip = snippet(line, span.column, span.len);
        let pipe = paint.paint(BLUE, "|");
        let _ = writeln!(out, "{gutter} {pipe}");
        let _ = writeln!(
            out,
            "{} {pipe} {}",
            paint.paint(BLUE, &number),
            snip.line().trim_end()
        );
        let _ = writeln!(
            out,
            "{gutter} {pipe} {}{}",
            " ".repeat(snip.caret_offset),
            paint.paint(color, &"^".repeat(snip.caret_width))
        );
    }
    if let Some(help) = &finding.diagnostic.help {
        if source.is_some() {
            let _ = writeln!(out, "{gutter} {}", paint.paint(BLUE, "|"));
        }
        let _ = writeln!(
            out,
            "{gutter} {} {}: {}",
            paint.paint(BLUE, "="),
            paint.paint(BOLD, "help"),
            terminal_safe(help)
        );
    }
}

fn write_table(out: &mut String, paint: &Paint, rows: &[crate::CodeCount]) {
    let head = ["code", "severity", "count", "files", "title"];
    let cells: Vec<[String; 5]> = rows
        .iter()
        .map(|r| {
            [
                terminal_safe(&r.code),
                r.severity.to_string(),
                r.count.to_string(),
                r.files.to_string(),
                terminal_safe(&r.title),
            ]
        })
        .collect();
    let mut widths = head.map(|h| h.chars().count());
    for row in &cells {
        for (width, cell) in widths.iter_mut().zip(row) {
            *width = (*width).max(cell.chars().count());
        }
    }
    let [code_w, severity_w, count_w, files_w, _] = widths;
    let header = format!(
        "{:<code_w$}  {:<severity_w$}  {:>count_w$}  {:>files_w$}  {}",
        head[0], head[1], head[2], head[3], head[4]
    );
    let _ = writeln!(out, "{}", paint.paint(BOLD, &header));
    for (row, cells) in rows.iter().zip(&cells) {
        let [code, severity, count, files, title] = cells;
        // Pad before painting so escape codes do not count as width.
        let severity = paint.paint(severity_color(row.severity), &format!("{severity:<severity_w$}"));
        let line = format!("{code:<code_w$}  {severity}  {count:>count_w$}  {files:>files_w$}  {title}");
        let _ = writeln!(out, "{}", line.trim_end());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_eds::{Diagnostic, Span};

    fn finding(severity: Severity, line: u32, column: u32, len: u32, help: Option<&str>) -> Finding {
        Finding {
            diagnostic: Diagnostic {
                code: "C301".into(),
                severity,
                message: "VendorNumber 0x123 differs from 1018sub1 DefaultValue 0x124".into(),
                span: Span::new(line, column, len),
                section: Some("DeviceInfo".into()),
                key: Some("VendorNumber".into()),
                help: help.map(str::to_owned),
            },
            fixable: false,
        }
    }

    fn report(findings: Vec<Finding>, source: &[(u32, &str)]) -> Report {
        Report {
            tool_version: "0.1.0".into(),
            checks: Vec::new(),
            files: vec![FileReport {
                path: "dev.eds".into(),
                findings,
                source: source.iter().map(|(n, t)| (*n, (*t).to_owned())).collect(),
                problem: None,
            }],
        }
    }

    #[test]
    fn finding_with_source_and_help() {
        let r = report(
            vec![finding(Severity::Error, 12, 14, 5, Some("set it to 0x124"))],
            &[(12, "VendorNumber=0x123")],
        );
        let text = human(&r, &HumanOptions::default());
        let expected = "\
error[C301]: VendorNumber 0x123 differs from 1018sub1 DefaultValue 0x124
  --> dev.eds:12:14
   |
12 | VendorNumber=0x123
   |              ^^^^^
   |
   = help: set it to 0x124

";
        assert_eq!(text, expected);
    }

    #[test]
    fn point_span_gets_one_caret_and_missing_source_only_the_location() {
        let r = report(
            vec![
                finding(Severity::Warning, 3, 1, 0, None),
                finding(Severity::Info, 7, 2, 4, None),
            ],
            &[(3, "[1018]")],
        );
        let text = human(&r, &HumanOptions::default());
        assert!(text.contains("3 | [1018]\n  | ^\n"), "{text}");
        assert!(text.contains("info[C301]: VendorNumber"), "{text}");
        assert!(text.contains(" --> dev.eds:7:2\n\n"), "{text}");
    }

    #[test]
    fn colors_only_when_asked_and_file_text_cannot_inject_escapes() {
        let mut f = finding(Severity::Error, 1, 1, 3, None);
        f.diagnostic.message = "value \u{1b}[2J as written".into();
        let r = report(vec![f], &[(1, "A=\u{1b}]0;x\u{7}")]);
        let plain = human(&r, &HumanOptions::default());
        assert!(!plain.contains('\u{1b}'), "{plain:?}");
        let colored = human(
            &r,
            &HumanOptions {
                color: true,
                summary_table: true,
            },
        );
        assert!(
            colored.contains("\u{1b}[1;31merror[C301]\u{1b}[0m"),
            "{colored:?}"
        );
        assert!(!colored.contains("\u{1b}[2J"), "{colored:?}");
        assert!(!colored.contains("\u{1b}]0"), "{colored:?}");
    }

    #[test]
    fn problems_print_as_errors_and_count_in_the_total() {
        let r = Report {
            tool_version: "0.1.0".into(),
            checks: Vec::new(),
            files: vec![FileReport::unreadable(
                "missing.eds",
                "No such file or directory (os error 2)",
            )],
        };
        let options = HumanOptions {
            color: false,
            summary_table: true,
        };
        let text = human(&r, &options);
        assert_eq!(
            text,
            "error: missing.eds: No such file or directory (os error 2)\n\n\
             0 errors, 0 warnings, 0 infos in 1 file (1 could not be read)\n"
        );
    }
}

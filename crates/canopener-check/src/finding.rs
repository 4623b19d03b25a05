//! One thing the checker found in a file.

use canopener_eds::{Diagnostic, DiagnosticCode, Severity, Span};
use serde::Serialize;

use crate::check_info::CheckInfo;

/// A finding: the shared diagnostic shape (which check, how serious, what, where, how to fix it)
/// and whether `canopener eds fix` corrects it. The code is a string because findings mix series:
/// `P` loading codes, `C` and `T` checks, and the ids of user rules.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Finding {
    /// What was found: code (`C301`, `P020`, `T004`, or a rule-pack id), severity, message, span,
    /// section and key as written, and help.
    pub diagnostic: Diagnostic<String>,
    /// Whether `canopener eds fix` corrects it.
    pub fixable: bool,
}

impl Finding {
    /// A finding of a built-in check at `span`, with the check's severity.
    pub fn new(info: &CheckInfo, span: Span, message: impl Into<String>) -> Self {
        Self {
            diagnostic: Diagnostic::from_parts(info.code.to_owned(), info.severity, span, message),
            fixable: info.fixable,
        }
    }

    /// Names the section and key the finding is about (as written in the file).
    pub fn at(mut self, section: Option<&str>, key: Option<&str>) -> Self {
        self.diagnostic = self.diagnostic.at(section, key);
        self
    }

    /// Adds a help line.
    pub fn with_help(mut self, help: impl Into<String>) -> Self {
        self.diagnostic = self.diagnostic.with_help(help);
        self
    }

    /// Overrides the severity (a check whose severity depends on the case, e.g. pre-4.0 files).
    pub fn with_severity(mut self, severity: Severity) -> Self {
        self.diagnostic.severity = severity;
        self
    }

    /// Marks whether this particular finding can be fixed automatically.
    pub fn with_fixable(mut self, fixable: bool) -> Self {
        self.fixable = fixable;
        self
    }

    /// A finding from a reader's diagnostic (the loader's `P` series, or any other series).
    pub fn from_diagnostic<C: DiagnosticCode>(diagnostic: &Diagnostic<C>, fixable: bool) -> Self {
        Self {
            diagnostic: diagnostic.clone().into_string_code(),
            fixable,
        }
    }
}

/// Sorts findings by line, column and code, keeping the order of equal ones: the order every report
/// shows them in.
pub fn sort_by_position(findings: &mut [Finding]) {
    findings.sort_by(|a, b| {
        let (a, b) = (&a.diagnostic, &b.diagnostic);
        (a.span.line, a.span.column, &a.code).cmp(&(b.span.line, b.span.column, &b.code))
    });
}

//! One thing the checker found in a file.

use canopener_eds::{Diagnostic, Severity, Span};
use serde::Serialize;

use crate::check_info::CheckInfo;

/// A finding: which check, how serious, what and where.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Finding {
    /// The stable code of the check (`C301`, `P020`, `T004`, or a rule-pack id).
    pub code: String,
    /// How serious it is.
    pub severity: Severity,
    /// What is wrong, naming the values as written.
    pub message: String,
    /// Where it is (1-based line and column).
    pub span: Span,
    /// The section name as written (e.g. `1018sub1`), if the finding is inside one.
    pub section: Option<String>,
    /// The key as written, if the finding is about an entry.
    pub key: Option<String>,
    /// How to fix it, when there is something to say.
    pub help: Option<String>,
    /// Whether `canopener eds fix` corrects it.
    pub fixable: bool,
}

impl Finding {
    /// A finding of a built-in check at `span`, with the check's severity.
    pub fn new(info: &CheckInfo, span: Span, message: impl Into<String>) -> Self {
        Self {
            code: info.code.to_owned(),
            severity: info.severity,
            message: message.into(),
            span,
            section: None,
            key: None,
            help: None,
            fixable: info.fixable,
        }
    }

    /// Names the section and key the finding is about (as written in the file).
    pub fn at(mut self, section: Option<&str>, key: Option<&str>) -> Self {
        self.section = section.map(str::to_owned);
        self.key = key.map(str::to_owned);
        self
    }

    /// Adds a help line.
    pub fn with_help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(help.into());
        self
    }

    /// Overrides the severity (a check whose severity depends on the case, e.g. pre-4.0 files).
    pub fn with_severity(mut self, severity: Severity) -> Self {
        self.severity = severity;
        self
    }

    /// Marks whether this particular finding can be fixed automatically.
    pub fn with_fixable(mut self, fixable: bool) -> Self {
        self.fixable = fixable;
        self
    }

    /// A finding from a loading diagnostic (the `P` series).
    pub fn from_diagnostic(diagnostic: &Diagnostic, fixable: bool) -> Self {
        Self {
            code: diagnostic.code.as_str().to_owned(),
            severity: diagnostic.severity,
            message: diagnostic.message.clone(),
            span: diagnostic.span,
            section: diagnostic.section.clone(),
            key: diagnostic.key.clone(),
            help: diagnostic.help.clone(),
            fixable,
        }
    }
}

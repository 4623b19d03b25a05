//! What can be wrong with a rule pack, and where.

use std::fmt;
use std::ops::Range;

use canopener_eds::{Diagnostic, Severity, Span};

/// What kind of problem a [`PackError`] reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PackErrorKind {
    /// The file is not valid TOML, or a key or value does not fit the pack format.
    Toml,
    /// A rule id is missing its namespace or uses characters ids cannot have.
    InvalidId,
    /// Two rules share an id.
    DuplicateId,
    /// `severity` is not `error`, `warning` or `info`.
    Severity,
    /// `select` names no selection.
    Select,
    /// A parameter's type is unknown or its value does not have that type.
    Parameter,
    /// A CEL expression does not parse.
    CelSyntax,
    /// A CEL expression names a variable, field or function that does not exist.
    UnknownName,
    /// A `{...}` message template is not closed, or a brace is unbalanced.
    Template,
    /// A structured `assert` table is malformed.
    Assertion,
    /// A fix or finding location is inconsistent with the rule's selection.
    Fix,
}

/// A rule pack that cannot be used: the pack, the rule, and a diagnostic in the shared shape saying
/// what kind of problem it is, where in the pack (1-based line and column, in characters), what is
/// wrong and how to fix it. Its severity is always `error`: a pack with a problem is not used.
///
/// Displayed as `origin:line:column: rule `id`: what is wrong` and a `help:` line.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}", self.render())]
pub struct PackError {
    /// The pack's path (or another name the caller gave it).
    pub origin: String,
    /// The id of the rule the problem is in, when it is in one.
    pub rule: Option<String>,
    /// What kind of problem it is (the code), where, what is wrong and how to fix it (boxed: errors
    /// travel through many `Result`s while a pack is parsed).
    pub diagnostic: Box<Diagnostic<PackErrorKind>>,
}

impl PackError {
    fn render(&self) -> String {
        let d = &self.diagnostic;
        let mut out = format!("{}:{}:{}: ", self.origin, d.span.line, d.span.column);
        if let Some(rule) = &self.rule {
            out.push_str(&format!("rule `{rule}`: "));
        }
        out.push_str(&d.message);
        if let Some(help) = &d.help {
            out.push_str(&format!("\n  help: {help}"));
        }
        out
    }
}

/// Builds [`PackError`]s for one pack text, turning byte offsets into line and column.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Locator<'a> {
    pub(crate) text: &'a str,
    pub(crate) origin: &'a str,
}

impl Locator<'_> {
    /// The 1-based line and column (in characters) of a byte offset; offsets past the end or inside a
    /// character are clamped back to the nearest boundary.
    pub(crate) fn line_column(&self, offset: usize) -> (usize, usize) {
        let mut offset = offset.min(self.text.len());
        while !self.text.is_char_boundary(offset) {
            offset -= 1;
        }
        // `offset` is now at most the length and on a character boundary, and `line_start` follows a
        // `\n` inside `before`: both slices are in bounds.
        let before = &self.text[..offset];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let column = before[line_start..].chars().count() + 1;
        (line, column)
    }

    pub(crate) fn error(
        &self,
        at: usize,
        rule: Option<&str>,
        kind: PackErrorKind,
        message: impl fmt::Display,
        help: impl fmt::Display,
    ) -> PackError {
        let (line, column) = self.line_column(at);
        let to_u32 = |n: usize| u32::try_from(n).unwrap_or(u32::MAX);
        let mut diagnostic = Diagnostic::from_parts(
            kind,
            Severity::Error,
            Span::new(to_u32(line), to_u32(column), 0),
            message.to_string(),
        );
        let help = help.to_string();
        if !help.is_empty() {
            diagnostic = diagnostic.with_help(help);
        }
        PackError {
            origin: self.origin.to_owned(),
            rule: rule.map(str::to_owned),
            diagnostic: Box::new(diagnostic),
        }
    }

    /// The byte offset of `inner` as a TOML string inside `span`: where its first character is in
    /// the pack, when the string is written without escapes; otherwise the start of `span`.
    pub(crate) fn string_start(&self, span: &Range<usize>, inner: &str) -> usize {
        self.locate(span, inner).unwrap_or(span.start)
    }

    /// Where the first character of `inner`, written as a TOML string without escapes, is inside
    /// `span`; `None` when it is not written that way.
    pub(crate) fn locate(&self, span: &Range<usize>, inner: &str) -> Option<usize> {
        self.locate_in(span.start, self.text.get(span.clone())?, inner)
    }

    /// Like [`Locator::locate`], for a string inside a table whose span may cover only its header
    /// (`[rule.assert]`): the first place after the span's start where it is written.
    pub(crate) fn locate_after(&self, start: usize, inner: &str) -> Option<usize> {
        self.locate_in(start, self.text.get(start..)?, inner)
    }

    fn locate_in(&self, start: usize, raw: &str, inner: &str) -> Option<usize> {
        let span = start..start + raw.len();
        for quote in ["\"\"\"", "'''", "\"", "'"] {
            let written = format!("{quote}{inner}{quote}");
            if let Some(at) = raw.find(&written) {
                return Some(span.start + at + quote.len());
            }
            // A multi-line string drops a newline right after the opening quotes.
            if quote.len() == 3 {
                for newline in ["\n", "\r\n"] {
                    let written = format!("{quote}{newline}{inner}{quote}");
                    if let Some(at) = raw.find(&written) {
                        return Some(span.start + at + quote.len() + newline.len());
                    }
                }
            }
        }
        None
    }

    /// The byte offset of the 1-based (line, column) position `pos` of an expression that starts at
    /// byte `start` of the pack (columns counted in characters).
    pub(crate) fn offset_in(&self, start: usize, expression: &str, pos: (isize, isize)) -> usize {
        let line = usize::try_from(pos.0).unwrap_or(1).max(1);
        let column = usize::try_from(pos.1).unwrap_or(1).max(1);
        let mut offset = 0usize;
        for (i, text) in expression.split_inclusive('\n').enumerate() {
            if i + 1 == line {
                let within: usize = text.chars().take(column - 1).map(char::len_utf8).sum();
                return start + offset + within;
            }
            offset += text.len();
        }
        start + expression.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_and_column_count_characters() {
        let at = Locator {
            text: "a = 1\nbé = 'x'\n",
            origin: "p.toml",
        };
        assert_eq!(at.line_column(0), (1, 1));
        assert_eq!(at.line_column(6), (2, 1));
        // `=` after `bé ` is the 4th character but the 5th byte of the line.
        assert_eq!(at.line_column(10), (2, 4));
        assert_eq!(at.line_column(999), (3, 1));
    }

    #[test]
    fn the_display_names_origin_rule_and_help() {
        let at = Locator {
            text: "x\ny = 2",
            origin: "pack.toml",
        };
        let e = at.error(
            4,
            Some("a/b"),
            PackErrorKind::Select,
            "unknown select `obj`",
            "use objects",
        );
        assert_eq!(
            e.to_string(),
            "pack.toml:2:3: rule `a/b`: unknown select `obj`\n  help: use objects"
        );
    }

    #[test]
    fn strings_are_located_inside_their_quotes() {
        let text = "assert = \"item.a\"\nwhere = '''\nitem.b'''";
        let at = Locator { text, origin: "p" };
        assert_eq!(at.string_start(&(9..17), "item.a"), 10);
        let start = at.string_start(&(26..text.len()), "item.b");
        assert_eq!(&text[start..start + 6], "item.b");
        // Escaped text cannot be found: the span start stands in.
        assert_eq!(at.string_start(&(9..17), "item\\.a"), 9);
        assert_eq!(at.offset_in(10, "a\nbc", (2, 2)), 13);
        assert_eq!(at.offset_in(10, "abc", (1, 3)), 12);
    }
}

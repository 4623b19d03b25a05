//! The lossless syntax layer: every byte of an EDS/DCF file, classified into lines and sections.
//!
//! A [`Document`] keeps the decoded text untouched and records, per line, its kind, its byte ranges
//! and its line ending. Writing an unedited document gives back the input bytes exactly, whatever they
//! contain: comments, blank lines, key spelling and case, duplicate sections and keys, trailing white
//! space, mixed line endings, a missing final newline or a byte order mark. [`Editor`] changes single
//! lines and leaves every other byte alone, which is what fixes and the lossless writer build on.
//!
//! Lexical rules follow CiA 306 §4.2 (sections `[name]` with `[` in column 1, entries `key=value`,
//! comments with `;` in column 1); deviations are accepted and reported.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::ops::Range;
use std::sync::OnceLock;

use crate::diag::{Code, Diagnostic, Span};
use crate::lines::{ending_at, line_end};
use crate::text::{self, Encoding, Unencodable};

pub use crate::lines::LineEnding;

/// What a line is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LineKind {
    /// Empty or white space only.
    Blank,
    /// A comment (`;` in column 1, or tolerated variants).
    Comment,
    /// A section header; `name` is the trimmed byte range of the name inside the brackets.
    Header {
        /// Byte range of the section name in the document text.
        name: Range<usize>,
    },
    /// `key=value`; both ranges are trimmed of surrounding white space.
    Entry {
        /// Byte range of the key.
        key: Range<usize>,
        /// Byte range of the value (empty range right after `=` when the value is empty).
        value: Range<usize>,
    },
    /// Anything else; kept verbatim and reported.
    Invalid,
}

/// One line of the document.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Line {
    /// Byte offset of the first character.
    pub start: usize,
    /// Byte offset just past the content (before the line ending).
    pub end: usize,
    /// The line ending that follows the content.
    pub ending: LineEnding,
    /// The classification.
    pub kind: LineKind,
}

/// A section: its header line and the lines up to the next header.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Section {
    /// Index of the header line.
    pub header_line: usize,
    /// Byte range of the name as written.
    pub name: Range<usize>,
    /// Indices of the lines after the header up to (not including) the next header.
    pub body: Range<usize>,
    /// The entry lines of the body, as a range of [`Document::entry_lines`] (use [`Document::entries`]).
    pub entries: Range<usize>,
}

/// A parsed EDS/DCF file that can be written back byte for byte.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Document {
    text: String,
    encoding: Encoding,
    lines: Vec<Line>,
    sections: Vec<Section>,
    /// Indices of every entry line inside a section, in order; sections own ranges of it.
    entry_lines: Vec<usize>,
    /// Section indices by lower-cased name, built on the first lookup (most loads never need it).
    by_name: OnceLock<HashMap<String, Vec<usize>>>,
}

impl Document {
    /// Parses file bytes. Never fails: what cannot be understood is kept and reported.
    pub fn parse(bytes: &[u8]) -> (Document, Vec<Diagnostic>) {
        let (text, encoding) = text::decode(bytes);
        let mut diagnostics = Vec::new();
        match encoding {
            Encoding::Windows1252 => diagnostics.push(
                Diagnostic::new(
                    Code::Windows1252,
                    first_non_utf8(bytes),
                    "file is not valid UTF-8; decoded as Windows-1252 (ISO 8859-1)",
                )
                .with_help(
                    "CiA 306 §4.2 allows only ASCII; replace the non-ASCII characters or save as UTF-8",
                ),
            ),
            Encoding::Utf8Bom => diagnostics.push(
                Diagnostic::new(
                    Code::ByteOrderMark,
                    Span::new(1, 1, 1),
                    "file starts with a UTF-8 byte order mark",
                )
                .with_help("python canopen and lely fail on the BOM; save the file without it"),
            ),
            Encoding::Utf8 => {}
        }
        let document = Self::from_text(text, encoding, &mut diagnostics);
        (document, diagnostics)
    }

    /// Parses already decoded text that will be written back in `encoding`.
    pub fn from_text(text: String, encoding: Encoding, diagnostics: &mut Vec<Diagnostic>) -> Document {
        let lines = split_lines(&text, diagnostics);
        let mut document = Document {
            text,
            encoding,
            lines,
            sections: Vec::new(),
            entry_lines: Vec::new(),
            by_name: OnceLock::new(),
        };
        document.index_sections(diagnostics);
        document
    }

    /// The decoded text (without a byte order mark).
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The encoding the bytes were decoded from, used again when writing.
    pub fn encoding(&self) -> Encoding {
        self.encoding
    }

    /// Every line, in order.
    pub fn lines(&self) -> &[Line] {
        &self.lines
    }

    /// Every section, in file order (duplicates included).
    pub fn sections(&self) -> &[Section] {
        &self.sections
    }

    /// Indices (into [`Document::sections`]) of the sections with this name, compared case-insensitively.
    pub fn sections_named(&self, name: &str) -> &[usize] {
        let by_name = self.by_name.get_or_init(|| {
            let mut map: HashMap<String, Vec<usize>> = HashMap::new();
            for (i, section) in self.sections.iter().enumerate() {
                map.entry(self.slice(&section.name).to_ascii_lowercase())
                    .or_default()
                    .push(i);
            }
            map
        });
        by_name.get(&name.to_ascii_lowercase()).map_or(&[], Vec::as_slice)
    }

    /// The first section with this name (case-insensitive).
    pub fn section(&self, name: &str) -> Option<&Section> {
        self.sections_named(name)
            .first()
            .and_then(|&i| self.sections.get(i))
    }

    /// The section name as written.
    pub fn section_name(&self, section: &Section) -> &str {
        self.slice(&section.name)
    }

    /// The key and value of an entry line, as written (trimmed).
    pub fn entry(&self, line: usize) -> Option<(&str, &str)> {
        match &self.lines.get(line)?.kind {
            LineKind::Entry { key, value } => Some((self.slice(key), self.slice(value))),
            _ => None,
        }
    }

    /// The line indices of a section's entries, in order.
    pub fn entries(&self, section: &Section) -> &[usize] {
        self.entry_lines.get(section.entries.clone()).unwrap_or(&[])
    }

    /// Every entry line inside a section, in file order.
    pub fn entry_lines(&self) -> &[usize] {
        &self.entry_lines
    }

    /// The line index of the first entry with this key (case-insensitive) in a section.
    pub fn find_entry(&self, section: &Section, key: &str) -> Option<usize> {
        self.entries(section)
            .iter()
            .copied()
            .find(|&l| self.entry(l).is_some_and(|(k, _)| k.eq_ignore_ascii_case(key)))
    }

    /// The content of a line without its ending.
    pub fn line_text(&self, line: usize) -> &str {
        self.lines.get(line).map_or("", |l| self.slice(&(l.start..l.end)))
    }

    /// The span of a byte range inside the document, for diagnostics.
    pub fn span_of(&self, range: &Range<usize>) -> Span {
        let line_index = self
            .lines
            .partition_point(|l| l.end + l.ending.as_str().len() <= range.start);
        let Some(line) = self.lines.get(line_index) else {
            return Span::new(u32_of(self.lines.len().max(1)), 1, 0);
        };
        let column = char_count(&self.text, line.start..range.start.max(line.start)) + 1;
        let len = char_count(&self.text, range.start..range.end.min(line.end).max(range.start));
        Span::new(u32_of(line_index + 1), u32_of(column), u32_of(len))
    }

    /// The span of a whole line (1-based line number of `line`).
    pub fn line_span(&self, line: usize) -> Span {
        self.lines
            .get(line)
            .map_or(Span::new(u32_of(line + 1), 1, 0), |l| {
                Span::new(
                    u32_of(line + 1),
                    1,
                    u32_of(char_count(&self.text, l.start..l.end)),
                )
            })
    }

    /// The span of the key of an entry line.
    pub fn key_span(&self, line: usize) -> Span {
        match self.lines.get(line).map(|l| &l.kind) {
            Some(LineKind::Entry { key, .. }) => self.span_of(key),
            _ => self.line_span(line),
        }
    }

    /// The span of the value of an entry line.
    pub fn value_span(&self, line: usize) -> Span {
        match self.lines.get(line).map(|l| &l.kind) {
            Some(LineKind::Entry { value, .. }) => self.span_of(value),
            _ => self.line_span(line),
        }
    }

    /// The file bytes: identical to the input when nothing was edited.
    pub fn to_bytes(&self) -> Result<Vec<u8>, Unencodable> {
        text::encode(&self.text, self.encoding)
    }

    /// The line ending most lines use (LF for a file without line breaks), for inserted lines.
    pub fn dominant_ending(&self) -> LineEnding {
        let crlf = self.lines.iter().filter(|l| l.ending == LineEnding::CrLf).count();
        let lf = self.lines.iter().filter(|l| l.ending == LineEnding::Lf).count();
        if crlf > lf {
            LineEnding::CrLf
        } else {
            LineEnding::Lf
        }
    }

    /// Starts a set of line edits.
    pub fn editor(&self) -> Editor<'_> {
        Editor {
            document: self,
            replaced: HashMap::new(),
            deleted: HashSet::new(),
            inserted_after: BTreeMap::new(),
            appended: Vec::new(),
        }
    }

    fn slice(&self, range: &Range<usize>) -> &str {
        self.text.get(range.clone()).unwrap_or("")
    }

    fn index_sections(&mut self, diagnostics: &mut Vec<Diagnostic>) {
        let mut current: Option<Section> = None;
        for (i, line) in self.lines.iter().enumerate() {
            match &line.kind {
                LineKind::Header { name } => {
                    if let Some(mut done) = current.take() {
                        done.body.end = i;
                        done.entries.end = self.entry_lines.len();
                        self.sections.push(done);
                    }
                    let first_entry = self.entry_lines.len();
                    current = Some(Section {
                        header_line: i,
                        name: name.clone(),
                        body: i + 1..i + 1,
                        entries: first_entry..first_entry,
                    });
                }
                LineKind::Entry { key, .. } => match current.as_mut() {
                    Some(_) => self.entry_lines.push(i),
                    None => diagnostics.push(
                        Diagnostic::new(
                            Code::EntryOutsideSection,
                            self.line_span(i),
                            format!(
                                "entry `{}` comes before the first section header",
                                self.slice(key)
                            ),
                        )
                        .with_help("move the entry into the section it belongs to"),
                    ),
                },
                _ => {}
            }
        }
        if let Some(mut done) = current.take() {
            done.body.end = self.lines.len();
            done.entries.end = self.entry_lines.len();
            self.sections.push(done);
        }
    }
}

/// A batch of line edits on a [`Document`]; untouched lines keep every byte.
#[derive(Debug)]
pub struct Editor<'a> {
    document: &'a Document,
    replaced: HashMap<usize, String>,
    deleted: HashSet<usize>,
    inserted_after: BTreeMap<usize, Vec<String>>,
    appended: Vec<String>,
}

impl Editor<'_> {
    /// Replaces the value of an entry line, keeping the key spelling and the spacing around it.
    pub fn set_value(&mut self, line: usize, value: &str) -> &mut Self {
        let doc = self.document;
        if let Some(Line {
            start,
            end,
            kind: LineKind::Entry { value: range, .. },
            ..
        }) = doc.lines.get(line)
        {
            let content = format!(
                "{}{}{}",
                doc.slice(&(*start..range.start)),
                value,
                doc.slice(&(range.end..*end))
            );
            self.replaced.insert(line, content);
        }
        self
    }

    /// Replaces the whole content of a line (its ending is kept).
    pub fn replace_line(&mut self, line: usize, content: &str) -> &mut Self {
        self.replaced.insert(line, content.to_owned());
        self
    }

    /// Deletes a line together with its ending.
    pub fn delete_line(&mut self, line: usize) -> &mut Self {
        self.deleted.insert(line);
        self
    }

    /// Inserts lines (without endings) after `line`.
    pub fn insert_after(&mut self, line: usize, contents: impl IntoIterator<Item = String>) -> &mut Self {
        self.inserted_after.entry(line).or_default().extend(contents);
        self
    }

    /// Inserts lines at the end of a section's entries (after its last non-blank line).
    pub fn append_to_section(
        &mut self,
        section: &Section,
        contents: impl IntoIterator<Item = String>,
    ) -> &mut Self {
        let doc = self.document;
        let last = section
            .body
            .clone()
            .rev()
            .find(|&l| doc.lines.get(l).is_some_and(|line| line.kind != LineKind::Blank))
            .unwrap_or(section.header_line);
        self.insert_after(last, contents)
    }

    /// Appends lines at the end of the file.
    pub fn append(&mut self, contents: impl IntoIterator<Item = String>) -> &mut Self {
        self.appended.extend(contents);
        self
    }

    /// Applies the edits and parses the result.
    pub fn apply(&self) -> Document {
        let doc = self.document;
        let ending = doc.dominant_ending().as_str();
        let mut out = String::with_capacity(doc.text.len() + 64);
        let last_index = doc.lines.len().checked_sub(1);
        for (i, line) in doc.lines.iter().enumerate() {
            if !self.deleted.contains(&i) {
                match self.replaced.get(&i) {
                    Some(content) => out.push_str(content),
                    None => out.push_str(doc.slice(&(line.start..line.end))),
                }
                out.push_str(line.ending.as_str());
            }
            if let Some(new_lines) = self.inserted_after.get(&i) {
                ensure_line_break(&mut out, ending);
                for content in new_lines {
                    out.push_str(content);
                    out.push_str(ending);
                }
                if Some(i) == last_index && line.ending == LineEnding::None {
                    // The original file had no final newline; keep it that way.
                    strip_suffix_in_place(&mut out, ending);
                }
            }
        }
        if !self.appended.is_empty() {
            let had_final_newline = doc.lines.last().is_none_or(|l| l.ending != LineEnding::None);
            ensure_line_break(&mut out, ending);
            for content in &self.appended {
                out.push_str(content);
                out.push_str(ending);
            }
            if !had_final_newline {
                strip_suffix_in_place(&mut out, ending);
            }
        }
        Document::from_text(out, doc.encoding, &mut Vec::new())
    }
}

fn ensure_line_break(out: &mut String, ending: &str) {
    if !out.is_empty() && !out.ends_with('\n') && !out.ends_with('\r') {
        out.push_str(ending);
    }
}

fn strip_suffix_in_place(out: &mut String, suffix: &str) {
    if out.ends_with(suffix) {
        out.truncate(out.len() - suffix.len());
    }
}

fn split_lines(text: &str, diagnostics: &mut Vec<Diagnostic>) -> Vec<Line> {
    let bytes = text.as_bytes();
    // One vectorised pass for the exact line count is cheaper than regrowing a vector of 400k lines
    // (byte-sized counters over chunks that cannot overflow them vectorise well).
    let newlines: usize = bytes
        .chunks(255)
        .map(|chunk| usize::from(chunk.iter().fold(0u8, |n, &b| n + u8::from(b == b'\n'))))
        .sum();
    let mut out: Vec<Line> = Vec::with_capacity(newlines + 1);
    let (mut saw_lf, mut saw_crlf, mut reported_cr) = (false, false, false);
    let mut start = 0;
    while start < bytes.len() {
        // Fast path for the `Key=value` line that makes up most of a file: a run of key characters
        // from column 1 followed directly by `=` is exactly the entry `classify` accepts without a
        // diagnostic, so the line is scanned once and its key needs no trimming.
        let key_len = bytes
            .get(start..)
            .unwrap_or_default()
            .iter()
            .position(|&b| !is_key_byte(b))
            .unwrap_or(bytes.len() - start);
        let eq = (key_len > 0 && bytes.get(start + key_len) == Some(&b'=')).then_some(start + key_len);
        // Key characters are never line breaks, so the search for the line end resumes after them.
        let end = line_end(bytes, eq.map_or(start + key_len, |eq| eq + 1));
        let (ending, next) = ending_at(bytes, end);
        let number = out.len();
        saw_lf |= ending == LineEnding::Lf;
        saw_crlf |= ending == LineEnding::CrLf;
        if ending == LineEnding::Cr && !reported_cr {
            reported_cr = true;
            diagnostics.push(
                Diagnostic::new(
                    Code::BareCarriageReturn,
                    Span::new(u32_of(number + 1), 1, 0),
                    "line ends with a bare CR",
                )
                .with_help("CiA 306 §4.2 allows LF or CR/LF line endings"),
            );
        }
        let kind = match eq {
            Some(eq) => LineKind::Entry {
                key: start..eq,
                value: entry_value(text, eq, end),
            },
            None => classify(text, start, end, number, diagnostics),
        };
        out.push(Line {
            start,
            end,
            ending,
            kind,
        });
        start = next;
    }
    if saw_lf && saw_crlf {
        let first = out
            .iter()
            .position(|l| out.first().is_some_and(|f| l.ending != f.ending))
            .unwrap_or(0);
        diagnostics.push(Diagnostic::new(
            Code::MixedLineEndings,
            Span::new(u32_of(first + 1), 1, 0),
            "the file mixes LF and CR/LF line endings",
        ));
    }
    out
}

/// Whether a byte may appear in a key without an [`Code::UnusualKey`] finding (letters, digits, `_`).
#[allow(clippy::indexing_slicing, reason = "a u8 indexes a table of 256 entries")]
fn is_key_byte(b: u8) -> bool {
    // A table lookup: the three range tests of `is_ascii_alphanumeric` cost more per key byte.
    const TABLE: [bool; 256] = {
        let mut table = [false; 256];
        let mut b = 0;
        while b < 256 {
            let c = b as u8;
            table[b] = c.is_ascii_alphanumeric() || c == b'_';
            b += 1;
        }
        table
    };
    TABLE[usize::from(b)]
}

/// The trimmed value range of an entry whose `=` is at `eq` (an empty range right after `=` when the
/// value is empty), as [`LineKind::Entry`] records it.
fn entry_value(text: &str, eq: usize, end: usize) -> Range<usize> {
    let value = trim_range(text, eq + 1..end);
    if value.is_empty() { eq + 1..eq + 1 } else { value }
}

fn classify(
    text: &str,
    start: usize,
    end: usize,
    number: usize,
    diagnostics: &mut Vec<Diagnostic>,
) -> LineKind {
    let content = &text[start..end];
    let trimmed = content.trim_ascii_start();
    let indent = content.len() - trimmed.len();
    let line_span =
        |column: usize, len: usize| Span::new(u32_of(number + 1), u32_of(column + 1), u32_of(len));
    let Some(&first) = trimmed.as_bytes().first() else {
        return LineKind::Blank;
    };
    if first == b';' || first == b'#' {
        if first == b'#' || indent > 0 {
            diagnostics.push(
                Diagnostic::new(
                    Code::NonStandardComment,
                    line_span(indent, 1),
                    format!("comment starts with `{}` in column {}", char::from(first), indent + 1),
                )
                .with_help("CiA 306 comments start with `;` in column 1; lely and configparser may read other lines as data"),
            );
        }
        return LineKind::Comment;
    }
    if first == b'[' {
        if indent > 0 {
            diagnostics.push(Diagnostic::new(
                Code::Indented,
                line_span(indent, 1),
                "section header does not start in column 1",
            ));
        }
        let inner_start = start + indent + 1;
        let (name_end, trailing) = match text[inner_start..end].find(']') {
            Some(close) => (inner_start + close, text[inner_start + close + 1..end].trim()),
            None => {
                diagnostics.push(
                    Diagnostic::new(
                        Code::MalformedSectionHeader,
                        line_span(indent, trimmed.chars().count()),
                        format!("section header `{}` has no closing `]`", trimmed.trim_end()),
                    )
                    .with_help("write the header as `[name]`"),
                );
                (end, "")
            }
        };
        if !trailing.is_empty() {
            diagnostics.push(
                Diagnostic::new(
                    Code::MalformedSectionHeader,
                    line_span(indent, trimmed.chars().count()),
                    format!("text `{trailing}` after the section header"),
                )
                .with_help("CiA 306 has no inline comments; put the text on its own `;` comment line"),
            );
        }
        return LineKind::Header {
            name: trim_range(text, inner_start..name_end),
        };
    }
    let Some(eq) = content.find('=') else {
        diagnostics.push(
            Diagnostic::new(
                Code::NotAnEntry,
                line_span(indent, trimmed.trim_end().chars().count()),
                format!(
                    "line `{}` is neither a section header, a comment nor `key=value`",
                    trimmed.trim_end()
                ),
            )
            .with_help("comment it out with `;` in column 1, or add the missing `=`"),
        );
        return LineKind::Invalid;
    };
    let key = trim_range(text, start..start + eq);
    let key_text = &text[key.clone()];
    if indent > 0 {
        diagnostics.push(Diagnostic::new(
            Code::Indented,
            line_span(indent, key_text.len()),
            "key does not start in column 1",
        ));
    }
    if key.end < start + eq {
        diagnostics.push(
            Diagnostic::new(
                Code::SpaceBeforeEquals,
                line_span(key.end - start, start + eq - key.end),
                format!("white space between key `{key_text}` and `=`"),
            )
            .with_help("CiA 306 §4.2: the key is immediately followed by `=`"),
        );
    }
    if key_text.is_empty() || !key_text.bytes().all(is_key_byte) {
        diagnostics.push(Diagnostic::new(
            Code::UnusualKey,
            line_span(indent, key_text.chars().count().max(1)),
            format!("key `{key_text}` is not made of letters, digits and `_`"),
        ));
    }
    LineKind::Entry {
        key,
        value: entry_value(text, start + eq, end),
    }
}

/// Trims ASCII white space (CiA 306 files are ASCII; Unicode-aware trimming costs a char decode per byte).
fn trim_range(text: &str, range: Range<usize>) -> Range<usize> {
    let bytes = text.as_bytes().get(range.clone()).unwrap_or_default();
    let leading = bytes.len() - bytes.trim_ascii_start().len();
    let trimmed_len = bytes.trim_ascii().len();
    range.start + leading..range.start + leading + trimmed_len
}

fn char_count(text: &str, range: Range<usize>) -> usize {
    text.get(range).map_or(0, |s| s.chars().count())
}

fn u32_of(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}

fn first_non_utf8(bytes: &[u8]) -> Span {
    let valid = match std::str::from_utf8(bytes) {
        Ok(_) => bytes.len(),
        Err(e) => e.valid_up_to(),
    };
    let prefix = bytes.get(..valid).unwrap_or(bytes);
    let line = prefix.iter().filter(|&&b| b == b'\n').count() + 1;
    let line_start = prefix.iter().rposition(|&b| b == b'\n').map_or(0, |p| p + 1);
    let column = String::from_utf8_lossy(prefix.get(line_start..).unwrap_or_default())
        .chars()
        .count()
        + 1;
    Span::new(u32_of(line), u32_of(column), 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn parse(text: &str) -> (Document, Vec<Diagnostic>) {
        Document::parse(text.as_bytes())
    }

    #[test]
    fn classifies_lines_and_sections() {
        let (doc, diags) =
            parse("; head\n[FileInfo]\nFileName=a.eds\n\n[1018sub1]\r\nParameterName = Vendor\r\n");
        assert_eq!(doc.sections().len(), 2);
        assert_eq!(doc.section_name(&doc.sections()[1]), "1018sub1");
        let fi = doc.section("fileinfo").unwrap();
        let line = doc.find_entry(fi, "FILENAME").unwrap();
        assert_eq!(doc.entry(line), Some(("FileName", "a.eds")));
        assert_eq!(doc.lines()[0].kind, LineKind::Comment);
        let codes: Vec<Code> = diags.iter().map(|d| d.code).collect();
        assert_eq!(codes, [Code::SpaceBeforeEquals, Code::MixedLineEndings]);
        assert_eq!(diags[0].span, Span::new(6, 14, 1));
    }

    #[test]
    fn malformed_lines_are_kept_and_reported() {
        let input = "[2000\nnonsense\n[3000] trailing\nk=v\n";
        let (doc, diags) = parse(input);
        assert_eq!(doc.to_bytes().unwrap(), input.as_bytes());
        let codes: Vec<Code> = diags.iter().map(|d| d.code).collect();
        assert_eq!(
            codes,
            [
                Code::MalformedSectionHeader,
                Code::NotAnEntry,
                Code::MalformedSectionHeader
            ]
        );
        assert_eq!(diags[1].span.line, 2);
        assert_eq!(doc.sections().len(), 2);
    }

    #[test]
    fn empty_file_and_no_final_newline() {
        let (doc, diags) = parse("");
        assert!(doc.lines().is_empty() && diags.is_empty());
        let (doc, _) = parse("[a]\nk=v");
        assert_eq!(doc.lines()[1].ending, LineEnding::None);
        assert_eq!(doc.to_bytes().unwrap(), b"[a]\nk=v");
    }

    #[test]
    fn duplicate_sections_are_all_indexed() {
        let (doc, _) = parse("[A]\nx=1\n[a]\nx=2\n");
        assert_eq!(doc.sections_named("A"), &[0, 1]);
    }

    #[test]
    fn editor_changes_only_the_edited_lines() {
        let input = "[1017]\r\nDefaultValue = 100   \r\n; keep me\r\nAccessType=rw";
        let (doc, _) = parse(input);
        let section = doc.section("1017").unwrap().clone();
        let line = doc.find_entry(&section, "defaultvalue").unwrap();
        let edited = doc
            .editor()
            .set_value(line, "0x3E8")
            .append_to_section(&section, ["PDOMapping=0".to_owned()])
            .apply();
        assert_eq!(
            edited.text(),
            "[1017]\r\nDefaultValue = 0x3E8   \r\n; keep me\r\nAccessType=rw\r\nPDOMapping=0"
        );
        let appended = doc.editor().append(["[2000]".to_owned()]).apply();
        assert_eq!(appended.text(), format!("{input}\r\n[2000]"));
    }

    #[test]
    fn span_of_values_counts_characters() {
        let (doc, _) = parse("[a]\nName=°C\n");
        let section = doc.section("a").unwrap();
        let line = doc.find_entry(section, "name").unwrap();
        assert_eq!(doc.value_span(line), Span::new(2, 6, 2));
    }

    proptest! {
        #[test]
        fn line_end_finds_the_first_break(bytes in proptest::collection::vec(
            prop_oneof![Just(b'\r'), Just(b'\n'), Just(0x8Du8), Just(0x0Au8 ^ 0x80), any::<u8>(), b'a'..=b'z'], 0..64),
            from in 0usize..70) {
            let naive = (from.min(bytes.len())..bytes.len())
                .find(|&i| bytes[i] == b'\n' || bytes[i] == b'\r')
                .unwrap_or(bytes.len());
            prop_assert_eq!(line_end(&bytes, from), naive);
        }

        #[test]
        fn any_bytes_round_trip(bytes in proptest::collection::vec(
            prop_oneof![Just(b'['), Just(b']'), Just(b'='), Just(b';'), Just(b'\r'), Just(b'\n'), Just(b' '),
                        Just(0xB0u8), Just(0xEF), Just(0xBB), Just(0xBF), any::<u8>(), b'a'..=b'z'], 0..300)) {
            let (doc, _) = Document::parse(&bytes);
            prop_assert_eq!(doc.to_bytes().unwrap(), bytes);
        }
    }
}

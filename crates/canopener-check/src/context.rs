//! One loaded file as the checks see it: the model, the lossless document, and lookups from a
//! section's meaning to where it is written.

use std::collections::HashMap;

use canopener_eds::section_name::{self, SectionKind};
use canopener_eds::syntax::Section;
use canopener_eds::{Diagnostic, Document, Eds, Loaded, Span};

use crate::finding::Finding;
use crate::registry::CheckInfo;

/// Where a finding points when the thing it is about is not written anywhere (a missing section):
/// the start of the file, so every span names a real line.
pub(crate) const FILE_START: Span = Span {
    line: 1,
    column: 1,
    len: 0,
};

/// A loaded file handed to every check.
#[derive(Debug)]
pub struct Context<'a> {
    /// The lossless document (spans, keys as written, duplicates).
    pub document: &'a Document,
    /// The object dictionary model.
    pub eds: &'a Eds,
    /// What loading found (the `P` series).
    pub diagnostics: &'a [Diagnostic],
    /// The file's name without directories, for the `FileName` check; `None` when read from stdin.
    pub file_name: Option<&'a str>,
    by_kind: HashMap<SectionKind, Vec<usize>>,
}

impl<'a> Context<'a> {
    /// Indexes a loaded file.
    pub fn new(loaded: &'a Loaded, file_name: Option<&'a str>) -> Self {
        let document = &loaded.document;
        let mut by_kind: HashMap<SectionKind, Vec<usize>> = HashMap::new();
        for (i, section) in document.sections().iter().enumerate() {
            let kind = section_name::classify(document.section_name(section)).identity();
            by_kind.entry(kind).or_default().push(i);
        }
        Self {
            document,
            eds: &loaded.eds,
            diagnostics: &loaded.diagnostics,
            file_name,
            by_kind,
        }
    }

    /// Whether the file is a DCF (CiA 306 §5: `LastEDS` or `[DeviceComissioning]` present).
    pub fn is_dcf(&self) -> bool {
        self.eds.is_dcf()
    }

    /// Indices into [`Document::sections`] of every section of this kind (duplicates included, both
    /// commissioning spellings count as one kind), in file order.
    pub fn sections_of(&self, kind: SectionKind) -> &[usize] {
        self.by_kind.get(&kind.identity()).map_or(&[], Vec::as_slice)
    }

    /// The first section of this kind.
    pub fn section(&self, kind: SectionKind) -> Option<&'a Section> {
        let &first = self.sections_of(kind).first()?;
        self.document.sections().get(first)
    }

    /// The name of the first section of this kind as written (e.g. `1018sub01`).
    pub fn section_name(&self, kind: SectionKind) -> Option<&'a str> {
        self.section(kind).map(|s| self.document.section_name(s))
    }

    /// The name as written, or the canonical CiA 306 name when the section is not in the file.
    pub fn display_name(&self, kind: SectionKind) -> String {
        self.section_name(kind)
            .map(str::to_owned)
            .or_else(|| section_name::canonical_name(kind))
            .unwrap_or_default()
    }

    /// The line index of the first entry with this key (case-insensitive) in the first section of
    /// this kind.
    pub fn entry_line(&self, kind: SectionKind, key: &str) -> Option<usize> {
        self.document.find_entry(self.section(kind)?, key)
    }

    /// The key as written and the value of an entry.
    pub fn entry(&self, kind: SectionKind, key: &str) -> Option<(&'a str, &'a str)> {
        self.document.entry(self.entry_line(kind, key)?)
    }

    /// The span of a section's header line, or the start of the file when it is not written.
    pub fn section_span(&self, kind: SectionKind) -> Span {
        self.section(kind)
            .map_or(FILE_START, |s| self.document.line_span(s.header_line))
    }

    /// The span of an entry's value; the section header when the key is missing; the file start when
    /// the section is missing.
    pub fn value_span(&self, kind: SectionKind, key: &str) -> Span {
        self.entry_line(kind, key)
            .map_or_else(|| self.section_span(kind), |l| self.document.value_span(l))
    }

    /// The span of an entry's key, with the same fallbacks as [`Context::value_span`].
    pub fn key_span(&self, kind: SectionKind, key: &str) -> Span {
        self.entry_line(kind, key)
            .map_or_else(|| self.section_span(kind), |l| self.document.key_span(l))
    }

    /// A finding about a section, or about one key of it when `key` is given. The span is the
    /// value of the entry (or the header when the key is missing); section and key are reported as
    /// written, falling back to the canonical names.
    pub fn finding(
        &self,
        info: &CheckInfo,
        kind: SectionKind,
        key: Option<&str>,
        message: impl Into<String>,
    ) -> Finding {
        let section = self.display_name(kind);
        match key {
            Some(key) => {
                let written = self.entry(kind, key).map_or(key, |(k, _)| k);
                Finding::new(info, self.value_span(kind, key), message).at(Some(&section), Some(written))
            }
            None => Finding::new(info, self.section_span(kind), message).at(Some(&section), None),
        }
    }

    /// A finding about the file as a whole (points at its first line).
    pub fn file_finding(&self, info: &CheckInfo, message: impl Into<String>) -> Finding {
        Finding::new(info, FILE_START, message)
    }
}

/// The section kind of an object (`sub` = `None`) or one of its sub-objects.
pub(crate) fn object_kind(index: u16, sub: Option<u8>) -> SectionKind {
    match sub {
        None => SectionKind::Object(index),
        Some(sub) => SectionKind::Sub(index, sub),
    }
}

//! One file as the checks see it: the model, and lookups from a section's meaning to where it is
//! written. For EDS/DCF text that is the lossless document; for a model read from another format (CiA
//! 311 XML) it is the sections the model has, named canonically, placed by the reader's locations
//! ([`Context::for_model`]): the same checks run on the model directly, with no text written and read
//! again.

use std::sync::OnceLock;

use canopener_eds::section_name::{self, SectionKind};
use canopener_eds::syntax::Section;
use canopener_eds::{Diagnostic, Document, Eds, Loaded, Span, write};

use crate::check_info::CheckInfo;
use crate::finding::Finding;

/// Where a finding points when the thing it is about is not written anywhere (a missing section):
/// the start of the file, so every span names a real line.
pub(crate) const FILE_START: Span = Span {
    line: 1,
    column: 1,
    len: 0,
};

/// Where a section (canonical name; `None` for the file as a whole) and one of its keys are written
/// in a file that is not EDS text.
pub type Place<'p> = dyn Fn(Option<&str>, Option<&str>) -> Span + 'p;

/// A file handed to every check.
pub struct Context<'a> {
    /// The lossless document (spans, keys as written, duplicates); empty for a model read from
    /// another format, which has no CiA 306 text.
    pub document: &'a Document,
    /// The object dictionary model.
    pub eds: &'a Eds,
    /// What loading found (the `P` series).
    pub diagnostics: &'a [Diagnostic],
    /// The file's name without directories, for the `FileName` check; `None` when read from stdin.
    pub file_name: Option<&'a str>,
    /// The kind of every section as written, by index into [`Document::sections`].
    kinds: Vec<SectionKind>,
    /// Every section index, sorted by identity kind (stable, so file order within a kind), with
    /// `sorted_kinds` holding the kind of each: a binary search finds a kind's run of indices
    /// without hashing or one allocation per kind (nearly every object section is a kind of its own).
    sorted_kinds: Vec<SectionKind>,
    sorted_sections: Vec<usize>,
    /// Entry lookups in sections longer than [`LINEAR_LOOKUP_MAX`], built on first use: a check that
    /// reports one finding per entry of an object list would otherwise scan the whole list for each
    /// (issue 13: 16 000 misplaced list entries took 1.25 s).
    long_sections: OnceLock<EntryIndex>,
    /// For a model read from another format: where its sections and keys are.
    place: Option<&'a Place<'a>>,
}

impl std::fmt::Debug for Context<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Context")
            .field("file_name", &self.file_name)
            .field("model", &self.place.is_some())
            .finish_non_exhaustive()
    }
}

/// The document of a model read from another format: no text.
fn empty_document() -> &'static Document {
    static EMPTY: OnceLock<Document> = OnceLock::new();
    EMPTY.get_or_init(|| Document::parse(b"").0)
}

/// Sections with at most this many entries are searched line by line: cheaper than the index for
/// the object sections that make up nearly every file.
const LINEAR_LOOKUP_MAX: usize = 16;

/// `(section header line, key in ASCII lower case, entry line)` of every entry of every long section,
/// sorted by section and key, file order within equal keys (so the first match is the first written).
type EntryIndex = Vec<(usize, Box<str>, usize)>;

impl<'a> Context<'a> {
    /// Indexes a loaded file.
    pub fn new(loaded: &'a Loaded, file_name: Option<&'a str>) -> Self {
        let document = &loaded.document;
        let kinds: Vec<SectionKind> = document
            .sections()
            .iter()
            .map(|s| {
                let name = document.section_name(s);
                object_kind_fast(name).unwrap_or_else(|| section_name::classify(name))
            })
            .collect();
        let mut order: Vec<(SectionKind, usize)> = kinds.iter().map(|k| k.identity()).zip(0..).collect();
        // Stable: indices of one kind stay in file order.
        order.sort_by_key(|&(kind, _)| kind);
        let (sorted_kinds, sorted_sections) = order.into_iter().unzip();
        Self {
            document,
            eds: &loaded.eds,
            diagnostics: &loaded.diagnostics,
            file_name,
            kinds,
            sorted_kinds,
            sorted_sections,
            long_sections: OnceLock::new(),
            place: None,
        }
    }

    /// A model read from another format (CiA 311 XML), with the diagnostics loading gives about its
    /// objects ([`canopener_eds::model_diagnostics`]) and where its sections and keys are written.
    /// The sections are those its canonical CiA 306 text would have, named canonically; every span is
    /// `place(section, key)`.
    pub fn for_model(
        eds: &'a Eds,
        diagnostics: &'a [Diagnostic],
        file_name: Option<&'a str>,
        place: &'a Place<'a>,
    ) -> Self {
        Self {
            document: empty_document(),
            eds,
            diagnostics,
            file_name,
            kinds: Vec::new(),
            sorted_kinds: Vec::new(),
            sorted_sections: Vec::new(),
            long_sections: OnceLock::new(),
            place: Some(place),
        }
    }

    /// Whether the file has a section of this kind: written in the document, or for a model (which
    /// has no document) in its canonical text.
    pub fn has_section(&self, kind: SectionKind) -> bool {
        match self.place {
            Some(_) => write::model_has_section(self.eds, kind),
            None => self.section(kind).is_some(),
        }
    }

    /// The kind of every section as written ([`section_name::classify`], not merged by
    /// [`SectionKind::identity`]), by index into [`Document::sections`]: classified once here for
    /// all checks.
    pub fn section_kinds(&self) -> &[SectionKind] {
        &self.kinds
    }

    /// Whether the file is a DCF (CiA 306 §5: `LastEDS` or `[DeviceComissioning]` present).
    pub fn is_dcf(&self) -> bool {
        self.eds.is_dcf()
    }

    /// Indices into [`Document::sections`] of every section of this kind (duplicates included, both
    /// commissioning spellings count as one kind), in file order.
    pub fn sections_of(&self, kind: SectionKind) -> &[usize] {
        let kind = kind.identity();
        let start = self.sorted_kinds.partition_point(|&k| k < kind);
        let len = self
            .sorted_kinds
            .get(start..)
            .map_or(0, |rest| rest.partition_point(|&k| k == kind));
        self.sorted_sections.get(start..start + len).unwrap_or(&[])
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
        let section = self.section(kind)?;
        if self.document.entries(section).len() <= LINEAR_LOOKUP_MAX {
            return self.document.find_entry(section, key);
        }
        let index = self.long_sections.get_or_init(|| self.index_long_sections());
        let key = key.to_ascii_lowercase();
        let wanted = (section.header_line, key.as_str());
        let first = index.partition_point(|(header, k, _)| (*header, &**k) < wanted);
        index
            .get(first)
            .filter(|(header, k, _)| (*header, &**k) == wanted)
            .map(|&(_, _, line)| line)
    }

    fn index_long_sections(&self) -> EntryIndex {
        let mut index: EntryIndex = Vec::new();
        for section in self.document.sections() {
            let lines = self.document.entries(section);
            if lines.len() <= LINEAR_LOOKUP_MAX {
                continue;
            }
            index.extend(lines.iter().filter_map(|&line| {
                let (key, _) = self.document.entry(line)?;
                Some((
                    section.header_line,
                    key.to_ascii_lowercase().into_boxed_str(),
                    line,
                ))
            }));
        }
        // Stable: equal keys keep file order, as `find_entry` returns the first.
        index.sort_by(|a, b| (a.0, &a.1).cmp(&(b.0, &b.1)));
        index
    }

    /// The key as written and the value of an entry (for a model: as its canonical text writes it).
    pub fn entry(&self, kind: SectionKind, key: &str) -> Option<(&'a str, &'a str)> {
        if self.place.is_some() {
            return write::model_entry(self.eds, kind, key);
        }
        self.document.entry(self.entry_line(kind, key)?)
    }

    /// Where a model's section and key are, by the reader's locations.
    fn placed(&self, kind: SectionKind, key: Option<&str>) -> Option<Span> {
        let place = self.place?;
        Some(place(Some(&self.display_name(kind)), key))
    }

    /// The span of a section's header line, or the start of the file when it is not written.
    pub fn section_span(&self, kind: SectionKind) -> Span {
        if let Some(span) = self.placed(kind, None) {
            return span;
        }
        self.section(kind)
            .map_or(FILE_START, |s| self.document.line_span(s.header_line))
    }

    /// The span of an entry's value; the section header when the key is missing; the file start when
    /// the section is missing.
    pub fn value_span(&self, kind: SectionKind, key: &str) -> Span {
        if let Some(span) = self.placed(kind, Some(key)) {
            return span;
        }
        self.entry_line(kind, key)
            .map_or_else(|| self.section_span(kind), |l| self.document.value_span(l))
    }

    /// The span of an entry's key, with the same fallbacks as [`Context::value_span`].
    pub fn key_span(&self, kind: SectionKind, key: &str) -> Span {
        if let Some(span) = self.placed(kind, Some(key)) {
            return span;
        }
        self.entry_line(kind, key)
            .map_or_else(|| self.section_span(kind), |l| self.document.key_span(l))
    }

    /// Where a finding about the file as a whole points: its first line, or for a model the file's
    /// place.
    pub fn file_span(&self) -> Span {
        self.place.map_or(FILE_START, |place| place(None, None))
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

    /// A finding about the file as a whole (points at its first line, or a model's file place).
    pub fn file_finding(&self, info: &CheckInfo, message: impl Into<String>) -> Finding {
        Finding::new(info, self.file_span(), message)
    }
}

/// The kind of the names nearly every section has, `[1018]` and `[1018sub1]` in any case, read
/// without the allocation [`section_name::classify`] makes; `None` for anything else, which
/// `classify` then decides (no fixed CiA 306 section name is made of hex digits alone).
pub(crate) fn object_kind_fast(name: &str) -> Option<SectionKind> {
    let bytes = name.as_bytes();
    let digits = bytes
        .iter()
        .position(|b| !b.is_ascii_hexdigit())
        .unwrap_or(bytes.len());
    if !(1..=4).contains(&digits) {
        return None;
    }
    let index = u16::from_str_radix(name.get(..digits)?, 16).ok()?;
    let rest = name.get(digits..)?;
    if rest.is_empty() {
        return Some(SectionKind::Object(index));
    }
    let sub = rest.get(3..)?;
    if !rest.get(..3)?.eq_ignore_ascii_case("sub")
        || !(1..=2).contains(&sub.len())
        || !sub.bytes().all(|b| b.is_ascii_hexdigit())
    {
        return None;
    }
    Some(SectionKind::Sub(index, u8::from_str_radix(sub, 16).ok()?))
}

/// The section kind of an object (`sub` = `None`) or one of its sub-objects.
pub(crate) fn object_kind(index: u16, sub: Option<u8>) -> SectionKind {
    match sub {
        None => SectionKind::Object(index),
        Some(sub) => SectionKind::Sub(index, sub),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lookups in long sections (the index) answer as the line-by-line search does: keys in any case,
    /// the first of a duplicated key, nothing for a key the section lacks.
    #[test]
    fn entry_lookups_in_long_sections_match_the_linear_search() {
        let mut text = String::from("[ManufacturerObjects]\nSupportedObjects=40\n");
        for n in 1..=40 {
            text.push_str(&format!("{n}=0x{:04X}\n", 0x6000 + n));
        }
        text.push_str("7=0x2000\n[DeviceInfo]\nVendorName=x\n");
        let loaded = canopener_eds::load(text.as_bytes());
        let cx = Context::new(&loaded, None);
        let list = SectionKind::ObjectList(canopener_eds::model::ObjectListKind::Manufacturer);
        let section = cx.section(list).expect("the list");
        assert!(cx.document.entries(section).len() > LINEAR_LOOKUP_MAX);
        for key in ["SupportedObjects", "supportedobjects", "1", "7", "40", "41", "x"] {
            assert_eq!(
                cx.entry_line(list, key),
                cx.document.find_entry(section, key),
                "key {key}"
            );
        }
        assert_eq!(
            cx.entry(list, "7"),
            Some(("7", "0x6007")),
            "the first of a duplicated key"
        );
        assert_eq!(
            cx.entry(list, "SUPPORTEDOBJECTS"),
            Some(("SupportedObjects", "40"))
        );
        assert_eq!(cx.entry_line(list, "41"), None);
        let info = SectionKind::DeviceInfo;
        assert_eq!(cx.entry(info, "vendorname"), Some(("VendorName", "x")));
    }

    #[test]
    fn fast_object_kinds_agree_with_classify() {
        for name in [
            "1018",
            "1a00",
            "1018sub1",
            "1018SUB1",
            "1018Sub01",
            "1A00subA",
            "40",
            "0sub0",
            "BEEF",
            "01018",
            "1018sub",
            "1018sub100",
            "2000Name",
            "FileInfo",
            "DeviceInfo",
            "Comments",
            "DummyUsage",
            "M1SubExt6000",
            "Tool1",
            "1018sub1x",
            "",
        ] {
            assert_eq!(
                object_kind_fast(name).unwrap_or_else(|| section_name::classify(name)),
                section_name::classify(name),
                "{name}"
            );
        }
    }
}

//! How the other tools read text, and the object sections every portability check walks.
//!
//! The emulations are deliberately narrow: each reproduces one documented behaviour of a parser
//! (`eds-format-and-checks.md` §11), so a finding can say precisely what that tool will do.

use canopener_eds::diag::Code;
use canopener_eds::section_name::SectionKind;
use canopener_eds::syntax::Section;
use canopener_eds::{Attributes, DataType, Object, ObjectType, Origin};

use crate::check_info::CheckInfo;
use crate::context::Context;
use crate::finding::Finding;

/// The tools, named with the versions the quirk matrix ran (`canopen-tools-survey.md` §1c).
pub(super) const PY: &str = "python canopen 2.4.1";
pub(super) const DCFCHK: &str = "Lely dcfchk 2.4.0";
pub(super) const HOST: &str = "canopen-host 0.6.1";
pub(super) const EDITOR: &str = "CANopenEditor";

/// The object-section keys the portability checks look at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Key {
    ParameterName,
    ObjectType,
    DataType,
    AccessType,
    DefaultValue,
    LowLimit,
    HighLimit,
    PdoMapping,
    CompactSubObj,
    ParameterValue,
    SubNumber,
}

impl Key {
    const ALL: [Key; 11] = [
        Key::ParameterName,
        Key::ObjectType,
        Key::DataType,
        Key::AccessType,
        Key::DefaultValue,
        Key::LowLimit,
        Key::HighLimit,
        Key::PdoMapping,
        Key::CompactSubObj,
        Key::ParameterValue,
        Key::SubNumber,
    ];

    /// The CiA 306 spelling.
    pub(super) fn name(self) -> &'static str {
        match self {
            Key::ParameterName => "ParameterName",
            Key::ObjectType => "ObjectType",
            Key::DataType => "DataType",
            Key::AccessType => "AccessType",
            Key::DefaultValue => "DefaultValue",
            Key::LowLimit => "LowLimit",
            Key::HighLimit => "HighLimit",
            Key::PdoMapping => "PDOMapping",
            Key::CompactSubObj => "CompactSubObj",
            Key::ParameterValue => "ParameterValue",
            Key::SubNumber => "SubNumber",
        }
    }

    /// The key a written key means (case-insensitive, CiA 306 §4.2).
    fn of(written: &str) -> Option<Key> {
        // Nearly every key is spelt exactly as CiA 306 does: one string match finds it without
        // comparing letter by letter against every name.
        let exact = match written {
            "ParameterName" => Some(Key::ParameterName),
            "ObjectType" => Some(Key::ObjectType),
            "DataType" => Some(Key::DataType),
            "AccessType" => Some(Key::AccessType),
            "DefaultValue" => Some(Key::DefaultValue),
            "LowLimit" => Some(Key::LowLimit),
            "HighLimit" => Some(Key::HighLimit),
            "PDOMapping" => Some(Key::PdoMapping),
            "CompactSubObj" => Some(Key::CompactSubObj),
            "ParameterValue" => Some(Key::ParameterValue),
            "SubNumber" => Some(Key::SubNumber),
            _ => None,
        };
        exact.or_else(|| {
            Key::ALL
                .into_iter()
                .find(|k| k.name().eq_ignore_ascii_case(written))
        })
    }
}

/// An object or sub-object section as the loader read it: its first occurrence, with the model's
/// attributes (the first value of every key) and its entries read once.
pub(super) struct Site<'a> {
    pub(super) section: &'a Section,
    /// The section name as written.
    pub(super) name: &'a str,
    pub(super) index: u16,
    pub(super) sub: Option<u8>,
    pub(super) attributes: &'a Attributes,
    /// The object type (`None` when unreadable).
    pub(super) object_type: Option<ObjectType>,
    /// `CompactSubObj` as a number (0 when missing).
    pub(super) compact: u64,
    /// The data type as written.
    pub(super) written_type: Option<DataType>,
    /// The data type, resolved through DEFTYPE objects of the file.
    pub(super) data_type: Option<DataType>,
    pub(super) object: &'a Object,
    /// For a sub-object: whether its object section came earlier in the file.
    pub(super) after_parent: bool,
    /// The first entry of each key in any letter case: line and value.
    first: [Option<(usize, &'a str)>; Key::ALL.len()],
    /// Which keys also appear spelt exactly as CiA 306 does (bit = position in `Key::ALL`).
    exact: u16,
    /// Entries of known keys spelt in other letter case: line, key as written, key.
    miscased: Vec<(usize, &'a str, Key)>,
}

impl<'a> Site<'a> {
    /// The line and value of the first entry with this key in any letter case.
    pub(super) fn entry(&self, key: Key) -> Option<(usize, &'a str)> {
        self.first.get(key as usize).copied().flatten()
    }

    /// The line of the first entry with this key in any letter case.
    pub(super) fn line(&self, key: Key) -> Option<usize> {
        self.entry(key).map(|(line, _)| line)
    }

    /// Whether a line with this key exists in any letter case.
    pub(super) fn has(&self, key: Key) -> bool {
        self.entry(key).is_some()
    }

    /// Whether the key is spelt exactly as CiA 306 does on some line (python canopen's view).
    pub(super) fn has_exact(&self, key: Key) -> bool {
        self.exact & (1 << key as u16) != 0
    }

    /// Entries of known keys spelt in other letter case.
    pub(super) fn miscased(&self) -> &[(usize, &'a str, Key)] {
        &self.miscased
    }
}

/// [`Attributes::object_type`], with the usual spellings read without parsing.
fn object_type_of(attributes: &Attributes) -> Option<ObjectType> {
    match attributes.object_type.as_deref() {
        None | Some("0x7" | "7" | "0x07") => Some(ObjectType::Var),
        Some("0x8" | "8" | "0x08") => Some(ObjectType::Array),
        Some("0x9" | "9" | "0x09") => Some(ObjectType::Record),
        Some(_) => attributes.object_type(),
    }
}

/// Calls `f` with every object and sub-object section that the loader used, in file order.
pub(super) fn for_each_site<'a>(cx: &Context<'a>, kinds: &[SectionKind], mut f: impl FnMut(&Site<'a>)) {
    let doc = cx.document;
    // Without a P020 every section is the first of its kind, and the look-up can be skipped.
    let repeats = cx.diagnostics.iter().any(|d| d.code == Code::DuplicateSection);
    // One bit per index: object sections met so far, for "sub-section before its object" (T027).
    let mut objects_seen = vec![0u64; 1024];
    for ((i, section), &kind) in doc.sections().iter().enumerate().zip(kinds) {
        let (index, sub) = match kind {
            SectionKind::Object(index) => (index, None),
            SectionKind::Sub(index, sub) => (index, Some(sub)),
            _ => continue,
        };
        // 1024 words of 64 bits hold every u16 index.
        let (word, bit) = (usize::from(index >> 6), 1u64 << (index & 63));
        if sub.is_none()
            && let Some(w) = objects_seen.get_mut(word)
        {
            *w |= bit;
        }
        let after_parent = objects_seen.get(word).is_some_and(|w| w & bit != 0);
        // Later repeats are ignored by the loader (P020); T007 speaks about them.
        if repeats && cx.sections_of(kind).first() != Some(&i) {
            continue;
        }
        let Some(object) = cx.eds.objects.get(&index) else {
            continue;
        };
        let attributes = match sub {
            None => &object.attributes,
            Some(s) => match object.subs.get(&s) {
                Some(sub_object) if sub_object.origin == Origin::Explicit => &sub_object.attributes,
                _ => continue,
            },
        };
        let mut first = [None; Key::ALL.len()];
        let mut exact = 0u16;
        let mut miscased = Vec::new();
        for &line in doc.entries(section) {
            let Some((written, value)) = doc.entry(line) else {
                continue;
            };
            let Some(key) = Key::of(written) else {
                continue;
            };
            if let Some(slot @ None) = first.get_mut(key as usize) {
                *slot = Some((line, value));
            }
            if written == key.name() {
                exact |= 1 << key as u16;
            } else {
                miscased.push((line, written, key));
            }
        }
        let written_type = attributes.data_type();
        f(&Site {
            section,
            name: doc.section_name(section),
            index,
            sub,
            attributes,
            object_type: object_type_of(attributes),
            compact: attributes.compact_sub_obj(),
            written_type,
            data_type: written_type.map(|t| cx.eds.resolve_data_type(t)),
            object,
            after_parent,
            first,
            exact,
            miscased,
        });
    }
}

/// The line of the first entry of a section whose key is spelt exactly `key`.
pub(super) fn exact_entry(cx: &Context<'_>, section: &Section, key: &str) -> Option<usize> {
    cx.document
        .entries(section)
        .iter()
        .copied()
        .find(|&l| cx.document.entry(l).is_some_and(|(k, _)| k == key))
}

/// A finding on the value of an entry line.
pub(super) fn at_value(
    cx: &Context<'_>,
    info: &CheckInfo,
    section: &str,
    line: usize,
    message: String,
) -> Finding {
    let key = cx.document.entry(line).map(|(k, _)| k);
    Finding::new(info, cx.document.value_span(line), message).at(Some(section), key)
}

/// A finding on a section header, optionally naming a key (e.g. a missing one).
pub(super) fn at_header(
    cx: &Context<'_>,
    info: &CheckInfo,
    section: &Section,
    key: Option<&str>,
    message: String,
) -> Finding {
    let name = cx.document.section_name(section);
    Finding::new(info, cx.document.line_span(section.header_line), message).at(Some(name), key)
}

/// Whether Python's `int(text, 0)` accepts the text (python canopen reads most numbers this way,
/// `eds-format-and-checks.md` §11.1): optional sign, `0x`/`0o`/`0b` prefixes, `_` between digits,
/// and no leading zeros on a decimal other than zero itself.
pub(super) fn python_int0(text: &str) -> bool {
    let t = text.trim();
    let t = t.strip_prefix(['+', '-']).unwrap_or(t);
    let prefix = t.get(..2).map(str::to_ascii_lowercase);
    let radix = match prefix.as_deref() {
        Some("0x") => 16,
        Some("0o") => 8,
        Some("0b") => 2,
        _ => 10,
    };
    if radix != 10 {
        return python_digits(t.get(2..).unwrap_or(""), radix, true);
    }
    if t.starts_with('0') {
        return python_digits(t, 10, false) && t.bytes().all(|b| b == b'0' || b == b'_');
    }
    python_digits(t, 10, false)
}

/// Whether Python's `int(text)` accepts the text (configparser's `getint`): decimal only, leading
/// zeros allowed.
pub(super) fn python_int10(text: &str) -> bool {
    let t = text.trim();
    python_digits(t.strip_prefix(['+', '-']).unwrap_or(t), 10, false)
}

fn python_digits(digits: &str, radix: u32, after_prefix: bool) -> bool {
    // Python allows one `_` between digits, and one right after a base prefix.
    let digits = if after_prefix {
        digits.strip_prefix('_').unwrap_or(digits)
    } else {
        digits
    };
    !digits.is_empty()
        && digits
            .split('_')
            .all(|part| !part.is_empty() && part.chars().all(|c| c.is_digit(radix)))
}

/// What python canopen's configparser keeps of a value: it cuts at a `;` that follows white space
/// (`inline_comment_prefixes=(';',)`), and never at `#`.
pub(super) fn python_value(text: &str) -> &str {
    let cut = text
        .char_indices()
        .zip(text.chars().skip(1))
        .find(|((_, c), next)| c.is_whitespace() && *next == ';')
        .map(|((i, _), _)| i);
    match cut {
        Some(i) => text.get(..i).unwrap_or(text).trim_end(),
        None => text,
    }
}

/// What Lely's INI lexer keeps of a value: everything before the first `;` or `#`.
pub(super) fn lely_value(text: &str) -> &str {
    match text.find([';', '#']) {
        Some(i) => text.get(..i).unwrap_or(text).trim_end(),
        None => text,
    }
}

/// Whether python canopen recognises a section as an object: `^[0-9A-Fa-f]{4}$`.
pub(super) fn python_object_section(name: &str) -> bool {
    name.len() == 4 && name.bytes().all(|b| b.is_ascii_hexdigit())
}

/// Whether python canopen recognises a section as a sub-object:
/// `^([0-9A-Fa-f]{4})[S|s]ub([0-9A-Fa-f]+)$`.
pub(super) fn python_sub_section(name: &str) -> bool {
    let (Some(index), Some(infix), Some(sub)) = (name.get(..4), name.get(4..7), name.get(7..)) else {
        return false;
    };
    python_object_section(index)
        && matches!(infix, "sub" | "Sub" | "|ub")
        && !sub.is_empty()
        && sub.bytes().all(|b| b.is_ascii_hexdigit())
}

/// Whether python canopen recognises a `[xxxxName]` section: `^([0-9A-Fa-f]{4})Name`.
pub(super) fn python_name_section(name: &str) -> bool {
    name.get(..4).is_some_and(python_object_section) && name.get(4..).is_some_and(|s| s.starts_with("Name"))
}

/// Whether python canopen builds a variable from this section, reading DataType and AccessType
/// without a fallback: sub-objects, VAR and DOMAIN objects, and compact arrays (whose sub 1 it
/// builds from the object section).
pub(super) fn python_builds_variable(site: &Site<'_>) -> bool {
    match site.sub {
        Some(_) => true,
        None => match site.object_type {
            Some(ObjectType::Var | ObjectType::Domain) => true,
            Some(ObjectType::Array) => site.compact != 0,
            _ => false,
        },
    }
}

/// Joins the parts of a message with `; `, dropping empty ones.
pub(super) fn views(parts: &[String]) -> String {
    parts
        .iter()
        .filter(|p| !p.is_empty())
        .cloned()
        .collect::<Vec<_>>()
        .join("; ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn python_int_zero_base_follows_python() {
        for ok in [
            "0", "00", "0x1A", "0X1a", "-5", "+7", "1_000", "0x_ff", "0o17", "0b101", " 12 ",
        ] {
            assert!(python_int0(ok), "{ok}");
        }
        for bad in ["", "0254", "001", "FEh", "1__0", "_1", "0x", "1.5", "0x1G", "0_1"] {
            assert!(!python_int0(bad), "{bad}");
        }
    }

    #[test]
    fn python_getint_is_decimal_only() {
        assert!(python_int10("0001") && python_int10("-250") && python_int10("250"));
        assert!(!python_int10("0xFA") && !python_int10("") && !python_int10("2.5"));
    }

    #[test]
    fn inline_comments_as_each_parser_cuts_them() {
        assert_eq!(python_value("254 ; async"), "254");
        assert_eq!(python_value("0;4"), "0;4");
        assert_eq!(python_value("Motor #1"), "Motor #1");
        assert_eq!(lely_value("254 ; async"), "254");
        assert_eq!(lely_value("Motor #1"), "Motor");
        assert_eq!(lely_value("0;4"), "0");
        assert_eq!(lely_value("plain"), "plain");
    }

    #[test]
    fn exact_key_spellings_match_their_names() {
        for key in Key::ALL {
            assert_eq!(Key::of(key.name()), Some(key));
            assert_eq!(Key::of(&key.name().to_ascii_lowercase()), Some(key));
        }
        assert_eq!(Key::of("Denotation"), None);
    }

    #[test]
    fn python_section_patterns() {
        assert!(
            python_object_section("1a00") && !python_object_section("01018") && !python_object_section("40")
        );
        assert!(python_sub_section("1018sub1") && python_sub_section("1018Sub1"));
        assert!(
            !python_sub_section("1018SUB1")
                && !python_sub_section("01018sub1")
                && !python_sub_section("1018sub")
        );
        assert!(python_name_section("2000Name") && !python_name_section("2000name"));
    }
}

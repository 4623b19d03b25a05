//! Group A of the check catalogue (`docs/check-catalogue.md`): syntax and lexical rules (checks 1-7).
//!
//! The loader already reports most of this group as `P0xx` diagnostics: encodings (P001-P004),
//! malformed headers and lines (P010-P016), duplicates (P020, P021), spelling of section names and
//! key case (P031, P032), and number syntax of typed values (P050-P053). The checks here add what
//! it does not see: line length, the characters of every line, comment characters inside values
//! other than the typed ones P053 reads, number notation of the untyped numeric keys the loader
//! reads silently, and unknown names that are misspellings of standard ones.

use canopener_eds::diag::Code;
use canopener_eds::model::{Attributes, DeviceCommissioning, DeviceInfo, FileInfo, ModuleInfo, decimal_key};
use canopener_eds::section_name::{Companion, ModulePart, SectionKind};
use canopener_eds::syntax::{LineKind, Section};
use canopener_eds::{Severity, Span};

use crate::check_info::{CheckInfo, Group};
use crate::context::Context;
use crate::finding::Finding;

/// The longest line CiA 306 V1.3 §4.2 allows, in characters, without the line ending.
const MAX_LINE: usize = 255;

const LINE_TOO_LONG: CheckInfo = CheckInfo {
    code: "C101",
    slug: "line-too-long",
    severity: Severity::Error,
    group: Group::Syntax,
    title: "no line is longer than 255 characters",
    reference: &[1],
    spec: "CiA 306 V1.3 §4.2",
    explanation: "\
A line has more than 255 characters (the line ending not counted). The finding points at the \
first character past the limit and names the key whose value is too long.

python canopen, lely and CANopenEditor read longer lines, but readers written to the \
specification may use fixed line buffers and truncate or reject a longer line, and a DCF is often \
read by the configuration manager of an embedded master. In the corpus the long lines are DOMAIN data of DCFs written as one hexadecimal number \
of almost 19000 characters, and string defaults of several hundred characters.

It is an error because CiA 306 §4.2 limits a line to 255 characters.

Fix: shorten the text. For DOMAIN data in a DCF, store the data in a file and name it with \
DownloadFile or UploadFile (CiA 306 §5.3.2) instead of ParameterValue.",
    fixable: false,
};

const NON_ASCII: CheckInfo = CheckInfo {
    code: "C102",
    slug: "non-ascii-character",
    severity: Severity::Warning,
    group: Group::Syntax,
    title: "every character is printable ASCII",
    reference: &[1],
    spec: "CiA 306 V1.3 §4.2",
    explanation: "\
A line contains a character outside printable ASCII: a non-ASCII character such as `°`, `€` or \
`‰`, or a control character other than tab. The finding names the characters with their code \
points, one finding per line.

lely's INI reader ends a value at the first byte that is not printable ASCII and ignores the rest \
of the line, so `Voltage pre-control [‰]` becomes `Voltage pre-control [`; the message says what \
lely reads. python canopen decodes the file with the locale's encoding, so a UTF-8 character turns \
into several wrong ones on a Windows machine. A file that is not even UTF-8 is reported as P001 \
as well.

It is a warning rather than an error: CiA 306 §4.2 allows only ASCII, but in a UTF-8 file such \
characters nearly always sit in names, strings and comments, which UTF-8 readers (python canopen \
on Linux, CANopenEditor) show correctly; in a key or a section name P016 or P030 reports them too.

Fix: replace the characters with ASCII (`deg C` for `°C`, `permille` for `‰`).",
    fixable: false,
};

const COMMENT_CHARACTER_IN_VALUE: CheckInfo = CheckInfo {
    code: "C103",
    slug: "comment-character-in-value",
    severity: Severity::Warning,
    group: Group::Syntax,
    title: "values contain no `;`, `#` or tab that other tools cut them at",
    reference: &[5],
    spec: "CiA 306 V1.3 §4.2",
    explanation: "\
A value contains `#`, `;` or a tab (`ParameterName=Mapped object #1`, `1=0x1000 ; device type`). \
CiA 306 has only whole-line comments, so to canopener the whole text is the value. P053 already \
covers a comment after a typed value of an object section; this check covers every other value.

lely's INI reader ends every value at `#`, `;` or a tab and ignores the rest of the line, so it \
reads `Mapped object`; python canopen cuts at a `;` that follows white space; CANopenEditor keeps \
the whole text, so a number followed by a comment becomes unreadable to it. The message says what \
lely (and, where it differs, python canopen) reads.

It is a warning where the value carries meaning (numbers, strings, file names): the readers \
disagree on it. It is reported as info for descriptive text (ParameterName, Denotation, \
Description, names of vendor, product and node, comment lines), which is valid CiA 306 and only \
shortened in lely's display.

Fix: move a comment to its own line starting with `;`; reword names so they do not need `#` or \
`;` (`Mapped object 1`).",
    fixable: false,
};

const NUMBER_NOTATION: CheckInfo = CheckInfo {
    code: "C104",
    slug: "number-notation",
    severity: Severity::Warning,
    group: Group::Syntax,
    title: "numbers outside object values are written without leading zeros or `h` suffix",
    reference: &[7],
    spec: "CiA 306 V1.3 §4.2",
    explanation: "\
A number of a key the loader reads without reporting its notation (FileVersion, VendorNumber, \
BaudRate_*, Granularity, NrOfRXPDO, DummyUsage entries, object list entries, ObjectType, DataType, \
SubNumber, PDOMapping, CompactSubObj, ObjFlags, NodeID, Baudrate, NrOfEntries, ...) is written \
with a leading zero (`002`, `010`) or with an `h` suffix (`0Ah`). P050-P052 report the same \
notations in DefaultValue, LowLimit, HighLimit and ParameterValue.

CiA 306 reads a leading zero as octal: `010` is 8. python canopen's int(x, 0) rejects such text \
(issue #313: `VendorNumber=001` stopped the import), while lely's C loader and CANopenEditor read \
octal, so tools disagree exactly where the author probably meant decimal.

A leading zero followed only by octal digits is a warning, as P051: the text is valid CiA 306 but \
ambiguous. A leading zero followed by 8 or 9 (`089`) and the `h` suffix are errors, as P050 and \
P052: CiA 306 §4.2 gives them no meaning.

Fix: write the number in decimal without leading zeros or in hexadecimal with `0x`.",
    fixable: false,
};

const MISSPELT_NAME: CheckInfo = CheckInfo {
    code: "C105",
    slug: "misspelt-name",
    severity: Severity::Warning,
    group: Group::Syntax,
    title: "unknown section names and keys are not misspellings of standard ones",
    reference: &[6],
    spec: "CiA 306 V1.3 §4.2",
    explanation: "\
A section name or a key that CiA 306 does not define is one or two letters, a space or an \
underscore away from one it does (`[OptionalObject]`, `[Device Info]`, `Supported Objects`, \
`DefaultValues`, `PDO_Mapping`). The finding names the standard spelling. P030 and P033 report \
unknown names as such; this check says which of them are likely mistakes.

No reader recognises the misspelt name, so the standard section or key is missing for all of \
them: a misspelt object list leaves its objects unlisted, a misspelt PDOMapping leaves the entry \
not mappable, a misspelt SupportedObjects broke Vector's CANeds check (libedssharp #110).

It is a warning: CiA 306 §4.2 allows additional sections and keys, so the file is not invalid by \
the name alone, but the standard information it was meant to carry is lost. What is then missing \
is reported by its own check.

Fix: rename the section or key to the spelling in the message.",
    fixable: false,
};

/// The checks of this group.
pub(crate) const CHECKS: &[CheckInfo] = &[
    LINE_TOO_LONG,
    NON_ASCII,
    COMMENT_CHARACTER_IN_VALUE,
    NUMBER_NOTATION,
    MISSPELT_NAME,
];

/// Runs the checks of this group.
pub(crate) fn run(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let document = cx.document;
    let sections = document.sections();
    let kinds = cx.section_kinds();
    // The section of every line, so the line checks can name it.
    let mut owner: Vec<Option<usize>> = vec![None; document.lines().len()];
    for (i, section) in sections.iter().enumerate() {
        for line in std::iter::once(section.header_line).chain(section.body.clone()) {
            if let Some(slot) = owner.get_mut(line) {
                *slot = Some(i);
            }
        }
    }
    // Lines with a P053 inline comment, by line index (a flag per line: cheaper than hashing
    // every line number).
    let mut inline_comment = vec![false; owner.len()];
    for d in cx.diagnostics.iter().filter(|d| d.code == Code::InlineComment) {
        let line = usize::try_from(d.span.line).ok().and_then(|l| l.checked_sub(1));
        if let Some(flag) = line.and_then(|l| inline_comment.get_mut(l)) {
            *flag = true;
        }
    }
    for (line, &section) in owner.iter().enumerate() {
        let at = LineAt {
            cx,
            line,
            text: document.line_text(line),
            section: section.and_then(|i| sections.get(i)),
            kind: section
                .and_then(|i| kinds.get(i).copied())
                .unwrap_or(SectionKind::Unknown),
            entry: document.entry(line),
        };
        check_length(&at, out);
        check_characters(&at, out);
        if !inline_comment.get(line).copied().unwrap_or(false) {
            check_comment_characters(&at, out);
        }
        check_number_notation(&at, out);
    }
    check_misspelt_names(cx, kinds, out);
}

/// One line with what the line checks need to know about it.
struct LineAt<'c, 'a> {
    cx: &'c Context<'a>,
    line: usize,
    /// The line's content without its ending.
    text: &'a str,
    section: Option<&'a Section>,
    kind: SectionKind,
    entry: Option<(&'a str, &'a str)>,
}

impl LineAt<'_, '_> {
    fn section_name(&self) -> Option<&str> {
        self.section.map(|s| self.cx.document.section_name(s))
    }

    fn finding(&self, info: &CheckInfo, span: Span, message: String) -> Finding {
        Finding::new(info, span, message).at(self.section_name(), self.entry.map(|(k, _)| k))
    }

    /// The span of `len` characters from character `column` (0-based) of the line.
    fn span(&self, column: usize, len: usize) -> Span {
        Span::new(line_number(self.line), to_u32(column + 1), to_u32(len))
    }
}

fn check_length(at: &LineAt<'_, '_>, out: &mut Vec<Finding>) {
    // A line has at most as many characters as bytes, so most lines need no count.
    if at.text.len() <= MAX_LINE {
        return;
    }
    let length = at.text.chars().count();
    if length <= MAX_LINE {
        return;
    }
    let what = match at.entry {
        Some((key, _)) => format!("the entry `{key}`"),
        None => "the line".to_owned(),
    };
    out.push(
        at.finding(
            &LINE_TOO_LONG,
            at.span(MAX_LINE, length - MAX_LINE),
            format!("{what} is {length} characters long; CiA 306 allows 255 per line"),
        )
        .with_help(
            if at
                .entry
                .is_some_and(|(k, _)| k.eq_ignore_ascii_case("ParameterValue"))
            {
                "store long DOMAIN data in a file named by DownloadFile (CiA 306 §5.3.2)"
            } else {
                "shorten the value to fit in 255 characters per line"
            },
        ),
    );
}

fn check_characters(at: &LineAt<'_, '_>, out: &mut Vec<Finding>) {
    let text = at.text;
    if is_plain_text(text.as_bytes()) {
        return;
    }
    let mut found: Vec<char> = Vec::new();
    let mut first_column = None;
    for (column, c) in text.chars().enumerate() {
        if is_plain(c) {
            continue;
        }
        first_column.get_or_insert(column);
        if !found.contains(&c) {
            found.push(c);
        }
    }
    let (Some(column), Some(&first)) = (first_column, found.first()) else {
        return;
    };
    let names: Vec<String> = found.iter().take(4).map(|&c| describe_char(c)).collect();
    let more = if found.len() > 4 { ", ..." } else { "" };
    let noun = if found.len() == 1 {
        "character"
    } else {
        "characters"
    };
    let kind = if found.iter().all(|c| c.is_control()) {
        format!("control {noun}")
    } else {
        format!("non-ASCII {noun}")
    };
    let mut message = format!("{kind} {}{more}", names.join(", "));
    match at.entry {
        Some((key, value)) => {
            message.push_str(&format!(" in the value of `{key}`"));
            if let Some(cut) = lely_cut(value).filter(|cut| cut.at == first) {
                message.push_str(&format!(
                    "; lely's loader ends the value there and reads {}",
                    cut.shown()
                ));
            }
        }
        None => {
            let place = match at.cx.document.lines().get(at.line).map(|l| &l.kind) {
                Some(LineKind::Comment) => " in a comment",
                Some(LineKind::Header { .. }) => " in a section name",
                _ => "",
            };
            message.push_str(place);
        }
    }
    out.push(
        at.finding(&NON_ASCII, at.span(column, 1), message)
            .with_help("CiA 306 §4.2 allows only ASCII; replace the characters with ASCII ones"),
    );
}

fn check_comment_characters(at: &LineAt<'_, '_>, out: &mut Vec<Finding>) {
    let Some((key, value)) = at.entry else { return };
    // `Count=0;2` of a module sub-extension uses `;` as CiA 306 §6 defines it; T020 says how tools read it.
    if key.eq_ignore_ascii_case("Count") {
        return;
    }
    // All three are ASCII, so a byte search finds the same (char boundary) position.
    let Some(column) = value.bytes().position(|b| matches!(b, b'#' | b';' | b'\t')) else {
        return;
    };
    // Where lely already stops at a non-ASCII character, C102 reports what it reads.
    let Some(cut) = lely_cut(value).filter(Cut::at_comment_character) else {
        return;
    };
    let Some(mark) = value.get(column..).and_then(|rest| rest.chars().next()) else {
        return;
    };
    let shown_mark = if mark == '\t' {
        "a tab".to_owned()
    } else {
        format!("`{mark}`")
    };
    let mut message = format!(
        "{shown_mark} in the value of `{key}`: lely's loader reads {}",
        cut.shown()
    );
    if let Some(python) = python_cut(value) {
        message.push_str(&format!(", python canopen reads `{python}`"));
    }
    let severity = if is_descriptive(at.kind, key) {
        Severity::Info
    } else {
        Severity::Warning
    };
    let value_column = value_column(at).unwrap_or(0);
    let offset = value.get(..column).map_or(0, |s| s.chars().count());
    out.push(
        at.finding(
            &COMMENT_CHARACTER_IN_VALUE,
            at.span(value_column + offset, 1),
            message,
        )
        .with_severity(severity)
        .with_help("CiA 306 has only whole-line comments; put a comment on its own `;` line"),
    );
}

fn check_number_notation(at: &LineAt<'_, '_>, out: &mut Vec<Finding>) {
    let Some((key, value)) = at.entry else { return };
    if value.is_empty() || !is_untyped_number(at.kind, key) {
        return;
    }
    // The loader reads these keys with `int_of`: the whole text, or the text before a `;`.
    let number = match canopener_eds::model::strip_inline_comment(value) {
        Some(head) if canopener_eds::value::parse_integer(value, &mut Vec::new()).is_none() => head,
        _ => value,
    };
    let mut issues = Vec::new();
    let Some(literal) = canopener_eds::value::parse_integer(number, &mut issues) else {
        // Not a number at all: the checks that use the key say so.
        return;
    };
    let Some(issue) = issues.first() else { return };
    let (severity, why) = match issue.code {
        Code::OctalLeadingZero => {
            let digits = number.trim_start_matches(['+', '-']);
            let reading = match digits.parse::<i128>() {
                Ok(decimal) if decimal.abs() != literal.value.abs() => {
                    format!(
                        "so CiA 306 reads it as octal {}, not decimal {decimal}",
                        literal.value
                    )
                }
                _ => format!(
                    "which CiA 306 reads as octal (the same value {} here), but number parsers with \
                     Python's rules reject the text (python canopen aborted on `VendorNumber=001`, issue #313)",
                    literal.value
                ),
            };
            (Severity::Warning, format!("has a leading zero, {reading}"))
        }
        Code::HexSuffix => (
            Severity::Error,
            format!(
                "uses an `h` suffix, which CiA 306 does not define; canopener reads 0x{:X}",
                literal.value
            ),
        ),
        _ => (
            Severity::Error,
            format!(
                "has a leading zero but 8 or 9 among its digits, so it is not octal and has no meaning in \
                 CiA 306; canopener reads decimal {}",
                literal.value
            ),
        ),
    };
    let value_column = value_column(at).unwrap_or(0);
    out.push(
        at.finding(
            &NUMBER_NOTATION,
            at.span(value_column, number.chars().count()),
            format!("{key}=`{number}` {why}"),
        )
        .with_severity(severity)
        .with_help("write the number in decimal without leading zeros, or in hexadecimal with `0x`"),
    );
}

fn check_misspelt_names(cx: &Context<'_>, kinds: &[SectionKind], out: &mut Vec<Finding>) {
    let document = cx.document;
    for (section, &kind) in document.sections().iter().zip(kinds) {
        let name = document.section_name(section);
        if kind == SectionKind::Unknown
            && let Some(standard) = closest(name, STANDARD_SECTIONS)
        {
            out.push(
                Finding::new(
                    &MISSPELT_NAME,
                    document.line_span(section.header_line),
                    format!("section [{name}] is not defined by CiA 306; did you mean [{standard}]?"),
                )
                .at(Some(name), None)
                .with_help(format!("rename the section to [{standard}]")),
            );
        }
        let Some(known) = known_keys(kind) else { continue };
        for &line in document.entries(section) {
            let Some((key, _)) = document.entry(line) else {
                continue;
            };
            // Nearly every key is spelt exactly as the standard does: compare exactly first.
            if known.contains(&key)
                || known.iter().any(|k| k.eq_ignore_ascii_case(key))
                || RESERVED_DEVICE_INFO_KEYS
                    .iter()
                    .any(|k| k.eq_ignore_ascii_case(key))
                || (numbered_keys(kind) && decimal_key(key).is_some())
            {
                continue;
            }
            if let Some(standard) = closest(key, known) {
                out.push(
                    Finding::new(
                        &MISSPELT_NAME,
                        document.key_span(line),
                        format!(
                            "key `{key}` is not defined by CiA 306 for [{name}]; did you mean `{standard}`?"
                        ),
                    )
                    .at(Some(name), Some(key))
                    .with_help(format!(
                        "rename the key to `{standard}`; no tool reads the value as written"
                    )),
                );
            }
        }
    }
}

/// Section names CiA 306 defines by fixed spelling (objects and modules are recognised by pattern).
const STANDARD_SECTIONS: &[&str] = &[
    "FileInfo",
    "DeviceInfo",
    "DummyUsage",
    "Comments",
    "MandatoryObjects",
    "OptionalObjects",
    "ManufacturerObjects",
    "DeviceComissioning",
    "Tools",
    "DynamicChannels",
    "SupportedModules",
    "ConnectedModules",
];

/// Keys of [DeviceInfo] CiA 306 §4.5 reserves for compatibility (reported as P034, not misspelt).
const RESERVED_DEVICE_INFO_KEYS: &[&str] = &[
    "ProductVersion",
    "ProductRevision",
    "LMT_ManufacturerName",
    "LMT_ProductName",
    "ExtendedBootUpMaster",
    "ExtendedBootUpSlave",
];

/// The keys a section kind defines, for sections whose keys are a fixed set.
fn known_keys(kind: SectionKind) -> Option<&'static [&'static str]> {
    Some(match kind {
        SectionKind::FileInfo => FileInfo::KEYS,
        SectionKind::DeviceInfo => DeviceInfo::KEYS,
        SectionKind::Commissioning(_) => DeviceCommissioning::KEYS,
        SectionKind::Object(_)
        | SectionKind::Sub(..)
        | SectionKind::Module(_, ModulePart::Fixed(_) | ModulePart::FixedSub(..))
        | SectionKind::Module(_, ModulePart::SubExt(_) | ModulePart::SubExtSub(..)) => Attributes::KEYS,
        SectionKind::Module(_, ModulePart::Info) => ModuleInfo::KEYS,
        SectionKind::ObjectList(_) => &["SupportedObjects"],
        SectionKind::Companion(_, Companion::ObjectLinks) => &["ObjectLinks"],
        SectionKind::Companion(..)
        | SectionKind::SupportedModules
        | SectionKind::ConnectedModules
        | SectionKind::Module(_, ModulePart::FixedObjects | ModulePart::SubExtends) => &["NrOfEntries"],
        _ => return None,
    })
}

/// Sections whose other entries are numbered `1=`, `2=`, ...
fn numbered_keys(kind: SectionKind) -> bool {
    matches!(
        kind,
        SectionKind::ObjectList(_)
            | SectionKind::Companion(..)
            | SectionKind::SupportedModules
            | SectionKind::ConnectedModules
            | SectionKind::Module(_, ModulePart::FixedObjects | ModulePart::SubExtends)
    )
}

/// The standard name `name` most likely misspells: equal once case, blanks, `_` and `-` are
/// ignored, or within one edit (two for names longer than 8 characters).
fn closest(name: &str, standard: &[&'static str]) -> Option<&'static str> {
    let wanted = normalise(name);
    if wanted.len() < 4 {
        return None;
    }
    let limit = if wanted.len() > 8 { 2 } else { 1 };
    standard
        .iter()
        .filter_map(|&s| {
            let candidate = normalise(s);
            // The distance is at least the difference in length: skip the table when that alone
            // is over the limit.
            if wanted.len().abs_diff(candidate.len()) > limit {
                return None;
            }
            Some((edit_distance(&wanted, &candidate), s))
        })
        .filter(|&(d, _)| d <= limit)
        .min_by_key(|&(d, _)| d)
        .map(|(_, s)| s)
}

fn normalise(name: &str) -> Vec<u8> {
    name.bytes()
        .filter(|b| !matches!(b, b' ' | b'_' | b'-' | b'\t'))
        .map(|b| b.to_ascii_lowercase())
        .collect()
}

/// Optimal string alignment distance: insertions, deletions, substitutions and swaps of neighbours.
#[allow(
    clippy::indexing_slicing,
    reason = "every index stays inside the table and inside `a` and `b`, as the comment below shows"
)]
fn edit_distance(a: &[u8], b: &[u8]) -> usize {
    // Indexing below stays inside the (a.len() + 1) x (b.len() + 1) table and inside `a` and `b`:
    // i runs over 1..=a.len(), j over 1..=b.len(), and the swap case requires i, j > 1.
    let width = b.len() + 1;
    let mut rows = vec![0usize; (a.len() + 1) * width];
    let at = |i: usize, j: usize| i * width + j;
    for i in 0..=a.len() {
        rows[at(i, 0)] = i;
    }
    for j in 0..=b.len() {
        rows[at(0, j)] = j;
    }
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut best = (rows[at(i - 1, j)] + 1)
                .min(rows[at(i, j - 1)] + 1)
                .min(rows[at(i - 1, j - 1)] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                best = best.min(rows[at(i - 2, j - 2)] + 1);
            }
            rows[at(i, j)] = best;
        }
    }
    rows[at(a.len(), b.len())]
}

/// Whether `key` of a section of this kind holds descriptive text, which lely only shows.
fn is_descriptive(kind: SectionKind, key: &str) -> bool {
    const TEXT_KEYS: &[&str] = &[
        "ParameterName",
        "Denotation",
        "Description",
        "CreatedBy",
        "ModifiedBy",
        "VendorName",
        "ProductName",
        "OrderCode",
        "NodeName",
        "NetworkName",
    ];
    match kind {
        SectionKind::Comments | SectionKind::Module(_, ModulePart::Comments) => true,
        SectionKind::Companion(_, Companion::Name | Companion::Denotation) => {
            !key.eq_ignore_ascii_case("NrOfEntries")
        }
        _ => TEXT_KEYS.iter().any(|k| k.eq_ignore_ascii_case(key)),
    }
}

/// Whether `key` of a section of this kind is an integer the loader reads without reporting how
/// it is written (typed values such as DefaultValue are read and reported by the loader).
fn is_untyped_number(kind: SectionKind, key: &str) -> bool {
    let any = |keys: &[&str]| keys.iter().any(|k| k.eq_ignore_ascii_case(key));
    match kind {
        SectionKind::FileInfo => any(&["FileVersion", "FileRevision"]),
        SectionKind::DeviceInfo => {
            key.get(..9).is_some_and(|p| p.eq_ignore_ascii_case("BaudRate_"))
                || DeviceInfo::FLAG_KEYS
                    .into_iter()
                    .chain(DeviceInfo::NUMBER_KEYS.map(|(key, _)| key))
                    .any(|k| k.eq_ignore_ascii_case(key))
        }
        SectionKind::DummyUsage
        | SectionKind::ObjectList(_)
        | SectionKind::Companion(_, Companion::ObjectLinks)
        | SectionKind::SupportedModules
        | SectionKind::ConnectedModules
        | SectionKind::Module(_, ModulePart::FixedObjects | ModulePart::SubExtends) => true,
        SectionKind::Commissioning(_) => any(&[
            "NodeID",
            "Baudrate",
            "NetNumber",
            "CANopenManager",
            "LSS_SerialNumber",
        ]),
        SectionKind::Object(_) | SectionKind::Sub(..) | SectionKind::Module(..) => {
            any(&[
                "ObjectType",
                "DataType",
                "PDOMapping",
                "SubNumber",
                "CompactSubObj",
                "ObjFlags",
                "ObjExtend",
            ]) || (matches!(kind, SectionKind::Module(_, ModulePart::Info))
                && any(&["ProductVersion", "ProductRevision"]))
        }
        SectionKind::Companion(..) => any(&["NrOfEntries"]),
        SectionKind::Comments => any(&["Lines"]),
        SectionKind::Tools => any(&["Items"]),
        SectionKind::DynamicChannels => {
            any(&["NrOfSeg"]) || key.get(..4).is_some_and(|p| p.eq_ignore_ascii_case("Type"))
        }
        SectionKind::Tool(_) | SectionKind::Unknown => false,
    }
}

/// Where lely's INI reader stops reading a value (CiA 306 readers take the whole text).
struct Cut<'v> {
    /// What lely keeps, trailing white space removed.
    kept: &'v str,
    /// The character it stopped at.
    at: char,
}

impl Cut<'_> {
    /// What lely reads, in words; long texts by their length, so the message stays one line.
    fn shown(&self) -> String {
        match self.kept.chars().count() {
            0 => "an empty value".to_owned(),
            n if n > 40 => format!("only the {n} characters before it"),
            _ => format!("`{}`", self.kept),
        }
    }

    /// Whether lely stops at a comment character or a tab (rather than at a non-ASCII character).
    fn at_comment_character(&self) -> bool {
        matches!(self.at, '#' | ';' | '\t')
    }
}

/// lely's `config_ini.c` reads a value while characters are printable ASCII other than `#` and `;`
/// and skips the rest of the line; a value starting with `"` is read as a C string literal instead.
fn lely_cut(value: &str) -> Option<Cut<'_>> {
    if value.starts_with('"') {
        return None;
    }
    let (position, at) = value
        .char_indices()
        .find(|&(_, c)| !(c == ' ' || c.is_ascii_graphic()) || c == '#' || c == ';')?;
    Some(Cut {
        kept: value.get(..position)?.trim_end(),
        at,
    })
}

/// python canopen reads with `inline_comment_prefixes=(';',)`: configparser cuts the value at a `;`
/// that follows white space. `None` when it reads the whole value.
fn python_cut(value: &str) -> Option<&str> {
    let bytes = value.as_bytes();
    let position = bytes
        .windows(2)
        .position(|pair| matches!(pair, [before, b';'] if before.is_ascii_whitespace()))?
        + 1;
    Some(value.get(..position)?.trim_end())
}

/// The 0-based character column where an entry's value starts.
fn value_column(at: &LineAt<'_, '_>) -> Option<usize> {
    let span = at.cx.document.value_span(at.line);
    usize::try_from(span.column).ok()?.checked_sub(1)
}

/// Whether every byte is a tab or printable ASCII ([`is_plain`] for every character). Checked in
/// blocks without an early exit so the compiler can test many bytes at once; nearly every line is
/// plain.
fn is_plain_text(bytes: &[u8]) -> bool {
    let not_plain = |b: u8| (b != b'\t') & (b.wrapping_sub(0x20) >= 0x5F);
    let mut blocks = bytes.chunks_exact(16);
    for block in &mut blocks {
        if block.iter().fold(false, |bad, &b| bad | not_plain(b)) {
            return false;
        }
    }
    !blocks.remainder().iter().any(|&b| not_plain(b))
}

fn is_plain(c: char) -> bool {
    c == '\t' || (' '..='~').contains(&c)
}

fn describe_char(c: char) -> String {
    if c.is_control() {
        format!("U+{:04X}", u32::from(c))
    } else {
        format!("`{c}` (U+{:04X})", u32::from(c))
    }
}

fn line_number(line: usize) -> u32 {
    to_u32(line + 1)
}

fn to_u32(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_text_test_agrees_with_byte_by_byte() {
        let slow = |bytes: &[u8]| bytes.iter().all(|&b| b == b'\t' || (0x20..0x7F).contains(&b));
        for bad in 0..=255u8 {
            for len in [1, 15, 16, 17, 40] {
                for at in [0, len / 2, len - 1] {
                    let mut line = vec![b'a'; len];
                    line[at] = bad;
                    assert_eq!(is_plain_text(&line), slow(&line), "{bad:#x} at {at} of {len}");
                }
            }
        }
        assert!(is_plain_text(b""));
    }

    fn findings(text: &str) -> Vec<Finding> {
        let loaded = canopener_eds::load(text.as_bytes());
        let cx = Context::new(&loaded, None);
        let mut out = Vec::new();
        run(&cx, &mut out);
        out
    }

    #[test]
    fn every_check_has_an_explanation_page() {
        for c in CHECKS {
            assert!(c.code.starts_with("C1") && c.reference.iter().all(|r| (1..=7).contains(r)));
            let paragraphs = c.explanation.split("\n\n").count();
            assert!(
                (2..=4).contains(&paragraphs),
                "{}: {paragraphs} paragraphs",
                c.code
            );
            assert!(c.explanation.lines().all(|l| !l.starts_with('#')), "{}", c.code);
        }
    }

    #[test]
    fn lely_stops_at_comment_characters_tabs_and_non_ascii() {
        let cut = |v| lely_cut(v).map(|c| (c.kept, c.at));
        assert_eq!(cut("Mapped object #1"), Some(("Mapped object", '#')));
        assert_eq!(cut("0x1000 ; device type"), Some(("0x1000", ';')));
        assert_eq!(cut("a\tb"), Some(("a", '\t')));
        assert_eq!(cut("Voltage [‰]"), Some(("Voltage [", '‰')));
        assert_eq!(cut("#1"), Some(("", '#')));
        assert_eq!(cut("\"quoted # text\""), None);
        assert_eq!(cut("plain text"), None);
    }

    #[test]
    fn python_canopen_cuts_only_at_a_semicolon_after_white_space() {
        assert_eq!(python_cut("254 ; async"), Some("254"));
        assert_eq!(python_cut("status;C1"), None);
        assert_eq!(python_cut("Motor #1"), None);
    }

    #[test]
    fn misspellings_are_close_and_extensions_are_not() {
        let attributes = Attributes::KEYS;
        assert_eq!(closest("DefaultValues", attributes), Some("DefaultValue"));
        assert_eq!(closest("PDO_Mapping", attributes), Some("PDOMapping"));
        assert_eq!(closest("Paramtername", attributes), Some("ParameterName"));
        assert_eq!(
            closest("Supported Objects", &["SupportedObjects"]),
            Some("SupportedObjects")
        );
        assert_eq!(
            closest("OptionalObject", STANDARD_SECTIONS),
            Some("OptionalObjects")
        );
        for extension in ["Factor", "Unit", "Description", "Category", "Offset", "RecordTag"] {
            assert_eq!(closest(extension, attributes), None, "{extension}");
        }
        for extension in ["NG_Slave", "NG_Master", "LSS_Master", "NrOfNG_MonitoredNodes"] {
            assert_eq!(closest(extension, DeviceInfo::KEYS), None, "{extension}");
        }
        for section in ["PreDefines", "ToolInfos", "VendorSpecificSection", "D000sub100"] {
            assert_eq!(closest(section, STANDARD_SECTIONS), None, "{section}");
        }
        assert_eq!(edit_distance(b"ab", b"ba"), 1);
        assert_eq!(edit_distance(b"", b"abc"), 3);
    }

    #[test]
    fn line_checks_point_at_the_offending_column() {
        let long = format!("[FileInfo]\nDescription={}\n", "x".repeat(250));
        let found = findings(&long);
        let finding = found.iter().find(|f| f.diagnostic.code == "C101");
        assert!(
            finding.is_some_and(|f| f.diagnostic.span == Span::new(2, 256, 7)),
            "{found:?}"
        );

        let found = findings("[FileInfo]\nDescription=Temperatur in °C\n");
        let finding = found.iter().find(|f| f.diagnostic.code == "C102");
        assert!(
            finding.is_some_and(|f| f.diagnostic.span == Span::new(2, 27, 1)
                && f.diagnostic.message.contains("`Temperatur in`")),
            "{found:?}"
        );

        let found = findings("[1000]\nParameterName=Device type #1\n");
        let finding = found.iter().find(|f| f.diagnostic.code == "C103");
        assert!(
            finding.is_some_and(
                |f| f.diagnostic.span == Span::new(2, 27, 1) && f.diagnostic.severity == Severity::Info
            ),
            "{found:?}"
        );

        let found = findings("[FileInfo]\nFileVersion=010\n");
        let finding = found.iter().find(|f| f.diagnostic.code == "C104");
        assert!(
            finding
                .is_some_and(|f| f.diagnostic.span == Span::new(2, 13, 3)
                    && f.diagnostic.severity == Severity::Warning),
            "{found:?}"
        );
        let found = findings("[FileInfo]\nFileVersion=09\n");
        assert!(
            found
                .iter()
                .any(|f| f.diagnostic.code == "C104" && f.diagnostic.severity == Severity::Error),
            "{found:?}"
        );
    }

    #[test]
    fn control_characters_are_named_by_code_point() {
        let found = findings("[FileInfo]\nDescription=a\u{1}b\n");
        let finding = found.iter().find(|f| f.diagnostic.code == "C102");
        assert!(
            finding.is_some_and(|f| f.diagnostic.message.starts_with("control character U+0001")),
            "{found:?}"
        );
    }
}

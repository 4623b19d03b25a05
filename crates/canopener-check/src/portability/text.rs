//! The text of the file: its encoding, and `;`/`#` inside values, which every parser cuts
//! differently.

use canopener_eds::diag::Code;
use canopener_eds::section_name::{Companion, ModulePart, SectionKind};
use canopener_eds::syntax::LineKind;
use canopener_eds::text::Encoding;
use canopener_eds::{Span, TypeKind};

use super::checks::{INLINE_COMMENT, NOT_UTF8, UTF8_BOM};
use super::tools::{DCFCHK, EDITOR, HOST, PY, lely_value, python_value, views};
use crate::context::{Context, FILE_START};
use crate::finding::Finding;

/// Keys whose values are names or descriptions: a truncated one is cosmetic.
const TEXT_KEYS: &[&str] = &[
    "ParameterName",
    "Denotation",
    "VendorName",
    "ProductName",
    "OrderCode",
    "Description",
    "CreatedBy",
    "ModifiedBy",
    "NodeName",
    "NetworkName",
    "NodeRefd",
    "NetRefd",
    "ParamRefd",
];

pub(super) fn run(cx: &Context<'_>, kinds: &[SectionKind], out: &mut Vec<Finding>) {
    encoding(cx, out);
    inline_comments(cx, kinds, out);
}

fn encoding(cx: &Context<'_>, out: &mut Vec<Finding>) {
    match cx.document.encoding() {
        Encoding::Utf8 => {}
        Encoding::Utf8Bom => out.push(Finding::new(
            &UTF8_BOM,
            Span::new(1, 1, 1),
            format!(
                "the file starts with a UTF-8 byte order mark: {PY} crashes (MissingSectionHeaderError); \
                 {DCFCHK} crashes; {HOST} and {EDITOR} skip it"
            ),
        )),
        Encoding::Windows1252 => {
            let span = cx
                .diagnostics
                .iter()
                .find(|d| d.code == Code::Windows1252)
                .map_or(FILE_START, |d| d.span);
            let line = usize::try_from(span.line.saturating_sub(1)).unwrap_or(0);
            let column = usize::try_from(span.column.saturating_sub(1)).unwrap_or(0);
            let character = cx
                .document
                .line_text(line)
                .chars()
                .nth(column)
                .map_or_else(String::new, |c| format!(" `{c}` (U+{:04X})", u32::from(c)));
            out.push(Finding::new(
                &NOT_UTF8,
                span,
                format!(
                    "the character{character} is not UTF-8 (the file is Latin-1/Windows-1252): {}",
                    views(&[
                        format!("{PY} crashes (UnicodeDecodeError) where its default encoding is UTF-8"),
                        format!("{DCFCHK} crashes"),
                        format!("{HOST} rejects the file"),
                        format!("{EDITOR} replaces it with U+FFFD"),
                    ])
                ),
            ));
        }
    }
}

/// T020: values with `;` or `#`. Settings are reported one by one; names and descriptions, whose
/// cut only changes text, once per file.
fn inline_comments(cx: &Context<'_>, kinds: &[SectionKind], out: &mut Vec<Finding>) {
    let doc = cx.document;
    let bytes = doc.text().as_bytes();
    let mut texts: Vec<(usize, &str, SectionKind)> = Vec::new();
    for (section, &kind) in doc.sections().iter().zip(kinds) {
        for &line in doc.entries(section) {
            // Only the value's bytes are searched; most values have neither character.
            let has_marker = doc.lines().get(line).is_some_and(|l| match &l.kind {
                LineKind::Entry { value, .. } => bytes
                    .get(value.clone())
                    .is_some_and(|v| v.iter().any(|&b| b == b';' || b == b'#')),
                _ => false,
            });
            if !has_marker {
                continue;
            }
            let Some((key, value)) = doc.entry(line) else {
                continue;
            };
            let section_name = doc.section_name(section);
            if is_text(kind, key) {
                texts.push((line, section_name, kind));
                continue;
            }
            let message = format!(
                "{key} `{value}` contains `{}`, which CiA 306 does not treat as a comment: {}",
                marker(value),
                readings(cx, kind, key, value)
            );
            out.push(
                Finding::new(&INLINE_COMMENT, doc.value_span(line), message)
                    .at(Some(section_name), Some(key)),
            );
        }
    }
    let Some(&(line, section_name, kind)) = texts.first() else {
        return;
    };
    let Some((key, value)) = doc.entry(line) else {
        return;
    };
    let more = match texts.len() - 1 {
        0 => String::new(),
        n => format!(" (and {n} more names, descriptions or comment lines)"),
    };
    out.push(
        Finding::new(
            &INLINE_COMMENT,
            doc.value_span(line),
            format!(
                "{key} `{value}` in [{section_name}]{more} contains `{}`: {}",
                marker(value),
                readings(cx, kind, key, value)
            ),
        )
        .at(Some(section_name), Some(key))
        .with_severity(canopener_eds::Severity::Info),
    );
}

fn marker(value: &str) -> char {
    value.chars().find(|c| *c == ';' || *c == '#').unwrap_or(';')
}

fn is_text(kind: SectionKind, key: &str) -> bool {
    matches!(
        kind,
        SectionKind::Comments
            | SectionKind::Companion(_, Companion::Name | Companion::Denotation)
            | SectionKind::Module(_, ModulePart::Comments)
            | SectionKind::Unknown
    ) || TEXT_KEYS.iter().any(|k| k.eq_ignore_ascii_case(key))
}

/// What each tool reads of a value containing `;` or `#`.
fn readings(cx: &Context<'_>, kind: SectionKind, key: &str, value: &str) -> String {
    let lely = lely_value(value);
    // python canopen ignores the object lists, module sections and tool sections altogether.
    let python_reads = matches!(
        kind,
        SectionKind::Object(_)
            | SectionKind::Sub(..)
            | SectionKind::Companion(_, Companion::Name)
            | SectionKind::DeviceInfo
            | SectionKind::DummyUsage
            | SectionKind::Comments
            | SectionKind::Commissioning(_)
    );
    let python = python_value(value);
    let mut parts = Vec::new();
    match (python_reads, python == lely) {
        (true, true) => parts.push(format!("{PY} and Lely read `{lely}`")),
        (true, false) if python == value => {
            parts.push(format!("Lely reads `{lely}`"));
            parts.push(format!("{PY} keeps the whole text"));
        }
        (true, false) => {
            parts.push(format!("Lely reads `{lely}`"));
            parts.push(format!("{PY} reads `{python}`"));
        }
        (false, _) => parts.push(format!("Lely reads `{lely}`")),
    }
    parts.push(format!("{EDITOR} keeps the whole text as the value"));
    if is_numeric_value(cx, kind, key) {
        parts.push(format!("{HOST} rejects the file"));
    }
    views(&parts)
}

/// Whether the entry is the DefaultValue or ParameterValue of a number, which canopen-host refuses
/// to read with a comment.
fn is_numeric_value(cx: &Context<'_>, kind: SectionKind, key: &str) -> bool {
    if !(key.eq_ignore_ascii_case("DefaultValue") || key.eq_ignore_ascii_case("ParameterValue")) {
        return false;
    }
    let attributes = match kind {
        SectionKind::Object(index) => cx.eds.objects.get(&index).map(|o| &o.attributes),
        SectionKind::Sub(index, sub) => cx
            .eds
            .objects
            .get(&index)
            .and_then(|o| o.subs.get(&sub))
            .map(|s| &s.attributes),
        _ => None,
    };
    attributes
        .and_then(|a| a.data_type())
        .map(|t| cx.eds.resolve_data_type(t))
        .and_then(|t| t.kind())
        .is_some_and(|k| {
            matches!(
                k,
                TypeKind::Signed(_)
                    | TypeKind::Unsigned(_)
                    | TypeKind::Boolean
                    | TypeKind::Real32
                    | TypeKind::Real64
            )
        })
}

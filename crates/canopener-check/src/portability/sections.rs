//! Sections the tools find, merge or lose differently: repeats, letter case, leading zeros, order,
//! orphans, missing mandatory sections and object links.

use std::collections::HashMap;

use canopener_eds::diag::Code;
use canopener_eds::model::{CommissioningSpelling, ObjectListKind};
use canopener_eds::section_name::{self, Companion, SectionKind};
use canopener_eds::{Origin, Severity};

use super::checks::{
    DUPLICATE_KEY, DUPLICATE_SECTION, MISSING_INFO_SECTION, OBJECT_LINKS, ORPHAN_SUB, SECTION_CASE,
    SECTION_DIGITS, SUB_BEFORE_PARENT, SUB_CASE,
};
use super::tools::{
    DCFCHK, EDITOR, HOST, PY, Site, at_header, python_name_section, python_object_section,
    python_sub_section, views,
};
use crate::context::Context;
use crate::finding::Finding;

pub(super) fn run(cx: &Context<'_>, kinds: &[SectionKind], out: &mut Vec<Finding>) {
    // A repeat the tools see is also one the loader reports (it compares at least as broadly), so
    // clean files skip the scans.
    let repeats = |code| cx.diagnostics.iter().any(|d| d.code == code);
    if repeats(Code::DuplicateSection) {
        duplicate_sections(cx, out);
    }
    if repeats(Code::DuplicateSection) || repeats(Code::DuplicateKey) {
        duplicate_keys(cx, out);
    }
    missing_sections(cx, out);
    section_case(cx, kinds, out);
    for ((i, section), &kind) in cx.document.sections().iter().enumerate().zip(kinds) {
        if let SectionKind::Companion(_, Companion::ObjectLinks) = kind
            && cx.sections_of(kind).first() == Some(&i)
        {
            let name = cx.document.section_name(section);
            out.push(at_header(
                cx,
                &OBJECT_LINKS,
                section,
                None,
                format!(
                    "{DCFCHK} reports [{name}] as an unknown section; {PY}, {HOST} and {EDITOR} ignore the \
                     links"
                ),
            ));
        }
    }
}

/// The checks of one object or sub-object section.
pub(super) fn site(cx: &Context<'_>, site: &Site<'_>, out: &mut Vec<Finding>) {
    section_digits(cx, site, out);
    if site.sub.is_none() {
        return;
    }
    sub_case(cx, site, out);
    if site.object.origin == Origin::Orphan {
        let python = if python_sub_section(site.name) {
            format!("{PY} crashes (KeyError)")
        } else {
            format!("{PY} ignores it")
        };
        out.push(at_header(
            cx,
            &ORPHAN_SUB,
            site.section,
            None,
            format!(
                "[{}] has no object section [{:X}]: {}",
                site.name,
                site.index,
                views(&[
                    python,
                    format!("{DCFCHK} reports it"),
                    format!("{HOST} keeps it as an orphan"),
                    format!("{EDITOR} ignores it"),
                ])
            ),
        ));
    } else if !site.after_parent
        && let Some(parent) = cx.section(SectionKind::Object(site.index))
    {
        out.push(at_header(
            cx,
            &SUB_BEFORE_PARENT,
            site.section,
            None,
            format!(
                "[{}] comes before its object section [{}] (line {}): {EDITOR} attaches sub-sections to an \
                 object it has already read and silently loses this one",
                site.name,
                cx.document.section_name(parent),
                parent.header_line + 1
            ),
        ));
    }
}

/// T007: repeated sections, compared as the tools compare them (names differing only in case are
/// one section for Lely, CANopenEditor and canopen-host, two for python canopen).
fn duplicate_sections(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let doc = cx.document;
    let mut first: HashMap<String, usize> = HashMap::new();
    for (i, section) in doc.sections().iter().enumerate() {
        let name = doc.section_name(section);
        let Some(&earlier) = first.get(&name.to_ascii_lowercase()) else {
            first.insert(name.to_ascii_lowercase(), i);
            continue;
        };
        let Some(earlier) = doc.sections().get(earlier) else {
            continue;
        };
        let earlier_name = doc.section_name(earlier);
        let python = if earlier_name == name {
            format!("{PY} crashes (DuplicateSectionError)")
        } else {
            format!(
                "{PY} reads [{earlier_name}] and [{name}] as two sections (it compares names \
                 case-sensitively)"
            )
        };
        out.push(at_header(
            cx,
            &DUPLICATE_SECTION,
            section,
            None,
            format!(
                "[{name}] repeats the section on line {}: {}",
                earlier.header_line + 1,
                views(&[
                    python,
                    format!("{DCFCHK} crashes"),
                    format!("Lely's loader and {HOST} merge the two, so later values win"),
                    format!("{EDITOR} warns and keeps the first"),
                ])
            ),
        ));
    }
}

/// T008: repeated keys within a section.
fn duplicate_keys(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let doc = cx.document;
    for section in doc.sections() {
        let section_name = doc.section_name(section);
        let mut first: HashMap<String, usize> = HashMap::new();
        for &line in doc.entries(section) {
            let Some((key, value)) = doc.entry(line) else {
                continue;
            };
            let Some(&earlier) = first.get(&key.to_ascii_lowercase()) else {
                first.insert(key.to_ascii_lowercase(), line);
                continue;
            };
            let Some((earlier_key, earlier_value)) = doc.entry(earlier) else {
                continue;
            };
            let python = if earlier_key == key {
                format!("{PY} crashes (DuplicateOptionError)")
            } else {
                format!(
                    "{PY} sees `{earlier_key}` and `{key}` as two keys (it compares keys case-sensitively)"
                )
            };
            let values = if earlier_value == value {
                String::new()
            } else {
                format!(
                    "{EDITOR} keeps the first value `{earlier_value}`, {HOST} silently the last `{value}`"
                )
            };
            out.push(
                Finding::new(
                    &DUPLICATE_KEY,
                    doc.key_span(line),
                    format!(
                        "`{key}` repeats line {} in [{section_name}]: {}",
                        earlier + 1,
                        views(&[python, format!("{DCFCHK} crashes"), values])
                    ),
                )
                .at(Some(section_name), Some(key)),
            );
        }
    }
}

/// T026: the sections CANopenEditor reads unconditionally.
fn missing_sections(cx: &Context<'_>, out: &mut Vec<Finding>) {
    for kind in [
        SectionKind::FileInfo,
        SectionKind::DeviceInfo,
        SectionKind::ObjectList(ObjectListKind::Mandatory),
    ] {
        if cx.section(kind).is_none() {
            let name = section_name::canonical_name(kind).unwrap_or_default();
            out.push(cx.file_finding(
                &MISSING_INFO_SECTION,
                format!("the file has no [{name}]: {EDITOR} throws KeyNotFoundException and opens nothing"),
            ));
        }
    }
}

/// T038: sections python canopen looks up by their exact name.
fn section_case(cx: &Context<'_>, kinds: &[SectionKind], out: &mut Vec<Finding>) {
    let doc = cx.document;
    for ((i, section), &kind) in doc.sections().iter().enumerate().zip(kinds) {
        if !matches!(
            kind,
            SectionKind::Commissioning(_)
                | SectionKind::DeviceInfo
                | SectionKind::Comments
                | SectionKind::Companion(_, Companion::Name)
        ) || cx.sections_of(kind).first() != Some(&i)
        {
            continue;
        }
        let name = doc.section_name(section);
        let (canonical, effect, severity) = match kind {
            SectionKind::Commissioning(CommissioningSpelling::DeviceComissioning) => (
                "DeviceComissioning".to_owned(),
                "so the DCF's NodeID and Baudrate are not applied; Lely reads it",
                Severity::Warning,
            ),
            SectionKind::DeviceInfo => (
                "DeviceInfo".to_owned(),
                "so the device information is missing there; Lely reads it",
                Severity::Info,
            ),
            SectionKind::Comments => (
                "Comments".to_owned(),
                "so the comment lines are missing there; Lely reads it",
                Severity::Info,
            ),
            SectionKind::Companion(index, Companion::Name)
                if name.get(..4).is_some_and(python_object_section)
                    && cx
                        .eds
                        .objects
                        .get(&index)
                        .is_some_and(|o| o.attributes.compact_sub_obj() != 0) =>
            {
                if python_name_section(name) {
                    continue;
                }
                (
                    format!("{}Name", name.get(..4).unwrap_or_default()),
                    "so it applies none of the names and creates only sub 0 and sub 1 of the compact array; \
                     Lely reads it",
                    Severity::Warning,
                )
            }
            _ => continue,
        };
        if name == canonical {
            continue;
        }
        out.push(
            at_header(
                cx,
                &SECTION_CASE,
                section,
                None,
                format!(
                    "[{name}] is not spelt [{canonical}]: {PY} matches section names case-sensitively and \
                     does not read it, {effect}"
                ),
            )
            .with_severity(severity),
        );
    }
}

/// T009: `sub` written in other letter case.
fn sub_case(cx: &Context<'_>, site: &Site<'_>, out: &mut Vec<Finding>) {
    let name = site.name;
    let Some(at) = sub_at(name) else { return };
    let message = match name.get(at..at + 3) {
        Some("sub") | None => return,
        Some("Sub") => format!(
            "[{name}] writes `Sub`: {EDITOR} matches `sub` case-sensitively and silently loses this \
             sub-object; {PY}, Lely and {HOST} read it"
        ),
        Some(other) => format!(
            "[{name}] writes `{other}`: {PY} (which accepts `sub` and `Sub`) and {EDITOR} (which accepts \
             only `sub`) silently lose this sub-object; Lely and {HOST} read it"
        ),
    };
    out.push(at_header(cx, &SUB_CASE, site.section, None, message));
}

/// T032: names Lely's generated look-up or python canopen's four-digit pattern does not find.
fn section_digits(cx: &Context<'_>, site: &Site<'_>, out: &mut Vec<Finding>) {
    let (name, index, sub) = (site.name, site.index, site.sub);
    let kind = match sub {
        None => SectionKind::Object(index),
        Some(s) => SectionKind::Sub(index, s),
    };
    // Nearly every section is spelt canonically; that is decided without allocating.
    if section_name::is_canonical_object_name(name, kind) == Some(true) {
        return;
    }
    let Some(canonical) = section_name::canonical_name(kind) else {
        return;
    };
    let lely_finds = name.eq_ignore_ascii_case(&canonical);
    // Below 1000h the CiA 306 name has fewer than four digits, so python canopen never finds it;
    // only Lely's side is reported there.
    let python_finds = index < 0x1000
        || match sub {
            None => python_object_section(name),
            Some(_) => sub_at(name) == Some(4) && name.get(..4).is_some_and(python_object_section),
        };
    if lely_finds && python_finds {
        return;
    }
    let lely = if lely_finds {
        "Lely reads it".to_owned()
    } else {
        format!("Lely's loader looks it up as [{canonical}] and does not find it")
    };
    let python = if python_finds {
        format!("{PY} reads it")
    } else {
        format!("{PY} recognises only four-digit indices and ignores it")
    };
    out.push(at_header(
        cx,
        &SECTION_DIGITS,
        site.section,
        None,
        format!(
            "[{name}] is not written [{canonical}]: {}",
            views(&[lely, python])
        ),
    ));
}

/// Where `sub` starts in a sub-object section name, in any letter case (the hex index before it
/// cannot contain an `s` or `u`).
fn sub_at(name: &str) -> Option<usize> {
    name.as_bytes()
        .windows(3)
        .position(|w| w.eq_ignore_ascii_case(b"sub"))
}

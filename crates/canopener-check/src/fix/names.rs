//! P031 and P032: section names and keys written as CiA 306 writes them.

use std::collections::{HashMap, HashSet};

use canopener_eds::Code;
use canopener_eds::model::{Attributes, DeviceCommissioning, DeviceInfo, FileInfo, ModuleInfo};
use canopener_eds::section_name::{self, ModulePart, SectionKind};

use super::{Edit, Fix, Planned, splice, with_key};
use crate::context::Context;

/// P031: rewrites each header the loader reported to the canonical name (CiA 306 §4.6.3.2: hex
/// without leading zeros, `sub` in lower case; §5.3.1: `DeviceComissioning`). A rename that would
/// make two sections of the same name is refused: the sections have to be merged by hand.
pub(super) fn section_names(cx: &Context<'_>, out: &mut Planned) {
    let doc = cx.document;
    let by_header: HashMap<usize, usize> = doc
        .sections()
        .iter()
        .enumerate()
        .map(|(i, s)| (s.header_line, i))
        .collect();
    let mut done = HashSet::new();
    for diagnostic in cx.diagnostics {
        if diagnostic.code != Code::NonCanonicalSectionName {
            continue;
        }
        let line = usize::try_from(diagnostic.span.line)
            .unwrap_or(usize::MAX)
            .saturating_sub(1);
        let Some(&index) = by_header.get(&line) else {
            continue;
        };
        if !done.insert(index) {
            continue;
        }
        let Some(section) = doc.sections().get(index) else {
            continue;
        };
        let written = doc.section_name(section);
        let kind = section_name::classify(written);
        let Some(canonical) = section_name::canonical_name(kind.identity()) else {
            continue;
        };
        if canonical == written {
            continue;
        }
        let Some(content) = splice(doc, line, &section.name, &canonical) else {
            continue;
        };
        let fix = Fix {
            code: "P031".to_owned(),
            description: format!("[{written}] -> [{canonical}]"),
            changes_meaning: false,
            edits: vec![Edit::ReplaceLine { line, content }],
        };
        let clash = doc
            .sections_named(&canonical)
            .iter()
            .chain(cx.sections_of(kind))
            .copied()
            .find(|&other| other != index)
            .and_then(|other| doc.sections().get(other));
        match clash {
            Some(other) => out.refused.push((
                fix,
                format!(
                    "section [{}] on line {} already describes the same thing; merge the two sections first",
                    doc.section_name(other),
                    other.header_line + 1
                ),
            )),
            None => out.fixes.push(fix),
        }
    }
}

/// P032: rewrites every key the loader reads with a case other than CiA 306's (python canopen
/// looks keys up case-sensitively). One fix per spelling, as the loader reports one finding per
/// spelling. Only the sections the loader reads are touched: the first of duplicated sections, the
/// first of repeated keys.
pub(super) fn key_case(cx: &Context<'_>, out: &mut Planned) {
    if !cx.diagnostics.iter().any(|d| d.code == Code::KeyCase) {
        return;
    }
    let doc = cx.document;
    // (written, canonical) -> (section name of the first occurrence, lines), in file order.
    let mut groups: Vec<((&str, &str), &str, Vec<usize>)> = Vec::new();
    let mut group_of: HashMap<(&str, &str), usize> = HashMap::new();
    for (index, section) in doc.sections().iter().enumerate() {
        let name = doc.section_name(section);
        let kind = section_name::classify(name);
        if cx.sections_of(kind).first() != Some(&index) {
            continue;
        }
        let Some(keys) = known_keys(kind) else { continue };
        let mut seen: HashSet<String> = HashSet::new();
        for &line in doc.entries(section) {
            let Some((key, _)) = doc.entry(line) else { continue };
            if !seen.insert(key.to_ascii_lowercase()) {
                continue;
            }
            let Some(&canonical) = keys.iter().find(|k| k.eq_ignore_ascii_case(key)) else {
                continue;
            };
            if canonical == key {
                continue;
            }
            let slot = *group_of.entry((key, canonical)).or_insert_with(|| {
                groups.push(((key, canonical), name, Vec::new()));
                groups.len() - 1
            });
            if let Some(group) = groups.get_mut(slot) {
                group.2.push(line);
            }
        }
    }
    for ((written, canonical), first_section, lines) in groups {
        let edits: Vec<Edit> = lines
            .iter()
            .filter_map(|&line| {
                Some(Edit::ReplaceLine {
                    line,
                    content: with_key(doc, line, canonical)?,
                })
            })
            .collect();
        let more = match edits.len() {
            0 => continue,
            1 => String::new(),
            n => format!(" (and {} more line(s))", n - 1),
        };
        out.fixes.push(Fix {
            code: "P032".to_owned(),
            description: format!("[{first_section}] key {written} -> {canonical}{more}"),
            changes_meaning: false,
            edits,
        });
    }
}

/// The keys CiA 306 defines for a section the loader reads key by key.
fn known_keys(kind: SectionKind) -> Option<&'static [&'static str]> {
    Some(match kind {
        SectionKind::FileInfo => FileInfo::KEYS,
        SectionKind::DeviceInfo => DeviceInfo::KEYS,
        SectionKind::Commissioning(_) => DeviceCommissioning::KEYS,
        SectionKind::Object(_) | SectionKind::Sub(..) => Attributes::KEYS,
        SectionKind::Module(_, ModulePart::Info) => ModuleInfo::KEYS,
        SectionKind::Module(
            _,
            ModulePart::Fixed(_)
            | ModulePart::FixedSub(..)
            | ModulePart::SubExt(_)
            | ModulePart::SubExtSub(..),
        ) => Attributes::KEYS,
        _ => return None,
    })
}

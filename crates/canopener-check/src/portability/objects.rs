//! Objects the tools build differently: compact arrays and their companion sections, missing keys,
//! custom data types, CompactPDO, object lists, PDO pairs and key spelling.

use std::collections::HashSet;

use canopener_eds::diag::Code;
use canopener_eds::model::{ObjectListKind, decimal_key, int_of};
use canopener_eds::section_name::{Companion, SectionKind};
use canopener_eds::{ObjectType, Origin};

use super::checks::{
    ARRAY_WITHOUT_SUB_NUMBER, COMPACT_LIMITS, COMPACT_NAMES_GAP, COMPACT_PDO_NO_MODULES, COMPACT_UNNAMED,
    COMPACT_VALUES_IGNORED, CUSTOM_DATA_TYPE, DOMAIN_WITHOUT_TYPES, KEY_CASE, LISTED_MISSING,
    TPDO_WITHOUT_MAPPING, UNKNOWN_KEYS, UNLISTED_OBJECT, VAR_MISSING_KEY,
};
use super::tools::{
    DCFCHK, EDITOR, HOST, Key, PY, Site, at_header, at_value, exact_entry, python_builds_variable,
    python_name_section, python_object_section, python_sub_section, views,
};
use crate::context::Context;
use crate::finding::Finding;

/// The checks of one object or sub-object section.
pub(super) fn site(cx: &Context<'_>, site: &Site<'_>, out: &mut Vec<Finding>) {
    missing_keys(cx, site, out);
    custom_data_type(cx, site, out);
    key_case(cx, site, out);
    if site.sub.is_none() && site.object.origin == Origin::Explicit {
        compact_array(cx, site, out);
        compact_limits(cx, site, out);
        array_without_sub_number(cx, site, out);
    }
}

/// The checks of the file as a whole.
pub(super) fn run(cx: &Context<'_>, out: &mut Vec<Finding>) {
    compact_values(cx, out);
    commissioning_key_case(cx, out);
    object_lists(cx, out);
    compact_pdo(cx, out);
    tpdo_pairs(cx, out);
    unknown_keys(cx, out);
}

/// T011 and T023: keys python canopen reads without a fallback.
fn missing_keys(cx: &Context<'_>, site: &Site<'_>, out: &mut Vec<Finding>) {
    let object_type = site.object_type;
    if site.sub.is_none() && object_type == Some(ObjectType::Domain) {
        let missing: Vec<&str> = [Key::DataType, Key::AccessType]
            .into_iter()
            .filter(|k| !site.has(*k))
            .map(Key::name)
            .collect();
        if !missing.is_empty() {
            let error = match missing.as_slice() {
                [one] => format!("NoOptionError: '{one}'"),
                _ => "NoOptionError".to_owned(),
            };
            out.push(at_header(
                cx,
                &DOMAIN_WITHOUT_TYPES,
                site.section,
                missing.first().copied(),
                format!(
                    "DOMAIN [{}] has no {}, which CiA 306 allows: {PY} crashes ({error}); Lely reads it as \
                     the spec says and {EDITOR} assumes DataType DOMAIN and AccessType rw",
                    site.name,
                    missing.join(" and ")
                ),
            ));
        }
    }
    let is_var = site.sub.is_some() || matches!(object_type, Some(ObjectType::Var));
    let keys: &[Key] = if is_var {
        &[Key::ParameterName, Key::DataType, Key::AccessType]
    } else {
        &[Key::ParameterName]
    };
    for &key in keys {
        if site.has(key) {
            continue;
        }
        let key = key.name();
        let mut parts = vec![format!("{PY} crashes (NoOptionError: '{key}')")];
        if key == "AccessType" {
            parts.push(format!("{DCFCHK} crashes (KeyError)"));
            parts.push(format!("{HOST} assumes ro"));
        }
        parts.push(format!("{EDITOR} silently drops [{}]", site.name));
        out.push(at_header(
            cx,
            &VAR_MISSING_KEY,
            site.section,
            Some(key),
            format!("[{}] has no {key}: {}", site.name, views(&parts)),
        ));
    }
}

/// T024: python canopen resolves a DataType above 0x1B only through `[<type>sub1]`.
fn custom_data_type(cx: &Context<'_>, site: &Site<'_>, out: &mut Vec<Finding>) {
    if !python_builds_variable(site) {
        return;
    }
    let Some(data_type) = site.written_type.filter(|t| t.0 > 0x1B) else {
        return;
    };
    let wanted = format!("{:X}sub1", data_type.0);
    let found = cx.document.sections_named(&wanted).iter().any(|&i| {
        cx.document.sections().get(i).is_some_and(|s| {
            cx.document.section_name(s) == wanted && exact_entry(cx, s, "DefaultValue").is_some()
        })
    });
    if found {
        return;
    }
    let intended = match site.data_type {
        Some(resolved) if resolved != data_type => format!(", while the file defines it as {resolved}"),
        _ => String::new(),
    };
    let Some(line) = site.line(Key::DataType) else {
        return;
    };
    out.push(at_value(
        cx,
        &CUSTOM_DATA_TYPE,
        site.name,
        line,
        format!(
            "DataType 0x{:04X} is not a basic type and there is no [{wanted}] with a DefaultValue: {PY} \
             reads the entry as DOMAIN (raw bytes){intended}",
            data_type.0
        ),
    ));
}

/// T037: keys python canopen reads, spelt in other letter case.
fn key_case(cx: &Context<'_>, site: &Site<'_>, out: &mut Vec<Finding>) {
    let python_sees = match site.sub {
        None => python_object_section(site.name),
        Some(_) => python_sub_section(site.name),
    };
    if !python_sees {
        return;
    }
    for &(line, key, canonical) in site.miscased() {
        if !PYTHON_OBJECT_KEYS.contains(&canonical) || site.has_exact(canonical) {
            continue;
        }
        let effect = match canonical {
            Key::ParameterName => format!("so it crashes (NoOptionError: '{}')", canonical.name()),
            Key::DataType | Key::AccessType if python_builds_variable(site) => {
                format!("so it crashes (NoOptionError: '{}')", canonical.name())
            }
            Key::ObjectType if site.sub.is_none() => "so it treats the object as a VAR".to_owned(),
            _ => "so the value is silently ignored there".to_owned(),
        };
        out.push(
            Finding::new(
                &KEY_CASE,
                cx.document.key_span(line),
                format!(
                    "`{key}` is not spelt `{}`: {PY} matches keys case-sensitively and does not see it, \
                     {effect}; Lely reads it",
                    canonical.name()
                ),
            )
            .at(Some(site.name), Some(key)),
        );
    }
}

/// The object keys python canopen reads (`eds-format-and-checks.md` §11.1).
const PYTHON_OBJECT_KEYS: &[Key] = &[
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
];

/// T037 for `[DeviceComissioning]`: python canopen reads NodeID and Baudrate from it.
fn commissioning_key_case(cx: &Context<'_>, out: &mut Vec<Finding>) {
    for &i in cx.sections_of(SectionKind::Commissioning(
        canopener_eds::model::CommissioningSpelling::DeviceComissioning,
    )) {
        let Some(section) = cx.document.sections().get(i) else {
            continue;
        };
        let name = cx.document.section_name(section);
        if name != "DeviceComissioning" {
            continue;
        }
        for canonical in ["NodeID", "Baudrate"] {
            if exact_entry(cx, section, canonical).is_some() {
                continue;
            }
            let Some(line) = cx.document.find_entry(section, canonical) else {
                continue;
            };
            let Some((key, _)) = cx.document.entry(line) else {
                continue;
            };
            out.push(
                Finding::new(
                    &KEY_CASE,
                    cx.document.key_span(line),
                    format!(
                        "`{key}` is not spelt `{canonical}`: {PY} matches keys case-sensitively and does not \
                         see it, so the DCF's {canonical} is not applied there; Lely reads it"
                    ),
                )
                .at(Some(name), Some(key)),
            );
        }
        break;
    }
}

/// T001 and T002: compact arrays python canopen builds partly or crashes on.
fn compact_array(cx: &Context<'_>, site: &Site<'_>, out: &mut Vec<Finding>) {
    if site.object_type != Some(ObjectType::Array) {
        return;
    }
    let n = site.compact.min(254);
    if n == 0 {
        return;
    }
    let name = site.object.name();
    let names_section = cx
        .sections_of(SectionKind::Companion(site.index, Companion::Name))
        .first()
        .and_then(|&i| cx.document.sections().get(i));
    // Point at the CompactSubObj value when it is written in this section.
    let at = |info, message: String| match site.line(Key::CompactSubObj) {
        Some(line) => at_value(cx, info, site.name, line, message),
        None => at_header(cx, info, site.section, Some("CompactSubObj"), message),
    };
    let Some(names_section) = names_section else {
        let (others, editor) = if n == 1 {
            (String::new(), format!("`{name}01` instead of `{name}1`"))
        } else {
            (
                format!(" (the others appear only when accessed, named `{name}_<hex>`)"),
                format!("`{name}01`..`{name}{n:02x}` instead of `{name}1`..`{name}{n}`"),
            )
        };
        out.push(at(
            &COMPACT_UNNAMED,
            format!(
                "CompactSubObj={n} without [{:X}Name]: {}",
                site.index,
                views(&[
                    format!("{PY} creates only sub 0 (default None) and sub 1{others}"),
                    format!("{HOST} reads a single VAR"),
                    format!("{EDITOR} names the sub-objects {editor}"),
                    format!("Lely creates all {n} as CiA 306 says"),
                ])
            ),
        ));
        return;
    };
    let names_name = cx.document.section_name(names_section);
    if !python_name_section(names_name) {
        // python canopen does not see the section at all; T038 says so.
        return;
    }
    let Some(count_line) = exact_entry(cx, names_section, "NrOfEntries") else {
        return;
    };
    let Some(count) = cx
        .document
        .entry(count_line)
        .and_then(|(_, v)| int_of(v))
        .and_then(|v| u64::try_from(v).ok())
    else {
        return;
    };
    let present: HashSet<u64> = cx
        .document
        .entries(names_section)
        .iter()
        .filter_map(|&l| cx.document.entry(l))
        .filter_map(|(k, _)| decimal_key(k).map(u64::from))
        .collect();
    if let Some(gap) = (1..=count.min(254)).find(|k| !present.contains(k)) {
        out.push(at_value(
            cx,
            &COMPACT_NAMES_GAP,
            names_name,
            count_line,
            format!(
                "[{names_name}] has NrOfEntries={count} but no entry `{gap}` (CiA 306 allows sparse names): \
                 {}",
                views(&[
                    format!("{PY} crashes (NoOptionError: '{gap}')"),
                    "Lely reads the sparse names".to_owned(),
                    format!("{HOST} and {EDITOR} ignore the names"),
                ])
            ),
        ));
        return;
    }
    let created = count.max(1);
    if created < n {
        out.push(at(
            &COMPACT_UNNAMED,
            format!(
                "CompactSubObj={n} but [{names_name}] has NrOfEntries={count}: {PY} creates only sub 0 to \
                 sub {created} (the others appear only when accessed); Lely creates all {n}"
            ),
        ));
    }
}

/// T031: CANopenEditor copies LowLimit into HighLimit when it expands a compact array.
fn compact_limits(cx: &Context<'_>, site: &Site<'_>, out: &mut Vec<Finding>) {
    let attributes = site.attributes;
    if site.compact == 0
        || !matches!(
            site.object_type,
            Some(ObjectType::Array | ObjectType::Record | ObjectType::DefStruct)
        )
    {
        return;
    }
    let Some(low) = attributes.low_limit.as_deref().filter(|l| !l.trim().is_empty()) else {
        return;
    };
    let high = attributes.high_limit.as_deref().filter(|h| !h.trim().is_empty());
    if high == Some(low) {
        return;
    }
    let Some(line) = site.line(Key::LowLimit) else {
        return;
    };
    let range = high.map_or_else(|| format!("{low}.. (no upper limit)"), |h| format!("{low}..{h}"));
    out.push(at_value(
        cx,
        &COMPACT_LIMITS,
        site.name,
        line,
        format!(
            "{EDITOR} copies LowLimit into HighLimit when it expands CompactSubObj, so there the sub-objects \
             get the range {low}..{low} instead of {range}"
        ),
    ));
}

/// T033: CANopenEditor drops an ARRAY or RECORD without SubNumber.
fn array_without_sub_number(cx: &Context<'_>, site: &Site<'_>, out: &mut Vec<Finding>) {
    if !matches!(
        site.object_type,
        Some(ObjectType::Array | ObjectType::Record | ObjectType::DefStruct)
    ) || site.compact != 0
        || site.has(Key::SubNumber)
        || site.has(Key::CompactSubObj)
    {
        return;
    }
    out.push(at_header(
        cx,
        &ARRAY_WITHOUT_SUB_NUMBER,
        site.section,
        Some("SubNumber"),
        format!(
            "[{}] has neither SubNumber nor CompactSubObj: {EDITOR} silently drops the object; Lely's loader \
             also requires one of the two; {PY} loads it from its sub-sections",
            site.name
        ),
    ));
}

/// T030: DCF values of compact arrays that python canopen and CANopenEditor never read, once per
/// file (every such section is lost the same way).
fn compact_values(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let mut sections = Vec::new();
    let mut values = 0;
    for (index, object) in &cx.eds.objects {
        let Some(written) = &object.values else { continue };
        if object.attributes.compact_sub_obj() == 0 {
            continue;
        }
        let count = written.numbered().count();
        let section = cx
            .sections_of(SectionKind::Companion(*index, Companion::Value))
            .first()
            .and_then(|&i| cx.document.sections().get(i));
        if let (Some(section), 1..) = (section, count) {
            sections.push(section);
            values += count;
        }
    }
    let Some(first) = sections.first() else { return };
    let names = listing(
        sections
            .iter()
            .map(|s| format!("[{}]", cx.document.section_name(s))),
    );
    out.push(at_header(
        cx,
        &COMPACT_VALUES_IGNORED,
        first,
        None,
        format!(
            "{PY} and {EDITOR} do not read {names}, so {values} configured value(s) are silently replaced by \
             the DefaultValue there; Lely reads them"
        ),
    ));
}

/// `a, b, c and 4 more`: the first few items of a list that may be long.
fn listing(items: impl Iterator<Item = String>) -> String {
    const SHOWN: usize = 3;
    let items: Vec<String> = items.collect();
    let shown = items.iter().take(SHOWN).cloned().collect::<Vec<_>>().join(", ");
    match items.len().saturating_sub(SHOWN) {
        0 => shown,
        more => format!("{shown} and {more} more"),
    }
}

/// T013 and T014: which tools load what the object lists say, once per file each (the loader's
/// P042 and P043 name every object).
fn object_lists(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let mut listed = HashSet::new();
    let mut missing: Vec<(ObjectListKind, String, u16)> = Vec::new();
    for kind in ObjectListKind::ALL {
        let Some(list) = cx.eds.object_lists.get(&kind) else {
            continue;
        };
        for (n, value) in list.0.numbered() {
            let Some(index) = int_of(value).and_then(|v| u16::try_from(v).ok()) else {
                continue;
            };
            listed.insert(index);
            let exists = cx
                .eds
                .objects
                .get(&index)
                .is_some_and(|o| o.origin != Origin::Orphan);
            if !exists {
                missing.push((kind, n.to_string(), index));
            }
        }
    }
    if let Some((kind, key, _)) = missing.first() {
        let indices = listing(missing.iter().map(|(_, _, i)| format!("{i:X}h")));
        out.push(cx.finding(
            &LISTED_MISSING,
            SectionKind::ObjectList(*kind),
            Some(key),
            format!(
                "the object lists name {indices} without a section: {DCFCHK} reports \"object not found\"; \
                 {PY}, {HOST} and {EDITOR} load the file without {them} and without a word",
                them = if missing.len() == 1 { "it" } else { "them" }
            ),
        ));
    }
    let unlisted: Vec<u16> = cx
        .eds
        .objects
        .iter()
        .filter(|(index, object)| object.origin == Origin::Explicit && !listed.contains(*index))
        .map(|(index, _)| *index)
        .collect();
    let Some(section) = unlisted
        .iter()
        .filter_map(|&i| cx.section(SectionKind::Object(i)))
        .min_by_key(|s| s.header_line)
    else {
        return;
    };
    let indices = listing(unlisted.iter().map(|i| format!("{i:X}h")));
    out.push(at_header(
        cx,
        &UNLISTED_OBJECT,
        section,
        None,
        format!(
            "no object list names {indices}: Lely's loader reads only listed objects and silently leaves \
             {them} out, and {DCFCHK} does not say so; {PY}, {HOST} and {EDITOR} load {them}",
            them = if unlisted.len() == 1 { "it" } else { "them" }
        ),
    ));
}

/// T029: CANopenEditor expands CompactPDO only when the file has `[SupportedModules]`.
fn compact_pdo(cx: &Context<'_>, out: &mut Vec<Finding>) {
    if cx.section(SectionKind::SupportedModules).is_some() {
        return;
    }
    let implied: Vec<u16> = cx
        .eds
        .objects
        .iter()
        .filter(|(i, o)| o.origin == Origin::CompactPdo && matches!(**i, 0x1400..=0x15FF | 0x1800..=0x19FF))
        .map(|(i, _)| *i)
        .collect();
    let Some(first) = implied.first() else { return };
    let list = if implied.len() == 1 {
        format!("object {first:X}h with its mapping object")
    } else {
        format!(
            "objects {first:X}h and {} more with their mapping objects",
            implied.len() - 1
        )
    };
    out.push(cx.finding(
        &COMPACT_PDO_NO_MODULES,
        SectionKind::DeviceInfo,
        Some("CompactPDO"),
        format!(
            "CompactPDO implies the PDO communication {list}: {EDITOR} expands CompactPDO only when \
             [SupportedModules] exists, so they are silently missing there; Lely's loader builds them"
        ),
    ));
}

/// T035: Lely dcfchk crashes on a TPDO communication object without its mapping object.
fn tpdo_pairs(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let present = |index: u16| {
        cx.eds
            .objects
            .get(&index)
            .is_some_and(|o| o.origin != Origin::Orphan)
    };
    for (&index, object) in cx.eds.objects.range(0x1800..=0x19FF) {
        let mapping = index + 0x200;
        if object.origin == Origin::Orphan || present(mapping) {
            continue;
        }
        let Some(section) = cx.section(SectionKind::Object(index)) else {
            continue;
        };
        out.push(at_header(
            cx,
            &TPDO_WITHOUT_MAPPING,
            section,
            None,
            format!(
                "TPDO communication object {index:X}h has no mapping object {mapping:X}h: {DCFCHK} crashes \
                 (KeyError: {mapping}) instead of reporting it; {PY} loads the file"
            ),
        ));
    }
}

/// T039: one summary of the keys CiA 306 does not define, which dcfchk rejects one by one.
fn unknown_keys(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let unknown: Vec<_> = cx
        .diagnostics
        .iter()
        .filter(|d| d.code == Code::UnknownKey)
        .collect();
    let Some(first) = unknown.first() else { return };
    let key = first.key.as_deref().unwrap_or("?");
    let section = first.section.as_deref().unwrap_or("?");
    let (more, verb) = match unknown.len() - 1 {
        0 => (String::new(), "is"),
        n => (format!(" and {n} more key(s)"), "are"),
    };
    out.push(
        Finding::new(
            &UNKNOWN_KEYS,
            first.span,
            format!(
                "`{key}` in [{section}]{more} {verb} not defined by CiA 306: {DCFCHK} reports each unknown \
                 key as an error"
            ),
        )
        .at(first.section.as_deref(), first.key.as_deref()),
    );
}

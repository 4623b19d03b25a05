//! Writers: the canonical CiA 306 formatter and the lossless writer.
//!
//! Both start from the same list of sections the model describes ([`model_sections`]). The canonical
//! formatter prints them in CiA 306 order with canonical section names and key spelling, CR/LF line
//! endings and `key=value` without spaces; values are written as they are in the model, so the radix
//! of every number and the symbolic `$NODEID` formulas stay. Comment lines of the source document
//! move with the section they are in. The lossless writer edits the source [`Document`] instead: a
//! section or key the model does not change keeps every byte, a changed value rewrites one line, a
//! new key or section is inserted, and a removed one deleted.

use std::collections::{HashMap, HashSet};

use crate::model::{Attributes, Eds, Object, ObjectListKind, Origin, Properties};
use crate::section_name::{self, SectionKind};
use crate::syntax::{Document, LineKind, Section};

/// A section as the model describes it: its CiA 306 name and its entries.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ModelSection {
    /// The section name in CiA 306 spelling (unknown sections keep theirs).
    pub name: String,
    /// Key/value pairs in canonical order.
    pub entries: Vec<(String, String)>,
}

/// The sections of a model in canonical CiA 306 order.
///
/// Order: FileInfo, DeviceInfo, DummyUsage, Comments, then each object list followed by its objects
/// (ascending), objects no list names, Tools, DynamicChannels, modules, DeviceComissioning,
/// ConnectedModules and the sections canopener does not interpret. Generated objects and sub-objects
/// (CompactSubObj, CompactPDO) are not written: the compact keys imply them.
pub fn model_sections(eds: &Eds) -> Vec<ModelSection> {
    let mut out = Vec::new();
    out.push(keyed("FileInfo", eds.file_info.entries()));
    out.push(keyed("DeviceInfo", eds.device_info.entries()));
    if let Some(p) = &eds.dummy_usage {
        out.push(props("DummyUsage", p));
    }
    if let Some(p) = &eds.comments {
        out.push(props("Comments", p));
    }
    let mut written: HashSet<u16> = HashSet::new();
    for kind in ObjectListKind::ALL {
        let Some(list) = eds.object_lists.get(&kind) else {
            continue;
        };
        out.push(props(kind.section_name(), &list.0));
        let mut indices = list.indices();
        indices.sort_unstable();
        for index in indices {
            if let Some(object) = eds.objects.get(&index)
                && written.insert(index)
            {
                push_object(&mut out, "", index, object);
            }
        }
    }
    for (index, object) in &eds.objects {
        if written.insert(*index) {
            push_object(&mut out, "", *index, object);
        }
    }
    if let Some(p) = &eds.tools {
        out.push(props("Tools", p));
    }
    for (n, p) in &eds.tool_sections {
        out.push(props(&format!("Tool{n}"), p));
    }
    if let Some(p) = &eds.dynamic_channels {
        out.push(props("DynamicChannels", p));
    }
    if let Some(p) = &eds.supported_modules {
        out.push(props("SupportedModules", p));
    }
    for (x, module) in &eds.modules {
        out.push(keyed(&format!("M{x}ModuleInfo"), module.info.entries()));
        if let Some(p) = &module.comments {
            out.push(props(&format!("M{x}Comments"), p));
        }
        if let Some(p) = &module.fixed_objects {
            out.push(props(&format!("M{x}FixedObjects"), p));
        }
        for (index, object) in &module.fixed {
            push_object(&mut out, &format!("M{x}Fixed"), *index, object);
        }
        if let Some(p) = &module.sub_extends {
            out.push(props(&format!("M{x}SubExtends"), p));
        }
        for (index, object) in &module.sub_ext {
            push_object(&mut out, &format!("M{x}SubExt"), *index, object);
        }
    }
    if let Some(c) = &eds.commissioning {
        out.push(keyed(eds.commissioning_spelling.section_name(), c.entries()));
    }
    if let Some(p) = &eds.connected_modules {
        out.push(props("ConnectedModules", p));
    }
    for section in &eds.other_sections {
        out.push(props(&section.name, &section.entries));
    }
    out
}

/// Whether the canonical text of `eds` ([`model_sections`]) has a section of this kind, without
/// writing it: what checks ask of a model read from another format (CiA 311 XML), which has no
/// document to look in.
pub fn model_has_section(eds: &Eds, kind: SectionKind) -> bool {
    let written = |o: &&Object| matches!(o.origin, Origin::Explicit | Origin::Orphan);
    match kind {
        SectionKind::FileInfo | SectionKind::DeviceInfo => true,
        SectionKind::DummyUsage => eds.dummy_usage.is_some(),
        SectionKind::Comments => eds.comments.is_some(),
        SectionKind::ObjectList(list) => eds.object_lists.contains_key(&list),
        SectionKind::Commissioning(_) => eds.commissioning.is_some(),
        SectionKind::Tools => eds.tools.is_some(),
        SectionKind::Tool(n) => eds.tool_sections.contains_key(&n),
        SectionKind::DynamicChannels => eds.dynamic_channels.is_some(),
        SectionKind::SupportedModules => eds.supported_modules.is_some(),
        SectionKind::ConnectedModules => eds.connected_modules.is_some(),
        SectionKind::Object(index) => eds
            .objects
            .get(&index)
            .is_some_and(|o| o.origin == Origin::Explicit),
        SectionKind::Sub(index, sub) => eds
            .objects
            .get(&index)
            .filter(written)
            .and_then(|o| o.subs.get(&sub))
            .is_some_and(|s| s.origin.is_written()),
        SectionKind::Companion(index, companion) => eds
            .objects
            .get(&index)
            .filter(written)
            .is_some_and(|o| companion_of(o, companion).is_some()),
        SectionKind::Module(x, _) => eds.modules.contains_key(&x),
        SectionKind::Unknown => false,
    }
}

/// The entry `key` (any letter case) of the section of this kind in the canonical text of `eds`, as
/// that text writes it: the key in canonical spelling and its value. Module sections are not looked in.
pub fn model_entry<'a>(eds: &'a Eds, kind: SectionKind, key: &str) -> Option<(&'a str, &'a str)> {
    if !model_has_section(eds, kind) {
        return None;
    }
    let find =
        |entries: Vec<(&'a str, &'a str)>| entries.into_iter().find(|(k, _)| k.eq_ignore_ascii_case(key));
    let property = |p: Option<&'a Properties>| {
        p?.0.iter()
            .find(|p| p.key.eq_ignore_ascii_case(key))
            .map(|p| (p.key.as_str(), p.value.as_str()))
    };
    match kind {
        SectionKind::FileInfo => find(eds.file_info.entries()),
        SectionKind::DeviceInfo => find(eds.device_info.entries()),
        SectionKind::Commissioning(_) => find(eds.commissioning.as_ref()?.entries()),
        SectionKind::Object(index) => find(eds.objects.get(&index)?.attributes.entries()),
        SectionKind::Sub(index, sub) => find(eds.objects.get(&index)?.subs.get(&sub)?.attributes.entries()),
        SectionKind::Companion(index, companion) => {
            property(companion_of(eds.objects.get(&index)?, companion))
        }
        SectionKind::ObjectList(list) => property(eds.object_lists.get(&list).map(|l| &l.0)),
        SectionKind::DummyUsage => property(eds.dummy_usage.as_ref()),
        SectionKind::Comments => property(eds.comments.as_ref()),
        SectionKind::Tools => property(eds.tools.as_ref()),
        SectionKind::Tool(n) => property(eds.tool_sections.get(&n)),
        SectionKind::DynamicChannels => property(eds.dynamic_channels.as_ref()),
        SectionKind::SupportedModules => property(eds.supported_modules.as_ref()),
        SectionKind::ConnectedModules => property(eds.connected_modules.as_ref()),
        SectionKind::Module(..) | SectionKind::Unknown => None,
    }
}

fn companion_of(object: &Object, companion: section_name::Companion) -> Option<&Properties> {
    match companion {
        section_name::Companion::Name => object.names.as_ref(),
        section_name::Companion::Value => object.values.as_ref(),
        section_name::Companion::Denotation => object.denotations.as_ref(),
        section_name::Companion::ObjectLinks => object.object_links.as_ref(),
    }
}

/// Canonical CiA 306 text of a model. With the source `document`, its comment lines are kept, each
/// in the section it was in (those before the first section stay at the top).
pub fn to_canonical(eds: &Eds, document: Option<&Document>) -> String {
    let comments = document.map(comments_by_section).unwrap_or_default();
    let mut out = String::new();
    if let Some(head) = comments.get(&None) {
        for line in head {
            out.push_str(line);
            out.push_str("\r\n");
        }
        if !head.is_empty() {
            out.push_str("\r\n");
        }
    }
    for (i, section) in model_sections(eds).iter().enumerate() {
        if i > 0 {
            out.push_str("\r\n");
        }
        out.push('[');
        out.push_str(&section.name);
        out.push_str("]\r\n");
        if let Some(lines) = comments.get(&Some(identity(&section.name))) {
            for line in lines {
                out.push_str(line);
                out.push_str("\r\n");
            }
        }
        for (key, value) in &section.entries {
            out.push_str(key);
            out.push('=');
            out.push_str(value);
            out.push_str("\r\n");
        }
    }
    out
}

/// Writes the model back into its source document, changing only the lines that must change.
///
/// An unchanged model gives back the document byte for byte. Key spelling, spacing, comments, blank
/// lines and line endings of untouched lines are kept; repeated sections and keys (which the model
/// ignores) are kept unless the key or section they repeat is removed.
pub fn write_lossless(document: &Document, eds: &Eds) -> Document {
    let mut by_identity: HashMap<(SectionKind, String), Vec<usize>> = HashMap::new();
    for (i, section) in document.sections().iter().enumerate() {
        by_identity
            .entry(identity(document.section_name(section)))
            .or_default()
            .push(i);
    }
    let mut editor = document.editor();
    let mut kept: HashSet<(SectionKind, String)> = HashSet::new();
    for model in model_sections(eds) {
        let id = identity(&model.name);
        kept.insert(id.clone());
        let Some(first) = by_identity
            .get(&id)
            .and_then(|v| v.first())
            .and_then(|&i| document.sections().get(i))
        else {
            if !model.entries.is_empty() || !is_info_section(&id.0) {
                let mut lines = vec![String::new(), format!("[{}]", model.name)];
                lines.extend(model.entries.iter().map(|(k, v)| format!("{k}={v}")));
                editor.append(lines);
            }
            continue;
        };
        sync_section(document, first, &model, &mut editor);
    }
    for (id, sections) in &by_identity {
        if kept.contains(id) {
            continue;
        }
        for &i in sections {
            if let Some(section) = document.sections().get(i) {
                editor.delete_line(section.header_line);
                for line in section.body.clone() {
                    editor.delete_line(line);
                }
            }
        }
    }
    editor.apply()
}

fn sync_section(
    document: &Document,
    section: &Section,
    model: &ModelSection,
    editor: &mut crate::syntax::Editor<'_>,
) {
    let mut model_keys: HashSet<String> = HashSet::new();
    let mut appended = Vec::new();
    for (key, value) in &model.entries {
        model_keys.insert(key.to_ascii_lowercase());
        match document.find_entry(section, key) {
            Some(line) => {
                if document.entry(line).is_some_and(|(_, v)| v != value) {
                    editor.set_value(line, value);
                }
            }
            None => appended.push(format!("{key}={value}")),
        }
    }
    if !appended.is_empty() {
        editor.append_to_section(section, appended);
    }
    for &line in document.entries(section) {
        if let Some((key, _)) = document.entry(line)
            && !model_keys.contains(&key.to_ascii_lowercase())
        {
            editor.delete_line(line);
        }
    }
}

fn is_info_section(kind: &SectionKind) -> bool {
    matches!(kind, SectionKind::FileInfo | SectionKind::DeviceInfo)
}

/// How sections are matched between a model and a document (the loader's notion of "the same section").
fn identity(name: &str) -> (SectionKind, String) {
    let kind = section_name::classify(name);
    (
        kind.identity(),
        if kind == SectionKind::Unknown {
            name.to_ascii_lowercase()
        } else {
            String::new()
        },
    )
}

fn comments_by_section(document: &Document) -> HashMap<Option<(SectionKind, String)>, Vec<String>> {
    let mut out: HashMap<Option<(SectionKind, String)>, Vec<String>> = HashMap::new();
    let mut current: Option<(SectionKind, String)> = None;
    for (i, line) in document.lines().iter().enumerate() {
        match &line.kind {
            LineKind::Header { .. } => {
                let name = document
                    .sections()
                    .iter()
                    .find(|s| s.header_line == i)
                    .map(|s| document.section_name(s));
                current = name.map(identity);
            }
            LineKind::Comment => out
                .entry(current.clone())
                .or_default()
                .push(document.line_text(i).trim().to_owned()),
            _ => {}
        }
    }
    out
}

fn keyed(name: &str, entries: Vec<(&str, &str)>) -> ModelSection {
    ModelSection {
        name: name.to_owned(),
        entries: entries
            .into_iter()
            .map(|(k, v)| (k.to_owned(), v.to_owned()))
            .collect(),
    }
}

fn props(name: &str, p: &Properties) -> ModelSection {
    ModelSection {
        name: name.to_owned(),
        entries: p.0.iter().map(|p| (p.key.clone(), p.value.clone())).collect(),
    }
}

fn push_object(out: &mut Vec<ModelSection>, prefix: &str, index: u16, object: &Object) {
    if object.origin == Origin::Explicit {
        out.push(attributes(&format!("{prefix}{index:X}"), &object.attributes));
    }
    if matches!(object.origin, Origin::Explicit | Origin::Orphan) {
        for (sub, sub_object) in &object.subs {
            if sub_object.origin.is_written() {
                out.push(attributes(
                    &format!("{prefix}{index:X}sub{sub:X}"),
                    &sub_object.attributes,
                ));
            }
        }
        for (suffix, companion) in [
            ("Name", &object.names),
            ("Value", &object.values),
            ("Denotation", &object.denotations),
            ("ObjectLinks", &object.object_links),
        ] {
            if let Some(p) = companion {
                out.push(props(&format!("{prefix}{index:X}{suffix}"), p));
            }
        }
    }
}

fn attributes(name: &str, a: &Attributes) -> ModelSection {
    keyed(name, a.entries())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::load;

    const SAMPLE: &str = "; written by hand\r\n[DeviceInfo]\r\nvendorname = ACME \r\n\r\n[FileInfo]\r\nFileName=x.eds\r\n\
        [1000]\r\nParameterName=Device type\r\nDataType=0x0007\r\nAccessType=ro\r\n; profile 401\r\nDefaultValue=0x191\r\n\
        [MandatoryObjects]\r\nSupportedObjects=1\r\n1=0x1000\r\n[2000]\r\nParameterName=Arr\r\nObjectType=0x8\r\n\
        DataType=0x0005\r\nAccessType=rw\r\nCompactSubObj=2\r\n";

    /// What the model says it writes is what its canonical text has: every section of
    /// [`model_sections`] exists for [`model_has_section`], and [`model_entry`] finds its entries.
    #[test]
    fn model_lookups_agree_with_the_canonical_text() {
        let text = format!(
            "{SAMPLE}[DummyUsage]\r\nDummy0005=1\r\n[2000Name]\r\nNrOfEntries=1\r\n1=first\r\n\
             [DeviceComissioning]\r\nNodeID=5\r\n[1018]\r\nParameterName=Identity\r\nObjectType=0x9\r\n\
             SubNumber=2\r\n[1018sub0]\r\nParameterName=n\r\nDataType=0x0005\r\nAccessType=ro\r\n\
             DefaultValue=1\r\n[1018sub1]\r\nParameterName=Vendor\r\nDataType=0x0007\r\nAccessType=ro\r\n"
        );
        let eds = load(text.as_bytes()).eds;
        let sections = model_sections(&eds);
        assert!(sections.len() > 8);
        for section in &sections {
            let kind = section_name::classify(&section.name);
            assert!(model_has_section(&eds, kind), "{}", section.name);
            for (key, value) in &section.entries {
                let upper = key.to_ascii_uppercase();
                assert_eq!(
                    model_entry(&eds, kind, &upper),
                    Some((key.as_str(), value.as_str())),
                    "[{}] {key}",
                    section.name
                );
            }
        }
        // CompactSubObj sub-objects are generated, not written; absent sections are absent.
        for kind in [
            SectionKind::Sub(0x2000, 1),
            SectionKind::Object(0x6000),
            SectionKind::DynamicChannels,
            SectionKind::Comments,
        ] {
            assert!(!model_has_section(&eds, kind), "{kind:?}");
        }
        assert_eq!(model_entry(&eds, SectionKind::Object(0x1000), "Nope"), None);
    }

    #[test]
    fn unchanged_model_writes_back_identically() {
        let loaded = load(SAMPLE.as_bytes());
        let written = write_lossless(&loaded.document, &loaded.eds);
        assert_eq!(written.text(), SAMPLE);
    }

    #[test]
    fn an_edit_changes_only_its_line() {
        let loaded = load(SAMPLE.as_bytes());
        let mut eds = loaded.eds.clone();
        eds.objects.get_mut(&0x1000).unwrap().attributes.default_value = Some("0x20191".to_owned());
        eds.device_info.set("VendorNumber", "0x1234");
        eds.objects.remove(&0x2000);
        let written = write_lossless(&loaded.document, &eds);
        assert_eq!(
            written.text(),
            SAMPLE
                .replace("DefaultValue=0x191", "DefaultValue=0x20191")
                .replace("vendorname = ACME \r\n", "vendorname = ACME \r\nVendorNumber=0x1234\r\n")
                .replace("[2000]\r\nParameterName=Arr\r\nObjectType=0x8\r\nDataType=0x0005\r\nAccessType=rw\r\nCompactSubObj=2\r\n", "")
        );
    }

    #[test]
    fn canonical_text_orders_sections_and_keeps_comments() {
        let loaded = load(SAMPLE.as_bytes());
        let text = to_canonical(&loaded.eds, Some(&loaded.document));
        assert_eq!(
            text,
            "; written by hand\r\n\r\n[FileInfo]\r\nFileName=x.eds\r\n\r\n[DeviceInfo]\r\nVendorName=ACME\r\n\r\n\
             [MandatoryObjects]\r\nSupportedObjects=1\r\n1=0x1000\r\n\r\n[1000]\r\n; profile 401\r\n\
             ParameterName=Device type\r\nDataType=0x0007\r\nAccessType=ro\r\nDefaultValue=0x191\r\n\r\n\
             [2000]\r\nParameterName=Arr\r\nObjectType=0x8\r\nDataType=0x0005\r\nAccessType=rw\r\nCompactSubObj=2\r\n"
        );
        let again = load(text.as_bytes());
        assert_eq!(again.eds, loaded.eds);
        assert_eq!(
            to_canonical(&again.eds, Some(&again.document)),
            text,
            "formatting is idempotent"
        );
    }
}

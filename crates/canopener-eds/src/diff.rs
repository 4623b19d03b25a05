//! Semantic difference of two EDS/DCF models: what a device description says differently, ignoring
//! how it is written (number notation, key case, section order, compact forms, comments).
//!
//! Changes to `[FileInfo]` (file metadata) are listed but do not make two descriptions different;
//! everything else does: device information, dummy usage, objects and sub-objects with their
//! attributes, DCF commissioning, modules and sections canopener does not interpret.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;

use serde::Serialize;

use crate::model::{
    Attributes, DeviceInfo, Eds, Object, Origin, Properties, REPRESENTATION_KEYS, SUB_CARRIED_KEYS, int_of,
};
use crate::types::DataType;
use crate::value::parse_value;

/// What happened to an item.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ChangeKind {
    /// Only in the second file.
    Added,
    /// Only in the first file.
    Removed,
    /// In both, with different meaning.
    Changed,
}

/// One difference.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Change {
    /// Added, removed or changed.
    pub kind: ChangeKind,
    /// The section it is in, in CiA 306 spelling (`1018sub1`, `DeviceInfo`).
    pub section: String,
    /// The key, or `None` when a whole section (object, sub-object) was added or removed.
    pub key: Option<String>,
    /// The value in the first file.
    pub old: Option<String>,
    /// The value in the second file.
    pub new: Option<String>,
    /// Whether it changes the description (false for `[FileInfo]` metadata).
    pub significant: bool,
}

impl fmt::Display for Change {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let sign = match self.kind {
            ChangeKind::Added => '+',
            ChangeKind::Removed => '-',
            ChangeKind::Changed => '~',
        };
        write!(f, "{sign} [{}]", self.section)?;
        if let Some(key) = &self.key {
            write!(f, " {key}")?;
        }
        match (&self.old, &self.new) {
            (Some(old), Some(new)) => write!(f, ": {old} -> {new}"),
            (Some(old), None) => write!(f, ": {old}"),
            (None, Some(new)) => write!(f, ": {new}"),
            (None, None) => Ok(()),
        }
    }
}

/// The differences between two models.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct Diff {
    /// Every difference, ordered by section.
    pub changes: Vec<Change>,
}

impl Diff {
    /// Whether both describe the same device and object dictionary (only metadata may differ).
    pub fn is_equivalent(&self) -> bool {
        self.changes.iter().all(|c| !c.significant)
    }

    /// The significant changes.
    pub fn significant(&self) -> impl Iterator<Item = &Change> {
        self.changes.iter().filter(|c| c.significant)
    }
}

/// Compares everything two files describe.
pub fn diff(a: &Eds, b: &Eds) -> Diff {
    let mut out = Vec::new();
    compare_pairs(
        "FileInfo",
        &a.file_info.entries(),
        &b.file_info.entries(),
        false,
        &mut out,
    );
    compare_pairs(
        "DeviceInfo",
        &a.device_info.entries(),
        &b.device_info.entries(),
        true,
        &mut out,
    );
    compare_props(
        "DummyUsage",
        a.dummy_usage.as_ref(),
        b.dummy_usage.as_ref(),
        &mut out,
    );
    compare_objects("", &a.objects, a, &b.objects, b, &mut out);
    let commissioning = |e: &Eds| {
        e.commissioning
            .as_ref()
            .map(|c| c.entries().into_iter().map(own).collect::<Vec<_>>())
    };
    match (commissioning(a), commissioning(b)) {
        (Some(x), Some(y)) => compare_pairs("DeviceComissioning", &borrow(&x), &borrow(&y), true, &mut out),
        (Some(_), None) => out.push(section_change(ChangeKind::Removed, "DeviceComissioning")),
        (None, Some(_)) => out.push(section_change(ChangeKind::Added, "DeviceComissioning")),
        (None, None) => {}
    }
    compare_props(
        "SupportedModules",
        a.supported_modules.as_ref(),
        b.supported_modules.as_ref(),
        &mut out,
    );
    compare_props(
        "ConnectedModules",
        a.connected_modules.as_ref(),
        b.connected_modules.as_ref(),
        &mut out,
    );
    compare_props(
        "DynamicChannels",
        a.dynamic_channels.as_ref(),
        b.dynamic_channels.as_ref(),
        &mut out,
    );
    let modules: BTreeSet<u32> = a.modules.keys().chain(b.modules.keys()).copied().collect();
    for x in modules {
        let prefix = format!("M{x}");
        match (a.modules.get(&x), b.modules.get(&x)) {
            (Some(ma), Some(mb)) => {
                let info =
                    |m: &crate::model::Module| m.info.entries().into_iter().map(own).collect::<Vec<_>>();
                compare_pairs(
                    &format!("{prefix}ModuleInfo"),
                    &borrow(&info(ma)),
                    &borrow(&info(mb)),
                    true,
                    &mut out,
                );
                compare_objects(&format!("{prefix}Fixed"), &ma.fixed, a, &mb.fixed, b, &mut out);
                compare_objects(
                    &format!("{prefix}SubExt"),
                    &ma.sub_ext,
                    a,
                    &mb.sub_ext,
                    b,
                    &mut out,
                );
            }
            (Some(_), None) => out.push(section_change(
                ChangeKind::Removed,
                &format!("{prefix}ModuleInfo"),
            )),
            (None, Some(_)) => out.push(section_change(ChangeKind::Added, &format!("{prefix}ModuleInfo"))),
            (None, None) => {}
        }
    }
    let others = |e: &Eds| -> BTreeMap<String, Properties> {
        e.other_sections
            .iter()
            .map(|s| (s.name.to_ascii_lowercase(), s.entries.clone()))
            .collect()
    };
    let (oa, ob) = (others(a), others(b));
    let names: BTreeSet<&String> = oa.keys().chain(ob.keys()).collect();
    for name in names {
        compare_props(name, oa.get(name), ob.get(name), &mut out);
    }
    Diff { changes: out }
}

/// Compares only the object dictionaries (objects and sub-objects with their attributes).
pub fn diff_objects(a: &Eds, b: &Eds) -> Diff {
    let mut out = Vec::new();
    compare_objects("", &a.objects, a, &b.objects, b, &mut out);
    Diff { changes: out }
}

fn own((k, v): (&str, &str)) -> (String, String) {
    (k.to_owned(), v.to_owned())
}

fn borrow(pairs: &[(String, String)]) -> Vec<(&str, &str)> {
    pairs.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect()
}

fn section_change(kind: ChangeKind, section: &str) -> Change {
    Change {
        kind,
        section: section.to_owned(),
        key: None,
        old: None,
        new: None,
        significant: true,
    }
}

fn compare_props(section: &str, a: Option<&Properties>, b: Option<&Properties>, out: &mut Vec<Change>) {
    fn pairs(p: &Properties) -> Vec<(&str, &str)> {
        p.0.iter().map(|p| (p.key.as_str(), p.value.as_str())).collect()
    }
    match (a, b) {
        (Some(a), Some(b)) => compare_pairs(section, &pairs(a), &pairs(b), true, out),
        (Some(a), None) if !a.is_empty() => out.push(section_change(ChangeKind::Removed, section)),
        (None, Some(b)) if !b.is_empty() => out.push(section_change(ChangeKind::Added, section)),
        _ => {}
    }
}

/// Compares key/value lists; keys match case-insensitively, values by number when both are numbers.
fn compare_pairs(
    section: &str,
    a: &[(&str, &str)],
    b: &[(&str, &str)],
    significant: bool,
    out: &mut Vec<Change>,
) {
    let map = |pairs: &[(&str, &str)]| -> BTreeMap<String, (String, String)> {
        let mut m = BTreeMap::new();
        for (k, v) in pairs {
            m.entry(k.to_ascii_lowercase())
                .or_insert(((*k).to_owned(), (*v).to_owned()));
        }
        m
    };
    let (ma, mb) = (map(a), map(b));
    let keys: BTreeSet<&String> = ma.keys().chain(mb.keys()).collect();
    for key in keys {
        let change = match (ma.get(key), mb.get(key)) {
            (Some((k, va)), Some((_, vb))) if !same_text_value(va, vb) => {
                Some((ChangeKind::Changed, k, Some(va.clone()), Some(vb.clone())))
            }
            (Some((k, va)), None) if !absent_means(k, va) => {
                Some((ChangeKind::Removed, k, Some(va.clone()), None))
            }
            (None, Some((k, vb))) if !absent_means(k, vb) => {
                Some((ChangeKind::Added, k, None, Some(vb.clone())))
            }
            _ => None,
        };
        if let Some((kind, k, old, new)) = change {
            out.push(Change {
                kind,
                section: section.to_owned(),
                key: Some(k.clone()),
                old,
                new,
                significant,
            });
        }
    }
}

/// Keys whose absence means 0 (CiA 306 §4.5: a flag not set, no compact PDOs, no dynamic channels), so
/// `CompactPDO=0` on one side and nothing on the other describe the same device.
fn zero_when_absent(key: &str) -> bool {
    ["CompactPDO", "DynamicChannelsSupported"]
        .into_iter()
        .chain(DeviceInfo::FLAG_KEYS)
        .chain(DeviceInfo::BAUD_RATE_KEYS.map(|(_, key)| key))
        .any(|k| k.eq_ignore_ascii_case(key))
}

/// Whether a key present on one side only says nothing the absent side does not.
fn absent_means(key: &str, value: &str) -> bool {
    value.trim().is_empty() || (zero_when_absent(key) && int_of(value) == Some(0))
}

fn same_text_value(a: &str, b: &str) -> bool {
    a == b || matches!((int_of(a), int_of(b)), (Some(x), Some(y)) if x == y)
}

fn compare_objects(
    prefix: &str,
    a: &BTreeMap<u16, Object>,
    eds_a: &Eds,
    b: &BTreeMap<u16, Object>,
    eds_b: &Eds,
    out: &mut Vec<Change>,
) {
    let indices: BTreeSet<u16> = a.keys().chain(b.keys()).copied().collect();
    for index in indices {
        let section = format!("{prefix}{index:X}");
        match (a.get(&index), b.get(&index)) {
            (Some(oa), Some(ob)) => {
                if oa.origin != Origin::Orphan || ob.origin != Origin::Orphan {
                    compare_attributes(&section, &oa.attributes, eds_a, &ob.attributes, eds_b, out);
                }
                let subs: BTreeSet<u8> = oa.subs.keys().chain(ob.subs.keys()).copied().collect();
                for sub in subs {
                    let sub_section = format!("{section}sub{sub:X}");
                    match (oa.subs.get(&sub), ob.subs.get(&sub)) {
                        (Some(sa), Some(sb)) => compare_attributes(
                            &sub_section,
                            &sa.attributes,
                            eds_a,
                            &sb.attributes,
                            eds_b,
                            out,
                        ),
                        (Some(sa), None) => {
                            out.push(removed_or_added(ChangeKind::Removed, sub_section, &sa.attributes))
                        }
                        (None, Some(sb)) => {
                            out.push(removed_or_added(ChangeKind::Added, sub_section, &sb.attributes))
                        }
                        (None, None) => {}
                    }
                }
            }
            (Some(oa), None) => out.push(removed_or_added(ChangeKind::Removed, section, &oa.attributes)),
            (None, Some(ob)) => out.push(removed_or_added(ChangeKind::Added, section, &ob.attributes)),
            (None, None) => {}
        }
    }
}

fn removed_or_added(kind: ChangeKind, section: String, attributes: &Attributes) -> Change {
    let name = attributes.parameter_name.clone();
    let (old, new) = if kind == ChangeKind::Removed {
        (name, None)
    } else {
        (None, name)
    };
    Change {
        kind,
        section,
        key: None,
        old,
        new,
        significant: true,
    }
}

fn compare_attributes(
    section: &str,
    a: &Attributes,
    eds_a: &Eds,
    b: &Attributes,
    eds_b: &Eds,
    out: &mut Vec<Change>,
) {
    let type_a = a.data_type().map(|t| eds_a.resolve_data_type(t));
    let type_b = b.data_type().map(|t| eds_b.resolve_data_type(t));
    let ea: BTreeMap<String, (String, String)> = a
        .entries()
        .into_iter()
        .map(|(k, v)| (k.to_ascii_lowercase(), (k.to_owned(), v.to_owned())))
        .collect();
    let eb: BTreeMap<String, (String, String)> = b
        .entries()
        .into_iter()
        .map(|(k, v)| (k.to_ascii_lowercase(), (k.to_owned(), v.to_owned())))
        .collect();
    let keys: BTreeSet<&String> = ea.keys().chain(eb.keys()).collect();
    // For ARRAY/RECORD objects the value attributes live on the sub-objects (a compact array also
    // writes them on the object, which is representation, not content).
    let structured =
        a.object_type().is_some_and(|t| t.has_subs()) && b.object_type().is_some_and(|t| t.has_subs());
    for key in keys {
        if REPRESENTATION_KEYS.iter().any(|r| r.eq_ignore_ascii_case(key))
            || (structured && SUB_CARRIED_KEYS.iter().any(|r| r.eq_ignore_ascii_case(key)))
        {
            continue;
        }
        let va = ea.get(key).map(|(_, v)| v.as_str());
        let vb = eb.get(key).map(|(_, v)| v.as_str());
        let display_key = ea
            .get(key)
            .or_else(|| eb.get(key))
            .map(|(k, _)| k.clone())
            .unwrap_or_default();
        let same = match key.as_str() {
            "objecttype" => a.object_type() == b.object_type(),
            "datatype" => type_a == type_b,
            "accesstype" => match (a.access_type(), b.access_type()) {
                (Some(x), Some(y)) => x == y,
                _ => text_eq(va, vb),
            },
            "pdomapping" => a.pdo_mapping() == b.pdo_mapping(),
            "objflags" => a.obj_flags() == b.obj_flags(),
            "defaultvalue" | "lowlimit" | "highlimit" | "parametervalue" => {
                same_value(va, type_a, vb, type_b)
            }
            _ => text_eq(va, vb),
        };
        if same {
            continue;
        }
        let kind = match (va.filter(|v| !v.is_empty()), vb.filter(|v| !v.is_empty())) {
            (Some(_), Some(_)) => ChangeKind::Changed,
            (Some(_), None) => ChangeKind::Removed,
            _ => ChangeKind::Added,
        };
        out.push(Change {
            kind,
            section: section.to_owned(),
            key: Some(display_key),
            old: va.map(str::to_owned),
            new: vb.map(str::to_owned),
            significant: true,
        });
    }
}

fn text_eq(a: Option<&str>, b: Option<&str>) -> bool {
    a.unwrap_or("").trim() == b.unwrap_or("").trim()
}

fn same_value(a: Option<&str>, ta: Option<DataType>, b: Option<&str>, tb: Option<DataType>) -> bool {
    let (a, b) = (a.unwrap_or("").trim(), b.unwrap_or("").trim());
    if a == b {
        return true;
    }
    if a.is_empty() || b.is_empty() {
        return false;
    }
    match (
        ta.and_then(|t| parse_value(a, t).value),
        tb.and_then(|t| parse_value(b, t).value),
    ) {
        (Some(x), Some(y)) => x.same_meaning(&y),
        _ => same_text_value(a, b) || a.eq_ignore_ascii_case(b),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::load;

    const A: &str = "[FileInfo]\nFileName=a.eds\nModificationDate=01-01-2020\n[DeviceInfo]\nVendorNumber=0x10\n\
        [1017]\nParameterName=Heartbeat\nDataType=0x0006\nAccessType=rw\nDefaultValue=1000\n\
        [2000]\nParameterName=Arr\nObjectType=0x8\nDataType=0x0005\nAccessType=ro\nDefaultValue=0\nCompactSubObj=2\n";

    #[test]
    fn notation_and_layout_do_not_matter() {
        let b = "[DeviceInfo]\nvendornumber=16\n[2000sub0]\nParameterName=NrOfObjects\nDataType=5\nAccessType=ro\nDefaultValue=2\n\
            PDOMapping=0\n[2000sub1]\nParameterName=Arr1\nObjectType=7\nDataType=5\nAccessType=RO\nDefaultValue=00\n\
            [2000sub2]\nParameterName=Arr2\nDataType=0x5\nAccessType=ro\nDefaultValue=0x0\n\
            [2000]\nParameterName=Arr\nObjectType=8\nSubNumber=3\n\
            [1017]\nParameterName=Heartbeat\nObjectType=0x7\nDataType=0x0006\nAccessType=rw\nDefaultValue=0x3E8\n\
            [FileInfo]\nFileName=b.eds\n";
        let d = diff(&load(A.as_bytes()).eds, &load(b.as_bytes()).eds);
        assert!(d.is_equivalent(), "{:#?}", d.significant().collect::<Vec<_>>());
        assert_eq!(
            d.changes.len(),
            2,
            "FileName and ModificationDate are listed: {d:#?}"
        );
    }

    #[test]
    fn zero_flags_equal_absent_flags() {
        let b = A.replace(
            "VendorNumber=0x10\n",
            "VendorNumber=0x10\nCompactPDO=0\nLSS_Supported=0\n",
        );
        assert!(diff(&load(A.as_bytes()).eds, &load(b.as_bytes()).eds).is_equivalent());
        let c = A.replace("VendorNumber=0x10\n", "VendorNumber=0x10\nLSS_Supported=1\n");
        assert!(!diff(&load(A.as_bytes()).eds, &load(c.as_bytes()).eds).is_equivalent());
    }

    #[test]
    fn real_changes_are_reported() {
        let b = A
            .replace("DefaultValue=1000", "DefaultValue=500")
            .replace("VendorNumber=0x10", "VendorNumber=0x11")
            .replace("CompactSubObj=2", "CompactSubObj=3");
        let d = diff(&load(A.as_bytes()).eds, &load(b.as_bytes()).eds);
        let lines: Vec<String> = d.significant().map(ToString::to_string).collect();
        assert_eq!(
            lines,
            [
                "~ [DeviceInfo] VendorNumber: 0x10 -> 0x11",
                "~ [1017] DefaultValue: 1000 -> 500",
                "~ [2000sub0] DefaultValue: 2 -> 3",
                "+ [2000sub3]: Arr3",
            ]
        );
        assert!(!d.is_equivalent());
    }
}

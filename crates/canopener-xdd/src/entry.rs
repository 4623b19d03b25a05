//! One object or sub-object as an XDD describes it, and the mapping between that and the CiA 306 keys
//! of the EDS model (CiA 311 §6.4 `parameter`, §7.1 `CANopenObject`; reference §8 and §11.4).
//!
//! [`XmlEntry`] holds what the XML says, with no interpretation: the object's own attributes and the
//! referenced parameter side by side. [`to_eds`] is the one place that interprets it (precedence,
//! schema defaults, BITSTRING, rwr/rww), so the writer can predict exactly what a reader will make of
//! what it writes ([`from_eds`] does that) and keep in the side channel only what would be lost.

use canopener_eds::model::{Property, int_of};
use canopener_eds::{AccessType, Attributes, ObjectType};

use crate::diag::{Note, XddCode};
use crate::notation::{Iec, ParamAccess, PdoMapping};
use crate::side_channel::{self, Control};
use crate::xml::sanitize;

/// What the XML says about one `CANopenObject` or `CANopenSubObject`.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct XmlEntry {
    /// `@name`.
    pub name: Option<String>,
    /// `@objectType` (decimal).
    pub object_type: Option<u8>,
    /// `@dataType` (inline style).
    pub data_type: Option<u16>,
    /// `@accessType` (inline style).
    pub access: Option<AccessType>,
    /// `@accessType` is there but names no access type: the object's access is not known.
    pub access_unreadable: bool,
    /// `@defaultValue`.
    pub default_value: Option<String>,
    /// `@lowLimit`.
    pub low_limit: Option<String>,
    /// `@highLimit`.
    pub high_limit: Option<String>,
    /// `@actualValue` (XDC).
    pub actual_value: Option<String>,
    /// `@denotation` (XDC).
    pub denotation: Option<String>,
    /// `@PDOmapping`.
    pub pdo_mapping: Option<PdoMapping>,
    /// `@objFlags`.
    pub obj_flags: Option<u32>,
    /// The parameter `@uniqueIDRef` points to.
    pub param: Option<Param>,
}

/// What an ApplicationProcess `parameter` says.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Param {
    /// `@access` as read; `None` means the schema default `read`, unless `access_unreadable`.
    pub access: Option<ParamAccess>,
    /// `@access` is there but names no access: no default stands in for it.
    pub access_unreadable: bool,
    /// The first `label` (or `description` when there is no label).
    pub label: Option<String>,
    /// The IEC element, also when reached through `dataTypeIDRef` (enum, derived).
    pub simple_type: Option<Iec>,
    /// `defaultValue@value`.
    pub default_value: Option<String>,
    /// `actualValue@value`.
    pub actual_value: Option<String>,
    /// The first label of `denotation`.
    pub denotation: Option<String>,
    /// `allowedValues/range[1]/minValue@value`.
    pub min: Option<String>,
    /// `allowedValues/range[1]/maxValue@value`.
    pub max: Option<String>,
    /// `property` elements (CANopenNode `CO_*` and the canopener side channel), in order.
    pub properties: Vec<(String, String)>,
}

/// The CiA 306 view of an entry.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Mapped {
    /// The keys of the section.
    pub attributes: Attributes,
    /// `[<index>ObjectLinks]` from the side channel.
    pub object_links: Option<Vec<Property>>,
    /// The side channel marks the object as a placeholder for orphan sub-object sections.
    pub orphan: bool,
}

/// How the writer describes entries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct EntryStyle {
    /// Also write dataType, accessType, values and limits on the object (inline style).
    pub inline: bool,
    /// Write configured values (ParameterValue, Denotation): an XDC.
    pub with_values: bool,
}

/// Whether an object code describes an object with sub-objects (ARRAY, RECORD, DEFSTRUCT).
pub(crate) fn is_parent_code(code: Option<u8>) -> bool {
    code.and_then(|c| ObjectType::from_code(c.into()))
        .is_some_and(ObjectType::has_subs)
}

/// Interprets an entry: the object's own attribute wins over the parameter (with a note when they
/// disagree), a parameter without `access` means `read` (P2), BITSTRING means OCTET_STRING or DOMAIN,
/// `rw` with `PDOmapping` TPDO/RPDO means rwr/rww (libedssharp #128), and an ARRAY/RECORD object keeps
/// no value keys of its own.
pub(crate) fn to_eds(entry: &XmlEntry, notes: &mut Vec<Note>) -> Mapped {
    let param = entry.param.as_ref();
    let parent = is_parent_code(entry.object_type);
    let mut a = Attributes::default();
    let name = nonempty(entry.name.as_deref()).or_else(|| nonempty(param.and_then(|p| p.label.as_deref())));
    a.parameter_name = name.map(|n| single_line("name", n, notes));
    a.object_type = entry.object_type.map(|c| format!("0x{c:X}"));
    if parent {
        let dropped = parent_values(entry);
        if !dropped.is_empty() {
            notes.push(Note::new(
                XddCode::ParentValuesIgnored,
                format!(
                    "{} on an ARRAY/RECORD object describe its sub-objects in CiA 306; not carried into the EDS",
                    dropped.join(", ")
                ),
            ));
        }
    } else {
        let default_value = pick(
            "defaultValue",
            entry.default_value.as_deref(),
            param.and_then(|p| p.default_value.as_deref()),
            notes,
        );
        let data_type = data_type(entry, default_value.is_some(), notes);
        a.data_type = data_type.map(|t| format!("0x{t:04X}"));
        a.access_type = access(entry, notes).map(|t| t.as_str().to_owned());
        a.pdo_mapping = entry
            .pdo_mapping
            .map(|p| if p == PdoMapping::No { "0" } else { "1" }.to_owned());
        a.default_value = default_value.map(|v| value_text("defaultValue", v, data_type, notes));
        a.low_limit = pick(
            "lowLimit",
            entry.low_limit.as_deref(),
            param.and_then(|p| p.min.as_deref()),
            notes,
        )
        .map(|v| single_line("lowLimit", v, notes));
        a.high_limit = pick(
            "highLimit",
            entry.high_limit.as_deref(),
            param.and_then(|p| p.max.as_deref()),
            notes,
        )
        .map(|v| single_line("highLimit", v, notes));
    }
    let data_type = a.data_type();
    a.parameter_value = pick(
        "actualValue",
        entry.actual_value.as_deref(),
        param.and_then(|p| p.actual_value.as_deref()),
        notes,
    )
    .map(|v| value_text("actualValue", v, data_type.map(|t| t.0), notes));
    a.denotation = pick(
        "denotation",
        entry.denotation.as_deref(),
        param.and_then(|p| p.denotation.as_deref()),
        notes,
    )
    .map(|v| single_line("denotation", v, notes));
    a.obj_flags = entry.obj_flags.map(|f| format!("0x{f:X}"));
    let mut mapped = Mapped {
        attributes: a,
        ..Mapped::default()
    };
    if let Some(param) = param {
        apply_side_channel(&param.properties, &mut mapped, notes);
    }
    mapped
}

/// Describes an EDS object or sub-object as XDD facts, with the side channel for whatever the XDD
/// form would not give back. `object_links` and `orphan` only apply to objects.
pub(crate) fn from_eds(
    attributes: &Attributes,
    object_links: Option<&[Property]>,
    orphan: bool,
    style: EntryStyle,
) -> XmlEntry {
    let mut e = XmlEntry::default();
    let name = attributes.parameter_name.as_deref().unwrap_or("").trim();
    e.name = Some(sanitize(name));
    let code = match attributes.object_type.as_deref().map(str::trim) {
        None | Some("") => ObjectType::Var.code(),
        Some(raw) => int_of(raw)
            .and_then(|c| u8::try_from(c).ok())
            .unwrap_or(ObjectType::Var.code()),
    };
    e.object_type = Some(code);
    let parent = is_parent_code(Some(code));
    let mut p = Param {
        label: e.name.clone(),
        ..Param::default()
    };
    if !parent {
        match attributes.data_type() {
            Some(t) => {
                let (iec, needs_inline) = Iec::for_data_type(t.0);
                p.simple_type = Some(iec);
                if needs_inline || style.inline {
                    e.data_type = Some(t.0);
                }
            }
            None => p.simple_type = Some(Iec::Bitstring),
        }
        let access = attributes.access_type();
        p.access = Some(access.map_or(ParamAccess::NoAccess, ParamAccess::from_access_type));
        if style.inline {
            e.access = access.map(|t| {
                if matches!(t, AccessType::Rwr | AccessType::Rww) {
                    AccessType::Rw
                } else {
                    t
                }
            });
        }
        e.pdo_mapping = attributes.pdo_mapping.as_deref().map(|raw| match int_of(raw) {
            Some(1) => PdoMapping::mappable(access),
            _ => PdoMapping::No,
        });
        p.default_value = text(attributes.default_value.as_deref());
        let (low, high) = (
            text(attributes.low_limit.as_deref()),
            text(attributes.high_limit.as_deref()),
        );
        if low.is_some() && high.is_some() && !style.inline {
            (p.min, p.max) = (low, high);
        } else {
            (e.low_limit, e.high_limit) = (low, high);
        }
        if style.inline {
            e.default_value = p.default_value.clone();
        }
    }
    if style.with_values {
        p.actual_value = text(attributes.parameter_value.as_deref());
        p.denotation = text(attributes.denotation.as_deref());
        if style.inline {
            e.actual_value = p.actual_value.clone();
            e.denotation = p.denotation.clone();
        }
    }
    if attributes
        .obj_flags
        .as_deref()
        .is_some_and(|f| !f.trim().is_empty())
    {
        e.obj_flags = attributes.obj_flags();
    }
    e.param = Some(p);
    let predicted = to_eds(&e, &mut Vec::new()).attributes;
    let mut properties = side_channel_for(attributes, &predicted, parent, style.with_values);
    if let Some(links) = object_links {
        properties.push(side_channel::property(Control::Links, ""));
        properties.extend(
            links
                .iter()
                .map(|l| side_channel::property(Control::Link, &format!("{}={}", l.key, l.value))),
        );
    }
    if orphan {
        properties.push(side_channel::property(Control::Origin, side_channel::ORPHAN));
    }
    if let Some(p) = e.param.as_mut() {
        p.properties = properties;
    }
    e
}

/// Keys no XDD element gives back, so the writer never compares them: `SubNumber` is derived from the
/// sub-objects, `CompactSubObj` is a form XDD does not have (its sub-objects are written explicitly).
const DERIVED_KEYS: &[&str] = canopener_eds::model::REPRESENTATION_KEYS;

/// Keys an ARRAY/RECORD object does not keep (CiA 306 gives them to its sub-objects).
const PARENT_VALUE_KEYS: &[&str] = canopener_eds::model::SUB_CARRIED_KEYS;

/// Keys of a configured device (DCF), left out of a plain XDD.
const CONFIGURED_KEYS: &[&str] = &["ParameterValue", "Denotation"];

/// The side-channel properties that turn `predicted` back into `original`.
fn side_channel_for(
    original: &Attributes,
    predicted: &Attributes,
    parent: bool,
    with_values: bool,
) -> Vec<(String, String)> {
    let skip = |key: &str| {
        let any = |list: &[&str]| list.iter().any(|k| k.eq_ignore_ascii_case(key));
        any(DERIVED_KEYS) || (parent && any(PARENT_VALUE_KEYS)) || (!with_values && any(CONFIGURED_KEYS))
    };
    let mut out = Vec::new();
    let original_entries = original.entries();
    for (key, value) in &original_entries {
        if skip(key) {
            continue;
        }
        if !equivalent(key, Some(value), predicted.get(key)) {
            out.push(side_channel::property(Control::Set, &format!("{key}={value}")));
        }
    }
    for (key, value) in predicted.entries() {
        let in_original = original_entries.iter().any(|(k, _)| k.eq_ignore_ascii_case(key));
        if !in_original && !skip(key) && !equivalent(key, None, Some(value)) {
            out.push(side_channel::property(Control::Absent, key));
        }
    }
    out
}

/// Whether two values of a key mean the same (the reading of `canopener_eds::diff`, a little stricter:
/// values compare as text).
pub(crate) fn equivalent(key: &str, a: Option<&str>, b: Option<&str>) -> bool {
    let (a, b) = (nonempty(a), nonempty(b));
    if a == b {
        return true;
    }
    let number = |t: Option<&str>| t.and_then(int_of);
    match key.to_ascii_lowercase().as_str() {
        "objecttype" => {
            let code = |t: Option<&str>| {
                if t.is_none() {
                    Some(i128::from(ObjectType::Var.code()))
                } else {
                    number(t)
                }
            };
            code(a).is_some() && code(a) == code(b)
        }
        "datatype" | "pdomapping" | "objflags" => number(a).is_some() && number(a) == number(b),
        "accesstype" => {
            let parse = |t: Option<&str>| t.and_then(AccessType::parse);
            parse(a).is_some() && parse(a) == parse(b)
        }
        _ => false,
    }
}

fn apply_side_channel(properties: &[(String, String)], mapped: &mut Mapped, notes: &mut Vec<Note>) {
    for (name, value) in properties {
        let Some((control, value)) = side_channel::decode(name, value) else {
            continue;
        };
        match control {
            Control::Set => match value.split_once('=') {
                Some((key, v)) if !key.is_empty() => mapped.attributes.set(key, v),
                _ => bad_side_channel(name, &value, notes),
            },
            Control::Absent => side_channel::remove_key(&mut mapped.attributes, &value),
            Control::Links => {
                mapped.object_links.get_or_insert_with(Vec::new);
            }
            Control::Link => match value.split_once('=') {
                Some((key, v)) => mapped.object_links.get_or_insert_with(Vec::new).push(Property {
                    key: key.to_owned(),
                    value: v.to_owned(),
                }),
                None => bad_side_channel(name, &value, notes),
            },
            Control::Origin if value == side_channel::ORPHAN => mapped.orphan = true,
            _ => bad_side_channel(name, &value, notes),
        }
    }
}

fn bad_side_channel(name: &str, value: &str, notes: &mut Vec<Note>) {
    notes.push(Note::new(
        XddCode::SideChannel,
        format!("side-channel property `{name}` = `{value}` is not understood; ignored"),
    ));
}

fn parent_values(entry: &XmlEntry) -> Vec<&'static str> {
    let param = entry.param.as_ref();
    let mut out = Vec::new();
    let has = |v: &Option<String>| nonempty(v.as_deref()).is_some();
    if entry.data_type.is_some() {
        out.push("dataType");
    }
    if entry.access.is_some() || param.is_some_and(|p| p.access.is_some_and(|a| a != ParamAccess::NoAccess)) {
        out.push("access");
    }
    if has(&entry.default_value) || param.is_some_and(|p| has(&p.default_value)) {
        out.push("defaultValue");
    }
    if has(&entry.low_limit) || has(&entry.high_limit) || param.is_some_and(|p| has(&p.min) || has(&p.max)) {
        out.push("limits");
    }
    if entry.pdo_mapping.is_some_and(|m| m != PdoMapping::No) {
        out.push("PDOmapping");
    }
    out
}

fn data_type(entry: &XmlEntry, has_default: bool, notes: &mut Vec<Note>) -> Option<u16> {
    let iec = entry.param.as_ref().and_then(|p| p.simple_type);
    match (entry.data_type, iec) {
        (Some(t), Some(iec)) => {
            if !iec.agrees_with(t) {
                notes.push(Note::new(
                    XddCode::ConflictingValues,
                    format!("dataType {t:04X} on the object, <{}> in the parameter; the object's dataType is used", iec.name()),
                ));
            }
            Some(t)
        }
        (Some(t), None) => Some(t),
        (None, Some(iec)) => {
            let t = iec.data_type(has_default);
            if iec == Iec::Bitstring {
                let name = if t == 0x000A { "OCTET_STRING" } else { "DOMAIN" };
                notes.push(Note::new(
                    XddCode::AmbiguousBitstring,
                    format!("<BITSTRING> without an inline dataType is read as {name}; CANopen types without an IEC element also use it"),
                ));
            }
            Some(t)
        }
        (None, None) => {
            notes.push(Note::new(
                XddCode::InvalidDataType,
                "no dataType attribute and no IEC type in a parameter; DataType is left out".to_owned(),
            ));
            None
        }
    }
}

/// The CiA 306 access type: [`stated_access`] with the direction an `rw` entry's PDOmapping gives it
/// (TPDO: rwr, RPDO: rww; libedssharp #128), whether the rw comes from the object's accessType or its
/// parameter's readWrite. CiA 311 says the PDO direction of read/write entries there, CiA 306 in the
/// access type.
fn access(entry: &XmlEntry, notes: &mut Vec<Note>) -> Option<AccessType> {
    stated_access(entry, notes).map(|t| match (t, entry.pdo_mapping) {
        (AccessType::Rw, Some(PdoMapping::Tpdo)) => AccessType::Rwr,
        (AccessType::Rw, Some(PdoMapping::Rpdo)) => AccessType::Rww,
        (t, _) => t,
    })
}

/// The access the object's accessType or its parameter's access states.
fn stated_access(entry: &XmlEntry, notes: &mut Vec<Note>) -> Option<AccessType> {
    let inline = entry.access.map(|t| match (t, entry.pdo_mapping) {
        (AccessType::Rw, Some(PdoMapping::Tpdo)) => AccessType::Rwr,
        (AccessType::Rw, Some(PdoMapping::Rpdo)) => AccessType::Rww,
        (t, _) => t,
    });
    let explicit = entry.param.as_ref().and_then(|p| p.access);
    // A parameter without `access` is `read` (P2); one whose access cannot be read is nothing, and an
    // object whose own accessType cannot be read leaves only what its parameter states.
    let from_param = entry
        .param
        .as_ref()
        .filter(|p| !p.access_unreadable)
        .map(|p| p.access.unwrap_or(ParamAccess::Read));
    let from_param = if entry.access_unreadable {
        explicit
    } else {
        from_param
    };
    match (inline, from_param) {
        (None, None) => None,
        (Some(t), None) => Some(t),
        (None, Some(p)) => {
            let t = p.access_type();
            if t.is_none() {
                notes.push(Note::new(
                    XddCode::NoAccess,
                    "access `noAccess` has no CiA 306 access type; AccessType is left out".to_owned(),
                ));
            }
            t
        }
        (Some(t), Some(p)) => match p.access_type() {
            None => Some(t),
            Some(from) if from == t => Some(t),
            Some(from @ (AccessType::Rwr | AccessType::Rww)) if entry.access == Some(AccessType::Rw) => {
                Some(from)
            }
            Some(from) => {
                if let Some(explicit) = explicit {
                    notes.push(Note::new(
                        XddCode::ConflictingValues,
                        format!(
                            "accessType `{t}` on the object, access `{}` ({from}) in the parameter; the object's accessType is used",
                            explicit.as_str()
                        ),
                    ));
                }
                Some(t)
            }
        },
    }
}

/// The object's value when it has one, else the parameter's; a note when both are given and differ.
fn pick<'a>(
    what: &str,
    own: Option<&'a str>,
    param: Option<&'a str>,
    notes: &mut Vec<Note>,
) -> Option<&'a str> {
    match (nonempty(own), nonempty(param)) {
        (Some(o), Some(p)) => {
            let same = o == p || matches!((int_of(o), int_of(p)), (Some(x), Some(y)) if x == y);
            if !same {
                notes.push(Note::new(
                    XddCode::ConflictingValues,
                    format!("{what} `{o}` on the object, `{p}` in the parameter; the object's value is used"),
                ));
            }
            Some(o)
        }
        (Some(o), None) => Some(o),
        (None, p) => p,
    }
}

/// A value as an EDS writes it: one line, and octets without the spaces CANopenEditor puts in (P7).
fn value_text(what: &str, value: &str, data_type: Option<u16>, notes: &mut Vec<Note>) -> String {
    let value = single_line(what, value, notes);
    if matches!(data_type, Some(0x000A | 0x000F))
        && let Some(joined) = join_spaced_octets(&value)
    {
        notes.push(Note::new(
            XddCode::SpacedOctets,
            format!("{what} `{value}` is written with spaces between bytes; read as `{joined}`"),
        ));
        return joined;
    }
    value
}

/// `C8 3D BB` to `C83DBB`; `None` unless the text is at least two hex byte pairs separated by spaces.
pub(crate) fn join_spaced_octets(text: &str) -> Option<String> {
    let pairs: Vec<&str> = text.split(' ').collect();
    let valid = pairs.len() >= 2
        && pairs
            .iter()
            .all(|p| p.len() == 2 && p.bytes().all(|b| b.is_ascii_hexdigit()));
    valid.then(|| pairs.concat())
}

/// Text for an EDS value, which cannot hold line breaks.
pub(crate) fn single_line(what: &str, text: &str, notes: &mut Vec<Note>) -> String {
    if !text.contains(['\n', '\r']) {
        return text.to_owned();
    }
    let joined = text
        .split(['\n', '\r'])
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ");
    notes.push(Note::new(
        XddCode::LineBreaks,
        format!("{what} has line breaks, which an EDS value cannot hold; joined with spaces"),
    ));
    joined
}

/// Trimmed, or `None` when empty (libedssharp writes `""` for unset values, P12).
pub(crate) fn nonempty(text: Option<&str>) -> Option<&str> {
    text.map(str::trim).filter(|t| !t.is_empty())
}

fn text(value: Option<&str>) -> Option<String> {
    nonempty(value).map(sanitize)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn attrs(pairs: &[(&str, &str)]) -> Attributes {
        let mut a = Attributes::default();
        for (k, v) in pairs {
            a.set(k, *v);
        }
        a
    }

    fn reference() -> EntryStyle {
        EntryStyle {
            inline: false,
            with_values: true,
        }
    }

    #[test]
    fn parameter_defaults_apply_and_the_object_wins() {
        let entry = XmlEntry {
            name: Some("Error register".into()),
            object_type: Some(7),
            pdo_mapping: Some(PdoMapping::Tpdo),
            param: Some(Param {
                simple_type: Some(Iec::Usint),
                default_value: Some("0x00".into()),
                ..Param::default()
            }),
            ..XmlEntry::default()
        };
        let mut notes = Vec::new();
        let a = to_eds(&entry, &mut notes).attributes;
        assert_eq!(
            a.access_type.as_deref(),
            Some("ro"),
            "a parameter without access is read (P2)"
        );
        assert_eq!(a.data_type.as_deref(), Some("0x0005"));
        assert_eq!(a.object_type.as_deref(), Some("0x7"));
        assert_eq!(a.pdo_mapping.as_deref(), Some("1"));
        assert_eq!(a.default_value.as_deref(), Some("0x00"));
        assert!(notes.is_empty(), "{notes:?}");

        let mut conflicting = entry.clone();
        conflicting.default_value = Some("5".into());
        conflicting.data_type = Some(0x0006);
        let mut notes = Vec::new();
        let a = to_eds(&conflicting, &mut notes).attributes;
        assert_eq!(a.default_value.as_deref(), Some("5"));
        assert_eq!(a.data_type.as_deref(), Some("0x0006"));
        let codes: Vec<XddCode> = notes.iter().map(|n| n.code).collect();
        assert_eq!(codes, [XddCode::ConflictingValues, XddCode::ConflictingValues]);
    }

    #[test]
    fn rw_with_a_pdo_direction_is_rwr_or_rww() {
        let mut entry = XmlEntry {
            object_type: Some(7),
            access: Some(AccessType::Rw),
            data_type: Some(6),
            ..XmlEntry::default()
        };
        entry.pdo_mapping = Some(PdoMapping::Rpdo);
        assert_eq!(
            to_eds(&entry, &mut Vec::new()).attributes.access_type.as_deref(),
            Some("rww")
        );
        entry.pdo_mapping = Some(PdoMapping::Tpdo);
        assert_eq!(
            to_eds(&entry, &mut Vec::new()).attributes.access_type.as_deref(),
            Some("rwr")
        );
        entry.pdo_mapping = Some(PdoMapping::No);
        entry.param = Some(Param {
            access: Some(ParamAccess::ReadWriteOutput),
            ..Param::default()
        });
        assert_eq!(
            to_eds(&entry, &mut Vec::new()).attributes.access_type.as_deref(),
            Some("rww")
        );
        // A parameter's readWrite gets its direction from the object's PDOmapping as well (reference
        // style, where the object carries no accessType).
        let reference = XmlEntry {
            object_type: Some(7),
            pdo_mapping: Some(PdoMapping::Tpdo),
            param: Some(Param {
                access: Some(ParamAccess::ReadWrite),
                simple_type: Some(Iec::Uint),
                ..Param::default()
            }),
            ..XmlEntry::default()
        };
        assert_eq!(
            to_eds(&reference, &mut Vec::new())
                .attributes
                .access_type
                .as_deref(),
            Some("rwr")
        );
    }

    #[test]
    fn no_access_and_bitstring_are_reported() {
        let entry = XmlEntry {
            object_type: Some(7),
            param: Some(Param {
                access: Some(ParamAccess::NoAccess),
                simple_type: Some(Iec::Bitstring),
                ..Param::default()
            }),
            ..XmlEntry::default()
        };
        let mut notes = Vec::new();
        let a = to_eds(&entry, &mut notes).attributes;
        assert_eq!(a.access_type, None);
        assert_eq!(
            a.data_type.as_deref(),
            Some("0x000F"),
            "BITSTRING without a default is DOMAIN"
        );
        let codes: Vec<XddCode> = notes.iter().map(|n| n.code).collect();
        assert_eq!(codes, [XddCode::AmbiguousBitstring, XddCode::NoAccess]);
    }

    #[test]
    fn octets_and_line_breaks_are_normalised() {
        let entry = XmlEntry {
            name: Some("two\nlines".into()),
            object_type: Some(7),
            param: Some(Param {
                simple_type: Some(Iec::Bitstring),
                default_value: Some("C8 3D BB".into()),
                ..Param::default()
            }),
            ..XmlEntry::default()
        };
        let mut notes = Vec::new();
        let a = to_eds(&entry, &mut notes).attributes;
        assert_eq!(a.default_value.as_deref(), Some("C83DBB"));
        assert_eq!(a.data_type.as_deref(), Some("0x000A"));
        assert_eq!(a.parameter_name.as_deref(), Some("two lines"));
        assert_eq!(join_spaced_octets("C8"), None);
        assert_eq!(join_spaced_octets("C8  3D"), None);
    }

    #[test]
    fn parents_keep_no_value_keys() {
        let entry = XmlEntry {
            name: Some("PDO".into()),
            object_type: Some(9),
            data_type: Some(0x20),
            access: Some(AccessType::Rw),
            obj_flags: Some(1),
            ..XmlEntry::default()
        };
        let mut notes = Vec::new();
        let a = to_eds(&entry, &mut notes).attributes;
        assert_eq!(
            a.entries(),
            [
                ("ParameterName", "PDO"),
                ("ObjectType", "0x9"),
                ("ObjFlags", "0x1")
            ]
        );
        assert_eq!(notes.first().map(|n| n.code), Some(XddCode::ParentValuesIgnored));
    }

    #[test]
    fn writer_entries_read_back_to_the_same_keys() {
        let cases: &[&[(&str, &str)]] = &[
            &[
                ("ParameterName", "Heartbeat"),
                ("ObjectType", "0x7"),
                ("DataType", "0x0006"),
                ("AccessType", "rw"),
                ("DefaultValue", "1000"),
                ("PDOMapping", "0"),
            ],
            &[
                ("ParameterName", "Int24"),
                ("DataType", "0x0010"),
                ("AccessType", "rwr"),
                ("PDOMapping", "1"),
                ("LowLimit", "-5"),
            ],
            &[
                ("ParameterName", "Odd"),
                ("ObjectType", "7"),
                ("DataType", "bogus"),
                ("AccessType", "UNKNOWN"),
                ("PDOMapping", "yes"),
                ("ObjFlags", "3"),
            ],
            &[
                ("ParameterName", "No type"),
                ("Count", "2"),
                ("UploadFile", "a.bin"),
                ("Vendor_Key", "x"),
            ],
            &[
                ("ParameterName", "bell\u{7}"),
                ("DataType", "0x0009"),
                ("AccessType", "ro"),
                ("DefaultValue", "a&b<c>\"d\""),
                ("ParameterValue", "v"),
                ("Denotation", "d"),
            ],
        ];
        for inline in [false, true] {
            for case in cases {
                let original = attrs(case);
                let entry = from_eds(
                    &original,
                    None,
                    false,
                    EntryStyle {
                        inline,
                        with_values: true,
                    },
                );
                let back = to_eds(&entry, &mut Vec::new()).attributes;
                for (key, value) in original.entries() {
                    assert!(
                        equivalent(key, Some(value), back.get(key)),
                        "{key}: {value:?} came back as {:?} (inline {inline})",
                        back.get(key)
                    );
                }
                for (key, value) in back.entries() {
                    assert!(
                        equivalent(key, original.get(key), Some(value)),
                        "{key} appeared as {value:?} (inline {inline})"
                    );
                }
            }
        }
    }

    #[test]
    fn the_side_channel_stays_empty_for_ordinary_entries() {
        let original = attrs(&[
            ("ParameterName", "Heartbeat"),
            ("ObjectType", "0x7"),
            ("DataType", "0x0006"),
            ("AccessType", "rw"),
            ("DefaultValue", "1000"),
            ("PDOMapping", "0"),
        ]);
        let entry = from_eds(&original, None, false, reference());
        assert_eq!(entry.param.map(|p| p.properties), Some(Vec::new()));
        let missing_access = attrs(&[("ParameterName", "x"), ("DataType", "0x0005")]);
        let entry = from_eds(&missing_access, None, false, reference());
        assert_eq!(
            entry.param.as_ref().and_then(|p| p.access),
            Some(ParamAccess::NoAccess)
        );
        assert!(entry.param.is_some_and(|p| p.properties.is_empty()));
    }

    #[test]
    fn object_links_and_orphans_survive() {
        let links = [
            Property {
                key: "ObjectLinks".into(),
                value: "2".into(),
            },
            Property {
                key: "1".into(),
                value: "0x6000".into(),
            },
        ];
        let entry = from_eds(
            &attrs(&[("ParameterName", "x"), ("ObjectType", "0x9")]),
            Some(&links),
            true,
            reference(),
        );
        let mapped = to_eds(&entry, &mut Vec::new());
        assert_eq!(mapped.object_links.as_deref(), Some(&links[..]));
        assert!(mapped.orphan);
    }

    #[test]
    fn equivalence_follows_meaning() {
        assert!(equivalent("ObjectType", None, Some("0x7")));
        assert!(equivalent("ObjectType", Some("7"), Some("0x7")));
        assert!(!equivalent("ObjectType", Some("0x8"), Some("0x7")));
        assert!(equivalent("AccessType", Some("RW"), Some("rw")));
        assert!(!equivalent("AccessType", Some("UNKNOWN"), None));
        assert!(equivalent("DataType", Some("7"), Some("0x0007")));
        assert!(equivalent("DefaultValue", Some(""), None));
        assert!(
            !equivalent("DefaultValue", Some("0x10"), Some("16")),
            "values compare as written"
        );
    }
}

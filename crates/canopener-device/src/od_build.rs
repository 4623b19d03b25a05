//! The runtime object dictionary of a device, built from an EDS or DCF (CiA 306 object descriptions
//! turned into CiA 301 object dictionary entries).
//!
//! [`build_od`] walks every object of an [`Eds`] and makes one [`Entry`] per VAR, DOMAIN and
//! sub-object of an ARRAY or RECORD, honouring the data type, access type, `LowLimit`/`HighLimit`,
//! `PDOMapping`, `ObjFlags` and the value. Sub-objects the EDS loader generated from
//! `CompactSubObj` and `[DeviceInfo] CompactPDO` are built like written ones, and manufacturer and
//! profile objects are held exactly as described. DEFTYPE, DEFSTRUCT and NULL objects describe
//! types, not data, and are skipped.
//!
//! The value of an entry is, in order of precedence: a DCF's `ParameterValue`, the `DefaultValue`,
//! or a fallback (zero, an empty string, or for sub-index 0 of an ARRAY or RECORD the highest
//! sub-index present). `$NODEID` formulas resolve with the node-ID given. REALs may be written as
//! decimals or as IEEE 754 bit patterns, OCTET_STRING and DOMAIN values as hex digits.
//!
//! Real files depart from CiA 306 all the time, so almost nothing is an error: whatever cannot be
//! taken as written is replaced by something a device can run with, and a [`BuildNote`] says what
//! and why. Only a node-ID outside 1..=127 or a dictionary that cannot hold the entries is an
//! [`OdBuildError`].
//!
//! Sizes of variable-length entries (CiA 301 leaves them to the device; an EDS cannot express them):
//! VISIBLE_STRING, OCTET_STRING and UNICODE_STRING entries accept writes of up to
//! [`STRING_MAX_LEN`] bytes or their default's length if that is longer; DOMAIN entries up to
//! [`DOMAIN_MAX_LEN`] bytes or their default's length if that is longer.

use std::fmt;

use canopener_eds::model::Attributes;
use canopener_eds::value::{Value, parse_value, range_of};
use canopener_eds::{Eds, Object, ObjectType, Origin};
use canopener_od::{Access, DataType, DynamicOd, Entry, ObjFlags, ObjectKey, OdError, TypeKind};

/// The most bytes a VISIBLE_STRING, OCTET_STRING or UNICODE_STRING entry accepts, unless its
/// default is longer (then the default's length is the maximum).
///
/// 256 bytes covers every string object of CiA 301 and the profiles in the corpus and is even, as a
/// UNICODE_STRING needs; it models a device with a fixed string buffer, so a too-long write is
/// refused with abort code 0607 0012h as such a device would.
pub const STRING_MAX_LEN: u32 = 256;

/// The most bytes a DOMAIN entry accepts, unless its default is longer.
///
/// DOMAINs carry program images (1F50h) and other bulk data, so the bound is generous (1 MiB); it
/// exists so a simulated device never holds more memory than this for one entry.
pub const DOMAIN_MAX_LEN: u32 = 1 << 20;

/// A runtime object dictionary built from an EDS or DCF, with what could not be taken as written.
#[derive(Debug)]
pub struct BuiltOd {
    /// The dictionary, sized exactly for its entries.
    pub od: DynamicOd,
    /// Everything that was not taken as written and what was done instead, in index order.
    pub notes: Vec<BuildNote>,
}

/// Why a dictionary could not be built at all.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OdBuildError {
    /// A node-ID outside 1..=127, which no device may have (CiA 301, network management).
    #[error("node-ID {node_id} is outside 1..=127; give the device a node-ID in that range")]
    InvalidNodeId {
        /// The node-ID given.
        node_id: u8,
    },
    /// The dictionary cannot hold every entry.
    #[error("the object dictionary cannot hold the entries of this file: {source}")]
    Full {
        /// The dictionary's refusal.
        #[from]
        source: OdError,
    },
}

/// What kind of departure a [`BuildNote`] reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum NoteKind {
    /// No `ParameterValue` or `DefaultValue`: the value is zero, empty, or for sub-index 0 of an
    /// ARRAY or RECORD the highest sub-index present.
    MissingDefault,
    /// The value does not parse for the data type: the value is zero or empty.
    InvalidDefault,
    /// The value parses but lies outside the data type's range (also after `$NODEID` is
    /// resolved): the value is zero.
    DefaultOutOfRange,
    /// No `DataType`, or one that is not a number: the ARRAY's element type, UNSIGNED8 for a
    /// sub-index 0, or DOMAIN is used.
    MissingDataType,
    /// A data type that is neither a CiA 301 basic type nor a DEFTYPE resolving to one: the entry is
    /// held as a DOMAIN.
    UnknownDataType,
    /// No valid `AccessType`: the object's access type or `ro` is used.
    MissingAccessType,
    /// A `LowLimit` or `HighLimit` that does not parse for the type, lies outside its range, or is
    /// given on a type without limits: that limit is ignored.
    InvalidLimit,
    /// `LowLimit` above `HighLimit`: both are ignored.
    InvertedLimits,
    /// A `PDOMapping` other than 0 or 1: the entry is not mappable.
    InvalidPdoMapping,
    /// An `ObjFlags` that is not a number: no flags are set.
    InvalidObjFlags,
    /// An `ObjectType` CiA 306 does not define: the object is built as a VAR, or as a RECORD if it
    /// has sub-objects.
    UnknownObjectType,
    /// An ARRAY or RECORD without any sub-object: the object is left out.
    NoSubObjects,
    /// Sub-object sections on a VAR or DOMAIN object: they are ignored.
    SubObjectsIgnored,
    /// Sub-object sections whose object section is missing: the sub-objects are built.
    MissingObjectSection,
    /// A DCF `UploadFile` or `DownloadFile`: not read (no IO here); the value comes from the file's
    /// text as usual.
    FileNotRead,
    /// An object at index 0000h, which CiA 301 does not use: the object is left out.
    InvalidIndex,
}

/// One entry (or object) that could not be taken as written, and what was done instead.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BuildNote {
    /// The object's index.
    pub index: u16,
    /// The sub-index, or `None` when the note is about the whole object.
    pub sub: Option<u8>,
    /// What kind of departure this is.
    pub kind: NoteKind,
    /// What was found and what was done instead, for people.
    pub detail: String,
}

impl fmt::Display for BuildNote {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.sub {
            Some(sub) => write!(f, "{:04X}sub{:X}: {}", self.index, sub, self.detail),
            None => write!(f, "{:04X}: {}", self.index, self.detail),
        }
    }
}

/// Builds the runtime object dictionary of a device with node-ID `node_id` from an EDS or DCF.
///
/// The dictionary holds exactly the entries built (its capacity equals its length). Fails only
/// for a node-ID outside 1..=127 or a dictionary that cannot hold the entries; every other
/// departure from CiA 306 becomes a [`BuildNote`].
pub fn build_od(eds: &Eds, node_id: u8) -> Result<BuiltOd, OdBuildError> {
    if !(1..=127).contains(&node_id) {
        return Err(OdBuildError::InvalidNodeId { node_id });
    }
    let mut builder = Builder {
        eds,
        node_id,
        entries: Vec::new(),
        notes: Vec::new(),
    };
    for (&index, object) in &eds.objects {
        builder.object(index, object);
    }
    let Builder { entries, notes, .. } = builder;
    let od = DynamicOd::from_entries(entries.len(), entries)?;
    Ok(BuiltOd { od, notes })
}

struct Builder<'a> {
    eds: &'a Eds,
    node_id: u8,
    entries: Vec<Entry>,
    notes: Vec<BuildNote>,
}

/// Where an entry sits, which decides its fallbacks.
#[derive(Clone, Copy)]
enum Place<'a> {
    /// A VAR or DOMAIN object (sub-index 0).
    Var { domain: bool },
    /// A sub-object of an ARRAY or RECORD.
    Sub {
        parent: &'a Attributes,
        array: bool,
        highest: u8,
    },
}

impl Builder<'_> {
    fn note(&mut self, index: u16, sub: Option<u8>, kind: NoteKind, detail: String) {
        self.notes.push(BuildNote {
            index,
            sub,
            kind,
            detail,
        });
    }

    fn object(&mut self, index: u16, object: &Object) {
        if index == 0 {
            self.note(
                index,
                None,
                NoteKind::InvalidIndex,
                "index 0000h is not used by CiA 301; object left out".to_owned(),
            );
            return;
        }
        let object_type = object.object_type();
        let compound = match object_type {
            // Type definitions describe data, they hold none (CiA 301, object dictionary).
            Some(ObjectType::DefType | ObjectType::DefStruct | ObjectType::Null) => return,
            Some(ObjectType::Array | ObjectType::Record) => true,
            Some(ObjectType::Var | ObjectType::Domain) if object.origin == Origin::Orphan => {
                self.note(
                    index,
                    None,
                    NoteKind::MissingObjectSection,
                    "sub-object sections without an object section; sub-objects built as a RECORD".to_owned(),
                );
                true
            }
            Some(ObjectType::Var | ObjectType::Domain) => {
                if !object.subs.is_empty() {
                    self.note(
                        index,
                        None,
                        NoteKind::SubObjectsIgnored,
                        format!(
                            "{} sub-object section(s) on a {}; ignored",
                            object.subs.len(),
                            object_type.map_or("VAR", |t| if t == ObjectType::Domain {
                                "DOMAIN"
                            } else {
                                "VAR"
                            })
                        ),
                    );
                }
                false
            }
            None => {
                let compound = !object.subs.is_empty();
                self.note(
                    index,
                    None,
                    NoteKind::UnknownObjectType,
                    format!(
                        "ObjectType `{}` is not defined by CiA 306; built as a {}",
                        object.attributes.object_type.as_deref().unwrap_or(""),
                        if compound { "RECORD" } else { "VAR" }
                    ),
                );
                compound
            }
        };
        if !compound {
            let domain = object_type == Some(ObjectType::Domain);
            self.entry(index, 0, &object.attributes, Place::Var { domain });
            return;
        }
        let Some(highest) = object.highest_sub() else {
            self.note(
                index,
                None,
                NoteKind::NoSubObjects,
                "ARRAY or RECORD without sub-objects; object left out".to_owned(),
            );
            return;
        };
        let place = Place::Sub {
            parent: &object.attributes,
            array: object_type == Some(ObjectType::Array),
            highest,
        };
        for (&sub, sub_object) in &object.subs {
            self.entry(index, sub, &sub_object.attributes, place);
        }
    }

    fn entry(&mut self, index: u16, sub: u8, attrs: &Attributes, place: Place<'_>) {
        let key = ObjectKey::new(index, sub);
        let data_type = self.data_type(key, attrs, place);
        let access = self.access(key, attrs, place);
        let value = self.value(key, attrs, data_type, place);
        let pdo_mapping = self.pdo_mapping(key, attrs);
        let obj_flags = self.obj_flags(key, attrs);
        let (low, high) = self.limits(key, attrs, data_type);
        for (name, file) in [
            ("UploadFile", &attrs.upload_file),
            ("DownloadFile", &attrs.download_file),
        ] {
            if let Some(file) = file.as_deref().filter(|f| !f.trim().is_empty()) {
                self.note(
                    index,
                    Some(sub),
                    NoteKind::FileNotRead,
                    format!("{name} `{file}` is not read; the value comes from the file's text"),
                );
            }
        }

        // `value` has the length `data_type` takes (see `encode`), so this cannot fail; a zero value
        // stands in if it ever did, since every entry must exist.
        let entry = Entry::new(key, data_type, access, &value)
            .or_else(|_| Entry::new(key, data_type, access, &zero(data_type)));
        let Ok(mut entry) = entry else { return };
        entry = entry.with_pdo_mapping(pdo_mapping).with_obj_flags(obj_flags);
        if data_type.is_variable_length() {
            let bound = if data_type == DataType::DOMAIN {
                DOMAIN_MAX_LEN
            } else {
                STRING_MAX_LEN
            };
            let len = u32::try_from(value.len()).unwrap_or(u32::MAX);
            if let Ok(bounded) = entry.clone().with_max_len(bound.max(len)) {
                entry = bounded;
            }
        }
        if low.is_some() || high.is_some() {
            match entry.clone().with_limits(low.as_deref(), high.as_deref()) {
                Ok(limited) => entry = limited,
                Err(err) => self.note(
                    index,
                    Some(sub),
                    NoteKind::InvertedLimits,
                    format!("{err}; both limits ignored"),
                ),
            }
        }
        self.entries.push(entry);
    }

    fn data_type(&mut self, key: ObjectKey, attrs: &Attributes, place: Place<'_>) -> DataType {
        let written = attrs
            .data_type
            .as_deref()
            .map(str::trim)
            .filter(|t| !t.is_empty());
        let Some(data_type) = attrs.data_type() else {
            let (fallback, what) = match place {
                Place::Var { domain: true } => (DataType::DOMAIN, "DOMAIN, as the object type says"),
                Place::Sub { .. } if key.sub == 0 => {
                    (DataType::UNSIGNED8, "UNSIGNED8, as for every sub-index 0")
                }
                Place::Sub {
                    parent, array: true, ..
                } if parent.data_type().is_some_and(|t| self.basic(t).is_some()) => (
                    parent
                        .data_type()
                        .and_then(|t| self.basic(t))
                        .unwrap_or(DataType::DOMAIN),
                    "the ARRAY's DataType",
                ),
                _ => (DataType::DOMAIN, "DOMAIN"),
            };
            let found = match written {
                Some(text) => format!("DataType `{text}` is not a number"),
                None => "no DataType".to_owned(),
            };
            self.note(
                key.index,
                Some(key.sub),
                NoteKind::MissingDataType,
                format!("{found}; using {what}"),
            );
            return fallback;
        };
        match self.basic(data_type) {
            Some(basic) => basic,
            None => {
                self.note(
                    key.index,
                    Some(key.sub),
                    NoteKind::UnknownDataType,
                    format!("DataType {data_type} is not a CiA 301 basic type; held as a DOMAIN"),
                );
                DataType::DOMAIN
            }
        }
    }

    /// The CiA 301 basic type `data_type` stands for, following DEFTYPE objects of the file.
    fn basic(&self, data_type: DataType) -> Option<DataType> {
        let resolved = self.eds.resolve_data_type(data_type);
        match resolved.kind() {
            None | Some(TypeKind::Structure) => None,
            Some(_) => Some(resolved),
        }
    }

    fn access(&mut self, key: ObjectKey, attrs: &Attributes, place: Place<'_>) -> Access {
        if let Some(access) = attrs.access_type() {
            return access;
        }
        let inherited = match place {
            Place::Sub { parent, .. } => parent.access_type(),
            Place::Var { .. } => None,
        };
        let found = match attrs
            .access_type
            .as_deref()
            .map(str::trim)
            .filter(|t| !t.is_empty())
        {
            Some(text) => format!("AccessType `{text}` is not one of ro, wo, rw, rwr, rww, const"),
            None => "no AccessType".to_owned(),
        };
        let (access, what) = match inherited {
            Some(access) => (access, "the object's"),
            None => (Access::Ro, "read-only"),
        };
        self.note(
            key.index,
            Some(key.sub),
            NoteKind::MissingAccessType,
            format!("{found}; using {what} ({access})"),
        );
        access
    }

    fn value(
        &mut self,
        key: ObjectKey,
        attrs: &Attributes,
        data_type: DataType,
        place: Place<'_>,
    ) -> Vec<u8> {
        // A DCF's ParameterValue is the configured value and wins over the EDS default (CiA 306, DCF).
        let (name, text) = match (non_empty(&attrs.parameter_value), non_empty(&attrs.default_value)) {
            (Some(text), _) => ("ParameterValue", text),
            (None, Some(text)) => ("DefaultValue", text),
            (None, None) => {
                let (value, what) = match place {
                    Place::Sub { highest, .. } if key.sub == 0 && data_type.is_integer() => (
                        encode_integer(i128::from(highest), data_type).unwrap_or_else(|| zero(data_type)),
                        format!("the highest sub-index present ({highest})"),
                    ),
                    _ => (zero(data_type), fallback_name(data_type).to_owned()),
                };
                self.note(
                    key.index,
                    Some(key.sub),
                    NoteKind::MissingDefault,
                    format!("no ParameterValue or DefaultValue; using {what}"),
                );
                return value;
            }
        };
        let Some(value) = parse_value(text, data_type).value else {
            self.note(
                key.index,
                Some(key.sub),
                NoteKind::InvalidDefault,
                format!(
                    "{name} `{text}` is not a valid {data_type} value; using {}",
                    fallback_name(data_type)
                ),
            );
            return zero(data_type);
        };
        match encode(&value, data_type, self.node_id) {
            Ok(bytes) => bytes,
            Err(problem) => {
                let (kind, why) = match problem {
                    Problem::OutOfRange(shown) => (
                        NoteKind::DefaultOutOfRange,
                        format!("is {shown}, outside the {data_type} range"),
                    ),
                    Problem::Mismatch => (NoteKind::InvalidDefault, format!("is not a {data_type} value")),
                };
                self.note(
                    key.index,
                    Some(key.sub),
                    kind,
                    format!("{name} `{text}` {why}; using {}", fallback_name(data_type)),
                );
                zero(data_type)
            }
        }
    }

    fn pdo_mapping(&mut self, key: ObjectKey, attrs: &Attributes) -> bool {
        let Some(text) = attrs
            .pdo_mapping
            .as_deref()
            .map(str::trim)
            .filter(|t| !t.is_empty())
        else {
            return false;
        };
        match canopener_eds::model::int_of(text) {
            Some(0) => false,
            Some(1) => true,
            _ => {
                self.note(
                    key.index,
                    Some(key.sub),
                    NoteKind::InvalidPdoMapping,
                    format!("PDOMapping `{text}` is neither 0 nor 1; the entry is not mappable"),
                );
                false
            }
        }
    }

    fn obj_flags(&mut self, key: ObjectKey, attrs: &Attributes) -> ObjFlags {
        match attrs.obj_flags() {
            Some(flags) => ObjFlags(flags),
            None => {
                self.note(
                    key.index,
                    Some(key.sub),
                    NoteKind::InvalidObjFlags,
                    format!(
                        "ObjFlags `{}` is not an UNSIGNED32; no flags set",
                        attrs.obj_flags.as_deref().unwrap_or("")
                    ),
                );
                ObjFlags::NONE
            }
        }
    }

    fn limits(
        &mut self,
        key: ObjectKey,
        attrs: &Attributes,
        data_type: DataType,
    ) -> (Option<Vec<u8>>, Option<Vec<u8>>) {
        let mut limit = |name: &str, text: &Option<String>| -> Option<Vec<u8>> {
            let text = text.as_deref().map(str::trim).filter(|t| !t.is_empty())?;
            let why = if !data_type.is_numeric() {
                format!("{data_type} takes no limits")
            } else {
                match parse_value(text, data_type)
                    .value
                    .map(|v| encode(&v, data_type, self.node_id))
                {
                    Some(Ok(bytes)) => return Some(bytes),
                    Some(Err(Problem::OutOfRange(shown))) => {
                        format!("is {shown}, outside the {data_type} range")
                    }
                    Some(Err(Problem::Mismatch)) | None => format!("is not a valid {data_type} value"),
                }
            };
            self.notes.push(BuildNote {
                index: key.index,
                sub: Some(key.sub),
                kind: NoteKind::InvalidLimit,
                detail: format!("{name} `{text}`: {why}; limit ignored"),
            });
            None
        };
        let low = limit("LowLimit", &attrs.low_limit);
        let high = limit("HighLimit", &attrs.high_limit);
        (low, high)
    }
}

/// Why a parsed value cannot be stored as a data type.
enum Problem {
    /// The value (shown as text) lies outside the type's range.
    OutOfRange(String),
    /// The value is of another kind than the type.
    Mismatch,
}

/// The little-endian bytes CiA 301 (data types) defines for `value` as `data_type`.
fn encode(value: &Value, data_type: DataType, node_id: u8) -> Result<Vec<u8>, Problem> {
    let Some(kind) = data_type.kind() else {
        return Err(Problem::Mismatch);
    };
    match (kind, value) {
        (TypeKind::Boolean | TypeKind::Signed(_) | TypeKind::Unsigned(_), _) => {
            let number = value.resolve(node_id).ok_or(Problem::Mismatch)?;
            encode_integer(number, data_type).ok_or_else(|| Problem::OutOfRange(number.to_string()))
        }
        (TypeKind::Real32, Value::Real { value, .. }) => Ok((*value as f32).to_le_bytes().to_vec()),
        (TypeKind::Real64, Value::Real { value, .. }) => Ok(value.to_le_bytes().to_vec()),
        (TypeKind::VisibleString, Value::Text { value }) => Ok(value.as_bytes().to_vec()),
        (TypeKind::UnicodeString, Value::Text { value }) => {
            Ok(value.encode_utf16().flat_map(u16::to_le_bytes).collect())
        }
        (TypeKind::OctetString | TypeKind::Domain, Value::Octets { value }) => Ok(value.clone()),
        (TypeKind::TimeOfDay | TypeKind::TimeDifference, Value::Time { days, ms }) => {
            // 28 bits of milliseconds, 4 reserved bits, then 16 bits of days (CiA 301, TIME_OF_DAY).
            if *ms > 0x0FFF_FFFF {
                return Err(Problem::OutOfRange(format!("{ms} ms")));
            }
            let mut bytes = ms.to_le_bytes().to_vec();
            bytes.extend_from_slice(&days.to_le_bytes());
            Ok(bytes)
        }
        _ => Err(Problem::Mismatch),
    }
}

/// An integer as the bytes of BOOLEAN, INTEGERn or UNSIGNEDn, or `None` outside the type's range.
fn encode_integer(number: i128, data_type: DataType) -> Option<Vec<u8>> {
    let (min, max, size) = match data_type.kind()? {
        TypeKind::Boolean => (0, 1, 1),
        TypeKind::Signed(bits) | TypeKind::Unsigned(bits) => {
            let (min, max) = range_of(bits, matches!(data_type.kind(), Some(TypeKind::Signed(_))));
            (min, max, data_type.byte_size()?)
        }
        _ => return None,
    };
    if number < min || number > max {
        return None;
    }
    // Two's complement little-endian: the low `size` bytes of the 128-bit value.
    number.to_le_bytes().get(..size).map(<[u8]>::to_vec)
}

/// The value an entry gets when its own cannot be used: zero, or empty for variable-length types.
/// The trimmed text of a key, unless it is missing or blank.
fn non_empty(text: &Option<String>) -> Option<&str> {
    text.as_deref().map(str::trim).filter(|t| !t.is_empty())
}

fn zero(data_type: DataType) -> Vec<u8> {
    vec![0; data_type.byte_size().unwrap_or(0)]
}

fn fallback_name(data_type: DataType) -> &'static str {
    if data_type.is_variable_length() {
        "an empty value"
    } else {
        "zero"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "[FileInfo]\nFileName=t.eds\n[DeviceInfo]\nVendorName=v\n";

    fn build(body: &str) -> BuiltOd {
        let loaded = canopener_eds::load(format!("{HEADER}{body}").as_bytes());
        build_od(&loaded.eds, 5).expect("node 5 is valid")
    }

    fn value(built: &BuiltOd, index: u16, sub: u8) -> Vec<u8> {
        built
            .od
            .get(ObjectKey::new(index, sub))
            .map(|e| e.value().to_vec())
            .unwrap_or_else(|| panic!("{index:04X}sub{sub} missing"))
    }

    fn kinds(built: &BuiltOd) -> Vec<(u16, Option<u8>, NoteKind)> {
        built.notes.iter().map(|n| (n.index, n.sub, n.kind)).collect()
    }

    fn var(index: u16, data_type: &str, access: &str, extra: &str) -> String {
        format!(
            "[{index:04X}]\nParameterName=x\nObjectType=0x7\n\
             DataType={data_type}\nAccessType={access}\n{extra}"
        )
    }

    #[test]
    fn rejects_node_ids_outside_1_to_127() {
        let eds = Eds::default();
        for node_id in [0, 128, 255] {
            assert_eq!(
                build_od(&eds, node_id).map(|_| ()),
                Err(OdBuildError::InvalidNodeId { node_id })
            );
        }
        assert!(build_od(&eds, 1).is_ok() && build_od(&eds, 127).is_ok());
    }

    #[test]
    fn every_basic_type_encodes_its_default() {
        let cases: [(&str, &str, &[u8]); 22] = [
            ("0x0001", "1", &[1]),
            ("0x0002", "-2", &[0xFE]),
            ("0x0003", "-300", &(-300i16).to_le_bytes()),
            ("0x0004", "0x12345678", &[0x78, 0x56, 0x34, 0x12]),
            ("0x0005", "200", &[200]),
            ("0x0006", "0x3E8", &[0xE8, 0x03]),
            ("0x0007", "4294967295", &[0xFF; 4]),
            ("0x0008", "1.5", &1.5f32.to_le_bytes()),
            ("0x0008", "0x3FC00000", &1.5f32.to_le_bytes()),
            ("0x0009", "hello", b"hello"),
            ("0x000A", "DEADBEEF", &[0xDE, 0xAD, 0xBE, 0xEF]),
            ("0x000B", "hé", &[b'h', 0, 0xE9, 0]),
            ("0x000C", "2 1000", &[0xE8, 0x03, 0, 0, 2, 0]),
            ("0x000F", "0102", &[1, 2]),
            ("0x0010", "-1", &[0xFF; 3]),
            ("0x0011", "-2.25", &(-2.25f64).to_le_bytes()),
            ("0x0012", "0x0102030405", &[5, 4, 3, 2, 1]),
            ("0x0013", "1", &[1, 0, 0, 0, 0, 0]),
            ("0x0014", "-1", &[0xFF; 7]),
            ("0x0016", "0xABCDEF", &[0xEF, 0xCD, 0xAB]),
            ("0x001A", "0x01", &[1, 0, 0, 0, 0, 0, 0]),
            ("0x001B", "0xFFFFFFFFFFFFFFFF", &[0xFF; 8]),
        ];
        for (data_type, text, expected) in cases {
            let built = build(&var(0x2000, data_type, "rw", &format!("DefaultValue={text}\n")));
            assert_eq!(value(&built, 0x2000, 0), expected, "{data_type} `{text}`");
            assert!(built.notes.is_empty(), "{data_type}: {:?}", built.notes);
        }
    }

    #[test]
    fn nodeid_formulas_resolve_and_parameter_value_wins() {
        let body = var(0x1800, "0x0007", "rw", "DefaultValue=$NODEID+0x180\n")
            + &var(0x1017, "0x0006", "rw", "DefaultValue=0\nParameterValue=1000\n")
            + &var(
                0x1014,
                "0x0007",
                "rw",
                "DefaultValue=0x80+$NODEID\nParameterValue=\n",
            );
        let built = build(&body);
        assert_eq!(value(&built, 0x1800, 0), 0x185u32.to_le_bytes());
        assert_eq!(value(&built, 0x1017, 0), 1000u16.to_le_bytes());
        assert_eq!(value(&built, 0x1014, 0), 0x85u32.to_le_bytes());
        assert!(built.notes.is_empty(), "{:?}", built.notes);
    }

    #[test]
    fn missing_default_becomes_zero_empty_or_highest_sub() {
        let body = var(0x2000, "0x0007", "rw", "")
            + &var(0x2001, "0x000F", "rw", "")
            + "[2002]\nParameterName=a\nObjectType=0x8\nDataType=0x0005\nSubNumber=3\n\
               [2002sub0]\nParameterName=n\nDataType=0x0005\nAccessType=ro\n\
               [2002sub4]\nParameterName=e\nDataType=0x0005\nAccessType=rw\nDefaultValue=1\n";
        let built = build(&body);
        assert_eq!(value(&built, 0x2000, 0), [0; 4]);
        assert_eq!(value(&built, 0x2001, 0), [0u8; 0]);
        assert_eq!(value(&built, 0x2002, 0), [4]);
        assert_eq!(
            kinds(&built),
            [
                (0x2000, Some(0), NoteKind::MissingDefault),
                (0x2001, Some(0), NoteKind::MissingDefault),
                (0x2002, Some(0), NoteKind::MissingDefault),
            ]
        );
        assert!(built.notes[1].detail.contains("empty"), "{}", built.notes[1]);
        assert!(
            built.notes[2].to_string().starts_with("2002sub0: "),
            "{}",
            built.notes[2]
        );
    }

    #[test]
    fn unparsable_and_out_of_range_defaults_become_zero() {
        let body = var(0x2000, "0x0006", "rw", "DefaultValue=lots\n")
            + &var(0x2001, "0x0005", "rw", "DefaultValue=300\n")
            + &var(0x2002, "0x0005", "rw", "DefaultValue=$NODEID+0xFF\n")
            + &var(0x2003, "0x000A", "rw", "DefaultValue=XYZ\n")
            + &var(0x2004, "0x000C", "rw", "DefaultValue=1 300000000\n");
        let built = build(&body);
        assert_eq!(value(&built, 0x2000, 0), [0, 0]);
        assert_eq!(value(&built, 0x2001, 0), [0]);
        assert_eq!(value(&built, 0x2002, 0), [0]);
        assert_eq!(value(&built, 0x2003, 0), [0u8; 0]);
        assert_eq!(value(&built, 0x2004, 0), [0; 6]);
        assert_eq!(
            kinds(&built),
            [
                (0x2000, Some(0), NoteKind::InvalidDefault),
                (0x2001, Some(0), NoteKind::DefaultOutOfRange),
                (0x2002, Some(0), NoteKind::DefaultOutOfRange),
                (0x2003, Some(0), NoteKind::InvalidDefault),
                (0x2004, Some(0), NoteKind::DefaultOutOfRange),
            ]
        );
        assert!(built.notes[2].detail.contains("260"), "{}", built.notes[2]);
    }

    #[test]
    fn data_type_fallbacks() {
        let body = "[2000]\nParameterName=a\nObjectType=0x8\nDataType=0x0006\nAccessType=rw\n\
                    [2000sub0]\nParameterName=n\nAccessType=ro\nDefaultValue=1\n\
                    [2000sub1]\nParameterName=e\nAccessType=rw\nDefaultValue=7\n"
            .to_owned()
            + "[2001]\nParameterName=d\nObjectType=0x2\nAccessType=rw\n"
            + &var(0x2002, "0x0020", "rw", "DefaultValue=0\n")
            + &var(0x2003, "nope", "rw", "");
        let built = build(&body);
        let data_type = |index, sub| built.od.get(ObjectKey::new(index, sub)).map(Entry::data_type);
        assert_eq!(data_type(0x2000, 0), Some(DataType::UNSIGNED8));
        assert_eq!(data_type(0x2000, 1), Some(DataType::UNSIGNED16));
        assert_eq!(value(&built, 0x2000, 1), [7, 0]);
        assert_eq!(data_type(0x2001, 0), Some(DataType::DOMAIN));
        assert_eq!(data_type(0x2002, 0), Some(DataType::DOMAIN));
        assert_eq!(data_type(0x2003, 0), Some(DataType::DOMAIN));
        let kinds = kinds(&built);
        for expected in [
            (0x2000, Some(0), NoteKind::MissingDataType),
            (0x2000, Some(1), NoteKind::MissingDataType),
            (0x2001, Some(0), NoteKind::MissingDataType),
            (0x2001, Some(0), NoteKind::MissingDefault),
            (0x2002, Some(0), NoteKind::UnknownDataType),
            (0x2003, Some(0), NoteKind::MissingDataType),
        ] {
            assert!(kinds.contains(&expected), "{expected:?} not in {kinds:?}");
        }
    }

    #[test]
    fn deftype_objects_are_followed_and_skipped() {
        // CANFestival writes custom types as DEFTYPE objects naming the basic type.
        let body =
            "[0040]\nParameterName=t\nObjectType=0x5\nDataType=0x0007\nAccessType=ro\nDefaultValue=0x0006\n"
                .to_owned()
                + &var(0x2000, "0x0040", "rw", "DefaultValue=513\n")
                + "[0041]\nParameterName=s\nObjectType=0x6\nSubNumber=1\n\
                   [0041sub0]\nParameterName=n\nDataType=0x0005\nAccessType=ro\nDefaultValue=1\n";
        let built = build(&body);
        assert_eq!(built.od.len(), 1);
        let entry = built.od.get(ObjectKey::new(0x2000, 0)).expect("built");
        assert_eq!(
            (entry.data_type(), entry.value()),
            (DataType::UNSIGNED16, &[1u8, 2][..])
        );
        assert!(built.notes.is_empty(), "{:?}", built.notes);
    }

    #[test]
    fn access_fallbacks() {
        let body = var(0x2000, "0x0005", "", "DefaultValue=1\n")
            + &var(0x2001, "0x0005", "readwrite", "DefaultValue=1\n")
            + "[2002]\nParameterName=r\nObjectType=0x9\nAccessType=rw\n\
               [2002sub0]\nParameterName=n\nDataType=0x0005\nDefaultValue=1\n";
        let built = build(&body);
        let access = |index| built.od.get(ObjectKey::new(index, 0)).map(Entry::access);
        assert_eq!(access(0x2000), Some(Access::Ro));
        assert_eq!(access(0x2001), Some(Access::Ro));
        assert_eq!(access(0x2002), Some(Access::Rw));
        assert_eq!(
            kinds(&built),
            [
                (0x2000, Some(0), NoteKind::MissingAccessType),
                (0x2001, Some(0), NoteKind::MissingAccessType),
                (0x2002, Some(0), NoteKind::MissingAccessType),
            ]
        );
    }

    #[test]
    fn limits_are_kept_and_bad_ones_dropped() {
        let body = var(
            0x2000,
            "0x0004",
            "rw",
            "DefaultValue=0\nLowLimit=-10\nHighLimit=$NODEID+5\n",
        ) + &var(
            0x2001,
            "0x0005",
            "rw",
            "DefaultValue=0\nLowLimit=abc\nHighLimit=300\n",
        ) + &var(
            0x2002,
            "0x0005",
            "rw",
            "DefaultValue=0\nLowLimit=9\nHighLimit=3\n",
        ) + &var(0x2003, "0x0009", "rw", "DefaultValue=x\nHighLimit=3\n")
            + &var(
                0x2004,
                "0x0008",
                "rw",
                "DefaultValue=0\nLowLimit=-1.5\nHighLimit=0x40200000\n",
            );
        let built = build(&body);
        let mut od = built.od;
        let abort = |od: &mut DynamicOd, index, data: &[u8]| {
            od.write(ObjectKey::new(index, 0), data)
                .map_err(|e| e.abort_code())
        };
        assert_eq!(abort(&mut od, 0x2000, &11i32.to_le_bytes()), Err(0x0609_0031));
        assert_eq!(abort(&mut od, 0x2000, &10i32.to_le_bytes()), Ok(()));
        assert_eq!(abort(&mut od, 0x2000, &(-11i32).to_le_bytes()), Err(0x0609_0032));
        assert_eq!(abort(&mut od, 0x2001, &[255]), Ok(()));
        assert_eq!(abort(&mut od, 0x2002, &[100]), Ok(()));
        assert_eq!(abort(&mut od, 0x2004, &2.5f32.to_le_bytes()), Ok(()));
        assert_eq!(abort(&mut od, 0x2004, &2.6f32.to_le_bytes()), Err(0x0609_0031));
        assert_eq!(abort(&mut od, 0x2004, &(-2.0f32).to_le_bytes()), Err(0x0609_0032));
        assert_eq!(
            kinds(&BuiltOd {
                od,
                notes: built.notes
            }),
            [
                (0x2001, Some(0), NoteKind::InvalidLimit),
                (0x2001, Some(0), NoteKind::InvalidLimit),
                (0x2002, Some(0), NoteKind::InvertedLimits),
                (0x2003, Some(0), NoteKind::InvalidLimit),
            ]
        );
    }

    #[test]
    fn pdo_mapping_and_obj_flags() {
        let body = var(
            0x2000,
            "0x0005",
            "rww",
            "DefaultValue=0\nPDOMapping=1\nObjFlags=0x3\n",
        ) + &var(
            0x2001,
            "0x0005",
            "rw",
            "DefaultValue=0\nPDOMapping=2\nObjFlags=lots\n",
        );
        let built = build(&body);
        let a = built.od.get(ObjectKey::new(0x2000, 0)).expect("built");
        assert!(a.pdo_mapping() && a.rpdo_mappable() && !a.tpdo_mappable());
        assert_eq!(a.obj_flags(), ObjFlags(3));
        let b = built.od.get(ObjectKey::new(0x2001, 0)).expect("built");
        assert!(!b.pdo_mapping());
        assert_eq!(b.obj_flags(), ObjFlags::NONE);
        assert_eq!(
            kinds(&built),
            [
                (0x2001, Some(0), NoteKind::InvalidPdoMapping),
                (0x2001, Some(0), NoteKind::InvalidObjFlags),
            ]
        );
    }

    #[test]
    fn string_and_domain_maxima() {
        let long = "x".repeat(300);
        let body = var(0x2000, "0x0009", "rw", "DefaultValue=abc\n")
            + &var(0x2001, "0x0009", "rw", &format!("DefaultValue={long}\n"))
            + &var(0x2002, "0x000F", "rw", "DefaultValue=00\n");
        let built = build(&body);
        let max = |index| built.od.get(ObjectKey::new(index, 0)).and_then(Entry::max_len);
        assert_eq!(max(0x2000), Some(STRING_MAX_LEN));
        assert_eq!(max(0x2001), Some(300));
        assert_eq!(max(0x2002), Some(DOMAIN_MAX_LEN));
        let mut od = built.od;
        let err = od
            .write(ObjectKey::new(0x2000, 0), &[b'y'; 257])
            .map_err(|e| e.abort_code());
        assert_eq!(err, Err(0x0607_0012));
    }

    #[test]
    fn object_shape_notes() {
        let body = "[0000]\nParameterName=z\nObjectType=0x7\nDataType=0x0005\nAccessType=ro\nDefaultValue=0\n"
            .to_owned()
            + "[2000]\nParameterName=r\nObjectType=0x9\nSubNumber=0\n"
            + &var(0x2001, "0x0005", "rw", "DefaultValue=1\n")
            + "[2001sub1]\nParameterName=s\nDataType=0x0005\nAccessType=rw\nDefaultValue=2\n"
            + "[2002]\nParameterName=q\nObjectType=0x3\nDataType=0x0005\nAccessType=rw\nDefaultValue=3\n"
            + "[2003sub0]\nParameterName=o\nDataType=0x0005\nAccessType=ro\nDefaultValue=1\n"
            + &var(0x2004, "0x000F", "rw", "DownloadFile=image.bin\n");
        let built = build(&body);
        assert_eq!(value(&built, 0x2001, 0), [1]);
        assert!(built.od.get(ObjectKey::new(0x2001, 1)).is_none());
        assert_eq!(value(&built, 0x2002, 0), [3]);
        assert_eq!(value(&built, 0x2003, 0), [1]);
        assert!(built.od.object(0x2000).is_empty() && built.od.object(0).is_empty());
        let kinds = kinds(&built);
        for expected in [
            (0x0000, None, NoteKind::InvalidIndex),
            (0x2000, None, NoteKind::NoSubObjects),
            (0x2001, None, NoteKind::SubObjectsIgnored),
            (0x2002, None, NoteKind::UnknownObjectType),
            (0x2003, None, NoteKind::MissingObjectSection),
            (0x2004, Some(0), NoteKind::FileNotRead),
        ] {
            assert!(kinds.contains(&expected), "{expected:?} not in {kinds:?}");
        }
    }

    #[test]
    fn compact_sub_obj_entries_are_built() {
        let body = "[2000]\nParameterName=c\nObjectType=0x8\nDataType=0x0006\nAccessType=rw\n\
                    DefaultValue=7\nCompactSubObj=3\n";
        let built = build(body);
        assert_eq!(built.od.object(0x2000).len(), 4);
        assert_eq!(value(&built, 0x2000, 0), [3]);
        assert_eq!(value(&built, 0x2000, 3), [7, 0]);
    }

    #[test]
    fn capacity_is_exact() {
        let built = build(
            &(var(0x2000, "0x0005", "rw", "DefaultValue=0\n")
                + &var(0x2001, "0x0005", "rw", "DefaultValue=0\n")),
        );
        assert_eq!((built.od.len(), built.od.capacity()), (2, 2));
    }

    #[test]
    fn full_error_comes_from_the_dictionary() {
        let err = OdBuildError::from(OdError::Full {
            capacity: 0,
            key: ObjectKey::new(0x1000, 0),
        });
        assert!(err.to_string().contains("cannot hold"), "{err}");
    }
}

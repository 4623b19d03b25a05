//! Reference profiles: what CiA 301 (communication objects 1000h–1FFFh) and CiA 401 (generic I/O,
//! 6000h–6FFFh) say about their standard objects, shipped as TOML data with the crate.
//!
//! The checker compares a file's standard objects with these tables (group K); the device
//! simulator uses them to build standard objects. A profile only states what its sources state:
//! every attribute is optional, and `None` means "not stated", never "anything goes" or "absent".
//! The data files (`data/cia301.toml`, `data/cia401.toml`) name the source of every fact.
//!
//! ```
//! use canopener_check::profile;
//!
//! let profiles = profile::for_device_type(0x000F_0191);
//! assert_eq!(profiles.iter().map(|p| p.number).collect::<Vec<_>>(), [301, 401]);
//! let heartbeat = profile::cia301().object(0x1017).map(|o| o.spec.data_type);
//! assert_eq!(heartbeat, Some(Some(canopener_eds::DataType::UNSIGNED16)));
//! ```

use std::sync::LazyLock;

use canopener_eds::{AccessType, DataType, ObjectType};
use serde::Deserialize;

/// Whether a profile requires an object.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Category {
    /// Every device of the profile has it.
    Mandatory,
    /// Required when the device has the function it belongs to (e.g. 1014h when EMCY is produced).
    Conditional,
    /// The device may have it.
    Optional,
}

/// Whether an entry may be mapped into a PDO.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PdoMapping {
    /// Not mappable (`PDOMapping=0`).
    No,
    /// The device decides.
    Optional,
    /// Mappable (`PDOMapping=1`); the profile's default PDOs use it.
    Yes,
}

/// What a profile states about one value: an object's own value (VAR) or one sub-object.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct EntrySpec {
    /// The data type.
    pub data_type: Option<DataType>,
    /// The access type the profile gives (`ro` and `const` mean the same to the checker, as do
    /// `rw`, `rwr` and `rww`).
    pub access: Option<AccessType>,
    /// Whether it may be mapped into a PDO.
    pub pdo_mapping: Option<PdoMapping>,
}

impl EntrySpec {
    /// This spec with the attributes it does not state taken from `fallback`.
    pub fn or(self, fallback: EntrySpec) -> EntrySpec {
        EntrySpec {
            data_type: self.data_type.or(fallback.data_type),
            access: self.access.or(fallback.access),
            pdo_mapping: self.pdo_mapping.or(fallback.pdo_mapping),
        }
    }
}

/// One sub-index, or a range of sub-indices with the same description.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProfileSub {
    /// The first sub-index described.
    pub first: u8,
    /// The last sub-index described (equal to `first` for a single one).
    pub last: u8,
    /// The name the profile gives it.
    pub name: String,
    /// Its own attributes (sub-indices ≥ 1 inherit what is not stated from the object).
    pub spec: EntrySpec,
    /// Whether every device that has the object must have this sub-index.
    pub required: bool,
}

/// One standard object, or a range of objects with the same description (1400h–15FFh).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProfileObject {
    /// The first index described.
    pub first: u16,
    /// The last index described (equal to `first` for a single object).
    pub last: u16,
    /// The name the profile gives it.
    pub name: String,
    /// The object type (VAR, ARRAY, RECORD).
    pub object_type: Option<ObjectType>,
    /// Whether devices must have it.
    pub category: Option<Category>,
    /// The value's attributes: the VAR itself, or every sub-index ≥ 1 not described in `subs`.
    pub spec: EntrySpec,
    /// The sub-index layout in sub-index order; empty when the profile does not state one.
    pub subs: Vec<ProfileSub>,
    /// Where the facts come from (keys of the reference notes, see the data file's header).
    pub source: String,
}

impl ProfileObject {
    /// Whether this description covers an index.
    pub fn covers(&self, index: u16) -> bool {
        (self.first..=self.last).contains(&index)
    }

    /// The description of a sub-index, if the layout lists it.
    pub fn sub(&self, sub: u8) -> Option<&ProfileSub> {
        self.subs.iter().find(|s| (s.first..=s.last).contains(&sub))
    }

    /// Whether the profile states a sub-index layout for this object.
    pub fn has_layout(&self) -> bool {
        !self.subs.is_empty()
    }

    /// Whether a device may have this sub-index: it is in the layout, the layout is not stated, or
    /// it is FFh (CiA 301's structure descriptor, allowed on every ARRAY and RECORD).
    pub fn allows_sub(&self, sub: u8) -> bool {
        sub == 0xFF || !self.has_layout() || self.sub(sub).is_some()
    }

    /// The attributes of the object's value (`None`) or of a sub-index. Sub 0 ("highest
    /// sub-index") only has what its own description states; sub-indices ≥ 1 inherit the object's.
    pub fn spec_for(&self, sub: Option<u8>) -> EntrySpec {
        match sub {
            None => self.spec,
            Some(0) => self.sub(0).map(|s| s.spec).unwrap_or_default(),
            Some(n) => self.sub(n).map_or(self.spec, |s| s.spec.or(self.spec)),
        }
    }

    /// The sub-indices every device with this object must have, in order.
    pub fn required_subs(&self) -> impl Iterator<Item = u8> + '_ {
        self.subs
            .iter()
            .filter(|s| s.required)
            .flat_map(|s| s.first..=s.last)
    }
}

/// A reference profile: the standard objects of one CiA specification.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Profile {
    /// The CiA number (301, 401); device profiles match 1000h bits 0–15.
    pub number: u16,
    /// A human-readable name.
    pub name: String,
    /// The first index of the area the profile defines.
    pub first: u16,
    /// The last index of that area.
    pub last: u16,
    /// The objects, in index order, without overlaps.
    pub objects: Vec<ProfileObject>,
}

/// A profile text that cannot be used.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ProfileError {
    /// The text is not TOML of the expected shape.
    #[error("profile is not valid TOML: {0}")]
    Toml(String),
    /// An object description is inconsistent.
    #[error("object {index:04X}h: {message}")]
    Object {
        /// The first index of the description.
        index: u16,
        /// What is wrong.
        message: String,
    },
}

impl Profile {
    /// Reads a profile from TOML in the layout of the shipped `data/cia301.toml`.
    ///
    /// Objects may be written in any order; they are sorted. Overlapping objects or sub-index
    /// ranges, ranges that run backwards, objects outside `first..=last`, unknown type or access
    /// names and unknown keys are errors.
    pub fn from_toml(text: &str) -> Result<Profile, ProfileError> {
        let raw: RawProfile = toml::from_str(text).map_err(|e| ProfileError::Toml(e.to_string()))?;
        let mut objects = raw
            .object
            .into_iter()
            .map(RawObject::build)
            .collect::<Result<Vec<_>, _>>()?;
        objects.sort_by_key(|o| o.first);
        for object in &objects {
            if object.first < raw.first || object.last > raw.last {
                return Err(ProfileError::Object {
                    index: object.first,
                    message: format!("outside the profile's area {:04X}h..{:04X}h", raw.first, raw.last),
                });
            }
        }
        for pair in objects.windows(2) {
            if let [a, b] = pair
                && b.first <= a.last
            {
                return Err(ProfileError::Object {
                    index: b.first,
                    message: format!("overlaps {:04X}h..{:04X}h", a.first, a.last),
                });
            }
        }
        Ok(Profile {
            number: raw.number,
            name: raw.name,
            first: raw.first,
            last: raw.last,
            objects,
        })
    }

    /// The description covering an index.
    pub fn object(&self, index: u16) -> Option<&ProfileObject> {
        // Objects are sorted and disjoint: the candidate is the last one starting at or before index.
        let after = self.objects.partition_point(|o| o.first <= index);
        let candidate = self.objects.get(after.checked_sub(1)?)?;
        candidate.covers(index).then_some(candidate)
    }

    /// Whether an index lies in the area this profile defines.
    pub fn covers(&self, index: u16) -> bool {
        (self.first..=self.last).contains(&index)
    }
}

/// The CiA 301 communication profile (1000h–1FFFh, plus 1F80h from CiA 302-2).
pub fn cia301() -> &'static Profile {
    &CIA301
}

/// The CiA 401 generic I/O profile (6000h–6FFFh).
pub fn cia401() -> &'static Profile {
    &CIA401
}

/// The shipped device profile with this number (1000h bits 0–15), if canopener has one.
pub fn device_profile(number: u16) -> Option<&'static Profile> {
    match number {
        401 => Some(cia401()),
        _ => None,
    }
}

/// The profiles that apply to a device with this device type (1000h): CiA 301 always, and the
/// device profile named by bits 0–15 when canopener ships it.
pub fn for_device_type(device_type: u32) -> Vec<&'static Profile> {
    let number = (device_type & 0xFFFF) as u16; // the low 16 bits always fit
    std::iter::once(cia301()).chain(device_profile(number)).collect()
}

static CIA301: LazyLock<Profile> = LazyLock::new(|| embedded(include_str!("../data/cia301.toml")));
static CIA401: LazyLock<Profile> = LazyLock::new(|| embedded(include_str!("../data/cia401.toml")));

/// Parses a profile compiled into the crate.
fn embedded(text: &str) -> Profile {
    // The shipped files are fixed at build time and parsed by `shipped_profiles_parse` below, so an
    // error here is a defect in the data, never a property of any file being checked.
    Profile::from_toml(text).unwrap_or_else(|e| panic!("shipped profile data is invalid: {e}"))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawProfile {
    number: u16,
    name: String,
    first: u16,
    last: u16,
    #[serde(default)]
    object: Vec<RawObject>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawObject {
    index: u16,
    last: Option<u16>,
    name: String,
    object_type: Option<String>,
    data_type: Option<String>,
    access: Option<String>,
    pdo_mapping: Option<String>,
    category: Option<String>,
    source: String,
    #[serde(default)]
    sub: Vec<RawSub>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSub {
    sub: u8,
    last: Option<u8>,
    name: String,
    data_type: Option<String>,
    access: Option<String>,
    pdo_mapping: Option<String>,
    #[serde(default)]
    required: bool,
}

impl RawObject {
    fn build(self) -> Result<ProfileObject, ProfileError> {
        let index = self.index;
        let fail = |message: String| ProfileError::Object { index, message };
        let last = self.last.unwrap_or(index);
        if last < index {
            return Err(fail(format!("range ends at {last:04X}h, before it starts")));
        }
        let object_type = self
            .object_type
            .as_deref()
            .map(|name| object_type(name).ok_or_else(|| fail(format!("unknown object type `{name}`"))))
            .transpose()?;
        let category = self
            .category
            .as_deref()
            .map(|name| category(name).ok_or_else(|| fail(format!("unknown category `{name}`"))))
            .transpose()?;
        let spec = entry_spec(
            self.data_type.as_deref(),
            self.access.as_deref(),
            self.pdo_mapping.as_deref(),
        )
        .map_err(&fail)?;
        let mut subs = self
            .sub
            .into_iter()
            .map(|raw| {
                let last = raw.last.unwrap_or(raw.sub);
                if last < raw.sub {
                    return Err(format!(
                        "sub-index range {:X}h..{last:X}h runs backwards",
                        raw.sub
                    ));
                }
                Ok(ProfileSub {
                    first: raw.sub,
                    last,
                    name: raw.name,
                    spec: entry_spec(
                        raw.data_type.as_deref(),
                        raw.access.as_deref(),
                        raw.pdo_mapping.as_deref(),
                    )?,
                    required: raw.required,
                })
            })
            .collect::<Result<Vec<_>, String>>()
            .map_err(&fail)?;
        subs.sort_by_key(|s| s.first);
        for pair in subs.windows(2) {
            if let [a, b] = pair
                && b.first <= a.last
            {
                return Err(fail(format!("sub-index {:X}h is described twice", b.first)));
            }
        }
        Ok(ProfileObject {
            first: index,
            last,
            name: self.name,
            object_type,
            category,
            spec,
            subs,
            source: self.source,
        })
    }
}

fn entry_spec(data_type: Option<&str>, access: Option<&str>, pdo: Option<&str>) -> Result<EntrySpec, String> {
    Ok(EntrySpec {
        data_type: data_type
            .map(|name| type_named(name).ok_or_else(|| format!("unknown data type `{name}`")))
            .transpose()?,
        access: access
            .map(|name| AccessType::parse(name).ok_or_else(|| format!("unknown access type `{name}`")))
            .transpose()?,
        pdo_mapping: pdo
            .map(|name| pdo_mapping(name).ok_or_else(|| format!("unknown PDO mapping `{name}`")))
            .transpose()?,
    })
}

fn type_named(name: &str) -> Option<DataType> {
    DataType::BASIC.into_iter().find(|t| t.name() == Some(name))
}

fn object_type(name: &str) -> Option<ObjectType> {
    [
        ObjectType::Var,
        ObjectType::Array,
        ObjectType::Record,
        ObjectType::Domain,
    ]
    .into_iter()
    .find(|t| t.to_string() == name)
}

fn category(name: &str) -> Option<Category> {
    match name {
        "mandatory" => Some(Category::Mandatory),
        "conditional" => Some(Category::Conditional),
        "optional" => Some(Category::Optional),
        _ => None,
    }
}

fn pdo_mapping(name: &str) -> Option<PdoMapping> {
    match name {
        "no" => Some(PdoMapping::No),
        "optional" => Some(PdoMapping::Optional),
        "yes" => Some(PdoMapping::Yes),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shipped() -> [Result<Profile, ProfileError>; 2] {
        [
            Profile::from_toml(include_str!("../data/cia301.toml")),
            Profile::from_toml(include_str!("../data/cia401.toml")),
        ]
    }

    #[test]
    fn shipped_profiles_parse() {
        for parsed in shipped() {
            let profile = parsed.unwrap_or_else(|e| panic!("{e}"));
            assert!(!profile.objects.is_empty(), "{} has no objects", profile.number);
        }
        assert_eq!(cia301().number, 301);
        assert_eq!(cia401().number, 401);
    }

    #[test]
    fn shipped_profiles_are_consistent() {
        for profile in [cia301(), cia401()] {
            for object in &profile.objects {
                let at = format!("{} {:04X}h", profile.number, object.first);
                assert!(!object.source.trim().is_empty(), "{at}: no source");
                assert!(!object.name.trim().is_empty(), "{at}: no name");
                if object.has_layout() {
                    // A layout describes a structured object, and every structured object has sub 0
                    // (the highest sub-index), UNSIGNED8, that never inherits the entries' attributes.
                    let sub0 = object.sub(0);
                    assert!(
                        sub0.is_some_and(|s| s.required),
                        "{at}: layout without a required sub 0"
                    );
                    assert_eq!(
                        object.spec_for(Some(0)).data_type,
                        Some(DataType::UNSIGNED8),
                        "{at}"
                    );
                    assert!(
                        !matches!(object.object_type, Some(ObjectType::Var | ObjectType::Domain)),
                        "{at}: a VAR with sub-indices"
                    );
                    assert!(
                        object.subs.iter().all(|s| s.last < 0xFF),
                        "{at}: FFh is the structure descriptor"
                    );
                }
                if object.object_type == Some(ObjectType::Array) {
                    // An ARRAY's entries share one type (CiA 301), so it is stated once on the object.
                    assert!(
                        object.spec.data_type.is_some(),
                        "{at}: ARRAY without an entry type"
                    );
                    assert!(
                        object
                            .subs
                            .iter()
                            .filter(|s| s.first > 0)
                            .all(|s| s.spec.data_type.is_none()),
                        "{at}: ARRAY entries with their own types"
                    );
                }
                if object.object_type == Some(ObjectType::Var) {
                    assert!(object.spec.data_type.is_some(), "{at}: VAR without a data type");
                }
            }
        }
    }

    #[test]
    fn lookup_by_index_and_device_type() {
        let p301 = cia301();
        assert_eq!(p301.object(0x1401).map(|o| o.first), Some(0x1400));
        assert_eq!(p301.object(0x15FF).map(|o| o.first), Some(0x1400));
        assert!(p301.object(0x1002).is_none());
        assert!(p301.object(0x0FFF).is_none());
        let mapping = p301.object(0x1A03).map(|o| o.spec_for(Some(0x40)).data_type);
        assert_eq!(mapping, Some(Some(DataType::UNSIGNED32)));
        let rpdo = p301.object(0x1400);
        assert_eq!(rpdo.map(|o| o.allows_sub(6)), Some(false));
        assert_eq!(rpdo.map(|o| o.allows_sub(0xFF)), Some(true));
        assert_eq!(
            rpdo.map(|o| o.required_subs().collect::<Vec<_>>()),
            Some(vec![0, 1, 2])
        );
        let identity = p301.object(0x1018);
        assert_eq!(
            identity.map(|o| o.spec_for(Some(2)).access),
            Some(Some(AccessType::Ro))
        );
        let inputs = cia401().object(0x6000);
        assert_eq!(inputs.map(|o| o.spec_for(Some(0)).pdo_mapping), Some(None));
        assert_eq!(
            inputs.map(|o| o.spec_for(Some(8)).pdo_mapping),
            Some(Some(PdoMapping::Yes))
        );
        assert_eq!(for_device_type(0x0002_0192).len(), 1);
        assert_eq!(for_device_type(0x0003_0191).len(), 2);
    }

    #[test]
    fn inconsistent_profiles_are_rejected() {
        let head = "number = 9\nname = \"t\"\nfirst = 0x2000\nlast = 0x2FFF\n";
        let object =
            |body: &str| format!("{head}[[object]]\nindex = 0x2000\nname = \"x\"\nsource = \"s\"\n{body}");
        let cases = [
            (object("data_type = \"UNSIGNED7\"\n"), "unknown data type"),
            (object("access = \"rx\"\n"), "unknown access type"),
            (object("last = 0x1FFF\n"), "before it starts"),
            (object("colour = 1\n"), "unknown field"),
            (
                object(
                    "[[object.sub]]\nsub = 1\nlast = 3\nname = \"a\"\n[[object.sub]]\nsub = 2\nname = \"b\"\n",
                ),
                "described twice",
            ),
            (
                format!(
                    "{}[[object]]\nindex = 0x1000\nname = \"x\"\nsource = \"s\"\n",
                    head
                ),
                "outside",
            ),
            (
                format!(
                    "{}[[object]]\nindex = 0x2001\nname = \"y\"\nsource = \"s\"\n",
                    object("last = 0x2002\n")
                ),
                "overlaps",
            ),
        ];
        for (text, expected) in cases {
            match Profile::from_toml(&text) {
                Ok(_) => panic!("accepted:\n{text}"),
                Err(e) => assert!(e.to_string().contains(expected), "{e} (expected `{expected}`)"),
            }
        }
    }
}

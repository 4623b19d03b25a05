//! The canopener side channel: EDS content that has no CiA 311 element, kept in `property` elements
//! so that EDS → XDD → EDS loses nothing (reference §16). Non-standard but schema-valid: `property`
//! is CiA 311's own extension point, and tools that do not know these names ignore them.
//!
//! Every property is named `EDS:<control>` and its value says what to do:
//!
//! | control | value | where | meaning |
//! |---|---|---|---|
//! | `set` | `Key=value` | entry parameter | set an object or sub-object key |
//! | `set` | `Section:Key=value` | file parameter | set a `[FileInfo]`, `[DeviceInfo]` or `[DeviceComissioning]` key |
//! | `absent` | `Key` / `Section:Key` | both | the EDS does not have a key the XDD form would give |
//! | `absent` | `MandatoryObjects` ... | file parameter | the EDS has no such object list (the lists as written follow) |
//! | `links`, `link` | ``, `key=value` | entry parameter | `[<index>ObjectLinks]` and its entries |
//! | `origin` | `orphan` | entry parameter | the object only holds orphan sub-object sections |
//! | `section`, `entry` | `Name`, `key=value` | file parameter | a whole section as written, then its entries |
//! | `modules` | JSON | file parameter | the `M<x>` module descriptions of a modular device |
//! | `spelling` | `DeviceCommissioning` | file parameter | the commissioning section's spelling |
//! | `version` | `1` | file parameter | the side-channel format |
//!
//! The file-level properties sit on a parameter no object references, `UID_CANOPENER_EDS`. A value
//! with characters XML cannot carry is written under `EDS%:<control>`, percent-encoded.

use canopener_eds::Attributes;

use crate::xml::{needs_encoding, percent_decode, percent_encode};

/// The uniqueID of the parameter that carries the file-level side channel.
pub(crate) const FILE_PARAMETER_ID: &str = "UID_CANOPENER_EDS";

/// The side-channel format written by this version.
pub(crate) const VERSION: &str = "1";

/// The `origin` value of an orphan placeholder object.
pub(crate) const ORPHAN: &str = "orphan";

const PREFIX: &str = "EDS:";
const ENCODED_PREFIX: &str = "EDS%:";

/// What a side-channel property does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Control {
    Set,
    Absent,
    Links,
    Link,
    Origin,
    Section,
    Entry,
    Modules,
    Spelling,
    Version,
    /// A name this version does not know.
    Unknown,
}

impl Control {
    const NAMED: [Control; 10] = [
        Control::Set,
        Control::Absent,
        Control::Links,
        Control::Link,
        Control::Origin,
        Control::Section,
        Control::Entry,
        Control::Modules,
        Control::Spelling,
        Control::Version,
    ];

    fn name(self) -> &'static str {
        match self {
            Control::Set => "set",
            Control::Absent => "absent",
            Control::Links => "links",
            Control::Link => "link",
            Control::Origin => "origin",
            Control::Section => "section",
            Control::Entry => "entry",
            Control::Modules => "modules",
            Control::Spelling => "spelling",
            Control::Version => "version",
            Control::Unknown => "unknown",
        }
    }
}

/// A property (name, value) for a control, encoded when XML could not carry the value.
pub(crate) fn property(control: Control, value: &str) -> (String, String) {
    if needs_encoding(value) {
        (
            format!("{ENCODED_PREFIX}{}", control.name()),
            percent_encode(value),
        )
    } else {
        (format!("{PREFIX}{}", control.name()), value.to_owned())
    }
}

/// The control and decoded value of a side-channel property; `None` for other properties (such as
/// CANopenNode's `CO_*`). A value that does not decode is returned as [`Control::Unknown`].
pub(crate) fn decode(name: &str, value: &str) -> Option<(Control, String)> {
    let (rest, value) = if let Some(rest) = name.strip_prefix(ENCODED_PREFIX) {
        match percent_decode(value) {
            Some(v) => (rest, v),
            None => return Some((Control::Unknown, value.to_owned())),
        }
    } else {
        (name.strip_prefix(PREFIX)?, value.to_owned())
    };
    let control = Control::NAMED
        .iter()
        .copied()
        .find(|c| c.name() == rest)
        .unwrap_or(Control::Unknown);
    Some((control, value))
}

/// Whether a property name belongs to the side channel.
pub(crate) fn is_side_channel(name: &str) -> bool {
    name.starts_with(PREFIX) || name.starts_with(ENCODED_PREFIX)
}

/// Removes a key from an object section (its slot or `extra`).
pub(crate) fn remove_key(attributes: &mut Attributes, key: &str) {
    match attributes.slot_mut(key) {
        Some(slot) => *slot = None,
        None => attributes.extra.retain(|p| !p.key.eq_ignore_ascii_case(key)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn properties_round_trip_and_encode_when_needed() {
        assert_eq!(
            property(Control::Set, "DataType=0x0010"),
            ("EDS:set".to_owned(), "DataType=0x0010".to_owned())
        );
        assert_eq!(
            decode("EDS:set", "DataType=0x0010"),
            Some((Control::Set, "DataType=0x0010".to_owned()))
        );
        let (name, value) = property(Control::Set, "ParameterName=bell\u{7}");
        assert_eq!(name, "EDS%:set");
        assert_eq!(
            decode(&name, &value),
            Some((Control::Set, "ParameterName=bell\u{7}".to_owned()))
        );
        assert_eq!(decode("CO_storageGroup", "RAM"), None);
        assert_eq!(
            decode("EDS:frobnicate", "x"),
            Some((Control::Unknown, "x".to_owned()))
        );
        assert_eq!(
            decode("EDS%:set", "%zz"),
            Some((Control::Unknown, "%zz".to_owned()))
        );
        assert!(is_side_channel("EDS%:set") && !is_side_channel("CO_disabled"));
    }

    #[test]
    fn keys_are_removed_from_slots_and_extra() {
        let mut a = Attributes::default();
        a.set("AccessType", "ro");
        a.set("Vendor_Key", "1");
        remove_key(&mut a, "accesstype");
        remove_key(&mut a, "VENDOR_KEY");
        assert!(a.entries().is_empty());
    }
}

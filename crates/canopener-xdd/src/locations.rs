//! Where in the XML each part of the model came from, so that a finding about the model (a check
//! run on the EDS form of an XDD) can point at the element or attribute that produced the value.
//!
//! Sections and keys are named as the CiA 306 model names them (`1018sub1`/`DefaultValue`,
//! `DeviceInfo`/`VendorNumber`), case-insensitively, because that is what checks report.

use std::collections::BTreeMap;

use canopener_eds::Span;

/// The XML position of one section of the model and of the keys it was read from.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SectionLocation {
    /// The element the section was read from.
    pub element: Span,
    /// Per CiA 306 key (lowercase), the attribute or element its value was read from.
    pub keys: BTreeMap<String, Span>,
}

/// Where the reader found every object, sub-object and device-level section, and their values.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Locations {
    /// The element a finding about the file as a whole points at (the device profile body, or the
    /// root element when there is none).
    pub file: Span,
    /// Objects (`None`) and sub-objects (`Some(sub)`) by index.
    pub entries: BTreeMap<(u16, Option<u8>), SectionLocation>,
    /// Device-level sections by lowercase CiA 306 name (`fileinfo`, `deviceinfo`,
    /// `devicecomissioning`, `dummyusage`, `dynamicchannels`).
    pub sections: BTreeMap<String, SectionLocation>,
}

impl Locations {
    /// The XML position of a CiA 306 section and key: the key's attribute or element when the
    /// reader took the value from one, else the section's element, else (for a sub-object) its
    /// object's element, else the file's.
    pub fn find(&self, section: Option<&str>, key: Option<&str>) -> Span {
        let Some(section) = section.map(str::trim) else {
            return self.file;
        };
        let key = key.map(|k| k.trim().to_ascii_lowercase());
        let in_section = |location: &SectionLocation| {
            key.as_ref()
                .and_then(|k| location.keys.get(k))
                .copied()
                .unwrap_or(location.element)
        };
        if let Some((index, sub)) = entry_of(section) {
            if let Some(location) = self.entries.get(&(index, sub)) {
                return in_section(location);
            }
            return self
                .entries
                .get(&(index, None))
                .map_or(self.file, |location| location.element);
        }
        let name = section.to_ascii_lowercase();
        self.sections.get(&name).map_or(self.file, in_section)
    }

    pub(crate) fn section(&mut self, name: &str, element: Span) -> &mut SectionLocation {
        let location = self.sections.entry(name.to_owned()).or_default();
        if location.element == Span::default() {
            location.element = element;
        }
        location
    }
}

impl SectionLocation {
    /// Records where a key's value came from; the first source recorded wins (the object's own
    /// attribute is recorded before the referenced parameter's element, as the reader prefers it).
    pub(crate) fn key(&mut self, key: &str, at: Span) {
        self.keys.entry(key.to_ascii_lowercase()).or_insert(at);
    }
}

/// The index and sub-index a CiA 306 object section names: `1018`, `1018sub1`, `0x1018`
/// (case-insensitive); `None` for other sections.
pub fn entry_of(section: &str) -> Option<(u16, Option<u8>)> {
    let lower = section.to_ascii_lowercase();
    let lower = lower.strip_prefix("0x").unwrap_or(&lower);
    let (index, sub) = match lower.split_once("sub") {
        Some((index, sub)) => (index, Some(sub)),
        None => (lower, None),
    };
    if index.is_empty() || index.len() > 4 || !index.bytes().all(|b| b.is_ascii_hexdigit()) {
        return None;
    }
    let index = u16::from_str_radix(index, 16).ok()?;
    match sub {
        None => Some((index, None)),
        Some(sub) if !sub.is_empty() && sub.len() <= 2 => {
            Some((index, Some(u8::from_str_radix(sub, 16).ok()?)))
        }
        Some(_) => None,
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    proptest! {
        /// Every object and sub-object section name, in any case and padding, names its entry.
        #[test]
        fn section_names_round_trip(index: u16, sub: u8, upper: bool, padded: bool) {
            let object = if padded { format!("{index:04X}") } else { format!("{index:X}") };
            let name = format!("{object}sub{sub:X}");
            let name = if upper { name.to_ascii_uppercase() } else { name.to_ascii_lowercase() };
            prop_assert_eq!(entry_of(&name), Some((index, Some(sub))));
            prop_assert_eq!(entry_of(&object), Some((index, None)));
        }
    }

    #[test]
    fn sections_name_entries_in_any_case() {
        assert_eq!(entry_of("1018"), Some((0x1018, None)));
        assert_eq!(entry_of("1018SUB1"), Some((0x1018, Some(1))));
        assert_eq!(entry_of("1a00sub1f"), Some((0x1A00, Some(0x1F))));
        assert_eq!(entry_of("DeviceInfo"), None);
        assert_eq!(entry_of("1018Name"), None);
        assert_eq!(entry_of("10180"), None);
        assert_eq!(entry_of("1018sub100"), None);
        assert_eq!(entry_of("sub1"), None);
    }

    #[test]
    fn lookups_fall_back_from_key_to_element_to_object_to_file() {
        let mut locations = Locations {
            file: Span::new(2, 1, 0),
            ..Locations::default()
        };
        let mut object = SectionLocation {
            element: Span::new(10, 3, 0),
            ..SectionLocation::default()
        };
        object.key("DefaultValue", Span::new(10, 40, 0));
        object.key("defaultvalue", Span::new(99, 1, 0));
        locations.entries.insert((0x1017, None), object);
        locations.section("deviceinfo", Span::new(5, 2, 0));
        let find = |s: Option<&str>, k: Option<&str>| {
            let span = locations.find(s, k);
            (span.line, span.column)
        };
        assert_eq!(find(Some("1017"), Some("DefaultValue")), (10, 40));
        assert_eq!(find(Some("1017"), Some("AccessType")), (10, 3));
        assert_eq!(find(Some("1017sub2"), Some("AccessType")), (10, 3));
        assert_eq!(find(Some("2000"), None), (2, 1));
        assert_eq!(find(Some("DeviceInfo"), Some("VendorName")), (5, 2));
        assert_eq!(find(Some("Comments"), None), (2, 1));
        assert_eq!(find(None, Some("x")), (2, 1));
    }
}

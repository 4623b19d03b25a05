//! What a section name means (CiA 306 §4.4–§6), and how CiA 306 spells it.

use crate::model::{CommissioningSpelling, ObjectListKind, decimal_key};

/// The part of a modular device a `M<x>...` section describes (CiA 306 §6.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum ModulePart {
    /// `M<x>ModuleInfo`
    Info,
    /// `M<x>Comments`
    Comments,
    /// `M<x>FixedObjects`
    FixedObjects,
    /// `M<x>Fixed<index>`
    Fixed(u16),
    /// `M<x>Fixed<index>sub<sub>`
    FixedSub(u16, u8),
    /// `M<x>SubExtends`
    SubExtends,
    /// `M<x>SubExt<index>`
    SubExt(u16),
    /// `M<x>SubExt<index>sub<sub>` (not in CiA 306 V1.3; kept in case a writer uses it)
    SubExtSub(u16, u8),
}

/// Companion sections of an object.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Companion {
    /// `[<index>Name]`
    Name,
    /// `[<index>Value]`
    Value,
    /// `[<index>Denotation]`
    Denotation,
    /// `[<index>ObjectLinks]`
    ObjectLinks,
}

impl Companion {
    /// The suffix CiA 306 uses.
    pub fn suffix(self) -> &'static str {
        match self {
            Self::Name => "Name",
            Self::Value => "Value",
            Self::Denotation => "Denotation",
            Self::ObjectLinks => "ObjectLinks",
        }
    }
}

/// The meaning of a section name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum SectionKind {
    /// `[FileInfo]`
    FileInfo,
    /// `[DeviceInfo]`
    DeviceInfo,
    /// `[DummyUsage]`
    DummyUsage,
    /// `[Comments]`
    Comments,
    /// One of the three object lists.
    ObjectList(ObjectListKind),
    /// `[DeviceComissioning]` in either spelling.
    Commissioning(CommissioningSpelling),
    /// `[Tools]`
    Tools,
    /// `[Tool<n>]`
    Tool(u32),
    /// `[DynamicChannels]`
    DynamicChannels,
    /// `[SupportedModules]`
    SupportedModules,
    /// `[ConnectedModules]`
    ConnectedModules,
    /// `[<index>]`
    Object(u16),
    /// `[<index>sub<sub>]`
    Sub(u16, u8),
    /// `[<index>Name]` and friends.
    Companion(u16, Companion),
    /// `M<x>...`
    Module(u32, ModulePart),
    /// Anything else.
    Unknown,
}

impl SectionKind {
    /// The section kind that decides duplicates (both commissioning spellings are one section).
    pub fn identity(self) -> SectionKind {
        match self {
            Self::Commissioning(_) => Self::Commissioning(CommissioningSpelling::DeviceComissioning),
            other => other,
        }
    }
}

/// Classifies a section name (case-insensitive, CiA 306 §4.2).
pub fn classify(name: &str) -> SectionKind {
    // Every section is classified on load; lower-casing the (short) name on the stack saves an
    // allocation per section.
    let mut buffer = [0u8; 64];
    let owned;
    let lower = match lowercase_on_stack(name, &mut buffer) {
        Some(lower) => lower,
        None => {
            owned = name.to_ascii_lowercase();
            owned.as_str()
        }
    };
    let fixed = match lower {
        "fileinfo" => Some(SectionKind::FileInfo),
        "deviceinfo" => Some(SectionKind::DeviceInfo),
        "dummyusage" => Some(SectionKind::DummyUsage),
        "comments" => Some(SectionKind::Comments),
        "mandatoryobjects" => Some(SectionKind::ObjectList(ObjectListKind::Mandatory)),
        "optionalobjects" => Some(SectionKind::ObjectList(ObjectListKind::Optional)),
        "manufacturerobjects" => Some(SectionKind::ObjectList(ObjectListKind::Manufacturer)),
        "devicecomissioning" => Some(SectionKind::Commissioning(
            CommissioningSpelling::DeviceComissioning,
        )),
        "devicecommissioning" => Some(SectionKind::Commissioning(
            CommissioningSpelling::DeviceCommissioning,
        )),
        "tools" => Some(SectionKind::Tools),
        "dynamicchannels" => Some(SectionKind::DynamicChannels),
        "supportedmodules" => Some(SectionKind::SupportedModules),
        "connectedmodules" => Some(SectionKind::ConnectedModules),
        _ => None,
    };
    if let Some(kind) = fixed {
        return kind;
    }
    if let Some(n) = lower.strip_prefix("tool").and_then(decimal_key) {
        return SectionKind::Tool(n);
    }
    if let Some(kind) = classify_module(lower) {
        return kind;
    }
    classify_object(lower).unwrap_or(SectionKind::Unknown)
}

/// `name.to_ascii_lowercase()` in `buffer`, or `None` when the name does not fit.
fn lowercase_on_stack<'b>(name: &str, buffer: &'b mut [u8; 64]) -> Option<&'b str> {
    let bytes = buffer.get_mut(..name.len())?;
    bytes.copy_from_slice(name.as_bytes());
    bytes.make_ascii_lowercase();
    // ASCII lower-casing keeps UTF-8 valid, so this always succeeds.
    std::str::from_utf8(bytes).ok()
}

/// The name CiA 306 gives a section of this kind (`None` for unknown sections).
pub fn canonical_name(kind: SectionKind) -> Option<String> {
    Some(match kind {
        SectionKind::FileInfo => "FileInfo".to_owned(),
        SectionKind::DeviceInfo => "DeviceInfo".to_owned(),
        SectionKind::DummyUsage => "DummyUsage".to_owned(),
        SectionKind::Comments => "Comments".to_owned(),
        SectionKind::ObjectList(list) => list.section_name().to_owned(),
        SectionKind::Commissioning(spelling) => spelling.section_name().to_owned(),
        SectionKind::Tools => "Tools".to_owned(),
        SectionKind::Tool(n) => format!("Tool{n}"),
        SectionKind::DynamicChannels => "DynamicChannels".to_owned(),
        SectionKind::SupportedModules => "SupportedModules".to_owned(),
        SectionKind::ConnectedModules => "ConnectedModules".to_owned(),
        SectionKind::Object(index) => format!("{index:X}"),
        SectionKind::Sub(index, sub) => format!("{index:X}sub{sub:X}"),
        SectionKind::Companion(index, c) => format!("{index:X}{}", c.suffix()),
        SectionKind::Module(x, part) => match part {
            ModulePart::Info => format!("M{x}ModuleInfo"),
            ModulePart::Comments => format!("M{x}Comments"),
            ModulePart::FixedObjects => format!("M{x}FixedObjects"),
            ModulePart::Fixed(i) => format!("M{x}Fixed{i:X}"),
            ModulePart::FixedSub(i, s) => format!("M{x}Fixed{i:X}sub{s:X}"),
            ModulePart::SubExtends => format!("M{x}SubExtends"),
            ModulePart::SubExt(i) => format!("M{x}SubExt{i:X}"),
            ModulePart::SubExtSub(i, s) => format!("M{x}SubExt{i:X}sub{s:X}"),
        },
        SectionKind::Unknown => return None,
    })
}

/// Whether a name has the `<index>sub<sub>` form with a sub-index that does not fit in 8 bits.
pub fn is_sub_index_out_of_range(name: &str) -> bool {
    let lower = name.to_ascii_lowercase();
    let Some(at) = find_sub(&lower) else { return false };
    let (head, tail) = (&lower[..at], &lower[at + 3..]);
    parse_hex(head, 4).is_some()
        && !tail.is_empty()
        && tail.bytes().all(|b| b.is_ascii_hexdigit())
        && tail.trim_start_matches('0').len() > 2
}

/// Whether `name` is already spelt as CiA 306 spells `kind`, decided without allocating for the
/// object, sub-object and companion sections that make up nearly every file; `None` for other kinds.
pub fn is_canonical_object_name(name: &str, kind: SectionKind) -> Option<bool> {
    fn hex_len(v: u16) -> usize {
        if v == 0 {
            1
        } else {
            (16 - v.leading_zeros() as usize).div_ceil(4)
        }
    }
    // The name already classified as `kind`, so only leading zeros or the case of `sub` can differ.
    Some(match kind {
        SectionKind::Object(i) => name.len() == hex_len(i),
        SectionKind::Sub(i, s) => {
            name.len() == hex_len(i) + 3 + hex_len(u16::from(s)) && name.contains("sub")
        }
        SectionKind::Companion(i, c) => name.len() == hex_len(i) + c.suffix().len(),
        _ => return None,
    })
}

fn classify_module(lower: &str) -> Option<SectionKind> {
    let rest = lower.strip_prefix('m')?;
    let digits = rest.bytes().take_while(u8::is_ascii_digit).count();
    let x = decimal_key(rest.get(..digits)?)?;
    let part = rest.get(digits..)?;
    let part = match part {
        "moduleinfo" => ModulePart::Info,
        "comments" => ModulePart::Comments,
        "fixedobjects" => ModulePart::FixedObjects,
        "subextends" => ModulePart::SubExtends,
        _ => {
            if let Some(obj) = part.strip_prefix("subext") {
                match parse_object_ref(obj)? {
                    (index, None) => ModulePart::SubExt(index),
                    (index, Some(sub)) => ModulePart::SubExtSub(index, sub),
                }
            } else if let Some(obj) = part.strip_prefix("fixed") {
                match parse_object_ref(obj)? {
                    (index, None) => ModulePart::Fixed(index),
                    (index, Some(sub)) => ModulePart::FixedSub(index, sub),
                }
            } else {
                return None;
            }
        }
    };
    Some(SectionKind::Module(x, part))
}

fn classify_object(lower: &str) -> Option<SectionKind> {
    for (suffix, companion) in [
        ("objectlinks", Companion::ObjectLinks),
        ("denotation", Companion::Denotation),
        ("value", Companion::Value),
        ("name", Companion::Name),
    ] {
        if let Some(head) = lower.strip_suffix(suffix) {
            return Some(SectionKind::Companion(parse_hex(head, 4)?, companion));
        }
    }
    Some(match parse_object_ref(lower)? {
        (index, None) => SectionKind::Object(index),
        (index, Some(sub)) => SectionKind::Sub(index, sub),
    })
}

fn parse_object_ref(text: &str) -> Option<(u16, Option<u8>)> {
    match find_sub(text) {
        Some(at) => {
            let index = parse_hex(text.get(..at)?, 4)?;
            let sub = parse_hex(text.get(at + 3..)?, 2)?;
            Some((index, Some(u8::try_from(sub).ok()?)))
        }
        None => Some((parse_hex(text, 4)?, None)),
    }
}

/// The byte offset of the first `sub` in a lower-cased name, as `str::find("sub")` gives it; the
/// substring searcher `find` sets up costs more than scanning a name of a dozen bytes.
fn find_sub(lower: &str) -> Option<usize> {
    lower.as_bytes().windows(3).position(|w| w == b"sub")
}

/// Parses up to `digits` (at most 4) significant hex digits (leading zeros allowed, reported by the caller).
fn parse_hex(text: &str, digits: usize) -> Option<u16> {
    if text.is_empty() || text.len() > 8 {
        return None;
    }
    // At most eight hex digits always fit in a u32.
    let mut value = 0u32;
    for b in text.bytes() {
        value = value << 4 | char::from(b).to_digit(16)?;
    }
    // No more than `digits` significant digits, i.e. below 16^digits.
    if value >= 1 << (4 * digits) {
        return None;
    }
    u16::try_from(value).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classifies_every_cia306_section() {
        use SectionKind::*;
        assert_eq!(classify("FileInfo"), FileInfo);
        assert_eq!(
            classify("DEVICECOMMISSIONING"),
            Commissioning(CommissioningSpelling::DeviceCommissioning)
        );
        assert_eq!(classify("1018"), Object(0x1018));
        assert_eq!(classify("1a00sub1F"), Sub(0x1A00, 0x1F));
        assert_eq!(classify("1018SUB1"), Sub(0x1018, 1));
        assert_eq!(classify("1018sub01"), Sub(0x1018, 1));
        assert_eq!(
            classify("1A00Denotation"),
            Companion(0x1A00, self::Companion::Denotation)
        );
        assert_eq!(
            classify("5800ObjectLinks"),
            Companion(0x5800, self::Companion::ObjectLinks)
        );
        assert_eq!(classify("2000Name"), Companion(0x2000, self::Companion::Name));
        assert_eq!(classify("M1ModuleInfo"), Module(1, ModulePart::Info));
        assert_eq!(
            classify("M12Fixed6423sub2"),
            Module(12, ModulePart::FixedSub(0x6423, 2))
        );
        assert_eq!(classify("M2SubExt6000"), Module(2, ModulePart::SubExt(0x6000)));
        assert_eq!(classify("Tool3"), Tool(3));
        assert_eq!(classify("Supported Objects"), Unknown);
        assert_eq!(classify("10000"), Unknown);
        assert_eq!(classify("1018sub100"), Unknown);
        assert_eq!(classify("StandardDataTypes"), Unknown);
        assert!(is_sub_index_out_of_range("D000sub101"));
        assert!(!is_sub_index_out_of_range("D000sub10"));
    }

    #[test]
    fn parse_hex_limits_significant_digits() {
        assert_eq!(parse_hex("00001018", 4), Some(0x1018));
        assert_eq!(parse_hex("000010180", 4), None);
        assert_eq!(parse_hex("10180", 4), None);
        assert_eq!(parse_hex("0FF", 2), Some(0xFF));
        assert_eq!(parse_hex("100", 2), None);
        assert_eq!(parse_hex("", 4), None);
        assert_eq!(parse_hex("+1", 4), None);
        assert_eq!(parse_hex("1g", 4), None);
        assert_eq!(find_sub("1a00sub1f"), Some(4));
        assert_eq!(find_sub("su"), None);
    }

    #[test]
    fn long_names_are_classified_too() {
        let long = format!("{}1018", "0".repeat(70));
        assert_eq!(classify(&long), SectionKind::Unknown);
        assert_eq!(classify(&"X".repeat(80)), SectionKind::Unknown);
    }

    #[test]
    fn fast_canonical_check_agrees_with_canonical_name() {
        for name in [
            "1018",
            "01018",
            "1A00sub1F",
            "1a00sub1f",
            "1018SUB1",
            "1018sub01",
            "0sub0",
            "2000Name",
            "02000Name",
        ] {
            let kind = classify(name);
            let slow = canonical_name(kind).is_some_and(|c| {
                c == name
                    || (c.eq_ignore_ascii_case(name) && name.contains("sub"))
                    || (c.eq_ignore_ascii_case(name) && !matches!(kind, SectionKind::Sub(..)))
            });
            assert_eq!(is_canonical_object_name(name, kind), Some(slow), "{name}");
        }
    }

    #[test]
    fn canonical_names_round_trip() {
        for name in [
            "1018",
            "1A00sub1F",
            "2000Name",
            "M1Fixed6423sub2",
            "DeviceComissioning",
            "Tool2",
            "1018sub0",
        ] {
            assert_eq!(canonical_name(classify(name)).as_deref(), Some(name));
        }
    }
}

//! The vocabularies of CiA 311 attributes and how they map to CiA 306 notation: hexBinary numbers,
//! booleans, the IEC 61131-3 type elements, `access`, `PDOmapping`, baud rates, xsd:date/xsd:time.
//!
//! Reading is lenient (`0x` prefixes, odd widths, `9:48:42 PM`); what a strict reader would reject
//! is reported by the caller with the message these functions return.

use canopener_eds::AccessType;

/// A hexBinary number as written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Hex {
    /// The value.
    pub value: u64,
    /// Number of digits written (after any `0x`).
    pub digits: usize,
    /// Whether it was written with `0x`, which xsd:hexBinary does not allow.
    pub prefixed: bool,
}

/// Reads a hex number with or without `0x`; `None` for anything else or more than 64 bits.
pub(crate) fn parse_hex(text: &str) -> Option<Hex> {
    let t = text.trim();
    let (digits, prefixed) = match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(d) => (d, true),
        None => (t, false),
    };
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_hexdigit()) {
        return None;
    }
    let significant = digits.trim_start_matches('0');
    let value = if significant.is_empty() {
        0
    } else {
        u64::from_str_radix(significant, 16).ok()?
    };
    Some(Hex {
        value,
        digits: digits.len(),
        prefixed,
    })
}

/// What reading an attribute by its CiA 311 schema type gave.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Reading<T> {
    /// The value, written as its schema type has it.
    Valid(T),
    /// A value whose meaning is clear though it is not written as its schema type has it, and why
    /// not, ending with what it was read as (`has a 0x prefix, ...; read as 2000h`).
    Lenient(T, String),
    /// No value of the type, and why not (`is not a hex number`).
    Unreadable(String),
}

/// Reads an xsd:hexBinary number up to `max`: a `0x` prefix or an odd number of digits is lenient (the
/// number is clear, the schema type is broken).
pub(crate) fn read_hex(text: &str, max: u64) -> Reading<u64> {
    let Some(hex) = parse_hex(text) else {
        return Reading::Unreadable("is not a hex number".to_owned());
    };
    if hex.value > max {
        return Reading::Unreadable(format!("is above {max:X}h"));
    }
    let broken = if hex.prefixed {
        "has a `0x` prefix"
    } else if hex.digits % 2 == 1 {
        "has an odd number of digits"
    } else {
        return Reading::Valid(hex.value);
    };
    Reading::Lenient(
        hex.value,
        format!(
            "{broken}, which xsd:hexBinary does not allow; read as {:X}h",
            hex.value
        ),
    )
}

/// The remark on a valid hexBinary of an unusual width (`expected` lists the widths CiA 311 writes).
pub(crate) fn hex_width_remark(what: &str, text: &str, expected: &[usize]) -> Option<String> {
    let hex = parse_hex(text).filter(|h| !h.prefixed && h.digits % 2 == 0)?;
    if expected.contains(&hex.digits) {
        return None;
    }
    let widths = expected
        .iter()
        .map(|w| w.to_string())
        .collect::<Vec<_>>()
        .join(" or ");
    Some(format!(
        "{what} `{text}` has {} hex digits where CiA 311 writes {widths}; read as 0x{:X}",
        hex.digits, hex.value
    ))
}

/// An XML Schema unsigned integer type CiA 311 gives attributes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Unsigned {
    /// The schema's name for it.
    pub name: &'static str,
    /// The largest value.
    pub max: u64,
}

/// xsd:unsignedByte (objectType, subNumber, granularity, nodeID, ...).
pub(crate) const UNSIGNED_BYTE: Unsigned = Unsigned {
    name: "unsignedByte",
    max: 0xFF,
};
/// xsd:unsignedShort (nrOfRxPDO, nrOfTxPDO).
pub(crate) const UNSIGNED_SHORT: Unsigned = Unsigned {
    name: "unsignedShort",
    max: 0xFFFF,
};
/// xsd:unsignedLong (networkNumber).
pub(crate) const UNSIGNED_LONG: Unsigned = Unsigned {
    name: "unsignedLong",
    max: u64::MAX,
};

/// Reads an unsigned integer of `ty`: decimal digits with an optional `+` as the schema has it; `0x` hex
/// is lenient (clear, but not the schema type); out of range or not a number is unreadable.
pub(crate) fn read_unsigned(text: &str, ty: Unsigned) -> Reading<u64> {
    let Some((value, hex)) = parse_unsigned(text.trim().strip_prefix('+').unwrap_or(text)) else {
        return Reading::Unreadable(format!("is not an xsd:{} (a decimal number)", ty.name));
    };
    if value > ty.max {
        return Reading::Unreadable(format!("is above {}, the largest xsd:{}", ty.max, ty.name));
    }
    if hex {
        Reading::Lenient(
            value,
            format!("is hexadecimal where xsd:{} is decimal; read as {value}", ty.name),
        )
    } else {
        Reading::Valid(value)
    }
}

/// Reads an xsd:boolean (`true`, `false`, `1`, `0`); another letter case is lenient.
pub(crate) fn read_bool(text: &str) -> Reading<bool> {
    match parse_bool(text) {
        Some((value, false)) => Reading::Valid(value),
        Some((value, true)) => Reading::Lenient(
            value,
            format!("is not an xsd:boolean (true, false, 1, 0); read as {value}"),
        ),
        None => Reading::Unreadable("is not an xsd:boolean (true, false, 1, 0)".to_owned()),
    }
}

/// Whether a text is an xsd:NCName, the lexical form of xsd:ID and xsd:IDREF: a letter or `_`, then
/// letters, digits, `.`, `-` and `_` (XML Namespaces 1.0 §3; non-ASCII letters and digits included).
pub(crate) fn is_ncname(text: &str) -> bool {
    let mut chars = text.chars();
    chars
        .next()
        .is_some_and(|first| first == '_' || first.is_alphabetic())
        && chars.all(|c| c.is_alphanumeric() || matches!(c, '.' | '-' | '_' | '\u{B7}'))
}

/// Reads an unsigned decimal; `0x` hex is accepted too (the flag says so).
pub(crate) fn parse_unsigned(text: &str) -> Option<(u64, bool)> {
    let t = text.trim();
    if t.starts_with("0x") || t.starts_with("0X") {
        return parse_hex(t).map(|h| (h.value, true));
    }
    if t.is_empty() || !t.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    t.parse().ok().map(|v| (v, false))
}

/// Reads an xsd:boolean (`true`, `false`, `1`, `0`); the flag says the case was not as the schema has it.
pub(crate) fn parse_bool(text: &str) -> Option<(bool, bool)> {
    match text.trim() {
        "true" | "1" => Some((true, false)),
        "false" | "0" => Some((false, false)),
        t if t.eq_ignore_ascii_case("true") => Some((true, true)),
        t if t.eq_ignore_ascii_case("false") => Some((false, true)),
        _ => None,
    }
}

/// The IEC 61131-3 simple type elements of CiA 311 (`g_simple`, 19 of them).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum Iec {
    Bool,
    Bitstring,
    Byte,
    Char,
    Word,
    Dword,
    Lword,
    Sint,
    Int,
    Dint,
    Lint,
    Usint,
    Uint,
    Udint,
    Ulint,
    Real,
    Lreal,
    String,
    Wstring,
}

impl Iec {
    const ALL: [Iec; 19] = [
        Iec::Bool,
        Iec::Bitstring,
        Iec::Byte,
        Iec::Char,
        Iec::Word,
        Iec::Dword,
        Iec::Lword,
        Iec::Sint,
        Iec::Int,
        Iec::Dint,
        Iec::Lint,
        Iec::Usint,
        Iec::Uint,
        Iec::Udint,
        Iec::Ulint,
        Iec::Real,
        Iec::Lreal,
        Iec::String,
        Iec::Wstring,
    ];

    /// The element name.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Iec::Bool => "BOOL",
            Iec::Bitstring => "BITSTRING",
            Iec::Byte => "BYTE",
            Iec::Char => "CHAR",
            Iec::Word => "WORD",
            Iec::Dword => "DWORD",
            Iec::Lword => "LWORD",
            Iec::Sint => "SINT",
            Iec::Int => "INT",
            Iec::Dint => "DINT",
            Iec::Lint => "LINT",
            Iec::Usint => "USINT",
            Iec::Uint => "UINT",
            Iec::Udint => "UDINT",
            Iec::Ulint => "ULINT",
            Iec::Real => "REAL",
            Iec::Lreal => "LREAL",
            Iec::String => "STRING",
            Iec::Wstring => "WSTRING",
        }
    }

    /// The type for an element name (exact, as the schema spells it).
    pub(crate) fn from_name(name: &str) -> Option<Self> {
        Self::ALL.iter().copied().find(|t| t.name() == name)
    }

    /// The CiA 301 data type an element stands for (reference §11.4). BITSTRING is OCTET_STRING, or
    /// DOMAIN when the parameter has no default value (the CANopenEditor convention); CHAR is a
    /// one-character string in CiA 311, so VISIBLE_STRING.
    pub(crate) fn data_type(self, has_default: bool) -> u16 {
        match self {
            Iec::Bool => 0x0001,
            Iec::Sint => 0x0002,
            Iec::Int => 0x0003,
            Iec::Dint => 0x0004,
            Iec::Lint => 0x0015,
            Iec::Usint | Iec::Byte => 0x0005,
            Iec::Uint | Iec::Word => 0x0006,
            Iec::Udint | Iec::Dword => 0x0007,
            Iec::Ulint | Iec::Lword => 0x001B,
            Iec::Real => 0x0008,
            Iec::Lreal => 0x0011,
            Iec::String | Iec::Char => 0x0009,
            Iec::Wstring => 0x000B,
            Iec::Bitstring if has_default => 0x000A,
            Iec::Bitstring => 0x000F,
        }
    }

    /// Whether an inline `dataType` agrees with this element. BITSTRING is the element writers use
    /// for every type without an IEC equivalent, so it agrees with anything.
    pub(crate) fn agrees_with(self, data_type: u16) -> bool {
        match self {
            Iec::Bitstring => true,
            Iec::Char => matches!(data_type, 0x0002 | 0x0009),
            other => other.data_type(true) == data_type,
        }
    }

    /// The element to write for a data type, and whether it needs an inline `dataType` to be read
    /// back exactly (types without an IEC equivalent, and BITSTRING's two meanings).
    pub(crate) fn for_data_type(data_type: u16) -> (Iec, bool) {
        let iec = match data_type {
            0x0001 => Iec::Bool,
            0x0002 => Iec::Sint,
            0x0003 => Iec::Int,
            0x0004 => Iec::Dint,
            0x0015 => Iec::Lint,
            0x0005 => Iec::Usint,
            0x0006 => Iec::Uint,
            0x0007 => Iec::Udint,
            0x001B => Iec::Ulint,
            0x0008 => Iec::Real,
            0x0011 => Iec::Lreal,
            0x0009 => Iec::String,
            0x000B => Iec::Wstring,
            _ => return (Iec::Bitstring, true),
        };
        (iec, false)
    }
}

/// Why a `parameter@access` is not one: the schema's tokens.
const ACCESS_TOKENS: &str = "is not a CiA 311 parameter access (const, read, write, readWrite, readWriteInput, \
     readWriteOutput, noAccess)";

/// `parameter@access` (CiA 311 `ag_parameter`; default `read`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ParamAccess {
    Const,
    Read,
    Write,
    ReadWrite,
    ReadWriteInput,
    ReadWriteOutput,
    NoAccess,
}

impl ParamAccess {
    const ALL: [ParamAccess; 7] = [
        Self::Const,
        Self::Read,
        Self::Write,
        Self::ReadWrite,
        Self::ReadWriteInput,
        Self::ReadWriteOutput,
        Self::NoAccess,
    ];

    pub(crate) fn parse(token: &str) -> Option<Self> {
        Some(match token.trim() {
            "const" => Self::Const,
            "read" => Self::Read,
            "write" => Self::Write,
            "readWrite" => Self::ReadWrite,
            "readWriteInput" => Self::ReadWriteInput,
            "readWriteOutput" => Self::ReadWriteOutput,
            "noAccess" => Self::NoAccess,
            _ => return None,
        })
    }

    /// Reads `parameter@access`. Another letter case of a CiA 311 token, or the CANopenObject
    /// accessType token of the same access (`rw` for readWrite, `rwr` for readWriteInput), is lenient:
    /// the meaning is clear but the schema has only its own tokens.
    pub(crate) fn read(token: &str) -> Reading<Self> {
        if let Some(access) = Self::parse(token) {
            return Reading::Valid(access);
        }
        let t = token.trim();
        let by_case = Self::ALL.into_iter().find(|a| a.as_str().eq_ignore_ascii_case(t));
        let by_eds = AccessType::parse(t).map(Self::from_access_type);
        match by_case.or(by_eds) {
            Some(access) => Reading::Lenient(access, format!("{ACCESS_TOKENS}; read as {}", access.as_str())),
            None => Reading::Unreadable(ACCESS_TOKENS.to_owned()),
        }
    }

    pub(crate) fn as_str(self) -> &'static str {
        match self {
            Self::Const => "const",
            Self::Read => "read",
            Self::Write => "write",
            Self::ReadWrite => "readWrite",
            Self::ReadWriteInput => "readWriteInput",
            Self::ReadWriteOutput => "readWriteOutput",
            Self::NoAccess => "noAccess",
        }
    }

    /// The CiA 306 access type; `None` for `noAccess`. readWriteInput is process input, which a
    /// TPDO transmits (rwr); readWriteOutput is process output, received by an RPDO (rww).
    pub(crate) fn access_type(self) -> Option<AccessType> {
        Some(match self {
            Self::Const => AccessType::Const,
            Self::Read => AccessType::Ro,
            Self::Write => AccessType::Wo,
            Self::ReadWrite => AccessType::Rw,
            Self::ReadWriteInput => AccessType::Rwr,
            Self::ReadWriteOutput => AccessType::Rww,
            Self::NoAccess => return None,
        })
    }

    pub(crate) fn from_access_type(access: AccessType) -> Self {
        match access {
            AccessType::Const => Self::Const,
            AccessType::Ro => Self::Read,
            AccessType::Wo => Self::Write,
            AccessType::Rw => Self::ReadWrite,
            AccessType::Rwr => Self::ReadWriteInput,
            AccessType::Rww => Self::ReadWriteOutput,
        }
    }
}

/// Reads `CANopenObject@accessType` (ro, wo, rw, const); another CiA 306 access type or letter case
/// (`rwr`, `RW`) is lenient.
pub(crate) fn read_access_type(token: &str) -> Reading<AccessType> {
    const TOKENS: &str = "is not a CiA 311 accessType (ro, wo, rw, const)";
    let t = token.trim();
    match AccessType::parse(t) {
        Some(access) if matches!(t, "ro" | "wo" | "rw" | "const") => Reading::Valid(access),
        Some(access) => Reading::Lenient(access, format!("{TOKENS}; read as {access}")),
        None => Reading::Unreadable(TOKENS.to_owned()),
    }
}

/// `CANopenObject@PDOmapping`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum PdoMapping {
    No,
    Default,
    Optional,
    Tpdo,
    Rpdo,
}

impl PdoMapping {
    pub(crate) fn parse(token: &str) -> Option<Self> {
        Some(match token.trim() {
            "no" => Self::No,
            "default" => Self::Default,
            "optional" => Self::Optional,
            "TPDO" => Self::Tpdo,
            "RPDO" => Self::Rpdo,
            _ => return None,
        })
    }

    /// Reads `PDOmapping`; another letter case of a token (`tpdo`) is lenient.
    pub(crate) fn read(token: &str) -> Reading<Self> {
        const TOKENS: &str = "is not a CiA 311 PDOmapping (no, default, optional, TPDO, RPDO)";
        if let Some(mapping) = Self::parse(token) {
            return Reading::Valid(mapping);
        }
        let t = token.trim();
        match [Self::No, Self::Default, Self::Optional, Self::Tpdo, Self::Rpdo]
            .into_iter()
            .find(|m| m.as_str().eq_ignore_ascii_case(t))
        {
            Some(mapping) => Reading::Lenient(mapping, format!("{TOKENS}; read as {}", mapping.as_str())),
            None => Reading::Unreadable(TOKENS.to_owned()),
        }
    }

    pub(crate) fn as_str(self) -> &'static str {
        match self {
            Self::No => "no",
            Self::Default => "default",
            Self::Optional => "optional",
            Self::Tpdo => "TPDO",
            Self::Rpdo => "RPDO",
        }
    }

    /// The PDO mapping token for CiA 306 `PDOMapping=1`, refined by direction as CANopenEditor
    /// does: what only a TPDO can carry (ro, const, rwr) is `TPDO`, what only an RPDO can carry
    /// (wo, rww) is `RPDO`, rw is `optional`.
    pub(crate) fn mappable(access: Option<AccessType>) -> Self {
        match access {
            Some(AccessType::Ro | AccessType::Const | AccessType::Rwr) => Self::Tpdo,
            Some(AccessType::Wo | AccessType::Rww) => Self::Rpdo,
            Some(AccessType::Rw) | None => Self::Optional,
        }
    }
}

/// A CiA 311 baud-rate token.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum BaudRate {
    /// A rate in kbit/s.
    Kbps(u32),
    /// `auto-baudRate`.
    Auto,
}

/// Reads `250 Kbps` (the schema spelling), leniently `250Kbps`, `250 kbps` and a bare `250`; the flag
/// says it was not the schema spelling.
pub(crate) fn parse_baud_rate(text: &str) -> Option<(BaudRate, bool)> {
    let t = text.trim();
    if t == "auto-baudRate" {
        return Some((BaudRate::Auto, false));
    }
    if t.eq_ignore_ascii_case("auto-baudrate") || t.eq_ignore_ascii_case("auto") {
        return Some((BaudRate::Auto, true));
    }
    let digits_end = t.find(|c: char| !c.is_ascii_digit()).unwrap_or(t.len());
    let (digits, unit) = t.split_at(digits_end);
    let rate: u32 = digits.parse().ok()?;
    let exact = matches!(rate, 10 | 20 | 50 | 100 | 125 | 250 | 500 | 800 | 1000) && unit == " Kbps";
    let unit = unit.trim();
    if !(unit.is_empty() || unit.eq_ignore_ascii_case("kbps") || unit.eq_ignore_ascii_case("kbit/s")) {
        return None;
    }
    Some((BaudRate::Kbps(rate), !exact))
}

/// The schema spelling of a baud rate in kbit/s.
pub(crate) fn baud_rate_token(kbps: u32) -> String {
    format!("{kbps} Kbps")
}

/// EDS `MM-DD-YYYY` to xsd:date `YYYY-MM-DD`.
pub(crate) fn date_to_xsd(eds: &str) -> Option<String> {
    let mut parts = eds.trim().split('-');
    let (m, d, y) = (parts.next()?, parts.next()?, parts.next()?);
    if parts.next().is_some() {
        return None;
    }
    let (month, day, year) = (number(m, 1..=12)?, number(d, 1..=31)?, number(y, 0..=9999)?);
    (y.len() == 4).then(|| format!("{year:04}-{month:02}-{day:02}"))
}

/// xsd:date `YYYY-MM-DD` (with an optional time zone, which EDS cannot hold) to EDS `MM-DD-YYYY`.
pub(crate) fn date_to_eds(xsd: &str) -> Option<String> {
    let t = xsd.trim();
    let (y, rest) = (t.get(..4)?, t.get(4..)?);
    let rest = rest.strip_prefix('-')?;
    let (m, rest) = (rest.get(..2)?, rest.get(2..)?);
    let rest = rest.strip_prefix('-')?;
    let (d, zone) = (rest.get(..2)?, rest.get(2..)?);
    if !(zone.is_empty() || zone == "Z" || is_zone_offset(zone)) {
        return None;
    }
    let (year, month, day) = (number(y, 0..=9999)?, number(m, 1..=12)?, number(d, 1..=31)?);
    Some(format!("{month:02}-{day:02}-{year:04}"))
}

/// EDS `hh:mmAM`/`hh:mmPM` (12-hour clock) to xsd:time `HH:MM:00`.
pub(crate) fn time_to_xsd(eds: &str) -> Option<String> {
    let t = eds.trim();
    let upper = t.to_ascii_uppercase();
    let (clock, pm) = match (upper.strip_suffix("AM"), upper.strip_suffix("PM")) {
        (Some(c), _) => (c.trim_end().to_owned(), false),
        (_, Some(c)) => (c.trim_end().to_owned(), true),
        _ => return None,
    };
    let (h, m) = clock.split_once(':')?;
    let (hour, minute) = (number(h, 1..=12)?, number(m, 0..=59)?);
    let hour24 = match (hour, pm) {
        (12, false) => 0,
        (12, true) => 12,
        (h, false) => h,
        (h, true) => h + 12,
    };
    Some(format!("{hour24:02}:{minute:02}:00"))
}

/// xsd:time `HH:MM:SS[.fff][zone]` to EDS `hh:mmAM`; leniently also `h:mm:ss PM`. Seconds and time
/// zone have no EDS home. The flag says the text was not xsd:time.
pub(crate) fn time_to_eds(xsd: &str) -> Option<(String, bool)> {
    let t = xsd.trim();
    let upper = t.to_ascii_uppercase();
    let twelve = match (upper.strip_suffix("AM"), upper.strip_suffix("PM")) {
        (Some(c), _) => Some((c.trim_end().to_owned(), false)),
        (_, Some(c)) => Some((c.trim_end().to_owned(), true)),
        _ => None,
    };
    let (hour24, minute, lenient) = match twelve {
        Some((clock, pm)) => {
            let mut parts = clock.split(':');
            let (hour, minute) = (number(parts.next()?, 1..=12)?, number(parts.next()?, 0..=59)?);
            let hour24 = match (hour, pm) {
                (12, false) => 0,
                (12, true) => 12,
                (h, false) => h,
                (h, true) => h + 12,
            };
            (hour24, minute, true)
        }
        None => {
            let (h, rest) = (t.get(..2)?, t.get(2..)?);
            let rest = rest.strip_prefix(':')?;
            let (m, rest) = (rest.get(..2)?, rest.get(2..)?);
            let rest = rest.strip_prefix(':')?;
            let (s, rest) = (rest.get(..2)?, rest.get(2..)?);
            number(s, 0..=60)?;
            let rest = match rest.strip_prefix('.') {
                Some(f) => f.trim_start_matches(|c: char| c.is_ascii_digit()),
                None => rest,
            };
            if !(rest.is_empty() || rest == "Z" || is_zone_offset(rest)) {
                return None;
            }
            (number(h, 0..=23)?, number(m, 0..=59)?, false)
        }
    };
    let (hour12, suffix) = match hour24 {
        0 => (12, "AM"),
        1..=11 => (hour24, "AM"),
        12 => (12, "PM"),
        h => (h - 12, "PM"),
    };
    Some((format!("{hour12:02}:{minute:02}{suffix}"), lenient))
}

fn is_zone_offset(text: &str) -> bool {
    matches!(text.as_bytes(), [b'+' | b'-', h1, h2, b':', m1, m2] if [h1, h2, m1, m2].iter().all(|d| d.is_ascii_digit()))
}

fn number(text: &str, range: std::ops::RangeInclusive<u32>) -> Option<u32> {
    if text.is_empty() || text.len() > 4 || !text.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    text.parse().ok().filter(|n| range.contains(n))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hex_is_read_leniently_and_remarks_say_why() {
        assert_eq!(
            parse_hex("1018"),
            Some(Hex {
                value: 0x1018,
                digits: 4,
                prefixed: false
            })
        );
        assert_eq!(
            parse_hex(" 0x7 "),
            Some(Hex {
                value: 7,
                digits: 1,
                prefixed: true
            })
        );
        assert_eq!(parse_hex("00010000").map(|h| h.value), Some(0x10000));
        assert_eq!(parse_hex("000000000000000000001").map(|h| h.value), Some(1));
        assert_eq!(parse_hex("1FFFFFFFFFFFFFFFF"), None, "more than 64 bits");
        assert_eq!(parse_hex("12G4"), None);
        assert_eq!(parse_hex(""), None);
        assert_eq!(parse_hex("0x"), None);
        assert_eq!(hex_width_remark("subIndex", "01", &[2]), None);
        assert!(hex_width_remark("subIndex", "0001", &[2]).is_some_and(|r| r.contains("4 hex digits")));
        assert_eq!(
            hex_width_remark("objFlags", "3", &[4]),
            None,
            "not hexBinary: read_hex says so"
        );
    }

    #[test]
    fn hex_binary_breaks_are_lenient_and_junk_is_unreadable() {
        assert_eq!(read_hex("1018", 0xFFFF), Reading::Valid(0x1018));
        let lenient = |text, max| match read_hex(text, max) {
            Reading::Lenient(value, why) => Some((value, why)),
            _ => None,
        };
        assert!(lenient("201", 0xFFFF).is_some_and(|(v, why)| v == 0x201 && why.contains("odd number")));
        assert!(lenient("0x2000", 0xFFFF).is_some_and(|(v, why)| v == 0x2000 && why.contains("`0x` prefix")));
        assert!(matches!(read_hex("20G0", 0xFFFF), Reading::Unreadable(_)));
        assert!(matches!(read_hex("0100", 0xFF), Reading::Unreadable(why) if why.contains("above FFh")));
        assert!(matches!(read_hex("", 0xFF), Reading::Unreadable(_)));
    }

    #[test]
    fn unsigned_types_booleans_and_ids() {
        assert_eq!(read_unsigned("7", UNSIGNED_BYTE), Reading::Valid(7));
        assert_eq!(read_unsigned(" +7 ", UNSIGNED_BYTE), Reading::Valid(7));
        assert!(matches!(
            read_unsigned("0x7", UNSIGNED_BYTE),
            Reading::Lenient(7, _)
        ));
        assert!(matches!(
            read_unsigned("256", UNSIGNED_BYTE),
            Reading::Unreadable(_)
        ));
        assert_eq!(read_unsigned("65535", UNSIGNED_SHORT), Reading::Valid(65535));
        assert!(
            matches!(read_unsigned("VAR", UNSIGNED_BYTE), Reading::Unreadable(why) if why.contains("unsignedByte"))
        );
        assert!(matches!(
            read_unsigned("-1", UNSIGNED_LONG),
            Reading::Unreadable(_)
        ));
        assert_eq!(read_bool("1"), Reading::Valid(true));
        assert!(matches!(read_bool("TRUE"), Reading::Lenient(true, _)));
        assert!(matches!(read_bool("yes"), Reading::Unreadable(_)));
        for id in ["UID_OBJ_1000", "_x", "p.1-a", "Größe"] {
            assert!(is_ncname(id), "{id}");
        }
        for id in ["", "1000", "a b", "x:y", "-a"] {
            assert!(!is_ncname(id), "{id}");
        }
    }

    #[test]
    fn unsigned_and_boolean_tokens() {
        assert_eq!(parse_unsigned("17"), Some((17, false)));
        assert_eq!(parse_unsigned("0x11"), Some((17, true)));
        assert_eq!(parse_unsigned("-1"), None);
        assert_eq!(parse_unsigned(""), None);
        assert_eq!(parse_bool("true"), Some((true, false)));
        assert_eq!(parse_bool("0"), Some((false, false)));
        assert_eq!(parse_bool("False"), Some((false, true)));
        assert_eq!(parse_bool("yes"), None);
    }

    #[test]
    fn iec_elements_map_both_ways() {
        for t in Iec::ALL {
            assert_eq!(Iec::from_name(t.name()), Some(t));
        }
        assert_eq!(Iec::from_name("udint"), None, "element names are case-sensitive");
        for code in [
            0x01u16, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08, 0x09, 0x0B, 0x11, 0x15, 0x1B,
        ] {
            let (iec, inline) = Iec::for_data_type(code);
            assert!(!inline, "{code:#x} has an IEC element");
            assert_eq!(iec.data_type(true), code);
        }
        for code in [
            0x0Au16, 0x0C, 0x0D, 0x0F, 0x10, 0x16, 0x18, 0x19, 0x1A, 0x12, 0x13, 0x14, 0x20, 0x1234,
        ] {
            assert_eq!(
                Iec::for_data_type(code),
                (Iec::Bitstring, true),
                "{code:#x} needs an inline dataType"
            );
        }
        assert_eq!(Iec::Bitstring.data_type(true), 0x000A);
        assert_eq!(Iec::Bitstring.data_type(false), 0x000F);
        assert_eq!(Iec::Dword.data_type(false), 0x0007);
        assert!(Iec::Udint.agrees_with(0x0007) && !Iec::Udint.agrees_with(0x0006));
        assert!(Iec::Bitstring.agrees_with(0x0016));
    }

    #[test]
    fn access_and_pdo_tokens() {
        for t in [
            "const",
            "read",
            "write",
            "readWrite",
            "readWriteInput",
            "readWriteOutput",
            "noAccess",
        ] {
            assert_eq!(ParamAccess::parse(t).map(ParamAccess::as_str), Some(t));
        }
        assert_eq!(ParamAccess::parse("ReadWrite"), None);
        assert_eq!(ParamAccess::ReadWriteInput.access_type(), Some(AccessType::Rwr));
        assert_eq!(ParamAccess::NoAccess.access_type(), None);
        for a in [
            AccessType::Ro,
            AccessType::Wo,
            AccessType::Rw,
            AccessType::Rwr,
            AccessType::Rww,
            AccessType::Const,
        ] {
            assert_eq!(ParamAccess::from_access_type(a).access_type(), Some(a));
        }
        for t in ["no", "default", "optional", "TPDO", "RPDO"] {
            assert_eq!(PdoMapping::parse(t).map(PdoMapping::as_str), Some(t));
        }
        assert_eq!(PdoMapping::mappable(Some(AccessType::Ro)), PdoMapping::Tpdo);
        assert_eq!(PdoMapping::mappable(Some(AccessType::Rww)), PdoMapping::Rpdo);
        assert_eq!(PdoMapping::mappable(Some(AccessType::Rw)), PdoMapping::Optional);
    }

    #[test]
    fn baud_rates() {
        assert_eq!(parse_baud_rate("250 Kbps"), Some((BaudRate::Kbps(250), false)));
        assert_eq!(parse_baud_rate("100 Kbps"), Some((BaudRate::Kbps(100), false)));
        assert_eq!(parse_baud_rate("500"), Some((BaudRate::Kbps(500), true)));
        assert_eq!(parse_baud_rate("1000kbps"), Some((BaudRate::Kbps(1000), true)));
        assert_eq!(parse_baud_rate("auto-baudRate"), Some((BaudRate::Auto, false)));
        assert_eq!(parse_baud_rate("fast"), None);
        assert_eq!(parse_baud_rate("250 Mbps"), None);
        assert_eq!(baud_rate_token(125), "125 Kbps");
    }

    #[test]
    fn dates_and_times_convert_both_ways() {
        assert_eq!(date_to_xsd("12-16-2025").as_deref(), Some("2025-12-16"));
        assert_eq!(date_to_xsd("2-1-2020").as_deref(), Some("2020-02-01"));
        assert_eq!(date_to_xsd("13-01-2020"), None);
        assert_eq!(date_to_xsd("12-16-25"), None);
        assert_eq!(date_to_eds("2025-12-16").as_deref(), Some("12-16-2025"));
        assert_eq!(date_to_eds("2025-12-16+01:00").as_deref(), Some("12-16-2025"));
        assert_eq!(date_to_eds("16.12.2025"), None);
        assert_eq!(date_to_eds(""), None);
        assert_eq!(time_to_xsd("10:00AM").as_deref(), Some("10:00:00"));
        assert_eq!(time_to_xsd("12:30AM").as_deref(), Some("00:30:00"));
        assert_eq!(time_to_xsd("01:05 pm").as_deref(), Some("13:05:00"));
        assert_eq!(time_to_xsd("13:00"), None);
        assert_eq!(
            time_to_eds("12:37:54.0000000+01:00"),
            Some(("12:37PM".to_owned(), false))
        );
        assert_eq!(time_to_eds("00:05:00"), Some(("12:05AM".to_owned(), false)));
        assert_eq!(time_to_eds("23:59:59Z"), Some(("11:59PM".to_owned(), false)));
        assert_eq!(time_to_eds("9:48:42 PM"), Some(("09:48PM".to_owned(), true)));
        assert_eq!(time_to_eds("25:00:00"), None);
        assert_eq!(time_to_eds("noon"), None);
        for eds in ["10:00AM", "12:00PM", "12:00AM", "11:59PM", "01:01AM"] {
            let back = time_to_xsd(eds).and_then(|x| time_to_eds(&x)).map(|(e, _)| e);
            assert_eq!(back.as_deref(), Some(eds));
        }
    }
}

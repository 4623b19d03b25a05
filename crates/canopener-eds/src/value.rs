//! Values as CiA 306 §4.2 writes them: integers in decimal, `0x` hexadecimal or `0` octal, `$NODEID`
//! formulas, REALs as decimals or IEEE 754 bit patterns, strings and hex octet strings.
//!
//! Parsing is lenient where the intent is unambiguous (`FEh`, `$NODEID + 0x180`, `0x180+$NODEID`,
//! `254 ; comment`) and reports every departure from the spec as an [`Issue`] with a stable code.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::diag::Code;
use crate::types::{DataType, TypeKind};

/// How an integer was written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Radix {
    /// Decimal digits.
    Decimal,
    /// `0x` followed by hex digits.
    Hex,
    /// A leading `0` followed by octal digits.
    Octal,
}

/// How a REAL was written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RealNotation {
    /// Decimal text such as `1.5` (python canopen, CANFestival).
    Decimal,
    /// The IEEE 754 bit pattern as an integer such as `0x3FC00000` (lely).
    BitPattern,
}

/// A typed value.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Value {
    /// BOOLEAN.
    Boolean {
        /// The value.
        value: bool,
    },
    /// Any INTEGERn or UNSIGNEDn (signed values already sign-extended).
    Integer {
        /// The value.
        value: i128,
        /// How it was written.
        radix: Radix,
    },
    /// `$NODEID+offset`: resolves to node-ID + offset.
    NodeRelative {
        /// The constant part.
        offset: i128,
        /// How the offset was written.
        radix: Radix,
    },
    /// REAL32 or REAL64.
    Real {
        /// The value.
        value: f64,
        /// How it was written.
        notation: RealNotation,
    },
    /// VISIBLE_STRING or UNICODE_STRING.
    Text {
        /// The text.
        value: String,
    },
    /// OCTET_STRING or DOMAIN bytes.
    Octets {
        /// The bytes.
        value: Vec<u8>,
    },
    /// TIME_OF_DAY or TIME_DIFFERENCE.
    Time {
        /// Days (since 1984-01-01 for TIME_OF_DAY).
        days: u16,
        /// Milliseconds (after midnight for TIME_OF_DAY).
        ms: u32,
    },
}

impl Value {
    /// The integer for a node-ID (resolving `$NODEID`), if the value is an integer.
    pub fn resolve(&self, node_id: u8) -> Option<i128> {
        match self {
            Self::Integer { value, .. } => Some(*value),
            Self::NodeRelative { offset, .. } => offset.checked_add(i128::from(node_id)),
            Self::Boolean { value } => Some(i128::from(*value)),
            _ => None,
        }
    }

    /// Whether two values mean the same thing, ignoring how they were written.
    pub fn same_meaning(&self, other: &Value) -> bool {
        match (self, other) {
            (Self::Integer { value: a, .. }, Self::Integer { value: b, .. }) => a == b,
            (Self::NodeRelative { offset: a, .. }, Self::NodeRelative { offset: b, .. }) => a == b,
            (Self::Real { value: a, .. }, Self::Real { value: b, .. }) => {
                a.to_bits() == b.to_bits() || a == b
            }
            (Self::Boolean { value: a }, Self::Integer { value: b, .. })
            | (Self::Integer { value: b, .. }, Self::Boolean { value: a }) => i128::from(*a) == *b,
            _ => self == other,
        }
    }
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Boolean { value } => write!(f, "{}", u8::from(*value)),
            Self::Integer {
                value,
                radix: Radix::Hex,
            } if *value >= 0 => write!(f, "0x{value:X}"),
            Self::Integer { value, .. } => write!(f, "{value}"),
            Self::NodeRelative { offset: 0, .. } => f.write_str("$NODEID"),
            Self::NodeRelative { offset, .. } => write!(f, "$NODEID+0x{offset:X}"),
            Self::Real { value, .. } => write!(f, "{value}"),
            Self::Text { value } => f.write_str(value),
            Self::Octets { value } => value.iter().try_for_each(|b| write!(f, "{b:02X}")),
            Self::Time { days, ms } => write!(f, "{days} {ms}"),
        }
    }
}

/// A departure from CiA 306 found while reading a value.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Issue {
    /// The diagnostic code.
    pub code: Code,
    /// What was found.
    pub message: String,
}

/// The outcome of reading a value: the value when one could be understood, and every issue.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Parsed {
    /// The value; `None` for an empty text or text that means nothing for the type.
    pub value: Option<Value>,
    /// Departures from CiA 306, in the order found.
    pub issues: Vec<Issue>,
}

/// A plain integer literal as written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct IntLiteral {
    /// The value (a leading `-` applied).
    pub value: i128,
    /// How it was written.
    pub radix: Radix,
}

/// Parses a CiA 306 integer: decimal, `0x` hex or leading-`0` octal, with an optional sign.
///
/// Lenient forms (an `h` suffix, a leading zero on what was meant as decimal but has 8 or 9 in it) are
/// accepted and reported in `issues`.
pub fn parse_integer(text: &str, issues: &mut Vec<Issue>) -> Option<IntLiteral> {
    let text = trim(text);
    let (negative, digits) = match text.strip_prefix('-') {
        Some(rest) => (true, rest.trim_start()),
        None => (false, text.strip_prefix('+').unwrap_or(text)),
    };
    let (magnitude, radix) = if let Some(hex) =
        digits.strip_prefix("0x").or_else(|| digits.strip_prefix("0X"))
    {
        (parse_digits(hex, 16)?, Radix::Hex)
    } else if let Some(hex) = digits.strip_suffix('h').or_else(|| digits.strip_suffix('H')) {
        let value = parse_digits(hex, 16)?;
        issues.push(Issue {
            code: Code::HexSuffix,
            message: format!("`{text}` uses an `h` suffix; read as 0x{value:X}"),
        });
        (value, Radix::Hex)
    } else if digits.len() > 1 && digits.starts_with('0') {
        match parse_digits(&digits[1..], 8) {
            Some(value) => {
                if digits.bytes().all(|b| b == b'0') {
                    (0, Radix::Octal)
                } else {
                    issues.push(Issue {
                        code: Code::OctalLeadingZero,
                        message: format!(
                            "`{text}` has a leading zero, so CiA 306 reads it as octal ({value}); python canopen rejects it"
                        ),
                    });
                    (value, Radix::Octal)
                }
            }
            None => {
                let value = parse_digits(digits, 10)?;
                issues.push(Issue {
                    code: Code::InvalidNumber,
                    message: format!("`{text}` has a leading zero but is not octal; read as decimal {value}"),
                });
                (value, Radix::Decimal)
            }
        }
    } else {
        (parse_digits(digits, 10)?, Radix::Decimal)
    };
    Some(IntLiteral {
        value: if negative { -magnitude } else { magnitude },
        radix,
    })
}

/// Whether a value mentions `$NODEID` in any letter case.
pub fn mentions_nodeid(text: &str) -> bool {
    // Most values have no `$` at all, which one `memchr` settles.
    text.as_bytes().contains(&b'$')
        && text
            .as_bytes()
            .windows(7)
            .any(|w| w.eq_ignore_ascii_case(b"$NODEID"))
}

/// `str::trim`, skipping its character decoding for the usual value (already trimmed of ASCII white
/// space by the loader) whose first and last bytes are visible ASCII, which no trimming removes.
pub(crate) fn trim(text: &str) -> &str {
    match (text.as_bytes().first(), text.as_bytes().last()) {
        (Some(first), Some(last)) if first.is_ascii_graphic() && last.is_ascii_graphic() => text,
        _ => text.trim(),
    }
}

/// Reads `text` as a value of `data_type` (`None` for types without a value syntax: records, unknown).
pub fn parse_value(text: &str, data_type: DataType) -> Parsed {
    let mut parsed = Parsed::default();
    let text = trim(text);
    if text.is_empty() {
        return parsed;
    }
    let Some(kind) = data_type.kind() else {
        return parsed;
    };
    parsed.value = match kind {
        TypeKind::VisibleString | TypeKind::UnicodeString => Some(Value::Text {
            value: text.to_owned(),
        }),
        TypeKind::Structure => None,
        _ => parse_typed(text, data_type, kind, &mut parsed.issues).or_else(|| {
            // Retry without a trailing comment; CiA 306 has none, but tools write `254 ; async`.
            let cut = text.find([';', '#'])?;
            let head = text[..cut].trim_end();
            if head.is_empty() {
                return None;
            }
            let mut retry = Vec::new();
            let value = parse_typed(head, data_type, kind, &mut retry)?;
            parsed.issues.push(Issue {
                code: Code::InlineComment,
                message: format!(
                    "`{}` after the value was ignored; CiA 306 has no inline comments",
                    &text[cut..]
                ),
            });
            parsed.issues.extend(retry);
            Some(value)
        }),
    };
    if parsed.value.is_none() && parsed.issues.iter().all(|i| i.code != Code::InvalidValue) {
        let code = match kind {
            TypeKind::Boolean => Code::InvalidBoolean,
            TypeKind::OctetString | TypeKind::Domain => Code::InvalidOctets,
            TypeKind::Signed(_) | TypeKind::Unsigned(_) => Code::InvalidNumber,
            _ => Code::InvalidValue,
        };
        parsed.issues.retain(|i| i.code != Code::InlineComment);
        parsed.issues.push(Issue {
            code,
            message: format!("`{text}` is not a valid {data_type} value"),
        });
    }
    parsed
}

fn parse_typed(text: &str, data_type: DataType, kind: TypeKind, issues: &mut Vec<Issue>) -> Option<Value> {
    match kind {
        TypeKind::Boolean => {
            let mut local = Vec::new();
            let literal = parse_integer(text, &mut local)?;
            match literal.value {
                0 | 1 => {
                    issues.extend(local);
                    Some(Value::Boolean {
                        value: literal.value == 1,
                    })
                }
                _ => None,
            }
        }
        TypeKind::Signed(bits) | TypeKind::Unsigned(bits) => {
            let signed = matches!(kind, TypeKind::Signed(_));
            if mentions_nodeid(text) {
                return parse_formula(text, bits, signed, issues);
            }
            let mut local = Vec::new();
            let literal = parse_integer(text, &mut local)?;
            issues.extend(local);
            Some(check_integer(text, literal, bits, signed, data_type, issues))
        }
        TypeKind::Real32 | TypeKind::Real64 => parse_real(text, kind == TypeKind::Real64, issues),
        TypeKind::OctetString | TypeKind::Domain => parse_octets(text),
        TypeKind::TimeOfDay | TypeKind::TimeDifference => parse_time(text, issues),
        TypeKind::VisibleString | TypeKind::UnicodeString | TypeKind::Structure => None,
    }
}

fn check_integer(
    text: &str,
    literal: IntLiteral,
    bits: u32,
    signed: bool,
    t: DataType,
    issues: &mut Vec<Issue>,
) -> Value {
    let (min, max) = range_of(bits, signed);
    let mut value = literal.value;
    if signed && literal.radix != Radix::Decimal && value > max && value < (1i128 << bits) {
        let wrapped = value - (1i128 << bits);
        issues.push(Issue {
            code: Code::TwosComplement,
            message: format!("`{text}` is above the {t} maximum; read as two's complement {wrapped}"),
        });
        value = wrapped;
    } else if value < min || value > max {
        issues.push(Issue {
            code: Code::OutOfRange,
            message: format!("`{text}` ({value}) is outside the {t} range {min}..={max}"),
        });
    }
    Value::Integer {
        value,
        radix: literal.radix,
    }
}

/// The range of an n-bit integer type.
pub fn range_of(bits: u32, signed: bool) -> (i128, i128) {
    if signed {
        (-(1i128 << (bits - 1)), (1i128 << (bits - 1)) - 1)
    } else {
        (0, (1i128 << bits) - 1)
    }
}

fn parse_formula(text: &str, bits: u32, signed: bool, issues: &mut Vec<Issue>) -> Option<Value> {
    let mut offset = 0i128;
    let mut radix = Radix::Hex;
    let mut node_terms = 0;
    let mut node_first = false;
    for (position, term) in text.split('+').enumerate() {
        let term = term.trim();
        if term.eq_ignore_ascii_case("$NODEID") {
            node_terms += 1;
            node_first |= position == 0;
        } else {
            let literal = parse_integer(term, issues)?;
            offset = offset.checked_add(literal.value)?;
            radix = literal.radix;
        }
    }
    if node_terms != 1 {
        return None;
    }
    let terms = text.matches('+').count();
    if !node_first || terms > 1 {
        let why = match (node_first, terms > 1) {
            (true, _) => {
                "CiA 306 allows a single offset after `$NODEID`; python canopen reads None and lely rejects it"
            }
            (false, false) => "CiA 306 wants `$NODEID` first; lely rejects this form",
            (false, true) => {
                "CiA 306 wants `$NODEID` first and a single offset; python canopen reads None and lely rejects it"
            }
        };
        issues.push(Issue {
            code: Code::NodeIdFormula,
            message: format!("`{text}` read as $NODEID+0x{offset:X}; {why}"),
        });
    } else if !(text == "$NODEID" || text.starts_with("$NODEID+")) {
        issues.push(Issue {
            code: Code::NodeIdSpelling,
            message: format!(
                "`{text}` read as $NODEID+0x{offset:X}; CiA 306 writes `$NODEID+offset` in capitals without spaces"
            ),
        });
    }
    let (min, max) = range_of(bits, signed);
    // lely's rule: the formula must fit for every node-ID 1..=127.
    if offset.saturating_add(1) < min || offset.saturating_add(127) > max {
        issues.push(Issue {
            code: Code::OutOfRange,
            message: format!("`{text}` leaves the {bits}-bit range for some node-ID 1..=127"),
        });
    }
    Some(Value::NodeRelative { offset, radix })
}

fn parse_real(text: &str, is64: bool, issues: &mut Vec<Issue>) -> Option<Value> {
    let lower = text.to_ascii_lowercase();
    if lower.starts_with("0x") || lower.starts_with("-0x") {
        let literal = parse_integer(text, &mut Vec::new())?;
        let value = if is64 {
            f64::from_bits(u64::try_from(literal.value).ok()?)
        } else {
            f64::from(f32::from_bits(u32::try_from(literal.value).ok()?))
        };
        issues.push(Issue {
            code: Code::RealNotation,
            message: format!("REAL `{text}` is an IEEE 754 bit pattern ({value}); python canopen reads None"),
        });
        return Some(Value::Real {
            value,
            notation: RealNotation::BitPattern,
        });
    }
    let value: f64 = text.parse().ok()?;
    if text.contains(['.', 'e', 'E']) {
        issues.push(Issue {
            code: Code::RealNotation,
            message: format!("REAL `{text}` is decimal; lely expects an IEEE 754 bit pattern and rejects it"),
        });
    }
    let value = if is64 { value } else { f64::from(value as f32) };
    Some(Value::Real {
        value,
        notation: RealNotation::Decimal,
    })
}

fn parse_octets(text: &str) -> Option<Value> {
    let digits: String = text.chars().filter(|c| !c.is_whitespace()).collect();
    let digits = digits.strip_prefix("0x").unwrap_or(&digits);
    if !digits.len().is_multiple_of(2) || !digits.bytes().all(|b| b.is_ascii_hexdigit()) {
        return None;
    }
    let value = (0..digits.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&digits[i..i + 2], 16).ok())
        .collect::<Option<Vec<u8>>>()?;
    Some(Value::Octets { value })
}

fn parse_time(text: &str, issues: &mut Vec<Issue>) -> Option<Value> {
    let parts: Vec<&str> = text.split_whitespace().collect();
    match parts.as_slice() {
        // lely's form: days, then milliseconds.
        [days, ms] => {
            let days = u16::try_from(parse_integer(days, issues)?.value).ok()?;
            let ms = u32::try_from(parse_integer(ms, issues)?.value).ok()?;
            Some(Value::Time { days, ms })
        }
        // One integer: the 48-bit wire value (ms in bits 0-27, days in bits 32-47).
        [raw] => {
            let raw = u64::try_from(parse_integer(raw, issues)?.value).ok()?;
            if raw >> 48 != 0 {
                return None;
            }
            Some(Value::Time {
                days: (raw >> 32) as u16,
                ms: (raw & 0x0FFF_FFFF) as u32,
            })
        }
        _ => None,
    }
}

fn parse_digits(digits: &str, radix: u32) -> Option<i128> {
    if digits.len() <= 15 && !digits.is_empty() {
        // Fifteen digits of a radix up to 16 fit in a u64, and u64 arithmetic is much cheaper than
        // the i128 `from_str_radix`; nearly every value takes this path.
        let mut value = 0u64;
        for b in digits.bytes() {
            value = value * u64::from(radix) + u64::from(char::from(b).to_digit(radix)?);
        }
        return Some(i128::from(value));
    }
    if digits.is_empty() || digits.len() > 40 || !digits.chars().all(|c| c.is_digit(radix)) {
        return None;
    }
    i128::from_str_radix(digits, radix).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn int(text: &str) -> (Option<i128>, Vec<Code>) {
        let mut issues = Vec::new();
        let value = parse_integer(text, &mut issues).map(|l| l.value);
        (value, issues.into_iter().map(|i| i.code).collect())
    }

    fn value(text: &str, t: DataType) -> (Option<Value>, Vec<Code>) {
        let parsed = parse_value(text, t);
        (parsed.value, parsed.issues.into_iter().map(|i| i.code).collect())
    }

    proptest::proptest! {
        #[test]
        fn parse_digits_agrees_with_from_str_radix(digits in "[0-9a-fA-F+ xé-]{0,20}") {
            for radix in [8, 10, 16] {
                let slow = (!digits.is_empty() && digits.chars().all(|c| c.is_digit(radix)))
                    .then(|| i128::from_str_radix(&digits, radix).ok())
                    .flatten();
                proptest::prop_assert_eq!(parse_digits(&digits, radix), slow);
            }
        }

        #[test]
        fn trim_agrees_with_str_trim(text in "[ \t\u{a0}a0;]{0,6}") {
            proptest::prop_assert_eq!(trim(&text), text.trim());
        }
    }

    #[test]
    fn integers_in_every_cia306_notation_are_equal() {
        for text in ["10", "0xa", "0x0A", "0xA", "0x000A", "012"] {
            assert_eq!(int(text).0, Some(10), "{text}");
        }
        assert_eq!(int("0"), (Some(0), vec![]));
        assert_eq!(int("00"), (Some(0), vec![]));
        assert_eq!(int("-0x10").0, Some(-16));
        assert_eq!(int("0254"), (Some(172), vec![Code::OctalLeadingZero]));
        assert_eq!(int("089"), (Some(89), vec![Code::InvalidNumber]));
        assert_eq!(int("FEh"), (Some(0xFE), vec![Code::HexSuffix]));
        assert_eq!(int("1.0").0, None);
        assert_eq!(int("").0, None);
        assert_eq!(int("0x").0, None);
    }

    #[test]
    fn integer_ranges_and_twos_complement() {
        assert_eq!(
            value("300", DataType::UNSIGNED8),
            (
                Some(Value::Integer {
                    value: 300,
                    radix: Radix::Decimal
                }),
                vec![Code::OutOfRange]
            )
        );
        assert_eq!(
            value("0x8000", DataType::INTEGER16),
            (
                Some(Value::Integer {
                    value: -32768,
                    radix: Radix::Hex
                }),
                vec![Code::TwosComplement]
            )
        );
        assert_eq!(value("-1", DataType::UNSIGNED8).1, vec![Code::OutOfRange]);
        assert_eq!(value("0xFFFFFF", DataType::UNSIGNED24).1, Vec::<Code>::new());
        assert_eq!(
            value("0x800000", DataType::INTEGER24)
                .0
                .and_then(|v| v.resolve(0)),
            Some(-0x800000)
        );
        assert_eq!(
            value("18446744073709551615", DataType::UNSIGNED64).1,
            Vec::<Code>::new()
        );
    }

    #[test]
    fn nodeid_formulas() {
        let rel = |offset| {
            Some(Value::NodeRelative {
                offset,
                radix: Radix::Hex,
            })
        };
        assert_eq!(value("$NODEID+0x180", DataType::UNSIGNED32), (rel(0x180), vec![]));
        assert_eq!(
            value("$NODEID + 0x180", DataType::UNSIGNED32),
            (rel(0x180), vec![Code::NodeIdSpelling])
        );
        assert_eq!(
            value("$NodeID+0x180", DataType::UNSIGNED32).1,
            vec![Code::NodeIdSpelling]
        );
        assert_eq!(
            value("0x180+$NODEID", DataType::UNSIGNED32),
            (rel(0x180), vec![Code::NodeIdFormula])
        );
        assert_eq!(
            value("0x40000000+$NODEID+0x180", DataType::UNSIGNED32),
            (rel(0x4000_0180), vec![Code::NodeIdFormula])
        );
        assert_eq!(
            value("$NODEID+0x80000200", DataType::UNSIGNED32)
                .0
                .and_then(|v| v.resolve(5)),
            Some(0x8000_0205)
        );
        assert_eq!(
            value("$NODEID+$NODEID", DataType::UNSIGNED32).1,
            vec![Code::InvalidNumber]
        );
        assert_eq!(
            value("$NODEID+0xFF", DataType::UNSIGNED8).1,
            vec![Code::OutOfRange]
        );
    }

    #[test]
    fn reals_remember_their_notation() {
        assert_eq!(
            value("0x3F800000", DataType::REAL32),
            (
                Some(Value::Real {
                    value: 1.0,
                    notation: RealNotation::BitPattern
                }),
                vec![Code::RealNotation]
            )
        );
        assert_eq!(
            value("1.5", DataType::REAL32),
            (
                Some(Value::Real {
                    value: 1.5,
                    notation: RealNotation::Decimal
                }),
                vec![Code::RealNotation]
            )
        );
        assert_eq!(
            value("0", DataType::REAL64),
            (
                Some(Value::Real {
                    value: 0.0,
                    notation: RealNotation::Decimal
                }),
                vec![]
            )
        );
        assert_eq!(value("abc", DataType::REAL32).1, vec![Code::InvalidValue]);
    }

    #[test]
    fn inline_comments_are_cut_with_a_warning() {
        assert_eq!(
            value("254 ; async", DataType::UNSIGNED8),
            (
                Some(Value::Integer {
                    value: 254,
                    radix: Radix::Decimal
                }),
                vec![Code::InlineComment]
            )
        );
        assert_eq!(value("Motor #1", DataType::VISIBLE_STRING).1, Vec::<Code>::new());
        assert_eq!(value("x ; y", DataType::UNSIGNED8).1, vec![Code::InvalidNumber]);
    }

    #[test]
    fn strings_octets_booleans_and_times() {
        assert_eq!(
            value("01a1053c", DataType::OCTET_STRING).0,
            Some(Value::Octets {
                value: vec![1, 0xa1, 5, 0x3c]
            })
        );
        assert_eq!(
            value("C8 3D BB", DataType::OCTET_STRING).0,
            Some(Value::Octets {
                value: vec![0xc8, 0x3d, 0xbb]
            })
        );
        assert_eq!(value("123", DataType::DOMAIN).1, vec![Code::InvalidOctets]);
        assert_eq!(
            value("1", DataType::BOOLEAN).0,
            Some(Value::Boolean { value: true })
        );
        assert_eq!(value("2", DataType::BOOLEAN).1, vec![Code::InvalidBoolean]);
        assert_eq!(
            value("12 3600000", DataType::TIME_OF_DAY).0,
            Some(Value::Time {
                days: 12,
                ms: 3_600_000
            })
        );
        assert_eq!(
            value("0x000C00000010", DataType::TIME_DIFFERENCE).0,
            Some(Value::Time { days: 12, ms: 16 })
        );
        assert_eq!(value("", DataType::UNSIGNED8), (None, vec![]));
        assert_eq!(value("anything", DataType(0x0040)), (None, vec![]));
    }

    #[test]
    fn huge_nodeid_offsets_are_out_of_range_not_an_overflow() {
        let parsed = parse_value(
            "$NODEID+170141183460469231731687303715884105700",
            DataType::UNSIGNED32,
        );
        assert!(parsed.issues.iter().any(|i| i.code == Code::OutOfRange));
        let huge = Value::NodeRelative {
            offset: i128::MAX,
            radix: Radix::Decimal,
        };
        assert_eq!(huge.resolve(1), None);
    }
}

//! Typed values for SDO reads and writes, and object addresses as people type them (CiA 301 §7.1
//! data types and their little-endian encoding, §7.4.3 object dictionary addressing).
//!
//! Before changing this file read CiA 301 §7.1 (how integers, REALs, BOOLEAN and strings are laid
//! out in bytes) and §7.4.7.1 (the basic data type indices).
//!
//! Text conventions, the same everywhere the CLI takes numbers:
//! - **Values** ([`ValueType::parse`]) are decimal unless marked: `0x1A` or `1Ah` is hexadecimal,
//!   `0b1010` binary, `_` may separate digits (`1_000_000`, `0xFFFF_FFFF`). A hexadecimal or binary
//!   value written without a sign is a bit pattern of the type, so `0xFFFF` is `-1` as an `i16`;
//!   with a minus sign it is a magnitude (`-0x10` is `-16`).
//! - **Object addresses** ([`parse_index`], [`parse_sub`], [`parse_object`], [`parse_mapping`]) are
//!   hexadecimal unless marked, as in CiA 301 and EDS files: `1018`, `0x1018` and `1018h` are all
//!   1018h. The marker `d:` makes the next number decimal: `d:4120` is 1018h, `1018:d:10` is
//!   sub-index 0Ah. Mapping lengths are in bits and decimal, as people say them: `6000:01:8`.

use std::borrow::Cow;
use std::fmt;
use std::str::FromStr;

use canopener_od::{DataType, ObjectKey};

use crate::pdo_config::MappedObject;

/// The type a value is read or written as, chosen by the user (`u16`, `str`, ...) or by the data
/// type of the object in an EDS ([`ValueType::from_data_type`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ValueType {
    /// BOOLEAN, one byte on SDO: 0 = false, 1 = true.
    Bool,
    /// UNSIGNED8.
    U8,
    /// UNSIGNED16.
    U16,
    /// UNSIGNED24.
    U24,
    /// UNSIGNED32.
    U32,
    /// UNSIGNED40.
    U40,
    /// UNSIGNED48.
    U48,
    /// UNSIGNED56.
    U56,
    /// UNSIGNED64.
    U64,
    /// INTEGER8.
    I8,
    /// INTEGER16.
    I16,
    /// INTEGER24.
    I24,
    /// INTEGER32.
    I32,
    /// INTEGER40.
    I40,
    /// INTEGER48.
    I48,
    /// INTEGER56.
    I56,
    /// INTEGER64.
    I64,
    /// REAL32.
    F32,
    /// REAL64.
    F64,
    /// VISIBLE_STRING: the text's bytes as they are, any length.
    Str,
    /// OCTET_STRING or DOMAIN: raw bytes written in hex, any length.
    Bytes,
}

/// A value decoded from its bytes, to print for people ([`fmt::Display`]: `4660 (0x1234)`) or to
/// hand to a JSON writer through the `as_*` accessors.
#[derive(Debug, Clone, PartialEq)]
pub enum DisplayValue {
    /// A BOOLEAN.
    Bool(bool),
    /// An unsigned integer of `bits` bits: an UNSIGNEDn, or a PDO field of unknown type.
    Unsigned {
        /// The value.
        value: u64,
        /// Its width, which sets the number of hex digits shown.
        bits: u32,
    },
    /// A two's complement integer of `bits` bits.
    Signed {
        /// The value, sign-extended.
        value: i64,
        /// Its width, which sets the bit pattern shown in hex.
        bits: u32,
    },
    /// A REAL32.
    Real32(f32),
    /// A REAL64.
    Real64(f64),
    /// A VISIBLE_STRING's bytes as received; not necessarily ASCII, not necessarily UTF-8.
    Text(Vec<u8>),
    /// An OCTET_STRING or DOMAIN.
    Bytes(Vec<u8>),
}

/// Why a type name, a value text or a value's bytes could not be used. The messages say what was
/// wrong and how to write it instead.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ValueError {
    /// A type name that is none of the known spellings.
    #[error(
        "unknown value type `{text}`: use bool, u8..u64, i8..i64 (also u24, i40, ...), f32, f64, str or hex \
         (CiA names like UNSIGNED16, INTEGER8, REAL32, VISIBLE_STRING and DOMAIN work too)"
    )]
    UnknownType {
        /// The name given.
        text: String,
    },
    /// Text that is not an integer at all.
    #[error("`{text}` is not a number for {ty}: write it in decimal or hex, e.g. {example}", example = ty.example())]
    NotAnInteger {
        /// The text given.
        text: String,
        /// The type asked for.
        ty: ValueType,
    },
    /// An integer outside the range of its type.
    #[error("`{text}` is out of range for {ty} ({min} to {max}), e.g. {example}", example = ty.example())]
    OutOfRange {
        /// The text given.
        text: String,
        /// The type asked for.
        ty: ValueType,
        /// The smallest value of the type.
        min: i128,
        /// The largest value of the type.
        max: i128,
    },
    /// Text that is not a floating-point number.
    #[error("`{text}` is not a number for {ty}: write it like 1.5, -0.25, 1e-3, NaN or inf (no hex)")]
    NotAFloat {
        /// The text given.
        text: String,
        /// The type asked for.
        ty: ValueType,
    },
    /// A finite number too large for REAL32 or REAL64.
    #[error("`{text}` is too large for {ty} (largest {max}); write inf if you mean infinity", max = ty.float_max())]
    FloatOutOfRange {
        /// The text given.
        text: String,
        /// The type asked for.
        ty: ValueType,
    },
    /// Text that is not a boolean.
    #[error("`{text}` is not a bool: write true, false, 1 or 0")]
    NotABool {
        /// The text given.
        text: String,
    },
    /// A group of hex digits with an odd count.
    #[error("odd number of hex digits in `{group}`: write two digits per byte, like 01 02 0F or 01020F")]
    OddHexDigits {
        /// The space-separated group with the odd count.
        group: String,
    },
    /// A group that is not hex digits.
    #[error("`{group}` is not hex bytes: write two hex digits per byte, like 01 02 FF or 0102FF")]
    NotHex {
        /// The space-separated group with a non-hex character.
        group: String,
    },
    /// Bytes of the wrong length for a fixed-size type.
    #[error("{ty} takes {expected} byte(s), got {got}")]
    WrongLength {
        /// The type asked for.
        ty: ValueType,
        /// The size of the type.
        expected: usize,
        /// The number of bytes given.
        got: usize,
    },
    /// A BOOLEAN byte other than 0 or 1.
    #[error("{byte:#04X} is not a BOOLEAN (0 = false, 1 = true)")]
    NotBoolean {
        /// The byte received.
        byte: u8,
    },
}

/// Why an object address, a sub-index or a mapping entry could not be read. The messages give an
/// example of a correct spelling.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum AddressError {
    /// Not an object index.
    #[error(
        "`{text}` is not an object index (0000h to FFFFh): write it in hex like 1018, 0x1018 or 1018h, or in decimal like d:4120"
    )]
    Index {
        /// The text given.
        text: String,
    },
    /// Not a sub-index.
    #[error(
        "`{text}` is not a sub-index (00h to FFh): write it in hex like 01, 0x1A or 1Ah, or in decimal like d:26"
    )]
    Sub {
        /// The text given.
        text: String,
    },
    /// Not `index:sub`.
    #[error("`{text}` is not an object address: write index:sub in hex like 1018:01 (decimal: d:4120:d:1)")]
    Object {
        /// The text given.
        text: String,
    },
    /// Not `index:sub:bits` nor a 32-bit mapping entry.
    #[error(
        "`{text}` is not a mapping entry ({reason}): write index:sub:bits like 6000:01:8 (index and sub in hex, \
         length in bits in decimal) or the 32-bit entry like 0x60000108"
    )]
    Mapping {
        /// The text given.
        text: String,
        /// What is wrong with it.
        reason: &'static str,
    },
}

impl ValueType {
    /// Every type, integers in increasing width.
    pub const ALL: [ValueType; 21] = [
        ValueType::Bool,
        ValueType::U8,
        ValueType::U16,
        ValueType::U24,
        ValueType::U32,
        ValueType::U40,
        ValueType::U48,
        ValueType::U56,
        ValueType::U64,
        ValueType::I8,
        ValueType::I16,
        ValueType::I24,
        ValueType::I32,
        ValueType::I40,
        ValueType::I48,
        ValueType::I56,
        ValueType::I64,
        ValueType::F32,
        ValueType::F64,
        ValueType::Str,
        ValueType::Bytes,
    ];

    /// The short name [`FromStr`] reads and [`fmt::Display`] prints, e.g. `"u16"`.
    pub const fn name(self) -> &'static str {
        match self {
            ValueType::Bool => "bool",
            ValueType::U8 => "u8",
            ValueType::U16 => "u16",
            ValueType::U24 => "u24",
            ValueType::U32 => "u32",
            ValueType::U40 => "u40",
            ValueType::U48 => "u48",
            ValueType::U56 => "u56",
            ValueType::U64 => "u64",
            ValueType::I8 => "i8",
            ValueType::I16 => "i16",
            ValueType::I24 => "i24",
            ValueType::I32 => "i32",
            ValueType::I40 => "i40",
            ValueType::I48 => "i48",
            ValueType::I56 => "i56",
            ValueType::I64 => "i64",
            ValueType::F32 => "f32",
            ValueType::F64 => "f64",
            ValueType::Str => "str",
            ValueType::Bytes => "hex",
        }
    }

    /// The CiA 301 data type written as this type: `Str` is VISIBLE_STRING, `Bytes` OCTET_STRING.
    pub const fn data_type(self) -> DataType {
        match self {
            ValueType::Bool => DataType::BOOLEAN,
            ValueType::U8 => DataType::UNSIGNED8,
            ValueType::U16 => DataType::UNSIGNED16,
            ValueType::U24 => DataType::UNSIGNED24,
            ValueType::U32 => DataType::UNSIGNED32,
            ValueType::U40 => DataType::UNSIGNED40,
            ValueType::U48 => DataType::UNSIGNED48,
            ValueType::U56 => DataType::UNSIGNED56,
            ValueType::U64 => DataType::UNSIGNED64,
            ValueType::I8 => DataType::INTEGER8,
            ValueType::I16 => DataType::INTEGER16,
            ValueType::I24 => DataType::INTEGER24,
            ValueType::I32 => DataType::INTEGER32,
            ValueType::I40 => DataType::INTEGER40,
            ValueType::I48 => DataType::INTEGER48,
            ValueType::I56 => DataType::INTEGER56,
            ValueType::I64 => DataType::INTEGER64,
            ValueType::F32 => DataType::REAL32,
            ValueType::F64 => DataType::REAL64,
            ValueType::Str => DataType::VISIBLE_STRING,
            ValueType::Bytes => DataType::OCTET_STRING,
        }
    }

    /// The type to read and write values of a CiA 301 §7.1 basic data type as.
    ///
    /// `None` for the types with no plain text form here (UNICODE_STRING, TIME_OF_DAY,
    /// TIME_DIFFERENCE) and for indices that are not basic types; read those as [`ValueType::Bytes`].
    pub fn from_data_type(data_type: DataType) -> Option<ValueType> {
        Some(match data_type {
            DataType::OCTET_STRING | DataType::DOMAIN => ValueType::Bytes,
            other => return ValueType::ALL.into_iter().find(|ty| ty.data_type() == other),
        })
    }

    /// The number of bytes a value takes, or `None` for `Str` and `Bytes`, which take any length.
    pub const fn byte_len(self) -> Option<usize> {
        match self.shape() {
            Shape::Bool => Some(1),
            Shape::Int { bits, .. } => Some(bits as usize / 8),
            Shape::F32 => Some(4),
            Shape::F64 => Some(8),
            Shape::Str | Shape::Bytes => None,
        }
    }

    /// Reads a value as the user wrote it and returns its little-endian bytes (CiA 301 §7.1.4).
    ///
    /// Integers are decimal, `0x`/`h` hex or `0b` binary and range-checked; floats are decimal
    /// (`1.5`, `-2e-3`, `NaN`, `inf`); bools are `true`, `false`, `1` or `0`; `str` takes the text
    /// as it is; `hex` takes two hex digits per byte, groups separated by spaces (`01 02 ff`,
    /// `0102ff`, the empty text for no bytes).
    pub fn parse(self, text: &str) -> Result<Vec<u8>, ValueError> {
        match self.shape() {
            Shape::Bool => match text.trim().to_ascii_lowercase().as_str() {
                "true" | "1" => Ok(vec![1]),
                "false" | "0" => Ok(vec![0]),
                _ => Err(ValueError::NotABool {
                    text: text.to_owned(),
                }),
            },
            Shape::Int { signed, bits } => parse_integer(self, text, signed, bits),
            Shape::F32 => Ok(parse_float::<f32>(self, text)?.to_le_bytes().to_vec()),
            Shape::F64 => Ok(parse_float::<f64>(self, text)?.to_le_bytes().to_vec()),
            Shape::Str => Ok(text.as_bytes().to_vec()),
            Shape::Bytes => parse_hex_bytes(text),
        }
    }

    /// Decodes a value's little-endian bytes. Fixed-size types need exactly [`byte_len`] bytes: an
    /// SDO client that got an expedited upload without a size should pass only the first ones.
    ///
    /// [`byte_len`]: ValueType::byte_len
    pub fn decode(self, bytes: &[u8]) -> Result<DisplayValue, ValueError> {
        if let Some(expected) = self.byte_len()
            && bytes.len() != expected
        {
            return Err(ValueError::WrongLength {
                ty: self,
                expected,
                got: bytes.len(),
            });
        }
        Ok(match self.shape() {
            Shape::Bool => match bytes {
                [0] => DisplayValue::Bool(false),
                [1] => DisplayValue::Bool(true),
                [byte, ..] => return Err(ValueError::NotBoolean { byte: *byte }),
                [] => {
                    return Err(ValueError::WrongLength {
                        ty: self,
                        expected: 1,
                        got: 0,
                    });
                }
            },
            Shape::Int { signed, bits } => {
                let raw = le_u64(bytes);
                if signed {
                    DisplayValue::Signed {
                        value: sign_extend(raw, bits),
                        bits,
                    }
                } else {
                    DisplayValue::Unsigned { value: raw, bits }
                }
            }
            Shape::F32 => DisplayValue::Real32(f32::from_bits(le_u64(bytes) as u32)),
            Shape::F64 => DisplayValue::Real64(f64::from_bits(le_u64(bytes))),
            Shape::Str => DisplayValue::Text(bytes.to_vec()),
            Shape::Bytes => DisplayValue::Bytes(bytes.to_vec()),
        })
    }

    const fn shape(self) -> Shape {
        match self {
            ValueType::Bool => Shape::Bool,
            ValueType::U8 => Shape::Int {
                signed: false,
                bits: 8,
            },
            ValueType::U16 => Shape::Int {
                signed: false,
                bits: 16,
            },
            ValueType::U24 => Shape::Int {
                signed: false,
                bits: 24,
            },
            ValueType::U32 => Shape::Int {
                signed: false,
                bits: 32,
            },
            ValueType::U40 => Shape::Int {
                signed: false,
                bits: 40,
            },
            ValueType::U48 => Shape::Int {
                signed: false,
                bits: 48,
            },
            ValueType::U56 => Shape::Int {
                signed: false,
                bits: 56,
            },
            ValueType::U64 => Shape::Int {
                signed: false,
                bits: 64,
            },
            ValueType::I8 => Shape::Int {
                signed: true,
                bits: 8,
            },
            ValueType::I16 => Shape::Int {
                signed: true,
                bits: 16,
            },
            ValueType::I24 => Shape::Int {
                signed: true,
                bits: 24,
            },
            ValueType::I32 => Shape::Int {
                signed: true,
                bits: 32,
            },
            ValueType::I40 => Shape::Int {
                signed: true,
                bits: 40,
            },
            ValueType::I48 => Shape::Int {
                signed: true,
                bits: 48,
            },
            ValueType::I56 => Shape::Int {
                signed: true,
                bits: 56,
            },
            ValueType::I64 => Shape::Int {
                signed: true,
                bits: 64,
            },
            ValueType::F32 => Shape::F32,
            ValueType::F64 => Shape::F64,
            ValueType::Str => Shape::Str,
            ValueType::Bytes => Shape::Bytes,
        }
    }

    /// A correct spelling to show in error messages.
    fn example(self) -> &'static str {
        match self {
            ValueType::Bool => "true or 0",
            ValueType::U8 => "200 or 0xC8",
            ValueType::U16 => "1000 or 0x3E8",
            ValueType::U24 | ValueType::U32 | ValueType::U40 | ValueType::U48 | ValueType::U56 => {
                "100000 or 0x186A0"
            }
            ValueType::U64 => "100000 or 0xFFFFFFFFFFFFFFFF",
            ValueType::I8 => "-5 or 0x7F",
            ValueType::I16 => "-1000 or 0xFC18",
            ValueType::I24 | ValueType::I32 | ValueType::I40 | ValueType::I48 | ValueType::I56 => {
                "-100000 or 0x7FFF"
            }
            ValueType::I64 => "-100000 or 0xFFFFFFFFFFFFFFFF",
            ValueType::F32 | ValueType::F64 => "1.5 or -2.5e-3",
            ValueType::Str => "hello",
            ValueType::Bytes => "01 02 FF",
        }
    }

    fn float_max(self) -> &'static str {
        match self {
            ValueType::F32 => "3.4028235e38",
            _ => "1.7976931348623157e308",
        }
    }
}

impl fmt::Display for ValueType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Reads the short names (`u8`, `i16`, `f32`, `bool`, `str`, `hex`), the Rust-like and C-like
/// spellings (`uint8`, `int16`, `float`, `double`, `string`, `bytes`) and the CiA 301 names
/// (`UNSIGNED8`, `INTEGER16`, `REAL32`, `BOOLEAN`, `VISIBLE_STRING`, `OCTET_STRING`, `DOMAIN`),
/// ignoring case.
impl FromStr for ValueType {
    type Err = ValueError;

    fn from_str(text: &str) -> Result<ValueType, ValueError> {
        let lower = text.trim().to_ascii_lowercase();
        let unknown = || ValueError::UnknownType {
            text: text.to_owned(),
        };
        let fixed = match lower.as_str() {
            "bool" | "boolean" => Some(ValueType::Bool),
            "f32" | "real32" | "float" | "float32" => Some(ValueType::F32),
            "f64" | "real64" | "double" | "float64" => Some(ValueType::F64),
            "str" | "string" | "vis" | "visible_string" | "visiblestring" => Some(ValueType::Str),
            "hex" | "bytes" | "domain" | "octet_string" | "octetstring" => Some(ValueType::Bytes),
            _ => None,
        };
        if let Some(ty) = fixed {
            return Ok(ty);
        }
        let (signed, digits) = ["unsigned", "uint", "u"]
            .iter()
            .find_map(|prefix| lower.strip_prefix(prefix).map(|rest| (false, rest)))
            .or_else(|| {
                ["integer", "int", "i"]
                    .iter()
                    .find_map(|prefix| lower.strip_prefix(prefix).map(|rest| (true, rest)))
            })
            .ok_or_else(unknown)?;
        ValueType::ALL
            .into_iter()
            .find(|ty| match ty.shape() {
                Shape::Int { signed: s, bits } => s == signed && digits == bits.to_string(),
                _ => false,
            })
            .ok_or_else(unknown)
    }
}

impl DisplayValue {
    /// The value as an unsigned number: unsigned integers, non-negative signed ones, and bools as
    /// 0 or 1.
    pub fn as_u64(&self) -> Option<u64> {
        match *self {
            DisplayValue::Unsigned { value, .. } => Some(value),
            DisplayValue::Signed { value, .. } => u64::try_from(value).ok(),
            DisplayValue::Bool(value) => Some(u64::from(value)),
            _ => None,
        }
    }

    /// The value as a signed number: integers that fit an `i64`, and bools as 0 or 1.
    pub fn as_i64(&self) -> Option<i64> {
        match *self {
            DisplayValue::Signed { value, .. } => Some(value),
            DisplayValue::Unsigned { value, .. } => i64::try_from(value).ok(),
            DisplayValue::Bool(value) => Some(i64::from(value)),
            _ => None,
        }
    }

    /// The value as a float: REALs, and integers (rounded to the nearest `f64` above 2^53).
    pub fn as_f64(&self) -> Option<f64> {
        match *self {
            DisplayValue::Real32(value) => Some(f64::from(value)),
            DisplayValue::Real64(value) => Some(value),
            DisplayValue::Unsigned { value, .. } => Some(value as f64),
            DisplayValue::Signed { value, .. } => Some(value as f64),
            _ => None,
        }
    }

    /// The value of a BOOLEAN.
    pub fn as_bool(&self) -> Option<bool> {
        match *self {
            DisplayValue::Bool(value) => Some(value),
            _ => None,
        }
    }

    /// The text of a VISIBLE_STRING; bytes that are not UTF-8 become U+FFFD.
    pub fn as_str(&self) -> Option<Cow<'_, str>> {
        match self {
            DisplayValue::Text(bytes) => Some(String::from_utf8_lossy(bytes)),
            _ => None,
        }
    }

    /// The bytes of a VISIBLE_STRING, OCTET_STRING or DOMAIN.
    pub fn as_bytes(&self) -> Option<&[u8]> {
        match self {
            DisplayValue::Text(bytes) | DisplayValue::Bytes(bytes) => Some(bytes),
            _ => None,
        }
    }

    /// The value alone, in the form [`ValueType::parse`] reads back: `4660`, `-1`, `1.5`, `true`,
    /// the string as it is (lossy if not UTF-8), `01 02 FF`.
    pub fn plain(&self) -> String {
        match self {
            DisplayValue::Bool(value) => value.to_string(),
            DisplayValue::Unsigned { value, .. } => value.to_string(),
            DisplayValue::Signed { value, .. } => value.to_string(),
            DisplayValue::Real32(value) => {
                format_float(f64::from(*value), value.to_string(), format!("{value:e}"))
            }
            DisplayValue::Real64(value) => format_float(*value, value.to_string(), format!("{value:e}")),
            DisplayValue::Text(bytes) => String::from_utf8_lossy(bytes).into_owned(),
            DisplayValue::Bytes(bytes) => hex_bytes(bytes),
        }
    }
}

/// Shows integers both ways (`4660 (0x1234)`, `-1 (0xFFFF)` with the bit pattern of the type's
/// width), floats plainly, strings quoted with `\n`, `\"`, `\xB0`-style escapes for what is not
/// printable, bytes as hex (`01 02 FF`, `(empty)` for none).
impl fmt::Display for DisplayValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DisplayValue::Unsigned { value, bits } => {
                write!(f, "{value} (0x{value:0width$X})", width = hex_width(*bits))
            }
            DisplayValue::Signed { value, bits } => {
                let pattern = (*value as u64) & mask(*bits);
                write!(f, "{value} (0x{pattern:0width$X})", width = hex_width(*bits))
            }
            DisplayValue::Text(bytes) => write_quoted(f, bytes),
            DisplayValue::Bytes(bytes) if bytes.is_empty() => f.write_str("(empty)"),
            other => f.write_str(&other.plain()),
        }
    }
}

/// Reads an object index: hexadecimal (`1018`, `0x1018`, `1018h`) unless marked decimal (`d:4120`).
pub fn parse_index(text: &str) -> Result<u16, AddressError> {
    let error = || AddressError::Index {
        text: text.to_owned(),
    };
    let (decimal, number) = match strip_decimal_marker(text.trim()) {
        Some(rest) => (true, rest),
        None => (false, text.trim()),
    };
    address_number(number, decimal)
        .and_then(|value| u16::try_from(value).ok())
        .ok_or_else(error)
}

/// Reads a sub-index: hexadecimal (`1`, `01`, `0x1A`, `1Ah`) unless marked decimal (`d:26`).
pub fn parse_sub(text: &str) -> Result<u8, AddressError> {
    let error = || AddressError::Sub {
        text: text.to_owned(),
    };
    let (decimal, number) = match strip_decimal_marker(text.trim()) {
        Some(rest) => (true, rest),
        None => (false, text.trim()),
    };
    address_number(number, decimal)
        .and_then(|value| u8::try_from(value).ok())
        .ok_or_else(error)
}

/// Reads `index:sub` (`1018:01`, `0x1018:0x01`, `1018h:1`, `d:4120:d:1`).
pub fn parse_object(text: &str) -> Result<ObjectKey, AddressError> {
    let error = || AddressError::Object {
        text: text.to_owned(),
    };
    match address_parts(text).as_slice() {
        [(index_decimal, index), (sub_decimal, sub)] => {
            let index = address_number(index, *index_decimal).and_then(|v| u16::try_from(v).ok());
            let sub = address_number(sub, *sub_decimal).and_then(|v| u8::try_from(v).ok());
            match (index, sub) {
                (Some(index), Some(sub)) => Ok(ObjectKey::new(index, sub)),
                _ => Err(error()),
            }
        }
        _ => Err(error()),
    }
}

/// Reads a PDO mapping entry (CiA 301 §7.4.8, mapping parameter): `index:sub:bits` with index and
/// sub-index in hex and the length in decimal bits (`6000:01:8`, `6401:02:16`, `0005:00:8` for an
/// UNSIGNED8 dummy), or the 32-bit entry as the object dictionary holds it (`0x60000108`,
/// `60000108h`, `60000108`).
pub fn parse_mapping(text: &str) -> Result<MappedObject, AddressError> {
    let error = |reason| AddressError::Mapping {
        text: text.to_owned(),
        reason,
    };
    let mapped = match address_parts(text).as_slice() {
        [(decimal, entry)] => {
            let entry = address_number(entry, *decimal)
                .and_then(|v| u32::try_from(v).ok())
                .ok_or_else(|| error("not a 32-bit number"))?;
            MappedObject::from_entry(entry)
        }
        // Lengths are decimal anyway, so a `d:` before one changes nothing.
        [(index_decimal, index), (sub_decimal, sub), (_, bits)] => {
            let index = address_number(index, *index_decimal)
                .and_then(|v| u16::try_from(v).ok())
                .ok_or_else(|| error("the index is not 0000h to FFFFh"))?;
            let sub = address_number(sub, *sub_decimal)
                .and_then(|v| u8::try_from(v).ok())
                .ok_or_else(|| error("the sub-index is not 00h to FFh"))?;
            let bits = length_number(bits)
                .and_then(|v| u8::try_from(v).ok())
                .ok_or_else(|| error("the length is not a number of bits"))?;
            MappedObject { index, sub, bits }
        }
        [_, _] => return Err(error("the length in bits is missing")),
        _ => return Err(error("too many parts")),
    };
    if mapped.bits == 0 || mapped.bits > 64 {
        return Err(error("the length must be 1 to 64 bits"));
    }
    Ok(mapped)
}

#[derive(Clone, Copy)]
enum Shape {
    Bool,
    Int { signed: bool, bits: u32 },
    F32,
    F64,
    Str,
    Bytes,
}

/// The value of the low `bits` bits of a sign-extended or zero-extended field.
pub(crate) fn mask(bits: u32) -> u64 {
    match bits {
        0 => 0,
        1..=63 => (1u64 << bits) - 1,
        _ => u64::MAX,
    }
}

/// Sign-extends the low `bits` bits of `raw`.
pub(crate) fn sign_extend(raw: u64, bits: u32) -> i64 {
    match bits {
        1..=63 => {
            let shift = 64 - bits;
            ((raw << shift) as i64) >> shift
        }
        _ => raw as i64,
    }
}

/// Up to eight little-endian bytes as a number; callers check the length first.
pub(crate) fn le_u64(bytes: &[u8]) -> u64 {
    bytes
        .iter()
        .take(8)
        .rev()
        .fold(0, |acc, byte| (acc << 8) | u64::from(*byte))
}

fn hex_width(bits: u32) -> usize {
    bits.div_ceil(4).max(1) as usize
}

/// An integer as `(negative, magnitude)`, the magnitude `None` when it overflows `u128`, and whether
/// it was written as a bit pattern (hex or binary).
struct IntText {
    negative: bool,
    magnitude: Option<u128>,
    pattern: bool,
}

fn read_int_text(text: &str) -> Option<IntText> {
    let text = text.trim();
    let (negative, rest) = match text.as_bytes().first() {
        Some(b'-') => (true, &text[1..]),
        Some(b'+') => (false, &text[1..]),
        _ => (false, text),
    };
    // A trailing `h` wins over a `0b` prefix: `0B12h` is hex, and binary never ends in `h`.
    let (radix, digits) = if let Some(hex) = rest.strip_prefix("0x").or_else(|| rest.strip_prefix("0X")) {
        (16, hex)
    } else if let Some(hex) = rest.strip_suffix('h').or_else(|| rest.strip_suffix('H')) {
        (16, hex)
    } else if let Some(binary) = rest.strip_prefix("0b").or_else(|| rest.strip_prefix("0B")) {
        (2, binary)
    } else {
        (10, rest)
    };
    let digits: String = digits.chars().filter(|c| *c != '_').collect();
    if digits.is_empty() || !digits.chars().all(|c| c.is_digit(radix)) {
        return None;
    }
    Some(IntText {
        negative,
        magnitude: u128::from_str_radix(&digits, radix).ok(),
        pattern: radix != 10,
    })
}

fn parse_integer(ty: ValueType, text: &str, signed: bool, bits: u32) -> Result<Vec<u8>, ValueError> {
    let (min, max): (i128, i128) = if signed {
        (-(1i128 << (bits - 1)), (1i128 << (bits - 1)) - 1)
    } else {
        (0, (1i128 << bits) - 1)
    };
    let out_of_range = || ValueError::OutOfRange {
        text: text.to_owned(),
        ty,
        min,
        max,
    };
    let int = read_int_text(text).ok_or_else(|| ValueError::NotAnInteger {
        text: text.to_owned(),
        ty,
    })?;
    let magnitude = int
        .magnitude
        .and_then(|m| i128::try_from(m).ok())
        .ok_or_else(out_of_range)?;
    let value = if int.negative {
        -magnitude
    } else if signed && int.pattern && magnitude > max && magnitude < (1i128 << bits) {
        // An unsigned hex spelling of a negative number: the bit pattern of the type's width.
        magnitude - (1i128 << bits)
    } else {
        magnitude
    };
    if value < min || value > max {
        return Err(out_of_range());
    }
    Ok(value.to_le_bytes().into_iter().take(bits as usize / 8).collect())
}

/// A REAL parsed straight into its own width, so the shortest text of an `f32` reads back as
/// exactly that `f32` (going through `f64` could round twice).
fn parse_float<F: FloatText>(ty: ValueType, text: &str) -> Result<F, ValueError> {
    let trimmed = text.trim();
    let not_a_float = || ValueError::NotAFloat {
        text: text.to_owned(),
        ty,
    };
    let lower = trimmed.to_ascii_lowercase();
    if lower.contains("0x") {
        return Err(not_a_float());
    }
    let value: F = trimmed.parse().map_err(|_| not_a_float())?;
    if value.is_infinite() && !lower.contains("inf") {
        return Err(ValueError::FloatOutOfRange {
            text: text.to_owned(),
            ty,
        });
    }
    Ok(value)
}

trait FloatText: FromStr {
    fn is_infinite(&self) -> bool;
}

impl FloatText for f32 {
    fn is_infinite(&self) -> bool {
        f32::is_infinite(*self)
    }
}

impl FloatText for f64 {
    fn is_infinite(&self) -> bool {
        f64::is_infinite(*self)
    }
}

fn parse_hex_bytes(text: &str) -> Result<Vec<u8>, ValueError> {
    let mut bytes = Vec::new();
    for group in text.split_whitespace() {
        let digits = group
            .strip_prefix("0x")
            .or_else(|| group.strip_prefix("0X"))
            .unwrap_or(group);
        if digits.is_empty() || !digits.chars().all(|c| c.is_ascii_hexdigit()) {
            return Err(ValueError::NotHex {
                group: group.to_owned(),
            });
        }
        if !digits.len().is_multiple_of(2) {
            return Err(ValueError::OddHexDigits {
                group: group.to_owned(),
            });
        }
        for pair in digits.as_bytes().chunks(2) {
            // Both characters were checked to be ASCII hex digits above.
            let pair = std::str::from_utf8(pair).map_err(|_| ValueError::NotHex {
                group: group.to_owned(),
            })?;
            let byte = u8::from_str_radix(pair, 16).map_err(|_| ValueError::NotHex {
                group: group.to_owned(),
            })?;
            bytes.push(byte);
        }
    }
    Ok(bytes)
}

/// Floats plainly, in exponent form when plain digits would run long; both forms parse back.
fn format_float(value: f64, plain: String, exponent: String) -> String {
    let magnitude = value.abs();
    if value.is_finite() && magnitude != 0.0 && !(1e-4..1e15).contains(&magnitude) {
        exponent
    } else {
        plain
    }
}

fn hex_bytes(bytes: &[u8]) -> String {
    let hex: Vec<String> = bytes.iter().map(|byte| format!("{byte:02X}")).collect();
    hex.join(" ")
}

fn write_quoted(f: &mut fmt::Formatter<'_>, bytes: &[u8]) -> fmt::Result {
    f.write_str("\"")?;
    for chunk in bytes.utf8_chunks() {
        for c in chunk.valid().chars() {
            match c {
                '"' => f.write_str("\\\"")?,
                '\\' => f.write_str("\\\\")?,
                '\n' => f.write_str("\\n")?,
                '\r' => f.write_str("\\r")?,
                '\t' => f.write_str("\\t")?,
                '\0' => f.write_str("\\0")?,
                c if c.is_control() => {
                    let code = u32::from(c);
                    if code <= 0xFF {
                        write!(f, "\\x{code:02X}")?;
                    } else {
                        write!(f, "\\u{{{code:X}}}")?;
                    }
                }
                c => write!(f, "{c}")?,
            }
        }
        for byte in chunk.invalid() {
            write!(f, "\\x{byte:02X}")?;
        }
    }
    f.write_str("\"")
}

fn strip_decimal_marker(text: &str) -> Option<&str> {
    text.strip_prefix("d:").or_else(|| text.strip_prefix("D:"))
}

/// Splits `a:b:c` into numbers, each marked whether a `d:` before it makes it decimal. A lone `d`
/// at the end is the hex number 0Dh, since no number follows it.
fn address_parts(text: &str) -> Vec<(bool, &str)> {
    let mut parts = Vec::new();
    let mut decimal = false;
    for piece in text.trim().split(':') {
        let piece = piece.trim();
        if piece.eq_ignore_ascii_case("d") && !decimal {
            decimal = true;
            continue;
        }
        parts.push((decimal, piece));
        decimal = false;
    }
    if decimal {
        parts.push((false, "d"));
    }
    parts
}

/// A number of an object address: hex unless `decimal`; `0x` and a trailing `h` are hex either way.
fn address_number(text: &str, decimal: bool) -> Option<u64> {
    let text = text.trim();
    let (radix, digits) = if let Some(hex) = text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        (16, hex)
    } else if let Some(hex) = text.strip_suffix('h').or_else(|| text.strip_suffix('H')) {
        (16, hex)
    } else if decimal {
        (10, text)
    } else {
        (16, text)
    };
    if digits.is_empty() || !digits.chars().all(|c| c.is_digit(radix)) {
        return None;
    }
    u64::from_str_radix(digits, radix).ok()
}

/// A length in bits: decimal unless written `0x..` or `..h`.
fn length_number(text: &str) -> Option<u64> {
    address_number(text, true)
}

/// Reads an unsigned number as every canopener command takes one, and as [`ValueType::parse`] reads
/// an unsigned value: decimal unless written in hex with `0x` before it or `h` after it, or in binary
/// with `0b` (`4660`, `0x1234`, `1234h`, `0b1010`; `_` may group digits). Object indices and
/// sub-indices ([`parse_index`], [`parse_sub`]) are the other way round, hexadecimal unless marked
/// `d:`, as CANopen documents write them.
pub fn parse_number(text: &str) -> Option<u64> {
    let int = read_int_text(text)?;
    if int.negative {
        return None;
    }
    int.magnitude.and_then(|m| u64::try_from(m).ok())
}

/// An object entry as messages name it: `1018h:01`.
pub fn entry_label(index: u16, sub: u8) -> String {
    format!("{index:04X}h:{sub:02X}")
}

/// A value's little-endian bytes as one hex number, most significant first: `80000185`.
pub fn hex_value(data: &[u8]) -> String {
    data.iter().rev().map(|byte| format!("{byte:02X}")).collect()
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    fn parse(ty: ValueType, text: &str) -> Result<Vec<u8>, ValueError> {
        ty.parse(text)
    }

    fn shown(ty: ValueType, bytes: &[u8]) -> String {
        match ty.decode(bytes) {
            Ok(value) => value.to_string(),
            Err(err) => format!("error: {err}"),
        }
    }

    #[test]
    fn type_names_in_every_spelling() {
        let cases = [
            ("u8", ValueType::U8),
            ("uint8", ValueType::U8),
            ("UNSIGNED8", ValueType::U8),
            ("Unsigned16", ValueType::U16),
            ("u24", ValueType::U24),
            ("i16", ValueType::I16),
            ("int16", ValueType::I16),
            ("INTEGER16", ValueType::I16),
            ("integer64", ValueType::I64),
            ("i56", ValueType::I56),
            ("f32", ValueType::F32),
            ("real32", ValueType::F32),
            ("REAL64", ValueType::F64),
            ("double", ValueType::F64),
            ("bool", ValueType::Bool),
            ("BOOLEAN", ValueType::Bool),
            ("str", ValueType::Str),
            ("string", ValueType::Str),
            ("vis", ValueType::Str),
            ("VISIBLE_STRING", ValueType::Str),
            ("hex", ValueType::Bytes),
            ("bytes", ValueType::Bytes),
            ("domain", ValueType::Bytes),
            (" OCTET_STRING ", ValueType::Bytes),
        ];
        for (text, ty) in cases {
            assert_eq!(text.parse::<ValueType>(), Ok(ty), "{text}");
        }
        for ty in ValueType::ALL {
            assert_eq!(ty.name().parse::<ValueType>(), Ok(ty));
            assert_eq!(ty.data_type().name().map(str::parse::<ValueType>), Some(Ok(ty)));
        }
        for bad in ["u7", "u", "i128", "uint", "text", "", "f16", "u08"] {
            let err = bad.parse::<ValueType>().unwrap_err();
            assert!(err.to_string().contains("use bool, u8..u64"), "{bad}: {err}");
        }
    }

    #[test]
    fn types_of_cia_301_basic_data_types() {
        assert_eq!(
            ValueType::from_data_type(DataType::UNSIGNED16),
            Some(ValueType::U16)
        );
        assert_eq!(
            ValueType::from_data_type(DataType::INTEGER24),
            Some(ValueType::I24)
        );
        assert_eq!(ValueType::from_data_type(DataType::REAL64), Some(ValueType::F64));
        assert_eq!(
            ValueType::from_data_type(DataType::BOOLEAN),
            Some(ValueType::Bool)
        );
        assert_eq!(
            ValueType::from_data_type(DataType::VISIBLE_STRING),
            Some(ValueType::Str)
        );
        assert_eq!(
            ValueType::from_data_type(DataType::OCTET_STRING),
            Some(ValueType::Bytes)
        );
        assert_eq!(
            ValueType::from_data_type(DataType::DOMAIN),
            Some(ValueType::Bytes)
        );
        assert_eq!(ValueType::from_data_type(DataType::UNICODE_STRING), None);
        assert_eq!(ValueType::from_data_type(DataType::TIME_OF_DAY), None);
        assert_eq!(ValueType::from_data_type(DataType::PDO_MAPPING), None);
        for ty in ValueType::ALL {
            assert_eq!(ValueType::from_data_type(ty.data_type()), Some(ty), "{ty}");
            assert_eq!(ty.byte_len(), ty.data_type().byte_size(), "{ty}");
        }
    }

    #[test]
    fn integers_decimal_hex_binary() {
        assert_eq!(parse(ValueType::U16, "1000"), Ok(vec![0xE8, 0x03]));
        assert_eq!(parse(ValueType::U16, "0x3E8"), Ok(vec![0xE8, 0x03]));
        assert_eq!(parse(ValueType::U16, "3E8h"), Ok(vec![0xE8, 0x03]));
        assert_eq!(parse(ValueType::U16, "0X3e8"), Ok(vec![0xE8, 0x03]));
        assert_eq!(parse(ValueType::U8, "0b1010_0101"), Ok(vec![0xA5]));
        assert_eq!(
            parse(ValueType::U32, " 1_000_000 "),
            Ok(1_000_000u32.to_le_bytes().to_vec())
        );
        assert_eq!(parse(ValueType::U8, "+7"), Ok(vec![7]));
        // A trailing `h` wins over a `0b` prefix.
        assert_eq!(parse(ValueType::U16, "0B12h"), Ok(vec![0x12, 0x0B]));
        assert_eq!(parse(ValueType::I8, "-5"), Ok(vec![0xFB]));
        assert_eq!(parse(ValueType::U24, "0x123456"), Ok(vec![0x56, 0x34, 0x12]));
        assert_eq!(
            parse(ValueType::U40, "0x0102030405"),
            Ok(vec![0x05, 0x04, 0x03, 0x02, 0x01])
        );
    }

    #[test]
    fn negative_hex_is_a_magnitude_and_unsigned_hex_a_bit_pattern() {
        assert_eq!(
            parse(ValueType::I16, "-0x10"),
            Ok((-16i16).to_le_bytes().to_vec())
        );
        assert_eq!(
            parse(ValueType::I16, "0xFFFF"),
            Ok((-1i16).to_le_bytes().to_vec())
        );
        assert_eq!(
            parse(ValueType::I16, "0x8000"),
            Ok(i16::MIN.to_le_bytes().to_vec())
        );
        assert_eq!(
            parse(ValueType::I16, "-0x8000"),
            Ok(i16::MIN.to_le_bytes().to_vec())
        );
        assert_eq!(parse(ValueType::I24, "0xFFFFFF"), Ok(vec![0xFF, 0xFF, 0xFF]));
        assert!(matches!(
            parse(ValueType::I16, "-0x8001"),
            Err(ValueError::OutOfRange { .. })
        ));
        assert!(matches!(
            parse(ValueType::I16, "0x10000"),
            Err(ValueError::OutOfRange { .. })
        ));
        // Decimal is never a bit pattern.
        assert!(matches!(
            parse(ValueType::I16, "65535"),
            Err(ValueError::OutOfRange { .. })
        ));
        assert!(matches!(
            parse(ValueType::U16, "-0x1"),
            Err(ValueError::OutOfRange { .. })
        ));
    }

    #[test]
    fn min_and_max_of_every_integer_type() {
        for ty in ValueType::ALL {
            let Shape::Int { signed, bits } = ty.shape() else {
                continue;
            };
            let (min, max) = if signed {
                (-(1i128 << (bits - 1)), (1i128 << (bits - 1)) - 1)
            } else {
                (0, (1i128 << bits) - 1)
            };
            let len = bits as usize / 8;
            assert_eq!(
                parse(ty, &min.to_string()),
                Ok(min.to_le_bytes()[..len].to_vec()),
                "{ty} min"
            );
            assert_eq!(
                parse(ty, &max.to_string()),
                Ok(max.to_le_bytes()[..len].to_vec()),
                "{ty} max"
            );
            for beyond in [min - 1, max + 1] {
                let err = parse(ty, &beyond.to_string()).unwrap_err();
                assert_eq!(
                    err,
                    ValueError::OutOfRange {
                        text: beyond.to_string(),
                        ty,
                        min,
                        max
                    },
                    "{ty}"
                );
                let message = err.to_string();
                assert!(message.contains(&format!("({min} to {max})")), "{message}");
                assert!(message.contains("e.g."), "{message}");
            }
            let min_value = ty.decode(&min.to_le_bytes()[..len]).unwrap();
            let max_value = ty.decode(&max.to_le_bytes()[..len]).unwrap();
            assert_eq!(
                min_value
                    .as_i64()
                    .map(i128::from)
                    .or(min_value.as_u64().map(i128::from)),
                Some(min)
            );
            assert_eq!(
                max_value
                    .as_u64()
                    .map(i128::from)
                    .or(max_value.as_i64().map(i128::from)),
                Some(max)
            );
        }
    }

    #[test]
    fn sixty_four_bit_values() {
        assert_eq!(parse(ValueType::U64, "18446744073709551615"), Ok(vec![0xFF; 8]));
        assert_eq!(parse(ValueType::U64, "0xFFFFFFFFFFFFFFFF"), Ok(vec![0xFF; 8]));
        assert_eq!(
            parse(ValueType::I64, "-9223372036854775808"),
            Ok(i64::MIN.to_le_bytes().to_vec())
        );
        assert_eq!(
            parse(ValueType::I64, "0x8000000000000000"),
            Ok(i64::MIN.to_le_bytes().to_vec())
        );
        assert_eq!(
            shown(ValueType::U64, &[0xFF; 8]),
            "18446744073709551615 (0xFFFFFFFFFFFFFFFF)"
        );
        assert_eq!(
            shown(ValueType::I64, &i64::MIN.to_le_bytes()),
            "-9223372036854775808 (0x8000000000000000)"
        );
        // Far beyond u128 still reads as out of range, not as garbage.
        let huge = "9".repeat(60);
        assert!(matches!(
            parse(ValueType::U64, &huge),
            Err(ValueError::OutOfRange { .. })
        ));
        assert!(matches!(
            parse(ValueType::I64, &format!("-{huge}")),
            Err(ValueError::OutOfRange { .. })
        ));
    }

    #[test]
    fn integer_typos_are_not_numbers() {
        for bad in [
            "", "  ", "12a", "0x", "h", "0xG1", "1.5", "--1", "0b102", "1 000", "-",
        ] {
            let err = parse(ValueType::U16, bad).unwrap_err();
            assert_eq!(
                err,
                ValueError::NotAnInteger {
                    text: bad.to_owned(),
                    ty: ValueType::U16
                },
                "{bad:?}"
            );
            assert!(err.to_string().contains("1000 or 0x3E8"), "{err}");
        }
    }

    #[test]
    fn floats() {
        assert_eq!(parse(ValueType::F32, "1.5"), Ok(1.5f32.to_le_bytes().to_vec()));
        assert_eq!(
            parse(ValueType::F64, "-2.5e-3"),
            Ok((-2.5e-3f64).to_le_bytes().to_vec())
        );
        assert_eq!(
            parse(ValueType::F32, "inf"),
            Ok(f32::INFINITY.to_le_bytes().to_vec())
        );
        assert_eq!(
            parse(ValueType::F64, "-infinity"),
            Ok(f64::NEG_INFINITY.to_le_bytes().to_vec())
        );
        let nan = parse(ValueType::F32, "NaN").unwrap();
        assert!(f32::from_le_bytes(nan.try_into().unwrap()).is_nan());
        assert_eq!(
            parse(ValueType::F32, "1e39"),
            Err(ValueError::FloatOutOfRange {
                text: "1e39".to_owned(),
                ty: ValueType::F32
            })
        );
        assert!(
            parse(ValueType::F32, "1e39")
                .unwrap_err()
                .to_string()
                .contains("3.4028235e38")
        );
        assert_eq!(parse(ValueType::F64, "1e39"), Ok(1e39f64.to_le_bytes().to_vec()));
        assert!(matches!(
            parse(ValueType::F64, "1e309"),
            Err(ValueError::FloatOutOfRange { .. })
        ));
        for bad in ["0x3F800000", "one", "", "1,5"] {
            assert!(
                matches!(parse(ValueType::F32, bad), Err(ValueError::NotAFloat { .. })),
                "{bad}"
            );
        }
        assert_eq!(shown(ValueType::F32, &1.5f32.to_le_bytes()), "1.5");
        assert_eq!(shown(ValueType::F64, &f64::NAN.to_le_bytes()), "NaN");
        assert_eq!(shown(ValueType::F32, &f32::NEG_INFINITY.to_le_bytes()), "-inf");
        assert_eq!(shown(ValueType::F32, &f32::MAX.to_le_bytes()), "3.4028235e38");
        assert_eq!(shown(ValueType::F64, &1e-7f64.to_le_bytes()), "1e-7");
        assert_eq!(shown(ValueType::F64, &0.0f64.to_le_bytes()), "0");
        assert_eq!(shown(ValueType::F64, &0.001f64.to_le_bytes()), "0.001");
    }

    #[test]
    fn nan_and_extremes_survive_text() {
        for value in [f32::NAN, f32::MIN_POSITIVE, f32::MAX, -0.0, 1e-45, f32::INFINITY] {
            let decoded = ValueType::F32.decode(&value.to_le_bytes()).unwrap();
            let back = ValueType::F32.parse(&decoded.plain()).unwrap();
            let back = f32::from_le_bytes(back.try_into().unwrap());
            assert!(back == value || (back.is_nan() && value.is_nan()), "{value}");
            assert_eq!(back.is_sign_negative(), value.is_sign_negative(), "{value}");
        }
    }

    #[test]
    fn bools() {
        for (text, byte) in [
            ("true", 1),
            ("TRUE", 1),
            ("1", 1),
            ("false", 0),
            (" False ", 0),
            ("0", 0),
        ] {
            assert_eq!(parse(ValueType::Bool, text), Ok(vec![byte]), "{text}");
        }
        for bad in ["yes", "2", "", "tru"] {
            let err = parse(ValueType::Bool, bad).unwrap_err();
            assert!(err.to_string().contains("true, false, 1 or 0"), "{err}");
        }
        assert_eq!(shown(ValueType::Bool, &[1]), "true");
        assert_eq!(shown(ValueType::Bool, &[0]), "false");
        assert_eq!(
            ValueType::Bool.decode(&[2]),
            Err(ValueError::NotBoolean { byte: 2 })
        );
        assert_eq!(
            shown(ValueType::Bool, &[2]),
            "error: 0x02 is not a BOOLEAN (0 = false, 1 = true)"
        );
        assert_eq!(ValueType::Bool.decode(&[1]).unwrap().as_u64(), Some(1));
    }

    #[test]
    fn strings_as_is_and_shown_quoted_with_escapes() {
        assert_eq!(parse(ValueType::Str, "Fixture IO"), Ok(b"Fixture IO".to_vec()));
        assert_eq!(parse(ValueType::Str, " padded "), Ok(b" padded ".to_vec()));
        assert_eq!(parse(ValueType::Str, "°C"), Ok("°C".as_bytes().to_vec()));
        assert_eq!(parse(ValueType::Str, ""), Ok(Vec::new()));
        assert_eq!(shown(ValueType::Str, b"ab\"c\\"), r#""ab\"c\\""#);
        assert_eq!(shown(ValueType::Str, b"v1\0\0"), r#""v1\0\0""#);
        assert_eq!(shown(ValueType::Str, b"a\nb\tc\r\x07"), r#""a\nb\tc\r\x07""#);
        assert_eq!(shown(ValueType::Str, "25°C".as_bytes()), "\"25°C\"");
        // Latin-1 degree sign, not UTF-8.
        assert_eq!(shown(ValueType::Str, b"25\xB0C"), r#""25\xB0C""#);
        assert_eq!(shown(ValueType::Str, "\u{85}".as_bytes()), r#""\x85""#);
        assert_eq!(shown(ValueType::Str, b""), r#""""#);
        let value = ValueType::Str.decode(b"25\xB0C").unwrap();
        assert_eq!(value.as_str().as_deref(), Some("25\u{FFFD}C"));
        assert_eq!(value.as_bytes(), Some(&b"25\xB0C"[..]));
        assert_eq!(value.as_u64(), None);
    }

    #[test]
    fn hex_bytes() {
        assert_eq!(parse(ValueType::Bytes, "01 02 ff"), Ok(vec![1, 2, 0xFF]));
        assert_eq!(parse(ValueType::Bytes, "0102ff"), Ok(vec![1, 2, 0xFF]));
        assert_eq!(parse(ValueType::Bytes, "0x0102 FF"), Ok(vec![1, 2, 0xFF]));
        assert_eq!(parse(ValueType::Bytes, "  "), Ok(Vec::new()));
        assert_eq!(
            parse(ValueType::Bytes, "01 2 03"),
            Err(ValueError::OddHexDigits {
                group: "2".to_owned()
            })
        );
        assert_eq!(
            parse(ValueType::Bytes, "0102f"),
            Err(ValueError::OddHexDigits {
                group: "0102f".to_owned()
            })
        );
        assert_eq!(
            parse(ValueType::Bytes, "01 zz"),
            Err(ValueError::NotHex {
                group: "zz".to_owned()
            })
        );
        assert_eq!(
            parse(ValueType::Bytes, "0x"),
            Err(ValueError::NotHex {
                group: "0x".to_owned()
            })
        );
        assert_eq!(
            parse(ValueType::Bytes, "é1"),
            Err(ValueError::NotHex {
                group: "é1".to_owned()
            })
        );
        assert!(
            parse(ValueType::Bytes, "123")
                .unwrap_err()
                .to_string()
                .contains("two digits per byte, like 01 02 0F")
        );
        assert_eq!(shown(ValueType::Bytes, &[1, 2, 0xFF]), "01 02 FF");
        assert_eq!(shown(ValueType::Bytes, &[]), "(empty)");
        let long: Vec<u8> = (0..=255).collect();
        let value = ValueType::Bytes.decode(&long).unwrap();
        assert_eq!(ValueType::Bytes.parse(&value.plain()), Ok(long));
    }

    #[test]
    fn integers_shown_both_ways() {
        assert_eq!(shown(ValueType::U16, &[0x34, 0x12]), "4660 (0x1234)");
        assert_eq!(shown(ValueType::I16, &[0xFF, 0xFF]), "-1 (0xFFFF)");
        assert_eq!(shown(ValueType::U8, &[5]), "5 (0x05)");
        assert_eq!(shown(ValueType::U32, &[1, 0, 0, 0]), "1 (0x00000001)");
        assert_eq!(shown(ValueType::I24, &[0, 0, 0x80]), "-8388608 (0x800000)");
        assert_eq!(shown(ValueType::I8, &[0x7F]), "127 (0x7F)");
        assert_eq!(
            DisplayValue::Unsigned { value: 1, bits: 1 }.to_string(),
            "1 (0x1)"
        );
        assert_eq!(
            DisplayValue::Signed { value: -3, bits: 7 }.to_string(),
            "-3 (0x7D)"
        );
    }

    #[test]
    fn wrong_lengths_are_reported() {
        assert_eq!(
            ValueType::U16.decode(&[1, 2, 3]),
            Err(ValueError::WrongLength {
                ty: ValueType::U16,
                expected: 2,
                got: 3
            })
        );
        assert_eq!(shown(ValueType::U32, &[1]), "error: u32 takes 4 byte(s), got 1");
        assert_eq!(shown(ValueType::Bool, &[]), "error: bool takes 1 byte(s), got 0");
        assert_eq!(
            shown(ValueType::F64, &[0; 9]),
            "error: f64 takes 8 byte(s), got 9"
        );
        assert!(ValueType::Bytes.decode(&[0; 300]).is_ok());
    }

    #[test]
    fn accessors() {
        let unsigned = ValueType::U64.decode(&[0xFF; 8]).unwrap();
        assert_eq!(unsigned.as_u64(), Some(u64::MAX));
        assert_eq!(unsigned.as_i64(), None);
        assert_eq!(unsigned.as_f64(), Some(1.8446744073709552e19));
        let signed = ValueType::I8.decode(&[0xFE]).unwrap();
        assert_eq!(signed.as_i64(), Some(-2));
        assert_eq!(signed.as_u64(), None);
        assert_eq!(signed.as_f64(), Some(-2.0));
        assert_eq!(signed.as_bool(), None);
        let real = ValueType::F32.decode(&0.5f32.to_le_bytes()).unwrap();
        assert_eq!(
            (real.as_f64(), real.as_u64(), real.as_str()),
            (Some(0.5), None, None)
        );
        let bytes = ValueType::Bytes.decode(&[9]).unwrap();
        assert_eq!((bytes.as_bytes(), bytes.as_str()), (Some(&[9u8][..]), None));
        assert_eq!(ValueType::Bool.decode(&[1]).unwrap().as_bool(), Some(true));
    }

    #[test]
    fn indices_and_sub_indices() {
        for text in ["0x1018", "1018h", "1018", "1018H", " 0X1018 ", "d:4120", "D:4120"] {
            assert_eq!(parse_index(text), Ok(0x1018), "{text}");
        }
        assert_eq!(parse_index("A00"), Ok(0x0A00));
        assert_eq!(parse_index("FFFF"), Ok(0xFFFF));
        for bad in ["10000", "x", "", "d:65536", "d:1A", "-1", "0x", "h"] {
            let err = parse_index(bad).unwrap_err();
            assert!(
                err.to_string().contains("like 1018, 0x1018 or 1018h"),
                "{bad}: {err}"
            );
        }
        for (text, sub) in [
            ("1", 1),
            ("01", 1),
            ("0x01", 1),
            ("01h", 1),
            ("1A", 0x1A),
            ("d:26", 26),
            ("FF", 255),
        ] {
            assert_eq!(parse_sub(text), Ok(sub), "{text}");
        }
        for bad in ["100", "d:256", "", "g"] {
            let err = parse_sub(bad).unwrap_err();
            assert!(err.to_string().contains("like 01, 0x1A or 1Ah"), "{bad}: {err}");
        }
    }

    #[test]
    fn object_addresses() {
        assert_eq!(parse_object("1018:01"), Ok(ObjectKey::new(0x1018, 1)));
        assert_eq!(parse_object("0x1018:0x04"), Ok(ObjectKey::new(0x1018, 4)));
        assert_eq!(parse_object("1018h:1Ah"), Ok(ObjectKey::new(0x1018, 0x1A)));
        assert_eq!(parse_object("d:4120:d:10"), Ok(ObjectKey::new(0x1018, 10)));
        assert_eq!(parse_object("1A00:10"), Ok(ObjectKey::new(0x1A00, 0x10)));
        assert_eq!(parse_object("1018:d"), Ok(ObjectKey::new(0x1018, 0x0D)));
        for bad in [
            "1018",
            "1018:",
            ":01",
            "1018:01:02",
            "10000:01",
            "1018:100",
            "d:",
            "1018:d:",
            "",
        ] {
            let err = parse_object(bad).unwrap_err();
            assert_eq!(err, AddressError::Object { text: bad.to_owned() });
            assert!(err.to_string().contains("like 1018:01"), "{err}");
        }
    }

    #[test]
    fn mapping_entries() {
        let entry = |index, sub, bits| MappedObject { index, sub, bits };
        assert_eq!(parse_mapping("6000:01:8"), Ok(entry(0x6000, 1, 8)));
        assert_eq!(parse_mapping("6401:02:16"), Ok(entry(0x6401, 2, 16)));
        assert_eq!(parse_mapping("0005:00:8"), Ok(entry(5, 0, 8)));
        assert_eq!(parse_mapping("6000:01:0x10"), Ok(entry(0x6000, 1, 16)));
        assert_eq!(parse_mapping("6000:01:10h"), Ok(entry(0x6000, 1, 16)));
        assert_eq!(parse_mapping("6000:01:d:1"), Ok(entry(0x6000, 1, 1)));
        assert_eq!(parse_mapping("0x60000108"), Ok(entry(0x6000, 1, 8)));
        assert_eq!(parse_mapping("60000108h"), Ok(entry(0x6000, 1, 8)));
        assert_eq!(parse_mapping("60000108"), Ok(entry(0x6000, 1, 8)));
        assert_eq!(
            parse_mapping("64"),
            Err(AddressError::Mapping {
                text: "64".to_owned(),
                reason: "the length must be 1 to 64 bits"
            })
        );
        let reason = |text: &str| match parse_mapping(text) {
            Err(AddressError::Mapping { reason, .. }) => reason,
            other => panic!("{text}: {other:?}"),
        };
        assert_eq!(reason("6000:01"), "the length in bits is missing");
        assert_eq!(reason("6000:01:0"), "the length must be 1 to 64 bits");
        assert_eq!(reason("6000:01:65"), "the length must be 1 to 64 bits");
        assert_eq!(reason("6000:01:300"), "the length is not a number of bits");
        assert_eq!(reason("6000:01:8:1"), "too many parts");
        assert_eq!(reason("16000:01:8"), "the index is not 0000h to FFFFh");
        assert_eq!(reason("6000:100:8"), "the sub-index is not 00h to FFh");
        assert_eq!(reason("160000108"), "not a 32-bit number");
        assert_eq!(reason("6000:01:d:"), "the length is not a number of bits");
        let message = parse_mapping("6000:01").unwrap_err().to_string();
        assert!(
            message.contains("like 6000:01:8") && message.contains("0x60000108"),
            "{message}"
        );
    }

    fn integer_types() -> impl Strategy<Value = ValueType> {
        prop::sample::select(
            ValueType::ALL
                .into_iter()
                .filter(|ty| matches!(ty.shape(), Shape::Int { .. }))
                .collect::<Vec<_>>(),
        )
    }

    proptest! {
        #[test]
        fn integers_round_trip_through_text(ty in integer_types(), seed in any::<u64>()) {
            let Shape::Int { signed, bits } = ty.shape() else { unreachable!() };
            let raw = seed & mask(bits);
            let bytes = raw.to_le_bytes()[..bits as usize / 8].to_vec();
            let value = ty.decode(&bytes).unwrap();
            prop_assert_eq!(ty.parse(&value.plain()), Ok(bytes.clone()));
            // The hex half of the two-way form reads back too.
            let shown = value.to_string();
            let hex = shown.split_once("(0x").map(|(_, rest)| rest.trim_end_matches(')')).unwrap();
            prop_assert_eq!(ty.parse(&format!("0x{hex}")), Ok(bytes.clone()));
            prop_assert_eq!(ty.parse(&format!("{hex}h")), Ok(bytes.clone()));
            if signed {
                let number = value.as_i64().unwrap();
                prop_assert_eq!(number, sign_extend(raw, bits));
                if number < 0 {
                    let magnitude = format!("-0x{:X}", number.unsigned_abs());
                    prop_assert_eq!(ty.parse(&magnitude), Ok(bytes));
                }
            } else {
                prop_assert_eq!(value.as_u64(), Some(raw));
            }
        }

        #[test]
        fn floats_round_trip_through_text(bits in any::<u64>()) {
            let value = f64::from_bits(bits);
            let decoded = ValueType::F64.decode(&value.to_le_bytes()).unwrap();
            let back = f64::from_le_bytes(ValueType::F64.parse(&decoded.plain()).unwrap().try_into().unwrap());
            prop_assert!(back == value || (back.is_nan() && value.is_nan()));
            let narrow = f32::from_bits(bits as u32);
            let decoded = ValueType::F32.decode(&narrow.to_le_bytes()).unwrap();
            let back = f32::from_le_bytes(ValueType::F32.parse(&decoded.plain()).unwrap().try_into().unwrap());
            prop_assert!(back == narrow || (back.is_nan() && narrow.is_nan()));
        }

        #[test]
        fn text_never_panics(text in ".{0,24}", ty_idx in 0..ValueType::ALL.len()) {
            let ty = ValueType::ALL[ty_idx];
            if let Ok(bytes) = ty.parse(&text) {
                prop_assert!(ty.decode(&bytes).is_ok());
            }
            let _ = parse_mapping(&text);
            let _ = parse_object(&text);
        }

        #[test]
        fn bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..12), ty_idx in 0..ValueType::ALL.len()) {
            let ty = ValueType::ALL[ty_idx];
            if let Ok(value) = ty.decode(&bytes) {
                let shown = value.to_string();
                prop_assert!(!shown.is_empty());
                prop_assert!(ty.parse(&value.plain()).is_ok());
            }
        }
    }
}

//! Data type indices of the object dictionary (CiA 301 §7.4.7, the static data types at 0001h–001Bh).
//!
//! A data type is identified by the index of its definition in the object dictionary. Every value
//! is stored as the little-endian bytes CiA 301 §7.1 defines for the type, which is also how SDO
//! and PDO carry it.

use std::fmt;

/// The index of an object dictionary data type, e.g. [`DataType::UNSIGNED16`] = `0x0006`.
///
/// Any number is a valid `DataType`: indices outside the CiA 301 basic types (complex types such as
/// `0x0020` PDO_COMMUNICATION_PARAMETER, manufacturer- or profile-specific types) are kept as they
/// are and treated as opaque byte strings of fixed length.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct DataType(pub u16);

/// What values of a data type look like, for code that reads or writes them as text.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TypeKind {
    /// BOOLEAN.
    Boolean,
    /// INTEGERn with n bits.
    Signed(u32),
    /// UNSIGNEDn with n bits.
    Unsigned(u32),
    /// REAL32.
    Real32,
    /// REAL64.
    Real64,
    /// VISIBLE_STRING.
    VisibleString,
    /// OCTET_STRING.
    OctetString,
    /// UNICODE_STRING.
    UnicodeString,
    /// TIME_OF_DAY (48 bits: milliseconds after midnight, days since 1984-01-01).
    TimeOfDay,
    /// TIME_DIFFERENCE (48 bits: milliseconds and days).
    TimeDifference,
    /// DOMAIN (arbitrary bytes).
    Domain,
    /// A record type definition 0020h–0023h (PDO_COMMUNICATION_PARAMETER ... IDENTITY), not a value type.
    Structure,
}

/// How a numeric type's bytes are read for limit checks.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum NumericKind {
    Signed,
    Unsigned,
    Real,
}

impl DataType {
    /// PDO_COMMUNICATION_PARAMETER record definition (CiA 301 §7.4.8).
    pub const PDO_COMMUNICATION_PARAMETER: DataType = DataType(0x0020);
    /// PDO_MAPPING record definition.
    pub const PDO_MAPPING: DataType = DataType(0x0021);
    /// SDO_PARAMETER record definition.
    pub const SDO_PARAMETER: DataType = DataType(0x0022);
    /// IDENTITY record definition.
    pub const IDENTITY: DataType = DataType(0x0023);
    /// BOOLEAN: one bit, carried in one byte (0 = false, 1 = true).
    pub const BOOLEAN: DataType = DataType(0x0001);
    /// INTEGER8: two's complement, 8 bits.
    pub const INTEGER8: DataType = DataType(0x0002);
    /// INTEGER16: two's complement, 16 bits.
    pub const INTEGER16: DataType = DataType(0x0003);
    /// INTEGER32: two's complement, 32 bits.
    pub const INTEGER32: DataType = DataType(0x0004);
    /// UNSIGNED8.
    pub const UNSIGNED8: DataType = DataType(0x0005);
    /// UNSIGNED16.
    pub const UNSIGNED16: DataType = DataType(0x0006);
    /// UNSIGNED32.
    pub const UNSIGNED32: DataType = DataType(0x0007);
    /// REAL32: IEEE 754 single precision.
    pub const REAL32: DataType = DataType(0x0008);
    /// VISIBLE_STRING: ISO 646 characters, variable length.
    pub const VISIBLE_STRING: DataType = DataType(0x0009);
    /// OCTET_STRING: bytes, variable length.
    pub const OCTET_STRING: DataType = DataType(0x000A);
    /// UNICODE_STRING: 16-bit code units, variable length.
    pub const UNICODE_STRING: DataType = DataType(0x000B);
    /// TIME_OF_DAY: milliseconds after midnight (28 bits, 4 reserved) and days since 1984-01-01 (16 bits).
    pub const TIME_OF_DAY: DataType = DataType(0x000C);
    /// TIME_DIFFERENCE: the same 48-bit layout as TIME_OF_DAY, read as a duration.
    pub const TIME_DIFFERENCE: DataType = DataType(0x000D);
    /// DOMAIN: an application-specific block of bytes of any length.
    pub const DOMAIN: DataType = DataType(0x000F);
    /// INTEGER24.
    pub const INTEGER24: DataType = DataType(0x0010);
    /// REAL64: IEEE 754 double precision.
    pub const REAL64: DataType = DataType(0x0011);
    /// INTEGER40.
    pub const INTEGER40: DataType = DataType(0x0012);
    /// INTEGER48.
    pub const INTEGER48: DataType = DataType(0x0013);
    /// INTEGER56.
    pub const INTEGER56: DataType = DataType(0x0014);
    /// INTEGER64.
    pub const INTEGER64: DataType = DataType(0x0015);
    /// UNSIGNED24.
    pub const UNSIGNED24: DataType = DataType(0x0016);
    /// UNSIGNED40.
    pub const UNSIGNED40: DataType = DataType(0x0018);
    /// UNSIGNED48.
    pub const UNSIGNED48: DataType = DataType(0x0019);
    /// UNSIGNED56.
    pub const UNSIGNED56: DataType = DataType(0x001A);
    /// UNSIGNED64.
    pub const UNSIGNED64: DataType = DataType(0x001B);

    /// Every basic type this crate knows, in index order.
    pub const BASIC: [DataType; 25] = [
        DataType::BOOLEAN,
        DataType::INTEGER8,
        DataType::INTEGER16,
        DataType::INTEGER32,
        DataType::UNSIGNED8,
        DataType::UNSIGNED16,
        DataType::UNSIGNED32,
        DataType::REAL32,
        DataType::VISIBLE_STRING,
        DataType::OCTET_STRING,
        DataType::UNICODE_STRING,
        DataType::TIME_OF_DAY,
        DataType::TIME_DIFFERENCE,
        DataType::DOMAIN,
        DataType::INTEGER24,
        DataType::REAL64,
        DataType::INTEGER40,
        DataType::INTEGER48,
        DataType::INTEGER56,
        DataType::INTEGER64,
        DataType::UNSIGNED24,
        DataType::UNSIGNED40,
        DataType::UNSIGNED48,
        DataType::UNSIGNED56,
        DataType::UNSIGNED64,
    ];

    /// The kind of a standard data type (CiA 301 §7.4.7.1 table 44); `None` for other indices.
    pub const fn kind(self) -> Option<TypeKind> {
        Some(match self {
            DataType::BOOLEAN => TypeKind::Boolean,
            DataType::REAL32 => TypeKind::Real32,
            DataType::REAL64 => TypeKind::Real64,
            DataType::VISIBLE_STRING => TypeKind::VisibleString,
            DataType::OCTET_STRING => TypeKind::OctetString,
            DataType::UNICODE_STRING => TypeKind::UnicodeString,
            DataType::TIME_OF_DAY => TypeKind::TimeOfDay,
            DataType::TIME_DIFFERENCE => TypeKind::TimeDifference,
            DataType::DOMAIN => TypeKind::Domain,
            DataType(0x0020..=0x0023) => TypeKind::Structure,
            _ => match (self.numeric_kind(), self.bit_size()) {
                (Some(NumericKind::Signed), Some(bits)) => TypeKind::Signed(bits),
                (Some(NumericKind::Unsigned), Some(bits)) => TypeKind::Unsigned(bits),
                _ => return None,
            },
        })
    }

    /// Whether values are integers (INTEGERn, UNSIGNEDn): the only types a `$NODEID` formula may describe.
    pub const fn is_integer(self) -> bool {
        matches!(
            self.numeric_kind(),
            Some(NumericKind::Signed | NumericKind::Unsigned)
        )
    }

    /// The size of a value in bits, or `None` for the variable-length types (strings, DOMAIN) and
    /// for indices that are not basic types.
    ///
    /// This is the length a PDO mapping entry gives; BOOLEAN is 1 bit there.
    pub const fn bit_size(self) -> Option<u32> {
        match self {
            DataType::BOOLEAN => Some(1),
            DataType::INTEGER8 | DataType::UNSIGNED8 => Some(8),
            DataType::INTEGER16 | DataType::UNSIGNED16 => Some(16),
            DataType::INTEGER24 | DataType::UNSIGNED24 => Some(24),
            DataType::INTEGER32 | DataType::UNSIGNED32 | DataType::REAL32 => Some(32),
            DataType::INTEGER40 | DataType::UNSIGNED40 => Some(40),
            DataType::INTEGER48 | DataType::UNSIGNED48 => Some(48),
            DataType::TIME_OF_DAY | DataType::TIME_DIFFERENCE => Some(48),
            DataType::INTEGER56 | DataType::UNSIGNED56 => Some(56),
            DataType::INTEGER64 | DataType::UNSIGNED64 | DataType::REAL64 => Some(64),
            _ => None,
        }
    }

    /// The number of bytes an SDO transfers for a value: [`bit_size`](DataType::bit_size) rounded
    /// up to whole bytes, so BOOLEAN takes one byte.
    pub const fn byte_size(self) -> Option<usize> {
        match self.bit_size() {
            Some(bits) => Some(bits.div_ceil(8) as usize),
            None => None,
        }
    }

    /// Whether values of this type may change length: VISIBLE_STRING, OCTET_STRING, UNICODE_STRING
    /// and DOMAIN.
    pub const fn is_variable_length(self) -> bool {
        matches!(
            self,
            DataType::VISIBLE_STRING | DataType::OCTET_STRING | DataType::UNICODE_STRING | DataType::DOMAIN
        )
    }

    /// Whether the type is an integer (INTEGERn, UNSIGNEDn) or REAL type, the types that take
    /// `LowLimit` and `HighLimit`.
    pub const fn is_numeric(self) -> bool {
        self.numeric_kind().is_some()
    }

    /// The CiA 301 name, e.g. `"UNSIGNED16"`, or `None` for indices that are not basic types.
    pub const fn name(self) -> Option<&'static str> {
        Some(match self {
            DataType::BOOLEAN => "BOOLEAN",
            DataType::INTEGER8 => "INTEGER8",
            DataType::INTEGER16 => "INTEGER16",
            DataType::INTEGER32 => "INTEGER32",
            DataType::UNSIGNED8 => "UNSIGNED8",
            DataType::UNSIGNED16 => "UNSIGNED16",
            DataType::UNSIGNED32 => "UNSIGNED32",
            DataType::REAL32 => "REAL32",
            DataType::VISIBLE_STRING => "VISIBLE_STRING",
            DataType::OCTET_STRING => "OCTET_STRING",
            DataType::UNICODE_STRING => "UNICODE_STRING",
            DataType::TIME_OF_DAY => "TIME_OF_DAY",
            DataType::TIME_DIFFERENCE => "TIME_DIFFERENCE",
            DataType::DOMAIN => "DOMAIN",
            DataType::INTEGER24 => "INTEGER24",
            DataType::REAL64 => "REAL64",
            DataType::INTEGER40 => "INTEGER40",
            DataType::INTEGER48 => "INTEGER48",
            DataType::INTEGER56 => "INTEGER56",
            DataType::INTEGER64 => "INTEGER64",
            DataType::UNSIGNED24 => "UNSIGNED24",
            DataType::UNSIGNED40 => "UNSIGNED40",
            DataType::UNSIGNED48 => "UNSIGNED48",
            DataType::UNSIGNED56 => "UNSIGNED56",
            DataType::UNSIGNED64 => "UNSIGNED64",
            _ => return None,
        })
    }

    pub(crate) const fn numeric_kind(self) -> Option<NumericKind> {
        match self {
            DataType::INTEGER8
            | DataType::INTEGER16
            | DataType::INTEGER24
            | DataType::INTEGER32
            | DataType::INTEGER40
            | DataType::INTEGER48
            | DataType::INTEGER56
            | DataType::INTEGER64 => Some(NumericKind::Signed),
            DataType::UNSIGNED8
            | DataType::UNSIGNED16
            | DataType::UNSIGNED24
            | DataType::UNSIGNED32
            | DataType::UNSIGNED40
            | DataType::UNSIGNED48
            | DataType::UNSIGNED56
            | DataType::UNSIGNED64 => Some(NumericKind::Unsigned),
            DataType::REAL32 | DataType::REAL64 => Some(NumericKind::Real),
            _ => None,
        }
    }
}

/// Prints the CiA 301 name, or `0x0020`-style hex for other indices.
impl fmt::Display for DataType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(name) => f.write_str(name),
            None => write!(f, "{:#06X}", self.0),
        }
    }
}

impl fmt::Debug for DataType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "DataType({self})")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn indices_match_cia_301() {
        let indices: Vec<u16> = DataType::BASIC.iter().map(|t| t.0).collect();
        assert_eq!(
            indices,
            [
                0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08, 0x09, 0x0A, 0x0B, 0x0C, 0x0D, 0x0F, 0x10,
                0x11, 0x12, 0x13, 0x14, 0x15, 0x16, 0x18, 0x19, 0x1A, 0x1B
            ]
        );
    }

    #[test]
    fn bit_sizes_of_every_basic_type() {
        let sizes: Vec<(&str, Option<u32>)> = DataType::BASIC
            .iter()
            .map(|t| (t.name().unwrap_or("?"), t.bit_size()))
            .collect();
        assert_eq!(
            sizes,
            [
                ("BOOLEAN", Some(1)),
                ("INTEGER8", Some(8)),
                ("INTEGER16", Some(16)),
                ("INTEGER32", Some(32)),
                ("UNSIGNED8", Some(8)),
                ("UNSIGNED16", Some(16)),
                ("UNSIGNED32", Some(32)),
                ("REAL32", Some(32)),
                ("VISIBLE_STRING", None),
                ("OCTET_STRING", None),
                ("UNICODE_STRING", None),
                ("TIME_OF_DAY", Some(48)),
                ("TIME_DIFFERENCE", Some(48)),
                ("DOMAIN", None),
                ("INTEGER24", Some(24)),
                ("REAL64", Some(64)),
                ("INTEGER40", Some(40)),
                ("INTEGER48", Some(48)),
                ("INTEGER56", Some(56)),
                ("INTEGER64", Some(64)),
                ("UNSIGNED24", Some(24)),
                ("UNSIGNED40", Some(40)),
                ("UNSIGNED48", Some(48)),
                ("UNSIGNED56", Some(56)),
                ("UNSIGNED64", Some(64)),
            ]
        );
    }

    #[test]
    fn byte_size_rounds_up() {
        assert_eq!(DataType::BOOLEAN.byte_size(), Some(1));
        assert_eq!(DataType::INTEGER24.byte_size(), Some(3));
        assert_eq!(DataType::UNSIGNED56.byte_size(), Some(7));
        assert_eq!(DataType::TIME_OF_DAY.byte_size(), Some(6));
        assert_eq!(DataType::DOMAIN.byte_size(), None);
    }

    #[test]
    fn variable_length_is_exactly_strings_and_domain() {
        for data_type in DataType::BASIC {
            assert_eq!(
                data_type.is_variable_length(),
                data_type.bit_size().is_none(),
                "{data_type}"
            );
        }
        assert!(!DataType(0x0020).is_variable_length());
        assert_eq!(DataType(0x0020).bit_size(), None);
    }

    #[test]
    fn numeric_types_are_integers_and_reals() {
        let numeric: Vec<_> = DataType::BASIC.into_iter().filter(|t| t.is_numeric()).collect();
        assert_eq!(numeric.len(), 18);
        assert!(!DataType::BOOLEAN.is_numeric());
        assert!(!DataType::TIME_OF_DAY.is_numeric());
        assert_eq!(DataType::INTEGER40.numeric_kind(), Some(NumericKind::Signed));
        assert_eq!(DataType::UNSIGNED24.numeric_kind(), Some(NumericKind::Unsigned));
        assert_eq!(DataType::REAL64.numeric_kind(), Some(NumericKind::Real));
    }

    #[test]
    fn displays_name_or_hex_index() {
        assert_eq!(DataType::UNSIGNED16.to_string(), "UNSIGNED16");
        assert_eq!(DataType(0x0021).to_string(), "0x0021");
        assert_eq!(DataType(0x0017).to_string(), "0x0017");
        assert_eq!(format!("{:?}", DataType::REAL32), "DataType(REAL32)");
    }
}

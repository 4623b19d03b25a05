//! CiA 301 data types, object codes and CiA 306 access types.

use std::fmt;

use serde::{Deserialize, Serialize};

/// Data types and access types are the runtime dictionary's vocabulary, shared so an EDS model and a
/// running device mean the same thing by them.
pub use canopener_od::{Access as AccessType, DataType, TypeKind};

/// An object code (CiA 301 §7.4.3, CiA 306 §4.6.3.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "UPPERCASE")]
pub enum ObjectType {
    /// 0x0: no data fields.
    Null,
    /// 0x2: large variable amount of data.
    Domain,
    /// 0x5: a type definition.
    DefType,
    /// 0x6: a record type definition.
    DefStruct,
    /// 0x7: a single value.
    Var,
    /// 0x8: sub-objects of one type.
    Array,
    /// 0x9: sub-objects of different types.
    Record,
}

impl ObjectType {
    /// The numeric code.
    pub fn code(self) -> u8 {
        match self {
            Self::Null => 0x0,
            Self::Domain => 0x2,
            Self::DefType => 0x5,
            Self::DefStruct => 0x6,
            Self::Var => 0x7,
            Self::Array => 0x8,
            Self::Record => 0x9,
        }
    }

    /// The object type for a code, if CiA 306 defines it.
    pub fn from_code(code: u64) -> Option<Self> {
        Some(match code {
            0x0 => Self::Null,
            0x2 => Self::Domain,
            0x5 => Self::DefType,
            0x6 => Self::DefStruct,
            0x7 => Self::Var,
            0x8 => Self::Array,
            0x9 => Self::Record,
            _ => return None,
        })
    }

    /// Whether objects of this type have sub-objects.
    pub fn has_subs(self) -> bool {
        matches!(self, Self::DefStruct | Self::Array | Self::Record)
    }
}

impl fmt::Display for ObjectType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Null => "NULL",
            Self::Domain => "DOMAIN",
            Self::DefType => "DEFTYPE",
            Self::DefStruct => "DEFSTRUCT",
            Self::Var => "VAR",
            Self::Array => "ARRAY",
            Self::Record => "RECORD",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_basic_type_has_a_kind() {
        for t in DataType::BASIC {
            assert!(t.kind().is_some(), "{t}");
        }
        assert_eq!(DataType::UNSIGNED24.kind(), Some(TypeKind::Unsigned(24)));
        assert_eq!(DataType::INTEGER56.kind(), Some(TypeKind::Signed(56)));
        assert_eq!(DataType::IDENTITY.kind(), Some(TypeKind::Structure));
        assert_eq!(DataType(0x17).kind(), None);
        assert!(DataType::UNSIGNED8.is_integer() && !DataType::REAL32.is_integer());
    }

    #[test]
    fn object_and_access_codes() {
        for code in [0u64, 2, 5, 6, 7, 8, 9] {
            assert_eq!(
                ObjectType::from_code(code).map(|t| u64::from(t.code())),
                Some(code)
            );
        }
        assert_eq!(ObjectType::from_code(3), None);
        assert_eq!(AccessType::parse("RW"), Some(AccessType::Rw));
        assert_eq!(AccessType::parse("readwrite"), None);
        assert!(!AccessType::Const.writable() && AccessType::Const.readable());
    }
}

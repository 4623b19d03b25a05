//! Errors of dictionary accesses, each mapping onto one CiA 301 SDO abort code (CiA 301 §7.2.4.3.17).

use crate::access::Access;
use crate::data_type::DataType;
use crate::key::ObjectKey;
use crate::number::Number;

/// Why a dictionary access failed.
///
/// An SDO server answers every variant with the abort code [`OdError::abort_code`] returns, so the
/// variants are split exactly where CiA 301 splits its abort codes.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum OdError {
    /// No entry has the key's index (abort code 0602 0000h).
    #[error(
        "object {:#06X} does not exist in the object dictionary; check the index or insert the object first",
        key.index
    )]
    ObjectDoesNotExist {
        /// The key that was asked for.
        key: ObjectKey,
    },
    /// The object exists but has no entry at this sub-index (abort code 0609 0011h).
    #[error("sub-index {key} does not exist although object {:#06X} does; check the sub-index", key.index)]
    SubIndexDoesNotExist {
        /// The key that was asked for.
        key: ObjectKey,
    },
    /// A read of a write-only entry (abort code 0601 0001h).
    #[error("{key} is write-only and cannot be read; change its access type to read it")]
    WriteOnly {
        /// The entry that was read.
        key: ObjectKey,
    },
    /// A write to a `ro` or `const` entry (abort code 0601 0002h).
    #[error("{key} is {access} and cannot be written; only wo, rw, rwr and rww entries accept writes")]
    ReadOnly {
        /// The entry that was written.
        key: ObjectKey,
        /// Its access type, `ro` or `const`.
        access: Access,
    },
    /// More bytes than the entry holds (abort code 0607 0012h).
    #[error("{len} bytes are too many for {key} of type {data_type}, which takes at most {max}")]
    LengthTooHigh {
        /// The entry that was written.
        key: ObjectKey,
        /// Its data type.
        data_type: DataType,
        /// The number of bytes written.
        len: usize,
        /// The most bytes the entry takes.
        max: usize,
    },
    /// Fewer bytes than a fixed-size entry holds (abort code 0607 0013h).
    #[error("{len} bytes are too few for {key} of type {data_type}, which takes exactly {expected}")]
    LengthTooLow {
        /// The entry that was written.
        key: ObjectKey,
        /// Its data type.
        data_type: DataType,
        /// The number of bytes written.
        len: usize,
        /// The number of bytes the entry takes.
        expected: usize,
    },
    /// A length that is neither too long nor too short but still cannot be a value of the type:
    /// an odd number of bytes for a UNICODE_STRING (abort code 0607 0010h).
    #[error(
        "{len} bytes are not a whole number of 16-bit code units for {key} of type {data_type}; write an even number of bytes"
    )]
    LengthMismatch {
        /// The entry that was written.
        key: ObjectKey,
        /// Its data type.
        data_type: DataType,
        /// The number of bytes written.
        len: usize,
    },
    /// A number above the entry's `HighLimit` (abort code 0609 0031h).
    #[error("value {value} is above the high limit {limit} of {key}; write at most {limit}")]
    ValueTooHigh {
        /// The entry that was written.
        key: ObjectKey,
        /// The value that was written.
        value: Number,
        /// The entry's high limit.
        limit: Number,
    },
    /// A number below the entry's `LowLimit` (abort code 0609 0032h).
    #[error("value {value} is below the low limit {limit} of {key}; write at least {limit}")]
    ValueTooLow {
        /// The entry that was written.
        key: ObjectKey,
        /// The value that was written.
        value: Number,
        /// The entry's low limit.
        limit: Number,
    },
    /// A REAL not-a-number written to an entry with limits, which no range contains
    /// (abort code 0609 0030h).
    #[error(
        "value {value} of {key} is not a number, so it cannot lie within the entry's limits; write a number"
    )]
    ValueOutOfRange {
        /// The entry that was written.
        key: ObjectKey,
        /// The value that was written.
        value: Number,
    },
    /// An insert into a full dictionary; the dictionary is unchanged (abort code 0800 0023h).
    #[error(
        "the object dictionary is full ({capacity} entries), so {key} cannot be added; \
         create it with a larger capacity or remove an entry first"
    )]
    Full {
        /// The fixed capacity of the dictionary.
        capacity: usize,
        /// The key of the entry that did not fit.
        key: ObjectKey,
    },
}

impl OdError {
    /// The SDO abort code (CiA 301 §7.2.4.3.17) a server sends for this error.
    ///
    /// [`OdError::Full`] maps onto 0800 0023h "object dictionary dynamic generation fails", the
    /// code CiA 301 gives for exactly the failure of building a dictionary at run time.
    pub const fn abort_code(&self) -> u32 {
        match self {
            OdError::ObjectDoesNotExist { .. } => 0x0602_0000,
            OdError::SubIndexDoesNotExist { .. } => 0x0609_0011,
            OdError::WriteOnly { .. } => 0x0601_0001,
            OdError::ReadOnly { .. } => 0x0601_0002,
            OdError::LengthMismatch { .. } => 0x0607_0010,
            OdError::LengthTooHigh { .. } => 0x0607_0012,
            OdError::LengthTooLow { .. } => 0x0607_0013,
            OdError::ValueOutOfRange { .. } => 0x0609_0030,
            OdError::ValueTooHigh { .. } => 0x0609_0031,
            OdError::ValueTooLow { .. } => 0x0609_0032,
            OdError::Full { .. } => 0x0800_0023,
        }
    }

    /// The key the failed access was about.
    pub const fn key(&self) -> ObjectKey {
        match self {
            OdError::ObjectDoesNotExist { key }
            | OdError::SubIndexDoesNotExist { key }
            | OdError::WriteOnly { key }
            | OdError::ReadOnly { key, .. }
            | OdError::LengthTooHigh { key, .. }
            | OdError::LengthTooLow { key, .. }
            | OdError::LengthMismatch { key, .. }
            | OdError::ValueTooHigh { key, .. }
            | OdError::ValueTooLow { key, .. }
            | OdError::ValueOutOfRange { key, .. }
            | OdError::Full { key, .. } => *key,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const KEY: ObjectKey = ObjectKey::new(0x2000, 3);

    #[test]
    fn messages_name_the_entry_lowercase_without_a_trailing_period() {
        let errors = [
            OdError::ObjectDoesNotExist { key: KEY },
            OdError::SubIndexDoesNotExist { key: KEY },
            OdError::WriteOnly { key: KEY },
            OdError::ReadOnly {
                key: KEY,
                access: Access::Const,
            },
            OdError::LengthTooHigh {
                key: KEY,
                data_type: DataType::UNSIGNED16,
                len: 3,
                max: 2,
            },
            OdError::LengthTooLow {
                key: KEY,
                data_type: DataType::UNSIGNED16,
                len: 1,
                expected: 2,
            },
            OdError::LengthMismatch {
                key: KEY,
                data_type: DataType::UNICODE_STRING,
                len: 3,
            },
            OdError::ValueTooHigh {
                key: KEY,
                value: Number::Signed(9),
                limit: Number::Signed(8),
            },
            OdError::ValueTooLow {
                key: KEY,
                value: Number::Unsigned(1),
                limit: Number::Unsigned(2),
            },
            OdError::ValueOutOfRange {
                key: KEY,
                value: Number::Real(f64::NAN),
            },
            OdError::Full {
                capacity: 4,
                key: KEY,
            },
        ];
        for error in errors {
            let message = error.to_string();
            assert!(message.contains("0x2000"), "{message}");
            assert!(!message.ends_with('.'), "{message}");
            assert!(message.starts_with(|c: char| !c.is_uppercase()), "{message}");
            assert_eq!(error.key(), KEY);
        }
    }

    #[test]
    fn messages_carry_the_numbers() {
        let too_high = OdError::ValueTooHigh {
            key: KEY,
            value: Number::Signed(-3),
            limit: Number::Signed(-4),
        };
        assert_eq!(
            too_high.to_string(),
            "value -3 is above the high limit -4 of 0x2000:03; write at most -4"
        );
        let read_only = OdError::ReadOnly {
            key: KEY,
            access: Access::Ro,
        };
        assert!(
            read_only
                .to_string()
                .starts_with("0x2000:03 is ro and cannot be written")
        );
    }

    #[test]
    fn abort_codes_are_the_cia_301_ones() {
        let codes: Vec<u32> = [
            OdError::ObjectDoesNotExist { key: KEY },
            OdError::SubIndexDoesNotExist { key: KEY },
            OdError::WriteOnly { key: KEY },
            OdError::ReadOnly {
                key: KEY,
                access: Access::Ro,
            },
            OdError::LengthMismatch {
                key: KEY,
                data_type: DataType::UNICODE_STRING,
                len: 1,
            },
            OdError::LengthTooHigh {
                key: KEY,
                data_type: DataType::UNSIGNED8,
                len: 2,
                max: 1,
            },
            OdError::LengthTooLow {
                key: KEY,
                data_type: DataType::UNSIGNED16,
                len: 1,
                expected: 2,
            },
            OdError::ValueOutOfRange {
                key: KEY,
                value: Number::Real(f64::NAN),
            },
            OdError::ValueTooHigh {
                key: KEY,
                value: Number::Unsigned(2),
                limit: Number::Unsigned(1),
            },
            OdError::ValueTooLow {
                key: KEY,
                value: Number::Unsigned(0),
                limit: Number::Unsigned(1),
            },
            OdError::Full {
                capacity: 0,
                key: KEY,
            },
        ]
        .iter()
        .map(OdError::abort_code)
        .collect();
        assert_eq!(
            codes,
            [
                0x0602_0000,
                0x0609_0011,
                0x0601_0001,
                0x0601_0002,
                0x0607_0010,
                0x0607_0012,
                0x0607_0013,
                0x0609_0030,
                0x0609_0031,
                0x0609_0032,
                0x0800_0023
            ]
        );
    }
}

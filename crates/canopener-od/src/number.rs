//! Numeric values decoded from their little-endian bytes (CiA 301 §7.1.4), for limit checks.
//!
//! Integers of 24, 40, 48 and 56 bits are sign- or zero-extended to 64 bits, so every INTEGERn
//! fits an `i64`, every UNSIGNEDn a `u64`, and REAL32 widens losslessly to `f64`.

use std::cmp::Ordering;
use std::fmt;

use crate::data_type::{DataType, NumericKind};

/// The value of an integer or REAL entry.
///
/// Numbers of the same kind compare by value; numbers of different kinds are unordered, which never
/// matters here because a value and its limits always share one data type.
#[derive(Clone, Copy, PartialEq, Debug)]
pub enum Number {
    /// An INTEGER8 … INTEGER64 value.
    Signed(i64),
    /// An UNSIGNED8 … UNSIGNED64 value.
    Unsigned(u64),
    /// A REAL32 or REAL64 value.
    Real(f64),
}

impl Number {
    /// Reads `bytes` as a value of `data_type`, or `None` when the type is not numeric or `bytes`
    /// is not exactly the type's size.
    pub fn decode(data_type: DataType, bytes: &[u8]) -> Option<Number> {
        let kind = data_type.numeric_kind()?;
        let size = data_type.byte_size()?;
        if bytes.len() != size {
            return None;
        }
        let mut wide = [0u8; 8];
        // `size` is at most 8 for every numeric type, so the destination range exists.
        wide.get_mut(..size)?.copy_from_slice(bytes);
        let raw = u64::from_le_bytes(wide);
        Some(match kind {
            NumericKind::Unsigned => Number::Unsigned(raw),
            NumericKind::Signed => {
                // Move the value's sign bit to bit 63, then shift back arithmetically to extend it.
                let unused_bits = 64 - 8 * size as u32;
                Number::Signed(((raw << unused_bits) as i64) >> unused_bits)
            }
            NumericKind::Real if size == 4 => Number::Real(f64::from(f32::from_bits(raw as u32))),
            NumericKind::Real => Number::Real(f64::from_bits(raw)),
        })
    }

    /// Whether this is a REAL not-a-number, which no limit can order.
    pub fn is_nan(self) -> bool {
        matches!(self, Number::Real(real) if real.is_nan())
    }
}

impl PartialOrd for Number {
    fn partial_cmp(&self, other: &Number) -> Option<Ordering> {
        match (self, other) {
            (Number::Signed(a), Number::Signed(b)) => a.partial_cmp(b),
            (Number::Unsigned(a), Number::Unsigned(b)) => a.partial_cmp(b),
            (Number::Real(a), Number::Real(b)) => a.partial_cmp(b),
            _ => None,
        }
    }
}

impl fmt::Display for Number {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Number::Signed(value) => write!(f, "{value}"),
            Number::Unsigned(value) => write!(f, "{value}"),
            Number::Real(value) => write!(f, "{value}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    #[test]
    fn sign_extends_odd_width_integers() {
        assert_eq!(
            Number::decode(DataType::INTEGER24, &[0xFF, 0xFF, 0xFF]),
            Some(Number::Signed(-1))
        );
        assert_eq!(
            Number::decode(DataType::INTEGER24, &[0x00, 0x00, 0x80]),
            Some(Number::Signed(-(1 << 23)))
        );
        assert_eq!(
            Number::decode(DataType::INTEGER40, &[0xFF, 0xFF, 0xFF, 0xFF, 0x7F]),
            Some(Number::Signed((1 << 39) - 1))
        );
        assert_eq!(
            Number::decode(DataType::INTEGER56, &[0, 0, 0, 0, 0, 0, 0x80]),
            Some(Number::Signed(-(1 << 55)))
        );
    }

    #[test]
    fn zero_extends_unsigned() {
        assert_eq!(
            Number::decode(DataType::UNSIGNED24, &[0xFF, 0xFF, 0xFF]),
            Some(Number::Unsigned(0xFF_FFFF))
        );
        assert_eq!(
            Number::decode(DataType::UNSIGNED48, &[1, 2, 3, 4, 5, 6]),
            Some(Number::Unsigned(0x0605_0403_0201))
        );
        assert_eq!(
            Number::decode(DataType::UNSIGNED64, &[0xFF; 8]),
            Some(Number::Unsigned(u64::MAX))
        );
    }

    #[test]
    fn reads_reals() {
        assert_eq!(
            Number::decode(DataType::REAL32, &1.5f32.to_le_bytes()),
            Some(Number::Real(1.5))
        );
        assert_eq!(
            Number::decode(DataType::REAL64, &(-2.25f64).to_le_bytes()),
            Some(Number::Real(-2.25))
        );
        assert!(Number::decode(DataType::REAL32, &f32::NAN.to_le_bytes()).is_some_and(Number::is_nan));
    }

    #[test]
    fn refuses_wrong_lengths_and_non_numeric_types() {
        assert_eq!(Number::decode(DataType::UNSIGNED16, &[1]), None);
        assert_eq!(Number::decode(DataType::UNSIGNED16, &[1, 2, 3]), None);
        assert_eq!(Number::decode(DataType::BOOLEAN, &[1]), None);
        assert_eq!(Number::decode(DataType::VISIBLE_STRING, b"abc"), None);
        assert_eq!(Number::decode(DataType(0x0020), &[0; 4]), None);
    }

    #[test]
    fn orders_within_a_kind_only() {
        assert!(Number::Signed(-5) < Number::Signed(3));
        assert!(Number::Unsigned(u64::MAX) > Number::Unsigned(0));
        assert!(Number::Real(-0.5) < Number::Real(0.25));
        assert_eq!(Number::Signed(1).partial_cmp(&Number::Unsigned(1)), None);
        assert_eq!(Number::Real(f64::NAN).partial_cmp(&Number::Real(0.0)), None);
    }

    proptest! {
        #[test]
        fn signed_round_trips_through_every_width(value in any::<i64>(), width in 1usize..=8) {
            let data_type = match width {
                1 => DataType::INTEGER8,
                2 => DataType::INTEGER16,
                3 => DataType::INTEGER24,
                4 => DataType::INTEGER32,
                5 => DataType::INTEGER40,
                6 => DataType::INTEGER48,
                7 => DataType::INTEGER56,
                _ => DataType::INTEGER64,
            };
            // Truncate to the width, then compute the expected value by wrapping in that width.
            let bits = 8 * width as u32;
            let expected = (value << (64 - bits)) >> (64 - bits);
            let bytes = value.to_le_bytes();
            prop_assert_eq!(Number::decode(data_type, &bytes[..width]), Some(Number::Signed(expected)));
        }
    }
}

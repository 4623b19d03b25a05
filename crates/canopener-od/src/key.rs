//! The address of one object dictionary entry: a 16-bit index and an 8-bit sub-index (CiA 301 §7.4).

use std::fmt;

/// The index and sub-index that address one entry of the object dictionary.
///
/// `Ord` is the dictionary order: by index, then by sub-index. [`DynamicOd`](crate::DynamicOd) keeps
/// its entries in this order, which is what makes binary search and contiguous objects possible.
///
/// `Display` prints `0x1018:01`; every error message of this crate names entries that way.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct ObjectKey {
    /// The object index, `0x0000..=0xFFFF`.
    pub index: u16,
    /// The sub-index within the object; `0` for a plain variable.
    pub sub: u8,
}

impl ObjectKey {
    /// The key of sub-index `sub` of object `index`.
    pub const fn new(index: u16, sub: u8) -> ObjectKey {
        ObjectKey { index, sub }
    }

    /// The key as one number, `index << 8 | sub`, ordered exactly like `ObjectKey` itself.
    ///
    /// This is the form a PDO mapping entry carries the address in (its top 24 bits, objects
    /// 1600h–17FFh and 1A00h–1BFFh) and the form the dictionary searches on.
    pub const fn packed(self) -> u32 {
        ((self.index as u32) << 8) | self.sub as u32
    }

    /// The key whose [`packed`](ObjectKey::packed) form is the low 24 bits of `packed`.
    pub const fn from_packed(packed: u32) -> ObjectKey {
        ObjectKey {
            index: (packed >> 8) as u16,
            sub: packed as u8,
        }
    }
}

impl From<(u16, u8)> for ObjectKey {
    fn from((index, sub): (u16, u8)) -> ObjectKey {
        ObjectKey { index, sub }
    }
}

impl fmt::Display for ObjectKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:#06X}:{:02X}", self.index, self.sub)
    }
}

impl fmt::Debug for ObjectKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    #[test]
    fn displays_index_and_sub_in_hex() {
        assert_eq!(ObjectKey::new(0x1018, 1).to_string(), "0x1018:01");
        assert_eq!(ObjectKey::new(0x00A, 0xFE).to_string(), "0x000A:FE");
        assert_eq!(format!("{:?}", ObjectKey::new(0x6040, 0)), "0x6040:00");
    }

    #[test]
    fn orders_by_index_then_sub() {
        let mut keys = vec![
            ObjectKey::new(0x2000, 0),
            ObjectKey::new(0x1018, 4),
            ObjectKey::new(0x1018, 0),
            ObjectKey::new(0x1000, 0xFF),
        ];
        keys.sort();
        assert_eq!(
            keys,
            [
                ObjectKey::new(0x1000, 0xFF),
                ObjectKey::new(0x1018, 0),
                ObjectKey::new(0x1018, 4),
                ObjectKey::new(0x2000, 0),
            ]
        );
    }

    #[test]
    fn packs_like_a_pdo_mapping_entry() {
        // 0x60410010 maps 0x6041:00 with 16 bits; the address is the top 24 bits.
        assert_eq!(ObjectKey::new(0x6041, 0).packed(), 0x0060_4100);
        assert_eq!(ObjectKey::from_packed(0x0060_4100), ObjectKey::new(0x6041, 0));
        assert_eq!(ObjectKey::from_packed(0xFF12_3456), ObjectKey::new(0x1234, 0x56));
    }

    proptest! {
        #[test]
        fn packed_order_is_key_order(a in any::<(u16, u8)>(), b in any::<(u16, u8)>()) {
            let (a, b) = (ObjectKey::from(a), ObjectKey::from(b));
            prop_assert_eq!(a.cmp(&b), a.packed().cmp(&b.packed()));
            prop_assert_eq!(ObjectKey::from_packed(a.packed()), a);
        }
    }
}

//! Byte storage for entry values: short values inline, long ones on the heap.
//!
//! Every numeric type is at most 8 bytes and most strings in real dictionaries are short, so an
//! inline buffer that fills the space a boxed slice needs anyway (24 bytes with the tag) keeps
//! nearly every entry free of its own allocation. The benchmark `value_storage` in `benches/od.rs`
//! measures what that saves against one `Vec<u8>` per entry.

use std::fmt;

/// The longest value kept inline: the enum is then exactly as large as its `Box<[u8]>` variant.
pub(crate) const INLINE_CAPACITY: usize = 22;

#[derive(Clone)]
pub(crate) enum ValueBytes {
    /// Invariant: `len <= INLINE_CAPACITY` and the bytes past `len` are zero.
    Inline { len: u8, bytes: [u8; INLINE_CAPACITY] },
    /// Invariant: longer than `INLINE_CAPACITY`.
    Heap(Box<[u8]>),
}

impl ValueBytes {
    pub(crate) fn new(data: &[u8]) -> ValueBytes {
        match u8::try_from(data.len()) {
            Ok(len) if data.len() <= INLINE_CAPACITY => {
                let mut bytes = [0; INLINE_CAPACITY];
                #[allow(
                    clippy::indexing_slicing,
                    reason = "the guard above keeps `data.len()` within the buffer"
                )]
                bytes[..data.len()].copy_from_slice(data);
                ValueBytes::Inline { len, bytes }
            }
            _ => ValueBytes::Heap(data.into()),
        }
    }

    pub(crate) fn as_slice(&self) -> &[u8] {
        match self {
            // `len <= INLINE_CAPACITY` is the variant's invariant, set only by `new`.
            ValueBytes::Inline { len, bytes } => bytes.get(..usize::from(*len)).unwrap_or(bytes),
            ValueBytes::Heap(bytes) => bytes,
        }
    }

    pub(crate) fn len(&self) -> usize {
        self.as_slice().len()
    }

    /// Replaces the value, reusing the storage when the length stays the same (every write to a
    /// fixed-size entry), so such writes never allocate.
    pub(crate) fn set(&mut self, data: &[u8]) {
        match self {
            ValueBytes::Inline { len, bytes } if usize::from(*len) == data.len() => {
                #[allow(
                    clippy::indexing_slicing,
                    reason = "the guard ties `data.len()` to the stored `len`, which never exceeds the buffer"
                )]
                bytes[..data.len()].copy_from_slice(data);
            }
            ValueBytes::Heap(bytes) if bytes.len() == data.len() => bytes.copy_from_slice(data),
            _ => *self = ValueBytes::new(data),
        }
    }
}

impl PartialEq for ValueBytes {
    fn eq(&self, other: &ValueBytes) -> bool {
        self.as_slice() == other.as_slice()
    }
}

impl Eq for ValueBytes {}

/// Prints the bytes as hex, e.g. `[E8 03]`.
impl fmt::Debug for ValueBytes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("[")?;
        for (byte_idx, byte) in self.as_slice().iter().enumerate() {
            if byte_idx > 0 {
                f.write_str(" ")?;
            }
            write!(f, "{byte:02X}")?;
        }
        f.write_str("]")
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    #[test]
    fn is_no_larger_than_a_boxed_slice_plus_tag() {
        assert_eq!(size_of::<ValueBytes>(), 24);
    }

    #[test]
    fn short_values_stay_inline_and_long_ones_go_to_the_heap() {
        assert!(matches!(
            ValueBytes::new(&[1, 2, 3, 4]),
            ValueBytes::Inline { len: 4, .. }
        ));
        assert!(matches!(
            ValueBytes::new(&[7; INLINE_CAPACITY]),
            ValueBytes::Inline { .. }
        ));
        assert!(matches!(
            ValueBytes::new(&[7; INLINE_CAPACITY + 1]),
            ValueBytes::Heap(_)
        ));
        assert!(matches!(ValueBytes::new(&[]), ValueBytes::Inline { len: 0, .. }));
    }

    #[test]
    fn set_moves_between_inline_and_heap() {
        let mut value = ValueBytes::new(b"short");
        value.set(&[0xAB; 40]);
        assert!(matches!(value, ValueBytes::Heap(_)));
        assert_eq!(value.as_slice(), [0xAB; 40]);
        value.set(b"ab");
        assert!(matches!(value, ValueBytes::Inline { len: 2, .. }));
        assert_eq!(value.as_slice(), b"ab");
    }

    #[test]
    fn shrinking_inline_keeps_the_tail_zero_so_equality_is_by_content() {
        let mut value = ValueBytes::new(b"longer text");
        value.set(b"hi");
        assert_eq!(value, ValueBytes::new(b"hi"));
        assert!(matches!(value, ValueBytes::Inline { bytes, .. } if bytes[2..].iter().all(|&b| b == 0)));
    }

    #[test]
    fn debug_prints_hex() {
        assert_eq!(format!("{:?}", ValueBytes::new(&[0xE8, 0x03])), "[E8 03]");
        assert_eq!(format!("{:?}", ValueBytes::new(&[])), "[]");
    }

    proptest! {
        #[test]
        fn holds_exactly_what_was_set(first in prop::collection::vec(any::<u8>(), 0..64),
                                      second in prop::collection::vec(any::<u8>(), 0..64)) {
            let mut value = ValueBytes::new(&first);
            prop_assert_eq!(value.as_slice(), &first[..]);
            prop_assert_eq!(value.len(), first.len());
            value.set(&second);
            prop_assert_eq!(value.as_slice(), &second[..]);
            prop_assert_eq!(value, ValueBytes::new(&second));
        }
    }
}

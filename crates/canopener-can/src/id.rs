//! CAN identifiers and their arbitration order (ISO 11898-1 §10.4.2 arbitration field).

use std::cmp::Ordering;
use std::fmt;

/// An 11-bit identifier of a base-format (CAN 2.0A) frame.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct StandardId(u16);

/// A 29-bit identifier of an extended-format (CAN 2.0B) frame.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ExtendedId(u32);

/// Why a raw number is not a valid identifier.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum IdError {
    /// The value needs more than 11 bits.
    #[error("standard CAN id {0:#X} is larger than 0x7FF (11 bits)")]
    StandardTooLarge(u32),
    /// The value needs more than 29 bits.
    #[error("extended CAN id {0:#X} is larger than 0x1FFFFFFF (29 bits)")]
    ExtendedTooLarge(u32),
}

impl StandardId {
    /// The largest standard identifier, 0x7FF.
    pub const MAX: StandardId = StandardId(0x7FF);
    /// Identifier 0, the highest priority on the bus (CANopen NMT).
    pub const ZERO: StandardId = StandardId(0);

    /// A standard identifier, or `None` when `raw` needs more than 11 bits.
    pub const fn new(raw: u16) -> Option<StandardId> {
        if raw <= 0x7FF { Some(StandardId(raw)) } else { None }
    }

    /// The identifier as a number.
    pub const fn as_raw(self) -> u16 {
        self.0
    }
}

impl ExtendedId {
    /// The largest extended identifier, 0x1FFFFFFF.
    pub const MAX: ExtendedId = ExtendedId(0x1FFF_FFFF);

    /// An extended identifier, or `None` when `raw` needs more than 29 bits.
    pub const fn new(raw: u32) -> Option<ExtendedId> {
        if raw <= 0x1FFF_FFFF {
            Some(ExtendedId(raw))
        } else {
            None
        }
    }

    /// The identifier as a number.
    pub const fn as_raw(self) -> u32 {
        self.0
    }

    /// The 11 most significant bits, sent first in the arbitration field.
    pub const fn base(self) -> u16 {
        (self.0 >> 18) as u16
    }

    /// The 18 least significant bits, sent after SRR and IDE.
    pub const fn extension(self) -> u32 {
        self.0 & 0x3_FFFF
    }
}

/// A CAN identifier in either format.
///
/// `Ord` is the arbitration order on the bus: `a < b` means a frame with `a` wins arbitration against a
/// data frame with `b`. Identifiers of different formats compare by their first 11 bits; when those
/// are equal the standard identifier wins, because its dominant IDE bit meets the extended frame's
/// recessive SRR bit. Use [`crate::CanFrame::arbitration_key`] to include the RTR bit.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub enum CanId {
    /// An 11-bit identifier.
    Standard(StandardId),
    /// A 29-bit identifier.
    Extended(ExtendedId),
}

impl CanId {
    /// A standard identifier from a raw value.
    pub fn standard(raw: u16) -> Result<CanId, IdError> {
        StandardId::new(raw)
            .map(CanId::Standard)
            .ok_or(IdError::StandardTooLarge(u32::from(raw)))
    }

    /// An extended identifier from a raw value.
    pub fn extended(raw: u32) -> Result<CanId, IdError> {
        ExtendedId::new(raw)
            .map(CanId::Extended)
            .ok_or(IdError::ExtendedTooLarge(raw))
    }

    /// The identifier as a number, without any format flag.
    pub const fn as_raw(self) -> u32 {
        match self {
            CanId::Standard(id) => id.0 as u32,
            CanId::Extended(id) => id.0,
        }
    }

    /// Whether this is a 29-bit identifier.
    pub const fn is_extended(self) -> bool {
        matches!(self, CanId::Extended(_))
    }

    /// The arbitration bits of a frame with this identifier as one number: the smaller key wins.
    ///
    /// Bit layout, most significant first, mirrors the order the bits are sent:
    /// 11 base-id bits, then RTR (standard) or SRR (extended, always recessive 1), then IDE, then the
    /// 18 extension bits (zero for standard frames) and finally the extended frame's RTR bit.
    /// Dominant bits are 0, so the numerically smaller key is the one that keeps sending dominant bits.
    pub const fn arbitration_key(self, remote: bool) -> u32 {
        match self {
            CanId::Standard(id) => ((id.0 as u32) << 21) | ((remote as u32) << 20),
            CanId::Extended(id) => {
                ((id.base() as u32) << 21) | (1 << 20) | (1 << 19) | (id.extension() << 1) | (remote as u32)
            }
        }
    }
}

impl Ord for CanId {
    fn cmp(&self, other: &CanId) -> Ordering {
        self.arbitration_key(false).cmp(&other.arbitration_key(false))
    }
}

impl PartialOrd for CanId {
    fn partial_cmp(&self, other: &CanId) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl From<StandardId> for CanId {
    fn from(id: StandardId) -> CanId {
        CanId::Standard(id)
    }
}

impl From<ExtendedId> for CanId {
    fn from(id: ExtendedId) -> CanId {
        CanId::Extended(id)
    }
}

/// Three uppercase hex digits, as candump and socketcand write base-format identifiers.
impl fmt::Display for StandardId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:03X}", self.0)
    }
}

/// Eight uppercase hex digits, as candump and socketcand write extended identifiers.
impl fmt::Display for ExtendedId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:08X}", self.0)
    }
}

/// `123` for standard and `1ABCDEF0` for extended identifiers: the digit count carries the format.
impl fmt::Display for CanId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CanId::Standard(id) => id.fmt(f),
            CanId::Extended(id) => id.fmt(f),
        }
    }
}

impl fmt::Debug for StandardId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "StandardId({:#05X})", self.0)
    }
}

impl fmt::Debug for ExtendedId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "ExtendedId({:#010X})", self.0)
    }
}

impl fmt::Debug for CanId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CanId::Standard(id) => id.fmt(f),
            CanId::Extended(id) => id.fmt(f),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::strategy::any_id;
    use proptest::prelude::*;

    fn std_id(raw: u16) -> CanId {
        CanId::standard(raw).unwrap()
    }

    fn ext_id(raw: u32) -> CanId {
        CanId::extended(raw).unwrap()
    }

    #[test]
    fn range_checks() {
        assert!(StandardId::new(0x7FF).is_some());
        assert!(StandardId::new(0x800).is_none());
        assert!(ExtendedId::new(0x1FFF_FFFF).is_some());
        assert!(ExtendedId::new(0x2000_0000).is_none());
        assert_eq!(CanId::standard(0x800), Err(IdError::StandardTooLarge(0x800)));
        assert_eq!(
            CanId::extended(0x2000_0000),
            Err(IdError::ExtendedTooLarge(0x2000_0000))
        );
    }

    #[test]
    fn lower_standard_id_wins() {
        assert!(std_id(0x000) < std_id(0x080));
        assert!(std_id(0x181) < std_id(0x581));
        assert!(std_id(0x7FF) > std_id(0x7FE));
    }

    #[test]
    fn standard_beats_extended_with_same_base_bits() {
        // 0x123 << 18 has the same 11 leading bits as standard 0x123; IDE decides for the standard one.
        let ext_same_base = ext_id(0x123 << 18);
        assert!(std_id(0x123) < ext_same_base);
        // Even a standard remote frame wins: its RTR meets the recessive SRR, then IDE decides.
        assert!(std_id(0x123).arbitration_key(true) < ext_same_base.arbitration_key(false));
        // But a smaller base in the extended id wins against a larger standard id.
        assert!(ext_id(0x122 << 18 | 0x3FFFF) < std_id(0x123));
    }

    #[test]
    fn data_beats_remote_with_same_id() {
        assert!(std_id(0x701).arbitration_key(false) < std_id(0x701).arbitration_key(true));
        assert!(ext_id(0x1234).arbitration_key(false) < ext_id(0x1234).arbitration_key(true));
    }

    #[test]
    fn display_pads_to_format_width() {
        assert_eq!(std_id(0x12).to_string(), "012");
        assert_eq!(ext_id(0x12).to_string(), "00000012");
        assert_eq!(ext_id(0x1AAA_AAAA).to_string(), "1AAAAAAA");
    }

    /// Reference arbitration: compare the dominant/recessive bit sequences one bit at a time.
    fn arbitration_bits(id: CanId, remote: bool) -> Vec<u8> {
        let mut bits = Vec::new();
        let push = |bits: &mut Vec<u8>, value: u32, width: u32| {
            for i in (0..width).rev() {
                bits.push(((value >> i) & 1) as u8);
            }
        };
        match id {
            CanId::Standard(id) => {
                push(&mut bits, u32::from(id.as_raw()), 11);
                bits.push(remote as u8);
                bits.push(0); // IDE
            }
            CanId::Extended(id) => {
                push(&mut bits, u32::from(id.base()), 11);
                bits.push(1); // SRR
                bits.push(1); // IDE
                push(&mut bits, id.extension(), 18);
                bits.push(remote as u8);
            }
        }
        bits
    }

    proptest! {
        #[test]
        fn key_order_matches_bitwise_arbitration(a in any_id(), ra: bool, b in any_id(), rb: bool) {
            prop_assume!((a, ra) != (b, rb));
            let (bits_a, bits_b) = (arbitration_bits(a, ra), arbitration_bits(b, rb));
            // The first differing bit decides; the frame sending the dominant 0 wins.
            let winner_a = bits_a.iter().zip(&bits_b).find(|(x, y)| x != y).map(|(x, _)| *x == 0);
            let key_a_wins = a.arbitration_key(ra) < b.arbitration_key(rb);
            prop_assert_eq!(winner_a, Some(key_a_wins));
        }
    }
}

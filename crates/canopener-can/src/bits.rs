//! The exact on-wire bit sequence and length of classical CAN frames (ISO 11898-1).
//!
//! Before changing this file read ISO 11898-1:2015, clause "Frame formats" (the fields of data and
//! remote frames, the CRC field with CRC-15) and clause "Frame coding" (bit stuffing); Bosch's CAN
//! Specification 2.0 part A states the same rules. The stuffed region runs from SOF through the CRC
//! sequence; when its last five bits are equal a stuff bit still follows them, before the CRC
//! delimiter. After the region comes a fixed-form tail of 13 bits (CRC delimiter, ACK slot, ACK
//! delimiter, 7 EOF bits, 3 intermission bits) that is never stuffed.
//!
//! Lengths here are computed from the real bit sequence, including the real CRC, so the stuff-bit
//! count is exact rather than an estimate. [`frame_bits`] runs once per frame in the bus simulator and
//! therefore works on a `u128` bit register instead of allocating.

use thiserror::Error;

use crate::frame::CanFrame;
use crate::id::CanId;

/// The CRC-15 generator polynomial x¹⁵ + x¹⁴ + x¹⁰ + x⁸ + x⁷ + x⁴ + x³ + 1 without its x¹⁵ term
/// (ISO 11898-1, "CRC field").
pub const CRC15_POLYNOMIAL: u16 = 0x4599;

/// Bits after the CRC sequence that are never stuffed: CRC delimiter 1, ACK slot 1, ACK delimiter 1,
/// end of frame 7 and intermission 3 (ISO 11898-1, "Frame formats").
pub const FIXED_TAIL_BITS: u32 = 13;

/// The intermission after the end of frame (ISO 11898-1, "Interframe space"): the bus is free for
/// the next SOF this many bits after the last EOF bit.
pub const INTERMISSION_BITS: u32 = 3;

/// The number of equal consecutive bits after which a transmitter inserts a complementary stuff bit
/// (ISO 11898-1, "Frame coding").
pub const STUFF_RUN: u32 = 5;

/// The bit counts of one frame on the wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct FrameBits {
    /// Bits from SOF through the CRC sequence after stuffing, stuff bits included.
    pub stuffed_region: u32,
    /// How many of `stuffed_region` are stuff bits.
    pub stuff_bits: u32,
    /// All bits from SOF to the end of the intermission: the bus time the frame occupies on a
    /// saturated bus, where the next frame's SOF follows the intermission directly.
    pub total: u32,
}

/// A stuffed bit sequence broke the stuffing rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
#[error(
    "stuff error at bit {position}: the bit after five equal bits must be a complementary stuff bit; \
     the sequence was not produced by a CAN transmitter or was cut"
)]
pub struct StuffError {
    /// Zero-based position of the offending bit in the stuffed sequence.
    pub position: usize,
}

/// The CRC-15 of a bit sequence, as ISO 11898-1 ("CRC field") defines it: the register starts at 0,
/// each bit is shifted in most significant first, and there is no final XOR.
///
/// For a frame the sequence is SOF through the last data bit, before stuffing. Appending the 15 CRC
/// bits (most significant first) to the sequence and taking the CRC again yields 0.
pub fn crc15(bits: impl IntoIterator<Item = bool>) -> u16 {
    let mut register: u16 = 0;
    for bit in bits {
        register = crc15_step(register, bit);
    }
    register
}

/// SOF through the CRC sequence, before stuffing, one `bool` per bit (`false` is dominant).
pub fn unstuffed_bits(frame: &CanFrame) -> Vec<bool> {
    unstuffed_region(frame).iter().collect()
}

/// SOF through the CRC sequence as sent, stuff bits included.
pub fn stuffed_bits(frame: &CanFrame) -> Vec<bool> {
    let region = unstuffed_region(frame);
    let mut out = Vec::with_capacity(region.len as usize + region.len as usize / 4 + 1);
    let mut run = Run::default();
    for bit in region.iter() {
        out.push(bit);
        if let Some(stuff) = run.push(bit) {
            out.push(stuff);
        }
    }
    out
}

/// Removes the stuff bits from a stuffed sequence such as [`stuffed_bits`] returns.
///
/// A stuff bit that follows the last five equal bits of the sequence is removed as well.
pub fn destuff(stuffed: &[bool]) -> Result<Vec<bool>, StuffError> {
    let mut out = Vec::with_capacity(stuffed.len());
    let mut run = Run::default();
    for (position, &bit) in stuffed.iter().enumerate() {
        if run.len == STUFF_RUN {
            if bit == run.value {
                return Err(StuffError { position });
            }
            run = Run { value: bit, len: 1 };
            continue;
        }
        out.push(bit);
        run.extend(bit);
    }
    Ok(out)
}

/// The exact bit counts of `frame`, computed from its real bit sequence and CRC.
pub fn frame_bits(frame: &CanFrame) -> FrameBits {
    let region = unstuffed_region(frame);
    let stuff_bits = count_stuff_bits(region);
    let stuffed_region = region.len + stuff_bits;
    FrameBits {
        stuffed_region,
        stuff_bits,
        total: stuffed_region + FIXED_TAIL_BITS,
    }
}

/// The longest a frame with this format and data length can be, whatever its identifier and data.
///
/// The stuffed region has `L` bits before stuffing: 34 + 8n for a standard frame and 54 + 8n for an
/// extended one, where n is the number of data bytes on the wire (0 for a remote frame, whatever its
/// DLC). The first stuff bit needs 5 equal bits; because a stuff bit starts the next run, each later
/// one needs only 4 more, so there are at most 1 + ⌊(L − 5)/4⌋ = ⌊(L − 1)/4⌋ stuff bits
/// (Davis, Burns, Bril, Lukkien 2007, "Controller Area Network (CAN) schedulability analysis").
/// Hence standard: 47 + 8n + ⌊(33 + 8n)/4⌋, extended: 67 + 8n + ⌊(53 + 8n)/4⌋.
///
/// The bound is not tight: it ignores the fixed bits (IDE and r0; SRR, IDE, r1 and r0) and the CRC,
/// and no real frame reaches it. The `worst_case_bound_reachability` test in `tests/bit_lengths.rs`
/// gives the argument and checks it exhaustively for up to one data byte.
pub fn worst_case_bits(frame: &CanFrame) -> u32 {
    let data_bits = 8 * frame.data().len() as u32;
    let region = match frame.id() {
        CanId::Standard(_) => STANDARD_REGION_FIXED_BITS,
        CanId::Extended(_) => EXTENDED_REGION_FIXED_BITS,
    } + data_bits;
    region + (region - 1) / (STUFF_RUN - 1) + FIXED_TAIL_BITS
}

/// SOF, 11 id bits, RTR, IDE, r0, 4 DLC bits and 15 CRC bits.
const STANDARD_REGION_FIXED_BITS: u32 = 34;
/// SOF, 11 base id bits, SRR, IDE, 18 extension bits, RTR, r1, r0, 4 DLC bits and 15 CRC bits.
const EXTENDED_REGION_FIXED_BITS: u32 = 54;
const CRC_BITS: u32 = 15;

const fn crc15_step(register: u16, bit: bool) -> u16 {
    let feedback = bit ^ (register & 0x4000 != 0);
    let shifted = (register << 1) & 0x7FFF;
    if feedback {
        shifted ^ CRC15_POLYNOMIAL
    } else {
        shifted
    }
}

/// `CRC15_TABLE[b]` is the register after shifting 8 zero bits through a register holding `b` in its
/// top 8 bits. Because the CRC is linear, XOR-ing an input byte into the top of the register and
/// applying this table handles 8 bits in one step.
#[allow(
    clippy::indexing_slicing,
    reason = "const evaluation: an index out of bounds fails the build, it cannot panic at run time"
)]
const CRC15_TABLE: [u16; 256] = {
    let mut table = [0u16; 256];
    let mut byte = 0;
    while byte < 256 {
        let mut register = (byte as u16) << 7;
        let mut step = 0;
        while step < 8 {
            register = crc15_step(register, false);
            step += 1;
        }
        table[byte] = register;
        byte += 1;
    }
    table
};

/// The CRC-15 of all bits in `reg`: leading bits one at a time until the rest is whole bytes, then a
/// byte per table lookup. Gives the same result as [`crc15`] over `reg.iter()`.
fn crc15_of_register(reg: BitRegister) -> u16 {
    let lead = reg.len % 8;
    let mut register = 0u16;
    for i in (reg.len - lead..reg.len).rev() {
        register = crc15_step(register, (reg.bits >> i) & 1 == 1);
    }
    for byte_idx in (0..(reg.len - lead) / 8).rev() {
        let byte = ((reg.bits >> (8 * byte_idx)) & 0xFF) as u16;
        let top = (register >> 7) ^ byte;
        #[allow(clippy::indexing_slicing, reason = "a u8 indexes a table of 256 entries")]
        let next = CRC15_TABLE[usize::from(top as u8)];
        register = ((register << 8) & 0x7FFF) ^ next;
    }
    register
}

/// The stuffing state as a small number: `value · 5 + len` for a run of `len` (0–4) bits of `value`.
/// A run never stays at 5: the stuff bit that ends it starts a run of 1.
const STUFF_STATES: usize = 10;

/// `STUFF_TABLE[state][byte]` is the state after sending the 8 bits of `byte` (most significant first)
/// in the low 4 bits, and the number of stuff bits inserted among them in the high 4 bits.
#[allow(
    clippy::indexing_slicing,
    reason = "const evaluation: an index out of bounds fails the build, it cannot panic at run time"
)]
const STUFF_TABLE: [[u8; 256]; STUFF_STATES] = {
    let mut table = [[0u8; 256]; STUFF_STATES];
    let mut state = 0;
    while state < STUFF_STATES {
        let mut byte = 0;
        while byte < 256 {
            let mut run = Run {
                value: state >= 5,
                len: (state % 5) as u32,
            };
            let mut stuffs = 0u8;
            let mut bit = 8;
            while bit > 0 {
                bit -= 1;
                if run.push((byte >> bit) & 1 == 1).is_some() {
                    stuffs += 1;
                }
            }
            table[state][byte] = (stuffs << 4) | run.state() as u8;
            byte += 1;
        }
        state += 1;
    }
    table
};

/// The stuff bits a transmitter inserts into `reg` (ISO 11898-1, "Frame coding"): leading bits one
/// at a time until the rest is whole bytes, then a byte per table lookup.
fn count_stuff_bits(reg: BitRegister) -> u32 {
    let lead = reg.len % 8;
    let mut run = Run::default();
    let mut stuff_bits = 0;
    for i in (reg.len - lead..reg.len).rev() {
        if run.push((reg.bits >> i) & 1 == 1).is_some() {
            stuff_bits += 1;
        }
    }
    let mut state = run.state();
    for byte_idx in (0..(reg.len - lead) / 8).rev() {
        let byte = ((reg.bits >> (8 * byte_idx)) & 0xFF) as usize;
        // `state` is always below STUFF_STATES: it comes from `Run::state` or the table's low nibble,
        // both of which encode a run of 0–4 bits.
        #[allow(
            clippy::indexing_slicing,
            reason = "state < STUFF_STATES (see above) and byte is masked to 0..=255, the table's sizes"
        )]
        let entry = STUFF_TABLE[state][byte];
        stuff_bits += u32::from(entry >> 4);
        state = usize::from(entry & 0x0F);
    }
    stuff_bits
}

/// Up to 128 bits, first bit in the most significant used position. The longest region, an extended
/// frame with 8 data bytes, is 54 + 64 = 118 bits.
#[derive(Debug, Clone, Copy, Default)]
struct BitRegister {
    bits: u128,
    len: u32,
}

impl BitRegister {
    fn push(&mut self, value: u64, width: u32) {
        let mask = (1u128 << width) - 1;
        self.bits = (self.bits << width) | (u128::from(value) & mask);
        self.len += width;
    }

    fn iter(self) -> impl Iterator<Item = bool> {
        (0..self.len).rev().map(move |i| (self.bits >> i) & 1 == 1)
    }
}

/// ISO 11898-1, "Data frame" and "Remote frame": SOF, arbitration field, control
/// field, data field (absent in remote frames), then the CRC sequence over everything before it.
fn unstuffed_region(frame: &CanFrame) -> BitRegister {
    let mut reg = BitRegister::default();
    reg.push(0, 1); // SOF, dominant.
    let rtr = u64::from(frame.is_remote());
    match frame.id() {
        CanId::Standard(id) => {
            reg.push(u64::from(id.as_raw()), 11);
            reg.push(rtr, 1);
            reg.push(0, 1); // IDE dominant: base format.
            reg.push(0, 1); // r0.
        }
        CanId::Extended(id) => {
            reg.push(u64::from(id.base()), 11);
            reg.push(1, 1); // SRR, always recessive.
            reg.push(1, 1); // IDE recessive: extended format.
            reg.push(u64::from(id.extension()), 18);
            reg.push(rtr, 1);
            reg.push(0, 1); // r1.
            reg.push(0, 1); // r0.
        }
    }
    reg.push(u64::from(frame.dlc()), 4);
    for &byte in frame.data() {
        reg.push(u64::from(byte), 8);
    }
    let crc = crc15_of_register(reg);
    reg.push(u64::from(crc), CRC_BITS);
    reg
}

/// The run of equal bits a transmitter is counting for stuffing (ISO 11898-1, "Frame coding").
#[derive(Debug, Clone, Copy, Default)]
struct Run {
    value: bool,
    len: u32,
}

impl Run {
    const fn extend(&mut self, bit: bool) {
        if self.len > 0 && bit == self.value {
            self.len += 1;
        } else {
            *self = Run { value: bit, len: 1 };
        }
    }

    /// Counts `bit` as sent; returns the stuff bit to send after it, if one is due. The stuff bit is
    /// the first bit of the next run.
    const fn push(&mut self, bit: bool) -> Option<bool> {
        self.extend(bit);
        if self.len == STUFF_RUN {
            let stuff = !bit;
            *self = Run { value: stuff, len: 1 };
            Some(stuff)
        } else {
            None
        }
    }

    /// The state number used by [`STUFF_TABLE`].
    const fn state(self) -> usize {
        self.value as usize * 5 + self.len as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::id::{ExtendedId, StandardId};

    fn bits(text: &str) -> Vec<bool> {
        text.chars()
            .filter(|c| !c.is_whitespace())
            .map(|c| c == '1')
            .collect()
    }

    fn bytes_msb_first(data: &[u8]) -> Vec<bool> {
        data.iter()
            .flat_map(|byte| (0..8).rev().map(move |i| (byte >> i) & 1 == 1))
            .collect()
    }

    fn std_frame(id: u16, data: &[u8]) -> CanFrame {
        CanFrame::new(StandardId::new(id).unwrap(), data).unwrap()
    }

    #[test]
    fn crc15_matches_the_published_check_value() {
        // The CRC catalogue's "CRC-15/CAN" entry: check value over the ASCII string "123456789".
        assert_eq!(crc15(bytes_msb_first(b"123456789")), 0x059E);
        assert_eq!(crc15([]), 0);
        assert_eq!(crc15([false; 40]), 0);
    }

    /// Worked by hand (polynomial long division, not a shift register): the CANopen SYNC frame,
    /// standard id 0x080, DLC 0.
    ///
    /// ```text
    /// SOF  ID 0x080      RTR IDE r0 DLC
    /// 0    00010000000   0   0   0  0000          -> 19 bits M(x)
    /// M(x)·x¹⁵ mod (x¹⁵+x¹⁴+x¹⁰+x⁸+x⁷+x⁴+x³+1) = 001110000000101 = 0x1C05
    /// region (34 bits): 0000100000000000000 001110000000101
    /// runs:             0000 1 [0 ×16] 111 [0 ×7] 1 0 1
    /// stuffed (38):     00001 00000[1] 00000[1] 00000[1] 0 111 00000[1] 00 101
    /// ```
    /// Four stuff bits (at stuffed positions 10, 16, 22 and 32), so 34 + 4 + 13 = 51 bits.
    #[test]
    fn hand_worked_sync_frame() {
        let frame = std_frame(0x080, &[]);
        assert_eq!(
            unstuffed_bits(&frame),
            bits("0000100000000000000 001110000000101")
        );
        assert_eq!(crc15(bits("0000100000000000000")), 0x1C05);
        assert_eq!(
            stuffed_bits(&frame),
            bits("00001 000001 000001 000001 0111 000001 00101")
        );
        assert_eq!(
            frame_bits(&frame),
            FrameBits {
                stuffed_region: 38,
                stuff_bits: 4,
                total: 51
            }
        );
    }

    #[test]
    fn remote_frame_sends_dlc_but_no_data() {
        let remote = CanFrame::remote(StandardId::new(0x701).unwrap(), 8).unwrap();
        let region = unstuffed_bits(&remote);
        assert_eq!(region.len(), 34);
        // RTR recessive, IDE and r0 dominant, DLC 1000.
        assert_eq!(region[12..19], bits("1 0 0 1000")[..]);
        assert_eq!(worst_case_bits(&remote), 47 + 33 / 4);
    }

    #[test]
    fn extended_frame_layout() {
        let id = ExtendedId::new(0x1555_5555).unwrap();
        let frame = CanFrame::new(id, &[0xA5]).unwrap();
        let region = unstuffed_bits(&frame);
        assert_eq!(region.len(), 54 + 8);
        // SOF, base id, SRR, IDE, extension, RTR, r1, r0, DLC, data.
        let expected_head = bits("0 10101010101 1 1 010101010101010101 0 0 0 0001 10100101");
        assert_eq!(region[..expected_head.len()], expected_head[..]);
        assert_eq!(worst_case_bits(&frame), 67 + 8 + (53 + 8) / 4);
    }

    #[test]
    fn destuff_rejects_six_equal_bits() {
        assert_eq!(destuff(&bits("0000000")), Err(StuffError { position: 5 }));
        assert_eq!(destuff(&bits("11111 0 1")), Ok(bits("11111 1")));
        // A trailing stuff bit after the last run of five is removed.
        assert_eq!(destuff(&bits("00000 1")), Ok(bits("00000")));
    }

    proptest::proptest! {
        #[test]
        fn table_driven_crc_and_stuffing_match_bit_by_bit(bits: u128, len in 0u32..=128) {
            let reg = BitRegister { bits: if len == 128 { bits } else { bits & ((1u128 << len) - 1) }, len };
            proptest::prop_assert_eq!(crc15_of_register(reg), crc15(reg.iter()));
            let mut run = Run::default();
            let bitwise = reg.iter().filter(|&bit| run.push(bit).is_some()).count() as u32;
            proptest::prop_assert_eq!(count_stuff_bits(reg), bitwise);
        }
    }

    #[test]
    fn stuff_bit_starts_the_next_run() {
        // 00000 [1] 1111 [0]: the stuff bit plus four ones make the next run of five.
        let region = bits("00000 1111");
        let mut run = Run::default();
        let stuffs: Vec<_> = region.iter().filter_map(|&b| run.push(b)).collect();
        assert_eq!(stuffs, vec![true, false]);
    }
}

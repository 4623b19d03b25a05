//! Exact frame lengths checked against independently worked examples, plus the invariants of CRC-15
//! and bit stuffing over random frames.

use canopener_can::bits::{
    FIXED_TAIL_BITS, FrameBits, crc15, destuff, frame_bits, stuffed_bits, unstuffed_bits, worst_case_bits,
};
use canopener_can::{Bitrate, CanFrame, ExtendedId, StandardId};
use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;

fn std_frame(id: u16, data: &[u8]) -> CanFrame {
    CanFrame::new(StandardId::new(id).unwrap(), data).unwrap()
}

fn ext_frame(id: u32, data: &[u8]) -> CanFrame {
    CanFrame::new(ExtendedId::new(id).unwrap(), data).unwrap()
}

/// Stuff bits a transmitter inserts into `region` (ISO 11898-1 "Frame coding"), written here as a
/// plain run counter so that tests can feed it regions no real frame produces.
fn count_stuff_bits(region: &[bool]) -> u32 {
    let (mut value, mut len, mut stuff) = (false, 0u32, 0u32);
    for &bit in region {
        if len > 0 && bit == value {
            len += 1;
        } else {
            (value, len) = (bit, 1);
        }
        if len == 5 {
            stuff += 1;
            (value, len) = (!bit, 1);
        }
    }
    stuff
}

/// Lengths from the bus-limits reference (§4): an exact encoder written independently of this crate.
#[test]
fn canopen_sdo_frames_match_the_reference() {
    let cases: [(u16, [u8; 8], u32, &str); 4] = [
        (
            0x622,
            [0x23, 0x04, 0x20, 0x00, 0x9C, 0xFF, 0xFF, 0xFF],
            121,
            "expedited download request",
        ),
        (
            0x5A2,
            [0x60, 0x04, 0x20, 0x00, 0x00, 0x00, 0x00, 0x00],
            124,
            "download response",
        ),
        (
            0x622,
            [0x40, 0x08, 0x10, 0x00, 0x00, 0x00, 0x00, 0x00],
            122,
            "upload request",
        ),
        (
            0x5A2,
            [0x20, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00],
            124,
            "segment ack",
        ),
    ];
    for (id, data, expected, what) in cases {
        assert_eq!(
            frame_bits(&std_frame(id, &data)).total,
            expected,
            "{what} {id:03X}"
        );
    }
}

/// The reference's "id 0x000 + all-zero data" column, DLC 0 to 8.
#[test]
fn all_zero_frames_match_the_reference() {
    let expected = [53, 59, 69, 79, 89, 98, 107, 117, 127];
    for (dlc, &total) in expected.iter().enumerate() {
        let frame = std_frame(0x000, &[0; 8][..dlc]);
        assert_eq!(frame_bits(&frame).total, total, "DLC {dlc}");
    }
}

/// Worked by hand: heartbeat of node 1 in state operational, `701#05`.
///
/// ```text
/// SOF ID 0x701     RTR IDE r0 DLC  data
/// 0   11100000001  0   0   0  0001 00000101      -> 27 bits
/// CRC = M(x)·x¹⁵ mod (x¹⁵+x¹⁴+x¹⁰+x⁸+x⁷+x⁴+x³+1) = 100110100001110 = 0x4D0E (by long division)
/// region (42): 011100000001000000100000101 100110100001110
/// stuffed:     0111 00000[1] 001 00000[1] 0 1 00000[1] 101 100110100001110
/// the runs of five: ID7..ID3; RTR, IDE, r0, DLC3, DLC2; data bits 7..3
/// ```
/// 3 stuff bits: 42 + 3 + 13 = 58 bits, 58 µs at 1 Mbit/s.
#[test]
fn hand_worked_heartbeat() {
    let frame = std_frame(0x701, &[0x05]);
    let bits = |text: &str| {
        text.chars()
            .filter(|c| *c != ' ')
            .map(|c| c == '1')
            .collect::<Vec<_>>()
    };
    assert_eq!(
        unstuffed_bits(&frame),
        bits("011100000001000000100000101 100110100001110")
    );
    assert_eq!(crc15(bits("011100000001000000100000101")), 0x4D0E);
    assert_eq!(
        stuffed_bits(&frame),
        bits("0111 000001 001 000001 0 1 000001 101 100110100001110")
    );
    assert_eq!(
        frame_bits(&frame),
        FrameBits {
            stuffed_region: 45,
            stuff_bits: 3,
            total: 58
        }
    );
    assert_eq!(Bitrate::M1.frame_duration(&frame).as_micros(), 58);
}

#[test]
fn worst_case_bound_formulas() {
    for n in 0..=8u32 {
        let data = [0u8; 8];
        let std = std_frame(0x123, &data[..n as usize]);
        let ext = ext_frame(0x123, &data[..n as usize]);
        assert_eq!(worst_case_bits(&std), 47 + 8 * n + (33 + 8 * n) / 4);
        assert_eq!(worst_case_bits(&ext), 67 + 8 * n + (53 + 8 * n) / 4);
    }
    // The reference table's bound column for standard frames: 55 for DLC 0, 135 for DLC 8.
    assert_eq!(worst_case_bits(&std_frame(0, &[])), 55);
    assert_eq!(worst_case_bits(&std_frame(0, &[0; 8])), 135);
}

/// Is the bound ⌊(L − 1)/4⌋ stuff bits ever reached? Almost never, and here is why.
///
/// To reach it the L-bit region must be: a first run of 5 equal bits, then runs of exactly 4 bits
/// that each join the stuff bit before them (so the runs alternate), and L − 1 ≡ 1 (mod 4) leaves one
/// spare bit. The spare bit can buy exactly one "break" (a run of 5 bits with the previous run's value
/// instead of 4 with the stuff bit's value), or a first run that starts one bit late, or one unused
/// bit at the end. SOF is dominant, so with no break the run boundaries (bit positions counted from
/// SOF = 0) sit at 5, 9, 13, …
///
/// * Standard frames: IDE (13) and r0 (14) are both dominant. Without a break, 13–16 is a run with
///   the value of the run 5–8 inverted twice, i.e. recessive: impossible. A break before position 13
///   makes 9–13 or 10–13 recessive: impossible again. The only option is a break at the run starting
///   at 13: 13–17 dominant (IDE, r0, DLC3..1 = 0), which forces DLC0 = 1 and then fixes every bit:
///   id 0x078 (0–4 = 0, 5–8 = 1, 9–12 = 0 with RTR = 0), DLC 1, data 0xE1, and CRC 0x70F0. Whether
///   the bound is reached thus hangs on a single CRC value; it is not (tested below), so no standard
///   frame of any DLC reaches the bound.
/// * Extended frames: SRR and IDE (12, 13) are both recessive and r1, r0 (33, 34) both dominant. With
///   boundaries at ≡ 1 (mod 4) one falls on 13; shifting by the spare bit before 13 moves them to
///   ≡ 2 (mod 4), and then one falls on 34. So no extended frame reaches the bound either.
///
/// Exhaustive search confirms it for every standard frame with at most one data byte.
#[test]
fn worst_case_bound_reachability() {
    // The single candidate of the argument above reaches the bound only with CRC 0x70F0.
    let candidate = std_frame(0x078, &[0xE1]);
    let bound = worst_case_bits(&candidate);
    let mut region = unstuffed_bits(&candidate);
    let crc_at = region.len() - 15;
    let ideal_crc: Vec<bool> = (0..15).rev().map(|i| (0x70F0u16 >> i) & 1 == 1).collect();
    region.splice(crc_at.., ideal_crc);
    assert_eq!(
        region.len() as u32 + count_stuff_bits(&region) + FIXED_TAIL_BITS,
        bound
    );
    let real_crc = crc15(unstuffed_bits(&candidate)[..crc_at].iter().copied());
    assert_ne!(real_crc, 0x70F0);
    assert!(frame_bits(&candidate).total < bound);

    let mut longest = [0u32; 2];
    for id in 0..=0x7FF {
        let sid = StandardId::new(id).unwrap();
        for dlc in 0..=8 {
            let remote = CanFrame::remote(sid, dlc).unwrap();
            longest[0] = longest[0].max(frame_bits(&remote).total);
        }
        longest[0] = longest[0].max(frame_bits(&std_frame(id, &[])).total);
        for byte in 0..=0xFF {
            longest[1] = longest[1].max(frame_bits(&std_frame(id, &[byte])).total);
        }
    }
    println!(
        "longest standard frames: DLC 0 {} bits (bound 55), DLC 1 {} bits (bound 65)",
        longest[0], longest[1]
    );
    assert!(longest[0] < 55 && longest[0] >= 53, "DLC 0: {}", longest[0]);
    assert!(longest[1] < 65 && longest[1] >= 59, "DLC 1: {}", longest[1]);
}

fn any_frame() -> impl Strategy<Value = CanFrame> {
    prop_oneof![
        5 => canopener_can::strategy::any_frame(),
        // Frames full of equal bits stuff the most; random bytes rarely produce them.
        2 => (canopener_can::strategy::any_id(), 0usize..=8, prop::sample::select(vec![0x00u8, 0xFF, 0x0F, 0xF0, 0x78, 0x87]))
            .prop_map(|(id, n, byte)| CanFrame::new(id, &[byte; 8][..n]).unwrap()),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 2_000,
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource("proptest-regressions"))),
        ..ProptestConfig::default()
    })]

    #[test]
    fn unstuffed_length_is_fixed_by_format_and_data(frame in any_frame()) {
        let n = 8 * frame.data().len() as u32;
        let (region, unstuffed_total) =
            if frame.id().is_extended() { (54 + n, 67 + n) } else { (34 + n, 47 + n) };
        prop_assert_eq!(unstuffed_bits(&frame).len() as u32, region);
        prop_assert_eq!(region + FIXED_TAIL_BITS, unstuffed_total);
        let bits = frame_bits(&frame);
        prop_assert_eq!(bits.total, unstuffed_total + bits.stuff_bits);
    }

    #[test]
    fn frame_bits_agrees_with_the_stuffed_sequence(frame in any_frame()) {
        let stuffed = stuffed_bits(&frame);
        let bits = frame_bits(&frame);
        prop_assert_eq!(bits.stuffed_region as usize, stuffed.len());
        prop_assert_eq!(bits.stuff_bits as usize, stuffed.len() - unstuffed_bits(&frame).len());
        prop_assert_eq!(bits.total, bits.stuffed_region + FIXED_TAIL_BITS);
        // Strictly below: `worst_case_bound_reachability` shows no frame reaches the bound.
        prop_assert!(bits.total < worst_case_bits(&frame), "{} >= {}", bits.total, worst_case_bits(&frame));
    }

    #[test]
    fn destuffing_restores_the_original(frame in any_frame()) {
        prop_assert_eq!(destuff(&stuffed_bits(&frame)), Ok(unstuffed_bits(&frame)));
    }

    #[test]
    fn stuffed_region_never_has_six_equal_bits(frame in any_frame()) {
        let stuffed = stuffed_bits(&frame);
        prop_assert!(stuffed.windows(6).all(|w| w.iter().any(|&b| b != w[0])));
    }

    #[test]
    fn crc_over_sequence_and_its_own_crc_is_zero(frame in any_frame()) {
        let region = unstuffed_bits(&frame);
        prop_assert_eq!(crc15(region.iter().copied()), 0);
        let (body, crc_bits) = region.split_at(region.len() - 15);
        let crc = crc_bits.iter().fold(0u16, |acc, &b| (acc << 1) | u16::from(b));
        prop_assert_eq!(crc15(body.iter().copied()), crc);
    }

    #[test]
    fn crc_detects_any_single_bit_error(frame in any_frame(), flip in 0usize..118) {
        let mut region = unstuffed_bits(&frame);
        let flip = flip % region.len();
        region[flip] = !region[flip];
        prop_assert_ne!(crc15(region), 0);
    }
}

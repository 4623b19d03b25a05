//! Prints the "physical CAN limits" section of BENCHMARKS.md: frame lengths and the frame and SDO rates a
//! bus allows, all computed from `canopener_can::bits` (real CRC-15, real bit stuffing).
//!
//! ```text
//! cargo run --release -p canopener-can --example can_limits > bench-results/can_limits.md
//! ```
//!
//! Deterministic: the "random" payloads come from a fixed-seed xorshift generator, so two runs print the
//! same text.

// A report generator for bench/run.sh: it prints its results.
#![allow(clippy::print_stdout)]

use canopener_can::bits::{frame_bits, worst_case_bits};
use canopener_can::{Bitrate, CanFrame, StandardId};

/// How many random frames the average length is taken over.
const RANDOM_FRAMES: u64 = 1_000_000;
/// The payload of the segmented transfer the section quotes (bytes).
const SEGMENTED_BYTES: usize = 889;

fn main() {
    let rate = Bitrate::M1;
    let per_second = |bits: f64| f64::from(rate.bits_per_second()) / bits;

    // The shortest DLC-8 frame: a standard ID and data whose bits never need a stuff bit.
    let no_stuff = CanFrame::new(sid(0x155), &[0x55; 8]).unwrap_or_else(|_| unreachable_frame());
    let no_stuff_bits = frame_bits(&no_stuff);
    let worst = worst_case_bits(&no_stuff);

    let mut state = 0x9E37_79B9_7F4A_7C15_u64;
    let mut total_bits = 0u64;
    for _ in 0..RANDOM_FRAMES {
        let word = xorshift(&mut state);
        let id = (xorshift(&mut state) & 0x7FF) as u16;
        let frame = CanFrame::new(sid(id), &word.to_le_bytes()).unwrap_or_else(|_| unreachable_frame());
        total_bits += u64::from(frame_bits(&frame).total);
    }
    let random_mean = total_bits as f64 / RANDOM_FRAMES as f64;

    // The hub's bus-capacity load (crates/canopener-hub/examples/hub_load.rs): id 0x123, DLC 8, the
    // frame counter as little-endian payload.
    let hub_frames = 100_000u64;
    let hub_bits: u64 = (0..hub_frames)
        .map(|i| {
            let frame = CanFrame::new(sid(0x123), &i.to_le_bytes()).unwrap_or_else(|_| unreachable_frame());
            u64::from(frame_bits(&frame).total)
        })
        .sum();
    let hub_mean = hub_bits as f64 / hub_frames as f64;

    // An expedited SDO exchange: upload request and its response to node 5 (CiA 301 §7.2.4.3.3).
    let request = CanFrame::new(sid(0x605), &[0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0])
        .unwrap_or_else(|_| unreachable_frame());
    let response = CanFrame::new(sid(0x585), &[0x43, 0x00, 0x10, 0x00, 0x91, 0x01, 0x0F, 0x00])
        .unwrap_or_else(|_| unreachable_frame());
    let exchange_bits = frame_bits(&request).total + frame_bits(&response).total;

    // A segmented upload of SEGMENTED_BYTES bytes: initiate request/response, then one request and one
    // 7-byte segment response per segment (CiA 301 §7.2.4.3.4); data bytes pseudo-random.
    let segments = SEGMENTED_BYTES.div_ceil(7);
    let mut segmented_bits = exchange_bits;
    for segment in 0..segments {
        let toggle = ((segment % 2) as u8) << 4;
        let last = segment + 1 == segments;
        let used = if last { SEGMENTED_BYTES - 7 * segment } else { 7 };
        let command = toggle | (((7 - used) as u8) << 1) | u8::from(last);
        let mut data = [0u8; 8];
        data[0] = command;
        let word = xorshift(&mut state).to_le_bytes();
        data[1..8].copy_from_slice(&word[..7]);
        let ask = CanFrame::new(sid(0x605), &[0x60 | toggle, 0, 0, 0, 0, 0, 0, 0])
            .unwrap_or_else(|_| unreachable_frame());
        let answer = CanFrame::new(sid(0x585), &data).unwrap_or_else(|_| unreachable_frame());
        segmented_bits += frame_bits(&ask).total + frame_bits(&answer).total;
    }

    println!(
        "Printed by `cargo run --release -p canopener-can --example can_limits` (exact frame lengths from"
    );
    println!(
        "`canopener_can::bits`: real CRC-15, real bit stuffing, checked against independently computed lengths)."
    );
    println!();
    println!("| at 1 Mbit/s | bits per frame | frames/s |");
    println!("|---|---:|---:|");
    println!(
        "| DLC 8, no stuff bits (the shortest) | {} | {:.0} |",
        no_stuff_bits.total,
        per_second(f64::from(no_stuff_bits.total))
    );
    println!(
        "| DLC 8, random identifier and payload (mean of {RANDOM_FRAMES} frames) | {random_mean:.1} | {:.0} |",
        per_second(random_mean)
    );
    println!(
        "| DLC 8, worst-case stuffing (the longest) | {worst} | {:.0} |",
        per_second(f64::from(worst))
    );
    println!(
        "| the hub's bus-capacity load: id 0x123, DLC 8, counter payload (mean of {hub_frames}) | {hub_mean:.1} | {:.1} |",
        per_second(hub_mean)
    );
    println!();
    println!(
        "An expedited SDO upload (request + response, {exchange_bits} bits) allows at most **{:.0} transfers/s** on a \
         1 Mbit/s bus at zero turnaround time; a {SEGMENTED_BYTES}-byte segmented upload ({segments} segments, \
         {} frames) needs **{:.1} ms** of wire time.",
        per_second(f64::from(exchange_bits)),
        2 * segments + 2,
        rate.bits_duration(u64::from(segmented_bits)).as_secs_f64() * 1e3
    );
}

fn sid(id: u16) -> StandardId {
    StandardId::new(id).unwrap_or(StandardId::MAX)
}

fn unreachable_frame() -> CanFrame {
    unreachable!("eight data bytes always fit a classical CAN frame")
}

/// Marsaglia's xorshift64: a fixed, dependency-free sequence so the output never changes between runs.
fn xorshift(state: &mut u64) -> u64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    *state
}

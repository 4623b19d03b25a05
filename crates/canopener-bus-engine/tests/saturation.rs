//! Acceptance: a saturated 1 Mbit/s bus delivers frames at the exact theoretical rate.
//!
//! Run with `cargo test -p canopener-bus-engine --test saturation -- --nocapture` to see the numbers.

// Prints the measured frame rates beside the asserted ones.
#![allow(clippy::print_stdout, clippy::print_stderr)]

use std::time::Duration;

use canopener_bus_engine::{BusConfig, BusEngine, Delivery};
use canopener_can::bits::frame_bits;
use canopener_can::{Bitrate, CanFrame, Instant, StandardId};

/// At least this much virtual time is simulated.
const RUN: Duration = Duration::from_secs(1);

/// SplitMix64: a seeded generator so the random payloads are the same on every run.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

/// Keeps every port's queue topped up and drives the bus on virtual time until `RUN` has passed.
/// Returns every delivery in bus order.
fn saturate(
    bus: &mut BusEngine,
    n_ports: usize,
    mut next_frame: impl FnMut(usize) -> CanFrame,
) -> Vec<Delivery> {
    let ports: Vec<_> = (0..n_ports).map(|_| bus.attach()).collect();
    let end = Instant::ZERO + RUN;
    let mut now = Instant::ZERO;
    let mut deliveries = Vec::new();
    while now <= end {
        for (idx, &port) in ports.iter().enumerate() {
            while bus.pending(port) < 3 {
                bus.submit(now, port, next_frame(idx)).unwrap();
            }
        }
        // Saturated means there is always a deadline; running out of work would be a bug here.
        now = bus.poll_timeout().unwrap();
        bus.handle_timeout(now);
        deliveries.extend(std::iter::from_fn(|| bus.poll_delivery()));
    }
    deliveries
}

struct Measured {
    frames: usize,
    elapsed: Duration,
    rate: f64,
    theoretical: f64,
    mean_bits: f64,
}

/// Measured rate: frames over the bus time from the first SOF to the end of the last intermission.
/// Theoretical rate: the same frames, each taking exactly its stuffed length in bit times, back to back.
fn measure(bitrate: Bitrate, deliveries: &[Delivery]) -> Measured {
    let first = deliveries.first().unwrap();
    let last = deliveries.last().unwrap();
    let elapsed = (last.start + bitrate.frame_duration(&last.frame)) - first.start;
    let total_bits: u64 = deliveries
        .iter()
        .map(|d| u64::from(frame_bits(&d.frame).total))
        .sum();
    let frames = deliveries.len();
    let rate = frames as f64 / elapsed.as_secs_f64();
    let theoretical = frames as f64 * f64::from(bitrate.bits_per_second()) / total_bits as f64;
    Measured {
        frames,
        elapsed,
        rate,
        theoretical,
        mean_bits: total_bits as f64 / frames as f64,
    }
}

fn report(label: &str, m: &Measured) {
    println!(
        "{label}: {} frames in {:.6} s of bus time = {:.2} frames/s; theoretical {:.2} frames/s \
         ({:.3} bits/frame on average); deviation {:+.4} %",
        m.frames,
        m.elapsed.as_secs_f64(),
        m.rate,
        m.theoretical,
        m.mean_bits,
        100.0 * (m.rate - m.theoretical) / m.theoretical
    );
}

fn assert_saturated(bitrate: Bitrate, bus: &BusEngine, deliveries: &[Delivery], m: &Measured) {
    assert!(m.elapsed >= RUN, "simulated only {:?}", m.elapsed);
    let deviation = (m.rate - m.theoretical).abs() / m.theoretical;
    assert!(
        deviation < 0.01,
        "measured {} frames/s, theoretical {}",
        m.rate,
        m.theoretical
    );
    // No idle gap anywhere: every frame starts the instant the previous one frees the bus.
    for pair in deliveries.windows(2) {
        assert_eq!(
            pair[1].start,
            pair[0].start + bitrate.frame_duration(&pair[0].frame)
        );
    }
    // Every delivered frame is counted, and the bus was busy for all of the elapsed time.
    assert_eq!(bus.stats().frames, deliveries.len() as u64);
    assert_eq!(bus.stats().busy, m.elapsed);
}

#[test]
fn saturated_1m_bus_with_dlc8_frames_runs_at_the_exact_frame_rate() {
    let bitrate = Bitrate::M1;
    let mut bus = BusEngine::new(BusConfig { bitrate });
    // Four PDO producers, each with its own fixed payload.
    let frames: Vec<CanFrame> = (0..4u8)
        .map(|i| {
            let id = StandardId::new(0x181 + u16::from(i)).unwrap();
            CanFrame::new(id, &[i, 0x10, 0x20, 0x30, 0x40, 0x50, 0x60, 0x70]).unwrap()
        })
        .collect();
    let deliveries = saturate(&mut bus, frames.len(), |port| frames[port]);
    let m = measure(bitrate, &deliveries);
    report("1 Mbit/s, 4 ports, fixed DLC-8 frames", &m);
    assert_saturated(bitrate, &bus, &deliveries, &m);
    // Priority: the lowest id always has a frame ready, so it wins every arbitration.
    assert!(deliveries.iter().all(|d| d.frame.id().as_raw() == 0x181));
    // And the rate is well below the 9009 frames/s that ignoring stuff bits (111 bits) would claim.
    assert!(m.rate < 1e6 / 111.0);
}

#[test]
fn saturated_1m_bus_with_random_payloads_runs_at_the_exact_frame_rate() {
    let bitrate = Bitrate::M1;
    let mut bus = BusEngine::new(BusConfig { bitrate });
    let mut rng = SplitMix64(0x00C0_FFEE);
    // Eight ports with random ids and payloads: every arbitration has different contenders.
    let deliveries = saturate(&mut bus, 8, |_| {
        let id = StandardId::new((rng.next() % 0x800) as u16).unwrap();
        CanFrame::new(id, &rng.next().to_le_bytes()).unwrap()
    });
    let m = measure(bitrate, &deliveries);
    report("1 Mbit/s, 8 ports, random ids and DLC-8 payloads", &m);
    assert_saturated(bitrate, &bus, &deliveries, &m);
    let distinct_lengths: std::collections::BTreeSet<u32> =
        deliveries.iter().map(|d| frame_bits(&d.frame).total).collect();
    assert!(
        distinct_lengths.len() > 3,
        "payloads should vary the stuffed length: {distinct_lengths:?}"
    );
}

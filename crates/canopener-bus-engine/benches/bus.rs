//! Simulated CAN frames per second of CPU time: a saturated 1 Mbit/s bus driven on virtual time.
//!
//! Criterion reports the throughput in frames (elements) per second; each frame is one submit, one
//! arbitration, one delivery and the `poll_timeout`/`handle_timeout` calls a virtual-time driver makes.

use std::hint::black_box;

use canopener_bus_engine::{BusConfig, BusEngine};
use canopener_can::{Bitrate, CanFrame, Instant, StandardId};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

const FRAMES: u64 = 10_000;

/// Keeps every port's queue non-empty and runs the bus until `FRAMES` frames were delivered.
fn saturate(n_ports: u16) -> u64 {
    let mut bus = BusEngine::new(BusConfig { bitrate: Bitrate::M1 });
    let ports: Vec<_> = (0..n_ports).map(|_| bus.attach()).collect();
    let frames: Vec<_> = (0..n_ports)
        .map(|i| {
            let id = StandardId::new(0x181 + i).unwrap_or(StandardId::MAX);
            CanFrame::new(id, &[i as u8, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77]).unwrap()
        })
        .collect();
    let mut now = Instant::ZERO;
    let mut delivered = 0;
    while delivered < FRAMES {
        for (&port, &frame) in ports.iter().zip(&frames) {
            if bus.pending(port) == 0 {
                bus.submit(now, port, frame).unwrap();
            }
        }
        let Some(deadline) = bus.poll_timeout() else { break };
        now = deadline;
        bus.handle_timeout(now);
        while let Some(delivery) = bus.poll_delivery() {
            black_box(delivery);
            delivered += 1;
        }
    }
    delivered
}

fn bench_saturated_bus(c: &mut Criterion) {
    let mut group = c.benchmark_group("saturated_1M_dlc8");
    group.throughput(Throughput::Elements(FRAMES));
    for n_ports in [2u16, 8, 32] {
        group.bench_with_input(BenchmarkId::new("ports", n_ports), &n_ports, |b, &n| {
            b.iter(|| saturate(black_box(n)))
        });
    }
    group.finish();
}

criterion_group!(benches, bench_saturated_bus);
criterion_main!(benches);

//! Cost of `frame_bits`, which the bus simulator calls once per frame: the shortest (standard, DLC 0)
//! and the longest (extended, DLC 8) bit sequences.

use std::hint::black_box;

use canopener_can::bits::frame_bits;
use canopener_can::{CanFrame, ExtendedId, StandardId};
use criterion::{Criterion, criterion_group, criterion_main};

fn bench_frame_bits(c: &mut Criterion) {
    let frames = [
        (
            "standard_dlc0",
            CanFrame::new(StandardId::new(0x080).unwrap(), &[]).unwrap(),
        ),
        (
            "standard_dlc8",
            CanFrame::new(
                StandardId::new(0x622).unwrap(),
                &[0x23, 4, 0x20, 0, 0x9C, 0xFF, 0xFF, 0xFF],
            )
            .unwrap(),
        ),
        (
            "extended_dlc0",
            CanFrame::new(ExtendedId::new(0x18FF_1234).unwrap(), &[]).unwrap(),
        ),
        (
            "extended_dlc8",
            CanFrame::new(ExtendedId::new(0x18FF_1234).unwrap(), &[0x55; 8]).unwrap(),
        ),
    ];
    let mut group = c.benchmark_group("frame_bits");
    for (name, frame) in frames {
        group.bench_function(name, |b| b.iter(|| frame_bits(black_box(&frame))));
    }
    group.finish();
}

criterion_group!(benches, bench_frame_bits);
criterion_main!(benches);

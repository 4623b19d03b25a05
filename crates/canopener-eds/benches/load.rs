//! EDS load time (`canopener_eds::load`: lossless syntax layer plus object dictionary model) on real
//! files of the shared corpus and on synthetic files of 100 to 20,000 objects.
//!
//! Every input is measured twice: in `eds_load/entries` criterion reports the throughput in
//! dictionary entries (objects plus sub-objects, as the model holds them) per second, in
//! `eds_load/bytes` in MB/s. The synthetic files come from `support/synthetic_eds.rs`, the same
//! generator `examples/load_timing.rs --generate` uses for the side-by-side run against python
//! canopen (`bench/eds_load.py`). The corpus files are vendored ones (`corpus/eds`), so every
//! checkout measures them.

// This is a benchmark, not library code: it reads the corpus it times, so the
// workspace's sans-IO bans do not apply here.
#![allow(clippy::disallowed_methods)]

use std::hint::black_box;
use std::time::Duration;

use canopener_testkit::corpus;
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

mod support {
    // `cargo clippy --all-targets` checks this harness-less bench with `cfg(test)` but drops `#[test]`
    // functions, which leaves only the imports of the generator's test module (its tests run as part
    // of `examples/load_timing.rs`).
    #[allow(unused_imports)]
    pub(crate) mod synthetic_eds;
}

use support::synthetic_eds::synthetic_eds;

/// Corpus files picked to span the range: a short generated file, python canopen's own quirky test
/// file (CompactSubObj, `$NODEID`, DCF values), a typical CANopenNode device, and the largest EDS.
const CORPUS_FILES: [(&str, &str); 4] = [
    (
        "small_ros2_simple",
        "ros-industrial__ros2_canopen__canopen_core__test__simple.eds",
    ),
    (
        "quirky_python_sample",
        "canopen-python__canopen__test__sample.eds",
    ),
    (
        "medium_canopennode_demo",
        "CANopenNode__CANopenDemo__demo__demoDevice.eds",
    ),
    ("large_sevcon_gen4", "brtiberio__Sevcon_gen4__Gen4.eds"),
];

const SYNTHETIC_OBJECTS: [usize; 4] = [100, 1_000, 5_000, 20_000];

/// One benchmark input: its name, its bytes and how many entries the model holds after loading.
struct Input {
    name: String,
    bytes: Vec<u8>,
    entries: u64,
}

fn entries_of(bytes: &[u8]) -> u64 {
    let loaded = canopener_eds::load(bytes);
    let entries = loaded.eds.objects.len() + loaded.eds.objects.values().map(|o| o.subs.len()).sum::<usize>();
    entries as u64
}

fn inputs() -> Vec<Input> {
    let mut inputs = Vec::new();
    for (name, file) in CORPUS_FILES {
        let path = corpus::eds(file);
        let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        inputs.push(Input {
            name: name.to_owned(),
            entries: entries_of(&bytes),
            bytes,
        });
    }
    for objects in SYNTHETIC_OBJECTS {
        let eds = synthetic_eds(objects);
        let bytes = eds.text.into_bytes();
        let entries = entries_of(&bytes);
        // A self-check of the generator, not input handling: a mismatch means the benchmark would
        // measure something other than what it claims.
        assert_eq!(
            entries,
            (eds.objects + eds.sub_objects) as u64,
            "synthetic file of {objects} objects does not load into the objects it was generated with"
        );
        inputs.push(Input {
            name: format!("synthetic_{objects}"),
            bytes,
            entries,
        });
    }
    inputs
}

fn bench_load(c: &mut Criterion) {
    let inputs = inputs();
    for (unit, throughput) in [
        (
            "entries",
            (|i: &Input| Throughput::Elements(i.entries)) as fn(&Input) -> Throughput,
        ),
        (
            "bytes",
            |i: &Input| Throughput::BytesDecimal(i.bytes.len() as u64),
        ),
    ] {
        let mut group = c.benchmark_group(format!("eds_load/{unit}"));
        group
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(4));
        for input in &inputs {
            // The 20,000-object file takes tens of milliseconds a load; fewer samples keep the run short.
            if input.bytes.len() > 1_000_000 {
                group.sample_size(20);
            } else {
                group.sample_size(60);
            }
            group.throughput(throughput(input));
            group.bench_with_input(
                BenchmarkId::from_parameter(&input.name),
                &input.bytes,
                |b, bytes| b.iter(|| canopener_eds::load(black_box(bytes))),
            );
        }
        group.finish();
    }
}

criterion_group!(benches, bench_load);
criterion_main!(benches);

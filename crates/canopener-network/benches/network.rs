//! How long the network tools take on a system of 100 devices (`test_data/hundred.graphml`): reading,
//! checking, drawing, and the localisation of every silent set a single cable cut gives (what the
//! monitor computes when a network's silence settles).

use std::collections::BTreeSet;
use std::hint::black_box;
use std::path::PathBuf;

use canopener_network::check::{DcfFound, check};
use canopener_network::localise::Localiser;
use canopener_network::wiring::{Faults, Wiring};
use criterion::{Criterion, criterion_group, criterion_main};

fn hundred() -> Vec<u8> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("test_data/hundred.graphml");
    canopener_testkit::fixture::read(path).expect("the 100-device fixture")
}

fn bench(c: &mut Criterion) {
    let bytes = hundred();
    let loaded = canopener_network::load(&bytes);
    c.bench_function("read 100 devices", |b| {
        b.iter(|| canopener_network::load(black_box(&bytes)))
    });
    c.bench_function("check 100 devices", |b| {
        b.iter(|| check(black_box(&loaded), &mut |_| DcfFound::Missing))
    });
    c.bench_function("draw 100 devices", |b| {
        b.iter(|| canopener_network::draw::svg(black_box(&loaded.topology)))
    });
    let topology = &loaded.topology;
    let wiring = Wiring::new(topology, 1, topology.default_position()).expect("network 1");
    let localiser = Localiser::new(topology, &wiring);
    let watched: BTreeSet<usize> = (0..wiring.devices().len()).collect();
    let silences: Vec<BTreeSet<usize>> = wiring
        .cables()
        .into_iter()
        .map(|cable| {
            let faults = Faults {
                cut: BTreeSet::from([cable]),
                ..Faults::none()
            };
            wiring.silent_under(&faults)
        })
        .collect();
    c.bench_function("localise every single cut of network 1", |b| {
        b.iter(|| {
            for silent in &silences {
                black_box(localiser.explain(&watched, silent));
            }
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);

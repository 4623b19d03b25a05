//! CPU time of the engine's pure parts on the shipped models: compiling a model (reading, names,
//! checks), exploring a state space, and synthesising a complete test graph. No bus and no clock:
//! the executor's own cost on a device run is in the `mbt_matrix` example's wall times.
//!
//! Before timing, each benchmark checks the size of what it measures (states, transitions), so a
//! model that changed shape stops the benchmark instead of being timed as if it had not.

use std::hint::black_box;

use canopener_mbt::compile::{Options, Source, compile};
use canopener_mbt::explore::explore;
use canopener_mbt::model::Model;
use canopener_mbt::shipped;
use canopener_mbt::synth::synthesize;
use criterion::{Criterion, criterion_group, criterion_main};

fn model(names: &[&str]) -> Model {
    let sources: Vec<Source> = names
        .iter()
        .map(|n| Source {
            origin: (*n).into(),
            text: shipped::text(n).expect("shipped").into(),
        })
        .collect();
    let options = Options {
        node_id: 5,
        ..Options::default()
    };
    let (model, report) = compile(&sources, &options, &|n| shipped::text(n).map(str::to_owned));
    model.unwrap_or_else(|| panic!("{report:#?}"))
}

fn benches(c: &mut Criterion) {
    c.bench_function("compile nmt+sdo", |b| b.iter(|| black_box(model(&["sdo"]))));

    let sdo = model(&["sdo"]);
    let (space, _) = explore(&sdo, 1_000_000);
    assert_eq!(space.lts.states, 3588, "the sdo+nmt state space changed shape");
    c.bench_function("explore nmt+sdo (3588 states)", |b| {
        b.iter(|| black_box(explore(&sdo, 1_000_000)))
    });

    let nmt = model(&["nmt"]);
    let (nmt_space, _) = explore(&nmt, 1_000_000);
    let purpose = nmt
        .purposes
        .iter()
        .find(|p| p.name == "stop_and_start")
        .expect("shipped purpose");
    assert!(synthesize(&nmt_space.lts, purpose).is_some());
    c.bench_function("synth nmt stop_and_start", |b| {
        b.iter(|| black_box(synthesize(&nmt_space.lts, purpose)))
    });
}

criterion_group!(mbt, benches);
criterion_main!(mbt);

//! The composition matrix of `docs/mbt.md`: every subset of the shipped CANopen models (every model
//! whose `Shipped::canopen` is set, so models added later join by themselves) against clean
//! simulated devices, and every catalogue fault a model catches alone against every composition
//! that contains the model.
//!
//! `cargo run --release -p canopener-runtime --example mbt_compose -- [OPTIONS]` prints Markdown:
//!
//! * `--steps N` (2000), `--seeds N` (5): each subset on each device, seeds 1..=N;
//! * `--eds A,B,...`: corpus EDS file names (default: the six below);
//! * `--fault-steps N` (1000), `--fault-seeds N` (5): the fault part, on the first device;
//! * `--subsets all|sample` (all): `sample` takes the single models, the compositions,
//!   every model with nmt, and the whole set (the CI sample);
//! * `--no-faults`: the clean part only;
//! * `--trace`: print the last steps of every run that does not pass (on stderr).
//!
//! A subset passes when every run is `pass`; a fault counts as caught by a model alone when at
//! least one of its fault seeds fails, and is then required to fail (at least one seed) in every
//! composition containing that model. The runs go in parallel on a rayon pool; each is
//! deterministic (virtual time), so the table does not depend on the machine.

// An example front end: it prints what it measured.
#![allow(clippy::print_stdout, clippy::print_stderr)]

use std::collections::BTreeMap;
use std::time::Duration;

use canopener_can::Instant;
use canopener_device::faults::Fault;
use canopener_eds::model::Eds;
use canopener_mbt::compile::{Options, Source, compile};
use canopener_mbt::executor::{Outcome, RunConfig, Verdict};
use canopener_mbt::model::Model;
use canopener_mbt::shipped;
use canopener_runtime::mbt_run::run;
use canopener_runtime::simulator::simulation::Simulation;
use canopener_testkit::corpus;
use rayon::prelude::*;

/// Vendored in `corpus/eds`, so a fresh clone has them. Chosen to differ where the models look:
/// heartbeat on (1000 ms) or off, self-starting (1F80h = 0) or not, 1029h present or not, a
/// heartbeat consumer (1016h) or not, TPDO1 mapped or not.
const DEVICES: &[&str] = &[
    "CANopenNode__CANopenNode__example__IO.eds",
    "CANopenNode__CANopenDemo__demo__demoDevice.eds",
    "YamamotoSoya__maxon_epos4compact50-5can_ros2__maxon_epos4_ros2__config__bus_config_cia402_epos4_pos__maxon_epos4_0x1018.eds",
    "iota2__CANopen-tools-suite__eds_files__sample_node_0x01.eds",
    "christiansandberg__canopen__test__sample.eds",
    "Daxbot__node-canopen__examples__eds__example.eds",
];
const NODE: u8 = 5;

struct Args {
    steps: usize,
    seeds: u64,
    eds: Vec<String>,
    fault_steps: usize,
    fault_seeds: u64,
    sample: bool,
    faults: bool,
    trace: bool,
}

fn args() -> Args {
    let mut a = Args {
        steps: 2000,
        seeds: 5,
        eds: DEVICES.iter().map(|s| (*s).to_owned()).collect(),
        fault_steps: 1000,
        fault_seeds: 5,
        sample: false,
        faults: true,
        trace: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = || it.next().unwrap_or_else(|| panic!("{flag} needs a value"));
        match flag.as_str() {
            "--steps" => a.steps = value().parse().expect("--steps N"),
            "--seeds" => a.seeds = value().parse().expect("--seeds N"),
            "--eds" => a.eds = value().split(',').map(str::to_owned).collect(),
            "--fault-steps" => a.fault_steps = value().parse().expect("--fault-steps N"),
            "--fault-seeds" => a.fault_seeds = value().parse().expect("--fault-seeds N"),
            "--subsets" => a.sample = value() == "sample",
            "--no-faults" => a.faults = false,
            "--trace" => a.trace = true,
            other => panic!("unknown argument {other}; see the example's doc comment"),
        }
    }
    a
}

/// The subsets of `names` to run, as bit masks: all of them, or the CI sample.
fn subsets(names: &[&str], sample: bool) -> Vec<u32> {
    let all = (1u32 << names.len()) - 1;
    if !sample {
        return (1..=all).collect();
    }
    let bit = |n: &str| names.iter().position(|m| *m == n).map_or(0, |i| 1u32 << i);
    let mut out: Vec<u32> = (0..names.len()).map(|i| 1 << i).collect();
    let nmt = bit("nmt");
    out.extend((0..names.len()).map(|i| nmt | 1 << i));
    // The compositions: nmt+heartbeat, nmt+heartbeat+sdo.
    out.push(nmt | bit("heartbeat") | bit("sdo"));
    out.push(all);
    out.sort_unstable();
    out.dedup();
    out
}

fn subset_name(names: &[&str], mask: u32) -> String {
    names
        .iter()
        .enumerate()
        .filter(|(i, _)| mask & (1 << i) != 0)
        .map(|(_, n)| *n)
        .collect::<Vec<_>>()
        .join(" ")
}

fn compose(names: &[&str], mask: u32, eds: &Eds) -> Model {
    let sources: Vec<Source> = names
        .iter()
        .enumerate()
        .filter(|(i, _)| mask & (1 << i) != 0)
        .map(|(_, n)| Source {
            origin: (*n).to_owned(),
            text: shipped::text(n).expect("shipped").to_owned(),
        })
        .collect();
    let options = Options {
        node_id: NODE,
        eds: Some(eds),
        set: Vec::new(),
    };
    let (model, report) = compile(&sources, &options, &|n| shipped::text(n).map(str::to_owned));
    model.unwrap_or_else(|| panic!("{} does not check: {report:?}", subset_name(names, mask)))
}

fn test(model: &Model, eds: &Eds, faults: &[Fault], seed: u64, steps: usize) -> Outcome {
    let mut bus = Simulation::ideal()
        .device(eds, NODE)
        .faults(faults.iter().copied())
        .start()
        .expect("simulation");
    bus.run_until(Instant::from_millis(100)).expect("virtual bus");
    let config = RunConfig {
        seed,
        steps,
        ..RunConfig::default()
    };
    run(&mut bus, model, config, Some(Duration::from_secs(1_000_000))).expect("virtual bus")
}

fn main() {
    let a = args();
    let names: Vec<&str> = shipped::canopen_models().map(|m| m.name).collect();
    let devices: Vec<(String, Eds)> = a
        .eds
        .iter()
        .map(|f| {
            let bytes = std::fs::read(corpus::eds(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
            (f.clone(), canopener_eds::load(&bytes).eds)
        })
        .collect();
    let masks = subsets(&names, a.sample);
    let wall = std::time::Instant::now();

    // Clean devices: every subset x device x seed.
    let jobs: Vec<(u32, usize, u64)> = masks
        .iter()
        .flat_map(|m| (0..devices.len()).flat_map(move |d| (1..=a.seeds).map(move |s| (*m, d, s))))
        .collect();
    let models: BTreeMap<(u32, usize), Model> = masks
        .iter()
        .flat_map(|m| (0..devices.len()).map(move |d| (*m, d)))
        .collect::<Vec<_>>()
        .into_par_iter()
        .map(|(m, d)| ((m, d), compose(&names, m, &devices[d].1)))
        .collect();
    let clean: Vec<(u32, usize, u64, Outcome)> = jobs
        .par_iter()
        .map(|&(m, d, s)| (m, d, s, test(&models[&(m, d)], &devices[d].1, &[], s, a.steps)))
        .collect();
    let clean_wall = wall.elapsed();

    println!(
        "#### Clean devices: {} compositions x {} devices x {} seeds x {} steps\n",
        masks.len(),
        devices.len(),
        a.seeds,
        a.steps
    );
    println!("Devices (corpus/eds, node {NODE}):\n");
    for (i, (f, _)) in devices.iter().enumerate() {
        println!("{}. `{f}`", i + 1);
    }
    let mut failures = Vec::new();
    let mut by_size: BTreeMap<u32, (usize, usize)> = BTreeMap::new();
    for (m, d, s, o) in &clean {
        let entry = by_size.entry(m.count_ones()).or_default();
        entry.1 += 1;
        if o.verdict == Verdict::Pass {
            entry.0 += 1;
        } else {
            failures.push(format!(
                "`{}` on device {} seed {s}: {:?} after {} steps: {}",
                subset_name(&names, *m),
                d + 1,
                o.verdict,
                o.steps,
                o.reason
            ));
            if a.trace {
                eprintln!("--- {}", failures.last().map_or("", String::as_str));
                for step in &o.trace[o.trace.len().saturating_sub(25)..] {
                    eprintln!("  {:>9.3}s {}", step.t, step.label);
                }
                for allowed in &o.allowed {
                    eprintln!("  allowed: {allowed}");
                }
            }
        }
    }
    println!("\n| models composed | compositions | runs | pass |");
    println!("|---|---|---|---|");
    for (size, (pass, runs)) in &by_size {
        let compositions = masks.iter().filter(|m| m.count_ones() == *size).count();
        println!("| {size} | {compositions} | {runs} | {pass} |");
    }
    let passed = clean.iter().filter(|c| c.3.verdict == Verdict::Pass).count();
    println!("| all | {} | {} | {passed} |\n", masks.len(), clean.len());
    if failures.is_empty() {
        println!("Every run passed.\n");
    } else {
        println!("Runs that did not pass:\n");
        for f in &failures {
            println!("* {f}");
        }
        println!();
    }
    // Coverage of the whole set, per device: how much of the composition one run exercises.
    let all = *masks.iter().max().unwrap_or(&0);
    if masks.contains(&all) {
        println!(
            "The whole set (`{}`), transitions covered per device (best seed):\n",
            subset_name(&names, all)
        );
        println!("| device | transitions covered | frames judged (median) |");
        println!("|---|---|---|");
        for d in 0..devices.len() {
            let runs: Vec<&Outcome> = clean
                .iter()
                .filter(|c| c.0 == all && c.1 == d)
                .map(|c| &c.3)
                .collect();
            let best = runs.iter().map(|o| o.coverage.transitions[0]).max().unwrap_or(0);
            let total = runs.first().map_or(0, |o| o.coverage.transitions[1]);
            let mut frames: Vec<usize> = runs.iter().map(|o| o.outputs_seen).collect();
            frames.sort_unstable();
            println!(
                "| {} | {best}/{total} | {} |",
                d + 1,
                frames.get(frames.len() / 2).copied().unwrap_or(0)
            );
        }
        println!();
    }
    eprintln!(
        "clean part: {} runs in {:.1} s",
        clean.len(),
        clean_wall.as_secs_f64()
    );

    if !a.faults {
        return;
    }
    let (device, eds) = &devices[0];
    // Faults each model catches alone.
    let singles: Vec<u32> = (0..names.len()).map(|i| 1u32 << i).collect();
    let fault_models: BTreeMap<u32, Model> = masks
        .iter()
        .chain(&singles)
        .map(|m| (*m, compose(&names, *m, eds)))
        .collect();
    let caught = |m: u32, fault: Fault| -> (usize, Vec<usize>) {
        let fails: Vec<usize> = (1..=a.fault_seeds)
            .into_par_iter()
            .filter_map(|s| {
                let o = test(&fault_models[&m], eds, &[fault], s, a.fault_steps);
                (o.verdict == Verdict::Fail).then_some(o.steps)
            })
            .collect();
        (fails.len(), fails)
    };
    let alone: Vec<(usize, Vec<Fault>)> = (0..names.len())
        .into_par_iter()
        .map(|i| {
            let found = Fault::ALL
                .iter()
                .copied()
                .filter(|f| caught(1 << i, *f).0 > 0)
                .collect();
            (i, found)
        })
        .collect();
    println!(
        "#### Faults: every catalogue fault a model catches alone, in every composition containing that model ({} seeds x at most {} steps, device 1 `{device}`)\n",
        a.fault_seeds, a.fault_steps
    );
    println!("| model | faults it catches alone |");
    println!("|---|---|");
    for (i, found) in &alone {
        let list: Vec<&str> = found.iter().map(|f| f.name()).collect();
        println!(
            "| {} | {} |",
            names[*i],
            if list.is_empty() {
                "–".to_owned()
            } else {
                list.join(", ")
            }
        );
    }
    // Every composition: the faults its members catch alone, each run against the composition.
    let checks: Vec<(u32, Fault)> = masks
        .iter()
        .flat_map(|m| {
            let mut faults: Vec<Fault> = alone
                .iter()
                .filter(|(i, _)| m & (1 << i) != 0)
                .flat_map(|(_, f)| f.iter().copied())
                .collect();
            faults.sort_by_key(|f| f.name());
            faults.dedup();
            faults.into_iter().map(move |f| (*m, f))
        })
        .collect();
    let results: Vec<(u32, Fault, usize)> = checks.par_iter().map(|&(m, f)| (m, f, caught(m, f).0)).collect();
    let mut per_mask: BTreeMap<u32, (usize, usize, Vec<String>)> = BTreeMap::new();
    for (m, f, n) in &results {
        let e = per_mask.entry(*m).or_default();
        e.1 += 1;
        if *n > 0 {
            e.0 += 1;
        } else {
            e.2.push(f.name().to_owned());
        }
    }
    let missed: usize = per_mask.values().map(|e| e.1 - e.0).sum();
    println!(
        "\n{} (composition, fault) pairs checked, {} caught, {missed} missed.\n",
        results.len(),
        results.len() - missed
    );
    println!("| composition | faults its models catch alone | caught in the composition | missed |");
    println!("|---|---|---|---|");
    for (m, (ok, total, miss)) in &per_mask {
        println!(
            "| {} | {total} | {ok} | {} |",
            subset_name(&names, *m),
            if miss.is_empty() {
                "–".to_owned()
            } else {
                miss.join(", ")
            }
        );
    }
    eprintln!("everything: {:.1} s", wall.elapsed().as_secs_f64());
}

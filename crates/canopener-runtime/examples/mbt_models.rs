//! The figures of `docs/mbt.md` for the CANopen models of issue 23 (block SDO, multi-segment
//! download, PDO mapping and RTR, store and restore, LSS configuration, life guarding): each model
//! against clean simulated devices built from corpus EDS (verdicts, and the states and transitions
//! the runs covered), each with nmt, and against the catalogue faults it is about (seeds failing,
//! steps and virtual time to the verdict).
//!
//! `cargo run --release -p canopener-runtime --example mbt_models -- [OPTIONS] [MODEL...]`
//!
//! * MODEL: a shipped model's name or a model file; several are composed into one run. Without a
//!   MODEL the tables for every model of the list below are printed.
//! * `--eds A,B,...`: corpus EDS file names; `--seeds N` (5); `--steps N` (2000);
//! * `--fault NAME`: run MODEL against a device with that fault; `--set NAME=VALUE`: a parameter;
//! * `--node N` (5); `--trace`: print the whole trace of every run that does not pass.
//! * `--compositions`: instead of the tables, each model composed as
//!   `canopener_runtime::mbt_sim::compositions_of` lists (with all seven shipped CANopen models,
//!   with `nmt sdo`, the SDO transfer models with each other) on the devices below where those
//!   pass alone: every clean run's verdict, and every fault the model catches alone on a device
//!   (a `fail` on one of the seeds) tried in each composition on that device.
//!
//! Every run is deterministic (virtual time): the same options print the same table.

// An example front end: it prints what it measured.
#![allow(clippy::print_stdout, clippy::print_stderr)]

use canopener_device::faults::Fault;
use canopener_eds::model::Eds;
use canopener_mbt::compile::{Options, Source, compile};
use canopener_mbt::executor::{RunConfig, RunResult, Verdict};
use canopener_mbt::model::Model;
use canopener_mbt::shipped;
use canopener_runtime::mbt_sim::{compositions_of, model_settings, run_simulated, sdo_download_settings};
use canopener_testkit::corpus;
use rayon::prelude::*;
use std::collections::BTreeSet;

/// Vendored in `corpus/eds`. The composition matrix's six, and three with life guarding (100Ch,
/// 100Dh) and limits.
const DEVICES: &[&str] = &[
    "CANopenNode__CANopenNode__example__IO.eds",
    "CANopenNode__CANopenDemo__demo__demoDevice.eds",
    "YamamotoSoya__maxon_epos4compact50-5can_ros2__maxon_epos4_ros2__config__bus_config_cia402_epos4_pos__maxon_epos4_0x1018.eds",
    "iota2__CANopen-tools-suite__eds_files__sample_node_0x01.eds",
    "christiansandberg__canopen__test__sample.eds",
    "Daxbot__node-canopen__examples__eds__example.eds",
];

/// With life guarding (100Ch, 100Dh).
const GUARDED: &[&str] = &[
    "CANopenNode__CANopenSocket__canopend__objDict__CANopenSocket.eds",
    "christiansandberg__canopen__examples__eds__e35.eds",
    "ljessendk__CanFestival__examples__DS401_Slave_Gui__DS401_Slave_Gui.eds",
    "ros-industrial__ros2_canopen__canopen_tests__config__cia402__cia402_slave.eds",
    "ros-industrial__ros_canopen__canopen_test_utils__config__Schunk.eds",
];

/// With entries sdo-download writes (a long string, an entry with limits; `mbt_settings`).
const WRITABLE: &[&str] = &[
    "christiansandberg__canopen__test__sample.eds",
    "samsamfire__gocanopen__pkg__od__base.eds",
    "YamamotoSoya__maxon_epos4compact50-5can_ros2__maxon_epos4_ros2__config__bus_config_cia402_epos4_pos__maxon_epos4_0x1018.eds",
    "christiansandberg__canopen__examples__eds__e35.eds",
    "ros-industrial__ros_canopen__canopen_chain_node__test__eds__ISD860.eds",
    "CANopenNode__CANopenNode__example__IO.eds",
];

/// Per model, the devices it is composed on (`--compositions`): those of its devices on which the
/// seven shipped CANopen models pass alone (the matrix devices; for life guarding the four with a
/// life time, e35 among them since the EMCY models take 1014h's CAN-ID).
const COMPOSED: &[(&str, &[&str])] = &[
    ("sdo-block", &[DEVICES[0], DEVICES[1], DEVICES[2], DEVICES[4]]),
    ("sdo-download", &[WRITABLE[0], WRITABLE[2], WRITABLE[5]]),
    ("pdo", &[DEVICES[0], DEVICES[1], DEVICES[2], DEVICES[3]]),
    ("store", &[DEVICES[0], DEVICES[1], DEVICES[2]]),
    ("lss-config", &[DEVICES[0], DEVICES[1], DEVICES[4]]),
    ("life-guarding", &[GUARDED[0], GUARDED[1], GUARDED[3], GUARDED[4]]),
];

/// The models of issue 23, the faults each is about, and the devices (with the feature) it runs on
/// when no `--eds` is given.
const MODELS: &[(&str, &[Fault], &[&str])] = &[
    ("sdo-block", &[Fault::BlockCrcWrong], DEVICES),
    (
        "sdo-download",
        &[Fault::LimitNotEnforced, Fault::SdoToggleIgnored],
        WRITABLE,
    ),
    (
        "pdo",
        &[
            Fault::UnmappableAccepted,
            Fault::PdoCobIdUnchecked,
            Fault::NoTpdoRtr,
        ],
        DEVICES,
    ),
    ("store", &[Fault::StoreIgnored], DEVICES),
    ("lss-config", &[Fault::LssStateNotChanged, Fault::NoLss], DEVICES),
    ("life-guarding", &[Fault::NoEmcy], GUARDED),
];

struct Args {
    models: Vec<String>,
    eds: Option<Vec<String>>,
    seeds: u64,
    steps: usize,
    fault: Option<Fault>,
    set: Vec<(String, i64)>,
    node: u8,
    trace: bool,
    compositions: bool,
}

fn args() -> Args {
    let mut a = Args {
        models: Vec::new(),
        eds: None,
        seeds: 5,
        steps: 2000,
        fault: None,
        set: Vec::new(),
        node: 5,
        trace: false,
        compositions: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = || it.next().unwrap_or_else(|| panic!("{flag} needs a value"));
        match flag.as_str() {
            "--eds" => a.eds = Some(value().split(',').map(str::to_owned).collect()),
            "--seeds" => a.seeds = value().parse().expect("--seeds N"),
            "--steps" => a.steps = value().parse().expect("--steps N"),
            "--fault" => a.fault = Some(value().parse().expect("a catalogue fault")),
            "--node" => a.node = value().parse().expect("--node N"),
            "--set" => {
                let v = value();
                let (name, number) = v.split_once('=').expect("--set NAME=VALUE");
                let number = match number.strip_prefix("0x") {
                    Some(hex) => i64::from_str_radix(hex, 16),
                    None => number.parse(),
                };
                a.set.push((name.to_owned(), number.expect("a number")));
            }
            "--trace" => a.trace = true,
            "--compositions" => a.compositions = true,
            other if other.starts_with("--") => panic!("unknown option {other}; see the doc comment"),
            other => a.models.push(other.to_owned()),
        }
    }
    a
}

fn main() {
    let a = args();
    if a.compositions {
        compositions(&a);
        return;
    }
    if a.models.is_empty() {
        tables(&a);
        return;
    }
    let names: Vec<&str> = a.models.iter().map(String::as_str).collect();
    let default: Vec<String> = DEVICES.iter().map(|s| (*s).to_owned()).collect();
    for file in a.eds.as_ref().unwrap_or(&default) {
        let eds = load(file);
        if names.contains(&"sdo-download") {
            println!("{}: {:?}", short(file), sdo_download_settings(&eds, a.node));
        }
        let Some(model) = compose(&names, &eds, a.node, &a.set) else {
            continue;
        };
        for seed in 1..=a.seeds {
            let faults: Vec<Fault> = a.fault.into_iter().collect();
            let o = test(&model, &eds, a.node, &faults, seed, a.steps);
            println!(
                "{} seed {seed}: {:?} after {} steps, {:.2} s: {} | transitions {}/{}, states {}",
                short(file),
                o.verdict,
                o.steps,
                o.trace.last().map_or(0.0, |s| s.t),
                o.reason,
                o.coverage.transitions[0],
                o.coverage.transitions[1],
                o.coverage.states_seen
            );
            if std::env::var("UNCOVERED").is_ok() {
                let taken: BTreeSet<usize> = o.coverage.taken.iter().copied().collect();
                for (f, file) in model.files.iter().enumerate() {
                    let lines: Vec<String> = model
                        .transitions
                        .iter()
                        .filter(|t| model.processes[t.process].file == f && !taken.contains(&t.id))
                        .map(|t| {
                            format!(
                                "{}{}",
                                t.span.line,
                                t.tags.first().map_or(String::new(), |g| format!(" {g}"))
                            )
                        })
                        .collect();
                    println!("    {}: lines not taken {lines:?}", file.name);
                }
            }
            if a.trace && (o.verdict != Verdict::Pass || std::env::var("ALL").is_ok()) {
                for s in &o.trace {
                    println!("    {:9.3} {:?} {}", s.t, s.dir, s.label);
                }
                println!("    allowed: {:?}", o.allowed);
            }
        }
    }
}

/// The tables of `docs/mbt.md`: per model, clean runs alone and with nmt, coverage, faults.
fn tables(a: &Args) {
    for (name, faults, devices) in MODELS {
        let files: Vec<String> = match &a.eds {
            Some(files) => files.clone(),
            None => devices.iter().map(|s| (*s).to_owned()).collect(),
        };
        println!("#### `{name}`\n");
        println!("| device | alone | with nmt | transitions covered | locations covered | states seen |");
        println!("|---|---|---|---|---|---|");
        let mut taken = BTreeSet::new();
        let mut total = 0;
        for file in &files {
            let eds = load(file);
            let Some(alone) = compose(&[name], &eds, a.node, &a.set) else {
                println!("| {} | does not compile | | | | |", short(file));
                continue;
            };
            let with_nmt = compose(&["nmt", name], &eds, a.node, &a.set).expect("compiles alone");
            let (mut verdicts, mut composed) = (BTreeSet::new(), BTreeSet::new());
            let (mut transitions, mut locations, mut states) = (0, 0, 0);
            for seed in 1..=a.seeds {
                let o = test(&alone, &eds, a.node, &[], seed, a.steps);
                verdicts.insert(verdict(&o));
                transitions = transitions.max(o.coverage.transitions[0]);
                locations = locations.max(o.coverage.locations[0]);
                states = states.max(o.coverage.states_seen);
                taken.extend(own(&alone, name, &o));
                let c = test(&with_nmt, &eds, a.node, &[], seed, a.steps);
                composed.insert(verdict(&c));
            }
            total = own_count(&alone, name);
            println!(
                "| {} | {} | {} | {transitions}/{} | {locations}/{} | {states} |",
                short(file),
                join(&verdicts),
                join(&composed),
                alone.transitions.len(),
                alone.location_count(),
            );
        }
        println!(
            "\nTransitions of `{name}` itself taken on some clean run: {}/{total}.\n",
            taken.len()
        );
        if faults.is_empty() {
            continue;
        }
        println!(
            "| fault | device | seeds failing | median steps to `fail` | median virtual time | first reason |"
        );
        println!("|---|---|---|---|---|---|");
        for fault in *faults {
            for file in &files {
                let eds = load(file);
                let Some(model) = compose(&[name], &eds, a.node, &a.set) else {
                    continue;
                };
                let mut fails = Vec::new();
                for seed in 1..=a.seeds {
                    let o = test(&model, &eds, a.node, &[*fault], seed, a.steps);
                    if o.verdict == Verdict::Fail {
                        fails.push((o.steps, o.trace.last().map_or(0.0, |s| s.t), o.reason));
                    }
                }
                if fails.is_empty() {
                    println!("| {} | {} | 0/{} | – | – | |", fault.name(), short(file), a.seeds);
                    continue;
                }
                let reason = fails[0].2.clone();
                let mut steps: Vec<usize> = fails.iter().map(|f| f.0).collect();
                let mut times: Vec<f64> = fails.iter().map(|f| f.1).collect();
                steps.sort_unstable();
                times.sort_by(f64::total_cmp);
                println!(
                    "| {} | {} | {}/{} | {} | {:.2} s | {} |",
                    fault.name(),
                    short(file),
                    fails.len(),
                    a.seeds,
                    steps[steps.len() / 2],
                    times[times.len() / 2],
                    reason.replace('|', "\\|")
                );
            }
        }
        println!();
    }
}

/// The compositions of each model (`--compositions`): clean runs, and the faults it catches alone.
fn compositions(a: &Args) {
    let started = std::time::Instant::now();
    println!(
        "| model | composed with | devices | clean runs passing ({} seeds x {} steps) | faults: devices catching it alone → of them, in this composition |",
        a.seeds, a.steps
    );
    println!("|---|---|---|---|---|");
    for (name, faults, _) in MODELS {
        let devices = COMPOSED
            .iter()
            .find(|(n, _)| n == name)
            .map_or(&[][..], |(_, d)| *d);
        let files: Vec<&str> = devices.to_vec();
        // Where the model catches each fault alone.
        let alone: Vec<(Fault, Vec<&str>)> = faults
            .iter()
            .map(|fault| {
                let caught = files
                    .par_iter()
                    .copied()
                    .filter(|file| {
                        let eds = load(file);
                        let m = compose(&[name], &eds, a.node, &a.set).expect("compiles");
                        caught(&m, &eds, a, *fault)
                    })
                    .collect();
                (*fault, caught)
            })
            .collect();
        for others in compositions_of(name) {
            let mut names = others.clone();
            names.push(name);
            let runs: Vec<(&str, u64)> = files
                .iter()
                .flat_map(|f| (1..=a.seeds).map(move |seed| (*f, seed)))
                .collect();
            let failed: Vec<String> = runs
                .par_iter()
                .filter_map(|(file, seed)| {
                    let eds = load(file);
                    let m = compose(&names, &eds, a.node, &a.set).expect("compiles");
                    let o = test(&m, &eds, a.node, &[], *seed, a.steps);
                    (o.verdict != Verdict::Pass).then(|| format!("{} seed {seed}: {}", short(file), o.reason))
                })
                .collect();
            for f in &failed {
                eprintln!("{names:?}: {f}");
            }
            let caught_here: Vec<String> = alone
                .iter()
                .map(|(fault, where_alone)| {
                    let n = where_alone
                        .par_iter()
                        .filter(|file| {
                            let eds = load(file);
                            let m = compose(&names, &eds, a.node, &a.set).expect("compiles");
                            caught(&m, &eds, a, *fault)
                        })
                        .count();
                    format!("`{}` {} → {n}", fault.name(), where_alone.len())
                })
                .collect();
            println!(
                "| `{name}` | `{}` | {} | {}/{} | {} |",
                others.join(" "),
                files.iter().map(|f| short(f)).collect::<Vec<_>>().join(", "),
                runs.len() - failed.len(),
                runs.len(),
                caught_here.join("; ")
            );
        }
    }
    println!(
        "\nWall time {:.0} s ({} rayon threads).",
        started.elapsed().as_secs_f64(),
        rayon::current_num_threads()
    );
}

/// Whether `fault` makes one of the seeds (tried in order) fail.
fn caught(model: &Model, eds: &Eds, a: &Args, fault: Fault) -> bool {
    (1..=a.seeds).any(|seed| test(model, eds, a.node, &[fault], seed, a.steps).verdict == Verdict::Fail)
}

fn verdict(o: &RunResult) -> String {
    format!("{:?}", o.verdict).to_lowercase()
}

fn join(set: &BTreeSet<String>) -> String {
    set.iter().cloned().collect::<Vec<_>>().join(", ")
}

/// The transitions of the model file `name` (not of the models it uses) that a run took.
fn own(model: &Model, name: &str, o: &RunResult) -> Vec<usize> {
    let Some(file) = model.files.iter().position(|f| f.origin == name) else {
        return Vec::new();
    };
    o.coverage
        .taken
        .iter()
        .copied()
        .filter(|t| model.processes[model.transitions[*t].process].file == file)
        .collect()
}

fn own_count(model: &Model, name: &str) -> usize {
    let Some(file) = model.files.iter().position(|f| f.origin == name) else {
        return 0;
    };
    model
        .transitions
        .iter()
        .filter(|t| model.processes[t.process].file == file)
        .count()
}

fn short(file: &str) -> String {
    file.rsplit("__")
        .next()
        .unwrap_or(file)
        .trim_end_matches(".eds")
        .to_owned()
}

fn load(file: &str) -> Eds {
    canopener_eds::load(&std::fs::read(corpus::eds(file)).expect("a corpus EDS")).eds
}

/// The model text: a shipped model, or a file.
fn text(name: &str) -> String {
    match shipped::text(name) {
        Some(text) => text.to_owned(),
        None => std::fs::read_to_string(name).unwrap_or_else(|e| panic!("{name}: {e}")),
    }
}

fn compose(names: &[&str], eds: &Eds, node_id: u8, set: &[(String, i64)]) -> Option<Model> {
    let sources: Vec<Source> = names
        .iter()
        .map(|n| Source {
            origin: (*n).into(),
            text: text(n),
        })
        .collect();
    // The entries sdo-download writes, from the description (given ones win).
    let set = model_settings(names, eds, node_id, set);
    let options = Options {
        node_id,
        eds: Some(eds),
        set,
    };
    let (model, report) = compile(&sources, &options, &|n| shipped::text(n).map(str::to_owned));
    if model.is_none() {
        for r in report {
            for d in r.diagnostics {
                eprintln!("{}: {d:?}", r.origin);
            }
        }
    }
    model
}

fn test(model: &Model, eds: &Eds, node_id: u8, faults: &[Fault], seed: u64, steps: usize) -> RunResult {
    let config = RunConfig {
        seed,
        steps,
        ..RunConfig::default()
    };
    run_simulated(model, eds, node_id, faults, config).expect("simulated run")
}

//! The composition matrix of `docs/mbt.md`: every subset of the shipped CANopen models (every model
//! whose `Shipped::canopen` is set, so models added later join by themselves) against clean
//! simulated devices, and every catalogue fault a model catches alone against every composition
//! that contains the model.
//!
//! `cargo run --release -p canopener-runtime --example mbt_compose -- [OPTIONS]` prints Markdown:
//!
//! * `--steps N` (2000), `--seeds N` (5): each subset on each device, seeds 1..=N;
//! * `--eds A,B,...`: corpus EDS file names (default: the six below);
//! * `--fault-steps N` (1000), `--fault-seeds N` (20): the fault part, on the first device;
//! * `--subsets all|sample|pairs` (all): `sample` takes the single models, the issue's
//!   compositions, every model with nmt, and the whole set (the CI sample); `pairs` the single
//!   models, every pair and the whole set;
//! * `--models canopen|thirteen` (canopen): the models composed: the shipped CANopen models (the
//!   2^7 matrix), or those and the six CANopen models added by issue 23 (every shipped model but
//!   the EnergyBus ones; 2^13 subsets are too many to run, so with `--subsets pairs`). The tables
//!   go between `<!-- mbt_compose thirteen: begin -->` and `<!-- mbt_compose thirteen: end -->`;
//! * `--no-faults`: the clean part only;
//! * `--results FILE` (`target/mbt_compose.tsv`): every finished run is appended there, and runs
//!   already there (same subset, device, seed and steps) are not run again, so a matrix cut short
//!   goes on where it stopped when the same command is given again;
//! * `--budget SECONDS`: start no run after that much wall time (the table then says how many of
//!   the runs it has; give the command again to run the rest);
//! * `--write FILE`: also put the tables into FILE between the lines `<!-- mbt_compose: begin -->`
//!   and `<!-- mbt_compose: end -->` (`docs/mbt.md`), through a temporary file and a rename;
//! * `--trace`: print the last steps of every run that does not pass (on stderr).
//!
//! A subset passes when every run is `pass`; a fault counts as caught by a model alone when one of
//! its fault seeds fails (the seeds are tried in order and the first failure ends the search), and
//! is then required to fail (on some seed) in every composition containing that model. The runs go
//! in parallel on a rayon pool; each is deterministic (virtual time), so the table does not depend
//! on the machine, only the wall times do.

// An example front end: it prints what it measured.
#![allow(clippy::print_stdout, clippy::print_stderr)]

use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Duration;

use canopener_can::Instant;
use canopener_device::faults::Fault;
use canopener_eds::model::Eds;
use canopener_files::write_atomic;
use canopener_mbt::compile::{Options, Source, compile};
use canopener_mbt::executor::{RunConfig, RunResult, Verdict};
use canopener_mbt::model::Model;
use canopener_mbt::shipped;
use canopener_runtime::mbt_run::run;
use canopener_runtime::mbt_sim::model_settings;
use canopener_sim::simulation::Simulation;
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
const BEGIN: &str = "<!-- mbt_compose: begin -->";
const END: &str = "<!-- mbt_compose: end -->";
const BEGIN_13: &str = "<!-- mbt_compose thirteen: begin -->";
const END_13: &str = "<!-- mbt_compose thirteen: end -->";

struct Args {
    steps: usize,
    seeds: u64,
    eds: Vec<String>,
    fault_steps: usize,
    fault_seeds: u64,
    sample: bool,
    pairs: bool,
    thirteen: bool,
    faults: bool,
    results: PathBuf,
    budget: Option<Duration>,
    write: Option<PathBuf>,
    trace: bool,
}

fn args() -> Args {
    let mut a = Args {
        steps: 2000,
        seeds: 5,
        eds: DEVICES.iter().map(|s| (*s).to_owned()).collect(),
        fault_steps: 1000,
        fault_seeds: 20,
        sample: false,
        pairs: false,
        thirteen: false,
        faults: true,
        results: PathBuf::from("target/mbt_compose.tsv"),
        budget: None,
        write: None,
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
            "--subsets" => match value().as_str() {
                "all" => {}
                "sample" => a.sample = true,
                "pairs" => a.pairs = true,
                other => panic!("--subsets all|sample|pairs, not {other}"),
            },
            "--models" => match value().as_str() {
                "canopen" => {}
                "thirteen" => a.thirteen = true,
                other => panic!("--models canopen|thirteen, not {other}"),
            },
            "--no-faults" => a.faults = false,
            "--results" => a.results = value().into(),
            "--budget" => a.budget = Some(Duration::from_secs(value().parse().expect("--budget SECONDS"))),
            "--write" => a.write = Some(value().into()),
            "--trace" => a.trace = true,
            other => panic!("unknown argument {other}; see the example's doc comment"),
        }
    }
    a
}

/// The subsets of `names` to run, as bit masks: all of them, the CI sample, or the singles, pairs
/// and all.
fn subsets(names: &[&str], sample: bool, pairs: bool) -> Vec<u32> {
    let all = (1u32 << names.len()) - 1;
    if pairs {
        let n = names.len();
        let mut out: Vec<u32> = (0..n).map(|i| 1 << i).collect();
        out.extend((0..n).flat_map(|i| (i + 1..n).map(move |j| (1u32 << i) | (1 << j))));
        out.push(all);
        out.sort_unstable();
        out.dedup();
        return out;
    }
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
    // The same settings as `mbt run` (the description's entries for `sdo-download`).
    let chosen: Vec<&str> = names
        .iter()
        .enumerate()
        .filter(|(i, _)| mask & (1 << i) != 0)
        .map(|(_, n)| *n)
        .collect();
    let set = model_settings(&chosen, eds, NODE, &[]);
    let options = Options {
        node_id: NODE,
        eds: Some(eds),
        set,
    };
    let (model, report) = compile(&sources, &options, &|n| shipped::text(n).map(str::to_owned));
    model.unwrap_or_else(|| panic!("{} does not check: {report:?}", subset_name(names, mask)))
}

fn test(model: &Model, eds: &Eds, faults: &[Fault], seed: u64, steps: usize) -> RunResult {
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

/// The runs done so far, one line each in a tab-separated file: a key (what was run) and what came
/// out. Runs are appended as they finish, so nothing is lost when the matrix is cut short.
struct Results {
    done: Mutex<HashMap<String, Vec<String>>>,
    file: Mutex<std::fs::File>,
    /// Runs made by this command (not taken from the file).
    new: std::sync::atomic::AtomicUsize,
}

impl Results {
    fn open(path: &PathBuf) -> Results {
        let text = std::fs::read_to_string(path).unwrap_or_default();
        let mut done = HashMap::new();
        for line in text.lines() {
            let fields: Vec<&str> = line.split('\t').collect();
            let key_len = match fields.first() {
                Some(&"clean") => 5,
                Some(&"fault") => 6,
                _ => continue,
            };
            if fields.len() > key_len {
                done.insert(
                    fields[..key_len].join("\t"),
                    fields[key_len..].iter().map(|s| (*s).to_owned()).collect(),
                );
            }
        }
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
        }
        let file = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        Results {
            done: Mutex::new(done),
            file: Mutex::new(file),
            new: std::sync::atomic::AtomicUsize::new(0),
        }
    }

    fn get(&self, key: &str) -> Option<Vec<String>> {
        let done = self
            .done
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        done.get(key).cloned()
    }

    fn record(&self, key: &str, value: &[String]) {
        // Tabs and line breaks in a reason would break the file's lines.
        let value: Vec<String> = value.iter().map(|v| v.replace(['\t', '\n'], " ")).collect();
        let line = format!("{key}\t{}\n", value.join("\t"));
        let mut file = self
            .file
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        file.write_all(line.as_bytes()).expect("results file");
        drop(file);
        let mut done = self
            .done
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        done.insert(key.to_owned(), value);
        self.new.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    }
}

/// One clean run as the table needs it.
struct Clean {
    pass: bool,
    verdict: String,
    steps: usize,
    frames: usize,
    covered: usize,
    total: usize,
    reason: String,
}

impl Clean {
    fn of(o: &RunResult) -> Clean {
        Clean {
            pass: o.verdict == Verdict::Pass,
            verdict: format!("{:?}", o.verdict).to_lowercase(),
            steps: o.steps,
            frames: o.outputs_seen,
            covered: o.coverage.transitions[0],
            total: o.coverage.transitions[1],
            reason: o.reason.clone(),
        }
    }

    fn fields(&self) -> Vec<String> {
        vec![
            self.verdict.clone(),
            self.steps.to_string(),
            self.frames.to_string(),
            self.covered.to_string(),
            self.total.to_string(),
            self.reason.clone(),
        ]
    }

    fn parse(f: &[String]) -> Option<Clean> {
        Some(Clean {
            pass: f.first()? == "pass",
            verdict: f.first()?.clone(),
            steps: f.get(1)?.parse().ok()?,
            frames: f.get(2)?.parse().ok()?,
            covered: f.get(3)?.parse().ok()?,
            total: f.get(4)?.parse().ok()?,
            reason: f.get(5).cloned().unwrap_or_default(),
        })
    }
}

fn main() {
    let a = args();
    let command = std::env::args().skip(1).collect::<Vec<_>>().join(" ");
    let names: Vec<&str> = if a.thirteen {
        shipped::all_canopen_models().map(|m| m.name).collect()
    } else {
        shipped::canopen_models().map(|m| m.name).collect()
    };
    let (begin_marker, end_marker) = if a.thirteen {
        (BEGIN_13, END_13)
    } else {
        (BEGIN, END)
    };
    let devices: Vec<(String, Eds)> = a
        .eds
        .iter()
        .map(|f| {
            let bytes = std::fs::read(corpus::eds(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
            (f.clone(), canopener_eds::load(&bytes).eds)
        })
        .collect();
    let masks = subsets(&names, a.sample, a.pairs);
    let results = Results::open(&a.results);
    let wall = std::time::Instant::now();
    let in_budget = || a.budget.is_none_or(|b| wall.elapsed() < b);
    let mut out = String::new();

    // Clean devices: every subset x device x seed.
    let clean_key = |m: u32, d: usize, s: u64| {
        format!(
            "clean\t{}\t{}\t{s}\t{}",
            subset_name(&names, m),
            devices[d].0,
            a.steps
        )
    };
    let jobs: Vec<(u32, usize, u64)> = masks
        .iter()
        .flat_map(|m| (0..devices.len()).flat_map(move |d| (1..=a.seeds).map(move |s| (*m, d, s))))
        .collect();
    let pending: Vec<(u32, usize)> = {
        let mut p: Vec<(u32, usize)> = jobs
            .iter()
            .filter(|(m, d, s)| results.get(&clean_key(*m, *d, *s)).is_none())
            .map(|(m, d, _)| (*m, *d))
            .collect();
        p.dedup();
        p
    };
    let models: BTreeMap<(u32, usize), Model> = pending
        .into_par_iter()
        .map(|(m, d)| ((m, d), compose(&names, m, &devices[d].1)))
        .collect();
    let clean: Vec<(u32, usize, u64, Clean)> = jobs
        .par_iter()
        .filter_map(|&(m, d, s)| {
            let key = clean_key(m, d, s);
            if let Some(done) = results.get(&key).and_then(|f| Clean::parse(&f)) {
                return Some((m, d, s, done));
            }
            if !in_budget() {
                return None;
            }
            let o = test(&models[&(m, d)], &devices[d].1, &[], s, a.steps);
            if a.trace && o.verdict != Verdict::Pass {
                let mut text = format!(
                    "--- {} on device {} seed {s}: {}\n",
                    subset_name(&names, m),
                    d + 1,
                    o.reason
                );
                for step in &o.trace[o.trace.len().saturating_sub(25)..] {
                    let _ = writeln!(text, "  {:>9.3}s {}", step.t, step.label);
                }
                for allowed in &o.allowed {
                    let _ = writeln!(text, "  allowed: {allowed}");
                }
                eprint!("{text}");
            }
            let done = Clean::of(&o);
            results.record(&key, &done.fields());
            Some((m, d, s, done))
        })
        .collect();
    let clean_wall = wall.elapsed();

    let _ = writeln!(
        out,
        "#### Clean devices: {} compositions x {} devices x {} seeds x {} steps\n",
        masks.len(),
        devices.len(),
        a.seeds,
        a.steps
    );
    let _ = writeln!(
        out,
        "Printed by `cargo run --release -p canopener-runtime --example mbt_compose -- {command}`.\n"
    );
    if clean.len() < jobs.len() {
        let _ = writeln!(
            out,
            "**Incomplete: {} of the {} runs are done.** The same command runs the rest (the runs done are kept in `{}`).\n",
            clean.len(),
            jobs.len(),
            a.results.display()
        );
    }
    let _ = writeln!(out, "Devices (corpus/eds, node {NODE}):\n");
    for (i, (f, _)) in devices.iter().enumerate() {
        let _ = writeln!(out, "{}. `{f}`", i + 1);
    }
    let mut failures = Vec::new();
    let mut by_size: BTreeMap<u32, (usize, usize)> = BTreeMap::new();
    for (m, d, s, c) in &clean {
        let entry = by_size.entry(m.count_ones()).or_default();
        entry.1 += 1;
        if c.pass {
            entry.0 += 1;
        } else {
            failures.push(format!(
                "`{}` on device {} seed {s}: {} after {} steps: {}",
                subset_name(&names, *m),
                d + 1,
                c.verdict,
                c.steps,
                c.reason
            ));
        }
    }
    let _ = writeln!(out, "\n| models composed | compositions | runs | pass |");
    let _ = writeln!(out, "|---|---|---|---|");
    for (size, (pass, runs)) in &by_size {
        let compositions = masks.iter().filter(|m| m.count_ones() == *size).count();
        let _ = writeln!(out, "| {size} | {compositions} | {runs} | {pass} |");
    }
    let passed = clean.iter().filter(|c| c.3.pass).count();
    let _ = writeln!(out, "| all | {} | {} | {passed} |\n", masks.len(), clean.len());
    if failures.is_empty() {
        let _ = writeln!(out, "Every run passed.\n");
    } else {
        let _ = writeln!(out, "Runs that did not pass:\n");
        for f in &failures {
            let _ = writeln!(out, "* {f}");
        }
        let _ = writeln!(out);
    }
    // Coverage of the whole set, per device: how much of the composition one run exercises.
    let all = *masks.iter().max().unwrap_or(&0);
    if masks.contains(&all) {
        let _ = writeln!(
            out,
            "The whole set (`{}`), transitions covered per device (best seed):\n",
            subset_name(&names, all)
        );
        let _ = writeln!(out, "| device | transitions covered | frames judged (median) |");
        let _ = writeln!(out, "|---|---|---|");
        for d in 0..devices.len() {
            let runs: Vec<&Clean> = clean
                .iter()
                .filter(|c| c.0 == all && c.1 == d)
                .map(|c| &c.3)
                .collect();
            let best = runs.iter().map(|c| c.covered).max().unwrap_or(0);
            let total = runs.first().map_or(0, |c| c.total);
            let mut frames: Vec<usize> = runs.iter().map(|c| c.frames).collect();
            frames.sort_unstable();
            let _ = writeln!(
                out,
                "| {} | {best}/{total} | {} |",
                d + 1,
                frames.get(frames.len() / 2).copied().unwrap_or(0)
            );
        }
        let _ = writeln!(out);
    }
    eprintln!(
        "clean part: {} runs ({} compositions compiled for new runs) in {:.1} s",
        clean.len(),
        models.len(),
        clean_wall.as_secs_f64()
    );

    if a.faults {
        faults(&a, &names, &masks, &devices[0], &results, &in_budget, &mut out);
    }
    let _ = writeln!(
        out,
        "This command made {} of the runs in {:.0} s of wall time; the others were taken from `{}`, where earlier runs of it left them.",
        results.new.load(std::sync::atomic::Ordering::Relaxed),
        wall.elapsed().as_secs_f64(),
        a.results.display()
    );
    print!("{out}");
    if let Some(path) = &a.write {
        let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let (Some(begin), Some(end)) = (text.find(begin_marker), text.find(end_marker)) else {
            panic!(
                "{} has no lines {begin_marker} and {end_marker} to write between",
                path.display()
            );
        };
        let updated = format!("{}{begin_marker}\n\n{out}\n{}", &text[..begin], &text[end..]);
        write_atomic(path, updated.as_bytes(), false).unwrap_or_else(|e| panic!("{e}"));
        eprintln!("wrote the tables into {}", path.display());
    }
}

/// The fault part: the faults each model catches alone, then each of them against every
/// composition containing the model.
fn faults(
    a: &Args,
    names: &[&str],
    masks: &[u32],
    (device, eds): &(String, Eds),
    results: &Results,
    in_budget: &(dyn Fn() -> bool + Sync),
    out: &mut String,
) {
    let singles: Vec<u32> = (0..names.len()).map(|i| 1u32 << i).collect();
    let fault_key = |m: u32, fault: Fault| {
        format!(
            "fault\t{}\t{device}\t{fault}\t{}\t{}",
            subset_name(names, m),
            a.fault_steps,
            a.fault_seeds
        )
    };
    let model_of: Mutex<BTreeMap<u32, std::sync::Arc<Model>>> = Mutex::new(BTreeMap::new());
    let model = |m: u32| {
        let mut cache = model_of.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        std::sync::Arc::clone(
            cache
                .entry(m)
                .or_insert_with(|| std::sync::Arc::new(compose(names, m, eds))),
        )
    };
    // The first failing seed, 0 if none fails; None if the budget ran out before it was tried.
    let caught = |m: u32, fault: Fault| -> Option<u64> {
        let key = fault_key(m, fault);
        if let Some(seed) = results.get(&key).and_then(|f| f.first()?.parse().ok()) {
            return Some(seed);
        }
        if !in_budget() {
            return None;
        }
        let model = model(m);
        let seed = (1..=a.fault_seeds)
            .find(|s| test(&model, eds, &[fault], *s, a.fault_steps).verdict == Verdict::Fail)
            .unwrap_or(0);
        results.record(&key, &[seed.to_string()]);
        Some(seed)
    };
    let alone: Vec<(usize, Vec<Fault>, usize)> = (0..names.len())
        .into_par_iter()
        .map(|i| {
            let tried: Vec<(Fault, Option<u64>)> = Fault::ALL
                .par_iter()
                .map(|f| (*f, caught(singles[i], *f)))
                .collect();
            let found = tried
                .iter()
                .filter(|(_, s)| s.is_some_and(|s| s > 0))
                .map(|(f, _)| *f)
                .collect();
            let untried = tried.iter().filter(|(_, s)| s.is_none()).count();
            (i, found, untried)
        })
        .collect();
    let _ = writeln!(
        out,
        "#### Faults: every catalogue fault a model catches alone, in every composition containing that model ({} seeds x at most {} steps, device 1 `{device}`)\n",
        a.fault_seeds, a.fault_steps
    );
    let _ = writeln!(out, "| model | faults it catches alone |");
    let _ = writeln!(out, "|---|---|");
    for (i, found, untried) in &alone {
        let list: Vec<&str> = found.iter().map(|f| f.name()).collect();
        let mut cell = if list.is_empty() {
            "–".to_owned()
        } else {
            list.join(", ")
        };
        if *untried > 0 {
            let _ = write!(cell, " ({untried} faults not tried yet)");
        }
        let _ = writeln!(out, "| {} | {cell} |", names[*i]);
    }
    // Every composition: the faults its members catch alone, each run against the composition.
    let checks: Vec<(u32, Fault)> = masks
        .iter()
        .flat_map(|m| {
            let mut faults: Vec<Fault> = alone
                .iter()
                .filter(|(i, _, _)| m & (1 << i) != 0)
                .flat_map(|(_, f, _)| f.iter().copied())
                .collect();
            faults.sort_by_key(|f| f.name());
            faults.dedup();
            faults.into_iter().map(move |f| (*m, f))
        })
        .collect();
    let results: Vec<(u32, Fault, Option<u64>)> =
        checks.par_iter().map(|&(m, f)| (m, f, caught(m, f))).collect();
    let caught_in = |seed: &Option<u64>| seed.is_some_and(|s| s > 0);
    let checked = results.iter().filter(|r| r.2.is_some()).count();
    let untried = results.len() - checked;
    let missed: Vec<String> = results
        .iter()
        .filter(|r| r.2 == Some(0))
        .map(|(m, f, _)| format!("`{f}` in `{}`", subset_name(names, *m)))
        .collect();
    let _ = writeln!(
        out,
        "\n{checked} (composition, fault) pairs checked, {} caught, {} missed{}.\n",
        checked - missed.len(),
        missed.len(),
        if untried > 0 || alone.iter().any(|(_, _, u)| *u > 0) {
            format!(
                "; **incomplete: {untried} pairs not run yet, and the faults some models catch alone not all known** (give the same command again)"
            )
        } else {
            String::new()
        }
    );
    let _ = writeln!(
        out,
        "| model | faults it catches alone | compositions containing it | (composition, fault) pairs | caught |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|");
    for (i, found, _) in &alone {
        let bit = 1u32 << i;
        let pairs: Vec<&(u32, Fault, Option<u64>)> = results
            .iter()
            .filter(|(m, f, s)| m & bit != 0 && found.contains(f) && s.is_some())
            .collect();
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} |",
            names[*i],
            found.len(),
            masks.iter().filter(|m| *m & bit != 0).count(),
            pairs.len(),
            pairs.iter().filter(|r| caught_in(&r.2)).count()
        );
    }
    if !missed.is_empty() {
        let _ = writeln!(out, "\nMissed:\n");
        for m in &missed {
            let _ = writeln!(out, "* {m}");
        }
    }
    let _ = writeln!(out);
}

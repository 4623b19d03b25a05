//! The figures of `docs/energybus.md`: the emulated EnergyBus system on virtual time.
//!
//! `cargo run --release -p canopener-runtime --example energybus_report [DEVICES] [SEEDS] [FAULT_SEEDS]`
//! (defaults 3, 5, 20) prints, as Markdown:
//! 1. the boot of the controller and DEVICES devices on a bit-accurate 250 kbit/s virtual bus: which
//!    device got which node-ID by fastscan and when it reached Operating, telegrams per service;
//! 2. the FORTE paper's test purposes: the size of each complete test graph (`mbt synth`), and SEEDS
//!    runs guided by each purpose against the system: reached, steps, virtual time, and whether the
//!    run's trace is a path of the graph ending in PASS;
//! 3. clean runs of every EnergyBus model, SEEDS seeds;
//! 4. the paper's three deviations as faults of the emulated device: FAULT_SEEDS seeds each, caught,
//!    median steps and virtual time to `fail`, and what each does to the system booted by the
//!    controller.

// An example front end: it prints what it measured.
#![allow(clippy::print_stdout, clippy::print_stderr)]

use std::time::Duration;

use canopener_can::{Bitrate, Instant};
use canopener_device::energybus::station::{DeviceFault, EnergyBusFault};
use canopener_device::faults::Fault;
use canopener_mbt::executor::{RunConfig, RunResult, Verdict};
use canopener_mbt::explore::explore;
use canopener_runtime::energybus_graphs::{PURPOSES, PaperPurpose, follows, graph, model, run};
use canopener_sim::energybus::system::{BOOT_LIMIT, EnergyBusSystem, boot, ready_for_test};
use canopener_sim::energybus::telegrams::TelegramDecoder;
use canopener_wire::NodeId;

const STEPS: usize = 3000;
const FAULT_STEPS: usize = 2000;

fn main() {
    let mut args = std::env::args()
        .skip(1)
        .map(|a| a.parse::<usize>().expect("numbers: DEVICES SEEDS FAULT_SEEDS"));
    let devices = args.next().unwrap_or(3);
    let seeds = args.next().unwrap_or(5) as u64;
    let fault_seeds = args.next().unwrap_or(20) as u64;
    let started = std::time::Instant::now();

    boot_table(devices);
    purpose_tables(seeds);
    clean_table(seeds);
    deviation_table(fault_seeds);
    println!(
        "\nThe whole command took {:.1} s of wall time.",
        started.elapsed().as_secs_f64()
    );
}

fn boot_table(devices: usize) {
    let system = EnergyBusSystem::new(devices).bit_accurate(Bitrate::K250);
    let mut bus = system.start().expect("the system starts");
    let report = boot(&mut bus, Instant::ZERO + BOOT_LIMIT, Duration::ZERO).expect("boots");
    println!("### Boot: the controller and {devices} devices, bit-accurate virtual bus at 250 kbit/s\n");
    println!("| node-ID | LSS address (vendor, product, revision, serial) | Operating at |");
    println!("|---|---|---|");
    for w in &report.operating {
        let a = w.address;
        println!(
            "| {} | {:#010X}, {:#010X}, {:#010X}, {:#010X} | {:.3} s |",
            w.node,
            a.vendor_id,
            a.product_code,
            a.revision_number,
            a.serial_number,
            seconds(w.at)
        );
    }
    let mut decoder = TelegramDecoder::new(&system.eds(), system.profile().expect("profile"));
    let mut counts: Vec<(String, usize)> = Vec::new();
    let mut ems = 0;
    for (at, frame) in &report.frames {
        let t = decoder.decode(*at, frame);
        ems += usize::from(t.ems.is_some());
        let name = t.service.to_string();
        match counts.iter_mut().find(|(n, _)| *n == name) {
            Some((_, c)) => *c += 1,
            None => counts.push((name, 1)),
        }
    }
    let counts: Vec<String> = counts.iter().map(|(n, c)| format!("{n} {c}")).collect();
    println!(
        "\nAll {devices} Operating at {:.3} s; {} telegrams until then ({}), {ems} of them carrying an EMS object.",
        report.all_operating_at.map_or(f64::NAN, seconds),
        report.frames.len(),
        counts.join(", ")
    );
}

/// The system a purpose's model is run against, and the device under test.
fn setup(p: &PaperPurpose) -> (EnergyBusSystem, Option<NodeId>) {
    match p.model {
        "energybus-controller" => (EnergyBusSystem::new(0), None),
        "energybus-lss" => (EnergyBusSystem::new(1).without_controller(), None),
        _ => (EnergyBusSystem::new(3), NodeId::new(p.node)),
    }
}

fn purpose_tables(seeds: u64) {
    let eds = EnergyBusSystem::new(0).eds();
    println!("\n### The test purposes: complete test graphs, and runs guided by them ({seeds} seeds)\n");
    println!(
        "| scenario (FORTE §5.4) | model, purpose | specification states / transitions | test graph states / transitions | reached | median steps | median virtual time | traces on the graph, ending in PASS |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for p in &PURPOSES {
        let m = model(p.model, p.node, &eds).expect("the model compiles");
        let (space, _) = explore(&m, 1_000_000);
        let ctg = graph(&m, p.purpose, 1_000_000).expect("the purpose can be reached");
        let (system, under_test) = setup(p);
        let purpose = m.purposes.iter().find(|x| x.name == p.purpose).cloned();
        let mut outcomes = Vec::new();
        let mut on_graph = 0;
        for seed in 1..=seeds {
            let config = RunConfig {
                seed,
                steps: STEPS,
                purpose: purpose.clone(),
                ..RunConfig::default()
            };
            let o = run(&system, under_test, &m, config).expect("the system runs");
            on_graph += usize::from(follows(&ctg, &o.trace, m.resets.len()) == Ok(true));
            outcomes.push(o);
        }
        let reached = outcomes
            .iter()
            .filter(|o| o.verdict == Verdict::Pass && o.purpose.as_ref().is_some_and(|(_, r)| *r))
            .count();
        println!(
            "| {} | {}, {} | {} / {} | {} / {} | {reached}/{seeds} | {} | {} s | {on_graph}/{seeds} |",
            p.scenario,
            p.model,
            p.purpose,
            space.lts.states,
            space.lts.transitions.len(),
            ctg.states,
            ctg.transitions.len(),
            median(outcomes.iter().map(|o| o.steps as f64)),
            median(outcomes.iter().map(virtual_time)),
        );
    }
}

fn clean_table(seeds: u64) {
    let eds = EnergyBusSystem::new(0).eds();
    println!("\n### Clean system: every EnergyBus model, {seeds} seeds x {STEPS} steps\n");
    println!("| model | against | verdicts | transitions covered | virtual time per run |");
    println!("|---|---|---|---|---|");
    let rows: [(&str, u8, &str); 3] = [
        ("energybus-ems", 2, "node 2 of 3 devices booted by the controller"),
        ("energybus-lss", 0xFF, "one device alone, unconfigured"),
        (
            "energybus-controller",
            2,
            "the controller alone (the tester plays the device)",
        ),
    ];
    for (name, node, against) in rows {
        let m = model(name, node, &eds).expect("the model compiles");
        let p = PURPOSES
            .iter()
            .find(|p| p.model == name)
            .expect("a purpose of the model");
        let (system, under_test) = setup(p);
        let mut verdicts = Vec::new();
        let mut covered = 0;
        let mut time = 0.0;
        for seed in 1..=seeds {
            let config = RunConfig {
                seed,
                steps: STEPS,
                ..RunConfig::default()
            };
            let o = run(&system, under_test, &m, config).expect("the system runs");
            verdicts.push(format!("{:?}", o.verdict).to_lowercase());
            covered = covered.max(o.coverage.transitions[0]);
            time = virtual_time(&o);
        }
        verdicts.sort();
        verdicts.dedup();
        println!(
            "| {name} | {against} | {} | {covered}/{} | {time:.0} s |",
            verdicts.join(", "),
            m.transitions.len()
        );
    }
}

fn deviation_table(seeds: u64) {
    let eds = EnergyBusSystem::new(0).eds();
    println!(
        "\n### The paper's three deviations as faults of the emulated device: {seeds} seeds, at most {FAULT_STEPS} steps\n"
    );
    println!(
        "| deviation (FORTE §5.4) | fault | model, against | caught | median steps | median virtual time | first reason |"
    );
    println!("|---|---|---|---|---|---|---|");
    let rows: [(&str, DeviceFault, &str, u8); 3] = [
        (
            "1. missing counter value data in SYNC message reception",
            DeviceFault::Catalogue(Fault::SyncCounterMissing),
            "sync",
            2,
        ),
        (
            "2. missing state change in the LSS FSA during configuration",
            DeviceFault::Catalogue(Fault::LssStateNotChanged),
            "energybus-lss",
            0xFF,
        ),
        (
            "3. wrong behaviour of unconfigured slaves in the LSS fastscan protocol",
            DeviceFault::EnergyBus(EnergyBusFault::FastscanWrongAnswer),
            "energybus-lss",
            0xFF,
        ),
    ];
    for (deviation, fault, name, node) in rows {
        let m = model(name, node, &eds).expect("the model compiles");
        let (system, under_test, against) = if node == 0xFF {
            (
                EnergyBusSystem::new(1).without_controller().fault(None, fault),
                None,
                "one device alone, unconfigured",
            )
        } else {
            (
                EnergyBusSystem::new(2).fault(Some(0), fault),
                NodeId::new(node),
                "node 2 of 2 devices booted by the controller",
            )
        };
        let mut caught: Vec<RunResult> = Vec::new();
        for seed in 1..=seeds {
            let config = RunConfig {
                seed,
                steps: FAULT_STEPS,
                ..RunConfig::default()
            };
            let o = run(&system, under_test, &m, config).expect("the system runs");
            if o.verdict == Verdict::Fail {
                caught.push(o);
            }
        }
        println!(
            "| {deviation} | {fault} | {name}, {against} | {}/{seeds} | {} | {} s | {} |",
            caught.len(),
            median(caught.iter().map(|o| o.steps as f64)),
            median(caught.iter().map(virtual_time)),
            caught.first().map_or("-".to_owned(), |o| o.reason.clone())
        );
    }
    println!(
        "\nWhat each does to the system booted by the controller (2 devices, the fault on the one with serial number 2):\n"
    );
    for fault in DeviceFault::PAPER_DEVIATIONS {
        let system = EnergyBusSystem::new(2).fault(Some(1), fault);
        let text = match ready_for_test(&system, None) {
            Ok((_, Some(report))) => {
                let serials: Vec<String> = report
                    .operating
                    .iter()
                    .map(|w| format!("node {} = serial {}", w.node, w.address.serial_number))
                    .collect();
                match report.all_operating_at {
                    Some(at) => format!(
                        "both Operating at {:.3} s; the scan reported {}",
                        seconds(at),
                        serials.join(", ")
                    ),
                    None => format!(
                        "{} of 2 Operating after {:.0} s ({})",
                        report.operating.len(),
                        BOOT_LIMIT.as_secs_f64(),
                        serials.join(", ")
                    ),
                }
            }
            Ok((_, None)) => "no boot report".to_owned(),
            Err(error) => error.to_string(),
        };
        println!("- `{fault}`: {text}");
    }
}

fn virtual_time(o: &RunResult) -> f64 {
    o.trace.last().map_or(0.0, |s| s.t)
}

fn seconds(at: Instant) -> f64 {
    at.as_nanos() as f64 / 1e9
}

fn median(values: impl Iterator<Item = f64>) -> String {
    let mut v: Vec<f64> = values.collect();
    if v.is_empty() {
        return "-".to_owned();
    }
    v.sort_by(f64::total_cmp);
    let m = v[v.len() / 2];
    if m.fract() == 0.0 {
        format!("{m:.0}")
    } else {
        format!("{m:.3}")
    }
}

//! The figures of `docs/mbt.md`: the shipped models against simulated devices on virtual time.
//!
//! `cargo run --release -p canopener-runtime --example mbt_matrix [STEPS] [SEEDS] [FAULT_SEEDS]`
//! (defaults 10000, 5, 20) prints, as Markdown:
//! 1. clean devices: every shipped model, SEEDS seeds of STEPS steps each, verdicts and time taken;
//! 2. every fault of the catalogue against every model: how many of FAULT_SEEDS seeds fail, the
//!    median steps and virtual time to the failure;
//! 3. shrinking: for each caught fault (first failing seed), inputs before and after, 1-minimality;
//! 4. LSS fastscan on a device without a node-ID (FFh), guided by the purpose `fastscan_select`,
//!    clean and with each LSS fault: SEEDS seeds.
//!
//! The device is CANopenNode's example I/O EDS from the corpus (heartbeat 1000 ms), node 5.

// An example front end: it prints what it measured.
#![allow(clippy::print_stdout, clippy::print_stderr)]

use std::time::Duration;

use canopener_can::Instant;
use canopener_device::faults::Fault;
use canopener_eds::model::Eds;
use canopener_link::link::LinkError;
use canopener_mbt::compile::{Options, Source, compile};
use canopener_mbt::executor::{RunConfig, RunResult, Verdict};
use canopener_mbt::model::Model;
use canopener_mbt::shipped;
use canopener_runtime::mbt_run::{run, shrink};
use canopener_sim::simulation::{SimulatedBus, Simulation};
use canopener_testkit::corpus;

const IO: &str = "CANopenNode__CANopenNode__example__IO.eds";
const NODE: u8 = 5;
const FAULT_STEPS: usize = 1000;

fn main() {
    let mut args = std::env::args()
        .skip(1)
        .map(|a| a.parse::<usize>().expect("numbers: STEPS SEEDS FAULT_SEEDS"));
    let steps = args.next().unwrap_or(10_000);
    let seeds = args.next().unwrap_or(5) as u64;
    let fault_seeds = args.next().unwrap_or(20) as u64;
    let eds = canopener_eds::load(&std::fs::read(corpus::eds(IO)).expect("the corpus EDS")).eds;
    // The EnergyBus models need the emulated EnergyBus system (`energybus_report` measures them).
    let models: Vec<(&str, Model)> = shipped::MODELS
        .iter()
        .filter(|m| !m.name.starts_with("energybus"))
        .map(|m| (m.name, model(m.name, &eds)))
        .collect();

    println!("### Clean device: {seeds} seeds x {steps} steps per model\n");
    println!("| model | verdicts | transitions covered | virtual time per run | wall time (all seeds) |");
    println!("|---|---|---|---|---|");
    for (name, model) in &models {
        let wall = std::time::Instant::now();
        let mut verdicts = Vec::new();
        let mut covered = 0;
        let mut virtual_s = 0.0;
        for seed in 1..=seeds {
            let o = test(model, &eds, &[], seed, steps);
            verdicts.push(format!("{:?}", o.verdict).to_lowercase());
            covered = covered.max(o.coverage.transitions[0]);
            virtual_s = o.trace.last().map_or(0.0, |s| s.t);
        }
        verdicts.dedup();
        println!(
            "| {name} | {} | {covered}/{} | {virtual_s:.0} s | {:.1} s |",
            verdicts.join(", "),
            model.transitions.len(),
            wall.elapsed().as_secs_f64()
        );
    }

    println!("\n### Faults: {fault_seeds} seeds, at most {FAULT_STEPS} steps each\n");
    println!("Cells: seeds failing / seeds; median steps and median virtual time to `fail` when caught.\n");
    print!("| fault |");
    for (name, _) in &models {
        print!(" {name} |");
    }
    println!();
    println!("|---|{}", "---|".repeat(models.len()));
    let mut caught: Vec<(Fault, usize, Vec<canopener_mbt::executor::ScriptStep>)> = Vec::new();
    for fault in Fault::ALL {
        print!("| {} |", fault.name());
        for (m, (_, model)) in models.iter().enumerate() {
            let mut fails = Vec::new();
            for seed in 1..=fault_seeds {
                let o = test(model, &eds, &[fault], seed, FAULT_STEPS);
                if o.verdict == Verdict::Fail {
                    fails.push((o.steps, o.trace.last().map_or(0.0, |s| s.t), o.script()));
                }
            }
            if fails.is_empty() {
                print!(" – |");
                continue;
            }
            let mut steps: Vec<usize> = fails.iter().map(|f| f.0).collect();
            let mut times: Vec<f64> = fails.iter().map(|f| f.1).collect();
            steps.sort_unstable();
            times.sort_by(f64::total_cmp);
            print!(
                " {}/{fault_seeds}: {} steps, {:.2} s |",
                fails.len(),
                steps[steps.len() / 2],
                times[times.len() / 2]
            );
            if !caught.iter().any(|(f, _, _)| *f == fault) {
                caught.push((fault, m, fails[0].2.clone()));
            }
        }
        println!();
    }

    println!("\n### Shrinking (first failing seed, the first model that catches the fault)\n");
    println!("| fault | model | inputs before | after | runs | 1-minimal |");
    println!("|---|---|---|---|---|---|");
    for (fault, m, inputs) in caught {
        let (name, model) = &models[m];
        let config = RunConfig {
            steps: FAULT_STEPS,
            ..RunConfig::default()
        };
        let mut new_bus = || bus(&eds, &[fault]);
        match shrink(&mut new_bus, model, &config, &inputs, None).expect("virtual bus") {
            Some(s) => {
                let minimal = (0..s.after.len()).all(|i| {
                    let mut fewer = s.after.clone();
                    fewer.remove(i);
                    let scripted = RunConfig {
                        script: Some(fewer),
                        ..config.clone()
                    };
                    run(
                        &mut bus(&eds, &[fault]).expect("virtual bus"),
                        model,
                        scripted,
                        None,
                    )
                    .expect("virtual bus")
                    .verdict
                        != Verdict::Fail
                });
                println!(
                    "| {} | {name} | {} | {} | {} | {} |",
                    fault.name(),
                    s.before.len(),
                    s.after.len(),
                    s.runs,
                    if minimal { "yes" } else { "NO" }
                );
            }
            None => println!(
                "| {} | {name} | {} | (replay does not fail) | | |",
                fault.name(),
                inputs.len()
            ),
        }
    }

    fastscan(&eds, seeds);
}

/// Section 4: fastscan on a non-configured device, guided by the shipped purpose.
fn fastscan(eds: &Eds, seeds: u64) {
    const NON_CONFIGURED: u8 = 0xFF;
    let lss = model_for("lss", eds, NON_CONFIGURED);
    let purpose = lss
        .purposes
        .iter()
        .find(|p| p.name == "fastscan_select")
        .expect("shipped purpose");
    println!(
        "\n### LSS fastscan, device without a node-ID (FFh), purpose `fastscan_select`: {seeds} seeds\n"
    );
    println!("| device | verdicts | purpose reached | median steps | median virtual time |");
    println!("|---|---|---|---|---|");
    for (label, faults) in [
        ("clean", &[][..]),
        ("lss-state-not-changed", &[Fault::LssStateNotChanged][..]),
        ("no-lss", &[Fault::NoLss][..]),
    ] {
        let mut verdicts = Vec::new();
        let mut reached = 0;
        let mut steps = Vec::new();
        let mut times = Vec::new();
        for seed in 1..=seeds {
            let config = RunConfig {
                seed,
                steps: 2000,
                purpose: Some(purpose.clone()),
                ..RunConfig::default()
            };
            let mut link = bus_for(eds, NON_CONFIGURED, faults).expect("virtual bus");
            let o = run(&mut link, &lss, config, Some(Duration::from_secs(1_000_000))).expect("virtual bus");
            verdicts.push(format!("{:?}", o.verdict).to_lowercase());
            reached += usize::from(o.purpose.as_ref().is_some_and(|p| p.1));
            steps.push(o.steps);
            times.push(o.trace.last().map_or(0.0, |s| s.t));
        }
        verdicts.sort();
        verdicts.dedup();
        steps.sort_unstable();
        times.sort_by(f64::total_cmp);
        println!(
            "| {label} | {} | {reached}/{seeds} | {} | {:.2} s |",
            verdicts.join(", "),
            steps[steps.len() / 2],
            times[times.len() / 2]
        );
    }
}

fn model(name: &str, eds: &Eds) -> Model {
    model_for(name, eds, NODE)
}

fn model_for(name: &str, eds: &Eds, node_id: u8) -> Model {
    let sources = [Source {
        origin: name.into(),
        text: shipped::text(name).expect("shipped").into(),
    }];
    let options = Options {
        node_id,
        eds: Some(eds),
        set: Vec::new(),
    };
    compile(&sources, &options, &|n| shipped::text(n).map(str::to_owned))
        .0
        .expect("shipped models check")
}

fn bus(eds: &Eds, faults: &[Fault]) -> Result<SimulatedBus, LinkError> {
    bus_for(eds, NODE, faults)
}

fn bus_for(eds: &Eds, node_id: u8, faults: &[Fault]) -> Result<SimulatedBus, LinkError> {
    let mut bus = Simulation::ideal()
        .device(eds, node_id)
        .faults(faults.iter().copied())
        .start()
        .expect("simulation");
    bus.run_until(Instant::from_millis(100))?;
    Ok(bus)
}

fn test(model: &Model, eds: &Eds, faults: &[Fault], seed: u64, steps: usize) -> RunResult {
    let config = RunConfig {
        seed,
        steps,
        ..RunConfig::default()
    };
    run(
        &mut bus(eds, faults).expect("virtual bus"),
        model,
        config,
        Some(Duration::from_secs(1_000_000)),
    )
    .expect("virtual bus")
}

//! `mbt run`, `mbt replay` and `mbt shrink`: the executor on a bus or a simulated device.

use std::time::Duration;

use canopener_can::Instant;
use canopener_link::link::BusLink;
use canopener_mbt::executor::{RunConfig, RunResult, Verdict};
use canopener_mbt::log::{self, RunHeader};
use canopener_mbt::model::Model;
use canopener_runtime::mbt_run;
use canopener_sim::simulation::{SimulatedBus, Simulation};

use crate::bus_open::open_bus;
use crate::error::{CliError, CliResult, exit_code};
use crate::master::output::count_bar;
use crate::mbt::args::NON_CONFIGURED;
use crate::mbt::args::{DeviceArgs, Format, ReplayArgs, RunArgs, ShrinkArgs, Strategy};
use crate::mbt::energybus;
use crate::mbt::load::{description, load, write};
use crate::output::print_stdout;
use crate::stop::StopFlag;

/// The device's power-on traffic is over by then; the run starts with the model's own reset.
const SIM_SETTLE: Instant = Instant::from_millis(100);

pub(crate) fn run(args: RunArgs) -> CliResult {
    let eds = models_description(args.model.eds.as_ref(), &args.device)?;
    let mut set = args.model.set.clone();
    // An EnergyBus device gets its node-ID by LSS and does not store it (docs/energybus.md): after
    // reset node it is non-configured, so the nmt model must not expect a boot-up there.
    if args.device.energybus.is_some() && !set.iter().any(|(name, _)| name == "KEEPS_NODE_ID") {
        set.push(("KEEPS_NODE_ID".to_owned(), 0));
    }
    let loaded = load(&args.model.models, args.model.node, eds.as_ref(), &set)?;
    eprint!("{}", loaded.warnings);
    let config = RunConfig {
        seed: args.seed,
        steps: args.steps,
        tolerance_us: i64::try_from(args.tolerance.as_micros()).unwrap_or(i64::MAX),
        strategy: match args.strategy {
            Strategy::Uniform => canopener_mbt::executor::Strategy::Uniform,
            Strategy::Coverage => canopener_mbt::executor::Strategy::Coverage,
        },
        purpose: find_purpose(&loaded.model, args.purpose.as_deref())?,
        ..RunConfig::default()
    };
    if let Some(seeds) = args.seeds {
        return crate::mbt::seeds::run(&args, &loaded.model, config, seeds);
    }
    let header = RunHeader::new(&args.model.models, &loaded.model.hash, args.model.node, &config);
    let outcome = execute(&args.device, args.model.node, &loaded.model, config)?;
    if let Some(path) = &args.log {
        write(path, &log::write(&header, &outcome))?;
    }
    if let Some(path) = &args.coverage_dot {
        write(
            path,
            &canopener_mbt::explore::coverage_dot(&loaded.model, &outcome.coverage.taken),
        )?;
    }
    if let Some(path) = &args.coverage_svg {
        let svg = canopener_mbt::explore::coverage_svg(&loaded.model, &outcome.coverage.taken)
            .map_err(|e| CliError::Internal(e.into()))?;
        write(path, &svg)?;
    }
    report(&header, &loaded.model, &outcome, args.format)
}

pub(crate) fn replay(args: ReplayArgs) -> CliResult {
    let log = read_log(&args.log)?;
    let eds = models_description(args.eds.as_ref(), &args.device)?;
    let loaded = load(&log.header.models, log.header.node, eds.as_ref(), &[])?;
    warn_hash(&log.header, &loaded.model);
    let mut config = log.header.config(Some(log.script.clone()));
    config.purpose = find_purpose(&loaded.model, log.header.purpose.as_deref())?;
    let outcome = execute(&args.device, log.header.node, &loaded.model, config)?;
    report(&log.header, &loaded.model, &outcome, args.format)
}

pub(crate) fn shrink(args: ShrinkArgs) -> CliResult {
    let log = read_log(&args.log)?;
    let eds = models_description(args.eds.as_ref(), &args.device)?;
    let loaded = load(&log.header.models, log.header.node, eds.as_ref(), &[])?;
    warn_hash(&log.header, &loaded.model);
    let mut config = log.header.config(None);
    config.purpose = find_purpose(&loaded.model, log.header.purpose.as_deref())?;
    let node = log.header.node;
    let limit = args.device.time_limit;
    let shrunk = match (&args.device.sim, args.device.energybus) {
        (_, Some(count)) => mbt_run::shrink(
            &mut || energybus::link(&args.device, count, node),
            &loaded.model,
            &config,
            &log.script,
            limit,
        )?,
        (Some(file), None) => mbt_run::shrink(
            &mut || simulated(file, &args.device, node),
            &loaded.model,
            &config,
            &log.script,
            limit,
        )?,
        (None, None) => mbt_run::shrink(
            &mut || bus_link(&args.device),
            &loaded.model,
            &config,
            &log.script,
            limit,
        )?,
    };
    let Some(shrunk) = shrunk else {
        eprintln!(
            "the log's {} inputs no longer make the device fail",
            log.script.len()
        );
        return Err(CliError::Exit(exit_code::CHECK_FAILED));
    };
    if let Some(path) = &args.output {
        write(path, &log::write(&log.header, &shrunk.outcome))?;
    }
    let mut text = format!(
        "shrunk {} inputs to {} in {} runs; the short script still fails: {}\n",
        shrunk.before.len(),
        shrunk.after.len(),
        shrunk.runs,
        shrunk.outcome.reason
    );
    for input in &shrunk.after {
        let at = input
            .at_us
            .map(|t| format!("{:>9.3}s ", t as f64 / 1e6))
            .unwrap_or_default();
        text.push_str(&format!("  {at}{}\n", input.label));
    }
    print_stdout(&text)
}

/// The description the models' parameters read: `--eds`, else the simulated device's, else the
/// EnergyBus one of `--energybus`.
fn models_description(
    eds: Option<&std::path::PathBuf>,
    device: &DeviceArgs,
) -> CliResult<Option<canopener_eds::Eds>> {
    match (eds.or(device.sim.as_ref()), device.energybus) {
        (None, Some(_)) => Ok(Some(energybus::description())),
        (path, _) => description(path),
    }
}

/// The purpose called `name` in the models.
fn find_purpose(model: &Model, name: Option<&str>) -> CliResult<Option<canopener_mbt::purpose::Purpose>> {
    let Some(name) = name else { return Ok(None) };
    match model.purposes.iter().find(|p| p.name == name) {
        Some(p) => Ok(Some(p.clone())),
        None => {
            let names: Vec<&str> = model.purposes.iter().map(|p| p.name.as_str()).collect();
            Err(CliError::Usage(format!(
                "the models have no purpose `{name}`; they have: {}",
                if names.is_empty() {
                    "none".to_owned()
                } else {
                    names.join(", ")
                }
            )))
        }
    }
}

fn read_log(path: &std::path::Path) -> CliResult<log::Log> {
    let bytes = canopener_files::read(path).map_err(|e| CliError::read_file(path, e))?;
    let text = String::from_utf8_lossy(&bytes);
    log::read(&text)
        .map_err(|e| CliError::InvalidInput(format!("{}:{}: {}", path.display(), e.line, e.message)))
}

fn warn_hash(header: &RunHeader, model: &Model) {
    if header.model_hash != model.hash {
        eprintln!(
            "warning: the models changed since the log was written (model hash differs); the replay may diverge"
        );
    }
}

/// A fresh simulated device (one per run, so that every run starts from power-on).
pub(crate) fn simulated(file: &std::path::Path, device: &DeviceArgs, node: u8) -> CliResult<SimulatedBus> {
    let mut bus = Simulation::ideal()
        .file(file)
        // Without a node-ID of its own the device starts LSS non-configured.
        .first_node_id((node != NON_CONFIGURED).then_some(node))
        .faults(energybus::catalogue_faults(&device.faults)?)
        .start()?;
    bus.run_until(SIM_SETTLE)?;
    Ok(bus)
}

fn bus_link(device: &DeviceArgs) -> CliResult<BusLink> {
    let bus = open_bus(device.bus.spec.as_deref(), "mbt")?;
    Ok(BusLink::new(bus, StopFlag::install()?.token())?)
}

fn execute(device: &DeviceArgs, node: u8, model: &Model, config: RunConfig) -> CliResult<RunResult> {
    let limit: Option<Duration> = device.time_limit;
    Ok(match (&device.sim, device.energybus) {
        (_, Some(count)) => mbt_run::run(&mut energybus::link(device, count, node)?, model, config, limit)?,
        (Some(file), None) => mbt_run::run(&mut simulated(file, device, node)?, model, config, limit)?,
        (None, None) => {
            // On a real bus a long run takes the wall clock's time: show its steps on a terminal.
            let bar = count_bar(
                config.steps as u64,
                "{bar:30} {pos}/{len} steps [{elapsed}<{eta}]",
            );
            let outcome = mbt_run::run_watched(&mut bus_link(device)?, model, config, limit, &mut |steps| {
                bar.set_position(steps as u64);
            });
            bar.finish_and_clear();
            outcome?
        }
    })
}

/// Prints the outcome and maps the verdict to the exit code: 0 pass, 6 fail or inconclusive, 7 a
/// device that sent nothing the models know.
fn report(header: &RunHeader, model: &Model, outcome: &RunResult, format: Format) -> CliResult {
    // The size of the untimed state space, for the coverage line; a composition's can be large, so
    // it is counted up to a bound (JSON `null`, "more than N" beyond it).
    const COUNT_STATES: usize = 20_000;
    let (space, _) = canopener_mbt::explore::explore(model, COUNT_STATES);
    let total = (!space.truncated).then_some(space.lts.states);
    let total_text = total.map_or_else(|| format!("more than {COUNT_STATES}"), |n| n.to_string());
    match format {
        Format::Json => {
            let trace: Vec<serde_json::Value> = outcome
                .trace
                .iter()
                .map(|s| serde_json::json!({"t": s.t, "dir": s.dir, "label": s.label, "frame": s.frame}))
                .collect();
            let value = serde_json::json!({
                "version": 1,
                "models": header.models,
                "model_hash": model.hash,
                "seed": header.seed,
                "steps": outcome.steps,
                "verdict": outcome.verdict,
                "reason": outcome.reason,
                "trace": trace,
                "allowed": outcome.allowed,
                "inputs": outcome.inputs,
                "purpose": outcome.purpose.as_ref().map(|(name, reached)| serde_json::json!({"name": name, "reached": reached})),
                "coverage": {
                    "purposes": outcome.purpose.as_ref().map(|(_, reached)| [usize::from(*reached), 1]),
                    "states": [serde_json::json!(outcome.coverage.states_seen), serde_json::json!(total)],
                    "transitions": outcome.coverage.transitions,
                    "locations": outcome.coverage.locations,
                },
            });
            print_stdout(&format!("{value}\n"))?;
        }
        Format::Human => {
            let mut text = format!(
                "{}: {} after {} steps ({} frames judged) - {}\n",
                model.name(),
                match outcome.verdict {
                    Verdict::Pass => "PASS",
                    Verdict::Fail => "FAIL",
                    Verdict::Inconclusive => "INCONCLUSIVE",
                },
                outcome.steps,
                outcome.outputs_seen,
                outcome.reason
            );
            if outcome.verdict != Verdict::Pass {
                text.push_str("last steps:\n");
                let from = outcome.trace.len().saturating_sub(12);
                for s in &outcome.trace[from..] {
                    let frame = s
                        .frame
                        .as_ref()
                        .map(|f| format!("  ({}#{})", f.id, f.data))
                        .unwrap_or_default();
                    text.push_str(&format!("  {:>9.3}s {}{frame}\n", s.t, s.label));
                }
            }
            if !outcome.allowed.is_empty() {
                text.push_str("the model allowed:\n");
                for a in &outcome.allowed {
                    text.push_str(&format!("  {a}\n"));
                }
            }
            if let Some((name, reached)) = &outcome.purpose {
                let state = if *reached { "reached" } else { "not reached" };
                text.push_str(&format!("purpose {name}: {state}\n"));
            }
            text.push_str(&format!(
                "coverage: {}/{} transitions, {}/{} locations, {} states seen of {}\n",
                outcome.coverage.transitions[0],
                outcome.coverage.transitions[1],
                outcome.coverage.locations[0],
                outcome.coverage.locations[1],
                outcome.coverage.states_seen,
                total_text
            ));
            print_stdout(&text)?;
        }
    }
    match outcome.verdict {
        Verdict::Pass => Ok(()),
        Verdict::Fail if outcome.outputs_seen == 0 => Err(CliError::Exit(exit_code::DEVICE)),
        Verdict::Fail | Verdict::Inconclusive => Err(CliError::Exit(exit_code::CHECK_FAILED)),
    }
}

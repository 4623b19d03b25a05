//! Options of the `mbt` commands.

use std::path::PathBuf;

use clap::{Args, Subcommand, ValueEnum};

use crate::args::{BusArg, parse_fault};
use crate::grammar::{parse_duration, parse_node_id, parse_u8, parse_u64, parse_usize};

/// FFh, the node-ID of a device that has none yet (CiA 305: LSS non-configured).
pub(crate) const NON_CONFIGURED: u8 = 0xFF;

/// A node-ID as `--node` takes it everywhere, or FFh: a model may test a non-configured device.
fn parse_model_node(text: &str) -> Result<u8, String> {
    parse_node_id(text).or_else(|e| match parse_u8(text) {
        Ok(NON_CONFIGURED) => Ok(NON_CONFIGURED),
        _ => Err(format!("{e}, or 0xFF for a device without a node-ID")),
    })
}

#[derive(Debug, Subcommand)]
pub(crate) enum MbtCommand {
    /// List the shipped models and what each covers.
    #[command(after_help = "Examples:
  canopener mbt models
  canopener mbt models --format json | jq -r '.[].name'")]
    Models(ModelsArgs),
    /// Check models: syntax, names, bounded domains, τ-cycles, gate directions, time bounds; composed
    /// models: where one requires an output another refuses (M043), resets that differ (M044).
    #[command(after_help = "Examples:
  canopener mbt check nmt sdo                     # shipped models
  canopener mbt check my-device.mbt --eds device.eds --node 0x05
  canopener mbt check nmt my-consumer.mbt         # does my model agree with nmt?
Diagnostics are printed as FILE:LINE:COLUMN: severity[CODE]: message.
Exit status: 0 the models check, 3 a model has errors, 2 bad arguments.")]
    Check(ModelArgs),
    /// Explore a model's state space and export it as Aldebaran .aut (CADP, mCRL2) or DOT.
    #[command(after_help = "Examples:
  canopener mbt explore nmt --aut nmt.aut --dot nmt.dot
  dot -Tsvg nmt.dot > nmt.svg
Exit status: 0 explored, 3 the model has errors, 5 an output file could not be written.")]
    Explore(ExploreArgs),
    /// Synthesise the complete test graph of a test purpose (TGV: suspension, determinisation,
    /// product, co-reachability) as .aut.
    #[command(after_help = "Examples:
  canopener mbt synth nmt --purpose stop_and_start --aut ctg.aut
  canopener mbt synth nmt --purpose stop_and_start --spec-aut nmt-from-cadp.aut
  canopener mbt synth nmt --purpose-aut my-purpose.aut
The graph keeps the specification's labels (?GATE tester sends, !GATE device sends, QUIESCENCE);
states with a PASS or INCONCLUSIVE loop are verdicts; outputs missing from the graph are fail.
The graph is untimed: the models' clocks and windows are dropped, so it cannot judge an output that
comes too late or too early, nor how long QUIESCENCE must last; `mbt run --purpose P` follows the same
purpose with the clocks (a late output is fail there).
Exit status: 0 synthesised, 6 the purpose cannot be reached, 3 a model or .aut that does not read.")]
    Synth(SynthArgs),
    /// Test a device against models on the fly: ioco with timed quiescence.
    #[command(after_help = "Examples:
  canopener mbt run nmt sdo --sim device.eds --node 5                  # a simulated device, virtual time
  canopener mbt run nmt --sim device.eds --node 5 --fault ignores-nmt-stop --log run.jsonl
  canopener mbt run nmt --bus socketcand://127.0.0.1:29536/can0 --node 5 --eds device.eds --steps 500
  canopener mbt run sync --sim device.eds --node 5 --format json | jq .verdict
  canopener mbt run nmt --sim device.eds --node 5 --purpose stop_and_start
  canopener mbt run lss --sim device.eds --node 0xFF --purpose fastscan_select  # no node-ID yet
  canopener mbt run guarding --sim device.eds --node 5 --coverage-svg coverage.svg
  canopener mbt run nmt heartbeat sdo --sim device.eds --node 5 --steps 2000 --seeds 1..100
On a real bus a progress bar shows the steps (on a terminal).
Exit status: 0 pass, 6 fail or inconclusive, 7 the device did not answer at all, 3 a model that does
not check, 2 bad arguments, 4 bus error.")]
    Run(RunArgs),
    /// Run a log's inputs again against a device.
    #[command(after_help = "Examples:
  canopener mbt replay run.jsonl --sim device.eds --fault ignores-nmt-stop
Exit status as for `mbt run`.")]
    Replay(ReplayArgs),
    /// Shrink a failing log to the shortest input script that still fails (delta debugging).
    #[command(after_help = "Examples:
  canopener mbt shrink run.jsonl --sim device.eds --fault ignores-nmt-stop -o short.jsonl
Exit status: 0 shrunk (the short script fails), 6 the log's inputs no longer fail, 2 bad arguments.")]
    Shrink(ShrinkArgs),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum Format {
    /// Text for people.
    Human,
    /// One JSON object for machines.
    Json,
}

#[derive(Debug, Args)]
pub(crate) struct ModelsArgs {
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Human)]
    pub(crate) format: Format,
}

#[derive(Debug, Args)]
pub(crate) struct ModelArgs {
    /// Shipped model names (`canopener mbt models`) or model files; they are composed.
    #[arg(required = true, value_name = "MODEL")]
    pub(crate) models: Vec<String>,
    /// The node-ID under test ($NODEID), decimal or 0x; 0xFF for a device without a node-ID (LSS
    /// non-configured, e.g. for the `lss` model's fastscan).
    #[arg(long, default_value = "1", value_parser = parse_model_node, value_name = "N")]
    pub(crate) node: u8,
    /// The device's EDS/DCF/XDD: the models' parameters read it (heartbeat period, identity...).
    #[arg(long, value_name = "FILE")]
    pub(crate) eds: Option<PathBuf>,
    /// Override a model parameter (repeatable), e.g. --set SDO_T=200ms.
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = parse_setting)]
    pub(crate) set: Vec<(String, i64)>,
}

#[derive(Debug, Args)]
pub(crate) struct ExploreArgs {
    #[command(flatten)]
    pub(crate) model: ModelArgs,
    /// Write the state space as Aldebaran .aut.
    #[arg(long, value_name = "OUT")]
    pub(crate) aut: Option<PathBuf>,
    /// Write the state space as Graphviz DOT.
    #[arg(long, value_name = "OUT")]
    pub(crate) dot: Option<PathBuf>,
    /// Stop exploring after this many states.
    #[arg(long, default_value = "100000", value_parser = parse_usize, value_name = "N")]
    pub(crate) max_states: usize,
}

#[derive(Debug, Args)]
pub(crate) struct SynthArgs {
    #[command(flatten)]
    pub(crate) model: ModelArgs,
    /// The test purpose: the name of a `purpose` block of the models.
    #[arg(
        long,
        value_name = "P",
        required_unless_present = "purpose_aut",
        conflicts_with = "purpose_aut"
    )]
    pub(crate) purpose: Option<String>,
    /// The test purpose as an .aut file in TGV's convention (ACCEPT / REFUSE loops mark states, `*` is
    /// any other label, labels are [?|!]GATE v1 v2 .. with numbers or `_`).
    #[arg(long, value_name = "FILE")]
    pub(crate) purpose_aut: Option<PathBuf>,
    /// Take the specification from this .aut file (e.g. made by CADP or mCRL2) instead of exploring
    /// the models; its labels are ?GATE .. (inputs), !GATE .. (outputs) and i or tau.
    #[arg(long, value_name = "FILE")]
    pub(crate) spec_aut: Option<PathBuf>,
    /// Write the test graph here (stdout without it).
    #[arg(long, value_name = "OUT")]
    pub(crate) aut: Option<PathBuf>,
}

/// Where the device under test is.
#[derive(Debug, Args)]
pub(crate) struct DeviceArgs {
    #[command(flatten)]
    pub(crate) bus: BusArg,
    /// Test a simulated device built from this EDS/DCF instead, on virtual time (deterministic).
    #[arg(long, value_name = "FILE", conflicts_with = "spec")]
    pub(crate) sim: Option<PathBuf>,
    /// Give the simulated device this defect (repeatable; `canopener sim --list-faults`).
    #[arg(long = "fault", value_name = "NAME", requires = "sim", value_parser = parse_fault)]
    pub(crate) faults: Vec<canopener_device::faults::Fault>,
    /// Stop after this long (of the bus's time) with the verdict so far.
    #[arg(long, value_parser = parse_duration, value_name = "DURATION")]
    pub(crate) time_limit: Option<std::time::Duration>,
}

#[derive(Debug, Args)]
pub(crate) struct RunArgs {
    #[command(flatten)]
    pub(crate) model: ModelArgs,
    #[command(flatten)]
    pub(crate) device: DeviceArgs,
    /// Steps (inputs, outputs, quiescence observations) before the verdict pass.
    #[arg(long, default_value = "500", value_parser = parse_usize, value_name = "K")]
    pub(crate) steps: usize,
    /// The master seed: the same seed, models and device give the same run.
    #[arg(long, default_value = "1", value_parser = parse_u64, value_name = "S")]
    pub(crate) seed: u64,
    /// Run every seed of A..B (inclusive) on a fresh simulated device each, in parallel on the
    /// machine's cores (RAYON_NUM_THREADS limits them), and print one summary: verdicts, steps,
    /// coverage and the first failing seed. Needs --sim (virtual time).
    #[arg(
        long,
        value_name = "A..B",
        value_parser = parse_seeds,
        conflicts_with_all = ["seed", "log", "coverage_dot", "coverage_svg"],
        requires = "sim"
    )]
    pub(crate) seeds: Option<(u64, u64)>,
    /// Tolerance added to every time window (bus latency, timer jitter).
    #[arg(long, default_value = "2ms", value_parser = parse_duration, value_name = "DURATION")]
    pub(crate) tolerance: std::time::Duration,
    /// How inputs are chosen.
    #[arg(long, value_enum, default_value_t = Strategy::Coverage)]
    pub(crate) strategy: Strategy,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Human)]
    pub(crate) format: Format,
    /// Write the run as JSON Lines (for `replay` and `shrink`).
    #[arg(long, value_name = "OUT.jsonl")]
    pub(crate) log: Option<PathBuf>,
    /// Follow this test purpose (a `purpose` block of the models): pass once it is reached,
    /// inconclusive if the run leaves it; inputs that advance it are chosen first.
    #[arg(long, value_name = "P")]
    pub(crate) purpose: Option<String>,
    /// Write the coverage as DOT: visited locations and transitions coloured.
    #[arg(long, value_name = "OUT.dot")]
    pub(crate) coverage_dot: Option<PathBuf>,
    /// Write the coverage as SVG (the same colours, drawn without Graphviz).
    #[arg(long, value_name = "OUT.svg")]
    pub(crate) coverage_svg: Option<PathBuf>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum Strategy {
    /// Every allowed input equally likely.
    Uniform,
    /// Inputs of transitions not taken yet first.
    Coverage,
}

#[derive(Debug, Args)]
pub(crate) struct ReplayArgs {
    /// The log of a run (`mbt run --log`).
    #[arg(value_name = "LOG.jsonl")]
    pub(crate) log: PathBuf,
    #[command(flatten)]
    pub(crate) device: DeviceArgs,
    /// The device's description, if the run had one.
    #[arg(long, value_name = "FILE")]
    pub(crate) eds: Option<PathBuf>,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Human)]
    pub(crate) format: Format,
}

#[derive(Debug, Args)]
pub(crate) struct ShrinkArgs {
    /// The log of a failing run (`mbt run --log`).
    #[arg(value_name = "LOG.jsonl")]
    pub(crate) log: PathBuf,
    #[command(flatten)]
    pub(crate) device: DeviceArgs,
    /// The device's description, if the run had one.
    #[arg(long, value_name = "FILE")]
    pub(crate) eds: Option<PathBuf>,
    /// Write the shortened run's log here.
    #[arg(short = 'o', long = "output", value_name = "SHORT.jsonl")]
    pub(crate) output: Option<PathBuf>,
}

/// `A..B`: the seeds A to B, inclusive.
fn parse_seeds(text: &str) -> Result<(u64, u64), String> {
    let (a, b) = text
        .split_once("..")
        .ok_or_else(|| format!("'{text}' is not A..B, e.g. 1..100"))?;
    let number = |s: &str| {
        s.trim()
            .parse::<u64>()
            .map_err(|_| format!("'{s}' in '{text}' is not a seed (a number)"))
    };
    let (a, b) = (number(a)?, number(b)?);
    if a > b {
        return Err(format!("'{text}': the first seed is above the last"));
    }
    if b - a >= 100_000 {
        return Err(format!("'{text}': at most 100000 seeds at once"));
    }
    Ok((a, b))
}

/// `NAME=VALUE`, the value a number (decimal or 0x) or a duration with a unit (in µs, as models
/// count time).
fn parse_setting(text: &str) -> Result<(String, i64), String> {
    let (name, value) = text
        .split_once('=')
        .ok_or_else(|| format!("'{text}' is not NAME=VALUE, e.g. SDO_T=200ms or N=5"))?;
    let v = value.trim();
    let number = match v.strip_prefix("0x").or_else(|| v.strip_prefix("0X")) {
        Some(hex) => i64::from_str_radix(hex, 16).ok(),
        None => v.parse().ok(),
    };
    let value = match number {
        Some(n) => n,
        None => i64::try_from(parse_duration(v)?.as_micros()).map_err(|_| format!("'{v}' is too long"))?,
    };
    Ok((name.trim().to_owned(), value))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seed_ranges_parse() {
        assert_eq!(parse_seeds("1..100"), Ok((1, 100)));
        assert_eq!(parse_seeds("7..7"), Ok((7, 7)));
        assert!(parse_seeds("5..1").is_err());
        assert!(parse_seeds("1-5").is_err());
        assert!(parse_seeds("a..5").is_err());
    }

    #[test]
    fn settings_parse() {
        assert_eq!(parse_setting("SDO_T=200ms"), Ok(("SDO_T".into(), 200_000)));
        assert_eq!(parse_setting("N=0x10"), Ok(("N".into(), 16)));
        assert!(parse_setting("N").is_err());
    }
}

//! Options of the `net` commands.

use std::path::PathBuf;
use std::time::Duration;

use clap::{Args, Subcommand, ValueEnum};

use crate::grammar::{parse_duration, parse_in_range};

#[derive(Debug, Subcommand)]
pub(crate) enum NetCommand {
    /// Check nodelist.cpj or Nodelist.graphml files: keys, ids, node-IDs, wiring, and the DCFs they name.
    #[command(after_help = "Examples:
  canopener net check Nodelist.graphml
  canopener net check nodelist.cpj other/Nodelist.graphml --format json | jq '.summary'
DCFs are looked up under EDSBaseName, then beside the topology file.
Exit status: 0 no errors, 1 errors found, 2 a file could not be read, or bad arguments.")]
    Check(NetCheckArgs),
    /// Show a system: networks, devices with node-IDs and DCFs, cables, supply domains.
    #[command(after_help = "Examples:
  canopener net show Nodelist.graphml
  canopener net show nodelist.cpj --format json | jq '.networks'
Exit status: 0 shown, 2 the file could not be read or bad arguments.")]
    Show(NetShowArgs),
    /// Convert between nodelist.cpj and Nodelist.graphml, or to Graphviz DOT.
    #[command(after_help = "Examples:
  canopener net convert nodelist.cpj --to graphml -o Nodelist.graphml   # loses nothing
  canopener net convert Nodelist.graphml --to cpj                       # names what cpj cannot hold
  canopener net convert Nodelist.graphml --to dot | dot -Tpng -o net.png
Exit status: 0 converted, 2 the file could not be read or written, or bad arguments.")]
    Convert(NetConvertArgs),
    /// Draw a system as SVG: devices at X/Y (else laid out automatically), networks coloured.
    #[command(after_help = "Examples:
  canopener net draw Nodelist.graphml -o net.svg
  canopener net draw nodelist.cpj > net.svg
Exit status: 0 drawn, 2 the file could not be read or written, or bad arguments.")]
    Draw(NetDrawArgs),
    /// Watch a running system's heartbeats and say which cable broke, which device died or which supply
    /// went off when devices fall silent.
    #[command(after_help = "Examples:
  canopener net monitor Nodelist.graphml --bus socketcand://127.0.0.1:29536/can0
  canopener net monitor Nodelist.graphml --bus 1=socketcand://hub:29536/can0 --bus 2=socketcand://hub:29536/can1
  canopener net monitor nodelist.cpj --bus socketcan:can0 --heartbeat-ms 500 --format json | jq -c 'select(.event==\"diagnosis\")'
A plain --bus is the bus of the monitor's network; --bus N=SPEC names the bus of network N.
JSON events (one per line): state, diagnosis, recovered (docs/networks.md).
Exit status: 0 stopped by Ctrl-C or --duration, 2 bad arguments or a file that cannot be read, 4 bus error.")]
    Monitor(NetMonitorArgs),
}

#[derive(Debug, Args)]
pub(crate) struct NetCheckArgs {
    /// Topology files (nodelist.cpj or Nodelist.graphml; the format is read from the content).
    #[arg(required = true, value_name = "FILE")]
    pub(crate) files: Vec<PathBuf>,
    #[arg(long, value_enum, default_value_t = NetCheckFormat::Human)]
    pub(crate) format: NetCheckFormat,
}

/// How `net check` reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum NetCheckFormat {
    /// Compiler-style findings for people.
    Human,
    /// The JSON document of `eds check --format json`.
    Json,
}

#[derive(Debug, Args)]
pub(crate) struct NetShowArgs {
    /// A topology file.
    #[arg(value_name = "FILE")]
    pub(crate) file: PathBuf,
    #[arg(long, value_enum, default_value_t = NetCheckFormat::Human)]
    pub(crate) format: NetCheckFormat,
}

#[derive(Debug, Args)]
pub(crate) struct NetConvertArgs {
    /// A topology file.
    #[arg(value_name = "FILE")]
    pub(crate) file: PathBuf,
    /// The format to write.
    #[arg(long, value_enum)]
    pub(crate) to: NetTarget,
    /// Write here instead of stdout (never over the input).
    #[arg(short, long, value_name = "OUT")]
    pub(crate) output: Option<PathBuf>,
}

/// What `net convert` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum NetTarget {
    /// Nodelist.graphml.
    Graphml,
    /// nodelist.cpj (CiA 306-3).
    Cpj,
    /// Graphviz DOT.
    Dot,
}

#[derive(Debug, Args)]
pub(crate) struct NetDrawArgs {
    /// A topology file.
    #[arg(value_name = "FILE")]
    pub(crate) file: PathBuf,
    /// Write the SVG here instead of stdout.
    #[arg(short, long, value_name = "OUT")]
    pub(crate) output: Option<PathBuf>,
}

#[derive(Debug, Args)]
pub(crate) struct NetMonitorArgs {
    /// A topology file.
    #[arg(value_name = "FILE")]
    pub(crate) file: PathBuf,
    #[arg(long = "bus", value_name = "SPEC", help = BUS_HELP_NET)]
    pub(crate) buses: Vec<String>,
    /// Where the monitor is connected: a GraphML node id or NodeName (default: the master, else the
    /// device with the lowest node-ID).
    #[arg(long, value_name = "VERTEX")]
    pub(crate) at: Option<String>,
    /// The heartbeat period of devices whose DCF gives no producer heartbeat time (1017h), in ms.
    #[arg(long, value_name = "MS", value_parser = |t: &str| parse_in_range(t, 1, 65535, "--heartbeat-ms"))]
    pub(crate) heartbeat_ms: Option<u64>,
    /// Stop after this long (e.g. 30s); without it, run until Ctrl-C.
    #[arg(long, value_parser = parse_duration, value_name = "DURATION")]
    pub(crate) duration: Option<Duration>,
    #[arg(long, value_enum, default_value_t = MonitorFormat::Human)]
    pub(crate) format: MonitorFormat,
}

const BUS_HELP_NET: &str = "The monitor network's bus (SPEC) or network N's bus (N=SPEC); repeatable \
[env: CANOPENER_BUS, for the monitor's network]. SPEC forms: socketcand://HOST:PORT/BUS, socketcan:IFACE, \
udp-multicast://GROUP:PORT";

/// How `net monitor` reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum MonitorFormat {
    /// A live view in the terminal (a line per event when stdout is not a terminal).
    Human,
    /// One JSON object per event on stdout.
    Json,
}

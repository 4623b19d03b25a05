//! Command-line grammar of `canopener demo`.

use std::path::PathBuf;

use canopener_device::faults::Fault;
use clap::Args;

use crate::args::{OutputFormat, parse_fault};

/// Where the tour writes its reports unless `--dir` says otherwise (relative to the working directory).
pub(crate) const DEFAULT_DIR: &str = "canopener-demo";

#[derive(Debug, Args)]
pub(crate) struct DemoArgs {
    /// Instead of the tour: replay a recorded 4-node CANopen session on an in-process hub and watch it
    /// decoded by the bus monitor.
    #[arg(long)]
    pub(crate) monitor: bool,
    /// Instead of the tour's reports: serve the tour in a browser (`canopener serve` on a simulated
    /// system, its runs in the history under --dir).
    #[arg(long, conflicts_with = "monitor")]
    pub(crate) serve: bool,
    /// With --serve: the address to listen on.
    #[arg(
        long,
        value_name = "ADDRESS",
        default_value = "127.0.0.1:8080",
        requires = "serve"
    )]
    pub(crate) listen: std::net::SocketAddr,
    /// Write the reports, the JSON reports and the bundled EDS into this directory (created if missing).
    #[arg(long, value_name = "DIR", default_value = DEFAULT_DIR, conflicts_with = "monitor")]
    pub(crate) dir: PathBuf,
    /// The fault the second run switches on (`canopener sim --list-faults` describes each).
    #[arg(long, value_name = "NAME", value_parser = parse_fault, default_value = "heartbeat-jitter", conflicts_with = "monitor")]
    pub(crate) fault: Fault,
    /// With --monitor: run it on this bus (socketcan:can0, socketcand://HOST:PORT/BUS,
    /// virtual:NAME?bitrate=500k) instead of an in-process hub.
    #[arg(long = "bus", value_name = "SPEC", requires = "monitor")]
    pub(crate) bus: Option<String>,
    /// With --monitor: replay speed factor (0 = as fast as possible).
    #[arg(long, default_value_t = 1.0, value_name = "FACTOR", requires = "monitor")]
    pub(crate) speed: f64,
    /// With --monitor: only print the summary, not every frame.
    #[arg(long, short, requires = "monitor")]
    pub(crate) quiet: bool,
    /// Text for people, or JSON for machines (the tour: one summary object; --monitor: one object per
    /// frame and a summary).
    #[arg(long, value_enum, default_value_t = OutputFormat::Text)]
    pub(crate) format: OutputFormat,
}

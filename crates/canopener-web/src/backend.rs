//! Every call of the web front end into `canopener-link`, `canopener-sim`, `canopener-files`,
//! `canopener-runtime` and the transports, in one module, so a change of those crates or names (the system simulation, the links) is a change here only.
//! The functions block: the server runs each on a thread of its own.
//!
//! What is here: reading a system and its DCFs, watching buses with the system monitor, simulating a
//! system onto in-process buses in real time (the tour), running conformance tests on a bus or on a
//! device simulated on virtual time, and the wall-clock stamp of a report.

use std::path::Path;
use std::sync::mpsc::Receiver;

use canopener_conformance::catalogue::TestDef;
use canopener_conformance::device_model::DeviceModel;
use canopener_conformance::runner::{self, FinishedRun, Progress, RunSpec};
use canopener_device::faults::Fault;
use canopener_eds::Eds;
use canopener_link::link::{BusLink, Flow, Link, LinkError};
use canopener_link::system_watch::SystemWatch;
use canopener_network::Topology;
use canopener_network::monitor::{Event, MonitorConfig, Snapshot, SystemMonitor};
use canopener_sim::simulation::Simulation;
use canopener_sim::system::files::{SystemError, SystemFiles};
use canopener_sim::system::serve::{ServeReport, serve};
use canopener_sim::system::sim::SimulatedSystem;

pub use canopener_link::cancel::Cancel;

/// Why a backend job could not run.
#[derive(Debug, thiserror::Error)]
pub enum BackendError {
    /// The system or one of its DCFs.
    #[error(transparent)]
    System(#[from] SystemError),
    /// A bus.
    #[error(transparent)]
    Link(#[from] LinkError),
    /// A bus that could not be opened.
    #[error("cannot open bus {spec}: {reason}")]
    Open {
        /// The spec as configured.
        spec: String,
        /// Why.
        reason: String,
    },
    /// A simulated device could not be built.
    #[error(transparent)]
    Sim(#[from] canopener_sim::error::SimError),
    /// The runner refused the run.
    #[error(transparent)]
    Run(#[from] runner::RunError),
}

/// A system read from its topology file, its DCFs found beside it.
#[derive(Debug, Clone)]
pub struct System(SystemFiles);

impl System {
    /// Reads a Nodelist.graphml or nodelist.cpj.
    pub fn read(path: &Path) -> Result<System, BackendError> {
        Ok(System(SystemFiles::read(path)?))
    }

    /// The topology.
    pub fn topology(&self) -> &Topology {
        self.0.topology()
    }

    /// The topology file's folder, where its pictures are looked up.
    pub fn folder(&self) -> &Path {
        self.0.path.parent().unwrap_or(Path::new(""))
    }
}

/// Opens a bus from its spec on the wall clock; `cancel` ends whatever waits on it.
fn open_link(spec: &str, cancel: &Cancel) -> Result<BusLink, BackendError> {
    let open_error = |reason: String| BackendError::Open {
        spec: spec.to_owned(),
        reason,
    };
    let parsed: canopener_transport::BusSpec = spec.parse().map_err(|e| open_error(format!("{e}")))?;
    let bus = canopener_transport::open(&parsed).map_err(|e| open_error(e.to_string()))?;
    Ok(BusLink::new(bus, cancel.clone())?)
}

/// Watches `buses` (network, spec) with the system monitor, placed at vertex `at`, until `cancel`:
/// `on_start` gets the monitor's start on the Unix clock in milliseconds, `on_events` the events of
/// every slice that had some, with the monitor's snapshot after them.
pub fn watch_buses(
    system: &System,
    at: Option<usize>,
    buses: &[(u32, String)],
    cancel: &Cancel,
    on_start: impl FnOnce(f64),
    mut on_events: impl FnMut(Vec<Event>, Snapshot),
) -> Result<(), BackendError> {
    let mut links = Vec::new();
    for (net, spec) in buses {
        links.push((*net, open_link(spec, cancel)?));
    }
    let config = MonitorConfig {
        at,
        networks: buses.iter().map(|(net, _)| *net).collect(),
        producer_times: system.0.producer_times(),
        fallback: None,
    };
    let mut watch = SystemWatch::new(SystemMonitor::new(system.topology(), &config));
    let mut links: Vec<(u32, &mut dyn Link)> =
        links.iter_mut().map(|(n, l)| (*n, l as &mut dyn Link)).collect();
    // A BusLink's clock is the Unix clock in nanoseconds (WallClock).
    if let Some((_, first)) = links.first() {
        on_start(first.now().as_nanos() as f64 / 1e6);
    }
    watch.run(&mut links, None, |now, monitor, events| {
        if !events.is_empty() {
            on_events(events, monitor.snapshot(now));
        }
        Ok::<_, BackendError>(Flow::Continue)
    })?;
    Ok(())
}

/// Simulates `system` from its DCFs onto `buses` (network, spec: in-process `virtual:` buses, or
/// real ones) in real time until `cancel`, applying the fault `commands` of `canopener sim
/// --nodelist` (`cut CABLE`, `repair CABLE`, ...); `on_report` hears each applied or refused.
pub fn simulate_system(
    system: &System,
    at: Option<usize>,
    buses: &[(u32, String)],
    commands: &Receiver<String>,
    cancel: &Cancel,
    mut on_report: impl FnMut(String),
) -> Result<(), BackendError> {
    let mut sim = SimulatedSystem::ideal(&system.0, at)?;
    let mut links = Vec::new();
    for (net, spec) in buses {
        links.push((*net, open_link(spec, cancel)?));
    }
    serve(&mut sim, links, commands, |report| {
        on_report(match report {
            ServeReport::Applied { command } => format!("applied: {command}"),
            ServeReport::Refused { command, reason } => format!("refused: {command}: {reason}"),
        })
    })?;
    Ok(())
}

/// Where a conformance run's device is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Target {
    /// On a bus, by spec.
    Bus(String),
    /// Simulated from the EDS on an embedded bus on virtual time, with these faults.
    Simulated(Vec<Fault>),
}

/// What a run needs besides the target.
#[derive(Debug)]
pub struct RunRequest<'a> {
    /// The device description.
    pub eds: &'a Eds,
    /// Its name as the report shows it.
    pub eds_name: String,
    /// The errors of canopener's EDS checks (`None` for XML descriptions).
    pub eds_errors: Option<Vec<String>>,
    /// The node under test.
    pub node: u8,
    /// The tests, in catalogue order.
    pub tests: &'a [TestDef],
    /// Stops the run as Ctrl-C stops `canopener test` (what the running test changed is written back).
    pub cancel: Cancel,
}

/// Runs the tests as `canopener test` does, reporting progress as each test starts and ends.
pub fn run_tests(
    target: &Target,
    request: &RunRequest<'_>,
    on_progress: impl FnMut(Progress<'_>),
) -> Result<FinishedRun, BackendError> {
    let model = DeviceModel::new(request.eds, request.node);
    let (mut link, bus): (Box<dyn Link>, String) = match target {
        Target::Bus(spec) => (Box::new(open_link(spec, &request.cancel)?), spec.clone()),
        Target::Simulated(faults) => {
            let bus = Simulation::ideal()
                .device(request.eds, request.node)
                .faults(faults.iter().copied())
                .cancel(request.cancel.clone())
                .start()?;
            (Box::new(bus), "embedded virtual bus (ideal timing)".to_owned())
        }
    };
    let spec = RunSpec {
        node: request.node,
        model: &model,
        eds: request.eds_name.clone(),
        bus,
        started: now_rfc3339(),
        sdo_timeout: std::time::Duration::from_millis(500),
        eds_errors: request.eds_errors.clone(),
        cancel: Some(request.cancel.clone()),
    };
    Ok(runner::run(link.as_mut(), &spec, request.tests, on_progress)?)
}

/// The wall-clock time now in RFC 3339 (UTC, whole seconds), as reports state it.
pub fn now_rfc3339() -> String {
    canopener_conformance::model::rfc3339_utc(canopener_runtime::clock::wall_time())
}

/// Writes `bytes` to `path` through a temporary file and a rename (never a half-written file).
pub fn write_file(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    canopener_files::write_atomic(path, bytes, false).map_err(std::io::Error::other)
}

/// Reads a file.
pub fn read_file(path: &Path) -> std::io::Result<Vec<u8>> {
    canopener_files::read(path)
}

/// Creates a folder and its parents.
pub fn create_dir(path: &Path) -> std::io::Result<()> {
    canopener_files::create_dir_all(path).map_err(std::io::Error::other)
}

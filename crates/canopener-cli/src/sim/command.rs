//! `canopener sim`: simulated CANopen devices built from EDS/DCF files, on a real bus, in real time.
//!
//! Each file becomes one [`Device`] (`canopener-device`, sans IO); this module is the IO around them: one
//! bus endpoint shared by all devices, the wall clock, and one driver loop. The loop receives with a
//! timeout of the earliest deadline of all devices (at most [`MAX_WAIT`], so Ctrl-C is noticed quickly),
//! feeds every received frame to every device, runs due timers, and sends every frame a device produces.
//! A frame one device sends is also fed to every other device, as a real bus would deliver it to the
//! other nodes (the hub does not echo a client's frames back to it).
//!
//! State changes and notable events (boot-up, NMT states, SDO writes and aborts, EMCY, LSS, heartbeat
//! consumer, store/restore) are logged to stderr, or as JSON lines on stdout with `--format json`.

use canopener_can::Core;
use std::collections::VecDeque;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Duration;

use canopener_can::{CanFrame, Instant};
use canopener_device::application::{Application, NoApplication};
use canopener_device::cia401::{Cia401Io, install_objects};
use canopener_device::device::{Device, DeviceEvent, UNCONFIGURED};
use canopener_device::faults::{Fault, FaultSet};
use canopener_device::heartbeat::{ConsumerEvent, ErrorControlEvent};
use canopener_device::lss_slave::{LssEvent, LssState};
use canopener_device::nmt_slave::{NmtEvent, NmtSlaveState};
use canopener_device::pdo::PdoEvent;
use canopener_device::sdo_server::{self, AbortOrigin};
use canopener_device::store::StoreEvent;
use canopener_device::sync::SyncEvent;
use canopener_device::time_stamp::TimeEvent;
use canopener_eds::{Eds, Severity};
use canopener_od::ObjectKey;
use canopener_transport::{CanBus, TransportError, WallClock};
use canopener_wire::TimeOfDay;
use canopener_wire::abort::abort_code_text;
use serde_json::{Map, Value, json};

use crate::bus_open::open_bus;
use crate::error::{CliError, CliResult, stdout_error};
use crate::sim::args::{SimApp, SimArgs, SimFormat};
use crate::sim::store::{FileStore, LssFile};
use crate::stop::StopFlag;

/// How often a TIME producer sends the time.
const TIME_PERIOD: Duration = Duration::from_secs(1);
/// The longest one receive waits: how quickly Ctrl-C/SIGTERM is noticed when no timer is due.
const MAX_WAIT: Duration = Duration::from_millis(50);
/// Frames the devices may pass among themselves in one round before the rest waits for the next one (a
/// guard against two devices answering each other forever; the cores do not, but the bus must not hang).
const MAX_FRAMES_PER_ROUND: usize = 10_000;
/// How many loader errors a refused file's message quotes.
const QUOTED_ERRORS: usize = 3;

pub(crate) fn run(args: SimArgs) -> CliResult {
    if args.list_faults {
        return list_faults();
    }
    let stop = StopFlag::install()?;
    let plans = plan(&args)?;
    let mut sim = Simulator {
        devices: plans
            .into_iter()
            .enumerate()
            .map(|(position, plan)| {
                let serial = args.serial.map(|first| first.wrapping_add(position as u32));
                build(plan, serial, args.app, args.state_dir.as_deref(), &args.faults)
            })
            .collect::<CliResult<_>>()?,
    };
    let mut bus = open_bus(args.bus.spec.as_deref(), "sim")?;
    let mut log = Log::new(args.format, WallClock::now());
    for device in &sim.devices {
        log.started(device, &bus.spec().to_string())?;
    }
    sim.boot(WallClock::now(), &mut *bus, &mut log)?;
    let result = loop {
        if stop.is_set() {
            break Ok(());
        }
        if let Err(err) = sim.step(&mut *bus, &mut log) {
            break Err(err);
        }
    };
    log.stopped(result.is_ok())?;
    result
}

/// One file to simulate, loaded, with the node-ID it runs as.
#[derive(Debug)]
struct Plan {
    path: PathBuf,
    eds: Eds,
    node_id: u8,
}

/// Loads every file and gives each a node-ID: the DCF's own, else `--node-id` N, N+1, ... in order for the
/// files without one, else none: the device starts LSS-unconfigured (FFh) and waits for an LSS master.
fn plan(args: &SimArgs) -> CliResult<Vec<Plan>> {
    let mut plans = Vec::with_capacity(args.files.len());
    let mut next = args.node_id.map(u16::from);
    for path in &args.files {
        let eds = load(path)?;
        let node_id = match eds.node_id() {
            Some(node_id) => node_id,
            None => {
                let Some(node_id) = next else {
                    plans.push(Plan {
                        path: path.clone(),
                        eds,
                        node_id: UNCONFIGURED,
                    });
                    continue;
                };
                next = Some(node_id + 1);
                u8::try_from(node_id)
                    .ok()
                    .filter(|id| *id <= 127)
                    .ok_or_else(|| {
                        CliError::Usage(format!(
                            "{}: node-ID {node_id} would be above 127; start --node-id lower",
                            path.display()
                        ))
                    })?
            }
        };
        if let Some(other) = plans
            .iter()
            .find(|p: &&Plan| p.node_id == node_id && node_id != UNCONFIGURED)
        {
            return Err(CliError::Usage(format!(
                "{} and {} would both be node {node_id}; two devices on one bus need different node-IDs",
                other.path.display(),
                path.display()
            )));
        }
        plans.push(Plan {
            path: path.clone(),
            eds,
            node_id,
        });
    }
    Ok(plans)
}

/// Reads an EDS/DCF. A file that cannot be read or describes no objects is invalid input (exit 3), quoting
/// the loader's first errors; a usable file with errors runs as well as the device side can take it.
fn load(path: &Path) -> CliResult<Eds> {
    let bytes = std::fs::read(path).map_err(|err| CliError::read_file(path, err))?;
    let loaded = canopener_eds::load(&bytes);
    if loaded.eds.objects.is_empty() {
        let errors: Vec<String> = loaded
            .diagnostics
            .iter()
            .filter(|d| d.severity == Severity::Error)
            .take(QUOTED_ERRORS)
            .map(|d| format!("\n  {}:{d}", path.display()))
            .collect();
        let hint = if bytes.trim_ascii_start().starts_with(b"<") {
            "; it looks like XML: convert an XDD/XDC first with `canopener eds convert FILE --to eds`"
        } else {
            "; run `canopener eds check` on it for details"
        };
        return Err(CliError::InvalidInput(format!(
            "{} is not a usable EDS/DCF: it describes no objects{hint}{}",
            path.display(),
            errors.concat()
        )));
    }
    Ok(loaded.eds)
}

/// `--list-faults`: every fault of the catalogue with what it does, for choosing `--fault NAME`.
fn list_faults() -> CliResult {
    let mut text = String::new();
    for fault in Fault::ALL {
        text.push_str(&format!("{}\n", fault.name()));
        for line in fault.description().lines() {
            text.push_str(&format!("    {line}\n"));
        }
    }
    text.push_str(&format!(
        "{} faults; give one or more with `canopener sim FILE --fault NAME`\n",
        Fault::ALL.len()
    ));
    crate::eds::input::print_stdout(&text)
}

/// One simulated device and what the log says about it.
struct SimDevice {
    device: Device,
    path: PathBuf,
    app: SimApp,
    store: Option<PathBuf>,
    /// When a TIME producer (1012h bit 30) next sends the wall time.
    next_time: Option<Instant>,
}

fn build(
    plan: Plan,
    serial: Option<u32>,
    app: SimApp,
    state_dir: Option<&Path>,
    faults: &[Fault],
) -> CliResult<SimDevice> {
    let Plan { path, eds, node_id } = plan;
    let refused = |err: &dyn std::fmt::Display| {
        CliError::InvalidInput(format!("{}: cannot build the device: {err}", path.display()))
    };
    let application = || -> Box<dyn Application> {
        match app {
            SimApp::None => Box::new(NoApplication),
            SimApp::Cia401 => Box::new(Cia401Io::new()),
        }
    };
    let make = |node_id: u8| -> CliResult<Device> {
        let mut device = match app {
            SimApp::None => Device::from_eds(&eds, node_id, application()),
            // The CiA 401 objects and factory test registers the file lacks are added (only those).
            SimApp::Cia401 => Device::from_eds_extended(&eds, node_id, application(), |od, node| {
                install_objects(od, node).map(drop).map_err(|err| err.to_string())
            }),
        }
        .map_err(|e| refused(&e))?;
        if let Some(serial) = serial {
            device = device
                .with_value(ObjectKey::new(0x1018, 4), &serial.to_le_bytes())
                .map_err(|err| {
                    CliError::InvalidInput(format!(
                        "{}: cannot set the serial number 1018h:04 to {serial}: {err}; --serial needs an \
                         identity object with sub-index 4 (UNSIGNED32)",
                        path.display()
                    ))
                })?;
        }
        if !faults.is_empty() {
            device = device.with_faults(faults.iter().copied().collect::<FaultSet>());
        }
        Ok(device)
    };
    let mut device = make(node_id)?;
    let mut store = None;
    if let Some(dir) = state_dir {
        let address = device.lss().map(|lss| *lss.identity());
        let params = match (node_id, address) {
            // A node-ID by LSS: the device is known by its LSS address, and starts with the node-ID
            // it stored last time, as a real device does after power-on.
            (UNCONFIGURED, Some(address)) => {
                let lss = LssFile::open(dir, &address)?;
                if let Some(stored) = lss.node_id() {
                    device = make(stored.get())?;
                }
                device = device.with_lss_storage(Box::new(lss));
                FileStore::open_lss(dir, &address)?
            }
            (_, address) => {
                if let Some(address) = address {
                    device = device.with_lss_storage(Box::new(LssFile::open(dir, &address)?));
                }
                FileStore::open(dir, node_id)?
            }
        };
        store = Some(params.path().to_owned());
        device = device.with_parameter_store(Box::new(params));
    }
    Ok(SimDevice {
        device,
        path,
        app,
        store,
        next_time: None,
    })
}

/// Every device of the process and the driver loop around them.
struct Simulator {
    devices: Vec<SimDevice>,
}

impl Simulator {
    /// Power-on of every device.
    fn boot(&mut self, now: Instant, bus: &mut dyn CanBus, log: &mut Log) -> CliResult {
        for sim in &mut self.devices {
            sim.device.boot(now);
        }
        self.pump(now, bus, log)
    }

    /// One turn of the loop: due timers, then one receive bounded by the next deadline.
    fn step(&mut self, bus: &mut dyn CanBus, log: &mut Log) -> CliResult {
        let now = WallClock::now();
        let mut ran = self.produce_time(now);
        for sim in &mut self.devices {
            if sim.device.poll_timeout().is_some_and(|due| due <= now) {
                sim.device.handle_timeout(now);
                ran = true;
            }
        }
        if ran {
            self.pump(now, bus, log)?;
        }
        let wait = match self.devices.iter().filter_map(|s| s.device.poll_timeout()).min() {
            // A deadline still due right after its timer ran would spin the loop: wait a little.
            Some(due) if due <= now => Duration::from_millis(1),
            Some(due) => due.saturating_duration_since(WallClock::now()).min(MAX_WAIT),
            None => MAX_WAIT,
        };
        match bus.recv(wait) {
            Ok(Some(received)) => {
                let now = WallClock::now();
                for sim in &mut self.devices {
                    sim.device.handle_frame(now, &received.frame);
                }
                self.pump(now, bus, log)
            }
            Ok(None) => Ok(()),
            Err(TransportError::Overrun { lost, .. }) => {
                eprintln!("warning: {lost} frames lost because the simulator did not keep up");
                Ok(())
            }
            Err(err) => Err(err.into()),
        }
    }

    /// TIME producers send the wall clock's time once a second (CiA 301 leaves the rate to the
    /// application; once a second is what a clock master typically does). Whether anything was sent.
    fn produce_time(&mut self, now: Instant) -> bool {
        let mut sent = false;
        for sim in &mut self.devices {
            if !sim.device.is_time_producer() {
                sim.next_time = None;
                continue;
            }
            if sim.next_time.is_some_and(|due| due > now) {
                continue;
            }
            sim.next_time = Some(now + TIME_PERIOD);
            let unix_millis = now.as_nanos() / 1_000_000;
            let Some(time) = TimeOfDay::from_unix_millis(unix_millis) else {
                continue;
            };
            // Refused outside the NMT states that run TIME: nothing to send then.
            sent |= sim.device.produce_time(now, time).is_ok();
        }
        sent
    }

    /// Logs every event, sends every frame and feeds each sent frame to the other devices, until no
    /// device has anything left (or [`MAX_FRAMES_PER_ROUND`] frames went round).
    fn pump(&mut self, now: Instant, bus: &mut dyn CanBus, log: &mut Log) -> CliResult {
        let mut queue: VecDeque<(usize, CanFrame)> = VecDeque::new();
        for _ in 0..MAX_FRAMES_PER_ROUND {
            for (index, sim) in self.devices.iter_mut().enumerate() {
                while let Some(event) = sim.device.poll_event() {
                    log.event(&sim.device, &event)?;
                }
                while let Some(frame) = sim.device.poll_transmit() {
                    bus.send(&frame)?;
                    queue.push_back((index, frame));
                }
            }
            let Some((from, frame)) = queue.pop_front() else {
                return Ok(());
            };
            for (index, sim) in self.devices.iter_mut().enumerate() {
                if index != from {
                    sim.device.handle_frame(now, &frame);
                }
            }
        }
        Ok(())
    }
}

/// The node-ID a log line names: the active one, or FFh while the device is LSS-unconfigured.
fn node_label(device: &Device) -> u8 {
    if device.is_configured() {
        device.node_id().get()
    } else {
        UNCONFIGURED
    }
}

/// Where and how the log goes.
enum Sink {
    Stderr,
    Stdout,
    #[cfg(test)]
    Memory(Vec<String>),
}

struct Log {
    format: SimFormat,
    started: Instant,
    sink: Sink,
}

/// One log entry: a kind for machines, a sentence for people, and fields for machines.
struct Entry {
    kind: &'static str,
    text: String,
    fields: Map<String, Value>,
}

impl Entry {
    fn new(kind: &'static str, text: impl Into<String>) -> Entry {
        Entry {
            kind,
            text: text.into(),
            fields: Map::new(),
        }
    }

    fn with(mut self, name: &str, value: impl Into<Value>) -> Entry {
        self.fields.insert(name.to_owned(), value.into());
        self
    }
}

impl Log {
    fn new(format: SimFormat, started: Instant) -> Log {
        let sink = match format {
            SimFormat::Human => Sink::Stderr,
            SimFormat::Json => Sink::Stdout,
        };
        Log {
            format,
            started,
            sink,
        }
    }

    fn started(&mut self, sim: &SimDevice, bus: &str) -> CliResult {
        let device = &sim.device;
        let mut text = format!(
            "simulating {} on {bus} ({} entries",
            sim.path.display(),
            device.od().len()
        );
        if sim.app == SimApp::Cia401 {
            text.push_str(", CiA 401 I/O");
        }
        if let Some(store) = &sim.store {
            text.push_str(&format!(", saved parameters in {}", store.display()));
        }
        text.push(')');
        let notes = device.notes();
        if let Some(first) = notes.first() {
            text.push_str(&format!(
                "; {} entries not taken as written, e.g. {first}",
                notes.len()
            ));
        }
        let entry = Entry::new("started", text)
            .with("file", sim.path.display().to_string())
            .with("bus", bus)
            .with("entries", device.od().len())
            .with("build_notes", notes.len());
        self.write(Some(node_label(device)), entry)
    }

    fn stopped(&mut self, clean: bool) -> CliResult {
        let text = if clean { "stopped" } else { "stopped by an error" };
        self.write(None, Entry::new("stopped", text))
    }

    fn event(&mut self, device: &Device, event: &DeviceEvent) -> CliResult {
        match describe(device, event) {
            Some(entry) => self.write(Some(node_label(device)), entry),
            None => Ok(()),
        }
    }

    fn write(&mut self, node: Option<u8>, entry: Entry) -> CliResult {
        let elapsed = WallClock::now()
            .saturating_duration_since(self.started)
            .as_secs_f64();
        let line = match self.format {
            SimFormat::Human => match node {
                Some(UNCONFIGURED) => format!("{elapsed:9.3} node FFh: {}", entry.text),
                Some(node) => format!("{elapsed:9.3} node {node:>3}: {}", entry.text),
                None => format!("{elapsed:9.3} {}", entry.text),
            },
            SimFormat::Json => {
                let mut object = Map::new();
                object.insert("time".into(), json!((elapsed * 1000.0).round() / 1000.0));
                if let Some(node) = node {
                    object.insert("node".into(), json!(node));
                }
                object.insert("event".into(), json!(entry.kind));
                object.insert("text".into(), json!(entry.text));
                object.extend(entry.fields);
                Value::Object(object).to_string()
            }
        };
        match &mut self.sink {
            Sink::Stderr => {
                eprintln!("{line}");
                Ok(())
            }
            Sink::Stdout => {
                let mut out = std::io::stdout().lock();
                writeln!(out, "{line}")
                    .and_then(|()| out.flush())
                    .map_err(stdout_error)
            }
            #[cfg(test)]
            Sink::Memory(lines) => {
                lines.push(line);
                Ok(())
            }
        }
    }
}

fn state_name(state: NmtSlaveState) -> &'static str {
    match state {
        NmtSlaveState::Initialisation => "initialisation",
        NmtSlaveState::PreOperational => "pre-operational",
        NmtSlaveState::Operational => "operational",
        NmtSlaveState::Stopped => "stopped",
    }
}

fn lss_state_name(state: LssState) -> &'static str {
    match state {
        LssState::Waiting => "waiting",
        LssState::Configuration => "configuration",
    }
}

fn hex(bytes: &[u8]) -> String {
    bytes
        .iter()
        .map(|b| format!("{b:02X}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// What the log says about `event`, or `None` for routine events (each SYNC, TIME, RPDO).
fn describe(device: &Device, event: &DeviceEvent) -> Option<Entry> {
    Some(match event {
        DeviceEvent::Nmt(NmtEvent::StateChanged { from, to }) => {
            let entry = if *from == NmtSlaveState::Initialisation {
                Entry::new(
                    "boot_up",
                    format!("boot-up message sent, now {}", state_name(*to)),
                )
            } else {
                Entry::new(
                    "nmt_state",
                    format!("NMT state {} -> {}", state_name(*from), state_name(*to)),
                )
            };
            entry.with("from", state_name(*from)).with("to", state_name(*to))
        }
        DeviceEvent::Nmt(NmtEvent::ResetApplication) => Entry::new("nmt_reset", "NMT reset node"),
        DeviceEvent::Nmt(NmtEvent::ResetCommunication) => Entry::new("nmt_reset", "reset communication"),
        DeviceEvent::Nmt(other) => Entry::new("nmt_ignored", format!("NMT command ignored: {other:?}")),
        DeviceEvent::Sdo { server, event } => match event {
            sdo_server::Event::Written { key } => {
                let value = device.od().get(*key).map(|e| hex(e.value())).unwrap_or_default();
                Entry::new(
                    "sdo_write",
                    format!(
                        "SDO download {:04X}h:{:02X} = {value} (server {server:04X}h)",
                        key.index, key.sub
                    ),
                )
                .with("index", format!("{:04X}", key.index))
                .with("sub", key.sub)
                .with("value", value)
            }
            sdo_server::Event::Aborted { key, code, by } => {
                let by = match by {
                    AbortOrigin::Client => "client",
                    AbortOrigin::Server => "server",
                };
                let meaning = abort_code_text(*code).unwrap_or("unknown abort code");
                Entry::new(
                    "sdo_abort",
                    format!(
                        "SDO transfer of {:04X}h:{:02X} aborted by the {by}: {code:08X}h ({meaning})",
                        key.index, key.sub
                    ),
                )
                .with("index", format!("{:04X}", key.index))
                .with("sub", key.sub)
                .with("abort_code", format!("{code:08X}"))
                .with("by", by)
            }
        },
        DeviceEvent::ErrorControl(event) => Entry::new(
            "life_guarding",
            match event {
                ErrorControlEvent::LifeGuardingLost => {
                    "life guarding lost: no guarding request in the life time"
                }
                ErrorControlEvent::LifeGuardingResumed => "life guarding resumed",
            },
        ),
        DeviceEvent::Heartbeat(event) => {
            let text = match event {
                ConsumerEvent::HeartbeatStarted { node } => format!("heartbeat of node {node} started"),
                ConsumerEvent::HeartbeatLost { node } => format!("heartbeat of node {node} lost"),
                ConsumerEvent::HeartbeatResumed { node } => format!("heartbeat of node {node} resumed"),
                ConsumerEvent::RemoteState { node, state } => format!("node {node} is {state}"),
                ConsumerEvent::RemoteReset { node } => format!("node {node} booted (boot-up message)"),
                ConsumerEvent::Malformed { node, dlc } => {
                    format!("malformed heartbeat of node {node}: {dlc} bytes")
                }
            };
            Entry::new("heartbeat_consumer", text)
        }
        DeviceEvent::EmcySent { code, register, data } => {
            let text = if *code == 0 {
                format!("EMCY error reset sent (error register {register:02X}h)")
            } else {
                format!(
                    "EMCY sent: error code {code:04X}h, error register {register:02X}h, data {}",
                    hex(data)
                )
            };
            Entry::new("emcy", text)
                .with("code", format!("{code:04X}"))
                .with("register", *register)
        }
        DeviceEvent::Emcy(event) => Entry::new("emcy_dropped", format!("{event:?}")),
        DeviceEvent::Pdo(PdoEvent::RpdoWritten { .. } | PdoEvent::RpdoLengthOk { .. }) => return None,
        DeviceEvent::Pdo(PdoEvent::Disabled { pdo, error }) => {
            Entry::new("pdo", format!("{pdo} disabled: {error}"))
        }
        DeviceEvent::Pdo(event) => Entry::new("pdo", format!("{event:?}")),
        DeviceEvent::Sync(SyncEvent::Sync { .. } | SyncEvent::WindowClosed) => return None,
        DeviceEvent::Sync(event) => Entry::new("sync", format!("{event:?}")),
        DeviceEvent::Time(TimeEvent::Time { .. }) => return None,
        DeviceEvent::Time(event) => Entry::new("time", format!("{event:?}")),
        DeviceEvent::Lss(LssEvent::StateChanged { from, to }) => Entry::new(
            "lss",
            format!("LSS state {} -> {}", lss_state_name(*from), lss_state_name(*to)),
        ),
        DeviceEvent::Lss(LssEvent::NodeIdConfigured { pending }) => Entry::new(
            "lss",
            match pending {
                Some(node) => format!("LSS configured node-ID {node} (active after reset communication)"),
                None => "LSS configured node-ID FFh (unconfigured after reset communication)".to_owned(),
            },
        ),
        DeviceEvent::Lss(event) => Entry::new("lss", format!("{event:?}")),
        DeviceEvent::Store(event) => Entry::new(
            "store",
            match event {
                StoreEvent::Saved { group } => format!("parameters saved: {group:?}"),
                StoreEvent::RestorePending { group } => {
                    format!("defaults restored from the next reset on: {group:?}")
                }
                StoreEvent::RestoreTookEffect { group } => format!("defaults restored: {group:?}"),
                StoreEvent::SavedValueSkipped { key } => {
                    format!("saved value of {:04X}h:{:02X} not applied", key.index, key.sub)
                }
            },
        ),
        DeviceEvent::StorageFailed(error) => Entry::new("storage_failed", error.to_string()),
        DeviceEvent::ConfigRefused(refused) => Entry::new(
            "config_refused",
            format!(
                "{:04X}h:{:02X} refused at reset ({:08X}h), the default applies",
                refused.key.index, refused.key.sub, refused.abort_code
            ),
        ),
        DeviceEvent::NodeIdChanged { from, to } => {
            let before = from.map_or_else(|| "FFh (unconfigured)".to_owned(), |node| node.to_string());
            Entry::new("node_id", format!("node-ID changed from {before} to {to}"))
                .with("from", from.map(|node| node.get()))
                .with("to", to.get())
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_transport::{BusSpec, Received};

    /// A bus that records what is sent and hands out queued frames.
    #[derive(Debug)]
    struct FakeBus {
        spec: BusSpec,
        sent: Vec<CanFrame>,
        inbox: VecDeque<CanFrame>,
    }

    impl FakeBus {
        fn new() -> FakeBus {
            FakeBus {
                spec: BusSpec::Socketcand {
                    host: "127.0.0.1".into(),
                    port: 9,
                    bus: "can0".into(),
                },
                sent: Vec::new(),
                inbox: VecDeque::new(),
            }
        }

        fn sent(&mut self) -> Vec<String> {
            self.sent.drain(..).map(|f| f.to_string()).collect()
        }
    }

    impl CanBus for FakeBus {
        fn send(&mut self, frame: &CanFrame) -> Result<(), TransportError> {
            self.sent.push(*frame);
            Ok(())
        }

        fn recv(&mut self, _timeout: Duration) -> Result<Option<Received>, TransportError> {
            Ok(self.inbox.pop_front().map(|frame| Received {
                timestamp: WallClock::now(),
                frame,
            }))
        }

        fn spec(&self) -> &BusSpec {
            &self.spec
        }
    }

    fn base_eds() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../canopener-check/test_data/checks/base.eds")
    }

    fn args(files: Vec<PathBuf>, node_id: Option<u8>) -> SimArgs {
        SimArgs {
            files,
            bus: crate::args::BusArg { spec: None },
            node_id,
            serial: None,
            state_dir: None,
            app: SimApp::None,
            format: SimFormat::Json,
            faults: Vec::new(),
            list_faults: false,
        }
    }

    fn memory_log() -> Log {
        Log {
            format: SimFormat::Json,
            started: WallClock::now(),
            sink: Sink::Memory(Vec::new()),
        }
    }

    fn logged(log: &mut Log) -> Vec<Value> {
        match &mut log.sink {
            Sink::Memory(lines) => lines
                .drain(..)
                .map(|l| serde_json::from_str(&l).unwrap())
                .collect(),
            _ => unreachable!(),
        }
    }

    fn frame(text: &str) -> CanFrame {
        canopener_can::candump::parse_compact_frame(text).expect("frame")
    }

    #[test]
    fn node_ids_come_from_the_option_in_order_and_must_differ() {
        let plans = plan(&args(vec![base_eds(), base_eds(), base_eds()], Some(10))).unwrap();
        let ids: Vec<u8> = plans.iter().map(|p| p.node_id).collect();
        assert_eq!(ids, [10, 11, 12]);

        // Without a node-ID the devices start LSS-unconfigured; any number of them may.
        let none = plan(&args(vec![base_eds(), base_eds()], None)).unwrap();
        let ids: Vec<u8> = none.iter().map(|p| p.node_id).collect();
        assert_eq!(ids, [UNCONFIGURED, UNCONFIGURED]);

        let high = plan(&args(vec![base_eds(), base_eds()], Some(127))).unwrap_err();
        assert_eq!(high.exit_code(), 2);
        assert!(high.to_string().contains("above 127"), "{high}");
    }

    #[test]
    fn a_dcf_node_id_wins_and_a_clash_is_refused() {
        let dcf =
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../canopener-check/test_data/checks/base.dcf");
        let own = load(&dcf).unwrap().node_id().expect("base.dcf has a node-ID");
        let plans = plan(&args(vec![dcf.clone(), base_eds()], Some(own.max(2) - 1))).unwrap();
        assert_eq!(plans[0].node_id, own);
        assert_ne!(plans[1].node_id, own);
        let clash = plan(&args(vec![base_eds(), dcf], Some(own))).unwrap_err();
        assert_eq!(clash.exit_code(), 2);
        assert!(clash.to_string().contains("both be node"), "{clash}");
    }

    #[test]
    fn files_without_objects_are_invalid_input_naming_the_file() {
        let dir = std::env::temp_dir().join(format!("canopener-sim-unit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let junk = dir.join("junk.eds");
        std::fs::write(&junk, "this is not\x00 an EDS [at all\n").unwrap();
        let err = load(&junk).unwrap_err();
        assert_eq!(err.exit_code(), 3);
        assert!(
            err.to_string().contains("junk.eds is not a usable EDS/DCF"),
            "{err}"
        );
        let xml = dir.join("device.xdd");
        std::fs::write(&xml, "<?xml version=\"1.0\"?><ISO15745ProfileContainer/>").unwrap();
        assert!(load(&xml).unwrap_err().to_string().contains("eds convert"));
        let missing = load(&dir.join("missing.eds")).unwrap_err();
        assert_eq!(missing.exit_code(), 3);
        assert!(missing.to_string().contains("missing.eds"));
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// base.eds with a heartbeat consumer 1016h (one entry, off).
    fn eds_with_consumer(dir: &Path) -> PathBuf {
        let mut text = std::fs::read_to_string(base_eds()).unwrap();
        text.push_str(
            "\n[1016]\nParameterName=Consumer heartbeat time\nObjectType=0x8\nSubNumber=2\n\n\
             [1016sub0]\nParameterName=Number of entries\nObjectType=0x7\nDataType=0x0005\nAccessType=ro\n\
             DefaultValue=1\nPDOMapping=0\n\n\
             [1016sub1]\nParameterName=Consumer heartbeat time 1\nObjectType=0x7\nDataType=0x0007\n\
             AccessType=rw\nDefaultValue=0\nPDOMapping=0\n",
        );
        std::fs::create_dir_all(dir).unwrap();
        let path = dir.join("consumer.eds");
        std::fs::write(&path, text).unwrap();
        path
    }

    /// Two devices on one bus: each boots, sees the other's frames, and answers SDO on its own node-ID.
    #[test]
    fn devices_boot_answer_and_hear_each_other() {
        let dir = std::env::temp_dir().join(format!("canopener-sim-unit-two-{}", std::process::id()));
        let eds = eds_with_consumer(&dir);
        let mut sim = Simulator {
            devices: plan(&args(vec![eds.clone(), eds], Some(5)))
                .unwrap()
                .into_iter()
                .map(|p| build(p, None, SimApp::None, None, &[]).unwrap())
                .collect(),
        };
        let mut bus = FakeBus::new();
        let mut log = memory_log();
        sim.boot(WallClock::now(), &mut bus, &mut log).unwrap();
        assert_eq!(bus.sent(), ["705#00", "706#00"]);
        let events = logged(&mut log);
        assert_eq!(
            events.iter().filter(|e| e["event"] == "boot_up").count(),
            2,
            "{events:?}"
        );

        // Node 5 consumes node 6's heartbeat: 1016h:01 = node 6, 1000 ms. Device 6's heartbeat then
        // reaches device 5 through the simulator, not the bus.
        bus.inbox.push_back(frame("605#23161001E8030600"));
        sim.step(&mut bus, &mut log).unwrap();
        bus.inbox.push_back(frame("606#2B17100064000000"));
        sim.step(&mut bus, &mut log).unwrap();
        assert_eq!(bus.sent(), ["585#6016100100000000", "586#6017100000000000"]);
        let events = logged(&mut log);
        assert!(
            events
                .iter()
                .any(|e| e["event"] == "sdo_write" && e["index"] == "1017" && e["value"] == "64 00"),
            "{events:?}"
        );
        let deadline = std::time::Instant::now() + Duration::from_secs(5);
        let mut heard = false;
        while !heard && std::time::Instant::now() < deadline {
            sim.step(&mut bus, &mut log).unwrap();
            heard = logged(&mut log)
                .iter()
                .any(|e| e["node"] == 5 && e["event"] == "heartbeat_consumer");
            std::thread::sleep(Duration::from_millis(5));
        }
        assert!(heard, "node 5 never heard node 6's heartbeat");
        assert!(bus.sent().iter().any(|f| f == "706#7F"));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn aborts_and_emcy_are_described_for_machines() {
        let mut sim = Simulator {
            devices: vec![
                build(
                    plan(&args(vec![base_eds()], Some(5))).unwrap().remove(0),
                    None,
                    SimApp::None,
                    None,
                    &[],
                )
                .unwrap(),
            ],
        };
        let mut bus = FakeBus::new();
        let mut log = memory_log();
        sim.boot(WallClock::now(), &mut bus, &mut log).unwrap();
        // 1018h:01 is read-only.
        bus.inbox.push_back(frame("605#2318100101000000"));
        sim.step(&mut bus, &mut log).unwrap();
        let events = logged(&mut log);
        let abort = events
            .iter()
            .find(|e| e["event"] == "sdo_abort")
            .expect("abort logged");
        assert_eq!(abort["abort_code"], "06010002");
        assert_eq!(abort["by"], "server");
        assert!(abort["text"].as_str().unwrap().contains("read-only"), "{abort}");

        // Operational, then a SYNC with a counter where 1019h is 0: EMCY 8240h.
        bus.inbox.push_back(frame("000#0105"));
        bus.inbox.push_back(frame("080#01"));
        sim.step(&mut bus, &mut log).unwrap();
        sim.step(&mut bus, &mut log).unwrap();
        let events = logged(&mut log);
        assert!(
            events
                .iter()
                .any(|e| e["event"] == "nmt_state" && e["to"] == "operational"),
            "{events:?}"
        );
        let emcy = events.iter().find(|e| e["event"] == "emcy").expect("emcy logged");
        assert_eq!(emcy["code"], "8240");
    }

    #[test]
    fn cia401_adds_only_the_objects_the_file_lacks() {
        let sim = build(
            plan(&args(vec![base_eds()], Some(5))).unwrap().remove(0),
            None,
            SimApp::Cia401,
            None,
            &[],
        )
        .unwrap();
        // base.eds has 6000h and 6200h: kept as they are (two inputs), the factory test registers
        // and the analogue inputs it lacks are added.
        assert!(!sim.device.od().object(0x2001).is_empty());

        assert!(!sim.device.od().object(0x6401).is_empty());

        let dir = std::env::temp_dir().join(format!("canopener-sim-unit-401-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bare = dir.join("bare.eds");
        let text = std::fs::read_to_string(base_eds()).unwrap();
        let cut = text.find("[6000]").expect("base.eds has 6000h");
        std::fs::write(&bare, &text[..cut]).unwrap();
        let sim = build(
            plan(&args(vec![bare], Some(5))).unwrap().remove(0),
            None,
            SimApp::Cia401,
            Some(&dir),
            &[],
        )
        .unwrap();
        for index in [0x2000, 0x2001, 0x6000, 0x6200, 0x6401] {
            assert!(!sim.device.od().object(index).is_empty(), "{index:04X}h missing");
        }
        assert!(sim.store.unwrap().ends_with("node-005.params"));
        let _ = std::fs::remove_dir_all(&dir);
    }
}

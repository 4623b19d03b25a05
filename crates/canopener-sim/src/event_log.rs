//! What a simulated device's events mean, in the same words for every front end: an event name for
//! machines, a sentence for people and named fields (the command line prints them as lines or JSON
//! objects, a web page or a test log may show them as it likes).

use std::fmt::Write as _;

use canopener_device::device::{Device, DeviceEvent, UNCONFIGURED};
use canopener_device::heartbeat::{ConsumerEvent, ErrorControlEvent};
use canopener_device::lss_slave::{LssEvent, LssState};
use canopener_device::nmt_slave::{NmtEvent, NmtSlaveState};
use canopener_device::pdo::PdoEvent;
use canopener_device::sdo_server::{self, AbortOrigin};
use canopener_device::store::StoreEvent;
use canopener_device::sync::SyncEvent;
use canopener_device::time_stamp::TimeEvent;
use canopener_wire::abort::abort_code_text;

use crate::device::{ApplicationKind, SimulatedDevice};
use crate::plan::NodeIdFrom;

/// One notable thing a simulation did.
#[derive(Debug, Clone, PartialEq)]
pub struct LogEntry {
    /// The device it is about (its node-ID, FFh while LSS-unconfigured); `None` for the simulation.
    pub node: Option<u8>,
    /// The kind of entry for machines (`boot_up`, `sdo_write`, `emcy`, ...).
    pub kind: &'static str,
    /// What happened, as a sentence for people.
    pub text: String,
    /// Details for machines, in the order they were added.
    pub fields: Vec<(&'static str, FieldValue)>,
}

/// The value of one field of a [`LogEntry`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FieldValue {
    /// Text (hex values are text: `"1017"`, `"64 00"`).
    Text(String),
    /// A number.
    Number(u64),
    /// Nothing (an unconfigured node-ID).
    Null,
}

impl From<&str> for FieldValue {
    fn from(text: &str) -> FieldValue {
        FieldValue::Text(text.to_owned())
    }
}

impl From<String> for FieldValue {
    fn from(text: String) -> FieldValue {
        FieldValue::Text(text)
    }
}

impl From<u8> for FieldValue {
    fn from(number: u8) -> FieldValue {
        FieldValue::Number(number.into())
    }
}

impl From<usize> for FieldValue {
    fn from(number: usize) -> FieldValue {
        FieldValue::Number(number as u64)
    }
}

impl<T: Into<FieldValue>> From<Option<T>> for FieldValue {
    fn from(value: Option<T>) -> FieldValue {
        value.map_or(FieldValue::Null, Into::into)
    }
}

impl LogEntry {
    /// An entry of the simulation as a whole.
    pub fn new(kind: &'static str, text: impl Into<String>) -> LogEntry {
        LogEntry {
            node: None,
            kind,
            text: text.into(),
            fields: Vec::new(),
        }
    }

    /// This entry about node `node`.
    pub fn about(mut self, node: u8) -> LogEntry {
        self.node = Some(node);
        self
    }

    /// This entry with one more field.
    pub fn with(mut self, name: &'static str, value: impl Into<FieldValue>) -> LogEntry {
        self.fields.push((name, value.into()));
        self
    }

    /// The sentence with the node it is about in front (`node   5: boot-up message sent, ...`), as a
    /// person reads a log line.
    pub fn human(&self) -> String {
        match self.node {
            Some(UNCONFIGURED) => format!("node FFh: {}", self.text),
            Some(node) => format!("node {node:>3}: {}", self.text),
            None => self.text.clone(),
        }
    }

    /// A device starts on bus `bus` (described as [`Link::describe`](canopener_link::link::Link::describe) does).
    pub fn started(sim: &SimulatedDevice, bus: &str) -> LogEntry {
        let device = sim.device();
        let mut text = format!(
            "simulating {} on {bus} ({} entries",
            sim.name(),
            device.od().len()
        );
        text.push_str(match (sim.application(), sim.application_is_auto()) {
            (ApplicationKind::Cia401, true) => {
                ", CiA 401 I/O application: 1000h says profile 401 (--app none turns it off)"
            }
            (ApplicationKind::Cia401, false) => ", CiA 401 I/O application",
            (_, true) => ", no application: not a CiA 401 I/O description (--app cia401 adds one)",
            (_, false) => ", no application",
        });
        if let Some(store) = sim.store_path() {
            let _ = write!(text, ", saved parameters in {}", store.display());
        }
        text.push(')');
        // Where the node-ID and the bit rate come from: what was asked for wins over the file.
        let node = sim.node_label();
        let _ = match sim.node_id_from() {
            NodeIdFrom::Asked { file: Some(own) } if own != node => write!(
                text,
                "; node-ID {node} as asked (the file's [DeviceComissioning] NodeID={own} is not used)"
            ),
            NodeIdFrom::Asked { .. } => write!(text, "; node-ID {node} as asked"),
            NodeIdFrom::File => write!(
                text,
                "; node-ID {node} from the file's [DeviceComissioning] NodeID"
            ),
            NodeIdFrom::Stored => write!(text, "; node-ID {node} stored by LSS in the state directory"),
            NodeIdFrom::Unconfigured => {
                write!(
                    text,
                    "; no node-ID (none asked for, none in the file): LSS-unconfigured"
                )
            }
        };
        let _ = match sim.file_bitrate() {
            Some(kbit) => write!(
                text,
                "; bit rate: the bus's (the file's [DeviceComissioning] Baudrate={kbit} kbit/s is not applied)"
            ),
            None => write!(text, "; bit rate: the bus's"),
        };
        let notes = device.notes();
        if let Some(first) = notes.first() {
            let _ = write!(
                text,
                "; {} entries not taken as written, e.g. {first}",
                notes.len()
            );
        }
        LogEntry::new("started", text)
            .about(sim.node_label())
            .with("file", sim.name())
            .with("bus", bus)
            .with("entries", device.od().len())
            .with("application", sim.application().name())
            .with("build_notes", notes.len())
            .with("node_id_from", sim.node_id_from().name())
            .with("bitrate_from", "bus")
            .with(
                "file_bitrate",
                sim.file_bitrate()
                    .map_or(FieldValue::Null, |kbit| FieldValue::Number(kbit.into())),
            )
    }

    /// The simulation ended, on request (`clean`) or by an error.
    pub fn stopped(clean: bool) -> LogEntry {
        LogEntry::new("stopped", if clean { "stopped" } else { "stopped by an error" })
    }

    /// What `event` of `sim` means, or `None` for routine events (each SYNC, TIME, RPDO). Call it
    /// right after the event: an SDO write is described with the value the dictionary holds now.
    pub fn event(sim: &SimulatedDevice, event: &DeviceEvent) -> Option<LogEntry> {
        describe(sim.device(), event).map(|entry| entry.about(sim.node_label()))
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
fn describe(device: &Device, event: &DeviceEvent) -> Option<LogEntry> {
    Some(match event {
        DeviceEvent::Nmt(NmtEvent::StateChanged { from, to }) => {
            let entry = if *from == NmtSlaveState::Initialisation {
                LogEntry::new(
                    "boot_up",
                    format!("boot-up message sent, now {}", state_name(*to)),
                )
            } else {
                LogEntry::new(
                    "nmt_state",
                    format!("NMT state {} -> {}", state_name(*from), state_name(*to)),
                )
            };
            entry.with("from", state_name(*from)).with("to", state_name(*to))
        }
        DeviceEvent::Nmt(NmtEvent::ResetApplication) => LogEntry::new("nmt_reset", "NMT reset node"),
        DeviceEvent::Nmt(NmtEvent::ResetCommunication) => LogEntry::new("nmt_reset", "reset communication"),
        DeviceEvent::Nmt(other) => LogEntry::new("nmt_ignored", format!("NMT command ignored: {other:?}")),
        DeviceEvent::Sdo { server, event } => match event {
            sdo_server::Event::Written { key } => {
                let value = device.od().get(*key).map(|e| hex(e.value())).unwrap_or_default();
                LogEntry::new(
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
                LogEntry::new(
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
        DeviceEvent::ErrorControl(event) => LogEntry::new(
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
            LogEntry::new("heartbeat_consumer", text)
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
            LogEntry::new("emcy", text)
                .with("code", format!("{code:04X}"))
                .with("register", *register)
        }
        DeviceEvent::Emcy(event) => LogEntry::new("emcy_dropped", format!("{event:?}")),
        DeviceEvent::Pdo(PdoEvent::RpdoWritten { .. } | PdoEvent::RpdoLengthOk { .. }) => return None,
        DeviceEvent::Pdo(PdoEvent::Disabled { pdo, error }) => {
            LogEntry::new("pdo", format!("{pdo} disabled: {error}"))
        }
        DeviceEvent::Pdo(PdoEvent::RpdoLate { number }) => LogEntry::new(
            "pdo",
            format!("RPDO{number} arrived after the synchronous window (1007h) and was discarded"),
        ),
        DeviceEvent::Pdo(event) => LogEntry::new("pdo", format!("{event:?}")),
        DeviceEvent::Sync(SyncEvent::Sync { .. } | SyncEvent::WindowClosed) => return None,
        DeviceEvent::Sync(event) => LogEntry::new("sync", format!("{event:?}")),
        DeviceEvent::Time(TimeEvent::Time { .. }) => return None,
        DeviceEvent::Time(event) => LogEntry::new("time", format!("{event:?}")),
        DeviceEvent::Lss(LssEvent::StateChanged { from, to }) => LogEntry::new(
            "lss",
            format!("LSS state {} -> {}", lss_state_name(*from), lss_state_name(*to)),
        ),
        DeviceEvent::Lss(LssEvent::NodeIdConfigured { pending }) => LogEntry::new(
            "lss",
            match pending {
                Some(node) => format!("LSS configured node-ID {node} (active after reset communication)"),
                None => "LSS configured node-ID FFh (unconfigured after reset communication)".to_owned(),
            },
        ),
        DeviceEvent::Lss(event) => LogEntry::new("lss", format!("{event:?}")),
        DeviceEvent::Store(event) => LogEntry::new(
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
        DeviceEvent::StorageFailed(error) => LogEntry::new("storage_failed", error.to_string()),
        DeviceEvent::ConfigRefused(refused) => LogEntry::new(
            "config_refused",
            format!(
                "{:04X}h:{:02X} refused at reset ({:08X}h), the default applies",
                refused.key.index, refused.key.sub, refused.abort_code
            ),
        ),
        DeviceEvent::NodeIdChanged { from, to } => {
            let before = from.map_or_else(|| "FFh (unconfigured)".to_owned(), |node| node.to_string());
            LogEntry::new("node_id", format!("node-ID changed from {before} to {to}"))
                .with("from", from.map(|node| node.get()))
                .with("to", to.get())
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simulation::{SimulatedBus, Simulation};
    use crate::test_support::{base_eds, frame};
    use canopener_link::link::Link;

    fn entries(bus: &mut SimulatedBus) -> Vec<LogEntry> {
        let mut entries = Vec::new();
        while let Some(event) = bus.virtual_bus_mut().poll_event() {
            let sim = bus.virtual_bus().node(event.node).expect("a device");
            entries.extend(LogEntry::event(sim, &event.event));
        }
        entries
    }

    #[test]
    fn aborts_and_emcy_are_described_for_machines() {
        let mut bus = Simulation::ideal()
            .device(base_eds().as_path(), 5)
            .start()
            .unwrap();
        // 1018h:01 is read-only.
        bus.send(&frame("605#2318100101000000")).unwrap();
        let log = entries(&mut bus);
        let abort = log
            .iter()
            .find(|e| e.kind == "sdo_abort")
            .expect("abort described");
        assert_eq!(abort.node, Some(5));
        assert!(abort.text.contains("read-only"), "{abort:?}");
        assert!(abort.fields.contains(&("abort_code", "06010002".into())));
        assert!(abort.fields.contains(&("by", "server".into())));
        assert!(abort.fields.contains(&("sub", FieldValue::Number(1))));

        // Operational, then a SYNC with a counter where 1019h is 0: EMCY 8240h.
        bus.send(&frame("000#0105")).unwrap();
        bus.send(&frame("080#01")).unwrap();
        let log = entries(&mut bus);
        let operational = log.iter().find(|e| e.kind == "nmt_state").expect("state change");
        assert_eq!(operational.text, "NMT state pre-operational -> operational");
        assert_eq!(
            operational.human(),
            "node   5: NMT state pre-operational -> operational"
        );
        let emcy = log.iter().find(|e| e.kind == "emcy").expect("emcy described");
        assert!(emcy.fields.contains(&("code", "8240".into())), "{emcy:?}");
    }

    #[test]
    fn the_start_names_file_bus_and_an_unconfigured_node() {
        let mut bus = Simulation::ideal().file(base_eds()).start().unwrap();
        let (_, sim) = bus.virtual_bus_mut().nodes().next().expect("one device");
        let started = LogEntry::started(sim, "simulated bus (ideal timing)");
        assert_eq!(started.node, Some(UNCONFIGURED));
        assert!(
            started.human().starts_with("node FFh: simulating "),
            "{started:?}"
        );
        assert!(
            started.text.contains(" on simulated bus (ideal timing) ("),
            "{started:?}"
        );
        assert!(
            started.text.ends_with(
                "; no node-ID (none asked for, none in the file): LSS-unconfigured; bit rate: the bus's"
            ),
            "{started:?}"
        );
        assert!(started.fields.contains(&("node_id_from", "unconfigured".into())));
        assert!(started.fields.contains(&("file_bitrate", FieldValue::Null)));
        assert!(
            started
                .fields
                .contains(&("bus", "simulated bus (ideal timing)".into()))
        );
        assert_eq!(LogEntry::stopped(false).human(), "stopped by an error");
    }
}

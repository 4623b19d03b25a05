//! The system monitor, sans-IO: heartbeats (and EMCYs) from one or more networks in, every device's
//! state and the diagnosis of silences out, as the events of `canopener net monitor --format json`.
//!
//! A device is *silent* when no heartbeat came for 1.5 × its producer heartbeat time (from its DCF's
//! 1017h, or the caller's fallback); a device never heard is silent 1.5 periods after the start. A
//! device with no producer time is reported `unmonitored` once and never silent. The monitor's own
//! vertex is never watched.
//!
//! After a cable cut, the devices behind it time out one by one, within one heartbeat period of each
//! other. Diagnosing at each timeout would blame a single device first and the cable a moment later,
//! so a diagnosis waits a *settling time* after the first change of a network's silent set (1.5 × the
//! longest producer time of the network: every device a cut silences has timed out by then) and is
//! emitted then if the silent set differs from the last one reported. Device states and `recovered`
//! events are emitted at once.
//!
//! A frame on a watched device's heartbeat or EMCY CAN-ID that no correct device sends (a heartbeat
//! without exactly 1 byte or with a state CiA 301 §7.2.8.3.2 does not have, an EMCY without 8 bytes,
//! CiA 301 §7.2.7.3.1) is no sign of life: it is an `anomaly` event quoting the frame. So is a
//! heartbeat with the state of the one before it within a tenth of the producer time (a producer
//! sends one per period, CiA 301 §7.2.8.3.2.2; a state change may add one), though it is a sign of
//! life. At most one anomaly per device and second is reported (all are counted), so a babbling
//! device cannot flood the output. [`SystemMonitor::health`] sums a run up.

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::time::Duration;

use canopener_can::{CanFrame, CanId, Instant};
use serde::Serialize;

use crate::localise::{Kind, Localiser};
use crate::model::Topology;
use crate::wiring::Wiring;

/// The factor of the producer heartbeat time after which a device is silent.
pub const SILENCE_FACTOR: f64 = 1.5;

/// The shortest time between two `anomaly` events of one device.
pub const ANOMALY_REPEAT: Duration = Duration::from_secs(1);

/// What a device last said about itself, or that it said nothing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum DeviceState {
    /// The boot-up message (00h).
    BootUp,
    /// Heartbeat 7Fh.
    PreOperational,
    /// Heartbeat 05h.
    Operational,
    /// Heartbeat 04h.
    Stopped,
    /// No heartbeat for 1.5 × its producer time.
    Silent,
    /// No producer time known: never reported silent.
    Unmonitored,
}

impl DeviceState {
    /// The state a heartbeat byte reports.
    pub fn from_heartbeat(byte: u8) -> Option<DeviceState> {
        match byte {
            0x00 => Some(DeviceState::BootUp),
            0x04 => Some(DeviceState::Stopped),
            0x05 => Some(DeviceState::Operational),
            0x7F => Some(DeviceState::PreOperational),
            _ => None,
        }
    }

    /// The word the JSON events use.
    pub fn as_str(self) -> &'static str {
        match self {
            DeviceState::BootUp => "boot-up",
            DeviceState::PreOperational => "pre-operational",
            DeviceState::Operational => "operational",
            DeviceState::Stopped => "stopped",
            DeviceState::Silent => "silent",
            DeviceState::Unmonitored => "unmonitored",
        }
    }
}

/// One explanation as the JSON events carry it: names instead of indices.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct NamedExplanation {
    /// `cable`, `device`, `supply` or `monitor`.
    pub kind: Kind,
    /// The ambiguity group.
    pub candidates: Vec<String>,
    /// The silent devices it accounts for.
    pub explains: Vec<String>,
}

/// What the monitor reports (the JSON lines of `canopener net monitor --format json`; `time` is
/// seconds since the monitor started).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "event", rename_all = "lowercase")]
pub enum Event {
    /// A device's state changed.
    State {
        /// Seconds since the start.
        time: f64,
        /// The network number.
        network: u32,
        /// The device's name.
        node: String,
        /// Its node-ID there.
        node_id: u8,
        /// The new state.
        state: DeviceState,
    },
    /// The set of silent devices of a network changed (an empty `silent` when all are back).
    Diagnosis {
        /// Seconds since the start.
        time: f64,
        /// The network number.
        network: u32,
        /// The silent devices, in vertex order.
        silent: Vec<String>,
        /// What explains them.
        explanations: Vec<NamedExplanation>,
    },
    /// A silent device was heard again.
    Recovered {
        /// Seconds since the start.
        time: f64,
        /// The network number.
        network: u32,
        /// The device's name.
        node: String,
        /// Its node-ID there.
        node_id: u8,
    },
    /// A frame on a device's heartbeat or EMCY CAN-ID that no correct device sends.
    Anomaly {
        /// Seconds since the start.
        time: f64,
        /// The network number.
        network: u32,
        /// The device's name.
        node: String,
        /// Its node-ID there.
        node_id: u8,
        /// The frame, `705#0501`.
        frame: String,
        /// What is wrong with it.
        reason: String,
    },
}

/// How the watched devices did over a run (what `net monitor --duration` exits with).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Health {
    /// Every watched device was heard and never silent, and no frame was an anomaly.
    Healthy,
    /// A device was silent at some point, or sent an anomaly.
    Troubled,
    /// No watched device was heard at all.
    Unheard,
}

impl Event {
    /// The event as one line of JSON (no newline).
    pub fn to_json(&self) -> String {
        // Plain structs of strings and numbers always serialise.
        serde_json::to_string(self).unwrap_or_default()
    }
}

/// The monitor's whole picture at one instant ([`SystemMonitor::snapshot`]), for a display that starts
/// watching late (a web page loading): every device's state and each network's last reported
/// diagnosis, in the words of the JSON events. Replaying the events since the start gives the same.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Snapshot {
    /// Seconds since the monitor started.
    pub time: f64,
    /// Every device, by network and then wiring order (the monitor's own vertex included, marked).
    pub devices: Vec<DeviceSnapshot>,
    /// Per watched network, ascending, the last diagnosis reported (`None` before the first).
    pub diagnoses: Vec<NetworkDiagnosis>,
}

/// One device in a [`Snapshot`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DeviceSnapshot {
    /// The network number.
    pub network: u32,
    /// The device's name (as the events name it).
    pub node: String,
    /// Its node-ID there.
    pub node_id: u8,
    /// Its state; `None` until heard or found silent.
    pub state: Option<DeviceState>,
    /// Whether it is the monitor's own vertex (not watched).
    pub is_monitor: bool,
}

/// The last diagnosis of one network in a [`Snapshot`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NetworkDiagnosis {
    /// The network number.
    pub network: u32,
    /// The last `diagnosis` event's `time`, `silent` and `explanations`; `None` before the first.
    pub last: Option<Diagnosed>,
}

/// What a `diagnosis` event said.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Diagnosed {
    /// Seconds since the start.
    pub time: f64,
    /// The silent devices, in vertex order.
    pub silent: Vec<String>,
    /// What explains them.
    pub explanations: Vec<NamedExplanation>,
}

/// An EMCY a device sent, for displays.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LastEmcy {
    /// When it came.
    pub at: Instant,
    /// The error code.
    pub code: u16,
    /// The error register.
    pub register: u8,
}

/// What the monitor knows about one device.
#[derive(Debug, Clone, PartialEq)]
pub struct DeviceStatus {
    /// The network.
    pub network: u32,
    /// The vertex in the topology.
    pub vertex: usize,
    /// Its name.
    pub name: String,
    /// Its node-ID on the network.
    pub node_id: u8,
    /// The producer heartbeat time, `None` when unmonitored.
    pub period: Option<Duration>,
    /// Its state; `None` until heard (or found silent).
    pub state: Option<DeviceState>,
    /// When it was last heard.
    pub last_heard: Option<Instant>,
    /// Its last EMCY.
    pub last_emcy: Option<LastEmcy>,
    /// Whether it is the monitor's own vertex (not watched).
    pub is_monitor: bool,
    /// How often it went silent.
    pub silences: usize,
    /// How many frames on its CAN-IDs were anomalies (reported or not).
    pub anomalies: usize,
    deadline: Option<Instant>,
    silent: bool,
    last_anomaly: Option<Instant>,
}

impl DeviceStatus {
    /// Whether it is silent now.
    pub fn is_silent(&self) -> bool {
        self.silent
    }
}

/// How to watch a system.
#[derive(Debug, Clone, Default)]
pub struct MonitorConfig {
    /// Where the monitor sits (a vertex index); `None` for the default position of each network.
    pub at: Option<usize>,
    /// The networks to watch.
    pub networks: Vec<u32>,
    /// Producer heartbeat times by (network, vertex), from the DCFs; zero or missing use `fallback`.
    pub producer_times: BTreeMap<(u32, usize), Duration>,
    /// The producer time of devices whose DCF gives none (`--heartbeat-ms`).
    pub fallback: Option<Duration>,
}

struct Watched {
    wiring: Wiring,
    localiser: Localiser,
    /// Indices into `devices` of this network's devices, in wiring order.
    devices: Vec<usize>,
    settle: Duration,
    due: Option<Instant>,
    reported: BTreeSet<usize>,
    last: Option<Diagnosed>,
}

/// The monitor (see the [module docs](self)).
pub struct SystemMonitor {
    devices: Vec<DeviceStatus>,
    networks: BTreeMap<u32, Watched>,
    started: Option<Instant>,
    events: VecDeque<Event>,
}

impl std::fmt::Debug for SystemMonitor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SystemMonitor")
            .field("devices", &self.devices.len())
            .field("networks", &self.networks.keys().collect::<Vec<_>>())
            .finish_non_exhaustive()
    }
}

impl SystemMonitor {
    /// A monitor of `config.networks` of `topology`. Networks without devices are left out.
    pub fn new(topology: &Topology, config: &MonitorConfig) -> SystemMonitor {
        let mut devices = Vec::new();
        let mut networks = BTreeMap::new();
        for &net in &config.networks {
            let Some(wiring) = Wiring::new(topology, net, config.at) else {
                continue;
            };
            let localiser = Localiser::new(topology, &wiring);
            let mut indices = Vec::new();
            let mut longest = Duration::ZERO;
            for device in wiring.devices() {
                let period = config
                    .producer_times
                    .get(&(net, device.vertex))
                    .copied()
                    .filter(|p| !p.is_zero())
                    .or(config.fallback.filter(|p| !p.is_zero()));
                if !device.is_monitor {
                    longest = longest.max(period.unwrap_or_default());
                }
                indices.push(devices.len());
                devices.push(DeviceStatus {
                    network: net,
                    vertex: device.vertex,
                    name: device.name.clone(),
                    node_id: device.node_id,
                    period: period.filter(|_| !device.is_monitor),
                    state: None,
                    last_heard: None,
                    last_emcy: None,
                    is_monitor: device.is_monitor,
                    silences: 0,
                    anomalies: 0,
                    deadline: None,
                    silent: false,
                    last_anomaly: None,
                });
            }
            networks.insert(
                net,
                Watched {
                    wiring,
                    localiser,
                    devices: indices,
                    settle: longest.mul_f64(SILENCE_FACTOR),
                    due: None,
                    reported: BTreeSet::new(),
                    last: None,
                },
            );
        }
        SystemMonitor {
            devices,
            networks,
            started: None,
            events: VecDeque::new(),
        }
    }

    /// Starts watching at `now`: every watched device must be heard within 1.5 periods; devices without
    /// a period are reported `unmonitored`.
    pub fn start(&mut self, now: Instant) {
        self.started = Some(now);
        for index in 0..self.devices.len() {
            let Some(device) = self.devices.get_mut(index) else {
                continue;
            };
            if device.is_monitor {
                continue;
            }
            match device.period {
                Some(period) => device.deadline = Some(now + period.mul_f64(SILENCE_FACTOR)),
                None => {
                    device.state = Some(DeviceState::Unmonitored);
                    self.events.extend(self.state_event(now, index));
                }
            }
        }
    }

    /// A frame received on network `network` at `now`.
    pub fn handle_frame(&mut self, now: Instant, network: u32, frame: &CanFrame) {
        let CanId::Standard(id) = frame.id() else {
            return;
        };
        let raw = id.as_raw();
        if frame.is_remote() {
            return;
        }
        let (base, node) = (raw & 0x780, raw & 0x7F);
        let Ok(node_id) = u8::try_from(node) else { return };
        let Some(index) = self.find(network, node_id) else {
            return;
        };
        match (base, frame.data()) {
            (0x700, &[byte]) => match DeviceState::from_heartbeat(byte) {
                Some(state) => {
                    let Some(device) = self.devices.get(index) else {
                        return;
                    };
                    let babbled = device.state == Some(state)
                        && device
                            .last_heard
                            .zip(device.period)
                            .is_some_and(|(last, period)| now.saturating_duration_since(last) < period / 10);
                    if let (true, Some(last), Some(period)) = (babbled, device.last_heard, device.period) {
                        let reason = format!(
                            "a heartbeat {:.3} ms after the last one with the same state; the producer time is {} ms",
                            now.saturating_duration_since(last).as_secs_f64() * 1e3,
                            period.as_millis()
                        );
                        self.anomaly(now, index, frame, reason);
                    }
                    self.heard(now, index, state);
                }
                // Bit 7 set with a state: a node guarding answer to someone's request.
                None if byte & 0x80 != 0 && DeviceState::from_heartbeat(byte & 0x7F).is_some() => {}
                None => self.anomaly(now, index, frame, format!("{byte:02X}h is no NMT state")),
            },
            (0x700, data) => {
                let reason = format!("a heartbeat has 1 byte, this one {}", data.len());
                self.anomaly(now, index, frame, reason);
            }
            (0x080, &[low, high, register, _, _, _, _, _]) => {
                if let Some(device) = self.devices.get_mut(index) {
                    device.last_emcy = Some(LastEmcy {
                        at: now,
                        code: u16::from_le_bytes([low, high]),
                        register,
                    });
                }
            }
            (0x080, data) => {
                let reason = format!("an EMCY has 8 bytes, this one {}", data.len());
                self.anomaly(now, index, frame, reason);
            }
            _ => {}
        }
    }

    /// How the watched devices did since the start (see [`Health`]).
    pub fn health(&self) -> Health {
        let watched: Vec<&DeviceStatus> = self
            .devices
            .iter()
            .filter(|d| d.period.is_some() && !d.is_monitor)
            .collect();
        if !watched.is_empty() && watched.iter().all(|d| d.last_heard.is_none()) {
            return Health::Unheard;
        }
        let troubled = self.devices.iter().any(|d| d.anomalies > 0)
            || watched.iter().any(|d| d.silences > 0 || d.last_heard.is_none());
        if troubled {
            Health::Troubled
        } else {
            Health::Healthy
        }
    }

    /// Runs what is due at `now`: silences and settled diagnoses.
    pub fn handle_timeout(&mut self, now: Instant) {
        for index in 0..self.devices.len() {
            let Some(device) = self.devices.get_mut(index) else {
                continue;
            };
            if device.deadline.is_some_and(|d| d <= now) && !device.silent {
                device.deadline = None;
                device.silent = true;
                device.silences = device.silences.saturating_add(1);
                device.state = Some(DeviceState::Silent);
                let network = device.network;
                self.events.extend(self.state_event(now, index));
                self.changed(now, network);
            }
        }
        let due: Vec<u32> = self
            .networks
            .iter()
            .filter(|(_, w)| w.due.is_some_and(|d| d <= now))
            .map(|(net, _)| *net)
            .collect();
        for net in due {
            self.diagnose(now, net);
        }
    }

    /// The next event.
    pub fn poll_event(&mut self) -> Option<Event> {
        self.events.pop_front()
    }

    /// When [`SystemMonitor::handle_timeout`] has something to do next.
    pub fn poll_timeout(&self) -> Option<Instant> {
        let deadlines = self
            .devices
            .iter()
            .filter(|d| !d.silent)
            .filter_map(|d| d.deadline);
        let dues = self.networks.values().filter_map(|w| w.due);
        deadlines.chain(dues).min()
    }

    /// Every device, by network and then wiring order.
    pub fn devices(&self) -> &[DeviceStatus] {
        &self.devices
    }

    /// The networks watched.
    pub fn networks(&self) -> Vec<u32> {
        self.networks.keys().copied().collect()
    }

    /// The vertex the monitor listens at on network `net`.
    pub fn listening_at(&self, net: u32) -> Option<usize> {
        self.networks.get(&net).map(|w| w.wiring.root_vertex())
    }

    /// Every device's state and each network's last reported diagnosis at `now` (see [`Snapshot`]).
    pub fn snapshot(&self, now: Instant) -> Snapshot {
        Snapshot {
            time: self.seconds(now),
            devices: self
                .devices
                .iter()
                .map(|d| DeviceSnapshot {
                    network: d.network,
                    node: d.name.clone(),
                    node_id: d.node_id,
                    state: d.state,
                    is_monitor: d.is_monitor,
                })
                .collect(),
            diagnoses: self
                .networks
                .iter()
                .map(|(net, w)| NetworkDiagnosis {
                    network: *net,
                    last: w.last.clone(),
                })
                .collect(),
        }
    }

    /// The explanations of the silent devices of `net` now (what the next diagnosis would say).
    pub fn explain_now(&self, net: u32) -> Vec<NamedExplanation> {
        self.networks
            .get(&net)
            .map(|w| self.explanations(w).1)
            .unwrap_or_default()
    }

    fn find(&self, network: u32, node_id: u8) -> Option<usize> {
        let watched = self.networks.get(&network)?;
        watched.devices.iter().copied().find(|&i| {
            self.devices
                .get(i)
                .is_some_and(|d| d.node_id == node_id && !d.is_monitor)
        })
    }

    /// Counts an anomaly and reports it unless the device's last report was within
    /// [`ANOMALY_REPEAT`].
    fn anomaly(&mut self, now: Instant, index: usize, frame: &CanFrame, reason: String) {
        let time = self.seconds(now);
        let Some(device) = self.devices.get_mut(index) else {
            return;
        };
        device.anomalies = device.anomalies.saturating_add(1);
        if device
            .last_anomaly
            .is_some_and(|at| now.saturating_duration_since(at) < ANOMALY_REPEAT)
        {
            return;
        }
        device.last_anomaly = Some(now);
        self.events.push_back(Event::Anomaly {
            time,
            network: device.network,
            node: device.name.clone(),
            node_id: device.node_id,
            frame: frame.to_string(),
            reason,
        });
    }

    fn heard(&mut self, now: Instant, index: usize, state: DeviceState) {
        let Some(device) = self.devices.get_mut(index) else {
            return;
        };
        device.last_heard = Some(now);
        if let Some(period) = device.period {
            device.deadline = Some(now + period.mul_f64(SILENCE_FACTOR));
        }
        let was_silent = std::mem::replace(&mut device.silent, false);
        let network = device.network;
        let changed = device.state != Some(state);
        if device.state != Some(DeviceState::Unmonitored) || device.period.is_some() {
            device.state = Some(state);
        }
        if was_silent && let Some(device) = self.devices.get(index) {
            self.events.push_back(Event::Recovered {
                time: self.seconds(now),
                network,
                node: device.name.clone(),
                node_id: device.node_id,
            });
            self.changed(now, network);
        }
        if changed && self.devices.get(index).is_some_and(|d| d.state == Some(state)) {
            self.events.extend(self.state_event(now, index));
        }
    }

    fn changed(&mut self, now: Instant, net: u32) {
        if let Some(watched) = self.networks.get_mut(&net)
            && watched.due.is_none()
        {
            watched.due = Some(now + watched.settle);
        }
    }

    fn diagnose(&mut self, now: Instant, net: u32) {
        let Some(watched) = self.networks.get(&net) else {
            return;
        };
        let (silent, explanations) = self.explanations(watched);
        let silent_set: BTreeSet<usize> = watched
            .devices
            .iter()
            .enumerate()
            .filter(|(_, i)| self.devices.get(**i).is_some_and(|d| d.silent))
            .map(|(position, _)| position)
            .collect();
        let time = self.seconds(now);
        let Some(watched) = self.networks.get_mut(&net) else {
            return;
        };
        watched.due = None;
        if silent_set == watched.reported {
            return;
        }
        watched.reported = silent_set;
        watched.last = Some(Diagnosed {
            time,
            silent: silent.clone(),
            explanations: explanations.clone(),
        });
        self.events.push_back(Event::Diagnosis {
            time,
            network: net,
            silent,
            explanations,
        });
    }

    /// The silent devices' names and the explanations of a network's silence now.
    fn explanations(&self, watched: &Watched) -> (Vec<String>, Vec<NamedExplanation>) {
        let positions = |pred: &dyn Fn(&DeviceStatus) -> bool| -> BTreeSet<usize> {
            watched
                .devices
                .iter()
                .enumerate()
                .filter(|(_, i)| self.devices.get(**i).is_some_and(pred))
                .map(|(position, _)| position)
                .collect()
        };
        let watched_set = positions(&|d| d.period.is_some() && !d.is_monitor);
        let silent = positions(&|d| d.silent);
        let name = |position: &usize| {
            watched
                .devices
                .get(*position)
                .and_then(|i| self.devices.get(*i))
                .map(|d| d.name.clone())
                .unwrap_or_default()
        };
        let explanations = watched
            .localiser
            .explain(&watched_set, &silent)
            .into_iter()
            .map(|e| NamedExplanation {
                kind: e.kind,
                candidates: e.candidates,
                explains: e.explains.iter().map(name).collect(),
            })
            .collect();
        (silent.iter().map(name).collect(), explanations)
    }

    fn state_event(&self, now: Instant, index: usize) -> Option<Event> {
        let device = self.devices.get(index)?;
        Some(Event::State {
            time: self.seconds(now),
            network: device.network,
            node: device.name.clone(),
            node_id: device.node_id,
            state: device.state.unwrap_or(DeviceState::Silent),
        })
    }

    fn seconds(&self, now: Instant) -> f64 {
        let elapsed = self
            .started
            .map_or(Duration::ZERO, |s| now.saturating_duration_since(s));
        // Microseconds are what the clock resolves; the JSON keeps them exactly.
        elapsed.as_micros() as f64 / 1e6
    }
}

#[cfg(test)]
mod tests {
    use canopener_can::StandardId;

    use super::*;
    use crate::wiring::tests::system;

    fn heartbeat(node: u16, state: u8) -> CanFrame {
        CanFrame::new(StandardId::new(0x700 + node).unwrap(), &[state]).unwrap()
    }

    fn at(ms: u64) -> Instant {
        Instant::from_millis(ms)
    }

    #[test]
    fn a_cut_gives_silent_states_then_one_settled_diagnosis_and_a_repair_recovers() {
        let topology = system(
            &[("m", 1, None), ("a", 2, None), ("b", 3, None)],
            &[],
            &[("W1", "m", "a"), ("W2", "a", "b")],
        );
        let config = MonitorConfig {
            networks: vec![1],
            fallback: Some(Duration::from_millis(100)),
            ..MonitorConfig::default()
        };
        let mut monitor = SystemMonitor::new(&topology, &config);
        monitor.start(at(0));
        let mut events = Vec::new();
        run_from(&mut monitor, 10, 1010, &[2, 3], &mut events);
        assert_eq!(
            events,
            [
                r#"{"event":"state","time":0.01,"network":1,"node":"a","node_id":2,"state":"operational"}"#,
                r#"{"event":"state","time":0.01,"network":1,"node":"b","node_id":3,"state":"operational"}"#,
            ]
        );
        events.clear();
        // W2 cut at 1.05 s: b's last heartbeat was at 1.01 s, silent at 1.16 s, diagnosed 0.15 s later.
        let mut monitor2 = monitor;
        run_from(&mut monitor2, 1110, 2000, &[2], &mut events);
        assert_eq!(
            events,
            [
                r#"{"event":"state","time":1.16,"network":1,"node":"b","node_id":3,"state":"silent"}"#,
                r#"{"event":"diagnosis","time":1.31,"network":1,"silent":["b"],"explanations":[{"kind":"cable","candidates":["W2"],"explains":["b"]},{"kind":"device","candidates":["b"],"explains":["b"]}]}"#,
            ]
        );
        events.clear();
        run_from(&mut monitor2, 2010, 2500, &[2, 3], &mut events);
        assert_eq!(
            events,
            [
                r#"{"event":"recovered","time":2.01,"network":1,"node":"b","node_id":3}"#,
                r#"{"event":"state","time":2.01,"network":1,"node":"b","node_id":3,"state":"operational"}"#,
                r#"{"event":"diagnosis","time":2.16,"network":1,"silent":[],"explanations":[]}"#,
            ]
        );
    }

    #[test]
    fn a_snapshot_holds_the_states_and_the_last_diagnosis_the_events_reported() {
        let topology = system(
            &[("m", 1, None), ("a", 2, None), ("b", 3, None)],
            &[],
            &[("W1", "m", "a"), ("W2", "a", "b")],
        );
        let config = MonitorConfig {
            networks: vec![1],
            fallback: Some(Duration::from_millis(100)),
            ..MonitorConfig::default()
        };
        let mut monitor = SystemMonitor::new(&topology, &config);
        monitor.start(at(0));
        let before = monitor.snapshot(at(0));
        assert_eq!(before.diagnoses[0].last, None);
        assert!(before.devices.iter().all(|d| d.state.is_none()));
        let mut events = Vec::new();
        run_from(&mut monitor, 10, 1010, &[2, 3], &mut events);
        run_from(&mut monitor, 1110, 2000, &[2], &mut events);
        let snapshot = monitor.snapshot(at(2000));
        assert_eq!(snapshot.time, 2.0);
        let states: Vec<(&str, Option<DeviceState>, bool)> = snapshot
            .devices
            .iter()
            .map(|d| (d.node.as_str(), d.state, d.is_monitor))
            .collect();
        assert_eq!(
            states,
            [
                ("m", None, true),
                ("a", Some(DeviceState::Operational), false),
                ("b", Some(DeviceState::Silent), false)
            ]
        );
        let last = snapshot.diagnoses[0].last.as_ref().expect("diagnosed");
        assert_eq!(last.silent, ["b"]);
        assert_eq!(last.explanations[0].candidates, ["W2"]);
        // The snapshot says what the last diagnosis event said.
        let reported = events.iter().rev().find(|e| e.contains("diagnosis")).unwrap();
        assert!(
            reported.contains(r#""time":1.31"#) && last.time == 1.31,
            "{reported}"
        );
    }

    fn run_from(
        monitor: &mut SystemMonitor,
        from: u64,
        until: u64,
        beating: &[u16],
        events: &mut Vec<String>,
    ) {
        for t in (from..=until).step_by(100) {
            while let Some(due) = monitor.poll_timeout().filter(|d| *d <= at(t)) {
                monitor.handle_timeout(due);
            }
            for &node in beating {
                monitor.handle_frame(at(t), 1, &heartbeat(node, 0x05));
            }
        }
        while let Some(due) = monitor.poll_timeout().filter(|d| *d <= at(until)) {
            monitor.handle_timeout(due);
        }
        events.extend(std::iter::from_fn(|| monitor.poll_event()).map(|e| e.to_json()));
    }

    fn frame(id: u16, data: &[u8]) -> CanFrame {
        CanFrame::new(StandardId::new(id).unwrap(), data).unwrap()
    }

    /// Heartbeats of the wrong length, unknown state bytes and short EMCYs are anomalies quoting the
    /// frame, never a sign of life; a babbling device is reported once a second per reason; a
    /// guarding answer is neither.
    #[test]
    fn malformed_heartbeats_and_emcys_are_anomalies_not_signs_of_life() {
        let topology = system(&[("m", 1, None), ("a", 2, None)], &[], &[]);
        let config = MonitorConfig {
            networks: vec![1],
            fallback: Some(Duration::from_millis(100)),
            ..MonitorConfig::default()
        };
        let mut monitor = SystemMonitor::new(&topology, &config);
        monitor.start(at(0));
        for (t, f) in [
            (10, frame(0x702, &[])),
            (1020, frame(0x702, &[0x05, 0x00])),
            (2030, frame(0x702, &[0x33])),
            (2040, frame(0x702, &[0x44])),
            (3050, frame(0x082, &[0x10, 0x82, 0x11])),
            (4060, frame(0x702, &[0x85])),
        ] {
            while let Some(due) = monitor.poll_timeout().filter(|d| *d <= at(t)) {
                monitor.handle_timeout(due);
            }
            monitor.handle_frame(at(t), 1, &f);
        }
        let events: Vec<String> = std::iter::from_fn(|| monitor.poll_event())
            .map(|e| e.to_json())
            .collect();
        assert_eq!(
            events,
            [
                r#"{"event":"anomaly","time":0.01,"network":1,"node":"a","node_id":2,"frame":"702#","reason":"a heartbeat has 1 byte, this one 0"}"#,
                r#"{"event":"state","time":0.15,"network":1,"node":"a","node_id":2,"state":"silent"}"#,
                r#"{"event":"diagnosis","time":0.3,"network":1,"silent":["a"],"explanations":[{"kind":"device","candidates":["a"],"explains":["a"]}]}"#,
                r#"{"event":"anomaly","time":1.02,"network":1,"node":"a","node_id":2,"frame":"702#0500","reason":"a heartbeat has 1 byte, this one 2"}"#,
                r#"{"event":"anomaly","time":2.03,"network":1,"node":"a","node_id":2,"frame":"702#33","reason":"33h is no NMT state"}"#,
                r#"{"event":"anomaly","time":3.05,"network":1,"node":"a","node_id":2,"frame":"082#108211","reason":"an EMCY has 8 bytes, this one 3"}"#,
            ]
        );
        assert_eq!(monitor.devices()[1].anomalies, 5);
        assert_eq!(monitor.devices()[1].last_heard, None);
        assert_eq!(monitor.health(), Health::Unheard);
        monitor.handle_frame(at(4100), 1, &heartbeat(2, 0x05));
        assert_eq!(monitor.health(), Health::Troubled);
    }

    /// Heartbeats repeated within a tenth of the producer time: an anomaly, but alive.
    #[test]
    fn a_babbling_heartbeat_is_an_anomaly_but_a_sign_of_life() {
        let topology = system(&[("m", 1, None), ("a", 2, None)], &[], &[]);
        let config = MonitorConfig {
            networks: vec![1],
            fallback: Some(Duration::from_millis(100)),
            ..MonitorConfig::default()
        };
        let mut monitor = SystemMonitor::new(&topology, &config);
        monitor.start(at(0));
        for t in [10, 10, 110, 111, 210] {
            monitor.handle_frame(at(t), 1, &heartbeat(2, 0x05));
        }
        // A state change may come at once.
        monitor.handle_frame(at(211), 1, &heartbeat(2, 0x7F));
        let anomalies: Vec<String> = std::iter::from_fn(|| monitor.poll_event())
            .filter(|e| matches!(e, Event::Anomaly { .. }))
            .map(|e| e.to_json())
            .collect();
        assert_eq!(
            anomalies,
            [
                r#"{"event":"anomaly","time":0.01,"network":1,"node":"a","node_id":2,"frame":"702#05","reason":"a heartbeat 0.000 ms after the last one with the same state; the producer time is 100 ms"}"#
            ]
        );
        assert_eq!(monitor.devices()[1].anomalies, 2);
        assert_eq!(monitor.devices()[1].state, Some(DeviceState::PreOperational));
    }

    #[test]
    fn a_run_of_valid_heartbeats_is_healthy() {
        let topology = system(&[("m", 1, None), ("a", 2, None)], &[], &[]);
        let config = MonitorConfig {
            networks: vec![1],
            fallback: Some(Duration::from_millis(100)),
            ..MonitorConfig::default()
        };
        let mut monitor = SystemMonitor::new(&topology, &config);
        monitor.start(at(0));
        let mut events = Vec::new();
        run_from(&mut monitor, 10, 1010, &[2], &mut events);
        assert_eq!(monitor.health(), Health::Healthy);
    }

    #[test]
    fn devices_without_a_period_are_unmonitored_once_and_never_silent() {
        let topology = system(&[("m", 1, None), ("a", 2, None)], &[], &[]);
        let config = MonitorConfig {
            networks: vec![1],
            ..MonitorConfig::default()
        };
        let mut monitor = SystemMonitor::new(&topology, &config);
        monitor.start(at(0));
        assert_eq!(monitor.poll_timeout(), None);
        let events: Vec<String> = std::iter::from_fn(|| monitor.poll_event())
            .map(|e| e.to_json())
            .collect();
        assert_eq!(
            events,
            [r#"{"event":"state","time":0.0,"network":1,"node":"a","node_id":2,"state":"unmonitored"}"#]
        );
        monitor.handle_frame(at(5), 1, &heartbeat(2, 0x7F));
        assert_eq!(monitor.poll_event(), None);
        assert_eq!(monitor.devices()[1].last_heard, Some(at(5)));
    }
}

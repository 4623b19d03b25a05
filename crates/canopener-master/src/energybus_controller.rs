//! The EnergyBus controller (EBC), sans IO: the NMT master and LSS master at node-ID 1 that brings
//! EnergyBus devices onto the network and walks them through the EMS states (seeds/003 §3.3: "the
//! EBC functionality requires ... NMT master functionality ... and LSS master functionality to
//! initialise and configure the devices"; it "controls the internal state and monitors the
//! Heartbeat of every connected device").
//!
//! What it does, built on [`LssMaster`], [`NmtMaster`], [`NodeMonitor`] and one [`SdoClient`] per
//! device:
//! 1. **Boot-up.** Its own boot-up message (701h, 00h) at [`EnergyBusController::start`], then its
//!    heartbeat, Operational, every [`ControllerConfig::heartbeat`].
//! 2. **Finding devices.** Every [`ControllerConfig::scan_period`] (the first time
//!    [`ControllerConfig::first_scan`] after the start) while the LSS master is idle, a fastscan
//!    of every unconfigured device ([`LssMaster::scan_all`], CiA 305 fastscan) that gives each the
//!    lowest free node-ID of [`ControllerConfig::node_ids`] (2 to 119 by default: node 1 is the
//!    controller's, 120 and up are fixed assignments, design note §5.9). EnergyBus devices keep no
//!    node-ID over a power cycle, so no store configuration is sent.
//! 3. **Heartbeat consumption.** At each managed device's boot-up: its heartbeat producer time
//!    1017h := [`ControllerConfig::device_heartbeat_ms`] and its consumer entry 1016h:01 := node 1,
//!    [`ControllerConfig::device_consumer_ms`] (the device watches the controller); then NMT start.
//!    The controller watches the device with [`ControllerConfig::consumer_time`] from its first
//!    heartbeat after the boot-up on.
//! 4. **The EMS walk** by SDO, on the assumed objects of the [`EmsProfile`]: read the status word,
//!    write the control word for the next step (Connected → Compatibility check → Limiting →
//!    Operating; Masterless → Compatibility check), write the current limit
//!    [`ControllerConfig::current_limit_ma`] in Limiting, read again, until the device reports
//!    Operating. A device in Disconnected is read again after [`ControllerConfig::status_poll`] (it
//!    steps to Connected on its own); a control word the device refuses (it stepped on its own
//!    meanwhile) is followed by a new read after the poll time. A failed transfer is tried again
//!    after the poll time, for as long as the device's heartbeat says it is there: a device that is
//!    gone is the heartbeat's business (5.), not the walk's.
//! 5. **Reactions.** A managed device's boot-up (it reset) starts step 3 again. A lost heartbeat
//!    ([`NodeMonitor`]) makes the controller send NMT reset node to the device (an EnergyBus device
//!    then forgets its node-ID: if it is still there, the next scan brings it back), free its
//!    node-ID and scan again soon. A node it did not configure that is heard (one that missed that
//!    reset, cut off the bus meanwhile) is sent NMT reset node once, so it asks for a node-ID again.
//!
//! A device can be handed over to someone else, a tester ([`EnergyBusController::hand_over`]): the
//! controller keeps its node-ID reserved and no longer watches, walks or resets it.

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::fmt;
use std::time::Duration;

use canopener_can::{CanFrame, CanId, Core, Instant, StandardId};
use canopener_wire::energybus::{EmsProfile, EmsState, EmsTransition};
use canopener_wire::{
    ERROR_CONTROL_BASE, LssAddress, NmtCommand, NmtState, NodeId, SDO_RX_BASE, SDO_TX_BASE,
};

use crate::error_control::{ConsumerTime, MonitorEvent, NodeMonitor};
use crate::lss_master::{KnownParts, LssConfig, LssEvent, LssMaster, ScanError, ScanPlan};
use crate::nmt_master::{NmtMaster, NmtTarget};
use crate::sdo_client::{DownloadMode, SdoClient, SdoClientEvent, SdoTransferError, UploadMode};

/// The controller's node-ID (EnergyBus: the active EBC is always node 1).
pub const CONTROLLER_NODE_ID: u8 = 1;

/// The controller's settings.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ControllerConfig {
    /// The node-IDs to give, lowest free first.
    pub node_ids: Vec<NodeId>,
    /// The controller's own heartbeat period.
    pub heartbeat: Duration,
    /// The heartbeat producer time written to each device's 1017h, in ms.
    pub device_heartbeat_ms: u16,
    /// The consumer time for node 1 written to each device's 1016h:01, in ms.
    pub device_consumer_ms: u16,
    /// How long the controller waits for a device's next heartbeat before it is lost.
    pub consumer_time: Duration,
    /// When the first scan starts after [`EnergyBusController::start`].
    pub first_scan: Duration,
    /// How often the controller looks for unconfigured devices.
    pub scan_period: Duration,
    /// The LSS master's timing.
    pub lss: LssConfig,
    /// How long an SDO transfer waits for the device.
    pub sdo_timeout: Duration,
    /// The current limit written in Limiting, in mA.
    pub current_limit_ma: u16,
    /// The wait before reading the status word again (a device in Disconnected, a failed transfer).
    pub status_poll: Duration,
}

impl Default for ControllerConfig {
    /// Node-IDs 2 to 119, a 100 ms heartbeat both ways with a consumer time of 2.5 periods (the
    /// devices watch the controller with 3), a scan every second (the first 100 ms after the start),
    /// CiA 305 LSS timing of [`LssConfig::DEFAULT`], SDO timeout 100 ms, current limit 1500 mA.
    fn default() -> ControllerConfig {
        ControllerConfig {
            node_ids: (2..=119).filter_map(NodeId::new).collect(),
            heartbeat: Duration::from_millis(100),
            device_heartbeat_ms: 100,
            device_consumer_ms: 300,
            consumer_time: Duration::from_millis(250),
            first_scan: Duration::from_millis(100),
            scan_period: Duration::from_secs(1),
            lss: LssConfig::DEFAULT,
            sdo_timeout: Duration::from_millis(100),
            current_limit_ma: 1500,
            status_poll: Duration::from_millis(50),
        }
    }
}

/// What the controller reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ControllerEvent {
    /// A fastscan found a device and gave it a node-ID.
    Found {
        /// The node-ID given.
        node: NodeId,
        /// Its LSS address.
        address: LssAddress,
    },
    /// A fastscan stopped early.
    ScanFailed {
        /// Why.
        error: ScanError,
    },
    /// A managed device sent its boot-up message; the controller configures it.
    BootUp {
        /// The device.
        node: NodeId,
    },
    /// The device's heartbeat producer and consumer are configured and it was started (NMT).
    HeartbeatConfigured {
        /// The device.
        node: NodeId,
    },
    /// The status word was read.
    StateRead {
        /// The device.
        node: NodeId,
        /// The status word.
        status: u16,
        /// The state it reports, if its code is one.
        state: Option<EmsState>,
    },
    /// A control word was written and confirmed.
    ControlWritten {
        /// The device.
        node: NodeId,
        /// The value.
        value: u16,
        /// The transition asked for.
        transition: EmsTransition,
    },
    /// The device refused a control word.
    ControlRefused {
        /// The device.
        node: NodeId,
        /// The value.
        value: u16,
        /// The abort code.
        code: u32,
    },
    /// The current limit was written.
    LimitWritten {
        /// The device.
        node: NodeId,
        /// The limit in mA.
        limit_ma: u16,
    },
    /// The device reports Operating: the walk is done.
    Operating {
        /// The device.
        node: NodeId,
    },
    /// A transfer of the walk failed; it is tried again after the poll time.
    StepFailed {
        /// The device.
        node: NodeId,
        /// The step, e.g. `write 1017h`.
        step: String,
        /// Why.
        error: SdoTransferError,
    },
    /// No heartbeat from a managed device within the consumer time.
    HeartbeatLost {
        /// The device.
        node: NodeId,
    },
    /// The reaction to a lost heartbeat: NMT reset node sent, node-ID freed.
    ResetSent {
        /// The device.
        node: NodeId,
    },
    /// The device was handed over; the controller leaves it alone.
    HandedOver {
        /// The device.
        node: NodeId,
    },
    /// A node the controller did not configure was heard; it was sent NMT reset node (once).
    ForeignNodeReset {
        /// The node.
        node: NodeId,
    },
}

/// One line per event, e.g. `node 2: EMS Limiting`.
impl fmt::Display for ControllerEvent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ControllerEvent::Found { node, address } => {
                write!(f, "node {node}: found by fastscan, {address}")
            }
            ControllerEvent::ScanFailed { error } => write!(f, "fastscan failed: {error}"),
            ControllerEvent::BootUp { node } => write!(f, "node {node}: boot-up"),
            ControllerEvent::HeartbeatConfigured { node } => {
                write!(f, "node {node}: heartbeat consumption configured, NMT start sent")
            }
            ControllerEvent::StateRead {
                node,
                status,
                state: Some(state),
            } => write!(f, "node {node}: status word {status:04X}h, EMS {state}"),
            ControllerEvent::StateRead {
                node,
                status,
                state: None,
            } => write!(f, "node {node}: status word {status:04X}h, no EMS state"),
            ControllerEvent::ControlWritten {
                node,
                value,
                transition,
            } => write!(f, "node {node}: control word {value} ({transition:?})"),
            ControllerEvent::ControlRefused { node, value, code } => {
                write!(f, "node {node}: control word {value} refused, abort {code:#010X}")
            }
            ControllerEvent::LimitWritten { node, limit_ma } => {
                write!(f, "node {node}: current limit {limit_ma} mA")
            }
            ControllerEvent::Operating { node } => write!(f, "node {node}: EMS Operating"),
            ControllerEvent::StepFailed { node, step, error } => {
                write!(f, "node {node}: {step} failed ({error}); trying again")
            }
            ControllerEvent::HeartbeatLost { node } => write!(f, "node {node}: heartbeat lost"),
            ControllerEvent::ResetSent { node } => {
                write!(f, "node {node}: NMT reset node sent, node-ID freed")
            }
            ControllerEvent::HandedOver { node } => write!(f, "node {node}: handed over"),
            ControllerEvent::ForeignNodeReset { node } => {
                write!(
                    f,
                    "node {node}: not configured by the controller; NMT reset node sent"
                )
            }
        }
    }
}

/// Where a managed device is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Phase {
    /// Given a node-ID; its boot-up has not come yet.
    AwaitingBootUp,
    /// Its heartbeat is being configured.
    Configuring,
    /// The EMS walk runs.
    Walking,
    /// It reports Operating.
    Operating,
    /// The description gives a transition the walk needs no control word value: it cannot go on.
    Stuck,
    /// Handed over: the controller leaves it alone.
    HandedOver,
}

/// What the controller knows about one device.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct DeviceStatus {
    /// Its LSS address.
    pub address: LssAddress,
    /// Where it is.
    pub phase: Phase,
    /// The EMS state it reported last.
    pub state: Option<EmsState>,
}

/// The SDO step a device is at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Step {
    WriteProducer,
    WriteConsumer,
    ReadStatus,
    WriteControl(u16, EmsTransition),
    WriteLimit,
}

impl fmt::Display for Step {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Step::WriteProducer => f.write_str("write 1017h"),
            Step::WriteConsumer => f.write_str("write 1016h:01"),
            Step::ReadStatus => f.write_str("read the status word"),
            Step::WriteControl(value, _) => write!(f, "write control word {value}"),
            Step::WriteLimit => f.write_str("write the current limit"),
        }
    }
}

#[derive(Debug, Clone)]
struct Managed {
    status: DeviceStatus,
    client: SdoClient,
    /// The step whose transfer runs, or waits for `wake`.
    step: Option<Step>,
    wake: Option<Instant>,
}

/// The EnergyBus controller (see the [module docs](self)).
#[derive(Debug, Clone)]
pub struct EnergyBusController {
    config: ControllerConfig,
    profile: EmsProfile,
    lss: LssMaster,
    nmt: NmtMaster,
    monitor: NodeMonitor,
    devices: BTreeMap<NodeId, Managed>,
    /// Nodes the controller did not configure and has reset.
    foreign_reset: BTreeSet<NodeId>,
    next_scan: Option<Instant>,
    next_heartbeat: Option<Instant>,
    transmit: VecDeque<CanFrame>,
    events: VecDeque<ControllerEvent>,
}

impl EnergyBusController {
    /// A controller for devices with the assumed objects and encodings of `profile`; silent until
    /// [`EnergyBusController::start`].
    pub fn new(profile: EmsProfile, config: ControllerConfig) -> EnergyBusController {
        EnergyBusController {
            lss: LssMaster::new(config.lss),
            config,
            profile,
            nmt: NmtMaster::new(),
            monitor: NodeMonitor::new(ConsumerTime::Off),
            devices: BTreeMap::new(),
            foreign_reset: BTreeSet::new(),
            next_scan: None,
            next_heartbeat: None,
            transmit: VecDeque::new(),
            events: VecDeque::new(),
        }
    }

    /// Power-on: the boot-up message now, the heartbeat and the scans from now on.
    pub fn start(&mut self, now: Instant) {
        self.error_control(NmtState::BootUp);
        self.next_heartbeat = Some(now + self.config.heartbeat);
        self.next_scan = Some(now + self.config.first_scan);
    }

    /// Every device it gave a node-ID, in ascending order.
    pub fn devices(&self) -> impl Iterator<Item = (NodeId, DeviceStatus)> + '_ {
        self.devices.iter().map(|(node, managed)| (*node, managed.status))
    }

    /// The devices that report Operating.
    pub fn operating(&self) -> Vec<NodeId> {
        self.devices()
            .filter(|(_, status)| status.phase == Phase::Operating)
            .map(|(node, _)| node)
            .collect()
    }

    /// Leaves `node` to someone else from now on: no more heartbeat watching, walking or resets;
    /// its node-ID stays reserved. Returns whether the controller managed that node.
    pub fn hand_over(&mut self, node: NodeId) -> bool {
        let Some(managed) = self.devices.get_mut(&node) else {
            return false;
        };
        managed.status.phase = Phase::HandedOver;
        managed.step = None;
        managed.wake = None;
        managed.client = new_client(node, self.config.sdo_timeout);
        self.monitor.set_consumer_time(node, ConsumerTime::Off);
        self.events.push_back(ControllerEvent::HandedOver { node });
        true
    }

    fn error_control(&mut self, state: NmtState) {
        let id = ERROR_CONTROL_BASE + u16::from(CONTROLLER_NODE_ID);
        if let Some(frame) = StandardId::new(id).and_then(|id| CanFrame::new(id, &[state.as_raw()]).ok()) {
            self.transmit.push_back(frame);
        }
    }

    fn maybe_scan(&mut self, now: Instant) {
        if self.next_scan.is_none_or(|due| due > now) || self.lss.running().is_some() {
            return;
        }
        self.next_scan = None;
        let free: Vec<NodeId> = self
            .config
            .node_ids
            .iter()
            .copied()
            .filter(|node| !self.devices.contains_key(node))
            .collect();
        let plan = ScanPlan {
            node_ids: free,
            store: false,
            known: KnownParts::NONE,
        };
        if self.lss.scan_all(now, plan).is_err() {
            // Busy or a duplicate node-ID: neither happens here (checked above, the list is a set).
            self.next_scan = Some(now + self.config.scan_period);
        }
    }

    fn on_lss(&mut self, now: Instant, event: LssEvent) {
        match event {
            LssEvent::Found {
                address,
                node_id: Some(node),
            } => {
                self.devices.insert(
                    node,
                    Managed {
                        status: DeviceStatus {
                            address,
                            phase: Phase::AwaitingBootUp,
                            state: None,
                        },
                        client: new_client(node, self.config.sdo_timeout),
                        step: None,
                        wake: None,
                    },
                );
                self.foreign_reset.remove(&node);
                self.events.push_back(ControllerEvent::Found { node, address });
            }
            LssEvent::ScanFinished { .. } => self.scan_at(now + self.config.scan_period),
            LssEvent::ScanFailed { error, .. } => {
                self.events.push_back(ControllerEvent::ScanFailed { error });
                self.scan_at(now + self.config.scan_period);
            }
            _ => {}
        }
    }

    /// Scans at `at`, or earlier if a scan is due earlier already.
    fn scan_at(&mut self, at: Instant) {
        self.next_scan = Some(self.next_scan.map_or(at, |due| due.min(at)));
    }

    fn on_monitor(&mut self, now: Instant, event: MonitorEvent) {
        let node = event.node();
        let Some(managed) = self.devices.get(&node) else {
            // A node the controller gave no node-ID (it kept one from before a lost heartbeat, whose
            // reset it missed): reset it once, so that it asks for a node-ID by LSS again.
            let heard = matches!(
                event,
                MonitorEvent::BootUp { .. }
                    | MonitorEvent::StateChanged { .. }
                    | MonitorEvent::HeartbeatResumed { .. }
                    | MonitorEvent::Interval { .. }
            );
            if heard && node.get() != CONTROLLER_NODE_ID && self.foreign_reset.insert(node) {
                self.nmt.send(now, NmtCommand::ResetNode, NmtTarget::Node(node));
                self.events.push_back(ControllerEvent::ForeignNodeReset { node });
            }
            return;
        };
        if managed.status.phase == Phase::HandedOver {
            return;
        }
        match event {
            MonitorEvent::BootUp { .. } => {
                self.events.push_back(ControllerEvent::BootUp { node });
                // Watched from its first heartbeat after the boot-up on (CiA 301 §7.2.8.3.2).
                self.monitor
                    .set_consumer_time(node, ConsumerTime::Fixed(self.config.consumer_time));
                if let Some(managed) = self.devices.get_mut(&node) {
                    // A transfer of the walk before the reset is void.
                    managed.client = new_client(node, self.config.sdo_timeout);
                }
                self.begin(now, node, Phase::Configuring, Step::WriteProducer);
            }
            MonitorEvent::HeartbeatLost { .. } => {
                self.events.push_back(ControllerEvent::HeartbeatLost { node });
                self.nmt.send(now, NmtCommand::ResetNode, NmtTarget::Node(node));
                self.monitor.set_consumer_time(node, ConsumerTime::Off);
                self.devices.remove(&node);
                self.events.push_back(ControllerEvent::ResetSent { node });
                self.scan_at(now + self.config.first_scan);
            }
            _ => {}
        }
    }

    /// Starts `step` on `node` now, in `phase`.
    fn begin(&mut self, now: Instant, node: NodeId, phase: Phase, step: Step) {
        if let Some(managed) = self.devices.get_mut(&node) {
            managed.status.phase = phase;
        }
        self.run(now, node, step);
    }

    /// Starts the transfer of `step`.
    fn run(&mut self, now: Instant, node: NodeId, step: Step) {
        let objects = self.profile.objects;
        let config = &self.config;
        let Some(managed) = self.devices.get_mut(&node) else {
            return;
        };
        managed.step = Some(step);
        managed.wake = None;
        let client = &mut managed.client;
        let started = match step {
            Step::WriteProducer => client.download(
                now,
                0x1017,
                0,
                config.device_heartbeat_ms.to_le_bytes().to_vec(),
                DownloadMode::Expedited,
            ),
            Step::WriteConsumer => {
                let entry = u32::from(CONTROLLER_NODE_ID) << 16 | u32::from(config.device_consumer_ms);
                client.download(
                    now,
                    0x1016,
                    1,
                    entry.to_le_bytes().to_vec(),
                    DownloadMode::Expedited,
                )
            }
            Step::ReadStatus => client.upload(now, objects.status_word, 0, UploadMode::Normal),
            Step::WriteControl(value, _) => client.download(
                now,
                objects.control_word,
                0,
                value.to_le_bytes().to_vec(),
                DownloadMode::Expedited,
            ),
            Step::WriteLimit => client.download(
                now,
                objects.current_limit,
                0,
                config.current_limit_ma.to_le_bytes().to_vec(),
                DownloadMode::Expedited,
            ),
        };
        if started.is_err() {
            // A transfer still runs (it cannot: steps follow their transfers' ends); wait for it.
            managed.wake = Some(now + config.status_poll);
        }
    }

    /// Reads the status word again after the poll time.
    fn later(&mut self, now: Instant, node: NodeId, step: Step) {
        if let Some(managed) = self.devices.get_mut(&node) {
            managed.step = Some(step);
            managed.wake = Some(now + self.config.status_poll);
        }
    }

    fn on_sdo(&mut self, now: Instant, node: NodeId, event: SdoClientEvent) {
        let Some(step) = self.devices.get(&node).and_then(|m| m.step) else {
            return;
        };
        match (step, event) {
            (_, SdoClientEvent::Progress { .. }) => {}
            (Step::WriteProducer, SdoClientEvent::Downloaded { .. }) => {
                self.run(now, node, Step::WriteConsumer)
            }
            (Step::WriteConsumer, SdoClientEvent::Downloaded { .. }) => {
                self.nmt
                    .send(now, NmtCommand::StartRemoteNode, NmtTarget::Node(node));
                self.events
                    .push_back(ControllerEvent::HeartbeatConfigured { node });
                self.begin(now, node, Phase::Walking, Step::ReadStatus);
            }
            (Step::ReadStatus, SdoClientEvent::Uploaded { data, .. }) => {
                let status = match <[u8; 2]>::try_from(data.as_slice()) {
                    Ok(bytes) => u16::from_le_bytes(bytes),
                    // Not a status word: read again later.
                    Err(_) => return self.later(now, node, Step::ReadStatus),
                };
                self.on_status(now, node, status);
            }
            (Step::WriteControl(value, transition), SdoClientEvent::Downloaded { .. }) => {
                self.events.push_back(ControllerEvent::ControlWritten {
                    node,
                    value,
                    transition,
                });
                self.run(now, node, Step::ReadStatus);
            }
            (
                Step::WriteControl(value, _),
                SdoClientEvent::Failed {
                    error: SdoTransferError::AbortedByServer { code },
                    ..
                },
            ) if code == self.profile.refused_abort => {
                // The device may have stepped on its own meanwhile: see where it is now, after the
                // poll time (a device that refuses every time is not asked at the bus's speed).
                self.events
                    .push_back(ControllerEvent::ControlRefused { node, value, code });
                self.later(now, node, Step::ReadStatus);
            }
            (Step::WriteLimit, SdoClientEvent::Downloaded { .. }) => {
                self.events.push_back(ControllerEvent::LimitWritten {
                    node,
                    limit_ma: self.config.current_limit_ma,
                });
                self.control(now, node, EmsTransition::LimitingToOperating);
            }
            (step, SdoClientEvent::Failed { error, .. }) => self.failed(now, node, step, error),
            // An answer that does not fit the step (cannot happen: one transfer per step).
            (step, _) => self.later(now, node, step),
        }
    }

    fn failed(&mut self, now: Instant, node: NodeId, step: Step, error: SdoTransferError) {
        self.events.push_back(ControllerEvent::StepFailed {
            node,
            step: step.to_string(),
            error,
        });
        self.later(now, node, step);
    }

    fn control(&mut self, now: Instant, node: NodeId, transition: EmsTransition) {
        match self.profile.control_value(transition) {
            Some(value) => self.run(now, node, Step::WriteControl(value, transition)),
            // The description gives the transition no value: the walk cannot go on.
            None => {
                if let Some(managed) = self.devices.get_mut(&node) {
                    managed.status.phase = Phase::Stuck;
                    managed.step = None;
                }
            }
        }
    }

    fn on_status(&mut self, now: Instant, node: NodeId, status: u16) {
        let state = self.profile.state_of(status);
        self.events
            .push_back(ControllerEvent::StateRead { node, status, state });
        if let Some(managed) = self.devices.get_mut(&node) {
            managed.status.state = state;
        }
        match state {
            Some(EmsState::Connected) => {
                self.control(now, node, EmsTransition::ConnectedToCompatibilityCheck)
            }
            Some(EmsState::CompatibilityCheck) => {
                self.control(now, node, EmsTransition::CompatibilityCheckToLimiting)
            }
            Some(EmsState::Limiting) => self.run(now, node, Step::WriteLimit),
            Some(EmsState::Masterless) => {
                self.control(now, node, EmsTransition::MasterlessToCompatibilityCheck)
            }
            Some(EmsState::Operating) => {
                if let Some(managed) = self.devices.get_mut(&node) {
                    managed.status.phase = Phase::Operating;
                    managed.step = None;
                }
                self.events.push_back(ControllerEvent::Operating { node });
            }
            Some(EmsState::Disconnected) | None => self.later(now, node, Step::ReadStatus),
        }
    }

    /// Handles every event the parts reported until none is left, then collects their frames.
    fn pump(&mut self, now: Instant) {
        // Bounded: each round handles what the previous one produced.
        for _ in 0..64 {
            let mut any = false;
            while let Some(event) = self.lss.poll_event() {
                any = true;
                self.on_lss(now, event);
            }
            while let Some(event) = self.monitor.poll_event() {
                any = true;
                self.on_monitor(now, event);
            }
            let mut sdo = Vec::new();
            for (node, managed) in &mut self.devices {
                sdo.extend(std::iter::from_fn(|| managed.client.poll_event()).map(|e| (*node, e)));
            }
            for (node, event) in sdo {
                any = true;
                self.on_sdo(now, node, event);
            }
            self.maybe_scan(now);
            if !any {
                break;
            }
        }
        self.transmit
            .extend(std::iter::from_fn(|| self.nmt.poll_transmit()));
        self.transmit
            .extend(std::iter::from_fn(|| self.lss.poll_transmit()));
        self.transmit
            .extend(std::iter::from_fn(|| self.monitor.poll_transmit()));
        for managed in self.devices.values_mut() {
            self.transmit
                .extend(std::iter::from_fn(|| managed.client.poll_transmit()));
        }
    }
}

/// The client of `node`'s default SDO channel (600h/580h + node-ID, CiA 301).
fn new_client(node: NodeId, timeout: Duration) -> SdoClient {
    // 580h..5FFh and 600h..67Fh are 11-bit identifiers for every node-ID 1..=127.
    let id =
        |base: u16| CanId::Standard(StandardId::new(base + u16::from(node.get())).unwrap_or(StandardId::MAX));
    SdoClient::with_ids(id(SDO_RX_BASE), id(SDO_TX_BASE)).with_timeout(timeout)
}

impl Core for EnergyBusController {
    type Event = ControllerEvent;

    fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
        self.lss.accept_frame(now, frame);
        self.monitor.handle_frame(now, frame);
        for managed in self.devices.values_mut() {
            if managed.status.phase != Phase::HandedOver && managed.client.accept_frame(now, frame) {
                break;
            }
        }
        self.pump(now);
    }

    fn handle_timeout(&mut self, now: Instant) {
        if let Some(due) = self.next_heartbeat.filter(|due| *due <= now) {
            self.error_control(NmtState::Operational);
            let next = due + self.config.heartbeat;
            self.next_heartbeat = Some(if next > now {
                next
            } else {
                now + self.config.heartbeat
            });
        }
        if self.lss.poll_timeout().is_some_and(|due| due <= now) {
            self.lss.handle_timeout(now);
        }
        if self.monitor.poll_timeout().is_some_and(|due| due <= now) {
            self.monitor.handle_timeout(now);
        }
        let mut woken = Vec::new();
        for (node, managed) in &mut self.devices {
            if managed.client.poll_timeout().is_some_and(|due| due <= now) {
                managed.client.handle_timeout(now);
            }
            if managed.wake.is_some_and(|due| due <= now) {
                managed.wake = None;
                woken.extend(managed.step.map(|step| (*node, step)));
            }
        }
        // Events of the timeouts first (a transfer that just failed), then the woken steps.
        self.pump(now);
        for (node, step) in woken {
            self.run(now, node, step);
        }
        self.pump(now);
    }

    fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.transmit.pop_front()
    }

    fn poll_event(&mut self) -> Option<ControllerEvent> {
        self.events.pop_front()
    }

    fn poll_timeout(&self) -> Option<Instant> {
        let devices = self
            .devices
            .values()
            .flat_map(|m| [m.client.poll_timeout(), m.wake]);
        [
            self.next_heartbeat,
            self.next_scan.map(|due| match self.lss.running() {
                // A scan waits for the LSS master's own deadline.
                Some(_) => due.max(self.lss.poll_timeout().unwrap_or(due)),
                None => due,
            }),
            self.lss.poll_timeout(),
            self.monitor.poll_timeout(),
        ]
        .into_iter()
        .chain(devices)
        .flatten()
        .min()
    }
}

//! NMT error control, master side: the heartbeat consumer and the node guarding master
//! (CiA 301 §7.2.8.3.2), in one [`NodeMonitor`] for every node 1 to 127.
//!
//! Before changing this file read CiA 301 §7.2.8.3.2.1 (node guarding), §7.2.8.3.2.2 (heartbeat)
//! and §7.2.8.3.3 (boot-up).
//!
//! Every node sends its error control messages on 700h + node-ID, one byte:
//! - boot-up: 00h, once, when the node enters pre-operational after a reset;
//! - heartbeat: the NMT state (04h stopped, 05h operational, 7Fh pre-operational), every producer
//!   heartbeat time (the node's 1017h);
//! - node guarding answer: the state in bits 6..0 and a toggle bit in bit 7, in reply to a remote
//!   frame on the same CAN-ID from the guarding master.
//!
//! [`NodeMonitor`] tracks the reported state of every node it hears and reports what changes as
//! [`MonitorEvent`]s. Heartbeat consumption follows a [`ConsumerTime`] per node (a default for all,
//! overridable per node). As on the device side and in CANopenNode, monitoring of a node starts with
//! its first heartbeat, and a boot-up message sends it back to waiting for the first heartbeat: a
//! node that boots with heartbeats switched off is not reported lost.
//!
//! Heartbeat intervals: the gap between two consecutive heartbeats with the same state is reported
//! as [`MonitorEvent::Interval`]. A gap ending in a state change is not a period sample (many
//! stacks, CANopenNode and our device among them, send the new state at once and restart the
//! period), and a boot-up message breaks the chain. In [`ConsumerTime::Learn`] the expected period
//! is the largest of the last [`LEARN_SAMPLES`] intervals since the node was last lost, and the node
//! is lost when no heartbeat arrives within 1.5 × that period. Watching starts once
//! [`LEARN_MIN_SAMPLES`] intervals are in. Taking the largest of several keeps a jittery producer, or
//! one that sends every heartbeat twice, from being reported lost; a producer that slows down is
//! lost once, and its period is learned again from the heartbeats after the loss.
//!
//! Node guarding ([`NodeMonitor::start_guarding`]): a remote frame on 700h + node-ID every guard
//! time, the first at once. An answer is correct when it is one byte, its state is known and its
//! toggle bit differs from the previous correct answer's; after a boot-up the next answer must
//! carry toggle 0. When guarding starts without a boot-up seen since the last guarding, the first
//! answer's toggle is taken as it comes (the node may have been guarded before this master
//! started). An answer with the same toggle as the one before is reported as
//! [`MonitorEvent::ToggleError`] and ignored, as lely's master does. No correct answer for the node
//! life time (guard time × life time factor) reports [`MonitorEvent::GuardingLost`], once; the next
//! correct answer reports [`MonitorEvent::GuardingResumed`]. While a node is guarded, every data
//! frame on its error control CAN-ID other than a boot-up is taken as a guarding answer.
//!
//! Frames are untrusted: a frame of the wrong length is reported as [`MonitorEvent::Malformed`], a
//! byte that is no state as [`MonitorEvent::UnknownState`], and neither counts as a heartbeat.
//! Remote frames from others (another master guarding) are ignored. A passive monitor cannot tell a
//! heartbeat from a guarding answer to another master: answers with toggle 1 are reported as
//! unknown states, answers with toggle 0 pass as heartbeats.

use std::collections::{BTreeMap, VecDeque};
use std::fmt;
use std::time::Duration;

use canopener_can::{CanFrame, CanId, Core, Instant, StandardId};
use canopener_wire::{ERROR_CONTROL_BASE, GUARD_TOGGLE_BIT, NmtState, NodeId};

/// How many recent heartbeat intervals [`ConsumerTime::Learn`] looks at.
pub const LEARN_SAMPLES: usize = 8;

/// How many heartbeat intervals [`ConsumerTime::Learn`] waits for before it watches a node.
pub const LEARN_MIN_SAMPLES: usize = 3;

/// How a node's heartbeats are consumed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ConsumerTime {
    /// States and intervals are followed, but a silent node is never reported lost.
    Off,
    /// The node is lost when no heartbeat arrives within this time after the previous one (the
    /// consumer heartbeat time of a 1016h entry).
    Fixed(Duration),
    /// The expected period is learned from the node's own heartbeats; see the module docs.
    Learn,
}

/// The node guarding parameters of one node, as in its 100Ch and 100Dh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct GuardingConfig {
    /// The guard time: how often the master asks.
    pub guard_time: Duration,
    /// The life time factor: the node life time is `guard_time × life_time_factor`.
    pub life_time_factor: u8,
}

impl GuardingConfig {
    /// The node life time, guard time × life time factor.
    pub fn life_time(&self) -> Duration {
        self.guard_time.saturating_mul(u32::from(self.life_time_factor))
    }
}

/// Why guarding could not start.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum GuardingConfigError {
    /// A guard time of zero disables node guarding in CiA 301 (100Ch = 0).
    #[error("a guard time of 0 disables node guarding; give a guard time such as 100 ms")]
    ZeroGuardTime,
    /// A life time factor of zero disables node guarding in CiA 301 (100Dh = 0).
    #[error("a life time factor of 0 disables node guarding; give a factor of 1 or more, typically 3")]
    ZeroLifeTimeFactor,
}

/// What [`NodeMonitor`] reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MonitorEvent {
    /// A boot-up message (00h): the node was reset or powered on and is now pre-operational. Its
    /// reported state is [`NmtState::BootUp`] until its next message.
    BootUp {
        /// The node.
        node: NodeId,
    },
    /// A heartbeat or a correct guarding answer reported another state than the node's last
    /// message; `from` is `None` the first time the node is heard.
    StateChanged {
        /// The node.
        node: NodeId,
        /// The state before.
        from: Option<NmtState>,
        /// The state now.
        to: NmtState,
    },
    /// No heartbeat within the consumer time. Reported once per loss.
    HeartbeatLost {
        /// The node.
        node: NodeId,
        /// The silence since the node's last heartbeat, when the loss was noticed.
        after: Duration,
    },
    /// A heartbeat arrived after [`MonitorEvent::HeartbeatLost`].
    HeartbeatResumed {
        /// The node.
        node: NodeId,
    },
    /// The gap between two consecutive heartbeats with the same state.
    Interval {
        /// The node.
        node: NodeId,
        /// The gap.
        period: Duration,
    },
    /// A one-byte message whose byte is no NMT state (or a heartbeat with the toggle bit set).
    UnknownState {
        /// The node.
        node: NodeId,
        /// The byte received.
        byte: u8,
    },
    /// A data frame on the node's error control CAN-ID that is not one byte long.
    Malformed {
        /// The node.
        node: NodeId,
        /// The frame's DLC.
        dlc: u8,
    },
    /// No correct guarding answer within the node life time. Reported once per loss.
    GuardingLost {
        /// The node.
        node: NodeId,
    },
    /// A guarding answer whose toggle bit did not alternate; it was ignored.
    ToggleError {
        /// The node.
        node: NodeId,
    },
    /// A correct guarding answer after [`MonitorEvent::GuardingLost`].
    GuardingResumed {
        /// The node.
        node: NodeId,
    },
}

impl MonitorEvent {
    /// The node the event is about.
    pub fn node(&self) -> NodeId {
        match *self {
            MonitorEvent::BootUp { node }
            | MonitorEvent::StateChanged { node, .. }
            | MonitorEvent::HeartbeatLost { node, .. }
            | MonitorEvent::HeartbeatResumed { node }
            | MonitorEvent::Interval { node, .. }
            | MonitorEvent::UnknownState { node, .. }
            | MonitorEvent::Malformed { node, .. }
            | MonitorEvent::GuardingLost { node }
            | MonitorEvent::ToggleError { node }
            | MonitorEvent::GuardingResumed { node } => node,
        }
    }
}

/// One line per event, e.g. `node 5: PRE-OPERATIONAL -> OPERATIONAL`.
impl fmt::Display for MonitorEvent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "node {}: ", self.node())?;
        match *self {
            MonitorEvent::BootUp { .. } => f.write_str("boot-up"),
            MonitorEvent::StateChanged { from: None, to, .. } => write!(f, "{to}"),
            MonitorEvent::StateChanged {
                from: Some(from), to, ..
            } => write!(f, "{from} -> {to}"),
            MonitorEvent::HeartbeatLost { after, .. } => {
                write!(f, "heartbeat lost (silent for {} ms)", after.as_millis())
            }
            MonitorEvent::HeartbeatResumed { .. } => f.write_str("heartbeat resumed"),
            MonitorEvent::Interval { period, .. } => {
                write!(f, "heartbeat interval {:.3} ms", period.as_secs_f64() * 1000.0)
            }
            MonitorEvent::UnknownState { byte, .. } => write!(f, "unknown NMT state byte {byte:02X}h"),
            MonitorEvent::Malformed { dlc, .. } => {
                write!(f, "error control frame with {dlc} bytes instead of 1")
            }
            MonitorEvent::GuardingLost { .. } => f.write_str("node guarding lost"),
            MonitorEvent::ToggleError { .. } => f.write_str("node guarding toggle bit did not alternate"),
            MonitorEvent::GuardingResumed { .. } => f.write_str("node guarding resumed"),
        }
    }
}

/// What the monitor knows about one node.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct NodeStatus {
    /// The state the node last reported, if it was heard.
    pub state: Option<NmtState>,
    /// When the node's last boot-up, heartbeat or correct guarding answer arrived.
    pub last_heard: Option<Instant>,
    /// The consumer time in force for the node.
    pub consumer_time: ConsumerTime,
    /// The learned heartbeat period ([`ConsumerTime::Learn`]), once there is a sample.
    pub learned_period: Option<Duration>,
    /// Whether its heartbeat is currently lost.
    pub heartbeat_lost: bool,
    /// The guarding parameters, while the node is guarded.
    pub guarding: Option<GuardingConfig>,
    /// Whether guarding is currently lost.
    pub guarding_lost: bool,
}

/// The heartbeat consumer and node guarding master for nodes 1 to 127 (CiA 301 §7.2.8.3.2), sans IO.
///
/// Feed it every received frame ([`NodeMonitor::handle_frame`]; it ignores frames outside 701h to
/// 77Fh) and call [`NodeMonitor::handle_timeout`] at [`NodeMonitor::poll_timeout`]; drain guarding
/// requests with [`NodeMonitor::poll_transmit`] and events with [`NodeMonitor::poll_event`].
#[derive(Debug, Clone)]
pub struct NodeMonitor {
    default_consumer: ConsumerTime,
    nodes: BTreeMap<NodeId, NodeEntry>,
    transmit: VecDeque<CanFrame>,
    events: VecDeque<MonitorEvent>,
}

impl NodeMonitor {
    /// A monitor that has heard nothing; `default_consumer` applies to every node without its own
    /// [`NodeMonitor::set_consumer_time`].
    pub fn new(default_consumer: ConsumerTime) -> NodeMonitor {
        NodeMonitor {
            default_consumer,
            nodes: BTreeMap::new(),
            transmit: VecDeque::new(),
            events: VecDeque::new(),
        }
    }

    /// Sets `node`'s consumer time. A node that is being watched is rewatched at once from its last
    /// heartbeat with the new time; one whose deadline has then passed is reported lost at the next
    /// [`NodeMonitor::handle_timeout`].
    pub fn set_consumer_time(&mut self, node: NodeId, consumer: ConsumerTime) {
        let entry = self.nodes.entry(node).or_default();
        entry.consumer = Some(consumer);
        entry.heartbeat.rearm(consumer);
    }

    /// Starts guarding `node` at `now`: the first remote frame goes out at once. Restarting
    /// guarding of a guarded node takes the new parameters and restarts the life time from `now`.
    pub fn start_guarding(
        &mut self,
        now: Instant,
        node: NodeId,
        config: GuardingConfig,
    ) -> Result<(), GuardingConfigError> {
        if config.guard_time.is_zero() {
            return Err(GuardingConfigError::ZeroGuardTime);
        }
        if config.life_time_factor == 0 {
            return Err(GuardingConfigError::ZeroLifeTimeFactor);
        }
        let entry = self.nodes.entry(node).or_default();
        // A guarded node's messages are guarding answers, not heartbeats.
        entry.heartbeat.forget_schedule();
        let lost = entry.guarding.as_ref().is_some_and(|guarding| guarding.lost);
        entry.guarding = Some(Guarding {
            config,
            next_request: now,
            life_deadline: Some(now + config.life_time()),
            lost,
        });
        Ok(())
    }

    /// Stops guarding `node`. The toggle bit expected next is kept, so guarding can resume.
    pub fn stop_guarding(&mut self, node: NodeId) {
        if let Some(entry) = self.nodes.get_mut(&node) {
            entry.guarding = None;
        }
    }

    /// The state `node` last reported.
    pub fn state(&self, node: NodeId) -> Option<NmtState> {
        self.nodes.get(&node).and_then(|entry| entry.state)
    }

    /// What the monitor knows about `node`, if it was heard or configured.
    pub fn status(&self, node: NodeId) -> Option<NodeStatus> {
        self.nodes
            .get(&node)
            .map(|entry| entry.status(self.default_consumer))
    }

    /// Every node heard or configured, in ascending order of node-ID.
    pub fn nodes(&self) -> impl Iterator<Item = (NodeId, NodeStatus)> + '_ {
        self.nodes
            .iter()
            .map(|(node, entry)| (*node, entry.status(self.default_consumer)))
    }
}

impl Core for NodeMonitor {
    type Event = MonitorEvent;

    /// Feeds a received frame. Data frames on 701h to 77Fh are boot-up, heartbeat or guarding
    /// answers; everything else is ignored.
    fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
        let CanId::Standard(id) = frame.id() else { return };
        let Some(node) = id
            .as_raw()
            .checked_sub(ERROR_CONTROL_BASE)
            .and_then(|raw| u8::try_from(raw).ok())
            .and_then(NodeId::new)
        else {
            return;
        };
        if frame.is_remote() {
            return;
        }
        let default = self.default_consumer;
        let entry = self.nodes.entry(node).or_default();
        let events = &mut self.events;
        let &[byte] = frame.data() else {
            events.push_back(MonitorEvent::Malformed {
                node,
                dlc: frame.dlc(),
            });
            return;
        };
        if byte == NmtState::BootUp.as_raw() {
            entry.on_boot_up(now, node, events);
        } else if entry.guarding.is_some() {
            entry.on_guarding_answer(now, node, byte, events);
        } else {
            let consumer = entry.consumer.unwrap_or(default);
            entry.on_heartbeat(now, node, byte, consumer, events);
        }
    }

    /// Sends the guarding requests that are due and reports the heartbeats and guarding lost by
    /// `now`.
    fn handle_timeout(&mut self, now: Instant) {
        for (node, entry) in &mut self.nodes {
            if let Watch::Active { deadline } = entry.heartbeat.watch
                && deadline <= now
            {
                entry.heartbeat.watch = Watch::Lost;
                entry.heartbeat.lost = true;
                let after = entry.heartbeat.last.map_or(Duration::ZERO, |(at, _)| now - at);
                self.events
                    .push_back(MonitorEvent::HeartbeatLost { node: *node, after });
            }
            let Some(guarding) = &mut entry.guarding else {
                continue;
            };
            if let Some(deadline) = guarding.life_deadline
                && deadline <= now
            {
                guarding.life_deadline = None;
                guarding.lost = true;
                self.events.push_back(MonitorEvent::GuardingLost { node: *node });
            }
            if guarding.next_request <= now {
                if let Some(frame) = guard_request(*node) {
                    self.transmit.push_back(frame);
                }
                let period = guarding.config.guard_time;
                let next = guarding.next_request + period;
                // On time the schedule stays exact; a driver that fell behind gets one request,
                // not a burst.
                guarding.next_request = if next > now { next } else { now + period };
            }
        }
    }

    /// The next guarding request to send.
    fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.transmit.pop_front()
    }

    /// The next event.
    fn poll_event(&mut self) -> Option<Self::Event> {
        self.events.pop_front()
    }

    /// When [`NodeMonitor::handle_timeout`] must next be called.
    fn poll_timeout(&self) -> Option<Instant> {
        self.nodes
            .values()
            .flat_map(|entry| {
                let heartbeat = match entry.heartbeat.watch {
                    Watch::Active { deadline } => Some(deadline),
                    Watch::Waiting | Watch::Lost => None,
                };
                let guarding = entry.guarding.as_ref().map(|guarding| {
                    guarding.life_deadline.map_or(guarding.next_request, |deadline| {
                        deadline.min(guarding.next_request)
                    })
                });
                [heartbeat, guarding]
            })
            .flatten()
            .min()
    }
}

/// The guarding request for `node`: a remote frame with DLC 1, the length of the answer, since
/// CAN requires remote frames on one identifier to agree on the DLC.
fn guard_request(node: NodeId) -> Option<CanFrame> {
    let id = StandardId::new(ERROR_CONTROL_BASE + u16::from(node.get()))?;
    CanFrame::remote(id, 1).ok()
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Watch {
    /// No deadline: monitoring has not started, is off, or has no learned period yet.
    Waiting,
    /// The next heartbeat is due before `deadline`.
    Active { deadline: Instant },
    /// The deadline passed.
    Lost,
}

#[derive(Debug, Clone)]
struct HeartbeatWatch {
    /// The last heartbeat since the last boot-up: when, and the state it carried.
    last: Option<(Instant, NmtState)>,
    /// Recent intervals since the last loss, newest last.
    samples: VecDeque<Duration>,
    watch: Watch,
    /// Lost and not heard again; kept over a boot-up, so the first heartbeat after it resumes.
    lost: bool,
}

impl Default for HeartbeatWatch {
    fn default() -> Self {
        HeartbeatWatch {
            last: None,
            samples: VecDeque::with_capacity(LEARN_SAMPLES),
            watch: Watch::Waiting,
            lost: false,
        }
    }
}

impl HeartbeatWatch {
    fn learned_period(&self) -> Option<Duration> {
        if self.samples.len() < LEARN_MIN_SAMPLES {
            return None;
        }
        self.samples.iter().max().copied()
    }

    fn consumer_time(&self, consumer: ConsumerTime) -> Option<Duration> {
        match consumer {
            ConsumerTime::Off => None,
            ConsumerTime::Fixed(time) => Some(time),
            ConsumerTime::Learn => self.learned_period().map(|period| period + period / 2),
        }
    }

    /// Sets the deadline from the last heartbeat, unless lost (a loss ends with a heartbeat).
    fn rearm(&mut self, consumer: ConsumerTime) {
        if self.watch == Watch::Lost {
            return;
        }
        self.watch = match (self.last, self.consumer_time(consumer)) {
            (Some((at, _)), Some(time)) => Watch::Active { deadline: at + time },
            _ => Watch::Waiting,
        };
    }

    /// Back to waiting for the first heartbeat (boot-up, or guarding taking over).
    fn forget_schedule(&mut self) {
        self.last = None;
        if self.watch != Watch::Lost {
            self.watch = Watch::Waiting;
        }
    }
}

#[derive(Debug, Clone, Copy)]
struct Guarding {
    config: GuardingConfig,
    next_request: Instant,
    /// When the node life time runs out without a correct answer; `None` while lost.
    life_deadline: Option<Instant>,
    lost: bool,
}

#[derive(Debug, Clone, Default)]
struct NodeEntry {
    state: Option<NmtState>,
    last_heard: Option<Instant>,
    /// `None`: the monitor's default.
    consumer: Option<ConsumerTime>,
    heartbeat: HeartbeatWatch,
    guarding: Option<Guarding>,
    /// The toggle the next guarding answer must carry; `None` takes the next one as it comes.
    expected_toggle: Option<bool>,
}

impl NodeEntry {
    fn status(&self, default: ConsumerTime) -> NodeStatus {
        NodeStatus {
            state: self.state,
            last_heard: self.last_heard,
            consumer_time: self.consumer.unwrap_or(default),
            learned_period: self.heartbeat.learned_period(),
            heartbeat_lost: self.heartbeat.lost,
            guarding: self.guarding.map(|guarding| guarding.config),
            guarding_lost: self.guarding.is_some_and(|guarding| guarding.lost),
        }
    }

    fn set_state(&mut self, node: NodeId, state: NmtState, events: &mut VecDeque<MonitorEvent>) {
        if self.state != Some(state) {
            events.push_back(MonitorEvent::StateChanged {
                node,
                from: self.state,
                to: state,
            });
            self.state = Some(state);
        }
    }

    /// CiA 301 §7.2.8.3.3: the node was reset. Its guarding toggle restarts at 0.
    fn on_boot_up(&mut self, now: Instant, node: NodeId, events: &mut VecDeque<MonitorEvent>) {
        events.push_back(MonitorEvent::BootUp { node });
        self.state = Some(NmtState::BootUp);
        self.last_heard = Some(now);
        self.heartbeat.forget_schedule();
        self.expected_toggle = Some(false);
    }

    /// CiA 301 §7.2.8.3.2.2: a heartbeat carrying `byte`.
    fn on_heartbeat(
        &mut self,
        now: Instant,
        node: NodeId,
        byte: u8,
        consumer: ConsumerTime,
        events: &mut VecDeque<MonitorEvent>,
    ) {
        let Some(state) = NmtState::from_raw(byte) else {
            events.push_back(MonitorEvent::UnknownState { node, byte });
            return;
        };
        let watch = &mut self.heartbeat;
        let was_lost = watch.lost;
        if was_lost {
            // The gap that ended the loss is no period sample: learning starts again.
            watch.lost = false;
            watch.watch = Watch::Waiting;
            watch.samples.clear();
            events.push_back(MonitorEvent::HeartbeatResumed { node });
        }
        self.set_state(node, state, events);
        let watch = &mut self.heartbeat;
        if let Some((at, previous)) = watch.last
            && previous == state
        {
            let period = now - at;
            events.push_back(MonitorEvent::Interval { node, period });
            if !was_lost {
                if watch.samples.len() == LEARN_SAMPLES {
                    watch.samples.pop_front();
                }
                watch.samples.push_back(period);
            }
        }
        watch.last = Some((now, state));
        watch.rearm(consumer);
        self.last_heard = Some(now);
    }

    /// CiA 301 §7.2.8.3.2.1: an answer to a guarding request.
    fn on_guarding_answer(
        &mut self,
        now: Instant,
        node: NodeId,
        byte: u8,
        events: &mut VecDeque<MonitorEvent>,
    ) {
        let toggle = byte & GUARD_TOGGLE_BIT != 0;
        let toggle_ok = self.expected_toggle.is_none_or(|expected| expected == toggle);
        if toggle_ok {
            self.expected_toggle = Some(!toggle);
        } else {
            events.push_back(MonitorEvent::ToggleError { node });
        }
        // State 0 (boot-up) is never a guarding answer, with or without the toggle.
        let state = NmtState::from_raw(byte & !GUARD_TOGGLE_BIT).filter(|state| *state != NmtState::BootUp);
        let Some(state) = state else {
            events.push_back(MonitorEvent::UnknownState { node, byte });
            return;
        };
        if !toggle_ok {
            return;
        }
        if let Some(guarding) = &mut self.guarding {
            guarding.life_deadline = Some(now + guarding.config.life_time());
            if guarding.lost {
                guarding.lost = false;
                events.push_back(MonitorEvent::GuardingResumed { node });
            }
        }
        self.set_state(node, state, events);
        self.last_heard = Some(now);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_can::Core;
    use canopener_testkit::trace::{Trace, ms};

    fn node(raw: u8) -> NodeId {
        NodeId::new(raw).unwrap()
    }

    fn monitor(default: ConsumerTime) -> Trace<NodeMonitor> {
        Trace::new(NodeMonitor::new(default))
    }

    /// The frames of a table, each received at its millisecond, in order.
    fn feed(trace: &mut Trace<NodeMonitor>, frames: &[(u64, &str)]) {
        for (at, frame) in frames {
            trace.rx(ms(*at), frame);
        }
    }

    #[test]
    fn states_from_boot_up_and_heartbeats() {
        let mut trace = monitor(ConsumerTime::Off);
        feed(
            &mut trace,
            &[
                (0, "705#00"),
                (100, "705#7F"),
                (150, "705#05"),
                (250, "705#05"),
                (300, "705#04"),
                (310, "70A#7F"),
            ],
        );
        assert_eq!(
            trace.events(),
            [
                "0.000 BootUp { node: NodeId(5) }",
                "100.000 StateChanged { node: NodeId(5), from: Some(BootUp), to: PreOperational }",
                "150.000 StateChanged { node: NodeId(5), from: Some(PreOperational), to: Operational }",
                "250.000 Interval { node: NodeId(5), period: 100ms }",
                "300.000 StateChanged { node: NodeId(5), from: Some(Operational), to: Stopped }",
                "310.000 StateChanged { node: NodeId(10), from: None, to: PreOperational }",
            ]
        );
        assert_eq!(trace.core.state(node(5)), Some(NmtState::Stopped));
        assert_eq!(trace.core.state(node(6)), None);
        let heard: Vec<u8> = trace.core.nodes().map(|(node, _)| node.get()).collect();
        assert_eq!(heard, [5, 10]);
        assert_eq!(trace.core.poll_timeout(), None, "consumer off: no deadline");
    }

    #[test]
    fn fixed_consumer_time_lost_and_resumed() {
        let mut trace = monitor(ConsumerTime::Fixed(Duration::from_millis(150)));
        trace.rx(ms(0), "705#00");
        // Waiting for the first heartbeat: a boot-up alone starts nothing.
        assert_eq!(trace.core.poll_timeout(), None);
        trace.rx(ms(100), "705#7F");
        assert_eq!(trace.core.poll_timeout(), Some(ms(250)));
        trace.rx(ms(200), "705#7F");
        trace.advance(ms(1000));
        feed(&mut trace, &[(1000, "705#7F"), (1100, "705#7F")]);
        let events = trace.events();
        assert_eq!(
            events[2..],
            [
                "200.000 Interval { node: NodeId(5), period: 100ms }",
                "350.000 HeartbeatLost { node: NodeId(5), after: 150ms }",
                "1000.000 HeartbeatResumed { node: NodeId(5) }",
                "1000.000 Interval { node: NodeId(5), period: 800ms }",
                "1100.000 Interval { node: NodeId(5), period: 100ms }",
            ]
        );
        assert!(!trace.core.status(node(5)).unwrap().heartbeat_lost);
        assert_eq!(trace.core.poll_timeout(), Some(ms(1250)));
    }

    #[test]
    fn learned_period_with_jitter_and_a_slower_producer() {
        let mut trace = monitor(ConsumerTime::Learn);
        // A producer whose every second heartbeat is 40 ms late at 100 ms.
        for at in [0, 140, 200, 340, 400] {
            trace.rx(ms(at), "705#05");
        }
        let status = trace.core.status(node(5)).unwrap();
        assert_eq!(status.learned_period, Some(Duration::from_millis(140)));
        // 1.5 × 140 ms after the last heartbeat.
        assert_eq!(trace.core.poll_timeout(), Some(ms(610)));
        // The producer slows to 1 s: lost once, then the new period is learned.
        feed(
            &mut trace,
            &[(1400, "705#05"), (2400, "705#05"), (3400, "705#05")],
        );
        assert_eq!(trace.core.poll_timeout(), None, "relearning: 2 samples");
        trace.rx(ms(4400), "705#05");
        let events = trace.events();
        assert!(events.contains(&"610.000 HeartbeatLost { node: NodeId(5), after: 210ms }".to_string()));
        assert!(events.contains(&"1400.000 HeartbeatResumed { node: NodeId(5) }".to_string()));
        assert_eq!(
            trace.core.status(node(5)).unwrap().learned_period,
            Some(Duration::from_secs(1))
        );
        assert_eq!(trace.core.poll_timeout(), Some(ms(5900)));
        let losses = events
            .iter()
            .filter(|line| line.contains("HeartbeatLost"))
            .count();
        assert_eq!(losses, 1, "{events:?}");
    }

    #[test]
    fn doubled_heartbeats_are_not_lost_in_learn_mode() {
        let mut trace = monitor(ConsumerTime::Learn);
        for at in [0, 1, 100, 101, 200, 201, 300, 301] {
            trace.rx(ms(at), "705#7F");
        }
        trace.advance(ms(400));
        let events = trace.events();
        assert!(!events.iter().any(|line| line.contains("Lost")), "{events:?}");
        assert_eq!(
            trace.core.status(node(5)).unwrap().learned_period,
            Some(Duration::from_millis(99))
        );
        trace.advance(ms(500));
        assert_eq!(
            trace.events(),
            ["449.500 HeartbeatLost { node: NodeId(5), after: 148.5ms }"]
        );
    }

    #[test]
    fn state_change_heartbeat_is_no_period_sample() {
        let mut trace = monitor(ConsumerTime::Learn);
        feed(&mut trace, &[(0, "705#7F"), (100, "705#7F")]);
        // The node sends its new state at once and restarts its period.
        feed(&mut trace, &[(130, "705#05"), (230, "705#05")]);
        assert_eq!(
            trace.core.status(node(5)).unwrap().learned_period,
            None,
            "2 samples"
        );
        trace.rx(ms(330), "705#05");
        let events = trace.events();
        let intervals: Vec<&String> = events.iter().filter(|line| line.contains("Interval")).collect();
        assert_eq!(
            intervals,
            [
                "100.000 Interval { node: NodeId(5), period: 100ms }",
                "230.000 Interval { node: NodeId(5), period: 100ms }",
                "330.000 Interval { node: NodeId(5), period: 100ms }"
            ]
        );
        assert_eq!(
            trace.core.status(node(5)).unwrap().learned_period,
            Some(Duration::from_millis(100))
        );
    }

    #[test]
    fn boot_up_restarts_monitoring_and_breaks_the_interval_chain() {
        let mut trace = monitor(ConsumerTime::Fixed(Duration::from_millis(150)));
        feed(&mut trace, &[(0, "705#05"), (100, "705#05"), (120, "705#00")]);
        assert_eq!(trace.core.poll_timeout(), None, "waiting again after boot-up");
        feed(&mut trace, &[(220, "705#7F"), (320, "705#7F")]);
        let events = trace.events();
        assert_eq!(
            events[2..],
            [
                "120.000 BootUp { node: NodeId(5) }",
                "220.000 StateChanged { node: NodeId(5), from: Some(BootUp), to: PreOperational }",
                "320.000 Interval { node: NodeId(5), period: 100ms }",
            ]
        );
    }

    #[test]
    fn per_node_consumer_time_overrides_the_default() {
        let mut trace = monitor(ConsumerTime::Off);
        trace
            .core
            .set_consumer_time(node(7), ConsumerTime::Fixed(Duration::from_millis(50)));
        feed(&mut trace, &[(0, "705#05"), (0, "707#05")]);
        trace.advance(ms(500));
        let events = trace.events();
        assert_eq!(events[2], "50.000 HeartbeatLost { node: NodeId(7), after: 50ms }");
        assert_eq!(events.len(), 3);
        // Tightening the time of a watched node applies from its last heartbeat.
        trace.rx(ms(500), "705#05");
        trace
            .core
            .set_consumer_time(node(5), ConsumerTime::Fixed(Duration::from_millis(20)));
        assert_eq!(trace.core.poll_timeout(), Some(ms(520)));
        assert_eq!(
            trace.core.status(node(5)).unwrap().consumer_time,
            ConsumerTime::Fixed(Duration::from_millis(20))
        );
    }

    #[test]
    fn garbage_is_reported_and_never_counts_as_a_heartbeat() {
        let mut trace = monitor(ConsumerTime::Fixed(Duration::from_millis(100)));
        feed(
            &mut trace,
            &[
                (0, "705#05"),
                (50, "705#"),
                (60, "705#0505"),
                (70, "705#03"),
                (80, "705#85"),
            ],
        );
        // Other masters' requests, node-ID 0, other services and 29-bit frames are not ours.
        feed(
            &mut trace,
            &[
                (90, "705#R1"),
                (90, "700#05"),
                (90, "780#05"),
                (90, "00000705#05"),
            ],
        );
        trace.advance(ms(200));
        assert_eq!(
            trace.events()[1..],
            [
                "50.000 Malformed { node: NodeId(5), dlc: 0 }",
                "60.000 Malformed { node: NodeId(5), dlc: 2 }",
                "70.000 UnknownState { node: NodeId(5), byte: 3 }",
                "80.000 UnknownState { node: NodeId(5), byte: 133 }",
                "100.000 HeartbeatLost { node: NodeId(5), after: 100ms }",
            ]
        );
        assert_eq!(trace.core.state(node(5)), Some(NmtState::Operational));
    }

    fn guarding(guard_ms: u64, factor: u8) -> GuardingConfig {
        GuardingConfig {
            guard_time: Duration::from_millis(guard_ms),
            life_time_factor: factor,
        }
    }

    #[test]
    fn guarding_requests_answers_and_toggle() {
        let mut trace = monitor(ConsumerTime::Off);
        trace.rx(ms(0), "705#00");
        trace
            .core
            .start_guarding(ms(10), node(5), guarding(100, 3))
            .unwrap();
        feed(&mut trace, &[(11, "705#7F"), (111, "705#FF"), (211, "705#05")]);
        // Same toggle again: ignored.
        feed(&mut trace, &[(311, "705#05"), (411, "705#85")]);
        trace.advance(ms(420));
        assert_eq!(
            trace.sent(),
            [
                "10.000 705#R1",
                "110.000 705#R1",
                "210.000 705#R1",
                "310.000 705#R1",
                "410.000 705#R1"
            ]
        );
        assert_eq!(
            trace.events(),
            [
                "0.000 BootUp { node: NodeId(5) }",
                "11.000 StateChanged { node: NodeId(5), from: Some(BootUp), to: PreOperational }",
                "211.000 StateChanged { node: NodeId(5), from: Some(PreOperational), to: Operational }",
                "311.000 ToggleError { node: NodeId(5) }",
            ]
        );
        let status = trace.core.status(node(5)).unwrap();
        assert_eq!(status.guarding, Some(guarding(100, 3)));
        assert_eq!(status.last_heard, Some(ms(411)));
    }

    #[test]
    fn first_answer_after_boot_up_must_carry_toggle_0() {
        let mut trace = monitor(ConsumerTime::Off);
        trace.rx(ms(0), "705#00");
        trace
            .core
            .start_guarding(ms(0), node(5), guarding(100, 3))
            .unwrap();
        trace.rx(ms(1), "705#FF");
        assert_eq!(trace.events()[1..], ["1.000 ToggleError { node: NodeId(5) }"]);
        // Without a boot-up seen, the first toggle is taken as it comes.
        let mut trace = monitor(ConsumerTime::Off);
        trace
            .core
            .start_guarding(ms(0), node(5), guarding(100, 3))
            .unwrap();
        feed(&mut trace, &[(1, "705#FF"), (101, "705#7F"), (201, "705#7F")]);
        assert_eq!(
            trace.events(),
            [
                "1.000 StateChanged { node: NodeId(5), from: None, to: PreOperational }",
                "201.000 ToggleError { node: NodeId(5) }"
            ]
        );
    }

    #[test]
    fn guarding_lost_after_the_life_time_and_resumed() {
        let mut trace = monitor(ConsumerTime::Off);
        trace
            .core
            .start_guarding(ms(0), node(5), guarding(100, 3))
            .unwrap();
        trace.rx(ms(1), "705#7F");
        // Silence: the life time 300 ms runs from the last correct answer.
        trace.wait(Duration::from_millis(349));
        // A toggle error is no correct answer.
        feed(&mut trace, &[(401, "705#7F"), (501, "705#FF")]);
        trace.advance(ms(520));
        assert_eq!(
            trace.events(),
            [
                "1.000 StateChanged { node: NodeId(5), from: None, to: PreOperational }",
                "301.000 GuardingLost { node: NodeId(5) }",
                "401.000 ToggleError { node: NodeId(5) }",
                "501.000 GuardingResumed { node: NodeId(5) }",
            ]
        );
        assert_eq!(trace.sent().len(), 6);
        assert_eq!(trace.core.poll_timeout(), Some(ms(600)));
        trace.core.stop_guarding(node(5));
        assert_eq!(trace.core.poll_timeout(), None);
        trace.advance(ms(2000));
        assert!(trace.sent().is_empty());
        assert!(trace.events().is_empty());
    }

    #[test]
    fn guarding_answers_with_unknown_states() {
        let mut trace = monitor(ConsumerTime::Off);
        trace
            .core
            .start_guarding(ms(0), node(5), guarding(100, 2))
            .unwrap();
        // Toggle right, state wrong: the toggle still advances, the answer is not correct.
        feed(
            &mut trace,
            &[
                (1, "705#02"),
                (101, "705#82"),
                (201, "705#80"),
                (301, "705#7F"),
                (302, "705#"),
            ],
        );
        trace.advance(ms(310));
        assert_eq!(
            trace.events(),
            [
                "1.000 UnknownState { node: NodeId(5), byte: 2 }",
                "101.000 UnknownState { node: NodeId(5), byte: 130 }",
                "200.000 GuardingLost { node: NodeId(5) }",
                "201.000 ToggleError { node: NodeId(5) }",
                "201.000 UnknownState { node: NodeId(5), byte: 128 }",
                "301.000 GuardingResumed { node: NodeId(5) }",
                "301.000 StateChanged { node: NodeId(5), from: None, to: PreOperational }",
                "302.000 Malformed { node: NodeId(5), dlc: 0 }",
            ]
        );
    }

    #[test]
    fn late_driver_gets_one_request_not_a_burst() {
        let mut monitor = NodeMonitor::new(ConsumerTime::Off);
        monitor.start_guarding(ms(0), node(9), guarding(10, 100)).unwrap();
        monitor.handle_timeout(ms(0));
        assert!(monitor.poll_transmit().is_some());
        monitor.handle_timeout(ms(55));
        assert!(monitor.poll_transmit().is_some());
        assert!(monitor.poll_transmit().is_none());
        assert_eq!(monitor.poll_timeout(), Some(ms(65)));
    }

    #[test]
    fn guarding_config_is_checked() {
        let mut monitor = NodeMonitor::new(ConsumerTime::Off);
        assert_eq!(
            monitor.start_guarding(ms(0), node(1), guarding(0, 3)),
            Err(GuardingConfigError::ZeroGuardTime)
        );
        assert_eq!(
            monitor.start_guarding(ms(0), node(1), guarding(100, 0)),
            Err(GuardingConfigError::ZeroLifeTimeFactor)
        );
        assert_eq!(guarding(100, 3).life_time(), Duration::from_millis(300));
        assert!(monitor.status(node(1)).is_none());
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(128))]

        /// Untrusted frames never panic, and every deadline handed out lies ahead of the clock.
        #[test]
        fn arbitrary_frames_never_panic_or_stall(
            frames in proptest::collection::vec(
                (0x6F0u16..0x790, proptest::bool::ANY, proptest::collection::vec(proptest::prelude::any::<u8>(), 0..=8), 0u64..400),
                0..80,
            )
        ) {
            let mut monitor = NodeMonitor::new(ConsumerTime::Learn);
            monitor.set_consumer_time(node(3), ConsumerTime::Fixed(Duration::from_millis(50)));
            monitor.start_guarding(ms(0), node(5), guarding(30, 2)).unwrap();
            let mut now = ms(0);
            for (id, remote, data, dt) in frames {
                let until = now + Duration::from_millis(dt);
                while let Some(due) = monitor.poll_timeout().filter(|due| *due <= until) {
                    proptest::prop_assert!(due >= now);
                    now = due;
                    monitor.handle_timeout(now);
                    proptest::prop_assert!(monitor.poll_timeout().is_none_or(|next| next > now));
                }
                now = until;
                let id = StandardId::new(id).unwrap();
                let frame = if remote {
                    CanFrame::remote(id, data.len() as u8).unwrap()
                } else {
                    CanFrame::new(id, &data).unwrap()
                };
                monitor.handle_frame(now, &frame);
                while monitor.poll_event().is_some() {}
                while monitor.poll_transmit().is_some() {}
            }
        }
    }

    #[test]
    fn display_lines() {
        let five = node(5);
        let cases = [
            (MonitorEvent::BootUp { node: five }, "node 5: boot-up"),
            (
                MonitorEvent::StateChanged {
                    node: five,
                    from: Some(NmtState::PreOperational),
                    to: NmtState::Operational,
                },
                "node 5: PRE-OPERATIONAL -> OPERATIONAL",
            ),
            (
                MonitorEvent::HeartbeatLost {
                    node: five,
                    after: Duration::from_millis(150),
                },
                "node 5: heartbeat lost (silent for 150 ms)",
            ),
            (
                MonitorEvent::Interval {
                    node: five,
                    period: Duration::from_micros(100_250),
                },
                "node 5: heartbeat interval 100.250 ms",
            ),
            (
                MonitorEvent::UnknownState {
                    node: five,
                    byte: 0x85,
                },
                "node 5: unknown NMT state byte 85h",
            ),
        ];
        for (event, text) in cases {
            assert_eq!(event.to_string(), text);
        }
    }
}

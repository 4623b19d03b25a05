//! NMT error control, device side (CiA 301, error control protocols: heartbeat protocol, node
//! guarding protocol and life guarding).
//!
//! Two cores:
//! - [`ErrorControl`]: what this node sends. The heartbeat producer (object 1017h, period in ms,
//!   0 = off) sends 700h + node-ID with the NMT state byte (04h stopped, 05h operational, 7Fh
//!   pre-operational); node guarding answers a remote frame on 700h + node-ID with the state and a
//!   toggle bit in bit 7 (0 in the first answer, then alternating); life guarding (100Ch guard time
//!   × 100Dh life time factor) reports when the master stops guarding.
//! - [`HeartbeatConsumer`]: monitors other nodes' heartbeats (object 1016h, one entry per node:
//!   bits 23..16 node-ID, 15..0 time in ms).
//!
//! CiA 301 forbids running heartbeat production and guarding at the same time. Heartbeat wins: while
//! 1017h is not 0, remote requests are not answered and life guarding is not monitored (as lely
//! does); writing 1017h = 0 hands error control back to guarding, which restarts with the next
//! remote request.

use std::collections::VecDeque;
use std::time::Duration;

use canopener_can::{CanFrame, CanId, Core, Instant, StandardId};
use canopener_wire::{ERROR_CONTROL_BASE, NmtState, NodeId, abort, encode_guard_response};

use crate::nmt_slave::NmtSlaveState;

/// What [`ErrorControl`] reports to the `Device`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ErrorControlEvent {
    /// No node guarding request arrived within the node life time (100Ch × 100Dh) after the
    /// previous one: a life guarding event. The `Device` raises EMCY 8130h and applies 1029h.
    /// Reported once per loss.
    LifeGuardingLost,
    /// A guarding request arrived again after [`ErrorControlEvent::LifeGuardingLost`].
    LifeGuardingResumed,
}

/// Heartbeat producer, node guarding responder and life guarding monitor of one node.
#[derive(Debug, Clone)]
pub struct ErrorControl {
    node: NodeId,
    state: NmtSlaveState,
    producer_ms: u16,
    guard_ms: u16,
    life_factor: u8,
    next_heartbeat: Option<Instant>,
    toggle: bool,
    life_deadline: Option<Instant>,
    life_lost: bool,
    transmit: VecDeque<CanFrame>,
    events: VecDeque<ErrorControlEvent>,
}

impl ErrorControl {
    /// Error control for `node`, in Initialisation, with heartbeat and guarding off.
    pub fn new(node: NodeId) -> ErrorControl {
        ErrorControl {
            node,
            state: NmtSlaveState::Initialisation,
            producer_ms: 0,
            guard_ms: 0,
            life_factor: 0,
            next_heartbeat: None,
            toggle: false,
            life_deadline: None,
            life_lost: false,
            transmit: VecDeque::new(),
            events: VecDeque::new(),
        }
    }

    /// Sets the node-ID (applied by the `Device` on reset communication, like the NMT slave's).
    pub fn set_node_id(&mut self, node: NodeId) {
        self.node = node;
    }

    /// The NMT state reported in heartbeats and guarding answers.
    pub fn state(&self) -> NmtSlaveState {
        self.state
    }

    /// Whether heartbeats are being produced (1017h ≠ 0 and the node has booted).
    pub fn heartbeat_active(&self) -> bool {
        self.producer_ms != 0 && self.state != NmtSlaveState::Initialisation
    }

    /// 1017h was written: `ms` is the producer heartbeat time, 0 = off. A non-zero time
    /// (re)starts the period: the next heartbeat is sent `ms` after `now`. Turning heartbeat on
    /// stops life guarding (heartbeat wins).
    pub fn set_producer_time(&mut self, now: Instant, ms: u16) {
        self.producer_ms = ms;
        if ms == 0 {
            self.next_heartbeat = None;
        } else {
            self.life_deadline = None;
            self.life_lost = false;
            if self.state != NmtSlaveState::Initialisation {
                self.next_heartbeat = Some(now + millis(ms));
            }
        }
    }

    /// 100Ch was written: the guard time in ms. A running life guarding timer restarts from `now`
    /// with the new life time; a life time of 0 stops life guarding.
    pub fn set_guard_time(&mut self, now: Instant, ms: u16) {
        self.guard_ms = ms;
        self.retime_life_guarding(now);
    }

    /// 100Dh was written: the life time factor. Same effect as [`ErrorControl::set_guard_time`].
    pub fn set_life_time_factor(&mut self, now: Instant, factor: u8) {
        self.life_factor = factor;
        self.retime_life_guarding(now);
    }

    /// The node life time, 100Ch × 100Dh, or `None` when either is 0 (life guarding off).
    pub fn life_time(&self) -> Option<Duration> {
        let ms = u64::from(self.guard_ms) * u64::from(self.life_factor);
        (ms != 0).then(|| Duration::from_millis(ms))
    }

    /// The NMT slave changed state (the `Device` forwards every `StateChanged`).
    ///
    /// Entering Initialisation (a reset) stops heartbeats and life guarding and resets the guarding
    /// toggle to 0. Leaving it (the boot-up) starts the heartbeat period from `now`, so the first
    /// heartbeat follows the boot-up message by one period. Any other change sends a heartbeat with
    /// the new state at once and restarts the period from it, as CANopenNode does, so a master
    /// sees the transition without waiting a full period.
    pub fn set_state(&mut self, now: Instant, state: NmtSlaveState) {
        let from = self.state;
        if from == state {
            return;
        }
        self.state = state;
        if state == NmtSlaveState::Initialisation {
            self.next_heartbeat = None;
            self.life_deadline = None;
            self.life_lost = false;
            self.toggle = false;
            self.transmit.clear();
            return;
        }
        if self.producer_ms == 0 {
            return;
        }
        if from != NmtSlaveState::Initialisation {
            self.send(state.reported().as_raw());
        }
        self.next_heartbeat = Some(now + millis(self.producer_ms));
    }

    fn retime_life_guarding(&mut self, now: Instant) {
        if self.life_deadline.is_some() {
            self.life_deadline = self.life_time().map(|life| now + life);
        }
    }

    fn own_id(&self) -> StandardId {
        StandardId::new(ERROR_CONTROL_BASE + u16::from(self.node.get())).unwrap_or(StandardId::MAX)
    }

    fn send(&mut self, byte: u8) {
        if let Ok(frame) = CanFrame::new(self.own_id(), &[byte]) {
            self.transmit.push_back(frame);
        }
    }
}

impl Core for ErrorControl {
    type Event = ErrorControlEvent;

    /// Feeds a received frame. Only a remote frame on 700h + node-ID (a node guarding request)
    /// concerns this core; any DLC is accepted. It is answered with one byte, the state with the
    /// toggle bit, unless the node is in Initialisation or heartbeat production is on.
    fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
        if !frame.is_remote() || frame.id() != CanId::Standard(self.own_id()) {
            return;
        }
        if self.producer_ms != 0 || self.state == NmtSlaveState::Initialisation {
            return;
        }
        let byte = encode_guard_response(self.state.reported(), self.toggle);
        self.toggle = !self.toggle;
        self.send(byte);
        if let Some(life) = self.life_time() {
            self.life_deadline = Some(now + life);
            if self.life_lost {
                self.life_lost = false;
                self.events.push_back(ErrorControlEvent::LifeGuardingResumed);
            }
        }
    }

    /// Runs the timers due at `now`: the heartbeat and the life guarding deadline.
    fn handle_timeout(&mut self, now: Instant) {
        if let Some(due) = self.next_heartbeat
            && due <= now
        {
            self.send(self.state.reported().as_raw());
            let period = millis(self.producer_ms);
            // Keep the period exact on the schedule; if the driver fell more than a period
            // behind, restart from now instead of sending a burst.
            let next = due + period;
            self.next_heartbeat = Some(if next > now { next } else { now + period });
        }
        if let Some(deadline) = self.life_deadline
            && deadline <= now
        {
            self.life_deadline = None;
            self.life_lost = true;
            self.events.push_back(ErrorControlEvent::LifeGuardingLost);
        }
    }

    /// The next frame to send.
    fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.transmit.pop_front()
    }

    /// The next event for the `Device`.
    fn poll_event(&mut self) -> Option<Self::Event> {
        self.events.pop_front()
    }

    /// When [`ErrorControl::handle_timeout`] must next be called.
    fn poll_timeout(&self) -> Option<Instant> {
        earliest(self.next_heartbeat, self.life_deadline)
    }
}

fn millis(ms: u16) -> Duration {
    Duration::from_millis(u64::from(ms))
}

fn earliest(a: Option<Instant>, b: Option<Instant>) -> Option<Instant> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// Why a 1016h entry was refused; [`ConsumerConfigError::abort_code`] is the SDO abort code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum ConsumerConfigError {
    /// Sub-index 0 or above 127: not a consumer entry (0609 0011h).
    #[error("1016h:{sub:02X} is not a heartbeat consumer entry; entries are sub-indices 1 to 127")]
    SubIndex {
        /// The sub-index written.
        sub: u8,
    },
    /// Bits 31..24 are reserved and must be 0 (0609 0030h).
    #[error("1016h:{sub:02X} = {value:#010X} sets reserved bits 31..24; write node-ID << 16 | time in ms")]
    ReservedBits {
        /// The sub-index written.
        sub: u8,
        /// The value written.
        value: u32,
    },
    /// Another active entry already monitors this node (0604 0043h, as the CCT expects).
    #[error("node {node} is already monitored by 1016h:{other:02X}; clear that entry first")]
    DuplicateNode {
        /// The node-ID written.
        node: u8,
        /// The sub-index that already monitors it.
        other: u8,
    },
}

impl ConsumerConfigError {
    /// The SDO abort code an SDO server sends for this error.
    pub fn abort_code(&self) -> u32 {
        match self {
            ConsumerConfigError::SubIndex { .. } => abort::SUB_INDEX_DOES_NOT_EXIST,
            ConsumerConfigError::ReservedBits { .. } => abort::INVALID_VALUE,
            ConsumerConfigError::DuplicateNode { .. } => abort::PARAMETER_INCOMPATIBLE,
        }
    }
}

/// What [`HeartbeatConsumer`] reports to the `Device`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ConsumerEvent {
    /// The first heartbeat of a monitored node arrived: monitoring of its entry starts.
    HeartbeatStarted {
        /// The monitored node.
        node: u8,
    },
    /// No heartbeat within the consumer time: a heartbeat event. The `Device` raises EMCY 8130h
    /// and applies 1029h. Reported once per loss.
    HeartbeatLost {
        /// The monitored node.
        node: u8,
    },
    /// A heartbeat arrived again after [`ConsumerEvent::HeartbeatLost`].
    HeartbeatResumed {
        /// The monitored node.
        node: u8,
    },
    /// A monitored node reported a different state than before (also on its first heartbeat).
    RemoteState {
        /// The monitored node.
        node: u8,
        /// Its new state.
        state: NmtState,
    },
    /// A monitored node sent a boot-up message after it had been heard before: it was reset.
    RemoteReset {
        /// The monitored node.
        node: u8,
    },
    /// A frame on a monitored node's heartbeat identifier that is not a heartbeat (DLC not 1 or an
    /// unknown state byte); it was ignored and does not count as a heartbeat.
    Malformed {
        /// The monitored node.
        node: u8,
        /// The frame's DLC.
        dlc: u8,
    },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Watch {
    /// Configured, no heartbeat heard yet.
    Waiting,
    /// Heartbeats arrive; the next is due before the deadline.
    Active(Instant),
    /// The deadline passed.
    Lost,
}

#[derive(Debug, Clone, Copy)]
struct ConsumerEntry {
    sub: u8,
    node: u8,
    time_ms: u16,
    watch: Watch,
    last_state: Option<NmtState>,
}

/// The heartbeat consumer (object 1016h).
#[derive(Debug, Clone, Default)]
pub struct HeartbeatConsumer {
    entries: Vec<ConsumerEntry>,
    events: VecDeque<ConsumerEvent>,
}

impl HeartbeatConsumer {
    /// A consumer with no entries.
    pub fn new() -> HeartbeatConsumer {
        HeartbeatConsumer::default()
    }

    /// 1016h:`sub` was written with `value` (bits 23..16 node-ID, 15..0 time in ms). An entry
    /// with node-ID 0 or above 127, or time 0, is unused. Monitoring of the entry restarts: it
    /// waits for the node's next heartbeat. Nothing changes on error.
    pub fn set_entry(&mut self, sub: u8, value: u32) -> Result<(), ConsumerConfigError> {
        if sub == 0 || sub > 127 {
            return Err(ConsumerConfigError::SubIndex { sub });
        }
        if value >> 24 != 0 {
            return Err(ConsumerConfigError::ReservedBits { sub, value });
        }
        let node = ((value >> 16) & 0xFF) as u8;
        let time_ms = (value & 0xFFFF) as u16;
        let used = NodeId::new(node).is_some() && time_ms != 0;
        if used && let Some(other) = self.entries.iter().find(|e| e.node == node && e.sub != sub) {
            return Err(ConsumerConfigError::DuplicateNode {
                node,
                other: other.sub,
            });
        }
        self.entries.retain(|e| e.sub != sub);
        if used {
            self.entries.push(ConsumerEntry {
                sub,
                node,
                time_ms,
                watch: Watch::Waiting,
                last_state: None,
            });
        }
        Ok(())
    }

    /// The last state heard from `node`, if it is monitored and has been heard.
    pub fn remote_state(&self, node: u8) -> Option<NmtState> {
        self.entries
            .iter()
            .find(|e| e.node == node)
            .and_then(|e| e.last_state)
    }

    /// Whether `node` is monitored and currently considered lost.
    pub fn is_lost(&self, node: u8) -> bool {
        self.entries
            .iter()
            .any(|e| e.node == node && e.watch == Watch::Lost)
    }

    /// Back to waiting for the first heartbeat on every entry (reset communication; the `Device`
    /// then rewrites the entries from the reloaded 1016h).
    pub fn restart(&mut self) {
        for entry in &mut self.entries {
            entry.watch = Watch::Waiting;
            entry.last_state = None;
        }
    }
}

impl Core for HeartbeatConsumer {
    type Event = ConsumerEvent;

    /// Feeds a received frame. Data frames on 701h–77Fh from monitored nodes are heartbeats;
    /// frames with bit 7 set are node guarding answers, not heartbeats, and are ignored.
    fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
        let CanId::Standard(id) = frame.id() else { return };
        if frame.is_remote() {
            return;
        }
        let Some(node) = id.as_raw().checked_sub(ERROR_CONTROL_BASE) else {
            return;
        };
        let Ok(node) = u8::try_from(node) else { return };
        for entry in self.entries.iter_mut().filter(|e| e.node == node) {
            let state = match *frame.data() {
                [byte] if byte & 0x80 != 0 => continue,
                [byte] => NmtState::from_raw(byte),
                _ => None,
            };
            let Some(state) = state else {
                self.events.push_back(ConsumerEvent::Malformed {
                    node,
                    dlc: frame.dlc(),
                });
                continue;
            };
            match entry.watch {
                Watch::Waiting => self.events.push_back(ConsumerEvent::HeartbeatStarted { node }),
                Watch::Lost => self.events.push_back(ConsumerEvent::HeartbeatResumed { node }),
                Watch::Active(_) => {}
            }
            if state == NmtState::BootUp && entry.watch != Watch::Waiting {
                self.events.push_back(ConsumerEvent::RemoteReset { node });
            }
            if entry.last_state != Some(state) {
                entry.last_state = Some(state);
                self.events.push_back(ConsumerEvent::RemoteState { node, state });
            }
            entry.watch = Watch::Active(now + millis(entry.time_ms));
        }
    }

    /// Declares lost every entry whose deadline is at or before `now`.
    fn handle_timeout(&mut self, now: Instant) {
        for entry in &mut self.entries {
            if let Watch::Active(deadline) = entry.watch
                && deadline <= now
            {
                entry.watch = Watch::Lost;
                self.events
                    .push_back(ConsumerEvent::HeartbeatLost { node: entry.node });
            }
        }
    }

    /// Always `None`: the consumer sends nothing (present for the uniform sans-IO shape).
    fn poll_transmit(&mut self) -> Option<CanFrame> {
        None
    }

    /// The next event for the `Device`.
    fn poll_event(&mut self) -> Option<Self::Event> {
        self.events.pop_front()
    }

    /// The earliest heartbeat deadline of an active entry.
    fn poll_timeout(&self) -> Option<Instant> {
        self.entries
            .iter()
            .filter_map(|e| match e.watch {
                Watch::Active(deadline) => Some(deadline),
                _ => None,
            })
            .min()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use NmtSlaveState::{Initialisation as Init, Operational as Op, PreOperational as PreOp, Stopped};
    use canopener_can::Core;
    use canopener_testkit::frames::any_frame;
    use canopener_testkit::trace::{Trace, ms};

    /// Error control of node 5, booted (pre-operational) at t = 0.
    fn booted() -> Trace<ErrorControl> {
        let mut trace = Trace::new(ErrorControl::new(NodeId::new(5).unwrap()));
        trace.core.set_state(Instant::ZERO, PreOp);
        trace
    }

    #[test]
    fn producer_period_is_exact_on_virtual_time() {
        let mut trace = booted();
        trace.core.set_producer_time(Instant::ZERO, 100);
        trace.advance(ms(350));
        assert_eq!(
            trace.sent(),
            ["100.000 705#7F", "200.000 705#7F", "300.000 705#7F"]
        );
        assert_eq!(trace.core.poll_timeout(), Some(ms(400)));
    }

    #[test]
    fn producer_set_before_boot_starts_at_boot() {
        let mut trace = Trace::new(ErrorControl::new(NodeId::new(5).unwrap()));
        trace.core.set_producer_time(Instant::ZERO, 50);
        assert_eq!(
            trace.core.poll_timeout(),
            None,
            "no heartbeat during initialisation"
        );
        trace.advance(ms(10));
        trace.core.set_state(ms(10), PreOp);
        trace.advance(ms(110));
        assert_eq!(trace.sent(), ["60.000 705#7F", "110.000 705#7F"]);
    }

    #[test]
    fn producer_state_byte_follows_every_transition() {
        let mut trace = booted();
        trace.core.set_producer_time(Instant::ZERO, 100);
        trace.advance(ms(130));
        trace.core.set_state(ms(130), Op);
        trace.advance(ms(240));
        trace.core.set_state(ms(240), Stopped);
        trace.advance(ms(300));
        trace.core.set_state(ms(300), PreOp);
        trace.advance(ms(400));
        assert_eq!(
            trace.sent(),
            [
                "100.000 705#7F",
                "130.000 705#05",
                "230.000 705#05",
                "240.000 705#04",
                "300.000 705#7F",
                "400.000 705#7F",
            ]
        );
    }

    #[test]
    fn producer_retimed_and_stopped_by_1017h() {
        let mut trace = booted();
        trace.core.set_producer_time(Instant::ZERO, 100);
        trace.advance(ms(150));
        trace.core.set_producer_time(ms(150), 20);
        trace.advance(ms(200));
        trace.core.set_producer_time(ms(200), 0);
        trace.advance(ms(1000));
        assert_eq!(
            trace.sent(),
            ["100.000 705#7F", "170.000 705#7F", "190.000 705#7F"],
            "the 200 ms heartbeat is not sent: 1017h = 0 was written first"
        );
        assert_eq!(trace.core.poll_timeout(), None);
    }

    #[test]
    fn late_driver_does_not_burst() {
        let mut ec = ErrorControl::new(NodeId::new(5).unwrap());
        ec.set_state(Instant::ZERO, PreOp);
        ec.set_producer_time(Instant::ZERO, 10);
        ec.handle_timeout(ms(55));
        assert!(ec.poll_transmit().is_some());
        assert!(ec.poll_transmit().is_none());
        assert_eq!(ec.poll_timeout(), Some(ms(65)));
    }

    #[test]
    fn reset_stops_heartbeat_until_boot() {
        let mut trace = booted();
        trace.core.set_producer_time(Instant::ZERO, 100);
        trace.advance(ms(150));
        trace.core.set_state(ms(150), Init);
        trace.advance(ms(400));
        trace.core.set_state(ms(400), PreOp);
        trace.advance(ms(500));
        assert_eq!(trace.sent(), ["100.000 705#7F", "500.000 705#7F"]);
    }

    #[test]
    fn guarding_answers_with_alternating_toggle() {
        let mut trace = booted();
        trace.rx(ms(10), "705#R1");
        trace.rx(ms(20), "705#R1");
        trace.core.set_state(ms(25), Op);
        trace.rx(ms(30), "705#R1");
        trace.rx(ms(40), "705#R");
        trace.core.set_state(ms(45), Stopped);
        trace.rx(ms(50), "705#R1");
        trace.rx(ms(60), "706#R1"); // another node's request
        trace.rx(ms(70), "705#01"); // a data frame on our identifier is not a request
        assert_eq!(
            trace.sent(),
            [
                "10.000 705#7F",
                "20.000 705#FF",
                "30.000 705#05",
                "40.000 705#85",
                "50.000 705#04"
            ]
        );
        assert!(
            trace.events().is_empty(),
            "life guarding is off: 100Ch/100Dh are 0"
        );
    }

    #[test]
    fn toggle_restarts_at_zero_after_reset_communication() {
        let mut trace = booted();
        trace.rx(ms(10), "705#R1");
        trace.core.set_state(ms(15), Init);
        trace.rx(ms(20), "705#R1"); // not answered during initialisation
        trace.core.set_state(ms(25), PreOp);
        trace.rx(ms(30), "705#R1");
        assert_eq!(trace.sent(), ["10.000 705#7F", "30.000 705#7F"]);
    }

    #[test]
    fn life_guarding_loss_and_resume() {
        let mut trace = booted();
        trace.core.set_guard_time(Instant::ZERO, 100);
        trace.core.set_life_time_factor(Instant::ZERO, 3);
        assert_eq!(
            trace.core.poll_timeout(),
            None,
            "life guarding starts with the first request"
        );
        trace.rx(ms(100), "705#R1");
        trace.rx(ms(200), "705#R1");
        trace.advance(ms(499));
        assert!(trace.events().is_empty());
        trace.advance(ms(1000));
        assert_eq!(
            trace.events(),
            ["500.000 LifeGuardingLost"],
            "exactly 300 ms after the last request"
        );
        trace.rx(ms(1200), "705#R1");
        assert_eq!(trace.events(), ["1200.000 LifeGuardingResumed"]);
        assert_eq!(
            trace.sent(),
            ["100.000 705#7F", "200.000 705#FF", "1200.000 705#7F"]
        );
        trace.advance(ms(1500));
        assert_eq!(trace.events(), ["1500.000 LifeGuardingLost"]);
    }

    #[test]
    fn life_time_change_retimes_and_zero_disables() {
        let mut trace = booted();
        trace.core.set_guard_time(Instant::ZERO, 100);
        trace.core.set_life_time_factor(Instant::ZERO, 2);
        trace.rx(ms(10), "705#R1");
        assert_eq!(trace.core.poll_timeout(), Some(ms(210)));
        trace.advance(ms(50));
        trace.core.set_guard_time(ms(50), 50);
        assert_eq!(trace.core.poll_timeout(), Some(ms(150)));
        trace.core.set_life_time_factor(ms(60), 0);
        assert_eq!(trace.core.poll_timeout(), None);
        trace.advance(ms(1000));
        assert!(trace.events().is_empty());
    }

    #[test]
    fn heartbeat_wins_over_guarding() {
        let mut trace = booted();
        trace.core.set_guard_time(Instant::ZERO, 100);
        trace.core.set_life_time_factor(Instant::ZERO, 2);
        trace.rx(ms(10), "705#R1");
        trace.core.set_producer_time(ms(20), 100);
        trace.rx(ms(30), "705#R1");
        trace.advance(ms(500));
        assert!(trace.events().is_empty(), "life guarding stopped by 1017h");
        assert_eq!(
            trace.sent(),
            [
                "10.000 705#7F",
                "120.000 705#7F",
                "220.000 705#7F",
                "320.000 705#7F",
                "420.000 705#7F"
            ]
        );
        trace.core.set_producer_time(ms(500), 0);
        trace.rx(ms(510), "705#R1");
        assert_eq!(
            trace.sent(),
            ["510.000 705#FF"],
            "guarding answers again once 1017h = 0"
        );
    }

    fn consumer(entries: &[(u8, u32)]) -> Trace<HeartbeatConsumer> {
        let mut consumer = HeartbeatConsumer::new();
        for &(sub, value) in entries {
            consumer.set_entry(sub, value).unwrap();
        }
        Trace::new(consumer)
    }

    #[test]
    fn consumer_starts_on_first_heartbeat_and_times_out_exactly() {
        let mut trace = consumer(&[(1, 0x0007_00C8)]); // node 7, 200 ms
        trace.advance(ms(1000));
        assert!(
            trace.events().is_empty(),
            "not monitored before the first heartbeat"
        );
        trace.rx(ms(1000), "707#7F");
        trace.rx(ms(1100), "707#7F");
        trace.advance(ms(1299));
        trace.rx(ms(1299), "707#05");
        trace.advance(ms(1498));
        assert!(!trace.core.is_lost(7));
        trace.advance(ms(2000));
        assert_eq!(
            trace.events(),
            [
                "1000.000 HeartbeatStarted { node: 7 }",
                "1000.000 RemoteState { node: 7, state: PreOperational }",
                "1299.000 RemoteState { node: 7, state: Operational }",
                "1499.000 HeartbeatLost { node: 7 }",
            ]
        );
        assert!(trace.core.is_lost(7));
        assert_eq!(trace.core.poll_timeout(), None, "lost once, not again");
        trace.rx(ms(2500), "707#05");
        assert_eq!(trace.events(), ["2500.000 HeartbeatResumed { node: 7 }"]);
        assert_eq!(trace.core.remote_state(7), Some(NmtState::Operational));
        trace.advance(ms(3000));
        assert_eq!(trace.events(), ["2700.000 HeartbeatLost { node: 7 }"]);
    }

    #[test]
    fn consumer_watches_several_nodes() {
        let mut trace = consumer(&[(1, 0x0007_0064), (2, 0x0008_012C)]);
        trace.rx(ms(0), "707#05");
        trace.rx(ms(0), "708#05");
        trace.rx(ms(0), "709#05"); // not monitored
        trace.events();
        trace.advance(ms(400));
        assert_eq!(
            trace.events(),
            [
                "100.000 HeartbeatLost { node: 7 }",
                "300.000 HeartbeatLost { node: 8 }"
            ]
        );
    }

    #[test]
    fn consumer_reports_remote_reset_and_ignores_malformed() {
        let mut trace = consumer(&[(1, 0x0007_0064)]);
        trace.rx(ms(0), "707#05");
        trace.rx(ms(10), "707#00");
        trace.rx(ms(20), "707#");
        trace.rx(ms(30), "707#0500");
        trace.rx(ms(40), "707#42");
        trace.rx(ms(50), "707#85"); // a node guarding answer, not a heartbeat
        trace.rx(ms(60), "707#R1");
        trace.advance(ms(200));
        assert_eq!(
            trace.events(),
            [
                "0.000 HeartbeatStarted { node: 7 }",
                "0.000 RemoteState { node: 7, state: Operational }",
                "10.000 RemoteReset { node: 7 }",
                "10.000 RemoteState { node: 7, state: BootUp }",
                "20.000 Malformed { node: 7, dlc: 0 }",
                "30.000 Malformed { node: 7, dlc: 2 }",
                "40.000 Malformed { node: 7, dlc: 1 }",
                "110.000 HeartbeatLost { node: 7 }",
            ]
        );
    }

    #[test]
    fn consumer_entry_errors_and_unused_entries() {
        let mut consumer = HeartbeatConsumer::new();
        assert_eq!(consumer.set_entry(1, 0x0007_0064), Ok(()));
        let duplicate = consumer.set_entry(2, 0x0007_00C8).unwrap_err();
        assert_eq!(
            duplicate,
            ConsumerConfigError::DuplicateNode { node: 7, other: 1 }
        );
        assert_eq!(duplicate.abort_code(), 0x0604_0043);
        assert_eq!(
            consumer.set_entry(1, 0x0007_00C8),
            Ok(()),
            "rewriting the same entry is fine"
        );
        assert_eq!(
            consumer.set_entry(2, 0x0007_0000),
            Ok(()),
            "time 0: unused, no conflict"
        );
        assert_eq!(consumer.set_entry(2, 0x0000_0064), Ok(()), "node 0: unused");
        assert_eq!(consumer.set_entry(2, 0x0080_0064), Ok(()), "node 128: unused");
        let reserved = consumer.set_entry(3, 0x0100_0064).unwrap_err();
        assert_eq!(reserved.abort_code(), 0x0609_0030);
        assert_eq!(
            consumer.set_entry(0, 0x0007_0064).unwrap_err().abort_code(),
            0x0609_0011
        );
        assert_eq!(
            consumer.set_entry(128, 0x0009_0064).unwrap_err().abort_code(),
            0x0609_0011
        );
        consumer.handle_frame(ms(0), &canopener_testkit::trace::frame("707#05"));
        assert_eq!(consumer.poll_timeout(), Some(ms(200)));
        // Clearing the entry stops monitoring.
        assert_eq!(consumer.set_entry(1, 0), Ok(()));
        assert_eq!(consumer.poll_timeout(), None);
    }

    #[test]
    fn consumer_restart_waits_for_the_first_heartbeat_again() {
        let mut trace = consumer(&[(1, 0x0007_0064)]);
        trace.rx(ms(0), "707#05");
        trace.core.restart();
        trace.advance(ms(500));
        assert_eq!(trace.events().len(), 2, "started and state only, no loss");
    }

    proptest::proptest! {
        #[test]
        fn no_frame_panics(frames in proptest::collection::vec(any_frame(), 0..50)) {
            let mut ec = ErrorControl::new(NodeId::new(5).unwrap());
            ec.set_state(Instant::ZERO, PreOp);
            ec.set_guard_time(Instant::ZERO, 10);
            ec.set_life_time_factor(Instant::ZERO, 2);
            let mut consumer = HeartbeatConsumer::new();
            consumer.set_entry(1, 0x0005_000A).unwrap();
            consumer.set_entry(2, 0x0006_000A).unwrap();
            for (i, frame) in frames.iter().enumerate() {
                let now = ms(i as u64 * 7);
                ec.handle_timeout(now);
                consumer.handle_timeout(now);
                ec.handle_frame(now, frame);
                consumer.handle_frame(now, frame);
                while ec.poll_transmit().is_some() {}
                while ec.poll_event().is_some() {}
                while consumer.poll_event().is_some() {}
            }
        }
    }
}

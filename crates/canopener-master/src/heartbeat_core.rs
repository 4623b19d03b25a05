//! Every node's NMT state and heartbeat as one core, [`HeartbeatCore`]: the [`NodeMonitor`] (heartbeat
//! consumer and node guarding, CiA 301 §7.2.8.3.2), the EMCY consumer (§7.2.7) and a report of every
//! single heartbeat (§7.2.8.3.2.2), which confirming an NMT command and counting heartbeats need;
//! and [`NodeStats`], what a watch saw of one node.

use std::collections::VecDeque;
use std::time::Duration;

use canopener_can::{CanFrame, CanId, Core, Instant};
use canopener_wire::{ERROR_CONTROL_BASE, NmtState, NodeId};

use crate::emcy_consumer::{EmcyConsumer, EmcyEvent};
use crate::error_control::{MonitorEvent, NodeMonitor};
use crate::statistics::Spread;

/// [`NodeMonitor`] as a driver core that also reports each heartbeat by itself: `MonitorEvent`
/// reports changes and intervals, but confirming an NMT command and counting heartbeats need every
/// one, with the time it arrived.
#[derive(Debug)]
pub struct HeartbeatCore {
    monitor: NodeMonitor,
    emcy: EmcyConsumer,
    heard: VecDeque<Heard>,
}

/// Something the monitor or a heartbeat told, with its receive time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Heard {
    /// When the frame arrived or the timer ran out.
    pub at: Instant,
    /// What was heard.
    pub kind: HeardKind,
}

/// What [`HeartbeatCore`] heard.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HeardKind {
    /// An event of the monitor.
    Monitor(MonitorEvent),
    /// A heartbeat carrying a known state other than boot-up (reported after the monitor's events
    /// for the same frame).
    Heartbeat {
        /// The node that sent it.
        node: NodeId,
        /// The NMT state it carried.
        state: NmtState,
    },
    /// An emergency message (or a malformed frame on an EMCY CAN-ID): a watcher wants to see why a
    /// node changed state or stopped, and devices say it with EMCY (CiA 301 §7.2.7).
    Emcy(EmcyEvent),
}

impl Heard {
    /// The node it is about.
    pub fn node(&self) -> NodeId {
        match self.kind {
            HeardKind::Monitor(event) => event.node(),
            HeardKind::Heartbeat { node, .. } => node,
            HeardKind::Emcy(event) => event.node(),
        }
    }
}

impl HeartbeatCore {
    /// The core around `monitor`, with an EMCY consumer for every node.
    pub fn new(monitor: NodeMonitor) -> HeartbeatCore {
        HeartbeatCore {
            monitor,
            emcy: EmcyConsumer::new(),
            heard: VecDeque::new(),
        }
    }

    /// The monitor, for the state of every node.
    pub fn monitor(&self) -> &NodeMonitor {
        &self.monitor
    }

    fn drain_monitor(&mut self, at: Instant) {
        while let Some(event) = self.monitor.poll_event() {
            self.heard.push_back(Heard {
                at,
                kind: HeardKind::Monitor(event),
            });
        }
    }
}

impl Core for HeartbeatCore {
    type Event = Heard;

    fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
        self.monitor.handle_frame(now, frame);
        self.drain_monitor(now);
        self.emcy.handle_frame(now, frame);
        while let Some(event) = self.emcy.poll_event() {
            self.heard.push_back(Heard {
                at: now,
                kind: HeardKind::Emcy(event),
            });
        }
        if let Some((node, state)) = heartbeat_of(frame) {
            self.heard.push_back(Heard {
                at: now,
                kind: HeardKind::Heartbeat { node, state },
            });
        }
    }

    fn handle_timeout(&mut self, now: Instant) {
        self.monitor.handle_timeout(now);
        self.drain_monitor(now);
    }

    fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.monitor.poll_transmit()
    }

    fn poll_event(&mut self) -> Option<Heard> {
        self.heard.pop_front()
    }

    fn poll_timeout(&self) -> Option<Instant> {
        self.monitor.poll_timeout()
    }
}

/// The node and state of a heartbeat frame (CiA 301 §7.2.8.3.2.2): one byte on 700h + node-ID
/// holding a state other than boot-up. Anything else is not one.
fn heartbeat_of(frame: &CanFrame) -> Option<(NodeId, NmtState)> {
    let CanId::Standard(id) = frame.id() else {
        return None;
    };
    let node = id
        .as_raw()
        .checked_sub(ERROR_CONTROL_BASE)
        .and_then(|raw| u8::try_from(raw).ok())
        .and_then(NodeId::new)?;
    if frame.is_remote() {
        return None;
    }
    let &[byte] = frame.data() else { return None };
    NmtState::from_raw(byte)
        .filter(|state| *state != NmtState::BootUp)
        .map(|state| (node, state))
}

/// What a watch saw of one node: counts, the heartbeat periods and losses.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct NodeStats {
    /// The state the monitor knows at the end.
    pub state: Option<NmtState>,
    /// Heartbeats with a state other than boot-up.
    pub heartbeats: u64,
    /// Boot-up messages.
    pub boot_ups: u64,
    /// The intervals between heartbeats the monitor measured.
    pub periods: Vec<Duration>,
    /// Heartbeat or guarding losses.
    pub losses: u64,
    /// Whether the heartbeat is lost at the end.
    pub lost_now: bool,
    /// EMCY messages (and malformed frames on the EMCY CAN-ID).
    pub emcys: u64,
}

impl NodeStats {
    /// Counts one thing heard of this node.
    pub fn record(&mut self, kind: &HeardKind) {
        match *kind {
            HeardKind::Heartbeat { .. } => self.heartbeats += 1,
            HeardKind::Monitor(MonitorEvent::BootUp { .. }) => self.boot_ups += 1,
            HeardKind::Monitor(MonitorEvent::Interval { period, .. }) => self.periods.push(period),
            HeardKind::Monitor(MonitorEvent::HeartbeatLost { .. } | MonitorEvent::GuardingLost { .. }) => {
                self.losses += 1;
            }
            HeardKind::Monitor(_) => {}
            HeardKind::Emcy(_) => self.emcys += 1,
        }
    }

    /// Min, median and max of the heartbeat periods.
    pub fn period_spread(&self) -> Option<Spread> {
        Spread::of(&self.periods)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error_control::ConsumerTime;
    use canopener_can::candump::parse_compact_frame;

    fn node(raw: u8) -> NodeId {
        NodeId::new(raw).unwrap()
    }

    fn feed(core: &mut HeartbeatCore, ms: u64, frame: &str) -> Vec<String> {
        let frame = parse_compact_frame(frame).unwrap();
        core.handle_frame(Instant::from_millis(ms), &frame);
        std::iter::from_fn(|| core.poll_event())
            .map(|heard| format!("{} {:?}", heard.at.as_micros() / 1000, heard.kind))
            .collect()
    }

    #[test]
    fn every_heartbeat_is_reported_after_the_monitor_events_of_its_frame() {
        let mut core = HeartbeatCore::new(NodeMonitor::new(ConsumerTime::Off));
        assert_eq!(
            feed(&mut core, 0, "705#00"),
            ["0 Monitor(BootUp { node: NodeId(5) })"]
        );
        assert_eq!(
            feed(&mut core, 100, "705#7F"),
            [
                "100 Monitor(StateChanged { node: NodeId(5), from: Some(BootUp), to: PreOperational })",
                "100 Heartbeat { node: NodeId(5), state: PreOperational }",
            ]
        );
        assert_eq!(
            feed(&mut core, 200, "705#7F"),
            [
                "200 Monitor(Interval { node: NodeId(5), period: 100ms })",
                "200 Heartbeat { node: NodeId(5), state: PreOperational }",
            ]
        );
        // Garbage on the error control CAN-ID is reported by the monitor and is no heartbeat.
        assert_eq!(
            feed(&mut core, 250, "705#0505"),
            ["250 Monitor(Malformed { node: NodeId(5), dlc: 2 })"]
        );
        assert_eq!(
            feed(&mut core, 260, "705#42"),
            ["260 Monitor(UnknownState { node: NodeId(5), byte: 66 })"]
        );
        assert!(feed(&mut core, 270, "705#R").is_empty());
        assert!(feed(&mut core, 280, "185#05").is_empty());
        assert!(feed(&mut core, 290, "700#05").is_empty(), "700h is no node's");
    }

    #[test]
    fn a_lost_heartbeat_is_timed_by_the_monitor() {
        let mut core = HeartbeatCore::new(NodeMonitor::new(ConsumerTime::Fixed(Duration::from_millis(150))));
        feed(&mut core, 0, "70A#05");
        assert_eq!(core.poll_timeout(), Some(Instant::from_millis(150)));
        core.handle_timeout(Instant::from_millis(150));
        let heard = core.poll_event().unwrap();
        assert_eq!(heard.at, Instant::from_millis(150));
        assert_eq!(
            heard.kind,
            HeardKind::Monitor(MonitorEvent::HeartbeatLost {
                node: node(10),
                after: Duration::from_millis(150)
            })
        );
    }

    #[test]
    fn stats_count_per_kind_and_keep_the_periods() {
        let mut five = NodeStats::default();
        for kind in [
            HeardKind::Heartbeat {
                node: node(5),
                state: NmtState::Stopped,
            },
            HeardKind::Monitor(MonitorEvent::Interval {
                node: node(5),
                period: Duration::from_millis(100),
            }),
            HeardKind::Monitor(MonitorEvent::Interval {
                node: node(5),
                period: Duration::from_millis(102),
            }),
            HeardKind::Monitor(MonitorEvent::HeartbeatLost {
                node: node(5),
                after: Duration::from_millis(150),
            }),
            HeardKind::Monitor(MonitorEvent::BootUp { node: node(5) }),
            HeardKind::Emcy(EmcyEvent::Emcy {
                node: node(5),
                code: 0x8130,
                register: 0x11,
                manufacturer: [0; 5],
                text: "Life guard error or heartbeat error",
            }),
        ] {
            five.record(&kind);
        }
        assert_eq!(
            (five.heartbeats, five.boot_ups, five.losses, five.emcys),
            (1, 1, 1, 1)
        );
        let spread = five.period_spread().unwrap();
        assert_eq!(
            (spread.min, spread.median, spread.max),
            (
                Duration::from_millis(100),
                Duration::from_millis(102),
                Duration::from_millis(102)
            )
        );
    }
}

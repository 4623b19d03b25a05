//! `canopener heartbeat watch`: the NMT state and heartbeat timing of every node, live (CiA 301
//! §7.2.8.3.2.2 heartbeat, §7.2.8.3.3 boot-up), through `NodeMonitor`, with the EMCYs the nodes send
//! (§7.2.7, `EmcyConsumer`).
//!
//! Also home of [`HeartbeatCore`], the monitor with every single heartbeat reported, which `nmt
//! --confirm` uses too, and of the node-list syntax (`1-10,20`) of `--nodes` and `lss scan --assign`.

use canopener_can::Core;
use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::io::Write;
use std::time::Duration;

use canopener_can::{CanFrame, CanId, Instant};
use canopener_master::emcy_consumer::{EmcyConsumer, EmcyEvent};
use canopener_master::error_control::{ConsumerTime, GuardingConfig, MonitorEvent, NodeMonitor};
use canopener_wire::{ERROR_CONTROL_BASE, NmtState, NodeId};
use serde_json::json;

use crate::args::OutputFormat;
use crate::error::{CliError, CliResult, stdout_error};
use crate::master::args::HeartbeatWatchArgs;
use canopener_runtime::link::{Ended, Flow, Link, drive};

use crate::master::link::open_link;
use crate::master::node_list::parse_node_list;
use crate::master::sync::Spread;

pub(crate) fn watch(args: HeartbeatWatchArgs) -> CliResult {
    let consumer = match args.consumer_time {
        Some(time) if time.is_zero() => {
            return Err(CliError::Usage(
                "--consumer-time 0 would report every node lost at once; give the longest silence \
                 to accept, e.g. `canopener heartbeat watch --consumer-time 300ms`"
                    .to_owned(),
            ));
        }
        Some(time) => ConsumerTime::Fixed(time),
        None => ConsumerTime::Learn,
    };
    let only: Option<BTreeSet<NodeId>> = args
        .nodes
        .as_deref()
        .map(|text| parse_node_list(text, "--nodes", "canopener heartbeat watch --nodes 1-10,20"))
        .transpose()?
        .map(|nodes| nodes.into_iter().collect());
    let guarded = args
        .guard
        .as_deref()
        .map(|text| {
            parse_node_list(
                text,
                "--guard",
                "canopener heartbeat watch --guard 5 --guard-time 200ms",
            )
        })
        .transpose()?
        .unwrap_or_default();
    let guarding = GuardingConfig {
        guard_time: args.guard_time,
        life_time_factor: args.life_time_factor,
    };
    let mut link = open_link(args.master.bus.spec.as_deref(), "heartbeat watch")?;
    let mut monitor = NodeMonitor::new(consumer);
    let started = link.now();
    for node in guarded {
        monitor.start_guarding(started, node, guarding).map_err(|err| {
            CliError::Usage(format!(
                "{err}; e.g. `canopener heartbeat watch --guard 5 --guard-time 200ms --life-time-factor 3`"
            ))
        })?;
    }
    let mut core = HeartbeatCore::new(monitor);
    let deadline = args.duration.map(|duration| started + duration);
    let format = args.master.format;
    let mut stats: BTreeMap<NodeId, NodeStats> = BTreeMap::new();
    let stdout = std::io::stdout();
    let ended = drive::<_, _, _, CliError>(&mut link, &mut core, deadline, |_, heard| {
        let node = heard.node();
        if only.as_ref().is_some_and(|only| !only.contains(&node)) {
            return Ok(Flow::<()>::Continue);
        }
        stats.entry(node).or_default().record(&heard.kind);
        if let Some(line) = event_line(format, heard.at - started, &heard.kind) {
            let mut out = stdout.lock();
            writeln!(out, "{line}")
                .and_then(|()| out.flush())
                .map_err(stdout_error)?;
        }
        Ok(Flow::Continue)
    })?;
    // Neither the deadline nor Ctrl-C is a failure of a watch: both end it as asked.
    let _: Result<(), Ended> = ended;
    let elapsed = link.now() - started;
    for (node, status) in core.monitor().nodes() {
        if let Some(stats) = stats.get_mut(&node) {
            stats.state = status.state;
            stats.lost_now = status.heartbeat_lost;
        }
    }
    print_summary(format, elapsed, &stats)?;
    let lost: Vec<String> = stats
        .iter()
        .filter(|(_, stats)| stats.losses > 0)
        .map(|(node, stats)| format!("node {node} ({}×)", stats.losses))
        .collect();
    if args.fail_on_loss && !lost.is_empty() {
        return Err(CliError::CheckFailed(format!(
            "heartbeat or guarding lost: {}",
            lost.join(", ")
        )));
    }
    Ok(())
}

/// [`NodeMonitor`] as a driver core that also reports each heartbeat by itself: `MonitorEvent`
/// reports changes and intervals, but confirming an NMT command and counting heartbeats need every
/// one, with the time it arrived.
#[derive(Debug)]
pub(crate) struct HeartbeatCore {
    monitor: NodeMonitor,
    emcy: EmcyConsumer,
    heard: VecDeque<Heard>,
}

/// Something the monitor or a heartbeat told, with its receive time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Heard {
    pub(crate) at: Instant,
    pub(crate) kind: HeardKind,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum HeardKind {
    /// An event of the monitor.
    Monitor(MonitorEvent),
    /// A heartbeat carrying a known state other than boot-up (reported after the monitor's events
    /// for the same frame).
    Heartbeat { node: NodeId, state: NmtState },
    /// An emergency message (or a malformed frame on an EMCY CAN-ID): a watcher wants to see why a
    /// node changed state or stopped, and devices say it with EMCY (CiA 301 §7.2.7).
    Emcy(EmcyEvent),
}

impl Heard {
    pub(crate) fn node(&self) -> NodeId {
        match self.kind {
            HeardKind::Monitor(event) => event.node(),
            HeardKind::Heartbeat { node, .. } => node,
            HeardKind::Emcy(event) => event.node(),
        }
    }
}

impl HeartbeatCore {
    pub(crate) fn new(monitor: NodeMonitor) -> HeartbeatCore {
        HeartbeatCore {
            monitor,
            emcy: EmcyConsumer::new(),
            heard: VecDeque::new(),
        }
    }

    pub(crate) fn monitor(&self) -> &NodeMonitor {
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

/// The lower-case CiA 301 name of a state, as JSON output writes it.
pub(crate) fn state_key(state: NmtState) -> &'static str {
    match state {
        NmtState::BootUp => "boot-up",
        NmtState::Stopped => "stopped",
        NmtState::Operational => "operational",
        NmtState::PreOperational => "pre-operational",
    }
}

/// What the watch saw of one node.
#[derive(Debug, Default)]
struct NodeStats {
    state: Option<NmtState>,
    heartbeats: u64,
    boot_ups: u64,
    periods: Vec<Duration>,
    losses: u64,
    lost_now: bool,
    emcys: u64,
}

impl NodeStats {
    fn record(&mut self, kind: &HeardKind) {
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
}

/// The line for one event, or `None` for what is only counted (single heartbeats and intervals).
fn event_line(format: OutputFormat, at: Duration, kind: &HeardKind) -> Option<String> {
    let event = match kind {
        HeardKind::Monitor(event) => event,
        HeardKind::Emcy(emcy) => return Some(emcy_line(format, at, emcy)),
        HeardKind::Heartbeat { .. } => return None,
    };
    if matches!(event, MonitorEvent::Interval { .. }) {
        return None;
    }
    Some(match format {
        OutputFormat::Text => format!("{:>9.3} s  {event}", at.as_secs_f64()),
        OutputFormat::Json => {
            let mut value = event_json(event);
            value["time_ms"] = json!(millis(at));
            value["node"] = json!(event.node().get());
            value.to_string()
        }
    })
}

fn emcy_line(format: OutputFormat, at: Duration, event: &EmcyEvent) -> String {
    match format {
        OutputFormat::Text => format!("{:>9.3} s  {event}", at.as_secs_f64()),
        OutputFormat::Json => {
            let mut value = match *event {
                EmcyEvent::Emcy {
                    code,
                    register,
                    manufacturer,
                    text,
                    ..
                } => json!({
                    "event": "emcy",
                    "code": format!("{code:04X}"),
                    "text": text,
                    "register": register,
                    "manufacturer": manufacturer.iter().map(|b| format!("{b:02X}")).collect::<String>(),
                    "reset": event.is_error_reset(),
                }),
                EmcyEvent::Malformed { .. } => json!({"event": "emcy_malformed", "text": event.to_string()}),
            };
            value["time_ms"] = json!(millis(at));
            value["node"] = json!(event.node().get());
            value.to_string()
        }
    }
}

fn event_json(event: &MonitorEvent) -> serde_json::Value {
    match *event {
        MonitorEvent::BootUp { .. } => json!({"event": "boot_up"}),
        MonitorEvent::StateChanged { from, to, .. } => json!({
            "event": "state",
            "from": from.map(state_key),
            "to": state_key(to),
        }),
        MonitorEvent::HeartbeatLost { after, .. } => {
            json!({"event": "lost", "silent_ms": millis(after)})
        }
        MonitorEvent::HeartbeatResumed { .. } => json!({"event": "resumed"}),
        MonitorEvent::Interval { period, .. } => json!({"event": "interval", "period_ms": millis(period)}),
        MonitorEvent::UnknownState { byte, .. } => json!({"event": "unknown_state", "byte": byte}),
        MonitorEvent::Malformed { dlc, .. } => json!({"event": "malformed", "dlc": dlc}),
        MonitorEvent::GuardingLost { .. } => json!({"event": "guarding_lost"}),
        MonitorEvent::ToggleError { .. } => json!({"event": "toggle_error"}),
        MonitorEvent::GuardingResumed { .. } => json!({"event": "guarding_resumed"}),
    }
}

fn print_summary(format: OutputFormat, elapsed: Duration, stats: &BTreeMap<NodeId, NodeStats>) -> CliResult {
    let mut out = std::io::stdout().lock();
    let text = match format {
        OutputFormat::Json => {
            let nodes: Vec<_> = stats
                .iter()
                .map(|(node, stats)| {
                    let spread = Spread::of(&stats.periods);
                    json!({
                        "node": node.get(),
                        "state": stats.state.map(state_key),
                        "lost": stats.lost_now,
                        "heartbeats": stats.heartbeats,
                        "boot_ups": stats.boot_ups,
                        "period_ms": spread.map(|spread| spread.json()),
                        "losses": stats.losses,
                        "emcys": stats.emcys,
                    })
                })
                .collect();
            json!({"event": "summary", "duration_ms": millis(elapsed), "nodes": nodes}).to_string() + "\n"
        }
        OutputFormat::Text => summary_table(elapsed, stats),
    };
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .map_err(stdout_error)
}

fn summary_table(elapsed: Duration, stats: &BTreeMap<NodeId, NodeStats>) -> String {
    let mut text = format!("\nwatched {:.1} s", elapsed.as_secs_f64());
    if stats.is_empty() {
        text.push_str(": no node sent a heartbeat, boot-up or EMCY message\n");
        return text;
    }
    text.push('\n');
    text.push_str(&format!(
        "{:>4}  {:<22}  {:>10}  {:>28}  {:>6}  {:>5}\n",
        "node", "state", "heartbeats", "period min/median/max (ms)", "losses", "EMCYs"
    ));
    for (node, stats) in stats {
        let mut state = stats
            .state
            .map_or_else(|| "unknown".to_owned(), |state| state.to_string());
        if stats.lost_now {
            state.push_str(" (lost)");
        }
        let period = Spread::of(&stats.periods).map_or_else(
            || "-".to_owned(),
            |spread| {
                format!(
                    "{:.1} / {:.1} / {:.1}",
                    millis(spread.min),
                    millis(spread.median),
                    millis(spread.max)
                )
            },
        );
        text.push_str(&format!(
            "{:>4}  {:<22}  {:>10}  {:>28}  {:>6}  {:>5}\n",
            node.get(),
            state,
            stats.heartbeats,
            period,
            stats.losses,
            stats.emcys
        ));
    }
    text
}

/// Milliseconds with microsecond resolution, for output.
pub(crate) fn millis(duration: Duration) -> f64 {
    (duration.as_micros() as f64) / 1000.0
}

#[cfg(test)]
mod tests {
    use super::*;
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
    fn events_print_as_lines_and_json_and_intervals_are_only_counted() {
        let lost = HeardKind::Monitor(MonitorEvent::HeartbeatLost {
            node: node(5),
            after: Duration::from_millis(151),
        });
        let at = Duration::from_millis(1234);
        assert_eq!(
            event_line(OutputFormat::Text, at, &lost).unwrap(),
            "    1.234 s  node 5: heartbeat lost (silent for 151 ms)"
        );
        let json: serde_json::Value =
            serde_json::from_str(&event_line(OutputFormat::Json, at, &lost).unwrap()).unwrap();
        assert_eq!(
            json,
            json!({"event": "lost", "node": 5, "silent_ms": 151.0, "time_ms": 1234.0})
        );
        let change = HeardKind::Monitor(MonitorEvent::StateChanged {
            node: node(5),
            from: Some(NmtState::Operational),
            to: NmtState::Stopped,
        });
        let json: serde_json::Value =
            serde_json::from_str(&event_line(OutputFormat::Json, at, &change).unwrap()).unwrap();
        assert_eq!(json["from"], "operational");
        assert_eq!(json["to"], "stopped");
        let interval = HeardKind::Monitor(MonitorEvent::Interval {
            node: node(5),
            period: Duration::from_millis(100),
        });
        assert_eq!(event_line(OutputFormat::Text, at, &interval), None);
        let heartbeat = HeardKind::Heartbeat {
            node: node(5),
            state: NmtState::Stopped,
        };
        assert_eq!(event_line(OutputFormat::Json, at, &heartbeat), None);
    }

    #[test]
    fn emcy_lines_decode_the_code_in_both_formats() {
        let emcy = EmcyEvent::Emcy {
            node: node(5),
            code: 0x8210,
            register: 0x11,
            manufacturer: [1, 0, 0, 0, 0],
            text: "PDO not processed due to length error",
        };
        let at = Duration::from_millis(1500);
        let text = event_line(OutputFormat::Text, at, &HeardKind::Emcy(emcy)).unwrap();
        assert!(
            text.contains("node 5: EMCY 8210h PDO not processed due to length error"),
            "{text}"
        );
        let json: serde_json::Value =
            serde_json::from_str(&event_line(OutputFormat::Json, at, &HeardKind::Emcy(emcy)).unwrap())
                .unwrap();
        assert_eq!(
            json,
            json!({"event": "emcy", "node": 5, "code": "8210", "text": "PDO not processed due to length error",
                   "register": 17, "manufacturer": "0100000000", "reset": false, "time_ms": 1500.0})
        );
    }

    #[test]
    fn the_summary_table_has_a_row_per_node() {
        let mut stats = BTreeMap::new();
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
        five.state = Some(NmtState::Stopped);
        five.lost_now = true;
        stats.insert(node(5), five);
        let table = summary_table(Duration::from_secs(2), &stats);
        let row = table
            .lines()
            .find(|line| line.trim_start().starts_with("5 "))
            .unwrap();
        assert!(row.contains("STOPPED (lost)"), "{table}");
        assert!(row.contains("100.0 / 102.0 / 102.0"), "{table}");
        let columns: Vec<&str> = row.split_whitespace().collect();
        assert_eq!(
            columns[columns.len() - 2..],
            ["1", "1"],
            "one loss, one EMCY: {table}"
        );
        assert!(summary_table(Duration::from_secs(1), &BTreeMap::new()).contains("no node sent"));
    }
}

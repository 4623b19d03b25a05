//! `canopener heartbeat watch`: the NMT state and heartbeat timing of every node, live (CiA 301
//! §7.2.8.3.2.2 heartbeat, §7.2.8.3.3 boot-up), with the EMCYs the nodes send (§7.2.7), watched by
//! `canopener_link::heartbeat_watch`; this module reads the options and prints the events and the
//! summary.

use std::collections::{BTreeMap, BTreeSet};
use std::time::Duration;

use canopener_link::heartbeat_watch::{WatchConfig, watch as watch_nodes};
use canopener_link::link::LinkError;
use canopener_master::emcy_consumer::EmcyEvent;
use canopener_master::error_control::{ConsumerTime, GuardingConfig, GuardingConfigError, MonitorEvent};
use canopener_master::heartbeat_core::{HeardKind, NodeStats};
use canopener_wire::NodeId;
use serde_json::json;

use crate::args::OutputFormat;
use crate::error::{CliError, CliResult};
use crate::grammar::parse_node_list;
use crate::master::args::HeartbeatWatchArgs;
use crate::master::link::open_link;
use crate::master::output::{millis, spread_json, state_key};
use crate::output::print_stdout;

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
    let config = WatchConfig {
        consumer,
        guarded,
        guarding: GuardingConfig {
            guard_time: args.guard_time,
            life_time_factor: args.life_time_factor,
        },
        only,
        duration: args.duration,
    };
    let mut link = open_link(args.master.bus.spec.as_deref(), "heartbeat watch")?;
    let format = args.master.format;
    let summary = watch_nodes::<_, WatchError>(&mut link, config, |at, kind| {
        if let Some(line) = event_line(format, at, kind) {
            print_stdout(&format!("{line}\n"))?;
        }
        Ok(())
    })
    .map_err(CliError::from)?;
    print_stdout(&summary_text(format, summary.elapsed, &summary.nodes))?;
    let lost: Vec<String> = summary
        .nodes
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

/// What can end a watch early: the bus, stdout, or guarding options the monitor refuses.
#[derive(Debug)]
enum WatchError {
    Cli(CliError),
    Guarding(GuardingConfigError),
}

impl From<LinkError> for WatchError {
    fn from(err: LinkError) -> WatchError {
        WatchError::Cli(err.into())
    }
}

impl From<GuardingConfigError> for WatchError {
    fn from(err: GuardingConfigError) -> WatchError {
        WatchError::Guarding(err)
    }
}

impl From<CliError> for WatchError {
    fn from(err: CliError) -> WatchError {
        WatchError::Cli(err)
    }
}

impl From<WatchError> for CliError {
    fn from(err: WatchError) -> CliError {
        match err {
            WatchError::Cli(err) => err,
            WatchError::Guarding(err) => CliError::Usage(format!(
                "{err}; e.g. `canopener heartbeat watch --guard 5 --guard-time 200ms --life-time-factor 3`"
            )),
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

fn summary_text(format: OutputFormat, elapsed: Duration, stats: &BTreeMap<NodeId, NodeStats>) -> String {
    match format {
        OutputFormat::Json => {
            let nodes: Vec<_> = stats
                .iter()
                .map(|(node, stats)| {
                    json!({
                        "node": node.get(),
                        "state": stats.state.map(state_key),
                        "lost": stats.lost_now,
                        "heartbeats": stats.heartbeats,
                        "boot_ups": stats.boot_ups,
                        "period_ms": stats.period_spread().map(|spread| spread_json(&spread)),
                        "losses": stats.losses,
                        "emcys": stats.emcys,
                    })
                })
                .collect();
            json!({"event": "summary", "duration_ms": millis(elapsed), "nodes": nodes}).to_string() + "\n"
        }
        OutputFormat::Text => summary_table(elapsed, stats),
    }
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
        let period = stats.period_spread().map_or_else(
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

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_wire::NmtState;

    fn node(raw: u8) -> NodeId {
        NodeId::new(raw).unwrap()
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

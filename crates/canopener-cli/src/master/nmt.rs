//! `canopener nmt`: one NMT module control command (CiA 301 §7.2.8.3.1), optionally confirmed by
//! the nodes' error control messages (heartbeat §7.2.8.3.2.2, boot-up §7.2.8.3.3).
//!
//! Module control is unconfirmed: a node's only answer is its next error control message. With
//! `--confirm` the command watches them through `NodeMonitor` ([`HeartbeatCore`]):
//! - a reset is confirmed by the boot-up message, start/stop/preop by a heartbeat with the new
//!   state, so those need the node's heartbeat producer (1017h);
//! - a node that sends two heartbeats with another state after the command did not follow it
//!   (one may have been under way when the command went out);
//! - the wait is `--timeout`, but a node that has sent one heartbeat with its old state and no
//!   second yet gets until its next heartbeat: many stacks send the new state at once, some only
//!   with their next periodic heartbeat, and its period (1017h, up to 65.535 s) may be longer than
//!   `--timeout`. That wait is bounded by [`NEXT_HEARTBEAT_WAIT`].
//!
//! With `all`, every node heard during the wait is confirmed or reported; the wait runs at least
//! `--timeout`, since nodes that did not answer yet cannot be known.

use std::collections::BTreeMap;
use std::io::Write;
use std::str::FromStr;
use std::time::Duration;

use canopener_can::Instant;
use canopener_master::error_control::{ConsumerTime, MonitorEvent, NodeMonitor};
use canopener_master::nmt_master::{NmtMaster, NmtTarget, command_name, expected_state};
use canopener_wire::{NmtCommand, NmtState, NodeId};
use serde_json::json;

use crate::args::OutputFormat;
use crate::error::{CliError, CliResult, stdout_error};
use crate::master::args::{NmtArgs, NmtVerb};
use crate::master::heartbeat::{Heard, HeardKind, HeartbeatCore, millis, state_key};
use canopener_runtime::link::{Ended, Flow, Link, drive};

use crate::master::link::open_link;

/// How long a node that reported its old state is given for its next heartbeat: the longest
/// producer heartbeat time 1017h can hold (UNSIGNED16 ms), and half a second for the bus.
pub(crate) const NEXT_HEARTBEAT_WAIT: Duration = Duration::from_millis(65_535 + 500);

pub(crate) fn run(args: NmtArgs) -> CliResult {
    let target = parse_target(&args.target)?;
    let command = nmt_command(args.command);
    let mut link = open_link(args.master.bus.spec.as_deref(), "nmt")?;
    let mut master = NmtMaster::new();
    let sent_at = link.now();
    master.send(sent_at, command, target);
    while let Some(frame) = master.poll_transmit() {
        link.send(&frame)?;
    }
    let format = args.master.format;
    if !args.confirm {
        return print(&unconfirmed_report(format, command, target));
    }
    let mut confirmation = Confirmation::new(command, target, sent_at, args.master.timeout);
    let mut core = HeartbeatCore::new(NodeMonitor::new(ConsumerTime::Off));
    let mut told_extension = false;
    let interrupted = loop {
        let deadline = confirmation.deadline();
        let ended = drive::<_, _, _, CliError>(&mut link, &mut core, Some(deadline), |_, heard| {
            confirmation.on(&heard);
            let moved = confirmation.deadline() != deadline;
            Ok(if confirmation.finished(heard.at) || moved {
                Flow::Done(())
            } else {
                Flow::Continue
            })
        })?;
        if matches!(ended, Err(Ended::Cancelled)) {
            break true;
        }
        let now = link.now();
        if confirmation.finished(now) {
            break false;
        }
        if now >= confirmation.base_deadline && !told_extension {
            told_extension = true;
            eprintln!(
                "{}: waiting for the next heartbeat (at most {} s; Ctrl-C to stop), since some devices report \
                 a new state only with their periodic heartbeat",
                confirmation.extension_note(),
                NEXT_HEARTBEAT_WAIT.as_secs()
            );
        }
    };
    let outcomes = confirmation.outcomes(interrupted);
    print(&confirmed_report(format, command, target, &outcomes))?;
    let failed: Vec<&Outcome> = outcomes.iter().filter(|outcome| !outcome.confirmed).collect();
    if outcomes.is_empty() {
        return Err(CliError::Device(format!(
            "no node answered {} to all nodes within {} ms: no boot-up or heartbeat was heard{}",
            command_name(command),
            args.master.timeout.as_millis(),
            hint(command, None)
        )));
    }
    match failed.as_slice() {
        [] => Ok(()),
        [one] => Err(CliError::Device(one.reason.clone().unwrap_or_default())),
        many => Err(CliError::Device(format!(
            "{} of {} nodes did not confirm {}: {}",
            many.len(),
            outcomes.len(),
            command_name(command),
            many.iter()
                .filter_map(|outcome| outcome.reason.as_deref())
                .collect::<Vec<_>>()
                .join("; ")
        ))),
    }
}

fn nmt_command(verb: NmtVerb) -> NmtCommand {
    match verb {
        NmtVerb::Start => NmtCommand::StartRemoteNode,
        NmtVerb::Stop => NmtCommand::StopRemoteNode,
        NmtVerb::Preop => NmtCommand::EnterPreOperational,
        NmtVerb::Reset => NmtCommand::ResetNode,
        NmtVerb::ResetComm => NmtCommand::ResetCommunication,
    }
}

fn parse_target(text: &str) -> CliResult<NmtTarget> {
    NmtTarget::from_str(text).map_err(|_| {
        CliError::Usage(format!(
            "{text:?} is not an NMT target: give a node-ID 1 to 127 (decimal or 0x hex) or `all`, \
             e.g. `canopener nmt start 5` or `canopener nmt preop all`"
        ))
    })
}

fn is_reset(command: NmtCommand) -> bool {
    matches!(command, NmtCommand::ResetNode | NmtCommand::ResetCommunication)
}

/// Advice for a node that did not answer, or `None` for every node.
fn hint(command: NmtCommand, node: Option<NodeId>) -> String {
    let node = node.map_or_else(|| "N".to_owned(), |node| node.to_string());
    if is_reset(command) {
        "; a device may take seconds to restart: give it longer with e.g. --timeout 5s".to_owned()
    } else {
        format!(
            "; start, stop and preop are confirmed by the node's heartbeat, so its producer heartbeat \
             time 1017h must be set, e.g. `canopener sdo write --node {node} 1017 0 100 --type u16`"
        )
    }
}

/// What a node said since the command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Progress {
    /// Heard, nothing decided: `old_heartbeats` heartbeats with another state since the command
    /// (or since its boot-up), the last reported state and when.
    Waiting {
        state: Option<NmtState>,
        old_heartbeats: u32,
        last_heard: Instant,
    },
    Confirmed {
        state: NmtState,
        boot_up: bool,
        at: Instant,
    },
    /// A second heartbeat after the command still carried `state`.
    Refused { state: NmtState },
}

/// The confirmation of one command, fed with what [`HeartbeatCore`] heard; sans IO.
#[derive(Debug)]
struct Confirmation {
    command: NmtCommand,
    target: NmtTarget,
    sent_at: Instant,
    timeout: Duration,
    base_deadline: Instant,
    nodes: BTreeMap<NodeId, Progress>,
}

/// How one node ended.
#[derive(Debug, Clone, PartialEq)]
struct Outcome {
    node: NodeId,
    confirmed: bool,
    /// The state the node reported last (pre-operational after a boot-up).
    state: Option<NmtState>,
    boot_up: bool,
    after: Option<Duration>,
    reason: Option<String>,
}

impl Confirmation {
    fn new(command: NmtCommand, target: NmtTarget, sent_at: Instant, timeout: Duration) -> Confirmation {
        Confirmation {
            command,
            target,
            sent_at,
            timeout,
            base_deadline: sent_at + timeout,
            nodes: BTreeMap::new(),
        }
    }

    fn on(&mut self, heard: &Heard) {
        let node = heard.node();
        if !self.target.addresses(node) {
            return;
        }
        let reset = is_reset(self.command);
        let expected = expected_state(self.command);
        let progress = self.nodes.entry(node).or_insert(Progress::Waiting {
            state: None,
            old_heartbeats: 0,
            last_heard: heard.at,
        });
        let Progress::Waiting { old_heartbeats, .. } = *progress else {
            return;
        };
        *progress = match heard.kind {
            HeardKind::Monitor(MonitorEvent::BootUp { .. }) if reset => Progress::Confirmed {
                state: NmtState::PreOperational,
                boot_up: true,
                at: heard.at,
            },
            // Restarted on its own: what it said before no longer counts.
            HeardKind::Monitor(MonitorEvent::BootUp { .. }) => Progress::Waiting {
                state: Some(NmtState::PreOperational),
                old_heartbeats: 0,
                last_heard: heard.at,
            },
            HeardKind::Heartbeat { state, .. } if !reset && state == expected => Progress::Confirmed {
                state,
                boot_up: false,
                at: heard.at,
            },
            HeardKind::Heartbeat { state, .. } if old_heartbeats >= 1 => Progress::Refused { state },
            HeardKind::Heartbeat { state, .. } => Progress::Waiting {
                state: Some(state),
                old_heartbeats: old_heartbeats + 1,
                last_heard: heard.at,
            },
            HeardKind::Monitor(_) | HeardKind::Emcy(_) => return,
        };
    }

    /// When the wait ends unless something decides it earlier.
    fn deadline(&self) -> Instant {
        self.nodes
            .values()
            .filter_map(|progress| match *progress {
                Progress::Waiting {
                    old_heartbeats: 1..,
                    last_heard,
                    ..
                } => Some(last_heard + NEXT_HEARTBEAT_WAIT),
                _ => None,
            })
            .fold(self.base_deadline, Instant::max)
    }

    fn finished(&self, now: Instant) -> bool {
        if now >= self.deadline() {
            return true;
        }
        let decided = self
            .nodes
            .values()
            .all(|progress| !matches!(progress, Progress::Waiting { .. }));
        match self.target {
            NmtTarget::Node(node) => decided && self.nodes.contains_key(&node),
            NmtTarget::All => decided && now >= self.base_deadline,
        }
    }

    /// The nodes still waiting for their next heartbeat, for a note on stderr.
    fn extension_note(&self) -> String {
        let waiting: Vec<String> = self
            .nodes
            .iter()
            .filter_map(|(node, progress)| match progress {
                Progress::Waiting {
                    state: Some(state),
                    old_heartbeats: 1..,
                    ..
                } => Some(format!("node {node} still reports {state}")),
                _ => None,
            })
            .collect();
        waiting.join(", ")
    }

    fn outcomes(&self, interrupted: bool) -> Vec<Outcome> {
        let name = command_name(self.command);
        let timeout_ms = self.timeout.as_millis();
        let mut outcomes: Vec<Outcome> = self
            .nodes
            .iter()
            .map(|(node, progress)| {
                let node = *node;
                match *progress {
                    Progress::Confirmed { state, boot_up, at } => Outcome {
                        node,
                        confirmed: true,
                        state: Some(state),
                        boot_up,
                        after: Some(at - self.sent_at),
                        reason: None,
                    },
                    Progress::Refused { state } => Outcome {
                        node,
                        confirmed: false,
                        state: Some(state),
                        boot_up: false,
                        after: None,
                        reason: Some(format!(
                            "node {node} did not confirm {name}: it still reports {state} in 2 heartbeats \
                             after the command"
                        )),
                    },
                    Progress::Waiting {
                        state,
                        old_heartbeats,
                        last_heard,
                    } => {
                        let why = if interrupted {
                            "interrupted before it answered".to_owned()
                        } else if old_heartbeats == 0 {
                            format!("it restarted (boot-up) but reported no state within {timeout_ms} ms")
                        } else {
                            let state = state.map_or_else(|| "nothing".to_owned(), |state| state.to_string());
                            format!(
                                "it last reported {state} and sent no further heartbeat within {:.1} s",
                                (self.deadline() - last_heard).as_secs_f64()
                            )
                        };
                        Outcome {
                            node,
                            confirmed: false,
                            state,
                            boot_up: false,
                            after: None,
                            reason: Some(format!("node {node} did not confirm {name}: {why}")),
                        }
                    }
                }
            })
            .collect();
        if let NmtTarget::Node(node) = self.target
            && !self.nodes.contains_key(&node)
        {
            let why = if interrupted {
                "interrupted before it answered".to_owned()
            } else {
                let what = if is_reset(self.command) {
                    "no boot-up message"
                } else {
                    "no heartbeat or boot-up message"
                };
                format!(
                    "{what} from it within {timeout_ms} ms{}",
                    hint(self.command, Some(node))
                )
            };
            outcomes.push(Outcome {
                node,
                confirmed: false,
                state: None,
                boot_up: false,
                after: None,
                reason: Some(format!("node {node} did not confirm {name}: {why}")),
            });
        }
        outcomes
    }
}

fn target_json(target: NmtTarget) -> serde_json::Value {
    match target {
        NmtTarget::All => json!("all"),
        NmtTarget::Node(node) => json!(node.get()),
    }
}

fn target_text(target: NmtTarget) -> String {
    match target {
        NmtTarget::All => "all nodes".to_owned(),
        NmtTarget::Node(node) => format!("node {node}"),
    }
}

fn unconfirmed_report(format: OutputFormat, command: NmtCommand, target: NmtTarget) -> String {
    match format {
        OutputFormat::Json => format!(
            "{}\n",
            json!({"command": command_name(command), "target": target_json(target), "confirmed": null})
        ),
        OutputFormat::Text => format!("sent {} to {}\n", command_name(command), target_text(target)),
    }
}

fn outcome_json(outcome: &Outcome) -> serde_json::Value {
    let mut value = json!({
        "confirmed": outcome.confirmed,
        "state": outcome.state.map(state_key),
        "boot_up": outcome.boot_up,
        "after_ms": outcome.after.map(millis),
    });
    if let Some(reason) = &outcome.reason {
        value["reason"] = json!(reason);
    }
    value
}

fn outcome_line(command: NmtCommand, outcome: &Outcome) -> String {
    match (outcome.confirmed, outcome.after) {
        (true, Some(after)) if outcome.boot_up => format!(
            "node {}: boot-up after {:.1} ms ({} confirmed), now PRE-OPERATIONAL",
            outcome.node,
            millis(after),
            command_name(command)
        ),
        (true, Some(after)) => format!(
            "node {}: {} after {:.1} ms ({} confirmed)",
            outcome.node,
            outcome.state.map_or_else(String::new, |state| state.to_string()),
            millis(after),
            command_name(command)
        ),
        _ => format!("node {}: NOT CONFIRMED", outcome.node),
    }
}

fn confirmed_report(
    format: OutputFormat,
    command: NmtCommand,
    target: NmtTarget,
    outcomes: &[Outcome],
) -> String {
    let all_confirmed = !outcomes.is_empty() && outcomes.iter().all(|outcome| outcome.confirmed);
    match (format, target) {
        (OutputFormat::Json, NmtTarget::Node(_)) => {
            let mut value = outcomes.first().map_or_else(|| json!({}), outcome_json);
            value["command"] = json!(command_name(command));
            value["target"] = target_json(target);
            format!("{value}\n")
        }
        (OutputFormat::Json, NmtTarget::All) => {
            let nodes: Vec<serde_json::Value> = outcomes
                .iter()
                .map(|outcome| {
                    let mut value = outcome_json(outcome);
                    value["node"] = json!(outcome.node.get());
                    value
                })
                .collect();
            let value = json!({
                "command": command_name(command),
                "target": "all",
                "confirmed": all_confirmed,
                "nodes": nodes,
            });
            format!("{value}\n")
        }
        (OutputFormat::Text, _) => {
            let mut text = format!("sent {} to {}\n", command_name(command), target_text(target));
            for outcome in outcomes {
                text.push_str(&outcome_line(command, outcome));
                text.push('\n');
            }
            text
        }
    }
}

fn print(text: &str) -> CliResult {
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .map_err(stdout_error)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn node(raw: u8) -> NodeId {
        NodeId::new(raw).unwrap()
    }

    fn ms(ms: u64) -> Instant {
        Instant::from_millis(ms)
    }

    fn heartbeat(at: u64, raw: u8, state: NmtState) -> Heard {
        Heard {
            at: ms(at),
            kind: HeardKind::Heartbeat {
                node: node(raw),
                state,
            },
        }
    }

    fn boot_up(at: u64, raw: u8) -> Heard {
        Heard {
            at: ms(at),
            kind: HeardKind::Monitor(MonitorEvent::BootUp { node: node(raw) }),
        }
    }

    fn confirmation(command: NmtCommand, target: NmtTarget) -> Confirmation {
        Confirmation::new(command, target, ms(0), Duration::from_millis(1000))
    }

    #[test]
    fn start_is_confirmed_by_an_operational_heartbeat_of_the_target_only() {
        let mut conf = confirmation(NmtCommand::StartRemoteNode, NmtTarget::Node(node(5)));
        conf.on(&heartbeat(2, 6, NmtState::Operational));
        assert!(!conf.finished(ms(2)), "node 6 is not the target");
        conf.on(&heartbeat(3, 5, NmtState::Operational));
        assert!(conf.finished(ms(3)));
        let outcomes = conf.outcomes(false);
        assert_eq!(outcomes.len(), 1);
        assert!(outcomes[0].confirmed);
        assert_eq!(outcomes[0].after, Some(Duration::from_millis(3)));
        let json: serde_json::Value = serde_json::from_str(&confirmed_report(
            OutputFormat::Json,
            NmtCommand::StartRemoteNode,
            NmtTarget::Node(node(5)),
            &outcomes,
        ))
        .unwrap();
        assert_eq!(
            json,
            json!({"command": "start", "target": 5, "confirmed": true, "state": "operational",
                   "boot_up": false, "after_ms": 3.0})
        );
    }

    #[test]
    fn a_heartbeat_under_way_is_forgiven_and_a_second_old_one_refuses() {
        let mut conf = confirmation(NmtCommand::StopRemoteNode, NmtTarget::Node(node(5)));
        conf.on(&heartbeat(1, 5, NmtState::Operational));
        assert!(!conf.finished(ms(1)));
        // One old heartbeat: the node gets until its next one, beyond --timeout.
        assert_eq!(conf.deadline(), ms(1) + NEXT_HEARTBEAT_WAIT);
        assert!(conf.extension_note().contains("node 5 still reports OPERATIONAL"));
        conf.on(&heartbeat(1500, 5, NmtState::Stopped));
        assert!(
            conf.finished(ms(1500)),
            "confirmed by the next periodic heartbeat"
        );
        assert!(conf.outcomes(false)[0].confirmed);

        let mut conf = confirmation(NmtCommand::StopRemoteNode, NmtTarget::Node(node(5)));
        conf.on(&heartbeat(1, 5, NmtState::Operational));
        conf.on(&heartbeat(101, 5, NmtState::Operational));
        assert!(conf.finished(ms(101)));
        let outcome = &conf.outcomes(false)[0];
        assert!(!outcome.confirmed);
        assert_eq!(outcome.state, Some(NmtState::Operational));
        assert!(
            outcome
                .reason
                .as_deref()
                .unwrap()
                .contains("still reports OPERATIONAL in 2 heartbeats"),
            "{outcome:?}"
        );
    }

    #[test]
    fn a_silent_node_times_out_with_advice() {
        let conf = confirmation(NmtCommand::StartRemoteNode, NmtTarget::Node(node(9)));
        assert!(!conf.finished(ms(999)));
        assert!(conf.finished(ms(1000)));
        let outcome = &conf.outcomes(false)[0];
        assert!(!outcome.confirmed);
        let reason = outcome.reason.as_deref().unwrap();
        assert!(
            reason.contains(
                "node 9 did not confirm start: no heartbeat or boot-up message from it within 1000 ms"
            ),
            "{reason}"
        );
        assert!(reason.contains("sdo write --node 9 1017"), "{reason}");
        let text = confirmed_report(
            OutputFormat::Text,
            NmtCommand::StartRemoteNode,
            NmtTarget::Node(node(9)),
            &conf.outcomes(false),
        );
        assert!(text.contains("node 9: NOT CONFIRMED"), "{text}");
    }

    #[test]
    fn reset_is_confirmed_by_boot_up_and_not_by_heartbeats() {
        let mut conf = confirmation(NmtCommand::ResetNode, NmtTarget::Node(node(5)));
        conf.on(&heartbeat(1, 5, NmtState::PreOperational));
        assert!(!conf.finished(ms(1)));
        conf.on(&boot_up(40, 5));
        assert!(conf.finished(ms(40)));
        let outcome = &conf.outcomes(false)[0];
        assert!(outcome.confirmed && outcome.boot_up);
        assert_eq!(outcome.state, Some(NmtState::PreOperational));
        let text = outcome_line(NmtCommand::ResetNode, outcome);
        assert_eq!(
            text,
            "node 5: boot-up after 40.0 ms (reset confirmed), now PRE-OPERATIONAL"
        );
    }

    #[test]
    fn all_waits_the_timeout_and_confirms_every_node_heard() {
        let mut conf = confirmation(NmtCommand::EnterPreOperational, NmtTarget::All);
        conf.on(&heartbeat(2, 5, NmtState::PreOperational));
        conf.on(&heartbeat(3, 7, NmtState::PreOperational));
        assert!(!conf.finished(ms(3)), "more nodes may answer");
        conf.on(&heartbeat(4, 8, NmtState::Stopped));
        conf.on(&heartbeat(5, 8, NmtState::Stopped));
        assert!(conf.finished(ms(1000)));
        let outcomes = conf.outcomes(false);
        let confirmed: Vec<(u8, bool)> = outcomes.iter().map(|o| (o.node.get(), o.confirmed)).collect();
        assert_eq!(confirmed, [(5, true), (7, true), (8, false)]);
        let json: serde_json::Value = serde_json::from_str(&confirmed_report(
            OutputFormat::Json,
            NmtCommand::EnterPreOperational,
            NmtTarget::All,
            &outcomes,
        ))
        .unwrap();
        assert_eq!(json["target"], "all");
        assert_eq!(json["confirmed"], false);
        assert_eq!(json["nodes"][1]["node"], 7);
        assert_eq!(json["nodes"][1]["state"], "pre-operational");
    }

    #[test]
    fn targets_accept_ids_and_all_and_refuse_the_rest_with_an_example() {
        assert_eq!(parse_target("5").unwrap(), NmtTarget::Node(node(5)));
        assert_eq!(parse_target("0x7f").unwrap(), NmtTarget::Node(node(127)));
        assert_eq!(parse_target("ALL").unwrap(), NmtTarget::All);
        for bad in ["200", "128", "-1", "five", ""] {
            let err = parse_target(bad).unwrap_err();
            assert!(matches!(err, CliError::Usage(_)), "{bad}");
            assert!(err.to_string().contains("e.g. `canopener nmt start 5`"), "{err}");
        }
    }

    #[test]
    fn without_confirm_the_report_says_what_was_sent() {
        assert_eq!(
            unconfirmed_report(OutputFormat::Text, NmtCommand::ResetCommunication, NmtTarget::All),
            "sent reset-comm to all nodes\n"
        );
        let json: serde_json::Value = serde_json::from_str(&unconfirmed_report(
            OutputFormat::Json,
            NmtCommand::StartRemoteNode,
            NmtTarget::Node(node(5)),
        ))
        .unwrap();
        assert_eq!(json, json!({"command": "start", "target": 5, "confirmed": null}));
    }
}

//! `canopener nmt`: one NMT module control command (CiA 301 §7.2.8.3.1), optionally confirmed by
//! the nodes' error control messages (heartbeat §7.2.8.3.2.2, boot-up §7.2.8.3.3). The rules of the
//! confirmation are `canopener_master::nmt_confirmation`'s, the wait `canopener_link::nmt_command`'s;
//! this module reads the target and prints the outcome.

use std::str::FromStr;

use canopener_link::nmt_command::{send, send_confirmed};
use canopener_master::nmt_confirmation::{NEXT_HEARTBEAT_WAIT, NodeConfirmation, Unconfirmed, is_reset};
use canopener_master::nmt_master::{NmtTarget, command_name};
use canopener_wire::{NmtCommand, NodeId};
use serde_json::json;

use crate::args::OutputFormat;
use crate::error::{CliError, CliResult};
use crate::master::args::{NmtArgs, NmtVerb};
use crate::master::link::open_link;
use crate::master::output::{millis, state_key};
use crate::output::print_stdout;

pub(crate) fn run(args: NmtArgs) -> CliResult {
    let target = parse_target(args.target())?;
    let command = nmt_command(args.command);
    let mut link = open_link(args.master.bus.spec.as_deref(), "nmt")?;
    let format = args.master.format;
    if !args.confirm {
        send(&mut link, command, target)?;
        return print_stdout(&unconfirmed_report(format, command, target));
    }
    let outcomes = send_confirmed(
        &mut link,
        command,
        target,
        args.master.timeout(),
        |confirmation| {
            eprintln!(
                "{}: waiting for the next heartbeat (at most {} s; Ctrl-C to stop), since some devices report \
             a new state only with their periodic heartbeat",
                confirmation.extension_note(),
                NEXT_HEARTBEAT_WAIT.as_secs()
            );
        },
    )?;
    print_stdout(&confirmed_report(format, command, target, &outcomes))?;
    let failed: Vec<&NodeConfirmation> = outcomes.iter().filter(|outcome| !outcome.confirmed()).collect();
    if outcomes.is_empty() {
        return Err(CliError::Device(format!(
            "no node answered {} to all nodes within {} ms: no boot-up or heartbeat was heard{}",
            command_name(command),
            args.master.timeout().as_millis(),
            hint(command, None)
        )));
    }
    match failed.as_slice() {
        [] => Ok(()),
        [one] => Err(CliError::Device(reason(command, one).unwrap_or_default())),
        many => Err(CliError::Device(format!(
            "{} of {} nodes did not confirm {}: {}",
            many.len(),
            outcomes.len(),
            command_name(command),
            many.iter()
                .filter_map(|outcome| reason(command, outcome))
                .collect::<Vec<_>>()
                .join("; ")
        ))),
    }
}

/// Why a node did not confirm, as the error says it: `node 9 did not confirm start: ...`, with
/// advice when the node was not heard at all.
fn reason(command: NmtCommand, outcome: &NodeConfirmation) -> Option<String> {
    let why = outcome.unconfirmed?;
    let advice = match why {
        Unconfirmed::NotHeard { .. } => hint(command, Some(outcome.node)),
        _ => String::new(),
    };
    Some(format!(
        "node {} did not confirm {}: {why}{advice}",
        outcome.node,
        command_name(command)
    ))
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
            "{text:?} is not an NMT target: give a node-ID 1 to 127 (decimal or hex) or `all`, \
             e.g. `canopener nmt start 5` or `canopener nmt preop all`"
        ))
    })
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

fn outcome_json(command: NmtCommand, outcome: &NodeConfirmation) -> serde_json::Value {
    let mut value = json!({
        "confirmed": outcome.confirmed(),
        "state": outcome.state.map(state_key),
        "boot_up": outcome.boot_up,
        "after_ms": outcome.after.map(millis),
    });
    if let Some(reason) = reason(command, outcome) {
        value["reason"] = json!(reason);
    }
    value
}

fn outcome_line(command: NmtCommand, outcome: &NodeConfirmation) -> String {
    match (outcome.confirmed(), outcome.after) {
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
    outcomes: &[NodeConfirmation],
) -> String {
    let all_confirmed = !outcomes.is_empty() && outcomes.iter().all(NodeConfirmation::confirmed);
    match (format, target) {
        (OutputFormat::Json, NmtTarget::Node(_)) => {
            let mut value = outcomes
                .first()
                .map_or_else(|| json!({}), |outcome| outcome_json(command, outcome));
            value["command"] = json!(command_name(command));
            value["target"] = target_json(target);
            format!("{value}\n")
        }
        (OutputFormat::Json, NmtTarget::All) => {
            let nodes: Vec<serde_json::Value> = outcomes
                .iter()
                .map(|outcome| {
                    let mut value = outcome_json(command, outcome);
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

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use canopener_can::Instant;
    use canopener_master::error_control::MonitorEvent;
    use canopener_master::heartbeat_core::{Heard, HeardKind};
    use canopener_master::nmt_confirmation::Confirmation;
    use canopener_wire::NmtState;

    use super::*;

    fn node(raw: u8) -> NodeId {
        NodeId::new(raw).unwrap()
    }

    fn heartbeat(ms: u64, raw: u8, state: NmtState) -> Heard {
        Heard {
            at: Instant::from_millis(ms),
            kind: HeardKind::Heartbeat {
                node: node(raw),
                state,
            },
        }
    }

    fn outcomes(command: NmtCommand, target: NmtTarget, heard: &[Heard]) -> Vec<NodeConfirmation> {
        let mut conf = Confirmation::new(command, target, Instant::ZERO, Duration::from_millis(1000));
        for one in heard {
            conf.on(one);
        }
        conf.outcomes(false)
    }

    #[test]
    fn a_confirmed_start_reports_state_and_time() {
        let target = NmtTarget::Node(node(5));
        let done = outcomes(
            NmtCommand::StartRemoteNode,
            target,
            &[heartbeat(3, 5, NmtState::Operational)],
        );
        let json: serde_json::Value = serde_json::from_str(&confirmed_report(
            OutputFormat::Json,
            NmtCommand::StartRemoteNode,
            target,
            &done,
        ))
        .unwrap();
        assert_eq!(
            json,
            json!({"command": "start", "target": 5, "confirmed": true, "state": "operational",
                   "boot_up": false, "after_ms": 3.0})
        );
        assert_eq!(
            outcome_line(NmtCommand::StartRemoteNode, &done[0]),
            "node 5: OPERATIONAL after 3.0 ms (start confirmed)"
        );
    }

    #[test]
    fn a_silent_node_is_not_confirmed_with_advice() {
        let target = NmtTarget::Node(node(9));
        let done = outcomes(NmtCommand::StartRemoteNode, target, &[]);
        let reason = reason(NmtCommand::StartRemoteNode, &done[0]).unwrap();
        assert!(
            reason.starts_with(
                "node 9 did not confirm start: no heartbeat or boot-up message from it within 1000 ms"
            ),
            "{reason}"
        );
        assert!(reason.contains("sdo write --node 9 1017"), "{reason}");
        let text = confirmed_report(OutputFormat::Text, NmtCommand::StartRemoteNode, target, &done);
        assert!(text.contains("node 9: NOT CONFIRMED"), "{text}");
    }

    #[test]
    fn a_reset_is_reported_with_its_boot_up() {
        let boot_up = Heard {
            at: Instant::from_millis(40),
            kind: HeardKind::Monitor(MonitorEvent::BootUp { node: node(5) }),
        };
        let done = outcomes(NmtCommand::ResetNode, NmtTarget::Node(node(5)), &[boot_up]);
        assert_eq!(
            outcome_line(NmtCommand::ResetNode, &done[0]),
            "node 5: boot-up after 40.0 ms (reset confirmed), now PRE-OPERATIONAL"
        );
        assert!(
            hint(NmtCommand::ResetNode, None).contains("--timeout 5s"),
            "resets are advised to wait longer"
        );
    }

    #[test]
    fn all_lists_every_node_heard() {
        let done = outcomes(
            NmtCommand::EnterPreOperational,
            NmtTarget::All,
            &[
                heartbeat(2, 5, NmtState::PreOperational),
                heartbeat(3, 7, NmtState::PreOperational),
                heartbeat(4, 8, NmtState::Stopped),
                heartbeat(5, 8, NmtState::Stopped),
            ],
        );
        let json: serde_json::Value = serde_json::from_str(&confirmed_report(
            OutputFormat::Json,
            NmtCommand::EnterPreOperational,
            NmtTarget::All,
            &done,
        ))
        .unwrap();
        assert_eq!(json["target"], "all");
        assert_eq!(json["confirmed"], false);
        assert_eq!(json["nodes"][1]["node"], 7);
        assert_eq!(json["nodes"][1]["state"], "pre-operational");
        assert_eq!(
            json["nodes"][2]["reason"],
            "node 8 did not confirm preop: it still reports STOPPED in 2 heartbeats after the command"
        );
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

//! NMT state and transition tests (CCT groups "State" and "Transition"): every transition of the
//! CiA 301 state diagram (§7.3.2.2.1 figure "NMT state diagram of a CANopen device"), addressed to the
//! node, to all nodes and to other nodes, and SDO and error control in stopped. The other services
//! per state are in [`super::nmt_pdo`] (PDOs) and [`super::nmt_services`] (EMCY, SYNC), what the
//! resets keep and restore in [`super::nmt_resets`]; `docs/conformance.md` maps every cell of CiA
//! 301's table of services per state to its test.

use std::time::Duration;

use canopener_wire::NmtCommand;

use crate::context::{Ctx, Reply};
use crate::finding::{Evidence, Finding, Outcome};
use crate::procedures::nmt::{
    BOOT_UP_WAIT, back_to_pre_operational, observed_state, start_heartbeat, state_name,
};
use crate::procedures::sdo::upload_text;
use crate::requirements as req;
use crate::test_def::TestDef;

const PRE_OPERATIONAL: u8 = 0x7F;
const OPERATIONAL: u8 = 0x05;
const STOPPED: u8 = 0x04;

/// How long after a boot-up message a second one counts as a duplicate.
const DUPLICATE_WAIT: Duration = Duration::from_millis(50);

/// The NMT tests.
pub fn tests() -> Vec<TestDef> {
    vec![
        TestDef {
            id: "cia301.nmt.1",
            suite: "cia301",
            group: "nmt",
            title: "Reset node and reset communication each end with one boot-up message (700h + node-ID, 00h)",
            references: &[
                req::BOOT_UP,
                req::NMT_MODULE_CONTROL,
                "CCT State 01",
                "CCT State 02",
                "CCT Transition 01",
            ],
            precondition: "always",
            tags: &["nmt"],
            run: boot_up,
        },
        TestDef {
            id: "cia301.nmt.2",
            suite: "cia301",
            group: "nmt",
            title: "Every transition between pre-operational, operational and stopped, addressed to the node",
            references: &[
                req::NMT_MODULE_CONTROL,
                "CCT State 03",
                "CCT State 04",
                "CCT Transition 02",
                "CCT Transition 03",
                "CCT Transition 04",
            ],
            precondition: "a writable 1017h or node guarding, to observe the state",
            tags: &["nmt", "heartbeat"],
            run: transitions,
        },
        TestDef {
            id: "cia301.nmt.3",
            suite: "cia301",
            group: "nmt",
            title: "The same transitions addressed to all nodes (node-ID 0)",
            references: &[req::NMT_MODULE_CONTROL],
            precondition: "a writable 1017h or node guarding, to observe the state",
            tags: &["nmt", "heartbeat"],
            run: broadcast_transitions,
        },
        TestDef {
            id: "cia301.nmt.4",
            suite: "cia301",
            group: "nmt",
            title: "Stopped: SDO not served, error control still served",
            references: &[req::NMT_STATES, "CCT State 04"],
            precondition: "a writable 1017h or node guarding",
            tags: &["nmt"],
            run: stopped_services,
        },
        TestDef {
            id: "cia301.nmt.7",
            suite: "cia301",
            group: "nmt",
            title: "NMT commands addressed to other node-IDs (all five, to two other node-IDs) are not obeyed",
            references: &[req::NMT_MODULE_CONTROL, req::BOOT_UP],
            precondition: "a writable 1017h or node guarding, to observe the state; the device alone on the bus (the commands address node-IDs it does not have)",
            tags: &["nmt", "heartbeat", "states"],
            run: other_node_ids,
        },
    ]
}

fn boot_up(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let node = u16::from(ctx.node());
    let boot = ctx.id(0x700 + node);
    for (command, name) in [
        (NmtCommand::ResetNode, "reset node"),
        (NmtCommand::ResetCommunication, "reset communication"),
    ] {
        ctx.nmt(command, false)?;
        let mut frames: Vec<_> = ctx
            .wait_for(BOOT_UP_WAIT, |f| f.id() == boot && !f.is_remote())?
            .into_iter()
            .collect();
        if !frames.is_empty() {
            // A second boot-up would follow at once; anything later is the heartbeat's business.
            frames.extend(ctx.listen(DUPLICATE_WAIT, |f| {
                f.id() == boot && !f.is_remote() && f.data() == [0]
            })?);
        }
        let boot_ups = frames.iter().filter(|l| l.frame.data() == [0]).count();
        if boot_ups != 1 {
            return Ok(Finding::fail(
                format!("{boot_ups} boot-up messages after NMT {name}"),
                Evidence {
                    request: format!("NMT {name} to node {node}"),
                    requirement: format!(
                        "{}: after initialisation the device sends one boot-up message, 700h + node-ID with 00h",
                        req::BOOT_UP
                    ),
                    answer: if frames.is_empty() {
                        format!(
                            "nothing on {:#X} within {} s",
                            0x700 + node,
                            BOOT_UP_WAIT.as_secs()
                        )
                    } else {
                        format!(
                            "{} frames on {:#X}, {boot_ups} of them boot-up",
                            frames.len(),
                            0x700 + node
                        )
                    },
                    cause: "no boot-up (or on the wrong CAN-ID) after the reset".to_owned(),
                },
            ));
        }
    }
    ctx.performed("State 01");
    ctx.performed("State 02");
    ctx.performed("Transition 01");
    Ok(Finding::pass("one boot-up after each reset"))
}

/// Observes the state after each command of `steps`; the first wrong one fails.
fn walk(ctx: &mut Ctx<'_, '_>, broadcast: bool) -> Outcome {
    let heartbeat = match start_heartbeat(ctx)? {
        Ok(started) => started,
        Err(failed) => return Ok(failed),
    };
    if !heartbeat && !ctx.model().has_guarding() {
        return Ok(Finding::not_applicable(
            "the EDS has neither a writable 1017h nor 100Ch and 100Dh: no way to observe the state",
        ));
    }
    let steps = [
        (NmtCommand::StartRemoteNode, OPERATIONAL, "start remote node"),
        (NmtCommand::StopRemoteNode, STOPPED, "stop remote node"),
        (
            NmtCommand::EnterPreOperational,
            PRE_OPERATIONAL,
            "enter pre-operational",
        ),
        (NmtCommand::StopRemoteNode, STOPPED, "stop remote node"),
        (NmtCommand::StartRemoteNode, OPERATIONAL, "start remote node"),
        (
            NmtCommand::EnterPreOperational,
            PRE_OPERATIONAL,
            "enter pre-operational",
        ),
        (NmtCommand::StartRemoteNode, OPERATIONAL, "start remote node"),
        (
            NmtCommand::StartRemoteNode,
            OPERATIONAL,
            "start remote node (again)",
        ),
        (NmtCommand::StopRemoteNode, STOPPED, "stop remote node"),
        (NmtCommand::StopRemoteNode, STOPPED, "stop remote node (again)"),
        (
            NmtCommand::EnterPreOperational,
            PRE_OPERATIONAL,
            "enter pre-operational",
        ),
        (
            NmtCommand::EnterPreOperational,
            PRE_OPERATIONAL,
            "enter pre-operational (again)",
        ),
    ];
    let target = if broadcast {
        "all nodes (0)".to_owned()
    } else {
        format!("node {}", ctx.node())
    };
    let mut from = PRE_OPERATIONAL;
    for (command, expected, name) in steps {
        ctx.nmt(command, broadcast)?;
        let state = observed_state(ctx, heartbeat)?;
        if state != Some(expected) {
            return Ok(Finding::fail(
                format!(
                    "after NMT {name} from {}: {}",
                    state_name(from),
                    state.map_or("no answer".to_owned(), state_name)
                ),
                Evidence {
                    request: format!("NMT {name} to {target} in {}", state_name(from)),
                    requirement: format!(
                        "{}: the device goes to {}",
                        req::NMT_MODULE_CONTROL,
                        state_name(expected)
                    ),
                    answer: match state {
                        Some(state) => format!(
                            "{} reported {}",
                            if heartbeat {
                                "the heartbeat"
                            } else {
                                "the guarding answer"
                            },
                            state_name(state)
                        ),
                        None => "no heartbeat or guarding answer".to_owned(),
                    },
                    cause: if broadcast {
                        "NMT commands to node-ID 0 are not applied".to_owned()
                    } else {
                        format!(
                            "the command is ignored or the {} reports a wrong state",
                            if heartbeat { "heartbeat" } else { "guarding answer" }
                        )
                    },
                },
            ));
        }
        from = expected;
    }
    Ok(Finding::pass(format!(
        "12 commands to {target}, each state as required"
    )))
}

fn transitions(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let finding = walk(ctx, false)?;
    if matches!(
        finding.verdict,
        crate::model::Verdict::Pass | crate::model::Verdict::Fail
    ) {
        for case in [
            "State 03",
            "State 04",
            "Transition 02",
            "Transition 03",
            "Transition 04",
        ] {
            ctx.performed(case);
        }
    }
    Ok(finding)
}

fn broadcast_transitions(ctx: &mut Ctx<'_, '_>) -> Outcome {
    walk(ctx, true)
}

fn stopped_services(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let heartbeat = match start_heartbeat(ctx)? {
        Ok(started) => started,
        Err(failed) => return Ok(failed),
    };
    if !heartbeat && !ctx.model().has_guarding() {
        return Ok(Finding::not_applicable(
            "the EDS has neither a writable 1017h nor 100Ch and 100Dh: no way to observe the state",
        ));
    }
    ctx.nmt(NmtCommand::StopRemoteNode, false)?;
    ctx.listen(Duration::from_millis(20), |_| false)?;
    let reply = ctx.read(0x1000, 0)?;
    let state = observed_state(ctx, heartbeat)?;
    back_to_pre_operational(ctx)?;
    if !matches!(reply, Reply::Silent) {
        return Ok(Finding::fail(
            "an SDO request was answered in stopped",
            Evidence {
                request: format!("NMT stop, then {}", upload_text((0x1000, 0))),
                requirement: format!(
                    "{}: in stopped only NMT and error control are served, no SDO",
                    req::NMT_STATES
                ),
                answer: reply.describe(),
                cause: "the SDO server runs in every state, or NMT stop is ignored".to_owned(),
            },
        ));
    }
    ctx.performed("State 04");
    Ok(match state {
        Some(STOPPED) => Finding::pass("SDO silent, error control reports stopped"),
        other => Finding::fail(
            "error control in stopped",
            Evidence {
                request: "NMT stop, then wait for the heartbeat (or send a guarding request)".to_owned(),
                requirement: format!(
                    "{}: error control is served in stopped and reports 04h",
                    req::NMT_STATES
                ),
                answer: other.map_or("no answer".to_owned(), state_name),
                cause: "error control stops in stopped, or reports a wrong state".to_owned(),
            },
        ),
    })
}

/// Two node-IDs other than `node`: the next one (an off-by-one) and the one that differs in bit 6
/// (a device comparing fewer bits; 7Fh for node 40h, whose twin would be 0, all nodes).
fn other_nodes(node: u8) -> [u8; 2] {
    let twin = node ^ 0x40;
    [node % 127 + 1, if twin == 0 { 0x7F } else { twin }]
}

fn other_node_ids(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let heartbeat = match start_heartbeat(ctx)? {
        Ok(started) => started,
        Err(failed) => return Ok(failed),
    };
    if !heartbeat && !ctx.model().has_guarding() {
        return Ok(Finding::not_applicable(
            "neither a writable 1017h nor node guarding to observe the state",
        ));
    }
    let node = ctx.node();
    let [a, b] = other_nodes(node);
    let boot = ctx.id(0x700 + u16::from(node));
    let since = ctx.mark();
    // Every command to another node-ID from a state it would change; one to the device itself
    // (start) moves it on, so that enter pre-operational and stop have something to change.
    let steps = [
        (NmtCommand::StopRemoteNode, a, PRE_OPERATIONAL),
        (NmtCommand::StartRemoteNode, b, PRE_OPERATIONAL),
        (NmtCommand::StartRemoteNode, node, OPERATIONAL),
        (NmtCommand::EnterPreOperational, a, OPERATIONAL),
        (NmtCommand::StopRemoteNode, b, OPERATIONAL),
        (NmtCommand::ResetCommunication, a, OPERATIONAL),
        (NmtCommand::ResetNode, b, OPERATIONAL),
    ];
    let mut sent = Vec::new();
    for (command, target, expected) in steps {
        ctx.send(0x000, &[command.as_raw(), target])?;
        sent.push(format!("{} to node {target}", command_name(command)));
        let state = observed_state(ctx, heartbeat)?;
        if state != Some(expected) {
            back_to_pre_operational(ctx)?;
            return Ok(Finding::fail(
                format!(
                    "after NMT {} to node {target}: {}",
                    command_name(command),
                    state.map_or("no answer".to_owned(), state_name)
                ),
                Evidence {
                    request: format!("node {node}; {}", sent.join(", ")),
                    requirement: format!(
                        "{}: a command addressed to another node-ID is not for this node, which stays {}",
                        req::NMT_MODULE_CONTROL,
                        state_name(expected)
                    ),
                    answer: state.map_or("no heartbeat or guarding answer".to_owned(), |s| {
                        format!("the device reported {}", state_name(s))
                    }),
                    cause: "the node-ID byte of NMT commands is not compared with the device's own"
                        .to_owned(),
                },
            ));
        }
    }
    // A reset may take longer than one observation: its boot-up shows it whenever it comes.
    let booted = ctx
        .received_since(since)
        .into_iter()
        .any(|l| l.frame.id() == boot && !l.frame.is_remote() && l.frame.data() == [0]);
    back_to_pre_operational(ctx)?;
    if booted {
        return Ok(Finding::fail(
            "a boot-up after NMT resets addressed to other node-IDs",
            Evidence {
                request: format!("node {node}; {}", sent.join(", ")),
                requirement: format!(
                    "{}: a reset addressed to another node-ID does not reset this node (no boot-up)",
                    req::NMT_MODULE_CONTROL
                ),
                answer: format!("a boot-up on {:03X}h", 0x700 + u16::from(node)),
                cause: "the node-ID byte of NMT commands is not compared with the device's own".to_owned(),
            },
        ));
    }
    Ok(Finding::pass(format!(
        "5 commands to nodes {a} and {b} ignored, start to node {node} obeyed"
    )))
}

/// `enter pre-operational`.
fn command_name(command: NmtCommand) -> &'static str {
    match command {
        NmtCommand::StartRemoteNode => "start remote node",
        NmtCommand::StopRemoteNode => "stop remote node",
        NmtCommand::EnterPreOperational => "enter pre-operational",
        NmtCommand::ResetNode => "reset node",
        NmtCommand::ResetCommunication => "reset communication",
    }
}

//! Confirming an NMT module control command (CiA 301 §7.2.8.3.1) by the nodes' error control
//! messages (heartbeat §7.2.8.3.2.2, boot-up §7.2.8.3.3), sans IO: [`Confirmation`] is fed what
//! [`HeartbeatCore`](crate::heartbeat_core::HeartbeatCore) heard and says when the wait is over and
//! how every node ended.
//!
//! Module control is unconfirmed: a node's only answer is its next error control message.
//! - a reset is confirmed by the boot-up message, start/stop/preop by a heartbeat with the new
//!   state, so those need the node's heartbeat producer (1017h);
//! - a node that sends two heartbeats with another state after the command did not follow it
//!   (one may have been under way when the command went out);
//! - the wait is the timeout, but a node that has sent one heartbeat with its old state and no
//!   second yet gets until its next heartbeat: many stacks send the new state at once, some only
//!   with their next periodic heartbeat, and its period (1017h, up to 65.535 s) may be longer than
//!   the timeout. That wait is bounded by [`NEXT_HEARTBEAT_WAIT`].
//!
//! With [`NmtTarget::All`], every node heard during the wait is confirmed or reported; the wait runs at
//! least the timeout, since nodes that did not answer yet cannot be known.

use std::collections::BTreeMap;
use std::time::Duration;

use canopener_can::Instant;
use canopener_wire::{NmtCommand, NmtState, NodeId};

use crate::error_control::MonitorEvent;
use crate::heartbeat_core::{Heard, HeardKind};
use crate::nmt_master::{NmtTarget, expected_state};

/// How long a node that reported its old state is given for its next heartbeat: the longest
/// producer heartbeat time 1017h can hold (UNSIGNED16 ms), and half a second for the bus.
pub const NEXT_HEARTBEAT_WAIT: Duration = Duration::from_millis(65_535 + 500);

/// Whether `command` restarts the node (confirmed by its boot-up message).
pub fn is_reset(command: NmtCommand) -> bool {
    matches!(command, NmtCommand::ResetNode | NmtCommand::ResetCommunication)
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

/// The confirmation of one command, fed with what [`HeartbeatCore`](crate::heartbeat_core::HeartbeatCore)
/// heard.
#[derive(Debug, Clone)]
pub struct Confirmation {
    command: NmtCommand,
    target: NmtTarget,
    sent_at: Instant,
    timeout: Duration,
    base_deadline: Instant,
    nodes: BTreeMap<NodeId, Progress>,
}

/// How one node ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NodeConfirmation {
    /// The node.
    pub node: NodeId,
    /// The state the node reported last (pre-operational after a boot-up).
    pub state: Option<NmtState>,
    /// Whether a boot-up confirmed a reset.
    pub boot_up: bool,
    /// From the command to the confirmation.
    pub after: Option<Duration>,
    /// Why the node did not confirm, `None` when it did.
    pub unconfirmed: Option<Unconfirmed>,
}

impl NodeConfirmation {
    /// Whether the node confirmed the command.
    pub fn confirmed(&self) -> bool {
        self.unconfirmed.is_none()
    }
}

/// Why a node did not confirm a command.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum Unconfirmed {
    /// A second heartbeat after the command still carried the old state.
    #[error("it still reports {0} in 2 heartbeats after the command")]
    StillReports(NmtState),
    /// The wait was cancelled first.
    #[error("interrupted before it answered")]
    Interrupted,
    /// It restarted on its own and then said nothing.
    #[error("it restarted (boot-up) but reported no state within {} ms", .within.as_millis())]
    NoStateAfterBootUp {
        /// The wait.
        within: Duration,
    },
    /// It reported its old state once and then fell silent.
    #[error(
        "it last reported {} and sent no further heartbeat within {:.1} s",
        .last.map_or_else(|| "nothing".to_owned(), |state| state.to_string()),
        .within.as_secs_f64()
    )]
    NoFurtherHeartbeat {
        /// The state of its last heartbeat.
        last: Option<NmtState>,
        /// From that heartbeat to the end of the wait.
        within: Duration,
    },
    /// The target node was not heard at all.
    #[error(
        "{} from it within {} ms",
        if *.reset { "no boot-up message" } else { "no heartbeat or boot-up message" },
        .within.as_millis()
    )]
    NotHeard {
        /// Whether the command was a reset (confirmed by boot-up only).
        reset: bool,
        /// The wait.
        within: Duration,
    },
}

impl Confirmation {
    /// The confirmation of `command` to `target`, sent at `sent_at`, waiting `timeout` (and longer for
    /// a node that has reported its old state once, see the module docs).
    pub fn new(command: NmtCommand, target: NmtTarget, sent_at: Instant, timeout: Duration) -> Confirmation {
        Confirmation {
            command,
            target,
            sent_at,
            timeout,
            base_deadline: sent_at + timeout,
            nodes: BTreeMap::new(),
        }
    }

    /// Takes one thing heard into account.
    pub fn on(&mut self, heard: &Heard) {
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
    pub fn deadline(&self) -> Instant {
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

    /// The wait without extensions: sent time plus timeout.
    pub fn base_deadline(&self) -> Instant {
        self.base_deadline
    }

    /// Whether the wait is over at `now`: every node decided, or the deadline reached.
    pub fn finished(&self, now: Instant) -> bool {
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
    pub fn extension_note(&self) -> String {
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

    /// How every node heard (and a target node not heard) ended; `interrupted` when the wait was
    /// cancelled.
    pub fn outcomes(&self, interrupted: bool) -> Vec<NodeConfirmation> {
        let mut outcomes: Vec<NodeConfirmation> = self
            .nodes
            .iter()
            .map(|(node, progress)| {
                let node = *node;
                match *progress {
                    Progress::Confirmed { state, boot_up, at } => NodeConfirmation {
                        node,
                        state: Some(state),
                        boot_up,
                        after: Some(at - self.sent_at),
                        unconfirmed: None,
                    },
                    Progress::Refused { state } => NodeConfirmation {
                        node,
                        state: Some(state),
                        boot_up: false,
                        after: None,
                        unconfirmed: Some(Unconfirmed::StillReports(state)),
                    },
                    Progress::Waiting {
                        state,
                        old_heartbeats,
                        last_heard,
                    } => {
                        let why = if interrupted {
                            Unconfirmed::Interrupted
                        } else if old_heartbeats == 0 {
                            Unconfirmed::NoStateAfterBootUp { within: self.timeout }
                        } else {
                            Unconfirmed::NoFurtherHeartbeat {
                                last: state,
                                within: self.deadline() - last_heard,
                            }
                        };
                        NodeConfirmation {
                            node,
                            state,
                            boot_up: false,
                            after: None,
                            unconfirmed: Some(why),
                        }
                    }
                }
            })
            .collect();
        if let NmtTarget::Node(node) = self.target
            && !self.nodes.contains_key(&node)
        {
            let why = if interrupted {
                Unconfirmed::Interrupted
            } else {
                Unconfirmed::NotHeard {
                    reset: is_reset(self.command),
                    within: self.timeout,
                }
            };
            outcomes.push(NodeConfirmation {
                node,
                state: None,
                boot_up: false,
                after: None,
                unconfirmed: Some(why),
            });
        }
        outcomes
    }
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
        assert!(outcomes[0].confirmed());
        assert_eq!(outcomes[0].after, Some(Duration::from_millis(3)));
        assert_eq!(outcomes[0].state, Some(NmtState::Operational));
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
        assert!(conf.outcomes(false)[0].confirmed());

        let mut conf = confirmation(NmtCommand::StopRemoteNode, NmtTarget::Node(node(5)));
        conf.on(&heartbeat(1, 5, NmtState::Operational));
        conf.on(&heartbeat(101, 5, NmtState::Operational));
        assert!(conf.finished(ms(101)));
        let outcome = &conf.outcomes(false)[0];
        assert_eq!(outcome.state, Some(NmtState::Operational));
        assert_eq!(
            outcome.unconfirmed.unwrap().to_string(),
            "it still reports OPERATIONAL in 2 heartbeats after the command"
        );
    }

    #[test]
    fn a_silent_node_times_out_with_advice() {
        let conf = confirmation(NmtCommand::StartRemoteNode, NmtTarget::Node(node(9)));
        assert!(!conf.finished(ms(999)));
        assert!(conf.finished(ms(1000)));
        let outcome = &conf.outcomes(false)[0];
        assert_eq!(
            outcome.unconfirmed.unwrap().to_string(),
            "no heartbeat or boot-up message from it within 1000 ms"
        );
        assert_eq!(conf.outcomes(true)[0].unconfirmed, Some(Unconfirmed::Interrupted));
    }

    #[test]
    fn reset_is_confirmed_by_boot_up_and_not_by_heartbeats() {
        let mut conf = confirmation(NmtCommand::ResetNode, NmtTarget::Node(node(5)));
        conf.on(&heartbeat(1, 5, NmtState::PreOperational));
        assert!(!conf.finished(ms(1)));
        conf.on(&boot_up(40, 5));
        assert!(conf.finished(ms(40)));
        let outcome = &conf.outcomes(false)[0];
        assert!(outcome.confirmed() && outcome.boot_up);
        assert_eq!(outcome.state, Some(NmtState::PreOperational));
        assert_eq!(outcome.after, Some(Duration::from_millis(40)));
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
        let confirmed: Vec<(u8, bool)> = outcomes.iter().map(|o| (o.node.get(), o.confirmed())).collect();
        assert_eq!(confirmed, [(5, true), (7, true), (8, false)]);
        assert_eq!(
            outcomes[2].unconfirmed,
            Some(Unconfirmed::StillReports(NmtState::Stopped))
        );
    }

    #[test]
    fn a_node_that_falls_silent_after_its_old_state_says_how_long_it_was_given() {
        let mut conf = confirmation(NmtCommand::StartRemoteNode, NmtTarget::Node(node(5)));
        conf.on(&heartbeat(10, 5, NmtState::PreOperational));
        let end = conf.deadline();
        assert!(conf.finished(end));
        assert_eq!(
            conf.outcomes(false)[0].unconfirmed.unwrap().to_string(),
            "it last reported PRE-OPERATIONAL and sent no further heartbeat within 66.0 s"
        );
    }
}

//! The NMT master: module control commands (CiA 301 §7.2.8.3.1).
//!
//! Before changing this file read CiA 301 §7.2.8.2 (NMT states) and §7.2.8.3.1 (module control).
//!
//! A module control frame is CAN-ID 000h with 2 bytes: the command specifier and the target node-ID,
//! 0 addressing every node. The protocol is unconfirmed: the only answer a node gives is its next
//! error control message (a heartbeat with the new state, or a boot-up message after a reset), which
//! [`crate::error_control::NodeMonitor`] follows. [`expected_state`] says which state to look for.
//!
//! [`NmtMaster`] queues the frames and remembers the last command per target, so a driver can tell
//! a user what it last asked of a node. [`command_name`] and [`parse_command`] give the commands
//! the short names the CLI uses (`start`, `stop`, `preop`, `reset`, `reset-comm`).

use std::collections::VecDeque;
use std::fmt;
use std::str::FromStr;

use canopener_can::{CanFrame, Instant, StandardId};
use canopener_wire::{NMT_ID, NmtCommand, NmtState, NodeId};

/// Who a module control command is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum NmtTarget {
    /// Every node (node-ID 0 in the frame).
    All,
    /// One node.
    Node(NodeId),
}

impl NmtTarget {
    /// The target byte of the frame: 0 for all nodes, else the node-ID.
    pub const fn as_raw(self) -> u8 {
        match self {
            NmtTarget::All => 0,
            NmtTarget::Node(node) => node.get(),
        }
    }

    /// The target of a frame's target byte: 0 is every node, 1 to 127 one node, anything else none.
    pub const fn from_raw(raw: u8) -> Option<NmtTarget> {
        if raw == 0 {
            return Some(NmtTarget::All);
        }
        match NodeId::new(raw) {
            Some(node) => Some(NmtTarget::Node(node)),
            None => None,
        }
    }

    /// Whether a command to this target reaches `node`.
    pub fn addresses(self, node: NodeId) -> bool {
        match self {
            NmtTarget::All => true,
            NmtTarget::Node(target) => target == node,
        }
    }
}

/// `all` or the node-ID, the form [`NmtTarget::from_str`] reads back.
impl fmt::Display for NmtTarget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            NmtTarget::All => f.write_str("all"),
            NmtTarget::Node(node) => write!(f, "{node}"),
        }
    }
}

/// Why text is not an NMT target.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "{text:?} is not an NMT target; give a node-ID 1 to 127 (decimal or 0x hex), or `all` (or 0) for every node"
)]
pub struct TargetParseError {
    /// The text given.
    pub text: String,
}

/// Reads `all`, `0` (every node), a decimal node-ID or a `0x` hexadecimal one.
impl FromStr for NmtTarget {
    type Err = TargetParseError;

    fn from_str(text: &str) -> Result<NmtTarget, TargetParseError> {
        let trimmed = text.trim();
        let error = || TargetParseError {
            text: text.to_owned(),
        };
        if trimmed.eq_ignore_ascii_case("all") {
            return Ok(NmtTarget::All);
        }
        let raw = crate::value::parse_number(trimmed)
            .and_then(|raw| u8::try_from(raw).ok())
            .ok_or_else(error)?;
        NmtTarget::from_raw(raw).ok_or_else(error)
    }
}

/// The CLI names of the commands, canonical name first for each.
const COMMAND_NAMES: [(&str, NmtCommand); 5] = [
    ("start", NmtCommand::StartRemoteNode),
    ("stop", NmtCommand::StopRemoteNode),
    ("preop", NmtCommand::EnterPreOperational),
    ("reset", NmtCommand::ResetNode),
    ("reset-comm", NmtCommand::ResetCommunication),
];

/// Other spellings users type, accepted by [`parse_command`] but never printed.
const COMMAND_ALIASES: [(&str, NmtCommand); 6] = [
    ("operational", NmtCommand::StartRemoteNode),
    ("pre-op", NmtCommand::EnterPreOperational),
    ("pre-operational", NmtCommand::EnterPreOperational),
    ("reset-node", NmtCommand::ResetNode),
    ("reset-communication", NmtCommand::ResetCommunication),
    ("reset-com", NmtCommand::ResetCommunication),
];

/// The CLI name of a command: `start`, `stop`, `preop`, `reset` or `reset-comm`.
pub fn command_name(command: NmtCommand) -> &'static str {
    match command {
        NmtCommand::StartRemoteNode => "start",
        NmtCommand::StopRemoteNode => "stop",
        NmtCommand::EnterPreOperational => "preop",
        NmtCommand::ResetNode => "reset",
        NmtCommand::ResetCommunication => "reset-comm",
    }
}

/// The CLI names in the order a help text lists them.
pub fn command_names() -> impl Iterator<Item = &'static str> {
    COMMAND_NAMES.iter().map(|(name, _)| *name)
}

/// Why text is not an NMT command name.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{text:?} is not an NMT command; use one of start, stop, preop, reset, reset-comm")]
pub struct CommandParseError {
    /// The text given.
    pub text: String,
}

/// The command named `text` (case-insensitive): a name of [`command_name`] or a long spelling such
/// as `pre-operational` or `reset-communication`.
pub fn parse_command(text: &str) -> Result<NmtCommand, CommandParseError> {
    let trimmed = text.trim();
    COMMAND_NAMES
        .iter()
        .chain(COMMAND_ALIASES.iter())
        .find(|(name, _)| name.eq_ignore_ascii_case(trimmed))
        .map(|(_, command)| *command)
        .ok_or_else(|| CommandParseError {
            text: text.to_owned(),
        })
}

/// The state a node reports in its next error control message after `command` (CiA 301 §7.2.8.2):
/// the commanded state, or [`NmtState::BootUp`] after either reset, since a reset ends with the
/// boot-up message.
pub fn expected_state(command: NmtCommand) -> NmtState {
    match command {
        NmtCommand::StartRemoteNode => NmtState::Operational,
        NmtCommand::StopRemoteNode => NmtState::Stopped,
        NmtCommand::EnterPreOperational => NmtState::PreOperational,
        NmtCommand::ResetNode | NmtCommand::ResetCommunication => NmtState::BootUp,
    }
}

/// A command this master sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SentCommand {
    /// When it was queued.
    pub at: Instant,
    /// The command.
    pub command: NmtCommand,
    /// Its target.
    pub target: NmtTarget,
}

/// The NMT master's module control (CiA 301 §7.2.8.3.1), sans IO.
///
/// Feed it commands with [`NmtMaster::send`]; drain frames with [`NmtMaster::poll_transmit`]. It has
/// no timers and consumes no frames: module control is unconfirmed.
#[derive(Debug, Clone, Default)]
pub struct NmtMaster {
    transmit: VecDeque<CanFrame>,
    last_broadcast: Option<SentCommand>,
    last_per_node: Vec<(NodeId, SentCommand)>,
}

impl NmtMaster {
    /// A master that has sent nothing.
    pub fn new() -> NmtMaster {
        NmtMaster::default()
    }

    /// Queues the module control frame `command` for `target`.
    pub fn send(&mut self, now: Instant, command: NmtCommand, target: NmtTarget) {
        let data = command.encode(target.as_raw());
        // 000h and two bytes always make a frame; the fallback only keeps this panic-free.
        if let Ok(frame) = CanFrame::new(StandardId::new(NMT_ID).unwrap_or(StandardId::ZERO), &data) {
            self.transmit.push_back(frame);
        }
        let sent = SentCommand {
            at: now,
            command,
            target,
        };
        match target {
            NmtTarget::All => {
                // A broadcast supersedes every earlier command to a single node.
                self.last_broadcast = Some(sent);
                self.last_per_node.clear();
            }
            NmtTarget::Node(node) => {
                self.last_per_node.retain(|(known, _)| *known != node);
                self.last_per_node.push((node, sent));
            }
        }
    }

    /// The last command that reached `node`, addressed to it or to all nodes.
    pub fn last_command(&self, node: NodeId) -> Option<SentCommand> {
        self.last_per_node
            .iter()
            .find(|(known, _)| *known == node)
            .map(|(_, sent)| *sent)
            .or(self.last_broadcast)
    }

    /// The next frame to send.
    pub fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.transmit.pop_front()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn node(raw: u8) -> NodeId {
        NodeId::new(raw).unwrap()
    }

    fn drain(master: &mut NmtMaster) -> Vec<String> {
        std::iter::from_fn(|| master.poll_transmit())
            .map(|frame| frame.to_string())
            .collect()
    }

    #[test]
    fn every_command_as_a_frame() {
        let mut master = NmtMaster::new();
        let t = Instant::ZERO;
        master.send(t, NmtCommand::StartRemoteNode, NmtTarget::Node(node(5)));
        master.send(t, NmtCommand::StopRemoteNode, NmtTarget::Node(node(127)));
        master.send(t, NmtCommand::EnterPreOperational, NmtTarget::All);
        master.send(t, NmtCommand::ResetNode, NmtTarget::Node(node(1)));
        master.send(t, NmtCommand::ResetCommunication, NmtTarget::All);
        assert_eq!(
            drain(&mut master),
            ["000#0105", "000#027F", "000#8000", "000#8101", "000#8200"]
        );
        assert_eq!(master.poll_transmit(), None);
    }

    #[test]
    fn last_command_per_node_and_broadcast() {
        let mut master = NmtMaster::new();
        assert_eq!(master.last_command(node(5)), None);
        master.send(
            Instant::from_millis(1),
            NmtCommand::StartRemoteNode,
            NmtTarget::Node(node(5)),
        );
        master.send(
            Instant::from_millis(2),
            NmtCommand::StopRemoteNode,
            NmtTarget::Node(node(6)),
        );
        assert_eq!(
            master.last_command(node(5)).map(|sent| (sent.at, sent.command)),
            Some((Instant::from_millis(1), NmtCommand::StartRemoteNode))
        );
        master.send(Instant::from_millis(3), NmtCommand::ResetNode, NmtTarget::All);
        assert_eq!(
            master.last_command(node(6)).map(|sent| sent.target),
            Some(NmtTarget::All)
        );
        master.send(
            Instant::from_millis(4),
            NmtCommand::StartRemoteNode,
            NmtTarget::Node(node(6)),
        );
        assert_eq!(
            master.last_command(node(6)).map(|sent| sent.command),
            Some(NmtCommand::StartRemoteNode)
        );
        assert_eq!(
            master.last_command(node(7)).map(|sent| sent.command),
            Some(NmtCommand::ResetNode)
        );
    }

    #[test]
    fn cli_names_round_trip() {
        for command in NmtCommand::ALL {
            assert_eq!(parse_command(command_name(command)), Ok(command));
        }
        assert_eq!(
            command_names().collect::<Vec<_>>(),
            ["start", "stop", "preop", "reset", "reset-comm"]
        );
        assert_eq!(
            parse_command(" Pre-Operational "),
            Ok(NmtCommand::EnterPreOperational)
        );
        assert_eq!(
            parse_command("RESET-COMMUNICATION"),
            Ok(NmtCommand::ResetCommunication)
        );
        let error = parse_command("halt").unwrap_err();
        assert_eq!(
            error.to_string(),
            "\"halt\" is not an NMT command; use one of start, stop, preop, reset, reset-comm"
        );
    }

    #[test]
    fn targets_parse_and_print() {
        assert_eq!("all".parse(), Ok(NmtTarget::All));
        assert_eq!("0".parse(), Ok(NmtTarget::All));
        assert_eq!("5".parse(), Ok(NmtTarget::Node(node(5))));
        assert_eq!("0x7F".parse(), Ok(NmtTarget::Node(node(127))));
        for bad in ["128", "-1", "", "0x80", "node5", "300"] {
            assert!(bad.parse::<NmtTarget>().is_err(), "{bad:?}");
        }
        assert_eq!(NmtTarget::All.to_string(), "all");
        assert_eq!(NmtTarget::Node(node(42)).to_string(), "42");
        assert_eq!(NmtTarget::from_raw(0), Some(NmtTarget::All));
        assert_eq!(NmtTarget::from_raw(128), None);
        assert!(NmtTarget::All.addresses(node(3)));
        assert!(!NmtTarget::Node(node(4)).addresses(node(3)));
    }

    #[test]
    fn expected_states() {
        assert_eq!(expected_state(NmtCommand::StartRemoteNode), NmtState::Operational);
        assert_eq!(expected_state(NmtCommand::StopRemoteNode), NmtState::Stopped);
        assert_eq!(
            expected_state(NmtCommand::EnterPreOperational),
            NmtState::PreOperational
        );
        assert_eq!(expected_state(NmtCommand::ResetNode), NmtState::BootUp);
        assert_eq!(expected_state(NmtCommand::ResetCommunication), NmtState::BootUp);
    }
}

//! Network management: module control commands and NMT states (CiA 301 §7.2.8).
//!
//! Module control (§7.2.8.3.1): CAN-ID 000h, 2 bytes: command specifier and target node-id
//! (0 = all nodes). Error control (§7.2.8.3.2): CAN-ID 700h + node-id, 1 byte: the NMT state, with
//! bit 7 used as the toggle bit of node guarding responses; a boot-up message is state 00h.

use std::fmt;

/// An NMT module control command specifier.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum NmtCommand {
    /// 01h: go to operational.
    StartRemoteNode,
    /// 02h: go to stopped.
    StopRemoteNode,
    /// 80h: go to pre-operational.
    EnterPreOperational,
    /// 81h: reset the application, then the communication.
    ResetNode,
    /// 82h: reset the communication parameters.
    ResetCommunication,
}

impl NmtCommand {
    /// Every command, in ascending order of specifier.
    pub const ALL: [NmtCommand; 5] = [
        NmtCommand::StartRemoteNode,
        NmtCommand::StopRemoteNode,
        NmtCommand::EnterPreOperational,
        NmtCommand::ResetNode,
        NmtCommand::ResetCommunication,
    ];

    /// The command with this specifier, or `None` for an unknown one.
    pub const fn from_raw(raw: u8) -> Option<NmtCommand> {
        match raw {
            0x01 => Some(NmtCommand::StartRemoteNode),
            0x02 => Some(NmtCommand::StopRemoteNode),
            0x80 => Some(NmtCommand::EnterPreOperational),
            0x81 => Some(NmtCommand::ResetNode),
            0x82 => Some(NmtCommand::ResetCommunication),
            _ => None,
        }
    }

    /// The command specifier.
    pub const fn as_raw(self) -> u8 {
        match self {
            NmtCommand::StartRemoteNode => 0x01,
            NmtCommand::StopRemoteNode => 0x02,
            NmtCommand::EnterPreOperational => 0x80,
            NmtCommand::ResetNode => 0x81,
            NmtCommand::ResetCommunication => 0x82,
        }
    }

    /// The CiA 301 service name, e.g. "Start Remote Node".
    pub const fn name(self) -> &'static str {
        match self {
            NmtCommand::StartRemoteNode => "Start Remote Node",
            NmtCommand::StopRemoteNode => "Stop Remote Node",
            NmtCommand::EnterPreOperational => "Enter Pre-Operational",
            NmtCommand::ResetNode => "Reset Node",
            NmtCommand::ResetCommunication => "Reset Communication",
        }
    }

    /// The 2 data bytes of a module control frame to `target` (0 = all nodes).
    pub const fn encode(self, target: u8) -> [u8; 2] {
        [self.as_raw(), target]
    }
}

impl fmt::Display for NmtCommand {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// An NMT state as reported in heartbeat and node guarding messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum NmtState {
    /// 00h: sent once, as the boot-up message, when the node enters pre-operational.
    BootUp,
    /// 04h.
    Stopped,
    /// 05h.
    Operational,
    /// 7Fh.
    PreOperational,
}

impl NmtState {
    /// The state with this code (bit 7, the guarding toggle, must already be removed).
    pub const fn from_raw(raw: u8) -> Option<NmtState> {
        match raw {
            0x00 => Some(NmtState::BootUp),
            0x04 => Some(NmtState::Stopped),
            0x05 => Some(NmtState::Operational),
            0x7F => Some(NmtState::PreOperational),
            _ => None,
        }
    }

    /// The state code.
    pub const fn as_raw(self) -> u8 {
        match self {
            NmtState::BootUp => 0x00,
            NmtState::Stopped => 0x04,
            NmtState::Operational => 0x05,
            NmtState::PreOperational => 0x7F,
        }
    }
}

/// The CiA 301 state name in capitals, e.g. `PRE-OPERATIONAL`.
impl fmt::Display for NmtState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            NmtState::BootUp => "BOOT-UP",
            NmtState::Stopped => "STOPPED",
            NmtState::Operational => "OPERATIONAL",
            NmtState::PreOperational => "PRE-OPERATIONAL",
        })
    }
}

/// Bit 7 of a node guarding response: the toggle bit, which alternates with every response
/// (CiA 301 §7.2.8.3.2.1). It is 0 in heartbeat and boot-up messages.
pub const GUARD_TOGGLE_BIT: u8 = 0x80;

/// The byte of a node guarding response: `state` with the toggle in bit 7.
pub const fn encode_guard_response(state: NmtState, toggle: bool) -> u8 {
    state.as_raw() | if toggle { GUARD_TOGGLE_BIT } else { 0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_round_trip() {
        for command in NmtCommand::ALL {
            assert_eq!(NmtCommand::from_raw(command.as_raw()), Some(command));
        }
        assert_eq!(NmtCommand::from_raw(0x03), None);
        assert_eq!(NmtCommand::StartRemoteNode.encode(5), [0x01, 0x05]);
        assert_eq!(NmtCommand::ResetCommunication.encode(0), [0x82, 0x00]);
        assert_eq!(
            NmtCommand::EnterPreOperational.to_string(),
            "Enter Pre-Operational"
        );
    }

    #[test]
    fn states_and_toggle() {
        for raw in [0x00, 0x04, 0x05, 0x7F] {
            assert_eq!(NmtState::from_raw(raw).map(NmtState::as_raw), Some(raw));
        }
        assert_eq!(NmtState::from_raw(0x01), None);
        assert_eq!(NmtState::PreOperational.to_string(), "PRE-OPERATIONAL");
        assert_eq!(encode_guard_response(NmtState::Operational, true), 0x85);
        assert_eq!(encode_guard_response(NmtState::PreOperational, false), 0x7F);
    }
}

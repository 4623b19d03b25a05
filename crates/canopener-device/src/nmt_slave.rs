//! The NMT slave state machine (CiA 301, network management: NMT state machine and NMT module
//! control services).
//!
//! A node powers up in Initialisation, sends its boot-up message (CAN-ID 700h + node-ID, one byte
//! 00h) and enters Pre-operational on its own. From then on the NMT master moves it with module
//! control commands on CAN-ID 000h (byte 0 command specifier, byte 1 node-ID, 0 = all nodes):
//!
//! | command | specifier | from | to |
//! |---|---|---|---|
//! | start remote node | 01h | pre-operational, stopped | operational |
//! | stop remote node | 02h | pre-operational, operational | stopped |
//! | enter pre-operational | 80h | operational, stopped | pre-operational |
//! | reset node | 81h | any | initialisation (reset application, then reset communication) |
//! | reset communication | 82h | any | initialisation (reset communication) |
//!
//! A reset leaves the slave in [`NmtSlaveState::Initialisation`] and reports
//! [`NmtEvent::ResetApplication`] and/or [`NmtEvent::ResetCommunication`]: the `Device` owning the
//! slave reloads the power-on values of the areas concerned (2000h–9FFFh, then 1000h–1FFFh), applies a
//! new node-ID if LSS configured one ([`NmtSlave::set_node_id`]) and then calls [`NmtSlave::boot`],
//! which sends the boot-up message. Keeping that last step explicit lets the boot-up go out only
//! after the communication objects (heartbeat time, EMCY COB-ID, ...) hold their power-on values.
//!
//! Module control frames whose DLC is not 2, or which are remote frames, are ignored (as
//! CANopenNode does) and reported as [`NmtEvent::Malformed`]; unknown command specifiers addressed
//! to this node are reported as [`NmtEvent::UnknownCommand`]. Nothing here panics on any frame.

use std::collections::VecDeque;

use canopener_can::{CanFrame, Core, Instant, StandardId};
use canopener_wire::{ERROR_CONTROL_BASE, NMT_ID, NmtCommand, NmtState, NodeId};

/// The NMT state of the local node (CiA 301, NMT state machine).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum NmtSlaveState {
    /// Initialisation: power-on or a reset in progress; nothing is sent except the boot-up message
    /// that ends it.
    Initialisation,
    /// Pre-operational: SDO, SYNC, TIME, EMCY and error control run, PDOs do not.
    PreOperational,
    /// Operational: every service runs.
    Operational,
    /// Stopped: only NMT and error control (heartbeat, node guarding) run.
    Stopped,
}

/// A communication service whose activity depends on the NMT state (CiA 301, NMT states and
/// communication objects table).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CommService {
    /// Process data objects (RPDO and TPDO).
    Pdo,
    /// Service data objects (every SDO server and client).
    Sdo,
    /// SYNC producer and consumer.
    Sync,
    /// TIME producer and consumer.
    Time,
    /// EMCY producer and consumer.
    Emcy,
    /// Error control: heartbeat production and consumption, node guarding and life guarding.
    ErrorControl,
    /// Reception of NMT module control commands.
    Nmt,
}

impl CommService {
    /// Every service, in the order of the CiA 301 table.
    pub const ALL: [CommService; 7] = [
        CommService::Pdo,
        CommService::Sdo,
        CommService::Sync,
        CommService::Time,
        CommService::Emcy,
        CommService::ErrorControl,
        CommService::Nmt,
    ];
}

impl NmtSlaveState {
    /// Whether `service` runs in this state, per the CiA 301 table of NMT states and communication
    /// objects: PDO only in Operational; SDO, SYNC, TIME and EMCY in Pre-operational and
    /// Operational; NMT and error control in Pre-operational, Operational and Stopped. In
    /// Initialisation nothing runs (the boot-up message is sent by the transition out of it).
    pub const fn is_active(self, service: CommService) -> bool {
        match self {
            NmtSlaveState::Initialisation => false,
            NmtSlaveState::Operational => true,
            NmtSlaveState::PreOperational => !matches!(service, CommService::Pdo),
            NmtSlaveState::Stopped => matches!(service, CommService::ErrorControl | CommService::Nmt),
        }
    }

    /// The state as reported in heartbeat and node guarding messages: Initialisation is reported
    /// as boot-up (00h), the others as 7Fh, 05h and 04h.
    pub const fn reported(self) -> NmtState {
        match self {
            NmtSlaveState::Initialisation => NmtState::BootUp,
            NmtSlaveState::PreOperational => NmtState::PreOperational,
            NmtSlaveState::Operational => NmtState::Operational,
            NmtSlaveState::Stopped => NmtState::Stopped,
        }
    }
}

/// Why a frame on CAN-ID 000h was not a module control command.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MalformedNmt {
    /// A data frame whose DLC is not 2.
    WrongDlc(u8),
    /// A remote frame on CAN-ID 000h.
    Remote,
}

/// What the NMT slave reports to the `Device` that owns it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum NmtEvent {
    /// The state changed. Reported for every transition, including into and out of
    /// Initialisation.
    StateChanged {
        /// The state left.
        from: NmtSlaveState,
        /// The state entered.
        to: NmtSlaveState,
    },
    /// Reset node received: reload the power-on values of 2000h–9FFFh. Always followed by
    /// [`NmtEvent::ResetCommunication`].
    ResetApplication,
    /// Reset communication (or the second half of reset node): reload the power-on values of
    /// 1000h–1FFFh, then call [`NmtSlave::boot`].
    ResetCommunication,
    /// A frame on CAN-ID 000h that is not a module control command; it was ignored.
    Malformed(MalformedNmt),
    /// A well-formed module control frame for this node (or all nodes) with an unknown command
    /// specifier; it was ignored.
    UnknownCommand {
        /// The command specifier received.
        specifier: u8,
    },
}

/// The NMT slave of one node.
#[derive(Debug, Clone)]
pub struct NmtSlave {
    node: NodeId,
    state: NmtSlaveState,
    auto_start: bool,
    transmit: VecDeque<CanFrame>,
    events: VecDeque<NmtEvent>,
}

impl NmtSlave {
    /// A slave for `node`, in Initialisation. Call [`NmtSlave::boot`] once the object dictionary
    /// holds its power-on values.
    pub fn new(node: NodeId) -> NmtSlave {
        NmtSlave {
            node,
            state: NmtSlaveState::Initialisation,
            auto_start: false,
            transmit: VecDeque::new(),
            events: VecDeque::new(),
        }
    }

    /// The current state.
    pub fn state(&self) -> NmtSlaveState {
        self.state
    }

    /// The node-ID the slave answers to and sends its boot-up message with.
    pub fn node_id(&self) -> NodeId {
        self.node
    }

    /// Sets the node-ID (for example one configured by LSS). CiA 305 applies a new node-ID on
    /// reset communication, so the `Device` calls this between [`NmtEvent::ResetCommunication`]
    /// and [`NmtSlave::boot`].
    pub fn set_node_id(&mut self, node: NodeId) {
        self.node = node;
    }

    /// NMT startup behaviour: when `true` the node enters Operational on its own right after the
    /// boot-up message (CiA 302-2 object 1F80h bit 2 = 0 on a self-starting device). The default,
    /// `false`, waits in Pre-operational for the master's start remote node.
    pub fn set_auto_start(&mut self, auto_start: bool) {
        self.auto_start = auto_start;
    }

    /// Ends Initialisation: sends the boot-up message (700h + node-ID, data 00h) and enters
    /// Pre-operational (and then Operational if [`NmtSlave::set_auto_start`] is on). Does nothing
    /// unless the slave is in Initialisation.
    pub fn boot(&mut self, _now: Instant) {
        if self.state != NmtSlaveState::Initialisation {
            return;
        }
        if let Some(frame) = self.error_control_frame(NmtState::BootUp.as_raw()) {
            self.transmit.push_back(frame);
        }
        self.enter(NmtSlaveState::PreOperational);
        if self.auto_start {
            self.enter(NmtSlaveState::Operational);
        }
    }

    /// Moves to `to` on local request (for example the 1029h error behaviour: go to
    /// pre-operational or stopped on a communication error). Entering Initialisation this way is a
    /// reset communication. Reports [`NmtEvent::StateChanged`] when the state changes.
    pub fn enter_local(&mut self, to: NmtSlaveState) {
        if to == NmtSlaveState::Initialisation {
            self.reset(false);
        } else if self.state != NmtSlaveState::Initialisation {
            self.enter(to);
        }
    }

    fn command(&mut self, command: NmtCommand) {
        match command {
            NmtCommand::StartRemoteNode => self.enter(NmtSlaveState::Operational),
            NmtCommand::StopRemoteNode => self.enter(NmtSlaveState::Stopped),
            NmtCommand::EnterPreOperational => self.enter(NmtSlaveState::PreOperational),
            NmtCommand::ResetNode => self.reset(true),
            NmtCommand::ResetCommunication => self.reset(false),
        }
    }

    fn reset(&mut self, application: bool) {
        self.enter(NmtSlaveState::Initialisation);
        // A reset abandons anything not yet sent from the previous life of the node.
        self.transmit.clear();
        if application {
            self.events.push_back(NmtEvent::ResetApplication);
        }
        self.events.push_back(NmtEvent::ResetCommunication);
    }

    fn enter(&mut self, to: NmtSlaveState) {
        let from = self.state;
        if from != to {
            self.state = to;
            self.events.push_back(NmtEvent::StateChanged { from, to });
        }
    }

    fn error_control_frame(&self, byte: u8) -> Option<CanFrame> {
        let id = StandardId::new(ERROR_CONTROL_BASE + u16::from(self.node.get()))?;
        CanFrame::new(id, &[byte]).ok()
    }
}

impl Core for NmtSlave {
    type Event = NmtEvent;

    /// Feeds a received frame. Only data frames on CAN-ID 000h (11-bit) concern the NMT slave;
    /// everything else is ignored. Commands are ignored while in Initialisation: the node has not
    /// booted yet.
    fn handle_frame(&mut self, _now: Instant, frame: &CanFrame) {
        if frame.id().is_extended() || frame.id().as_raw() != u32::from(NMT_ID) {
            return;
        }
        if frame.is_remote() {
            self.events.push_back(NmtEvent::Malformed(MalformedNmt::Remote));
            return;
        }
        let &[specifier, target] = frame.data() else {
            self.events
                .push_back(NmtEvent::Malformed(MalformedNmt::WrongDlc(frame.dlc())));
            return;
        };
        if target != 0 && target != self.node.get() {
            return;
        }
        if self.state == NmtSlaveState::Initialisation {
            return;
        }
        match NmtCommand::from_raw(specifier) {
            Some(command) => self.command(command),
            None => self.events.push_back(NmtEvent::UnknownCommand { specifier }),
        }
    }

    /// The NMT slave has no timers; present for the uniform sans-IO shape.
    fn handle_timeout(&mut self, _now: Instant) {}

    /// The next frame to send.
    fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.transmit.pop_front()
    }

    /// The next event for the `Device`.
    fn poll_event(&mut self) -> Option<Self::Event> {
        self.events.pop_front()
    }

    /// Always `None`: the NMT slave has no timers.
    fn poll_timeout(&self) -> Option<Instant> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_can::Core;
    use canopener_testkit::frames::any_frame;
    use canopener_testkit::trace::{Trace, ms};

    use NmtSlaveState::{Initialisation as Init, Operational as Op, PreOperational as PreOp, Stopped};

    fn booted(node: u8) -> Trace<NmtSlave> {
        let mut trace = Trace::new(NmtSlave::new(NodeId::new(node).unwrap()));
        trace.core.boot(Instant::ZERO);
        assert_eq!(
            trace.sent(),
            [format!("0.000 {:03X}#00", 0x700 + u16::from(node))]
        );
        assert_eq!(
            trace.events(),
            ["0.000 StateChanged { from: Initialisation, to: PreOperational }"]
        );
        trace
    }

    fn changed(at: &str, from: NmtSlaveState, to: NmtSlaveState) -> String {
        format!("{at} StateChanged {{ from: {from:?}, to: {to:?} }}")
    }

    #[test]
    fn boot_up_message_then_pre_operational() {
        let trace = booted(5);
        assert_eq!(trace.core.state(), PreOp);
        assert_eq!(trace.core.poll_timeout(), None);
    }

    #[test]
    fn nothing_is_accepted_before_boot() {
        let mut trace = Trace::new(NmtSlave::new(NodeId::new(5).unwrap()));
        trace.rx(ms(1), "000#0105");
        assert_eq!(trace.core.state(), Init);
        assert!(trace.sent().is_empty());
        assert!(trace.events().is_empty());
    }

    #[test]
    fn every_transition_of_the_state_machine() {
        let mut trace = booted(5);
        // 3: pre-operational -> operational
        trace.rx(ms(10), "000#0105");
        // 4: operational -> pre-operational
        trace.rx(ms(20), "000#8005");
        // 5: pre-operational -> stopped
        trace.rx(ms(30), "000#0205");
        // 6: stopped -> operational
        trace.rx(ms(40), "000#0105");
        // 8: operational -> stopped
        trace.rx(ms(50), "000#0205");
        // 7: stopped -> pre-operational
        trace.rx(ms(60), "000#8005");
        assert_eq!(
            trace.events(),
            [
                changed("10.000", PreOp, Op),
                changed("20.000", Op, PreOp),
                changed("30.000", PreOp, Stopped),
                changed("40.000", Stopped, Op),
                changed("50.000", Op, Stopped),
                changed("60.000", Stopped, PreOp),
            ]
        );
        assert!(
            trace.sent().is_empty(),
            "state changes send nothing by themselves"
        );
    }

    #[test]
    fn same_state_command_reports_nothing() {
        let mut trace = booted(5);
        trace.rx(ms(1), "000#8005");
        trace.rx(ms(2), "000#0105");
        trace.rx(ms(3), "000#0105");
        assert_eq!(trace.events(), [changed("2.000", PreOp, Op)]);
    }

    #[test]
    fn reset_node_from_every_state() {
        for (setup, state) in [(None, PreOp), (Some("000#0105"), Op), (Some("000#0205"), Stopped)] {
            let mut trace = booted(5);
            if let Some(setup) = setup {
                trace.rx(ms(1), setup);
            }
            trace.events();
            trace.rx(ms(10), "000#8105");
            assert_eq!(trace.core.state(), Init);
            assert_eq!(
                trace.events(),
                [
                    changed("10.000", state, Init),
                    "10.000 ResetApplication".to_string(),
                    "10.000 ResetCommunication".to_string(),
                ]
            );
            trace.advance(ms(12));
            trace.core.boot(ms(12));
            assert_eq!(trace.sent(), ["12.000 705#00"]);
            assert_eq!(trace.events(), [changed("12.000", Init, PreOp)]);
        }
    }

    #[test]
    fn reset_communication_from_every_state() {
        for (setup, state) in [(None, PreOp), (Some("000#0105"), Op), (Some("000#0205"), Stopped)] {
            let mut trace = booted(5);
            if let Some(setup) = setup {
                trace.rx(ms(1), setup);
            }
            trace.events();
            trace.rx(ms(10), "000#8205");
            assert_eq!(
                trace.events(),
                [
                    changed("10.000", state, Init),
                    "10.000 ResetCommunication".to_string()
                ]
            );
            trace.core.boot(ms(10));
            assert_eq!(trace.sent(), ["10.000 705#00"]);
        }
    }

    #[test]
    fn new_node_id_applies_at_boot_after_reset_communication() {
        let mut trace = booted(5);
        trace.rx(ms(10), "000#8205");
        trace.core.set_node_id(NodeId::new(0x22).unwrap());
        trace.advance(ms(11));
        trace.core.boot(ms(11));
        assert_eq!(trace.sent(), ["11.000 722#00"]);
        trace.rx(ms(12), "000#0105");
        assert_eq!(trace.core.state(), PreOp, "old node-ID no longer addressed");
        trace.rx(ms(13), "000#0122");
        assert_eq!(trace.core.state(), Op);
    }

    #[test]
    fn broadcast_commands_reach_every_node() {
        let mut a = booted(5);
        let mut b = booted(6);
        for text in ["000#0100", "000#0200", "000#8000"] {
            a.rx(ms(1), text);
            b.rx(ms(1), text);
            assert_eq!(a.core.state(), b.core.state());
        }
        assert_eq!(a.core.state(), PreOp);
        a.rx(ms(2), "000#8100");
        b.rx(ms(2), "000#8200");
        assert_eq!((a.core.state(), b.core.state()), (Init, Init));
    }

    #[test]
    fn commands_for_other_nodes_are_ignored() {
        let mut trace = booted(5);
        trace.rx(ms(1), "000#0106");
        trace.rx(ms(2), "000#8106");
        trace.rx(ms(3), "000#01FF");
        assert_eq!(trace.core.state(), PreOp);
        assert!(trace.events().is_empty());
    }

    #[test]
    fn malformed_frames_are_ignored_and_reported() {
        let mut trace = booted(5);
        trace.rx(ms(1), "000#01");
        trace.rx(ms(2), "000#010500");
        trace.rx(ms(3), "000#");
        trace.rx(ms(4), "000#R2");
        trace.rx(ms(5), "000#0305");
        trace.rx(ms(6), "000#0306"); // unknown command for another node: not ours
        assert_eq!(trace.core.state(), PreOp);
        assert_eq!(
            trace.events(),
            [
                "1.000 Malformed(WrongDlc(1))",
                "2.000 Malformed(WrongDlc(3))",
                "3.000 Malformed(WrongDlc(0))",
                "4.000 Malformed(Remote)",
                "5.000 UnknownCommand { specifier: 3 }",
            ]
        );
        assert!(trace.sent().is_empty());
    }

    #[test]
    fn other_identifiers_are_not_nmt() {
        let mut trace = booted(5);
        trace.rx(ms(1), "001#0105");
        trace.rx(ms(2), "00000000#0105"); // 29-bit identifier 0 is not the NMT frame
        assert_eq!(trace.core.state(), PreOp);
        assert!(trace.events().is_empty());
    }

    #[test]
    fn auto_start_enters_operational_after_boot_up() {
        let mut slave = NmtSlave::new(NodeId::new(9).unwrap());
        slave.set_auto_start(true);
        slave.boot(Instant::ZERO);
        assert_eq!(
            slave.poll_transmit().map(|f| f.to_string()),
            Some("709#00".into())
        );
        assert_eq!(slave.state(), Op);
        assert_eq!(
            [slave.poll_event(), slave.poll_event()],
            [
                Some(NmtEvent::StateChanged {
                    from: Init,
                    to: PreOp
                }),
                Some(NmtEvent::StateChanged { from: PreOp, to: Op })
            ]
        );
    }

    #[test]
    fn local_transitions() {
        let mut trace = booted(5);
        trace.core.enter_local(Op);
        trace.core.enter_local(PreOp);
        trace.core.enter_local(Init);
        assert_eq!(
            trace.events(),
            [
                changed("0.000", PreOp, Op),
                changed("0.000", Op, PreOp),
                changed("0.000", PreOp, Init),
                "0.000 ResetCommunication".to_string(),
            ]
        );
        trace.core.enter_local(Op);
        assert_eq!(trace.core.state(), Init, "only boot leaves initialisation");
    }

    #[test]
    fn services_per_state_follow_the_cia_301_table() {
        use CommService::*;
        let active = |state: NmtSlaveState| {
            CommService::ALL
                .into_iter()
                .filter(|s| state.is_active(*s))
                .collect::<Vec<_>>()
        };
        assert_eq!(active(Init), []);
        assert_eq!(active(PreOp), [Sdo, Sync, Time, Emcy, ErrorControl, Nmt]);
        assert_eq!(active(Op), [Pdo, Sdo, Sync, Time, Emcy, ErrorControl, Nmt]);
        assert_eq!(active(Stopped), [ErrorControl, Nmt]);
        assert_eq!(Stopped.reported().as_raw(), 0x04);
        assert_eq!(Op.reported().as_raw(), 0x05);
        assert_eq!(PreOp.reported().as_raw(), 0x7F);
        assert_eq!(Init.reported().as_raw(), 0x00);
    }

    proptest::proptest! {
        #[test]
        fn no_frame_panics(frames in proptest::collection::vec(any_frame(), 0..50)) {
            let mut slave = NmtSlave::new(NodeId::new(5).unwrap());
            slave.boot(Instant::ZERO);
            for frame in &frames {
                slave.handle_frame(Instant::ZERO, frame);
                if slave.state() == Init {
                    slave.boot(Instant::ZERO);
                }
            }
            while slave.poll_event().is_some() {}
            while slave.poll_transmit().is_some() {}
        }
    }
}

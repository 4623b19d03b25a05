//! The LSS slave (CiA 305, layer setting services and protocols).
//!
//! The LSS master sends on CAN-ID 7E5h, slaves answer on 7E4h; every frame has 8 data bytes, D0 being
//! the command specifier ([`canopener_wire::lss`] reads and writes them). A slave is addressed by its
//! LSS address, the 128-bit identity of 1018h:01..04 (vendor-ID, product code, revision number,
//! serial number), given as an [`LssAddress`].
//!
//! The slave is in one of two LSS states, [`LssState::Waiting`] (after power-on) or
//! [`LssState::Configuration`]. Which service runs in which state (CiA 305, LSS slave state machine):
//!
//! | service | waiting | configuration |
//! |---|---|---|
//! | switch state global (04h) | yes | yes |
//! | switch state selective (40h–43h, answer 44h) | yes | no |
//! | configure node-ID (11h), configure bit timing (13h), activate bit timing (15h), store configuration (17h) | no | yes |
//! | inquire identity (5Ah–5Dh), inquire node-ID (5Eh) | no | yes |
//! | identify remote slave (46h–4Bh, answer 4Fh), identify non-configured remote slave (4Ch, answer 50h) | yes | yes |
//! | fastscan (51h, answer 4Fh) | yes, unconfigured slaves only | no |
//!
//! Requests in the wrong state are ignored without an answer and reported as
//! [`LssEvent::Ignored`]. Frames on 7E5h whose DLC is not 8, and remote frames, are ignored (as
//! CANopenNode does) and reported as [`LssEvent::Malformed`]; unknown command specifiers as
//! [`LssEvent::UnknownCommand`]. Reserved bytes are not checked. Nothing here panics on any frame.
//!
//! Node-ID. The slave keeps an *active* node-ID (the one the node runs with, or none: FFh,
//! unconfigured) and a *pending* one. Configure node-ID changes only the pending node-ID and reports
//! [`LssEvent::NodeIdConfigured`]; per CiA 305 it takes effect at the next NMT reset communication,
//! when the `Device` calls [`LssSlave::reset_communication`] and hands the result to
//! [`NmtSlave::set_node_id`](crate::nmt_slave::NmtSlave::set_node_id). A node that was
//! unconfigured and got a node-ID asks for that reset itself ([`LssEvent::ResetCommunication`]) when
//! the master switches it back to waiting, as CANopenNode does (reference §7.3).
//!
//! Bit timing. Configure bit timing keeps a pending bit rate (table selector 0, the CiA 305 table;
//! other tables and unsupported indices are refused with error code 1). Activate bit timing is
//! unconfirmed: the slave stays silent for the switch delay, switches, and stays silent for the
//! switch delay again before anything may be sent (CiA 305, activate bit timing parameters). The
//! slave reports the three moments as [`LssEvent::BitTimingActivate`] (silence starts),
//! [`LssEvent::SwitchBitRate`] (switch now) and [`LssEvent::BitTimingSilenceEnded`];
//! [`LssSlave::is_silent`] tells the `Device` to hold back every other core's frames meanwhile.
//!
//! Store configuration hands the pending node-ID and bit rate to an [`LssStorage`]: the `Device`'s
//! default keeps them in memory and starts with them again after NMT reset node (its power cycle),
//! the simulator's keeps them in its state file; `()` stores nothing and answers error code 1,
//! "storing not supported", for a slave without storage.

use std::collections::VecDeque;
use std::time::Duration;

use canopener_can::{CanFrame, Core, Instant, StandardId};
use canopener_od::{DynamicOd, ObjectKey};
use canopener_wire::lss::{FASTSCAN_RESET, UNCONFIGURED_NODE_ID};
use canopener_wire::{
    IdentifyField, LSS_MASTER_TO_SLAVE_ID, LSS_SLAVE_TO_MASTER_ID, LssAddress, LssAddressPart, LssError,
    LssRequest, LssResponse, NodeId,
};

/// Why [`lss_address_from_od`] could not read the LSS address.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum LssAddressError {
    /// The object dictionary has no 1018h:01 (vendor-ID).
    #[error("the object dictionary has no 1018h:01 (vendor-ID), so the device has no LSS address")]
    NoVendorId,
    /// A sub-index of 1018h does not hold 4 bytes.
    #[error("1018h:{sub:02X} holds {len} bytes, not the 4 of an UNSIGNED32")]
    NotUnsigned32 {
        /// The sub-index.
        sub: u8,
        /// Its length in bytes.
        len: usize,
    },
}

/// Reads the LSS address 1018h:01..04 from `od`. The vendor-ID is required; a missing product code,
/// revision number or serial number (CiA 301 makes them optional) counts as 0.
pub fn lss_address_from_od(od: &DynamicOd) -> Result<LssAddress, LssAddressError> {
    let read = |sub: u8| -> Result<Option<u32>, LssAddressError> {
        let Some(entry) = od.get(ObjectKey::new(0x1018, sub)) else {
            return Ok(None);
        };
        let bytes = <[u8; 4]>::try_from(entry.value()).map_err(|_| LssAddressError::NotUnsigned32 {
            sub,
            len: entry.value().len(),
        })?;
        Ok(Some(u32::from_le_bytes(bytes)))
    };
    Ok(LssAddress {
        vendor_id: read(1)?.ok_or(LssAddressError::NoVendorId)?,
        product_code: read(2)?.unwrap_or(0),
        revision_number: read(3)?.unwrap_or(0),
        serial_number: read(4)?.unwrap_or(0),
    })
}

/// The LSS state of the slave (CiA 305, LSS slave state machine).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LssState {
    /// LSS waiting: the state after power-on; only switch, identify and fastscan services run.
    Waiting,
    /// LSS configuration: node-ID and bit timing can be configured and the identity inquired.
    Configuration,
}

/// An entry of a bit timing table (CiA 305, configure bit timing parameters).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct BitTiming {
    /// The table selector: 0 is the CiA 305 table.
    pub table: u8,
    /// The index in the table, see [`canopener_wire::bit_timing_text`].
    pub index: u8,
}

/// The table 0 indices a slave accepts by default: 1000, 800, 500, 250, 125, 50, 20 and 10 kbit/s.
///
/// Choice where sources disagree: index 5 (formerly 100 kbit/s) is refused, as CANopenNode and lely
/// do and as the reference advises for CCT conformance; index 9 (automatic bit rate detection) is a
/// hardware capability a simulated device does not claim. [`LssSlave::with_supported_bit_timings`]
/// changes the set.
pub const DEFAULT_BIT_TIMINGS: [u8; 8] = [0, 1, 2, 3, 4, 6, 7, 8];

/// Why store configuration failed; [`LssStoreError::error_code`] is what the slave answers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error)]
pub enum LssStoreError {
    /// Error code 1: the device cannot store its LSS configuration.
    #[error("storing the LSS configuration is not supported")]
    NotSupported,
    /// Error code 2: the storage medium could not be accessed.
    #[error("storage media access error")]
    MediaAccess,
    /// Error code FFh with an implementation-specific error in D2.
    #[error("implementation-specific store error {0:#04X}")]
    Specific(u8),
}

impl LssStoreError {
    /// The error code (D1) and implementation-specific error (D2) of the store configuration answer.
    pub fn error_code(&self) -> (u8, u8) {
        match *self {
            LssStoreError::NotSupported => (1, 0),
            LssStoreError::MediaAccess => (2, 0),
            LssStoreError::Specific(spec) => (0xFF, spec),
        }
    }
}

/// What store configuration (17h) saved: the node-ID and bit rate a device starts with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct StoredConfiguration {
    /// The node-ID (`None` = unconfigured, FFh).
    pub node_id: Option<NodeId>,
    /// The bit rate, if one was configured or known.
    pub bit_timing: Option<BitTiming>,
}

/// Where store configuration (17h) puts the pending LSS configuration; the `Device` holds one (in
/// memory by default, in a file for the simulated device). `()` supports no storing.
pub trait LssStorage {
    /// Stores the pending node-ID (`None` = unconfigured, FFh) and the pending bit rate (`None`
    /// when none was ever configured or known), to be used at the next power-on.
    fn store(&mut self, node_id: Option<NodeId>, bit_timing: Option<BitTiming>) -> Result<(), LssStoreError>;

    /// What was stored last, which the next power-on (and NMT reset node, a device's software power
    /// cycle) makes pending again; `None` while nothing was stored.
    fn stored(&self) -> Option<StoredConfiguration> {
        None
    }
}

impl LssStorage for () {
    fn store(
        &mut self,
        _node_id: Option<NodeId>,
        _bit_timing: Option<BitTiming>,
    ) -> Result<(), LssStoreError> {
        Err(LssStoreError::NotSupported)
    }
}

/// Why a frame on CAN-ID 7E5h was not an LSS request.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MalformedLss {
    /// A data frame whose DLC is not 8.
    WrongDlc(u8),
    /// A remote frame on CAN-ID 7E5h.
    Remote,
}

/// Why a well-formed LSS request was ignored without an answer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum IgnoredReason {
    /// The service runs only in LSS configuration state.
    NotInConfiguration,
    /// The service runs only in LSS waiting state.
    NotInWaiting,
    /// Switch state global with a mode other than 0 (waiting) or 1 (configuration).
    InvalidMode(u8),
    /// Fastscan with BitChecked above 31 (and not 80h), or LSSSub or LSSNext above 3.
    InvalidFastscan,
    /// Fastscan from a slave with an active node-ID: only unconfigured slaves take part.
    Configured,
    /// The last part of switch state selective (43h) or identify remote slave (4Bh) came without
    /// all the earlier parts.
    Incomplete,
    /// Activate bit timing without a pending bit rate (none configured, none known).
    NoPendingBitTiming,
    /// A request during the silence of a bit rate switch.
    Silent,
}

/// What [`LssSlave`] reports to the `Device`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LssEvent {
    /// The LSS state changed.
    StateChanged {
        /// The state left.
        from: LssState,
        /// The state entered.
        to: LssState,
    },
    /// Configure node-ID succeeded: `pending` (`None` = FFh, unconfigured) becomes the active
    /// node-ID at the next NMT reset communication ([`LssSlave::reset_communication`]).
    NodeIdConfigured {
        /// The pending node-ID.
        pending: Option<NodeId>,
    },
    /// Configure bit timing succeeded: the pending bit rate.
    BitTimingConfigured {
        /// The table selector.
        table: u8,
        /// The table index.
        index: u8,
    },
    /// Activate bit timing received: send nothing from now on; switch to the pending bit rate after
    /// `delay` (reported as [`LssEvent::SwitchBitRate`]) and keep silent for `delay` after that.
    BitTimingActivate {
        /// The table selector of the bit rate to switch to.
        table: u8,
        /// Its table index.
        index: u8,
        /// The switch delay.
        delay: Duration,
    },
    /// The first switch delay is over: switch the CAN controller to this bit rate now.
    SwitchBitRate {
        /// The table selector.
        table: u8,
        /// The table index.
        index: u8,
    },
    /// The second switch delay is over: the node may send again.
    BitTimingSilenceEnded,
    /// An unconfigured node got a node-ID and was switched back to waiting: perform an NMT reset
    /// communication, which makes the node-ID active (CANopenNode behaviour, reference §7.3).
    ResetCommunication,
    /// Store configuration failed; the error code went to the master.
    StoreFailed(LssStoreError),
    /// A frame on CAN-ID 7E5h that is not an LSS request; it was ignored.
    Malformed(MalformedLss),
    /// An 8-byte frame on 7E5h with an unknown command specifier; it was ignored.
    UnknownCommand {
        /// The command specifier received.
        specifier: u8,
    },
    /// A well-formed request ignored without an answer.
    Ignored {
        /// The command specifier.
        specifier: u8,
        /// Why.
        reason: IgnoredReason,
    },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Switching {
    /// Silent until `at`, then switch.
    BeforeSwitch {
        at: Instant,
        timing: BitTiming,
        delay: Duration,
    },
    /// Switched; silent until `at`.
    AfterSwitch { at: Instant },
}

/// The LSS slave of one node.
#[derive(Debug, Clone)]
pub struct LssSlave {
    identity: LssAddress,
    state: LssState,
    active_node: Option<NodeId>,
    pending_node: Option<NodeId>,
    active_timing: Option<BitTiming>,
    pending_timing: Option<BitTiming>,
    supported: Vec<u8>,
    selective: [Option<u32>; 4],
    identify: [Option<u32>; 6],
    fastscan_position: u8,
    switching: Option<Switching>,
    transmit: VecDeque<CanFrame>,
    events: VecDeque<LssEvent>,
}

impl LssSlave {
    /// A slave with LSS address `identity` running with node-ID `node` (`None`: unconfigured,
    /// FFh), in LSS waiting state, with [`DEFAULT_BIT_TIMINGS`] and no known bit rate.
    pub fn new(identity: LssAddress, node: Option<NodeId>) -> LssSlave {
        LssSlave {
            identity,
            state: LssState::Waiting,
            active_node: node,
            pending_node: node,
            active_timing: None,
            pending_timing: None,
            supported: DEFAULT_BIT_TIMINGS.to_vec(),
            selective: [None; 4],
            identify: [None; 6],
            fastscan_position: 0,
            switching: None,
            transmit: VecDeque::new(),
            events: VecDeque::new(),
        }
    }

    /// [`LssSlave::new`] with the identity read from 1018h of `od`.
    pub fn from_od(od: &DynamicOd, node: Option<NodeId>) -> Result<LssSlave, LssAddressError> {
        Ok(LssSlave::new(lss_address_from_od(od)?, node))
    }

    /// The bit rate the node runs with (table selector 0 index), which activate bit timing uses
    /// when no other was configured.
    pub fn with_bit_timing(mut self, index: u8) -> LssSlave {
        let timing = BitTiming { table: 0, index };
        self.active_timing = Some(timing);
        self.pending_timing = Some(timing);
        self
    }

    /// The table 0 indices configure bit timing accepts (instead of [`DEFAULT_BIT_TIMINGS`]).
    pub fn with_supported_bit_timings(mut self, indices: &[u8]) -> LssSlave {
        self.supported = indices.to_vec();
        self
    }

    /// The LSS address.
    pub fn identity(&self) -> &LssAddress {
        &self.identity
    }

    /// The LSS state.
    pub fn state(&self) -> LssState {
        self.state
    }

    /// The node-ID the node runs with; `None` when unconfigured (FFh).
    pub fn node_id(&self) -> Option<NodeId> {
        self.active_node
    }

    /// The node-ID configured by LSS, active after the next reset communication.
    pub fn pending_node_id(&self) -> Option<NodeId> {
        self.pending_node
    }

    /// The bit rate the node runs with, if known.
    pub fn bit_timing(&self) -> Option<BitTiming> {
        self.active_timing
    }

    /// The bit rate configure bit timing set, if any (else the active one).
    pub fn pending_bit_timing(&self) -> Option<BitTiming> {
        self.pending_timing
    }

    /// Power-on with what store configuration saved (`Device` calls it at NMT reset node): the stored
    /// node-ID and bit rate become pending, as a device reads them from its non-volatile memory at
    /// start-up; the next reset communication makes them active.
    pub fn restore_stored(&mut self, stored: StoredConfiguration) {
        self.pending_node = stored.node_id;
        if stored.bit_timing.is_some() {
            self.pending_timing = stored.bit_timing;
        }
    }

    /// NMT reset communication: the pending node-ID becomes active (CiA 305). Returns the node-ID
    /// the node now runs with, for [`NmtSlave::set_node_id`](crate::nmt_slave::NmtSlave::set_node_id);
    /// `None` means it stays unconfigured and only LSS runs. The LSS state is kept: CiA 305 changes
    /// it only by switch services and power-on.
    pub fn reset_communication(&mut self) -> Option<NodeId> {
        self.active_node = self.pending_node;
        self.active_node
    }

    /// Whether a bit rate switch forbids sending now: from activate bit timing until the
    /// second switch delay is over. The `Device` holds back every core's frames meanwhile.
    pub fn is_silent(&self) -> bool {
        self.switching.is_some()
    }

    /// Feeds a received frame with no storage for store configuration (it answers "storing not
    /// supported"). Only frames on CAN-ID 7E5h (11-bit) concern the LSS slave; returns whether the
    /// frame was one.
    pub fn accept_frame(&mut self, now: Instant, frame: &CanFrame) -> bool {
        self.handle_frame_with(now, frame, &mut ())
    }

    /// [`handle_frame`](LssSlave::handle_frame) with the device's storage.
    pub fn handle_frame_with(
        &mut self,
        now: Instant,
        frame: &CanFrame,
        storage: &mut dyn LssStorage,
    ) -> bool {
        if frame.id().is_extended() || frame.id().as_raw() != u32::from(LSS_MASTER_TO_SLAVE_ID) {
            return false;
        }
        if frame.is_remote() {
            self.events.push_back(LssEvent::Malformed(MalformedLss::Remote));
            return true;
        }
        let Ok(data) = <[u8; 8]>::try_from(frame.data()) else {
            self.events
                .push_back(LssEvent::Malformed(MalformedLss::WrongDlc(frame.dlc())));
            return true;
        };
        let specifier = data[0];
        let request = match LssRequest::parse(&data) {
            Ok(request) => request,
            Err(LssError::UnknownCommand { specifier, .. }) => {
                self.events.push_back(LssEvent::UnknownCommand { specifier });
                return true;
            }
        };
        if self.switching.is_some() {
            self.ignore(specifier, IgnoredReason::Silent);
            return true;
        }
        self.request(now, specifier, request, storage);
        true
    }

    fn request(&mut self, now: Instant, specifier: u8, request: LssRequest, storage: &mut dyn LssStorage) {
        use LssState::{Configuration, Waiting};
        let needs = match request {
            LssRequest::SwitchStateGlobal { .. }
            | LssRequest::IdentifyRemoteSlave { .. }
            | LssRequest::IdentifyNonConfiguredRemoteSlave => None,
            LssRequest::SwitchStateSelective { .. } | LssRequest::Fastscan { .. } => Some(Waiting),
            LssRequest::ConfigureNodeId { .. }
            | LssRequest::ConfigureBitTiming { .. }
            | LssRequest::ActivateBitTiming { .. }
            | LssRequest::StoreConfiguration
            | LssRequest::InquireAddress(_)
            | LssRequest::InquireNodeId => Some(Configuration),
        };
        match needs {
            Some(Waiting) if self.state != Waiting => {
                return self.ignore(specifier, IgnoredReason::NotInWaiting);
            }
            Some(Configuration) if self.state != Configuration => {
                return self.ignore(specifier, IgnoredReason::NotInConfiguration);
            }
            _ => {}
        }
        match request {
            LssRequest::SwitchStateGlobal { mode: 0 } => self.switch_to_waiting(),
            LssRequest::SwitchStateGlobal { mode: 1 } => self.enter(Configuration),
            LssRequest::SwitchStateGlobal { mode } => {
                self.ignore(specifier, IgnoredReason::InvalidMode(mode))
            }
            LssRequest::SwitchStateSelective { part, value } => self.switch_selective(specifier, part, value),
            LssRequest::ConfigureNodeId { node_id } => self.configure_node_id(node_id),
            LssRequest::ConfigureBitTiming { table, index } => self.configure_bit_timing(table, index),
            LssRequest::ActivateBitTiming { delay_ms } => self.activate_bit_timing(now, specifier, delay_ms),
            LssRequest::StoreConfiguration => {
                let (error, spec_error) = match storage.store(self.pending_node, self.pending_timing) {
                    Ok(()) => (0, 0),
                    Err(err) => {
                        self.events.push_back(LssEvent::StoreFailed(err));
                        err.error_code()
                    }
                };
                self.respond(LssResponse::StoreConfiguration { error, spec_error });
            }
            LssRequest::IdentifyRemoteSlave { field, value } => self.identify_remote(specifier, field, value),
            LssRequest::IdentifyNonConfiguredRemoteSlave => {
                // CiA 305: slaves whose (active) node-ID is FFh answer.
                if self.active_node.is_none() {
                    self.respond(LssResponse::IdentifyNonConfiguredSlave);
                }
            }
            LssRequest::Fastscan {
                id_number,
                bit_checked,
                lss_sub,
                lss_next,
            } => self.fastscan(specifier, id_number, bit_checked, lss_sub, lss_next),
            LssRequest::InquireAddress(part) => self.respond(LssResponse::InquireAddress {
                part,
                value: self.identity.part(part),
            }),
            LssRequest::InquireNodeId => {
                // The active node-ID, as CANopenNode answers (lely answers the pending one while
                // initialising); FFh when unconfigured.
                let node_id = self.active_node.map_or(UNCONFIGURED_NODE_ID, NodeId::get);
                self.respond(LssResponse::InquireNodeId { node_id });
            }
        }
    }

    fn switch_to_waiting(&mut self) {
        let was_configuration = self.state == LssState::Configuration;
        self.enter(LssState::Waiting);
        if was_configuration && self.active_node.is_none() && self.pending_node.is_some() {
            self.events.push_back(LssEvent::ResetCommunication);
        }
    }

    fn switch_selective(&mut self, specifier: u8, part: LssAddressPart, value: u32) {
        let slot = match part {
            LssAddressPart::VendorId => 0,
            LssAddressPart::ProductCode => 1,
            LssAddressPart::RevisionNumber => 2,
            LssAddressPart::SerialNumber => 3,
        };
        if let Some(received) = self.selective.get_mut(slot) {
            *received = Some(value);
        }
        if part != LssAddressPart::SerialNumber {
            return;
        }
        let received = std::mem::take(&mut self.selective);
        let Some(address) = received.iter().copied().collect::<Option<Vec<u32>>>() else {
            return self.ignore(specifier, IgnoredReason::Incomplete);
        };
        let ours = [
            self.identity.vendor_id,
            self.identity.product_code,
            self.identity.revision_number,
            self.identity.serial_number,
        ];
        if address == ours {
            self.enter(LssState::Configuration);
            self.respond(LssResponse::SwitchStateSelective);
        }
    }

    fn configure_node_id(&mut self, raw: u8) {
        let accepted = match NodeId::new(raw) {
            Some(node) => Some(Some(node)),
            None if raw == UNCONFIGURED_NODE_ID => Some(None),
            None => None,
        };
        let error = match accepted {
            Some(pending) => {
                self.pending_node = pending;
                self.events.push_back(LssEvent::NodeIdConfigured { pending });
                0
            }
            // Error code 1: node-ID out of range (0 and 80h..FEh).
            None => 1,
        };
        self.respond(LssResponse::ConfigureNodeId { error, spec_error: 0 });
    }

    fn configure_bit_timing(&mut self, table: u8, index: u8) {
        let error = if table == 0 && self.supported.contains(&index) {
            self.pending_timing = Some(BitTiming { table, index });
            self.events
                .push_back(LssEvent::BitTimingConfigured { table, index });
            0
        } else {
            // Error code 1: bit rate not supported (other tables, reserved or unsupported indices).
            1
        };
        self.respond(LssResponse::ConfigureBitTiming { error, spec_error: 0 });
    }

    fn activate_bit_timing(&mut self, now: Instant, specifier: u8, delay_ms: u16) {
        let Some(timing) = self.pending_timing else {
            return self.ignore(specifier, IgnoredReason::NoPendingBitTiming);
        };
        let delay = Duration::from_millis(u64::from(delay_ms));
        // Anything not yet sent would go out during the silence: drop it.
        self.transmit.clear();
        self.events.push_back(LssEvent::BitTimingActivate {
            table: timing.table,
            index: timing.index,
            delay,
        });
        self.switching = Some(Switching::BeforeSwitch {
            at: now + delay,
            timing,
            delay,
        });
    }

    fn identify_remote(&mut self, specifier: u8, field: IdentifyField, value: u32) {
        let slot = match field {
            IdentifyField::VendorId => 0,
            IdentifyField::ProductCode => 1,
            IdentifyField::RevisionLow => 2,
            IdentifyField::RevisionHigh => 3,
            IdentifyField::SerialLow => 4,
            IdentifyField::SerialHigh => 5,
        };
        if let Some(received) = self.identify.get_mut(slot) {
            *received = Some(value);
        }
        if field != IdentifyField::SerialHigh {
            return;
        }
        let received = std::mem::take(&mut self.identify);
        let [
            Some(vendor),
            Some(product),
            Some(rev_low),
            Some(rev_high),
            Some(serial_low),
            Some(serial_high),
        ] = received
        else {
            return self.ignore(specifier, IgnoredReason::Incomplete);
        };
        // Vendor-ID and product code match exactly; revision and serial number are inclusive ranges.
        let id = &self.identity;
        if id.vendor_id == vendor
            && id.product_code == product
            && (rev_low..=rev_high).contains(&id.revision_number)
            && (serial_low..=serial_high).contains(&id.serial_number)
        {
            self.respond(LssResponse::IdentifySlave);
        }
    }

    /// Fastscan (CiA 305), with CANopenNode's slave rules (reference §7.4).
    ///
    /// Choice: only slaves in waiting state whose active node-ID is FFh (unconfigured) take part; a
    /// node with a valid node-ID stays silent, as in CANopenNode, so a fastscan finds exactly the
    /// nodes that still need a node-ID.
    fn fastscan(&mut self, specifier: u8, id_number: u32, bit_checked: u8, sub: u8, next: u8) {
        if self.active_node.is_some() {
            return self.ignore(specifier, IgnoredReason::Configured);
        }
        if bit_checked == FASTSCAN_RESET {
            self.fastscan_position = 0;
            self.respond(LssResponse::IdentifySlave);
            return;
        }
        let (Some(part), true, true) = (
            LssAddressPart::from_offset(sub).map(|part| self.identity.part(part)),
            bit_checked <= 31,
            next <= 3,
        ) else {
            return self.ignore(specifier, IgnoredReason::InvalidFastscan);
        };
        if self.fastscan_position != sub {
            return;
        }
        let mask = u32::MAX << bit_checked;
        if part & mask != id_number & mask {
            return;
        }
        self.respond(LssResponse::IdentifySlave);
        if bit_checked == 0 && next < sub {
            // The serial number (the last part) was confirmed: the whole address matched.
            self.fastscan_position = 0;
            self.enter(LssState::Configuration);
        } else {
            self.fastscan_position = next;
        }
    }

    fn ignore(&mut self, specifier: u8, reason: IgnoredReason) {
        self.events.push_back(LssEvent::Ignored { specifier, reason });
    }

    fn respond(&mut self, response: LssResponse) {
        if let Some(id) = StandardId::new(LSS_SLAVE_TO_MASTER_ID)
            && let Ok(frame) = CanFrame::new(id, &response.encode())
        {
            self.transmit.push_back(frame);
        }
    }

    fn enter(&mut self, to: LssState) {
        let from = self.state;
        if from != to {
            self.state = to;
            self.selective = [None; 4];
            self.fastscan_position = 0;
            self.events.push_back(LssEvent::StateChanged { from, to });
        }
    }
}

impl Core for LssSlave {
    type Event = LssEvent;

    fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
        self.accept_frame(now, frame);
    }

    /// Lets time pass: runs the two switch delays of activate bit timing.
    fn handle_timeout(&mut self, now: Instant) {
        match self.switching {
            Some(Switching::BeforeSwitch { at, timing, delay }) if now >= at => {
                self.active_timing = Some(timing);
                self.events.push_back(LssEvent::SwitchBitRate {
                    table: timing.table,
                    index: timing.index,
                });
                self.switching = Some(Switching::AfterSwitch { at: at + delay });
                if now >= at + delay {
                    self.handle_timeout(now);
                }
            }
            Some(Switching::AfterSwitch { at }) if now >= at => {
                self.switching = None;
                self.events.push_back(LssEvent::BitTimingSilenceEnded);
            }
            _ => {}
        }
    }

    /// The next frame to send.
    fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.transmit.pop_front()
    }

    /// The next event for the `Device`.
    fn poll_event(&mut self) -> Option<Self::Event> {
        self.events.pop_front()
    }

    /// When [`handle_timeout`](LssSlave::handle_timeout) wants to be called next: the end of a
    /// switch delay.
    fn poll_timeout(&self) -> Option<Instant> {
        match self.switching? {
            Switching::BeforeSwitch { at, .. } | Switching::AfterSwitch { at } => Some(at),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_can::Core;
    use canopener_od::{Access, DataType, Entry};
    use canopener_testkit::trace::{Trace, frame, ms};

    /// A storage that records what it stored, or fails as told.
    #[derive(Debug, Default)]
    struct Memory {
        fail: Option<LssStoreError>,
        stored: Vec<(Option<NodeId>, Option<BitTiming>)>,
    }

    impl LssStorage for Memory {
        fn store(
            &mut self,
            node_id: Option<NodeId>,
            bit_timing: Option<BitTiming>,
        ) -> Result<(), LssStoreError> {
            match self.fail {
                Some(err) => Err(err),
                None => {
                    self.stored.push((node_id, bit_timing));
                    Ok(())
                }
            }
        }
    }

    /// An LSS slave owned together with its storage, as a `Device` would.
    struct WithStorage(LssSlave, Memory);

    impl Core for WithStorage {
        type Event = LssEvent;
        fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
            self.0.handle_frame_with(now, frame, &mut self.1);
        }
        fn handle_timeout(&mut self, now: Instant) {
            self.0.handle_timeout(now);
        }
        fn poll_transmit(&mut self) -> Option<CanFrame> {
            self.0.poll_transmit()
        }
        fn poll_event(&mut self) -> Option<LssEvent> {
            self.0.poll_event()
        }
        fn poll_timeout(&self) -> Option<Instant> {
            self.0.poll_timeout()
        }
    }

    const IDENTITY: LssAddress = LssAddress {
        vendor_id: 0x0000_031A,
        product_code: 0x1234_5678,
        revision_number: 0x0001_0002,
        serial_number: 0xCAFE_BABE,
    };

    /// A master request on 7E5h: `hex` padded with zero bytes to 8.
    fn m(hex: &str) -> String {
        format!("7E5#{hex:0<16}")
    }

    /// `"<at> 7E4#<hex padded>"`: a slave answer sent at `at`.
    fn s(at: &str, hex: &str) -> String {
        format!("{at} 7E4#{hex:0<16}")
    }

    fn node(raw: u8) -> Option<NodeId> {
        NodeId::new(raw)
    }

    fn slave(node_id: Option<NodeId>) -> Trace<LssSlave> {
        Trace::new(LssSlave::new(IDENTITY, node_id))
    }

    /// A slave already switched to configuration state (events and frames drained).
    fn configuring(node_id: Option<NodeId>) -> Trace<LssSlave> {
        let mut trace = slave(node_id);
        trace.rx(ms(0), &m("0401"));
        trace.events();
        assert_eq!(trace.core.state(), LssState::Configuration);
        trace
    }

    fn changed(at: &str, from: LssState, to: LssState) -> String {
        format!("{at} StateChanged {{ from: {from:?}, to: {to:?} }}")
    }

    fn ignored(at: &str, specifier: u8, reason: IgnoredReason) -> String {
        format!("{at} Ignored {{ specifier: {specifier}, reason: {reason:?} }}")
    }

    use LssState::{Configuration as Config, Waiting};

    #[test]
    fn switch_state_global_both_ways() {
        let mut trace = slave(node(5));
        assert_eq!(trace.core.state(), Waiting);
        trace.rx(ms(1), &m("0401"));
        trace.rx(ms(2), &m("0401"));
        trace.rx(ms(3), &m("0400"));
        trace.rx(ms(4), &m("0400"));
        assert_eq!(
            trace.events(),
            [
                changed("1.000", Waiting, Config),
                changed("3.000", Config, Waiting)
            ]
        );
        assert!(trace.sent().is_empty(), "switch state global is unconfirmed");
    }

    #[test]
    fn switch_state_global_with_an_invalid_mode_is_ignored() {
        let mut trace = slave(node(5));
        trace.rx(ms(1), &m("0402"));
        trace.rx(ms(2), &m("04FF"));
        assert_eq!(trace.core.state(), Waiting);
        assert_eq!(
            trace.events(),
            [
                ignored("1.000", 0x04, IgnoredReason::InvalidMode(2)),
                ignored("2.000", 0x04, IgnoredReason::InvalidMode(0xFF)),
            ]
        );
    }

    #[test]
    fn switch_state_selective_with_the_right_identity() {
        let mut trace = slave(node(5));
        trace.rx(ms(1), &m("401A030000"));
        trace.rx(ms(2), &m("4178563412"));
        trace.rx(ms(3), &m("4202000100"));
        assert!(trace.sent().is_empty(), "only the serial number part is answered");
        trace.rx(ms(4), &m("43BEBAFECA"));
        assert_eq!(trace.sent(), [s("4.000", "44")]);
        assert_eq!(trace.events(), [changed("4.000", Waiting, Config)]);
    }

    #[test]
    fn switch_state_selective_with_a_wrong_identity() {
        let right = ["401A030000", "4178563412", "4202000100", "43BEBAFECA"];
        for wrong_part in 0..4 {
            let mut trace = slave(node(5));
            for (part, text) in right.iter().enumerate() {
                let mut text = text.to_string();
                if part == wrong_part {
                    text.replace_range(2..4, "FF");
                }
                trace.rx(ms(part as u64), &m(&text));
            }
            assert_eq!(trace.core.state(), Waiting, "part {wrong_part} wrong");
            assert!(trace.sent().is_empty());
            assert!(trace.events().is_empty());
        }
    }

    #[test]
    fn switch_state_selective_needs_every_part_and_waiting_state() {
        let mut trace = slave(node(5));
        // Serial number without the other parts.
        trace.rx(ms(1), &m("43BEBAFECA"));
        // A complete sequence afterwards still works: the early serial number was forgotten.
        trace.rx(ms(2), &m("401A030000"));
        trace.rx(ms(3), &m("4178563412"));
        trace.rx(ms(4), &m("43BEBAFECA"));
        assert_eq!(trace.core.state(), Waiting);
        assert_eq!(
            trace.events(),
            [
                ignored("1.000", 0x43, IgnoredReason::Incomplete),
                ignored("4.000", 0x43, IgnoredReason::Incomplete),
            ]
        );
        let mut trace = configuring(node(5));
        for (at, text) in [
            (1, "401A030000"),
            (2, "4178563412"),
            (3, "4202000100"),
            (4, "43BEBAFECA"),
        ] {
            trace.rx(ms(at), &m(text));
        }
        assert!(trace.sent().is_empty());
        assert_eq!(
            trace.events(),
            [
                ignored("1.000", 0x40, IgnoredReason::NotInWaiting),
                ignored("2.000", 0x41, IgnoredReason::NotInWaiting),
                ignored("3.000", 0x42, IgnoredReason::NotInWaiting),
                ignored("4.000", 0x43, IgnoredReason::NotInWaiting),
            ]
        );
    }

    #[test]
    fn configure_node_id_valid_values() {
        let mut trace = configuring(node(5));
        trace.rx(ms(1), &m("1101"));
        trace.rx(ms(2), &m("117F"));
        trace.rx(ms(3), &m("11FF"));
        trace.rx(ms(4), &m("1122"));
        assert_eq!(
            trace.sent(),
            [
                s("1.000", "1100"),
                s("2.000", "1100"),
                s("3.000", "1100"),
                s("4.000", "1100")
            ]
        );
        assert_eq!(
            trace.events(),
            [
                "1.000 NodeIdConfigured { pending: Some(NodeId(1)) }",
                "2.000 NodeIdConfigured { pending: Some(NodeId(127)) }",
                "3.000 NodeIdConfigured { pending: None }",
                "4.000 NodeIdConfigured { pending: Some(NodeId(34)) }",
            ]
        );
        assert_eq!(trace.core.node_id(), node(5), "active until reset communication");
        assert_eq!(trace.core.pending_node_id(), node(0x22));
        trace.rx(ms(5), &m("5E"));
        assert_eq!(
            trace.sent(),
            [s("5.000", "5E05")],
            "inquire node-ID answers the active one"
        );
        assert_eq!(trace.core.reset_communication(), node(0x22));
        assert_eq!(trace.core.node_id(), node(0x22));
        trace.rx(ms(6), &m("5E"));
        assert_eq!(trace.sent(), [s("6.000", "5E22")]);
    }

    #[test]
    fn configure_node_id_out_of_range_is_error_code_1() {
        let mut trace = configuring(node(5));
        for (at, raw) in [(1, "00"), (2, "80"), (3, "FE")] {
            trace.rx(ms(at), &m(&format!("11{raw}")));
        }
        assert_eq!(
            trace.sent(),
            [s("1.000", "1101"), s("2.000", "1101"), s("3.000", "1101")]
        );
        assert!(trace.events().is_empty());
        assert_eq!(trace.core.pending_node_id(), node(5), "nothing changed");
    }

    #[test]
    fn an_unconfigured_node_asks_for_reset_communication_when_switched_to_waiting() {
        let mut trace = configuring(None);
        trace.rx(ms(1), &m("1120"));
        trace.rx(ms(2), &m("0400"));
        assert_eq!(
            trace.events(),
            [
                "1.000 NodeIdConfigured { pending: Some(NodeId(32)) }".to_string(),
                changed("2.000", Config, Waiting),
                "2.000 ResetCommunication".to_string(),
            ]
        );
        assert_eq!(trace.core.reset_communication(), node(0x20));
        // A configured node keeps running with its node-ID until the master resets it.
        let mut trace = configuring(node(5));
        trace.rx(ms(1), &m("1120"));
        trace.rx(ms(2), &m("0400"));
        assert_eq!(
            trace.events(),
            [
                "1.000 NodeIdConfigured { pending: Some(NodeId(32)) }".to_string(),
                changed("2.000", Config, Waiting),
            ]
        );
        // And an unconfigured node switched back without a node-ID has nothing to apply.
        let mut trace = configuring(None);
        trace.rx(ms(1), &m("0400"));
        assert_eq!(trace.events(), [changed("1.000", Config, Waiting)]);
    }

    #[test]
    fn configure_bit_timing_from_table_0() {
        let mut trace = configuring(node(5));
        for (at, index) in DEFAULT_BIT_TIMINGS.iter().enumerate() {
            trace.rx(ms(at as u64), &m(&format!("1300{index:02X}")));
        }
        let sent = trace.sent();
        assert_eq!(sent.len(), DEFAULT_BIT_TIMINGS.len());
        assert!(
            sent.iter().all(|line| line.ends_with("7E4#1300000000000000")),
            "{sent:?}"
        );
        assert_eq!(trace.events().len(), DEFAULT_BIT_TIMINGS.len());
        assert_eq!(
            trace.core.pending_bit_timing(),
            Some(BitTiming { table: 0, index: 8 })
        );
        assert_eq!(
            trace.core.bit_timing(),
            None,
            "active only after activate bit timing"
        );
    }

    #[test]
    fn configure_bit_timing_unsupported_is_error_code_1() {
        let mut trace = configuring(node(5));
        trace.rx(ms(1), &m("130005")); // reserved, formerly 100 kbit/s
        trace.rx(ms(2), &m("130009")); // automatic bit rate detection
        trace.rx(ms(3), &m("13000A")); // not in the table
        trace.rx(ms(4), &m("130102")); // table 1 is reserved
        trace.rx(ms(5), &m("138002")); // no user-defined tables
        assert_eq!(
            trace.sent(),
            [
                s("1.000", "1301"),
                s("2.000", "1301"),
                s("3.000", "1301"),
                s("4.000", "1301"),
                s("5.000", "1301")
            ]
        );
        assert!(trace.events().is_empty());
        assert_eq!(trace.core.pending_bit_timing(), None);
        // A device that supports fewer rates refuses the others.
        let mut trace = Trace::new(LssSlave::new(IDENTITY, node(5)).with_supported_bit_timings(&[2, 3]));
        trace.rx(ms(0), &m("0401"));
        trace.rx(ms(1), &m("130000"));
        trace.rx(ms(2), &m("130003"));
        assert_eq!(trace.sent(), [s("1.000", "1301"), s("2.000", "1300")]);
    }

    #[test]
    fn activate_bit_timing_switches_after_the_delay_in_silence() {
        let mut trace = Trace::new(LssSlave::new(IDENTITY, node(5)).with_bit_timing(3));
        trace.rx(ms(0), &m("0401"));
        trace.rx(ms(1), &m("130002"));
        trace.events();
        trace.sent();
        trace.rx(ms(10), &m("156400")); // 100 ms
        assert!(trace.core.is_silent());
        assert_eq!(trace.core.poll_timeout(), Some(ms(110)));
        trace.rx(ms(50), &m("5E")); // the master should not talk now; no answer in any case
        trace.advance(ms(109));
        assert_eq!(trace.core.bit_timing(), Some(BitTiming { table: 0, index: 3 }));
        trace.advance(ms(110));
        assert_eq!(trace.core.bit_timing(), Some(BitTiming { table: 0, index: 2 }));
        assert_eq!(trace.core.poll_timeout(), Some(ms(210)));
        trace.advance(ms(250));
        assert!(!trace.core.is_silent());
        assert_eq!(trace.core.poll_timeout(), None);
        assert_eq!(
            trace.events(),
            [
                "10.000 BitTimingActivate { table: 0, index: 2, delay: 100ms }".to_string(),
                ignored("50.000", 0x5E, IgnoredReason::Silent),
                "110.000 SwitchBitRate { table: 0, index: 2 }".to_string(),
                "210.000 BitTimingSilenceEnded".to_string(),
            ]
        );
        assert!(trace.sent().is_empty());
        trace.rx(ms(260), &m("5E"));
        assert_eq!(trace.sent(), [s("260.000", "5E05")]);
        assert_eq!(
            trace.core.state(),
            Config,
            "activate bit timing keeps the LSS state"
        );
    }

    #[test]
    fn activate_bit_timing_with_no_delay_and_with_the_current_rate() {
        let mut trace = Trace::new(LssSlave::new(IDENTITY, node(5)).with_bit_timing(4));
        trace.rx(ms(0), &m("0401"));
        trace.events();
        trace.rx(ms(5), &m("150000"));
        trace.advance(ms(6));
        assert_eq!(
            trace.events(),
            [
                "5.000 BitTimingActivate { table: 0, index: 4, delay: 0ns }",
                "5.000 SwitchBitRate { table: 0, index: 4 }",
                "5.000 BitTimingSilenceEnded",
            ]
        );
    }

    #[test]
    fn activate_bit_timing_without_a_pending_rate_is_ignored() {
        let mut trace = configuring(node(5));
        trace.rx(ms(1), &m("156400"));
        assert!(!trace.core.is_silent());
        assert_eq!(trace.core.poll_timeout(), None);
        assert_eq!(
            trace.events(),
            [ignored("1.000", 0x15, IgnoredReason::NoPendingBitTiming)]
        );
    }

    #[test]
    fn store_configuration_without_storage_is_not_supported() {
        let mut trace = configuring(node(5));
        trace.rx(ms(1), &m("17"));
        assert_eq!(trace.sent(), [s("1.000", "1701")]);
        assert_eq!(trace.events(), ["1.000 StoreFailed(NotSupported)"]);
    }

    #[test]
    fn store_configuration_hands_the_pending_values_to_the_storage() {
        let mut trace = Trace::new(WithStorage(
            LssSlave::new(IDENTITY, None).with_bit_timing(0),
            Memory::default(),
        ));
        trace.rx(ms(0), &m("0401"));
        trace.rx(ms(1), &m("1133"));
        trace.rx(ms(2), &m("130003"));
        trace.rx(ms(3), &m("17"));
        assert_eq!(
            trace.sent(),
            [s("1.000", "1100"), s("2.000", "1300"), s("3.000", "1700")]
        );
        assert_eq!(
            trace.core.1.stored,
            [(node(0x33), Some(BitTiming { table: 0, index: 3 }))]
        );
    }

    #[test]
    fn store_configuration_errors_are_answered_with_their_codes() {
        for (fail, answer, event) in [
            (LssStoreError::MediaAccess, "1702", "StoreFailed(MediaAccess)"),
            (
                LssStoreError::Specific(0x42),
                "17FF42",
                "StoreFailed(Specific(66))",
            ),
            (LssStoreError::NotSupported, "1701", "StoreFailed(NotSupported)"),
        ] {
            let memory = Memory {
                fail: Some(fail),
                stored: Vec::new(),
            };
            let mut trace = Trace::new(WithStorage(LssSlave::new(IDENTITY, node(5)), memory));
            trace.rx(ms(0), &m("0401"));
            trace.events();
            trace.rx(ms(1), &m("17"));
            assert_eq!(trace.sent(), [s("1.000", answer)]);
            assert_eq!(trace.events(), [format!("1.000 {event}")]);
        }
    }

    #[test]
    fn inquire_identity_and_node_id() {
        let mut trace = configuring(node(5));
        for (at, cs) in [(1, "5A"), (2, "5B"), (3, "5C"), (4, "5D"), (5, "5E")] {
            trace.rx(ms(at), &m(cs));
        }
        assert_eq!(
            trace.sent(),
            [
                s("1.000", "5A1A030000"),
                s("2.000", "5B78563412"),
                s("3.000", "5C02000100"),
                s("4.000", "5DBEBAFECA"),
                s("5.000", "5E05"),
            ]
        );
        let mut trace = configuring(None);
        trace.rx(ms(1), &m("5E"));
        assert_eq!(trace.sent(), [s("1.000", "5EFF")]);
    }

    #[test]
    fn configuration_services_are_ignored_in_waiting_state() {
        let mut trace = Trace::new(LssSlave::new(IDENTITY, node(5)).with_bit_timing(3));
        let requests = ["1122", "130002", "156400", "17", "5A", "5B", "5C", "5D", "5E"];
        for (at, text) in requests.iter().enumerate() {
            trace.rx(ms(at as u64), &m(text));
        }
        assert!(trace.sent().is_empty());
        let expected: Vec<String> = requests
            .iter()
            .enumerate()
            .map(|(at, text)| {
                let specifier = u8::from_str_radix(&text[..2], 16).unwrap();
                ignored(&format!("{at}.000"), specifier, IgnoredReason::NotInConfiguration)
            })
            .collect();
        assert_eq!(trace.events(), expected);
        assert_eq!(trace.core.pending_node_id(), node(5));
        assert!(!trace.core.is_silent());
    }

    /// Identify remote slave with the given bounds, as six requests from `at` ms on.
    fn identify(trace: &mut Trace<LssSlave>, at: u64, bounds: [u32; 6]) {
        for (offset, value) in bounds.into_iter().enumerate() {
            let [a, b, c, d] = value.to_le_bytes();
            let text = format!("{:02X}{a:02X}{b:02X}{c:02X}{d:02X}", 0x46 + offset);
            trace.rx(ms(at + offset as u64), &m(&text));
        }
    }

    #[test]
    fn identify_remote_slave_inside_and_outside_the_ranges() {
        let id = IDENTITY;
        let exact = [
            id.vendor_id,
            id.product_code,
            id.revision_number,
            id.revision_number,
            id.serial_number,
            id.serial_number,
        ];
        let mut trace = slave(node(5));
        identify(&mut trace, 0, exact);
        identify(
            &mut trace,
            10,
            [id.vendor_id, id.product_code, 0, u32::MAX, 0, u32::MAX],
        );
        assert_eq!(trace.sent(), [s("5.000", "4F"), s("15.000", "4F")]);
        let misses = [
            [id.vendor_id + 1, id.product_code, 0, u32::MAX, 0, u32::MAX],
            [id.vendor_id, id.product_code - 1, 0, u32::MAX, 0, u32::MAX],
            [
                id.vendor_id,
                id.product_code,
                0,
                id.revision_number - 1,
                0,
                u32::MAX,
            ],
            [
                id.vendor_id,
                id.product_code,
                id.revision_number + 1,
                u32::MAX,
                0,
                u32::MAX,
            ],
            [
                id.vendor_id,
                id.product_code,
                0,
                u32::MAX,
                0,
                id.serial_number - 1,
            ],
            [
                id.vendor_id,
                id.product_code,
                0,
                u32::MAX,
                id.serial_number + 1,
                u32::MAX,
            ],
            [id.vendor_id, id.product_code, u32::MAX, 0, 0, u32::MAX], // empty range
        ];
        for (n, bounds) in misses.into_iter().enumerate() {
            identify(&mut trace, 100 + 10 * n as u64, bounds);
        }
        assert!(trace.sent().is_empty());
        assert!(trace.events().is_empty());
        // Identify runs in configuration state too.
        let mut trace = configuring(node(5));
        identify(&mut trace, 0, exact);
        assert_eq!(trace.sent(), [s("5.000", "4F")]);
    }

    #[test]
    fn identify_remote_slave_needs_every_bound() {
        let mut trace = slave(node(5));
        trace.rx(ms(1), &m("4BFFFFFFFF"));
        assert!(trace.sent().is_empty());
        assert_eq!(
            trace.events(),
            [ignored("1.000", 0x4B, IgnoredReason::Incomplete)]
        );
    }

    #[test]
    fn identify_non_configured_remote_slave() {
        let mut unconfigured = slave(None);
        unconfigured.rx(ms(1), &m("4C"));
        assert_eq!(unconfigured.sent(), [s("1.000", "50")]);
        let mut configured = slave(node(5));
        configured.rx(ms(1), &m("4C"));
        assert!(configured.sent().is_empty());
        // The answer follows the active node-ID: a pending one does not count yet.
        let mut trace = configuring(None);
        trace.rx(ms(1), &m("1110"));
        trace.rx(ms(2), &m("4C"));
        trace.core.reset_communication();
        trace.rx(ms(3), &m("4C"));
        assert_eq!(trace.sent(), [s("1.000", "1100"), s("2.000", "50")]);
    }

    /// A bus of LSS slaves driven by a test LSS master.
    struct Bus {
        slaves: Vec<LssSlave>,
        now: Instant,
        exchanges: usize,
    }

    impl Bus {
        /// Sends `request` to every slave; returns the answers.
        fn send(&mut self, request: LssRequest) -> Vec<(usize, LssResponse)> {
            self.now += Duration::from_millis(1);
            self.exchanges += 1;
            let frame = CanFrame::new(
                StandardId::new(LSS_MASTER_TO_SLAVE_ID).unwrap(),
                &request.encode(),
            )
            .unwrap();
            let mut answers = Vec::new();
            for (n, slave) in self.slaves.iter_mut().enumerate() {
                assert!(slave.accept_frame(self.now, &frame));
                while let Some(answer) = slave.poll_transmit() {
                    assert_eq!(answer.id().as_raw(), u32::from(LSS_SLAVE_TO_MASTER_ID));
                    let data = <[u8; 8]>::try_from(answer.data()).unwrap();
                    answers.push((n, LssResponse::parse(&data).unwrap()));
                }
            }
            answers
        }

        fn fastscan(&mut self, id_number: u32, bit_checked: u8, lss_sub: u8, lss_next: u8) -> bool {
            let answers = self.send(LssRequest::Fastscan {
                id_number,
                bit_checked,
                lss_sub,
                lss_next,
            });
            assert!(answers.iter().all(|(_, a)| *a == LssResponse::IdentifySlave));
            !answers.is_empty()
        }

        /// The master side of fastscan (reference §7.4): the LSS address found, if any.
        fn scan(&mut self) -> Option<[u32; 4]> {
            if !self.fastscan(0, FASTSCAN_RESET, 0, 0) {
                return None;
            }
            let mut address = [0u32; 4];
            for sub in 0..4u8 {
                let part = &mut address[usize::from(sub)];
                for bit in (0..32u8).rev() {
                    if !self.fastscan(*part, bit, sub, sub) {
                        *part |= 1 << bit;
                    }
                }
                let next = (sub + 1) % 4;
                assert!(self.fastscan(*part, 0, sub, next), "confirmation of part {sub}");
            }
            Some(address)
        }
    }

    #[test]
    fn fastscan_finds_every_unconfigured_slave_bit_by_bit() {
        let identities = [
            IDENTITY,
            // Differs from the first only in the lowest serial number bit.
            LssAddress {
                serial_number: IDENTITY.serial_number ^ 1,
                ..IDENTITY
            },
            LssAddress {
                vendor_id: 0xFFFF_FFFF,
                product_code: 0,
                revision_number: 0x8000_0001,
                serial_number: 0x0000_0000,
            },
            // A configured slave with the smallest address: it must not take part.
            LssAddress::default(),
        ];
        let slaves = identities
            .iter()
            .enumerate()
            .map(|(n, id)| LssSlave::new(*id, if n == 3 { node(9) } else { None }))
            .collect();
        let mut bus = Bus {
            slaves,
            now: Instant::ZERO,
            exchanges: 0,
        };
        let mut found = Vec::new();
        while let Some(address) = bus.scan() {
            // Exactly one slave is in configuration state: the one with this address.
            let configuring: Vec<usize> = (0..bus.slaves.len())
                .filter(|n| bus.slaves[*n].state() == Config)
                .collect();
            assert_eq!(configuring.len(), 1);
            let n = configuring[0];
            let id = identities[n];
            assert_eq!(
                address,
                [
                    id.vendor_id,
                    id.product_code,
                    id.revision_number,
                    id.serial_number
                ]
            );
            let node_id = 0x20 + found.len() as u8;
            let answers = bus.send(LssRequest::ConfigureNodeId { node_id });
            assert_eq!(
                answers,
                [(
                    n,
                    LssResponse::ConfigureNodeId {
                        error: 0,
                        spec_error: 0
                    }
                )]
            );
            bus.send(LssRequest::SwitchStateGlobal { mode: 0 });
            let events: Vec<LssEvent> = std::iter::from_fn(|| bus.slaves[n].poll_event()).collect();
            assert!(events.contains(&LssEvent::ResetCommunication), "{events:?}");
            assert_eq!(bus.slaves[n].reset_communication(), node(node_id));
            found.push(n);
            assert!(found.len() <= 3, "a slave was found twice");
        }
        found.sort();
        assert_eq!(found, [0, 1, 2]);
        // 4 scans (the last finds nobody) of 1 reset + 4 × (32 bits + 1 confirmation), plus 2
        // configuration frames per slave found.
        assert_eq!(bus.exchanges, 3 * (1 + 4 * 33 + 2) + 1);
        assert_eq!(bus.slaves[3].node_id(), node(9));
    }

    #[test]
    fn fastscan_frame_trace() {
        let mut trace = slave(None);
        trace.rx(ms(1), &m("51000000008000")); // reset
        trace.rx(ms(2), &m("51000000001F0000")); // vendor-ID bit 31 is 0: answer
        trace.rx(ms(3), &m("510000000010000")); // bits 31..16 are 0: answer
        trace.rx(ms(4), &m("51000000000C0000")); // bits 31..12 are 0: answer
        trace.rx(ms(5), &m("5100000000080000")); // bits 31..8 are not 0 (31Ah): silence
        trace.rx(ms(6), &m("511A030000000001")); // confirm vendor-ID, next: product code
        trace.rx(ms(7), &m("511A030000000001")); // vendor-ID is no longer the position
        assert_eq!(
            trace.sent(),
            [
                s("1.000", "4F"),
                s("2.000", "4F"),
                s("3.000", "4F"),
                s("4.000", "4F"),
                s("6.000", "4F")
            ]
        );
        assert!(trace.events().is_empty());
        assert_eq!(trace.core.state(), Waiting);
    }

    #[test]
    fn fastscan_ignores_invalid_requests_configured_nodes_and_configuration_state() {
        let mut trace = slave(None);
        trace.rx(ms(1), &m("51000000002000")); // BitChecked 32
        trace.rx(ms(2), &m("51000000007F00")); // BitChecked 7Fh
        trace.rx(ms(3), &m("5100000000000400")); // LSSSub 4
        trace.rx(ms(4), &m("5100000000000004")); // LSSNext 4
        assert!(trace.sent().is_empty());
        assert_eq!(
            trace.events(),
            [
                ignored("1.000", 0x51, IgnoredReason::InvalidFastscan),
                ignored("2.000", 0x51, IgnoredReason::InvalidFastscan),
                ignored("3.000", 0x51, IgnoredReason::InvalidFastscan),
                ignored("4.000", 0x51, IgnoredReason::InvalidFastscan),
            ]
        );
        let mut configured = slave(node(5));
        configured.rx(ms(1), &m("51000000008000"));
        assert!(configured.sent().is_empty());
        assert_eq!(
            configured.events(),
            [ignored("1.000", 0x51, IgnoredReason::Configured)]
        );
        let mut trace = configuring(None);
        trace.rx(ms(1), &m("51000000008000"));
        assert!(trace.sent().is_empty());
        assert_eq!(
            trace.events(),
            [ignored("1.000", 0x51, IgnoredReason::NotInWaiting)]
        );
    }

    #[test]
    fn malformed_frames_are_ignored_and_reported() {
        let mut trace = slave(None);
        trace.rx(ms(1), "7E5#04010000000000"); // 7 bytes
        trace.rx(ms(2), "7E5#");
        trace.rx(ms(3), "7E5#R8");
        trace.rx(ms(4), &m("44")); // a slave's answer sent by a master
        trace.rx(ms(5), &m("00"));
        trace.rx(ms(6), &m("FF"));
        assert_eq!(trace.core.state(), Waiting);
        assert!(trace.sent().is_empty());
        assert_eq!(
            trace.events(),
            [
                "1.000 Malformed(WrongDlc(7))",
                "2.000 Malformed(WrongDlc(0))",
                "3.000 Malformed(Remote)",
                "4.000 UnknownCommand { specifier: 68 }",
                "5.000 UnknownCommand { specifier: 0 }",
                "6.000 UnknownCommand { specifier: 255 }",
            ]
        );
    }

    #[test]
    fn other_identifiers_are_not_lss_requests() {
        let mut lss = LssSlave::new(IDENTITY, None);
        for text in [
            "7E4#4F00000000000000",
            "000007E5#0401000000000000",
            "7E6#0401000000000000",
        ] {
            assert!(!lss.accept_frame(Instant::ZERO, &frame(text)), "{text}");
        }
        assert!(lss.accept_frame(Instant::ZERO, &frame("7E5#0401000000000000")));
        assert_eq!(lss.state(), Config);
    }

    fn u32_entry(sub: u8, value: u32) -> Entry {
        Entry::new(
            ObjectKey::new(0x1018, sub),
            DataType::UNSIGNED32,
            Access::Ro,
            &value.to_le_bytes(),
        )
        .unwrap()
    }

    #[test]
    fn identity_from_1018h() {
        let mut od = DynamicOd::with_capacity(8);
        od.insert(u32_entry(1, IDENTITY.vendor_id)).unwrap();
        od.insert(u32_entry(2, IDENTITY.product_code)).unwrap();
        od.insert(u32_entry(3, IDENTITY.revision_number)).unwrap();
        od.insert(u32_entry(4, IDENTITY.serial_number)).unwrap();
        let lss = LssSlave::from_od(&od, None).unwrap();
        assert_eq!(*lss.identity(), IDENTITY);
        assert_eq!(lss.node_id(), None);
        let mut partial = DynamicOd::with_capacity(8);
        partial.insert(u32_entry(1, 7)).unwrap();
        assert_eq!(
            lss_address_from_od(&partial),
            Ok(LssAddress {
                vendor_id: 7,
                ..LssAddress::default()
            })
        );
    }

    #[test]
    fn identity_errors() {
        let mut od = DynamicOd::with_capacity(8);
        od.insert(u32_entry(2, 1)).unwrap();
        assert_eq!(lss_address_from_od(&od), Err(LssAddressError::NoVendorId));
        let short = Entry::new(
            ObjectKey::new(0x1018, 1),
            DataType::VISIBLE_STRING,
            Access::Ro,
            b"abc",
        )
        .unwrap();
        od.insert(short).unwrap();
        let err = lss_address_from_od(&od).unwrap_err();
        assert_eq!(err, LssAddressError::NotUnsigned32 { sub: 1, len: 3 });
        assert_eq!(
            err.to_string(),
            "1018h:01 holds 3 bytes, not the 4 of an UNSIGNED32"
        );
    }

    fn any_lss_frame() -> impl proptest::strategy::Strategy<Value = CanFrame> {
        use proptest::prelude::*;
        let specifier = prop_oneof![
            prop::sample::select(vec![
                0x04u8, 0x11, 0x13, 0x15, 0x17, 0x40, 0x41, 0x42, 0x43, 0x46, 0x47, 0x48, 0x49, 0x4A, 0x4B,
                0x4C, 0x51, 0x5A, 0x5B, 0x5C, 0x5D, 0x5E,
            ]),
            any::<u8>()
        ];
        let lss = (specifier, proptest::collection::vec(any::<u8>(), 7)).prop_map(|(cs, rest)| {
            let mut data = vec![cs];
            data.extend(rest);
            CanFrame::new(StandardId::new(LSS_MASTER_TO_SLAVE_ID).unwrap(), &data).unwrap()
        });
        prop_oneof![4 => lss, 1 => canopener_testkit::frames::any_frame()]
    }

    proptest::proptest! {
        #[test]
        fn no_frame_panics_or_sticks(
            frames in proptest::collection::vec((any_lss_frame(), 0u64..200), 0..80),
            configured in proptest::bool::ANY,
        ) {
            let mut lss = LssSlave::new(IDENTITY, if configured { node(5) } else { None }).with_bit_timing(2);
            let mut now = Instant::ZERO;
            for (frame, step) in &frames {
                now += Duration::from_millis(*step);
                while let Some(due) = lss.poll_timeout().filter(|due| *due <= now) {
                    lss.handle_timeout(due);
                }
                lss.handle_frame(now, frame);
                while lss.poll_transmit().is_some() {}
                while lss.poll_event().is_some() {}
            }
            // Not stuck: every silence ends and the master can always bring the slave back.
            now += Duration::from_secs(200);
            lss.handle_timeout(now);
            lss.handle_timeout(now);
            proptest::prop_assert!(!lss.is_silent());
            lss.handle_frame(now, &frame("7E5#0400000000000000"));
            proptest::prop_assert_eq!(lss.state(), Waiting);
        }
    }
}

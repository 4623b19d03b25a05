//! The LSS master (CiA 305, layer setting services and protocols), sans IO.
//!
//! Before changing this file read CiA 305 (LSS services and protocols) and reference §7: the
//! master sends on CAN-ID 7E5h, slaves answer on 7E4h, every frame carries 8 bytes with the command
//! specifier in D0 ([`canopener_wire::lss`] reads and writes them).
//!
//! [`LssMaster`] runs one service at a time (a second one is refused with
//! [`LssCommandError::Busy`]) and ends every service with an [`LssEvent`]:
//!
//! | service | frames | ends with |
//! |---|---|---|
//! | switch state global (04h) | 1, unconfirmed | [`LssEvent::Done`] at once |
//! | switch state selective (40h–43h) | 4, answer 44h | [`LssEvent::Done`] or [`LssEvent::TimedOut`] |
//! | configure node-ID (11h), bit timing (13h), store configuration (17h) | 1, answer with error code | [`LssEvent::Configured`] or [`LssEvent::TimedOut`] |
//! | activate bit timing (15h) | 1, unconfirmed | [`LssEvent::SwitchBitRate`] after the switch delay, [`LssEvent::Done`] after two |
//! | inquire identity (5Ah–5Dh), inquire node-ID (5Eh) | 1, answer with the value | [`LssEvent::Inquired`] / [`LssEvent::NodeIdInquired`] or [`LssEvent::TimedOut`] |
//! | identify remote slave (46h–4Bh), identify non-configured remote slave (4Ch) | 6 / 1, any number of answers | [`LssEvent::Identified`] (0 answers after the timeout) |
//! | fastscan (51h) | [`LssMaster::fastscan`], [`LssMaster::scan_all`] | [`LssEvent::Found`] per slave, then [`LssEvent::ScanFinished`] or [`LssEvent::ScanFailed`] |
//!
//! Answers are matched to the pending service by their command specifier (and the inquired part);
//! anything else on 7E4h, including garbage, is reported as [`LssEvent::Ignored`] and changes
//! nothing. Nothing here panics on any frame, and every wait ends at a deadline, so no service
//! hangs.
//!
//! Timing. A request waits [`LssConfig::timeout`] for its first answer. After the first answer the
//! master keeps listening for [`LssConfig::settle`], so that a second slave's answer to the same
//! request is counted (identify), reported ([`LssEvent::ExtraAnswer`]: more than one slave in
//! configuration state where CiA 305 expects one) or at least not taken for the answer to the next
//! request (fastscan, where CANopenNode waits a whole timeout per step for the same reason).
//! Identical answers sent at the same moment merge into one frame on a real bus, so two slaves
//! with the same LSS address are found only when their answers arrive apart; on a virtual bus they
//! always do.
//!
//! Choice: [`LssConfig::DEFAULT`] is a 100 ms timeout and 20 ms settle. python canopen waits 0.5 s
//! per LSS response, CANopenNode masters are usually set to a few tens of milliseconds. Fastscan
//! spends one whole timeout on every step no slave answers (each 1 bit of a scanned part, and the
//! final probe), about 65 for a full 128-bit address: ~33 s at 0.5 s, ~6.5 s at 100 ms, ~1.3 s at
//! 20 ms; the settle time adds itself to each of the ~68 answered steps (~1.4 s at 20 ms). The
//! settle time covers the spread between slaves' answers to one request (a slave serving LSS from
//! a 10 ms main loop answers up to 10 ms after a fast one). Too short a timeout makes a late answer a wrong bit (the part's confirmation then fails,
//! [`ScanError::ConfirmationFailed`]) or a service [`LssEvent::TimedOut`]. 100 ms is about 20 times
//! the worst round trip measured through the socketcand hub and slcan (p99 under 6 ms) and covers
//! slaves that serve LSS from a 10 ms main loop; on a direct CAN link with fast slaves 20 ms is
//! enough, behind a slow gateway use more. [`LssStats`] counts the frames and the time spent in
//! timeouts so that the tradeoff can be measured.
//!
//! Fastscan (CiA 305 fastscan, reference §7.4, CANopenNode's master algorithm): a probe (BitChecked
//! 80h) asks whether any unconfigured slave in waiting state is there; then every part of the LSS
//! address is found bit by bit from bit 31 down (no answer means the bit is 1) and confirmed with
//! LSSNext = the next part, and the confirmation of the serial number puts exactly the slave with
//! that address into configuration state. Parts the caller knows ([`KnownParts`], CANopenNode's
//! "MATCH" mode) are only confirmed: 1 frame instead of 33. [`LssMaster::scan_all`] then gives the
//! slave a node-ID from the caller's list (configure node-ID, optionally store configuration,
//! switch state global to waiting, upon which the slave makes the node-ID active) and scans again
//! until the probe gets no answer. Slaves must be in LSS waiting state to take part.

use std::collections::{BTreeSet, VecDeque};
use std::fmt;
use std::ops::RangeInclusive;
use std::time::Duration;

use canopener_can::{CanFrame, CanId, Core, Instant, StandardId};
use canopener_wire::lss::{FASTSCAN_RESET, UNCONFIGURED_NODE_ID};
use canopener_wire::{
    IdentifyField, LSS_MASTER_TO_SLAVE_ID, LSS_SLAVE_TO_MASTER_ID, LssAddress, LssAddressPart, LssRequest,
    LssResponse, NodeId, bit_timing_text,
};

/// How long the master waits for answers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LssConfig {
    /// How long a request waits for its first answer. Silence that long ends a confirmed service
    /// with [`LssEvent::TimedOut`] and is the "no" of fastscan and identify, paid on every fastscan
    /// step no slave answers.
    pub timeout: Duration,
    /// How long the master keeps listening after the first answer, so that other slaves' answers
    /// to the same request are counted or reported instead of being taken for the answer to the
    /// next request.
    pub settle: Duration,
}

impl LssConfig {
    /// A 100 ms timeout and a 20 ms settle time; the module documentation explains the choice.
    pub const DEFAULT: LssConfig = LssConfig {
        timeout: Duration::from_millis(100),
        settle: Duration::from_millis(20),
    };
}

/// The parts of the LSS address a fastscan does not need to search, CANopenNode's "MATCH" mode:
/// each known part costs one confirmation frame instead of 32 bit steps and a confirmation. Only
/// slaves matching every known part are found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct KnownParts {
    /// 1018h:01, if known.
    pub vendor_id: Option<u32>,
    /// 1018h:02, if known.
    pub product_code: Option<u32>,
    /// 1018h:03, if known.
    pub revision_number: Option<u32>,
    /// 1018h:04, if known.
    pub serial_number: Option<u32>,
}

impl KnownParts {
    /// Nothing known: every part is searched.
    pub const NONE: KnownParts = KnownParts {
        vendor_id: None,
        product_code: None,
        revision_number: None,
        serial_number: None,
    };

    fn by_offset(&self) -> [Option<u32>; 4] {
        [
            self.vendor_id,
            self.product_code,
            self.revision_number,
            self.serial_number,
        ]
    }
}

/// What [`LssMaster::scan_all`] does with every slave it finds.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ScanPlan {
    /// The node-IDs to give, in this order, one per slave found; see [`node_id_range`].
    pub node_ids: Vec<NodeId>,
    /// Whether to send store configuration after configure node-ID, so that the slave keeps the
    /// node-ID after a power cycle.
    pub store: bool,
    /// Parts of the LSS address every wanted slave has.
    pub known: KnownParts,
}

/// The node-IDs `first` to `last` in ascending order, for [`ScanPlan::node_ids`]; empty when `first`
/// is above `last`.
pub fn node_id_range(first: NodeId, last: NodeId) -> Vec<NodeId> {
    (first.get()..=last.get()).filter_map(NodeId::new).collect()
}

/// The slaves identify remote slave asks for (CiA 305): vendor-ID and product code match exactly,
/// revision and serial number are inclusive ranges.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct IdentifyRange {
    /// 1018h:01.
    pub vendor_id: u32,
    /// 1018h:02.
    pub product_code: u32,
    /// 1018h:03 low to high.
    pub revision_number: RangeInclusive<u32>,
    /// 1018h:04 low to high.
    pub serial_number: RangeInclusive<u32>,
}

/// The target of switch state global.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LssMode {
    /// LSS waiting state (mode 0); a slave unconfigured until now makes a configured node-ID
    /// active.
    Waiting,
    /// LSS configuration state (mode 1) for every slave.
    Configuration,
}

/// An LSS service, as named in events and errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LssService {
    /// 04h.
    SwitchStateGlobal,
    /// 40h–43h, answer 44h.
    SwitchStateSelective,
    /// 11h.
    ConfigureNodeId,
    /// 13h.
    ConfigureBitTiming,
    /// 15h.
    ActivateBitTiming,
    /// 17h.
    StoreConfiguration,
    /// 5Ah–5Dh.
    InquireAddress(LssAddressPart),
    /// 5Eh.
    InquireNodeId,
    /// 46h–4Bh, answer 4Fh.
    IdentifyRemoteSlave,
    /// 4Ch, answer 50h.
    IdentifyNonConfiguredRemoteSlave,
    /// One slave by fastscan (51h), [`LssMaster::fastscan`].
    Fastscan,
    /// Fastscan and node-ID assignment until no unconfigured slave is left, [`LssMaster::scan_all`].
    ScanAll,
}

impl LssService {
    /// Whether `response` is an answer to this service.
    fn answered_by(self, response: &LssResponse) -> bool {
        match (self, response) {
            (LssService::SwitchStateSelective, LssResponse::SwitchStateSelective)
            | (LssService::ConfigureNodeId, LssResponse::ConfigureNodeId { .. })
            | (LssService::ConfigureBitTiming, LssResponse::ConfigureBitTiming { .. })
            | (LssService::StoreConfiguration, LssResponse::StoreConfiguration { .. })
            | (LssService::InquireNodeId, LssResponse::InquireNodeId { .. })
            | (LssService::IdentifyRemoteSlave, LssResponse::IdentifySlave)
            | (LssService::IdentifyNonConfiguredRemoteSlave, LssResponse::IdentifyNonConfiguredSlave)
            | (LssService::Fastscan | LssService::ScanAll, LssResponse::IdentifySlave) => true,
            (LssService::InquireAddress(asked), LssResponse::InquireAddress { part, .. }) => asked == *part,
            _ => false,
        }
    }

    /// Whether any number of slaves may answer (CiA 305 identify and fastscan); the others expect
    /// exactly one slave, the one in configuration state.
    fn expects_many(self) -> bool {
        matches!(
            self,
            LssService::IdentifyRemoteSlave
                | LssService::IdentifyNonConfiguredRemoteSlave
                | LssService::Fastscan
                | LssService::ScanAll
        )
    }
}

impl fmt::Display for LssService {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LssService::SwitchStateGlobal => f.write_str("switch state global"),
            LssService::SwitchStateSelective => f.write_str("switch state selective"),
            LssService::ConfigureNodeId => f.write_str("configure node-ID"),
            LssService::ConfigureBitTiming => f.write_str("configure bit timing"),
            LssService::ActivateBitTiming => f.write_str("activate bit timing"),
            LssService::StoreConfiguration => f.write_str("store configuration"),
            LssService::InquireAddress(part) => write!(f, "inquire {part}"),
            LssService::InquireNodeId => f.write_str("inquire node-ID"),
            LssService::IdentifyRemoteSlave => f.write_str("identify remote slave"),
            LssService::IdentifyNonConfiguredRemoteSlave => {
                f.write_str("identify non-configured remote slave")
            }
            LssService::Fastscan => f.write_str("fastscan"),
            LssService::ScanAll => f.write_str("fastscan of all unconfigured slaves"),
        }
    }
}

/// The error code a slave answered configure node-ID, configure bit timing or store
/// configuration with (CiA 305 error codes, reference §7.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error)]
pub enum LssServiceError {
    /// Configure node-ID, error code 1.
    #[error("node-ID out of range")]
    NodeIdOutOfRange,
    /// Configure bit timing, error code 1.
    #[error("bit rate not supported")]
    BitRateNotSupported,
    /// Store configuration, error code 1.
    #[error("storing not supported")]
    StoringNotSupported,
    /// Store configuration, error code 2.
    #[error("storage media access error")]
    StorageMediaAccess,
    /// Error code FFh: implementation-specific, with the slave's specific error (D2).
    #[error("implementation-specific error {0:#04X}")]
    Specific(u8),
    /// An error code CiA 305 reserves.
    #[error("reserved error code {0}")]
    Reserved(u8),
}

impl LssServiceError {
    /// The meaning of error code `error` (D1) with specific error `spec_error` (D2) in the answer
    /// to `service`.
    pub fn decode(service: LssService, error: u8, spec_error: u8) -> Result<(), LssServiceError> {
        match (error, service) {
            (0, _) => Ok(()),
            (0xFF, _) => Err(LssServiceError::Specific(spec_error)),
            (1, LssService::ConfigureNodeId) => Err(LssServiceError::NodeIdOutOfRange),
            (1, LssService::ConfigureBitTiming) => Err(LssServiceError::BitRateNotSupported),
            (1, LssService::StoreConfiguration) => Err(LssServiceError::StoringNotSupported),
            (2, LssService::StoreConfiguration) => Err(LssServiceError::StorageMediaAccess),
            (code, _) => Err(LssServiceError::Reserved(code)),
        }
    }
}

/// Why a fastscan stopped before the probe found no more slaves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error)]
pub enum ScanError {
    /// No slave confirmed a part found bit by bit: an answer came after the timeout (or the
    /// settle time), or a slave left the bus.
    #[error("no slave confirmed the {part} found bit by bit; an answer may have come too late")]
    ConfirmationFailed {
        /// The part.
        part: LssAddressPart,
    },
    /// More than one slave answered where only the one with this address may: the slaves share the
    /// LSS address and cannot be told apart. They were sent back to waiting without a node-ID.
    #[error("more than one slave has the LSS address {address}")]
    SameAddress {
        /// The shared address.
        address: LssAddress,
    },
    /// The slave refused the node-ID; it was sent back to waiting.
    #[error("the slave with {address} refused node-ID {node_id}: {error}")]
    NodeIdRefused {
        /// The slave.
        address: LssAddress,
        /// The node-ID.
        node_id: NodeId,
        /// Its answer.
        error: LssServiceError,
    },
    /// The slave did not answer configure node-ID; it was sent back to waiting.
    #[error("the slave with {address} did not answer configure node-ID {node_id}")]
    NoAnswer {
        /// The slave.
        address: LssAddress,
        /// The node-ID.
        node_id: NodeId,
    },
    /// An unconfigured slave (matching the known parts) is left but every node-ID of the plan is
    /// used; it is in waiting state.
    #[error("an unconfigured slave is left but every node-ID given is used")]
    NoNodeIdLeft,
}

/// Why a frame on 7E4h was ignored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum IgnoredReason {
    /// A remote frame.
    Remote,
    /// A data frame whose DLC is not 8.
    WrongLength(u8),
    /// D0 is no command specifier a slave sends.
    UnknownCommand(u8),
    /// A well-formed answer no pending request asked for (or one arriving after its request was
    /// settled).
    NotAwaited,
}

impl fmt::Display for IgnoredReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            IgnoredReason::Remote => f.write_str("remote frame"),
            IgnoredReason::WrongLength(dlc) => write!(f, "DLC {dlc}, not 8"),
            IgnoredReason::UnknownCommand(cs) => write!(f, "unknown command specifier {cs:#04X}"),
            IgnoredReason::NotAwaited => f.write_str("no request waits for this answer"),
        }
    }
}

/// What the master reports: the end of every service, fastscan progress, and answers it ignored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LssEvent {
    /// An unconfirmed service was sent (switch state global), switch state selective was
    /// answered 44h, or activate bit timing's two switch delays are over.
    Done {
        /// The service.
        service: LssService,
    },
    /// Configure node-ID, configure bit timing or store configuration answered.
    Configured {
        /// The service.
        service: LssService,
        /// Success, or the error code the slave answered.
        result: Result<(), LssServiceError>,
    },
    /// Inquire identity answered.
    Inquired {
        /// The part asked for.
        part: LssAddressPart,
        /// Its value.
        value: u32,
    },
    /// Inquire node-ID answered: 1 to 127, or FFh when the slave is unconfigured (as sent, a slave
    /// may answer anything).
    NodeIdInquired {
        /// The node-ID.
        node_id: u8,
    },
    /// Identify remote slave or identify non-configured remote slave: how many answers came (0
    /// after the timeout). On a real bus identical answers sent together merge into one frame,
    /// so more than 0 means "at least one".
    Identified {
        /// The service.
        service: LssService,
        /// The answers counted.
        answers: usize,
    },
    /// Activate bit timing: the first switch delay is over; switch the master's CAN controller to
    /// the new bit rate now, and send nothing until [`LssEvent::Done`].
    SwitchBitRate,
    /// No slave answered within the timeout.
    TimedOut {
        /// The service.
        service: LssService,
        /// How long the master waited.
        after: Duration,
    },
    /// A second answer where CiA 305 expects one (from the one slave in configuration state):
    /// more slaves are in configuration state, for example two with the same LSS address. The
    /// service's result is the first answer.
    ExtraAnswer {
        /// The service.
        service: LssService,
        /// The additional answer.
        response: LssResponse,
    },
    /// A frame on 7E4h that answers nothing pending, or is no LSS answer at all; it changed
    /// nothing.
    Ignored {
        /// The frame.
        frame: CanFrame,
        /// Why.
        reason: IgnoredReason,
    },
    /// Fastscan found a slave, which is now in configuration state ([`LssMaster::fastscan`]) or
    /// runs with `node_id` ([`LssMaster::scan_all`]).
    Found {
        /// The slave's LSS address.
        address: LssAddress,
        /// The node-ID it was given.
        node_id: Option<NodeId>,
    },
    /// The scan is over: the probe found no more unconfigured slave, or none matching the known
    /// parts (or [`LssMaster::fastscan`] found its one slave).
    ScanFinished {
        /// Slaves found by this scan.
        found: usize,
    },
    /// The scan stopped early.
    ScanFailed {
        /// Slaves found (and configured) before.
        found: usize,
        /// Why.
        error: ScanError,
    },
}

/// `configure node-ID: node-ID out of range`, `found vendor-id 0x… -> node-ID 5`, …
impl fmt::Display for LssEvent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LssEvent::Done { service } => write!(f, "{service}: done"),
            LssEvent::Configured {
                service,
                result: Ok(()),
            } => write!(f, "{service}: success"),
            LssEvent::Configured {
                service,
                result: Err(err),
            } => write!(f, "{service}: {err}"),
            LssEvent::Inquired { part, value } => write!(f, "{part} = 0x{value:08X}"),
            LssEvent::NodeIdInquired {
                node_id: UNCONFIGURED_NODE_ID,
            } => f.write_str("node-ID = unconfigured (FFh)"),
            LssEvent::NodeIdInquired { node_id } => write!(f, "node-ID = {node_id}"),
            LssEvent::Identified { service, answers: 0 } => write!(f, "{service}: no slave answered"),
            LssEvent::Identified { service, answers } => write!(f, "{service}: {answers} answer(s)"),
            LssEvent::SwitchBitRate => f.write_str("activate bit timing: switch the bit rate now"),
            LssEvent::TimedOut { service, after } => write!(f, "{service}: no answer within {after:?}"),
            LssEvent::ExtraAnswer { service, response } => {
                write!(f, "{service}: another slave answered too ({response})")
            }
            LssEvent::Ignored { frame, reason } => write!(f, "ignored {frame}: {reason}"),
            LssEvent::Found {
                address,
                node_id: None,
            } => write!(f, "found {address}"),
            LssEvent::Found {
                address,
                node_id: Some(node),
            } => write!(f, "found {address} -> node-ID {node}"),
            LssEvent::ScanFinished { found } => write!(f, "scan finished: {found} slave(s) found"),
            LssEvent::ScanFailed { found, error } => {
                write!(f, "scan failed after {found} slave(s) found: {error}")
            }
        }
    }
}

/// Why a service could not be started.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error)]
pub enum LssCommandError {
    /// Another service runs; CiA 305 services share one pair of CAN-IDs, so they cannot overlap.
    #[error("the LSS master is busy with {running}")]
    Busy {
        /// The running service.
        running: LssService,
    },
    /// Configure bit timing with an index outside the CiA 305 table, or the reserved index 5
    /// (formerly 100 kbit/s), which a master should not send (reference §7.3).
    #[error("bit timing index {0} is not in the CiA 305 table (0-4, 6-9; 5 is reserved)")]
    BitTimingIndex(u8),
    /// Identify remote slave with a range that contains no value.
    #[error("the {0} range of identify remote slave is empty")]
    EmptyRange(LssAddressPart),
    /// A node-ID appears twice in a [`ScanPlan`].
    #[error("node-ID {0} appears twice in the scan plan")]
    DuplicateNodeId(NodeId),
}

/// Counters since the master was made or [`LssMaster::take_stats`] was called.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct LssStats {
    /// Frames sent on 7E5h.
    pub sent: u64,
    /// Frames received on 7E4h, ignored ones included.
    pub received: u64,
    /// Requests no slave answered within the timeout.
    pub timeouts: u64,
    /// Time spent waiting for those: `timeouts` times the timeout.
    pub silence: Duration,
}

/// The LSS master: every CiA 305 service, one at a time, sans IO.
///
/// Start a service with one of its methods, then feed frames ([`LssMaster::handle_frame`]) and
/// time ([`LssMaster::handle_timeout`] whenever [`LssMaster::poll_timeout`] is due) and drain
/// [`LssMaster::poll_transmit`] and [`LssMaster::poll_event`]. Answers that arrive at the same
/// instant as a deadline must be fed before the timeout is handled.
#[derive(Debug, Clone)]
pub struct LssMaster {
    config: LssConfig,
    job: Job,
    wait: Option<Wait>,
    transmit: VecDeque<CanFrame>,
    events: VecDeque<LssEvent>,
    stats: LssStats,
}

impl LssMaster {
    /// An idle master.
    pub fn new(config: LssConfig) -> LssMaster {
        LssMaster {
            config,
            job: Job::Idle,
            wait: None,
            transmit: VecDeque::new(),
            events: VecDeque::new(),
            stats: LssStats::default(),
        }
    }

    /// The timing in use.
    pub fn config(&self) -> LssConfig {
        self.config
    }

    /// The service running, if any.
    pub fn running(&self) -> Option<LssService> {
        match &self.job {
            Job::Idle => None,
            Job::Single(service) => Some(*service),
            Job::Activate { .. } => Some(LssService::ActivateBitTiming),
            Job::Scan(scan) if scan.assign.is_some() => Some(LssService::ScanAll),
            Job::Scan(_) => Some(LssService::Fastscan),
        }
    }

    /// The counters so far.
    pub fn stats(&self) -> LssStats {
        self.stats
    }

    /// The counters so far; they restart from zero.
    pub fn take_stats(&mut self) -> LssStats {
        std::mem::take(&mut self.stats)
    }

    /// Switch state global (04h): every slave enters `mode`. Unconfirmed: ends at once with
    /// [`LssEvent::Done`].
    pub fn switch_state_global(&mut self, mode: LssMode) -> Result<(), LssCommandError> {
        self.ensure_idle()?;
        let mode = match mode {
            LssMode::Waiting => 0,
            LssMode::Configuration => 1,
        };
        self.send(LssRequest::SwitchStateGlobal { mode });
        self.events.push_back(LssEvent::Done {
            service: LssService::SwitchStateGlobal,
        });
        Ok(())
    }

    /// Switch state selective (40h–43h): the slave with `address` enters configuration state and
    /// answers 44h.
    pub fn switch_state_selective(
        &mut self,
        now: Instant,
        address: LssAddress,
    ) -> Result<(), LssCommandError> {
        self.ensure_idle()?;
        for part in PARTS {
            let value = address.part(part);
            self.send(LssRequest::SwitchStateSelective { part, value });
        }
        self.start(now, LssService::SwitchStateSelective);
        Ok(())
    }

    /// Configure node-ID (11h) of the slave in configuration state: `Some` node-ID, or `None` for
    /// FFh, unconfigured.
    pub fn configure_node_id(
        &mut self,
        now: Instant,
        node_id: Option<NodeId>,
    ) -> Result<(), LssCommandError> {
        self.configure_node_id_raw(now, node_id.map_or(UNCONFIGURED_NODE_ID, NodeId::get))
    }

    /// [`LssMaster::configure_node_id`] with any byte, so that a slave's "node-ID out of range"
    /// can be tested.
    pub fn configure_node_id_raw(&mut self, now: Instant, node_id: u8) -> Result<(), LssCommandError> {
        self.ensure_idle()?;
        self.send(LssRequest::ConfigureNodeId { node_id });
        self.start(now, LssService::ConfigureNodeId);
        Ok(())
    }

    /// Configure bit timing (13h) of the slave in configuration state: entry `index` of the CiA
    /// 305 table (table selector 0), see [`canopener_wire::bit_timing_text`].
    pub fn configure_bit_timing(&mut self, now: Instant, index: u8) -> Result<(), LssCommandError> {
        if index == 5 || bit_timing_text(index).is_none() {
            return Err(LssCommandError::BitTimingIndex(index));
        }
        self.ensure_idle()?;
        self.send(LssRequest::ConfigureBitTiming { table: 0, index });
        self.start(now, LssService::ConfigureBitTiming);
        Ok(())
    }

    /// Activate bit timing (15h), CiA 305: every slave in configuration state waits `delay_ms`,
    /// switches to its pending bit rate and waits `delay_ms` again before sending. The master
    /// does the same: [`LssEvent::SwitchBitRate`] after the first delay, [`LssEvent::Done`] after
    /// the second; it stays busy meanwhile.
    pub fn activate_bit_timing(&mut self, now: Instant, delay_ms: u16) -> Result<(), LssCommandError> {
        self.ensure_idle()?;
        self.send(LssRequest::ActivateBitTiming { delay_ms });
        let delay = Duration::from_millis(u64::from(delay_ms));
        self.job = Job::Activate {
            switch_at: now + delay,
            done_at: now + delay + delay,
            switched: false,
        };
        Ok(())
    }

    /// Store configuration (17h) of the slave in configuration state.
    pub fn store_configuration(&mut self, now: Instant) -> Result<(), LssCommandError> {
        self.ensure_idle()?;
        self.send(LssRequest::StoreConfiguration);
        self.start(now, LssService::StoreConfiguration);
        Ok(())
    }

    /// Inquire identity (5Ah–5Dh): one part of the LSS address of the slave in configuration
    /// state.
    pub fn inquire_address(&mut self, now: Instant, part: LssAddressPart) -> Result<(), LssCommandError> {
        self.ensure_idle()?;
        self.send(LssRequest::InquireAddress(part));
        self.start(now, LssService::InquireAddress(part));
        Ok(())
    }

    /// Inquire node-ID (5Eh) of the slave in configuration state.
    pub fn inquire_node_id(&mut self, now: Instant) -> Result<(), LssCommandError> {
        self.ensure_idle()?;
        self.send(LssRequest::InquireNodeId);
        self.start(now, LssService::InquireNodeId);
        Ok(())
    }

    /// Identify remote slave (46h–4Bh): every slave inside `range` answers 4Fh.
    pub fn identify_remote_slave(
        &mut self,
        now: Instant,
        range: &IdentifyRange,
    ) -> Result<(), LssCommandError> {
        if range.revision_number.is_empty() {
            return Err(LssCommandError::EmptyRange(LssAddressPart::RevisionNumber));
        }
        if range.serial_number.is_empty() {
            return Err(LssCommandError::EmptyRange(LssAddressPart::SerialNumber));
        }
        self.ensure_idle()?;
        let bounds = [
            (IdentifyField::VendorId, range.vendor_id),
            (IdentifyField::ProductCode, range.product_code),
            (IdentifyField::RevisionLow, *range.revision_number.start()),
            (IdentifyField::RevisionHigh, *range.revision_number.end()),
            (IdentifyField::SerialLow, *range.serial_number.start()),
            (IdentifyField::SerialHigh, *range.serial_number.end()),
        ];
        for (field, value) in bounds {
            self.send(LssRequest::IdentifyRemoteSlave { field, value });
        }
        self.start(now, LssService::IdentifyRemoteSlave);
        Ok(())
    }

    /// Identify non-configured remote slave (4Ch): every slave without node-ID answers 50h.
    pub fn identify_non_configured(&mut self, now: Instant) -> Result<(), LssCommandError> {
        self.ensure_idle()?;
        self.send(LssRequest::IdentifyNonConfiguredRemoteSlave);
        self.start(now, LssService::IdentifyNonConfiguredRemoteSlave);
        Ok(())
    }

    /// Fastscan for one unconfigured slave in waiting state that matches `known`: ends with
    /// [`LssEvent::Found`] (the slave is then in configuration state, ready for the configuration
    /// services) and [`LssEvent::ScanFinished`], or [`LssEvent::ScanFinished`] with `found: 0`.
    pub fn fastscan(&mut self, now: Instant, known: KnownParts) -> Result<(), LssCommandError> {
        self.ensure_idle()?;
        self.begin_scan(now, known, None);
        Ok(())
    }

    /// Fastscan repeated until no unconfigured slave (matching `plan.known`) answers: each slave
    /// found gets the next node-ID of `plan.node_ids` (configure node-ID, store configuration if
    /// asked, switch state global to waiting) and is reported with [`LssEvent::Found`]; the scan
    /// ends with [`LssEvent::ScanFinished`] or [`LssEvent::ScanFailed`]. A store configuration
    /// the slave refuses or does not answer is reported ([`LssEvent::Configured`],
    /// [`LssEvent::TimedOut`]) and the scan goes on: the node-ID works, it is only not kept over
    /// a power cycle.
    pub fn scan_all(&mut self, now: Instant, plan: ScanPlan) -> Result<(), LssCommandError> {
        let mut seen = BTreeSet::new();
        if let Some(twice) = plan.node_ids.iter().find(|node| !seen.insert(**node)) {
            return Err(LssCommandError::DuplicateNodeId(*twice));
        }
        self.ensure_idle()?;
        let assign = Assign {
            node_ids: plan.node_ids.into(),
            store: plan.store,
        };
        self.begin_scan(now, plan.known, Some(assign));
        Ok(())
    }

    /// Feeds a received frame. Only frames on CAN-ID 7E4h (11-bit) concern the LSS master;
    /// returns whether the frame was one.
    pub fn accept_frame(&mut self, now: Instant, frame: &CanFrame) -> bool {
        if frame.id() != slave_id() {
            return false;
        }
        self.stats.received += 1;
        if frame.is_remote() {
            self.ignore(frame, IgnoredReason::Remote);
            return true;
        }
        let Ok(data) = <[u8; 8]>::try_from(frame.data()) else {
            self.ignore(frame, IgnoredReason::WrongLength(frame.dlc()));
            return true;
        };
        let Ok(response) = LssResponse::parse(&data) else {
            self.ignore(frame, IgnoredReason::UnknownCommand(data[0]));
            return true;
        };
        let settle = self.config.settle;
        match &mut self.wait {
            Some(wait) if wait.service.answered_by(&response) => {
                wait.answers += 1;
                if wait.first.is_none() {
                    wait.first = Some(response);
                    wait.deadline = now + settle;
                } else if !wait.service.expects_many() {
                    let service = wait.service;
                    self.events.push_back(LssEvent::ExtraAnswer { service, response });
                }
            }
            _ => self.ignore(frame, IgnoredReason::NotAwaited),
        }
        true
    }

    fn ensure_idle(&self) -> Result<(), LssCommandError> {
        match self.running() {
            Some(running) => Err(LssCommandError::Busy { running }),
            None => Ok(()),
        }
    }

    fn send(&mut self, request: LssRequest) {
        // 7E5h is a valid 11-bit identifier and 8 bytes fit a classical frame; neither fails.
        if let Ok(frame) = CanFrame::new(master_id(), &request.encode()) {
            self.stats.sent += 1;
            self.transmit.push_back(frame);
        }
    }

    /// Starts a single-request service whose answer the master now waits for.
    fn start(&mut self, now: Instant, service: LssService) {
        self.job = Job::Single(service);
        self.expect(now, service);
    }

    fn expect(&mut self, now: Instant, service: LssService) {
        self.wait = Some(Wait {
            service,
            sent_at: now,
            deadline: now + self.config.timeout,
            first: None,
            answers: 0,
        });
    }

    fn ignore(&mut self, frame: &CanFrame, reason: IgnoredReason) {
        self.events.push_back(LssEvent::Ignored {
            frame: *frame,
            reason,
        });
    }

    /// A wait is over: its answers (if any) go to the running service.
    fn settled(&mut self, now: Instant, wait: Wait) {
        if wait.first.is_none() {
            self.stats.timeouts += 1;
            self.stats.silence += wait.deadline - wait.sent_at;
        }
        match std::mem::replace(&mut self.job, Job::Idle) {
            Job::Single(service) => self.finish_single(service, &wait),
            Job::Scan(mut scan) => match self.scan_step(now, &mut scan, &wait) {
                None => self.job = Job::Scan(scan),
                Some(Ok(())) => self
                    .events
                    .push_back(LssEvent::ScanFinished { found: scan.found }),
                Some(Err(error)) => self.events.push_back(LssEvent::ScanFailed {
                    found: scan.found,
                    error,
                }),
            },
            // A wait only exists while a single service or a scan runs.
            job @ (Job::Idle | Job::Activate { .. }) => self.job = job,
        }
    }

    fn finish_single(&mut self, service: LssService, wait: &Wait) {
        let event = match wait.first {
            None if service.expects_many() => LssEvent::Identified { service, answers: 0 },
            None => LssEvent::TimedOut {
                service,
                after: self.config.timeout,
            },
            Some(LssResponse::SwitchStateSelective) => LssEvent::Done { service },
            Some(
                LssResponse::ConfigureNodeId { error, spec_error }
                | LssResponse::ConfigureBitTiming { error, spec_error }
                | LssResponse::StoreConfiguration { error, spec_error },
            ) => LssEvent::Configured {
                service,
                result: LssServiceError::decode(service, error, spec_error),
            },
            Some(LssResponse::IdentifySlave | LssResponse::IdentifyNonConfiguredSlave) => {
                LssEvent::Identified {
                    service,
                    answers: wait.answers,
                }
            }
            Some(LssResponse::InquireAddress { part, value }) => LssEvent::Inquired { part, value },
            Some(LssResponse::InquireNodeId { node_id }) => LssEvent::NodeIdInquired { node_id },
        };
        self.events.push_back(event);
    }

    fn begin_scan(&mut self, now: Instant, known: KnownParts, assign: Option<Assign>) {
        let mut scan = Box::new(Scan {
            known: known.by_offset(),
            assign,
            found: 0,
            address: [0; 4],
            step: Step::Probe,
        });
        self.probe(now, &mut scan);
        self.job = Job::Scan(scan);
    }

    /// One fastscan wait is over; returns `Some` when the scan ends.
    fn scan_step(&mut self, now: Instant, scan: &mut Scan, wait: &Wait) -> Option<Result<(), ScanError>> {
        let answered = wait.first.is_some();
        match scan.step {
            Step::Probe if !answered => return Some(Ok(())),
            Step::Probe => {
                // Without known parts any unconfigured slave is wanted: no need to search it when
                // there is no node-ID left for it. With known parts the search tells.
                let unknown = scan.known.iter().all(Option::is_none);
                let exhausted = scan
                    .assign
                    .as_ref()
                    .is_some_and(|assign| assign.node_ids.is_empty());
                if unknown && exhausted {
                    return Some(Err(ScanError::NoNodeIdLeft));
                }
                self.start_part(now, scan, 0);
            }
            Step::Bit { sub, bit, id } => {
                // Silence: no slave has a 0 here, so the bit is 1 (reference §7.4).
                let id = if answered { id } else { id | (1 << bit) };
                match bit.checked_sub(1) {
                    Some(lower) => self.bit_step(now, scan, sub, lower, id),
                    None => self.confirm(now, scan, sub, id),
                }
            }
            Step::Confirm { sub, id } => {
                let known = scan.known.get(usize::from(sub)).copied().flatten().is_some();
                if !answered && known {
                    // No unconfigured slave has the known part: nothing (more) to find.
                    return Some(Ok(()));
                }
                if !answered {
                    return Some(Err(ScanError::ConfirmationFailed { part: part_at(sub) }));
                }
                if let Some(slot) = scan.address.get_mut(usize::from(sub)) {
                    *slot = id;
                }
                if sub < LAST_PART {
                    self.start_part(now, scan, sub + 1);
                } else if wait.answers > 1 {
                    // Every slave with this whole address entered configuration state.
                    self.switch_all_to_waiting();
                    return Some(Err(ScanError::SameAddress {
                        address: scan.found_address(),
                    }));
                } else {
                    return self.found(now, scan);
                }
            }
            Step::ConfigureNodeId { node } => {
                let address = scan.found_address();
                // The wait takes only configure node-ID answers, so `first` is one or nothing.
                let Some(LssResponse::ConfigureNodeId { error, spec_error }) = wait.first else {
                    self.switch_all_to_waiting();
                    return Some(Err(ScanError::NoAnswer {
                        address,
                        node_id: node,
                    }));
                };
                if wait.answers > 1 {
                    // Two slaves took the node-ID: take it back before they make it active.
                    self.send(LssRequest::ConfigureNodeId {
                        node_id: UNCONFIGURED_NODE_ID,
                    });
                    self.expect(now, LssService::ConfigureNodeId);
                    scan.step = Step::Revert;
                } else if let Err(error) =
                    LssServiceError::decode(LssService::ConfigureNodeId, error, spec_error)
                {
                    self.switch_all_to_waiting();
                    return Some(Err(ScanError::NodeIdRefused {
                        address,
                        node_id: node,
                        error,
                    }));
                } else if scan.assign.as_ref().is_some_and(|assign| assign.store) {
                    self.send(LssRequest::StoreConfiguration);
                    self.expect(now, LssService::StoreConfiguration);
                    scan.step = Step::Store { node };
                } else {
                    self.configured(now, scan, node);
                }
            }
            Step::Revert => {
                self.switch_all_to_waiting();
                return Some(Err(ScanError::SameAddress {
                    address: scan.found_address(),
                }));
            }
            Step::Store { node } => {
                let service = LssService::StoreConfiguration;
                match wait.first {
                    None => self.events.push_back(LssEvent::TimedOut {
                        service,
                        after: self.config.timeout,
                    }),
                    Some(LssResponse::StoreConfiguration { error, spec_error }) => {
                        if let Err(err) = LssServiceError::decode(service, error, spec_error) {
                            self.events.push_back(LssEvent::Configured {
                                service,
                                result: Err(err),
                            });
                        }
                    }
                    Some(_) => {}
                }
                self.configured(now, scan, node);
            }
        }
        None
    }

    fn probe(&mut self, now: Instant, scan: &mut Scan) {
        scan.step = Step::Probe;
        self.fastscan_request(now, 0, FASTSCAN_RESET, 0, 0);
    }

    fn start_part(&mut self, now: Instant, scan: &mut Scan, sub: u8) {
        match scan.known.get(usize::from(sub)).copied().flatten() {
            Some(value) => self.confirm(now, scan, sub, value),
            None => self.bit_step(now, scan, sub, 31, 0),
        }
    }

    fn bit_step(&mut self, now: Instant, scan: &mut Scan, sub: u8, bit: u8, id: u32) {
        scan.step = Step::Bit { sub, bit, id };
        self.fastscan_request(now, id, bit, sub, sub);
    }

    /// Confirms part `sub` as `id`; the matching slaves move on to the next part, and after the
    /// serial number (next = vendor-ID, 0) the one slave left enters configuration state.
    fn confirm(&mut self, now: Instant, scan: &mut Scan, sub: u8, id: u32) {
        scan.step = Step::Confirm { sub, id };
        let next = if sub < LAST_PART { sub + 1 } else { 0 };
        self.fastscan_request(now, id, 0, sub, next);
    }

    fn fastscan_request(&mut self, now: Instant, id_number: u32, bit_checked: u8, lss_sub: u8, lss_next: u8) {
        self.send(LssRequest::Fastscan {
            id_number,
            bit_checked,
            lss_sub,
            lss_next,
        });
        self.expect(now, LssService::Fastscan);
    }

    /// The slave with the scanned address is the only one in configuration state.
    fn found(&mut self, now: Instant, scan: &mut Scan) -> Option<Result<(), ScanError>> {
        let node = match &mut scan.assign {
            None => {
                scan.found += 1;
                self.events.push_back(LssEvent::Found {
                    address: scan.found_address(),
                    node_id: None,
                });
                return Some(Ok(()));
            }
            Some(assign) => assign.node_ids.pop_front(),
        };
        let Some(node) = node else {
            self.switch_all_to_waiting();
            return Some(Err(ScanError::NoNodeIdLeft));
        };
        self.send(LssRequest::ConfigureNodeId { node_id: node.get() });
        self.expect(now, LssService::ConfigureNodeId);
        scan.step = Step::ConfigureNodeId { node };
        None
    }

    /// The slave took `node`: back to waiting, where it makes the node-ID active, then look for
    /// the next one.
    fn configured(&mut self, now: Instant, scan: &mut Scan, node: NodeId) {
        self.switch_all_to_waiting();
        scan.found += 1;
        self.events.push_back(LssEvent::Found {
            address: scan.found_address(),
            node_id: Some(node),
        });
        self.probe(now, scan);
    }

    fn switch_all_to_waiting(&mut self) {
        self.send(LssRequest::SwitchStateGlobal { mode: 0 });
    }
}

impl Core for LssMaster {
    type Event = LssEvent;

    fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
        self.accept_frame(now, frame);
    }

    /// Lets time pass: ends the waits and switch delays due at `now`.
    fn handle_timeout(&mut self, now: Instant) {
        if let Job::Activate {
            switch_at,
            done_at,
            switched,
        } = &mut self.job
        {
            if !*switched && now >= *switch_at {
                *switched = true;
                self.events.push_back(LssEvent::SwitchBitRate);
            }
            if now >= *done_at {
                self.job = Job::Idle;
                self.events.push_back(LssEvent::Done {
                    service: LssService::ActivateBitTiming,
                });
            }
        }
        if let Some(wait) = self.wait.take_if(|wait| wait.deadline <= now) {
            self.settled(now, wait);
        }
    }

    /// The next frame to send.
    fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.transmit.pop_front()
    }

    /// The next event.
    fn poll_event(&mut self) -> Option<Self::Event> {
        self.events.pop_front()
    }

    /// When [`LssMaster::handle_timeout`] wants to be called next.
    fn poll_timeout(&self) -> Option<Instant> {
        let activate = match self.job {
            Job::Activate {
                switch_at,
                switched: false,
                ..
            } => Some(switch_at),
            Job::Activate { done_at, .. } => Some(done_at),
            _ => None,
        };
        [activate, self.wait.as_ref().map(|wait| wait.deadline)]
            .into_iter()
            .flatten()
            .min()
    }
}

/// The address parts in fastscan order (LSSSub 0 to 3).
const PARTS: [LssAddressPart; 4] = LssAddressPart::ALL;

/// LSSSub of the serial number, the part whose confirmation ends the search.
const LAST_PART: u8 = 3;

fn part_at(sub: u8) -> LssAddressPart {
    LssAddressPart::from_offset(sub).unwrap_or(LssAddressPart::SerialNumber)
}

fn slave_id() -> CanId {
    // 7E4h fits 11 bits.
    CanId::Standard(StandardId::new(LSS_SLAVE_TO_MASTER_ID).unwrap_or(StandardId::MAX))
}

fn master_id() -> StandardId {
    // 7E5h fits 11 bits.
    StandardId::new(LSS_MASTER_TO_SLAVE_ID).unwrap_or(StandardId::MAX)
}

/// What the running service is.
#[derive(Debug, Clone)]
enum Job {
    Idle,
    /// A service of one request (or one group of frames) and one wait.
    Single(LssService),
    /// Activate bit timing: the two switch delays.
    Activate {
        switch_at: Instant,
        done_at: Instant,
        switched: bool,
    },
    Scan(Box<Scan>),
}

/// The answers to the request last sent.
#[derive(Debug, Clone, Copy)]
struct Wait {
    service: LssService,
    sent_at: Instant,
    /// The timeout, or the end of the settle time once an answer came.
    deadline: Instant,
    first: Option<LssResponse>,
    answers: usize,
}

#[derive(Debug, Clone)]
struct Scan {
    known: [Option<u32>; 4],
    /// `None` for [`LssMaster::fastscan`], which leaves the slave found in configuration state.
    assign: Option<Assign>,
    found: usize,
    address: [u32; 4],
    step: Step,
}

impl Scan {
    fn found_address(&self) -> LssAddress {
        LssAddress::from_parts(self.address)
    }
}

#[derive(Debug, Clone)]
struct Assign {
    node_ids: VecDeque<NodeId>,
    store: bool,
}

/// The fastscan request waiting for its answers.
#[derive(Debug, Clone, Copy)]
enum Step {
    /// BitChecked 80h: is any unconfigured slave there?
    Probe,
    /// Bits 31..`bit` of part `sub`, bits above `bit` already found in `id`.
    Bit {
        sub: u8,
        bit: u8,
        id: u32,
    },
    /// Part `sub` is `id`.
    Confirm {
        sub: u8,
        id: u32,
    },
    ConfigureNodeId {
        node: NodeId,
    },
    /// Configure node-ID FFh after two slaves took one node-ID.
    Revert,
    Store {
        node: NodeId,
    },
}

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_can::candump::parse_compact_frame;
    use canopener_device::lss_slave::{LssEvent as SlaveEvent, LssSlave, LssState};

    const A: LssAddress = LssAddress {
        vendor_id: 0x0000_031A,
        product_code: 0x0000_1234,
        revision_number: 0x0001_0002,
        serial_number: 0x0000_CAFE,
    };

    const ALL_KNOWN: KnownParts = KnownParts {
        vendor_id: Some(A.vendor_id),
        product_code: Some(A.product_code),
        revision_number: Some(A.revision_number),
        serial_number: Some(A.serial_number),
    };

    fn identity(address: LssAddress) -> LssAddress {
        LssAddress {
            vendor_id: address.vendor_id,
            product_code: address.product_code,
            revision_number: address.revision_number,
            serial_number: address.serial_number,
        }
    }

    fn node(raw: u8) -> NodeId {
        NodeId::new(raw).unwrap()
    }

    fn plan(node_ids: &[u8], store: bool, known: KnownParts) -> ScanPlan {
        ScanPlan {
            node_ids: node_ids.iter().map(|raw| node(*raw)).collect(),
            store,
            known,
        }
    }

    /// A slave frame (7E4h) from the leading hex bytes, padded with zeros to 8 bytes.
    fn s(hex: &str) -> String {
        format!("7E4#{hex:0<16}")
    }

    /// A master frame (7E5h) from the leading hex bytes, padded with zeros to 8 bytes.
    fn m(hex: &str) -> String {
        format!("7E5#{hex:0<16}")
    }

    fn stamp(now: Instant) -> String {
        let micros = now.as_micros();
        format!("{}.{:03}", micros / 1000, micros % 1000)
    }

    /// Who answers the master's frames at the instant they are sent.
    enum Partner {
        /// A real LSS slave of the device crate.
        Slave(Box<LssSlave>),
        /// Answers requests as the closure says.
        Script(Box<dyn Respond>),
    }

    trait Respond {
        fn respond(&mut self, request: &LssRequest) -> Vec<CanFrame>;
    }

    impl<F: FnMut(&LssRequest) -> Vec<CanFrame>> Respond for F {
        fn respond(&mut self, request: &LssRequest) -> Vec<CanFrame> {
            self(request)
        }
    }

    impl Partner {
        fn answer(&mut self, now: Instant, frame: &CanFrame) -> Vec<CanFrame> {
            match self {
                Partner::Slave(slave) => {
                    slave.handle_frame(now, frame);
                    while let Some(event) = slave.poll_event() {
                        // What the `Device` does: the configured node-ID becomes active.
                        if event == SlaveEvent::ResetCommunication {
                            slave.reset_communication();
                        }
                    }
                    std::iter::from_fn(|| slave.poll_transmit()).collect()
                }
                Partner::Script(script) => {
                    let data = <[u8; 8]>::try_from(frame.data()).unwrap();
                    script.respond(&LssRequest::parse(&data).unwrap())
                }
            }
        }

        fn slave(&self) -> &LssSlave {
            match self {
                Partner::Slave(slave) => slave,
                Partner::Script(_) => panic!("not a slave"),
            }
        }
    }

    fn answer(response: LssResponse) -> Vec<CanFrame> {
        vec![CanFrame::new(slave_id(), &response.encode()).unwrap()]
    }

    fn answers(hex: &[&str]) -> Vec<CanFrame> {
        hex.iter()
            .map(|hex| parse_compact_frame(&s(hex)).unwrap())
            .collect()
    }

    /// A master on virtual time with its partners; what is sent, received and reported, as
    /// `"<ms>.<µs> tx|rx <frame>"` and `"<ms>.<µs> <event>"` lines.
    struct Trace {
        master: LssMaster,
        partners: Vec<Partner>,
        now: Instant,
        log: Vec<String>,
        events: Vec<LssEvent>,
    }

    impl Trace {
        fn new() -> Trace {
            Trace::with(Vec::new())
        }

        fn with(partners: Vec<Partner>) -> Trace {
            Trace {
                master: LssMaster::new(LssConfig::DEFAULT),
                partners,
                now: Instant::ZERO,
                log: Vec::new(),
                events: Vec::new(),
            }
        }

        fn slaves(addresses: &[LssAddress]) -> Trace {
            let slaves = addresses
                .iter()
                .map(|address| Partner::Slave(Box::new(LssSlave::new(identity(*address), None))))
                .collect();
            Trace::with(slaves)
        }

        fn script(script: impl FnMut(&LssRequest) -> Vec<CanFrame> + 'static) -> Trace {
            Trace::with(vec![Partner::Script(Box::new(script))])
        }

        fn pump(&mut self) {
            let now = self.now;
            while let Some(frame) = self.master.poll_transmit() {
                self.log.push(format!("{} tx {frame}", stamp(now)));
                let answers: Vec<CanFrame> = self
                    .partners
                    .iter_mut()
                    .flat_map(|partner| partner.answer(now, &frame))
                    .collect();
                for answer in answers {
                    self.log.push(format!("{} rx {answer}", stamp(now)));
                    assert!(self.master.accept_frame(now, &answer));
                }
            }
            while let Some(event) = self.master.poll_event() {
                self.log.push(format!("{} {event}", stamp(now)));
                self.events.push(event);
            }
        }

        /// Runs every deadline up to and including `until_ms`.
        fn advance(&mut self, until_ms: u64) {
            let until = Instant::from_millis(until_ms);
            self.pump();
            while let Some(due) = self.master.poll_timeout().filter(|due| *due <= until) {
                assert!(due >= self.now, "deadline in the past");
                self.now = due;
                self.master.handle_timeout(due);
                self.pump();
            }
            self.now = until;
        }

        /// Runs deadlines until the master is idle.
        fn finish(&mut self) {
            self.pump();
            for _ in 0..10_000 {
                let Some(due) = self.master.poll_timeout() else {
                    return;
                };
                self.now = due;
                self.master.handle_timeout(due);
                self.pump();
            }
            panic!("the master did not finish");
        }

        fn call(
            &mut self,
            at_ms: u64,
            service: impl FnOnce(&mut LssMaster, Instant) -> Result<(), LssCommandError>,
        ) {
            self.advance(at_ms);
            service(&mut self.master, self.now).expect("service starts");
            self.pump();
        }

        fn rx(&mut self, at_ms: u64, text: &str) {
            self.advance(at_ms);
            let frame = parse_compact_frame(text).unwrap();
            self.log.push(format!("{} rx {frame}", stamp(self.now)));
            self.master.handle_frame(self.now, &frame);
            self.pump();
        }

        fn log(&mut self) -> Vec<String> {
            self.pump();
            std::mem::take(&mut self.log)
        }
    }

    #[test]
    fn switch_state_global_is_unconfirmed() {
        let mut t = Trace::new();
        t.call(0, |m, _| m.switch_state_global(LssMode::Configuration));
        t.call(1, |m, _| m.switch_state_global(LssMode::Waiting));
        assert_eq!(
            t.log(),
            [
                "0.000 tx 7E5#0401000000000000",
                "0.000 switch state global: done",
                "1.000 tx 7E5#0400000000000000",
                "1.000 switch state global: done",
            ]
        );
        assert_eq!(t.master.running(), None);
        assert_eq!(t.master.poll_timeout(), None);
    }

    #[test]
    fn switch_state_selective_sends_four_parts_and_waits_for_44h() {
        let mut t = Trace::new();
        t.call(0, |m, now| m.switch_state_selective(now, A));
        assert_eq!(t.master.running(), Some(LssService::SwitchStateSelective));
        t.rx(3, &s("44"));
        t.advance(200);
        assert_eq!(
            t.log(),
            [
                "0.000 tx 7E5#401A030000000000",
                "0.000 tx 7E5#4134120000000000",
                "0.000 tx 7E5#4202000100000000",
                "0.000 tx 7E5#43FECA0000000000",
                "3.000 rx 7E4#4400000000000000",
                // The settle time: a second 44h would be reported.
                "23.000 switch state selective: done",
            ]
        );
        t.call(300, |m, now| m.switch_state_selective(now, A));
        t.advance(500);
        assert_eq!(
            t.log()[4..],
            ["400.000 switch state selective: no answer within 100ms"]
        );
        assert_eq!(
            t.events[1],
            LssEvent::TimedOut {
                service: LssService::SwitchStateSelective,
                after: Duration::from_millis(100)
            }
        );
        assert_eq!(
            t.master.stats(),
            LssStats {
                sent: 8,
                received: 1,
                timeouts: 1,
                silence: Duration::from_millis(100)
            }
        );
    }

    #[test]
    fn configure_node_id_answers_and_error_codes() {
        let mut t = Trace::new();
        t.call(0, |m, now| m.configure_node_id(now, Some(node(5))));
        t.rx(2, &s("1100"));
        t.call(30, |m, now| m.configure_node_id(now, None));
        t.rx(31, &s("1101"));
        t.call(60, |m, now| m.configure_node_id_raw(now, 0));
        t.rx(61, &s("11FF2A"));
        t.call(90, |m, now| m.configure_node_id_raw(now, 0x80));
        t.rx(91, &s("1107"));
        t.call(120, |m, now| m.configure_node_id(now, Some(node(127))));
        t.advance(300);
        assert_eq!(
            t.log(),
            [
                "0.000 tx 7E5#1105000000000000",
                "2.000 rx 7E4#1100000000000000",
                "22.000 configure node-ID: success",
                "30.000 tx 7E5#11FF000000000000",
                "31.000 rx 7E4#1101000000000000",
                "51.000 configure node-ID: node-ID out of range",
                "60.000 tx 7E5#1100000000000000",
                "61.000 rx 7E4#11FF2A0000000000",
                "81.000 configure node-ID: implementation-specific error 0x2A",
                "90.000 tx 7E5#1180000000000000",
                "91.000 rx 7E4#1107000000000000",
                "111.000 configure node-ID: reserved error code 7",
                "120.000 tx 7E5#117F000000000000",
                "220.000 configure node-ID: no answer within 100ms",
            ]
        );
        assert_eq!(
            t.events[1],
            LssEvent::Configured {
                service: LssService::ConfigureNodeId,
                result: Err(LssServiceError::NodeIdOutOfRange)
            }
        );
    }

    #[test]
    fn configure_bit_timing_uses_table_0_and_refuses_reserved_indices() {
        let mut t = Trace::new();
        t.call(0, |m, now| m.configure_bit_timing(now, 3));
        t.rx(1, &s("1300"));
        t.call(30, |m, now| m.configure_bit_timing(now, 9));
        t.rx(31, &s("1301"));
        t.call(60, |m, now| m.configure_bit_timing(now, 0));
        t.advance(200);
        assert_eq!(
            t.log(),
            [
                "0.000 tx 7E5#1300030000000000",
                "1.000 rx 7E4#1300000000000000",
                "21.000 configure bit timing: success",
                "30.000 tx 7E5#1300090000000000",
                "31.000 rx 7E4#1301000000000000",
                "51.000 configure bit timing: bit rate not supported",
                "60.000 tx 7E5#1300000000000000",
                "160.000 configure bit timing: no answer within 100ms",
            ]
        );
        for index in [5, 10, 0xFF] {
            assert_eq!(
                t.master.configure_bit_timing(t.now, index),
                Err(LssCommandError::BitTimingIndex(index))
            );
        }
        assert_eq!(t.log(), Vec::<String>::new());
    }

    #[test]
    fn activate_bit_timing_waits_two_switch_delays() {
        let mut t = Trace::new();
        t.call(0, |m, now| m.activate_bit_timing(now, 1000));
        assert_eq!(
            t.master.configure_node_id(t.now, Some(node(1))),
            Err(LssCommandError::Busy {
                running: LssService::ActivateBitTiming
            })
        );
        t.rx(700, &s("4F"));
        t.advance(3000);
        assert_eq!(
            t.log(),
            [
                "0.000 tx 7E5#15E8030000000000",
                "700.000 rx 7E4#4F00000000000000",
                "700.000 ignored 7E4#4F00000000000000: no request waits for this answer",
                "1000.000 activate bit timing: switch the bit rate now",
                "2000.000 activate bit timing: done",
            ]
        );
        // A zero delay switches and ends at once.
        t.call(3000, |m, now| m.activate_bit_timing(now, 0));
        t.advance(3000);
        assert_eq!(
            t.log(),
            [
                "3000.000 tx 7E5#1500000000000000",
                "3000.000 activate bit timing: switch the bit rate now",
                "3000.000 activate bit timing: done",
            ]
        );
        assert_eq!(t.master.running(), None);
    }

    #[test]
    fn store_configuration_error_codes() {
        let mut t = Trace::new();
        for (n, answer) in ["1700", "1701", "1702", "17FF09", "1703"].into_iter().enumerate() {
            let at = 100 * n as u64;
            t.call(at, |m, now| m.store_configuration(now));
            t.rx(at + 1, &s(answer));
        }
        t.advance(1000);
        let results: Vec<String> = t.log().into_iter().filter(|line| !line.contains('#')).collect();
        assert_eq!(
            results,
            [
                "21.000 store configuration: success",
                "121.000 store configuration: storing not supported",
                "221.000 store configuration: storage media access error",
                "321.000 store configuration: implementation-specific error 0x09",
                "421.000 store configuration: reserved error code 3",
            ]
        );
    }

    #[test]
    fn error_codes_decode_per_service() {
        use LssService::{ConfigureBitTiming, ConfigureNodeId, StoreConfiguration};
        let decode = LssServiceError::decode;
        assert_eq!(decode(ConfigureNodeId, 0, 7), Ok(()));
        assert_eq!(
            decode(ConfigureNodeId, 1, 0),
            Err(LssServiceError::NodeIdOutOfRange)
        );
        assert_eq!(decode(ConfigureNodeId, 2, 0), Err(LssServiceError::Reserved(2)));
        assert_eq!(
            decode(ConfigureBitTiming, 1, 0),
            Err(LssServiceError::BitRateNotSupported)
        );
        assert_eq!(
            decode(ConfigureBitTiming, 0xFF, 3),
            Err(LssServiceError::Specific(3))
        );
        assert_eq!(
            decode(StoreConfiguration, 1, 0),
            Err(LssServiceError::StoringNotSupported)
        );
        assert_eq!(
            decode(StoreConfiguration, 2, 0),
            Err(LssServiceError::StorageMediaAccess)
        );
        assert_eq!(
            decode(StoreConfiguration, 254, 0),
            Err(LssServiceError::Reserved(254))
        );
    }

    #[test]
    fn inquire_identity_and_node_id() {
        let mut t = Trace::new();
        t.call(0, |m, now| m.inquire_address(now, LssAddressPart::VendorId));
        // The answer for another part does not end the service.
        t.rx(1, &s("5B34120000"));
        t.rx(2, &s("5A1A030000"));
        t.call(30, |m, now| m.inquire_address(now, LssAddressPart::SerialNumber));
        t.rx(31, &s("5DFECA0000"));
        t.call(60, |m, now| m.inquire_node_id(now));
        t.rx(61, &s("5E05"));
        t.call(90, |m, now| m.inquire_node_id(now));
        t.rx(91, &s("5EFF"));
        t.advance(200);
        assert_eq!(
            t.log(),
            [
                "0.000 tx 7E5#5A00000000000000",
                "1.000 rx 7E4#5B34120000000000",
                "1.000 ignored 7E4#5B34120000000000: no request waits for this answer",
                "2.000 rx 7E4#5A1A030000000000",
                "22.000 vendor-id = 0x0000031A",
                "30.000 tx 7E5#5D00000000000000",
                "31.000 rx 7E4#5DFECA0000000000",
                "51.000 serial number = 0x0000CAFE",
                "60.000 tx 7E5#5E00000000000000",
                "61.000 rx 7E4#5E05000000000000",
                "81.000 node-ID = 5",
                "90.000 tx 7E5#5E00000000000000",
                "91.000 rx 7E4#5EFF000000000000",
                "111.000 node-ID = unconfigured (FFh)",
            ]
        );
        assert_eq!(
            t.events[1],
            LssEvent::Inquired {
                part: LssAddressPart::VendorId,
                value: 0x31A
            }
        );
    }

    #[test]
    fn identify_remote_slave_counts_the_answers() {
        let range = IdentifyRange {
            vendor_id: A.vendor_id,
            product_code: A.product_code,
            revision_number: 0..=0xFFFF_FFFF,
            serial_number: 0x100..=0xFFFF,
        };
        let mut t = Trace::new();
        t.call(0, |m, now| m.identify_remote_slave(now, &range));
        t.rx(4, &s("4F"));
        t.rx(5, &s("4F"));
        t.call(100, |m, now| m.identify_remote_slave(now, &range));
        t.advance(300);
        let log = t.log();
        assert_eq!(
            log[..9],
            [
                "0.000 tx 7E5#461A030000000000",
                "0.000 tx 7E5#4734120000000000",
                "0.000 tx 7E5#4800000000000000",
                "0.000 tx 7E5#49FFFFFFFF000000",
                "0.000 tx 7E5#4A00010000000000",
                "0.000 tx 7E5#4BFFFF0000000000",
                "4.000 rx 7E4#4F00000000000000",
                "5.000 rx 7E4#4F00000000000000",
                "24.000 identify remote slave: 2 answer(s)",
            ]
        );
        assert_eq!(log[15..], ["200.000 identify remote slave: no slave answered"]);
        assert_eq!(t.master.stats().timeouts, 1);
        let high = 8;
        let empty = IdentifyRange {
            serial_number: 9..=high,
            ..range.clone()
        };
        assert_eq!(
            t.master.identify_remote_slave(t.now, &empty),
            Err(LssCommandError::EmptyRange(LssAddressPart::SerialNumber))
        );
    }

    #[test]
    fn identify_non_configured_remote_slave() {
        let mut t = Trace::new();
        t.call(0, |m, now| m.identify_non_configured(now));
        t.rx(2, &s("50"));
        t.advance(100);
        assert_eq!(
            t.log(),
            [
                "0.000 tx 7E5#4C00000000000000",
                "2.000 rx 7E4#5000000000000000",
                "22.000 identify non-configured remote slave: 1 answer(s)",
            ]
        );
    }

    #[test]
    fn one_service_at_a_time() {
        let mut t = Trace::new();
        t.call(0, |m, now| m.inquire_node_id(now));
        let busy = Err(LssCommandError::Busy {
            running: LssService::InquireNodeId,
        });
        let now = t.now;
        let m = &mut t.master;
        assert_eq!(m.switch_state_global(LssMode::Waiting), busy);
        assert_eq!(m.switch_state_selective(now, A), busy);
        assert_eq!(m.store_configuration(now), busy);
        assert_eq!(m.inquire_address(now, LssAddressPart::ProductCode), busy);
        assert_eq!(m.identify_non_configured(now), busy);
        assert_eq!(m.fastscan(now, KnownParts::NONE), busy);
        assert_eq!(m.scan_all(now, plan(&[1], false, KnownParts::NONE)), busy);
        assert_eq!(
            LssCommandError::Busy {
                running: LssService::InquireNodeId
            }
            .to_string(),
            "the LSS master is busy with inquire node-ID"
        );
        t.advance(100);
        assert_eq!(t.master.running(), None);
        t.call(100, |m, _| m.switch_state_global(LssMode::Waiting));
    }

    #[test]
    fn garbage_and_foreign_frames_change_nothing() {
        let mut t = Trace::new();
        t.call(0, |m, now| m.inquire_node_id(now));
        t.rx(1, "7E4#5E05");
        t.rx(2, "7E4#R8");
        t.rx(3, &s("04"));
        t.rx(4, &s("FF"));
        t.rx(5, &s("1100"));
        // Not LSS answers at all: another identifier, the extended 7E4h, the master's own CAN-ID.
        for text in ["000007E4#5E05000000000000", &m("5E05"), "7E3#5E05000000000000"] {
            let frame = parse_compact_frame(text).unwrap();
            assert!(!t.master.accept_frame(t.now, &frame), "{text}");
        }
        t.rx(6, &s("5E07"));
        t.advance(100);
        assert_eq!(
            t.log(),
            [
                "0.000 tx 7E5#5E00000000000000",
                "1.000 rx 7E4#5E05",
                "1.000 ignored 7E4#5E05: DLC 2, not 8",
                "2.000 rx 7E4#R8",
                "2.000 ignored 7E4#R8: remote frame",
                "3.000 rx 7E4#0400000000000000",
                "3.000 ignored 7E4#0400000000000000: unknown command specifier 0x04",
                "4.000 rx 7E4#FF00000000000000",
                "4.000 ignored 7E4#FF00000000000000: unknown command specifier 0xFF",
                "5.000 rx 7E4#1100000000000000",
                "5.000 ignored 7E4#1100000000000000: no request waits for this answer",
                "6.000 rx 7E4#5E07000000000000",
                "26.000 node-ID = 7",
            ]
        );
        assert_eq!(t.master.stats().received, 6);
    }

    #[test]
    fn a_second_answer_where_one_is_expected_is_reported() {
        let mut t = Trace::new();
        t.call(0, |m, now| m.inquire_address(now, LssAddressPart::SerialNumber));
        t.rx(1, &s("5D01"));
        t.rx(2, &s("5D02"));
        // After the settle time an answer belongs to nothing.
        t.rx(30, &s("5D03"));
        assert_eq!(
            t.log(),
            [
                "0.000 tx 7E5#5D00000000000000",
                "1.000 rx 7E4#5D01000000000000",
                "2.000 rx 7E4#5D02000000000000",
                "2.000 inquire serial number: another slave answered too (serial number = 0x00000002)",
                "21.000 serial number = 0x00000001",
                "30.000 rx 7E4#5D03000000000000",
                "30.000 ignored 7E4#5D03000000000000: no request waits for this answer",
            ]
        );
    }

    #[test]
    fn fastscan_with_every_part_known_only_confirms() {
        let mut t = Trace::new();
        t.call(0, |m, now| m.fastscan(now, ALL_KNOWN));
        t.rx(1, &s("4F"));
        t.rx(22, &s("4F"));
        t.rx(43, &s("4F"));
        t.rx(64, &s("4F"));
        t.rx(85, &s("4F"));
        t.advance(1000);
        assert_eq!(
            t.log(),
            [
                "0.000 tx 7E5#5100000000800000",
                "1.000 rx 7E4#4F00000000000000",
                "21.000 tx 7E5#511A030000000001",
                "22.000 rx 7E4#4F00000000000000",
                "42.000 tx 7E5#5134120000000102",
                "43.000 rx 7E4#4F00000000000000",
                "63.000 tx 7E5#5102000100000203",
                "64.000 rx 7E4#4F00000000000000",
                "84.000 tx 7E5#51FECA0000000300",
                "85.000 rx 7E4#4F00000000000000",
                "105.000 found vendor-id 0x0000031A, product code 0x00001234, revision number 0x00010002, \
                 serial number 0x0000CAFE",
                "105.000 scan finished: 1 slave(s) found",
            ]
        );
        assert_eq!(
            t.events[0],
            LssEvent::Found {
                address: A,
                node_id: None
            }
        );
    }

    #[test]
    fn fastscan_without_unconfigured_slaves_or_matching_known_parts() {
        let mut t = Trace::new();
        t.call(0, |m, now| m.fastscan(now, KnownParts::NONE));
        t.advance(1000);
        assert_eq!(
            t.log(),
            [
                "0.000 tx 7E5#5100000000800000",
                "100.000 scan finished: 0 slave(s) found",
            ]
        );
        // The probe is answered, but nobody has the known vendor-ID.
        let mut t = Trace::slaves(&[A]);
        let known = KnownParts {
            vendor_id: Some(0x999),
            ..KnownParts::NONE
        };
        t.call(0, |m, now| m.fastscan(now, known));
        t.finish();
        assert_eq!(
            t.log(),
            [
                "0.000 tx 7E5#5100000000800000",
                "0.000 rx 7E4#4F00000000000000",
                "20.000 tx 7E5#5199090000000001",
                "120.000 scan finished: 0 slave(s) found",
            ]
        );
        assert_eq!(t.partners[0].slave().state(), LssState::Waiting);
    }

    #[test]
    fn fastscan_finds_a_slave_bit_by_bit() {
        let mut t = Trace::slaves(&[A]);
        t.call(0, |m, now| m.fastscan(now, KnownParts::NONE));
        t.finish();
        let log = t.log();
        assert_eq!(
            log[..7],
            [
                "0.000 tx 7E5#5100000000800000",
                "0.000 rx 7E4#4F00000000000000",
                // Vendor-ID bit 31 is 0: the slave answers.
                "20.000 tx 7E5#51000000001F0000",
                "20.000 rx 7E4#4F00000000000000",
                "40.000 tx 7E5#51000000001E0000",
                "40.000 rx 7E4#4F00000000000000",
                "60.000 tx 7E5#51000000001D0000",
            ]
        );
        // Every 1 bit is a timeout; every other step ends 20 ms after its answer.
        let ones = u64::from(
            A.vendor_id.count_ones()
                + A.product_code.count_ones()
                + A.revision_number.count_ones()
                + A.serial_number.count_ones(),
        );
        let requests = 1 + 4 * 33;
        let end = stamp(Instant::from_millis(100 * ones + 20 * (requests - ones)));
        let found = format!("{end} found {A}");
        assert_eq!(
            log[log.len() - 2..],
            [found, format!("{end} scan finished: 1 slave(s) found")]
        );
        assert_eq!(
            t.master.stats(),
            LssStats {
                sent: requests,
                received: requests - ones,
                timeouts: ones,
                silence: Duration::from_millis(100 * ones)
            }
        );
        assert_eq!(t.partners[0].slave().state(), LssState::Configuration);
    }

    #[test]
    fn scan_all_gives_every_unconfigured_slave_a_node_id() {
        let addresses = [
            A,
            LssAddress {
                serial_number: A.serial_number ^ 1,
                ..A
            },
            LssAddress {
                vendor_id: 0xFFFF_FFFF,
                product_code: 0,
                revision_number: 0x8000_0001,
                serial_number: 0,
            },
        ];
        let mut t = Trace::slaves(&addresses);
        // A configured slave does not take part.
        let configured = LssSlave::new(LssAddress::default(), Some(node(9)));
        t.partners.push(Partner::Slave(Box::new(configured)));
        t.call(0, |m, now| {
            m.scan_all(now, plan(&[20, 21, 22, 23], false, KnownParts::NONE))
        });
        t.finish();
        // The smallest address is found first (the search follows the 0 bits).
        let found: Vec<LssEvent> = t
            .events
            .iter()
            .copied()
            .filter(|event| matches!(event, LssEvent::Found { .. } | LssEvent::ScanFinished { .. }))
            .collect();
        assert_eq!(
            found,
            [
                LssEvent::Found {
                    address: addresses[0],
                    node_id: Some(node(20))
                },
                LssEvent::Found {
                    address: addresses[1],
                    node_id: Some(node(21))
                },
                LssEvent::Found {
                    address: addresses[2],
                    node_id: Some(node(22))
                },
                LssEvent::ScanFinished { found: 3 },
            ]
        );
        assert_eq!(t.events.len(), 4, "{:?}", t.events);
        let nodes: Vec<Option<NodeId>> = t.partners.iter().map(|p| p.slave().node_id()).collect();
        assert_eq!(
            nodes,
            [Some(node(20)), Some(node(21)), Some(node(22)), Some(node(9))]
        );
        assert!(t.partners.iter().all(|p| p.slave().state() == LssState::Waiting));
        // Per slave: probe, 4 × (32 bits + confirmation), configure node-ID, switch state global;
        // then the probe nobody answers. Every 1 bit of a found address is a timeout.
        let ones: u32 = addresses
            .iter()
            .map(|a| PARTS.map(|part| a.part(part).count_ones()).iter().sum::<u32>())
            .sum();
        let stats = t.master.stats();
        assert_eq!(stats.sent, 3 * (1 + 4 * 33 + 2) + 1);
        assert_eq!(stats.timeouts, u64::from(ones) + 1);
    }

    #[test]
    fn scan_all_reports_slaves_with_the_same_address() {
        let mut t = Trace::slaves(&[A, A]);
        t.call(0, |m, now| m.scan_all(now, plan(&[5, 6], false, ALL_KNOWN)));
        t.finish();
        let log = t.log();
        assert_eq!(
            log[log.len() - 4..],
            [
                "80.000 rx 7E4#4F00000000000000",
                "80.000 rx 7E4#4F00000000000000",
                "100.000 tx 7E5#0400000000000000",
                "100.000 scan failed after 0 slave(s) found: more than one slave has the LSS address \
                 vendor-id 0x0000031A, product code 0x00001234, revision number 0x00010002, serial number \
                 0x0000CAFE",
            ]
        );
        for partner in &t.partners {
            assert_eq!(partner.slave().state(), LssState::Waiting);
            assert_eq!(partner.slave().pending_node_id(), None);
        }
    }

    /// A scripted slave with address [`A`] that answers every fastscan request, each configure
    /// node-ID with the next of `configure` and store configuration with `store`.
    fn scripted(configure: &'static [&'static [&'static str]], store: &'static [&'static str]) -> Trace {
        let mut configures = configure.iter();
        Trace::script(move |request| match request {
            LssRequest::Fastscan { .. } => answer(LssResponse::IdentifySlave),
            LssRequest::ConfigureNodeId { .. } => configures.next().map_or(Vec::new(), |hex| answers(hex)),
            LssRequest::StoreConfiguration => answers(store),
            _ => Vec::new(),
        })
    }

    #[test]
    fn scan_all_takes_back_a_node_id_two_slaves_took() {
        // The serial number confirmation merged into one frame, the node-ID answers did not.
        let mut t = scripted(&[&["1100", "1100"], &["1100"]], &[]);
        t.call(0, |m, now| m.scan_all(now, plan(&[5], false, ALL_KNOWN)));
        t.finish();
        let log = t.log();
        assert_eq!(
            log[10..],
            [
                "100.000 tx 7E5#1105000000000000",
                "100.000 rx 7E4#1100000000000000",
                "100.000 rx 7E4#1100000000000000",
                "100.000 configure node-ID: another slave answered too (configure node-id: success)",
                "120.000 tx 7E5#11FF000000000000",
                "120.000 rx 7E4#1100000000000000",
                "140.000 tx 7E5#0400000000000000",
                "140.000 scan failed after 0 slave(s) found: more than one slave has the LSS address \
                 vendor-id 0x0000031A, product code 0x00001234, revision number 0x00010002, serial number \
                 0x0000CAFE",
            ]
        );
    }

    #[test]
    fn scan_all_stops_when_a_slave_refuses_or_ignores_the_node_id() {
        let mut t = scripted(&[&["1101"]], &[]);
        t.call(0, |m, now| m.scan_all(now, plan(&[5], false, ALL_KNOWN)));
        t.finish();
        assert_eq!(
            t.log()[10..],
            [
                "100.000 tx 7E5#1105000000000000",
                "100.000 rx 7E4#1101000000000000",
                "120.000 tx 7E5#0400000000000000",
                "120.000 scan failed after 0 slave(s) found: the slave with vendor-id 0x0000031A, product \
                 code 0x00001234, revision number 0x00010002, serial number 0x0000CAFE refused node-ID 5: \
                 node-ID out of range",
            ]
        );
        let mut t = scripted(&[], &[]);
        t.call(0, |m, now| m.scan_all(now, plan(&[5], false, ALL_KNOWN)));
        t.finish();
        assert_eq!(
            t.events,
            [LssEvent::ScanFailed {
                found: 0,
                error: ScanError::NoAnswer {
                    address: A,
                    node_id: node(5)
                }
            }]
        );
        assert_eq!(
            t.log()[10..12],
            [
                "100.000 tx 7E5#1105000000000000",
                "200.000 tx 7E5#0400000000000000"
            ]
        );
    }

    #[test]
    fn scan_all_goes_on_when_store_fails() {
        // The scripted slave answers the probe for ever: the node-ID list ends the scan.
        let mut t = scripted(&[&["1100"], &["1100"]], &["1701"]);
        t.call(0, |m, now| m.scan_all(now, plan(&[5, 6], true, ALL_KNOWN)));
        t.finish();
        let log = t.log();
        assert_eq!(
            log[10..19],
            [
                "100.000 tx 7E5#1105000000000000",
                "100.000 rx 7E4#1100000000000000",
                "120.000 tx 7E5#1700000000000000",
                "120.000 rx 7E4#1701000000000000",
                "140.000 tx 7E5#0400000000000000",
                "140.000 tx 7E5#5100000000800000",
                "140.000 rx 7E4#4F00000000000000",
                "140.000 store configuration: storing not supported",
                "140.000 found vendor-id 0x0000031A, product code 0x00001234, revision number 0x00010002, \
                 serial number 0x0000CAFE -> node-ID 5",
            ]
        );
        assert_eq!(
            t.events[t.events.len() - 1],
            LssEvent::ScanFailed {
                found: 2,
                error: ScanError::NoNodeIdLeft
            }
        );
        // No store answer: reported, and the scan goes on.
        let mut t = scripted(&[&["1100"]], &[]);
        t.call(0, |m, now| m.scan_all(now, plan(&[5], true, ALL_KNOWN)));
        t.finish();
        assert_eq!(
            t.events[..2],
            [
                LssEvent::TimedOut {
                    service: LssService::StoreConfiguration,
                    after: Duration::from_millis(100)
                },
                LssEvent::Found {
                    address: A,
                    node_id: Some(node(5))
                }
            ]
        );
    }

    #[test]
    fn scan_all_runs_out_of_node_ids() {
        let second = LssAddress {
            serial_number: 0xCAFF,
            ..A
        };
        let mut t = Trace::slaves(&[A, second]);
        t.call(0, |m, now| m.scan_all(now, plan(&[5], false, KnownParts::NONE)));
        t.finish();
        assert_eq!(
            t.events,
            [
                LssEvent::Found {
                    address: A,
                    node_id: Some(node(5))
                },
                LssEvent::ScanFailed {
                    found: 1,
                    error: ScanError::NoNodeIdLeft
                }
            ]
        );
        assert_eq!(t.partners[1].slave().node_id(), None);
        assert_eq!(
            t.master
                .scan_all(t.now, plan(&[5, 6, 5], false, KnownParts::NONE)),
            Err(LssCommandError::DuplicateNodeId(node(5)))
        );
        assert_eq!(node_id_range(node(3), node(5)), [node(3), node(4), node(5)]);
        assert_eq!(node_id_range(node(5), node(3)), []);
    }

    #[test]
    fn a_late_answer_fails_the_confirmation() {
        // Answers every bit step except bit 0 and the confirmations: as if the answer to those came
        // too late.
        let mut t = Trace::script(|request| match request {
            LssRequest::Fastscan { bit_checked, .. } if *bit_checked != 0 => {
                answer(LssResponse::IdentifySlave)
            }
            _ => Vec::new(),
        });
        t.call(0, |m, now| m.fastscan(now, KnownParts::NONE));
        t.finish();
        let log = t.log();
        assert_eq!(
            log[log.len() - 3..],
            [
                "640.000 tx 7E5#5100000000000000",
                "740.000 tx 7E5#5101000000000001",
                "840.000 scan failed after 0 slave(s) found: no slave confirmed the vendor-id found bit by \
                 bit; an answer may have come too late",
            ]
        );
        assert_eq!(t.master.stats().timeouts, 2);
    }

    mod robustness {
        use super::*;
        use proptest::prelude::*;

        /// Any frame on 7E4h: well-formed answers, wrong lengths, unknown specifiers, remote frames.
        fn any_answer() -> impl Strategy<Value = Option<CanFrame>> {
            let specifier = prop_oneof![
                prop::sample::select(vec![
                    0x11u8, 0x13, 0x17, 0x44, 0x4F, 0x50, 0x5A, 0x5B, 0x5C, 0x5D, 0x5E
                ]),
                any::<u8>(),
            ];
            let data = (specifier, prop::collection::vec(any::<u8>(), 7), 0usize..=8);
            let frame = prop_oneof![
                8 => data.prop_map(|(cs, rest, len)| {
                    let mut bytes = vec![cs];
                    bytes.extend(rest);
                    bytes.truncate(len.max(1));
                    if len == 8 { bytes.resize(8, 0) }
                    CanFrame::new(slave_id(), &bytes).ok()
                }),
                1 => (0u8..=8).prop_map(|dlc| CanFrame::remote(slave_id(), dlc).ok()),
            ];
            prop_oneof![2 => Just(None), 3 => frame]
        }

        proptest! {
            #[test]
            fn no_answer_sequence_panics_or_hangs(
                answers in prop::collection::vec(prop::collection::vec(any_answer(), 0..3), 1..64),
                service in 0usize..6,
            ) {
                let mut master = LssMaster::new(LssConfig::DEFAULT);
                let mut now = Instant::ZERO;
                let started = match service {
                    0 => master.scan_all(now, plan(&[1, 2, 3], true, KnownParts::NONE)),
                    1 => master.fastscan(now, KnownParts { vendor_id: Some(0), ..KnownParts::NONE }),
                    2 => master.configure_node_id(now, Some(node(3))),
                    3 => master.inquire_address(now, LssAddressPart::ProductCode),
                    4 => master.identify_non_configured(now),
                    _ => master.switch_state_selective(now, A),
                };
                prop_assert!(started.is_ok());
                // Each request gets the next batch of answers. Bounded: every step of a scan either
                // hands out one of the 3 node-IDs or gets nearer to the end of one of 4 × 33 steps.
                let mut batches = answers.iter().cycle();
                for _ in 0..2_000 {
                    while master.poll_transmit().is_some() {
                        for frame in batches.next().into_iter().flatten().flatten() {
                            prop_assert!(master.accept_frame(now, frame));
                        }
                    }
                    while master.poll_event().is_some() {}
                    let Some(due) = master.poll_timeout() else { break };
                    now = due;
                    master.handle_timeout(now);
                }
                prop_assert_eq!(master.running(), None);
                prop_assert_eq!(master.poll_timeout(), None);
            }
        }
    }
}

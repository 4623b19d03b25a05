//! The PDO engine (CiA 301, process data object (PDO) protocol: communication and mapping
//! parameters, transmission types, inhibit time, event timer, SYNC start value, remote request).
//!
//! The engine runs every RPDO and TPDO the object dictionary describes: RPDO *n* has its
//! communication parameter at 1400h + *n* − 1 and its mapping at 1600h + *n* − 1, TPDO *n* at
//! 1800h + *n* − 1 and 1A00h + *n* − 1 (512 of each at most). [`PdoEngine::reload`] reads them; the
//! `Device` calls it after every SDO write to 1400h–1BFFh, and before such a write is accepted its
//! SDO hooks call [`PdoEngine::check_write`], which applies the checks of the CiA 301 dynamic mapping
//! procedure and of the COB-ID rules and returns a [`PdoConfigError`] whose
//! [`abort_code`](PdoConfigError::abort_code) is the SDO abort code to send.
//!
//! Communication parameter (sub-index: meaning): 1: COB-ID (bit 31 set = PDO not valid, bit 30 set
//! = no RTR allowed, bit 29 set = 29-bit CAN-ID), 2: transmission type, 3: inhibit time (100 µs),
//! 5: event timer (ms; for an RPDO the deadline monitor), 6: SYNC start value (TPDO). Mapping
//! entries are `index << 16 | sub-index << 8 | length in bits`; lengths are bit-granular, with up
//! to 64 bits per PDO.
//!
//! TPDO transmission types:
//! - 0 (synchronous, acyclic): sent on the next SYNC after [`PdoEngine::application_event`];
//! - 1–240 (synchronous, cyclic): sent on every *n*-th SYNC. The first SYNC the TPDO sees counts as
//!   the first one, unless a SYNC start value is set and the SYNCs carry a counter: then the SYNC
//!   whose counter equals the start value is the first one;
//! - 252 (RTR only, synchronous): the data is sampled at each SYNC and sent on a remote request;
//! - 253 (RTR only, event-driven): the data is sampled and sent on a remote request;
//! - 254, 255 (event-driven): sent on an application event and when the event timer expires, never
//!   twice within the inhibit time. The event timer restarts on every transmission.
//!
//! A remote request on a TPDO whose COB-ID allows RTR (bit 30 clear) is answered by every type:
//! synchronous types (0–240, 252) with the data sampled at the last SYNC (nothing before the first
//! SYNC), event-driven types (253–255) with the current data. Answers are not held back by the
//! inhibit time.
//!
//! RPDO transmission types 0–240 buffer the received data and write it into the mapped entries on
//! the next SYNC; 254 and 255 write it at once. With a synchronous window (1007h), synchronous
//! RPDOs that arrive after the window has closed are discarded until the next SYNC
//! ([`PdoEvent::RpdoLate`]; CiA 301 §7.2.5.1, as lely does). An RPDO shorter than its mapping is not processed
//! and one longer than its mapping is processed (extra bytes ignored); both are reported as
//! [`PdoEvent::RpdoTooShort`] / [`PdoEvent::RpdoTooLong`] for the `Device` to send EMCY 8210h /
//! 8220h, and [`PdoEvent::RpdoLengthOk`] reports the next correct one. A non-zero RPDO event timer
//! monitors the deadline: [`PdoEvent::RpdoTimeout`] (EMCY 8250h) when no RPDO arrived within it.
//!
//! PDOs run only in Operational (CiA 301 table of services per NMT state): [`PdoEngine::set_state`]
//! starts and stops them. Entering Operational sends the event-driven TPDOs once, and makes
//! acyclic synchronous (type 0) TPDOs go out on the first SYNC, as CANopenNode does, so a master
//! sees the current inputs without waiting for a change.
//!
//! Frame contents are sampled from the object dictionary when the frame is built, so
//! [`PdoEngine::handle_timeout`] takes the dictionary; [`PdoEngine::application_event`] only marks
//! the TPDOs concerned and [`PdoEngine::poll_timeout`] then asks for a call at once (or at the end
//! of the inhibit time).
//!
//! Choices where stacks disagree (reference §3 and §9), taking what CiA's CCT accepts:
//! - mapping written while the PDO is valid, and entries written while sub-index 0 ≠ 0: 0601 0000h
//!   (CANopenNode; in the CCT's accepted set; lely answers 0609 0030h);
//! - a mapped object or sub-index that does not exist: 0602 0000h for both (0609 0011h is not in the
//!   set the CCT accepts for this step);
//! - a mapping length larger than the object (CANopenNode), a length of 0 and a variable-length
//!   object (strings, DOMAIN): 0604 0041h, the object cannot be mapped so (in the set the CCT
//!   accepts for a mapping entry, reference §3.4);
//! - sub-index 0 above the number of mapping entries the object has, or above 40h, MPDO (sub-index
//!   0 = FEh/FFh, not supported) and more than 64 bits in total: 0604 0042h (CANopenNode, in the
//!   CCT set for enabling a mapping);
//! - every refusal with its code and reason is tabled in `docs/pdo-mapping-refusals.md`;
//! - transmission types 252 and 253 are supported (lely) rather than refused (CANopenNode), but
//!   refused with 0609 0030h while COB-ID bit 30 forbids RTR, and bit 30 cannot be set while the
//!   type is 252 or 253 (lely);
//! - dummy mapping (index 0001h–0007h, sub-index 0) is accepted in both directions for the types
//!   [`DummyUsage`] enables, and sends zeros in a TPDO (CANopenNode; lely has no TPDO dummies); a
//!   type not enabled is 0602 0000h (lely);
//! - the RPDO deadline monitor starts at the first RPDO received, not when the PDO becomes valid
//!   (CANopenNode: fewer false alarms);
//! - a PDO whose mapping has no entries is disabled (it neither sends nor processes anything).

use std::collections::VecDeque;
use std::fmt;
use std::time::Duration;

use canopener_can::{CanFrame, CanId, Instant};
use canopener_od::{DynamicOd, ObjectKey};
use canopener_wire::abort;

use crate::nmt_slave::{CommService, NmtSlaveState};

/// First RPDO communication parameter index.
pub const RPDO_COMM_BASE: u16 = 0x1400;
/// First RPDO mapping parameter index.
pub const RPDO_MAPPING_BASE: u16 = 0x1600;
/// First TPDO communication parameter index.
pub const TPDO_COMM_BASE: u16 = 0x1800;
/// First TPDO mapping parameter index.
pub const TPDO_MAPPING_BASE: u16 = 0x1A00;
/// The number of RPDOs (and of TPDOs) CiA 301 provides for.
pub const MAX_PDOS: u16 = 512;
/// COB-ID bit 31: set = the PDO is not valid.
pub const COB_ID_INVALID: u32 = 0x8000_0000;
/// COB-ID bit 30: set = no remote request allowed on this PDO.
pub const COB_ID_NO_RTR: u32 = 0x4000_0000;
/// COB-ID bit 29: set = 29-bit CAN-ID.
pub const COB_ID_EXTENDED: u32 = 0x2000_0000;
/// The most bits one PDO carries on classical CAN.
pub const MAX_MAPPED_BITS: u32 = 64;
/// The most mapping entries (sub-index 0 of a mapping parameter) CiA 301 allows.
pub const MAX_MAPPED_OBJECTS: u8 = 0x40;
/// EMCY error code for [`PdoEvent::RpdoTooShort`]: PDO not processed due to length error.
pub const EMCY_PDO_LENGTH_ERROR: u16 = 0x8210;
/// EMCY error code for [`PdoEvent::RpdoTooLong`]: PDO length exceeded.
pub const EMCY_PDO_LENGTH_EXCEEDED: u16 = 0x8220;
/// EMCY error code for [`PdoEvent::RpdoTimeout`]: RPDO timeout.
pub const EMCY_RPDO_TIMEOUT: u16 = 0x8250;

/// Receive or transmit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Direction {
    /// A receive PDO: the device consumes it.
    Receive,
    /// A transmit PDO: the device produces it.
    Transmit,
}

/// One PDO of the device: its direction and its number (1 to 512).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct PdoRef {
    /// RPDO or TPDO.
    pub direction: Direction,
    /// The number, 1 to 512 (RPDO1 is 1400h/1600h).
    pub number: u16,
}

impl PdoRef {
    /// The index of the communication parameter.
    pub fn comm_index(self) -> u16 {
        let base = match self.direction {
            Direction::Receive => RPDO_COMM_BASE,
            Direction::Transmit => TPDO_COMM_BASE,
        };
        base + self.number.saturating_sub(1)
    }

    /// The index of the mapping parameter.
    pub fn mapping_index(self) -> u16 {
        self.comm_index() + 0x200
    }

    /// The PDO whose communication or mapping parameter is at `index`, if any.
    pub fn from_index(index: u16) -> Option<(PdoRef, bool)> {
        let (direction, base, comm) = match index {
            0x1400..=0x15FF => (Direction::Receive, RPDO_COMM_BASE, true),
            0x1600..=0x17FF => (Direction::Receive, RPDO_MAPPING_BASE, false),
            0x1800..=0x19FF => (Direction::Transmit, TPDO_COMM_BASE, true),
            0x1A00..=0x1BFF => (Direction::Transmit, TPDO_MAPPING_BASE, false),
            _ => return None,
        };
        let number = index - base + 1;
        Some((PdoRef { direction, number }, comm))
    }
}

/// `RPDO1`, `TPDO3`, …
impl fmt::Display for PdoRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.direction {
            Direction::Receive => write!(f, "RPDO{}", self.number),
            Direction::Transmit => write!(f, "TPDO{}", self.number),
        }
    }
}

/// The dummy data types (0001h–0007h: BOOLEAN, INTEGER8/16/32, UNSIGNED8/16/32) a device accepts
/// as placeholders in a mapping, as its EDS `[DummyUsage]` section declares (`Dummy0001=1`, ...).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct DummyUsage(u8);

impl DummyUsage {
    /// No dummy mapping.
    pub const NONE: DummyUsage = DummyUsage(0);
    /// Dummies of all seven types.
    pub const ALL: DummyUsage = DummyUsage(0xFE);

    /// Also accepts dummies of type `index` (0001h–0007h; other indices are ignored).
    pub fn with(self, index: u16) -> DummyUsage {
        match index {
            1..=7 => DummyUsage(self.0 | 1 << index),
            _ => self,
        }
    }

    /// Whether a dummy of type `index` is accepted.
    pub fn allows(self, index: u16) -> bool {
        matches!(index, 1..=7) && self.0 & (1 << index) != 0
    }
}

/// Why a write to a PDO parameter was refused, or why a PDO described in the object dictionary
/// cannot run; [`PdoConfigError::abort_code`] is the SDO abort code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum PdoConfigError {
    /// An 11-bit COB-ID (bit 29 clear) with bits 28..11 set (0609 0030h).
    #[error("COB-ID {value:#010X}: bits 28..11 must be 0 for an 11-bit CAN-ID (or set bit 29 for 29-bit)")]
    UnsupportedCobId {
        /// The value written.
        value: u32,
    },
    /// A valid COB-ID with another CAN-ID while the PDO is valid (0609 0030h).
    #[error("{pdo}: the CAN-ID cannot change while the PDO is valid; write the COB-ID with bit 31 set first")]
    CanIdChangedWhileValid {
        /// The PDO.
        pdo: PdoRef,
    },
    /// A valid COB-ID with a restricted CAN-ID (0609 0030h).
    #[error(
        "{pdo}: CAN-ID {can_id:03X}h is restricted (NMT, SDO, error control, reserved) and cannot carry a PDO"
    )]
    RestrictedCanId {
        /// The PDO.
        pdo: PdoRef,
        /// The CAN-ID written.
        can_id: u16,
    },
    /// A reserved transmission type: 241–251 for a TPDO, 241–253 for an RPDO (0609 0030h).
    #[error("{pdo}: transmission type {value} is reserved")]
    ReservedTransmissionType {
        /// The PDO.
        pdo: PdoRef,
        /// The type written.
        value: u8,
    },
    /// Transmission type 252 or 253 (RTR only) together with COB-ID bit 30 (no RTR) (0609 0030h).
    #[error("{pdo}: transmission type {transmission_type} needs RTR, which COB-ID bit 30 forbids")]
    RtrNotAllowed {
        /// The PDO.
        pdo: PdoRef,
        /// The transmission type, 252 or 253.
        transmission_type: u8,
    },
    /// Inhibit time (sub 3) or SYNC start value (sub 6) changed while the TPDO is valid (0609 0030h).
    #[error("{pdo}: sub-index {sub} can only change while the PDO is not valid (COB-ID bit 31 set)")]
    ChangedWhileValid {
        /// The PDO.
        pdo: PdoRef,
        /// The sub-index written.
        sub: u8,
    },
    /// A SYNC start value above 240 (0609 0030h).
    #[error("{pdo}: SYNC start value {value} is above 240")]
    SyncStartValueTooHigh {
        /// The PDO.
        pdo: PdoRef,
        /// The value written.
        value: u8,
    },
    /// The mapping written while the PDO is valid (0601 0000h).
    #[error("{pdo}: the mapping can only change while the PDO is not valid (COB-ID bit 31 set)")]
    MappingWhileValid {
        /// The PDO.
        pdo: PdoRef,
    },
    /// A mapping entry written while sub-index 0 is not 0 (0601 0000h).
    #[error("{pdo}: mapping entries can only change while sub-index 0 is 0; write 0 to it first")]
    MappingWhileEnabled {
        /// The PDO.
        pdo: PdoRef,
    },
    /// A mapped object or sub-index that does not exist, or a dummy of a type the device does not
    /// enable (0602 0000h).
    #[error("{pdo}: mapped object {key} does not exist")]
    ObjectDoesNotExist {
        /// The PDO.
        pdo: PdoRef,
        /// The object mapped.
        key: ObjectKey,
    },
    /// An object that cannot be mapped into a PDO of this direction (0604 0041h).
    #[error("{pdo}: {key} cannot be mapped into this PDO (PDOMapping or access type)")]
    NotMappable {
        /// The PDO.
        pdo: PdoRef,
        /// The object mapped.
        key: ObjectKey,
    },
    /// A mapping length longer than the object (0604 0041h).
    #[error("{pdo}: {bits} bits mapped from {key}, which holds only {max}")]
    MappingLengthTooLong {
        /// The PDO.
        pdo: PdoRef,
        /// The object mapped.
        key: ObjectKey,
        /// The length in the mapping entry.
        bits: u8,
        /// The object's size in bits.
        max: u32,
    },
    /// Sub-index 0 above 40h or above the mapping entries the object has (0604 0042h).
    #[error("{pdo}: {count} mapping entries requested, at most {max} possible")]
    TooManyObjects {
        /// The PDO.
        pdo: PdoRef,
        /// The value written to sub-index 0.
        count: u8,
        /// The number of mapping entries available.
        max: u8,
    },
    /// The mapped objects take more than 64 bits (0604 0042h).
    #[error("{pdo}: the mapping takes {bits} bits, more than the 64 of a PDO")]
    LengthExceeded {
        /// The PDO.
        pdo: PdoRef,
        /// The total length in bits.
        bits: u32,
    },
    /// Sub-index 0 = FEh or FFh, a multiplexed PDO, which the device does not support
    /// (0604 0042h: a number of mapped objects the PDO cannot take).
    #[error("{pdo}: sub-index 0 = {count:02X}h asks for an MPDO, which this device does not support")]
    MpdoNotSupported {
        /// The PDO.
        pdo: PdoRef,
        /// The value written to sub-index 0.
        count: u8,
    },
    /// A mapping entry with length 0 (0604 0041h: nothing of the object can be mapped so).
    #[error("{pdo}: mapping entry {entry:#010X} has length 0; give the length in bits")]
    ZeroLength {
        /// The PDO.
        pdo: PdoRef,
        /// The mapping entry.
        entry: u32,
    },
    /// A variable-length object (strings, DOMAIN) in a mapping (0604 0041h: only fixed-size objects
    /// can be mapped).
    #[error("{pdo}: {key} has no fixed size, so it cannot be mapped into a PDO")]
    VariableLength {
        /// The PDO.
        pdo: PdoRef,
        /// The object mapped.
        key: ObjectKey,
    },
}

impl PdoConfigError {
    /// The SDO abort code an SDO server sends for this error.
    pub fn abort_code(&self) -> u32 {
        match self {
            PdoConfigError::UnsupportedCobId { .. }
            | PdoConfigError::CanIdChangedWhileValid { .. }
            | PdoConfigError::RestrictedCanId { .. }
            | PdoConfigError::ReservedTransmissionType { .. }
            | PdoConfigError::RtrNotAllowed { .. }
            | PdoConfigError::ChangedWhileValid { .. }
            | PdoConfigError::SyncStartValueTooHigh { .. } => abort::INVALID_VALUE,
            PdoConfigError::MappingWhileValid { .. } | PdoConfigError::MappingWhileEnabled { .. } => {
                abort::UNSUPPORTED_ACCESS
            }
            PdoConfigError::ObjectDoesNotExist { .. } => abort::OBJECT_DOES_NOT_EXIST,
            PdoConfigError::NotMappable { .. }
            | PdoConfigError::MappingLengthTooLong { .. }
            | PdoConfigError::ZeroLength { .. }
            | PdoConfigError::VariableLength { .. } => abort::OBJECT_NOT_MAPPABLE,
            PdoConfigError::TooManyObjects { .. }
            | PdoConfigError::LengthExceeded { .. }
            | PdoConfigError::MpdoNotSupported { .. } => abort::PDO_LENGTH_EXCEEDED,
        }
    }
}

/// One entry of a valid mapping.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Mapped {
    /// The low `bits` bits of the entry at `key`.
    Object {
        /// The mapped entry.
        key: ObjectKey,
        /// The length in bits.
        bits: u8,
    },
    /// A placeholder of `bits` bits: skipped in an RPDO, zeros in a TPDO.
    Dummy {
        /// The length in bits.
        bits: u8,
    },
}

impl Mapped {
    fn bits(self) -> u8 {
        match self {
            Mapped::Object { bits, .. } | Mapped::Dummy { bits } => bits,
        }
    }
}

/// What the PDO engine reports to the `Device`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PdoEvent {
    /// An RPDO's data was written into its mapped entries (at reception or at SYNC).
    RpdoWritten {
        /// The RPDO number.
        number: u16,
    },
    /// An RPDO shorter than its mapping arrived and was not processed: raise EMCY 8210h.
    RpdoTooShort {
        /// The RPDO number.
        number: u16,
        /// The bytes received.
        received: u8,
        /// The bytes mapped.
        expected: u8,
    },
    /// An RPDO longer than its mapping arrived; it was processed: raise EMCY 8220h.
    RpdoTooLong {
        /// The RPDO number.
        number: u16,
        /// The bytes received.
        received: u8,
        /// The bytes mapped.
        expected: u8,
    },
    /// An RPDO of the right length arrived after a length error: clear 8210h / 8220h.
    RpdoLengthOk {
        /// The RPDO number.
        number: u16,
    },
    /// A synchronous RPDO arrived after the synchronous window (1007h) had closed and was
    /// discarded; synchronous RPDOs count again from the next SYNC (CiA 301 §7.2.5.1).
    RpdoLate {
        /// The RPDO number.
        number: u16,
    },
    /// No RPDO arrived within the event timer (deadline monitoring): raise EMCY 8250h.
    RpdoTimeout {
        /// The RPDO number.
        number: u16,
    },
    /// An RPDO arrived again after [`PdoEvent::RpdoTimeout`]: clear 8250h.
    RpdoResumed {
        /// The RPDO number.
        number: u16,
    },
    /// The parameters of a PDO in the object dictionary cannot run; the PDO is disabled until a
    /// [`PdoEngine::reload`] finds them usable.
    Disabled {
        /// The PDO.
        pdo: PdoRef,
        /// What is wrong.
        error: PdoConfigError,
    },
}

impl PdoEvent {
    /// The EMCY error code the `Device` raises for this event, if any.
    pub fn emcy_code(&self) -> Option<u16> {
        match self {
            PdoEvent::RpdoTooShort { .. } => Some(EMCY_PDO_LENGTH_ERROR),
            PdoEvent::RpdoTooLong { .. } => Some(EMCY_PDO_LENGTH_EXCEEDED),
            PdoEvent::RpdoTimeout { .. } => Some(EMCY_RPDO_TIMEOUT),
            _ => None,
        }
    }
}

/// Communication parameters as read from the dictionary.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Comm {
    cob_id: u32,
    transmission_type: u8,
    inhibit_100us: u16,
    event_ms: u16,
    sync_start: u8,
}

impl Comm {
    fn valid(&self) -> bool {
        self.cob_id & COB_ID_INVALID == 0
    }

    fn can_id(&self) -> Option<CanId> {
        cob_can_id(self.cob_id)
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum LengthState {
    Ok,
    Short,
    Long,
}

#[derive(Debug, Clone)]
struct Rpdo {
    number: u16,
    comm: Comm,
    map: Vec<Mapped>,
    /// The CAN-ID when the PDO is valid, usable and has a mapping.
    id: Option<CanId>,
    bytes: usize,
    /// Why the parameters cannot run, as last reported.
    error: Option<PdoConfigError>,
    buffered: Option<[u8; 8]>,
    deadline: Option<Instant>,
    timed_out: bool,
    length: LengthState,
}

#[derive(Debug, Clone)]
struct Tpdo {
    number: u16,
    comm: Comm,
    map: Vec<Mapped>,
    id: Option<CanId>,
    bytes: usize,
    /// Why the parameters cannot run, as last reported.
    error: Option<PdoConfigError>,
    /// Event-driven types: a transmission is due at `max(pending_since, inhibit_until)`.
    event_pending: bool,
    pending_since: Instant,
    inhibit_until: Instant,
    event_due: Option<Instant>,
    /// Type 0: an application event waits for the next SYNC.
    sync_pending: bool,
    /// Types 1–240: the first SYNC has been seen; `sync_left` SYNCs to the next transmission.
    sync_started: bool,
    sync_left: u8,
    /// Synchronous types: the data sampled at the last SYNC, for remote requests.
    sample: Option<[u8; 8]>,
}

impl Tpdo {
    fn is_event_driven(&self) -> bool {
        self.comm.transmission_type >= 254
    }

    fn rtr_allowed(&self) -> bool {
        self.comm.cob_id & COB_ID_NO_RTR == 0
    }

    fn stop(&mut self) {
        self.event_pending = false;
        self.event_due = None;
        self.sync_pending = false;
        self.sync_started = false;
        self.sync_left = 0;
        self.sample = None;
        self.inhibit_until = Instant::ZERO;
    }

    fn start(&mut self, now: Instant) {
        self.stop();
        if self.id.is_none() {
            return;
        }
        // CANopenNode sends event-driven TPDOs on entering Operational and lets type 0 go out on
        // the first SYNC, so the master sees the current values at once.
        if self.is_event_driven() {
            self.event_pending = true;
            self.pending_since = now;
        }
        self.sync_pending = self.comm.transmission_type == 0;
    }

    fn due(&self) -> Option<Instant> {
        let pending = self
            .event_pending
            .then(|| self.pending_since.max(self.inhibit_until));
        match (pending, self.event_due) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }
}

/// The RPDOs and TPDOs of one node.
#[derive(Debug, Clone)]
pub struct PdoEngine {
    state: NmtSlaveState,
    dummies: DummyUsage,
    rpdos: Vec<Rpdo>,
    tpdos: Vec<Tpdo>,
    /// The synchronous window (1007h) after the last SYNC has closed: synchronous RPDOs are
    /// discarded until the next SYNC.
    window_closed: bool,
    transmit: VecDeque<CanFrame>,
    events: VecDeque<PdoEvent>,
}

impl Default for PdoEngine {
    fn default() -> PdoEngine {
        PdoEngine::new()
    }
}

impl PdoEngine {
    /// An engine without PDOs, in Initialisation, accepting no dummy mapping. Call
    /// [`PdoEngine::reload`] once the dictionary holds its power-on values.
    pub fn new() -> PdoEngine {
        PdoEngine {
            state: NmtSlaveState::Initialisation,
            dummies: DummyUsage::NONE,
            rpdos: Vec::new(),
            tpdos: Vec::new(),
            window_closed: false,
            transmit: VecDeque::new(),
            events: VecDeque::new(),
        }
    }

    /// Accepts the dummy types `dummies` in mappings (from the EDS `[DummyUsage]` section). Call
    /// [`PdoEngine::reload`] afterwards for mappings already in the dictionary.
    pub fn with_dummy_usage(mut self, dummies: DummyUsage) -> PdoEngine {
        self.dummies = dummies;
        self
    }

    /// The RPDOs and TPDOs the dictionary describes (a communication parameter with a COB-ID
    /// exists), in number order.
    pub fn pdos(&self) -> impl Iterator<Item = PdoRef> + '_ {
        let rx = self.rpdos.iter().map(|p| PdoRef {
            direction: Direction::Receive,
            number: p.number,
        });
        let tx = self.tpdos.iter().map(|p| PdoRef {
            direction: Direction::Transmit,
            number: p.number,
        });
        rx.chain(tx)
    }

    /// Whether `pdo` exists, is valid and has a usable, non-empty mapping: whether it runs in
    /// Operational.
    pub fn is_active(&self, pdo: PdoRef) -> bool {
        match pdo.direction {
            Direction::Receive => self.rpdo(pdo.number).is_some_and(|p| p.id.is_some()),
            Direction::Transmit => self.tpdo(pdo.number).is_some_and(|p| p.id.is_some()),
        }
    }

    /// The mapping of `pdo` as last loaded, if it is usable (empty when sub-index 0 is 0).
    pub fn mapping(&self, pdo: PdoRef) -> Option<&[Mapped]> {
        match pdo.direction {
            Direction::Receive => self.rpdo(pdo.number).map(|p| p.map.as_slice()),
            Direction::Transmit => self.tpdo(pdo.number).map(|p| p.map.as_slice()),
        }
    }

    /// Reads every PDO's parameters from `od` (after power-on, a reset communication, or an SDO
    /// write to 1400h–1BFFh). PDOs whose parameters did not change keep their timers and SYNC
    /// counting; changed ones restart as on entering Operational. Parameters that cannot run are
    /// reported as [`PdoEvent::Disabled`].
    pub fn reload(&mut self, now: Instant, od: &DynamicOd) {
        let operational = self.operational();
        let mut rpdos = Vec::new();
        let mut tpdos = Vec::new();
        for offset in 0..MAX_PDOS {
            let number = offset + 1;
            for direction in [Direction::Receive, Direction::Transmit] {
                let pdo = PdoRef { direction, number };
                let Some(comm) = read_comm(od, pdo) else {
                    continue;
                };
                let (map, id, error) = match self.load(od, pdo, &comm) {
                    Ok((map, id)) => (map, id, None),
                    Err(error) => (Vec::new(), None, Some(error)),
                };
                let old_error = match direction {
                    Direction::Receive => self.rpdo(number).and_then(|p| p.error),
                    Direction::Transmit => self.tpdo(number).and_then(|p| p.error),
                };
                if let Some(error) = error
                    && old_error != Some(error)
                {
                    self.events.push_back(PdoEvent::Disabled { pdo, error });
                }
                let bits: u32 = map.iter().map(|m| u32::from(m.bits())).sum();
                let bytes = bits.div_ceil(8) as usize;
                match direction {
                    Direction::Receive => {
                        let old = self.rpdo(number);
                        if let Some(old) =
                            old.filter(|o| o.comm == comm && o.map == map && o.id == id && o.error == error)
                        {
                            rpdos.push(old.clone());
                        } else {
                            rpdos.push(Rpdo {
                                number,
                                comm,
                                map,
                                id,
                                bytes,
                                error,
                                buffered: None,
                                deadline: None,
                                timed_out: false,
                                length: LengthState::Ok,
                            });
                        }
                    }
                    Direction::Transmit => {
                        let old = self.tpdo(number);
                        if let Some(old) =
                            old.filter(|o| o.comm == comm && o.map == map && o.id == id && o.error == error)
                        {
                            tpdos.push(old.clone());
                        } else {
                            let mut tpdo = Tpdo {
                                number,
                                comm,
                                map,
                                id,
                                bytes,
                                error,
                                event_pending: false,
                                pending_since: now,
                                inhibit_until: Instant::ZERO,
                                event_due: None,
                                sync_pending: false,
                                sync_started: false,
                                sync_left: 0,
                                sample: None,
                            };
                            if operational {
                                tpdo.start(now);
                            }
                            tpdos.push(tpdo);
                        }
                    }
                }
            }
        }
        self.rpdos = rpdos;
        self.tpdos = tpdos;
    }

    /// The NMT slave changed state. PDOs run in Operational only: entering it starts the TPDOs
    /// (event-driven ones are sent once), leaving it stops every timer and drops buffered RPDOs.
    pub fn set_state(&mut self, now: Instant, state: NmtSlaveState) {
        let was = self.operational();
        self.state = state;
        let is = self.operational();
        self.window_closed = false;
        if was && !is {
            for tpdo in &mut self.tpdos {
                tpdo.stop();
            }
            for rpdo in &mut self.rpdos {
                rpdo.buffered = None;
                rpdo.deadline = None;
            }
            if state == NmtSlaveState::Initialisation {
                self.transmit.clear();
            }
        } else if is && !was {
            for tpdo in &mut self.tpdos {
                tpdo.start(now);
            }
        }
    }

    /// The checks a write of `data` to `key` must pass before the SDO server stores it, for keys in
    /// 1400h–1BFFh (every other key passes). `od` holds the values before the write. Data of a
    /// length the entry does not take passes too: the dictionary refuses it with its own abort
    /// code.
    pub fn check_write(&self, key: ObjectKey, data: &[u8], od: &DynamicOd) -> Result<(), PdoConfigError> {
        let Some((pdo, comm)) = PdoRef::from_index(key.index) else {
            return Ok(());
        };
        let Some(entry) = od.get(key) else {
            return Ok(());
        };
        if data.len() != entry.value().len() || data.is_empty() || data.len() > 4 {
            return Ok(());
        }
        let value = le_u64(data) as u32;
        if comm {
            self.check_comm_write(pdo, key.sub, value, od)
        } else {
            self.check_mapping_write(pdo, key.sub, value, od)
        }
    }

    fn check_comm_write(
        &self,
        pdo: PdoRef,
        sub: u8,
        value: u32,
        od: &DynamicOd,
    ) -> Result<(), PdoConfigError> {
        let index = pdo.comm_index();
        let current = read_u32(od, ObjectKey::new(index, 1)).unwrap_or(COB_ID_INVALID);
        let currently_valid = current & COB_ID_INVALID == 0;
        let transmission_type = read_u32(od, ObjectKey::new(index, 2)).unwrap_or(255) as u8;
        let tx = pdo.direction == Direction::Transmit;
        match sub {
            1 => {
                check_cob_id(pdo, value)?;
                if value & COB_ID_INVALID == 0 && currently_valid && cob_can_id(value) != cob_can_id(current)
                {
                    return Err(PdoConfigError::CanIdChangedWhileValid { pdo });
                }
                if tx && value & COB_ID_NO_RTR != 0 && matches!(transmission_type, 252 | 253) {
                    return Err(PdoConfigError::RtrNotAllowed {
                        pdo,
                        transmission_type,
                    });
                }
                Ok(())
            }
            2 => {
                let value = value as u8;
                check_transmission_type(pdo, value)?;
                if tx && current & COB_ID_NO_RTR != 0 && matches!(value, 252 | 253) {
                    return Err(PdoConfigError::RtrNotAllowed {
                        pdo,
                        transmission_type: value,
                    });
                }
                Ok(())
            }
            3 | 6 if tx => {
                if sub == 6 && value > 240 {
                    return Err(PdoConfigError::SyncStartValueTooHigh {
                        pdo,
                        value: value as u8,
                    });
                }
                let old = read_u32(od, ObjectKey::new(index, sub));
                if currently_valid && old != Some(value) {
                    return Err(PdoConfigError::ChangedWhileValid { pdo, sub });
                }
                Ok(())
            }
            _ => Ok(()),
        }
    }

    fn check_mapping_write(
        &self,
        pdo: PdoRef,
        sub: u8,
        value: u32,
        od: &DynamicOd,
    ) -> Result<(), PdoConfigError> {
        let cob_id = read_u32(od, ObjectKey::new(pdo.comm_index(), 1)).unwrap_or(COB_ID_INVALID);
        if cob_id & COB_ID_INVALID == 0 {
            return Err(PdoConfigError::MappingWhileValid { pdo });
        }
        let index = pdo.mapping_index();
        if sub == 0 {
            let entries: Vec<u32> = (1..=value.min(255) as u8)
                .map_while(|s| read_u32(od, ObjectKey::new(index, s)))
                .collect();
            self.check_mapping(od, pdo, value as u8, &entries).map(|_| ())
        } else {
            let count = read_u32(od, ObjectKey::new(index, 0)).unwrap_or(0);
            if count != 0 {
                return Err(PdoConfigError::MappingWhileEnabled { pdo });
            }
            if value == 0 {
                return Ok(()); // clearing an entry
            }
            self.check_entry(od, pdo, value).map(|_| ())
        }
    }

    /// Checks a mapping of `count` entries, `entries` being those present (1..=count).
    fn check_mapping(
        &self,
        od: &DynamicOd,
        pdo: PdoRef,
        count: u8,
        entries: &[u32],
    ) -> Result<Vec<Mapped>, PdoConfigError> {
        if count >= 0xFE {
            return Err(PdoConfigError::MpdoNotSupported { pdo, count });
        }
        let available = od
            .object(pdo.mapping_index())
            .iter()
            .filter(|e| e.key().sub != 0)
            .count()
            .min(usize::from(MAX_MAPPED_OBJECTS)) as u8;
        if count > available || entries.len() < usize::from(count) {
            return Err(PdoConfigError::TooManyObjects {
                pdo,
                count,
                max: available,
            });
        }
        let mut map = Vec::with_capacity(entries.len());
        let mut bits = 0u32;
        for &raw in entries.iter().take(usize::from(count)) {
            let mapped = self.check_entry(od, pdo, raw)?;
            bits += u32::from(mapped.bits());
            map.push(mapped);
        }
        if bits > MAX_MAPPED_BITS {
            return Err(PdoConfigError::LengthExceeded { pdo, bits });
        }
        Ok(map)
    }

    fn check_entry(&self, od: &DynamicOd, pdo: PdoRef, raw: u32) -> Result<Mapped, PdoConfigError> {
        let key = ObjectKey::new((raw >> 16) as u16, (raw >> 8) as u8);
        let bits = raw as u8;
        if matches!(key.index, 1..=7) && key.sub == 0 && od.object(key.index).is_empty() {
            if !self.dummies.allows(key.index) {
                return Err(PdoConfigError::ObjectDoesNotExist { pdo, key });
            }
            let max = canopener_od::DataType(key.index).byte_size().unwrap_or(0) as u32 * 8;
            if bits == 0 {
                return Err(PdoConfigError::ZeroLength { pdo, entry: raw });
            }
            if u32::from(bits) > max {
                return Err(PdoConfigError::MappingLengthTooLong { pdo, key, bits, max });
            }
            return Ok(Mapped::Dummy { bits });
        }
        let Some(entry) = od.get(key) else {
            return Err(PdoConfigError::ObjectDoesNotExist { pdo, key });
        };
        let mappable = match pdo.direction {
            Direction::Receive => entry.rpdo_mappable(),
            Direction::Transmit => entry.tpdo_mappable(),
        };
        if !mappable {
            return Err(PdoConfigError::NotMappable { pdo, key });
        }
        if entry.data_type().is_variable_length() || entry.data_type().byte_size().is_none() {
            return Err(PdoConfigError::VariableLength { pdo, key });
        }
        if bits == 0 {
            return Err(PdoConfigError::ZeroLength { pdo, entry: raw });
        }
        // The stored bytes bound the length, so a BOOLEAN maps as 1 or 8 bits.
        let max = (entry.value().len().min(8) * 8) as u32;
        if u32::from(bits) > max {
            return Err(PdoConfigError::MappingLengthTooLong { pdo, key, bits, max });
        }
        Ok(Mapped::Object { key, bits })
    }

    /// Validates the parameters of `pdo` as they stand in `od`.
    fn load(
        &self,
        od: &DynamicOd,
        pdo: PdoRef,
        comm: &Comm,
    ) -> Result<(Vec<Mapped>, Option<CanId>), PdoConfigError> {
        check_transmission_type(pdo, comm.transmission_type)?;
        let index = pdo.mapping_index();
        let count = read_u32(od, ObjectKey::new(index, 0)).unwrap_or(0).min(255) as u8;
        let entries: Vec<u32> = (1..=count)
            .map_while(|s| read_u32(od, ObjectKey::new(index, s)))
            .collect();
        let map = self.check_mapping(od, pdo, count, &entries)?;
        if !comm.valid() || map.is_empty() {
            return Ok((map, None));
        }
        check_cob_id(pdo, comm.cob_id)?;
        if pdo.direction == Direction::Transmit
            && comm.cob_id & COB_ID_NO_RTR != 0
            && matches!(comm.transmission_type, 252 | 253)
        {
            return Err(PdoConfigError::RtrNotAllowed {
                pdo,
                transmission_type: comm.transmission_type,
            });
        }
        Ok((map, comm.can_id()))
    }

    /// A mapped value changed (for example a digital input): TPDOs of type 254/255 mapping `key` are
    /// sent (once the inhibit time allows), those of type 0 on the next SYNC. Returns whether any
    /// active TPDO maps `key`. Does nothing outside Operational.
    pub fn application_event(&mut self, now: Instant, key: ObjectKey) -> bool {
        let mut any = false;
        let numbers: Vec<u16> = self
            .tpdos
            .iter()
            .filter(|t| {
                t.map
                    .iter()
                    .any(|m| matches!(m, Mapped::Object { key: k, .. } if *k == key))
            })
            .map(|t| t.number)
            .collect();
        for number in numbers {
            any |= self.trigger_tpdo(now, number);
        }
        any
    }

    /// Requests a transmission of TPDO `number` as an application event does (CiA 401 devices tie
    /// their input interrupts to a TPDO this way). Returns whether the TPDO is active and of type 0,
    /// 254 or 255. Does nothing outside Operational.
    pub fn trigger_tpdo(&mut self, now: Instant, number: u16) -> bool {
        if !self.operational() {
            return false;
        }
        let Some(tpdo) = self
            .tpdos
            .iter_mut()
            .find(|t| t.number == number && t.id.is_some())
        else {
            return false;
        };
        match tpdo.comm.transmission_type {
            0 => tpdo.sync_pending = true,
            254 | 255 => {
                if !tpdo.event_pending {
                    tpdo.event_pending = true;
                    tpdo.pending_since = now;
                }
            }
            _ => return false,
        }
        true
    }

    /// Feeds a received frame: an RPDO (data frame on an RPDO's CAN-ID) or a remote request for a
    /// TPDO. Returns whether the frame was one of these and was processed (only in Operational).
    pub fn handle_frame(&mut self, now: Instant, frame: &CanFrame, od: &mut DynamicOd) -> bool {
        if !self.operational() {
            return false;
        }
        if frame.is_remote() {
            return self.handle_rtr(frame, od);
        }
        let mut handled = false;
        for i in 0..self.rpdos.len() {
            if self.rpdos.get(i).is_some_and(|rpdo| rpdo.id == Some(frame.id())) {
                handled = true;
                self.receive(now, i, frame.data(), od);
            }
        }
        handled
    }

    /// Answers a remote request for a TPDO whatever the NMT state: for the `Device`'s
    /// `tpdo-rtr-in-pre-operational` fault, which lets remote requests through where CiA 301 keeps
    /// PDOs silent. Returns whether a TPDO has the frame's CAN-ID and allows RTR.
    pub(crate) fn handle_rtr(&mut self, frame: &CanFrame, od: &DynamicOd) -> bool {
        let mut handled = false;
        for tpdo in &self.tpdos {
            if tpdo.id != Some(frame.id()) || !tpdo.rtr_allowed() {
                continue;
            }
            let Some(id) = tpdo.id else { continue };
            let data = match tpdo.comm.transmission_type {
                0..=240 | 252 => tpdo.sample,
                _ => Some(sample(od, &tpdo.map)),
            };
            handled = true;
            if let Some(data) = data
                && let Some(bytes) = data.get(..tpdo.bytes)
                && let Ok(frame) = CanFrame::new(id, bytes)
            {
                self.transmit.push_back(frame);
            }
        }
        handled
    }

    fn receive(&mut self, now: Instant, i: usize, data: &[u8], od: &mut DynamicOd) {
        let Some(rpdo) = self.rpdos.get_mut(i) else {
            return;
        };
        let number = rpdo.number;
        let expected = rpdo.bytes as u8;
        let received = data.len() as u8;
        let length = match data.len().cmp(&rpdo.bytes) {
            std::cmp::Ordering::Less => LengthState::Short,
            std::cmp::Ordering::Equal => LengthState::Ok,
            std::cmp::Ordering::Greater => LengthState::Long,
        };
        if length != rpdo.length {
            rpdo.length = length;
            self.events.push_back(match length {
                LengthState::Short => PdoEvent::RpdoTooShort {
                    number,
                    received,
                    expected,
                },
                LengthState::Long => PdoEvent::RpdoTooLong {
                    number,
                    received,
                    expected,
                },
                LengthState::Ok => PdoEvent::RpdoLengthOk { number },
            });
        }
        if length == LengthState::Short {
            return;
        }
        if rpdo.comm.event_ms > 0 {
            rpdo.deadline = Some(now + Duration::from_millis(u64::from(rpdo.comm.event_ms)));
        }
        if rpdo.timed_out {
            rpdo.timed_out = false;
            self.events.push_back(PdoEvent::RpdoResumed { number });
        }
        let mut buf = [0u8; 8];
        for (slot, byte) in buf.iter_mut().zip(data.iter().take(rpdo.bytes)) {
            *slot = *byte;
        }
        if rpdo.comm.transmission_type <= 240 {
            if self.window_closed {
                self.events.push_back(PdoEvent::RpdoLate { number });
            } else {
                rpdo.buffered = Some(buf);
            }
        } else {
            write_mapped(od, &rpdo.map, buf);
            self.events.push_back(PdoEvent::RpdoWritten { number });
        }
    }

    /// A SYNC was received (or produced), with its counter if it carries one. Buffered synchronous
    /// RPDOs are written into the dictionary first, then synchronous TPDOs are sampled and those
    /// due are sent. Does nothing outside Operational.
    pub fn handle_sync(&mut self, _now: Instant, counter: Option<u8>, od: &mut DynamicOd) {
        if !self.operational() {
            return;
        }
        self.window_closed = false;
        for rpdo in &mut self.rpdos {
            if let Some(buf) = rpdo.buffered.take() {
                write_mapped(od, &rpdo.map, buf);
                self.events
                    .push_back(PdoEvent::RpdoWritten { number: rpdo.number });
            }
        }
        for tpdo in &mut self.tpdos {
            let Some(id) = tpdo.id else { continue };
            let transmission_type = tpdo.comm.transmission_type;
            if !matches!(transmission_type, 0..=240 | 252) {
                continue;
            }
            let data = sample(od, &tpdo.map);
            tpdo.sample = Some(data);
            let send = match transmission_type {
                0 => std::mem::take(&mut tpdo.sync_pending),
                1..=240 => {
                    if !tpdo.sync_started {
                        // CiA 301 SYNC start value: with a counter in the SYNC, the SYNC whose
                        // counter equals it counts as the first; otherwise the first SYNC seen.
                        let start = tpdo.comm.sync_start;
                        if start == 0 || counter.is_none_or(|c| c == start) {
                            tpdo.sync_started = true;
                            tpdo.sync_left = transmission_type;
                        }
                    }
                    // "Every n-th SYNC", the first counting as one: type 2 goes out with the 2nd,
                    // 4th, ... SYNC, as lely and CANopenNode count.
                    if tpdo.sync_started {
                        tpdo.sync_left = tpdo.sync_left.saturating_sub(1);
                        if tpdo.sync_left == 0 {
                            tpdo.sync_left = transmission_type;
                        }
                        tpdo.sync_left == transmission_type
                    } else {
                        false
                    }
                }
                _ => false,
            };
            if send
                && let Some(bytes) = data.get(..tpdo.bytes)
                && let Ok(frame) = CanFrame::new(id, bytes)
            {
                self.transmit.push_back(frame);
            }
        }
    }

    /// The synchronous window (1007h) after the last SYNC has closed (CiA 301 §7.2.5.1,
    /// [`SyncEvent::WindowClosed`](crate::sync::SyncEvent::WindowClosed)): synchronous RPDOs that
    /// arrive from now until the next SYNC are discarded ([`PdoEvent::RpdoLate`]). Synchronous
    /// TPDOs need nothing here: the engine sends them the moment the SYNC is handled, inside the
    /// window, so none is ever pending when it closes.
    pub fn window_closed(&mut self) {
        self.window_closed = true;
    }

    /// Runs the timers due at `now`: event-driven TPDOs (event timer, end of inhibit time,
    /// application events), sampling `od`; RPDO deadline monitoring.
    pub fn handle_timeout(&mut self, now: Instant, od: &DynamicOd) {
        if !self.operational() {
            return;
        }
        for tpdo in &mut self.tpdos {
            let Some(id) = tpdo.id else { continue };
            if !tpdo.is_event_driven() {
                continue;
            }
            if let Some(due) = tpdo.event_due
                && due <= now
            {
                tpdo.event_due = None;
                if !tpdo.event_pending {
                    tpdo.event_pending = true;
                    tpdo.pending_since = due;
                }
            }
            let scheduled = tpdo.pending_since.max(tpdo.inhibit_until);
            if tpdo.event_pending && now >= scheduled {
                let data = sample(od, &tpdo.map);
                if let Some(bytes) = data.get(..tpdo.bytes)
                    && let Ok(frame) = CanFrame::new(id, bytes)
                {
                    self.transmit.push_back(frame);
                }
                tpdo.event_pending = false;
                // Inhibit time in 100 µs units, event timer in ms (CiA 301, PDO communication
                // parameter); the event timer restarts on every transmission. Both run from when
                // the transmission was due, so a driver that wakes up late (a real-time loop on a
                // busy OS) does not stretch every period; one later than a whole period starts
                // afresh rather than catching up in a burst.
                let inhibit = Duration::from_micros(u64::from(tpdo.comm.inhibit_100us) * 100);
                let period = Duration::from_millis(u64::from(tpdo.comm.event_ms));
                let base = if now.saturating_duration_since(scheduled) < period.max(inhibit) {
                    scheduled
                } else {
                    now
                };
                tpdo.inhibit_until = base + inhibit;
                tpdo.event_due = (tpdo.comm.event_ms > 0).then(|| base + period);
            }
        }
        for rpdo in &mut self.rpdos {
            if let Some(deadline) = rpdo.deadline
                && deadline <= now
            {
                rpdo.deadline = None;
                rpdo.timed_out = true;
                self.events
                    .push_back(PdoEvent::RpdoTimeout { number: rpdo.number });
            }
        }
    }

    /// The next frame to send.
    pub fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.transmit.pop_front()
    }

    /// The next event for the `Device`.
    pub fn poll_event(&mut self) -> Option<PdoEvent> {
        self.events.pop_front()
    }

    /// When [`PdoEngine::handle_timeout`] should run next: a TPDO transmission waiting for its
    /// inhibit time or due now, an event timer, an RPDO deadline. `None` outside Operational.
    pub fn poll_timeout(&self) -> Option<Instant> {
        if !self.operational() {
            return None;
        }
        let tpdos = self
            .tpdos
            .iter()
            .filter(|t| t.id.is_some() && t.is_event_driven())
            .filter_map(Tpdo::due);
        let rpdos = self.rpdos.iter().filter_map(|r| r.deadline);
        tpdos.chain(rpdos).min()
    }

    fn operational(&self) -> bool {
        self.state.is_active(CommService::Pdo)
    }

    fn rpdo(&self, number: u16) -> Option<&Rpdo> {
        self.rpdos.iter().find(|p| p.number == number)
    }

    fn tpdo(&self, number: u16) -> Option<&Tpdo> {
        self.tpdos.iter().find(|p| p.number == number)
    }
}

/// The communication parameters of `pdo`, if its COB-ID entry exists. Missing sub-indices take
/// their CiA 301 defaults (type 255, no inhibit time, no event timer, no SYNC start value).
fn read_comm(od: &DynamicOd, pdo: PdoRef) -> Option<Comm> {
    let index = pdo.comm_index();
    let cob_id = read_u32(od, ObjectKey::new(index, 1))?;
    let read = |sub| read_u32(od, ObjectKey::new(index, sub));
    Some(Comm {
        cob_id,
        transmission_type: read(2).unwrap_or(255) as u8,
        inhibit_100us: read(3).unwrap_or(0) as u16,
        event_ms: read(5).unwrap_or(0) as u16,
        sync_start: match pdo.direction {
            Direction::Transmit => read(6).unwrap_or(0) as u8,
            Direction::Receive => 0,
        },
    })
}

fn check_cob_id(pdo: PdoRef, value: u32) -> Result<(), PdoConfigError> {
    if value & COB_ID_EXTENDED == 0 && value & 0x1FFF_F800 != 0 {
        return Err(PdoConfigError::UnsupportedCobId { value });
    }
    if value & (COB_ID_INVALID | COB_ID_EXTENDED) == 0 {
        let can_id = (value & 0x7FF) as u16;
        if crate::can_id::is_restricted(can_id) {
            return Err(PdoConfigError::RestrictedCanId { pdo, can_id });
        }
    }
    Ok(())
}

fn check_transmission_type(pdo: PdoRef, value: u8) -> Result<(), PdoConfigError> {
    let reserved = match pdo.direction {
        Direction::Receive => (241..=253).contains(&value),
        Direction::Transmit => (241..=251).contains(&value),
    };
    if reserved {
        return Err(PdoConfigError::ReservedTransmissionType { pdo, value });
    }
    Ok(())
}

/// The CAN-ID a COB-ID selects (bit 29 chooses the format), whether or not it is valid.
fn cob_can_id(cob_id: u32) -> Option<CanId> {
    if cob_id & COB_ID_EXTENDED != 0 {
        CanId::extended(cob_id & 0x1FFF_FFFF).ok()
    } else {
        CanId::standard((cob_id & 0x7FF) as u16).ok()
    }
}

/// Up to 8 little-endian bytes as a number.
fn le_u64(bytes: &[u8]) -> u64 {
    let mut buf = [0u8; 8];
    for (slot, byte) in buf.iter_mut().zip(bytes) {
        *slot = *byte;
    }
    u64::from_le_bytes(buf)
}

fn read_u32(od: &DynamicOd, key: ObjectKey) -> Option<u32> {
    let value = od.get(key)?.value();
    (value.len() <= 4).then(|| le_u64(value) as u32)
}

fn mask(bits: u8) -> u64 {
    match bits {
        0 => 0,
        64.. => u64::MAX,
        n => (1u64 << n) - 1,
    }
}

/// The PDO data of `map`, packed little-endian from bit 0 (missing entries and dummies give zeros).
fn sample(od: &DynamicOd, map: &[Mapped]) -> [u8; 8] {
    let mut acc = 0u64;
    let mut offset = 0u32;
    for item in map {
        let bits = item.bits();
        let value = match item {
            Mapped::Object { key, .. } => od.get(*key).map_or(0, |e| le_u64(e.value())),
            Mapped::Dummy { .. } => 0,
        };
        acc |= (value & mask(bits)).checked_shl(offset).unwrap_or(0);
        offset += u32::from(bits);
    }
    acc.to_le_bytes()
}

/// Writes the PDO data `data` into the entries of `map`; each entry's bits above the mapped length
/// keep their value.
fn write_mapped(od: &mut DynamicOd, map: &[Mapped], data: [u8; 8]) {
    let acc = u64::from_le_bytes(data);
    let mut offset = 0u32;
    for item in map {
        let bits = item.bits();
        if let Mapped::Object { key, .. } = item
            && let Some(mut entry) = od.get_mut(*key)
        {
            let m = mask(bits);
            let field = acc.checked_shr(offset).unwrap_or(0) & m;
            let len = entry.value().len().min(8);
            let old = le_u64(entry.value());
            let new = (old & !m) | field;
            if let Some(bytes) = new.to_le_bytes().get(..len) {
                let _ = entry.set_value(bytes);
            }
        }
        offset += u32::from(bits);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_can::Core;
    use canopener_od::{Access, DataType, Entry};
    use canopener_testkit::frames::any_frame;
    use canopener_testkit::trace::{Trace, ms};

    /// The engine with the dictionary it works on, as a `Device` holds them.
    struct Bench {
        engine: PdoEngine,
        od: DynamicOd,
    }

    impl Core for Bench {
        type Event = PdoEvent;
        fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
            self.engine.handle_frame(now, frame, &mut self.od);
        }
        fn handle_timeout(&mut self, now: Instant) {
            self.engine.handle_timeout(now, &self.od);
        }
        fn poll_transmit(&mut self) -> Option<CanFrame> {
            self.engine.poll_transmit()
        }
        fn poll_event(&mut self) -> Option<PdoEvent> {
            self.engine.poll_event()
        }
        fn poll_timeout(&self) -> Option<Instant> {
            self.engine.poll_timeout()
        }
    }

    const DI1: ObjectKey = ObjectKey::new(0x6000, 1);
    const DI2: ObjectKey = ObjectKey::new(0x6000, 2);
    const DO1: ObjectKey = ObjectKey::new(0x6200, 1);
    const DO2: ObjectKey = ObjectKey::new(0x6200, 2);

    fn entry(index: u16, sub: u8, data_type: DataType, access: Access, value: &[u8], map: bool) -> Entry {
        Entry::new(ObjectKey::new(index, sub), data_type, access, value)
            .unwrap()
            .with_pdo_mapping(map)
    }

    /// Node 5: RPDO1 (205h, type 255, 6200h:01), RPDO2 (invalid, empty), TPDO1 (185h, type 255,
    /// 6000h:01), TPDO2 (invalid, empty), and objects to map.
    fn dictionary() -> DynamicOd {
        use Access::{Const, Ro, Rw, Wo};
        use DataType as T;
        let mut entries = Vec::new();
        for (comm, cob_ids, tx) in [
            (0x1400, [0x205u32, 0x8000_0305], false),
            (0x1800, [0x185, 0x8000_0285], true),
        ] {
            for (n, cob_id) in cob_ids.into_iter().enumerate() {
                let index = comm + n as u16;
                entries.push(entry(
                    index,
                    0,
                    T::UNSIGNED8,
                    Const,
                    &[if tx { 6 } else { 5 }],
                    false,
                ));
                entries.push(entry(index, 1, T::UNSIGNED32, Rw, &cob_id.to_le_bytes(), false));
                entries.push(entry(index, 2, T::UNSIGNED8, Rw, &[255], false));
                entries.push(entry(index, 3, T::UNSIGNED16, Rw, &[0, 0], false));
                entries.push(entry(index, 5, T::UNSIGNED16, Rw, &[0, 0], false));
                if tx {
                    entries.push(entry(index, 6, T::UNSIGNED8, Rw, &[0], false));
                }
                let mapping = index + 0x200;
                let first: u32 = match (tx, n) {
                    (false, 0) => 0x6200_0108,
                    (true, 0) => 0x6000_0108,
                    _ => 0,
                };
                entries.push(entry(
                    mapping,
                    0,
                    T::UNSIGNED8,
                    Rw,
                    &[u8::from(first != 0)],
                    false,
                ));
                entries.push(entry(mapping, 1, T::UNSIGNED32, Rw, &first.to_le_bytes(), false));
                for sub in 2..=8 {
                    entries.push(entry(mapping, sub, T::UNSIGNED32, Rw, &[0; 4], false));
                }
            }
        }
        entries.push(entry(0x2000, 0, T::UNSIGNED32, Rw, &[0; 4], false));
        entries.push(entry(0x2001, 0, T::VISIBLE_STRING, Rw, b"ab", true));
        entries.push(entry(0x2002, 0, T::UNSIGNED32, Wo, &[0; 4], true));
        entries.push(entry(0x2003, 0, T::UNSIGNED64, Ro, &[0; 8], true));
        entries.push(entry(0x2004, 0, T::BOOLEAN, Rw, &[0], true));
        entries.push(entry(0x6000, 0, T::UNSIGNED8, Ro, &[2], false));
        entries.push(entry(0x6000, 1, T::UNSIGNED8, Ro, &[0], true));
        entries.push(entry(0x6000, 2, T::UNSIGNED8, Ro, &[0], true));
        entries.push(entry(0x6200, 0, T::UNSIGNED8, Ro, &[2], false));
        entries.push(entry(0x6200, 1, T::UNSIGNED8, Rw, &[0], true));
        entries.push(entry(0x6200, 2, T::UNSIGNED8, Rw, &[0], true));
        entries.push(entry(0x6401, 1, T::INTEGER16, Ro, &[0, 0], true));
        DynamicOd::from_entries(entries.len(), entries).unwrap()
    }

    fn set(od: &mut DynamicOd, index: u16, sub: u8, value: u32) {
        let key = ObjectKey::new(index, sub);
        let len = od.get(key).expect("entry").value().len();
        od.set_value(key, &value.to_le_bytes()[..len]).unwrap();
    }

    /// A bench in Operational at 0 ms after `setup` changed the dictionary; what entering
    /// Operational sent is left in the trace.
    fn bench_with(dummies: DummyUsage, setup: impl FnOnce(&mut DynamicOd)) -> Trace<Bench> {
        let mut od = dictionary();
        setup(&mut od);
        let mut engine = PdoEngine::new().with_dummy_usage(dummies);
        engine.reload(Instant::ZERO, &od);
        engine.set_state(Instant::ZERO, NmtSlaveState::Operational);
        Trace::new(Bench { engine, od })
    }

    fn bench(setup: impl FnOnce(&mut DynamicOd)) -> Trace<Bench> {
        bench_with(DummyUsage::NONE, setup)
    }

    fn sync(trace: &mut Trace<Bench>, at: Instant, counter: Option<u8>) {
        trace.advance(at);
        let Bench { engine, od } = &mut trace.core;
        engine.handle_sync(at, counter, od);
    }

    /// The application changes `key` at `at` and reports it.
    fn input(trace: &mut Trace<Bench>, at: Instant, key: ObjectKey, value: u8) {
        trace.advance(at);
        trace.core.od.set_value(key, &[value]).unwrap();
        trace.core.engine.application_event(at, key);
    }

    /// An SDO download as the `Device` runs it: the engine's checks, the dictionary's, then reload.
    fn sdo_write(trace: &mut Trace<Bench>, index: u16, sub: u8, value: u32) -> Result<(), u32> {
        let key = ObjectKey::new(index, sub);
        let len = trace.core.od.get(key).map_or(4, |e| e.value().len());
        let data = &value.to_le_bytes()[..len];
        let Bench { engine, od } = &mut trace.core;
        engine.check_write(key, data, od).map_err(|e| e.abort_code())?;
        od.write(key, data).map_err(|e| e.abort_code())?;
        let now = trace.now;
        trace.core.engine.reload(now, &trace.core.od);
        Ok(())
    }

    fn value(trace: &Trace<Bench>, key: ObjectKey) -> u8 {
        trace.core.od.get(key).unwrap().value()[0]
    }

    #[test]
    fn event_driven_tpdo_on_entering_operational_and_on_events() {
        let mut trace = bench(|_| {});
        trace.advance(ms(1));
        assert_eq!(
            trace.sent(),
            ["0.000 185#00"],
            "sent once on entering operational"
        );
        input(&mut trace, ms(10), DI1, 0x55);
        input(&mut trace, ms(20), DI2, 0x66); // not mapped
        input(&mut trace, ms(30), DI1, 0x01);
        trace.advance(ms(100));
        assert_eq!(trace.sent(), ["10.000 185#55", "30.000 185#01"]);
        assert_eq!(trace.core.poll_timeout(), None, "no event timer");
    }

    #[test]
    fn inhibit_time_exact() {
        let mut trace = bench(|od| set(od, 0x1800, 3, 100)); // 10 ms
        trace.advance(ms(1));
        input(&mut trace, ms(3), DI1, 1);
        assert_eq!(trace.core.poll_timeout(), Some(ms(10)));
        input(&mut trace, ms(4), DI1, 2); // merges with the waiting transmission
        trace.advance(Instant::from_micros(9_999));
        assert_eq!(trace.sent(), ["0.000 185#00"]);
        trace.advance(ms(10));
        assert_eq!(
            trace.sent(),
            ["10.000 185#02"],
            "exactly 100 × 100 µs after the last one"
        );
        input(&mut trace, Instant::from_micros(20_000), DI1, 3);
        input(&mut trace, ms(35), DI1, 4);
        trace.advance(ms(50));
        assert_eq!(trace.sent(), ["20.000 185#03", "35.000 185#04"]);
    }

    #[test]
    fn event_timer_exact_and_restarted_by_events() {
        let mut trace = bench(|od| set(od, 0x1800, 5, 50));
        trace.advance(ms(120));
        input(&mut trace, ms(130), DI1, 7);
        trace.advance(ms(200));
        assert_eq!(
            trace.sent(),
            [
                "0.000 185#00",
                "50.000 185#00",
                "100.000 185#00",
                "130.000 185#07",
                "180.000 185#07"
            ]
        );
        assert_eq!(trace.core.poll_timeout(), Some(ms(230)));
    }

    #[test]
    fn event_timer_keeps_its_period_when_the_driver_wakes_up_late() {
        let mut trace = bench(|od| set(od, 0x1800, 5, 100));
        // Every wake-up comes 4 ms after the deadline, as a coarse OS timer delivers it.
        for _ in 0..3 {
            trace.wake_late(Duration::from_millis(4));
        }
        assert_eq!(
            trace.sent(),
            ["4.000 185#00", "104.000 185#00", "204.000 185#00"],
            "each sent 4 ms late, but one every 100 ms"
        );
        // A wake-up more than a period late starts the period afresh instead of a burst.
        let woke = trace.wake_late(Duration::from_millis(250));
        assert_eq!(woke, ms(550));
        assert_eq!(trace.sent(), ["550.000 185#00"]);
        assert_eq!(trace.core.poll_timeout(), Some(ms(650)));
    }

    #[test]
    fn event_timer_waits_for_the_inhibit_time() {
        let mut trace = bench(|od| {
            set(od, 0x1800, 5, 5);
            set(od, 0x1800, 3, 80); // 8 ms
        });
        trace.advance(ms(20));
        assert_eq!(trace.sent(), ["0.000 185#00", "8.000 185#00", "16.000 185#00"]);
    }

    #[test]
    fn acyclic_synchronous_type_0() {
        let mut trace = bench(|od| set(od, 0x1800, 2, 0));
        trace.advance(ms(5));
        assert!(trace.sent().is_empty(), "nothing before the SYNC");
        sync(&mut trace, ms(10), None);
        sync(&mut trace, ms(20), None);
        input(&mut trace, ms(25), DI1, 9);
        input(&mut trace, ms(26), DI1, 10);
        trace.advance(ms(29));
        sync(&mut trace, ms(30), None);
        sync(&mut trace, ms(40), None);
        assert_eq!(trace.sent(), ["10.000 185#00", "30.000 185#0A"]);
        assert_eq!(trace.core.poll_timeout(), None);
    }

    #[test]
    fn cyclic_synchronous_without_counter() {
        let mut trace = bench(|od| set(od, 0x1800, 2, 3));
        for i in 1..=8 {
            input(&mut trace, ms(i * 10 - 1), DI1, i as u8);
            sync(&mut trace, ms(i * 10), None);
        }
        assert_eq!(
            trace.sent(),
            ["30.000 185#03", "60.000 185#06"],
            "every third SYNC, the first counting as one"
        );
    }

    #[test]
    fn cyclic_synchronous_with_sync_start_value() {
        let mut trace = bench(|od| {
            set(od, 0x1800, 2, 2);
            set(od, 0x1800, 6, 3);
        });
        for counter in 1..=8u8 {
            sync(&mut trace, ms(u64::from(counter) * 10), Some(counter));
        }
        assert_eq!(
            trace.sent(),
            ["40.000 185#00", "60.000 185#00", "80.000 185#00"],
            "the SYNC with counter 3 is the first, so every second from there"
        );
        // Without a counter in the SYNC the start value has no effect.
        let mut trace = bench(|od| {
            set(od, 0x1800, 2, 2);
            set(od, 0x1800, 6, 3);
        });
        for i in 1..=4 {
            sync(&mut trace, ms(i * 10), None);
        }
        assert_eq!(trace.sent(), ["20.000 185#00", "40.000 185#00"]);
    }

    #[test]
    fn sync_start_value_with_counter_wrapping() {
        let mut trace = bench(|od| {
            set(od, 0x1800, 2, 1);
            set(od, 0x1800, 6, 2);
        });
        for (i, counter) in [4u8, 5, 1, 2, 3].into_iter().enumerate() {
            sync(&mut trace, ms(i as u64 * 10 + 10), Some(counter));
        }
        assert_eq!(trace.sent(), ["40.000 185#00", "50.000 185#00"]);
    }

    #[test]
    fn rtr_synchronous_type_252_samples_at_sync() {
        let mut trace = bench(|od| set(od, 0x1800, 2, 252));
        trace.rx(ms(5), "185#R1");
        assert!(trace.sent().is_empty(), "nothing sampled before the first SYNC");
        input(&mut trace, ms(8), DI1, 0x11);
        sync(&mut trace, ms(10), None);
        assert!(trace.sent().is_empty(), "252 is not sent on SYNC");
        input(&mut trace, ms(12), DI1, 0x22);
        trace.rx(ms(15), "185#R1");
        sync(&mut trace, ms(20), None);
        trace.rx(ms(25), "185#R1");
        assert_eq!(trace.sent(), ["15.000 185#11", "25.000 185#22"]);
    }

    #[test]
    fn rtr_event_driven_type_253() {
        let mut trace = bench(|od| set(od, 0x1800, 2, 253));
        trace.advance(ms(5));
        assert!(trace.sent().is_empty(), "253 is sent on request only");
        trace.rx(ms(5), "185#R1");
        input(&mut trace, ms(6), DI1, 0x33);
        trace.rx(ms(7), "185#R");
        trace.rx(ms(8), "186#R1"); // another node's TPDO
        assert_eq!(trace.sent(), ["5.000 185#00", "7.000 185#33"]);
    }

    #[test]
    fn rtr_on_other_types_and_refused_by_bit_30() {
        let mut trace = bench(|_| {});
        trace.advance(ms(1));
        trace.sent();
        input(&mut trace, ms(2), DI1, 0x44);
        trace.advance(ms(2));
        trace.core.od.set_value(DI1, &[0x45]).unwrap(); // no event: RTR still sees the value
        trace.rx(ms(3), "185#R1");
        assert_eq!(trace.sent(), ["2.000 185#44", "3.000 185#45"]);

        let mut trace = bench(|od| set(od, 0x1800, 1, COB_ID_NO_RTR | 0x185));
        trace.advance(ms(1));
        trace.sent();
        trace.rx(ms(2), "185#R1");
        assert!(trace.sent().is_empty(), "COB-ID bit 30 forbids RTR");

        let mut trace = bench(|od| set(od, 0x1800, 2, 1));
        trace.rx(ms(1), "185#R1");
        sync(&mut trace, ms(10), None);
        input(&mut trace, ms(12), DI1, 0x99);
        trace.rx(ms(15), "185#R1");
        assert_eq!(
            trace.sent(),
            ["10.000 185#00", "15.000 185#00"],
            "cyclic: the data sampled at the last SYNC"
        );
    }

    #[test]
    fn rpdo_write_through() {
        let mut trace = bench(|_| {});
        trace.rx(ms(5), "205#2A");
        assert_eq!(value(&trace, DO1), 0x2A);
        trace.rx(ms(6), "305#2B"); // RPDO2 is not valid
        trace.rx(ms(7), "205#R1"); // a remote frame is no RPDO
        assert_eq!(value(&trace, DO1), 0x2A);
        assert_eq!(trace.events(), ["5.000 RpdoWritten { number: 1 }"]);
    }

    #[test]
    fn rpdo_synchronous_buffered_until_sync() {
        let mut trace = bench(|od| set(od, 0x1400, 2, 0));
        trace.rx(ms(5), "205#01");
        trace.rx(ms(6), "205#02");
        assert_eq!(value(&trace, DO1), 0, "not before the SYNC");
        sync(&mut trace, ms(10), None);
        assert_eq!(value(&trace, DO1), 2, "the last one received");
        sync(&mut trace, ms(20), None);
        assert_eq!(trace.events(), ["10.000 RpdoWritten { number: 1 }"]);
    }

    #[test]
    fn rpdo_length_mismatch() {
        let mut trace = bench(|od| {
            set(od, 0x1600, 0, 2);
            set(od, 0x1600, 2, 0x6200_0208);
        });
        trace.rx(ms(1), "205#11");
        trace.rx(ms(2), "205#12");
        assert_eq!(
            (value(&trace, DO1), value(&trace, DO2)),
            (0, 0),
            "too short: not processed"
        );
        trace.rx(ms(3), "205#212223");
        assert_eq!(
            (value(&trace, DO1), value(&trace, DO2)),
            (0x21, 0x22),
            "too long: processed"
        );
        trace.rx(ms(4), "205#3132");
        trace.rx(ms(5), "205#4142");
        assert_eq!(
            trace.events(),
            [
                "1.000 RpdoTooShort { number: 1, received: 1, expected: 2 }",
                "3.000 RpdoTooLong { number: 1, received: 3, expected: 2 }",
                "3.000 RpdoWritten { number: 1 }",
                "4.000 RpdoLengthOk { number: 1 }",
                "4.000 RpdoWritten { number: 1 }",
                "5.000 RpdoWritten { number: 1 }",
            ]
        );
        let short = PdoEvent::RpdoTooShort {
            number: 1,
            received: 1,
            expected: 2,
        };
        assert_eq!(short.emcy_code(), Some(0x8210));
        let long = PdoEvent::RpdoTooLong {
            number: 1,
            received: 3,
            expected: 2,
        };
        assert_eq!(long.emcy_code(), Some(0x8220));
        assert_eq!(PdoEvent::RpdoLengthOk { number: 1 }.emcy_code(), None);
    }

    #[test]
    fn rpdo_deadline_monitoring() {
        let mut trace = bench(|od| set(od, 0x1400, 5, 100));
        trace.advance(ms(500));
        assert!(trace.events().is_empty(), "armed only by the first RPDO");
        trace.rx(ms(510), "205#01");
        trace.rx(ms(560), "205#02");
        assert_eq!(trace.core.poll_timeout(), Some(ms(660)));
        trace.advance(Instant::from_micros(659_999));
        trace.events();
        trace.advance(ms(900));
        trace.rx(ms(950), "205#03");
        assert_eq!(
            trace.events(),
            [
                "660.000 RpdoTimeout { number: 1 }",
                "950.000 RpdoResumed { number: 1 }",
                "950.000 RpdoWritten { number: 1 }",
            ]
        );
        assert_eq!(PdoEvent::RpdoTimeout { number: 1 }.emcy_code(), Some(0x8250));
    }

    #[test]
    fn pdos_run_only_in_operational() {
        let mut trace = bench(|od| set(od, 0x1800, 5, 10));
        trace.advance(ms(15));
        assert_eq!(trace.sent(), ["0.000 185#00", "10.000 185#00"]);
        trace.core.engine.set_state(ms(15), NmtSlaveState::PreOperational);
        assert_eq!(trace.core.poll_timeout(), None);
        trace.rx(ms(20), "205#05");
        input(&mut trace, ms(21), DI1, 1);
        sync(&mut trace, ms(22), None);
        trace.rx(ms(23), "185#R1");
        trace.advance(ms(100));
        assert!(trace.sent().is_empty());
        assert_eq!(value(&trace, DO1), 0);
        trace.core.engine.set_state(ms(100), NmtSlaveState::Stopped);
        trace.core.engine.set_state(ms(100), NmtSlaveState::Operational);
        trace.advance(ms(115));
        assert_eq!(trace.sent(), ["100.000 185#01", "110.000 185#01"]);
    }

    #[test]
    fn dynamic_mapping_procedure() {
        let mut trace = bench(|_| {});
        trace.advance(ms(1));
        trace.sent();
        trace
            .core
            .od
            .set_value(ObjectKey::new(0x6401, 1), &[0x34, 0x12])
            .unwrap();
        trace.core.od.set_value(DI2, &[0x56]).unwrap();
        // 1. invalid, 2. disable, 3. entries, 4. enable, 5. valid
        assert_eq!(sdo_write(&mut trace, 0x1800, 1, COB_ID_INVALID | 0x185), Ok(()));
        assert_eq!(sdo_write(&mut trace, 0x1A00, 0, 0), Ok(()));
        assert_eq!(sdo_write(&mut trace, 0x1A00, 1, 0x6401_0110), Ok(()));
        assert_eq!(sdo_write(&mut trace, 0x1A00, 2, 0x6000_0208), Ok(()));
        assert_eq!(sdo_write(&mut trace, 0x1A00, 0, 2), Ok(()));
        trace.advance(ms(2));
        assert!(trace.sent().is_empty(), "not valid yet");
        assert_eq!(sdo_write(&mut trace, 0x1800, 1, 0x185), Ok(()));
        trace.advance(ms(3));
        assert_eq!(
            trace.sent(),
            ["2.000 185#341256"],
            "restarts as on entering operational"
        );
        let pdo = PdoRef {
            direction: Direction::Transmit,
            number: 1,
        };
        assert!(trace.core.engine.is_active(pdo));
        assert_eq!(
            trace.core.engine.mapping(pdo),
            Some(
                &[
                    Mapped::Object {
                        key: ObjectKey::new(0x6401, 1),
                        bits: 16
                    },
                    Mapped::Object { key: DI2, bits: 8 }
                ][..]
            )
        );
        assert!(trace.events().is_empty());
    }

    /// Abort codes of the mapping procedure, each with the write refused and nothing changed.
    #[test]
    fn every_mapping_abort_code() {
        let mut trace = bench(|_| {});
        let map = |index, sub| ObjectKey::new(index, sub);
        // 0601 0000h: mapping while the PDO is valid, entries while sub-index 0 is not 0.
        assert_eq!(sdo_write(&mut trace, 0x1A00, 0, 0), Err(0x0601_0000));
        assert_eq!(sdo_write(&mut trace, 0x1A00, 1, 0x6000_0208), Err(0x0601_0000));
        assert_eq!(sdo_write(&mut trace, 0x1600, 1, 0x6200_0208), Err(0x0601_0000));
        sdo_write(&mut trace, 0x1800, 1, COB_ID_INVALID | 0x185).unwrap();
        sdo_write(&mut trace, 0x1400, 1, COB_ID_INVALID | 0x205).unwrap();
        assert_eq!(sdo_write(&mut trace, 0x1A00, 2, 0x6000_0208), Err(0x0601_0000));
        sdo_write(&mut trace, 0x1A00, 0, 0).unwrap();
        sdo_write(&mut trace, 0x1600, 0, 0).unwrap();
        let cases: [(u16, u32, u32); 14] = [
            // 0602 0000h: object missing, sub-index missing, dummy type not enabled.
            (0x1A00, 0x7000_0008, 0x0602_0000),
            (0x1A00, 0x6000_0308, 0x0602_0000),
            (0x1600, 0x0005_0008, 0x0602_0000),
            // 0604 0041h: no PDOMapping, wrong direction, length larger than the object.
            (0x1A00, 0x2000_0020, 0x0604_0041),
            (0x1A00, 0x6000_0008, 0x0604_0041),
            (0x1600, 0x6000_0108, 0x0604_0041),
            (0x1A00, 0x2002_0020, 0x0604_0041),
            (0x1A00, 0x6000_0110, 0x0604_0041),
            (0x1A00, 0x2004_0009, 0x0604_0041),
            // 0604 0041h too (in the CCT's set for a mapping entry): length 0, variable-length object.
            (0x1A00, 0x6000_0100, 0x0604_0041),
            (0x1A00, 0x2001_0010, 0x0604_0041),
            (0x1600, 0x2001_0010, 0x0604_0041),
            // accepted: BOOLEAN as 1 or 8 bits, a write-only object into an RPDO
            (0x1A00, 0x2004_0001, 0),
            (0x1600, 0x2002_0020, 0),
        ];
        for (index, entry, code) in cases {
            let before = trace.core.od.get(map(index, 1)).unwrap().value().to_vec();
            let result = sdo_write(&mut trace, index, 1, entry);
            if code == 0 {
                assert_eq!(result, Ok(()), "{index:04X}h:01 = {entry:08X}h");
                sdo_write(&mut trace, index, 1, 0).unwrap();
            } else {
                assert_eq!(result, Err(code), "{index:04X}h:01 = {entry:08X}h");
                assert_eq!(trace.core.od.get(map(index, 1)).unwrap().value(), before);
            }
        }
        // 0604 0042h: sub-index 0 above the entries present, and more than 64 bits.
        assert_eq!(sdo_write(&mut trace, 0x1A00, 0, 9), Err(0x0604_0042));
        assert_eq!(sdo_write(&mut trace, 0x1A00, 0, 0x41), Err(0x0604_0042));
        sdo_write(&mut trace, 0x1A00, 1, 0x2003_0040).unwrap();
        sdo_write(&mut trace, 0x1A00, 2, 0x6000_0108).unwrap();
        assert_eq!(sdo_write(&mut trace, 0x1A00, 0, 2), Err(0x0604_0042));
        assert_eq!(sdo_write(&mut trace, 0x1A00, 0, 1), Ok(()), "64 bits fit");
        sdo_write(&mut trace, 0x1A00, 0, 0).unwrap();
        // 0604 0042h: MPDO (in the CCT's set for enabling); enabling re-checks the entries
        // (0602 0000h for an empty one).
        assert_eq!(sdo_write(&mut trace, 0x1A00, 0, 0xFE), Err(0x0604_0042));
        assert_eq!(sdo_write(&mut trace, 0x1A00, 0, 0xFF), Err(0x0604_0042));
        assert_eq!(sdo_write(&mut trace, 0x1A00, 0, 3), Err(0x0602_0000));
        // the errors themselves
        let pdo = PdoRef {
            direction: Direction::Transmit,
            number: 1,
        };
        let err = trace
            .core
            .engine
            .check_write(map(0x1A00, 0), &[9], &trace.core.od)
            .unwrap_err();
        assert_eq!(
            err,
            PdoConfigError::TooManyObjects {
                pdo,
                count: 9,
                max: 8
            }
        );
        assert_eq!(
            err.to_string(),
            "TPDO1: 9 mapping entries requested, at most 8 possible"
        );
        assert!(trace.events().is_empty());
    }

    #[test]
    fn cob_id_and_communication_parameter_checks() {
        let mut trace = bench(|_| {});
        // CAN-ID change while valid; unsupported bits; restricted CAN-IDs.
        assert_eq!(sdo_write(&mut trace, 0x1800, 1, 0x186), Err(0x0609_0030));
        assert_eq!(sdo_write(&mut trace, 0x1800, 1, 0x185), Ok(()), "same CAN-ID");
        assert_eq!(sdo_write(&mut trace, 0x1400, 1, 0x206), Err(0x0609_0030));
        sdo_write(&mut trace, 0x1800, 1, COB_ID_INVALID | 0x185).unwrap();
        for value in [0x0000_0885u32, 0x1000_0185] {
            assert_eq!(
                sdo_write(&mut trace, 0x1800, 1, value),
                Err(0x0609_0030),
                "{value:08X}"
            );
        }
        for can_id in [
            0x000u32, 0x001, 0x07F, 0x101, 0x180, 0x581, 0x5FF, 0x601, 0x67F, 0x6E0, 0x701, 0x77F, 0x7E4,
            0x7FF,
        ] {
            assert_eq!(
                sdo_write(&mut trace, 0x1800, 1, can_id),
                Err(0x0609_0030),
                "{can_id:03X}h"
            );
            assert_eq!(
                sdo_write(&mut trace, 0x1400, 1, can_id),
                Err(0x0609_0030),
                "{can_id:03X}h"
            );
            assert_eq!(
                sdo_write(&mut trace, 0x1800, 1, COB_ID_INVALID | can_id),
                Ok(()),
                "not checked while invalid"
            );
        }
        let err = trace
            .core
            .engine
            .check_write(ObjectKey::new(0x1800, 1), &0x701u32.to_le_bytes(), &trace.core.od)
            .unwrap_err();
        assert_eq!(
            err.to_string(),
            "TPDO1: CAN-ID 701h is restricted (NMT, SDO, error control, reserved) and cannot carry a PDO"
        );
        // Inhibit time and SYNC start value only while invalid; SYNC start value up to 240.
        assert_eq!(sdo_write(&mut trace, 0x1800, 3, 10), Ok(()));
        assert_eq!(sdo_write(&mut trace, 0x1800, 6, 241), Err(0x0609_0030));
        assert_eq!(sdo_write(&mut trace, 0x1800, 6, 240), Ok(()));
        sdo_write(&mut trace, 0x1800, 1, 0x185).unwrap();
        assert_eq!(sdo_write(&mut trace, 0x1800, 3, 20), Err(0x0609_0030));
        assert_eq!(sdo_write(&mut trace, 0x1800, 3, 10), Ok(()), "unchanged");
        assert_eq!(sdo_write(&mut trace, 0x1800, 6, 1), Err(0x0609_0030));
        assert_eq!(
            sdo_write(&mut trace, 0x1800, 5, 1000),
            Ok(()),
            "event timer any time"
        );
        // Reserved transmission types; RTR-only types against COB-ID bit 30.
        for value in 241..=251 {
            assert_eq!(sdo_write(&mut trace, 0x1800, 2, value), Err(0x0609_0030));
        }
        for value in 241..=253 {
            assert_eq!(sdo_write(&mut trace, 0x1400, 2, value), Err(0x0609_0030));
        }
        for value in [0, 1, 240, 254, 255] {
            assert_eq!(sdo_write(&mut trace, 0x1400, 2, value), Ok(()));
        }
        assert_eq!(sdo_write(&mut trace, 0x1800, 2, 252), Ok(()));
        sdo_write(&mut trace, 0x1800, 1, COB_ID_INVALID | 0x185).unwrap();
        assert_eq!(
            sdo_write(&mut trace, 0x1800, 1, COB_ID_NO_RTR | COB_ID_INVALID | 0x185),
            Err(0x0609_0030)
        );
        sdo_write(&mut trace, 0x1800, 2, 255).unwrap();
        sdo_write(&mut trace, 0x1800, 1, COB_ID_NO_RTR | 0x185).unwrap();
        assert_eq!(sdo_write(&mut trace, 0x1800, 2, 253), Err(0x0609_0030));
        // A write of the wrong length is left to the dictionary; other objects pass.
        let od = &trace.core.od;
        assert_eq!(
            trace
                .core
                .engine
                .check_write(ObjectKey::new(0x1800, 1), &[1, 2], od),
            Ok(())
        );
        assert_eq!(
            trace
                .core
                .engine
                .check_write(ObjectKey::new(0x1017, 0), &[1, 2], od),
            Ok(())
        );
    }

    #[test]
    fn extended_can_id() {
        let mut trace = bench(|od| {
            set(od, 0x1800, 1, COB_ID_EXTENDED | 0x1234_5678);
            set(od, 0x1400, 1, COB_ID_EXTENDED | 0x0000_0005);
        });
        trace.rx(ms(1), "00000005#77");
        trace.rx(ms(2), "005#78"); // 11-bit 005h is not the RPDO
        assert_eq!(value(&trace, DO1), 0x77);
        assert_eq!(trace.sent(), ["0.000 12345678#00"]);
    }

    #[test]
    fn dummy_mapping() {
        let dummies = DummyUsage::NONE.with(0x0005).with(0x0007);
        assert!(dummies.allows(5) && dummies.allows(7) && !dummies.allows(6) && !dummies.allows(8));
        let mut trace = bench_with(dummies, |od| {
            set(od, 0x1600, 0, 2);
            set(od, 0x1600, 1, 0x0005_0008);
            set(od, 0x1600, 2, 0x6200_0108);
            set(od, 0x1A00, 0, 3);
            set(od, 0x1A00, 1, 0x0007_0010); // 16 bits of an UNSIGNED32 dummy
            set(od, 0x1A00, 2, 0x6000_0108);
            set(od, 0x1A00, 3, 0x0005_0008);
            set(od, 0x6000, 1, 0xAB);
        });
        trace.rx(ms(1), "205#FF12");
        assert_eq!(value(&trace, DO1), 0x12, "the dummy byte is skipped");
        assert_eq!(trace.sent(), ["0.000 185#0000AB00"], "dummies send zeros");
        assert!(trace.events().iter().all(|e| e.contains("RpdoWritten")));
        sdo_write(&mut trace, 0x1400, 1, COB_ID_INVALID | 0x205).unwrap();
        sdo_write(&mut trace, 0x1600, 0, 0).unwrap();
        assert_eq!(
            sdo_write(&mut trace, 0x1600, 1, 0x0006_0010),
            Err(0x0602_0000),
            "not enabled"
        );
        assert_eq!(
            sdo_write(&mut trace, 0x1600, 1, 0x0005_0010),
            Err(0x0604_0041),
            "longer than the type"
        );
        assert_eq!(sdo_write(&mut trace, 0x1600, 1, 0x0005_0000), Err(0x0604_0041));
    }

    #[test]
    fn bit_granular_mapping() {
        let mut trace = bench(|od| {
            set(od, 0x1A00, 0, 3);
            set(od, 0x1A00, 1, 0x2004_0001);
            set(od, 0x1A00, 2, 0x6000_0104);
            set(od, 0x1A00, 3, 0x6000_0208);
            set(od, 0x2004, 0, 1);
            set(od, 0x6000, 1, 0xF5); // only the low nibble 5 is mapped
            set(od, 0x6000, 2, 0x81);
            set(od, 0x1600, 0, 2);
            set(od, 0x1600, 1, 0x2004_0001);
            set(od, 0x1600, 2, 0x6200_0107);
            set(od, 0x6200, 1, 0x80);
        });
        // bit 0: BOOLEAN 1, bits 1..4: 5, bits 5..12: 81h -> 0x102B
        trace.advance(ms(1));
        assert_eq!(trace.sent(), ["0.000 185#2B10"]);
        trace.rx(ms(1), "205#FE");
        assert_eq!(value(&trace, ObjectKey::new(0x2004, 0)), 0);
        assert_eq!(value(&trace, DO1), 0xFF, "bit 7 above the 7 mapped bits kept");
    }

    #[test]
    fn invalid_dictionary_parameters_disable_the_pdo_once() {
        let mut trace = bench(|od| {
            set(od, 0x1801, 1, 0x285);
            set(od, 0x1A01, 0, 1);
            set(od, 0x1A01, 1, 0x7000_0008);
            set(od, 0x1401, 2, 245);
        });
        let tpdo2 = PdoRef {
            direction: Direction::Transmit,
            number: 2,
        };
        assert!(!trace.core.engine.is_active(tpdo2));
        trace.core.engine.reload(Instant::ZERO, &trace.core.od);
        assert_eq!(
            trace.events(),
            [
                "0.000 Disabled { pdo: PdoRef { direction: Receive, number: 2 }, error: ReservedTransmissionType { pdo: PdoRef { direction: Receive, number: 2 }, value: 245 } }",
                "0.000 Disabled { pdo: PdoRef { direction: Transmit, number: 2 }, error: ObjectDoesNotExist { pdo: PdoRef { direction: Transmit, number: 2 }, key: 0x7000:00 } }",
            ]
        );
        trace.advance(ms(1));
        assert_eq!(trace.sent(), ["0.000 185#00"]);
        assert_eq!(
            trace
                .core
                .engine
                .pdos()
                .map(|p| p.to_string())
                .collect::<Vec<_>>(),
            ["RPDO1", "RPDO2", "TPDO1", "TPDO2"]
        );
        assert_eq!((tpdo2.comm_index(), tpdo2.mapping_index()), (0x1801, 0x1A01));
        assert_eq!(
            PdoRef::from_index(0x1BFF),
            Some((
                PdoRef {
                    direction: Direction::Transmit,
                    number: 512
                },
                false
            ))
        );
        assert_eq!(PdoRef::from_index(0x1C00), None);
    }

    #[test]
    fn reload_keeps_the_timers_of_unchanged_pdos() {
        let mut trace = bench(|od| {
            set(od, 0x1800, 5, 10);
            set(od, 0x1801, 1, 0x285);
            set(od, 0x1A01, 0, 1);
            set(od, 0x1A01, 1, 0x6000_0208);
        });
        trace.advance(ms(5));
        assert_eq!(trace.sent(), ["0.000 185#00", "0.000 285#00"]);
        sdo_write(&mut trace, 0x1801, 5, 20).unwrap();
        sdo_write(&mut trace, 0x1400, 5, 0).unwrap();
        trace.advance(ms(10));
        assert_eq!(
            trace.sent(),
            ["5.000 285#00", "10.000 185#00"],
            "TPDO2 restarted, TPDO1 kept its timer"
        );
    }

    proptest::proptest! {
        /// Arbitrary frames, SYNCs and time steps never panic, whatever the configuration.
        #[test]
        fn no_frame_panics(
            frames in proptest::collection::vec((any_frame(), 0u8..4, proptest::prelude::any::<u8>()), 0..60),
            trans in proptest::prelude::any::<u8>(),
            rx_trans in proptest::prelude::any::<u8>(),
            event in 0u16..20,
            inhibit in 0u16..50,
        ) {
            let mut od = dictionary();
            set(&mut od, 0x1800, 2, u32::from(trans));
            set(&mut od, 0x1800, 3, u32::from(inhibit));
            set(&mut od, 0x1800, 5, u32::from(event));
            set(&mut od, 0x1800, 6, u32::from(trans % 4));
            set(&mut od, 0x1400, 2, u32::from(rx_trans));
            set(&mut od, 0x1400, 5, u32::from(event));
            set(&mut od, 0x1400, 1, 0x185);
            let mut engine = PdoEngine::new().with_dummy_usage(DummyUsage::ALL);
            engine.reload(Instant::ZERO, &od);
            engine.set_state(Instant::ZERO, NmtSlaveState::Operational);
            for (i, (frame, action, byte)) in frames.iter().enumerate() {
                let now = Instant::from_micros(i as u64 * 700);
                if let Some(due) = engine.poll_timeout() && due <= now {
                    engine.handle_timeout(now, &od);
                }
                engine.handle_frame(now, frame, &mut od);
                match action {
                    0 => engine.handle_sync(now, (byte % 2 == 0).then_some(*byte), &mut od),
                    1 => { engine.application_event(now, DI1); }
                    2 => {
                        let key = ObjectKey::new(0x1400 + u16::from(byte & 0x3) * 0x200, byte >> 4);
                        let data = u32::from(*byte).wrapping_mul(0x0101_0101).to_le_bytes();
                        if engine.check_write(key, &data, &od).is_ok() {
                            let _ = od.write(key, &data);
                            engine.reload(now, &od);
                        }
                    }
                    _ => {}
                }
                while engine.poll_transmit().is_some() {}
                while engine.poll_event().is_some() {}
            }
        }
    }
}

//! PDO configuration as an ordered list of SDO writes: the dynamic mapping procedure of CiA 301
//! §7.2.2 (PDO) with its communication parameters (reference §3.1–§3.4).
//!
//! Before changing this file read CiA 301 §7.5.2.35–§7.5.2.38 (objects 1400h–1BFFh), §7.3.5 (the
//! pre-defined connection set and restricted CAN-IDs) and the reference notes on how stacks answer
//! each step (§3.4): the order below is the procedure vendor manuals give, citing CiA 301.
//!
//! [`PdoConfig::plan`] checks what a device would refuse before anything is sent, then returns:
//! 1. the COB-ID (14xxh/18xxh sub 1) with bit 31 set: the PDO is invalid while it changes;
//! 2. mapping sub 0 = 0: the mapping is disabled while its entries change;
//! 3. the entries `index << 16 | sub << 8 | bits` on 16xxh/1Axxh sub 1..n;
//! 4. mapping sub 0 = n;
//! 5. transmission type (sub 2), inhibit time (sub 3, TPDO), event timer (sub 5) and SYNC start
//!    value (sub 6, TPDO), which some devices accept only while the PDO is invalid;
//! 6. the COB-ID with bit 31 clear: the PDO is valid again.
//!
//! Nothing here talks to a device: the CLI hands the writes to the SDO client one by one and stops at
//! the first abort.

use std::fmt;

use canopener_wire::{NodeId, RPDO_BASES, TPDO_BASES};

/// Whether a PDO is sent or received by the device.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Direction {
    /// Transmit PDO: the device sends it (communication 1800h.., mapping 1A00h..).
    Tpdo,
    /// Receive PDO: the device consumes it (communication 1400h.., mapping 1600h..).
    Rpdo,
}

/// One mapping entry: `bits` bits of object `index:sub` (CiA 301 §7.4.8, PDO_MAPPING).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MappedObject {
    /// The object index, or a data type index 0001h–0007h for a dummy entry.
    pub index: u16,
    /// The sub-index, 0 for a dummy entry.
    pub sub: u8,
    /// The length in bits, 1 to 64.
    pub bits: u8,
}

/// What a PDO should look like after configuration. `None` leaves a communication parameter as the
/// device has it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PdoConfig {
    /// TPDO or RPDO.
    pub direction: Direction,
    /// The PDO number, 1 to 512.
    pub number: u16,
    /// The COB-ID to use. Without it the current one is kept, or for PDOs 1–4 the pre-defined
    /// connection set gives one (180h/280h/380h/480h + node for TPDOs, 200h/300h/400h/500h + node
    /// for RPDOs). Bit 31 set keeps the PDO invalid after configuration.
    pub cob_id: Option<u32>,
    /// Transmission type (sub 2): 0–240, 254, 255, and 252/253 (RTR) for TPDOs.
    pub transmission_type: Option<u8>,
    /// Inhibit time (sub 3) in units of 100 µs; TPDO only.
    pub inhibit_time_100us: Option<u16>,
    /// Event timer (sub 5) in ms: the send period of an event-driven TPDO, the deadline of an RPDO.
    pub event_timer_ms: Option<u16>,
    /// SYNC start value (sub 6), 0 or 1–240; TPDO only.
    pub sync_start: Option<u8>,
    /// The entries in PDO order, the first one in the lowest bits. Empty disables the PDO: the plan
    /// then leaves the COB-ID invalid.
    pub mapping: Vec<MappedObject>,
}

/// One SDO download of a plan.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SdoWrite {
    /// The object index.
    pub index: u16,
    /// The sub-index.
    pub sub: u8,
    /// The value's little-endian bytes, sized by the object's data type.
    pub data: Vec<u8>,
    /// The step of the procedure, for progress output and for naming the step a device refused.
    pub why: &'static str,
}

/// Why a configuration was refused before anything was sent.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PdoConfigError {
    /// A PDO number outside 1–512.
    #[error("PDO number {number} is out of range: TPDOs and RPDOs are numbered 1 to 512")]
    Number {
        /// The number given.
        number: u16,
    },
    /// More mapping entries than sub-indices 01h–40h.
    #[error("{count} mapping entries; a PDO maps at most 64 (sub-indices 01h to 40h)")]
    TooManyEntries {
        /// The number of entries given.
        count: usize,
    },
    /// A mapping entry of length 0.
    #[error("mapping entry {entry} has length 0: give 1 to 64 bits, e.g. 6000:01:8")]
    ZeroLength {
        /// The entry.
        entry: MappedObject,
    },
    /// A dummy entry longer than its data type.
    #[error("dummy entry {entry} is longer than its data type ({max} bits)")]
    DummyTooLong {
        /// The entry.
        entry: MappedObject,
        /// The size of the dummy's data type.
        max: u8,
    },
    /// More than 64 bits mapped.
    #[error("the mapping takes {bits} bits; a classical CAN PDO carries at most 64 (8 bytes)")]
    TooManyBits {
        /// The total length.
        bits: u32,
    },
    /// A transmission type the direction does not have.
    #[error("transmission type {value} is not valid for {pdo}: use {valid}", valid = transmission_types(pdo.direction))]
    TransmissionType {
        /// The PDO.
        pdo: PdoName,
        /// The value given.
        value: u8,
    },
    /// An RTR transmission type with a COB-ID that forbids RTR.
    #[error(
        "transmission type {value} answers remote frames, but COB-ID {cob_id:#010X} has bit 30 set (no RTR allowed)"
    )]
    RtrNotAllowed {
        /// The transmission type given.
        value: u8,
        /// The COB-ID the PDO will have.
        cob_id: u32,
    },
    /// A TPDO-only parameter given for an RPDO.
    #[error("{pdo} has no {what}: it applies to TPDOs only")]
    TpdoOnly {
        /// The PDO.
        pdo: PdoName,
        /// The parameter.
        what: &'static str,
    },
    /// A SYNC start value above 240.
    #[error("SYNC start value {value} is out of range: 0 (not used) or 1 to 240")]
    SyncStart {
        /// The value given.
        value: u8,
    },
    /// No COB-ID given, none known and none pre-defined.
    #[error(
        "{pdo} has no pre-defined COB-ID (the pre-defined connection set covers PDOs 1 to 4): give one, \
         e.g. 0x00000190"
    )]
    NeedsCobId {
        /// The PDO.
        pdo: PdoName,
    },
    /// An 11-bit COB-ID with bits 28..11 set.
    #[error(
        "COB-ID {cob_id:#010X} has bits 28..11 set: clear them for an 11-bit CAN-ID or set bit 29 for 29 bits"
    )]
    ExtendedBits {
        /// The COB-ID.
        cob_id: u32,
    },
    /// A restricted CAN-ID.
    #[error("CAN-ID {can_id:03X}h is restricted ({reason}) and cannot carry a PDO")]
    RestrictedCanId {
        /// The CAN-ID.
        can_id: u16,
        /// What the range is reserved for.
        reason: &'static str,
    },
}

/// A PDO by direction and number, printed `TPDO1`, `RPDO12`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct PdoName {
    /// TPDO or RPDO.
    pub direction: Direction,
    /// The PDO number.
    pub number: u16,
}

/// COB-ID bit 31: 1 = the PDO does not exist / is not valid.
pub const COB_ID_INVALID: u32 = 1 << 31;
/// COB-ID bit 30: 1 = no RTR allowed on this PDO.
pub const COB_ID_NO_RTR: u32 = 1 << 30;
/// COB-ID bit 29: 1 = 29-bit CAN-ID.
pub const COB_ID_EXTENDED: u32 = 1 << 29;
/// The most bits one PDO carries on classical CAN.
pub const MAX_PDO_BITS: u32 = 64;
/// The most entries a mapping parameter has (sub-indices 01h–40h).
pub const MAX_MAPPED_OBJECTS: usize = 64;

impl Direction {
    /// The communication parameter of PDO 1: 1800h for TPDOs, 1400h for RPDOs.
    pub const fn comm_base(self) -> u16 {
        match self {
            Direction::Tpdo => 0x1800,
            Direction::Rpdo => 0x1400,
        }
    }

    /// The mapping parameter of PDO 1: 1A00h for TPDOs, 1600h for RPDOs.
    pub const fn mapping_base(self) -> u16 {
        match self {
            Direction::Tpdo => 0x1A00,
            Direction::Rpdo => 0x1600,
        }
    }

    /// The pre-defined COB-ID of PDO `number` (1–4) of `node` (CiA 301 §7.3.5), `None` for the others.
    pub fn default_cob_id(self, number: u16, node: NodeId) -> Option<u32> {
        let bases = match self {
            Direction::Tpdo => TPDO_BASES,
            Direction::Rpdo => RPDO_BASES,
        };
        let base = bases.get(usize::from(number).checked_sub(1)?)?;
        Some(u32::from(*base) + u32::from(node.get()))
    }

    /// Whether the PDO may use transmission type `value` (CiA 301 §7.2.2.1, reference §3.2): 0–240,
    /// 254 and 255 both ways; 252 and 253 (RTR) for TPDOs only; 241–251 are reserved.
    pub const fn allows_transmission_type(self, value: u8) -> bool {
        match value {
            0..=240 | 254 | 255 => true,
            252 | 253 => matches!(self, Direction::Tpdo),
            _ => false,
        }
    }
}

impl MappedObject {
    /// The entry `index:sub`, `bits` long.
    pub const fn new(index: u16, sub: u8, bits: u8) -> MappedObject {
        MappedObject { index, sub, bits }
    }

    /// The 32-bit value of the mapping parameter: index in bits 31..16, sub-index in 15..8, length
    /// in bits in 7..0.
    pub const fn entry(self) -> u32 {
        (self.index as u32) << 16 | (self.sub as u32) << 8 | self.bits as u32
    }

    /// The entry a mapping parameter holds.
    pub const fn from_entry(entry: u32) -> MappedObject {
        MappedObject {
            index: (entry >> 16) as u16,
            sub: (entry >> 8) as u8,
            bits: entry as u8,
        }
    }

    /// Whether this is a dummy entry (reference §3.5): a basic data type index 0001h–0007h with
    /// sub-index 0, which only takes up room in the PDO.
    pub const fn is_dummy(self) -> bool {
        matches!(self.index, 0x0001..=0x0007) && self.sub == 0
    }

    /// The size of a dummy entry's data type in bits (BOOLEAN 1, INTEGER8/UNSIGNED8 8, ...).
    pub const fn dummy_type_bits(self) -> Option<u8> {
        match (self.index, self.sub) {
            (0x0001, 0) => Some(1),
            (0x0002 | 0x0005, 0) => Some(8),
            (0x0003 | 0x0006, 0) => Some(16),
            (0x0004 | 0x0007, 0) => Some(32),
            _ => None,
        }
    }
}

/// Prints the spelling [`parse_mapping`](crate::value::parse_mapping) reads: `6000:01:8`.
impl fmt::Display for MappedObject {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:04X}:{:02X}:{}", self.index, self.sub, self.bits)
    }
}

impl PdoConfig {
    /// The PDO `number` of `direction` with `mapping`, every parameter left as the device has it.
    pub fn new(direction: Direction, number: u16, mapping: Vec<MappedObject>) -> PdoConfig {
        PdoConfig {
            direction,
            number,
            cob_id: None,
            transmission_type: None,
            inhibit_time_100us: None,
            event_timer_ms: None,
            sync_start: None,
            mapping,
        }
    }

    /// The PDO's name, e.g. `TPDO1`.
    pub const fn name(&self) -> PdoName {
        PdoName {
            direction: self.direction,
            number: self.number,
        }
    }

    /// The communication parameter index: 1800h + n − 1 for TPDOs, 1400h + n − 1 for RPDOs.
    pub fn comm_index(&self) -> Result<u16, PdoConfigError> {
        Ok(self.direction.comm_base() + self.offset()?)
    }

    /// The mapping parameter index: 1A00h + n − 1 for TPDOs, 1600h + n − 1 for RPDOs.
    pub fn mapping_index(&self) -> Result<u16, PdoConfigError> {
        Ok(self.direction.mapping_base() + self.offset()?)
    }

    /// The ordered SDO writes that configure the PDO on node `node_id`, whose COB-ID is
    /// `current_cob_id` if the caller read it first (then the CAN-ID and bits 30/29 are kept unless
    /// [`cob_id`](PdoConfig::cob_id) is given).
    ///
    /// Refuses, before anything is sent, what a device would refuse: more than 64 entries or 64 bits,
    /// zero-length entries, dummies longer than their type, transmission types the direction lacks,
    /// RTR types with RTR forbidden, inhibit time or SYNC start on an RPDO, SYNC start above 240,
    /// restricted CAN-IDs and 11-bit COB-IDs with bits 28..11 set.
    pub fn plan(
        &self,
        node_id: NodeId,
        current_cob_id: Option<u32>,
    ) -> Result<Vec<SdoWrite>, PdoConfigError> {
        let comm = self.comm_index()?;
        let mapping = self.mapping_index()?;
        check_mapping(&self.mapping)?;
        let pdo = self.name();
        if let Some(value) = self.transmission_type
            && !self.direction.allows_transmission_type(value)
        {
            return Err(PdoConfigError::TransmissionType { pdo, value });
        }
        if self.direction == Direction::Rpdo {
            if self.inhibit_time_100us.is_some() {
                return Err(PdoConfigError::TpdoOnly {
                    pdo,
                    what: "inhibit time",
                });
            }
            if self.sync_start.is_some() {
                return Err(PdoConfigError::TpdoOnly {
                    pdo,
                    what: "SYNC start value",
                });
            }
        }
        if let Some(value) = self.sync_start
            && value > 240
        {
            return Err(PdoConfigError::SyncStart { value });
        }
        let target = self
            .cob_id
            .or(current_cob_id.map(|cob_id| cob_id & !COB_ID_INVALID))
            .or_else(|| self.direction.default_cob_id(self.number, node_id))
            .ok_or(PdoConfigError::NeedsCobId { pdo })?;
        check_cob_id(target)?;
        if let Some(value @ (252 | 253)) = self.transmission_type
            && target & COB_ID_NO_RTR != 0
        {
            return Err(PdoConfigError::RtrNotAllowed {
                value,
                cob_id: target,
            });
        }

        let mut writes = Vec::new();
        let invalid = current_cob_id.unwrap_or(target) | COB_ID_INVALID;
        writes.push(write(
            comm,
            1,
            &invalid.to_le_bytes(),
            "make the PDO invalid while it changes",
        ));
        writes.push(write(
            mapping,
            0,
            &[0],
            "disable the mapping while its entries change",
        ));
        for (entry, sub) in self.mapping.iter().zip(1u8..) {
            writes.push(write(mapping, sub, &entry.entry().to_le_bytes(), "mapping entry"));
        }
        // `check_mapping` allows at most 64 entries.
        let count = u8::try_from(self.mapping.len()).unwrap_or(u8::MAX);
        if count > 0 {
            writes.push(write(
                mapping,
                0,
                &[count],
                "enable the mapping with its number of entries",
            ));
        }
        if let Some(value) = self.transmission_type {
            writes.push(write(comm, 2, &[value], "transmission type"));
        }
        if let Some(value) = self.inhibit_time_100us {
            writes.push(write(comm, 3, &value.to_le_bytes(), "inhibit time in 100 µs"));
        }
        if let Some(value) = self.event_timer_ms {
            writes.push(write(comm, 5, &value.to_le_bytes(), "event timer in ms"));
        }
        if let Some(value) = self.sync_start {
            writes.push(write(comm, 6, &[value], "SYNC start value"));
        }
        // An empty mapping cannot be made valid (CANopenNode refuses with 0609 0030h), so the PDO is
        // left disabled; so it is when the COB-ID asked for has bit 31 set.
        let enable = count > 0 && target & COB_ID_INVALID == 0;
        let last = if enable { target } else { target | COB_ID_INVALID };
        if last != invalid {
            let why = if enable {
                "make the PDO valid with its COB-ID"
            } else {
                "set the COB-ID, leaving the PDO invalid"
            };
            writes.push(write(comm, 1, &last.to_le_bytes(), why));
        }
        Ok(writes)
    }

    fn offset(&self) -> Result<u16, PdoConfigError> {
        match self.number {
            1..=512 => Ok(self.number - 1),
            number => Err(PdoConfigError::Number { number }),
        }
    }
}

/// Prints `1800h:01 = 80000185h (make the PDO invalid while it changes)`, numbers shown by their
/// size: one byte as `05h`, two as `0064h`, four as `80000185h`.
impl fmt::Display for SdoWrite {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:04X}h:{:02X} = ", self.index, self.sub)?;
        for byte in self.data.iter().rev() {
            write!(f, "{byte:02X}")?;
        }
        write!(f, "h ({})", self.why)
    }
}

impl fmt::Display for PdoName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let prefix = match self.direction {
            Direction::Tpdo => "TPDO",
            Direction::Rpdo => "RPDO",
        };
        write!(f, "{prefix}{}", self.number)
    }
}

/// Checks a mapping for what every device refuses and returns its length in bits.
pub(crate) fn check_mapping(mapping: &[MappedObject]) -> Result<u32, PdoConfigError> {
    if mapping.len() > MAX_MAPPED_OBJECTS {
        return Err(PdoConfigError::TooManyEntries { count: mapping.len() });
    }
    let mut bits = 0u32;
    for entry in mapping {
        if entry.bits == 0 {
            return Err(PdoConfigError::ZeroLength { entry: *entry });
        }
        if let Some(max) = entry.dummy_type_bits()
            && entry.bits > max
        {
            return Err(PdoConfigError::DummyTooLong { entry: *entry, max });
        }
        bits += u32::from(entry.bits);
    }
    if bits > MAX_PDO_BITS {
        return Err(PdoConfigError::TooManyBits { bits });
    }
    Ok(bits)
}

/// What a restricted 11-bit CAN-ID is reserved for (CiA 301 §7.3.5, reference §6), `None` if a PDO
/// may use it.
pub fn restricted_can_id(can_id: u16) -> Option<&'static str> {
    Some(match can_id {
        0x000 => "NMT",
        0x001..=0x07F | 0x101..=0x180 | 0x6E0..=0x6FF => "reserved",
        0x581..=0x5FF => "default SDO, server to client",
        0x601..=0x67F => "default SDO, client to server",
        0x701..=0x77F => "NMT error control",
        0x780..=0x7FF => "reserved, includes LSS",
        _ => return None,
    })
}

fn check_cob_id(cob_id: u32) -> Result<(), PdoConfigError> {
    if cob_id & COB_ID_EXTENDED != 0 {
        return Ok(());
    }
    if cob_id & 0x1FFF_F800 != 0 {
        return Err(PdoConfigError::ExtendedBits { cob_id });
    }
    let can_id = (cob_id & 0x7FF) as u16;
    match restricted_can_id(can_id) {
        Some(reason) => Err(PdoConfigError::RestrictedCanId { can_id, reason }),
        None => Ok(()),
    }
}

fn transmission_types(direction: Direction) -> &'static str {
    match direction {
        Direction::Tpdo => {
            "0 (at the next SYNC after an event), 1 to 240 (every n-th SYNC), 252/253 (on RTR), 254 or 255 \
             (event-driven)"
        }
        Direction::Rpdo => "0 to 240 (applied at the next SYNC), 254 or 255 (applied on reception)",
    }
}

fn write(index: u16, sub: u8, data: &[u8], why: &'static str) -> SdoWrite {
    SdoWrite {
        index,
        sub,
        data: data.to_vec(),
        why,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn node(id: u8) -> NodeId {
        NodeId::new(id).expect("node-id")
    }

    fn tpdo(number: u16, mapping: &[(u16, u8, u8)]) -> PdoConfig {
        PdoConfig::new(
            Direction::Tpdo,
            number,
            mapping
                .iter()
                .map(|&(i, s, b)| MappedObject::new(i, s, b))
                .collect(),
        )
    }

    fn rpdo(number: u16, mapping: &[(u16, u8, u8)]) -> PdoConfig {
        PdoConfig {
            direction: Direction::Rpdo,
            ..tpdo(number, mapping)
        }
    }

    /// The plan as lines, one write each.
    fn check(config: &PdoConfig, node_id: u8, current: Option<u32>) -> Vec<String> {
        match config.plan(node(node_id), current) {
            Ok(writes) => writes.iter().map(ToString::to_string).collect(),
            Err(err) => vec![format!("error: {err}")],
        }
    }

    #[test]
    fn tpdo_write_order() {
        let config = PdoConfig {
            transmission_type: Some(254),
            inhibit_time_100us: Some(100),
            event_timer_ms: Some(500),
            sync_start: Some(3),
            ..tpdo(1, &[(0x6000, 1, 8), (0x0005, 0, 8), (0x6401, 1, 16)])
        };
        assert_eq!(
            check(&config, 5, None),
            [
                "1800h:01 = 80000185h (make the PDO invalid while it changes)",
                "1A00h:00 = 00h (disable the mapping while its entries change)",
                "1A00h:01 = 60000108h (mapping entry)",
                "1A00h:02 = 00050008h (mapping entry)",
                "1A00h:03 = 64010110h (mapping entry)",
                "1A00h:00 = 03h (enable the mapping with its number of entries)",
                "1800h:02 = FEh (transmission type)",
                "1800h:03 = 0064h (inhibit time in 100 µs)",
                "1800h:05 = 01F4h (event timer in ms)",
                "1800h:06 = 03h (SYNC start value)",
                "1800h:01 = 00000185h (make the PDO valid with its COB-ID)",
            ]
        );
        let writes = config.plan(node(5), None).unwrap();
        assert_eq!(writes[0].data, [0x85, 0x01, 0x00, 0x80]);
        assert_eq!(writes[3].data, [0x08, 0x00, 0x05, 0x00]);
    }

    #[test]
    fn rpdo_write_order() {
        let config = PdoConfig {
            transmission_type: Some(1),
            event_timer_ms: Some(100),
            ..rpdo(2, &[(0x6200, 1, 8), (0x6200, 2, 8)])
        };
        assert_eq!(
            check(&config, 0x7F, None),
            [
                "1401h:01 = 8000037Fh (make the PDO invalid while it changes)",
                "1601h:00 = 00h (disable the mapping while its entries change)",
                "1601h:01 = 62000108h (mapping entry)",
                "1601h:02 = 62000208h (mapping entry)",
                "1601h:00 = 02h (enable the mapping with its number of entries)",
                "1401h:02 = 01h (transmission type)",
                "1401h:05 = 0064h (event timer in ms)",
                "1401h:01 = 0000037Fh (make the PDO valid with its COB-ID)",
            ]
        );
    }

    #[test]
    fn default_cob_ids_of_the_predefined_connection_set() {
        let cob = |direction, number| direction_cob(direction, number, 1);
        assert_eq!(
            [1, 2, 3, 4].map(|n| cob(Direction::Tpdo, n)),
            [Some(0x181), Some(0x281), Some(0x381), Some(0x481)]
        );
        assert_eq!(
            [1, 2, 3, 4].map(|n| cob(Direction::Rpdo, n)),
            [Some(0x201), Some(0x301), Some(0x401), Some(0x501)]
        );
        assert_eq!(cob(Direction::Tpdo, 5), None);
        assert_eq!(cob(Direction::Rpdo, 0), None);
    }

    fn direction_cob(direction: Direction, number: u16, node_id: u8) -> Option<u32> {
        direction.default_cob_id(number, node(node_id))
    }

    #[test]
    fn current_cob_id_is_kept_with_its_flags() {
        // CANopenNode's default TPDO COB-ID has bit 30 (no RTR) set; the plan keeps it.
        let config = tpdo(1, &[(0x6000, 1, 8)]);
        let lines = check(&config, 5, Some(0xC000_0185));
        assert_eq!(
            lines[0],
            "1800h:01 = C0000185h (make the PDO invalid while it changes)"
        );
        assert_eq!(
            lines[lines.len() - 1],
            "1800h:01 = 40000185h (make the PDO valid with its COB-ID)"
        );
        // A moved PDO stays where it is.
        let lines = check(&config, 5, Some(0x1A5));
        assert_eq!(
            lines[0],
            "1800h:01 = 800001A5h (make the PDO invalid while it changes)"
        );
        assert_eq!(
            lines[lines.len() - 1],
            "1800h:01 = 000001A5h (make the PDO valid with its COB-ID)"
        );
    }

    #[test]
    fn explicit_cob_id_moves_the_pdo() {
        let config = PdoConfig {
            cob_id: Some(0x1A5),
            ..tpdo(9, &[(0x6000, 1, 8)])
        };
        let lines = check(&config, 5, Some(0x8000_0000));
        assert_eq!(
            lines[0],
            "1808h:01 = 80000000h (make the PDO invalid while it changes)"
        );
        assert_eq!(
            lines[1],
            "1A08h:00 = 00h (disable the mapping while its entries change)"
        );
        assert_eq!(
            lines[lines.len() - 1],
            "1808h:01 = 000001A5h (make the PDO valid with its COB-ID)"
        );
        // 29-bit COB-IDs are taken as they are.
        let config = PdoConfig {
            cob_id: Some(0x2000_0185 | 0x1234_5000),
            ..tpdo(1, &[(0x6000, 1, 8)])
        };
        let lines = check(&config, 5, None);
        assert_eq!(
            lines[0],
            "1800h:01 = B2345185h (make the PDO invalid while it changes)"
        );
        assert_eq!(
            lines[lines.len() - 1],
            "1800h:01 = 32345185h (make the PDO valid with its COB-ID)"
        );
    }

    #[test]
    fn pdo_512_is_the_last() {
        let config = PdoConfig {
            cob_id: Some(0x190),
            ..rpdo(512, &[(0x6200, 1, 8)])
        };
        let lines = check(&config, 5, None);
        assert_eq!(
            lines[0],
            "15FFh:01 = 80000190h (make the PDO invalid while it changes)"
        );
        assert_eq!(
            lines[1],
            "17FFh:00 = 00h (disable the mapping while its entries change)"
        );
        assert_eq!(config.comm_index(), Ok(0x15FF));
        assert_eq!(config.mapping_index(), Ok(0x17FF));
        assert_eq!(tpdo(512, &[]).comm_index(), Ok(0x19FF));
        assert_eq!(tpdo(512, &[]).mapping_index(), Ok(0x1BFF));
    }

    #[test]
    fn empty_mapping_or_invalid_cob_id_leaves_the_pdo_disabled() {
        let config = PdoConfig {
            transmission_type: Some(255),
            ..tpdo(2, &[])
        };
        assert_eq!(
            check(&config, 5, Some(0x285)),
            [
                "1801h:01 = 80000285h (make the PDO invalid while it changes)",
                "1A01h:00 = 00h (disable the mapping while its entries change)",
                "1801h:02 = FFh (transmission type)",
            ]
        );
        let config = PdoConfig {
            cob_id: Some(0x8000_0190),
            ..tpdo(2, &[(0x6000, 1, 8)])
        };
        let lines = check(&config, 5, Some(0x285));
        assert_eq!(
            lines[0],
            "1801h:01 = 80000285h (make the PDO invalid while it changes)"
        );
        assert_eq!(
            lines[lines.len() - 1],
            "1801h:01 = 80000190h (set the COB-ID, leaving the PDO invalid)"
        );
    }

    #[test]
    fn refusals() {
        let full = |n: usize| -> Vec<(u16, u8, u8)> { (0..n).map(|_| (0x0001, 0, 1)).collect() };
        let cases: Vec<(PdoConfig, &str)> = vec![
            (
                tpdo(0, &[]),
                "PDO number 0 is out of range: TPDOs and RPDOs are numbered 1 to 512",
            ),
            (
                rpdo(513, &[]),
                "PDO number 513 is out of range: TPDOs and RPDOs are numbered 1 to 512",
            ),
            (
                tpdo(1, &full(65)),
                "65 mapping entries; a PDO maps at most 64 (sub-indices 01h to 40h)",
            ),
            (
                tpdo(1, &[(0x6000, 1, 8), (0x6000, 2, 0)]),
                "mapping entry 6000:02:0 has length 0: give 1 to 64 bits, e.g. 6000:01:8",
            ),
            (
                tpdo(1, &[(0x0005, 0, 16)]),
                "dummy entry 0005:00:16 is longer than its data type (8 bits)",
            ),
            (
                tpdo(1, &[(0x6401, 1, 32), (0x6401, 2, 32), (0x6000, 1, 1)]),
                "the mapping takes 65 bits; a classical CAN PDO carries at most 64 (8 bytes)",
            ),
            (
                PdoConfig {
                    transmission_type: Some(241),
                    ..tpdo(1, &[])
                },
                "transmission type 241 is not valid for TPDO1: use 0 (at the next SYNC after an event), \
                 1 to 240 (every n-th SYNC), 252/253 (on RTR), 254 or 255 (event-driven)",
            ),
            (
                PdoConfig {
                    transmission_type: Some(251),
                    ..tpdo(1, &[])
                },
                "transmission type 251 is not valid for TPDO1: use 0 (at the next SYNC after an event), \
                 1 to 240 (every n-th SYNC), 252/253 (on RTR), 254 or 255 (event-driven)",
            ),
            (
                PdoConfig {
                    transmission_type: Some(252),
                    ..rpdo(1, &[])
                },
                "transmission type 252 is not valid for RPDO1: use 0 to 240 (applied at the next SYNC), \
                 254 or 255 (applied on reception)",
            ),
            (
                PdoConfig {
                    transmission_type: Some(253),
                    cob_id: Some(0x4000_0185),
                    ..tpdo(1, &[])
                },
                "transmission type 253 answers remote frames, but COB-ID 0x40000185 has bit 30 set (no RTR allowed)",
            ),
            (
                PdoConfig {
                    inhibit_time_100us: Some(10),
                    ..rpdo(1, &[])
                },
                "RPDO1 has no inhibit time: it applies to TPDOs only",
            ),
            (
                PdoConfig {
                    sync_start: Some(1),
                    ..rpdo(3, &[])
                },
                "RPDO3 has no SYNC start value: it applies to TPDOs only",
            ),
            (
                PdoConfig {
                    sync_start: Some(241),
                    ..tpdo(1, &[])
                },
                "SYNC start value 241 is out of range: 0 (not used) or 1 to 240",
            ),
            (
                tpdo(5, &[(0x6000, 1, 8)]),
                "TPDO5 has no pre-defined COB-ID (the pre-defined connection set covers PDOs 1 to 4): give one, \
                 e.g. 0x00000190",
            ),
            (
                PdoConfig {
                    cob_id: Some(0x0000_0985),
                    ..tpdo(1, &[])
                },
                "COB-ID 0x00000985 has bits 28..11 set: clear them for an 11-bit CAN-ID or set bit 29 for 29 bits",
            ),
        ];
        for (config, message) in cases {
            assert_eq!(
                check(&config, 5, None),
                [format!("error: {message}")],
                "{config:?}"
            );
        }
    }

    #[test]
    fn restricted_can_ids_are_refused() {
        let refused = |cob_id: u32| match tpdo(1, &[(0x6000, 1, 8)]).with_cob_id(cob_id).plan(node(5), None) {
            Err(PdoConfigError::RestrictedCanId { can_id, reason }) => Some((can_id, reason)),
            _ => None,
        };
        for can_id in [
            0x000, 0x001, 0x07F, 0x101, 0x180, 0x581, 0x5FF, 0x601, 0x67F, 0x6E0, 0x6FF, 0x701, 0x77F, 0x780,
            0x7E4, 0x7E5, 0x7FF,
        ] {
            assert!(refused(can_id).is_some(), "{can_id:03X}h must be refused");
            // Invalid or not, the CAN-ID is refused: the device checks it when it is made valid.
            assert!(
                refused(can_id | COB_ID_INVALID).is_some(),
                "{can_id:03X}h invalid"
            );
        }
        for can_id in [
            0x080, 0x081, 0x0FF, 0x100, 0x181, 0x57F, 0x580, 0x600, 0x680, 0x6DF, 0x700,
        ] {
            assert_eq!(refused(can_id), None, "{can_id:03X}h must be allowed");
        }
        assert_eq!(refused(0x701), Some((0x701, "NMT error control")));
        assert_eq!(
            tpdo(1, &[])
                .with_cob_id(0x605)
                .plan(node(5), None)
                .unwrap_err()
                .to_string(),
            "CAN-ID 605h is restricted (default SDO, client to server) and cannot carry a PDO"
        );
        // The current COB-ID is checked as well when it is the one kept.
        assert!(matches!(
            tpdo(1, &[]).plan(node(5), Some(0x585)),
            Err(PdoConfigError::RestrictedCanId { can_id: 0x585, .. })
        ));
    }

    impl PdoConfig {
        fn with_cob_id(self, cob_id: u32) -> PdoConfig {
            PdoConfig {
                cob_id: Some(cob_id),
                ..self
            }
        }
    }

    #[test]
    fn transmission_types_by_direction() {
        for value in 0..=255u8 {
            let tpdo_ok = matches!(value, 0..=240 | 252..=255);
            let rpdo_ok = matches!(value, 0..=240 | 254 | 255);
            assert_eq!(
                Direction::Tpdo.allows_transmission_type(value),
                tpdo_ok,
                "{value}"
            );
            assert_eq!(
                Direction::Rpdo.allows_transmission_type(value),
                rpdo_ok,
                "{value}"
            );
        }
    }

    #[test]
    fn sixty_four_bits_and_entries_fit() {
        let config = tpdo(1, &[(0x0001, 0, 1); 64]);
        let writes = config.plan(node(1), None).unwrap();
        assert_eq!(writes.len(), 1 + 1 + 64 + 1 + 1);
        assert_eq!(writes[66].data, [64]);
        assert_eq!(writes[65].sub, 0x40);
        let config = tpdo(1, &[(0x6401, 1, 32), (0x6401, 2, 32)]);
        assert!(config.plan(node(1), None).is_ok());
    }

    #[test]
    fn entries_round_trip() {
        let entry = MappedObject::new(0x6401, 0x0C, 16);
        assert_eq!(entry.entry(), 0x6401_0C10);
        assert_eq!(MappedObject::from_entry(0x6401_0C10), entry);
        assert_eq!(entry.to_string(), "6401:0C:16");
        assert!(MappedObject::new(0x0007, 0, 32).is_dummy());
        assert!(!MappedObject::new(0x0008, 0, 32).is_dummy());
        assert!(!MappedObject::new(0x0005, 1, 8).is_dummy());
        assert_eq!(MappedObject::new(0x0001, 0, 1).dummy_type_bits(), Some(1));
        assert_eq!(MappedObject::new(0x6000, 0, 1).dummy_type_bits(), None);
    }
}

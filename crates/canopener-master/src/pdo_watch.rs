//! Watching a node's TPDOs (CiA 301 §7.2.2, communication parameters 1800h–19FFh §7.5.2.37, mapping
//! parameters 1A00h–1BFFh §7.5.2.38): which TPDOs an EDS describes, a TPDO's configuration as a
//! [`WatchedPdo`] (from a dictionary built from the EDS, or from values read from the device by the
//! runtime's `pdo_watch`), decoding what arrives by the mapping, and statistics per TPDO.
//!
//! A TPDO whose COB-ID has bit 31 set does not exist on the bus and is skipped, as is one whose
//! mapping cannot be decoded (an MPDO, more than 64 bits). Frames are untrusted: one shorter than its
//! mapping is counted as malformed (a device receiving it as an RPDO would not process it either).

use canopener_can::{CanFrame, CanId, Instant};
use canopener_eds::{DataType, Eds, ObjectType};
use canopener_od::{DynamicOd, ObjectKey};

use crate::pdo_config::{COB_ID_EXTENDED, COB_ID_INVALID, Direction};
use crate::pdo_decode::{DecodedField, PdoDecodeError, PdoLayout};
use crate::statistics::{Gaps, Spread};
use crate::value::entry_label;

/// The TPDOs the EDS describes by their communication parameter, 1 to 512.
pub fn tpdo_numbers(eds: &Eds) -> Vec<u16> {
    let base = Direction::Tpdo.comm_base();
    (1..=512u16)
        .filter(|number| eds.object(base + number - 1).is_some())
        .collect()
}

/// A TPDO to watch, or why it is not watched.
#[derive(Debug)]
pub enum Found {
    /// A valid TPDO with a decodable mapping.
    Watch(WatchedPdo),
    /// A TPDO that is not watched.
    Skip {
        /// The TPDO number.
        number: u16,
        /// Why.
        reason: String,
    },
}

/// One TPDO being watched: where it arrives, how to decode it, what arrived so far.
#[derive(Debug)]
pub struct WatchedPdo {
    /// The TPDO number, 1 to 512.
    pub number: u16,
    /// The COB-ID (communication parameter sub 1).
    pub cob_id: u32,
    /// The CAN-ID it arrives on.
    pub can_id: CanId,
    /// The transmission type (sub 2), if known.
    pub transmission_type: Option<u8>,
    /// How its data decodes.
    pub layout: PdoLayout,
    /// What arrived so far.
    pub stats: PdoStats,
}

/// Arrivals of one TPDO.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct PdoStats {
    /// Frames received.
    pub received: u64,
    /// Frames that did not fit the mapping.
    pub malformed: u64,
    /// The time between arrivals.
    pub gaps: Gaps,
}

impl PdoStats {
    /// The shortest, median and longest time between arrivals.
    pub fn periods(&self) -> Option<Spread> {
        self.gaps.spread()
    }
}

/// The TPDO `number` with COB-ID `cob_id` skipped because bit 31 is set: it does not exist on the
/// bus (CiA 301 §7.5.2.37).
pub fn invalid(number: u16, cob_id: u32) -> Option<Found> {
    (cob_id & COB_ID_INVALID != 0).then(|| Found::Skip {
        number,
        reason: format!("not valid (COB-ID {cob_id:08X}h has bit 31 set)"),
    })
}

impl WatchedPdo {
    /// The TPDO with a valid COB-ID `cob_id`, or why it cannot be watched.
    pub fn found(number: u16, cob_id: u32, transmission_type: Option<u8>, layout: PdoLayout) -> Found {
        let can_id = if cob_id & COB_ID_EXTENDED != 0 {
            CanId::extended(cob_id & 0x1FFF_FFFF)
        } else {
            // Bits 28..11 of an 11-bit COB-ID should be 0; the device sends on the low 11 bits.
            CanId::standard((cob_id & 0x7FF) as u16)
        };
        match can_id {
            Ok(can_id) => Found::Watch(WatchedPdo {
                number,
                cob_id,
                can_id,
                transmission_type,
                layout,
                stats: PdoStats::default(),
            }),
            Err(err) => Found::Skip {
                number,
                reason: format!("COB-ID {cob_id:08X}h gives no CAN-ID: {err}"),
            },
        }
    }

    /// `TPDO1`.
    pub fn name(&self) -> String {
        format!("TPDO{}", self.number)
    }

    /// The CAN-ID as candump writes it: `185`, or `00123456` for a 29-bit one.
    pub fn can_id_text(&self) -> String {
        match self.can_id {
            CanId::Standard(_) => format!("{:03X}", self.can_id.as_raw()),
            CanId::Extended(_) => format!("{:08X}", self.can_id.as_raw()),
        }
    }

    /// Decodes one frame of this TPDO received at `at`, and counts it.
    pub fn receive(&mut self, at: Instant, frame: &CanFrame) -> Result<Vec<DecodedField>, PdoDecodeError> {
        let decoded = self.layout.decode(frame.data());
        self.stats.received += 1;
        if decoded.is_err() {
            self.stats.malformed += 1;
        }
        self.stats.gaps.record(at);
        decoded
    }
}

/// A TPDO from a dictionary built from the EDS/DCF (its values with `$NODEID` resolved).
pub fn from_od(od: &DynamicOd, number: u16) -> Found {
    let comm = Direction::Tpdo.comm_base() + number - 1;
    let mapping = Direction::Tpdo.mapping_base() + number - 1;
    let value = |index: u16, sub: u8| {
        od.get(ObjectKey::new(index, sub))
            .map(|entry| entry.value().to_vec())
    };
    let Some(cob_id) = value(comm, 1)
        .and_then(|data| <[u8; 4]>::try_from(data.as_slice()).ok())
        .map(u32::from_le_bytes)
    else {
        return Found::Skip {
            number,
            reason: format!("the EDS has no UNSIGNED32 COB-ID {}", entry_label(comm, 1)),
        };
    };
    if let Some(skip) = invalid(number, cob_id) {
        return skip;
    }
    let transmission_type = value(comm, 2).and_then(|data| data.first().copied());
    match PdoLayout::from_od(od, mapping) {
        Ok(layout) => WatchedPdo::found(number, cob_id, transmission_type, layout),
        Err(err) => Found::Skip {
            number,
            reason: format!("mapping {mapping:04X}h in the EDS: {err}"),
        },
    }
}

/// Names and types a mapped object by the EDS: a VAR or an ARRAY element by the object's name
/// (the sub-index tells elements apart), a RECORD member by the object's and the member's name.
pub fn eds_lookup(eds: &Eds) -> impl FnMut(u16, u8) -> Option<(String, DataType)> + '_ {
    move |index, sub| {
        let object = eds.object(index)?;
        let (attributes, name) = if object.subs.is_empty() {
            if sub != 0 {
                return None;
            }
            (&object.attributes, object.name().trim().to_owned())
        } else {
            let member = object.subs.get(&sub)?;
            let member_name = member.attributes.parameter_name.as_deref().unwrap_or("").trim();
            let object_name = object.name().trim();
            let name = match object.object_type() {
                Some(ObjectType::Record) if !member_name.is_empty() => {
                    format!("{object_name}: {member_name}")
                }
                _ if object_name.is_empty() => member_name.to_owned(),
                _ => object_name.to_owned(),
            };
            (&member.attributes, name)
        };
        Some((name, eds.resolve_data_type(attributes.data_type()?)))
    }
}

/// What a TPDO transmission type means (CiA 301 §7.2.2.1, reference §3.2).
pub fn transmission_text(value: u8) -> &'static str {
    match value {
        0 => "at the SYNC after an event",
        1 => "every SYNC",
        2..=240 => "every n-th SYNC",
        252 => "on RTR, sampled at SYNC",
        253 => "on RTR",
        254 | 255 => "event-driven",
        _ => "reserved",
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use crate::pdo_config::MappedObject;

    use super::*;

    fn watched(mapping: &[MappedObject]) -> WatchedPdo {
        let layout = PdoLayout::new(mapping).expect("layout");
        match WatchedPdo::found(1, 0x185, Some(255), layout) {
            Found::Watch(pdo) => pdo,
            Found::Skip { reason, .. } => panic!("{reason}"),
        }
    }

    #[test]
    fn frames_decode_by_the_mapping_and_short_ones_count_as_malformed() {
        let mut pdo = watched(&[MappedObject::new(0x6000, 1, 8), MappedObject::new(0x6401, 1, 16)]);
        let id = CanId::standard(0x185).expect("id");
        let frame = |data: &[u8]| CanFrame::new(id, data).expect("frame");
        let first = pdo
            .receive(Instant::from_millis(12_345), &frame(&[0x3C, 0xFB, 0xFF]))
            .expect("decoded");
        assert_eq!(first.len(), 2);
        assert_eq!(first[1].raw, 0xFFFB);
        assert!(
            pdo.receive(Instant::from_millis(12_445), &frame(&[0x3C]))
                .is_err()
        );
        pdo.receive(Instant::from_millis(12_545), &frame(&[1, 0x10, 0, 0xEE]))
            .expect("decoded");
        assert_eq!((pdo.stats.received, pdo.stats.malformed), (3, 1));
        let periods = pdo.stats.periods().expect("periods");
        assert_eq!(periods.median, Duration::from_millis(100));
    }

    #[test]
    fn cob_ids_give_standard_or_extended_can_ids() {
        let layout = || PdoLayout::new(&[]).expect("empty layout");
        let can_id = |cob_id: u32| match WatchedPdo::found(1, cob_id, None, layout()) {
            Found::Watch(pdo) => pdo.can_id_text(),
            Found::Skip { reason, .. } => reason,
        };
        assert_eq!(can_id(0x4000_0185), "185");
        assert_eq!(can_id(0x2012_3456), "00123456");
        assert!(matches!(
            invalid(3, 0x8000_0385),
            Some(Found::Skip { number: 3, .. })
        ));
        assert!(invalid(3, 0x385).is_none());
    }

    #[test]
    fn transmission_types_are_named() {
        assert_eq!(transmission_text(0), "at the SYNC after an event");
        assert_eq!(transmission_text(1), "every SYNC");
        assert_eq!(transmission_text(255), "event-driven");
        assert_eq!(transmission_text(245), "reserved");
    }
}

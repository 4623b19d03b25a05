//! What one node is, as its mandatory and common CiA 301 objects say: 1000h device type and 1001h
//! error register (mandatory), 1018h identity (sub 1 mandatory), 1008h/1009h/100Ah names and
//! versions and 1017h producer heartbeat time (optional), and the state of its heartbeat.
//!
//! This module holds the data and its decoding; reading it over SDO is a procedure of the link crate
//! (`canopener_link::node_info`).

use std::time::Duration;

use canopener_can::CanFrame;
use canopener_wire::{ERROR_CONTROL_BASE, NmtState};

use crate::sdo_client::SdoTransferError;
use crate::value_typing::without_trailing_zeros;

/// The objects read for the identity, 1018h sub 1 to 4, in this order.
pub const IDENTITY_SUBS: [u8; 4] = [1, 2, 3, 4];

/// The name objects read, 1008h device name, 1009h hardware version, 100Ah software version.
pub const NAME_INDICES: [u16; 3] = [0x1008, 0x1009, 0x100A];

/// A value of the wrong length for an UNSIGNEDn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("the device answered with {got} byte(s); UNSIGNED{bits} has {width}", bits = width * 8)]
pub struct WidthError {
    /// The bytes the device sent.
    pub got: usize,
    /// The bytes of the type.
    pub width: usize,
}

/// A little-endian unsigned number of `width` bytes; shorter answers are zero-extended (an
/// expedited answer may carry fewer bytes), longer and empty ones are wrong.
pub fn unsigned(data: &[u8], width: usize) -> Result<u64, WidthError> {
    if data.is_empty() || data.len() > width || width > 8 {
        return Err(WidthError {
            got: data.len(),
            width,
        });
    }
    Ok(data
        .iter()
        .rev()
        .fold(0, |acc, byte| (acc << 8) | u64::from(*byte)))
}

/// Whether an abort says the object or sub-index is not there (CiA 301 §7.2.4.3.17: 0602 0000h,
/// 0609 0011h): "not implemented", not an error, for an optional object.
pub fn is_absent(error: &SdoTransferError) -> bool {
    matches!(
        error,
        SdoTransferError::AbortedByServer {
            code: canopener_wire::abort::OBJECT_DOES_NOT_EXIST
                | canopener_wire::abort::SUB_INDEX_DOES_NOT_EXIST
        }
    )
}

/// One optional object as read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Field<T> {
    /// The value.
    Value(T),
    /// The device says the object or sub-index does not exist.
    Absent,
    /// Any other failure, as a message.
    Failed(String),
}

impl Field<u64> {
    /// An UNSIGNEDn of `width` bytes from a read.
    pub fn unsigned(read: Result<Vec<u8>, SdoTransferError>, width: usize) -> Field<u64> {
        match read {
            Ok(data) => {
                unsigned(&data, width).map_or_else(|err| Field::Failed(err.to_string()), Field::Value)
            }
            Err(err) if is_absent(&err) => Field::Absent,
            Err(err) => Field::Failed(err.to_string()),
        }
    }
}

impl Field<String> {
    /// A VISIBLE_STRING from a read, without the trailing NULs of a fixed-size buffer; bytes that are
    /// no printable text fail with their hex.
    pub fn text(read: Result<Vec<u8>, SdoTransferError>) -> Field<String> {
        match read {
            Ok(data) if data.is_empty() || crate::value_typing::is_printable(&data) => {
                Field::Value(String::from_utf8_lossy(without_trailing_zeros(&data)).into_owned())
            }
            Ok(data) => Field::Failed(format!(
                "not text: {}",
                data.iter()
                    .map(|byte| format!("{byte:02X}"))
                    .collect::<Vec<_>>()
                    .join(" ")
            )),
            Err(err) if is_absent(&err) => Field::Absent,
            Err(err) => Field::Failed(err.to_string()),
        }
    }
}

/// What one heartbeat said, or that none came.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HeartbeatSeen {
    /// How long the wait lasted at most.
    pub waited: Duration,
    /// The state and how long after the wait began it arrived.
    pub state: Option<(NmtState, Duration)>,
    /// A heartbeat byte that is no NMT state.
    pub invalid: Option<u8>,
}

/// How long to wait for one heartbeat of a producer with period `period_ms` (1017h): 1.5 periods.
pub fn heartbeat_wait(period_ms: u64) -> Duration {
    Duration::from_millis(period_ms.saturating_mul(3) / 2)
}

/// What a frame says as a heartbeat of `node` (CiA 301 §7.2.8.3.2.2: one byte on 700h + node-ID, the
/// toggle bit 7 of node guarding ignored): `None` for another frame, else the state or the byte that
/// is none.
pub fn heartbeat_state(frame: &CanFrame, node: u8) -> Option<Result<NmtState, u8>> {
    let id = u32::from(ERROR_CONTROL_BASE) + u32::from(node);
    if frame.id().as_raw() != id || frame.is_remote() {
        return None;
    }
    let &[byte] = frame.data() else { return None };
    Some(NmtState::from_raw(byte & 0x7F).ok_or(byte))
}

/// 1000h decoded (CiA 301 §7.5.2.1): the device profile in bits 0..15, additional information in
/// bits 16..31, which CiA 401 splits into I/O functionality and specific functionality.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeviceType {
    /// The value of 1000h.
    pub raw: u32,
    /// The device profile number.
    pub profile: u16,
    /// The additional information.
    pub additional: u16,
    /// The profile's name.
    pub profile_name: String,
    /// The functions the additional information announces (CiA 401 only).
    pub functions: Vec<String>,
}

impl DeviceType {
    /// Decodes a value of 1000h.
    pub fn describe(raw: u32) -> DeviceType {
        let profile = (raw & 0xFFFF) as u16;
        let additional = (raw >> 16) as u16;
        let profile_name = match profile {
            0 => "no standardized device profile".to_owned(),
            401 => "CiA 401 generic I/O".to_owned(),
            402 => "CiA 402 drives and motion control".to_owned(),
            404 => "CiA 404 measuring devices and closed-loop controllers".to_owned(),
            405 => "CiA 405 IEC 61131-3 programmable devices".to_owned(),
            406 => "CiA 406 encoders".to_owned(),
            408 => "CiA 408 fluid power technology".to_owned(),
            410 => "CiA 410 inclinometers".to_owned(),
            413 => "CiA 413 truck gateways".to_owned(),
            417 => "CiA 417 lift control".to_owned(),
            418 => "CiA 418 battery modules".to_owned(),
            419 => "CiA 419 battery chargers".to_owned(),
            443 => "CiA 443 SIIS level-2 devices".to_owned(),
            447 => "CiA 447 special-purpose car add-on devices".to_owned(),
            453 => "CiA 453 power supplies".to_owned(),
            other => format!("CiA {other} device profile"),
        };
        let mut functions = Vec::new();
        if profile == 401 {
            if additional == 0xFFFF {
                functions.push("multiple-device module (the device types are in 67FFh)".to_owned());
            } else {
                // CiA 401 §8.1 of the reference: bits 16..23 I/O functionality, 24..31 specific.
                for (bit, name) in [
                    (16, "digital inputs"),
                    (17, "digital outputs"),
                    (18, "analogue inputs"),
                    (19, "analogue outputs"),
                ] {
                    if raw & (1 << bit) != 0 {
                        functions.push(name.to_owned());
                    }
                }
                match raw >> 24 {
                    0 => {}
                    1 => functions.push("joystick".to_owned()),
                    other => functions.push(format!("specific functionality {other:02X}h")),
                }
            }
        }
        DeviceType {
            raw,
            profile,
            additional,
            profile_name,
            functions,
        }
    }
}

/// Everything `node info` reads of one node.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NodeInfo {
    /// The node-ID.
    pub node: u8,
    /// 1000h.
    pub device_type: DeviceType,
    /// 1001h.
    pub error_register: Field<u64>,
    /// 1018h sub 1..4.
    pub identity: [Field<u64>; 4],
    /// 1008h, 1009h, 100Ah.
    pub names: [Field<String>; 3],
    /// 1017h in ms.
    pub heartbeat_time: Field<u64>,
    /// The heartbeat waited for when 1017h is not 0.
    pub heartbeat: Option<HeartbeatSeen>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn device_types_decode_the_profile_and_cia_401_functions() {
        let io = DeviceType::describe(0x000F_0191);
        assert_eq!(io.profile, 401);
        assert_eq!(io.profile_name, "CiA 401 generic I/O");
        assert_eq!(
            io.functions,
            [
                "digital inputs",
                "digital outputs",
                "analogue inputs",
                "analogue outputs"
            ]
        );
        let joystick = DeviceType::describe(0x0102_0191);
        assert_eq!(joystick.functions, ["digital outputs", "joystick"]);
        let module = DeviceType::describe(0xFFFF_0191);
        assert!(module.functions[0].contains("67FFh"));
        let drive = DeviceType::describe(0x0002_0192);
        assert_eq!(
            (drive.profile_name.as_str(), drive.additional),
            ("CiA 402 drives and motion control", 2)
        );
        assert!(drive.functions.is_empty());
        assert_eq!(
            DeviceType::describe(0).profile_name,
            "no standardized device profile"
        );
        assert_eq!(DeviceType::describe(499).profile_name, "CiA 499 device profile");
    }

    #[test]
    fn numbers_are_little_endian_and_length_checked() {
        assert_eq!(unsigned(&[0xBC, 0x0A, 0, 0], 4), Ok(0xABC));
        assert_eq!(unsigned(&[0x05], 4), Ok(5));
        assert_eq!(
            unsigned(&[1, 2, 3], 2).unwrap_err().to_string(),
            "the device answered with 3 byte(s); UNSIGNED16 has 2"
        );
        assert!(unsigned(&[], 1).is_err());
    }

    #[test]
    fn fields_tell_absent_objects_from_failures() {
        let absent = SdoTransferError::AbortedByServer { code: 0x0609_0011 };
        assert!(is_absent(&absent));
        assert_eq!(Field::unsigned(Err(absent.clone()), 2), Field::Absent);
        let silent = SdoTransferError::TimedOut {
            waiting_for: "initiate upload response",
            after: Duration::from_millis(300),
        };
        assert!(!is_absent(&silent));
        assert!(matches!(Field::unsigned(Err(silent), 2), Field::Failed(_)));
        assert_eq!(Field::unsigned(Ok(vec![100, 0]), 2), Field::Value(100));
        assert_eq!(
            Field::text(Ok(b"sim\0\0".to_vec())),
            Field::Value("sim".to_owned())
        );
        assert_eq!(
            Field::text(Ok(vec![1, 2])),
            Field::Failed("not text: 01 02".to_owned())
        );
        assert_eq!(Field::text(Err(absent)), Field::Absent);
    }

    #[test]
    fn heartbeats_of_the_node_give_its_state_or_the_bad_byte() {
        let frame = |text: &str| canopener_can::candump::parse_compact_frame(text).unwrap();
        assert_eq!(
            heartbeat_state(&frame("705#05"), 5),
            Some(Ok(NmtState::Operational))
        );
        // The toggle bit of a node guarding answer does not change the state.
        assert_eq!(
            heartbeat_state(&frame("705#FF"), 5),
            Some(Ok(NmtState::PreOperational))
        );
        assert_eq!(heartbeat_state(&frame("705#42"), 5), Some(Err(0x42)));
        assert_eq!(heartbeat_state(&frame("706#05"), 5), None);
        assert_eq!(heartbeat_state(&frame("705#0505"), 5), None);
        assert_eq!(heartbeat_state(&frame("705#R"), 5), None);
        assert_eq!(heartbeat_wait(100), Duration::from_millis(150));
    }
}

//! SDO abort codes (CiA 301 §7.2.4.3.17, table "SDO abort codes").
//!
//! The list is the complete CiA 301 table as every surveyed stack reproduces it. Codes outside it are
//! manufacturer-specific and have no standard text.

/// Toggle bit not alternated.
pub const TOGGLE_BIT_NOT_ALTERNATED: u32 = 0x0503_0000;
/// SDO protocol timed out.
pub const PROTOCOL_TIMED_OUT: u32 = 0x0504_0000;
/// Client/server command specifier not valid or unknown.
pub const COMMAND_SPECIFIER_INVALID: u32 = 0x0504_0001;
/// Invalid block size (block mode only).
pub const INVALID_BLOCK_SIZE: u32 = 0x0504_0002;
/// Invalid sequence number (block mode only).
pub const INVALID_SEQUENCE_NUMBER: u32 = 0x0504_0003;
/// CRC error (block mode only).
pub const CRC_ERROR: u32 = 0x0504_0004;
/// Out of memory.
pub const OUT_OF_MEMORY: u32 = 0x0504_0005;
/// Unsupported access to an object.
pub const UNSUPPORTED_ACCESS: u32 = 0x0601_0000;
/// Attempt to read a write-only object.
pub const READ_WRITE_ONLY: u32 = 0x0601_0001;
/// Attempt to write a read-only object.
pub const WRITE_READ_ONLY: u32 = 0x0601_0002;
/// Object does not exist in the object dictionary.
pub const OBJECT_DOES_NOT_EXIST: u32 = 0x0602_0000;
/// Object cannot be mapped to the PDO.
pub const OBJECT_NOT_MAPPABLE: u32 = 0x0604_0041;
/// The number and length of the objects to be mapped would exceed the PDO length.
pub const PDO_LENGTH_EXCEEDED: u32 = 0x0604_0042;
/// General parameter incompatibility.
pub const PARAMETER_INCOMPATIBLE: u32 = 0x0604_0043;
/// General internal incompatibility in the device.
pub const INTERNAL_INCOMPATIBLE: u32 = 0x0604_0047;
/// Access failed due to a hardware error.
pub const HARDWARE_ERROR: u32 = 0x0606_0000;
/// Data type does not match, length of service parameter does not match.
pub const LENGTH_MISMATCH: u32 = 0x0607_0010;
/// Data type does not match, length of service parameter too high.
pub const LENGTH_TOO_HIGH: u32 = 0x0607_0012;
/// Data type does not match, length of service parameter too low.
pub const LENGTH_TOO_LOW: u32 = 0x0607_0013;
/// Sub-index does not exist.
pub const SUB_INDEX_DOES_NOT_EXIST: u32 = 0x0609_0011;
/// Invalid value for parameter (download only).
pub const INVALID_VALUE: u32 = 0x0609_0030;
/// Value of parameter written too high (download only).
pub const VALUE_TOO_HIGH: u32 = 0x0609_0031;
/// Value of parameter written too low (download only).
pub const VALUE_TOO_LOW: u32 = 0x0609_0032;
/// Maximum value is less than minimum value.
pub const MAX_LESS_THAN_MIN: u32 = 0x0609_0036;
/// Resource not available: SDO connection.
pub const SDO_CONNECTION_UNAVAILABLE: u32 = 0x060A_0023;
/// General error.
pub const GENERAL_ERROR: u32 = 0x0800_0000;
/// Data cannot be transferred or stored to the application.
pub const CANNOT_TRANSFER: u32 = 0x0800_0020;
/// Data cannot be transferred or stored to the application because of local control.
pub const CANNOT_TRANSFER_LOCAL_CONTROL: u32 = 0x0800_0021;
/// Data cannot be transferred or stored to the application because of the present device state.
pub const CANNOT_TRANSFER_DEVICE_STATE: u32 = 0x0800_0022;
/// Object dictionary dynamic generation fails or no object dictionary is present.
pub const NO_OBJECT_DICTIONARY: u32 = 0x0800_0023;
/// No data available.
pub const NO_DATA_AVAILABLE: u32 = 0x0800_0024;

/// Every CiA 301 abort code with its text, in ascending order of code.
pub const ABORT_CODES: &[(u32, &str)] = &[
    (TOGGLE_BIT_NOT_ALTERNATED, "toggle bit not alternated"),
    (PROTOCOL_TIMED_OUT, "SDO protocol timed out"),
    (
        COMMAND_SPECIFIER_INVALID,
        "client/server command specifier not valid or unknown",
    ),
    (INVALID_BLOCK_SIZE, "invalid block size"),
    (INVALID_SEQUENCE_NUMBER, "invalid sequence number"),
    (CRC_ERROR, "CRC error"),
    (OUT_OF_MEMORY, "out of memory"),
    (UNSUPPORTED_ACCESS, "unsupported access to an object"),
    (READ_WRITE_ONLY, "attempt to read a write-only object"),
    (WRITE_READ_ONLY, "attempt to write a read-only object"),
    (
        OBJECT_DOES_NOT_EXIST,
        "object does not exist in the object dictionary",
    ),
    (OBJECT_NOT_MAPPABLE, "object cannot be mapped to the PDO"),
    (
        PDO_LENGTH_EXCEEDED,
        "number and length of the objects to be mapped would exceed the PDO length",
    ),
    (PARAMETER_INCOMPATIBLE, "general parameter incompatibility"),
    (
        INTERNAL_INCOMPATIBLE,
        "general internal incompatibility in the device",
    ),
    (HARDWARE_ERROR, "access failed due to a hardware error"),
    (
        LENGTH_MISMATCH,
        "data type does not match, length of service parameter does not match",
    ),
    (
        LENGTH_TOO_HIGH,
        "data type does not match, length of service parameter too high",
    ),
    (
        LENGTH_TOO_LOW,
        "data type does not match, length of service parameter too low",
    ),
    (SUB_INDEX_DOES_NOT_EXIST, "sub-index does not exist"),
    (INVALID_VALUE, "invalid value for parameter"),
    (VALUE_TOO_HIGH, "value of parameter written too high"),
    (VALUE_TOO_LOW, "value of parameter written too low"),
    (MAX_LESS_THAN_MIN, "maximum value is less than minimum value"),
    (
        SDO_CONNECTION_UNAVAILABLE,
        "resource not available: SDO connection",
    ),
    (GENERAL_ERROR, "general error"),
    (
        CANNOT_TRANSFER,
        "data cannot be transferred or stored to the application",
    ),
    (
        CANNOT_TRANSFER_LOCAL_CONTROL,
        "data cannot be transferred or stored to the application because of local control",
    ),
    (
        CANNOT_TRANSFER_DEVICE_STATE,
        "data cannot be transferred or stored to the application because of the present device state",
    ),
    (
        NO_OBJECT_DICTIONARY,
        "object dictionary dynamic generation fails or no object dictionary is present",
    ),
    (NO_DATA_AVAILABLE, "no data available"),
];

/// The CiA 301 text of an SDO abort code, or `None` for a code the standard does not define.
pub fn abort_code_text(code: u32) -> Option<&'static str> {
    ABORT_CODES
        .binary_search_by_key(&code, |(known, _)| *known)
        .ok()
        .and_then(|idx| {
            // `binary_search` returned an index inside the table.
            ABORT_CODES.get(idx).map(|(_, text)| *text)
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_is_sorted_and_complete() {
        assert!(ABORT_CODES.windows(2).all(|pair| pair[0].0 < pair[1].0));
        assert_eq!(ABORT_CODES.len(), 31);
    }

    #[test]
    fn known_and_unknown_codes() {
        assert_eq!(
            abort_code_text(0x0602_0000),
            Some("object does not exist in the object dictionary")
        );
        assert_eq!(abort_code_text(0x0503_0000), Some("toggle bit not alternated"));
        assert_eq!(abort_code_text(0x0800_0024), Some("no data available"));
        assert_eq!(abort_code_text(0x0604_0044), None);
        assert_eq!(abort_code_text(0), None);
        for (code, text) in ABORT_CODES {
            assert_eq!(abort_code_text(*code), Some(*text));
        }
    }
}

//! What CiA 301 requires, in one place: the clauses the tests cite and the abort codes each refusal
//! may carry.
//!
//! The accepted sets follow one rule, written down in `docs/conformance.md`: where the CCT's accepted
//! codes are public (the CCT log quoted in `cia301-401-305-essentials.md` §1.3 and §3.4), exactly that
//! set; elsewhere the code CiA 301's table names for the condition, plus the general error
//! 0800 0000h, which CiA 301 allows for any refusal. `cia301.sdo.31` then holds a device to the
//! specific codes, so a device that answers everything with the general error is still caught.

use canopener_wire::abort;

/// CiA 301 §7.2.4.3.6: initiate SDO upload.
pub const SDO_UPLOAD: &str = "CiA 301 §7.2.4.3.6 (SDO upload initiate)";
/// CiA 301 §7.2.4.3.7: upload SDO segment.
pub const SDO_UPLOAD_SEGMENT: &str = "CiA 301 §7.2.4.3.7 (SDO upload segment)";
/// CiA 301 §7.2.4.3.3: initiate SDO download.
pub const SDO_DOWNLOAD: &str = "CiA 301 §7.2.4.3.3 (SDO download initiate)";
/// CiA 301 §7.2.4.3.4: download SDO segment.
pub const SDO_DOWNLOAD_SEGMENT: &str = "CiA 301 §7.2.4.3.4 (SDO download segment)";
/// CiA 301 §7.2.4.3.9–11: SDO block download.
pub const SDO_BLOCK_DOWNLOAD: &str = "CiA 301 §7.2.4.3.9–11 (SDO block download)";
/// CiA 301 §7.2.4.3.13–15: SDO block upload.
pub const SDO_BLOCK_UPLOAD: &str = "CiA 301 §7.2.4.3.13–15 (SDO block upload)";
/// CiA 301 §7.2.4.3.17: abort SDO transfer and the table of abort codes.
pub const SDO_ABORT: &str = "CiA 301 §7.2.4.3.17 (SDO abort codes)";
/// CiA 301 §7.5.2: the SDO server parameter 1200h–127Fh.
pub const SDO_SERVER_PARAMETER: &str = "CiA 301 §7.5.2 (SDO server parameter 1200h–127Fh)";
/// CiA 301 §7.5.2: the SDO client parameter 1280h–12FFh.
pub const SDO_CLIENT_PARAMETER: &str = "CiA 301 §7.5.2 (SDO client parameter 1280h–12FFh)";
/// CiA 301 §7.2.2: PDO, transmission types and triggering.
pub const PDO: &str = "CiA 301 §7.2.2 (PDO)";
/// CiA 301 §7.5.2.35–38: the PDO communication and mapping parameters.
pub const PDO_PARAMETERS: &str = "CiA 301 §7.5.2.35–38 (PDO communication and mapping parameters)";
/// CiA 301 §7.4: the object dictionary and its entries' attributes.
pub const OBJECT_DICTIONARY: &str = "CiA 301 §7.4 (object dictionary)";
/// CiA 306 §4.6.3: how an EDS describes an entry (default, limits, access, ObjFlags).
pub const EDS_OBJECTS: &str = "CiA 306 §4.6.3 (object descriptions)";
/// CiA 301 §7.2.7: emergency objects.
pub const EMCY: &str = "CiA 301 §7.2.7 (EMCY)";
/// CiA 301 §7.5.2: error register 1001h and pre-defined error field 1003h.
pub const ERROR_OBJECTS: &str = "CiA 301 §7.5.2 (1001h error register, 1003h pre-defined error field)";
/// CiA 301 §7.5.2.2: the error register 1001h and its generic bit.
pub const ERROR_REGISTER: &str = "CiA 301 §7.5.2.2 (1001h error register)";
/// CiA 301 §7.2.5: SYNC.
pub const SYNC: &str = "CiA 301 §7.2.5 (SYNC)";
/// CiA 301 §7.5.2: SYNC objects 1005h, 1006h, 1007h, 1019h.
pub const SYNC_OBJECTS: &str = "CiA 301 §7.5.2 (1005h, 1006h, 1007h, 1019h)";
/// CiA 301 §7.2.8.3.2.1: node guarding and life guarding.
pub const GUARDING: &str = "CiA 301 §7.2.8.3.2.1 (node guarding)";
/// CiA 301 §7.2.8.3.2.2: heartbeat.
pub const HEARTBEAT: &str = "CiA 301 §7.2.8.3.2.2 (heartbeat)";
/// CiA 301 §7.5.2: heartbeat consumer 1016h and error behaviour 1029h.
pub const HEARTBEAT_CONSUMER: &str = "CiA 301 §7.5.2 (1016h consumer heartbeat time, 1029h error behaviour)";
/// CiA 301 §7.5.2: store 1010h and restore 1011h.
pub const STORE_RESTORE: &str = "CiA 301 §7.5.2 (1010h store parameters, 1011h restore default parameters)";
/// CiA 301 §7.5.2: 1020h, the date and time of the configuration a tool downloaded and saved.
pub const VERIFY_CONFIGURATION: &str = "CiA 301 §7.5.2 (1020h verify configuration)";
/// CiA 301 §7.3.5: restricted CAN-IDs.
pub const RESTRICTED_IDS: &str = "CiA 301 §7.3.5 (restricted CAN-IDs)";
/// CiA 301 §7.2.8.2: NMT states and the services allowed in each.
pub const NMT_STATES: &str = "CiA 301 §7.2.8.2 (NMT states and services per state)";
/// CiA 301 §7.2.8.2: the initialisation sub-states reset application (2000h–9FFFh to their power-on
/// values, then reset communication) and reset communication (1000h–1FFFh).
pub const NMT_RESETS: &str =
    "CiA 301 §7.2.8.2 (NMT initialisation: reset application 2000h–9FFFh, reset communication 1000h–1FFFh)";
/// CiA 301 §7.2.8.3.1: NMT module control services.
pub const NMT_MODULE_CONTROL: &str = "CiA 301 §7.2.8.3.1 (NMT module control)";
/// CiA 301 §7.2.8.3.3: boot-up.
pub const BOOT_UP: &str = "CiA 301 §7.2.8.3.3 (boot-up)";
/// CiA 306: the EDS file format.
pub const EDS_FORMAT: &str = "CiA 306 (electronic data sheet)";

/// The abort codes a refusal may carry, and where that set comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Accepted {
    /// The codes.
    pub codes: &'static [u32],
    /// Where the set comes from (a CCT case, or CiA 301's table).
    pub source: &'static str,
}

impl Accepted {
    /// Whether `code` is in the set.
    pub fn accepts(&self, code: u32) -> bool {
        self.codes.contains(&code)
    }

    /// `0601 0002h, 0601 0000h or 0800 0000h`.
    pub fn list(&self) -> String {
        let codes: Vec<String> = self.codes.iter().map(|c| code_text(*c)).collect();
        match codes.split_last() {
            Some((last, [])) => last.clone(),
            Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
            None => String::new(),
        }
    }
}

/// `0609 0031h`, as CiA 301 writes abort codes.
pub fn code_text(code: u32) -> String {
    format!("{:04X} {:04X}h", code >> 16, code & 0xFFFF)
}

/// `0609 0031h (value of parameter written too high)`.
pub fn code_meaning(code: u32) -> String {
    match abort::abort_code_text(code) {
        Some(text) => format!("{} ({text})", code_text(code)),
        None => code_text(code),
    }
}

const CCT_LOG: &str = "the CCT's accepted codes (cia301-401-305-essentials.md §1.3)";
const CCT_MAPPING: &str = "the CCT's accepted codes for PDO mapping (cia301-401-305-essentials.md §3.4)";
const CIA_TABLE: &str = "CiA 301's abort code for the condition, or the general error";

/// Writing a read-only entry (CCT SDO 03, OD 03).
pub const WRITE_READ_ONLY: Accepted = Accepted {
    codes: &[
        abort::WRITE_READ_ONLY,
        abort::UNSUPPORTED_ACCESS,
        abort::GENERAL_ERROR,
    ],
    source: CCT_LOG,
};
/// Reading a write-only entry (CCT OD 04).
pub const READ_WRITE_ONLY: Accepted = Accepted {
    codes: &[
        abort::READ_WRITE_ONLY,
        abort::UNSUPPORTED_ACCESS,
        abort::GENERAL_ERROR,
    ],
    source: CCT_LOG,
};
/// A sub-index that does not exist (CCT SDO 05).
pub const NO_SUB_INDEX: Accepted = Accepted {
    codes: &[abort::SUB_INDEX_DOES_NOT_EXIST, abort::GENERAL_ERROR],
    source: CCT_LOG,
};
/// An object that does not exist (CCT SDO 06, SDO 28–30).
pub const NO_OBJECT: Accepted = Accepted {
    codes: &[abort::OBJECT_DOES_NOT_EXIST, abort::GENERAL_ERROR],
    source: CCT_LOG,
};
/// An unknown command specifier (CCT SDO 07).
pub const BAD_COMMAND: Accepted = Accepted {
    codes: &[abort::COMMAND_SPECIFIER_INVALID, abort::GENERAL_ERROR],
    source: CCT_LOG,
};
/// Too many bytes for the entry's type (CCT SDO 08).
pub const TOO_LONG: Accepted = Accepted {
    codes: &[
        abort::LENGTH_MISMATCH,
        abort::LENGTH_TOO_HIGH,
        abort::GENERAL_ERROR,
    ],
    source: CCT_LOG,
};
/// Too few bytes for the entry's type (CCT SDO 09).
pub const TOO_SHORT: Accepted = Accepted {
    codes: &[
        abort::LENGTH_MISMATCH,
        abort::LENGTH_TOO_LOW,
        abort::GENERAL_ERROR,
    ],
    source: CCT_LOG,
};
/// A value above HighLimit (CCT SDO 10, OD 06).
pub const TOO_HIGH: Accepted = Accepted {
    codes: &[abort::VALUE_TOO_HIGH, abort::INVALID_VALUE, abort::GENERAL_ERROR],
    source: CCT_LOG,
};
/// A value below LowLimit (CCT SDO 11, OD 06): the CCT's set for SDO 10 mirrored to "too low".
pub const TOO_LOW: Accepted = Accepted {
    codes: &[abort::VALUE_TOO_LOW, abort::INVALID_VALUE, abort::GENERAL_ERROR],
    source: CIA_TABLE,
};
/// A segment whose toggle bit did not alternate (CCT SDO 17).
pub const TOGGLE: Accepted = Accepted {
    codes: &[abort::TOGGLE_BIT_NOT_ALTERNATED, abort::GENERAL_ERROR],
    source: CIA_TABLE,
};
/// A block upload with a block size outside 1..127 (CCT SDO 26).
pub const BLOCK_SIZE: Accepted = Accepted {
    codes: &[
        abort::COMMAND_SPECIFIER_INVALID,
        abort::INVALID_BLOCK_SIZE,
        abort::GENERAL_ERROR,
    ],
    source: CCT_LOG,
};
/// A block acknowledge with an impossible sequence number (CCT SDO 27).
pub const SEQUENCE_NUMBER: Accepted = Accepted {
    codes: &[
        abort::COMMAND_SPECIFIER_INVALID,
        abort::INVALID_SEQUENCE_NUMBER,
        abort::GENERAL_ERROR,
    ],
    source: CCT_LOG,
};
/// The answer of a device without block transfer to a block request (CCT SDO 19, 22).
pub const NO_BLOCK_TRANSFER: Accepted = Accepted {
    codes: &[abort::COMMAND_SPECIFIER_INVALID],
    source: CCT_LOG,
};
/// Writing mapping entries outside the mapping procedure (CCT PDO 23, 24).
pub const MAPPING_SEQUENCE: Accepted = Accepted {
    codes: &[
        abort::UNSUPPORTED_ACCESS,
        abort::OBJECT_NOT_MAPPABLE,
        abort::GENERAL_ERROR,
    ],
    source: CCT_MAPPING,
};
/// Enabling a mapping that is too long or has too many entries (CCT PDO 25, 26). 0609 0030h and
/// 0609 0031h are CiA 301's codes for a sub-index 0 above its range, which some stacks use.
pub const MAPPING_LENGTH: Accepted = Accepted {
    codes: &[
        abort::PDO_LENGTH_EXCEEDED,
        abort::UNSUPPORTED_ACCESS,
        abort::OBJECT_NOT_MAPPABLE,
        abort::OBJECT_DOES_NOT_EXIST,
        abort::INVALID_VALUE,
        abort::VALUE_TOO_HIGH,
        abort::GENERAL_ERROR,
    ],
    source: CCT_MAPPING,
};
/// Mapping an object that may not be mapped, or in the wrong direction (CCT PDO 28, 29, 31, 32).
pub const NOT_MAPPABLE: Accepted = Accepted {
    codes: &[abort::OBJECT_NOT_MAPPABLE, abort::OBJECT_DOES_NOT_EXIST],
    source: CCT_MAPPING,
};
/// A value CiA 301 does not allow for a parameter (reserved transmission types, restricted CAN-IDs,
/// a CAN-ID changed while valid, SYNC counter overflow 1 or above 240).
pub const INVALID_VALUE: Accepted = Accepted {
    codes: &[abort::INVALID_VALUE, abort::GENERAL_ERROR],
    source: CIA_TABLE,
};
/// A value out of range, with either of CiA 301's codes for it.
pub const OUT_OF_RANGE: Accepted = Accepted {
    codes: &[
        abort::INVALID_VALUE,
        abort::VALUE_TOO_HIGH,
        abort::VALUE_TOO_LOW,
        abort::GENERAL_ERROR,
    ],
    source: CIA_TABLE,
};
/// 1019h written while 1006h is not 0 (CCT SYNC 09).
pub const DEVICE_STATE: Accepted = Accepted {
    codes: &[abort::CANNOT_TRANSFER_DEVICE_STATE, abort::GENERAL_ERROR],
    source: CIA_TABLE,
};
/// A wrong store or restore signature (CCT Other 01, 03).
pub const WRONG_SIGNATURE: Accepted = Accepted {
    codes: &[abort::CANNOT_TRANSFER, abort::GENERAL_ERROR],
    source: CIA_TABLE,
};
/// Reading 1003h above its number of errors (CCT Emergency 03; CiA 301 as quoted in CANopenNode
/// PR 253).
pub const NO_DATA: Accepted = Accepted {
    codes: &[abort::NO_DATA_AVAILABLE, abort::GENERAL_ERROR],
    source: CIA_TABLE,
};
/// Two heartbeat consumer entries for one node (CCT Heartbeat 04).
pub const INCOMPATIBLE: Accepted = Accepted {
    codes: &[abort::PARAMETER_INCOMPATIBLE, abort::GENERAL_ERROR],
    source: CIA_TABLE,
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_read_as_cia_301_writes_them() {
        assert_eq!(code_text(0x0609_0031), "0609 0031h");
        assert_eq!(TOO_HIGH.list(), "0609 0031h, 0609 0030h or 0800 0000h");
        assert!(NO_BLOCK_TRANSFER.accepts(0x0504_0001) && !NO_BLOCK_TRANSFER.accepts(0x0800_0000));
        assert!(code_meaning(0x0602_0000).contains("does not exist"));
    }
}

/// The CiA 305 (LSS) clauses, cited by service name: the section numbers of CiA 305 v3.0 were not at
/// hand to verify, and a wrong number is worse than none.
pub mod lss {
    /// CiA 305 LSS slave states (waiting and configuration).
    pub const STATES: &str = "CiA 305 v3.0 (LSS slave state machine)";
    /// CiA 305 switch state global.
    pub const SWITCH_GLOBAL: &str = "CiA 305 v3.0 (switch state global)";
    /// CiA 305 switch state selective.
    pub const SWITCH_SELECTIVE: &str = "CiA 305 v3.0 (switch state selective)";
    /// CiA 305 configure node-ID.
    pub const CONFIGURE_NODE_ID: &str = "CiA 305 v3.0 (configure node-ID)";
    /// CiA 305 configure bit timing.
    pub const CONFIGURE_BIT_TIMING: &str = "CiA 305 v3.0 (configure bit timing parameters)";
    /// CiA 305 store configuration.
    pub const STORE: &str = "CiA 305 v3.0 (store configuration)";
    /// CiA 305 inquire services.
    pub const INQUIRE: &str = "CiA 305 v3.0 (inquire LSS address, inquire node-ID)";
    /// CiA 305 identify remote slave.
    pub const IDENTIFY_REMOTE: &str = "CiA 305 v3.0 (LSS identify remote slave)";
    /// CiA 305 identify non-configured remote slave.
    pub const IDENTIFY_NON_CONFIGURED: &str = "CiA 305 v3.0 (LSS identify non-configured remote slave)";
    /// CiA 305 fastscan.
    pub const FASTSCAN: &str = "CiA 305 v3.0 (LSS fastscan)";
}

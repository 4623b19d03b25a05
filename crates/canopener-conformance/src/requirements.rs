//! What CiA 301 requires, in one place: the clauses the tests cite and the abort codes each refusal
//! may carry.
//!
//! The accepted sets follow one rule, written down in `docs/conformance.md`: where the CCT's accepted
//! codes are public (the CCT log quoted in `cia301-401-305-essentials.md` §1.3 and §3.4), exactly that
//! set; elsewhere the code CiA 301's table names for the condition, plus the general error
//! 0800 0000h, which CiA 301 allows for any refusal. `cia301.sdo.31` then holds a device to the
//! specific codes, so a device that answers everything with the general error is still caught.

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
/// CiA 301 §7.3.5: restricted CAN-IDs.
pub const RESTRICTED_IDS: &str = "CiA 301 §7.3.5 (restricted CAN-IDs)";
/// CiA 301 §7.2.8.2: NMT states and the services allowed in each.
pub const NMT_STATES: &str = "CiA 301 §7.2.8.2 (NMT states and services per state)";
/// CiA 301 §7.2.8.3.1: NMT module control services.
pub const NMT_MODULE_CONTROL: &str = "CiA 301 §7.2.8.3.1 (NMT module control)";
/// CiA 301 §7.2.8.3.3: boot-up.
pub const BOOT_UP: &str = "CiA 301 §7.2.8.3.3 (boot-up)";
/// CiA 306: the EDS file format.
pub const EDS_FORMAT: &str = "CiA 306 (electronic data sheet)";

// The accepted abort codes live in `canopener_wire::accepted`, the one table the conformance suites
// and the model-based tester's models share; they are re-exported here under their old names.
pub use canopener_wire::accepted::{
    Accepted, BAD_COMMAND, BLOCK_SIZE, DEVICE_STATE, INCOMPATIBLE, INVALID_VALUE, MAPPING_LENGTH,
    MAPPING_SEQUENCE, NO_BLOCK_TRANSFER, NO_DATA, NO_OBJECT, NO_SUB_INDEX, NOT_MAPPABLE, OUT_OF_RANGE,
    READ_WRITE_ONLY, SEQUENCE_NUMBER, TOGGLE, TOO_HIGH, TOO_LONG, TOO_LOW, TOO_SHORT, WRITE_READ_ONLY,
    WRONG_SIGNATURE, code_meaning, code_text,
};

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

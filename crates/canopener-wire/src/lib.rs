//! CANopen on the wire: frame codecs, the CiA 301 / CiA 305 tables, and a decoder that explains any
//! CAN frame as CANopen.
//!
//! This crate is pure data: it performs no IO, starts no threads and never reads a clock. It knows
//! the predefined connection set of CiA 301 §7.3.5, not the configuration of particular devices, so
//! PDOs moved to other CAN-IDs are not recognised.
//!
//! Main items:
//! - Codecs that later protocol state machines build on: [`SdoRequest`] / [`SdoResponse`] /
//!   [`BlockSegment`] (CiA 301 §7.2.4), [`NmtCommand`] and [`NmtState`] (§7.2.8), [`EmcyMessage`]
//!   (§7.2.7), [`TimeOfDay`] (§7.2.6), [`LssRequest`] / [`LssResponse`] (CiA 305), and the block
//!   transfer CRC [`crc16_ccitt`].
//! - Tables: [`abort_code_text`], [`emcy_code_text`], [`error_register_text`], [`bit_timing_text`],
//!   and [`classify`] for the service of a CAN-ID.
//! - [`accepted`]: the one table of the abort codes a refusal may carry and the answers an SDO
//!   server may choose between, which the conformance suites and the model-based tester share.
//! - [`Decoder`]: the stateful monitor decoder. It follows SDO transfers (segmented and block) and node
//!   guarding per node, so that every frame gets one line such as
//!   `SDO rx node 5: download segment toggle=1 7 bytes (14/23) of 1008h:00`, with protocol mistakes
//!   listed as anomalies.
//!
//! ```
//! use canopener_can::{CanFrame, StandardId};
//! use canopener_wire::Decoder;
//!
//! let mut decoder = Decoder::new();
//! let trace = [(0x705, &[0x05][..]), (0x622, &[0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0][..])];
//! let lines: Vec<String> = trace
//!     .iter()
//!     .map(|(id, data)| CanFrame::new(StandardId::new(*id).unwrap(), data).unwrap())
//!     .map(|frame| decoder.decode(&frame).to_string())
//!     .collect();
//! assert_eq!(lines, ["Heartbeat node 5: OPERATIONAL", "SDO rx node 34: initiate upload 1018h:01"]);
//! ```

#![warn(missing_docs)]
// A file or a frame must never panic this library: no unwrap, expect or unchecked index outside tests
// (as rustls does); each exception names, where it stands, why it cannot fail.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)
)]

pub mod abort;
pub mod accepted;
mod cob;
mod crc;
mod decoded;
mod decoder;
mod emcy;
pub mod energybus;
pub mod lss;
mod nmt;
mod node;
pub mod sdo;
mod time_of_day;

pub use abort::{ABORT_CODES, abort_code_text};
pub use cob::{
    CobClass, EMCY_BASE, ERROR_CONTROL_BASE, LSS_MASTER_TO_SLAVE_ID, LSS_SLAVE_TO_MASTER_ID, NMT_ID,
    RPDO_BASES, SDO_RX_BASE, SDO_TX_BASE, SYNC_ID, Service, TIME_ID, TPDO_BASES, classify,
};
pub use crc::{crc16_ccitt, crc16_ccitt_update};
pub use decoded::{
    CrcCheck, Decoded, EmcyPayload, ErrorControlPayload, LssPayload, Payload, SdoFrame, SdoPayload,
    TransferKind, TransferProgress,
};
pub use decoder::{Decoder, GUARD_RESPONSE_WINDOW};
pub use emcy::{
    EMCY_CODES, ERROR_REGISTER_BITS, ERROR_REGISTER_GENERIC, ERROR_REGISTER_RESERVED, EmcyError, EmcyMessage,
    emcy_code_text, error_register_text,
};
pub use lss::{
    BIT_TIMING_TABLE, BitTiming, IdentifyField, LssAddress, LssAddressPart, LssError, LssRequest,
    LssResponse, bit_timing_index, bit_timing_text,
};
pub use nmt::{GUARD_TOGGLE_BIT, NmtCommand, NmtState, encode_guard_response};
pub use node::NodeId;
pub use sdo::{
    BlockSegment, InitiateData, Multiplexer, SdoEncodeError, SdoParseError, SdoRequest, SdoResponse, Segment,
};
pub use time_of_day::{
    MILLIS_MASK, MILLIS_PER_DAY, TimeOfDay, TimeOfDayError, UNIX_MILLIS_AT_1984, civil_from_days,
    since_1984_from_unix_millis,
};

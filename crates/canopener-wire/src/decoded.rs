//! What the monitor decoder found in one frame: plain data plus a one-line `Display`.

use std::fmt;

use canopener_can::CanId;

use crate::cob::Service;
use crate::lss::{LssRequest, LssResponse};
use crate::nmt::{NmtCommand, NmtState};
use crate::sdo::{BlockSegment, InitiateData, Multiplexer, SdoRequest, SdoResponse};
use crate::time_of_day::TimeOfDay;

/// One frame, decoded as CANopen.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Decoded {
    /// The frame's CAN-ID.
    pub id: CanId,
    /// The service by the predefined connection set.
    pub service: Service,
    /// The node the frame comes from or is addressed to: the node-id in a node-addressed CAN-ID
    /// (0 is flagged as an anomaly), or an NMT command's target node; `None` for broadcasts.
    pub node: Option<u8>,
    /// What the frame says.
    pub payload: Payload,
    /// Protocol mistakes seen in this frame (wrong DLC, reserved bits set, wrong toggle, …), each a
    /// short lowercase sentence. Empty for a correct frame.
    pub anomalies: Vec<String>,
}

/// What a frame says, per service.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Payload {
    /// NMT module control (CiA 301 §7.2.8.3.1).
    Nmt {
        /// The command, or `None` for an unknown specifier.
        command: Option<NmtCommand>,
        /// The command specifier byte.
        raw_command: u8,
        /// The target node-id; 0 addresses all nodes.
        target: u8,
    },
    /// SYNC (CiA 301 §7.2.5).
    Sync {
        /// The counter (1 to 240), if the SYNC carries one.
        counter: Option<u8>,
    },
    /// Emergency (CiA 301 §7.2.7).
    Emcy(EmcyPayload),
    /// TIME (CiA 301 §7.2.6).
    Time(TimeOfDay),
    /// PDO data (CiA 301 §7.2.2).
    Pdo {
        /// The data bytes; their meaning depends on the PDO mapping.
        data: Vec<u8>,
    },
    /// A remote request for a TPDO.
    PdoRequest {
        /// The requested length.
        dlc: u8,
    },
    /// SDO (CiA 301 §7.2.4).
    Sdo(SdoPayload),
    /// Boot-up, heartbeat or node guarding (CiA 301 §7.2.8.3.2).
    ErrorControl(ErrorControlPayload),
    /// Layer setting services (CiA 305).
    Lss(LssPayload),
    /// A frame that is not CANopen or could not be decoded: the raw content.
    Raw {
        /// Whether it is a remote frame.
        remote: bool,
        /// The DLC.
        dlc: u8,
        /// The data bytes (empty for a remote frame).
        data: Vec<u8>,
    },
}

/// An emergency message with its texts.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EmcyPayload {
    /// The error code; 0000h resets an error.
    pub code: u16,
    /// The text of the error code, see [`crate::emcy_code_text`].
    pub code_text: &'static str,
    /// The error register 1001h.
    pub register: u8,
    /// The names of the register bits that are set, e.g. "generic, communication".
    pub register_text: String,
    /// The manufacturer-specific bytes D3..D7 present in the frame.
    pub vendor: Vec<u8>,
}

/// A boot-up, heartbeat or node guarding frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorControlPayload {
    /// The node entered pre-operational after initialisation.
    BootUp,
    /// A heartbeat with the node's state.
    Heartbeat {
        /// The state, or `None` for an undefined state code.
        state: Option<NmtState>,
        /// The state byte.
        raw_state: u8,
    },
    /// The NMT master asks the node for its state (a remote frame).
    GuardRequest,
    /// The node's answer to a guarding request.
    GuardResponse {
        /// The state, or `None` for an undefined state code.
        state: Option<NmtState>,
        /// The state code (bits 6..0).
        raw_state: u8,
        /// The toggle bit (bit 7).
        toggle: bool,
    },
}

/// An LSS frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LssPayload {
    /// From the LSS master (7E5h).
    Request(LssRequest),
    /// From an LSS slave (7E4h).
    Response(LssResponse),
}

/// An SDO frame with what the decoder knows about the transfer it belongs to.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SdoPayload {
    /// The frame itself.
    pub frame: SdoFrame,
    /// The transfer this frame belongs to, after the frame was taken into account; `None` when the
    /// frame belongs to no known transfer.
    pub transfer: Option<TransferProgress>,
    /// The outcome of the CRC check on a block end frame.
    pub crc: Option<CrcCheck>,
}

impl SdoPayload {
    /// The value of an expedited transfer as a little-endian integer.
    pub fn expedited_value(&self) -> Option<u32> {
        match &self.frame {
            SdoFrame::Request(SdoRequest::InitiateDownload { data, .. })
            | SdoFrame::Response(SdoResponse::InitiateUpload { data, .. }) => data.expedited_value(),
            _ => None,
        }
    }

    /// The abort code and its CiA 301 text (if the code is standard).
    pub fn abort(&self) -> Option<(u32, Option<&'static str>)> {
        match &self.frame {
            SdoFrame::Request(SdoRequest::Abort { code, .. })
            | SdoFrame::Response(SdoResponse::Abort { code, .. }) => {
                Some((*code, crate::abort::abort_code_text(*code)))
            }
            _ => None,
        }
    }
}

/// An SDO frame, classified with the help of the transfer state.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SdoFrame {
    /// Client to server.
    Request(SdoRequest),
    /// Server to client.
    Response(SdoResponse),
    /// A block sub-block segment, from the client in a download or the server in an upload.
    BlockSegment(BlockSegment),
    /// A command byte that means nothing in this direction.
    Invalid {
        /// D0.
        command: u8,
    },
}

/// How far a transfer has got.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TransferProgress {
    /// The entry being transferred.
    pub mux: Multiplexer,
    /// The protocol.
    pub kind: TransferKind,
    /// Data bytes transferred so far.
    pub bytes: u64,
    /// The announced total, if any.
    pub size: Option<u32>,
}

/// The SDO transfer protocols.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TransferKind {
    /// Write with the value in the initiate frame (§7.2.4.3.3).
    ExpeditedDownload,
    /// Write in segments (§7.2.4.3.4).
    SegmentedDownload,
    /// Read with the value in the initiate response (§7.2.4.3.6).
    ExpeditedUpload,
    /// Read in segments (§7.2.4.3.7).
    SegmentedUpload,
    /// Write in blocks (§7.2.4.3.9).
    BlockDownload,
    /// Read in blocks (§7.2.4.3.13).
    BlockUpload,
}

impl TransferKind {
    /// Whether data flows from the client to the server.
    pub const fn is_download(self) -> bool {
        matches!(
            self,
            TransferKind::ExpeditedDownload | TransferKind::SegmentedDownload | TransferKind::BlockDownload
        )
    }
}

impl fmt::Display for TransferKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            TransferKind::ExpeditedDownload => "expedited download",
            TransferKind::SegmentedDownload => "segmented download",
            TransferKind::ExpeditedUpload => "expedited upload",
            TransferKind::SegmentedUpload => "segmented upload",
            TransferKind::BlockDownload => "block download",
            TransferKind::BlockUpload => "block upload",
        })
    }
}

/// The CRC check of a block transfer (CiA 301 §7.2.4.3.16).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CrcCheck {
    /// The CRC in the end frame matches the data.
    Match(u16),
    /// The CRC in the end frame does not match the data.
    Mismatch {
        /// The CRC the sender wrote.
        sent: u16,
        /// The CRC of the data seen on the bus.
        computed: u16,
    },
    /// Client and server did not both announce CRC support, so the field is not a CRC.
    NotUsed,
    /// Segments were repeated, so the monitor cannot be sure which data the receiver kept.
    NotVerified,
}

impl fmt::Display for Decoded {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let node = NodeText(self.node);
        match &self.payload {
            Payload::Nmt {
                command,
                raw_command,
                target,
            } => {
                match command {
                    Some(command) => write!(f, "NMT {command}")?,
                    None => write!(f, "NMT unknown command 0x{raw_command:02X}")?,
                }
                if *target == 0 {
                    f.write_str(" -> all nodes")?
                } else {
                    write!(f, " -> node {target}")?
                }
            }
            Payload::Sync {
                counter: Some(counter),
            } => write!(f, "SYNC counter {counter}")?,
            Payload::Sync { counter: None } => f.write_str("SYNC")?,
            Payload::Emcy(emcy) => {
                write!(
                    f,
                    "EMCY{node}: 0x{:04X} ({}) reg 0x{:02X}",
                    emcy.code, emcy.code_text, emcy.register
                )?;
                if !emcy.register_text.is_empty() {
                    write!(f, " ({})", emcy.register_text)?;
                }
                if emcy.vendor.iter().any(|byte| *byte != 0) {
                    f.write_str(" vendor")?;
                    for byte in &emcy.vendor {
                        write!(f, " {byte:02X}")?;
                    }
                }
            }
            Payload::Time(time) => write!(f, "TIME {time}")?,
            Payload::Pdo { data } => write!(f, "{}{node} ({})", self.service, ByteCount(data.len()))?,
            Payload::PdoRequest { dlc } => write!(f, "{}{node} remote request (DLC {dlc})", self.service)?,
            Payload::Sdo(sdo) => {
                write!(f, "{}{node}: ", self.service)?;
                fmt_sdo(f, sdo)?;
            }
            Payload::ErrorControl(event) => match event {
                ErrorControlPayload::BootUp => write!(f, "Boot-up{node}")?,
                ErrorControlPayload::Heartbeat { state, raw_state } => {
                    write!(f, "Heartbeat{node}: {}", StateText(*state, *raw_state))?;
                }
                ErrorControlPayload::GuardRequest => write!(f, "Node guarding request{node}")?,
                ErrorControlPayload::GuardResponse {
                    state,
                    raw_state,
                    toggle,
                } => write!(
                    f,
                    "Node guarding response{node}: {} toggle={}",
                    StateText(*state, *raw_state),
                    u8::from(*toggle)
                )?,
            },
            Payload::Lss(LssPayload::Request(request)) => write!(f, "LSS master: {request}")?,
            Payload::Lss(LssPayload::Response(response)) => write!(f, "LSS slave: {response}")?,
            Payload::Raw { remote, dlc, data } => {
                if self.service == Service::Unknown {
                    write!(f, "{} not CANopen (predefined set)", self.id)?;
                } else {
                    write!(f, "{}{node}", self.service)?;
                }
                if *remote {
                    write!(f, " remote frame (DLC {dlc})")?
                } else {
                    write!(f, " ({})", ByteCount(data.len()))?
                }
            }
        }
        if !self.anomalies.is_empty() {
            write!(f, " [anomaly: {}]", self.anomalies.join("; "))?;
        }
        Ok(())
    }
}

/// `1 byte`, `7 bytes`.
struct ByteCount<T>(T);

impl<T: fmt::Display + PartialEq + From<u8>> fmt::Display for ByteCount<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0 == T::from(1) {
            f.write_str("1 byte")
        } else {
            write!(f, "{} bytes", self.0)
        }
    }
}

/// ` node 5`, or nothing.
struct NodeText(Option<u8>);

impl fmt::Display for NodeText {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(node) => write!(f, " node {node}"),
            None => Ok(()),
        }
    }
}

struct StateText(Option<NmtState>, u8);

impl fmt::Display for StateText {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(state) => write!(f, "{state}"),
            None => write!(f, "unknown state 0x{:02X}", self.1),
        }
    }
}

/// `(14/23)`, `(14/?)` when no size was announced.
struct Progress(TransferProgress);

impl fmt::Display for Progress {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0.size {
            Some(size) => write!(f, "({}/{size})", self.0.bytes),
            None => write!(f, "({}/?)", self.0.bytes),
        }
    }
}

/// ` (14/23) of 1008h:00`, or nothing without a transfer.
struct Context(Option<TransferProgress>);

impl fmt::Display for Context {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(progress) => write!(f, " {} of {}", Progress(progress), progress.mux),
            None => Ok(()),
        }
    }
}

/// ` of 1008h:00`, or nothing without a transfer.
struct Of(Option<TransferProgress>);

impl fmt::Display for Of {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(progress) => write!(f, " of {}", progress.mux),
            None => Ok(()),
        }
    }
}

fn fmt_value(f: &mut fmt::Formatter<'_>, mux: &Multiplexer, data: &InitiateData) -> fmt::Result {
    match data {
        InitiateData::Expedited { data, size_indicated } => {
            let value = le_hex(data);
            if *size_indicated {
                write!(f, "{mux} = {value} ({})", ByteCount(data.len()))
            } else {
                write!(f, "{mux} = {value} (4 bytes, size not indicated)")
            }
        }
        InitiateData::Segmented { size: Some(size) } => write!(f, "{mux} ({}, segmented)", ByteCount(*size)),
        InitiateData::Segmented { size: None } => write!(f, "{mux} (size not indicated, segmented)"),
    }
}

/// `0x03E8` for 2 bytes: the little-endian bytes as one number, with as many hex digits as they hold.
fn le_hex(data: &[u8]) -> String {
    let digits: String = data.iter().rev().map(|byte| format!("{byte:02X}")).collect();
    format!("0x{digits}")
}

fn crc_support(supported: bool) -> &'static str {
    if supported { "crc" } else { "no crc" }
}

fn fmt_size(f: &mut fmt::Formatter<'_>, size: Option<u32>) -> fmt::Result {
    match size {
        Some(size) => write!(f, "{}", ByteCount(size)),
        None => f.write_str("size not indicated"),
    }
}

fn fmt_crc(f: &mut fmt::Formatter<'_>, crc: u16, check: Option<CrcCheck>) -> fmt::Result {
    match check {
        Some(CrcCheck::Match(_)) => write!(f, " crc=0x{crc:04X} ok"),
        Some(CrcCheck::Mismatch { computed, .. }) => {
            write!(f, " crc=0x{crc:04X} WRONG (data gives 0x{computed:04X})")
        }
        Some(CrcCheck::NotUsed) => f.write_str(" crc not used"),
        Some(CrcCheck::NotVerified) => write!(f, " crc=0x{crc:04X} (not verified: segments were repeated)"),
        None => write!(f, " crc=0x{crc:04X}"),
    }
}

fn fmt_abort(f: &mut fmt::Formatter<'_>, mux: &Multiplexer, code: u32) -> fmt::Result {
    match crate::abort::abort_code_text(code) {
        Some(text) => write!(f, "ABORT {mux} 0x{code:08X} ({text})"),
        None => write!(f, "ABORT {mux} 0x{code:08X} (not a CiA 301 abort code)"),
    }
}

fn fmt_sdo(f: &mut fmt::Formatter<'_>, sdo: &SdoPayload) -> fmt::Result {
    let ctx = Context(sdo.transfer);
    let of = Of(sdo.transfer);
    let last = |last: bool| if last { " last" } else { "" };
    match &sdo.frame {
        SdoFrame::Request(request) => match request {
            SdoRequest::InitiateDownload {
                mux,
                data: data @ InitiateData::Expedited { .. },
            } => {
                f.write_str("download ")?;
                fmt_value(f, mux, data)
            }
            SdoRequest::InitiateDownload { mux, data } => {
                f.write_str("initiate download ")?;
                fmt_value(f, mux, data)
            }
            SdoRequest::DownloadSegment(segment) => write!(
                f,
                "download segment toggle={}{} {}{ctx}",
                u8::from(segment.toggle),
                last(segment.last),
                ByteCount(segment.data.len())
            ),
            SdoRequest::InitiateUpload { mux } => write!(f, "initiate upload {mux}"),
            SdoRequest::UploadSegment { toggle } => {
                write!(f, "upload segment request toggle={}{ctx}", u8::from(*toggle))
            }
            SdoRequest::Abort { mux, code } => fmt_abort(f, mux, *code),
            SdoRequest::BlockDownloadInitiate {
                mux,
                crc_supported,
                size,
            } => {
                write!(f, "initiate block download {mux} (")?;
                fmt_size(f, *size)?;
                write!(f, ", {})", crc_support(*crc_supported))
            }
            SdoRequest::BlockDownloadEnd { unused, crc } => {
                match sdo.transfer {
                    Some(progress) => write!(
                        f,
                        "end block download of {} ({} bytes)",
                        progress.mux, progress.bytes
                    )?,
                    None => write!(f, "end block download ({} unused)", ByteCount(*unused))?,
                }
                fmt_crc(f, *crc, sdo.crc)
            }
            SdoRequest::BlockUploadInitiate {
                mux,
                crc_supported,
                blksize,
                pst,
            } => write!(
                f,
                "initiate block upload {mux} blksize={blksize} pst={pst} ({})",
                crc_support(*crc_supported)
            ),
            SdoRequest::BlockUploadStart => write!(f, "start block upload{of}"),
            SdoRequest::BlockUploadAck { ackseq, blksize } => {
                write!(f, "block upload ack seq={ackseq} blksize={blksize}{ctx}")
            }
            SdoRequest::BlockUploadEndResponse => write!(f, "block upload{of} confirmed"),
        },
        SdoFrame::Response(response) => match response {
            SdoResponse::InitiateUpload {
                mux,
                data: data @ InitiateData::Expedited { .. },
            } => {
                f.write_str("upload ")?;
                fmt_value(f, mux, data)
            }
            SdoResponse::InitiateUpload { mux, data } => {
                f.write_str("initiate upload response ")?;
                fmt_value(f, mux, data)
            }
            SdoResponse::UploadSegment(segment) => write!(
                f,
                "upload segment toggle={}{} {}{ctx}",
                u8::from(segment.toggle),
                last(segment.last),
                ByteCount(segment.data.len())
            ),
            SdoResponse::InitiateDownload { mux } => match sdo.transfer {
                Some(TransferProgress {
                    kind: TransferKind::ExpeditedDownload,
                    ..
                }) => {
                    write!(f, "download {mux} confirmed")
                }
                _ => write!(f, "initiate download response {mux}"),
            },
            SdoResponse::DownloadSegment { toggle } => {
                write!(f, "download segment response toggle={}{ctx}", u8::from(*toggle))
            }
            SdoResponse::Abort { mux, code } => fmt_abort(f, mux, *code),
            SdoResponse::BlockDownloadInitiate {
                mux,
                crc_supported,
                blksize,
            } => write!(
                f,
                "initiate block download response {mux} blksize={blksize} ({})",
                crc_support(*crc_supported)
            ),
            SdoResponse::BlockDownloadAck { ackseq, blksize } => {
                write!(f, "block download ack seq={ackseq} blksize={blksize}{ctx}")
            }
            SdoResponse::BlockDownloadEndResponse => write!(f, "block download{of} confirmed"),
            SdoResponse::BlockUploadInitiate {
                mux,
                crc_supported,
                size,
            } => {
                write!(f, "initiate block upload response {mux} (")?;
                fmt_size(f, *size)?;
                write!(f, ", {})", crc_support(*crc_supported))
            }
            SdoResponse::BlockUploadEnd { unused, crc } => {
                match sdo.transfer {
                    Some(progress) => write!(
                        f,
                        "end block upload of {} ({} bytes)",
                        progress.mux, progress.bytes
                    )?,
                    None => write!(f, "end block upload ({} unused)", ByteCount(*unused))?,
                }
                fmt_crc(f, *crc, sdo.crc)
            }
        },
        SdoFrame::BlockSegment(segment) => {
            write!(
                f,
                "block segment seq={}{}{ctx}",
                segment.seqno,
                last(segment.last)
            )
        }
        SdoFrame::Invalid { command } => write!(f, "invalid command byte 0x{command:02X}"),
    }
}

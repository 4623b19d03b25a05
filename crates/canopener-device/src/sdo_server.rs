//! The SDO server of one server channel (CiA 301, "Service data object"), sans IO.
//!
//! One [`SdoServer`] serves one pair of COB-IDs: requests arrive on the client→server CAN-ID (`rx`,
//! 600h + node-ID for the default server 1200h) and responses leave on the server→client CAN-ID
//! (`tx`, 580h + node-ID). The additional servers 1201h–127Fh are just more instances with other
//! COB-IDs. The server does not own the object dictionary: the device passes its [`DynamicOd`] into
//! every call, so the same dictionary serves every channel, the PDOs and the application.
//!
//! Implemented, with the CiA 301 protocol names:
//! - SDO download (expedited with and without size indication, segmented with and without size
//!   indication, toggle bit, "n" unused bytes) and SDO upload (expedited and segmented);
//! - SDO block download and SDO block upload: initiate with size and CRC support flags, negotiated
//!   block size 1..127, sequence numbers, sub-block acknowledge with the last good sequence number and
//!   the next block size, end with the CRC-16 of [`canopener_wire::crc16_ccitt`] when both sides
//!   support it, and the protocol switch threshold of the block upload;
//! - SDO abort transfer from the client, and the SDO protocol timeout (default 1 s, abort 0504 0000h).
//!
//! Frames are read with [`canopener_wire::sdo`]'s parser and written with its encoder; abort codes are
//! [`canopener_wire::abort`]'s constants, and the checks of the dictionary ([`OdError::abort_code`])
//! give the object-related codes.
//!
//! Feed it with [`SdoServer::handle_frame`] (or [`SdoServer::handle_request`] for an already routed
//! frame) and [`SdoServer::handle_timeout`]; drain it with [`SdoServer::poll_transmit`],
//! [`SdoServer::poll_event`] and [`SdoServer::poll_timeout`].

use std::collections::VecDeque;
use std::time::Duration;

use canopener_can::{CanFrame, CanId, Instant, StandardId};
use canopener_od::{DynamicOd, ObjectKey, OdError};
use canopener_wire::abort;
use canopener_wire::sdo::{
    BlockSegment, InitiateData, MAX_BLOCK_SIZE, Multiplexer, SEGMENT_DATA_LEN, SdoRequest, SdoResponse,
    Segment, ccs,
};
use canopener_wire::{SDO_RX_BASE, SDO_TX_BASE, crc16_ccitt};

/// The SDO protocol timeout a server uses unless told otherwise.
///
/// CiA 301 leaves the value to the implementation; 1 s is CANopenNode's server default and the
/// suggestion of the reference notes (configurable, about 1 s).
pub const DEFAULT_TIMEOUT: Duration = Duration::from_secs(1);

/// Why a server cannot be built as asked.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SdoServerError {
    /// The default server's COB-IDs exist for node-IDs 1 to 127 only.
    #[error("node-ID {0} is outside 1..=127, so it has no default SDO server")]
    NodeId(u8),
    /// A sub-block has 1 to 127 segments (CiA 301, SDO block download).
    #[error("block size {0} is outside 1..=127")]
    BlockSize(u8),
}

/// Who ended a transfer with an abort.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AbortOrigin {
    /// The client sent "abort SDO transfer".
    Client,
    /// This server sent "abort SDO transfer".
    Server,
}

/// Something the device may want to react to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Event {
    /// A download finished and its value is stored in the dictionary at `key`.
    Written {
        /// The entry that was written.
        key: ObjectKey,
    },
    /// A transfer (or a request) ended with an abort.
    Aborted {
        /// The entry the transfer was about, as the abort frame names it.
        key: ObjectKey,
        /// The abort code.
        code: u32,
        /// Who aborted.
        by: AbortOrigin,
    },
}

/// Checks the device adds to the server's own, called before the dictionary is touched.
///
/// The server checks existence, access type, length and limits through the dictionary. A device
/// adds its own rules here: PDO mapping checks (0604 0041h..0604 0047h), COB-ID rules (0609 0030h),
/// entries that SDO may not reach at all (0601 0000h "unsupported access"), an empty error history
/// (0800 0024h). Returning `Err(code)` aborts the transfer with `code` and leaves the dictionary as
/// it was. `()` is the hook that allows everything.
pub trait SdoHooks {
    /// Called when a download is complete, before `data` is stored at `key`.
    fn check_download(&mut self, key: ObjectKey, data: &[u8], od: &DynamicOd) -> Result<(), u32> {
        let _ = (key, data, od);
        Ok(())
    }

    /// Called when an upload of `key` starts, before the value is read.
    fn check_upload(&mut self, key: ObjectKey, od: &DynamicOd) -> Result<(), u32> {
        let _ = (key, od);
        Ok(())
    }

    /// Stores a download that passed [`SdoHooks::check_download`], in every transfer mode; by
    /// default the dictionary's own write, which applies access, length and limits
    /// ([`DynamicOd::write`]).
    fn write(&mut self, key: ObjectKey, data: &[u8], od: &mut DynamicOd) -> Result<(), OdError> {
        od.write(key, data)
    }
}

/// No additional checks.
impl SdoHooks for () {}

/// Where the server is in a transfer.
#[derive(Debug, Clone, PartialEq, Eq)]
enum State {
    Idle,
    /// Segmented download: waiting for a download segment with toggle `toggle`.
    Download {
        key: ObjectKey,
        toggle: bool,
        size: Option<u32>,
        buf: Vec<u8>,
        limit: Option<usize>,
    },
    /// Segmented upload: waiting for an upload segment request with toggle `toggle`.
    Upload {
        key: ObjectKey,
        toggle: bool,
        data: Vec<u8>,
        offset: usize,
    },
    /// Block download: receiving sub-block segments.
    BlockDownload {
        key: ObjectKey,
        crc: bool,
        size: Option<u32>,
        buf: Vec<u8>,
        limit: Option<usize>,
        /// Sequence number of the last segment received in order in this sub-block (0 = none).
        last_good: u8,
    },
    /// Block download: the last segment is acknowledged, waiting for the end request.
    BlockDownloadEnd {
        key: ObjectKey,
        crc: bool,
        size: Option<u32>,
        buf: Vec<u8>,
    },
    /// Block upload: initiate answered, waiting for "start upload".
    BlockUploadStart {
        key: ObjectKey,
        crc: bool,
        data: Vec<u8>,
        blksize: u8,
    },
    /// Block upload: a sub-block is sent, waiting for its acknowledge.
    BlockUploadAck {
        key: ObjectKey,
        crc: bool,
        data: Vec<u8>,
        /// Offset of the first byte of the sub-block just sent.
        start: usize,
        /// Segments in that sub-block.
        sent: u8,
    },
    /// Block upload: the end frame is sent, waiting for the end response.
    BlockUploadEnd {
        key: ObjectKey,
    },
}

impl State {
    fn key(&self) -> Option<ObjectKey> {
        match self {
            State::Idle => None,
            State::Download { key, .. }
            | State::Upload { key, .. }
            | State::BlockDownload { key, .. }
            | State::BlockDownloadEnd { key, .. }
            | State::BlockUploadStart { key, .. }
            | State::BlockUploadAck { key, .. }
            | State::BlockUploadEnd { key } => Some(*key),
        }
    }
}

/// A sans-IO SDO server for one server channel (CiA 301, "SDO protocols").
///
/// ```
/// use canopener_can::{CanFrame, Instant, StandardId};
/// use canopener_device::sdo_server::SdoServer;
/// use canopener_od::{Access, DataType, DynamicOd, Entry, ObjectKey};
///
/// let mut od = DynamicOd::with_capacity(4);
/// od.insert(Entry::new(ObjectKey::new(0x1017, 0), DataType::UNSIGNED16, Access::Rw, &[0, 0])?)?;
/// let mut server = SdoServer::default_for_node(5)?;
/// let request = CanFrame::new(StandardId::new(0x605).ok_or("id")?, &[0x2B, 0x17, 0x10, 0, 0xE8, 0x03, 0, 0])?;
/// assert!(server.handle_frame(Instant::ZERO, &request, &mut od));
/// let reply = server.poll_transmit().ok_or("no reply")?;
/// assert_eq!(reply.data(), [0x60, 0x17, 0x10, 0, 0, 0, 0, 0]);
/// assert_eq!(od.read(ObjectKey::new(0x1017, 0))?, [0xE8, 0x03]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
pub struct SdoServer {
    rx: CanId,
    tx: CanId,
    timeout: Duration,
    block_size: u8,
    crc_supported: bool,
    downloads_allowed: bool,
    state: State,
    /// When the running transfer times out.
    deadline: Option<Instant>,
    /// Block download only: when the server acknowledges a sub-block on its own because segments
    /// stopped arriving (a lost segment), so the client resends instead of running into the timeout.
    ack_deadline: Option<Instant>,
    transmit: VecDeque<CanFrame>,
    events: VecDeque<Event>,
}

impl SdoServer {
    /// A server that receives requests on `rx` (client→server) and answers on `tx`
    /// (server→client), with the default timeout, block size 127 and CRC support.
    pub fn new(rx: CanId, tx: CanId) -> SdoServer {
        SdoServer {
            rx,
            tx,
            timeout: DEFAULT_TIMEOUT,
            block_size: MAX_BLOCK_SIZE,
            crc_supported: true,
            downloads_allowed: true,
            state: State::Idle,
            deadline: None,
            ack_deadline: None,
            transmit: VecDeque::new(),
            events: VecDeque::new(),
        }
    }

    /// The default server (1200h) of node `node_id`: requests on 600h + node-ID, responses on
    /// 580h + node-ID (CiA 301, pre-defined connection set).
    pub fn default_for_node(node_id: u8) -> Result<SdoServer, SdoServerError> {
        if !(1..=127).contains(&node_id) {
            return Err(SdoServerError::NodeId(node_id));
        }
        let id = |base: u16| StandardId::new(base + u16::from(node_id)).map(CanId::from);
        match (id(SDO_RX_BASE), id(SDO_TX_BASE)) {
            (Some(rx), Some(tx)) => Ok(SdoServer::new(rx, tx)),
            _ => Err(SdoServerError::NodeId(node_id)),
        }
    }

    /// The server with SDO protocol timeout `timeout` (the time allowed between two frames of a
    /// transfer); `Duration::ZERO` disables it.
    pub fn with_timeout(mut self, timeout: Duration) -> SdoServer {
        self.timeout = timeout;
        self
    }

    /// The server offering `block_size` segments per sub-block in block downloads (1..=127).
    pub fn with_block_size(mut self, block_size: u8) -> Result<SdoServer, SdoServerError> {
        if !(1..=MAX_BLOCK_SIZE).contains(&block_size) {
            return Err(SdoServerError::BlockSize(block_size));
        }
        self.block_size = block_size;
        Ok(self)
    }

    /// The server with or without CRC support in block transfers (the "sc" flag).
    pub fn with_crc_supported(mut self, crc_supported: bool) -> SdoServer {
        self.crc_supported = crc_supported;
        self
    }

    /// The CAN-ID requests arrive on (client→server).
    pub fn rx_id(&self) -> CanId {
        self.rx
    }

    /// The CAN-ID responses leave on (server→client).
    pub fn tx_id(&self) -> CanId {
        self.tx
    }

    /// Whether the present device state lets downloads through.
    ///
    /// CiA 301 runs SDO in pre-operational and operational (the device does not route SDO frames in
    /// stopped at all). When the device forbids writes for a reason of its own state, it clears
    /// this flag; every download is then refused with 0800 0022h "data cannot be transferred or
    /// stored to the application because of the present device state". Uploads are unaffected.
    pub fn set_downloads_allowed(&mut self, allowed: bool) {
        self.downloads_allowed = allowed;
    }

    /// Whether a transfer is in progress.
    pub fn is_busy(&self) -> bool {
        self.state != State::Idle
    }

    /// Drops any transfer without a frame, as a communication reset does.
    pub fn reset(&mut self) {
        self.state = State::Idle;
        self.deadline = None;
        self.ack_deadline = None;
        self.transmit.clear();
    }

    /// Handles `frame` if it is addressed to this server (its CAN-ID is `rx`, it is a data frame);
    /// returns whether it was.
    pub fn handle_frame(&mut self, now: Instant, frame: &CanFrame, od: &mut DynamicOd) -> bool {
        self.handle_frame_with(now, frame, od, &mut ())
    }

    /// [`handle_frame`](SdoServer::handle_frame) with the device's extra checks.
    pub fn handle_frame_with(
        &mut self,
        now: Instant,
        frame: &CanFrame,
        od: &mut DynamicOd,
        hooks: &mut dyn SdoHooks,
    ) -> bool {
        if frame.id() != self.rx || frame.is_remote() {
            return false;
        }
        self.handle_request_with(now, frame.data(), od, hooks);
        true
    }

    /// Handles the data of a request already routed to this server.
    ///
    /// Every SDO frame has 8 bytes; a request of any other length is ignored, as CANopenNode does
    /// (the client's timeout then reports it).
    pub fn handle_request(&mut self, now: Instant, data: &[u8], od: &mut DynamicOd) {
        self.handle_request_with(now, data, od, &mut ());
    }

    /// [`handle_request`](SdoServer::handle_request) with the device's extra checks.
    pub fn handle_request_with(
        &mut self,
        now: Instant,
        data: &[u8],
        od: &mut DynamicOd,
        hooks: &mut dyn SdoHooks,
    ) {
        let Ok(data) = <[u8; 8]>::try_from(data) else {
            return;
        };
        self.deadline = None;
        self.ack_deadline = None;
        let state = std::mem::replace(&mut self.state, State::Idle);
        self.state = self.step(state, &data, od, hooks);
        if self.state != State::Idle && self.timeout > Duration::ZERO {
            self.deadline = Some(now + self.timeout);
            if matches!(self.state, State::BlockDownload { .. }) {
                // CANopenNode acknowledges a stalled sub-block after 70 % of the timeout.
                self.ack_deadline = Some(now + self.timeout.mul_f64(0.7));
            }
        }
    }

    /// Lets time pass: a transfer with no frame from the client within the timeout is aborted with
    /// 0504 0000h "SDO protocol timed out" (CiA 301, "Abort SDO transfer").
    pub fn handle_timeout(&mut self, now: Instant) {
        if self.deadline.is_some_and(|deadline| now >= deadline) {
            self.deadline = None;
            self.ack_deadline = None;
            if let Some(key) = self.state.key() {
                self.state = State::Idle;
                self.abort(key, abort::PROTOCOL_TIMED_OUT);
            }
            return;
        }
        if self.ack_deadline.is_some_and(|deadline| now >= deadline) {
            self.ack_deadline = None;
            if let State::BlockDownload { last_good, .. } = &mut self.state {
                // Segments stopped arriving: acknowledge what arrived so the client resends the
                // rest in a new sub-block, which starts again at sequence number 1.
                let ackseq = *last_good;
                *last_good = 0;
                let blksize = self.block_size;
                self.respond(&SdoResponse::BlockDownloadAck { ackseq, blksize });
            }
        }
    }

    /// The next frame to send.
    pub fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.transmit.pop_front()
    }

    /// The next event.
    pub fn poll_event(&mut self) -> Option<Event> {
        self.events.pop_front()
    }

    /// When [`handle_timeout`](SdoServer::handle_timeout) wants to be called next.
    pub fn poll_timeout(&self) -> Option<Instant> {
        match (self.deadline, self.ack_deadline) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    fn step(&mut self, state: State, data: &[u8; 8], od: &mut DynamicOd, hooks: &mut dyn SdoHooks) -> State {
        let command = data[0];
        // "Abort SDO transfer" from the client ends the transfer; no answer (CiA 301). Inside a
        // block download sub-block, D0 is c + sequence number, so only 80h exactly is an abort there
        // (80h would be c = 1 with the invalid sequence number 0).
        let is_abort = match state {
            State::BlockDownload { .. } => command == 0x80,
            _ => command >> 5 == ccs::ABORT,
        };
        if is_abort {
            if let Some(key) = state.key() {
                let code = u32::from_le_bytes([data[4], data[5], data[6], data[7]]);
                self.events.push_back(Event::Aborted {
                    key,
                    code,
                    by: AbortOrigin::Client,
                });
            }
            return State::Idle;
        }
        match state {
            State::Idle => self.initiate(data, od, hooks),
            State::Download {
                key,
                toggle,
                size,
                buf,
                limit,
            } => self.download_segment(data, od, hooks, key, toggle, size, buf, limit),
            State::Upload {
                key,
                toggle,
                data: value,
                offset,
            } => self.upload_segment(data, key, toggle, value, offset),
            State::BlockDownload {
                key,
                crc,
                size,
                buf,
                limit,
                last_good,
            } => self.block_download_segment(data, key, crc, size, buf, limit, last_good),
            State::BlockDownloadEnd { key, crc, size, buf } => {
                self.block_download_end(data, od, hooks, key, crc, size, buf)
            }
            State::BlockUploadStart {
                key,
                crc,
                data: value,
                blksize,
            } => match SdoRequest::parse(data) {
                Ok(SdoRequest::BlockUploadStart) => self.send_sub_block(key, crc, value, 0, blksize),
                _ => self.abort_state(key, abort::COMMAND_SPECIFIER_INVALID),
            },
            State::BlockUploadAck {
                key,
                crc,
                data: value,
                start,
                sent,
            } => self.block_upload_ack(data, key, crc, value, start, sent),
            State::BlockUploadEnd { key } => match SdoRequest::parse(data) {
                Ok(SdoRequest::BlockUploadEndResponse) => State::Idle,
                _ => self.abort_state(key, abort::COMMAND_SPECIFIER_INVALID),
            },
        }
    }

    /// A request while no transfer runs: only the initiate requests are valid.
    fn initiate(&mut self, data: &[u8; 8], od: &mut DynamicOd, hooks: &mut dyn SdoHooks) -> State {
        let frame_key = ObjectKey::new(u16::from_le_bytes([data[1], data[2]]), data[3]);
        match SdoRequest::parse(data) {
            Ok(SdoRequest::InitiateDownload { mux, data: init }) => {
                self.initiate_download(od, hooks, key_of(mux), init)
            }
            Ok(SdoRequest::InitiateUpload { mux }) => match self.read(od, hooks, key_of(mux)) {
                Ok(value) => self.start_upload(key_of(mux), value),
                Err(code) => self.abort_state(key_of(mux), code),
            },
            Ok(SdoRequest::BlockDownloadInitiate {
                mux,
                crc_supported,
                size,
            }) => {
                let key = key_of(mux);
                match self.check_download_start(od, key, size) {
                    Ok(limit) => {
                        let crc = crc_supported && self.crc_supported;
                        self.respond(&SdoResponse::BlockDownloadInitiate {
                            mux,
                            crc_supported: self.crc_supported,
                            blksize: self.block_size,
                        });
                        State::BlockDownload {
                            key,
                            crc,
                            size,
                            buf: Vec::new(),
                            limit,
                            last_good: 0,
                        }
                    }
                    Err(code) => self.abort_state(key, code),
                }
            }
            Ok(SdoRequest::BlockUploadInitiate {
                mux,
                crc_supported,
                blksize,
                pst,
            }) => {
                let key = key_of(mux);
                if !(1..=MAX_BLOCK_SIZE).contains(&blksize) {
                    return self.abort_state(key, abort::INVALID_BLOCK_SIZE);
                }
                let value = match self.read(od, hooks, key) {
                    Ok(value) => value,
                    Err(code) => return self.abort_state(key, code),
                };
                // CiA 301, SDO block upload: with a protocol switch threshold pst > 0 the server
                // may answer with a normal upload when the data is not larger than pst. We switch
                // whenever allowed, as CANopenNode does.
                if pst > 0 && value.len() <= usize::from(pst) {
                    return self.start_upload(key, value);
                }
                let Ok(size) = u32::try_from(value.len()) else {
                    return self.abort_state(key, abort::LENGTH_TOO_HIGH);
                };
                self.respond(&SdoResponse::BlockUploadInitiate {
                    mux,
                    crc_supported: self.crc_supported,
                    size: Some(size),
                });
                State::BlockUploadStart {
                    key,
                    crc: crc_supported && self.crc_supported,
                    data: value,
                    blksize,
                }
            }
            // A segment, a block sub-command other than initiate, or ccs 7 outside a transfer.
            _ => self.abort_state(frame_key, abort::COMMAND_SPECIFIER_INVALID),
        }
    }

    fn initiate_download(
        &mut self,
        od: &mut DynamicOd,
        hooks: &mut dyn SdoHooks,
        key: ObjectKey,
        init: InitiateData,
    ) -> State {
        let mux = Multiplexer::new(key.index, key.sub);
        match init {
            InitiateData::Expedited { data, size_indicated } => {
                if let Err(code) = self.check_download_start(od, key, None) {
                    return self.abort_state(key, code);
                }
                let mut value = data;
                if !size_indicated {
                    // Size not indicated: the frame carries 4 bytes and the receiver knows the real
                    // size. Like CANopenNode we take the entry's size when it is 1..3 bytes.
                    let len = od
                        .get(key)
                        .and_then(|entry| entry.data_type().byte_size())
                        .filter(|&len| (1..4).contains(&len))
                        .unwrap_or(4);
                    value.truncate(len);
                }
                match self.store(od, hooks, key, &value) {
                    Ok(()) => {
                        self.respond(&SdoResponse::InitiateDownload { mux });
                        self.events.push_back(Event::Written { key });
                        State::Idle
                    }
                    Err(code) => self.abort_state(key, code),
                }
            }
            InitiateData::Segmented { size } => match self.check_download_start(od, key, size) {
                Ok(limit) => {
                    self.respond(&SdoResponse::InitiateDownload { mux });
                    State::Download {
                        key,
                        toggle: false,
                        size,
                        buf: Vec::new(),
                        limit,
                    }
                }
                Err(code) => self.abort_state(key, code),
            },
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn download_segment(
        &mut self,
        data: &[u8; 8],
        od: &mut DynamicOd,
        hooks: &mut dyn SdoHooks,
        key: ObjectKey,
        toggle: bool,
        size: Option<u32>,
        mut buf: Vec<u8>,
        limit: Option<usize>,
    ) -> State {
        // CiA 301, "Download SDO segment". A new initiate request here is not served: like
        // CANopenNode (whose behaviour CiA's CCT accepts), any other command aborts the running
        // transfer with 0504 0001h and the client starts again.
        let Ok(SdoRequest::DownloadSegment(segment)) = SdoRequest::parse(data) else {
            return self.abort_state(key, abort::COMMAND_SPECIFIER_INVALID);
        };
        if segment.toggle != toggle {
            return self.abort_state(key, abort::TOGGLE_BIT_NOT_ALTERNATED);
        }
        buf.extend_from_slice(&segment.data);
        if let Some(code) = overflow(&buf, size, limit) {
            return self.abort_state(key, code);
        }
        if !segment.last {
            self.respond(&SdoResponse::DownloadSegment { toggle });
            return State::Download {
                key,
                toggle: !toggle,
                size,
                buf,
                limit,
            };
        }
        if let Some(code) = size_mismatch(buf.len(), size) {
            return self.abort_state(key, code);
        }
        match self.store(od, hooks, key, &buf) {
            Ok(()) => {
                self.respond(&SdoResponse::DownloadSegment { toggle });
                self.events.push_back(Event::Written { key });
                State::Idle
            }
            Err(code) => self.abort_state(key, code),
        }
    }

    /// Answers an upload (or a block upload switched to a normal one): expedited for 1 to 4 bytes,
    /// otherwise segmented with the size indicated (CiA 301, "Initiate SDO upload").
    fn start_upload(&mut self, key: ObjectKey, value: Vec<u8>) -> State {
        let mux = Multiplexer::new(key.index, key.sub);
        if (1..=4).contains(&value.len()) {
            self.respond(&SdoResponse::InitiateUpload {
                mux,
                data: InitiateData::Expedited {
                    data: value,
                    size_indicated: true,
                },
            });
            return State::Idle;
        }
        let Ok(size) = u32::try_from(value.len()) else {
            return self.abort_state(key, abort::LENGTH_TOO_HIGH);
        };
        self.respond(&SdoResponse::InitiateUpload {
            mux,
            data: InitiateData::Segmented { size: Some(size) },
        });
        State::Upload {
            key,
            toggle: false,
            data: value,
            offset: 0,
        }
    }

    fn upload_segment(
        &mut self,
        data: &[u8; 8],
        key: ObjectKey,
        toggle: bool,
        value: Vec<u8>,
        offset: usize,
    ) -> State {
        // CiA 301, "Upload SDO segment"; other commands abort as in the download (see there).
        let Ok(SdoRequest::UploadSegment { toggle: asked }) = SdoRequest::parse(data) else {
            return self.abort_state(key, abort::COMMAND_SPECIFIER_INVALID);
        };
        if asked != toggle {
            return self.abort_state(key, abort::TOGGLE_BIT_NOT_ALTERNATED);
        }
        let end = value.len().min(offset.saturating_add(SEGMENT_DATA_LEN));
        let chunk = value.get(offset..end).unwrap_or_default().to_vec();
        // A 0-byte value is sent as one segment with n = 7 and c = 1.
        let last = end >= value.len();
        self.respond(&SdoResponse::UploadSegment(Segment {
            toggle,
            data: chunk,
            last,
        }));
        if last {
            State::Idle
        } else {
            State::Upload {
                key,
                toggle: !toggle,
                data: value,
                offset: end,
            }
        }
    }

    /// CiA 301, "SDO block download": one segment of a sub-block.
    #[allow(clippy::too_many_arguments)]
    fn block_download_segment(
        &mut self,
        data: &[u8; 8],
        key: ObjectKey,
        crc: bool,
        size: Option<u32>,
        mut buf: Vec<u8>,
        limit: Option<usize>,
        last_good: u8,
    ) -> State {
        let segment = BlockSegment::parse(data);
        if segment.seqno == 0 || segment.seqno > self.block_size {
            return self.abort_state(key, abort::INVALID_SEQUENCE_NUMBER);
        }
        let blksize = self.block_size;
        if segment.seqno != last_good.saturating_add(1) {
            if segment.seqno <= last_good || last_good == 0 {
                // A duplicate, or the rest of a sub-block the client sent before it saw our
                // acknowledge: ignored, as CANopenNode does.
            } else {
                // A gap: segments were lost. Acknowledge the last good one at once; the client
                // resends from there in a new sub-block numbered from 1.
                self.respond(&SdoResponse::BlockDownloadAck {
                    ackseq: last_good,
                    blksize,
                });
                return State::BlockDownload {
                    key,
                    crc,
                    size,
                    buf,
                    limit,
                    last_good: 0,
                };
            }
            return State::BlockDownload {
                key,
                crc,
                size,
                buf,
                limit,
                last_good,
            };
        }
        buf.extend_from_slice(&segment.data);
        // The last segment may be all padding (n = 7 for an empty value); the end request says how
        // much, so only the bytes before it count against the size here.
        let padding = if segment.last { SEGMENT_DATA_LEN } else { 0 };
        let received = buf.len().saturating_sub(padding);
        let check = buf.get(..received).unwrap_or_default();
        if let Some(code) = overflow(check, size, limit) {
            return self.abort_state(key, code);
        }
        if segment.last {
            self.respond(&SdoResponse::BlockDownloadAck {
                ackseq: segment.seqno,
                blksize,
            });
            return State::BlockDownloadEnd { key, crc, size, buf };
        }
        if segment.seqno == blksize {
            self.respond(&SdoResponse::BlockDownloadAck {
                ackseq: segment.seqno,
                blksize,
            });
            return State::BlockDownload {
                key,
                crc,
                size,
                buf,
                limit,
                last_good: 0,
            };
        }
        State::BlockDownload {
            key,
            crc,
            size,
            buf,
            limit,
            last_good: segment.seqno,
        }
    }

    /// CiA 301, "SDO block download", end: drop the padding, check size and CRC, store.
    #[allow(clippy::too_many_arguments)]
    fn block_download_end(
        &mut self,
        data: &[u8; 8],
        od: &mut DynamicOd,
        hooks: &mut dyn SdoHooks,
        key: ObjectKey,
        crc: bool,
        size: Option<u32>,
        mut buf: Vec<u8>,
    ) -> State {
        let Ok(SdoRequest::BlockDownloadEnd {
            unused,
            crc: their_crc,
        }) = SdoRequest::parse(data)
        else {
            return self.abort_state(key, abort::COMMAND_SPECIFIER_INVALID);
        };
        buf.truncate(buf.len().saturating_sub(usize::from(unused)));
        if let Some(code) = size_mismatch(buf.len(), size) {
            return self.abort_state(key, code);
        }
        // The CRC counts only when both sides announced support; otherwise the field is 0 and
        // ignored (CCT "SDO 19" shows a 0 field).
        if crc && crc16_ccitt(&buf) != their_crc {
            return self.abort_state(key, abort::CRC_ERROR);
        }
        match self.store(od, hooks, key, &buf) {
            Ok(()) => {
                self.respond(&SdoResponse::BlockDownloadEndResponse);
                self.events.push_back(Event::Written { key });
                State::Idle
            }
            Err(code) => self.abort_state(key, code),
        }
    }

    /// CiA 301, "SDO block upload": sends segments `1..=blksize` from `start` (fewer at the end).
    fn send_sub_block(
        &mut self,
        key: ObjectKey,
        crc: bool,
        value: Vec<u8>,
        start: usize,
        blksize: u8,
    ) -> State {
        let mut offset = start;
        let mut sent = 0u8;
        while sent < blksize {
            let end = value.len().min(offset.saturating_add(SEGMENT_DATA_LEN));
            let mut chunk = [0u8; SEGMENT_DATA_LEN];
            for (slot, byte) in chunk.iter_mut().zip(value.get(offset..end).unwrap_or_default()) {
                *slot = *byte;
            }
            sent += 1;
            let last = end >= value.len();
            let segment = BlockSegment {
                last,
                seqno: sent,
                data: chunk,
            };
            match segment.encode() {
                Ok(frame) => self.send(frame),
                Err(_) => return self.abort_state(key, abort::GENERAL_ERROR),
            }
            offset = end;
            if last {
                break;
            }
        }
        State::BlockUploadAck {
            key,
            crc,
            data: value,
            start,
            sent,
        }
    }

    fn block_upload_ack(
        &mut self,
        data: &[u8; 8],
        key: ObjectKey,
        crc: bool,
        value: Vec<u8>,
        start: usize,
        sent: u8,
    ) -> State {
        let Ok(SdoRequest::BlockUploadAck { ackseq, blksize }) = SdoRequest::parse(data) else {
            return self.abort_state(key, abort::COMMAND_SPECIFIER_INVALID);
        };
        // An acknowledge of a segment never sent (the CCT's "SDO 27" sends 80h) is an invalid
        // sequence number; the CCT accepts 0504 0003h.
        if ackseq > sent {
            return self.abort_state(key, abort::INVALID_SEQUENCE_NUMBER);
        }
        if !(1..=MAX_BLOCK_SIZE).contains(&blksize) {
            return self.abort_state(key, abort::INVALID_BLOCK_SIZE);
        }
        let next = value
            .len()
            .min(start.saturating_add(usize::from(ackseq) * SEGMENT_DATA_LEN));
        let all_acked = ackseq == sent && next >= value.len();
        if !all_acked {
            // Resend from the first segment not acknowledged, in a sub-block of the new size.
            return self.send_sub_block(key, crc, value, next, blksize);
        }
        let before_last = start.saturating_add(usize::from(sent.saturating_sub(1)) * SEGMENT_DATA_LEN);
        let in_last = value.len().saturating_sub(before_last);
        let unused = u8::try_from(SEGMENT_DATA_LEN.saturating_sub(in_last)).unwrap_or(0);
        let crc = if crc { crc16_ccitt(&value) } else { 0 };
        self.respond(&SdoResponse::BlockUploadEnd { unused, crc });
        State::BlockUploadEnd { key }
    }

    /// Checks that a download of `size` bytes (if known) to `key` may start; returns the most
    /// bytes the entry takes (CiA 301 length codes, as CANopenNode checks them at initiate).
    fn check_download_start(
        &self,
        od: &DynamicOd,
        key: ObjectKey,
        size: Option<u32>,
    ) -> Result<Option<usize>, u32> {
        if !self.downloads_allowed {
            return Err(abort::CANNOT_TRANSFER_DEVICE_STATE);
        }
        let entry = match od.get(key) {
            Some(entry) => entry,
            // `read` tells a missing object from a missing sub-index.
            None => {
                return Err(od
                    .read(key)
                    .err()
                    .map_or(abort::OBJECT_DOES_NOT_EXIST, |e| e.abort_code()));
            }
        };
        if !entry.access().writable() {
            return Err(abort::WRITE_READ_ONLY);
        }
        let data_type = entry.data_type();
        let limit = if data_type.is_variable_length() {
            entry
                .max_len()
                .map(|max| usize::try_from(max).unwrap_or(usize::MAX))
        } else {
            Some(data_type.byte_size().unwrap_or(entry.value().len()))
        };
        if let Some(size) = size.map(|size| usize::try_from(size).unwrap_or(usize::MAX)) {
            if limit.is_some_and(|limit| size > limit) {
                return Err(abort::LENGTH_TOO_HIGH);
            }
            // Strings may be shorter; fixed-size values may not.
            if !data_type.is_variable_length() && limit.is_some_and(|limit| size < limit) {
                return Err(abort::LENGTH_TOO_LOW);
            }
        }
        Ok(limit)
    }

    fn read(&self, od: &DynamicOd, hooks: &mut dyn SdoHooks, key: ObjectKey) -> Result<Vec<u8>, u32> {
        // Existence and access first, so a hook sees only entries the dictionary would serve.
        od.read(key).map_err(|e| e.abort_code())?;
        hooks.check_upload(key, od)?;
        od.read(key).map(<[u8]>::to_vec).map_err(|e| e.abort_code())
    }

    fn store(
        &self,
        od: &mut DynamicOd,
        hooks: &mut dyn SdoHooks,
        key: ObjectKey,
        value: &[u8],
    ) -> Result<(), u32> {
        if !self.downloads_allowed {
            return Err(abort::CANNOT_TRANSFER_DEVICE_STATE);
        }
        hooks.check_download(key, value, od)?;
        hooks.write(key, value, od).map_err(|e: OdError| e.abort_code())
    }

    /// Sends an abort for `key` and ends the transfer.
    fn abort_state(&mut self, key: ObjectKey, code: u32) -> State {
        self.abort(key, code);
        State::Idle
    }

    fn abort(&mut self, key: ObjectKey, code: u32) {
        let mux = Multiplexer::new(key.index, key.sub);
        self.respond(&SdoResponse::Abort { mux, code });
        self.events.push_back(Event::Aborted {
            key,
            code,
            by: AbortOrigin::Server,
        });
    }

    fn respond(&mut self, response: &SdoResponse) {
        match response.encode() {
            Ok(data) => self.send(data),
            // Every response built here encodes; should one not, say so on the bus.
            Err(_) => self.send([0x80, 0, 0, 0, 0x00, 0x00, 0x00, 0x08]),
        }
    }

    fn send(&mut self, data: [u8; 8]) {
        if let Ok(frame) = CanFrame::new(self.tx, &data) {
            self.transmit.push_back(frame);
        }
    }
}

fn key_of(mux: Multiplexer) -> ObjectKey {
    ObjectKey::new(mux.index, mux.sub)
}

/// The abort code when `received` is already more than the indicated size or the entry takes.
fn overflow(received: &[u8], size: Option<u32>, limit: Option<usize>) -> Option<u32> {
    let len = received.len();
    let too_many_for_size = size.is_some_and(|size| u64::try_from(len).unwrap_or(u64::MAX) > u64::from(size));
    if too_many_for_size || limit.is_some_and(|limit| len > limit) {
        Some(abort::LENGTH_TOO_HIGH)
    } else {
        None
    }
}

/// The abort code when a finished transfer carried another number of bytes than it announced.
fn size_mismatch(len: usize, size: Option<u32>) -> Option<u32> {
    let size = usize::try_from(size?).unwrap_or(usize::MAX);
    match len.cmp(&size) {
        std::cmp::Ordering::Greater => Some(abort::LENGTH_TOO_HIGH),
        std::cmp::Ordering::Less => Some(abort::LENGTH_TOO_LOW),
        std::cmp::Ordering::Equal => None,
    }
}

#[cfg(test)]
mod tests {
    use canopener_od::{Access, DataType, Entry};
    use proptest::prelude::*;

    use super::*;

    const RO_U32: ObjectKey = ObjectKey::new(0x1000, 0);
    const STRING_1008: ObjectKey = ObjectKey::new(0x1008, 0);
    const HEARTBEAT: ObjectKey = ObjectKey::new(0x1017, 0);
    const LIMITED_U8: ObjectKey = ObjectKey::new(0x2000, 0);
    const WO_U32: ObjectKey = ObjectKey::new(0x2001, 0);
    const DOMAIN: ObjectKey = ObjectKey::new(0x2002, 0);
    const SHORT_STRING: ObjectKey = ObjectKey::new(0x2003, 0);
    const LIMITED_REAL: ObjectKey = ObjectKey::new(0x2004, 0);
    const UNICODE: ObjectKey = ObjectKey::new(0x2005, 0);
    const RW_U32: ObjectKey = ObjectKey::new(0x2006, 0);

    fn entry(key: ObjectKey, data_type: DataType, access: Access, value: &[u8]) -> Entry {
        match Entry::new(key, data_type, access, value) {
            Ok(entry) => entry,
            Err(err) => panic!("{err}"),
        }
    }

    fn od() -> DynamicOd {
        let limited =
            entry(LIMITED_U8, DataType::UNSIGNED8, Access::Rw, &[50]).with_limits(Some(&[10]), Some(&[100]));
        let real = entry(LIMITED_REAL, DataType::REAL32, Access::Rw, &0f32.to_le_bytes())
            .with_limits(Some(&(-1f32).to_le_bytes()), Some(&1f32.to_le_bytes()));
        let string = entry(SHORT_STRING, DataType::VISIBLE_STRING, Access::Rw, b"").with_max_len(10);
        let (Ok(limited), Ok(real), Ok(string)) = (limited, real, string) else {
            panic!("fixture entries");
        };
        let entries = [
            entry(
                RO_U32,
                DataType::UNSIGNED32,
                Access::Ro,
                &[0x91, 0x01, 0x0F, 0x00],
            ),
            entry(
                STRING_1008,
                DataType::VISIBLE_STRING,
                Access::Const,
                b"CANopenDemoPIC32",
            ),
            entry(HEARTBEAT, DataType::UNSIGNED16, Access::Rw, &[0, 0]),
            entry(
                ObjectKey::new(0x1018, 0),
                DataType::UNSIGNED8,
                Access::Const,
                &[1],
            ),
            entry(
                ObjectKey::new(0x1018, 1),
                DataType::UNSIGNED32,
                Access::Ro,
                &[0x78, 0x56, 0x34, 0x12],
            ),
            limited,
            entry(WO_U32, DataType::UNSIGNED32, Access::Wo, &[0; 4]),
            entry(DOMAIN, DataType::DOMAIN, Access::Rw, b""),
            string,
            real,
            entry(UNICODE, DataType::UNICODE_STRING, Access::Rw, b""),
            entry(RW_U32, DataType::UNSIGNED32, Access::Rw, &[0; 4]),
        ];
        match DynamicOd::from_entries(32, entries) {
            Ok(od) => od,
            Err(err) => panic!("{err}"),
        }
    }

    /// A server for node 5 on virtual time: feed timestamped requests, assert the responses.
    struct Trace {
        server: SdoServer,
        od: DynamicOd,
    }

    impl Trace {
        fn new() -> Trace {
            Trace::with(|server| server)
        }

        fn with(configure: impl FnOnce(SdoServer) -> SdoServer) -> Trace {
            let Ok(server) = SdoServer::default_for_node(5) else {
                panic!("node 5");
            };
            Trace {
                server: configure(server),
                od: od(),
            }
        }

        /// At `ms`, the client sends `request` (on 605h) and the server answers exactly `out` (on 585h).
        fn req(&mut self, ms: u64, request: [u8; 8], out: &[[u8; 8]]) {
            self.req_with(ms, request, out, &mut ());
        }

        fn req_with(&mut self, ms: u64, request: [u8; 8], out: &[[u8; 8]], hooks: &mut dyn SdoHooks) {
            let frame = frame(0x605, &request);
            assert!(
                self.server
                    .handle_frame_with(Instant::from_millis(ms), &frame, &mut self.od, hooks)
            );
            self.expect(ms, &request, out);
        }

        /// At `ms`, time passes; the server sends exactly `out`.
        fn tick(&mut self, ms: u64, out: &[[u8; 8]]) {
            self.server.handle_timeout(Instant::from_millis(ms));
            self.expect(ms, &[], out);
        }

        fn expect(&mut self, ms: u64, request: &[u8], out: &[[u8; 8]]) {
            let mut sent = Vec::new();
            while let Some(frame) = self.server.poll_transmit() {
                assert_eq!(
                    frame.id(),
                    CanId::from(StandardId::new(0x585).unwrap_or(StandardId::ZERO))
                );
                sent.push(frame.data().to_vec());
            }
            let out: Vec<Vec<u8>> = out.iter().map(|data| data.to_vec()).collect();
            assert_eq!(sent, out, "at {ms} ms after {request:02X?}");
        }

        fn events(&mut self) -> Vec<Event> {
            std::iter::from_fn(|| self.server.poll_event()).collect()
        }

        fn value(&self, key: ObjectKey) -> Vec<u8> {
            self.od
                .get(key)
                .map(|entry| entry.value().to_vec())
                .unwrap_or_default()
        }

        /// The abort the server answers `request` with, as a trace step, and its event.
        fn aborts(&mut self, ms: u64, request: [u8; 8], key: ObjectKey, code: u32) {
            self.req(ms, request, &[abort_frame(key, code)]);
            assert_eq!(
                self.events(),
                [Event::Aborted {
                    key,
                    code,
                    by: AbortOrigin::Server
                }]
            );
            assert!(!self.server.is_busy());
        }
    }

    /// One request of a scripted exchange, at a virtual millisecond.
    enum Step {
        /// The client sends the request; the server answers exactly these frames.
        Answers(u64, [u8; 8], Vec<[u8; 8]>),
        /// The client sends the request; the server aborts the transfer of the entry with the code.
        Aborts(u64, [u8; 8], ObjectKey, u32),
    }

    use Step::{Aborts, Answers};

    impl Trace {
        /// Plays the steps in order on this server, checking every answer and abort.
        fn play(&mut self, steps: &[Step]) {
            for step in steps {
                match step {
                    Answers(ms, request, out) => self.req(*ms, *request, out),
                    Aborts(ms, request, key, code) => self.aborts(*ms, *request, *key, *code),
                }
            }
        }
    }

    fn frame(id: u16, data: &[u8]) -> CanFrame {
        let id = StandardId::new(id).unwrap_or(StandardId::ZERO);
        match CanFrame::new(id, data) {
            Ok(frame) => frame,
            Err(err) => panic!("{err}"),
        }
    }

    fn mux(command: u8, key: ObjectKey, d4: [u8; 4]) -> [u8; 8] {
        let [lo, hi] = key.index.to_le_bytes();
        let [a, b, c, d] = d4;
        [command, lo, hi, key.sub, a, b, c, d]
    }

    fn abort_frame(key: ObjectKey, code: u32) -> [u8; 8] {
        mux(0x80, key, code.to_le_bytes())
    }

    fn segment(command: u8, chunk: &[u8]) -> [u8; 8] {
        let mut data = [command, 0, 0, 0, 0, 0, 0, 0];
        for (slot, byte) in data.iter_mut().skip(1).zip(chunk) {
            *slot = *byte;
        }
        data
    }

    fn payload(len: usize) -> Vec<u8> {
        (0..len).map(|i| (i * 7 + 3) as u8).collect()
    }

    const SIZES: [usize; 6] = [0, 1, 4, 7, 8, 889];

    /// A segmented download of `data` to `key` with the size indicated, one request every ms.
    fn segmented_download(t: &mut Trace, key: ObjectKey, data: &[u8]) {
        t.req(
            0,
            mux(0x21, key, (data.len() as u32).to_le_bytes()),
            &[mux(0x60, key, [0; 4])],
        );
        let chunks: Vec<&[u8]> = if data.is_empty() {
            vec![&[]]
        } else {
            data.chunks(7).collect()
        };
        for (i, chunk) in chunks.iter().enumerate() {
            let toggle = (i as u8 % 2) << 4;
            let last = u8::from(i + 1 == chunks.len());
            let n = (7 - chunk.len() as u8) << 1;
            t.req(
                1 + i as u64,
                segment(toggle | n | last, chunk),
                &[[0x20 | toggle, 0, 0, 0, 0, 0, 0, 0]],
            );
        }
    }

    /// A segmented upload of `key`, expecting `data`.
    fn segmented_upload(t: &mut Trace, key: ObjectKey, data: &[u8]) {
        t.req(
            0,
            mux(0x40, key, [0; 4]),
            &[mux(0x41, key, (data.len() as u32).to_le_bytes())],
        );
        let chunks: Vec<&[u8]> = if data.is_empty() {
            vec![&[]]
        } else {
            data.chunks(7).collect()
        };
        for (i, chunk) in chunks.iter().enumerate() {
            let toggle = (i as u8 % 2) << 4;
            let last = u8::from(i + 1 == chunks.len());
            let n = (7 - chunk.len() as u8) << 1;
            t.req(
                1 + i as u64,
                [0x60 | toggle, 0, 0, 0, 0, 0, 0, 0],
                &[segment(toggle | n | last, chunk)],
            );
        }
    }

    /// A block download of `data` to `key` with CRC; the server offers `blksize`.
    fn block_download(t: &mut Trace, key: ObjectKey, data: &[u8], blksize: u8) {
        t.req(
            0,
            mux(0xC6, key, (data.len() as u32).to_le_bytes()),
            &[mux(0xA4, key, [blksize, 0, 0, 0])],
        );
        let chunks: Vec<&[u8]> = if data.is_empty() {
            vec![&[]]
        } else {
            data.chunks(7).collect()
        };
        for (i, chunk) in chunks.iter().enumerate() {
            let seqno = (i % usize::from(blksize)) as u8 + 1;
            let last = i + 1 == chunks.len();
            let ack = [0xA2, seqno, blksize, 0, 0, 0, 0, 0];
            let out: &[[u8; 8]] = if last || seqno == blksize { &[ack] } else { &[] };
            t.req(1 + i as u64, segment((u8::from(last) << 7) | seqno, chunk), out);
        }
        let n = 7 - chunks.last().map_or(0, |chunk| chunk.len()) as u8;
        let [lo, hi] = crc16_ccitt(data).to_le_bytes();
        t.req(
            900,
            [0xC1 | (n << 2), lo, hi, 0, 0, 0, 0, 0],
            &[[0xA1, 0, 0, 0, 0, 0, 0, 0]],
        );
    }

    /// A block upload of `key` with CRC and client block size `blksize`, expecting `data`.
    fn block_upload(t: &mut Trace, key: ObjectKey, data: &[u8], blksize: u8) {
        t.req(
            0,
            mux(0xA4, key, [blksize, 0, 0, 0]),
            &[mux(0xC6, key, (data.len() as u32).to_le_bytes())],
        );
        let chunks: Vec<&[u8]> = if data.is_empty() {
            vec![&[]]
        } else {
            data.chunks(7).collect()
        };
        let mut request = [0xA3, 0, 0, 0, 0, 0, 0, 0];
        for (block, segments) in chunks.chunks(usize::from(blksize)).enumerate() {
            let out: Vec<[u8; 8]> = segments
                .iter()
                .enumerate()
                .map(|(i, chunk)| {
                    let last = block * usize::from(blksize) + i + 1 == chunks.len();
                    segment((u8::from(last) << 7) | (i as u8 + 1), chunk)
                })
                .collect();
            t.req(1 + block as u64, request, &out);
            request = [0xA2, segments.len() as u8, blksize, 0, 0, 0, 0, 0];
        }
        let n = 7 - chunks.last().map_or(0, |chunk| chunk.len()) as u8;
        let [lo, hi] = crc16_ccitt(data).to_le_bytes();
        t.req(900, request, &[[0xC1 | (n << 2), lo, hi, 0, 0, 0, 0, 0]]);
        t.req(901, [0xA1, 0, 0, 0, 0, 0, 0, 0], &[]);
        assert!(!t.server.is_busy());
    }

    // --- expedited ---

    #[test]
    fn expedited_download_of_1_2_and_4_bytes() {
        let mut t = Trace::new();
        t.req(
            0,
            mux(0x2B, HEARTBEAT, [0xE8, 0x03, 0, 0]),
            &[mux(0x60, HEARTBEAT, [0; 4])],
        );
        assert_eq!(t.value(HEARTBEAT), [0xE8, 0x03]);
        t.req(
            1,
            mux(0x2F, LIMITED_U8, [99, 0, 0, 0]),
            &[mux(0x60, LIMITED_U8, [0; 4])],
        );
        assert_eq!(t.value(LIMITED_U8), [99]);
        t.req(2, mux(0x23, RW_U32, [1, 2, 3, 4]), &[mux(0x60, RW_U32, [0; 4])]);
        assert_eq!(t.value(RW_U32), [1, 2, 3, 4]);
        assert_eq!(
            t.events(),
            [
                Event::Written { key: HEARTBEAT },
                Event::Written { key: LIMITED_U8 },
                Event::Written { key: RW_U32 }
            ]
        );
        assert_eq!(t.server.poll_timeout(), None);
    }

    #[test]
    fn expedited_download_without_size_takes_the_entry_size() {
        let mut t = Trace::new();
        t.req(
            0,
            mux(0x22, HEARTBEAT, [0x10, 0x27, 0xAA, 0xBB]),
            &[mux(0x60, HEARTBEAT, [0; 4])],
        );
        assert_eq!(t.value(HEARTBEAT), [0x10, 0x27]);
        t.req(1, mux(0x22, RW_U32, [9, 8, 7, 6]), &[mux(0x60, RW_U32, [0; 4])]);
        assert_eq!(t.value(RW_U32), [9, 8, 7, 6]);
    }

    #[test]
    fn expedited_upload_of_1_and_4_bytes() {
        let mut t = Trace::new();
        t.req(
            0,
            mux(0x40, RO_U32, [0; 4]),
            &[mux(0x43, RO_U32, [0x91, 0x01, 0x0F, 0x00])],
        );
        t.req(
            1,
            mux(0x40, LIMITED_U8, [0; 4]),
            &[mux(0x4F, LIMITED_U8, [50, 0, 0, 0])],
        );
        assert_eq!(t.events(), []);
        assert!(!t.server.is_busy());
    }

    // --- segmented ---

    #[test]
    fn segmented_download_literal_trace_of_8_bytes() {
        let mut t = Trace::new();
        t.req(0, mux(0x21, DOMAIN, [8, 0, 0, 0]), &[mux(0x60, DOMAIN, [0; 4])]);
        assert_eq!(t.server.poll_timeout(), Some(Instant::from_millis(1000)));
        t.req(10, [0x00, 1, 2, 3, 4, 5, 6, 7], &[[0x20, 0, 0, 0, 0, 0, 0, 0]]);
        assert_eq!(t.server.poll_timeout(), Some(Instant::from_millis(1010)));
        // t = 1, n = 6, c = 1
        t.req(20, [0x1D, 8, 0, 0, 0, 0, 0, 0], &[[0x30, 0, 0, 0, 0, 0, 0, 0]]);
        assert_eq!(t.value(DOMAIN), [1, 2, 3, 4, 5, 6, 7, 8]);
        assert_eq!(t.events(), [Event::Written { key: DOMAIN }]);
        assert_eq!(t.server.poll_timeout(), None);
    }

    #[test]
    fn segmented_download_without_size_indicated() {
        let mut t = Trace::new();
        t.req(
            0,
            mux(0x20, SHORT_STRING, [0; 4]),
            &[mux(0x60, SHORT_STRING, [0; 4])],
        );
        t.req(1, segment(0x09, b"abc"), &[[0x20, 0, 0, 0, 0, 0, 0, 0]]);
        assert_eq!(t.value(SHORT_STRING), b"abc");
    }

    #[test]
    fn segmented_download_of_0_1_4_7_8_889_bytes() {
        for len in SIZES {
            let mut t = Trace::new();
            let data = payload(len);
            segmented_download(&mut t, DOMAIN, &data);
            assert_eq!(t.value(DOMAIN), data, "{len} bytes");
            assert_eq!(t.events(), [Event::Written { key: DOMAIN }]);
        }
    }

    #[test]
    fn segmented_upload_literal_trace_of_10_bytes() {
        let mut t = Trace::new();
        t.od.set_value(DOMAIN, b"0123456789").unwrap_or_default();
        t.req(0, mux(0x40, DOMAIN, [0; 4]), &[mux(0x41, DOMAIN, [10, 0, 0, 0])]);
        t.req(1, [0x60, 0, 0, 0, 0, 0, 0, 0], &[segment(0x00, b"0123456")]);
        // 2nd (last) segment, 3 data bytes, t = 1: 19h
        t.req(2, [0x70, 0, 0, 0, 0, 0, 0, 0], &[segment(0x19, b"789")]);
        assert!(!t.server.is_busy());
    }

    #[test]
    fn segmented_upload_of_0_7_8_889_bytes_and_expedited_for_1_and_4() {
        for len in SIZES {
            let mut t = Trace::new();
            let data = payload(len);
            t.od.set_value(DOMAIN, &data).unwrap_or_default();
            if (1..=4).contains(&len) {
                let n = (4 - len as u8) << 2;
                let mut d4 = [0; 4];
                d4[..len].copy_from_slice(&data);
                t.req(0, mux(0x40, DOMAIN, [0; 4]), &[mux(0x43 | n, DOMAIN, d4)]);
            } else {
                segmented_upload(&mut t, DOMAIN, &data);
            }
            assert!(!t.server.is_busy(), "{len} bytes");
        }
    }

    // --- block download ---

    #[test]
    fn block_download_matches_the_cct_trace() {
        // CCT "SDO 25": block download of 1017h = 0000h with CRC.
        let mut t = Trace::new();
        t.od.set_value(HEARTBEAT, &[5, 5]).unwrap_or_default();
        t.req(
            0,
            [0xC6, 0x17, 0x10, 0, 2, 0, 0, 0],
            &[[0xA4, 0x17, 0x10, 0, 0x7F, 0, 0, 0]],
        );
        t.req(
            1,
            [0x81, 0, 0, 0, 0, 0, 0, 0],
            &[[0xA2, 0x01, 0x7F, 0, 0, 0, 0, 0]],
        );
        t.req(2, [0xD5, 0, 0, 0, 0, 0, 0, 0], &[[0xA1, 0, 0, 0, 0, 0, 0, 0]]);
        assert_eq!(t.value(HEARTBEAT), [0, 0]);
        assert_eq!(t.events(), [Event::Written { key: HEARTBEAT }]);
    }

    #[test]
    fn block_download_of_0_1_4_7_8_889_bytes_in_one_and_in_many_sub_blocks() {
        for blksize in [127, 4, 1] {
            for len in SIZES {
                let mut t =
                    Trace::with(|server| server.with_block_size(blksize).unwrap_or_else(|_| panic!()));
                let data = payload(len);
                block_download(&mut t, DOMAIN, &data, blksize);
                assert_eq!(t.value(DOMAIN), data, "{len} bytes, blksize {blksize}");
                assert_eq!(t.events(), [Event::Written { key: DOMAIN }]);
            }
        }
    }

    #[test]
    fn block_download_without_client_crc_ignores_the_crc_field() {
        let mut t = Trace::new();
        t.req(
            0,
            mux(0xC2, RW_U32, [4, 0, 0, 0]),
            &[mux(0xA4, RW_U32, [127, 0, 0, 0])],
        );
        t.req(1, [0x81, 1, 2, 3, 4, 0, 0, 0], &[[0xA2, 1, 127, 0, 0, 0, 0, 0]]);
        t.req(2, [0xCD, 0, 0, 0, 0, 0, 0, 0], &[[0xA1, 0, 0, 0, 0, 0, 0, 0]]);
        assert_eq!(t.value(RW_U32), [1, 2, 3, 4]);
    }

    #[test]
    fn block_download_resends_after_a_bad_sequence_number() {
        let mut t = Trace::with(|server| server.with_block_size(4).unwrap_or_else(|_| panic!()));
        let data = payload(50); // 8 segments
        let seg = |i: usize| data.chunks(7).nth(i).unwrap_or_default();
        t.req(
            0,
            mux(0xC6, DOMAIN, [50, 0, 0, 0]),
            &[mux(0xA4, DOMAIN, [4, 0, 0, 0])],
        );
        t.req(1, segment(1, seg(0)), &[]);
        t.req(2, segment(2, seg(1)), &[]);
        // Segment 3 is lost; 4 arrives: acknowledge 2 at once.
        t.req(3, segment(4, seg(3)), &[[0xA2, 2, 4, 0, 0, 0, 0, 0]]);
        // The client resends from data segment 3 in a new sub-block numbered from 1.
        t.req(4, segment(1, seg(2)), &[]);
        t.req(5, segment(1, seg(2)), &[]); // a duplicate is ignored
        t.req(6, segment(2, seg(3)), &[]);
        t.req(7, segment(3, seg(4)), &[]);
        t.req(8, segment(4, seg(5)), &[[0xA2, 4, 4, 0, 0, 0, 0, 0]]);
        t.req(9, segment(1, seg(6)), &[]);
        t.req(10, segment(0x82, seg(7)), &[[0xA2, 2, 4, 0, 0, 0, 0, 0]]);
        let n = 7 - seg(7).len() as u8;
        let [lo, hi] = crc16_ccitt(&data).to_le_bytes();
        t.req(
            11,
            [0xC1 | (n << 2), lo, hi, 0, 0, 0, 0, 0],
            &[[0xA1, 0, 0, 0, 0, 0, 0, 0]],
        );
        assert_eq!(t.value(DOMAIN), data);
    }

    #[test]
    fn block_download_acknowledges_a_stalled_sub_block_before_the_timeout() {
        let mut t = Trace::new();
        t.req(
            0,
            mux(0xC6, DOMAIN, [20, 0, 0, 0]),
            &[mux(0xA4, DOMAIN, [127, 0, 0, 0])],
        );
        t.req(1, segment(1, b"0123456"), &[]);
        assert_eq!(t.server.poll_timeout(), Some(Instant::from_millis(701)));
        t.tick(700, &[]);
        t.tick(701, &[[0xA2, 1, 127, 0, 0, 0, 0, 0]]);
        assert_eq!(t.server.poll_timeout(), Some(Instant::from_millis(1001)));
        t.req(800, segment(1, b"789abcd"), &[]);
        t.req(801, segment(0x82, b"efghij"), &[[0xA2, 2, 127, 0, 0, 0, 0, 0]]);
        let [lo, hi] = crc16_ccitt(b"0123456789abcdefghij").to_le_bytes();
        t.req(802, [0xC5, lo, hi, 0, 0, 0, 0, 0], &[[0xA1, 0, 0, 0, 0, 0, 0, 0]]);
        assert_eq!(t.value(DOMAIN), b"0123456789abcdefghij");
    }

    // --- block upload ---

    #[test]
    fn block_upload_matches_the_cct_trace() {
        // CCT "SDO 23": block upload of 1008h "CANopenDemoPIC32" with CRC 43F3h.
        let mut t = Trace::new();
        t.req(
            0,
            [0xA4, 0x08, 0x10, 0, 0x14, 0, 0, 0],
            &[[0xC6, 0x08, 0x10, 0, 0x10, 0, 0, 0]],
        );
        t.req(
            1,
            [0xA3, 0, 0, 0, 0, 0, 0, 0],
            &[
                [0x01, 0x43, 0x41, 0x4E, 0x6F, 0x70, 0x65, 0x6E],
                [0x02, 0x44, 0x65, 0x6D, 0x6F, 0x50, 0x49, 0x43],
                [0x83, 0x33, 0x32, 0, 0, 0, 0, 0],
            ],
        );
        t.req(
            2,
            [0xA2, 0x03, 0x14, 0, 0, 0, 0, 0],
            &[[0xD5, 0xF3, 0x43, 0, 0, 0, 0, 0]],
        );
        t.req(3, [0xA1, 0, 0, 0, 0, 0, 0, 0], &[]);
        assert!(!t.server.is_busy());
        assert_eq!(t.server.poll_timeout(), None);
    }

    #[test]
    fn block_upload_without_client_crc_sends_crc_0() {
        // CCT "SDO 19": A0, C6 size 4, A3, one segment, ack, end CD 00 00.
        let mut t = Trace::new();
        t.req(
            0,
            mux(0xA0, RO_U32, [0x14, 0, 0, 0]),
            &[mux(0xC6, RO_U32, [4, 0, 0, 0])],
        );
        t.req(
            1,
            [0xA3, 0, 0, 0, 0, 0, 0, 0],
            &[[0x81, 0x91, 0x01, 0x0F, 0, 0, 0, 0]],
        );
        t.req(2, [0xA2, 1, 0x14, 0, 0, 0, 0, 0], &[[0xCD, 0, 0, 0, 0, 0, 0, 0]]);
        t.req(3, [0xA1, 0, 0, 0, 0, 0, 0, 0], &[]);
    }

    #[test]
    fn block_upload_of_0_1_4_7_8_889_bytes_in_one_and_in_many_sub_blocks() {
        for blksize in [127, 5, 1] {
            for len in SIZES {
                let mut t = Trace::new();
                let data = payload(len);
                t.od.set_value(DOMAIN, &data).unwrap_or_default();
                block_upload(&mut t, DOMAIN, &data, blksize);
            }
        }
    }

    #[test]
    fn block_upload_resends_from_the_acknowledged_segment_with_the_new_block_size() {
        let mut t = Trace::new();
        let data = payload(30); // 5 segments
        t.od.set_value(DOMAIN, &data).unwrap_or_default();
        let seg = |i: usize| data.chunks(7).nth(i).unwrap_or_default();
        t.req(
            0,
            mux(0xA4, DOMAIN, [3, 0, 0, 0]),
            &[mux(0xC6, DOMAIN, [30, 0, 0, 0])],
        );
        t.req(
            1,
            [0xA3, 0, 0, 0, 0, 0, 0, 0],
            &[segment(1, seg(0)), segment(2, seg(1)), segment(3, seg(2))],
        );
        // The client got only segment 1 and asks for sub-blocks of 2 from now on.
        t.req(
            2,
            [0xA2, 1, 2, 0, 0, 0, 0, 0],
            &[segment(1, seg(1)), segment(2, seg(2))],
        );
        t.req(
            3,
            [0xA2, 2, 2, 0, 0, 0, 0, 0],
            &[segment(1, seg(3)), segment(0x82, seg(4))],
        );
        // Nothing of the last sub-block arrived: all of it again.
        t.req(
            4,
            [0xA2, 0, 2, 0, 0, 0, 0, 0],
            &[segment(1, seg(3)), segment(0x82, seg(4))],
        );
        let [lo, hi] = crc16_ccitt(&data).to_le_bytes();
        t.req(
            5,
            [0xA2, 2, 2, 0, 0, 0, 0, 0],
            &[[0xC1 | (5 << 2), lo, hi, 0, 0, 0, 0, 0]],
        );
        t.req(6, [0xA1, 0, 0, 0, 0, 0, 0, 0], &[]);
    }

    #[test]
    fn block_upload_switches_to_a_normal_upload_below_the_threshold() {
        let mut t = Trace::new();
        // pst 4 and 4 bytes: expedited.
        t.req(
            0,
            mux(0xA4, RO_U32, [127, 4, 0, 0]),
            &[mux(0x43, RO_U32, [0x91, 0x01, 0x0F, 0x00])],
        );
        // pst 16 and 16 bytes: segmented.
        t.req(
            1,
            mux(0xA4, STRING_1008, [127, 16, 0, 0]),
            &[mux(0x41, STRING_1008, [16, 0, 0, 0])],
        );
        t.req(2, [0x60, 0, 0, 0, 0, 0, 0, 0], &[segment(0x00, b"CANopen")]);
        t.req(3, [0x70, 0, 0, 0, 0, 0, 0, 0], &[segment(0x10, b"DemoPIC")]);
        t.req(4, [0x60, 0, 0, 0, 0, 0, 0, 0], &[segment(0x0B, b"32")]);
        // pst 15 and 16 bytes: block.
        t.req(
            5,
            mux(0xA4, STRING_1008, [127, 15, 0, 0]),
            &[mux(0xC6, STRING_1008, [16, 0, 0, 0])],
        );
    }

    // --- aborts ---

    #[test]
    fn client_abort_ends_the_transfer_without_an_answer() {
        let mut t = Trace::new();
        t.req(0, mux(0x21, DOMAIN, [20, 0, 0, 0]), &[mux(0x60, DOMAIN, [0; 4])]);
        t.req(1, abort_frame(DOMAIN, 0x0800_0000), &[]);
        assert_eq!(
            t.events(),
            [Event::Aborted {
                key: DOMAIN,
                code: 0x0800_0000,
                by: AbortOrigin::Client
            }]
        );
        assert!(!t.server.is_busy());
        assert_eq!(t.server.poll_timeout(), None);
        // Also inside a block download sub-block, and while idle (ignored).
        t.req(
            2,
            mux(0xC6, DOMAIN, [20, 0, 0, 0]),
            &[mux(0xA4, DOMAIN, [127, 0, 0, 0])],
        );
        t.req(3, segment(1, b"0123456"), &[]);
        t.req(4, abort_frame(DOMAIN, 0x0504_0000), &[]);
        assert!(!t.server.is_busy());
        t.req(5, abort_frame(DOMAIN, 0x0504_0000), &[]);
        assert_eq!(t.events().len(), 1);
    }

    #[test]
    fn abort_0503_0000_toggle_in_download_and_upload() {
        let mut t = Trace::new();
        let toggle = 0x0503_0000;
        t.play(&[
            Answers(
                0,
                mux(0x21, DOMAIN, [14, 0, 0, 0]),
                vec![mux(0x60, DOMAIN, [0; 4])],
            ),
            Aborts(1, segment(0x10, b"0123456"), DOMAIN, toggle),
            Answers(
                2,
                mux(0x21, DOMAIN, [14, 0, 0, 0]),
                vec![mux(0x60, DOMAIN, [0; 4])],
            ),
            Answers(3, segment(0x00, b"0123456"), vec![[0x20, 0, 0, 0, 0, 0, 0, 0]]),
            Aborts(4, segment(0x01, b"0123456"), DOMAIN, toggle),
        ]);
        assert_eq!(t.value(DOMAIN), b"");
        t.play(&[
            Answers(
                5,
                mux(0x40, STRING_1008, [0; 4]),
                vec![mux(0x41, STRING_1008, [16, 0, 0, 0])],
            ),
            Aborts(6, [0x70, 0, 0, 0, 0, 0, 0, 0], STRING_1008, toggle),
        ]);
    }

    /// A request that starts a transfer, the answer, and the entry.
    type Start<'a> = ([u8; 8], &'a [[u8; 8]], ObjectKey);

    #[test]
    fn abort_0504_0000_timeout_in_every_kind_of_transfer() {
        let starts: [Start<'_>; 4] = [
            (
                mux(0x21, DOMAIN, [20, 0, 0, 0]),
                &[mux(0x60, DOMAIN, [0; 4])],
                DOMAIN,
            ),
            (
                mux(0x40, STRING_1008, [0; 4]),
                &[mux(0x41, STRING_1008, [16, 0, 0, 0])],
                STRING_1008,
            ),
            (
                mux(0xC6, RW_U32, [4, 0, 0, 0]),
                &[mux(0xA4, RW_U32, [127, 0, 0, 0])],
                RW_U32,
            ),
            (
                mux(0xA4, STRING_1008, [127, 0, 0, 0]),
                &[mux(0xC6, STRING_1008, [16, 0, 0, 0])],
                STRING_1008,
            ),
        ];
        for (request, answer, key) in starts {
            let mut t = Trace::with(|server| server.with_timeout(Duration::from_millis(500)));
            t.req(100, request, answer);
            assert_eq!(
                t.server.poll_timeout().map(|at| at.as_nanos() / 1_000_000),
                Some(if key == RW_U32 { 450 } else { 600 })
            );
            t.tick(
                599,
                if key == RW_U32 {
                    &[[0xA2, 0, 127, 0, 0, 0, 0, 0]]
                } else {
                    &[]
                },
            );
            t.tick(600, &[abort_frame(key, 0x0504_0000)]);
            assert_eq!(
                t.events(),
                [Event::Aborted {
                    key,
                    code: 0x0504_0000,
                    by: AbortOrigin::Server
                }]
            );
            assert_eq!(t.server.poll_timeout(), None);
            assert!(!t.server.is_busy());
        }
    }

    #[test]
    fn timeout_zero_disables_the_timer() {
        let mut t = Trace::with(|server| server.with_timeout(Duration::ZERO));
        t.req(0, mux(0x21, DOMAIN, [20, 0, 0, 0]), &[mux(0x60, DOMAIN, [0; 4])]);
        assert_eq!(t.server.poll_timeout(), None);
        t.tick(1_000_000, &[]);
        assert!(t.server.is_busy());
    }

    #[test]
    fn abort_0504_0001_bad_command_specifier() {
        let invalid = 0x0504_0001;
        Trace::new().play(&[
            // ccs 7 does not exist.
            Aborts(0, mux(0xE0, RO_U32, [0; 4]), RO_U32, invalid),
            // Segments, block sub-commands and end frames outside a transfer.
            Aborts(1, [0x60, 0x00, 0x10, 0, 0, 0, 0, 0], RO_U32, invalid),
            Aborts(2, [0x00, 0x00, 0x10, 0, 0, 0, 0, 0], RO_U32, invalid),
            Aborts(3, [0xA3, 0x00, 0x10, 0, 0, 0, 0, 0], RO_U32, invalid),
            Aborts(4, [0xC1, 0x00, 0x10, 0, 0, 0, 0, 0], RO_U32, invalid),
            // A new initiate during a segmented transfer aborts the running one (CANopenNode, CCT).
            Answers(
                5,
                mux(0x21, DOMAIN, [20, 0, 0, 0]),
                vec![mux(0x60, DOMAIN, [0; 4])],
            ),
            Aborts(6, mux(0x40, RO_U32, [0; 4]), DOMAIN, invalid),
            Answers(
                7,
                mux(0x40, STRING_1008, [0; 4]),
                vec![mux(0x41, STRING_1008, [16, 0, 0, 0])],
            ),
            Aborts(8, segment(0x00, b"x"), STRING_1008, invalid),
            // Wrong frames in the block states.
            Answers(
                9,
                mux(0xA4, STRING_1008, [127, 0, 0, 0]),
                vec![mux(0xC6, STRING_1008, [16, 0, 0, 0])],
            ),
            Aborts(10, [0xA2, 0, 127, 0, 0, 0, 0, 0], STRING_1008, invalid),
            Answers(
                11,
                mux(0xC6, RW_U32, [4, 0, 0, 0]),
                vec![mux(0xA4, RW_U32, [127, 0, 0, 0])],
            ),
            Answers(
                12,
                [0x81, 1, 2, 3, 4, 0, 0, 0],
                vec![[0xA2, 1, 127, 0, 0, 0, 0, 0]],
            ),
            Aborts(13, [0xA1, 0, 0, 0, 0, 0, 0, 0], RW_U32, invalid),
        ]);
    }

    #[test]
    fn abort_0504_0002_block_size() {
        let block_size = 0x0504_0002;
        Trace::new().play(&[
            // CCT "SDO 26": blksize 128; and blksize 0.
            Aborts(0, mux(0xA4, STRING_1008, [128, 0, 0, 0]), STRING_1008, block_size),
            Aborts(1, mux(0xA4, STRING_1008, [0, 0, 0, 0]), STRING_1008, block_size),
            // A new block size of 0 in the acknowledge.
            Answers(
                2,
                mux(0xA4, STRING_1008, [2, 0, 0, 0]),
                vec![mux(0xC6, STRING_1008, [16, 0, 0, 0])],
            ),
            Answers(
                3,
                [0xA3, 0, 0, 0, 0, 0, 0, 0],
                vec![segment(1, b"CANopen"), segment(2, b"DemoPIC")],
            ),
            Aborts(4, [0xA2, 2, 0, 0, 0, 0, 0, 0], STRING_1008, block_size),
        ]);
        assert!(matches!(
            SdoServer::default_for_node(5).map(|s| s.with_block_size(0)),
            Ok(Err(SdoServerError::BlockSize(0)))
        ));
        assert!(matches!(
            SdoServer::default_for_node(5).map(|s| s.with_block_size(128)),
            Ok(Err(_))
        ));
    }

    #[test]
    fn abort_0504_0003_sequence_number() {
        let sequence = 0x0504_0003;
        Trace::with(|server| server.with_block_size(4).unwrap_or_else(|_| panic!())).play(&[
            // Block download: seqno 0 and seqno above the block size.
            Answers(
                0,
                mux(0xC6, DOMAIN, [20, 0, 0, 0]),
                vec![mux(0xA4, DOMAIN, [4, 0, 0, 0])],
            ),
            Aborts(1, segment(0x00, b"0123456"), DOMAIN, sequence),
            Answers(
                2,
                mux(0xC6, DOMAIN, [20, 0, 0, 0]),
                vec![mux(0xA4, DOMAIN, [4, 0, 0, 0])],
            ),
            Aborts(3, segment(0x05, b"0123456"), DOMAIN, sequence),
            // Block upload: CCT "SDO 27" acknowledges sequence number 80h.
            Answers(
                4,
                mux(0xA4, RO_U32, [0x14, 0, 0, 0]),
                vec![mux(0xC6, RO_U32, [4, 0, 0, 0])],
            ),
            Answers(
                5,
                [0xA3, 0, 0, 0, 0, 0, 0, 0],
                vec![[0x81, 0x91, 0x01, 0x0F, 0, 0, 0, 0]],
            ),
            Aborts(6, [0xA2, 0x80, 0x14, 0, 0, 0, 0, 0], RO_U32, sequence),
        ]);
    }

    #[test]
    fn abort_0504_0004_crc() {
        let mut t = Trace::new();
        t.req(
            0,
            mux(0xC6, RW_U32, [4, 0, 0, 0]),
            &[mux(0xA4, RW_U32, [127, 0, 0, 0])],
        );
        t.req(1, [0x81, 1, 2, 3, 4, 0, 0, 0], &[[0xA2, 1, 127, 0, 0, 0, 0, 0]]);
        let [lo, hi] = (crc16_ccitt(&[1, 2, 3, 4]) ^ 1).to_le_bytes();
        t.aborts(2, [0xCD, lo, hi, 0, 0, 0, 0, 0], RW_U32, 0x0504_0004);
        assert_eq!(t.value(RW_U32), [0; 4]);
        // A server without CRC support ignores the field even when the client supports it.
        let mut t = Trace::with(|server| server.with_crc_supported(false));
        t.req(
            0,
            mux(0xC6, RW_U32, [4, 0, 0, 0]),
            &[mux(0xA0, RW_U32, [127, 0, 0, 0])],
        );
        t.req(1, [0x81, 1, 2, 3, 4, 0, 0, 0], &[[0xA2, 1, 127, 0, 0, 0, 0, 0]]);
        t.req(
            2,
            [0xCD, 0xDE, 0xAD, 0, 0, 0, 0, 0],
            &[[0xA1, 0, 0, 0, 0, 0, 0, 0]],
        );
    }

    /// Refuses SDO access to one entry, as a device does for entries SDO may not reach.
    struct Hidden(ObjectKey);

    impl SdoHooks for Hidden {
        fn check_download(&mut self, key: ObjectKey, _: &[u8], _: &DynamicOd) -> Result<(), u32> {
            if key == self.0 {
                Err(abort::UNSUPPORTED_ACCESS)
            } else {
                Ok(())
            }
        }
        fn check_upload(&mut self, key: ObjectKey, _: &DynamicOd) -> Result<(), u32> {
            if key == self.0 {
                Err(abort::UNSUPPORTED_ACCESS)
            } else {
                Ok(())
            }
        }
    }

    #[test]
    fn abort_0601_0000_unsupported_access_from_a_device_hook() {
        let mut t = Trace::new();
        let mut hooks = Hidden(RW_U32);
        t.req_with(
            0,
            mux(0x40, RW_U32, [0; 4]),
            &[abort_frame(RW_U32, 0x0601_0000)],
            &mut hooks,
        );
        t.req_with(
            1,
            mux(0x23, RW_U32, [1, 2, 3, 4]),
            &[abort_frame(RW_U32, 0x0601_0000)],
            &mut hooks,
        );
        assert_eq!(t.value(RW_U32), [0; 4]);
        // Other entries pass.
        t.req_with(
            2,
            mux(0x40, RO_U32, [0; 4]),
            &[mux(0x43, RO_U32, [0x91, 0x01, 0x0F, 0x00])],
            &mut hooks,
        );
    }

    #[test]
    fn abort_0601_0001_and_0601_0002_access() {
        Trace::new().play(&[
            Aborts(0, mux(0x40, WO_U32, [0; 4]), WO_U32, 0x0601_0001),
            Aborts(1, mux(0xA4, WO_U32, [127, 0, 0, 0]), WO_U32, 0x0601_0001),
            Aborts(2, mux(0x23, RO_U32, [1, 2, 3, 4]), RO_U32, 0x0601_0002),
            Aborts(3, mux(0x21, STRING_1008, [3, 0, 0, 0]), STRING_1008, 0x0601_0002),
            Aborts(4, mux(0xC6, RO_U32, [4, 0, 0, 0]), RO_U32, 0x0601_0002),
            // Writing a write-only entry works.
            Answers(
                5,
                mux(0x23, WO_U32, [1, 0, 0, 0]),
                vec![mux(0x60, WO_U32, [0; 4])],
            ),
        ]);
    }

    #[test]
    fn abort_0602_0000_and_0609_0011_missing_object_or_sub_index() {
        let missing = ObjectKey::new(0x1004, 0);
        let missing_sub = ObjectKey::new(0x1018, 7);
        Trace::new().play(&[
            Aborts(0, mux(0x40, missing, [0; 4]), missing, 0x0602_0000),
            Aborts(1, mux(0x23, missing, [0; 4]), missing, 0x0602_0000),
            Aborts(2, mux(0xC6, missing, [0; 4]), missing, 0x0602_0000),
            Aborts(3, mux(0x40, missing_sub, [0; 4]), missing_sub, 0x0609_0011),
            Aborts(4, mux(0x21, missing_sub, [9, 0, 0, 0]), missing_sub, 0x0609_0011),
            Aborts(
                5,
                mux(0xA4, missing_sub, [127, 0, 0, 0]),
                missing_sub,
                0x0609_0011,
            ),
            // The worked example of the reference: abort for 1004h:00 on 585h.
            Answers(
                6,
                mux(0x40, missing, [0; 4]),
                vec![[0x80, 0x04, 0x10, 0x00, 0x00, 0x00, 0x02, 0x06]],
            ),
        ]);
    }

    #[test]
    fn abort_0607_0010_0012_0013_length() {
        let (too_long, too_short) = (0x0607_0012, 0x0607_0013);
        let [lo, hi] = crc16_ccitt(b"abc").to_le_bytes();
        let mut t = Trace::new();
        t.play(&[
            // 0607 0010: an odd number of bytes for a UNICODE_STRING.
            Aborts(0, mux(0x27, UNICODE, [0x41, 0, 0x42, 0]), UNICODE, 0x0607_0010),
            // 0607 0012: too long, expedited, announced, and by the segments themselves.
            Aborts(1, mux(0x23, HEARTBEAT, [1, 2, 3, 4]), HEARTBEAT, too_long),
            Aborts(2, mux(0x21, HEARTBEAT, [8, 0, 0, 0]), HEARTBEAT, too_long),
            Aborts(3, mux(0xC6, SHORT_STRING, [11, 0, 0, 0]), SHORT_STRING, too_long),
            Answers(
                4,
                mux(0x20, HEARTBEAT, [0; 4]),
                vec![mux(0x60, HEARTBEAT, [0; 4])],
            ),
            Aborts(5, segment(0x04, b"abcde"), HEARTBEAT, too_long),
            Answers(
                6,
                mux(0x21, DOMAIN, [3, 0, 0, 0]),
                vec![mux(0x60, DOMAIN, [0; 4])],
            ),
            Aborts(7, segment(0x06, b"abcd"), DOMAIN, too_long),
            Answers(
                8,
                mux(0xC4, SHORT_STRING, [0; 4]),
                vec![mux(0xA4, SHORT_STRING, [127, 0, 0, 0])],
            ),
            Answers(9, segment(0x01, b"0123456"), vec![]),
            Aborts(10, segment(0x02, b"789abcd"), SHORT_STRING, too_long),
            // 0607 0013: too short, expedited, announced, and a transfer shorter than announced.
            Aborts(11, mux(0x2B, RW_U32, [1, 2, 0, 0]), RW_U32, too_short),
            Aborts(12, mux(0x21, RW_U32, [2, 0, 0, 0]), RW_U32, too_short),
            Answers(
                13,
                mux(0x21, DOMAIN, [9, 0, 0, 0]),
                vec![mux(0x60, DOMAIN, [0; 4])],
            ),
            Aborts(14, segment(0x05, b"abc"), DOMAIN, too_short),
            Answers(
                15,
                mux(0xC6, DOMAIN, [9, 0, 0, 0]),
                vec![mux(0xA4, DOMAIN, [127, 0, 0, 0])],
            ),
            Answers(16, segment(0x81, b"abc"), vec![[0xA2, 1, 127, 0, 0, 0, 0, 0]]),
            Aborts(17, [0xC1 | (4 << 2), lo, hi, 0, 0, 0, 0, 0], DOMAIN, too_short),
        ]);
        assert_eq!(t.value(DOMAIN), b"");
        assert_eq!(t.value(HEARTBEAT), [0, 0]);
    }

    #[test]
    fn abort_0609_0030_0031_0032_limits() {
        let (too_high, too_low) = (0x0609_0031, 0x0609_0032);
        let [lo, hi] = crc16_ccitt(&[0]).to_le_bytes();
        let mut t = Trace::new();
        t.play(&[
            Aborts(0, mux(0x2F, LIMITED_U8, [101, 0, 0, 0]), LIMITED_U8, too_high),
            Aborts(1, mux(0x2F, LIMITED_U8, [9, 0, 0, 0]), LIMITED_U8, too_low),
            Aborts(
                2,
                mux(0x23, LIMITED_REAL, f32::NAN.to_le_bytes()),
                LIMITED_REAL,
                0x0609_0030,
            ),
            // The same checks at the end of a segmented and a block download.
            Answers(
                3,
                mux(0x21, LIMITED_U8, [1, 0, 0, 0]),
                vec![mux(0x60, LIMITED_U8, [0; 4])],
            ),
            Aborts(4, segment(0x0D, &[200]), LIMITED_U8, too_high),
            Answers(
                5,
                mux(0xC6, LIMITED_U8, [1, 0, 0, 0]),
                vec![mux(0xA4, LIMITED_U8, [127, 0, 0, 0])],
            ),
            Answers(6, segment(0x81, &[0]), vec![[0xA2, 1, 127, 0, 0, 0, 0, 0]]),
            Aborts(7, [0xC1 | (6 << 2), lo, hi, 0, 0, 0, 0, 0], LIMITED_U8, too_low),
        ]);
        assert_eq!(t.value(LIMITED_U8), [50]);
    }

    #[test]
    fn abort_0800_0022_device_state_refuses_downloads_only() {
        let refused = 0x0800_0022;
        let mut t = Trace::new();
        t.server.set_downloads_allowed(false);
        t.play(&[
            Aborts(0, mux(0x2B, HEARTBEAT, [1, 0, 0, 0]), HEARTBEAT, refused),
            Aborts(1, mux(0x21, DOMAIN, [1, 0, 0, 0]), DOMAIN, refused),
            Aborts(2, mux(0xC6, DOMAIN, [1, 0, 0, 0]), DOMAIN, refused),
            Answers(
                3,
                mux(0x40, HEARTBEAT, [0; 4]),
                vec![mux(0x4B, HEARTBEAT, [0, 0, 0, 0])],
            ),
        ]);
        // The state changes during a transfer: the final store is refused.
        t.server.set_downloads_allowed(true);
        t.req(4, mux(0x21, DOMAIN, [1, 0, 0, 0]), &[mux(0x60, DOMAIN, [0; 4])]);
        t.server.set_downloads_allowed(false);
        t.aborts(5, segment(0x0D, b"a"), DOMAIN, refused);
        assert_eq!(t.value(DOMAIN), b"");
    }

    // --- routing and robustness ---

    #[test]
    fn routes_only_its_own_data_frames_and_ignores_short_ones() {
        let mut t = Trace::new();
        let mut od = od();
        let other = frame(0x606, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]);
        assert!(!t.server.handle_frame(Instant::ZERO, &other, &mut od));
        let remote = CanFrame::remote(StandardId::new(0x605).unwrap_or(StandardId::ZERO), 8);
        assert!(remote.is_ok_and(|remote| !t.server.handle_frame(Instant::ZERO, &remote, &mut od)));
        let short = frame(0x605, &[0x40, 0x00, 0x10, 0]);
        assert!(t.server.handle_frame(Instant::ZERO, &short, &mut od));
        t.expect(0, &[], &[]);
        assert!(SdoServer::default_for_node(0).is_err());
        assert!(SdoServer::default_for_node(128).is_err());
        let server = SdoServer::default_for_node(127).unwrap_or_else(|_| panic!());
        assert_eq!(server.rx_id().as_raw(), 0x67F);
        assert_eq!(server.tx_id().as_raw(), 0x5FF);
    }

    #[test]
    fn reset_drops_a_transfer_silently() {
        let mut t = Trace::new();
        t.req(
            0,
            mux(0x40, STRING_1008, [0; 4]),
            &[mux(0x41, STRING_1008, [16, 0, 0, 0])],
        );
        t.server.reset();
        assert!(!t.server.is_busy());
        assert_eq!(t.server.poll_timeout(), None);
        t.tick(5000, &[]);
    }

    proptest! {
        #[test]
        fn arbitrary_frames_never_panic_and_never_get_stuck(
            frames in proptest::collection::vec((0u64..2000, proptest::collection::vec(any::<u8>(), 0..=8)), 0..64),
        ) {
            let mut t = Trace::new();
            let mut now = 0;
            for (delay, data) in frames {
                now += delay;
                t.server.handle_request(Instant::from_millis(now), &data, &mut t.od);
                t.server.handle_timeout(Instant::from_millis(now));
                while t.server.poll_transmit().is_some() {}
                while t.server.poll_event().is_some() {}
            }
            // Whatever happened, time ends every transfer.
            for _ in 0..3 {
                if let Some(at) = t.server.poll_timeout() {
                    t.server.handle_timeout(at);
                }
            }
            prop_assert!(!t.server.is_busy());
            prop_assert_eq!(t.server.poll_timeout(), None);
        }
    }
}

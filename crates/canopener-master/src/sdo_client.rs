//! The SDO client of one client channel (CiA 301 §7.2.4, "Service data object"), sans IO.
//!
//! Heads up: read CiA 301 §7.2.4.3 (SDO protocols) and the frame layouts in
//! [`canopener_wire::sdo`] before changing this file. The device side of the same protocols is
//! `canopener_device::sdo_server`; the integration test runs this client against it.
//!
//! One [`SdoClient`] drives one SDO channel: requests leave on the client→server CAN-ID (600h +
//! node-ID for a server's default channel 1200h) and responses arrive on the server→client CAN-ID
//! (580h + node-ID). Other channels (a client parameter record 1280h..12FFh, an additional server
//! 1201h..127Fh) are the same client built with [`SdoClient::with_ids`]. One transfer runs at a time;
//! CiA 301 allows no more on one channel.
//!
//! Implemented, with the CiA 301 protocol names:
//! - SDO upload (§7.2.4.3.5..7): expedited with and without size indication (without it all 4
//!   bytes are taken), segmented with and without size indication, toggle bit, "n" unused bytes;
//! - SDO download (§7.2.4.3.2..4): expedited (1 to 4 bytes) or segmented, size always indicated;
//! - SDO block upload (§7.2.4.3.12..15): CRC and size flags, offered block size, the protocol switch
//!   threshold (a server may answer with a normal upload, which the client then follows), duplicate
//!   segments ignored, a sequence gap or a stalled sub-block answered with an acknowledge of the last
//!   good segment so the server repeats the rest, end with the CRC of [`crc16_ccitt`] (§7.2.4.3.16);
//! - SDO block download (§7.2.4.3.8..11): sub-blocks of the server's block size, retransmission from
//!   `ackseq + 1` when the server acknowledges fewer segments than were sent, the new block size of
//!   every acknowledge, end with the CRC;
//! - Abort SDO transfer (§7.2.4.3.17) in both directions, and the SDO protocol timeout (0504 0000h).
//!
//! Every departure of the server from the protocol ends the transfer with an abort frame carrying
//! the matching CiA 301 code and a [`SdoClientEvent::Failed`]; a silent server ends it after the
//! timeout. Nothing the server sends can make the client panic or wait forever.
//!
//! Feed it with [`SdoClient::handle_frame`] and [`SdoClient::handle_timeout`]; drain it with
//! [`SdoClient::poll_transmit`], [`SdoClient::poll_event`] and [`SdoClient::poll_timeout`].

use std::collections::VecDeque;
use std::fmt;
use std::time::Duration;

use canopener_can::{CanFrame, CanId, Core, Instant, StandardId};
use canopener_wire::abort::{self, abort_code_text};
use canopener_wire::sdo::{
    BlockSegment, InitiateData, MAX_BLOCK_SIZE, Multiplexer, SEGMENT_DATA_LEN, SdoRequest, SdoResponse,
    Segment, scs,
};
use canopener_wire::{SDO_RX_BASE, SDO_TX_BASE, crc16_ccitt};

/// How long the client waits for each answer of the server unless told otherwise: 1 s.
///
/// CiA 301 leaves the value to the implementation; python canopen waits 0.3 s (and retries once),
/// CANopenNode's example client 0.5 s. We wait longer because the time also covers the server's
/// own work: a write to 1010h (store parameters) commits flash before the server answers, which
/// takes hundreds of milliseconds on many devices. And in a block download a server that missed a
/// segment acknowledges on its own only after 70 % of *its* timeout (CANopenNode and our device
/// server: 1 s, so 700 ms); a client that gives up sooner never sees that recovery.
pub const DEFAULT_TIMEOUT: Duration = Duration::from_secs(1);

/// How often a block download sub-block is sent again when the server acknowledges none of its
/// segments (ackseq 0), before the client gives up.
///
/// CiA 301 lets the sender repeat unacknowledged segments without a limit; without one, a server
/// that keeps answering "nothing received" would keep the transfer alive forever.
pub const MAX_FRUITLESS_SUB_BLOCKS: u8 = 3;

/// Why a client cannot be built or a transfer cannot start.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SdoClientError {
    /// A server's default SDO channel exists for node-IDs 1 to 127 only.
    #[error("node-ID {0} is outside 1..=127, so it has no default SDO channel")]
    NodeId(u8),
    /// A transfer is running; CiA 301 allows one transfer per channel at a time.
    #[error("an SDO transfer is already running on this channel")]
    Busy,
    /// Index 0000h is not used in any object dictionary (CiA 301, object dictionary structure).
    #[error("index {0:04X}h is not used in an object dictionary")]
    Index(u16),
    /// An expedited download carries 1 to 4 bytes.
    #[error("an expedited download carries 1 to 4 bytes, got {0}; use a segmented or block download")]
    ExpeditedLength(usize),
    /// SDO transfers announce their size as UNSIGNED32.
    #[error("{0} bytes do not fit the UNSIGNED32 size of an SDO transfer")]
    TooLarge(usize),
}

/// How an upload is started.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum UploadMode {
    /// Initiate SDO upload (§7.2.4.3.6): the server answers expedited or segmented, as it likes.
    Normal,
    /// Initiate SDO block upload (§7.2.4.3.13); with a protocol switch threshold the server may
    /// still answer like a normal upload.
    Block,
}

/// How a download is sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DownloadMode {
    /// Expedited for 1 to 4 bytes, otherwise segmented.
    Auto,
    /// Expedited (§7.2.4.3.3): 1 to 4 bytes in the initiate frame.
    Expedited,
    /// Segmented (§7.2.4.3.4), size indicated: any length, 0 included.
    Segmented,
    /// Block download (§7.2.4.3.8), size indicated: any length, 0 included.
    Block,
}

/// The SDO protocol a transfer actually used.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Protocol {
    /// The value travelled in the initiate frames.
    Expedited,
    /// Toggled 7-byte segments, each answered by the other side.
    Segmented,
    /// Sub-blocks of up to 127 segments, each sub-block acknowledged once.
    Block,
}

/// `expedited`, `segmented` or `block`.
impl fmt::Display for Protocol {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Protocol::Expedited => "expedited",
            Protocol::Segmented => "segmented",
            Protocol::Block => "block",
        })
    }
}

/// What the client does with a response whose DLC is not 8.
///
/// CiA 301 sends every SDO frame with 8 bytes, and CiA's conformance test fails a device that
/// does not; CANopenNode drops shorter frames and python canopen fails on them. Dropping them would
/// turn a wrong answer into a misleading timeout, so by default the client aborts at once and says
/// why. Some older devices do shorten their frames (an expedited answer of 1 byte in a DLC-5
/// frame); [`ShortFrames::Pad`] talks to them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum ShortFrames {
    /// A response with fewer than 8 bytes aborts the transfer with 0504 0001h.
    #[default]
    Abort,
    /// A response with fewer than 8 bytes is read as if padded with zeros, provided it still holds
    /// every byte its command uses (an expedited upload without size indication then carries the
    /// bytes after D3 that are there). Block sub-block segments must still have 8 bytes: the block
    /// protocols postdate the devices that shorten frames.
    Pad,
}

/// What the client reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SdoClientEvent {
    /// A segmented or block transfer moved on: `done` bytes have been confirmed, of `total` if the
    /// size is known. Sent once when the transfer starts (`done` 0), then after every segment
    /// (segmented) or sub-block (block); expedited transfers send none.
    Progress {
        /// Bytes received (upload) or acknowledged by the server (download).
        done: usize,
        /// The size of the value, if known.
        total: Option<usize>,
    },
    /// An upload finished with the value `data`.
    Uploaded {
        /// The object index.
        index: u16,
        /// The sub-index.
        sub: u8,
        /// The value, little-endian as it travels.
        data: Vec<u8>,
        /// The protocol the server answered with.
        protocol: Protocol,
    },
    /// A download finished: the server confirmed the last frame.
    Downloaded {
        /// The object index.
        index: u16,
        /// The sub-index.
        sub: u8,
        /// The protocol used.
        protocol: Protocol,
    },
    /// A transfer ended without success.
    Failed {
        /// The object index.
        index: u16,
        /// The sub-index.
        sub: u8,
        /// Why.
        error: SdoTransferError,
    },
}

/// Why a transfer failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SdoTransferError {
    /// The server sent "abort SDO transfer" (§7.2.4.3.17).
    #[error("SDO abort {code:#010X} from the server: {}", describe_abort(*code))]
    AbortedByServer {
        /// The server's abort code.
        code: u32,
    },
    /// The client sent "abort SDO transfer": the server broke the protocol, or the application
    /// called [`SdoClient::abort`].
    #[error("SDO transfer aborted by the client with {code:#010X} ({}): {reason}", code_text(*code))]
    AbortedByClient {
        /// The abort code sent to the server.
        code: u32,
        /// What went wrong, for people.
        reason: String,
    },
    /// The server did not answer in time; the client sent abort 0504 0000h.
    #[error("timed out after {after:?} waiting for the {waiting_for} (abort 0x05040000 sent to the server)")]
    TimedOut {
        /// The frame the client was waiting for, e.g. "initiate upload response".
        waiting_for: &'static str,
        /// The timeout that ran out.
        after: Duration,
    },
}

impl SdoTransferError {
    /// The abort code that ended the transfer on the bus.
    pub fn abort_code(&self) -> u32 {
        match self {
            SdoTransferError::AbortedByServer { code } | SdoTransferError::AbortedByClient { code, .. } => {
                *code
            }
            SdoTransferError::TimedOut { .. } => abort::PROTOCOL_TIMED_OUT,
        }
    }
}

/// A sans-IO SDO client for one SDO channel (CiA 301 §7.2.4.3, "SDO protocols").
///
/// ```
/// use canopener_can::{CanFrame, Core, Instant, StandardId};
/// use canopener_master::sdo_client::{Protocol, SdoClient, SdoClientEvent, UploadMode};
///
/// let mut client = SdoClient::new(5)?;
/// client.upload(Instant::ZERO, 0x1018, 1, UploadMode::Normal)?;
/// let request = client.poll_transmit().ok_or("no request")?;
/// assert_eq!(request.to_string(), "605#4018100100000000");
///
/// let id = StandardId::new(0x585).ok_or("id")?;
/// let reply = CanFrame::new(id, &[0x43, 0x18, 0x10, 0x01, 0x78, 0x56, 0x34, 0x12])?;
/// assert!(client.accept_frame(Instant::from_millis(1), &reply));
/// assert_eq!(
///     client.poll_event(),
///     Some(SdoClientEvent::Uploaded {
///         index: 0x1018,
///         sub: 1,
///         data: vec![0x78, 0x56, 0x34, 0x12],
///         protocol: Protocol::Expedited,
///     })
/// );
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
pub struct SdoClient {
    request: CanId,
    response: CanId,
    timeout: Duration,
    block_size: u8,
    crc: bool,
    pst: u8,
    short_frames: ShortFrames,
    state: State,
    /// When the running transfer times out.
    deadline: Option<Instant>,
    /// Block upload only: when the client acknowledges a sub-block on its own because segments
    /// stopped arriving, so the server repeats the lost ones instead of both sides timing out.
    stall_deadline: Option<Instant>,
    transmit: VecDeque<CanFrame>,
    events: VecDeque<SdoClientEvent>,
}

impl SdoClient {
    /// A client for the default SDO channel of server node `node_id` (1..=127): requests on
    /// 600h + node-ID, responses on 580h + node-ID (CiA 301, pre-defined connection set).
    pub fn new(node_id: u8) -> Result<SdoClient, SdoClientError> {
        if !(1..=127).contains(&node_id) {
            return Err(SdoClientError::NodeId(node_id));
        }
        let id = |base: u16| StandardId::new(base + u16::from(node_id)).map(CanId::from);
        match (id(SDO_RX_BASE), id(SDO_TX_BASE)) {
            (Some(request), Some(response)) => Ok(SdoClient::with_ids(request, response)),
            _ => Err(SdoClientError::NodeId(node_id)),
        }
    }

    /// A client that sends requests on `request` (client→server) and receives responses on
    /// `response` (server→client), as a client parameter record 1280h..12FFh sets them.
    pub fn with_ids(request: CanId, response: CanId) -> SdoClient {
        SdoClient {
            request,
            response,
            timeout: DEFAULT_TIMEOUT,
            block_size: MAX_BLOCK_SIZE,
            crc: true,
            pst: 0,
            short_frames: ShortFrames::Abort,
            state: State::Idle,
            deadline: None,
            stall_deadline: None,
            transmit: VecDeque::new(),
            events: VecDeque::new(),
        }
    }

    /// The client waiting at most `timeout` for each answer of the server (default
    /// [`DEFAULT_TIMEOUT`], see there why 1 s). `Duration::ZERO` disables the timeout, so a silent
    /// server then stalls the channel until [`SdoClient::abort`].
    pub fn with_timeout(mut self, timeout: Duration) -> SdoClient {
        self.timeout = timeout;
        self
    }

    /// The client offering `block_size` segments per sub-block in block uploads (default 127).
    /// CiA 301 allows 1..=127; 0 counts as 1 and anything above 127 as 127.
    pub fn with_block_size(mut self, block_size: u8) -> SdoClient {
        self.block_size = block_size.clamp(1, MAX_BLOCK_SIZE);
        self
    }

    /// The client offering (and, when the server offers it too, checking) the CRC of block
    /// transfers (the "cc" flag, default on).
    pub fn with_crc(mut self, crc: bool) -> SdoClient {
        self.crc = crc;
        self
    }

    /// The protocol switch threshold `pst` of block uploads (default 0): a server may answer a
    /// block upload of at most `pst` bytes with a normal upload; 0 forbids it (§7.2.4.3.13).
    pub fn with_block_upload_threshold(mut self, pst: u8) -> SdoClient {
        self.pst = pst;
        self
    }

    /// What to do with responses shorter than 8 bytes (default [`ShortFrames::Abort`]).
    pub fn with_short_frames(mut self, short_frames: ShortFrames) -> SdoClient {
        self.short_frames = short_frames;
        self
    }

    /// The CAN-ID requests leave on (client→server).
    pub fn request_id(&self) -> CanId {
        self.request
    }

    /// The CAN-ID responses arrive on (server→client).
    pub fn response_id(&self) -> CanId {
        self.response
    }

    /// Whether a transfer is running.
    pub fn is_busy(&self) -> bool {
        !matches!(self.state, State::Idle)
    }

    /// Starts reading `index`:`sub` (§7.2.4.3.6 initiate SDO upload, or §7.2.4.3.13 initiate SDO
    /// block upload). The result arrives as [`SdoClientEvent::Uploaded`] or
    /// [`SdoClientEvent::Failed`].
    pub fn upload(
        &mut self,
        now: Instant,
        index: u16,
        sub: u8,
        mode: UploadMode,
    ) -> Result<(), SdoClientError> {
        let mux = self.check_start(index, sub)?;
        let block = match mode {
            UploadMode::Normal => {
                self.request(&SdoRequest::InitiateUpload { mux });
                false
            }
            UploadMode::Block => {
                self.request(&SdoRequest::BlockUploadInitiate {
                    mux,
                    crc_supported: self.crc,
                    blksize: self.block_size,
                    pst: self.pst,
                });
                true
            }
        };
        self.state = State::UploadInitiate { mux, block };
        self.arm(now);
        Ok(())
    }

    /// Starts writing `data` to `index`:`sub` (§7.2.4.3.3 initiate SDO download, or §7.2.4.3.9
    /// initiate SDO block download). The result arrives as [`SdoClientEvent::Downloaded`] or
    /// [`SdoClientEvent::Failed`].
    pub fn download(
        &mut self,
        now: Instant,
        index: u16,
        sub: u8,
        data: Vec<u8>,
        mode: DownloadMode,
    ) -> Result<(), SdoClientError> {
        let len = data.len();
        let size = u32::try_from(len).map_err(|_| SdoClientError::TooLarge(len))?;
        let protocol = match mode {
            DownloadMode::Auto if (1..=4).contains(&len) => Protocol::Expedited,
            DownloadMode::Auto | DownloadMode::Segmented => Protocol::Segmented,
            DownloadMode::Expedited if (1..=4).contains(&len) => Protocol::Expedited,
            DownloadMode::Expedited => return Err(SdoClientError::ExpeditedLength(len)),
            DownloadMode::Block => Protocol::Block,
        };
        let mux = self.check_start(index, sub)?;
        self.state = match protocol {
            Protocol::Expedited => {
                self.request(&SdoRequest::InitiateDownload {
                    mux,
                    data: InitiateData::Expedited {
                        data,
                        size_indicated: true,
                    },
                });
                State::DownloadInitiate { mux, segmented: None }
            }
            Protocol::Segmented => {
                self.request(&SdoRequest::InitiateDownload {
                    mux,
                    data: InitiateData::Segmented { size: Some(size) },
                });
                State::DownloadInitiate {
                    mux,
                    segmented: Some(data),
                }
            }
            Protocol::Block => {
                self.request(&SdoRequest::BlockDownloadInitiate {
                    mux,
                    crc_supported: self.crc,
                    size: Some(size),
                });
                State::BlockDownloadInitiate { mux, data }
            }
        };
        self.arm(now);
        Ok(())
    }

    /// Aborts the running transfer with `code` (§7.2.4.3.17): frames of it not yet sent are
    /// dropped, the abort frame is sent and [`SdoTransferError::AbortedByClient`] reported. Does
    /// nothing when no transfer runs.
    pub fn abort(&mut self, _now: Instant, code: u32) {
        let state = std::mem::take(&mut self.state);
        if let Some(mux) = state.mux() {
            self.state = self.client_abort(mux, code, "aborted by the application".to_owned());
        }
    }

    /// Handles `frame` if it arrived on the response CAN-ID (a data frame); returns whether it did.
    /// Frames on that CAN-ID while no transfer runs are ignored.
    pub fn accept_frame(&mut self, now: Instant, frame: &CanFrame) -> bool {
        if frame.id() != self.response || frame.is_remote() {
            return false;
        }
        let state = std::mem::take(&mut self.state);
        let Some(mux) = state.mux() else {
            return true;
        };
        let payload = frame.data();
        let in_block_segments = matches!(state, State::BlockUploadSegments(_));
        self.state = match (payload.len(), self.short_frames) {
            (8, _) => self.step(now, state, &Rx::new(payload)),
            (1..8, ShortFrames::Pad) if !in_block_segments => self.step(now, state, &Rx::new(payload)),
            (len, _) => self.client_abort(
                mux,
                abort::COMMAND_SPECIFIER_INVALID,
                format!("the server answered with DLC {len} ({frame}); CiA 301 SDO frames have 8 bytes"),
            ),
        };
        if !self.is_busy() {
            self.deadline = None;
            self.stall_deadline = None;
        }
        true
    }

    fn check_start(&self, index: u16, sub: u8) -> Result<Multiplexer, SdoClientError> {
        if self.is_busy() {
            return Err(SdoClientError::Busy);
        }
        if index == 0 {
            return Err(SdoClientError::Index(index));
        }
        Ok(Multiplexer::new(index, sub))
    }

    fn step(&mut self, now: Instant, state: State, rx: &Rx) -> State {
        let Some(mux) = state.mux() else {
            return State::Idle;
        };
        // "Abort SDO transfer" ends the transfer in every state. Inside a block upload sub-block
        // D0 is c + sequence number, so only 80h exactly is an abort there (80h would be c = 1 with
        // the invalid sequence number 0).
        let is_abort = match state {
            State::BlockUploadSegments(_) => rx.data[0] == 0x80,
            _ => rx.data[0] >> 5 == scs::ABORT,
        };
        if is_abort {
            if rx.len < 8 {
                return self.client_abort(
                    mux,
                    abort::COMMAND_SPECIFIER_INVALID,
                    format!(
                        "the server sent an abort frame with DLC {}, which cuts off its code",
                        rx.len
                    ),
                );
            }
            let [_, _, _, _, c0, c1, c2, c3] = rx.data;
            let code = u32::from_le_bytes([c0, c1, c2, c3]);
            self.transmit.clear();
            self.fail(mux, SdoTransferError::AbortedByServer { code });
            return State::Idle;
        }
        if let State::BlockUploadSegments(upload) = state {
            return self.block_upload_segment(now, upload, rx);
        }
        let waiting_for = state.waiting_for();
        let response = match self.parse(rx) {
            Ok(response) => response,
            Err(reason) => return self.client_abort(mux, abort::COMMAND_SPECIFIER_INVALID, reason),
        };
        match (state, response) {
            (State::UploadInitiate { block, .. }, response) => {
                self.upload_initiated(now, mux, block, response, rx)
            }
            (State::UploadSegments(upload), SdoResponse::UploadSegment(segment)) => {
                self.upload_segment(now, upload, segment)
            }
            (State::DownloadInitiate { segmented, .. }, SdoResponse::InitiateDownload { mux: answered }) => {
                if answered != mux {
                    return self.wrong_mux(mux, answered);
                }
                match segmented {
                    None => self.finish(SdoClientEvent::Downloaded {
                        index: mux.index,
                        sub: mux.sub,
                        protocol: Protocol::Expedited,
                    }),
                    Some(data) => {
                        self.progress(0, Some(data.len()));
                        self.send_download_segment(
                            now,
                            Download {
                                mux,
                                data,
                                end: 0,
                                toggle: false,
                            },
                        )
                    }
                }
            }
            (State::DownloadSegments(download), SdoResponse::DownloadSegment { toggle }) => {
                self.download_segment_confirmed(now, download, toggle)
            }
            (
                State::BlockDownloadInitiate { data, .. },
                SdoResponse::BlockDownloadInitiate {
                    mux: answered,
                    crc_supported,
                    blksize,
                },
            ) => {
                if answered != mux {
                    return self.wrong_mux(mux, answered);
                }
                if !(1..=MAX_BLOCK_SIZE).contains(&blksize) {
                    return self.bad_block_size(mux, blksize);
                }
                self.progress(0, Some(data.len()));
                let download = BlockDownload {
                    mux,
                    data,
                    crc: self.crc && crc_supported,
                    start: 0,
                    sent: 0,
                    last_sent: false,
                    fruitless: 0,
                };
                self.send_sub_block(now, download, blksize)
            }
            (State::BlockDownloadAck(download), SdoResponse::BlockDownloadAck { ackseq, blksize }) => {
                self.block_download_acked(now, download, ackseq, blksize)
            }
            (State::BlockDownloadEnd { .. }, SdoResponse::BlockDownloadEndResponse) => {
                self.finish(SdoClientEvent::Downloaded {
                    index: mux.index,
                    sub: mux.sub,
                    protocol: Protocol::Block,
                })
            }
            (State::BlockUploadEnd(upload), SdoResponse::BlockUploadEnd { unused, crc }) => {
                self.block_upload_end(upload, unused, crc)
            }
            (_, _) => self.unexpected(mux, waiting_for, rx),
        }
    }

    /// §7.2.4.3.6 and §7.2.4.3.13: the answer to an initiate (block) upload request.
    fn upload_initiated(
        &mut self,
        now: Instant,
        mux: Multiplexer,
        block: bool,
        response: SdoResponse,
        rx: &Rx,
    ) -> State {
        match response {
            SdoResponse::BlockUploadInitiate {
                mux: answered,
                crc_supported,
                size,
            } if block => {
                if answered != mux {
                    return self.wrong_mux(mux, answered);
                }
                let size = size.map(usize_from);
                self.request(&SdoRequest::BlockUploadStart);
                self.progress(0, size);
                self.arm(now);
                State::BlockUploadSegments(BlockUpload {
                    mux,
                    crc: self.crc && crc_supported,
                    size,
                    buf: Vec::with_capacity(initial_capacity(size)),
                    last_good: 0,
                    resync: false,
                })
            }
            // With a protocol switch threshold the server may answer a block upload like a
            // normal one (§7.2.4.3.13). A server that switches for a value larger than pst still
            // delivers it correctly, so only a switch that pst 0 forbids is an error.
            SdoResponse::InitiateUpload { mux: answered, data } if !block || self.pst > 0 => {
                if answered != mux {
                    return self.wrong_mux(mux, answered);
                }
                match data {
                    InitiateData::Expedited {
                        mut data,
                        size_indicated,
                    } => {
                        if !size_indicated {
                            // No size: the value is all of D4..D7 (what a short frame has of them).
                            data.truncate(rx.len.saturating_sub(4));
                        }
                        self.finish(SdoClientEvent::Uploaded {
                            index: mux.index,
                            sub: mux.sub,
                            data,
                            protocol: Protocol::Expedited,
                        })
                    }
                    InitiateData::Segmented { size } => {
                        let size = size.map(usize_from);
                        self.request(&SdoRequest::UploadSegment { toggle: false });
                        self.progress(0, size);
                        self.arm(now);
                        State::UploadSegments(Upload {
                            mux,
                            toggle: false,
                            size,
                            buf: Vec::with_capacity(initial_capacity(size)),
                        })
                    }
                }
            }
            SdoResponse::InitiateUpload { .. } => self.client_abort(
                mux,
                abort::COMMAND_SPECIFIER_INVALID,
                format!(
                    "the server answered the block upload with a normal upload ({}) although the protocol switch threshold is 0",
                    hex(&rx.data)
                ),
            ),
            _ => {
                let waiting_for = if block {
                    "block upload initiate response"
                } else {
                    "initiate upload response"
                };
                self.unexpected(mux, waiting_for, rx)
            }
        }
    }

    /// §7.2.4.3.7: one segment of a segmented upload.
    fn upload_segment(&mut self, now: Instant, mut upload: Upload, segment: Segment) -> State {
        let mux = upload.mux;
        if segment.toggle != upload.toggle {
            return self.client_abort(
                mux,
                abort::TOGGLE_BIT_NOT_ALTERNATED,
                toggle_reason(segment.toggle, upload.toggle),
            );
        }
        upload.buf.extend_from_slice(&segment.data);
        let len = upload.buf.len();
        if let Some(size) = upload.size
            && (len > size || (segment.last && len != size))
        {
            return self.length_mismatch(mux, len, size);
        }
        self.progress(len, upload.size);
        if segment.last {
            return self.finish(SdoClientEvent::Uploaded {
                index: mux.index,
                sub: mux.sub,
                data: upload.buf,
                protocol: Protocol::Segmented,
            });
        }
        upload.toggle = !upload.toggle;
        self.request(&SdoRequest::UploadSegment {
            toggle: upload.toggle,
        });
        self.arm(now);
        State::UploadSegments(upload)
    }

    /// §7.2.4.3.4: sends the segment that starts at `download.end`.
    fn send_download_segment(&mut self, now: Instant, mut download: Download) -> State {
        let start = download.end;
        let end = download.data.len().min(start.saturating_add(SEGMENT_DATA_LEN));
        let chunk = download.data.get(start..end).unwrap_or_default().to_vec();
        // A 0-byte value is one segment with n = 7 and c = 1.
        let last = end >= download.data.len();
        self.request(&SdoRequest::DownloadSegment(Segment {
            toggle: download.toggle,
            data: chunk,
            last,
        }));
        download.end = end;
        self.arm(now);
        State::DownloadSegments(download)
    }

    fn download_segment_confirmed(&mut self, now: Instant, mut download: Download, toggle: bool) -> State {
        let mux = download.mux;
        if toggle != download.toggle {
            return self.client_abort(
                mux,
                abort::TOGGLE_BIT_NOT_ALTERNATED,
                toggle_reason(toggle, download.toggle),
            );
        }
        let len = download.data.len();
        self.progress(download.end, Some(len));
        if download.end >= len {
            return self.finish(SdoClientEvent::Downloaded {
                index: mux.index,
                sub: mux.sub,
                protocol: Protocol::Segmented,
            });
        }
        download.toggle = !download.toggle;
        self.send_download_segment(now, download)
    }

    /// §7.2.4.3.10: sends segments `1..=blksize` from `download.start` (fewer at the end).
    fn send_sub_block(&mut self, now: Instant, mut download: BlockDownload, blksize: u8) -> State {
        let len = download.data.len();
        let mut offset = download.start;
        let mut sent = 0u8;
        let mut last = false;
        while sent < blksize && !last {
            let end = len.min(offset.saturating_add(SEGMENT_DATA_LEN));
            let mut chunk = [0u8; SEGMENT_DATA_LEN];
            for (slot, byte) in chunk
                .iter_mut()
                .zip(download.data.get(offset..end).unwrap_or_default())
            {
                *slot = *byte;
            }
            sent += 1;
            last = end >= len;
            let segment = BlockSegment {
                last,
                seqno: sent,
                data: chunk,
            };
            match segment.encode() {
                Ok(bytes) => self.send(bytes),
                // `sent` is 1..=blksize and blksize 1..=127 was checked, so this cannot fail.
                Err(err) => return self.client_abort(download.mux, abort::GENERAL_ERROR, err.to_string()),
            }
            offset = end;
        }
        download.sent = sent;
        download.last_sent = last;
        self.arm(now);
        State::BlockDownloadAck(download)
    }

    /// §7.2.4.3.10: the server's acknowledge of a sub-block.
    fn block_download_acked(
        &mut self,
        now: Instant,
        mut download: BlockDownload,
        ackseq: u8,
        blksize: u8,
    ) -> State {
        let mux = download.mux;
        if ackseq > download.sent {
            return self.client_abort(
                mux,
                abort::INVALID_SEQUENCE_NUMBER,
                format!(
                    "the server acknowledged segment {ackseq} of a sub-block of {} segments",
                    download.sent
                ),
            );
        }
        if !(1..=MAX_BLOCK_SIZE).contains(&blksize) {
            return self.bad_block_size(mux, blksize);
        }
        let len = download.data.len();
        if ackseq == download.sent && download.last_sent {
            self.progress(len, Some(len));
            // §7.2.4.3.11: n counts the bytes of the last segment that carry no data.
            let last_start = download
                .start
                .saturating_add(usize::from(download.sent.saturating_sub(1)) * SEGMENT_DATA_LEN);
            let in_last = len.saturating_sub(last_start);
            let unused = u8::try_from(SEGMENT_DATA_LEN.saturating_sub(in_last)).unwrap_or(0);
            let crc = if download.crc {
                crc16_ccitt(&download.data)
            } else {
                0
            };
            self.request(&SdoRequest::BlockDownloadEnd { unused, crc });
            self.arm(now);
            return State::BlockDownloadEnd { mux };
        }
        if ackseq == 0 {
            download.fruitless = download.fruitless.saturating_add(1);
            if download.fruitless > MAX_FRUITLESS_SUB_BLOCKS {
                return self.client_abort(
                    mux,
                    abort::GENERAL_ERROR,
                    format!(
                        "the server acknowledged no segment of {} sub-blocks in a row",
                        download.fruitless
                    ),
                );
            }
        } else {
            download.fruitless = 0;
        }
        // Segments after `ackseq` were lost (or the sub-block was complete): CiA 301 has the
        // client continue with the segment after `ackseq`, in a new sub-block numbered from 1.
        download.start = len.min(
            download
                .start
                .saturating_add(usize::from(ackseq) * SEGMENT_DATA_LEN),
        );
        self.progress(download.start, Some(len));
        self.send_sub_block(now, download, blksize)
    }

    /// §7.2.4.3.14: one segment of a block upload sub-block.
    fn block_upload_segment(&mut self, now: Instant, mut upload: BlockUpload, rx: &Rx) -> State {
        let segment = BlockSegment::parse(&rx.data);
        let mux = upload.mux;
        if segment.seqno == 0 || segment.seqno > self.block_size {
            return self.client_abort(
                mux,
                abort::INVALID_SEQUENCE_NUMBER,
                format!(
                    "the server sent segment {} in a sub-block of at most {} ({})",
                    segment.seqno,
                    self.block_size,
                    hex(&rx.data)
                ),
            );
        }
        if upload.resync {
            // After acknowledging a gap, the rest of the broken sub-block may still arrive; the
            // repetition starts at sequence number 1.
            if segment.seqno != 1 {
                return State::BlockUploadSegments(upload);
            }
            upload.resync = false;
        }
        if segment.seqno <= upload.last_good {
            // A duplicate: ignored, as CANopenNode and python canopen do.
            return State::BlockUploadSegments(upload);
        }
        if segment.seqno != upload.last_good.saturating_add(1) {
            self.ack_gap(&mut upload);
            return State::BlockUploadSegments(upload);
        }
        upload.buf.extend_from_slice(&segment.data);
        upload.last_good = segment.seqno;
        if let Some(size) = upload.size {
            // The last segment may carry up to 7 padding bytes; more than that is too much data.
            let most = size
                .div_ceil(SEGMENT_DATA_LEN)
                .max(1)
                .saturating_mul(SEGMENT_DATA_LEN);
            if upload.buf.len() > most {
                return self.length_mismatch(mux, upload.buf.len(), size);
            }
        }
        self.arm(now);
        if segment.last || segment.seqno == self.block_size {
            self.request(&SdoRequest::BlockUploadAck {
                ackseq: segment.seqno,
                blksize: self.block_size,
            });
            upload.last_good = 0;
            self.stall_deadline = None;
            let done = upload
                .size
                .map_or(upload.buf.len(), |size| size.min(upload.buf.len()));
            if segment.last {
                return State::BlockUploadEnd(upload);
            }
            self.progress(done, upload.size);
        } else {
            self.stall_deadline = (self.timeout > Duration::ZERO).then(|| now + self.timeout / 10 * 7);
        }
        State::BlockUploadSegments(upload)
    }

    /// Acknowledges the segments received in order so far; the server repeats the rest in a new
    /// sub-block numbered from 1 (§7.2.4.3.14). The deadline is not renewed: a server that keeps
    /// sending the wrong segments still times out.
    fn ack_gap(&mut self, upload: &mut BlockUpload) {
        self.request(&SdoRequest::BlockUploadAck {
            ackseq: upload.last_good,
            blksize: self.block_size,
        });
        upload.last_good = 0;
        upload.resync = true;
        self.stall_deadline = None;
    }

    /// §7.2.4.3.15: drop the padding, check size and CRC, confirm.
    fn block_upload_end(&mut self, mut upload: BlockUpload, unused: u8, their_crc: u16) -> State {
        let mux = upload.mux;
        let len = upload.buf.len().saturating_sub(usize::from(unused));
        upload.buf.truncate(len);
        if let Some(size) = upload.size
            && len != size
        {
            return self.length_mismatch(mux, len, size);
        }
        // The CRC counts only when both sides announced support; otherwise the field is 0.
        if upload.crc {
            let ours = crc16_ccitt(&upload.buf);
            if ours != their_crc {
                return self.client_abort(
                    mux,
                    abort::CRC_ERROR,
                    format!("the server's CRC is {their_crc:04X}h, the data received has {ours:04X}h"),
                );
            }
        }
        self.request(&SdoRequest::BlockUploadEndResponse);
        self.progress(len, upload.size);
        self.finish(SdoClientEvent::Uploaded {
            index: mux.index,
            sub: mux.sub,
            data: upload.buf,
            protocol: Protocol::Block,
        })
    }

    /// The response in `rx`, or why it is not one.
    fn parse(&self, rx: &Rx) -> Result<SdoResponse, String> {
        let response = SdoResponse::parse(&rx.data)
            .map_err(|err| format!("the server sent {}: {err}", hex(rx.received())))?;
        let needed = needed_len(&response);
        if rx.len < needed {
            return Err(format!(
                "the server sent {} with DLC {}, but that frame needs {needed} bytes",
                hex(rx.received()),
                rx.len
            ));
        }
        Ok(response)
    }

    fn unexpected(&mut self, mux: Multiplexer, waiting_for: &str, rx: &Rx) -> State {
        self.client_abort(
            mux,
            abort::COMMAND_SPECIFIER_INVALID,
            format!(
                "expected the {waiting_for}, the server sent {}",
                hex(rx.data.get(..rx.len).unwrap_or_default())
            ),
        )
    }

    /// An answer for another entry: someone else uses the channel, or the server is confused.
    /// CANopenNode's client aborts with 0604 0043h "general parameter incompatibility" here.
    fn wrong_mux(&mut self, mux: Multiplexer, answered: Multiplexer) -> State {
        self.client_abort(
            mux,
            abort::PARAMETER_INCOMPATIBLE,
            format!("the server answered for {answered} instead of {mux}"),
        )
    }

    fn bad_block_size(&mut self, mux: Multiplexer, blksize: u8) -> State {
        self.client_abort(
            mux,
            abort::INVALID_BLOCK_SIZE,
            format!("the server asked for block size {blksize}, CiA 301 allows 1 to 127"),
        )
    }

    fn length_mismatch(&mut self, mux: Multiplexer, received: usize, size: usize) -> State {
        self.client_abort(
            mux,
            abort::LENGTH_MISMATCH,
            format!("the server announced {size} bytes and delivered {received}"),
        )
    }

    /// Sends an abort for `mux` with `code`, reports it, and ends the transfer.
    fn client_abort(&mut self, mux: Multiplexer, code: u32, reason: String) -> State {
        self.end_with_abort(mux, code);
        self.fail(mux, SdoTransferError::AbortedByClient { code, reason });
        State::Idle
    }

    /// Drops the frames of the transfer not sent yet (the rest of a sub-block) and sends the abort.
    fn end_with_abort(&mut self, mux: Multiplexer, code: u32) {
        self.transmit.clear();
        self.request(&SdoRequest::Abort { mux, code });
        self.deadline = None;
        self.stall_deadline = None;
    }

    fn fail(&mut self, mux: Multiplexer, error: SdoTransferError) {
        self.events.push_back(SdoClientEvent::Failed {
            index: mux.index,
            sub: mux.sub,
            error,
        });
    }

    fn finish(&mut self, event: SdoClientEvent) -> State {
        self.events.push_back(event);
        State::Idle
    }

    fn progress(&mut self, done: usize, total: Option<usize>) {
        self.events.push_back(SdoClientEvent::Progress { done, total });
    }

    fn arm(&mut self, now: Instant) {
        self.deadline = (self.timeout > Duration::ZERO).then(|| now + self.timeout);
    }

    fn request(&mut self, request: &SdoRequest) {
        match request.encode() {
            Ok(bytes) => self.send(bytes),
            // Every request built here encodes (lengths are checked before); should one not, tell
            // the server the transfer is over rather than go silent.
            Err(_) => self.send([0x80, 0, 0, 0, 0x00, 0x00, 0x00, 0x08]),
        }
    }

    fn send(&mut self, bytes: [u8; 8]) {
        if let Ok(frame) = CanFrame::new(self.request, &bytes) {
            self.transmit.push_back(frame);
        }
    }
}

impl Core for SdoClient {
    type Event = SdoClientEvent;

    fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
        self.accept_frame(now, frame);
    }

    /// Lets time pass: without an answer within the timeout the transfer is aborted with
    /// 0504 0000h "SDO protocol timed out" (§7.2.4.3.17); a stalled block upload sub-block is
    /// acknowledged first (see [`SdoClient::poll_timeout`]).
    fn handle_timeout(&mut self, now: Instant) {
        if self.deadline.is_some_and(|deadline| now >= deadline) {
            let state = std::mem::take(&mut self.state);
            if let Some(mux) = state.mux() {
                let waiting_for = state.waiting_for();
                self.end_with_abort(mux, abort::PROTOCOL_TIMED_OUT);
                self.fail(
                    mux,
                    SdoTransferError::TimedOut {
                        waiting_for,
                        after: self.timeout,
                    },
                );
            }
            self.deadline = None;
            self.stall_deadline = None;
            return;
        }
        if self.stall_deadline.is_some_and(|deadline| now >= deadline) {
            self.stall_deadline = None;
            if let State::BlockUploadSegments(mut upload) = std::mem::take(&mut self.state) {
                // Segments stopped before the sub-block was complete (the last ones were lost):
                // acknowledge what arrived, so the server repeats the rest in a new sub-block.
                self.ack_gap(&mut upload);
                self.state = State::BlockUploadSegments(upload);
            }
        }
    }

    /// The next frame to send on the request CAN-ID.
    fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.transmit.pop_front()
    }

    /// The next event.
    fn poll_event(&mut self) -> Option<Self::Event> {
        self.events.pop_front()
    }

    /// When [`handle_timeout`](SdoClient::handle_timeout) wants to be called next: the timeout of
    /// the running transfer, or earlier in a block upload whose segments stopped arriving (after
    /// 70 % of the timeout, as CANopenNode's server does for block downloads).
    fn poll_timeout(&self) -> Option<Instant> {
        match (self.deadline, self.stall_deadline) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }
}

/// Where the client is in a transfer; every state but `Idle` waits for a frame of the server.
#[derive(Debug, Clone, Default)]
enum State {
    #[default]
    Idle,
    /// The initiate (block) upload request is sent.
    UploadInitiate { mux: Multiplexer, block: bool },
    /// Segmented upload: an upload segment request is sent.
    UploadSegments(Upload),
    /// The initiate download request is sent; `segmented` holds the value still to send.
    DownloadInitiate {
        mux: Multiplexer,
        segmented: Option<Vec<u8>>,
    },
    /// Segmented download: a segment is sent.
    DownloadSegments(Download),
    /// The initiate block download request is sent.
    BlockDownloadInitiate { mux: Multiplexer, data: Vec<u8> },
    /// Block download: a sub-block is sent.
    BlockDownloadAck(BlockDownload),
    /// Block download: the end request is sent.
    BlockDownloadEnd { mux: Multiplexer },
    /// Block upload: receiving sub-block segments.
    BlockUploadSegments(BlockUpload),
    /// Block upload: the last segment is acknowledged, the end frame is due.
    BlockUploadEnd(BlockUpload),
}

impl State {
    fn mux(&self) -> Option<Multiplexer> {
        match self {
            State::Idle => None,
            State::UploadInitiate { mux, .. }
            | State::DownloadInitiate { mux, .. }
            | State::BlockDownloadInitiate { mux, .. }
            | State::BlockDownloadEnd { mux } => Some(*mux),
            State::UploadSegments(upload) => Some(upload.mux),
            State::DownloadSegments(download) => Some(download.mux),
            State::BlockDownloadAck(download) => Some(download.mux),
            State::BlockUploadSegments(upload) | State::BlockUploadEnd(upload) => Some(upload.mux),
        }
    }

    /// The frame this state waits for, as [`SdoTransferError::TimedOut`] names it.
    fn waiting_for(&self) -> &'static str {
        match self {
            State::Idle => "nothing",
            State::UploadInitiate { block: false, .. } => "initiate upload response",
            State::UploadInitiate { block: true, .. } => "block upload initiate response",
            State::UploadSegments(_) => "upload segment response",
            State::DownloadInitiate { .. } => "initiate download response",
            State::DownloadSegments(_) => "download segment response",
            State::BlockDownloadInitiate { .. } => "block download initiate response",
            State::BlockDownloadAck(_) => "block download sub-block acknowledge",
            State::BlockDownloadEnd { .. } => "block download end response",
            State::BlockUploadSegments(_) => "block upload sub-block segment",
            State::BlockUploadEnd(_) => "block upload end",
        }
    }
}

#[derive(Debug, Clone)]
struct Upload {
    mux: Multiplexer,
    /// The toggle of the segment asked for.
    toggle: bool,
    size: Option<usize>,
    buf: Vec<u8>,
}

#[derive(Debug, Clone)]
struct Download {
    mux: Multiplexer,
    data: Vec<u8>,
    /// The offset after the segment sent last.
    end: usize,
    /// The toggle of the segment sent last.
    toggle: bool,
}

#[derive(Debug, Clone)]
struct BlockDownload {
    mux: Multiplexer,
    data: Vec<u8>,
    /// Both sides support the CRC.
    crc: bool,
    /// The offset of the first byte of the sub-block sent last.
    start: usize,
    /// Segments in that sub-block.
    sent: u8,
    /// Whether that sub-block holds the last segment (c = 1).
    last_sent: bool,
    /// Sub-blocks acknowledged with ackseq 0 in a row.
    fruitless: u8,
}

#[derive(Debug, Clone)]
struct BlockUpload {
    mux: Multiplexer,
    /// Both sides support the CRC.
    crc: bool,
    size: Option<usize>,
    /// Whole segments, padding of the last one included until the end frame says how much.
    buf: Vec<u8>,
    /// The sequence number of the last segment received in order in this sub-block (0 = none).
    last_good: u8,
    /// A gap was acknowledged: segments are ignored until the repetition starts at 1.
    resync: bool,
}

/// A received response: 8 bytes (a short frame padded with zeros) and the frame's real length.
#[derive(Debug)]
struct Rx {
    data: [u8; 8],
    len: usize,
}

impl Rx {
    /// The bytes the frame carried (`len` never exceeds 8).
    fn received(&self) -> &[u8] {
        self.data.get(..self.len).unwrap_or(&self.data)
    }

    fn new(payload: &[u8]) -> Rx {
        let mut data = [0; 8];
        for (slot, byte) in data.iter_mut().zip(payload) {
            *slot = *byte;
        }
        Rx {
            data,
            len: payload.len().min(8),
        }
    }
}

/// The bytes of a response that carry meaning; a shorter frame lacks some of them.
fn needed_len(response: &SdoResponse) -> usize {
    match response {
        SdoResponse::InitiateUpload {
            data:
                InitiateData::Expedited {
                    data,
                    size_indicated: true,
                },
            ..
        } => 4 + data.len(),
        SdoResponse::InitiateUpload {
            data:
                InitiateData::Expedited {
                    size_indicated: false,
                    ..
                },
            ..
        } => 5,
        SdoResponse::InitiateUpload {
            data: InitiateData::Segmented { size: Some(_) },
            ..
        }
        | SdoResponse::BlockUploadInitiate { size: Some(_), .. }
        | SdoResponse::Abort { .. } => 8,
        SdoResponse::InitiateUpload { .. }
        | SdoResponse::InitiateDownload { .. }
        | SdoResponse::BlockUploadInitiate { size: None, .. } => 4,
        SdoResponse::UploadSegment(segment) => 1 + segment.data.len(),
        SdoResponse::DownloadSegment { .. } | SdoResponse::BlockDownloadEndResponse => 1,
        SdoResponse::BlockDownloadInitiate { .. } => 5,
        SdoResponse::BlockDownloadAck { .. } | SdoResponse::BlockUploadEnd { .. } => 3,
    }
}

/// Memory reserved up front for an upload: the announced size comes from the bus, so it is not
/// trusted beyond 64 KiB (the buffer grows as data really arrives).
fn initial_capacity(size: Option<usize>) -> usize {
    size.unwrap_or(0).min(64 * 1024)
}

fn usize_from(size: u32) -> usize {
    usize::try_from(size).unwrap_or(usize::MAX)
}

fn toggle_reason(got: bool, expected: bool) -> String {
    format!(
        "the server answered with toggle {}, expected {}",
        u8::from(got),
        u8::from(expected)
    )
}

fn hex(bytes: &[u8]) -> String {
    let parts: Vec<String> = bytes.iter().map(|byte| format!("{byte:02X}")).collect();
    parts.join(" ")
}

/// "Object does not exist in the object dictionary": the CiA 301 text, as a sentence.
fn describe_abort(code: u32) -> String {
    let text = code_text(code);
    let mut chars = text.chars();
    match chars.next() {
        Some(first) => first.to_uppercase().chain(chars).collect(),
        None => String::new(),
    }
}

fn code_text(code: u32) -> &'static str {
    abort_code_text(code).unwrap_or("not a CiA 301 abort code")
}

#[cfg(test)]
mod tests {
    use canopener_can::candump::parse_compact_frame;

    use super::*;

    /// A client for node 5 on virtual time: timestamped frames from the server go in, the frames
    /// the client answers with are compared as candump text (`605#...`).
    struct Trace {
        client: SdoClient,
    }

    impl Trace {
        fn new() -> Trace {
            Trace::with(|client| client)
        }

        fn with(configure: impl FnOnce(SdoClient) -> SdoClient) -> Trace {
            let client = SdoClient::new(5).expect("node 5");
            Trace {
                client: configure(client),
            }
        }

        /// At `ms` the application starts an upload; the client sends exactly `out`.
        fn upload(&mut self, ms: u64, index: u16, sub: u8, mode: UploadMode, out: &[&str]) {
            self.client
                .upload(Instant::from_millis(ms), index, sub, mode)
                .expect("upload starts");
            self.expect(ms, "upload", out);
        }

        /// At `ms` the application starts a download; the client sends exactly `out`.
        fn download(&mut self, ms: u64, index: u16, sub: u8, data: &[u8], mode: DownloadMode, out: &[&str]) {
            self.client
                .download(Instant::from_millis(ms), index, sub, data.to_vec(), mode)
                .expect("download starts");
            self.expect(ms, "download", out);
        }

        /// At `ms` the server sends `frame`; the client answers exactly `out`.
        fn rx(&mut self, ms: u64, frame: &str, out: &[&str]) {
            let parsed = parse_compact_frame(frame).expect("test frame");
            assert!(
                self.client.accept_frame(Instant::from_millis(ms), &parsed),
                "{frame}"
            );
            self.expect(ms, frame, out);
        }

        /// At `ms` time passes; the client sends exactly `out`.
        fn tick(&mut self, ms: u64, out: &[&str]) {
            self.client.handle_timeout(Instant::from_millis(ms));
            self.expect(ms, "timeout", out);
        }

        fn expect(&mut self, ms: u64, after: &str, out: &[&str]) {
            let sent: Vec<String> = std::iter::from_fn(|| self.client.poll_transmit())
                .map(|frame| frame.to_string())
                .collect();
            assert_eq!(sent, out, "at {ms} ms after {after}");
        }

        fn events(&mut self) -> Vec<SdoClientEvent> {
            std::iter::from_fn(|| self.client.poll_event()).collect()
        }

        /// The events without progress reports.
        fn outcome(&mut self) -> Vec<SdoClientEvent> {
            self.events()
                .into_iter()
                .filter(|event| !matches!(event, SdoClientEvent::Progress { .. }))
                .collect()
        }

        /// The transfer on `index`:`sub` failed with `error` and the channel is free again.
        fn failed(&mut self, index: u16, sub: u8) -> SdoTransferError {
            assert!(!self.client.is_busy());
            assert_eq!(self.client.poll_timeout(), None);
            match self.outcome().as_slice() {
                [
                    SdoClientEvent::Failed {
                        index: i,
                        sub: s,
                        error,
                    },
                ] if (*i, *s) == (index, sub) => error.clone(),
                other => panic!("expected one failure of {index:04X}h:{sub}, got {other:?}"),
            }
        }

        /// The client aborted with `code`.
        fn client_aborted(&mut self, index: u16, sub: u8, code: u32) -> String {
            match self.failed(index, sub) {
                SdoTransferError::AbortedByClient { code: sent, reason } if sent == code => reason,
                other => panic!("expected a client abort {code:#010X}, got {other:?}"),
            }
        }

        fn uploaded(&mut self, index: u16, sub: u8, data: &[u8], protocol: Protocol) {
            assert!(!self.client.is_busy());
            assert_eq!(
                self.outcome(),
                [SdoClientEvent::Uploaded {
                    index,
                    sub,
                    data: data.to_vec(),
                    protocol
                }]
            );
        }

        fn downloaded(&mut self, index: u16, sub: u8, protocol: Protocol) {
            assert!(!self.client.is_busy());
            assert_eq!(
                self.outcome(),
                [SdoClientEvent::Downloaded { index, sub, protocol }]
            );
        }
    }

    /// One step of a scripted exchange at a virtual millisecond, and the frames the client must answer
    /// with (candump text).
    #[derive(Debug, Clone, Copy)]
    enum Step {
        /// The application starts an upload of `index`:`sub`.
        Up(u64, u16, u8, UploadMode, &'static [&'static str]),
        /// The application starts a download of these bytes to `index`:`sub`.
        Down(u64, u16, u8, &'static [u8], DownloadMode, &'static [&'static str]),
        /// The server sends a frame.
        Server(u64, &'static str, &'static [&'static str]),
        /// Time passes.
        Wait(u64, &'static [&'static str]),
    }

    /// How a scripted transfer ends.
    #[derive(Debug, Clone, Copy)]
    enum End {
        Uploaded(&'static [u8], Protocol),
        Downloaded(Protocol),
        /// The client aborted with the code, for the reason given.
        Aborted(u32, Reason),
        /// At this millisecond, not one earlier, the transfer times out (after 100 ms) waiting for this.
        TimedOut(u64, &'static str),
    }

    /// The text of a client abort's reason.
    #[derive(Debug, Clone, Copy)]
    enum Reason {
        Any,
        Is(&'static str),
        Has(&'static str),
    }

    /// A transfer: its steps, the first of which starts it, and its end.
    type Script = (&'static [Step], End);

    use End::{Aborted, Downloaded, TimedOut, Uploaded};
    use Step::{Down, Server, Up, Wait};

    impl Trace {
        /// Plays the scripts one after the other on this client, checking every frame it sends and how
        /// each transfer ends (so each also shows the channel is free again for the next).
        fn play(&mut self, scripts: &[Script]) {
            for (number, (steps, end)) in scripts.iter().enumerate() {
                let mut target = None;
                for step in *steps {
                    match *step {
                        Up(ms, index, sub, mode, out) => {
                            target = Some((index, sub));
                            self.upload(ms, index, sub, mode, out);
                        }
                        Down(ms, index, sub, data, mode, out) => {
                            target = Some((index, sub));
                            self.download(ms, index, sub, data, mode, out);
                        }
                        Server(ms, frame, out) => self.rx(ms, frame, out),
                        Wait(ms, out) => self.tick(ms, out),
                    }
                }
                let Some((index, sub)) = target else {
                    panic!("script {number} starts no transfer");
                };
                match *end {
                    Uploaded(data, protocol) => self.uploaded(index, sub, data, protocol),
                    Downloaded(protocol) => self.downloaded(index, sub, protocol),
                    Aborted(code, reason) => {
                        let text = self.client_aborted(index, sub, code);
                        match reason {
                            Reason::Any => {}
                            Reason::Is(expected) => assert_eq!(text, expected, "script {number}"),
                            Reason::Has(part) => assert!(text.contains(part), "script {number}: {text}"),
                        }
                    }
                    TimedOut(at, waiting_for) => times_out(self, at, index, sub, waiting_for),
                }
            }
        }
    }

    fn progress(done: usize, total: Option<usize>) -> SdoClientEvent {
        SdoClientEvent::Progress { done, total }
    }

    // Construction and arguments.

    #[test]
    fn default_channel_ids_and_argument_errors() {
        let client = SdoClient::new(127).expect("node 127");
        assert_eq!(client.request_id().as_raw(), 0x67F);
        assert_eq!(client.response_id().as_raw(), 0x5FF);
        assert_eq!(SdoClient::new(0).err(), Some(SdoClientError::NodeId(0)));
        assert_eq!(SdoClient::new(128).err(), Some(SdoClientError::NodeId(128)));

        let mut trace = Trace::new();
        let now = Instant::ZERO;
        assert_eq!(
            trace.client.upload(now, 0, 0, UploadMode::Normal),
            Err(SdoClientError::Index(0))
        );
        assert_eq!(
            trace
                .client
                .download(now, 0x2000, 0, vec![0; 5], DownloadMode::Expedited),
            Err(SdoClientError::ExpeditedLength(5))
        );
        assert_eq!(
            trace
                .client
                .download(now, 0x2000, 0, Vec::new(), DownloadMode::Expedited),
            Err(SdoClientError::ExpeditedLength(0))
        );
        assert!(!trace.client.is_busy());
        trace.expect(0, "refused starts", &[]);
        trace.upload(0, 0x1000, 0, UploadMode::Normal, &["605#4000100000000000"]);
        assert_eq!(
            trace.client.upload(now, 0x1000, 0, UploadMode::Normal),
            Err(SdoClientError::Busy)
        );
        assert_eq!(
            trace.client.download(now, 0x1017, 0, vec![1], DownloadMode::Auto),
            Err(SdoClientError::Busy)
        );
        trace.expect(0, "busy starts", &[]);
        assert!(trace.client.is_busy());
    }

    #[test]
    fn block_size_is_clamped_to_what_cia_301_allows() {
        let mut trace = Trace::with(|client| client.with_block_size(0).with_crc(false));
        trace.upload(0, 0x1008, 0, UploadMode::Block, &["605#A008100001000000"]);
        let mut trace = Trace::with(|client| client.with_block_size(200));
        trace.upload(0, 0x1008, 0, UploadMode::Block, &["605#A40810007F000000"]);
    }

    #[test]
    fn frames_of_other_channels_and_frames_while_idle() {
        let mut trace = Trace::new();
        let other = parse_compact_frame("586#4318100100000000").expect("frame");
        assert!(!trace.client.accept_frame(Instant::ZERO, &other));
        let remote = parse_compact_frame("585#R8").expect("frame");
        assert!(!trace.client.accept_frame(Instant::ZERO, &remote));
        // On our channel but no transfer runs: taken and ignored.
        trace.rx(0, "585#4318100100000000", &[]);
        trace.rx(0, "585#E0", &[]);
        assert!(trace.events().is_empty());
        assert!(!trace.client.is_busy());
    }

    // Expedited and segmented upload (§7.2.4.3.5..7).

    #[test]
    fn expedited_upload_with_size_indication() {
        let mut trace = Trace::new();
        trace.upload(0, 0x1018, 1, UploadMode::Normal, &["605#4018100100000000"]);
        assert_eq!(trace.client.poll_timeout(), Some(Instant::from_millis(1000)));
        trace.rx(3, "585#4B18100134120000", &[]);
        trace.uploaded(0x1018, 1, &[0x34, 0x12], Protocol::Expedited);
        assert_eq!(trace.client.poll_timeout(), None);
    }

    #[test]
    fn expedited_upload_without_size_indication_takes_all_four_bytes() {
        Trace::new().play(&[(
            &[
                Up(0, 0x1001, 0, UploadMode::Normal, &["605#4001100000000000"]),
                Server(1, "585#4201100005000000", &[]),
            ],
            Uploaded(&[5, 0, 0, 0], Protocol::Expedited),
        )]);
    }

    #[test]
    fn segmented_upload_with_size_toggles_and_reports_progress() {
        let mut trace = Trace::new();
        trace.upload(0, 0x1008, 0, UploadMode::Normal, &["605#4008100000000000"]);
        trace.rx(2, "585#410810000B000000", &["605#6000000000000000"]);
        trace.rx(4, "585#0054455354204445", &["605#7000000000000000"]);
        // Last segment: t = 1, n = 3, c = 1 (17h): 4 data bytes.
        trace.rx(6, "585#1756494345000000", &[]);
        assert_eq!(
            trace.events(),
            [
                progress(0, Some(11)),
                progress(7, Some(11)),
                progress(11, Some(11)),
                SdoClientEvent::Uploaded {
                    index: 0x1008,
                    sub: 0,
                    data: b"TEST DEVICE".to_vec(),
                    protocol: Protocol::Segmented
                }
            ]
        );
    }

    #[test]
    fn segmented_upload_without_size() {
        let mut trace = Trace::new();
        trace.upload(0, 0x1008, 0, UploadMode::Normal, &["605#4008100000000000"]);
        trace.rx(1, "585#4008100000000000", &["605#6000000000000000"]);
        // n = 5, c = 1 (0Bh): 2 data bytes.
        trace.rx(2, "585#0B4F4B0000000000", &[]);
        assert_eq!(
            trace.events(),
            [
                progress(0, None),
                progress(2, None),
                SdoClientEvent::Uploaded {
                    index: 0x1008,
                    sub: 0,
                    data: b"OK".to_vec(),
                    protocol: Protocol::Segmented
                }
            ]
        );
    }

    #[test]
    fn segmented_upload_of_an_empty_value() {
        Trace::new().play(&[(
            &[
                Up(0, 0x2002, 0, UploadMode::Normal, &["605#4002200000000000"]),
                Server(1, "585#4102200000000000", &["605#6000000000000000"]),
                Server(2, "585#0F00000000000000", &[]),
            ],
            Uploaded(&[], Protocol::Segmented),
        )]);
    }

    // Expedited and segmented download (§7.2.4.3.2..4).

    #[test]
    fn expedited_download() {
        Trace::new().play(&[
            (
                &[
                    Down(
                        0,
                        0x1017,
                        0,
                        &[0xE8, 0x03],
                        DownloadMode::Auto,
                        &["605#2B171000E8030000"],
                    ),
                    Server(1, "585#6017100000000000", &[]),
                ],
                Downloaded(Protocol::Expedited),
            ),
            // 1, 3 and 4 bytes: n = 3, 1 and 0 in the command byte.
            (
                &[
                    Down(
                        10,
                        0x2000,
                        0,
                        &[0xAA],
                        DownloadMode::Expedited,
                        &["605#2F002000AA000000"],
                    ),
                    Server(11, "585#6000200000000000", &[]),
                ],
                Downloaded(Protocol::Expedited),
            ),
            (
                &[
                    Down(
                        10,
                        0x2000,
                        0,
                        &[0xAA; 3],
                        DownloadMode::Expedited,
                        &["605#27002000AAAAAA00"],
                    ),
                    Server(11, "585#6000200000000000", &[]),
                ],
                Downloaded(Protocol::Expedited),
            ),
            (
                &[
                    Down(
                        10,
                        0x2000,
                        0,
                        &[0xAA; 4],
                        DownloadMode::Expedited,
                        &["605#23002000AAAAAAAA"],
                    ),
                    Server(11, "585#6000200000000000", &[]),
                ],
                Downloaded(Protocol::Expedited),
            ),
        ]);
    }

    #[test]
    fn segmented_download_with_n_and_toggle() {
        let mut trace = Trace::new();
        let data = b"0123456789";
        trace.download(0, 0x1008, 0, data, DownloadMode::Auto, &["605#210810000A000000"]);
        trace.rx(1, "585#6008100000000000", &["605#0030313233343536"]);
        // Second segment: t = 1, n = 4, c = 1 (19h).
        trace.rx(2, "585#2000000000000000", &["605#1937383900000000"]);
        trace.rx(3, "585#3000000000000000", &[]);
        assert_eq!(
            trace.events(),
            [
                progress(0, Some(10)),
                progress(7, Some(10)),
                progress(10, Some(10)),
                SdoClientEvent::Downloaded {
                    index: 0x1008,
                    sub: 0,
                    protocol: Protocol::Segmented
                }
            ]
        );
    }

    #[test]
    fn segmented_download_of_small_and_empty_values_when_asked() {
        Trace::new().play(&[
            (
                &[
                    Down(0, 0x2002, 0, &[], DownloadMode::Auto, &["605#2102200000000000"]),
                    Server(1, "585#6002200000000000", &["605#0F00000000000000"]),
                    Server(2, "585#2000000000000000", &[]),
                ],
                Downloaded(Protocol::Segmented),
            ),
            (
                &[
                    Down(
                        3,
                        0x2002,
                        0,
                        &[7],
                        DownloadMode::Segmented,
                        &["605#2102200001000000"],
                    ),
                    Server(4, "585#6002200000000000", &["605#0D07000000000000"]),
                    Server(5, "585#2000000000000000", &[]),
                ],
                Downloaded(Protocol::Segmented),
            ),
        ]);
    }

    // Block upload (§7.2.4.3.12..15).

    #[test]
    fn block_upload_with_crc_as_in_the_conformance_log() {
        // CiA CCT "SDO 23" against CANopenNode's demo device, node 4 there, 5 here.
        let mut trace = Trace::with(|client| client.with_block_size(20));
        trace.upload(0, 0x1008, 0, UploadMode::Block, &["605#A408100014000000"]);
        trace.rx(1, "585#C608100010000000", &["605#A300000000000000"]);
        trace.rx(2, "585#0143414E6F70656E", &[]);
        trace.rx(2, "585#0244656D6F504943", &[]);
        trace.rx(2, "585#8333320000000000", &["605#A203140000000000"]);
        trace.rx(3, "585#D5F3430000000000", &["605#A100000000000000"]);
        assert_eq!(
            trace.events(),
            [
                progress(0, Some(16)),
                progress(16, Some(16)),
                SdoClientEvent::Uploaded {
                    index: 0x1008,
                    sub: 0,
                    data: b"CANopenDemoPIC32".to_vec(),
                    protocol: Protocol::Block
                }
            ]
        );
    }

    #[test]
    fn block_upload_without_crc_ignores_the_crc_field() {
        // CCT "SDO 19": the client offers no CRC, the server does; the field is 0.
        Trace::with(|client| client.with_block_size(20).with_crc(false)).play(&[(
            &[
                Up(0, 0x1000, 0, UploadMode::Block, &["605#A000100014000000"]),
                Server(1, "585#C600100004000000", &["605#A300000000000000"]),
                Server(2, "585#8191010F00000000", &["605#A201140000000000"]),
                Server(3, "585#CD00000000000000", &["605#A100000000000000"]),
            ],
            Uploaded(&[0x91, 0x01, 0x0F, 0x00], Protocol::Block),
        )]);
    }

    #[test]
    fn block_upload_over_several_sub_blocks() {
        let data: Vec<u8> = (0..20).collect();
        let crc = crc16_ccitt(&data).to_le_bytes();
        let mut trace = Trace::with(|client| client.with_block_size(2));
        trace.upload(0, 0x2002, 0, UploadMode::Block, &["605#A402200002000000"]);
        trace.rx(1, "585#C402200000000000", &["605#A300000000000000"]);
        trace.rx(2, "585#0100010203040506", &[]);
        trace.rx(2, "585#020708090A0B0C0D", &["605#A202020000000000"]);
        trace.rx(3, "585#810E0F1011121300", &["605#A201020000000000"]);
        trace.rx(
            4,
            &format!("585#C5{:02X}{:02X}0000000000", crc[0], crc[1]),
            &["605#A100000000000000"],
        );
        assert_eq!(
            trace.events(),
            [
                progress(0, None),
                progress(14, None),
                progress(20, None),
                SdoClientEvent::Uploaded {
                    index: 0x2002,
                    sub: 0,
                    data,
                    protocol: Protocol::Block
                }
            ]
        );
    }

    #[test]
    fn block_upload_gap_is_acknowledged_and_repeated() {
        let mut trace = Trace::with(|client| client.with_block_size(4).with_crc(false));
        trace.upload(0, 0x2002, 0, UploadMode::Block, &["605#A002200004000000"]);
        trace.rx(1, "585#C20220001C000000", &["605#A300000000000000"]);
        trace.rx(2, "585#0101010101010101", &[]);
        // Segment 2 is lost: segment 3 shows the gap, the client acknowledges segment 1 at once.
        trace.rx(2, "585#0303030303030303", &["605#A201040000000000"]);
        // The rest of the broken sub-block is ignored until the repetition starts at 1.
        trace.rx(2, "585#8404040404040404", &[]);
        trace.rx(3, "585#0102020202020202", &[]);
        trace.rx(3, "585#0203030303030303", &[]);
        // A duplicate is ignored too.
        trace.rx(3, "585#0203030303030303", &[]);
        trace.rx(3, "585#8304040404040404", &["605#A203040000000000"]);
        trace.rx(4, "585#C100000000000000", &["605#A100000000000000"]);
        let mut data = Vec::new();
        for byte in 1..=4u8 {
            data.extend_from_slice(&[byte; 7]);
        }
        trace.uploaded(0x2002, 0, &data, Protocol::Block);
    }

    #[test]
    fn block_upload_stalled_sub_block_is_acknowledged_before_the_timeout() {
        let mut trace = Trace::with(|client| client.with_block_size(4).with_crc(false));
        trace.upload(0, 0x2002, 0, UploadMode::Block, &["605#A002200004000000"]);
        trace.rx(1, "585#C20220000E000000", &["605#A300000000000000"]);
        trace.rx(10, "585#0101010101010101", &[]);
        // The last segment is lost: after 70 % of the timeout the client acknowledges segment 1.
        assert_eq!(trace.client.poll_timeout(), Some(Instant::from_millis(710)));
        trace.tick(709, &[]);
        trace.tick(710, &["605#A201040000000000"]);
        assert_eq!(trace.client.poll_timeout(), Some(Instant::from_millis(1010)));
        trace.rx(720, "585#8102020202020202", &["605#A201040000000000"]);
        trace.rx(730, "585#C100000000000000", &["605#A100000000000000"]);
        let mut data = vec![1; 7];
        data.extend_from_slice(&[2; 7]);
        trace.uploaded(0x2002, 0, &data, Protocol::Block);
    }

    #[test]
    fn block_upload_answered_with_a_normal_upload_under_the_threshold() {
        // pst 8: the server may switch; an expedited answer ends the transfer at once, a segmented
        // answer is followed with upload segment requests.
        Trace::with(|client| client.with_block_upload_threshold(8)).play(&[
            (
                &[
                    Up(0, 0x1017, 0, UploadMode::Block, &["605#A41710007F080000"]),
                    Server(1, "585#4B171000E8030000", &[]),
                ],
                Uploaded(&[0xE8, 0x03], Protocol::Expedited),
            ),
            (
                &[
                    Up(2, 0x1008, 0, UploadMode::Block, &["605#A40810007F080000"]),
                    Server(3, "585#4108100005000000", &["605#6000000000000000"]),
                    Server(4, "585#0548454C4C4F0000", &[]),
                ],
                Uploaded(b"HELLO", Protocol::Segmented),
            ),
        ]);
    }

    #[test]
    fn protocol_switch_without_threshold_is_an_error() {
        Trace::new().play(&[(
            &[
                Up(0, 0x1017, 0, UploadMode::Block, &["605#A41710007F000000"]),
                Server(1, "585#4B171000E8030000", &["605#8017100001000405"]),
            ],
            Aborted(
                abort::COMMAND_SPECIFIER_INVALID,
                Reason::Has("protocol switch threshold is 0"),
            ),
        )]);
    }

    // Block download (§7.2.4.3.8..11).

    #[test]
    fn block_download_as_in_the_conformance_log() {
        // CCT "SDO 25": 1017h = 0000h with CRC; n = 5 and the CRC of 00 00 is 0000h.
        let mut trace = Trace::new();
        trace.download(
            0,
            0x1017,
            0,
            &[0, 0],
            DownloadMode::Block,
            &["605#C617100002000000"],
        );
        trace.rx(1, "585#A41710007F000000", &["605#8100000000000000"]);
        trace.rx(2, "585#A2017F0000000000", &["605#D500000000000000"]);
        trace.rx(3, "585#A100000000000000", &[]);
        assert_eq!(
            trace.events(),
            [
                progress(0, Some(2)),
                progress(2, Some(2)),
                SdoClientEvent::Downloaded {
                    index: 0x1017,
                    sub: 0,
                    protocol: Protocol::Block
                }
            ]
        );
    }

    #[test]
    fn block_download_retransmits_after_ackseq_and_follows_the_new_block_size() {
        let data: Vec<u8> = (0..30).collect();
        let crc = crc16_ccitt(&data).to_le_bytes();
        let mut trace = Trace::new();
        trace.download(
            0,
            0x2002,
            0,
            &data,
            DownloadMode::Block,
            &["605#C60220001E000000"],
        );
        trace.rx(
            1,
            "585#A402200003000000",
            &[
                "605#0100010203040506",
                "605#020708090A0B0C0D",
                "605#030E0F1011121314",
            ],
        );
        // Only segment 1 arrived; next sub-blocks of 2 segments, from byte 7 on, numbered from 1.
        trace.rx(
            2,
            "585#A201020000000000",
            &["605#010708090A0B0C0D", "605#020E0F1011121314"],
        );
        trace.rx(
            3,
            "585#A202020000000000",
            &["605#0115161718191A1B", "605#821C1D0000000000"],
        );
        // All acknowledged: end with n = 5 and the CRC.
        trace.rx(
            4,
            "585#A202020000000000",
            &[format!("605#D5{:02X}{:02X}0000000000", crc[0], crc[1]).as_str()],
        );
        trace.rx(5, "585#A100000000000000", &[]);
        assert_eq!(
            trace.events(),
            [
                progress(0, Some(30)),
                progress(7, Some(30)),
                progress(21, Some(30)),
                progress(30, Some(30)),
                SdoClientEvent::Downloaded {
                    index: 0x2002,
                    sub: 0,
                    protocol: Protocol::Block
                }
            ]
        );
    }

    #[test]
    fn block_download_repeats_the_last_segment_when_its_ack_falls_short() {
        Trace::with(|client| client.with_crc(false)).play(&[(
            &[
                Down(
                    0,
                    0x2002,
                    0,
                    &[9; 10],
                    DownloadMode::Block,
                    &["605#C20220000A000000"],
                ),
                Server(
                    1,
                    "585#A002200010000000",
                    &["605#0109090909090909", "605#8209090900000000"],
                ),
                Server(2, "585#A201100000000000", &["605#8109090900000000"]),
                // Without CRC on both sides the field is 0; n = 4.
                Server(3, "585#A201100000000000", &["605#D100000000000000"]),
                Server(4, "585#A100000000000000", &[]),
            ],
            Downloaded(Protocol::Block),
        )]);
    }

    #[test]
    fn block_download_of_an_empty_value() {
        Trace::new().play(&[(
            &[
                Down(0, 0x2002, 0, &[], DownloadMode::Block, &["605#C602200000000000"]),
                Server(1, "585#A40220007F000000", &["605#8100000000000000"]),
                Server(2, "585#A2017F0000000000", &["605#DD00000000000000"]),
                Server(3, "585#A100000000000000", &[]),
            ],
            Downloaded(Protocol::Block),
        )]);
    }

    #[test]
    fn block_download_gives_up_when_nothing_is_ever_acknowledged() {
        let mut trace = Trace::with(|client| client.with_crc(false));
        trace.download(
            0,
            0x2002,
            0,
            &[1; 8],
            DownloadMode::Block,
            &["605#C202200008000000"],
        );
        let sub_block = ["605#0101010101010101", "605#8201000000000000"];
        trace.rx(1, "585#A00220007F000000", &sub_block);
        for ms in 2..2 + u64::from(MAX_FRUITLESS_SUB_BLOCKS) {
            trace.rx(ms, "585#A2007F0000000000", &sub_block);
        }
        trace.rx(9, "585#A2007F0000000000", &["605#8002200000000008"]);
        let reason = trace.client_aborted(0x2002, 0, abort::GENERAL_ERROR);
        assert!(reason.contains("no segment of 4 sub-blocks"), "{reason}");
    }

    // Every server deviation ends in a client abort with the right code.

    #[test]
    fn garbage_responses_abort_with_0504_0001() {
        let invalid = abort::COMMAND_SPECIFIER_INVALID;
        Trace::new().play(&[
            (
                &[
                    Up(0, 0x1018, 1, UploadMode::Normal, &["605#4018100100000000"]),
                    Server(1, "585#E0FFFFFFFFFFFFFF", &["605#8018100101000405"]),
                ],
                Aborted(invalid, Reason::Has("E0 FF")),
            ),
            // A valid frame of the wrong kind: a download confirmation for an upload.
            (
                &[
                    Up(2, 0x1018, 1, UploadMode::Normal, &["605#4018100100000000"]),
                    Server(3, "585#6018100100000000", &["605#8018100101000405"]),
                ],
                Aborted(invalid, Reason::Has("expected the initiate upload response")),
            ),
            // A block download answer to a segmented download.
            (
                &[
                    Down(
                        4,
                        0x2002,
                        0,
                        &[1; 9],
                        DownloadMode::Segmented,
                        &["605#2102200009000000"],
                    ),
                    Server(5, "585#A40220007F000000", &["605#8002200001000405"]),
                ],
                Aborted(invalid, Reason::Any),
            ),
            // A block upload answer to a normal upload.
            (
                &[
                    Up(6, 0x2002, 0, UploadMode::Normal, &["605#4002200000000000"]),
                    Server(7, "585#C602200010000000", &["605#8002200001000405"]),
                ],
                Aborted(invalid, Reason::Any),
            ),
            // Anything but the end response after a block download end.
            (
                &[
                    Down(
                        8,
                        0x1017,
                        0,
                        &[0, 0],
                        DownloadMode::Block,
                        &["605#C617100002000000"],
                    ),
                    Server(9, "585#A41710007F000000", &["605#8100000000000000"]),
                    Server(10, "585#A2017F0000000000", &["605#D500000000000000"]),
                    Server(11, "585#A2017F0000000000", &["605#8017100001000405"]),
                ],
                Aborted(invalid, Reason::Has("block download end response")),
            ),
        ]);
    }

    #[test]
    fn answer_for_another_entry_aborts_with_0604_0043() {
        let incompatible = abort::PARAMETER_INCOMPATIBLE;
        Trace::new().play(&[
            (
                &[
                    Up(0, 0x1018, 1, UploadMode::Normal, &["605#4018100100000000"]),
                    Server(1, "585#4318100278563412", &["605#8018100143000406"]),
                ],
                Aborted(
                    incompatible,
                    Reason::Is("the server answered for 1018h:02 instead of 1018h:01"),
                ),
            ),
            (
                &[
                    Down(
                        2,
                        0x1017,
                        0,
                        &[1, 0],
                        DownloadMode::Auto,
                        &["605#2B17100001000000"],
                    ),
                    Server(3, "585#6016100000000000", &["605#8017100043000406"]),
                ],
                Aborted(incompatible, Reason::Any),
            ),
            (
                &[
                    Down(
                        4,
                        0x1017,
                        0,
                        &[1, 0],
                        DownloadMode::Block,
                        &["605#C617100002000000"],
                    ),
                    Server(5, "585#A41610007F000000", &["605#8017100043000406"]),
                ],
                Aborted(incompatible, Reason::Any),
            ),
            (
                &[
                    Up(6, 0x1008, 0, UploadMode::Block, &["605#A40810007F000000"]),
                    Server(7, "585#C609100010000000", &["605#8008100043000406"]),
                ],
                Aborted(incompatible, Reason::Any),
            ),
        ]);
    }

    #[test]
    fn toggle_errors_abort_with_0503_0000() {
        let toggle = abort::TOGGLE_BIT_NOT_ALTERNATED;
        Trace::new().play(&[
            (
                &[
                    Up(0, 0x1008, 0, UploadMode::Normal, &["605#4008100000000000"]),
                    Server(1, "585#4108100010000000", &["605#6000000000000000"]),
                    Server(2, "585#0041414141414141", &["605#7000000000000000"]),
                    // The second segment repeats toggle 0.
                    Server(3, "585#0042424242424242", &["605#8008100000000305"]),
                ],
                Aborted(
                    toggle,
                    Reason::Is("the server answered with toggle 0, expected 1"),
                ),
            ),
            (
                &[
                    Down(
                        4,
                        0x2002,
                        0,
                        &[1; 9],
                        DownloadMode::Auto,
                        &["605#2102200009000000"],
                    ),
                    Server(5, "585#6002200000000000", &["605#0001010101010101"]),
                    Server(6, "585#3000000000000000", &["605#8002200000000305"]),
                ],
                Aborted(toggle, Reason::Any),
            ),
        ]);
    }

    #[test]
    fn delivered_length_disagreeing_with_the_size_aborts_with_0607_0010() {
        let mismatch = abort::LENGTH_MISMATCH;
        Trace::new().play(&[
            (
                &[
                    Up(0, 0x1008, 0, UploadMode::Normal, &["605#4008100000000000"]),
                    Server(1, "585#4108100003000000", &["605#6000000000000000"]),
                    Server(2, "585#0141424344454647", &["605#8008100010000706"]),
                ],
                Aborted(
                    mismatch,
                    Reason::Is("the server announced 3 bytes and delivered 7"),
                ),
            ),
            // Fewer bytes than announced, noticed at the last segment.
            (
                &[
                    Up(3, 0x1008, 0, UploadMode::Normal, &["605#4008100000000000"]),
                    Server(4, "585#410810000A000000", &["605#6000000000000000"]),
                    Server(5, "585#0B41420000000000", &["605#8008100010000706"]),
                ],
                Aborted(mismatch, Reason::Any),
            ),
            // Block upload: the end frame leaves 10 bytes of 16 announced.
            (
                &[
                    Up(6, 0x1008, 0, UploadMode::Block, &["605#A40810007F000000"]),
                    Server(7, "585#C608100010000000", &["605#A300000000000000"]),
                    Server(8, "585#0141424344454647", &[]),
                    Server(8, "585#8241424344454647", &["605#A2027F0000000000"]),
                    Server(9, "585#D100000000000000", &["605#8008100010000706"]),
                ],
                Aborted(mismatch, Reason::Any),
            ),
            // Block upload: more segments than 16 bytes need.
            (
                &[
                    Up(10, 0x1008, 0, UploadMode::Block, &["605#A40810007F000000"]),
                    Server(11, "585#C608100010000000", &["605#A300000000000000"]),
                    Server(12, "585#0141424344454647", &[]),
                    Server(12, "585#0241424344454647", &[]),
                    Server(12, "585#0341424344454647", &[]),
                    Server(12, "585#0441424344454647", &["605#8008100010000706"]),
                ],
                Aborted(mismatch, Reason::Any),
            ),
        ]);
    }

    #[test]
    fn short_frames_abort_by_default() {
        Trace::new().play(&[
            (
                &[
                    Down(
                        0,
                        0x1017,
                        0,
                        &[1, 0],
                        DownloadMode::Auto,
                        &["605#2B17100001000000"],
                    ),
                    Server(1, "585#60171000", &["605#8017100001000405"]),
                ],
                Aborted(
                    abort::COMMAND_SPECIFIER_INVALID,
                    Reason::Is(
                        "the server answered with DLC 4 (585#60171000); CiA 301 SDO frames have 8 bytes",
                    ),
                ),
            ),
            (
                &[
                    Up(2, 0x1017, 0, UploadMode::Normal, &["605#4017100000000000"]),
                    Server(3, "585#", &["605#8017100001000405"]),
                ],
                Aborted(abort::COMMAND_SPECIFIER_INVALID, Reason::Any),
            ),
        ]);
    }

    #[test]
    fn short_frames_are_padded_when_asked_if_nothing_is_cut_off() {
        let invalid = abort::COMMAND_SPECIFIER_INVALID;
        Trace::with(|client| client.with_short_frames(ShortFrames::Pad)).play(&[
            (
                &[
                    Down(
                        0,
                        0x1017,
                        0,
                        &[1, 0],
                        DownloadMode::Auto,
                        &["605#2B17100001000000"],
                    ),
                    Server(1, "585#60171000", &[]),
                ],
                Downloaded(Protocol::Expedited),
            ),
            // An expedited answer of 1 byte in a DLC-5 frame, with and without size indication.
            (
                &[
                    Up(2, 0x1001, 0, UploadMode::Normal, &["605#4001100000000000"]),
                    Server(3, "585#4F01100005", &[]),
                ],
                Uploaded(&[5], Protocol::Expedited),
            ),
            (
                &[
                    Up(4, 0x1001, 0, UploadMode::Normal, &["605#4001100000000000"]),
                    Server(5, "585#4201100005", &[]),
                ],
                Uploaded(&[5], Protocol::Expedited),
            ),
            // Segments shortened to their data.
            (
                &[
                    Up(6, 0x1008, 0, UploadMode::Normal, &["605#4008100000000000"]),
                    Server(7, "585#4108100002000000", &["605#6000000000000000"]),
                    Server(8, "585#0B4F4B", &[]),
                ],
                Uploaded(b"OK", Protocol::Segmented),
            ),
            // But a frame missing bytes its command uses still aborts: "4 bytes" in a DLC-6 frame.
            (
                &[
                    Up(9, 0x1018, 1, UploadMode::Normal, &["605#4018100100000000"]),
                    Server(10, "585#431810017856", &["605#8018100101000405"]),
                ],
                Aborted(invalid, Reason::Has("needs 8 bytes")),
            ),
            // Block segments always need 8 bytes.
            (
                &[
                    Up(11, 0x1008, 0, UploadMode::Block, &["605#A40810007F000000"]),
                    Server(12, "585#C608100002000000", &["605#A300000000000000"]),
                    Server(13, "585#814F4B", &["605#8008100001000405"]),
                ],
                Aborted(invalid, Reason::Any),
            ),
            // A shortened abort frame has lost its code.
            (
                &[
                    Up(14, 0x1018, 1, UploadMode::Normal, &["605#4018100100000000"]),
                    Server(15, "585#8018100100", &["605#8018100101000405"]),
                ],
                Aborted(invalid, Reason::Any),
            ),
        ]);
    }

    #[test]
    fn crc_mismatch_aborts_with_0504_0004() {
        Trace::with(|client| client.with_block_size(20)).play(&[(
            &[
                Up(0, 0x1008, 0, UploadMode::Block, &["605#A408100014000000"]),
                Server(1, "585#C608100010000000", &["605#A300000000000000"]),
                Server(2, "585#0143414E6F70656E", &[]),
                Server(2, "585#0244656D6F504943", &[]),
                Server(2, "585#8333320000000000", &["605#A203140000000000"]),
                Server(3, "585#D5F3440000000000", &["605#8008100004000405"]),
            ],
            Aborted(
                abort::CRC_ERROR,
                Reason::Is("the server's CRC is 44F3h, the data received has 43F3h"),
            ),
        )]);
    }

    #[test]
    fn block_sizes_0_and_128_from_the_server_abort_with_0504_0002() {
        for blksize in ["00", "80"] {
            let mut trace = Trace::new();
            trace.download(
                0,
                0x1017,
                0,
                &[0, 0],
                DownloadMode::Block,
                &["605#C617100002000000"],
            );
            trace.rx(
                1,
                &format!("585#A4171000{blksize}000000"),
                &["605#8017100002000405"],
            );
            trace.client_aborted(0x1017, 0, abort::INVALID_BLOCK_SIZE);
            // The same in the block size of an acknowledge.
            let data = [1; 10];
            trace.download(
                2,
                0x2002,
                0,
                &data,
                DownloadMode::Block,
                &["605#C60220000A000000"],
            );
            trace.rx(3, "585#A402200001000000", &["605#0101010101010101"]);
            trace.rx(
                4,
                &format!("585#A201{blksize}0000000000"),
                &["605#8002200002000405"],
            );
            let reason = trace.client_aborted(0x2002, 0, abort::INVALID_BLOCK_SIZE);
            assert!(reason.contains("block size"), "{reason}");
        }
    }

    #[test]
    fn bad_sequence_numbers_abort_with_0504_0003() {
        let invalid = abort::INVALID_SEQUENCE_NUMBER;
        // An acknowledge of more segments than were sent.
        Trace::new().play(&[(
            &[
                Down(
                    0,
                    0x1017,
                    0,
                    &[0, 0],
                    DownloadMode::Block,
                    &["605#C617100002000000"],
                ),
                Server(1, "585#A41710007F000000", &["605#8100000000000000"]),
                Server(2, "585#A2027F0000000000", &["605#8017100003000405"]),
            ],
            Aborted(
                invalid,
                Reason::Is("the server acknowledged segment 2 of a sub-block of 1 segments"),
            ),
        )]);
        // Segment 0, and a segment beyond the block size the client offered.
        for segment in ["585#0041424344454647", "585#0541424344454647"] {
            let mut trace = Trace::with(|client| client.with_block_size(4));
            trace.upload(3, 0x1008, 0, UploadMode::Block, &["605#A408100004000000"]);
            trace.rx(4, "585#C608100010000000", &["605#A300000000000000"]);
            trace.rx(5, segment, &["605#8008100003000405"]);
            trace.client_aborted(0x1008, 0, invalid);
        }
    }

    // A silent server times out in every phase, and the server is told with 0504 0000h.

    /// At `at` ms (not a millisecond earlier) the transfer times out: abort 0504 0000h goes out.
    fn times_out(trace: &mut Trace, at: u64, index: u16, sub: u8, waiting_for: &'static str) {
        let [i0, i1] = index.to_le_bytes();
        let abort = format!("605#80{i0:02X}{i1:02X}{sub:02X}00000405");
        trace.tick(at - 1, &[]);
        trace.tick(at, &[abort.as_str()]);
        assert_eq!(
            trace.failed(index, sub),
            SdoTransferError::TimedOut {
                waiting_for,
                after: Duration::from_millis(100)
            }
        );
    }

    #[test]
    fn silence_times_out_in_every_phase() {
        Trace::with(|client| client.with_timeout(Duration::from_millis(100))).play(&[
            (
                &[Up(0, 0x1018, 1, UploadMode::Normal, &["605#4018100100000000"])],
                TimedOut(100, "initiate upload response"),
            ),
            (
                &[
                    Up(200, 0x1008, 0, UploadMode::Normal, &["605#4008100000000000"]),
                    Server(250, "585#410810000A000000", &["605#6000000000000000"]),
                ],
                TimedOut(350, "upload segment response"),
            ),
            (
                &[Down(
                    400,
                    0x1017,
                    0,
                    &[1, 0],
                    DownloadMode::Auto,
                    &["605#2B17100001000000"],
                )],
                TimedOut(500, "initiate download response"),
            ),
            (
                &[
                    Down(
                        600,
                        0x2002,
                        0,
                        &[1; 9],
                        DownloadMode::Auto,
                        &["605#2102200009000000"],
                    ),
                    Server(610, "585#6002200000000000", &["605#0001010101010101"]),
                ],
                TimedOut(710, "download segment response"),
            ),
            (
                &[Down(
                    800,
                    0x2002,
                    0,
                    &[1; 9],
                    DownloadMode::Block,
                    &["605#C602200009000000"],
                )],
                TimedOut(900, "block download initiate response"),
            ),
            (
                &[
                    Down(
                        1000,
                        0x2002,
                        0,
                        &[1; 9],
                        DownloadMode::Block,
                        &["605#C602200009000000"],
                    ),
                    Server(
                        1010,
                        "585#A40220007F000000",
                        &["605#0101010101010101", "605#8201010000000000"],
                    ),
                ],
                TimedOut(1110, "block download sub-block acknowledge"),
            ),
            // The CRC of 01 01 is 2310h.
            (
                &[
                    Down(
                        1200,
                        0x2002,
                        0,
                        &[1; 2],
                        DownloadMode::Block,
                        &["605#C602200002000000"],
                    ),
                    Server(1210, "585#A40220007F000000", &["605#8101010000000000"]),
                    Server(1220, "585#A2017F0000000000", &["605#D510230000000000"]),
                ],
                TimedOut(1320, "block download end response"),
            ),
            (
                &[Up(1400, 0x1008, 0, UploadMode::Block, &["605#A40810007F000000"])],
                TimedOut(1500, "block upload initiate response"),
            ),
            // No segment at all after "start upload": no acknowledge can help, the timeout ends it.
            (
                &[
                    Up(1600, 0x1008, 0, UploadMode::Block, &["605#A40810007F000000"]),
                    Server(1610, "585#C608100010000000", &["605#A300000000000000"]),
                ],
                TimedOut(1710, "block upload sub-block segment"),
            ),
            // Segments stop: one acknowledge after 70 ms, then the timeout 100 ms after the last one.
            (
                &[
                    Up(1800, 0x1008, 0, UploadMode::Block, &["605#A40810007F000000"]),
                    Server(1810, "585#C608100010000000", &["605#A300000000000000"]),
                    Server(1820, "585#0141424344454647", &[]),
                    Wait(1890, &["605#A2017F0000000000"]),
                ],
                TimedOut(1920, "block upload sub-block segment"),
            ),
            (
                &[
                    Up(2000, 0x1008, 0, UploadMode::Block, &["605#A40810007F000000"]),
                    Server(2010, "585#C608100002000000", &["605#A300000000000000"]),
                    Server(2020, "585#814F4B0000000000", &["605#A2017F0000000000"]),
                ],
                TimedOut(2120, "block upload end"),
            ),
        ]);
    }

    #[test]
    fn a_server_sending_only_wrong_segments_still_times_out() {
        let mut trace = Trace::with(|client| client.with_timeout(Duration::from_millis(100)).with_crc(false));
        trace.upload(0, 0x1008, 0, UploadMode::Block, &["605#A00810007F000000"]);
        trace.rx(1, "585#C208100010000000", &["605#A300000000000000"]);
        trace.rx(2, "585#0241424344454647", &["605#A2007F0000000000"]);
        for ms in (10..100).step_by(10) {
            trace.rx(ms, "585#0241424344454647", &[]);
        }
        trace.tick(101, &["605#8008100000000405"]);
        assert!(matches!(
            trace.failed(0x1008, 0),
            SdoTransferError::TimedOut { .. }
        ));
    }

    #[test]
    fn zero_timeout_never_expires() {
        let mut trace = Trace::with(|client| client.with_timeout(Duration::ZERO));
        trace.upload(0, 0x1018, 1, UploadMode::Normal, &["605#4018100100000000"]);
        assert_eq!(trace.client.poll_timeout(), None);
        trace.tick(1_000_000, &[]);
        assert!(trace.client.is_busy());
        trace.client.abort(Instant::from_secs(1001), abort::GENERAL_ERROR);
        trace.expect(1_001_000, "abort", &["605#8018100100000008"]);
        assert!(matches!(
            trace.failed(0x1018, 1),
            SdoTransferError::AbortedByClient {
                code: abort::GENERAL_ERROR,
                ..
            }
        ));
    }

    // Aborts from either side.

    #[test]
    fn server_abort_mid_transfer_is_reported_decoded() {
        let mut trace = Trace::new();
        trace.upload(0, 0x1008, 0, UploadMode::Normal, &["605#4008100000000000"]);
        trace.rx(1, "585#4108100010000000", &["605#6000000000000000"]);
        trace.rx(2, "585#8008100000000008", &[]);
        let error = trace.failed(0x1008, 0);
        assert_eq!(error, SdoTransferError::AbortedByServer { code: 0x0800_0000 });
        assert_eq!(
            error.to_string(),
            "SDO abort 0x08000000 from the server: General error"
        );
        assert_eq!(error.abort_code(), 0x0800_0000);
    }

    #[test]
    fn server_abort_during_a_block_download_drops_the_unsent_segments() {
        let mut trace = Trace::new();
        trace.download(
            0,
            0x2002,
            0,
            &[1; 20],
            DownloadMode::Block,
            &["605#C602200014000000"],
        );
        let parsed = parse_compact_frame("585#A40220007F000000").expect("frame");
        assert!(trace.client.accept_frame(Instant::from_millis(1), &parsed));
        // The driver has sent one segment of the sub-block when the server aborts.
        assert_eq!(
            trace.client.poll_transmit().map(|frame| frame.to_string()),
            Some("605#0101010101010101".to_owned())
        );
        trace.rx(2, "585#8002200000000206", &[]);
        let error = trace.failed(0x2002, 0);
        assert_eq!(
            error.to_string(),
            "SDO abort 0x06020000 from the server: Object does not exist in the object dictionary"
        );
    }

    #[test]
    fn server_abort_inside_block_upload_segments_is_80h_only() {
        let mut trace = Trace::new();
        trace.upload(0, 0x1008, 0, UploadMode::Block, &["605#A40810007F000000"]);
        trace.rx(1, "585#C608100010000000", &["605#A300000000000000"]);
        trace.rx(2, "585#0141424344454647", &[]);
        trace.rx(3, "585#8008100000000405", &[]);
        assert_eq!(
            trace.failed(0x1008, 0),
            SdoTransferError::AbortedByServer { code: 0x0504_0000 }
        );
    }

    #[test]
    fn application_abort_sends_the_code_and_reports_it() {
        let mut trace = Trace::new();
        trace.client.abort(Instant::ZERO, abort::GENERAL_ERROR);
        trace.expect(0, "abort while idle", &[]);
        assert!(trace.events().is_empty());
        trace.download(
            0,
            0x2002,
            0,
            &[1; 20],
            DownloadMode::Block,
            &["605#C602200014000000"],
        );
        let parsed = parse_compact_frame("585#A40220007F000000").expect("frame");
        assert!(trace.client.accept_frame(Instant::from_millis(1), &parsed));
        trace
            .client
            .abort(Instant::from_millis(1), abort::CANNOT_TRANSFER_LOCAL_CONTROL);
        // The queued sub-block is dropped; only the abort goes out.
        trace.expect(1, "abort", &["605#8002200021000008"]);
        let error = trace.failed(0x2002, 0);
        assert_eq!(
            error.to_string(),
            "SDO transfer aborted by the client with 0x08000021 (data cannot be transferred or stored to the \
             application because of local control): aborted by the application"
        );
        // A late frame of the aborted transfer is ignored.
        trace.rx(2, "585#A2037F0000000000", &[]);
        assert!(trace.events().is_empty());
    }

    fn start(client: &mut SdoClient, mode: u8, len: usize) -> Result<(), SdoClientError> {
        let data = vec![0x5A; len];
        let now = Instant::ZERO;
        match mode % 6 {
            0 => client.upload(now, 0x2002, 0, UploadMode::Normal),
            1 => client.upload(now, 0x2002, 0, UploadMode::Block),
            2 => client.download(now, 0x2002, 0, data, DownloadMode::Auto),
            3 => client.download(now, 0x2002, 0, data, DownloadMode::Segmented),
            4 => client.download(now, 0x2002, 0, data, DownloadMode::Block),
            _ => client.download(now, 0x2002, 0, data, DownloadMode::Expedited),
        }
    }

    proptest::proptest! {
        /// Whatever the server sends, the client neither panics nor hangs: every transfer ends in
        /// one outcome, and a failure the client detects goes to the server as an abort frame.
        #[test]
        fn arbitrary_responses_end_every_transfer_cleanly(
            mode in 0u8..6,
            len in 0usize..40,
            pad: bool,
            frames in proptest::collection::vec(proptest::collection::vec(proptest::prelude::any::<u8>(), 0..=8), 0..40),
        ) {
            let short_frames = if pad { ShortFrames::Pad } else { ShortFrames::Abort };
            let mut client = SdoClient::new(5)
                .expect("node 5")
                .with_block_size(4)
                .with_block_upload_threshold(8)
                .with_short_frames(short_frames);
            if start(&mut client, mode, len).is_err() {
                return Ok(());
            }
            let mut sent = Vec::new();
            for (ms, bytes) in (1u64..).zip(&frames) {
                let frame = CanFrame::new(StandardId::new(0x585).unwrap_or(StandardId::ZERO), bytes)
                    .expect("at most 8 bytes");
                client.handle_frame(Instant::from_millis(ms), &frame);
                sent.extend(std::iter::from_fn(|| client.poll_transmit()));
            }
            client.handle_timeout(Instant::from_secs(60));
            client.handle_timeout(Instant::from_secs(120));
            sent.extend(std::iter::from_fn(|| client.poll_transmit()));
            proptest::prop_assert!(!client.is_busy());
            proptest::prop_assert_eq!(client.poll_timeout(), None);
            let outcomes: Vec<SdoClientEvent> = std::iter::from_fn(|| client.poll_event())
                .filter(|event| !matches!(event, SdoClientEvent::Progress { .. }))
                .collect();
            proptest::prop_assert_eq!(outcomes.len(), 1, "{:?}", outcomes);
            if let Some(SdoClientEvent::Failed { error, .. }) = outcomes.first()
                && !matches!(error, SdoTransferError::AbortedByServer { .. })
            {
                let last = sent.last().map(|frame| frame.data().to_vec()).unwrap_or_default();
                proptest::prop_assert_eq!(last.first(), Some(&0x80));
                proptest::prop_assert_eq!(last.get(4..8), Some(&error.abort_code().to_le_bytes()[..]));
            }
        }
    }

    #[test]
    fn error_texts() {
        let unknown = SdoTransferError::AbortedByServer { code: 0x1234_5678 };
        assert_eq!(
            unknown.to_string(),
            "SDO abort 0x12345678 from the server: Not a CiA 301 abort code"
        );
        let timed_out = SdoTransferError::TimedOut {
            waiting_for: "upload segment response",
            after: Duration::from_millis(300),
        };
        assert_eq!(
            timed_out.to_string(),
            "timed out after 300ms waiting for the upload segment response (abort 0x05040000 sent to the server)"
        );
        assert_eq!(timed_out.abort_code(), 0x0504_0000);
        assert_eq!(
            SdoClientError::ExpeditedLength(5).to_string(),
            "an expedited download carries 1 to 4 bytes, got 5; use a segmented or block download"
        );
        assert_eq!(Protocol::Block.to_string(), "block");
    }
}

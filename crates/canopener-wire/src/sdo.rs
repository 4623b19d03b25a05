//! SDO frames: expedited, segmented and block transfers (CiA 301 §7.2.4).
//!
//! Heads up: read CiA 301 §7.2.4.3 (SDO protocols) before changing this file. Every SDO frame has 8
//! bytes. D0 is the command byte whose top 3 bits are the client (ccs) or server (scs) command
//! specifier; the same bits mean different things in each direction, so requests (client to server,
//! 600h + node-id) and responses (server to client, 580h + node-id) are separate types.
//!
//! Block sub-block segments (§7.2.4.3.10, §7.2.4.3.14) are the exception: D0 is `c` and a 7-bit
//! sequence number, and only the receiver's state tells that a segment is due. [`BlockSegment`]
//! therefore has its own parser, and [`crate::Decoder`] decides which parser applies.
//!
//! Parsing is lenient like a receiver: reserved bits are ignored. [`SdoRequest::reserved_mask`] and
//! [`SdoResponse::reserved_mask`] tell which bits a conforming sender leaves 0, so a monitor can flag
//! them.

use std::fmt;

/// Client command specifiers (bits 7..5 of D0 in client-to-server frames).
pub mod ccs {
    /// Download segment request.
    pub const DOWNLOAD_SEGMENT: u8 = 0;
    /// Initiate download request.
    pub const INITIATE_DOWNLOAD: u8 = 1;
    /// Initiate upload request.
    pub const INITIATE_UPLOAD: u8 = 2;
    /// Upload segment request.
    pub const UPLOAD_SEGMENT: u8 = 3;
    /// Abort transfer.
    pub const ABORT: u8 = 4;
    /// Every client frame of a block upload.
    pub const BLOCK_UPLOAD: u8 = 5;
    /// Every client frame of a block download.
    pub const BLOCK_DOWNLOAD: u8 = 6;
}

/// Server command specifiers (bits 7..5 of D0 in server-to-client frames).
pub mod scs {
    /// Upload segment response.
    pub const UPLOAD_SEGMENT: u8 = 0;
    /// Download segment response.
    pub const DOWNLOAD_SEGMENT: u8 = 1;
    /// Initiate upload response.
    pub const INITIATE_UPLOAD: u8 = 2;
    /// Initiate download response.
    pub const INITIATE_DOWNLOAD: u8 = 3;
    /// Abort transfer.
    pub const ABORT: u8 = 4;
    /// Every server frame of a block download.
    pub const BLOCK_DOWNLOAD: u8 = 5;
    /// Every server frame of a block upload.
    pub const BLOCK_UPLOAD: u8 = 6;
}

/// The largest block size: a sub-block has 1 to 127 segments (CiA 301 §7.2.4.3.9).
pub const MAX_BLOCK_SIZE: u8 = 127;

/// Bytes of data in one segment.
pub const SEGMENT_DATA_LEN: usize = 7;

/// An object dictionary entry: index and sub-index (the SDO "multiplexer").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Multiplexer {
    /// The object index.
    pub index: u16,
    /// The sub-index.
    pub sub: u8,
}

impl Multiplexer {
    /// The entry `index`:`sub`.
    pub const fn new(index: u16, sub: u8) -> Multiplexer {
        Multiplexer { index, sub }
    }

    fn read(data: &[u8; 8]) -> Multiplexer {
        let [_, lo, hi, sub, ..] = *data;
        Multiplexer {
            index: u16::from_le_bytes([lo, hi]),
            sub,
        }
    }

    fn write(self, data: &mut [u8; 8]) {
        let [lo, hi] = self.index.to_le_bytes();
        data[1] = lo;
        data[2] = hi;
        data[3] = self.sub;
    }
}

/// `1018h:01`, the way CANopen documents write entries.
impl fmt::Display for Multiplexer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:04X}h:{:02X}", self.index, self.sub)
    }
}

/// What an initiate download request or initiate upload response carries (§7.2.4.3.3, §7.2.4.3.6).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum InitiateData {
    /// The whole value travels in this frame (e = 1): 1 to 4 bytes.
    Expedited {
        /// The value's bytes, little-endian.
        data: Vec<u8>,
        /// Whether the frame states the size (s = 1). Without it, 4 bytes are sent and the receiver
        /// must know the real size.
        size_indicated: bool,
    },
    /// Segments follow (e = 0).
    Segmented {
        /// The total size in bytes, if indicated (s = 1).
        size: Option<u32>,
    },
}

impl InitiateData {
    /// The expedited value as a little-endian integer, or `None` for a segmented transfer.
    pub fn expedited_value(&self) -> Option<u32> {
        match self {
            InitiateData::Expedited { data, .. } => Some(le_u32(data)),
            InitiateData::Segmented { .. } => None,
        }
    }

    fn read(command: u8, data: &[u8; 8]) -> InitiateData {
        let n = usize::from((command >> 2) & 0x3);
        let expedited = command & 0x02 != 0;
        let size_indicated = command & 0x01 != 0;
        let payload = data.get(4..).unwrap_or_default();
        match (expedited, size_indicated) {
            (true, true) => InitiateData::Expedited {
                data: payload.get(..4 - n).unwrap_or_default().to_vec(),
                size_indicated: true,
            },
            (true, false) => InitiateData::Expedited {
                data: payload.to_vec(),
                size_indicated: false,
            },
            (false, true) => InitiateData::Segmented {
                size: Some(le_u32(payload)),
            },
            (false, false) => InitiateData::Segmented { size: None },
        }
    }

    /// The low 4 bits of the command byte and D4..D7.
    fn write(&self, data: &mut [u8; 8]) -> Result<u8, SdoEncodeError> {
        match self {
            InitiateData::Expedited {
                data: value,
                size_indicated,
            } => {
                if value.is_empty() || value.len() > 4 {
                    return Err(SdoEncodeError::ExpeditedLength(value.len()));
                }
                for (slot, byte) in data.iter_mut().skip(4).zip(value) {
                    *slot = *byte;
                }
                if *size_indicated {
                    // The length is 1 to 4 here, so n = 4 - len fits in 2 bits.
                    let n = (4 - value.len()) as u8;
                    Ok((n << 2) | 0x03)
                } else {
                    Ok(0x02)
                }
            }
            InitiateData::Segmented { size: Some(size) } => {
                write_u32(data, *size);
                Ok(0x01)
            }
            InitiateData::Segmented { size: None } => Ok(0x00),
        }
    }

    /// Reserved bits: bit 4 of D0, n when it is not meaningful, D4..D7 when nothing is in them.
    fn reserved_mask(&self) -> [u8; 8] {
        match self {
            InitiateData::Expedited {
                size_indicated: true, ..
            } => [0x10, 0, 0, 0, 0, 0, 0, 0],
            InitiateData::Expedited {
                size_indicated: false,
                ..
            }
            | InitiateData::Segmented { size: Some(_) } => [0x1C, 0, 0, 0, 0, 0, 0, 0],
            InitiateData::Segmented { size: None } => [0x1C, 0, 0, 0, 0xFF, 0xFF, 0xFF, 0xFF],
        }
    }
}

/// A segment of a segmented transfer (§7.2.4.3.4, §7.2.4.3.7).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Segment {
    /// The toggle bit: 0 in the first segment, then alternating.
    pub toggle: bool,
    /// The segment data, 0 to 7 bytes (a conforming sender sends at least 1).
    pub data: Vec<u8>,
    /// Whether this is the last segment (c = 1).
    pub last: bool,
}

impl Segment {
    fn read(command: u8, data: &[u8; 8]) -> Segment {
        let n = usize::from((command >> 1) & 0x7);
        Segment {
            toggle: command & 0x10 != 0,
            data: data.get(1..8 - n).unwrap_or_default().to_vec(),
            last: command & 0x01 != 0,
        }
    }

    fn write(&self, specifier: u8, data: &mut [u8; 8]) -> Result<(), SdoEncodeError> {
        if self.data.len() > SEGMENT_DATA_LEN {
            return Err(SdoEncodeError::SegmentLength(self.data.len()));
        }
        // At most 7 bytes, so n = 7 - len fits in 3 bits.
        let n = (SEGMENT_DATA_LEN - self.data.len()) as u8;
        data[0] = (specifier << 5) | (u8::from(self.toggle) << 4) | (n << 1) | u8::from(self.last);
        for (slot, byte) in data.iter_mut().skip(1).zip(&self.data) {
            *slot = *byte;
        }
        Ok(())
    }
}

/// A segment of a block sub-block (§7.2.4.3.10, §7.2.4.3.14): D0 = c (bit 7) and the sequence number.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct BlockSegment {
    /// Whether this is the last segment of the whole transfer (c = 1).
    pub last: bool,
    /// The sequence number in the sub-block, 1 to the block size (0 is invalid).
    pub seqno: u8,
    /// Seven data bytes; how many of the last segment are used is told by the end frame.
    pub data: [u8; 7],
}

impl BlockSegment {
    /// Reads a segment; every 8-byte frame reads as one, so only call this when a segment is due.
    pub fn parse(data: &[u8; 8]) -> BlockSegment {
        let [command, d1, d2, d3, d4, d5, d6, d7] = *data;
        BlockSegment {
            last: command & 0x80 != 0,
            seqno: command & 0x7F,
            data: [d1, d2, d3, d4, d5, d6, d7],
        }
    }

    /// The 8 data bytes.
    pub fn encode(&self) -> Result<[u8; 8], SdoEncodeError> {
        if self.seqno == 0 || self.seqno > MAX_BLOCK_SIZE {
            return Err(SdoEncodeError::SequenceNumber(self.seqno));
        }
        let [d1, d2, d3, d4, d5, d6, d7] = self.data;
        Ok([
            (u8::from(self.last) << 7) | self.seqno,
            d1,
            d2,
            d3,
            d4,
            d5,
            d6,
            d7,
        ])
    }
}

/// A client-to-server SDO frame (other than a block segment).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum SdoRequest {
    /// Start writing an entry, with the value (expedited) or its size (segmented).
    InitiateDownload {
        /// The entry.
        mux: Multiplexer,
        /// The value or the size.
        data: InitiateData,
    },
    /// One segment of a segmented download.
    DownloadSegment(Segment),
    /// Start reading an entry.
    InitiateUpload {
        /// The entry.
        mux: Multiplexer,
    },
    /// Ask for the next segment of a segmented upload.
    UploadSegment {
        /// The toggle bit of the segment asked for.
        toggle: bool,
    },
    /// Abort the transfer.
    Abort {
        /// The entry.
        mux: Multiplexer,
        /// The abort code, see [`crate::abort_code_text`].
        code: u32,
    },
    /// Start a block download (§7.2.4.3.9).
    BlockDownloadInitiate {
        /// The entry.
        mux: Multiplexer,
        /// Whether the client supports the CRC (cc).
        crc_supported: bool,
        /// The total size, if indicated.
        size: Option<u32>,
    },
    /// End a block download (§7.2.4.3.11).
    BlockDownloadEnd {
        /// Bytes of the last segment that carry no data (0 to 7).
        unused: u8,
        /// The CRC of all data, 0 unless both sides support it.
        crc: u16,
    },
    /// Start a block upload (§7.2.4.3.13).
    BlockUploadInitiate {
        /// The entry.
        mux: Multiplexer,
        /// Whether the client supports the CRC (cc).
        crc_supported: bool,
        /// Segments per sub-block, 1 to 127.
        blksize: u8,
        /// Protocol switch threshold: the server may answer with a normal upload up to this size.
        pst: u8,
    },
    /// Let the server start sending sub-blocks.
    BlockUploadStart,
    /// Acknowledge a sub-block of a block upload.
    BlockUploadAck {
        /// The last segment received in order.
        ackseq: u8,
        /// Segments in the next sub-block.
        blksize: u8,
    },
    /// Confirm the end of a block upload.
    BlockUploadEndResponse,
}

/// A server-to-client SDO frame (other than a block segment).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum SdoResponse {
    /// The value (expedited) or the size of the segments to follow.
    InitiateUpload {
        /// The entry.
        mux: Multiplexer,
        /// The value or the size.
        data: InitiateData,
    },
    /// One segment of a segmented upload.
    UploadSegment(Segment),
    /// The download was accepted (and, if expedited, done).
    InitiateDownload {
        /// The entry.
        mux: Multiplexer,
    },
    /// A download segment was accepted.
    DownloadSegment {
        /// The toggle bit of the acknowledged segment.
        toggle: bool,
    },
    /// Abort the transfer.
    Abort {
        /// The entry.
        mux: Multiplexer,
        /// The abort code, see [`crate::abort_code_text`].
        code: u32,
    },
    /// The block download may start.
    BlockDownloadInitiate {
        /// The entry.
        mux: Multiplexer,
        /// Whether the server supports the CRC (sc).
        crc_supported: bool,
        /// Segments per sub-block, 1 to 127.
        blksize: u8,
    },
    /// Acknowledge a sub-block of a block download.
    BlockDownloadAck {
        /// The last segment received in order.
        ackseq: u8,
        /// Segments in the next sub-block.
        blksize: u8,
    },
    /// Confirm the end of a block download.
    BlockDownloadEndResponse,
    /// The block upload may start.
    BlockUploadInitiate {
        /// The entry.
        mux: Multiplexer,
        /// Whether the server supports the CRC (sc).
        crc_supported: bool,
        /// The total size, if indicated.
        size: Option<u32>,
    },
    /// End a block upload.
    BlockUploadEnd {
        /// Bytes of the last segment that carry no data (0 to 7).
        unused: u8,
        /// The CRC of all data, 0 unless both sides support it.
        crc: u16,
    },
}

/// Why 8 bytes are not an SDO frame of the expected direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SdoParseError {
    /// The command byte has no meaning in this direction (abort code 0504 0001h).
    #[error("command byte {byte:#04X} is not a valid {direction} SDO command")]
    UnknownCommand {
        /// D0.
        byte: u8,
        /// "client" or "server".
        direction: &'static str,
    },
}

/// Why a frame cannot be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SdoEncodeError {
    /// Expedited transfers carry 1 to 4 bytes.
    #[error("expedited data carries 1 to 4 bytes, got {0}; use a segmented transfer for more")]
    ExpeditedLength(usize),
    /// Segments carry at most 7 bytes.
    #[error("an SDO segment carries at most 7 bytes, got {0}")]
    SegmentLength(usize),
    /// Block end frames have 3 bits for the unused byte count.
    #[error("the unused byte count of a block end frame is 0 to 7, got {0}")]
    UnusedBytes(u8),
    /// Sequence numbers are 1 to 127.
    #[error("a block segment sequence number is 1 to 127, got {0}")]
    SequenceNumber(u8),
}

fn le_u32(bytes: &[u8]) -> u32 {
    let mut word = [0; 4];
    for (slot, byte) in word.iter_mut().zip(bytes) {
        *slot = *byte;
    }
    u32::from_le_bytes(word)
}

fn write_u32(data: &mut [u8; 8], value: u32) {
    let [b0, b1, b2, b3] = value.to_le_bytes();
    data[4] = b0;
    data[5] = b1;
    data[6] = b2;
    data[7] = b3;
}

fn size_if(flag: bool, data: &[u8; 8]) -> Option<u32> {
    flag.then(|| le_u32(data.get(4..).unwrap_or_default()))
}

fn crc_at(data: &[u8; 8]) -> u16 {
    u16::from_le_bytes([data[1], data[2]])
}

fn end_frame(unused: u8, crc: u16) -> Result<[u8; 8], SdoEncodeError> {
    if unused > 7 {
        return Err(SdoEncodeError::UnusedBytes(unused));
    }
    let [lo, hi] = crc.to_le_bytes();
    Ok([0xC1 | (unused << 2), lo, hi, 0, 0, 0, 0, 0])
}

/// The reserved bits of D0 (`d0`) and of whole bytes `from..8`.
#[allow(
    clippy::indexing_slicing,
    reason = "byte 0 and bytes below 8 (the loop's bound) of an 8-byte array"
)]
const fn mask(d0: u8, from: usize) -> [u8; 8] {
    let mut bytes = [0; 8];
    bytes[0] = d0;
    let mut idx = from;
    while idx < 8 {
        bytes[idx] = 0xFF;
        idx += 1;
    }
    bytes
}

impl SdoRequest {
    /// Reads a client-to-server frame.
    pub fn parse(data: &[u8; 8]) -> Result<SdoRequest, SdoParseError> {
        let command = data[0];
        let mux = Multiplexer::read(data);
        Ok(match command >> 5 {
            ccs::DOWNLOAD_SEGMENT => SdoRequest::DownloadSegment(Segment::read(command, data)),
            ccs::INITIATE_DOWNLOAD => SdoRequest::InitiateDownload {
                mux,
                data: InitiateData::read(command, data),
            },
            ccs::INITIATE_UPLOAD => SdoRequest::InitiateUpload { mux },
            ccs::UPLOAD_SEGMENT => SdoRequest::UploadSegment {
                toggle: command & 0x10 != 0,
            },
            ccs::ABORT => SdoRequest::Abort {
                mux,
                code: le_u32(data.get(4..).unwrap_or_default()),
            },
            ccs::BLOCK_UPLOAD => match command & 0x03 {
                0 => SdoRequest::BlockUploadInitiate {
                    mux,
                    crc_supported: command & 0x04 != 0,
                    blksize: data[4],
                    pst: data[5],
                },
                1 => SdoRequest::BlockUploadEndResponse,
                2 => SdoRequest::BlockUploadAck {
                    ackseq: data[1],
                    blksize: data[2],
                },
                _ => SdoRequest::BlockUploadStart,
            },
            ccs::BLOCK_DOWNLOAD => {
                if command & 0x01 == 0 {
                    SdoRequest::BlockDownloadInitiate {
                        mux,
                        crc_supported: command & 0x04 != 0,
                        size: size_if(command & 0x02 != 0, data),
                    }
                } else {
                    SdoRequest::BlockDownloadEnd {
                        unused: (command >> 2) & 0x07,
                        crc: crc_at(data),
                    }
                }
            }
            _ => {
                return Err(SdoParseError::UnknownCommand {
                    byte: command,
                    direction: "client",
                });
            }
        })
    }

    /// The 8 data bytes, reserved bits 0.
    pub fn encode(&self) -> Result<[u8; 8], SdoEncodeError> {
        let mut data = [0; 8];
        match self {
            SdoRequest::InitiateDownload { mux, data: init } => {
                mux.write(&mut data);
                data[0] = (ccs::INITIATE_DOWNLOAD << 5) | init.write(&mut data)?;
            }
            SdoRequest::DownloadSegment(segment) => segment.write(ccs::DOWNLOAD_SEGMENT, &mut data)?,
            SdoRequest::InitiateUpload { mux } => {
                mux.write(&mut data);
                data[0] = ccs::INITIATE_UPLOAD << 5;
            }
            SdoRequest::UploadSegment { toggle } => {
                data[0] = (ccs::UPLOAD_SEGMENT << 5) | (u8::from(*toggle) << 4)
            }
            SdoRequest::Abort { mux, code } => {
                mux.write(&mut data);
                write_u32(&mut data, *code);
                data[0] = ccs::ABORT << 5;
            }
            SdoRequest::BlockDownloadInitiate {
                mux,
                crc_supported,
                size,
            } => {
                mux.write(&mut data);
                if let Some(size) = size {
                    write_u32(&mut data, *size);
                }
                data[0] = (ccs::BLOCK_DOWNLOAD << 5)
                    | (u8::from(*crc_supported) << 2)
                    | (u8::from(size.is_some()) << 1);
            }
            SdoRequest::BlockDownloadEnd { unused, crc } => data = end_frame(*unused, *crc)?,
            SdoRequest::BlockUploadInitiate {
                mux,
                crc_supported,
                blksize,
                pst,
            } => {
                mux.write(&mut data);
                data[0] = (ccs::BLOCK_UPLOAD << 5) | (u8::from(*crc_supported) << 2);
                data[4] = *blksize;
                data[5] = *pst;
            }
            SdoRequest::BlockUploadStart => data[0] = 0xA3,
            SdoRequest::BlockUploadAck { ackseq, blksize } => data = [0xA2, *ackseq, *blksize, 0, 0, 0, 0, 0],
            SdoRequest::BlockUploadEndResponse => data[0] = 0xA1,
        }
        Ok(data)
    }

    /// The bits CiA 301 reserves in this frame (a conforming client sends them as 0).
    ///
    /// Unused data bytes of expedited frames and segments are not included: CiA 301 leaves their
    /// content open.
    pub fn reserved_mask(&self) -> [u8; 8] {
        match self {
            SdoRequest::InitiateDownload { data, .. } => data.reserved_mask(),
            SdoRequest::DownloadSegment(_) => [0; 8],
            SdoRequest::InitiateUpload { .. } => mask(0x1F, 4),
            SdoRequest::UploadSegment { .. } => mask(0x0F, 1),
            SdoRequest::Abort { .. } => mask(0x1F, 8),
            SdoRequest::BlockDownloadInitiate { size: Some(_), .. } => mask(0x18, 8),
            SdoRequest::BlockDownloadInitiate { size: None, .. } => mask(0x18, 4),
            SdoRequest::BlockDownloadEnd { .. } => mask(0x02, 3),
            SdoRequest::BlockUploadInitiate { .. } => mask(0x18, 6),
            SdoRequest::BlockUploadStart | SdoRequest::BlockUploadEndResponse => mask(0x1C, 1),
            SdoRequest::BlockUploadAck { .. } => mask(0x1C, 3),
        }
    }
}

impl SdoResponse {
    /// Reads a server-to-client frame.
    pub fn parse(data: &[u8; 8]) -> Result<SdoResponse, SdoParseError> {
        let command = data[0];
        let mux = Multiplexer::read(data);
        Ok(match command >> 5 {
            scs::UPLOAD_SEGMENT => SdoResponse::UploadSegment(Segment::read(command, data)),
            scs::DOWNLOAD_SEGMENT => SdoResponse::DownloadSegment {
                toggle: command & 0x10 != 0,
            },
            scs::INITIATE_UPLOAD => SdoResponse::InitiateUpload {
                mux,
                data: InitiateData::read(command, data),
            },
            scs::INITIATE_DOWNLOAD => SdoResponse::InitiateDownload { mux },
            scs::ABORT => SdoResponse::Abort {
                mux,
                code: le_u32(data.get(4..).unwrap_or_default()),
            },
            scs::BLOCK_DOWNLOAD => match command & 0x03 {
                0 => SdoResponse::BlockDownloadInitiate {
                    mux,
                    crc_supported: command & 0x04 != 0,
                    blksize: data[4],
                },
                1 => SdoResponse::BlockDownloadEndResponse,
                2 => SdoResponse::BlockDownloadAck {
                    ackseq: data[1],
                    blksize: data[2],
                },
                _ => {
                    return Err(SdoParseError::UnknownCommand {
                        byte: command,
                        direction: "server",
                    });
                }
            },
            scs::BLOCK_UPLOAD => {
                if command & 0x01 == 0 {
                    SdoResponse::BlockUploadInitiate {
                        mux,
                        crc_supported: command & 0x04 != 0,
                        size: size_if(command & 0x02 != 0, data),
                    }
                } else {
                    SdoResponse::BlockUploadEnd {
                        unused: (command >> 2) & 0x07,
                        crc: crc_at(data),
                    }
                }
            }
            _ => {
                return Err(SdoParseError::UnknownCommand {
                    byte: command,
                    direction: "server",
                });
            }
        })
    }

    /// The 8 data bytes, reserved bits 0.
    pub fn encode(&self) -> Result<[u8; 8], SdoEncodeError> {
        let mut data = [0; 8];
        match self {
            SdoResponse::InitiateUpload { mux, data: init } => {
                mux.write(&mut data);
                data[0] = (scs::INITIATE_UPLOAD << 5) | init.write(&mut data)?;
            }
            SdoResponse::UploadSegment(segment) => segment.write(scs::UPLOAD_SEGMENT, &mut data)?,
            SdoResponse::InitiateDownload { mux } => {
                mux.write(&mut data);
                data[0] = scs::INITIATE_DOWNLOAD << 5;
            }
            SdoResponse::DownloadSegment { toggle } => {
                data[0] = (scs::DOWNLOAD_SEGMENT << 5) | (u8::from(*toggle) << 4);
            }
            SdoResponse::Abort { mux, code } => {
                mux.write(&mut data);
                write_u32(&mut data, *code);
                data[0] = scs::ABORT << 5;
            }
            SdoResponse::BlockDownloadInitiate {
                mux,
                crc_supported,
                blksize,
            } => {
                mux.write(&mut data);
                data[0] = (scs::BLOCK_DOWNLOAD << 5) | (u8::from(*crc_supported) << 2);
                data[4] = *blksize;
            }
            SdoResponse::BlockDownloadAck { ackseq, blksize } => {
                data = [0xA2, *ackseq, *blksize, 0, 0, 0, 0, 0]
            }
            SdoResponse::BlockDownloadEndResponse => data[0] = 0xA1,
            SdoResponse::BlockUploadInitiate {
                mux,
                crc_supported,
                size,
            } => {
                mux.write(&mut data);
                if let Some(size) = size {
                    write_u32(&mut data, *size);
                }
                data[0] = (scs::BLOCK_UPLOAD << 5)
                    | (u8::from(*crc_supported) << 2)
                    | (u8::from(size.is_some()) << 1);
            }
            SdoResponse::BlockUploadEnd { unused, crc } => data = end_frame(*unused, *crc)?,
        }
        Ok(data)
    }

    /// The bits CiA 301 reserves in this frame (a conforming server sends them as 0).
    ///
    /// Unused data bytes of expedited frames and segments are not included: CiA 301 leaves their
    /// content open.
    pub fn reserved_mask(&self) -> [u8; 8] {
        match self {
            SdoResponse::InitiateUpload { data, .. } => data.reserved_mask(),
            SdoResponse::UploadSegment(_) => [0; 8],
            SdoResponse::InitiateDownload { .. } => mask(0x1F, 4),
            SdoResponse::DownloadSegment { .. } => mask(0x0F, 1),
            SdoResponse::Abort { .. } => mask(0x1F, 8),
            SdoResponse::BlockDownloadInitiate { .. } => mask(0x18, 5),
            SdoResponse::BlockDownloadAck { .. } => mask(0x1C, 3),
            SdoResponse::BlockDownloadEndResponse => mask(0x1C, 1),
            SdoResponse::BlockUploadInitiate { size: Some(_), .. } => mask(0x18, 8),
            SdoResponse::BlockUploadInitiate { size: None, .. } => mask(0x18, 4),
            SdoResponse::BlockUploadEnd { .. } => mask(0x02, 3),
        }
    }
}

/// The reserved bits that are set in `data`, as "D0 & 1Fh = 03h" fragments; empty if none.
pub fn reserved_bits_set(data: &[u8; 8], reserved: &[u8; 8]) -> Vec<String> {
    data.iter()
        .zip(reserved)
        .enumerate()
        .filter(|(_, (byte, mask))| *byte & *mask != 0)
        .map(|(idx, (byte, mask))| {
            if *mask == 0xFF {
                format!("D{idx} = {byte:02X}h")
            } else {
                format!("D{idx} & {mask:02X}h = {:02X}h", byte & mask)
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const MUX_1018_01: Multiplexer = Multiplexer::new(0x1018, 0x01);

    #[test]
    fn worked_examples_from_the_reference() {
        // Read 1018h:01 of node 5 and the 4-byte reply.
        let request = SdoRequest::parse(&[0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0]).unwrap();
        assert_eq!(request, SdoRequest::InitiateUpload { mux: MUX_1018_01 });
        let reply = SdoResponse::parse(&[0x43, 0x18, 0x10, 0x01, 0x78, 0x56, 0x34, 0x12]).unwrap();
        let SdoResponse::InitiateUpload { mux, data } = &reply else {
            panic!("not an upload: {reply:?}")
        };
        assert_eq!(*mux, MUX_1018_01);
        assert_eq!(data.expedited_value(), Some(0x1234_5678));
        // Write UNSIGNED16 1017h = 1000 ms: 2Bh = n 2.
        let write = SdoRequest::InitiateDownload {
            mux: Multiplexer::new(0x1017, 0),
            data: InitiateData::Expedited {
                data: vec![0xE8, 0x03],
                size_indicated: true,
            },
        };
        assert_eq!(
            write.encode().unwrap(),
            [0x2B, 0x17, 0x10, 0x00, 0xE8, 0x03, 0, 0]
        );
        // Segmented upload announcing 10 bytes, last segment with 3 bytes and t = 1: D0 = 19h.
        let announce = SdoResponse::parse(&[0x41, 0x08, 0x10, 0x00, 0x0A, 0, 0, 0]).unwrap();
        assert_eq!(
            announce,
            SdoResponse::InitiateUpload {
                mux: Multiplexer::new(0x1008, 0),
                data: InitiateData::Segmented { size: Some(10) }
            }
        );
        let last = SdoResponse::parse(&[0x19, b'a', b'b', b'c', 0, 0, 0, 0]).unwrap();
        assert_eq!(
            last,
            SdoResponse::UploadSegment(Segment {
                toggle: true,
                data: b"abc".to_vec(),
                last: true
            })
        );
        // Abort "object does not exist" for 1004h:00.
        let abort = SdoResponse::parse(&[0x80, 0x04, 0x10, 0x00, 0x00, 0x00, 0x02, 0x06]).unwrap();
        assert_eq!(
            abort,
            SdoResponse::Abort {
                mux: Multiplexer::new(0x1004, 0),
                code: 0x0602_0000
            }
        );
    }

    #[test]
    fn expedited_command_bytes_by_size() {
        for (len, command) in [(1, 0x2F), (2, 0x2B), (3, 0x27), (4, 0x23)] {
            let request = SdoRequest::InitiateDownload {
                mux: MUX_1018_01,
                data: InitiateData::Expedited {
                    data: vec![0xAA; len],
                    size_indicated: true,
                },
            };
            assert_eq!(request.encode().unwrap()[0], command);
        }
    }

    #[test]
    fn block_frames_from_a_conformance_trace() {
        // CiA CCT "SDO 23": block upload of 1008h with CRC.
        let initiate = SdoRequest::parse(&[0xA4, 0x08, 0x10, 0x00, 0x14, 0, 0, 0]).unwrap();
        assert_eq!(
            initiate,
            SdoRequest::BlockUploadInitiate {
                mux: Multiplexer::new(0x1008, 0),
                crc_supported: true,
                blksize: 20,
                pst: 0
            }
        );
        let response = SdoResponse::parse(&[0xC6, 0x08, 0x10, 0x00, 0x10, 0, 0, 0]).unwrap();
        assert_eq!(
            response,
            SdoResponse::BlockUploadInitiate {
                mux: Multiplexer::new(0x1008, 0),
                crc_supported: true,
                size: Some(16)
            }
        );
        assert_eq!(
            SdoRequest::parse(&[0xA3, 0, 0, 0, 0, 0, 0, 0]).unwrap(),
            SdoRequest::BlockUploadStart
        );
        let segment = BlockSegment::parse(&[0x83, 0x33, 0x32, 0, 0, 0, 0, 0]);
        assert!(segment.last);
        assert_eq!(segment.seqno, 3);
        assert_eq!(
            SdoRequest::parse(&[0xA2, 0x03, 0x14, 0, 0, 0, 0, 0]).unwrap(),
            SdoRequest::BlockUploadAck {
                ackseq: 3,
                blksize: 20
            }
        );
        assert_eq!(
            SdoResponse::parse(&[0xD5, 0xF3, 0x43, 0, 0, 0, 0, 0]).unwrap(),
            SdoResponse::BlockUploadEnd {
                unused: 5,
                crc: 0x43F3
            }
        );
        assert_eq!(
            SdoRequest::parse(&[0xA1, 0, 0, 0, 0, 0, 0, 0]).unwrap(),
            SdoRequest::BlockUploadEndResponse
        );
        // "SDO 25": block download initiate response with blksize 127.
        assert_eq!(
            SdoResponse::parse(&[0xA4, 0x17, 0x10, 0x00, 0x7F, 0, 0, 0]).unwrap(),
            SdoResponse::BlockDownloadInitiate {
                mux: Multiplexer::new(0x1017, 0),
                crc_supported: true,
                blksize: 127
            }
        );
    }

    #[test]
    fn unknown_specifiers_are_errors() {
        assert!(SdoRequest::parse(&[0xE0, 0, 0, 0, 0, 0, 0, 0]).is_err());
        assert!(SdoResponse::parse(&[0xE0, 0, 0, 0, 0, 0, 0, 0]).is_err());
        assert_eq!(
            SdoResponse::parse(&[0xA3, 0, 0, 0, 0, 0, 0, 0]),
            Err(SdoParseError::UnknownCommand {
                byte: 0xA3,
                direction: "server"
            })
        );
    }

    #[test]
    fn encode_rejects_what_the_frame_cannot_hold() {
        let too_long = SdoRequest::InitiateDownload {
            mux: MUX_1018_01,
            data: InitiateData::Expedited {
                data: vec![0; 5],
                size_indicated: true,
            },
        };
        assert_eq!(too_long.encode(), Err(SdoEncodeError::ExpeditedLength(5)));
        let segment = SdoRequest::DownloadSegment(Segment {
            toggle: false,
            data: vec![0; 8],
            last: false,
        });
        assert_eq!(segment.encode(), Err(SdoEncodeError::SegmentLength(8)));
        assert_eq!(
            SdoRequest::BlockDownloadEnd { unused: 8, crc: 0 }.encode(),
            Err(SdoEncodeError::UnusedBytes(8))
        );
        let zero_seq = BlockSegment {
            last: false,
            seqno: 0,
            data: [0; 7],
        };
        assert_eq!(zero_seq.encode(), Err(SdoEncodeError::SequenceNumber(0)));
    }

    #[test]
    fn reserved_bits_are_reported() {
        let data = [0x43, 0x18, 0x10, 0x01, 0, 0, 0, 0];
        let request = SdoRequest::parse(&data).unwrap();
        assert_eq!(
            reserved_bits_set(&data, &request.reserved_mask()),
            vec!["D0 & 1Fh = 03h"]
        );
        let clean = [0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0];
        assert!(reserved_bits_set(&clean, &request.reserved_mask()).is_empty());
        let dirty_tail = [0x60, 0, 0, 0, 0, 0, 0, 0x55];
        let request = SdoRequest::parse(&dirty_tail).unwrap();
        assert_eq!(
            reserved_bits_set(&dirty_tail, &request.reserved_mask()),
            vec!["D7 = 55h"]
        );
    }

    fn any_mux() -> impl Strategy<Value = Multiplexer> {
        (any::<u16>(), any::<u8>()).prop_map(|(index, sub)| Multiplexer { index, sub })
    }

    fn any_init() -> impl Strategy<Value = InitiateData> {
        prop_oneof![
            proptest::collection::vec(any::<u8>(), 1..=4).prop_map(|data| InitiateData::Expedited {
                data,
                size_indicated: true
            }),
            proptest::collection::vec(any::<u8>(), 4..=4).prop_map(|data| InitiateData::Expedited {
                data,
                size_indicated: false
            }),
            proptest::option::of(any::<u32>()).prop_map(|size| InitiateData::Segmented { size }),
        ]
    }

    fn any_segment() -> impl Strategy<Value = Segment> {
        (
            any::<bool>(),
            proptest::collection::vec(any::<u8>(), 0..=7),
            any::<bool>(),
        )
            .prop_map(|(toggle, data, last)| Segment { toggle, data, last })
    }

    fn any_request() -> impl Strategy<Value = SdoRequest> {
        prop_oneof![
            (any_mux(), any_init()).prop_map(|(mux, data)| SdoRequest::InitiateDownload { mux, data }),
            any_segment().prop_map(SdoRequest::DownloadSegment),
            any_mux().prop_map(|mux| SdoRequest::InitiateUpload { mux }),
            any::<bool>().prop_map(|toggle| SdoRequest::UploadSegment { toggle }),
            (any_mux(), any::<u32>()).prop_map(|(mux, code)| SdoRequest::Abort { mux, code }),
            (any_mux(), any::<bool>(), proptest::option::of(any::<u32>())).prop_map(
                |(mux, crc_supported, size)| SdoRequest::BlockDownloadInitiate {
                    mux,
                    crc_supported,
                    size
                }
            ),
            (0u8..=7, any::<u16>()).prop_map(|(unused, crc)| SdoRequest::BlockDownloadEnd { unused, crc }),
            (any_mux(), any::<bool>(), any::<u8>(), any::<u8>()).prop_map(
                |(mux, crc_supported, blksize, pst)| SdoRequest::BlockUploadInitiate {
                    mux,
                    crc_supported,
                    blksize,
                    pst
                }
            ),
            Just(SdoRequest::BlockUploadStart),
            (any::<u8>(), any::<u8>())
                .prop_map(|(ackseq, blksize)| SdoRequest::BlockUploadAck { ackseq, blksize }),
            Just(SdoRequest::BlockUploadEndResponse),
        ]
    }

    fn any_response() -> impl Strategy<Value = SdoResponse> {
        prop_oneof![
            (any_mux(), any_init()).prop_map(|(mux, data)| SdoResponse::InitiateUpload { mux, data }),
            any_segment().prop_map(SdoResponse::UploadSegment),
            any_mux().prop_map(|mux| SdoResponse::InitiateDownload { mux }),
            any::<bool>().prop_map(|toggle| SdoResponse::DownloadSegment { toggle }),
            (any_mux(), any::<u32>()).prop_map(|(mux, code)| SdoResponse::Abort { mux, code }),
            (any_mux(), any::<bool>(), any::<u8>()).prop_map(|(mux, crc_supported, blksize)| {
                SdoResponse::BlockDownloadInitiate {
                    mux,
                    crc_supported,
                    blksize,
                }
            }),
            (any::<u8>(), any::<u8>())
                .prop_map(|(ackseq, blksize)| SdoResponse::BlockDownloadAck { ackseq, blksize }),
            Just(SdoResponse::BlockDownloadEndResponse),
            (any_mux(), any::<bool>(), proptest::option::of(any::<u32>())).prop_map(
                |(mux, crc_supported, size)| SdoResponse::BlockUploadInitiate {
                    mux,
                    crc_supported,
                    size
                }
            ),
            (0u8..=7, any::<u16>()).prop_map(|(unused, crc)| SdoResponse::BlockUploadEnd { unused, crc }),
        ]
    }

    proptest! {
        #[test]
        fn requests_round_trip_with_clean_reserved_bits(request in any_request()) {
            let bytes = request.encode().unwrap();
            prop_assert!(reserved_bits_set(&bytes, &request.reserved_mask()).is_empty());
            prop_assert_eq!(SdoRequest::parse(&bytes), Ok(request));
        }

        #[test]
        fn responses_round_trip_with_clean_reserved_bits(response in any_response()) {
            let bytes = response.encode().unwrap();
            prop_assert!(reserved_bits_set(&bytes, &response.reserved_mask()).is_empty());
            prop_assert_eq!(SdoResponse::parse(&bytes), Ok(response));
        }

        #[test]
        fn block_segments_round_trip(last: bool, seqno in 1u8..=127, data: [u8; 7]) {
            let segment = BlockSegment { last, seqno, data };
            prop_assert_eq!(BlockSegment::parse(&segment.encode().unwrap()), segment);
        }

        #[test]
        fn whatever_parses_re_encodes_to_the_same_meaning(data: [u8; 8]) {
            if let Ok(request) = SdoRequest::parse(&data) {
                let again = request.encode().unwrap();
                prop_assert_eq!(SdoRequest::parse(&again), Ok(request));
            }
            if let Ok(response) = SdoResponse::parse(&data) {
                let again = response.encode().unwrap();
                prop_assert_eq!(SdoResponse::parse(&again), Ok(response));
            }
        }
    }
}

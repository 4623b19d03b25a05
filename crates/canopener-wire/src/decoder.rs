//! The stateful monitor decoder: explains every frame on the bus as CANopen.
//!
//! Heads up: read CiA 301 §7.2.4.3 (SDO protocols) and §7.2.8.3.2 (error control) before changing
//! this file. Some frames can only be understood in context: an SDO block sub-block segment looks like
//! any other SDO frame, a segment's toggle bit is only right or wrong relative to the previous one, and
//! a node guarding response looks like a heartbeat. The decoder therefore follows, per node, the SDO
//! transfer in progress and the node guarding exchange. Its memory is fixed: one slot per node-id
//! (128), each holding fixed-size state, however long it runs and whatever it is fed.
//!
//! The decoder shows what is on the wire, including mistakes: a frame that breaks a rule is decoded as
//! far as possible and the broken rule is listed in [`Decoded::anomalies`]. Nothing here panics on any
//! frame or sequence of frames.

use std::time::Duration;

use canopener_can::{CanFrame, Instant};

use crate::cob::{LSS_MASTER_TO_SLAVE_ID, Service, classify};
use crate::crc::crc16_ccitt_update;
use crate::decoded::{
    CrcCheck, Decoded, EmcyPayload, ErrorControlPayload, LssPayload, Payload, SdoFrame, SdoPayload,
    TransferKind, TransferProgress,
};
use crate::emcy::{
    ERROR_REGISTER_GENERIC, ERROR_REGISTER_RESERVED, EmcyMessage, emcy_code_text, error_register_text,
};
use crate::lss::{LssRequest, LssResponse};
use crate::nmt::{GUARD_TOGGLE_BIT, NmtCommand, NmtState};
use crate::sdo::{
    BlockSegment, InitiateData, MAX_BLOCK_SIZE, Multiplexer, SEGMENT_DATA_LEN, SdoRequest, SdoResponse,
    reserved_bits_set,
};
use crate::time_of_day::{MILLIS_PER_DAY, TimeOfDay};

/// Node-ids 0 to 127: the decoder keeps one state slot for each.
const N_NODE_SLOTS: usize = 128;

/// The largest SYNC counter value (CiA 301 object 1019h: 2 to 240).
const MAX_SYNC_COUNTER: u8 = 240;

/// How long after a node guarding request (an RTR on 700h + node-ID) an error control frame of that
/// node is taken as its answer, when [`Decoder::decode_at`] knows the time: CiA 301 names no bound;
/// a master waits about this long (canopener's conformance tests wait 100 ms). A later frame is a
/// heartbeat, whatever came before.
pub const GUARD_RESPONSE_WINDOW: Duration = Duration::from_millis(100);

/// Decodes frames one after another, keeping the context that SDO transfers and node guarding need.
///
/// ```
/// use canopener_can::{CanFrame, StandardId};
/// use canopener_wire::Decoder;
///
/// let mut decoder = Decoder::new();
/// let frame = CanFrame::new(StandardId::new(0x000).unwrap(), &[0x01, 0x05]).unwrap();
/// assert_eq!(decoder.decode(&frame).to_string(), "NMT Start Remote Node -> node 5");
/// ```
#[derive(Debug, Clone)]
pub struct Decoder {
    transfers: [Option<Transfer>; N_NODE_SLOTS],
    guarding: [Guarding; N_NODE_SLOTS],
}

impl Default for Decoder {
    fn default() -> Decoder {
        Decoder::new()
    }
}

impl Decoder {
    /// A decoder that has seen nothing yet.
    pub fn new() -> Decoder {
        Decoder {
            transfers: std::array::from_fn(|_| None),
            guarding: [Guarding::default(); N_NODE_SLOTS],
        }
    }

    /// Decodes one frame and updates the context. Without the time a node guarding request stays
    /// open until an error control frame of its node comes; [`Decoder::decode_at`] closes it after
    /// [`GUARD_RESPONSE_WINDOW`].
    pub fn decode(&mut self, frame: &CanFrame) -> Decoded {
        self.decode_inner(None, frame)
    }

    /// [`Decoder::decode`] of a frame seen at `at` (any clock, as long as it is the same for every
    /// frame): a guarding response is a reply to a request within [`GUARD_RESPONSE_WINDOW`], so a
    /// heartbeat after an unanswered request is not taken for its answer.
    pub fn decode_at(&mut self, at: Instant, frame: &CanFrame) -> Decoded {
        self.decode_inner(Some(at), frame)
    }

    fn decode_inner(&mut self, at: Option<Instant>, frame: &CanFrame) -> Decoded {
        let class = classify(frame.id());
        let mut anomalies = Vec::new();
        if class.node == Some(0) {
            anomalies.push(format!(
                "node-id 0 in a {} CAN-ID; node-ids are 1 to 127 (CiA 301 7.3.5)",
                class.service
            ));
        }
        let mut node = class.node;
        let payload = match class.service {
            Service::Unknown => raw(frame),
            _ if frame.is_remote() && !remote_allowed(class.service) => {
                anomalies.push(format!(
                    "remote frame on the {} CAN-ID; only TPDOs and node guarding use remote frames",
                    class.service
                ));
                raw(frame)
            }
            Service::Nmt => {
                let (payload, target) = self.decode_nmt(frame, &mut anomalies);
                node = target;
                payload
            }
            Service::Sync => decode_sync(frame, &mut anomalies),
            Service::Emcy => decode_emcy(frame, &mut anomalies),
            Service::Time => decode_time(frame, &mut anomalies),
            Service::Tpdo(_) | Service::Rpdo(_) => {
                if frame.is_remote() {
                    Payload::PdoRequest { dlc: frame.dlc() }
                } else {
                    Payload::Pdo {
                        data: frame.data().to_vec(),
                    }
                }
            }
            Service::SdoTx | Service::SdoRx => {
                let slot = slot_index(class.node);
                self.decode_sdo(slot, class.service == Service::SdoRx, frame, &mut anomalies)
            }
            Service::ErrorControl => {
                self.decode_error_control(slot_index(class.node), at, frame, &mut anomalies)
            }
            Service::Lss => decode_lss(frame, &mut anomalies),
        };
        Decoded {
            id: frame.id(),
            service: class.service,
            node,
            payload,
            anomalies,
        }
    }

    fn decode_nmt(&mut self, frame: &CanFrame, anomalies: &mut Vec<String>) -> (Payload, Option<u8>) {
        let data = frame.data();
        if data.len() != 2 {
            anomalies.push(format!(
                "NMT command with DLC {}; CiA 301 7.2.8.3.1 requires 2",
                data.len()
            ));
        }
        let [raw_command, target, ..] = *data else {
            return (raw(frame), None);
        };
        let command = NmtCommand::from_raw(raw_command);
        if command.is_none() {
            anomalies.push(format!("unknown NMT command specifier 0x{raw_command:02X}"));
        }
        if target > 127 {
            anomalies.push(format!(
                "NMT target node {target} does not exist; node-ids are 1 to 127 and 0 addresses all nodes"
            ));
        }
        if matches!(
            command,
            Some(NmtCommand::ResetNode | NmtCommand::ResetCommunication)
        ) {
            // A reset ends every SDO transfer and restarts node guarding (toggle back to 0) on the
            // nodes it reaches.
            let targets = if target == 0 {
                0..N_NODE_SLOTS
            } else {
                usize::from(target)..usize::from(target) + 1
            };
            for idx in targets {
                if let Some(slot) = self.transfers.get_mut(idx) {
                    *slot = None;
                }
                if let Some(guarding) = self.guarding.get_mut(idx) {
                    *guarding = Guarding::default();
                }
            }
        }
        let node = (1..=127).contains(&target).then_some(target);
        (
            Payload::Nmt {
                command,
                raw_command,
                target,
            },
            node,
        )
    }

    fn decode_error_control(
        &mut self,
        slot: usize,
        at: Option<Instant>,
        frame: &CanFrame,
        anomalies: &mut Vec<String>,
    ) -> Payload {
        let Some(guarding) = self.guarding.get_mut(slot) else {
            // Unreachable: `slot_index` keeps the index below N_NODE_SLOTS.
            return raw(frame);
        };
        if frame.is_remote() {
            guarding.request_pending = true;
            guarding.request_at = at;
            return Payload::ErrorControl(ErrorControlPayload::GuardRequest);
        }
        if let (Some(now), Some(asked)) = (at, guarding.request_at)
            && now.saturating_duration_since(asked) > GUARD_RESPONSE_WINDOW
        {
            guarding.request_pending = false;
            guarding.request_at = None;
        }
        let data = frame.data();
        if data.len() != 1 {
            anomalies.push(format!(
                "error control frame with DLC {}; CiA 301 7.2.8.3.2 requires 1",
                data.len()
            ));
        }
        let Some(&byte) = data.first() else {
            return raw(frame);
        };
        if byte == 0x00 {
            // Boot-up: the node restarted, so guarding starts over with toggle 0.
            *guarding = Guarding::default();
            return Payload::ErrorControl(ErrorControlPayload::BootUp);
        }
        let raw_state = byte & !GUARD_TOGGLE_BIT;
        let toggle = byte & GUARD_TOGGLE_BIT != 0;
        let state = NmtState::from_raw(raw_state).filter(|state| *state != NmtState::BootUp);
        if state.is_none() {
            anomalies.push(format!(
                "state 0x{raw_state:02X} is not an NMT state (04h, 05h or 7Fh)"
            ));
        }
        if guarding.request_pending || toggle {
            if !guarding.request_pending {
                anomalies.push(
                    "toggle bit set without a node guarding request; heartbeats send bit 7 as 0".to_owned(),
                );
            }
            if guarding.last_toggle == Some(toggle) {
                anomalies.push(format!(
                    "node guarding toggle={} did not alternate (CiA 301 7.2.8.3.2.1)",
                    u8::from(toggle)
                ));
            }
            guarding.request_pending = false;
            guarding.last_toggle = Some(toggle);
            return Payload::ErrorControl(ErrorControlPayload::GuardResponse {
                state,
                raw_state,
                toggle,
            });
        }
        Payload::ErrorControl(ErrorControlPayload::Heartbeat { state, raw_state })
    }

    fn decode_sdo(
        &mut self,
        slot: usize,
        from_client: bool,
        frame: &CanFrame,
        anomalies: &mut Vec<String>,
    ) -> Payload {
        let data = frame.data();
        if data.len() != 8 {
            anomalies.push(format!(
                "SDO frame with DLC {}; CiA 301 7.2.4.3 requires 8 (missing bytes read as 0)",
                data.len()
            ));
        }
        if data.is_empty() {
            return raw(frame);
        }
        let mut bytes = [0u8; 8];
        for (slot_byte, byte) in bytes.iter_mut().zip(data) {
            *slot_byte = *byte;
        }
        let Some(transfer) = self.transfers.get_mut(slot) else {
            // Unreachable: `slot_index` keeps the index below N_NODE_SLOTS.
            return raw(frame);
        };

        // Abort (80h) is the one frame a block data sender may send in place of a segment: its
        // sequence number would be 0, which no segment has.
        if bytes[0] != 0x80
            && let Some(active) = transfer.as_mut()
            && let Phase::Block(block) = &mut active.phase
            && block.step == BlockStep::SubBlock
            && from_client == active.kind.is_download()
        {
            let segment = BlockSegment::parse(&bytes);
            block_segment(active, &segment, anomalies);
            let progress = Some(active.progress());
            return Payload::Sdo(SdoPayload {
                frame: SdoFrame::BlockSegment(segment),
                transfer: progress,
                crc: None,
            });
        }

        let outcome = if from_client {
            match SdoRequest::parse(&bytes) {
                Ok(request) => {
                    report_reserved(&bytes, &request.reserved_mask(), anomalies);
                    let outcome = apply_request(transfer, &request, anomalies);
                    (SdoFrame::Request(request), outcome)
                }
                Err(err) => {
                    anomalies.push(format!("{err} (the server answers with abort 0504 0001h)"));
                    (SdoFrame::Invalid { command: bytes[0] }, FrameEffect::default())
                }
            }
        } else {
            match SdoResponse::parse(&bytes) {
                Ok(response) => {
                    report_reserved(&bytes, &response.reserved_mask(), anomalies);
                    let outcome = apply_response(transfer, &response, anomalies);
                    (SdoFrame::Response(response), outcome)
                }
                Err(err) => {
                    anomalies.push(err.to_string());
                    (SdoFrame::Invalid { command: bytes[0] }, FrameEffect::default())
                }
            }
        };
        let (frame, FrameEffect { progress, crc }) = outcome;
        Payload::Sdo(SdoPayload {
            frame,
            transfer: progress,
            crc,
        })
    }
}

fn remote_allowed(service: Service) -> bool {
    matches!(service, Service::Tpdo(_) | Service::ErrorControl)
}

/// The state slot of a node-id; classification yields 0 to 127.
fn slot_index(node: Option<u8>) -> usize {
    usize::from(node.unwrap_or(0) & 0x7F)
}

fn raw(frame: &CanFrame) -> Payload {
    Payload::Raw {
        remote: frame.is_remote(),
        dlc: frame.dlc(),
        data: frame.data().to_vec(),
    }
}

fn decode_sync(frame: &CanFrame, anomalies: &mut Vec<String>) -> Payload {
    let data = frame.data();
    if data.len() > 1 {
        anomalies.push(format!(
            "SYNC with DLC {}; CiA 301 7.2.5.3 allows 0 or 1 (counter)",
            data.len()
        ));
    }
    let counter = data.first().copied();
    if let Some(counter) = counter
        && !(1..=MAX_SYNC_COUNTER).contains(&counter)
    {
        anomalies.push(format!(
            "SYNC counter {counter} is outside 1 to {MAX_SYNC_COUNTER}"
        ));
    }
    Payload::Sync { counter }
}

fn decode_emcy(frame: &CanFrame, anomalies: &mut Vec<String>) -> Payload {
    let data = frame.data();
    if data.len() != 8 {
        anomalies.push(format!(
            "EMCY with DLC {}; CiA 301 7.2.7.3.1 requires 8",
            data.len()
        ));
    }
    let Ok(emcy) = EmcyMessage::parse(data) else {
        return raw(frame);
    };
    if emcy.register & ERROR_REGISTER_RESERVED != 0 {
        anomalies.push("error register bit 6 is reserved and must be 0 (CiA 301 object 1001h)".to_owned());
    }
    if emcy.code != 0 && emcy.register & ERROR_REGISTER_GENERIC == 0 {
        anomalies.push(format!(
            "error register bit 0 (generic) is clear although error code 0x{:04X} reports an error",
            emcy.code
        ));
    }
    Payload::Emcy(EmcyPayload {
        code: emcy.code,
        code_text: emcy_code_text(emcy.code),
        register: emcy.register,
        register_text: error_register_text(emcy.register),
        vendor: data.get(3..).unwrap_or_default().to_vec(),
    })
}

fn decode_time(frame: &CanFrame, anomalies: &mut Vec<String>) -> Payload {
    let data = frame.data();
    if data.len() != 6 {
        anomalies.push(format!(
            "TIME with DLC {}; CiA 301 7.2.6.3 requires 6",
            data.len()
        ));
    }
    let Ok(time) = TimeOfDay::parse(data) else {
        return raw(frame);
    };
    if TimeOfDay::reserved_bits(data) != 0 {
        anomalies.push("the reserved top 4 bits of the milliseconds are not 0".to_owned());
    }
    if time.millis >= MILLIS_PER_DAY {
        anomalies.push(format!("{} ms after midnight is more than a day", time.millis));
    }
    Payload::Time(time)
}

fn decode_lss(frame: &CanFrame, anomalies: &mut Vec<String>) -> Payload {
    let data = frame.data();
    if data.len() != 8 {
        anomalies.push(format!(
            "LSS frame with DLC {}; CiA 305 requires 8 (missing bytes read as 0)",
            data.len()
        ));
    }
    if data.is_empty() {
        return raw(frame);
    }
    let mut bytes = [0u8; 8];
    for (slot, byte) in bytes.iter_mut().zip(data) {
        *slot = *byte;
    }
    let from_master = frame.id().as_raw() == u32::from(LSS_MASTER_TO_SLAVE_ID);
    let parsed = if from_master {
        LssRequest::parse(&bytes).map(|request| (LssPayload::Request(request), request.used_len()))
    } else {
        LssResponse::parse(&bytes).map(|response| (LssPayload::Response(response), response.used_len()))
    };
    match parsed {
        Ok((payload, used_len)) => {
            let dirty: Vec<String> = bytes
                .iter()
                .enumerate()
                .skip(used_len)
                .filter(|(_, byte)| **byte != 0)
                .map(|(idx, byte)| format!("D{idx} = {byte:02X}h"))
                .collect();
            if !dirty.is_empty() {
                anomalies.push(format!("reserved bytes are not 0: {}", dirty.join(", ")));
            }
            if let LssPayload::Request(LssRequest::SwitchStateGlobal { mode }) = payload
                && mode > 1
            {
                anomalies.push(format!(
                    "switch state global mode {mode} is neither 0 (waiting) nor 1 (configuration)"
                ));
            }
            Payload::Lss(payload)
        }
        Err(err) => {
            anomalies.push(err.to_string());
            raw(frame)
        }
    }
}

fn report_reserved(bytes: &[u8; 8], mask: &[u8; 8], anomalies: &mut Vec<String>) {
    let set = reserved_bits_set(bytes, mask);
    if !set.is_empty() {
        anomalies.push(format!("reserved bits are not 0: {}", set.join(", ")));
    }
}

/// Node guarding context of one node.
#[derive(Debug, Clone, Copy, Default)]
struct Guarding {
    /// A remote request was seen and not answered yet.
    request_pending: bool,
    /// When that request was seen, if the decoder was told.
    request_at: Option<Instant>,
    /// The toggle bit of the last response since guarding (re)started.
    last_toggle: Option<bool>,
}

/// The SDO transfer in progress on one node's default SDO server.
#[derive(Debug, Clone)]
struct Transfer {
    mux: Multiplexer,
    kind: TransferKind,
    size: Option<u32>,
    bytes: u64,
    phase: Phase,
}

impl Transfer {
    fn new(mux: Multiplexer, kind: TransferKind, size: Option<u32>, phase: Phase) -> Transfer {
        Transfer {
            mux,
            kind,
            size,
            bytes: 0,
            phase,
        }
    }

    fn progress(&self) -> TransferProgress {
        TransferProgress {
            mux: self.mux,
            kind: self.kind,
            bytes: self.bytes,
            size: self.size,
        }
    }

    fn check_not_beyond_size(&self, anomalies: &mut Vec<String>) {
        if let Some(size) = self.size
            && self.bytes > u64::from(size)
        {
            anomalies.push(format!(
                "{} bytes sent but only {size} were announced",
                self.bytes
            ));
        }
    }

    fn check_complete(&self, anomalies: &mut Vec<String>) {
        if let Some(size) = self.size
            && self.bytes != u64::from(size)
        {
            anomalies.push(format!(
                "the transfer ended after {} bytes but {size} were announced",
                self.bytes
            ));
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// The client's initiate request is waiting for the server's initiate response.
    Initiated,
    /// The client's next download segment, or upload segment request, is due with this toggle.
    SegmentRequestDue { toggle: bool },
    /// The server's answer to the client's segment (request) with this toggle is due.
    SegmentResponseDue { toggle: bool, last: bool },
    /// A block transfer.
    Block(Block),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum BlockStep {
    /// The initiate response is due.
    AwaitInitiateResponse,
    /// Block upload: the client's start command is due.
    AwaitStart,
    /// Segments of a sub-block, then the receiver's ack.
    SubBlock,
    /// The data sender's end frame is due.
    AwaitEnd,
    /// The receiver's end response is due.
    AwaitEndResponse,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Block {
    client_crc: bool,
    server_crc: bool,
    blksize: u8,
    step: BlockStep,
    /// The last sequence number received in order in the current sub-block.
    seq: u8,
    /// A segment arrived out of order; the receiver ignores the rest of the sub-block.
    out_of_order: bool,
    /// Bytes transferred before the current sub-block.
    sub_block_start: u64,
    /// The segment with c = 1 arrived in order.
    last_seen: bool,
    last_data: [u8; SEGMENT_DATA_LEN],
    bytes_before_last: u64,
    /// CRC over all segments before the last one.
    crc: u16,
    /// False once segments were repeated: the CRC above may then include data the receiver dropped.
    crc_trustworthy: bool,
}

impl Block {
    fn new(client_crc: bool, blksize: u8) -> Block {
        Block {
            client_crc,
            server_crc: false,
            blksize,
            step: BlockStep::AwaitInitiateResponse,
            seq: 0,
            out_of_order: false,
            sub_block_start: 0,
            last_seen: false,
            last_data: [0; SEGMENT_DATA_LEN],
            bytes_before_last: 0,
            crc: 0,
            crc_trustworthy: true,
        }
    }

    fn sub_block_complete(&self) -> bool {
        self.last_seen || self.seq >= self.blksize
    }
}

/// What a frame tells about its transfer.
#[derive(Debug, Default)]
struct FrameEffect {
    progress: Option<TransferProgress>,
    crc: Option<CrcCheck>,
}

impl FrameEffect {
    fn of(transfer: &Transfer) -> FrameEffect {
        FrameEffect {
            progress: Some(transfer.progress()),
            crc: None,
        }
    }
}

fn check_block_size(blksize: u8, anomalies: &mut Vec<String>) {
    if blksize == 0 || blksize > MAX_BLOCK_SIZE {
        anomalies.push(format!(
            "block size {blksize} is outside 1 to 127 (the peer aborts with 0504 0002h)"
        ));
    }
}

/// Starts a new transfer, flagging one that was still running.
fn start(slot: &mut Option<Transfer>, transfer: Transfer, anomalies: &mut Vec<String>) {
    if let Some(old) = slot.as_ref() {
        anomalies.push(format!(
            "a new transfer of {} starts while the {} of {} was not finished",
            transfer.mux, old.kind, old.mux
        ));
    }
    *slot = Some(transfer);
}

fn unexpected(what: &str, slot: &Option<Transfer>, anomalies: &mut Vec<String>) {
    match slot {
        Some(transfer) => anomalies.push(format!(
            "{what} does not fit the {} of {} in progress",
            transfer.kind, transfer.mux
        )),
        None => anomalies.push(format!("{what} without a transfer in progress")),
    }
}

fn check_mux(expected: Multiplexer, got: Multiplexer, anomalies: &mut Vec<String>) {
    if expected != got {
        anomalies.push(format!("the response names {got} but {expected} was requested"));
    }
}

fn apply_request(
    slot: &mut Option<Transfer>,
    request: &SdoRequest,
    anomalies: &mut Vec<String>,
) -> FrameEffect {
    match request {
        SdoRequest::InitiateDownload { mux, data } => {
            let transfer = match data {
                InitiateData::Expedited { data, size_indicated } => {
                    // At most 4 bytes, so the length fits in u32.
                    let size = size_indicated.then_some(data.len() as u32);
                    Transfer::new(*mux, TransferKind::ExpeditedDownload, size, Phase::Initiated)
                }
                InitiateData::Segmented { size } => {
                    Transfer::new(*mux, TransferKind::SegmentedDownload, *size, Phase::Initiated)
                }
            };
            start(slot, transfer, anomalies);
            FrameEffect::default()
        }
        SdoRequest::DownloadSegment(segment) => match slot {
            Some(
                transfer @ Transfer {
                    kind: TransferKind::SegmentedDownload,
                    ..
                },
            ) if matches!(transfer.phase, Phase::SegmentRequestDue { .. }) => {
                if let Phase::SegmentRequestDue { toggle } = transfer.phase
                    && segment.toggle != toggle
                {
                    anomalies.push(format!(
                        "toggle={} but {} was due; the toggle alternates with every segment \
                         (the server aborts with 0503 0000h)",
                        u8::from(segment.toggle),
                        u8::from(toggle)
                    ));
                }
                if segment.data.is_empty() {
                    anomalies.push("the segment carries no data (n = 7)".to_owned());
                }
                transfer.bytes = transfer.bytes.saturating_add(segment.data.len() as u64);
                transfer.check_not_beyond_size(anomalies);
                if segment.last {
                    transfer.check_complete(anomalies);
                }
                transfer.phase = Phase::SegmentResponseDue {
                    toggle: segment.toggle,
                    last: segment.last,
                };
                FrameEffect::of(transfer)
            }
            _ => {
                unexpected("a download segment", slot, anomalies);
                FrameEffect::default()
            }
        },
        SdoRequest::InitiateUpload { mux } => {
            // Expedited or segmented is up to the server; the response sets the kind.
            start(
                slot,
                Transfer::new(*mux, TransferKind::SegmentedUpload, None, Phase::Initiated),
                anomalies,
            );
            FrameEffect::default()
        }
        SdoRequest::UploadSegment { toggle } => match slot {
            Some(
                transfer @ Transfer {
                    kind: TransferKind::SegmentedUpload,
                    ..
                },
            ) if matches!(transfer.phase, Phase::SegmentRequestDue { .. }) => {
                if let Phase::SegmentRequestDue { toggle: due } = transfer.phase
                    && *toggle != due
                {
                    anomalies.push(format!(
                        "toggle={} but {} was due; the toggle alternates with every segment \
                         (the server aborts with 0503 0000h)",
                        u8::from(*toggle),
                        u8::from(due)
                    ));
                }
                transfer.phase = Phase::SegmentResponseDue {
                    toggle: *toggle,
                    last: false,
                };
                FrameEffect::of(transfer)
            }
            _ => {
                unexpected("an upload segment request", slot, anomalies);
                FrameEffect::default()
            }
        },
        SdoRequest::Abort { .. } => FrameEffect {
            progress: slot.take().map(|t| t.progress()),
            crc: None,
        },
        SdoRequest::BlockDownloadInitiate {
            mux,
            crc_supported,
            size,
        } => {
            let block = Block::new(*crc_supported, 0);
            start(
                slot,
                Transfer::new(*mux, TransferKind::BlockDownload, *size, Phase::Block(block)),
                anomalies,
            );
            FrameEffect::default()
        }
        SdoRequest::BlockDownloadEnd { unused, crc } => block_end(
            slot,
            TransferKind::BlockDownload,
            "an end block download",
            *unused,
            *crc,
            anomalies,
        ),
        SdoRequest::BlockUploadInitiate {
            mux,
            crc_supported,
            blksize,
            ..
        } => {
            check_block_size(*blksize, anomalies);
            let block = Block::new(*crc_supported, *blksize);
            start(
                slot,
                Transfer::new(*mux, TransferKind::BlockUpload, None, Phase::Block(block)),
                anomalies,
            );
            FrameEffect::default()
        }
        SdoRequest::BlockUploadStart => {
            match block_in_step(slot, TransferKind::BlockUpload, BlockStep::AwaitStart) {
                Some((transfer, mut block)) => {
                    block.step = BlockStep::SubBlock;
                    transfer.phase = Phase::Block(block);
                    FrameEffect::of(transfer)
                }
                None => {
                    unexpected("a start block upload", slot, anomalies);
                    FrameEffect::default()
                }
            }
        }
        SdoRequest::BlockUploadAck { ackseq, blksize } => block_ack(
            slot,
            TransferKind::BlockUpload,
            "a block upload ack",
            *ackseq,
            *blksize,
            anomalies,
        ),
        SdoRequest::BlockUploadEndResponse => block_end_response(
            slot,
            TransferKind::BlockUpload,
            "a block upload end response",
            anomalies,
        ),
    }
}

fn apply_response(
    slot: &mut Option<Transfer>,
    response: &SdoResponse,
    anomalies: &mut Vec<String>,
) -> FrameEffect {
    match response {
        SdoResponse::InitiateUpload { mux, data } => {
            let awaiting = match slot {
                Some(Transfer {
                    kind: TransferKind::SegmentedUpload,
                    phase: Phase::Initiated,
                    ..
                }) => true,
                // A block upload request may be answered with a normal upload (protocol switch,
                // CiA 301 §7.2.4.3.13, when the size is at most pst).
                Some(Transfer {
                    kind: TransferKind::BlockUpload,
                    phase: Phase::Block(block),
                    ..
                }) => block.step == BlockStep::AwaitInitiateResponse,
                _ => false,
            };
            let Some(transfer) = slot.as_mut().filter(|_| awaiting) else {
                unexpected("an initiate upload response", slot, anomalies);
                return FrameEffect::default();
            };
            check_mux(transfer.mux, *mux, anomalies);
            match data {
                InitiateData::Expedited { data, size_indicated } => {
                    transfer.kind = TransferKind::ExpeditedUpload;
                    transfer.bytes = data.len() as u64;
                    transfer.size = size_indicated.then_some(data.len() as u32);
                    FrameEffect {
                        progress: slot.take().map(|t| t.progress()),
                        crc: None,
                    }
                }
                InitiateData::Segmented { size } => {
                    transfer.kind = TransferKind::SegmentedUpload;
                    transfer.size = *size;
                    transfer.phase = Phase::SegmentRequestDue { toggle: false };
                    FrameEffect::of(transfer)
                }
            }
        }
        SdoResponse::UploadSegment(segment) => match slot {
            Some(
                transfer @ Transfer {
                    kind: TransferKind::SegmentedUpload,
                    ..
                },
            ) if matches!(transfer.phase, Phase::SegmentResponseDue { .. }) => {
                if let Phase::SegmentResponseDue { toggle, .. } = transfer.phase
                    && segment.toggle != toggle
                {
                    anomalies.push(format!(
                        "toggle={} does not echo the request's toggle={}",
                        u8::from(segment.toggle),
                        u8::from(toggle)
                    ));
                }
                if segment.data.is_empty() {
                    anomalies.push("the segment carries no data (n = 7)".to_owned());
                }
                transfer.bytes = transfer.bytes.saturating_add(segment.data.len() as u64);
                transfer.check_not_beyond_size(anomalies);
                let outcome = FrameEffect::of(transfer);
                if segment.last {
                    transfer.check_complete(anomalies);
                    *slot = None;
                } else {
                    transfer.phase = Phase::SegmentRequestDue {
                        toggle: !segment.toggle,
                    };
                }
                outcome
            }
            _ => {
                unexpected("an upload segment", slot, anomalies);
                FrameEffect::default()
            }
        },
        SdoResponse::InitiateDownload { mux } => match slot {
            Some(
                transfer @ Transfer {
                    phase: Phase::Initiated,
                    ..
                },
            ) if matches!(
                transfer.kind,
                TransferKind::ExpeditedDownload | TransferKind::SegmentedDownload
            ) =>
            {
                check_mux(transfer.mux, *mux, anomalies);
                if transfer.kind == TransferKind::ExpeditedDownload {
                    transfer.bytes = transfer.size.map_or(4, u64::from);
                    FrameEffect {
                        progress: slot.take().map(|t| t.progress()),
                        crc: None,
                    }
                } else {
                    transfer.phase = Phase::SegmentRequestDue { toggle: false };
                    FrameEffect::of(transfer)
                }
            }
            _ => {
                unexpected("an initiate download response", slot, anomalies);
                FrameEffect::default()
            }
        },
        SdoResponse::DownloadSegment { toggle } => match slot {
            Some(
                transfer @ Transfer {
                    kind: TransferKind::SegmentedDownload,
                    ..
                },
            ) if matches!(transfer.phase, Phase::SegmentResponseDue { .. }) => {
                let Phase::SegmentResponseDue { toggle: sent, last } = transfer.phase else {
                    // Unreachable: the guard above matched this phase.
                    return FrameEffect::default();
                };
                if *toggle != sent {
                    anomalies.push(format!(
                        "toggle={} does not echo the segment's toggle={}",
                        u8::from(*toggle),
                        u8::from(sent)
                    ));
                }
                let outcome = FrameEffect::of(transfer);
                if last {
                    *slot = None;
                } else {
                    transfer.phase = Phase::SegmentRequestDue { toggle: !sent };
                }
                outcome
            }
            _ => {
                unexpected("a download segment response", slot, anomalies);
                FrameEffect::default()
            }
        },
        SdoResponse::Abort { .. } => FrameEffect {
            progress: slot.take().map(|t| t.progress()),
            crc: None,
        },
        SdoResponse::BlockDownloadInitiate {
            mux,
            crc_supported,
            blksize,
        } => {
            match block_in_step(
                slot,
                TransferKind::BlockDownload,
                BlockStep::AwaitInitiateResponse,
            ) {
                Some((transfer, mut block)) => {
                    check_mux(transfer.mux, *mux, anomalies);
                    check_block_size(*blksize, anomalies);
                    block.server_crc = *crc_supported;
                    block.blksize = *blksize;
                    block.step = BlockStep::SubBlock;
                    transfer.phase = Phase::Block(block);
                    FrameEffect::of(transfer)
                }
                None => {
                    unexpected("an initiate block download response", slot, anomalies);
                    FrameEffect::default()
                }
            }
        }
        SdoResponse::BlockDownloadAck { ackseq, blksize } => block_ack(
            slot,
            TransferKind::BlockDownload,
            "a block download ack",
            *ackseq,
            *blksize,
            anomalies,
        ),
        SdoResponse::BlockDownloadEndResponse => block_end_response(
            slot,
            TransferKind::BlockDownload,
            "a block download end response",
            anomalies,
        ),
        SdoResponse::BlockUploadInitiate {
            mux,
            crc_supported,
            size,
        } => match block_in_step(slot, TransferKind::BlockUpload, BlockStep::AwaitInitiateResponse) {
            Some((transfer, mut block)) => {
                check_mux(transfer.mux, *mux, anomalies);
                block.server_crc = *crc_supported;
                block.step = BlockStep::AwaitStart;
                transfer.size = *size;
                transfer.phase = Phase::Block(block);
                FrameEffect::of(transfer)
            }
            None => {
                unexpected("an initiate block upload response", slot, anomalies);
                FrameEffect::default()
            }
        },
        SdoResponse::BlockUploadEnd { unused, crc } => block_end(
            slot,
            TransferKind::BlockUpload,
            "an end block upload",
            *unused,
            *crc,
            anomalies,
        ),
    }
}

/// The transfer and a copy of its block state if it is a `kind` block transfer in `step`.
fn block_in_step(
    slot: &mut Option<Transfer>,
    kind: TransferKind,
    step: BlockStep,
) -> Option<(&mut Transfer, Block)> {
    let transfer = slot.as_mut()?;
    match transfer.phase {
        Phase::Block(block) if transfer.kind == kind && block.step == step => Some((transfer, block)),
        _ => None,
    }
}

fn block_segment(transfer: &mut Transfer, segment: &BlockSegment, anomalies: &mut Vec<String>) {
    let Phase::Block(mut block) = transfer.phase else {
        return;
    };
    if block.sub_block_complete() {
        anomalies.push(format!(
            "segment seq={} after the sub-block was complete; the receiver's ack was due",
            segment.seqno
        ));
        return;
    }
    if block.out_of_order {
        // The receiver ignores the rest of this sub-block; the first wrong number was reported.
        return;
    }
    let expected = block.seq.saturating_add(1);
    if segment.seqno == expected && segment.seqno <= block.blksize {
        if segment.last {
            block.bytes_before_last = transfer.bytes;
            let in_last = match transfer.size {
                Some(size) => u64::from(size)
                    .saturating_sub(transfer.bytes)
                    .min(SEGMENT_DATA_LEN as u64),
                None => SEGMENT_DATA_LEN as u64,
            };
            transfer.bytes = transfer.bytes.saturating_add(in_last);
            block.last_data = segment.data;
            block.last_seen = true;
        } else {
            transfer.bytes = transfer.bytes.saturating_add(SEGMENT_DATA_LEN as u64);
            block.crc = crc16_ccitt_update(block.crc, &segment.data);
            transfer.check_not_beyond_size(anomalies);
        }
        block.seq = segment.seqno;
    } else if segment.seqno == block.seq && segment.seqno != 0 {
        anomalies.push(format!(
            "segment seq={} repeated; the receiver ignores duplicates",
            segment.seqno
        ));
    } else {
        block.out_of_order = true;
        if segment.seqno == 0 {
            anomalies.push("sequence number 0 is invalid; segments count from 1".to_owned());
        } else if segment.seqno > block.blksize {
            anomalies.push(format!(
                "sequence number {} exceeds the block size {} (abort code 0504 0003h)",
                segment.seqno, block.blksize
            ));
        } else {
            anomalies.push(format!(
                "sequence number {} but {expected} was due; the receiver ignores the rest of this sub-block",
                segment.seqno
            ));
        }
    }
    transfer.phase = Phase::Block(block);
}

fn block_ack(
    slot: &mut Option<Transfer>,
    kind: TransferKind,
    what: &str,
    ackseq: u8,
    blksize: u8,
    anomalies: &mut Vec<String>,
) -> FrameEffect {
    let Some((transfer, mut block)) = block_in_step(slot, kind, BlockStep::SubBlock) else {
        unexpected(what, slot, anomalies);
        return FrameEffect::default();
    };
    if ackseq > block.seq {
        anomalies.push(format!(
            "ack of sequence number {ackseq} but only {} segments arrived in order",
            block.seq
        ));
    } else if ackseq < block.seq {
        // The receiver lost segments: the sender repeats everything after `ackseq`.
        transfer.bytes = block
            .sub_block_start
            .saturating_add(u64::from(ackseq) * SEGMENT_DATA_LEN as u64);
        block.crc_trustworthy = false;
        block.last_seen = false;
    }
    if block.last_seen {
        block.step = BlockStep::AwaitEnd;
    } else {
        check_block_size(blksize, anomalies);
        block.blksize = blksize;
        block.seq = 0;
        block.out_of_order = false;
        block.sub_block_start = transfer.bytes;
    }
    transfer.phase = Phase::Block(block);
    FrameEffect::of(transfer)
}

fn block_end(
    slot: &mut Option<Transfer>,
    kind: TransferKind,
    what: &str,
    unused: u8,
    crc: u16,
    anomalies: &mut Vec<String>,
) -> FrameEffect {
    let Some((transfer, mut block)) = block_in_step(slot, kind, BlockStep::AwaitEnd) else {
        unexpected(what, slot, anomalies);
        return FrameEffect::default();
    };
    if usize::from(unused) >= SEGMENT_DATA_LEN {
        anomalies.push(format!(
            "{unused} unused bytes leave no data in the last segment (0 to 6 allowed)"
        ));
    }
    let used = SEGMENT_DATA_LEN.saturating_sub(usize::from(unused));
    transfer.bytes = block.bytes_before_last.saturating_add(used as u64);
    transfer.check_complete(anomalies);
    let check = if !(block.client_crc && block.server_crc) {
        CrcCheck::NotUsed
    } else if !block.crc_trustworthy {
        CrcCheck::NotVerified
    } else {
        let computed = crc16_ccitt_update(block.crc, block.last_data.get(..used).unwrap_or_default());
        if computed == crc {
            CrcCheck::Match(crc)
        } else {
            anomalies.push(format!(
                "crc 0x{crc:04X} does not match the data, which gives 0x{computed:04X} \
                 (abort code 0504 0004h)"
            ));
            CrcCheck::Mismatch { sent: crc, computed }
        }
    };
    block.step = BlockStep::AwaitEndResponse;
    transfer.phase = Phase::Block(block);
    FrameEffect {
        progress: Some(transfer.progress()),
        crc: Some(check),
    }
}

fn block_end_response(
    slot: &mut Option<Transfer>,
    kind: TransferKind,
    what: &str,
    anomalies: &mut Vec<String>,
) -> FrameEffect {
    if block_in_step(slot, kind, BlockStep::AwaitEndResponse).is_none() {
        unexpected(what, slot, anomalies);
        return FrameEffect::default();
    }
    FrameEffect {
        progress: slot.take().map(|t| t.progress()),
        crc: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crc::crc16_ccitt;
    use crate::sdo::Segment;
    use canopener_can::candump::parse_compact_frame;
    use canopener_can::{CanId, ExtendedId, StandardId};
    use proptest::prelude::*;

    fn frame(compact: &str) -> CanFrame {
        parse_compact_frame(compact).unwrap()
    }

    /// Decodes a trace of compact frames with one decoder and returns the printed lines.
    fn lines(trace: &[&str]) -> Vec<String> {
        let mut decoder = Decoder::new();
        trace
            .iter()
            .map(|compact| decoder.decode(&frame(compact)).to_string())
            .collect()
    }

    fn line(compact: &str) -> String {
        lines(&[compact]).remove(0)
    }

    #[test]
    fn golden_line_per_service() {
        assert_eq!(line("000#0105"), "NMT Start Remote Node -> node 5");
        assert_eq!(line("000#8200"), "NMT Reset Communication -> all nodes");
        assert_eq!(line("080#"), "SYNC");
        assert_eq!(line("080#07"), "SYNC counter 7");
        assert_eq!(
            line("083#3081110000000000"),
            "EMCY node 3: 0x8130 (life guard error or heartbeat error) reg 0x11 (generic, communication)"
        );
        assert_eq!(
            line("083#0000000000000000"),
            "EMCY node 3: 0x0000 (error reset or no error) reg 0x00"
        );
        assert_eq!(line("100#002E93021239"), "TIME 2024-01-01 12:00:00.000");
        assert_eq!(line("185#01020304"), "TPDO1 node 5 (4 bytes)");
        assert_eq!(line("485#R8"), "TPDO4 node 5 remote request (DLC 8)");
        assert_eq!(line("305#01"), "RPDO2 node 5 (1 byte)");
        assert_eq!(
            line("622#4018100100000000"),
            "SDO rx node 34: initiate upload 1018h:01"
        );
        assert_eq!(
            lines(&["622#4018100100000000", "5A2#4318100178563412"])[1],
            "SDO tx node 34: upload 1018h:01 = 0x12345678 (4 bytes)"
        );
        assert_eq!(
            line("5A2#8000600000000206"),
            "SDO tx node 34: ABORT 6000h:00 0x06020000 (object does not exist in the object dictionary)"
        );
        assert_eq!(line("705#00"), "Boot-up node 5");
        assert_eq!(line("705#05"), "Heartbeat node 5: OPERATIONAL");
        assert_eq!(line("705#7F"), "Heartbeat node 5: PRE-OPERATIONAL");
        assert_eq!(line("705#04"), "Heartbeat node 5: STOPPED");
        assert_eq!(line("705#R1"), "Node guarding request node 5");
        assert_eq!(line("7E5#5A00000000000000"), "LSS master: inquire vendor-id");
        assert_eq!(line("7E4#5A1A030000000000"), "LSS slave: vendor-id = 0x0000031A");
        assert_eq!(line("7E0#01"), "7E0 not CANopen (predefined set) (1 byte)");
        assert_eq!(
            line("18DAF110#R2"),
            "18DAF110 not CANopen (predefined set) remote frame (DLC 2)"
        );
    }

    #[test]
    fn expedited_download_round() {
        assert_eq!(
            lines(&["605#2B17100064000000", "585#6017100000000000"]),
            [
                "SDO rx node 5: download 1017h:00 = 0x0064 (2 bytes)",
                "SDO tx node 5: download 1017h:00 confirmed"
            ]
        );
    }

    #[test]
    fn full_segmented_upload() {
        let trace = [
            "605#4008100000000000",
            "585#4108100016000000",
            "605#6000000000000000",
            "585#0043414E6F70656E",
            "605#7000000000000000",
            "585#102064656D6F2064",
            "605#6000000000000000",
            "585#0065766963652076",
            "605#7000000000000000",
            "585#1D31000000000000",
        ];
        assert_eq!(
            lines(&trace),
            [
                "SDO rx node 5: initiate upload 1008h:00",
                "SDO tx node 5: initiate upload response 1008h:00 (22 bytes, segmented)",
                "SDO rx node 5: upload segment request toggle=0 (0/22) of 1008h:00",
                "SDO tx node 5: upload segment toggle=0 7 bytes (7/22) of 1008h:00",
                "SDO rx node 5: upload segment request toggle=1 (7/22) of 1008h:00",
                "SDO tx node 5: upload segment toggle=1 7 bytes (14/22) of 1008h:00",
                "SDO rx node 5: upload segment request toggle=0 (14/22) of 1008h:00",
                "SDO tx node 5: upload segment toggle=0 7 bytes (21/22) of 1008h:00",
                "SDO rx node 5: upload segment request toggle=1 (21/22) of 1008h:00",
                "SDO tx node 5: upload segment toggle=1 last 1 byte (22/22) of 1008h:00",
            ]
        );
    }

    #[test]
    fn full_block_download_with_crc() {
        // 20 bytes "0123456789ABCDEFGHIJ" to 2000h:00 in sub-blocks of 2 segments.
        let trace = [
            "605#C600200014000000",
            "585#A400200002000000",
            "605#0130313233343536",
            "605#0237383941424344",
            "585#A202020000000000",
            "605#8145464748494A00",
            "585#A201020000000000",
            "605#C5F1340000000000",
            "585#A100000000000000",
        ];
        assert_eq!(
            lines(&trace),
            [
                "SDO rx node 5: initiate block download 2000h:00 (20 bytes, crc)",
                "SDO tx node 5: initiate block download response 2000h:00 blksize=2 (crc)",
                "SDO rx node 5: block segment seq=1 (7/20) of 2000h:00",
                "SDO rx node 5: block segment seq=2 (14/20) of 2000h:00",
                "SDO tx node 5: block download ack seq=2 blksize=2 (14/20) of 2000h:00",
                "SDO rx node 5: block segment seq=1 last (20/20) of 2000h:00",
                "SDO tx node 5: block download ack seq=1 blksize=2 (20/20) of 2000h:00",
                "SDO rx node 5: end block download of 2000h:00 (20 bytes) crc=0x34F1 ok",
                "SDO tx node 5: block download of 2000h:00 confirmed",
            ]
        );
        assert_eq!(crc16_ccitt(b"0123456789ABCDEFGHIJ"), 0x34F1);
    }

    #[test]
    fn conformance_test_block_upload_trace() {
        // CiA CCT "SDO 23" on CANopenNode's demo device (node 4).
        let trace = [
            "604#A408100014000000",
            "584#C608100010000000",
            "604#A300000000000000",
            "584#0143414E6F70656E",
            "584#0244656D6F504943",
            "584#8333320000000000",
            "604#A203140000000000",
            "584#D5F3430000000000",
            "604#A100000000000000",
        ];
        assert_eq!(
            lines(&trace),
            [
                "SDO rx node 4: initiate block upload 1008h:00 blksize=20 pst=0 (crc)",
                "SDO tx node 4: initiate block upload response 1008h:00 (16 bytes, crc)",
                "SDO rx node 4: start block upload of 1008h:00",
                "SDO tx node 4: block segment seq=1 (7/16) of 1008h:00",
                "SDO tx node 4: block segment seq=2 (14/16) of 1008h:00",
                "SDO tx node 4: block segment seq=3 last (16/16) of 1008h:00",
                "SDO rx node 4: block upload ack seq=3 blksize=20 (16/16) of 1008h:00",
                "SDO tx node 4: end block upload of 1008h:00 (16 bytes) crc=0x43F3 ok",
                "SDO rx node 4: block upload of 1008h:00 confirmed",
            ]
        );
    }

    #[test]
    fn block_crc_mismatch_and_repeated_segments() {
        let mut decoder = Decoder::new();
        let mut decode = |compact: &str| decoder.decode(&frame(compact));
        decode("605#C600200014000000");
        decode("585#A400200002000000");
        decode("605#0130313233343536");
        decode("605#0237383941424344");
        // The server only got segment 1: segment 2 is sent again in the next sub-block.
        let ack = decode("585#A201020000000000");
        assert!(ack.anomalies.is_empty(), "{ack}");
        assert!(ack.to_string().contains("(7/20)"), "{ack}");
        decode("605#0137383941424344");
        decode("605#8245464748494A00");
        decode("585#A202020000000000");
        let end = decode("605#C5F1340000000000");
        let Payload::Sdo(sdo) = &end.payload else {
            panic!("not SDO: {end}")
        };
        assert_eq!(sdo.crc, Some(CrcCheck::NotVerified));
        assert!(end.anomalies.is_empty(), "{end}");

        let mut decoder = Decoder::new();
        for compact in [
            "605#C600200014000000",
            "585#A400200002000000",
            "605#0130313233343536",
        ] {
            decoder.decode(&frame(compact));
        }
        for compact in [
            "605#0237383941424344",
            "585#A202020000000000",
            "605#8145464748494A00",
        ] {
            decoder.decode(&frame(compact));
        }
        decoder.decode(&frame("585#A201020000000000"));
        let wrong = decoder.decode(&frame("605#C512340000000000"));
        assert!(
            wrong.anomalies.iter().any(|a| a.contains("does not match")),
            "{wrong}"
        );
        assert!(
            wrong.to_string().contains("crc=0x3412 WRONG (data gives 0x34F1)"),
            "{wrong}"
        );
    }

    #[test]
    fn out_of_order_block_segment_is_an_anomaly() {
        let decoded = lines(&[
            "605#C600200014000000",
            "585#A400200004000000",
            "605#0130313233343536",
            "605#0345464748494A00",
            "605#0237383941424344",
        ]);
        assert!(
            decoded[3].contains("sequence number 3 but 2 was due"),
            "{}",
            decoded[3]
        );
        assert!(!decoded[4].contains("anomaly"), "{}", decoded[4]);
    }

    #[test]
    fn abort_ends_the_transfer() {
        let decoded = lines(&[
            "605#4008100000000000",
            "585#4108100016000000",
            "605#8008100000000405",
            "585#0043414E6F70656E",
        ]);
        assert_eq!(
            decoded[2],
            "SDO rx node 5: ABORT 1008h:00 0x05040000 (SDO protocol timed out)"
        );
        assert_eq!(
            decoded[3],
            "SDO tx node 5: upload segment toggle=0 7 bytes \
             [anomaly: an upload segment without a transfer in progress]"
        );
        assert_eq!(
            line("585#8008100078563412"),
            "SDO tx node 5: ABORT 1008h:00 0x12345678 (not a CiA 301 abort code)"
        );
    }

    #[test]
    fn wrong_toggle_in_a_segmented_download() {
        let decoded = lines(&[
            "605#210120000A000000",
            "585#6001200000000000",
            "605#0030313233343536",
            "585#2000000000000000",
            "605#0937383900000000",
            "585#8001200000000305",
        ]);
        assert_eq!(
            decoded[0],
            "SDO rx node 5: initiate download 2001h:00 (10 bytes, segmented)"
        );
        assert_eq!(
            decoded[2],
            "SDO rx node 5: download segment toggle=0 7 bytes (7/10) of 2001h:00"
        );
        assert_eq!(
            decoded[3],
            "SDO tx node 5: download segment response toggle=0 (7/10) of 2001h:00"
        );
        assert!(
            decoded[4]
                .starts_with("SDO rx node 5: download segment toggle=0 last 3 bytes (10/10) of 2001h:00")
        );
        assert!(
            decoded[4].contains("[anomaly: toggle=0 but 1 was due"),
            "{}",
            decoded[4]
        );
        assert_eq!(
            decoded[5],
            "SDO tx node 5: ABORT 2001h:00 0x05030000 (toggle bit not alternated)"
        );
    }

    #[test]
    fn malformed_frames_are_anomalies() {
        let mut decoder = Decoder::new();
        let heartbeat = decoder.decode(&frame("705#0500"));
        assert_eq!(
            heartbeat.anomalies,
            ["error control frame with DLC 2; CiA 301 7.2.8.3.2 requires 1"]
        );
        assert!(
            heartbeat
                .to_string()
                .starts_with("Heartbeat node 5: OPERATIONAL [anomaly:")
        );

        let nmt = decoder.decode(&frame("000#01C8"));
        assert_eq!(nmt.node, None);
        assert_eq!(
            nmt.anomalies,
            ["NMT target node 200 does not exist; node-ids are 1 to 127 and 0 addresses all nodes"]
        );
        let short_nmt = decoder.decode(&frame("000#01"));
        assert!(matches!(short_nmt.payload, Payload::Raw { .. }));
        assert!(!short_nmt.anomalies.is_empty());
        assert_eq!(
            decoder.decode(&frame("000#0305")).to_string().split(" [").next(),
            Some("NMT unknown command 0x03 -> node 5")
        );

        let zero = decoder.decode(&frame("180#00"));
        assert_eq!(zero.node, Some(0));
        assert!(zero.anomalies[0].starts_with("node-id 0 in a TPDO1 CAN-ID"));

        let reserved = decoder.decode(&frame("605#4318100100000000"));
        assert_eq!(reserved.anomalies, ["reserved bits are not 0: D0 & 1Fh = 03h"]);
        let short_sdo = decoder.decode(&frame("605#40181001"));
        assert!(short_sdo.anomalies.iter().any(|a| a.contains("DLC 4")));
        let invalid = decoder.decode(&frame("605#E000000000000000"));
        assert!(invalid.to_string().contains("invalid command byte 0xE0"));

        assert!(!decoder.decode(&frame("080#00")).anomalies.is_empty());
        assert!(!decoder.decode(&frame("080#0102")).anomalies.is_empty());
        assert!(!decoder.decode(&frame("081#3081")).anomalies.is_empty());
        let emcy_no_generic = decoder.decode(&frame("081#3081100000000000"));
        assert!(emcy_no_generic.anomalies[0].contains("bit 0 (generic)"));
        assert!(!decoder.decode(&frame("100#002E930212")).anomalies.is_empty());
        assert!(!decoder.decode(&frame("100#FFFFFFFF1239")).anomalies.is_empty());
        let rpdo_rtr = decoder.decode(&frame("205#R"));
        assert!(rpdo_rtr.anomalies[0].starts_with("remote frame on the RPDO1 CAN-ID"));
        assert!(
            decoder
                .decode(&frame("7E5#0400000000000000"))
                .anomalies
                .is_empty()
        );
        assert!(
            !decoder
                .decode(&frame("7E5#0402000000000000"))
                .anomalies
                .is_empty()
        );
        assert!(
            !decoder
                .decode(&frame("7E5#5A00000000000001"))
                .anomalies
                .is_empty()
        );
        assert!(
            !decoder
                .decode(&frame("7E4#0400000000000000"))
                .anomalies
                .is_empty()
        );
        assert!(!decoder.decode(&frame("705#33")).anomalies.is_empty());
    }

    #[test]
    fn a_guarding_response_is_a_reply_within_the_window_after_the_request() {
        let mut decoder = Decoder::new();
        let at = |ms: u64| Instant::from_millis(ms);
        let mut decode = |ms: u64, compact: &str| decoder.decode_at(at(ms), &frame(compact)).to_string();
        // A request nobody answers (heartbeats run), then the next heartbeat 200 ms later.
        assert_eq!(decode(0, "705#R1"), "Node guarding request node 5");
        assert_eq!(decode(200, "705#7F"), "Heartbeat node 5: PRE-OPERATIONAL");
        assert_eq!(decode(400, "705#7F"), "Heartbeat node 5: PRE-OPERATIONAL");
        // An answer within the window is one.
        assert_eq!(decode(500, "705#R1"), "Node guarding request node 5");
        assert_eq!(
            decode(502, "705#7F"),
            "Node guarding response node 5: PRE-OPERATIONAL toggle=0"
        );
        assert_eq!(GUARD_RESPONSE_WINDOW, Duration::from_millis(100));
        // Without the time the request stays open (the old reading).
        let mut untimed = Decoder::new();
        untimed.decode(&frame("705#R1"));
        assert!(
            untimed
                .decode(&frame("705#7F"))
                .to_string()
                .starts_with("Node guarding response")
        );
    }

    #[test]
    fn node_guarding_toggle_is_followed() {
        let decoded = lines(&[
            "705#R1", "705#05", "705#R1", "705#85", "705#R1", "705#85", "705#05",
        ]);
        assert_eq!(decoded[1], "Node guarding response node 5: OPERATIONAL toggle=0");
        assert_eq!(decoded[3], "Node guarding response node 5: OPERATIONAL toggle=1");
        assert!(decoded[5].contains("did not alternate"), "{}", decoded[5]);
        // Without a pending request a clear toggle bit is a heartbeat.
        assert_eq!(decoded[6], "Heartbeat node 5: OPERATIONAL");
        let reset = lines(&["705#R1", "705#05", "000#8205", "705#00", "705#R1", "705#7F"]);
        assert_eq!(
            reset[5],
            "Node guarding response node 5: PRE-OPERATIONAL toggle=0"
        );
        let unrequested = line("705#85");
        assert!(
            unrequested.contains("without a node guarding request"),
            "{unrequested}"
        );
    }

    #[test]
    fn new_transfer_over_an_unfinished_one_is_flagged() {
        let decoded = lines(&["605#4000100000000000", "605#4018100100000000"]);
        assert!(
            decoded[1].contains("while the segmented upload of 1000h:00 was not finished"),
            "{}",
            decoded[1]
        );
    }

    #[test]
    fn protocol_switch_from_block_to_expedited_upload() {
        let decoded = lines(&["605#A400100014040000", "585#4300100091010F00"]);
        assert_eq!(
            decoded[1],
            "SDO tx node 5: upload 1000h:00 = 0x000F0191 (4 bytes)"
        );
    }

    /// Frames of a correct segmented upload of `value`, built with the codecs.
    fn segmented_upload(node: u16, mux: Multiplexer, value: &[u8]) -> Vec<CanFrame> {
        let request = |data: [u8; 8]| CanFrame::new(StandardId::new(0x600 + node).unwrap(), &data).unwrap();
        let response = |data: [u8; 8]| CanFrame::new(StandardId::new(0x580 + node).unwrap(), &data).unwrap();
        let size = Some(value.len() as u32);
        let mut frames = vec![
            request(SdoRequest::InitiateUpload { mux }.encode().unwrap()),
            response(
                SdoResponse::InitiateUpload {
                    mux,
                    data: InitiateData::Segmented { size },
                }
                .encode()
                .unwrap(),
            ),
        ];
        let chunks: Vec<&[u8]> = value.chunks(7).collect();
        for (idx, chunk) in chunks.iter().enumerate() {
            let toggle = idx % 2 == 1;
            frames.push(request(SdoRequest::UploadSegment { toggle }.encode().unwrap()));
            let segment = Segment {
                toggle,
                data: chunk.to_vec(),
                last: idx + 1 == chunks.len(),
            };
            frames.push(response(SdoResponse::UploadSegment(segment).encode().unwrap()));
        }
        frames
    }

    /// Frames of a correct block download of `value` with CRC, built with the codecs.
    fn block_download(node: u16, mux: Multiplexer, value: &[u8], blksize: u8) -> Vec<CanFrame> {
        let request = |data: [u8; 8]| CanFrame::new(StandardId::new(0x600 + node).unwrap(), &data).unwrap();
        let response = |data: [u8; 8]| CanFrame::new(StandardId::new(0x580 + node).unwrap(), &data).unwrap();
        let size = Some(value.len() as u32);
        let mut frames = vec![
            request(
                SdoRequest::BlockDownloadInitiate {
                    mux,
                    crc_supported: true,
                    size,
                }
                .encode()
                .unwrap(),
            ),
            response(
                SdoResponse::BlockDownloadInitiate {
                    mux,
                    crc_supported: true,
                    blksize,
                }
                .encode()
                .unwrap(),
            ),
        ];
        let chunks: Vec<&[u8]> = value.chunks(7).collect();
        for (sub_block_idx, sub_block) in chunks.chunks(usize::from(blksize)).enumerate() {
            for (idx, chunk) in sub_block.iter().enumerate() {
                let mut data = [0; 7];
                data[..chunk.len()].copy_from_slice(chunk);
                let last = sub_block_idx * usize::from(blksize) + idx + 1 == chunks.len();
                let segment = BlockSegment {
                    last,
                    seqno: idx as u8 + 1,
                    data,
                };
                frames.push(request(segment.encode().unwrap()));
            }
            let ack = SdoResponse::BlockDownloadAck {
                ackseq: sub_block.len() as u8,
                blksize,
            };
            frames.push(response(ack.encode().unwrap()));
        }
        let unused = (7 - chunks.last().map_or(7, |chunk| chunk.len())) as u8;
        let end = SdoRequest::BlockDownloadEnd {
            unused,
            crc: crc16_ccitt(value),
        };
        frames.push(request(end.encode().unwrap()));
        frames.push(response(SdoResponse::BlockDownloadEndResponse.encode().unwrap()));
        frames
    }

    fn any_frame() -> impl Strategy<Value = CanFrame> {
        let id = prop_oneof![
            4 => (0u16..=0x7FF).prop_map(|raw| CanId::Standard(StandardId::new(raw).unwrap())),
            4 => prop::sample::select(vec![0x000u16, 0x080, 0x100, 0x585, 0x605, 0x705, 0x7E4, 0x7E5, 0x000])
                .prop_map(|raw| CanId::Standard(StandardId::new(raw).unwrap())),
            1 => (0u32..=0x1FFF_FFFF).prop_map(|raw| CanId::Extended(ExtendedId::new(raw).unwrap())),
        ];
        canopener_can::strategy::frame_with_id(id)
    }

    proptest! {
        #[test]
        fn any_sequence_of_frames_decodes(frames in proptest::collection::vec(any_frame(), 0..300)) {
            let mut decoder = Decoder::new();
            for frame in &frames {
                let decoded = decoder.decode(frame);
                prop_assert_eq!(decoded.id, frame.id());
                prop_assert!(!decoded.to_string().is_empty());
            }
        }

        #[test]
        fn correct_segmented_uploads_have_no_anomalies(
            value in proptest::collection::vec(any::<u8>(), 1..100),
            node in 1u16..=127,
        ) {
            let mut decoder = Decoder::new();
            let mux = Multiplexer::new(0x2000, 1);
            let mut last = None;
            for frame in segmented_upload(node, mux, &value) {
                let decoded = decoder.decode(&frame);
                prop_assert!(decoded.anomalies.is_empty(), "{}", decoded);
                last = Some(decoded);
            }
            let Some(Decoded { payload: Payload::Sdo(sdo), .. }) = last else { panic!("no SDO frame") };
            prop_assert_eq!(sdo.transfer.map(|t| t.bytes), Some(value.len() as u64));
            prop_assert!(decoder.transfers.iter().all(Option::is_none));
        }

        #[test]
        fn correct_block_downloads_pass_the_crc_check(value in proptest::collection::vec(any::<u8>(), 1..400),
                                                      blksize in 1u8..=127) {
            let mut decoder = Decoder::new();
            let mux = Multiplexer::new(0x1F50, 1);
            let mut crc = None;
            for frame in block_download(7, mux, &value, blksize) {
                let decoded = decoder.decode(&frame);
                prop_assert!(decoded.anomalies.is_empty(), "{}", decoded);
                if let Payload::Sdo(SdoPayload { crc: Some(check), transfer, .. }) = decoded.payload {
                    crc = Some(check);
                    prop_assert_eq!(transfer.map(|t| t.bytes), Some(value.len() as u64));
                }
            }
            prop_assert_eq!(crc, Some(CrcCheck::Match(crc16_ccitt(&value))));
            prop_assert!(decoder.transfers.iter().all(Option::is_none));
        }
    }
}

//! The EMCY producer (CiA 301, emergency object (EMCY) service, error register 1001h and
//! pre-defined error field 1003h).
//!
//! The `Device` (or its application) calls [`EmcyProducer::raise`] when an error appears and
//! [`EmcyProducer::clear`] when it goes away. The producer:
//! - keeps the set of active errors and derives the error register 1001h from them: bit 0
//!   (generic) whenever any error is active, plus the OR of the bits given with each error (bit 6 is
//!   reserved and always 0);
//! - records every raised error in the pre-defined error field 1003h, newest at sub-index 1, up to
//!   a fixed number of entries (older ones fall off); writing 0 to 1003h:00 clears it;
//! - sends `EMCY` frames on the CAN-ID of 1014h (default 80h + node-ID; bit 31 set = no EMCY):
//!   D0..D1 error code (LE), D2 error register, D3..D7 manufacturer data; and an error-reset EMCY
//!   (code 0000h, register 00h) when the last active error clears;
//! - holds frames back for the inhibit time 1015h (100 µs units) after each EMCY: queued EMCYs go
//!   out one per inhibit period, the first when the running inhibit time expires;
//! - sends only in Pre-operational and Operational (CiA 301 table of services per NMT state). In
//!   Stopped, EMCYs wait in the queue and go out on the return to Pre-operational or Operational,
//!   as CANopenNode does.
//!
//! Choice where sources disagree: the 1003h entry holds the error code in bits 15..0 and the first
//! two manufacturer bytes (D3, D4 of the frame, little-endian) in bits 31..16, so that a tester can
//! match a history entry against the EMCY frame it came with. CANopenNode stores D2..D3 instead and
//! fails the CCT's "Emergency 06" check on it; what the CCT compares exactly is not confirmed.

use std::collections::VecDeque;
use std::time::Duration;

use canopener_can::{CanFrame, Core, Instant, StandardId};
use canopener_od::{DynamicOd, ObjectKey};
use canopener_wire::{
    EMCY_BASE, ERROR_REGISTER_GENERIC, ERROR_REGISTER_RESERVED, EmcyMessage, NodeId, abort,
};

use crate::nmt_slave::{CommService, NmtSlaveState};

/// Bit 31 of 1014h: set = the EMCY object does not exist / is not valid.
pub const COB_ID_INVALID: u32 = 0x8000_0000;
/// The default number of 1003h entries kept.
pub const DEFAULT_HISTORY_LEN: usize = 8;
/// The number of EMCYs that may wait for the inhibit time or for the NMT state; more are dropped
/// and reported.
pub const QUEUE_LEN: usize = 16;

/// Why an EMCY configuration write was refused; [`EmcyConfigError::abort_code`] is the SDO abort
/// code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum EmcyConfigError {
    /// 1014h with bits other than 31 and the 11-bit CAN-ID set (29-bit EMCY is not supported) (0609
    /// 0030h).
    #[error("1014h = {value:#010X}: only bit 31 (invalid) and an 11-bit CAN-ID may be set")]
    UnsupportedCobId {
        /// The value written.
        value: u32,
    },
    /// 1014h: a valid COB-ID with another CAN-ID while the current one is valid (0609 0030h). Set
    /// bit 31 first, then write the new CAN-ID.
    #[error("1014h: the CAN-ID cannot change while the EMCY is valid; write it with bit 31 set first")]
    CanIdChangedWhileValid,
    /// 1014h: a valid COB-ID with a restricted CAN-ID (0609 0030h).
    #[error(
        "1014h: CAN-ID {can_id:03X}h is restricted (NMT, SDO, error control, reserved) and cannot carry EMCY"
    )]
    RestrictedCanId {
        /// The CAN-ID written.
        can_id: u16,
    },
    /// 1003h:00 written with a value other than 0 (0609 0030h).
    #[error("1003h:00 accepts only 0, which clears the error history; got {value}")]
    HistoryWriteNotZero {
        /// The value written.
        value: u8,
    },
    /// 1003h read above the number of stored errors (0800 0024h).
    #[error("1003h:{sub:02X} holds no error: only {count} are stored")]
    NoDataAvailable {
        /// The sub-index read.
        sub: u8,
        /// The number of stored errors.
        count: u8,
    },
    /// 1003h sub-index above the history length (0609 0011h).
    #[error("1003h:{sub:02X} does not exist: the error history holds at most {len} entries")]
    NoSuchHistoryEntry {
        /// The sub-index read.
        sub: u8,
        /// The history length.
        len: usize,
    },
}

impl EmcyConfigError {
    /// The SDO abort code an SDO server sends for this error.
    pub fn abort_code(&self) -> u32 {
        match self {
            EmcyConfigError::UnsupportedCobId { .. }
            | EmcyConfigError::CanIdChangedWhileValid
            | EmcyConfigError::RestrictedCanId { .. }
            | EmcyConfigError::HistoryWriteNotZero { .. } => abort::INVALID_VALUE,
            EmcyConfigError::NoDataAvailable { .. } => abort::NO_DATA_AVAILABLE,
            EmcyConfigError::NoSuchHistoryEntry { .. } => abort::SUB_INDEX_DOES_NOT_EXIST,
        }
    }
}

/// Why an EMCY was not sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DropReason {
    /// [`QUEUE_LEN`] EMCYs were already waiting.
    QueueFull,
    /// 1014h bit 31 is set: the EMCY object is not valid.
    CobIdInvalid,
}

/// What [`EmcyProducer`] reports to the `Device`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EmcyEvent {
    /// An EMCY was recorded (register, history) but its frame will not be sent.
    Dropped {
        /// The error code of the EMCY.
        code: u16,
        /// Why.
        reason: DropReason,
    },
}

#[derive(Debug, Clone, Copy)]
struct ActiveError {
    code: u16,
    bits: u8,
}

/// The EMCY producer of one node, with its error register and error history.
#[derive(Debug, Clone)]
pub struct EmcyProducer {
    cob_id: u32,
    inhibit_100us: u16,
    state: NmtSlaveState,
    active: Vec<ActiveError>,
    history: VecDeque<u32>,
    history_len: usize,
    pending: VecDeque<EmcyMessage>,
    inhibit_until: Instant,
    transmit: VecDeque<CanFrame>,
    events: VecDeque<EmcyEvent>,
}

impl EmcyProducer {
    /// A producer for `node`: COB-ID 80h + node-ID, no inhibit time, [`DEFAULT_HISTORY_LEN`]
    /// history entries, in Initialisation (so nothing is sent before
    /// [`EmcyProducer::set_state`] reports Pre-operational).
    pub fn new(node: NodeId) -> EmcyProducer {
        EmcyProducer {
            cob_id: u32::from(EMCY_BASE) + u32::from(node.get()),
            inhibit_100us: 0,
            state: NmtSlaveState::Initialisation,
            active: Vec::new(),
            history: VecDeque::new(),
            history_len: DEFAULT_HISTORY_LEN,
            pending: VecDeque::new(),
            inhibit_until: Instant::ZERO,
            transmit: VecDeque::new(),
            events: VecDeque::new(),
        }
    }

    /// Keeps at most `len` (clamped to 1..=254) entries in 1003h; the `Device` passes the number of
    /// sub-indices the EDS gives 1003h.
    pub fn with_history_len(mut self, len: usize) -> EmcyProducer {
        self.history_len = len.clamp(1, 254);
        self.history.truncate(self.history_len);
        self
    }

    /// 1014h, as last accepted.
    pub fn cob_id(&self) -> u32 {
        self.cob_id
    }

    /// 1014h was written. Refused (nothing changes) when bits other than 31 and 10..0 are set, when a
    /// valid COB-ID would change the CAN-ID of a valid one, or when a valid COB-ID uses a
    /// restricted CAN-ID (CiA 301 pre-defined connection set: the CCT expects 0609 0030h). Making
    /// the EMCY invalid drops the EMCYs waiting to be sent.
    pub fn set_cob_id(&mut self, value: u32) -> Result<(), EmcyConfigError> {
        if value & !(COB_ID_INVALID | 0x7FF) != 0 {
            return Err(EmcyConfigError::UnsupportedCobId { value });
        }
        let can_id = (value & 0x7FF) as u16;
        if value & COB_ID_INVALID == 0 {
            if self.cob_id & COB_ID_INVALID == 0 && (self.cob_id & 0x7FF) as u16 != can_id {
                return Err(EmcyConfigError::CanIdChangedWhileValid);
            }
            if crate::can_id::is_restricted(can_id) {
                return Err(EmcyConfigError::RestrictedCanId { can_id });
            }
        }
        self.cob_id = value;
        if value & COB_ID_INVALID != 0 {
            for message in std::mem::take(&mut self.pending) {
                self.events.push_back(EmcyEvent::Dropped {
                    code: message.code,
                    reason: DropReason::CobIdInvalid,
                });
            }
        }
        Ok(())
    }

    /// 1015h was written: the inhibit time in units of 100 µs, 0 = none. A running inhibit period
    /// keeps its end.
    pub fn set_inhibit_time(&mut self, now: Instant, units_100us: u16) {
        self.inhibit_100us = units_100us;
        self.flush(now);
    }

    /// The NMT slave changed state. EMCYs are sent in Pre-operational and Operational only;
    /// entering Initialisation (a reset) drops the queue and the running inhibit period.
    pub fn set_state(&mut self, now: Instant, state: NmtSlaveState) {
        self.state = state;
        if state == NmtSlaveState::Initialisation {
            self.pending.clear();
            self.transmit.clear();
            self.inhibit_until = Instant::ZERO;
        }
        self.flush(now);
    }

    /// An error appeared: `code` (not 0000h) with the error register bits it sets (the generic
    /// bit 0 is added) and 5 bytes of manufacturer data. Updates 1001h and 1003h and queues the
    /// EMCY. Returns `false` and does nothing if `code` is already active or is 0000h.
    pub fn raise(&mut self, now: Instant, code: u16, register_bits: u8, data: [u8; 5]) -> bool {
        if code == 0 || self.is_active(code) {
            return false;
        }
        self.active.push(ActiveError {
            code,
            bits: register_bits,
        });
        let [d3, d4, ..] = data;
        self.history
            .push_front(u32::from(code) | u32::from(u16::from_le_bytes([d3, d4])) << 16);
        self.history.truncate(self.history_len);
        let register = self.error_register();
        self.queue(
            now,
            EmcyMessage {
                code,
                register,
                vendor: data,
            },
        );
        true
    }

    /// An error went away. Updates 1001h; when it was the last active error, queues the
    /// error-reset EMCY (code 0000h, register 00h, no data). Returns `false` if `code` was not
    /// active.
    pub fn clear(&mut self, now: Instant, code: u16) -> bool {
        let before = self.active.len();
        self.active.retain(|e| e.code != code);
        if self.active.len() == before {
            return false;
        }
        if self.active.is_empty() {
            self.queue(
                now,
                EmcyMessage {
                    code: 0,
                    register: 0,
                    vendor: [0; 5],
                },
            );
        }
        true
    }

    /// Clears every active error (one error-reset EMCY if any was active).
    pub fn clear_all(&mut self, now: Instant) {
        if !self.active.is_empty() {
            self.active.clear();
            self.queue(
                now,
                EmcyMessage {
                    code: 0,
                    register: 0,
                    vendor: [0; 5],
                },
            );
        }
    }

    /// Whether `code` is active.
    pub fn is_active(&self, code: u16) -> bool {
        self.active.iter().any(|e| e.code == code)
    }

    /// The error register 1001h: 0 without active errors, else bit 0 plus the OR of their bits
    /// (bit 6 reserved, always 0).
    pub fn error_register(&self) -> u8 {
        if self.active.is_empty() {
            return 0;
        }
        let bits = self
            .active
            .iter()
            .fold(ERROR_REGISTER_GENERIC, |acc, e| acc | e.bits);
        bits & !ERROR_REGISTER_RESERVED
    }

    /// The pre-defined error field 1003h, newest first (sub-index 1 first).
    pub fn history(&self) -> impl ExactSizeIterator<Item = u32> + '_ {
        self.history.iter().copied()
    }

    /// The history length (the highest 1003h sub-index).
    pub fn history_len(&self) -> usize {
        self.history_len
    }

    /// Reads 1003h:`sub` as an SDO upload does: sub 0 is the number of stored errors, 1..=count an
    /// entry; above that 0800 0024h (no data available, as CiA 301 allows), above the history
    /// length 0609 0011h.
    pub fn read_history(&self, sub: u8) -> Result<u32, EmcyConfigError> {
        let count = self.history.len() as u8;
        if sub == 0 {
            return Ok(u32::from(count));
        }
        if usize::from(sub) > self.history_len {
            return Err(EmcyConfigError::NoSuchHistoryEntry {
                sub,
                len: self.history_len,
            });
        }
        self.history
            .get(usize::from(sub) - 1)
            .copied()
            .ok_or(EmcyConfigError::NoDataAvailable { sub, count })
    }

    /// 1003h:00 was written: 0 clears the history; anything else is refused with 0609 0030h.
    pub fn write_history_count(&mut self, value: u8) -> Result<(), EmcyConfigError> {
        if value != 0 {
            return Err(EmcyConfigError::HistoryWriteNotZero { value });
        }
        self.history.clear();
        Ok(())
    }

    /// Mirrors 1001h and 1003h into `od` (as the application, bypassing access checks) so SDO
    /// uploads and PDOs see them: 1001h:00, 1003h:00 = count, 1003h:01.. = entries, 0 beyond the
    /// count. Entries missing from `od` are skipped.
    pub fn sync_od(&self, od: &mut DynamicOd) {
        let _ = od.set_value(ObjectKey::new(0x1001, 0), &[self.error_register()]);
        let _ = od.set_value(ObjectKey::new(0x1003, 0), &[self.history.len() as u8]);
        for sub in 1..=self.history_len {
            let Ok(sub) = u8::try_from(sub) else { break };
            let value = self.history.get(usize::from(sub) - 1).copied().unwrap_or(0);
            let _ = od.set_value(ObjectKey::new(0x1003, sub), &value.to_le_bytes());
        }
    }

    fn can_send(&self) -> bool {
        self.state.is_active(CommService::Emcy) && self.cob_id & COB_ID_INVALID == 0
    }

    fn queue(&mut self, now: Instant, message: EmcyMessage) {
        if self.cob_id & COB_ID_INVALID != 0 {
            let reason = DropReason::CobIdInvalid;
            self.events.push_back(EmcyEvent::Dropped {
                code: message.code,
                reason,
            });
            return;
        }
        if self.pending.len() >= QUEUE_LEN {
            let reason = DropReason::QueueFull;
            self.events.push_back(EmcyEvent::Dropped {
                code: message.code,
                reason,
            });
            return;
        }
        self.pending.push_back(message);
        self.flush(now);
    }

    fn flush(&mut self, now: Instant) {
        while self.can_send() && now >= self.inhibit_until {
            let Some(message) = self.pending.pop_front() else {
                return;
            };
            let Some(id) = StandardId::new((self.cob_id & 0x7FF) as u16) else {
                return;
            };
            if let Ok(frame) = CanFrame::new(id, &message.encode()) {
                self.transmit.push_back(frame);
            }
            // Inhibit time in 100 µs units (CiA 301, EMCY inhibit time 1015h).
            self.inhibit_until = now + Duration::from_micros(u64::from(self.inhibit_100us) * 100);
        }
    }
}

impl Core for EmcyProducer {
    type Event = EmcyEvent;

    /// EmcyProducer takes no frames.
    fn handle_frame(&mut self, _now: Instant, _frame: &CanFrame) {}

    /// Sends the queued EMCY whose inhibit time has expired.
    fn handle_timeout(&mut self, now: Instant) {
        self.flush(now);
    }

    /// The next frame to send.
    fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.transmit.pop_front()
    }

    /// The next event for the `Device`.
    fn poll_event(&mut self) -> Option<Self::Event> {
        self.events.pop_front()
    }

    /// When a queued EMCY may go out: the end of the inhibit period, if EMCYs wait and the state
    /// allows sending.
    fn poll_timeout(&self) -> Option<Instant> {
        (!self.pending.is_empty() && self.can_send()).then_some(self.inhibit_until)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_can::Core;
    use canopener_od::{Access, DataType, Entry};
    use canopener_testkit::trace::{Trace, ms};

    fn producer() -> Trace<EmcyProducer> {
        let mut trace = Trace::new(EmcyProducer::new(NodeId::new(5).unwrap()));
        trace.core.set_state(Instant::ZERO, NmtSlaveState::PreOperational);
        trace
    }

    /// Raises at the trace's current time.
    fn raise(trace: &mut Trace<EmcyProducer>, code: u16, bits: u8, data: [u8; 5]) -> bool {
        let now = trace.now;
        trace.core.raise(now, code, bits, data)
    }

    fn clear(trace: &mut Trace<EmcyProducer>, code: u16) -> bool {
        let now = trace.now;
        trace.core.clear(now, code)
    }

    #[test]
    fn frame_layout_register_and_error_reset() {
        let mut trace = producer();
        trace.advance(ms(10));
        assert!(raise(&mut trace, 0x8130, 0x10, [1, 2, 3, 4, 5]));
        assert!(!raise(&mut trace, 0x8130, 0x10, [0; 5]), "already active");
        assert_eq!(trace.core.error_register(), 0x11);
        trace.advance(ms(20));
        assert!(raise(&mut trace, 0x3210, 0x04, [0; 5]));
        assert_eq!(trace.core.error_register(), 0x15);
        trace.advance(ms(30));
        assert!(clear(&mut trace, 0x8130));
        assert_eq!(trace.core.error_register(), 0x05);
        assert!(!clear(&mut trace, 0x8130), "not active any more");
        trace.advance(ms(40));
        assert!(clear(&mut trace, 0x3210));
        assert_eq!(trace.core.error_register(), 0);
        assert_eq!(
            trace.sent(),
            [
                "10.000 085#3081110102030405",
                "20.000 085#1032150000000000",
                "40.000 085#0000000000000000",
            ]
        );
    }

    #[test]
    fn reserved_register_bit_is_never_set_and_code_zero_is_not_an_error() {
        let mut trace = producer();
        assert!(raise(&mut trace, 0xFF00, 0xFF, [0; 5]));
        assert_eq!(trace.core.error_register(), 0xBF);
        assert!(!raise(&mut trace, 0x0000, 0x01, [0; 5]));
        trace.core.clear_all(Instant::ZERO);
        trace.core.clear_all(Instant::ZERO);
        assert_eq!(
            trace.sent(),
            ["0.000 085#00FFBF0000000000", "0.000 085#0000000000000000"]
        );
    }

    #[test]
    fn inhibit_time_queues_emcys() {
        let mut trace = producer();
        trace.core.set_inhibit_time(Instant::ZERO, 50); // 5 ms
        trace.advance(ms(10));
        raise(&mut trace, 0x1000, 0, [0; 5]);
        trace.advance(Instant::from_micros(11_000));
        raise(&mut trace, 0x2000, 0x02, [0; 5]);
        raise(&mut trace, 0x3000, 0x04, [0; 5]);
        assert_eq!(trace.core.poll_timeout(), Some(ms(15)));
        trace.advance(ms(30));
        raise(&mut trace, 0x4000, 0x08, [0; 5]);
        assert_eq!(
            trace.sent(),
            [
                "10.000 085#0010010000000000",
                "15.000 085#0020030000000000",
                "20.000 085#0030070000000000",
                "30.000 085#00400F0000000000",
            ]
        );
        assert_eq!(trace.core.poll_timeout(), None);
        trace.wait(Duration::from_micros(4_900));
        raise(&mut trace, 0x5000, 0, [0; 5]);
        trace.wait(Duration::from_micros(100));
        assert_eq!(
            trace.sent(),
            ["35.000 085#00500F0000000000"],
            "exactly 50 × 100 µs later"
        );
    }

    #[test]
    fn stopped_holds_emcys_until_pre_operational() {
        let mut trace = producer();
        trace.core.set_state(Instant::ZERO, NmtSlaveState::Stopped);
        raise(&mut trace, 0x5000, 0, [0; 5]);
        assert_eq!(trace.core.poll_timeout(), None);
        trace.advance(ms(100));
        assert!(trace.sent().is_empty());
        trace.core.set_state(ms(100), NmtSlaveState::Operational);
        assert_eq!(trace.sent(), ["100.000 085#0050010000000000"]);
    }

    #[test]
    fn nothing_is_sent_before_boot_and_reset_drops_the_queue() {
        let mut trace = Trace::new(EmcyProducer::new(NodeId::new(5).unwrap()));
        trace.core.raise(Instant::ZERO, 0x5000, 0, [0; 5]);
        trace.advance(ms(5));
        assert!(trace.sent().is_empty());
        trace.core.set_state(ms(5), NmtSlaveState::Initialisation);
        trace.core.set_state(ms(5), NmtSlaveState::PreOperational);
        assert!(trace.sent().is_empty());
        assert_eq!(trace.core.error_register(), 0x01, "the error itself stays active");
    }

    #[test]
    fn queue_overflow_is_reported() {
        let mut trace = producer();
        trace.core.set_state(Instant::ZERO, NmtSlaveState::Stopped);
        for code in 0..=(QUEUE_LEN as u16) {
            raise(&mut trace, 0x1000 + code, 0, [0; 5]);
        }
        let last = 0x1000 + QUEUE_LEN as u16;
        assert_eq!(
            trace.events(),
            [format!("0.000 Dropped {{ code: {last}, reason: QueueFull }}")]
        );
    }

    #[test]
    fn cob_id_from_1014h() {
        let mut trace = producer();
        let invalid = COB_ID_INVALID | 0x85;
        let err = trace.core.set_cob_id(0x95).unwrap_err();
        assert_eq!(err, EmcyConfigError::CanIdChangedWhileValid);
        assert_eq!(err.abort_code(), 0x0609_0030);
        assert_eq!(trace.core.set_cob_id(invalid), Ok(()));
        raise(&mut trace, 0x6100, 0, [0; 5]);
        assert_eq!(
            trace.events(),
            ["0.000 Dropped { code: 24832, reason: CobIdInvalid }"]
        );
        assert_eq!(trace.core.error_register(), 0x01, "recorded although not sent");
        assert_eq!(trace.core.set_cob_id(0x95), Ok(()));
        raise(&mut trace, 0x6200, 0, [0; 5]);
        assert_eq!(trace.sent(), ["0.000 095#0062010000000000"]);
        assert_eq!(trace.core.cob_id(), 0x95);
    }

    #[test]
    fn cob_id_invalid_drops_waiting_emcys() {
        let mut trace = producer();
        trace.core.set_inhibit_time(Instant::ZERO, 100);
        raise(&mut trace, 0x1000, 0, [0; 5]);
        raise(&mut trace, 0x2000, 0, [0; 5]);
        assert_eq!(trace.core.set_cob_id(COB_ID_INVALID | 0x85), Ok(()));
        trace.advance(ms(100));
        assert_eq!(trace.sent(), ["0.000 085#0010010000000000"]);
        assert_eq!(
            trace.events(),
            ["0.000 Dropped { code: 8192, reason: CobIdInvalid }"]
        );
    }

    #[test]
    fn restricted_and_unsupported_cob_ids_are_refused() {
        let mut producer = EmcyProducer::new(NodeId::new(5).unwrap());
        producer.set_cob_id(COB_ID_INVALID | 0x85).unwrap();
        for can_id in [
            0x000, 0x001, 0x07F, 0x101, 0x180, 0x581, 0x5FF, 0x601, 0x67F, 0x6E0, 0x701, 0x7E5, 0x7FF,
        ] {
            let err = producer.set_cob_id(can_id).unwrap_err();
            assert_eq!(
                err,
                EmcyConfigError::RestrictedCanId {
                    can_id: can_id as u16
                }
            );
            assert_eq!(err.abort_code(), 0x0609_0030);
        }
        for value in [0x4000_0085, 0x2000_0085, 0x0000_0885] {
            let err = producer.set_cob_id(value).unwrap_err();
            assert_eq!(err, EmcyConfigError::UnsupportedCobId { value });
            assert_eq!(err.abort_code(), 0x0609_0030);
        }
        assert_eq!(
            producer.cob_id(),
            COB_ID_INVALID | 0x85,
            "unchanged by refused writes"
        );
        for can_id in [0x080, 0x081, 0x0FF, 0x100, 0x181, 0x6DF] {
            assert_eq!(producer.set_cob_id(COB_ID_INVALID | can_id), Ok(()));
            assert_eq!(producer.set_cob_id(can_id), Ok(()), "{can_id:03X} is allowed");
            producer.set_cob_id(COB_ID_INVALID | can_id).unwrap();
        }
        assert_eq!(
            producer.set_cob_id(COB_ID_INVALID | 0x701),
            Ok(()),
            "invalid: not checked"
        );
    }

    #[test]
    fn error_history_newest_first_bounded_and_cleared() {
        let mut trace = Trace::new(EmcyProducer::new(NodeId::new(5).unwrap()).with_history_len(3));
        for (i, code) in [0x1000u16, 0x2000, 0x3000, 0x4000].into_iter().enumerate() {
            raise(&mut trace, code, 0, [i as u8, 0xAB, 0, 0, 0]);
        }
        assert_eq!(
            trace.core.history().collect::<Vec<_>>(),
            [0xAB03_4000, 0xAB02_3000, 0xAB01_2000]
        );
        assert_eq!(trace.core.read_history(0), Ok(3));
        assert_eq!(trace.core.read_history(1), Ok(0xAB03_4000));
        let err = trace.core.read_history(4).unwrap_err();
        assert_eq!(err.abort_code(), 0x0609_0011);
        let err = trace.core.write_history_count(2).unwrap_err();
        assert_eq!(err, EmcyConfigError::HistoryWriteNotZero { value: 2 });
        assert_eq!(err.abort_code(), 0x0609_0030);
        assert_eq!(trace.core.write_history_count(0), Ok(()));
        assert_eq!(trace.core.read_history(0), Ok(0));
        let err = trace.core.read_history(1).unwrap_err();
        assert_eq!(err, EmcyConfigError::NoDataAvailable { sub: 1, count: 0 });
        assert_eq!(err.abort_code(), 0x0800_0024);
        assert_eq!(
            trace.core.error_register(),
            0x01,
            "clearing the history keeps active errors"
        );
    }

    #[test]
    fn error_reset_is_not_recorded_in_the_history() {
        let mut trace = producer();
        raise(&mut trace, 0x1000, 0, [0; 5]);
        clear(&mut trace, 0x1000);
        assert_eq!(trace.core.history().collect::<Vec<_>>(), [0x0000_1000]);
    }

    #[test]
    fn sync_od_mirrors_1001h_and_1003h() {
        let u8_ro =
            |index, sub| Entry::new(ObjectKey::new(index, sub), DataType::UNSIGNED8, Access::Ro, &[0]);
        let u32_ro = |sub| {
            Entry::new(
                ObjectKey::new(0x1003, sub),
                DataType::UNSIGNED32,
                Access::Ro,
                &[0; 4],
            )
        };
        let mut od = DynamicOd::with_capacity(8);
        od.insert(u8_ro(0x1001, 0).unwrap()).unwrap();
        od.insert(u8_ro(0x1003, 0).unwrap()).unwrap();
        od.insert(u32_ro(1).unwrap()).unwrap();
        od.insert(u32_ro(2).unwrap()).unwrap();
        let mut trace = Trace::new(EmcyProducer::new(NodeId::new(5).unwrap()).with_history_len(2));
        raise(&mut trace, 0x2310, 0x02, [0; 5]);
        trace.core.sync_od(&mut od);
        assert_eq!(od.read(ObjectKey::new(0x1001, 0)), Ok(&[0x03][..]));
        assert_eq!(od.read(ObjectKey::new(0x1003, 0)), Ok(&[1][..]));
        assert_eq!(
            od.read(ObjectKey::new(0x1003, 1)),
            Ok(&0x2310u32.to_le_bytes()[..])
        );
        assert_eq!(od.read(ObjectKey::new(0x1003, 2)), Ok(&[0; 4][..]));
    }

    proptest::proptest! {
        /// EMCY has no frame input; arbitrary raise/clear sequences never panic and keep 1001h
        /// consistent with the active errors.
        #[test]
        fn raise_and_clear_never_panic(ops in proptest::collection::vec((proptest::prelude::any::<bool>(), 0u16..8, proptest::prelude::any::<u8>()), 0..60)) {
            let mut producer = EmcyProducer::new(NodeId::new(5).unwrap()).with_history_len(4);
            producer.set_state(Instant::ZERO, NmtSlaveState::Operational);
            producer.set_inhibit_time(Instant::ZERO, 7);
            for (i, (up, code, bits)) in ops.into_iter().enumerate() {
                let now = Instant::from_micros(i as u64 * 300);
                producer.handle_timeout(now);
                if up { producer.raise(now, code, bits, [0; 5]); } else { producer.clear(now, code); }
                proptest::prop_assert_eq!(producer.error_register() == 0, producer.active.is_empty());
                proptest::prop_assert!(producer.history().len() <= 4);
                while producer.poll_transmit().is_some() {}
            }
        }
    }
}

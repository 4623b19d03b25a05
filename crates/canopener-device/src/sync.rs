//! The SYNC consumer and producer (CiA 301, synchronisation object (SYNC) service, objects 1005h,
//! 1006h, 1007h and 1019h).
//!
//! One [`SyncService`] is both ends of SYNC for a node:
//! - COB-ID SYNC 1005h: bits 10..0 the CAN-ID (default 080h), bit 30 set = this node produces SYNC.
//!   Bit 31 is "don't care" in CiA 301 and kept as written; bit 29 (29-bit CAN-ID) is not supported
//!   and refused with 0609 0030h, like the restricted CAN-IDs. The CAN-ID cannot change while the
//!   node is and remains a producer (0609 0030h).
//! - Communication cycle period 1006h (µs, 0 = no SYNC produced): a producer sends SYNC exactly
//!   every period on virtual time, the first one a full period after production starts.
//! - Synchronous window length 1007h (µs, 0 = none): after each SYNC (received or produced) the
//!   service reports [`SyncEvent::WindowClosed`] when the window ends; the `Device` tells the PDO
//!   engine, which discards synchronous RPDOs until the next SYNC (its synchronous TPDOs go out at
//!   the SYNC itself, inside the window).
//! - Synchronous counter overflow value 1019h: 0 = SYNC carries no data (DLC 0); 2..240 = SYNC
//!   carries a counter byte that starts at 1 and wraps from the overflow value back to 1; 1 and
//!   241..255 are reserved (0609 0030h). 1019h cannot be written while 1006h ≠ 0 (0800 0022h).
//!
//! A consumed SYNC (a data frame on the SYNC CAN-ID while this node does not produce) with the
//! expected length is reported as [`SyncEvent::Sync`] with the counter byte, if any; a SYNC of the
//! wrong length (a counter byte where 1019h = 0, or none where 1019h ≠ 0) is not processed and is
//! reported as [`SyncEvent::WrongLength`], for which the `Device` sends EMCY
//! [`EMCY_SYNC_LENGTH`] (8240h, unexpected SYNC data length), as CANopenNode and lely do. A SYNC
//! this node produces is reported as [`SyncEvent::Sync`] too, since the node's own synchronous PDOs
//! follow it. Remote frames on the SYNC CAN-ID are ignored.
//!
//! SYNC runs in Pre-operational and Operational only (CiA 301 table of services per NMT state).
//!
//! A consumer with 1006h ≠ 0 monitors the SYNC as CANopenNode does (reference §4.1): once a SYNC
//! was received or produced, no SYNC within 1.5 × 1006h is reported as [`SyncEvent::Timeout`]
//! (the `Device` raises EMCY [`EMCY_SYNC_TIMEOUT`], 8100h), and the next SYNC as
//! [`SyncEvent::Resumed`] (the error clears). So a producer switched back to consumer (1005h bit
//! 30 cleared) while 1006h still holds a period times out, as CANopenNode does: a tester must set
//! 1006h to 0 before it clears bit 30.
//!
//! Choice where sources disagree or are silent: the counter restarts at 1 whenever production
//! (re)starts — 1005h bit 30 set, 1006h changed from 0, or the node (re)entering Pre-operational
//! or Operational — as CANopenNode and lely do (CiA 301's wording on this is unconfirmed). Writing
//! 1006h while producing retimes production from the write without touching the counter. A SYNC
//! received while this node is the producer (a second producer on the bus) is ignored.

use std::collections::VecDeque;
use std::time::Duration;

use canopener_can::{CanFrame, Core, Instant, StandardId};
use canopener_od::{DynamicOd, ObjectKey};
use canopener_wire::{SYNC_ID, abort};

use crate::nmt_slave::{CommService, NmtSlaveState};

/// Bit 30 of 1005h: set = this node produces SYNC.
pub const SYNC_PRODUCER: u32 = 0x4000_0000;
/// Bit 29 of 1005h: set = 29-bit CAN-ID (not supported).
pub const SYNC_FRAME_29BIT: u32 = 0x2000_0000;
/// Bit 31 of 1005h: "don't care" in CiA 301.
pub const SYNC_DONT_CARE: u32 = 0x8000_0000;
/// The EMCY error code the `Device` raises for [`SyncEvent::WrongLength`]: unexpected SYNC data
/// length (CiA 301 EMCY error codes).
pub const EMCY_SYNC_LENGTH: u16 = 0x8240;
/// The EMCY error code the `Device` raises for [`SyncEvent::Timeout`]: communication, generic (the
/// code CANopenNode reports its SYNC timeout with).
pub const EMCY_SYNC_TIMEOUT: u16 = 0x8100;

/// The COB-ID SYNC object.
pub const COB_ID_SYNC: u16 = 0x1005;
/// The communication cycle period object.
pub const COMMUNICATION_CYCLE_PERIOD: u16 = 0x1006;
/// The synchronous window length object.
pub const SYNC_WINDOW_LENGTH: u16 = 0x1007;
/// The synchronous counter overflow value object.
pub const SYNC_COUNTER_OVERFLOW: u16 = 0x1019;

/// Why a SYNC configuration write was refused; [`SyncConfigError::abort_code`] is the SDO abort
/// code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SyncConfigError {
    /// 1005h with bit 29 or any of bits 28..11 set (0609 0030h): only an 11-bit CAN-ID is supported.
    #[error("1005h = {value:#010X}: only bits 31, 30 and an 11-bit CAN-ID may be set")]
    UnsupportedCobId {
        /// The value written.
        value: u32,
    },
    /// 1005h with a restricted CAN-ID (0609 0030h).
    #[error(
        "1005h: CAN-ID {can_id:03X}h is restricted (NMT, SDO, error control, reserved) and cannot carry SYNC"
    )]
    RestrictedCanId {
        /// The CAN-ID written.
        can_id: u16,
    },
    /// 1005h: a new CAN-ID while this node is and remains the SYNC producer (0609 0030h). Clear bit 30
    /// first, then write the new CAN-ID.
    #[error("1005h: the CAN-ID cannot change while this node produces SYNC; clear bit 30 first")]
    CanIdChangedWhileProducing,
    /// 1019h = 1 or 241..255, reserved values (0609 0030h).
    #[error("1019h = {value} is reserved: use 0 (no counter) or 2..240")]
    CounterOverflowReserved {
        /// The value written.
        value: u8,
    },
    /// 1019h written while 1006h ≠ 0 (0800 0022h, as CiA 301 requires). Write 1006h = 0 first.
    #[error(
        "1019h cannot change while the communication cycle period 1006h is {period_us} µs; write 0 first"
    )]
    CounterOverflowWhilePeriodSet {
        /// The current 1006h.
        period_us: u32,
    },
}

impl SyncConfigError {
    /// The SDO abort code an SDO server sends for this error.
    pub fn abort_code(&self) -> u32 {
        match self {
            SyncConfigError::UnsupportedCobId { .. }
            | SyncConfigError::RestrictedCanId { .. }
            | SyncConfigError::CanIdChangedWhileProducing
            | SyncConfigError::CounterOverflowReserved { .. } => abort::INVALID_VALUE,
            SyncConfigError::CounterOverflowWhilePeriodSet { .. } => abort::CANNOT_TRANSFER_DEVICE_STATE,
        }
    }
}

/// What [`SyncService`] reports to the `Device` (and through it to the PDO engine).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SyncEvent {
    /// A SYNC was received or produced: synchronous PDOs act now. `counter` is the counter byte, or
    /// `None` for a SYNC without data.
    Sync {
        /// The counter byte (1..=1019h), if the SYNC carries one.
        counter: Option<u8>,
    },
    /// The synchronous window (1007h) after the last SYNC has ended: synchronous PDOs must not be
    /// sent or processed for this SYNC any more (CiA 301 §7.2.5.1); RPDOs received from now until
    /// the next SYNC are discarded.
    WindowClosed,
    /// A SYNC of the wrong length was received and ignored; the `Device` raises EMCY
    /// [`EMCY_SYNC_LENGTH`].
    WrongLength {
        /// The expected data length: 0 when 1019h = 0, else 1.
        expected: u8,
        /// The data length received.
        received: u8,
    },
    /// A consumer with 1006h ≠ 0 got no SYNC within 1.5 × 1006h of the last one; the `Device`
    /// raises EMCY [`EMCY_SYNC_TIMEOUT`].
    Timeout,
    /// A SYNC came after a [`SyncEvent::Timeout`]; the `Device` clears the error.
    Resumed,
}

/// The SYNC consumer and producer of one node.
#[derive(Debug, Clone)]
pub struct SyncService {
    cob_id: u32,
    period_us: u32,
    window_us: u32,
    overflow: u8,
    state: NmtSlaveState,
    /// Counter byte of the next produced SYNC (1..=overflow).
    next_counter: u8,
    /// When the next SYNC is produced, while producing.
    next_sync: Option<Instant>,
    /// When the synchronous window after the last SYNC closes.
    window_end: Option<Instant>,
    /// When the last SYNC was received or produced (the consumer's timeout counts from it); `None`
    /// before the first, which arms the monitoring.
    last_sync: Option<Instant>,
    /// A [`SyncEvent::Timeout`] was reported and no SYNC has come since.
    timed_out: bool,
    transmit: VecDeque<CanFrame>,
    events: VecDeque<SyncEvent>,
}

impl Default for SyncService {
    fn default() -> Self {
        SyncService::new()
    }
}

impl SyncService {
    /// A consumer on CAN-ID 080h, not producing, no window, no counter, in Initialisation (so
    /// nothing runs before [`SyncService::set_state`] reports Pre-operational). The `Device` then
    /// loads the power-on values with [`SyncService::load_od`].
    pub fn new() -> SyncService {
        SyncService {
            cob_id: u32::from(SYNC_ID),
            period_us: 0,
            window_us: 0,
            overflow: 0,
            state: NmtSlaveState::Initialisation,
            next_counter: 1,
            next_sync: None,
            window_end: None,
            last_sync: None,
            timed_out: false,
            transmit: VecDeque::new(),
            events: VecDeque::new(),
        }
    }

    /// 1005h, as last accepted.
    pub fn cob_id(&self) -> u32 {
        self.cob_id
    }

    /// 1006h in µs, as last accepted.
    pub fn period_us(&self) -> u32 {
        self.period_us
    }

    /// 1007h in µs, as last accepted.
    pub fn window_us(&self) -> u32 {
        self.window_us
    }

    /// 1019h, as last accepted.
    pub fn counter_overflow(&self) -> u8 {
        self.overflow
    }

    /// Whether this node is configured as the SYNC producer (1005h bit 30).
    pub fn is_producer(&self) -> bool {
        self.cob_id & SYNC_PRODUCER != 0
    }

    /// Whether SYNC frames are being produced now: producer bit set, 1006h ≠ 0 and the NMT state
    /// allows SYNC.
    pub fn is_producing(&self) -> bool {
        self.next_sync.is_some()
    }

    /// Checks a 1005h value against the current configuration without applying it.
    pub fn check_cob_id(&self, value: u32) -> Result<(), SyncConfigError> {
        if value & !(SYNC_DONT_CARE | SYNC_PRODUCER | 0x7FF) != 0 {
            return Err(SyncConfigError::UnsupportedCobId { value });
        }
        let can_id = (value & 0x7FF) as u16;
        // The CCT writes every restricted CAN-ID into 1005h and expects 0609 0030h whatever bit 30.
        if crate::can_id::is_restricted(can_id) {
            return Err(SyncConfigError::RestrictedCanId { can_id });
        }
        if self.is_producer() && value & SYNC_PRODUCER != 0 && (self.cob_id & 0x7FF) as u16 != can_id {
            return Err(SyncConfigError::CanIdChangedWhileProducing);
        }
        Ok(())
    }

    /// 1005h was written: checked as [`SyncService::check_cob_id`] does, then applied. Setting bit
    /// 30 starts production (if 1006h ≠ 0), clearing it stops it.
    pub fn set_cob_id(&mut self, now: Instant, value: u32) -> Result<(), SyncConfigError> {
        self.check_cob_id(value)?;
        self.cob_id = value;
        self.reschedule(now, false);
        Ok(())
    }

    /// 1006h was written (any value is valid). Starting from 0 restarts the counter; a change while
    /// producing retimes production from `now`; 0 stops production.
    pub fn set_period(&mut self, now: Instant, period_us: u32) {
        let changed = period_us != self.period_us;
        self.period_us = period_us;
        self.reschedule(now, changed);
    }

    /// 1007h was written (any value is valid). A window already running keeps its end.
    pub fn set_window(&mut self, window_us: u32) {
        self.window_us = window_us;
        if window_us == 0 {
            self.window_end = None;
        }
    }

    /// Checks a 1019h value against the current configuration without applying it: 1 and 241..255
    /// are refused with 0609 0030h, any value while 1006h ≠ 0 with 0800 0022h.
    pub fn check_counter_overflow(&self, value: u8) -> Result<(), SyncConfigError> {
        if value == 1 || value > 240 {
            return Err(SyncConfigError::CounterOverflowReserved { value });
        }
        if self.period_us != 0 {
            return Err(SyncConfigError::CounterOverflowWhilePeriodSet {
                period_us: self.period_us,
            });
        }
        Ok(())
    }

    /// 1019h was written: checked as [`SyncService::check_counter_overflow`] does, then applied; the
    /// counter restarts at 1.
    pub fn set_counter_overflow(&mut self, value: u8) -> Result<(), SyncConfigError> {
        self.check_counter_overflow(value)?;
        self.overflow = value;
        self.next_counter = 1;
        Ok(())
    }

    /// The check the `Device`'s [`SdoHooks::check_download`](crate::sdo_server::SdoHooks) makes for
    /// an SDO download of `data` to `key`, before the dictionary stores it. Keys other than 1005h:00
    /// and 1019h:00, and data of the wrong length (which the dictionary refuses), pass. After the
    /// download, the `Device` applies the stored value with [`SyncService::load_od`].
    pub fn check_download(&self, key: ObjectKey, data: &[u8]) -> Result<(), SyncConfigError> {
        match (key.index, key.sub, data) {
            (COB_ID_SYNC, 0, &[a, b, c, d]) => self.check_cob_id(u32::from_le_bytes([a, b, c, d])),
            (SYNC_COUNTER_OVERFLOW, 0, &[value]) => self.check_counter_overflow(value),
            _ => Ok(()),
        }
    }

    /// Takes 1005h, 1006h, 1007h and 1019h from `od` (power-on values, or values an SDO download
    /// just stored). Missing entries keep their current value. Values the dictionary holds but a
    /// write would have been refused for (from a faulty EDS) are taken as close as possible: a 29-bit
    /// or restricted COB-ID keeps the current CAN-ID, a reserved 1019h counts as 0.
    pub fn load_od(&mut self, now: Instant, od: &DynamicOd) {
        let u32_at = |index| match od.get(ObjectKey::new(index, 0)).map(|e| e.value()) {
            Some(&[a, b, c, d]) => Some(u32::from_le_bytes([a, b, c, d])),
            _ => None,
        };
        if let Some(&[value]) = od
            .get(ObjectKey::new(SYNC_COUNTER_OVERFLOW, 0))
            .map(|e| e.value())
        {
            let value = if value == 1 || value > 240 { 0 } else { value };
            if value != self.overflow {
                self.overflow = value;
                self.next_counter = 1;
            }
        }
        if let Some(window) = u32_at(SYNC_WINDOW_LENGTH) {
            self.set_window(window);
        }
        if let Some(value) = u32_at(COB_ID_SYNC) {
            let can_id = (value & 0x7FF) as u16;
            let fits = value & !(SYNC_DONT_CARE | SYNC_PRODUCER | 0x7FF) == 0
                && !crate::can_id::is_restricted(can_id);
            let can_id = if fits { value & 0x7FF } else { self.cob_id & 0x7FF };
            self.cob_id = value & (SYNC_DONT_CARE | SYNC_PRODUCER) | can_id;
        }
        match u32_at(COMMUNICATION_CYCLE_PERIOD) {
            Some(period) if period != self.period_us => self.set_period(now, period),
            _ => self.reschedule(now, false),
        }
    }

    /// The NMT slave changed state. SYNC runs in Pre-operational and Operational; (re)entering
    /// them restarts production (counter at 1, first SYNC one period later), leaving them stops it.
    pub fn set_state(&mut self, now: Instant, state: NmtSlaveState) {
        let was = self.state.is_active(CommService::Sync);
        self.state = state;
        if !state.is_active(CommService::Sync) {
            self.window_end = None;
            self.transmit.clear();
        }
        // The timeout counts from a state change, as CANopenNode restarts its timer outside
        // Pre-operational and Operational.
        if self.last_sync.is_some() {
            self.last_sync = Some(now);
        }
        self.reschedule(now, !was);
    }

    /// When a consumer with 1006h ≠ 0 that has seen a SYNC reports [`SyncEvent::Timeout`]: 1.5 ×
    /// 1006h after the last SYNC.
    fn timeout_due(&self) -> Option<Instant> {
        let monitoring = !self.is_producer()
            && self.period_us != 0
            && !self.timed_out
            && self.state.is_active(CommService::Sync);
        let period = Duration::from_micros(u64::from(self.period_us));
        self.last_sync
            .filter(|_| monitoring)
            .map(|last| last + period + period / 2)
    }

    fn synchronise(&mut self, now: Instant, counter: Option<u8>) {
        self.last_sync = Some(now);
        if self.timed_out {
            self.timed_out = false;
            self.events.push_back(SyncEvent::Resumed);
        }
        self.events.push_back(SyncEvent::Sync { counter });
        self.window_end =
            (self.window_us != 0).then(|| now + Duration::from_micros(u64::from(self.window_us)));
    }

    /// Starts, stops or retimes production after a configuration or state change. `restart_timing`
    /// asks for a new period from `now` even if production was already running.
    fn reschedule(&mut self, now: Instant, restart_timing: bool) {
        let should = self.is_producer() && self.period_us != 0 && self.state.is_active(CommService::Sync);
        if !should {
            self.next_sync = None;
            return;
        }
        if self.next_sync.is_none() {
            self.next_counter = 1;
        } else if !restart_timing {
            return;
        }
        self.next_sync = Some(now + Duration::from_micros(u64::from(self.period_us)));
    }
}

impl Core for SyncService {
    type Event = SyncEvent;

    /// Feeds a received frame: a data frame on the SYNC CAN-ID (11-bit) is a SYNC to consume,
    /// unless this node is the producer or the NMT state does not allow SYNC.
    fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
        if frame.id().is_extended()
            || frame.id().as_raw() != self.cob_id & 0x7FF
            || frame.is_remote()
            || self.is_producer()
            || !self.state.is_active(CommService::Sync)
        {
            return;
        }
        let expected = u8::from(self.overflow != 0);
        match (self.overflow, frame.data()) {
            (0, []) => self.synchronise(now, None),
            (1.., &[counter]) => self.synchronise(now, Some(counter)),
            (_, data) => self.events.push_back(SyncEvent::WrongLength {
                expected,
                received: data.len() as u8,
            }),
        }
    }

    /// Produces the SYNC that is due and closes the window that has ended.
    fn handle_timeout(&mut self, now: Instant) {
        if self.window_end.is_some_and(|end| end <= now) {
            self.window_end = None;
            self.events.push_back(SyncEvent::WindowClosed);
        }
        if self.timeout_due().is_some_and(|due| due <= now) {
            self.timed_out = true;
            self.events.push_back(SyncEvent::Timeout);
        }
        let Some(due) = self.next_sync else { return };
        if due > now {
            return;
        }
        let period = Duration::from_micros(u64::from(self.period_us));
        let mut next = due + period;
        // A driver that calls late gets one SYNC, not a burst; on time, the period stays exact.
        if next <= now {
            next = now + period;
        }
        self.next_sync = Some(next);
        let counter = (self.overflow != 0).then(|| {
            let counter = self.next_counter;
            self.next_counter = if counter >= self.overflow { 1 } else { counter + 1 };
            counter
        });
        let data = counter.map(|c| vec![c]).unwrap_or_default();
        if let Some(id) = StandardId::new((self.cob_id & 0x7FF) as u16)
            && let Ok(frame) = CanFrame::new(id, &data)
        {
            self.transmit.push_back(frame);
        }
        self.synchronise(now, counter);
    }

    /// The next frame to send.
    fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.transmit.pop_front()
    }

    /// The next event for the `Device`.
    fn poll_event(&mut self) -> Option<Self::Event> {
        self.events.pop_front()
    }

    /// When the next SYNC is produced, the synchronous window closes or the consumer times out,
    /// whichever is first.
    fn poll_timeout(&self) -> Option<Instant> {
        [self.next_sync, self.window_end, self.timeout_due()]
            .into_iter()
            .flatten()
            .min()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use NmtSlaveState::{Initialisation as Init, Operational as Op, PreOperational as PreOp, Stopped};
    use canopener_can::Core;
    use canopener_od::{Access, DataType, Entry};
    use canopener_testkit::frames::any_frame;
    use canopener_testkit::trace::{Trace, ms};

    fn us(micros: u64) -> Instant {
        Instant::from_micros(micros)
    }

    /// A SYNC service, pre-operational at t = 0.
    fn booted() -> Trace<SyncService> {
        let mut trace = Trace::new(SyncService::new());
        trace.core.set_state(Instant::ZERO, PreOp);
        trace
    }

    /// A producer on 080h with the given period (µs) and counter overflow, started at t = 0.
    fn producer(period_us: u32, overflow: u8) -> Trace<SyncService> {
        let mut trace = booted();
        trace.core.set_counter_overflow(overflow).unwrap();
        trace
            .core
            .set_cob_id(Instant::ZERO, SYNC_PRODUCER | 0x80)
            .unwrap();
        trace.core.set_period(Instant::ZERO, period_us);
        trace
    }

    #[test]
    fn producer_period_is_exact_on_virtual_time() {
        let mut trace = producer(10_000, 0);
        trace.advance(ms(35));
        assert_eq!(trace.sent(), ["10.000 080#", "20.000 080#", "30.000 080#"]);
        assert_eq!(
            trace.events(),
            [
                "10.000 Sync { counter: None }",
                "20.000 Sync { counter: None }",
                "30.000 Sync { counter: None }"
            ]
        );
        assert_eq!(trace.core.poll_timeout(), Some(ms(40)));
        // Sub-millisecond periods stay exact too.
        let mut trace = producer(250, 0);
        trace.advance(us(1000));
        assert_eq!(
            trace.sent(),
            ["0.250 080#", "0.500 080#", "0.750 080#", "1.000 080#"]
        );
    }

    #[test]
    fn a_consumer_with_a_period_times_out_after_one_and_a_half_periods_once_it_saw_a_sync() {
        let mut trace = booted();
        trace.core.set_period(Instant::ZERO, 10_000);
        // Not armed before the first SYNC: no timeout at all.
        trace.advance(ms(100));
        assert!(trace.events().is_empty());
        trace.rx(ms(100), "080#");
        trace.advance(ms(114));
        assert_eq!(trace.events(), ["100.000 Sync { counter: None }"]);
        trace.advance(ms(116));
        assert_eq!(trace.events(), ["115.000 Timeout"]);
        // Reported once; the next SYNC clears it.
        trace.advance(ms(200));
        assert!(trace.events().is_empty());
        trace.rx(ms(200), "080#");
        assert_eq!(
            trace.events(),
            ["200.000 Resumed", "200.000 Sync { counter: None }"]
        );
        // 1006h = 0: no monitoring.
        trace.core.set_period(ms(201), 0);
        trace.advance(ms(400));
        assert!(trace.events().is_empty());
    }

    #[test]
    fn a_producer_switched_to_consumer_with_the_period_set_times_out_but_not_with_the_period_first() {
        // CANopenNode's behaviour the conformance write-back must respect: bit 30 cleared while
        // 1006h still runs makes the node a consumer that misses its SYNC.
        let mut trace = producer(10_000, 0);
        trace.advance(ms(25));
        trace.events();
        trace.core.set_cob_id(ms(25), 0x80).unwrap();
        trace.advance(ms(40));
        assert_eq!(trace.events(), ["35.000 Timeout"]);
        // 1006h to 0 first, then bit 30: nothing.
        let mut trace = producer(10_000, 0);
        trace.advance(ms(25));
        trace.events();
        trace.core.set_period(ms(25), 0);
        trace.core.set_cob_id(ms(25), 0x80).unwrap();
        trace.advance(ms(100));
        assert!(trace.events().is_empty());
    }

    #[test]
    fn producer_counter_wraps_from_overflow_to_one() {
        // The CCT expects 1,2,3,4,5,1,2,… for 1019h = 5.
        let mut trace = producer(1000, 5);
        trace.advance(ms(7));
        assert_eq!(
            trace.sent(),
            [
                "1.000 080#01",
                "2.000 080#02",
                "3.000 080#03",
                "4.000 080#04",
                "5.000 080#05",
                "6.000 080#01",
                "7.000 080#02"
            ]
        );
        assert_eq!(trace.events()[5], "6.000 Sync { counter: Some(1) }");
        let mut trace = producer(1000, 240);
        trace.advance(ms(241));
        let sent = trace.sent();
        assert_eq!(sent[239], "240.000 080#F0");
        assert_eq!(sent[240], "241.000 080#01");
    }

    #[test]
    fn late_driver_does_not_burst() {
        let mut sync = SyncService::new();
        sync.set_state(Instant::ZERO, PreOp);
        sync.set_cob_id(Instant::ZERO, SYNC_PRODUCER | 0x80).unwrap();
        sync.set_period(Instant::ZERO, 10_000);
        sync.handle_timeout(ms(55));
        assert!(sync.poll_transmit().is_some());
        assert!(sync.poll_transmit().is_none());
        assert_eq!(sync.poll_timeout(), Some(ms(65)));
    }

    #[test]
    fn producer_follows_1005h_1006h_and_nmt_state() {
        let mut trace = booted();
        trace.core.set_period(Instant::ZERO, 10_000);
        trace.advance(ms(25));
        assert!(trace.sent().is_empty(), "1005h bit 30 not set: consumer only");
        trace.core.set_cob_id(ms(25), SYNC_PRODUCER | 0x80).unwrap();
        trace.advance(ms(50));
        trace.core.set_period(ms(50), 5000); // retimed from the write
        trace.advance(ms(61));
        trace.core.set_state(ms(61), Stopped);
        trace.advance(ms(100));
        trace.core.set_state(ms(100), Op);
        trace.advance(ms(111));
        trace.core.set_cob_id(ms(111), 0x80).unwrap();
        trace.advance(ms(200));
        trace.core.set_cob_id(ms(200), SYNC_PRODUCER | 0x80).unwrap();
        trace.core.set_period(ms(200), 0);
        trace.advance(ms(300));
        assert_eq!(
            trace.sent(),
            [
                "35.000 080#",
                "45.000 080#",
                "55.000 080#",
                "60.000 080#",
                "105.000 080#",
                "110.000 080#"
            ]
        );
        assert_eq!(trace.core.poll_timeout(), None);
    }

    #[test]
    fn counter_restarts_when_production_restarts() {
        let mut trace = producer(1000, 3);
        trace.advance(ms(2));
        trace.core.set_state(ms(2), Stopped);
        trace.core.set_state(ms(2), PreOp);
        trace.advance(ms(4));
        trace.core.set_state(ms(4), Init);
        trace.advance(ms(10));
        assert_eq!(
            trace.sent(),
            ["1.000 080#01", "2.000 080#02", "3.000 080#01", "4.000 080#02"],
            "nothing during initialisation"
        );
    }

    #[test]
    fn consumer_with_and_without_counter() {
        let mut trace = booted();
        trace.rx(ms(10), "080#");
        trace.rx(ms(20), "080#07"); // wrong length: 1019h = 0
        trace.rx(ms(25), "080#R"); // remote frames are not SYNC
        trace.rx(ms(26), "081#"); // another CAN-ID
        trace.core.set_counter_overflow(10).unwrap();
        trace.rx(ms(30), "080#07");
        trace.rx(ms(40), "080#"); // wrong length: 1019h ≠ 0
        trace.rx(ms(50), "080#0102");
        assert_eq!(
            trace.events(),
            [
                "10.000 Sync { counter: None }",
                "20.000 WrongLength { expected: 0, received: 1 }",
                "30.000 Sync { counter: Some(7) }",
                "40.000 WrongLength { expected: 1, received: 0 }",
                "50.000 WrongLength { expected: 1, received: 2 }",
            ]
        );
        assert!(trace.sent().is_empty());
        assert_eq!(EMCY_SYNC_LENGTH, 0x8240);
    }

    #[test]
    fn consumer_follows_can_id_and_nmt_state() {
        let mut trace = Trace::new(SyncService::new());
        trace.rx(ms(1), "080#"); // initialisation
        trace.core.set_state(ms(2), PreOp);
        trace.core.set_cob_id(ms(2), 0x90).unwrap();
        trace.rx(ms(3), "080#");
        trace.rx(ms(4), "090#");
        trace.core.set_state(ms(5), Stopped);
        trace.rx(ms(6), "090#");
        trace.core.set_state(ms(7), Op);
        trace.rx(ms(8), "090#");
        trace.core.set_cob_id(ms(9), SYNC_PRODUCER | 0x90).unwrap();
        trace.rx(ms(10), "090#"); // a second producer: ignored
        assert_eq!(
            trace.events(),
            ["4.000 Sync { counter: None }", "8.000 Sync { counter: None }"]
        );
    }

    #[test]
    fn window_closes_after_each_sync() {
        let mut trace = booted();
        trace.core.set_window(3000);
        trace.rx(ms(10), "080#");
        trace.rx(ms(20), "080#");
        trace.rx(ms(21), "080#"); // restarts the window
        trace.advance(ms(30));
        trace.core.set_window(0);
        trace.rx(ms(40), "080#");
        trace.advance(ms(100));
        assert_eq!(
            trace.events(),
            [
                "10.000 Sync { counter: None }",
                "13.000 WindowClosed",
                "20.000 Sync { counter: None }",
                "21.000 Sync { counter: None }",
                "24.000 WindowClosed",
                "40.000 Sync { counter: None }",
            ]
        );
    }

    #[test]
    fn window_with_producer() {
        let mut trace = producer(10_000, 0);
        trace.core.set_window(2500);
        trace.advance(ms(25));
        assert_eq!(
            trace.events(),
            [
                "10.000 Sync { counter: None }",
                "12.500 WindowClosed",
                "20.000 Sync { counter: None }",
                "22.500 WindowClosed"
            ]
        );
        trace.core.set_state(ms(25), Stopped);
        assert_eq!(trace.core.poll_timeout(), None);
    }

    #[test]
    fn cob_id_errors() {
        let mut sync = SyncService::new();
        for can_id in [
            0x000u32, 0x001, 0x07F, 0x101, 0x180, 0x581, 0x5FF, 0x601, 0x67F, 0x6E0, 0x701, 0x7E5, 0x7FF,
        ] {
            for bits in [0, SYNC_PRODUCER] {
                let err = sync.set_cob_id(Instant::ZERO, bits | can_id).unwrap_err();
                assert_eq!(
                    err,
                    SyncConfigError::RestrictedCanId {
                        can_id: can_id as u16
                    }
                );
                assert_eq!(err.abort_code(), 0x0609_0030);
            }
        }
        for value in [0x2000_0080, 0x0000_0880, 0x1000_0080] {
            let err = sync.set_cob_id(Instant::ZERO, value).unwrap_err();
            assert_eq!(err, SyncConfigError::UnsupportedCobId { value });
            assert_eq!(err.abort_code(), 0x0609_0030);
        }
        assert_eq!(sync.cob_id(), 0x80, "unchanged by refused writes");
        assert_eq!(
            sync.set_cob_id(Instant::ZERO, 0x8000_0081),
            Ok(()),
            "bit 31: don't care"
        );
        assert_eq!(sync.set_cob_id(Instant::ZERO, SYNC_PRODUCER | 0x80), Ok(()));
        let err = sync.set_cob_id(Instant::ZERO, SYNC_PRODUCER | 0x90).unwrap_err();
        assert_eq!(err, SyncConfigError::CanIdChangedWhileProducing);
        assert_eq!(err.abort_code(), 0x0609_0030);
        assert_eq!(
            sync.set_cob_id(Instant::ZERO, 0x90),
            Ok(()),
            "leaving production may move it"
        );
        assert_eq!(sync.set_cob_id(Instant::ZERO, SYNC_PRODUCER | 0x100), Ok(()));
    }

    #[test]
    fn counter_overflow_errors() {
        let mut sync = SyncService::new();
        for value in [1u8, 241, 255] {
            let err = sync.set_counter_overflow(value).unwrap_err();
            assert_eq!(err, SyncConfigError::CounterOverflowReserved { value });
            assert_eq!(err.abort_code(), 0x0609_0030);
        }
        for value in [0u8, 2, 240] {
            assert_eq!(sync.set_counter_overflow(value), Ok(()));
        }
        sync.set_period(Instant::ZERO, 1000);
        let err = sync.set_counter_overflow(5).unwrap_err();
        assert_eq!(
            err,
            SyncConfigError::CounterOverflowWhilePeriodSet { period_us: 1000 }
        );
        assert_eq!(err.abort_code(), 0x0800_0022);
        assert_eq!(sync.counter_overflow(), 240);
        sync.set_period(Instant::ZERO, 0);
        assert_eq!(sync.set_counter_overflow(5), Ok(()));
    }

    fn u32_rw(index: u16, value: u32) -> Entry {
        Entry::new(
            ObjectKey::new(index, 0),
            DataType::UNSIGNED32,
            Access::Rw,
            &value.to_le_bytes(),
        )
        .unwrap()
    }

    #[test]
    fn check_download_and_load_od() {
        let mut od = DynamicOd::with_capacity(4);
        od.insert(u32_rw(COB_ID_SYNC, 0x80)).unwrap();
        od.insert(u32_rw(COMMUNICATION_CYCLE_PERIOD, 0)).unwrap();
        od.insert(u32_rw(SYNC_WINDOW_LENGTH, 0)).unwrap();
        let overflow = ObjectKey::new(SYNC_COUNTER_OVERFLOW, 0);
        od.insert(Entry::new(overflow, DataType::UNSIGNED8, Access::Rw, &[0]).unwrap())
            .unwrap();
        let mut trace = booted();
        let cob = ObjectKey::new(COB_ID_SYNC, 0);
        let period = ObjectKey::new(COMMUNICATION_CYCLE_PERIOD, 0);
        assert_eq!(
            trace
                .core
                .check_download(cob, &0x0000_0701u32.to_le_bytes())
                .unwrap_err()
                .abort_code(),
            0x0609_0030
        );
        assert_eq!(
            trace.core.check_download(cob, &[1, 2]),
            Ok(()),
            "length: the dictionary's job"
        );
        assert_eq!(trace.core.check_download(period, &[0xFF; 4]), Ok(()));
        assert_eq!(
            trace
                .core
                .check_download(overflow, &[1])
                .unwrap_err()
                .abort_code(),
            0x0609_0030
        );
        // The SDO server stores the values, then the Device applies them.
        od.write(overflow, &[3]).unwrap();
        od.write(cob, &(SYNC_PRODUCER | 0x80).to_le_bytes()).unwrap();
        od.write(period, &2000u32.to_le_bytes()).unwrap();
        trace.core.load_od(Instant::ZERO, &od);
        assert_eq!(
            trace
                .core
                .check_download(overflow, &[4])
                .unwrap_err()
                .abort_code(),
            0x0800_0022
        );
        trace.advance(ms(8));
        assert_eq!(
            trace.sent(),
            ["2.000 080#01", "4.000 080#02", "6.000 080#03", "8.000 080#01"]
        );
        // Reloading unchanged values does not disturb the running period.
        trace.core.load_od(ms(9), &od);
        trace.advance(ms(10));
        assert_eq!(trace.sent(), ["10.000 080#02"]);
        // A faulty dictionary value is taken as close as possible.
        od.set_value(overflow, &[1]).unwrap();
        od.set_value(cob, &0x0000_0701u32.to_le_bytes()).unwrap();
        od.set_value(period, &0u32.to_le_bytes()).unwrap();
        trace.core.load_od(ms(10), &od);
        assert_eq!(trace.core.counter_overflow(), 0);
        assert_eq!(trace.core.cob_id(), 0x80);
        assert!(!trace.core.is_producing());
    }

    proptest::proptest! {
        #[test]
        fn no_frame_panics(frames in proptest::collection::vec(any_frame(), 0..50), overflow in 0u8..=255) {
            let mut sync = SyncService::new();
            sync.set_state(Instant::ZERO, Op);
            let _ = sync.set_counter_overflow(overflow);
            sync.set_window(3000);
            let mut producer = SyncService::new();
            producer.set_state(Instant::ZERO, PreOp);
            let _ = producer.set_counter_overflow(overflow);
            producer.set_cob_id(Instant::ZERO, SYNC_PRODUCER | 0x80).unwrap();
            producer.set_period(Instant::ZERO, 1500);
            for (i, frame) in frames.iter().enumerate() {
                let now = ms(i as u64 * 7);
                for core in [&mut sync, &mut producer] {
                    core.handle_timeout(now);
                    core.handle_frame(now, frame);
                    while core.poll_transmit().is_some() {}
                    while core.poll_event().is_some() {}
                }
            }
        }
    }
}

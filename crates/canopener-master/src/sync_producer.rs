//! The SYNC producer (CiA 301 §7.2.5): a SYNC frame every communication cycle period.
//!
//! Before changing this file read CiA 301 §7.2.5 (SYNC) and the descriptions of objects 1005h, 1006h,
//! 1007h and 1019h.
//!
//! [`SyncConfig`] carries what a SYNC-producing device keeps in its dictionary: the CAN-ID (1005h,
//! default 080h), the period (1006h), the counter overflow value (1019h) and the synchronous window
//! length (1007h). The window is only recorded: closing it is the consumers' business.
//!
//! With a counter overflow value (2 to 240), every SYNC carries one byte: 1 in the first SYNC after
//! [`SyncProducer::start`], then counting up and wrapping from the overflow value back to 1.
//! Without one, SYNC has no data.
//!
//! Timing: the first SYNC is due at [`SyncProducer::start`] itself, so traffic starts at once; the
//! device side of this toolkit waits a period first, as CANopenNode does, and CiA 301 allows both.
//! Deadlines are `start + k × period`: each one is the previous deadline plus the period, never
//! "now plus the period", so a driver that wakes a little late does not make the cycle drift. A
//! driver that wakes a period or more late does not get a burst of SYNCs: the deadlines that have
//! passed are skipped, one SYNC goes out for the latest, and [`SyncEvent::Overrun`] says how many
//! were missed. The counter counts SYNCs sent, so it has no gaps for consumers to trip on.

use std::collections::VecDeque;
use std::time::Duration;

use canopener_can::{CanFrame, CanId, Core, Instant, StandardId};
use canopener_wire::SYNC_ID;

/// The largest counter overflow value CiA 301 allows (1019h); 241 to 255 are reserved.
pub const MAX_COUNTER_OVERFLOW: u8 = 240;

/// What a SYNC producer sends and how often.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SyncConfig {
    /// The CAN-ID (1005h bits 10..0, or 28..0 with bit 29).
    pub cob_id: CanId,
    /// The communication cycle period (1006h).
    pub period: Duration,
    /// The synchronous counter overflow value (1019h), 2 to 240; `None` for SYNC without data
    /// (1019h = 0).
    pub counter_overflow: Option<u8>,
    /// The synchronous window length (1007h), recorded only; zero = none.
    pub window: Duration,
}

impl SyncConfig {
    /// SYNC on 080h every `period`, without counter and window.
    pub fn new(period: Duration) -> SyncConfig {
        SyncConfig {
            cob_id: CanId::Standard(StandardId::new(SYNC_ID).unwrap_or(StandardId::ZERO)),
            period,
            counter_overflow: None,
            window: Duration::ZERO,
        }
    }
}

/// Why a [`SyncConfig`] cannot produce SYNC.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SyncConfigError {
    /// A period of zero means "no SYNC" in 1006h.
    #[error("a SYNC period of 0 produces no SYNC; give a period such as 10 ms")]
    ZeroPeriod,
    /// A counter overflow value outside 2 to 240 (1019h: 1 and 241 to 255 are reserved).
    #[error("SYNC counter overflow {0} is reserved; use 2 to 240, or no counter")]
    CounterOverflow(u8),
}

/// What [`SyncProducer`] reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SyncEvent {
    /// A SYNC was queued, with its counter byte if it carries one.
    Sent {
        /// The counter byte.
        counter: Option<u8>,
    },
    /// [`SyncProducer::handle_timeout`] came a period or more late: `missed` SYNC deadlines passed
    /// without a SYNC. Reported before the SYNC that is sent instead.
    Overrun {
        /// How many deadlines were skipped.
        missed: u64,
    },
}

/// The SYNC producer (CiA 301 §7.2.5), sans IO.
///
/// Call [`SyncProducer::start`], then [`SyncProducer::handle_timeout`] at
/// [`SyncProducer::poll_timeout`]; drain [`SyncProducer::poll_transmit`] and
/// [`SyncProducer::poll_event`]. It consumes no frames.
#[derive(Debug, Clone)]
pub struct SyncProducer {
    config: SyncConfig,
    /// The next deadline, while running.
    next: Option<Instant>,
    /// The counter byte of the next SYNC.
    counter: u8,
    transmit: VecDeque<CanFrame>,
    events: VecDeque<SyncEvent>,
}

impl SyncProducer {
    /// A stopped producer for `config`.
    pub fn new(config: SyncConfig) -> Result<SyncProducer, SyncConfigError> {
        if config.period.is_zero() {
            return Err(SyncConfigError::ZeroPeriod);
        }
        if let Some(overflow) = config.counter_overflow
            && !(2..=MAX_COUNTER_OVERFLOW).contains(&overflow)
        {
            return Err(SyncConfigError::CounterOverflow(overflow));
        }
        Ok(SyncProducer {
            config,
            next: None,
            counter: 1,
            transmit: VecDeque::new(),
            events: VecDeque::new(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &SyncConfig {
        &self.config
    }

    /// Starts (or restarts) production: the first SYNC is due at `now` and carries counter 1.
    pub fn start(&mut self, now: Instant) {
        self.next = Some(now);
        self.counter = 1;
    }

    /// Stops production; SYNCs already queued stay queued.
    pub fn stop(&mut self) {
        self.next = None;
    }

    /// Whether SYNCs are being produced.
    pub fn is_running(&self) -> bool {
        self.next.is_some()
    }
}

impl Core for SyncProducer {
    type Event = SyncEvent;

    /// SyncProducer takes no frames.
    fn handle_frame(&mut self, _now: Instant, _frame: &CanFrame) {}

    /// Sends the SYNC that is due at `now`.
    fn handle_timeout(&mut self, now: Instant) {
        let Some(due) = self.next else { return };
        if due > now {
            return;
        }
        let period_nanos = u64::try_from(self.config.period.as_nanos()).unwrap_or(u64::MAX);
        let behind_nanos = u64::try_from((now - due).as_nanos()).unwrap_or(u64::MAX);
        // `period_nanos` is not 0: `new` refuses a zero period.
        let missed = behind_nanos / period_nanos.max(1);
        if missed > 0 {
            self.events.push_back(SyncEvent::Overrun { missed });
        }
        let deadline = due + Duration::from_nanos(missed.saturating_mul(period_nanos));
        self.next = Some(deadline + self.config.period);
        let counter = self.config.counter_overflow.map(|overflow| {
            let counter = self.counter;
            self.counter = if counter >= overflow { 1 } else { counter + 1 };
            counter
        });
        let data = counter.map_or(Vec::new(), |counter| vec![counter]);
        if let Ok(frame) = CanFrame::new(self.config.cob_id, &data) {
            self.transmit.push_back(frame);
        }
        self.events.push_back(SyncEvent::Sent { counter });
    }

    /// The next frame to send.
    fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.transmit.pop_front()
    }

    /// The next event.
    fn poll_event(&mut self) -> Option<Self::Event> {
        self.events.pop_front()
    }

    /// When the next SYNC is due, while running.
    fn poll_timeout(&self) -> Option<Instant> {
        self.next
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_can::Core;
    use canopener_testkit::trace::{Trace, ms};

    fn producer(period: Duration, overflow: Option<u8>) -> Trace<SyncProducer> {
        let config = SyncConfig {
            counter_overflow: overflow,
            ..SyncConfig::new(period)
        };
        Trace::new(SyncProducer::new(config).unwrap())
    }

    #[test]
    fn period_without_counter() {
        let mut trace = producer(Duration::from_millis(10), None);
        assert_eq!(trace.core.poll_timeout(), None, "stopped until started");
        trace.core.start(ms(5));
        trace.advance(ms(36));
        assert_eq!(
            trace.sent(),
            ["5.000 080#", "15.000 080#", "25.000 080#", "35.000 080#"]
        );
        assert_eq!(trace.events()[0], "5.000 Sent { counter: None }");
        trace.core.stop();
        assert!(!trace.core.is_running());
        trace.advance(ms(100));
        assert!(trace.sent().is_empty());
    }

    #[test]
    fn counter_wraps_from_overflow_to_one() {
        // 1019h = 5: 1, 2, 3, 4, 5, 1, 2, as the CCT expects.
        let mut trace = producer(Duration::from_millis(1), Some(5));
        trace.core.start(ms(0));
        trace.advance(ms(6));
        assert_eq!(
            trace.sent(),
            [
                "0.000 080#01",
                "1.000 080#02",
                "2.000 080#03",
                "3.000 080#04",
                "4.000 080#05",
                "5.000 080#01",
                "6.000 080#02"
            ]
        );
        // A restart begins at 1 again.
        trace.core.start(ms(10));
        trace.advance(ms(10));
        assert_eq!(trace.sent(), ["10.000 080#01"]);
        let mut trace = producer(Duration::from_micros(250), Some(240));
        trace.core.start(ms(0));
        trace.advance(Instant::from_micros(240 * 250));
        let sent = trace.sent();
        assert_eq!(sent[239], "59.750 080#F0");
        assert_eq!(sent[240], "60.000 080#01");
    }

    #[test]
    fn late_calls_do_not_drift() {
        let mut sync = SyncProducer::new(SyncConfig::new(Duration::from_millis(10))).unwrap();
        sync.start(ms(0));
        // Every wake-up 3 ms late: the deadlines stay on the 10 ms grid.
        for wake in [0, 13, 23, 33] {
            sync.handle_timeout(ms(wake));
            assert!(sync.poll_transmit().is_some(), "SYNC at {wake} ms");
        }
        assert_eq!(sync.poll_timeout(), Some(ms(40)));
        assert!(
            std::iter::from_fn(|| sync.poll_event()).all(|event| matches!(event, SyncEvent::Sent { .. }))
        );
        // Too early: nothing.
        sync.handle_timeout(ms(39));
        assert!(sync.poll_transmit().is_none());
    }

    #[test]
    fn overrun_skips_missed_syncs() {
        let mut trace = producer(Duration::from_millis(10), Some(3));
        trace.core.start(ms(0));
        trace.advance(ms(0));
        // The driver sleeps through the deadlines at 10, 20 and 30 ms and wakes at 35 ms.
        trace.core.handle_timeout(ms(35));
        trace.now = ms(35);
        assert_eq!(trace.sent(), ["0.000 080#01", "35.000 080#02"]);
        assert_eq!(
            trace.events(),
            [
                "0.000 Sent { counter: Some(1) }",
                "35.000 Overrun { missed: 2 }",
                "35.000 Sent { counter: Some(2) }"
            ]
        );
        // Back on the grid.
        assert_eq!(trace.core.poll_timeout(), Some(ms(40)));
        // Exactly one period late is one missed deadline.
        trace.core.handle_timeout(ms(50));
        assert_eq!(trace.core.poll_event(), Some(SyncEvent::Overrun { missed: 1 }));
        assert_eq!(trace.core.poll_timeout(), Some(ms(60)));
    }

    #[test]
    fn configured_can_id_and_window() {
        let config = SyncConfig {
            cob_id: CanId::standard(0x081).unwrap(),
            window: Duration::from_millis(2),
            ..SyncConfig::new(Duration::from_millis(10))
        };
        let mut trace = Trace::new(SyncProducer::new(config).unwrap());
        trace.core.start(ms(0));
        trace.advance(ms(10));
        assert_eq!(trace.sent(), ["0.000 081#", "10.000 081#"]);
        assert_eq!(trace.core.config().window, Duration::from_millis(2));
        let extended = SyncConfig {
            cob_id: CanId::extended(0x1000_0080).unwrap(),
            ..SyncConfig::new(Duration::from_millis(10))
        };
        let mut trace = Trace::new(SyncProducer::new(extended).unwrap());
        trace.core.start(ms(0));
        trace.advance(ms(0));
        assert_eq!(trace.sent(), ["0.000 10000080#"]);
    }

    #[test]
    fn bad_configs_are_refused() {
        assert_eq!(
            SyncProducer::new(SyncConfig::new(Duration::ZERO)).unwrap_err(),
            SyncConfigError::ZeroPeriod
        );
        for overflow in [0, 1, 241, 255] {
            let config = SyncConfig {
                counter_overflow: Some(overflow),
                ..SyncConfig::new(Duration::from_millis(1))
            };
            assert_eq!(
                SyncProducer::new(config).unwrap_err(),
                SyncConfigError::CounterOverflow(overflow)
            );
        }
    }
}

//! The TIME producer (CiA 301 §7.2.6): TIME_OF_DAY frames on request and periodically.
//!
//! Before changing this file read CiA 301 §7.2.6 (TIME), §7.1.6.5 (TIME_OF_DAY) and the description
//! of object 1012h (COB-ID TIME).
//!
//! A TIME frame (default CAN-ID 100h) carries 6 bytes: milliseconds after midnight and days since
//! 1 January 1984 ([`TimeOfDay`]). The core reads no clock, so the caller says what the wall time
//! is: [`TimeProducer::set_clock`] pairs an [`Instant`] with a wall time in milliseconds since
//! 1984-01-01 00:00 (see [`canopener_wire::since_1984_from_unix_millis`]), and the producer extends that pairing
//! along the `now` values it is given. [`TimeProducer::send`] sends a given wall time once (and
//! takes it as the new pairing); periodic production ([`TimeProducer::start_periodic`]) sends the
//! paired time every period, the first at once.

use std::collections::VecDeque;
use std::time::Duration;

use canopener_can::{CanFrame, CanId, Core, Instant, StandardId};
use canopener_wire::{TIME_ID, TimeOfDay};

/// The TIME_OF_DAY of a wall time in milliseconds since 1984-01-01, or why it cannot be sent.
fn time_of_day(since_1984_millis: u64) -> Result<TimeOfDay, TimeError> {
    TimeOfDay::from_millis_since_1984(since_1984_millis).ok_or(TimeError::OutOfRange { since_1984_millis })
}

/// Why no TIME was sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error)]
pub enum TimeError {
    /// The producer does not know the wall time: call [`TimeProducer::set_clock`] first.
    #[error("the TIME producer has no wall time; set the clock first")]
    NoClock,
    /// After 2163-06-06 the day count does not fit its 16 bits.
    #[error("{since_1984_millis} ms after 1984-01-01 is past 2163-06-06, the last day TIME_OF_DAY can carry")]
    OutOfRange {
        /// The wall time.
        since_1984_millis: u64,
    },
    /// A period of zero.
    #[error("a TIME period of 0 is no period; give one such as 1 s")]
    ZeroPeriod,
}

/// What [`TimeProducer`] reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TimeEvent {
    /// A TIME frame was queued.
    Sent {
        /// The time it carries.
        time: TimeOfDay,
    },
    /// A periodic TIME could not be sent.
    NotSent {
        /// Why.
        error: TimeError,
    },
}

/// The TIME producer (CiA 301 §7.2.6), sans IO.
#[derive(Debug, Clone)]
pub struct TimeProducer {
    cob_id: CanId,
    /// An instant and the wall time (ms since 1984-01-01) at that instant.
    clock: Option<(Instant, u64)>,
    period: Option<Duration>,
    next: Option<Instant>,
    transmit: VecDeque<CanFrame>,
    events: VecDeque<TimeEvent>,
}

impl Default for TimeProducer {
    fn default() -> Self {
        TimeProducer::new()
    }
}

impl TimeProducer {
    /// A producer on 100h without a clock, not producing.
    pub fn new() -> TimeProducer {
        let id = CanId::Standard(StandardId::new(TIME_ID).unwrap_or(StandardId::ZERO));
        TimeProducer::with_cob_id(id)
    }

    /// A producer on `cob_id` (1012h bits 10..0, or 28..0 with bit 29).
    pub fn with_cob_id(cob_id: CanId) -> TimeProducer {
        TimeProducer {
            cob_id,
            clock: None,
            period: None,
            next: None,
            transmit: VecDeque::new(),
            events: VecDeque::new(),
        }
    }

    /// Pairs `now` with the wall time `since_1984_millis`.
    pub fn set_clock(&mut self, now: Instant, since_1984_millis: u64) {
        self.clock = Some((now, since_1984_millis));
    }

    /// The wall time at `now` from the last pairing, in ms since 1984-01-01 (whole milliseconds;
    /// an instant before the pairing counts as the pairing).
    pub fn wall_time(&self, now: Instant) -> Option<u64> {
        let (at, wall) = self.clock?;
        let elapsed = u64::try_from((now - at).as_millis()).unwrap_or(u64::MAX);
        Some(wall.saturating_add(elapsed))
    }

    /// Sends `since_1984_millis` now, and pairs it with `now` for later TIMEs.
    pub fn send(&mut self, now: Instant, since_1984_millis: u64) -> Result<TimeOfDay, TimeError> {
        let time = time_of_day(since_1984_millis)?;
        self.set_clock(now, since_1984_millis);
        self.queue(time);
        Ok(time)
    }

    /// Sends the wall time at `now` from the clock pairing.
    pub fn send_now(&mut self, now: Instant) -> Result<TimeOfDay, TimeError> {
        let wall = self.wall_time(now).ok_or(TimeError::NoClock)?;
        let time = time_of_day(wall)?;
        self.queue(time);
        Ok(time)
    }

    /// Sends TIME every `period`, the first at `now`. Needs the clock.
    pub fn start_periodic(&mut self, now: Instant, period: Duration) -> Result<(), TimeError> {
        if period.is_zero() {
            return Err(TimeError::ZeroPeriod);
        }
        if self.clock.is_none() {
            return Err(TimeError::NoClock);
        }
        self.period = Some(period);
        self.next = Some(now);
        Ok(())
    }

    /// Stops periodic production.
    pub fn stop_periodic(&mut self) {
        self.period = None;
        self.next = None;
    }

    fn queue(&mut self, time: TimeOfDay) {
        if let Ok(frame) = CanFrame::new(self.cob_id, &time.encode()) {
            self.transmit.push_back(frame);
        }
        self.events.push_back(TimeEvent::Sent { time });
    }
}

impl Core for TimeProducer {
    type Event = TimeEvent;

    /// TimeProducer takes no frames.
    fn handle_frame(&mut self, _now: Instant, _frame: &CanFrame) {}

    /// Sends the periodic TIME that is due at `now`.
    fn handle_timeout(&mut self, now: Instant) {
        let (Some(due), Some(period)) = (self.next, self.period) else {
            return;
        };
        if due > now {
            return;
        }
        let next = due + period;
        // On time the period stays exact; a driver that fell behind gets one TIME, not a burst.
        self.next = Some(if next > now { next } else { now + period });
        if let Err(error) = self.send_now(now) {
            self.events.push_back(TimeEvent::NotSent { error });
        }
    }

    /// The next frame to send.
    fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.transmit.pop_front()
    }

    /// The next event.
    fn poll_event(&mut self) -> Option<Self::Event> {
        self.events.pop_front()
    }

    /// When the next periodic TIME is due.
    fn poll_timeout(&self) -> Option<Instant> {
        self.next
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_can::Core;
    use canopener_testkit::trace::{Trace, ms};

    /// 2024-01-01 12:00:00.000 UTC, the worked example of the reference.
    const NOON_2024: u64 = 14_610 * 86_400_000 + 43_200_000;

    #[test]
    fn one_time_on_request() {
        let mut trace = Trace::new(TimeProducer::new());
        trace.advance(ms(3));
        let time = trace.core.send(ms(3), NOON_2024).unwrap();
        assert_eq!(time.to_string(), "2024-01-01 12:00:00.000");
        assert_eq!(trace.sent(), ["3.000 100#002E93021239"]);
        assert_eq!(
            trace.events(),
            ["3.000 Sent { time: TimeOfDay { millis: 43200000, days: 14610 } }"]
        );
        // The pairing carries on: 1.5 s later.
        trace.advance(ms(1503));
        let time = trace.core.send_now(ms(1503)).unwrap();
        assert_eq!(time.to_string(), "2024-01-01 12:00:01.500");
        assert_eq!(trace.core.poll_timeout(), None);
    }

    #[test]
    fn periodic_time_from_the_clock() {
        let mut trace = Trace::new(TimeProducer::new());
        assert_eq!(
            trace.core.start_periodic(ms(0), Duration::from_secs(1)),
            Err(TimeError::NoClock)
        );
        // Just before midnight: the day rolls over between two TIMEs.
        trace.core.set_clock(ms(0), 14_610 * 86_400_000 + 86_399_500);
        trace
            .core
            .start_periodic(ms(0), Duration::from_millis(400))
            .unwrap();
        trace.advance(ms(800));
        assert_eq!(
            trace.sent(),
            [
                "0.000 100#0C5A26051239",
                "400.000 100#9C5B26051239",
                "800.000 100#2C0100001339"
            ]
        );
        assert_eq!(
            trace.events()[2],
            "800.000 Sent { time: TimeOfDay { millis: 300, days: 14611 } }"
        );
        trace.core.stop_periodic();
        trace.advance(ms(5000));
        assert!(trace.sent().is_empty());
    }

    #[test]
    fn late_driver_gets_one_time() {
        let mut time = TimeProducer::new();
        time.set_clock(ms(0), 0);
        time.start_periodic(ms(0), Duration::from_millis(100)).unwrap();
        time.handle_timeout(ms(0));
        time.handle_timeout(ms(350));
        assert_eq!(
            time.poll_transmit().map(|f| f.to_string()),
            Some("100#000000000000".into())
        );
        assert_eq!(
            time.poll_transmit().map(|f| f.to_string()),
            Some("100#5E0100000000".into())
        );
        assert_eq!(time.poll_transmit(), None);
        assert_eq!(time.poll_timeout(), Some(ms(450)));
    }

    #[test]
    fn wall_time_helpers_and_limits() {
        // 2024-01-01T12:00:00Z is 1 704 110 400 s after the Unix epoch.
        assert_eq!(
            canopener_wire::since_1984_from_unix_millis(1_704_110_400_000),
            Some(NOON_2024)
        );
        assert_eq!(canopener_wire::since_1984_from_unix_millis(0), None);
        assert_eq!(
            time_of_day(u64::from(u16::MAX) * 86_400_000 + 86_399_999).map(|t| t.days),
            Ok(u16::MAX)
        );
        let too_late = (u64::from(u16::MAX) + 1) * 86_400_000;
        assert_eq!(
            time_of_day(too_late),
            Err(TimeError::OutOfRange {
                since_1984_millis: too_late
            })
        );
        let mut producer = TimeProducer::with_cob_id(CanId::standard(0x101).unwrap());
        assert_eq!(producer.send_now(ms(0)), Err(TimeError::NoClock));
        assert_eq!(
            producer.send(ms(0), too_late).map(|_| ()),
            Err(TimeError::OutOfRange {
                since_1984_millis: too_late
            })
        );
        assert_eq!(producer.poll_transmit(), None, "nothing sent on error");
        producer.set_clock(ms(0), too_late - 1000);
        producer.start_periodic(ms(0), Duration::from_secs(1)).unwrap();
        producer.handle_timeout(ms(0));
        producer.handle_timeout(ms(1000));
        assert!(
            producer
                .poll_transmit()
                .is_some_and(|frame| frame.id() == CanId::standard(0x101).unwrap())
        );
        assert_eq!(producer.poll_transmit(), None);
        assert!(matches!(producer.poll_event(), Some(TimeEvent::Sent { .. })));
        assert_eq!(
            producer.poll_event(),
            Some(TimeEvent::NotSent {
                error: TimeError::OutOfRange {
                    since_1984_millis: too_late
                }
            })
        );
        assert_eq!(
            producer.start_periodic(ms(0), Duration::ZERO),
            Err(TimeError::ZeroPeriod)
        );
        assert_eq!(producer.wall_time(ms(500)), Some(too_late - 500));
    }
}

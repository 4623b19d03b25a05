//! A virtual-time test harness for one sans-IO protocol core, shared by the device and master crates'
//! unit tests.
//!
//! A [`Trace`] drives one core: it runs every timer at exactly its deadline, feeds frames written in
//! compact candump form, and records what the core sends as `"<ms>.<µs> <frame>"` lines and what it
//! reports as `"<ms>.<µs> <event:?>"` lines, so a test reads as a timestamped frame trace.

use std::fmt::{self, Debug};
use std::time::Duration;

use canopener_can::candump::parse_compact_frame;
use canopener_can::{CanFrame, Core, Instant};

/// A frame from compact candump text, e.g. `"000#0105"` or `"705#R"`; panics on a typo in a test.
pub fn frame(text: &str) -> CanFrame {
    parse_compact_frame(text).expect("test frame")
}

/// `ms` milliseconds after the virtual epoch.
pub fn ms(ms: u64) -> Instant {
    Instant::from_millis(ms)
}

/// Drives a core on virtual time and records what it sends and reports.
pub struct Trace<C: Core> {
    /// The core under test.
    pub core: C,
    /// The virtual time.
    pub now: Instant,
    out: Vec<String>,
    events: Vec<(Instant, C::Event)>,
}

impl<C: Core> Debug for Trace<C> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Trace")
            .field("now", &self.now)
            .field("out", &self.out)
            .field("events", &self.events.len())
            .finish_non_exhaustive()
    }
}

/// `now` as `<ms>.<µs>` (`12.345`), the time stamp of trace lines.
pub fn stamp(now: Instant) -> String {
    let micros = now.as_micros();
    format!("{}.{:03}", micros / 1000, micros % 1000)
}

impl<C: Core> Trace<C>
where
    C::Event: Debug,
{
    /// A trace at virtual time zero.
    pub fn new(core: C) -> Self {
        Trace {
            core,
            now: Instant::ZERO,
            out: Vec::new(),
            events: Vec::new(),
        }
    }

    /// Records what the core has sent and reported, at the current time (after a test fed the core
    /// directly).
    pub fn drain(&mut self) {
        while let Some(frame) = self.core.poll_transmit() {
            self.out.push(format!("{} {frame}", stamp(self.now)));
        }
        while let Some(event) = self.core.poll_event() {
            self.events.push((self.now, event));
        }
    }

    /// Runs every timer due up to and including `until`, then sets the clock to `until`.
    pub fn advance(&mut self, until: Instant) {
        self.drain();
        while let Some(due) = self.core.poll_timeout() {
            if due > until {
                break;
            }
            assert!(due >= self.now, "timer in the past: {due:?} < {:?}", self.now);
            self.now = due;
            self.core.handle_timeout(due);
            self.drain();
        }
        self.now = until;
    }

    /// Runs the next timer `late` after it was due, as a driver woken by a coarse OS timer would,
    /// and returns when that was.
    pub fn wake_late(&mut self, late: Duration) -> Instant {
        self.drain();
        let due = self.core.poll_timeout().expect("a timer is armed");
        self.now = due + late;
        self.core.handle_timeout(self.now);
        self.drain();
        self.now
    }

    /// Advances by `delta` from the current time.
    pub fn wait(&mut self, delta: Duration) {
        let until = self.now + delta;
        self.advance(until);
    }

    /// Advances to `at`, then feeds `text` (compact candump, e.g. `705#05` or `705#R1`) as a
    /// received frame.
    pub fn rx(&mut self, at: Instant, text: &str) {
        self.advance(at);
        self.core.handle_frame(at, &frame(text));
        self.drain();
    }

    /// Takes the frames sent so far.
    pub fn sent(&mut self) -> Vec<String> {
        self.drain();
        std::mem::take(&mut self.out)
    }

    /// Takes the events reported so far, as `"<ms>.<µs> <event:?>"` lines.
    pub fn events(&mut self) -> Vec<String> {
        self.take_events_at()
            .into_iter()
            .map(|(at, event)| format!("{} {event:?}", stamp(at)))
            .collect()
    }

    /// Takes the events reported so far.
    pub fn take_events(&mut self) -> Vec<C::Event> {
        self.take_events_at()
            .into_iter()
            .map(|(_, event)| event)
            .collect()
    }

    /// Takes the events reported so far, with when they were reported.
    pub fn take_events_at(&mut self) -> Vec<(Instant, C::Event)> {
        self.drain();
        std::mem::take(&mut self.events)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Echoes every frame back after 10 ms.
    #[derive(Debug, Default)]
    struct Echo {
        pending: Option<(Instant, CanFrame)>,
        out: Option<CanFrame>,
    }

    impl Core for Echo {
        type Event = &'static str;
        fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
            self.pending = Some((now + Duration::from_millis(10), *frame));
        }
        fn handle_timeout(&mut self, now: Instant) {
            if let Some((due, frame)) = self.pending.take_if(|(due, _)| *due <= now) {
                assert!(due <= now);
                self.out = Some(frame);
            }
        }
        fn poll_transmit(&mut self) -> Option<CanFrame> {
            self.out.take()
        }
        fn poll_event(&mut self) -> Option<&'static str> {
            None
        }
        fn poll_timeout(&self) -> Option<Instant> {
            self.pending.map(|(due, _)| due)
        }
    }

    #[test]
    fn timers_run_at_their_deadlines_and_frames_are_stamped() {
        let mut trace = Trace::new(Echo::default());
        trace.rx(ms(5), "123#01");
        trace.advance(ms(100));
        assert_eq!(trace.sent(), ["15.000 123#01"]);
        trace.rx(ms(200), "124#02");
        assert_eq!(trace.wake_late(Duration::from_millis(4)), ms(214));
        assert_eq!(trace.sent(), ["214.000 124#02"]);
        assert!(trace.events().is_empty());
    }
}

//! The sans-IO surface every protocol core of canopener offers.
//!
//! A core is a state machine that never touches a socket and never reads a clock: a driver hands it
//! received frames and the current time, and takes from it the frames to send, the events to report
//! and the time it next wants to be woken. The same core therefore runs on virtual time in tests, on a
//! simulated bus and on real hardware. The drivers live in `canopener-link`; the virtual-time test
//! harness in `canopener-testkit`.

use crate::{CanFrame, Instant};

/// A sans-IO protocol core: frames and time in, frames, events and a deadline out.
///
/// A driver calls [`handle_frame`](Core::handle_frame) for every frame received on the bus (a core
/// ignores what is not addressed to it) and [`handle_timeout`](Core::handle_timeout) once
/// [`poll_timeout`](Core::poll_timeout)'s deadline has passed, then drains
/// [`poll_transmit`](Core::poll_transmit) and [`poll_event`](Core::poll_event) until both return
/// `None`. `now` never goes backwards between calls.
pub trait Core {
    /// What the core reports to whoever drives it.
    type Event;

    /// A frame received on the bus at `now`.
    fn handle_frame(&mut self, now: Instant, frame: &CanFrame);

    /// Runs the timers due at or before `now`.
    fn handle_timeout(&mut self, now: Instant);

    /// The next frame to send, in order.
    fn poll_transmit(&mut self) -> Option<CanFrame>;

    /// The next event, in order.
    fn poll_event(&mut self) -> Option<Self::Event>;

    /// When [`handle_timeout`](Core::handle_timeout) is next due; `None` while no timer runs.
    fn poll_timeout(&self) -> Option<Instant>;
}

impl<C: Core + ?Sized> Core for Box<C> {
    type Event = C::Event;

    fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
        (**self).handle_frame(now, frame);
    }

    fn handle_timeout(&mut self, now: Instant) {
        (**self).handle_timeout(now);
    }

    fn poll_transmit(&mut self) -> Option<CanFrame> {
        (**self).poll_transmit()
    }

    fn poll_event(&mut self) -> Option<Self::Event> {
        (**self).poll_event()
    }

    fn poll_timeout(&self) -> Option<Instant> {
        (**self).poll_timeout()
    }
}

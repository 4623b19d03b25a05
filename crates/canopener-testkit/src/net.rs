//! The one multi-core test harness: cores on a simulated bus on virtual time, every frame recorded as a
//! timestamped trace line.
//!
//! It is a thin layer over [`VirtualBus`] (the same loop the runtime's virtual bus uses): a tap to inject
//! frames written in candump compact form, the recording rendered as `"<ms>.<µs> <frame>"` lines, and
//! [`Net::drive`] to run a core under test (a master core, say) against the nodes through the tap.
//! Several kinds of core on one bus are one enum made with [`cores!`](crate::cores).

use std::fmt::Debug;
use std::time::Duration;

use canopener_bus_engine::virtual_bus::{BusFrame, NodeEvent, StationId, Timing, VirtualBus};
use canopener_can::{CanFrame, Core, Instant};

use crate::trace::{frame, stamp};

/// Cores on one simulated bus, with a tap for the test (see the [module docs](self)).
pub struct Net<N: Core> {
    bus: VirtualBus<N>,
    tap: StationId,
}

impl<N: Core + Debug> Debug for Net<N> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Net").field("bus", &self.bus).finish()
    }
}

impl<N: Core> Net<N> {
    /// An empty bus with ideal timing (frames arrive at the instant they are sent), recording.
    pub fn ideal() -> Net<N> {
        Net::new(Timing::Ideal)
    }

    /// An empty bus with `timing`, recording every frame, at virtual time zero.
    pub fn new(timing: Timing) -> Net<N> {
        let mut bus = VirtualBus::new(timing);
        let tap = bus.tap();
        bus.record();
        Net { bus, tap }
    }

    /// Puts a core on the bus; frames it already has waiting go out first.
    pub fn attach(&mut self, node: N) -> StationId {
        self.bus.attach(node)
    }

    /// The test's own station (frames it injects come from here).
    pub fn tap(&self) -> StationId {
        self.tap
    }

    /// The virtual time.
    pub fn now(&self) -> Instant {
        self.bus.now()
    }

    /// Runs everything due up to and including `until`.
    pub fn advance(&mut self, until: Instant) {
        self.bus
            .run_until(until, None)
            .expect("the simulated bus takes the frames");
    }

    /// Runs for `delta` from now.
    pub fn wait(&mut self, delta: Duration) {
        let until = self.now() + delta;
        self.advance(until);
    }

    /// Advances to `at`, then sends `text` (compact candump, e.g. `000#0105` or `705#R1`) from the tap.
    pub fn inject(&mut self, at: Instant, text: &str) {
        self.advance(at);
        self.send(frame(text));
    }

    /// Sends `frame` from the tap now and lets everything due at this instant happen.
    pub fn send(&mut self, frame: CanFrame) {
        self.bus
            .send(self.tap, frame)
            .expect("the simulated bus takes the frame");
        self.bus.settle().expect("the simulated bus takes the frames");
    }

    /// The frames on the bus since the last call, as `"<ms>.<µs> <frame>"` (` (lost)` appended to
    /// frames the bus lost).
    pub fn frames(&mut self) -> Vec<String> {
        self.bus_frames().iter().map(line).collect()
    }

    /// The frames on the bus since the last call.
    pub fn bus_frames(&mut self) -> Vec<BusFrame> {
        self.bus.take_recording()
    }

    /// The nodes' events since the last call.
    pub fn events(&mut self) -> Vec<NodeEvent<N::Event>> {
        std::iter::from_fn(|| self.bus.poll_event()).collect()
    }

    /// What the tap received since the last call.
    pub fn received(&mut self) -> Vec<(Instant, CanFrame)> {
        std::iter::from_fn(|| self.bus.take_received(self.tap)).collect()
    }

    /// The node at `id`.
    ///
    /// # Panics
    /// When `id` is the tap or not on this bus: a mistake in the test.
    pub fn node(&self, id: StationId) -> &N {
        self.bus.node(id).expect("a node of this bus")
    }

    /// The node at `id`, mutably (see [`Net::node`]).
    ///
    /// # Panics
    /// When `id` is the tap or not on this bus.
    pub fn node_mut(&mut self, id: StationId) -> &mut N {
        self.bus.node_mut(id).expect("a node of this bus")
    }

    /// The virtual bus, for wiring faults ([`VirtualBus::disconnect`], [`VirtualBus::lose_when`]) and statistics.
    pub fn virtual_bus_mut(&mut self) -> &mut VirtualBus<N> {
        &mut self.bus
    }

    /// Runs `core` (outside the bus, on the tap) against the nodes until `done` says so or `limit`
    /// comes; returns the core's events. `done` sees the core and its events so far, and is asked only
    /// while no frame is on its way, so a run ends on a settled bus. The core's frames go out through
    /// the tap (and are recorded), frames the tap receives go to the core, its timers run when due.
    pub fn drive<C: Core>(
        &mut self,
        core: &mut C,
        limit: Instant,
        mut done: impl FnMut(&C, &[C::Event]) -> bool,
    ) -> Vec<C::Event> {
        let mut events = Vec::new();
        loop {
            while let Some(frame) = core.poll_transmit() {
                self.send(frame);
            }
            let received = self.received();
            if !received.is_empty() {
                for (at, frame) in received {
                    core.handle_frame(at, &frame);
                }
                // Its answers go out at the same instant, before time moves on.
                continue;
            }
            events.extend(std::iter::from_fn(|| core.poll_event()));
            let settled = !self.bus.frames_in_flight();
            if (settled && done(core, &events)) || self.now() >= limit {
                while let Some(frame) = core.poll_transmit() {
                    self.send(frame);
                }
                return events;
            }
            let now = self.now();
            if core.poll_timeout().is_some_and(|due| due <= now) {
                core.handle_timeout(now);
                continue;
            }
            let until = core.poll_timeout().map_or(limit, |due| due.min(limit));
            self.bus
                .run_until(until, Some(self.tap))
                .expect("the simulated bus takes the frames");
        }
    }
}

/// One recorded frame as a trace line.
fn line(frame: &BusFrame) -> String {
    let lost = if frame.lost { " (lost)" } else { "" };
    format!("{} {}{lost}", stamp(frame.at), frame.frame)
}

/// One core type for several kinds of core on a [`Net`]: an enum of the cores and an enum of their
/// events, with [`Core`] implemented by dispatch.
///
/// ```
/// # use canopener_can::{CanFrame, Core, Instant};
/// # #[derive(Debug)] struct Silent;
/// # impl Core for Silent {
/// #     type Event = u8;
/// #     fn handle_frame(&mut self, _: Instant, _: &CanFrame) {}
/// #     fn handle_timeout(&mut self, _: Instant) {}
/// #     fn poll_transmit(&mut self) -> Option<CanFrame> { None }
/// #     fn poll_event(&mut self) -> Option<u8> { None }
/// #     fn poll_timeout(&self) -> Option<Instant> { None }
/// # }
/// canopener_testkit::cores! {
///     /// The parties of this test.
///     pub enum Party, PartyEvent {
///         Quiet(Silent) => u8,
///         Other(Silent) => u8,
///     }
/// }
/// let mut net = canopener_testkit::net::Net::<Party>::ideal();
/// let quiet = net.attach(Party::Quiet(Silent));
/// assert!(matches!(net.node(quiet), Party::Quiet(_)));
/// ```
#[macro_export]
macro_rules! cores {
    ($(#[$meta:meta])* $vis:vis enum $name:ident, $event:ident { $($variant:ident($core:ty) => $ev:ty),+ $(,)? }) => {
        $(#[$meta])*
        #[derive(Debug)]
        $vis enum $name {
            $(
                #[allow(missing_docs)]
                $variant($core),
            )+
        }

        /// The events of the cores of one enum.
        #[derive(Debug)]
        $vis enum $event {
            $(
                #[allow(missing_docs)]
                $variant($ev),
            )+
        }

        impl $crate::__private::Core for $name {
            type Event = $event;

            fn handle_frame(&mut self, now: $crate::__private::Instant, frame: &$crate::__private::CanFrame) {
                match self { $($name::$variant(core) => core.handle_frame(now, frame),)+ }
            }

            fn handle_timeout(&mut self, now: $crate::__private::Instant) {
                match self { $($name::$variant(core) => core.handle_timeout(now),)+ }
            }

            fn poll_transmit(&mut self) -> Option<$crate::__private::CanFrame> {
                match self { $($name::$variant(core) => core.poll_transmit(),)+ }
            }

            fn poll_event(&mut self) -> Option<$event> {
                match self { $($name::$variant(core) => core.poll_event().map($event::$variant),)+ }
            }

            fn poll_timeout(&self) -> Option<$crate::__private::Instant> {
                match self { $($name::$variant(core) => core.poll_timeout(),)+ }
            }
        }
    };
}

//! A simulated bus on virtual time as a [`Link`]: the same drive loops and sessions that talk to real
//! devices run here against in-process cores, deterministically and as fast as the CPU allows.
//!
//! The link is one tap of a [`VirtualBus`]; the cores on the bus (simulated devices, other masters) run
//! exactly when their timers and the frames on the bus say, and virtual time only moves while the link
//! waits for a frame. Two runs with the same inputs produce the same frames at the same instants.

use canopener_bus_engine::virtual_bus::{StationId, Timing, VirtualBus};
use canopener_can::{CanFrame, Core, Instant};

use crate::cancel::Cancel;
use crate::link::{Link, LinkError, TimestampSource, Timestamps};

/// One endpoint on a simulated bus of cores `N`, on virtual time.
pub struct VirtualLink<N: Core> {
    bus: VirtualBus<N>,
    tap: StationId,
    cancel: Cancel,
}

impl<N: Core + std::fmt::Debug> std::fmt::Debug for VirtualLink<N> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("VirtualLink")
            .field("bus", &self.bus)
            .field("tap", &self.tap)
            .finish_non_exhaustive()
    }
}

impl<N: Core> VirtualLink<N> {
    /// A link on an empty simulated bus with `timing`, at virtual time zero.
    pub fn new(timing: Timing) -> VirtualLink<N> {
        let mut bus = VirtualBus::new(timing);
        let tap = bus.tap();
        VirtualLink {
            bus,
            tap,
            cancel: Cancel::new(),
        }
    }

    /// Makes the link honour `cancel` (a fresh link is never cancelled).
    pub fn with_cancel(mut self, cancel: Cancel) -> VirtualLink<N> {
        self.cancel = cancel;
        self
    }

    /// Puts a core on the bus.
    pub fn attach(&mut self, node: N) -> StationId {
        self.bus.attach(node)
    }

    /// The simulated bus, to look at its nodes, events and recording.
    pub fn virtual_bus(&self) -> &VirtualBus<N> {
        &self.bus
    }

    /// The simulated bus, to change its nodes.
    pub fn virtual_bus_mut(&mut self) -> &mut VirtualBus<N> {
        &mut self.bus
    }

    /// This link's own station on the bus (frames it sends come from here).
    pub fn station(&self) -> StationId {
        self.tap
    }

    /// Lets virtual time run to `until` with nothing to receive: frames that arrive meanwhile are kept
    /// for the next [`Link::recv_until`].
    pub fn run_until(&mut self, until: Instant) -> Result<(), LinkError> {
        self.bus.run_until(until, None)?;
        Ok(())
    }
}

impl<N: Core> Link for VirtualLink<N> {
    fn now(&self) -> Instant {
        self.bus.now()
    }

    /// Puts the frame on the bus and lets everything due at this instant happen, so that the cores have
    /// it (on an ideal bus) before the caller looks at them.
    fn send(&mut self, frame: &CanFrame) -> Result<(), LinkError> {
        self.bus.send(self.tap, *frame)?;
        self.bus.settle()?;
        Ok(())
    }

    fn recv_until(&mut self, deadline: Instant) -> Result<Option<(Instant, CanFrame)>, LinkError> {
        loop {
            if let Some(received) = self.bus.take_received(self.tap) {
                return Ok(Some(received));
            }
            if self.is_cancelled() || self.bus.now() >= deadline {
                // Frames handed over just now still go out, even when no time is left to wait.
                self.bus.settle()?;
                return Ok(self.bus.take_received(self.tap));
            }
            self.bus.run_until(deadline, Some(self.tap))?;
        }
    }

    fn is_cancelled(&self) -> bool {
        self.cancel.is_cancelled()
    }

    fn idle_until(&mut self, until: Instant) -> Result<(), LinkError> {
        if !self.is_cancelled() {
            self.bus.run_until(until, None)?;
        }
        while self.bus.take_received(self.tap).is_some() {}
        Ok(())
    }

    /// Virtual time is kept in nanoseconds.
    fn timestamps(&self) -> Timestamps {
        Timestamps {
            source: TimestampSource::Virtual,
            resolution: std::time::Duration::from_nanos(1),
        }
    }

    fn describe(&self) -> String {
        match self.bus.timing() {
            Timing::Ideal => "simulated bus (ideal timing)".to_owned(),
            Timing::Delayed(delay) => format!("simulated bus ({delay:?} per frame)"),
            Timing::BitAccurate(bitrate) => format!("simulated bus ({bitrate})"),
        }
    }
}

//! The IO around the master-side cores of `canopener-master`: one bus endpoint, the wall clock, and a loop
//! that feeds received frames and due timers to a core, sends what it produces, and hands its events to the
//! command until the command has what it wanted.
//!
//! The cores never block; the wait is here, bounded by the core's next deadline, a deadline the command
//! gives, and [`MAX_WAIT`] so that Ctrl-C is noticed. A core that stops asking for time while the command
//! still waits cannot hang a command: every wait has the command's deadline.

use std::time::Duration;

use canopener_can::{CanFrame, Core, Instant};
use canopener_transport::{BusSpec, CanBus, TransportError, WallClock};

use crate::bus_open::open_bus;
use crate::error::{CliError, CliResult};
use crate::stop::StopFlag;

/// Longer than `canopener bus serve`'s default raw-mode grace (50 ms).
const HUB_RAW_GRACE: Duration = Duration::from_millis(60);
/// The longest one receive waits, so that Ctrl-C is noticed quickly.
const MAX_WAIT: Duration = Duration::from_millis(50);

/// What a command's event handler tells the driver.
#[derive(Debug)]
pub(crate) enum Flow<T> {
    /// Keep going.
    Continue,
    /// Stop driving and return this.
    Done(T),
}

/// Why [`Link::drive`] ended without a result.
#[derive(Debug)]
pub(crate) enum Ended {
    /// The deadline passed.
    Deadline,
    /// Ctrl-C or SIGTERM.
    Interrupted,
}

/// One bus endpoint opened for a master command, with the wall clock.
#[derive(Debug)]
pub(crate) struct Link {
    bus: Box<dyn CanBus>,
    stop: StopFlag,
}

impl Link {
    /// Opens `--bus SPEC` (or `CANOPENER_BUS`) for `command`.
    pub(crate) fn open(spec: Option<&str>, command: &str) -> CliResult<Link> {
        let bus = open_bus(spec, command)?;
        let mut link = Link {
            bus,
            stop: StopFlag::install()?,
        };
        if matches!(link.bus.spec(), BusSpec::Socketcand { .. }) {
            // A socketcand hub (ours by default) holds a new client's traffic back for its raw-mode
            // grace (50 ms, for python-can's handshake): answers in that window would arrive late
            // and a short timeout would take them for silence. Nothing sent before our first
            // request matters to a master command, so wait the grace out first.
            let until = link.now() + HUB_RAW_GRACE;
            while link.recv_until(until)?.is_some() {}
        }
        Ok(link)
    }

    /// The time the cores are given.
    pub(crate) fn now(&self) -> Instant {
        WallClock::now()
    }

    /// Whether the user asked to stop.
    pub(crate) fn interrupted(&self) -> bool {
        self.stop.is_set()
    }

    /// The bus spec, for messages.
    pub(crate) fn spec(&self) -> String {
        self.bus.spec().to_string()
    }

    /// Sends one frame now.
    pub(crate) fn send(&mut self, frame: &CanFrame) -> CliResult {
        Ok(self.bus.send(frame)?)
    }

    /// The next frame received before `deadline`, or `None` at the deadline or on Ctrl-C.
    pub(crate) fn recv_until(&mut self, deadline: Instant) -> CliResult<Option<(Instant, CanFrame)>> {
        loop {
            let now = self.now();
            if now >= deadline || self.interrupted() {
                return Ok(None);
            }
            let wait = deadline.saturating_duration_since(now).min(MAX_WAIT);
            if let Some((at, frame)) = self.recv_one(wait)? {
                return Ok(Some((at, frame)));
            }
        }
    }

    /// Runs `core` until `on_event` returns [`Flow::Done`], `deadline` passes or the user interrupts.
    /// Every frame the core produces is sent; every frame received goes to the core.
    pub(crate) fn drive<C: Core, T>(
        &mut self,
        core: &mut C,
        deadline: Option<Instant>,
        mut on_event: impl FnMut(&mut C, C::Event) -> CliResult<Flow<T>>,
    ) -> CliResult<Result<T, Ended>> {
        loop {
            self.flush(core)?;
            while let Some(event) = core.poll_event() {
                if let Flow::Done(result) = on_event(core, event)? {
                    self.flush(core)?;
                    return Ok(Ok(result));
                }
                self.flush(core)?;
            }
            if self.interrupted() {
                return Ok(Err(Ended::Interrupted));
            }
            let now = self.now();
            if deadline.is_some_and(|deadline| now >= deadline) {
                return Ok(Err(Ended::Deadline));
            }
            if let Some(due) = core.poll_timeout()
                && due <= now
            {
                core.handle_timeout(now);
                continue;
            }
            let until = [core.poll_timeout(), deadline].into_iter().flatten().min();
            let wait = until
                .map_or(MAX_WAIT, |until| until.saturating_duration_since(now))
                .min(MAX_WAIT);
            if let Some((at, frame)) = self.recv_one(wait)? {
                core.handle_frame(at, &frame);
            }
        }
    }

    fn flush<C: Core>(&mut self, core: &mut C) -> CliResult {
        while let Some(frame) = core.poll_transmit() {
            self.bus.send(&frame)?;
        }
        Ok(())
    }

    /// One receive of at most `wait`; overruns are reported on stderr and otherwise ignored (a lost
    /// frame shows up as a timeout or protocol error of the core that needed it).
    fn recv_one(&mut self, wait: Duration) -> CliResult<Option<(Instant, CanFrame)>> {
        match self.bus.recv(wait) {
            Ok(Some(received)) => {
                // The core runs on our clock: a hub's receive timestamp may come from another clock.
                Ok(Some((self.now(), received.frame)))
            }
            Ok(None) => Ok(None),
            Err(TransportError::Overrun { lost, .. }) => {
                eprintln!("warning: {lost} frames lost because canopener did not keep up with the bus");
                Ok(None)
            }
            Err(err) => Err(CliError::from(err)),
        }
    }
}

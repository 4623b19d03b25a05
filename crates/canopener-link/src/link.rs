//! The drive loop: frames between a bus and a sans-IO core, on a clock.
//!
//! A [`Link`] is one endpoint on a bus together with the clock the cores run on: [`BusLink`] is a real
//! transport (SocketCAN, socketcand, a `virtual:` bus of another thread) on the wall clock;
//! [`VirtualLink`](crate::virtual_link::VirtualLink) is a simulated bus on virtual time, deterministic.
//! [`drive`] moves frames between any link and any [`Core`] until the caller has what it wanted, the
//! deadline passes or someone cancels: the same code runs a bench session and a test on virtual time.
//!
//! The cores never block; the wait is here, bounded by the core's next deadline, the caller's deadline
//! and [`MAX_WAIT`] so that a cancellation is noticed. A core that stops asking for time while the
//! caller still waits cannot hang it: every wait has the caller's deadline.

use std::time::Duration;

use canopener_bus_engine::SubmitError;
use canopener_bus_engine::virtual_bus::SendError;
use canopener_can::{CanFrame, Core, Instant};
use canopener_transport::{BusSpec, CanBus, TransportError, WallClock};

use crate::cancel::Cancel;

/// The longest one receive waits, so that a cancellation is noticed quickly.
pub const MAX_WAIT: Duration = Duration::from_millis(50);

/// Longer than `canopener bus serve`'s default raw-mode grace (50 ms): a socketcand hub holds a new
/// client's traffic back that long.
const HUB_RAW_GRACE: Duration = Duration::from_millis(60);

/// Why a link stopped working.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// The transport failed (connection lost, interface down, ...).
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// The simulated bus refused a frame (a station's transmit queue is full).
    #[error("the simulated bus refused a frame: {0}")]
    Simulated(#[from] SubmitError),
    /// The simulated bus has no such tap.
    #[error(transparent)]
    Tap(#[from] SendError),
}

/// Where the receive times of a link's frames come from, for reports that must say how far their
/// timings can be trusted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TimestampSource {
    /// The kernel's receive time (SocketCAN).
    Kernel,
    /// The time a socketcand server stamped the frame with.
    Hub,
    /// The simulated bus's virtual time.
    Virtual,
    /// This process's clock when the frame was taken from the transport.
    Host,
}

impl TimestampSource {
    /// `kernel`, `hub`, `virtual` or `host`.
    pub fn as_str(self) -> &'static str {
        match self {
            TimestampSource::Kernel => "kernel",
            TimestampSource::Hub => "hub",
            TimestampSource::Virtual => "virtual",
            TimestampSource::Host => "host",
        }
    }
}

/// How a link's receive times are taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Timestamps {
    /// Who stamps the frames.
    pub source: TimestampSource,
    /// The smallest step the stamps can show.
    pub resolution: Duration,
}

/// A frame as a link received it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stamped {
    /// When the link took it, on [`Link::now`]'s clock (what the cores see).
    pub at: Instant,
    /// When the bus side stamped it (see [`Link::timestamps`]); equal to `at` where nothing else
    /// stamps frames.
    pub bus_time: Instant,
    /// The frame.
    pub frame: CanFrame,
}

/// One endpoint on a bus and the clock the cores run on.
pub trait Link {
    /// The time given to the cores.
    fn now(&self) -> Instant;

    /// Sends one frame now.
    fn send(&mut self, frame: &CanFrame) -> Result<(), LinkError>;

    /// The next frame received before `deadline`, with its receive time on [`Link::now`]'s clock;
    /// `None` once the deadline has come or the link is cancelled.
    fn recv_until(&mut self, deadline: Instant) -> Result<Option<(Instant, CanFrame)>, LinkError>;

    /// Whether whoever runs this link asked to stop.
    fn is_cancelled(&self) -> bool;

    /// The bus, for messages (`socketcand://127.0.0.1:29536/can0`, `virtual bus (1 Mbit/s)`).
    fn describe(&self) -> String;

    /// Waits until `until` (or until cancelled) discarding what arrives, for a producer that only
    /// sends (SYNC): it must keep reading, since a hub drops a client that stops, but has no frame to
    /// wait for. A link may wait more precisely here than in [`Link::recv_until`].
    fn idle_until(&mut self, until: Instant) -> Result<(), LinkError> {
        while self.recv_until(until)?.is_some() {}
        Ok(())
    }

    /// [`Link::recv_until`] with the time the bus side stamped the frame, for measurements and
    /// telegram logs; a link whose transport stamps nothing gives its own receive time.
    fn recv_stamped_until(&mut self, deadline: Instant) -> Result<Option<Stamped>, LinkError> {
        Ok(self.recv_until(deadline)?.map(|(at, frame)| Stamped {
            at,
            bus_time: at,
            frame,
        }))
    }

    /// Who stamps the frames [`Link::recv_stamped_until`] returns, and how finely.
    fn timestamps(&self) -> Timestamps {
        Timestamps {
            source: TimestampSource::Host,
            resolution: Duration::from_micros(1),
        }
    }
}

impl<L: Link + ?Sized> Link for &mut L {
    fn now(&self) -> Instant {
        (**self).now()
    }

    fn send(&mut self, frame: &CanFrame) -> Result<(), LinkError> {
        (**self).send(frame)
    }

    fn recv_until(&mut self, deadline: Instant) -> Result<Option<(Instant, CanFrame)>, LinkError> {
        (**self).recv_until(deadline)
    }

    fn is_cancelled(&self) -> bool {
        (**self).is_cancelled()
    }

    fn describe(&self) -> String {
        (**self).describe()
    }

    fn idle_until(&mut self, until: Instant) -> Result<(), LinkError> {
        (**self).idle_until(until)
    }

    fn recv_stamped_until(&mut self, deadline: Instant) -> Result<Option<Stamped>, LinkError> {
        (**self).recv_stamped_until(deadline)
    }

    fn timestamps(&self) -> Timestamps {
        (**self).timestamps()
    }
}

/// What the caller's event handler tells [`drive`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flow<T> {
    /// Keep going.
    Continue,
    /// Stop driving and return this.
    Done(T),
}

/// Why [`drive`] ended without a result.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ended {
    /// The deadline passed.
    Deadline,
    /// The link was cancelled.
    Cancelled,
}

/// Runs `core` on `link` until `on_event` returns [`Flow::Done`], `deadline` passes or the link is
/// cancelled. Every frame the core produces is sent; every frame received goes to the core; its timers
/// run when due. The handler's own errors (and link errors, converted) end the drive at once.
pub fn drive<L, C, T, E>(
    link: &mut L,
    core: &mut C,
    deadline: Option<Instant>,
    mut on_event: impl FnMut(&mut C, C::Event) -> Result<Flow<T>, E>,
) -> Result<Result<T, Ended>, E>
where
    L: Link + ?Sized,
    C: Core,
    E: From<LinkError>,
{
    loop {
        flush(link, core)?;
        while let Some(event) = core.poll_event() {
            if let Flow::Done(result) = on_event(core, event)? {
                flush(link, core)?;
                return Ok(Ok(result));
            }
            flush(link, core)?;
        }
        if link.is_cancelled() {
            return Ok(Err(Ended::Cancelled));
        }
        let now = link.now();
        if deadline.is_some_and(|deadline| now >= deadline) {
            return Ok(Err(Ended::Deadline));
        }
        if let Some(due) = core.poll_timeout()
            && due <= now
        {
            core.handle_timeout(now);
            continue;
        }
        let until = [core.poll_timeout(), deadline, Some(now + MAX_WAIT)]
            .into_iter()
            .flatten()
            .min()
            .unwrap_or(now + MAX_WAIT);
        if let Some((at, frame)) = link.recv_until(until)? {
            core.handle_frame(at, &frame);
        }
    }
}

/// Sends every frame `core` has queued.
pub fn flush<L: Link + ?Sized, C: Core>(link: &mut L, core: &mut C) -> Result<(), LinkError> {
    while let Some(frame) = core.poll_transmit() {
        link.send(&frame)?;
    }
    Ok(())
}

/// A transport endpoint on the wall clock.
#[derive(Debug)]
pub struct BusLink {
    bus: Box<dyn CanBus>,
    cancel: Cancel,
}

impl BusLink {
    /// A link on an open bus, cancelled through `cancel`.
    ///
    /// On a socketcand hub (ours by default) the first 60 ms of traffic are waited out: the
    /// hub holds a new client's traffic back for its raw-mode grace (for python-can's handshake), and
    /// answers arriving that late would look like silence to a short timeout. Nothing sent before our
    /// first request matters to a master.
    pub fn new(bus: Box<dyn CanBus>, cancel: Cancel) -> Result<BusLink, LinkError> {
        let mut link = BusLink { bus, cancel };
        if matches!(link.bus.spec(), BusSpec::Socketcand { .. }) {
            let until = link.now() + HUB_RAW_GRACE;
            while link.recv_until(until)?.is_some() {}
        }
        Ok(link)
    }

    /// The bus spec.
    pub fn spec(&self) -> &BusSpec {
        self.bus.spec()
    }

    /// The transport, for what a link does not offer.
    pub fn bus_mut(&mut self) -> &mut dyn CanBus {
        &mut *self.bus
    }

    /// The transport back.
    pub fn into_bus(self) -> Box<dyn CanBus> {
        self.bus
    }

    /// One receive of at most `wait`. Overruns are logged and otherwise ignored: a lost frame shows up
    /// as a timeout or protocol error of the core that needed it.
    fn recv_one(&mut self, wait: Duration) -> Result<Option<Stamped>, LinkError> {
        match self.bus.recv(wait) {
            // The cores run on our clock: a hub's receive timestamp may come from another clock.
            Ok(Some(received)) => Ok(Some(Stamped {
                at: self.now(),
                bus_time: received.timestamp,
                frame: received.frame,
            })),
            Ok(None) => Ok(None),
            Err(TransportError::Overrun { lost, .. }) => {
                tracing::warn!("{lost} frames lost because canopener did not keep up with the bus");
                Ok(None)
            }
            Err(err) => Err(err.into()),
        }
    }
}

impl Link for BusLink {
    fn now(&self) -> Instant {
        WallClock::now()
    }

    fn send(&mut self, frame: &CanFrame) -> Result<(), LinkError> {
        Ok(self.bus.send(frame)?)
    }

    fn recv_until(&mut self, deadline: Instant) -> Result<Option<(Instant, CanFrame)>, LinkError> {
        Ok(self
            .recv_stamped_until(deadline)?
            .map(|stamped| (stamped.at, stamped.frame)))
    }

    fn recv_stamped_until(&mut self, deadline: Instant) -> Result<Option<Stamped>, LinkError> {
        loop {
            let now = self.now();
            if now >= deadline || self.is_cancelled() {
                return Ok(None);
            }
            let wait = deadline.saturating_duration_since(now).min(MAX_WAIT);
            if let Some(received) = self.recv_one(wait)? {
                return Ok(Some(received));
            }
        }
    }

    /// The transports document their stamps (`canopener_transport::Received`): the kernel's on
    /// SocketCAN, the server's on socketcand, the wire's on a bit-accurate `virtual:` bus, the local
    /// receive time otherwise; all on the Unix epoch in microseconds.
    fn timestamps(&self) -> Timestamps {
        let source = match self.bus.spec() {
            BusSpec::SocketCan { .. } => TimestampSource::Kernel,
            BusSpec::Socketcand { .. } => TimestampSource::Hub,
            _ => TimestampSource::Host,
        };
        Timestamps {
            source,
            resolution: Duration::from_micros(1),
        }
    }

    fn is_cancelled(&self) -> bool {
        self.cancel.is_cancelled()
    }

    fn describe(&self) -> String {
        self.bus.spec().to_string()
    }

    /// Takes what has arrived without waiting, then sleeps: a receive with a timeout is no way to
    /// wait precisely, since a socket timeout is rounded up to the kernel's tick (4 or 10 ms), far
    /// coarser than a SYNC period, while a sleep is precise to tens of microseconds.
    fn idle_until(&mut self, until: Instant) -> Result<(), LinkError> {
        loop {
            while self.recv_one(Duration::ZERO)?.is_some() {}
            let now = self.now();
            if now >= until || self.is_cancelled() {
                return Ok(());
            }
            std::thread::sleep(until.saturating_duration_since(now).min(MAX_WAIT));
        }
    }
}

//! The system monitor (`canopener-network`) on buses: heartbeats and EMCYs from one link per network into
//! [`SystemMonitor`], its events out.
//!
//! The links are served in turn up to a common deadline (the monitor's next timeout, at most
//! [`SLICE`] ahead): each real bus waits its share of the slice, every simulated bus on virtual time
//! runs to the deadline, so they stay in step, and real buses are read at least every [`SLICE`]. Frames carry their receive times, so the order of service does not change what the
//! monitor concludes.

use std::time::Duration;

use canopener_can::Instant;
use canopener_network::monitor::{Event, SystemMonitor};

use crate::link::{Flow, Link, LinkError};

/// The longest the links are served before the monitor's timers run and the caller hears back.
pub const SLICE: Duration = Duration::from_millis(20);

/// A monitor watching links (see the [module docs](self)).
#[derive(Debug)]
pub struct SystemWatch {
    monitor: SystemMonitor,
    started: bool,
}

impl SystemWatch {
    /// Watches with `monitor`; it starts at the first link's time on the first [`SystemWatch::run`].
    pub fn new(monitor: SystemMonitor) -> SystemWatch {
        SystemWatch {
            monitor,
            started: false,
        }
    }

    /// The monitor, for displays.
    pub fn monitor(&self) -> &SystemMonitor {
        &self.monitor
    }

    /// Serves `links` (network number, link) until `until` (on the first link's clock), until a link
    /// is cancelled or `on_slice` returns [`Flow::Done`]. After every slice `on_slice` gets the time, the
    /// monitor and the events of the slice (often none: a display redraws then). Returns the first link's time
    /// at the end.
    pub fn run<E>(
        &mut self,
        links: &mut [(u32, &mut dyn Link)],
        until: Option<Instant>,
        mut on_slice: impl FnMut(Instant, &SystemMonitor, Vec<Event>) -> Result<Flow<()>, E>,
    ) -> Result<Instant, E>
    where
        E: From<LinkError>,
    {
        let Some(first) = links.first() else {
            return Ok(Instant::ZERO);
        };
        let mut now = first.1.now();
        if !std::mem::replace(&mut self.started, true) {
            self.monitor.start(now);
        }
        loop {
            if until.is_some_and(|until| now >= until) || links.iter().any(|(_, link)| link.is_cancelled()) {
                return Ok(now);
            }
            let mut deadline = now + SLICE;
            if let Some(due) = self.monitor.poll_timeout() {
                deadline = deadline.min(due.max(now));
            }
            if let Some(until) = until {
                deadline = deadline.min(until);
            }
            // Each link waits its share of the slice in turn (a real bus only delivers while waited
            // on), then every link is brought up to the deadline (a simulated bus runs to it).
            let count = u32::try_from(links.len()).unwrap_or(u32::MAX);
            let span = deadline.saturating_duration_since(now);
            for pass in [true, false] {
                for (i, (net, link)) in links.iter_mut().enumerate() {
                    let share = now + span * (u32::try_from(i).unwrap_or(u32::MAX).saturating_add(1)) / count;
                    let until = if pass { share } else { deadline };
                    while let Some((at, frame)) = link.recv_until(until)? {
                        self.monitor.handle_frame(at, *net, &frame);
                    }
                }
            }
            // `links` is not empty (checked above); its first link's clock is the watch's.
            now = links.first().map_or(now, |(_, link)| link.now()).max(deadline);
            self.monitor.handle_timeout(now);
            let events: Vec<Event> = std::iter::from_fn(|| self.monitor.poll_event()).collect();
            if let Flow::Done(()) = on_slice(now, &self.monitor, events)? {
                return Ok(now);
            }
        }
    }
}

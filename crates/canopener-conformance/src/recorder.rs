//! A [`Link`] that keeps every frame it sends and receives: the telegram log of the whole run, of which
//! each test takes its part, and the frames tests look through after a wait (heartbeats counted, an
//! EMCY searched for).

use canopener_can::{CanFrame, Instant};
use canopener_link::link::{Link, LinkError, Stamped, Timestamps};

use crate::model::Direction;

/// One frame the tester sent or received.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Logged {
    /// When: the tester's clock when sending, the bus's stamp when receiving.
    pub at: Instant,
    /// When the link handed it over, on the clock the cores run on (for timeouts and windows).
    pub link_time: Instant,
    /// Which way.
    pub dir: Direction,
    /// The frame.
    pub frame: CanFrame,
}

/// Wraps a link and logs its traffic (see the [module docs](self)).
pub struct Recorder<'l> {
    inner: &'l mut dyn Link,
    log: Vec<Logged>,
}

impl std::fmt::Debug for Recorder<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Recorder")
            .field("link", &self.inner.describe())
            .field("logged", &self.log.len())
            .finish()
    }
}

impl<'l> Recorder<'l> {
    /// Logs `inner`'s traffic from now on.
    pub fn new(inner: &'l mut dyn Link) -> Recorder<'l> {
        Recorder {
            inner,
            log: Vec::new(),
        }
    }

    /// How many frames are logged: a mark to take the frames after it later.
    pub fn mark(&self) -> usize {
        self.log.len()
    }

    /// The frames logged since `mark`.
    pub fn since(&self, mark: usize) -> &[Logged] {
        self.log.get(mark..).unwrap_or(&[])
    }

    /// Forgets everything logged: the runner keeps each test's frames in its report and starts the
    /// next test with an empty log, so a long run does not hold every frame twice.
    pub fn clear(&mut self) {
        self.log.clear();
    }
}

impl Link for Recorder<'_> {
    fn now(&self) -> Instant {
        self.inner.now()
    }

    fn send(&mut self, frame: &CanFrame) -> Result<(), LinkError> {
        let at = self.inner.now();
        self.inner.send(frame)?;
        self.log.push(Logged {
            at,
            link_time: at,
            dir: Direction::Tx,
            frame: *frame,
        });
        Ok(())
    }

    fn recv_until(&mut self, deadline: Instant) -> Result<Option<(Instant, CanFrame)>, LinkError> {
        Ok(self
            .recv_stamped_until(deadline)?
            .map(|stamped| (stamped.at, stamped.frame)))
    }

    fn recv_stamped_until(&mut self, deadline: Instant) -> Result<Option<Stamped>, LinkError> {
        let received = self.inner.recv_stamped_until(deadline)?;
        if let Some(stamped) = received {
            self.log.push(Logged {
                at: stamped.bus_time,
                link_time: stamped.at,
                dir: Direction::Rx,
                frame: stamped.frame,
            });
        }
        Ok(received)
    }

    fn is_cancelled(&self) -> bool {
        self.inner.is_cancelled()
    }

    fn describe(&self) -> String {
        self.inner.describe()
    }

    /// Waits through [`Link::recv_stamped_until`], so that what arrives meanwhile is logged.
    fn idle_until(&mut self, until: Instant) -> Result<(), LinkError> {
        while self.recv_stamped_until(until)?.is_some() {}
        Ok(())
    }

    fn timestamps(&self) -> Timestamps {
        self.inner.timestamps()
    }
}

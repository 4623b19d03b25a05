//! Running the socketcand hub (`canopener-hub`) in the foreground: started, then served until a cancel
//! or a time limit, with its counters reported at a steady interval.

use std::io;
use std::net::SocketAddr;
use std::time::{Duration, Instant};

use canopener_hub::HubHandle;
/// The hub's settings and counters, so that front ends need not depend on the hub crate (and its
/// tokio) themselves.
pub use canopener_hub::{HubConfig, HubStats};

use crate::pacing::{SLICE, offset_from, sleep_until};
use canopener_link::cancel::Cancel;

/// The hub could not start; nothing is listening.
#[derive(Debug, thiserror::Error)]
#[error("cannot start a hub on {listen}: {source}")]
pub struct HubStartError {
    /// The address it was to listen on.
    pub listen: SocketAddr,
    /// Why: typically the port is taken.
    #[source]
    pub source: io::Error,
}

/// Why [`RunningHub::serve`] returned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HubEnd {
    /// The cancel token was set.
    Cancelled,
    /// The time limit passed.
    TimeUp,
}

/// A hub that listens and serves clients on its own threads until [`RunningHub::serve`] ends it.
#[derive(Debug)]
pub struct RunningHub {
    handle: HubHandle,
}

impl RunningHub {
    /// Binds `config.listen` and starts serving; returns once clients can connect.
    pub fn start(config: HubConfig) -> Result<RunningHub, HubStartError> {
        let listen = config.listen;
        let handle = canopener_hub::spawn(config).map_err(|source| HubStartError { listen, source })?;
        Ok(RunningHub { handle })
    }

    /// The address the hub listens on, with the real port when port 0 was asked for.
    pub fn local_addr(&self) -> SocketAddr {
        self.handle.local_addr()
    }

    /// The hub's counters now.
    pub fn stats(&self) -> HubStats {
        self.handle.stats()
    }

    /// Blocks until `cancel` is set or `limit` has passed, calling `on_stats` every `stats_every` (not at
    /// the start), then stops accepting, closes every connection and returns why it ended.
    pub fn serve(
        self,
        cancel: &Cancel,
        limit: Option<Duration>,
        stats_every: Option<Duration>,
        mut on_stats: impl FnMut(&HubStats),
    ) -> HubEnd {
        let started = Instant::now();
        let end = limit.map(|limit| offset_from(started, limit.as_secs_f64()));
        let stats_every = stats_every.filter(|every| !every.is_zero());
        let mut reports = 0u64;
        let end = loop {
            let next_report = stats_every
                .and_then(|every| offset_from(started, every.as_secs_f64() * (reports + 1) as f64));
            let wake = [next_report, end.flatten()].into_iter().flatten().min();
            // Sleeping in slices bounds how late a cancel is noticed, as everywhere in this crate.
            if !sleep_until(Some(wake.unwrap_or_else(|| Instant::now() + SLICE)), cancel) {
                break HubEnd::Cancelled;
            }
            let now = Instant::now();
            if end.flatten().is_some_and(|end| now >= end) {
                break HubEnd::TimeUp;
            }
            if next_report.is_some_and(|due| now >= due) {
                reports += 1;
                on_stats(&self.handle.stats());
            }
        };
        self.handle.shutdown();
        end
    }
}

#[cfg(test)]
mod tests {
    use std::io::{BufRead, BufReader, Read};
    use std::net::TcpStream;

    use super::*;

    fn local_config() -> HubConfig {
        HubConfig::new(SocketAddr::from(([127, 0, 0, 1], 0)))
    }

    #[test]
    fn serves_socketcand_clients_until_cancelled() {
        let hub = RunningHub::start(local_config()).unwrap();
        let addr = hub.local_addr();
        assert_ne!(addr.port(), 0);
        let mut client = BufReader::new(TcpStream::connect(addr).unwrap());
        let mut greeting = Vec::new();
        client.read_until(b'>', &mut greeting).unwrap();
        assert_eq!(greeting, b"< hi >");
        let cancel = Cancel::new();
        let canceller = cancel.clone();
        let stopper = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(100));
            canceller.cancel();
        });
        assert_eq!(hub.serve(&cancel, None, None, |_| {}), HubEnd::Cancelled);
        stopper.join().unwrap();
        // Shut down: the connection is closed and nobody listens any more.
        client
            .get_ref()
            .set_read_timeout(Some(Duration::from_secs(5)))
            .unwrap();
        let mut rest = Vec::new();
        assert_eq!(client.read_to_end(&mut rest).unwrap(), 0);
        assert!(TcpStream::connect(addr).is_err());
    }

    #[test]
    fn reports_counters_at_each_interval_until_the_limit() {
        let hub = RunningHub::start(local_config()).unwrap();
        assert_eq!(hub.stats().clients_active, 0);
        let mut reports = Vec::new();
        let end = hub.serve(
            &Cancel::new(),
            Some(Duration::from_millis(350)),
            Some(Duration::from_millis(100)),
            |stats| reports.push(*stats),
        );
        assert_eq!(end, HubEnd::TimeUp);
        assert_eq!(reports.len(), 3, "{reports:?}");
        assert!(reports.iter().all(|stats| stats.frames_in == 0));
    }

    #[test]
    fn a_taken_port_is_an_error_naming_the_address() {
        let first = RunningHub::start(local_config()).unwrap();
        let mut config = local_config();
        config.listen = first.local_addr();
        let err = RunningHub::start(config).unwrap_err();
        assert_eq!(err.listen, first.local_addr());
        assert_eq!(err.source.kind(), io::ErrorKind::AddrInUse);
        first.serve(&Cancel::new(), Some(Duration::ZERO), None, |_| {});
    }
}

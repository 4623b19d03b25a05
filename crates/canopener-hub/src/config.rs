//! How a hub is set up.

use std::net::SocketAddr;
use std::time::Duration;

use canopener_socketcand::DEFAULT_MAX_ELEMENT_LEN;

/// The smallest per-client queue the hub uses, whatever the configuration says.
pub(crate) const MIN_CLIENT_QUEUE: usize = 16;
/// The largest per-client queue; far beyond any useful size, and below tokio's semaphore limit.
pub(crate) const MAX_CLIENT_QUEUE: usize = 1 << 24;

/// The settings of a [`crate::Hub`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HubConfig {
    /// The address to listen on; port 0 picks a free port (see [`crate::Hub::local_addr`]).
    pub listen: SocketAddr,
    /// How long bus traffic is held back (queued, never dropped) after the `< ok >` that answers
    /// `< rawmode >`. python-can reads that reply with one `recv` and fails if a frame is glued to it.
    /// Default 50 ms; 20 ms already gave zero failures in 200 handshakes under a flood.
    pub raw_grace: Duration,
    /// How many frames (and replies) may wait for one client before its senders are slowed down.
    /// Default 8192, about 0.9 s of a saturated 1 Mbit/s bus.
    pub client_queue: usize,
    /// How long a client may leave its queue full, or a socket write unfinished, before it is dropped.
    /// Senders on its bus wait at most this long for it. Default 2 s.
    pub stall_timeout: Duration,
    /// Whether a client also receives its own frames. Default off, as with socketcand, whose CAN_RAW
    /// sockets do not receive their own messages.
    pub echo: bool,
    /// The longest element accepted from a client, in bytes including the brackets; longer ones are
    /// discarded. Default 256.
    pub max_element_len: usize,
}

impl HubConfig {
    /// The defaults documented on each field, listening on `listen`.
    pub fn new(listen: SocketAddr) -> HubConfig {
        HubConfig {
            listen,
            raw_grace: Duration::from_millis(50),
            client_queue: 8192,
            stall_timeout: Duration::from_secs(2),
            echo: false,
            max_element_len: DEFAULT_MAX_ELEMENT_LEN,
        }
    }

    /// The per-client queue size actually used: `client_queue` clamped to a workable range.
    pub(crate) fn effective_client_queue(&self) -> usize {
        self.client_queue.clamp(MIN_CLIENT_QUEUE, MAX_CLIENT_QUEUE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_documented_ones() {
        let config = HubConfig::new(SocketAddr::from(([127, 0, 0, 1], 29536)));
        assert_eq!(config.raw_grace, Duration::from_millis(50));
        assert_eq!(config.client_queue, 8192);
        assert_eq!(config.stall_timeout, Duration::from_secs(2));
        assert!(!config.echo);
        assert_eq!(config.max_element_len, 256);
    }

    #[test]
    fn queue_size_is_clamped() {
        let mut config = HubConfig::new(SocketAddr::from(([127, 0, 0, 1], 0)));
        config.client_queue = 0;
        assert_eq!(config.effective_client_queue(), MIN_CLIENT_QUEUE);
        config.client_queue = usize::MAX;
        assert_eq!(config.effective_client_queue(), MAX_CLIENT_QUEUE);
    }
}

//! Counters the hub keeps while it runs, readable from any thread without stopping it.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// A snapshot of the hub's counters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct HubStats {
    /// Connections accepted since the hub started.
    pub clients_connected: u64,
    /// Connections open right now.
    pub clients_active: u64,
    /// Clients the hub disconnected because they stopped reading (stalled) or could not be written to.
    pub clients_dropped: u64,
    /// Frames received from clients and put on a bus.
    pub frames_in: u64,
    /// Frame deliveries written to client sockets (one frame to three receivers counts three).
    pub frames_out: u64,
    /// Elements that were over-long, not UTF-8, malformed, or not allowed in the client's state.
    pub garbage_elements: u64,
    /// Bytes outside any element, or inside a discarded over-long element.
    pub discarded_bytes: u64,
    /// Buses that have at least one client attached.
    pub buses_active: u64,
}

/// A cheap, cloneable view of a running hub's counters.
#[derive(Debug, Clone, Default)]
pub struct HubStatsHandle {
    counters: Arc<Counters>,
}

impl HubStatsHandle {
    /// The counters as they are now. Each counter is read atomically, the set is not: under load
    /// `frames_out` may already include deliveries of frames that `frames_in` does not count yet.
    pub fn snapshot(&self) -> HubStats {
        let c = &self.counters;
        HubStats {
            clients_connected: c.clients_connected.load(Ordering::Relaxed),
            clients_active: c.clients_active.load(Ordering::Relaxed),
            clients_dropped: c.clients_dropped.load(Ordering::Relaxed),
            frames_in: c.frames_in.load(Ordering::Relaxed),
            frames_out: c.frames_out.load(Ordering::Relaxed),
            garbage_elements: c.garbage_elements.load(Ordering::Relaxed),
            discarded_bytes: c.discarded_bytes.load(Ordering::Relaxed),
            buses_active: c.buses_active.load(Ordering::Relaxed),
        }
    }

    pub(crate) fn counters(&self) -> &Arc<Counters> {
        &self.counters
    }
}

/// The live counters behind [`HubStatsHandle`].
#[derive(Debug, Default)]
pub(crate) struct Counters {
    pub(crate) clients_connected: AtomicU64,
    pub(crate) clients_active: AtomicU64,
    pub(crate) clients_dropped: AtomicU64,
    pub(crate) frames_in: AtomicU64,
    pub(crate) frames_out: AtomicU64,
    pub(crate) garbage_elements: AtomicU64,
    pub(crate) discarded_bytes: AtomicU64,
    pub(crate) buses_active: AtomicU64,
}

impl Counters {
    pub(crate) fn add(counter: &AtomicU64, amount: u64) {
        counter.fetch_add(amount, Ordering::Relaxed);
    }

    pub(crate) fn sub(counter: &AtomicU64, amount: u64) {
        counter.fetch_sub(amount, Ordering::Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snapshot_reflects_updates_from_clones() {
        let handle = HubStatsHandle::default();
        let clone = handle.clone();
        Counters::add(&clone.counters().frames_in, 5);
        Counters::add(&clone.counters().clients_active, 2);
        Counters::sub(&clone.counters().clients_active, 1);
        let stats = handle.snapshot();
        assert_eq!(stats.frames_in, 5);
        assert_eq!(stats.clients_active, 1);
        assert_eq!(stats.frames_out, 0);
    }
}

//! Cooperative cancellation: a front end asks a long-running loop (a link's, a simulator's, a bus
//! tool's) to stop, and the loop ends at its next safe point (after aborting a running SDO transfer on
//! the bus, after flushing a log) instead of dying mid-write.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// A flag shared between whoever asks to stop and the loops that honour it. Clones share the flag.
#[derive(Debug, Clone, Default)]
pub struct Cancel(Arc<AtomicBool>);

impl Cancel {
    /// A token nobody has cancelled yet.
    pub fn new() -> Cancel {
        Cancel::default()
    }

    /// Asks every loop holding a clone of this token to stop.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::SeqCst);
    }

    /// Takes a cancellation back, for a loop that stopped at its safe point and must still finish a
    /// bounded clean-up on the bus (writing back what it changed); a later
    /// [`cancel`](Cancel::cancel), e.g. a second Ctrl-C, stops that too.
    pub fn resume(&self) {
        self.0.store(false, Ordering::SeqCst);
    }

    /// Whether [`cancel`](Cancel::cancel) has been called on this token or a clone.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clones_share_the_flag() {
        let token = Cancel::new();
        let loop_side = token.clone();
        assert!(!loop_side.is_cancelled());
        token.cancel();
        assert!(loop_side.is_cancelled());
        loop_side.resume();
        assert!(!token.is_cancelled());
    }
}

//! Rate limiting for log lines a peer can trigger, so a garbage flood cannot flood the log.

use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Allows at most `burst` log lines per `window`, counting what it suppressed in between.
#[derive(Debug)]
pub(crate) struct LogLimiter {
    burst: u32,
    window: Duration,
    state: Mutex<WindowState>,
}

#[derive(Debug)]
struct WindowState {
    started: Option<Instant>,
    emitted: u32,
    suppressed: u64,
}

impl LogLimiter {
    pub(crate) fn new(burst: u32, window: Duration) -> LogLimiter {
        LogLimiter {
            burst,
            window,
            state: Mutex::new(WindowState {
                started: None,
                emitted: 0,
                suppressed: 0,
            }),
        }
    }

    /// `Some(n)` when a line may be logged now, `n` being how many were suppressed since the last
    /// logged one; `None` when this line must be dropped.
    pub(crate) fn allow(&self) -> Option<u64> {
        self.allow_at(Instant::now())
    }

    fn allow_at(&self, now: Instant) -> Option<u64> {
        // The state is a few counters; a panic elsewhere cannot leave them unusable.
        let mut state = self.state.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        let window_over = state
            .started
            .is_none_or(|started| now.saturating_duration_since(started) >= self.window);
        if window_over {
            state.started = Some(now);
            state.emitted = 0;
        }
        if state.emitted < self.burst {
            state.emitted += 1;
            Some(std::mem::take(&mut state.suppressed))
        } else {
            state.suppressed += 1;
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_burst_is_allowed_then_lines_are_counted_until_the_next_window() {
        let limiter = LogLimiter::new(3, Duration::from_secs(1));
        let start = Instant::now();
        let first_window: Vec<_> = (0..10).map(|_| limiter.allow_at(start)).collect();
        assert_eq!(first_window[..3], [Some(0), Some(0), Some(0)]);
        assert!(first_window[3..].iter().all(Option::is_none));
        assert_eq!(limiter.allow_at(start + Duration::from_millis(999)), None);
        assert_eq!(limiter.allow_at(start + Duration::from_secs(1)), Some(8));
        assert_eq!(limiter.allow_at(start + Duration::from_secs(1)), Some(0));
    }
}

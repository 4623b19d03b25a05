//! Waiting on the wall clock without becoming deaf to a [`Cancel`]: every wait here is cut into short
//! slices, so a stop request during a long recorded gap or a slow rate is honoured within one slice.

use std::time::{Duration, Instant};

use canopener_link::cancel::Cancel;

/// The longest single sleep: how late a cancel may be noticed while waiting.
pub(crate) const SLICE: Duration = Duration::from_millis(100);

/// Sleeps until `due`, or forever when `due` is `None` (a schedule too far out to represent), unless
/// `cancel` is set first. Returns whether `due` was reached; `false` means cancelled.
pub(crate) fn sleep_until(due: Option<Instant>, cancel: &Cancel) -> bool {
    loop {
        if cancel.is_cancelled() {
            return false;
        }
        let now = Instant::now();
        let wait = match due {
            Some(due) if now >= due => return true,
            Some(due) => (due - now).min(SLICE),
            None => SLICE,
        };
        std::thread::sleep(wait);
    }
}

/// `start + offset`, or `None` when that instant cannot be represented (an absurd rate or speed).
pub(crate) fn offset_from(start: Instant, offset_secs: f64) -> Option<Instant> {
    Duration::try_from_secs_f64(offset_secs)
        .ok()
        .and_then(|offset| start.checked_add(offset))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reaches_a_due_time_in_the_past_at_once() {
        let cancel = Cancel::new();
        let started = Instant::now();
        assert!(sleep_until(Some(started), &cancel));
        assert!(started.elapsed() < SLICE);
    }

    #[test]
    fn a_cancel_ends_even_an_endless_wait() {
        let cancel = Cancel::new();
        cancel.cancel();
        assert!(!sleep_until(None, &cancel));
    }

    #[test]
    fn waits_until_the_due_time() {
        let cancel = Cancel::new();
        let started = Instant::now();
        assert!(sleep_until(Some(started + Duration::from_millis(30)), &cancel));
        assert!(started.elapsed() >= Duration::from_millis(30));
    }

    #[test]
    fn offsets_beyond_any_clock_are_never() {
        let start = Instant::now();
        assert_eq!(offset_from(start, 1.5), Some(start + Duration::from_millis(1500)));
        assert_eq!(offset_from(start, f64::INFINITY), None);
        assert_eq!(offset_from(start, f64::NAN), None);
        assert_eq!(offset_from(start, -1.0), None);
        assert_eq!(offset_from(start, 1e300), None);
    }
}

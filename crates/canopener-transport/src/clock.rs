//! The wall clock: the only clock canopener's real-time code reads.

use std::sync::OnceLock;
use std::time::{SystemTime, UNIX_EPOCH};

use canopener_can::Instant;

/// Unix-epoch time that never goes backwards within one process.
///
/// The system time is read once, on first use, and from then on the monotonic clock's elapsed time
/// is added to it. An NTP step or a manual clock change therefore cannot reorder timestamps of
/// frames received by this process, at the price of drifting from the system clock by whatever
/// the system clock is corrected by while the process runs.
#[derive(Debug, Clone, Copy, Default)]
pub struct WallClock;

impl WallClock {
    /// Nanoseconds since the Unix epoch, monotonic within the process.
    pub fn now() -> Instant {
        let (epoch_at_anchor, anchor) = anchor();
        epoch_at_anchor + anchor.elapsed()
    }
}

fn anchor() -> (Instant, std::time::Instant) {
    static ANCHOR: OnceLock<(Instant, std::time::Instant)> = OnceLock::new();
    *ANCHOR.get_or_init(|| {
        // A system clock set before 1970 is a broken machine, not input; starting at the epoch
        // keeps timestamps monotonic and printable instead of failing every receive.
        let since_epoch = SystemTime::now().duration_since(UNIX_EPOCH).unwrap_or_default();
        let nanos = u64::try_from(since_epoch.as_nanos()).unwrap_or(u64::MAX);
        (Instant::from_nanos(nanos), std::time::Instant::now())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn wall_clock_is_unix_epoch_based() {
        let system = SystemTime::now().duration_since(UNIX_EPOCH).unwrap();
        let ours = WallClock::now();
        let diff = Duration::from_nanos(ours.as_nanos()).abs_diff(system);
        assert!(
            diff < Duration::from_secs(5),
            "wall clock is {diff:?} away from the system time"
        );
    }

    #[test]
    fn wall_clock_never_goes_backwards() {
        let mut last = WallClock::now();
        for _ in 0..10_000 {
            let now = WallClock::now();
            assert!(now >= last, "{now:?} is before {last:?}");
            last = now;
        }
    }

    #[test]
    fn wall_clock_advances_with_real_time() {
        let before = WallClock::now();
        std::thread::sleep(Duration::from_millis(20));
        let elapsed = WallClock::now() - before;
        assert!(elapsed >= Duration::from_millis(20), "only {elapsed:?} elapsed");
        assert!(
            elapsed < Duration::from_secs(2),
            "{elapsed:?} elapsed for a 20 ms sleep"
        );
    }
}

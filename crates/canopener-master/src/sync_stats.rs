//! How well a SYNC producer (CiA 301 §7.2.5) kept its period: on a non-real-time OS wakeups come
//! late, and the consumers' synchronous PDOs inherit every late SYNC.

use std::time::Duration;

use canopener_can::Instant;

use crate::statistics::{Gaps, Spread};

/// What a run of a SYNC producer measured.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SyncStats {
    /// The communication cycle period asked for.
    pub period: Duration,
    /// SYNCs sent.
    pub sent: u64,
    /// Gaps between consecutive SYNCs.
    pub gaps: Gaps,
    /// Wakeups a whole period or more late (SYNC deadlines skipped).
    pub overruns: u64,
    /// SYNC deadlines skipped by those overruns.
    pub skipped: u64,
    /// SYNCs sent more than [`SyncStats::late_threshold`] after their deadline.
    pub late: u64,
    /// The latest a SYNC was sent after its deadline.
    pub worst_late: Duration,
}

impl SyncStats {
    /// Nothing sent yet with `period`.
    pub fn new(period: Duration) -> SyncStats {
        SyncStats {
            period,
            sent: 0,
            gaps: Gaps::new(),
            overruns: 0,
            skipped: 0,
            late: 0,
            worst_late: Duration::ZERO,
        }
    }

    /// A tenth of the period: later than that, consumers see a visibly uneven cycle.
    pub fn late_threshold(&self) -> Duration {
        self.period / 10
    }

    /// One SYNC sent at `now` for the deadline `due` (if known).
    pub fn sent(&mut self, now: Instant, due: Option<Instant>) {
        self.sent += 1;
        self.gaps.record(now);
        if let Some(due) = due {
            let late = now.saturating_duration_since(due);
            if late > self.late_threshold() {
                self.late += 1;
            }
            self.worst_late = self.worst_late.max(late);
        }
    }

    /// A wakeup that came `missed` periods too late.
    pub fn overrun(&mut self, missed: u64) {
        self.overruns += 1;
        self.skipped += missed;
    }

    /// Min, median and max of the gaps between SYNCs.
    pub fn gap_spread(&self) -> Option<Spread> {
        self.gaps.spread()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ms(ms: u64) -> Instant {
        Instant::from_millis(ms)
    }

    #[test]
    fn gaps_lateness_and_overruns_are_counted() {
        let mut stats = SyncStats::new(Duration::from_millis(10));
        // Due at 0, 10, 20, 60 and sent on time, 0.5 ms late, 3 ms late, on time.
        stats.sent(ms(0), Some(ms(0)));
        stats.sent(Instant::from_micros(10_500), Some(ms(10)));
        stats.sent(ms(23), Some(ms(20)));
        stats.overrun(2);
        stats.sent(ms(60), Some(ms(60)));
        assert_eq!(stats.sent, 4);
        assert_eq!((stats.late, stats.worst_late), (1, Duration::from_millis(3)));
        assert_eq!((stats.overruns, stats.skipped), (1, 2));
        let spread = stats.gap_spread().unwrap();
        assert_eq!(spread.min, Duration::from_micros(10_500));
        assert_eq!(spread.median, Duration::from_micros(12_500));
        assert_eq!(spread.max, Duration::from_millis(37));
    }
}

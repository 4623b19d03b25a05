//! Running a SYNC producer (CiA 301 §7.2.5) on a link, with a report of how well the period was
//! kept ([`SyncStats`]): on a non-real-time OS wakeups come late, and the consumers' synchronous PDOs
//! inherit every late SYNC.
//!
//! The producer takes no frames, so the loop does not wait in timed receives but in
//! [`Link::idle_until`], which keeps the period far better on a real bus.

use std::time::Duration;

use canopener_can::Core;
use canopener_master::sync_producer::{SyncEvent, SyncProducer};
use canopener_master::sync_stats::SyncStats;

use crate::link::{Link, LinkError, flush};

/// When a SYNC run ends (besides cancellation of the link).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SyncLimits {
    /// After this many SYNCs.
    pub count: Option<u64>,
    /// After this long.
    pub duration: Option<Duration>,
}

/// Runs `producer` (of period `period`) on `link` until `limits` or a cancellation end it; `on_sent`
/// hears of every wakeup that sent. Returns the statistics and how long the run took.
pub fn run<L: Link + ?Sized>(
    link: &mut L,
    producer: &mut SyncProducer,
    period: Duration,
    limits: SyncLimits,
    mut on_sent: impl FnMut(&SyncStats),
) -> Result<(SyncStats, Duration), LinkError> {
    let started = link.now();
    let deadline = limits.duration.map(|duration| started + duration);
    let mut stats = SyncStats::new(period);
    producer.start(started);
    while !link.is_cancelled() && limits.count.is_none_or(|count| stats.sent < count) {
        let now = link.now();
        if deadline.is_some_and(|deadline| now >= deadline) {
            break;
        }
        match producer.poll_timeout() {
            Some(due) if due <= now => {
                producer.handle_timeout(now);
                flush(link, producer)?;
                let sent_at = link.now();
                let mut missed_now = 0;
                while let Some(event) = producer.poll_event() {
                    match event {
                        SyncEvent::Sent { .. } => {
                            // The first deadline this wakeup served: the next one less a period and
                            // the deadlines skipped (SyncProducer keeps them on the start + k × period
                            // grid), so that lateness counts from when the wakeup was due.
                            let skipped =
                                period.saturating_mul(u32::try_from(missed_now).unwrap_or(u32::MAX));
                            let due = producer.poll_timeout().map(|next| next - period - skipped);
                            stats.sent(sent_at, due);
                        }
                        SyncEvent::Overrun { missed } => {
                            missed_now = missed;
                            stats.overrun(missed);
                        }
                    }
                }
                on_sent(&stats);
            }
            due => {
                let until = [due, deadline]
                    .into_iter()
                    .flatten()
                    .min()
                    .unwrap_or(now + crate::link::MAX_WAIT);
                link.idle_until(until.min(now + crate::link::MAX_WAIT))?;
            }
        }
    }
    Ok((stats, link.now().saturating_duration_since(started)))
}

//! `sync_producer`: SYNC on virtual time keeps its period exactly.

use std::time::Duration;

use canopener_link::cancel::Cancel;
use canopener_link::sync_producer::{SyncLimits, run};
use canopener_link::virtual_link::VirtualLink;
use canopener_master::sync_producer::{SyncConfig, SyncProducer};

use crate::common::{Node, bus, trace};

#[test]
fn a_counted_run_sends_on_the_period_grid_with_the_counter() {
    let (mut link, _) = bus(vec![]);
    let mut config = SyncConfig::new(Duration::from_millis(10));
    config.counter_overflow = Some(3);
    let mut producer = SyncProducer::new(config).expect("producer");
    let limits = SyncLimits {
        count: Some(5),
        duration: None,
    };
    let mut wakeups = 0;
    let (stats, elapsed) = run(
        &mut link,
        &mut producer,
        Duration::from_millis(10),
        limits,
        |_| wakeups += 1,
    )
    .expect("ran");
    assert_eq!((stats.sent, wakeups), (5, 5));
    assert_eq!(
        (stats.late, stats.overruns, stats.worst_late),
        (0, 0, Duration::ZERO)
    );
    let gaps = stats.gap_spread().expect("gaps");
    assert_eq!(
        (gaps.min, gaps.max),
        (Duration::from_millis(10), Duration::from_millis(10))
    );
    assert_eq!(elapsed, Duration::from_millis(40));
    assert_eq!(
        trace(&mut link, &[0x080]),
        ["0 080#01", "10 080#02", "20 080#03", "30 080#01", "40 080#02"]
    );
}

/// SYNC every 10 ms without counter on `link` until `limits`: the number sent and the time taken.
fn run_plain(link: &mut VirtualLink<Node>, limits: SyncLimits) -> (u64, Duration) {
    let period = Duration::from_millis(10);
    let mut producer = SyncProducer::new(SyncConfig::new(period)).expect("producer");
    let (stats, elapsed) = run(link, &mut producer, period, limits, |_| {}).expect("ran");
    (stats.sent, elapsed)
}

#[test]
fn a_timed_run_ends_at_its_duration_and_a_cancelled_one_at_once() {
    let limits = SyncLimits {
        count: None,
        duration: Some(Duration::from_millis(95)),
    };
    let (mut link, _) = bus(vec![]);
    assert_eq!(run_plain(&mut link, limits), (10, Duration::from_millis(95)));

    let cancel = Cancel::new();
    cancel.cancel();
    let (link, _) = bus(Vec::new());
    let mut link = link.with_cancel(cancel);
    assert_eq!(run_plain(&mut link, limits), (0, Duration::ZERO));
}

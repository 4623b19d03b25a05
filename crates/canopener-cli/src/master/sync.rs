//! `canopener sync`: a SYNC producer (CiA 301 §7.2.5) on the bus, run by
//! `canopener_link::sync_producer`, with a report of how well the operating system kept the
//! period (`canopener_master::sync_stats`): on a non-real-time OS wakeups come late, and the
//! consumers' synchronous PDOs inherit every late SYNC.

use std::time::Duration;

use canopener_link::sync_producer::{SyncLimits, run as produce};
use canopener_master::sync_producer::{SyncConfig, SyncProducer};
use canopener_master::sync_stats::SyncStats;

use serde_json::json;

use crate::args::OutputFormat;
use crate::error::{CliError, CliResult};
use crate::master::args::SyncArgs;
use crate::master::link::open_link;
use crate::master::output::{millis, spinner, spread_json};
use crate::output::print_stdout;

pub(crate) fn run(args: SyncArgs) -> CliResult {
    if args.count == Some(0) {
        return Err(CliError::Usage(
            "--count 0 sends no SYNC; give how many to send, e.g. `canopener sync --period 10ms --count 100`"
                .to_owned(),
        ));
    }
    let mut config = SyncConfig::new(args.period);
    config.counter_overflow = args.counter;
    let mut producer = SyncProducer::new(config).map_err(|err| {
        CliError::Usage(format!(
            "{err}, e.g. `canopener sync --period 10ms --counter 240`"
        ))
    })?;
    let mut link = open_link(args.master.bus.spec.as_deref(), "sync")?;
    let progress = spinner("{spinner} {pos} SYNC sent, {elapsed} (Ctrl-C to stop)");
    let limits = SyncLimits {
        count: args.count,
        duration: args.duration,
    };
    let (stats, elapsed) = produce(&mut link, &mut producer, args.period, limits, |stats| {
        progress.set_position(stats.sent);
    })?;
    progress.finish_and_clear();
    print_stdout(&report(&stats, args.master.format, elapsed, args.counter))
}

/// The report of a run, as text or one JSON line.
fn report(stats: &SyncStats, format: OutputFormat, elapsed: Duration, counter: Option<u8>) -> String {
    let spread = stats.gap_spread();
    match format {
        OutputFormat::Json => {
            json!({
                "sent": stats.sent,
                "duration_ms": millis(elapsed),
                "period_ms": millis(stats.period),
                "counter_overflow": counter,
                "gap_ms": spread.map(|spread| spread_json(&spread)),
                "late": stats.late,
                "late_threshold_ms": millis(stats.late_threshold()),
                "worst_late_ms": millis(stats.worst_late),
                "overruns": stats.overruns,
                "skipped": stats.skipped,
            })
            .to_string()
                + "\n"
        }
        OutputFormat::Text => {
            let counter = counter.map_or_else(|| "no counter".to_owned(), |max| format!("counter 1..{max}"));
            let mut text = format!(
                "sent {} SYNC in {:.3} s (period {:.3} ms, {counter})\n",
                stats.sent,
                elapsed.as_secs_f64(),
                millis(stats.period)
            );
            if let Some(spread) = spread {
                text.push_str(&format!(
                    "gaps between SYNCs: min {:.3} ms, median {:.3} ms, max {:.3} ms\n",
                    millis(spread.min),
                    millis(spread.median),
                    millis(spread.max)
                ));
            }
            text.push_str(&format!(
                "late wakeups: {} more than {:.3} ms late (worst {:.3} ms); overruns: {} ({} SYNC skipped)\n",
                stats.late,
                millis(stats.late_threshold()),
                millis(stats.worst_late),
                stats.overruns,
                stats.skipped
            ));
            text
        }
    }
}
#[cfg(test)]
mod tests {
    use super::*;
    use canopener_can::Instant;

    fn ms(ms: u64) -> Instant {
        Instant::from_millis(ms)
    }

    #[test]
    fn gaps_lateness_and_overruns_are_reported() {
        let mut stats = SyncStats::new(Duration::from_millis(10));
        // Due at 0, 10, 20, 60 and sent on time, 0.5 ms late, 3 ms late, on time.
        stats.sent(ms(0), Some(ms(0)));
        stats.sent(Instant::from_micros(10_500), Some(ms(10)));
        stats.sent(ms(23), Some(ms(20)));
        stats.overrun(2);
        stats.sent(ms(60), Some(ms(60)));
        let text = report(&stats, OutputFormat::Text, Duration::from_millis(60), Some(4));
        assert!(
            text.contains("sent 4 SYNC in 0.060 s (period 10.000 ms, counter 1..4)"),
            "{text}"
        );
        assert!(
            text.contains("min 10.500 ms, median 12.500 ms, max 37.000 ms"),
            "{text}"
        );
        assert!(
            text.contains("1 more than 1.000 ms late (worst 3.000 ms); overruns: 1 (2 SYNC skipped)"),
            "{text}"
        );
        let json: serde_json::Value = serde_json::from_str(&report(
            &stats,
            OutputFormat::Json,
            Duration::from_millis(60),
            None,
        ))
        .unwrap();
        assert_eq!(json["sent"], 4);
        assert_eq!(json["gap_ms"]["max"], 37.0);
        assert_eq!(json["late"], 1);
        assert_eq!(json["overruns"], 1);
        assert_eq!(json["skipped"], 2);
        assert_eq!(json["counter_overflow"], serde_json::Value::Null);
    }

    #[test]
    fn a_single_sync_has_no_gap_line() {
        let mut stats = SyncStats::new(Duration::from_millis(10));
        stats.sent(ms(0), Some(ms(0)));
        let text = report(&stats, OutputFormat::Text, Duration::from_millis(1), None);
        assert!(!text.contains("gaps"), "{text}");
        assert!(text.contains("no counter"), "{text}");
    }
}

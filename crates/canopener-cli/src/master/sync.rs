//! `canopener sync`: a SYNC producer (CiA 301 §7.2.5) on the wall clock, with a report of how well
//! the operating system kept the period: on a non-real-time OS wakeups come late, and the consumers'
//! synchronous PDOs inherit every late SYNC.
//!
//! It does not go through `master_io::BusLink::drive`, which waits in timed receives: the producer
//! takes no frames, and a sleep keeps the period far better (see [`drain`]).

use canopener_can::Core;
use std::io::{IsTerminal, Write};
use std::time::Duration;

use canopener_master::sync_producer::{SyncConfig, SyncEvent, SyncProducer};
use canopener_transport::{CanBus, TransportError, WallClock};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde_json::json;

use crate::args::OutputFormat;
use crate::bus_open::open_bus;
use crate::error::{CliError, CliResult, stdout_error};
use crate::master::args::SyncArgs;
use crate::master::heartbeat::millis;
use crate::stop::StopFlag;

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
    let stop = StopFlag::install()?;
    let mut bus = open_bus(args.master.bus.spec.as_deref(), "sync")?;
    let progress = progress_bar();
    let started = WallClock::now();
    let deadline = args.duration.map(|duration| started + duration);
    let mut stats = SyncStats::new(args.period);
    producer.start(started);
    while !stop.is_set() && args.count.is_none_or(|count| stats.sent < count) {
        let now = WallClock::now();
        if deadline.is_some_and(|deadline| now >= deadline) {
            break;
        }
        match producer.poll_timeout() {
            Some(due) if due <= now => {
                producer.handle_timeout(now);
                while let Some(frame) = producer.poll_transmit() {
                    bus.send(&frame)?;
                }
                let sent_at = WallClock::now();
                let mut missed_now = 0;
                while let Some(event) = producer.poll_event() {
                    match event {
                        SyncEvent::Sent { .. } => {
                            // The first deadline this wakeup served: the next one less a period and
                            // the deadlines skipped (SyncProducer keeps them on the start + k × period
                            // grid), so that lateness counts from when the wakeup was due.
                            let skipped = args
                                .period
                                .saturating_mul(u32::try_from(missed_now).unwrap_or(u32::MAX));
                            let due = producer.poll_timeout().map(|next| next - args.period - skipped);
                            stats.sent(sent_at, due);
                        }
                        SyncEvent::Overrun { missed } => {
                            missed_now = missed;
                            stats.overruns += 1;
                            stats.skipped += missed;
                        }
                    }
                }
                progress.set_position(stats.sent);
            }
            due => {
                drain(&mut *bus)?;
                let until = [due, deadline].into_iter().flatten().min();
                let wait = until.map_or(MAX_SLEEP, |until| until - now).min(MAX_SLEEP);
                std::thread::sleep(wait);
            }
        }
    }
    progress.finish_and_clear();
    let elapsed = WallClock::now() - started;
    let report = stats.report(args.master.format, elapsed, args.counter);
    let mut out = std::io::stdout().lock();
    out.write_all(report.as_bytes())
        .and_then(|()| out.flush())
        .map_err(stdout_error)
}

/// The longest sleep, so that Ctrl-C and the frames arriving meanwhile are looked at often.
const MAX_SLEEP: Duration = Duration::from_millis(50);

/// Takes every frame already received, without waiting: the producer needs none, but a hub
/// drops a client that stops reading. A receive with a timeout is no way to wait here: a socket
/// timeout is rounded up to the kernel's tick (4 or 10 ms), far coarser than a SYNC period, while
/// a sleep is precise to tens of microseconds.
fn drain(bus: &mut dyn CanBus) -> CliResult {
    loop {
        match bus.recv(Duration::ZERO) {
            Ok(Some(_)) => {}
            Ok(None) => return Ok(()),
            Err(TransportError::Overrun { .. }) => {}
            Err(err) => return Err(CliError::from(err)),
        }
    }
}

/// Minimum, median and maximum of some durations.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Spread {
    pub(crate) min: Duration,
    pub(crate) median: Duration,
    pub(crate) max: Duration,
}

impl Spread {
    /// `None` without samples. The median of an even number of samples is the upper middle one, a
    /// gap that really occurred.
    pub(crate) fn of(samples: &[Duration]) -> Option<Spread> {
        let mut sorted = samples.to_vec();
        sorted.sort_unstable();
        Some(Spread {
            min: *sorted.first()?,
            median: *sorted.get(sorted.len() / 2)?,
            max: *sorted.last()?,
        })
    }

    pub(crate) fn json(&self) -> serde_json::Value {
        json!({"min": millis(self.min), "median": millis(self.median), "max": millis(self.max)})
    }
}

/// What the run measured.
#[derive(Debug)]
struct SyncStats {
    period: Duration,
    sent: u64,
    last: Option<canopener_can::Instant>,
    /// Gaps between consecutive SYNCs in µs: 4 bytes each keep a long run at 1 ms affordable.
    gaps_us: Vec<u32>,
    /// Wakeups a whole period or more late (SYNC deadlines skipped).
    overruns: u64,
    skipped: u64,
    /// SYNCs sent more than [`SyncStats::late_threshold`] after their deadline.
    late: u64,
    worst_late: Duration,
}

impl SyncStats {
    fn new(period: Duration) -> SyncStats {
        SyncStats {
            period,
            sent: 0,
            last: None,
            gaps_us: Vec::new(),
            overruns: 0,
            skipped: 0,
            late: 0,
            worst_late: Duration::ZERO,
        }
    }

    /// A tenth of the period: later than that, consumers see a visibly uneven cycle.
    fn late_threshold(&self) -> Duration {
        self.period / 10
    }

    fn sent(&mut self, now: canopener_can::Instant, due: Option<canopener_can::Instant>) {
        self.sent += 1;
        if let Some(last) = self.last {
            let gap = u32::try_from((now - last).as_micros()).unwrap_or(u32::MAX);
            self.gaps_us.push(gap);
        }
        self.last = Some(now);
        if let Some(due) = due {
            let late = now - due;
            if late > self.late_threshold() {
                self.late += 1;
            }
            self.worst_late = self.worst_late.max(late);
        }
    }

    fn report(&self, format: OutputFormat, elapsed: Duration, counter: Option<u8>) -> String {
        let gaps: Vec<Duration> = self
            .gaps_us
            .iter()
            .map(|us| Duration::from_micros(u64::from(*us)))
            .collect();
        let spread = Spread::of(&gaps);
        match format {
            OutputFormat::Json => {
                json!({
                    "sent": self.sent,
                    "duration_ms": millis(elapsed),
                    "period_ms": millis(self.period),
                    "counter_overflow": counter,
                    "gap_ms": spread.map(|spread| spread.json()),
                    "late": self.late,
                    "late_threshold_ms": millis(self.late_threshold()),
                    "worst_late_ms": millis(self.worst_late),
                    "overruns": self.overruns,
                    "skipped": self.skipped,
                })
                .to_string()
                    + "\n"
            }
            OutputFormat::Text => {
                let counter =
                    counter.map_or_else(|| "no counter".to_owned(), |max| format!("counter 1..{max}"));
                let mut text = format!(
                    "sent {} SYNC in {:.3} s (period {:.3} ms, {counter})\n",
                    self.sent,
                    elapsed.as_secs_f64(),
                    millis(self.period)
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
                    self.late,
                    millis(self.late_threshold()),
                    millis(self.worst_late),
                    self.overruns,
                    self.skipped
                ));
                text
            }
        }
    }
}

/// A counter on stderr, drawn only on a terminal.
fn progress_bar() -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
    if let Ok(style) = ProgressStyle::with_template("{spinner} {pos} SYNC sent, {elapsed} (Ctrl-C to stop)") {
        bar.set_style(style);
    }
    bar
}

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_can::Instant;

    fn ms(ms: u64) -> Instant {
        Instant::from_millis(ms)
    }

    #[test]
    fn spread_takes_min_upper_median_and_max() {
        let samples = [5, 3, 9, 4].map(Duration::from_millis);
        let spread = Spread::of(&samples).unwrap();
        assert_eq!(spread.min, Duration::from_millis(3));
        assert_eq!(spread.median, Duration::from_millis(5));
        assert_eq!(spread.max, Duration::from_millis(9));
        assert_eq!(Spread::of(&[]), None);
    }

    #[test]
    fn gaps_lateness_and_overruns_are_reported() {
        let mut stats = SyncStats::new(Duration::from_millis(10));
        // Due at 0, 10, 20, 30 and sent on time, 0.5 ms late, 3 ms late, on time.
        stats.sent(ms(0), Some(ms(0)));
        stats.sent(Instant::from_micros(10_500), Some(ms(10)));
        stats.sent(ms(23), Some(ms(20)));
        stats.overruns += 1;
        stats.skipped += 2;
        stats.sent(ms(60), Some(ms(60)));
        let text = stats.report(OutputFormat::Text, Duration::from_millis(60), Some(4));
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
        let json: serde_json::Value =
            serde_json::from_str(&stats.report(OutputFormat::Json, Duration::from_millis(60), None)).unwrap();
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
        let text = stats.report(OutputFormat::Text, Duration::from_millis(1), None);
        assert!(!text.contains("gaps"), "{text}");
        assert!(text.contains("no counter"), "{text}");
    }
}

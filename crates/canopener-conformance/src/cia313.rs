//! The CiA 313-style performance test: how fast and how regularly a device does what CiA 301
//! requires, measured on the bus and judged against criteria the user gives (`--criteria FILE`,
//! [`criteria`](crate::performance::criteria)).
//!
//! Every test is designed from CiA 301 (what the device must do at all) and the method of CiA 313 as
//! the thesis (`seeds/001`, §4) applies it: a request seen on the bus, the answer seen on the bus,
//! repeated, the statistics (min, mean, p50/p90/p99, max) of the samples in ms. Both stamps of a
//! sample come from one clock. A response time is taken on the link's clock: the request when the
//! tester hands it to the link, the answer when the link hands it over (virtual bus time on a
//! simulated bus; the tester's clock on SocketCAN and socketcand, whose receive stamps come from the
//! kernel's or the hub's clock, which the tester's send time cannot be compared with). It includes
//! both frames' time on the wire and, on a real bus, the tester's own send and receive latency. A
//! period is the difference of two receive stamps of one producer from the bus side (the report's
//! `bus.timestamps`), so it carries no tester latency. A sample that is negative (an answer stamped
//! before its request, a frame before the one received before it) or not finite is impossible:
//! the test is inconclusive and says so, the sample is never clamped to 0.
//!
//! CiA 301 sets no response-time figures: without a criterion a response time is reported as a
//! measurement with the verdict `pass` ("measured, no criterion"); a device that does not answer at
//! all fails the CiA 301 clause it breaks. Each verdict's reason names the criterion that decided it,
//! and warns when the stamps are too coarse for it.

use std::time::Duration;

use canopener_can::{CanFrame, CanId, Instant};
use canopener_wire::NmtCommand;

use canopener_link::link::{TimestampSource, Timestamps};

use crate::context::{Ctx, Reply};
use crate::finding::{Evidence, Finding, Stop};
use crate::model::{Limits, Measurement};
use crate::requirements as req;
use crate::test_def::TestDef;

pub mod cycle;
mod response;

/// How many resets the boot-up time test makes at most.
pub const BOOT_UPS: usize = 10;

/// CiA 313's measurement method as the thesis applies it.
const METHOD: &str = "CiA 313 (performance testing: request and response seen on the bus), seeds/001 §4.2";

/// The performance tests.
pub fn tests() -> Vec<TestDef> {
    let test = |id, title, references, precondition, tags, run| TestDef {
        id,
        suite: "cia313",
        group: "perf",
        title,
        references,
        precondition,
        tags,
        run,
    };
    vec![
        test(
            "cia313.perf.1",
            "SDO read response time of a type-I object (mapped into a TPDO, else an RPDO): upload request → response",
            &[METHOD, req::SDO_UPLOAD],
            "a PDO maps a readable object of at most 4 bytes",
            &["sdo", "timing", "performance"],
            response::sdo_read,
        ),
        test(
            "cia313.perf.2",
            "SDO write response time of a type-I object (mapped into an RPDO, else a TPDO): download request → response",
            &[METHOD, req::SDO_DOWNLOAD],
            "a PDO maps a writable object of at most 4 bytes (its own value is written back)",
            &["sdo", "timing", "performance", "writes"],
            response::sdo_write,
        ),
        test(
            "cia313.perf.3",
            "TPDO cycle time against the event timer (10 ms, 100 periods): deviation of every period",
            &[METHOD, req::PDO, req::PDO_PARAMETERS],
            "a TPDO with writable COB-ID, transmission type and event timer that maps data",
            &["pdo", "timing", "performance", "writes", "nmt"],
            cycle::event_timer,
        ),
        test(
            "cia313.perf.4",
            "TPDO cycle time against SYNC (type 1, 100 SYNCs 10 ms apart): SYNC → TPDO time and TPDO period jitter",
            &[METHOD, req::PDO, req::SYNC],
            "a TPDO with writable COB-ID and transmission type that maps data",
            &["pdo", "sync", "timing", "performance", "writes", "nmt"],
            cycle::sync,
        ),
        test(
            "cia313.perf.5",
            "TPDO RTR response time: remote frame → TPDO",
            &[METHOD, req::PDO],
            "a TPDO that allows RTR (COB-ID bit 30 clear), or one that can be set up so",
            &["pdo", "timing", "performance", "writes", "nmt"],
            response::rtr,
        ),
        test(
            "cia313.perf.6",
            "Boot-up time: NMT reset node → boot-up message",
            &[METHOD, req::BOOT_UP, req::NMT_MODULE_CONTROL],
            "every device",
            &["nmt", "timing", "performance"],
            response::boot_up,
        ),
        test(
            "cia313.perf.7",
            "LSS response time per confirmed service: inquire vendor-ID, product code, revision, serial, node-ID; switch state selective",
            &[METHOD, "CiA 305 v3.0 (inquire services, switch state selective)"],
            "EDS LSS_Supported=1, or (key absent) the device answers inquire or identify",
            &["lss", "timing", "performance"],
            response::lss,
        ),
        test(
            "cia313.perf.8",
            "Heartbeat producer deviation: 100 consecutive periods at 1017h = 100 ms",
            &[METHOD, req::HEARTBEAT],
            "1017h is writable",
            &["heartbeat", "timing", "performance", "writes"],
            cycle::heartbeat,
        ),
    ]
}

/// A bound on every sample and who set it.
#[derive(Debug, Clone)]
struct Criterion {
    low: Option<f64>,
    high: Option<f64>,
    /// `heartbeat.deviation_percent = 5 (documented default)`.
    name: String,
}

impl Criterion {
    /// At most `max` ms, when the criteria set it (`key` names it).
    fn at_most(ctx: &Ctx<'_, '_>, key: &str, max: Option<f64>) -> Option<Criterion> {
        max.map(|max| Criterion {
            low: None,
            high: Some(max),
            name: format!("{} = {max} ms", ctx.performance().criteria.origin(key)),
        })
    }

    /// `nominal` ±`percent` %.
    fn around(ctx: &Ctx<'_, '_>, key: &str, nominal: f64, percent: f64) -> Criterion {
        Criterion {
            low: Some(nominal * (1.0 - percent / 100.0)),
            high: Some(nominal * (1.0 + percent / 100.0)),
            name: format!(
                "{} ±{percent} % of {nominal} ms",
                ctx.performance().criteria.origin(key)
            ),
        }
    }

    fn admits(&self, sample: f64) -> bool {
        self.low.is_none_or(|low| sample >= low) && self.high.is_none_or(|high| sample <= high)
    }

    fn range_text(&self) -> String {
        match (self.low, self.high) {
            (Some(low), Some(high)) => format!("{low:.3}–{high:.3} ms"),
            (None, Some(high)) => format!("≤ {high:.3} ms"),
            (Some(low), None) => format!("≥ {low:.3} ms"),
            (None, None) => "any".to_owned(),
        }
    }

    /// The smallest step the criterion must tell apart, in ms: the distance from nominal to a bound.
    fn tolerance_ms(&self) -> f64 {
        match (self.low, self.high) {
            (Some(low), Some(high)) => (high - low) / 2.0,
            (None, Some(high)) => high,
            (Some(low), None) => low,
            (None, None) => f64::INFINITY,
        }
    }
}

/// Which clock a measurement's two stamps come from (see the [module docs](self)).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Clock {
    /// A response time: request and answer on the link's clock.
    Link,
    /// A period: two receive stamps of the bus side.
    Bus,
}

impl Clock {
    /// Who stamps `ctx`'s samples on this clock, and how finely.
    fn stamps(self, ctx: &Ctx<'_, '_>) -> Timestamps {
        let bus = ctx.timestamps();
        match self {
            Clock::Bus => bus,
            Clock::Link => link_stamps(bus),
        }
    }
}

/// The link's own clock for a link whose bus side stamps with `bus`: the same on virtual time, the
/// tester's (host) clock otherwise.
fn link_stamps(bus: Timestamps) -> Timestamps {
    match bus.source {
        TimestampSource::Virtual => bus,
        _ => Timestamps {
            source: TimestampSource::Host,
            resolution: Duration::from_micros(1),
        },
    }
}

/// What was measured, for the analysis of a failure.
struct Judged<'a> {
    /// The measurement's name in the report.
    name: &'a str,
    /// `SDO upload response time of 6000h:01`.
    what: String,
    /// The request, as the evidence states it.
    request: String,
    /// What CiA 301 requires of the device itself (the clause), before the criterion.
    clause: &'a str,
    /// The likely cause of a failure.
    cause: &'a str,
    /// Where the two stamps of each sample come from.
    clock: Clock,
}

/// Records `samples` (ms) as the measurement `judged.name` and judges them: inconclusive when one
/// is impossible ([`impossible`]), else against `criterion` when there is one, else `pass` with
/// "measured, no criterion", which the context records so that the summaries count it apart from
/// the conformance passes.
fn judge(
    ctx: &mut Ctx<'_, '_>,
    judged: Judged<'_>,
    samples: Vec<f64>,
    criterion: Option<Criterion>,
) -> Finding {
    let mut measurement = Measurement::new("ms", samples);
    let stats = stats_text(&measurement);
    let stamps = stamps_note(ctx, judged.clock, criterion.as_ref());
    if let Some(why) = impossible(&measurement.samples, judged.clock) {
        ctx.measure(judged.name, measurement);
        return Finding::inconclusive(format!("{}: {why}; not judged{stamps}", judged.what));
    }
    let Some(criterion) = criterion else {
        ctx.measure(judged.name, measurement);
        ctx.judged_without_criterion();
        return Finding::pass(format!(
            "{}: {stats}; measured, no criterion{stamps}",
            judged.what
        ));
    };
    measurement = measurement.with_limits(Limits {
        low: criterion.low,
        high: criterion.high,
        criterion: criterion.name.clone(),
    });
    let outside: Vec<(usize, f64)> = measurement
        .samples
        .iter()
        .copied()
        .enumerate()
        .filter(|(_, s)| !criterion.admits(*s))
        .collect();
    let count = measurement.samples.len();
    ctx.measure(judged.name, measurement);
    if outside.is_empty() {
        return Finding::pass(format!(
            "{}: all {count} within {} ({}): {stats}{stamps}",
            judged.what,
            criterion.range_text(),
            criterion.name
        ));
    }
    let listed: Vec<String> = outside
        .iter()
        .take(5)
        .map(|(i, s)| format!("#{} {s:.3} ms", i + 1))
        .collect();
    Finding::fail(
        format!(
            "{}: {} of {count} outside {} ({}){stamps}",
            judged.what,
            outside.len(),
            criterion.range_text(),
            criterion.name
        ),
        Evidence {
            request: judged.request,
            requirement: format!(
                "{}; criterion {}: every sample {}",
                judged.clause,
                criterion.name,
                criterion.range_text()
            ),
            answer: format!(
                "{stats}; outside: {}{}",
                listed.join(", "),
                if outside.len() > listed.len() { ", ..." } else { "" }
            ),
            cause: judged.cause.to_owned(),
        },
    )
}

/// `min 0.222 / mean 0.222 / p50 0.222 / p90 0.222 / p99 0.222 / max 0.222 ms (n = 1000)`.
fn stats_text(measurement: &Measurement) -> String {
    match measurement.statistics {
        Some(s) => format!(
            "min {:.3} / mean {:.3} / p50 {:.3} / p90 {:.3} / p99 {:.3} / max {:.3} ms (n = {})",
            s.min, s.mean, s.p50, s.p90, s.p99, s.max, s.count
        ),
        None => "no samples".to_owned(),
    }
}

/// The first sample that cannot be (negative or not finite), as the reason says it; `None` when all
/// can. A time cannot run backwards: such a sample says the two stamps are not comparable, and no
/// criterion can judge it.
fn impossible(samples: &[f64], clock: Clock) -> Option<String> {
    let (i, sample) = samples
        .iter()
        .enumerate()
        .find(|(_, s)| !s.is_finite() || **s < 0.0)?;
    let what = match clock {
        Clock::Link => "a latency below 0: the answer is stamped before its request was sent",
        Clock::Bus => "a period below 0: a frame is stamped before the one received before it",
    };
    Some(format!(
        "sample #{} of {} is {sample:.3} ms, an impossible value ({what}), so the stamps cannot be compared",
        i + 1,
        samples.len()
    ))
}

/// `; stamps: virtual, 0.001 µs` (with who stamps a response time's request and answer), and a
/// warning when they are too coarse for `criterion`.
fn stamps_note(ctx: &Ctx<'_, '_>, clock: Clock, criterion: Option<&Criterion>) -> String {
    let mut note = note_on(clock.stamps(ctx), criterion);
    if clock == Clock::Link && ctx.timestamps().source != TimestampSource::Virtual {
        note.push_str(" (request and answer on the tester's clock)");
    }
    note
}

/// [`stamps_note`] for `stamps`: a resolution above a tenth of the criterion's tolerance cannot tell
/// a pass from a fail near the bound.
fn note_on(stamps: Timestamps, criterion: Option<&Criterion>) -> String {
    let resolution_ms = stamps.resolution.as_secs_f64() * 1000.0;
    let mut note = format!(
        "; stamps: {}, {} µs",
        stamps.source.as_str(),
        stamps.resolution.as_secs_f64() * 1e6
    );
    if let Some(criterion) = criterion.filter(|c| resolution_ms * 10.0 > c.tolerance_ms()) {
        note.push_str(&format!(
            "; WARNING: a resolution of {resolution_ms} ms is too coarse for {} (tolerance {:.3} ms)",
            criterion.name,
            criterion.tolerance_ms()
        ));
    }
    note
}

/// One timed exchange: the time from sending to the answer's arrival, both on the link's clock, in
/// ms, and the answer; `None` without an answer.
type Timed = Result<Option<(f64, CanFrame)>, Stop>;

/// Sends `frame` and waits up to `wait` for the first frame `answer` accepts.
fn exchange(
    ctx: &mut Ctx<'_, '_>,
    frame: Outgoing<'_>,
    wait: Duration,
    answer: impl Fn(&CanFrame) -> bool,
) -> Timed {
    let sent = ctx.now();
    match frame {
        Outgoing::Data(id, data) => ctx.send(id, data)?,
        Outgoing::Remote(id) => ctx.send_remote(id, 0)?,
        Outgoing::Nmt(command) => ctx.nmt(command, false)?,
    }
    Ok(ctx
        .wait_for(wait, answer)?
        .map(|logged| (ms_between(sent, logged.link_time), logged.frame)))
}

/// What [`exchange`] sends.
#[derive(Debug, Clone, Copy)]
enum Outgoing<'a> {
    Data(u16, &'a [u8]),
    Remote(u16),
    Nmt(NmtCommand),
}

/// `to - from` in ms, negative when `to` is earlier: never clamped, so that [`judge`] sees an
/// impossible sample as one.
fn ms_between(from: Instant, to: Instant) -> f64 {
    (i128::from(to.as_nanos()) - i128::from(from.as_nanos())) as f64 / 1e6
}

/// The frame's standard CAN-ID, or `None`.
fn standard_id(frame: &CanFrame) -> Option<u16> {
    match frame.id() {
        CanId::Standard(id) => Some(id.as_raw()),
        CanId::Extended(_) => None,
    }
}

/// A reply that is no completed transfer, as a finding that cannot measure anything.
fn unusable(what: &str, reply: &Reply) -> Finding {
    Finding::inconclusive(format!("{what} got {}: nothing to measure", reply.describe()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stamps(source: TimestampSource, micros: u64) -> Timestamps {
        Timestamps {
            source,
            resolution: Duration::from_micros(micros),
        }
    }

    #[test]
    fn stamps_too_coarse_for_a_criterion_are_warned_about() {
        let heartbeat = Criterion {
            low: Some(95.0),
            high: Some(105.0),
            name: "heartbeat.deviation_percent (documented default) ±5 % of 100 ms".to_owned(),
        };
        let fine = note_on(stamps(TimestampSource::Hub, 1), Some(&heartbeat));
        assert_eq!(fine, "; stamps: hub, 1 µs");
        // 1 ms stamps against a ±5 ms band: a tenth of the tolerance is 0.5 ms.
        let coarse = note_on(stamps(TimestampSource::Host, 1000), Some(&heartbeat));
        assert!(
            coarse.starts_with("; stamps: host, 1000 µs; WARNING: a resolution of 1 ms"),
            "{coarse}"
        );
        assert!(coarse.contains("(tolerance 5.000 ms)"), "{coarse}");
        let sdo = Criterion {
            low: None,
            high: Some(0.5),
            name: "sdo.read_max_ms from limits.toml = 0.5 ms".to_owned(),
        };
        assert!(note_on(stamps(TimestampSource::Kernel, 100), Some(&sdo)).contains("WARNING"));
        assert!(!note_on(stamps(TimestampSource::Kernel, 10), Some(&sdo)).contains("WARNING"));
        // Without a criterion there is nothing to be too coarse for.
        assert!(!note_on(stamps(TimestampSource::Host, 1000), None).contains("WARNING"));
    }

    #[test]
    fn a_negative_or_infinite_sample_is_impossible_never_clamped() {
        assert_eq!(impossible(&[0.0, 0.2, 1.5], Clock::Link), None);
        let negative = impossible(&[0.2, -0.35, 0.1], Clock::Link).expect("impossible");
        assert!(negative.starts_with("sample #2 of 3 is -0.350 ms"), "{negative}");
        assert!(negative.contains("stamped before its request"), "{negative}");
        let period = impossible(&[100.0, f64::NAN], Clock::Bus).expect("impossible");
        assert!(period.contains("sample #2 of 2 is NaN ms"), "{period}");
        assert_eq!(
            ms_between(Instant::from_micros(5), Instant::from_micros(3)),
            -0.002
        );
        // A response time is on the link's clock: the tester's (host) clock unless on virtual time.
        assert_eq!(
            link_stamps(stamps(TimestampSource::Hub, 1)).source,
            TimestampSource::Host
        );
        assert_eq!(
            link_stamps(stamps(TimestampSource::Kernel, 1)).source,
            TimestampSource::Host
        );
        assert_eq!(
            link_stamps(stamps(TimestampSource::Virtual, 0)).source,
            TimestampSource::Virtual
        );
    }

    #[test]
    fn a_criterion_admits_exactly_its_range() {
        let band = Criterion {
            low: Some(95.0),
            high: Some(105.0),
            name: String::new(),
        };
        assert!(band.admits(95.0) && band.admits(105.0) && band.admits(100.0));
        assert!(!band.admits(94.999) && !band.admits(105.001));
        assert_eq!(band.range_text(), "95.000–105.000 ms");
        let max = Criterion {
            low: None,
            high: Some(2.0),
            name: String::new(),
        };
        assert!(max.admits(0.0) && max.admits(2.0) && !max.admits(2.0001));
        assert_eq!(max.range_text(), "≤ 2.000 ms");
    }
}

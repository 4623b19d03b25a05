//! The report model every suite fills and every renderer reads: verdicts, telegrams, measurements and
//! the run around them. Its JSON form is version 1 of the documented report (`docs/conformance.md`):
//! field names are kept, fields may be added.

use std::collections::BTreeMap;

use canopener_can::{CanFrame, Instant};
use serde::Serialize;

/// The version of the JSON report this model serialises to.
pub const REPORT_VERSION: u32 = 1;

/// What a test concluded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// The device did what the specification requires.
    Pass,
    /// The device did not; the analysis says what and where.
    Fail,
    /// The test could not decide (a prerequisite got no usable answer, the run was interrupted).
    Inconclusive,
    /// The test does not apply to this device (the EDS says the feature is absent, or the device
    /// refused it in a way the specification allows).
    NotApplicable,
}

impl Verdict {
    /// `pass`, `fail`, `inconclusive` or `not_applicable`, as the JSON report writes it.
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Pass => "pass",
            Verdict::Fail => "fail",
            Verdict::Inconclusive => "inconclusive",
            Verdict::NotApplicable => "not_applicable",
        }
    }
}

/// Which way a telegram went, seen from the tester.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Direction {
    /// Sent by the tester.
    Tx,
    /// Received from the bus.
    Rx,
}

/// One frame of a test's telegram log.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Telegram {
    /// Seconds since the run started (the tester's clock for sent frames, the bus's stamps for
    /// received ones).
    pub t: f64,
    /// Sent or received.
    pub dir: Direction,
    /// The CAN-ID, `0x605` (three digits) or eight digits for an extended ID.
    pub id: String,
    /// The data bytes in hex, separated by spaces; empty for a remote frame.
    pub data: String,
    /// A remote (RTR) frame.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub remote: bool,
    /// What the frame means as CANopen (the bus monitor's decoding).
    pub meaning: String,
    /// When, on the link's clock (for the candump log).
    #[serde(skip)]
    pub at: Instant,
    /// The frame itself.
    #[serde(skip)]
    pub frame: CanFrame,
}

/// The spread of a measurement's samples.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Statistics {
    /// How many samples.
    pub count: usize,
    /// The smallest.
    pub min: f64,
    /// The arithmetic mean.
    pub mean: f64,
    /// The median (nearest rank).
    pub p50: f64,
    /// The 90th percentile (nearest rank).
    pub p90: f64,
    /// The 99th percentile (nearest rank).
    pub p99: f64,
    /// The largest.
    pub max: f64,
}

impl Statistics {
    /// The statistics of `samples`, `None` without any (or with a NaN).
    pub fn of(samples: &[f64]) -> Option<Statistics> {
        if samples.is_empty() || samples.iter().any(|s| s.is_nan()) {
            return None;
        }
        let mut sorted = samples.to_vec();
        sorted.sort_by(f64::total_cmp);
        let rank = |p: f64| {
            // Nearest rank: the smallest sample with at least p of the samples at or below it.
            let index = ((p * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len()) - 1;
            sorted.get(index).copied().unwrap_or(f64::NAN)
        };
        let (Some(&min), Some(&max)) = (sorted.first(), sorted.last()) else {
            return None;
        };
        Some(Statistics {
            count: sorted.len(),
            min,
            mean: sorted.iter().sum::<f64>() / sorted.len() as f64,
            p50: rank(0.5),
            p90: rank(0.9),
            p99: rank(0.99),
            max,
        })
    }
}

/// A measured quantity: the raw samples and their statistics.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Measurement {
    /// The unit of every sample (`ms`, `frames`, ...).
    pub unit: String,
    /// The statistics of the samples, if there are any.
    pub statistics: Option<Statistics>,
    /// Every sample, in the order measured.
    pub samples: Vec<f64>,
    /// The bounds a criterion put on each sample, when one decided the verdict; plots draw them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub limits: Option<Limits>,
}

/// The acceptable range a criterion gives a measurement's samples.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Limits {
    /// The smallest acceptable sample, if bounded below.
    pub low: Option<f64>,
    /// The largest acceptable sample, if bounded above.
    pub high: Option<f64>,
    /// Where the bounds come from, e.g. `heartbeat deviation ±5 % (thesis default)` or the criteria file.
    pub criterion: String,
}

impl Measurement {
    /// A measurement of `samples` in `unit`.
    pub fn new(unit: &str, samples: Vec<f64>) -> Measurement {
        Measurement {
            unit: unit.to_owned(),
            statistics: Statistics::of(&samples),
            samples,
            limits: None,
        }
    }

    /// The same measurement judged against `limits`.
    pub fn with_limits(mut self, limits: Limits) -> Measurement {
        self.limits = Some(limits);
        self
    }
}

/// The result of one test.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TestReport {
    /// The stable id, e.g. `cia301.sdo.12`.
    pub id: String,
    /// The suite it belongs to (`cia301`, `eds`).
    pub suite: String,
    /// The group within the suite (`sdo`, `pdo`, ...), as the human summary counts them.
    pub group: String,
    /// What the test checks.
    pub title: String,
    /// The CiA clauses it implements and the CCT cases it covers.
    pub references: Vec<String>,
    /// The verdict.
    pub verdict: Verdict,
    /// One line: why this verdict.
    pub reason: String,
    /// For a failure: the request, what CiA 301 requires (with the clause), what came back, and
    /// the likely cause; empty otherwise.
    pub analysis: String,
    /// What the test measured.
    pub measurements: BTreeMap<String, Measurement>,
    /// How long the test ran, in seconds on the link's clock.
    pub duration_s: f64,
    /// The CCT cases (`SDO 19`, `PDO 27`) whose check this run actually performed, in the order
    /// performed: a case is listed only when the step that checks it ran and was judged, not
    /// because the test references it (a test that ends early, or does not apply, performed
    /// less). Added to version 1 of the report; empty for tests outside the CCT.
    pub performed: Vec<String>,
    /// Every frame sent and received while the test ran, decoded.
    pub telegrams: Vec<Telegram>,
    /// A `pass` whose measurement no criterion judged ("measured, no criterion"): not a conformance
    /// pass, counted apart in [`VerdictCounts::measured_no_criterion`].
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub no_criterion: bool,
}

impl TestReport {
    /// Whether this is a `pass` no criterion judged.
    pub fn measured_no_criterion(&self) -> bool {
        self.verdict == Verdict::Pass && self.no_criterion
    }
}

/// The device under test.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct DeviceInfo {
    /// Its node-ID; `None` when only the EDS was tested.
    pub node: Option<u8>,
    /// The EDS the tests were derived from, as given.
    pub eds: String,
    /// The identity object 1018h as read, when it could be read.
    pub identity: Option<Identity>,
}

/// The identity object 1018h.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Identity {
    /// 1018h:01.
    pub vendor_id: Option<u32>,
    /// 1018h:02.
    pub product_code: Option<u32>,
    /// 1018h:03.
    pub revision: Option<u32>,
    /// 1018h:04.
    pub serial: Option<u32>,
}

/// The bus the tests ran on.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BusInfo {
    /// The bus as the user named it, or the simulated bus.
    pub spec: String,
    /// Who stamps received frames: `kernel`, `hub`, `virtual` or `host`.
    pub timestamps: String,
    /// The resolution of those stamps in microseconds.
    pub resolution_us: f64,
}

/// How many tests ended with each verdict.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct VerdictCounts {
    /// Passed.
    pub pass: usize,
    /// Failed.
    pub fail: usize,
    /// Could not decide.
    pub inconclusive: usize,
    /// Not applicable.
    pub not_applicable: usize,
    /// Of the passes, those whose measurement no criterion judged: measured, not conformance
    /// passes.
    pub measured_no_criterion: usize,
}

impl VerdictCounts {
    /// The counts of `tests`.
    pub fn of<'a>(tests: impl IntoIterator<Item = &'a TestReport>) -> VerdictCounts {
        tests.into_iter().fold(VerdictCounts::default(), |mut s, t| {
            s.measured_no_criterion += usize::from(t.measured_no_criterion());
            match t.verdict {
                Verdict::Pass => s.pass += 1,
                Verdict::Fail => s.fail += 1,
                Verdict::Inconclusive => s.inconclusive += 1,
                Verdict::NotApplicable => s.not_applicable += 1,
            }
            s
        })
    }

    /// Whether every applicable test passed (nothing failed, nothing undecided).
    pub fn all_passed(&self) -> bool {
        self.fail == 0 && self.inconclusive == 0
    }

    /// The passes a criterion or a CiA requirement decided: [`VerdictCounts::pass`] without the
    /// measurements no criterion judged.
    pub fn conformance_passes(&self) -> usize {
        self.pass - self.measured_no_criterion
    }
}

/// A whole run: the device, the bus, every test and the summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Report {
    /// [`REPORT_VERSION`].
    pub version: u32,
    /// The device under test.
    pub device: DeviceInfo,
    /// The bus.
    pub bus: BusInfo,
    /// When the run started (RFC 3339, UTC); the only field that differs between two runs on
    /// virtual time.
    pub started: String,
    /// How long the run took, in seconds on the link's clock (virtual seconds on a simulated bus).
    pub duration_s: f64,
    /// Whether the run was interrupted (Ctrl-C); the tests not run are missing.
    pub interrupted: bool,
    /// What the preparation did before the first test (reset, restore of defaults).
    pub preparation: Vec<String>,
    /// Values the run changed and could not write back (after an interruption or a device that
    /// stopped answering), so the user knows what the device holds now.
    pub left_modified: Vec<String>,
    /// Every test run, in catalogue order.
    pub tests: Vec<TestReport>,
    /// The counts.
    pub summary: VerdictCounts,
}

impl Report {
    /// The report as pretty-printed JSON (version 1), ending with a newline.
    pub fn to_json(&self) -> String {
        // Serialising plain data with string keys cannot fail.
        let mut text = serde_json::to_string_pretty(self).unwrap_or_default();
        text.push('\n');
        text
    }
}

/// `2024-01-01T00:00:00Z`: `time` in RFC 3339, UTC, whole seconds (for [`Report::started`]).
pub fn rfc3339_utc(time: std::time::SystemTime) -> String {
    let secs = time
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let (year, month, day) = canopener_wire::civil_from_days((secs / 86_400) as i64);
    let of_day = secs % 86_400;
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z",
        of_day / 3600,
        of_day % 3600 / 60,
        of_day % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statistics_use_nearest_ranks() {
        let samples: Vec<f64> = (1..=100).map(f64::from).collect();
        let stats = Statistics::of(&samples).unwrap();
        assert_eq!(
            (stats.min, stats.p50, stats.p90, stats.p99, stats.max),
            (1.0, 50.0, 90.0, 99.0, 100.0)
        );
        assert_eq!(stats.mean, 50.5);
        assert_eq!(Statistics::of(&[7.0]).unwrap().p99, 7.0);
        assert!(Statistics::of(&[]).is_none());
        assert!(Statistics::of(&[1.0, f64::NAN]).is_none());
    }

    proptest::proptest! {
        #[test]
        fn statistics_are_ordered_and_bounded(samples in proptest::collection::vec(-1e6f64..1e6, 1..200)) {
            let stats = Statistics::of(&samples).unwrap();
            proptest::prop_assert_eq!(stats.count, samples.len());
            proptest::prop_assert!(stats.min <= stats.p50 && stats.p50 <= stats.p90);
            proptest::prop_assert!(stats.p90 <= stats.p99 && stats.p99 <= stats.max);
            proptest::prop_assert!(stats.min <= stats.mean + 1e-6 && stats.mean <= stats.max + 1e-6);
            proptest::prop_assert!(samples.contains(&stats.p50) && samples.contains(&stats.p99));
        }
    }

    #[test]
    fn start_times_read_as_rfc_3339() {
        let time = std::time::UNIX_EPOCH + std::time::Duration::from_secs(1_704_067_200 + 3_723);
        assert_eq!(rfc3339_utc(time), "2024-01-01T01:02:03Z");
        assert_eq!(rfc3339_utc(std::time::UNIX_EPOCH), "1970-01-01T00:00:00Z");
    }

    #[test]
    fn verdicts_serialise_as_the_report_names_them() {
        for verdict in [
            Verdict::Pass,
            Verdict::Fail,
            Verdict::Inconclusive,
            Verdict::NotApplicable,
        ] {
            assert_eq!(serde_json::to_value(verdict).unwrap(), verdict.as_str());
        }
    }
}

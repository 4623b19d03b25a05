//! Run against run ("what changed since the last firmware"): the tests whose verdict changed, the
//! tests only one run has, and the measurements that moved, from the two reports' JSON (version 1).
//!
//! A measurement *moved* when its median changed by more than [`MOVED_FRACTION`] of the earlier
//! median (or, with an earlier median of 0, by more than [`MOVED_FLOOR`] in its unit), or when the
//! criterion's limits judged it differently (a sample outside in one run only).

use std::collections::BTreeMap;

use canopener_conformance::model::{Limits, Measurement};
use serde_json::Value;

/// The relative change of the median that counts as moved.
pub const MOVED_FRACTION: f64 = 0.05;
/// The absolute change that counts as moved when the earlier median is 0.
pub const MOVED_FLOOR: f64 = 0.001;

/// One test's verdict in both runs.
#[derive(Debug, Clone, PartialEq)]
pub struct VerdictChange {
    /// The test id.
    pub id: String,
    /// Its title.
    pub title: String,
    /// The earlier verdict (`None`: not run then).
    pub before: Option<String>,
    /// The later verdict (`None`: not run now).
    pub after: Option<String>,
    /// The later run's reason (else the earlier's).
    pub reason: String,
}

/// A measurement that moved.
#[derive(Debug, Clone, PartialEq)]
pub struct Moved {
    /// The test that measured it.
    pub test: String,
    /// Its name.
    pub name: String,
    /// In the earlier run.
    pub before: Measurement,
    /// In the later run.
    pub after: Measurement,
}

impl Moved {
    /// The medians, earlier and later.
    pub fn medians(&self) -> (Option<f64>, Option<f64>) {
        (
            self.before.statistics.map(|s| s.p50),
            self.after.statistics.map(|s| s.p50),
        )
    }
}

/// What changed between two runs.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Comparison {
    /// Tests whose verdict differs, or that only one run has, in the later run's order.
    pub verdicts: Vec<VerdictChange>,
    /// Measurements that moved.
    pub moved: Vec<Moved>,
    /// Tests in both runs with the same verdict.
    pub unchanged: usize,
}

/// Compares report `before` with report `after` (each the JSON of a report).
pub fn compare(before: &Value, after: &Value) -> Comparison {
    let tests = |report: &Value| -> Vec<Value> { report["tests"].as_array().cloned().unwrap_or_default() };
    let (old, new) = (tests(before), tests(after));
    let old_by_id: BTreeMap<&str, &Value> = old.iter().filter_map(|t| Some((t["id"].as_str()?, t))).collect();
    let new_ids: std::collections::BTreeSet<&str> = new.iter().filter_map(|t| t["id"].as_str()).collect();
    let mut comparison = Comparison::default();
    let text = |v: &Value| v.as_str().unwrap_or_default().to_owned();
    for test in &new {
        let id = test["id"].as_str().unwrap_or_default();
        let earlier = old_by_id.get(id);
        let verdict_before = earlier.map(|t| text(&t["verdict"]));
        let verdict_after = text(&test["verdict"]);
        if verdict_before.as_deref() == Some(verdict_after.as_str()) {
            comparison.unchanged += 1;
        } else {
            comparison.verdicts.push(VerdictChange {
                id: id.to_owned(),
                title: text(&test["title"]),
                before: verdict_before,
                after: Some(verdict_after),
                reason: text(&test["reason"]),
            });
        }
        let Some(earlier) = earlier else { continue };
        let measurements = |t: &Value| -> BTreeMap<String, Measurement> {
            t["measurements"]
                .as_object()
                .map(|m| {
                    m.iter()
                        .filter_map(|(k, v)| Some((k.clone(), measurement(v)?)))
                        .collect()
                })
                .unwrap_or_default()
        };
        let (was, now) = (measurements(earlier), measurements(test));
        for (name, after) in now {
            if let Some(before) = was.get(&name)
                && moved(before, &after)
            {
                comparison.moved.push(Moved {
                    test: id.to_owned(),
                    name,
                    before: before.clone(),
                    after,
                });
            }
        }
    }
    for test in &old {
        let id = test["id"].as_str().unwrap_or_default();
        if !new_ids.contains(id) {
            comparison.verdicts.push(VerdictChange {
                id: id.to_owned(),
                title: text(&test["title"]),
                before: Some(text(&test["verdict"])),
                after: None,
                reason: text(&test["reason"]),
            });
        }
    }
    comparison
}

/// A measurement from its JSON (samples that were not finite are written as `null`).
fn measurement(value: &Value) -> Option<Measurement> {
    let unit = value["unit"].as_str()?;
    let samples = value["samples"]
        .as_array()?
        .iter()
        .map(|s| s.as_f64().unwrap_or(f64::NAN))
        .collect();
    let mut m = Measurement::new(unit, samples);
    if let Some(limits) = value.get("limits").filter(|l| l.is_object()) {
        m = m.with_limits(Limits {
            low: limits["low"].as_f64(),
            high: limits["high"].as_f64(),
            criterion: limits["criterion"].as_str().unwrap_or_default().to_owned(),
        });
    }
    Some(m)
}

fn outside(m: &Measurement) -> usize {
    let Some(limits) = &m.limits else { return 0 };
    m.samples
        .iter()
        .filter(|s| limits.low.is_some_and(|low| **s < low) || limits.high.is_some_and(|high| **s > high))
        .count()
}

fn moved(before: &Measurement, after: &Measurement) -> bool {
    if (outside(before) == 0) != (outside(after) == 0) {
        return true;
    }
    match (before.statistics, after.statistics) {
        (Some(a), Some(b)) => {
            let change = (b.p50 - a.p50).abs();
            if a.p50 == 0.0 {
                change > MOVED_FLOOR
            } else {
                change > MOVED_FRACTION * a.p50.abs()
            }
        }
        (None, None) => false,
        _ => true,
    }
}

#[cfg(test)]
mod tests {
    use serde_json::json;

    use super::*;

    fn report(tests: Value) -> Value {
        json!({ "version": 1, "tests": tests })
    }

    #[test]
    fn changed_verdicts_new_and_dropped_tests_are_listed_unchanged_counted() {
        let before = report(json!([
            {"id": "a", "title": "A", "verdict": "pass", "reason": "ok", "measurements": {}},
            {"id": "b", "title": "B", "verdict": "pass", "reason": "ok", "measurements": {}},
            {"id": "gone", "title": "G", "verdict": "fail", "reason": "x", "measurements": {}},
        ]));
        let after = report(json!([
            {"id": "a", "title": "A", "verdict": "pass", "reason": "ok", "measurements": {}},
            {"id": "b", "title": "B", "verdict": "fail", "reason": "late", "measurements": {}},
            {"id": "new", "title": "N", "verdict": "pass", "reason": "ok", "measurements": {}},
        ]));
        let c = compare(&before, &after);
        assert_eq!(c.unchanged, 1);
        let rows: Vec<(&str, Option<&str>, Option<&str>)> = c
            .verdicts
            .iter()
            .map(|v| (v.id.as_str(), v.before.as_deref(), v.after.as_deref()))
            .collect();
        assert_eq!(
            rows,
            [
                ("b", Some("pass"), Some("fail")),
                ("new", None, Some("pass")),
                ("gone", Some("fail"), None)
            ]
        );
        assert_eq!(c.verdicts[0].reason, "late");
    }

    #[test]
    fn a_measurement_moves_when_its_median_shifts_or_its_limits_judge_it_otherwise() {
        let m = |samples: Value, limits: Value| json!({"unit": "ms", "samples": samples, "limits": limits});
        let test = |m: Value| {
            report(
                json!([{"id": "t", "title": "T", "verdict": "pass", "reason": "", "measurements": {"x": m}}]),
            )
        };
        let steady = test(m(json!([100.0, 100.0, 101.0]), Value::Null));
        let slower = test(m(json!([110.0, 110.0, 111.0]), Value::Null));
        let within = test(m(json!([100.0, 102.0, 101.0]), Value::Null));
        assert_eq!(compare(&steady, &slower).moved.len(), 1);
        assert!(compare(&steady, &within).moved.is_empty(), "2 % is not a move");
        let limits = json!({"low": 95.0, "high": 105.0, "criterion": "±5 %"});
        let inside = test(m(json!([100.0, 100.0, 100.0, 100.0]), limits.clone()));
        let one_out = test(m(json!([100.0, 100.0, 100.0, 140.0]), limits));
        let moved = compare(&inside, &one_out).moved;
        assert_eq!(moved.len(), 1, "same median, but a sample beyond the limit");
        assert_eq!(moved[0].after.limits.as_ref().unwrap().high, Some(105.0));
        assert_eq!(moved[0].medians(), (Some(100.0), Some(100.0)));
        let nulls = test(m(json!([null, 1.0]), Value::Null));
        assert!(compare(&nulls, &nulls).moved.is_empty());
    }
}

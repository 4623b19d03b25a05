//! Periods measured between frames on the bus.

use crate::context::Ctx;
use crate::model::Measurement;
use crate::recorder::Logged;

/// The intervals between consecutive `frames` in ms (the bus's stamps), recorded as the measurement
/// `name` with their statistics.
pub fn measure_intervals(ctx: &mut Ctx<'_, '_>, name: &str, frames: &[Logged]) -> Vec<f64> {
    let intervals: Vec<f64> = frames
        .iter()
        .zip(frames.iter().skip(1))
        .map(|(before, after)| after.at.saturating_duration_since(before.at).as_secs_f64() * 1000.0)
        .collect();
    ctx.measure(name, Measurement::new("ms", intervals.clone()));
    intervals
}

/// `96.0, 104.0, 100.0`: intervals as an analysis lists them.
pub fn intervals_text(intervals: &[f64]) -> String {
    intervals
        .iter()
        .map(|i| format!("{i:.1}"))
        .collect::<Vec<_>>()
        .join(", ")
}

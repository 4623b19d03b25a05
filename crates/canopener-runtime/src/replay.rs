//! Replaying recorded frames onto a bus: with their recorded gaps (optionally faster or slower) or back to
//! back, once or in loops, stoppable between any two frames.

use std::time::{Duration, Instant};

use canopener_can::CanFrame;
use canopener_can::candump::{LogEvent, LogRecord};
use canopener_transport::{CanBus, TransportError};

use crate::pacing::{offset_from, sleep_until};
use canopener_link::cancel::Cancel;

/// A frame with the time it was recorded.
pub type TimedFrame = (canopener_can::Instant, CanFrame);

/// How frames are spaced when replayed: their recorded gaps scaled by a speed factor, or none at all.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pace {
    /// `None`: back to back. Private, so that every factor went through [`Pace::recorded`]'s check.
    speed: Option<f64>,
}

/// A speed factor that is not a number above zero.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("replay speed {0} is not a number above 0 (2 = twice as fast)")]
pub struct BadSpeed(pub f64);

impl Pace {
    /// Each frame as soon as the bus takes the previous one.
    pub const BACK_TO_BACK: Pace = Pace { speed: None };

    /// The recorded gaps divided by `speed` (2.0 = twice as fast), which must be finite and above zero.
    pub fn recorded(speed: f64) -> Result<Pace, BadSpeed> {
        if speed.is_finite() && speed > 0.0 {
            Ok(Pace { speed: Some(speed) })
        } else {
            Err(BadSpeed(speed))
        }
    }

    /// The speed factor, `None` for back to back.
    pub fn speed(&self) -> Option<f64> {
        self.speed
    }
}

/// How a replay went.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReplaySummary {
    /// Frames sent, over all loops, before the end or a cancel.
    pub sent: u64,
    /// How long it took.
    pub elapsed: Duration,
}

/// The frames of `records` (only those recorded on `interface`, if given) and how many error frames were
/// left out, since a controller cannot send them.
pub fn frames_of(records: Vec<(usize, LogRecord)>, interface: Option<&str>) -> (Vec<TimedFrame>, usize) {
    let mut frames = Vec::with_capacity(records.len());
    let mut error_frames = 0;
    for (_, record) in records {
        if interface.is_some_and(|wanted| wanted != record.interface) {
            continue;
        }
        match record.event {
            LogEvent::Frame(frame) => frames.push((record.timestamp, frame)),
            LogEvent::ErrorFrame { .. } => error_frames += 1,
        }
    }
    (frames, error_frames)
}

/// Sends `frames` onto `bus` `loops` times, spaced by `pace`; `on_sent` gets the running total after every
/// frame. Each loop keeps its own schedule, absolute from the loop's start, so a late wake-up is caught up
/// rather than accumulated. A cancel stops between two frames.
pub fn replay(
    bus: &mut dyn CanBus,
    frames: &[TimedFrame],
    pace: Pace,
    loops: u64,
    cancel: &Cancel,
    mut on_sent: impl FnMut(u64),
) -> Result<ReplaySummary, TransportError> {
    let started = Instant::now();
    let mut sent = 0;
    for _ in 0..loops {
        if cancel.is_cancelled() || !play_once(bus, frames, pace, cancel, &mut sent, &mut on_sent)? {
            break;
        }
    }
    Ok(ReplaySummary {
        sent,
        elapsed: started.elapsed(),
    })
}

/// One pass over `frames`; returns `false` when cancelled.
fn play_once(
    bus: &mut dyn CanBus,
    frames: &[TimedFrame],
    pace: Pace,
    cancel: &Cancel,
    sent: &mut u64,
    on_sent: &mut impl FnMut(u64),
) -> Result<bool, TransportError> {
    let Some((first, _)) = frames.first() else {
        return Ok(true);
    };
    let start = Instant::now();
    for (timestamp, frame) in frames {
        if cancel.is_cancelled() {
            return Ok(false);
        }
        if let Some(speed) = pace.speed {
            let offset = timestamp.saturating_duration_since(*first).as_secs_f64() / speed;
            if !sleep_until(offset_from(start, offset), cancel) {
                return Ok(false);
            }
        }
        bus.send(frame)?;
        *sent += 1;
        on_sent(*sent);
    }
    Ok(true)
}

#[cfg(test)]
mod tests {
    use canopener_can::candump::parse_log;

    use super::*;
    use crate::test_support::virtual_pair;

    fn frames(log: &str) -> Vec<TimedFrame> {
        let (records, errors) = parse_log(log);
        assert!(errors.is_empty());
        frames_of(records, None).0
    }

    fn drain(bus: &mut dyn CanBus) -> Vec<String> {
        let mut seen = Vec::new();
        while let Some(received) = bus.recv(Duration::ZERO).unwrap() {
            seen.push(received.frame.to_string());
        }
        seen
    }

    #[test]
    fn frames_of_filters_by_interface_and_drops_error_frames() {
        let (records, errors) = parse_log(
            "(1.000000) can0 123#01\n(1.001000) can1 456#02\n(1.002000) can0 20000080#0000000000000000\n",
        );
        assert!(errors.is_empty(), "{errors:?}");
        let (all, error_frames) = frames_of(records.clone(), None);
        assert_eq!(all.len(), 2);
        assert_eq!(error_frames, 1);
        let (can1, error_frames) = frames_of(records, Some("can1"));
        assert_eq!(can1.len(), 1);
        assert_eq!(can1[0].1.to_string(), "456#02");
        assert_eq!(error_frames, 0);
    }

    #[test]
    fn back_to_back_loops_send_every_frame_in_order() {
        let (mut source, mut sink) = virtual_pair("replay-loops");
        let frames = frames("(10.000000) can0 080#\n(99.000000) can0 701#05\n");
        let mut reported = Vec::new();
        let summary = replay(
            &mut *source,
            &frames,
            Pace::BACK_TO_BACK,
            2,
            &Cancel::new(),
            |n| reported.push(n),
        )
        .unwrap();
        assert_eq!(summary.sent, 4);
        assert_eq!(reported, [1, 2, 3, 4]);
        assert!(
            summary.elapsed < Duration::from_secs(10),
            "recorded gaps were ignored"
        );
        assert_eq!(drain(&mut *sink), ["080#", "701#05", "080#", "701#05"]);
    }

    #[test]
    fn recorded_gaps_are_kept_and_scaled_by_speed() {
        let (mut source, mut sink) = virtual_pair("replay-timing");
        let frames = frames("(5.000000) can0 080#\n(5.200000) can0 081#\n(5.400000) can0 082#\n");
        let pace = Pace::recorded(2.0).unwrap();
        let summary = replay(&mut *source, &frames, pace, 1, &Cancel::new(), |_| {}).unwrap();
        assert_eq!(summary.sent, 3);
        // 400 ms recorded at twice the speed: 200 ms, give or take the scheduler.
        assert!(summary.elapsed >= Duration::from_millis(200), "{summary:?}");
        assert!(summary.elapsed < Duration::from_millis(1500), "{summary:?}");
        assert_eq!(drain(&mut *sink), ["080#", "081#", "082#"]);
    }

    #[test]
    fn a_cancel_stops_inside_a_long_recorded_gap() {
        let (mut source, mut sink) = virtual_pair("replay-cancel");
        let frames = frames("(1.000000) can0 080#\n(3601.000000) can0 081#\n");
        let cancel = Cancel::new();
        let summary = replay(
            &mut *source,
            &frames,
            Pace::recorded(1.0).unwrap(),
            3,
            &cancel,
            |_| cancel.cancel(),
        )
        .unwrap();
        assert_eq!(summary.sent, 1);
        assert_eq!(drain(&mut *sink), ["080#"]);
    }

    #[test]
    fn speeds_must_be_above_zero() {
        assert_eq!(Pace::recorded(0.5).unwrap().speed(), Some(0.5));
        assert_eq!(Pace::BACK_TO_BACK.speed(), None);
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(Pace::recorded(bad).is_err(), "{bad}");
        }
        assert!(BadSpeed(0.0).to_string().contains("above 0"));
    }

    #[test]
    fn nothing_to_replay_sends_nothing() {
        let (mut source, _sink) = virtual_pair("replay-empty");
        let summary = replay(
            &mut *source,
            &[],
            Pace::recorded(1.0).unwrap(),
            5,
            &Cancel::new(),
            |_| {},
        )
        .unwrap();
        assert_eq!(summary.sent, 0);
    }
}

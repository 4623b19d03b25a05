//! Generating bus load like can-utils' cangen: counting frames of one id, at a fixed rate or as fast as
//! the bus takes them, until a count, a duration or a cancel ends it.

use std::time::{Duration, Instant};

use canopener_can::{CanFrame, CanId};
use canopener_transport::{CanBus, TransportError};

use crate::pacing::{offset_from, sleep_until};
use canopener_link::cancel::Cancel;

/// What to generate and when to stop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Generator {
    /// The id of every frame.
    pub id: CanId,
    /// The data length of every frame, 0 to 8; bytes 0-7 carry the frame's number, little-endian.
    pub dlc: u8,
    /// Frames per second; 0 sends as fast as the bus accepts them.
    pub rate: f64,
    /// Stop after this many frames.
    pub count: Option<u64>,
    /// Stop after this long.
    pub duration: Option<Duration>,
}

/// Why a generator did not run or stopped early.
#[derive(Debug, thiserror::Error)]
pub enum GenerateError {
    /// The data length is above the classical CAN maximum.
    #[error("data length {0} is above 8, the classical CAN maximum")]
    DlcTooLarge(u8),
    /// The rate is negative, not a number, or too small to schedule.
    #[error("rate {0} is not a usable number of frames per second")]
    BadRate(f64),
    /// Neither a count nor a duration was given, so the generator would never stop by itself.
    #[error("a generator needs a count or a duration to know when to stop")]
    Endless,
    /// The bus failed.
    #[error(transparent)]
    Bus(#[from] TransportError),
}

/// How a generator run went.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GenerateSummary {
    /// Frames sent.
    pub sent: u64,
    /// How long it ran.
    pub elapsed: Duration,
}

impl GenerateSummary {
    /// The average rate achieved, in frames per second (0 when no time passed).
    pub fn frames_per_second(&self) -> f64 {
        let seconds = self.elapsed.as_secs_f64();
        if seconds > 0.0 {
            self.sent as f64 / seconds
        } else {
            0.0
        }
    }
}

impl Generator {
    /// Refuses settings that cannot run: a DLC above 8, a rate that is negative, not a number or too
    /// small to schedule, or no end.
    pub fn validate(&self) -> Result<(), GenerateError> {
        if self.dlc > 8 {
            return Err(GenerateError::DlcTooLarge(self.dlc));
        }
        if self.interval().is_err() {
            return Err(GenerateError::BadRate(self.rate));
        }
        if self.count.is_none() && self.duration.is_none() {
            return Err(GenerateError::Endless);
        }
        Ok(())
    }

    /// Frame number `n`: the configured id, its DLC, and `n` little-endian in the data.
    pub fn frame(&self, n: u64) -> Result<CanFrame, GenerateError> {
        let len = usize::from(self.dlc);
        let data = n.to_le_bytes();
        let data = data.get(..len).ok_or(GenerateError::DlcTooLarge(self.dlc))?;
        CanFrame::new(self.id, data).map_err(|_| GenerateError::DlcTooLarge(self.dlc))
    }

    /// The time between two frames, `None` when unpaced.
    fn interval(&self) -> Result<Option<Duration>, ()> {
        if !self.rate.is_finite() || self.rate < 0.0 {
            return Err(());
        }
        if self.rate == 0.0 {
            return Ok(None);
        }
        Duration::try_from_secs_f64(1.0 / self.rate)
            .map(Some)
            .map_err(|_| ())
    }
}

/// Sends `generator`'s frames onto `bus` until its count or duration is reached or `cancel` is set.
/// A paced schedule is absolute (start + n × interval): a late wake-up is caught up instead of lowering
/// the average rate.
pub fn generate(
    bus: &mut dyn CanBus,
    generator: &Generator,
    cancel: &Cancel,
) -> Result<GenerateSummary, GenerateError> {
    generator.validate()?;
    let interval = generator
        .interval()
        .map_err(|()| GenerateError::BadRate(generator.rate))?;
    let started = Instant::now();
    let end = generator
        .duration
        .map(|duration| offset_from(started, duration.as_secs_f64()));
    let mut sent: u64 = 0;
    while !cancel.is_cancelled() {
        if generator.count.is_some_and(|count| sent >= count)
            || generator
                .duration
                .is_some_and(|duration| started.elapsed() >= duration)
        {
            break;
        }
        if let Some(interval) = interval {
            let due = offset_from(started, interval.as_secs_f64() * sent as f64);
            // Never sleep past the end: a slow rate must not outlive its duration.
            let wake = match (due, end) {
                (Some(due), Some(Some(end))) => Some(due.min(end)),
                (None, Some(end)) => end,
                (due, _) => due,
            };
            if !sleep_until(wake, cancel) || due.is_none_or(|due| Instant::now() < due) {
                continue;
            }
        }
        bus.send(&generator.frame(sent)?)?;
        sent += 1;
    }
    Ok(GenerateSummary {
        sent,
        elapsed: started.elapsed(),
    })
}

#[cfg(test)]
mod tests {

    use super::*;
    use crate::test_support::virtual_pair;

    fn generator(rate: f64, count: Option<u64>, duration: Option<Duration>) -> Generator {
        Generator {
            id: CanId::standard(0x123).unwrap(),
            dlc: 8,
            rate,
            count,
            duration,
        }
    }

    #[test]
    fn unpaced_frames_count_up_in_their_data() {
        let (mut sender, mut receiver) = virtual_pair("gen-count");
        let summary = generate(&mut *sender, &generator(0.0, Some(3), None), &Cancel::new()).unwrap();
        assert_eq!(summary.sent, 3);
        let mut seen = Vec::new();
        while let Some(received) = receiver.recv(Duration::ZERO).unwrap() {
            seen.push(received.frame.to_string());
        }
        assert_eq!(
            seen,
            [
                "123#0000000000000000",
                "123#0100000000000000",
                "123#0200000000000000"
            ]
        );
    }

    #[test]
    fn a_paced_generator_keeps_its_rate() {
        let (mut sender, _receiver) = virtual_pair("gen-rate");
        // 11 frames at 100/s: the last is due 100 ms after the first.
        let summary = generate(&mut *sender, &generator(100.0, Some(11), None), &Cancel::new()).unwrap();
        assert_eq!(summary.sent, 11);
        assert!(summary.elapsed >= Duration::from_millis(100), "{summary:?}");
        assert!(summary.elapsed < Duration::from_secs(2), "{summary:?}");
        assert!(summary.frames_per_second() > 0.0);
    }

    #[test]
    fn a_slow_rate_still_ends_with_its_duration() {
        let (mut sender, _receiver) = virtual_pair("gen-slow");
        let slow = generator(0.001, None, Some(Duration::from_millis(100)));
        let summary = generate(&mut *sender, &slow, &Cancel::new()).unwrap();
        assert_eq!(
            summary.sent, 1,
            "the first frame is due at once, the second in 1000 s"
        );
        assert!(summary.elapsed < Duration::from_secs(2), "{summary:?}");
    }

    #[test]
    fn a_cancel_stops_the_generator() {
        let (mut sender, _receiver) = virtual_pair("gen-cancel");
        let cancel = Cancel::new();
        cancel.cancel();
        let summary = generate(
            &mut *sender,
            &generator(0.0, None, Some(Duration::from_secs(3600))),
            &cancel,
        )
        .unwrap();
        assert_eq!(summary.sent, 0);
    }

    #[test]
    fn settings_that_cannot_run_are_refused() {
        let refused = |generator: Generator| generator.validate().unwrap_err();
        let mut long = generator(0.0, Some(1), None);
        long.dlc = 9;
        assert!(matches!(refused(long), GenerateError::DlcTooLarge(9)));
        for rate in [-1.0, f64::NAN, f64::INFINITY, 1e-320] {
            assert!(
                matches!(refused(generator(rate, Some(1), None)), GenerateError::BadRate(_)),
                "{rate}"
            );
        }
        assert!(matches!(
            refused(generator(0.0, None, None)),
            GenerateError::Endless
        ));
        let (mut sender, _receiver) = virtual_pair("gen-refused");
        assert!(generate(&mut *sender, &generator(0.0, None, None), &Cancel::new()).is_err());
    }

    #[test]
    fn short_frames_carry_the_low_bytes_of_the_count() {
        let mut short = generator(0.0, Some(1), None);
        short.dlc = 2;
        assert_eq!(short.frame(0x0102_0304).unwrap().to_string(), "123#0403");
        short.dlc = 0;
        assert_eq!(short.frame(7).unwrap().to_string(), "123#");
    }
}

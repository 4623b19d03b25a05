//! CAN bit rates and the exact bus time of bits and frames.
//!
//! Durations are computed as `bits · 10⁹ / bitrate` nanoseconds in one division, rounded to the
//! nearest nanosecond, never as `bits · bit_time()`: at a bit rate that does not divide 10⁹ the
//! per-bit time is not a whole number of nanoseconds, and multiplying a rounded bit time would turn a
//! sub-nanosecond error into one that grows with the frame (or, summed by a simulator, with the run).

use std::fmt;
use std::str::FromStr;
use std::time::Duration;

use thiserror::Error;

use crate::bits::frame_bits;
use crate::frame::CanFrame;

/// A classical CAN bit rate in bits per second: above zero and at most 1 Mbit/s (ISO 11898-1 limits
/// classical CAN to 1 Mbit/s).
///
/// `Display` and `FromStr` use the short form engineers type: `125k`, `1M`, or plain digits for rates
/// that are not a whole number of kbit/s.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Bitrate(u32);

/// Why a bit rate was rejected.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum BitrateError {
    /// The text was empty.
    #[error("bitrate is empty; write bits per second such as 125k, 500k, 1M or 250000")]
    Empty,
    /// The text is not digits with an optional `k` or `M` suffix.
    #[error(
        "bitrate `{0}` is not a number of bits per second; write digits with an optional k or M suffix, \
         such as 125k, 500k, 1M or 250000"
    )]
    Malformed(String),
    /// The rate is zero.
    #[error("bitrate `{0}` is zero; a CAN bus needs a positive bitrate such as 125k or 1M")]
    Zero(String),
    /// The rate is above the classical CAN maximum.
    #[error("bitrate `{0}` is above 1 Mbit/s, the classical CAN maximum; use at most 1M")]
    TooHigh(String),
}

impl Bitrate {
    /// 10 kbit/s, the slowest rate of the CiA bit timing table (CiA 301, CiA 305 LSS table index 8).
    pub const K10: Bitrate = Bitrate(10_000);
    /// 20 kbit/s (CiA bit timing table index 7).
    pub const K20: Bitrate = Bitrate(20_000);
    /// 50 kbit/s (CiA bit timing table index 6).
    pub const K50: Bitrate = Bitrate(50_000);
    /// 100 kbit/s: index 5 of the CiA table, now reserved but still found on older devices.
    pub const K100: Bitrate = Bitrate(100_000);
    /// 125 kbit/s (CiA bit timing table index 4).
    pub const K125: Bitrate = Bitrate(125_000);
    /// 250 kbit/s (CiA bit timing table index 3).
    pub const K250: Bitrate = Bitrate(250_000);
    /// 500 kbit/s (CiA bit timing table index 2).
    pub const K500: Bitrate = Bitrate(500_000);
    /// 800 kbit/s (CiA bit timing table index 1).
    pub const K800: Bitrate = Bitrate(800_000);
    /// 1 Mbit/s, the classical CAN maximum (CiA bit timing table index 0).
    pub const M1: Bitrate = Bitrate(1_000_000);

    /// A bit rate of `bits_per_second`, which must be in 1..=1 000 000.
    pub fn new(bits_per_second: u32) -> Result<Bitrate, BitrateError> {
        match bits_per_second {
            0 => Err(BitrateError::Zero(bits_per_second.to_string())),
            1..=1_000_000 => Ok(Bitrate(bits_per_second)),
            _ => Err(BitrateError::TooHigh(bits_per_second.to_string())),
        }
    }

    /// Bits per second.
    pub const fn bits_per_second(self) -> u32 {
        self.0
    }

    /// The duration of one bit, rounded to the nearest nanosecond (exact for every rate that divides
    /// 10⁹, which includes all rates of the CiA table). Use [`Bitrate::bits_duration`] for more than
    /// one bit so the rounding happens once.
    pub fn bit_time(self) -> Duration {
        self.bits_duration(1)
    }

    /// The duration of `bits` bits: `bits · 10⁹ / bitrate` nanoseconds, rounded once to the nearest
    /// nanosecond (halves round up), saturating at `u64::MAX` nanoseconds.
    pub fn bits_duration(self, bits: u64) -> Duration {
        Duration::from_nanos(self.bits_nanos(bits))
    }

    /// [`Bitrate::bits_duration`] as a plain number of nanoseconds.
    pub fn bits_nanos(self, bits: u64) -> u64 {
        let rate = u128::from(self.0);
        // Invariant: `self.0` is never zero (checked in `new`, and every constant is non-zero), so the
        // division cannot fail; u128 holds u64::MAX · 10⁹ without overflow.
        let nanos = (u128::from(bits) * 1_000_000_000 + rate / 2) / rate;
        u64::try_from(nanos).unwrap_or(u64::MAX)
    }

    /// The bus time `frame` occupies, SOF through intermission, from its exact stuffed length.
    pub fn frame_duration(self, frame: &CanFrame) -> Duration {
        self.bits_duration(u64::from(frame_bits(frame).total))
    }
}

/// `125k`, `1M`, or the plain number when it is not a whole number of kbit/s.
impl fmt::Display for Bitrate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0.is_multiple_of(1_000_000) {
            write!(f, "{}M", self.0 / 1_000_000)
        } else if self.0.is_multiple_of(1_000) {
            write!(f, "{}k", self.0 / 1_000)
        } else {
            write!(f, "{}", self.0)
        }
    }
}

/// Accepts digits with an optional `k`/`K` (×1000) or `m`/`M` (×1 000 000) suffix: `125k`, `500K`,
/// `1M`, `1m`, `250000`.
impl FromStr for Bitrate {
    type Err = BitrateError;

    fn from_str(text: &str) -> Result<Bitrate, BitrateError> {
        if text.is_empty() {
            return Err(BitrateError::Empty);
        }
        let malformed = || BitrateError::Malformed(text.to_owned());
        let (digits, multiplier) = match text.as_bytes().last() {
            Some(b'k' | b'K') => (&text[..text.len() - 1], 1_000u64),
            Some(b'm' | b'M') => (&text[..text.len() - 1], 1_000_000u64),
            _ => (text, 1u64),
        };
        // `u64::from_str` alone would also accept a leading `+`.
        if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
            return Err(malformed());
        }
        let too_high = || BitrateError::TooHigh(text.to_owned());
        // Only overflow can make a string of ASCII digits fail to parse.
        let value = digits.parse::<u64>().map_err(|_| too_high())?;
        let bits_per_second = value.checked_mul(multiplier).ok_or_else(too_high)?;
        match bits_per_second {
            0 => Err(BitrateError::Zero(text.to_owned())),
            1..=1_000_000 => Ok(Bitrate(bits_per_second as u32)),
            _ => Err(too_high()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::id::StandardId;
    use proptest::prelude::*;

    #[test]
    fn parses_the_usual_spellings() {
        let cases = [
            ("125k", 125_000),
            ("500K", 500_000),
            ("1M", 1_000_000),
            ("1m", 1_000_000),
            ("250000", 250_000),
            ("1000000", 1_000_000),
            ("1000k", 1_000_000),
            ("10k", 10_000),
            ("800k", 800_000),
            ("1", 1),
        ];
        for (text, bps) in cases {
            assert_eq!(
                text.parse::<Bitrate>().map(Bitrate::bits_per_second),
                Ok(bps),
                "{text}"
            );
        }
    }

    #[test]
    fn rejects_with_a_reason() {
        let err = |text: &str| text.parse::<Bitrate>().unwrap_err();
        assert_eq!(err(""), BitrateError::Empty);
        assert_eq!(err("0"), BitrateError::Zero("0".into()));
        assert_eq!(err("0k"), BitrateError::Zero("0k".into()));
        assert_eq!(err("2M"), BitrateError::TooHigh("2M".into()));
        assert_eq!(err("1000001"), BitrateError::TooHigh("1000001".into()));
        assert_eq!(
            err("99999999999999999999999"),
            BitrateError::TooHigh("99999999999999999999999".into())
        );
        assert_eq!(
            err("18446744073709551615M"),
            BitrateError::TooHigh("18446744073709551615M".into())
        );
        for bad in [
            "k", "M", "fast", "125 k", " 125k", "+125k", "-1", "1.5M", "125kk", "125kbit", "١٢٥",
        ] {
            assert_eq!(err(bad), BitrateError::Malformed(bad.into()), "{bad}");
        }
        assert_eq!(Bitrate::new(0), Err(BitrateError::Zero("0".into())));
        assert_eq!(
            Bitrate::new(1_000_001),
            Err(BitrateError::TooHigh("1000001".into()))
        );
    }

    #[test]
    fn error_messages_say_how_to_fix() {
        let message = "2M".parse::<Bitrate>().unwrap_err().to_string();
        assert_eq!(
            message,
            "bitrate `2M` is above 1 Mbit/s, the classical CAN maximum; use at most 1M"
        );
        let message = "fast".parse::<Bitrate>().unwrap_err().to_string();
        assert!(message.starts_with("bitrate `fast` is not a number"), "{message}");
        assert!(message.contains("125k"), "{message}");
    }

    #[test]
    fn display_uses_the_short_form() {
        assert_eq!(Bitrate::K125.to_string(), "125k");
        assert_eq!(Bitrate::M1.to_string(), "1M");
        assert_eq!(Bitrate::K800.to_string(), "800k");
        assert_eq!(Bitrate::new(333_333).unwrap().to_string(), "333333");
    }

    #[test]
    fn bit_times_of_the_cia_rates_are_exact() {
        assert_eq!(Bitrate::M1.bit_time(), Duration::from_nanos(1_000));
        assert_eq!(Bitrate::K800.bit_time(), Duration::from_nanos(1_250));
        assert_eq!(Bitrate::K500.bit_time(), Duration::from_nanos(2_000));
        assert_eq!(Bitrate::K125.bit_time(), Duration::from_nanos(8_000));
        assert_eq!(Bitrate::K10.bit_time(), Duration::from_micros(100));
    }

    #[test]
    fn odd_rates_round_once_not_per_bit() {
        let rate = Bitrate::new(333_333).unwrap();
        // 10⁹ / 333 333 = 3000.003 ns: the bit rounds to 3000 ns, but a million bits are 3 000 003 000 ns,
        // not 3 000 000 000.
        assert_eq!(rate.bit_time(), Duration::from_nanos(3_000));
        assert_eq!(rate.bits_duration(1_000_000), Duration::from_nanos(3_000_003_000));
        // 10⁹ / 3 = 333 333 333.33 rounds down, 2·10⁹ / 3 = 666 666 666.67 rounds up.
        let three = Bitrate::new(3).unwrap();
        assert_eq!(three.bit_time(), Duration::from_nanos(333_333_333));
        assert_eq!(three.bits_duration(2), Duration::from_nanos(666_666_667));
        assert_eq!(
            Bitrate::new(1).unwrap().bits_duration(u64::MAX),
            Duration::from_nanos(u64::MAX)
        );
    }

    #[test]
    fn frame_duration_uses_the_stuffed_length() {
        // The SYNC frame is 51 bits (worked by hand in the `bits` tests).
        let sync = CanFrame::new(StandardId::new(0x080).unwrap(), &[]).unwrap();
        assert_eq!(Bitrate::M1.frame_duration(&sync), Duration::from_micros(51));
        assert_eq!(Bitrate::K125.frame_duration(&sync), Duration::from_micros(51 * 8));
    }

    proptest! {
        #[test]
        fn display_round_trips(bps in 1u32..=1_000_000) {
            let rate = Bitrate::new(bps).unwrap();
            prop_assert_eq!(rate.to_string().parse::<Bitrate>(), Ok(rate));
        }

        #[test]
        fn bits_duration_is_within_half_a_nanosecond(bps in 1u32..=1_000_000, bits in 0u64..1 << 40) {
            let nanos = Bitrate::new(bps).unwrap().bits_nanos(bits);
            let exact = i128::from(bits) * 1_000_000_000;
            let rounded = (exact + i128::from(bps) / 2) / i128::from(bps);
            if rounded > i128::from(u64::MAX) {
                // Slow rates times many bits exceed u64 nanoseconds (584 years): saturate, never wrap.
                prop_assert_eq!(nanos, u64::MAX, "{} bits at {} bit/s", bits, bps);
            } else {
                // |nanos · rate − bits · 10⁹| ≤ rate / 2.
                let error = i128::from(nanos) * i128::from(bps) - exact;
                prop_assert!(2 * error.abs() <= i128::from(bps), "error {error} at {bps} bit/s");
            }
        }
    }
}

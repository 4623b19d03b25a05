//! The TIME service's TIME_OF_DAY value (CiA 301 §7.2.6 and §7.1.6.5).
//!
//! Six bytes: D0..D3 milliseconds after midnight in the low 28 bits (the top 4 bits are reserved),
//! D4..D5 days since 1 January 1984. All little-endian.

use std::fmt;

/// Milliseconds in a day; a valid TIME_OF_DAY has fewer.
pub const MILLIS_PER_DAY: u32 = 86_400_000;

/// The mask of the 28 bits that hold the milliseconds.
pub const MILLIS_MASK: u32 = 0x0FFF_FFFF;

/// 1984-01-01T00:00:00Z, day 0 of TIME_OF_DAY, in milliseconds since the Unix epoch.
pub const UNIX_MILLIS_AT_1984: u64 = 441_763_200_000;

/// Milliseconds since 1984-01-01 of a time in milliseconds since the Unix epoch, or `None` before
/// 1984 (TIME_OF_DAY cannot express it).
pub fn since_1984_from_unix_millis(unix_millis: u64) -> Option<u64> {
    unix_millis.checked_sub(UNIX_MILLIS_AT_1984)
}

/// A TIME_OF_DAY value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TimeOfDay {
    /// Milliseconds after midnight (28 bits on the wire).
    pub millis: u32,
    /// Days since 1 January 1984.
    pub days: u16,
}

/// Why bytes are not a TIME_OF_DAY.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum TimeOfDayError {
    /// Fewer than 6 bytes.
    #[error("a TIME frame carries 6 bytes (milliseconds and days), got {0}")]
    TooShort(usize),
}

impl TimeOfDay {
    /// The TIME_OF_DAY of a wall time in milliseconds since 1984-01-01 00:00, or `None` after
    /// 2163-06-06, the last day its 16-bit day count reaches.
    pub fn from_millis_since_1984(since_1984_millis: u64) -> Option<TimeOfDay> {
        let per_day = u64::from(MILLIS_PER_DAY);
        let days = u16::try_from(since_1984_millis / per_day).ok()?;
        // The remainder is below one day, which fits 32 bits.
        let millis = (since_1984_millis % per_day) as u32;
        Some(TimeOfDay { millis, days })
    }

    /// The TIME_OF_DAY of a wall time in milliseconds since the Unix epoch (UTC, as a system clock
    /// gives it), or `None` outside 1984-01-01 to 2163-06-06.
    pub fn from_unix_millis(unix_millis: u64) -> Option<TimeOfDay> {
        since_1984_from_unix_millis(unix_millis).and_then(TimeOfDay::from_millis_since_1984)
    }

    /// Reads the first 6 bytes. The reserved top 4 bits of the milliseconds are dropped; check
    /// [`TimeOfDay::reserved_bits`] to see them.
    pub fn parse(data: &[u8]) -> Result<TimeOfDay, TimeOfDayError> {
        let [m0, m1, m2, m3, d0, d1, ..] = data else {
            return Err(TimeOfDayError::TooShort(data.len()));
        };
        Ok(TimeOfDay {
            millis: u32::from_le_bytes([*m0, *m1, *m2, *m3]) & MILLIS_MASK,
            days: u16::from_le_bytes([*d0, *d1]),
        })
    }

    /// The reserved top 4 bits of the milliseconds word in `data`, 0 in a correct frame.
    pub fn reserved_bits(data: &[u8]) -> u8 {
        data.get(3).map_or(0, |byte| byte >> 4)
    }

    /// The 6 data bytes (milliseconds above 28 bits are cut off).
    pub fn encode(&self) -> [u8; 6] {
        let [m0, m1, m2, m3] = (self.millis & MILLIS_MASK).to_le_bytes();
        let [d0, d1] = self.days.to_le_bytes();
        [m0, m1, m2, m3, d0, d1]
    }

    /// The calendar date (year, month 1–12, day 1–31) of `days`, in the Gregorian calendar.
    pub fn date(&self) -> (u32, u8, u8) {
        let (year, month, day) = civil_from_days(DAYS_1970_TO_1984 + i64::from(self.days));
        // From 1984 on, 65 535 days later at most: the year fits a u32, month and day a u8.
        (
            u32::try_from(year).unwrap_or(u32::MAX),
            u8::try_from(month).unwrap_or(u8::MAX),
            u8::try_from(day).unwrap_or(u8::MAX),
        )
    }
}

/// Days from 1970-01-01 to 1984-01-01, the TIME_OF_DAY epoch (14 years, 3 of them leap years).
const DAYS_1970_TO_1984: i64 = 14 * 365 + 3;

/// The Gregorian date (year, month 1–12, day 1–31) of a day counted from 1970-01-01, after Howard
/// Hinnant's `civil_from_days`: the one calendar of the workspace (TIME_OF_DAY, the dates reports and
/// DCF headers state).
pub fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let month = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let year = yoe + era * 400 + i64::from(month <= 2);
    (year, month, day)
}

/// `2024-01-01 12:00:00.000`; milliseconds of a day or more print as hours above 23.
impl fmt::Display for TimeOfDay {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (year, month, day) = self.date();
        let ms = self.millis;
        write!(
            f,
            "{year:04}-{month:02}-{day:02} {:02}:{:02}:{:02}.{:03}",
            ms / 3_600_000,
            ms / 60_000 % 60,
            ms / 1000 % 60,
            ms % 1000
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn worked_example_from_the_reference() {
        // 2024-01-01 12:00:00.000 UTC: ms 43 200 000 = 0293 2E00h, days 14 610 = 3912h.
        let bytes = [0x00, 0x2E, 0x93, 0x02, 0x12, 0x39];
        let time = TimeOfDay::parse(&bytes).unwrap();
        assert_eq!(
            time,
            TimeOfDay {
                millis: 43_200_000,
                days: 14_610
            }
        );
        assert_eq!(time.encode(), bytes);
        assert_eq!(time.to_string(), "2024-01-01 12:00:00.000");
    }

    #[test]
    fn calendar_edges() {
        assert_eq!(TimeOfDay { millis: 0, days: 0 }.date(), (1984, 1, 1));
        assert_eq!(TimeOfDay { millis: 0, days: 59 }.date(), (1984, 2, 29));
        assert_eq!(TimeOfDay { millis: 0, days: 365 }.date(), (1984, 12, 31));
        assert_eq!(TimeOfDay { millis: 0, days: 366 }.date(), (1985, 1, 1));
        // 2000 is a leap year, 2100 is not.
        assert_eq!(
            TimeOfDay {
                millis: 0,
                days: 5_903
            }
            .date(),
            (2000, 2, 29)
        );
        assert_eq!(
            TimeOfDay {
                millis: 0,
                days: 42_427
            }
            .date(),
            (2100, 2, 28)
        );
        assert_eq!(
            TimeOfDay {
                millis: 0,
                days: 42_428
            }
            .date(),
            (2100, 3, 1)
        );
        assert_eq!(
            TimeOfDay {
                millis: 0,
                days: u16::MAX
            }
            .date(),
            (2163, 6, 6)
        );
    }

    #[test]
    fn reserved_bits_and_short_frames() {
        assert_eq!(TimeOfDay::reserved_bits(&[0, 0, 0, 0xF0, 0, 0]), 0xF);
        assert_eq!(TimeOfDay::parse(&[0, 0, 0, 0xF0, 0, 0]).unwrap().millis, 0);
        assert_eq!(TimeOfDay::parse(&[0; 5]), Err(TimeOfDayError::TooShort(5)));
    }

    proptest! {
        #[test]
        fn round_trip(millis in 0..=MILLIS_MASK, days: u16) {
            let time = TimeOfDay { millis, days };
            prop_assert_eq!(TimeOfDay::parse(&time.encode()), Ok(time));
            let (_, month, day) = time.date();
            prop_assert!((1..=12).contains(&month) && (1..=31).contains(&day));
        }

        /// The calendar against the Gregorian rules themselves: each day is the day after the one
        /// before, months have their lengths and February 29 exists in leap years only.
        #[test]
        fn each_day_follows_the_one_before(days in -800_000i64..800_000) {
            let leap = |y: i64| (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
            let (y, m, d) = civil_from_days(days);
            let (ny, nm, nd) = civil_from_days(days + 1);
            let length = match m {
                2 if leap(y) => 29,
                2 => 28,
                4 | 6 | 9 | 11 => 30,
                _ => 31,
            };
            prop_assert!(d >= 1 && d <= length, "{y}-{m}-{d}");
            if d < length {
                prop_assert_eq!((ny, nm, nd), (y, m, d + 1));
            } else if m < 12 {
                prop_assert_eq!((ny, nm, nd), (y, m + 1, 1));
            } else {
                prop_assert_eq!((ny, nm, nd), (y + 1, 1, 1));
            }
        }
    }

    #[test]
    fn the_epochs_are_their_dates() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(TimeOfDay { millis: 0, days: 0 }.date(), (1984, 1, 1));
    }

    #[test]
    fn wall_times_convert_to_days_since_1984() {
        // 2024-01-01T12:00:00Z.
        let noon = TimeOfDay::from_unix_millis(1_704_110_400_000).expect("in range");
        assert_eq!(noon.millis, 12 * 3_600_000);
        assert_eq!(noon.date(), (2024, 1, 1));
        assert_eq!(TimeOfDay::from_unix_millis(UNIX_MILLIS_AT_1984 - 1), None);
        let last = u64::from(u16::MAX) * u64::from(MILLIS_PER_DAY) + u64::from(MILLIS_PER_DAY) - 1;
        assert_eq!(
            TimeOfDay::from_millis_since_1984(last).map(|t| t.days),
            Some(u16::MAX)
        );
        assert_eq!(TimeOfDay::from_millis_since_1984(last + 1), None);
    }
}

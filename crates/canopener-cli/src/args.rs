//! Arguments every command family shares: the bus, the output format, and the number and duration
//! notations.

use clap::{Args, ValueEnum};

pub(crate) const BUS_HELP: &str = "CAN bus to use [env: CANOPENER_BUS]. Forms: virtual:NAME[?bitrate=500k], \
socketcand://HOST:PORT/BUS, socketcan:IFACE, udp-multicast://GROUP:PORT";

#[derive(Debug, Args)]
pub(crate) struct BusArg {
    #[arg(long = "bus", value_name = "SPEC", help = BUS_HELP)]
    pub(crate) spec: Option<String>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum OutputFormat {
    /// Aligned text for people.
    Text,
    /// One JSON object per line for machines.
    Json,
}

/// Reads an object index as CANopen tools write it: hexadecimal, with or without `0x` or `h`.
pub(crate) fn parse_index(text: &str) -> Result<u16, String> {
    let t = text.trim();
    let digits = t
        .strip_prefix("0x")
        .or_else(|| t.strip_prefix("0X"))
        .or_else(|| t.strip_suffix('h'))
        .or_else(|| t.strip_suffix('H'))
        .unwrap_or(t);
    u16::from_str_radix(digits, 16)
        .map_err(|_| format!("'{text}' is not an object index; write e.g. 1018, 0x1018 or 1018h"))
}

/// Reads an UNSIGNED32 in decimal or with a `0x` prefix in hexadecimal.
pub(crate) fn parse_u32_number(text: &str) -> Result<u32, String> {
    let t = text.trim();
    let parsed = match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(hex) => u32::from_str_radix(hex, 16),
        None => t.parse(),
    };
    parsed.map_err(|_| format!("'{text}' is not an UNSIGNED32; write e.g. 4660 or 0x1234"))
}

/// Parses `250ms`, `2s`, `1.5s`, `10us`, `1m`, or a bare number of seconds.
pub(crate) fn parse_duration(text: &str) -> Result<std::time::Duration, String> {
    let text = text.trim();
    let split = text
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(text.len());
    let (number, unit) = text.split_at(split);
    let value: f64 = number
        .parse()
        .map_err(|_| format!("'{text}' is not a duration; write e.g. 250ms, 2s, 1.5s, 10us or 1m"))?;
    let seconds = match unit.trim() {
        "" | "s" => value,
        "ms" => value / 1e3,
        "us" | "µs" => value / 1e6,
        "ns" => value / 1e9,
        "m" | "min" => value * 60.0,
        "h" => value * 3600.0,
        other => {
            return Err(format!(
                "unknown duration unit '{other}' in '{text}'; use ns, us, ms, s, m or h"
            ));
        }
    };
    if !seconds.is_finite() || !(0.0..=1e9).contains(&seconds) {
        return Err(format!("duration '{text}' is out of range"));
    }
    Ok(std::time::Duration::from_secs_f64(seconds))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn durations_parse_with_units() {
        assert_eq!(parse_duration("250ms"), Ok(Duration::from_millis(250)));
        assert_eq!(parse_duration("2"), Ok(Duration::from_secs(2)));
        assert_eq!(parse_duration("1.5s"), Ok(Duration::from_millis(1500)));
        assert_eq!(parse_duration("10us"), Ok(Duration::from_micros(10)));
        assert_eq!(parse_duration("1m"), Ok(Duration::from_secs(60)));
        assert!(parse_duration("fast").unwrap_err().contains("not a duration"));
        assert!(
            parse_duration("3 parsecs")
                .unwrap_err()
                .contains("unknown duration unit")
        );
        assert!(parse_duration("").is_err());
    }
}

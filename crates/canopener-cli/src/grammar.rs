//! The one grammar of the command line (`docs/master.md`, "One grammar"): how every command reads a
//! number, an object index, a node-ID or a set of them, a duration and a bit rate. Every option that
//! takes one of these goes through a function here, so a spelling one command accepts, every command
//! accepts (`tests` below walk the whole command tree to prove it).
//!
//! - Numbers: decimal unless written hexadecimal with `0x` before or `h` after (`4660`, `0x1234`,
//!   `1234h`), the syntax `canopener_master::value::parse_number` defines.
//! - Object indices and sub-indices: hexadecimal, as CANopen documents write them, with or without
//!   `0x`/`h`, or decimal when marked `d:` (`1018`, `0x1018`, `1018h`, `d:4120`).
//! - Node-IDs: 1 to 127 as numbers; node lists add ranges (`1-10,20,0x7F`).
//! - Durations: a number with a unit; a bare number is refused because commands once disagreed on
//!   whether it meant seconds or milliseconds.
//! - Bit rates: kbit/s from the CiA 305 bit timing table (`canopener_wire::BIT_TIMING_TABLE`).

use std::time::Duration;

use canopener_master::value::parse_number;
use canopener_wire::NodeId;

use crate::error::{CliError, CliResult};

/// Reads an object index: hexadecimal with or without `0x`/`h`, or decimal marked `d:`.
pub(crate) fn parse_index(text: &str) -> Result<u16, String> {
    canopener_master::value::parse_index(text)
        .map_err(|_| format!("'{text}' is not an object index; write e.g. 1018, 0x1018, 1018h or d:4120"))
}

/// An unsigned number up to `max`.
fn unsigned(text: &str, max: u64) -> Result<u64, String> {
    match parse_number(text) {
        Some(value) if value <= max => Ok(value),
        Some(_) => Err(format!("'{text}' is larger than {max} (0x{max:X})")),
        None => Err(format!(
            "'{text}' is not a whole number; write e.g. 10, 0x0A or 0Ah"
        )),
    }
}

/// An UNSIGNED8.
pub(crate) fn parse_u8(text: &str) -> Result<u8, String> {
    unsigned(text, u8::MAX.into()).and_then(|v| u8::try_from(v).map_err(|e| e.to_string()))
}

/// An UNSIGNED16.
pub(crate) fn parse_u16(text: &str) -> Result<u16, String> {
    unsigned(text, u16::MAX.into()).and_then(|v| u16::try_from(v).map_err(|e| e.to_string()))
}

/// An UNSIGNED32.
pub(crate) fn parse_u32(text: &str) -> Result<u32, String> {
    unsigned(text, u32::MAX.into()).and_then(|v| u32::try_from(v).map_err(|e| e.to_string()))
}

/// A count (UNSIGNED64).
pub(crate) fn parse_u64(text: &str) -> Result<u64, String> {
    unsigned(text, u64::MAX)
}

/// A count of things in memory (states, steps).
pub(crate) fn parse_usize(text: &str) -> Result<usize, String> {
    unsigned(text, u64::MAX).and_then(|v| usize::try_from(v).map_err(|e| e.to_string()))
}

/// An integer in `min..=max`; `what` names it in the message.
pub(crate) fn parse_in_range(text: &str, min: u64, max: u64, what: &str) -> Result<u64, String> {
    let value = unsigned(text, u64::MAX)?;
    if (min..=max).contains(&value) {
        Ok(value)
    } else {
        Err(format!("{what} must be {min}..{max}, not {text}"))
    }
}

/// A node-ID 1..127 (`--node 5`, `--node 0x05`, `--node-id 05h`).
pub(crate) fn parse_node_id(text: &str) -> Result<u8, String> {
    parse_number(text)
        .and_then(|v| u8::try_from(v).ok())
        .filter(|v| (1..=127).contains(v))
        .ok_or_else(|| format!("'{text}' is not a node-ID: give 1..127 in decimal or hex, e.g. 5 or 0x05"))
}

/// A CiA 301 bit rate in kbit/s (the rates of the CiA 305 bit timing table), as every `--bitrate`
/// takes it.
pub(crate) fn parse_cia_bitrate(text: &str) -> Result<u16, String> {
    let rates: Vec<u16> = canopener_wire::BIT_TIMING_TABLE
        .iter()
        .filter_map(|entry| entry.kbit)
        .collect();
    parse_u16(text)
        .ok()
        .filter(|rate| rates.contains(rate))
        .ok_or_else(|| {
            format!("'{text}' is not a CANopen bit rate in kbit/s; use one of {rates:?}, e.g. --bitrate 250")
        })
}

/// Reads a node list: node-IDs 1..127 and ranges, comma-separated (`1-10,20,0x7F`), in the order
/// given. `option` and `example` go into the message of a bad list.
pub(crate) fn parse_node_list(text: &str, option: &str, example: &str) -> CliResult<Vec<NodeId>> {
    let bad = |why: String| {
        CliError::Usage(format!(
            "{option} {text:?}: {why}; give node-IDs 1 to 127 and ranges, e.g. `{example}`"
        ))
    };
    let node = |part: &str| -> CliResult<NodeId> {
        let part = part.trim();
        parse_node_id(part)
            .ok()
            .and_then(NodeId::new)
            .ok_or_else(|| bad(format!("{part:?} is not a node-ID")))
    };
    let mut nodes = Vec::new();
    for part in text.split(',') {
        match part.split_once('-') {
            Some((first, last)) => {
                let (first, last) = (node(first)?, node(last)?);
                if first > last {
                    return Err(bad(format!("the range {first}-{last} runs backwards")));
                }
                nodes.extend((first.get()..=last.get()).filter_map(NodeId::new));
            }
            None => nodes.push(node(part)?),
        }
    }
    Ok(nodes)
}

/// Parses `250ms`, `2s`, `1.5s`, `10us`, `1m`. A bare number is refused with an example: `10` meant
/// ten seconds to one command and ten milliseconds to the reader of another.
pub(crate) fn parse_duration(text: &str) -> Result<Duration, String> {
    let text = text.trim();
    let split = text
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(text.len());
    let (number, unit) = text.split_at(split);
    let value: f64 = number
        .parse()
        .map_err(|_| format!("'{text}' is not a duration; write e.g. 250ms, 2s, 1.5s, 10us or 1m"))?;
    let seconds = match unit.trim() {
        "" => {
            return Err(format!(
                "'{text}' has no unit; write e.g. {number}ms or {number}s (units: ns, us, ms, s, m, h)"
            ));
        }
        "s" => value,
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
    Ok(Duration::from_secs_f64(seconds))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_parse_with_units() {
        assert_eq!(parse_duration("250ms"), Ok(Duration::from_millis(250)));
        assert_eq!(parse_duration("2s"), Ok(Duration::from_secs(2)));
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

    /// Issue 13 item 12: a bare number is no duration (it was seconds, silently).
    #[test]
    fn a_bare_number_is_not_a_duration() {
        let err = parse_duration("10").unwrap_err();
        assert!(
            err.contains("has no unit") && err.contains("10ms or 10s"),
            "{err}"
        );
        assert!(parse_duration("0").is_err());
        assert_eq!(parse_duration("0s"), Ok(Duration::ZERO));
    }

    #[test]
    fn integers_take_decimal_0x_and_h_everywhere() {
        assert_eq!(parse_u8("0x05"), Ok(5));
        assert_eq!(parse_u8("05h"), Ok(5));
        assert_eq!(parse_u8("255"), Ok(255));
        assert!(parse_u8("256").unwrap_err().contains("larger than 255"));
        assert_eq!(parse_u16("0XFFFF"), Ok(0xFFFF));
        assert_eq!(parse_u32("1234h"), Ok(0x1234));
        assert_eq!(parse_u64("0x10"), Ok(16));
        assert!(parse_u16("ten").unwrap_err().contains("e.g. 10, 0x0A or 0Ah"));
        assert_eq!(parse_in_range("0x02", 2, 240, "--counter"), Ok(2));
        assert!(
            parse_in_range("1", 2, 240, "--counter")
                .unwrap_err()
                .contains("2..240")
        );
    }

    #[test]
    fn indices_are_hex_unless_marked_decimal() {
        for spelling in ["1018", "0x1018", "1018h", "d:4120", "D:4120"] {
            assert_eq!(parse_index(spelling), Ok(0x1018), "{spelling}");
        }
        assert!(parse_index("10180").unwrap_err().contains("d:4120"));
    }

    #[test]
    fn node_ids_are_1_to_127_in_decimal_or_hex() {
        assert_eq!(parse_node_id("5"), Ok(5));
        assert_eq!(parse_node_id("0x05"), Ok(5));
        assert_eq!(parse_node_id("7Fh"), Ok(127));
        for bad in ["0", "128", "0x80", "-1", "five", ""] {
            assert!(parse_node_id(bad).unwrap_err().contains("1..127"), "{bad}");
        }
    }

    #[test]
    fn bitrates_are_the_cia_rates() {
        assert_eq!(parse_cia_bitrate("250"), Ok(250));
        assert_eq!(parse_cia_bitrate("0x3E8"), Ok(1000));
        assert!(parse_cia_bitrate("100").unwrap_err().contains("--bitrate 250"));
    }

    #[test]
    fn node_lists_keep_their_order_and_refuse_nonsense_with_an_example() {
        let list = parse_node_list("10-12, 5,0x7F", "--nodes", "x").unwrap();
        let raw: Vec<u8> = list.iter().map(|node| node.get()).collect();
        assert_eq!(raw, [10, 11, 12, 5, 127]);
        for bad in ["", "0", "128", "5-", "12-10", "a", "1,,2"] {
            let err = parse_node_list(bad, "--nodes", "canopener heartbeat watch --nodes 1-10").unwrap_err();
            assert!(matches!(err, CliError::Usage(_)), "{bad:?}");
            let text = err.to_string();
            assert!(
                text.contains("--nodes") && text.contains("e.g. `canopener heartbeat watch --nodes 1-10`"),
                "{text}"
            );
        }
    }
}

/// Every integer option of every command, read the way the whole command line reads it.
#[cfg(test)]
mod every_command {
    use std::any::TypeId;

    use clap::{Arg, ArgMatches, Command, CommandFactory};
    use proptest::prelude::*;

    /// Every option and positional argument whose parsed type is an integer, with its command path.
    fn integer_args() -> Vec<(String, Arg)> {
        fn walk(command: &Command, path: &str, out: &mut Vec<(String, Arg)>) {
            for arg in command.get_arguments() {
                let ty = arg.get_value_parser().type_id();
                let integer = [
                    TypeId::of::<u8>(),
                    TypeId::of::<u16>(),
                    TypeId::of::<u32>(),
                    TypeId::of::<u64>(),
                    TypeId::of::<usize>(),
                ]
                .into_iter()
                .any(|t| ty == t);
                // A duration that becomes a count of ms or µs is read as a duration, with its unit.
                let duration = arg
                    .get_value_names()
                    .is_some_and(|names| names.iter().any(|n| n.as_str() == "DURATION"));
                if integer && !duration && arg.get_action().takes_values() {
                    out.push((path.to_owned(), arg.clone()));
                }
            }
            for sub in command.get_subcommands() {
                walk(sub, &format!("{path} {}", sub.get_name()), out);
            }
        }
        let mut out = Vec::new();
        walk(&crate::cli::Cli::command(), "canopener", &mut out);
        out
    }

    /// The value `arg` alone parses `text` to, as text (`Err` when it refuses it).
    fn parse_alone(arg: &Arg, text: &str) -> Result<String, String> {
        // The option alone, as a positional argument: its parser, none of its relations to the
        // command's other options.
        let id = arg.get_id().to_string();
        let alone = Arg::new(arg.get_id().clone()).value_parser(arg.get_value_parser().clone());
        let line = ["t", text];
        let matches: ArgMatches = Command::new("t")
            .arg(alone)
            .try_get_matches_from(line)
            .map_err(|e| e.kind().to_string())?;
        macro_rules! value {
            ($($t:ty),*) => {
                $(if let Ok(Some(v)) = matches.try_get_one::<$t>(&id) {
                    return Ok(format!("{v:?}"));
                })*
            };
        }
        value!(u8, u16, u32, u64, usize);
        Err(format!("{id}: no integer value"))
    }

    /// Whether `arg` takes an object index or sub-index, which the grammar reads as hex by default.
    fn is_index(arg: &Arg) -> bool {
        arg.get_value_names()
            .is_some_and(|names| names.iter().any(|n| n.as_str() == "INDEX" || n.as_str() == "SUB"))
    }

    /// The spellings of `value` the grammar promises for `arg`: for a number decimal, `0x`/`0X` hex,
    /// `h`/`H` hex, binary and a leading zero; for an index plain hex, `0x`, `h` and `d:` decimal.
    fn spellings(arg: &Arg, value: u64) -> Vec<String> {
        if is_index(arg) {
            return vec![
                format!("{value:X}"),
                format!("0x{value:04x}"),
                format!("{value:X}h"),
                format!("d:{value}"),
            ];
        }
        vec![
            format!("{value}"),
            format!("0x{value:x}"),
            format!("0X{value:X}"),
            format!("0{value:X}h"),
            format!("{value:x}H"),
            format!("0b{value:b}"),
            format!("0{value}"),
        ]
    }

    #[test]
    fn the_tree_has_the_integer_options_the_docs_promise() {
        let found: Vec<String> = integer_args()
            .iter()
            .map(|(path, arg)| format!("{path} {}", arg.get_id()))
            .collect();
        for expected in [
            "canopener sdo read node",
            "canopener eds convert bitrate",
            "canopener mbt run steps",
            "canopener mbt run seed",
            "canopener net monitor heartbeat_ms",
            "canopener sim serial",
            "canopener test repetitions",
            "canopener pdo map transmission_type",
        ] {
            assert!(
                found.iter().any(|f| f == expected),
                "{expected} not among {found:#?}"
            );
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// Issue 25 item 3: whichever command an integer goes to, every spelling of it reads alike:
        /// accepted as the same value, or refused by all (out of the option's range).
        #[test]
        fn every_command_accepts_the_same_spellings(value in prop_oneof![0u64..=255, 0u64..=65_535, any::<u32>().prop_map(u64::from)]) {
            for (path, arg) in integer_args() {
                let outcomes: Vec<(String, Result<String, String>)> = spellings(&arg, value)
                    .into_iter()
                    .map(|text| (text.clone(), parse_alone(&arg, &text)))
                    .collect();
                let first = &outcomes[0].1;
                for (text, outcome) in &outcomes {
                    prop_assert_eq!(
                        outcome.is_ok(),
                        first.is_ok(),
                        "{} {}: {:?} gives {:?} but {} gives {:?}",
                        path, arg.get_id(), text, outcome, value, first
                    );
                    if let (Ok(a), Ok(b)) = (outcome, first) {
                        prop_assert_eq!(a, b, "{} {}: {:?}", path, arg.get_id(), text);
                    }
                }
            }
        }
    }

    #[test]
    fn every_integer_option_reads_some_value() {
        for (path, arg) in integer_args() {
            let read = [1u64, 5, 10, 127, 250, 1000]
                .iter()
                .any(|v| parse_alone(&arg, &spellings(&arg, *v)[0]).is_ok());
            assert!(
                read,
                "{path} {} reads none of 1, 5, 10, 127, 250, 1000",
                arg.get_id()
            );
        }
    }
}

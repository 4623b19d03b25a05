//! Arguments every command family shares: the bus, the output format, and the number, node-ID and
//! duration notations of the one CLI grammar (`docs/master.md`, "One grammar"): every integer in
//! decimal or `0x` hex, every duration with a unit, `--node` for the device a command talks to,
//! `--nodes` for a set of them. Object indices and CAN-IDs are the exceptions CANopen itself makes:
//! hexadecimal, with or without `0x`/`h`.

use canopener_wire::NodeId;
use clap::{Args, ValueEnum};

use crate::error::{CliError, CliResult};

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

/// Reads a fault name of the device fault catalogue (`sim`, `mbt`, `demo --fault`); the error lists
/// every name.
pub(crate) fn parse_fault(text: &str) -> Result<canopener_device::faults::Fault, String> {
    text.parse()
        .map_err(|e: canopener_device::faults::UnknownFault| e.to_string())
}

/// Reads a fault name of the device fault catalogue or an EnergyBus fault (`mbt --energybus`, `sim
/// --energybus`); the error lists every name.
pub(crate) fn parse_device_fault(
    text: &str,
) -> Result<canopener_device::energybus::station::DeviceFault, String> {
    text.parse()
        .map_err(|e: canopener_device::energybus::station::UnknownDeviceFault| e.to_string())
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

/// Reads an unsigned integer up to `max` in decimal or with a `0x` prefix in hexadecimal.
fn parse_unsigned(text: &str, max: u64) -> Result<u64, String> {
    let t = text.trim();
    let parsed = match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(hex) => u64::from_str_radix(hex, 16),
        None => t.parse(),
    };
    match parsed {
        Ok(value) if value <= max => Ok(value),
        Ok(_) => Err(format!("'{text}' is larger than {max} (0x{max:X})")),
        Err(_) => Err(format!("'{text}' is not a whole number; write e.g. 10 or 0x0A")),
    }
}

/// An UNSIGNED8 in decimal or `0x` hex.
pub(crate) fn parse_u8(text: &str) -> Result<u8, String> {
    parse_unsigned(text, u8::MAX.into()).map(|v| u8::try_from(v).unwrap_or(u8::MAX))
}

/// An UNSIGNED16 in decimal or `0x` hex.
pub(crate) fn parse_u16(text: &str) -> Result<u16, String> {
    parse_unsigned(text, u16::MAX.into()).map(|v| u16::try_from(v).unwrap_or(u16::MAX))
}

/// A count (UNSIGNED64) in decimal or `0x` hex.
pub(crate) fn parse_u64(text: &str) -> Result<u64, String> {
    parse_unsigned(text, u64::MAX)
}

/// An integer in `min..=max`, decimal or `0x` hex; `what` names it in the message.
pub(crate) fn parse_in_range(text: &str, min: u64, max: u64, what: &str) -> Result<u64, String> {
    let value = parse_unsigned(text, u64::MAX)?;
    if (min..=max).contains(&value) {
        Ok(value)
    } else {
        Err(format!("{what} must be {min}..{max}, not {text}"))
    }
}

/// A node-ID 1..127 in decimal or `0x` hex (`--node 5`, `--node 0x05`, `--node-id 5`).
pub(crate) fn parse_node_id(text: &str) -> Result<u8, String> {
    parse_unsigned(text, u8::MAX.into())
        .ok()
        .and_then(|v| u8::try_from(v).ok())
        .filter(|v| (1..=127).contains(v))
        .ok_or_else(|| format!("'{text}' is not a node-ID: give 1..127 in decimal or 0x hex, e.g. 5 or 0x05"))
}

/// A CiA 301 bit rate in kbit/s (the rates of the CiA 305 bit timing table), as every `--bitrate` takes it.
pub(crate) fn parse_cia_bitrate(text: &str) -> Result<u16, String> {
    const RATES: [u16; 8] = [10, 20, 50, 125, 250, 500, 800, 1000];
    parse_u16(text)
        .ok()
        .filter(|rate| RATES.contains(rate))
        .ok_or_else(|| {
            format!("'{text}' is not a CANopen bit rate in kbit/s; use one of {RATES:?}, e.g. --bitrate 250")
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
    Ok(std::time::Duration::from_secs_f64(seconds))
}

/// `--bus` values: `N=SPEC` for network N, a plain `SPEC` for the monitor's network (`None`).
pub(crate) fn split_bus(value: &str) -> Result<(Option<u32>, &str), String> {
    match value.split_once('=') {
        Some((net, spec)) if !net.is_empty() && net.bytes().all(|b| b.is_ascii_digit()) => {
            let net = net
                .parse()
                .map_err(|_| format!("--bus {value}: network number {net} is too large"))?;
            Ok((Some(net), spec))
        }
        _ => Ok((None, value)),
    }
}

/// The `--bus` values of a system command, or `CANOPENER_BUS` as the monitor network's bus when none is
/// given.
pub(crate) fn bus_values(given: &[String]) -> Result<Vec<String>, CliError> {
    if !given.is_empty() {
        return Ok(given.to_vec());
    }
    match std::env::var("CANOPENER_BUS") {
        Ok(spec) if !spec.trim().is_empty() => Ok(vec![spec]),
        _ => Err(CliError::Usage(
            "pass --bus SPEC (the monitor's network) or --bus N=SPEC per network, or set CANOPENER_BUS"
                .to_owned(),
        )),
    }
}

/// `--bus` values by network: `N=SPEC` for network N, a plain `SPEC` for network `home`. Every
/// network must be one of `networks`, and have one bus.
pub(crate) fn buses_by_network(
    values: &[String],
    home: u32,
    networks: &std::collections::BTreeSet<u32>,
) -> Result<std::collections::BTreeMap<u32, String>, String> {
    let mut specs = std::collections::BTreeMap::new();
    for value in values {
        let (net, spec) = split_bus(value)?;
        let net = net.unwrap_or(home);
        if !networks.contains(&net) {
            return Err(format!(
                "--bus {value}: the topology has no network {net}; its networks are {networks:?}"
            ));
        }
        if specs.insert(net, spec.to_owned()).is_some() {
            return Err(format!("network {net} is given two buses"));
        }
    }
    Ok(specs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn bus_values_name_their_network_or_none() {
        assert_eq!(split_bus("2=socketcan:can1"), Ok((Some(2), "socketcan:can1")));
        assert_eq!(split_bus("socketcan:can0"), Ok((None, "socketcan:can0")));
        assert_eq!(
            split_bus("virtual:x?bitrate=500k"),
            Ok((None, "virtual:x?bitrate=500k"))
        );
        assert!(split_bus("99999999999=virtual:x").is_err());
    }

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
    fn integers_take_decimal_and_0x_everywhere() {
        assert_eq!(parse_u8("0x05"), Ok(5));
        assert_eq!(parse_u8("255"), Ok(255));
        assert!(parse_u8("256").unwrap_err().contains("larger than 255"));
        assert_eq!(parse_u16("0XFFFF"), Ok(0xFFFF));
        assert_eq!(parse_u64("0x10"), Ok(16));
        assert!(parse_u16("ten").unwrap_err().contains("e.g. 10 or 0x0A"));
        assert_eq!(parse_in_range("0x02", 2, 240, "--counter"), Ok(2));
        assert!(
            parse_in_range("1", 2, 240, "--counter")
                .unwrap_err()
                .contains("2..240")
        );
    }

    #[test]
    fn node_ids_are_1_to_127_in_decimal_or_hex() {
        assert_eq!(parse_node_id("5"), Ok(5));
        assert_eq!(parse_node_id("0x05"), Ok(5));
        assert_eq!(parse_node_id("0x7F"), Ok(127));
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

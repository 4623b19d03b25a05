//! Arguments every command family shares: the bus, the output format and the fault names. How
//! numbers, indices, node-IDs, durations and bit rates are written is [`crate::grammar`]'s business.

use clap::{Args, ValueEnum};

use crate::error::CliError;

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
}

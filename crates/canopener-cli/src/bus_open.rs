//! Resolving `--bus SPEC` (or `CANOPENER_BUS`) to an open endpoint, with advice for specs that cannot work
//! from a one-shot command.

use canopener_transport::{BusSpec, CanBus, open, spec_from_env_or};

use crate::error::{CliError, CliResult};

/// Opens the bus for `command`. A `virtual:` bus lives inside one process, so a standalone `bus send` on it
/// would reach nobody: that is refused with advice rather than silently doing nothing.
pub(crate) fn open_bus(arg: Option<&str>, command: &str) -> CliResult<Box<dyn CanBus>> {
    let spec = spec_from_env_or(arg)?;
    if let BusSpec::Virtual { name, .. } = &spec {
        return Err(CliError::Usage(format!(
            "`{command}` cannot use virtual:{name}: a virtual bus exists only inside one canopener process, so \
             nothing else would be on it; start a hub with `canopener bus serve` and use \
             --bus socketcand://127.0.0.1:29536/can0, or try `canopener demo --bus virtual:{name}`"
        )));
    }
    Ok(open(&spec)?)
}

//! Opening the bus of a master command as a runtime [`BusLink`] that the Ctrl-C handler cancels.

use canopener_runtime::link::BusLink;

use crate::bus_open::open_bus;
use crate::error::CliResult;
use crate::stop::StopFlag;

/// Opens `--bus SPEC` (or `CANOPENER_BUS`) for `command`.
pub(crate) fn open_link(spec: Option<&str>, command: &str) -> CliResult<BusLink> {
    let bus = open_bus(spec, command)?;
    Ok(BusLink::new(bus, StopFlag::install()?.token())?)
}

//! Opening the bus of a master command as a runtime [`BusLink`] that the Ctrl-C handler cancels, and
//! the SDO session of one node on it.

use std::time::Duration;

use canopener_link::link::BusLink;
use canopener_link::sdo_session::{SdoSession, SessionError};

use crate::bus_open::open_bus;
use crate::error::{CliError, CliResult};
use crate::master::args::MasterArgs;
use crate::stop::StopFlag;

/// Opens `--bus SPEC` (or `CANOPENER_BUS`) for `command`.
pub(crate) fn open_link(spec: Option<&str>, command: &str) -> CliResult<BusLink> {
    let bus = open_bus(spec, command)?;
    Ok(BusLink::new(bus, StopFlag::install()?.token())?)
}

/// Checks `--timeout` and the node-ID, then opens `--bus` for `command` and the SDO session of `node`.
pub(crate) fn open_session(master: &MasterArgs, node: u8, command: &str) -> CliResult<SdoSession<BusLink>> {
    checked_timeout(master.timeout())?;
    canopener_master::sdo_client::SdoClient::new(node)
        .map_err(|err| CliError::Usage(format!("{err}; give --node 1..127, e.g. --node 5")))?;
    let link = open_link(master.bus.spec.as_deref(), command)?;
    SdoSession::new(link, node, master.timeout()).map_err(|err| match err {
        SessionError::ZeroTimeout => zero_timeout(),
        SessionError::Client(err) => CliError::Usage(format!("{err}; give --node 1..127, e.g. --node 5")),
    })
}

/// Refuses `--timeout 0`: the SDO client reads zero as "wait forever", which a command must not do.
pub(crate) fn checked_timeout(timeout: Duration) -> CliResult<Duration> {
    if timeout.is_zero() {
        return Err(zero_timeout());
    }
    Ok(timeout)
}

fn zero_timeout() -> CliError {
    CliError::Usage("--timeout must be longer than 0, e.g. --timeout 500ms".to_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_timeouts_are_refused_with_an_example() {
        let err = checked_timeout(Duration::ZERO).unwrap_err();
        assert_eq!(err.exit_code(), 2);
        assert!(err.to_string().contains("e.g. --timeout 500ms"));
        assert_eq!(
            checked_timeout(Duration::from_millis(1)).unwrap(),
            Duration::from_millis(1)
        );
    }
}

//! `canopener bus serve`: the socketcand-compatible hub, until Ctrl-C or SIGTERM.

use canopener_runtime::hub::{HubConfig, HubEnd, HubStats, RunningHub};
use canopener_transport::TransportError;

use crate::bus::args::ServeArgs;
use crate::error::{CliError, CliResult};
use crate::output::print_stdout;
use crate::stop::StopFlag;

pub(crate) fn run(args: ServeArgs) -> CliResult {
    // Installed before the hub starts, so that a signal arriving at any point stops it cleanly.
    let stop = StopFlag::install()?;
    let mut config = HubConfig::new(args.listen);
    config.raw_grace = args.raw_grace;
    config.stall_timeout = args.stall_timeout;
    config.echo = args.echo;
    let hub = RunningHub::start(config).map_err(|err| {
        CliError::Bus(TransportError::Io {
            endpoint: format!("socketcand://{}", args.listen),
            operation: "listening",
            hint: "is another hub already using this port? pick another with --listen 127.0.0.1:PORT",
            source: err.source,
        })
    })?;
    let addr = hub.local_addr();
    // The first stdout line is machine-readable on purpose: scripts and tests wait for it.
    print_stdout(&format!(
        "canopener hub listening on socketcand://{addr}\n  connect with --bus socketcand://{addr}/can0, or \
         python-can: can.Bus(interface=\"socketcand\", host=\"{}\", port={}, channel=\"can0\")\n",
        addr.ip(),
        addr.port()
    ))?;
    let end = hub.serve(&stop.token(), None, Some(args.stats_every), |stats| {
        eprintln!("{}", stats_line(stats));
    });
    if end == HubEnd::Cancelled {
        eprintln!("stopping the hub");
    }
    Ok(())
}

fn stats_line(stats: &HubStats) -> String {
    format!(
        "hub: {} clients ({} since start, {} dropped), {} buses, {} frames in, {} deliveries out, \
         {} garbage elements",
        stats.clients_active,
        stats.clients_connected,
        stats.clients_dropped,
        stats.buses_active,
        stats.frames_in,
        stats.frames_out,
        stats.garbage_elements
    )
}

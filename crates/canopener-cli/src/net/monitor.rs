//! `canopener net monitor`: the system monitor on one bus per network, its events as JSON lines, as
//! text lines, or in a live terminal view ([`crate::net::tui`]).

use std::io::{IsTerminal, Write};

use canopener_link::link::{BusLink, Flow, Link};
use canopener_link::system_watch::SystemWatch;
use canopener_network::Topology;
use canopener_network::monitor::{Event, Health, MonitorConfig, SystemMonitor};

use crate::args::{bus_values, buses_by_network};
use crate::bus_open::open_bus;
use crate::error::{CliError, CliResult, exit_code, stdout_error};
use crate::net::args::{MonitorFormat, NetMonitorArgs};
use crate::net::input::read_system;
use crate::net::tui::Tui;
use crate::output::buffered_stdout;
use crate::stop::StopFlag;

pub(crate) fn run(args: NetMonitorArgs) -> CliResult {
    let system = read_system(&args.file)?;
    let topology = system.topology();
    if topology.network_numbers().is_empty() {
        return Err(CliError::EdsTrouble(format!(
            "{}: no network with devices; `canopener net check {}` says why",
            args.file.display(),
            args.file.display()
        )));
    }
    let at = monitor_position(topology, args.at.as_deref())?;
    let home = at
        .and_then(|at| topology.vertices[at].networks().into_iter().next())
        .or_else(|| topology.network_numbers().into_iter().next())
        .unwrap_or(1);
    let values = bus_values(&args.buses)?;
    let specs = buses_by_network(&values, home, &topology.network_numbers()).map_err(CliError::Usage)?;
    let config = MonitorConfig {
        at,
        networks: specs.keys().copied().collect(),
        producer_times: system.producer_times(),
        fallback: args.heartbeat_ms.map(std::time::Duration::from_millis),
    };
    let stop = StopFlag::install()?;
    let mut links: Vec<(u32, BusLink)> = Vec::new();
    for (net, spec) in &specs {
        let bus = open_bus(Some(spec), "net monitor")?;
        links.push((*net, BusLink::new(bus, stop.token())?));
    }
    let mut watch = SystemWatch::new(SystemMonitor::new(topology, &config));
    let mut dyn_links: Vec<(u32, &mut dyn Link)> =
        links.iter_mut().map(|(n, l)| (*n, l as &mut dyn Link)).collect();
    let until = args.duration.map(|d| dyn_links[0].1.now() + d);
    let ended = match args.format {
        MonitorFormat::Json => {
            let mut out = buffered_stdout();
            watch.run(&mut dyn_links, until, |_, _, events| {
                for event in &events {
                    writeln!(out, "{}", event.to_json()).map_err(stdout_error)?;
                }
                out.flush().map_err(stdout_error)?;
                Ok::<_, CliError>(Flow::Continue)
            })?
        }
        MonitorFormat::Human if std::io::stdout().is_terminal() => {
            let mut tui = Tui::start(topology, &args.file.display().to_string())?;
            let result = watch.run(&mut dyn_links, until, |now, monitor, events| {
                tui.update(now, monitor, events)
            });
            tui.stop();
            result?
        }
        MonitorFormat::Human => {
            let mut out = buffered_stdout();
            watch.run(&mut dyn_links, until, |_, _, events| {
                for event in &events {
                    writeln!(out, "{}", line(event)).map_err(stdout_error)?;
                }
                out.flush().map_err(stdout_error)?;
                Ok::<_, CliError>(Flow::Continue)
            })?
        }
    };
    // A run of --duration ends with the health of what it watched; one the user ended (q,
    // Ctrl-C) with 0, as before.
    let cancelled = dyn_links.iter().any(|(_, link)| link.is_cancelled());
    if until.is_none_or(|until| ended < until) || cancelled {
        return Ok(());
    }
    match watch.monitor().health() {
        Health::Healthy => Ok(()),
        Health::Troubled => Err(CliError::Exit(exit_code::CHECK_FAILED)),
        Health::Unheard => Err(CliError::Exit(exit_code::DEVICE)),
    }
}

/// `--at`, or the default position ([`Topology::default_position`]).
fn monitor_position(topology: &Topology, at: Option<&str>) -> CliResult<Option<usize>> {
    match at {
        Some(name) => topology.find_vertex(name).map(Some).ok_or_else(|| {
            CliError::Usage(format!(
                "--at {name}: no vertex of the topology has this id or NodeName"
            ))
        }),
        None => Ok(topology.default_position()),
    }
}

/// An event as one line for people.
pub(crate) fn line(event: &Event) -> String {
    match event {
        Event::State {
            time,
            network,
            node,
            node_id,
            state,
        } => format!(
            "{time:>9.3}s  net {network}  {node} (node {node_id}): {}",
            state.as_str()
        ),
        Event::Recovered {
            time,
            network,
            node,
            node_id,
        } => format!("{time:>9.3}s  net {network}  {node} (node {node_id}) is heard again"),
        Event::Anomaly {
            time,
            network,
            node,
            node_id,
            frame,
            reason,
        } => format!("{time:>9.3}s  net {network}  {node} (node {node_id}): anomaly {frame}: {reason}"),
        Event::Diagnosis {
            time,
            network,
            silent,
            ..
        } if silent.is_empty() => format!("{time:>9.3}s  net {network}  every device is heard"),
        Event::Diagnosis {
            time,
            network,
            silent,
            explanations,
        } => {
            let mut text = format!("{time:>9.3}s  net {network}  silent: {}", silent.join(", "));
            for e in explanations {
                text.push_str(&format!(
                    "\n            {} {} explains {}",
                    e.kind.as_str(),
                    e.candidates.join(" or "),
                    e.explains.join(", ")
                ));
            }
            text
        }
    }
}

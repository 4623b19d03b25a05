//! `canopener sim --nodelist FILE`: a whole system from its topology on real buses, wiring-aware, with
//! cuts and supply domains changed while it runs by commands on standard input (`cut CABLE`,
//! `repair CABLE`, `kill DEVICE`, `revive DEVICE`, `power-off DOMAIN`, `power-on DOMAIN`,
//! `repair-all`, one a line).

use std::path::Path;

use canopener_link::link::BusLink;
use canopener_sim::system::files::{SystemError, SystemFiles};
use canopener_sim::system::serve::{ServeReport, serve, stdin_commands};
use canopener_sim::system::sim::SimulatedSystem;

use crate::args::{bus_values, buses_by_network};
use crate::bus_open::open_bus;
use crate::error::{CliError, CliResult};
use crate::output::print_stdout;
use crate::sim::args::{SimArgs, SimFormat};
use crate::stop::StopFlag;

pub(crate) fn run(path: &Path, args: &SimArgs) -> CliResult {
    let files = SystemFiles::read(path).map_err(|e| CliError::InvalidInput(e.to_string()))?;
    let topology = files.topology();
    let at = match &args.at {
        Some(name) => Some(topology.find_vertex(name).ok_or_else(|| {
            CliError::Usage(format!(
                "--at {name}: no vertex of the topology has this id or NodeName"
            ))
        })?),
        None => topology.default_position(),
    };
    let home = at
        .and_then(|at| topology.vertices[at].networks().into_iter().next())
        .or_else(|| topology.network_numbers().into_iter().next())
        .unwrap_or(1);
    let values = bus_values(&args.buses)?;
    let specs = buses_by_network(&values, home, &topology.network_numbers()).map_err(CliError::Usage)?;
    let mut sim = SimulatedSystem::ideal(&files, at).map_err(sim_error)?;
    let initial = args
        .cuts
        .iter()
        .map(|c| format!("cut {c}"))
        .chain(args.power_off.iter().map(|d| format!("power-off {d}")));
    for command in initial {
        sim.command(&command)
            .map_err(|e| CliError::Usage(e.to_string()))?;
    }
    let stop = StopFlag::install()?;
    let mut buses = Vec::new();
    for (net, spec) in &specs {
        buses.push((
            *net,
            BusLink::new(open_bus(Some(spec), "sim --nodelist")?, stop.token())?,
        ));
    }
    let devices: usize = sim
        .nets()
        .iter()
        .map(|n| n.link.virtual_bus().nodes().count())
        .sum();
    eprintln!(
        "simulating {devices} device(s) on {} network(s) of {}; type `cut CABLE`, `repair CABLE`, `kill DEVICE`, \
         `revive DEVICE`, `power-off DOMAIN`, `power-on DOMAIN` or `repair-all`; Ctrl-C ends",
        sim.nets().len(),
        path.display()
    );
    let commands = stdin_commands();
    let mut failed = None;
    serve(&mut sim, buses, &commands, |report| {
        let result = match (&report, args.format) {
            (ServeReport::Applied { command }, SimFormat::Human) => {
                eprintln!("applied: {command}");
                Ok(())
            }
            (ServeReport::Refused { command, reason }, SimFormat::Human) => {
                eprintln!("refused: {command}: {reason}");
                Ok(())
            }
            (ServeReport::Applied { command }, SimFormat::Json) => print_stdout(&format!(
                "{}\n",
                serde_json::json!({"event": "applied", "command": command})
            )),
            (ServeReport::Refused { command, reason }, SimFormat::Json) => print_stdout(&format!(
                "{}\n",
                serde_json::json!({"event": "refused", "command": command, "reason": reason})
            )),
        };
        if let Err(err) = result {
            failed.get_or_insert(err);
        }
    })
    .map_err(sim_error)?;
    failed.map_or(Ok(()), Err)
}

fn sim_error(err: SystemError) -> CliError {
    match err {
        SystemError::Sim(err) => err.into(),
        SystemError::Link(err) => err.into(),
        SystemError::UnknownVertex(_) | SystemError::UnknownFault(_) => CliError::Usage(err.to_string()),
        SystemError::Read { .. } | SystemError::Dcf { .. } => CliError::InvalidInput(err.to_string()),
    }
}

//! `canopener serve` and `canopener demo --serve`: the configuration from the arguments, the address
//! (and token) printed once the server listens, Ctrl-C to stop (running tests stop as `canopener
//! test` stops on Ctrl-C: what the running test changed is written back).
//!
//! Exit status: 0 stopped by Ctrl-C, 2 bad arguments or an address that cannot be listened on, 3 a
//! system, DCF or token file that cannot be read, 5 `--data` that cannot be written. A bus that cannot
//! be opened is shown on the monitor page (the server keeps serving /check and /test).

use std::path::Path;

use canopener_web::{Ready, ServeConfig, ServeError, SystemConfig};

use crate::args::{bus_values, buses_by_network, split_bus};
use crate::error::{CliError, CliResult};
use crate::serve::args::ServeArgs;
use crate::stop::StopFlag;

pub(crate) fn run(args: ServeArgs) -> CliResult {
    let (system, buses) = match &args.nodelist {
        Some(file) => {
            let read = canopener_web::backend::System::read(file)
                .map_err(|e| CliError::InvalidInput(e.to_string()))?;
            let topology = read.topology();
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
            let specs =
                buses_by_network(&values, home, &topology.network_numbers()).map_err(CliError::Usage)?;
            let system = SystemConfig {
                file: file.clone(),
                at: args.at.clone(),
            };
            (Some(system), specs.into_iter().collect())
        }
        None => {
            let mut buses = Vec::new();
            for value in &args.buses {
                let (net, spec) = split_bus(value).map_err(CliError::Usage)?;
                buses.push((net.unwrap_or(1), spec.to_owned()));
            }
            (None, buses)
        }
    };
    let config = ServeConfig {
        listen: args.listen,
        system,
        buses,
        data: args.data,
        token_file: args.token_file,
        max_upload: args.max_upload,
    };
    let stop = StopFlag::install()?;
    canopener_web::serve(config, stop.token(), None, announce).map_err(serve_error)
}

/// `canopener demo --serve`: the tour's system written into `dir`, served.
pub(crate) fn demo(dir: &Path, listen: std::net::SocketAddr) -> CliResult {
    let (config, extra) = canopener_web::tour::prepare(dir, listen, None).map_err(serve_error)?;
    let stop = StopFlag::install()?;
    eprintln!(
        "the tour: a forwarder's two CANopen networks simulated from {}, a cable cut and repaired every {} s, \
         the demo's conformance runs in the history ({})",
        dir.join("system").display(),
        canopener_web::tour::CUT_FOR.as_secs(),
        dir.display()
    );
    canopener_web::serve(config, stop.token(), Some(extra), announce).map_err(serve_error)
}

fn announce(ready: &Ready) {
    println!("{}", ready.url);
    match &ready.token {
        Some(token) => eprintln!(
            "canopener serve: listening on {} with token {token} (open the address above); Ctrl-C stops",
            ready.address
        ),
        None => eprintln!("canopener serve: open {} in a browser; Ctrl-C stops", ready.url),
    }
}

fn serve_error(err: ServeError) -> CliError {
    match err {
        ServeError::Usage(_) | ServeError::Listen { .. } => CliError::Usage(err.to_string()),
        ServeError::Token(_) | ServeError::Backend(_) => CliError::InvalidInput(err.to_string()),
        ServeError::Store(_) | ServeError::Data { .. } => CliError::Output {
            context: "canopener serve".to_owned(),
            source: std::io::Error::other(err.to_string()),
        },
    }
}

//! `canopener net draw`: the system as an SVG drawing.

use canopener_files::write_atomic;

use crate::error::CliResult;
use crate::net::args::NetDrawArgs;
use crate::net::input::{read_system, refuse_overwrite};
use crate::output::print_stdout;

pub(crate) fn run(args: NetDrawArgs) -> CliResult {
    refuse_overwrite(args.output.as_deref(), &args.file)?;
    let system = read_system(&args.file)?;
    let svg = canopener_network::draw::svg(system.topology());
    match &args.output {
        Some(out) => Ok(write_atomic(out, svg.as_bytes(), false)?),
        None => print_stdout(&svg),
    }
}

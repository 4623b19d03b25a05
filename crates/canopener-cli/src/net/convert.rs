//! `canopener net convert`: nodelist.cpj ⇄ Nodelist.graphml, and DOT.

use canopener_files::write_atomic;
use canopener_network::convert::{Target, convert};

use crate::error::CliResult;
use crate::net::args::{NetConvertArgs, NetTarget};
use crate::net::input::{read_system, refuse_overwrite};
use crate::output::print_stdout;

pub(crate) fn run(args: NetConvertArgs) -> CliResult {
    refuse_overwrite(args.output.as_deref(), &args.file)?;
    let system = read_system(&args.file)?;
    let target = match args.to {
        NetTarget::Graphml => Target::Graphml,
        NetTarget::Cpj => Target::Cpj,
        NetTarget::Dot => Target::Dot,
    };
    let converted = convert(&system.loaded, target);
    for dropped in &converted.dropped {
        eprintln!("warning: nodelist.cpj cannot hold {dropped}; dropped");
    }
    match &args.output {
        Some(out) => Ok(write_atomic(out, converted.text.as_bytes(), false)?),
        None => print_stdout(&converted.text),
    }
}

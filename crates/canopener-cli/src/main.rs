//! The `canopener` binary: parses the command line, runs one command, maps its outcome to an exit code.
//!
//! This crate is the edge of the system: it owns the terminal (progress bars, colours, JSON output), signal
//! handling and process exit codes. Library crates below it never print or exit.

mod bus_decode;
mod bus_dump;
mod bus_gen;
mod bus_open;
mod bus_replay;
mod bus_send;
mod bus_serve;
mod cli;
mod cli_master;
mod demo;
mod eds_check;
mod eds_check_inputs;
mod eds_convert;
mod eds_diff;
mod eds_explain;
mod eds_fix;
mod eds_fmt;
mod eds_input;
mod eds_input_xdd;
mod eds_rules;
mod eds_show;
mod error;
mod heartbeat;
mod lss;
mod master_io;
mod monitor;
mod nmt;
mod node;
mod node_dump;
mod node_list;
mod node_scan;
mod output_file;
mod pdo;
mod pdo_watch;
mod sdo;
mod sdo_session;
mod sdo_typing;
mod sim;
mod sim_store;
mod stop;
mod sync;

use std::process::ExitCode;

use clap::Parser;

use crate::cli::{BusCommand, Cli, Command, EdsCommand, EdsRulesCommand};
use crate::cli_master::{HeartbeatCommand, LssCommand, NodeCommand, PdoCommand, SdoCommand};

use crate::error::{CliError, exit_code};

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(err) => {
            // clap prints help/version to stdout with exit 0 and usage errors to stderr with exit 2.
            let _ = err.print();
            return ExitCode::from(if err.use_stderr() {
                exit_code::USAGE
            } else {
                exit_code::SUCCESS
            });
        }
    };
    init_logging(cli.verbose);
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) if err.is_broken_pipe() => ExitCode::SUCCESS,
        Err(CliError::Exit(code)) => ExitCode::from(code),
        Err(err) => {
            eprintln!("error: {err}");
            ExitCode::from(err.exit_code())
        }
    }
}

fn run(cli: Cli) -> Result<(), CliError> {
    match cli.command {
        Command::Demo(args) => demo::run(args),
        Command::Bus(BusCommand::Serve(args)) => bus_serve::run(args),
        Command::Bus(BusCommand::Dump(args)) => bus_dump::run(args),
        Command::Bus(BusCommand::Send(args)) => bus_send::run(args),
        Command::Bus(BusCommand::Replay(args)) => bus_replay::run(args),
        Command::Bus(BusCommand::Gen(args)) => bus_gen::run(args),
        Command::Bus(BusCommand::Decode(args)) => bus_decode::run(args),
        Command::Eds(EdsCommand::Show(args)) => eds_show::run(args),
        Command::Eds(EdsCommand::Convert(args)) => eds_convert::run(args),
        Command::Eds(EdsCommand::Fmt(args)) => eds_fmt::run(args),
        Command::Eds(EdsCommand::Diff(args)) => eds_diff::run(args),
        Command::Eds(EdsCommand::Check(args)) => eds_check::run(args),
        Command::Eds(EdsCommand::Explain(args)) => eds_explain::run(args),
        Command::Eds(EdsCommand::Rules(EdsRulesCommand::List(args))) => eds_rules::list(args),
        Command::Eds(EdsCommand::Fix(args)) => eds_fix::run(args),
        Command::Sim(args) => sim::run(args),
        Command::Sdo(SdoCommand::Read(args)) => sdo::read(args),
        Command::Sdo(SdoCommand::Write(args)) => sdo::write(args),
        Command::Sdo(SdoCommand::Upload(args)) => sdo::upload(args),
        Command::Sdo(SdoCommand::Download(args)) => sdo::download(args),
        Command::Nmt(args) => nmt::run(args),
        Command::Node(NodeCommand::Info(args)) => node::info(args),
        Command::Node(NodeCommand::Scan(args)) => node::scan(args),
        Command::Node(NodeCommand::Dump(args)) => node::dump(args),
        Command::Lss(LssCommand::Scan(args)) => lss::scan(args),
        Command::Lss(LssCommand::Configure(args)) => lss::configure(args),
        Command::Lss(LssCommand::Inquire(args)) => lss::inquire(args),
        Command::Pdo(PdoCommand::Map(args)) => pdo::map(args),
        Command::Pdo(PdoCommand::Watch(args)) => pdo::watch(args),
        Command::Sync(args) => sync::run(args),
        Command::Heartbeat(HeartbeatCommand::Watch(args)) => heartbeat::watch(args),
    }
}

fn init_logging(verbose: u8) {
    let default = match verbose {
        0 => "warn",
        1 => "info",
        2 => "debug",
        _ => "trace",
    };
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(default));
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_target(false)
        .init();
}

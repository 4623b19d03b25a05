//! The `canopener` binary: parses the command line, runs one command, maps its outcome to an exit code.
//!
//! This crate is the edge of the system: it owns the terminal (progress bars, colours, JSON output), signal
//! handling and process exit codes. Library crates below it never print or exit.

// The binary is the terminal: it is where printing belongs.
#![allow(clippy::print_stdout, clippy::print_stderr)]

mod args;
mod bus;
mod bus_open;
mod cli;
mod demo;
mod eds;
mod error;
mod grammar;
mod master;
mod mbt;
mod net;
mod output;
mod serve;
mod sim;
mod stop;
mod test;

use std::process::ExitCode;

use clap::Parser;

use crate::bus::args::BusCommand;
use crate::cli::{Cli, Command};
use crate::eds::args::{EdsCommand, EdsRulesCommand};
use crate::master::args::{HeartbeatCommand, LssCommand, NodeCommand, PdoCommand, SdoCommand};
use crate::mbt::args::MbtCommand;
use crate::net::args::NetCommand;

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
        Command::Demo(args) if args.monitor => bus::session_replay::run(bus::args::SessionReplayArgs {
            bus: args.bus,
            speed: args.speed,
            format: args.format,
            quiet: args.quiet,
        }),
        Command::Demo(args) if args.serve => serve::command::demo(&args.dir, args.listen),
        Command::Demo(args) => demo::tour::run(args),
        Command::Serve(args) => serve::command::run(args),
        Command::Bus(BusCommand::Serve(args)) => bus::serve::run(args),
        Command::Bus(BusCommand::Dump(args)) => bus::dump::run(args),
        Command::Bus(BusCommand::Send(args)) => bus::send::run(args),
        Command::Bus(BusCommand::Replay(args)) => bus::replay::run(args),
        Command::Bus(BusCommand::Gen(args)) => bus::generate::run(args),
        Command::Bus(BusCommand::Decode(args)) => bus::decode::run(args),
        Command::Eds(EdsCommand::Show(args)) => eds::show::run(args),
        Command::Eds(EdsCommand::Convert(args)) => eds::convert::run(args),
        Command::Eds(EdsCommand::Fmt(args)) => eds::fmt::run(args),
        Command::Eds(EdsCommand::Diff(args)) => eds::diff::run(args),
        Command::Eds(EdsCommand::Check(args)) => eds::check::run(args),
        Command::Eds(EdsCommand::Explain(args)) => eds::explain::run(args),
        Command::Eds(EdsCommand::Rules(EdsRulesCommand::List(args))) => eds::rules::list(args),
        Command::Eds(EdsCommand::Fix(args)) => eds::fix::run(args),
        Command::Net(NetCommand::Check(args)) => net::check::run(args),
        Command::Net(NetCommand::Show(args)) => net::show::run(args),
        Command::Net(NetCommand::Convert(args)) => net::convert::run(args),
        Command::Net(NetCommand::Draw(args)) => net::draw::run(args),
        Command::Net(NetCommand::Monitor(args)) => net::monitor::run(args),
        Command::Sim(args) => sim::command::run(args),
        Command::Test(args) => test::command::run(args),
        Command::Sdo(SdoCommand::Read(args)) => master::sdo::read(args),
        Command::Sdo(SdoCommand::Write(args)) => master::sdo::write(args),
        Command::Sdo(SdoCommand::Upload(args)) => master::sdo::upload(args),
        Command::Sdo(SdoCommand::Download(args)) => master::sdo::download(args),
        Command::Nmt(args) => master::nmt::run(args),
        Command::Node(NodeCommand::Info(args)) => master::node::info(args),
        Command::Node(NodeCommand::Scan(args)) => master::node::scan(args),
        Command::Node(NodeCommand::Dump(args)) => master::node_dump::run(args),
        Command::Lss(LssCommand::Scan(args)) => master::lss::scan(args),
        Command::Lss(LssCommand::Configure(args)) => master::lss::configure(args),
        Command::Lss(LssCommand::Inquire(args)) => master::lss::inquire(args),
        Command::Pdo(PdoCommand::Map(args)) => master::pdo::map(args),
        Command::Pdo(PdoCommand::Watch(args)) => master::pdo_watch::run(args),
        Command::Sync(args) => master::sync::run(args),
        Command::Heartbeat(HeartbeatCommand::Watch(args)) => master::heartbeat::watch(args),
        Command::Mbt(MbtCommand::Models(args)) => mbt::inspect::models(args),
        Command::Mbt(MbtCommand::Check(args)) => mbt::inspect::check(args),
        Command::Mbt(MbtCommand::Explore(args)) => mbt::inspect::explore(args),
        Command::Mbt(MbtCommand::Synth(args)) => mbt::inspect::synth(args),
        Command::Mbt(MbtCommand::Run(args)) => mbt::run::run(args),
        Command::Mbt(MbtCommand::Replay(args)) => mbt::run::replay(args),
        Command::Mbt(MbtCommand::Shrink(args)) => mbt::run::shrink(args),
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

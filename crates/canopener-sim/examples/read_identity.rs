//! A new front end in fifty lines: two simulated devices from an EDS on a 1 Mbit/s virtual bus, and
//! the identity object 1018h of both read through SDO sessions.
//!
//! `cargo run -p canopener-sim --example read_identity [EDS]`; without an argument it takes a real
//! vendor's device from the corpus: Sevcon's Gen4 motor controller (vendor-ID 1Eh).

// An example front end: it prints what it read.
#![allow(clippy::print_stdout, clippy::print_stderr)]

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use canopener_can::Bitrate;
use canopener_link::sdo_session::SdoSession;
use canopener_sim::simulation::Simulation;
use canopener_testkit::corpus::{self, Kind};

const DEFAULT_EDS: &str = "brtiberio__Sevcon_gen4__Gen4.eds";
const NODES: [u8; 2] = [5, 6];
const IDENTITY: [(u8, &str); 4] = [
    (1, "vendor-ID"),
    (2, "product code"),
    (3, "revision number"),
    (4, "serial number"),
];

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("read_identity: {err}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let eds = match std::env::args_os().nth(1) {
        Some(path) => PathBuf::from(path),
        // The vendored corpus, else the extended one beside the checkout.
        None => corpus::find(Kind::Eds, DEFAULT_EDS)
            .ok_or_else(|| format!("{DEFAULT_EDS} is in neither corpus; give an EDS path"))?,
    };
    let mut bus = Simulation::bit_accurate(Bitrate::M1)
        .devices(&NODES.map(|node| (eds.as_path(), node)))
        // Distinct serial numbers, as two real devices of one type have.
        .serial(Some(1001))
        .start()?;
    println!("{} on node {NODES:?}", eds.display());
    for node in NODES {
        let mut session = SdoSession::new(&mut bus, node, Duration::from_millis(500))?;
        for (sub, name) in IDENTITY {
            let value = session.read(0x1018, sub)?;
            let number = u32::from_le_bytes(
                value
                    .try_into()
                    .map_err(|v| format!("1018h:{sub:02X} is {v:02X?}"))?,
            );
            println!("node {node} 1018h:{sub:02X} {name:<16} {number:08X}h");
        }
    }
    Ok(())
}

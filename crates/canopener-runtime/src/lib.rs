//! The runs of canopener's front ends: what a command of the CLI or the web server does between parsing
//! what the user asked and presenting what came back, when that is more than one call into a library.
//!
//! Talking to devices (links, sessions, master procedures) is `canopener-link`; simulating them
//! (simulated devices, systems, the EnergyBus system) is `canopener-sim`; writing files without losing
//! data is `canopener-files`. This crate composes them with the hub, the transports and the checkers.
//!
//! - [`clock`]: the calendar time a report states it was made at.
//! - [`mbt_run`]: model-based tests (`canopener-mbt`'s on-the-fly executor) on any link, and shrinking
//!   a failing run; [`mbt_sim`]: a run on a fresh simulated device, and the entries of its
//!   description a model is told to use (`--set`).
//! - [`energybus_graphs`]: the FORTE paper's EnergyBus test purposes as complete test graphs, run
//!   against the emulated system (`canopener_sim::energybus`).
//! - [`description`]: reading device descriptions (any format) and rule packs from files.
//! - [`batch`]: checking many description files: expanding directories and glob patterns, and
//!   checking the files in parallel.
//! - The `canopener bus` tools, raw frames on a transport: [`candump_file`] (candump logs on disk, read
//!   whole or written frame by frame), [`capture`] (receiving live traffic, optionally into a log),
//!   [`replay`] (recorded frames with their timing, scaled, or back to back), [`send`] (a list of
//!   frames, repeated, with a gap), [`generate`] (counting frames at a fixed rate or as fast as the bus
//!   takes them), [`hub`] (the socketcand hub served in the foreground until cancelled) and [`session_replay`]
//!   (the embedded CANopen session played and watched end to end, by default through an in-process
//!   hub).

#![warn(missing_docs)]
// A file or a frame must never panic this library: no unwrap, expect or unchecked index outside tests
// (as rustls does).
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)
)]

pub mod batch;
pub mod clock;
pub mod description;
pub mod energybus_graphs;
pub mod mbt_run;
pub mod mbt_sim;

pub mod candump_file;
pub mod capture;
pub mod generate;
pub mod hub;
mod pacing;
pub mod replay;
pub mod send;
pub mod session_replay;
#[cfg(test)]
mod test_support;

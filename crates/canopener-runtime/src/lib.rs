//! The runtime every canopener front end stands on.
//!
//! The protocol cores (`canopener-device`, `canopener-master`) are sans-IO: they never read a clock,
//! sleep, or touch a socket or a file. This crate is where that happens, besides the transports
//! (`canopener-transport`) and the hub (`canopener-hub`), so that a command-line tool, a test runner, a
//! network monitor or a web server only parse what the user asked and present what came back.
//!
//! - [`cancel`]: a cancellation token that a front end sets (Ctrl-C, a web request going away) and every
//!   long-running loop here polls.
//! - [`clock`]: the calendar time a report states it was made at.
//! - [`files`]: writing results without losing data (temporary file, rename, optional backup).
//! - [`link`]: the drive loop that moves frames between a bus and any sans-IO
//!   [`Core`](canopener_can::Core): [`link::BusLink`] on a transport and the wall clock,
//!   [`virtual_link::VirtualLink`] on a simulated bus and virtual time, the same API for both.
//! - [`sdo_session`]: blocking SDO transfers with progress and cancellation, on any link.
//! - [`candump_file`]: candump logs on disk, read whole or written frame by frame.
//! - [`capture`]: receiving live traffic for display, optionally into a candump log.
//! - [`replay`]: playing recorded frames onto a bus with their recorded timing, scaled, or back to back.
//! - [`send`]: sending a list of frames, repeated, with a gap.
//! - [`generate`]: generating counting frames at a fixed rate or as fast as the bus takes them.
//! - [`hub`]: the socketcand hub served in the foreground until cancelled, reporting its counters.
//! - [`demo`]: the embedded CANopen session played and watched end to end, by default through an
//!   in-process hub.
//! - [`simulator`]: simulated devices from EDS/DCF files, in-process on a virtual bus
//!   ([`simulator::simulation::Simulation`]) or on a real bus in real time ([`simulator::host::SimHost`]).
//! - [`state_store`]: the files in which simulated devices keep what they store across runs.
//! - The master procedures on a link, each the library form of a master command: [`node_info`],
//!   [`node_scan`], [`node_dump`], [`nmt_command`] (with confirmation), [`lss_session`], [`pdo_map`],
//!   [`pdo_watch`], [`sync_producer`] and [`heartbeat_watch`]. Their pure parts (plans, reports,
//!   statistics) are `canopener-master`'s.
//! - [`mbt_run`]: model-based tests (`canopener-mbt`'s on-the-fly executor) on any link;
//!   [`mbt_sim`]: a run on a fresh simulated device, and the entries of its description a model is
//!   told to use (`--set`).
//! - [`energybus`]: the emulated EnergyBus system (controller and devices) on a virtual bus or a real
//!   one, its boot and its telegrams.
//! - [`description`]: reading device descriptions (any format) and rule packs from files.
//! - [`batch`]: checking many description files: expanding directories and glob patterns, and
//!   checking the files in parallel.

#![warn(missing_docs)]

pub mod batch;
pub mod cancel;
pub mod clock;
pub mod description;
pub mod energybus;
pub mod files;
pub mod heartbeat_watch;
pub mod link;
pub mod lss_session;
pub mod mbt_run;
pub mod mbt_sim;
pub mod nmt_command;
pub mod node_dump;
pub mod node_info;
pub mod node_scan;
pub mod pdo_map;
pub mod pdo_watch;
pub mod sdo_session;
pub mod simulator;
pub mod state_store;
pub mod stimulus_program;
pub mod sync_producer;
pub mod system;
pub mod virtual_link;

pub mod candump_file;
pub mod capture;
pub mod demo;
pub mod generate;
pub mod hub;
mod pacing;
pub mod replay;
pub mod send;
#[cfg(test)]
mod test_support;

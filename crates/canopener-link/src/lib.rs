//! Talking to CANopen devices: the drive loop that moves frames between a bus and a sans-IO core, the
//! SDO and LSS sessions, and the master procedures, on a real bus on the wall clock or on a simulated
//! bus on virtual time, with the same API for both.
//!
//! The protocol cores (`canopener-master`, `canopener-device`) never read a clock or touch a socket;
//! this crate is where their frames meet a bus and their timeouts meet a clock.
//!
//! - [`link`]: the drive loop that moves frames between a bus and any sans-IO
//!   [`Core`](canopener_can::Core): [`link::BusLink`] on a transport and the wall clock,
//!   [`virtual_link::VirtualLink`] on a simulated bus and virtual time.
//! - [`cancel`]: the cancellation token that a front end sets (Ctrl-C, a web request going away) and
//!   every long-running loop polls.
//! - [`sdo_session`]: blocking SDO transfers with progress and cancellation, on any link.
//! - [`lss_session`]: LSS (CiA 305) configuration and scans on any link.
//! - The master procedures, each the library form of a master command: [`node_info`], [`node_scan`],
//!   [`node_dump`], [`nmt_command`] (with confirmation), [`pdo_map`], [`pdo_watch`],
//!   [`sync_producer`] and [`heartbeat_watch`]. Their pure parts (plans, reports, statistics) are
//!   `canopener-master`'s.
//! - [`system_watch`]: the system monitor (`canopener-network`) on one or more links.
//! - [`stimulus_program`]: the user's program that changes a device's inputs on a test rig.

#![warn(missing_docs)]
// A file or a frame must never panic this library: no unwrap, expect or unchecked index outside tests
// (as rustls does).
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)
)]

pub mod cancel;
pub mod heartbeat_watch;
pub mod link;
pub mod lss_session;
pub mod nmt_command;
pub mod node_dump;
pub mod node_info;
pub mod node_scan;
pub mod pdo_map;
pub mod pdo_watch;
pub mod sdo_session;
pub mod stimulus_program;
pub mod sync_producer;
pub mod system_watch;
pub mod virtual_link;

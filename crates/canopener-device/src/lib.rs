//! The device side of CANopen: sans-IO protocol cores (CiA 301, CiA 305) on a runtime object
//! dictionary built from an EDS or DCF.
//!
//! Every core follows one shape: `handle_frame(now, &frame)` and `handle_timeout(now)` feed it,
//! `poll_transmit()`, `poll_event()` and `poll_timeout()` drain it. No core reads a clock, sleeps or
//! touches a socket: time arrives as [`canopener_can::Instant`], so tests run on virtual time.

#![warn(missing_docs)]
// A file or a frame must never panic this library: no unwrap, expect or unchecked index outside tests
// (as rustls does); each exception names, where it stands, why it cannot fail.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)
)]

pub mod application;
pub mod can_id;
pub mod cia401;
pub mod device;
pub mod emcy;
pub mod energybus;
pub mod faults;
pub mod heartbeat;
pub mod lss_slave;
pub mod nmt_slave;
pub mod od_build;
pub mod pdo;
pub mod sdo_server;
pub mod store;
pub mod sync;
pub mod time_stamp;

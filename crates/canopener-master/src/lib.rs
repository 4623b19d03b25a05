//! The master side of CANopen as sans-IO client cores (CiA 301, CiA 305).
//!
//! Every core here follows the same discipline as `canopener-device`: frames and the current time go
//! in (`handle_frame(now, &frame)`, `handle_timeout(now)`), frames, events and the next deadline come out
//! (`poll_transmit()`, `poll_event()`, `poll_timeout()`). Nothing here opens a socket, starts a thread or
//! reads a clock; `canopener-link` drives the cores over a real bus or on virtual time.
//!
//! The cores share the frame codecs of `canopener-wire` with the device side, but no state.

#![warn(missing_docs)]
// A file or a frame must never panic this library: no unwrap, expect or unchecked index outside tests
// (as rustls does); each exception names, where it stands, why it cannot fail.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)
)]

pub mod dcf_dump;
pub mod emcy_consumer;
pub mod energybus_controller;
pub mod error_control;
pub mod heartbeat_core;
pub mod lss_master;
pub mod nmt_confirmation;
pub mod nmt_master;
pub mod node_info;
pub mod node_scan;
pub mod pdo_config;
pub mod pdo_decode;
pub mod pdo_map_report;
pub mod pdo_watch;
pub mod sdo_client;
pub mod statistics;
pub mod sync_producer;
pub mod sync_stats;
pub mod time_producer;
pub mod value;
pub mod value_typing;

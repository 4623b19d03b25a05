//! A socketcand-compatible CAN hub: python-can (`interface="socketcand"`) and canopener clients share
//! named buses (`can0`, `can1`, …) over TCP, on machines without SocketCAN.
//!
//! This crate is IO code: it owns sockets, a tokio runtime and the wall clock (frames are stamped with
//! the hub's receive time, as socketcand stamps them with the kernel's). The protocol itself lives in
//! the sans-IO `canopener-socketcand` codec.
//!
//! Behaviour, following socketcand and the python-can traps in the interop reference §3:
//! - Handshake `< hi >`, `< open NAME >` → `< ok >`, `< rawmode >` → `< ok >`, each reply in its own
//!   write with TCP_NODELAY. After the raw-mode `< ok >` bus traffic is held back (queued, not dropped)
//!   for [`HubConfig::raw_grace`], so python-can never reads `< ok >< frame …` in one `recv`.
//! - A frame from a client reaches every other raw-mode client on the same bus, in one total order per
//!   bus, never the sender unless [`HubConfig::echo`].
//! - Lossless with bounded memory: each client has a queue of [`HubConfig::client_queue`] frames.
//!   A full queue slows the senders on that bus; a client that leaves it full, or does not finish a
//!   write, for [`HubConfig::stall_timeout`] is dropped and the others carry on.
//! - Garbage, half elements, over-long elements and unknown commands are logged (rate-limited) and
//!   dropped. The hub never sends `< error … >` after `open`, because python-can in raw mode dies on it.
//!
//! Main items: [`Hub`] (async: [`Hub::bind`], [`Hub::run`]), [`spawn`] and [`HubHandle`] (own runtime
//! on a thread, for sync callers), [`HubConfig`], [`HubStats`].
//!
//! ```no_run
//! # fn main() -> std::io::Result<()> {
//! let hub = canopener_hub::spawn(canopener_hub::HubConfig::new("127.0.0.1:29536".parse().unwrap()))?;
//! println!("python-can: interface='socketcand', host='127.0.0.1', port={}", hub.local_addr().port());
//! println!("frames so far: {}", hub.stats().frames_in);
//! hub.shutdown();
//! # Ok(())
//! # }
//! ```

#![warn(missing_docs)]
// A file or a frame must never panic this library: no unwrap, expect or unchecked index outside tests
// (as rustls does).
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)
)]

mod bus;
mod config;
mod connection;
mod hub;
mod log_limit;
mod stats;

pub use config::HubConfig;
pub use hub::{HUB_THREAD_NAME, Hub, HubHandle, spawn};
pub use stats::{HubStats, HubStatsHandle};

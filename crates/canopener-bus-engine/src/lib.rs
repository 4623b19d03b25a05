//! A virtual classical CAN bus: arbitration by identifier and bit-exact frame timing.
//!
//! [`BusEngine`] models what a saturated or idle CAN wire does with the frames its nodes want to send:
//! each [`Port`] queues frames, the lowest arbitration field wins when the bus goes idle, and a frame
//! occupies exactly as many bit times as its real stuffed bit sequence has
//! ([`canopener_can::bits::frame_bits`]). Each frame comes out once, as a [`Delivery`] with the instant
//! its SOF started and the instant receivers have it.
//!
//! This crate does no IO: no sockets, no threads, no sleeping and no clock reads. Time is an
//! [`canopener_can::Instant`] passed in by whoever drives the engine, so the same engine runs
//! deterministic tests on virtual time and, fed the wall clock by a background thread, the real-time
//! `virtual:NAME?bitrate=…` bus of the transport crate. It does not model error frames, bit errors,
//! bus-off or ACK-less sending; every frame is received.
//!
//! Main types: [`BusEngine`] (the engine), [`BusConfig`], [`Port`], [`Delivery`], [`BusStats`] and
//! [`SubmitError`].
//!
//! # The drive loop
//!
//! On virtual time the driver jumps straight to the next deadline; a real-time driver sleeps until
//! the deadline (or until a node hands over a frame) and passes the clock's `now` instead.
//!
//! ```
//! use canopener_can::{Bitrate, CanFrame, Instant, StandardId};
//! use canopener_bus_engine::{BusConfig, BusEngine};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let mut bus = BusEngine::new(BusConfig { bitrate: Bitrate::K500 });
//! let master = bus.attach();
//! let device = bus.attach();
//! let id = |raw| StandardId::new(raw).ok_or("bad id");
//!
//! // Both nodes hand over a frame at t = 0: node 0x22's SDO upload request (0x622) wins
//! // against the heartbeat of node 0x22 (0x722).
//! bus.submit(Instant::ZERO, device, CanFrame::new(id(0x722)?, &[0x05])?)?;
//! bus.submit(Instant::ZERO, master, CanFrame::new(id(0x622)?, &[0x40, 0x08, 0x10, 0, 0, 0, 0, 0])?)?;
//!
//! let mut received = Vec::new();
//! while let Some(deadline) = bus.poll_timeout() {
//!     bus.handle_timeout(deadline);
//!     while let Some(delivery) = bus.poll_delivery() {
//!         // Every port but the sender receives the frame; the sender takes it as TX confirmation.
//!         for port in bus.ports().filter(|&port| port != delivery.from) {
//!             received.push((port, delivery.frame.id().as_raw(), delivery.at));
//!         }
//!     }
//! }
//! // This upload request is 122 bits long, so at 2 µs per bit receivers have it at 119 bits = 238 µs;
//! // the heartbeat starts when the bus is free at 244 µs.
//! assert_eq!(received[0], (device, 0x622, Instant::from_micros(238)));
//! assert_eq!(received[1].1, 0x722);
//! assert_eq!(bus.stats().frames, 2);
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

mod engine;
pub mod virtual_bus;

pub use engine::{BusConfig, BusEngine, BusStats, Delivery, Port, SubmitError};

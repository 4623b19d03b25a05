//! CAN 2.0 building blocks shared by every other canopener crate.
//!
//! This crate is pure data and arithmetic: it performs no IO and never reads a clock.
//! Time arrives from the caller as an [`Instant`]; durations are [`std::time::Duration`].
//!
//! Main types:
//! - [`CanId`] (with [`StandardId`] and [`ExtendedId`]): an 11- or 29-bit identifier whose `Ord` is
//!   the bus arbitration order (the smaller value wins arbitration).
//! - [`CanFrame`]: a classical CAN data or remote frame with DLC 0–8.
//! - [`Instant`]: a point in time in nanoseconds since an epoch chosen by whoever drives the code.
//! - [`Core`]: the sans-IO surface of every protocol core (frames and time in, frames, events and a
//!   deadline out).
//! - [`Bitrate`] and [`bits`]: the exact on-wire bit sequence and duration of a frame (CRC-15, bit
//!   stuffing), which the bus simulator and the bus-load figures are built on.

#![warn(missing_docs)]
// A file or a frame must never panic this library: no unwrap, expect or unchecked index outside tests
// (as rustls does); each exception names, where it stands, why it cannot fail.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)
)]

mod bitrate;
pub mod bits;
pub mod candump;
mod frame;
mod id;
mod sans_io;
#[cfg(any(test, feature = "_proptest"))]
pub mod strategy;
mod time;

pub use bitrate::{Bitrate, BitrateError};
pub use frame::{CanFrame, FrameError, MAX_CLASSIC_DATA_LEN};
pub use id::{CanId, ExtendedId, IdError, StandardId};
pub use sans_io::Core;
pub use time::Instant;

//! Model-based testing of CANopen devices.
//!
//! A model is a text file describing timed extended state machines whose labels are CAN frames
//! (see `models/README.md`). This crate reads it ([`syntax`]), compiles and checks it
//! ([`compile`]), explores its state space and exports it as Aldebaran `.aut` or DOT
//! ([`explore`], [`aut`]), and tests a device against it on the fly with ioco and timed quiescence
//! ([`executor`]): a sans-IO state machine that takes frames and time in and gives frames and a
//! verdict out. It never reads a clock, sleeps or touches a file: the runtime drives it.

#![warn(missing_docs)]
// A file or a frame must never panic this library: no unwrap, expect or unchecked index outside tests
// (as rustls does).
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)
)]

pub mod agreement;
pub mod aut;
pub mod compile;
pub mod compose;
pub(crate) mod device_facts;
pub mod diagnostics;
pub mod executor;
pub mod explore;
pub mod expr;
pub mod label;
pub mod log;
pub mod model;
pub mod purpose;
pub mod shipped;
pub mod shrink;
pub mod syntax;
pub mod synth;

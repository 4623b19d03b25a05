//! Simulated CANopen devices built from EDS/DCF descriptions, in-process on a simulated bus or on a
//! real bus in real time.
//!
//! - [`plan`]: loading descriptions and giving every device its node-ID.
//! - [`device`]: [`SimulatedDevice`](device::SimulatedDevice), one device with its faults, its store and
//!   its TIME production as a sans-IO core.
//! - [`simulation`]: [`Simulation`](simulation::Simulation), N devices on a virtual bus in one expression,
//!   which is a [`Link`](crate::link::Link) for sessions and drive loops.
//! - [`host`]: [`SimHost`](host::SimHost), the devices on a real bus on the wall clock (`canopener sim`).
//! - [`event_log`]: what the devices' events mean, in the same words for every front end.
//! - [`error`]: what can go wrong, [`SimError`](error::SimError).

pub mod device;
pub mod error;
pub mod event_log;
pub mod host;
pub mod plan;
pub mod simulation;

#[cfg(test)]
mod test_support;

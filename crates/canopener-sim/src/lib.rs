//! Simulating CANopen devices and systems: devices built from EDS/DCF descriptions, whole networks
//! from a topology file, and the emulated EnergyBus system, each in-process on a simulated bus on
//! virtual time or on a real bus in real time. Everything here is a [`Link`](canopener_link::link::Link)
//! or is driven on one, so the sessions, procedures and test runs that talk to real devices talk to
//! these the same way.
//!
//! - [`plan`]: loading descriptions and giving every device its node-ID.
//! - [`device`]: [`SimulatedDevice`](device::SimulatedDevice), one device with its faults, its store and
//!   its TIME production as a sans-IO core.
//! - [`simulation`]: [`Simulation`](simulation::Simulation), N devices on a virtual bus in one expression,
//!   which is a [`Link`](canopener_link::link::Link) for sessions and drive loops.
//! - [`host`]: [`SimHost`](host::SimHost), the devices on a real bus on the wall clock (`canopener sim`).
//! - [`event_log`]: what the devices' events mean, in the same words for every front end.
//! - [`error`]: what can go wrong, [`SimError`](error::SimError).
//! - [`state_store`]: the files in which simulated devices keep what they store across runs.
//! - [`system`]: CANopen systems (nodelist.cpj, Nodelist.graphml) simulated wiring-aware, with cut
//!   cables, dead devices and supply domains off, in-process or on real buses.
//! - [`energybus`]: the emulated EnergyBus system (controller and devices) on a virtual bus or a real
//!   one, its boot and its telegrams.

#![warn(missing_docs)]
// A file or a frame must never panic this library: no unwrap, expect or unchecked index outside tests
// (as rustls does).
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)
)]

pub mod device;
pub mod energybus;
pub mod error;
pub mod event_log;
pub mod host;
pub mod plan;
pub mod simulation;
pub mod state_store;
pub mod system;

#[cfg(test)]
mod test_support;

//! The emulated EnergyBus system (CiA 454), as the FORTE paper's framework emulated it (seeds/003
//! §5.4): the EnergyBus controller at node-ID 1 (`canopener_master::energybus_controller`) and N
//! emulated EnergyBus devices (`canopener_device::energybus`) on one bus.
//!
//! - [`system`]: the stations as one core type, [`system::EnergyBusSystem`] (the system in one
//!   expression, on virtual time), its boot until every device is Operating with the telegrams it
//!   took ([`system::boot`]), and the system ready for a tester ([`system::ready_for_test`]: booted,
//!   the device under test handed over by the controller).
//! - [`telegrams`]: every frame decoded with the bus decoder, and the EMS objects named.
//! - [`serve`]: the system on a real bus, in real time.
//!
//! The FORTE paper's test purposes run against this system are model-based test runs:
//! `canopener_runtime::energybus_graphs`.

pub mod serve;
pub mod system;
pub mod telegrams;

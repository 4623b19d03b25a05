//! CANopen systems described by nodelist.cpj or Nodelist.graphml (`canopener-network`), on files and
//! buses: reading a topology with its DCFs ([`files`]), simulating it wiring-aware with cut cables,
//! dead devices and supply domains off ([`sim`]), and watching it with the system monitor on one or
//! more links ([`watch`]); [`serve`] puts a simulated system on real buses in real time.

pub mod files;
pub mod serve;
pub mod sim;
pub mod watch;

//! CANopen systems described by nodelist.cpj or Nodelist.graphml (`canopener-network`), on files and
//! buses: reading a topology with its DCFs ([`files`]), simulating it wiring-aware with cut cables,
//! dead devices and supply domains off ([`sim`]); [`serve`] puts a simulated system on real buses in
//! real time. Watching a system with the system monitor is `canopener_link::system_watch`.

pub mod files;
pub mod serve;
pub mod sim;

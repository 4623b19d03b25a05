//! The `sim` command: simulated devices on a real bus, from EDS/DCF files or a whole system from its
//! topology (`--nodelist`).

pub(crate) mod args;
pub(crate) mod command;
pub(crate) mod energybus;
pub(crate) mod nodelist;

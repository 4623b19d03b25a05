//! `canopener sim`: simulated devices on a bus.

pub(crate) mod args;
pub(crate) mod command;

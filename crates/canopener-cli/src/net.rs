//! The `net` commands: check, show, convert, draw and monitor CANopen systems described by
//! nodelist.cpj or Nodelist.graphml.

pub(crate) mod args;
pub(crate) mod check;
pub(crate) mod convert;
pub(crate) mod draw;
pub(crate) mod input;
pub(crate) mod monitor;
pub(crate) mod show;
pub(crate) mod tui;

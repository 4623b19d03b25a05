//! The master procedures of the link crate against real device cores on a simulated bus, on virtual
//! time: the way the CLI runs them on a real bus, and the way the conformance runner will test them.

mod common;
mod lss;
mod nmt_heartbeat;
mod node;
mod pdo_map;
mod pdo_watch;
mod sync;

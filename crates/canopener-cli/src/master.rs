//! The master commands: `sdo`, `nmt`, `node`, `lss`, `pdo`, `sync` and `heartbeat`.

pub(crate) mod args;
pub(crate) mod heartbeat;
pub(crate) mod link;
pub(crate) mod lss;
pub(crate) mod nmt;
pub(crate) mod node;
pub(crate) mod node_dump;
pub(crate) mod output;
pub(crate) mod pdo;
pub(crate) mod pdo_watch;
pub(crate) mod sdo;
pub(crate) mod sync;

//! The `bus` commands (serve, dump, send, replay, gen, decode) and `demo`.

pub(crate) mod args;
pub(crate) mod decode;
pub(crate) mod dump;
pub(crate) mod generate;
pub(crate) mod monitor;
pub(crate) mod replay;
pub(crate) mod send;
pub(crate) mod serve;
pub(crate) mod session_replay;

//! `canopener demo`: the product tour (a simulated CiA 401 device checked and tested, clean and with a
//! fault, the HTML reports written), and with `--monitor` the decoded 4-node session of `bus/session_replay.rs`.

pub(crate) mod args;
pub(crate) mod tour;

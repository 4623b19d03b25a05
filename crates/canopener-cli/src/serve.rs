//! `canopener serve`: the web front end (`canopener-web`) started from the command line, and the
//! tour's `demo --serve`.

pub(crate) mod args;
pub(crate) mod command;

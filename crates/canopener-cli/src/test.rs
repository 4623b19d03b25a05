//! `canopener test`: the conformance suites of `canopener-conformance` against one device on a bus.

pub(crate) mod args;
pub(crate) mod command;

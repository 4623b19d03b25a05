//! The `eds` commands: show, convert, fmt, diff, check, explain, rules and fix.

pub(crate) mod args;
pub(crate) mod check;
pub(crate) mod convert;
pub(crate) mod diff;
pub(crate) mod explain;
pub(crate) mod fix;
pub(crate) mod fmt;
pub(crate) mod input;
pub(crate) mod rules;
pub(crate) mod show;

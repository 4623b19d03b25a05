//! The EDS/DCF checker: every CiA 306/301 check of the check catalogue (`docs/check-catalogue.md`,
//! numbered after `eds-format-and-checks.md` §10), a portability lint
//! that predicts how other tools misread a file, comparison with shipped CiA 301/401 reference
//! profiles, and safe fixes that leave every untouched line byte-identical.
//!
//! Layers, each depending only on the ones above it:
//! - [`CheckInfo`]: what a check is (stable code, severity, clause, explanation);
//! - [`Context`]: one loaded file with section lookup and spans, handed to every check;
//! - the check modules, one per catalogue group, each describing and running its own checks;
//! - [`registry`]: every check's description, assembled from the check modules;
//! - [`check`]: runs the selected checks and returns [`Finding`]s;
//! - [`fix`]: turns fixable findings (and rule-pack fixes) into line edits;
//! - [`value_rules`]: the CiA 301 value ranges of the rule table, for testers that write values to a
//!   device rather than read them from a file.
//!
//! This crate performs no IO: callers pass a loaded file in and get findings out.

#![warn(missing_docs)]
// A file or a frame must never panic this library: no unwrap, expect or unchecked index outside tests
// (as rustls does); each exception names, where it stands, why it cannot fail.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)
)]

mod canchkeds;
mod check_info;
mod context;
mod finding;
pub mod registry;
mod run;

mod checks;
pub mod portability;
pub mod profile;
pub mod value_rules;

pub mod fix;

pub use check_info::{CheckDescription, CheckInfo, Group};
pub use context::{Context, Place};
pub use finding::{Finding, sort_by_position};
pub use run::{FileCheck, Selection, check, check_context};

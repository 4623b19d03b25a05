//! The EDS/DCF checker: every CiA 306/301 check of `eds-format-and-checks.md` §10, a portability lint
//! that predicts how other tools misread a file, comparison with shipped CiA 301/401 reference
//! profiles, and safe fixes that leave every untouched line byte-identical.
//!
//! Layers:
//! - [`registry`]: what each check is ([`CheckInfo`]: stable code, severity, explanation);
//! - [`Context`]: one loaded file with section lookup and spans, handed to every check;
//! - [`check`]: runs the selected checks and returns [`Finding`]s;
//! - [`fix`]: turns fixable findings (and rule-pack fixes) into line edits.
//!
//! This crate performs no IO: callers pass a loaded file in and get findings out.

#![warn(missing_docs)]

mod context;
mod finding;
pub mod registry;
mod run;

mod group_a;
mod group_b;
mod group_c;
mod group_d;
mod group_e;
mod group_f;
mod group_g;
mod group_h;
mod group_i;
mod group_j;
mod group_k;
mod parse_codes;
pub mod portability;
pub mod profile;

pub mod fix;

pub use context::Context;
pub use finding::Finding;
pub use registry::{CheckDescription, CheckInfo, Group};
pub use run::{FileCheck, Selection, check};

//! Test support shared by canopener's crates (`publish = false`; never a dependency of a library).
//!
//! - [`trace`]: drives one sans-IO [`Core`](canopener_can::Core) on virtual time and records what it
//!   sends and reports as a timestamped trace.
//! - [`frames`]: proptest strategies for frames a CANopen core meets.
//! - [`corpus`]: where the EDS/XDD corpus is: the files vendored in the repository, and the optional
//!   extended corpus next to the checkout.

#![warn(missing_docs)]

pub mod corpus;
pub mod frames;
pub mod trace;

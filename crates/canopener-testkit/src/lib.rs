//! Test support shared by canopener's crates (`publish = false`; never a dependency of a library).
//!
//! - [`trace`]: drives one sans-IO [`Core`](canopener_can::Core) on virtual time and records what it
//!   sends and reports as a timestamped trace.
//! - [`net`]: many cores on one simulated bus on virtual time (the runtime's network loop), every frame
//!   recorded as a trace line; [`cores!`] makes one core type of several kinds.
//! - [`frames`]: proptest strategies for frames a CANopen core meets.
//! - [`hostile`]: devices that answer with junk (empty, short, random, echoed, on another node's
//!   CAN-ID, babbling, flooding, or as a fuzzer's bytes say), and a junk node beside a correct device.
//! - [`fixture`]: the file system as tests of sans-IO crates may use it (the workspace bans it there).
//! - [`browser`]: headless Chromium for the tests of HTML pages (DOM dumps, screenshots).
//! - [`corpus`]: where the EDS/XDD corpus is: the files vendored in the repository, and the optional
//!   extended corpus next to the checkout.

#![warn(missing_docs)]
// Test support reports on the test's own output (a corpus file skipped, and why).
#![allow(clippy::print_stdout, clippy::print_stderr)]

pub mod browser;
pub mod corpus;
pub mod fixture;
pub mod frames;
pub mod hostile;
pub mod net;
pub mod trace;

/// What [`cores!`] expands to refers to; not part of the API.
#[doc(hidden)]
pub mod __private {
    pub use canopener_can::{CanFrame, Core, Instant};
}

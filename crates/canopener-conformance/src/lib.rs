//! Conformance test suites for CANopen devices: point them at a device on any
//! [`Link`](canopener_link::link::Link) (a real bus on the wall clock, or simulated devices on
//! virtual time) with its EDS, and get a verdict per test with the evidence.
//!
//! - [`test_def`]: what a test is (stable id, title, CiA and CCT references, the precondition it takes
//!   from the EDS); [`catalogue`]: every suite's tests assembled, selection by suite, id and tag.
//! - [`cct`]: the CCT 3.0.3.10 cases, how canopener covers each (covered, partial, different) and
//!   the tests that perform them.
//! - [`procedures`]: what the suites share (refusal verdicts, NMT resets, TPDO set-up, an LSS master);
//!   a suite never uses another suite (`tests/layering.rs`).
//! - [`cia301`]: the CiA 301 device test (designed from CiA 301, covering the CCT's cases; see
//!   `docs/conformance.md` for the mapping and what is not covered yet).
//! - [`cia305`]: the CiA 305 (LSS) device test.
//! - [`cia313`]: the CiA 313-style performance test (response times, cycle times, heartbeat
//!   deviation) judged by [`performance::criteria`].
//! - [`runner`]: runs a selection against one node, keeps each test's telegrams, restores what a test
//!   changed and leaves the device in pre-operational between tests.
//! - [`model`]: the report every suite fills (verdicts, telegrams, measurements with raw samples and
//!   statistics); its JSON form is version 1 of the documented report.
//! - [`render`]: the human summary, the HTML page with plots, JUnit XML and candump telegram logs.
//! - [`tour`]: the product tour of `canopener demo` (a bundled CiA 401 device, clean and with a fault).
//! - [`device_model`]: what the EDS says the device is; [`requirements`]: clauses and accepted abort
//!   codes; [`junk`]: frames no correct device sends, which keep a test from passing.
//!
//! Everything here is sans-IO apart from the link it is given: no clocks, no files.
#![warn(missing_docs)]
// Whatever a device sends, the runner must not panic (issue 22): no unwrap, expect, panic! or unchecked
// index outside tests (as rustls does); each exception names, where it stands, why it cannot fail.
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

pub mod catalogue;
pub mod cct;
pub mod cia301;
pub mod cia305;
pub mod cia313;
pub mod cia401;
pub mod context;
pub mod device_model;
pub mod finding;
pub mod junk;
pub mod model;
pub mod performance;
pub mod procedures;
pub mod recorder;
pub mod render;
pub mod requirements;
pub mod runner;
pub mod stimulus;
pub mod test_def;
pub mod tour;

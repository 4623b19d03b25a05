//! `canopener serve`: a local web application over canopener's libraries, in the same binary.
//!
//! - `/` (also `/monitor`): the system monitor on the machine's drawing (the `net draw` engine with
//!   the Nodelist.graphml `Background` and `NodeFig` pictures), live device states, the diagnosis
//!   drawn on the picture, an event log; pushed by server-sent events (`/api/events`: exactly the
//!   JSON events of `canopener net monitor --format json`), `/api/state` the current state.
//! - `/check`: a dropped EDS, DCF, XDD or XDC checked as `canopener eds check --format json` checks
//!   it, with the safe fixes as a diff and a download.
//! - `/test`: conformance runs on a configured bus or a simulated device, live verdicts, the HTML
//!   report at the end, the history in SQLite (`--data DIR`) with run-to-run comparison.
//!
//! The crate holds no protocol logic: every call into the runtime goes through [`backend`]. The page
//! contract and the API are documented in `docs/web.md`.

// A file or a frame must never panic this library: no unwrap, expect or unchecked index outside tests
// (as rustls does).
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)
)]

pub mod access;
pub mod assets;
pub mod backend;
pub mod check;
pub mod compare;
pub mod events;
pub mod monitor;
pub mod pages;
pub mod runs;
pub mod server;
pub mod store;
pub mod tour;
pub mod upload;

pub use server::{Ready, ServeConfig, ServeError, SystemConfig, serve};

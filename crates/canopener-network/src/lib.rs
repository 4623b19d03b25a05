//! CANopen systems: which networks there are, which devices sit on them with which node-IDs and
//! DCFs, how they are wired, and where a cable broke when some of them fall silent.
//!
//! - [`model`]: the system ([`Topology`]) every format reads into.
//! - [`cpj`]: CiA 306-3 nodelist.cpj, read through the lossless EDS syntax layer and written.
//! - [`graphml`]: Nodelist.graphml (the TUT/Sandvik proposal), read losslessly (unknown keys and
//!   other tools' markup kept) and written; networkx and yEd files read.
//! - [`codes`]: the `N` diagnostic codes, in the shared diagnostic shape of `canopener-eds`.
//! - [`check`]: the checks of `canopener net check`.
//! - [`convert`]: cpj ⇄ GraphML (naming what cpj cannot hold) and DOT.
//! - [`draw`]: the SVG drawing.
//! - [`wiring`]: each network's cable graph with every device as a leaf, and [`localise`]: which
//!   cable, device or supply explains a set of silent devices.
//! - [`monitor`]: the sans-IO system monitor: heartbeats in, device states and diagnoses out.
//!
//! No IO: bytes and text in, models, text and events out.

#![warn(missing_docs)]
// A file or a frame must never panic this library: no unwrap, expect or unchecked index outside tests
// (as rustls does).
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)
)]

pub mod check;
pub mod codes;
pub mod convert;
pub mod cpj;
pub mod draw;
pub mod graphml;
pub mod localise;
pub mod model;
pub mod monitor;
pub mod read;
pub mod vocabulary;
pub mod wiring;

pub use codes::{NetCode, NetDiagnostic};
pub use model::{Attachment, Cable, Format, Network, Topology, Vertex, VertexKind};
pub use read::{Loaded, load};

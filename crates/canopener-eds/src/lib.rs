//! CiA 306 EDS and DCF files: read every real-world file faithfully, say precisely where it departs
//! from the specification, and write it back without destroying anything.
//!
//! Layers:
//! - [`lines`]: the one rule for lines and columns every report counts by (EDS text and XML alike);
//! - [`syntax`]: the lossless [`Document`] (every byte kept, with line/column spans) and line edits;
//! - [`model`]: the object dictionary [`Eds`] built by [`load`], with [`Diagnostic`]s;
//! - [`value`]: typed values in every CiA 306 notation, `$NODEID` formulas kept symbolic.
//!
//! This crate performs no IO: callers pass bytes in and get bytes out.
//!
//! ```
//! let text = "[FileInfo]\nFileName=demo.eds\n[1017]\nParameterName=Producer heartbeat time\n\
//!             DataType=0x0006\nAccessType=rw\nDefaultValue=0x3E8\n";
//! let loaded = canopener_eds::load(text.as_bytes());
//! let value = loaded.eds.default_value(0x1017, None).and_then(|v| v.resolve(1));
//! assert_eq!(value, Some(1000));
//! assert_eq!(loaded.document.to_bytes().unwrap(), text.as_bytes());
//! ```

#![warn(missing_docs)]
// A file or a frame must never panic this library: no unwrap, expect or unchecked index outside tests
// (as rustls does); each exception names, where it stands, why it cannot fail.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)
)]

pub mod dcf;
pub mod diag;
pub mod diff;
pub mod json;
pub mod lines;
mod load;
pub mod model;
pub mod section_name;
pub mod syntax;
pub mod text;
pub mod types;
pub mod value;
pub mod write;
pub mod xml_text;

pub use diag::{Code, Diagnostic, DiagnosticCode, Severity, Span};

pub use load::{Loaded, build, load, model_diagnostics};
pub use model::{Attributes, Eds, Object, ObjectListKind, Origin, SubObject};
/// For [`diagnostic_codes!`]: the codes it defines serialise as their code string.
#[doc(hidden)]
pub use serde;
pub use syntax::Document;
pub use types::{AccessType, DataType, ObjectType, TypeKind};
pub use value::Value;

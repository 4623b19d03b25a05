//! Device descriptions in every format canopener reads, conversion between them, and the check
//! pipeline: what every front end (the command line, a test runner, a web service) does with a
//! description once it has the bytes.
//!
//! - [`Format`]: EDS/DCF (CiA 306), XDD/XDC (CiA 311) or canopener's JSON form, told apart by
//!   the file's extension and then by its first character;
//! - [`Description`]: a loaded description of any format (the model, the lossless document for
//!   EDS/DCF, and what loading found, in the shared diagnostic shape with [`DescriptionCode`]);
//! - [`convert`]: canonical EDS, DCF for a node, XDD/XDC and JSON from a loaded description;
//! - [`Checker`]: the built-in checks and rule packs in force, turning a file's bytes into a
//!   [`canopener_report::FileReport`] and applying safe fixes. CiA 311 XML ([`Format::is_xml`],
//!   by content first) is read by the XDD reader: its `X` findings, the model-level checks that
//!   [`applies_to_xml`] keeps and the rule packs, each placed at the XML element or attribute that
//!   gave the value (`docs/xdd-check.md`).
//!
//! This crate performs no IO: callers pass bytes in and get descriptions, bytes and reports out.
//! Reading files, expanding directories and checking many files in parallel is
//! `canopener-runtime`'s job.
//!
//! ```
//! use canopener_description::{Description, Format};
//!
//! let text = b"[FileInfo]\nFileName=demo.eds\n[1017]\nParameterName=Producer heartbeat time\n\
//!     ObjectType=0x7\nDataType=0x0006\nAccessType=rw\nDefaultValue=1000\nPDOMapping=0\n";
//! let description = Description::load(Some("eds"), text).expect("EDS text always loads");
//! assert_eq!(description.format, Format::Eds);
//! assert!(description.document.is_some());
//! assert!(description.eds.objects.contains_key(&0x1017));
//! ```

#![warn(missing_docs)]
// A file or a frame must never panic this library: no unwrap, expect or unchecked index outside tests
// (as rustls does); each exception names, where it stands, why it cannot fail.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)
)]

mod checker;
pub mod convert;
mod description;
mod format;

pub use checker::{Checker, SUPERSEDED, UnknownCheck, applies_to_xml};
pub use description::{Description, DescriptionCode, LoadError};
pub use format::Format;

/// Re-exported: which checks a [`Checker`] reports, and how a check is described.
pub use canopener_check::{CheckDescription, Selection};

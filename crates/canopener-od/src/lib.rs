//! The runtime object dictionary of a CANopen device: entries kept sorted by index and sub-index in
//! an array of fixed capacity, found by binary search, read and written with the checks of an SDO
//! server (CiA 301 §7.4 object dictionary, §7.2.4.3.17 SDO abort codes).
//!
//! This crate holds data only: it performs no IO, reads no clock and starts no threads. It knows
//! nothing about frames or EDS files; the EDS model builds [`Entry`] values from object
//! descriptions and the device simulator serves SDO and PDO traffic from a [`DynamicOd`].
//!
//! Main types:
//! - [`DynamicOd`]: the dictionary. Fixed capacity chosen up front, O(log n) lookup, O(n) insert
//!   and remove, all sub-indices of an object as one slice ([`DynamicOd::object`]).
//! - [`Entry`]: a value of a [`DataType`] at an [`ObjectKey`], stored as CANopen little-endian bytes,
//!   with its [`Access`], `PDOMapping`, [`ObjFlags`] and optional limits.
//! - [`OdError`]: why an access failed; [`OdError::abort_code`] is the SDO abort code to send.
//!
//! ```
//! use canopener_od::{Access, DataType, DynamicOd, Entry, ObjectKey};
//!
//! let mut od = DynamicOd::with_capacity(64);
//! od.insert(Entry::new(ObjectKey::new(0x1000, 0), DataType::UNSIGNED32, Access::Ro, &[0x91, 0x01, 0, 0])?)?;
//! let setpoint = Entry::new(ObjectKey::new(0x2000, 1), DataType::INTEGER16, Access::Rww, &[0, 0])?
//!     .with_pdo_mapping(true)
//!     .with_limits(Some(&(-100i16).to_le_bytes()), Some(&100i16.to_le_bytes()))?;
//! od.insert(setpoint)?;
//!
//! // What an SDO server does with an incoming download:
//! let refused = od.write(ObjectKey::new(0x2000, 1), &500i16.to_le_bytes());
//! assert_eq!(refused.map_err(|err| err.abort_code()), Err(0x0609_0031)); // value too high
//! assert_eq!(od.object(0x2000).len(), 1);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]
// A file or a frame must never panic this library: no unwrap, expect or unchecked index outside tests
// (as rustls does); each exception names, where it stands, why it cannot fail.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)
)]

mod access;
mod data_type;
mod entry;
mod error;
mod key;
mod number;
mod obj_flags;
mod od;
mod value;

pub use access::{Access, ParseAccessError};
pub use data_type::{DataType, TypeKind};
pub use entry::{Entry, EntryError, EntryMut};
pub use error::OdError;
pub use key::ObjectKey;
pub use number::Number;
pub use obj_flags::ObjFlags;
pub use od::{DynamicOd, MAX_ENTRIES};

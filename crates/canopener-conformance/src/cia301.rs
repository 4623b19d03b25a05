//! The CiA 301 device test: every test designed from CiA 301 (and CiA 306 for what the EDS
//! promises), grouped as the CCT groups its cases. `docs/conformance.md` maps each id to the CCT
//! case it covers and lists the CCT cases not covered yet.
//!
//! Every test leaves the device as it found it: values are changed through
//! [`Ctx::modify`](crate::context::Ctx::modify) and written back by the runner, which then puts the
//! device into pre-operational.

pub mod consumer;
pub mod eds;
pub mod error_control;
pub mod nmt;
pub mod nmt_pdo;
pub mod nmt_resets;
pub mod nmt_services;
pub mod object_dictionary;
pub mod pdo;
pub mod pdo_mapping;
pub mod pdo_transmission;
pub mod sdo;
pub mod store;
pub mod sync;

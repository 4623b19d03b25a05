//! Procedures the suites share, below every suite: a suite uses these and never another suite, so
//! a test can be read with this module and its own file open. Nothing here decides a test's
//! verdict by itself except the refusal and confirmation checks in [`sdo`].

pub mod emcy;
pub mod entries;
pub mod intervals;
pub mod lss;
pub mod nmt;
pub mod sdo;
pub mod tpdo;

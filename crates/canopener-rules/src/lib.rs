//! User rule packs for the EDS checker.

//! Nodelist.graphml: the [`document`] layer (every element as written), [`read`] into the system
//! model, and [`build`] a document from a model.

pub mod build;
pub mod document;
pub mod read;

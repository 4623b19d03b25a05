//! `canopener mbt`: model-based testing: shipped and own behaviour models, their static checks and
//! state spaces, and on-the-fly runs against a device on a bus or a simulated one.

pub(crate) mod args;
pub(crate) mod inspect;
pub(crate) mod load;
pub(crate) mod run;
pub(crate) mod seeds;

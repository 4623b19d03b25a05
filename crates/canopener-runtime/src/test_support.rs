//! What the unit tests share: endpoints on a private in-process bus, and scratch directories (the
//! test kit's).

use canopener_transport::{BusSpec, CanBus, open};

/// Two endpoints on the ideal virtual bus `name` (at most 16 characters; unique per test, since virtual
/// buses are shared by name within the process).
pub(crate) fn virtual_pair(name: &str) -> (Box<dyn CanBus>, Box<dyn CanBus>) {
    let spec: BusSpec = format!("virtual:{name}")
        .parse()
        .expect("a valid virtual bus name");
    (
        open(&spec).expect("a virtual endpoint"),
        open(&spec).expect("a virtual endpoint"),
    )
}

pub(crate) use canopener_testkit::fixture::ScratchDir;

//! proptest strategies for CAN values, shared by the property tests of every crate.
//!
//! Enabled by the private `_proptest` feature (dev-dependencies only) and in this crate's own tests.
//! Crates that want a bias (few ids so arbitration ties happen, CANopen ids so decoders get exercised)
//! pass their own id strategy to [`frame_with_id`].
#![allow(
    clippy::expect_used,
    reason = "test support only (the `_proptest` feature): the ranges keep every value valid, so nothing here can fail"
)]

use proptest::prelude::*;

use crate::{CanFrame, CanId, ExtendedId, MAX_CLASSIC_DATA_LEN, StandardId};

/// Any 11-bit identifier.
pub fn any_standard_id() -> impl Strategy<Value = CanId> + Clone {
    (0..=StandardId::MAX.as_raw()).prop_map(|raw| CanId::Standard(StandardId::new(raw).expect("11 bits")))
}

/// Any 29-bit identifier.
pub fn any_extended_id() -> impl Strategy<Value = CanId> + Clone {
    (0..=ExtendedId::MAX.as_raw()).prop_map(|raw| CanId::Extended(ExtendedId::new(raw).expect("29 bits")))
}

/// Standard and extended identifiers, half and half.
pub fn any_id() -> impl Strategy<Value = CanId> + Clone {
    prop_oneof![any_standard_id(), any_extended_id()]
}

/// Data frames (0–8 random bytes) and, one time in five, remote frames with any DLC, on ids from `id`.
pub fn frame_with_id(id: impl Strategy<Value = CanId> + Clone) -> impl Strategy<Value = CanFrame> {
    // The ranges keep every frame valid, so the constructors cannot fail here.
    prop_oneof![
        4 => (id.clone(), prop::collection::vec(any::<u8>(), 0..=MAX_CLASSIC_DATA_LEN))
            .prop_map(|(id, data)| CanFrame::new(id, &data).expect("at most 8 bytes")),
        1 => (id, 0..=MAX_CLASSIC_DATA_LEN as u8)
            .prop_map(|(id, dlc)| CanFrame::remote(id, dlc).expect("DLC at most 8")),
    ]
}

/// Any classical frame on any identifier.
pub fn any_frame() -> impl Strategy<Value = CanFrame> {
    frame_with_id(any_id())
}

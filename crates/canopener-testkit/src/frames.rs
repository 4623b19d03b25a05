//! proptest strategies for the frames a CANopen core meets on a bus.

use canopener_can::{CanFrame, StandardId};
use proptest::prelude::*;

/// Any classical frame with an 11-bit identifier, weighted towards the CANopen services (NMT,
/// SYNC/EMCY, heartbeat), with remote frames of any DLC now and then.
pub fn any_frame() -> impl Strategy<Value = CanFrame> {
    let id = prop_oneof![0u16..0x800, Just(0), 0x700u16..0x780, 0x80u16..0x100];
    (id, any::<bool>(), proptest::collection::vec(any::<u8>(), 0..=8)).prop_map(|(id, remote, data)| {
        let id = StandardId::new(id).expect("11-bit id");
        if remote {
            CanFrame::remote(id, data.len() as u8).expect("dlc <= 8")
        } else {
            CanFrame::new(id, &data).expect("<= 8 bytes")
        }
    })
}

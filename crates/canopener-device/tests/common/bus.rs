//! What the device and fault tests share: their fixture files and the testkit's virtual-time trace of
//! one device (time advanced by its deadlines, what it sends recorded as `"<ms>.<µs> <frame>"`).

use std::path::Path;
use std::sync::LazyLock;

use canopener_can::Instant;
use canopener_device::device::Device;
use canopener_od::ObjectKey;
use canopener_testkit::trace::Trace;
pub(crate) use canopener_testkit::trace::ms;

pub(crate) const BASE: &str = canopener_testkit::fixture::BASE_EDS;
pub(crate) static DS301: LazyLock<String> = LazyLock::new(|| {
    canopener_testkit::corpus::eds("CANopenNode__CANopenNode__example__DS301_profile.eds")
        .display()
        .to_string()
});

pub(crate) fn eds(path: impl AsRef<Path>) -> canopener_eds::model::Eds {
    canopener_eds::load(&canopener_testkit::fixture::read(path).expect("EDS file")).eds
}

/// A device on virtual time with what it sends recorded as `"<ms>.<µs> <frame>"`: the shared
/// single-core harness of `canopener-testkit`.
pub(crate) type Bus = Trace<Device>;

/// `dev` powered on at time zero (its boot-up message is the first frame of the trace).
pub(crate) fn booted(mut dev: Device) -> Bus {
    dev.boot(Instant::ZERO);
    let mut bus = Trace::new(dev);
    bus.drain();
    bus
}

/// What the device tests ask of a traced device beyond frames and events.
pub(crate) trait DeviceBus {
    /// The value of `index`:`sub` in the device's object dictionary.
    fn value(&self, index: u16, sub: u8) -> Vec<u8>;
}

impl DeviceBus for Bus {
    fn value(&self, index: u16, sub: u8) -> Vec<u8> {
        self.core
            .od()
            .read(ObjectKey::new(index, sub))
            .expect("readable")
            .to_vec()
    }
}

/// An expedited SDO download request to `node` as compact candump text.
pub(crate) fn download(node: u8, index: u16, sub: u8, data: &[u8]) -> String {
    let command = 0x23 | ((4 - data.len() as u8) << 2);
    let mut bytes = vec![command, index as u8, (index >> 8) as u8, sub];
    bytes.extend_from_slice(data);
    bytes.resize(8, 0);
    let hex: String = bytes.iter().map(|b| format!("{b:02X}")).collect();
    format!("{:03X}#{hex}", 0x600 + u16::from(node))
}

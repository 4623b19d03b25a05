//! The virtual-time harness shared by the device and fault tests: a device on its own, time advanced
//! by its deadlines, what it sends recorded as `"<ms>.<µs> <frame>"`.

use std::path::Path;
use std::sync::LazyLock;

use canopener_can::Core;
use canopener_can::candump::parse_compact_frame;
use canopener_can::{CanFrame, Instant};
use canopener_device::device::{Device, DeviceEvent};
use canopener_od::ObjectKey;

pub(crate) const BASE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../canopener-check/test_data/checks/base.eds"
);
pub(crate) static DS301: LazyLock<String> = LazyLock::new(|| {
    canopener_testkit::corpus::eds("CANopenNode__CANopenNode__example__DS301_profile.eds")
        .display()
        .to_string()
});

pub(crate) fn eds(path: impl AsRef<Path>) -> canopener_eds::model::Eds {
    canopener_eds::load(&std::fs::read(path).expect("EDS file")).eds
}

/// Drives a device on virtual time and records what it sends as `"<ms>.<µs> <frame>"`.
pub(crate) struct Bus {
    pub(crate) dev: Device,
    pub(crate) now: Instant,
    pub(crate) out: Vec<String>,
    pub(crate) events: Vec<DeviceEvent>,
}

impl Bus {
    pub(crate) fn booted(dev: Device) -> Bus {
        let mut bus = Bus {
            dev,
            now: Instant::ZERO,
            out: Vec::new(),
            events: Vec::new(),
        };
        bus.dev.boot(Instant::ZERO);
        bus.drain();
        bus
    }

    pub(crate) fn drain(&mut self) {
        while let Some(frame) = self.dev.poll_transmit() {
            let micros = self.now.as_micros();
            self.out
                .push(format!("{}.{:03} {frame}", micros / 1000, micros % 1000));
        }
        while let Some(event) = self.dev.poll_event() {
            self.events.push(event);
        }
    }

    pub(crate) fn advance(&mut self, until_ms: u64) {
        let until = Instant::from_millis(until_ms);
        self.drain();
        while let Some(due) = self.dev.poll_timeout() {
            if due > until {
                break;
            }
            assert!(due >= self.now, "timer in the past");
            self.now = due;
            self.dev.handle_timeout(due);
            self.drain();
        }
        self.now = until;
    }

    pub(crate) fn rx(&mut self, at_ms: u64, text: &str) {
        self.advance(at_ms);
        let frame: CanFrame = parse_compact_frame(text).expect("test frame");
        self.dev.handle_frame(self.now, &frame);
        self.drain();
    }

    pub(crate) fn sent(&mut self) -> Vec<String> {
        self.drain();
        std::mem::take(&mut self.out)
    }

    pub(crate) fn events(&mut self) -> Vec<DeviceEvent> {
        self.drain();
        std::mem::take(&mut self.events)
    }

    pub(crate) fn value(&self, index: u16, sub: u8) -> Vec<u8> {
        self.dev
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

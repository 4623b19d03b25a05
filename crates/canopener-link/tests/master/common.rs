//! Devices and misbehaving stand-ins on a simulated bus.

use std::collections::VecDeque;

use canopener_bus_engine::virtual_bus::{StationId, Timing};
use canopener_can::{CanFrame, Core, Instant, StandardId};
use canopener_device::application::NoApplication;
use canopener_device::device::Device;
use canopener_link::virtual_link::VirtualLink;
use canopener_od::ObjectKey;
use canopener_testkit::corpus;

/// CANopenNode's example I/O device: CiA 301 communication objects, four TPDOs, 1008h as text.
pub(crate) const IO_EDS: &str = "CANopenNode__CANopenNode__example__IO.eds";

/// The checker's base EDS: TPDO1 only, with a one-entry mapping.
pub(crate) const BASE_EDS: &str = canopener_testkit::fixture::BASE_EDS;

/// The EDS `name` of the corpus, or a path.
pub(crate) fn eds(name: &str) -> canopener_eds::Eds {
    let path = if name.starts_with('/') {
        std::path::PathBuf::from(name)
    } else {
        corpus::eds(name)
    };
    canopener_eds::load(&canopener_testkit::fixture::read(path).expect("EDS file")).eds
}

/// A booted device of `eds` with node-ID `node`.
pub(crate) fn device(eds_name: &str, node: u8) -> Device {
    let mut device = Device::from_eds(&eds(eds_name), node, Box::new(NoApplication)).expect("device");
    device.boot(Instant::ZERO);
    device
}

/// How a node on the test bus behaves.
pub(crate) enum Node {
    /// As the device core does.
    Device(Box<Device>),
    /// A device that stops answering SDO requests after the first `answered` ones.
    SilentAfter {
        /// The device.
        device: Box<Device>,
        /// How many requests it still answers.
        answered: usize,
    },
    /// Answers every SDO request to node 5 (except aborts) with a 3-byte frame.
    Garbage(VecDeque<CanFrame>),
}

type DeviceEvent = <Device as Core>::Event;

impl Core for Node {
    type Event = DeviceEvent;

    fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
        match self {
            Node::Device(device) => device.handle_frame(now, frame),
            Node::SilentAfter { device, answered } => {
                if frame.id().as_raw() == 0x605 {
                    if *answered == 0 {
                        return;
                    }
                    *answered -= 1;
                }
                device.handle_frame(now, frame);
            }
            Node::Garbage(replies) => {
                if frame.id().as_raw() == 0x605 && frame.data().first() != Some(&0x80) {
                    let id = StandardId::new(0x585).expect("id");
                    replies.push_back(CanFrame::new(id, &[0x60, 0x00, 0x18]).expect("frame"));
                }
            }
        }
    }

    fn handle_timeout(&mut self, now: Instant) {
        match self {
            Node::Device(device) | Node::SilentAfter { device, .. } => device.handle_timeout(now),
            Node::Garbage(_) => {}
        }
    }

    fn poll_transmit(&mut self) -> Option<CanFrame> {
        match self {
            Node::Device(device) | Node::SilentAfter { device, .. } => device.poll_transmit(),
            Node::Garbage(replies) => replies.pop_front(),
        }
    }

    fn poll_event(&mut self) -> Option<DeviceEvent> {
        match self {
            Node::Device(device) | Node::SilentAfter { device, .. } => device.poll_event(),
            Node::Garbage(_) => None,
        }
    }

    fn poll_timeout(&self) -> Option<Instant> {
        match self {
            Node::Device(device) | Node::SilentAfter { device, .. } => device.poll_timeout(),
            Node::Garbage(_) => None,
        }
    }
}

/// A bus on ideal timing with `nodes`, recording from the start.
pub(crate) fn bus(nodes: Vec<Node>) -> (VirtualLink<Node>, Vec<StationId>) {
    let mut link = VirtualLink::new(Timing::Ideal);
    link.virtual_bus_mut().record();
    let stations = nodes.into_iter().map(|node| link.attach(node)).collect();
    (link, stations)
}

/// The frames recorded since the last call as `"<ms> <frame>"`, only those on `ids`.
pub(crate) fn trace(link: &mut VirtualLink<Node>, ids: &[u32]) -> Vec<String> {
    link.virtual_bus_mut()
        .take_recording()
        .iter()
        .filter(|f| ids.contains(&f.frame.id().as_raw()))
        .map(|f| format!("{} {}", f.at.as_micros() / 1000, f.frame))
        .collect()
}

/// The value of `index`:`sub` in the device at `station`.
pub(crate) fn value(link: &VirtualLink<Node>, station: StationId, index: u16, sub: u8) -> Vec<u8> {
    let device = match link.virtual_bus().node(station) {
        Some(Node::Device(device) | Node::SilentAfter { device, .. }) => device,
        _ => panic!("no device at {station:?}"),
    };
    device
        .od()
        .get(ObjectKey::new(index, sub))
        .expect("entry")
        .value()
        .to_vec()
}

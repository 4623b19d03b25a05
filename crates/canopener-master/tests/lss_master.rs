//! The LSS master against LSS-unconfigured `Device`s on one virtual bus: fastscan finds every
//! device, gives it a node-ID, and the devices boot with it (CiA 305 with CiA 301 boot-up).

use std::time::Duration;

use canopener_bus_engine::virtual_bus::{BusFrame, StationId, Timing};
use canopener_can::Instant;
use canopener_device::application::NoApplication;
use canopener_device::device::{self, Device};
use canopener_device::nmt_slave::NmtSlaveState;
use canopener_master::lss_master::{
    KnownParts, LssConfig, LssEvent, LssMaster, LssMode, LssService, LssServiceError, ScanPlan, node_id_range,
};
use canopener_od::ObjectKey;
use canopener_testkit::net::Net;
use canopener_wire::LssAddress;
use canopener_wire::{LssAddressPart, NodeId};

const BASE: &str = canopener_testkit::fixture::BASE_EDS;

/// The identity of `base.eds` (1018h:01..03); the serial number is set per device.
const VENDOR_ID: u32 = 0x0000_0ABC;
const PRODUCT_CODE: u32 = 0x0000_0401;
const REVISION_NUMBER: u32 = 0x0001_0002;

/// One 8-byte frame takes about 1 ms on a 125 kbit/s bus.
const FRAME_TIME: Duration = Duration::from_millis(1);

fn unconfigured_device(serial_number: u32) -> Device {
    let eds = canopener_eds::load(&canopener_testkit::fixture::read(BASE).expect("base.eds")).eds;
    Device::from_eds(&eds, device::UNCONFIGURED, Box::new(NoApplication))
        .expect("device")
        .with_value(ObjectKey::new(0x1018, 4), &serial_number.to_le_bytes())
        .expect("serial number")
}

fn address(serial_number: u32) -> LssAddress {
    LssAddress {
        vendor_id: VENDOR_ID,
        product_code: PRODUCT_CODE,
        revision_number: REVISION_NUMBER,
        serial_number,
    }
}

fn node(raw: u8) -> NodeId {
    NodeId::new(raw).expect("node-ID")
}

/// The master and the devices on the test harness's virtual bus: every frame anyone sends reaches
/// every other participant one frame time later; timers run after the frames due at the same instant.
struct Bus {
    net: Net<Device>,
    devices: Vec<StationId>,
    master: LssMaster,
    /// Every frame delivered, with its delivery time and sender.
    wire: Vec<BusFrame>,
    events: Vec<LssEvent>,
}

impl Bus {
    fn new(devices: Vec<Device>) -> Bus {
        let mut net = Net::new(Timing::Delayed(FRAME_TIME));
        let devices = devices
            .into_iter()
            .map(|mut dev| {
                dev.boot(Instant::ZERO);
                net.attach(dev)
            })
            .collect();
        Bus {
            net,
            devices,
            master: LssMaster::new(LssConfig::DEFAULT),
            wire: Vec::new(),
            events: Vec::new(),
        }
    }

    fn now(&self) -> Instant {
        self.net.now()
    }

    fn device(&self, index: usize) -> &Device {
        self.net.node(self.devices[index])
    }

    /// Runs until the master is idle and nothing is in flight, or until `limit`.
    fn run(&mut self, limit: Duration) {
        let limit = self.now() + limit;
        let events = self
            .net
            .drive(&mut self.master, limit, |master, _| master.running().is_none());
        assert!(
            self.master.running().is_none(),
            "the bus did not settle before {limit}"
        );
        self.events.extend(events);
        self.net.events();
        self.wire.extend(self.net.bus_frames());
    }

    /// The frames devices sent on CAN-IDs other than LSS, as `(device, frame)`.
    fn device_frames(&self) -> Vec<(usize, String)> {
        self.wire
            .iter()
            .filter(|seen| seen.frame.id().as_raw() != 0x7E4)
            .filter_map(|seen| {
                let index = self.devices.iter().position(|dev| *dev == seen.from)?;
                Some((index, seen.frame.to_string()))
            })
            .collect()
    }

    fn take_events(&mut self) -> Vec<LssEvent> {
        std::mem::take(&mut self.events)
    }
}

fn ones(address: LssAddress) -> u64 {
    [
        LssAddressPart::VendorId,
        LssAddressPart::ProductCode,
        LssAddressPart::RevisionNumber,
        LssAddressPart::SerialNumber,
    ]
    .iter()
    .map(|part| u64::from(address.part(*part).count_ones()))
    .sum()
}

#[test]
fn fastscan_finds_three_unconfigured_devices_and_they_boot_with_the_node_ids_given() {
    let serials = [0x0000_0303, 0x0000_0101, 0x0000_0202];
    let mut bus = Bus::new(serials.into_iter().map(unconfigured_device).collect());
    // Unconfigured devices are silent.
    bus.run(Duration::from_secs(1));
    assert!(bus.wire.is_empty());

    let start = bus.now();
    let plan = ScanPlan {
        node_ids: node_id_range(node(0x20), node(0x2F)),
        store: true,
        known: KnownParts::NONE,
    };
    bus.master.scan_all(start, plan).expect("scan starts");
    bus.run(Duration::from_secs(60));

    // The smallest address first: only the serial numbers differ.
    assert_eq!(
        bus.take_events(),
        [
            LssEvent::Found {
                address: address(0x101),
                node_id: Some(node(0x20))
            },
            LssEvent::Found {
                address: address(0x202),
                node_id: Some(node(0x21))
            },
            LssEvent::Found {
                address: address(0x303),
                node_id: Some(node(0x22))
            },
            LssEvent::ScanFinished { found: 3 },
        ]
    );
    // Devices 1, 2, 0 (serial 101h, 202h, 303h) booted with 20h, 21h, 22h.
    assert_eq!(
        bus.device_frames(),
        [
            (1, "720#00".to_owned()),
            (2, "721#00".to_owned()),
            (0, "722#00".to_owned())
        ]
    );
    for (index, raw) in [0x22, 0x20, 0x21].into_iter().enumerate() {
        let dev = bus.device(index);
        assert!(dev.is_configured());
        assert_eq!(dev.node_id(), node(raw));
        assert_eq!(dev.state(), NmtSlaveState::PreOperational);
    }

    // Per device: probe, 4 × (32 bit steps + confirmation), configure node-ID, store, switch state
    // global; then one probe nobody answers. Each 1 bit of a found address costs a timeout.
    let timeouts = serials.iter().map(|serial| ones(address(*serial))).sum::<u64>() + 1;
    let waits = 3 * (1 + 4 * 33 + 2) + 1;
    let stats = bus.master.stats();
    assert_eq!(stats.sent, waits + 3);
    assert_eq!(stats.timeouts, timeouts);
    assert_eq!(stats.silence, Duration::from_millis(100) * timeouts as u32);
    // Several devices answer the probe and the shared leading bits.
    let answered = waits - timeouts;
    assert!(stats.received > answered, "{stats:?}");
    // The scan took the silence, plus 2 frame times and the 20 ms settle time per answered request.
    let expected = stats.silence + (FRAME_TIME * 2 + Duration::from_millis(20)) * answered as u32;
    assert_eq!(bus.now() - start, expected);

    // Nobody is left unconfigured.
    let now = bus.now();
    bus.master.identify_non_configured(now).expect("identify");
    bus.run(Duration::from_secs(1));
    assert_eq!(
        bus.take_events(),
        [LssEvent::Identified {
            service: LssService::IdentifyNonConfiguredRemoteSlave,
            answers: 0
        }]
    );
}

#[test]
fn known_vendor_and_product_need_fewer_frames() {
    let serial = 0x0000_1234;
    let known = KnownParts {
        vendor_id: Some(VENDOR_ID),
        product_code: Some(PRODUCT_CODE),
        ..KnownParts::NONE
    };
    let mut counts = Vec::new();
    for known in [KnownParts::NONE, known] {
        let mut bus = Bus::new(vec![unconfigured_device(serial)]);
        let plan = ScanPlan {
            node_ids: vec![node(7)],
            store: false,
            known,
        };
        bus.master.scan_all(bus.now(), plan).expect("scan starts");
        bus.run(Duration::from_secs(60));
        assert_eq!(
            bus.take_events(),
            [
                LssEvent::Found {
                    address: address(serial),
                    node_id: Some(node(7))
                },
                LssEvent::ScanFinished { found: 1 },
            ]
        );
        assert_eq!(bus.device_frames(), [(0, "707#00".to_owned())]);
        counts.push((bus.master.stats(), bus.now()));
    }
    let (full, full_time) = counts[0];
    let (matched, matched_time) = counts[1];
    // Full: probe, 4 × 33, configure node-ID, switch state global, final probe.
    assert_eq!(full.sent, 1 + 4 * 33 + 2 + 1);
    // Known vendor-ID and product code: one confirmation each instead of 33 frames.
    assert_eq!(matched.sent, 1 + 2 + 2 * 33 + 2 + 1);
    let scanned_ones = u64::from(REVISION_NUMBER.count_ones()) + u64::from(serial.count_ones());
    assert_eq!(matched.timeouts, scanned_ones + 1);
    assert_eq!(matched.received, 1 + 2 + (2 * 33 - scanned_ones) + 1);
    assert_eq!(full.timeouts, ones(address(serial)) + 1);
    assert!(matched_time < full_time, "{matched_time} >= {full_time}");
}

#[test]
fn configuration_services_against_a_device() {
    fn step(bus: &mut Bus, service: &dyn Fn(&mut LssMaster, Instant)) -> Vec<LssEvent> {
        let now = bus.now();
        service(&mut bus.master, now);
        bus.run(Duration::from_secs(5));
        bus.take_events()
    }
    let serial = 0x00C0_FFEE;
    let mut bus = Bus::new(vec![unconfigured_device(serial)]);
    assert_eq!(
        step(&mut bus, &|m, now| m.identify_non_configured(now).unwrap()),
        [LssEvent::Identified {
            service: LssService::IdentifyNonConfiguredRemoteSlave,
            answers: 1
        }]
    );
    // A selection that matches nobody, then the device's address.
    assert_eq!(
        step(&mut bus, &|m, now| m
            .switch_state_selective(now, address(serial + 1))
            .unwrap()),
        [LssEvent::TimedOut {
            service: LssService::SwitchStateSelective,
            after: Duration::from_millis(100)
        }]
    );
    assert_eq!(
        step(&mut bus, &|m, now| m
            .switch_state_selective(now, address(serial))
            .unwrap()),
        [LssEvent::Done {
            service: LssService::SwitchStateSelective
        }]
    );
    assert_eq!(
        step(&mut bus, &|m, now| m
            .inquire_address(now, LssAddressPart::SerialNumber)
            .unwrap()),
        [LssEvent::Inquired {
            part: LssAddressPart::SerialNumber,
            value: serial
        }]
    );
    assert_eq!(
        step(&mut bus, &|m, now| m.inquire_node_id(now).unwrap()),
        [LssEvent::NodeIdInquired { node_id: 0xFF }]
    );
    assert_eq!(
        step(&mut bus, &|m, now| m.configure_node_id_raw(now, 0).unwrap()),
        [LssEvent::Configured {
            service: LssService::ConfigureNodeId,
            result: Err(LssServiceError::NodeIdOutOfRange)
        }]
    );
    assert_eq!(
        step(&mut bus, &|m, now| m
            .configure_node_id(now, Some(node(5)))
            .unwrap()),
        [LssEvent::Configured {
            service: LssService::ConfigureNodeId,
            result: Ok(())
        }]
    );
    // The device does not claim automatic bit rate detection.
    assert_eq!(
        step(&mut bus, &|m, now| m.configure_bit_timing(now, 9).unwrap()),
        [LssEvent::Configured {
            service: LssService::ConfigureBitTiming,
            result: Err(LssServiceError::BitRateNotSupported)
        }]
    );
    assert_eq!(
        step(&mut bus, &|m, now| m.configure_bit_timing(now, 3).unwrap()),
        [LssEvent::Configured {
            service: LssService::ConfigureBitTiming,
            result: Ok(())
        }]
    );
    assert_eq!(
        step(&mut bus, &|m, now| m.store_configuration(now).unwrap()),
        [LssEvent::Configured {
            service: LssService::StoreConfiguration,
            result: Ok(())
        }]
    );
    // Still unconfigured until the switch back to waiting; then it boots as node 5.
    assert!(bus.device_frames().is_empty());
    assert_eq!(
        step(&mut bus, &|m, _| m.switch_state_global(LssMode::Waiting).unwrap()),
        [LssEvent::Done {
            service: LssService::SwitchStateGlobal
        }]
    );
    assert_eq!(bus.device_frames(), [(0, "705#00".to_owned())]);
    assert_eq!(bus.device(0).node_id(), node(5));
}

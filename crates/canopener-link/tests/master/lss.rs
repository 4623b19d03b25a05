//! `lss_session`: CiA 305 sequences against unconfigured devices.

use canopener_can::Instant;
use canopener_device::application::NoApplication;
use canopener_device::device::{Device, UNCONFIGURED};
use canopener_device::faults::{Fault, FaultSet};
use canopener_link::lss_session::{LssError, LssSession, ScanOutcome};
use canopener_link::virtual_link::VirtualLink;
use canopener_master::lss_master::{KnownParts, LssConfig, ScanPlan};
use canopener_od::ObjectKey;
use canopener_wire::{LssAddress, NodeId};

use crate::common::{IO_EDS, Node, bus, eds};

/// An LSS-unconfigured I/O device with serial number `serial`.
fn unconfigured(serial: u32) -> Node {
    unconfigured_with(serial, FaultSet::none())
}

/// [`unconfigured`] with the defects `faults`.
fn unconfigured_with(serial: u32, faults: FaultSet) -> Node {
    let mut device = Device::from_eds(&eds(IO_EDS), UNCONFIGURED, Box::new(NoApplication))
        .expect("device")
        .with_value(ObjectKey::new(0x1018, 4), &serial.to_le_bytes())
        .expect("serial number")
        .with_faults(faults);
    device.boot(Instant::ZERO);
    Node::Device(Box::new(device))
}

/// Fastscan assigning `node_ids` in order, without storing.
fn assigning(node_ids: &[u8]) -> ScanPlan {
    ScanPlan {
        node_ids: node_ids
            .iter()
            .map(|&id| NodeId::new(id).expect("node"))
            .collect(),
        store: false,
        known: KnownParts::NONE,
    }
}

fn session(serials: &[u32]) -> LssSession<VirtualLink<Node>> {
    let (link, _) = bus(serials.iter().map(|&serial| unconfigured(serial)).collect());
    LssSession::new(link, LssConfig::DEFAULT)
}

fn serials(found: &[canopener_link::lss_session::Found]) -> Vec<u32> {
    let mut serials: Vec<u32> = found.iter().map(|device| device.address.serial_number).collect();
    serials.sort_unstable();
    serials
}

#[test]
fn listing_finds_every_unconfigured_device_once() {
    let mut session = session(&[0x1234, 0x5678]);
    let mut heard = 0;
    let (found, outcome) = session
        .list_all::<LssError>(|_| {
            heard += 1;
            Ok(())
        })
        .expect("listed");
    assert_eq!(outcome, ScanOutcome::Complete);
    assert_eq!(serials(&found), [0x1234, 0x5678]);
    assert_eq!(heard, 2);
    assert!(found.iter().all(|device| device.node_id.is_none()));
}

#[test]
fn scanning_assigns_the_node_ids_in_order() {
    let mut session = session(&[0x1234, 0x5678]);
    let (found, outcome) = session
        .scan_all::<LssError>(assigning(&[10, 11]), |_| Ok(()))
        .expect("no bus error")
        .expect("started");
    assert_eq!(outcome, ScanOutcome::Complete);
    let mut given: Vec<u8> = found
        .iter()
        .filter_map(|device| device.node_id.map(NodeId::get))
        .collect();
    given.sort_unstable();
    assert_eq!(given, [10, 11]);
    assert!(session.stats().sent > 0);
}

#[test]
fn a_device_is_inquired_selected_and_configured_by_its_address() {
    let mut session = session(&[0x1234]);
    session.select_all().expect("all in configuration state");
    let (address, node_id) = session.inquire_selected(true).expect("inquired");
    session.back_to_waiting().expect("waiting");
    assert_eq!(address.serial_number, 0x1234);
    assert_eq!(node_id, Ok(UNCONFIGURED));

    session.select(address).expect("selected");
    let previous = session
        .configure_selected(&address, Some(NodeId::new(20).expect("node")), None, false)
        .expect("configured");
    session.back_to_waiting().expect("waiting");
    assert_eq!(previous, Some(UNCONFIGURED));
    assert_eq!(session.extra_answers(), 0);
}

#[test]
fn an_unknown_address_is_not_selected() {
    let mut session = session(&[0x1234]);
    let nobody = LssAddress {
        vendor_id: 1,
        product_code: 2,
        revision_number: 3,
        serial_number: 4,
    };
    let err = session.select(nobody).expect_err("nobody has it");
    assert!(matches!(err, LssError::NotSelected { .. }));
    assert!(
        err.to_string()
            .ends_with("answered switch state selective within 100 ms"),
        "{err}"
    );
}

/// `lss-state-not-changed` holds for fastscan too: the device answers the scan but never enters
/// LSS configuration state, so `lss scan --assign` gives it no node-ID and says so.
#[test]
fn scanning_a_device_that_never_leaves_waiting_configures_nothing() {
    let faulty = unconfigured_with(0x1234, Fault::LssStateNotChanged.into());
    let (link, stations) = bus(vec![faulty]);
    let mut session = LssSession::new(link, LssConfig::DEFAULT);
    let (found, outcome) = session
        .scan_all::<LssError>(assigning(&[10]), |_| Ok(()))
        .expect("no bus error")
        .expect("started");
    assert!(
        found.iter().all(|device| device.node_id.is_none()),
        "{found:?} {outcome:?}"
    );
    assert!(matches!(outcome, ScanOutcome::Failed(_)), "{outcome:?}");
    let configured = match session.link_mut().virtual_bus().node(stations[0]) {
        Some(Node::Device(device)) => device.is_configured(),
        _ => panic!("no device"),
    };
    assert!(!configured, "the faulty device took a node-ID");
}

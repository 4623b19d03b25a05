//! The EnergyBus controller against emulated EnergyBus devices (canopener-device) on one virtual bus:
//! fastscan finds every device, each boots with its node-ID, gets its heartbeat configured and is
//! walked to Operating; a lost heartbeat is answered with NMT reset node and the device comes back.

use std::time::Duration;

use canopener_bus_engine::virtual_bus::StationId;
use canopener_can::Instant;
use canopener_device::energybus::EDS;
use canopener_device::energybus::station::{DeviceFault, EnergyBusDevice, EnergyBusFault};
use canopener_device::nmt_slave::NmtSlaveState;
use canopener_master::energybus_controller::{ControllerConfig, ControllerEvent, EnergyBusController, Phase};
use canopener_testkit::net::Net;
use canopener_wire::NodeId;
use canopener_wire::energybus::EmsState;

fn node(raw: u8) -> NodeId {
    NodeId::new(raw).expect("node-ID")
}

/// Devices with serial numbers 1, 2, ... (and `faults` on the one with serial `faulty`), powered on
/// at zero, and a started controller.
fn system(
    count: u32,
    faulty: Option<(u32, DeviceFault)>,
) -> (Net<EnergyBusDevice>, Vec<StationId>, EnergyBusController) {
    let eds = canopener_eds::load(EDS.as_bytes()).eds;
    let mut net = Net::ideal();
    let stations = (1..=count)
        .map(|serial| {
            let faults: Vec<DeviceFault> = faulty
                .filter(|(s, _)| *s == serial)
                .map(|(_, f)| f)
                .into_iter()
                .collect();
            let mut device = EnergyBusDevice::new(&eds, serial, &faults).expect("device");
            device.boot(Instant::ZERO);
            net.attach(device)
        })
        .collect();
    let profile = canopener_device::energybus::profile(&eds).expect("profile");
    let mut controller = EnergyBusController::new(profile, ControllerConfig::default());
    controller.start(Instant::ZERO);
    (net, stations, controller)
}

fn at(seconds: u64) -> Instant {
    Instant::ZERO + Duration::from_secs(seconds)
}

#[test]
fn three_devices_are_found_by_fastscan_and_walked_to_operating() {
    let (mut net, stations, mut controller) = system(3, None);
    let events = net.drive(&mut controller, at(30), |c, _| c.operating().len() == 3);
    let operating_at = net.now();
    assert_eq!(controller.operating(), [node(2), node(3), node(4)], "{events:#?}");
    // Lowest LSS address first: serial 1 gets node 2.
    let serials: Vec<u32> = controller
        .devices()
        .map(|(_, status)| status.address.serial_number)
        .collect();
    assert_eq!(serials, [1, 2, 3]);
    for (i, station) in stations.iter().enumerate() {
        let device = net.node(*station);
        assert_eq!(device.node_id(), Some(node(2 + i as u8)));
        assert_eq!(device.ems_state(), Some(EmsState::Operating));
        assert_eq!(device.device().state(), NmtSlaveState::Operational);
    }
    // Three fastscans of 133 requests each, most answered within the settle time.
    assert!(operating_at < at(15), "{operating_at:?}");
    let walk: Vec<String> = events
        .iter()
        .filter(|e| matches!(e, ControllerEvent::ControlWritten { node: n, .. } | ControllerEvent::LimitWritten { node: n, .. } if *n == node(2)))
        .map(ToString::to_string)
        .collect();
    assert_eq!(
        walk,
        [
            "node 2: control word 3 (ConnectedToCompatibilityCheck)",
            "node 2: control word 5 (CompatibilityCheckToLimiting)",
            "node 2: current limit 1500 mA",
            "node 2: control word 6 (LimitingToOperating)",
        ]
    );
    // The devices consume the controller's heartbeat: silence from it would be their event.
    let frames = net.frames();
    assert!(
        frames.iter().any(|f| f.ends_with(" 602#2B17100064000000")),
        "1017h := 100 ms"
    );
    assert!(
        frames.iter().any(|f| f.ends_with(" 602#231610012C010100")),
        "1016h:01 := node 1, 300 ms"
    );
}

#[test]
fn a_lost_heartbeat_is_answered_with_reset_node_and_the_device_comes_back() {
    let (mut net, stations, mut controller) = system(2, None);
    net.drive(&mut controller, at(30), |c, _| c.operating().len() == 2);
    // Node 3 is cut off the bus: its heartbeat stops, and it misses the reset.
    net.virtual_bus_mut().disconnect(stations[1]);
    let lost = net.now();
    let events = net.drive(&mut controller, lost + Duration::from_secs(1), |_, events| {
        events.contains(&ControllerEvent::ResetSent { node: node(3) })
    });
    assert!(
        events.contains(&ControllerEvent::HeartbeatLost { node: node(3) }),
        "{events:#?}"
    );
    assert!(
        net.now() - lost <= Duration::from_millis(260),
        "{:?}",
        net.now() - lost
    );
    assert_eq!(controller.operating(), [node(2)]);
    // Back on the bus with its old node-ID: reset once, found again, walked again.
    net.virtual_bus_mut().reconnect(stations[1]);
    let events = net.drive(&mut controller, net.now() + Duration::from_secs(20), |c, _| {
        c.operating().len() == 2
    });
    assert!(
        events.contains(&ControllerEvent::ForeignNodeReset { node: node(3) }),
        "{events:#?}"
    );
    assert_eq!(controller.operating(), [node(2), node(3)]);
    assert_eq!(net.node(stations[1]).ems_state(), Some(EmsState::Operating));
}

#[test]
fn a_handed_over_device_is_left_alone() {
    let (mut net, stations, mut controller) = system(1, None);
    net.drive(&mut controller, at(30), |c, _| c.operating().len() == 1);
    assert!(controller.hand_over(node(2)));
    assert!(!controller.hand_over(node(9)));
    // The tester resets the device's communication: it boots in Connected and stays there.
    net.inject(net.now(), "000#8202");
    let events = net.drive(&mut controller, net.now() + Duration::from_secs(2), |_, _| false);
    assert_eq!(events, [ControllerEvent::HandedOver { node: node(2) }]);
    assert_eq!(
        net.node(stations[0]).ems_state(),
        Some(EmsState::CompatibilityCheck)
    );
    let status = controller.devices().next().expect("node 2").1;
    assert_eq!(status.phase, Phase::HandedOver);
}

/// The paper's third deviation on the system: a slave that compares only the checked bit answers
/// for another one, so the scan reports an address no device has.
#[test]
fn a_fastscan_that_answers_wrongly_makes_the_scan_report_a_wrong_address() {
    let fault = DeviceFault::EnergyBus(EnergyBusFault::FastscanWrongAnswer);
    let (mut net, _, mut controller) = system(2, Some((2, fault)));
    let events = net.drive(&mut controller, at(30), |c, _| c.operating().len() == 2);
    let found: Vec<u32> = events
        .iter()
        .filter_map(|e| match e {
            ControllerEvent::Found { address, .. } => Some(address.serial_number),
            _ => None,
        })
        .collect();
    assert_eq!(
        found,
        [0, 1],
        "serial 2 answered for serial 1's bit 0: {events:#?}"
    );
}

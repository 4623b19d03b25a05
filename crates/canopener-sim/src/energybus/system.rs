//! The EnergyBus system on a simulated bus: one controller and N devices, built from one EnergyBus
//! description (the shipped one unless told otherwise), powered on at virtual time zero.
//!
//! Devices get serial numbers 1, 2, ... in 1018h:04, so their LSS addresses differ only there and
//! the controller's fastscan, which finds the lowest address first, gives device *i* (0-based) node-ID
//! 2 + *i* when every device is found; [`node_of_device`] says so.

use std::time::Duration;

use canopener_bus_engine::virtual_bus::{StationId, Timing};
use canopener_can::{Bitrate, CanFrame, Core, Instant};
use canopener_device::device::DeviceEvent;
use canopener_device::energybus::station::{DeviceFault, EnergyBusDevice, StationError};
use canopener_device::energybus::{EDS, EnergyBusError, profile};
use canopener_eds::Eds;
use canopener_master::energybus_controller::{ControllerConfig, ControllerEvent, EnergyBusController};
use canopener_wire::energybus::EmsProfile;
use canopener_wire::{LssAddress, NodeId};

use canopener_link::link::{Link, LinkError};
use canopener_link::virtual_link::VirtualLink;

/// How long a boot may take on virtual time before it is given up: each device's fastscan takes a few
/// seconds at the default LSS timing.
pub const BOOT_LIMIT: Duration = Duration::from_secs(120);

/// The slice virtual time advances by while a boot is watched.
const BOOT_SLICE: Duration = Duration::from_millis(10);

/// A station of the system: the controller or a device.
#[derive(Debug)]
pub enum Station {
    /// The EnergyBus controller.
    Controller(Box<EnergyBusController>),
    /// An emulated EnergyBus device.
    Device(Box<EnergyBusDevice>),
}

/// What a station reports.
#[derive(Debug, Clone, PartialEq)]
pub enum StationEvent {
    /// The controller's event.
    Controller(ControllerEvent),
    /// A device's event.
    Device(DeviceEvent),
}

impl Core for Station {
    type Event = StationEvent;

    fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
        match self {
            Station::Controller(c) => c.handle_frame(now, frame),
            Station::Device(d) => d.handle_frame(now, frame),
        }
    }

    fn handle_timeout(&mut self, now: Instant) {
        match self {
            Station::Controller(c) => c.handle_timeout(now),
            Station::Device(d) => d.handle_timeout(now),
        }
    }

    fn poll_transmit(&mut self) -> Option<CanFrame> {
        match self {
            Station::Controller(c) => c.poll_transmit(),
            Station::Device(d) => d.poll_transmit(),
        }
    }

    fn poll_event(&mut self) -> Option<StationEvent> {
        match self {
            Station::Controller(c) => c.poll_event().map(StationEvent::Controller),
            Station::Device(d) => d.poll_event().map(StationEvent::Device),
        }
    }

    fn poll_timeout(&self) -> Option<Instant> {
        match self {
            Station::Controller(c) => c.poll_timeout(),
            Station::Device(d) => d.poll_timeout(),
        }
    }
}

/// The system on a simulated bus; its tap is the caller's endpoint (a tester, a monitor).
pub type EnergyBusBus = VirtualLink<Station>;

/// Why the system cannot be built, or did not boot.
#[derive(Debug, thiserror::Error)]
pub enum SystemError {
    /// The description is no EnergyBus device.
    #[error(transparent)]
    Description(#[from] EnergyBusError),
    /// A device cannot be built.
    #[error("device {index}: {error}")]
    Device {
        /// Its place, 0-based.
        index: usize,
        /// Why.
        error: StationError,
    },
    /// The simulated bus failed.
    #[error(transparent)]
    Link(#[from] LinkError),
    /// The device under test did not reach Operating.
    #[error(
        "node {node} is not Operating after {after:?} of virtual time ({operating} of {devices} device(s) are); \
         the controller's last events: {last_events}"
    )]
    NotBooted {
        /// The node under test.
        node: u8,
        /// How long the boot ran.
        after: Duration,
        /// How many devices reached Operating.
        operating: usize,
        /// How many devices there are.
        devices: usize,
        /// The controller's last events, `; `-separated.
        last_events: String,
    },
}

/// The node-ID the controller gives device `index` (0-based) when every device is found.
pub fn node_of_device(index: usize) -> Option<NodeId> {
    u8::try_from(index + 2).ok().and_then(NodeId::new)
}

/// The controller and N devices (see the [module docs](self)).
#[derive(Debug, Clone)]
pub struct EnergyBusSystem {
    devices: usize,
    controller: Option<ControllerConfig>,
    eds: Option<Eds>,
    faults: Vec<(Option<usize>, DeviceFault)>,
    timing: Timing,
}

impl EnergyBusSystem {
    /// `devices` devices from the shipped description and a controller with the default settings, on
    /// an ideal bus.
    pub fn new(devices: usize) -> EnergyBusSystem {
        EnergyBusSystem {
            devices,
            controller: Some(ControllerConfig::default()),
            eds: None,
            faults: Vec::new(),
            timing: Timing::Ideal,
        }
    }

    /// No controller: the devices wait for an LSS master (a tester).
    pub fn without_controller(mut self) -> EnergyBusSystem {
        self.controller = None;
        self
    }

    /// The controller's settings.
    pub fn controller_config(mut self, config: ControllerConfig) -> EnergyBusSystem {
        self.controller = Some(config);
        self
    }

    /// Devices from `eds` (an EnergyBus description) instead of the shipped one.
    pub fn description(mut self, eds: Eds) -> EnergyBusSystem {
        self.eds = Some(eds);
        self
    }

    /// Gives device `device` (0-based; `None`: every device) the defect `fault`.
    pub fn fault(mut self, device: Option<usize>, fault: DeviceFault) -> EnergyBusSystem {
        self.faults.push((device, fault));
        self
    }

    /// On a bus with `timing`.
    pub fn timing(mut self, timing: Timing) -> EnergyBusSystem {
        self.timing = timing;
        self
    }

    /// On a bus that times every frame bit by bit at `bitrate`, as a wire would.
    pub fn bit_accurate(self, bitrate: Bitrate) -> EnergyBusSystem {
        self.timing(Timing::BitAccurate(bitrate))
    }

    /// How many devices.
    pub fn device_count(&self) -> usize {
        self.devices
    }

    /// Whether there is a controller.
    pub fn has_controller(&self) -> bool {
        self.controller.is_some()
    }

    /// The description the devices are built from.
    pub fn eds(&self) -> Eds {
        self.eds
            .clone()
            .unwrap_or_else(|| canopener_eds::load(EDS.as_bytes()).eds)
    }

    /// The assumed EMS objects and encodings of the description.
    pub fn profile(&self) -> Result<EmsProfile, SystemError> {
        Ok(profile(&self.eds())?)
    }

    /// The stations, not powered on: the controller (if any) first, then the devices in order.
    pub fn build(&self) -> Result<Vec<Station>, SystemError> {
        let eds = self.eds();
        let profile = profile(&eds)?;
        let mut stations = Vec::new();
        if let Some(config) = &self.controller {
            let controller = EnergyBusController::new(profile, config.clone());
            stations.push(Station::Controller(Box::new(controller)));
        }
        for index in 0..self.devices {
            let faults: Vec<DeviceFault> = self
                .faults
                .iter()
                .filter(|(device, _)| device.is_none_or(|d| d == index))
                .map(|(_, fault)| *fault)
                .collect();
            let serial = u32::try_from(index + 1).unwrap_or(u32::MAX);
            let device = EnergyBusDevice::new(&eds, serial, &faults)
                .map_err(|error| SystemError::Device { index, error })?;
            stations.push(Station::Device(Box::new(device)));
        }
        Ok(stations)
    }

    /// Builds the stations, powers them on at virtual time zero and puts them on a simulated bus that
    /// records every frame.
    pub fn start(&self) -> Result<EnergyBusBus, SystemError> {
        let mut bus = VirtualLink::new(self.timing);
        bus.virtual_bus_mut().record();
        for station in self.build()? {
            bus.attach(power_on(station, Instant::ZERO));
        }
        Ok(bus)
    }
}

/// Powers a station on at `now`.
pub fn power_on(mut station: Station, now: Instant) -> Station {
    match &mut station {
        Station::Controller(controller) => controller.start(now),
        Station::Device(device) => device.boot(now),
    }
    station
}

/// One device the controller brought to Operating.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Walked {
    /// Its node-ID.
    pub node: NodeId,
    /// Its LSS address.
    pub address: LssAddress,
    /// When the controller saw it Operating.
    pub at: Instant,
}

/// What a boot did.
#[derive(Debug, Clone, PartialEq)]
pub struct BootReport {
    /// The devices in Operating, in the order they got there.
    pub operating: Vec<Walked>,
    /// When every device was Operating, if they all were.
    pub all_operating_at: Option<Instant>,
    /// The controller's events with their time.
    pub events: Vec<(Instant, ControllerEvent)>,
    /// Every frame on the bus, in bus order.
    pub frames: Vec<(Instant, CanFrame)>,
}

/// The controller's station on `bus`.
pub fn controller(bus: &EnergyBusBus) -> Option<(StationId, &EnergyBusController)> {
    bus.virtual_bus().nodes().find_map(|(id, station)| match station {
        Station::Controller(c) => Some((id, c.as_ref())),
        Station::Device(_) => None,
    })
}

/// The devices on `bus`, in order.
pub fn devices(bus: &EnergyBusBus) -> Vec<(StationId, &EnergyBusDevice)> {
    bus.virtual_bus()
        .nodes()
        .filter_map(|(id, station)| match station {
            Station::Device(d) => Some((id, d.as_ref())),
            Station::Controller(_) => None,
        })
        .collect()
}

/// Runs the system until the controller reports every device Operating (and `linger` longer), or
/// until `limit`; the caller's endpoint listens to nothing meanwhile.
pub fn boot(bus: &mut EnergyBusBus, limit: Instant, linger: Duration) -> Result<BootReport, LinkError> {
    let expected = devices(bus).len();
    let mut report = BootReport {
        operating: Vec::new(),
        all_operating_at: None,
        events: Vec::new(),
        frames: Vec::new(),
    };
    let mut until = limit;
    while bus.now() < until {
        let next = (bus.now() + BOOT_SLICE).min(until);
        bus.idle_until(next)?;
        while let Some(event) = bus.virtual_bus_mut().poll_event() {
            let at = event.at;
            let StationEvent::Controller(event) = event.event else {
                continue;
            };
            if let ControllerEvent::Operating { node } = event {
                let address = controller(bus)
                    .and_then(|(_, c)| c.devices().find(|(n, _)| *n == node))
                    .map(|(_, status)| status.address);
                if let Some(address) = address {
                    report.operating.retain(|w| w.node != node);
                    report.operating.push(Walked { node, address, at });
                }
            }
            report.events.push((at, event));
        }
        let all = controller(bus).is_some_and(|(_, c)| c.operating().len() == expected);
        if all && report.all_operating_at.is_none() {
            report.all_operating_at = report.operating.iter().map(|w| w.at).max();
            until = bus.now() + linger;
        }
    }
    report.frames = bus
        .virtual_bus_mut()
        .take_recording()
        .into_iter()
        .map(|f| (f.at, f.frame))
        .collect();
    Ok(report)
}

/// The system started and ready for a tester on the bus's tap, testing `node`:
/// - with a controller and devices: booted until every device is Operating (at most
///   [`BOOT_LIMIT`]), then `node` handed over, so the controller leaves it to the tester; an error if
///   `node` did not reach Operating;
/// - with a controller alone: at once (the tester plays the devices);
/// - without a controller: after 100 ms, the devices' power-on done (they wait for an LSS master).
pub fn ready_for_test(
    system: &EnergyBusSystem,
    node: Option<NodeId>,
) -> Result<(EnergyBusBus, Option<BootReport>), SystemError> {
    let mut bus = system.start()?;
    if !system.has_controller() {
        bus.idle_until(Instant::ZERO + Duration::from_millis(100))?;
        bus.virtual_bus_mut().take_recording();
        return Ok((bus, None));
    }
    if system.device_count() == 0 {
        return Ok((bus, None));
    }
    let report = boot(&mut bus, Instant::ZERO + BOOT_LIMIT, Duration::ZERO)?;
    let handed = node.and_then(|node| {
        let (id, c) = controller(&bus)?;
        c.operating().contains(&node).then_some((id, node))
    });
    match (node, handed) {
        (Some(_), Some((id, node))) => {
            if let Some(Station::Controller(c)) = bus.virtual_bus_mut().node_mut(id) {
                c.hand_over(node);
            }
        }
        (Some(node), None) => {
            let last_events: Vec<String> = report
                .events
                .iter()
                .rev()
                .take(4)
                .rev()
                .map(|(_, e)| e.to_string())
                .collect();
            return Err(SystemError::NotBooted {
                node: node.get(),
                after: bus.now() - Instant::ZERO,
                operating: report.operating.len(),
                devices: system.device_count(),
                last_events: last_events.join("; "),
            });
        }
        (None, _) => {}
    }
    while bus.virtual_bus_mut().poll_event().is_some() {}
    Ok((bus, Some(report)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_device::energybus::station::EnergyBusFault;
    use canopener_wire::energybus::EmsState;

    fn node(raw: u8) -> NodeId {
        NodeId::new(raw).expect("node-ID")
    }

    #[test]
    fn three_devices_boot_to_operating_with_node_ids_in_address_order() {
        let system = EnergyBusSystem::new(3);
        let mut bus = system.start().unwrap();
        let report = boot(&mut bus, Instant::ZERO + BOOT_LIMIT, Duration::from_millis(500)).unwrap();
        let nodes: Vec<(u8, u32)> = report
            .operating
            .iter()
            .map(|w| (w.node.get(), w.address.serial_number))
            .collect();
        assert_eq!(nodes, [(2, 1), (3, 2), (4, 3)]);
        for (i, (_, device)) in devices(&bus).into_iter().enumerate() {
            assert_eq!(device.node_id(), node_of_device(i));
            assert_eq!(device.ems_state(), Some(EmsState::Operating));
        }
        let done = report.all_operating_at.expect("all Operating");
        assert!(done < Instant::ZERO + Duration::from_secs(15), "{done:?}");
        // The frames end half a second after that.
        let last = report.frames.last().expect("frames").0;
        assert!(last > done && last <= done + Duration::from_millis(500));
        // Deterministic: the same system boots identically.
        let mut again = system.start().unwrap();
        let second = boot(&mut again, Instant::ZERO + BOOT_LIMIT, Duration::from_millis(500)).unwrap();
        assert_eq!(second, report);
    }

    #[test]
    fn the_device_under_test_is_handed_over_and_a_missing_one_is_an_error() {
        let (bus, report) = ready_for_test(&EnergyBusSystem::new(2), Some(node(3))).unwrap();
        assert_eq!(report.expect("booted").operating.len(), 2);
        let (_, c) = controller(&bus).unwrap();
        let phases: Vec<_> = c.devices().map(|(n, s)| (n.get(), s.phase)).collect();
        use canopener_master::energybus_controller::Phase;
        assert_eq!(phases, [(2, Phase::Operating), (3, Phase::HandedOver)]);

        // An LSS slave that never changes state is never configured: node 2 never comes.
        let fault = DeviceFault::Catalogue(canopener_device::faults::Fault::LssStateNotChanged);
        let error =
            ready_for_test(&EnergyBusSystem::new(1).fault(Some(0), fault), Some(node(2))).unwrap_err();
        assert!(
            error
                .to_string()
                .starts_with("node 2 is not Operating after 120s of virtual time (0 of 1 device(s) are)"),
            "{error}"
        );
        let fastscan = DeviceFault::EnergyBus(EnergyBusFault::FastscanWrongAnswer);
        assert!(ready_for_test(&EnergyBusSystem::new(1).fault(None, fastscan), Some(node(2))).is_ok());
    }
}

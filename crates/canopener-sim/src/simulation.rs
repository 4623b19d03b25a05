//! Simulated devices set up in one expression: what a test, a conformance suite or a front end needs
//! to have devices to talk to.
//!
//! ```no_run
//! # use std::time::Duration;
//! # use canopener_can::Bitrate;
//! # use canopener_device::faults::Fault;
//! # use canopener_link::sdo_session::SdoSession;
//! # use canopener_sim::simulation::Simulation;
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let eds = canopener_eds::load(&std::fs::read("device.eds")?).eds;
//! let mut bus = Simulation::bit_accurate(Bitrate::M1)
//!     .devices(&[(&eds, 5), (&eds, 6)])
//!     .fault(Fault::SdoSlow)
//!     .start()?;
//! let mut session = SdoSession::new(&mut bus, 5, Duration::from_millis(500))?;
//! let vendor = session.read(0x1018, 1)?;
//! # Ok(()) }
//! ```

use std::path::{Path, PathBuf};

use canopener_bus_engine::virtual_bus::Timing;
use canopener_can::{Bitrate, Instant};
use canopener_device::faults::Fault;

use crate::device::{ApplicationKind, DeviceOptions, SimulatedDevice};
use crate::error::SimError;
use crate::plan::{Description, plan};
use canopener_link::cancel::Cancel;
use canopener_link::virtual_link::VirtualLink;

/// The calendar time at the start of a simulation on virtual time, for the TIME its devices produce:
/// 2024-01-01 00:00:00 UTC, so that runs are reproducible.
pub const VIRTUAL_CALENDAR_START_UNIX_MILLIS: u64 = 1_704_067_200_000;

/// The simulated bus with its devices, on virtual time; the caller's endpoint is its tap.
pub type SimulatedBus = VirtualLink<SimulatedDevice>;

/// Which devices to simulate and how (a builder; see the [module docs](self)).
#[derive(Debug, Clone)]
pub struct Simulation {
    timing: Timing,
    descriptions: Vec<(Description, Option<u8>)>,
    first_node_id: Option<u8>,
    options: DeviceOptions,
    cancel: Cancel,
    calendar_start: u64,
}

impl Default for Simulation {
    fn default() -> Simulation {
        Simulation::new(Timing::Ideal)
    }
}

impl Simulation {
    /// No devices yet, on a bus with `timing`.
    pub fn new(timing: Timing) -> Simulation {
        Simulation {
            timing,
            descriptions: Vec::new(),
            first_node_id: None,
            options: DeviceOptions::default(),
            cancel: Cancel::new(),
            calendar_start: VIRTUAL_CALENDAR_START_UNIX_MILLIS,
        }
    }

    /// On an ideal bus: every frame arrives the instant it is sent (exact, readable traces).
    pub fn ideal() -> Simulation {
        Simulation::new(Timing::Ideal)
    }

    /// On a bus that arbitrates and times every frame bit by bit at `bitrate`, as a wire would.
    pub fn bit_accurate(bitrate: Bitrate) -> Simulation {
        Simulation::new(Timing::BitAccurate(bitrate))
    }

    /// One more device from `description` (an `&Eds`, or a path to an EDS/DCF) on node `node_id`
    /// (1 to 127, or FFh to start LSS-unconfigured). The node-ID wins over a DCF's own.
    pub fn device(mut self, description: impl Into<Description>, node_id: u8) -> Simulation {
        self.descriptions.push((description.into(), Some(node_id)));
        self
    }

    /// One more device per `(description, node-ID)` pair, in order (see [`Simulation::device`]).
    pub fn devices<D: Into<Description> + Clone>(mut self, devices: &[(D, u8)]) -> Simulation {
        for (description, node_id) in devices {
            self = self.device(description.clone(), *node_id);
        }
        self
    }

    /// One more device from an EDS/DCF file whose node-ID is planned as `canopener sim FILE` plans it:
    /// the next of [`Simulation::first_node_id`] when one is given, else the DCF's own, else
    /// LSS-unconfigured.
    pub fn file(mut self, path: impl AsRef<Path>) -> Simulation {
        self.descriptions
            .push((Description::File(path.as_ref().to_owned()), None));
        self
    }

    /// One more device per file, in order (see [`Simulation::file`]).
    pub fn files<P: AsRef<Path>>(self, paths: impl IntoIterator<Item = P>) -> Simulation {
        paths.into_iter().fold(self, Simulation::file)
    }

    /// The node-ID of the first device added with [`Simulation::file`]; the next ones count up (N, N+1,
    /// ...), whatever node-ID their files configure. Without it a DCF runs at its own node-ID and the
    /// other devices start LSS-unconfigured.
    pub fn first_node_id(mut self, node_id: Option<u8>) -> Simulation {
        self.first_node_id = node_id;
        self
    }

    /// The serial number 1018h:04 of the first device; the next ones count up (S, S+1, ...).
    pub fn serial(mut self, first: Option<u32>) -> Simulation {
        self.options.first_serial = first;
        self
    }

    /// The application behind every device's object dictionary.
    pub fn application(mut self, application: ApplicationKind) -> Simulation {
        self.options.application = application;
        self
    }

    /// Makes every device refuse SDO downloads while Operational with 0800 0022h, as devices do that
    /// take parameters only in Pre-operational.
    pub fn downloads_refused_in_operational(mut self, refused: bool) -> Simulation {
        self.options.downloads_refused_in_operational = refused;
        self
    }

    /// Gives every device the defect `fault` too.
    pub fn fault(mut self, fault: Fault) -> Simulation {
        self.options.faults.push(fault);
        self
    }

    /// Gives every device these defects too.
    pub fn faults(mut self, faults: impl IntoIterator<Item = Fault>) -> Simulation {
        self.options.faults.extend(faults);
        self
    }

    /// Keeps what the devices store (1010h parameters, LSS configuration) in `dir` across runs
    /// (see [`state_store`](crate::state_store)).
    pub fn state_dir(mut self, dir: Option<PathBuf>) -> Simulation {
        self.options.state_dir = dir;
        self
    }

    /// Makes the bus's link honour `cancel`.
    pub fn cancel(mut self, cancel: Cancel) -> Simulation {
        self.cancel = cancel;
        self
    }

    /// The calendar time (Unix milliseconds) at virtual time zero, for the TIME devices produce
    /// (default [`VIRTUAL_CALENDAR_START_UNIX_MILLIS`]).
    pub fn calendar_start(mut self, unix_millis: u64) -> Simulation {
        self.calendar_start = unix_millis;
        self
    }

    /// Loads every description, plans the node-IDs and builds the devices, not yet powered on: for a
    /// host of one's own, such as [`SimHost`](crate::host::SimHost) on a real bus.
    pub fn build(self) -> Result<Vec<SimulatedDevice>, SimError> {
        plan(self.descriptions, self.first_node_id)?
            .into_iter()
            .enumerate()
            .map(|(position, plan)| SimulatedDevice::build(plan, position, &self.options))
            .collect()
    }

    /// Builds the devices, powers them on at virtual time zero and puts them on a simulated bus, whose
    /// tap is the returned link: `SdoSession::new(&mut bus, 5, timeout)` talks to node 5.
    pub fn start(self) -> Result<SimulatedBus, SimError> {
        let timing = self.timing;
        let cancel = self.cancel.clone();
        let calendar_start = self.calendar_start;
        let mut bus = VirtualLink::new(timing).with_cancel(cancel);
        for device in self.build()? {
            let mut device = device.with_calendar_at_zero(calendar_start);
            device.boot(Instant::ZERO);
            bus.attach(device);
        }
        Ok(bus)
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use canopener_bus_engine::virtual_bus::NodeEvent;
    use canopener_device::device::DeviceEvent;
    use canopener_device::faults::DEFAULT_SDO_DELAY;

    use super::*;
    use crate::event_log::LogEntry;
    use crate::test_support::{CONSUMER_1016, base_eds, base_eds_with, frame, temp_dir};
    use canopener_link::link::Link;
    use canopener_link::sdo_session::SdoSession;

    fn described(bus: &mut SimulatedBus) -> Vec<(Instant, LogEntry)> {
        let events: Vec<NodeEvent<DeviceEvent>> =
            std::iter::from_fn(|| bus.virtual_bus_mut().poll_event()).collect();
        events
            .iter()
            .filter_map(|event| {
                let sim = bus.virtual_bus().node(event.node)?;
                LogEntry::event(sim, &event.event).map(|entry| (event.at, entry))
            })
            .collect()
    }

    /// Two devices on one bus: each boots, answers SDO on its own node-ID, and hears the other's
    /// heartbeat at the instant it is sent.
    #[test]
    fn devices_boot_answer_and_hear_each_other() {
        let dir = temp_dir("two");
        let eds = base_eds_with(&dir, "consumer.eds", CONSUMER_1016);
        let mut bus = Simulation::ideal()
            .files([&eds, &eds])
            .first_node_id(Some(5))
            .start()
            .unwrap();
        bus.virtual_bus_mut().record();
        // Node 5 consumes node 6's heartbeat (1016h:01 = node 6, 1000 ms); node 6 beats every 100 ms.
        let timeout = Duration::from_millis(100);
        SdoSession::new(&mut bus, 5, timeout)
            .unwrap()
            .write(0x1016, 1, 0x0006_03E8u32.to_le_bytes().to_vec())
            .unwrap();
        SdoSession::new(&mut bus, 6, timeout)
            .unwrap()
            .write(0x1017, 0, 100u16.to_le_bytes().to_vec())
            .unwrap();
        bus.run_until(Instant::ZERO + Duration::from_millis(250)).unwrap();

        let frames: Vec<String> = bus
            .virtual_bus_mut()
            .take_recording()
            .iter()
            .map(|f| format!("{} {}", f.at.as_micros(), f.frame))
            .collect();
        assert_eq!(
            frames,
            [
                "0 705#00",
                "0 706#00",
                "0 605#23161001E8030600",
                "0 585#6016100100000000",
                "0 606#2B17100064000000",
                "0 586#6017100000000000",
                "100000 706#7F",
                "200000 706#7F",
            ]
        );
        let log = described(&mut bus);
        let boot_ups = log.iter().filter(|(_, e)| e.kind == "boot_up").count();
        assert_eq!(boot_ups, 2, "{log:?}");
        assert!(
            log.iter().any(|(_, e)| e.kind == "sdo_write"
                && e.node == Some(6)
                && e.text == "SDO download 1017h:00 = 64 00 (server 1200h)"),
            "{log:?}"
        );
        let heard = log
            .iter()
            .find(|(_, e)| e.node == Some(5) && e.kind == "heartbeat_consumer")
            .expect("node 5 hears node 6's heartbeat");
        assert_eq!(heard.0, Instant::ZERO + Duration::from_millis(100));
        assert_eq!(heard.1.text, "heartbeat of node 6 started");
    }

    /// A CiA 401 description acts like a CiA 401 device without being told (`--app auto`, the
    /// default): CANopenNode's basicDevice (1000h = 000F0191h, 6000h, 6200h, TPDO1 = 6000h:01..02 on
    /// event) gets the factory test registers, and 2000h = 1 with 2001h = F0h drives 6000h:01 and sends
    /// TPDO1. `ApplicationKind::None` turns it off.
    #[test]
    fn a_cia401_description_runs_the_cia401_application_by_default() {
        let eds = canopener_testkit::corpus::eds(
            "CANopenNode__CANopenSocket__examples__basicDevice__basicDevice.eds",
        );
        let mut bus = Simulation::ideal().device(&eds, 5).start().unwrap();
        let (_, sim) = bus.virtual_bus().nodes().next().expect("one device");
        assert_eq!(sim.application(), ApplicationKind::Cia401);
        assert!(sim.application_is_auto());
        let started = LogEntry::started(sim, "virtual:test");
        assert!(
            started
                .text
                .contains("CiA 401 I/O application: 1000h says profile 401"),
            "{}",
            started.text
        );
        bus.virtual_bus_mut().record();
        bus.send(&frame("000#0105")).unwrap();
        let timeout = Duration::from_millis(100);
        let mut session = SdoSession::new(&mut bus, 5, timeout).unwrap();
        session.write(0x2000, 0, vec![1]).unwrap();
        session.write(0x2001, 0, vec![0xF0]).unwrap();
        assert_eq!(session.read(0x6000, 1).unwrap(), [0xF0]);
        let tpdos: Vec<String> = bus
            .virtual_bus_mut()
            .take_recording()
            .iter()
            .filter(|f| f.frame.id().as_raw() == 0x185)
            .map(|f| f.frame.to_string())
            .collect();
        assert_eq!(
            tpdos,
            ["185#0000", "185#F000"],
            "TPDO1 at the start, then on the change"
        );

        let bus = Simulation::ideal()
            .device(&eds, 5)
            .application(ApplicationKind::None)
            .start()
            .unwrap();
        let (_, sim) = bus.virtual_bus().nodes().next().expect("one device");
        assert_eq!(sim.application(), ApplicationKind::None);
        assert!(
            sim.device().od().object(0x2000).is_empty(),
            "no factory registers without the application"
        );
        // A description of another profile runs nothing, and says why.
        let other = canopener_testkit::corpus::eds("CANopenNode__CANopenNode__example__DS301_profile.eds");
        let bus = Simulation::ideal().device(&other, 5).start().unwrap();
        let (_, sim) = bus.virtual_bus().nodes().next().expect("one device");
        assert_eq!(sim.application(), ApplicationKind::None);
        assert!(
            LogEntry::started(sim, "virtual:test")
                .text
                .contains("no application: not a CiA 401 I/O description")
        );
    }

    #[test]
    fn serials_state_dir_and_faults_apply_to_every_device() {
        let dir = temp_dir("options");
        let eds = canopener_eds::load(&std::fs::read(base_eds()).unwrap()).eds;
        let mut bus = Simulation::bit_accurate(Bitrate::M1)
            .devices(&[(&eds, 5), (&eds, 6)])
            .serial(Some(0x100))
            .state_dir(Some(dir.to_path_buf()))
            .fault(Fault::SdoSlow)
            .start()
            .unwrap();
        let stores: Vec<PathBuf> = bus
            .virtual_bus()
            .nodes()
            .filter_map(|(_, sim)| sim.store_path().map(Path::to_owned))
            .collect();
        assert_eq!(stores, [dir.join("node-005.params"), dir.join("node-006.params")]);
        for (node, serial) in [(5, 0x100u32), (6, 0x101)] {
            let started = bus.now();
            let mut session = SdoSession::new(&mut bus, node, Duration::from_secs(1)).unwrap();
            assert_eq!(session.read(0x1018, 4).unwrap(), serial.to_le_bytes());
            assert!(bus.now().saturating_duration_since(started) >= DEFAULT_SDO_DELAY);
        }
    }

    #[test]
    fn bad_descriptions_are_errors_not_panics() {
        let dir = temp_dir("bad");
        let junk = dir.join("junk.eds");
        canopener_testkit::fixture::write(&junk, b"\xFF\xFE[nothing").unwrap();
        let err = Simulation::ideal().file(&junk).start().unwrap_err();
        assert!(
            err.to_string().contains("junk.eds is not a usable EDS/DCF"),
            "{err}"
        );
        let eds = canopener_eds::load(&std::fs::read(base_eds()).unwrap()).eds;
        let clash = Simulation::ideal()
            .devices(&[(&eds, 5), (&eds, 5)])
            .start()
            .unwrap_err();
        assert!(
            matches!(clash, SimError::NodeIdClash { node_id: 5, .. }),
            "{clash:?}"
        );
    }
}

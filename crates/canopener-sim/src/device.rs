//! One simulated device as a sans-IO [`Core`]: a [`Device`] with its faults, its store and its TIME
//! production, so that it runs on a simulated bus ([`VirtualLink`](canopener_link::virtual_link::VirtualLink)) as
//! well as on a real one ([`SimHost`](crate::host::SimHost)).

use std::path::{Path, PathBuf};
use std::time::Duration;

use canopener_can::{CanFrame, Core, Instant};
use canopener_device::application::{Application, NoApplication};
use canopener_device::cia401::{Cia401Io, install_objects, is_cia401_io};
use canopener_device::device::{Device, DeviceEvent, UNCONFIGURED};
use canopener_device::faults::{Fault, FaultSet};
use canopener_device::od_build::build_od;
use canopener_eds::Eds;
use canopener_od::ObjectKey;
use canopener_wire::TimeOfDay;

use crate::error::SimError;
use crate::plan::{NodeIdFrom, Plan};
use crate::state_store::{FileStore, LssFile};

/// How often a TIME producer sends the time. CiA 301 §7.2.6 leaves the rate to the application; once a
/// second is what a clock master typically does.
pub const TIME_PERIOD: Duration = Duration::from_secs(1);

/// What runs behind a simulated device's object dictionary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ApplicationKind {
    /// What the description says the device is: [`ApplicationKind::Cia401`] for a CiA 401 generic
    /// I/O device (1000h bits 15..0 = 0191h and digital I/O 6000h or 6200h,
    /// [`is_cia401_io`]), else [`ApplicationKind::None`]. A device described as a CiA 401 module
    /// behaves as one unless told otherwise.
    #[default]
    Auto,
    /// Nothing: the device only holds its object dictionary.
    None,
    /// CiA 401 generic I/O (6000h/6200h/6401h, factory test registers 2000h-2002h); the objects the
    /// description lacks are added (only those).
    Cia401,
}

impl ApplicationKind {
    /// The application a device described by `eds` runs: `Auto` decided by the description's
    /// dictionary (as built for node 1), anything else as asked. Never `Auto`.
    pub fn resolve(self, eds: &Eds) -> ApplicationKind {
        match self {
            ApplicationKind::Auto => match build_od(eds, 1) {
                Ok(built) if is_cia401_io(&built.od) => ApplicationKind::Cia401,
                // A description that does not build fails with its own message when the device is.
                _ => ApplicationKind::None,
            },
            chosen => chosen,
        }
    }

    /// How `--app` and the JSON log name it: `auto`, `none`, `cia401`.
    pub fn name(self) -> &'static str {
        match self {
            ApplicationKind::Auto => "auto",
            ApplicationKind::None => "none",
            ApplicationKind::Cia401 => "cia401",
        }
    }
}

/// How every device of a simulation is built besides its description and node-ID.
#[derive(Debug, Clone, Default)]
pub struct DeviceOptions {
    /// The serial number 1018h:04 of the first device; the next ones count up, so that devices of one
    /// description have distinct LSS addresses.
    pub first_serial: Option<u32>,
    /// The application behind each object dictionary.
    pub application: ApplicationKind,
    /// The defects every device has.
    pub faults: Vec<Fault>,
    /// Every device refuses SDO downloads while Operational with 0800 0022h
    /// ([`Device::with_downloads_refused_in_operational`]).
    pub downloads_refused_in_operational: bool,
    /// Where devices keep what they store (1010h parameters, LSS configuration) across runs; nothing
    /// survives the process without it.
    pub state_dir: Option<PathBuf>,
}

/// A simulated device: one [`Device`] plus what a real one has around its protocol stack (see the
/// [module docs](self)).
#[derive(Debug)]
pub struct SimulatedDevice {
    device: Device,
    name: String,
    /// The application it runs (never `Auto`).
    application: ApplicationKind,
    /// Whether that was decided from the description (`--app auto`).
    application_auto: bool,
    store: Option<PathBuf>,
    /// Where its node-ID at start comes from.
    node_id_from: NodeIdFrom,
    /// The bit rate in kbit/s the file configures (`[DeviceComissioning] Baudrate`), which a simulated
    /// device does not apply: it runs at its bus's rate.
    file_bitrate: Option<u32>,
    /// When a TIME producer (1012h bit 30) next sends the time; `None` while it is no producer.
    next_time: Option<Instant>,
    /// The Unix time in milliseconds of [`Instant::ZERO`] on the clock the device runs on.
    unix_millis_at_zero: u64,
}

impl SimulatedDevice {
    /// Builds the device `plan` describes; `position` is its place in the simulation (0 for the first),
    /// which numbers its serial number. With a state directory, a device that starts LSS-unconfigured
    /// starts with the node-ID it stored last time instead, as a real device does after power-on.
    pub fn build(plan: Plan, position: usize, options: &DeviceOptions) -> Result<SimulatedDevice, SimError> {
        let Plan {
            name,
            eds,
            node_id,
            mut node_id_from,
        } = plan;
        let file_bitrate = eds
            .commissioning
            .as_ref()
            .and_then(|c| c.baudrate.as_deref())
            .and_then(canopener_eds::model::int_of)
            .and_then(|b| u32::try_from(b).ok());
        let application = options.application.resolve(&eds);
        let serial = options
            .first_serial
            .map(|first| first.wrapping_add(position as u32));
        let make = |node_id: u8| -> Result<Device, SimError> {
            let mut device = match application {
                ApplicationKind::Auto | ApplicationKind::None => {
                    Device::from_eds(&eds, node_id, Box::new(NoApplication))
                }
                ApplicationKind::Cia401 => {
                    let app: Box<dyn Application> = Box::new(Cia401Io::new());
                    Device::from_eds_extended(&eds, node_id, app, |od, node| {
                        install_objects(od, node).map(drop).map_err(|err| err.to_string())
                    })
                }
            }
            .map_err(|err| SimError::Build {
                name: name.clone(),
                reason: err.to_string(),
            })?;
            if let Some(serial) = serial {
                device = device
                    .with_value(ObjectKey::new(0x1018, 4), &serial.to_le_bytes())
                    .map_err(|err| SimError::Serial {
                        name: name.clone(),
                        serial,
                        reason: err.to_string(),
                    })?;
            }
            if !options.faults.is_empty() {
                device = device.with_faults(options.faults.iter().copied().collect::<FaultSet>());
            }
            if options.downloads_refused_in_operational {
                device = device.with_downloads_refused_in_operational();
            }
            Ok(device)
        };
        let mut device = make(node_id)?;
        let mut store = None;
        if let Some(dir) = &options.state_dir {
            let address = device.lss().map(|lss| *lss.identity());
            let params = match (node_id, address) {
                // A node-ID by LSS: the device is known by its LSS address.
                (UNCONFIGURED, Some(address)) => {
                    let lss = LssFile::open(dir, &address)?;
                    if let Some(stored) = lss.node_id() {
                        device = make(stored.get())?;
                        node_id_from = NodeIdFrom::Stored;
                    }
                    device = device.with_lss_storage(Box::new(lss));
                    FileStore::open_lss(dir, &address)?
                }
                (_, address) => {
                    if let Some(address) = address {
                        device = device.with_lss_storage(Box::new(LssFile::open(dir, &address)?));
                    }
                    FileStore::open(dir, node_id)?
                }
            };
            store = Some(params.path().to_owned());
            device = device.with_parameter_store(Box::new(params));
        }
        Ok(SimulatedDevice {
            device,
            name,
            application,
            application_auto: options.application == ApplicationKind::Auto,
            store,
            node_id_from,
            file_bitrate,
            next_time: None,
            unix_millis_at_zero: 0,
        })
    }

    /// Sets which calendar time [`Instant::ZERO`] is, for the TIME the device produces: 0 (the default)
    /// on the wall clock, whose epoch is the Unix epoch; a date after 1984 on virtual time, whose zero is
    /// the start of the simulation (CiA 301 TIME_OF_DAY cannot say anything before 1984).
    pub fn with_calendar_at_zero(mut self, unix_millis: u64) -> SimulatedDevice {
        self.unix_millis_at_zero = unix_millis;
        self
    }

    /// Power-on (CiA 301 §7.3.2.2.1: initialisation, then the boot-up message).
    pub fn boot(&mut self, now: Instant) {
        self.device.boot(now);
        self.follow_time_producer(now);
    }

    /// The device.
    pub fn device(&self) -> &Device {
        &self.device
    }

    /// The device, to change it from outside (an application value, a fault).
    pub fn device_mut(&mut self) -> &mut Device {
        &mut self.device
    }

    /// What messages call its description (the file's path).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The application behind its object dictionary (never `Auto`).
    pub fn application(&self) -> ApplicationKind {
        self.application
    }

    /// Whether [`SimulatedDevice::application`] was decided from the description
    /// ([`ApplicationKind::Auto`]) rather than asked for.
    pub fn application_is_auto(&self) -> bool {
        self.application_auto
    }

    /// Where its node-ID at start came from.
    pub fn node_id_from(&self) -> NodeIdFrom {
        self.node_id_from
    }

    /// The bit rate in kbit/s its file configures, which the simulation does not apply (the bus sets
    /// the rate); `None` when the file configures none.
    pub fn file_bitrate(&self) -> Option<u32> {
        self.file_bitrate
    }

    /// The file its saved parameters go to, with a state directory.
    pub fn store_path(&self) -> Option<&Path> {
        self.store.as_deref()
    }

    /// The node-ID it answers on, or [`UNCONFIGURED`] (FFh) while it has none.
    pub fn node_label(&self) -> u8 {
        if self.device.is_configured() {
            self.device.node_id().get()
        } else {
            UNCONFIGURED
        }
    }

    /// Starts or stops the TIME schedule when 1012h bit 30 changed: a new producer sends at once.
    fn follow_time_producer(&mut self, now: Instant) {
        if !self.device.is_time_producer() {
            self.next_time = None;
        } else if self.next_time.is_none() {
            self.next_time = Some(now);
        }
    }

    /// Sends the time if due (CiA 301 §7.2.6.2, TIME producer).
    fn produce_time(&mut self, now: Instant) {
        if self.next_time.is_none_or(|due| due > now) {
            return;
        }
        self.next_time = Some(now + TIME_PERIOD);
        let unix_millis = self
            .unix_millis_at_zero
            .saturating_add(now.as_nanos() / 1_000_000);
        if let Some(time) = TimeOfDay::from_unix_millis(unix_millis) {
            // Refused outside the NMT states that run TIME: nothing to send then.
            let _ = self.device.produce_time(now, time);
        }
    }
}

impl Core for SimulatedDevice {
    type Event = DeviceEvent;

    fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
        self.device.handle_frame(now, frame);
        self.follow_time_producer(now);
    }

    fn handle_timeout(&mut self, now: Instant) {
        self.produce_time(now);
        if self.device.poll_timeout().is_some_and(|due| due <= now) {
            self.device.handle_timeout(now);
        }
        self.follow_time_producer(now);
    }

    fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.device.poll_transmit()
    }

    fn poll_event(&mut self) -> Option<DeviceEvent> {
        self.device.poll_event()
    }

    fn poll_timeout(&self) -> Option<Instant> {
        [self.device.poll_timeout(), self.next_time]
            .into_iter()
            .flatten()
            .min()
    }
}

#[cfg(test)]
mod tests {
    use canopener_bus_engine::virtual_bus::Timing;

    use super::*;
    use crate::plan::{Description, plan};
    use crate::simulation::Simulation;
    use crate::test_support::{TIME_1012, base_eds, base_eds_with, temp_dir};
    use canopener_link::sdo_session::SdoSession;

    fn one(path: &Path) -> Plan {
        plan([(Description::from(path), Some(5))], None)
            .unwrap()
            .remove(0)
    }

    #[test]
    fn cia401_adds_only_the_objects_the_file_lacks() {
        let options = DeviceOptions {
            application: ApplicationKind::Cia401,
            ..DeviceOptions::default()
        };
        let sim = SimulatedDevice::build(one(&base_eds()), 0, &options).unwrap();
        // base.eds has 6000h and 6200h: kept as they are (two inputs), the factory test registers
        // and the analogue inputs it lacks are added.
        assert!(!sim.device().od().object(0x2001).is_empty());
        assert!(!sim.device().od().object(0x6401).is_empty());

        let dir = temp_dir("401");
        let text = std::fs::read_to_string(base_eds()).unwrap();
        let cut = text.find("[6000]").expect("base.eds has 6000h");
        let bare = dir.join("bare.eds");
        canopener_testkit::fixture::write(&bare, &text[..cut]).unwrap();
        let options = DeviceOptions {
            state_dir: Some(dir.to_path_buf()),
            ..options
        };
        let sim = SimulatedDevice::build(one(&bare), 0, &options).unwrap();
        for index in [0x2000, 0x2001, 0x6000, 0x6200, 0x6401] {
            assert!(
                !sim.device().od().object(index).is_empty(),
                "{index:04X}h missing"
            );
        }
        assert!(sim.store_path().unwrap().ends_with("node-005.params"));
    }

    /// 1012h bit 30 makes the device a TIME producer (CiA 301 §7.5.2.6): it sends at once and then
    /// once a second, the calendar counting from the simulation's start.
    #[test]
    fn a_time_producer_sends_the_calendar_once_a_second() {
        let dir = temp_dir("time");
        let eds = base_eds_with(&dir, "time.eds", TIME_1012);
        let mut bus = Simulation::new(Timing::Ideal).device(&eds, 5).start().unwrap();
        bus.run_until(Instant::ZERO + Duration::from_millis(500)).unwrap();
        bus.virtual_bus_mut().record();
        SdoSession::new(&mut bus, 5, Duration::from_millis(100))
            .unwrap()
            .write(0x1012, 0, 0x4000_0100u32.to_le_bytes().to_vec())
            .unwrap();
        bus.run_until(Instant::ZERO + Duration::from_millis(2600))
            .unwrap();
        let time: Vec<String> = bus
            .virtual_bus_mut()
            .take_recording()
            .iter()
            .filter(|f| f.frame.to_string().starts_with("100#"))
            .map(|f| format!("{} {}", f.at.as_micros(), f.frame))
            .collect();
        // 2024-01-01 is day 14610 (3912h) since 1984-01-01; 500 ms is 1F4h.
        assert_eq!(
            time,
            [
                "500000 100#F40100001239",
                "1500000 100#DC0500001239",
                "2500000 100#C40900001239",
            ]
        );
    }
}

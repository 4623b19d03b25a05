//! One emulated EnergyBus device as a sans-IO [`Core`]: a [`Device`] running the
//! [`EmsApplication`], with the LSS behaviour EnergyBus asks for and the EnergyBus faults.
//!
//! - LSS is mandatory: the device powers on without a node-ID (FFh) and waits for an LSS master
//!   (the EnergyBus controller's fastscan). It refuses store configuration ("storing not
//!   supported") and forgets its node-ID at every NMT reset node, the device's power cycle, so the
//!   controller assigns node-IDs afresh every time (design note §5.9: "NMT reset application →
//!   Disconnected; the node also forgets its node-ID, so LSS has to reassign it").
//! - Faults. Every fault of the device catalogue ([`crate::faults`]) applies as on any device; two
//!   of them are deviations the FORTE paper found (seeds/003 §5.4): `sync-counter-missing` and
//!   `lss-state-not-changed`. The third, "wrong behaviour of unconfigured slaves in the LSS
//!   fastscan protocol", is [`EnergyBusFault::FastscanWrongAnswer`], applied here around the
//!   device, on the received frame, so the LSS slave itself stays correct.

use std::fmt;
use std::str::FromStr;

use canopener_can::{CanFrame, Core, Instant};
use canopener_eds::model::Eds;
use canopener_od::{ObjectKey, OdError};
use canopener_wire::energybus::{EmsProfile, EmsState};
use canopener_wire::{LSS_MASTER_TO_SLAVE_ID, LssAddressPart, NodeId};

use crate::device::{Device, DeviceError, DeviceEvent, UNCONFIGURED};
use crate::energybus::ems::EmsApplication;
use crate::energybus::{EnergyBusError, profile};
use crate::faults::{Fault, FaultSet};
use crate::lss_slave::{BitTiming, LssStorage, LssStoreError, StoredConfiguration};

/// A defect of an emulated EnergyBus device that the device catalogue does not have.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum EnergyBusFault {
    /// The unconfigured slave compares only the bit BitChecked of a fastscan request, not bits
    /// 31..BitChecked.
    FastscanWrongAnswer,
}

impl EnergyBusFault {
    /// Every EnergyBus fault.
    pub const ALL: [EnergyBusFault; 1] = [EnergyBusFault::FastscanWrongAnswer];

    /// The stable kebab-case name (`--fault NAME`).
    pub const fn name(self) -> &'static str {
        match self {
            EnergyBusFault::FastscanWrongAnswer => "fastscan-wrong-answer",
        }
    }

    /// What the defect is, what a test should catch, and where it comes from.
    pub const fn description(self) -> &'static str {
        match self {
            EnergyBusFault::FastscanWrongAnswer => {
                "An unconfigured slave compares only the bit BitChecked of a fastscan request (51h) with \
                 its LSS address part, not bits 31..BitChecked (a mask 1 << BitChecked where CiA 305 \
                 asks for FFFFFFFFh << BitChecked), so it answers 4Fh to requests whose higher bits \
                 differ. Alone on the bus a master's scan still finds it (the higher bits of its \
                 requests match by then); beside other unconfigured slaves it answers for them and the \
                 scan finds no slave or the wrong address. A test should send a request whose checked \
                 bits differ above BitChecked and expect silence. From the EnergyBus paper (deviation 3: \
                 wrong behaviour of unconfigured slaves in the LSS fastscan protocol, not confirmed by \
                 the stack's vendor; this is one concrete reading of it)."
            }
        }
    }
}

impl fmt::Display for EnergyBusFault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A fault an emulated EnergyBus device can have: one of the device catalogue or an EnergyBus one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum DeviceFault {
    /// A fault of the device catalogue.
    Catalogue(Fault),
    /// An EnergyBus fault.
    EnergyBus(EnergyBusFault),
}

impl DeviceFault {
    /// The three deviations of the FORTE paper, in its order.
    pub const PAPER_DEVIATIONS: [DeviceFault; 3] = [
        DeviceFault::Catalogue(Fault::SyncCounterMissing),
        DeviceFault::Catalogue(Fault::LssStateNotChanged),
        DeviceFault::EnergyBus(EnergyBusFault::FastscanWrongAnswer),
    ];

    /// The fault's name.
    pub fn name(self) -> &'static str {
        match self {
            DeviceFault::Catalogue(fault) => fault.name(),
            DeviceFault::EnergyBus(fault) => fault.name(),
        }
    }
}

impl fmt::Display for DeviceFault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A name that is no fault of the catalogue and no EnergyBus fault.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown fault `{name}`; the faults are: {}", known())]
pub struct UnknownDeviceFault {
    /// The name given.
    pub name: String,
}

fn known() -> String {
    Fault::ALL
        .map(Fault::name)
        .into_iter()
        .chain(EnergyBusFault::ALL.map(EnergyBusFault::name))
        .collect::<Vec<_>>()
        .join(", ")
}

impl FromStr for DeviceFault {
    type Err = UnknownDeviceFault;

    fn from_str(s: &str) -> Result<DeviceFault, UnknownDeviceFault> {
        if let Ok(fault) = s.parse::<Fault>() {
            return Ok(DeviceFault::Catalogue(fault));
        }
        EnergyBusFault::ALL
            .into_iter()
            .find(|f| f.name().eq_ignore_ascii_case(s.trim()))
            .map(DeviceFault::EnergyBus)
            .ok_or_else(|| UnknownDeviceFault { name: s.to_owned() })
    }
}

/// Why an emulated EnergyBus device cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StationError {
    /// The description is no EnergyBus device or its assumptions do not read.
    #[error(transparent)]
    EnergyBus(#[from] EnergyBusError),
    /// The device cannot be built from the description.
    #[error(transparent)]
    Device(#[from] DeviceError),
    /// The serial number does not fit 1018h:04.
    #[error("cannot set the serial number 1018h:04: {0}")]
    Serial(OdError),
}

/// LSS storage of an EnergyBus device: nothing is kept, and a power cycle starts without a node-ID.
#[derive(Debug, Clone, Copy, Default)]
struct NodeIdForgotten;

impl LssStorage for NodeIdForgotten {
    fn store(
        &mut self,
        _node_id: Option<NodeId>,
        _bit_timing: Option<BitTiming>,
    ) -> Result<(), LssStoreError> {
        Err(LssStoreError::NotSupported)
    }

    fn stored(&self) -> Option<StoredConfiguration> {
        Some(StoredConfiguration {
            node_id: None,
            bit_timing: None,
        })
    }
}

/// An emulated EnergyBus device (see the [module docs](self)).
#[derive(Debug)]
pub struct EnergyBusDevice {
    device: Device,
    profile: EmsProfile,
    fastscan_wrong_answer: bool,
}

impl EnergyBusDevice {
    /// A device from `eds` (an EnergyBus description, such as [`crate::energybus::EDS`]) with serial
    /// number `serial` in 1018h:04, so that several devices of one description have distinct LSS
    /// addresses, and the defects `faults`. It powers on without a node-ID.
    pub fn new(eds: &Eds, serial: u32, faults: &[DeviceFault]) -> Result<EnergyBusDevice, StationError> {
        let profile = profile(eds)?;
        let app = Box::new(EmsApplication::new(profile.clone()));
        let catalogue: FaultSet = faults
            .iter()
            .filter_map(|f| match f {
                DeviceFault::Catalogue(fault) => Some(*fault),
                DeviceFault::EnergyBus(_) => None,
            })
            .collect();
        let device = Device::from_eds(eds, UNCONFIGURED, app)?
            .with_value(ObjectKey::new(0x1018, 4), &serial.to_le_bytes())
            .map_err(StationError::Serial)?
            .with_lss_storage(Box::new(NodeIdForgotten))
            .with_faults(catalogue);
        Ok(EnergyBusDevice {
            device,
            profile,
            fastscan_wrong_answer: faults
                .contains(&DeviceFault::EnergyBus(EnergyBusFault::FastscanWrongAnswer)),
        })
    }

    /// Power-on.
    pub fn boot(&mut self, now: Instant) {
        self.device.boot(now);
    }

    /// The device.
    pub fn device(&self) -> &Device {
        &self.device
    }

    /// The assumed objects and encodings it runs with.
    pub fn profile(&self) -> &EmsProfile {
        &self.profile
    }

    /// The EMS state its status word reports.
    pub fn ems_state(&self) -> Option<EmsState> {
        let entry = self
            .device
            .od()
            .get(ObjectKey::new(self.profile.objects.status_word, 0))?;
        let status = <[u8; 2]>::try_from(entry.value()).ok().map(u16::from_le_bytes)?;
        self.profile.state_of(status)
    }

    /// The node-ID it runs with, `None` while it has none.
    pub fn node_id(&self) -> Option<NodeId> {
        self.device.is_configured().then(|| self.device.node_id())
    }

    /// `fastscan-wrong-answer`: the IDNumber's bits above BitChecked replaced by the slave's own, so
    /// that the slave's (correct) comparison of bits 31..BitChecked looks at bit BitChecked alone.
    fn fault_inbound(&self, frame: &CanFrame) -> CanFrame {
        if !self.fastscan_wrong_answer
            || frame.id().as_raw() != u32::from(LSS_MASTER_TO_SLAVE_ID)
            || frame.is_remote()
        {
            return *frame;
        }
        let Ok([0x51, a, b, c, d, bit, sub, next]) = <[u8; 8]>::try_from(frame.data()) else {
            return *frame;
        };
        let (Some(part), Some(lss)) = (LssAddressPart::from_offset(sub), self.device.lss()) else {
            return *frame;
        };
        if bit > 31 {
            return *frame;
        }
        let own = lss.identity().part(part);
        let low = u32::MAX >> (31 - bit);
        let id = (u32::from_le_bytes([a, b, c, d]) & low) | (own & !low);
        let [a, b, c, d] = id.to_le_bytes();
        CanFrame::new(frame.id(), &[0x51, a, b, c, d, bit, sub, next]).unwrap_or(*frame)
    }
}

impl Core for EnergyBusDevice {
    type Event = DeviceEvent;

    fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
        let frame = self.fault_inbound(frame);
        self.device.handle_frame(now, &frame);
    }

    fn handle_timeout(&mut self, now: Instant) {
        self.device.handle_timeout(now);
    }

    fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.device.poll_transmit()
    }

    fn poll_event(&mut self) -> Option<DeviceEvent> {
        self.device.poll_event()
    }

    fn poll_timeout(&self) -> Option<Instant> {
        self.device.poll_timeout()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energybus::EDS;
    use canopener_testkit::trace::{Trace, ms};

    fn eds() -> Eds {
        canopener_eds::load(EDS.as_bytes()).eds
    }

    fn station(faults: &[DeviceFault]) -> Trace<EnergyBusDevice> {
        let mut device = EnergyBusDevice::new(&eds(), 7, faults).expect("builds");
        device.boot(Instant::ZERO);
        Trace::new(device)
    }

    #[test]
    fn names_read_back() {
        for fault in Fault::ALL.map(DeviceFault::Catalogue) {
            assert_eq!(fault.name().parse::<DeviceFault>(), Ok(fault));
        }
        assert_eq!(
            "fastscan-wrong-answer".parse::<DeviceFault>(),
            Ok(DeviceFault::EnergyBus(EnergyBusFault::FastscanWrongAnswer))
        );
        let unknown = "nope".parse::<DeviceFault>().unwrap_err().to_string();
        assert!(
            unknown.ends_with("tpdo-rtr-in-pre-operational, fastscan-wrong-answer"),
            "{unknown}"
        );
    }

    /// Powers on silent (no node-ID), is configured by LSS, boots in Connected, refuses to store
    /// its node-ID and forgets it at reset node.
    #[test]
    fn lss_is_mandatory_and_the_node_id_is_forgotten_at_reset_node() {
        let mut t = station(&[]);
        t.rx(ms(1), "7E5#0401000000000000");
        t.rx(ms(2), "7E5#1105000000000000");
        t.rx(ms(3), "7E5#1700000000000000");
        t.rx(ms(4), "7E5#0400000000000000");
        assert_eq!(t.core.node_id(), NodeId::new(5));
        assert_eq!(t.core.ems_state(), Some(EmsState::Connected));
        t.rx(ms(10), "000#8105");
        t.advance(ms(500));
        assert_eq!(t.core.node_id(), None);
        // After reset node the device is silent: no boot-up, no heartbeat, until LSS again.
        assert_eq!(
            t.sent(),
            [
                "2.000 7E4#1100000000000000",
                "3.000 7E4#1701000000000000",
                "4.000 705#00",
            ]
        );
    }

    /// A request whose bit 16 differs and that checks bits 31..1 gets no answer from a correct
    /// slave and a 4Fh from the faulty one; a request that checks bit 16 itself is refused by both.
    #[test]
    fn fastscan_wrong_answer_compares_only_the_checked_bit() {
        // Vendor-ID 0: bit 16 set differs.
        for (faults, answered) in [(vec![], false), (vec![EnergyBusFault::FastscanWrongAnswer], true)] {
            let faults: Vec<DeviceFault> = faults.into_iter().map(DeviceFault::EnergyBus).collect();
            let mut t = station(&faults);
            t.rx(ms(1), "7E5#5100000000800000");
            t.rx(ms(2), "7E5#5100000100010000");
            t.rx(ms(3), "7E5#5100000100100000");
            let frames = t.sent();
            let mut expected = vec!["1.000 7E4#4F00000000000000"];
            if answered {
                expected.push("2.000 7E4#4F00000000000000");
            }
            assert_eq!(frames, expected, "{faults:?}");
        }
    }
}

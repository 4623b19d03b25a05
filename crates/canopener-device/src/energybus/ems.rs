//! The EnergyBus EMS application: the virtual-device state machine of CiA 454 (as assumed, see
//! [`canopener_wire::energybus`]) behind a device's object dictionary, and the process values its
//! PDOs carry.
//!
//! - **State machine.** Power-on and NMT reset node enter Disconnected; Disconnected becomes
//!   Connected on its own after the profile's automatic step (the emulated device is always plugged
//!   in); every reset communication that leaves the device with a node-ID enters Connected, from
//!   where it goes on to Compatibility check on its own after another automatic step, unless the
//!   controller asks first (control word 3). Every other change is a control word write; a value
//!   that names no transition, or a transition the present state does not allow, is refused before
//!   it is stored ([`Application::check_write`]) with the profile's abort code. While the device has
//!   no node-ID the device runs no application timer, so nothing happens then (nor could anything be
//!   seen).
//! - **Status word**: the state in its bit field, the other bits 0; always in step with the state.
//! - **Process values.** Static: the virtual device type and the nominal voltage, as the
//!   description gives them. Dynamic, sampled every [`SAMPLE_PERIOD`]: the load the battery would
//!   deliver ([`LOAD_MA`] plus a deterministic ripple of ±100 mA), the actual current (that load,
//!   at most the current limit the controller wrote, while the state delivers power: Limiting and
//!   Operating; 0 otherwise: assumed, a device must not deliver power before), and the actual
//!   voltage (the nominal voltage less 50 mΩ times the current, plus a ripple of −50..+50 mV). A
//!   control word or current limit write updates them at once, so a PDO never shows a current that
//!   does not fit the state it shows.
//!
//! The values change silently (no [`AppChanges`]): the PDOs carrying them are cyclic (their event
//! timers), so their timing does not depend on the process.

use std::time::Duration;

use canopener_can::Instant;
use canopener_od::{DynamicOd, ObjectKey};
use canopener_wire::NodeId;
use canopener_wire::energybus::{EmsProfile, EmsState};

use crate::application::{AppChanges, Application};

/// How often the dynamic values are sampled.
pub const SAMPLE_PERIOD: Duration = Duration::from_millis(100);

/// The load the emulated battery would deliver, in mA, before its ripple.
pub const LOAD_MA: u16 = 2000;

/// The internal resistance of the emulated battery, in mΩ: the voltage drops by current × this.
pub const RESISTANCE_MILLIOHM: u32 = 50;

/// The widest the actual voltage strays from the nominal one, in mV: down by the full current
/// through the resistance and the ripple, up by the ripple.
pub const VOLTAGE_BELOW_NOMINAL_MV: u16 = 200;
/// See [`VOLTAGE_BELOW_NOMINAL_MV`].
pub const VOLTAGE_ABOVE_NOMINAL_MV: u16 = 50;

/// The EMS application of one device (see the [module docs](self)).
#[derive(Debug, Clone)]
pub struct EmsApplication {
    profile: EmsProfile,
    state: EmsState,
    has_node_id: bool,
    /// When the next automatic step is due.
    automatic: Option<Instant>,
    next_sample: Option<Instant>,
    sample: u32,
}

impl EmsApplication {
    /// The application with the objects and encodings of `profile`, in Disconnected until the
    /// device starts it.
    pub fn new(profile: EmsProfile) -> EmsApplication {
        EmsApplication {
            profile,
            state: EmsState::Disconnected,
            has_node_id: false,
            automatic: None,
            next_sample: None,
            sample: 0,
        }
    }

    /// The present state.
    pub fn state(&self) -> EmsState {
        self.state
    }

    /// The profile it runs with.
    pub fn profile(&self) -> &EmsProfile {
        &self.profile
    }

    fn enter(&mut self, now: Instant, state: EmsState) {
        self.state = state;
        let automatic = match state {
            EmsState::Disconnected => true,
            EmsState::Connected => self.has_node_id,
            _ => false,
        };
        self.automatic = automatic.then(|| now + self.profile.automatic_step);
    }

    /// The current the battery delivers now, in mA.
    fn current(&self, od: &DynamicOd) -> u16 {
        if !self.state.delivers_power() {
            return 0;
        }
        let limit = read_u16(od, self.profile.objects.current_limit).unwrap_or(0);
        let ripple = (self.sample.wrapping_mul(53) % 11) as u16 * 20;
        (LOAD_MA - 100 + ripple).min(limit)
    }

    /// Writes the status word and the dynamic values for the present state and sample.
    fn write_outputs(&self, od: &mut DynamicOd) {
        let objects = self.profile.objects;
        let current = self.current(od);
        let nominal = read_u16(od, objects.nominal_voltage).unwrap_or(0);
        let drop = (u32::from(current) * RESISTANCE_MILLIOHM / 1000) as u16;
        let ripple = (self.sample.wrapping_mul(37) % 11) as u16 * 10;
        let voltage = nominal
            .saturating_sub(drop)
            .saturating_sub(50)
            .saturating_add(ripple);
        let status = self.profile.status_bits(self.state);
        // Objects the description lacks were refused when the profile was read; a dictionary
        // built otherwise simply shows nothing.
        for (index, value) in [
            (objects.status_word, status),
            (objects.actual_current, current),
            (objects.actual_voltage, voltage),
        ] {
            let _ = od.set_value(ObjectKey::new(index, 0), &value.to_le_bytes());
        }
    }

    /// The state a control word write of `data` leads to, or the abort code that refuses it.
    fn target(&self, data: &[u8]) -> Result<EmsState, u32> {
        let refused = self.profile.refused_abort;
        let value = <[u8; 2]>::try_from(data)
            .map(u16::from_le_bytes)
            .map_err(|_| refused)?;
        let transition = self.profile.transition_of(value).ok_or(refused)?;
        transition
            .target(self.state, self.profile.passive, self.has_node_id)
            .ok_or(refused)
    }
}

impl Application for EmsApplication {
    fn reset(&mut self, now: Instant, od: &mut DynamicOd) -> AppChanges {
        self.sample = 0;
        self.next_sample = Some(now + SAMPLE_PERIOD);
        self.enter(now, EmsState::Disconnected);
        self.write_outputs(od);
        AppChanges::none()
    }

    fn reset_communication(
        &mut self,
        now: Instant,
        node_id: Option<NodeId>,
        od: &mut DynamicOd,
    ) -> AppChanges {
        self.has_node_id = node_id.is_some();
        if self.has_node_id {
            self.enter(now, EmsState::Connected);
        }
        self.write_outputs(od);
        AppChanges::none()
    }

    fn check_write(&self, key: ObjectKey, data: &[u8], _od: &DynamicOd) -> Result<(), u32> {
        if key == ObjectKey::new(self.profile.objects.control_word, 0) {
            self.target(data)?;
        }
        Ok(())
    }

    fn on_write(&mut self, now: Instant, key: ObjectKey, od: &mut DynamicOd) -> AppChanges {
        let objects = self.profile.objects;
        if key == ObjectKey::new(objects.control_word, 0) {
            let written = od.get(key).map(|e| e.value().to_vec()).unwrap_or_default();
            // Checked before it was stored; a refused value never gets here.
            if let Ok(state) = self.target(&written) {
                self.enter(now, state);
            }
        }
        if key.index == objects.control_word || key.index == objects.current_limit {
            self.write_outputs(od);
        }
        AppChanges::none()
    }

    fn handle_timeout(&mut self, now: Instant, od: &mut DynamicOd) -> AppChanges {
        if self.automatic.is_some_and(|due| due <= now) {
            self.automatic = None;
            match self.state {
                EmsState::Disconnected => self.enter(now, EmsState::Connected),
                EmsState::Connected if self.has_node_id => self.enter(now, EmsState::CompatibilityCheck),
                _ => {}
            }
        }
        if let Some(due) = self.next_sample.filter(|due| *due <= now) {
            self.sample = self.sample.wrapping_add(1);
            let next = due + SAMPLE_PERIOD;
            // A device that had no node-ID ran no timer: it starts sampling again from now.
            self.next_sample = Some(if next > now { next } else { now + SAMPLE_PERIOD });
        }
        self.write_outputs(od);
        AppChanges::none()
    }

    fn poll_timeout(&self) -> Option<Instant> {
        [self.automatic, self.next_sample].into_iter().flatten().min()
    }
}

fn read_u16(od: &DynamicOd, index: u16) -> Option<u16> {
    let entry = od.get(ObjectKey::new(index, 0))?;
    <[u8; 2]>::try_from(entry.value()).ok().map(u16::from_le_bytes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energybus::{EDS, profile};
    use crate::od_build::build_od;
    use canopener_wire::energybus::EmsTransition;

    fn setup() -> (EmsApplication, DynamicOd) {
        let eds = canopener_eds::load(EDS.as_bytes()).eds;
        let od = build_od(&eds, 5).expect("the shipped description builds").od;
        (EmsApplication::new(profile(&eds).expect("profile")), od)
    }

    fn status(od: &DynamicOd) -> u16 {
        read_u16(od, 0x6002).unwrap()
    }

    fn control(app: &mut EmsApplication, od: &mut DynamicOd, now: Instant, value: u16) -> Result<(), u32> {
        let key = ObjectKey::new(0x6001, 0);
        app.check_write(key, &value.to_le_bytes(), od)?;
        od.set_value(key, &value.to_le_bytes()).unwrap();
        app.on_write(now, key, od);
        Ok(())
    }

    fn at(ms: u64) -> Instant {
        Instant::from_millis(ms)
    }

    #[test]
    fn power_on_steps_to_connected_and_to_compatibility_check_once_it_has_a_node_id() {
        let (mut app, mut od) = setup();
        app.reset(at(0), &mut od);
        app.reset_communication(at(0), None, &mut od);
        assert_eq!((app.state(), status(&od)), (EmsState::Disconnected, 0x0000));
        app.handle_timeout(at(200), &mut od);
        assert_eq!((app.state(), status(&od)), (EmsState::Connected, 0x2000));
        // No node-ID: it stays Connected.
        assert_eq!(app.poll_timeout(), Some(at(300)), "only the sample timer");
        app.reset_communication(at(1000), NodeId::new(5), &mut od);
        app.handle_timeout(at(1199), &mut od);
        assert_eq!(app.state(), EmsState::Connected);
        app.handle_timeout(at(1200), &mut od);
        assert_eq!((app.state(), status(&od)), (EmsState::CompatibilityCheck, 0x4000));
    }

    #[test]
    fn the_controller_walks_it_to_operating_and_refused_writes_change_nothing() {
        let (mut app, mut od) = setup();
        app.reset(at(0), &mut od);
        app.reset_communication(at(0), NodeId::new(5), &mut od);
        let refused = app.profile().refused_abort;
        assert_eq!(
            control(&mut app, &mut od, at(1), 6),
            Err(refused),
            "Limiting -> Operating from Connected"
        );
        assert_eq!(
            control(&mut app, &mut od, at(1), 0x7D),
            Err(refused),
            "sleep is not modelled"
        );
        assert_eq!(control(&mut app, &mut od, at(1), 3), Ok(()));
        assert_eq!(
            control(&mut app, &mut od, at(2), 4),
            Err(refused),
            "4 is for passive devices"
        );
        assert_eq!(control(&mut app, &mut od, at(2), 5), Ok(()));
        assert_eq!((app.state(), status(&od)), (EmsState::Limiting, 0x6000));
        assert_eq!(read_u16(&od, 0x603E), Some(0), "no current without a limit");
        od.set_value(ObjectKey::new(0x6020, 0), &1500u16.to_le_bytes())
            .unwrap();
        app.on_write(at(3), ObjectKey::new(0x6020, 0), &mut od);
        assert_eq!(read_u16(&od, 0x603E), Some(1500), "the load is limited");
        assert_eq!(control(&mut app, &mut od, at(4), 6), Ok(()));
        assert_eq!((app.state(), status(&od)), (EmsState::Operating, 0x8000));
        assert_eq!(control(&mut app, &mut od, at(5), 10), Ok(()));
        assert_eq!(app.state(), EmsState::Masterless);
        assert_eq!(
            read_u16(&od, 0x603E),
            Some(0),
            "Masterless delivers no power (assumed)"
        );
        let value = app
            .profile()
            .control_value(EmsTransition::ToDisconnected)
            .unwrap();
        assert_eq!(control(&mut app, &mut od, at(6), value), Ok(()));
        assert_eq!(app.state(), EmsState::Disconnected);
        app.handle_timeout(at(206), &mut od);
        assert_eq!(app.state(), EmsState::Connected, "plugged in: back to Connected");
    }

    #[test]
    fn dynamic_values_stay_in_their_documented_ranges() {
        let (mut app, mut od) = setup();
        app.reset(at(0), &mut od);
        app.reset_communication(at(0), NodeId::new(5), &mut od);
        od.set_value(ObjectKey::new(0x6020, 0), &5000u16.to_le_bytes())
            .unwrap();
        for value in [3, 5, 6] {
            control(&mut app, &mut od, at(1), value).unwrap();
        }
        let nominal = read_u16(&od, 0x6008).unwrap();
        let mut currents = std::collections::BTreeSet::new();
        for k in 1..=200 {
            app.handle_timeout(at(k * 100), &mut od);
            let (v, i) = (read_u16(&od, 0x6040).unwrap(), read_u16(&od, 0x603E).unwrap());
            assert!((LOAD_MA - 100..=LOAD_MA + 100).contains(&i), "{i}");
            assert!(
                (nominal - VOLTAGE_BELOW_NOMINAL_MV..=nominal + VOLTAGE_ABOVE_NOMINAL_MV).contains(&v),
                "{v}"
            );
            currents.insert(i);
        }
        assert!(currents.len() > 5, "the current varies: {currents:?}");
    }
}

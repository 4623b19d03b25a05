//! The emulated EnergyBus device (CiA 454 energy management system, EMS), as the FORTE paper's
//! framework emulated devices because none were on the market (seeds/003 §5.4).
//!
//! Three parts:
//! - [`EDS`], the one description file: a battery pack with the assumed CiA 454 objects (6000h
//!   range) and the `[EnergyBusAssumptions]` section that holds every assumed encoding. CiA 454 is
//!   not in the project's references; `docs/energybus.md` lists each assumption and how to replace
//!   it. [`profile`] reads the assumptions of a description and checks that the objects they name
//!   exist with the types the application needs.
//! - [`ems::EmsApplication`], the [`Application`](crate::application::Application) behind the
//!   dictionary: the EMS state machine driven by SDO writes to the control word and reported in the
//!   status word, and the process values its PDOs carry (static: device type and nominal voltage;
//!   dynamic: status word, actual voltage and current).
//! - [`station::EnergyBusDevice`], a [`Device`](crate::device::Device) with that application, LSS
//!   mandatory (it powers on without a node-ID and forgets its node-ID at every reset node, as
//!   EnergyBus devices do), and the EnergyBus faults ([`station::EnergyBusFault`]) the paper's
//!   deviations become.

pub mod ems;
pub mod station;

use canopener_eds::model::{Eds, typed};
use canopener_od::DataType;
use canopener_wire::energybus::{ASSUMPTIONS_SECTION, EmsProfile, ProfileError};

/// The shipped description of the emulated EnergyBus battery (`energybus/energybus-battery.eds`).
pub const EDS: &str = include_str!("../energybus/energybus-battery.eds");

/// Why a description cannot run the EnergyBus application.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum EnergyBusError {
    /// The description has no `[EnergyBusAssumptions]` section.
    #[error(
        "the description has no [{ASSUMPTIONS_SECTION}] section, so it is no EnergyBus device; start from the \
         shipped energybus-battery.eds (docs/energybus.md)"
    )]
    NotEnergyBus,
    /// A key of the section is missing or wrong.
    #[error(transparent)]
    Profile(#[from] ProfileError),
    /// An object the assumptions name is missing or has the wrong type.
    #[error("object {index:04X}h ({role}) {why}")]
    Object {
        /// The object.
        index: u16,
        /// What the assumptions call it.
        role: &'static str,
        /// What is wrong.
        why: String,
    },
}

/// Whether `eds` describes an EnergyBus device: it has the `[EnergyBusAssumptions]` section.
pub fn is_energybus(eds: &Eds) -> bool {
    assumptions(eds).is_some()
}

fn assumptions(eds: &Eds) -> Option<&canopener_eds::model::RawSection> {
    eds.other_sections
        .iter()
        .find(|s| s.name.eq_ignore_ascii_case(ASSUMPTIONS_SECTION))
}

/// The assumed EMS objects and encodings of `eds`, checked against its objects: every object the
/// section names exists as a VAR of the type the application reads and writes (UNSIGNED8 for the
/// virtual device, UNSIGNED16 for the others).
pub fn profile(eds: &Eds) -> Result<EmsProfile, EnergyBusError> {
    let section = assumptions(eds).ok_or(EnergyBusError::NotEnergyBus)?;
    let profile = EmsProfile::from_keys(|key| section.entries.get(key))?;
    for (role, index) in profile.objects.keyed() {
        let wanted = if role == "VirtualDevice" {
            DataType::UNSIGNED8
        } else {
            DataType::UNSIGNED16
        };
        let object = eds.objects.get(&index).ok_or_else(|| EnergyBusError::Object {
            index,
            role,
            why: "is not in the description".into(),
        })?;
        let data_type = object.attributes.data_type();
        if !object.subs.is_empty() || data_type != Some(wanted) {
            return Err(EnergyBusError::Object {
                index,
                role,
                why: format!("must be a VAR of type {wanted}"),
            });
        }
        // The value must read, so that the dictionary builds.
        let default = typed(object.attributes.default_value.as_deref(), data_type);
        if default.value.is_none() {
            return Err(EnergyBusError::Object {
                index,
                role,
                why: "has no default value".into(),
            });
        }
    }
    Ok(profile)
}

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_wire::energybus::EmsState;

    fn shipped() -> Eds {
        canopener_eds::load(EDS.as_bytes()).eds
    }

    #[test]
    fn the_shipped_description_is_an_energybus_device() {
        let eds = shipped();
        assert!(is_energybus(&eds));
        let profile = profile(&eds).expect("the shipped assumptions read");
        assert_eq!(profile.status_bits(EmsState::Operating), 0x8000);
        assert_eq!(profile.objects.actual_voltage, 0x6040);
    }

    #[test]
    fn a_description_without_the_assumptions_is_none() {
        let text = EDS.replace("[EnergyBusAssumptions]", "[Other]");
        let eds = canopener_eds::load(text.as_bytes()).eds;
        assert!(!is_energybus(&eds));
        assert_eq!(profile(&eds), Err(EnergyBusError::NotEnergyBus));
    }

    #[test]
    fn objects_the_assumptions_name_must_exist_with_their_type() {
        let moved = EDS.replace("Object_StatusWord=0x6002", "Object_StatusWord=0x6003");
        let error = profile(&canopener_eds::load(moved.as_bytes()).eds).unwrap_err();
        assert_eq!(
            error.to_string(),
            "object 6003h (StatusWord) is not in the description"
        );
        let typed = EDS.replacen(
            "ParameterName=EMS control word (assumed)\nObjectType=0x7\nDataType=0x0006",
            "ParameterName=EMS control word (assumed)\nObjectType=0x7\nDataType=0x0007",
            1,
        );
        assert_ne!(typed, EDS, "the control word section is as written");
        let error = profile(&canopener_eds::load(typed.as_bytes()).eds).unwrap_err();
        assert!(
            error
                .to_string()
                .contains("6001h (ControlWord) must be a VAR of type"),
            "{error}"
        );
    }
}

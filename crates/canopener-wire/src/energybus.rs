//! The EnergyBus energy management system (EMS, CiA 454) on the wire, as *assumed*.
//!
//! CiA 454 is for CiA members only and is not in the project's references. What the EnergyBus code
//! of canopener uses of it comes from the public material the design note (§5.9) collected: the
//! emtas EnergyBus Framework source "according to CiA 454" (work draft era, 2012–2015). Every object
//! index and every encoding here is therefore an assumption, and none is written in code: an
//! [`EmsProfile`] is read from the keys of the `[EnergyBusAssumptions]` section of the one EnergyBus
//! description file canopener ships (see `docs/energybus.md`, which lists each key and how to
//! replace it with the real CiA 454 value). What is code is the shape of the virtual-device state
//! machine (which transition is allowed from which state), also from the design note:
//!
//! ```text
//! Disconnected --automatic--> Connected --automatic with a node-ID, or 3--> Compatibility check
//! Compatibility check --5--> Limiting --6--> Operating;  Compatibility check --4, passive only--> Operating
//! Operating --10--> Masterless --11--> Compatibility check
//! any --1, 8, 9--> Disconnected;  any --2, 7--> Connected
//! ```
//!
//! The numbers are the control word values of the shipped description (the transition numbers of
//! the source); the state is the value of a bit field of the status word.

use std::fmt;
use std::time::Duration;

/// The section of the EnergyBus description file that holds the assumed encodings.
pub const ASSUMPTIONS_SECTION: &str = "EnergyBusAssumptions";

/// A state of the EMS virtual-device state machine. The three Running states of the FORTE paper are
/// [`EmsState::CompatibilityCheck`], [`EmsState::Limiting`] and [`EmsState::Operating`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum EmsState {
    /// Not connected to the EnergyBus.
    Disconnected,
    /// Plugged in: on the CAN network, may use the bus as auxiliary supply.
    Connected,
    /// Running: its electrical characteristics are checked against the connected devices.
    CompatibilityCheck,
    /// Running: its variable power settings are adjusted.
    Limiting,
    /// Running: its application runs (a battery delivers power).
    Operating,
    /// Operating without an EnergyBus controller.
    Masterless,
}

impl EmsState {
    /// Every state, in the order of [`EmsProfile::state_codes`].
    pub const ALL: [EmsState; 6] = [
        EmsState::Disconnected,
        EmsState::Connected,
        EmsState::CompatibilityCheck,
        EmsState::Limiting,
        EmsState::Operating,
        EmsState::Masterless,
    ];

    /// The name the description file's keys use: `Disconnected`, `CompatibilityCheck`, ...
    pub const fn key(self) -> &'static str {
        match self {
            EmsState::Disconnected => "Disconnected",
            EmsState::Connected => "Connected",
            EmsState::CompatibilityCheck => "CompatibilityCheck",
            EmsState::Limiting => "Limiting",
            EmsState::Operating => "Operating",
            EmsState::Masterless => "Masterless",
        }
    }

    /// Whether the device may deliver power (assumed: only in Limiting and Operating).
    pub const fn delivers_power(self) -> bool {
        matches!(self, EmsState::Limiting | EmsState::Operating)
    }

    /// This state's code among `codes`, which are in [`EmsState::ALL`] order.
    #[allow(
        clippy::indexing_slicing,
        reason = "`position` is 0..=5 for the six states, the array's length"
    )]
    fn code_in(self, codes: &[u16; 6]) -> u16 {
        codes[self.position()]
    }

    fn position(self) -> usize {
        match self {
            EmsState::Disconnected => 0,
            EmsState::Connected => 1,
            EmsState::CompatibilityCheck => 2,
            EmsState::Limiting => 3,
            EmsState::Operating => 4,
            EmsState::Masterless => 5,
        }
    }
}

/// `Compatibility check`, `Operating`, ...
impl fmt::Display for EmsState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            EmsState::Disconnected => "Disconnected",
            EmsState::Connected => "Connected",
            EmsState::CompatibilityCheck => "Compatibility check",
            EmsState::Limiting => "Limiting",
            EmsState::Operating => "Operating",
            EmsState::Masterless => "Masterless",
        })
    }
}

/// A transition the EMS controller asks for by writing the control word.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum EmsTransition {
    /// Any state to Disconnected.
    ToDisconnected,
    /// Any state to Connected.
    ToConnected,
    /// Connected to Compatibility check (only with a node-ID).
    ConnectedToCompatibilityCheck,
    /// Compatibility check to Operating, for passive devices only.
    CompatibilityCheckToOperating,
    /// Compatibility check to Limiting.
    CompatibilityCheckToLimiting,
    /// Limiting to Operating.
    LimitingToOperating,
    /// Operating to Masterless.
    OperatingToMasterless,
    /// Masterless to Compatibility check.
    MasterlessToCompatibilityCheck,
}

impl EmsTransition {
    /// Every transition.
    pub const ALL: [EmsTransition; 8] = [
        EmsTransition::ToDisconnected,
        EmsTransition::ToConnected,
        EmsTransition::ConnectedToCompatibilityCheck,
        EmsTransition::CompatibilityCheckToOperating,
        EmsTransition::CompatibilityCheckToLimiting,
        EmsTransition::LimitingToOperating,
        EmsTransition::OperatingToMasterless,
        EmsTransition::MasterlessToCompatibilityCheck,
    ];

    /// The key of its control word values in the description file, after `Control_`.
    pub const fn key(self) -> &'static str {
        match self {
            EmsTransition::ToDisconnected => "ToDisconnected",
            EmsTransition::ToConnected => "ToConnected",
            EmsTransition::ConnectedToCompatibilityCheck => "ConnectedToCompatibilityCheck",
            EmsTransition::CompatibilityCheckToOperating => "CompatibilityCheckToOperating",
            EmsTransition::CompatibilityCheckToLimiting => "CompatibilityCheckToLimiting",
            EmsTransition::LimitingToOperating => "LimitingToOperating",
            EmsTransition::OperatingToMasterless => "OperatingToMasterless",
            EmsTransition::MasterlessToCompatibilityCheck => "MasterlessToCompatibilityCheck",
        }
    }

    /// The state this transition leads to from `from`, or `None` where the state machine does not
    /// allow it. `passive`: the device is a passive one (device class 0); `has_node_id`: the device
    /// has a node-ID (Compatibility check needs one).
    pub fn target(self, from: EmsState, passive: bool, has_node_id: bool) -> Option<EmsState> {
        use EmsState as S;
        use EmsTransition as T;
        match (self, from) {
            (T::ToDisconnected, _) => Some(S::Disconnected),
            (T::ToConnected, _) => Some(S::Connected),
            (T::ConnectedToCompatibilityCheck, S::Connected) if has_node_id => Some(S::CompatibilityCheck),
            (T::CompatibilityCheckToOperating, S::CompatibilityCheck) if passive => Some(S::Operating),
            (T::CompatibilityCheckToLimiting, S::CompatibilityCheck) => Some(S::Limiting),
            (T::LimitingToOperating, S::Limiting) => Some(S::Operating),
            (T::OperatingToMasterless, S::Operating) => Some(S::Masterless),
            (T::MasterlessToCompatibilityCheck, S::Masterless) => Some(S::CompatibilityCheck),
            _ => None,
        }
    }
}

/// The object indices of the EMS objects.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct EmsObjects {
    /// The virtual device (its device type code), `Object_VirtualDevice`.
    pub virtual_device: u16,
    /// The control word, `Object_ControlWord`.
    pub control_word: u16,
    /// The status word, `Object_StatusWord`.
    pub status_word: u16,
    /// The nominal voltage, `Object_NominalVoltage`.
    pub nominal_voltage: u16,
    /// The current limit the controller sets in Limiting, `Object_CurrentLimit`.
    pub current_limit: u16,
    /// The actual current, `Object_ActualCurrent`.
    pub actual_current: u16,
    /// The actual voltage, `Object_ActualVoltage`.
    pub actual_voltage: u16,
}

impl EmsObjects {
    /// The key of each index in the description file (after `Object_`) with its value.
    pub fn keyed(&self) -> [(&'static str, u16); 7] {
        [
            ("VirtualDevice", self.virtual_device),
            ("ControlWord", self.control_word),
            ("StatusWord", self.status_word),
            ("NominalVoltage", self.nominal_voltage),
            ("CurrentLimit", self.current_limit),
            ("ActualCurrent", self.actual_current),
            ("ActualVoltage", self.actual_voltage),
        ]
    }
}

/// Every assumed object index and encoding, as the description file gives them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EmsProfile {
    /// The object indices.
    pub objects: EmsObjects,
    /// The lowest bit of the state field in the status word.
    pub state_shift: u8,
    /// The width of the state field in bits.
    pub state_width: u8,
    /// The state field's value of each state, in the order of [`EmsState::ALL`].
    pub state_codes: [u16; 6],
    /// The control word values and the transition each asks for.
    pub controls: Vec<(u16, EmsTransition)>,
    /// The SDO abort code a device answers a control word it refuses with.
    pub refused_abort: u32,
    /// How long a device takes for the automatic steps (Disconnected to Connected, and Connected to
    /// Compatibility check once it has a node-ID).
    pub automatic_step: Duration,
    /// Whether the device is a passive one (device class 0).
    pub passive: bool,
}

/// Why the description file's assumptions do not make a profile.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ProfileError {
    /// A key is missing.
    #[error("[{ASSUMPTIONS_SECTION}] has no `{0}`; docs/energybus.md lists every key")]
    Missing(String),
    /// A key's value does not read.
    #[error("[{ASSUMPTIONS_SECTION}] {key}={value}: {why}")]
    Invalid {
        /// The key.
        key: String,
        /// Its value.
        value: String,
        /// What is wrong.
        why: String,
    },
}

impl EmsProfile {
    /// Reads the profile from the `[EnergyBusAssumptions]` keys `get` looks up (case as written in
    /// `docs/energybus.md`).
    pub fn from_keys<'a>(get: impl Fn(&str) -> Option<&'a str>) -> Result<EmsProfile, ProfileError> {
        let text = |key: &str| {
            get(key)
                .map(str::trim)
                .ok_or_else(|| ProfileError::Missing(key.into()))
        };
        let invalid = |key: &str, value: &str, why: &str| ProfileError::Invalid {
            key: key.into(),
            value: value.into(),
            why: why.into(),
        };
        let number = |key: &str| -> Result<u64, ProfileError> {
            let value = text(key)?;
            parse_number(value).ok_or_else(|| invalid(key, value, "not a number (decimal or 0x hex)"))
        };
        let index = |name: &str| -> Result<u16, ProfileError> {
            let key = format!("Object_{name}");
            let value = number(&key)?;
            u16::try_from(value)
                .ok()
                .filter(|i| *i != 0)
                .ok_or_else(|| invalid(&key, &value.to_string(), "not an object index 0001h..FFFFh"))
        };
        let objects = EmsObjects {
            virtual_device: index("VirtualDevice")?,
            control_word: index("ControlWord")?,
            status_word: index("StatusWord")?,
            nominal_voltage: index("NominalVoltage")?,
            current_limit: index("CurrentLimit")?,
            actual_current: index("ActualCurrent")?,
            actual_voltage: index("ActualVoltage")?,
        };
        let bits_key = "Status_StateBits";
        let bits = text(bits_key)?;
        let (high, low) = bits
            .split_once("..")
            .and_then(|(h, l)| Some((h.trim().parse::<u8>().ok()?, l.trim().parse::<u8>().ok()?)))
            .filter(|(h, l)| h >= l && *h < 16)
            .ok_or_else(|| {
                invalid(
                    bits_key,
                    bits,
                    "give the bits as HIGH..LOW within 15..0, e.g. 15..13",
                )
            })?;
        let (state_shift, state_width) = (low, high - low + 1);
        let mut state_codes = [0u16; 6];
        for state in EmsState::ALL {
            let key = format!("State_{}", state.key());
            let value = number(&key)?;
            let code = u16::try_from(value)
                .ok()
                .filter(|v| u32::from(*v) < 1u32 << state_width)
                .ok_or_else(|| invalid(&key, &value.to_string(), "does not fit the state bits"))?;
            if let Some(other) = EmsState::ALL
                .iter()
                .take(state.position())
                .find(|s| s.code_in(&state_codes) == code)
            {
                return Err(invalid(
                    &key,
                    &value.to_string(),
                    &format!("{other} has that code"),
                ));
            }
            if let Some(slot) = state_codes.get_mut(state.position()) {
                *slot = code;
            }
        }
        let mut controls: Vec<(u16, EmsTransition)> = Vec::new();
        for transition in EmsTransition::ALL {
            let key = format!("Control_{}", transition.key());
            let list = text(&key)?;
            for item in list.split(',') {
                let value = parse_number(item.trim())
                    .and_then(|v| u16::try_from(v).ok())
                    .ok_or_else(|| invalid(&key, list, "not a list of control word values"))?;
                if let Some((_, other)) = controls.iter().find(|(v, _)| *v == value) {
                    let why = format!("{value} already asks for {}", other.key());
                    return Err(invalid(&key, list, &why));
                }
                controls.push((value, transition));
            }
        }
        let abort_key = "Control_RefusedAbort";
        let refused_abort = u32::try_from(number(abort_key)?).map_err(|_| {
            invalid(
                abort_key,
                text(abort_key).unwrap_or(""),
                "not a 32-bit abort code",
            )
        })?;
        let step_key = "Device_AutomaticStepMs";
        let automatic_step = Duration::from_millis(number(step_key)?);
        let passive_key = "Device_Passive";
        let passive = match number(passive_key)? {
            0 => false,
            1 => true,
            _ => {
                return Err(invalid(
                    passive_key,
                    text(passive_key)?,
                    "0 (active) or 1 (passive)",
                ));
            }
        };
        Ok(EmsProfile {
            objects,
            state_shift,
            state_width,
            state_codes,
            controls,
            refused_abort,
            automatic_step,
            passive,
        })
    }

    /// The state a status word reports, or `None` for a code no state has.
    pub fn state_of(&self, status: u16) -> Option<EmsState> {
        let mask = (1u32 << self.state_width) - 1;
        let code = (u32::from(status) >> self.state_shift) & mask;
        EmsState::ALL
            .into_iter()
            .find(|s| u32::from(s.code_in(&self.state_codes)) == code)
    }

    /// The status word bits that report `state` (the other bits 0).
    pub fn status_bits(&self, state: EmsState) -> u16 {
        state.code_in(&self.state_codes) << self.state_shift
    }

    /// The transition a control word value asks for, if any.
    pub fn transition_of(&self, control: u16) -> Option<EmsTransition> {
        self.controls.iter().find(|(v, _)| *v == control).map(|(_, t)| *t)
    }

    /// The first control word value that asks for `transition`.
    pub fn control_value(&self, transition: EmsTransition) -> Option<u16> {
        self.controls
            .iter()
            .find(|(_, t)| *t == transition)
            .map(|(v, _)| *v)
    }

    /// What a control word value means, for people: `5 (Compatibility check -> Limiting)`.
    pub fn describe_control(&self, control: u16) -> String {
        match self.transition_of(control) {
            Some(t) => format!("{control} ({})", transition_text(t)),
            None => format!("{control} (no transition)"),
        }
    }
}

fn transition_text(t: EmsTransition) -> &'static str {
    match t {
        EmsTransition::ToDisconnected => "-> Disconnected",
        EmsTransition::ToConnected => "-> Connected",
        EmsTransition::ConnectedToCompatibilityCheck => "Connected -> Compatibility check",
        EmsTransition::CompatibilityCheckToOperating => "Compatibility check -> Operating, passive",
        EmsTransition::CompatibilityCheckToLimiting => "Compatibility check -> Limiting",
        EmsTransition::LimitingToOperating => "Limiting -> Operating",
        EmsTransition::OperatingToMasterless => "Operating -> Masterless",
        EmsTransition::MasterlessToCompatibilityCheck => "Masterless -> Compatibility check",
    }
}

/// A decimal or `0x` hexadecimal number.
fn parse_number(text: &str) -> Option<u64> {
    match text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        Some(hex) => u64::from_str_radix(hex, 16).ok(),
        None => text.parse().ok(),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The keys of the shipped description file (crates/canopener-device/energybus).
    pub(crate) const KEYS: &[(&str, &str)] = &[
        ("Object_VirtualDevice", "0x6000"),
        ("Object_ControlWord", "0x6001"),
        ("Object_StatusWord", "0x6002"),
        ("Object_NominalVoltage", "0x6008"),
        ("Object_CurrentLimit", "0x6020"),
        ("Object_ActualCurrent", "0x603E"),
        ("Object_ActualVoltage", "0x6040"),
        ("Status_StateBits", "15..13"),
        ("State_Disconnected", "0"),
        ("State_Connected", "1"),
        ("State_CompatibilityCheck", "2"),
        ("State_Limiting", "3"),
        ("State_Operating", "4"),
        ("State_Masterless", "5"),
        ("Control_ToDisconnected", "1, 8, 9"),
        ("Control_ToConnected", "2, 7"),
        ("Control_ConnectedToCompatibilityCheck", "3"),
        ("Control_CompatibilityCheckToOperating", "4"),
        ("Control_CompatibilityCheckToLimiting", "5"),
        ("Control_LimitingToOperating", "6"),
        ("Control_OperatingToMasterless", "10"),
        ("Control_MasterlessToCompatibilityCheck", "11"),
        ("Control_RefusedAbort", "0x08000022"),
        ("Device_AutomaticStepMs", "200"),
        ("Device_Passive", "0"),
    ];

    fn profile_with(change: (&str, &str)) -> Result<EmsProfile, ProfileError> {
        EmsProfile::from_keys(|key| {
            if key == change.0 {
                return (!change.1.is_empty()).then_some(change.1);
            }
            KEYS.iter().find(|(k, _)| *k == key).map(|(_, v)| *v)
        })
    }

    fn profile() -> EmsProfile {
        profile_with(("", "")).expect("the shipped keys read")
    }

    #[test]
    fn the_shipped_keys_read_as_the_design_note_says() {
        let p = profile();
        assert_eq!(p.objects.control_word, 0x6001);
        assert_eq!((p.state_shift, p.state_width), (13, 3));
        assert_eq!(p.status_bits(EmsState::Operating), 0x8000);
        assert_eq!(p.state_of(0x8000 | 0x1FFF), Some(EmsState::Operating));
        assert_eq!(p.state_of(0x6000), Some(EmsState::Limiting));
        assert_eq!(p.state_of(0xE000), None, "code 7 (sleep) is no modelled state");
        assert_eq!(p.transition_of(8), Some(EmsTransition::ToDisconnected));
        assert_eq!(p.transition_of(0x7D), None);
        assert_eq!(p.control_value(EmsTransition::ToConnected), Some(2));
        assert_eq!(p.refused_abort, 0x0800_0022);
        assert_eq!(p.automatic_step, Duration::from_millis(200));
        assert!(!p.passive);
        assert_eq!(p.describe_control(5), "5 (Compatibility check -> Limiting)");
    }

    #[test]
    fn wrong_keys_are_named() {
        let missing = profile_with(("State_Limiting", "")).unwrap_err();
        assert_eq!(
            missing.to_string(),
            "[EnergyBusAssumptions] has no `State_Limiting`; docs/energybus.md lists every key"
        );
        let twice = profile_with(("State_Limiting", "2")).unwrap_err();
        assert!(
            twice.to_string().contains("Compatibility check has that code"),
            "{twice}"
        );
        let wide = profile_with(("State_Limiting", "8")).unwrap_err();
        assert!(wide.to_string().contains("does not fit the state bits"), "{wide}");
        let bits = profile_with(("Status_StateBits", "13..15")).unwrap_err();
        assert!(bits.to_string().contains("HIGH..LOW"), "{bits}");
        let again = profile_with(("Control_LimitingToOperating", "5")).unwrap_err();
        assert!(again.to_string().contains("5 already asks for"), "{again}");
        let index = profile_with(("Object_ControlWord", "0x10000")).unwrap_err();
        assert!(index.to_string().contains("not an object index"), "{index}");
    }

    /// The state machine of the design note: every allowed change, and nothing else.
    #[test]
    fn transitions_follow_the_state_machine() {
        use EmsState as S;
        use EmsTransition as T;
        let allowed: Vec<(T, S, S)> = T::ALL
            .into_iter()
            .flat_map(|t| S::ALL.into_iter().map(move |s| (t, s)))
            .filter_map(|(t, s)| t.target(s, false, true).map(|to| (t, s, to)))
            .filter(|(t, _, _)| !matches!(t, T::ToDisconnected | T::ToConnected))
            .collect();
        assert_eq!(
            allowed,
            [
                (
                    T::ConnectedToCompatibilityCheck,
                    S::Connected,
                    S::CompatibilityCheck
                ),
                (
                    T::CompatibilityCheckToLimiting,
                    S::CompatibilityCheck,
                    S::Limiting
                ),
                (T::LimitingToOperating, S::Limiting, S::Operating),
                (T::OperatingToMasterless, S::Operating, S::Masterless),
                (
                    T::MasterlessToCompatibilityCheck,
                    S::Masterless,
                    S::CompatibilityCheck
                ),
            ]
        );
        assert_eq!(
            T::CompatibilityCheckToOperating.target(S::CompatibilityCheck, true, true),
            Some(S::Operating)
        );
        assert_eq!(
            T::ConnectedToCompatibilityCheck.target(S::Connected, false, false),
            None
        );
        for s in S::ALL {
            assert_eq!(T::ToDisconnected.target(s, false, false), Some(S::Disconnected));
            assert_eq!(T::ToConnected.target(s, false, false), Some(S::Connected));
        }
    }
}

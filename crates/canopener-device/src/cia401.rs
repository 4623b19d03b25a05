//! The CiA 401 generic I/O application (device profile for generic I/O modules): 8-bit digital
//! inputs and outputs and 16-bit analogue inputs, with the factory test registers of the UWASA
//! Node thesis so that a tester drives the inputs over SDO.
//!
//! [`Cia401Io`] implements [`Application`]. It holds the physical I/O (what the simulator or a
//! test sets with [`Cia401Io::set_digital_inputs`] and [`Cia401Io::set_analog_input`], and what the
//! outputs are driven to, [`Cia401Io::outputs`]) and keeps the process objects of the dictionary in
//! step with it:
//! - digital inputs: 6000h:01 = input XOR polarity 6002h:01. When 6000h:01 changes and the global
//!   interrupt enable 6005h is TRUE, the change triggers TPDO1 if
//!   `(changed & 6006h:01) | (rose & 6007h:01) | (fell & 6008h:01) != 0` (reference §8.4, "how
//!   interrupt masks trigger TPDOs"). The masks are OR-ed, as emtas does; Axiomatic evaluates them
//!   with a priority, and OR is the reading a conformance test of any single mask passes either way.
//!   A trigger returns `trigger_tpdos: [1]` and `changed: [6000h:01]`; a change the masks do not
//!   select updates 6000h:01 silently (synchronous and RTR TPDOs still carry it);
//! - digital outputs: the physical outputs follow 6200h:01 XOR change polarity 6202h:01, for the
//!   bits the filter mask 6208h:01 lets through (other bits keep their state);
//! - analogue inputs: 6401h:*n* = channel *n*. A change is returned in `changed`, so event-driven
//!   TPDOs mapping it (TPDO2 by default) send it; cyclic transmission is the PDO engine's event
//!   timer. If the dictionary has the analogue global interrupt enable 6423h, changes are returned
//!   only while it is TRUE (CiA 401 default FALSE); without it interrupts are enabled (the thesis
//!   device). An enabled change of channel *n* is returned when a condition its interrupt trigger
//!   selection 6421h:*n* (default 07h) selects holds for the new value (reference §8.2/§8.4):
//!   bit 0 value > upper limit 6424h:*n*, bit 1 value < lower limit 6425h:*n*, bit 2
//!   |value − previous value| ≥ delta 6426h:*n*, bit 3 a decrease ≥ negative delta 6427h:*n*, bit 4
//!   an increase ≥ positive delta 6428h:*n* (absent objects: their default 0). With the defaults every
//!   change triggers. The limits are levels: every new value beyond one triggers, not only the
//!   crossing. The delta compares with the previous value, as esd does (the reference leaves open
//!   whether CiA 401 means the last transmitted one); the interrupt source 6422h is not kept, since
//!   its reset rule is unconfirmed;
//! - factory test registers (thesis §5.2): while 2000h (BOOLEAN) is TRUE, the digital inputs come
//!   from 2001h (UNSIGNED8) and analogue channel *n* from 2002h:*n* (INTEGER16) instead of the
//!   physical inputs, so an SDO write to 2001h/2002h acts like a change at the terminals.
//!
//! Objects the dictionary lacks switch their feature off ([`Cia401Io::features`] lists what is
//! supported); absent interrupt objects behave as their CiA 401 defaults (6005h TRUE, 6006h FFh,
//! 6007h and 6008h 00h), absent polarity and filter objects as "no inversion" and "pass all".
//! [`install_objects`] adds the CiA 401 objects, the factory test registers and the default PDOs to
//! a dictionary that lacks them.
//!
//! The inputs change only when the simulator or a write says so, so the application needs no
//! timer ([`Application::poll_timeout`] is always `None`).

use std::fmt;

use canopener_can::Instant;
use canopener_od::{Access, DataType, DynamicOd, Entry, ObjectKey, OdError};
use canopener_wire::{RPDO_BASES, TPDO_BASES};

use crate::application::{AppChanges, Application};
use crate::pdo::{COB_ID_INVALID, RPDO_COMM_BASE, RPDO_MAPPING_BASE, TPDO_COMM_BASE, TPDO_MAPPING_BASE};

/// Device type 1000h.
pub const DEVICE_TYPE: ObjectKey = ObjectKey::new(0x1000, 0);
/// The profile number in bits 15..0 of 1000h: 401 (0191h).
pub const PROFILE_401: u32 = 0x0191;
/// 1000h bits 23..16: digital inputs.
pub const TYPE_DIGITAL_INPUTS: u32 = 0x01 << 16;
/// 1000h bits 23..16: digital outputs.
pub const TYPE_DIGITAL_OUTPUTS: u32 = 0x02 << 16;
/// 1000h bits 23..16: analogue inputs.
pub const TYPE_ANALOG_INPUTS: u32 = 0x04 << 16;
/// 1000h bits 23..16: analogue outputs.
pub const TYPE_ANALOG_OUTPUTS: u32 = 0x08 << 16;

/// Factory test config 2000h (BOOLEAN): TRUE = the inputs come from 2001h and 2002h.
pub const FACTORY_TEST: ObjectKey = ObjectKey::new(0x2000, 0);
/// Intermediate register of the digital inputs 2001h (UNSIGNED8).
pub const FACTORY_DIGITAL: ObjectKey = ObjectKey::new(0x2001, 0);
/// Intermediate register of the analogue inputs 2002h (ARRAY of INTEGER16, sub-index *n* for channel
/// *n*).
pub const FACTORY_ANALOG: u16 = 0x2002;
/// Read input 8-bit 6000h:01.
pub const READ_INPUT: ObjectKey = ObjectKey::new(0x6000, 1);
/// Polarity input 8-bit 6002h:01.
pub const POLARITY_INPUT: ObjectKey = ObjectKey::new(0x6002, 1);
/// Global interrupt enable digital 6005h.
pub const GLOBAL_INTERRUPT_ENABLE: ObjectKey = ObjectKey::new(0x6005, 0);
/// Interrupt mask any change 8-bit 6006h:01.
pub const MASK_ANY_CHANGE: ObjectKey = ObjectKey::new(0x6006, 1);
/// Interrupt mask low-to-high 8-bit 6007h:01.
pub const MASK_LOW_TO_HIGH: ObjectKey = ObjectKey::new(0x6007, 1);
/// Interrupt mask high-to-low 8-bit 6008h:01.
pub const MASK_HIGH_TO_LOW: ObjectKey = ObjectKey::new(0x6008, 1);
/// Write output 8-bit 6200h:01.
pub const WRITE_OUTPUT: ObjectKey = ObjectKey::new(0x6200, 1);
/// Change polarity output 8-bit 6202h:01.
pub const POLARITY_OUTPUT: ObjectKey = ObjectKey::new(0x6202, 1);
/// Filter mask output 8-bit 6208h:01.
pub const FILTER_MASK_OUTPUT: ObjectKey = ObjectKey::new(0x6208, 1);
/// Read analogue input 16-bit 6401h (sub-index *n* for channel *n*).
pub const READ_ANALOG_INPUT: u16 = 0x6401;
/// Write analogue output 16-bit 6411h (only looked at for the device type; not driven).
pub const WRITE_ANALOG_OUTPUT: u16 = 0x6411;
/// Global interrupt enable analogue 6423h.
pub const ANALOG_INTERRUPT_ENABLE: ObjectKey = ObjectKey::new(0x6423, 0);
/// Analogue input interrupt trigger selection 6421h (ARRAY of UNSIGNED8, sub-index *n* for channel *n*).
pub const ANALOG_TRIGGER_SELECTION: u16 = 0x6421;
/// Analogue input interrupt upper limit integer 6424h (ARRAY of INTEGER32).
pub const ANALOG_UPPER_LIMIT: u16 = 0x6424;
/// Analogue input interrupt lower limit integer 6425h (ARRAY of INTEGER32).
pub const ANALOG_LOWER_LIMIT: u16 = 0x6425;
/// Analogue input interrupt delta unsigned 6426h (ARRAY of UNSIGNED32).
pub const ANALOG_DELTA: u16 = 0x6426;
/// Analogue input interrupt negative delta unsigned 6427h.
pub const ANALOG_NEGATIVE_DELTA: u16 = 0x6427;
/// Analogue input interrupt positive delta unsigned 6428h.
pub const ANALOG_POSITIVE_DELTA: u16 = 0x6428;
/// 6421h's CiA 401 default: upper limit, lower limit and delta selected.
pub const DEFAULT_TRIGGER_SELECTION: u8 = 0x07;

/// Whether `od` describes a CiA 401 generic I/O device the application can run: device type
/// 1000h says profile 401 in bits 15..0 (0191h) and the dictionary has digital inputs 6000h or
/// digital outputs 6200h. `canopener sim` runs [`Cia401Io`] on such a device unless told otherwise.
pub fn is_cia401_io(od: &DynamicOd) -> bool {
    let profile_401 = od.get(DEVICE_TYPE).is_some_and(|e| is_profile_401(e.value()));
    profile_401 && (!od.object(READ_INPUT.index).is_empty() || !od.object(WRITE_OUTPUT.index).is_empty())
}

/// The analogue channels [`install_objects`] creates and TPDO2 maps (CiA 401 default: four per TPDO).
pub const INSTALLED_ANALOG_CHANNELS: u8 = 4;

/// A CiA 401 function the application runs when the dictionary has its object.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Feature {
    /// 8 digital inputs in 6000h:01.
    DigitalInputs,
    /// Input polarity 6002h:01.
    InputPolarity,
    /// Global interrupt enable 6005h (without it, interrupts are always enabled).
    GlobalInterruptEnable,
    /// Interrupt mask any change 6006h:01 (without it, every bit triggers: FFh).
    MaskAnyChange,
    /// Interrupt mask low-to-high 6007h:01 (without it, 00h).
    MaskLowToHigh,
    /// Interrupt mask high-to-low 6008h:01 (without it, 00h).
    MaskHighToLow,
    /// 8 digital outputs in 6200h:01.
    DigitalOutputs,
    /// Output polarity 6202h:01.
    OutputPolarity,
    /// Output filter mask 6208h:01.
    OutputFilterMask,
    /// 16-bit analogue inputs 6401h:01.. (the count is [`Cia401Io::analog_channels`]).
    AnalogInputs,
    /// Analogue global interrupt enable 6423h (without it, every analogue change is sent).
    AnalogInterruptEnable,
    /// The factory test config register 2000h.
    FactoryTest,
    /// The factory test digital input register 2001h.
    FactoryDigitalInputs,
    /// The factory test analogue input registers 2002h.
    FactoryAnalogInputs,
}

impl fmt::Display for Feature {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let text = match self {
            Feature::DigitalInputs => "digital inputs (6000h)",
            Feature::InputPolarity => "input polarity (6002h)",
            Feature::GlobalInterruptEnable => "global interrupt enable (6005h)",
            Feature::MaskAnyChange => "interrupt mask any change (6006h)",
            Feature::MaskLowToHigh => "interrupt mask low-to-high (6007h)",
            Feature::MaskHighToLow => "interrupt mask high-to-low (6008h)",
            Feature::DigitalOutputs => "digital outputs (6200h)",
            Feature::OutputPolarity => "output polarity (6202h)",
            Feature::OutputFilterMask => "output filter mask (6208h)",
            Feature::AnalogInputs => "analogue inputs (6401h)",
            Feature::AnalogInterruptEnable => "analogue global interrupt enable (6423h)",
            Feature::FactoryTest => "factory test config (2000h)",
            Feature::FactoryDigitalInputs => "factory test digital inputs (2001h)",
            Feature::FactoryAnalogInputs => "factory test analogue inputs (2002h)",
        };
        f.write_str(text)
    }
}

/// Why the simulator could not set an input.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum InputError {
    /// The dictionary lacks the object of this input kind (6000h:01 or 6401h).
    #[error("the device has no {feature}; add the object to its EDS or use install_objects")]
    NotSupported {
        /// The missing feature.
        feature: Feature,
    },
    /// No analogue input with this channel number (6401h has no such sub-index).
    #[error("analogue input {channel} does not exist: the device has channels 1..={count} in 6401h")]
    NoSuchAnalogInput {
        /// The channel asked for.
        channel: u8,
        /// The number of channels the device has.
        count: u8,
    },
}

/// Why [`install_objects`] could not add the CiA 401 objects.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InstallError {
    /// A node-ID outside 1..=127 (the default PDO COB-IDs are 180h/200h/280h + node-ID).
    #[error("node-ID {node_id} is outside 1..=127; give the device a node-ID in that range")]
    InvalidNodeId {
        /// The node-ID given.
        node_id: u8,
    },
    /// The dictionary could not be rebuilt with room for the new entries.
    #[error("the object dictionary cannot hold the CiA 401 objects: {source}")]
    Od {
        /// The dictionary's refusal.
        #[from]
        source: OdError,
    },
}

/// The CiA 401 generic I/O application: 8 digital inputs, 8 digital outputs, 16-bit analogue
/// inputs and the thesis's factory test registers.
///
/// Which objects exist is looked up in [`Application::reset`], which the `Device` calls before
/// anything else; until then no feature is supported.
#[derive(Debug, Clone, Default)]
pub struct Cia401Io {
    features: Vec<Feature>,
    analog_channels: u8,
    physical_inputs: u8,
    physical_analog: Vec<i16>,
    outputs: u8,
}

impl Cia401Io {
    /// An application with all physical inputs and outputs at 0.
    pub fn new() -> Cia401Io {
        Cia401Io::default()
    }

    /// The features the dictionary has objects for (in [`Feature`] order), as of the last
    /// [`Application::reset`].
    pub fn features(&self) -> &[Feature] {
        &self.features
    }

    /// Whether `feature` is supported.
    pub fn supports(&self, feature: Feature) -> bool {
        self.features.contains(&feature)
    }

    /// The number of analogue input channels (sub-indices 1, 2, … of 6401h present in a row).
    pub fn analog_channels(&self) -> u8 {
        self.analog_channels
    }

    /// The physical digital outputs (bit *n* = output *n* + 1).
    pub fn outputs(&self) -> u8 {
        self.outputs
    }

    /// The physical digital inputs as last set with [`Cia401Io::set_digital_inputs`] (before
    /// polarity; ignored while the factory test is on).
    pub fn physical_inputs(&self) -> u8 {
        self.physical_inputs
    }

    /// The physical analogue inputs, channel 1 first.
    pub fn physical_analog_inputs(&self) -> &[i16] {
        &self.physical_analog
    }

    /// Whether the factory test registers currently feed the inputs (2000h is TRUE).
    pub fn factory_test_active(&self, od: &DynamicOd) -> bool {
        self.supports(Feature::FactoryTest) && read_uint(od, FACTORY_TEST).is_some_and(|v| v != 0)
    }

    /// The physical digital inputs changed to `inputs` (bit *n* = input *n* + 1). Updates 6000h:01
    /// unless the factory test is on and returns what the device must send.
    pub fn set_digital_inputs(
        &mut self,
        _now: Instant,
        inputs: u8,
        od: &mut DynamicOd,
    ) -> Result<AppChanges, InputError> {
        if !self.supports(Feature::DigitalInputs) {
            return Err(InputError::NotSupported {
                feature: Feature::DigitalInputs,
            });
        }
        self.physical_inputs = inputs;
        Ok(self.update_digital(od))
    }

    /// The physical analogue input `channel` (1-based) changed to `value`. Updates 6401h:`channel`
    /// unless the factory test is on and returns what the device must send.
    pub fn set_analog_input(
        &mut self,
        _now: Instant,
        channel: u8,
        value: i16,
        od: &mut DynamicOd,
    ) -> Result<AppChanges, InputError> {
        if !self.supports(Feature::AnalogInputs) {
            return Err(InputError::NotSupported {
                feature: Feature::AnalogInputs,
            });
        }
        let count = self.analog_channels;
        let slot = usize::from(channel)
            .checked_sub(1)
            .and_then(|i| self.physical_analog.get_mut(i))
            .ok_or(InputError::NoSuchAnalogInput { channel, count })?;
        *slot = value;
        let mut changes = AppChanges::none();
        self.update_analog(channel, od, &mut changes);
        Ok(changes)
    }

    /// Device type 1000h for the I/O the dictionary has: 0191h with bits 16..19 for digital
    /// inputs (6000h), digital outputs (6200h), analogue inputs (6401h) and analogue outputs
    /// (6411h).
    pub fn device_type(od: &DynamicOd) -> u32 {
        let mut value = PROFILE_401;
        for (index, bit) in [
            (READ_INPUT.index, TYPE_DIGITAL_INPUTS),
            (WRITE_OUTPUT.index, TYPE_DIGITAL_OUTPUTS),
            (READ_ANALOG_INPUT, TYPE_ANALOG_INPUTS),
            (WRITE_ANALOG_OUTPUT, TYPE_ANALOG_OUTPUTS),
        ] {
            if !od.object(index).is_empty() {
                value |= bit;
            }
        }
        value
    }

    fn detect(&mut self, od: &DynamicOd) {
        let has = |key: ObjectKey, len: usize| od.get(key).is_some_and(|e| e.value().len() == len);
        // The factory test registers are the thesis's, not CiA 401's: a vendor's own 2000h–2002h
        // (a RECORD, a counter) must not switch the inputs over, so their types must match too.
        let typed =
            |key: ObjectKey, data_type: DataType| od.get(key).is_some_and(|e| e.data_type() == data_type);
        let mut features = Vec::new();
        for (feature, key, len) in [
            (Feature::DigitalInputs, READ_INPUT, 1),
            (Feature::InputPolarity, POLARITY_INPUT, 1),
            (Feature::GlobalInterruptEnable, GLOBAL_INTERRUPT_ENABLE, 1),
            (Feature::MaskAnyChange, MASK_ANY_CHANGE, 1),
            (Feature::MaskLowToHigh, MASK_LOW_TO_HIGH, 1),
            (Feature::MaskHighToLow, MASK_HIGH_TO_LOW, 1),
            (Feature::DigitalOutputs, WRITE_OUTPUT, 1),
            (Feature::OutputPolarity, POLARITY_OUTPUT, 1),
            (Feature::OutputFilterMask, FILTER_MASK_OUTPUT, 1),
            (Feature::AnalogInputs, ObjectKey::new(READ_ANALOG_INPUT, 1), 2),
            (Feature::AnalogInterruptEnable, ANALOG_INTERRUPT_ENABLE, 1),
            (Feature::FactoryTest, FACTORY_TEST, 1),
            (Feature::FactoryDigitalInputs, FACTORY_DIGITAL, 1),
            (Feature::FactoryAnalogInputs, ObjectKey::new(FACTORY_ANALOG, 1), 2),
        ] {
            let factory_type = match feature {
                Feature::FactoryTest => Some(DataType::BOOLEAN),
                Feature::FactoryDigitalInputs => Some(DataType::UNSIGNED8),
                Feature::FactoryAnalogInputs => Some(DataType::INTEGER16),
                _ => None,
            };
            if has(key, len) && factory_type.is_none_or(|data_type| typed(key, data_type)) {
                features.push(feature);
            }
        }
        self.analog_channels = (1..=u8::MAX)
            .take_while(|&sub| has(ObjectKey::new(READ_ANALOG_INPUT, sub), 2))
            .last()
            .unwrap_or(0);
        self.physical_analog.resize(usize::from(self.analog_channels), 0);
        self.features = features;
    }

    /// Brings 6000h:01 up to date and decides whether the change triggers TPDO1.
    fn update_digital(&mut self, od: &mut DynamicOd) -> AppChanges {
        if !self.supports(Feature::DigitalInputs) {
            return AppChanges::none();
        }
        let source = if self.factory_test_active(od) && self.supports(Feature::FactoryDigitalInputs) {
            read_u8(od, FACTORY_DIGITAL).unwrap_or(0)
        } else {
            self.physical_inputs
        };
        let polarity = self.optional_u8(od, Feature::InputPolarity, POLARITY_INPUT, 0x00);
        let value = source ^ polarity;
        let old = read_u8(od, READ_INPUT).unwrap_or(0);
        if value == old || od.set_value(READ_INPUT, &[value]).is_err() {
            return AppChanges::none();
        }
        // Absent interrupt objects behave as their CiA 401 defaults.
        let enabled = self.optional_u8(od, Feature::GlobalInterruptEnable, GLOBAL_INTERRUPT_ENABLE, 1) != 0;
        let any = self.optional_u8(od, Feature::MaskAnyChange, MASK_ANY_CHANGE, 0xFF);
        let low_to_high = self.optional_u8(od, Feature::MaskLowToHigh, MASK_LOW_TO_HIGH, 0x00);
        let high_to_low = self.optional_u8(od, Feature::MaskHighToLow, MASK_HIGH_TO_LOW, 0x00);
        let changed = old ^ value;
        let rose = changed & value;
        let fell = changed & old;
        if enabled && (changed & any) | (rose & low_to_high) | (fell & high_to_low) != 0 {
            AppChanges {
                changed: vec![READ_INPUT],
                trigger_tpdos: vec![1],
            }
        } else {
            AppChanges::none()
        }
    }

    /// Brings 6401h:`channel` up to date; a change is added to `changes` if analogue events are
    /// enabled.
    fn update_analog(&mut self, channel: u8, od: &mut DynamicOd, changes: &mut AppChanges) {
        let Some(physical) = usize::from(channel)
            .checked_sub(1)
            .and_then(|i| self.physical_analog.get(i))
        else {
            return;
        };
        let factory = ObjectKey::new(FACTORY_ANALOG, channel);
        let value = match read_i16(od, factory) {
            Some(value) if self.factory_test_active(od) && self.supports(Feature::FactoryAnalogInputs) => {
                value
            }
            _ => *physical,
        };
        let key = ObjectKey::new(READ_ANALOG_INPUT, channel);
        let previous = read_i16(od, key);
        if previous == Some(value) || od.set_value(key, &value.to_le_bytes()).is_err() {
            return;
        }
        let enabled = self.optional_u8(od, Feature::AnalogInterruptEnable, ANALOG_INTERRUPT_ENABLE, 1) != 0;
        if enabled && analog_trigger(od, channel, previous.unwrap_or(0), value) {
            changes.changed.push(key);
        }
    }

    fn update_all_analog(&mut self, od: &mut DynamicOd) -> AppChanges {
        let mut changes = AppChanges::none();
        for channel in 1..=self.analog_channels {
            self.update_analog(channel, od, &mut changes);
        }
        changes
    }

    /// Drives the physical outputs from 6200h:01, 6202h:01 and 6208h:01.
    fn update_outputs(&mut self, od: &DynamicOd) {
        if !self.supports(Feature::DigitalOutputs) {
            return;
        }
        let written = read_u8(od, WRITE_OUTPUT).unwrap_or(0);
        let polarity = self.optional_u8(od, Feature::OutputPolarity, POLARITY_OUTPUT, 0x00);
        let filter = self.optional_u8(od, Feature::OutputFilterMask, FILTER_MASK_OUTPUT, 0xFF);
        self.outputs = (self.outputs & !filter) | ((written ^ polarity) & filter);
    }

    fn optional_u8(&self, od: &DynamicOd, feature: Feature, key: ObjectKey, default: u8) -> u8 {
        if self.supports(feature) {
            read_u8(od, key).unwrap_or(default)
        } else {
            default
        }
    }
}

/// Whether the change of analogue channel `channel` from `previous` to `value` meets a condition
/// 6421h:`channel` selects (see the [module docs](self)).
fn analog_trigger(od: &DynamicOd, channel: u8, previous: i16, value: i16) -> bool {
    let at = |index: u16| ObjectKey::new(index, channel);
    let selection = read_u8(od, at(ANALOG_TRIGGER_SELECTION)).unwrap_or(DEFAULT_TRIGGER_SELECTION);
    let signed = |index: u16| read_int(od, at(index)).unwrap_or(0);
    let unsigned = |index: u16| {
        read_uint(od, at(index))
            .and_then(|v| i64::try_from(v).ok())
            .unwrap_or(0)
    };
    let value = i64::from(value);
    let step = value - i64::from(previous);
    let conditions = [
        value > signed(ANALOG_UPPER_LIMIT),
        value < signed(ANALOG_LOWER_LIMIT),
        step.abs() >= unsigned(ANALOG_DELTA),
        step < 0 && -step >= unsigned(ANALOG_NEGATIVE_DELTA),
        step > 0 && step >= unsigned(ANALOG_POSITIVE_DELTA),
    ];
    conditions
        .iter()
        .enumerate()
        .any(|(bit, &holds)| holds && selection & (1 << bit) != 0)
}

fn merge(mut into: AppChanges, from: AppChanges) -> AppChanges {
    into.changed.extend(from.changed);
    into.trigger_tpdos.extend(from.trigger_tpdos);
    into
}

impl Application for Cia401Io {
    /// Looks up which objects exist, then brings the inputs and the outputs up to date with the
    /// dictionary silently: PDOs are not running at a reset, and entering Operational sends the
    /// event-driven TPDOs anyway.
    fn reset(&mut self, _now: Instant, od: &mut DynamicOd) -> AppChanges {
        self.detect(od);
        self.update_digital(od);
        self.update_all_analog(od);
        self.outputs = 0;
        self.update_outputs(od);
        AppChanges::none()
    }

    fn on_write(&mut self, _now: Instant, key: ObjectKey, od: &mut DynamicOd) -> AppChanges {
        match key.index {
            // A polarity change changes 6000h:01 like an input change does and is evaluated the same
            // way (the sampled value after polarity is what the masks compare).
            0x2001 | 0x6002 => self.update_digital(od),
            0x2000 => merge(self.update_digital(od), self.update_all_analog(od)),
            FACTORY_ANALOG => {
                let mut changes = AppChanges::none();
                self.update_analog(key.sub, od, &mut changes);
                changes
            }
            0x6200 | 0x6202 | 0x6208 => {
                self.update_outputs(od);
                AppChanges::none()
            }
            _ => AppChanges::none(),
        }
    }

    fn handle_timeout(&mut self, _now: Instant, _od: &mut DynamicOd) -> AppChanges {
        AppChanges::none()
    }

    fn poll_timeout(&self) -> Option<Instant> {
        None
    }
}

fn read_uint(od: &DynamicOd, key: ObjectKey) -> Option<u64> {
    let value = od.get(key)?.value();
    if value.is_empty() {
        return None;
    }
    let mut buf = [0u8; 8];
    buf.get_mut(..value.len())?.copy_from_slice(value);
    Some(u64::from_le_bytes(buf))
}

/// A signed value of 1, 2 or 4 bytes, sign-extended.
fn read_int(od: &DynamicOd, key: ObjectKey) -> Option<i64> {
    match *od.get(key)?.value() {
        [a] => Some(i64::from(a as i8)),
        [a, b] => Some(i64::from(i16::from_le_bytes([a, b]))),
        [a, b, c, d] => Some(i64::from(i32::from_le_bytes([a, b, c, d]))),
        _ => None,
    }
}

fn read_u8(od: &DynamicOd, key: ObjectKey) -> Option<u8> {
    od.get(key)?.value().first().copied()
}

fn read_i16(od: &DynamicOd, key: ObjectKey) -> Option<i16> {
    match od.get(key)?.value() {
        [lo, hi] => Some(i16::from_le_bytes([*lo, *hi])),
        _ => None,
    }
}

/// Adds what a CiA 401 generic I/O device needs to `od`, for a device with node-ID `node_id`, and
/// returns the indices of the objects added (in ascending order).
///
/// Objects the dictionary already has are kept as they are (not a single sub-index is added to
/// them); missing ones are added with their CiA 401 defaults (reference §8.2):
/// - 2000h factory test config (BOOLEAN rw, FALSE), 2001h (UNSIGNED8 rw, 0), 2002h:01..04
///   (INTEGER16 rw, 0);
/// - 6000h:01 (UNSIGNED8 ro, mappable), 6002h:01 (00h), 6005h (BOOLEAN, TRUE), 6006h:01 (FFh),
///   6007h:01 (00h), 6008h:01 (00h), 6200h:01 (UNSIGNED8 rww, mappable, 00h), 6401h:01..04
///   (INTEGER16 ro, mappable);
/// - the default PDOs (reference §8.3), transmission type 255: RPDO1 (1400h/1600h, 200h + node-ID)
///   ← 6200h:01, TPDO1 (1800h/1A00h, 180h + node-ID) → 6000h:01, TPDO2 (1801h/1A01h, 280h +
///   node-ID) → 6401h:01..04 (as many as exist, at most four). A PDO with nothing to map is left
///   invalid (COB-ID bit 31 set).
///
/// 1000h is then set (or added) to [`Cia401Io::device_type`] of the result: 00070191h for the
/// objects added here, 000F0191h if the dictionary also has analogue outputs (6411h); a 1000h that
/// already says profile 401 (bits 15..0 = 0191h) is the description's own and is kept. A
/// dictionary too small for the new entries is rebuilt with a larger capacity.
pub fn install_objects(od: &mut DynamicOd, node_id: u8) -> Result<Vec<u16>, InstallError> {
    if !(1..=127).contains(&node_id) {
        return Err(InstallError::InvalidNodeId { node_id });
    }
    use Access::{Const, Ro, Rw, Rww};
    use DataType as T;
    let mut objects: Vec<(u16, Vec<Entry>)> = Vec::new();
    let add = |objects: &mut Vec<(u16, Vec<Entry>)>, index: u16, entries: Vec<Option<Entry>>| {
        if od.object(index).is_empty() {
            objects.push((index, entries.into_iter().flatten().collect()));
        }
    };
    let array = |index: u16, data_type: DataType, access: Access, map: bool, values: &[&[u8]]| {
        let count = u8::try_from(values.len()).unwrap_or(u8::MAX);
        let mut entries = vec![entry(index, 0, T::UNSIGNED8, Const, &[count], false)];
        for (sub, value) in (1..=count).zip(values) {
            entries.push(entry(index, sub, data_type, access, value, map));
        }
        entries
    };
    let zero16: &[u8] = &[0, 0];
    let analog_zeros = vec![zero16; usize::from(INSTALLED_ANALOG_CHANNELS)];
    add(
        &mut objects,
        0x2000,
        vec![entry(0x2000, 0, T::BOOLEAN, Rw, &[0], false)],
    );
    add(
        &mut objects,
        0x2001,
        vec![entry(0x2001, 0, T::UNSIGNED8, Rw, &[0], false)],
    );
    add(
        &mut objects,
        FACTORY_ANALOG,
        array(FACTORY_ANALOG, T::INTEGER16, Rw, false, &analog_zeros),
    );
    add(
        &mut objects,
        0x6000,
        array(0x6000, T::UNSIGNED8, Ro, true, &[&[0]]),
    );
    add(
        &mut objects,
        0x6002,
        array(0x6002, T::UNSIGNED8, Rw, false, &[&[0]]),
    );
    add(
        &mut objects,
        0x6005,
        vec![entry(0x6005, 0, T::BOOLEAN, Rw, &[1], false)],
    );
    add(
        &mut objects,
        0x6006,
        array(0x6006, T::UNSIGNED8, Rw, false, &[&[0xFF]]),
    );
    add(
        &mut objects,
        0x6007,
        array(0x6007, T::UNSIGNED8, Rw, false, &[&[0]]),
    );
    add(
        &mut objects,
        0x6008,
        array(0x6008, T::UNSIGNED8, Rw, false, &[&[0]]),
    );
    add(
        &mut objects,
        0x6200,
        array(0x6200, T::UNSIGNED8, Rww, true, &[&[0]]),
    );
    add(
        &mut objects,
        READ_ANALOG_INPUT,
        array(READ_ANALOG_INPUT, T::INTEGER16, Ro, true, &analog_zeros),
    );

    // The default mappings refer to the process objects as they will be after the additions above.
    let exists =
        |key: ObjectKey| od.contains(key) || objects.iter().flat_map(|(_, e)| e).any(|e| e.key() == key);
    let digital_in: Vec<u32> = [READ_INPUT]
        .into_iter()
        .filter(|&k| exists(k))
        .map(|k| mapping(k, 8))
        .collect();
    let digital_out: Vec<u32> = [WRITE_OUTPUT]
        .into_iter()
        .filter(|&k| exists(k))
        .map(|k| mapping(k, 8))
        .collect();
    let analog_in: Vec<u32> = (1..=INSTALLED_ANALOG_CHANNELS)
        .map(|sub| ObjectKey::new(READ_ANALOG_INPUT, sub))
        .take_while(|&k| exists(k))
        .map(|k| mapping(k, 16))
        .collect();
    let node = u32::from(node_id);
    let pdos = [
        (
            RPDO_COMM_BASE,
            RPDO_MAPPING_BASE,
            u32::from(RPDO_BASES[0]) + node,
            false,
            digital_out,
        ),
        (
            TPDO_COMM_BASE,
            TPDO_MAPPING_BASE,
            u32::from(TPDO_BASES[0]) + node,
            true,
            digital_in,
        ),
        (
            TPDO_COMM_BASE + 1,
            TPDO_MAPPING_BASE + 1,
            u32::from(TPDO_BASES[1]) + node,
            true,
            analog_in,
        ),
    ];
    for (comm, map, can_id, transmit, mapped) in pdos {
        let cob_id = if mapped.is_empty() {
            can_id | COB_ID_INVALID
        } else {
            can_id
        };
        let mut entries = vec![
            entry(
                comm,
                0,
                T::UNSIGNED8,
                Const,
                &[if transmit { 6 } else { 5 }],
                false,
            ),
            entry(comm, 1, T::UNSIGNED32, Rw, &cob_id.to_le_bytes(), false),
            entry(comm, 2, T::UNSIGNED8, Rw, &[255], false),
            entry(comm, 3, T::UNSIGNED16, Rw, &[0, 0], false),
            entry(comm, 5, T::UNSIGNED16, Rw, &[0, 0], false),
        ];
        if transmit {
            entries.push(entry(comm, 6, T::UNSIGNED8, Rw, &[0], false));
        }
        add(&mut objects, comm, entries);
        let count = u8::try_from(mapped.len()).unwrap_or(0);
        let mut entries = vec![entry(map, 0, T::UNSIGNED8, Rw, &[count], false)];
        for sub in 1..=8u8 {
            let value = mapped.get(usize::from(sub - 1)).copied().unwrap_or(0);
            entries.push(entry(map, sub, T::UNSIGNED32, Rw, &value.to_le_bytes(), false));
        }
        add(&mut objects, map, entries);
    }

    let added: Vec<u16> = objects.iter().map(|(index, _)| *index).collect();
    let new_entries: Vec<Entry> = objects.into_iter().flat_map(|(_, e)| e).collect();
    let device_type_missing = !od.contains(DEVICE_TYPE);
    let needed = od.len() + new_entries.len() + usize::from(device_type_missing);
    if needed > od.capacity() {
        let rebuilt = DynamicOd::from_entries(needed, od.iter().cloned().chain(new_entries))?;
        *od = rebuilt;
    } else {
        for new in new_entries {
            od.insert(new)?;
        }
    }
    let device_type = Cia401Io::device_type(od);
    match od.get(DEVICE_TYPE) {
        Some(existing) if existing.data_type() == T::UNSIGNED32 && is_profile_401(existing.value()) => {}
        Some(existing) if existing.value().len() == 4 => {
            od.set_value(DEVICE_TYPE, &device_type.to_le_bytes())?
        }
        _ => {
            // Absent, or of a type 1000h cannot have: replaced by a proper UNSIGNED32.
            if let Some(e) = entry(
                DEVICE_TYPE.index,
                0,
                T::UNSIGNED32,
                Ro,
                &device_type.to_le_bytes(),
                false,
            ) {
                od.insert(e)?;
            }
        }
    }
    Ok(added)
}

/// Whether a 1000h value says profile 401 in bits 15..0.
fn is_profile_401(value: &[u8]) -> bool {
    matches!(value, [lo, hi, _, _] if u32::from(u16::from_le_bytes([*lo, *hi])) == PROFILE_401)
}

/// A mapping entry for `key` with `bits` bits (`index << 16 | sub << 8 | bits`).
fn mapping(key: ObjectKey, bits: u8) -> u32 {
    key.packed() << 8 | u32::from(bits)
}

/// An entry; `None` only if `value` does not suit `data_type`, which the fixed tables of
/// [`install_objects`] never do.
fn entry(index: u16, sub: u8, data_type: DataType, access: Access, value: &[u8], map: bool) -> Option<Entry> {
    Entry::new(ObjectKey::new(index, sub), data_type, access, value)
        .ok()
        .map(|e| e.with_pdo_mapping(map))
}

#[cfg(test)]
mod tests {
    use canopener_can::CanFrame;
    use proptest::prelude::*;

    use super::*;
    use crate::nmt_slave::NmtSlaveState;
    use crate::pdo::{PdoEngine, PdoEvent};
    use canopener_can::Core;
    use canopener_testkit::frames::any_frame;
    use canopener_testkit::trace::{Trace, ms};

    const T0: Instant = Instant::ZERO;
    const AI1: ObjectKey = ObjectKey::new(READ_ANALOG_INPUT, 1);
    const AI2: ObjectKey = ObjectKey::new(READ_ANALOG_INPUT, 2);
    const FA1: ObjectKey = ObjectKey::new(FACTORY_ANALOG, 1);

    fn base_od() -> DynamicOd {
        let mut od = DynamicOd::with_capacity(4);
        od.insert(Entry::new(DEVICE_TYPE, DataType::UNSIGNED32, Access::Ro, &[0; 4]).unwrap())
            .unwrap();
        od
    }

    /// A node-5 CiA 401 device with everything [`install_objects`] adds, reset.
    fn device() -> (Cia401Io, DynamicOd) {
        let mut od = base_od();
        install_objects(&mut od, 5).unwrap();
        let mut io = Cia401Io::new();
        assert!(io.reset(T0, &mut od).is_empty());
        (io, od)
    }

    #[test]
    fn a_cia401_io_device_is_profile_401_with_digital_io() {
        let with = |device_type: u32, index: Option<u16>| {
            let mut od = DynamicOd::with_capacity(4);
            od.insert(
                Entry::new(
                    DEVICE_TYPE,
                    DataType::UNSIGNED32,
                    Access::Ro,
                    &device_type.to_le_bytes(),
                )
                .unwrap(),
            )
            .unwrap();
            if let Some(index) = index {
                od.insert(
                    Entry::new(ObjectKey::new(index, 1), DataType::UNSIGNED8, Access::Rw, &[0]).unwrap(),
                )
                .unwrap();
            }
            is_cia401_io(&od)
        };
        assert!(with(0x000F_0191, Some(0x6000)));
        assert!(
            with(0x0000_0191, Some(0x6200)),
            "the I/O bits 23..16 do not decide"
        );
        assert!(!with(0x000F_0191, None), "no digital I/O object");
        assert!(!with(0x0002_0192, Some(0x6200)), "CiA 402 is not CiA 401");
        assert!(!with(0x0191_0000, Some(0x6000)), "401 in the wrong bits");
    }

    /// A vendor's own 2000h–2002h (Elcom's e-RIO has a RECORD "Layer Settings" at 2000h) are not the
    /// factory test registers: the inputs keep coming from the terminals.
    #[test]
    fn factory_registers_of_another_type_are_not_taken_for_the_test_registers() {
        let mut od = base_od();
        let record = [
            Entry::new(FACTORY_TEST, DataType::UNSIGNED8, Access::Const, &[2]).unwrap(),
            Entry::new(FACTORY_DIGITAL, DataType::UNSIGNED32, Access::Rw, &[0; 4]).unwrap(),
        ];
        for entry in record {
            od.insert(entry).unwrap();
        }
        install_objects(&mut od, 5).unwrap();
        let mut io = Cia401Io::new();
        io.reset(T0, &mut od);
        assert!(!io.supports(Feature::FactoryTest));
        assert!(!io.supports(Feature::FactoryDigitalInputs));
        assert!(!io.factory_test_active(&od));
        io.set_digital_inputs(T0, 0x21, &mut od).unwrap();
        assert_eq!(od.read(READ_INPUT).unwrap(), [0x21]);
    }

    /// An SDO download of `data` to `key`, then the application's reaction.
    fn sdo(io: &mut Cia401Io, od: &mut DynamicOd, key: ObjectKey, data: &[u8]) -> AppChanges {
        od.write(key, data).unwrap();
        io.on_write(T0, key, od)
    }

    /// Room for a few more entries.
    fn grow(od: &mut DynamicOd) {
        *od = DynamicOd::from_entries(od.len() + 8, od.iter().cloned()).unwrap();
    }

    fn input(od: &DynamicOd) -> u8 {
        od.get(READ_INPUT).unwrap().value()[0]
    }

    fn triggered() -> AppChanges {
        AppChanges {
            changed: vec![READ_INPUT],
            trigger_tpdos: vec![1],
        }
    }

    /// Sets the masks (any change, low-to-high, high-to-low) and the global enable.
    fn masks(io: &mut Cia401Io, od: &mut DynamicOd, any: u8, rise: u8, fall: u8, enable: bool) {
        sdo(io, od, MASK_ANY_CHANGE, &[any]);
        sdo(io, od, MASK_LOW_TO_HIGH, &[rise]);
        sdo(io, od, MASK_HIGH_TO_LOW, &[fall]);
        sdo(io, od, GLOBAL_INTERRUPT_ENABLE, &[u8::from(enable)]);
    }

    fn set(io: &mut Cia401Io, od: &mut DynamicOd, inputs: u8) -> AppChanges {
        io.set_digital_inputs(T0, inputs, od).unwrap()
    }

    #[test]
    fn any_change_mask_by_default_triggers_tpdo1_on_every_edge() {
        let (mut io, mut od) = device();
        assert_eq!(set(&mut io, &mut od, 0x01), triggered());
        assert_eq!(input(&od), 0x01);
        assert_eq!(set(&mut io, &mut od, 0x00), triggered());
        assert_eq!(
            set(&mut io, &mut od, 0x00),
            AppChanges::none(),
            "no change, no trigger"
        );
    }

    #[test]
    fn any_change_mask_selects_bits() {
        let (mut io, mut od) = device();
        masks(&mut io, &mut od, 0x0F, 0, 0, true);
        assert_eq!(set(&mut io, &mut od, 0x10), AppChanges::none());
        assert_eq!(input(&od), 0x10, "6000h follows the input even without a trigger");
        assert_eq!(set(&mut io, &mut od, 0x00), AppChanges::none());
        assert_eq!(set(&mut io, &mut od, 0x08), triggered());
        assert_eq!(set(&mut io, &mut od, 0x00), triggered());
    }

    #[test]
    fn low_to_high_mask_triggers_on_rising_edges_only() {
        let (mut io, mut od) = device();
        masks(&mut io, &mut od, 0, 0x02, 0, true);
        assert_eq!(set(&mut io, &mut od, 0x02), triggered());
        assert_eq!(set(&mut io, &mut od, 0x00), AppChanges::none(), "falling edge");
        assert_eq!(
            set(&mut io, &mut od, 0x01),
            AppChanges::none(),
            "rising edge of an unmasked bit"
        );
    }

    #[test]
    fn high_to_low_mask_triggers_on_falling_edges_only() {
        let (mut io, mut od) = device();
        masks(&mut io, &mut od, 0, 0, 0x80, true);
        assert_eq!(set(&mut io, &mut od, 0x80), AppChanges::none(), "rising edge");
        assert_eq!(set(&mut io, &mut od, 0x00), triggered());
        assert_eq!(set(&mut io, &mut od, 0x40), AppChanges::none());
        assert_eq!(
            set(&mut io, &mut od, 0x00),
            AppChanges::none(),
            "falling edge of an unmasked bit"
        );
    }

    #[test]
    fn masks_are_ored() {
        let (mut io, mut od) = device();
        masks(&mut io, &mut od, 0x01, 0x02, 0x04, true);
        set(&mut io, &mut od, 0x04);
        // Bit 0 any change, bit 1 rising, bit 2 falling: each alone triggers.
        assert_eq!(set(&mut io, &mut od, 0x05), triggered());
        assert_eq!(set(&mut io, &mut od, 0x07), triggered());
        assert_eq!(set(&mut io, &mut od, 0x03), triggered());
        // Bit 1 falling and bit 2 rising: neither is selected.
        assert_eq!(set(&mut io, &mut od, 0x05), AppChanges::none());
    }

    #[test]
    fn global_interrupt_disable_suppresses_every_mask() {
        let (mut io, mut od) = device();
        masks(&mut io, &mut od, 0xFF, 0xFF, 0xFF, false);
        assert_eq!(set(&mut io, &mut od, 0xFF), AppChanges::none());
        assert_eq!(input(&od), 0xFF);
        assert_eq!(set(&mut io, &mut od, 0x00), AppChanges::none());
        sdo(&mut io, &mut od, GLOBAL_INTERRUPT_ENABLE, &[1]);
        assert_eq!(set(&mut io, &mut od, 0x01), triggered());
    }

    #[test]
    fn polarity_inverts_inputs_and_a_polarity_change_is_an_input_change() {
        let (mut io, mut od) = device();
        set(&mut io, &mut od, 0x0F);
        assert_eq!(sdo(&mut io, &mut od, POLARITY_INPUT, &[0xFF]), triggered());
        assert_eq!(input(&od), 0xF0);
        assert_eq!(set(&mut io, &mut od, 0x0E), triggered());
        assert_eq!(input(&od), 0xF1);
        // Rising edge seen after polarity: physical 1 → 0 on bit 0 with bit 0 inverted.
        masks(&mut io, &mut od, 0, 0x02, 0, true);
        assert_eq!(
            set(&mut io, &mut od, 0x0C),
            triggered(),
            "bit 1 falls at the pin, rises in 6000h"
        );
        assert_eq!(set(&mut io, &mut od, 0x0E), AppChanges::none());
    }

    /// The thesis's digital input test (§5.2), steps 1 to 14, through the factory test registers.
    #[test]
    fn factory_test_digital_inputs_follow_2001h() {
        let (mut io, mut od) = device();
        set(&mut io, &mut od, 0xAA);
        masks(&mut io, &mut od, 0, 0, 0, false);
        sdo(&mut io, &mut od, GLOBAL_INTERRUPT_ENABLE, &[1]);
        assert!(!io.factory_test_active(&od));
        // Enabling the factory test replaces the physical inputs by 2001h (= 00h): 6000h follows.
        assert_eq!(sdo(&mut io, &mut od, FACTORY_TEST, &[1]), AppChanges::none());
        assert!(io.factory_test_active(&od));
        assert_eq!(input(&od), 0x00);
        sdo(&mut io, &mut od, MASK_LOW_TO_HIGH, &[0x02]);
        assert_eq!(
            sdo(&mut io, &mut od, FACTORY_DIGITAL, &[0x00]),
            AppChanges::none()
        );
        assert_eq!(sdo(&mut io, &mut od, FACTORY_DIGITAL, &[0x02]), triggered());
        assert_eq!(
            sdo(&mut io, &mut od, FACTORY_DIGITAL, &[0x40]),
            AppChanges::none()
        );
        sdo(&mut io, &mut od, MASK_LOW_TO_HIGH, &[0x42]);
        sdo(&mut io, &mut od, FACTORY_DIGITAL, &[0x00]);
        assert_eq!(sdo(&mut io, &mut od, FACTORY_DIGITAL, &[0x40]), triggered());
        assert_eq!(
            sdo(&mut io, &mut od, FACTORY_DIGITAL, &[0x02]),
            triggered(),
            "bit 1 rises"
        );
        // The physical inputs are recorded but do not reach 6000h while the test is on.
        assert_eq!(set(&mut io, &mut od, 0xFF), AppChanges::none());
        assert_eq!(input(&od), 0x02);
        assert_eq!(io.physical_inputs(), 0xFF);
        // Switching the test off brings the physical inputs back (bits 0..7 rise: bit 6 is masked).
        assert_eq!(sdo(&mut io, &mut od, FACTORY_TEST, &[0]), triggered());
        assert_eq!(input(&od), 0xFF);
        assert_eq!(
            sdo(&mut io, &mut od, FACTORY_DIGITAL, &[0x00]),
            AppChanges::none()
        );
        assert_eq!(input(&od), 0xFF);
    }

    #[test]
    fn factory_test_analog_inputs_follow_2002h() {
        let (mut io, mut od) = device();
        io.set_analog_input(T0, 1, 100, &mut od).unwrap();
        assert_eq!(
            sdo(&mut io, &mut od, FA1, &(-5i16).to_le_bytes()),
            AppChanges::none(),
            "test off"
        );
        let on = sdo(&mut io, &mut od, FACTORY_TEST, &[1]);
        assert_eq!(on.changed, [AI1]);
        assert_eq!(read_i16(&od, AI1), Some(-5));
        let changed = sdo(&mut io, &mut od, FA1, &0x1234i16.to_le_bytes());
        assert_eq!(changed.changed, [AI1]);
        assert!(changed.trigger_tpdos.is_empty());
        assert_eq!(read_i16(&od, AI1), Some(0x1234));
        assert_eq!(
            io.set_analog_input(T0, 1, 7, &mut od).unwrap(),
            AppChanges::none()
        );
        assert_eq!(sdo(&mut io, &mut od, FACTORY_TEST, &[0]).changed, [AI1]);
        assert_eq!(read_i16(&od, AI1), Some(7));
    }

    #[test]
    fn analog_changes_are_reported_per_channel() {
        let (mut io, mut od) = device();
        assert_eq!(io.analog_channels(), 4);
        let changes = io.set_analog_input(T0, 2, -300, &mut od).unwrap();
        assert_eq!(changes.changed, [AI2]);
        assert!(changes.trigger_tpdos.is_empty());
        assert_eq!(read_i16(&od, AI2), Some(-300));
        assert_eq!(
            io.set_analog_input(T0, 2, -300, &mut od).unwrap(),
            AppChanges::none()
        );
        assert_eq!(io.physical_analog_inputs(), [0, -300, 0, 0]);
    }

    #[test]
    fn analog_global_interrupt_enable_gates_analog_events_when_present() {
        let (mut io, mut od) = device();
        grow(&mut od);
        od.insert(Entry::new(ANALOG_INTERRUPT_ENABLE, DataType::BOOLEAN, Access::Rw, &[0]).unwrap())
            .unwrap();
        io.reset(T0, &mut od);
        assert!(io.supports(Feature::AnalogInterruptEnable));
        assert_eq!(
            io.set_analog_input(T0, 1, 1, &mut od).unwrap(),
            AppChanges::none()
        );
        assert_eq!(read_i16(&od, AI1), Some(1), "the value is still updated");
        sdo(&mut io, &mut od, ANALOG_INTERRUPT_ENABLE, &[1]);
        assert_eq!(io.set_analog_input(T0, 1, 2, &mut od).unwrap().changed, [AI1]);
    }

    /// A device with 6423h TRUE and channel 1's 6421h, 6424h, 6425h, 6426h (as a CiA 401 EDS lists
    /// them, with their defaults).
    fn analog_interrupt_device() -> (Cia401Io, DynamicOd) {
        let (mut io, mut od) = device();
        grow(&mut od);
        for (key, data_type, value) in [
            (ANALOG_INTERRUPT_ENABLE, DataType::BOOLEAN, vec![1]),
            (
                ObjectKey::new(ANALOG_TRIGGER_SELECTION, 1),
                DataType::UNSIGNED8,
                vec![0x07],
            ),
            (
                ObjectKey::new(ANALOG_UPPER_LIMIT, 1),
                DataType::INTEGER32,
                vec![0; 4],
            ),
            (
                ObjectKey::new(ANALOG_LOWER_LIMIT, 1),
                DataType::INTEGER32,
                vec![0; 4],
            ),
            (ObjectKey::new(ANALOG_DELTA, 1), DataType::UNSIGNED32, vec![0; 4]),
        ] {
            od.insert(Entry::new(key, data_type, Access::Rw, &value).unwrap())
                .unwrap();
        }
        io.reset(T0, &mut od);
        (io, od)
    }

    fn analog_settings(od: &mut DynamicOd, selection: u8, upper: i32, lower: i32, delta: u32) {
        od.set_value(ObjectKey::new(ANALOG_TRIGGER_SELECTION, 1), &[selection])
            .unwrap();
        od.set_value(ObjectKey::new(ANALOG_UPPER_LIMIT, 1), &upper.to_le_bytes())
            .unwrap();
        od.set_value(ObjectKey::new(ANALOG_LOWER_LIMIT, 1), &lower.to_le_bytes())
            .unwrap();
        od.set_value(ObjectKey::new(ANALOG_DELTA, 1), &delta.to_le_bytes())
            .unwrap();
    }

    /// Applies each value to channel 1 and returns which ones triggered.
    fn analog_steps(io: &mut Cia401Io, od: &mut DynamicOd, values: &[i16]) -> Vec<bool> {
        values
            .iter()
            .map(|&v| !io.set_analog_input(T0, 1, v, od).unwrap().changed.is_empty())
            .collect()
    }

    #[test]
    fn analog_defaults_trigger_on_every_change() {
        let (mut io, mut od) = analog_interrupt_device();
        assert_eq!(
            analog_steps(&mut io, &mut od, &[5, -5, 6, 6, 0]),
            [true, true, true, false, true],
            "an unchanged value is no new sample"
        );
    }

    #[test]
    fn analog_upper_limit_triggers_above_it_only() {
        let (mut io, mut od) = analog_interrupt_device();
        analog_settings(&mut od, 0x01, 1000, 0, 0);
        assert_eq!(
            analog_steps(&mut io, &mut od, &[500, 1000, 1001, 1500, 500, -1500]),
            [false, false, true, true, false, false]
        );
    }

    #[test]
    fn analog_lower_limit_triggers_below_it_only() {
        let (mut io, mut od) = analog_interrupt_device();
        analog_settings(&mut od, 0x02, 0, -1000, 0);
        assert_eq!(
            analog_steps(&mut io, &mut od, &[-500, -1000, -1001, -1500, 0, 1500]),
            [false, false, true, true, false, false]
        );
    }

    #[test]
    fn analog_delta_compares_with_the_previous_value() {
        let (mut io, mut od) = analog_interrupt_device();
        analog_settings(&mut od, 0x04, i32::MAX, i32::MIN, 100);
        assert_eq!(
            analog_steps(&mut io, &mut od, &[50, 200, 250, 80, 179, 79]),
            [false, true, false, true, false, true]
        );
    }

    #[test]
    fn analog_negative_and_positive_deltas_see_one_direction_each() {
        let (mut io, mut od) = analog_interrupt_device();
        analog_settings(&mut od, 0x08, 0, 0, 0);
        assert_eq!(
            analog_steps(&mut io, &mut od, &[10, 5, 7]),
            [false, true, false],
            "6427h absent: any decrease"
        );
        analog_settings(&mut od, 0x10, 0, 0, 0);
        assert_eq!(analog_steps(&mut io, &mut od, &[3, 9]), [false, true]);
    }

    proptest! {
        /// With 6421h's defaults (07h, limits and delta 0) every new value triggers and a repeated
        /// one does not; with no condition selected (00h) nothing does, whatever the values.
        #[test]
        fn analog_defaults_send_every_change_and_no_selection_sends_none(
            values in proptest::collection::vec(any::<i16>(), 1..24)
        ) {
            let (mut io, mut od) = analog_interrupt_device();
            let mut previous = 0i16;
            for &value in &values {
                let sent = !io.set_analog_input(T0, 1, value, &mut od).unwrap().changed.is_empty();
                prop_assert_eq!(sent, value != previous, "{} after {}", value, previous);
                previous = value;
            }
            analog_settings(&mut od, 0x00, 0, 0, 0);
            for &value in &values {
                let changes = io.set_analog_input(T0, 1, value.wrapping_add(1), &mut od).unwrap();
                prop_assert!(changes.changed.is_empty());
            }
        }
    }

    #[test]
    fn analog_global_interrupt_enable_gates_the_trigger_conditions() {
        let (mut io, mut od) = analog_interrupt_device();
        od.set_value(ANALOG_INTERRUPT_ENABLE, &[0]).unwrap();
        assert_eq!(analog_steps(&mut io, &mut od, &[300, -300]), [false, false]);
        assert_eq!(read_i16(&od, AI1), Some(-300), "the value is still updated");
    }

    #[test]
    fn setting_a_missing_analog_channel_is_an_error() {
        let (mut io, mut od) = device();
        for channel in [0, 5, 255] {
            let err = io.set_analog_input(T0, channel, 1, &mut od).unwrap_err();
            assert_eq!(err, InputError::NoSuchAnalogInput { channel, count: 4 });
            assert!(err.to_string().contains("channels 1..=4"), "{err}");
        }
    }

    #[test]
    fn missing_objects_switch_features_off() {
        let mut od = DynamicOd::with_capacity(8);
        for (index, sub, data_type, access) in [
            (0x6000, 1, DataType::UNSIGNED8, Access::Ro),
            (0x6200, 1, DataType::UNSIGNED8, Access::Rww),
        ] {
            let e = Entry::new(ObjectKey::new(index, sub), data_type, access, &[0]).unwrap();
            od.insert(e).unwrap();
        }
        let mut io = Cia401Io::new();
        assert_eq!(
            io.set_digital_inputs(T0, 1, &mut od),
            Err(InputError::NotSupported {
                feature: Feature::DigitalInputs
            }),
            "before reset nothing is known"
        );
        io.reset(T0, &mut od);
        assert_eq!(io.features(), [Feature::DigitalInputs, Feature::DigitalOutputs]);
        assert_eq!(Cia401Io::device_type(&od), 0x0003_0191);
        // Absent interrupt objects act as their defaults: any change triggers.
        assert_eq!(set(&mut io, &mut od, 0x01), triggered());
        let err = io.set_analog_input(T0, 1, 1, &mut od).unwrap_err();
        assert_eq!(
            err,
            InputError::NotSupported {
                feature: Feature::AnalogInputs
            }
        );
        assert!(err.to_string().contains("analogue inputs (6401h)"), "{err}");
        // Factory test writes to objects that do not exist change nothing.
        assert_eq!(io.on_write(T0, FACTORY_TEST, &mut od), AppChanges::none());

        let mut empty = DynamicOd::with_capacity(0);
        io.reset(T0, &mut empty);
        assert!(io.features().is_empty());
        assert_eq!(Cia401Io::device_type(&empty), PROFILE_401);
    }

    #[test]
    fn outputs_follow_6200h_with_polarity_and_filter_mask() {
        let (mut io, mut od) = device();
        assert_eq!(sdo(&mut io, &mut od, WRITE_OUTPUT, &[0x5A]), AppChanges::none());
        assert_eq!(io.outputs(), 0x5A);
        grow(&mut od);
        for (index, value) in [(0x6202, 0x0F), (0x6208, 0xF0)] {
            let e = Entry::new(
                ObjectKey::new(index, 1),
                DataType::UNSIGNED8,
                Access::Rw,
                &[value],
            )
            .unwrap();
            od.insert(e).unwrap();
        }
        io.reset(T0, &mut od);
        assert!(io.supports(Feature::OutputPolarity) && io.supports(Feature::OutputFilterMask));
        // After reset the low nibble is frozen at 0; the high nibble shows 5h (polarity 0 there).
        assert_eq!(io.outputs(), 0x50);
        sdo(&mut io, &mut od, WRITE_OUTPUT, &[0xFF]);
        assert_eq!(io.outputs(), 0xF0);
        sdo(&mut io, &mut od, FILTER_MASK_OUTPUT, &[0xFF]);
        assert_eq!(io.outputs(), 0xF0, "FFh XOR polarity 0Fh");
    }

    #[test]
    fn install_objects_adds_the_cia401_objects_and_default_pdos() {
        let mut od = base_od();
        let added = install_objects(&mut od, 5).unwrap();
        assert_eq!(
            added,
            [
                0x2000, 0x2001, 0x2002, 0x6000, 0x6002, 0x6005, 0x6006, 0x6007, 0x6008, 0x6200, 0x6401,
                0x1400, 0x1600, 0x1800, 0x1A00, 0x1801, 0x1A01
            ]
        );
        let u32_at = |index, sub| read_uint(&od, ObjectKey::new(index, sub)).unwrap();
        assert_eq!(u32_at(0x1000, 0), 0x0007_0191);
        assert_eq!(u32_at(0x1400, 1), 0x205);
        assert_eq!(u32_at(0x1800, 1), 0x185);
        assert_eq!(u32_at(0x1801, 1), 0x285);
        assert_eq!(u32_at(0x1800, 2), 255);
        assert_eq!(u32_at(0x1600, 0), 1);
        assert_eq!(u32_at(0x1600, 1), 0x6200_0108);
        assert_eq!(u32_at(0x1A00, 1), 0x6000_0108);
        assert_eq!(u32_at(0x1A01, 0), 4);
        let map: Vec<u64> = (1..=4).map(|sub| u32_at(0x1A01, sub)).collect();
        assert_eq!(map, [0x6401_0110, 0x6401_0210, 0x6401_0310, 0x6401_0410]);
        assert_eq!(u32_at(0x6005, 0), 1);
        assert_eq!(u32_at(0x6006, 1), 0xFF);
        assert!(od.get(READ_INPUT).unwrap().tpdo_mappable());
        assert!(od.get(WRITE_OUTPUT).unwrap().rpdo_mappable());
        assert!(od.get(AI1).unwrap().tpdo_mappable());
        assert!(
            od.write(READ_INPUT, &[1]).is_err(),
            "6000h is read-only for the network"
        );
        // A second call adds nothing.
        assert_eq!(install_objects(&mut od, 5).unwrap(), [] as [u16; 0]);
        let mut io = Cia401Io::new();
        io.reset(T0, &mut od);
        assert_eq!(
            io.features().len(),
            11,
            "all but 6202h, 6208h and 6423h: {:?}",
            io.features()
        );
    }

    #[test]
    fn install_objects_keeps_existing_objects() {
        let mut od = DynamicOd::with_capacity(128);
        let e = |index, sub, value: &[u8]| {
            let data_type = if value.len() == 2 {
                DataType::INTEGER16
            } else {
                DataType::UNSIGNED8
            };
            Entry::new(ObjectKey::new(index, sub), data_type, Access::Rw, value).unwrap()
        };
        for entry in [
            e(0x6006, 0, &[1]),
            e(0x6006, 1, &[0x0F]),
            e(0x6401, 0, &[2]),
            e(0x6401, 1, &[0, 0]),
            e(0x6401, 2, &[0, 0]),
            e(0x6411, 0, &[1]),
            e(0x6411, 1, &[0, 0]),
            e(0x1000, 0, &[0x91]), // wrong type: replaced
        ] {
            od.insert(entry).unwrap();
        }
        let added = install_objects(&mut od, 127).unwrap();
        assert!(!added.contains(&0x6006) && !added.contains(&0x6401));
        assert_eq!(od.capacity(), 128, "room enough: not rebuilt");
        assert_eq!(read_u8(&od, MASK_ANY_CHANGE), Some(0x0F));
        assert_eq!(
            read_uint(&od, DEVICE_TYPE),
            Some(0x000F_0191),
            "analogue outputs present"
        );
        assert_eq!(od.get(DEVICE_TYPE).unwrap().data_type(), DataType::UNSIGNED32);
        assert_eq!(
            read_uint(&od, ObjectKey::new(0x1A01, 0)),
            Some(2),
            "only two channels exist"
        );
        assert_eq!(read_uint(&od, ObjectKey::new(0x1801, 1)), Some(0x2FF));
        assert!(od.get(ObjectKey::new(FACTORY_ANALOG, 4)).is_some());
    }

    /// A description that says it is a CiA 401 device keeps its 1000h (all four I/O kinds here,
    /// though it has digital I/O only): the application adds objects, it does not rewrite the
    /// identity a master reads.
    #[test]
    fn install_objects_keeps_a_profile_401_device_type() {
        let mut od = DynamicOd::with_capacity(4);
        od.insert(
            Entry::new(
                DEVICE_TYPE,
                DataType::UNSIGNED32,
                Access::Ro,
                &0x000F_0191u32.to_le_bytes(),
            )
            .unwrap(),
        )
        .unwrap();
        install_objects(&mut od, 5).unwrap();
        assert_eq!(read_uint(&od, DEVICE_TYPE), Some(0x000F_0191));
        let mut other = DynamicOd::with_capacity(4);
        other
            .insert(
                Entry::new(
                    DEVICE_TYPE,
                    DataType::UNSIGNED32,
                    Access::Ro,
                    &0x0002_0192u32.to_le_bytes(),
                )
                .unwrap(),
            )
            .unwrap();
        install_objects(&mut other, 5).unwrap();
        assert_eq!(
            read_uint(&other, DEVICE_TYPE),
            Some(0x0007_0191),
            "another profile becomes 401"
        );
    }

    #[test]
    fn install_objects_leaves_pdos_without_objects_invalid() {
        let mut od = base_od();
        // An RPDO1 mapping target that cannot be added: 6200h exists, but without sub-index 1.
        od.insert(Entry::new(ObjectKey::new(0x6200, 0), DataType::UNSIGNED8, Access::Ro, &[0]).unwrap())
            .unwrap_or_else(|_| panic!("room"));
        // `base_od` has capacity 4: this forces a rebuild as well.
        install_objects(&mut od, 1).unwrap();
        assert_eq!(read_uint(&od, ObjectKey::new(0x1400, 1)), Some(0x8000_0201));
        assert_eq!(read_uint(&od, ObjectKey::new(0x1600, 0)), Some(0));
        assert_eq!(od.capacity(), od.len());
    }

    #[test]
    fn install_objects_refuses_invalid_node_ids() {
        for node_id in [0, 128, 255] {
            let mut od = base_od();
            let err = install_objects(&mut od, node_id).unwrap_err();
            assert_eq!(err, InstallError::InvalidNodeId { node_id });
            assert!(err.to_string().contains("1..=127"));
            assert_eq!(od.len(), 1, "nothing added");
        }
    }

    #[test]
    fn application_has_no_timer() {
        let (mut io, mut od) = device();
        assert_eq!(io.poll_timeout(), None);
        assert_eq!(io.handle_timeout(ms(5), &mut od), AppChanges::none());
    }

    /// What a `Device` does with the application and the PDO engine, for frame traces.
    struct Bench {
        io: Cia401Io,
        pdo: PdoEngine,
        od: DynamicOd,
    }

    impl Bench {
        fn new() -> Bench {
            let (io, od) = device();
            let mut pdo = PdoEngine::new();
            pdo.reload(T0, &od);
            Bench { io, pdo, od }
        }

        fn apply(&mut self, now: Instant, changes: AppChanges) {
            for key in changes.changed {
                self.pdo.application_event(now, key);
            }
            for number in changes.trigger_tpdos {
                self.pdo.trigger_tpdo(now, number);
            }
        }

        fn sdo(&mut self, now: Instant, key: ObjectKey, data: &[u8]) {
            self.od.write(key, data).unwrap();
            let changes = self.io.on_write(now, key, &mut self.od);
            self.apply(now, changes);
        }
    }

    impl Core for Bench {
        type Event = PdoEvent;
        fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
            if self.pdo.handle_frame(now, frame, &mut self.od) {
                let changes = self.io.on_write(now, WRITE_OUTPUT, &mut self.od);
                self.apply(now, changes);
            }
        }
        fn handle_timeout(&mut self, now: Instant) {
            self.pdo.handle_timeout(now, &self.od);
            let changes = self.io.handle_timeout(now, &mut self.od);
            self.apply(now, changes);
        }
        fn poll_transmit(&mut self) -> Option<CanFrame> {
            self.pdo.poll_transmit()
        }
        fn poll_event(&mut self) -> Option<PdoEvent> {
            self.pdo.poll_event()
        }
        fn poll_timeout(&self) -> Option<Instant> {
            self.pdo.poll_timeout()
        }
    }

    #[test]
    fn trace_inputs_drive_tpdos_and_rpdo_drives_outputs() {
        let mut t = Trace::new(Bench::new());
        t.core.pdo.set_state(T0, NmtSlaveState::Operational);
        t.advance(ms(1));
        assert_eq!(t.sent(), ["0.000 185#00", "0.000 285#0000000000000000"]);

        // Thesis steps: only a rising bit 1 triggers.
        t.core.sdo(ms(10), MASK_ANY_CHANGE, &[0]);
        t.core.sdo(ms(10), MASK_LOW_TO_HIGH, &[0x02]);
        t.core.sdo(ms(10), FACTORY_TEST, &[1]);
        t.core.sdo(ms(20), FACTORY_DIGITAL, &[0x02]);
        t.advance(ms(30));
        t.core.sdo(ms(30), FACTORY_DIGITAL, &[0x40]);
        t.advance(ms(40));
        assert_eq!(t.sent(), ["20.000 185#02"]);

        // The physical input is shadowed by 2002h:03 while the factory test is on.
        let now = t.now;
        let changes = t
            .core
            .io
            .set_analog_input(now, 3, 0x0BAD, &mut t.core.od)
            .unwrap();
        assert!(changes.is_empty());
        t.core.sdo(
            ms(40),
            ObjectKey::new(FACTORY_ANALOG, 3),
            &0x0102i16.to_le_bytes(),
        );
        t.advance(ms(50));
        assert_eq!(t.sent(), ["40.000 285#0000000002010000"]);

        t.rx(ms(60), "205#A5");
        assert_eq!(t.core.io.outputs(), 0xA5);
        assert!(t.sent().is_empty());
        assert_eq!(t.events(), ["60.000 RpdoWritten { number: 1 }"]);
    }

    #[test]
    fn trace_event_timer_sends_analog_inputs_cyclically() {
        let mut t = Trace::new(Bench::new());
        t.core
            .sdo(T0, ObjectKey::new(0x1801, 1), &0x8000_0285u32.to_le_bytes());
        t.core.sdo(T0, ObjectKey::new(0x1801, 5), &100u16.to_le_bytes());
        t.core.sdo(T0, ObjectKey::new(0x1801, 1), &0x285u32.to_le_bytes());
        t.core.pdo.reload(T0, &t.core.od);
        t.core.sdo(T0, FACTORY_TEST, &[1]);
        t.core.pdo.set_state(T0, NmtSlaveState::Operational);
        t.advance(ms(1));
        t.sent();
        t.core.sdo(ms(50), FA1, &0x7FFFi16.to_le_bytes());
        t.advance(ms(250));
        // The change itself goes out at once (type 255), then every 100 ms from there.
        assert_eq!(
            t.sent(),
            [
                "50.000 285#FF7F000000000000",
                "150.000 285#FF7F000000000000",
                "250.000 285#FF7F000000000000"
            ]
        );
    }

    proptest! {
        #[test]
        fn arbitrary_writes_and_inputs_never_panic(
            steps in proptest::collection::vec(
                (0u8..4, 0u16..8, any::<u8>(), proptest::collection::vec(any::<u8>(), 0..4), any::<i16>()),
                0..40,
            ),
            frames in proptest::collection::vec(any_frame(), 0..8),
        ) {
            let mut bench = Bench::new();
            bench.pdo.set_state(T0, NmtSlaveState::Operational);
            let indices = [0x2000, 0x2001, 0x2002, 0x6000, 0x6002, 0x6005, 0x6006, 0x6200];
            for (kind, which, sub, data, analog) in steps {
                let key = ObjectKey::new(indices[usize::from(which)], sub % 6);
                match kind {
                    0 => {
                        // Whatever the network or a restore puts there, valid or not.
                        let _ = bench.od.set_value(key, &data);
                        let changes = bench.io.on_write(T0, key, &mut bench.od);
                        bench.apply(T0, changes);
                    }
                    1 => {
                        let _ = bench.io.set_digital_inputs(T0, sub, &mut bench.od);
                    }
                    2 => {
                        let _ = bench.io.set_analog_input(T0, sub, analog, &mut bench.od);
                    }
                    _ => {
                        // Objects replaced by ones of another type, then a reset.
                        let _ = bench.od.insert(Entry::new(key, DataType::VISIBLE_STRING, Access::Rw, &data).unwrap());
                        bench.io.reset(T0, &mut bench.od);
                    }
                }
            }
            for frame in frames {
                bench.handle_frame(ms(1), &frame);
            }
            bench.handle_timeout(ms(2));
            while bench.poll_transmit().is_some() {}
        }
    }
}

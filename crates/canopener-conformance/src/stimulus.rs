//! The user's hook that changes a device's inputs when it has no factory test registers
//! (`canopener test --stimulus CMD`): the CiA 401 tests name the input to apply as an
//! [`InputChange`], a [`Stimulus`] applies it (a test rig, a signal generator, a PLC output), and
//! the tests wait [`Hook::settle`] on the link's clock before they look, since a real input has a
//! filter between the terminal and the object dictionary.
//!
//! The crate runs no programs: [`canopener_link::stimulus_program::StimulusProgram`] (the CLI's
//! `--stimulus CMD`) implements [`Stimulus`] here, tests implement it in Rust.

use std::fmt;
use std::time::Duration;

use canopener_link::stimulus_program::StimulusProgram;

/// The settle time when the user gives none: long enough for a typical input filter (1–3 ms) and
/// the device's processing, short enough that the event-driven TPDO window stays tight.
pub const DEFAULT_SETTLE: Duration = Duration::from_millis(10);

/// One input to apply, named by the CiA 401 object that reads it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputChange {
    /// Digital input block `block` (6000h:`block`, 8 inputs) to `value` (bit *n* = input *n* + 1, as
    /// at the terminals: before polarity 6002h).
    Digital {
        /// The sub-index of 6000h (1 = inputs 1..8).
        block: u8,
        /// The terminal levels.
        value: u8,
    },
    /// Analogue input channel `channel` (6401h:`channel`) to `value`, in the unit 6401h reads.
    Analog {
        /// The sub-index of 6401h (1-based).
        channel: u8,
        /// The value to apply.
        value: i16,
    },
}

impl InputChange {
    /// The object that reads the input: 6000h or 6401h.
    pub fn index(&self) -> u16 {
        match self {
            InputChange::Digital { .. } => 0x6000,
            InputChange::Analog { .. } => 0x6401,
        }
    }

    /// Its sub-index.
    pub fn sub(&self) -> u8 {
        match *self {
            InputChange::Digital { block, .. } => block,
            InputChange::Analog { channel, .. } => channel,
        }
    }

    /// The value as the hook's contract passes it: `0x5A` for a digital block, `-1234` for an
    /// analogue channel.
    pub fn value_text(&self) -> String {
        match *self {
            InputChange::Digital { value, .. } => format!("0x{value:02X}"),
            InputChange::Analog { value, .. } => value.to_string(),
        }
    }

    /// The program's arguments: `6000 1 0x5A`, `6401 1 1000`.
    pub fn arguments(&self) -> [String; 3] {
        [
            format!("{:04X}", self.index()),
            self.sub().to_string(),
            self.value_text(),
        ]
    }
}

impl fmt::Display for InputChange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:04X}h:{:02X} = {}",
            self.index(),
            self.sub(),
            self.value_text()
        )
    }
}

/// Applies inputs to the device under test.
pub trait Stimulus {
    /// Applies `change`; returns once it is applied at the terminals, or why it could not be (the
    /// test that asked is then `inconclusive` with that text).
    fn apply(&mut self, change: &InputChange) -> Result<(), String>;
}

impl Stimulus for StimulusProgram {
    fn apply(&mut self, change: &InputChange) -> Result<(), String> {
        self.run(&change.arguments())
    }
}

/// A stimulus with the time the tests wait after it returns.
pub struct Hook<'a> {
    /// Applies the inputs.
    pub stimulus: &'a mut dyn Stimulus,
    /// How long the tests wait on the link's clock after the stimulus returned, before they read
    /// 6000h/6401h or expect the TPDO.
    pub settle: Duration,
}

impl fmt::Debug for Hook<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Hook")
            .field("settle", &self.settle)
            .finish_non_exhaustive()
    }
}

impl Hook<'_> {
    /// The same hook, borrowed for a shorter time (one test's context).
    pub fn reborrow(&mut self) -> Hook<'_> {
        Hook {
            stimulus: &mut *self.stimulus,
            settle: self.settle,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_program_gets_the_object_the_sub_index_and_the_value() {
        let digital = InputChange::Digital {
            block: 1,
            value: 0x5A,
        };
        assert_eq!(digital.arguments(), ["6000", "1", "0x5A"]);
        assert_eq!(digital.to_string(), "6000h:01 = 0x5A");
        let analog = InputChange::Analog {
            channel: 2,
            value: -1234,
        };
        assert_eq!(analog.arguments(), ["6401", "2", "-1234"]);
    }
}

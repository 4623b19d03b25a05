//! The EMCY consumer (CiA 301 §7.2.7): emergency messages decoded into events.
//!
//! Before changing this file read CiA 301 §7.2.7 (EMCY: the error code table and the write protocol,
//! §7.2.7.3.1) and the description of object 1014h (COB-ID EMCY).
//!
//! An EMCY is 8 bytes: the error code (little-endian), the error register (the node's 1001h) and 5
//! manufacturer-specific bytes. Code 0000h is the error reset: an error went away, and the register
//! shows what remains. Every node sends on 80h + node-ID unless its 1014h says otherwise;
//! [`EmcyConsumer::set_cob_id`] takes a node's 1014h value, which wins over the predefined
//! connection set when the two overlap.
//!
//! Frames of another length than 8, and remote frames, on an EMCY CAN-ID are reported as
//! [`EmcyEvent::Malformed`], with what could be read of them, never dropped: a device that sends
//! short EMCYs is exactly what a user of a monitor wants to see.

use std::collections::{BTreeMap, VecDeque};
use std::fmt;

use canopener_can::{CanFrame, CanId, Core, ExtendedId, Instant, StandardId};
use canopener_wire::{EMCY_BASE, EmcyMessage, NodeId, emcy_code_text, error_register_text};

/// The length of a correct EMCY frame.
pub const EMCY_LEN: u8 = 8;

/// 1014h bit 31: set = the node has no EMCY (the COB-ID is not valid).
pub const EMCY_INVALID: u32 = 0x8000_0000;
/// 1014h bit 30: reserved, 0.
pub const EMCY_RESERVED: u32 = 0x4000_0000;
/// 1014h bit 29: set = 29-bit CAN-ID.
pub const EMCY_FRAME_29BIT: u32 = 0x2000_0000;

/// What [`EmcyConsumer`] reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EmcyEvent {
    /// An emergency message, or with code 0000h an error reset.
    Emcy {
        /// The node that sent it.
        node: NodeId,
        /// The error code.
        code: u16,
        /// The error register (1001h) sent with it.
        register: u8,
        /// The manufacturer-specific error field, D3..D7.
        manufacturer: [u8; 5],
        /// The CiA 301 / CiA 401 text of the code.
        text: &'static str,
    },
    /// A frame on an EMCY CAN-ID that is not an EMCY.
    Malformed {
        /// The node whose EMCY CAN-ID it used.
        node: NodeId,
        /// What is wrong.
        problem: MalformedEmcy,
        /// What could be read: code and register from 3 bytes on, missing manufacturer bytes 0.
        partial: Option<EmcyMessage>,
    },
}

impl EmcyEvent {
    /// The node the event is about.
    pub fn node(&self) -> NodeId {
        match *self {
            EmcyEvent::Emcy { node, .. } | EmcyEvent::Malformed { node, .. } => node,
        }
    }

    /// Whether this is an error reset (code 0000h).
    pub fn is_error_reset(&self) -> bool {
        matches!(self, EmcyEvent::Emcy { code: 0, .. })
    }
}

/// What makes a frame on an EMCY CAN-ID malformed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MalformedEmcy {
    /// A data frame with another length than 8.
    WrongLength {
        /// The frame's DLC.
        dlc: u8,
    },
    /// A remote frame: EMCY has no remote requests.
    Remote,
}

/// `node 5: EMCY 8130h life guard error or heartbeat error, error register 11h (generic,
/// communication), manufacturer 03 00 00 00 00`.
impl fmt::Display for EmcyEvent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "node {}: ", self.node())?;
        match *self {
            EmcyEvent::Emcy {
                code,
                register,
                manufacturer,
                text,
                ..
            } => {
                write!(f, "EMCY {code:04X}h {text}, ")?;
                write_register(f, register)?;
                let [m0, m1, m2, m3, m4] = manufacturer;
                write!(f, ", manufacturer {m0:02X} {m1:02X} {m2:02X} {m3:02X} {m4:02X}")
            }
            EmcyEvent::Malformed { problem, partial, .. } => {
                match problem {
                    MalformedEmcy::WrongLength { dlc } => {
                        write!(f, "malformed EMCY with {dlc} bytes instead of {EMCY_LEN}")?
                    }
                    MalformedEmcy::Remote => f.write_str("remote frame on the EMCY CAN-ID")?,
                }
                if let Some(emcy) = partial {
                    write!(f, " (code {:04X}h {}, ", emcy.code, emcy_code_text(emcy.code))?;
                    write_register(f, emcy.register)?;
                    f.write_str(")")?;
                }
                Ok(())
            }
        }
    }
}

fn write_register(f: &mut fmt::Formatter<'_>, register: u8) -> fmt::Result {
    write!(f, "error register {register:02X}h")?;
    if register != 0 {
        write!(f, " ({})", error_register_text(register))?;
    }
    Ok(())
}

/// Why a 1014h value was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum EmcyConfigError {
    /// Bit 30 is reserved and must be 0.
    #[error("1014h = {value:#010X} sets the reserved bit 30; write 0 there")]
    ReservedBit {
        /// The value given.
        value: u32,
    },
    /// Bits 28..11 set without bit 29: an 11-bit CAN-ID has only bits 10..0.
    #[error(
        "1014h = {value:#010X} has bits 28..11 set without bit 29 (29-bit CAN-ID); an 11-bit CAN-ID uses bits 10..0"
    )]
    NotElevenBit {
        /// The value given.
        value: u32,
    },
}

/// The EMCY consumer for every node (CiA 301 §7.2.7), sans IO.
///
/// Feed it every received frame ([`EmcyConsumer::handle_frame`]; frames on other CAN-IDs are
/// ignored) and drain [`EmcyConsumer::poll_event`]. It has no timers and sends nothing.
#[derive(Debug, Clone, Default)]
pub struct EmcyConsumer {
    /// 1014h per node, where it was given: `None` for a node without EMCY.
    configured: BTreeMap<NodeId, Option<CanId>>,
    registers: BTreeMap<NodeId, u8>,
    events: VecDeque<EmcyEvent>,
}

impl EmcyConsumer {
    /// A consumer that listens on the predefined connection set: 81h to FFh.
    pub fn new() -> EmcyConsumer {
        EmcyConsumer::default()
    }

    /// Takes `node`'s COB-ID EMCY (1014h): bit 31 set = the node has no EMCY, bit 29 set = 29-bit
    /// CAN-ID in bits 28..0, else an 11-bit CAN-ID in bits 10..0. Nothing changes on error.
    pub fn set_cob_id(&mut self, node: NodeId, value: u32) -> Result<(), EmcyConfigError> {
        if value & EMCY_RESERVED != 0 {
            return Err(EmcyConfigError::ReservedBit { value });
        }
        let id = if value & EMCY_FRAME_29BIT != 0 {
            // 29 bits always fit an extended identifier.
            ExtendedId::new(value & 0x1FFF_FFFF).map(CanId::Extended)
        } else if value & 0x1FFF_F800 != 0 {
            return Err(EmcyConfigError::NotElevenBit { value });
        } else {
            StandardId::new((value & 0x7FF) as u16).map(CanId::Standard)
        };
        let id = if value & EMCY_INVALID != 0 { None } else { id };
        self.configured.insert(node, id);
        Ok(())
    }

    /// Forgets `node`'s 1014h: it sends on 80h + node-ID again.
    pub fn reset_cob_id(&mut self, node: NodeId) {
        self.configured.remove(&node);
    }

    /// The CAN-ID `node`'s EMCYs arrive on, or `None` when it has none.
    pub fn cob_id(&self, node: NodeId) -> Option<CanId> {
        match self.configured.get(&node) {
            Some(configured) => *configured,
            None => StandardId::new(EMCY_BASE + u16::from(node.get())).map(CanId::Standard),
        }
    }

    /// The error register `node` sent with its last EMCY.
    pub fn error_register(&self, node: NodeId) -> Option<u8> {
        self.registers.get(&node).copied()
    }

    fn node_of(&self, id: CanId) -> Option<NodeId> {
        if let Some((node, _)) = self
            .configured
            .iter()
            .find(|(_, configured)| **configured == Some(id))
        {
            return Some(*node);
        }
        let CanId::Standard(standard) = id else {
            return None;
        };
        let node = standard
            .as_raw()
            .checked_sub(EMCY_BASE)
            .and_then(|raw| u8::try_from(raw).ok())
            .and_then(NodeId::new)?;
        // A node with its own 1014h no longer sends on its predefined CAN-ID.
        (!self.configured.contains_key(&node)).then_some(node)
    }
}

impl Core for EmcyConsumer {
    type Event = EmcyEvent;

    /// Feeds a received frame.
    fn handle_frame(&mut self, _now: Instant, frame: &CanFrame) {
        let Some(node) = self.node_of(frame.id()) else {
            return;
        };
        let data = frame.data();
        let partial = EmcyMessage::parse(data).ok();
        let problem = if frame.is_remote() {
            Some(MalformedEmcy::Remote)
        } else if frame.dlc() != EMCY_LEN {
            Some(MalformedEmcy::WrongLength { dlc: frame.dlc() })
        } else {
            None
        };
        let event = match (problem, partial) {
            (None, Some(emcy)) => {
                self.registers.insert(node, emcy.register);
                EmcyEvent::Emcy {
                    node,
                    code: emcy.code,
                    register: emcy.register,
                    manufacturer: emcy.vendor,
                    text: emcy_code_text(emcy.code),
                }
            }
            // An 8-byte frame always parses; the fallback keeps this total.
            (problem, partial) => EmcyEvent::Malformed {
                node,
                problem: problem.unwrap_or(MalformedEmcy::WrongLength { dlc: frame.dlc() }),
                partial: partial.filter(|_| !frame.is_remote()),
            },
        };
        self.events.push_back(event);
    }

    /// EmcyConsumer has no timers.
    fn handle_timeout(&mut self, _now: Instant) {}

    /// EmcyConsumer sends nothing.
    fn poll_transmit(&mut self) -> Option<CanFrame> {
        None
    }

    /// The next event.
    fn poll_event(&mut self) -> Option<Self::Event> {
        self.events.pop_front()
    }

    /// EmcyConsumer has no timers.
    fn poll_timeout(&self) -> Option<Instant> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_can::Core;
    use canopener_testkit::trace::{Trace, ms};

    fn node(raw: u8) -> NodeId {
        NodeId::new(raw).unwrap()
    }

    /// Feeds compact candump frames and returns the events.
    fn feed(consumer: &mut EmcyConsumer, frames: &[&str]) -> Vec<EmcyEvent> {
        for text in frames {
            let frame = canopener_can::candump::parse_compact_frame(text).unwrap();
            consumer.handle_frame(Instant::ZERO, &frame);
        }
        std::iter::from_fn(|| consumer.poll_event()).collect()
    }

    fn displayed(consumer: &mut EmcyConsumer, frames: &[&str]) -> Vec<String> {
        feed(consumer, frames)
            .iter()
            .map(|event| event.to_string())
            .collect()
    }

    #[test]
    fn emcy_and_error_reset() {
        let mut trace = Trace::new(EmcyConsumer::new());
        trace.rx(ms(4), "085#1082110100000000");
        trace.rx(ms(5), "085#0000000000000000");
        assert_eq!(
            trace.events(),
            [
                "4.000 Emcy { node: NodeId(5), code: 33296, register: 17, manufacturer: [1, 0, 0, 0, 0], \
                 text: \"PDO not processed due to length error\" }",
                "5.000 Emcy { node: NodeId(5), code: 0, register: 0, manufacturer: [0, 0, 0, 0, 0], \
                 text: \"error reset or no error\" }",
            ]
        );
        assert_eq!(trace.core.error_register(node(5)), Some(0));
        assert_eq!(trace.core.error_register(node(6)), None);
    }

    #[test]
    fn display_lines() {
        let mut consumer = EmcyConsumer::new();
        let frames = ["08A#3081110300000000", "08A#0000000000000000", "0FF#1082"];
        assert_eq!(
            displayed(&mut consumer, &frames),
            [
                "node 10: EMCY 8130h life guard error or heartbeat error, error register 11h \
                 (generic, communication), manufacturer 03 00 00 00 00",
                "node 10: EMCY 0000h error reset or no error, error register 00h, manufacturer 00 00 00 00 00",
                "node 127: malformed EMCY with 2 bytes instead of 8",
            ]
        );
        let reset = EmcyEvent::Emcy {
            node: node(1),
            code: 0,
            register: 0,
            manufacturer: [0; 5],
            text: "",
        };
        assert!(reset.is_error_reset());
    }

    #[test]
    fn malformed_frames_are_reported() {
        let mut trace = Trace::new(EmcyConsumer::new());
        trace.rx(ms(0), "085#");
        trace.rx(ms(1), "085#108211");
        trace.rx(ms(2), "085#R8");
        trace.rx(ms(3), "085#30811103000000");
        assert_eq!(
            trace.events(),
            [
                "0.000 Malformed { node: NodeId(5), problem: WrongLength { dlc: 0 }, partial: None }",
                "1.000 Malformed { node: NodeId(5), problem: WrongLength { dlc: 3 }, partial: \
                 Some(EmcyMessage { code: 33296, register: 17, vendor: [0, 0, 0, 0, 0] }) }",
                "2.000 Malformed { node: NodeId(5), problem: Remote, partial: None }",
                "3.000 Malformed { node: NodeId(5), problem: WrongLength { dlc: 7 }, partial: \
                 Some(EmcyMessage { code: 33072, register: 17, vendor: [3, 0, 0, 0, 0] }) }",
            ]
        );
        assert_eq!(
            displayed(&mut trace.core, &["085#30811103"]),
            [
                "node 5: malformed EMCY with 4 bytes instead of 8 (code 8130h life guard error or \
              heartbeat error, error register 11h (generic, communication))"
            ]
        );
        // A malformed frame does not update the error register.
        assert_eq!(trace.core.error_register(node(5)), None);
    }

    #[test]
    fn only_emcy_can_ids() {
        let mut trace = Trace::new(EmcyConsumer::new());
        for text in [
            "080#0000000000000000",
            "100#0000000000000000",
            "185#0000000000000000",
            "00000085#0000000000000000",
        ] {
            trace.rx(ms(0), text);
        }
        assert!(trace.events().is_empty());
    }

    #[test]
    fn configured_cob_ids_from_1014h() {
        let mut consumer = EmcyConsumer::new();
        // Node 5 moves to 0x0A5; node 6 is disabled; node 7 uses a 29-bit CAN-ID.
        consumer.set_cob_id(node(5), 0x0A5).unwrap();
        consumer.set_cob_id(node(6), EMCY_INVALID | 0x86).unwrap();
        consumer
            .set_cob_id(node(7), EMCY_FRAME_29BIT | 0x0123_4567)
            .unwrap();
        assert_eq!(consumer.cob_id(node(6)), None);
        assert_eq!(consumer.cob_id(node(8)), Some(CanId::standard(0x88).unwrap()));
        // 0A5h would be node 37 in the predefined set; the configuration wins.
        let frames = [
            "0A5#0010010000000000",
            "085#0010010000000000",
            "086#0010010000000000",
            "01234567#0010010000000000",
        ];
        let nodes: Vec<u8> = feed(&mut consumer, &frames)
            .iter()
            .map(|event| event.node().get())
            .collect();
        assert_eq!(nodes, [5, 7]);
        consumer.reset_cob_id(node(5));
        let frames = ["085#0010010000000000", "0A5#0010010000000000"];
        let nodes: Vec<u8> = feed(&mut consumer, &frames)
            .iter()
            .map(|event| event.node().get())
            .collect();
        assert_eq!(nodes, [5, 37]);
    }

    proptest::proptest! {
        /// Every frame on an EMCY CAN-ID gives exactly one event, whatever it holds; others none.
        #[test]
        fn one_event_per_emcy_frame(
            id in 0u16..0x800,
            remote: bool,
            data in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..=8),
        ) {
            let mut consumer = EmcyConsumer::new();
            let id_std = StandardId::new(id).unwrap();
            let frame = if remote {
                CanFrame::remote(id_std, data.len() as u8).unwrap()
            } else {
                CanFrame::new(id_std, &data).unwrap()
            };
            consumer.handle_frame(Instant::ZERO, &frame);
            let events: Vec<EmcyEvent> = std::iter::from_fn(|| consumer.poll_event()).collect();
            let expected = usize::from((0x81..=0xFF).contains(&id));
            proptest::prop_assert_eq!(events.len(), expected);
            let well_formed = events.iter().all(|event| matches!(event, EmcyEvent::Emcy { .. }));
            if expected == 1 {
                proptest::prop_assert_eq!(well_formed, !remote && data.len() == 8);
            }
        }
    }

    #[test]
    fn bad_1014h_values_are_refused() {
        let mut consumer = EmcyConsumer::new();
        assert_eq!(
            consumer.set_cob_id(node(5), 0x4000_0085),
            Err(EmcyConfigError::ReservedBit { value: 0x4000_0085 })
        );
        assert_eq!(
            consumer.set_cob_id(node(5), 0x0000_0885),
            Err(EmcyConfigError::NotElevenBit { value: 0x885 })
        );
        assert_eq!(consumer.cob_id(node(5)), Some(CanId::standard(0x85).unwrap()));
    }
}

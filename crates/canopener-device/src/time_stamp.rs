//! The TIME producer and consumer (CiA 301, time stamp object (TIME) service, object 1012h).
//!
//! COB-ID TIME 1012h: bit 31 set = this node consumes TIME, bit 30 set = this node produces TIME,
//! bits 10..0 the CAN-ID (default 100h). Bit 29 (29-bit CAN-ID) and bits 28..11 are not supported,
//! and restricted CAN-IDs are refused; both with 0609 0030h, as CANopenNode does and the CCT
//! expects for the restricted CAN-IDs.
//!
//! The TIME frame carries a TIME_OF_DAY ([`TimeOfDay`]): 6 bytes, milliseconds after midnight in
//! 28 bits, then days since 1 January 1984. The producer has no clock of its own: it sends when
//! the `Device` asks with [`TimeService::produce`]. The consumer reports every TIME frame of 6 bytes
//! as [`TimeEvent::Time`] and every other data frame on the TIME CAN-ID as
//! [`TimeEvent::WrongLength`] (ignored otherwise, as CANopenNode does). Remote frames are ignored.
//!
//! TIME runs in Pre-operational and Operational only (CiA 301 table of services per NMT state).
//!
//! Choice where sources disagree: the CAN-ID may change while bits 30/31 are set (CANopenNode,
//! which passes the CCT, allows it; lely refuses it).

use std::collections::VecDeque;

use canopener_can::{CanFrame, Core, Instant, StandardId};
use canopener_od::{DynamicOd, ObjectKey};
use canopener_wire::{TIME_ID, TimeOfDay, abort};

use crate::nmt_slave::{CommService, NmtSlaveState};

/// Bit 31 of 1012h: set = this node consumes TIME.
pub const TIME_CONSUMER: u32 = 0x8000_0000;
/// Bit 30 of 1012h: set = this node produces TIME.
pub const TIME_PRODUCER: u32 = 0x4000_0000;
/// The COB-ID TIME object.
pub const COB_ID_TIME: u16 = 0x1012;

/// Why a 1012h write was refused; [`TimeConfigError::abort_code`] is the SDO abort code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum TimeConfigError {
    /// 1012h with bit 29 or any of bits 28..11 set (0609 0030h): only an 11-bit CAN-ID is supported.
    #[error("1012h = {value:#010X}: only bits 31, 30 and an 11-bit CAN-ID may be set")]
    UnsupportedCobId {
        /// The value written.
        value: u32,
    },
    /// 1012h with a restricted CAN-ID (0609 0030h).
    #[error(
        "1012h: CAN-ID {can_id:03X}h is restricted (NMT, SDO, error control, reserved) and cannot carry TIME"
    )]
    RestrictedCanId {
        /// The CAN-ID written.
        can_id: u16,
    },
}

impl TimeConfigError {
    /// The SDO abort code an SDO server sends for this error.
    pub fn abort_code(&self) -> u32 {
        match self {
            TimeConfigError::UnsupportedCobId { .. } | TimeConfigError::RestrictedCanId { .. } => {
                abort::INVALID_VALUE
            }
        }
    }
}

/// What [`TimeService`] reports to the `Device`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TimeEvent {
    /// A TIME frame was consumed.
    Time {
        /// The time of day it carried (the reserved top 4 bits of the milliseconds dropped).
        time: TimeOfDay,
    },
    /// A data frame on the TIME CAN-ID whose length is not 6 was ignored.
    WrongLength {
        /// The data length received.
        received: u8,
    },
}

/// Why [`TimeService::produce`] sent nothing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, thiserror::Error)]
pub enum ProduceError {
    /// 1012h bit 30 is not set.
    #[error("this node does not produce TIME: 1012h bit 30 is not set")]
    NotProducer,
    /// The NMT state is Initialisation or Stopped.
    #[error("TIME is not sent in the NMT state {0:?}")]
    State(NmtSlaveState),
}

/// The TIME producer and consumer of one node.
#[derive(Debug, Clone)]
pub struct TimeService {
    cob_id: u32,
    state: NmtSlaveState,
    transmit: VecDeque<CanFrame>,
    events: VecDeque<TimeEvent>,
}

impl Default for TimeService {
    fn default() -> Self {
        TimeService::new()
    }
}

impl TimeService {
    /// TIME on CAN-ID 100h, neither consumed nor produced, in Initialisation. The `Device` loads
    /// the power-on 1012h with [`TimeService::load_od`].
    pub fn new() -> TimeService {
        TimeService {
            cob_id: u32::from(TIME_ID),
            state: NmtSlaveState::Initialisation,
            transmit: VecDeque::new(),
            events: VecDeque::new(),
        }
    }

    /// 1012h, as last accepted.
    pub fn cob_id(&self) -> u32 {
        self.cob_id
    }

    /// Whether 1012h bit 31 (consume) is set.
    pub fn is_consumer(&self) -> bool {
        self.cob_id & TIME_CONSUMER != 0
    }

    /// Whether 1012h bit 30 (produce) is set.
    pub fn is_producer(&self) -> bool {
        self.cob_id & TIME_PRODUCER != 0
    }

    /// Checks a 1012h value without applying it.
    pub fn check_cob_id(&self, value: u32) -> Result<(), TimeConfigError> {
        if value & !(TIME_CONSUMER | TIME_PRODUCER | 0x7FF) != 0 {
            return Err(TimeConfigError::UnsupportedCobId { value });
        }
        let can_id = (value & 0x7FF) as u16;
        if crate::can_id::is_restricted(can_id) {
            return Err(TimeConfigError::RestrictedCanId { can_id });
        }
        Ok(())
    }

    /// 1012h was written: checked as [`TimeService::check_cob_id`] does, then applied.
    pub fn set_cob_id(&mut self, value: u32) -> Result<(), TimeConfigError> {
        self.check_cob_id(value)?;
        self.cob_id = value;
        Ok(())
    }

    /// The check the `Device`'s [`SdoHooks::check_download`](crate::sdo_server::SdoHooks) makes for
    /// an SDO download of `data` to `key`: only 1012h:00 with 4 bytes is checked, everything else
    /// passes (the dictionary refuses wrong lengths). After the download the `Device` applies the
    /// stored value with [`TimeService::load_od`].
    pub fn check_download(&self, key: ObjectKey, data: &[u8]) -> Result<(), TimeConfigError> {
        match (key.index, key.sub, data) {
            (COB_ID_TIME, 0, &[a, b, c, d]) => self.check_cob_id(u32::from_le_bytes([a, b, c, d])),
            _ => Ok(()),
        }
    }

    /// Takes 1012h from `od`. A value a write would have been refused for (from a faulty EDS) keeps
    /// its bits 31 and 30 and the current CAN-ID. A missing 1012h changes nothing.
    pub fn load_od(&mut self, od: &DynamicOd) {
        if let Some(&[a, b, c, d]) = od.get(ObjectKey::new(COB_ID_TIME, 0)).map(|e| e.value()) {
            let value = u32::from_le_bytes([a, b, c, d]);
            self.cob_id = if self.check_cob_id(value).is_ok() {
                value
            } else {
                value & (TIME_CONSUMER | TIME_PRODUCER) | self.cob_id & 0x7FF
            };
        }
    }

    /// The NMT slave changed state. TIME runs in Pre-operational and Operational.
    pub fn set_state(&mut self, _now: Instant, state: NmtSlaveState) {
        self.state = state;
        if !state.is_active(CommService::Time) {
            self.transmit.clear();
        }
    }

    /// Sends a TIME frame carrying `time`, as the `Device` asks (from its wall clock or a test's
    /// virtual one). Refused when 1012h bit 30 is clear or the NMT state does not allow TIME.
    pub fn produce(&mut self, _now: Instant, time: TimeOfDay) -> Result<(), ProduceError> {
        if !self.is_producer() {
            return Err(ProduceError::NotProducer);
        }
        if !self.state.is_active(CommService::Time) {
            return Err(ProduceError::State(self.state));
        }
        if let Some(id) = StandardId::new((self.cob_id & 0x7FF) as u16)
            && let Ok(frame) = CanFrame::new(id, &time.encode())
        {
            self.transmit.push_back(frame);
        }
        Ok(())
    }
}

impl Core for TimeService {
    type Event = TimeEvent;

    /// Feeds a received frame: a data frame on the TIME CAN-ID (11-bit) is consumed when 1012h bit
    /// 31 is set and the NMT state allows TIME.
    fn handle_frame(&mut self, _now: Instant, frame: &CanFrame) {
        if frame.id().is_extended()
            || frame.id().as_raw() != self.cob_id & 0x7FF
            || frame.is_remote()
            || !self.is_consumer()
            || !self.state.is_active(CommService::Time)
        {
            return;
        }
        let data = frame.data();
        let event = match TimeOfDay::parse(data) {
            Ok(time) if data.len() == 6 => TimeEvent::Time { time },
            _ => TimeEvent::WrongLength {
                received: data.len() as u8,
            },
        };
        self.events.push_back(event);
    }

    /// TIME has no timers; present for the uniform sans-IO shape.
    fn handle_timeout(&mut self, _now: Instant) {}

    /// The next frame to send.
    fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.transmit.pop_front()
    }

    /// The next event for the `Device`.
    fn poll_event(&mut self) -> Option<Self::Event> {
        self.events.pop_front()
    }

    /// Always `None`: TIME has no timers.
    fn poll_timeout(&self) -> Option<Instant> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use NmtSlaveState::{Initialisation as Init, Operational as Op, PreOperational as PreOp, Stopped};
    use canopener_can::Core;
    use canopener_od::{Access, DataType, Entry};
    use canopener_testkit::frames::any_frame;
    use canopener_testkit::trace::{Trace, ms};

    /// 2024-01-01 12:00:00.000, the reference's worked example: `00 2E 93 02 12 39`.
    const NOON: TimeOfDay = TimeOfDay {
        millis: 43_200_000,
        days: 14_610,
    };

    fn service(cob_id: u32) -> Trace<TimeService> {
        let mut trace = Trace::new(TimeService::new());
        trace.core.set_cob_id(cob_id).unwrap();
        trace.core.set_state(Instant::ZERO, PreOp);
        trace
    }

    fn produce(trace: &mut Trace<TimeService>, at: Instant, time: TimeOfDay) -> Result<(), ProduceError> {
        trace.advance(at);
        trace.core.produce(at, time)
    }

    #[test]
    fn producer_sends_time_of_day_when_asked() {
        let mut trace = service(TIME_PRODUCER | 0x100);
        assert_eq!(produce(&mut trace, ms(10), NOON), Ok(()));
        let later = TimeOfDay {
            millis: 43_200_250,
            days: 14_610,
        };
        assert_eq!(produce(&mut trace, ms(260), later), Ok(()));
        assert_eq!(
            trace.sent(),
            ["10.000 100#002E93021239", "260.000 100#FA2E93021239"]
        );
    }

    #[test]
    fn producer_refusals() {
        let mut trace = service(TIME_CONSUMER | 0x100);
        assert_eq!(produce(&mut trace, ms(1), NOON), Err(ProduceError::NotProducer));
        trace.core.set_cob_id(TIME_PRODUCER | 0x1A3).unwrap();
        trace.core.set_state(ms(2), Stopped);
        assert_eq!(
            produce(&mut trace, ms(3), NOON),
            Err(ProduceError::State(Stopped))
        );
        trace.core.set_state(ms(4), Init);
        assert_eq!(produce(&mut trace, ms(5), NOON), Err(ProduceError::State(Init)));
        trace.core.set_state(ms(6), Op);
        assert_eq!(produce(&mut trace, ms(7), NOON), Ok(()));
        assert_eq!(trace.sent(), ["7.000 1A3#002E93021239"]);
    }

    #[test]
    fn consumer_decodes_time_and_reports_wrong_length() {
        let mut trace = service(TIME_CONSUMER | 0x100);
        trace.rx(ms(10), "100#002E93021239");
        trace.rx(ms(20), "100#002E93F21239"); // reserved bits set: dropped
        trace.rx(ms(30), "100#002E930212");
        trace.rx(ms(40), "100#002E9302123900");
        trace.rx(ms(50), "100#R");
        trace.rx(ms(60), "101#002E93021239");
        assert_eq!(
            trace.events(),
            [
                "10.000 Time { time: TimeOfDay { millis: 43200000, days: 14610 } }",
                "20.000 Time { time: TimeOfDay { millis: 43200000, days: 14610 } }",
                "30.000 WrongLength { received: 5 }",
                "40.000 WrongLength { received: 7 }",
            ]
        );
        assert!(trace.sent().is_empty());
    }

    #[test]
    fn consumer_follows_1012h_and_nmt_state() {
        let mut trace = service(0x100);
        trace.rx(ms(1), "100#002E93021239"); // bit 31 clear
        trace.core.set_cob_id(TIME_CONSUMER | 0x200).unwrap();
        trace.rx(ms(2), "100#002E93021239");
        trace.rx(ms(3), "200#002E93021239");
        trace.core.set_state(ms(4), Stopped);
        trace.rx(ms(5), "200#002E93021239");
        trace.core.set_state(ms(6), Op);
        trace.rx(ms(7), "200#");
        assert_eq!(
            trace.events(),
            [
                "3.000 Time { time: TimeOfDay { millis: 43200000, days: 14610 } }",
                "7.000 WrongLength { received: 0 }"
            ]
        );
    }

    #[test]
    fn cob_id_errors() {
        let mut time = TimeService::new();
        for can_id in [
            0x000u32, 0x001, 0x07F, 0x101, 0x180, 0x581, 0x5FF, 0x601, 0x67F, 0x6E0, 0x701, 0x7E5, 0x7FF,
        ] {
            for bits in [0, TIME_CONSUMER, TIME_PRODUCER] {
                let err = time.set_cob_id(bits | can_id).unwrap_err();
                assert_eq!(
                    err,
                    TimeConfigError::RestrictedCanId {
                        can_id: can_id as u16
                    }
                );
                assert_eq!(err.abort_code(), 0x0609_0030);
            }
        }
        for value in [0x2000_0100, 0x8000_0900] {
            let err = time.set_cob_id(value).unwrap_err();
            assert_eq!(err, TimeConfigError::UnsupportedCobId { value });
            assert_eq!(err.abort_code(), 0x0609_0030);
        }
        assert_eq!(time.cob_id(), 0x100, "unchanged by refused writes");
        assert_eq!(time.set_cob_id(0xC000_0100), Ok(()));
        assert!(time.is_consumer() && time.is_producer());
        assert_eq!(
            time.set_cob_id(0xC000_0181),
            Ok(()),
            "CAN-ID may change while active"
        );
    }

    #[test]
    fn check_download_and_load_od() {
        let key = ObjectKey::new(COB_ID_TIME, 0);
        let mut od = DynamicOd::with_capacity(1);
        od.insert(
            Entry::new(
                key,
                DataType::UNSIGNED32,
                Access::Rw,
                &0x8000_0100u32.to_le_bytes(),
            )
            .unwrap(),
        )
        .unwrap();
        let mut time = TimeService::new();
        time.load_od(&od);
        assert_eq!(time.cob_id(), 0x8000_0100);
        let err = time
            .check_download(key, &0x8000_0701u32.to_le_bytes())
            .unwrap_err();
        assert_eq!(err.abort_code(), 0x0609_0030);
        assert_eq!(time.check_download(key, &[0; 2]), Ok(()));
        assert_eq!(time.check_download(ObjectKey::new(0x1013, 0), &[0xFF; 4]), Ok(()));
        od.set_value(key, &0x4000_0701u32.to_le_bytes()).unwrap();
        time.load_od(&od);
        assert_eq!(time.cob_id(), 0x4000_0100, "faulty CAN-ID not taken");
    }

    proptest::proptest! {
        #[test]
        fn no_frame_panics(frames in proptest::collection::vec(any_frame(), 0..50)) {
            let mut time = TimeService::new();
            time.set_cob_id(TIME_CONSUMER | TIME_PRODUCER | 0x100).unwrap();
            time.set_state(Instant::ZERO, Op);
            for (i, frame) in frames.iter().enumerate() {
                let now = ms(i as u64 * 7);
                time.handle_frame(now, frame);
                let _ = time.produce(now, NOON);
                while time.poll_transmit().is_some() {}
                while time.poll_event().is_some() {}
            }
        }
    }
}

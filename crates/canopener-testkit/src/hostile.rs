//! Hostile devices: cores that answer a tester with frames no correct CANopen device sends, so that
//! a tester (the conformance runner, the model-based executor, the network monitor) can be shown
//! never to panic, hang or give up, whatever a device sends.
//!
//! - [`Hostile`] wraps any device core (a simulated device, say) and spoils what it sends as its
//!   [`Behaviour`] says: answers with no data, cut short, random, an echo of the request, on another
//!   node's CAN-ID, babbling with SDO toggles out of order, or buried in a flood of random frames.
//!   [`Behaviour::Scripted`] lets a fuzzer's bytes choose every answer.
//! - [`JunkNode`] is a second node beside a correct device: it answers a share of the requests
//!   addressed to that device first, with junk on the device's answer CAN-ID (a tester cannot tell
//!   who sent a frame); [`Station`] puts both on one bus.
//! - [`Entropy`] is where the hostile choices come from: a seeded generator (a run is reproducible
//!   from its seed), or a byte script (a fuzzer's input; when it runs out, a scripted device falls
//!   silent, so every run ends).
//!
//! Every behaviour is bounded: noise comes on a timer of at least [`FLOOD_PERIOD`], and an answer is
//! repeated at most three times, so a run on virtual time always advances.

use std::collections::VecDeque;
use std::convert::Infallible;
use std::time::Duration;

use canopener_can::{CanFrame, CanId, Core, Instant, StandardId};

/// How often a flooding device sends a random frame: about a fully loaded bus at 125 kbit/s.
pub const FLOOD_PERIOD: Duration = Duration::from_millis(1);

/// How often a babbling device speaks unasked.
pub const BABBLE_PERIOD: Duration = Duration::from_millis(10);

/// Where a hostile device's choices come from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Entropy {
    /// splitmix64 from a seed: never runs out.
    Seeded(u64),
    /// A fuzzer's bytes, taken in order; `None` once they are used up.
    Script {
        /// The bytes.
        bytes: Vec<u8>,
        /// How many are used.
        at: usize,
    },
}

impl Entropy {
    /// A generator started from `seed`.
    pub fn seeded(seed: u64) -> Entropy {
        Entropy::Seeded(seed)
    }

    /// The bytes of a script.
    pub fn script(bytes: impl Into<Vec<u8>>) -> Entropy {
        Entropy::Script {
            bytes: bytes.into(),
            at: 0,
        }
    }

    /// The next byte; `None` when a script ran out.
    pub fn byte(&mut self) -> Option<u8> {
        match self {
            Entropy::Seeded(state) => Some(splitmix64(state).to_le_bytes()[0]),
            Entropy::Script { bytes, at } => {
                let byte = bytes.get(*at).copied();
                *at = (*at).saturating_add(1);
                byte
            }
        }
    }

    /// A number below `bound` (0 when `bound` is 0); `None` when a script ran out. A script spends
    /// one byte (its value modulo `bound`: the fuzzer picks), the generator a whole draw (no bias).
    pub fn below(&mut self, bound: u8) -> Option<u8> {
        let draw = match self {
            Entropy::Seeded(state) => splitmix64(state),
            Entropy::Script { .. } => u64::from(self.byte()?),
        };
        let value = draw.checked_rem(u64::from(bound)).unwrap_or(0);
        Some(u8::try_from(value).unwrap_or(0))
    }

    /// `true` in `percent` of the calls; `None` when a script ran out.
    pub fn chance(&mut self, percent: u8) -> Option<bool> {
        Some(self.below(100)? < percent)
    }

    /// `len` bytes (fewer when a script runs out).
    pub fn bytes(&mut self, len: usize) -> Vec<u8> {
        std::iter::from_fn(|| self.byte()).take(len).collect()
    }

    /// An 11-bit CAN-ID; `None` when a script ran out.
    pub fn id(&mut self) -> Option<StandardId> {
        let raw = u16::from_le_bytes([self.byte()?, self.byte()?]) & 0x7FF;
        StandardId::new(raw)
    }

    /// Whether a script ran out (a seeded generator never does).
    pub fn exhausted(&self) -> bool {
        match self {
            Entropy::Seeded(_) => false,
            Entropy::Script { bytes, at } => *at >= bytes.len(),
        }
    }
}

/// splitmix64: a tiny, well-known generator; enough for reproducible junk.
fn splitmix64(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// How a [`Hostile`] device spoils what its core sends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Behaviour {
    /// Every answer on its CAN-ID with no data (DLC 0).
    Empty,
    /// Every answer cut to fewer bytes than it has.
    Short,
    /// Every answer replaced by 0–8 random bytes on its CAN-ID.
    Random,
    /// Every answer replaced by the data of the last frame the device received (the request), on
    /// the answer's CAN-ID.
    Echo,
    /// Every answer on the same service's CAN-ID of the next node-ID (585h becomes 586h, 705h 706h).
    OtherNode,
    /// Every answer sent one to three times, SDO segment answers with the toggle bit inverted, and
    /// unasked SDO segments with random toggles every [`BABBLE_PERIOD`].
    Babble,
    /// Answers unchanged, but a random frame every [`FLOOD_PERIOD`], half of them on the device's
    /// own CAN-IDs (EMCY, PDOs, SDO answer, heartbeat), half on any CAN-ID.
    Flood,
    /// Each answer as the next script byte says (pass, drop, empty, short, random, echo, other node,
    /// an extra frame, a repeat with the toggle inverted); silent once the script runs out. Meant for
    /// [`Entropy::Script`].
    Scripted,
}

impl Behaviour {
    /// Every behaviour, for tests that try them all.
    pub const ALL: [Behaviour; 8] = [
        Behaviour::Empty,
        Behaviour::Short,
        Behaviour::Random,
        Behaviour::Echo,
        Behaviour::OtherNode,
        Behaviour::Babble,
        Behaviour::Flood,
        Behaviour::Scripted,
    ];

    /// The behaviour's name in test output (`other-node`).
    pub fn name(self) -> &'static str {
        match self {
            Behaviour::Empty => "empty",
            Behaviour::Short => "short",
            Behaviour::Random => "random",
            Behaviour::Echo => "echo",
            Behaviour::OtherNode => "other-node",
            Behaviour::Babble => "babble",
            Behaviour::Flood => "flood",
            Behaviour::Scripted => "scripted",
        }
    }

    fn noise_period(self) -> Option<Duration> {
        match self {
            Behaviour::Babble => Some(BABBLE_PERIOD),
            Behaviour::Flood => Some(FLOOD_PERIOD),
            _ => None,
        }
    }
}

/// A device core whose frames are spoiled (see the [module docs](self)).
#[derive(Debug)]
pub struct Hostile<C> {
    inner: C,
    node: u8,
    behaviour: Behaviour,
    percent: u8,
    entropy: Entropy,
    last_request: Option<CanFrame>,
    outbox: VecDeque<CanFrame>,
    next_noise: Option<Instant>,
    spoiled: usize,
    now: Instant,
    starved: Option<Instant>,
}

impl<C: Core> Hostile<C> {
    /// `inner`, the device with node-ID `node`, spoiling every frame it sends as `behaviour` says.
    pub fn new(inner: C, node: u8, behaviour: Behaviour, entropy: Entropy) -> Hostile<C> {
        Hostile {
            inner,
            node,
            behaviour,
            percent: 100,
            entropy,
            last_request: None,
            outbox: VecDeque::new(),
            next_noise: behaviour.noise_period().map(|period| Instant::ZERO + period),
            spoiled: 0,
            now: Instant::ZERO,
            starved: None,
        }
    }

    /// Spoils only `percent` of the frames (chosen by the entropy); the others go out as the core
    /// sent them. Noise ([`Behaviour::Babble`], [`Behaviour::Flood`]) is not affected.
    pub fn percent(mut self, percent: u8) -> Hostile<C> {
        self.percent = percent.min(100);
        self
    }

    /// The wrapped core.
    pub fn inner(&self) -> &C {
        &self.inner
    }

    /// The wrapped core, mutably.
    pub fn inner_mut(&mut self) -> &mut C {
        &mut self.inner
    }

    /// How many frames were spoiled, dropped or added so far.
    pub fn spoiled(&self) -> usize {
        self.spoiled
    }

    /// Where the choices come from (whether a script ran out).
    pub fn entropy(&self) -> &Entropy {
        &self.entropy
    }

    /// When the first frame was dropped because the script had run out (the device fell silent
    /// from then on).
    pub fn starved_since(&self) -> Option<Instant> {
        self.starved
    }

    /// Takes what the core sends and spoils it into the outbox.
    fn pull(&mut self) {
        while let Some(frame) = self.inner.poll_transmit() {
            self.spoil(frame);
        }
    }

    fn spoil(&mut self, frame: CanFrame) {
        if frame.is_remote() && self.behaviour != Behaviour::Scripted {
            self.outbox.push_back(frame);
            return;
        }
        let spoil = match self.behaviour {
            Behaviour::Scripted | Behaviour::Flood => true,
            _ => self.entropy.chance(self.percent).unwrap_or(false),
        };
        if !spoil {
            self.outbox.push_back(frame);
            return;
        }
        let id = frame.id();
        match self.behaviour {
            Behaviour::Empty => self.push(id, &[]),
            Behaviour::Short => {
                let len = self.entropy.below(frame.data().len() as u8).unwrap_or(0);
                self.push(id, frame.data().get(..usize::from(len)).unwrap_or(&[]));
            }
            Behaviour::Random => self.push_random(id),
            Behaviour::Echo => self.push_echo(id),
            Behaviour::OtherNode => self.push(next_node(id), frame.data()),
            Behaviour::Babble => {
                let copies = 1 + self.entropy.below(3).unwrap_or(0);
                let babbled = invert_toggle(frame);
                for _ in 0..copies {
                    self.outbox.push_back(babbled);
                }
                self.spoiled += 1;
            }
            Behaviour::Flood => self.outbox.push_back(frame),
            Behaviour::Scripted => self.scripted(frame),
        }
    }

    /// One answer as the script says; nothing once it ran out.
    fn scripted(&mut self, frame: CanFrame) {
        let Some(op) = self.entropy.below(10) else {
            self.spoiled += 1;
            self.starved.get_or_insert(self.now);
            return;
        };
        let id = frame.id();
        match op {
            0 | 1 => self.outbox.push_back(frame),
            2 => self.spoiled += 1,
            3 => self.push(id, &[]),
            4 => {
                let len = self.entropy.below(frame.data().len() as u8).unwrap_or(0);
                self.push(id, frame.data().get(..usize::from(len)).unwrap_or(&[]));
            }
            5 => self.push_random(id),
            6 => self.push_echo(id),
            7 => self.push(next_node(id), frame.data()),
            8 => {
                self.outbox.push_back(frame);
                if let Some(extra) = self.entropy.id() {
                    self.push_random(CanId::Standard(extra));
                }
            }
            _ => {
                let babbled = invert_toggle(frame);
                self.outbox.push_back(babbled);
                self.outbox.push_back(babbled);
                self.spoiled += 1;
            }
        }
    }

    fn push(&mut self, id: CanId, data: &[u8]) {
        if let Ok(frame) = CanFrame::new(id, data.get(..data.len().min(8)).unwrap_or(&[])) {
            self.outbox.push_back(frame);
        }
        self.spoiled += 1;
    }

    fn push_random(&mut self, id: CanId) {
        let len = self.entropy.below(9).unwrap_or(0);
        let data = self.entropy.bytes(usize::from(len));
        self.push(id, &data);
    }

    fn push_echo(&mut self, id: CanId) {
        let data = self
            .last_request
            .filter(|request| !request.is_remote())
            .map(|request| request.data().to_vec())
            .unwrap_or_default();
        self.push(id, &data);
    }

    /// Unasked frames: babble on the SDO answer channel, or a flood frame.
    fn noise(&mut self) {
        let node = u16::from(self.node & 0x7F);
        match self.behaviour {
            Behaviour::Babble => {
                // An upload segment response (scs 0) with a random toggle and random data.
                let toggle = if self.entropy.chance(50).unwrap_or(false) {
                    0x10
                } else {
                    0
                };
                let mut data = self.entropy.bytes(8);
                if let Some(first) = data.first_mut() {
                    *first = (*first & 0x0F) | toggle;
                }
                self.push(standard(0x580 + node), &data);
            }
            Behaviour::Flood => {
                let own = [0x080, 0x180, 0x280, 0x380, 0x480, 0x580, 0x700];
                let id = if self.entropy.chance(50).unwrap_or(false) {
                    let pick = usize::from(self.entropy.below(own.len() as u8).unwrap_or(0));
                    standard(own.get(pick).copied().unwrap_or(0x700) + node)
                } else {
                    self.entropy.id().map_or(standard(0x7FF), CanId::Standard)
                };
                self.push_random(id);
            }
            _ => {}
        }
    }
}

impl<C: Core> Core for Hostile<C> {
    type Event = C::Event;

    fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
        self.now = now;
        self.last_request = Some(*frame);
        self.inner.handle_frame(now, frame);
        self.pull();
    }

    fn handle_timeout(&mut self, now: Instant) {
        self.now = now;
        if self.inner.poll_timeout().is_some_and(|due| due <= now) {
            self.inner.handle_timeout(now);
        }
        if let Some(due) = self.next_noise.filter(|due| *due <= now) {
            self.noise();
            let period = self.behaviour.noise_period().unwrap_or(FLOOD_PERIOD);
            self.next_noise = Some(due.max(now) + period);
        }
        self.pull();
    }

    fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.pull();
        self.outbox.pop_front()
    }

    fn poll_event(&mut self) -> Option<C::Event> {
        self.inner.poll_event()
    }

    fn poll_timeout(&self) -> Option<Instant> {
        [self.inner.poll_timeout(), self.next_noise]
            .into_iter()
            .flatten()
            .min()
    }
}

/// A second node that answers `percent` of the requests addressed to node `node` first, with junk
/// on the answer's CAN-ID: no data, a few random bytes, 0–8 random bytes, or the request echoed.
/// Requests are SDO requests (600h + node-ID, answered on 580h + node-ID), remote frames (answered
/// on their CAN-ID) and LSS requests (7E5h, answered on 7E4h).
#[derive(Debug)]
pub struct JunkNode {
    node: u8,
    percent: u8,
    entropy: Entropy,
    outbox: VecDeque<CanFrame>,
    sent: Vec<(Instant, CanFrame)>,
}

impl JunkNode {
    /// Answers `percent` of the requests to `node` with junk chosen by `entropy`.
    pub fn new(node: u8, percent: u8, entropy: Entropy) -> JunkNode {
        JunkNode {
            node,
            percent: percent.min(100),
            entropy,
            outbox: VecDeque::new(),
            sent: Vec::new(),
        }
    }

    /// How many requests it answered with junk.
    pub fn answered(&self) -> usize {
        self.sent.len()
    }

    /// The junk it sent, with when the request came.
    pub fn sent(&self) -> &[(Instant, CanFrame)] {
        &self.sent
    }

    /// The CAN-ID the answer to `frame` comes on, if `frame` is a request to the device.
    fn answer_id(&self, frame: &CanFrame) -> Option<u16> {
        let CanId::Standard(id) = frame.id() else {
            return None;
        };
        let raw = id.as_raw();
        let node = u16::from(self.node);
        if frame.is_remote() {
            Some(raw)
        } else if raw == 0x600 + node {
            Some(0x580 + node)
        } else if raw == 0x7E5 {
            Some(0x7E4)
        } else {
            None
        }
    }
}

impl Core for JunkNode {
    type Event = Infallible;

    fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
        let Some(answer) = self.answer_id(frame) else {
            return;
        };
        if !self.entropy.chance(self.percent).unwrap_or(false) {
            return;
        }
        let data = match self.entropy.below(4).unwrap_or(0) {
            0 => Vec::new(),
            1 => {
                let len = 1 + self.entropy.below(7).unwrap_or(0);
                self.entropy.bytes(usize::from(len))
            }
            2 => {
                let len = self.entropy.below(9).unwrap_or(0);
                self.entropy.bytes(usize::from(len))
            }
            _ if frame.is_remote() => Vec::new(),
            _ => frame.data().to_vec(),
        };
        if let Ok(junk) = CanFrame::new(standard(answer), &data) {
            self.outbox.push_back(junk);
            self.sent.push((now, junk));
        }
    }

    fn handle_timeout(&mut self, _now: Instant) {}

    fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.outbox.pop_front()
    }

    fn poll_event(&mut self) -> Option<Infallible> {
        None
    }

    fn poll_timeout(&self) -> Option<Instant> {
        None
    }
}

/// A device and a [`JunkNode`] as one core type, for one bus. Attach the junk node first: at one
/// instant its frames then go out before the device's, as a faster node's would.
#[derive(Debug)]
pub enum Station<C> {
    /// The device.
    Device(C),
    /// The junk node.
    Junk(JunkNode),
}

impl<C: Core> Core for Station<C> {
    type Event = C::Event;

    fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
        match self {
            Station::Device(core) => core.handle_frame(now, frame),
            Station::Junk(core) => core.handle_frame(now, frame),
        }
    }

    fn handle_timeout(&mut self, now: Instant) {
        match self {
            Station::Device(core) => core.handle_timeout(now),
            Station::Junk(core) => core.handle_timeout(now),
        }
    }

    fn poll_transmit(&mut self) -> Option<CanFrame> {
        match self {
            Station::Device(core) => core.poll_transmit(),
            Station::Junk(core) => core.poll_transmit(),
        }
    }

    fn poll_event(&mut self) -> Option<C::Event> {
        match self {
            Station::Device(core) => core.poll_event(),
            Station::Junk(_) => None,
        }
    }

    fn poll_timeout(&self) -> Option<Instant> {
        match self {
            Station::Device(core) => core.poll_timeout(),
            Station::Junk(core) => core.poll_timeout(),
        }
    }
}

fn standard(raw: u16) -> CanId {
    CanId::Standard(StandardId::new(raw & 0x7FF).unwrap_or(StandardId::ZERO))
}

/// The same service's CAN-ID of the next node-ID (node 127 wraps to 1).
fn next_node(id: CanId) -> CanId {
    match id {
        CanId::Standard(id) => {
            let raw = id.as_raw();
            let node = raw & 0x7F;
            standard((raw & 0x780) | (node % 127 + 1))
        }
        extended => extended,
    }
}

/// An SDO segment answer (upload segment, scs 0; download segment confirmation, scs 1) on an SDO
/// answer CAN-ID (581h–5FFh) with its toggle bit inverted; other frames unchanged.
fn invert_toggle(frame: CanFrame) -> CanFrame {
    let is_sdo_answer = matches!(frame.id(), CanId::Standard(id) if (0x581..=0x5FF).contains(&id.as_raw()));
    let mut data = frame.data().to_vec();
    match data.first_mut() {
        Some(first) if is_sdo_answer && *first >> 5 <= 1 => *first ^= 0x10,
        _ => return frame,
    }
    CanFrame::new(frame.id(), &data).unwrap_or(frame)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::frame;

    /// Answers every SDO request to node 5 with an upload segment (toggle clear) and beats every 100 ms.
    #[derive(Debug, Default)]
    struct Device {
        out: VecDeque<CanFrame>,
        beat: Option<Instant>,
    }

    impl Core for Device {
        type Event = ();
        fn handle_frame(&mut self, _: Instant, f: &CanFrame) {
            if f.id() == frame("605#").id() {
                self.out.push_back(frame("585#0001020304050607"));
            }
        }
        fn handle_timeout(&mut self, now: Instant) {
            self.out.push_back(frame("705#05"));
            self.beat = Some(now + Duration::from_millis(100));
        }
        fn poll_transmit(&mut self) -> Option<CanFrame> {
            self.out.pop_front()
        }
        fn poll_event(&mut self) -> Option<()> {
            None
        }
        fn poll_timeout(&self) -> Option<Instant> {
            self.beat.or(Some(Instant::ZERO))
        }
    }

    fn answers(behaviour: Behaviour, entropy: Entropy) -> Vec<CanFrame> {
        let mut hostile = Hostile::new(Device::default(), 5, behaviour, entropy);
        hostile.handle_frame(Instant::ZERO, &frame("605#4000100000000000"));
        std::iter::from_fn(|| hostile.poll_transmit()).collect()
    }

    #[test]
    fn each_behaviour_spoils_the_answer_as_documented() {
        let seed = || Entropy::seeded(7);
        assert_eq!(answers(Behaviour::Empty, seed()), [frame("585#")]);
        let short = answers(Behaviour::Short, seed());
        assert!(short.len() == 1 && short[0].data().len() < 8, "{short:?}");
        assert_eq!(answers(Behaviour::Echo, seed()), [frame("585#4000100000000000")]);
        assert_eq!(
            answers(Behaviour::OtherNode, seed()),
            [frame("586#0001020304050607")]
        );
        let babble = answers(Behaviour::Babble, seed());
        assert!(!babble.is_empty() && babble.len() <= 3, "{babble:?}");
        assert!(
            babble.iter().all(|f| *f == frame("585#1001020304050607")),
            "{babble:?}"
        );
        assert_eq!(answers(Behaviour::Flood, seed()), [frame("585#0001020304050607")]);
        assert_eq!(answers(Behaviour::Random, seed()).len(), 1);
    }

    #[test]
    fn a_script_chooses_each_answer_and_its_end_silences_the_device() {
        // 0: pass; 2: drop; 3: empty; then nothing left.
        let mut hostile = Hostile::new(
            Device::default(),
            5,
            Behaviour::Scripted,
            Entropy::script([0, 2, 3]),
        );
        let mut sent = Vec::new();
        for _ in 0..5 {
            hostile.handle_frame(Instant::ZERO, &frame("605#40"));
            sent.extend(std::iter::from_fn(|| hostile.poll_transmit()));
        }
        assert_eq!(sent, [frame("585#0001020304050607"), frame("585#")]);
        assert_eq!(hostile.spoiled(), 4);
    }

    #[test]
    fn a_percentage_spoils_about_that_share() {
        let mut hostile =
            Hostile::new(Device::default(), 5, Behaviour::Empty, Entropy::seeded(1)).percent(30);
        let mut empty = 0;
        for _ in 0..1000 {
            hostile.handle_frame(Instant::ZERO, &frame("605#40"));
            empty += std::iter::from_fn(|| hostile.poll_transmit())
                .filter(|f| f.data().is_empty())
                .count();
        }
        assert!((250..350).contains(&empty), "{empty}");
    }

    #[test]
    fn a_flood_sends_one_frame_per_period_besides_the_answers() {
        let mut hostile = Hostile::new(Device::default(), 5, Behaviour::Flood, Entropy::seeded(3));
        let mut frames = 0;
        let mut now = Instant::ZERO;
        let end = Instant::from_millis(100);
        while let Some(due) = hostile.poll_timeout().filter(|due| *due <= end) {
            now = now.max(due);
            hostile.handle_timeout(now);
            frames += std::iter::from_fn(|| hostile.poll_transmit()).count();
        }
        // 100 flood frames and the heartbeats at 0 and 100 ms.
        assert_eq!(frames, 102);
    }

    #[test]
    fn the_junk_node_answers_requests_to_its_device_only() {
        let mut junk = JunkNode::new(5, 100, Entropy::seeded(9));
        for request in [
            "605#4000100000000000",
            "705#R",
            "7E5#5E",
            "606#40",
            "185#01",
            "000#0105",
        ] {
            junk.handle_frame(Instant::ZERO, &frame(request));
        }
        let ids: Vec<u32> = std::iter::from_fn(|| junk.poll_transmit())
            .map(|f| f.id().as_raw())
            .collect();
        assert_eq!(ids, [0x585, 0x705, 0x7E4]);
        assert_eq!(junk.answered(), 3);
    }

    #[test]
    fn a_script_gives_bytes_until_it_runs_out() {
        let mut entropy = Entropy::script([7, 90]);
        assert_eq!(entropy.below(5), Some(2));
        assert_eq!(entropy.chance(60), Some(false));
        assert!(entropy.exhausted());
        assert_eq!(entropy.byte(), None);
        assert_eq!(next_node(frame("5FF#").id()), frame("581#").id());
    }
}

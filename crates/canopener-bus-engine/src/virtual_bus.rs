//! Sans-IO cores on one simulated bus, on virtual time: the single loop behind the runtime's virtual
//! bus and the test harness.
//!
//! A [`VirtualBus`] owns *nodes* (any [`Core`]: simulated devices, master cores) and *taps* (endpoints
//! without a core, whose received frames queue up for whoever drives the bus from outside, such as a
//! master session or a recorder). Every frame a station sends reaches every other station, as on a real
//! bus. Time only moves when the driver calls [`VirtualBus::run_until`]; it then jumps from deadline to
//! deadline, so a run is a pure function of its inputs.
//!
//! Three timings: [`Timing::Ideal`] delivers a frame at the instant it is sent (exact, readable traces
//! in protocol tests), [`Timing::Delayed`] a fixed time later (round trips that take time, without
//! arbitration), [`Timing::BitAccurate`] arbitrates and times every frame with [`BusEngine`] at a bit
//! rate (what a real wire would allow).
//!
//! Faults of the wiring are part of the model: a station can be [disconnected](VirtualBus::disconnect)
//! (an unplugged connector or a broken drop cable: it neither sends nor receives), and frames can be
//! [lost](VirtualBus::lose_when) by a predicate (recorded as lost, delivered to nobody). A cut cable
//! splits the bus into [segments](VirtualBus::set_segment): stations hear only the stations of their own
//! segment, so devices beyond a cut keep talking among themselves.

use std::collections::VecDeque;
use std::time::Duration;

use canopener_can::{Bitrate, CanFrame, Core, Instant};

use crate::{BusConfig, BusEngine, BusStats, Port, SubmitError};

/// How long frames take on the simulated bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Timing {
    /// No time at all: a frame reaches the other stations at the instant it is sent, in send order.
    Ideal,
    /// Every frame reaches the other stations this long after it was sent, in send order, with no
    /// arbitration.
    Delayed(Duration),
    /// Arbitration and exact frame durations at this bit rate ([`BusEngine`]).
    BitAccurate(Bitrate),
}

/// A station of a [`VirtualBus`]: a node or a tap, numbered in the order they were added.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct StationId(usize);

impl StationId {
    /// The position of the station in the order of attaching (0 for the first).
    pub fn index(self) -> usize {
        self.0
    }
}

/// A frame that went over the bus, as a recording shows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BusFrame {
    /// When the other stations had it.
    pub at: Instant,
    /// Who sent it.
    pub from: StationId,
    /// The frame.
    pub frame: CanFrame,
    /// Whether the bus lost it ([`VirtualBus::lose_when`]): nobody received it.
    pub lost: bool,
}

/// An event of a node, with when and where it happened.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NodeEvent<E> {
    /// When the node reported it.
    pub at: Instant,
    /// The node.
    pub node: StationId,
    /// What it reported.
    pub event: E,
}

/// Why a frame could not be sent from a tap.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SendError {
    /// The station is a node (nodes send through their core) or does not exist.
    #[error("station {0:?} is not a tap of this bus")]
    NotATap(StationId),
    /// The bus engine refused the frame.
    #[error(transparent)]
    Submit(#[from] SubmitError),
}

/// Sans-IO cores and taps on one simulated bus, on virtual time (see the [module docs](self)).
pub struct VirtualBus<N: Core> {
    timing: Timing,
    engine: Option<BusEngine>,
    now: Instant,
    stations: Vec<Station<N>>,
    /// Frames sent on an ideal or delayed bus and not yet delivered: when they arrive, in send order.
    in_flight: VecDeque<(Instant, StationId, CanFrame)>,
    delay: Duration,
    events: VecDeque<NodeEvent<N::Event>>,
    recording: Option<Vec<BusFrame>>,
    ideal_frames: u64,
    lose: Option<LossFilter>,
}

/// Decides which frames the bus loses.
type LossFilter = Box<dyn FnMut(&BusFrame) -> bool + Send>;

impl<N: Core + std::fmt::Debug> std::fmt::Debug for VirtualBus<N> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("VirtualBus")
            .field("timing", &self.timing)
            .field("now", &self.now)
            .field("stations", &self.stations)
            .field("events", &self.events.len())
            .finish_non_exhaustive()
    }
}

#[derive(Debug)]
struct Station<N> {
    kind: StationKind<N>,
    port: Option<Port>,
    connected: bool,
    segment: u32,
}

#[derive(Debug)]
enum StationKind<N> {
    Node(N),
    Tap(VecDeque<(Instant, CanFrame)>),
}

impl<N: Core> VirtualBus<N> {
    /// Frames delivered at one instant without bit timing before the rest waits for the next call of
    /// [`VirtualBus::run_until`]: a guard against two cores answering each other forever, which no correct
    /// core does, but a virtual bus must not hang its driver.
    pub const MAX_FRAMES_PER_INSTANT: usize = 100_000;

    /// An empty bus at virtual time zero.
    pub fn new(timing: Timing) -> VirtualBus<N> {
        let (engine, delay) = match timing {
            Timing::Ideal => (None, Duration::ZERO),
            Timing::Delayed(delay) => (None, delay),
            Timing::BitAccurate(bitrate) => (Some(BusEngine::new(BusConfig { bitrate })), Duration::ZERO),
        };
        VirtualBus {
            timing,
            engine,
            now: Instant::ZERO,
            stations: Vec::new(),
            in_flight: VecDeque::new(),
            delay,
            events: VecDeque::new(),
            recording: None,
            ideal_frames: 0,
            lose: None,
        }
    }

    /// Loses every frame `lose` says yes to from now on: it is recorded with `lost` set and nobody
    /// receives it (a disturbed bus, a frame the sender's controller never got out).
    pub fn lose_when(&mut self, lose: impl FnMut(&BusFrame) -> bool + Send + 'static) {
        self.lose = Some(Box::new(lose));
    }

    /// Unplugs a station: until [`VirtualBus::reconnect`] it neither sends (its frames are dropped before
    /// the bus) nor receives. A node keeps running its timers meanwhile, as a powered device behind a
    /// broken cable does.
    pub fn disconnect(&mut self, station: StationId) {
        if let Some(station) = self.stations.get_mut(station.0) {
            station.connected = false;
        }
    }

    /// Plugs a station back in.
    pub fn reconnect(&mut self, station: StationId) {
        if let Some(station) = self.stations.get_mut(station.0) {
            station.connected = true;
        }
    }

    /// Puts a station on segment `segment` of the wire (all start on segment 0): a frame reaches only the
    /// stations of its sender's segment, as on a bus cut into pieces. With [`Timing::BitAccurate`] the
    /// pieces still share one arbitration, an approximation: a frame on one piece delays the others.
    pub fn set_segment(&mut self, station: StationId, segment: u32) {
        if let Some(station) = self.stations.get_mut(station.0) {
            station.segment = segment;
        }
    }

    /// The segment a station is on ([`VirtualBus::set_segment`]).
    pub fn segment(&self, station: StationId) -> Option<u32> {
        self.stations.get(station.0).map(|station| station.segment)
    }

    /// Whether a station is plugged in.
    pub fn is_connected(&self, station: StationId) -> bool {
        self.stations
            .get(station.0)
            .is_some_and(|station| station.connected)
    }

    /// The timing the bus was made with.
    pub fn timing(&self) -> Timing {
        self.timing
    }

    /// The virtual time.
    pub fn now(&self) -> Instant {
        self.now
    }

    /// Adds a core to the bus.
    pub fn attach(&mut self, node: N) -> StationId {
        self.add(StationKind::Node(node))
    }

    /// Adds an endpoint without a core: frames other stations send queue up for
    /// [`VirtualBus::take_received`], and [`VirtualBus::send`] puts frames on the bus from it.
    pub fn tap(&mut self) -> StationId {
        self.add(StationKind::Tap(VecDeque::new()))
    }

    /// Keeps every frame that goes over the bus from now on, for [`VirtualBus::take_recording`].
    pub fn record(&mut self) {
        self.recording.get_or_insert_with(Vec::new);
    }

    /// The frames that went over the bus since recording started or was last taken.
    pub fn take_recording(&mut self) -> Vec<BusFrame> {
        self.recording.as_mut().map(std::mem::take).unwrap_or_default()
    }

    /// The node at `id`, if `id` is a node.
    pub fn node(&self, id: StationId) -> Option<&N> {
        match &self.stations.get(id.0)?.kind {
            StationKind::Node(node) => Some(node),
            StationKind::Tap(_) => None,
        }
    }

    /// The node at `id`, mutably. A core changed from outside may have frames to send or a new deadline:
    /// the next [`VirtualBus::run_until`] collects them.
    pub fn node_mut(&mut self, id: StationId) -> Option<&mut N> {
        match &mut self.stations.get_mut(id.0)?.kind {
            StationKind::Node(node) => Some(node),
            StationKind::Tap(_) => None,
        }
    }

    /// Every node with its id, in attach order.
    pub fn nodes(&self) -> impl Iterator<Item = (StationId, &N)> + '_ {
        self.stations
            .iter()
            .enumerate()
            .filter_map(|(index, station)| match &station.kind {
                StationKind::Node(node) => Some((StationId(index), node)),
                StationKind::Tap(_) => None,
            })
    }

    /// Every node mutably, in attach order.
    pub fn nodes_mut(&mut self) -> impl Iterator<Item = (StationId, &mut N)> + '_ {
        self.stations
            .iter_mut()
            .enumerate()
            .filter_map(|(index, station)| match &mut station.kind {
                StationKind::Node(node) => Some((StationId(index), node)),
                StationKind::Tap(_) => None,
            })
    }

    /// Puts `frame` on the bus from tap `tap` at the current virtual time, after the frames the nodes
    /// already have waiting (a core that was just attached or changed from outside sent those first).
    pub fn send(&mut self, tap: StationId, frame: CanFrame) -> Result<(), SendError> {
        let station = self.stations.get(tap.0).ok_or(SendError::NotATap(tap))?;
        if !matches!(station.kind, StationKind::Tap(_)) {
            return Err(SendError::NotATap(tap));
        }
        self.collect()?;
        self.put_on_bus(tap, frame)?;
        Ok(())
    }

    /// The next frame tap `tap` received, with when it had it.
    pub fn take_received(&mut self, tap: StationId) -> Option<(Instant, CanFrame)> {
        match &mut self.stations.get_mut(tap.0)?.kind {
            StationKind::Tap(inbox) => inbox.pop_front(),
            StationKind::Node(_) => None,
        }
    }

    /// Whether tap `tap` has received frames not yet taken.
    pub fn has_received(&self, tap: StationId) -> bool {
        matches!(
            self.stations.get(tap.0).map(|station| &station.kind),
            Some(StationKind::Tap(inbox)) if !inbox.is_empty()
        )
    }

    /// The next event a node reported.
    pub fn poll_event(&mut self) -> Option<NodeEvent<N::Event>> {
        self.events.pop_front()
    }

    /// When something next happens on its own: a node's timer or the end of a frame on the wire.
    pub fn poll_timeout(&self) -> Option<Instant> {
        let nodes = self.stations.iter().filter_map(|station| match &station.kind {
            StationKind::Node(node) => node.poll_timeout(),
            StationKind::Tap(_) => None,
        });
        let engine = self.engine.as_ref().and_then(BusEngine::poll_timeout);
        let in_flight = self.in_flight.front().map(|(at, ..)| *at);
        nodes.chain(engine).chain(in_flight).min()
    }

    /// Whether a frame is on its way: sent but not yet received by the other stations.
    pub fn frames_in_flight(&self) -> bool {
        !self.in_flight.is_empty()
            || self
                .engine
                .as_ref()
                .is_some_and(|engine| engine.poll_timeout().is_some())
    }

    /// Runs the bus up to and including `until`: every frame sent, every timer and every frame
    /// end due by then, in time order. With `stop_at` a tap, it returns as soon as that tap has a frame
    /// to take (the time is then that frame's arrival), so a driver can answer it. Returns whether it
    /// stopped for the tap. Time never runs backwards: an `until` in the past only settles what is due now.
    pub fn run_until(&mut self, until: Instant, stop_at: Option<StationId>) -> Result<bool, SubmitError> {
        let until = until.max(self.now);
        loop {
            self.exchange()?;
            if stop_at.is_some_and(|tap| self.has_received(tap)) {
                return Ok(true);
            }
            let Some(due) = self.poll_timeout().filter(|due| *due <= until) else {
                self.now = until;
                return Ok(false);
            };
            self.now = self.now.max(due);
            let now = self.now;
            // Frames that arrive at this instant first, then the timers: a timer that expires as the
            // awaited frame arrives sees the frame.
            if let Some(engine) = &mut self.engine {
                engine.handle_timeout(now);
            }
            self.exchange()?;
            for station in &mut self.stations {
                if let StationKind::Node(node) = &mut station.kind
                    && node.poll_timeout().is_some_and(|at| at <= now)
                {
                    node.handle_timeout(now);
                }
            }
        }
    }

    /// Runs everything due at the current instant (frames handed over from outside, timers at `now`).
    pub fn settle(&mut self) -> Result<(), SubmitError> {
        self.run_until(self.now, None).map(drop)
    }

    /// Totals of the frames that went over the bus (bit times and busy time only with
    /// [`Timing::BitAccurate`]).
    pub fn stats(&self) -> BusStats {
        match &self.engine {
            Some(engine) => engine.stats(),
            None => BusStats {
                frames: self.ideal_frames,
                ..BusStats::default()
            },
        }
    }

    fn add(&mut self, kind: StationKind<N>) -> StationId {
        let port = self.engine.as_mut().map(BusEngine::attach);
        self.stations.push(Station {
            kind,
            port,
            connected: true,
            segment: 0,
        });
        StationId(self.stations.len() - 1)
    }

    fn put_on_bus(&mut self, from: StationId, frame: CanFrame) -> Result<(), SubmitError> {
        let Some(station) = self.stations.get(from.0) else {
            return Ok(());
        };
        if !station.connected {
            return Ok(());
        }
        match (&mut self.engine, station.port) {
            (Some(engine), Some(port)) => engine.submit(self.now, port, frame),
            _ => {
                self.in_flight.push_back((self.now + self.delay, from, frame));
                Ok(())
            }
        }
    }

    /// Moves frames until nothing is left to move at the current instant: nodes' frames onto the bus,
    /// delivered frames to the stations, events out of the nodes.
    fn exchange(&mut self) -> Result<(), SubmitError> {
        for _ in 0..Self::MAX_FRAMES_PER_INSTANT {
            self.collect()?;
            let delivered = if self.engine.is_some() {
                let deliveries: Vec<_> = self
                    .engine
                    .as_mut()
                    .map(|engine| std::iter::from_fn(|| engine.poll_delivery()).collect())
                    .unwrap_or_default();
                for delivery in &deliveries {
                    let from = self
                        .stations
                        .iter()
                        .position(|station| station.port == Some(delivery.from))
                        .map(StationId);
                    if let Some(from) = from {
                        self.deliver(delivery.at, from, &delivery.frame);
                    }
                }
                !deliveries.is_empty()
            } else {
                let now = self.now;
                match self.in_flight.pop_front_if(|(at, ..)| *at <= now) {
                    Some((at, from, frame)) => {
                        self.ideal_frames += 1;
                        self.deliver(at, from, &frame);
                        true
                    }
                    None => false,
                }
            };
            if !delivered {
                return Ok(());
            }
        }
        Ok(())
    }

    /// Takes every node's pending frames (onto the bus) and events.
    fn collect(&mut self) -> Result<(), SubmitError> {
        let now = self.now;
        let mut outgoing = Vec::new();
        for (index, station) in self.stations.iter_mut().enumerate() {
            if let StationKind::Node(node) = &mut station.kind {
                while let Some(event) = node.poll_event() {
                    self.events.push_back(NodeEvent {
                        at: now,
                        node: StationId(index),
                        event,
                    });
                }
                while let Some(frame) = node.poll_transmit() {
                    outgoing.push((StationId(index), frame));
                }
            }
        }
        for (from, frame) in outgoing {
            self.put_on_bus(from, frame)?;
        }
        Ok(())
    }

    fn deliver(&mut self, at: Instant, from: StationId, frame: &CanFrame) {
        let mut seen = BusFrame {
            at,
            from,
            frame: *frame,
            lost: false,
        };
        seen.lost = self.lose.as_mut().is_some_and(|lose| lose(&seen));
        if let Some(recording) = &mut self.recording {
            recording.push(seen);
        }
        if seen.lost {
            return;
        }
        let segment = self.stations.get(from.0).map_or(0, |station| station.segment);
        for (index, station) in self.stations.iter_mut().enumerate() {
            if index == from.0 || !station.connected || station.segment != segment {
                continue;
            }
            match &mut station.kind {
                StationKind::Node(node) => node.handle_frame(at, frame),
                StationKind::Tap(inbox) => inbox.push_back((at, *frame)),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use canopener_can::StandardId;

    use super::*;

    /// Answers every frame on `listen` with `reply` after `delay`, and counts what it heard.
    #[derive(Debug)]
    struct Echo {
        listen: u16,
        reply: CanFrame,
        delay: Duration,
        due: Option<Instant>,
        out: Option<CanFrame>,
        heard: usize,
    }

    impl Echo {
        fn new(listen: u16, reply: u16, delay: Duration) -> Echo {
            Echo {
                listen,
                reply: frame(reply, &[1]),
                delay,
                due: None,
                out: None,
                heard: 0,
            }
        }
    }

    impl Core for Echo {
        type Event = u16;

        fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
            self.heard += 1;
            if frame.id().as_raw() == u32::from(self.listen) {
                self.due = Some(now + self.delay);
            }
        }

        fn handle_timeout(&mut self, now: Instant) {
            if self.due.is_some_and(|due| due <= now) {
                self.due = None;
                self.out = Some(self.reply);
            }
        }

        fn poll_transmit(&mut self) -> Option<CanFrame> {
            self.out.take()
        }

        fn poll_event(&mut self) -> Option<u16> {
            None
        }

        fn poll_timeout(&self) -> Option<Instant> {
            self.due
        }
    }

    fn frame(id: u16, data: &[u8]) -> CanFrame {
        CanFrame::new(StandardId::new(id).expect("11 bits"), data).expect("<= 8 bytes")
    }

    #[test]
    fn ideal_timing_answers_at_the_core_deadline_and_the_tap_hears_it() {
        let mut net = VirtualBus::new(Timing::Ideal);
        let echo = net.attach(Echo::new(0x601, 0x581, Duration::from_millis(3)));
        let tap = net.tap();
        net.record();
        net.send(tap, frame(0x601, &[0x40])).unwrap();
        assert!(net.run_until(Instant::from_millis(10), Some(tap)).unwrap());
        assert_eq!(net.now(), Instant::from_millis(3));
        let (at, reply) = net.take_received(tap).unwrap();
        assert_eq!((at, reply.id().as_raw()), (Instant::from_millis(3), 0x581));
        // Nothing else happens: the run goes to the end of the window.
        assert!(!net.run_until(Instant::from_millis(10), Some(tap)).unwrap());
        assert_eq!(net.now(), Instant::from_millis(10));
        let recorded: Vec<(u64, usize)> = net
            .take_recording()
            .iter()
            .map(|f| (f.at.as_micros(), f.from.index()))
            .collect();
        assert_eq!(recorded, [(0, tap.index()), (3000, echo.index())]);
        assert_eq!(net.node(echo).unwrap().heard, 1, "a sender does not hear itself");
    }

    #[test]
    fn bit_accurate_timing_delays_each_frame_by_its_length() {
        let mut net = VirtualBus::new(Timing::BitAccurate(Bitrate::K500));
        net.attach(Echo::new(0x601, 0x581, Duration::ZERO));
        let tap = net.tap();
        net.send(tap, frame(0x601, &[0x40, 0, 0, 0, 0, 0, 0, 0])).unwrap();
        assert!(net.run_until(Instant::from_millis(10), Some(tap)).unwrap());
        // Request and answer are each well over 100 bits at 2 µs a bit, back to back.
        let (at, _) = net.take_received(tap).unwrap();
        assert!(
            at > Instant::from_micros(300) && at < Instant::from_millis(1),
            "{at:?}"
        );
        assert_eq!(net.stats().frames, 2);
    }

    #[test]
    fn runs_are_deterministic_and_time_never_goes_back() {
        let run = || {
            let mut net = VirtualBus::new(Timing::BitAccurate(Bitrate::M1));
            let tap = net.tap();
            for node in 0..4u16 {
                net.attach(Echo::new(
                    0x100,
                    0x200 + node,
                    Duration::from_micros(u64::from(node) * 7),
                ));
            }
            net.record();
            net.send(tap, frame(0x100, &[])).unwrap();
            net.run_until(Instant::from_millis(5), None).unwrap();
            net.run_until(Instant::from_millis(1), None).unwrap();
            assert_eq!(net.now(), Instant::from_millis(5));
            net.take_recording()
        };
        let first = run();
        assert_eq!(first.len(), 5);
        assert_eq!(first, run());
    }

    #[test]
    fn nodes_cannot_be_sent_from_as_taps() {
        let mut net = VirtualBus::new(Timing::Ideal);
        let echo = net.attach(Echo::new(1, 2, Duration::ZERO));
        assert_eq!(net.send(echo, frame(1, &[])), Err(SendError::NotATap(echo)));
        assert_eq!(net.take_received(echo), None);
    }

    #[test]
    fn delayed_timing_takes_the_delay_each_way() {
        let mut net = VirtualBus::new(Timing::Delayed(Duration::from_millis(1)));
        net.attach(Echo::new(0x601, 0x581, Duration::from_millis(2)));
        let tap = net.tap();
        net.send(tap, frame(0x601, &[])).unwrap();
        assert!(net.run_until(Instant::from_millis(10), Some(tap)).unwrap());
        assert_eq!(
            net.take_received(tap).map(|(at, _)| at),
            Some(Instant::from_millis(4))
        );
    }

    #[test]
    fn an_unplugged_station_neither_sends_nor_receives_until_plugged_back() {
        let mut net = VirtualBus::new(Timing::Ideal);
        let echo = net.attach(Echo::new(0x601, 0x581, Duration::ZERO));
        let tap = net.tap();
        net.disconnect(echo);
        assert!(!net.is_connected(echo));
        net.send(tap, frame(0x601, &[])).unwrap();
        assert!(!net.run_until(Instant::from_millis(1), Some(tap)).unwrap());
        assert_eq!(net.node(echo).unwrap().heard, 0);
        net.reconnect(echo);
        net.send(tap, frame(0x601, &[])).unwrap();
        assert!(net.run_until(Instant::from_millis(2), Some(tap)).unwrap());
        assert_eq!(net.node(echo).unwrap().heard, 1);
    }

    #[test]
    fn stations_on_other_segments_do_not_hear_each_other_but_their_own_segment_does() {
        let mut net = VirtualBus::new(Timing::Ideal);
        let near = net.attach(Echo::new(0x601, 0x581, Duration::ZERO));
        let far = net.attach(Echo::new(0x601, 0x582, Duration::ZERO));
        let tap = net.tap();
        let far_tap = net.tap();
        net.set_segment(far, 1);
        net.set_segment(far_tap, 1);
        assert_eq!(net.segment(far), Some(1));
        net.send(tap, frame(0x601, &[])).unwrap();
        net.send(far_tap, frame(0x601, &[])).unwrap();
        net.run_until(Instant::from_millis(1), None).unwrap();
        assert_eq!(net.node(near).unwrap().heard, 1);
        assert_eq!(net.node(far).unwrap().heard, 1);
        let heard: Vec<u32> = std::iter::from_fn(|| net.take_received(tap))
            .map(|(_, f)| f.id().as_raw())
            .collect();
        assert_eq!(heard, [0x581]);
        assert_eq!(
            net.take_received(far_tap).map(|(_, f)| f.id().as_raw()),
            Some(0x582)
        );
    }

    #[test]
    fn lost_frames_are_recorded_and_reach_nobody() {
        let mut net = VirtualBus::new(Timing::Ideal);
        let echo = net.attach(Echo::new(0x601, 0x581, Duration::ZERO));
        let tap = net.tap();
        net.record();
        let mut count = 0;
        net.lose_when(move |_| {
            count += 1;
            count == 1
        });
        net.send(tap, frame(0x601, &[])).unwrap();
        net.send(tap, frame(0x601, &[])).unwrap();
        net.settle().unwrap();
        let lost: Vec<bool> = net.take_recording().iter().map(|f| f.lost).collect();
        assert_eq!(lost, [true, false, false]);
        assert_eq!(net.node(echo).unwrap().heard, 1);
    }
}

//! The bus engine: per-port transmit queues, arbitration when the bus is idle, and frame timing from
//! exact stuffed bit counts.
//!
//! Before changing this file read ISO 11898-1, clauses "Bus access method" / "Arbitration" (the bus is
//! free after the intermission, contenders start SOF together and the lowest arbitration field wins)
//! and "Interframe space" (3 intermission bits; a receiver has the frame at the end of EOF), and the
//! `canopener_can::bits` module doc for how frame lengths are counted.

use std::collections::{BTreeMap, VecDeque};
use std::fmt;
use std::time::Duration;

use canopener_can::bits::{INTERMISSION_BITS, frame_bits};
use canopener_can::{Bitrate, CanFrame, Instant};

/// How a bus is set up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BusConfig {
    /// The bit rate every frame on this bus is timed with.
    pub bitrate: Bitrate,
}

/// One node attached to a [`BusEngine`].
///
/// Ports are numbered in attach order and never reused, so a detached port stays unknown.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Port(u64);

/// A frame that went over the bus.
///
/// There is one `Delivery` per frame: every port except `from` receives `frame`, and `from` takes it
/// as confirmation that its frame was sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Delivery {
    /// The port that sent the frame.
    pub from: Port,
    /// The frame.
    pub frame: CanFrame,
    /// When its SOF bit started.
    pub start: Instant,
    /// When receivers have it: the end of its last EOF bit, 3 bit times before the bus is free.
    ///
    /// ISO 11898-1 ("Message validation") lets a receiver accept one bit earlier, after the last but
    /// one EOF bit; the engine uses the end of EOF for sender and receivers alike, so one instant
    /// serves as both reception and TX confirmation.
    pub at: Instant,
}

/// Totals over every frame delivered so far.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct BusStats {
    /// Frames delivered.
    pub frames: u64,
    /// Bus time those frames occupied, SOF through intermission.
    pub busy: Duration,
    /// Bits those frames occupied, stuff bits and intermission included.
    pub bits: u64,
}

/// Why [`BusEngine::submit`] refused a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SubmitError {
    /// The port was never attached to this bus or has been detached.
    #[error(
        "{0} is not attached to this bus; attach a port before submitting and stop using it after detach"
    )]
    UnknownPort(Port),
    /// The port already has as many frames waiting as its queue holds.
    #[error(
        "the transmit queue of {port} is full ({capacity} frames waiting); \
         drive the bus forward with handle_timeout so queued frames go out, then submit again"
    )]
    QueueFull {
        /// The port whose queue is full.
        port: Port,
        /// The queue bound.
        capacity: usize,
    },
}

/// A virtual classical CAN bus: arbitration by identifier and bit-exact timing, with no IO.
///
/// Each attached [`Port`] has a FIFO transmit queue. When the bus is idle the head frames of all ports
/// whose frames are ready contend; the smallest [`CanFrame::arbitration_key`] wins, exactly as the
/// dominant bits win on a wire. A frame lasts `frame_bits(frame).total` bit times; receivers have it
/// 3 bit times (the intermission) before the bus is free for the next SOF.
///
/// Drive it like any sans-IO engine: [`BusEngine::submit`] frames with the time they were handed over,
/// call [`BusEngine::handle_timeout`] at (or after) [`BusEngine::poll_timeout`], then drain
/// [`BusEngine::poll_delivery`] until it returns `None`. Deliveries pile up until drained.
///
/// The schedule depends only on the submit times, never on when `handle_timeout` is called: a driver
/// that oversleeps gets the same `start` and `at` instants, just later. All instants of a run of
/// back-to-back frames are computed from the bit count since the run began, so there is no rounding
/// drift even at bit rates that do not divide 10⁹ ns.
#[derive(Debug, Clone)]
pub struct BusEngine {
    bitrate: Bitrate,
    queue_capacity: usize,
    queues: BTreeMap<Port, VecDeque<Queued>>,
    next_port: u64,
    wire: Option<OnWire>,
    /// Start of the current run of back-to-back frames and the bits sent in it so far.
    train_start: Instant,
    train_bits: u64,
    /// The latest `now` of `handle_timeout`; earlier calls are ignored.
    handled_until: Instant,
    /// The latest time any call brought in; submit times are clamped to it so time never runs back.
    latest_input: Instant,
    deliveries: VecDeque<Delivery>,
    stats: BusStats,
    busy_nanos: u64,
}

impl BusEngine {
    /// Frames a port may have waiting before [`SubmitError::QueueFull`]. It holds a whole CiA 301
    /// SDO block (up to 127 segments) several times over, yet bounds a runaway sender to at most
    /// 140 ms of a saturated 1 Mbit/s bus (1024 DLC-8 frames of 111 to 135 bits) and a few tens of KiB.
    pub const DEFAULT_QUEUE_CAPACITY: usize = 1024;

    /// An idle bus with no ports and [`BusEngine::DEFAULT_QUEUE_CAPACITY`] frames per port queue.
    pub fn new(config: BusConfig) -> BusEngine {
        BusEngine::with_queue_capacity(config, BusEngine::DEFAULT_QUEUE_CAPACITY)
    }

    /// An idle bus whose port queues hold `capacity` frames each (0 refuses every frame).
    pub fn with_queue_capacity(config: BusConfig, capacity: usize) -> BusEngine {
        BusEngine {
            bitrate: config.bitrate,
            queue_capacity: capacity,
            queues: BTreeMap::new(),
            next_port: 0,
            wire: None,
            train_start: Instant::ZERO,
            train_bits: 0,
            handled_until: Instant::ZERO,
            latest_input: Instant::ZERO,
            deliveries: VecDeque::new(),
            stats: BusStats::default(),
            busy_nanos: 0,
        }
    }

    /// The bus bit rate.
    pub fn bitrate(&self) -> Bitrate {
        self.bitrate
    }

    /// Attaches a new node and returns its port.
    pub fn attach(&mut self) -> Port {
        let port = Port(self.next_port);
        // A u64 counter cannot run out: 2⁶⁴ attaches would take centuries at any real rate.
        self.next_port = self.next_port.saturating_add(1);
        self.queues.insert(port, VecDeque::new());
        port
    }

    /// Detaches a node and drops the frames it still had waiting. A frame of this port already on the
    /// wire completes and is delivered as usual. Unknown ports are ignored.
    ///
    /// Detach takes no time argument: it acts on the state as of the last call. A driver that is late
    /// calls [`BusEngine::handle_timeout`] first so frames that were due have left the queue.
    pub fn detach(&mut self, port: Port) {
        self.queues.remove(&port);
    }

    /// The attached ports in attach order.
    pub fn ports(&self) -> impl Iterator<Item = Port> + '_ {
        self.queues.keys().copied()
    }

    /// Whether `port` is attached.
    pub fn is_attached(&self, port: Port) -> bool {
        self.queues.contains_key(&port)
    }

    /// Queues `frame` for transmission from `port`, handed over at `now`.
    ///
    /// On an idle bus the frame starts at `now`, unless another frame handed over at the same `now`
    /// wins arbitration; on a busy bus it contends when the current frame's intermission ends. A `now`
    /// earlier than a time the engine has already seen is treated as that time.
    ///
    /// Everything due before `now` is settled first, exactly as [`BusEngine::handle_timeout`] would, so
    /// deliveries may be waiting afterwards: drain [`BusEngine::poll_delivery`] after submitting too.
    pub fn submit(&mut self, now: Instant, port: Port, frame: CanFrame) -> Result<(), SubmitError> {
        let ready = now.max(self.latest_input);
        self.latest_input = ready;
        // Everything due strictly before `ready` happens first: frames starting then cannot see this
        // one, and doing it now makes `pending` and `QueueFull` independent of driver lateness.
        // Nothing at `ready` itself is decided yet, so frames submitted at the same instant arbitrate.
        self.advance(ready, Bound::Exclusive);
        let capacity = self.queue_capacity;
        let queue = self.queues.get_mut(&port).ok_or(SubmitError::UnknownPort(port))?;
        if queue.len() >= capacity {
            return Err(SubmitError::QueueFull { port, capacity });
        }
        queue.push_back(Queued { frame, ready });
        Ok(())
    }

    /// Frames `port` has waiting, not counting one on the wire; 0 for an unknown port.
    pub fn pending(&self, port: Port) -> usize {
        self.queues.get(&port).map_or(0, VecDeque::len)
    }

    /// Processes everything due up to and including `now`: deliveries whose `at` has come and frames
    /// that start by then. A `now` earlier than that of a previous call is ignored.
    pub fn handle_timeout(&mut self, now: Instant) {
        if now < self.handled_until {
            return;
        }
        self.handled_until = now;
        self.latest_input = self.latest_input.max(now);
        self.advance(now, Bound::Inclusive);
    }

    /// When the engine next needs [`BusEngine::handle_timeout`]: the `at` of the frame on the wire, or
    /// when the next arbitration happens. `None` while nothing is on the wire or waiting. The instant
    /// may lie in the past for a late driver; call `handle_timeout` right away then.
    pub fn poll_timeout(&self) -> Option<Instant> {
        if let Some(wire) = &self.wire
            && !wire.delivered
        {
            return Some(wire.at);
        }
        self.next_arbitration()
    }

    /// The next frame that went over the bus, in bus order.
    pub fn poll_delivery(&mut self) -> Option<Delivery> {
        self.deliveries.pop_front()
    }

    /// Totals over every frame delivered so far.
    pub fn stats(&self) -> BusStats {
        BusStats {
            busy: Duration::from_nanos(self.busy_nanos),
            ..self.stats
        }
    }

    fn advance(&mut self, until: Instant, bound: Bound) {
        // Every pass delivers the frame on the wire or takes a frame from a queue, and stops otherwise,
        // so the loop runs at most twice per queued frame.
        loop {
            if let Some(wire) = &mut self.wire
                && !wire.delivered
            {
                if !bound.includes(wire.at, until) {
                    return;
                }
                wire.delivered = true;
                let delivery = Delivery {
                    from: wire.from,
                    frame: wire.frame,
                    start: wire.start,
                    at: wire.at,
                };
                self.stats.frames += 1;
                self.stats.bits += u64::from(wire.bits);
                self.busy_nanos = self
                    .busy_nanos
                    .saturating_add(nanos_between(wire.start, wire.free));
                self.deliveries.push_back(delivery);
                continue;
            }
            match self.next_arbitration() {
                Some(start) if bound.includes(start, until) => self.start_frame(start),
                _ => return,
            }
        }
    }

    /// When the bus is free for the next SOF.
    fn free_at(&self) -> Instant {
        self.wire.as_ref().map_or(Instant::ZERO, |wire| wire.free)
    }

    /// When the next arbitration happens: once the bus is free and some head frame is ready.
    fn next_arbitration(&self) -> Option<Instant> {
        let earliest_ready = self
            .queues
            .values()
            .filter_map(|queue| queue.front())
            .map(|q| q.ready)
            .min()?;
        Some(earliest_ready.max(self.free_at()))
    }

    /// Arbitration at `start`: among the head frames ready by then, the smallest arbitration key wins.
    ///
    /// Two ports sending the same arbitration field would both keep transmitting on a real bus: an
    /// identical frame merges into one, different data ends in a bit error and a retransmission. The
    /// engine does neither and lets the lower port go first; CANopen forbids two producers of one
    /// COB-ID, so only a misconfigured network can tell the difference.
    fn start_frame(&mut self, start: Instant) {
        let winner = self
            .queues
            .iter()
            .filter_map(|(port, queue)| queue.front().map(|head| (head, *port)))
            // Always true today: `submit` settles everything before a frame's instant before queueing
            // it, so no queued frame is newer than a pending arbitration. Kept so that a change there
            // cannot let a frame win an arbitration that happened before it existed.
            .filter(|(head, _)| head.ready <= start)
            .min_by_key(|(head, port)| (head.frame.arbitration_key(), *port))
            .map(|(_, port)| port);
        let Some(queued) = winner.and_then(|port| Some((port, self.queues.get_mut(&port)?.pop_front()?)))
        else {
            return;
        };
        let (from, Queued { frame, .. }) = queued;
        let bits = frame_bits(&frame).total;
        // A frame that starts the moment the previous one frees the bus continues the train, so its
        // instants come from one bit count; any gap starts a new train at `start`.
        if self.wire.as_ref().is_none_or(|wire| wire.free != start) {
            self.train_start = start;
            self.train_bits = 0;
        }
        // Every frame is at least 47 bits long, so subtracting the 3 intermission bits cannot wrap.
        let at = self.train_instant(self.train_bits + u64::from(bits - INTERMISSION_BITS));
        self.train_bits += u64::from(bits);
        let free = self.train_instant(self.train_bits);
        self.wire = Some(OnWire {
            from,
            frame,
            start,
            at,
            free,
            bits,
            delivered: false,
        });
    }

    fn train_instant(&self, bits: u64) -> Instant {
        Instant::from_nanos(
            self.train_start
                .as_nanos()
                .saturating_add(self.bitrate.bits_nanos(bits)),
        )
    }
}

/// `port 3`.
impl fmt::Display for Port {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "port {}", self.0)
    }
}

#[derive(Debug, Clone, Copy)]
struct Queued {
    frame: CanFrame,
    ready: Instant,
}

/// The frame on the wire, or the last one sent: its `free` is when the bus became idle.
#[derive(Debug, Clone, Copy)]
struct OnWire {
    from: Port,
    frame: CanFrame,
    start: Instant,
    at: Instant,
    free: Instant,
    bits: u32,
    delivered: bool,
}

#[derive(Debug, Clone, Copy)]
enum Bound {
    Inclusive,
    Exclusive,
}

impl Bound {
    fn includes(self, t: Instant, until: Instant) -> bool {
        match self {
            Bound::Inclusive => t <= until,
            Bound::Exclusive => t < until,
        }
    }
}

fn nanos_between(earlier: Instant, later: Instant) -> u64 {
    later.as_nanos().saturating_sub(earlier.as_nanos())
}

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_can::StandardId;

    fn frame(id: u16) -> CanFrame {
        CanFrame::new(StandardId::new(id).unwrap(), &[]).unwrap()
    }

    fn bus() -> BusEngine {
        BusEngine::new(BusConfig { bitrate: Bitrate::M1 })
    }

    #[test]
    fn unknown_and_detached_ports_are_refused() {
        let mut bus = bus();
        let port = bus.attach();
        bus.detach(port);
        assert_eq!(
            bus.submit(Instant::ZERO, port, frame(1)),
            Err(SubmitError::UnknownPort(port))
        );
        assert_eq!(bus.pending(port), 0);
        assert!(!bus.is_attached(port));
        let again = bus.attach();
        assert_ne!(again, port, "ports are never reused");
    }

    #[test]
    fn full_queue_refuses_and_recovers() {
        let mut bus = BusEngine::with_queue_capacity(BusConfig { bitrate: Bitrate::M1 }, 2);
        let port = bus.attach();
        bus.submit(Instant::ZERO, port, frame(1)).unwrap();
        bus.submit(Instant::ZERO, port, frame(2)).unwrap();
        let err = bus.submit(Instant::ZERO, port, frame(3)).unwrap_err();
        assert_eq!(err, SubmitError::QueueFull { port, capacity: 2 });
        assert!(
            err.to_string()
                .starts_with("the transmit queue of port 0 is full (2 frames waiting)")
        );
        // Once the first frame is on the wire a slot is free again.
        bus.handle_timeout(Instant::ZERO);
        assert_eq!(bus.pending(port), 1);
        bus.submit(Instant::ZERO, port, frame(3)).unwrap();
    }

    #[test]
    fn earlier_timeouts_are_ignored() {
        let mut bus = bus();
        let port = bus.attach();
        bus.submit(Instant::from_micros(10), port, frame(1)).unwrap();
        bus.handle_timeout(Instant::from_micros(10));
        let due = bus.poll_timeout().unwrap();
        bus.handle_timeout(Instant::from_micros(5));
        assert_eq!(bus.poll_timeout(), Some(due));
        assert_eq!(bus.poll_delivery(), None);
    }

    #[test]
    fn submit_in_the_past_is_clamped_to_the_latest_time_seen() {
        let mut bus = bus();
        let port = bus.attach();
        bus.handle_timeout(Instant::from_millis(1));
        bus.submit(Instant::ZERO, port, frame(1)).unwrap();
        assert_eq!(bus.poll_timeout(), Some(Instant::from_millis(1)));
        bus.handle_timeout(Instant::from_millis(1));
        let at = bus.poll_timeout().unwrap();
        bus.handle_timeout(at);
        assert_eq!(
            bus.poll_delivery().map(|d| d.start),
            Some(Instant::from_millis(1))
        );
    }

    #[test]
    fn idle_bus_needs_no_timeout() {
        let mut bus = bus();
        assert_eq!(bus.poll_timeout(), None);
        bus.attach();
        bus.handle_timeout(Instant::MAX);
        assert_eq!(bus.poll_timeout(), None);
        assert_eq!(bus.stats(), BusStats::default());
    }

    #[test]
    fn time_near_the_end_of_the_range_saturates_without_hanging() {
        let mut bus = bus();
        let port = bus.attach();
        let late = Instant::MAX - Duration::from_micros(10);
        bus.submit(late, port, frame(1)).unwrap();
        bus.submit(late, port, frame(2)).unwrap();
        bus.handle_timeout(Instant::MAX);
        assert_eq!(
            bus.poll_delivery().map(|d| (d.start, d.at)),
            Some((late, Instant::MAX))
        );
        assert_eq!(bus.poll_delivery().map(|d| d.at), Some(Instant::MAX));
        assert_eq!(bus.poll_timeout(), None);
    }
}

//! The `virtual:NAME[?bitrate=RATE]` backend: in-process buses shared by name.
//!
//! A process-global registry maps bus names to buses. Every [`VirtualBus::open`] of a name adds an
//! endpoint to the same bus; a frame sent by one endpoint reaches every other endpoint, never the
//! sender, and all endpoints see all frames in the same order. The bus (and, in bit-accurate mode,
//! its engine thread) disappears when its last endpoint is dropped.
//!
//! Queues are bounded and loss is never silent:
//! - each endpoint's receive queue holds [`VirtualOptions::queue_capacity`] frames;
//! - ideal mode: a sender that finds a receiver's queue full waits up to
//!   [`VirtualOptions::send_block`] for room. If there is still none, that receiver loses the frame
//!   and its next `recv` returns [`TransportError::Overrun`] with the number lost; until it has been
//!   told, further frames it has no room for are counted without blocking the sender again, so
//!   one stalled endpoint cannot slow the bus down for everybody;
//! - bit-accurate mode: the wire does not wait for slow receivers (a real CAN controller overruns
//!   too), so a frame for a full queue is counted as lost at once and reported the same way; the
//!   sender waits instead for room in its own transmit queue of [`VirtualOptions::tx_queue_len`]
//!   frames, at most [`VirtualOptions::send_timeout`].

use std::collections::{BTreeMap, HashMap, VecDeque};
use std::io;
use std::sync::{Arc, Condvar, LazyLock, Mutex, MutexGuard, PoisonError, Weak};
use std::thread::JoinHandle;
use std::time::Duration;

use canopener_bus_engine::{BusConfig, BusEngine, Port, SubmitError};
use canopener_can::{Bitrate, CanFrame};

use crate::clock::WallClock;
use crate::error::TransportError;
use crate::spec::{self, BusSpec, SpecError};
use crate::virtual_engine;
use crate::{CanBus, Received};

/// The engine's own per-port bound, above any useful [`VirtualOptions::tx_queue_len`]; each
/// endpoint enforces its own, smaller bound before submitting.
const MAX_TX_QUEUE_LEN: usize = 1 << 16;

/// Tuning of one virtual bus endpoint.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct VirtualOptions {
    /// Frames this endpoint's receive queue holds before frames for it are lost (at least 1).
    pub queue_capacity: usize,
    /// Ideal mode: how long a send waits for room in a full receive queue of another endpoint.
    pub send_block: Duration,
    /// Bit-accurate mode: frames this endpoint may have waiting for the wire (at least 1).
    pub tx_queue_len: usize,
    /// Bit-accurate mode: how long a send waits for room in this endpoint's transmit queue.
    pub send_timeout: Duration,
}

impl Default for VirtualOptions {
    /// 16 384 queued frames per receiver (about 2 s of a saturated 1 Mbit/s bus), a 100 ms send
    /// block, and a transmit queue of 64 frames (7 ms at 1 Mbit/s, 0.5 s at 125 kbit/s) with a 2 s
    /// send timeout.
    fn default() -> VirtualOptions {
        VirtualOptions {
            queue_capacity: 16_384,
            send_block: Duration::from_millis(100),
            tx_queue_len: 64,
            send_timeout: Duration::from_secs(2),
        }
    }
}

/// An endpoint on an in-process bus.
#[derive(Debug)]
pub struct VirtualBus {
    spec: BusSpec,
    endpoint: String,
    bus: Arc<SharedBus>,
    id: EndpointId,
    readable: Arc<Condvar>,
    options: VirtualOptions,
}

impl VirtualBus {
    /// Opens an endpoint on the bus `name`, creating the bus if this is its first endpoint.
    ///
    /// `bitrate: None` is the ideal bus (instant delivery); `Some` makes every frame take its
    /// exact wire time at that bit rate, with arbitration by identifier, in real time.
    pub fn open(name: &str, bitrate: Option<Bitrate>) -> Result<VirtualBus, TransportError> {
        VirtualBus::open_with(name, bitrate, VirtualOptions::default())
    }

    /// [`VirtualBus::open`] with explicit queue sizes and timeouts.
    pub fn open_with(
        name: &str,
        bitrate: Option<Bitrate>,
        options: VirtualOptions,
    ) -> Result<VirtualBus, TransportError> {
        let spec = BusSpec::Virtual {
            name: name.to_owned(),
            bitrate,
        };
        let endpoint = spec.to_string();
        spec::validate_bus_name(name).map_err(|problem| SpecError {
            spec: endpoint.clone(),
            problem,
        })?;
        let mut registry = lock(&REGISTRY);
        let bus = match registry.get(name).and_then(Weak::upgrade) {
            Some(bus) if bus.bitrate == bitrate => bus,
            Some(bus) => {
                return Err(TransportError::VirtualBusMismatch {
                    name: name.to_owned(),
                    existing: describe_mode(bus.bitrate),
                    requested: describe_mode(bitrate),
                });
            }
            None => {
                let bus = SharedBus::new(name, bitrate).map_err(|source| {
                    TransportError::io(
                        &endpoint,
                        "starting the bus thread",
                        "the process is out of threads or memory; close other buses",
                        source,
                    )
                })?;
                registry.insert(name.to_owned(), Arc::downgrade(&bus));
                bus
            }
        };
        let readable = Arc::new(Condvar::new());
        let mut state = bus.lock_state();
        let id = EndpointId(state.next_endpoint);
        state.next_endpoint += 1;
        let port = state.engine.as_mut().map(|engine| engine.sim.attach());
        state.inboxes.insert(
            id,
            Inbox {
                frames: VecDeque::new(),
                capacity: options.queue_capacity.max(1),
                lost: 0,
                readable: Arc::clone(&readable),
                port,
            },
        );
        drop(state);
        drop(registry);
        Ok(VirtualBus {
            spec,
            endpoint,
            bus,
            id,
            readable,
            options,
        })
    }

    /// How many endpoints the bus of this endpoint has, this one included.
    pub fn endpoint_count(&self) -> usize {
        self.bus.lock_state().inboxes.len()
    }

    fn send_ideal(&mut self, frame: &CanFrame) -> Result<(), TransportError> {
        let mut state = self.bus.lock_state();
        let deadline = std::time::Instant::now().checked_add(self.options.send_block);
        // Wait while some receiver that has not overrun yet has a full queue.
        while state
            .inboxes
            .iter()
            .any(|(&id, inbox)| id != self.id && inbox.lost == 0 && inbox.is_full())
        {
            let wait = deadline.map_or(Duration::MAX, |d| {
                d.saturating_duration_since(std::time::Instant::now())
            });
            if wait.is_zero() {
                break;
            }
            state.blocked_senders += 1;
            state = self
                .bus
                .writable
                .wait_timeout(state, wait)
                .unwrap_or_else(PoisonError::into_inner)
                .0;
            state.blocked_senders -= 1;
        }
        let received = Received {
            frame: *frame,
            timestamp: WallClock::now(),
        };
        deliver(&mut state.inboxes, Sender::Endpoint(self.id), received);
        Ok(())
    }

    fn send_timed(&mut self, frame: &CanFrame) -> Result<(), TransportError> {
        let started = std::time::Instant::now();
        let deadline = started.checked_add(self.options.send_timeout);
        let mut state = self.bus.lock_state();
        let port = state.inboxes.get(&self.id).and_then(|inbox| inbox.port);
        loop {
            let BusState {
                engine,
                blocked_senders,
                ..
            } = &mut *state;
            // Every bit-accurate bus has an engine and gave this endpoint a port in `open_with`.
            let (Some(engine), Some(port)) = (engine.as_mut(), port) else {
                return Err(self.engine_gone());
            };
            if engine.sim.pending(port) < self.options.tx_queue_len.max(1) {
                match engine.sim.submit(WallClock::now(), port, *frame) {
                    Ok(()) => {
                        self.bus.engine_wake.notify_one();
                        return Ok(());
                    }
                    Err(SubmitError::UnknownPort(_)) => return Err(self.engine_gone()),
                    Err(SubmitError::QueueFull { .. }) => {}
                }
            }
            let wait = deadline.map_or(Duration::MAX, |d| {
                d.saturating_duration_since(std::time::Instant::now())
            });
            if wait.is_zero() {
                return Err(TransportError::SendTimeout {
                    endpoint: self.endpoint.clone(),
                    waited: started.elapsed(),
                });
            }
            *blocked_senders += 1;
            state = self
                .bus
                .writable
                .wait_timeout(state, wait)
                .unwrap_or_else(PoisonError::into_inner)
                .0;
            state.blocked_senders -= 1;
        }
    }

    fn engine_gone(&self) -> TransportError {
        TransportError::Closed {
            endpoint: self.endpoint.clone(),
        }
    }
}

impl CanBus for VirtualBus {
    fn send(&mut self, frame: &CanFrame) -> Result<(), TransportError> {
        if self.bus.bitrate.is_some() {
            self.send_timed(frame)
        } else {
            self.send_ideal(frame)
        }
    }

    fn recv(&mut self, timeout: Duration) -> Result<Option<Received>, TransportError> {
        let deadline = std::time::Instant::now().checked_add(timeout);
        let mut state = self.bus.lock_state();
        loop {
            let BusState {
                inboxes,
                blocked_senders,
                ..
            } = &mut *state;
            let Some(inbox) = inboxes.get_mut(&self.id) else {
                return Err(self.engine_gone());
            };
            if inbox.lost > 0 {
                let lost = std::mem::take(&mut inbox.lost);
                return Err(TransportError::Overrun {
                    endpoint: self.endpoint.clone(),
                    lost,
                });
            }
            if let Some(received) = inbox.frames.pop_front() {
                if *blocked_senders > 0 {
                    self.bus.writable.notify_all();
                }
                return Ok(Some(received));
            }
            let wait = deadline.map_or(Duration::MAX, |d| {
                d.saturating_duration_since(std::time::Instant::now())
            });
            if wait.is_zero() {
                return Ok(None);
            }
            state = self
                .readable
                .wait_timeout(state, wait)
                .unwrap_or_else(PoisonError::into_inner)
                .0;
        }
    }

    fn spec(&self) -> &BusSpec {
        &self.spec
    }
}

impl Drop for VirtualBus {
    fn drop(&mut self) {
        // Lock order everywhere: registry, then bus state.
        let mut registry = lock(&REGISTRY);
        let mut state = self.bus.lock_state();
        if let Some(inbox) = state.inboxes.remove(&self.id)
            && let (Some(engine), Some(port)) = (state.engine.as_mut(), inbox.port)
        {
            engine.sim.detach(port);
        }
        // Senders waiting for room in this endpoint's queue can go on.
        self.bus.writable.notify_all();
        let last = state.inboxes.is_empty();
        if last {
            state.shutdown = true;
            self.bus.engine_wake.notify_all();
            if registry
                .get(&self.bus.name)
                .is_some_and(|entry| entry.ptr_eq(&Arc::downgrade(&self.bus)))
            {
                registry.remove(&self.bus.name);
            }
        }
        drop(state);
        drop(registry);
        if last {
            let engine_thread = lock(&self.bus.engine_thread).take();
            if let Some(thread) = engine_thread {
                // The engine exits as soon as it sees `shutdown`; it never panics, and if it did
                // there is nothing left to clean up.
                let _ = thread.join();
            }
        }
    }
}

/// Identifies an endpoint within its bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) struct EndpointId(u64);

/// Who put a frame on the bus.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Sender {
    Endpoint(EndpointId),
    Port(Port),
}

/// One bus: its endpoints' queues and, in bit-accurate mode, the engine.
#[derive(Debug)]
pub(crate) struct SharedBus {
    name: String,
    bitrate: Option<Bitrate>,
    state: Mutex<BusState>,
    /// Signalled when a receive queue or a transmit queue gets room.
    pub(crate) writable: Condvar,
    /// Signalled when the engine thread should look at the bus again.
    pub(crate) engine_wake: Condvar,
    engine_thread: Mutex<Option<JoinHandle<()>>>,
}

#[derive(Debug)]
pub(crate) struct BusState {
    /// Ordered by id so every delivery visits endpoints in the same order.
    pub(crate) inboxes: BTreeMap<EndpointId, Inbox>,
    next_endpoint: u64,
    pub(crate) blocked_senders: usize,
    pub(crate) engine: Option<Engine>,
    pub(crate) shutdown: bool,
}

/// The bit-accurate engine's state, guarded by the bus lock.
#[derive(Debug)]
pub(crate) struct Engine {
    pub(crate) sim: BusEngine,
}

#[derive(Debug)]
pub(crate) struct Inbox {
    frames: VecDeque<Received>,
    capacity: usize,
    lost: u64,
    readable: Arc<Condvar>,
    port: Option<Port>,
}

impl Inbox {
    fn is_full(&self) -> bool {
        self.frames.len() >= self.capacity
    }
}

impl SharedBus {
    fn new(name: &str, bitrate: Option<Bitrate>) -> io::Result<Arc<SharedBus>> {
        let engine = bitrate.map(|bitrate| Engine {
            sim: BusEngine::with_queue_capacity(BusConfig { bitrate }, MAX_TX_QUEUE_LEN),
        });
        let bus = Arc::new(SharedBus {
            name: name.to_owned(),
            bitrate,
            state: Mutex::new(BusState {
                inboxes: BTreeMap::new(),
                next_endpoint: 0,
                blocked_senders: 0,
                engine,
                shutdown: false,
            }),
            writable: Condvar::new(),
            engine_wake: Condvar::new(),
            engine_thread: Mutex::new(None),
        });
        if bitrate.is_some() {
            let thread = virtual_engine::spawn(Arc::clone(&bus))?;
            *lock(&bus.engine_thread) = Some(thread);
        }
        Ok(bus)
    }

    /// The bus state; a panic while it was held cannot leave it inconsistent (every update is a
    /// single push, pop or counter change), so a poisoned lock is used as is.
    pub(crate) fn lock_state(&self) -> MutexGuard<'_, BusState> {
        lock(&self.state)
    }

    pub(crate) fn name(&self) -> &str {
        &self.name
    }
}

/// Queues `received` for every endpoint except the sender, counting a loss where there is no room.
pub(crate) fn deliver(inboxes: &mut BTreeMap<EndpointId, Inbox>, from: Sender, received: Received) {
    for (&id, inbox) in inboxes {
        let is_sender = match from {
            Sender::Endpoint(sender) => id == sender,
            Sender::Port(port) => inbox.port == Some(port),
        };
        if is_sender {
            continue;
        }
        if inbox.is_full() {
            inbox.lost += 1;
        } else {
            inbox.frames.push_back(received);
        }
        inbox.readable.notify_one();
    }
}

static REGISTRY: LazyLock<Mutex<HashMap<String, Weak<SharedBus>>>> = LazyLock::new(Mutex::default);

fn lock<T>(mutex: &Mutex<T>) -> MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(PoisonError::into_inner)
}

fn describe_mode(bitrate: Option<Bitrate>) -> String {
    match bitrate {
        None => "ideal timing".to_owned(),
        Some(rate) => format!("bitrate {rate}"),
    }
}

/// Whether a bus named `name` exists in this process.
#[cfg(test)]
fn bus_exists(name: &str) -> bool {
    lock(&REGISTRY)
        .get(name)
        .is_some_and(|bus| bus.strong_count() > 0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_can::{CanId, StandardId};
    use std::thread;

    fn frame(id: u16, data: &[u8]) -> CanFrame {
        CanFrame::new(StandardId::new(id).unwrap(), data).unwrap()
    }

    fn recv_frame(bus: &mut VirtualBus) -> CanFrame {
        bus.recv(Duration::from_secs(5))
            .unwrap()
            .expect("a frame within 5 s")
            .frame
    }

    #[test]
    fn delivers_to_every_other_endpoint_never_the_sender() {
        let mut a = VirtualBus::open("t-fanout", None).unwrap();
        let mut b = VirtualBus::open("t-fanout", None).unwrap();
        let mut c = VirtualBus::open("t-fanout", None).unwrap();
        assert_eq!(a.endpoint_count(), 3);
        a.send(&frame(0x181, &[1])).unwrap();
        assert_eq!(recv_frame(&mut b), frame(0x181, &[1]));
        assert_eq!(recv_frame(&mut c), frame(0x181, &[1]));
        assert_eq!(a.recv(Duration::ZERO).unwrap(), None);
        assert_eq!(b.recv(Duration::ZERO).unwrap(), None);
    }

    #[test]
    fn endpoints_of_other_names_see_nothing() {
        let mut a = VirtualBus::open("t-iso-a", None).unwrap();
        let mut b = VirtualBus::open("t-iso-b", None).unwrap();
        let _a2 = VirtualBus::open("t-iso-a", None).unwrap();
        a.send(&frame(1, &[])).unwrap();
        assert_eq!(b.recv(Duration::from_millis(20)).unwrap(), None);
    }

    #[test]
    fn all_receivers_see_one_total_order() {
        let senders: Vec<_> = (0..3)
            .map(|_| VirtualBus::open("t-order", None).unwrap())
            .collect();
        let mut receivers: Vec<_> = (0..2)
            .map(|_| VirtualBus::open("t-order", None).unwrap())
            .collect();
        let threads: Vec<_> = senders
            .into_iter()
            .enumerate()
            .map(|(n, mut bus)| {
                thread::spawn(move || {
                    for seq in 0..500u16 {
                        bus.send(&frame(0x100 + n as u16, &seq.to_le_bytes())).unwrap();
                    }
                    bus
                })
            })
            .collect();
        let _senders: Vec<_> = threads.into_iter().map(|t| t.join().unwrap()).collect();
        let sequences: Vec<Vec<CanFrame>> = receivers
            .iter_mut()
            .map(|bus| (0..1500).map(|_| recv_frame(bus)).collect())
            .collect();
        assert_eq!(sequences[0], sequences[1]);
        for n in 0..3u16 {
            // Per sender, frames arrive in the order they were sent.
            let seqs: Vec<u16> = sequences[0]
                .iter()
                .filter(|f| f.id() == CanId::standard(0x100 + n).unwrap())
                .map(|f| u16::from_le_bytes([f.data()[0], f.data()[1]]))
                .collect();
            assert_eq!(seqs, (0..500).collect::<Vec<_>>());
        }
    }

    #[test]
    fn recv_blocks_until_a_frame_or_the_timeout() {
        let mut a = VirtualBus::open("t-block", None).unwrap();
        let mut b = VirtualBus::open("t-block", None).unwrap();
        let started = std::time::Instant::now();
        assert_eq!(b.recv(Duration::from_millis(50)).unwrap(), None);
        assert!(started.elapsed() >= Duration::from_millis(50));
        let sender = thread::spawn(move || {
            thread::sleep(Duration::from_millis(30));
            a.send(&frame(0x80, &[])).unwrap();
            a
        });
        let before = WallClock::now();
        let received = b.recv(Duration::from_secs(5)).unwrap().unwrap();
        assert_eq!(received.frame, frame(0x80, &[]));
        assert!(received.timestamp >= before && received.timestamp <= WallClock::now());
        sender.join().unwrap();
    }

    #[test]
    fn overrun_is_reported_to_the_receiver_not_silently_dropped() {
        let options = VirtualOptions {
            queue_capacity: 4,
            send_block: Duration::from_millis(20),
            ..Default::default()
        };
        let mut sender = VirtualBus::open_with("t-overrun", None, options).unwrap();
        let mut slow = VirtualBus::open_with("t-overrun", None, options).unwrap();
        let started = std::time::Instant::now();
        for n in 0..10u8 {
            sender.send(&frame(0x200, &[n])).unwrap();
        }
        // Only the first lost frame blocked the sender; the rest were counted without waiting.
        let took = started.elapsed();
        assert!(
            took >= Duration::from_millis(20) && took < Duration::from_millis(500),
            "{took:?}"
        );
        let err = slow.recv(Duration::ZERO).unwrap_err();
        assert!(matches!(err, TransportError::Overrun { lost: 6, .. }), "{err:?}");
        assert!(
            err.to_string().contains("virtual:t-overrun lost 6 frames"),
            "{err}"
        );
        for n in 0..4u8 {
            assert_eq!(recv_frame(&mut slow), frame(0x200, &[n]));
        }
        assert_eq!(slow.recv(Duration::ZERO).unwrap(), None);
    }

    #[test]
    fn a_reading_receiver_makes_room_for_a_blocked_sender() {
        let options = VirtualOptions {
            queue_capacity: 2,
            send_block: Duration::from_secs(5),
            ..Default::default()
        };
        let mut sender = VirtualBus::open_with("t-room", None, options).unwrap();
        let mut receiver = VirtualBus::open_with("t-room", None, options).unwrap();
        let reader = thread::spawn(move || {
            let mut got = Vec::new();
            while got.len() < 50 {
                got.push(recv_frame(&mut receiver).data()[0]);
                thread::sleep(Duration::from_micros(200));
            }
            got
        });
        for n in 0..50u8 {
            sender.send(&frame(0x300, &[n])).unwrap();
        }
        assert_eq!(reader.join().unwrap(), (0..50).collect::<Vec<_>>());
    }

    #[test]
    fn last_endpoint_drop_removes_the_bus() {
        let a = VirtualBus::open("t-lifetime", None).unwrap();
        let b = VirtualBus::open("t-lifetime", None).unwrap();
        assert!(bus_exists("t-lifetime"));
        drop(a);
        assert!(bus_exists("t-lifetime"));
        assert_eq!(b.endpoint_count(), 1);
        drop(b);
        assert!(!bus_exists("t-lifetime"));
        // A new bus of that name starts empty and may use another mode.
        let timed = VirtualBus::open("t-lifetime", Some(Bitrate::K125)).unwrap();
        assert_eq!(timed.endpoint_count(), 1);
        drop(timed);
        assert!(!bus_exists("t-lifetime"));
    }

    #[test]
    fn mixing_modes_on_one_name_is_refused() {
        let _ideal = VirtualBus::open("t-mixed", None).unwrap();
        let err = VirtualBus::open("t-mixed", Some(Bitrate::K500)).unwrap_err();
        let message = err.to_string();
        assert!(
            matches!(err, TransportError::VirtualBusMismatch { .. }),
            "{err:?}"
        );
        assert!(
            message.contains("ideal timing") && message.contains("bitrate 500k"),
            "{message}"
        );
    }

    #[test]
    fn invalid_names_are_refused() {
        let err = VirtualBus::open("", None).unwrap_err();
        assert!(matches!(err, TransportError::Spec(_)), "{err:?}");
        assert!(VirtualBus::open("name with spaces", None).is_err());
    }

    #[test]
    fn bit_accurate_bus_arbitrates_and_times_frames() {
        let mut low = VirtualBus::open("t-timed", Some(Bitrate::K125)).unwrap();
        let mut high = VirtualBus::open("t-timed", Some(Bitrate::K125)).unwrap();
        let mut listener = VirtualBus::open("t-timed", Some(Bitrate::K125)).unwrap();
        // A long frame occupies the bus so the next two contend when it ends.
        let blocker = frame(0x7FF, &[0xAA; 8]);
        low.send(&blocker).unwrap();
        high.send(&frame(0x701, &[5])).unwrap();
        low.send(&frame(0x181, &[1, 2])).unwrap();
        let first = listener.recv(Duration::from_secs(5)).unwrap().unwrap();
        let second = listener.recv(Duration::from_secs(5)).unwrap().unwrap();
        let third = listener.recv(Duration::from_secs(5)).unwrap().unwrap();
        assert_eq!(
            [first.frame, second.frame, third.frame],
            [blocker, frame(0x181, &[1, 2]), frame(0x701, &[5])]
        );
        // Back to back: each frame's receive time is one full frame (incl. intermission) after the last.
        assert_eq!(
            second.timestamp - first.timestamp,
            Bitrate::K125.frame_duration(&second.frame)
        );
        assert_eq!(
            third.timestamp - second.timestamp,
            Bitrate::K125.frame_duration(&third.frame)
        );
        // The timestamps are wall-clock times, taken no later than the frame was handed out.
        assert!(third.timestamp <= WallClock::now());
        assert!(WallClock::now() - first.timestamp < Duration::from_secs(5));
        // Senders got no copies, but `high` saw what `low` sent.
        assert_eq!(
            low.recv(Duration::ZERO).unwrap().map(|r| r.frame),
            Some(frame(0x701, &[5]))
        );
        assert_eq!(
            high.recv(Duration::from_secs(1)).unwrap().map(|r| r.frame),
            Some(blocker)
        );
    }

    #[test]
    fn bit_accurate_sender_waits_for_its_transmit_queue_then_times_out() {
        // At 10 kbit/s a DLC-8 frame lasts over 11 ms, so the queue cannot drain within the timeout.
        let options = VirtualOptions {
            tx_queue_len: 2,
            send_timeout: Duration::from_millis(5),
            ..Default::default()
        };
        let mut sender = VirtualBus::open_with("t-tx-full", Some(Bitrate::K10), options).unwrap();
        let _receiver = VirtualBus::open("t-tx-full", Some(Bitrate::K10)).unwrap();
        let long = frame(0x100, &[0; 8]);
        let mut accepted = 0;
        let err = loop {
            let started = std::time::Instant::now();
            match sender.send(&long) {
                Ok(()) => accepted += 1,
                Err(err) => {
                    assert!(started.elapsed() >= Duration::from_millis(5));
                    break err;
                }
            }
            assert!(
                accepted <= 3,
                "the transmit queue of 2 frames took {accepted} frames"
            );
        };
        // One frame on the wire plus two waiting, or two waiting if the first had not started yet.
        assert!((2..=3).contains(&accepted), "{accepted}");
        assert!(matches!(err, TransportError::SendTimeout { .. }), "{err:?}");
        assert!(
            err.to_string()
                .starts_with("sending on virtual:t-tx-full?bitrate=10k timed out"),
            "{err}"
        );
    }

    #[test]
    fn bit_accurate_receiver_overrun_is_reported() {
        let options = VirtualOptions {
            queue_capacity: 1,
            ..Default::default()
        };
        let mut sender = VirtualBus::open("t-timed-overrun", Some(Bitrate::M1)).unwrap();
        let mut slow = VirtualBus::open_with("t-timed-overrun", Some(Bitrate::M1), options).unwrap();
        let mut listener = VirtualBus::open("t-timed-overrun", Some(Bitrate::M1)).unwrap();
        for n in 0..5u8 {
            sender.send(&frame(0x181, &[n])).unwrap();
        }
        for n in 0..5u8 {
            assert_eq!(recv_frame(&mut listener), frame(0x181, &[n]));
        }
        let err = slow.recv(Duration::ZERO).unwrap_err();
        assert!(matches!(err, TransportError::Overrun { lost: 4, .. }), "{err:?}");
        assert_eq!(recv_frame(&mut slow), frame(0x181, &[0]));
    }

    #[test]
    fn bit_accurate_bus_thread_stops_with_the_last_endpoint() {
        let a = VirtualBus::open("t-timed-drop", Some(Bitrate::M1)).unwrap();
        let thread = lock(&a.bus.engine_thread).as_ref().map(|t| t.thread().id());
        assert!(thread.is_some());
        let shared = Arc::downgrade(&a.bus);
        drop(a);
        // The engine thread was joined and released its reference: the bus is gone.
        assert_eq!(shared.strong_count(), 0);
        assert!(!bus_exists("t-timed-drop"));
    }
}

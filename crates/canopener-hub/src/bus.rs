//! Named buses and lossless, ordered fan-out to the raw-mode clients on each.
//!
//! Delivery semantics follow socketcand on SocketCAN (interop reference §3, "Bus semantics"): a
//! frame from one client reaches every other raw-mode client of the same bus, not the sender
//! (CAN_RAW_RECV_OWN_MSGS off), unless the hub runs with echo.
//!
//! Each bus has one async mutex. A publish takes it, stamps the frames with the wall clock, encodes
//! them once, and hands the encoded batch to every subscriber's queue before releasing it, so every
//! subscriber sees the same total order. Queues are bounded by a semaphore counted in frames: when a
//! subscriber's queue is full the publisher waits (backpressure on the sender, nothing dropped) for
//! at most the stall timeout, after which that subscriber alone is dropped.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, Weak};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use canopener_can::{CanFrame, Instant};
use canopener_socketcand::write_frame;
use tokio::sync::{Semaphore, mpsc, watch};

use crate::stats::Counters;

/// Identifies one connection for the lifetime of the hub.
pub(crate) type ClientId = u64;

/// What a connection's writer sends, in queue order.
#[derive(Debug)]
pub(crate) enum Outgoing {
    /// A protocol reply, written in its own socket write. `hold` delays the bus traffic queued
    /// behind it (the raw-mode grace).
    Reply {
        bytes: &'static [u8],
        hold: Option<Duration>,
    },
    /// Encoded frames from a bus.
    Frames(Arc<FrameBatch>),
    /// Write what is queued before this, then close the connection.
    Close,
}

/// Frames encoded once for all receivers.
#[derive(Debug)]
pub(crate) struct FrameBatch {
    pub(crate) bytes: Vec<u8>,
    pub(crate) count: u32,
}

/// The state a connection shares with the buses that deliver to it.
#[derive(Debug)]
pub(crate) struct ClientLink {
    pub(crate) id: ClientId,
    pub(crate) peer: String,
    /// Free queue slots, in frames; replies take one slot each.
    pub(crate) queue_slots: Semaphore,
    pub(crate) outgoing: mpsc::UnboundedSender<Outgoing>,
    killed: AtomicBool,
    kill_signal: watch::Sender<bool>,
}

impl ClientLink {
    pub(crate) fn new(
        id: ClientId,
        peer: String,
        queue_len: usize,
    ) -> (
        Arc<ClientLink>,
        mpsc::UnboundedReceiver<Outgoing>,
        watch::Receiver<bool>,
    ) {
        let (outgoing, receiver) = mpsc::unbounded_channel();
        let (kill_signal, kill_watch) = watch::channel(false);
        let link = ClientLink {
            id,
            peer,
            queue_slots: Semaphore::new(queue_len),
            outgoing,
            killed: AtomicBool::new(false),
            kill_signal,
        };
        (Arc::new(link), receiver, kill_watch)
    }

    /// Ends the connection: its tasks stop, publishers waiting for its queue give up at once.
    /// Returns whether this call was the one that ended it.
    pub(crate) fn kill(&self) -> bool {
        let first = !self.killed.swap(true, Ordering::AcqRel);
        self.queue_slots.close();
        self.kill_signal.send_replace(true);
        first
    }

    pub(crate) fn is_killed(&self) -> bool {
        self.killed.load(Ordering::Acquire)
    }
}

/// One named bus.
#[derive(Debug)]
pub(crate) struct Bus {
    pub(crate) name: String,
    subscribers: tokio::sync::Mutex<Vec<Arc<ClientLink>>>,
    counters: Arc<Counters>,
}

impl Drop for Bus {
    fn drop(&mut self) {
        Counters::sub(&self.counters.buses_active, 1);
    }
}

/// How a publish ended for the hub's bookkeeping.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub(crate) struct PublishOutcome {
    /// Subscribers that were dropped because their queue stayed full.
    pub(crate) stalled_dropped: u32,
}

impl Bus {
    /// Queues `reply` for `client` and starts delivering this bus's frames to it, atomically with
    /// respect to publishing: every frame published after this call is queued after `reply`, and no
    /// frame published before it is. The caller has already reserved the reply's queue slot.
    pub(crate) async fn subscribe(&self, client: Arc<ClientLink>, reply: Outgoing) -> bool {
        let mut subscribers = self.subscribers.lock().await;
        if client.outgoing.send(reply).is_err() {
            return false;
        }
        if !subscribers.iter().any(|s| s.id == client.id) {
            subscribers.push(client);
        }
        true
    }

    /// Stops delivering to the client `id`; frames already queued for it are still written.
    pub(crate) async fn unsubscribe(&self, id: ClientId) {
        self.subscribers.lock().await.retain(|s| s.id != id);
    }

    /// Puts `frames` from `sender` on the bus, in order, after everything published before.
    pub(crate) async fn publish(
        &self,
        sender: ClientId,
        frames: &[CanFrame],
        echo: bool,
        stall_timeout: Duration,
    ) -> PublishOutcome {
        let mut outcome = PublishOutcome::default();
        let Ok(count) = u32::try_from(frames.len()) else {
            debug_assert!(false, "callers publish bounded batches");
            return outcome;
        };
        if count == 0 {
            return outcome;
        }
        let mut subscribers = self.subscribers.lock().await;
        Counters::add(&self.counters.frames_in, u64::from(count));
        if !subscribers.iter().any(|s| echo || s.id != sender) {
            // Nobody listens, as on a real bus without other nodes: the frames are gone.
            return outcome;
        }
        // Stamped under the lock so timestamps follow the bus order.
        let timestamp = wall_clock_now();
        let mut bytes = Vec::with_capacity(frames.len() * 48);
        for frame in frames {
            write_frame(&mut bytes, frame, timestamp);
        }
        let batch = Arc::new(FrameBatch { bytes, count });
        let mut index = 0;
        while let Some(subscriber) = subscribers.get(index) {
            if subscriber.id == sender && !echo {
                index += 1;
                continue;
            }
            let delivered = self
                .deliver(subscriber, &batch, stall_timeout, &mut outcome)
                .await;
            if delivered {
                index += 1;
            } else {
                subscribers.swap_remove(index);
                // `swap_remove` moved the last subscriber here; order of delivery between
                // subscribers does not matter, only the order within each queue.
            }
        }
        outcome
    }

    /// Queues `batch` for one subscriber, waiting up to `stall_timeout` for room; `false` when the
    /// subscriber is gone or was dropped for stalling.
    async fn deliver(
        &self,
        subscriber: &ClientLink,
        batch: &Arc<FrameBatch>,
        stall_timeout: Duration,
        outcome: &mut PublishOutcome,
    ) -> bool {
        // The common case, a queue with room, needs no timer.
        let slots = match subscriber.queue_slots.try_acquire_many(batch.count) {
            Ok(slots) => Ok(Ok(slots)),
            Err(_) => {
                tokio::time::timeout(stall_timeout, subscriber.queue_slots.acquire_many(batch.count)).await
            }
        };
        match slots {
            Ok(Ok(slots)) => {
                slots.forget();
                subscriber
                    .outgoing
                    .send(Outgoing::Frames(Arc::clone(batch)))
                    .is_ok()
            }
            // The semaphore is closed: the client is gone.
            Ok(Err(_)) => false,
            Err(_elapsed) => {
                if subscriber.kill() {
                    tracing::warn!(
                        client = subscriber.id,
                        peer = %subscriber.peer,
                        bus = %self.name,
                        "dropping client: its queue stayed full for {stall_timeout:?} (it stopped reading)"
                    );
                    Counters::add(&self.counters.clients_dropped, 1);
                    outcome.stalled_dropped += 1;
                }
                false
            }
        }
    }
}

/// The wall clock as a socketcand timestamp (Unix epoch), as the kernel stamps received frames.
pub(crate) fn wall_clock_now() -> Instant {
    match SystemTime::now().duration_since(UNIX_EPOCH) {
        Ok(since_epoch) => Instant::from_nanos(u64::try_from(since_epoch.as_nanos()).unwrap_or(u64::MAX)),
        // A clock before 1970 is misconfigured; zero still prints as a valid timestamp.
        Err(_) => Instant::ZERO,
    }
}

/// All buses by name, created on first `open` and forgotten when the last client leaves.
#[derive(Debug)]
pub(crate) struct BusRegistry {
    buses: Mutex<HashMap<String, Weak<Bus>>>,
    counters: Arc<Counters>,
}

impl BusRegistry {
    pub(crate) fn new(counters: Arc<Counters>) -> BusRegistry {
        BusRegistry {
            buses: Mutex::new(HashMap::new()),
            counters,
        }
    }

    /// The bus called `name`, created if no client has it open.
    pub(crate) fn open(&self, name: &str) -> Arc<Bus> {
        // A poisoned lock only means another connection panicked mid-lookup; the map is still valid.
        let mut buses = self.buses.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        if let Some(bus) = buses.get(name).and_then(Weak::upgrade) {
            return bus;
        }
        buses.retain(|_, bus| bus.strong_count() > 0);
        let bus = Arc::new(Bus {
            name: name.to_owned(),
            subscribers: tokio::sync::Mutex::new(Vec::new()),
            counters: Arc::clone(&self.counters),
        });
        Counters::add(&self.counters.buses_active, 1);
        buses.insert(name.to_owned(), Arc::downgrade(&bus));
        bus
    }
}

#[cfg(test)]
mod tests {
    use canopener_can::CanId;
    use canopener_socketcand::{ElementReader, ServerMessage, parse_server_message};

    use super::*;

    fn frame(n: u8) -> CanFrame {
        CanFrame::new(CanId::standard(0x100).unwrap(), &[n]).unwrap()
    }

    fn decode(batches: &mut mpsc::UnboundedReceiver<Outgoing>) -> Vec<u8> {
        let mut reader = ElementReader::default();
        while let Ok(item) = batches.try_recv() {
            if let Outgoing::Frames(batch) = item {
                reader.push(&batch.bytes);
            }
        }
        let mut firsts = Vec::new();
        while let Some(element) = reader.next_element() {
            match parse_server_message(&element.unwrap()).unwrap() {
                ServerMessage::Frame { frame, .. } => firsts.push(frame.data()[0]),
                other => panic!("unexpected {other:?}"),
            }
        }
        firsts
    }

    #[tokio::test]
    async fn publish_reaches_others_in_order_but_not_the_sender() {
        let counters = Arc::new(Counters::default());
        let registry = BusRegistry::new(Arc::clone(&counters));
        let bus = registry.open("can0");
        let (a, mut a_rx, _a_kill) = ClientLink::new(1, "a".into(), 64);
        let (b, mut b_rx, _b_kill) = ClientLink::new(2, "b".into(), 64);
        bus.subscribe(Arc::clone(&a), Outgoing::Close).await;
        bus.subscribe(Arc::clone(&b), Outgoing::Close).await;
        bus.publish(1, &[frame(1), frame(2)], false, Duration::from_secs(1))
            .await;
        bus.publish(2, &[frame(3)], false, Duration::from_secs(1)).await;
        assert_eq!(decode(&mut a_rx), [3]);
        assert_eq!(decode(&mut b_rx), [1, 2]);
        assert_eq!(counters.frames_in.load(Ordering::Relaxed), 3);
    }

    #[tokio::test]
    async fn echo_delivers_to_the_sender_too() {
        let registry = BusRegistry::new(Arc::new(Counters::default()));
        let bus = registry.open("can0");
        let (a, mut a_rx, _kill) = ClientLink::new(1, "a".into(), 64);
        bus.subscribe(a, Outgoing::Close).await;
        bus.publish(1, &[frame(7)], true, Duration::from_secs(1)).await;
        assert_eq!(decode(&mut a_rx), [7]);
    }

    #[tokio::test]
    async fn a_full_queue_drops_only_that_subscriber_after_the_stall_timeout() {
        let counters = Arc::new(Counters::default());
        let registry = BusRegistry::new(Arc::clone(&counters));
        let bus = registry.open("can0");
        let (stuck, _stuck_rx, stuck_kill) = ClientLink::new(1, "stuck".into(), 2);
        let (good, mut good_rx, _good_kill) = ClientLink::new(2, "good".into(), 64);
        bus.subscribe(Arc::clone(&stuck), Outgoing::Close).await;
        bus.subscribe(Arc::clone(&good), Outgoing::Close).await;
        let outcome = bus
            .publish(3, &[frame(1), frame(2)], false, Duration::from_millis(20))
            .await;
        assert_eq!(outcome.stalled_dropped, 0);
        // The good client keeps reading: give its slots back as a writer would.
        good.queue_slots.add_permits(2);
        let outcome = bus
            .publish(3, &[frame(3)], false, Duration::from_millis(20))
            .await;
        assert_eq!(outcome.stalled_dropped, 1);
        assert!(stuck.is_killed());
        assert!(*stuck_kill.borrow());
        assert_eq!(counters.clients_dropped.load(Ordering::Relaxed), 1);
        assert_eq!(decode(&mut good_rx), [1, 2, 3]);
        // The stuck subscriber is gone: the next publish does not wait for it.
        let started = std::time::Instant::now();
        bus.publish(3, &[frame(4)], false, Duration::from_secs(5)).await;
        assert!(started.elapsed() < Duration::from_secs(1));
    }

    #[tokio::test]
    async fn buses_are_shared_by_name_and_forgotten_when_unused() {
        let counters = Arc::new(Counters::default());
        let registry = BusRegistry::new(Arc::clone(&counters));
        let first = registry.open("can0");
        let again = registry.open("can0");
        let other = registry.open("can1");
        assert!(Arc::ptr_eq(&first, &again));
        assert!(!Arc::ptr_eq(&first, &other));
        assert_eq!(counters.buses_active.load(Ordering::Relaxed), 2);
        drop((first, again, other));
        assert_eq!(counters.buses_active.load(Ordering::Relaxed), 0);
        let fresh = registry.open("can0");
        assert_eq!(fresh.name, "can0");
        assert_eq!(counters.buses_active.load(Ordering::Relaxed), 1);
    }
}

//! The real-time driver of a bit-accurate virtual bus: one thread per bus feeding
//! `canopener_bus_engine::BusEngine` the wall clock.
//!
//! The engine's schedule depends only on when frames were submitted, never on when this thread
//! wakes up (see `BusEngine`), so a late wake-up delays delivery but does not stretch the bus timeline:
//! a saturated bus carries exactly `bitrate / frame_bits` frames per second.

use std::io;
use std::sync::{Arc, PoisonError};
use std::thread::JoinHandle;
use std::time::Duration;

use crate::Received;
use crate::clock::WallClock;
use crate::virtual_bus::{BusState, Sender, SharedBus, deliver};

/// The longest the thread sleeps without a deadline; a safety net only, every state change that
/// matters signals `engine_wake`.
const IDLE_WAIT: Duration = Duration::from_secs(1);

/// Starts the engine thread of `bus`; it runs until the bus state says `shutdown`.
pub(crate) fn spawn(bus: Arc<SharedBus>) -> io::Result<JoinHandle<()>> {
    let name = format!("canopener-vbus-{}", bus.name());
    std::thread::Builder::new().name(name).spawn(move || run(&bus))
}

fn run(bus: &SharedBus) {
    let mut state = bus.lock_state();
    loop {
        if state.shutdown {
            return;
        }
        let now = WallClock::now();
        let mut next = None;
        let BusState { engine, inboxes, .. } = &mut *state;
        if let Some(engine) = engine.as_mut() {
            engine.sim.handle_timeout(now);
            while let Some(delivery) = engine.sim.poll_delivery() {
                let received = Received {
                    frame: delivery.frame,
                    timestamp: delivery.at,
                };
                deliver(inboxes, Sender::Port(delivery.from), received);
            }
            next = engine.sim.poll_timeout();
        }
        // Frames that started on the wire left their senders' queues: there may be room now.
        if state.blocked_senders > 0 {
            bus.writable.notify_all();
        }
        let wait = match next {
            Some(deadline) => deadline.saturating_duration_since(WallClock::now()),
            None => IDLE_WAIT,
        };
        if !wait.is_zero() {
            state = bus
                .engine_wake
                .wait_timeout(state, wait)
                .unwrap_or_else(PoisonError::into_inner)
                .0;
        }
    }
}

//! Simulated devices on a real bus, in real time: what `canopener sim` runs.
//!
//! One bus endpoint is shared by all devices. The loop receives with a timeout of the earliest deadline
//! of all devices (at most [`MAX_WAIT`], so that a cancellation is noticed quickly), feeds every received
//! frame to every device, runs due timers, and sends every frame a device produces. A frame one device
//! sends is also fed to every other device, as a real bus would deliver it to the other nodes (a
//! socketcand hub does not echo a client's frames back to it).

use std::collections::VecDeque;
use std::time::Duration;

use canopener_can::{CanFrame, Core, Instant};
use canopener_transport::{CanBus, TransportError, WallClock};

use crate::device::SimulatedDevice;
use crate::error::SimError;
use crate::event_log::LogEntry;
use canopener_link::cancel::Cancel;
use canopener_link::link::MAX_WAIT;

/// Frames the devices may pass among themselves in one round before the rest waits for the next one (a
/// guard against two devices answering each other forever; the cores do not, but the bus must not hang).
pub const MAX_FRAMES_PER_ROUND: usize = 10_000;

/// How long before a device's deadline the loop stops waiting on the transport's receive timeout
/// (longer than the coarsest kernel tick, 10 ms at HZ=100) and polls instead.
const PRECISE_WINDOW: Duration = Duration::from_millis(12);

/// How long the loop sleeps between polls within [`PRECISE_WINDOW`]: the most a timer fires late or
/// a frame waits there.
const PRECISE_SLICE: Duration = Duration::from_micros(200);

/// What a running [`SimHost`] reports.
#[derive(Debug, Clone, PartialEq)]
pub enum HostReport {
    /// Something happened, `elapsed` after the host started.
    Entry {
        /// Time since [`SimHost::run`] started.
        elapsed: Duration,
        /// What happened.
        entry: LogEntry,
    },
    /// The transport dropped frames because the simulator did not keep up: the devices missed them.
    FramesLost {
        /// How many.
        lost: u64,
    },
}

/// Simulated devices on one bus endpoint, on the wall clock (see the [module docs](self)).
#[derive(Debug)]
pub struct SimHost {
    devices: Vec<SimulatedDevice>,
    bus: Box<dyn CanBus>,
    cancel: Cancel,
    started: Instant,
}

impl SimHost {
    /// The devices on `bus`, running until `cancel` is cancelled.
    pub fn new(devices: Vec<SimulatedDevice>, bus: Box<dyn CanBus>, cancel: Cancel) -> SimHost {
        SimHost {
            devices,
            bus,
            cancel,
            started: WallClock::now(),
        }
    }

    /// The devices.
    pub fn devices(&self) -> &[SimulatedDevice] {
        &self.devices
    }

    /// Announces every device, powers them on and runs them until the cancellation, then reports the
    /// end. Every report goes to `on_report`; its error ends the run (after the final report, if that
    /// can still be made). A failing bus ends it with the bus's error.
    pub fn run<E>(&mut self, mut on_report: impl FnMut(HostReport) -> Result<(), E>) -> Result<(), E>
    where
        E: From<SimError>,
    {
        self.started = WallClock::now();
        let bus = self.bus.spec().to_string();
        for device in &self.devices {
            self.report(&mut on_report, LogEntry::started(device, &bus))?;
        }
        let mut result = self.boot(WallClock::now(), &mut on_report);
        while result.is_ok() && !self.cancel.is_cancelled() {
            result = self.step(&mut on_report);
        }
        self.report(&mut on_report, LogEntry::stopped(result.is_ok()))?;
        result
    }

    /// Power-on of every device.
    fn boot<E: From<SimError>>(
        &mut self,
        now: Instant,
        on_report: &mut impl FnMut(HostReport) -> Result<(), E>,
    ) -> Result<(), E> {
        for sim in &mut self.devices {
            sim.boot(now);
        }
        self.pump(now, on_report)
    }

    /// One turn of the loop: due timers, then one receive bounded by the next deadline.
    fn step<E: From<SimError>>(
        &mut self,
        on_report: &mut impl FnMut(HostReport) -> Result<(), E>,
    ) -> Result<(), E> {
        let now = WallClock::now();
        let mut ran = false;
        for sim in &mut self.devices {
            // A late wakeup runs the timers with the real time; the cores schedule their next deadline
            // from the one that was due, so periodic frames keep their period on average.
            if sim.poll_timeout().is_some_and(|due| due <= now) {
                sim.handle_timeout(now);
                ran = true;
            }
        }
        if ran {
            self.pump(now, on_report)?;
        }
        let wait = match self.devices.iter().filter_map(Core::poll_timeout).min() {
            // A deadline still due right after its timer ran would spin the loop: wait a little.
            Some(due) if due <= now => Duration::from_millis(1),
            Some(due) => due.saturating_duration_since(WallClock::now()).min(MAX_WAIT),
            None => MAX_WAIT,
        };
        // A receive timeout is rounded up to the kernel's tick (4 or 10 ms): waiting for a deadline
        // with it makes heartbeats and event timers late by up to a tick. Far from the deadline the
        // receive stops a window early; within the window the loop polls and sleeps in short slices,
        // which a sleep does precisely, so a timer fires within a slice of its deadline and a frame
        // waits at most one slice.
        let wait = if wait > PRECISE_WINDOW {
            wait - PRECISE_WINDOW
        } else {
            match self.bus.recv(Duration::ZERO) {
                Ok(None) => {
                    std::thread::sleep(wait.min(PRECISE_SLICE));
                    return Ok(());
                }
                received => return self.received(received, on_report),
            }
        };
        let received = self.bus.recv(wait);
        self.received(received, on_report)
    }

    /// Feeds what one receive brought to the devices.
    fn received<E: From<SimError>>(
        &mut self,
        received: Result<Option<canopener_transport::Received>, TransportError>,
        on_report: &mut impl FnMut(HostReport) -> Result<(), E>,
    ) -> Result<(), E> {
        match received {
            Ok(Some(received)) => {
                let now = WallClock::now();
                for sim in &mut self.devices {
                    sim.handle_frame(now, &received.frame);
                }
                self.pump(now, on_report)
            }
            Ok(None) => Ok(()),
            Err(TransportError::Overrun { lost, .. }) => on_report(HostReport::FramesLost { lost }),
            Err(err) => Err(SimError::Bus(err).into()),
        }
    }

    /// Reports every event, sends every frame and feeds each sent frame to the other devices, until no
    /// device has anything left (or [`MAX_FRAMES_PER_ROUND`] frames went round).
    fn pump<E: From<SimError>>(
        &mut self,
        now: Instant,
        on_report: &mut impl FnMut(HostReport) -> Result<(), E>,
    ) -> Result<(), E> {
        let mut queue: VecDeque<(usize, CanFrame)> = VecDeque::new();
        for _ in 0..MAX_FRAMES_PER_ROUND {
            for index in 0..self.devices.len() {
                while let Some(event) = self.devices.get_mut(index).and_then(|d| d.poll_event()) {
                    if let Some(entry) = self.devices.get(index).and_then(|d| LogEntry::event(d, &event)) {
                        self.report(on_report, entry)?;
                    }
                }
                while let Some(frame) = self.devices.get_mut(index).and_then(|d| d.poll_transmit()) {
                    self.bus.send(&frame).map_err(SimError::Bus)?;
                    queue.push_back((index, frame));
                }
            }
            let Some((from, frame)) = queue.pop_front() else {
                return Ok(());
            };
            for (index, sim) in self.devices.iter_mut().enumerate() {
                if index != from {
                    sim.handle_frame(now, &frame);
                }
            }
        }
        Ok(())
    }

    fn report<E>(
        &self,
        on_report: &mut impl FnMut(HostReport) -> Result<(), E>,
        entry: LogEntry,
    ) -> Result<(), E> {
        let elapsed = WallClock::now().saturating_duration_since(self.started);
        on_report(HostReport::Entry { elapsed, entry })
    }
}

#[cfg(test)]
mod tests {
    use canopener_transport::{BusSpec, Received};

    use super::*;
    use crate::simulation::Simulation;
    use crate::test_support::{CONSUMER_1016, base_eds_with, frame, temp_dir};

    /// A bus that records what is sent and hands out queued frames at once; it cancels the run once it
    /// has had nothing to hand out many times, so that no test can hang.
    #[derive(Debug)]
    struct FakeBus {
        spec: BusSpec,
        sent: std::sync::Arc<std::sync::Mutex<Vec<String>>>,
        inbox: VecDeque<CanFrame>,
        idle: usize,
        cancel: Cancel,
    }

    impl CanBus for FakeBus {
        fn send(&mut self, frame: &CanFrame) -> Result<(), TransportError> {
            self.sent.lock().unwrap().push(frame.to_string());
            Ok(())
        }

        fn recv(&mut self, _timeout: Duration) -> Result<Option<Received>, TransportError> {
            let frame = self.inbox.pop_front();
            if frame.is_none() {
                self.idle += 1;
                if self.idle > 100 {
                    self.cancel.cancel();
                }
            }
            Ok(frame.map(|frame| Received {
                timestamp: WallClock::now(),
                frame,
            }))
        }

        fn spec(&self) -> &BusSpec {
            &self.spec
        }
    }

    /// The host feeds what one device sends to the others: node 6's boot-up after an NMT reset reaches
    /// node 5's heartbeat consumer although the bus never echoes it.
    #[test]
    fn devices_hear_each_other_through_the_host_and_stop_on_cancel() {
        let dir = temp_dir("host");
        let eds = base_eds_with(&dir, "consumer.eds", CONSUMER_1016);
        let devices = Simulation::ideal()
            .files([&eds, &eds])
            .first_node_id(Some(5))
            .build()
            .unwrap();
        let cancel = Cancel::new();
        let sent = std::sync::Arc::default();
        let bus = FakeBus {
            spec: BusSpec::Socketcand {
                host: "127.0.0.1".into(),
                port: 9,
                bus: "can0".into(),
            },
            sent: std::sync::Arc::clone(&sent),
            // 1016h:01 of node 5 = node 6, 1000 ms; then reset node 6.
            inbox: [frame("605#23161001E8030600"), frame("000#8106")].into(),
            idle: 0,
            cancel: cancel.clone(),
        };
        let mut host = SimHost::new(devices, Box::new(bus), cancel);
        let mut log = Vec::new();
        host.run(|report| {
            match report {
                HostReport::Entry { entry, .. } => log.push(entry),
                HostReport::FramesLost { lost } => panic!("{lost} frames lost on a fake bus"),
            }
            Ok::<(), SimError>(())
        })
        .unwrap();
        assert_eq!(
            *sent.lock().unwrap(),
            ["705#00", "706#00", "585#6016100100000000", "706#00"]
        );
        let kinds: Vec<&str> = log.iter().map(|e| e.kind).collect();
        assert_eq!(kinds.first(), Some(&"started"));
        assert_eq!(kinds.last(), Some(&"stopped"));
        assert_eq!(log.last().unwrap().text, "stopped");
        assert!(
            log.iter()
                .any(|e| e.node == Some(5) && e.text == "heartbeat of node 6 started"),
            "{log:?}"
        );
        assert!(
            log[0].text.contains(" on socketcand://127.0.0.1:9/can0 ("),
            "{:?}",
            log[0]
        );
    }
}

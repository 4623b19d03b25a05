//! The session replay behind `canopener demo --monitor`: a recorded CANopen session played by a traffic source while a second endpoint watches the
//! same bus, by default through an in-process socketcand hub, so that every layer from the transports up
//! runs end to end without hardware.

use std::io;
use std::net::SocketAddr;
use std::thread;
use std::time::{Duration, Instant};

use canopener_can::candump::parse_log;
use canopener_hub::{HubConfig, HubHandle};
use canopener_transport::{BusSpec, CanBus, Received, TransportError, open};

use crate::replay::{Pace, TimedFrame, frames_of, replay};
use canopener_link::cancel::Cancel;

/// The recorded session: four nodes with boot-up, NMT, SDO expedited/segmented/block, PDOs with SYNC,
/// EMCY, heartbeat, node guarding, LSS and TIME. A candump log kept with its generator in
/// `canopener-wire/test_data`, whose tests prove it decodes with no anomalies.
pub const DEMO_LOG: &str = include_str!("../../canopener-wire/test_data/demo.log");

/// After the source has sent its last frame, how long the watcher waits for stragglers.
const DRAIN_TIMEOUT: Duration = Duration::from_secs(2);
/// How long one receive of the watcher may block: how late a cancel or the source's end is noticed.
const POLL: Duration = Duration::from_millis(50);

/// Why a demo could not run to its end.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// The embedded session does not parse (a build problem, not a user's).
    #[error("the embedded demo log is broken at {0}")]
    BrokenLog(String),
    /// The in-process hub could not start.
    #[error("cannot start the in-process hub: {0}")]
    Hub(#[source] io::Error),
    /// The traffic source thread could not start.
    #[error("cannot start the traffic source thread: {0}")]
    Thread(#[source] io::Error),
    /// The traffic source thread panicked.
    #[error("the traffic source thread panicked")]
    SourcePanicked,
    /// Opening, sending on or receiving from the bus failed.
    #[error(transparent)]
    Bus(#[from] TransportError),
    /// The front end could not take a frame (for example its output went away).
    #[error("the demo's output failed: {0}")]
    Output(#[source] io::Error),
}

/// The frames of [`DEMO_LOG`] with their recorded times.
pub fn recorded_session() -> Result<Vec<TimedFrame>, ReplayError> {
    let (records, errors) = parse_log(DEMO_LOG);
    if let Some(err) = errors.first() {
        return Err(ReplayError::BrokenLog(err.to_string()));
    }
    Ok(frames_of(records, None).0)
}

/// How a demo went.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReplayReport {
    /// Frames the source sent.
    pub sent: u64,
    /// Frames the watcher received.
    pub received: u64,
    /// From the first frame sent until the watcher stopped.
    pub elapsed: Duration,
}

/// A bus with two endpoints open on it, a traffic source and a watcher; with an in-process hub serving
/// it when no bus was given.
#[derive(Debug)]
pub struct SessionReplay {
    hub: Option<HubHandle>,
    spec: BusSpec,
    source: Box<dyn CanBus>,
    watcher: Box<dyn CanBus>,
}

impl SessionReplay {
    /// Opens both endpoints on `bus`; without one, starts a hub on a free loopback port and uses its bus
    /// `can0`.
    pub fn open(bus: Option<BusSpec>) -> Result<SessionReplay, ReplayError> {
        let (hub, spec) = match bus {
            Some(spec) => (None, spec),
            None => {
                let hub = canopener_hub::spawn(HubConfig::new(SocketAddr::from(([127, 0, 0, 1], 0))))
                    .map_err(ReplayError::Hub)?;
                let addr = hub.local_addr();
                let spec = BusSpec::Socketcand {
                    host: addr.ip().to_string(),
                    port: addr.port(),
                    bus: "can0".into(),
                };
                (Some(hub), spec)
            }
        };
        let watcher = open(&spec)?;
        let source = open(&spec)?;
        Ok(SessionReplay {
            hub,
            spec,
            source,
            watcher,
        })
    }

    /// The bus the demo runs on.
    pub fn spec(&self) -> &BusSpec {
        &self.spec
    }

    /// The address of the in-process hub, when the demo started one (others may join it meanwhile).
    pub fn hub_addr(&self) -> Option<SocketAddr> {
        self.hub.as_ref().map(HubHandle::local_addr)
    }

    /// Plays `frames` from the source endpoint on a thread of its own, spaced by `pace`, while this
    /// thread hands every frame the watcher receives to `on_frame`. Ends when the watcher has received
    /// as many frames as there are, two seconds after the source finished, or on `cancel`; then
    /// closes both endpoints and the hub.
    pub fn run(
        self,
        frames: &[TimedFrame],
        pace: Pace,
        cancel: &Cancel,
        mut on_frame: impl FnMut(&Received) -> io::Result<()>,
    ) -> Result<ReplayReport, ReplayError> {
        let SessionReplay {
            hub,
            spec: _,
            mut source,
            mut watcher,
        } = self;
        let expected = frames.len() as u64;
        // The source has a token of its own, so that a watcher that fails stops it without cancelling the
        // caller's token; the caller's cancel is passed on by the watch loop.
        let source_stop = Cancel::new();
        let started = Instant::now();
        let (sent, watched) = thread::scope(|scope| {
            let source_thread = thread::Builder::new()
                .name("demo-source".into())
                .spawn_scoped(scope, || {
                    replay(&mut *source, frames, pace, 1, &source_stop, |_| {})
                })
                .map_err(ReplayError::Thread)?;
            let watched = watch(
                &mut *watcher,
                expected,
                cancel,
                &source_stop,
                &mut on_frame,
                || source_thread.is_finished(),
            );
            source_stop.cancel();
            let sent = source_thread.join().map_err(|_| ReplayError::SourcePanicked)?;
            Ok::<_, ReplayError>((sent, watched))
        })?;
        let elapsed = started.elapsed();
        drop(source);
        drop(watcher);
        if let Some(hub) = hub {
            hub.shutdown();
        }
        // A source failure explains a watcher's shortfall, so it is reported first.
        let sent = sent?.sent;
        let received = watched?;
        Ok(ReplayReport {
            sent,
            received,
            elapsed,
        })
    }
}

/// Receives until `expected` frames arrived, `DRAIN_TIMEOUT` after `source_done`, or on `cancel`
/// (which it passes on to `source_stop`). Returns how many frames arrived.
fn watch(
    bus: &mut dyn CanBus,
    expected: u64,
    cancel: &Cancel,
    source_stop: &Cancel,
    on_frame: &mut impl FnMut(&Received) -> io::Result<()>,
    source_done: impl Fn() -> bool,
) -> Result<u64, ReplayError> {
    let mut received = 0;
    let mut drain_deadline: Option<Instant> = None;
    while received < expected {
        if cancel.is_cancelled() {
            source_stop.cancel();
            break;
        }
        if drain_deadline.is_none() && source_done() {
            drain_deadline = Some(Instant::now() + DRAIN_TIMEOUT);
        }
        if drain_deadline.is_some_and(|deadline| Instant::now() >= deadline) {
            break;
        }
        if let Some(frame) = bus.recv(POLL)? {
            received += 1;
            on_frame(&frame).map_err(ReplayError::Output)?;
        }
    }
    Ok(received)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn first_frames(count: usize) -> Vec<TimedFrame> {
        recorded_session().unwrap().into_iter().take(count).collect()
    }

    #[test]
    fn the_embedded_session_parses() {
        let frames = recorded_session().unwrap();
        assert!(frames.len() > 100, "{} frames", frames.len());
        assert!(
            frames.windows(2).all(|pair| pair[0].0 <= pair[1].0),
            "recorded in time order"
        );
    }

    #[test]
    fn every_frame_reaches_the_watcher_on_a_virtual_bus() {
        let demo = SessionReplay::open(Some("virtual:demo-rt-all".parse().unwrap())).unwrap();
        assert_eq!(demo.hub_addr(), None);
        assert_eq!(demo.spec().to_string(), "virtual:demo-rt-all");
        let frames = first_frames(50);
        let mut seen = Vec::new();
        let outcome = demo
            .run(&frames, Pace::BACK_TO_BACK, &Cancel::new(), |received| {
                seen.push(received.frame);
                Ok(())
            })
            .unwrap();
        assert_eq!((outcome.sent, outcome.received), (50, 50));
        let played: Vec<_> = frames.iter().map(|(_, frame)| *frame).collect();
        assert_eq!(seen, played);
    }

    #[test]
    fn the_in_process_hub_carries_the_session() {
        let demo = SessionReplay::open(None).unwrap();
        let addr = demo.hub_addr().expect("an in-process hub");
        assert_eq!(
            demo.spec().to_string(),
            format!("socketcand://{}:{}/can0", addr.ip(), addr.port())
        );
        let outcome = demo
            .run(&first_frames(20), Pace::BACK_TO_BACK, &Cancel::new(), |_| Ok(()))
            .unwrap();
        assert_eq!((outcome.sent, outcome.received), (20, 20));
        assert!(
            std::net::TcpStream::connect(addr).is_err(),
            "the hub is shut down"
        );
    }

    #[test]
    fn a_failing_front_end_stops_the_source_and_reports_its_error() {
        let demo = SessionReplay::open(Some("virtual:demo-rt-output".parse().unwrap())).unwrap();
        // Recorded timing: without the stop the source would take the whole session's seconds.
        let frames = recorded_session().unwrap();
        let started = Instant::now();
        let err = demo
            .run(&frames, Pace::recorded(1.0).unwrap(), &Cancel::new(), |_| {
                Err(io::Error::from(io::ErrorKind::BrokenPipe))
            })
            .unwrap_err();
        assert!(matches!(err, ReplayError::Output(_)), "{err}");
        assert!(
            started.elapsed() < Duration::from_secs(3),
            "{:?}",
            started.elapsed()
        );
    }

    #[test]
    fn a_cancel_ends_the_demo_early() {
        let demo = SessionReplay::open(Some("virtual:demo-rt-cancel".parse().unwrap())).unwrap();
        let frames = recorded_session().unwrap();
        let cancel = Cancel::new();
        let outcome = demo
            .run(&frames, Pace::recorded(1.0).unwrap(), &cancel, |_| {
                cancel.cancel();
                Ok(())
            })
            .unwrap();
        assert!(outcome.sent < frames.len() as u64, "{outcome:?}");
        assert!(outcome.received <= outcome.sent);
    }
}

//! Capturing live traffic: receive every frame of a bus until told to stop, hand each to the front end
//! for display, and optionally keep it in a candump log that is flushed often enough that a crash loses
//! at most half a second.

use std::io;
use std::time::{Duration, Instant};

use canopener_can::candump::{LogEvent, LogRecord};
use canopener_transport::{BusSpec, CanBus, Received, TransportError};

use crate::candump_file::{LogFileError, LogWriter};
use canopener_link::cancel::Cancel;

/// How long one receive may block: how late a cancel or the end of the duration is noticed.
const POLL: Duration = Duration::from_millis(100);
/// The log and the front end's output are flushed at least this often, so a crash or a kill -9 loses at
/// most this much.
const FLUSH_EVERY: Duration = Duration::from_millis(500);

/// When a capture ends by itself; with neither it runs until cancelled.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CaptureLimits {
    /// Stop after this many frames.
    pub count: Option<u64>,
    /// Stop after this long.
    pub duration: Option<Duration>,
}

/// What a capture hands its front end, in bus order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CaptureEvent<'a> {
    /// A frame was received (and, with a log, is about to be logged).
    Frame(&'a Received),
    /// This many frames were lost because the capture did not keep up; it carries on.
    Lost(u64),
    /// A good moment to flush buffered output: sent every half second and once at the end.
    Flush,
}

/// How a capture went.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CaptureSummary {
    /// Frames received.
    pub frames: u64,
    /// Frames reported lost by the transport.
    pub lost: u64,
    /// How long the capture ran.
    pub elapsed: Duration,
}

/// Why a capture ended early. Frames received before are in the log either way.
#[derive(Debug, thiserror::Error)]
pub enum CaptureError {
    /// The bus failed.
    #[error(transparent)]
    Bus(#[from] TransportError),
    /// The log could not be written.
    #[error(transparent)]
    Log(#[from] LogFileError),
    /// The front end could not take an event (for example its output went away).
    #[error("the capture's output failed: {0}")]
    Output(#[source] io::Error),
}

/// The interface name that monitor lines show and candump logs record for frames from `spec`.
pub fn interface_name(spec: &BusSpec) -> String {
    match spec {
        BusSpec::Virtual { name, .. } => name.clone(),
        BusSpec::Socketcand { bus, .. } => bus.clone(),
        BusSpec::SocketCan { interface } => interface.clone(),
        BusSpec::UdpMulticast { .. } => "udp".to_owned(),
    }
}

/// Receives frames from `bus` until `cancel` is set or a limit is reached, giving every frame and every
/// loss to `on_event` first and then writing it to `log` under the bus's [`interface_name`].
///
/// The log and `on_event` are flushed at the end whatever happened, so a failing bus never costs frames
/// already received.
pub fn capture(
    bus: &mut dyn CanBus,
    limits: CaptureLimits,
    mut log: Option<&mut LogWriter>,
    cancel: &Cancel,
    mut on_event: impl FnMut(CaptureEvent<'_>) -> io::Result<()>,
) -> Result<CaptureSummary, CaptureError> {
    let interface = interface_name(bus.spec());
    let started = Instant::now();
    let mut last_flush = started;
    let mut summary = CaptureSummary {
        frames: 0,
        lost: 0,
        elapsed: Duration::ZERO,
    };
    // One receive and what follows from it; `Ok(false)` ends the capture. A closure, so that every way out
    // of the loop below, errors included, passes the final flush after it.
    let mut step = || -> Result<bool, CaptureError> {
        if cancel.is_cancelled()
            || limits.count.is_some_and(|count| summary.frames >= count)
            || limits
                .duration
                .is_some_and(|duration| started.elapsed() >= duration)
        {
            return Ok(false);
        }
        match bus.recv(POLL) {
            Ok(Some(received)) => {
                summary.frames += 1;
                on_event(CaptureEvent::Frame(&received)).map_err(CaptureError::Output)?;
                if let Some(log) = log.as_deref_mut() {
                    log.write(&LogRecord {
                        timestamp: received.timestamp,
                        interface: interface.clone(),
                        event: LogEvent::Frame(received.frame),
                    })?;
                }
            }
            Ok(None) => {}
            Err(TransportError::Overrun { lost, .. }) => {
                summary.lost += lost;
                on_event(CaptureEvent::Lost(lost)).map_err(CaptureError::Output)?;
            }
            Err(err) => return Err(err.into()),
        }
        if last_flush.elapsed() >= FLUSH_EVERY {
            last_flush = Instant::now();
            on_event(CaptureEvent::Flush).map_err(CaptureError::Output)?;
            if let Some(log) = log.as_deref_mut() {
                log.flush()?;
            }
        }
        Ok(true)
    };
    let result = loop {
        match step() {
            Ok(true) => {}
            Ok(false) => break Ok(()),
            Err(err) => break Err(err),
        }
    };
    let flushed = on_event(CaptureEvent::Flush).map_err(CaptureError::Output);
    let logged = log.map_or(Ok(()), |log| log.flush().map_err(CaptureError::from));
    result.and(flushed).and(logged)?;
    summary.elapsed = started.elapsed();
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use canopener_can::{CanFrame, StandardId};
    use std::path::Path;

    use super::*;
    use crate::test_support::virtual_pair;

    fn frame(id: u16, data: &[u8]) -> CanFrame {
        CanFrame::new(StandardId::new(id).unwrap(), data).unwrap()
    }

    #[test]
    fn stops_after_count_frames_logging_each_under_the_bus_name() {
        let (mut sender, mut receiver) = virtual_pair("capture-count");
        for id in [0x701, 0x181, 0x000] {
            sender.send(&frame(id, &[1, 2])).unwrap();
        }
        let dir = canopener_testkit::fixture::ScratchDir::new("runtime-capture");
        let path = dir.join("count.log");
        let mut log = LogWriter::create(&path, true).unwrap();
        let mut seen = Vec::new();
        let mut flushes = 0;
        let limits = CaptureLimits {
            count: Some(2),
            duration: None,
        };
        let summary = capture(&mut *receiver, limits, Some(&mut log), &Cancel::new(), |event| {
            match event {
                CaptureEvent::Frame(received) => seen.push(received.frame),
                CaptureEvent::Lost(_) => panic!("nothing is lost on a virtual bus"),
                CaptureEvent::Flush => flushes += 1,
            }
            Ok(())
        })
        .unwrap();
        assert_eq!(seen, [frame(0x701, &[1, 2]), frame(0x181, &[1, 2])]);
        assert_eq!((summary.frames, summary.lost), (2, 0));
        assert!(flushes >= 1, "the end always flushes");
        drop(log);
        let written = std::fs::read_to_string(&path).unwrap();
        let frames: Vec<&str> = written
            .lines()
            .map(|line| line.split_once(' ').map_or(line, |(_, rest)| rest))
            .collect();
        assert_eq!(
            frames,
            ["capture-count 701#0102", "capture-count 181#0102"],
            "{written}"
        );
    }

    #[test]
    fn a_cancelled_capture_ends_without_receiving() {
        let (mut sender, mut receiver) = virtual_pair("capture-cancel");
        sender.send(&frame(0x123, &[])).unwrap();
        let cancel = Cancel::new();
        cancel.cancel();
        let summary = capture(&mut *receiver, CaptureLimits::default(), None, &cancel, |event| {
            assert_eq!(event, CaptureEvent::Flush);
            Ok(())
        })
        .unwrap();
        assert_eq!(summary.frames, 0);
    }

    #[test]
    fn a_duration_ends_a_quiet_capture() {
        let (_sender, mut receiver) = virtual_pair("capture-duration");
        let limits = CaptureLimits {
            count: None,
            duration: Some(Duration::from_millis(150)),
        };
        let summary = capture(&mut *receiver, limits, None, &Cancel::new(), |_| Ok(())).unwrap();
        assert_eq!(summary.frames, 0);
        assert!(summary.elapsed >= Duration::from_millis(150), "{summary:?}");
        assert!(summary.elapsed < Duration::from_secs(2), "{summary:?}");
    }

    #[test]
    fn a_failing_front_end_ends_the_capture_with_its_error() {
        let (mut sender, mut receiver) = virtual_pair("capture-output");
        sender.send(&frame(0x123, &[])).unwrap();
        let err = capture(
            &mut *receiver,
            CaptureLimits::default(),
            None,
            &Cancel::new(),
            |event| match event {
                CaptureEvent::Frame(_) => Err(io::Error::from(io::ErrorKind::BrokenPipe)),
                _ => Ok(()),
            },
        )
        .unwrap_err();
        assert!(
            matches!(&err, CaptureError::Output(source) if source.kind() == io::ErrorKind::BrokenPipe),
            "{err}"
        );
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn a_log_that_cannot_be_written_ends_the_capture_after_the_output_is_flushed() {
        let (mut sender, mut receiver) = virtual_pair("capture-fulldisk");
        sender.send(&frame(0x123, &[])).unwrap();
        // /dev/full takes buffered writes and fails the flush, as a full disk does.
        let mut log = LogWriter::create(Path::new("/dev/full"), true).unwrap();
        let limits = CaptureLimits {
            count: Some(1),
            duration: None,
        };
        let mut flushed = false;
        let err = capture(&mut *receiver, limits, Some(&mut log), &Cancel::new(), |event| {
            flushed |= event == CaptureEvent::Flush;
            Ok(())
        })
        .unwrap_err();
        assert!(
            matches!(err, CaptureError::Log(LogFileError::Write { .. })),
            "{err}"
        );
        assert!(flushed);
    }

    #[test]
    fn interface_names_follow_the_spec() {
        let name = |spec: &str| interface_name(&spec.parse().unwrap());
        assert_eq!(name("virtual:demo?bitrate=500k"), "demo");
        assert_eq!(name("socketcand://127.0.0.1:29536/can1"), "can1");
        assert_eq!(name("socketcan:vcan0"), "vcan0");
        assert_eq!(name("udp-multicast://239.74.163.2:43113"), "udp");
    }
}

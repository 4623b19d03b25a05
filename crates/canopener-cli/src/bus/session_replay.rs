//! `canopener demo --monitor`: the recorded session replayed. An in-process socketcand hub, a traffic source replaying a recorded
//! CANopen session (four nodes: boot-up, NMT, SDO expedited/segmented/block, PDOs with SYNC, EMCY, heartbeat,
//! node guarding, LSS, TIME) and the decoding monitor as a second client, so that every layer of the
//! foundation runs end to end with no hardware. It exits non-zero if the monitor missed a frame or decoded
//! anything as a protocol anomaly.

use std::io::Write;
use std::time::Duration;

use canopener_can::bits::frame_bits;
use canopener_can::{Bitrate, CanFrame};
use canopener_runtime::capture::interface_name;
use canopener_runtime::replay::Pace;
use canopener_runtime::session_replay::{ReplayError, ReplayReport, SessionReplay, recorded_session};
use canopener_transport::{BusSpec, spec_from_env_or};

use crate::args::OutputFormat;
use crate::bus::args::SessionReplayArgs;
use crate::bus::monitor::{Monitor, service_key};
use crate::error::{CliError, CliResult, stdout_error};
use crate::output::print_stdout;
use crate::stop::StopFlag;

pub(crate) fn run(args: SessionReplayArgs) -> CliResult {
    let pace = if args.speed == 0.0 {
        Pace::BACK_TO_BACK
    } else {
        Pace::recorded(args.speed).map_err(|_| {
            CliError::Usage(format!(
                "--speed {} must be 0 (no pauses) or a positive factor",
                args.speed
            ))
        })?
    };
    let frames = recorded_session().map_err(demo_error)?;
    let stop = StopFlag::install()?;
    let bus = args
        .bus
        .as_deref()
        .map(|arg| spec_from_env_or(Some(arg)))
        .transpose()?;
    let demo = SessionReplay::open(bus).map_err(demo_error)?;
    let spec = demo.spec().clone();
    let interface = interface_name(&spec);

    let header = format!(
        "canopener demo: replaying a {:.1} s CANopen session ({} frames, 4 nodes) on {spec}{}",
        session_span(&frames).as_secs_f64(),
        frames.len(),
        match &spec {
            BusSpec::Socketcand { host, port, bus } if demo.hub_addr().is_some() => format!(
                "\n  an in-process hub serves it: python-can can join with \
                 can.Bus(interface=\"socketcand\", host=\"{host}\", port={port}, channel=\"{bus}\")"
            ),
            _ => String::new(),
        }
    );
    if args.format == OutputFormat::Text && !args.quiet {
        print_stdout(&format!("{header}\n\n"))?;
    } else {
        eprintln!("{header}");
    }

    let mut out = crate::output::buffered_stdout();
    let mut monitor = Monitor::new(args.format, false);
    let quiet = args.quiet;
    let outcome = demo
        .run(&frames, pace, &stop.token(), |received| {
            let target: &mut dyn Write = if quiet { &mut std::io::sink() } else { &mut out };
            monitor.print_frame(target, received.timestamp, &interface, &received.frame)?;
            // Line-by-line flushing keeps the demo watchable live; throughput is not the point here.
            out.flush()
        })
        .map_err(demo_error)?;
    out.flush().map_err(stdout_error)?;
    drop(out);
    let summary = ReplayFigures {
        outcome,
        monitor: &monitor,
        frames: &frames,
        spec: &spec,
    };
    summary.print(args.format)?;
    summary.verdict()
}

/// The demo's failures as the exit codes it has always had: the bus is the user's, the rest are ours.
fn demo_error(err: ReplayError) -> CliError {
    match err {
        ReplayError::Bus(err) => CliError::Bus(err),
        ReplayError::Output(err) => stdout_error(err),
        other => CliError::Internal(anyhow::anyhow!(other)),
    }
}

fn session_span(frames: &[(canopener_can::Instant, CanFrame)]) -> Duration {
    match (frames.first(), frames.last()) {
        (Some((first, _)), Some((last, _))) => last.saturating_duration_since(*first),
        _ => Duration::ZERO,
    }
}

/// The figures of a replayed session (frames lost, bus load), for the printout and the exit code.
struct ReplayFigures<'a> {
    outcome: ReplayReport,
    monitor: &'a Monitor,
    frames: &'a [(canopener_can::Instant, CanFrame)],
    spec: &'a BusSpec,
}

impl ReplayFigures<'_> {
    fn lost(&self) -> u64 {
        self.outcome.sent.saturating_sub(self.monitor.stats().frames)
    }

    /// The share of a bus at `bitrate` this traffic occupies over the recorded session (exact bit lengths).
    fn load_at(&self, bitrate: Bitrate) -> f64 {
        let bits: u64 = self
            .frames
            .iter()
            .map(|(_, frame)| u64::from(frame_bits(frame).total))
            .sum();
        let span = session_span(self.frames).as_secs_f64();
        if span <= 0.0 {
            0.0
        } else {
            bits as f64 / (span * f64::from(bitrate.bits_per_second()))
        }
    }

    fn print(&self, format: OutputFormat) -> CliResult {
        let stats = self.monitor.stats();
        let rates = [Bitrate::K125, Bitrate::K250, Bitrate::K500, Bitrate::M1];
        let text = match format {
            OutputFormat::Text => {
                let services = stats
                    .by_service
                    .iter()
                    .map(|(service, count)| format!("{service} {count}"))
                    .collect::<Vec<_>>()
                    .join(", ");
                let loads = rates
                    .iter()
                    .map(|rate| format!("{rate}: {:.1} %", self.load_at(*rate) * 100.0))
                    .collect::<Vec<_>>()
                    .join(", ");
                format!(
                    "\nsummary: {} frames sent, {} received by the monitor, {} lost, {} with protocol anomalies, \
                     {:.2} s on {}\n  services: {services}\n  bus load of this session at {loads}\n",
                    self.outcome.sent,
                    stats.frames,
                    self.lost(),
                    stats.frames_with_anomalies,
                    self.outcome.elapsed.as_secs_f64(),
                    self.spec
                )
            }
            OutputFormat::Json => {
                let by_service: serde_json::Map<String, serde_json::Value> = stats
                    .by_service
                    .iter()
                    .map(|(service, count)| (service_key(*service), (*count).into()))
                    .collect();
                let loads: serde_json::Map<String, serde_json::Value> = rates
                    .iter()
                    .map(|rate| (rate.to_string(), self.load_at(*rate).into()))
                    .collect();
                let summary = serde_json::json!({ "summary": {
                    "bus": self.spec.to_string(),
                    "sent": self.outcome.sent,
                    "received": stats.frames,
                    "lost": self.lost(),
                    "frames_with_anomalies": stats.frames_with_anomalies,
                    "elapsed_s": self.outcome.elapsed.as_secs_f64(),
                    "by_service": by_service,
                    "bus_load": loads,
                }});
                format!("{summary}\n")
            }
        };
        print_stdout(&text)
    }

    fn verdict(&self) -> CliResult {
        if self.lost() > 0 {
            return Err(CliError::CheckFailed(format!(
                "the monitor received {} of {} frames: {} lost",
                self.monitor.stats().frames,
                self.outcome.sent,
                self.lost()
            )));
        }
        if self.monitor.stats().frames_with_anomalies > 0 {
            return Err(CliError::CheckFailed(format!(
                "{} frames decoded with protocol anomalies (marked [anomaly: …] above)",
                self.monitor.stats().frames_with_anomalies
            )));
        }
        Ok(())
    }
}

//! `canopener demo`: the embedded default. An in-process socketcand hub, a traffic source replaying a recorded
//! CANopen session (four nodes: boot-up, NMT, SDO expedited/segmented/block, PDOs with SYNC, EMCY, heartbeat,
//! node guarding, LSS, TIME) and the decoding monitor as a second client, so that every layer of the
//! foundation runs end to end with no hardware. It exits non-zero if the monitor missed a frame or decoded
//! anything as a protocol anomaly.

use std::io::{BufWriter, Write};
use std::net::SocketAddr;
use std::thread;
use std::time::{Duration, Instant};

use canopener_can::bits::frame_bits;
use canopener_can::candump::parse_log;
use canopener_can::{Bitrate, CanFrame};
use canopener_hub::HubConfig;
use canopener_transport::{BusSpec, CanBus, open, spec_from_env_or};

use crate::args::OutputFormat;
use crate::bus::args::DemoArgs;
use crate::bus::monitor::{Monitor, MonitorStats, service_key};
use crate::bus::replay::{frames_of, send_timed};
use crate::bus_open::interface_name;
use crate::error::{CliError, CliResult, stdout_error};
use crate::stop::StopFlag;

/// The recorded session, a candump log kept with its generator in `canopener-wire/test_data` (whose tests
/// check it decodes with no anomalies).
pub(crate) const DEMO_LOG: &str = include_str!("../../../canopener-wire/test_data/demo.log");

/// After the source has sent its last frame, how long the monitor waits for stragglers.
const DRAIN_TIMEOUT: Duration = Duration::from_secs(2);

pub(crate) fn run(args: DemoArgs) -> CliResult {
    if !(args.speed.is_finite() && args.speed >= 0.0) {
        return Err(CliError::Usage(format!(
            "--speed {} must be 0 (no pauses) or a positive factor",
            args.speed
        )));
    }
    let frames = demo_frames()?;
    let stop = StopFlag::install()?;
    let (hub, spec) = match args.bus.as_deref() {
        None => {
            let listen: SocketAddr = SocketAddr::from(([127, 0, 0, 1], 0));
            let hub = canopener_hub::spawn(HubConfig::new(listen)).map_err(|err| {
                CliError::Internal(anyhow::anyhow!("cannot start the in-process hub: {err}"))
            })?;
            let addr = hub.local_addr();
            let spec = BusSpec::Socketcand {
                host: addr.ip().to_string(),
                port: addr.port(),
                bus: "can0".into(),
            };
            (Some(hub), spec)
        }
        Some(arg) => (None, spec_from_env_or(Some(arg))?),
    };
    let mut monitor_bus = open(&spec)?;
    let mut source_bus = open(&spec)?;
    let interface = interface_name(&spec);

    let header = format!(
        "canopener demo: replaying a {:.1} s CANopen session ({} frames, 4 nodes) on {spec}{}",
        session_span(&frames).as_secs_f64(),
        frames.len(),
        match &spec {
            BusSpec::Socketcand { host, port, bus } if hub.is_some() => format!(
                "\n  an in-process hub serves it: python-can can join with \
                 can.Bus(interface=\"socketcand\", host=\"{host}\", port={port}, channel=\"{bus}\")"
            ),
            _ => String::new(),
        }
    );
    if args.format == OutputFormat::Text && !args.quiet {
        let mut out = std::io::stdout().lock();
        writeln!(out, "{header}\n")
            .and_then(|()| out.flush())
            .map_err(stdout_error)?;
    } else {
        eprintln!("{header}");
    }

    let expected = frames.len() as u64;
    let monitor_stop = stop.clone();
    let (format, quiet) = (args.format, args.quiet);
    let (done_tx, done_rx) = std::sync::mpsc::channel::<()>();
    let monitor = thread::Builder::new()
        .name("demo-monitor".into())
        .spawn(move || {
            watch(
                &mut *monitor_bus,
                &interface,
                format,
                quiet,
                expected,
                &monitor_stop,
                &done_rx,
            )
        })
        .map_err(|err| CliError::Internal(anyhow::anyhow!("cannot start the monitor thread: {err}")))?;

    let started = Instant::now();
    let speed = (args.speed > 0.0).then_some(args.speed);
    let sent = send_timed(&mut *source_bus, &frames, speed, &stop, |_| {});
    let _ = done_tx.send(());
    let watched = monitor
        .join()
        .map_err(|_| CliError::Internal(anyhow::anyhow!("the monitor thread panicked")))?;
    let elapsed = started.elapsed();
    drop(source_bus);
    if let Some(hub) = hub {
        hub.shutdown();
    }
    let sent = sent?;
    let watched = watched?;
    let summary = Summary {
        sent,
        watched,
        elapsed,
        frames: &frames,
        spec: &spec,
    };
    summary.print(args.format)?;
    summary.verdict()
}

fn demo_frames() -> CliResult<Vec<(canopener_can::Instant, CanFrame)>> {
    let (records, errors) = parse_log(DEMO_LOG);
    if let Some(err) = errors.first() {
        return Err(CliError::Internal(anyhow::anyhow!(
            "the embedded demo log is broken at {err}"
        )));
    }
    Ok(frames_of(records, None).0)
}

fn session_span(frames: &[(canopener_can::Instant, CanFrame)]) -> Duration {
    match (frames.first(), frames.last()) {
        (Some((first, _)), Some((last, _))) => last.saturating_duration_since(*first),
        _ => Duration::ZERO,
    }
}

struct Watched {
    stats: MonitorStats,
}

fn watch(
    bus: &mut dyn CanBus,
    interface: &str,
    format: OutputFormat,
    quiet: bool,
    expected: u64,
    stop: &StopFlag,
    source_done: &std::sync::mpsc::Receiver<()>,
) -> CliResult<Watched> {
    let stdout = std::io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    let mut sink = std::io::sink();
    let mut monitor = Monitor::new(format, false);
    let mut drain_deadline: Option<Instant> = None;
    while monitor.stats().frames < expected && !stop.is_set() {
        if drain_deadline.is_none() && source_done.try_recv().is_ok() {
            drain_deadline = Some(Instant::now() + DRAIN_TIMEOUT);
        }
        if drain_deadline.is_some_and(|deadline| Instant::now() >= deadline) {
            break;
        }
        if let Some(received) = bus.recv(Duration::from_millis(50))? {
            let target: &mut dyn Write = if quiet { &mut sink } else { &mut out };
            monitor
                .print_frame(target, received.timestamp, interface, &received.frame)
                .map_err(stdout_error)?;
            // Line-by-line flushing keeps the demo watchable live; throughput is not the point here.
            out.flush().map_err(stdout_error)?;
        }
    }
    out.flush().map_err(stdout_error)?;
    Ok(Watched {
        stats: monitor.stats().clone(),
    })
}

struct Summary<'a> {
    sent: u64,
    watched: Watched,
    elapsed: Duration,
    frames: &'a [(canopener_can::Instant, CanFrame)],
    spec: &'a BusSpec,
}

impl Summary<'_> {
    fn lost(&self) -> u64 {
        self.sent.saturating_sub(self.watched.stats.frames)
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
        let stats = &self.watched.stats;
        let rates = [Bitrate::K125, Bitrate::K250, Bitrate::K500, Bitrate::M1];
        let mut out = std::io::stdout().lock();
        match format {
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
                writeln!(
                    out,
                    "\nsummary: {} frames sent, {} received by the monitor, {} lost, {} with protocol anomalies, \
                     {:.2} s on {}",
                    self.sent,
                    stats.frames,
                    self.lost(),
                    stats.frames_with_anomalies,
                    self.elapsed.as_secs_f64(),
                    self.spec
                )
                .map_err(stdout_error)?;
                writeln!(out, "  services: {services}").map_err(stdout_error)?;
                writeln!(out, "  bus load of this session at {loads}").map_err(stdout_error)?;
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
                    "sent": self.sent,
                    "received": stats.frames,
                    "lost": self.lost(),
                    "frames_with_anomalies": stats.frames_with_anomalies,
                    "elapsed_s": self.elapsed.as_secs_f64(),
                    "by_service": by_service,
                    "bus_load": loads,
                }});
                writeln!(out, "{summary}").map_err(stdout_error)?;
            }
        }
        Ok(())
    }

    fn verdict(&self) -> CliResult {
        if self.lost() > 0 {
            return Err(CliError::CheckFailed(format!(
                "the monitor received {} of {} frames: {} lost",
                self.watched.stats.frames,
                self.sent,
                self.lost()
            )));
        }
        if self.watched.stats.frames_with_anomalies > 0 {
            return Err(CliError::CheckFailed(format!(
                "{} frames decoded with protocol anomalies (marked [anomaly: …] above)",
                self.watched.stats.frames_with_anomalies
            )));
        }
        Ok(())
    }
}

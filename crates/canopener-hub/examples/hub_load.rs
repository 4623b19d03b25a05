//! Load generator for the hub; prints one JSON line of results per run.
//!
//! ```text
//! cargo run --release -p canopener-hub --example hub_load -- throughput --clients 8 --frames 100000 [--all-send]
//! cargo run --release -p canopener-hub --example hub_load -- latency --samples 20000
//! cargo run --release -p canopener-hub --example hub_load -- buses --buses 16 --rate 9000 --seconds 10
//! ```
//!
//! Every mode starts its own hub in this process (threads named `canopener-hub`, so its CPU time can
//! be read from `/proc/self/task/*/stat` apart from the load generator's), or targets another hub
//! with `--hub HOST:PORT` (then no hub CPU is reported). Clients are blocking sockets on threads and
//! do the python-can handshake.

// A load generator for bench/run.py: it prints its measurements.
#![allow(clippy::print_stdout, clippy::print_stderr)]

use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread;
use std::time::{Duration, Instant as StdInstant};

use canopener_can::{CanFrame, CanId, StandardId};
use canopener_hub::{HUB_THREAD_NAME, HubConfig};
use canopener_socketcand::{ElementReader, ServerMessage, parse_server_message, write_send};
use serde_json::json;

/// Linux's USER_HZ; /proc reports CPU time in these ticks on every mainstream architecture.
const CLOCK_TICKS_PER_SEC: f64 = 100.0;

const USAGE: &str = "usage: hub_load [--hub HOST:PORT] <mode>
  throughput --clients N --frames M [--all-send]   one sender (or all) to every other client
  latency --samples K                              ping-pong round trips between two clients
  buses --buses B --rate R --seconds S             B buses each paced at R frames/s (DLC 8)";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match run(&args) {
        Ok(result) => {
            println!("{result}");
            ExitCode::SUCCESS
        }
        Err(message) => {
            eprintln!("hub_load: {message}\n{USAGE}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: &[String]) -> Result<serde_json::Value, String> {
    let options = Options::parse(args)?;
    let (hub, addr) = match options.hub {
        Some(addr) => (None, addr),
        None => {
            let mut config = HubConfig::new(SocketAddr::from(([127, 0, 0, 1], 0)));
            // Generous stall timeout: a loaded 2-core machine must not make the hub drop a client.
            config.stall_timeout = Duration::from_secs(10);
            let hub = canopener_hub::spawn(config).map_err(|e| format!("could not start a hub: {e}"))?;
            let addr = hub.local_addr();
            (Some(hub), addr)
        }
    };
    let cpu_before = CpuTimes::now();
    let started = StdInstant::now();
    let mut result = match options.mode.as_str() {
        "throughput" => throughput(addr, options.clients, options.frames, options.all_send),
        "latency" => latency(addr, options.samples),
        "buses" => buses(addr, options.buses, options.rate, options.seconds),
        other => return Err(format!("unknown mode `{other}`")),
    }
    .map_err(|e| e.to_string())?;
    let wall = started.elapsed().as_secs_f64();
    if let (Some(before), Some(after)) = (cpu_before, CpuTimes::now()) {
        let hub_secs = (after.hub_ticks - before.hub_ticks) as f64 / CLOCK_TICKS_PER_SEC;
        let all_secs = (after.process_ticks - before.process_ticks) as f64 / CLOCK_TICKS_PER_SEC;
        if hub.is_some() {
            result["hub_cpu_seconds"] = json!(round(hub_secs, 3));
            result["hub_cpu_percent_of_one_core"] = json!(round(100.0 * hub_secs / wall, 1));
        }
        result["loadgen_cpu_seconds"] = json!(round(all_secs - hub_secs, 3));
    }
    result["wall_seconds"] = json!(round(wall, 3));
    result["cores"] = json!(thread::available_parallelism().map(|n| n.get()).unwrap_or(1));
    if let Some(hub) = hub {
        let stats = hub.stats();
        result["hub_frames_in"] = json!(stats.frames_in);
        result["hub_frames_out"] = json!(stats.frames_out);
        result["hub_clients_dropped"] = json!(stats.clients_dropped);
        hub.shutdown();
    }
    Ok(result)
}

#[derive(Debug)]
struct Options {
    mode: String,
    hub: Option<SocketAddr>,
    clients: usize,
    frames: u64,
    all_send: bool,
    samples: usize,
    buses: usize,
    rate: u64,
    seconds: f64,
}

impl Options {
    fn parse(args: &[String]) -> Result<Options, String> {
        let mut options = Options {
            mode: String::new(),
            hub: None,
            clients: 2,
            frames: 100_000,
            all_send: false,
            samples: 10_000,
            buses: 8,
            rate: 9_000,
            seconds: 10.0,
        };
        let mut rest = args.iter();
        while let Some(arg) = rest.next() {
            let mut value = |name: &str| {
                rest.next()
                    .cloned()
                    .ok_or_else(|| format!("{name} needs a value"))
            };
            match arg.as_str() {
                "--hub" => options.hub = Some(parse(&value("--hub")?, "--hub")?),
                "--clients" => options.clients = parse(&value("--clients")?, "--clients")?,
                "--frames" => options.frames = parse(&value("--frames")?, "--frames")?,
                "--all-send" => options.all_send = true,
                "--samples" => options.samples = parse(&value("--samples")?, "--samples")?,
                "--buses" => options.buses = parse(&value("--buses")?, "--buses")?,
                "--rate" => options.rate = parse(&value("--rate")?, "--rate")?,
                "--seconds" => options.seconds = parse(&value("--seconds")?, "--seconds")?,
                mode if !mode.starts_with('-') && options.mode.is_empty() => options.mode = mode.to_owned(),
                other => return Err(format!("unexpected argument `{other}`")),
            }
        }
        if options.mode.is_empty() {
            return Err("no mode given".to_owned());
        }
        if options.clients < 2 || options.buses == 0 || options.rate == 0 || options.samples == 0 {
            return Err("need --clients >= 2, --buses >= 1, --rate >= 1 and --samples >= 1".to_owned());
        }
        if !(options.seconds > 0.0 && options.seconds.is_finite()) {
            return Err("--seconds must be a positive number".to_owned());
        }
        Ok(options)
    }
}

fn parse<T: std::str::FromStr>(text: &str, name: &str) -> Result<T, String> {
    text.parse()
        .map_err(|_| format!("{name}: `{text}` is not a valid value"))
}

fn round(value: f64, decimals: i32) -> f64 {
    let scale = 10f64.powi(decimals);
    (value * scale).round() / scale
}

/// CPU ticks of the whole process and of the hub's threads, from /proc (Linux only).
#[derive(Debug, Clone, Copy)]
struct CpuTimes {
    process_ticks: u64,
    hub_ticks: u64,
}

impl CpuTimes {
    fn now() -> Option<CpuTimes> {
        let process_ticks = stat_ticks(&std::fs::read_to_string("/proc/self/stat").ok()?)?;
        let mut hub_ticks = 0;
        for task in std::fs::read_dir("/proc/self/task").ok()?.flatten() {
            let Ok(stat) = std::fs::read_to_string(task.path().join("stat")) else {
                continue;
            };
            let comm = stat
                .split_once('(')
                .and_then(|(_, rest)| rest.rsplit_once(')'))
                .map(|(comm, _)| comm);
            if comm == Some(HUB_THREAD_NAME) {
                hub_ticks += stat_ticks(&stat).unwrap_or(0);
            }
        }
        Some(CpuTimes {
            process_ticks,
            hub_ticks,
        })
    }
}

/// utime + stime (fields 14 and 15 of `/proc/.../stat`).
fn stat_ticks(stat: &str) -> Option<u64> {
    let (_, after_comm) = stat.rsplit_once(')')?;
    let fields: Vec<&str> = after_comm.split_whitespace().collect();
    // After the comm field, the state is field 3, so utime (14) and stime (15) are at 11 and 12.
    let utime: u64 = fields.get(11)?.parse().ok()?;
    let stime: u64 = fields.get(12)?.parse().ok()?;
    Some(utime + stime)
}

/// The python-can handshake; the stream is in raw mode afterwards.
fn connect(addr: SocketAddr, bus: &str) -> io::Result<TcpStream> {
    let mut stream = TcpStream::connect(addr)?;
    stream.set_nodelay(true)?;
    stream.set_read_timeout(Some(Duration::from_secs(30)))?;
    let mut buf = [0u8; 256];
    for (command, reply) in [
        (None, "< hi >"),
        (Some(format!("< open {bus} >")), "< ok >"),
        (Some("< rawmode >".to_owned()), "< ok >"),
    ] {
        if let Some(command) = command {
            stream.write_all(command.as_bytes())?;
        }
        let n = stream.read(&mut buf)?;
        if buf.get(..n) != Some(reply.as_bytes()) {
            return Err(io::Error::other(format!(
                "handshake: expected {reply:?}, got {:?}",
                String::from_utf8_lossy(buf.get(..n).unwrap_or_default())
            )));
        }
    }
    Ok(stream)
}

fn frame(id: u16, payload: u64) -> CanFrame {
    let id = StandardId::new(id).unwrap_or(StandardId::MAX);
    match CanFrame::new(id, &payload.to_le_bytes()) {
        Ok(frame) => frame,
        Err(_) => unreachable!("8 data bytes always fit a classical frame"),
    }
}

/// Reads until `count` elements arrived, counting `>` bytes (cheap, so the hub gets the CPU).
fn count_elements(stream: &mut TcpStream, count: u64) -> io::Result<()> {
    let mut seen = 0u64;
    let mut buf = vec![0u8; 256 * 1024];
    while seen < count {
        let n = stream.read(&mut buf)?;
        if n == 0 {
            return Err(io::Error::other(format!(
                "hub closed the connection after {seen} of {count} frames"
            )));
        }
        seen += buf
            .get(..n)
            .unwrap_or_default()
            .iter()
            .filter(|&&b| b == b'>')
            .count() as u64;
    }
    Ok(())
}

fn send_frames(stream: &mut TcpStream, id: u16, count: u64) -> io::Result<()> {
    let mut out = Vec::with_capacity(64 * 1024);
    for i in 0..count {
        write_send(&mut out, &frame(id, i));
        if out.len() >= 60 * 1024 {
            stream.write_all(&out)?;
            out.clear();
        }
    }
    stream.write_all(&out)
}

fn throughput(
    addr: SocketAddr,
    clients: usize,
    frames: u64,
    all_send: bool,
) -> io::Result<serde_json::Value> {
    let streams: Vec<TcpStream> = (0..clients)
        .map(|_| connect(addr, "load"))
        .collect::<io::Result<_>>()?;
    // Let the raw-mode grace of the last client pass so no frame waits on it.
    thread::sleep(Duration::from_millis(100));
    let senders = if all_send { clients } else { 1 };
    let started = StdInstant::now();
    let mut threads = Vec::new();
    for (index, stream) in streams.iter().enumerate() {
        let expected = if index < senders {
            (senders as u64 - 1) * frames
        } else {
            senders as u64 * frames
        };
        let mut reader = stream.try_clone()?;
        threads.push(thread::spawn(move || count_elements(&mut reader, expected)));
        if index < senders {
            let mut writer = stream.try_clone()?;
            // `index < senders <= clients`, and clients are few, so the id stays below 0x800.
            let id = 0x100 + index as u16;
            threads.push(thread::spawn(move || send_frames(&mut writer, id, frames)));
        }
    }
    for handle in threads {
        handle
            .join()
            .map_err(|_| io::Error::other("a client thread panicked"))??;
    }
    let elapsed = started.elapsed().as_secs_f64();
    let sent = senders as u64 * frames;
    let delivered = sent * (clients as u64 - 1);
    Ok(json!({
        "mode": "throughput",
        "clients": clients,
        "senders": senders,
        "frames_per_sender": frames,
        "frames_sent": sent,
        "frames_delivered": delivered,
        "seconds": round(elapsed, 3),
        "sent_per_second": round(sent as f64 / elapsed, 0),
        "delivered_per_second": round(delivered as f64 / elapsed, 0),
    }))
}

fn latency(addr: SocketAddr, samples: usize) -> io::Result<serde_json::Value> {
    const WARMUP: usize = 200;
    let mut pinger = connect(addr, "latency")?;
    let mut ponger = connect(addr, "latency")?;
    thread::sleep(Duration::from_millis(100));
    let total = WARMUP + samples;
    let echo = thread::spawn(move || -> io::Result<()> {
        let mut reader = ElementReader::default();
        let mut buf = [0u8; 4096];
        let mut out = Vec::new();
        let mut answered = 0;
        while answered < total {
            let n = ponger.read(&mut buf)?;
            if n == 0 {
                return Err(io::Error::other("hub closed the echo client"));
            }
            reader.push(buf.get(..n).unwrap_or_default());
            out.clear();
            while let Some(element) = reader.next_element() {
                if let Ok(Ok(ServerMessage::Frame { frame, .. })) =
                    element.as_deref().map(parse_server_message)
                {
                    let reply =
                        CanFrame::new(CanId::standard(0x581).map_err(io::Error::other)?, frame.data())
                            .map_err(io::Error::other)?;
                    write_send(&mut out, &reply);
                    answered += 1;
                }
            }
            ponger.write_all(&out)?;
        }
        Ok(())
    });
    let mut reader = ElementReader::default();
    let mut buf = [0u8; 4096];
    let mut round_trips = Vec::with_capacity(samples);
    let mut out = Vec::new();
    for i in 0..total {
        out.clear();
        write_send(&mut out, &frame(0x601, i as u64));
        let started = StdInstant::now();
        pinger.write_all(&out)?;
        let mut answered = false;
        while !answered {
            if let Some(element) = reader.next_element() {
                answered = matches!(
                    element.as_deref().map(parse_server_message),
                    Ok(Ok(ServerMessage::Frame { .. }))
                );
                continue;
            }
            let n = pinger.read(&mut buf)?;
            if n == 0 {
                return Err(io::Error::other("hub closed the ping client"));
            }
            reader.push(buf.get(..n).unwrap_or_default());
        }
        if i >= WARMUP {
            round_trips.push(started.elapsed());
        }
    }
    echo.join()
        .map_err(|_| io::Error::other("echo thread panicked"))??;
    round_trips.sort_unstable();
    let percentile = |p: f64| {
        let index = ((round_trips.len() as f64 - 1.0) * p).round() as usize;
        round_trips
            .get(index)
            .map_or(0.0, |d| round(d.as_secs_f64() * 1e6, 1))
    };
    let mean = round_trips.iter().sum::<Duration>().as_secs_f64() * 1e6 / round_trips.len().max(1) as f64;
    Ok(json!({
        "mode": "latency",
        "samples": round_trips.len(),
        "rtt_us_p50": percentile(0.50),
        "rtt_us_p90": percentile(0.90),
        "rtt_us_p99": percentile(0.99),
        "rtt_us_max": percentile(1.0),
        "rtt_us_mean": round(mean, 1),
        "round_trips_per_second": round(1e6 / mean.max(f64::MIN_POSITIVE), 0),
    }))
}

/// What one bus's receiver measured.
#[derive(Debug, Clone, Copy, Default)]
struct BusResult {
    received: u64,
    max_lag: Duration,
    lag_sum: Duration,
    late_over_10ms: u64,
}

fn buses(addr: SocketAddr, buses: usize, rate: u64, seconds: f64) -> io::Result<serde_json::Value> {
    let expected = (rate as f64 * seconds).round() as u64;
    let mut pairs = Vec::new();
    for bus in 0..buses {
        let name = format!("bus{bus}");
        pairs.push((connect(addr, &name)?, connect(addr, &name)?));
    }
    thread::sleep(Duration::from_millis(100));
    let epoch = StdInstant::now();
    let failed = Arc::new(AtomicBool::new(false));
    let mut senders = Vec::new();
    let mut receivers = Vec::new();
    for (mut sender, mut receiver) in pairs {
        let sender_failed = Arc::clone(&failed);
        senders.push(thread::spawn(move || -> io::Result<u64> {
            // Paced in 1 ms ticks: each tick sends what is due, as a saturated bus would deliver it.
            let mut sent = 0u64;
            let mut out = Vec::with_capacity(4096);
            while sent < expected && !sender_failed.load(Ordering::Relaxed) {
                let due = ((epoch.elapsed().as_secs_f64() * rate as f64) as u64).min(expected);
                out.clear();
                while sent < due {
                    let now_ns = u64::try_from(epoch.elapsed().as_nanos()).unwrap_or(u64::MAX);
                    write_send(&mut out, &frame(0x181, now_ns));
                    sent += 1;
                }
                sender.write_all(&out)?;
                thread::sleep(Duration::from_millis(1));
            }
            Ok(sent)
        }));
        let receiver_failed = Arc::clone(&failed);
        receivers.push(thread::spawn(move || -> io::Result<BusResult> {
            let mut result = BusResult::default();
            let mut reader = ElementReader::default();
            let mut buf = vec![0u8; 64 * 1024];
            while result.received < expected {
                let n = match receiver.read(&mut buf) {
                    Ok(0) => break,
                    Ok(n) => n,
                    Err(error) => {
                        receiver_failed.store(true, Ordering::Relaxed);
                        return Err(error);
                    }
                };
                let now = epoch.elapsed();
                reader.push(buf.get(..n).unwrap_or_default());
                while let Some(element) = reader.next_element() {
                    let Ok(Ok(ServerMessage::Frame { frame, .. })) =
                        element.as_deref().map(parse_server_message)
                    else {
                        continue;
                    };
                    let mut sent_ns = [0u8; 8];
                    sent_ns.copy_from_slice(frame.data().get(..8).unwrap_or(&[0; 8]));
                    let lag = now.saturating_sub(Duration::from_nanos(u64::from_le_bytes(sent_ns)));
                    result.received += 1;
                    result.max_lag = result.max_lag.max(lag);
                    result.lag_sum += lag;
                    if lag > Duration::from_millis(10) {
                        result.late_over_10ms += 1;
                    }
                }
            }
            Ok(result)
        }));
    }
    let mut sent_total = 0;
    for handle in senders {
        sent_total += handle.join().map_err(|_| io::Error::other("sender panicked"))??;
    }
    let mut results = Vec::new();
    for handle in receivers {
        results.push(
            handle
                .join()
                .map_err(|_| io::Error::other("receiver panicked"))??,
        );
    }
    let elapsed = epoch.elapsed().as_secs_f64();
    let received_total: u64 = results.iter().map(|r| r.received).sum();
    let max_lag = results.iter().map(|r| r.max_lag).max().unwrap_or_default();
    let mean_lag =
        results.iter().map(|r| r.lag_sum).sum::<Duration>().as_secs_f64() / received_total.max(1) as f64;
    let min_received = results.iter().map(|r| r.received).min().unwrap_or(0);
    let late: u64 = results.iter().map(|r| r.late_over_10ms).sum();
    // Kept pace: every frame arrived and none waited more than 50 ms (a few hundred frame times).
    let kept_pace = min_received == expected && max_lag < Duration::from_millis(50);
    Ok(json!({
        "mode": "buses",
        "buses": buses,
        "rate_per_bus": rate,
        "seconds": seconds,
        "frames_expected_per_bus": expected,
        "frames_sent": sent_total,
        "frames_received": received_total,
        "min_frames_received_on_a_bus": min_received,
        "delivered_per_second_per_bus": round(received_total as f64 / buses as f64 / elapsed, 0),
        "delivered_per_second_total": round(received_total as f64 / elapsed, 0),
        "mean_lag_ms": round(mean_lag * 1e3, 3),
        "max_lag_ms": round(max_lag.as_secs_f64() * 1e3, 3),
        "frames_later_than_10ms": late,
        "kept_pace": kept_pace,
    }))
}

//! SDO client throughput (CiA 301 §7.2.4.3, "SDO protocols"): how close [`SdoClient`] gets to the
//! wire, and how fast it is against a real server over the socketcand hub.
//!
//! ```text
//! sdo_throughput virtual
//! sdo_throughput hub SPEC NODE_ID EDS KIND ROUNDS [FIRST_ROUND]
//! ```
//!
//! `virtual` puts the client on one port of a bit-accurate 1 Mbit/s [`BusEngine`] and a
//! `canopener_device` [`Device`] (the checker's `base.eds`, node 22h, plus a 10 000-byte DOMAIN and
//! an UNSIGNED32) on another, on virtual time with zero processing time on both sides: every frame is
//! arbitrated and lasts its exact stuffed length, each side gets the other's frame at the end of
//! its EOF, and timers run at their deadlines. What is left is protocol efficiency against the wire:
//! expedited, segmented and block (blksize 127, CRC on) uploads and downloads, each compared with the
//! physical limits of the interop notes §4 (1 Mbit/s, zero turnaround) and with the limit of the
//! very frames that went over the bus. It also reports how fast the simulation itself ran (frames
//! per second of wall-clock time: the two protocol cores plus the bus engine). Prints JSON.
//!
//! `hub` connects to a socketcand server (`socketcand://HOST:PORT/BUS`, e.g. `canopener bus serve`)
//! and runs one kind of transfer ROUNDS times against node NODE_ID on the wall clock, with the same
//! objects, values and checks as `bench/sdo_client.py`'s python canopen client, so the two compare:
//! 1018h:01 (expected as in the EDS), the UNSIGNED32 2007h and 889 bytes to and from the DOMAIN 200Fh
//! of gocanopen's `base.eds`. KIND is one of `expedited_upload`, `expedited_download`,
//! `segmented_download`, `segmented_upload`, `block_download`, `block_upload`; the values written
//! depend on the round number, which starts at FIRST_ROUND (default 0). Every transfer is verified
//! untimed: uploads against bytes written beforehand, downloads by reading them back. Prints one
//! JSON object: `{"kind", "ok", "failed", "error", "times_s"}`.

// This is a measurement program, not library code: it opens buses and reads the clock, so the
// workspace's sans-IO bans and its no-printing rule do not apply here.
#![allow(clippy::disallowed_methods, clippy::print_stdout, clippy::print_stderr)]

use canopener_can::Core;
use std::error::Error;
use std::process::ExitCode;
use std::time::Duration;

use canopener_bus_engine::{BusConfig, BusEngine, BusStats, Port};
use canopener_can::bits::INTERMISSION_BITS;
use canopener_can::{Bitrate, Instant};
use canopener_device::application::NoApplication;
use canopener_device::device::Device;
use canopener_device::od_build::build_od;
use canopener_master::sdo_client::{
    DownloadMode, Protocol, SdoClient, SdoClientError, SdoClientEvent, UploadMode,
};
use canopener_od::{Access, DataType, DynamicOd, Entry, ObjectKey};
use canopener_transport::{BusSpec, CanBus, WallClock};
use serde_json::{Value, json};

type BoxError = Box<dyn Error>;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let res = match args.first().map(String::as_str) {
        Some("virtual") => virtual_bus(),
        Some("hub") => hub(&args[1..]),
        _ => Err(USAGE.into()),
    };
    match res {
        Ok(report) => {
            println!("{report:#}");
            ExitCode::SUCCESS
        }
        Err(err) => {
            eprintln!("sdo_throughput: {err}");
            ExitCode::FAILURE
        }
    }
}

const USAGE: &str =
    "usage: sdo_throughput virtual | sdo_throughput hub SPEC NODE_ID EDS KIND ROUNDS [FIRST_ROUND]";

/// One kind of transfer of the workload.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    ExpeditedUpload,
    ExpeditedDownload,
    SegmentedDownload,
    SegmentedUpload,
    BlockDownload,
    BlockUpload,
}

impl Kind {
    const ALL: [Kind; 6] = [
        Kind::ExpeditedUpload,
        Kind::ExpeditedDownload,
        Kind::SegmentedDownload,
        Kind::SegmentedUpload,
        Kind::BlockDownload,
        Kind::BlockUpload,
    ];

    fn name(self) -> &'static str {
        match self {
            Kind::ExpeditedUpload => "expedited_upload",
            Kind::ExpeditedDownload => "expedited_download",
            Kind::SegmentedDownload => "segmented_download",
            Kind::SegmentedUpload => "segmented_upload",
            Kind::BlockDownload => "block_download",
            Kind::BlockUpload => "block_upload",
        }
    }

    fn parse(text: &str) -> Option<Kind> {
        Kind::ALL.into_iter().find(|kind| kind.name() == text)
    }

    fn protocol(self) -> Protocol {
        match self {
            Kind::ExpeditedUpload | Kind::ExpeditedDownload => Protocol::Expedited,
            Kind::SegmentedDownload | Kind::SegmentedUpload => Protocol::Segmented,
            Kind::BlockDownload | Kind::BlockUpload => Protocol::Block,
        }
    }

    fn is_upload(self) -> bool {
        matches!(
            self,
            Kind::ExpeditedUpload | Kind::SegmentedUpload | Kind::BlockUpload
        )
    }

    /// The frames CiA 301 §7.2.4.3 needs for `len` bytes with sub-blocks of 127 segments:
    /// expedited 2; segmented the initiate pair plus a segment and its answer per 7 bytes; block
    /// download the initiate pair, the segments, one acknowledge per sub-block and the end pair;
    /// block upload the same plus the client's "start upload".
    fn frames(self, len: usize) -> usize {
        let segments = len.div_ceil(7).max(1);
        let sub_blocks = segments.div_ceil(127);
        match self.protocol() {
            Protocol::Expedited => 2,
            Protocol::Segmented => 2 + 2 * segments,
            Protocol::Block => 4 + segments + sub_blocks + usize::from(self.is_upload()),
        }
    }

    /// The limit at 1 Mbit/s with zero turnaround time from the interop notes §4 (best / typical /
    /// worst: 111 / 125 / 135-bit frames); transfers/s for expedited, bytes/s otherwise (the long-
    /// transfer rates: 7 bytes per 2 frames segmented, 889 bytes per 128 frames block).
    fn reference_limit(self) -> (f64, f64, f64) {
        match self.protocol() {
            Protocol::Expedited => (4505.0, 4000.0, 3704.0),
            Protocol::Segmented => (31_532.0, 28_000.0, 25_926.0),
            Protocol::Block => (62_570.0, 55_562.0, 51_447.0),
        }
    }
}

/// 889 printable bytes (127 segments, one full sub-block) or any other length, different for every
/// round so that a stale value never passes a check; the same bytes `bench/sdo_client.py` uses.
fn payload(len: usize, round: usize) -> Vec<u8> {
    (0..len).map(|idx| 0x41 + ((idx + round) % 26) as u8).collect()
}

/// The 4-byte value of an expedited download in round `round`.
fn word(round: usize) -> Vec<u8> {
    let value = 0x9E37_79B9u32.wrapping_mul(round as u32 + 1);
    value.to_le_bytes().to_vec()
}

/// The outcome of one transfer, progress reports left out.
fn outcome(event: SdoClientEvent, kind: Kind) -> Result<Option<Vec<u8>>, String> {
    match event {
        SdoClientEvent::Uploaded { data, protocol, .. } if protocol == kind.protocol() => Ok(Some(data)),
        SdoClientEvent::Downloaded { protocol, .. } if protocol == kind.protocol() => Ok(None),
        SdoClientEvent::Failed { error, .. } => Err(error.to_string()),
        other => Err(format!("{}: unexpected outcome {other:?}", kind.name())),
    }
}

fn check_same(got: &[u8], expected: &[u8]) -> Result<(), String> {
    if got == expected {
        Ok(())
    } else {
        Err(format!(
            "wrong data: {} bytes, expected {}",
            got.len(),
            expected.len()
        ))
    }
}

// --- virtual bus ------------------------------------------------------------------------------

const BITRATE: Bitrate = Bitrate::M1;
const NODE: u8 = 0x22;
const BASE: &str = canopener_testkit::fixture::BASE_EDS;
/// 1018h:01 Vendor-ID of `base.eds`: 0000 0ABCh.
const VENDOR_ID: ObjectKey = ObjectKey::new(0x1018, 1);
const VENDOR_ID_VALUE: [u8; 4] = [0xBC, 0x0A, 0, 0];
/// Added to `base.eds`: a DOMAIN that takes the 10 000-byte values and a writable UNSIGNED32.
const DOMAIN: ObjectKey = ObjectKey::new(0x2100, 0);
const U32: ObjectKey = ObjectKey::new(0x2101, 0);
const EXPEDITED_ROUNDS: usize = 2000;
/// Rounds per large size; every round takes the same virtual time (the run is deterministic), the
/// rounds only give the wall-clock figure enough frames to average over.
const LARGE: [(usize, usize); 2] = [(889, 100), (10_000, 20)];

/// The client and the device on one bit-accurate bus, on virtual time.
struct VirtualNet {
    bus: BusEngine,
    client_port: Port,
    device_port: Port,
    client: SdoClient,
    dev: Device,
    now: Instant,
}

/// What the transfers of one scenario took.
#[derive(Debug, Default)]
struct Totals {
    stats: BusStats,
    /// Wall-clock time spent driving the client, the device and the bus engine.
    wall: Duration,
}

impl VirtualNet {
    fn new() -> Result<VirtualNet, BoxError> {
        let eds = canopener_eds::load(&std::fs::read(BASE)?).eds;
        let built = build_od(&eds, NODE)?;
        let extra = [
            Entry::new(DOMAIN, DataType::DOMAIN, Access::Rw, &[])?,
            Entry::new(U32, DataType::UNSIGNED32, Access::Rw, &[0; 4])?,
        ];
        // The built dictionary is sized exactly for its entries, so it is rebuilt with room for two.
        let entries: Vec<Entry> = built.od.entries().iter().cloned().chain(extra).collect();
        let od = DynamicOd::from_entries(entries.len(), entries)?;
        let mut dev = Device::new(od, NODE, Box::new(NoApplication))?;
        dev.boot(Instant::ZERO);
        // The boot-up message is not part of any measurement.
        while dev.poll_transmit().is_some() {}
        let mut bus = BusEngine::new(BusConfig { bitrate: BITRATE });
        let client_port = bus.attach();
        let device_port = bus.attach();
        Ok(VirtualNet {
            bus,
            client_port,
            device_port,
            client: SdoClient::new(NODE)?,
            dev,
            now: Instant::ZERO,
        })
    }

    /// Starts a transfer at the current instant and drives the bus until the client has reported
    /// its outcome and the bus has carried every frame; adds the frames and the wall-clock time it
    /// took to `totals`. The next transfer starts at once, when the client has its outcome, which
    /// is while the last frame's intermission still runs.
    fn transfer(
        &mut self,
        totals: &mut Totals,
        start: impl FnOnce(&mut SdoClient, Instant) -> Result<(), SdoClientError>,
    ) -> Result<SdoClientEvent, BoxError> {
        let began = self.now;
        let stats_before = self.bus.stats();
        let wall = std::time::Instant::now();
        start(&mut self.client, self.now)?;
        let mut done = None;
        // The longest transfer of the workload takes 0.34 s of bus time; a stuck one must not spin
        // forever.
        let give_up = began + Duration::from_secs(10);
        loop {
            self.exchange()?;
            while let Some(event) = self.client.poll_event() {
                if !matches!(event, SdoClientEvent::Progress { .. }) {
                    done = Some(event);
                }
            }
            // Once the client has its outcome only frames still on the bus matter; a timer the
            // device may have running for later must not stretch the measurement.
            let next = match done {
                Some(_) => self.bus.poll_timeout(),
                None => [
                    self.bus.poll_timeout(),
                    self.client.poll_timeout(),
                    self.dev.poll_timeout(),
                ]
                .into_iter()
                .flatten()
                .min(),
            };
            match (next, done.take()) {
                (None, Some(event)) => {
                    totals.wall += wall.elapsed();
                    let after = self.bus.stats();
                    totals.stats.frames += after.frames - stats_before.frames;
                    totals.stats.bits += after.bits - stats_before.bits;
                    totals.stats.busy += after.busy - stats_before.busy;
                    return Ok(event);
                }
                (Some(next), event) if next <= give_up => {
                    done = event;
                    self.advance(next);
                }
                (next, _) => {
                    return Err(format!(
                        "the transfer stalled at {} µs (next deadline {next:?})",
                        self.now.as_micros()
                    )
                    .into());
                }
            }
        }
    }

    /// Hands every frame either side wants to send to the bus, and every frame the bus delivered
    /// to the other side, until nothing moves.
    fn exchange(&mut self) -> Result<(), BoxError> {
        loop {
            let mut moved = false;
            while let Some(frame) = self.client.poll_transmit() {
                self.bus.submit(self.now, self.client_port, frame)?;
                moved = true;
            }
            while let Some(frame) = self.dev.poll_transmit() {
                self.bus.submit(self.now, self.device_port, frame)?;
                moved = true;
            }
            while self.dev.poll_event().is_some() {}
            while let Some(delivery) = self.bus.poll_delivery() {
                moved = true;
                if delivery.from == self.client_port {
                    self.dev.handle_frame(delivery.at, &delivery.frame);
                } else {
                    self.client.handle_frame(delivery.at, &delivery.frame);
                }
            }
            if !moved {
                return Ok(());
            }
        }
    }

    /// The instant the bus is idle again after the last frame delivered: receivers have a frame
    /// at the end of its EOF, 3 intermission bits before the next SOF may start.
    fn bus_free(&self) -> Instant {
        self.now + BITRATE.bits_duration(u64::from(INTERMISSION_BITS))
    }

    fn advance(&mut self, to: Instant) {
        self.now = self.now.max(to);
        self.bus.handle_timeout(self.now);
        if self.client.poll_timeout().is_some_and(|due| due <= self.now) {
            self.client.handle_timeout(self.now);
        }
        if self.dev.poll_timeout().is_some_and(|due| due <= self.now) {
            self.dev.handle_timeout(self.now);
        }
    }

    /// One round of `kind` with `len` bytes: the value is set (uploads) or checked (downloads)
    /// directly in the device's dictionary, outside the measurement.
    fn round(&mut self, totals: &mut Totals, kind: Kind, len: usize, round: usize) -> Result<(), BoxError> {
        let (key, value) = match kind {
            Kind::ExpeditedUpload => (VENDOR_ID, VENDOR_ID_VALUE.to_vec()),
            Kind::ExpeditedDownload => (U32, word(round)),
            _ => (DOMAIN, payload(len, round)),
        };
        if kind.is_upload() && key != VENDOR_ID {
            self.dev.od_mut().set_value(key, &value)?;
        }
        let event = if kind.is_upload() {
            let mode = match kind.protocol() {
                Protocol::Block => UploadMode::Block,
                _ => UploadMode::Normal,
            };
            self.transfer(totals, |client, now| client.upload(now, key.index, key.sub, mode))?
        } else {
            let mode = match kind.protocol() {
                Protocol::Expedited => DownloadMode::Expedited,
                Protocol::Segmented => DownloadMode::Segmented,
                Protocol::Block => DownloadMode::Block,
            };
            let data = value.clone();
            self.transfer(totals, |client, now| {
                client.download(now, key.index, key.sub, data, mode)
            })?
        };
        let got = match outcome(event, kind)? {
            Some(uploaded) => uploaded,
            None => self.dev.od().read(key)?.to_vec(),
        };
        Ok(check_same(&got, &value)?)
    }
}

fn virtual_bus() -> Result<Value, BoxError> {
    let mut net = VirtualNet::new()?;
    let mut scenarios = Vec::new();
    let mut all = Totals::default();
    let mut plan: Vec<(Kind, usize, usize)> = vec![
        (Kind::ExpeditedUpload, 4, EXPEDITED_ROUNDS),
        (Kind::ExpeditedDownload, 4, EXPEDITED_ROUNDS),
    ];
    for kind in &Kind::ALL[2..] {
        plan.extend(LARGE.map(|(len, rounds)| (*kind, len, rounds)));
    }
    for (kind, len, rounds) in plan {
        // Each scenario starts on an idle bus and ends when the bus is idle again, so that its
        // elapsed time and the bus time of its frames cover the same span.
        net.now = net.bus_free();
        let began = net.now;
        let mut totals = Totals::default();
        for round in 0..rounds {
            net.round(&mut totals, kind, len, round)
                .map_err(|err| format!("{} of {len} bytes, round {round}: {err}", kind.name()))?;
        }
        let elapsed = net.bus_free() - began;
        scenarios.push(scenario_json(kind, len, rounds, elapsed, &totals));
        all.stats.frames += totals.stats.frames;
        all.wall += totals.wall;
    }
    let total_wall = all.wall.as_secs_f64();
    Ok(json!({
        "bitrate": BITRATE.bits_per_second(),
        "node_id": NODE,
        "eds": "crates/canopener-check/test_data/checks/base.eds + DOMAIN 2100h + UNSIGNED32 2101h",
        "block_size": 127,
        "crc": true,
        "scenarios": scenarios,
        "total": {
            "frames": all.stats.frames,
            "wall_s": total_wall,
            "frames_per_wall_s": all.stats.frames as f64 / total_wall,
        },
    }))
}

fn scenario_json(kind: Kind, len: usize, rounds: usize, elapsed: Duration, totals: &Totals) -> Value {
    let elapsed = elapsed.as_secs_f64();
    let busy = totals.stats.busy.as_secs_f64();
    let bytes = (len * rounds) as f64;
    let wire = totals.stats.bits as f64 / f64::from(BITRATE.bits_per_second());
    let (best, typical, worst) = kind.reference_limit();
    let (measured, exact_limit) = match kind.protocol() {
        Protocol::Expedited => (rounds as f64 / elapsed, rounds as f64 / wire),
        _ => (bytes / elapsed, bytes / wire),
    };
    let expected_frames = kind.frames(len);
    let typical_for_size = match kind.protocol() {
        Protocol::Expedited => 1.0 / (expected_frames as f64 * 125e-6),
        _ => len as f64 / (expected_frames as f64 * 125e-6),
    };
    json!({
        "kind": kind.name(),
        "bytes": len,
        "rounds": rounds,
        "unit": if kind.protocol() == Protocol::Expedited { "transfers/s" } else { "B/s" },
        "frames": totals.stats.frames,
        "frames_per_transfer": totals.stats.frames as f64 / rounds as f64,
        "expected_frames_per_transfer": expected_frames,
        "bits": totals.stats.bits,
        "bits_per_frame": totals.stats.bits as f64 / totals.stats.frames as f64,
        "virtual_s": elapsed,
        "busy_s": busy,
        "wire_utilisation": busy / elapsed,
        "measured": measured,
        "transfers_per_s": rounds as f64 / elapsed,
        "ms_per_transfer": elapsed * 1e3 / rounds as f64,
        "reference_limit": {"best": best, "typical": typical, "worst": worst},
        "pct_of_reference_typical": 100.0 * measured / typical,
        "typical_limit_for_size": typical_for_size,
        "pct_of_typical_for_size": 100.0 * measured / typical_for_size,
        "exact_frames_limit": exact_limit,
        "pct_of_exact_frames_limit": 100.0 * measured / exact_limit,
        "wall_s": totals.wall.as_secs_f64(),
        "frames_per_wall_s": totals.stats.frames as f64 / totals.wall.as_secs_f64(),
    })
}

// --- over a socketcand hub, on the wall clock ---------------------------------------------------

/// The objects of gocanopen's `base.eds` that `bench/sdo_client.py` and `bench/sdo_server.py` use.
const HUB_IDENTITY: ObjectKey = ObjectKey::new(0x1018, 1);
const HUB_U32: ObjectKey = ObjectKey::new(0x2007, 0);
const HUB_DOMAIN: ObjectKey = ObjectKey::new(0x200F, 0);
const HUB_LARGE: usize = 889;
/// How long to wait for the server to answer its first request (it may still be booting, and the
/// hub holds traffic back for a moment after a client connects).
const READY_TIMEOUT: Duration = Duration::from_secs(15);

/// The client on a real transport, driven by the wall clock.
struct HubLink {
    bus: Box<dyn CanBus>,
    client: SdoClient,
}

impl HubLink {
    /// Runs one transfer to its outcome; returns it and the time it took.
    fn transfer(
        &mut self,
        start: impl FnOnce(&mut SdoClient, Instant) -> Result<(), SdoClientError>,
    ) -> Result<(SdoClientEvent, Duration), BoxError> {
        let began = WallClock::now();
        start(&mut self.client, began)?;
        loop {
            while let Some(frame) = self.client.poll_transmit() {
                self.bus.send(&frame)?;
            }
            let mut done = None;
            while let Some(event) = self.client.poll_event() {
                if !matches!(event, SdoClientEvent::Progress { .. }) {
                    done = Some(event);
                }
            }
            if let Some(event) = done {
                // A block upload ends with the client's own frame, sent above.
                return Ok((event, WallClock::now() - began));
            }
            let now = WallClock::now();
            let wait = self
                .client
                .poll_timeout()
                .map_or(Duration::from_millis(100), |due| due - now);
            if let Some(received) = self.bus.recv(wait)? {
                self.client.handle_frame(WallClock::now(), &received.frame);
            }
            // Other traffic (the server's heartbeat) must not hold a due timeout back.
            let now = WallClock::now();
            if self.client.poll_timeout().is_some_and(|due| due <= now) {
                self.client.handle_timeout(now);
            }
        }
    }

    fn upload(&mut self, key: ObjectKey, mode: UploadMode) -> Result<(Vec<u8>, Duration), BoxError> {
        let (event, took) = self.transfer(|client, now| client.upload(now, key.index, key.sub, mode))?;
        match event {
            SdoClientEvent::Uploaded { data, .. } => Ok((data, took)),
            SdoClientEvent::Failed { error, .. } => Err(error.into()),
            other => Err(format!("unexpected outcome {other:?}").into()),
        }
    }

    fn download(&mut self, key: ObjectKey, data: &[u8], mode: DownloadMode) -> Result<Duration, BoxError> {
        let data = data.to_vec();
        let (event, took) =
            self.transfer(|client, now| client.download(now, key.index, key.sub, data, mode))?;
        match event {
            SdoClientEvent::Downloaded { .. } => Ok(took),
            SdoClientEvent::Failed { error, .. } => Err(error.into()),
            other => Err(format!("unexpected outcome {other:?}").into()),
        }
    }

    fn wait_until_answering(&mut self) -> Result<(), BoxError> {
        let deadline = WallClock::now() + READY_TIMEOUT;
        loop {
            match self.upload(HUB_IDENTITY, UploadMode::Normal) {
                Ok(_) => return Ok(()),
                Err(err) if WallClock::now() >= deadline => {
                    return Err(format!("the server did not answer within {READY_TIMEOUT:?}: {err}").into());
                }
                Err(_) => std::thread::sleep(Duration::from_millis(50)),
            }
        }
    }

    /// One round of `kind`: the setup and the check are untimed SDO transfers (a segmented or
    /// expedited download before an upload, a normal upload after a download).
    fn round(&mut self, kind: Kind, round: usize, identity: &[u8]) -> Result<Duration, BoxError> {
        let took = match kind {
            Kind::ExpeditedUpload => {
                let (got, took) = self.upload(HUB_IDENTITY, UploadMode::Normal)?;
                check_same(&got, identity)?;
                took
            }
            Kind::ExpeditedDownload => {
                let value = word(round);
                let took = self.download(HUB_U32, &value, DownloadMode::Expedited)?;
                check_same(&self.upload(HUB_U32, UploadMode::Normal)?.0, &value)?;
                took
            }
            Kind::SegmentedDownload | Kind::BlockDownload => {
                let value = payload(HUB_LARGE, round);
                let mode = match kind {
                    Kind::BlockDownload => DownloadMode::Block,
                    _ => DownloadMode::Segmented,
                };
                let took = self.download(HUB_DOMAIN, &value, mode)?;
                check_same(&self.upload(HUB_DOMAIN, UploadMode::Normal)?.0, &value)?;
                took
            }
            Kind::SegmentedUpload | Kind::BlockUpload => {
                let value = payload(HUB_LARGE, round);
                self.download(HUB_DOMAIN, &value, DownloadMode::Segmented)?;
                let mode = match kind {
                    Kind::BlockUpload => UploadMode::Block,
                    _ => UploadMode::Normal,
                };
                let (got, took) = self.upload(HUB_DOMAIN, mode)?;
                check_same(&got, &value)?;
                took
            }
        };
        Ok(took)
    }
}

fn hub(args: &[String]) -> Result<Value, BoxError> {
    let (spec, node, eds, kind, rounds, first_round) = match args {
        [spec, node, eds, kind, rounds] => (spec, node, eds, kind, rounds, 0),
        [spec, node, eds, kind, rounds, first] => (spec, node, eds, kind, rounds, first.parse()?),
        _ => return Err(USAGE.into()),
    };
    let spec: BusSpec = spec.parse()?;
    let node = parse_node(node)?;
    let kind = Kind::parse(kind).ok_or_else(|| format!("unknown kind {kind:?}; {USAGE}"))?;
    let rounds: usize = rounds.parse()?;
    // The expected 1018h:01 is whatever the EDS says, as python canopen's RemoteNode reads it.
    let built = build_od(&canopener_eds::load(&std::fs::read(eds)?).eds, node)?;
    let identity = built.od.read(HUB_IDENTITY)?.to_vec();
    let mut link = HubLink {
        bus: canopener_transport::open(&spec)?,
        client: SdoClient::new(node)?,
    };
    link.wait_until_answering()?;
    let mut times = Vec::with_capacity(rounds);
    let mut error = None;
    for round in first_round..first_round + rounds {
        match link.round(kind, round, &identity) {
            Ok(took) => times.push(took.as_secs_f64()),
            Err(err) => {
                // Nothing wrong is ever timed as a success: the first failure ends this kind.
                error = Some(err.to_string());
                break;
            }
        }
    }
    Ok(json!({
        "client": "canopener",
        "kind": kind.name(),
        "ok": times.len(),
        "failed": usize::from(error.is_some()),
        "error": error,
        "times_s": times,
    }))
}

fn parse_node(text: &str) -> Result<u8, BoxError> {
    let node = match text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        Some(hex) => u8::from_str_radix(hex, 16)?,
        None => text.parse()?,
    };
    Ok(node)
}

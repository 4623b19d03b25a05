//! The tester no device can crash, through the binary: `canopener test --suite all`, `mbt run` and
//! `net monitor` against hostile devices (canopener-testkit's `hostile`) on a hub, run in this
//! process on the wall clock. Each command ends with exit 6 or 7 and output that parses.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

use canopener_can::{Core, Instant};
use canopener_eds::model::Eds;
use canopener_sim::device::SimulatedDevice;
use canopener_sim::simulation::Simulation;
use canopener_testkit::fixture::ScratchDir;
use canopener_testkit::hostile::{Behaviour, Entropy, Hostile, JunkNode};
use canopener_transport::WallClock;
use serde_json::Value;

use crate::harness::{Background, client, expect_frame, json_lines, run_on};
use crate::stdout;
use crate::support::{HubProc, workspace_root};

const NODE: u8 = 5;

/// The bundled demo device's EDS (`canopener demo`).
fn demo_eds_path() -> PathBuf {
    workspace_root().join("crates/canopener-conformance/test_data/cia401_full_io.eds")
}

/// The demo EDS with a producer heartbeat of 100 ms from the start.
fn beating_eds() -> Eds {
    let text = canopener_testkit::fixture::read_to_string(demo_eds_path()).expect("demo EDS");
    let at = text.find("[1017]").expect("1017h");
    let value = at + text[at..].find("DefaultValue=").expect("a default") + "DefaultValue=".len();
    let end = value + text[value..].find(['\r', '\n']).expect("a line end");
    canopener_eds::load(format!("{}100{}", &text[..value], &text[end..]).as_bytes()).eds
}

fn device(eds: &Eds, now: Instant) -> SimulatedDevice {
    let mut device = Simulation::ideal()
        .device(eds, NODE)
        .build()
        .expect("simulated device")
        .pop()
        .expect("one device");
    device.boot(now);
    device
}

/// A core on the hub's bus, driven on the wall clock by a thread until dropped.
struct OnHub {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl OnHub {
    /// Starts the core `make` builds (given the wall clock's now) on `hub`'s can0.
    fn start<C: Core>(hub: &HubProc, make: impl FnOnce(Instant) -> C + Send + 'static) -> OnHub {
        let stop = Arc::new(AtomicBool::new(false));
        let mut bus = client(hub);
        let stopped = Arc::clone(&stop);
        let thread = std::thread::spawn(move || {
            let mut core = make(WallClock::now());
            while !stopped.load(Ordering::Relaxed) {
                while let Some(frame) = core.poll_transmit() {
                    if bus.send(&frame).is_err() {
                        return;
                    }
                }
                while core.poll_event().is_some() {}
                let now = WallClock::now();
                if core.poll_timeout().is_some_and(|due| due <= now) {
                    core.handle_timeout(now);
                    continue;
                }
                let wait = core
                    .poll_timeout()
                    .map_or(Duration::from_millis(5), |due| due.saturating_duration_since(now))
                    .min(Duration::from_millis(5));
                match bus.recv(wait) {
                    Ok(Some(received)) => core.handle_frame(WallClock::now(), &received.frame),
                    Ok(None) => {}
                    Err(_) => return,
                }
            }
        });
        OnHub {
            stop,
            thread: Some(thread),
        }
    }
}

impl Drop for OnHub {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// The hostile demo device on `hub`, spoiling every frame as `behaviour` says.
fn hostile(hub: &HubProc, behaviour: Behaviour) -> OnHub {
    let eds = beating_eds();
    OnHub::start(hub, move |now| {
        Hostile::new(device(&eds, now), NODE, behaviour, Entropy::seeded(22))
    })
}

/// `canopener test --suite all` with the JSON report in `dir`; the exit code and the report.
fn conformance(hub: &HubProc, dir: &ScratchDir, args: &[&str]) -> (i32, Value) {
    let out = dir.path().join("report.json");
    let eds = demo_eds_path();
    let mut all = vec![
        "test",
        "--node",
        "5",
        "--eds",
        eds.to_str().expect("path"),
        "--suite",
        "all",
        "--format",
        "json",
        "-o",
        out.to_str().expect("path"),
    ];
    all.extend_from_slice(args);
    let output = run_on(&hub.spec("can0"), &all);
    let code = output.status.code().unwrap_or(-1);
    let text = canopener_testkit::fixture::read_to_string(&out).expect("the report is written");
    let report: Value = serde_json::from_str(&text).expect("the JSON report parses");
    (code, report)
}

#[test]
fn test_against_a_device_answering_with_empty_frames_exits_7_and_quotes_the_frame() {
    let hub = HubProc::start();
    let dir = ScratchDir::new("hostile-empty");
    let _device = hostile(&hub, Behaviour::Empty);
    let (code, report) = conformance(&hub, &dir, &["--timeout", "100ms"]);
    assert_eq!(code, 7, "{report:#}");
    let preparation = report["preparation"].to_string();
    assert!(preparation.contains("585#"), "{preparation}");
}

#[test]
fn test_beside_a_junk_node_exits_6_and_junk_never_passes() {
    let hub = HubProc::start();
    let dir = ScratchDir::new("hostile-junk");
    let eds = demo_eds_path();
    let sim = Background::sim(
        &hub,
        dir.path(),
        "sim",
        &[eds.to_str().expect("path"), "--node-id", "5"],
    );
    let mut watcher = client(&hub);
    assert_eq!(expect_frame(&mut *watcher, "705#", &|| sim.report()), "705#00");
    drop(watcher);
    let _junk = OnHub::start(&hub, |_| JunkNode::new(NODE, 30, Entropy::seeded(7)));
    let (code, report) = conformance(&hub, &dir, &["--timeout", "200ms", "--repetitions", "3"]);
    assert!(code == 6 || code == 7, "exit {code}: {report:#}");
    let mut touched = 0;
    for test in report["tests"].as_array().expect("tests") {
        let junk: Vec<String> = test["telegrams"]
            .as_array()
            .expect("telegrams")
            .iter()
            .filter(|t| t["dir"] == "rx" && t["id"] == "0x585")
            .filter_map(|t| t["data"].as_str())
            .filter(|data| data.split_whitespace().count() != 8)
            .map(str::to_owned)
            .collect();
        if junk.is_empty() {
            continue;
        }
        touched += 1;
        let verdict = test["verdict"].as_str().unwrap_or_default();
        assert!(
            verdict == "fail" || verdict == "inconclusive",
            "{} met {junk:?} and says {verdict}: {}",
            test["id"],
            test["reason"]
        );
    }
    println!(
        "exit {code}, {} tests met junk; summary {}",
        touched, report["summary"]
    );
}

#[test]
fn mbt_run_against_a_device_answering_with_random_frames_exits_6_or_7_with_json() {
    let hub = HubProc::start();
    let _device = hostile(&hub, Behaviour::Random);
    let eds = demo_eds_path();
    let output = run_on(
        &hub.spec("can0"),
        &[
            "mbt",
            "run",
            "sdo",
            "--node",
            "5",
            "--eds",
            eds.to_str().expect("path"),
            "--steps",
            "40",
            "--format",
            "json",
        ],
    );
    let code = output.status.code().unwrap_or(-1);
    assert!(code == 6 || code == 7, "exit {code}: {}", stdout(&output));
    let json: Value = serde_json::from_str(stdout(&output).trim()).expect("one JSON object");
    assert_eq!(json["verdict"], "fail", "{json:#}");
}

/// One device, node 5, watched from the master (node 1).
const SYSTEM: &str = "[Topology]\nNetName=hostile\nNodes=0x02\nNode1Present=0x01\nNode1Name=Master\nNode5Present=0x01\nNode5Name=Device\n";

#[test]
fn net_monitor_against_junk_heartbeats_exits_6_or_7_and_quotes_the_frames() {
    let hub = HubProc::start();
    let dir = ScratchDir::new("hostile-monitor");
    let system = dir.write("system.cpj", SYSTEM);
    for (behaviour, expected) in [(Behaviour::Empty, 7), (Behaviour::Flood, 6)] {
        let _device = hostile(&hub, behaviour);
        let output = run_on(
            &hub.spec("can0"),
            &[
                "net",
                "monitor",
                system.to_str().expect("path"),
                "--heartbeat-ms",
                "100",
                "--duration",
                "2s",
                "--format",
                "json",
            ],
        );
        let what = behaviour.name();
        assert_eq!(
            output.status.code(),
            Some(expected),
            "{what}: {}",
            stdout(&output)
        );
        let events = json_lines(&stdout(&output));
        let anomalies: Vec<&Value> = events.iter().filter(|e| e["event"] == "anomaly").collect();
        // Empty heartbeats are quoted as such; a flood's junk lands on whatever CAN-IDs chance picks
        // (an EMCY of the wrong length, a heartbeat with an unknown state...), each quoted.
        let quotes_frames = match behaviour {
            Behaviour::Empty => anomalies
                .iter()
                .any(|e| e["frame"].as_str().is_some_and(|f| f.starts_with("705#"))),
            _ => {
                !anomalies.is_empty()
                    && anomalies
                        .iter()
                        .all(|e| e["frame"].as_str().is_some_and(|f| f.contains('#')))
            }
        };
        assert!(quotes_frames, "{what}: {events:?}");
        println!(
            "{what}: exit {expected}, {} events, first anomaly {}",
            events.len(),
            anomalies[0]
        );
    }
}

//! `mbt run` and `net monitor` against hostile devices on virtual time (canopener-testkit's
//! `hostile`): answers and heartbeats with no data, cut short, random, echoed, on another node's
//! CAN-ID, babbling with SDO toggles out of order, buried in a flood, or as random scripts say. No
//! run panics or hangs (bounded virtual time); the model-based tester's verdict is never `pass` and
//! maps to exit 6 or 7; the monitor reports anomalies quoting the frames, its events serialise to
//! JSON that parses, and the run's health maps to exit 6 or 7.

use std::time::Duration;

use canopener_bus_engine::virtual_bus::Timing;
use canopener_can::Instant;
use canopener_eds::model::Eds;
use canopener_link::link::{Flow, LinkError};
use canopener_link::system_watch::SystemWatch;
use canopener_link::virtual_link::VirtualLink;
use canopener_mbt::compile::{Options, Source, compile};
use canopener_mbt::executor::{RunConfig, Verdict};
use canopener_mbt::model::Model;
use canopener_mbt::shipped;
use canopener_network::monitor::{Event, Health, MonitorConfig, SystemMonitor};
use canopener_runtime::mbt_run::run;
use canopener_sim::device::SimulatedDevice;
use canopener_sim::simulation::{Simulation, VIRTUAL_CALENDAR_START_UNIX_MILLIS};
use canopener_testkit::corpus;
use canopener_testkit::hostile::{Behaviour, Entropy, Hostile};

const NODE: u8 = 5;

/// CANopenNode's example I/O device (heartbeat every 1000 ms), the device of `tests/mbt.rs`.
fn io_eds() -> Eds {
    let path = corpus::eds("CANopenNode__CANopenNode__example__IO.eds");
    canopener_eds::load(&canopener_testkit::fixture::read(&path).expect("EDS file")).eds
}

fn device(eds: &Eds) -> SimulatedDevice {
    let mut device = Simulation::ideal()
        .device(eds, NODE)
        .build()
        .expect("simulated device")
        .pop()
        .expect("one device")
        .with_calendar_at_zero(VIRTUAL_CALENDAR_START_UNIX_MILLIS);
    device.boot(Instant::ZERO);
    device
}

fn hostile(eds: &Eds, behaviour: Behaviour, percent: u8) -> VirtualLink<Hostile<SimulatedDevice>> {
    let mut bus = VirtualLink::new(Timing::Ideal);
    bus.attach(Hostile::new(device(eds), NODE, behaviour, Entropy::seeded(22)).percent(percent));
    bus
}

fn model(names: &[&str], eds: &Eds) -> Model {
    let sources: Vec<Source> = names
        .iter()
        .map(|n| Source {
            origin: (*n).into(),
            text: shipped::text(n).expect("shipped model").into(),
        })
        .collect();
    let options = Options {
        node_id: NODE,
        eds: Some(eds),
        set: Vec::new(),
    };
    let (model, report) = compile(&sources, &options, &|n| shipped::text(n).map(str::to_owned));
    model.unwrap_or_else(|| panic!("{report:#?}"))
}

/// The exit code `canopener mbt run` gives (crates/canopener-cli/src/mbt/run.rs).
fn mbt_exit(verdict: Verdict, outputs_seen: usize) -> u8 {
    match verdict {
        Verdict::Pass => 0,
        Verdict::Fail if outputs_seen == 0 => 7,
        Verdict::Fail | Verdict::Inconclusive => 6,
    }
}

/// Every hostile behaviour (all answers spoiled, and 30 % of them) against the `sdo` model (which
/// composes `nmt`) and the `heartbeat` model: never a pass, always an end within the time limit.
#[test]
fn mbt_runs_against_every_hostile_behaviour_end_in_fail_or_inconclusive() {
    let eds = io_eds();
    let models = [model(&["sdo"], &eds), model(&["heartbeat"], &eds)];
    for behaviour in Behaviour::ALL {
        for percent in [100, 30] {
            for (name, model) in ["sdo", "heartbeat"].iter().zip(&models) {
                let mut bus = hostile(&eds, behaviour, percent);
                // The power-on boot-up is history when the tester starts with its own reset.
                bus.run_until(Instant::from_millis(100)).expect("virtual time");
                let config = RunConfig {
                    seed: 3,
                    steps: 400,
                    ..RunConfig::default()
                };
                let limit = Duration::from_secs(600);
                let outcome = run(&mut bus, model, config, Some(limit)).expect("link");
                let what = format!("{} {percent} % {name}", behaviour.name());
                let code = mbt_exit(outcome.verdict, outcome.outputs_seen);
                assert!(
                    code == 6 || code == 7,
                    "{what}: {:?} {} (exit {code})",
                    outcome.verdict,
                    outcome.reason
                );
                assert!(
                    bus_time(&bus) <= Instant::ZERO + limit,
                    "{what}: ran past the limit"
                );
                println!(
                    "{what}: exit {code}, {:?} after {} steps: {}",
                    outcome.verdict, outcome.steps, outcome.reason
                );
            }
        }
    }
}

fn bus_time<N: canopener_can::Core>(bus: &VirtualLink<N>) -> Instant {
    use canopener_link::link::Link;
    bus.now()
}

/// A system of one device, node 5, watched by a monitor at the master (node 1).
const SYSTEM: &str = "[Topology]\nNetName=hostile\nNodes=0x02\nNode1Present=0x01\nNode1Name=Master\nNode5Present=0x01\nNode5Name=Device\n";

/// The I/O device with a producer heartbeat of 100 ms from the start.
fn beating_eds() -> Eds {
    let path = corpus::eds("CANopenNode__CANopenNode__example__IO.eds");
    let text = canopener_testkit::fixture::read_to_string(&path).expect("EDS file");
    let at = text.find("[1017]").expect("1017h");
    let value = at + text[at..].find("DefaultValue=").expect("a default") + "DefaultValue=".len();
    let end = value + text[value..].find(['\r', '\n']).expect("a line end");
    let text = format!("{}100{}", &text[..value], &text[end..]);
    canopener_eds::load(text.as_bytes()).eds
}

/// Watches `bus` for 5 s of virtual time; the events and the health at the end.
fn watch<N: canopener_can::Core>(bus: &mut VirtualLink<N>) -> (Vec<Event>, Health) {
    let loaded = canopener_network::load(SYSTEM.as_bytes());
    let topology = loaded.topology;
    let at = topology.find_vertex("Master");
    let config = MonitorConfig {
        at,
        networks: vec![1],
        producer_times: Default::default(),
        fallback: Some(Duration::from_millis(100)),
    };
    let mut watch = SystemWatch::new(SystemMonitor::new(&topology, &config));
    let mut events = Vec::new();
    let mut links: Vec<(u32, &mut dyn canopener_link::link::Link)> = vec![(1, bus)];
    watch
        .run(&mut links, Some(Instant::from_secs(5)), |_, _, mut slice| {
            events.append(&mut slice);
            Ok::<_, LinkError>(Flow::Continue)
        })
        .expect("watch");
    (events, watch.monitor().health())
}

/// `net monitor` on a device that beats correctly is healthy (exit 0); on every hostile behaviour
/// it ends in time with anomalies quoting the frames or the device silent, and the health maps to
/// exit 6 or 7.
#[test]
fn the_monitor_reports_every_hostile_behaviour_and_ends_troubled_or_unheard() {
    let eds = beating_eds();
    let mut clean = VirtualLink::new(Timing::Ideal);
    clean.attach(device(&eds));
    let (events, health) = watch(&mut clean);
    assert_eq!(health, Health::Healthy, "{events:?}");
    for behaviour in Behaviour::ALL {
        let mut bus = hostile(&eds, behaviour, 100);
        let (events, health) = watch(&mut bus);
        let what = behaviour.name();
        assert_ne!(health, Health::Healthy, "{what}: {events:?}");
        let anomalies: Vec<(String, String)> = events
            .iter()
            .filter_map(|e| match e {
                Event::Anomaly { frame, reason, .. } => Some((frame.clone(), reason.clone())),
                _ => None,
            })
            .collect();
        for event in &events {
            let json: serde_json::Value = serde_json::from_str(&event.to_json()).expect("JSON");
            assert!(json["event"].is_string(), "{what}: {json}");
        }
        for (frame, _) in &anomalies {
            assert!(
                frame.starts_with("705#") || frame.starts_with("085#"),
                "{what}: {frame}"
            );
        }
        // One anomaly event per second and reason at most: a flood cannot flood the output.
        assert!(anomalies.len() <= 5 * 8, "{what}: {} anomalies", anomalies.len());
        let code = if health == Health::Unheard { 7 } else { 6 };
        println!(
            "{what}: exit {code}, {} events, {} anomalies reported, e.g. {:?}",
            events.len(),
            anomalies.len(),
            anomalies.first()
        );
    }
}

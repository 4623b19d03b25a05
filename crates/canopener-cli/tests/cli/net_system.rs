//! `canopener sim --nodelist` and `canopener net monitor` together through a hub, in real time: the
//! monitor's JSON events name the cable cut on the simulator's standard input, and the devices that
//! come back when it is repaired; two networks on two buses of the hub.

use std::time::{Duration, Instant};

use serde_json::Value;

use crate::support::{HubProc, Proc, canopener};

fn fixture(name: &str) -> String {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../canopener-network/test_data")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

/// Monitor events until one satisfies `wanted` (or `within` passes).
fn wait_for(monitor: &mut Proc, within: Duration, wanted: impl Fn(&Value) -> bool) -> Vec<Value> {
    let started = Instant::now();
    let mut seen = Vec::new();
    while started.elapsed() < within {
        let event = monitor.json(within.saturating_sub(started.elapsed()));
        let done = wanted(&event);
        seen.push(event);
        if done {
            return seen;
        }
    }
    panic!("no awaited event within {within:?}: {seen:?}");
}

fn has_cable(event: &Value, cable: &str) -> bool {
    event["event"] == "diagnosis"
        && event["explanations"].as_array().is_some_and(|list| {
            list.iter().any(|e| {
                e["kind"] == "cable"
                    && e["candidates"]
                        .as_array()
                        .is_some_and(|c| c.iter().any(|n| n == cable))
            })
        })
}

#[test]
fn a_cut_typed_into_the_simulator_is_named_by_the_monitor_and_its_repair_recovers() {
    let hub = HubProc::start();
    let file = fixture("gateway.graphml");
    let (can0, can1) = (hub.spec("can0"), hub.spec("can1"));
    let mut sim_cmd = canopener();
    sim_cmd.args([
        "sim",
        "--nodelist",
        &file,
        "--bus",
        &format!("1={can0}"),
        "--bus",
        &format!("2={can1}"),
    ]);
    let mut sim = Proc::spawn("sim --nodelist", sim_cmd);
    let mut monitor_cmd = canopener();
    monitor_cmd.args([
        "net",
        "monitor",
        &file,
        "--bus",
        &can0,
        "--bus",
        &format!("2={can1}"),
        "--format",
        "json",
        "--duration",
        "30s",
    ]);
    let mut monitor = Proc::spawn("net monitor", monitor_cmd);
    // Every device is heard: the first heartbeats give their states.
    wait_for(&mut monitor, Duration::from_secs(10), |e| {
        e["event"] == "state" && e["node"] == "Boom3"
    });
    sim.send_line("cut B2");
    let seen = wait_for(&mut monitor, Duration::from_secs(10), |e| has_cable(e, "B2"));
    let diagnosis = seen.last().expect("diagnosis");
    assert_eq!(diagnosis["network"], 2, "{diagnosis}");
    assert_eq!(
        diagnosis["silent"],
        serde_json::json!(["Boom2", "Boom3"]),
        "{diagnosis}"
    );
    sim.send_line("repair B2");
    let seen = wait_for(&mut monitor, Duration::from_secs(10), |e| {
        e["event"] == "diagnosis" && e["silent"].as_array().is_some_and(Vec::is_empty)
    });
    let recovered: Vec<&str> = seen
        .iter()
        .filter(|e| e["event"] == "recovered")
        .filter_map(|e| e["node"].as_str())
        .collect();
    assert_eq!(recovered, ["Boom2", "Boom3"], "{seen:?}");
    assert!(sim.stderr().contains("applied: cut B2"), "{}", sim.stderr());
}

//! `canopener nmt`, `sync`, `heartbeat watch` and `lss scan|configure|inquire` against `canopener sim`
//! devices on a hub, checked by a test client on the same hub.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use canopener_transport::CanBus;
use serde_json::Value;

use crate::harness::{
    Background, NO_BUS, WAIT, base_eds, client, expect_frame, identify_unconfigured, json_lines, json_of,
    run_exiting, run_on, send,
};
use crate::support::HubProc;
use crate::{stderr, stdout, temp_dir};

/// base.eds with a producer heartbeat time (1017h) of 100 ms, so that NMT states can be confirmed.
fn heartbeat_eds(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(base_eds()).expect("read base.eds");
    let section = text.find("[1017]").expect("base.eds has 1017h");
    let default = section
        + text[section..]
            .find("DefaultValue=0")
            .expect("1017h has a default");
    let mut patched = text.clone();
    patched.replace_range(default..default + "DefaultValue=0".len(), "DefaultValue=100");
    let path = dir.join("heartbeat.eds");
    std::fs::write(&path, patched).expect("write heartbeat.eds");
    path
}

/// A hub with `count` unconfigured devices from base.eds, serial numbers `serial` and up, each
/// answering LSS: the hub, a test client on it and the simulator.
fn unconfigured_sims(name: &str, count: usize, serial: &str) -> (HubProc, Box<dyn CanBus>, Background) {
    unconfigured_sims_with(name, count, serial, &[])
}

/// [`unconfigured_sims`] with more `canopener sim` arguments (faults).
fn unconfigured_sims_with(
    name: &str,
    count: usize,
    serial: &str,
    extra: &[&str],
) -> (HubProc, Box<dyn CanBus>, Background) {
    let hub = HubProc::start();
    let dir = temp_dir(name);
    let mut bus = client(&hub);
    let eds = base_eds();
    let mut args = vec![eds.to_str().unwrap(); count];
    args.extend(["--serial", serial]);
    args.extend_from_slice(extra);
    let sim = Background::sim(&hub, &dir, "sim", &args);
    // Asked until all answer, so that the test starts once the simulator is on the hub.
    let deadline = Instant::now() + WAIT;
    loop {
        let answers = identify_unconfigured(&mut *bus)
            .iter()
            .filter(|frame| *frame == "7E4#5000000000000000")
            .count();
        if answers == count {
            return (hub, bus, sim);
        }
        assert!(
            Instant::now() < deadline,
            "{answers} of {count} unconfigured devices answered; {}",
            sim.report()
        );
    }
}

/// A hub with node 5 simulated from [`heartbeat_eds`], its boot-up seen: the hub, the directory for
/// the test's files and the simulator.
fn heartbeat_node_5(name: &str) -> (HubProc, PathBuf, Background) {
    let hub = HubProc::start();
    let dir = temp_dir(name);
    let mut bus = client(&hub);
    let eds = heartbeat_eds(&dir);
    let sim = Background::sim(&hub, &dir, "sim", &[eds.to_str().unwrap(), "--node-id", "5"]);
    assert_eq!(expect_frame(&mut *bus, "705#", &|| sim.report()), "705#00");
    (hub, dir, sim)
}

#[test]
fn nmt_commands_are_confirmed_by_heartbeats_and_boot_up() {
    let (hub, _dir, _sim) = heartbeat_node_5("master-nmt");
    let spec = hub.spec("can0");

    for (command, state, boot_up) in [
        ("start", "operational", false),
        ("stop", "stopped", false),
        ("preop", "pre-operational", false),
        ("reset", "pre-operational", true),
        ("reset-comm", "pre-operational", true),
    ] {
        let output = run_exiting(&spec, &["nmt", command, "5", "--confirm", "--format", "json"], 0);
        let json = json_of(&output);
        assert_eq!(json["command"], command, "{json}");
        assert_eq!(json["target"], 5, "{json}");
        assert_eq!(json["confirmed"], true, "{json}");
        assert_eq!(json["state"], state, "{json}");
        assert_eq!(json["boot_up"], boot_up, "{json}");
        let after = json["after_ms"].as_f64().expect("after_ms");
        assert!(after > 0.0 && after < 1000.0, "{json}");
    }

    // Every node heard is confirmed; here the one simulated node.
    let output = run_exiting(&spec, &["nmt", "stop", "all", "--confirm", "--format", "json"], 0);
    let json = json_of(&output);
    assert_eq!(json["target"], "all");
    assert_eq!(json["confirmed"], true);
    assert_eq!(json["nodes"].as_array().map(Vec::len), Some(1), "{json}");
    assert_eq!(json["nodes"][0]["node"], 5);
    assert_eq!(json["nodes"][0]["state"], "stopped");

    // Text without --confirm just says what was sent.
    let output = run_exiting(&spec, &["nmt", "start", "5"], 0);
    assert_eq!(stdout(&output), "sent start to node 5\n");

    // Nobody is node 9: not confirmed, exit 7, and the message says what was waited for and how long.
    let output = run_exiting(
        &spec,
        &[
            "nmt",
            "start",
            "9",
            "--confirm",
            "--timeout",
            "300ms",
            "--format",
            "json",
        ],
        7,
    );
    let json = json_of(&output);
    assert_eq!(json["confirmed"], false);
    assert_eq!(json["state"], Value::Null);
    let message = stderr(&output);
    assert!(
        message
            .contains("node 9 did not confirm start: no heartbeat or boot-up message from it within 300 ms"),
        "{message}"
    );
    assert!(message.contains("1017"), "{message}");
}

/// `heartbeat watch ARGS --format json --fail-on-loss` on the hub bus `spec`, in the background.
fn heartbeat_watch(dir: &Path, spec: &str, args: &[&str]) -> Background {
    let mut all = vec!["heartbeat", "watch"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--format", "json", "--fail-on-loss", "--bus", spec]);
    Background::spawn(dir, "watch", &all)
}

#[test]
fn heartbeat_watch_guards_a_node_without_heartbeat_and_sees_it_lost() {
    let hub = HubProc::start();
    let dir = temp_dir("master-guarding");
    let mut bus = client(&hub);
    let eds = base_eds();
    // base.eds produces no heartbeat (1017h = 0): node guarding is how a master watches it.
    let mut sim = Background::sim(&hub, &dir, "sim", &[eds.to_str().unwrap(), "--node-id", "5"]);
    assert_eq!(expect_frame(&mut *bus, "705#", &|| sim.report()), "705#00");
    let spec = hub.spec("can0");
    let mut watch = heartbeat_watch(
        &dir,
        &spec,
        &[
            "--guard",
            "5",
            "--guard-time",
            "100ms",
            "--life-time-factor",
            "3",
            "--duration",
            "2500ms",
        ],
    );
    // The device answers every remote frame on 705h with its state and an alternating toggle bit.
    // (A guarding request is a remote frame with DLC 1, CiA 301.)
    assert_eq!(expect_frame(&mut *bus, "705#R", &|| watch.report()), "705#R1");
    let answer = loop {
        let frame = expect_frame(&mut *bus, "705#", &|| watch.report());
        if !frame.starts_with("705#R") {
            break frame;
        }
    };
    assert!(answer == "705#7F" || answer == "705#FF", "{answer}");
    std::thread::sleep(Duration::from_millis(1200));
    sim.kill();
    assert_eq!(watch.wait(WAIT).code(), Some(6), "{}", watch.report());
    let lines = json_lines(&watch.stdout());
    assert!(
        lines
            .iter()
            .any(|e| e["event"] == "guarding_lost" && e["node"] == 5),
        "{lines:?}"
    );
    assert!(
        !lines.iter().any(|e| e["event"] == "toggle_error"),
        "a correct device never breaks the toggle: {lines:?}"
    );
    let summary = lines.last().expect("summary");
    assert_eq!(summary["nodes"][0]["losses"], 1, "{summary}");
    assert!(
        watch.stderr().contains("heartbeat or guarding lost: node 5"),
        "{}",
        watch.report()
    );
}

#[test]
fn heartbeat_watch_sees_an_emcy_a_stop_and_a_lost_heartbeat() {
    let (hub, dir, mut sim) = heartbeat_node_5("master-heartbeat");
    let spec = hub.spec("can0");
    let mut watch = heartbeat_watch(&dir, &spec, &["--duration", "4s"]);
    // Long enough for the watch to learn the 100 ms period from its heartbeats.
    std::thread::sleep(Duration::from_millis(1000));
    // An RPDO1 without its one mapped byte: the device answers with EMCY 8210h (CiA 301).
    run_exiting(&spec, &["nmt", "start", "5"], 0);
    run_exiting(&spec, &["bus", "send", "205#"], 0);
    std::thread::sleep(Duration::from_millis(100));
    run_exiting(&spec, &["nmt", "stop", "5"], 0);
    std::thread::sleep(Duration::from_millis(700));
    sim.kill();
    assert_eq!(
        watch.wait(WAIT).code(),
        Some(6),
        "a loss with --fail-on-loss exits 6"
    );
    assert!(
        watch.stderr().contains("heartbeat or guarding lost: node 5"),
        "{}",
        watch.stderr()
    );
    let lines = json_lines(&watch.stdout());
    assert!(
        lines
            .iter()
            .any(|e| e["event"] == "state" && e["node"] == 5 && e["to"] == "stopped"),
        "{lines:?}"
    );
    let lost = lines
        .iter()
        .position(|e| e["event"] == "lost" && e["node"] == 5)
        .unwrap_or_else(|| panic!("no lost event: {lines:?}"));
    let stopped = lines
        .iter()
        .position(|e| e["event"] == "state" && e["to"] == "stopped")
        .unwrap();
    assert!(stopped < lost, "{lines:?}");
    assert!(
        lines
            .iter()
            .any(|e| e["event"] == "emcy" && e["node"] == 5 && e["code"] == "8210"),
        "{lines:?}"
    );
    let summary = lines.last().unwrap();
    assert_eq!(summary["event"], "summary", "{summary}");
    let node = &summary["nodes"][0];
    assert_eq!(node["node"], 5, "{summary}");
    assert_eq!(node["state"], "stopped", "{summary}");
    assert_eq!(node["lost"], true, "{summary}");
    assert_eq!(node["losses"], 1, "{summary}");
    assert!(node["heartbeats"].as_u64().unwrap() >= 10, "{summary}");
    let median = node["period_ms"]["median"].as_f64().unwrap();
    assert!((50.0..200.0).contains(&median), "{summary}");
}

#[test]
fn sync_sends_the_counted_syncs_a_client_receives() {
    let hub = HubProc::start();
    let spec = hub.spec("can0");
    let mut bus = client(&hub);
    // Past the hub's hold-back of a new client's traffic, so the client misses no SYNC.
    std::thread::sleep(Duration::from_millis(200));
    let output = run_exiting(
        &spec,
        &[
            "sync",
            "--period",
            "5ms",
            "--count",
            "20",
            "--counter",
            "10",
            "--format",
            "json",
        ],
        0,
    );
    let json = json_of(&output);
    assert_eq!(json["sent"], 20, "{json}");
    assert_eq!(json["counter_overflow"], 10, "{json}");
    let median = json["gap_ms"]["median"].as_f64().expect("gap median");
    assert!((2.5..=12.0).contains(&median), "{json}");
    let context = || String::new();
    let counters: Vec<String> = (0..20)
        .map(|_| expect_frame(&mut *bus, "080#", &context))
        .collect();
    let expected: Vec<String> = (1..=10)
        .chain(1..=10)
        .map(|counter| format!("080#{counter:02X}"))
        .collect();
    assert_eq!(counters, expected);

    let output = run_exiting(&spec, &["sync", "--period", "2ms", "--duration", "100ms"], 0);
    let text = stdout(&output);
    assert!(
        text.contains("no counter") && text.contains("gaps between SYNCs"),
        "{text}"
    );
}

#[test]
fn lss_scan_gives_three_unconfigured_devices_node_ids_they_then_answer_sdo_on() {
    let (hub, mut bus, sim) = unconfigured_sims("master-lss-scan", 3, "100");
    let spec = hub.spec("can0");

    // Without --timeout: the LSS default of 100 ms, not the 1 s SDO default.
    let output = run_exiting(
        &spec,
        &["lss", "scan", "--assign", "10-20", "--format", "json"],
        0,
    );
    let json = json_of(&output);
    assert_eq!(json["timeout_ms"], 100.0, "{json}");
    assert_eq!(json["complete"], true, "{json}");
    assert_eq!(json["found"], 3, "{json}");
    let devices: Vec<(u64, u64)> = json["devices"]
        .as_array()
        .unwrap()
        .iter()
        .map(|device| {
            assert_eq!(device["vendor_id"], 0xABC, "{device}");
            assert_eq!(device["product_code"], 0x401, "{device}");
            assert_eq!(device["revision_number"], 0x10002, "{device}");
            (
                device["serial_number"].as_u64().unwrap(),
                device["node_id"].as_u64().unwrap(),
            )
        })
        .collect();
    // Fastscan finds the lowest address first.
    assert_eq!(devices, [(100, 10), (101, 11), (102, 12)]);
    assert!(json["frames_sent"].as_u64().unwrap() > 100, "{json}");

    // Each device now runs with its node-ID: SDO upload of 1018h:04, its serial number.
    let context = || sim.report();
    for (node, serial) in [(10u8, 100u8), (11, 101), (12, 102)] {
        let response = 0x580 + u16::from(node);
        send(&mut *bus, &format!("6{node:02X}#4018100400000000"));
        let answer = expect_frame(&mut *bus, &format!("{response:03X}#"), &context);
        assert_eq!(answer, format!("{response:03X}#43181004{serial:02X}000000"));
    }

    // Nothing unconfigured is left.
    let output = run_exiting(&spec, &["lss", "scan", "--timeout", "50ms"], 0);
    assert!(
        stdout(&output).starts_with("0 device(s) found"),
        "{}",
        stdout(&output)
    );
}

/// Issue 13 item 8: a device with `lss-state-not-changed` never enters LSS configuration state, not
/// even by fastscan, so `lss scan --assign` gives it no node-ID (it configured one before).
#[test]
fn lss_scan_configures_no_device_that_never_leaves_waiting_state() {
    let (hub, mut bus, sim) = unconfigured_sims_with(
        "master-lss-stuck",
        1,
        "100",
        &["--fault", "lss-state-not-changed"],
    );
    let spec = hub.spec("can0");
    let output = run_on(&spec, &["lss", "scan", "--assign", "10", "--format", "json"]);
    let assigned: Vec<Value> = json_lines(&stdout(&output))
        .iter()
        .flat_map(|json| json["devices"].as_array().cloned().unwrap_or_default())
        .filter(|device| device["node_id"] == 10)
        .collect();
    assert!(
        assigned.is_empty(),
        "the stuck device was given node 10: {assigned:?}\n{}",
        stderr(&output)
    );
    // Node 10 does not answer SDO, and the device still answers as unconfigured.
    send(&mut *bus, "60A#4018100400000000");
    let deadline = Instant::now() + Duration::from_millis(500);
    while let Some(wait) = deadline.checked_duration_since(Instant::now()) {
        if let Some(received) = bus.recv(wait).expect("recv") {
            assert_ne!(
                received.frame.id().as_raw(),
                0x58A,
                "node 10 answered SDO; {}",
                sim.report()
            );
        }
    }
    assert!(
        identify_unconfigured(&mut *bus).contains(&"7E4#5000000000000000".to_owned()),
        "{}",
        sim.report()
    );
}

#[test]
fn lss_inquire_and_configure_one_device() {
    let (hub, mut bus, sim) = unconfigured_sims("master-lss-configure", 1, "0x55");
    let spec = hub.spec("can0");

    let json = json_of(&run_exiting(&spec, &["lss", "inquire", "--format", "json"], 0));
    assert_eq!(json["vendor_id"], 0xABC, "{json}");
    assert_eq!(json["product_code"], 0x401, "{json}");
    assert_eq!(json["revision_number"], 0x10002, "{json}");
    assert_eq!(json["serial_number"], 0x55, "{json}");
    assert_eq!(json["node_id"], 255, "unconfigured: {json}");
    assert_eq!(json["selected"], "global");
    assert_eq!(json["several_answered"], false);

    let address = [
        "--vendor",
        "0xABC",
        "--product",
        "0x401",
        "--revision",
        "10002h",
        "--serial",
        "85",
    ];
    let mut args = vec!["lss", "configure"];
    args.extend(address);
    args.extend([
        "--node-id",
        "7",
        "--bitrate",
        "250",
        "--store",
        "--format",
        "json",
    ]);
    let json = json_of(&run_exiting(&spec, &args, 0));
    assert_eq!(json["previous_node_id"], 255, "{json}");
    assert_eq!(json["node_id"], 7, "{json}");
    assert_eq!(json["bitrate_kbit"], 250, "{json}");
    assert_eq!(json["stored"], true, "{json}");
    let context = || sim.report();
    // Switched back to waiting, the unconfigured device takes node-ID 7 and boots.
    assert_eq!(expect_frame(&mut *bus, "707#", &context), "707#00");

    let mut args = vec!["lss", "inquire"];
    args.extend(address);
    let text = stdout(&run_exiting(&spec, &args, 0));
    assert!(text.contains("serial number    0x00000055"), "{text}");
    assert!(text.contains("node-ID          7"), "{text}");

    // Another serial number: nobody answers, exit 7 naming the address and the service.
    let output = run_exiting(
        &spec,
        &[
            "lss",
            "configure",
            "--vendor",
            "0xABC",
            "--product",
            "0x401",
            "--revision",
            "0x10002",
            "--serial",
            "0x56",
            "--node-id",
            "8",
        ],
        7,
    );
    let message = stderr(&output);
    assert!(
        message.contains("serial number 0x00000056 answered switch state selective within 100 ms"),
        "{message}"
    );
}

#[test]
fn bad_arguments_exit_2_with_an_example() {
    // A complete LSS address, so that only the argument under test is wrong.
    let configure = |rest: &[&'static str]| {
        let mut args = vec![
            "lss",
            "configure",
            "--vendor",
            "1",
            "--product",
            "2",
            "--revision",
            "3",
            "--serial",
            "4",
        ];
        args.extend_from_slice(rest);
        args
    };
    let cases: [(Vec<&str>, &str); 8] = [
        (vec!["nmt", "start", "200"], "e.g. `canopener nmt start 5`"),
        (
            vec!["lss", "configure", "--serial", "1", "--node-id", "5"],
            "e.g. `canopener lss configure --vendor",
        ),
        (
            vec!["lss", "configure", "--node-id", "5"],
            "e.g. `canopener lss configure --vendor",
        ),
        (
            configure(&["--node-id", "0"]),
            "255 to make the device unconfigured",
        ),
        (
            configure(&["--node-id", "5", "--bitrate", "100"]),
            "--bitrate 250",
        ),
        (
            vec!["lss", "scan", "--assign", "10-12,11"],
            "e.g. `canopener lss scan --assign 10-20`",
        ),
        (
            vec!["heartbeat", "watch", "--nodes", "0-5"],
            "e.g. `canopener heartbeat watch --nodes",
        ),
        (
            vec!["sync", "--period", "0ms"],
            "e.g. `canopener sync --period 10ms",
        ),
    ];
    for (args, example) in cases {
        let output = run_on(NO_BUS, &args);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {}", stderr(&output));
        assert!(stderr(&output).contains(example), "{args:?}: {}", stderr(&output));
    }
    let partial = run_on(NO_BUS, &["lss", "inquire", "--vendor", "1"]);
    assert_eq!(partial.status.code(), Some(2));
    assert!(
        stderr(&partial).contains("--product, --revision, --serial are missing"),
        "{}",
        stderr(&partial)
    );
}

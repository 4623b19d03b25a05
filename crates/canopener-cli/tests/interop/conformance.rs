//! `canopener test` end to end through the hub (issue 14): against `canopener sim` devices (clean, with a
//! fault, absent, interrupted by Ctrl-C) and against python canopen's `LocalNode`, a device we did not
//! write. Reports, exit codes and the per-test candump logs (which `bus decode` and `bus replay` accept)
//! are checked from the outside, as a user sees them.

use std::path::Path;
use std::time::{Duration, Instant};

use canopener_testkit::corpus::{self, Kind};
use canopener_testkit::fixture::{self, ScratchDir};
use serde_json::Value;

use crate::support::{HubProc, Proc, canopener, local_node, python};

/// A vendored EDS with node guarding, limits, EMCY and RPDOs: all but the long-entry tests apply.
const SIM_EDS: &str = "ros-industrial__ros_canopen__ipa_canopen_test__config__PRL120.eds";
/// How long one whole run may take on the wall clock before the test calls it hung.
const RUN_LIMIT: Duration = Duration::from_secs(120);

/// `canopener sim` on the hub, once it reports that it is on the bus.
fn sim(hub: &HubProc, bus: &str, node: &str, extra: &[&str]) -> Proc {
    let mut command = canopener();
    command
        .arg("sim")
        .arg(corpus::eds(SIM_EDS))
        .args(["--node-id", node, "--bus", &hub.spec(bus), "--format", "json"])
        .args(extra)
        .env_remove("CANOPENER_BUS");
    let mut proc = Proc::spawn("canopener sim", command);
    let started = proc.json(Duration::from_secs(30));
    assert_eq!(started["event"], "started", "unexpected first event {started}");
    proc
}

/// `canopener test ARGS` run to its end: exit code, stdout, stderr and wall time.
fn run_test(args: &[&str]) -> (Option<i32>, String, String, Duration) {
    let mut command = canopener();
    command.arg("test").args(args).env_remove("CANOPENER_BUS");
    let start = Instant::now();
    let mut proc = Proc::spawn(&format!("canopener test {}", args.join(" ")), command);
    let status = proc.wait(RUN_LIMIT);
    let stdout = proc.remaining_lines().join("\n");
    (status.code(), stdout, proc.stderr_after_exit(), start.elapsed())
}

/// `canopener test --bus BUS --node NODE --eds EDS --format json -o DIR/report.json EXTRA…`: exit code,
/// the JSON report, stderr and wall time.
fn json_run(
    dir: &ScratchDir,
    bus: &str,
    node: &str,
    eds: &Path,
    extra: &[&str],
) -> (Option<i32>, Value, String, Duration) {
    let out = dir.join("report.json");
    let eds = eds.to_str().unwrap();
    let out_arg = out.to_str().unwrap();
    let mut args = vec![
        "--bus", bus, "--node", node, "--eds", eds, "--format", "json", "-o", out_arg,
    ];
    args.extend_from_slice(extra);
    let (code, _, stderr, took) = run_test(&args);
    (code, report(&out), stderr, took)
}

fn report(path: &Path) -> Value {
    serde_json::from_str(&fixture::read_to_string(path).expect("report written")).expect("JSON report")
}

/// Every test of `report` as (id, verdict, reason).
fn verdicts(report: &Value) -> Vec<(String, String, String)> {
    report["tests"]
        .as_array()
        .expect("tests")
        .iter()
        .map(|t| {
            let field = |name: &str| t[name].as_str().unwrap_or_default().to_owned();
            (field("id"), field("verdict"), field("reason"))
        })
        .collect()
}

fn failed(report: &Value) -> Vec<String> {
    report["tests"]
        .as_array()
        .expect("tests")
        .iter()
        .filter(|t| t["verdict"] == "fail")
        .map(|t| t["id"].as_str().unwrap_or_default().to_owned())
        .collect()
}

#[test]
fn a_clean_simulated_device_passes_and_its_logs_decode_and_replay() {
    let hub = HubProc::start();
    let _device = sim(&hub, "can0", "5", &[]);
    let dir = ScratchDir::new("conformance-clean");
    let logs = dir.join("logs");
    let bus = hub.spec("can0");
    let eds = corpus::eds(SIM_EDS);
    let (code, report, stderr, took) = json_run(
        &dir,
        &bus,
        "0x05",
        &eds,
        &[
            "--log",
            logs.to_str().unwrap(),
            // The simulated device runs on this (loaded, shared) host's scheduler, not on a real-time
            // controller: its heartbeat, event timer, inhibit time and SYNC producer intervals are
            // judged on virtual time (tests/simulated.rs), not here.
            "--skip",
            "cia301.ec.1",
            "--skip",
            "cia301.pdo.6",
            "--skip",
            "cia301.pdo.12",
            "--skip",
            "cia301.sync.4",
            // The performance suite through the hub has its own test below (heartbeat deviation).
            "--skip",
            "cia313",
        ],
    );
    let undecided: Vec<String> = report["tests"]
        .as_array()
        .expect("tests")
        .iter()
        .filter(|t| t["verdict"] == "fail" || t["verdict"] == "inconclusive")
        .map(|t| format!("{} {}: {}\n{}", t["id"], t["verdict"], t["reason"], t["analysis"]))
        .collect();
    assert_eq!(code, Some(0), "stderr: {stderr}\n{}", undecided.join("\n"));
    assert_eq!(report["version"], 1);
    assert_eq!(report["bus"]["timestamps"], "hub");
    assert_eq!(report["summary"]["fail"], 0, "{:?}", failed(&report));
    assert_eq!(report["summary"]["inconclusive"], 0);
    eprintln!(
        "clean simulated device over the hub: {} tests in {:.1} s wall ({} s on the link's clock)",
        report["tests"].as_array().map_or(0, Vec::len),
        took.as_secs_f64(),
        report["duration_s"]
    );
    // One candump log per test; every one decodes, and one replays onto the bus.
    let files = fixture::list(&logs).expect("log dir");
    assert_eq!(files.len(), report["tests"].as_array().map_or(0, Vec::len));
    assert!(
        !files.iter().any(|f| f.ends_with("cia301.ec.1.log")),
        "--skip left a log"
    );
    for file in &files {
        let output = canopener()
            .args(["bus", "decode"])
            .arg(file)
            .output()
            .expect("bus decode");
        assert!(
            output.status.success(),
            "bus decode {}: {}",
            file.display(),
            String::from_utf8_lossy(&output.stderr)
        );
        let text = String::from_utf8_lossy(&output.stdout);
        // The EDS check talks to nobody, nor does a test whose precondition the EDS alone denies
        // (the runner then has nothing to clean up): their logs are empty.
        let id = file.file_stem().and_then(|s| s.to_str()).unwrap_or_default();
        let test = report["tests"]
            .as_array()
            .and_then(|tests| tests.iter().find(|t| t["id"] == id))
            .expect("every log belongs to a test");
        let empty = test["telegrams"].as_array().is_none_or(Vec::is_empty);
        assert!(
            !empty || id == "cia301.eds.1" || test["verdict"] == "not_applicable",
            "{id}"
        );
        assert_eq!(text.contains("node 5"), !empty, "{}: {text}", file.display());
    }
    let replayed = canopener()
        .args(["bus", "replay", "--no-timing", "--bus", &hub.spec("replay")])
        .arg(logs.join("cia301.sdo.1.log"))
        .env_remove("CANOPENER_BUS")
        .output()
        .expect("bus replay");
    assert!(
        replayed.status.success(),
        "bus replay: {}",
        String::from_utf8_lossy(&replayed.stderr)
    );
}

#[test]
fn a_fault_fails_with_its_evidence_and_exit_code_6() {
    let hub = HubProc::start();
    let _device = sim(&hub, "can0", "5", &["--fault", "limit-not-enforced"]);
    let bus = hub.spec("can0");
    let eds = corpus::eds(SIM_EDS);
    let (code, stdout, stderr, _) = run_test(&[
        "--bus",
        &bus,
        "--node",
        "5",
        "--eds",
        eds.to_str().unwrap(),
        "--only",
        "cia301.sdo.9",
    ]);
    assert_eq!(code, Some(6), "stderr: {stderr}");
    assert!(stdout.contains("SDO Test (1): 0 passed, 1 failed"), "{stdout}");
    assert!(stdout.contains("FAIL cia301.sdo.9"), "{stdout}");
    assert!(stdout.contains("Required: CiA 301 §7.2.4.3.17"), "{stdout}");
    assert!(stdout.contains("0609 0031h"), "{stdout}");
    assert!(
        stdout.contains("Answer:   the transfer was confirmed"),
        "{stdout}"
    );
}

#[test]
fn no_device_is_exit_7_and_an_unreadable_eds_exit_3() {
    let hub = HubProc::start();
    let bus = hub.spec("empty");
    let eds = corpus::eds(SIM_EDS);
    let (code, _, stderr, _) = run_test(&["--bus", &bus, "--node", "5", "--eds", eds.to_str().unwrap()]);
    assert_eq!(code, Some(7), "stderr: {stderr}");
    assert!(stderr.contains("node 5 did not answer"), "{stderr}");
    let (code, _, stderr, _) = run_test(&["--bus", &bus, "--node", "5", "--eds", "/nonexistent/device.eds"]);
    assert_eq!(code, Some(3), "stderr: {stderr}");
    let (code, _, stderr, _) = run_test(&[
        "--bus",
        &bus,
        "--node",
        "5",
        "--eds",
        eds.to_str().unwrap(),
        "--only",
        "cia301.nope",
    ]);
    assert_eq!(code, Some(2), "stderr: {stderr}");
    assert!(stderr.contains("--list"), "{stderr}");
}

#[test]
fn ctrl_c_writes_the_partial_report_and_exits_130() {
    let hub = HubProc::start();
    let _device = sim(&hub, "can0", "5", &[]);
    let dir = ScratchDir::new("conformance-interrupt");
    let out = dir.join("partial.json");
    let mut command = canopener();
    command
        .arg("test")
        .args([
            "--bus",
            &hub.spec("can0"),
            "--node",
            "5",
            "--format",
            "json",
            "-o",
        ])
        .arg(&out)
        .arg("--eds")
        .arg(corpus::eds(SIM_EDS))
        .env_remove("CANOPENER_BUS");
    let mut proc = Proc::spawn("canopener test (interrupted)", command);
    // The preparation takes at least the boot-up; the whole run several seconds.
    std::thread::sleep(Duration::from_secs(3));
    proc.interrupt();
    let status = proc.wait(Duration::from_secs(20));
    assert_eq!(status.code(), Some(130), "stderr: {}", proc.stderr_after_exit());
    let report = report(&out);
    assert_eq!(report["interrupted"], true);
    let run = report["tests"].as_array().map_or(0, Vec::len);
    assert!(
        run > 0 && run < canopener_tests_total(),
        "{run} tests in the partial report"
    );
}

fn canopener_tests_total() -> usize {
    let output = canopener()
        .args(["test", "--list", "--format", "json"])
        .output()
        .expect("--list");
    serde_json::from_slice::<Value>(&output.stdout)
        .expect("list JSON")
        .as_array()
        .map_or(0, Vec::len)
}

/// python canopen 2.4.1's `LocalNode` (with the boot-up, resets and heartbeat tests/python/co_local_node.py
/// adds) lacks what a certified device must have; the suite must name exactly those gaps, and nothing
/// else, and run to its end.
const LOCAL_NODE_GAPS: &[&str] = &[
    // Its SDO server answers a sub-index a VAR does not have, and sub-indices beyond an array's;
    // sub-index FFh of a VAR reads as the VAR's value (CCT OD 05).
    "cia301.sdo.4",
    "cia301.od.7",
    "cia301.od.9",
    // 1003h:00 takes any value, not only 0 (CCT SDO 10 writes FFh there).
    "cia301.sdo.9",
    // It answers a block upload (with or without CRC, even one with block size 128, or the one
    // cia301.sdo.21 then acknowledges wrongly) with a normal upload instead of refusing it with
    // 0504 0001h.
    "cia301.sdo.15",
    "cia301.sdo.18",
    "cia301.sdo.21",
    // No PDO timing (event timer, inhibit time, synchronous transmission with or without a SYNC
    // start value, TPDOs on SYNC as consumer), no RTR on TPDOs, no checks of PDO
    // COB-IDs, and no mapping procedure: entries are taken while the PDO is valid or sub-index 0 is
    // not 0, beyond the mapping's entries and 64 bits, in the wrong direction and for objects that
    // may not be mapped (into a TPDO and into an RPDO).
    "cia301.pdo.6",
    "cia301.pdo.7",
    "cia301.pdo.12",
    "cia301.pdo.14",
    "cia301.sync.5",
    "cia301.pdo.3",
    "cia301.pdo.4",
    "cia301.pdo.5",
    "cia301.pdo.9",
    "cia301.pdo.10",
    "cia301.pdo.11",
    // It sends no PDOs at all, so a new mapping never shows on the bus (pdo.8 observes it).
    "cia301.pdo.8",
    // Entries without a DefaultValue in the EDS are aborted with 060A 0023h, 1010h:01 among them:
    // the EDS describes it readable and 060A 0023h does not say "not supported", so the store tests
    // fail where they used to be "not applicable".
    "cia301.od.1",
    "cia301.other.1",
    "cia301.other.2",
    "cia301.other.3",
    // 1010h:02 is in its EDS but answered with 060A 0023h (no DefaultValue in the data store).
    "cia301.other.5",
    // 1019h takes any value at any time, and 1005h bit 30 is accepted but no SYNC is produced.
    "cia301.sync.2",
    "cia301.sync.3",
    "cia301.sync.4",
    // No EMCY producer, no node guarding, and its SDO server runs in stopped.
    "cia301.emcy.3",
    "cia301.ec.4",
    "cia301.ec.9",
    "cia301.nmt.4",
];

#[test]
fn a_foreign_device_runs_to_the_end_and_names_its_real_gaps() {
    let Some(python) = python() else { return };
    let Some(eds) = corpus::extended_file(Kind::Eds, "jinr-greenlab__canopen__disk2__CANopen__eds__Test.eds")
    else {
        eprintln!("skipped: the extended corpus (with the LocalNode's EDS) is not here");
        return;
    };
    let hub = HubProc::start();
    let _peer = local_node(&python, &hub, "34", &eds, &[]);
    let dir = ScratchDir::new("conformance-foreign");
    let bus = hub.spec("can0");
    let (code, report, stderr, took) = json_run(
        &dir,
        &bus,
        "34",
        &eds,
        &[
            // A Python process on a loaded, shared host is no real-time device: its heartbeat jitter
            // would measure the host, not python canopen. For the same reason the performance suite
            // (cia313) is not judged here.
            "--skip",
            "cia301.ec.1",
            "--skip",
            "cia313",
        ],
    );
    assert_eq!(code, Some(6), "stderr: {stderr}");
    assert_eq!(report["interrupted"], false);
    // Without node guarding, life guarding cannot be judged (cia301.ec.4 fails for guarding itself);
    // without RTR on TPDOs in operational (cia301.pdo.3 fails), neither can RTR in stopped; without
    // an EMCY for the too short RPDO (cia301.emcy.3 fails) there is no error whose reset and history
    // emcy.4 and emcy.5 could look at (no EMCY is no CiA 301 reason for "not applicable"). The
    // per-state tests cannot judge silence where nothing ever happens: no TPDO by event timer or
    // SYNC (nmt.5, pdo.20; pdo.6 and sync.5 fail), no SYNC from a producer it claims to be (nmt.9;
    // sync.4 fails), no error it notices, so no EMCY and 1001h stays 00h (nmt.8, emcy.6), and its
    // RPDO-mapped objects 2000h/2001h have no DefaultValue, so they cannot be read back (nmt.6;
    // `python_local_node_per_state` shows the RPDO gap with an EDS that has one).
    let undecided: Vec<&str> = report["tests"]
        .as_array()
        .expect("tests")
        .iter()
        .filter(|t| t["verdict"] == "inconclusive")
        .map(|t| t["id"].as_str().unwrap_or_default())
        .collect();
    assert_eq!(
        undecided,
        [
            "cia301.pdo.15",
            "cia301.emcy.4",
            "cia301.emcy.5",
            "cia301.ec.7",
            "cia301.nmt.5",
            "cia301.nmt.6",
            "cia301.pdo.20",
            "cia301.nmt.8",
            "cia301.nmt.9",
            "cia301.emcy.6"
        ]
    );
    let mut expected: Vec<String> = LOCAL_NODE_GAPS.iter().map(|s| (*s).to_owned()).collect();
    expected.sort();
    let mut got = failed(&report);
    got.sort();
    let reasons: Vec<String> = report["tests"]
        .as_array()
        .expect("tests")
        .iter()
        .filter(|t| t["verdict"] == "fail")
        .map(|t| format!("{}: {}", t["id"], t["reason"]))
        .collect();
    assert_eq!(got, expected, "{reasons:#?}");
    let count = |verdict: &str| {
        report["tests"]
            .as_array()
            .map_or(0, |t| t.iter().filter(|t| t["verdict"] == verdict).count())
    };
    eprintln!(
        "python LocalNode: {} tests ({} pass, {} fail, {} inconclusive, {} not applicable) in {:.1} s wall",
        report["tests"].as_array().map_or(0, Vec::len),
        count("pass"),
        count("fail"),
        count("inconclusive"),
        count("not_applicable"),
        took.as_secs_f64()
    );
}

#[test]
fn the_eds_suite_alone_needs_no_bus() {
    let clean = corpus::eds("CANopenNode__CANopenDemo__demo__demoDevice.eds");
    let (code, stdout, stderr, _) =
        run_test(&["--node", "5", "--eds", clean.to_str().unwrap(), "--suite", "eds"]);
    assert_eq!(code, Some(0), "stderr: {stderr}");
    assert!(stdout.contains("EDS Test (1): 1 passed"), "{stdout}");
    let flawed = corpus::eds("CANopenNode__CANopenNode__example__DS301_profile.eds");
    let (code, stdout, stderr, _) =
        run_test(&["--node", "5", "--eds", flawed.to_str().unwrap(), "--suite", "eds"]);
    assert_eq!(code, Some(6), "stderr: {stderr}");
    assert!(stdout.contains("C301 VendorNumber is empty"), "{stdout}");
}

/// The CiA 401 suite against python canopen's `LocalNode` serving a CiA 401 EDS (the demo device with
/// the optional CiA 401 objects): an SDO server over a data store, with no I/O application and no
/// factory test registers. Only what a data store can truly do may pass (the device type it serves
/// from the EDS); every input and interrupt test is inconclusive and says why, and the outputs fail
/// on the RPDO it ignores.
#[test]
fn python_local_node_has_no_cia401_behaviour_and_never_passes_for_it() {
    let Some(python) = python() else { return };
    let eds =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../canopener-conformance/test_data/cia401_full_io.eds");
    let hub = HubProc::start();
    let _peer = local_node(&python, &hub, "34", &eds, &[]);
    let dir = ScratchDir::new("conformance-cia401-local-node");
    let bus = hub.spec("can0");
    let (code, report, stderr, _) = json_run(&dir, &bus, "34", &eds, &["--suite", "cia401"]);
    let verdicts = verdicts(&report);
    eprintln!("python LocalNode, cia401: {verdicts:#?}");
    assert_eq!(code, Some(6), "stderr: {stderr}");
    assert_eq!(verdicts.len(), 9);
    for (id, verdict, reason) in &verdicts {
        match id.as_str() {
            "cia401.io.1" => assert_eq!(verdict, "pass", "{id}: {reason}"),
            // It stores 6200h:01 written by SDO but does not process RPDOs.
            "cia401.io.7" => {
                assert_eq!(verdict, "fail", "{id}: {reason}");
                assert!(reason.starts_with("after RPDO1 carried A5h"), "{id}: {reason}");
            }
            _ => {
                assert_eq!(verdict, "inconclusive", "{id}: {reason}");
                assert!(reason.contains("no factory test registers"), "{id}: {reason}");
            }
        }
    }
}

/// `canopener test --only cia313.perf.8` against `canopener sim` (with `fault`) through a fresh hub:
/// the test's JSON report entry.
fn heartbeat_deviation(fault: Option<&str>) -> Value {
    let hub = HubProc::start();
    let extra: Vec<&str> = fault.map_or(Vec::new(), |f| vec!["--fault", f]);
    let _device = sim(&hub, "can0", "5", &extra);
    let dir = ScratchDir::new("conformance-heartbeat");
    let bus = hub.spec("can0");
    let eds = corpus::eds(SIM_EDS);
    let (code, report, stderr, _) = json_run(&dir, &bus, "5", &eds, &["--only", "cia313.perf.8"]);
    assert_eq!(report["bus"]["timestamps"], "hub");
    let test = report["tests"][0].clone();
    let expected = if test["verdict"] == "pass" { 0 } else { 6 };
    assert_eq!(code, Some(expected), "stderr: {stderr}");
    let stats = &test["measurements"]["heartbeat_period"]["statistics"];
    eprintln!(
        "heartbeat through the hub, fault {fault:?}: {} (min {} / p50 {} / max {} ms)",
        test["verdict"], stats["min"], stats["p50"], stats["max"]
    );
    test
}

/// How late this host wakes a sleeping thread: the 99th percentile of 100 sleeps of 20 ms, in ms. The
/// simulated device and the hub are such threads: their heartbeats are sent and stamped that late.
fn host_wakeup_lateness_p99_ms() -> f64 {
    let mut late: Vec<f64> = (0..100)
        .map(|_| {
            let start = Instant::now();
            std::thread::sleep(Duration::from_millis(20));
            (start.elapsed().as_secs_f64() - 0.020) * 1000.0
        })
        .collect();
    late.sort_by(f64::total_cmp);
    late[98]
}

/// The heartbeat producer deviation (thesis §4.2.2: 100 periods at 100 ms, ±5 %) on the wall clock,
/// through the hub, with the hub's stamps. The criterion stays ±5 % (5 ms). The simulated device and
/// the hub are threads on this shared 2-core VM: at load averages of 7–10 a plain 50 ms sleep here
/// overshoots by 4 ms at p90 and 10 ms at p99 (even at nice -15), so a period of a correct producer can
/// leave the band by the host's doing. The clean device must therefore pass in one of three runs; only
/// when it passes none, and this host's own wake-up lateness (p99) is measured above half the
/// tolerance (2.5 ms), is the clean verdict left unjudged, and the test says so on stderr. A quiet
/// host that fails the clean device three times fails the test. The faults must always fail: their
/// periods (1 ms apart, or 40 % = 40 ms late) are far outside any such noise.
#[test]
fn the_heartbeat_deviation_through_the_hub_passes_clean_and_fails_with_heartbeat_faults() {
    let runs: Vec<Value> = (0..3)
        .scan(false, |passed, _| {
            (!*passed).then(|| {
                let test = heartbeat_deviation(None);
                *passed = test["verdict"] == "pass";
                test
            })
        })
        .collect();
    match runs.iter().find(|test| test["verdict"] == "pass") {
        Some(clean) => assert!(
            clean["reason"]
                .as_str()
                .is_some_and(|r| r.contains("all 100 within 95.000–105.000 ms")),
            "{clean}"
        ),
        None => {
            let lateness = host_wakeup_lateness_p99_ms();
            assert!(
                lateness > 2.5,
                "the clean simulated device failed three runs on a host that wakes threads within {lateness:.2} ms \
                 (p99): {:#?}",
                runs.iter().map(|t| t["analysis"].clone()).collect::<Vec<_>>()
            );
            eprintln!(
                "NOT JUDGED: the clean device's heartbeat through the hub: this host wakes sleeping threads up to \
                 {lateness:.1} ms late (p99), more than half the ±5 ms tolerance; the three runs' figures are above"
            );
        }
    }
    for (fault, outside) in [("heartbeat-too-fast", 2.0), ("heartbeat-jitter", 130.0)] {
        let test = heartbeat_deviation(Some(fault));
        assert_eq!(test["verdict"], "fail", "{fault}: {test}");
        let reason = test["reason"].as_str().unwrap_or_default();
        assert!(reason.contains("outside 95.000–105.000 ms"), "{fault}: {reason}");
        assert!(
            reason.contains("heartbeat.deviation_percent (documented default) ±5 %"),
            "{fault}: {reason}"
        );
        let analysis = test["analysis"].as_str().unwrap_or_default();
        assert!(analysis.contains("Answer:   min "), "{fault}: {analysis}");
        let stats = &test["measurements"]["heartbeat_period"]["statistics"];
        let limits = &test["measurements"]["heartbeat_period"]["limits"];
        assert_eq!(
            (limits["low"].as_f64(), limits["high"].as_f64()),
            (Some(95.0), Some(105.0))
        );
        // Too fast: a copy 1 ms after each heartbeat; jitter: every second one 40 ms late.
        match fault {
            "heartbeat-too-fast" => assert!(stats["min"].as_f64().is_some_and(|m| m < outside), "{stats}"),
            _ => assert!(stats["max"].as_f64().is_some_and(|m| m > outside), "{stats}"),
        }
    }
}

/// The tests of the services per NMT state and of the resets (issue 22 item 3) against python
/// canopen's `LocalNode` serving the CiA 401 EDS, whose RPDO1 maps 6200h:01 with a DefaultValue, so
/// an RPDO's effect can be read back. LocalNode obeys only NMT commands for its own node-ID (its
/// `NmtSlave.on_command` compares the node-ID byte with its own and 0) and, with the peer's resets,
/// restores what each reset must; but without an application that subscribes its RPDOs
/// (`rpdo.read()`) it never acts on one, in any state, so `nmt.6` fails on operational: its silence in
/// pre-operational and stopped is no merit.
#[test]
fn python_local_node_per_state() {
    let Some(python) = python() else { return };
    let eds =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../canopener-conformance/test_data/cia401_full_io.eds");
    let hub = HubProc::start();
    let _peer = local_node(&python, &hub, "34", &eds, &[]);
    let dir = ScratchDir::new("conformance-states-local-node");
    let bus = hub.spec("can0");
    let (code, report, stderr, _) = json_run(&dir, &bus, "34", &eds, &["--tag", "states"]);
    let verdicts = verdicts(&report);
    eprintln!("python LocalNode, per-state tests: {verdicts:#?}");
    assert_eq!(code, Some(6), "stderr: {stderr}");
    assert_eq!(verdicts.len(), 9);
    for (id, verdict, reason) in &verdicts {
        let expected = match id.as_str() {
            // Commands to other node-IDs ignored; the peer's resets restore 1000h–1FFFh (reset
            // communication) and every written value (reset node), keeping 6200h on reset
            // communication.
            "cia301.nmt.7" | "cia301.nmt.10" | "cia301.nmt.11" => "pass",
            // 6200h:01 stays at 00h after an RPDO in pre-operational and stopped, and in operational.
            "cia301.nmt.6" => {
                assert!(reason.contains("not acted on in operational"), "{id}: {reason}");
                "fail"
            }
            // No TPDO by event timer or SYNC, no error noticed, no SYNC produced: nothing whose
            // silence could be judged.
            _ => "inconclusive",
        };
        assert_eq!(verdict, expected, "{id}: {reason}");
    }
}

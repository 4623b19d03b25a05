//! canopener's `nmt` and `sdo` models against python canopen's `LocalNode` through the hub (issue 17):
//! what they report is LocalNode's, not the tester's.
//!
//! The device is tests/python/co_local_node.py: python canopen 2.4.1's `LocalNode` plus the boot-up and
//! the reset reactions a device application adds (LocalNode has neither of its own: its docstring says
//! which is which). The models find two gaps of LocalNode's SDO server, each against CiA 301:
//! - it answers SDO requests in Stopped (CiA 301 §7.3.2.2: no SDO service in Stopped);
//! - a request with an invalid command specifier (E0h) as the first request gets no answer at all,
//!   where CiA 301 asks for the abort 0504 0001h (LocalNode's abort needs the multiplexer of an earlier
//!   transfer: `struct.pack` of `None` raises inside its receive callback).
//!
//! And with LocalNode as shipped (`--bare`), a third: no boot-up after a reset node.
//!
//! Runs are on the wall clock: a 50 ms tolerance and a 1 s SDO bound (`--set SDO_T=1s`, the model's
//! default is 100 ms) absorb the Python process's latency on a loaded machine; with 100 ms, one run in
//! several failed on a late answer under load, which says nothing about LocalNode's conformance.

use std::path::Path;
use std::process::Command;

use canopener_testkit::corpus::{self, Kind};
use serde_json::Value;

use crate::support::{HubProc, canopener, local_node, python};

/// The EDS co_local_node.py is tested with in master_cli.rs (1017h = 0: no heartbeat).
const EDS: &str = "jinr-greenlab__canopen__disk2__CANopen__eds__Test.eds";
const NODE: &str = "34";

/// Whether the last NMT command the run sent to the device (node 34 = 22h, or all nodes) was stop:
/// an SDO answer after it is LocalNode serving SDO in Stopped, whichever model names the refusal.
fn last_nmt_command_is_stop(json: &Value) -> bool {
    json["inputs"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(Value::as_str)
        .rfind(|i| i.starts_with("?NMT ") && (i.ends_with("!0x22") || i.ends_with("!0x00")))
        .is_some_and(|i| i.starts_with("?NMT !0x02 "))
}

fn mbt_run(hub: &HubProc, eds: &Path, models: &[&str], seed: u64) -> (Option<i32>, Value) {
    let mut command: Command = canopener();
    command.args(["mbt", "run"]);
    command.args(models);
    command.args([
        "--node",
        NODE,
        "--steps",
        "60",
        "--tolerance",
        "50ms",
        "--format",
        "json",
    ]);
    // Every model but nmt alone sends SDO requests, each bounded by its SDO_T.
    if models.iter().any(|m| *m != "nmt") {
        command.args(["--set", "SDO_T=1s"]);
    }
    command.args([
        "--eds",
        eds.to_str().expect("UTF-8 path"),
        "--seed",
        &seed.to_string(),
    ]);
    command.args(["--bus", &hub.spec("can0"), "--time-limit", "60s"]);
    let output = command.output().expect("run canopener");
    let json: Value = serde_json::from_slice(&output.stdout)
        .unwrap_or_else(|_| panic!("no JSON: {}", String::from_utf8_lossy(&output.stderr)));
    (output.status.code(), json)
}

#[test]
fn nmt_and_sdo_models_report_local_node_gaps_and_no_false_failure() {
    let Some(python) = python() else { return };
    let Some(eds) = corpus::extended_file(Kind::Eds, EDS) else {
        eprintln!("skipped: {EDS} is in the extended corpus, which this checkout does not have");
        return;
    };
    let hub = HubProc::start();
    let _peer = local_node(&python, &hub, NODE, &eds, &[]);

    // First, while LocalNode's SDO server has served nothing yet: an invalid command as the first
    // request (a replayed script, so that it is the first whatever the seeds below choose).
    let dir = std::env::temp_dir().join(format!("canopener-interop-mbt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let log = dir.join("invalid-command.jsonl");
    let header = serde_json::json!({"kind": "run", "version": 1, "models": ["sdo"], "model_hash": "",
        "node": 34, "seed": 1, "steps": 60, "tolerance_us": 50_000, "settle_us": 5_000, "input_percent": 60,
        "strategy": "coverage"});
    let verdict = serde_json::json!({"kind": "verdict", "verdict": "fail", "inputs": ["?SDO_RX !0xE0 !0x1000 !0x00 !0x00000000"]});
    std::fs::write(&log, format!("{header}\n{verdict}\n")).expect("write the log");
    let mut replay: Command = canopener();
    replay.args([
        "mbt",
        "replay",
        log.to_str().expect("UTF-8 path"),
        "--format",
        "json",
    ]);
    replay.args([
        "--eds",
        eds.to_str().expect("UTF-8 path"),
        "--bus",
        &hub.spec("can0"),
        "--time-limit",
        "60s",
    ]);
    let output = replay.output().expect("run canopener");
    let json: Value = serde_json::from_slice(&output.stdout).expect("JSON");
    assert_eq!(output.status.code(), Some(6), "{json}");
    assert!(
        json["reason"]
            .as_str()
            .unwrap_or_default()
            .starts_with("missing output"),
        "{json}"
    );
    assert!(
        json["allowed"]
            .to_string()
            .contains("SDO_TX !0x80 !_ !_ !0x05040001"),
        "{json}"
    );

    // NMT: boot-up after both resets, every transition; with 1017h = 0 the state is not observable,
    // so what is judged is the boot-up and the silence around it. No failure.
    for seed in 1..=2 {
        let (code, json) = mbt_run(&hub, &eds, &["nmt"], seed);
        assert_eq!(code, Some(0), "nmt seed {seed}: {json}");
    }
    // SDO: every failure is LocalNode answering in Stopped, and it shows up. Since the model has the
    // segmented transfers (1008h upload, 1005h download, wrong toggles) a run spreads its 60 steps
    // over more requests: eight seeds, of which seeds 6 and 7 stop the device and then read.
    let mut answered_in_stopped = false;
    for seed in 1..=8 {
        let (code, json) = mbt_run(&hub, &eds, &["sdo"], seed);
        eprintln!("sdo seed {seed}: {} {}", json["verdict"], json["reason"]);
        if code == Some(0) {
            continue;
        }
        assert_eq!(code, Some(6), "sdo seed {seed}: {json}");
        let reason = json["reason"].as_str().unwrap_or_default();
        // An answer nmt refuses because the device is Stopped (the trace shows the NMT stop); a late
        // answer to a request sent before the stop may still be allowed, so `allowed` may hold SDO_TX.
        assert!(
            reason.starts_with("unexpected output 0x5a2#") && last_nmt_command_is_stop(&json),
            "sdo seed {seed}: a failure that is not a known LocalNode gap: {json}"
        );
        answered_in_stopped = true;
    }
    assert!(
        answered_in_stopped,
        "seeds 1..8 stop the device and read an object"
    );
}

/// LocalNode as python canopen ships it, without the peer's boot-up and resets: the `nmt` model reports
/// the missing boot-up after a reset node (CiA 301 §7.2.8.3.2) as a missing output, with the boot-up as
/// what was allowed.
#[test]
fn the_nmt_model_reports_that_a_bare_local_node_sends_no_boot_up() {
    let Some(python) = python() else { return };
    let Some(eds) = corpus::extended_file(Kind::Eds, EDS) else {
        eprintln!("skipped: {EDS} is in the extended corpus, which this checkout does not have");
        return;
    };
    let hub = HubProc::start();
    let _peer = local_node(&python, &hub, NODE, &eds, &["--bare"]);
    // With 1017h = 0 and no boot-up, LocalNode sends nothing at all: the verdict is `fail`, and the
    // exit code says that the device never answered (7).
    let (code, json) = mbt_run(&hub, &eds, &["nmt"], 1);
    assert_eq!(code, Some(7), "{json}");
    assert_eq!(json["verdict"], "fail", "{json}");
    let reason = json["reason"].as_str().unwrap_or_default();
    assert!(reason.starts_with("missing output"), "{json}");
    assert!(
        json["allowed"].to_string().contains("EC !0x00"),
        "the boot-up is what the model allowed: {json}"
    );
    eprintln!("bare LocalNode: {reason}; allowed {}", json["allowed"]);
}

/// Issue 23's composition `nmt heartbeat sdo` through the hub against LocalNode: every failure is one
/// of LocalNode's known gaps (an SDO answer in Stopped), never one the composition makes up.
#[test]
fn the_composition_nmt_heartbeat_sdo_fails_local_node_only_on_its_known_gap() {
    let Some(python) = python() else { return };
    let Some(eds) = corpus::extended_file(Kind::Eds, EDS) else {
        eprintln!("skipped: {EDS} is in the extended corpus, which this checkout does not have");
        return;
    };
    let hub = HubProc::start();
    let _peer = local_node(&python, &hub, NODE, &eds, &[]);
    let mut verdicts = Vec::new();
    for seed in 1..=5u64 {
        let (code, json) = mbt_run(&hub, &eds, &["nmt", "heartbeat", "sdo"], seed);
        eprintln!(
            "nmt heartbeat sdo seed {seed}: {} {}",
            json["verdict"], json["reason"]
        );
        verdicts.push(json["verdict"].as_str().unwrap_or_default().to_owned());
        if code == Some(0) {
            continue;
        }
        assert_eq!(code, Some(6), "seed {seed}: {json}");
        // An SDO answer the composition refuses because nmt has the device Stopped.
        let reason = json["reason"].as_str().unwrap_or_default();
        assert!(
            reason.starts_with("unexpected output 0x5a2#") && last_nmt_command_is_stop(&json),
            "seed {seed}: a failure that is not a known LocalNode gap: {json}"
        );
    }
    eprintln!("nmt heartbeat sdo against LocalNode, seeds 1-5: {verdicts:?}");
}

/// The models added by issue 23 against LocalNode (seed 1 each): a pass, or a failure that is one of
/// LocalNode's gaps against CiA 301, each named by what the run saw. LocalNode has no PDO, store,
/// block upload or node guarding behaviour of its own: it takes every SDO write into its data store.
#[test]
fn the_newer_models_fail_local_node_only_on_its_known_gaps() {
    let Some(python) = python() else { return };
    let Some(eds) = corpus::extended_file(Kind::Eds, EDS) else {
        eprintln!("skipped: {EDS} is in the extended corpus, which this checkout does not have");
        return;
    };
    let hub = HubProc::start();
    let _peer = local_node(&python, &hub, NODE, &eds, &[]);
    type Gap = fn(&str, &Value) -> bool;
    let cases: [(&[&str], &str, Gap); 6] = [
        // EMCY on 1014h's CAN-ID: LocalNode has no 1016h, so the consumer write is refused and
        // nothing more is due.
        (&["nmt", "heartbeat", "emcy"], "none", |_, _| false),
        (&["nmt", "sdo-download"], "none", |_, _| false),
        // The mapping changed while the PDO is valid is confirmed (CiA 301 §7.5.2.36: refused).
        (
            &["nmt", "pdo"],
            "a mapping write confirmed while the PDO is valid",
            |r, _| r.starts_with("unexpected output 0x5a2#60") && r.contains("pdo refuses it in pdo@Busy"),
        ),
        // 1010h:01 has no value in the EDS, and LocalNode aborts such an entry with 060A 0023h.
        (
            &["nmt", "store"],
            "1010h:01 read aborted with 060A 0023h",
            |r, _| {
                r.starts_with("unexpected output 0x5a2#8010100123000a06")
                    || r.starts_with("unexpected output 0x5a2#8010100123000A06")
            },
        ),
        // A block upload initiate with protocol switch threshold 0 answered by a normal upload.
        (
            &["nmt", "sdo-block"],
            "a block upload answered as a normal upload",
            |r, _| r.starts_with("unexpected output 0x5a2#43") && r.contains("sdo_block refuses it"),
        ),
        // No answer to a node guarding request (LocalNode has no node guarding).
        (
            &["nmt", "life-guarding"],
            "no answer to node guarding",
            |r, json| {
                r.starts_with("missing output")
                    && json["trace"]
                        .as_array()
                        .and_then(|t| t.last())
                        .is_some_and(|s| s["label"].as_str().is_some_and(|l| l.starts_with("?GUARD")))
            },
        ),
    ];
    for (models, gap, known) in cases {
        let (code, json) = mbt_run(&hub, &eds, models, 1);
        let reason = json["reason"].as_str().unwrap_or_default();
        eprintln!("{models:?} seed 1: {} {reason}", json["verdict"]);
        if code == Some(0) {
            continue;
        }
        assert_eq!(code, Some(6), "{models:?}: {json}");
        assert!(
            known(reason, &json)
                || (reason.starts_with("unexpected output 0x5a2#") && last_nmt_command_is_stop(&json)),
            "{models:?}: a failure that is not LocalNode's known gap ({gap}): {json}"
        );
    }
}

//! The `canopener` binary as users run it: exit codes, messages, and commands working together through a hub.

// These tests run the binary, start hubs and read and write the files they produce: the CLI's own bans on clocks, sleeping and files do not
// apply to them.
#![allow(clippy::disallowed_methods, clippy::print_stdout, clippy::print_stderr)]

#[path = "../interop/support.rs"]
#[allow(
    dead_code,
    reason = "shared with the interop tests, which use the Python helpers"
)]
mod support;

mod demo;
mod eds;
mod eds_check;
mod energybus;
mod grammar;
mod harness;
mod hostile;
mod master_pdo;
mod master_sdo;
mod master_services;
mod mbt;
mod net;
mod net_browser;
mod net_system;
mod sim;
mod test_criteria;
mod test_html;
mod test_list;
mod test_stimulus;
mod web;
mod web_harness;

use std::process::Output;
use std::time::Duration;

use support::{HubProc, Proc, canopener};

fn run(args: &[&str]) -> Output {
    canopener()
        .args(args)
        .env_remove("CANOPENER_BUS")
        .output()
        .expect("run canopener")
}

fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("canopener-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

#[test]
fn help_lists_commands_examples_and_exit_codes() {
    let output = run(&["--help"]);
    assert!(output.status.success());
    let text = stdout(&output);
    for needle in ["demo", "bus", "Exit codes:", "3  invalid input", "4  bus error"] {
        assert!(text.contains(needle), "--help lacks {needle:?}:\n{text}");
    }
    let serve = stdout(&run(&["bus", "serve", "--help"]));
    assert!(serve.contains("Examples:") && serve.contains("python"), "{serve}");
    let dump = stdout(&run(&["bus", "dump", "--help"]));
    assert!(dump.contains("--bus socketcand://127.0.0.1:29536/can0"), "{dump}");
}

/// Issue 25 item 8: the exit-code rules are stated once; the README quotes `--help` word for word.
#[test]
fn the_readme_states_the_exit_codes_of_the_help() {
    let help = stdout(&run(&["--help"]));
    let table = &help[help.find("Exit codes:").expect("--help has its exit codes")..];
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../README.md"))
        .expect("the README is readable");
    assert!(
        readme.contains(table.trim_end()),
        "README.md's exit codes differ from `canopener --help`; paste this into its Exit codes block:\n{table}"
    );
}

#[test]
fn usage_errors_exit_2_with_advice() {
    let unknown = run(&["bus", "frobnicate"]);
    assert_eq!(unknown.status.code(), Some(2));

    let no_bus = run(&["bus", "dump"]);
    assert_eq!(no_bus.status.code(), Some(2));
    assert!(
        stderr(&no_bus).contains("pass --bus SPEC or set the CANOPENER_BUS"),
        "{}",
        stderr(&no_bus)
    );

    let bad_spec = run(&["bus", "dump", "--bus", "can0"]);
    assert_eq!(bad_spec.status.code(), Some(2));
    assert!(
        stderr(&bad_spec).contains("socketcand://HOST"),
        "{}",
        stderr(&bad_spec)
    );

    let virtual_send = run(&["bus", "send", "--bus", "virtual:x", "123#00"]);
    assert_eq!(virtual_send.status.code(), Some(2));
    assert!(stderr(&virtual_send).contains("exists only inside one canopener process"));

    let bad_duration = run(&["bus", "dump", "--bus", "virtual:x", "--duration", "soon"]);
    assert_eq!(bad_duration.status.code(), Some(2));
}

#[test]
fn bus_spec_falls_back_to_the_environment() {
    let output = canopener()
        .args(["bus", "dump"])
        .env("CANOPENER_BUS", "nonsense")
        .output()
        .expect("run");
    assert_eq!(output.status.code(), Some(2));
    assert!(
        stderr(&output).contains("CANOPENER_BUS environment variable is invalid"),
        "{}",
        stderr(&output)
    );
}

#[test]
fn invalid_frames_exit_3_before_anything_is_sent() {
    let output = run(&[
        "bus",
        "send",
        "--bus",
        "socketcand://127.0.0.1:9/can0",
        "123#00",
        "800#11",
    ]);
    assert_eq!(output.status.code(), Some(3), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("frame 2 '800#11'"),
        "{}",
        stderr(&output)
    );
}

#[test]
fn unreachable_or_missing_buses_exit_4_naming_alternatives() {
    let refused = run(&["bus", "send", "--bus", "socketcand://127.0.0.1:9/can0", "123#00"]);
    assert_eq!(refused.status.code(), Some(4));
    assert!(
        stderr(&refused).contains("canopener bus serve"),
        "{}",
        stderr(&refused)
    );

    let socketcan = run(&["bus", "dump", "--bus", "socketcan:can0", "--count", "1"]);
    assert_eq!(socketcan.status.code(), Some(4));
    // Either this kernel lacks AF_CAN (say so and name the alternatives) or it lacks the interface.
    let text = stderr(&socketcan);
    assert!(
        text.contains("socketcand://") || text.contains("ip link"),
        "{text}"
    );
}

#[test]
fn replay_refuses_a_log_with_bad_lines_and_names_them() {
    let dir = temp_dir("replay-bad");
    let log = dir.join("bad.log");
    std::fs::write(
        &log,
        "(1.000000) can0 123#00\n(1.100000) can0 123#0G\n(1.200000) can0 XYZ\n",
    )
    .unwrap();
    let output = run(&[
        "bus",
        "replay",
        log.to_str().unwrap(),
        "--bus",
        "socketcand://127.0.0.1:9/can0",
    ]);
    assert_eq!(output.status.code(), Some(3));
    let text = stderr(&output);
    assert!(
        text.contains("bad.log:2:") && text.contains("bad.log:3:"),
        "{text}"
    );
    assert!(text.contains("--skip-invalid"), "{text}");

    let missing = run(&[
        "bus",
        "replay",
        "/nonexistent/x.log",
        "--bus",
        "socketcand://127.0.0.1:9/can0",
    ]);
    assert_eq!(missing.status.code(), Some(3));
    assert!(stderr(&missing).contains("/nonexistent/x.log"));
}

#[test]
fn decode_prints_the_embedded_demo_session_exactly() {
    let log = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../canopener-wire/test_data/demo.log");
    let output = run(&["bus", "decode", log.to_str().unwrap()]);
    assert!(output.status.success(), "{}", stderr(&output));
    insta::assert_snapshot!("demo_session_decoded", stdout(&output));
}

#[test]
fn decode_reports_bad_lines_and_still_decodes_the_rest() {
    let dir = temp_dir("decode-bad");
    let log = dir.join("mixed.log");
    std::fs::write(
        &log,
        "(1.000000) can0 701#05\ngarbage\n(1.200000) can0 000#0100\n",
    )
    .unwrap();
    let output = run(&["bus", "decode", log.to_str().unwrap(), "--format", "json"]);
    assert_eq!(output.status.code(), Some(3));
    let lines: Vec<serde_json::Value> = stdout(&output)
        .lines()
        .map(|line| serde_json::from_str(line).expect("json line"))
        .collect();
    assert_eq!(lines.len(), 2);
    assert_eq!(lines[0]["text"], "Heartbeat node 1: OPERATIONAL");
    assert_eq!(lines[1]["service"], "nmt");
    assert!(stderr(&output).contains("mixed.log:2:"), "{}", stderr(&output));
}

#[test]
fn demo_runs_end_to_end_and_reports_no_loss() {
    let output = run(&["demo", "--monitor", "--speed", "0", "--format", "json"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let lines: Vec<serde_json::Value> = stdout(&output)
        .lines()
        .map(|line| serde_json::from_str(line).expect("json line"))
        .collect();
    let summary = &lines.last().expect("summary line")["summary"];
    assert_eq!(summary["lost"], 0, "{summary}");
    assert_eq!(summary["frames_with_anomalies"], 0, "{summary}");
    assert_eq!(summary["sent"], summary["received"]);
    assert_eq!(lines.len() as u64 - 1, summary["received"].as_u64().unwrap());
}

#[test]
fn demo_on_a_bit_accurate_virtual_bus() {
    let output = run(&[
        "demo",
        "--monitor",
        "--speed",
        "0",
        "--quiet",
        "--bus",
        "virtual:demo?bitrate=500k",
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(stdout(&output).contains("0 lost"), "{}", stdout(&output));
}

#[test]
fn send_dump_and_replay_share_a_hub_and_log_losslessly() {
    let hub = HubProc::start();
    let dir = temp_dir("send-dump");
    let log = dir.join("capture.log");
    let mut dump_cmd = canopener();
    dump_cmd.args([
        "bus",
        "dump",
        "--bus",
        &hub.spec("can0"),
        "--count",
        "6",
        "--log",
        log.to_str().unwrap(),
    ]);
    let mut dump = Proc::spawn("bus dump", dump_cmd);
    // The dump must be connected before we send; its first frame proves it.
    std::thread::sleep(Duration::from_millis(300));
    let send = run(&[
        "bus",
        "send",
        "--bus",
        &hub.spec("can0"),
        "000#0105",
        "705#05",
        "605#4018100100000000",
    ]);
    assert!(send.status.success(), "{}", stderr(&send));
    let replay_src = dir.join("src.log");
    std::fs::write(&replay_src, "(10.000000) can0 080#\n(10.001000) can1 185#0102\n(10.002000) can0 70A#R1\n(10.010000) can0 1ABCDEF0#01F1\n").unwrap();
    let replay = run(&[
        "bus",
        "replay",
        replay_src.to_str().unwrap(),
        "--bus",
        &hub.spec("can0"),
        "--interface",
        "can0",
    ]);
    assert!(replay.status.success(), "{}", stderr(&replay));
    assert!(dump.wait(Duration::from_secs(20)).success(), "{}", dump.stderr());
    let printed = dump.remaining_lines().join("\n");
    for needle in [
        "NMT Start Remote Node -> node 5",
        "Heartbeat node 5: OPERATIONAL",
        "SDO rx node 5: initiate upload 1018h:01",
        "SYNC",
        "Node guarding request node 10",
        "1ABCDEF0",
    ] {
        assert!(
            printed.contains(needle),
            "dump output lacks {needle:?}:\n{printed}"
        );
    }
    // The log holds exactly the six frames, in candump format, readable by our own parser.
    let written = std::fs::read_to_string(&log).unwrap();
    let frames: Vec<&str> = written
        .lines()
        .map(|line| line.split_whitespace().nth(2).unwrap())
        .collect();
    assert_eq!(
        frames,
        [
            "000#0105",
            "705#05",
            "605#4018100100000000",
            "080#",
            "70A#R1",
            "1ABCDEF0#01F1"
        ]
    );

    // An existing log is never overwritten without --overwrite.
    let again = run(&[
        "bus",
        "dump",
        "--bus",
        &hub.spec("can0"),
        "--count",
        "1",
        "--log",
        log.to_str().unwrap(),
    ]);
    assert_eq!(again.status.code(), Some(5));
    assert!(stderr(&again).contains("already exists"));
    assert_eq!(std::fs::read_to_string(&log).unwrap(), written);
}

#[test]
fn output_to_a_closed_pipe_is_not_an_error() {
    let mut child = canopener()
        .args(["demo", "--monitor", "--speed", "0"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawn");
    drop(child.stdout.take());
    let status = child.wait().expect("wait");
    // Either it finished before noticing, or it saw the broken pipe and stopped quietly: never a failure code.
    assert!(status.success() || status.code() == Some(0), "{status:?}");
}

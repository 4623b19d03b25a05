//! Interop with independently written CANopen software: python-can and python `canopen` processes talk to
//! each other and to canopener through `canopener bus serve` (socketcand) and over udp-multicast.
//!
//! The Python peers come from the venv `cargo xtask setup` creates (pinned in tests/python/requirements.txt).

// These tests run the binary and Python peers, wait for them and read the files they produce: the CLI's own bans on clocks, sleeping and files do not
// apply to them.
#![allow(clippy::disallowed_methods, clippy::print_stdout, clippy::print_stderr)]

mod conformance;
mod master_cli;
mod mbt_local_node;
mod networkx;
mod sim_master;
mod support;

use std::time::Duration;

use support::{HubProc, Proc, canopener, corpus_eds, python, python_peer};

/// Frames each python-can process sends in the exchange test. CI uses the default; the full acceptance run
/// sets CANOPENER_INTEROP_FRAMES=100000.
fn exchange_count() -> u64 {
    std::env::var("CANOPENER_INTEROP_FRAMES")
        .ok()
        .and_then(|text| text.parse().ok())
        .unwrap_or(20_000)
}

fn reconnect_count() -> u64 {
    std::env::var("CANOPENER_INTEROP_RECONNECTS")
        .ok()
        .and_then(|text| text.parse().ok())
        .unwrap_or(200)
}

#[test]
fn python_can_processes_exchange_frames_through_the_hub_losslessly_and_in_order() {
    let Some(python) = python() else { return };
    let hub = HubProc::start();
    let count = exchange_count();
    let peer = |send_id: &str, recv_id: &str| {
        let args = [
            hub.addr.ip().to_string(),
            hub.addr.port().to_string(),
            "can0".to_owned(),
            send_id.to_owned(),
            recv_id.to_owned(),
            count.to_string(),
        ];
        python_peer(&python, "pycan_exchange.py", &args)
    };
    let mut left = peer("0x100", "0x200");
    let mut right = peer("0x200", "0x100");
    for proc in [&mut left, &mut right] {
        assert_eq!(
            proc.json(Duration::from_secs(30))["ready"],
            true,
            "{} did not connect",
            proc.name
        );
    }
    left.send_line("go");
    right.send_line("go");
    let timeout = Duration::from_secs(60 + count / 500);
    for proc in [&mut left, &mut right] {
        let result = proc.json(timeout);
        eprintln!("{}: {result}", proc.name);
        assert_eq!(result["received"], count, "{}: {result}", proc.name);
        assert_eq!(result["missing"], 0, "{}: {result}", proc.name);
        assert_eq!(result["out_of_order"], 0, "{}: {result}", proc.name);
        assert_eq!(result["duplicates"], 0, "{}: {result}", proc.name);
        assert_eq!(result["corrupt"], 0, "{}: {result}", proc.name);
        assert_eq!(
            result["send_error"],
            serde_json::json!([]),
            "{}: {result}",
            proc.name
        );
    }
}

#[test]
fn python_can_handshakes_never_fail_while_the_bus_is_flooded() {
    let Some(python) = python() else { return };
    let hub = HubProc::start();
    // An unpaced flood from our own generator keeps frames arriving during every handshake.
    let mut flood_cmd = canopener();
    flood_cmd.args([
        "bus",
        "gen",
        "--bus",
        &hub.spec("can0"),
        "--duration",
        "300s",
        "--id",
        "181",
    ]);
    let mut flood = Proc::spawn("canopener bus gen (flood)", flood_cmd);
    let attempts = reconnect_count();
    let args = [
        hub.addr.ip().to_string(),
        hub.addr.port().to_string(),
        "can0".to_owned(),
        attempts.to_string(),
    ];
    let mut reconnect = python_peer(&python, "pycan_reconnect.py", &args);
    let result = reconnect.json(Duration::from_secs(60 + attempts));
    eprintln!("reconnects: {result}");
    flood.interrupt();
    assert_eq!(result["attempts"], attempts);
    assert_eq!(result["failures"], 0, "python-can handshakes failed: {result}");
    // Every connection read flood frames right after its handshake, so the flood really was on.
    assert_eq!(result["connections_with_traffic"], attempts, "{result}");
    assert!(
        flood.wait(Duration::from_secs(10)).success(),
        "the flood generator failed: {}",
        flood.stderr()
    );
}

#[test]
fn python_canopen_master_and_device_complete_nmt_and_sdo_through_the_hub() {
    let Some(python) = python() else { return };
    let hub = HubProc::start();
    let eds = corpus_eds("canopen-python__canopen__test__sample.eds");
    let node_id = "0x22".to_owned();
    let base = [
        hub.addr.ip().to_string(),
        hub.addr.port().to_string(),
        "can0".to_owned(),
    ];
    let with = |extra: &[String]| base.iter().chain(extra).cloned().collect::<Vec<_>>();

    // Our monitor listens in as a third client and must decode the whole conversation without anomalies.
    let mut sniffer_cmd = canopener();
    sniffer_cmd.args(["bus", "dump", "--bus", &hub.spec("can0"), "--format", "json"]);
    let mut sniffer = Proc::spawn("canopener bus dump", sniffer_cmd);

    let mut device = python_peer(
        &python,
        "co_slave.py",
        &with(&[node_id.clone(), eds.display().to_string()]),
    );
    let mut master = python_peer(
        &python,
        "co_master.py",
        &with(&[node_id, eds.display().to_string(), "300".to_owned()]),
    );
    assert_eq!(device.json(Duration::from_secs(30))["ready"], true);
    assert_eq!(master.json(Duration::from_secs(30))["ready"], true);
    device.send_line("go");
    master.send_line("go");
    let result = master.json(Duration::from_secs(120));
    eprintln!("python canopen through the hub: {result}");
    let checks = result["checks"].as_object().expect("checks object");
    for name in [
        "boot-up received",
        "heartbeat PRE-OPERATIONAL",
        "NMT start",
        "NMT stop",
        "NMT enter pre-operational",
        "SDO expedited upload 1017h",
        "SDO expedited download+upload 2004h",
        "SDO segmented upload 1008h",
        "SDO segmented download+upload 2000h (889 bytes)",
        "SDO abort for a missing object",
    ] {
        let check = &checks[name];
        assert_eq!(check["ok"], true, "check '{name}' failed: {check}");
    }
    device.close_stdin();
    let done = device.json(Duration::from_secs(20));
    assert!(
        done["sdo_requests"].as_u64().is_some_and(|n| n > 300),
        "device saw too few SDO requests: {done}"
    );

    sniffer.interrupt();
    assert!(
        sniffer.wait(Duration::from_secs(10)).success(),
        "bus dump failed: {}",
        sniffer.stderr()
    );
    let frames: Vec<serde_json::Value> = sniffer
        .remaining_lines()
        .iter()
        .filter_map(|line| serde_json::from_str(line).ok())
        .collect();
    let count_of = |service: &str| frames.iter().filter(|frame| frame["service"] == service).count();
    assert!(
        count_of("sdo_rx") > 300 && count_of("sdo_tx") > 300,
        "monitor missed SDO traffic"
    );
    assert!(count_of("nmt") >= 3, "monitor missed NMT commands");
    assert!(
        frames.iter().any(|frame| frame["text"] == "Boot-up node 34"),
        "monitor did not decode the device's boot-up"
    );
    let anomalies: Vec<&serde_json::Value> = frames
        .iter()
        .filter(|frame| frame["anomalies"].as_array().is_some_and(|list| !list.is_empty()))
        .collect();
    assert!(
        anomalies.is_empty(),
        "the monitor decoded protocol anomalies in python canopen traffic: {anomalies:?}"
    );
}

/// python-can's udp_multicast peers and ours share a bus with no server. Runs inside a private network
/// namespace (loopback plus a multicast route) so no datagram leaves the machine; where the kernel does not
/// allow creating one, the test says why and skips, unless CANOPENER_REQUIRE_NETNS is set (CI sets it).
#[test]
fn rust_and_python_can_interoperate_over_udp_multicast() {
    let Some(python) = python() else { return };
    let probe = std::process::Command::new("unshare")
        .args(["--net", "--map-root-user", "true"])
        .status();
    if !probe.is_ok_and(|status| status.success()) {
        let reason = "cannot create a network namespace here (`unshare --net` failed: needs root or \
                      unprivileged user namespaces), and multicast over the host network would leave the machine";
        assert!(std::env::var_os("CANOPENER_REQUIRE_NETNS").is_none(), "{reason}");
        eprintln!("skipped: {reason}");
        return;
    }
    let count = 200;
    let bin = env!("CARGO_BIN_EXE_canopener");
    let group = "239.74.163.2";
    let port = 43113;
    let spec = format!("udp-multicast://{group}:{port}");
    // Inside the namespace: start the python echo peer, our monitor, then send requests with our sender.
    let script = format!(
        r#"set -e
ip link set lo up
ip route add 224.0.0.0/4 dev lo
out=$(mktemp -d)
"{python}" -u "{echo}" {group} {port} 0x123 {count} > "$out/py.jsonl" 2> "$out/py.err" &
py=$!
"{bin}" bus dump --bus {spec} --format json --count {twice} --duration 60s > "$out/dump.jsonl" 2> "$out/dump.err" &
dump=$!
for _ in $(seq 100); do grep -q ready "$out/py.jsonl" 2>/dev/null && break; sleep 0.05; done
sleep 0.3
i=0
while [ $i -lt {count} ]; do
  printf -v frame '123#%08X' $i
  "{bin}" bus send --bus {spec} "$frame"
  i=$((i+1))
done
wait $py || {{ cat "$out/py.err" >&2; exit 11; }}
wait $dump || {{ cat "$out/dump.err" >&2; exit 12; }}
echo "PY $(tail -n 1 "$out/py.jsonl")"
cat "$out/dump.jsonl"
"#,
        python = python.display(),
        echo = support::script("udp_echo.py").display(),
        twice = 2 * count,
    );
    let mut command = std::process::Command::new("unshare");
    command.args(["--net", "--map-root-user", "bash", "-c", &script]);
    let mut proc = Proc::spawn("udp-multicast netns", command);
    let status = proc.wait(Duration::from_secs(180));
    let lines = proc.remaining_lines();
    assert!(
        status.success(),
        "udp-multicast run failed ({status}); stderr:\n{}",
        proc.stderr_after_exit()
    );
    let python_result: serde_json::Value = lines
        .iter()
        .find_map(|line| line.strip_prefix("PY "))
        .and_then(|json| serde_json::from_str(json).ok())
        .expect("python result line");
    assert_eq!(
        python_result["echoed"], count,
        "python-can did not receive every frame we sent: {python_result}"
    );
    let frames: Vec<serde_json::Value> = lines
        .iter()
        .filter_map(|line| serde_json::from_str(line).ok())
        .collect();
    let requests: Vec<&serde_json::Value> = frames.iter().filter(|frame| frame["id"] == "123").collect();
    let replies: Vec<&serde_json::Value> = frames.iter().filter(|frame| frame["id"] == "124").collect();
    assert_eq!(
        requests.len(),
        count,
        "our monitor missed requests sent by our sender"
    );
    assert_eq!(replies.len(), count, "our monitor missed python-can's replies");
    // python-can answered each request with its data; every payload must come back exactly once.
    let mut payloads: Vec<&str> = replies
        .iter()
        .filter_map(|frame| frame["data"].as_str())
        .collect();
    payloads.sort_unstable();
    let expected: Vec<String> = (0..count).map(|i| format!("{i:08X}")).collect();
    assert_eq!(payloads, expected.iter().map(String::as_str).collect::<Vec<_>>());
}

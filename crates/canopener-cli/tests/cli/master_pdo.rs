//! `canopener pdo map` and `canopener pdo watch` against a `canopener sim --app cia401` device on a hub,
//! with a test client on the same hub that drives the inputs, starts the node and sends SYNC.

use std::path::{Path, PathBuf};
use std::time::Duration;

use canopener_transport::CanBus;
use serde_json::Value;

use crate::harness::{
    Background, NO_BUS, WAIT, client, expect_frame, json_lines, json_of, run_exiting, run_on, send,
};
use crate::support::{HubProc, Proc, canopener, corpus_eds};
use crate::{stderr, stdout, temp_dir};

/// CANopenNode's CiA 401 example (6000h, 6401h, TPDO1..4 with 8-entry mappings) plus the factory
/// test registers 2000h..2002h of the CiA 401 application, so the test drives the inputs over SDO.
fn io_eds(dir: &Path) -> PathBuf {
    let mut text = std::fs::read_to_string(corpus_eds("CANopenNode__CANopenNode__example__IO.eds"))
        .expect("read the CiA 401 example EDS");
    let var = |index: &str, name: &str, data_type: &str| {
        format!(
            "\n[{index}]\nParameterName={name}\nObjectType=0x7\nDataType={data_type}\nAccessType=rw\n\
             DefaultValue=0\nPDOMapping=0\n"
        )
    };
    text.push_str(&var("2000", "Factory test config", "0x0001"));
    text.push_str(&var("2001", "Factory test digital inputs", "0x0005"));
    text.push_str(
        "\n[2002]\nParameterName=Factory test analogue inputs\nObjectType=0x8\nSubNumber=3\n\n\
         [2002sub0]\nParameterName=Number of entries\nObjectType=0x7\nDataType=0x0005\nAccessType=ro\n\
         DefaultValue=2\nPDOMapping=0\n",
    );
    text.push_str(&var("2002sub1", "Analogue input 1", "0x0003"));
    text.push_str(&var("2002sub2", "Analogue input 2", "0x0003"));
    let path = dir.join("io.eds");
    std::fs::write(&path, text).expect("write io.eds");
    path
}

/// Node 5 simulated from [`io_eds`] with the CiA 401 application, booted; the test client on the hub.
struct Bench {
    hub: HubProc,
    bus: Box<dyn CanBus>,
    sim: Background,
    eds: PathBuf,
}

impl Bench {
    fn start(dir: &Path) -> Bench {
        let hub = HubProc::start();
        let mut bus = client(&hub);
        let eds = io_eds(dir);
        let sim = Background::sim(
            &hub,
            dir,
            "sim",
            &[eds.to_str().unwrap(), "--node-id", "5", "--app", "cia401"],
        );
        assert_eq!(expect_frame(&mut *bus, "705#", &|| sim.report()), "705#00");
        Bench { hub, bus, sim, eds }
    }

    fn spec(&self) -> String {
        self.hub.spec("can0")
    }

    /// Forgets what the test client received so far (e.g. the SDO traffic of a command).
    fn drain(&mut self) {
        while self.bus.recv(Duration::from_millis(200)).expect("recv").is_some() {}
    }

    /// An SDO request from the test client and the device's answer.
    fn sdo(&mut self, request: &str) -> String {
        self.drain();
        send(&mut *self.bus, request);
        expect_frame(&mut *self.bus, "585#", &|| self.sim.report())
    }

    /// An expedited SDO download from the test client, confirmed by the device.
    fn sdo_write(&mut self, request: &str) {
        let answer = self.sdo(request);
        assert!(answer.starts_with("585#60"), "{request} answered {answer}");
    }

    /// Factory test mode: digital inputs 1..8 = `digital`, analogue input 1 = `analog`.
    fn set_inputs(&mut self, digital: u8, analog: i16) {
        self.sdo_write("605#2F00200001000000");
        self.sdo_write(&format!("605#2F012000{digital:02X}000000"));
        let [low, high] = analog.to_le_bytes();
        self.sdo_write(&format!("605#2B022001{low:02X}{high:02X}0000"));
    }

    fn pdo(&self, args: &[&str]) -> std::process::Output {
        run_on(&self.spec(), &pdo_args(args))
    }
}

fn pdo_args<'a>(args: &[&'a str]) -> Vec<&'a str> {
    let mut all = vec!["pdo"];
    all.extend_from_slice(args);
    all
}

/// `canopener pdo ARGS` on [`NO_BUS`], which must exit 2 without touching the bus: its stderr.
fn refusal(args: &[&str]) -> String {
    stderr(&run_exiting(NO_BUS, &pdo_args(args), 2))
}

#[test]
fn map_a_tpdo_start_the_node_and_watch_the_values_the_device_holds() {
    let dir = temp_dir("pdo-map-watch");
    let mut bench = Bench::start(&dir);
    bench.set_inputs(0x3C, -1234);

    let map = bench.pdo(&[
        "map",
        "--node",
        "5",
        "--tpdo",
        "1",
        "6000:01:8",
        "6401:01:16",
        "--transmission-type",
        "255",
        "--event-timer",
        "100ms",
    ]);
    assert_eq!(map.status.code(), Some(0), "{}", stderr(&map));
    let text = stdout(&map);
    for line in [
        "TPDO1 of node 5: COB-ID 1800h:01 reads 00000185h; 8 SDO writes:",
        "  1/8 1800h:01 = 80000185h (make the PDO invalid while it changes): ok",
        "  3/8 1A00h:01 = 60000108h (map 6000:01:8): ok",
        "  4/8 1A00h:02 = 64010110h (map 6401:01:16): ok",
        "  7/8 1800h:05 = 0064h (event timer in ms): ok",
        "  8/8 1800h:01 = 00000185h (make the PDO valid with its COB-ID): ok",
        "TPDO1 of node 5 configured: 6000:01:8 6401:01:16 (24 bits) on COB-ID 00000185h, valid",
    ] {
        assert!(text.lines().any(|l| l == line), "no line {line:?} in:\n{text}");
    }

    send(&mut *bench.bus, "000#0105");
    let eds = bench.eds.to_str().unwrap().to_owned();
    let watch = bench.pdo(&[
        "watch", "--node", "5", "--eds", &eds, "--count", "3", "--format", "json",
    ]);
    assert_eq!(watch.status.code(), Some(0), "{}", stderr(&watch));
    let events = json_lines(&stdout(&watch));
    let layout = events
        .iter()
        .find(|e| e["event"] == "layout" && e["pdo"] == "TPDO1")
        .expect("a layout for TPDO1");
    assert_eq!(layout["source"], "device");
    assert_eq!(layout["transmission_type"], 255);
    assert_eq!(layout["mapping"][1]["name"], "Read analogue input 16 bit");
    let pdos: Vec<&Value> = events.iter().filter(|e| e["event"] == "pdo").collect();
    assert_eq!(pdos.len(), 3, "{events:?}");
    for pdo in &pdos {
        assert_eq!(pdo["pdo"], "TPDO1");
        assert_eq!(pdo["can_id"], "185");
        assert_eq!(pdo["data"], "3C 2E FB");
        assert_eq!(pdo["fields"][0]["index"], "6000");
        assert_eq!(pdo["fields"][0]["value"], 0x3C);
        assert_eq!(pdo["fields"][0]["text"], "60 (0x3C)");
        assert_eq!(pdo["fields"][1]["value"], -1234);
        assert_eq!(pdo["fields"][1]["type"], "INTEGER16");
    }
    let summary = events.last().expect("a summary");
    assert_eq!(summary["event"], "summary");
    let tpdo1 = &summary["pdos"][0];
    assert_eq!(tpdo1["received"], 3);
    let median = tpdo1["period_ms"]["median"].as_f64().expect("a median period");
    assert!(
        (50.0..200.0).contains(&median),
        "event timer 100 ms, median {median}"
    );

    // Offline, the layout is the EDS's default mapping of TPDO1, not what the device now holds.
    let offline = bench.pdo(&["watch", "--node", "5", "--eds", &eds, "--offline", "--count", "1"]);
    assert_eq!(offline.status.code(), Some(0), "{}", stderr(&offline));
    let text = stdout(&offline);
    assert!(
        text.contains(
            "TPDO1  COB-ID 00000185h  type 255 (event-driven)  16 bits: 6000:01:8 Read input 8 bit, 6000:02:8"
        ),
        "{text}"
    );

    // Issue 13 item 12: without --eds, TPDO 1..4 are read from the device and shown raw, not refused.
    let raw = bench.pdo(&["watch", "--node", "5", "--count", "2", "--format", "json"]);
    assert_eq!(raw.status.code(), Some(0), "{}", stderr(&raw));
    let events = json_lines(&stdout(&raw));
    let layout = events
        .iter()
        .find(|e| e["event"] == "layout" && e["pdo"] == "TPDO1")
        .expect("a layout for TPDO1");
    assert_eq!(layout["mapping"][1]["index"], "6401");
    assert_eq!(layout["mapping"][1]["name"], Value::Null, "no EDS, no names");
    assert_eq!(layout["mapping"][1]["type"], Value::Null, "no EDS, no types");
    let pdos: Vec<&Value> = events.iter().filter(|e| e["event"] == "pdo").collect();
    assert_eq!(pdos.len(), 2, "{events:?}");
    assert!(pdos.iter().all(|pdo| pdo["data"] == "3C 2E FB"), "{pdos:?}");
    let offline_without_eds = bench.pdo(&["watch", "--node", "5", "--offline"]);
    assert_eq!(
        offline_without_eds.status.code(),
        Some(2),
        "--offline needs the EDS's mapping"
    );
}

#[test]
fn a_non_mappable_object_stops_the_plan_at_its_step_with_exit_7() {
    let dir = temp_dir("pdo-map-abort");
    let mut bench = Bench::start(&dir);
    let map = bench.pdo(&["map", "--node", "5", "--tpdo", "1", "6000:01:8", "1017:00:16"]);
    assert_eq!(map.status.code(), Some(7), "{}", stderr(&map));
    let text = stdout(&map);
    assert!(
        text.contains("  4/6 1A00h:02 = 10170010h (map 1017:00:16): SDO abort 0x06040041 from the server: Object cannot be mapped to the PDO"),
        "{text}"
    );
    assert!(
        text.contains("  6/6 1800h:01 = 00000185h (make the PDO valid with its COB-ID): not run"),
        "{text}"
    );
    let err = stderr(&map);
    for needle in [
        "error: TPDO1 of node 5: step 4 of 6, 1A00h:02 = 10170010h (map 1017:00:16): SDO abort 0x06040041",
        "TPDO1 is left invalid (COB-ID 80000185h) with its mapping disabled",
        "canopener nmt reset 5",
    ] {
        assert!(err.contains(needle), "no {needle:?} in:\n{err}");
    }
    // The device holds what the message says: the PDO invalid.
    assert_eq!(bench.sdo("605#4000180100000000"), "585#4300180185010080");

    // JSON: the plan and each step's outcome, and still exit 7.
    let json = bench.pdo(&[
        "map",
        "--node",
        "5",
        "--tpdo",
        "1",
        "1017:00:16",
        "--format",
        "json",
    ]);
    assert_eq!(json.status.code(), Some(7), "{}", stderr(&json));
    let report = json_of(&json);
    assert_eq!(report["configured"], false);
    assert_eq!(report["current_cob_id"], "80000185");
    assert_eq!(report["steps"][2]["outcome"], "aborted");
    assert_eq!(report["steps"][2]["abort_code"], "06040041");
    assert_eq!(report["steps"][3]["outcome"], "not run");
}

#[test]
fn planner_refusals_exit_2_before_the_bus_is_opened() {
    let err = refusal(&[
        "map",
        "--node",
        "5",
        "--tpdo",
        "1",
        "6401:01:32",
        "6401:02:32",
        "6000:01:1",
    ]);
    assert!(
        err.contains("the mapping takes 65 bits; a classical CAN PDO carries at most 64 (8 bytes)"),
        "{err}"
    );
    assert!(
        err.contains("example: canopener pdo map --node 5 --tpdo 1 "),
        "{err}"
    );

    let bad_entry = refusal(&["map", "--node", "5", "--tpdo", "1", "6000-01-8"]);
    assert!(bad_entry.contains("like 6000:01:8"), "{bad_entry}");

    let restricted = refusal(&[
        "map",
        "--node",
        "5",
        "--rpdo",
        "1",
        "6200:01:8",
        "--cob-id",
        "0x605",
    ]);
    assert!(restricted.contains("CAN-ID 605h is restricted"), "{restricted}");

    let missing_eds = refusal(&["watch", "--node", "5", "--eds", "/nonexistent/device.eds"]);
    assert!(missing_eds.contains("/nonexistent/device.eds"));
}

#[test]
fn watch_a_sync_driven_tpdo_while_the_client_sends_sync() {
    let dir = temp_dir("pdo-watch-sync");
    let mut bench = Bench::start(&dir);
    bench.set_inputs(0xA5, 7);
    let map = bench.pdo(&["map", "--node", "5", "--tpdo", "1", "6000:01:8", "--type", "1"]);
    assert_eq!(map.status.code(), Some(0), "{}", stderr(&map));
    send(&mut *bench.bus, "000#0105");

    let mut command = canopener();
    command
        .args([
            "pdo",
            "watch",
            "--node",
            "5",
            "--eds",
            bench.eds.to_str().unwrap(),
        ])
        .args(["--bus", &bench.spec()])
        .env_remove("CANOPENER_BUS");
    let mut watch = Proc::spawn("canopener pdo watch", command);
    // The layout lines come once the mapping is read, just before receiving starts.
    let first = watch.line(WAIT);
    assert_eq!(
        first,
        "TPDO1  COB-ID 00000185h  type 1 (every SYNC)  8 bits: 6000:01:8 Read input 8 bit"
    );
    std::thread::sleep(Duration::from_millis(200));
    for _ in 0..8 {
        send(&mut *bench.bus, "080#");
        std::thread::sleep(Duration::from_millis(100));
    }
    // A frame shorter than the mapping: an error line, not a crash.
    send(&mut *bench.bus, "185#");
    std::thread::sleep(Duration::from_millis(300));
    watch.interrupt();
    assert!(watch.wait(WAIT).success(), "{}", watch.stderr());
    let lines = watch.remaining_lines();
    let values = lines
        .iter()
        .filter(|line| line.ends_with(" TPDO1 185  6000:01 Read input 8 bit = 165 (0xA5)"))
        .count();
    assert_eq!(values, 8, "one TPDO per SYNC:\n{}", lines.join("\n"));
    assert!(
        lines.iter().any(|line| line
            .contains(" TPDO1 185  error: the frame has 0 byte(s) but the mapping needs 1 (8 bits)")),
        "{}",
        lines.join("\n")
    );
    let summary = lines
        .iter()
        .find(|line| line.starts_with("TPDO1 185: "))
        .unwrap_or_else(|| panic!("no summary:\n{}", lines.join("\n")));
    assert!(
        summary.starts_with("TPDO1 185: 9 received, 1 malformed, period min "),
        "{summary}"
    );
}

//! `canopener sdo read|write|upload|download` and `canopener node info|scan|dump` against `canopener sim`
//! through a hub: every type both ways, expedited, segmented and block transfers, large objects byte for
//! byte, aborts and silent nodes (exit 7), argument errors (exit 2), and DCFs the checker loads.

use std::path::{Path, PathBuf};
use std::process::Output;
use std::time::{Duration, Instant};

use serde_json::Value;

use crate::harness::{Background, NO_BUS, WAIT, base_eds, json_of, run_exiting, run_on};
use crate::support::HubProc;
use crate::{run, stderr, stdout, temp_dir};

/// The test device: an object of every type at 2200h, a DOMAIN at 2100h.
const FIXTURE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/cli/fixtures/master_sdo.eds");

/// A hub, a directory for the test's files, and the simulators started on the hub.
struct Bench {
    hub: HubProc,
    spec: String,
    dir: PathBuf,
    sims: Vec<Background>,
}

impl Bench {
    /// No device yet.
    fn empty(name: &str) -> Bench {
        let hub = HubProc::start();
        let spec = hub.spec("can0");
        Bench {
            hub,
            spec,
            dir: temp_dir(name),
            sims: Vec::new(),
        }
    }

    /// The fixture device as node 5.
    fn start(name: &str) -> Bench {
        let mut bench = Bench::empty(name);
        bench.add_sim("sim", 5, "200ms", &[FIXTURE, "--node-id", "5"]);
        bench
    }

    /// Starts `canopener sim ARGS` on the hub and waits until node `first_node` answers an SDO read
    /// within `timeout` (longer than the response delay of a slow device).
    fn add_sim(&mut self, name: &str, first_node: u8, timeout: &str, args: &[&str]) {
        let sim = Background::sim(&self.hub, &self.dir, name, args);
        let node = first_node.to_string();
        let deadline = Instant::now() + WAIT;
        while !self
            .run(&["sdo", "read", "--node", &node, "1000", "0", "--timeout", timeout])
            .status
            .success()
        {
            assert!(
                Instant::now() < deadline,
                "node {node} did not answer within {WAIT:?}; {}",
                sim.report()
            );
        }
        self.sims.push(sim);
    }

    /// `canopener ARGS --bus <hub>`.
    fn run(&self, args: &[&str]) -> Output {
        run_on(&self.spec, args)
    }

    /// Runs and expects exit 0, returning stdout.
    fn ok(&self, args: &[&str]) -> String {
        stdout(&run_exiting(&self.spec, args, 0))
    }

    /// Downloads `bytes` to the DOMAIN 2100h of node 5 from a file `file_name`, with more `options`.
    fn download_domain(&self, file_name: &str, bytes: &[u8], options: &[&str]) {
        let file = self.dir.join(file_name);
        std::fs::write(&file, bytes).unwrap();
        let mut args = vec![
            "sdo",
            "download",
            "--node",
            "5",
            "2100",
            "0",
            file.to_str().unwrap(),
        ];
        args.extend_from_slice(options);
        self.ok(&args);
    }

    /// Runs with `--format json` and parses the one object printed.
    fn json(&self, args: &[&str]) -> Value {
        let mut all = args.to_vec();
        all.extend(["--format", "json"]);
        json_of(&run_exiting(&self.spec, &all, 0))
    }
}

/// Deterministic bytes that are not a pattern a bug could reproduce by accident.
fn data(len: usize, seed: u32) -> Vec<u8> {
    let mut state = seed.wrapping_mul(2_654_435_761).wrapping_add(1);
    (0..len)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            (state >> 8) as u8
        })
        .collect()
}

#[test]
fn sdo_reads_and_writes_every_type_in_both_formats() {
    let bench = Bench::start("sdo-types");
    let eds = FIXTURE;
    // (sub of 2200h, type, value written, JSON value read back as typed by the EDS)
    let cases: [(&str, &str, &str, Value); 15] = [
        ("1", "i8", "-128", Value::from(-128)),
        ("2", "i16", "0x8000", Value::from(-32768)),
        ("3", "i32", "-2147483648", Value::from(-2_147_483_648i64)),
        ("4", "i64", "-1", Value::from(-1)),
        ("5", "u8", "255", Value::from(255)),
        ("6", "u16", "0xFFFF", Value::from(65535)),
        ("7", "u32", "4294967295", Value::from(4_294_967_295u64)),
        ("8", "u64", "0xFFFFFFFFFFFFFFFF", Value::from(u64::MAX)),
        ("9", "f32", "-2.5", Value::from(-2.5)),
        ("A", "f64", "1e-3", Value::from(0.001)),
        ("B", "bool", "false", Value::from(false)),
        (
            "C",
            "str",
            "a longer text, segmented",
            Value::from("a longer text, segmented"),
        ),
        (
            "D",
            "hex",
            "00 01 FE FF 10 20 30 40",
            Value::from("00 01 FE FF 10 20 30 40"),
        ),
        ("E", "u24", "0xABCDEF", Value::from(0xAB_CDEF)),
        ("F", "i24", "-8388608", Value::from(-8_388_608)),
    ];
    for (sub, ty, value, expected) in &cases {
        let written = bench.json(&["sdo", "write", "--node", "5", "2200", sub, value, "--type", ty]);
        assert_eq!(written["confirmed"], true, "{written}");
        assert_eq!(&written["value"], expected, "{sub} {ty}: {written}");
        let read = bench.json(&["sdo", "read", "--node", "5", "2200", sub, "--eds", eds]);
        assert_eq!(&read["value"], expected, "{sub} {ty}: {read}");
        assert_eq!(read["type"], *ty, "{read}");
        assert_eq!(read["type_source"], "eds");
        assert!(read["elapsed_ms"].as_f64().is_some_and(|ms| ms > 0.0), "{read}");
        let by_option = bench.json(&["sdo", "read", "--node", "5", "2200", sub, "--type", ty]);
        assert_eq!(by_option["raw"], read["raw"]);
        assert_eq!(by_option["type_source"], "option");
    }
    // The string took the segmented protocol, the numbers the expedited one.
    let text = bench.json(&["sdo", "read", "--node", "5", "2200", "C", "--type", "str"]);
    assert_eq!(text["protocol"], "segmented");
    let small = bench.json(&["sdo", "read", "--node", "5", "2200", "5", "--type", "u8"]);
    assert_eq!(
        (small["protocol"].as_str(), small["raw"].as_str()),
        (Some("expedited"), Some("FF"))
    );

    // Text output: name, decimal and hex; EDS typing of a write; forced segmented and block transfers.
    let line = bench.ok(&[
        "sdo",
        "write",
        "--node",
        "5",
        "0x2200",
        "05h",
        "0x7B",
        "--eds",
        eds,
        "--segmented",
    ]);
    assert!(
        line.starts_with(
            "2200h:05 Unsigned8 = 123 (0x7B): written, node 5 confirmed (segmented download, 1 byte, "
        ) && line.ends_with(" ms)\n"),
        "{line}"
    );
    assert_eq!(
        bench.ok(&["sdo", "read", "--node", "5", "2200", "5", "--eds", eds]),
        "2200h:05 Unsigned8 = 123 (0x7B)\n"
    );
    let block = bench.json(&[
        "sdo",
        "write",
        "--node",
        "5",
        "2200",
        "8",
        "0x0123456789ABCDEF",
        "--type",
        "u64",
        "--block",
    ]);
    assert_eq!(block["protocol"], "block");
    let block = bench.json(&["sdo", "read", "--node", "5", "2200", "8", "--block", "--eds", eds]);
    assert_eq!(
        (block["protocol"].as_str(), block["raw"].as_str()),
        (Some("block"), Some("EFCDAB8967452301"))
    );
    let name = bench.json(&["sdo", "read", "--node", "5", "1008", "0", "--block"]);
    assert_eq!(name["value"], "canopener test device");
    assert_eq!(name["type_source"], "guessed");

    // Without --type or --eds a read types by length and says so.
    let guessed = bench.run(&["sdo", "read", "--node", "5", "1018", "1"]);
    assert_eq!(stdout(&guessed), "1018h:01 = 2748 (0x00000ABC)\n");
    assert!(
        stderr(&guessed).contains("typed as u32 by its length"),
        "{}",
        stderr(&guessed)
    );
}

#[test]
fn upload_and_download_of_a_large_domain_are_byte_identical() {
    let bench = Bench::start("sdo-domain");
    for (bytes, block, seed) in [(30_000, false, 1), (300_000, true, 2)] {
        let original = data(bytes, seed);
        let input = bench.dir.join(format!("in-{seed}.bin"));
        let output = bench.dir.join(format!("out-{seed}.bin"));
        std::fs::write(&input, &original).unwrap();
        let (input_arg, output_arg) = (input.to_str().unwrap(), output.to_str().unwrap());
        let mut down = vec!["sdo", "download", "--node", "5", "2100", "0", input_arg];
        let mut up = vec!["sdo", "upload", "--node", "5", "2100", "0", "-o", output_arg];
        if block {
            down.push("--block");
            up.push("--block");
        }
        let line = bench.ok(&down);
        let protocol = if block { "block" } else { "segmented" };
        assert!(
            line.starts_with(&format!(
                "wrote {bytes} bytes from {input_arg} to node 5, 2100h:00 in "
            )) && line.contains(&format!(" kB/s, {protocol})")),
            "{line}"
        );
        let report = bench.json(&up);
        assert_eq!(report["bytes"], bytes);
        assert_eq!(report["protocol"], protocol);
        assert!(
            report["kbytes_per_s"].as_f64().is_some_and(|rate| rate > 0.0),
            "{report}"
        );
        assert!(
            std::fs::read(&output).unwrap() == original,
            "{bytes} bytes differ after the round trip"
        );
        eprintln!(
            "{bytes} bytes {protocol}: download {}, upload {:.1} kB/s",
            line.trim(),
            report["kbytes_per_s"].as_f64().unwrap_or_default()
        );

        // The result is never overwritten without --force; with it the old file is kept as .bak.
        let refused = bench.run(&up);
        assert_eq!(refused.status.code(), Some(2), "{}", stderr(&refused));
        assert!(stderr(&refused).contains("--force"), "{}", stderr(&refused));
        std::fs::write(&output, b"old").unwrap();
        up.push("--force");
        bench.ok(&up);
        assert!(std::fs::read(&output).unwrap() == original);
        let mut backup = output.clone().into_os_string();
        backup.push(".bak");
        assert_eq!(std::fs::read(PathBuf::from(backup)).unwrap(), b"old");
    }
}

#[test]
fn aborts_silent_nodes_and_bad_arguments_give_clear_errors() {
    let bench = Bench::start("sdo-errors");
    let eds = FIXTURE;

    let missing_sub = bench.run(&["sdo", "read", "--node", "5", "1018", "5"]);
    assert_eq!(missing_sub.status.code(), Some(7));
    assert_eq!(
        stderr(&missing_sub),
        "error: node 5, 1018h:05: SDO abort 0x06090011 from the server: Sub-index does not exist\n"
    );
    let never = bench.dir.join("never.bin");
    let missing_object = bench.run(&[
        "sdo",
        "upload",
        "--node",
        "5",
        "3000",
        "0",
        "-o",
        never.to_str().unwrap(),
    ]);
    assert_eq!(missing_object.status.code(), Some(7));
    assert!(
        stderr(&missing_object)
            .contains("node 5, 3000h:00: SDO abort 0x06020000 from the server: Object does not exist")
    );
    assert!(!never.exists());

    let read_only = bench.run(&["sdo", "write", "--node", "5", "1018", "1", "5", "--eds", eds]);
    assert_eq!(read_only.status.code(), Some(7));
    let text = stderr(&read_only);
    assert!(
        text.contains("warning: node 5, 1018h:01 (Vendor-ID): the EDS gives AccessType=ro"),
        "{text}"
    );
    assert!(
        text.contains("error: node 5, 1018h:01 (Vendor-ID): SDO abort 0x06010002 from the server: Attempt to write a read-only object"),
        "{text}"
    );
    let too_high = bench.run(&["sdo", "write", "--node", "5", "2000", "0", "5000", "--eds", eds]);
    assert_eq!(too_high.status.code(), Some(7));
    assert!(
        stderr(&too_high).contains("5000 is above the EDS's HighLimit=1000"),
        "{}",
        stderr(&too_high)
    );
    assert!(stderr(&too_high).contains("0x06090031"));

    // Nothing has node-ID 9: a timeout naming what was waited for, after about the timeout.
    let started = Instant::now();
    let dead = bench.run(&["sdo", "read", "--node", "9", "1000", "0", "--timeout", "300ms"]);
    let took = started.elapsed();
    assert_eq!(dead.status.code(), Some(7));
    assert_eq!(
        stderr(&dead),
        "error: node 9, 1000h:00: timed out after 300ms waiting for the initiate upload response (abort 0x05040000 sent to the server)\n"
    );
    assert!(took < Duration::from_secs(3), "took {took:?}");
    let dead_info = bench.run(&["node", "info", "--node", "9", "--timeout", "200ms"]);
    assert_eq!(dead_info.status.code(), Some(7));
    assert!(stderr(&dead_info).contains("node 9, 1000h:00 (Device type): timed out after 200ms"));

    // Argument errors exit 2 with an example before the bus is opened (port 9 has no hub).
    for args in [
        vec!["sdo", "read", "--node", "5", "zz", "0"],
        vec!["sdo", "read", "--node", "5", "1018", "100"],
        vec!["sdo", "read", "--node", "5", "1018", "1", "--type", "u9"],
        vec!["sdo", "write", "--node", "5", "1017", "0", "1000"],
        vec![
            "sdo", "write", "--node", "5", "1017", "0", "lots", "--type", "u16",
        ],
        vec![
            "sdo", "write", "--node", "5", "1017", "0", "70000", "--type", "u16",
        ],
        vec!["sdo", "write", "--node", "5", "3000", "0", "1", "--eds", eds],
        vec!["sdo", "upload", "--node", "5", "1F50", "x1", "-o", "out.bin"],
        vec!["node", "scan", "--range", "0-200"],
        vec!["node", "dump", "--node", "5", "--eds", eds, "--format", "json"],
    ] {
        let output = run_on(NO_BUS, &args);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {}", stderr(&output));
        let text = stderr(&output);
        assert!(
            text.contains("e.g.") || text.contains("like "),
            "{args:?} gives no example: {text}"
        );
    }
    let zero = run_on(
        NO_BUS,
        &["sdo", "read", "--node", "5", "1018", "1", "--timeout", "0s"],
    );
    assert_eq!(zero.status.code(), Some(2), "{}", stderr(&zero));
}

#[test]
fn misbehaving_devices_end_in_a_clean_abort_or_timeout() {
    let mut bench = Bench::empty("sdo-faults");
    let args = [FIXTURE, "--node-id", "7", "--fault", "block-crc-wrong"];
    bench.add_sim("crc", 7, "200ms", &args);
    let bad_crc = bench.run(&["sdo", "read", "--node", "7", "1008", "0", "--block"]);
    assert_eq!(bad_crc.status.code(), Some(7), "{}", stderr(&bad_crc));
    assert!(
        stderr(&bad_crc).contains("node 7, 1008h:00: SDO transfer aborted by the client with 0x05040004"),
        "{}",
        stderr(&bad_crc)
    );

    // A device that answers later than the timeout, in the middle of a segmented transfer too.
    let args = [FIXTURE, "--node-id", "8", "--fault", "sdo-slow"];
    bench.add_sim("slow", 8, "2s", &args);
    let started = Instant::now();
    let never = bench.dir.join("x");
    let slow = bench.run(&[
        "sdo",
        "upload",
        "--node",
        "8",
        "1008",
        "0",
        "-o",
        never.to_str().unwrap(),
        "--timeout",
        "250ms",
    ]);
    assert_eq!(slow.status.code(), Some(7));
    assert!(
        stderr(&slow).contains("node 8, 1008h:00: timed out after 250ms waiting for the"),
        "{}",
        stderr(&slow)
    );
    assert!(started.elapsed() < Duration::from_secs(3));
    assert!(!never.exists(), "nothing is written after a failed upload");
}

#[test]
fn node_info_reports_identity_names_and_heartbeat_state() {
    let bench = Bench::start("node-info");
    let info = bench.ok(&["node", "info", "--node", "5"]);
    for needle in [
        "Node 5\n",
        "Device type       0x000F0191  CiA 401 generic I/O: digital inputs, digital outputs, analogue inputs, analogue outputs",
        "Error register    0x00  no error",
        "Vendor-ID         0x00000ABC  (2748)",
        "Product code      0x00000401  (1025)",
        "Revision number   0x00010002  (65538)",
        "Serial number     0x00000000  (0)",
        "Device name       \"canopener test device\"",
        "Hardware version  not implemented",
        "Software version  not implemented",
        "Heartbeat         off (1017h = 0)",
    ] {
        assert!(info.contains(needle), "{needle:?} missing:\n{info}");
    }
    // Heartbeat every 100 ms and Operational: one heartbeat gives the state.
    bench.ok(&["sdo", "write", "--node", "5", "1017", "0", "100", "--type", "u16"]);
    bench.ok(&["bus", "send", "000#0105"]);
    let base = base_eds();
    let json = bench.json(&["node", "info", "--node", "5", "--eds", base.to_str().unwrap()]);
    assert_eq!(json["node"], 5);
    assert_eq!(json["device_type"]["profile"], 401);
    assert_eq!(json["device_type"]["profile_name"], "CiA 401 generic I/O");
    assert_eq!(json["identity"]["vendor_id"], 0xABC);
    assert_eq!(json["identity"]["serial_number"], 0);
    assert_eq!(json["names"]["device_name"], "canopener test device");
    assert!(json["names"]["hardware_version"].is_null());
    assert_eq!(json["heartbeat_time_ms"], 100);
    assert_eq!(json["heartbeat"]["state"], "OPERATIONAL", "{json}");
    assert!(
        json["heartbeat"]["after_ms"]
            .as_f64()
            .is_some_and(|ms| ms <= 150.0),
        "{json}"
    );
    assert!(
        json["eds"]["check"]
            .as_str()
            .unwrap()
            .ends_with("identity matches"),
        "{json}"
    );
    assert_eq!(json["problems"], serde_json::json!({}));
}

#[test]
fn node_scan_finds_two_sims_among_127_node_ids_in_about_one_timeout() {
    let mut bench = Bench::empty("node-scan");
    let args = [FIXTURE, FIXTURE, "--node-id", "20", "--serial", "0x100"];
    bench.add_sim("sims", 20, "200ms", &args);
    let started = Instant::now();
    let output = bench.run(&["node", "scan", "--timeout", "500ms", "--format", "json"]);
    let took = started.elapsed();
    assert!(output.status.success(), "{}", stderr(&output));
    let json = json_of(&output);
    assert_eq!(json["asked"], 127);
    let nodes: Vec<(u64, u64)> = json["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| (n["node"].as_u64().unwrap(), n["serial_number"].as_u64().unwrap()))
        .collect();
    assert_eq!(nodes, [(20, 0x100), (21, 0x101)], "{json}");
    assert_eq!(json["nodes"][0]["vendor_id"], 0xABC);
    // 125 silent node-IDs cost one timeout together, not 125.
    assert!(took < Duration::from_millis(2500), "scan took {took:?}");
    eprintln!(
        "node scan of 127 IDs, 2 devices, --timeout 500ms: {:.0} ms (command: {took:?})",
        json["elapsed_ms"].as_f64().unwrap_or_default()
    );

    let table = stdout(&bench.run(&[
        "node",
        "scan",
        "--range",
        "15-25",
        "--timeout",
        "200ms",
        "--parallel",
        "4",
    ]));
    assert!(
        table.contains(
            "  20  0x000F0191  0x00000ABC  0x00000401  0x00010002  0x00000100  CiA 401 generic I/O"
        ),
        "{table}"
    );
    assert!(table.contains("2 of 11 node-IDs answered in "), "{table}");
}

/// The error codes of P-series findings `canopener eds check` reports for a file.
fn p_errors(file: &Path) -> Vec<String> {
    let output = run(&["eds", "check", file.to_str().unwrap(), "--format", "json"]);
    let report: Value =
        serde_json::from_str(&stdout(&output)).unwrap_or_else(|err| panic!("{err}: {}", stderr(&output)));
    let file_report = &report["files"][0];
    assert!(file_report["problem"].is_null(), "{file_report}");
    let mut codes: Vec<String> = file_report["findings"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| f["severity"] == "error" && f["code"].as_str().is_some_and(|c| c.starts_with('P')))
        .map(|f| f["code"].as_str().unwrap().to_owned())
        .collect();
    codes.sort();
    codes
}

#[test]
fn node_dump_writes_a_dcf_of_the_device_values_that_the_checker_loads() {
    let bench = Bench::start("node-dump");
    let eds_arg = FIXTURE;
    // Values the EDS does not have: a written parameter, a string, a short and a long DOMAIN.
    bench.ok(&[
        "sdo", "write", "--node", "5", "2000", "0", "0x1F4", "--type", "u16",
    ]);
    bench.ok(&[
        "sdo",
        "write",
        "--node",
        "5",
        "2200",
        "C",
        "changed on the device",
        "--type",
        "str",
    ]);
    bench.download_domain("short.bin", &[0xDE, 0xAD, 0xBE, 0xEF], &[]);

    let dcf = bench.dir.join("node5.dcf");
    let dcf_arg = dcf.to_str().unwrap();
    let summary = bench.json(&["node", "dump", "--node", "5", "--eds", eds_arg, "-o", dcf_arg]);
    assert_eq!(summary["read"], 46, "{summary}");
    assert_eq!(summary["aborted"], serde_json::json!([]));

    let text = std::fs::read_to_string(&dcf).unwrap();
    let loaded = canopener_eds::load(text.as_bytes()).eds;
    let value = |index: u16, sub: Option<u8>| {
        let object = &loaded.objects[&index];
        let attributes = match sub {
            Some(sub) => &object.subs[&sub].attributes,
            None => &object.attributes,
        };
        attributes.parameter_value.clone().unwrap_or_default()
    };
    assert_eq!(value(0x2000, None), "0x1F4");
    assert_eq!(value(0x2200, Some(0x0C)), "changed on the device");
    assert_eq!(value(0x2100, None), "DEADBEEF");
    assert_eq!(value(0x1018, Some(1)), "0xABC");
    assert_eq!(value(0x1000, None), "0xF0191");
    assert_eq!(value(0x1200, Some(1)), "0x605");
    assert_eq!(value(0x2200, Some(4)), "-5000000000");
    assert_eq!(value(0x2200, Some(9)), "1.5");
    assert_eq!(value(0x1008, None), "canopener test device");
    assert_eq!(loaded.node_id(), Some(5));
    let commissioning = loaded.commissioning.as_ref().unwrap();
    assert_eq!(commissioning.node_name.as_deref(), Some("canopener test device"));
    assert_eq!(loaded.file_info.file_name.as_deref(), Some("node5.dcf"));
    assert_eq!(loaded.file_info.last_eds.as_deref(), Some("master_sdo.eds"));
    assert!(
        text.starts_with("; DCF of node 5 made by canopener node dump from master_sdo.eds: 46 entries read")
    );

    // The checker loads it with no P-series error the EDS did not already have.
    assert_eq!(p_errors(&dcf), p_errors(Path::new(FIXTURE)));

    // A DOMAIN too long for a line goes to a file named by UploadFile; the DCF is not overwritten
    // without --force.
    let bytes = data(5000, 3);
    bench.download_domain("long.bin", &bytes, &["--block"]);
    let refused = bench.run(&["node", "dump", "--node", "5", "--eds", eds_arg, "-o", dcf_arg]);
    assert_eq!(refused.status.code(), Some(2), "{}", stderr(&refused));
    let line = bench.ok(&[
        "node", "dump", "--node", "5", "--eds", eds_arg, "-o", dcf_arg, "--force",
    ]);
    assert!(line.starts_with("node 5: 46 entries read into "), "{line}");
    let loaded = canopener_eds::load(&std::fs::read(&dcf).unwrap()).eds;
    assert_eq!(
        loaded.objects[&0x2100].attributes.upload_file.as_deref(),
        Some("node5_2100sub0.bin")
    );
    assert!(std::fs::read(bench.dir.join("node5_2100sub0.bin")).unwrap() == bytes);
    assert_eq!(p_errors(&dcf), p_errors(Path::new(FIXTURE)));

    // To stdout: the DCF there, the summary on stderr; the long DOMAIN becomes a comment.
    let to_stdout = bench.run(&["node", "dump", "--node", "5", "--eds", eds_arg]);
    assert!(to_stdout.status.success(), "{}", stderr(&to_stdout));
    let text = stdout(&to_stdout);
    assert!(
        text.contains("[DeviceComissioning]") && text.contains("; 5000 bytes read, too long for one line"),
        "{text}"
    );
    assert!(
        stderr(&to_stdout).starts_with("node 5: 45 entries read into stdout"),
        "{}",
        stderr(&to_stdout)
    );
}

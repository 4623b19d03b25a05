//! `canopener sim`: a simulated device from an EDS on a hub, driven by a test client over socketcand.

use std::time::Instant;

use crate::harness::{
    Background, NO_BUS, WAIT, base_eds, client, expect_frame, identify_unconfigured, json_lines, run_on, send,
};
use crate::support::{HubProc, corpus_eds};
use crate::{run, stderr, stdout, temp_dir};

#[test]
fn sim_boots_answers_sdo_runs_nmt_and_heartbeat_and_stops_cleanly() {
    let hub = HubProc::start();
    let dir = temp_dir("sim-run");
    // The client is on the hub before the device boots, so it sees the boot-up message.
    let mut bus = client(&hub);
    let eds = base_eds();
    let mut sim = Background::sim(
        &hub,
        &dir,
        "sim",
        &[eds.to_str().unwrap(), "--node-id", "5", "--format", "json"],
    );
    let context = || sim.report();
    assert_eq!(expect_frame(&mut *bus, "705#", &context), "705#00");

    // Expedited upload of 1018h:01, the vendor-ID.
    send(&mut *bus, "605#4018100100000000");
    assert_eq!(expect_frame(&mut *bus, "585#", &context), "585#43181001BC0A0000");

    // 1017h = 100 ms, then NMT start: heartbeats with state 05h.
    send(&mut *bus, "605#2B17100064000000");
    assert_eq!(expect_frame(&mut *bus, "585#", &context), "585#6017100000000000");
    send(&mut *bus, "000#0105");
    assert_eq!(expect_frame(&mut *bus, "705#05", &context), "705#05");

    let status = sim.terminate();
    assert_eq!(status.code(), Some(0), "stderr:\n{}", sim.stderr());
    let events = json_lines(&sim.stdout());
    let kinds: Vec<&str> = events.iter().filter_map(|e| e["event"].as_str()).collect();
    for kind in ["started", "boot_up", "sdo_write", "nmt_state", "stopped"] {
        assert!(kinds.contains(&kind), "no {kind} event in {kinds:?}");
    }
    assert!(
        events
            .iter()
            .any(|e| e["event"] == "nmt_state" && e["to"] == "operational" && e["node"] == 5),
        "{events:?}"
    );
}

/// Issue 22: python canopen's sample.eds configures node 0x10 and 500 kbit/s in [DeviceComissioning];
/// `--node-id 5` used to run node 16 without a word. The flag wins, and the start line says where the
/// node-ID and the bit rate come from.
#[test]
fn sim_node_id_asked_for_wins_over_the_files_and_the_start_line_says_so() {
    let hub = HubProc::start();
    let dir = temp_dir("sim-node-id");
    let mut bus = client(&hub);
    let eds = corpus_eds("canopen-python__canopen__test__sample.eds");
    let mut sim = Background::sim(
        &hub,
        &dir,
        "sim",
        &[eds.to_str().unwrap(), "--node-id", "5", "--format", "json"],
    );
    let context = || sim.report();
    assert_eq!(expect_frame(&mut *bus, "705#", &context), "705#00");
    send(&mut *bus, "605#4018100100000000");
    assert_eq!(expect_frame(&mut *bus, "585#", &context), "585#4318100101000000");
    assert_eq!(sim.terminate().code(), Some(0), "{}", sim.stderr());
    let events = json_lines(&sim.stdout());
    let started = events
        .iter()
        .find(|e| e["event"] == "started")
        .unwrap_or_else(|| panic!("no started event in {events:?}"));
    assert_eq!(started["node"], 5);
    assert_eq!(started["node_id_from"], "asked");
    assert_eq!(
        (started["bitrate_from"].as_str(), started["file_bitrate"].as_u64()),
        (Some("bus"), Some(500))
    );
    let text = started["text"].as_str().unwrap_or_default();
    assert!(
        text.contains(
            "; node-ID 5 as asked (the file's [DeviceComissioning] NodeID=16 is not used); bit rate: \
                       the bus's (the file's [DeviceComissioning] Baudrate=500 kbit/s is not applied)"
        ),
        "{text}"
    );

    // Without --node-id the file's node-ID is used, and the line says so.
    let mut sim = Background::sim(
        &hub,
        &dir,
        "sim-own",
        &[eds.to_str().unwrap(), "--format", "json"],
    );
    let context = || sim.report();
    assert_eq!(expect_frame(&mut *bus, "710#", &context), "710#00");
    assert_eq!(sim.terminate().code(), Some(0), "{}", sim.stderr());
    let events = json_lines(&sim.stdout());
    let started = events.iter().find(|e| e["event"] == "started").expect("started");
    assert_eq!(
        (started["node"].as_u64(), started["node_id_from"].as_str()),
        (Some(16), Some("file"))
    );
    assert!(
        started["text"]
            .as_str()
            .is_some_and(|t| t.contains("; node-ID 16 from the file's [DeviceComissioning] NodeID")),
        "{started}"
    );
}

#[test]
fn sim_keeps_saved_parameters_in_the_state_dir_across_restarts() {
    let hub = HubProc::start();
    let dir = temp_dir("sim-state");
    let state = dir.join("state");
    // base.eds with store parameters 1010h (sub-index 1, all parameters).
    let mut text = std::fs::read_to_string(base_eds()).unwrap();
    text.push_str(
        "\n[1010]\nParameterName=Store parameters\nObjectType=0x8\nSubNumber=2\n\n\
         [1010sub0]\nParameterName=Highest sub-index supported\nObjectType=0x7\nDataType=0x0005\n\
         AccessType=ro\nDefaultValue=1\nPDOMapping=0\n\n\
         [1010sub1]\nParameterName=Save all parameters\nObjectType=0x7\nDataType=0x0007\n\
         AccessType=rw\nDefaultValue=1\nPDOMapping=0\n",
    );
    let eds = dir.join("store.eds");
    std::fs::write(&eds, text).unwrap();
    let args = [
        eds.to_str().unwrap(),
        "--node-id",
        "7",
        "--state-dir",
        state.to_str().unwrap(),
    ];
    let mut bus = client(&hub);
    let mut sim = Background::sim(&hub, &dir, "sim", &args);
    let context = || sim.report();
    expect_frame(&mut *bus, "707#00", &context);
    send(&mut *bus, "607#2B171000FA000000");
    assert_eq!(expect_frame(&mut *bus, "587#", &context), "587#6017100000000000");
    // 1010h:01 = "save".
    send(&mut *bus, "607#2310100173617665");
    assert_eq!(expect_frame(&mut *bus, "587#", &context), "587#6010100100000000");
    assert_eq!(sim.terminate().code(), Some(0), "{}", sim.stderr());
    assert!(state.join("node-007.params").exists());
    drop(sim);

    let mut sim = Background::sim(&hub, &dir, "sim", &args);
    let context = || sim.report();
    expect_frame(&mut *bus, "707#00", &context);
    send(&mut *bus, "607#4017100000000000");
    assert_eq!(expect_frame(&mut *bus, "587#", &context), "587#4B171000FA000000");
    assert_eq!(sim.terminate().code(), Some(0), "{}", sim.stderr());
}

#[test]
fn sim_refuses_bad_files_and_bad_state() {
    let dir = temp_dir("sim-bad");
    let bad = dir.join("broken.eds");
    std::fs::write(&bad, "garbage without sections\n").unwrap();
    let output = run_on(NO_BUS, &["sim", bad.to_str().unwrap(), "--node-id", "5"]);
    assert_eq!(output.status.code(), Some(3), "{}", stderr(&output));
    assert!(stderr(&output).contains("broken.eds"), "{}", stderr(&output));

    // A stored LSS configuration that does not parse names the file and line.
    let state = dir.join("state");
    std::fs::create_dir_all(&state).unwrap();
    std::fs::write(
        state.join("lss-00000ABC-00000401-00010002-00000000.lss"),
        "node-id 200\n",
    )
    .unwrap();
    let eds = base_eds();
    let bad_lss = run_on(
        NO_BUS,
        &[
            "sim",
            eds.to_str().unwrap(),
            "--state-dir",
            state.to_str().unwrap(),
        ],
    );
    assert_eq!(bad_lss.status.code(), Some(3), "{}", stderr(&bad_lss));
    assert!(
        stderr(&bad_lss).contains(".lss:1: the node-ID must be 1 to 127"),
        "{}",
        stderr(&bad_lss)
    );

    let help = run(&["sim", "--help"]);
    assert!(help.status.success());
    assert!(
        String::from_utf8_lossy(&help.stdout).contains("Examples:"),
        "{help:?}"
    );
}

#[test]
fn unconfigured_sims_are_found_by_lss_and_boot_with_the_node_id_it_gives() {
    let hub = HubProc::start();
    let dir = temp_dir("sim-lss");
    let mut bus = client(&hub);
    let eds = base_eds();
    let eds = eds.to_str().unwrap();
    let mut sim = Background::sim(
        &hub,
        &dir,
        "sim",
        &[eds, eds, "--serial", "0x100", "--format", "json"],
    );
    // Both devices are unconfigured: each answers "identify non-configured remote slave".
    // Asked again until the simulator is on the hub (it may still be starting).
    let deadline = Instant::now() + WAIT;
    let mut answers = Vec::new();
    while answers.is_empty() && Instant::now() < deadline {
        answers = identify_unconfigured(&mut *bus);
    }
    assert_eq!(
        answers,
        ["7E4#5000000000000000", "7E4#5000000000000000"],
        "both devices answer; sim stderr:\n{}",
        sim.stderr()
    );
    // Select the second device by its LSS address (base.eds: vendor ABCh, product 401h, revision
    // 10002h; serial 101h from --serial), give it node-ID 9, and let it boot.
    for frame in [
        "7E5#40BC0A0000000000",
        "7E5#4101040000000000",
        "7E5#4202000100000000",
        "7E5#4301010000000000",
    ] {
        send(&mut *bus, frame);
    }
    let context = || sim.report();
    assert_eq!(expect_frame(&mut *bus, "7E4#", &context), "7E4#4400000000000000");
    send(&mut *bus, "7E5#1109000000000000");
    assert_eq!(expect_frame(&mut *bus, "7E4#", &context), "7E4#1100000000000000");
    send(&mut *bus, "7E5#0400000000000000");
    assert_eq!(expect_frame(&mut *bus, "709#", &context), "709#00");
    send(&mut *bus, "609#4018100400000000");
    assert_eq!(expect_frame(&mut *bus, "589#", &context), "589#4318100401010000");

    assert_eq!(sim.terminate().code(), Some(0), "stderr:\n{}", sim.stderr());
    let events = json_lines(&sim.stdout());
    assert!(
        events
            .iter()
            .any(|e| e["event"] == "node_id" && e["from"].is_null() && e["to"] == 9),
        "{events:?}"
    );
}

#[test]
fn list_faults_describes_the_catalogue_and_unknown_faults_are_refused() {
    let output = run(&["sim", "--list-faults"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let text = stdout(&output);
    for fault in canopener_device::faults::Fault::ALL {
        assert!(
            text.contains(fault.name()),
            "{} not listed:\n{text}",
            fault.name()
        );
    }
    let unknown = run(&["sim", "x.eds", "--fault", "no-such-fault", "--node-id", "5"]);
    assert_eq!(unknown.status.code(), Some(2));
    assert!(
        stderr(&unknown).contains("no-boot-up"),
        "the error lists the names: {}",
        stderr(&unknown)
    );
}

#[test]
fn a_sim_made_time_producer_sends_the_wall_clock_time() {
    let hub = HubProc::start();
    let dir = temp_dir("sim-time");
    let mut bus = client(&hub);
    let eds = corpus_eds("CANopenNode__CANopenNode__example__DS301_profile.eds");
    let mut sim = Background::sim(&hub, &dir, "sim", &[eds.to_str().unwrap(), "--node-id", "7"]);
    let context = || sim.report();
    assert_eq!(expect_frame(&mut *bus, "707#", &context), "707#00");
    // 1012h = 4000 0100h: produce TIME on 100h.
    send(&mut *bus, "607#2312100000010040");
    assert_eq!(expect_frame(&mut *bus, "587#", &context), "587#6012100000000000");
    let frame = expect_frame(&mut *bus, "100#", &context);
    let bytes: Vec<u8> = (4..16)
        .step_by(2)
        .map(|at| u8::from_str_radix(&frame[at..at + 2], 16).expect("hex"))
        .collect();
    let millis = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]) & 0x0FFF_FFFF;
    let days = u16::from_le_bytes([bytes[4], bytes[5]]);
    // The days since 1984-01-01 of the machine's clock (either side of midnight).
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .expect("clock after 1970")
        .as_millis();
    let today = ((now - 441_763_200_000) / 86_400_000) as u16;
    assert!(
        days == today || days + 1 == today,
        "{frame}: day {days}, expected {today}"
    );
    assert!(millis < 86_400_000, "{frame}");
    sim.terminate();
}

#[test]
fn an_lss_stored_node_id_survives_a_restart_of_the_simulator() {
    let hub = HubProc::start();
    let dir = temp_dir("sim-lss-store");
    let state = dir.join("state");
    let eds = base_eds();
    let args = [
        eds.to_str().unwrap(),
        "--serial",
        "0x200",
        "--state-dir",
        state.to_str().unwrap(),
    ];
    let mut bus = client(&hub);
    let mut sim = Background::sim(&hub, &dir, "first", &args);
    let deadline = Instant::now() + WAIT;
    while identify_unconfigured(&mut *bus).is_empty() {
        assert!(
            Instant::now() < deadline,
            "the unconfigured device never answered"
        );
    }
    // Switch state global to configuration, node-ID 12, store configuration, back to waiting.
    let context = || sim.report();
    send(&mut *bus, "7E5#0401000000000000");
    send(&mut *bus, "7E5#110C000000000000");
    assert_eq!(expect_frame(&mut *bus, "7E4#", &context), "7E4#1100000000000000");
    send(&mut *bus, "7E5#1700000000000000");
    assert_eq!(expect_frame(&mut *bus, "7E4#", &context), "7E4#1700000000000000");
    send(&mut *bus, "7E5#0400000000000000");
    assert_eq!(expect_frame(&mut *bus, "70C#", &context), "70C#00");
    assert_eq!(sim.terminate().code(), Some(0), "{}", sim.report());
    let stored = std::fs::read_to_string(state.join("lss-00000ABC-00000401-00010002-00000200.lss"))
        .expect("the stored LSS configuration");
    assert!(stored.contains("node-id 12"), "{stored}");

    // Power-on again: the device starts with the stored node-ID, no LSS needed.
    let mut again = Background::sim(&hub, &dir, "second", &args);
    let context = || again.report();
    assert_eq!(expect_frame(&mut *bus, "70C#", &context), "70C#00");
    send(&mut *bus, "60C#4018100400000000");
    assert_eq!(expect_frame(&mut *bus, "58C#", &context), "58C#4318100400020000");
    assert_eq!(again.terminate().code(), Some(0), "{}", again.report());
}

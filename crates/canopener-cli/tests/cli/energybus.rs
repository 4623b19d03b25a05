//! `canopener sim --energybus` and `canopener mbt run --energybus` as users run them: the emulated
//! EnergyBus system boots on a virtual bus with its telegrams shown, one of its devices (or its
//! controller) is tested on the fly, and the paper's deviations fail with the documented exit code.

use crate::support::HubProc;
use crate::{run, stderr, stdout};

#[test]
fn sim_energybus_shows_the_boot_until_every_device_is_operating() {
    let output = run(&["sim", "--energybus", "2"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let text = stdout(&output);
    // The bus decoder's words, with the EMS meaning added.
    for line in [
        "  000  [2]  01 02                    NMT Start Remote Node -> node 2",
        "  602  [8]  2B 01 60 00 05 00 00 00  SDO rx node 2: download 6001h:00 = 0x0005 (2 bytes)  | EMS control word := 5 (Compatibility check -> Limiting)",
        "  582  [8]  4B 02 60 00 00 80 00 00  SDO tx node 2: upload 6002h:00 = 0x8000 (2 bytes)  | EMS status word = 8000h: Operating",
        "controller: node 3: EMS Operating",
    ] {
        assert!(text.contains(line), "missing {line:?} in:\n{text}");
    }
    assert!(text.contains("  node 2: vendor-id 0x00000000, product code 0x00000454, revision number 0x00010000, serial number 0x00000001 -> Operating at "), "{text}");
    assert!(
        text.contains("all 2 device(s) found by fastscan and walked to Operating at "),
        "{text}"
    );
    assert!(
        text.lines()
            .any(|l| l.contains("TPDO2 node 3") && l.contains("| TPDO2: EMS status word = 8000h: Operating")),
        "{text}"
    );

    let json = run(&["sim", "--energybus", "1", "--summary", "--format", "json"]);
    assert_eq!(json.status.code(), Some(0), "{}", stderr(&json));
    let last: serde_json::Value =
        serde_json::from_str(stdout(&json).lines().last().expect("a summary")).expect("JSON");
    assert_eq!(last["kind"], "summary");
    assert_eq!(last["operating"][0]["node"], 2);
    assert!(
        stdout(&json).lines().all(|l| !l.contains("\"telegram\"")),
        "--summary leaves the telegrams out"
    );
}

#[test]
fn sim_energybus_exits_7_when_a_device_never_reaches_operating_and_refuses_wrong_options() {
    let stuck = run(&[
        "sim",
        "--energybus",
        "1",
        "--fault",
        "lss-state-not-changed",
        "--for",
        "5s",
        "--summary",
    ]);
    assert_eq!(stuck.status.code(), Some(7), "{}", stderr(&stuck));
    assert!(
        stderr(&stuck).contains("not every device reached Operating"),
        "{}",
        stderr(&stuck)
    );
    let node = run(&[
        "sim",
        "--energybus",
        "2",
        "--fault",
        "no-boot-up",
        "--fault-node",
        "9",
    ]);
    assert_eq!(node.status.code(), Some(2));
    assert!(
        stderr(&node).contains("the devices get node-IDs 2 to 3"),
        "{}",
        stderr(&node)
    );
    let eb_only = run(&[
        "sim",
        "x.eds",
        "--node-id",
        "5",
        "--fault",
        "fastscan-wrong-answer",
    ]);
    assert_eq!(eb_only.status.code(), Some(2));
    assert!(
        stderr(&eb_only).contains("use it with --energybus N"),
        "{}",
        stderr(&eb_only)
    );
}

#[test]
fn mbt_run_tests_a_device_of_the_running_system_and_its_controller() {
    let device = run(&[
        "mbt",
        "run",
        "energybus-ems",
        "--energybus",
        "3",
        "--node",
        "3",
        "--purpose",
        "walk_to_operating",
        "--seed",
        "2",
    ]);
    assert_eq!(
        device.status.code(),
        Some(0),
        "{}{}",
        stdout(&device),
        stderr(&device)
    );
    assert!(
        stderr(&device).contains("the controller hands node 3 over to the tester"),
        "{}",
        stderr(&device)
    );
    assert!(
        stdout(&device).contains("purpose walk_to_operating: reached"),
        "{}",
        stdout(&device)
    );

    let controller = run(&[
        "mbt",
        "run",
        "energybus-controller",
        "--energybus",
        "0",
        "--node",
        "2",
        "--purpose",
        "integrate_device",
        "--steps",
        "3000",
        "--format",
        "json",
    ]);
    assert_eq!(controller.status.code(), Some(0), "{}", stderr(&controller));
    let value: serde_json::Value = serde_json::from_str(&stdout(&controller)).expect("JSON");
    assert_eq!(value["verdict"], "pass");
    assert_eq!(value["purpose"]["reached"], true);

    let wrong = run(&["mbt", "run", "energybus-ems", "--energybus", "2", "--node", "7"]);
    assert_eq!(wrong.status.code(), Some(2));
    assert!(stderr(&wrong).contains("node-IDs 2 to 3"), "{}", stderr(&wrong));
}

#[test]
fn the_papers_deviations_fail_mbt_runs_with_exit_6() {
    for (model, args, fault) in [
        (
            "sync",
            &["--energybus", "2", "--node", "2"][..],
            "sync-counter-missing",
        ),
        (
            "energybus-lss",
            &["--energybus", "1", "--no-controller", "--node", "0xFF"][..],
            "lss-state-not-changed",
        ),
        (
            "energybus-lss",
            &["--energybus", "1", "--no-controller", "--node", "0xFF"][..],
            "fastscan-wrong-answer",
        ),
    ] {
        let mut argv = vec!["mbt", "run", model];
        argv.extend_from_slice(args);
        argv.extend_from_slice(&["--fault", fault, "--steps", "1000"]);
        let output = run(&argv);
        assert_eq!(
            output.status.code(),
            Some(6),
            "{fault}: {}{}",
            stdout(&output),
            stderr(&output)
        );
        assert!(
            stdout(&output).contains(": FAIL after "),
            "{fault}: {}",
            stdout(&output)
        );
    }
}

/// With a bus the system runs in real time (on a hub here): the controller finds the device and
/// walks it to Operating, its events printed as they happen, and stops after --for.
#[test]
fn sim_energybus_runs_on_a_bus_in_real_time() {
    let hub = HubProc::start();
    let spec = hub.spec("can0");
    let output = run(&["sim", "--energybus", "1", "--bus", &spec, "--for", "6s"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let log = stderr(&output);
    assert!(log.contains(&format!("EnergyBus system on {spec}")), "{log}");
    assert!(log.contains("controller: node 2: found by fastscan"), "{log}");
    assert!(log.contains("controller: node 2: EMS Operating"), "{log}");
}

//! `canopener test --suite cia401 --stimulus CMD` against `canopener sim` on a hub: a device whose
//! 2000h is the vendor's own (no factory test registers), so the input tests need the hook. The
//! program is called with the documented arguments, a program that fails makes the tests
//! inconclusive with its stderr, and one that exits 0 without changing anything (it only writes
//! its arguments down) never makes a test pass.

use std::path::{Path, PathBuf};

use canopener_testkit::fixture::{self, ScratchDir};
use serde_json::Value;

use crate::harness::{Background, NO_BUS, client, expect_frame, run_exiting, run_on};
use crate::stderr;
use crate::support::{HubProc, workspace_root};

/// The full CiA 401 test device with a 2000h of its own (an UNSIGNED32 counter), which the thesis's
/// factory test config (BOOLEAN) is not: the tester finds no factory test registers.
fn eds_without_factory_registers(dir: &ScratchDir) -> PathBuf {
    let full = workspace_root().join("crates/canopener-conformance/test_data/cia401_full_io.eds");
    let text = fixture::read_to_string(&full).expect("cia401_full_io.eds");
    let text = text.replacen(
        "[ManufacturerObjects]\nSupportedObjects=8\n",
        "[ManufacturerObjects]\nSupportedObjects=9\n9=0x2000\n",
        1,
    );
    assert!(
        text.contains("9=0x2000"),
        "the fixture's ManufacturerObjects changed"
    );
    let text = format!(
        "{text}\n[2000]\nParameterName=Vendor counter\nObjectType=0x7\nDataType=0x0007\nAccessType=rw\nDefaultValue=0\nPDOMapping=0\n"
    );
    dir.write("io_vendor_2000.eds", text)
}

struct Bench {
    hub: HubProc,
    _sim: Background,
    eds: PathBuf,
}

impl Bench {
    fn start(dir: &ScratchDir) -> Bench {
        let hub = HubProc::start();
        let mut bus = client(&hub);
        let eds = eds_without_factory_registers(dir);
        let sim = Background::sim(&hub, dir, "sim", &[eds.to_str().unwrap(), "--node-id", "5"]);
        assert_eq!(expect_frame(&mut *bus, "705#", &|| sim.report()), "705#00");
        Bench { hub, _sim: sim, eds }
    }

    /// `canopener test --suite cia401 --only ID… ARGS`, exit 6; its JSON report's tests by id.
    fn test(&self, dir: &Path, only: &[&str], args: &[&str]) -> Vec<(String, String, String, String)> {
        let out = dir.join("report.json");
        let mut all = vec![
            "test",
            "--node",
            "5",
            "--eds",
            self.eds.to_str().unwrap(),
            "--suite",
            "cia401",
            "--format",
            "json",
            "-o",
            out.to_str().unwrap(),
        ];
        for id in only {
            all.extend(["--only", id]);
        }
        all.extend(args);
        run_exiting(&self.hub.spec("can0"), &all, 6);
        let report: Value =
            serde_json::from_str(&fixture::read_to_string(&out).expect("report")).expect("JSON report");
        report["tests"]
            .as_array()
            .expect("tests")
            .iter()
            .map(|t| {
                let field = |name: &str| t[name].as_str().unwrap_or_default().to_owned();
                (field("id"), field("verdict"), field("reason"), field("analysis"))
            })
            .collect()
    }
}

#[test]
fn the_stimulus_program_gets_object_sub_and_value_and_its_failure_is_inconclusive() {
    let dir = ScratchDir::new("test-stimulus");
    let bench = Bench::start(&dir);
    let calls = dir.join("calls.log");
    let recorder = dir.write("record.sh", format!("echo \"$@\" >> '{}'\n", calls.display()));
    let recorder = format!("sh '{}'", recorder.display());
    let tests = bench.test(
        &dir,
        &["cia401.io.2"],
        &["--stimulus", &recorder, "--stimulus-settle", "5ms"],
    );
    let called = fixture::read_to_string(&calls).expect("the stimulus was called");
    let lines: Vec<_> = called.lines().collect();
    assert_eq!(lines.first(), Some(&"6000 1 0x5A"), "{called}");
    // Nothing changed the input, so 6000h:01 did not follow: a failure that names the hook.
    let (id, verdict, reason, analysis) = &tests[0];
    assert_eq!(
        (id.as_str(), verdict.as_str()),
        ("cia401.io.2", "fail"),
        "{reason}"
    );
    assert!(
        analysis.contains("stimulus hook applied 6000h:01 = 0x5A"),
        "{analysis}"
    );
    // The test put the input back to 00h when it ended.
    assert_eq!(lines.last(), Some(&"6000 1 0x00"), "{called}");

    let failing = dir.write("fail.sh", "echo 'bench not powered' >&2\nexit 5\n");
    let failing = format!("sh '{}'", failing.display());
    let tests = bench.test(
        &dir,
        &["cia401.io.2", "cia401.io.4", "cia401.io.8"],
        &["--stimulus", &failing],
    );
    assert_eq!(tests.len(), 3);
    for (id, verdict, reason, _) in &tests {
        assert_eq!(verdict, "inconclusive", "{id}: {reason}");
        assert!(
            reason.contains("exited with 5: bench not powered"),
            "{id}: {reason}"
        );
    }
    // Without a hook, the same tests say how to give one.
    for (id, verdict, reason, _) in &bench.test(&dir, &["cia401.io.2"], &[]) {
        assert_eq!(verdict, "inconclusive", "{id}: {reason}");
        assert!(reason.contains("--stimulus"), "{id}: {reason}");
    }
}

#[test]
fn stimulus_arguments_are_checked_before_the_bus_is_opened() {
    let eds = workspace_root().join("crates/canopener-conformance/test_data/cia401_full_io.eds");
    let eds = eds.to_str().unwrap();
    let base = ["test", "--node", "5", "--eds", eds, "--suite", "cia401"];
    for (extra, needle) in [
        (&["--stimulus-settle", "20ms"][..], "--stimulus"),
        (&["--stimulus", " "][..], "--stimulus"),
        (
            &["--stimulus", "true", "--stimulus-settle", "20"][..],
            "--stimulus-settle",
        ),
    ] {
        let mut args = base.to_vec();
        args.extend(extra);
        let output = run_exiting(NO_BUS, &args, 2);
        assert!(stderr(&output).contains(needle), "{extra:?}: {}", stderr(&output));
    }
    // Good ones get to the bus (exit 4: nobody listens there).
    let mut args = base.to_vec();
    args.extend(["--stimulus", "true", "--stimulus-settle", "20ms"]);
    let output = run_on(NO_BUS, &args);
    assert_eq!(output.status.code(), Some(4), "{}", stderr(&output));
}

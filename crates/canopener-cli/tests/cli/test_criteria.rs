//! `canopener test --criteria FILE --repetitions N`: the cia313 options are checked before the bus
//! is opened; a bad criteria file is exit 3 naming file:line:column.

use canopener_testkit::fixture::ScratchDir;

use crate::harness::{NO_BUS, base_eds, run_exiting};
use crate::stderr;

fn test_args<'a>(eds: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec!["test", "--node", "5", "--eds", eds, "--suite", "cia313"];
    args.extend(extra);
    args
}

#[test]
fn a_bad_criteria_file_is_exit_3_with_file_line_and_column() {
    let dir = ScratchDir::new("criteria");
    let eds = base_eds();
    let eds = eds.to_str().unwrap();
    for (text, needle) in [
        ("[sdo]\nread_max = 1\n", "bad.toml:2:1: unknown field `read_max`"),
        (
            "[heartbeat]\ndeviation_percent = 0\n",
            "bad.toml:2:21: heartbeat.deviation_percent = 0",
        ),
        ("[lss]\nresponse_max_ms = \"fast\"\n", "bad.toml:2:19:"),
    ] {
        let file = dir.write("bad.toml", text);
        let output = run_exiting(
            NO_BUS,
            &test_args(eds, &["--criteria", file.to_str().unwrap()]),
            3,
        );
        let message = stderr(&output);
        assert!(message.contains(needle), "{text:?}: {message}");
        assert!(message.contains("docs/conformance.md"), "{message}");
    }
    let missing = dir.path().join("missing.toml");
    let output = run_exiting(
        NO_BUS,
        &test_args(eds, &["--criteria", missing.to_str().unwrap()]),
        3,
    );
    assert!(stderr(&output).contains("missing.toml"), "{}", stderr(&output));
}

#[test]
fn good_criteria_and_repetitions_get_to_the_bus() {
    let dir = ScratchDir::new("criteria-good");
    let file = dir.write(
        "limits.toml",
        "[sdo]\nread_max_ms = 2.5\n[heartbeat]\ndeviation_percent = 5\n",
    );
    let eds = base_eds();
    let eds = eds.to_str().unwrap();
    for repetitions in ["1", "0x10", "1000000"] {
        let args = test_args(
            eds,
            &["--criteria", file.to_str().unwrap(), "--repetitions", repetitions],
        );
        // Exit 4: the arguments are fine, the bus is not there.
        run_exiting(NO_BUS, &args, 4);
    }
    for repetitions in ["0", "1000001", "ten"] {
        let output = run_exiting(NO_BUS, &test_args(eds, &["--repetitions", repetitions]), 2);
        let message = stderr(&output);
        assert!(message.contains("--repetitions"), "{repetitions}: {message}");
    }
}

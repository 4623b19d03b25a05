//! One CLI grammar (issue 13, items 12 and 13): the same notation for the same thing in every command.
//! Every case runs against a bus nobody listens on, so an accepted command line ends in a bus error (4)
//! and a refused one in a usage error (2) before any bus is opened.

use crate::harness::{NO_BUS, base_eds, run_on};
use crate::{run, stderr, stdout, temp_dir};

/// `line` split at spaces (no argument here contains one).
fn words(line: &str) -> Vec<&str> {
    line.split_whitespace().collect()
}

/// Exit status 4: the arguments were accepted and the command went on to open the (dead) bus.
fn accepted(line: &str) {
    let output = run_on(NO_BUS, &words(line));
    assert_eq!(
        output.status.code(),
        Some(4),
        "canopener {line} should get past its arguments to the bus; stderr:\n{}",
        stderr(&output)
    );
}

/// Exit status 2 with `needle` in the message.
fn refused(line: &str, needle: &str) {
    let output = run_on(NO_BUS, &words(line));
    let text = stderr(&output);
    assert_eq!(output.status.code(), Some(2), "canopener {line}: {text}");
    assert!(
        text.contains(needle),
        "canopener {line} should say {needle:?}:\n{text}"
    );
}

/// Item 13: `sync` and `heartbeat watch` wait for no answer; a `--timeout` they accepted and ignored is now
/// refused, so a script learns it had no effect.
#[test]
fn sync_and_heartbeat_watch_take_no_timeout() {
    refused("sync --period 10ms --timeout 1s", "--timeout");
    refused("heartbeat watch --timeout 1s", "--timeout");
    accepted("sync --period 10ms --count 1");
    // The commands that wait for answers keep it.
    accepted("sdo read --node 5 1018 1 --timeout 50ms");
}

/// Item 12: a duration without a unit is an error with an example, everywhere (it was seconds to `sync
/// --period` and milliseconds to `pdo map --event-timer`).
#[test]
fn a_bare_number_is_not_a_duration() {
    refused("sync --period 10", "write e.g. 10ms or 10s");
    refused("sdo read --node 5 1018 1 --timeout 2", "has no unit");
    refused("heartbeat watch --consumer-time 300", "300ms or 300s");
    refused("bus dump --duration 5", "has no unit");
    let output = run(&words("bus serve --listen 127.0.0.1:0 --stats-every 5"));
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert!(stderr(&output).contains("5ms or 5s"), "{}", stderr(&output));
}

/// Item 12: every integer takes decimal and `0x`; `--node 0x05` was refused while `nmt start 0x05` worked.
#[test]
fn integers_and_node_ids_take_decimal_and_0x_in_every_command() {
    accepted("sdo read --node 0x05 1018 1");
    accepted("node info --node 0x05");
    accepted("nmt start 0x05");
    accepted("pdo map --node 0x05 --tpdo 0x1 6000:01:8 --transmission-type 0xFF");
    accepted("sync --period 10ms --count 0x10 --counter 0x10");
    accepted("lss configure --vendor 1 --product 2 --revision 3 --serial 4 --node-id 0x05");
    refused("sdo read --node 0x80 1018 1", "1..127");
    // Issue 25 item 3: one number grammar; `h` hex and `d:` decimal indices work in every command.
    accepted("sdo read --node 05h d:4120 1");
    accepted("lss inquire --vendor 2F7h --product 1 --revision 0x10 --serial 0b101");
    accepted("sync --period 10ms --count 10h");
    refused("sync --period 10ms --counter 0x01", "--counter must be 2..240");
}

/// Item 12: one name per thing. `--node` names the device in every command (nmt too), `--nodes` a set
/// (node scan's `--range` stays as a hidden alias for scripts), `pdo map --transmission-type` (its
/// `--type` clashed with `sdo --type`, a data type; the old spelling stays hidden).
#[test]
fn one_name_per_thing() {
    accepted("nmt start --node 5");
    accepted("nmt reset --node all");
    refused("nmt start 5 --node 6", "cannot be used with");
    accepted("node scan --nodes 1-3");
    accepted("node scan --range 1-3");
    accepted("pdo map --node 5 --tpdo 1 6000:01:8 --type 255");
    let scan_help = stdout(&run(&words("node scan --help")));
    assert!(
        scan_help.contains("--nodes") && !scan_help.contains("--range"),
        "{scan_help}"
    );
    let map_help = stdout(&run(&words("pdo map --help")));
    assert!(map_help.contains("--transmission-type"), "{map_help}");
    assert!(
        !map_help.contains("--type <"),
        "the old spelling must stay hidden:\n{map_help}"
    );
}

/// Item 12: `pdo map` timings are durations in the unit the object stores them in: the event timer in
/// whole milliseconds (1800h sub 5), the inhibit time in 100 µs (sub 3).
#[test]
fn pdo_map_timings_are_durations() {
    let map = "pdo map --node 5 --tpdo 1 6000:01:8";
    accepted(&format!("{map} --event-timer 1s --inhibit 500us"));
    for (extra, needle) in [
        ("--event-timer 100", "100ms or 100s"),
        ("--event-timer 1500us", "whole milliseconds"),
        ("--event-timer 66s", "65535ms"),
        ("--inhibit 150us", "multiples of 100us"),
        ("--inhibit 10", "has no unit"),
    ] {
        refused(&format!("{map} {extra}"), needle);
    }
}

/// Item 12: `eds convert --bitrate` is checked like every other `--bitrate` (it took any number).
#[test]
fn eds_convert_checks_its_bitrate() {
    let dir = temp_dir("grammar-convert");
    let out = dir.join("node5.dcf");
    let convert = |bitrate: &str| {
        let (eds, out) = (base_eds().display().to_string(), out.display().to_string());
        let line = format!("eds convert {eds} --to dcf --node-id 0x05 --bitrate {bitrate} -o {out}");
        run(&words(&line))
    };
    let output = convert("100");
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert!(stderr(&output).contains("--bitrate 250"), "{}", stderr(&output));
    assert!(!out.exists(), "a refused conversion wrote {}", out.display());
    let output = convert("250");
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    assert!(out.exists());
    let _ = std::fs::remove_dir_all(&dir);
}

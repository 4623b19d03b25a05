//! `canopener demo`, the product tour: exit codes, the files it writes, a clean run without failures and
//! a faulty run with them, the narrative, a second run replacing the first run's files and saying so,
//! and the grammar that keeps `--monitor`'s options with `--monitor`.

use std::path::Path;

use serde_json::Value;

use super::{run, stderr, stdout, temp_dir};

fn json_of(path: &Path) -> Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn the_tour_writes_a_clean_and_a_failing_report() {
    let dir = temp_dir("demo-tour");
    let out = dir.join("reports");
    let output = run(&["demo", "--dir", out.to_str().unwrap(), "--format", "json"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let summary: Value = serde_json::from_str(&stdout(&output)).expect("one JSON summary");
    assert_eq!(summary["eds"]["errors"], 0, "{summary}");
    assert_eq!(summary["replaced"].as_array().map(Vec::len), Some(0));
    let runs = summary["runs"].as_array().expect("runs");
    assert_eq!(runs.len(), 2);
    let (clean, faulty) = (&runs[0], &runs[1]);
    assert_eq!(clean["fault"], Value::Null);
    assert_eq!(clean["summary"]["fail"], 0, "{clean}");
    assert_eq!(clean["summary"]["inconclusive"], 0, "{clean}");
    assert!(clean["summary"]["pass"].as_u64() > Some(50), "{clean}");
    assert_eq!(faulty["fault"], "heartbeat-jitter");
    assert!(faulty["summary"]["fail"].as_u64() > Some(0), "{faulty}");
    assert!(
        faulty["failed"]
            .as_array()
            .unwrap()
            .contains(&Value::from("cia301.ec.1")),
        "{faulty}"
    );
    for run in runs {
        let report = json_of(Path::new(run["json"].as_str().unwrap()));
        assert_eq!(report["summary"], run["summary"]);
        let tests = report["tests"].as_array().unwrap().len();
        assert_eq!(run["tests"], tests);
        let html = std::fs::read_to_string(run["html"].as_str().unwrap()).expect("HTML report");
        assert!(html.starts_with("<!DOCTYPE html>"));
        assert_eq!(html.matches("<details class=\"test\"").count(), tests);
        assert!(
            !html.contains("http://") || !html.contains("src=\"http"),
            "no external assets"
        );
    }
    assert!(
        out.join("cia401_full_io.eds").is_file(),
        "the bundled EDS is written for the user"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_narrative_names_the_failure_and_a_second_tour_says_what_it_replaced() {
    let dir = temp_dir("demo-narrative");
    let out = dir.to_str().unwrap();
    let first = run(&["demo", "--dir", out]);
    assert_eq!(first.status.code(), Some(0), "{}", stderr(&first));
    let text = stdout(&first);
    for needle in [
        "1. EDS check",
        "0 errors",
        "0 failed, 0 inconclusive",
        "heartbeat-jitter",
        "FAIL cia301.ec.1",
        "fault-heartbeat-jitter.html",
        "clean.html",
    ] {
        assert!(text.contains(needle), "{needle:?} missing:\n{text}");
    }
    assert!(!text.contains("Replaced"), "{text}");
    let again = run(&["demo", "--dir", out, "--fault", "no-lss"]);
    assert_eq!(again.status.code(), Some(0), "{}", stderr(&again));
    let text = stdout(&again);
    assert!(text.contains("Replaced the files of an earlier run"), "{text}");
    assert!(text.contains("FAIL cia305.lss"), "{text}");
    assert!(dir.join("fault-no-lss.html").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn monitor_options_need_monitor_and_bad_faults_and_directories_are_refused() {
    let output = run(&["demo", "--speed", "0"]);
    assert_eq!(output.status.code(), Some(2));
    assert!(stderr(&output).contains("--monitor"), "{}", stderr(&output));

    let output = run(&["demo", "--fault", "no-such-fault"]);
    assert_eq!(output.status.code(), Some(2));
    assert!(
        stderr(&output).contains("heartbeat-jitter"),
        "lists the names: {}",
        stderr(&output)
    );

    let dir = temp_dir("demo-not-a-dir");
    let file = dir.join("file");
    std::fs::write(&file, "mine").unwrap();
    let output = run(&["demo", "--dir", file.to_str().unwrap()]);
    assert_eq!(output.status.code(), Some(5), "{}", stderr(&output));
    assert_eq!(
        std::fs::read_to_string(&file).unwrap(),
        "mine",
        "the user's file is untouched"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

//! `canopener test --format html`: the EDS check alone needs no bus, so the HTML report of a run is
//! checked here without a device; the report of a run against a simulated device is checked in headless
//! Chromium by `canopener-conformance`'s `html_report` test.

use super::{run, stderr, temp_dir};

#[test]
fn the_eds_suite_writes_a_self_contained_html_report() {
    let dir = temp_dir("test-html");
    let eds = canopener_testkit::corpus::eds("CANopenNode__CANopenDemo__demo__demoDevice.eds");
    let out = dir.join("report.html");
    let output = run(&[
        "test",
        "--suite",
        "eds",
        "--node",
        "0x05",
        "--eds",
        eds.to_str().unwrap(),
        "--format",
        "html",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let html = std::fs::read_to_string(&out).expect("report written");
    assert!(html.starts_with("<!DOCTYPE html>"));
    assert_eq!(html.matches("<details class=\"test\"").count(), 1);
    assert!(html.contains("id=\"test-cia301.eds.1\""));
    assert!(html.contains("<style>") && !html.contains("<link") && !html.contains("<script src"));
    let _ = std::fs::remove_dir_all(&dir);
}

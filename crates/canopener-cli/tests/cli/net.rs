//! `canopener net check|show|convert|draw|monitor` as users run them: the exit codes and JSON of
//! `eds check`, findings at file:line:column, conversions, drawings, and argument errors.

use std::path::{Path, PathBuf};

use serde_json::Value;

use super::{run, stderr, stdout, temp_dir};

fn test_data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../canopener-network/test_data")
        .join(name)
}

fn arg(path: &Path) -> &str {
    path.to_str().expect("test paths are UTF-8")
}

fn check_json(files: &[&Path]) -> (Option<i32>, Value) {
    let mut args = vec!["net", "check", "--format", "json"];
    args.extend(files.iter().map(|p| arg(p)));
    let output = run(&args);
    let json = serde_json::from_str(&stdout(&output)).unwrap_or_else(|e| panic!("{e}: {}", stdout(&output)));
    (output.status.code(), json)
}

fn codes(file: &Value) -> Vec<String> {
    file["findings"]
        .as_array()
        .expect("findings")
        .iter()
        .map(|f| f["code"].as_str().expect("code").to_owned())
        .collect()
}

#[test]
fn clean_systems_exit_0_and_the_papers_example_only_warns() {
    // trunk-num-of-nets-default.graphml gives NumOfNets only by its <key>'s <default> (issue 22: every
    // junction got N032).
    let (code, json) = check_json(&[
        &test_data("gateway.graphml"),
        &test_data("paper/Nodelist.graphml"),
        &test_data("trunk-num-of-nets-default.graphml"),
    ]);
    assert_eq!(code, Some(0), "{json:#}");
    assert_eq!(json["version"], 1);
    assert!(codes(&json["files"][0]).is_empty(), "{json:#}");
    assert!(codes(&json["files"][2]).is_empty(), "{json:#}");
    let paper = codes(&json["files"][1]);
    assert_eq!(paper.iter().filter(|c| *c == "N011").count(), 1, "{paper:?}");
    assert_eq!(paper.iter().filter(|c| *c == "N012").count(), 8, "{paper:?}");
    let first = &json["files"][1]["findings"][0];
    assert_eq!(
        (first["line"].as_u64(), first["column"].as_u64()),
        (Some(36), Some(5)),
        "{first}"
    );
    assert_eq!(json["summary"]["errors"], 0);
}

#[test]
fn malformed_xml_missing_dcfs_rings_and_cpj_nodes_without_dcf_are_errors_exit_1() {
    let dir = temp_dir("net-check-bad");
    let broken = dir.join("broken.graphml");
    std::fs::write(&broken, "<graphml>\n  <graph>\n    <node id=\"a\">\n  </graph>\n").expect("write");
    let ring = dir.join("ring.graphml");
    let line = std::fs::read_to_string(test_data("line.graphml")).expect("fixture");
    let ring_text = line.replace(
        "  </graph>",
        "    <edge source=\"d6\" target=\"m\"><data key=\"NetNumber\">1</data></edge>\n  </graph>",
    );
    std::fs::write(&ring, ring_text).expect("write");
    let cpj = dir.join("nodelist.cpj");
    std::fs::write(
        &cpj,
        "[Topology]\nNodes=0x01\nNode5Present=0x01\nNode5Name=Drive\n",
    )
    .expect("write");
    let (code, json) = check_json(&[&broken, &ring, &cpj]);
    assert_eq!(code, Some(1), "{json:#}");
    let malformed = &json["files"][0]["findings"][0];
    assert_eq!(malformed["code"], "N001", "{malformed}");
    assert_eq!(malformed["line"], 4, "{malformed}");
    let ring_codes = codes(&json["files"][1]);
    assert!(ring_codes.contains(&"N036".to_owned()), "{ring_codes:?}");
    // The ring's DCFs are looked up under its own folder's dcf/: missing there.
    assert!(ring_codes.contains(&"N040".to_owned()), "{ring_codes:?}");
    assert_eq!(codes(&json["files"][2]), ["N044"]);
}

#[test]
fn dcf_problems_are_findings_on_the_topology_line_that_names_the_dcf() {
    let dir = temp_dir("net-check-dcf");
    let good = std::fs::read(test_data("dcf/node2.dcf")).expect("fixture");
    std::fs::write(dir.join("node2.dcf"), &good).expect("write");
    // Node 3's DCF says node 2; node 4's says node 2 too and has a line the EDS reader cannot read.
    std::fs::write(dir.join("node3.dcf"), &good).expect("write");
    let mut broken = good.clone();
    broken.extend_from_slice(b"\n[1018]\nthis line is no key=value pair\n");
    std::fs::write(dir.join("node4.dcf"), broken).expect("write");
    let cpj = dir.join("nodelist.cpj");
    std::fs::write(
        &cpj,
        "[Topology]\nNodes=0x03\nNode2Present=0x01\nNode2DCFName=node2.dcf\nNode3Present=0x01\n\
         Node3DCFName=node3.dcf\nNode4Present=0x01\nNode4DCFName=node4.dcf\n",
    )
    .expect("write");
    let (code, json) = check_json(&[&cpj]);
    assert_eq!(code, Some(1), "{json:#}");
    let findings: Vec<(String, u64)> = json["files"][0]["findings"]
        .as_array()
        .expect("findings")
        .iter()
        .map(|f| {
            (
                f["code"].as_str().unwrap_or("").to_owned(),
                f["line"].as_u64().unwrap_or(0),
            )
        })
        .collect();
    // Each on the line where the node's entries start (its Node<X>Present).
    let expected = [("N041", 5), ("N041", 7), ("N043", 7)].map(|(c, l)| (c.to_owned(), l));
    assert_eq!(findings, expected);
}

#[test]
fn a_file_that_cannot_be_read_exits_2_and_is_named() {
    let (code, json) = check_json(&[Path::new("/nonexistent/Nodelist.graphml")]);
    assert_eq!(code, Some(2));
    assert!(
        json["files"][0]["problem"]
            .as_str()
            .expect("problem")
            .contains("/nonexistent/Nodelist.graphml")
    );
    let show = run(&["net", "show", "/nonexistent/nodelist.cpj"]);
    assert_eq!(show.status.code(), Some(2));
    assert!(
        stderr(&show).contains("/nonexistent/nodelist.cpj"),
        "{}",
        stderr(&show)
    );
}

#[test]
fn show_lists_networks_devices_and_cables_as_json() {
    let output = run(&[
        "net",
        "show",
        arg(&test_data("gateway.graphml")),
        "--format",
        "json",
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let json: Value = serde_json::from_str(&stdout(&output)).expect("json");
    let networks = json["networks"].as_array().expect("networks");
    assert_eq!(networks.len(), 2);
    assert_eq!(networks[1]["number"], 2);
    assert_eq!(networks[1]["name"], "Boom");
    let names: Vec<&str> = networks[1]["devices"]
        .as_array()
        .expect("devices")
        .iter()
        .map(|d| d["name"].as_str().expect("name"))
        .collect();
    assert_eq!(names, ["Gateway", "Boom1", "Boom2", "Boom3"]);
    assert_eq!(networks[1]["cables"][0]["name"], "B1");
}

#[test]
fn convert_round_trips_through_cpj_and_names_what_it_drops() {
    let dir = temp_dir("net-convert");
    let cpj = dir.join("nodelist.cpj");
    let output = run(&[
        "net",
        "convert",
        arg(&test_data("trunk.graphml")),
        "--to",
        "cpj",
        "-o",
        arg(&cpj),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("cannot hold 11 cable(s)"),
        "{}",
        stderr(&output)
    );
    let graphml = dir.join("Nodelist.graphml");
    let output = run(&[
        "net",
        "convert",
        arg(&cpj),
        "--to",
        "graphml",
        "-o",
        arg(&graphml),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(stderr(&output).is_empty(), "{}", stderr(&output));
    let again = run(&["net", "convert", arg(&graphml), "--to", "cpj"]);
    assert_eq!(stdout(&again), std::fs::read_to_string(&cpj).expect("cpj"));
    let refused = run(&["net", "convert", arg(&cpj), "--to", "graphml", "-o", arg(&cpj)]);
    assert_eq!(refused.status.code(), Some(2));
    let dot = run(&["net", "convert", arg(&test_data("hub.graphml")), "--to", "dot"]);
    assert!(stdout(&dot).starts_with("graph canopen {"), "{}", stdout(&dot));
}

#[test]
fn draw_writes_an_svg_naming_every_device() {
    let output = run(&["net", "draw", arg(&test_data("gateway.graphml"))]);
    assert!(output.status.success(), "{}", stderr(&output));
    let svg = stdout(&output);
    assert!(svg.starts_with("<svg"), "{svg}");
    for name in ["PLC", "Engine", "Gateway", "Boom1", "Boom2", "Boom3", "A1 4 m"] {
        assert!(svg.contains(name), "{name}");
    }
}

#[test]
fn monitor_arguments_are_checked_before_any_bus_is_opened() {
    let file = test_data("gateway.graphml");
    let unknown_net = run(&[
        "net",
        "monitor",
        arg(&file),
        "--bus",
        "9=socketcand://127.0.0.1:9/can0",
    ]);
    assert_eq!(unknown_net.status.code(), Some(2));
    assert!(
        stderr(&unknown_net).contains("no network 9"),
        "{}",
        stderr(&unknown_net)
    );
    let unknown_at = run(&[
        "net",
        "monitor",
        arg(&file),
        "--bus",
        "socketcand://127.0.0.1:9/can0",
        "--at",
        "Nobody",
    ]);
    assert_eq!(unknown_at.status.code(), Some(2));
    assert!(
        stderr(&unknown_at).contains("--at Nobody"),
        "{}",
        stderr(&unknown_at)
    );
    let twice = run(&[
        "net",
        "monitor",
        arg(&file),
        "--bus",
        "socketcand://127.0.0.1:9/can0",
        "--bus",
        "1=socketcand://127.0.0.1:9/can1",
    ]);
    assert_eq!(twice.status.code(), Some(2), "{}", stderr(&twice));
    let refused = run(&[
        "net",
        "monitor",
        arg(&file),
        "--bus",
        "socketcand://127.0.0.1:9/can0",
        "--duration",
        "1s",
    ]);
    assert_eq!(refused.status.code(), Some(4), "{}", stderr(&refused));
}

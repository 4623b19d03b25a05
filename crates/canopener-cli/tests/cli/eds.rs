//! `canopener eds show|convert|fmt|diff` as users run them: outputs, files written, exit codes 0/1/2.

use std::path::{Path, PathBuf};

use super::{run, stderr, stdout, temp_dir};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../canopener-eds/test_data/quirks")
        .join(name)
}

fn arg(path: &Path) -> &str {
    path.to_str().expect("test paths are UTF-8")
}

#[test]
fn show_prints_the_object_dictionary() {
    let baseline = fixture("baseline.eds");
    let output = run(&["eds", "show", arg(&baseline), "--node-id", "5"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    insta::assert_snapshot!("eds_show_baseline", stdout(&output));
    for spelling in ["1018", "0x1018", "1018h"] {
        let one = run(&["eds", "show", arg(&baseline), "--object", spelling]);
        assert_eq!(one.status.code(), Some(0));
        let text = stdout(&one);
        assert!(text.contains("Identity") && !text.contains("1017h"), "{text}");
    }
    let missing = run(&["eds", "show", arg(&baseline), "--object", "5FFF"]);
    assert_eq!(missing.status.code(), Some(2));
    assert!(
        stderr(&missing).contains("has no object 5FFFh"),
        "{}",
        stderr(&missing)
    );
}

#[test]
fn show_json_is_one_document_with_every_row() {
    let output = run(&["eds", "show", arg(&fixture("baseline.eds")), "--format", "json"]);
    assert_eq!(output.status.code(), Some(0));
    let doc: serde_json::Value = serde_json::from_slice(&output.stdout).expect("valid JSON");
    let rows = doc["objects"].as_array().expect("objects array");
    assert!(
        rows.iter()
            .any(|r| r["index"] == "1018" && r["sub"] == "01" && r["data_type"] == "UNSIGNED32")
    );
    assert!(
        rows.iter()
            .any(|r| r["index"] == "2000" && r["sub"] == "03" && r["origin"] == "CompactSubObj")
    );
    assert_eq!(doc["diagnostics"].as_array().map(Vec::len), Some(0));
}

#[test]
fn show_reports_loading_diagnostics_with_file_line_column() {
    let output = run(&["eds", "show", arg(&fixture("duplicate-key.eds")), "--diagnostics"]);
    assert_eq!(output.status.code(), Some(0), "a file with errors still shows");
    let err = stderr(&output);
    assert!(err.contains("duplicate-key.eds:87:1: error[P021]"), "{err}");
    assert!(err.contains("help: delete one of the two lines"), "{err}");
}

#[test]
fn convert_round_trips_through_json_dcf_and_back() {
    let dir = temp_dir("eds-convert");
    let baseline = fixture("baseline.eds");
    let json = dir.join("baseline.json");
    let back = dir.join("back.eds");
    let dcf = dir.join("node5.dcf");
    let dcf_eds = dir.join("from-dcf.eds");
    assert_eq!(
        run(&["eds", "convert", arg(&baseline), "--to", "json", "-o", arg(&json)])
            .status
            .code(),
        Some(0)
    );
    let doc: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(
        (doc["format"].as_str(), doc["version"].as_u64()),
        (Some("canopener-eds"), Some(1))
    );
    assert_eq!(
        run(&["eds", "convert", arg(&json), "--to", "eds", "-o", arg(&back)])
            .status
            .code(),
        Some(0)
    );
    assert_eq!(
        run(&["eds", "diff", arg(&baseline), arg(&back)]).status.code(),
        Some(0)
    );

    let no_node = run(&["eds", "convert", arg(&baseline), "--to", "dcf"]);
    assert_eq!(no_node.status.code(), Some(2));
    assert!(
        stderr(&no_node).contains("--node-id is required"),
        "{}",
        stderr(&no_node)
    );
    let made = run(&[
        "eds",
        "convert",
        arg(&baseline),
        "--to",
        "dcf",
        "--node-id",
        "5",
        "--bitrate",
        "500",
        "-o",
        arg(&dcf),
    ]);
    assert_eq!(made.status.code(), Some(0), "{}", stderr(&made));
    let text = std::fs::read_to_string(&dcf).unwrap();
    assert!(
        text.contains("[DeviceComissioning]\r\nNodeID=5\r\nBaudrate=500"),
        "{text}"
    );
    assert!(
        text.contains("ParameterValue=0x185"),
        "$NODEID resolved in the DCF:\n{text}"
    );
    assert_eq!(
        run(&["eds", "convert", arg(&dcf), "--to", "eds", "-o", arg(&dcf_eds)])
            .status
            .code(),
        Some(0)
    );
    assert_eq!(
        run(&["eds", "diff", arg(&baseline), arg(&dcf_eds)]).status.code(),
        Some(0)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn convert_refuses_to_overwrite_its_input_and_bad_arguments() {
    let dir = temp_dir("eds-convert-refuse");
    let copy = dir.join("device.eds");
    std::fs::copy(fixture("baseline.eds"), &copy).unwrap();
    let before = std::fs::read(&copy).unwrap();
    let same = run(&["eds", "convert", arg(&copy), "--to", "eds", "-o", arg(&copy)]);
    assert_eq!(same.status.code(), Some(2));
    assert!(
        stderr(&same).contains("refusing to overwrite the input"),
        "{}",
        stderr(&same)
    );
    assert_eq!(std::fs::read(&copy).unwrap(), before);
    let stray = run(&["eds", "convert", arg(&copy), "--to", "json", "--node-id", "3"]);
    assert_eq!(stray.status.code(), Some(2));
    let missing = run(&["eds", "show", arg(&dir.join("nope.eds"))]);
    assert_eq!(missing.status.code(), Some(2));
    assert!(stderr(&missing).contains("cannot read"), "{}", stderr(&missing));
    let bad_json = dir.join("bad.json");
    std::fs::write(&bad_json, "{\"format\": \"something-else\", \"version\": 1}").unwrap();
    let refused = run(&["eds", "show", arg(&bad_json)]);
    assert_eq!(refused.status.code(), Some(2));
    assert!(
        stderr(&refused).contains("not a canopener EDS document"),
        "{}",
        stderr(&refused)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn fmt_checks_writes_and_keeps_a_backup_in_place() {
    let dir = temp_dir("eds-fmt");
    let messy = dir.join("messy.eds");
    std::fs::copy(fixture("duplicate-key.eds"), &messy).unwrap();
    let original = std::fs::read(&messy).unwrap();
    let check = run(&["eds", "fmt", arg(&messy), "--check"]);
    assert_eq!(check.status.code(), Some(1));
    assert!(
        stderr(&check).contains("is not in canonical form"),
        "{}",
        stderr(&check)
    );
    let clean = dir.join("clean.eds");
    assert_eq!(
        run(&["eds", "fmt", arg(&messy), "-o", arg(&clean)]).status.code(),
        Some(0)
    );
    assert_eq!(
        run(&["eds", "fmt", arg(&clean), "--check"]).status.code(),
        Some(0),
        "fmt output is canonical"
    );
    assert_eq!(
        run(&["eds", "diff", arg(&messy), arg(&clean)]).status.code(),
        Some(0),
        "fmt keeps the model"
    );
    let in_place = run(&["eds", "fmt", arg(&messy), "--in-place"]);
    assert_eq!(in_place.status.code(), Some(0));
    assert_eq!(std::fs::read(dir.join("messy.eds.bak")).unwrap(), original);
    assert_eq!(std::fs::read(&messy).unwrap(), std::fs::read(&clean).unwrap());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn diff_exits_1_and_names_what_changed() {
    let dir = temp_dir("eds-diff");
    let baseline = fixture("baseline.eds");
    let changed = dir.join("changed.eds");
    let text = std::fs::read_to_string(&baseline).unwrap();
    assert_eq!(
        text.matches("DefaultValue=1000").count(),
        1,
        "fixture has one 1000 ms heartbeat"
    );
    std::fs::write(&changed, text.replace("DefaultValue=1000", "DefaultValue=0x1F4")).unwrap();
    let output = run(&["eds", "diff", arg(&baseline), arg(&changed)]);
    assert_eq!(output.status.code(), Some(1));
    let out = stdout(&output);
    assert!(out.contains("~ [1017] DefaultValue: 1000 -> 0x1F4"), "{out}");
    assert!(out.contains("0 added, 0 removed, 1 changed"), "{out}");
    let json = run(&["eds", "diff", arg(&baseline), arg(&changed), "--format", "json"]);
    assert_eq!(json.status.code(), Some(1));
    let doc: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
    assert_eq!(doc["equivalent"], false);
    assert_eq!(doc["changes"][0]["section"], "1017");
    assert_eq!(
        run(&["eds", "diff", arg(&baseline), arg(&baseline)])
            .status
            .code(),
        Some(0)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn binary_garbage_loads_without_panicking() {
    let dir = temp_dir("eds-garbage");
    let garbage = dir.join("garbage.eds");
    let bytes: Vec<u8> = (0..4096u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .collect();
    std::fs::write(&garbage, bytes).unwrap();
    for args in [
        vec!["eds", "show"],
        vec!["eds", "fmt"],
        vec!["eds", "convert", "--to", "json"],
    ] {
        let mut full = args.clone();
        full.push(arg(&garbage));
        let output = run(&full);
        assert!(
            matches!(output.status.code(), Some(0 | 2)),
            "{full:?}: {:?}",
            output.status
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn xdd_round_trip_and_powerlink_refusal() {
    let dir = temp_dir("eds-xdd");
    let baseline = fixture("baseline.eds");
    let xdd = dir.join("baseline.xdd");
    let back = dir.join("back.eds");
    let made = run(&["eds", "convert", arg(&baseline), "--to", "xdd", "-o", arg(&xdd)]);
    assert_eq!(made.status.code(), Some(0), "{}", stderr(&made));
    let text = std::fs::read_to_string(&xdd).unwrap();
    assert!(
        text.contains("ISO15745ProfileContainer") && text.contains("CANopenObjectList"),
        "{text}"
    );
    assert_eq!(
        run(&["eds", "convert", arg(&xdd), "--to", "eds", "-o", arg(&back)])
            .status
            .code(),
        Some(0)
    );
    let same = run(&["eds", "diff", arg(&baseline), arg(&xdd)]);
    assert_eq!(same.status.code(), Some(0), "{}", stdout(&same));
    assert_eq!(
        run(&["eds", "diff", arg(&baseline), arg(&back)]).status.code(),
        Some(0)
    );
    let shown = run(&["eds", "show", arg(&xdd), "--object", "1018"]);
    assert!(stdout(&shown).contains("Vendor-ID"), "{}", stdout(&shown));

    let powerlink = dir.join("powerlink.xdd");
    std::fs::write(
        &powerlink,
        r#"<?xml version="1.0"?><ISO15745ProfileContainer xmlns="http://www.ethernet-powerlink.org"></ISO15745ProfileContainer>"#,
    )
    .unwrap();
    let refused = run(&["eds", "show", arg(&powerlink)]);
    assert_eq!(refused.status.code(), Some(2));
    assert!(
        stderr(&refused).contains("Ethernet POWERLINK"),
        "{}",
        stderr(&refused)
    );
    let broken = dir.join("broken.xdd");
    std::fs::write(&broken, "<ISO15745ProfileContainer><unclosed>").unwrap();
    let bad = run(&["eds", "show", arg(&broken)]);
    assert_eq!(bad.status.code(), Some(2));
    let _ = std::fs::remove_dir_all(&dir);
}

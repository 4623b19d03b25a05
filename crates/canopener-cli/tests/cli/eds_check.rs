//! `canopener eds check|explain|rules list|fix` as users run them: reports, exit codes 0/1/2, files
//! written and kept.

use std::path::{Path, PathBuf};

use super::{run, stderr, stdout, temp_dir};

fn base() -> PathBuf {
    PathBuf::from(canopener_testkit::fixture::BASE_EDS)
}

fn seed_pack() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../canopener-rules/packs/seed-paper.toml")
}

fn arg(path: &Path) -> &str {
    path.to_str().expect("test paths are UTF-8")
}

/// base.eds with SubNumber of 1018h one too low (P045, fixable) and a VendorNumber that differs from
/// 1018sub1 (C304, not fixable), in a fresh directory; the file is named `base.eds` like the original.
fn broken(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(base()).expect("base.eds");
    let text = text
        .replacen(
            "ObjectType=0x9\nSubNumber=5\n",
            "ObjectType=0x9\nSubNumber=4\n",
            1,
        )
        .replacen("VendorNumber=0x00000ABC", "VendorNumber=0x00000ABD", 1);
    let path = dir.join("base.eds");
    std::fs::write(&path, text).expect("write fixture");
    path
}

#[test]
fn check_of_a_clean_file_exits_0_and_says_so() {
    let output = run(&["eds", "check", arg(&base())]);
    assert_eq!(output.status.code(), Some(0), "{}", stdout(&output));
    assert!(
        stdout(&output).contains("0 errors, 0 warnings, 0 infos in 1 file"),
        "{}",
        stdout(&output)
    );
}

#[test]
fn check_reports_errors_compiler_style_and_exits_1() {
    let dir = temp_dir("check-human");
    let file = broken(&dir);
    let output = run(&["eds", "check", arg(&file), "--color", "never"]);
    assert_eq!(output.status.code(), Some(1));
    let text = stdout(&output);
    for wanted in [
        "error[P045]",
        "error[C304]",
        "SubNumber=4",
        "^",
        "= help:",
        "base.eds:",
    ] {
        assert!(text.contains(wanted), "missing {wanted:?} in:\n{text}");
    }
    let quiet = run(&["eds", "check", arg(&file), "--skip", "P045,C304"]);
    assert_eq!(quiet.status.code(), Some(0), "{}", stdout(&quiet));
    let unknown = run(&["eds", "check", arg(&file), "--only", "C999"]);
    assert_eq!(unknown.status.code(), Some(2));
    assert!(
        stderr(&unknown).contains("unknown check 'C999'"),
        "{}",
        stderr(&unknown)
    );
}

#[test]
fn check_json_has_the_documented_shape() {
    let dir = temp_dir("check-json");
    let file = broken(&dir);
    let output = run(&["eds", "check", arg(&file), "--format", "json"]);
    assert_eq!(output.status.code(), Some(1));
    let doc: serde_json::Value = serde_json::from_slice(&output.stdout).expect("one JSON document");
    assert_eq!(doc["version"], 1);
    let findings = doc["files"][0]["findings"].as_array().expect("findings");
    let p045 = findings
        .iter()
        .find(|f| f["code"] == "P045")
        .expect("P045 finding");
    for key in [
        "code", "severity", "message", "line", "column", "section", "key", "fixable",
    ] {
        assert!(p045.get(key).is_some(), "finding lacks {key}: {p045}");
    }
    assert_eq!(p045["severity"], "error");
    assert_eq!(p045["section"], "1018");
    assert_eq!(p045["fixable"], true);
    assert!(
        doc["summary"]["errors"].as_u64().is_some_and(|n| n >= 2),
        "{}",
        doc["summary"]
    );
}

#[test]
fn check_walks_directories_and_globs_and_counts_unreadable_files_as_trouble() {
    let dir = temp_dir("check-batch");
    broken(&dir);
    std::fs::create_dir_all(dir.join("more")).expect("subdir");
    std::fs::copy(base(), dir.join("more/clean.EDS")).expect("copy");
    std::fs::write(dir.join("notes.txt"), "not an EDS").expect("write");
    let output = run(&["eds", "check", arg(&dir), "--format", "json"]);
    let doc: serde_json::Value = serde_json::from_slice(&output.stdout).expect("JSON");
    let paths: Vec<&str> = doc["files"]
        .as_array()
        .expect("files")
        .iter()
        .filter_map(|f| f["path"].as_str())
        .collect();
    assert_eq!(paths.len(), 2, "{paths:?}");
    assert_eq!(output.status.code(), Some(1));
    let pattern = format!("{}/more/*.EDS", dir.display());
    let globbed = run(&[
        "eds",
        "check",
        &pattern,
        arg(&dir.join("missing.eds")),
        "--format",
        "json",
    ]);
    assert_eq!(globbed.status.code(), Some(2), "a missing file is trouble");
    let doc: serde_json::Value = serde_json::from_slice(&globbed.stdout).expect("JSON");
    assert_eq!(doc["files"].as_array().map(Vec::len), Some(2));
    assert!(
        doc["files"][1]["problem"]
            .as_str()
            .is_some_and(|p| p.contains("no such file")),
        "{doc}"
    );
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).expect("empty dir");
    let nothing = run(&["eds", "check", arg(&empty)]);
    assert_eq!(
        nothing.status.code(),
        Some(2),
        "an empty directory is not a clean result"
    );
    assert!(
        stdout(&nothing).contains("no .eds, .dcf, .xdd, .xdc or .xpd file"),
        "{}",
        stdout(&nothing)
    );
}

#[test]
fn deny_warnings_fails_on_warnings() {
    let dir = temp_dir("check-deny");
    let text = std::fs::read_to_string(base())
        .expect("base.eds")
        .replacen("Dummy0007=1\n", "", 1);
    let file = dir.join("base.eds");
    std::fs::write(&file, text).expect("write");
    let plain = run(&["eds", "check", arg(&file), "--format", "json"]);
    assert_eq!(plain.status.code(), Some(0), "{}", stdout(&plain));
    let denied = run(&["eds", "check", arg(&file), "--deny", "warnings"]);
    assert_eq!(denied.status.code(), Some(1));
    assert!(stdout(&denied).contains("T006"), "{}", stdout(&denied));
}

#[test]
fn check_writes_sarif_junit_and_html_files() {
    let dir = temp_dir("check-formats");
    let file = broken(&dir);
    for (format, marker) in [
        ("sarif", "\"2.1.0\""),
        ("junit", "<testsuites"),
        ("html", "<!DOCTYPE html>"),
    ] {
        let out = dir.join(format!("report.{format}"));
        let output = run(&["eds", "check", arg(&file), "--format", format, "-o", arg(&out)]);
        assert_eq!(output.status.code(), Some(1), "{format}: {}", stderr(&output));
        let written = std::fs::read_to_string(&out).expect("report written");
        assert!(written.contains(marker), "{format} lacks {marker}");
        assert!(written.contains("P045"), "{format} lacks the finding");
    }
}

#[test]
fn explain_prints_the_page_and_rules_list_shows_every_check() {
    let page = run(&["eds", "explain", "p045"]);
    assert_eq!(page.status.code(), Some(0));
    let text = stdout(&page);
    assert!(text.starts_with("P045 sub-number-mismatch (error"), "{text}");
    assert!(text.contains("Fixable by `canopener eds fix`: yes"), "{text}");
    let by_slug = run(&["eds", "explain", "sub-number-mismatch"]);
    assert_eq!(stdout(&by_slug), text);
    assert_eq!(run(&["eds", "explain", "C999"]).status.code(), Some(2));

    let list = run(&[
        "eds",
        "rules",
        "list",
        "--rules",
        arg(&seed_pack()),
        "--format",
        "json",
    ]);
    assert_eq!(list.status.code(), Some(0), "{}", stderr(&list));
    let doc: serde_json::Value = serde_json::from_slice(&list.stdout).expect("JSON");
    let checks = doc["checks"].as_array().expect("checks");
    let builtin = canopener_check::registry::builtin().len();
    assert!(
        checks.len() > builtin,
        "{} listed, {builtin} built in",
        checks.len()
    );
    assert!(checks.iter().any(|c| c["origin"] != "built-in"));
    let portability = run(&["eds", "rules", "list", "--tag", "portability"]);
    let text = stdout(&portability);
    assert!(text.contains("T001") && !text.contains("C301"), "{text}");
}

#[test]
fn fix_dry_run_prints_a_diff_and_writes_nothing() {
    let dir = temp_dir("fix-dry");
    let file = broken(&dir);
    let before = std::fs::read(&file).expect("read");
    let output = run(&["eds", "fix", arg(&file), "--dry-run"]);
    let diff = stdout(&output);
    assert!(
        diff.contains("-SubNumber=4") && diff.contains("+SubNumber=5"),
        "{diff}"
    );
    assert!(stderr(&output).contains("fixed P045"), "{}", stderr(&output));
    assert_eq!(
        output.status.code(),
        Some(1),
        "C304 is not fixable, so an error remains"
    );
    assert_eq!(
        std::fs::read(&file).expect("read"),
        before,
        "--dry-run must not write"
    );
}

#[test]
fn fix_in_place_keeps_a_backup_and_changes_only_the_fixed_line() {
    let dir = temp_dir("fix-in-place");
    let file = broken(&dir);
    let before = std::fs::read_to_string(&file).expect("read");
    let output = run(&["eds", "fix", arg(&file), "--in-place", "--only", "P045"]);
    // --only also limits the re-check, so the unfixable C304 does not count here.
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let after = std::fs::read_to_string(&file).expect("read");
    let backup = std::fs::read_to_string(dir.join("base.eds.bak")).expect("backup kept");
    assert_eq!(backup, before);
    let changed: Vec<(&str, &str)> = before
        .lines()
        .zip(after.lines())
        .filter(|(a, b)| a != b)
        .collect();
    assert_eq!(changed, vec![("SubNumber=4", "SubNumber=5")]);
    assert_eq!(before.lines().count(), after.lines().count());
    let again = run(&["eds", "fix", arg(&file), "--in-place", "--only", "P045"]);
    assert!(stderr(&again).contains("nothing to fix"), "{}", stderr(&again));
    let refused = run(&["eds", "fix", arg(&file), "-o", arg(&file)]);
    assert_eq!(refused.status.code(), Some(2));
}

/// base.xdd with its vendor ID changed in DeviceIdentity (C304 against 1018sub1) and a dangling
/// `uniqueIDRef` (X006), saved as `device.eds`: XML is recognised by content, not by extension.
fn broken_xdd(dir: &Path) -> PathBuf {
    let xdd = base().with_file_name("base.xdd");
    let text = std::fs::read_to_string(xdd).expect("base.xdd");
    let text = text
        .replacen(
            "<q1:vendorID>0x00000ABC</q1:vendorID>",
            "<q1:vendorID>0x00000ABD</q1:vendorID>",
            1,
        )
        .replacen(
            r#"uniqueIDRef="UID_OBJ_2000""#,
            r#"uniqueIDRef="UID_OBJ_2001""#,
            1,
        );
    let path = dir.join("device.eds");
    std::fs::write(&path, text).expect("write fixture");
    path
}

#[test]
fn check_reads_xml_by_content_and_points_into_the_xml_in_every_format() {
    let dir = temp_dir("check-xdd");
    let file = broken_xdd(&dir);
    let text = std::fs::read_to_string(&file).expect("fixture");
    let line_of = |needle: &str| {
        text.lines()
            .position(|l| l.contains(needle))
            .map(|i| i + 1)
            .expect("needle in the fixture")
    };
    let output = run(&["eds", "check", arg(&file), "--format", "json"]);
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    let json: serde_json::Value = serde_json::from_str(&stdout(&output)).expect("JSON report");
    let findings = json["files"][0]["findings"].as_array().expect("findings").clone();
    let at = |code: &str| {
        findings
            .iter()
            .find(|f| f["code"] == code)
            .and_then(|f| f["line"].as_u64())
            .unwrap_or_else(|| panic!("{code} not reported: {findings:?}"))
    };
    assert_eq!(at("C304"), line_of("<q1:vendorID>") as u64);
    assert_eq!(at("X006"), line_of("UID_OBJ_2001") as u64);
    assert!(
        findings.iter().all(|f| {
            let code = f["code"].as_str().unwrap_or("");
            !code.starts_with('P') && !code.starts_with("C1") && !code.starts_with('T')
        }),
        "no CiA 306 text findings on XML: {findings:?}"
    );
    for (format, marker) in [
        ("sarif", "\"2.1.0\""),
        ("junit", "<testsuites"),
        ("html", "<!DOCTYPE html>"),
    ] {
        let out = dir.join(format!("report.{format}"));
        let output = run(&["eds", "check", arg(&file), "--format", format, "-o", arg(&out)]);
        assert_eq!(output.status.code(), Some(1), "{format}: {}", stderr(&output));
        let written = std::fs::read_to_string(&out).expect("report written");
        assert!(written.contains(marker) && written.contains("X006"), "{format}");
    }
    let clean = run(&["eds", "check", arg(&base().with_file_name("base.xdd"))]);
    assert_eq!(clean.status.code(), Some(0), "{}", stdout(&clean));
}

#[test]
fn fix_refuses_xml_and_explain_knows_the_x_codes() {
    let dir = temp_dir("fix-xdd");
    let file = broken_xdd(&dir);
    let before = std::fs::read(&file).expect("fixture");
    let output = run(&["eds", "fix", arg(&file), "--in-place"]);
    assert_eq!(output.status.code(), Some(2));
    assert!(stderr(&output).contains("CiA 311 XML"), "{}", stderr(&output));
    assert_eq!(
        std::fs::read(&file).expect("still there"),
        before,
        "the file is untouched"
    );
    let page = run(&["eds", "explain", "X101"]);
    assert_eq!(page.status.code(), Some(0));
    assert!(stdout(&page).contains("allowedValues"), "{}", stdout(&page));
}

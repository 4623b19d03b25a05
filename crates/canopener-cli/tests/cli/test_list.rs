//! `canopener test --list --format json`: every test with its CCT cases and how it covers each,
//! the input of `crates/canopener-conformance/scripts/cct_coverage.py`.

use super::{run, stderr};

#[test]
fn the_json_list_gives_each_test_its_cct_cases_with_their_coverage() {
    let output = run(&["test", "--list", "--format", "json"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let tests: serde_json::Value = serde_json::from_slice(&output.stdout).expect("JSON");
    let tests = tests.as_array().expect("an array of tests");
    let cases = |id: &str| -> Vec<(String, String)> {
        let test = tests.iter().find(|t| t["id"] == id).expect("listed");
        test["cct"]
            .as_array()
            .expect("cct")
            .iter()
            .map(|c| {
                (
                    c["case"].as_str().unwrap_or_default().to_owned(),
                    c["coverage"].as_str().unwrap_or_default().to_owned(),
                )
            })
            .collect()
    };
    assert_eq!(
        cases("cia301.sdo.15"),
        [
            ("SDO 19", "covered"),
            ("SDO 22", "covered"),
            ("SDO 23", "covered")
        ]
        .map(|(a, b)| (a.to_owned(), b.to_owned()))
    );
    assert_eq!(
        cases("cia301.sdo.1"),
        [("SDO 01", "covered"), ("SDO 13", "different")].map(|(a, b)| (a.to_owned(), b.to_owned()))
    );
    // A test outside the CCT lists none; every listed case has a reading or is covered.
    assert!(cases("cia301.sdo.17").is_empty());
    let listed: usize = tests
        .iter()
        .map(|t| t["cct"].as_array().map_or(0, Vec::len))
        .sum();
    assert!(listed >= 127, "{listed} case entries");
}

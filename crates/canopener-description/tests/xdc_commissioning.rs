//! Issue 18 item 1: on an XDC the commissioning rules of a DCF apply (node-ID, bit rate against the
//! supported ones, configured values against limits), reported at the XML attribute or element.

use canopener_description::{Checker, Selection};

fn base_xdc() -> String {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../canopener-check/test_data/checks/base.xdc"
    );
    canopener_testkit::fixture::read_to_string(path).expect("base.xdc")
}

/// Codes found, with the line and the column they point at.
fn findings(text: &str) -> Vec<(String, u32, u32)> {
    let checker = Checker::new(Vec::new(), Selection::default()).expect("no names");
    let report = checker.check("base.xdc", Some("base.xdc"), text.as_bytes());
    assert_eq!(report.problem, None);
    report
        .findings
        .iter()
        .map(|f| {
            (
                f.diagnostic.code.clone(),
                f.diagnostic.span.line,
                f.diagnostic.span.column,
            )
        })
        .collect()
}

/// The 1-based line and column of `needle`.
fn at(text: &str, needle: &str) -> (u32, u32) {
    text.lines()
        .enumerate()
        .find_map(|(i, l)| {
            let column = l.find(needle)?;
            Some((u32::try_from(i + 1).ok()?, u32::try_from(column + 1).ok()?))
        })
        .unwrap_or_else(|| panic!("{needle} not in the fixture"))
}

fn located(found: &[(String, u32, u32)], code: &str) -> Option<(u32, u32)> {
    found.iter().find(|f| f.0 == code).map(|f| (f.1, f.2))
}

#[test]
fn the_base_xdc_is_clean_but_for_the_note_on_other_readers() {
    let found = findings(&base_xdc());
    assert!(found.iter().all(|f| f.0 == "X102"), "{found:?}");
}

#[test]
fn node_id_bit_rate_and_configured_values_follow_the_dcf_rules_at_their_attributes() {
    let text = base_xdc()
        .replacen(r#"nodeID="5""#, r#"nodeID="200""#, 1)
        .replacen(r#"actualBaudRate="250 Kbps""#, r#"actualBaudRate="800 Kbps""#, 1);
    let found = findings(&text);
    assert_eq!(
        located(&found, "C802"),
        Some(at(&text, r#"nodeID="200""#)),
        "{found:?}"
    );
    assert_eq!(
        located(&found, "C804"),
        Some(at(&text, r#"actualBaudRate="800 Kbps""#)),
        "800 kbit/s is not among the supported rates: {found:?}"
    );
    assert!(found.iter().all(|f| f.0 != "X035"), "C802/C803 say it: {found:?}");
    let unusable = base_xdc().replacen(r#"actualBaudRate="250 Kbps""#, r#"actualBaudRate="fast""#, 1);
    let found = findings(&unusable);
    assert_eq!(
        located(&found, "C803"),
        Some(at(&unusable, r#"actualBaudRate="fast""#)),
        "{found:?}"
    );
    let too_big = base_xdc().replacen(
        r#"<q1:actualValue value="20" />"#,
        r#"<q1:actualValue value="2000" />"#,
        1,
    );
    let found = findings(&too_big);
    assert_eq!(
        located(&found, "C602"),
        Some(at(&too_big, r#"<q1:actualValue value="2000" />"#)),
        "a configured value above the parameter's range: {found:?}"
    );
    let not_a_number = base_xdc().replacen(
        r#"<q1:actualValue value="20" />"#,
        r#"<q1:actualValue value="2O" />"#,
        1,
    );
    let found = findings(&not_a_number);
    assert_eq!(
        located(&found, "P050"),
        Some(at(&not_a_number, r#"<q1:actualValue value="2O" />"#)),
        "a configured value that is not a UNSIGNED16: {found:?}"
    );
}

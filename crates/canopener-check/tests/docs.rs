//! The documents the checker's output points to: `docs/checks.md`, where SARIF `helpUri` links and
//! the HTML report point, must list exactly the checks this build has; `docs/check-catalogue.md`,
//! which defines the check numbers the code cites, must agree with the codes that cite them;
//! `docs/cia301-value-rules.md` must be the rule table the checker evaluates.

/// Rewrites `docs/NAME` when `CANOPENER_UPDATE_DOCS` is set, then asserts it equals `wanted`;
/// returns the file's text.
fn up_to_date(name: &str, wanted: &str) -> String {
    let path = format!("{}/../../docs/{name}", env!("CARGO_MANIFEST_DIR"));
    if std::env::var_os("CANOPENER_UPDATE_DOCS").is_some() {
        canopener_testkit::fixture::write(&path, wanted).unwrap_or_else(|e| panic!("write docs/{name}: {e}"));
    }
    let current = canopener_testkit::fixture::read_to_string(&path).unwrap_or_default();
    assert!(
        current == wanted,
        "docs/{name} is stale; run `CANOPENER_UPDATE_DOCS=1 cargo test -p canopener-check --test docs`"
    );
    current
}

#[test]
fn docs_checks_md_is_up_to_date() {
    let current = up_to_date("checks.md", &canopener_check::registry::catalogue_markdown());
    for check in canopener_check::registry::builtin() {
        assert!(
            current.contains(&format!("\n## {}\n", check.code)),
            "{} has no heading",
            check.code
        );
    }
}

/// `docs/check-catalogue.md` defines the check numbers the code cites: it must have a row for every
/// number, and each row must name exactly the codes that say they implement it.
#[test]
fn the_check_catalogue_names_the_codes_of_every_number() {
    use std::collections::{BTreeMap, BTreeSet};

    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/check-catalogue.md");
    let text = canopener_testkit::fixture::read_to_string(path).expect("read docs/check-catalogue.md");
    let mut documented: BTreeMap<u8, BTreeSet<String>> = BTreeMap::new();
    for line in text.lines() {
        let Some(rest) = line.strip_prefix("| <a id=\"check-") else {
            continue;
        };
        let number: u8 = rest
            .split('"')
            .next()
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("a catalogue row without a number: {line}"));
        let codes = line
            .trim_end_matches('|')
            .rsplit('|')
            .next()
            .unwrap_or_default()
            .split(',')
            .map(|c| c.trim().to_owned())
            .collect();
        assert!(
            documented.insert(number, codes).is_none(),
            "check {number} has two rows"
        );
    }
    let mut implemented: BTreeMap<u8, BTreeSet<String>> = BTreeMap::new();
    for check in canopener_check::registry::builtin() {
        for &number in check.reference {
            implemented
                .entry(number)
                .or_default()
                .insert(check.code.to_owned());
        }
    }
    assert_eq!(
        documented.keys().copied().collect::<Vec<_>>(),
        (1..=65).collect::<Vec<u8>>(),
        "the catalogue must number its checks 1 to 65"
    );
    for (number, codes) in &implemented {
        assert_eq!(
            documented.get(number),
            Some(codes),
            "check {number}: the catalogue's codes differ from the codes that cite it"
        );
    }
}

/// The table of CiA 301 value rules is generated from the rule table the checker evaluates.
#[test]
fn docs_cia301_value_rules_md_is_up_to_date() {
    let current = up_to_date(
        "cia301-value-rules.md",
        &canopener_check::registry::value_rules_markdown(),
    );
    for code in ["C870", "C872", "C886"] {
        assert!(
            current.contains(&format!("[{code}](checks.md#")),
            "{code} is not in the table"
        );
    }
}

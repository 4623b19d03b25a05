//! `docs/checks.md` is the catalogue SARIF `helpUri` links and the HTML report point to: it must list
//! exactly the checks this build has.

#[test]
fn docs_checks_md_is_up_to_date() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/checks.md");
    let wanted = canopener_check::registry::catalogue_markdown();
    if std::env::var_os("CANOPENER_UPDATE_DOCS").is_some() {
        std::fs::write(path, &wanted).expect("write docs/checks.md");
    }
    let current = std::fs::read_to_string(path).unwrap_or_default();
    assert!(
        current == wanted,
        "docs/checks.md is stale; run `CANOPENER_UPDATE_DOCS=1 cargo test -p canopener-check --test docs`"
    );
    for check in canopener_check::registry::builtin() {
        assert!(
            current.contains(&format!("\n## {}\n", check.code)),
            "{} has no heading",
            check.code
        );
    }
}

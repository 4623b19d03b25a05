//! The catalogue of built-in checks, assembled from the descriptions each check module gives of
//! its own checks (the private `checks` module): lookup by code or slug, and the Markdown page
//! `docs/checks.md`. This module only reads those descriptions; no check depends on it.

pub use crate::check_info::{CheckDescription, CheckInfo, Group};

/// Every built-in check, in code order.
pub fn builtin() -> Vec<&'static CheckInfo> {
    let mut all: Vec<&'static CheckInfo> = crate::checks::GROUPS
        .iter()
        .flat_map(|group| group.checks)
        .collect();
    all.sort_by_key(|c| c.code);
    all
}

/// Looks a built-in check up by code (case-insensitive) or slug.
pub fn lookup(name: &str) -> Option<&'static CheckInfo> {
    builtin()
        .into_iter()
        .find(|c| c.code.eq_ignore_ascii_case(name) || c.slug == name)
}

/// Every built-in check as Markdown: `docs/checks.md`, where SARIF `helpUri` links
/// and the HTML report point (`#c301` anchors). Kept in sync by a test.
pub fn catalogue_markdown() -> String {
    let all = builtin();
    let mut out = String::from(
        "# canopener's EDS/DCF checks\n\n\
         Generated from the check descriptions (`crates/canopener-check/src/checks/`, assembled by\n\
         `crates/canopener-check/src/registry.rs`); do not edit by hand:\n\
         `CANOPENER_UPDATE_DOCS=1 cargo test -p canopener-check --test docs` rewrites it.\n\
         `canopener eds explain CODE` prints the same page on a terminal.\n\n\
         Series: `P` found while loading, `C1xx`-`C9xx` checks by group of the [check catalogue](check-catalogue.md)\n\
         (1 syntax, 2 FileInfo, 3 DeviceInfo and DummyUsage, 4 object lists, 5 object sections, 6 values,\n\
         7 CiA 301, 8 DCF and modules, 9 reference profiles), `T` portability (how other tools misread a file),\n\
         `X0xx` found while reading CiA 311 XDD/XDC, `X1xx` checks only XML files need.\n\n",
    );
    out.push_str(&format!(
        "{} checks.\n\n| code | severity | group | fix | title |\n|---|---|---|---|---|\n",
        all.len()
    ));
    for check in &all {
        out.push_str(&format!(
            "| [{}](#{}) | {} | {} | {} | {} |\n",
            check.code,
            check.code.to_ascii_lowercase(),
            check.severity,
            check.group,
            if check.fixable { "yes" } else { "" },
            check.title.replace('|', "\\|")
        ));
    }
    for check in &all {
        out.push_str(&format!(
            "\n## {}\n\n`{}` · {} · {} · {}{}\n\n",
            check.code,
            check.slug,
            check.severity,
            check.group,
            check.spec,
            if check.fixable {
                " · fixed by `canopener eds fix`"
            } else {
                ""
            }
        ));
        out.push_str(&format!("**{}**\n\n", check.title));
        let numbers: Vec<String> = check
            .reference
            .iter()
            .map(|n| format!("[{n}](check-catalogue.md#check-{n})"))
            .collect();
        if !numbers.is_empty() {
            out.push_str(&format!(
                "Implements checks {} of the [check catalogue](check-catalogue.md).\n\n",
                numbers.join(", ")
            ));
        }
        out.push_str(check.explanation.trim());
        out.push('\n');
    }
    out
}

/// The table of CiA 301 value rules of the communication objects (object → rule → check code →
/// source) as Markdown: `docs/cia301-value-rules.md`, generated from the rule table the checker
/// evaluates, so the two cannot drift. Kept in sync by a test.
pub fn value_rules_markdown() -> String {
    crate::checks::value_rules_markdown(|code| lookup(code).map(|c| c.severity))
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;

    use super::*;

    #[test]
    fn codes_and_slugs_are_unique() {
        let all = builtin();
        let codes: BTreeSet<&str> = all.iter().map(|c| c.code).collect();
        let slugs: BTreeSet<&str> = all.iter().map(|c| c.slug).collect();
        assert_eq!(codes.len(), all.len(), "a code is defined twice");
        assert_eq!(slugs.len(), all.len(), "a slug is used twice");
    }

    #[test]
    fn every_check_of_the_reference_list_is_implemented() {
        let covered: BTreeSet<u8> = builtin()
            .iter()
            .flat_map(|c| c.reference.iter().copied())
            .collect();
        let missing: Vec<u8> = (1..=65).filter(|n| !covered.contains(n)).collect();
        assert!(
            missing.is_empty(),
            "checks of the check catalogue without a code: {missing:?}"
        );
        assert!(
            covered.iter().all(|n| (1..=65).contains(n)),
            "a reference number outside 1..=65"
        );
    }

    #[test]
    fn every_check_is_documented_and_in_its_series() {
        for check in builtin() {
            assert!(
                !check.title.is_empty() && !check.explanation.trim().is_empty(),
                "{} undocumented",
                check.code
            );
            assert!(
                !check.spec.is_empty(),
                "{} names no specification clause",
                check.code
            );
            let series_ok = match check.group {
                Group::Portability => check.code.starts_with('T'),
                Group::Xml => check.code.starts_with('X'),
                _ => check.code.starts_with('P') || check.code.starts_with('C'),
            };
            assert!(
                series_ok,
                "{} is in the wrong series for {}",
                check.code, check.group
            );
        }
        assert_eq!(lookup("c537").map(|c| c.slug), Some("sub0-not-highest-sub-index"));
        assert_eq!(lookup("duplicate-section").map(|c| c.code), Some("P020"));
        assert!(lookup("C999").is_none());
    }
}

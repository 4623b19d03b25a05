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
    out.push_str(&canchkeds_markdown());
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

/// The section on CiA's EDS checker: every CANchkEDS and CANeds message the references name with the
/// checks that cover it, and the subjects of its manual.
fn canchkeds_markdown() -> String {
    let links = |codes: &[&str]| -> String {
        if codes.is_empty() {
            return "not covered".to_owned();
        }
        codes
            .iter()
            .map(|c| format!("[{c}](#{})", c.to_ascii_lowercase()))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let mut out = String::from(
        "\n## CiA's EDS checker (CANchkEDS) and canopener\n\n\
         CANchkEDS is the checker the CiA conformance test runs on the EDS first; Vector's CANeds has the \
         same checks. Its manual is not public. Every message of it, or of CANeds, that canopener's \
         references quote, with the checks that report the same (`crates/canopener-check/src/canchkeds.rs`):\n\n\
         | message | text | source | canopener | how |\n|---|---|---|---|---|\n",
    );
    for m in crate::canchkeds::MESSAGES {
        out.push_str(&format!(
            "| {} | {} | {} | {} | {} |\n",
            m.message,
            m.text.replace('|', "\\|"),
            m.source,
            links(m.codes),
            m.note
        ));
    }
    out.push_str(
        "\nThe subjects of the CANchkEDS manual v1.4 (its table of contents), and canopener's checks on each:\n\n\
         | subject | canopener | what |\n|---|---|---|\n",
    );
    for (subject, codes, what) in crate::canchkeds::MANUAL_SUBJECTS {
        out.push_str(&format!("| {subject} | {} | {what} |\n", links(codes)));
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
        let foreign = crate::canchkeds::MESSAGES
            .iter()
            .flat_map(|m| m.codes.iter())
            .chain(crate::canchkeds::MANUAL_SUBJECTS.iter().flat_map(|s| s.1.iter()));
        for code in foreign {
            assert!(
                lookup(code).is_some(),
                "the CANchkEDS table names {code}, which is no check"
            );
        }
        assert_eq!(lookup("duplicate-section").map(|c| c.code), Some("P020"));
        assert!(lookup("C999").is_none());
    }
}

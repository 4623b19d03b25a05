//! What each check is: a stable code, a severity justified by the specification, and an explanation
//! page (`canopener eds explain CODE`).
//!
//! Codes never change meaning once published. Series:
//! - `P0xx`: found while loading (syntax and model building), see [`canopener_eds::diag::Code`];
//! - `C1xx`…`C9xx`: checks on the loaded file, the hundreds digit naming the group of
//!   `eds-format-and-checks.md` §10 (1 = A syntax, 2 = B FileInfo, 3 = C DeviceInfo and D DummyUsage,
//!   4 = E object lists, 5 = F object sections, 6 = G values, 7 = H CiA 301 semantics, 8 = I DCF and
//!   J modules, 9 = K reference profiles);
//! - `T0xx`: portability, how other tools misread the file.

use std::fmt;

use canopener_eds::Severity;
use serde::Serialize;

/// The group of a check (`eds-format-and-checks.md` §10, plus portability).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
pub enum Group {
    /// A. Syntax and lexical rules.
    Syntax,
    /// B. `[FileInfo]`.
    FileInfo,
    /// C. `[DeviceInfo]` and its cross-checks.
    DeviceInfo,
    /// D. `[DummyUsage]`.
    DummyUsage,
    /// E. Object lists.
    ObjectLists,
    /// F. Object and sub-object sections.
    Objects,
    /// G. Values.
    Values,
    /// H. CiA 301 semantics.
    Cia301,
    /// I. DCF-specific.
    Dcf,
    /// J. Modular devices.
    Modules,
    /// K. Comparison with reference profiles.
    Profiles,
    /// How python canopen, Lely and CANopenEditor misread the file.
    Portability,
    /// A check from a user rule pack.
    Rules,
}

impl Group {
    /// A short name for tables and filters (`syntax`, `file-info`, …).
    pub fn name(self) -> &'static str {
        match self {
            Self::Syntax => "syntax",
            Self::FileInfo => "file-info",
            Self::DeviceInfo => "device-info",
            Self::DummyUsage => "dummy-usage",
            Self::ObjectLists => "object-lists",
            Self::Objects => "objects",
            Self::Values => "values",
            Self::Cia301 => "cia301",
            Self::Dcf => "dcf",
            Self::Modules => "modules",
            Self::Profiles => "profiles",
            Self::Portability => "portability",
            Self::Rules => "rules",
        }
    }
}

impl fmt::Display for Group {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A built-in check.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CheckInfo {
    /// The stable code, e.g. `C301`.
    pub code: &'static str,
    /// A short kebab-case name, e.g. `vendor-number-mismatch`.
    pub slug: &'static str,
    /// The severity findings are reported with (justified in `explanation`).
    pub severity: Severity,
    /// The group.
    pub group: Group,
    /// One line: what the check verifies.
    pub title: &'static str,
    /// The numbers of the checks in `eds-format-and-checks.md` §10 this code implements.
    pub reference: &'static [u8],
    /// The specification clause that makes it a finding, e.g. `CiA 306 V1.3 §4.5`.
    pub spec: &'static str,
    /// The explanation page: why it matters, why this severity, how to fix it (plain text,
    /// paragraphs separated by blank lines).
    pub explanation: &'static str,
    /// Whether `canopener eds fix` corrects it.
    pub fixable: bool,
}

impl CheckInfo {
    /// The owned description used by reports (shared with rule-pack checks).
    pub fn describe(&self) -> CheckDescription {
        CheckDescription {
            code: self.code.to_owned(),
            slug: self.slug.to_owned(),
            severity: self.severity,
            group: self.group,
            title: self.title.to_owned(),
            spec: self.spec.to_owned(),
            explanation: self.explanation.to_owned(),
            fixable: self.fixable,
            tags: vec![self.group.name().to_owned()],
            origin: "built-in".to_owned(),
        }
    }
}

/// A check as reports and `eds rules list` show it, built-in or from a rule pack.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct CheckDescription {
    /// The stable code or rule id.
    pub code: String,
    /// A short kebab-case name.
    pub slug: String,
    /// The default severity.
    pub severity: Severity,
    /// The group.
    pub group: Group,
    /// One line: what the check verifies.
    pub title: String,
    /// The specification clause (empty for user rules without one).
    pub spec: String,
    /// The explanation page.
    pub explanation: String,
    /// Whether a fix exists.
    pub fixable: bool,
    /// Tags for `--tag` selection (built-ins carry their group name).
    pub tags: Vec<String>,
    /// `built-in` or the path of the rule pack.
    pub origin: String,
}

/// Every built-in check, in code order.
pub fn builtin() -> Vec<&'static CheckInfo> {
    let mut all: Vec<&'static CheckInfo> = [
        crate::parse_codes::CHECKS,
        crate::group_a::CHECKS,
        crate::group_b::CHECKS,
        crate::group_c::CHECKS,
        crate::group_d::CHECKS,
        crate::group_e::CHECKS,
        crate::group_f::CHECKS,
        crate::group_g::CHECKS,
        crate::group_h::CHECKS,
        crate::group_i::CHECKS,
        crate::group_j::CHECKS,
        crate::group_k::CHECKS,
        crate::portability::CHECKS,
    ]
    .into_iter()
    .flatten()
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

/// The catalogue of every built-in check as Markdown: `docs/checks.md`, where SARIF `helpUri` links
/// and the HTML report point (`#c301` anchors). Kept in sync by a test.
pub fn catalogue_markdown() -> String {
    let all = builtin();
    let mut out = String::from(
        "# canopener's EDS/DCF checks\n\n\
         Generated from the check registry (`crates/canopener-check/src/registry.rs`); do not edit by hand:\n\
         `CANOPENER_UPDATE_DOCS=1 cargo test -p canopener-check --test docs` rewrites it.\n\
         `canopener eds explain CODE` prints the same page on a terminal.\n\n\
         Series: `P` found while loading, `C1xx`-`C9xx` checks by group of eds-format-and-checks.md §10\n\
         (1 syntax, 2 FileInfo, 3 DeviceInfo and DummyUsage, 4 object lists, 5 object sections, 6 values,\n\
         7 CiA 301, 8 DCF and modules, 9 reference profiles), `T` portability (how other tools misread a file).\n\n",
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
        let numbers: Vec<String> = check.reference.iter().map(u8::to_string).collect();
        if !numbers.is_empty() {
            out.push_str(&format!(
                "Implements checks {} of eds-format-and-checks.md §10.\n\n",
                numbers.join(", ")
            ));
        }
        out.push_str(check.explanation.trim());
        out.push('\n');
    }
    out
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
            "checks of eds-format-and-checks.md §10 without a code: {missing:?}"
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

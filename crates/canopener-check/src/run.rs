//! Running the checks on one file and selecting which ones count.

use canopener_eds::Loaded;

use crate::check_info::CheckInfo;
use crate::context::Context;
use crate::finding::{Finding, sort_by_position};
use crate::registry;

/// Which checks to report: `--only`, `--skip`, `--tag`.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Selection {
    /// Report only these codes (or slugs); empty means all.
    pub only: Vec<String>,
    /// Never report these codes (or slugs).
    pub skip: Vec<String>,
    /// Report only checks carrying one of these tags (built-ins: their group name); empty means all.
    pub tags: Vec<String>,
}

impl Selection {
    /// Whether a check with this code, slug and tags is selected.
    pub fn selects(&self, code: &str, slug: &str, tags: &[&str]) -> bool {
        let named = |list: &[String]| list.iter().any(|n| n.eq_ignore_ascii_case(code) || n == slug);
        (self.only.is_empty() || named(&self.only))
            && !named(&self.skip)
            && (self.tags.is_empty() || self.tags.iter().any(|t| tags.contains(&t.as_str())))
    }

    /// Whether a built-in check is selected.
    pub fn selects_builtin(&self, info: &CheckInfo) -> bool {
        self.selects(info.code, info.slug, &[info.group.name()])
    }
}

/// The built-in findings for one file, sorted by position.
#[derive(Debug, Clone, Default)]
pub struct FileCheck {
    /// Every finding, sorted by line, column, code.
    pub findings: Vec<Finding>,
}

/// Runs every built-in check on a loaded file and keeps the selected findings.
///
/// `file_name` is the file's name without directories (for the `FileName` check).
pub fn check(loaded: &Loaded, file_name: Option<&str>, selection: &Selection) -> FileCheck {
    check_context(&Context::new(loaded, file_name), selection)
}

/// Runs every built-in check on a file as a [`Context`] presents it (EDS text, or a model read from
/// another format, [`Context::for_model`]) and keeps the selected findings.
pub fn check_context(cx: &Context<'_>, selection: &Selection) -> FileCheck {
    let mut findings = Vec::new();
    for group in crate::checks::GROUPS {
        (group.run)(cx, &mut findings);
    }
    if *selection != Selection::default() {
        let dropped: std::collections::HashSet<&str> = registry::builtin()
            .into_iter()
            .filter(|info| !selection.selects_builtin(info))
            .map(|info| info.code)
            .collect();
        findings.retain(|f| !dropped.contains(f.diagnostic.code.as_str()));
    }
    sort_by_position(&mut findings);
    FileCheck { findings }
}

/// The findings with one code on an EDS text (for the check modules' unit tests).
#[cfg(test)]
pub(crate) fn findings_with_code(text: &str, code: &str) -> Vec<Finding> {
    let loaded = canopener_eds::load(text.as_bytes());
    check(&loaded, None, &Selection::default())
        .findings
        .into_iter()
        .filter(|f| f.diagnostic.code == code)
        .collect()
}

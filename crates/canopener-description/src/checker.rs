//! The check pipeline: the built-in checks and rule packs in force, from a file's bytes to its
//! report, and the safe fixes.

use std::collections::{BTreeMap, BTreeSet};

use canopener_check::fix::{self, Fix, FixOutcome};
use canopener_check::{CheckDescription, Context, Selection};
use canopener_eds::Loaded;
use canopener_report::FileReport;
use canopener_rules::RulePack;

use crate::format::Format;

mod xml;

pub use xml::{SUPERSEDED, applies_to_xml};

/// A name in a selection (`--only`, `--skip`) that is neither a built-in check nor a rule.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown check '{name}'")]
pub struct UnknownCheck {
    /// The name as given.
    pub name: String,
}

/// The checks in force: every built-in check and the rules of the packs, and the selection of
/// those that are reported.
#[derive(Debug)]
pub struct Checker {
    packs: Vec<RulePack>,
    selection: Selection,
}

impl Checker {
    /// The checks of `packs` and the built-in ones, selected by `selection`. Every code or slug
    /// the selection names to keep or skip must be a known check or rule id (tags need not be).
    pub fn new(packs: Vec<RulePack>, selection: Selection) -> Result<Checker, UnknownCheck> {
        let checker = Checker { packs, selection };
        let known = checker.all();
        for name in checker.selection.only.iter().chain(&checker.selection.skip) {
            if !known
                .iter()
                .any(|c| c.code.eq_ignore_ascii_case(name) || &c.slug == name)
            {
                return Err(UnknownCheck { name: name.clone() });
            }
        }
        Ok(checker)
    }

    /// Which checks are reported.
    pub fn selection(&self) -> &Selection {
        &self.selection
    }

    /// Every check, built-in and from the packs, selected or not: built-ins in code order, then
    /// each pack's rules.
    pub fn all(&self) -> Vec<CheckDescription> {
        let mut all: Vec<CheckDescription> = canopener_check::registry::builtin()
            .iter()
            .map(|c| c.describe())
            .collect();
        for pack in &self.packs {
            all.extend(pack.describe());
        }
        all
    }

    /// The checks the selection keeps, in the order of [`Checker::all`].
    pub fn selected(&self) -> Vec<CheckDescription> {
        self.all()
            .into_iter()
            .filter(|c| {
                let tags: Vec<&str> = c.tags.iter().map(String::as_str).collect();
                self.selection.selects(&c.code, &c.slug, &tags)
            })
            .collect()
    }

    /// A check by code (case-insensitive) or slug, selected or not.
    pub fn find(&self, name: &str) -> Option<CheckDescription> {
        self.all()
            .into_iter()
            .find(|c| c.code.eq_ignore_ascii_case(name) || c.slug == name)
    }

    /// Checks a file's bytes: the selected built-in checks and rules, findings sorted by position,
    /// with the source lines they point at. `path` is how the report names the file; `file_name`
    /// (without directories) is what the `FileName` check compares with. CiA 311 XML
    /// ([`Format::is_xml`]) is read by the XDD reader and its findings point into the XML; anything
    /// else is read as EDS/DCF text.
    pub fn check(&self, path: &str, file_name: Option<&str>, bytes: &[u8]) -> FileReport {
        if Format::is_xml(file_name.and_then(extension), bytes) {
            return xml::check(&self.packs, &self.selection, path, file_name, bytes);
        }
        self.check_loaded(path, file_name, &canopener_eds::load(bytes))
    }

    /// [`Checker::check`] on a file already loaded.
    pub fn check_loaded(&self, path: &str, file_name: Option<&str>, loaded: &Loaded) -> FileReport {
        let mut findings = canopener_check::check(loaded, file_name, &self.selection).findings;
        if !self.packs.is_empty() {
            let cx = Context::new(loaded, file_name);
            for pack in &self.packs {
                findings.extend(pack.check(&cx, &self.selection));
            }
            canopener_check::sort_by_position(&mut findings);
        }
        let lines: BTreeSet<u32> = findings.iter().map(|f| f.diagnostic.span.line).collect();
        // A finding on an empty file points at line 1, which the document does not have: it is
        // shown as an empty line.
        let source: BTreeMap<u32, String> = lines
            .into_iter()
            .filter_map(|line| {
                let index = usize::try_from(line).ok()?.checked_sub(1)?;
                Some((line, loaded.document.line_text(index).to_owned()))
            })
            .collect();
        FileReport {
            path: path.to_owned(),
            findings,
            source,
            problem: None,
        }
    }

    /// Applies the safe fixes of the selected built-in checks and rules to a file's bytes, round
    /// after round, keeping only rounds that do not add errors (see [`fix::fix_file`]).
    pub fn fix(&self, file_name: Option<&str>, bytes: &[u8]) -> FixOutcome {
        let rule_fixes = |cx: &Context<'_>| -> Vec<Fix> {
            self.packs
                .iter()
                .flat_map(|pack| pack.fixes(cx, &self.selection))
                .collect()
        };
        fix::fix_file(bytes, file_name, &self.selection, &rule_fixes)
    }
}

/// The extension of a file name, if it has one.
fn extension(file_name: &str) -> Option<&str> {
    file_name.rsplit_once('.').map(|(_, extension)| extension)
}

#[cfg(test)]
mod tests {
    use canopener_eds::Severity;

    use super::*;

    /// A one-rule pack the XML pipeline's tests share.
    pub(super) const PACK: &str = r#"
[pack]
name = "test"

[[rule]]
id = "test/no-blank-names"
description = "names have no blanks"
severity = "warning"
select = "objects"
assert = "!item.name.contains(' ')"
message = "ParameterName '{item.name}' contains blanks"
"#;

    const EDS: &[u8] = b"[FileInfo]\nFileName=x.eds\n[1000]\nParameterName=Device type\n\
        ObjectType=0x7\nDataType=0x0007\nAccessType=ro\nDefaultValue=0\nPDOMapping=0\n\
        [1000sub1]\n";

    fn selection(only: &[&str], skip: &[&str]) -> Selection {
        Selection {
            only: only.iter().map(|s| (*s).to_owned()).collect(),
            skip: skip.iter().map(|s| (*s).to_owned()).collect(),
            tags: Vec::new(),
        }
    }

    fn pack() -> RulePack {
        canopener_rules::parse_pack(PACK, "test.toml").expect("the test pack parses")
    }

    #[test]
    fn names_to_keep_or_skip_must_be_known() {
        let unknown = Checker::new(Vec::new(), selection(&["C999"], &[])).expect_err("no C999");
        assert_eq!(unknown.to_string(), "unknown check 'C999'");
        assert!(Checker::new(Vec::new(), selection(&["test/no-blank-names"], &[])).is_err());
        let checker = Checker::new(vec![pack()], selection(&["test/no-blank-names"], &["p020"]))
            .expect("a rule id and a code in another case are known");
        assert_eq!(
            checker
                .selected()
                .iter()
                .map(|c| c.code.as_str())
                .collect::<Vec<_>>(),
            ["test/no-blank-names"]
        );
        assert_eq!(
            checker.find("duplicate-section").map(|c| c.code),
            Some("P020".to_owned())
        );
        assert_eq!(
            checker.all().len(),
            canopener_check::registry::builtin().len() + 1
        );
    }

    #[test]
    fn a_report_has_builtin_and_rule_findings_in_order_with_their_lines() {
        let checker = Checker::new(vec![pack()], Selection::default()).expect("no names to check");
        let report = checker.check("dir/x.eds", Some("x.eds"), EDS);
        assert_eq!(
            (report.path.as_str(), report.problem.as_deref()),
            ("dir/x.eds", None)
        );
        let positions: Vec<(u32, u32)> = report
            .findings
            .iter()
            .map(|f| (f.diagnostic.span.line, f.diagnostic.span.column))
            .collect();
        assert!(positions.is_sorted(), "{positions:?}");
        let rule = report
            .findings
            .iter()
            .find(|f| f.diagnostic.code == "test/no-blank-names")
            .expect("the rule finds the blank in `Device type`");
        assert_eq!(rule.diagnostic.severity, Severity::Warning);
        let line = rule.diagnostic.span.line;
        assert_eq!(report.source.get(&line).map(String::as_str), Some("[1000]"));
        assert_eq!(
            report.source.len(),
            positions.iter().map(|p| p.0).collect::<BTreeSet<_>>().len()
        );
    }

    #[test]
    fn an_empty_file_shows_its_findings_on_an_empty_first_line() {
        let checker = Checker::new(Vec::new(), Selection::default()).expect("no names to check");
        let report = checker.check("empty.eds", Some("empty.eds"), b"");
        assert!(!report.findings.is_empty());
        assert_eq!(report.source.get(&1).map(String::as_str), Some(""));
    }

    #[test]
    fn fixes_use_the_selection() {
        let text = b"[FileInfo]\nFileName=x.eds\n[1000]\nParameterName=Device type\nSubNumber=5\n";
        let all = Checker::new(Vec::new(), Selection::default()).expect("no names");
        let none = Checker::new(Vec::new(), selection(&[], &["P045"])).expect("P045 is known");
        let fixed = all.fix(Some("x.eds"), text);
        assert!(fixed.fixes.iter().any(|f| f.code == "P045"), "{:?}", fixed.fixes);
        assert!(
            none.fix(Some("x.eds"), text)
                .fixes
                .iter()
                .all(|f| f.code != "P045")
        );
    }
}

//! Every test the runner knows, with its stable id, and the selection of a run.

pub use crate::test_def::TestDef;

/// The groups of the CiA 301 suite as the human summary names them, in report order.
pub const GROUPS: &[(&str, &str)] = &[
    ("eds", "EDS Test"),
    ("sdo", "SDO Test"),
    ("pdo", "PDO Test"),
    ("od", "Object Dictionary Test"),
    ("emcy", "Emergency Test"),
    ("sync", "SYNC Test"),
    ("ec", "Guarding/Heartbeat Test"),
    ("other", "Store/Restore and Restricted CAN-ID Test"),
    ("nmt", "NMT State and Transition Test"),
    ("io", "CiA 401 Generic I/O Test"),
    ("lss", "LSS Test (CiA 305)"),
    ("perf", "Performance Test (CiA 313)"),
];

/// The suites.
pub const SUITES: &[&str] = &["eds", "cia301", "cia401", "cia305", "cia313"];

/// Every test, in catalogue order.
pub fn catalogue() -> Vec<TestDef> {
    let mut all = crate::cia301::eds::tests();
    all.extend(crate::cia301::sdo::tests());
    all.extend(crate::cia301::pdo::tests());
    all.extend(crate::cia301::pdo_transmission::tests());
    all.extend(crate::cia301::pdo_mapping::tests());
    all.extend(crate::cia301::object_dictionary::tests());
    all.extend(crate::cia301::error_control::emcy_tests());
    all.extend(crate::cia301::sync::tests());
    all.extend(crate::cia301::error_control::tests());
    all.extend(crate::cia301::consumer::tests());
    all.extend(crate::cia301::store::tests());
    all.extend(crate::cia301::nmt::tests());
    all.extend(crate::cia301::nmt_pdo::tests());
    all.extend(crate::cia301::nmt_services::tests());
    all.extend(crate::cia301::nmt_resets::tests());
    all.extend(crate::cia401::tests());
    all.extend(crate::cia305::tests());
    all.extend(crate::cia313::tests());
    all
}

/// Which tests a run takes.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Selection {
    /// `cia301`, `eds` or `all` (`None` is all).
    pub suite: Option<String>,
    /// Only these ids (or id prefixes such as `cia301.sdo`); empty is every id.
    pub only: Vec<String>,
    /// Not these ids or prefixes.
    pub skip: Vec<String>,
    /// Only tests with one of these tags; empty is any.
    pub tags: Vec<String>,
}

/// A selection naming an id, suite or tag no test has.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{what} `{name}` matches no test; `canopener test --list` shows them all")]
pub struct UnknownName {
    /// `--only`, `--skip`, `--suite` or `--tag`.
    pub what: &'static str,
    /// What was given.
    pub name: String,
}

impl Selection {
    /// The selected tests in catalogue order; a name that matches nothing is an error (a typo must
    /// not silently run nothing, or everything).
    pub fn pick(&self, tests: &[TestDef]) -> Result<Vec<TestDef>, UnknownName> {
        let matches =
            |pattern: &str, test: &TestDef| test.id == pattern || test.id.starts_with(&format!("{pattern}."));
        let suite = self.suite.as_deref().filter(|s| *s != "all");
        if let Some(suite) = suite.filter(|s| !SUITES.contains(s)) {
            return Err(UnknownName {
                what: "--suite",
                name: suite.to_owned(),
            });
        }
        for (what, names) in [("--only", &self.only), ("--skip", &self.skip)] {
            if let Some(name) = names.iter().find(|n| !tests.iter().any(|t| matches(n, t))) {
                return Err(UnknownName {
                    what,
                    name: name.clone(),
                });
            }
        }
        if let Some(tag) = self
            .tags
            .iter()
            .find(|tag| !tests.iter().any(|t| t.tags.contains(&tag.as_str())))
        {
            return Err(UnknownName {
                what: "--tag",
                name: tag.clone(),
            });
        }
        Ok(tests
            .iter()
            // The `eds` suite is the EDS check the CiA 301 suite starts with.
            .filter(|t| suite.is_none_or(|s| t.suite == s || (s == "eds" && t.group == "eds")))
            .filter(|t| self.only.is_empty() || self.only.iter().any(|p| matches(p, t)))
            .filter(|t| !self.skip.iter().any(|p| matches(p, t)))
            .filter(|t| self.tags.is_empty() || self.tags.iter().any(|tag| t.tags.contains(&tag.as_str())))
            .copied()
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashSet;

    use super::*;

    #[test]
    fn ids_are_unique_and_name_their_suite_and_group() {
        let all = catalogue();
        let ids: HashSet<_> = all.iter().map(|t| t.id).collect();
        assert_eq!(ids.len(), all.len());
        for test in &all {
            assert!(
                test.id.starts_with(&format!("{}.{}.", test.suite, test.group)),
                "{}",
                test.id
            );
            assert!(GROUPS.iter().any(|(g, _)| *g == test.group), "{}", test.id);
            assert!(!test.references.is_empty(), "{} cites nothing", test.id);
        }
    }

    #[test]
    fn selection_by_prefix_skip_and_unknown_names() {
        let all = catalogue();
        let sdo = Selection {
            only: vec!["cia301.sdo".into()],
            skip: vec!["cia301.sdo.1".into()],
            ..Selection::default()
        };
        let picked = sdo.pick(&all).unwrap();
        assert!(!picked.is_empty());
        assert!(picked.iter().all(|t| t.group == "sdo" && t.id != "cia301.sdo.1"));
        // A prefix matches whole id components only: `cia301.sdo.1` is not `cia301.sdo.10`.
        assert!(picked.iter().any(|t| t.id == "cia301.sdo.10"));
        let typo = Selection {
            only: vec!["cia301.sdoo".into()],
            ..Selection::default()
        };
        assert_eq!(typo.pick(&all).unwrap_err().what, "--only");
        let suite = Selection {
            suite: Some("cia999".into()),
            ..Selection::default()
        };
        assert_eq!(suite.pick(&all).unwrap_err().what, "--suite");
    }
}

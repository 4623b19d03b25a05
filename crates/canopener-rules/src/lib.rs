//! User rule packs for the EDS checker: declarative TOML files of checks written in CEL (the Common
//! Expression Language), loaded at run time, so project policies need no recompiling.
//!
//! ```
//! let pack = canopener_rules::parse_pack(
//!     r#"
//!     [pack]
//!     name = "demo"
//!     [[rule]]
//!     id = "demo/no-blank-names"
//!     description = "ParameterName has no blanks"
//!     severity = "warning"
//!     select = "objects"
//!     assert = "!item.name.contains(' ')"
//!     message = "ParameterName '{item.name}' contains blanks"
//!     "#,
//!     "demo.toml",
//! )
//! .unwrap();
//! let loaded = canopener_eds::load(b"[1000]\nParameterName=Device type\nDataType=0x0007\n");
//! let cx = canopener_check::Context::new(&loaded, Some("demo.eds"));
//! let findings = pack.check(&cx, &canopener_check::Selection::default());
//! assert_eq!(findings[0].diagnostic.message, "ParameterName 'Device type' contains blanks");
//! ```
//!
//! The format and the function library are described in this crate's `README.md`.
//!
//! Every expression is compiled, and every variable, field and function name in it checked, when
//! the pack is parsed ([`parse_pack`]); evaluation never aborts a file: an expression that fails on
//! an item is reported once per rule and file as an `R000` finding ([`EVALUATION_ERROR`]).

#![warn(missing_docs)]
// A file or a frame must never panic this library: no unwrap, expect or unchecked index outside tests
// (as rustls does); each exception names, where it stands, why it cannot fail.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)
)]

mod error;
mod eval;
mod expr;
pub mod functions;
mod items;
mod pack;
mod template;

use std::sync::Arc;

use canopener_check::fix::Fix;
use canopener_check::{CheckDescription, CheckInfo, Context, Finding, Group, Selection};
use canopener_eds::Severity;

pub use error::{PackError, PackErrorKind};
pub use eval::EVALUATION_ERROR_CODE;

/// The check that reports a rule which could not be evaluated on a file (`R000`).
pub const EVALUATION_ERROR: CheckInfo = CheckInfo {
    code: EVALUATION_ERROR_CODE,
    slug: "rule-evaluation-error",
    severity: Severity::Error,
    group: Group::Rules,
    title: "A rule of a rule pack could not be evaluated on the file",
    reference: &[],
    spec: "",
    explanation: "\
A rule pack's expressions are compiled and their names checked when the pack is loaded, but CEL is \
dynamically typed: an expression can still fail on a particular item, for example when it compares \
`item.value` (null when the default is not an integer) with a number, reads a map key the file does \
not have (`eds.device_info.BaudRate_250` when the file lacks it), or calls a function with a value \
of the wrong type. R000 reports the first such failure of each rule in each file, naming the rule, \
the item, the expression part (where, assert, message, let or fix.value) and CEL's error, and \
counts the other items that failed the same way.

It matters because a rule that cannot be evaluated checks nothing: without R000 a broken policy \
would pass silently. The rest of the file, and the other rules, are still checked.

It is an error because the file could not be verified against the policy the pack states; CI \
should not pass while a rule is broken.

Fix the rule: guard values that may be null (`item.value != null && item.value > 0`), test keys \
before reading them (`has(eds.device_info.BaudRate_250)` or `'BaudRate_250' in eds.device_info`), \
or convert text with number(). Until then, `--skip RULE-ID` leaves the rule out, and \
`--skip R000` hides these findings.",
    fixable: false,
};

/// A parsed, compiled rule pack.
pub struct RulePack {
    /// The pack's name (`[pack] name`).
    pub name: String,
    /// What the pack is for (`[pack] description`).
    pub description: String,
    /// Where the pack was read from, as given to [`parse_pack`].
    pub origin: String,
    rules: Vec<pack::Rule>,
    env: Arc<cel::Env>,
}

impl std::fmt::Debug for RulePack {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RulePack")
            .field("name", &self.name)
            .field("origin", &self.origin)
            .field("rules", &self.rule_ids())
            .finish_non_exhaustive()
    }
}

/// Parses and compiles a rule pack; `origin` (usually its path) names it in errors and in
/// [`CheckDescription::origin`].
pub fn parse_pack(text: &str, origin: &str) -> Result<RulePack, PackError> {
    let parsed = pack::parse(text, origin)?;
    Ok(RulePack {
        name: parsed.name,
        description: parsed.description,
        origin: origin.to_owned(),
        rules: parsed.rules,
        env: Arc::clone(&parsed.compiler.env),
    })
}

impl RulePack {
    /// The ids of the pack's rules, in file order.
    pub fn rule_ids(&self) -> Vec<&str> {
        self.rules.iter().map(|r| r.id.as_str()).collect()
    }

    /// Every rule as reports and `eds rules list` show it.
    pub fn describe(&self) -> Vec<CheckDescription> {
        self.rules
            .iter()
            .map(|rule| CheckDescription {
                code: rule.id.clone(),
                slug: eval::slug(rule).to_owned(),
                severity: rule.severity,
                group: Group::Rules,
                title: rule.description.clone(),
                spec: rule.spec.clone().unwrap_or_default(),
                explanation: explanation(rule, self),
                fixable: rule.fix.is_some(),
                tags: eval::tags(rule).into_iter().map(str::to_owned).collect(),
                origin: self.origin.clone(),
            })
            .collect()
    }

    /// Runs the selected rules on one file. Findings carry the rule id as their code; a rule that
    /// cannot be evaluated gives one `R000` finding (unless `R000` is skipped).
    pub fn check(&self, cx: &Context<'_>, selection: &Selection) -> Vec<Finding> {
        eval::run(&self.env, &self.rules, cx, selection).findings
    }

    /// The fixes the selected rules propose for one file, planned against `cx.document`.
    pub fn fixes(&self, cx: &Context<'_>, selection: &Selection) -> Vec<Fix> {
        eval::run(&self.env, &self.rules, cx, selection).fixes
    }
}

fn explanation(rule: &pack::Rule, pack: &RulePack) -> String {
    if let Some(text) = &rule.explanation {
        return text.trim().to_owned();
    }
    let mut out = format!("{}.", rule.description.trim_end_matches('.'));
    let what = match rule.select {
        pack::Select::File => "the file as a whole".to_owned(),
        other => {
            let mut s = match other {
                pack::Select::Objects => "every object",
                pack::Select::SubObjects => "every sub-object",
                _ => "every object and sub-object",
            }
            .to_owned();
            if !rule.include_generated {
                s.push_str(" written in the file");
            }
            s
        }
    };
    out.push_str(&format!("\n\nChecks {what}"));
    if let Some(filter) = &rule.filter {
        out.push_str(&format!(" where `{}`", expr::one_line(&filter.source)));
    }
    out.push_str(&format!(": {}.", eval::describe_assertion(&rule.assert)));
    if !rule.params.is_empty() {
        out.push_str("\n\nParameters:");
        for p in &rule.params {
            out.push_str(&format!(
                "\n  {} ({}) = {}",
                p.name,
                p.type_name,
                template::show(&p.value)
            ));
            if let Some(d) = &p.description {
                out.push_str(&format!(": {d}"));
            }
        }
    }
    if let Some(fix) = &rule.fix {
        out.push_str(&format!(
            "\n\nFix: sets {} to `{}`{}.",
            fix.key,
            expr::one_line(&fix.value.source),
            if fix.changes_meaning {
                " (this changes what the file says about the device)"
            } else {
                ""
            }
        ));
    }
    let severity = match rule.severity {
        Severity::Error => "an error",
        Severity::Warning => "a warning",
        Severity::Info => "information",
    };
    out.push_str(&format!(
        "\n\nA user rule from the pack `{}` ({}), reported as {severity}.",
        pack.name, pack.origin
    ));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_send_sync<T: Send + Sync>() {}

    #[test]
    fn a_pack_can_be_shared_between_threads() {
        assert_send_sync::<RulePack>();
    }

    #[test]
    fn r000_is_a_rules_check() {
        assert_eq!(EVALUATION_ERROR.describe().group, Group::Rules);
        assert!(EVALUATION_ERROR.explanation.split("\n\n").count() >= 3);
    }
}

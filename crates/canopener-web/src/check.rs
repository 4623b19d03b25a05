//! `/check`: a device description the browser sent, checked exactly as `canopener eds check
//! --format json FILE` checks it (the built-in selection, no rule packs), with the source lines the
//! findings point at and the safe fixes of `canopener eds fix` as a unified diff.

use canopener_description::{Checker, Format, Selection};
use serde::Serialize;
use serde_json::Value;

/// What the page gets back for one file.
#[derive(Debug, Clone, Serialize)]
pub struct Checked {
    /// The document `canopener eds check --format json NAME` prints, parsed.
    pub report: Value,
    /// The text of the lines the findings point at, by line number.
    pub source: std::collections::BTreeMap<u32, String>,
    /// The safe fixes.
    pub fixes: Fixes,
}

/// The safe fixes of one file, as `canopener eds fix --dry-run` would apply them.
#[derive(Debug, Clone, Serialize)]
pub struct Fixes {
    /// Whether fixes apply at all (CiA 311 XML is checked, not fixed).
    pub available: bool,
    /// Why not, when they do not.
    pub unavailable: Option<String>,
    /// The fixes applied: code, what it does, whether it changes what the file says.
    pub applied: Vec<AppliedFix>,
    /// Fixes planned but not applied, with why.
    pub skipped: Vec<AppliedFix>,
    /// The unified diff (`a/NAME`, `b/NAME`); empty when nothing changes.
    pub diff: String,
    /// Error findings before and after fixing.
    pub errors_before: usize,
    /// Error findings after.
    pub errors_after: usize,
}

/// One fix.
#[derive(Debug, Clone, Serialize)]
pub struct AppliedFix {
    /// The code of the finding it corrects.
    pub code: String,
    /// What it does.
    pub description: String,
    /// Whether it changes what the file says about the device.
    pub changes_meaning: bool,
    /// Why it was not applied (skipped fixes only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

/// The checker `canopener eds check` uses without `--only`, `--skip`, `--tag` or `--rules`.
fn checker() -> Checker {
    // The default selection names no check, so it cannot name an unknown one.
    Checker::new(Vec::new(), Selection::default()).unwrap_or_else(|_| unreachable!("the default selection"))
}

/// The report document of `canopener eds check --format json NAME` for `bytes` named `name`.
pub fn report_json(name: &str, bytes: &[u8]) -> (String, std::collections::BTreeMap<u32, String>) {
    let checker = checker();
    let file = checker.check(name, Some(name), bytes);
    let source = file.source.clone();
    let report = canopener_report::Report {
        tool_version: env!("CARGO_PKG_VERSION").to_owned(),
        checks: checker.selected(),
        files: vec![file],
    };
    (canopener_report::json(&report), source)
}

/// Checks and plans the fixes of `bytes` named `name` (a name [`crate::upload::check_name`] passed).
pub fn check(name: &str, bytes: &[u8]) -> Checked {
    let (json, source) = report_json(name, bytes);
    Checked {
        report: serde_json::from_str(&json).unwrap_or(Value::Null),
        source,
        fixes: fixes(name, bytes),
    }
}

/// The fixed file, or why there is none.
pub fn fixed(name: &str, bytes: &[u8]) -> Result<Vec<u8>, String> {
    if let Some(reason) = xml_reason(name, bytes) {
        return Err(reason);
    }
    Ok(checker().fix(Some(name), bytes).bytes)
}

fn xml_reason(name: &str, bytes: &[u8]) -> Option<String> {
    let extension = name.rsplit_once('.').map(|(_, e)| e);
    Format::is_xml(extension, bytes).then(|| {
        format!(
            "{name} is CiA 311 XML: fixes are line edits on CiA 306 text, so XML is checked, not fixed \
             (as `canopener eds fix` refuses it)"
        )
    })
}

fn fixes(name: &str, bytes: &[u8]) -> Fixes {
    if let Some(reason) = xml_reason(name, bytes) {
        return Fixes {
            available: false,
            unavailable: Some(reason),
            applied: Vec::new(),
            skipped: Vec::new(),
            diff: String::new(),
            errors_before: 0,
            errors_after: 0,
        };
    }
    let outcome = checker().fix(Some(name), bytes);
    let fix = |f: &canopener_check::fix::Fix, reason: Option<&String>| AppliedFix {
        code: f.code.clone(),
        description: f.description.clone(),
        changes_meaning: f.changes_meaning,
        reason: reason.cloned(),
    };
    Fixes {
        available: true,
        unavailable: None,
        applied: outcome.fixes.iter().map(|f| fix(f, None)).collect(),
        skipped: outcome.skipped.iter().map(|(f, r)| fix(f, Some(r))).collect(),
        diff: canopener_check::fix::unified_diff(
            bytes,
            &outcome.bytes,
            &format!("a/{name}"),
            &format!("b/{name}"),
        ),
        errors_before: outcome.errors_before,
        errors_after: outcome.errors_after,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const BROKEN: &[u8] = b"[FileInfo]\r\nFileName=other.eds\r\n[DeviceInfo]\r\nVendorName=x\r\n";

    #[test]
    fn the_report_is_the_eds_check_document_with_its_source_lines() {
        let checked = check("motor.eds", BROKEN);
        assert_eq!(checked.report["version"], 1);
        assert_eq!(checked.report["files"][0]["path"], "motor.eds");
        let findings = checked.report["files"][0]["findings"].as_array().unwrap();
        assert!(!findings.is_empty());
        for finding in findings {
            let line = u32::try_from(finding["line"].as_u64().unwrap()).unwrap();
            assert!(checked.source.contains_key(&line), "{finding}");
        }
        assert!(checked.fixes.available);
    }

    #[test]
    fn xml_is_checked_but_not_fixed() {
        let xml = b"<?xml version=\"1.0\"?><ISO15745ProfileContainer/>";
        let checked = check("device.xdd", xml);
        assert!(!checked.fixes.available);
        assert!(checked.fixes.unavailable.unwrap().contains("checked, not fixed"));
        assert!(fixed("device.xdd", xml).is_err());
    }
}

//! SARIF 2.1.0 (OASIS), the format GitHub and GitLab code scanning read.

use std::collections::{BTreeSet, HashMap};

use canopener_check::{CheckDescription, Finding};
use canopener_eds::Severity;
use serde_json::{Map, Value, json};

use crate::Report;
use crate::text::{fnv1a64, path_uri};

const SCHEMA: &str = "https://docs.oasis-open.org/sarif/sarif/v2.1.0/os/schemas/sarif-schema-2.1.0.json";
const INFORMATION_URI: &str = "https://github.com/canopener/canopener";
const CHECKS_PAGE: &str = "https://github.com/canopener/canopener/blob/main/docs/checks.md";
/// The key of our partial fingerprint; the `/v1` changes if the hashed content ever changes.
const FINGERPRINT_KEY: &str = "canopenerFindingHash/v1";

fn level(severity: Severity) -> &'static str {
    match severity {
        Severity::Error => "error",
        Severity::Warning => "warning",
        Severity::Info => "note",
    }
}

/// The report as a SARIF 2.1.0 log with one run.
///
/// `tool.driver.rules` holds the selected checks (plus any code that has findings but no
/// description, so every `ruleIndex` resolves); built-in checks link to their section of
/// `docs/checks.md`. Each finding is a result at `path:line:column` (columns in Unicode code points,
/// `columnKind` says so) with a `partialFingerprints` entry hashed from code, section, key and
/// message (not the line), so code-scanning alerts survive lines moving. Files that could not be
/// read are error notifications of the invocation, and `executionSuccessful` is false then.
pub fn sarif(report: &Report) -> String {
    let (rules, rule_index) = rules(report);
    let artifacts: Vec<Value> = report
        .files
        .iter()
        .map(|f| json!({ "location": { "uri": path_uri(&f.path) } }))
        .collect();
    let mut results = Vec::new();
    let mut notifications = Vec::new();
    for (artifact, file) in report.files.iter().enumerate() {
        let uri = path_uri(&file.path);
        if let Some(problem) = &file.problem {
            notifications.push(json!({
                "level": "error",
                "message": { "text": format!("{}: {problem}", file.path) },
                "locations": [{
                    "physicalLocation": { "artifactLocation": { "uri": uri, "index": artifact } }
                }],
            }));
        }
        let mut occurrences: HashMap<u64, usize> = HashMap::new();
        for finding in &file.findings {
            let hash = fnv1a64(&[
                &finding.diagnostic.code,
                finding.diagnostic.section.as_deref().unwrap_or(""),
                finding.diagnostic.key.as_deref().unwrap_or(""),
                &finding.diagnostic.message,
            ]);
            // Identical findings in one file are told apart by their order, as GitHub does with
            // its own line hashes.
            let occurrence = occurrences.entry(hash).or_insert(0);
            *occurrence += 1;
            let fingerprint = format!("{hash:016x}:{occurrence}");
            let index = rule_index
                .get(finding.diagnostic.code.as_str())
                .copied()
                .unwrap_or(0);
            results.push(result(
                finding,
                index,
                &uri,
                artifact,
                &fingerprint,
                file.source.get(&finding.diagnostic.span.line),
            ));
        }
    }
    let mut driver = Map::new();
    driver.insert("name".into(), json!("canopener"));
    if !report.tool_version.is_empty() {
        driver.insert("version".into(), json!(report.tool_version));
    }
    driver.insert("informationUri".into(), json!(INFORMATION_URI));
    driver.insert("rules".into(), Value::Array(rules));
    let log = json!({
        "$schema": SCHEMA,
        "version": "2.1.0",
        "runs": [{
            "tool": { "driver": driver },
            "invocations": [{
                "executionSuccessful": notifications.is_empty(),
                "toolExecutionNotifications": notifications,
            }],
            "columnKind": "unicodeCodePoints",
            "artifacts": artifacts,
            "results": results,
        }],
    });
    // Serialising a `Value` into a String cannot fail.
    let mut text = serde_json::to_string_pretty(&log).unwrap_or_default();
    text.push('\n');
    text
}

/// The rules array and the index of each code in it.
fn rules(report: &Report) -> (Vec<Value>, HashMap<&str, usize>) {
    let mut rules = Vec::new();
    let mut index: HashMap<&str, usize> = HashMap::new();
    for check in &report.checks {
        if !index.contains_key(check.code.as_str()) {
            index.insert(&check.code, rules.len());
            rules.push(rule(check));
        }
    }
    // Codes with findings but no description (e.g. the caller passed a narrower check list).
    let missing: BTreeSet<&str> = report
        .files
        .iter()
        .flat_map(|f| &f.findings)
        .map(|f| f.diagnostic.code.as_str())
        .filter(|code| !index.contains_key(code))
        .collect();
    for code in missing {
        index.insert(code, rules.len());
        rules.push(json!({ "id": code, "shortDescription": { "text": code } }));
    }
    (rules, index)
}

fn non_empty<'a>(text: &'a str, fallback: &'a str) -> &'a str {
    if text.trim().is_empty() { fallback } else { text }
}

fn rule(check: &CheckDescription) -> Value {
    let title = non_empty(&check.title, &check.code);
    let explanation = non_empty(&check.explanation, title);
    let help = if check.spec.is_empty() {
        explanation.to_owned()
    } else {
        format!("{explanation}\n\nSpecification: {}", check.spec)
    };
    let mut rule = Map::new();
    rule.insert("id".into(), json!(check.code));
    rule.insert("name".into(), json!(non_empty(&check.slug, &check.code)));
    rule.insert("shortDescription".into(), json!({ "text": title }));
    rule.insert("fullDescription".into(), json!({ "text": explanation }));
    rule.insert("help".into(), json!({ "text": help }));
    if check.origin == "built-in" {
        let anchor = check.code.to_ascii_lowercase();
        rule.insert("helpUri".into(), json!(format!("{CHECKS_PAGE}#{anchor}")));
    }
    rule.insert(
        "defaultConfiguration".into(),
        json!({ "level": level(check.severity) }),
    );
    let mut tags = check.tags.clone();
    if !tags.iter().any(|t| t == "canopener") {
        tags.push("canopener".into());
    }
    rule.insert(
        "properties".into(),
        json!({
            "tags": tags,
            "group": check.group.name(),
            "spec": check.spec,
            "fixable": check.fixable,
            "origin": check.origin,
            "precision": "very-high",
        }),
    );
    Value::Object(rule)
}

fn result(
    finding: &Finding,
    rule_index: usize,
    uri: &str,
    artifact: usize,
    fingerprint: &str,
    source: Option<&String>,
) -> Value {
    let mut physical = Map::new();
    physical.insert(
        "artifactLocation".into(),
        json!({ "uri": uri, "index": artifact }),
    );
    let span = finding.diagnostic.span;
    // Line 0 means the finding concerns the file as a whole: no region.
    if span.line > 0 {
        let column = span.column.max(1);
        let mut region = Map::new();
        region.insert("startLine".into(), json!(span.line));
        region.insert("startColumn".into(), json!(column));
        // Without an end column a SARIF region extends to the end of the line, which is what a point
        // finding (a missing key, a section header) is about.
        if span.len > 0 {
            region.insert("endColumn".into(), json!(column.saturating_add(span.len)));
            if let Some(line) = source {
                let skip = usize::try_from(column - 1).unwrap_or(usize::MAX);
                let take = usize::try_from(span.len).unwrap_or(usize::MAX);
                let covered: String = line.chars().skip(skip).take(take).collect();
                if covered.chars().count() == take {
                    region.insert("snippet".into(), json!({ "text": covered }));
                }
            }
        }
        physical.insert("region".into(), Value::Object(region));
        if let Some(line) = source {
            physical.insert(
                "contextRegion".into(),
                json!({ "startLine": span.line, "snippet": { "text": line } }),
            );
        }
    }
    let text = match &finding.diagnostic.help {
        Some(help) => format!("{}\nhelp: {help}", finding.diagnostic.message),
        None => finding.diagnostic.message.clone(),
    };
    json!({
        "ruleId": finding.diagnostic.code,
        "ruleIndex": rule_index,
        "level": level(finding.diagnostic.severity),
        "message": { "text": text },
        "locations": [{ "physicalLocation": physical }],
        "partialFingerprints": { (FINGERPRINT_KEY): fingerprint },
        "properties": {
            "section": finding.diagnostic.section,
            "key": finding.diagnostic.key,
            "fixable": finding.fixable,
        },
    })
}

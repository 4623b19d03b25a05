//! Running a pack's rules on one file: findings, fixes, and `R000` when a rule cannot be evaluated.

use std::sync::Arc;

use canopener_check::fix::{Edit, Fix};
use canopener_check::{Context, Finding, Selection, sort_by_position};
use canopener_eds::section_name::SectionKind;
use canopener_eds::{Diagnostic, Severity, Span};
use cel::common::value::{CowVal, Val};
use cel::context::VariableResolver;
use cel::{Env, ExecutionError, Value};

use crate::expr::{Compiled, one_line};
use crate::functions;
use crate::items::{FileItems, Item};
use crate::pack::{Assertion, Place, Rule, Select};
use crate::template::{Part, Template, show};

/// The code of a finding that says a rule could not be evaluated on a file.
pub const EVALUATION_ERROR_CODE: &str = "R000";

/// What running the rules on one file produced.
#[derive(Debug, Default)]
pub(crate) struct Output {
    pub(crate) findings: Vec<Finding>,
    pub(crate) fixes: Vec<Fix>,
}

/// Binds `item` to one prebuilt value without copying it.
struct ItemVar<'a>(&'a (dyn Val + 'a));

impl VariableResolver for ItemVar<'_> {
    fn resolve<'b>(&'b self, variable: &str) -> Option<CowVal<'b, 'b>> {
        (variable == "item").then_some(CowVal::Borrowed(self.0))
    }
}

/// Binds `eds` (and the hidden name the lookup functions use) to the file's value.
struct FileVars<'a>(&'a (dyn Val + 'a));

impl VariableResolver for FileVars<'_> {
    fn resolve<'b>(&'b self, variable: &str) -> Option<CowVal<'b, 'b>> {
        (variable == "eds" || variable == functions::EDS_VAR).then_some(CowVal::Borrowed(self.0))
    }
}

/// The first evaluation error of a rule in a file, and how many items had one.
struct Failure {
    item: Option<usize>,
    what: String,
    error: String,
    count: usize,
}

pub(crate) fn run(env: &Arc<Env>, rules: &[Rule], cx: &Context<'_>, selection: &Selection) -> Output {
    let mut out = Output::default();
    let selected: Vec<&Rule> = rules.iter().filter(|r| selects(selection, r)).collect();
    if selected.is_empty() {
        return out;
    }
    let file = FileItems::build(cx);
    let vars = FileVars(file.eds.as_ref());
    let mut root = cel::Context::with_env(Arc::clone(env));
    root.set_variable_resolver(&vars);
    functions::install(&mut root, &file.index);
    let report_failures = !selection
        .skip
        .iter()
        .any(|s| s.eq_ignore_ascii_case(EVALUATION_ERROR_CODE));
    for rule in selected {
        if let Some(f) = run_rule(rule, &root, &file, cx, &mut out)
            && report_failures
        {
            let item = f.item.and_then(|i| file.items.get(i));
            out.findings.push(failure_finding(cx, rule, item, &f));
        }
    }
    sort_by_position(&mut out.findings);
    out
}

/// Runs one rule on every item it selects; the first evaluation error, if any, with a count.
fn run_rule(
    rule: &Rule,
    root: &cel::Context<'_, '_>,
    file: &FileItems<'_>,
    cx: &Context<'_>,
    out: &mut Output,
) -> Option<Failure> {
    let mut failure: Option<Failure> = None;
    let mut fail = |item: Option<usize>, what: &str, error: String| match &mut failure {
        Some(f) => f.count += 1,
        None => {
            failure = Some(Failure {
                item,
                what: what.to_owned(),
                error,
                count: 1,
            })
        }
    };
    let mut scope = root.new_inner_scope();
    if let Ok(params) = Box::<dyn Val>::try_from(rule.params_value.clone()) {
        scope.add_variable_as_val("params", params);
    }
    let mut bound = Vec::new();
    for (name, compiled) in &rule.lets {
        // Kept as CEL's own value rather than converted to a `Value`: a list of items stays a list of
        // shared items, so later comprehensions over it do not copy every field.
        let value = Value::resolve_val(compiled.program.expression(), &scope).map(CowVal::into_owned);
        match value {
            Ok(v) => bound.push((name.clone(), v)),
            Err(e) => {
                fail(None, &format!("let.{name}"), error_text(&e));
                return failure;
            }
        }
    }
    for (name, v) in bound {
        scope.add_variable_as_val(name, v);
    }
    if rule.select == Select::File {
        match evaluate(rule, &scope) {
            Ok(Some(verdict)) => report(cx, rule, None, &verdict, out),
            Ok(None) => {}
            Err((what, e)) => fail(None, what, e),
        }
        return failure;
    }
    for (i, (item, value)) in file.items.iter().zip(file.values()).enumerate() {
        if !rule_selects(rule, item) {
            continue;
        }
        let resolver = ItemVar(value.as_ref());
        let mut item_scope = scope.new_inner_scope();
        item_scope.set_variable_resolver(&resolver);
        match evaluate(rule, &item_scope) {
            Ok(Some(verdict)) => report(cx, rule, Some(item), &verdict, out),
            Ok(None) => {}
            Err((what, e)) => fail(Some(i), what, e),
        }
    }
    failure
}

/// The selection tags of a rule: its own and `rules`, as built-ins carry their group name.
pub(crate) fn tags(rule: &Rule) -> Vec<&str> {
    let mut tags: Vec<&str> = rule.tags.iter().map(String::as_str).collect();
    tags.push("rules");
    tags
}

/// The rule id's last segment (`no-blank-names` of `paper/no-blank-names`).
pub(crate) fn slug(rule: &Rule) -> &str {
    rule.id.rsplit('/').next().unwrap_or(&rule.id)
}

fn selects(selection: &Selection, rule: &Rule) -> bool {
    selection.selects(&rule.id, slug(rule), &tags(rule))
}

fn rule_selects(rule: &Rule, item: &Item) -> bool {
    let kind_ok = match rule.select {
        Select::File => false,
        Select::Objects => item.sub.is_none(),
        Select::SubObjects => item.sub.is_some(),
        Select::Entries => true,
    };
    kind_ok && (item.written || rule.include_generated)
}

/// A failed assertion: the message, help, and the fix value when the rule has a fix.
struct Verdict {
    message: String,
    help: Option<String>,
    fix_value: Option<String>,
}

/// `Ok(None)` when the item passes (or the filter skips it); the error names the expression.
fn evaluate(rule: &Rule, scope: &cel::Context<'_, '_>) -> Result<Option<Verdict>, (&'static str, String)> {
    if let Some(filter) = &rule.filter
        && !boolean(filter, scope).map_err(|e| ("where", e))?
    {
        return Ok(None);
    }
    let Some(clause) = failing_clause(&rule.assert, scope).map_err(|e| ("assert", e))? else {
        return Ok(None);
    };
    let message = match &rule.message {
        Some(t) => render(t, scope).map_err(|e| ("message", e))?,
        None if matches!(rule.assert, Assertion::Expr(_)) => rule.description.clone(),
        None => format!("{} (failed: {clause})", rule.description),
    };
    let help = match &rule.help {
        Some(t) => Some(render(t, scope).map_err(|e| ("help", e))?),
        None => None,
    };
    let fix_value = match &rule.fix {
        Some(fix) => match fix.value.program.execute(scope) {
            Ok(Value::String(s)) => Some(s.as_str().to_owned()),
            Ok(other) => {
                return Err((
                    "fix.value",
                    format!("gave a {} where a string is needed", other.type_of()),
                ));
            }
            Err(e) => return Err(("fix.value", error_text(&e))),
        },
        None => None,
    };
    Ok(Some(Verdict {
        message,
        help,
        fix_value,
    }))
}

fn boolean(c: &Compiled, scope: &cel::Context<'_, '_>) -> Result<bool, String> {
    match c.program.execute(scope) {
        Ok(Value::Bool(b)) => Ok(b),
        Ok(other) => Err(format!(
            "`{}` gave a {} where a bool is needed",
            one_line(&c.source),
            other.type_of()
        )),
        Err(e) => Err(format!("`{}`: {}", one_line(&c.source), error_text(&e))),
    }
}

/// `None` when the assertion holds, otherwise the clause that failed, as written.
///
/// `all` stops at its first failing member; `any` holds when one member holds, even if another
/// could not be evaluated (as CEL's `||` does); errors otherwise propagate.
fn failing_clause(a: &Assertion, scope: &cel::Context<'_, '_>) -> Result<Option<String>, String> {
    match a {
        Assertion::Expr(c) => Ok((!boolean(c, scope)?).then(|| format!("`{}`", one_line(&c.source)))),
        Assertion::All(members) => {
            for m in members {
                if let Some(clause) = failing_clause(m, scope)? {
                    return Ok(Some(clause));
                }
            }
            Ok(None)
        }
        Assertion::Any(members) => {
            let mut failed = Vec::new();
            let mut error = None;
            for m in members {
                match failing_clause(m, scope) {
                    Ok(None) => return Ok(None),
                    Ok(Some(clause)) => failed.push(clause),
                    Err(e) => error = error.or(Some(e)),
                }
            }
            match error {
                Some(e) => Err(e),
                None => Ok(Some(format!("none of {}", failed.join(", ")))),
            }
        }
        Assertion::Not(inner) => Ok(match failing_clause(inner, scope)? {
            Some(_) => None,
            None => Some(format!("not {}", describe_assertion(inner))),
        }),
    }
}

/// An assertion in one line, for messages and explanations.
pub(crate) fn describe_assertion(a: &Assertion) -> String {
    let list = |members: &[Assertion]| {
        members
            .iter()
            .map(describe_assertion)
            .collect::<Vec<_>>()
            .join(", ")
    };
    match a {
        Assertion::Expr(c) => format!("`{}`", one_line(&c.source)),
        Assertion::All(m) => format!("all of ({})", list(m)),
        Assertion::Any(m) => format!("any of ({})", list(m)),
        Assertion::Not(inner) => format!("not {}", describe_assertion(inner)),
    }
}

fn render(t: &Template, scope: &cel::Context<'_, '_>) -> Result<String, String> {
    let mut out = String::new();
    for part in &t.parts {
        match part {
            Part::Text(text) => out.push_str(text),
            Part::Expr(c) => match c.program.execute(scope) {
                Ok(v) => out.push_str(&show(&v)),
                Err(e) => return Err(format!("`{}`: {}", one_line(&c.source), error_text(&e))),
            },
        }
    }
    Ok(out)
}

fn error_text(e: &ExecutionError) -> String {
    match e {
        ExecutionError::NoSuchKey(k) => format!("no such key `{k}` (test with has() or `in` first)"),
        ExecutionError::NoSuchOverload(o) => {
            let null = o.argument_types().iter().any(|t| t == "null_type");
            let mut text = o.to_string();
            if null {
                text.push_str(" (a value is null: test it with `!= null` first)");
            }
            text
        }
        other => other.to_string(),
    }
}

/// Where a finding about `item` (or the file, for `None`) points: its section and key, as written.
struct Location {
    span: Span,
    section: Option<String>,
    key: Option<String>,
    /// What a fix may edit: `Some(Some(i))` the document's section `i`, `Some(None)` a section the
    /// file lacks (a file rule's fix adds it), `None` nothing (a generated item has no section).
    target: Option<Option<usize>>,
}

fn locate(cx: &Context<'_>, rule: &Rule, item: Option<&Item>, key: Option<&str>) -> Location {
    let place_kind = match item {
        Some(item) => Some(item.kind),
        None => rule.section.as_ref().map(|p: &Place| p.kind),
    };
    let Some(kind) = place_kind else {
        return Location {
            span: cx.file_span(),
            section: None,
            key: None,
            target: None,
        };
    };
    let display = cx
        .section_name(kind)
        .map(str::to_owned)
        .unwrap_or_else(|| match item {
            Some(_) => cx.display_name(kind),
            None => rule
                .section
                .as_ref()
                .map_or_else(|| cx.display_name(kind), |p| p.name.clone()),
        });
    let has_section = cx.has_section(kind);
    let span = if has_section {
        match key {
            Some(k) => cx.value_span(kind, k),
            None => cx.section_span(kind),
        }
    } else {
        // A generated sub-object has no section of its own: point at its object's.
        match item {
            Some(i) => cx.section_span(SectionKind::Object(i.index)),
            None => cx.file_span(),
        }
    };
    let written_key = key.map(|k| cx.entry(kind, k).map_or(k, |(written, _)| written).to_owned());
    let target = match item {
        Some(i) if i.written => Some(i.section),
        Some(_) => None,
        None => Some(cx.sections_of(kind).first().copied()),
    };
    Location {
        span,
        section: Some(display),
        key: written_key,
        target,
    }
}

fn report(cx: &Context<'_>, rule: &Rule, item: Option<&Item>, verdict: &Verdict, out: &mut Output) {
    let fix_key = rule.fix.as_ref().map(|f| f.key.as_str());
    let key = rule.key.as_deref().or(fix_key);
    let at = locate(cx, rule, item, key);
    let fix = match (&rule.fix, &verdict.fix_value) {
        (Some(spec), Some(value)) => {
            // A file rule's fix may edit another section than the one its findings point at.
            let fix_at = match (&spec.section, item) {
                (Some(place), None) => {
                    let kind = place.kind;
                    Location {
                        target: Some(cx.sections_of(kind).first().copied()),
                        section: Some(
                            cx.section_name(kind)
                                .map_or_else(|| place.name.clone(), str::to_owned),
                        ),
                        ..locate(cx, rule, None, Some(&spec.key))
                    }
                }
                _ => locate(cx, rule, item, Some(&spec.key)),
            };
            plan_fix(cx, rule, &fix_at, &spec.key, value, spec.changes_meaning)
        }
        _ => None,
    };
    out.findings.push(Finding {
        diagnostic: Diagnostic {
            code: rule.id.clone(),
            severity: rule.severity,
            message: verdict.message.clone(),
            span: at.span,
            section: at.section,
            key: at.key,
            help: verdict.help.clone(),
        },
        fixable: fix.is_some(),
    });
    out.fixes.extend(fix);
}

fn plan_fix(
    cx: &Context<'_>,
    rule: &Rule,
    at: &Location,
    key: &str,
    value: &str,
    changes_meaning: bool,
) -> Option<Fix> {
    let section = at.target?;
    // A value cannot hold a line break, and leading or trailing blanks would not survive a reread.
    if value.contains(['\n', '\r']) || value.trim() != value {
        return None;
    }
    let name = at.section.clone().unwrap_or_default();
    let (edit, description) = match section {
        Some(section_index) => {
            let section = cx.document.sections().get(section_index)?;
            match cx.document.find_entry(section, key) {
                Some(line) => {
                    let (written, old) = cx.document.entry(line)?;
                    if old.trim() == value {
                        return None;
                    }
                    (
                        Edit::SetValue {
                            line,
                            value: value.to_owned(),
                        },
                        format!("[{name}] {written}: {} -> {value}", old.trim()),
                    )
                }
                None => (
                    Edit::AppendEntry {
                        section: section_index,
                        key: key.to_owned(),
                        value: value.to_owned(),
                    },
                    format!("[{name}] add {key}={value}"),
                ),
            }
        }
        None => {
            // Only a file rule gets here (an item's section exists when it is written).
            let header = rule
                .fix
                .as_ref()
                .and_then(|f| f.section.as_ref())
                .or(rule.section.as_ref())
                .map_or(name, |p| p.name.clone());
            (
                Edit::AppendLines {
                    lines: vec![format!("[{header}]"), format!("{key}={value}")],
                },
                format!("add [{header}] with {key}={value}"),
            )
        }
    };
    Some(Fix {
        code: rule.id.clone(),
        description,
        changes_meaning,
        edits: vec![edit],
    })
}

fn failure_finding(cx: &Context<'_>, rule: &Rule, item: Option<&Item>, f: &Failure) -> Finding {
    let at = locate(cx, rule, item, None);
    let subject = match item {
        Some(_) => format!(" on [{}]", at.section.as_deref().unwrap_or("?")),
        None => String::new(),
    };
    let more = match f.count {
        1 => String::new(),
        2 => " (and 1 more item)".to_owned(),
        n => format!(" (and {} more items)", n - 1),
    };
    Finding {
        diagnostic: Diagnostic {
            code: EVALUATION_ERROR_CODE.to_owned(),
            severity: Severity::Error,
            message: format!(
                "rule `{}` could not be evaluated{subject}{more}: {}: {}",
                rule.id, f.what, f.error
            ),
            span: at.span,
            section: at.section,
            key: None,
            help: Some(format!(
                "fix the rule in its pack, or skip it with --skip {}; `canopener eds explain R000` says more",
                rule.id
            )),
        },
        fixable: false,
    }
}

//! Reading a rule pack: the TOML format, checked and compiled into [`Rule`]s.

use std::collections::{BTreeMap, HashMap};
use std::ops::Range;
use std::sync::Arc;

use canopener_eds::Severity;
use canopener_eds::section_name::{SectionKind, classify};
use cel::Value;
use cel::objects::{Key, Map};
use serde::Deserialize;
use toml::Spanned;

use crate::error::{Locator, PackError, PackErrorKind};
use crate::expr::{Compiled, Compiler, Refusal, Scope, one_line};
use crate::template::{Part, Template};

/// What a rule iterates over.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Select {
    /// The file as a whole: evaluated once, no `item`.
    File,
    /// Every object (`[1018]`).
    Objects,
    /// Every sub-object (`[1018sub1]`).
    SubObjects,
    /// Objects and sub-objects.
    Entries,
}

/// An assertion: a CEL expression, or all/any/not of assertions.
#[derive(Debug)]
pub(crate) enum Assertion {
    Expr(Compiled),
    All(Vec<Assertion>),
    Any(Vec<Assertion>),
    Not(Box<Assertion>),
}

/// A parameter's declared type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ParamType {
    Int,
    Double,
    Bool,
    String,
    List(ScalarType),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ScalarType {
    Int,
    Double,
    Bool,
    String,
}

impl ParamType {
    const NAMES: &'static str =
        "int, double, bool, string, list<int>, list<double>, list<bool>, list<string>";

    fn parse(text: &str) -> Option<Self> {
        let compact: String = text.chars().filter(|c| !c.is_whitespace()).collect();
        let scalar = |t: &str| match t {
            "int" => Some(ScalarType::Int),
            "double" => Some(ScalarType::Double),
            "bool" => Some(ScalarType::Bool),
            "string" => Some(ScalarType::String),
            _ => None,
        };
        if let Some(inner) = compact.strip_prefix("list<").and_then(|r| r.strip_suffix('>')) {
            return scalar(inner).map(Self::List);
        }
        Some(match scalar(&compact)? {
            ScalarType::Int => Self::Int,
            ScalarType::Double => Self::Double,
            ScalarType::Bool => Self::Bool,
            ScalarType::String => Self::String,
        })
    }
}

impl ScalarType {
    fn name(self) -> &'static str {
        match self {
            Self::Int => "int",
            Self::Double => "double",
            Self::Bool => "bool",
            Self::String => "string",
        }
    }

    /// The TOML value as a CEL value of this type (an integer is a fine double).
    fn convert(self, v: &toml::Value) -> Option<Value> {
        Some(match (self, v) {
            (Self::Int, toml::Value::Integer(i)) => Value::Int(*i),
            (Self::Double, toml::Value::Float(f)) => Value::Float(*f),
            (Self::Double, toml::Value::Integer(i)) => Value::Float(*i as f64),
            (Self::Bool, toml::Value::Boolean(b)) => Value::Bool(*b),
            (Self::String, toml::Value::String(s)) => Value::String(Arc::new(s.clone())),
            _ => return None,
        })
    }
}

/// A typed parameter of a rule.
#[derive(Debug, Clone)]
pub(crate) struct Param {
    pub(crate) name: String,
    pub(crate) value: Value,
    pub(crate) type_name: String,
    pub(crate) description: Option<String>,
}

/// Where a file rule's findings point, or which section a file rule's fix edits.
#[derive(Debug, Clone)]
pub(crate) struct Place {
    pub(crate) kind: SectionKind,
    /// The section name as the pack writes it (for sections the file lacks).
    pub(crate) name: String,
}

/// A rule's fix.
#[derive(Debug)]
pub(crate) struct FixRule {
    /// For file rules: the section to edit.
    pub(crate) section: Option<Place>,
    pub(crate) key: String,
    pub(crate) value: Compiled,
    pub(crate) changes_meaning: bool,
}

/// A compiled rule.
#[derive(Debug)]
pub(crate) struct Rule {
    pub(crate) id: String,
    pub(crate) description: String,
    pub(crate) severity: Severity,
    pub(crate) tags: Vec<String>,
    pub(crate) select: Select,
    pub(crate) include_generated: bool,
    pub(crate) filter: Option<Compiled>,
    pub(crate) assert: Assertion,
    pub(crate) message: Option<Template>,
    pub(crate) help: Option<Template>,
    /// The key findings point at.
    pub(crate) key: Option<String>,
    /// For file rules: the section findings point at.
    pub(crate) section: Option<Place>,
    pub(crate) params: Vec<Param>,
    /// `params` as one CEL map.
    pub(crate) params_value: Value,
    pub(crate) lets: Vec<(String, Compiled)>,
    pub(crate) fix: Option<FixRule>,
    pub(crate) spec: Option<String>,
    pub(crate) explanation: Option<String>,
}

/// The parts of a rule pack before compiling.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PackFile {
    pack: Spanned<PackHeader>,
    #[serde(default)]
    rule: Vec<Spanned<RuleSpec>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PackHeader {
    name: Spanned<String>,
    #[serde(default)]
    description: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RuleSpec {
    id: Spanned<String>,
    description: Spanned<String>,
    severity: Spanned<String>,
    #[serde(default)]
    tags: Vec<Spanned<String>>,
    select: Spanned<String>,
    #[serde(default)]
    include_generated: bool,
    #[serde(default, rename = "where")]
    filter: Option<Spanned<String>>,
    assert: Spanned<toml::Value>,
    #[serde(default)]
    message: Option<Spanned<String>>,
    #[serde(default)]
    help: Option<Spanned<String>>,
    #[serde(default)]
    key: Option<Spanned<String>>,
    #[serde(default)]
    section: Option<Spanned<String>>,
    #[serde(default)]
    params: BTreeMap<String, Spanned<ParamSpec>>,
    #[serde(default, rename = "let")]
    lets: BTreeMap<String, Spanned<String>>,
    #[serde(default)]
    fix: Option<Spanned<FixSpec>>,
    #[serde(default)]
    spec: Option<String>,
    #[serde(default)]
    explanation: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ParamSpec {
    #[serde(rename = "type")]
    ty: Spanned<String>,
    value: Spanned<toml::Value>,
    #[serde(default)]
    description: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FixSpec {
    #[serde(default)]
    section: Option<Spanned<String>>,
    #[serde(default)]
    key: Option<Spanned<String>>,
    value: Spanned<String>,
    changes_meaning: bool,
}

/// A parsed pack before it is wrapped in the public type.
#[derive(Debug)]
pub(crate) struct Parsed {
    pub(crate) name: String,
    pub(crate) description: String,
    pub(crate) rules: Vec<Rule>,
    pub(crate) compiler: Compiler,
}

pub(crate) fn parse(text: &str, origin: &str) -> Result<Parsed, PackError> {
    let at = Locator { text, origin };
    let file: PackFile = toml::from_str(text).map_err(|e| {
        let offset = e.span().map_or(0, |s| s.start);
        at.error(
            offset,
            None,
            PackErrorKind::Toml,
            e.message().trim_end(),
            "a pack is a [pack] table with `name` and [[rule]] tables; see the canopener-rules README",
        )
    })?;
    let pack_start = file.pack.span().start;
    let header = file.pack.into_inner();
    let name = header.name.into_inner();
    if name.trim().is_empty() {
        return Err(at.error(
            pack_start,
            None,
            PackErrorKind::Toml,
            "the pack's `name` is empty",
            "give the pack a short name, e.g. name = \"plant-policy\"",
        ));
    }
    let mut compiler = Compiler::new();
    let mut rules = Vec::new();
    let mut seen: HashMap<String, usize> = HashMap::new();
    for spec in file.rule {
        let span = spec.span();
        let rule = compile_rule(&at, &mut compiler, spec.into_inner(), &span)?;
        if let Some(&first) = seen.get(&rule.id.to_ascii_lowercase()) {
            let (line, _) = at.line_column(first);
            return Err(at.error(
                span.start,
                Some(&rule.id),
                PackErrorKind::DuplicateId,
                format!("the id is already used by the rule on line {line}"),
                "ids are the codes findings are reported under: give every rule its own id",
            ));
        }
        seen.insert(rule.id.to_ascii_lowercase(), span.start);
        rules.push(rule);
    }
    Ok(Parsed {
        name,
        description: header.description.unwrap_or_default(),
        rules,
        compiler,
    })
}

fn compile_rule(
    at: &Locator<'_>,
    compiler: &mut Compiler,
    spec: RuleSpec,
    span: &Range<usize>,
) -> Result<Rule, PackError> {
    let id = spec.id.get_ref().trim().to_owned();
    check_id(at, &spec.id)?;
    let rid = Some(id.as_str());
    let err = |offset: usize, kind: PackErrorKind, message: String, help: &str| {
        at.error(offset, rid, kind, message, help)
    };

    let severity = match spec.severity.get_ref().as_str() {
        "error" => Severity::Error,
        "warning" => Severity::Warning,
        "info" => Severity::Info,
        other => {
            return Err(err(
                at.string_start(&spec.severity.span(), other),
                PackErrorKind::Severity,
                format!("unknown severity `{other}`"),
                "write severity = \"error\", \"warning\" or \"info\"",
            ));
        }
    };
    let select = match spec.select.get_ref().as_str() {
        "file" => Select::File,
        "objects" => Select::Objects,
        "subobjects" => Select::SubObjects,
        "entries" => Select::Entries,
        other => {
            return Err(err(
                at.string_start(&spec.select.span(), other),
                PackErrorKind::Select,
                format!("unknown select `{other}`"),
                "select one of \"file\" (once per file), \"objects\", \"subobjects\" or \"entries\" \
                 (objects and sub-objects)",
            ));
        }
    };
    if spec.description.get_ref().trim().is_empty() {
        return Err(err(
            spec.description.span().start,
            PackErrorKind::Toml,
            "the description is empty".to_owned(),
            "say in one line what the rule requires; it is the title `eds rules list` shows",
        ));
    }

    let mut params = Vec::new();
    for (name, p) in spec.params {
        params.push(compile_param(at, rid, &name, p)?);
    }
    let param_names: Vec<String> = params.iter().map(|p| p.name.clone()).collect();
    let let_names: Vec<String> = spec.lets.keys().cloned().collect();
    for name in &let_names {
        if ["item", "eds", "params"].contains(&name.as_str()) {
            let offset = spec.lets.get(name).map_or(span.start, |s| s.span().start);
            return Err(err(
                offset,
                PackErrorKind::UnknownName,
                format!("the let binding `{name}` hides the variable of that name"),
                "choose another name",
            ));
        }
    }
    let item_scope = Scope {
        item: select != Select::File,
        no_item_because: "a rule with select = \"file\" is evaluated once per file",
        params: &param_names,
        lets: &let_names,
    };
    let let_scope = Scope {
        item: false,
        no_item_because: "`let` bindings are evaluated once per file, before any item",
        params: &param_names,
        lets: &[],
    };
    let compile = |compiler: &mut Compiler, what: &str, source: &Spanned<String>, scope: Scope<'_>| {
        compile_expr(at, rid, compiler, what, source, scope)
    };

    let mut lets = Vec::new();
    for (name, source) in &spec.lets {
        lets.push((
            name.clone(),
            compile(compiler, &format!("let.{name}"), source, let_scope)?,
        ));
    }
    let filter = match &spec.filter {
        Some(f) => Some(compile(compiler, "where", f, item_scope)?),
        None => None,
    };
    let assert = compile_assertion(at, rid, compiler, &spec.assert, "assert", item_scope)?;
    let message = match &spec.message {
        Some(m) => Some(compile_template(at, rid, compiler, "message", m, item_scope)?),
        None => None,
    };
    let help = match &spec.help {
        Some(h) => Some(compile_template(at, rid, compiler, "help", h, item_scope)?),
        None => None,
    };

    let section = match &spec.section {
        Some(s) if select != Select::File => {
            return Err(err(
                s.span().start,
                PackErrorKind::Fix,
                "`section` is only for select = \"file\" rules".to_owned(),
                "findings of object rules point at the item's own section; remove `section`",
            ));
        }
        Some(s) => Some(place(at, rid, s)?),
        None => None,
    };
    let key = spec.key.as_ref().map(|k| k.get_ref().trim().to_owned());
    let fix = match spec.fix {
        Some(f) => Some(compile_fix(
            at,
            rid,
            compiler,
            f,
            section.as_ref(),
            key.as_deref(),
            item_scope,
        )?),
        None => None,
    };

    let mut params_map: HashMap<Key, Value> = HashMap::new();
    for p in &params {
        params_map.insert(Key::from(p.name.as_str()), p.value.clone());
    }

    Ok(Rule {
        id,
        description: spec.description.into_inner().trim().to_owned(),
        severity,
        tags: spec.tags.into_iter().map(Spanned::into_inner).collect(),
        select,
        include_generated: spec.include_generated,
        filter,
        assert,
        message,
        help,
        key,
        section,
        params,
        params_value: Value::Map(Map {
            map: Arc::new(params_map),
        }),
        lets,
        fix,
        spec: spec.spec,
        explanation: spec.explanation,
    })
}

/// Compiles one expression written as a TOML string, locating refusals in the pack.
fn compile_expr(
    at: &Locator<'_>,
    rule: Option<&str>,
    compiler: &mut Compiler,
    what: &str,
    source: &Spanned<String>,
    scope: Scope<'_>,
) -> Result<Compiled, PackError> {
    let span = source.span();
    let start = (at.locate(&span, source.get_ref()), span.start);
    compiler
        .compile(source.get_ref(), scope)
        .map_err(|r| refusal_error(at, rule, what, source.get_ref(), start, r))
}

/// Compiles `[rule.fix]`: a file rule's fix edits a named section (its own or the rule's), an item
/// rule's fix the item's section; the key defaults to the rule's `key`.
fn compile_fix(
    at: &Locator<'_>,
    rule: Option<&str>,
    compiler: &mut Compiler,
    spec: Spanned<FixSpec>,
    rule_section: Option<&Place>,
    rule_key: Option<&str>,
    scope: Scope<'_>,
) -> Result<FixRule, PackError> {
    let start = spec.span().start;
    let f = spec.into_inner();
    let err =
        |offset: usize, message: &str, help: &str| at.error(offset, rule, PackErrorKind::Fix, message, help);
    let section = match (&f.section, scope.item) {
        (Some(s), false) => Some(place(at, rule, s)?),
        (Some(s), true) => {
            return Err(err(
                s.span().start,
                "a fix of an object rule edits the item's own section",
                "remove `section` from [rule.fix]",
            ));
        }
        (None, false) => match rule_section {
            Some(s) => Some(s.clone()),
            None => {
                return Err(err(
                    start,
                    "a fix of a file rule needs the section it edits",
                    "add section = \"DeviceInfo\" (or another section) to [rule.fix] or to the rule",
                ));
            }
        },
        (None, true) => None,
    };
    let key = f
        .key
        .as_ref()
        .map(|k| k.get_ref().trim())
        .or(rule_key)
        .filter(|k| !k.is_empty() && !k.contains(['=', '[', ']', '\n']))
        .ok_or_else(|| {
            err(
                f.key.as_ref().map_or(start, |k| k.span().start),
                "the fix needs the key it sets",
                "add key = \"ParameterName\" (or another key) to [rule.fix] or to the rule",
            )
        })?
        .to_owned();
    let value = compile_expr(at, rule, compiler, "fix.value", &f.value, scope)?;
    Ok(FixRule {
        section,
        key,
        value,
        changes_meaning: f.changes_meaning,
    })
}

/// Rule ids are namespaced (`team/rule`) so they never collide with built-in codes.
fn check_id(at: &Locator<'_>, id: &Spanned<String>) -> Result<(), PackError> {
    let text = id.get_ref().trim();
    let segment_ok = |s: &str| {
        !s.is_empty()
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'))
            && s.chars().next().is_some_and(|c| c.is_ascii_alphanumeric())
    };
    let segments: Vec<&str> = text.split('/').collect();
    if segments.len() >= 2 && segments.iter().all(|s| segment_ok(s)) {
        return Ok(());
    }
    Err(at.error(
        at.string_start(&id.span(), id.get_ref()),
        Some(text),
        PackErrorKind::InvalidId,
        "a rule id is a namespace and a name separated by `/`, of letters, digits, `-`, `_` and `.`",
        "write e.g. id = \"plant/no-blank-names\"; the namespace keeps user codes apart from built-in ones",
    ))
}

fn place(at: &Locator<'_>, rule: Option<&str>, s: &Spanned<String>) -> Result<Place, PackError> {
    let name = s
        .get_ref()
        .trim()
        .trim_start_matches('[')
        .trim_end_matches(']')
        .trim();
    let kind = classify(name);
    if matches!(kind, SectionKind::Unknown) || name.is_empty() {
        return Err(at.error(
            at.string_start(&s.span(), s.get_ref()),
            rule,
            PackErrorKind::Fix,
            format!("`{name}` is not a CiA 306 section name"),
            "name a section such as \"DeviceInfo\", \"FileInfo\", \"1018\" or \"1018sub1\"",
        ));
    }
    Ok(Place {
        kind,
        name: name.to_owned(),
    })
}

fn compile_param(
    at: &Locator<'_>,
    rule: Option<&str>,
    name: &str,
    p: Spanned<ParamSpec>,
) -> Result<Param, PackError> {
    let span = p.span();
    let p = p.into_inner();
    let valid_name = name
        .chars()
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !valid_name {
        return Err(at.error(
            span.start,
            rule,
            PackErrorKind::Parameter,
            format!("`{name}` cannot be a parameter name"),
            "parameter names are identifiers (letters, digits, `_`) so expressions can write params.name",
        ));
    }
    let type_text = p.ty.get_ref();
    let Some(ty) = ParamType::parse(type_text) else {
        return Err(at.error(
            at.string_start(&p.ty.span(), type_text),
            rule,
            PackErrorKind::Parameter,
            format!("parameter `{name}` has the unknown type `{type_text}`"),
            format!("use one of {}", ParamType::NAMES),
        ));
    };
    let raw = p.value.get_ref();
    let wrong = |detail: String| {
        at.error(
            p.value.span().start,
            rule,
            PackErrorKind::Parameter,
            format!("parameter `{name}` is declared `{type_text}` but {detail}"),
            "make the value match the type, or change the type",
        )
    };
    let value = match ty {
        ParamType::Int => ScalarType::Int.convert(raw),
        ParamType::Double => ScalarType::Double.convert(raw),
        ParamType::Bool => ScalarType::Bool.convert(raw),
        ParamType::String => ScalarType::String.convert(raw),
        ParamType::List(element) => {
            let toml::Value::Array(items) = raw else {
                return Err(wrong(format!("its value is a {}", raw.type_str())));
            };
            let mut out = Vec::new();
            for (i, item) in items.iter().enumerate() {
                let Some(v) = element.convert(item) else {
                    return Err(wrong(format!(
                        "element {} is a {} (expected {})",
                        i + 1,
                        item.type_str(),
                        element.name()
                    )));
                };
                out.push(v);
            }
            Some(Value::List(Arc::new(out)))
        }
    };
    let value = value.ok_or_else(|| wrong(format!("its value is a {}", raw.type_str())))?;
    Ok(Param {
        name: name.to_owned(),
        value,
        type_name: type_text.trim().to_owned(),
        description: p.description,
    })
}

/// `start` is where the expression's text begins in the pack, when it is written without escapes
/// (then a position inside it can be pointed at); `fallback` is where its value begins.
fn refusal_error(
    at: &Locator<'_>,
    rule: Option<&str>,
    what: &str,
    source: &str,
    (start, fallback): (Option<usize>, usize),
    r: Refusal,
) -> PackError {
    let offset = match (start, r.position) {
        (Some(start), Some(pos)) => at.offset_in(start, source, pos),
        (Some(start), None) => start,
        (None, _) => fallback,
    };
    let kind = if r.syntax {
        PackErrorKind::CelSyntax
    } else {
        PackErrorKind::UnknownName
    };
    let message = if r.syntax {
        format!("in {what}: {}", r.message)
    } else {
        format!("in {what} `{}`: {}", one_line(source), r.message)
    };
    at.error(offset, rule, kind, message, r.help)
}

fn compile_assertion(
    at: &Locator<'_>,
    rule: Option<&str>,
    compiler: &mut Compiler,
    value: &Spanned<toml::Value>,
    path: &str,
    scope: Scope<'_>,
) -> Result<Assertion, PackError> {
    // Nested values carry no spans of their own: locate each one by its text inside the outer span.
    let span = value.span();
    compile_assertion_value(at, rule, compiler, value.get_ref(), &span, path, scope)
}

fn compile_assertion_value(
    at: &Locator<'_>,
    rule: Option<&str>,
    compiler: &mut Compiler,
    value: &toml::Value,
    span: &Range<usize>,
    path: &str,
    scope: Scope<'_>,
) -> Result<Assertion, PackError> {
    let malformed = |message: String| {
        at.error(
            span.start,
            rule,
            PackErrorKind::Assertion,
            message,
            "an assertion is a CEL string, or a table with exactly one of all = [...], any = [...], \
             not = ..., whose members are assertions again",
        )
    };
    match value {
        toml::Value::String(source) => {
            let found = at
                .locate(span, source)
                .or_else(|| at.locate_after(span.start, source));
            let start = (found, span.start);
            compiler
                .compile(source, scope)
                .map(Assertion::Expr)
                .map_err(|r| refusal_error(at, rule, path, source, start, r))
        }
        toml::Value::Table(table) => {
            let mut entries = table.iter();
            let (Some((key, inner)), None) = (entries.next(), entries.next()) else {
                let keys: Vec<&str> = table.keys().map(String::as_str).collect();
                return Err(malformed(format!(
                    "{path} has {} keys ({}); it needs exactly one of all, any, not",
                    keys.len(),
                    keys.join(", ")
                )));
            };
            match key.as_str() {
                "all" | "any" => {
                    let toml::Value::Array(items) = inner else {
                        return Err(malformed(format!("{path}.{key} must be an array of assertions")));
                    };
                    if items.is_empty() {
                        return Err(malformed(format!("{path}.{key} is empty")));
                    }
                    let mut out = Vec::new();
                    for (i, item) in items.iter().enumerate() {
                        let inner_path = format!("{path}.{key}[{i}]");
                        out.push(compile_assertion_value(
                            at,
                            rule,
                            compiler,
                            item,
                            span,
                            &inner_path,
                            scope,
                        )?);
                    }
                    Ok(if key == "all" {
                        Assertion::All(out)
                    } else {
                        Assertion::Any(out)
                    })
                }
                "not" => Ok(Assertion::Not(Box::new(compile_assertion_value(
                    at,
                    rule,
                    compiler,
                    inner,
                    span,
                    &format!("{path}.not"),
                    scope,
                )?))),
                other => Err(malformed(format!("{path} has the unknown key `{other}`"))),
            }
        }
        other => Err(malformed(format!("{path} is a {}", other.type_str()))),
    }
}

fn compile_template(
    at: &Locator<'_>,
    rule: Option<&str>,
    compiler: &mut Compiler,
    what: &str,
    text: &Spanned<String>,
    scope: Scope<'_>,
) -> Result<Template, PackError> {
    let span = text.span();
    let start = at.locate(&span, text.get_ref());
    let pieces = crate::template::split(text.get_ref()).map_err(|(offset, message)| {
        at.error(
            start.map_or(span.start, |s| s + offset),
            rule,
            PackErrorKind::Template,
            format!("in {what}: {message}"),
            "write {expression} to insert a value, {{ and }} for literal braces",
        )
    })?;
    let mut parts = Vec::new();
    for piece in pieces {
        match piece {
            crate::template::Piece::Text(t) => parts.push(Part::Text(t)),
            crate::template::Piece::Expr { offset, source } => {
                let expr_start = (start.map(|s| s + offset), span.start);
                let compiled = compiler
                    .compile(&source, scope)
                    .map_err(|r| refusal_error(at, rule, what, &source, expr_start, r))?;
                parts.push(Part::Expr(compiled));
            }
        }
    }
    Ok(Template { parts })
}

//! Compiling CEL expressions once, when a pack is parsed, and refusing names that cannot exist.
//!
//! CEL itself only finds an unknown variable, field or function when it evaluates one, which for a
//! rule means silently on every file. Walking the parsed expression against what rules can see
//! turns a typo into a [`crate::PackError`] with its line and column instead.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use cel::common::ast::{EntryExpr, Expr};
use cel::parser::Expression;
use cel::{Env, ExecutionError, Program};

use crate::functions::{self, FileIndex};
use crate::items::{EDS_FIELDS, ITEM_FIELDS};

/// A compiled expression and the text it came from.
#[derive(Debug)]
pub(crate) struct Compiled {
    pub(crate) source: String,
    pub(crate) program: Program,
}

/// What an expression may refer to.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Scope<'a> {
    /// Whether `item` exists (not in file rules and `let` bindings).
    pub(crate) item: bool,
    /// Why `item` does not exist, for the error message.
    pub(crate) no_item_because: &'a str,
    pub(crate) params: &'a [String],
    pub(crate) lets: &'a [String],
}

/// Why an expression was refused: where in it (1-based line and column, when known) and what.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Refusal {
    pub(crate) position: Option<(isize, isize)>,
    pub(crate) syntax: bool,
    pub(crate) message: String,
    pub(crate) help: String,
}

/// Compiles expressions against one environment and remembers which function names exist.
pub(crate) struct Compiler {
    pub(crate) env: Arc<Env>,
    probe: cel::Context<'static, 'static>,
    known_functions: HashMap<String, bool>,
}

impl std::fmt::Debug for Compiler {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Compiler").finish_non_exhaustive()
    }
}

/// Macros CEL expands while parsing; a call left with their name was written with the wrong
/// arguments.
const MACROS: &[(&str, &str)] = &[
    ("has", "has(x.field)"),
    ("all", "list.all(x, predicate)"),
    ("exists", "list.exists(x, predicate)"),
    ("exists_one", "list.exists_one(x, predicate)"),
    (
        "map",
        "list.map(x, expression) or list.map(x, filter, expression)",
    ),
    ("filter", "list.filter(x, predicate)"),
    ("sortBy", "list.sortBy(x, key)"),
];

/// Names that evaluate to CEL types (`type(x) == int`).
const TYPE_NAMES: &[&str] = &[
    "int",
    "uint",
    "double",
    "bool",
    "string",
    "bytes",
    "list",
    "map",
    "null_type",
    "type",
    "dyn",
];

/// Standard and extension functions, only to suggest a spelling (existence is probed).
const SUGGESTIONS: &[&str] = &[
    "size",
    "contains",
    "startsWith",
    "endsWith",
    "matches",
    "int",
    "uint",
    "double",
    "string",
    "bool",
    "type",
    "dyn",
    "lowerAscii",
    "upperAscii",
    "trim",
    "split",
    "join",
    "indexOf",
    "lastIndexOf",
    "substring",
    "charAt",
    "format",
    "reverse",
    "distinct",
    "flatten",
    "slice",
    "sort",
];

impl Compiler {
    pub(crate) fn new() -> Self {
        let env = Arc::new(functions::environment());
        let mut probe = cel::Context::with_env(Arc::clone(&env));
        functions::install(&mut probe, &Arc::new(FileIndex::default()));
        Self {
            env,
            probe,
            known_functions: HashMap::new(),
        }
    }

    /// Parses `source` and checks every name in it against `scope`.
    pub(crate) fn compile(&mut self, source: &str, scope: Scope<'_>) -> Result<Compiled, Refusal> {
        let program = self.env.compile(source).map_err(|errors| {
            let first = errors.errors.first();
            Refusal {
                position: first.map(|e| e.pos),
                syntax: true,
                message: format!(
                    "CEL syntax error in `{}`: {}",
                    one_line(source),
                    first.map_or_else(|| errors.to_string(), |e| e.msg.clone())
                ),
                help: "see https://github.com/google/cel-spec/blob/master/doc/langdef.md for CEL's syntax; \
                       strings are quoted with ' or \""
                    .to_owned(),
            }
        })?;
        let mut walk = Walk {
            compiler: self,
            scope,
            program: &program,
            bound: Vec::new(),
        };
        walk.expr(program.expression())?;
        Ok(Compiled {
            source: source.to_owned(),
            program,
        })
    }

    /// Whether a function of this name (qualified like `math.bitAnd` or not) exists: calling it with
    /// no arguments tells an undeclared name from one whose overloads just do not fit.
    fn function_exists(&mut self, name: &str) -> bool {
        if let Some(&known) = self.known_functions.get(name) {
            return known;
        }
        let undeclared = |result: Result<cel::Value, ExecutionError>| {
            matches!(result, Err(ExecutionError::UndeclaredReference(_)))
        };
        let mut exists = false;
        let mut calls = vec![format!("{name}()")];
        if !name.contains('.') {
            calls.push(format!("(0).{name}()"));
        }
        for call in calls {
            if let Ok(program) = self.env.compile(&call)
                && !undeclared(program.execute(&self.probe))
            {
                exists = true;
            }
        }
        self.known_functions.insert(name.to_owned(), exists);
        exists
    }
}

struct Walk<'c, 's, 'p> {
    compiler: &'c mut Compiler,
    scope: Scope<'s>,
    program: &'p Program,
    /// Variables bound by comprehensions around the current node.
    bound: Vec<String>,
}

impl Walk<'_, '_, '_> {
    fn position(&self, id: u64) -> Option<(isize, isize)> {
        let info = self.program.source_info();
        let (start, _) = info.offset_for(id)?;
        let start = usize::try_from(start).ok()?;
        let mut line = 1isize;
        let mut column = 1isize;
        for c in info.source.chars().take(start) {
            if c == '\n' {
                line += 1;
                column = 1;
            } else {
                column += 1;
            }
        }
        Some((line, column))
    }

    fn refuse(&self, id: u64, message: String, help: String) -> Refusal {
        Refusal {
            position: self.position(id),
            syntax: false,
            message,
            help,
        }
    }

    fn is_bound(&self, name: &str) -> bool {
        self.bound.iter().any(|b| b == name)
    }

    fn expr(&mut self, e: &Expression) -> Result<(), Refusal> {
        match &e.expr {
            Expr::Unspecified | Expr::Literal(_) => Ok(()),
            Expr::Ident(name) => self.ident(e.id, name),
            Expr::Select(select) => {
                if let Expr::Ident(root) = &select.operand.expr
                    && !self.is_bound(root)
                {
                    self.ident(select.operand.id, root)?;
                    return self.field(e.id, root, &select.field);
                }
                self.expr(&select.operand)
            }
            Expr::Call(call) => {
                // Operators (`_&&_`, `!_`) and what macros expand to (`@in`, `math.@max`) are not
                // names a user wrote.
                let operator = call.func_name.starts_with('_')
                    || call.func_name.contains('@')
                    || call.func_name.ends_with('_');
                if !operator {
                    if let Some(target) = &call.target
                        && let Some(namespace) = self.namespace(target)
                    {
                        let qualified = format!("{namespace}.{}", call.func_name);
                        if self.compiler.function_exists(&qualified) {
                            return call.args.iter().try_for_each(|a| self.expr(a));
                        }
                    }
                    self.function(e.id, &call.func_name)?;
                }
                if let Some(target) = &call.target {
                    self.expr(target)?;
                }
                call.args.iter().try_for_each(|a| self.expr(a))
            }
            Expr::Comprehension(c) => {
                self.expr(&c.iter_range)?;
                self.expr(&c.accu_init)?;
                let depth = self.bound.len();
                self.bound.push(c.iter_var.clone());
                self.bound.extend(c.iter_var2.iter().cloned());
                self.bound.push(c.accu_var.clone());
                let inner = [&c.loop_cond, &c.loop_step, &c.result]
                    .into_iter()
                    .try_for_each(|x| self.expr(x));
                self.bound.truncate(depth);
                inner
            }
            Expr::List(list) => list.elements.iter().try_for_each(|x| self.expr(x)),
            Expr::Map(map) => map.entries.iter().try_for_each(|entry| match &entry.expr {
                EntryExpr::MapEntry(m) => {
                    self.expr(&m.key)?;
                    self.expr(&m.value)
                }
                EntryExpr::StructField(f) => self.expr(&f.value),
            }),
            Expr::Struct(s) => s.entries.iter().try_for_each(|entry| match &entry.expr {
                EntryExpr::MapEntry(m) => {
                    self.expr(&m.key)?;
                    self.expr(&m.value)
                }
                EntryExpr::StructField(f) => self.expr(&f.value),
            }),
        }
    }

    /// The dotted name a call target spells (`math` in `math.bitAnd(..)`), unless its root is a
    /// variable.
    fn namespace(&self, target: &Expression) -> Option<String> {
        match &target.expr {
            Expr::Ident(name) if !self.is_bound(name) && !self.is_variable(name) => Some(name.clone()),
            Expr::Select(s) if !s.test => Some(format!("{}.{}", self.namespace(&s.operand)?, s.field)),
            _ => None,
        }
    }

    fn is_variable(&self, name: &str) -> bool {
        (name == "item" && self.scope.item)
            || name == "eds"
            || name == "params"
            || self.scope.lets.iter().any(|l| l == name)
    }

    fn ident(&self, id: u64, name: &str) -> Result<(), Refusal> {
        if self.is_bound(name)
            || name.starts_with('@')
            || self.is_variable(name)
            || TYPE_NAMES.contains(&name)
        {
            return Ok(());
        }
        if name == "item" {
            return Err(self.refuse(
                id,
                format!("`item` does not exist here: {}", self.scope.no_item_because),
                "look items up with object(index), sub(index, sub) or eds.objects, or select objects, \
                 subobjects or entries to get one `item` at a time"
                    .to_owned(),
            ));
        }
        let mut known: Vec<&str> = vec!["eds", "params"];
        if self.scope.item {
            known.push("item");
        }
        known.extend(self.scope.lets.iter().map(String::as_str));
        Err(self.refuse(
            id,
            format!("unknown variable `{name}`"),
            format!(
                "{}rules can use {}",
                suggest(name, &known).map_or_else(String::new, |s| format!("did you mean `{s}`? ")),
                known
                    .iter()
                    .map(|k| format!("`{k}`"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ))
    }

    fn field(&self, id: u64, root: &str, field: &str) -> Result<(), Refusal> {
        let fields: Vec<&str> = match root {
            "item" => ITEM_FIELDS.to_vec(),
            "eds" => EDS_FIELDS.to_vec(),
            "params" => self.scope.params.iter().map(String::as_str).collect(),
            _ => return Ok(()),
        };
        if fields.contains(&field) {
            return Ok(());
        }
        let what = if root == "params" { "parameter" } else { "field" };
        let hint = suggest(field, &fields).map_or_else(String::new, |s| format!("did you mean `{s}`? "));
        let listing = if fields.is_empty() {
            "the rule declares no parameters: add them under [rule.params]".to_owned()
        } else {
            format!(
                "`{root}` has {}",
                fields
                    .iter()
                    .map(|f| format!("`{f}`"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        };
        Err(self.refuse(
            id,
            format!("unknown {what} `{root}.{field}`"),
            format!("{hint}{listing}"),
        ))
    }

    fn function(&mut self, id: u64, name: &str) -> Result<(), Refusal> {
        if let Some((_, usage)) = MACROS.iter().find(|(m, _)| *m == name) {
            return Err(self.refuse(
                id,
                format!("`{name}` is a macro and was called with the wrong arguments"),
                format!("write {usage}"),
            ));
        }
        if self.compiler.function_exists(name) {
            return Ok(());
        }
        let mut candidates: Vec<&str> = SUGGESTIONS.to_vec();
        candidates.extend(functions::FUNCTIONS.iter().map(|(n, _)| *n));
        Err(self.refuse(
            id,
            format!("unknown function `{name}`"),
            match suggest(name, &candidates) {
                Some(s) => format!("did you mean `{s}`?"),
                None => "see the function list in the canopener-rules README".to_owned(),
            },
        ))
    }
}

/// The expression on one line, for messages.
pub(crate) fn one_line(source: &str) -> String {
    source.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The closest candidate within a small edit distance (case differences count as half).
fn suggest<'a>(name: &str, candidates: &[&'a str]) -> Option<&'a str> {
    let unique: HashSet<&&str> = candidates.iter().collect();
    unique
        .into_iter()
        .map(|c| (distance(name, c), *c))
        .filter(|(d, c)| *d <= 2 || c.eq_ignore_ascii_case(name))
        .min()
        .map(|(_, c)| c)
}

fn distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.iter().enumerate() {
        let mut previous = row.first().copied().unwrap_or(0);
        if let Some(first) = row.first_mut() {
            *first = i + 1;
        }
        for (j, cb) in b.iter().enumerate() {
            let cost = usize::from(!ca.eq_ignore_ascii_case(cb));
            let above = row.get(j + 1).copied().unwrap_or(usize::MAX);
            let left = row.get(j).copied().unwrap_or(usize::MAX);
            let next = (previous + cost)
                .min(above.saturating_add(1))
                .min(left.saturating_add(1));
            previous = above;
            if let Some(cell) = row.get_mut(j + 1) {
                *cell = next;
            }
        }
    }
    row.last().copied().unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ITEM_SCOPE: Scope<'static> = Scope {
        item: true,
        no_item_because: "",
        params: &[],
        lets: &[],
    };

    fn refusal(source: &str, scope: Scope<'_>) -> Refusal {
        match Compiler::new().compile(source, scope) {
            Ok(_) => panic!("`{source}` compiled"),
            Err(r) => r,
        }
    }

    #[test]
    fn valid_expressions_compile() {
        let params = ["required".to_owned()];
        let lets = ["names".to_owned()];
        let scope = Scope {
            params: &params,
            lets: &lets,
            ..ITEM_SCOPE
        };
        let mut compiler = Compiler::new();
        for source in [
            "!item.name.contains(' ')",
            "params.required.all(b, has(eds.device_info.BaudRate_125) || b > 0)",
            "count(names, item.name) == 1 && item.keys.exists(k, k.startsWith('Param'))",
            "math.bitAnd(item.value, 0xFF) == 0 && type(item.value) == int",
            "{'a': item.index}.a > 0 && [item.sub].size() == 1",
            "eds.objects.filter(o, o.sub == null).map(o, o.name).unique()",
            "item.name.lowerAscii().replace(' ', '_') == replace(item.name, ' ', '_')",
            "has(item.keys.Unit)",
        ] {
            if let Err(e) = compiler.compile(source, scope) {
                panic!("`{source}`: {e:?}");
            }
        }
    }

    #[test]
    fn syntax_errors_have_positions() {
        let r = refusal("item.name ==", ITEM_SCOPE);
        assert!(r.syntax);
        assert_eq!(r.position, Some((1, 13)));
        assert!(
            r.message.starts_with("CEL syntax error in `item.name ==`"),
            "{}",
            r.message
        );
    }

    #[test]
    fn unknown_names_are_refused_with_a_suggestion() {
        let r = refusal("itme.name == ''", ITEM_SCOPE);
        assert_eq!(r.message, "unknown variable `itme`");
        assert!(r.help.starts_with("did you mean `item`?"), "{}", r.help);
        assert_eq!(r.position, Some((1, 1)));

        let r = refusal("item.nmae == ''", ITEM_SCOPE);
        assert_eq!(r.message, "unknown field `item.nmae`");
        assert!(r.help.starts_with("did you mean `name`?"), "{}", r.help);
        assert_eq!(r.position, Some((1, 5)));

        let r = refusal("eds.device.x", ITEM_SCOPE);
        assert_eq!(r.message, "unknown field `eds.device`");

        let r = refusal("item.name.startswith('a')", ITEM_SCOPE);
        assert_eq!(r.message, "unknown function `startswith`");
        assert_eq!(r.help, "did you mean `startsWith`?");

        let r = refusal("duplicate([1])", ITEM_SCOPE);
        assert_eq!(r.help, "did you mean `duplicates`?");

        let r = refusal("params.baud == 1", ITEM_SCOPE);
        assert_eq!(r.message, "unknown parameter `params.baud`");
        assert!(r.help.contains("[rule.params]"), "{}", r.help);

        let r = refusal("[1].all(x)", ITEM_SCOPE);
        assert!(r.message.contains("macro"), "{}", r.message);
    }

    #[test]
    fn item_is_refused_where_there_is_none() {
        let scope = Scope {
            item: false,
            no_item_because: "a file rule has no item",
            ..ITEM_SCOPE
        };
        let r = refusal("item.index > 0", scope);
        assert_eq!(r.message, "`item` does not exist here: a file rule has no item");
    }

    #[test]
    fn comprehension_variables_shadow_and_end() {
        let mut compiler = Compiler::new();
        assert!(
            compiler
                .compile(
                    "[1].exists(item, item > 0)",
                    Scope {
                        item: false,
                        ..ITEM_SCOPE
                    }
                )
                .is_ok()
        );
        assert!(
            compiler
                .compile("[1].exists(o, o > 0) && o > 0", ITEM_SCOPE)
                .is_err()
        );
        assert!(
            compiler
                .compile("eds.objects.exists(o, o.whatever)", ITEM_SCOPE)
                .is_ok()
        );
    }

    #[test]
    fn every_library_function_exists() {
        let mut compiler = Compiler::new();
        for (name, _) in functions::FUNCTIONS {
            assert!(compiler.function_exists(name), "{name}");
        }
        for name in SUGGESTIONS {
            assert!(compiler.function_exists(name), "{name}");
        }
        // Names the README promises, in calls that must pass the name checks.
        for call in [
            "math.greatest(1, 2) == 2 && math.least(1, 2) == 1",
            "math.bitAnd(6, 3) == 2 && math.bitShiftLeft(1, 3) == 8 && math.abs(-1) == 1",
            "lists.range(3) == [0, 1, 2] && [1, 1].distinct() == [1] && [[1]].flatten() == [1]",
            "[1, 2].exists_one(x, x > 1) && [2, 1].sortBy(x, x) == [1, 2] && [1, 2].slice(0, 1) == [1]",
            "'abc'.charAt(0) == 'a' && 'x%sx'.format(['y']) == 'xyx' && 'ab'.reverse() == 'ba'",
            "' a '.trim() == 'a' && 'ABC'.lowerAscii().upperAscii() == 'ABC' && ['a'].join('') == 'a'",
            "'abc'.indexOf('b') == 1 && 'abab'.lastIndexOf('b') == 3 && 'abc'.substring(1) == 'bc'",
            "size('a') == 1 && 'a'.endsWith('a') && int('1') == 1 && uint(1) == 1u && double(1) == 1.0",
            "bool('true') && bytes('a') == b'a' && type(1) == int && dyn(1) == 1 && string(1) == '1'",
        ] {
            if let Err(e) = compiler.compile(call, ITEM_SCOPE) {
                panic!("`{call}`: {e:?}");
            }
            let program = compiler.env.compile(call).map_err(|e| e.to_string());
            let value = program.and_then(|p| p.execute(&compiler.probe).map_err(|e| e.to_string()));
            assert_eq!(value, Ok(cel::Value::Bool(true)), "{call}");
        }
        assert!(!compiler.function_exists("nonesuch"));
        assert!(!compiler.function_exists("math.nonesuch"));
    }

    #[test]
    fn edit_distance() {
        assert_eq!(distance("kitten", "sitting"), 3);
        assert_eq!(distance("", "abc"), 3);
        assert_eq!(distance("startswith", "startsWith"), 0);
        assert_eq!(suggest("nmae", &["name", "index"]), Some("name"));
        assert_eq!(suggest("zzzz", &["name"]), None);
    }
}

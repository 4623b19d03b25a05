//! From model files to a [`Model`]: names resolved, parameters evaluated, static checks run.
//!
//! Several files compose in parallel, each file one component (see [`crate::compose`] for the
//! semantics): gates and hidden events are shared by name (a gate declared twice must be declared
//! the same way); parameters, constants, `let`s and clocks belong to their file, which also sees
//! the definitions of the files it `use`s (its own win); processes are global by name, so a
//! component may read another's variables and locations (`nmt@Stopped`, `hb.period`) but only
//! write its own.

use std::collections::{BTreeMap, BTreeSet};

use canopener_eds::diag::Span;
use canopener_eds::model::Eds;
use sha2::{Digest, Sha256};

use crate::diagnostics::{MbtCode, MbtDiagnostic, diag, has_errors};
use crate::expr::{BinOp, CExpr, UnOp};
use crate::label::Label;
use crate::model::{CPattern, Field, Gate, Kind, Location, Model, ModelFile, Process, Transition, Var};
use crate::purpose::{LabelPattern, Purpose, PurposeTransition, ValuePattern};
use crate::syntax::ast::*;
use crate::syntax::parser::parse;

/// Widest range an input field may take values from; wider ones must be narrowed in the model.
pub const MAX_INPUT_CHOICES: i64 = 256;

/// One model text to compose.
#[derive(Debug, Clone)]
pub struct Source {
    /// A shipped model's name or a path: used in messages.
    pub origin: String,
    /// The text.
    pub text: String,
}

/// What a model is instantiated with.
#[derive(Debug, Clone, Default)]
pub struct Options<'a> {
    /// The node-ID under test (`$NODEID`).
    pub node_id: u8,
    /// The device description, for `od()`, `exists()` and `pdo_bytes()` in parameters.
    pub eds: Option<&'a Eds>,
    /// `--set NAME=VALUE` overrides of parameters.
    pub set: Vec<(String, i64)>,
}

/// The diagnostics of one source.
#[derive(Debug, Clone, PartialEq)]
pub struct SourceDiagnostics {
    /// The source's origin.
    pub origin: String,
    /// What was found in it.
    pub diagnostics: Vec<MbtDiagnostic>,
}

/// Compiles `sources` (and the shipped models they `use`, resolved with `shipped`) into one model.
/// Returns the model if no source has errors, and every diagnostic either way.
pub fn compile(
    sources: &[Source],
    options: &Options<'_>,
    shipped: &dyn Fn(&str) -> Option<String>,
) -> (Option<Model>, Vec<SourceDiagnostics>) {
    let mut files: Vec<(Source, File)> = Vec::new();
    let mut report = Vec::new();
    let mut pending: Vec<Source> = sources.to_vec();
    pending.reverse();
    // Each `use` loads a shipped model once, before the file that uses it.
    let mut loaded = BTreeSet::new();
    while let Some(source) = pending.pop() {
        if !loaded.insert(source.origin.clone()) {
            continue;
        }
        let (file, diagnostics) = parse(&source.text);
        let mut diagnostics = diagnostics;
        for used in &file.uses {
            match shipped(&used.text) {
                Some(text) if used.text != source.origin => {
                    pending.push(Source {
                        origin: used.text.clone(),
                        text,
                    });
                }
                _ => diagnostics.push(diag(
                    MbtCode::BadUse,
                    used.span,
                    format!("`use {}` names no shipped model (or the model itself)", used.text),
                )),
            }
        }
        report.push(SourceDiagnostics {
            origin: source.origin.clone(),
            diagnostics,
        });
        files.push((source, file));
    }
    // Which files each file sees the definitions of: itself, then what it uses, transitively.
    let mut visible: Vec<Vec<usize>> = Vec::new();
    for (i, (_, file)) in files.iter().enumerate() {
        let mut seen = vec![i];
        let mut work: Vec<usize> = vec![i];
        while let Some(f) = work.pop() {
            for used in files.get(f).into_iter().flat_map(|(_, file)| &file.uses) {
                if let Some(j) = files.iter().position(|(s, _)| s.origin == used.text)
                    && !seen.contains(&j)
                {
                    seen.push(j);
                    work.push(j);
                }
            }
        }
        let _ = file;
        visible.push(seen);
    }
    let mut compiler = Compiler::new(options, visible);
    // Every file's name first: a parameter is named after its file (`nmt.TOL`).
    for (source, file) in &files {
        compiler.model.files.push(ModelFile {
            name: file.name.as_ref().map_or_else(String::new, |n| n.text.clone()),
            title: file.title.clone().unwrap_or_default(),
            cites: file.cites.clone(),
            origin: source.origin.clone(),
        });
    }
    // Definitions next, each file's after those of the files it uses, so that a parameter may be
    // computed from a used model's (the files are loaded users first).
    for index in definition_order(&files) {
        let Some((_, file)) = files.get(index) else {
            continue;
        };
        compiler.file = index;
        compiler.declare_definitions(file);
    }
    for (index, (_, file)) in files.iter().enumerate() {
        compiler.file = index;
        compiler.declare(file);
    }
    for (index, (_, file)) in files.iter().enumerate() {
        compiler.file = index;
        compiler.define(file);
    }
    for (i, diagnostics) in compiler.diagnostics {
        if let Some(r) = report.get_mut(i) {
            r.diagnostics.extend(diagnostics);
        }
    }
    for r in &mut report {
        r.diagnostics.sort_by_key(|d| d.span);
    }
    if report.iter().any(|r| has_errors(&r.diagnostics)) {
        return (None, report);
    }
    let mut hasher = Sha256::new();
    for (source, _) in &files {
        hasher.update(source.origin.as_bytes());
        hasher.update([0]);
        hasher.update(source.text.as_bytes());
        hasher.update([0]);
    }
    for (name, value) in &compiler.model.params {
        hasher.update(format!("{name}={value};").as_bytes());
    }
    let mut model = compiler.model;
    model.components = (0..files.len())
        .map(|file| {
            let processes: Vec<usize> = model
                .processes
                .iter()
                .enumerate()
                .filter(|(_, p)| p.file == file)
                .map(|(p, _)| p)
                .collect();
            let transitions = model
                .processes
                .iter()
                .filter(|p| p.file == file)
                .flat_map(|p| p.transitions.iter().copied())
                .collect();
            crate::model::Component {
                file,
                gates: compiler.file_gates.get(&file).cloned().unwrap_or_default(),
                events: compiler.file_events.get(&file).cloned().unwrap_or_default(),
                resets: compiler.file_resets.get(&file).cloned().unwrap_or_default(),
                processes,
                transitions,
            }
        })
        .collect();
    model.hash = hasher.finalize().iter().map(|b| format!("{b:02x}")).collect();
    (Some(model), report)
}

/// The files in an order where each comes after the files it `use`s (depth first, in load order
/// otherwise).
fn definition_order(files: &[(Source, File)]) -> Vec<usize> {
    fn visit(index: usize, files: &[(Source, File)], done: &mut Vec<bool>, order: &mut Vec<usize>) {
        let Some((flag, (_, file))) = done.get_mut(index).zip(files.get(index)) else {
            return;
        };
        if std::mem::replace(flag, true) {
            return;
        }
        for used in &file.uses {
            if let Some(u) = files.iter().position(|(s, _)| s.origin == used.text) {
                visit(u, files, done, order);
            }
        }
        order.push(index);
    }
    let mut done = vec![false; files.len()];
    let mut order = Vec::with_capacity(files.len());
    for index in 0..files.len() {
        visit(index, files, &mut done, &mut order);
    }
    order
}

/// A name an expression can see.
#[derive(Clone)]
enum Binding {
    Value(i64),
    Let(Expr, usize),
}

struct Compiler<'a> {
    options: &'a Options<'a>,
    model: Model,
    file: usize,
    /// Per file, what compiling it found.
    diagnostics: BTreeMap<usize, Vec<MbtDiagnostic>>,
    /// Per file, its definitions by name (`NODEID` is in every file's).
    globals: Vec<BTreeMap<String, Binding>>,
    /// Per file, the files whose definitions it sees, its own first.
    visible: Vec<Vec<usize>>,
    /// Clocks by file and name.
    clock_index: BTreeMap<(usize, String), usize>,
    /// Per file, the gates it declares.
    file_gates: BTreeMap<usize, Vec<usize>>,
    /// Per file, the hidden events it declares.
    file_events: BTreeMap<usize, Vec<usize>>,
    /// Per file, its `reset` stimuli.
    file_resets: BTreeMap<usize, Vec<Label>>,
    quiescence_declared: bool,
}

/// Where an expression is compiled: which process it belongs to and which gate's fields it sees.
#[derive(Clone, Copy)]
struct Scope<'s> {
    process: Option<usize>,
    fields: Option<&'s [Field]>,
    depth: usize,
}

impl<'a> Compiler<'a> {
    fn new(options: &'a Options<'a>, visible: Vec<Vec<usize>>) -> Self {
        let mut base = BTreeMap::new();
        base.insert("NODEID".to_owned(), Binding::Value(i64::from(options.node_id)));
        let globals = vec![base; visible.len()];
        Compiler {
            options,
            model: Model {
                files: Vec::new(),
                params: vec![("NODEID".to_owned(), i64::from(options.node_id))],
                gates: Vec::new(),
                clocks: Vec::new(),
                events: Vec::new(),
                components: Vec::new(),
                processes: Vec::new(),
                transitions: Vec::new(),
                quiescence_us: 1_000_000,
                resets: Vec::new(),
                purposes: Vec::new(),
                initial: Vec::new(),
                hash: String::new(),
            },
            file: 0,
            diagnostics: BTreeMap::new(),
            globals,
            visible,
            clock_index: BTreeMap::new(),
            file_gates: BTreeMap::new(),
            file_events: BTreeMap::new(),
            file_resets: BTreeMap::new(),
            quiescence_declared: false,
        }
    }

    /// The clock called `name` that the current file sees: its own, else one of a file it uses.
    fn clock(&self, name: &str) -> Option<usize> {
        self.visible
            .get(self.file)
            .into_iter()
            .flatten()
            .find_map(|f| self.clock_index.get(&(*f, name.to_owned())).copied())
    }

    fn report(&mut self, d: MbtDiagnostic) {
        self.diagnostics.entry(self.file).or_default().push(d);
    }

    fn error(&mut self, code: MbtCode, span: Span, message: impl Into<String>) {
        self.report(diag(code, span, message));
    }

    /// First pass, before [`Compiler::declare`]: the `param`, `const` and `let` definitions of
    /// `file`.
    fn declare_definitions(&mut self, file: &File) {
        let global = Scope {
            process: None,
            fields: None,
            depth: 0,
        };
        for def in &file.definitions {
            if self
                .globals
                .get(self.file)
                .is_some_and(|g| g.contains_key(&def.name.text))
            {
                self.error(
                    MbtCode::Duplicate,
                    def.name.span,
                    format!("`{}` is defined twice", def.name.text),
                );
                continue;
            }
            let binding = match def.kind {
                DefKind::Let => Binding::Let(def.value.clone(), self.file),
                DefKind::Const | DefKind::Param => {
                    let set = self
                        .options
                        .set
                        .iter()
                        .find(|(n, _)| *n == def.name.text)
                        .map(|(_, v)| *v);
                    let value = match set {
                        Some(v) if def.kind == DefKind::Param => Some(v),
                        _ => self.constant(&def.value, global, def.fallback.as_ref()),
                    };
                    let Some(value) = value else { continue };
                    if def.kind == DefKind::Param {
                        // Parameters belong to their file: `nmt.TOL` and `sync.TOL` may differ.
                        let file = &self.model.file_at(self.file).name;
                        self.model
                            .params
                            .push((format!("{file}.{}", def.name.text), value));
                    }
                    Binding::Value(value)
                }
            };
            // One table per file was made with the compiler.
            if let Some(globals) = self.globals.get_mut(self.file) {
                globals.insert(def.name.text.clone(), binding);
            }
        }
    }

    /// First pass, after every file's definitions: gates, clocks and process skeletons (so
    /// processes can refer to each other whatever the order).
    fn declare(&mut self, file: &File) {
        let global = Scope {
            process: None,
            fields: None,
            depth: 0,
        };
        if let Some(q) = &file.quiescence
            && let Some(v) = self.constant(q, global, None)
        {
            // Composed models wait as long as the most patient of them.
            self.model.quiescence_us = if self.quiescence_declared {
                self.model.quiescence_us.max(v)
            } else {
                v
            };
            self.quiescence_declared = true;
        }
        for clock in &file.clocks {
            let key = (self.file, clock.text.clone());
            if !self.clock_index.contains_key(&key) {
                self.clock_index.insert(key, self.model.clocks.len());
                self.model.clocks.push(clock.text.clone());
            }
        }
        for decl in &file.gates {
            self.gate(decl, global);
        }
        for event in &file.events {
            let e = match self.model.events.iter().position(|e| *e == event.text) {
                Some(e) => e,
                None => {
                    self.model.events.push(event.text.clone());
                    self.model.events.len() - 1
                }
            };
            if self
                .file_events
                .get(&self.file)
                .is_some_and(|events| events.contains(&e))
            {
                self.error(
                    MbtCode::Duplicate,
                    event.span,
                    format!("the event `{}` is declared twice", event.text),
                );
            } else {
                self.file_events.entry(self.file).or_default().push(e);
            }
        }
        for decl in &file.processes {
            self.process_skeleton(decl, global);
        }
    }

    fn gate(&mut self, decl: &GateDecl, scope: Scope<'_>) {
        let Some(cob_id) = self.constant(&decl.cob_id, scope, None) else {
            return;
        };
        let Some(cob_id) = u16::try_from(cob_id).ok().filter(|id| *id <= 0x7FF) else {
            self.error(
                MbtCode::BadGate,
                decl.cob_id.span,
                format!("the COB-ID {cob_id:#X} is not an 11-bit CAN-ID"),
            );
            return;
        };
        let mut fields = Vec::new();
        let mut dlc = 0u32;
        for f in &decl.fields {
            let (size, opaque) = match &f.ty {
                FieldType::Unsigned(n) => (u32::from(*n), false),
                FieldType::Bytes(n) => match self.constant(n, scope, None) {
                    Some(n @ 1..=8) => (n as u32, true),
                    _ => {
                        self.error(MbtCode::BadGate, n.span, "bytes(N) takes N from 1 to 8");
                        return;
                    }
                },
            };
            dlc += size;
            fields.push(Field {
                name: f.name.text.clone(),
                size: size as u8,
                opaque,
            });
        }
        if dlc > 8 {
            self.error(
                MbtCode::BadGate,
                decl.name.span,
                format!(
                    "the gate `{}` has {dlc} data bytes; a CAN frame has at most 8",
                    decl.name.text
                ),
            );
            return;
        }
        let gate = Gate {
            name: decl.name.text.clone(),
            direction: decl.direction,
            cob_id,
            remote: decl.remote,
            fields,
            dlc: dlc as u8,
        };
        if let Some((existing, differs)) = self
            .model
            .gates
            .iter()
            .enumerate()
            .find(|(_, g)| g.name == gate.name)
            .map(|(existing, g)| (existing, *g != gate))
        {
            if differs {
                let message = format!(
                    "the gate `{}` is declared differently in another model",
                    gate.name
                );
                self.error(MbtCode::GateClash, decl.name.span, message);
            } else {
                let gates = self.file_gates.entry(self.file).or_default();
                if !gates.contains(&existing) {
                    gates.push(existing);
                }
            }
            return;
        }
        if let Some(other) = self.model.gates.iter().find(|g| {
            g.cob_id == gate.cob_id
                && g.direction == gate.direction
                && g.remote == gate.remote
                && g.dlc == gate.dlc
        }) && other.fields.len() != gate.fields.len()
        {
            let message = format!(
                "the gates `{}` and `{}` share COB-ID {:#05X} and length",
                gate.name, other.name, gate.cob_id
            );
            self.error(MbtCode::AmbiguousGates, decl.name.span, message);
        }
        self.file_gates
            .entry(self.file)
            .or_default()
            .push(self.model.gates.len());
        self.model.gates.push(gate);
    }

    fn process_skeleton(&mut self, decl: &ProcessDecl, scope: Scope<'_>) {
        if self.model.processes.iter().any(|p| p.name == decl.name.text) {
            self.error(
                MbtCode::Duplicate,
                decl.name.span,
                format!("the process `{}` is defined twice", decl.name.text),
            );
            return;
        }
        if decl.locations.is_empty() {
            self.error(
                MbtCode::NoLocations,
                decl.name.span,
                format!("the process `{}` has no `location`", decl.name.text),
            );
            return;
        }
        let location_slot = self.model.initial.len();
        self.model.initial.push(0);
        let mut locations: Vec<Location> = Vec::new();
        for l in &decl.locations {
            if locations.iter().any(|x| x.name == l.name.text) {
                self.error(
                    MbtCode::Duplicate,
                    l.name.span,
                    format!("the location `{}` is declared twice", l.name.text),
                );
                continue;
            }
            let quiescence_us = l.quiescence.as_ref().and_then(|q| self.constant(q, scope, None));
            locations.push(Location {
                name: l.name.text.clone(),
                quiescence_us,
            });
        }
        let mut vars: Vec<Var> = Vec::new();
        for v in &decl.vars {
            let (lo, hi, boolean) = match &v.ty {
                TypeDecl::Bool => (0, 1, true),
                TypeDecl::Range(lo, hi) => {
                    match (self.constant(lo, scope, None), self.constant(hi, scope, None)) {
                        (Some(lo), Some(hi)) if lo <= hi => (lo, hi, false),
                        (Some(_), Some(_)) => {
                            self.error(
                                MbtCode::Unbounded,
                                v.name.span,
                                format!("the domain of `{}` is empty", v.name.text),
                            );
                            continue;
                        }
                        _ => continue,
                    }
                }
            };
            let Some(init) = self.constant(&v.init, scope, None) else {
                continue;
            };
            if !(lo..=hi).contains(&init) {
                self.error(
                    MbtCode::OutOfDomain,
                    v.init.span,
                    format!("`{}` starts at {init}, outside {lo}..{hi}", v.name.text),
                );
            }
            if vars.iter().any(|x| x.name == v.name.text) {
                self.error(
                    MbtCode::Duplicate,
                    v.name.span,
                    format!("the variable `{}` is declared twice", v.name.text),
                );
                continue;
            }
            let slot = self.model.initial.len();
            self.model.initial.push(init);
            vars.push(Var {
                name: v.name.text.clone(),
                slot,
                lo,
                hi,
                boolean,
            });
        }
        self.model.processes.push(Process {
            name: decl.name.text.clone(),
            file: self.file,
            locations,
            location_slot,
            vars,
            transitions: Vec::new(),
        });
    }

    /// Second pass: transitions, resets and purposes.
    fn define(&mut self, file: &File) {
        let global = Scope {
            process: None,
            fields: None,
            depth: 0,
        };
        for reset in &file.resets {
            if let Some((gate, patterns, _)) = self.action(reset, Direction::Input, global)
                && let Some(values) = patterns
                    .iter()
                    .map(|p| match p {
                        CPattern::Value(e) => e.constant(),
                        _ => None,
                    })
                    .collect::<Option<Vec<i64>>>()
            {
                // Each distinct stimulus once: composed models that reset alike reset once.
                let label = Label::concrete(gate, &values);
                self.file_resets.entry(self.file).or_default().push(label.clone());
                if !self.model.resets.contains(&label) {
                    self.model.resets.push(label);
                }
            } else {
                self.error(
                    MbtCode::Unbounded,
                    reset.span,
                    "a `reset` stimulus needs a value for every field",
                );
            }
        }
        for decl in &file.processes {
            let Some(p) = self
                .model
                .processes
                .iter()
                .position(|p| p.name == decl.name.text && p.file == self.file)
            else {
                continue;
            };
            for t in &decl.transitions {
                self.transition(p, t);
            }
            self.check_process(p, decl);
        }
        for decl in &file.purposes {
            self.purpose(decl);
        }
    }

    fn location(&mut self, p: usize, name: &Name) -> Option<i64> {
        let found = self
            .model
            .process_at(p)
            .locations
            .iter()
            .position(|l| l.name == name.text);
        if found.is_none() {
            let message = format!(
                "the process `{}` has no location `{}`",
                self.model.process_at(p).name,
                name.text
            );
            self.error(MbtCode::UnknownName, name.span, message);
        }
        found.map(|l| l as i64)
    }

    fn transition(&mut self, p: usize, t: &TransitionDecl) {
        let mut from = Vec::new();
        for name in &t.from {
            from.extend(self.location(p, name));
        }
        if from.len() != t.from.len() {
            return;
        }
        let to = match &t.to {
            None => None,
            Some(name) => match self.location(p, name) {
                Some(l) => Some(l),
                None => return,
            },
        };
        let kind = match t.kind {
            ActionKind::Input => Kind::Input,
            ActionKind::Output => Kind::Output,
            ActionKind::MaybeOutput => Kind::MaybeOutput,
            ActionKind::Internal => Kind::Internal,
            ActionKind::Signal => Kind::Signal,
            ActionKind::On => Kind::On,
        };
        let event = match &t.event {
            None => None,
            Some(name) => {
                let declared = self
                    .file_events
                    .get(&self.file)
                    .into_iter()
                    .flatten()
                    .copied()
                    .find(|e| self.model.events.get(*e) == Some(&name.text));
                if declared.is_none() {
                    self.error(
                        MbtCode::UnknownName,
                        name.span,
                        format!(
                            "`{}` is not an event of this model; declare it with `event {}`",
                            name.text, name.text
                        ),
                    );
                    return;
                }
                declared
            }
        };
        let scope = Scope {
            process: Some(p),
            fields: None,
            depth: 0,
        };
        let (gate, patterns, fields) = match &t.action {
            Some(action) => {
                let direction = if kind == Kind::Input {
                    Direction::Input
                } else {
                    Direction::Output
                };
                match self.action(action, direction, scope) {
                    Some((g, patterns, fields)) => {
                        // A gate a transition uses is in its component's alphabet, even if only a
                        // used model declares it.
                        let gates = self.file_gates.entry(self.file).or_default();
                        if !gates.contains(&g) {
                            gates.push(g);
                        }
                        (Some(g), patterns, Some(fields))
                    }
                    None => return,
                }
            }
            None => (None, Vec::new(), None),
        };
        let field_scope = Scope {
            process: Some(p),
            fields: fields.as_deref(),
            depth: 0,
        };
        let mut guard: Option<CExpr> = None;
        for g in &t.guards {
            let Some(c) = self.expr(g, field_scope) else {
                return;
            };
            if kind.is_output() && c.reads_fields() {
                self.error(
                    MbtCode::OutputGuardReadsField,
                    g.span,
                    "a guard of an output cannot read the output's fields; write the allowed values in the pattern",
                );
            }
            guard = Some(match guard {
                None => c,
                Some(prev) => CExpr::Binary(BinOp::And, Box::new(prev), Box::new(c)),
            });
        }
        if kind == Kind::Input
            && !t.passive
            && let Some(fields) = &fields
        {
            let open: Vec<&str> = patterns
                .iter()
                .zip(fields.iter())
                .filter(|(pat, f)| matches!(pat, CPattern::Any) && !f.opaque)
                .map(|(_, f)| f.name.as_str())
                .collect();
            if !open.is_empty() {
                self.error(
                    MbtCode::Unbounded,
                    t.span,
                    format!("the input leaves the field(s) {} open: give each a value, a set or a range so the tester can choose", open.join(", ")),
                );
            }
        }
        let mut updates = Vec::new();
        for (name, value) in &t.updates {
            let Some(var) = self
                .model
                .process_at(p)
                .vars
                .iter()
                .find(|v| v.name == name.text)
                .cloned()
            else {
                let message = if self
                    .model
                    .processes
                    .iter()
                    .any(|q| q.vars.iter().any(|v| v.name == name.text))
                {
                    format!(
                        "`{}` belongs to another process; only its owner may assign it",
                        name.text
                    )
                } else {
                    format!("`{}` is not a variable of this process", name.text)
                };
                let code = if message.contains("another") {
                    MbtCode::NotOwner
                } else {
                    MbtCode::UnknownName
                };
                self.error(code, name.span, message);
                continue;
            };
            if let Some(c) = self.expr(value, field_scope) {
                updates.push((var.slot, c, var.lo, var.hi));
            }
        }
        let mut resets = Vec::new();
        for clock in &t.resets {
            match self.clock(&clock.text) {
                Some(c) => resets.push(c),
                None => self.error(
                    MbtCode::UnknownName,
                    clock.span,
                    format!("`{}` is not a declared clock", clock.text),
                ),
            }
        }
        if kind.is_hidden() && !resets.is_empty() {
            self.error(
                MbtCode::TauResetsClock,
                t.span,
                "an internal transition cannot reset a clock: when it happens is not observed",
            );
        }
        let window = match &t.window {
            None => None,
            Some(w) => {
                let clock = self.clock(&w.clock.text);
                if clock.is_none() {
                    self.error(
                        MbtCode::UnknownName,
                        w.clock.span,
                        format!("`{}` is not a declared clock", w.clock.text),
                    );
                }
                match (self.expr(&w.lo, scope), self.expr(&w.hi, scope), clock) {
                    (Some(lo), Some(hi), Some(c)) => Some((lo, hi, c)),
                    _ => return,
                }
            }
        };
        if kind == Kind::On && window.is_some() {
            self.error(
                MbtCode::Syntax,
                t.span,
                "an `on` transition follows another model's `signal`: the window is the signal's",
            );
        }
        if kind == Kind::Output && window.is_none() {
            self.error(
                MbtCode::NoTimeBound,
                t.span,
                "this output has no `within LO..HI of CLOCK`: a missing output could never fail; add a window or write `maybe out`",
            );
        }
        let id = self.model.transitions.len();
        self.model.transitions.push(Transition {
            id,
            process: p,
            from,
            to,
            kind,
            gate,
            event,
            passive: t.passive,
            otherwise: t.otherwise,
            patterns,
            guard,
            updates,
            resets,
            window,
            tags: t.tags.clone(),
            span: t.span,
        });
        crate::model::at_mut(&mut self.model.processes, p)
            .transitions
            .push(id);
    }

    /// Resolves an action: the gate (checked for direction), one pattern per field.
    fn action(
        &mut self,
        action: &Action,
        direction: Direction,
        scope: Scope<'_>,
    ) -> Option<(usize, Vec<CPattern>, Vec<Field>)> {
        let Some(g) = self.model.gate(&action.gate.text) else {
            self.error(
                MbtCode::UnknownName,
                action.gate.span,
                format!("`{}` is not a declared gate", action.gate.text),
            );
            return None;
        };
        let gate = self.model.gate_at(g).clone();
        if gate.direction != direction {
            let (is, used) = match gate.direction {
                Direction::Input => ("an input", "an output"),
                Direction::Output => ("an output", "an input"),
            };
            self.error(
                MbtCode::GateDirection,
                action.gate.span,
                format!("`{}` is {is} gate, used here as {used}", gate.name),
            );
            return None;
        }
        let mut patterns = vec![CPattern::Any; gate.fields.len()];
        let mut positional = 0;
        for arg in &action.args {
            let index = match &arg.field {
                Some(name) => match gate.fields.iter().position(|f| f.name == name.text) {
                    Some(i) => i,
                    None => {
                        self.error(
                            MbtCode::UnknownName,
                            name.span,
                            format!("the gate `{}` has no field `{}`", gate.name, name.text),
                        );
                        return None;
                    }
                },
                None => {
                    positional += 1;
                    positional - 1
                }
            };
            let Some(field) = gate.fields.get(index) else {
                self.error(
                    MbtCode::Syntax,
                    action.span,
                    format!("the gate `{}` has {} fields", gate.name, gate.fields.len()),
                );
                return None;
            };
            let max = if field.size >= 8 {
                i64::MAX
            } else {
                (1i64 << (8 * field.size)) - 1
            };
            let pattern = match &arg.pattern {
                Pattern::Any(_) => CPattern::Any,
                Pattern::Value(e) => match self.named_set(e) {
                    Some(set) => CPattern::Set(self.set_in_field(set?, e.span, max)?),
                    None => CPattern::Value(self.field_value(e, scope, max)?),
                },
                Pattern::Set(items, _) => {
                    let mut values = Vec::new();
                    for item in items {
                        match self.named_set(item) {
                            Some(set) => values.extend(self.set_in_field(set?, item.span, max)?),
                            None => values.push(self.field_value(item, scope, max)?),
                        }
                    }
                    CPattern::Set(values)
                }
                Pattern::Range(lo, hi) => {
                    let (lo, hi) = (
                        self.field_value(lo, scope, max)?,
                        self.field_value(hi, scope, max)?,
                    );
                    if direction == Direction::Input
                        && let (Some(l), Some(h)) = (lo.constant(), hi.constant())
                        && h - l >= MAX_INPUT_CHOICES
                    {
                        self.error(
                            MbtCode::Unbounded,
                            action.span,
                            format!("an input range may offer at most {MAX_INPUT_CHOICES} values"),
                        );
                    }
                    CPattern::Range(lo, hi)
                }
            };
            if field.opaque && pattern != CPattern::Any {
                self.error(
                    MbtCode::Syntax,
                    action.span,
                    format!("the field `{}` is bytes(N): only `_` matches it", field.name),
                );
            }
            // `field` is the gate's, and there is a pattern per field.
            if let Some(slot) = patterns.get_mut(index) {
                *slot = pattern;
            }
        }
        Some((g, patterns, gate.fields))
    }

    /// `accepted(NAME)`: the values of a set of the shared oracle (`canopener_wire::accepted`);
    /// `None` if `e` is not such a call, `Some(None)` if it names no set (reported).
    fn named_set(&mut self, e: &Expr) -> Option<Option<Vec<i64>>> {
        let ExprKind::Call(f, args) = &e.kind else {
            return None;
        };
        if f != "accepted" {
            return None;
        }
        let name = match args.as_slice() {
            [
                Expr {
                    kind: ExprKind::Name(n),
                    ..
                },
            ] => n.clone(),
            _ => {
                self.error(
                    MbtCode::BadCall,
                    e.span,
                    "`accepted` takes the name of a set, e.g. `accepted(no_object)`",
                );
                return Some(None);
            }
        };
        match canopener_wire::accepted::named_set(&name) {
            Some(set) => Some(Some(set.values.iter().map(|v| i64::from(*v)).collect())),
            None => {
                let names: Vec<&str> = canopener_wire::accepted::named_sets()
                    .iter()
                    .map(|s| s.name)
                    .collect();
                self.error(
                    MbtCode::BadCall,
                    e.span,
                    format!(
                        "`{name}` is not a set of accepted answers; there are {}",
                        names.join(", ")
                    ),
                );
                Some(None)
            }
        }
    }

    /// The values of a named set as constants that fit a field of at most `max`.
    fn set_in_field(&mut self, values: Vec<i64>, span: Span, max: i64) -> Option<Vec<CExpr>> {
        if let Some(v) = values.iter().find(|v| !(0..=max).contains(*v)) {
            self.error(
                MbtCode::OutOfDomain,
                span,
                format!("the set holds {v:#X}, which does not fit the field (0..={max:#X})"),
            );
            return None;
        }
        Some(values.into_iter().map(CExpr::Const).collect())
    }

    fn field_value(&mut self, e: &Expr, scope: Scope<'_>, max: i64) -> Option<CExpr> {
        let c = self.expr(e, scope)?;
        if let Some(v) = c.constant()
            && !(0..=max).contains(&v)
        {
            self.error(
                MbtCode::OutOfDomain,
                e.span,
                format!("{v} does not fit the field (0..={max:#X})"),
            );
            return None;
        }
        Some(c)
    }

    /// A value known at compile time; reports why not.
    fn constant(&mut self, e: &Expr, scope: Scope<'_>, fallback: Option<&Expr>) -> Option<i64> {
        let before = self.diagnostics.get(&self.file).map_or(0, Vec::len);
        let compiled = self.expr(e, scope);
        let after = self.diagnostics.get(&self.file).map_or(0, Vec::len);
        let needs_eds = after > before
            && self
                .diagnostics
                .get(&self.file)
                .into_iter()
                .flat_map(|d| d.iter().skip(before))
                .all(|d| d.code == MbtCode::ParamUnresolved);
        if needs_eds && let Some(fallback) = fallback {
            if let Some(found) = self.diagnostics.get_mut(&self.file) {
                found.truncate(before);
            }
            return self.constant(fallback, scope, None);
        }
        let c = compiled?;
        match c.eval(&[], &[]) {
            Ok(v) if !c.reads_state() && !c.reads_fields() => Some(v),
            Ok(_) => {
                self.error(
                    MbtCode::ParamUnresolved,
                    e.span,
                    "this value must be known before the run: it cannot read variables or fields",
                );
                None
            }
            Err(err) => {
                self.error(
                    MbtCode::ParamUnresolved,
                    e.span,
                    format!("cannot evaluate: {err}"),
                );
                None
            }
        }
    }

    fn expr(&mut self, e: &Expr, scope: Scope<'_>) -> Option<CExpr> {
        if scope.depth > 32 {
            self.error(
                MbtCode::ParamUnresolved,
                e.span,
                "`let` definitions refer to each other in a cycle",
            );
            return None;
        }
        Some(match &e.kind {
            ExprKind::Int(v) => CExpr::Const(*v),
            ExprKind::Bool(b) => CExpr::Const(i64::from(*b)),
            ExprKind::NodeId => CExpr::Const(i64::from(self.options.node_id)),
            ExprKind::Name(name) => return self.name(name, e.span, scope),
            ExprKind::Member(process, var) => {
                let found = self
                    .model
                    .processes
                    .iter()
                    .find(|p| p.name == *process)
                    .and_then(|p| p.vars.iter().find(|v| v.name == *var));
                match found {
                    Some(v) => CExpr::Slot(v.slot),
                    None => {
                        self.error(
                            MbtCode::UnknownName,
                            e.span,
                            format!("`{process}.{var}` is not a variable"),
                        );
                        return None;
                    }
                }
            }
            ExprKind::At(process, locations) => {
                let Some(p) = self.model.processes.iter().position(|p| p.name == *process) else {
                    self.error(
                        MbtCode::UnknownName,
                        e.span,
                        format!("`{process}` is not a process"),
                    );
                    return None;
                };
                let mut numbers = Vec::new();
                for l in locations {
                    numbers.push(self.location(p, l)?);
                }
                CExpr::At(self.model.process_at(p).location_slot, numbers)
            }
            ExprKind::Unary(op, inner) => {
                let op = if *op == "!" { UnOp::Not } else { UnOp::Neg };
                CExpr::Unary(op, Box::new(self.expr(inner, scope)?))
            }
            ExprKind::Binary(op, a, b) => {
                let op = BinOp::from_symbol(op)?;
                CExpr::Binary(op, Box::new(self.expr(a, scope)?), Box::new(self.expr(b, scope)?))
            }
            ExprKind::In(x, items) => {
                let x = self.expr(x, scope)?;
                let mut list = Vec::new();
                for i in items {
                    match self.named_set(i) {
                        Some(set) => list.extend(set?.into_iter().map(CExpr::Const)),
                        None => list.push(self.expr(i, scope)?),
                    }
                }
                CExpr::In(Box::new(x), list)
            }
            ExprKind::InRange(x, lo, hi) => CExpr::InRange(
                Box::new(self.expr(x, scope)?),
                Box::new(self.expr(lo, scope)?),
                Box::new(self.expr(hi, scope)?),
            ),
            ExprKind::If(c, a, b) => CExpr::If(
                Box::new(self.expr(c, scope)?),
                Box::new(self.expr(a, scope)?),
                Box::new(self.expr(b, scope)?),
            ),
            ExprKind::Call(f, args) => return self.call(f, args, e.span, scope),
        })
    }

    fn name(&mut self, name: &str, span: Span, scope: Scope<'_>) -> Option<CExpr> {
        if let Some(fields) = scope.fields
            && let Some(i) = fields.iter().position(|f| f.name == name)
        {
            return Some(CExpr::Field(i));
        }
        if let Some(p) = scope.process
            && let Some(v) = self.model.process_at(p).vars.iter().find(|v| v.name == name)
        {
            return Some(CExpr::Slot(v.slot));
        }
        let binding = self
            .visible
            .get(self.file)
            .into_iter()
            .flatten()
            .find_map(|f| self.globals.get(*f)?.get(name).cloned());
        match binding {
            Some(Binding::Value(v)) => Some(CExpr::Const(v)),
            Some(Binding::Let(e, file)) => {
                let here = self.file;
                self.file = file;
                let c = self.expr(
                    &e,
                    Scope {
                        depth: scope.depth + 1,
                        ..scope
                    },
                );
                self.file = here;
                c
            }
            None => {
                self.error(
                    MbtCode::UnknownName,
                    span,
                    format!("`{name}` is not defined here"),
                );
                None
            }
        }
    }

    fn call(&mut self, f: &str, args: &[Expr], span: Span, scope: Scope<'_>) -> Option<CExpr> {
        let arity = match f {
            "accepted" => {
                self.error(
                    MbtCode::BadCall,
                    span,
                    "`accepted(NAME)` is a set: use it as a field pattern or after `in`",
                );
                return None;
            }
            "od" | "exists" => 2,
            "pdo_bytes" => 1,
            "min" | "max" => 2,
            _ => {
                self.error(
                    MbtCode::BadCall,
                    span,
                    format!(
                        "`{f}` is not a function; there are od, exists, pdo_bytes, min, max and accepted"
                    ),
                );
                return None;
            }
        };
        if args.len() != arity {
            self.error(
                MbtCode::BadCall,
                span,
                format!("`{f}` takes {arity} argument(s), not {}", args.len()),
            );
            return None;
        }
        let mut compiled = Vec::new();
        for a in args {
            compiled.push(self.expr(a, scope)?);
        }
        if let [a, b] = &compiled[..]
            && (f == "min" || f == "max")
        {
            let (a, b) = (Box::new(a.clone()), Box::new(b.clone()));
            return Some(if f == "min" {
                CExpr::Min(a, b)
            } else {
                CExpr::Max(a, b)
            });
        }
        let values: Option<Vec<i64>> = compiled.iter().map(CExpr::constant).collect();
        let Some(values) = values else {
            self.error(
                MbtCode::ParamUnresolved,
                span,
                format!("the arguments of `{f}` must be constants"),
            );
            return None;
        };
        let Some(eds) = self.options.eds else {
            let message = format!(
                "`{f}` reads the device description: pass --eds FILE or give the parameter an `else` value"
            );
            self.error(MbtCode::ParamUnresolved, span, message);
            return None;
        };
        let node = self.options.node_id;
        // The arity was checked above: two arguments for od and exists, one for pdo_bytes.
        let argument = |i: usize| values.get(i).copied().unwrap_or(0);
        let index = u16::try_from(argument(0)).unwrap_or(0);
        let result = match f {
            "od" => crate::device_facts::value(eds, node, index, u8::try_from(argument(1)).unwrap_or(0)),
            "exists" => Ok(i64::from(crate::device_facts::exists(
                eds,
                index,
                u8::try_from(argument(1)).unwrap_or(0),
            ))),
            _ => crate::device_facts::pdo_bytes(eds, node, index),
        };
        match result {
            Ok(v) => Some(CExpr::Const(v)),
            Err(message) => {
                self.error(MbtCode::ParamUnresolved, span, message);
                None
            }
        }
    }

    /// τ-cycles (internal transitions that can loop without a window) and unreachable locations.
    fn check_process(&mut self, p: usize, decl: &ProcessDecl) {
        let process = self.model.process_at(p).clone();
        let n = process.locations.len();
        let targets = |t: &Transition| -> Vec<(usize, usize)> {
            let from: Vec<usize> = if t.from.is_empty() {
                (0..n).collect()
            } else {
                t.from.iter().map(|l| *l as usize).collect()
            };
            from.into_iter()
                .map(|f| (f, t.to.map_or(f, |l| l as usize)))
                .collect()
        };
        let mut tau = vec![Vec::new(); n];
        let mut reached = vec![false; n];
        if let Some(initial) = reached.first_mut() {
            *initial = true;
        }
        for &t in &process.transitions {
            let t = self.model.transition_at(t);
            // A step that stays where it is and writes a variable its guard reads changes its own
            // condition (`when foreign do foreign := false`): not a loop by itself.
            let mut read = Vec::new();
            if let Some(g) = &t.guard {
                g.slots(&mut read);
            }
            let settles = t.to.is_none() && t.updates.iter().any(|(slot, ..)| read.contains(slot));
            for (f, to) in targets(t) {
                if matches!(t.kind, Kind::Internal | Kind::Signal)
                    && t.window.is_none()
                    && !(settles && f == to)
                    && let Some(out) = tau.get_mut(f)
                {
                    out.push(to);
                }
            }
        }
        // Locations reachable through any transition from the initial one.
        let mut stack = vec![0];
        while let Some(l) = stack.pop() {
            for &t in &process.transitions {
                for (f, to) in targets(self.model.transition_at(t)) {
                    if f == l
                        && let Some(reached) = reached.get_mut(to)
                        && !*reached
                    {
                        *reached = true;
                        stack.push(to);
                    }
                }
            }
        }
        for (decl_l, reached) in decl.locations.iter().zip(&reached) {
            if !reached {
                self.error(
                    MbtCode::UnreachableLocation,
                    decl_l.name.span,
                    format!("no transition leads to the location `{}`", decl_l.name.text),
                );
            }
        }
        // A cycle of immediate internal steps: depth-first search with colours.
        let mut colour = vec![0u8; n];
        // Locations and the targets in `tau` are below `n`, the length of `tau` and `colour`.
        fn cyclic(l: usize, tau: &[Vec<usize>], colour: &mut [u8]) -> bool {
            if let Some(c) = colour.get_mut(l) {
                *c = 1;
            }
            for &to in tau.get(l).into_iter().flatten() {
                let c = colour.get(to).copied();
                if c == Some(1) || (c == Some(0) && cyclic(to, tau, colour)) {
                    return true;
                }
            }
            if let Some(c) = colour.get_mut(l) {
                *c = 2;
            }
            false
        }
        for (l, location) in process.locations.iter().enumerate() {
            if colour.get(l) == Some(&0) && cyclic(l, &tau, &mut colour) {
                self.error(
                    MbtCode::TauCycle,
                    decl.name.span,
                    format!(
                        "internal transitions of `{}` can loop forever without a window through `{}`",
                        process.name, location.name
                    ),
                );
                break;
            }
        }
    }

    fn purpose(&mut self, decl: &PurposeDecl) {
        let states: Vec<(String, Marker)> = decl.states.iter().map(|(n, m)| (n.text.clone(), *m)).collect();
        if states.is_empty() {
            self.error(
                MbtCode::BadPurpose,
                decl.name.span,
                "a purpose needs `state` lines; the first is initial",
            );
            return;
        }
        let find = |name: &Name| states.iter().position(|(s, _)| *s == name.text);
        let mut transitions = Vec::new();
        for t in &decl.transitions {
            let (Some(from), Some(to)) = (find(&t.from), find(&t.to)) else {
                self.error(
                    MbtCode::UnknownName,
                    t.span,
                    "a purpose transition names a state not declared with `state`",
                );
                continue;
            };
            let pattern = match &t.pattern {
                LabelPatternDecl::Otherwise => LabelPattern::Otherwise,
                LabelPatternDecl::Quiescence => LabelPattern::Quiescence,
                LabelPatternDecl::Gate {
                    direction,
                    action,
                    guard,
                } => {
                    let Some(g) = self.model.gate(&action.gate.text) else {
                        self.error(
                            MbtCode::BadPurpose,
                            action.gate.span,
                            format!("`{}` is not a gate of the specification", action.gate.text),
                        );
                        continue;
                    };
                    let dir = self.model.gate_at(g).direction;
                    let Some((_, patterns, fields)) = self.action(
                        action,
                        dir,
                        Scope {
                            process: None,
                            fields: None,
                            depth: 0,
                        },
                    ) else {
                        continue;
                    };
                    let mut values = Vec::new();
                    for p in patterns {
                        let v = match p {
                            CPattern::Any => Some(ValuePattern::Any),
                            CPattern::Value(e) => e.constant().map(|v| ValuePattern::Set(vec![v])),
                            CPattern::Set(items) => items
                                .iter()
                                .map(CExpr::constant)
                                .collect::<Option<Vec<_>>>()
                                .map(ValuePattern::Set),
                            CPattern::Range(lo, hi) => lo
                                .constant()
                                .zip(hi.constant())
                                .map(|(l, h)| ValuePattern::Range(l, h)),
                        };
                        match v {
                            Some(v) => values.push(v),
                            None => {
                                self.error(
                                    MbtCode::BadPurpose,
                                    action.span,
                                    "purpose patterns must be constants",
                                );
                                break;
                            }
                        }
                    }
                    let guard = guard.as_ref().and_then(|g| {
                        self.expr(
                            g,
                            Scope {
                                process: None,
                                fields: Some(&fields),
                                depth: 0,
                            },
                        )
                    });
                    LabelPattern::Gate {
                        direction: *direction,
                        gate: action.gate.text.clone(),
                        values,
                        guard,
                    }
                }
            };
            transitions.push(PurposeTransition { from, to, pattern });
        }
        let purpose = Purpose {
            name: decl.name.text.clone(),
            title: decl.title.clone().unwrap_or_default(),
            states,
            transitions,
        };
        for problem in purpose.problems() {
            self.error(MbtCode::BadPurpose, decl.name.span, problem);
        }
        self.model.purposes.push(purpose);
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub(crate) fn one(text: &str) -> (Option<Model>, Vec<MbtDiagnostic>) {
        let (model, report) = compile(
            &[Source {
                origin: "test".into(),
                text: text.into(),
            }],
            &Options {
                node_id: 5,
                ..Options::default()
            },
            &|_| None,
        );
        (model, report.into_iter().flat_map(|r| r.diagnostics).collect())
    }

    fn codes(text: &str) -> Vec<(u32, &'static str)> {
        one(text)
            .1
            .iter()
            .map(|d| (d.span.line, d.code.as_str()))
            .collect()
    }

    #[test]
    fn a_model_compiles_with_node_id_arithmetic() {
        let (model, d) = one(
            "model m\nparam P = 100ms\ninput NMT = 0 (cs: u8, node: u8)\noutput EC = 0x700 + $NODEID (s: u8)\nclock t\n\
             reset NMT(0x81, $NODEID)\nprocess p {\n var n: 0..3 = 0\n location A, B\n \
             A -> B: out EC(0) within 0..P of t reset t\n B -> same: in NMT({1, 2}, {0, $NODEID}) when n < 3 do n := n + 1\n}\n",
        );
        assert!(d.is_empty(), "{d:#?}");
        let model = model.unwrap();
        assert_eq!(model.gates[1].cob_id, 0x705);
        assert_eq!(model.resets, [Label::concrete(0, &[0x81, 5])]);
        assert_eq!(model.initial, [0, 0]);
        assert_eq!(model.param("P"), Some(100_000));
        assert_eq!(model.hash.len(), 64);
    }

    #[test]
    fn static_checks_report_their_line() {
        let base = "model m\ninput I = 1 (a: u8)\noutput O = 2 (a: u8)\nclock t\n";
        assert_eq!(
            codes(&format!(
                "{base}process p {{\n location A\n A -> A: out O(1)\n}}\n"
            )),
            [(7, "M023")]
        );
        assert_eq!(
            codes(&format!(
                "{base}process p {{\n location A\n A -> A: in O(1)\n}}\n"
            )),
            [(7, "M022")]
        );
        assert_eq!(
            codes(&format!(
                "{base}process p {{\n location A\n A -> A: in I(_)\n}}\n"
            )),
            [(7, "M020")]
        );
        assert_eq!(
            codes(&format!(
                "{base}process p {{\n location A, B\n A -> B: internal\n B -> A: internal\n}}\n"
            )),
            [(5, "M021")]
        );
        assert_eq!(
            codes(&format!(
                "{base}process p {{\n location A, B\n A -> A: in I(1)\n}}\n"
            )),
            [(6, "M041")]
        );
        assert_eq!(
            codes(&format!(
                "{base}process p {{\n location A\n A -> A: in I(x)\n}}\n"
            )),
            [(7, "M010")]
        );
        assert_eq!(codes(&format!("{base}const C = od(0x1017, 0)\n")), [(5, "M030")]);
        assert_eq!(codes(&format!("{base}param C = od(0x1017, 0) else 5\n")), []);
        assert_eq!(
            codes(&format!(
                "{base}process p {{\n location A\n A -> A: in I(300)\n}}\n"
            )),
            [(7, "M031")]
        );
        assert_eq!(codes(&format!("{base}output W = 0x800 (a: u8)\n")), [(5, "M032")]);
        assert_eq!(
            codes(&format!(
                "{base}process p {{\n var v: 0..1 = 0\n location A\n A -> A: in I(1)\n}}\nprocess q {{\n location A\n A -> A: in I(2) do v := 1\n}}\n"
            )),
            [(12, "M024")]
        );
    }
}

//! The model file as written: every item with its span, before names are resolved.

use canopener_eds::diag::Span;

/// A name as written and where.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Name {
    /// The text.
    pub text: String,
    /// Where it is written.
    pub span: Span,
}

/// One model file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct File {
    /// `model NAME`.
    pub name: Option<Name>,
    /// `title "..."`.
    pub title: Option<String>,
    /// `cite "..."` lines: the clauses of the specifications the model encodes.
    pub cites: Vec<String>,
    /// `use NAME` lines: other models composed with this one.
    pub uses: Vec<Name>,
    /// `param`, `const` and `let` definitions, in order.
    pub definitions: Vec<Definition>,
    /// `quiescence DURATION`: the default quiescence bound.
    pub quiescence: Option<Expr>,
    /// `reset GATE(...)`: the stimuli that bring the device to the initial state.
    pub resets: Vec<Action>,
    /// `input` and `output` gates.
    pub gates: Vec<GateDecl>,
    /// `clock` declarations.
    pub clocks: Vec<Name>,
    /// `event` declarations: hidden gates the composed components synchronise on.
    pub events: Vec<Name>,
    /// `process` blocks.
    pub processes: Vec<ProcessDecl>,
    /// `purpose` blocks.
    pub purposes: Vec<PurposeDecl>,
}

/// What kind of definition.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DefKind {
    /// `param`: a value the run may override (`$NODEID` and `--set NAME=VALUE`), evaluated once.
    Param,
    /// `const`: a value evaluated once.
    Const,
    /// `let`: a named expression, evaluated where it is used (it may read the state).
    Let,
}

/// `param NAME = expr [else expr]`, `const NAME = expr` or `let NAME = expr`.
#[derive(Debug, Clone, PartialEq)]
pub struct Definition {
    /// Which kind.
    pub kind: DefKind,
    /// The name.
    pub name: Name,
    /// The value.
    pub value: Expr,
    /// The fallback when `value` needs a device description that is not given.
    pub fallback: Option<Expr>,
}

/// Direction of a gate, from the device's point of view.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Direction {
    /// A frame the tester sends (an input of the device).
    Input,
    /// A frame the device sends.
    Output,
}

/// `input NAME = COBID [rtr] (field: type, ...)`.
#[derive(Debug, Clone, PartialEq)]
pub struct GateDecl {
    /// Input or output.
    pub direction: Direction,
    /// The gate's name.
    pub name: Name,
    /// The CAN-ID expression.
    pub cob_id: Expr,
    /// A remote frame (`rtr`), with the DLC given by its fields' length.
    pub remote: bool,
    /// The data fields, in byte order.
    pub fields: Vec<FieldDecl>,
}

/// The type of a field.
#[derive(Debug, Clone, PartialEq)]
pub enum FieldType {
    /// An unsigned little-endian integer of 1, 2 or 4 bytes.
    Unsigned(u8),
    /// `bytes(N)`: N opaque bytes (only `_` can match them).
    Bytes(Expr),
}

/// One field of a gate.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldDecl {
    /// The field's name.
    pub name: Name,
    /// Its type.
    pub ty: FieldType,
}

/// A variable's domain.
#[derive(Debug, Clone, PartialEq)]
pub enum TypeDecl {
    /// `bool`.
    Bool,
    /// `lo..hi`, inclusive; `u8`, `u16` and `u32` are ranges too.
    Range(Expr, Expr),
}

/// `process NAME { ... }`.
#[derive(Debug, Clone, PartialEq)]
pub struct ProcessDecl {
    /// The name.
    pub name: Name,
    /// `var NAME: TYPE = INIT`.
    pub vars: Vec<VarDecl>,
    /// `location NAME [quiescence D]`, the first is the initial location.
    pub locations: Vec<LocationDecl>,
    /// The transitions.
    pub transitions: Vec<TransitionDecl>,
}

/// A variable.
#[derive(Debug, Clone, PartialEq)]
pub struct VarDecl {
    /// The name.
    pub name: Name,
    /// The domain.
    pub ty: TypeDecl,
    /// The initial value.
    pub init: Expr,
}

/// A location.
#[derive(Debug, Clone, PartialEq)]
pub struct LocationDecl {
    /// The name.
    pub name: Name,
    /// Its quiescence bound, if not the model's.
    pub quiescence: Option<Expr>,
}

/// What a transition does.
#[derive(Debug, Clone, PartialEq)]
pub enum ActionKind {
    /// `in GATE(...)`: the tester sends.
    Input,
    /// `out GATE(...)`: the device must send, within the window.
    Output,
    /// `maybe out GATE(...)`: the device may send, within the window.
    MaybeOutput,
    /// `internal`: the device changes state without a frame.
    Internal,
    /// `signal EVENT`: the device changes state without a frame, and every composed model that
    /// declares the event takes part (a hidden gate).
    Signal,
    /// `on EVENT`: follows another model's `signal EVENT`; never happens alone.
    On,
}

/// An action with a gate: `GATE(pattern, name = pattern, ...)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Action {
    /// The gate.
    pub gate: Name,
    /// Patterns, by position or by field name.
    pub args: Vec<Arg>,
    /// Where the action is written.
    pub span: Span,
}

/// One argument of an action.
#[derive(Debug, Clone, PartialEq)]
pub struct Arg {
    /// `field =`, if named.
    pub field: Option<Name>,
    /// The pattern.
    pub pattern: Pattern,
}

/// What a field may be.
#[derive(Debug, Clone, PartialEq)]
pub enum Pattern {
    /// `_`: any value.
    Any(Span),
    /// An expression: exactly this value.
    Value(Expr),
    /// `{a, b, c}`: one of these values.
    Set(Vec<Expr>, Span),
    /// `lo..hi`: a value in this range (inclusive).
    Range(Expr, Expr),
}

/// `FROM, FROM -> TO: ACTION clauses`.
#[derive(Debug, Clone, PartialEq)]
pub struct TransitionDecl {
    /// Source locations; empty means every location (`any`).
    pub from: Vec<Name>,
    /// Target location; `None` for `same`: stay where it is.
    pub to: Option<Name>,
    /// What it does.
    pub kind: ActionKind,
    /// The gate and patterns (none for internal transitions).
    pub action: Option<Action>,
    /// The hidden event of a `signal` or `on` transition.
    pub event: Option<Name>,
    /// `passive`: an input that follows what another composed model sends; never chosen for this one.
    pub passive: bool,
    /// `otherwise`: a passive input taken only when no other input transition of the model takes the
    /// label.
    pub otherwise: bool,
    /// `when GUARD` (several are joined with `&&`).
    pub guards: Vec<Expr>,
    /// `do VAR := EXPR, ...`.
    pub updates: Vec<(Name, Expr)>,
    /// `reset CLOCK, ...`.
    pub resets: Vec<Name>,
    /// `within LO..HI of CLOCK`.
    pub window: Option<Window>,
    /// `tag "..."`: requirement tags for coverage.
    pub tags: Vec<String>,
    /// Where the transition starts.
    pub span: Span,
}

/// A time window relative to a clock.
#[derive(Debug, Clone, PartialEq)]
pub struct Window {
    /// Earliest time after the clock's reset.
    pub lo: Expr,
    /// Latest time after the clock's reset.
    pub hi: Expr,
    /// The clock the window is measured from (its last reset).
    pub clock: Name,
}

/// `purpose NAME "title" { ... }`.
#[derive(Debug, Clone, PartialEq)]
pub struct PurposeDecl {
    /// The name.
    pub name: Name,
    /// What it is for.
    pub title: Option<String>,
    /// States: name, marker; the first is initial.
    pub states: Vec<(Name, Marker)>,
    /// `FROM -> TO: PATTERN`.
    pub transitions: Vec<PurposeTransitionDecl>,
}

/// How a purpose state is marked.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Marker {
    /// An ordinary state.
    None,
    /// The purpose is reached.
    Accept,
    /// This part of the specification is cut away.
    Refuse,
}

/// A purpose transition.
#[derive(Debug, Clone, PartialEq)]
pub struct PurposeTransitionDecl {
    /// Source state.
    pub from: Name,
    /// Target state.
    pub to: Name,
    /// What it matches.
    pub pattern: LabelPatternDecl,
    /// Where it is.
    pub span: Span,
}

/// A pattern over labels in a purpose.
#[derive(Debug, Clone, PartialEq)]
pub enum LabelPatternDecl {
    /// `*`: any label no other transition of the state matches.
    Otherwise,
    /// `quiescence`: the device stayed silent.
    Quiescence,
    /// `in GATE(...)` / `out GATE(...)` / `GATE(...)` with optional `when` predicate.
    Gate {
        /// Direction, if written.
        direction: Option<Direction>,
        /// The gate and field patterns.
        action: Action,
        /// A predicate over the field names.
        guard: Option<Expr>,
    },
}

/// An expression.
#[derive(Debug, Clone, PartialEq)]
pub struct Expr {
    /// What it is.
    pub kind: ExprKind,
    /// Where it is.
    pub span: Span,
}

/// The kinds of expression.
#[derive(Debug, Clone, PartialEq)]
pub enum ExprKind {
    /// A number (durations in microseconds).
    Int(i64),
    /// `true` or `false`.
    Bool(bool),
    /// `$NODEID`.
    NodeId,
    /// A name: a parameter, constant, `let`, own variable or field.
    Name(String),
    /// `process.variable`.
    Member(String, String),
    /// `process@Location` or `process@{A, B}`.
    At(String, Vec<Name>),
    /// A unary operator (`!`, `-`).
    Unary(&'static str, Box<Expr>),
    /// A binary operator.
    Binary(&'static str, Box<Expr>, Box<Expr>),
    /// `e in {a, b}` or `e in lo..hi`.
    In(Box<Expr>, Vec<Expr>),
    /// `e in lo..hi`.
    InRange(Box<Expr>, Box<Expr>, Box<Expr>),
    /// `if c then a else b`.
    If(Box<Expr>, Box<Expr>, Box<Expr>),
    /// `f(args)`: `od`, `exists`, `min`, `max`, `pdo_bytes`, `accepted`.
    Call(String, Vec<Expr>),
}

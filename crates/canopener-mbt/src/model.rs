//! A compiled model: the composition of one or more model files with every name resolved, every
//! parameter evaluated and every check passed. This is what exploration, synthesis and the executor
//! work on.
//!
//! The state of a model is one vector of integers: per process its location, then its variables.
//! Clocks are not part of it: the untimed semantics ignores them and the timed tracker keeps their
//! reset instants beside the vector.

use canopener_eds::diag::Span;

use crate::expr::CExpr;
use crate::syntax::ast::Direction;

/// A compiled model.
#[derive(Debug, Clone)]
pub struct Model {
    /// The model files composed, in the order they were loaded (used models first).
    pub files: Vec<ModelFile>,
    /// The parameters with their values, `NODEID` first, then each file's as `model.NAME`.
    pub params: Vec<(String, i64)>,
    /// The gates.
    pub gates: Vec<Gate>,
    /// The clocks; each belongs to the file that declares it (two files' `cmd` are two clocks).
    pub clocks: Vec<String>,
    /// The hidden events (`event NAME`), by name across the files.
    pub events: Vec<String>,
    /// The components of the composition, one per model file (see [`crate::compose`]).
    pub components: Vec<Component>,
    /// The processes.
    pub processes: Vec<Process>,
    /// Every transition of every process; processes refer to theirs by index.
    pub transitions: Vec<Transition>,
    /// The default quiescence bound, in microseconds.
    pub quiescence_us: i64,
    /// The stimuli that bring the device into the initial state, in order.
    pub resets: Vec<crate::label::Label>,
    /// The test purposes defined in the files.
    pub purposes: Vec<crate::purpose::Purpose>,
    /// The initial state vector.
    pub initial: Vec<i64>,
    /// SHA-256 of the composed sources and the parameter values, hex: the model hash of logs.
    pub hash: String,
}

/// One model file of a composition.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ModelFile {
    /// `model NAME`.
    pub name: String,
    /// `title`.
    pub title: String,
    /// `cite` lines.
    pub cites: Vec<String>,
    /// Where it came from: a shipped model's name or a path, for messages.
    pub origin: String,
}

/// One model file of a composition as a component: what it declares and what it holds.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Component {
    /// Index into [`Model::files`].
    pub file: usize,
    /// The gates the file declares: its alphabet of frames.
    pub gates: Vec<usize>,
    /// The hidden events the file declares.
    pub events: Vec<usize>,
    /// Its processes.
    pub processes: Vec<usize>,
    /// The transitions of its processes.
    pub transitions: Vec<usize>,
    /// Its own `reset` stimuli (the run sends every component's, each distinct one once).
    pub resets: Vec<crate::label::Label>,
}

/// A gate: one kind of CAN frame.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Gate {
    /// The name.
    pub name: String,
    /// Input (the tester sends) or output (the device sends).
    pub direction: Direction,
    /// The 11-bit CAN-ID.
    pub cob_id: u16,
    /// A remote frame.
    pub remote: bool,
    /// The fields in byte order.
    pub fields: Vec<Field>,
    /// Data length: the sum of the fields' sizes.
    pub dlc: u8,
}

impl Gate {
    /// The frames this gate names: CAN-ID, remote flag, length and direction. Two gates with the
    /// same key (declared under different names) name the same frames, so components that declare
    /// either synchronise on them.
    pub fn frame_key(&self) -> (u16, bool, u8, Direction) {
        (self.cob_id, self.remote, self.dlc, self.direction)
    }
}

/// A field of a gate.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Field {
    /// The name.
    pub name: String,
    /// Size in bytes (1..=8).
    pub size: u8,
    /// `bytes(N)`: only `_` matches it; its value is the bytes as a little-endian number.
    pub opaque: bool,
}

/// A process: locations, variables and transitions.
#[derive(Debug, Clone)]
pub struct Process {
    /// The name.
    pub name: String,
    /// The model file it comes from (index into [`Model::files`]).
    pub file: usize,
    /// Its locations; the first is the initial one.
    pub locations: Vec<Location>,
    /// The slot of the state vector holding the location number.
    pub location_slot: usize,
    /// Its variables.
    pub vars: Vec<Var>,
    /// Its transitions (indices into [`Model::transitions`]).
    pub transitions: Vec<usize>,
}

/// A location.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Location {
    /// The name.
    pub name: String,
    /// Its own quiescence bound in microseconds, if any.
    pub quiescence_us: Option<i64>,
}

/// A variable.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Var {
    /// The name.
    pub name: String,
    /// Its slot in the state vector.
    pub slot: usize,
    /// Smallest value.
    pub lo: i64,
    /// Largest value.
    pub hi: i64,
    /// A boolean (printed as true/false).
    pub boolean: bool,
}

/// What a transition does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Kind {
    /// The tester sends.
    Input,
    /// The device must send within the window.
    Output,
    /// The device may send within the window.
    MaybeOutput,
    /// The device changes state without a frame: at once, or within its window.
    Internal,
    /// `signal EVENT`: an internal step every component declaring the event takes part in.
    Signal,
    /// `on EVENT`: takes part in another component's `signal EVENT`; never happens alone.
    On,
}

impl Kind {
    /// Whether the device sends a frame.
    pub fn is_output(self) -> bool {
        matches!(self, Kind::Output | Kind::MaybeOutput)
    }

    /// Whether the step is unobservable (no frame): internal steps and hidden events.
    pub fn is_hidden(self) -> bool {
        matches!(self, Kind::Internal | Kind::Signal | Kind::On)
    }
}

/// What a field of a transition's label may be.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum CPattern {
    /// Any value.
    Any,
    /// Exactly this value.
    Value(CExpr),
    /// One of these values.
    Set(Vec<CExpr>),
    /// A value in this inclusive range.
    Range(CExpr, CExpr),
}

/// A transition.
#[derive(Debug, Clone)]
pub struct Transition {
    /// Its index in [`Model::transitions`].
    pub id: usize,
    /// The process it belongs to.
    pub process: usize,
    /// Source locations; empty means every location.
    pub from: Vec<i64>,
    /// Target location; `None` stays.
    pub to: Option<i64>,
    /// What it does.
    pub kind: Kind,
    /// The gate, for inputs and outputs.
    pub gate: Option<usize>,
    /// The hidden event, for `signal` and `on`.
    pub event: Option<usize>,
    /// An input that follows another component's input and is never chosen for its own sake.
    pub passive: bool,
    /// A passive input taken only when no other input transition of the component takes the label.
    pub otherwise: bool,
    /// One pattern per field of the gate.
    pub patterns: Vec<CPattern>,
    /// The guard (reads the label's fields for inputs).
    pub guard: Option<CExpr>,
    /// Assignments, evaluated on the state before the transition: slot, value, domain.
    pub updates: Vec<(usize, CExpr, i64, i64)>,
    /// Clocks reset to the instant of the transition.
    pub resets: Vec<usize>,
    /// The time window: earliest, latest, clock.
    pub window: Option<(CExpr, CExpr, usize)>,
    /// Requirement tags.
    pub tags: Vec<String>,
    /// Where it is written (in its file).
    pub span: Span,
}

/// The entry `id` names in one of a compiled model's tables, or in a table made to the size of one
/// (a state vector, the instants of the clocks). Every id a [`Model`] holds (of a file, gate,
/// component, process, transition, clock or state slot) is the position at which `compile` pushed
/// that entry, only `compile` makes a `Model`, and the tables made beside it take its sizes
/// (`initial` for states, `clocks` for instants) and keep them.
#[allow(
    clippy::indexing_slicing,
    reason = "a compiled model's ids are positions compile pushed to the table they name, and the tables made beside a model take its sizes"
)]
pub(crate) fn at<T>(table: &[T], id: usize) -> &T {
    &table[id]
}

/// [`at`], to write.
#[allow(
    clippy::indexing_slicing,
    reason = "a compiled model's ids are positions compile pushed to the table they name, and the tables made beside a model take its sizes"
)]
pub(crate) fn at_mut<T>(table: &mut [T], id: usize) -> &mut T {
    &mut table[id]
}

impl Model {
    /// Model file `f` (panics when this model has no such file; every file id it holds is one).
    pub fn file_at(&self, f: usize) -> &ModelFile {
        at(&self.files, f)
    }

    /// Gate `g` (panics when this model has no such gate; every gate id it holds is one).
    pub fn gate_at(&self, g: usize) -> &Gate {
        at(&self.gates, g)
    }

    /// Component `c` (panics when this model has no such component; every component id it holds is
    /// one).
    pub fn component_at(&self, c: usize) -> &Component {
        at(&self.components, c)
    }

    /// Process `p` (panics when this model has no such process; every process id it holds is one).
    pub fn process_at(&self, p: usize) -> &Process {
        at(&self.processes, p)
    }

    /// Transition `t` (panics when this model has no such transition; every transition id it holds is
    /// one).
    pub fn transition_at(&self, t: usize) -> &Transition {
        at(&self.transitions, t)
    }

    /// The composed name: the model names joined with `+`.
    pub fn name(&self) -> String {
        self.files
            .iter()
            .map(|f| f.name.as_str())
            .collect::<Vec<_>>()
            .join("+")
    }

    /// The gate called `name`.
    pub fn gate(&self, name: &str) -> Option<usize> {
        self.gates.iter().position(|g| g.name == name)
    }

    /// A parameter's value: `NODEID`, `nmt.HB` (a file's parameter), or `HB` (the first file's that
    /// has one).
    pub fn param(&self, name: &str) -> Option<i64> {
        self.params
            .iter()
            .find(|(n, _)| n == name || n.rsplit_once('.').is_some_and(|(_, short)| short == name))
            .map(|(_, v)| *v)
    }

    /// The node-ID the model is instantiated for.
    pub fn node_id(&self) -> u8 {
        self.param("NODEID")
            .and_then(|v| u8::try_from(v).ok())
            .unwrap_or(0)
    }

    /// How many locations all processes have together.
    pub fn location_count(&self) -> usize {
        self.processes.iter().map(|p| p.locations.len()).sum()
    }

    /// `process.location` for the location number `loc` of process `p`.
    pub fn location_name(&self, p: usize, loc: i64) -> String {
        let process = self.process_at(p);
        let name = usize::try_from(loc)
            .ok()
            .and_then(|l| process.locations.get(l))
            .map_or("?", |l| l.name.as_str());
        format!("{}.{name}", process.name)
    }

    /// A state vector in words: `nmt@PreOperational hb@Running period=100`.
    pub fn describe_state(&self, state: &[i64]) -> String {
        let mut parts = Vec::new();
        for process in &self.processes {
            let loc = *at(state, process.location_slot);
            let name = usize::try_from(loc)
                .ok()
                .and_then(|l| process.locations.get(l))
                .map_or("?", |l| l.name.as_str());
            parts.push(format!("{}@{name}", process.name));
            for var in &process.vars {
                let value = *at(state, var.slot);
                if var.boolean {
                    parts.push(format!("{}.{}={}", process.name, var.name, value != 0));
                } else {
                    parts.push(format!("{}.{}={value}", process.name, var.name));
                }
            }
        }
        parts.join(" ")
    }

    /// The quiescence bound of a state: the largest bound of its processes' locations (a location
    /// without its own has the model's).
    pub fn quiescence_of(&self, state: &[i64]) -> i64 {
        self.processes
            .iter()
            .map(|p| {
                usize::try_from(*at(state, p.location_slot))
                    .ok()
                    .and_then(|loc| p.locations.get(loc)?.quiescence_us)
                    .unwrap_or(self.quiescence_us)
            })
            .max()
            .unwrap_or(self.quiescence_us)
    }
}

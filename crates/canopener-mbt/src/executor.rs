//! The on-the-fly tester: ioco (uioco for partial models) with timed quiescence, as a sans-IO
//! [`Core`]. Frames and time go in, stimuli and one verdict come out.
//!
//! The TorX structure: the *explorer* is the configuration set below (every state the
//! specification may be in after the trace so far, each with its clocks); the *IO-chooser* picks,
//! at each decision point, between sending an input and observing (seeded, uniform or
//! coverage-guided); the *instantiator* turns a chosen label into a frame (little-endian fields in
//! order); the *adapter* is whoever drives this core on a `Link` (the runtime).
//!
//! Time (design note §6.5): every output has a window `LO..HI` after a clock's last reset; a
//! configuration whose enabled must-outputs all passed their `HI` (plus the tolerance) is dropped,
//! so a missing or late output empties the set: `fail`, naming the outputs that were due. An output
//! before its `LO` is `fail` too. Waiting the quiescence bound without an output is the observation
//! δ. Only inputs every configuration accepts are sent (uioco); frames on CAN-IDs the model has no
//! output gate for are not judged (a partial model speaks only about its own frames).

use std::collections::{BTreeSet, VecDeque};

use canopener_can::{CanFrame, Core, Instant, StandardId};
use serde::Serialize;

use crate::compose::Blocked;
use crate::label::{Label, LabelText};
use crate::model::{Kind, Model, at, at_mut};
use crate::purpose::{Purpose, Seen};
use crate::syntax::ast::{Direction, Marker};

/// How many configurations the set may hold before the run stops as inconclusive.
pub const MAX_CONFIGURATIONS: usize = 4096;

/// How many observation rounds a scripted input may wait to become allowed, and how many follow
/// the last one.
const SCRIPT_PATIENCE: usize = 8;

/// How the IO-chooser picks inputs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Strategy {
    /// Every allowed input equally likely.
    Uniform,
    /// Inputs of transitions not taken yet first, uniform among them.
    Coverage,
}

/// How a run is made.
#[derive(Debug, Clone, Serialize)]
pub struct RunConfig {
    /// The master seed: the same seed, model and device give the same run.
    pub seed: u64,
    /// Steps (inputs, outputs and quiescence observations) before the run passes.
    pub steps: usize,
    /// Added to every window's end and taken from its start: bus latency and timer jitter.
    pub tolerance_us: i64,
    /// How inputs are chosen.
    pub strategy: Strategy,
    /// Percent of decisions that send an input when one is allowed (the rest observe).
    pub input_percent: u8,
    /// After an output, how long the tester keeps listening before it decides, so that frames a
    /// device sends together (a boot-up and the heartbeat after it) are all seen first.
    pub settle_us: i64,
    /// A fixed input script instead of chosen inputs (replay and shrinking).
    #[serde(skip)]
    pub script: Option<Vec<ScriptStep>>,
    /// A test purpose: the run passes once it is reached (inconclusive if refused), and inputs that
    /// advance it are chosen first.
    #[serde(skip)]
    pub purpose: Option<Purpose>,
}

impl Default for RunConfig {
    fn default() -> RunConfig {
        RunConfig {
            seed: 1,
            steps: 200,
            tolerance_us: 2_000,
            strategy: Strategy::Coverage,
            input_percent: 60,
            settle_us: 5_000,
            script: None,
            purpose: None,
        }
    }
}

/// One input of a script: its label and, if recorded, when it was sent (µs after the start). A
/// timed input goes out at that offset or, if the model does not allow it yet, as soon as it does;
/// an untimed one as soon as the model allows it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, serde::Deserialize)]
pub struct ScriptStep {
    /// `?GATE !v ...`.
    pub label: String,
    /// Microseconds after the start of the run.
    pub at_us: Option<i64>,
}

impl From<&str> for ScriptStep {
    fn from(label: &str) -> ScriptStep {
        ScriptStep {
            label: label.to_owned(),
            at_us: None,
        }
    }
}

/// A verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    /// No observation contradicted the model.
    Pass,
    /// An observation the model does not allow (or a missing one).
    Fail,
    /// The run could not go on in a way that decides (no input allowed and nothing due, a scripted
    /// input the model no longer allows, too many configurations).
    Inconclusive,
}

/// Which way a trace step went.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Dir {
    /// The tester sent it.
    In,
    /// The device sent it.
    Out,
    /// The device stayed silent for the quiescence bound.
    Quiescence,
}

/// A frame as logged.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct FrameJson {
    /// `0x705`.
    pub id: String,
    /// Hex bytes, `05`; `R` and the DLC for remote frames.
    pub data: String,
}

/// One step of the trace.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TraceStep {
    /// Seconds since the start of the run.
    pub t: f64,
    /// Input, output or quiescence.
    pub dir: Dir,
    /// The label (`?NMT !0x01 !0x05`), or `quiescence`.
    pub label: String,
    /// The frame, if there was one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frame: Option<FrameJson>,
}

/// How a model-based run ended: the verdict, why, and the trace that decided it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunResult {
    /// The verdict.
    pub verdict: Verdict,
    /// Why, in words.
    pub reason: String,
    /// The trace, ending with the step that decided.
    pub trace: Vec<TraceStep>,
    /// For `fail`: the outputs (with their windows) the model allowed at that point.
    pub allowed: Vec<String>,
    /// The inputs the tester chose, in order (not the reset stimuli): the script to replay.
    pub inputs: Vec<String>,
    /// When each input was sent, µs after the start.
    pub input_times_us: Vec<i64>,
    /// Steps taken.
    pub steps: usize,
    /// How many frames the device sent that the model judged.
    pub outputs_seen: usize,
    /// Coverage.
    pub coverage: Coverage,
    /// The test purpose, if the run had one: its name and whether it was reached.
    pub purpose: Option<(String, bool)>,
}

impl RunResult {
    /// The run's inputs with their times: the script that replays it.
    pub fn script(&self) -> Vec<ScriptStep> {
        self.inputs
            .iter()
            .enumerate()
            .map(|(i, label)| ScriptStep {
                label: label.clone(),
                at_us: self.input_times_us.get(i).copied(),
            })
            .collect()
    }
}

/// What the run visited.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Coverage {
    /// Locations visited, all locations.
    pub locations: [usize; 2],
    /// Transitions taken, all transitions.
    pub transitions: [usize; 2],
    /// The transitions taken, by index.
    pub taken: Vec<usize>,
    /// Distinct state vectors visited.
    pub states_seen: usize,
}

/// A configuration: a specification state, the instant each clock was last reset, and whether its
/// urgent internal steps are done.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
struct Conf {
    state: Vec<i64>,
    clocks: Vec<i64>,
}

/// An obligation no device can meet: the transition that requires it and the component that
/// refuses it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Unmet {
    required: usize,
    refuser: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// Reset stimuli not sent yet.
    Start,
    /// Waiting for an output until this instant (µs), started at the second value.
    Observing(i64, i64),
    /// A decision is due at this instant.
    Deciding(i64),
    /// Done.
    Finished,
}

/// The on-the-fly tester for one model and one device.
#[derive(Debug)]
pub struct Executor<'m> {
    model: &'m Model,
    config: RunConfig,
    rng: u64,
    start: i64,
    confs: Vec<Conf>,
    phase: Phase,
    outbox: VecDeque<CanFrame>,
    trace: Vec<TraceStep>,
    steps: usize,
    outputs_seen: usize,
    taken: BTreeSet<usize>,
    locations: BTreeSet<(usize, i64)>,
    states: BTreeSet<Vec<i64>>,
    inputs_sent: Vec<String>,
    input_times: Vec<i64>,
    script_pos: usize,
    script_waits: usize,
    waiting_for_script: bool,
    purpose_state: usize,
    outcome: Option<RunResult>,
    reported: bool,
    /// The last instant the internal steps were taken for: windows opening later are due then.
    closed_at: i64,
}

impl<'m> Executor<'m> {
    /// A tester that starts at `start` by sending the model's reset stimuli.
    pub fn new(model: &'m Model, config: RunConfig, start: Instant) -> Executor<'m> {
        let start = micros(start);
        let mut rng = config.seed ^ 0x9E37_79B9_7F4A_7C15;
        next(&mut rng);
        let initial = Conf {
            state: model.initial.clone(),
            clocks: vec![start; model.clocks.len()],
        };
        let mut exec = Executor {
            model,
            config,
            rng,
            start,
            confs: Vec::new(),
            phase: Phase::Start,
            outbox: VecDeque::new(),
            trace: Vec::new(),
            steps: 0,
            outputs_seen: 0,
            taken: BTreeSet::new(),
            locations: BTreeSet::new(),
            states: BTreeSet::new(),
            inputs_sent: Vec::new(),
            input_times: Vec::new(),
            script_pos: 0,
            script_waits: 0,
            waiting_for_script: false,
            purpose_state: 0,
            outcome: None,
            reported: false,
            closed_at: start,
        };
        exec.confs = exec.closure(vec![initial], start);
        exec.visit();
        exec
    }

    /// Steps taken so far (for a progress display).
    pub fn steps_taken(&self) -> usize {
        self.steps
    }

    /// The outcome, once the run is over.
    pub fn outcome(&self) -> Option<&RunResult> {
        self.outcome.as_ref()
    }

    /// Ends the run now (the driver's deadline): `pass` if nothing failed so far.
    pub fn finish(&mut self, reason: &str) -> RunResult {
        match &self.outcome {
            Some(outcome) => outcome.clone(),
            None => self.conclude(Verdict::Pass, reason.to_owned(), Vec::new()),
        }
    }

    fn rand(&mut self, below: usize) -> usize {
        (next(&mut self.rng) % below.max(1) as u64) as usize
    }

    fn t(&self, now: i64) -> f64 {
        (now - self.start) as f64 / 1e6
    }

    fn visit(&mut self) {
        for c in &self.confs {
            for p in &self.model.processes {
                self.locations
                    .insert((p.location_slot, *at(&c.state, p.location_slot)));
            }
            self.states.insert(c.state.clone());
        }
    }

    /// Adds internal successors until nothing new: an internal step (or hidden event) without a
    /// window happens at once (its source is left); one with a window may happen once its window
    /// has opened at `now` and may still be pending until it closes (both are kept: the deadline
    /// drops the source then). A hidden event happens only with every component that declares it.
    fn closure(&mut self, confs: Vec<Conf>, now: i64) -> Vec<Conf> {
        self.closed_at = self.closed_at.max(now);
        let mut taken = BTreeSet::new();
        let out = self.closed(confs, now, &mut taken);
        self.taken.extend(taken);
        out
    }

    /// [`Executor::closure`] without recording anything: the configurations and, in `taken`, the
    /// internal transitions on the way.
    fn closed(&self, confs: Vec<Conf>, now: i64, taken: &mut BTreeSet<usize>) -> Vec<Conf> {
        let mut out: Vec<Conf> = Vec::new();
        let mut work = confs;
        let mut guard = 0;
        while let Some(c) = work.pop() {
            guard += 1;
            if guard > MAX_CONFIGURATIONS * 4 {
                break;
            }
            let mut urgent = false;
            for t in &self.model.transitions {
                if !matches!(t.kind, Kind::Internal | Kind::Signal) || !self.model.located(t, &c.state) {
                    continue;
                }
                if !self.model.guard_holds(t, &c.state, &[]).unwrap_or(false) {
                    continue;
                }
                if self.opens_at(t, &c).is_some_and(|at| at > now) {
                    continue;
                }
                let Ok(joint) = self.model.signal_joint(&c.state, t.id) else {
                    continue;
                };
                for j in joint {
                    urgent |= t.window.is_none();
                    let n = Conf {
                        state: j.state,
                        clocks: c.clocks.clone(),
                    };
                    if !out.contains(&n) && !work.contains(&n) {
                        work.push(n);
                    }
                    taken.extend(j.transitions);
                }
            }
            if !urgent && !out.contains(&c) {
                out.push(c);
            }
        }
        out.sort();
        out.dedup();
        out
    }

    /// When the window of a windowed internal step opens in configuration `c` (its `LO` less the
    /// tolerance); `None` for a step without a window.
    fn opens_at(&self, t: &crate::model::Transition, c: &Conf) -> Option<i64> {
        let (lo, _, clock) = t.window.as_ref()?;
        let lo = lo.eval(&c.state, &[]).ok()?;
        Some(*at(&c.clocks, *clock) + lo - self.config.tolerance_us)
    }

    /// The next instant after `now` at which an internal step of some configuration becomes
    /// possible: the closure must be taken again then.
    fn next_opening(&self, now: i64) -> Option<i64> {
        self.confs
            .iter()
            .flat_map(|c| {
                self.model.transitions.iter().filter_map(move |t| {
                    if !matches!(t.kind, Kind::Internal | Kind::Signal)
                        || !self.model.located(t, &c.state)
                        || !self.model.guard_holds(t, &c.state, &[]).unwrap_or(false)
                    {
                        return None;
                    }
                    self.opens_at(t, c).filter(|at| *at > now)
                })
            })
            .min()
    }

    /// The instant by which this configuration must have moved on: processes interleave, so each
    /// process with enabled must-outputs (or windowed internal steps) owes one of them by the latest
    /// end of their windows, and the configuration is due at the earliest of those; `None` if it
    /// may stay silent.
    fn deadline(&self, c: &Conf) -> Option<i64> {
        let mut per_process: Vec<Option<i64>> = vec![None; self.model.processes.len()];
        for t in &self.model.transitions {
            let must = t.kind == Kind::Output
                || (matches!(t.kind, Kind::Internal | Kind::Signal) && t.window.is_some());
            if !must
                || !self.model.located(t, &c.state)
                || !self.model.guard_holds(t, &c.state, &[]).unwrap_or(false)
            {
                continue;
            }
            if t.gate.is_some() && self.model.offers(t, &c.state).map_or(true, |o| o.is_empty()) {
                continue;
            }
            if let Some((_, hi, clock)) = &t.window
                && let Ok(hi) = hi.eval(&c.state, &[])
            {
                let end = *at(&c.clocks, *clock) + hi + self.config.tolerance_us;
                let slot = at_mut(&mut per_process, t.process);
                *slot = Some(slot.map_or(end, |l| l.max(end)));
            }
        }
        per_process.into_iter().flatten().min()
    }

    /// The outputs a configuration allows, with their windows in seconds since the start.
    fn allowed(&self, confs: &[Conf]) -> Vec<String> {
        let mut out = BTreeSet::new();
        for c in confs {
            for t in &self.model.transitions {
                if !t.kind.is_output()
                    || !self.model.located(t, &c.state)
                    || !self.model.guard_holds(t, &c.state, &[]).unwrap_or(false)
                {
                    continue;
                }
                let Some(gate) = t.gate else { continue };
                for values in self.model.offers(t, &c.state).unwrap_or_default() {
                    let label = self.model.label_text(&Label { gate, values });
                    let window = match &t.window {
                        Some((lo, hi, clock)) => {
                            let base = *at(&c.clocks, *clock);
                            match (lo.eval(&c.state, &[]), hi.eval(&c.state, &[])) {
                                (Ok(lo), Ok(hi)) => {
                                    format!(" at {:.3}s..{:.3}s", self.t(base + lo), self.t(base + hi))
                                }
                                _ => String::new(),
                            }
                        }
                        None => String::new(),
                    };
                    let may = if t.kind == Kind::MaybeOutput { " (may)" } else { "" };
                    out.insert(format!("{label}{window}{may}"));
                }
            }
        }
        out.into_iter().collect()
    }

    fn conclude(&mut self, verdict: Verdict, reason: String, allowed: Vec<String>) -> RunResult {
        self.phase = Phase::Finished;
        self.outbox.clear();
        let taken: Vec<usize> = self.taken.iter().copied().collect();
        let purpose = self
            .config
            .purpose
            .as_ref()
            .map(|p| (p.name.clone(), p.marker(self.purpose_state) == Marker::Accept));
        let outcome = RunResult {
            verdict,
            reason,
            trace: self.trace.clone(),
            allowed,
            inputs: self.inputs_sent.clone(),
            input_times_us: self.input_times.clone(),
            steps: self.steps,
            outputs_seen: self.outputs_seen,
            coverage: Coverage {
                locations: [self.locations.len(), self.model.location_count()],
                transitions: [taken.len(), self.model.transitions.len()],
                taken,
                states_seen: self.states.len(),
            },
            purpose,
        };
        self.outcome = Some(outcome.clone());
        outcome
    }

    /// Takes the internal steps whose windows opened by `now`, then drops configurations whose
    /// deadline passed before `now`; fails if none is left.
    fn expire(&mut self, now: i64) -> bool {
        let confs = std::mem::take(&mut self.confs);
        self.confs = self.closure(confs, now);
        let (alive, dead): (Vec<Conf>, Vec<Conf>) = std::mem::take(&mut self.confs)
            .into_iter()
            .partition(|c| self.deadline(c).is_none_or(|d| d >= now));
        if alive.is_empty() {
            // A deadline no device could meet (another component forbids what was due) is the
            // models' fault, not the device's.
            let before = std::mem::replace(&mut self.confs, dead.clone());
            let disagreement = self.disagreement(None);
            self.confs = before;
            if let Some(reason) = disagreement {
                let allowed = self.allowed(&dead);
                let _ = self.conclude(Verdict::Inconclusive, reason, allowed);
                return false;
            }
        }
        self.confs = alive;
        if self.confs.is_empty() {
            let allowed = self.allowed(&dead);
            let reason = format!(
                "missing output: nothing the model requires came by {:.3}s",
                self.t(now)
            );
            let _ = self.conclude(Verdict::Fail, reason, allowed);
            return false;
        }
        true
    }

    fn count_step(&mut self, now: i64) {
        self.steps += 1;
        if self.steps >= self.config.steps && self.outcome.is_none() {
            let reason = format!("{} steps without a failure", self.steps);
            let _ = self.conclude(Verdict::Pass, reason, Vec::new());
        } else if self.outcome.is_none() {
            self.waiting_for_script = false;
            self.phase = Phase::Deciding(now + self.config.settle_us);
        }
    }

    /// The output gates a frame may be a label of, with its field values.
    fn decode(&self, frame: &CanFrame) -> Vec<(usize, Vec<i64>)> {
        let id = frame.id();
        if id.is_extended() {
            return Vec::new();
        }
        let raw = id.as_raw() as u16;
        let mut out = Vec::new();
        for (g, gate) in self.model.gates.iter().enumerate() {
            if gate.direction != Direction::Output || gate.cob_id != raw || gate.remote != frame.is_remote() {
                continue;
            }
            if frame.dlc() != gate.dlc {
                continue;
            }
            let data = frame.data();
            let mut values = Vec::new();
            let mut at = 0usize;
            for f in &gate.fields {
                let mut v: i64 = 0;
                for i in 0..usize::from(f.size) {
                    v |= i64::from(data.get(at + i).copied().unwrap_or(0)) << (8 * i);
                }
                at += usize::from(f.size);
                values.push(v);
            }
            out.push((g, values));
        }
        out
    }

    fn is_output_id(&self, frame: &CanFrame) -> bool {
        !frame.id().is_extended()
            && self
                .model
                .gates
                .iter()
                .any(|g| g.direction == Direction::Output && u32::from(g.cob_id) == frame.id().as_raw())
    }

    fn observe(&mut self, now: i64, frame: &CanFrame) {
        if !self.is_output_id(frame) {
            return;
        }
        if !self.expire(now) {
            return;
        }
        let decoded = self.decode(frame);
        let label = decoded.first().map_or_else(
            || format!("frame {}", frame_text(frame)),
            |(g, v)| format!("!{}", self.model.label_text(&Label::concrete(*g, v))),
        );
        self.trace.push(TraceStep {
            t: self.t(now),
            dir: Dir::Out,
            label,
            frame: Some(frame_json(frame)),
        });
        self.outputs_seen += 1;
        let mut next = Vec::new();
        let mut early = false;
        let mut refused: Option<(usize, Vec<i64>)> = None;
        let tol = self.config.tolerance_us;
        if let Some((g, values)) = decoded.first() {
            let open: Vec<Option<i64>> = values.iter().copied().map(Some).collect();
            for c in &self.confs {
                // Every component holding the frame must take it within its own window: the
                // windows of a synchronised output intersect.
                let mut admit = |t: &crate::model::Transition| -> bool {
                    let Some((lo, hi, clock)) = &t.window else {
                        return true;
                    };
                    let since = now - *at(&c.clocks, *clock);
                    let (Ok(lo), Ok(hi)) = (lo.eval(&c.state, values), hi.eval(&c.state, values)) else {
                        return false;
                    };
                    if since < lo - tol {
                        early = true;
                        return false;
                    }
                    since <= hi + tol
                };
                match self.model.output_joint(&c.state, *g, &open, &mut admit) {
                    Ok(joint) => {
                        for j in joint {
                            let mut clocks = c.clocks.clone();
                            for t in &j.transitions {
                                for r in &self.model.transition_at(*t).resets {
                                    *at_mut(&mut clocks, *r) = now;
                                }
                            }
                            self.taken.extend(j.transitions.iter().copied());
                            next.push(Conf {
                                state: j.state,
                                clocks,
                            });
                        }
                    }
                    Err(Blocked::Refused(component)) => {
                        refused.get_or_insert((component, c.state.clone()));
                    }
                    Err(Blocked::Error(..)) => {}
                }
            }
        }
        if next.is_empty() {
            if let Some(reason) = self.disagreement(Some(now)) {
                let allowed = self.allowed(&self.confs.clone());
                let _ = self.conclude(Verdict::Inconclusive, reason, allowed);
                return;
            }
            let allowed = self.allowed(&self.confs.clone());
            let what = match (&refused, early) {
                (_, true) => "too early".to_owned(),
                (Some((component, state)), false) if self.model.components.len() > 1 => format!(
                    "not allowed here ({} refuses it in {})",
                    self.model.file_at(*component).name,
                    self.model.component_state(*component, state)
                ),
                _ => "not allowed here".to_owned(),
            };
            let reason = format!(
                "unexpected output {} at {:.3}s: {what}",
                frame_text(frame),
                self.t(now)
            );
            let _ = self.conclude(Verdict::Fail, reason, allowed);
            return;
        }
        self.confs = self.closure(next, now);
        self.visit();
        if self.confs.len() > MAX_CONFIGURATIONS {
            let _ = self.conclude(
                Verdict::Inconclusive,
                "the model allows too many states at once".into(),
                Vec::new(),
            );
            return;
        }
        // The label the purpose sees: the first gate the frame decodes as that an output took.
        let seen = decoded
            .iter()
            .find_map(|(g, v)| LabelText::parse(&self.model.label_text(&Label::concrete(*g, v))));
        if let Some(text) = seen
            && self.purpose_step(Seen::Label(Some(Direction::Output), &text))
        {
            return;
        }
        self.count_step(now);
    }

    /// Input labels the composition accepts in every configuration (uioco) and after which every
    /// obligation can still be met (no component then requires an output another forbids), with
    /// the transitions behind them. Passive inputs follow other components and are not proposed.
    fn inputs(&self, now: i64) -> Vec<(Label, Vec<usize>)> {
        let Some(first) = self.confs.first() else {
            return Vec::new();
        };
        let mut candidates: Vec<(Label, Vec<usize>)> = Vec::new();
        for t in &self.model.transitions {
            if t.kind != Kind::Input || t.passive || !self.model.located(t, &first.state) {
                continue;
            }
            let Some(gate) = t.gate else { continue };
            for values in self.model.offers(t, &first.state).unwrap_or_default() {
                let label = Label {
                    gate,
                    values: values.iter().map(|v| Some(v.unwrap_or(0))).collect(),
                };
                match candidates.iter_mut().find(|(l, _)| *l == label) {
                    Some((_, ts)) => ts.push(t.id),
                    None => candidates.push((label, vec![t.id])),
                }
            }
        }
        candidates.retain(|(label, _)| {
            self.confs.iter().all(|c| {
                let next: Vec<Conf> = self
                    .input_successors(c, label, now)
                    .into_iter()
                    .map(|(_, n)| n)
                    .collect();
                if next.is_empty() {
                    return false;
                }
                let after = self.closed(next, now, &mut BTreeSet::new());
                after.iter().all(|n| self.unanswerable(n, Some(now)).is_none())
            })
        });
        candidates
    }

    /// The configurations after the input `label` from `c`, each with the transitions taken, and
    /// their internal successors.
    fn input_successors(&self, c: &Conf, label: &Label, now: i64) -> Vec<(Vec<usize>, Conf)> {
        let values: Vec<i64> = label.values.iter().map(|v| v.unwrap_or(0)).collect();
        let Ok(joint) = self.model.input_joint(&c.state, label.gate, &values) else {
            return Vec::new();
        };
        joint
            .into_iter()
            .map(|j| {
                let mut clocks = c.clocks.clone();
                for t in &j.transitions {
                    for r in &self.model.transition_at(*t).resets {
                        *at_mut(&mut clocks, *r) = now;
                    }
                }
                (
                    j.transitions,
                    Conf {
                        state: j.state,
                        clocks,
                    },
                )
            })
            .collect()
    }

    /// An obligation of `c` that cannot be met: a process owes an output (or a hidden event) by a
    /// deadline, and for every way it has to meet it another component holding the frame refuses
    /// it, or accepts it only outside the window. `None` if every obligation can be met. With
    /// `now`, only what can still happen from then on counts; without it, the windows alone (for a
    /// configuration whose deadline passed).
    fn unanswerable(&self, c: &Conf, now: Option<i64>) -> Option<Unmet> {
        let tol = self.config.tolerance_us;
        let mut owed: Vec<(usize, Vec<usize>)> = Vec::new();
        for t in &self.model.transitions {
            let must = t.kind == Kind::Output || (t.kind == Kind::Signal && t.window.is_some());
            if !must
                || !self.model.located(t, &c.state)
                || !self.model.guard_holds(t, &c.state, &[]).unwrap_or(false)
            {
                continue;
            }
            match owed.iter_mut().find(|(p, _)| *p == t.process) {
                Some((_, ts)) => ts.push(t.id),
                None => owed.push((t.process, vec![t.id])),
            }
        }
        for (_, ts) in owed {
            let mut first_refusal = None;
            let answerable = ts.iter().any(|&t| {
                let t = self.model.transition_at(t);
                if t.kind == Kind::Signal {
                    return match self.model.signal_joint(&c.state, t.id) {
                        Ok(j) => !j.is_empty(),
                        Err(b) => {
                            first_refusal.get_or_insert((t.id, b.component()));
                            false
                        }
                    };
                }
                let Some(gate) = t.gate else { return true };
                let window = |u: &crate::model::Transition| -> (i64, i64) {
                    match &u.window {
                        Some((lo, hi, clock)) => {
                            let base = *at(&c.clocks, *clock);
                            match (lo.eval(&c.state, &[]), hi.eval(&c.state, &[])) {
                                (Ok(lo), Ok(hi)) => (base + lo - tol, base + hi + tol),
                                _ => (i64::MIN, i64::MAX),
                            }
                        }
                        None => (i64::MIN, i64::MAX),
                    }
                };
                let (lo, hi) = window(t);
                let offers = self.model.offers(t, &c.state).unwrap_or_default();
                if now.is_some_and(|now| hi < now) || offers.is_empty() {
                    // Already overdue or not offered: the deadline decides, not a disagreement.
                    return true;
                }
                offers.iter().any(|values| {
                    // The other holders must accept the output at a time inside t's window.
                    let own = self.model.component_of(t);
                    let mut admit = |u: &crate::model::Transition| {
                        if self.model.component_of(u) == own {
                            return u.id == t.id;
                        }
                        let (ulo, uhi) = window(u);
                        lo.max(ulo).max(now.unwrap_or(i64::MIN)) <= hi.min(uhi)
                    };
                    match self.model.output_joint(&c.state, gate, values, &mut admit) {
                        Ok(j) => !j.is_empty(),
                        Err(b) => {
                            first_refusal.get_or_insert((t.id, b.component()));
                            false
                        }
                    }
                })
            });
            if !answerable && let Some((required, Some(refuser))) = first_refusal {
                return Some(Unmet { required, refuser });
            }
        }
        None
    }

    /// If a configuration holds an obligation another component forbids, the verdict cannot be
    /// `fail`: the reason, naming both sides.
    fn disagreement(&self, now: Option<i64>) -> Option<String> {
        self.confs.iter().find_map(|c| {
            let unmet = self.unanswerable(c, now)?;
            let t = self.model.transition_at(unmet.required);
            let file = self.model.file_at(self.model.component_of(t));
            let refuser = self.model.file_at(unmet.refuser);
            let what = match t.gate {
                Some(g) => {
                    let values = self.model.offers(t, &c.state).unwrap_or_default();
                    let label = Label {
                        gate: g,
                        values: values.into_iter().next().unwrap_or_default(),
                    };
                    self.model.label_text(&label)
                }
                None => "its hidden event".to_owned(),
            };
            Some(format!(
                "the models disagree: {} ({}:{}) requires {what}, which {} refuses in {}; no device can satisfy both",
                file.name,
                file.origin,
                t.span.line,
                refuser.name,
                self.model.component_state(unmet.refuser, &c.state)
            ))
        })
    }

    fn send(&mut self, now: i64, label: &Label) {
        let gate = self.model.gate_at(label.gate);
        let mut data = Vec::new();
        for (f, v) in gate.fields.iter().zip(&label.values) {
            let v = v.unwrap_or(0);
            for i in 0..usize::from(f.size) {
                data.push((v >> (8 * i)) as u8);
            }
        }
        let id = StandardId::new(gate.cob_id).unwrap_or(StandardId::ZERO);
        let frame = if gate.remote {
            CanFrame::remote(id, gate.dlc)
        } else {
            CanFrame::new(id, &data)
        };
        let Ok(frame) = frame else { return };
        let mut next = Vec::new();
        for c in &self.confs {
            for (ts, n) in self.input_successors(c, label, now) {
                self.taken.extend(ts);
                next.push(n);
            }
        }
        self.trace.push(TraceStep {
            t: self.t(now),
            dir: Dir::In,
            label: format!("?{}", self.model.label_text(label)),
            frame: Some(frame_json(&frame)),
        });
        self.outbox.push_back(frame);
        self.inputs_sent
            .push(format!("?{}", self.model.label_text(label)));
        self.input_times.push(now - self.start);
        self.confs = self.closure(next, now);
        self.visit();
        let text = LabelText::parse(&self.model.label_text(label));
        if let Some(text) = text
            && self.purpose_step(Seen::Label(Some(Direction::Input), &text))
        {
            return;
        }
        self.steps += 1;
        if self.steps >= self.config.steps {
            let reason = format!("{} steps without a failure", self.steps);
            let _ = self.conclude(Verdict::Pass, reason, Vec::new());
            return;
        }
        // After a stimulus, always observe: the answer is what the step is for.
        self.observe_from(now);
    }

    /// Moves the purpose on by what was seen; `true` if that ended the run (reached or refused).
    fn purpose_step(&mut self, seen: Seen<'_>) -> bool {
        let Some(purpose) = &self.config.purpose else {
            return false;
        };
        self.purpose_state = purpose.step(self.purpose_state, seen);
        let (name, marker) = (purpose.name.clone(), purpose.marker(self.purpose_state));
        match marker {
            Marker::Accept => {
                let reason = format!("the purpose `{name}` was reached without a failure");
                let _ = self.conclude(Verdict::Pass, reason, Vec::new());
                true
            }
            Marker::Refuse => {
                let reason = format!("the run left the purpose `{name}` (a refusing state)");
                let _ = self.conclude(Verdict::Inconclusive, reason, Vec::new());
                true
            }
            Marker::None => false,
        }
    }

    /// Where the purpose goes on `label` (an input), for choosing inputs that advance it.
    fn purpose_after(&self, label: &Label) -> Option<(usize, Marker)> {
        let purpose = self.config.purpose.as_ref()?;
        let text = LabelText::parse(&self.model.label_text(label))?;
        let next = purpose.step(self.purpose_state, Seen::Label(Some(Direction::Input), &text));
        Some((next, purpose.marker(next)))
    }

    fn quiescence_bound(&self) -> i64 {
        self.confs
            .iter()
            .map(|c| self.model.quiescence_of(&c.state))
            .max()
            .unwrap_or(self.model.quiescence_us)
    }

    fn observe_from(&mut self, now: i64) {
        self.phase = Phase::Observing(now + self.quiescence_bound(), now);
    }

    fn decide(&mut self, now: i64) {
        if !self.expire(now) {
            return;
        }
        if let Some(script) = self.config.script.clone() {
            // Replay: each input at its recorded offset, or as soon as the model allows it.
            let Some(next) = script.get(self.script_pos) else {
                // The failure a script provokes may show only in what follows its last input.
                if self.script_waits >= SCRIPT_PATIENCE {
                    let reason = "the scripted inputs all ran without a failure".to_owned();
                    let _ = self.conclude(Verdict::Pass, reason, Vec::new());
                } else {
                    self.script_waits += 1;
                    self.observe_from(now);
                }
                return;
            };
            if let Some(at) = next.at_us.map(|at| self.start + at)
                && at > now
            {
                self.phase = Phase::Observing(at, now);
                self.waiting_for_script = true;
                return;
            }
            let inputs = self.inputs(now);
            match inputs
                .iter()
                .find(|(l, _)| format!("?{}", self.model.label_text(l)) == next.label)
            {
                Some((label, _)) => {
                    let label = label.clone();
                    self.script_pos += 1;
                    self.script_waits = 0;
                    self.send(now, &label);
                }
                // Outputs may make it allowed; if a few observations do not, the script no
                // longer fits what the device does.
                None if self.script_waits >= SCRIPT_PATIENCE => {
                    let reason = format!("the scripted input {} is not allowed here", next.label);
                    let _ = self.conclude(Verdict::Inconclusive, reason, Vec::new());
                }
                None => {
                    self.script_waits += 1;
                    self.observe_from(now);
                }
            }
            return;
        }
        let inputs = self.inputs(now);
        let send = !inputs.is_empty() && self.rand(100) < usize::from(self.config.input_percent);
        if send {
            let fresh: Vec<&(Label, Vec<usize>)> = match self.config.strategy {
                Strategy::Coverage => inputs
                    .iter()
                    .filter(|(_, ts)| ts.iter().any(|t| !self.taken.contains(t)))
                    .collect(),
                Strategy::Uniform => Vec::new(),
            };
            // Inputs that move the purpose on (and not into a refusing state) come first.
            let advancing: Vec<&(Label, Vec<usize>)> = inputs
                .iter()
                .filter(|(l, _)| {
                    self.purpose_after(l)
                        .is_some_and(|(next, marker)| next != self.purpose_state && marker != Marker::Refuse)
                })
                .collect();
            let pool: Vec<&(Label, Vec<usize>)> = if !advancing.is_empty() {
                advancing
            } else if fresh.is_empty() {
                inputs.iter().collect()
            } else {
                fresh
            };
            // Each component of a composition gets its share of the stimuli: one whose inputs are
            // in the pool is chosen first, then one of its inputs, so that a model with one
            // procedure step is not drowned by another's dozen commands.
            let mut owners: Vec<usize> = pool
                .iter()
                .flat_map(|(_, ts)| {
                    ts.iter()
                        .map(|t| self.model.component_of(self.model.transition_at(*t)))
                })
                .collect();
            owners.sort_unstable();
            owners.dedup();
            let owner = owners.get(self.rand(owners.len())).copied();
            let own: Vec<&&(Label, Vec<usize>)> = pool
                .iter()
                .filter(|(_, ts)| {
                    ts.iter()
                        .any(|t| Some(self.model.component_of(self.model.transition_at(*t))) == owner)
                })
                .collect();
            // The pool is not empty here, so neither are the owners and their inputs.
            if let Some(choice) = own.get(self.rand(own.len())) {
                let label = choice.0.clone();
                self.send(now, &label);
            }
        } else {
            self.observe_from(now);
        }
    }

    fn tick(&mut self, now: i64) {
        match self.phase {
            Phase::Start => {
                for reset in self.model.resets.clone() {
                    // Resets are sent as they are: the initial state expects their consequences.
                    let gate = self.model.gate_at(reset.gate);
                    let mut data = Vec::new();
                    for (f, v) in gate.fields.iter().zip(&reset.values) {
                        for i in 0..usize::from(f.size) {
                            data.push((v.unwrap_or(0) >> (8 * i)) as u8);
                        }
                    }
                    if let Ok(frame) =
                        CanFrame::new(StandardId::new(gate.cob_id).unwrap_or(StandardId::ZERO), &data)
                    {
                        self.trace.push(TraceStep {
                            t: self.t(now),
                            dir: Dir::In,
                            label: format!("?{}", self.model.label_text(&reset)),
                            frame: Some(frame_json(&frame)),
                        });
                        self.outbox.push_back(frame);
                    }
                }
                self.observe_from(now);
            }
            Phase::Observing(until, since) => {
                if !self.expire(now) {
                    return;
                }
                if now >= until && self.waiting_for_script {
                    // Waiting for a scripted input's time is not an observation of its own.
                    self.waiting_for_script = false;
                    self.phase = Phase::Deciding(now);
                } else if now >= until {
                    self.trace.push(TraceStep {
                        t: self.t(now),
                        dir: Dir::Quiescence,
                        label: format!("quiescence {:.3}s", (now - since) as f64 / 1e6),
                        frame: None,
                    });
                    if self.purpose_step(Seen::Quiescence) {
                        return;
                    }
                    self.count_step(now);
                }
            }
            Phase::Deciding(_) => self.decide(now),
            Phase::Finished => {}
        }
    }

    fn next_due(&self) -> Option<i64> {
        match self.phase {
            Phase::Start => Some(self.start),
            Phase::Deciding(at) => Some(at),
            Phase::Observing(until, _) => {
                let deadline = self.confs.iter().filter_map(|c| self.deadline(c)).min();
                let due = deadline.map_or(until, |d| until.min(d + 1));
                Some(
                    self.next_opening(self.closed_at)
                        .map_or(due, |open| due.min(open)),
                )
            }
            Phase::Finished => None,
        }
    }
}

impl Core for Executor<'_> {
    type Event = RunResult;

    fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
        // Frames from before the run (buffered by the link) say nothing about the reset state.
        if self.phase == Phase::Finished || self.phase == Phase::Start || micros(now) < self.start {
            return;
        }
        self.observe(micros(now), frame);
    }

    fn handle_timeout(&mut self, now: Instant) {
        let now = micros(now);
        // Several decisions may fall on one instant (a decision right after an output).
        for _ in 0..16 {
            match self.next_due() {
                Some(due) if due <= now && self.phase != Phase::Finished => self.tick(now),
                _ => break,
            }
        }
    }

    fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.outbox.pop_front()
    }

    fn poll_event(&mut self) -> Option<RunResult> {
        if self.reported {
            return None;
        }
        let outcome = self.outcome.clone()?;
        self.reported = true;
        Some(outcome)
    }

    fn poll_timeout(&self) -> Option<Instant> {
        self.next_due()
            .map(|t| Instant::from_micros(u64::try_from(t).unwrap_or(0)))
    }
}

fn micros(t: Instant) -> i64 {
    i64::try_from(t.as_micros()).unwrap_or(i64::MAX)
}

/// splitmix64: a tiny, well-known generator; enough for choosing test inputs reproducibly.
fn next(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

fn frame_json(frame: &CanFrame) -> FrameJson {
    FrameJson {
        id: format!("{:#05x}", frame.id().as_raw()),
        data: if frame.is_remote() {
            format!("R{}", frame.dlc())
        } else {
            frame.data().iter().map(|b| format!("{b:02X}")).collect()
        },
    }
}

fn frame_text(frame: &CanFrame) -> String {
    let j = frame_json(frame);
    format!("{}#{}", j.id, j.data)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compile::tests::one;

    const ECHO: &str = "model echo\ninput REQ = 0x601 (v: u8)\noutput RES = 0x581 (v: u8)\noutput OTHER = 0x182 (v: u8)\n\
        clock t\nquiescence 100ms\nprocess p {\n var x: u8 = 0\n location Idle, Busy\n \
        Idle -> Busy: in REQ({1, 2}) do x := v reset t\n Busy -> Idle: out RES(x) within 3ms..10ms of t\n}\n";

    /// Runs the executor against a scripted device on virtual time: the device answers each frame
    /// it receives with frames after delays (µs).
    fn run(config: RunConfig, device: impl Fn(&CanFrame) -> Vec<(u64, CanFrame)>) -> RunResult {
        let (model, d) = one(ECHO);
        assert!(d.is_empty(), "{d:?}");
        let model = model.unwrap();
        let mut exec = Executor::new(&model, config, Instant::from_millis(1));
        let mut pending: Vec<(u64, CanFrame)> = Vec::new();
        let mut now = 0;
        for _ in 0..100_000 {
            while let Some(frame) = exec.poll_transmit() {
                for (delay, answer) in device(&frame) {
                    pending.push((now + delay, answer));
                }
            }
            if let Some(outcome) = exec.poll_event() {
                return outcome;
            }
            pending.sort_by_key(|(at, _)| *at);
            let timer = exec.poll_timeout().map(Instant::as_micros);
            let next_frame = pending.first().map(|(at, _)| *at);
            if next_frame.is_some_and(|at| timer.is_none_or(|t| at <= t)) {
                let (at, frame) = pending.remove(0);
                now = at;
                exec.handle_frame(Instant::from_micros(at), &frame);
            } else if let Some(t) = timer {
                now = t;
                exec.handle_timeout(Instant::from_micros(t));
            } else {
                break;
            }
        }
        exec.finish("the test loop ended")
    }

    fn frame(id: u16, data: &[u8]) -> CanFrame {
        CanFrame::new(StandardId::new(id).unwrap(), data).unwrap()
    }

    fn echo(delay: u64, add: u8) -> impl Fn(&CanFrame) -> Vec<(u64, CanFrame)> {
        move |f| {
            vec![
                (delay, frame(0x581, &[f.data()[0] + add])),
                (delay, frame(0x123, &[9])),
            ]
        }
    }

    fn config(steps: usize) -> RunConfig {
        RunConfig {
            steps,
            tolerance_us: 1_000,
            ..RunConfig::default()
        }
    }

    #[test]
    fn a_conforming_device_passes_and_is_covered() {
        let outcome = run(config(50), echo(5_000, 0));
        assert_eq!(outcome.verdict, Verdict::Pass, "{outcome:#?}");
        assert_eq!(outcome.steps, 50);
        assert_eq!(outcome.coverage.transitions, [2, 2]);
        assert!(
            outcome.trace.iter().any(|s| s.dir == Dir::Quiescence),
            "idle time is observed as quiescence"
        );
        // The frame on 123h is not the model's business (uioco on a partial model).
        assert!(outcome.trace.iter().all(|s| !s.label.contains("0x123")));
    }

    #[test]
    fn a_wrong_value_fails_naming_what_was_allowed() {
        let outcome = run(config(50), echo(5_000, 1));
        assert_eq!(outcome.verdict, Verdict::Fail);
        assert!(
            outcome.reason.starts_with("unexpected output 0x581#"),
            "{}",
            outcome.reason
        );
        let sent = outcome.trace.iter().rev().find(|s| s.dir == Dir::In).unwrap();
        let expected = if sent.label.ends_with("0x01") {
            "RES !0x01"
        } else {
            "RES !0x02"
        };
        assert_eq!(outcome.allowed.len(), 1);
        assert!(outcome.allowed[0].starts_with(expected), "{:?}", outcome.allowed);
    }

    #[test]
    fn late_missing_and_early_answers_fail() {
        // Late: the window ends 10 ms after the request, plus 1 ms tolerance.
        let late = run(config(50), echo(12_500, 0));
        assert_eq!(late.verdict, Verdict::Fail);
        assert!(late.reason.starts_with("missing output"), "{}", late.reason);
        let sent = late.trace.iter().rev().find(|s| s.dir == Dir::In).unwrap().t;
        let decided: f64 = late
            .reason
            .split(" by ")
            .nth(1)
            .unwrap()
            .trim_end_matches('s')
            .parse()
            .unwrap();
        assert!(
            (decided - sent - 0.011).abs() < 0.0005,
            "failed at {decided}, request at {sent}"
        );
        let silent = run(config(50), |_| Vec::new());
        assert_eq!(silent.verdict, Verdict::Fail);
        assert_eq!(silent.outputs_seen, 0);
        let early = run(config(50), echo(1_000, 0));
        assert_eq!(early.verdict, Verdict::Fail);
        assert!(early.reason.ends_with("too early"), "{}", early.reason);
    }

    #[test]
    fn runs_are_reproducible_from_the_seed() {
        let a = run(
            RunConfig {
                seed: 7,
                ..config(40)
            },
            echo(5_000, 0),
        );
        let b = run(
            RunConfig {
                seed: 7,
                ..config(40)
            },
            echo(5_000, 0),
        );
        let c = run(
            RunConfig {
                seed: 8,
                ..config(40)
            },
            echo(5_000, 0),
        );
        assert_eq!(a.trace, b.trace);
        assert_ne!(a.trace, c.trace);
    }

    #[test]
    fn a_script_replays_its_inputs_in_order() {
        let script: Vec<ScriptStep> = ["?REQ !0x02", "?REQ !0x02", "?REQ !0x01"]
            .map(ScriptStep::from)
            .to_vec();
        let outcome = run(
            RunConfig {
                script: Some(script.clone()),
                ..config(1000)
            },
            echo(5_000, 0),
        );
        assert_eq!(outcome.verdict, Verdict::Pass, "{outcome:#?}");
        let sent: Vec<&str> = outcome
            .trace
            .iter()
            .filter(|s| s.dir == Dir::In)
            .map(|s| s.label.as_str())
            .collect();
        let labels: Vec<&str> = script.iter().map(|s| s.label.as_str()).collect();
        assert_eq!(sent, labels);
        // Timed steps go out at their offsets.
        let timed = vec![
            ScriptStep {
                label: "?REQ !0x02".into(),
                at_us: Some(500_000),
            },
            ScriptStep {
                label: "?REQ !0x01".into(),
                at_us: Some(900_000),
            },
        ];
        let outcome = run(
            RunConfig {
                script: Some(timed),
                ..config(1000)
            },
            echo(5_000, 0),
        );
        assert_eq!(outcome.verdict, Verdict::Pass, "{outcome:#?}");
        assert_eq!(outcome.input_times_us, [500_000, 900_000], "{outcome:#?}");
        // One observation after the reset; waiting for the scripted times is not observed as quiescence.
        let early = outcome
            .trace
            .iter()
            .filter(|s| s.dir == Dir::Quiescence && s.t < 0.9)
            .count();
        assert_eq!(early, 1, "{:#?}", outcome.trace);
        let bad = run(
            RunConfig {
                script: Some(vec!["?REQ !0x03".into()]),
                ..config(1000)
            },
            echo(5_000, 0),
        );
        assert_eq!(bad.verdict, Verdict::Inconclusive);
    }
}

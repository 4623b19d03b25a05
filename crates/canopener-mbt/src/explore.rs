//! The untimed semantics of a model and the exploration of its state space.
//!
//! The composed semantics of [`crate::compose`]: internal steps interleave per process; inputs,
//! outputs and hidden events synchronise the components that hold them. A step's guards and
//! updates read the state before it; updates must stay in their variable's domain.
//! Exploration enumerates the concrete labels of inputs (their patterns are bounded: the static
//! checks see to that) and of outputs with values or sets; an output field the model leaves open
//! (`_`, or a range wider than [`MAX_INPUT_CHOICES`]) stays open in the label (`!_`). Clocks are
//! ignored: exploration over-approximates the timed behaviour, which is what `.aut` tools expect.

use std::collections::{HashMap, VecDeque};

use crate::compile::MAX_INPUT_CHOICES;
use crate::diagnostics::{MbtCode, MbtDiagnostic, diag};
use crate::expr::EvalError;
use crate::label::Label;
use crate::model::{CPattern, Kind, Model, Transition};
use crate::syntax::ast::Direction;

/// A labelled transition system: states `0..states`, state 0 initial.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Lts {
    /// The initial state.
    pub initial: usize,
    /// How many states.
    pub states: usize,
    /// `(from, label, to)`, labels in the `.aut` convention (see [`crate::aut`]).
    pub transitions: Vec<(usize, String, usize)>,
}

/// One step of the untimed semantics: the transition, its label (none for internal steps) and
/// the state it leads to.
pub type Step = (usize, Option<Label>, Vec<i64>);

/// One step of the composed untimed semantics with every transition taking part (the initiator
/// first), its label and the state it leads to.
pub type JointStep = (Vec<usize>, Option<Label>, Vec<i64>);

/// The explored state space of a model.
#[derive(Debug, Clone)]
pub struct StateSpace {
    /// The LTS, labels as text.
    pub lts: Lts,
    /// The state vector of each state.
    pub vectors: Vec<Vec<i64>>,
    /// The model transition behind each LTS transition.
    pub origins: Vec<usize>,
    /// Whether the exploration stopped at its bound.
    pub truncated: bool,
}

impl Model {
    /// Whether `t` may start in `state` (location only).
    pub fn located(&self, t: &Transition, state: &[i64]) -> bool {
        let loc = *crate::model::at(state, self.process_at(t.process).location_slot);
        t.from.is_empty() || t.from.contains(&loc)
    }

    /// Whether `t`'s guard holds in `state` for the label `fields`.
    pub fn guard_holds(&self, t: &Transition, state: &[i64], fields: &[i64]) -> Result<bool, EvalError> {
        Ok(match &t.guard {
            None => true,
            Some(g) => g.eval(state, fields)? != 0,
        })
    }

    /// Whether the concrete `fields` match `t`'s patterns in `state`.
    pub fn patterns_match(&self, t: &Transition, state: &[i64], fields: &[i64]) -> Result<bool, EvalError> {
        for (p, v) in t.patterns.iter().zip(fields) {
            let ok = match p {
                CPattern::Any => true,
                CPattern::Value(e) => e.eval(state, fields)? == *v,
                CPattern::Set(items) => {
                    let mut any = false;
                    for i in items {
                        any |= i.eval(state, fields)? == *v;
                    }
                    any
                }
                CPattern::Range(lo, hi) => lo.eval(state, fields)? <= *v && *v <= hi.eval(state, fields)?,
            };
            if !ok {
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// The state after `t` with the label `fields`; an update leaving its domain is an error.
    pub fn apply(&self, t: &Transition, state: &[i64], fields: &[i64]) -> Result<Vec<i64>, String> {
        let mut next = state.to_vec();
        for (slot, e, lo, hi) in &t.updates {
            let v = e.eval(state, fields).map_err(|e| e.to_string())?;
            if v < *lo || v > *hi {
                return Err(format!("an update sets a variable to {v}, outside {lo}..{hi}"));
            }
            *crate::model::at_mut(&mut next, *slot) = v;
        }
        if let Some(to) = t.to {
            *crate::model::at_mut(&mut next, self.process_at(t.process).location_slot) = to;
        }
        Ok(next)
    }

    /// The field values `t` offers in `state`, one vector per concrete label; `None` is an open
    /// field. Guards reading fields are applied to labels whose fields are all known.
    pub fn offers(&self, t: &Transition, state: &[i64]) -> Result<Vec<Vec<Option<i64>>>, EvalError> {
        let mut labels: Vec<Vec<Option<i64>>> = vec![Vec::new()];
        for p in &t.patterns {
            let choices: Vec<Option<i64>> = match p {
                CPattern::Any => vec![None],
                CPattern::Value(e) => vec![Some(e.eval(state, &[])?)],
                CPattern::Set(items) => items
                    .iter()
                    .map(|i| i.eval(state, &[]).map(Some))
                    .collect::<Result<_, _>>()?,
                CPattern::Range(lo, hi) => {
                    let (lo, hi) = (lo.eval(state, &[])?, hi.eval(state, &[])?);
                    if hi - lo >= MAX_INPUT_CHOICES {
                        vec![None]
                    } else {
                        (lo..=hi).map(Some).collect()
                    }
                }
            };
            labels = extend_each(labels, &choices);
        }
        let mut kept = Vec::new();
        for l in labels {
            let known: Option<Vec<i64>> = l.iter().copied().collect();
            let ok = match (&known, &t.guard) {
                (_, None) => true,
                (Some(fields), Some(_)) => self.guard_holds(t, state, fields)?,
                (None, Some(g)) if !g.reads_fields() => self.guard_holds(t, state, &[])?,
                (None, Some(_)) => true,
            };
            if ok {
                kept.push(l);
            }
        }
        Ok(kept)
    }

    /// A label in the `.aut` convention: `?GATE !v..` for inputs, `!GATE !v..` for outputs, `i` for
    /// internal steps.
    pub fn aut_label(&self, kind: Kind, label: Option<&Label>) -> String {
        match (kind, label) {
            (Kind::Input, Some(l)) => format!("?{}", self.label_text(l)),
            (_, Some(l)) => format!("!{}", self.label_text(l)),
            (_, None) => "i".to_owned(),
        }
    }

    /// Every step from `state` in the composed semantics ([`crate::compose`]): transition (the one
    /// that starts the step), label (none for internal steps and hidden events), target.
    /// Internal steps are per process; inputs, outputs and hidden events synchronise every
    /// component that holds them. Duplicate steps (the same label to the same state) are listed
    /// once.
    pub fn steps(&self, state: &[i64]) -> Result<Vec<Step>, (usize, String)> {
        Ok(self
            .joint_steps(state)?
            .into_iter()
            .filter_map(|(ts, label, next)| Some((*ts.first()?, label, next)))
            .collect())
    }

    /// [`Model::steps`] with every transition that takes part in each step (one per component
    /// holding its frame or event; the initiator first).
    pub fn joint_steps(&self, state: &[i64]) -> Result<Vec<JointStep>, (usize, String)> {
        use crate::compose::Blocked;
        let mut out: Vec<JointStep> = Vec::new();
        let push = |out: &mut Vec<JointStep>, step: JointStep| {
            if !out.iter().any(|(_, l, s)| *l == step.1 && *s == step.2) {
                out.push(step);
            }
        };
        let error = |b: Blocked| match b {
            Blocked::Error(t, e) => Err((t, e)),
            Blocked::Refused(_) => Ok(()),
        };
        let mut inputs: Vec<Label> = Vec::new();
        for t in &self.transitions {
            if !self.located(t, state) {
                continue;
            }
            let fail = |e: String| (t.id, e);
            match t.kind {
                Kind::Internal | Kind::Signal => {
                    if !self.guard_holds(t, state, &[]).map_err(|e| fail(e.to_string()))? {
                        continue;
                    }
                    match self.signal_joint(state, t.id) {
                        Ok(joint) => {
                            for j in joint {
                                push(&mut out, (j.transitions, None, j.state));
                            }
                        }
                        Err(b) => error(b)?,
                    }
                }
                Kind::On => {}
                Kind::Input => {
                    if t.passive {
                        continue;
                    }
                    let Some(gate) = t.gate else { continue };
                    for values in self.offers(t, state).map_err(|e| fail(e.to_string()))? {
                        let label = Label {
                            gate,
                            values: values.iter().map(|v| Some(v.unwrap_or(0))).collect(),
                        };
                        if !inputs.contains(&label) {
                            inputs.push(label);
                        }
                    }
                }
                Kind::Output | Kind::MaybeOutput => {
                    let Some(gate) = t.gate else { continue };
                    let own = self.component_of(t);
                    let offers = self.offers(t, state).map_err(|e| fail(e.to_string()))?;
                    for values in offers.into_iter().flat_map(|v| self.refine(state, gate, v)) {
                        // The initiator takes part with this transition; every other holder with
                        // one of its own.
                        let mut admit = |u: &Transition| self.component_of(u) != own || u.id == t.id;
                        match self.output_joint(state, gate, &values, &mut admit) {
                            Ok(joint) => {
                                for j in joint {
                                    push(
                                        &mut out,
                                        (
                                            j.transitions,
                                            Some(Label {
                                                gate,
                                                values: values.clone(),
                                            }),
                                            j.state,
                                        ),
                                    );
                                }
                            }
                            Err(b) => error(b)?,
                        }
                    }
                }
            }
        }
        // Maximal progress: an internal step without a window happens at once, so a state that has
        // one is left before anything else can happen (the executor's closure does the same).
        let urgent: Vec<JointStep> = out
            .iter()
            .filter(|(ts, label, _)| {
                label.is_none()
                    && ts
                        .first()
                        .is_some_and(|t| self.transition_at(*t).window.is_none())
            })
            .cloned()
            .collect();
        if !urgent.is_empty() {
            return Ok(urgent);
        }
        for label in inputs {
            let values: Vec<i64> = label.values.iter().map(|v| v.unwrap_or(0)).collect();
            match self.input_joint(state, label.gate, &values) {
                Ok(joint) => {
                    for j in joint {
                        push(&mut out, (j.transitions, Some(label.clone()), j.state));
                    }
                }
                Err(b) => error(b)?,
            }
        }
        Ok(out)
    }

    /// An output label whose fields the initiator leaves open, made concrete wherever a holder of
    /// the frame cares: each open field takes every value some holder's pattern names there, and
    /// one value none names (still open if no holder names any). Without this, two holders could
    /// each read the same open label as a different frame (a confirmation and an abort).
    fn refine(&self, state: &[i64], gate: usize, values: Vec<Option<i64>>) -> Vec<Vec<Option<i64>>> {
        const MAX_LABELS: usize = 64;
        let key = self.gate_at(gate).frame_key();
        let mut choices: Vec<Vec<Option<i64>>> = Vec::new();
        for (field, value) in values.iter().enumerate() {
            if value.is_some() {
                choices.push(vec![*value]);
                continue;
            }
            let mut named: Vec<i64> = Vec::new();
            for t in &self.transitions {
                // Only holders' transitions that could take this label (its known fields) name
                // values that matter.
                if !t.kind.is_output()
                    || !self.on_frames(t, key)
                    || !self.located(t, state)
                    || !self.matches_open(t, state, &values)
                {
                    continue;
                }
                match t.patterns.get(field) {
                    Some(CPattern::Value(e)) => named.extend(e.eval(state, &[]).ok()),
                    Some(CPattern::Set(items)) => {
                        named.extend(items.iter().filter_map(|i| i.eval(state, &[]).ok()))
                    }
                    _ => {}
                }
            }
            named.sort_unstable();
            named.dedup();
            if named.is_empty() {
                choices.push(vec![None]);
                continue;
            }
            // A value no holder names: one past the largest, or below the smallest at the top of
            // the field's range.
            let size = crate::model::at(&self.gate_at(gate).fields, field).size;
            let max = if size >= 8 {
                i64::MAX
            } else {
                (1i64 << (8 * size)) - 1
            };
            let fresh = named
                .last()
                .map(|v| v + 1)
                .filter(|v| *v <= max)
                .or_else(|| (0..=max).find(|v| !named.contains(v)));
            let mut options: Vec<Option<i64>> = named.into_iter().map(Some).collect();
            options.extend(fresh.map(Some));
            choices.push(options);
        }
        let mut labels: Vec<Vec<Option<i64>>> = vec![Vec::new()];
        for options in choices {
            labels = extend_each(labels, &options);
            if labels.len() > MAX_LABELS {
                return vec![values];
            }
        }
        labels
    }

    /// The direction of a transition's label, if it has one.
    pub fn direction(&self, t: &Transition) -> Option<Direction> {
        t.gate.map(|g| self.gate_at(g).direction)
    }
}

/// Every label of `labels` extended by every value of `choices` (a cartesian product, field by field).
fn extend_each(labels: Vec<Vec<Option<i64>>>, choices: &[Option<i64>]) -> Vec<Vec<Option<i64>>> {
    labels
        .into_iter()
        .flat_map(|prefix| {
            choices.iter().map(move |c| {
                let mut l = prefix.clone();
                l.push(*c);
                l
            })
        })
        .collect()
}

/// Explores the state space breadth first, up to `max_states` states.
pub fn explore(model: &Model, max_states: usize) -> (StateSpace, Vec<MbtDiagnostic>) {
    let mut diagnostics = Vec::new();
    let mut index: HashMap<Vec<i64>, usize> = HashMap::new();
    let mut vectors = vec![model.initial.clone()];
    index.insert(model.initial.clone(), 0);
    let mut queue = VecDeque::from([0usize]);
    let mut transitions = Vec::new();
    let mut origins = Vec::new();
    let mut truncated = false;
    while let Some(s) = queue.pop_front() {
        // Only positions in `vectors` are queued.
        let Some(state) = vectors.get(s).cloned() else {
            continue;
        };
        let steps = match model.steps(&state) {
            Ok(steps) => steps,
            Err((t, message)) => {
                let t = model.transition_at(t);
                diagnostics.push(diag(
                    MbtCode::EvalError,
                    t.span,
                    format!("in state {}: {message}", model.describe_state(&state)),
                ));
                continue;
            }
        };
        for (t, label, next) in steps {
            let target = match index.get(&next) {
                Some(i) => *i,
                None if vectors.len() >= max_states => {
                    truncated = true;
                    continue;
                }
                None => {
                    let i = vectors.len();
                    index.insert(next.clone(), i);
                    vectors.push(next);
                    queue.push_back(i);
                    i
                }
            };
            transitions.push((
                s,
                model.aut_label(model.transition_at(t).kind, label.as_ref()),
                target,
            ));
            origins.push(t);
        }
    }
    if truncated {
        diagnostics.push(diag(
            MbtCode::StateBound,
            Default::default(),
            format!("exploration stopped at {max_states} states; the exported space is a prefix"),
        ));
    }
    let lts = Lts {
        initial: 0,
        states: vectors.len(),
        transitions,
    };
    (
        StateSpace {
            lts,
            vectors,
            origins,
            truncated,
        },
        diagnostics,
    )
}

/// A string as a DOT quoted string's content.
fn dot_escape(s: &str) -> String {
    s.replace('\\', "\\\\").replace('"', "\\\"")
}

/// The state space as Graphviz DOT: states named by their vectors, inputs blue, outputs green,
/// internal steps dashed.
pub fn to_dot(model: &Model, space: &StateSpace) -> String {
    let esc = dot_escape;
    let mut out = format!(
        "digraph \"{}\" {{\n  rankdir=LR;\n  node [shape=box, fontsize=10];\n",
        esc(&model.name())
    );
    for (i, v) in space.vectors.iter().enumerate() {
        let style = if i == space.lts.initial {
            ", penwidth=2"
        } else {
            ""
        };
        out.push_str(&format!(
            "  s{i} [label=\"{i}: {}\"{style}];\n",
            esc(&model.describe_state(v))
        ));
    }
    for (from, label, to) in &space.lts.transitions {
        let attrs = match label.chars().next() {
            Some('?') => "color=blue",
            Some('!') => "color=darkgreen",
            _ => "style=dashed",
        };
        out.push_str(&format!(
            "  s{from} -> s{to} [label=\"{}\", {attrs}];\n",
            esc(label)
        ));
    }
    out.push_str("}\n");
    out
}

/// The model's processes as DOT, one cluster each: locations as nodes, transitions as edges, those
/// in `taken` green and bold, the rest grey: what a run covered.
pub fn coverage_dot(model: &Model, taken: &[usize]) -> String {
    let esc = dot_escape;
    let mut out = format!(
        "digraph \"{} coverage\" {{\n  rankdir=LR;\n  node [shape=ellipse, fontsize=10];\n",
        esc(&model.name())
    );
    for (p, process) in model.processes.iter().enumerate() {
        out.push_str(&format!(
            "  subgraph cluster_{p} {{\n    label=\"{}\";\n",
            esc(&process.name)
        ));
        for (l, location) in process.locations.iter().enumerate() {
            out.push_str(&format!("    p{p}l{l} [label=\"{}\"];\n", esc(&location.name)));
        }
        out.push_str("  }\n");
        for &t in &process.transitions {
            let transition = model.transition_at(t);
            let label = match transition.gate {
                Some(g) => format!(
                    "{}{}",
                    if transition.kind == Kind::Input { "?" } else { "!" },
                    model.gate_at(g).name
                ),
                None => "i".to_owned(),
            };
            let style = if taken.contains(&t) {
                "color=darkgreen, penwidth=2"
            } else {
                "color=grey, fontcolor=grey"
            };
            let froms: Vec<usize> = if transition.from.is_empty() {
                (0..process.locations.len()).collect()
            } else {
                transition.from.iter().map(|l| *l as usize).collect()
            };
            for f in froms {
                let to = transition.to.map_or(f, |l| l as usize);
                out.push_str(&format!(
                    "  p{p}l{f} -> p{p}l{to} [label=\"{}\", {style}];\n",
                    esc(&label)
                ));
            }
        }
    }
    out.push_str("}\n");
    out
}

/// [`coverage_dot`] drawn as SVG by the `layout-rs` crate (no Graphviz needed): the same colours,
/// green and bold for what the run took, grey for the rest. `layout-rs` draws no cluster boxes, so the
/// processes are not framed; the DOT has them for Graphviz.
pub fn coverage_svg(model: &Model, taken: &[usize]) -> Result<String, SvgError> {
    let dot = coverage_dot(model, taken);
    let mut parser = layout::gv::DotParser::new(&dot);
    let graph = parser.process().map_err(SvgError)?;
    let mut builder = layout::gv::GraphBuilder::new();
    builder.visit_graph(&graph);
    let mut visual = builder.get();
    let mut svg = layout::backends::svg::SVGWriter::new();
    visual.do_it(false, false, false, &mut svg);
    Ok(svg.finalize())
}

/// The DOT the model made could not be read back for drawing: a bug in [`coverage_dot`]'s escaping.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("cannot draw the coverage graph: {0}")]
pub struct SvgError(pub String);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compile::tests::one;

    #[test]
    fn coverage_svg_colours_taken_and_untaken_transitions() {
        let (model, d) = one(
            "model m\ninput I = 1 (a: u8)\noutput O = 2 (n: u8)\nclock t\nprocess p {\n location A, B\n \
             A -> B: in I(1) reset t\n B -> A: out O(0) within 0..10ms of t\n A -> same: in I(2)\n}\n",
        );
        assert!(d.is_empty(), "{d:?}");
        let model = model.unwrap();
        let svg = coverage_svg(&model, &[0]).unwrap();
        assert!(svg.contains("<svg"), "{svg}");
        // The taken transition's edge is dark green (006400), the two others grey (808080).
        assert_eq!(svg.matches("stroke=\"#006400ff\"").count(), 1, "{svg}");
        assert_eq!(svg.matches("stroke=\"#808080ff\"").count(), 2, "{svg}");
        for name in [">A<", ">B<", "?I", "!O"] {
            assert!(svg.contains(name), "{name} missing: {svg}");
        }
    }

    #[test]
    fn a_counter_explores_to_its_bound_and_back() {
        let (model, d) = one(
            "model m\ninput I = 1 (a: u8)\noutput O = 2 (n: u8)\nclock t\nprocess p {\n var n: 0..2 = 0\n location A, B\n \
             A -> B: in I({1, 2}) when n < 2 do n := n + 1 reset t\n B -> A: out O(n) within 0..10ms of t\n}\n",
        );
        assert!(d.is_empty(), "{d:?}");
        let (space, d) = explore(&model.unwrap(), 100);
        assert!(d.is_empty(), "{d:?}");
        // A/0 -I1,I2-> B/1 -O1-> A/1 -I1,I2-> B/2 -O2-> A/2 (no input: n == 2).
        assert_eq!(space.lts.states, 5);
        let labels: Vec<&str> = space.lts.transitions.iter().map(|(_, l, _)| l.as_str()).collect();
        assert_eq!(
            labels,
            [
                "?I !0x01", "?I !0x02", "!O !0x01", "?I !0x01", "?I !0x02", "!O !0x02"
            ]
        );
        let (small, d) = explore(&one("model m\ninput I = 1 (a: u8)\nprocess p {\n var n: 0..9 = 0\n location A\n A -> A: in I(1) when n < 9 do n := n + 1\n}\n").0.unwrap(), 3);
        assert_eq!(small.lts.states, 3);
        assert!(small.truncated && d[0].code == MbtCode::StateBound);
    }

    #[test]
    fn leaving_a_domain_is_reported_with_the_transition() {
        let (model, _) = one(
            "model m\ninput I = 1 (a: u8)\nprocess p {\n var n: 0..1 = 0\n location A\n A -> A: in I(1) do n := n + 1\n}\n",
        );
        let (_, d) = explore(&model.unwrap(), 100);
        assert_eq!(d.len(), 1);
        assert_eq!((d[0].code, d[0].span.line), (MbtCode::EvalError, 6));
        assert!(d[0].message.contains("outside 0..1"), "{}", d[0].message);
    }

    proptest::proptest! {
        /// A counter modulo M with K input values: exactly M states and M·K transitions, whatever
        /// the bounds, and the explored space survives the .aut round trip.
        #[test]
        fn counters_explore_to_their_size_and_round_trip(m in 1i64..40, k in 1i64..5) {
            let text = format!(
                "model m\ninput I = 1 (a: u8)\nprocess p {{\n var n: 0..{} = 0\n location A\n A -> A: in I(0..{}) do n := (n + a + 1) % {m}\n}}\n",
                m - 1,
                k - 1
            );
            let (model, d) = one(&text);
            proptest::prop_assert!(d.is_empty(), "{:?}", d);
            let (space, d) = explore(&model.unwrap(), 10_000);
            proptest::prop_assert!(d.is_empty());
            proptest::prop_assert_eq!(space.lts.states as i64, m);
            proptest::prop_assert_eq!(space.lts.transitions.len() as i64, m * k);
            let (back, d) = crate::aut::read(&crate::aut::write(&space.lts));
            proptest::prop_assert!(d.is_empty());
            proptest::prop_assert_eq!(back, space.lts);
        }
    }
}

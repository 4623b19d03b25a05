//! The semantics of a composition: LOTOS/LNT parallel composition with multiway synchronisation on
//! the common gates, as `docs/mbt.md` ("Composition") defines it.
//!
//! * A **component** is one model file (the files named on the command line and the ones they
//!   `use`). Its processes interleave: one of them takes each event of the component.
//! * A component's **alphabet** is the frames of the gates it declares or uses (CAN-ID, remote
//!   flag, length, direction: [`Gate::frame_key`]) and the hidden events it declares. Components
//!   **synchronise on every frame and event their alphabets share**; a frame outside a component's
//!   alphabet does not concern it.
//! * An **input** happens only if every component holding its frame takes one of its input
//!   transitions (explicit ones first, its `otherwise` ones only if no explicit one takes the
//!   label). An **output** happens only if every holder takes one of its output transitions whose
//!   pattern, guard and (for the executor) window admit it, so the windows of a synchronised output
//!   intersect. A **hidden event** (`signal E`) happens only if every component declaring `E` takes
//!   part, with a `signal E` or an `on E` transition.
//! * Internal steps (`internal`) are per process, as in a single model.
//!
//! Processes of different components write only their own variables, so the updates of a joint
//! step are all evaluated on the state before it and combined.
//!
//! [`Gate::frame_key`]: crate::model::Gate::frame_key

use crate::model::{CPattern, Kind, Model, Transition};

/// One way the composition takes an event: the transitions that take part (one per component
/// holding the event) and the state after them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Joint {
    /// The transitions taken, the initiator's first where there is one.
    pub transitions: Vec<usize>,
    /// The state after the event.
    pub state: Vec<i64>,
}

/// Why an event cannot happen in a state.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Blocked {
    /// A component holding the event takes no part (index into [`Model::components`]).
    Refused(usize),
    /// An update of this transition leaves its variable's domain: a model error.
    Error(usize, String),
}

impl Blocked {
    /// The refusing component, if that is why.
    pub fn component(&self) -> Option<usize> {
        match self {
            Blocked::Refused(c) => Some(*c),
            Blocked::Error(..) => None,
        }
    }
}

impl Model {
    /// The component a transition belongs to.
    pub fn component_of(&self, t: &Transition) -> usize {
        self.process_at(t.process).file
    }

    /// Whether `t` is an action on a gate that names the frames of `key`.
    pub fn on_frames(&self, t: &Transition, key: (u16, bool, u8, crate::syntax::ast::Direction)) -> bool {
        t.gate.is_some_and(|g| self.gate_at(g).frame_key() == key)
    }

    /// The gates naming the same frames as `gate` (itself included).
    pub fn aliases(&self, gate: usize) -> impl Iterator<Item = usize> + '_ {
        let key = self.gate_at(gate).frame_key();
        (0..self.gates.len()).filter(move |g| self.gate_at(*g).frame_key() == key)
    }

    /// The components whose alphabet holds the frames of `gate`.
    pub fn holders_of_gate(&self, gate: usize) -> Vec<usize> {
        let key = self.gate_at(gate).frame_key();
        self.components
            .iter()
            .enumerate()
            .filter(|(_, c)| c.gates.iter().any(|g| self.gate_at(*g).frame_key() == key))
            .map(|(i, _)| i)
            .collect()
    }

    /// The components that declare the hidden event `event`.
    pub fn holders_of_event(&self, event: usize) -> Vec<usize> {
        self.components
            .iter()
            .enumerate()
            .filter(|(_, c)| c.events.contains(&event))
            .map(|(i, _)| i)
            .collect()
    }

    /// The input transitions of `component` that take the label (`gate`, `values`) in `state`:
    /// its explicit ones, or, if none does, its `otherwise` ones.
    pub fn input_moves(&self, component: usize, state: &[i64], gate: usize, values: &[i64]) -> Vec<usize> {
        let takes = |otherwise: bool| -> Vec<usize> {
            self.component_at(component)
                .transitions
                .iter()
                .copied()
                .filter(|t| {
                    let t = self.transition_at(*t);
                    t.kind == Kind::Input
                        && t.otherwise == otherwise
                        && t.gate
                            .is_some_and(|g| self.gate_at(g).frame_key() == self.gate_at(gate).frame_key())
                        && self.located(t, state)
                        && self.patterns_match(t, state, values).unwrap_or(false)
                        && self.guard_holds(t, state, values).unwrap_or(false)
                })
                .collect()
        };
        let explicit = takes(false);
        if explicit.is_empty() {
            takes(true)
        } else {
            explicit
        }
    }

    /// The output transitions of `component` that may produce the label (`gate`, `values`; `None`
    /// is a field left open, which any pattern matches) in `state` and that `admit` lets through
    /// (the executor's window check).
    pub fn output_moves(
        &self,
        component: usize,
        state: &[i64],
        gate: usize,
        values: &[Option<i64>],
        admit: &mut dyn FnMut(&Transition) -> bool,
    ) -> Vec<usize> {
        let key = self.gate_at(gate).frame_key();
        let known: Vec<i64> = values.iter().map(|v| v.unwrap_or(0)).collect();
        let mut out = Vec::new();
        for &t in &self.component_at(component).transitions {
            let tr = self.transition_at(t);
            if !tr.kind.is_output()
                || !self.on_frames(tr, key)
                || !self.located(tr, state)
                || !self.guard_holds(tr, state, &known).unwrap_or(false)
                || !self.matches_open(tr, state, values)
                || !admit(tr)
            {
                continue;
            }
            out.push(t);
        }
        out
    }

    /// The `signal`/`on` transitions of `component` for `event` enabled in `state`.
    pub fn event_moves(&self, component: usize, state: &[i64], event: usize) -> Vec<usize> {
        self.component_at(component)
            .transitions
            .iter()
            .copied()
            .filter(|t| {
                let t = self.transition_at(*t);
                matches!(t.kind, Kind::Signal | Kind::On)
                    && t.event == Some(event)
                    && self.located(t, state)
                    && self.guard_holds(t, state, &[]).unwrap_or(false)
            })
            .collect()
    }

    /// Whether `t`'s patterns match `values` in `state`, an open value matching anything.
    pub(crate) fn matches_open(&self, t: &Transition, state: &[i64], values: &[Option<i64>]) -> bool {
        t.patterns.iter().zip(values).all(|(p, v)| {
            let Some(v) = v else { return true };
            let known = [*v];
            match p {
                CPattern::Any => true,
                CPattern::Value(e) => e.eval(state, &known).is_ok_and(|x| x == *v),
                CPattern::Set(items) => items.iter().any(|i| i.eval(state, &known).is_ok_and(|x| x == *v)),
                CPattern::Range(lo, hi) => {
                    lo.eval(state, &known).is_ok_and(|l| l <= *v)
                        && hi.eval(state, &known).is_ok_and(|h| *v <= h)
                }
            }
        })
    }

    /// Every joint step from `state` choosing one transition per entry of `choices` (one entry per
    /// component taking part, each with its label's field values): the product of the choices,
    /// each with the state after all of them. An update leaving its domain is an error naming the
    /// transition.
    pub fn join(&self, state: &[i64], choices: &[(Vec<usize>, Vec<i64>)]) -> Result<Vec<Joint>, Blocked> {
        let mut partial: Vec<(Vec<usize>, Vec<i64>)> = vec![(Vec::new(), state.to_vec())];
        for (transitions, fields) in choices {
            let mut next = Vec::new();
            for (taken, after) in &partial {
                for &t in transitions {
                    let mut after = after.clone();
                    for (slot, value) in self
                        .writes(self.transition_at(t), state, fields)
                        .map_err(|e| Blocked::Error(t, e))?
                    {
                        *crate::model::at_mut(&mut after, slot) = value;
                    }
                    let mut taken = taken.clone();
                    taken.push(t);
                    next.push((taken, after));
                }
            }
            partial = next;
        }
        Ok(partial
            .into_iter()
            .map(|(transitions, state)| Joint { transitions, state })
            .collect())
    }

    /// The joint steps of an input label, or the first holder that refuses it.
    pub fn input_joint(&self, state: &[i64], gate: usize, values: &[i64]) -> Result<Vec<Joint>, Blocked> {
        let mut choices = Vec::new();
        for component in self.holders_of_gate(gate) {
            let moves = self.input_moves(component, state, gate, values);
            if moves.is_empty() {
                return Err(Blocked::Refused(component));
            }
            choices.push((moves, values.to_vec()));
        }
        self.join(state, &choices)
    }

    /// The joint steps of an output label, or the first holder that refuses it. `admit` filters
    /// each holder's candidate transitions (the executor checks their windows there).
    pub fn output_joint(
        &self,
        state: &[i64],
        gate: usize,
        values: &[Option<i64>],
        admit: &mut dyn FnMut(&Transition) -> bool,
    ) -> Result<Vec<Joint>, Blocked> {
        let known: Vec<i64> = values.iter().map(|v| v.unwrap_or(0)).collect();
        let mut choices = Vec::new();
        for component in self.holders_of_gate(gate) {
            let moves = self.output_moves(component, state, gate, values, admit);
            if moves.is_empty() {
                return Err(Blocked::Refused(component));
            }
            choices.push((moves, known.clone()));
        }
        self.join(state, &choices)
    }

    /// The joint steps of the hidden event a `signal` transition `initiator` starts, or the first
    /// other holder that cannot take part.
    pub fn signal_joint(&self, state: &[i64], initiator: usize) -> Result<Vec<Joint>, Blocked> {
        let t = self.transition_at(initiator);
        let own = self.component_of(t);
        let Some(event) = t.event else {
            return self.join(state, &[(vec![initiator], Vec::new())]);
        };
        let mut choices = vec![(vec![initiator], Vec::new())];
        for component in self.holders_of_event(event) {
            if component == own {
                continue;
            }
            let moves = self.event_moves(component, state, event);
            if moves.is_empty() {
                return Err(Blocked::Refused(component));
            }
            choices.push((moves, Vec::new()));
        }
        self.join(state, &choices)
    }

    /// A component's part of a state in words: `nmt@Stopped`.
    pub fn component_state(&self, component: usize, state: &[i64]) -> String {
        self.component_at(component)
            .processes
            .iter()
            .map(|p| {
                self.location_name(*p, *crate::model::at(state, self.process_at(*p).location_slot))
                    .replacen('.', "@", 1)
            })
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// The variable and location slots `t` writes, evaluated on `state` with the label `fields`.
    pub fn writes(&self, t: &Transition, state: &[i64], fields: &[i64]) -> Result<Vec<(usize, i64)>, String> {
        let mut out = Vec::new();
        for (slot, e, lo, hi) in &t.updates {
            let v = e.eval(state, fields).map_err(|e| e.to_string())?;
            if v < *lo || v > *hi {
                return Err(format!("an update sets a variable to {v}, outside {lo}..{hi}"));
            }
            out.push((*slot, v));
        }
        if let Some(to) = t.to {
            out.push((self.process_at(t.process).location_slot, to));
        }
        Ok(out)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use crate::compile::{Options, Source, compile};
    use crate::model::Model;

    /// Two components on one output gate and one input gate, and a third that declares the gates
    /// under other names.
    pub(crate) fn composed(texts: &[&str]) -> Model {
        let sources: Vec<Source> = texts
            .iter()
            .enumerate()
            .map(|(i, t)| Source {
                origin: format!("m{i}"),
                text: (*t).to_owned(),
            })
            .collect();
        let (model, report) = compile(
            &sources,
            &Options {
                node_id: 5,
                ..Options::default()
            },
            &|_| None,
        );
        let d: Vec<_> = report.iter().flat_map(|r| &r.diagnostics).collect();
        assert!(d.is_empty(), "{d:#?}");
        model.unwrap()
    }

    const A: &str = "model a\ninput REQ = 0x601 (v: u8)\noutput RES = 0x581 (v: u8)\nclock t\n\
        process a {\n location Idle, Busy\n Idle -> Busy: in REQ(1) reset t\n Busy -> Idle: out RES(1) within 0..10ms of t\n}\n";
    const B: &str = "model b\ninput ASK = 0x601 (v: u8)\noutput ANSWER = 0x581 (v: u8)\n\
        process b {\n var n: 0..3 = 0\n location Quiet, Heard\n Quiet -> Heard: in ASK(_) otherwise do n := 1\n \
        Heard -> Quiet: maybe out ANSWER(_)\n Quiet -> same: in ASK(2) do n := 2\n}\n";
    const C: &str = "model c\noutput OTHER = 0x182 (v: u8)\nprocess c {\n location Z\n Z -> same: maybe out OTHER(_)\n}\n";

    #[test]
    fn components_synchronise_on_the_frames_they_share_and_only_those() {
        let m = composed(&[A, B, C]);
        let req = m.gate("REQ").unwrap();
        let res = m.gate("RES").unwrap();
        assert_eq!(m.holders_of_gate(req), [0, 1]);
        assert_eq!(m.holders_of_gate(m.gate("OTHER").unwrap()), [2]);
        // Both move on the request: `a` explicitly, `b` through its `otherwise`.
        let joint = m.input_joint(&m.initial, req, &[1]).unwrap();
        assert_eq!(joint.len(), 1);
        assert_eq!(m.describe_state(&joint[0].state), "a@Busy b@Heard b.n=1 c@Z");
        // b takes 2 explicitly; a refuses it, so the composition does.
        assert_eq!(
            m.input_joint(&m.initial, req, &[2]).unwrap_err().component(),
            Some(0)
        );
        // The answer: both take it; in the initial state `b` would, but `a` owes nothing yet.
        let after = &joint[0].state;
        let out = m.output_joint(after, res, &[Some(1)], &mut |_| true).unwrap();
        assert_eq!(m.describe_state(&out[0].state), "a@Idle b@Quiet b.n=1 c@Z");
        assert_eq!(
            m.output_joint(&m.initial, res, &[Some(1)], &mut |_| true)
                .unwrap_err()
                .component(),
            Some(0)
        );
    }

    #[test]
    fn a_hidden_event_needs_every_holder() {
        let emitter = "model e\nevent ERR\nclock t\nprocess e {\n location Up, Down\n Up -> Down: signal ERR within 1ms..2ms of t\n}\n";
        let listener = "model l\nevent ERR\nprocess l {\n var hit: bool = false\n location L\n L -> same: on ERR when !hit do hit := true\n}\n";
        let m = composed(&[emitter, listener]);
        let signal = m
            .transitions
            .iter()
            .position(|t| t.kind == crate::model::Kind::Signal)
            .unwrap();
        let joint = m.signal_joint(&m.initial, signal).unwrap();
        assert_eq!(m.describe_state(&joint[0].state), "e@Down l@L l.hit=true");
        // A listener that cannot follow blocks the event.
        assert_eq!(
            m.signal_joint(&joint[0].state, signal).unwrap_err().component(),
            Some(1)
        );
    }
}

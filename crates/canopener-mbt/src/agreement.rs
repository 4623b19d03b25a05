//! Whether composed models agree: the static check behind `mbt check A B ...` (codes M043, M044).
//!
//! A composition disagrees where a component owes an output (an `out`, or a `signal` with a window)
//! and, for every way it has to meet it, another component that holds the frame (or event) takes no
//! part in it: no device can satisfy both, so any verdict there would be the models' fault. The
//! executor avoids this at run time (it never sends an input after which an obligation cannot be
//! met, and ends `inconclusive` if outputs lead there anyway); this check finds the reachable cases
//! before a run, in the untimed state space (time windows are not compared here, so a state the
//! timed semantics never reaches may be reported: the report is a warning).

use std::collections::{HashMap, VecDeque};

use crate::diagnostics::{MbtCode, MbtDiagnostic, diag};
use crate::label::Label;
use crate::model::{Kind, Model};

/// An obligation one component has and another refuses, in a reachable state.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Disagreement {
    /// The transition that requires the output (or hidden event).
    pub required: usize,
    /// The label required, as text (`SDO_TX !0x60 !0x1016 !0x01 !_`).
    pub label: String,
    /// The transition of the requiring component that led to the state, if the path has one.
    pub led_by: Option<usize>,
    /// The component that refuses it.
    pub refuser: usize,
    /// The refusing component's part of the state (`nmt@Stopped`).
    pub refuser_state: String,
    /// The refusing component's transition that brought it there, if the path has one.
    pub refuser_entered_by: Option<usize>,
    /// The state, in words.
    pub state: String,
    /// The labels of a shortest way there from the initial state (`i` for internal steps).
    pub trace: Vec<String>,
}

/// The disagreements reachable within `max_states` states of the composed untimed state space
/// (one per requiring transition, refusing component and refusing state), and whether the
/// exploration stopped at its bound.
pub fn disagreements(model: &Model, max_states: usize) -> (Vec<Disagreement>, bool) {
    let mut index: HashMap<Vec<i64>, usize> = HashMap::from([(model.initial.clone(), 0)]);
    let mut states = vec![model.initial.clone()];
    // How each state was first reached: the previous state and the transitions of that step.
    let mut parent: Vec<Option<(usize, Vec<usize>, String)>> = vec![None];
    let mut queue = VecDeque::from([0usize]);
    let mut found: Vec<Disagreement> = Vec::new();
    let mut truncated = false;
    while let Some(s) = queue.pop_front() {
        // Only positions in `states` are queued.
        let Some(state) = states.get(s).cloned() else {
            continue;
        };
        let Ok(steps) = model.joint_steps(&state) else {
            continue;
        };
        // A state with an internal step due at once is left before anything can be observed.
        let transient = !steps.is_empty()
            && steps.iter().all(|(ts, label, _)| {
                label.is_none()
                    && ts
                        .first()
                        .is_some_and(|t| model.transition_at(*t).window.is_none())
            });
        for d in if transient {
            Vec::new()
        } else {
            unmet(model, &state)
        } {
            let (required, label, refuser) = d;
            let (path, trace) = path_to(&parent, s);
            let own = model.component_of(model.transition_at(required));
            let last_of = |component: usize| {
                path.iter()
                    .rev()
                    .flat_map(|ts| ts.iter())
                    .copied()
                    .find(|t| model.component_of(model.transition_at(*t)) == component)
            };
            let led_by = path
                .iter()
                .rev()
                .flat_map(|ts| ts.iter())
                .copied()
                .find(|t| {
                    let t = model.transition_at(*t);
                    t.kind == Kind::Input && model.component_of(t) == own
                })
                .or_else(|| last_of(own));
            let refuser_state = model.component_state(refuser, &state);
            // The refuser's step that moved it to the location it refuses in.
            let slots: Vec<usize> = model
                .component_at(refuser)
                .processes
                .iter()
                .map(|p| model.process_at(*p).location_slot)
                .collect();
            let mut at = s;
            let mut refuser_entered_by = None;
            while let Some(Some((p, ts, _))) = parent.get(at) {
                let (before, after) = (states.get(*p), states.get(at));
                let value = |state: Option<&Vec<i64>>, slot: usize| state.and_then(|s| s.get(slot)).copied();
                if slots
                    .iter()
                    .any(|&slot| value(before, slot) != value(after, slot))
                {
                    refuser_entered_by = ts
                        .iter()
                        .copied()
                        .find(|t| model.component_of(model.transition_at(*t)) == refuser);
                    break;
                }
                at = *p;
            }
            let dup = found
                .iter()
                .any(|f| f.required == required && f.refuser == refuser && f.refuser_state == refuser_state);
            if !dup {
                found.push(Disagreement {
                    required,
                    label,
                    led_by,
                    refuser,
                    refuser_state,
                    refuser_entered_by,
                    state: model.describe_state(&state),
                    trace,
                });
            }
        }
        for (transitions, label, next) in steps {
            if index.contains_key(&next) {
                continue;
            }
            if states.len() >= max_states {
                truncated = true;
                continue;
            }
            // A step is taken by at least one transition.
            let Some(&first) = transitions.first() else {
                continue;
            };
            index.insert(next.clone(), states.len());
            states.push(next);
            let kind = model.transition_at(first).kind;
            parent.push(Some((s, transitions, model.aut_label(kind, label.as_ref()))));
            queue.push_back(states.len() - 1);
        }
    }
    (found, truncated)
}

/// The transitions on the path from the initial state to state `s`, step by step, and the labels.
fn path_to(parent: &[Option<(usize, Vec<usize>, String)>], mut s: usize) -> (Vec<Vec<usize>>, Vec<String>) {
    let mut steps = Vec::new();
    let mut labels = Vec::new();
    while let Some(Some((p, ts, label))) = parent.get(s) {
        steps.push(ts.clone());
        labels.push(label.clone());
        s = *p;
    }
    steps.reverse();
    labels.reverse();
    (steps, labels)
}

/// The obligations of `state` no way of meeting which every holder accepts: (the first requiring
/// transition, its label, the component refusing it), one per owing process.
fn unmet(model: &Model, state: &[i64]) -> Vec<(usize, String, usize)> {
    let mut owed: Vec<(usize, Vec<usize>)> = Vec::new();
    for t in &model.transitions {
        let must = t.kind == Kind::Output || (t.kind == Kind::Signal && t.window.is_some());
        if !must || !model.located(t, state) || !model.guard_holds(t, state, &[]).unwrap_or(false) {
            continue;
        }
        match owed.iter_mut().find(|(p, _)| *p == t.process) {
            Some((_, ts)) => ts.push(t.id),
            None => owed.push((t.process, vec![t.id])),
        }
    }
    let mut out = Vec::new();
    for (_, ts) in owed {
        let mut refusal: Option<(usize, String, usize)> = None;
        let answerable = ts.iter().any(|&t| {
            let tr = model.transition_at(t);
            if tr.kind == Kind::Signal {
                return match model.signal_joint(state, t) {
                    Ok(j) => !j.is_empty(),
                    Err(b) => {
                        if let Some(c) = b.component() {
                            refusal.get_or_insert((t, "its hidden event".to_owned(), c));
                        }
                        false
                    }
                };
            }
            let Some(gate) = tr.gate else { return true };
            let offers = model.offers(tr, state).unwrap_or_default();
            if offers.is_empty() {
                return true;
            }
            let own = model.component_of(tr);
            offers.iter().any(|values| {
                let mut admit = |u: &crate::model::Transition| model.component_of(u) != own || u.id == t;
                match model.output_joint(state, gate, values, &mut admit) {
                    Ok(j) => !j.is_empty(),
                    Err(b) => {
                        if let Some(c) = b.component() {
                            let label = model.label_text(&Label {
                                gate,
                                values: values.clone(),
                            });
                            refusal.get_or_insert((t, label, c));
                        }
                        false
                    }
                }
            })
        });
        if !answerable && let Some(r) = refusal {
            out.push(r);
        }
    }
    out
}

/// [`disagreements`] as diagnostics, each with the file (index into [`Model::files`]) whose
/// transition requires the output; plus M044 for components that reset differently on a gate they
/// share. Nothing for a single model.
pub fn check(model: &Model, max_states: usize) -> Vec<(usize, MbtDiagnostic)> {
    let mut out = Vec::new();
    if model.components.len() < 2 {
        return out;
    }
    let place = |t: usize| {
        let t = model.transition_at(t);
        let file = model.file_at(model.component_of(t));
        format!("{}:{}", file.origin, t.span.line)
    };
    let (found, _) = disagreements(model, max_states);
    for d in found {
        let t = model.transition_at(d.required);
        let file = model.component_of(t);
        let after = d
            .led_by
            .map(|l| format!("after the transition at {}, ", place(l)))
            .unwrap_or_default();
        let entered = d
            .refuser_entered_by
            .map(|e| format!(" (entered by the transition at {})", place(e)))
            .unwrap_or_default();
        let mut diagnostic = diag(
            MbtCode::Disagreement,
            t.span,
            format!(
                "in the composition {}: {after}this transition requires {} but {} refuses it in {}{entered}; no device can satisfy both",
                model.name(),
                d.label,
                model.file_at(d.refuser).name,
                d.refuser_state,
            ),
        );
        let from = d.trace.len().saturating_sub(8);
        diagnostic.help = Some(format!(
            "the tester never sends the input that leads there ({}{}); guard it with the state the other model reads (e.g. `when nmt@{{PreOperational, Operational}}`) or let the other model accept the output",
            if from > 0 { "... " } else { "" },
            d.trace.get(from..).unwrap_or_default().join(", ")
        ));
        out.push((file, diagnostic));
    }
    // Resets: each component's initial state assumes its own reset stimuli only, so two that share
    // a gate must reset it alike.
    for (a, ca) in model.components.iter().enumerate() {
        for cb in model.components.iter().skip(a + 1) {
            // A component concerns a gate it holds or resets with.
            let concerns = |c: &crate::model::Component, key| {
                c.gates.iter().any(|g| model.gate_at(*g).frame_key() == key)
                    || c.resets.iter().any(|r| model.gate_at(r.gate).frame_key() == key)
            };
            let on_shared = |c: &crate::model::Component, other: &crate::model::Component| -> Vec<String> {
                c.resets
                    .iter()
                    .filter(|r| {
                        let key = model.gate_at(r.gate).frame_key();
                        concerns(c, key) && concerns(other, key)
                    })
                    .map(|r| model.label_text(r))
                    .collect()
            };
            let (ra, rb) = (on_shared(ca, cb), on_shared(cb, ca));
            if ra != rb {
                let message = format!(
                    "{} resets with {} and {} with {} on a gate they share; each starts from the state after its own reset, and the run sends both",
                    model.file_at(ca.file).name,
                    if ra.is_empty() {
                        "nothing".to_owned()
                    } else {
                        ra.join(", ")
                    },
                    model.file_at(cb.file).name,
                    if rb.is_empty() {
                        "nothing".to_owned()
                    } else {
                        rb.join(", ")
                    },
                );
                out.push((cb.file, diag(MbtCode::ResetsDiffer, Default::default(), message)));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compose::tests::composed;

    /// The case (b): a model writes an SDO object in any NMT state and requires the
    /// answer; a model of the NMT states forbids SDO answers in Stopped.
    #[test]
    fn an_answer_one_model_requires_and_another_forbids_is_reported_with_both_transitions() {
        let states = "model states\ninput NMT = 0 (cs: u8, node: u8)\noutput TX = 0x585 (v: u8)\n\
            process states {\n location Pre, Stopped\n Pre -> Stopped: in NMT(2, 5)\n Stopped -> Pre: in NMT(0x80, 5)\n \
            Pre -> same: maybe out TX(_)\n}\n";
        let writer = "model writer\ninput NMT = 0 (cs: u8, node: u8)\ninput RX = 0x605 (v: u8)\noutput TX = 0x585 (v: u8)\nclock t\n\
            process writer {\n location Idle, Asked\n Idle -> Asked: in RX(1) reset t\n Asked -> Idle: out TX(0x60) within 0..100ms of t\n \
            Idle -> same: in NMT(_, _) otherwise\n}\n";
        let m = composed(&[states, writer]);
        let (found, truncated) = disagreements(&m, 1000);
        assert!(!truncated);
        assert_eq!(found.len(), 1, "{found:#?}");
        let d = &found[0];
        assert_eq!(m.transitions[d.required].span.line, 9);
        assert_eq!(d.label, "TX !0x60");
        assert_eq!(d.refuser_state, "states@Stopped");
        assert_eq!(m.transitions[d.led_by.unwrap()].span.line, 8);
        assert_eq!(m.transitions[d.refuser_entered_by.unwrap()].span.line, 6);
        let diagnostics = check(&m, 1000);
        assert_eq!(diagnostics.len(), 1);
        assert_eq!(diagnostics[0].0, 1);
        let message = &diagnostics[0].1.message;
        assert!(
            message.contains("m1:8")
                && message.contains("m0:6")
                && message.contains("states refuses it in states@Stopped"),
            "{message}"
        );
        // Guarded by the state, the write is never offered in Stopped: nothing to report.
        let guarded = writer.replace(
            "Idle -> Asked: in RX(1)",
            "Idle -> Asked: in RX(1) when states@Pre",
        );
        assert!(disagreements(&composed(&[states, &guarded]), 1000).0.is_empty());
    }
}

//! Test purposes (TGV): deterministic automata over labels whose states may be accepting (the
//! purpose is reached) or refusing (that part of the specification is cut away). A transition
//! carries a pattern: a gate with a value, a set, a range or `_` per field and an optional
//! predicate, `quiescence`, or `*` ("otherwise": any label no other transition of the state
//! matches). Labels a state does not match leave it where it is (implicit completion).

use crate::expr::CExpr;
use crate::label::{LabelText, Offer};
use crate::syntax::ast::{Direction, Marker};

/// A compiled test purpose.
#[derive(Debug, Clone, PartialEq)]
pub struct Purpose {
    /// The name.
    pub name: String,
    /// What it is for.
    pub title: String,
    /// States with their markers; state 0 is initial.
    pub states: Vec<(String, Marker)>,
    /// Transitions.
    pub transitions: Vec<PurposeTransition>,
}

/// One transition of a purpose.
#[derive(Debug, Clone, PartialEq)]
pub struct PurposeTransition {
    /// Source state.
    pub from: usize,
    /// Target state.
    pub to: usize,
    /// What it matches.
    pub pattern: LabelPattern,
}

/// A pattern over labels.
#[derive(Debug, Clone, PartialEq)]
pub enum LabelPattern {
    /// Any label no other transition of the state matches.
    Otherwise,
    /// The device stayed silent.
    Quiescence,
    /// A gate with field patterns.
    Gate {
        /// Only inputs or only outputs, if given.
        direction: Option<Direction>,
        /// The gate's name.
        gate: String,
        /// One pattern per field (missing trailing fields match anything).
        values: Vec<ValuePattern>,
        /// A predicate over the fields (compiled against the gate), if any.
        guard: Option<CExpr>,
    },
}

/// What one field may be.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ValuePattern {
    /// Anything.
    Any,
    /// One of these values.
    Set(Vec<i64>),
    /// A value in this inclusive range.
    Range(i64, i64),
}

/// A label as a purpose sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Seen<'a> {
    /// A gate label, its direction (if known) and text.
    Label(Option<Direction>, &'a LabelText),
    /// Quiescence.
    Quiescence,
}

impl ValuePattern {
    fn matches(&self, offer: &Offer) -> bool {
        match (self, offer) {
            (ValuePattern::Any, _) => true,
            (ValuePattern::Set(values), Offer::Number(v)) => values.contains(v),
            (ValuePattern::Range(lo, hi), Offer::Number(v)) => lo <= v && v <= hi,
            _ => false,
        }
    }
}

impl LabelPattern {
    /// Whether this (non-`*`) pattern matches what was seen.
    pub fn matches(&self, seen: Seen<'_>) -> bool {
        match (self, seen) {
            (LabelPattern::Otherwise, _) => false,
            (LabelPattern::Quiescence, Seen::Quiescence) => true,
            (
                LabelPattern::Gate {
                    direction,
                    gate,
                    values,
                    guard,
                },
                Seen::Label(dir, label),
            ) => {
                if *gate != label.gate
                    || direction.is_some_and(|d| dir.is_some_and(|seen| seen != d))
                    || values.len() > label.values.len()
                    || !values.iter().zip(&label.values).all(|(p, v)| p.matches(v))
                {
                    return false;
                }
                match guard {
                    None => true,
                    Some(guard) => {
                        // A predicate needs every value; an open value (`_`) cannot satisfy it.
                        let numbers: Option<Vec<i64>> = label
                            .values
                            .iter()
                            .map(|o| match o {
                                Offer::Number(v) => Some(*v),
                                _ => None,
                            })
                            .collect();
                        numbers.is_some_and(|n| guard.eval(&[], &n).is_ok_and(|v| v != 0))
                    }
                }
            }
            _ => false,
        }
    }
}

impl Purpose {
    /// The state after seeing `seen` in state `from`: the first matching transition, else a `*`
    /// transition, else `from` itself (implicit completion).
    pub fn step(&self, from: usize, seen: Seen<'_>) -> usize {
        let mut otherwise = None;
        for t in self.transitions.iter().filter(|t| t.from == from) {
            if t.pattern == LabelPattern::Otherwise {
                otherwise.get_or_insert(t.to);
            } else if t.pattern.matches(seen) {
                return t.to;
            }
        }
        otherwise.unwrap_or(from)
    }

    /// The marker of a state.
    pub fn marker(&self, state: usize) -> Marker {
        self.states.get(state).map_or(Marker::None, |(_, m)| *m)
    }

    /// Checks what TGV requires of a purpose: every accepting and refusing state is a sink, no
    /// state is both (by construction), and no two explicit patterns of a state obviously overlap
    /// (the same gate with the same first field values). Returns what is wrong, in words.
    pub fn problems(&self) -> Vec<String> {
        let mut problems = Vec::new();
        for t in &self.transitions {
            if self.marker(t.from) != Marker::None && t.to != t.from {
                problems.push(format!(
                    "state `{}` is {} but has a transition to `{}`: accepting and refusing states are sinks",
                    self.state_name(t.from),
                    if self.marker(t.from) == Marker::Accept {
                        "accepting"
                    } else {
                        "refusing"
                    },
                    self.state_name(t.to)
                ));
            }
        }
        for (i, a) in self.transitions.iter().enumerate() {
            for b in self.transitions.iter().skip(i + 1) {
                if a.from == b.from && a.to != b.to && overlap(&a.pattern, &b.pattern) {
                    problems.push(format!(
                        "state `{}` is not deterministic: two transitions (to `{}` and to `{}`) match the same labels",
                        self.state_name(a.from),
                        self.state_name(a.to),
                        self.state_name(b.to)
                    ));
                }
            }
        }
        problems
    }

    /// The name of a state (`?` for a number the purpose does not have).
    fn state_name(&self, state: usize) -> &str {
        self.states.get(state).map_or("?", |(name, _)| name)
    }
}

/// The most states a purpose read from `.aut` may declare (each gets a name).
pub const MAX_AUT_PURPOSE_STATES: usize = 100_000;

/// A purpose read from an Aldebaran `.aut` LTS in TGV's convention: state 0 of the header is the
/// initial state, an `ACCEPT` or `REFUSE` loop marks a state, `*` is "otherwise", `QUIESCENCE` is
/// δ, and any other label is a pattern `[?|!]GATE v1 v2 ...` whose values are numbers or `_`.
pub fn from_aut(name: &str, lts: &crate::explore::Lts) -> Result<Purpose, String> {
    if lts.states > MAX_AUT_PURPOSE_STATES {
        return Err(format!(
            "{} states: a test purpose has at most {MAX_AUT_PURPOSE_STATES}",
            lts.states
        ));
    }
    if lts.initial >= lts.states {
        return Err(format!(
            "the initial state {} is not one of the {} states",
            lts.initial, lts.states
        ));
    }
    let mut states: Vec<(String, Marker)> =
        (0..lts.states).map(|s| (format!("s{s}"), Marker::None)).collect();
    let mut transitions = Vec::new();
    for (from, label, to) in &lts.transitions {
        if *from >= lts.states || *to >= lts.states {
            return Err(format!(
                "the transition {from} -> {to} leaves the {} states",
                lts.states
            ));
        }
        let pattern = match label.as_str() {
            "ACCEPT" | "REFUSE" => {
                if from != to {
                    return Err(format!(
                        "`{label}` marks a state: it must be a loop, not {from} -> {to}"
                    ));
                }
                // `from` was checked to be a state above.
                if let Some((_, marker)) = states.get_mut(*from) {
                    *marker = if label == "ACCEPT" {
                        Marker::Accept
                    } else {
                        Marker::Refuse
                    };
                }
                continue;
            }
            "*" => LabelPattern::Otherwise,
            "QUIESCENCE" | "delta" => LabelPattern::Quiescence,
            text => {
                let (direction, rest) = match text.chars().next() {
                    Some('?') => (Some(Direction::Input), &text[1..]),
                    Some('!') => (Some(Direction::Output), &text[1..]),
                    _ => (None, text),
                };
                let parsed = LabelText::parse(rest)
                    .ok_or_else(|| format!("an empty label between {from} and {to}"))?;
                let mut values = Vec::new();
                for offer in &parsed.values {
                    values.push(match offer {
                        Offer::Any => ValuePattern::Any,
                        Offer::Number(v) => ValuePattern::Set(vec![*v]),
                        Offer::Text(t) => {
                            return Err(format!("`{t}` in `{text}` is neither a number nor `_`"));
                        }
                    });
                }
                LabelPattern::Gate {
                    direction,
                    gate: parsed.gate,
                    values,
                    guard: None,
                }
            }
        };
        transitions.push(PurposeTransition {
            from: *from,
            to: *to,
            pattern,
        });
    }
    // State 0 is initial in a purpose; the header's initial state is renumbered to 0.
    if lts.initial != 0 {
        let swap = |s: usize| {
            if s == 0 {
                lts.initial
            } else if s == lts.initial {
                0
            } else {
                s
            }
        };
        states.swap(0, lts.initial);
        for t in &mut transitions {
            t.from = swap(t.from);
            t.to = swap(t.to);
        }
    }
    let purpose = Purpose {
        name: name.to_owned(),
        title: String::new(),
        states,
        transitions,
    };
    match purpose.problems().first() {
        Some(problem) => Err(problem.clone()),
        None => Ok(purpose),
    }
}

/// Whether two patterns can match one label, judged on what is written (predicates are taken to
/// be satisfiable).
fn overlap(a: &LabelPattern, b: &LabelPattern) -> bool {
    match (a, b) {
        (LabelPattern::Quiescence, LabelPattern::Quiescence) => true,
        (LabelPattern::Otherwise, LabelPattern::Otherwise) => true,
        (
            LabelPattern::Gate {
                direction: da,
                gate: ga,
                values: va,
                ..
            },
            LabelPattern::Gate {
                direction: db,
                gate: gb,
                values: vb,
                ..
            },
        ) => {
            ga == gb
                && (da.is_none() || db.is_none() || da == db)
                && va.iter().zip(vb).all(|(x, y)| values_overlap(x, y))
        }
        _ => false,
    }
}

fn values_overlap(a: &ValuePattern, b: &ValuePattern) -> bool {
    let within = |v: i64, p: &ValuePattern| match p {
        ValuePattern::Any => true,
        ValuePattern::Set(s) => s.contains(&v),
        ValuePattern::Range(lo, hi) => *lo <= v && v <= *hi,
    };
    match (a, b) {
        (ValuePattern::Any, _) | (_, ValuePattern::Any) => true,
        (ValuePattern::Set(s), other) | (other, ValuePattern::Set(s)) => s.iter().any(|v| within(*v, other)),
        (ValuePattern::Range(a0, a1), ValuePattern::Range(b0, b1)) => a0 <= b1 && b0 <= a1,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gate(name: &str, values: Vec<ValuePattern>) -> LabelPattern {
        LabelPattern::Gate {
            direction: None,
            gate: name.into(),
            values,
            guard: None,
        }
    }

    fn purpose() -> Purpose {
        Purpose {
            name: "p".into(),
            title: String::new(),
            states: vec![
                ("start".into(), Marker::None),
                ("sent".into(), Marker::None),
                ("ok".into(), Marker::Accept),
                ("reset".into(), Marker::Refuse),
            ],
            transitions: vec![
                PurposeTransition {
                    from: 0,
                    to: 1,
                    pattern: gate("NMT", vec![ValuePattern::Set(vec![1]), ValuePattern::Any]),
                },
                PurposeTransition {
                    from: 1,
                    to: 2,
                    pattern: gate("EC", vec![ValuePattern::Set(vec![5])]),
                },
                PurposeTransition {
                    from: 1,
                    to: 3,
                    pattern: gate("NMT", vec![ValuePattern::Range(0x81, 0x82)]),
                },
                PurposeTransition {
                    from: 1,
                    to: 1,
                    pattern: LabelPattern::Otherwise,
                },
            ],
        }
    }

    #[test]
    fn steps_follow_patterns_otherwise_and_implicit_completion() {
        let p = purpose();
        let l = |t: &str| LabelText::parse(t).unwrap();
        let (start, ec5, reset, other) = (l("NMT !0x01 !5"), l("EC !0x05"), l("NMT !0x81 !0"), l("EC !0x7F"));
        assert_eq!(p.step(0, Seen::Label(None, &ec5)), 0, "implicit completion");
        assert_eq!(p.step(0, Seen::Label(None, &start)), 1);
        assert_eq!(p.step(1, Seen::Label(None, &other)), 1, "otherwise");
        assert_eq!(p.step(1, Seen::Quiescence), 1);
        assert_eq!(p.step(1, Seen::Label(None, &ec5)), 2);
        assert_eq!(p.step(1, Seen::Label(None, &reset)), 3);
        assert_eq!(p.marker(2), Marker::Accept);
        assert!(p.problems().is_empty(), "{:?}", p.problems());
    }

    #[test]
    fn non_sinks_and_overlaps_are_problems() {
        let mut p = purpose();
        p.transitions.push(PurposeTransition {
            from: 2,
            to: 0,
            pattern: LabelPattern::Quiescence,
        });
        p.transitions.push(PurposeTransition {
            from: 1,
            to: 0,
            pattern: gate("EC", vec![ValuePattern::Range(0, 9)]),
        });
        let problems = p.problems();
        assert_eq!(problems.len(), 2, "{problems:?}");
        assert!(problems[0].contains("sinks"));
        assert!(problems[1].contains("not deterministic"));
    }

    #[test]
    fn purposes_read_from_aut_in_the_tgv_convention() {
        let (lts, d) = crate::aut::read(
            "des (1, 5, 3)\n(1, \"?NMT !0x02 !_\", 0)\n(0, \"!EC !0x04\", 2)\n(0, *, 0)\n(2, ACCEPT, 2)\n(1, QUIESCENCE, 1)\n",
        );
        assert!(d.is_empty(), "{d:?}");
        let p = from_aut("stop", &lts).unwrap();
        assert_eq!(p.marker(2), Marker::Accept);
        let l = |t: &str| LabelText::parse(t).unwrap();
        // The header's initial state 1 became state 0.
        let stopped = p.step(0, Seen::Label(Some(Direction::Input), &l("NMT !0x02 !0x05")));
        assert_eq!(stopped, 1);
        assert_eq!(
            p.step(stopped, Seen::Label(Some(Direction::Output), &l("EC !0x04"))),
            2
        );
        assert_eq!(
            p.step(stopped, Seen::Label(Some(Direction::Output), &l("EC !0x05"))),
            stopped
        );
        let (bad, _) = crate::aut::read("des (0, 1, 2)\n(0, ACCEPT, 1)\n");
        assert!(from_aut("x", &bad).unwrap_err().contains("loop"));
        // Found by the fuzzer: an initial state beyond the declared ones.
        let (bad, _) = crate::aut::read("des(2,0,1)");
        assert!(from_aut("x", &bad).unwrap_err().contains("initial state 2"));
    }
}

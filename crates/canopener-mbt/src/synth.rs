//! TGV-style synthesis of the complete test graph (CTG) of a specification and a test purpose
//! (design note §2.2): suspension (δ loops on quiescent states), determinisation (subset
//! construction over visible labels), the synchronous product with the purpose, and pruning by
//! co-reachability of the purpose's accepting states.
//!
//! The result is an LTS in the specification's label convention (`?GATE ..` the tester sends,
//! `!GATE ..` the device sends, `QUIESCENCE` for δ) plus verdict loops: a state with a `PASS` loop
//! reached the purpose; a state with an `INCONCLUSIVE` loop was reached by an output the
//! specification allows but from which the purpose cannot be reached any more. Outputs absent from
//! the graph are `fail` (left implicit, as TGV does). Inputs that lead away from the purpose are cut.
//! States are numbered breadth first with labels in order, which is canonical for a deterministic
//! graph: two CTGs are equal up to state renaming iff their [`canonical`] forms are equal.

use std::collections::{BTreeMap, BTreeSet, VecDeque};

use crate::explore::Lts;
use crate::label::LabelText;
use crate::purpose::{Purpose, Seen};
use crate::syntax::ast::{Direction, Marker};

/// The δ label.
pub const QUIESCENCE: &str = "QUIESCENCE";
/// The verdict loop of states where the purpose is reached.
pub const PASS: &str = "PASS";
/// The verdict loop of states reached by an allowed output from which the purpose is out of reach.
pub const INCONCLUSIVE: &str = "INCONCLUSIVE";

/// What a label is, in the `.aut` convention.
fn direction(label: &str) -> Option<Direction> {
    match label.chars().next() {
        Some('?') => Some(Direction::Input),
        Some('!') => Some(Direction::Output),
        _ => None,
    }
}

fn is_internal(label: &str) -> bool {
    label == "i" || label == "tau"
}

/// The complete test graph of `spec` for `purpose`, or `None` if no accepting state is reachable.
pub fn synthesize(spec: &Lts, purpose: &Purpose) -> Option<Lts> {
    // By state, only for the states transitions mention: a header may declare any number of states.
    let mut succ: BTreeMap<usize, Vec<(&str, usize)>> = BTreeMap::new();
    for (from, label, to) in &spec.transitions {
        succ.entry(*from).or_default().push((label.as_str(), *to));
    }
    let none: Vec<(&str, usize)> = Vec::new();
    let succ = |s: usize| succ.get(&s).unwrap_or(&none);
    let closure = |set: BTreeSet<usize>| -> BTreeSet<usize> {
        let mut out = set.clone();
        let mut work: Vec<usize> = set.into_iter().collect();
        while let Some(s) = work.pop() {
            for (l, t) in succ(s) {
                if is_internal(l) && out.insert(*t) {
                    work.push(*t);
                }
            }
        }
        out
    };
    // Suspension: a state is quiescent if it has no output and no internal step.
    let quiescent = |s: usize| {
        succ(s)
            .iter()
            .all(|(l, _)| direction(l) == Some(Direction::Input))
    };

    type Node = (BTreeSet<usize>, usize);
    let start: Node = (closure(BTreeSet::from([spec.initial])), 0);
    let mut index: BTreeMap<Node, usize> = BTreeMap::new();
    let mut nodes: Vec<Node> = vec![start.clone()];
    index.insert(start, 0);
    let mut edges: Vec<(usize, String, usize)> = Vec::new();
    let mut queue = VecDeque::from([0usize]);
    while let Some(n) = queue.pop_front() {
        // Only positions in `nodes` are queued.
        let Some((set, p)) = nodes.get(n).cloned() else {
            continue;
        };
        if purpose.marker(p) != Marker::None {
            continue;
        }
        let mut by_label: BTreeMap<String, BTreeSet<usize>> = BTreeMap::new();
        for &s in &set {
            for (l, t) in succ(s) {
                if !is_internal(l) {
                    by_label.entry((*l).to_owned()).or_default().insert(*t);
                }
            }
            if quiescent(s) {
                by_label.entry(QUIESCENCE.to_owned()).or_default().insert(s);
            }
        }
        for (label, targets) in by_label {
            let seen_text;
            let seen = if label == QUIESCENCE {
                Seen::Quiescence
            } else {
                // Any text may come from an .aut file: strip the direction by character.
                let rest = label.strip_prefix(['?', '!']).unwrap_or(&label);
                let Some(text) = LabelText::parse(rest) else {
                    continue;
                };
                seen_text = text;
                Seen::Label(direction(&label), &seen_text)
            };
            let next: Node = (closure(targets), purpose.step(p, seen));
            let target = match index.get(&next) {
                Some(i) => *i,
                None => {
                    let i = nodes.len();
                    index.insert(next.clone(), i);
                    nodes.push(next);
                    queue.push_back(i);
                    i
                }
            };
            edges.push((n, label, target));
        }
    }
    // Co-reachability of the accepting states, never through a refusing one.
    let accept: Vec<bool> = nodes
        .iter()
        .map(|(_, p)| purpose.marker(*p) == Marker::Accept)
        .collect();
    let refuse: Vec<bool> = nodes
        .iter()
        .map(|(_, p)| purpose.marker(*p) == Marker::Refuse)
        .collect();
    // Edges join positions in `nodes`, which the flags are per.
    let flag = |flags: &[bool], node: usize| flags.get(node).copied().unwrap_or(false);
    let mut reaches = accept.clone();
    let mut changed = true;
    while changed {
        changed = false;
        for (from, _, to) in &edges {
            if flag(&reaches, *to)
                && !flag(&reaches, *from)
                && !flag(&refuse, *from)
                && let Some(reached) = reaches.get_mut(*from)
            {
                *reached = true;
                changed = true;
            }
        }
    }
    if !flag(&reaches, 0) {
        return None;
    }
    let mut kept = Vec::new();
    let mut inconclusive = BTreeSet::new();
    for (from, label, to) in edges {
        if !flag(&reaches, from) || flag(&accept, from) {
            continue;
        }
        if flag(&reaches, to) {
            kept.push((from, label, to));
        } else if direction(&label) != Some(Direction::Input) {
            // An allowed observation that leaves the purpose behind: inconclusive, not fail.
            inconclusive.insert(to);
            kept.push((from, label, to));
        }
    }
    for (i, (a, r)) in accept.iter().zip(&reaches).enumerate() {
        if *a && *r {
            kept.push((i, PASS.to_owned(), i));
        }
    }
    for i in inconclusive {
        kept.push((i, INCONCLUSIVE.to_owned(), i));
    }
    Some(canonical(&Lts {
        initial: 0,
        states: nodes.len(),
        transitions: kept,
    }))
}

/// The LTS renumbered breadth first from its initial state, following labels in order, with the
/// states it cannot reach left out and the transitions sorted.
pub fn canonical(lts: &Lts) -> Lts {
    let mut succ: BTreeMap<usize, Vec<(&str, usize)>> = BTreeMap::new();
    for (from, label, to) in &lts.transitions {
        succ.entry(*from).or_default().push((label.as_str(), *to));
    }
    for list in succ.values_mut() {
        list.sort();
    }
    let mut number: BTreeMap<usize, usize> = BTreeMap::from([(lts.initial, 0)]);
    let mut queue = VecDeque::from([lts.initial]);
    let mut transitions = Vec::new();
    while let Some(s) = queue.pop_front() {
        // Every queued state was numbered first.
        let Some(&from) = number.get(&s) else {
            continue;
        };
        for (label, t) in succ.get(&s).cloned().unwrap_or_default() {
            let next = number.len();
            let n = *number.entry(t).or_insert_with(|| {
                queue.push_back(t);
                next
            });
            transitions.push((from, label.to_owned(), n));
        }
    }
    transitions.sort();
    Lts {
        initial: 0,
        states: number.len(),
        transitions,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aut;
    use crate::compile::tests::one;
    use crate::explore::explore;

    /// Synthesises the CTG of the first purpose of `model` and compares it with `expected` (an
    /// `.aut` text numbered freely) up to state renaming.
    fn check(model: &str, expected: &str) {
        let (model, d) = one(model);
        assert!(d.is_empty(), "{d:#?}");
        let model = model.unwrap();
        let (space, _) = explore(&model, 1000);
        let ctg = synthesize(&space.lts, &model.purposes[0]).expect("the purpose is reachable");
        let (expected, d) = aut::read(expected);
        assert!(d.is_empty(), "{d:?}");
        assert_eq!(aut::write(&ctg), aut::write(&canonical(&expected)));
    }

    /// A request answered by one of two responses; the purpose wants the second. The first is an
    /// allowed output after which the purpose cannot be reached: inconclusive.
    #[test]
    fn a_choice_of_outputs_gives_pass_and_inconclusive() {
        check(
            "model m\ninput REQ = 0x601 (v: u8)\noutput OK = 0x581 (v: u8)\nclock t\n\
             process p {\n location Idle, Busy, Done\n Idle -> Busy: in REQ(1) reset t\n Busy -> Done: out OK(1) within 0..1ms of t\n \
             Busy -> Idle: out OK(2) within 0..1ms of t\n}\n\
             purpose two {\n state s, hit accept\n s -> hit: out OK(2)\n}\n",
            "des (7, 6, 8)\n(7, \"?REQ !0x01\", 3)\n(7, QUIESCENCE, 7)\n(3, \"!OK !0x01\", 5)\n(3, \"!OK !0x02\", 1)\n(1, PASS, 1)\n(5, INCONCLUSIVE, 5)\n",
        );
    }

    /// Two inputs, one of which leads away (a refuse state cuts it); quiescence before the input.
    #[test]
    fn refused_branches_are_cut() {
        check(
            "model m\ninput CMD = 0 (cs: u8)\noutput EC = 0x705 (s: u8)\nclock t\n\
             process p {\n location Pre, Op, Stopped\n Pre -> Op: in CMD(1) reset t\n Pre -> Stopped: in CMD(2) reset t\n \
             Op -> same: out EC(5) within 0..1ms of t reset t\n Stopped -> same: out EC(4) within 0..1ms of t reset t\n}\n\
             purpose start {\n state s, started, hit accept, stop refuse\n s -> started: in CMD(1)\n s -> stop: in CMD(2)\n started -> hit: out EC(5)\n}\n",
            "des (0, 4, 3)\n(0, \"?CMD !0x01\", 1)\n(0, QUIESCENCE, 0)\n(1, \"!EC !0x05\", 2)\n(2, PASS, 2)\n",
        );
    }

    /// An internal step before the output: determinisation merges the states around it.
    #[test]
    fn internal_steps_are_determinised_away() {
        check(
            "model m\ninput GO = 1 (v: u8)\noutput A = 2 (v: u8)\noutput B = 3 (v: u8)\nclock t\n\
             process p {\n location S, T, U, W\n S -> T: in GO(0) reset t\n T -> U: internal within 0..1ms of t\n \
             T -> W: out A(0) within 0..1ms of t\n U -> W: out B(0) within 0..2ms of t\n}\n\
             purpose b {\n state s, hit accept\n s -> hit: out B(_)\n}\n",
            "des (0, 6, 5)\n(0, \"?GO !0x00\", 1)\n(0, QUIESCENCE, 0)\n(1, \"!A !0x00\", 3)\n(1, \"!B !0x00\", 2)\n(2, PASS, 2)\n(3, INCONCLUSIVE, 3)\n",
        );
    }

    #[test]
    fn an_unreachable_purpose_gives_nothing() {
        let (model, _) = one(
            "model m\ninput I = 1 (v: u8)\noutput O = 2 (v: u8)\nclock t\nprocess p {\n location A\n A -> A: in I(1)\n}\npurpose never {\n state s, hit accept\n s -> hit: out O(_)\n}\n",
        );
        let model = model.unwrap();
        let (space, _) = explore(&model, 100);
        assert_eq!(synthesize(&space.lts, &model.purposes[0]), None);
    }

    /// Found by the fuzzer: a label starting with a multi-byte character.
    #[test]
    fn labels_of_any_text_synthesise_without_panicking() {
        let spec = Lts {
            initial: 0,
            states: 2,
            transitions: vec![(0, "\u{FFFD}x".into(), 1), (0, "?é".into(), 1)],
        };
        let purpose = crate::purpose::from_aut(
            "p",
            &Lts {
                initial: 0,
                states: 2,
                transitions: vec![(0, "*".into(), 1), (1, "ACCEPT".into(), 1)],
            },
        )
        .unwrap();
        assert!(synthesize(&spec, &purpose).is_some());
    }
}

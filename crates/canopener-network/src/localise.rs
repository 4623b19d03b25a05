//! Which cable broke, which device died or which supply went off, from the set of devices the
//! monitor no longer hears (`../shared/reference/topology-formats.md` §5.4–5.5).
//!
//! Every single fault the topology allows is a *hypothesis* with the set of devices it would silence:
//! the cut of each cable, the death of each device and active coupler, the loss of each supply domain
//! and the monitor's own connection. A hypothesis explains part of what is silent only if everything
//! it predicts is silent. The diagnosis is the smallest number of faults whose predictions cover the
//! silent set (parsimony): the cable and device faults form a laminar family (subtrees of the tree
//! rooted at the monitor), so the maximal silent subtrees are the fewest of them that cover; supply
//! domains, which need not be contiguous on the cable, are tried in every combination on top (up to
//! [`EXHAUSTIVE_SUPPLY_DOMAINS`], greedily beyond). Each covering set is reported once per kind with
//! every hypothesis of that kind predicting exactly it: the ambiguity group of equivalent cables, the
//! device (a drop cable or its device), the supply domain, the monitor.

use std::collections::{BTreeMap, BTreeSet};

use serde::Serialize;

use crate::model::{Cable, Topology};
use crate::wiring::{Faults, Wiring};

/// Supply domains whose combinations are tried exhaustively (2^n); beyond, a greedy choice.
pub const EXHAUSTIVE_SUPPLY_DOMAINS: usize = 12;

/// What kind of fault an explanation names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    /// A cable cut (candidates: `CableName`, else the edge id).
    Cable,
    /// A device or active coupler dead (candidates: `NodeName`, else the vertex id).
    Device,
    /// A supply domain off (candidates: the `SupplyDomain` values).
    Supply,
    /// The monitor's own connection (candidates: the monitor's vertex).
    Monitor,
}

impl Kind {
    /// The word the JSON events use.
    pub fn as_str(self) -> &'static str {
        match self {
            Kind::Cable => "cable",
            Kind::Device => "device",
            Kind::Supply => "supply",
            Kind::Monitor => "monitor",
        }
    }
}

/// One single fault and what it would silence.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Hypothesis {
    /// Its kind.
    pub kind: Kind,
    /// What it names.
    pub candidate: String,
    /// The devices (indices into [`Wiring::devices`]) it silences.
    pub predicts: BTreeSet<usize>,
}

/// One explanation of (part of) a silent set.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Explanation {
    /// The kind of fault.
    pub kind: Kind,
    /// The ambiguity group: every fault of this kind that predicts exactly `explains`.
    pub candidates: Vec<String>,
    /// The devices (indices into [`Wiring::devices`]) it accounts for.
    pub explains: BTreeSet<usize>,
}

/// The hypotheses of one network, computed once, and the diagnosis of any silent set.
#[derive(Debug, Clone)]
pub struct Localiser {
    hypotheses: Vec<Hypothesis>,
}

impl Localiser {
    /// Every single-fault hypothesis of `wiring` with its prediction. A network without cables (a cpj)
    /// has only device and supply hypotheses.
    pub fn new(topology: &Topology, wiring: &Wiring) -> Localiser {
        let mut hypotheses = Vec::new();
        let mut add = |kind: Kind, candidate: String, faults: Faults| {
            let predicts = wiring.silent_under(&faults);
            if !predicts.is_empty() {
                hypotheses.push(Hypothesis {
                    kind,
                    candidate,
                    predicts,
                });
            }
        };
        for cable in wiring.cables() {
            // The wiring's cables are positions in the topology it was built from.
            let Some(label) = topology.cables.get(cable).map(Cable::label) else {
                continue;
            };
            let faults = Faults {
                cut: [cable].into(),
                ..Faults::none()
            };
            add(Kind::Cable, label, faults);
        }
        let mut dead: Vec<usize> = wiring
            .devices()
            .iter()
            .filter(|d| !d.is_monitor)
            .map(|d| d.vertex)
            .collect();
        dead.extend(wiring.active_vertices());
        for vertex in dead {
            let Some(label) = topology.vertices.get(vertex).map(|v| v.label().to_owned()) else {
                continue;
            };
            let faults = Faults {
                dead: [vertex].into(),
                ..Faults::none()
            };
            add(Kind::Device, label, faults);
        }
        for domain in topology.supply_domains() {
            let faults = Faults {
                unpowered: [domain.to_owned()].into(),
                ..Faults::none()
            };
            add(Kind::Supply, domain.to_owned(), faults);
        }
        if wiring.has_cables() {
            let all: BTreeSet<usize> = wiring
                .devices()
                .iter()
                .enumerate()
                .filter(|(_, d)| !d.is_monitor)
                .map(|(index, _)| index)
                .collect();
            let monitor = topology
                .vertices
                .get(wiring.root_vertex())
                .map(|v| v.label().to_owned());
            if let Some(monitor) = monitor
                && !all.is_empty()
            {
                hypotheses.push(Hypothesis {
                    kind: Kind::Monitor,
                    candidate: monitor,
                    predicts: all,
                });
            }
        }
        Localiser { hypotheses }
    }

    /// The hypotheses.
    pub fn hypotheses(&self) -> &[Hypothesis] {
        &self.hypotheses
    }

    /// The explanations of `silent` (devices the monitor does not hear) among `watched` (the devices it
    /// can tell about: monitored ones; unwatched devices neither confirm nor refute a hypothesis).
    /// Ordered by the first device each accounts for, then by kind.
    pub fn explain(&self, watched: &BTreeSet<usize>, silent: &BTreeSet<usize>) -> Vec<Explanation> {
        let silent: BTreeSet<usize> = silent.intersection(watched).copied().collect();
        if silent.is_empty() {
            return Vec::new();
        }
        // Every prediction, seen through what is watched, that is wholly silent.
        let fitting: Vec<(&Hypothesis, BTreeSet<usize>)> = self
            .hypotheses
            .iter()
            .map(|h| {
                (
                    h,
                    h.predicts
                        .intersection(watched)
                        .copied()
                        .collect::<BTreeSet<usize>>(),
                )
            })
            .filter(|(_, p)| !p.is_empty() && p.is_subset(&silent))
            .collect();
        let laminar: BTreeSet<&BTreeSet<usize>> = fitting
            .iter()
            .filter(|(h, _)| h.kind != Kind::Supply)
            .map(|(_, p)| p)
            .collect();
        let maximal: Vec<&BTreeSet<usize>> = laminar
            .iter()
            .filter(|p| !laminar.iter().any(|q| q.len() > p.len() && p.is_subset(q)))
            .copied()
            .collect();
        let supplies: Vec<&BTreeSet<usize>> = {
            let distinct: BTreeSet<&BTreeSet<usize>> = fitting
                .iter()
                .filter(|(h, _)| h.kind == Kind::Supply)
                .map(|(_, p)| p)
                .collect();
            distinct.into_iter().collect()
        };
        let chosen = choose_supplies(&silent, &maximal, &supplies);
        let covered: BTreeSet<usize> = chosen.iter().flat_map(|s| s.iter().copied()).collect();
        let mut groups: Vec<BTreeSet<usize>> = chosen.into_iter().cloned().collect();
        for set in &maximal {
            // Tree faults are needed for what the supplies leave; a fault whose devices a supply covers
            // entirely is the supply's alternative if it predicts the same set, and else not needed.
            if set.iter().any(|d| !covered.contains(d)) && !groups.contains(set) {
                groups.push((*set).clone());
            }
        }
        // Devices that no hypothesis fits (a device of a cpj the monitor never heard) are each their own.
        let explained: BTreeSet<usize> = groups.iter().flat_map(|g| g.iter().copied()).collect();
        groups.extend(silent.difference(&explained).map(|&d| BTreeSet::from([d])));
        groups.sort_by_key(|g| g.iter().next().copied());
        let mut explanations = Vec::new();
        for group in groups {
            let mut by_kind: BTreeMap<Kind, Vec<String>> = BTreeMap::new();
            for (hypothesis, predicts) in &fitting {
                if *predicts == group {
                    let candidates = by_kind.entry(hypothesis.kind).or_default();
                    if !candidates.contains(&hypothesis.candidate) {
                        candidates.push(hypothesis.candidate.clone());
                    }
                }
            }
            explanations.extend(by_kind.into_iter().map(|(kind, candidates)| Explanation {
                kind,
                candidates,
                explains: group.clone(),
            }));
        }
        explanations
    }
}

/// The supply domains to blame, fewest faults first: the combination minimising (supplies chosen) +
/// (maximal tree faults still needed), preferring fewer supplies on a tie.
fn choose_supplies<'a>(
    silent: &BTreeSet<usize>,
    maximal: &[&BTreeSet<usize>],
    supplies: &[&'a BTreeSet<usize>],
) -> Vec<&'a BTreeSet<usize>> {
    let cost = |chosen: &[&BTreeSet<usize>]| -> (usize, usize) {
        let covered: BTreeSet<usize> = chosen.iter().flat_map(|s| s.iter().copied()).collect();
        let rest: BTreeSet<usize> = silent.difference(&covered).copied().collect();
        let trees = maximal
            .iter()
            .filter(|m| m.iter().any(|d| rest.contains(d)))
            .count();
        let loose = rest
            .iter()
            .filter(|d| !maximal.iter().any(|m| m.contains(d)))
            .count();
        (chosen.len() + trees + loose, chosen.len())
    };
    if supplies.len() <= EXHAUSTIVE_SUPPLY_DOMAINS {
        let mut best: (Vec<&BTreeSet<usize>>, (usize, usize)) = (Vec::new(), cost(&[]));
        for mask in 1u32..(1 << supplies.len()) {
            let chosen: Vec<&BTreeSet<usize>> = supplies
                .iter()
                .enumerate()
                .filter(|(i, _)| mask & (1 << i) != 0)
                .map(|(_, s)| *s)
                .collect();
            let c = cost(&chosen);
            if c < best.1 {
                best = (chosen, c);
            }
        }
        return best.0;
    }
    let mut chosen: Vec<&BTreeSet<usize>> = Vec::new();
    loop {
        let current = cost(&chosen);
        let better = supplies
            .iter()
            .filter(|s| !chosen.contains(s))
            .map(|s| {
                let mut next = chosen.clone();
                next.push(s);
                (cost(&next), *s)
            })
            .filter(|(c, _)| c.0 < current.0)
            .min_by_key(|(c, _)| *c);
        match better {
            Some((_, s)) => chosen.push(s),
            None => return chosen,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wiring::tests::system;

    fn explain(topology: &Topology, silent: &[&str]) -> Vec<(Kind, Vec<String>, Vec<String>)> {
        let wiring = Wiring::new(topology, 1, None).unwrap();
        let localiser = Localiser::new(topology, &wiring);
        let index = |name: &str| wiring.devices().iter().position(|d| d.name == name).unwrap();
        let watched: BTreeSet<usize> = (0..wiring.devices().len()).collect();
        let silent: BTreeSet<usize> = silent.iter().map(|n| index(n)).collect();
        localiser
            .explain(&watched, &silent)
            .into_iter()
            .map(|e| {
                let explains = e
                    .explains
                    .iter()
                    .map(|&d| wiring.devices()[d].name.clone())
                    .collect();
                (e.kind, e.candidates, explains)
            })
            .collect()
    }

    fn strings(items: &[&str]) -> Vec<String> {
        items.iter().map(|s| (*s).to_owned()).collect()
    }

    /// m (monitor, node 1) — W1 — a — W2 — j — W3 — b, j — W4 — c: a trunk with a junction.
    fn trunk() -> Topology {
        system(
            &[
                ("m", 1, Some("A")),
                ("a", 2, Some("A")),
                ("b", 3, Some("B")),
                ("c", 4, Some("B")),
            ],
            &[("j", "junction")],
            &[
                ("W1", "m", "a"),
                ("W2", "a", "j"),
                ("W3", "j", "b"),
                ("W4", "j", "c"),
            ],
        )
    }

    #[test]
    fn a_cut_names_its_ambiguity_group_and_the_supply_that_predicts_the_same() {
        assert_eq!(
            explain(&trunk(), &["b", "c"]),
            [
                (Kind::Cable, strings(&["W2"]), strings(&["b", "c"])),
                (Kind::Supply, strings(&["B"]), strings(&["b", "c"])),
            ]
        );
        assert_eq!(
            explain(&trunk(), &["b"]),
            [
                (Kind::Cable, strings(&["W3"]), strings(&["b"])),
                (Kind::Device, strings(&["b"]), strings(&["b"])),
            ]
        );
    }

    #[test]
    fn everything_silent_is_the_first_cable_the_monitor_or_both_supplies() {
        let all = explain(&trunk(), &["a", "b", "c"]);
        assert_eq!(
            all,
            [
                (Kind::Cable, strings(&["W1"]), strings(&["a", "b", "c"])),
                (Kind::Monitor, strings(&["m"]), strings(&["a", "b", "c"])),
            ]
        );
    }

    #[test]
    fn two_faults_in_different_branches_give_two_explanations() {
        let topology = system(
            &[
                ("m", 1, None),
                ("a", 2, None),
                ("b", 3, None),
                ("c", 4, None),
                ("d", 5, None),
            ],
            &[("j", "junction")],
            &[
                ("W1", "m", "j"),
                ("W2", "j", "a"),
                ("W3", "a", "b"),
                ("W4", "j", "c"),
                ("W5", "c", "d"),
            ],
        );
        let found = explain(&topology, &["b", "d"]);
        let sets: BTreeSet<Vec<String>> = found.iter().map(|(_, _, e)| e.clone()).collect();
        assert_eq!(sets.len(), 2, "{found:?}");
        assert!(found.contains(&(Kind::Cable, strings(&["W3"]), strings(&["b"]))));
        assert!(found.contains(&(Kind::Cable, strings(&["W5"]), strings(&["d"]))));
    }

    #[test]
    fn a_scattered_supply_domain_is_one_fault_not_many() {
        let topology = system(
            &[
                ("m", 1, None),
                ("a", 2, Some("F1")),
                ("b", 3, None),
                ("c", 4, Some("F1")),
            ],
            &[],
            &[("W1", "m", "a"), ("W2", "a", "b"), ("W3", "b", "c")],
        );
        assert_eq!(
            explain(&topology, &["a", "c"]),
            [(Kind::Supply, strings(&["F1"]), strings(&["a", "c"]))]
        );
    }

    #[test]
    fn a_dead_hub_and_its_feeder_are_alternatives() {
        let topology = system(
            &[("m", 1, None), ("a", 2, None), ("b", 3, None)],
            &[("hub", "hub")],
            &[("W1", "m", "hub"), ("W2", "hub", "a"), ("W3", "hub", "b")],
        );
        assert_eq!(
            explain(&topology, &["a", "b"]),
            [
                (Kind::Cable, strings(&["W1"]), strings(&["a", "b"])),
                (Kind::Device, strings(&["hub"]), strings(&["a", "b"])),
                (Kind::Monitor, strings(&["m"]), strings(&["a", "b"])),
            ]
        );
    }

    #[test]
    fn a_cpj_can_only_blame_devices() {
        let topology = system(&[("m", 1, None), ("a", 2, None), ("b", 3, None)], &[], &[]);
        assert_eq!(
            explain(&topology, &["a", "b"]),
            [
                (Kind::Device, strings(&["a"]), strings(&["a"])),
                (Kind::Device, strings(&["b"]), strings(&["b"])),
            ]
        );
    }
}

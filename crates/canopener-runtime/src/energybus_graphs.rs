//! The FORTE paper's test purposes for EnergyBus (seeds/003 §5.4) as complete test graphs, and runs
//! checked against them.
//!
//! [`PURPOSES`] names the purpose of each scenario the paper lists (the device side of EMS, the
//! controller side, the initialisation of unconfigured nodes via combinations of LSS communications,
//! the boot-up of configured nodes with their PDOs), [`graph`] synthesises its complete test graph
//! (`canopener_mbt::synth`, TGV style, on the untimed state space), and [`follows`] says whether a
//! run guided by the same purpose (the on-the-fly executor, which also judges time) stayed on the
//! graph and ended in a `PASS` state: the graph executed against the device.

use canopener_eds::Eds;
use canopener_mbt::compile::{Options, Source, compile};
use canopener_mbt::executor::{Dir, RunConfig, RunResult, TraceStep};
use canopener_mbt::explore::{Lts, explore};
use canopener_mbt::label::{LabelText, Offer};
use canopener_mbt::model::Model;
use canopener_mbt::shipped;
use canopener_mbt::synth::{PASS, QUIESCENCE, synthesize};
use canopener_wire::NodeId;

use crate::mbt_run;
use canopener_sim::energybus::system::{EnergyBusSystem, SystemError, ready_for_test};

/// One test purpose of the paper, in one shipped model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PaperPurpose {
    /// The scenario in the paper's words.
    pub scenario: &'static str,
    /// The shipped model.
    pub model: &'static str,
    /// The purpose's name in it.
    pub purpose: &'static str,
    /// The node-ID the model is instantiated with (FFh: an unconfigured device).
    pub node: u8,
}

/// The paper's scenarios and the purposes that make them.
pub const PURPOSES: [PaperPurpose; 6] = [
    PaperPurpose {
        scenario: "device side of EMS",
        model: "energybus-ems",
        purpose: "walk_to_operating",
        node: 2,
    },
    PaperPurpose {
        scenario: "controller side",
        model: "energybus-controller",
        purpose: "integrate_device",
        node: 2,
    },
    PaperPurpose {
        scenario: "controller side: reaction to a lost heartbeat",
        model: "energybus-controller",
        purpose: "lost_heartbeat",
        node: 2,
    },
    PaperPurpose {
        scenario: "initialisation of unconfigured nodes via combinations of LSS communications",
        model: "energybus-lss",
        purpose: "initialise_by_fastscan",
        node: 0xFF,
    },
    PaperPurpose {
        scenario: "initialisation of unconfigured nodes via combinations of LSS communications (any combination)",
        model: "energybus-lss",
        purpose: "initialise",
        node: 0xFF,
    },
    PaperPurpose {
        scenario: "boot-up of configured nodes, including the transmission of its PDOs with dynamic and static values",
        model: "energybus-ems",
        purpose: "boot_with_pdos",
        node: 2,
    },
];

/// The shipped model `name` for node `node`, its parameters read from `eds`.
pub fn model(name: &str, node: u8, eds: &Eds) -> Result<Model, String> {
    let text = shipped::text(name).ok_or_else(|| format!("no shipped model `{name}`"))?;
    let sources = [Source {
        origin: name.to_owned(),
        text: text.to_owned(),
    }];
    // An EnergyBus device forgets its LSS node-ID at reset node (docs/energybus.md): the CANopen
    // models start with reset communication and never send reset node.
    let options = Options {
        node_id: node,
        eds: Some(eds),
        set: vec![("KEEPS_NODE_ID".to_owned(), 0)],
    };
    let (model, report) = compile(&sources, &options, &|n| shipped::text(n).map(str::to_owned));
    model.ok_or_else(|| {
        let messages: Vec<String> = report
            .iter()
            .flat_map(|r| {
                r.diagnostics
                    .iter()
                    .map(|d| format!("{}: {}", r.origin, d.message))
            })
            .collect();
        messages.join("; ")
    })
}

/// One run of `model` against the system, testing `under_test` (see [`ready_for_test`]), on virtual
/// time: deterministic for the seed of `config`.
pub fn run(
    system: &EnergyBusSystem,
    under_test: Option<NodeId>,
    model: &Model,
    config: RunConfig,
) -> Result<RunResult, SystemError> {
    let (mut bus, _) = ready_for_test(system, under_test)?;
    Ok(mbt_run::run(&mut bus, model, config, None)?)
}

/// The complete test graph of `purpose` in `model` (explored to at most `max_states`), or `None`
/// when the model has no such purpose or it cannot be reached.
pub fn graph(model: &Model, purpose: &str, max_states: usize) -> Option<Lts> {
    let purpose = model.purposes.iter().find(|p| p.name == purpose)?;
    let (space, _) = explore(model, max_states);
    synthesize(&space.lts, purpose)
}

/// Whether a run's trace is a path of the test graph `ctg` from its initial state (after the first
/// `skip` steps, the model's reset stimuli, which the graph starts after) that ends in a `PASS`
/// state: `Ok(true)` if so, `Ok(false)` if it stayed on the graph without reaching `PASS`, and
/// `Err(step)` with the index of the first step the graph does not have.
///
/// The run is timed and the graph is not: the run observes quiescence after a bounded silence
/// (between two heartbeats, say), the graph has it only where no output may ever come. A quiescence
/// step is therefore followed where the graph has one and is time passing elsewhere.
pub fn follows(ctg: &Lts, trace: &[TraceStep], skip: usize) -> Result<bool, usize> {
    let mut current = vec![ctg.initial];
    for (index, step) in trace.iter().enumerate().skip(skip) {
        let seen = match step.dir {
            Dir::Quiescence => None,
            Dir::In | Dir::Out => Some(step.label.as_str()),
        };
        let mut next: Vec<usize> = ctg
            .transitions
            .iter()
            .filter(|(from, label, _)| current.contains(from) && matches(label, seen))
            .map(|(_, _, to)| *to)
            .collect();
        next.sort_unstable();
        next.dedup();
        match (next.is_empty(), seen) {
            (false, _) => current = next,
            (true, None) => {}
            (true, Some(_)) => return Err(index),
        }
    }
    Ok(ctg
        .transitions
        .iter()
        .any(|(from, label, _)| current.contains(from) && label == PASS))
}

/// Whether the graph's `label` (values may be `_`) admits the trace's label (`None`: quiescence).
fn matches(label: &str, seen: Option<&str>) -> bool {
    let Some(seen) = seen else {
        return label == QUIESCENCE;
    };
    let (Some(direction), Some(seen_direction)) = (label.chars().next(), seen.chars().next()) else {
        return false;
    };
    if direction != seen_direction || !matches!(direction, '?' | '!') {
        return false;
    }
    let (Some(expected), Some(got)) = (LabelText::parse(&label[1..]), LabelText::parse(&seen[1..])) else {
        return false;
    };
    expected.gate == got.gate
        && expected.values.len() == got.values.len()
        && expected
            .values
            .iter()
            .zip(&got.values)
            .all(|(e, g)| *e == Offer::Any || e == g)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(dir: Dir, label: &str) -> TraceStep {
        TraceStep {
            t: 0.0,
            dir,
            label: label.to_owned(),
            frame: None,
        }
    }

    #[test]
    fn a_trace_follows_a_graph_with_open_values_to_pass() {
        let ctg = Lts {
            initial: 0,
            states: 3,
            transitions: vec![
                (0, "?REQ !0x01".into(), 1),
                (1, "!RES !_".into(), 2),
                (1, QUIESCENCE.into(), 1),
                (2, PASS.into(), 2),
            ],
        };
        let reset = step(Dir::In, "?NMT !0x82 !0x02");
        let trace = [
            reset.clone(),
            step(Dir::In, "?REQ !0x01"),
            step(Dir::Quiescence, "quiescence 0.300s"),
            step(Dir::Out, "!RES !0x2A"),
        ];
        assert_eq!(follows(&ctg, &trace, 1), Ok(true));
        assert_eq!(follows(&ctg, &trace[..3], 1), Ok(false));
        assert_eq!(
            follows(&ctg, &trace, 0),
            Err(0),
            "the reset is no step of the graph"
        );
        let off = [reset.clone(), step(Dir::In, "?REQ !0x02")];
        assert_eq!(follows(&ctg, &off, 1), Err(1));
        // Quiescence where the graph has none is time passing.
        let waited = [
            reset,
            step(Dir::Quiescence, "quiescence 0.010s"),
            step(Dir::In, "?REQ !0x01"),
        ];
        assert_eq!(follows(&ctg, &waited, 1), Ok(false));
    }
}

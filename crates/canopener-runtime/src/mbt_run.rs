//! Model-based testing on a link: the driver loop of [`canopener_mbt::executor::Executor`]. The same
//! run works on a real bus on the wall clock and on a [`VirtualLink`](canopener_link::virtual_link::VirtualLink)
//! with simulated devices on virtual time, where it is deterministic.

use std::time::Duration;

use canopener_mbt::executor::{Executor, Outcome, RunConfig, ScriptStep};
use canopener_mbt::model::Model;

use canopener_link::link::{Ended, Flow, Link, LinkError, drive};

/// Tests the device behind `link` against `model` until the executor decides, `limit` passes
/// (a `pass` if nothing failed so far) or the link is cancelled (`inconclusive`).
pub fn run<L: Link + ?Sized>(
    link: &mut L,
    model: &Model,
    config: RunConfig,
    limit: Option<Duration>,
) -> Result<Outcome, LinkError> {
    let start = link.now();
    let mut executor = Executor::new(model, config, start);
    let deadline = limit.map(|limit| start + limit);
    let ended = drive(link, &mut executor, deadline, |_, outcome| {
        Ok::<_, LinkError>(Flow::Done(outcome))
    })?;
    Ok(match ended {
        Ok(outcome) => outcome,
        Err(Ended::Deadline) => executor.finish("the time limit passed without a failure"),
        Err(Ended::Cancelled) => {
            let mut outcome = executor.finish("cancelled");
            outcome.verdict = canopener_mbt::executor::Verdict::Inconclusive;
            outcome
        }
    })
}

/// A failing run's inputs shrunk by delta debugging against the device.
#[derive(Debug, Clone)]
pub struct Shrunk {
    /// The inputs of the failing run.
    pub before: Vec<ScriptStep>,
    /// The shortest failing script found; 1-minimal. Kept inputs keep their recorded times.
    pub after: Vec<ScriptStep>,
    /// How many runs shrinking took.
    pub runs: usize,
    /// The outcome of the shortened script (a `fail`).
    pub outcome: Outcome,
}

/// Shrinks `inputs` (a failing run's, see [`Outcome::script`]) to the shortest script that still
/// fails on the device. `link_for_run` gives the link for each run: a fresh simulation on virtual
/// time, or the same bus again (each run starts with the model's reset stimuli).
pub fn shrink<L: Link, E: From<LinkError>>(
    link_for_run: &mut dyn FnMut() -> Result<L, E>,
    model: &Model,
    config: &RunConfig,
    inputs: &[ScriptStep],
    limit: Option<Duration>,
) -> Result<Option<Shrunk>, E> {
    let mut error = None;
    let mut last_fail: Option<(Vec<ScriptStep>, Outcome)> = None;
    let mut fails = |script: &[ScriptStep]| -> bool {
        if error.is_some() {
            return false;
        }
        let scripted = RunConfig {
            script: Some(script.to_vec()),
            ..config.clone()
        };
        let outcome = link_for_run().and_then(|mut link| Ok(run(&mut link, model, scripted, limit)?));
        match outcome {
            Ok(outcome) if outcome.verdict == canopener_mbt::executor::Verdict::Fail => {
                if last_fail.as_ref().is_none_or(|(s, _)| s.len() >= script.len()) {
                    last_fail = Some((script.to_vec(), outcome));
                }
                true
            }
            Ok(_) => false,
            Err(e) => {
                error = Some(e);
                false
            }
        }
    };
    if !fails(inputs) {
        return match error {
            Some(e) => Err(e),
            None => Ok(None),
        };
    }
    let (after, runs) = canopener_mbt::shrink::ddmin(inputs, &mut fails);
    if let Some(e) = error {
        return Err(e);
    }
    // The outcome of exactly the kept script (ddmin's last failing test may be a longer one).
    let outcome = match last_fail {
        Some((script, outcome)) if script == after => outcome,
        _ => {
            let scripted = RunConfig {
                script: Some(after.clone()),
                ..config.clone()
            };
            run(&mut link_for_run()?, model, scripted, limit)?
        }
    };
    Ok(Some(Shrunk {
        before: inputs.to_vec(),
        after,
        runs: runs + 1,
        outcome,
    }))
}

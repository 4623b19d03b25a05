//! Model-based testing on a link: the driver loop of [`canopener_mbt::executor::Executor`]. The same
//! run works on a real bus on the wall clock and on a [`VirtualLink`](canopener_link::virtual_link::VirtualLink)
//! with simulated devices on virtual time, where it is deterministic.

use std::time::Duration;

use canopener_mbt::executor::{Executor, RunConfig, RunResult, ScriptStep};
use canopener_mbt::model::Model;
use rayon::prelude::*;

use canopener_link::link::{Ended, Flow, Link, LinkError, drive};

/// Tests the device behind `link` against `model` until the executor decides, `limit` passes
/// (a `pass` if nothing failed so far) or the link is cancelled (`inconclusive`).
pub fn run<L: Link + ?Sized>(
    link: &mut L,
    model: &Model,
    config: RunConfig,
    limit: Option<Duration>,
) -> Result<RunResult, LinkError> {
    run_watched(link, model, config, limit, &mut |_| {})
}

/// [`run`], telling `on_step` the number of steps taken each time it grows (a progress bar for a
/// long run on a real bus).
pub fn run_watched<L: Link + ?Sized>(
    link: &mut L,
    model: &Model,
    config: RunConfig,
    limit: Option<Duration>,
    on_step: &mut dyn FnMut(usize),
) -> Result<RunResult, LinkError> {
    let start = link.now();
    let mut watched = Watched {
        executor: Executor::new(model, config, start),
        steps: 0,
        on_step,
    };
    let deadline = limit.map(|limit| start + limit);
    let ended = drive(link, &mut watched, deadline, |_, outcome| {
        Ok::<_, LinkError>(Flow::Done(outcome))
    })?;
    let executor = &mut watched.executor;
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

/// The executor with an observer of its step count: the core the driver loop sees.
struct Watched<'m, 'f> {
    executor: Executor<'m>,
    steps: usize,
    on_step: &'f mut dyn FnMut(usize),
}

impl std::fmt::Debug for Watched<'_, '_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Watched")
            .field("steps", &self.steps)
            .finish_non_exhaustive()
    }
}

impl Watched<'_, '_> {
    fn tell(&mut self) {
        let steps = self.executor.steps_taken();
        if steps != self.steps {
            self.steps = steps;
            (self.on_step)(steps);
        }
    }
}

impl canopener_can::Core for Watched<'_, '_> {
    type Event = RunResult;

    fn handle_frame(&mut self, now: canopener_can::Instant, frame: &canopener_can::CanFrame) {
        self.executor.handle_frame(now, frame);
        self.tell();
    }

    fn handle_timeout(&mut self, now: canopener_can::Instant) {
        self.executor.handle_timeout(now);
        self.tell();
    }

    fn poll_transmit(&mut self) -> Option<canopener_can::CanFrame> {
        self.executor.poll_transmit()
    }

    fn poll_event(&mut self) -> Option<RunResult> {
        self.executor.poll_event()
    }

    fn poll_timeout(&self) -> Option<canopener_can::Instant> {
        self.executor.poll_timeout()
    }
}

/// One seed's run of a campaign ([`run_seeds`]).
#[derive(Debug, Clone)]
pub struct SeedRun {
    /// The seed.
    pub seed: u64,
    /// What the run found.
    pub outcome: RunResult,
    /// Wall-clock time the run took.
    pub wall: Duration,
}

/// A campaign's runs ([`run_seeds`]) and the wall-clock time it took.
#[derive(Debug, Clone)]
pub struct Campaign {
    /// One run per seed, in the order of the seeds.
    pub runs: Vec<SeedRun>,
    /// Wall-clock time of the whole campaign.
    pub wall: Duration,
    /// How many runs went at once (the threads of the pool).
    pub threads: usize,
}

/// Runs `model` once per seed of `seeds`, the seeds in parallel on the machine's cores (a rayon
/// pool), each on its own link from `link_for_seed` (a fresh simulated device on virtual time: each
/// run is deterministic, so the order they finish in changes nothing). `on_done` is told of each run
/// as it ends (a progress bar). The runs come back in the order of `seeds`; the first error stops
/// the campaign.
pub fn run_seeds<L, E, F>(
    seeds: &[u64],
    link_for_seed: F,
    model: &Model,
    config: &RunConfig,
    limit: Option<Duration>,
    on_done: &(dyn Fn(&SeedRun) + Sync),
) -> Result<Campaign, E>
where
    L: Link,
    E: From<LinkError> + Send,
    F: Fn(u64) -> Result<L, E> + Sync,
{
    let started = std::time::Instant::now();
    let runs = seeds
        .par_iter()
        .map(|&seed| {
            let started = std::time::Instant::now();
            let mut link = link_for_seed(seed)?;
            let config = RunConfig {
                seed,
                ..config.clone()
            };
            let outcome = run(&mut link, model, config, limit)?;
            let done = SeedRun {
                seed,
                outcome,
                wall: started.elapsed(),
            };
            on_done(&done);
            Ok(done)
        })
        .collect::<Result<Vec<_>, E>>()?;
    Ok(Campaign {
        runs,
        wall: started.elapsed(),
        // The machine's cores, or RAYON_NUM_THREADS.
        threads: rayon::current_num_threads(),
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
    pub outcome: RunResult,
}

/// Shrinks `inputs` (a failing run's, see [`RunResult::script`]) to the shortest script that still
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
    let mut last_fail: Option<(Vec<ScriptStep>, RunResult)> = None;
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

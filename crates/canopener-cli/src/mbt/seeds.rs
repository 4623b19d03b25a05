//! `mbt run --seeds A..B`: one run per seed, each on a fresh simulated device on virtual time, in
//! parallel (the runtime's rayon pool), and one summary of verdicts, steps, coverage and the first
//! failing seed.

use std::collections::BTreeSet;

use canopener_mbt::executor::{RunConfig, Verdict};
use canopener_mbt::model::Model;
use canopener_runtime::mbt_run::{self, SeedRun};

use crate::error::{CliError, CliResult, exit_code};
use crate::master::output::count_bar;
use crate::mbt::args::{Format, RunArgs};
use crate::mbt::run::simulated;
use crate::output::print_stdout;

pub(crate) fn run(args: &RunArgs, model: &Model, config: RunConfig, (first, last): (u64, u64)) -> CliResult {
    let Some(file) = &args.device.sim else {
        return Err(CliError::Usage("--seeds needs --sim FILE".into()));
    };
    let seeds: Vec<u64> = (first..=last).collect();
    let bar = count_bar(seeds.len() as u64, "{bar:30} {pos}/{len} seeds [{elapsed}] {msg}");
    let campaign = mbt_run::run_seeds(
        &seeds,
        |_| simulated(file, &args.device, args.model.node),
        model,
        &config,
        args.device.time_limit,
        &|done: &SeedRun| {
            if done.outcome.verdict != Verdict::Pass {
                bar.set_message(format!("seed {} {:?}", done.seed, done.outcome.verdict).to_lowercase());
            }
            bar.inc(1);
        },
    )?;
    bar.finish_and_clear();
    let runs = &campaign.runs;
    let wall = campaign.wall.as_secs_f64();
    let count = |v: Verdict| runs.iter().filter(|r| r.outcome.verdict == v).count();
    let first_failing = runs
        .iter()
        .find(|r| r.outcome.verdict == Verdict::Fail)
        .map(|r| r.seed);
    let first_inconclusive = runs
        .iter()
        .find(|r| r.outcome.verdict == Verdict::Inconclusive)
        .map(|r| r.seed);
    let taken: BTreeSet<usize> = runs
        .iter()
        .flat_map(|r| r.outcome.coverage.taken.iter().copied())
        .collect();
    let transitions = [taken.len(), model.transitions.len()];
    let threads = campaign.threads;
    match args.format {
        Format::Json => {
            let per_seed: Vec<serde_json::Value> = runs
                .iter()
                .map(|r| {
                    let o = &r.outcome;
                    serde_json::json!({
                        "seed": r.seed,
                        "verdict": o.verdict,
                        "steps": o.steps,
                        "frames": o.outputs_seen,
                        "transitions": o.coverage.transitions,
                        "locations": o.coverage.locations,
                        "virtual_s": o.trace.last().map_or(0.0, |s| s.t),
                        "reason": o.reason,
                    })
                })
                .collect();
            let value = serde_json::json!({
                "version": 1,
                "models": args.model.models,
                "model_hash": model.hash,
                "steps": config.steps,
                "seeds": per_seed,
                "summary": {
                    "runs": runs.len(),
                    "pass": count(Verdict::Pass),
                    "fail": count(Verdict::Fail),
                    "inconclusive": count(Verdict::Inconclusive),
                    "first_failing_seed": first_failing,
                    "first_inconclusive_seed": first_inconclusive,
                    "coverage": {"transitions": transitions},
                    "wall_s": wall,
                    "threads": threads,
                },
            });
            print_stdout(&format!("{value}\n"))?;
        }
        Format::Human => {
            let mut text = format!(
                "{}: {} seeds ({first}..{last}) x {} steps on virtual time: {} pass, {} fail, {} inconclusive; first failing seed: {}\n",
                model.name(),
                runs.len(),
                config.steps,
                count(Verdict::Pass),
                count(Verdict::Fail),
                count(Verdict::Inconclusive),
                first_failing.map_or_else(|| "none".to_owned(), |s| s.to_string())
            );
            text.push_str(&format!(
                "{:>6}  {:<12}  {:>6}  {:>6}  {:>11}  {:>9}  reason\n",
                "seed", "verdict", "steps", "frames", "transitions", "virtual"
            ));
            for r in runs {
                let o = &r.outcome;
                let reason = if o.verdict == Verdict::Pass {
                    ""
                } else {
                    o.reason.as_str()
                };
                let line = format!(
                    "{:>6}  {:<12}  {:>6}  {:>6}  {:>11}  {:>8.1}s  {reason}",
                    r.seed,
                    format!("{:?}", o.verdict).to_lowercase(),
                    o.steps,
                    o.outputs_seen,
                    format!("{}/{}", o.coverage.transitions[0], o.coverage.transitions[1]),
                    o.trace.last().map_or(0.0, |s| s.t),
                );
                text.push_str(line.trim_end());
                text.push('\n');
            }
            text.push_str(&format!(
                "coverage over all seeds: {}/{} transitions\nwall time {wall:.1} s on {threads} threads\n",
                transitions[0], transitions[1]
            ));
            if let Some(seed) = first_failing.or(first_inconclusive) {
                text.push_str(&format!(
                    "to see seed {seed} alone: canopener mbt run {} --sim {} --node {} --steps {} --seed {seed} --log run.jsonl\n",
                    args.model.models.join(" "),
                    file.display(),
                    args.model.node,
                    config.steps
                ));
            }
            print_stdout(&text)?;
        }
    }
    if runs.iter().all(|r| r.outcome.verdict == Verdict::Pass) {
        Ok(())
    } else {
        Err(CliError::Exit(exit_code::CHECK_FAILED))
    }
}

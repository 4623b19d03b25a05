//! `canopener demo`: the product tour. A simulated CiA 401 device from the bundled EDS on the embedded
//! virtual bus: its EDS checked, every conformance suite run against it and the HTML report written; then
//! the same with one fault switched on. Prints a short narrative (or one JSON summary) naming the files.
//! The work is `canopener_conformance::tour`'s; this module only writes the files and talks.
//!
//! Exit status: 0 the clean device passed and the faulty one failed (the tour showed what it should),
//! 6 otherwise, 5 a report could not be written, 130 interrupted.

use std::fmt::Write as _;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use canopener_conformance::model::{Report, Verdict, rfc3339_utc};
use canopener_conformance::render::html;
use canopener_conformance::tour::{self, EdsCheck};
use canopener_device::faults::Fault;
use canopener_files::{self as files, create_dir_all, write_atomic};
use canopener_runtime::clock::wall_time;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde_json::json;

use crate::args::OutputFormat;
use crate::demo::args::DemoArgs;
use crate::error::{CliError, CliResult, exit_code, write_failed};
use crate::output::print_stdout;
use crate::stop::StopFlag;

/// How many failures of the faulty run the narrative lists (the HTML report has them all).
const LISTED_FAILURES: usize = 5;

pub(crate) fn run(args: DemoArgs) -> CliResult {
    let stop = StopFlag::install()?;
    let text = args.format == OutputFormat::Text;
    let dir = args.dir.as_path();
    create_dir_all(dir).map_err(write_failed)?;
    let mut written = Written::default();
    written.write(&dir.join(tour::EDS_NAME), tour::EDS)?;
    let check = tour::check_eds();
    if text {
        print_stdout(&intro(&check, &dir.join(tour::EDS_NAME)))?;
    }
    let started = wall_time();
    let scenarios = [(None, "clean"), (Some(args.fault), "fault")];
    let tests = canopener_conformance::catalogue::catalogue().len();
    let bar = progress_bar((scenarios.len() * tests) as u64);
    let mut runs = Vec::new();
    for (step, (fault, name)) in scenarios.into_iter().enumerate() {
        let faults: Vec<Fault> = fault.into_iter().collect();
        let offset = (step * tests) as u64;
        let outcome = tour::run(&faults, &rfc3339_utc(wall_time()), Some(stop.token()), |p| {
            bar.set_position(offset + p.done as u64);
            if let Some(test) = p.current {
                bar.set_message(format!("{name}: {}", test.id));
            }
        })
        .map_err(|err| CliError::Internal(anyhow::anyhow!(err)))?;
        let (report, silent) = (outcome.report, outcome.silent);
        let stem = match fault {
            Some(fault) => format!("fault-{}", fault.name()),
            None => "clean".to_owned(),
        };
        let html_path = dir.join(format!("{stem}.html"));
        let json_path = dir.join(format!("{stem}.json"));
        written.write(&html_path, html::render(&report).as_bytes())?;
        written.write(&json_path, report.to_json().as_bytes())?;
        let run = Run {
            fault,
            report,
            silent,
            html: html_path,
            json: json_path,
        };
        if text {
            bar.suspend(|| print_stdout(&run.narrative(step + 2)))?;
        }
        let interrupted = run.report.interrupted;
        runs.push(run);
        if interrupted {
            break;
        }
    }
    bar.finish_and_clear();
    let took = wall_time()
        .duration_since(started)
        .map_or(0.0, |d| d.as_secs_f64());
    let verdict = verdict(&runs);
    match args.format {
        OutputFormat::Text => print_stdout(&closing(dir, &runs, &written, took, verdict.is_ok()))?,
        OutputFormat::Json => print_stdout(&summary_json(&check, &runs, &written, took))?,
    }
    verdict
}

/// The files the tour wrote, and those it replaced (from an earlier tour, most likely).
#[derive(Default)]
struct Written {
    files: Vec<PathBuf>,
    replaced: Vec<PathBuf>,
}

impl Written {
    fn write(&mut self, path: &Path, bytes: &[u8]) -> CliResult {
        if files::exists(path) {
            self.replaced.push(path.to_owned());
        }
        write_atomic(path, bytes, false).map_err(write_failed)?;
        self.files.push(path.to_owned());
        Ok(())
    }
}

struct Run {
    fault: Option<Fault>,
    report: Report,
    /// The device did not answer the first SDO read: nothing was tested.
    silent: bool,
    html: PathBuf,
    json: PathBuf,
}

impl Run {
    fn failed(&self) -> Vec<&canopener_conformance::model::TestReport> {
        self.report
            .tests
            .iter()
            .filter(|t| t.verdict == Verdict::Fail)
            .collect()
    }

    fn narrative(&self, step: usize) -> String {
        let mut out = String::new();
        let s = self.report.summary;
        match self.fault {
            None => {
                let _ = writeln!(
                    out,
                    "{step}. Every conformance suite against the simulated device (node {}, on virtual time):",
                    tour::NODE
                );
            }
            Some(fault) => {
                let _ = writeln!(
                    out,
                    "{step}. The same device with one fault switched on, {}: {}",
                    fault.name(),
                    first_sentence(fault.description())
                );
            }
        }
        let _ = writeln!(
            out,
            "   {} tests: {} passed, {} measured, no criterion, {} failed, {} inconclusive, {} not applicable ({:.1} s of bus time)",
            self.report.tests.len(),
            s.conformance_passes(),
            s.measured_no_criterion,
            s.fail,
            s.inconclusive,
            s.not_applicable,
            self.report.duration_s
        );
        if self.silent {
            let _ = writeln!(
                out,
                "   the device did not answer the first SDO read (1000h) in time: nothing could be tested"
            );
        }
        let failed = self.failed();
        for test in failed.iter().take(LISTED_FAILURES) {
            let _ = writeln!(out, "   FAIL {} {}", test.id, test.title);
            let _ = writeln!(out, "        {}", test.reason);
        }
        if failed.len() > LISTED_FAILURES {
            let _ = writeln!(out, "   … and {} more failures", failed.len() - LISTED_FAILURES);
        }
        let plotted = failed.iter().any(|t| !t.measurements.is_empty());
        let _ = writeln!(
            out,
            "   report: {}{}\n",
            self.html.display(),
            if plotted {
                " (open it: the failure is plotted against its limits)"
            } else {
                ""
            }
        );
        out
    }
}

/// The first sentence of a fault's description, lower-cased at its start, for one line of narrative.
fn first_sentence(text: &str) -> String {
    let sentence = text
        .find(". ")
        .map_or(text.trim_end_matches('.'), |end| &text[..end]);
    let mut chars = sentence.chars();
    chars
        .next()
        .map(|first| first.to_lowercase().chain(chars).collect())
        .unwrap_or_default()
}

fn intro(check: &EdsCheck, eds: &Path) -> String {
    format!(
        "canopener demo: a simulated CiA 401 I/O device on the embedded virtual bus, tested as a device maker\n\
         would before certification. (`canopener demo --monitor` shows a decoded CANopen session instead.)\n\n\
         1. EDS check of the bundled description ({}): {} objects, {} errors, {} warnings, {} infos\n   \
         (see them with: canopener eds check {})\n\n",
        eds.display(),
        check.objects,
        check.errors,
        check.warnings,
        check.infos,
        eds.display()
    )
}

fn closing(dir: &Path, runs: &[Run], written: &Written, took: f64, as_expected: bool) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "Wrote {} files to {} in {took:.1} s: the bundled EDS, and per run an HTML report (opens offline in \
         any browser) and the JSON report.",
        written.files.len(),
        dir.display()
    );
    if !written.replaced.is_empty() {
        let replaced: Vec<String> = written.replaced.iter().map(|p| p.display().to_string()).collect();
        let _ = writeln!(
            out,
            "Replaced the files of an earlier run: {}",
            replaced.join(", ")
        );
    }
    if as_expected {
        let _ = writeln!(
            out,
            "Your device: canopener test --bus socketcan:can0 --node N --eds device.eds --format html -o report.html"
        );
    } else if runs.iter().any(|r| r.report.interrupted) {
        let _ = writeln!(out, "Interrupted: the reports hold the tests that ran.");
    }
    out
}

fn summary_json(check: &EdsCheck, runs: &[Run], written: &Written, took: f64) -> String {
    let runs: Vec<_> = runs
        .iter()
        .map(|run| {
            json!({
                "fault": run.fault.map(Fault::name),
                "summary": run.report.summary,
                "tests": run.report.tests.len(),
                "failed": run.failed().iter().map(|t| &t.id).collect::<Vec<_>>(),
                "silent": run.silent,
                "interrupted": run.report.interrupted,
                "bus_time_s": run.report.duration_s,
                "html": run.html.display().to_string(),
                "json": run.json.display().to_string(),
            })
        })
        .collect();
    let paths = |list: &[PathBuf]| -> Vec<String> { list.iter().map(|p| p.display().to_string()).collect() };
    let summary = json!({
        "eds": {
            "file": tour::EDS_NAME,
            "objects": check.objects,
            "errors": check.errors,
            "warnings": check.warnings,
            "infos": check.infos,
        },
        "runs": runs,
        "written": paths(&written.files),
        "replaced": paths(&written.replaced),
        "elapsed_s": took,
    });
    format!("{summary}\n")
}

/// 0 when the clean device passed everything applicable and the faulty one failed a test (or fell
/// silent, which the tester reports as such).
fn verdict(runs: &[Run]) -> CliResult {
    if runs.iter().any(|r| r.report.interrupted) {
        return Err(CliError::Exit(exit_code::INTERRUPTED));
    }
    let clean = runs.iter().find(|r| r.fault.is_none());
    if let Some(clean) = clean.filter(|r| r.silent || !r.report.summary.all_passed()) {
        return Err(CliError::CheckFailed(format!(
            "the clean simulated device did not pass every test ({} failed, {} inconclusive): see {}",
            clean.report.summary.fail,
            clean.report.summary.inconclusive,
            clean.html.display()
        )));
    }
    if let Some(faulty) = runs
        .iter()
        .find(|r| r.fault.is_some() && !r.silent && r.report.summary.fail == 0)
    {
        return Err(CliError::CheckFailed(format!(
            "no test caught the fault {}: see {}",
            faulty.fault.map_or("", Fault::name),
            faulty.html.display()
        )));
    }
    Ok(())
}

fn progress_bar(len: u64) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
    if let Ok(style) = ProgressStyle::with_template("{spinner} {pos}/{len} {wide_bar} {msg}") {
        bar.set_style(style);
    }
    bar
}

//! `canopener test`: loads the EDS, opens the bus, runs the selected tests with a progress bar, writes
//! the report (human, JSON, JUnit or HTML) and the per-test candump logs, and ends with the documented exit
//! code: 0 every applicable test passed, 6 a test failed or could not decide, 7 the device does not
//! answer at all, 2 usage, 3 an unreadable EDS or criteria file, 130 interrupted (the partial report is still written).

use std::fmt::Write as _;
use std::io::IsTerminal;
use std::path::Path;

use canopener_conformance::catalogue::{Selection, TestDef, catalogue};
use canopener_conformance::device_model::DeviceModel;
use canopener_conformance::model::{Report, rfc3339_utc};
use canopener_conformance::performance::{Criteria, Performance};
use canopener_conformance::render::{candump, html, human, junit};
use canopener_conformance::runner::{self, RunSpec};
use canopener_conformance::stimulus::{Hook, Stimulus};
use canopener_files::{create_dir_all, same_file, write_atomic};
use canopener_link::link::{BusLink, Link};
use canopener_link::stimulus_program::StimulusProgram;
use canopener_sim::simulation::Simulation;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde_json::json;

use crate::bus_open::open_bus;
use crate::error::{CliError, CliResult, exit_code, write_failed};
use crate::output::print_stdout;
use crate::stop::StopFlag;
use crate::test::args::{ReportFormat, TestArgs};

pub(crate) fn run(args: TestArgs) -> CliResult {
    let selection = Selection {
        suite: Some(args.suite.clone()),
        only: args.only.clone(),
        skip: args.skip.clone(),
        tags: args.tag.clone(),
    };
    let tests = selection
        .pick(&catalogue())
        .map_err(|err| CliError::Usage(err.to_string()))?;
    if args.list {
        return print_stdout(&list(&tests, args.format));
    }
    let (Some(node), Some(eds_path)) = (args.node, args.eds.as_deref()) else {
        return Err(CliError::Usage(
            "give --node N and --eds FILE, e.g. canopener test --bus socketcan:can0 --node 5 --eds device.eds".to_owned(),
        ));
    };
    if let Some(out) = &args.output
        && same_file(out, eds_path)
    {
        return Err(CliError::Usage(format!(
            "-o {} is the EDS under test; write the report elsewhere, e.g. -o report.txt",
            out.display()
        )));
    }
    let performance = performance(&args)?;
    let description = canopener_runtime::description::read_description(eds_path)
        .map_err(|err| CliError::InvalidInput(err.to_string()))?;
    let eds_errors = eds_errors(eds_path)?;
    let model = DeviceModel::new(&description.eds, node);
    if let Some(dir) = &args.log {
        create_dir_all(dir).map_err(write_failed)?;
    }
    // The EDS check alone runs without a bus (an empty simulated one stands in for it).
    let needs_device = tests.iter().any(TestDef::needs_device);
    let stop = needs_device.then(StopFlag::install).transpose()?;
    let mut link: Box<dyn Link> = match &stop {
        Some(stop) => {
            let bus = open_bus(args.bus.spec.as_deref(), "test")?;
            Box::new(BusLink::new(bus, stop.token())?)
        }
        None => Box::new(Simulation::ideal().start()?),
    };
    let spec = RunSpec {
        node,
        model: &model,
        eds: eds_path.display().to_string(),
        bus: if needs_device {
            link.describe()
        } else {
            "none (EDS check only)".to_owned()
        },
        started: rfc3339_utc(canopener_runtime::clock::wall_time()),
        sdo_timeout: args.timeout,
        eds_errors,
        cancel: stop.as_ref().map(StopFlag::token),
    };
    let bar = progress_bar(tests.len());
    let mut program = args.stimulus.as_deref().map(StimulusProgram::new);
    let hook = program.as_mut().map(|program| Hook {
        stimulus: program as &mut dyn Stimulus,
        settle: args.stimulus_settle,
    });
    let outcome = runner::run_stimulated(link.as_mut(), &spec, &performance, hook, &tests, |progress| {
        bar.set_position(progress.done as u64);
        if let Some(test) = progress.current {
            bar.set_message(test.id);
        }
    })
    .map_err(|err| CliError::Usage(format!("{err}; give --node 1..127 and a --timeout above 0")))?;
    bar.finish_and_clear();
    let report = &outcome.report;
    if let Some(dir) = &args.log {
        write_logs(dir, report)?;
    }
    let text = match args.format {
        ReportFormat::Human => human::render(report),
        ReportFormat::Json => report.to_json(),
        ReportFormat::Junit => junit::render(report),
        ReportFormat::Html => html::render(report),
    };
    match &args.output {
        Some(path) => write_atomic(path, text.as_bytes(), false).map_err(write_failed)?,
        None => print_stdout(&text)?,
    }
    if report.interrupted {
        return Err(CliError::Exit(exit_code::INTERRUPTED));
    }
    if outcome.silent {
        return Err(CliError::Device(format!(
            "node {node} did not answer an SDO read of 1000h within {:?}: nothing to test (is the device on {}, \
             is --node right, is it slower than --timeout?)",
            args.timeout, spec.bus
        )));
    }
    if outcome.passed() {
        Ok(())
    } else {
        Err(CliError::Exit(exit_code::CHECK_FAILED))
    }
}

/// The cia313 criteria (`--criteria`, else the defaults) and repetitions; a criteria file that
/// cannot be read or used is exit 3 with file:line.
fn performance(args: &TestArgs) -> CliResult<Performance> {
    let criteria = match &args.criteria {
        Some(path) => {
            let bytes = canopener_files::read(path).map_err(|err| CliError::read_file(path, err))?;
            let text = String::from_utf8(bytes).map_err(|_| {
                CliError::InvalidInput(format!(
                    "{}: not UTF-8 text; a criteria file is TOML",
                    path.display()
                ))
            })?;
            Criteria::parse(&text, &path.display().to_string())
                .map_err(|err| CliError::InvalidInput(err.to_string()))?
        }
        None => Criteria::default(),
    };
    Ok(Performance {
        criteria,
        repetitions: args.repetitions,
    })
}

/// The errors of canopener's EDS checks for an EDS/DCF file; `None` for XDD/XDC and JSON forms.
fn eds_errors(path: &Path) -> CliResult<Option<Vec<String>>> {
    let is_eds = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("eds") || e.eq_ignore_ascii_case("dcf"));
    if !is_eds {
        return Ok(None);
    }
    let bytes = canopener_files::read(path).map_err(|err| CliError::read_file(path, err))?;
    let loaded = canopener_eds::load(&bytes);
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
    Ok(Some(canopener_conformance::cia301::eds::errors(
        &loaded,
        name.as_deref(),
    )))
}

fn write_logs(dir: &Path, report: &Report) -> CliResult {
    for test in &report.tests {
        let path = dir.join(candump::file_name(test));
        write_atomic(&path, candump::log(test).as_bytes(), false).map_err(write_failed)?;
    }
    Ok(())
}

fn progress_bar(len: usize) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(len as u64), ProgressDrawTarget::stderr());
    if let Ok(style) = ProgressStyle::with_template("{spinner} {pos}/{len} {wide_bar} {msg}") {
        bar.set_style(style);
    }
    bar
}

fn list(tests: &[TestDef], format: ReportFormat) -> String {
    if format == ReportFormat::Json {
        let rows: Vec<_> = tests
            .iter()
            .map(|t| {
                let cct: Vec<_> = canopener_conformance::cct::cases_of(t)
                    .map(|c| json!({"case": c.name, "coverage": c.coverage.as_str(), "reading": c.reading}))
                    .collect();
                json!({"id": t.id, "suite": t.suite, "group": t.group, "title": t.title,
                       "references": t.references, "precondition": t.precondition, "tags": t.tags,
                       "cct": cct})
            })
            .collect();
        return format!("{}\n", serde_json::Value::Array(rows));
    }
    let mut out = String::new();
    for test in tests {
        let _ = writeln!(out, "{:<16} {}", test.id, test.title);
        let _ = writeln!(out, "{:<16} references: {}", "", test.references.join("; "));
        let _ = writeln!(out, "{:<16} applies: {}", "", test.precondition);
    }
    let _ = writeln!(out, "{} tests", tests.len());
    out
}

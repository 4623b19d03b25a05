//! `canopener eds check`: check many EDS/DCF files in parallel and report for people or machines.

use std::io::IsTerminal;

use canopener_files::write_atomic;
use canopener_report::{HumanOptions, Report};
use canopener_runtime::batch::{check_all, expand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::eds::args::{CheckFormat, ColorChoice, DenyLevel, EdsCheckArgs};
use crate::eds::input::checker;
use crate::error::{CliError, CliResult};
use crate::output::print_stdout;

pub(crate) fn run(args: EdsCheckArgs) -> CliResult {
    let checker = checker(&args.selection)?;
    let targets = expand(&args.inputs);
    let progress = progress_bar(targets.len() as u64);
    let files = check_all(&checker, &targets, || progress.inc(1));
    progress.finish_and_clear();
    let report = Report {
        tool_version: env!("CARGO_PKG_VERSION").to_owned(),
        checks: checker.selected(),
        files,
    };
    let rendered = match args.format {
        CheckFormat::Human => {
            let color = match args.color {
                ColorChoice::Always => true,
                ColorChoice::Never => false,
                ColorChoice::Auto => {
                    args.output.is_none()
                        && std::io::stdout().is_terminal()
                        && std::env::var_os("NO_COLOR").is_none_or(|v| v.is_empty())
                }
            };
            canopener_report::human(
                &report,
                &HumanOptions {
                    color,
                    summary_table: !args.no_summary,
                },
            )
        }
        CheckFormat::Json => canopener_report::json(&report),
        CheckFormat::Sarif => canopener_report::sarif(&report),
        CheckFormat::Junit => canopener_report::junit(&report),
        CheckFormat::Html => canopener_report::html(&report),
    };
    match &args.output {
        Some(out) => write_atomic(out, rendered.as_bytes(), false)?,
        None => print_stdout(&rendered)?,
    }
    exit_status(&report, args.deny)
}

/// 2 when a file could not be read, 1 when errors (or denied warnings) were found, else 0.
fn exit_status(report: &Report, deny: Option<DenyLevel>) -> CliResult {
    let summary = report.summary();
    if summary.problems > 0 {
        return Err(CliError::Exit(2));
    }
    let denied = summary.errors > 0 || (deny == Some(DenyLevel::Warnings) && summary.warnings > 0);
    if denied { Err(CliError::Exit(1)) } else { Ok(()) }
}

/// A progress bar on stderr for batches, drawn only on a terminal.
fn progress_bar(len: u64) -> ProgressBar {
    if len < 2 || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
    if let Ok(style) = ProgressStyle::with_template("{spinner} checking {pos}/{len} files {wide_bar} {eta}") {
        bar.set_style(style);
    }
    bar
}

//! `canopener bus replay`: play a candump log onto a bus, keeping its timing unless told otherwise.

use std::path::Path;

use canopener_can::candump::{LogRecord, parse_log};
use canopener_runtime::candump_file::read_log;
use canopener_runtime::replay::{Pace, frames_of, replay};
use indicatif::{ProgressBar, ProgressStyle};

use crate::bus::args::ReplayArgs;
use crate::bus_open::open_bus;
use crate::error::{CliError, CliResult};
use crate::stop::StopFlag;

/// How many unreadable lines to list before summarising the rest.
const MAX_LISTED_ERRORS: usize = 10;

pub(crate) fn run(args: ReplayArgs) -> CliResult {
    let pace = if args.no_timing {
        Pace::BACK_TO_BACK
    } else {
        Pace::recorded(args.speed).map_err(|_| {
            CliError::Usage(format!(
                "--speed {} must be a number above 0 (2 = twice as fast)",
                args.speed
            ))
        })?
    };
    let text = read_log(&args.file)?;
    let records = load_records(&args.file, &text, args.skip_invalid)?;
    let (frames, error_frames) = frames_of(records, args.interface.as_deref());
    if error_frames > 0 {
        eprintln!(
            "note: {error_frames} error frames in the log are not replayed (a controller cannot send them)"
        );
    }
    if frames.is_empty() {
        return Err(CliError::InvalidInput(format!(
            "{} has no frames to replay{}",
            args.file.display(),
            args.interface
                .as_deref()
                .map(|name| format!(" on interface {name}"))
                .unwrap_or_default()
        )));
    }
    let stop = StopFlag::install()?;
    let mut bus = open_bus(args.bus.spec.as_deref(), "bus replay")?;
    let total = frames.len() as u64 * args.loops;
    let progress = ProgressBar::new(total).with_style(
        ProgressStyle::with_template("{spinner} replay [{bar:30}] {pos}/{len} frames {per_sec} eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    let summary = replay(&mut *bus, &frames, pace, args.loops, &stop.token(), |sent| {
        if sent.is_multiple_of(64) {
            progress.set_position(sent);
        }
    })?;
    progress.finish_and_clear();
    eprintln!(
        "replayed {} of {total} frames in {:.3} s",
        summary.sent,
        summary.elapsed.as_secs_f64()
    );
    Ok(())
}

/// Parses the log; unreadable lines are an error unless `skip_invalid`, and then they are listed as warnings.
fn load_records(path: &Path, text: &str, skip_invalid: bool) -> CliResult<Vec<(usize, LogRecord)>> {
    let (records, errors) = parse_log(text);
    if errors.is_empty() {
        return Ok(records);
    }
    let mut listing = String::new();
    for err in errors.iter().take(MAX_LISTED_ERRORS) {
        listing.push_str(&format!(
            "\n  {}:{}:{}: {}",
            path.display(),
            err.line,
            err.column,
            err.message
        ));
    }
    if errors.len() > MAX_LISTED_ERRORS {
        listing.push_str(&format!("\n  … and {} more", errors.len() - MAX_LISTED_ERRORS));
    }
    if skip_invalid {
        eprintln!("warning: skipping {} unreadable lines:{listing}", errors.len());
        Ok(records)
    } else {
        Err(CliError::InvalidInput(format!(
            "{} has {} unreadable lines (fix them, or pass --skip-invalid to replay the rest):{listing}",
            path.display(),
            errors.len()
        )))
    }
}

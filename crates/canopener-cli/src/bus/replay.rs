//! `canopener bus replay`: play a candump log onto a bus, keeping its timing unless told otherwise.

use std::path::Path;
use std::time::{Duration, Instant};

use canopener_can::CanFrame;
use canopener_can::candump::{LogEvent, LogRecord, parse_log};
use indicatif::{ProgressBar, ProgressStyle};

use canopener_transport::CanBus;

use crate::bus::args::ReplayArgs;
use crate::bus_open::open_bus;
use crate::error::{CliError, CliResult};
use crate::stop::StopFlag;

/// How many unreadable lines to list before summarising the rest.
const MAX_LISTED_ERRORS: usize = 10;

pub(crate) fn run(args: ReplayArgs) -> CliResult {
    if !(args.speed.is_finite() && args.speed > 0.0) {
        return Err(CliError::Usage(format!(
            "--speed {} must be a number above 0 (2 = twice as fast)",
            args.speed
        )));
    }
    let text = read_log_text(&args.file)?;
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
    let started = Instant::now();
    let speed = (!args.no_timing).then_some(args.speed);
    let mut sent = 0u64;
    for _ in 0..args.loops {
        if stop.is_set() {
            break;
        }
        sent += send_timed(&mut *bus, &frames, speed, &stop, |in_loop| {
            if in_loop.is_multiple_of(64) {
                progress.set_position(sent + in_loop);
            }
        })?;
    }
    progress.finish_and_clear();
    let elapsed = started.elapsed().as_secs_f64();
    eprintln!("replayed {sent} of {total} frames in {elapsed:.3} s");
    Ok(())
}

/// The frames of `records` (only those recorded on `interface`, if given) and how many error frames were
/// left out.
pub(crate) fn frames_of(
    records: Vec<(usize, LogRecord)>,
    interface: Option<&str>,
) -> (Vec<(canopener_can::Instant, CanFrame)>, usize) {
    let mut frames = Vec::with_capacity(records.len());
    let mut error_frames = 0;
    for (_, record) in records {
        if interface.is_some_and(|wanted| wanted != record.interface) {
            continue;
        }
        match record.event {
            LogEvent::Frame(frame) => frames.push((record.timestamp, frame)),
            LogEvent::ErrorFrame { .. } => error_frames += 1,
        }
    }
    (frames, error_frames)
}

/// Sends `frames` in order, keeping their recorded gaps divided by `speed`, or back to back when `speed` is
/// `None`. The schedule is absolute (start + offset), so a late wake-up is caught up rather than
/// accumulated. Returns how many frames were sent before the end or a stop request; `on_sent` gets the
/// running count.
pub(crate) fn send_timed(
    bus: &mut dyn CanBus,
    frames: &[(canopener_can::Instant, CanFrame)],
    speed: Option<f64>,
    stop: &StopFlag,
    mut on_sent: impl FnMut(u64),
) -> CliResult<u64> {
    let Some((first, _)) = frames.first() else {
        return Ok(0);
    };
    let start = Instant::now();
    let mut sent = 0;
    for (timestamp, frame) in frames {
        if stop.is_set() {
            break;
        }
        if let Some(speed) = speed {
            sleep_until(
                start + timestamp.saturating_duration_since(*first).div_f64(speed),
                stop,
            );
        }
        bus.send(frame)?;
        sent += 1;
        on_sent(sent);
    }
    Ok(sent)
}

pub(crate) fn read_log_text(path: &Path) -> CliResult<String> {
    let bytes = std::fs::read(path).map_err(|err| CliError::read_file(path, err))?;
    // candump logs are ASCII; a stray non-UTF-8 byte becomes U+FFFD and its line is reported by the parser.
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}

/// Parses the log; unreadable lines are an error unless `skip_invalid`, and then they are listed as warnings.
pub(crate) fn load_records(
    path: &Path,
    text: &str,
    skip_invalid: bool,
) -> CliResult<Vec<(usize, LogRecord)>> {
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

fn sleep_until(due: Instant, stop: &StopFlag) {
    // Sleep in slices so that Ctrl-C during a long recorded gap is honoured promptly.
    loop {
        let now = Instant::now();
        if now >= due || stop.is_set() {
            return;
        }
        std::thread::sleep((due - now).min(Duration::from_millis(100)));
    }
}

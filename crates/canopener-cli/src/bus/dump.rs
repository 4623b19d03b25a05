//! `canopener bus dump`: print live frames decoded as CANopen, optionally logging them in candump format.

use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Write};
use std::path::Path;
use std::time::{Duration, Instant};

use canopener_can::candump::{LogEvent, LogRecord};
use canopener_transport::TransportError;

use crate::bus::args::DumpArgs;
use crate::bus::monitor::Monitor;
use crate::bus_open::{interface_name, open_bus};
use crate::error::{CliError, CliResult, stdout_error};
use crate::stop::StopFlag;

/// How long one `recv` may block: the granularity at which Ctrl-C, --duration and log flushing are noticed.
const POLL: Duration = Duration::from_millis(100);
/// A live log is flushed at least this often, so a crash or a kill -9 loses at most this much.
const LOG_FLUSH_EVERY: Duration = Duration::from_millis(500);

pub(crate) fn run(args: DumpArgs) -> CliResult {
    let stop = StopFlag::install()?;
    if let Some(path) = args
        .log
        .as_deref()
        .filter(|path| path.exists() && !args.overwrite)
    {
        return Err(CliError::output(
            format!(
                "log file {} already exists; choose another name or pass --overwrite",
                path.display()
            ),
            std::io::Error::from(std::io::ErrorKind::AlreadyExists),
        ));
    }
    let mut bus = open_bus(args.bus.spec.as_deref(), "bus dump")?;
    // Created only once the bus is open, so a bus error leaves no empty log file behind.
    let mut log = args
        .log
        .as_deref()
        .map(|path| open_log(path, args.overwrite))
        .transpose()?;
    let interface = interface_name(bus.spec());
    let stdout = std::io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    let mut monitor = Monitor::new(args.format, args.raw);
    let started = Instant::now();
    let mut last_flush = Instant::now();
    let mut lost_total = 0u64;
    let mut line = String::new();
    let result = loop {
        if stop.is_set()
            || args.count.is_some_and(|count| monitor.stats().frames >= count)
            || args
                .duration
                .is_some_and(|duration| started.elapsed() >= duration)
        {
            break Ok(());
        }
        match bus.recv(POLL) {
            Ok(Some(received)) => {
                monitor
                    .print_frame(&mut out, received.timestamp, &interface, &received.frame)
                    .map_err(stdout_error)?;
                if let Some((writer, path)) = log.as_mut() {
                    line.clear();
                    let record = LogRecord {
                        timestamp: received.timestamp,
                        interface: interface.clone(),
                        event: LogEvent::Frame(received.frame),
                    };
                    // write_record ends the line itself.
                    canopener_can::candump::write_record(&mut line, &record);
                    writer
                        .write_all(line.as_bytes())
                        .map_err(|err| CliError::output(format!("writing {}", path_display(path)), err))?;
                }
            }
            Ok(None) => {}
            Err(TransportError::Overrun { lost, .. }) => {
                // The monitor fell behind; say so in the output stream where the gap is, and carry on.
                lost_total += lost;
                eprintln!("warning: {lost} frames lost because the monitor did not keep up");
            }
            Err(err) => break Err(CliError::from(err)),
        }
        if last_flush.elapsed() >= LOG_FLUSH_EVERY {
            last_flush = Instant::now();
            out.flush().map_err(stdout_error)?;
            if let Some((writer, path)) = log.as_mut() {
                writer
                    .flush()
                    .map_err(|err| CliError::output(format!("writing {}", path_display(path)), err))?;
            }
        }
    };
    // Flush whatever we have even when the bus failed: a log must never lose frames already received.
    out.flush().map_err(stdout_error)?;
    if let Some((mut writer, path)) = log {
        writer
            .flush()
            .map_err(|err| CliError::output(format!("writing {}", path_display(&path)), err))?;
    }
    if lost_total > 0 {
        eprintln!("warning: {lost_total} frames were lost in total");
    }
    result
}

fn open_log(path: &Path, overwrite: bool) -> CliResult<(BufWriter<File>, std::path::PathBuf)> {
    let mut options = OpenOptions::new();
    options.write(true);
    if overwrite {
        options.create(true).truncate(true);
    } else {
        // create_new refuses atomically if the file appeared meanwhile: an existing log is never clobbered.
        options.create_new(true);
    }
    match options.open(path) {
        Ok(file) => Ok((BufWriter::new(file), path.to_owned())),
        Err(err) if err.kind() == std::io::ErrorKind::AlreadyExists => Err(CliError::output(
            format!(
                "log file {} already exists; choose another name or pass --overwrite",
                path.display()
            ),
            err,
        )),
        Err(err) => Err(CliError::output(
            format!("cannot create log file {}", path.display()),
            err,
        )),
    }
}

fn path_display(path: &Path) -> String {
    path.display().to_string()
}

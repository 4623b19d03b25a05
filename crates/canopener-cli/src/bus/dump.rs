//! `canopener bus dump`: print live frames decoded as CANopen, optionally logging them in candump format.

use std::io::Write;

use canopener_runtime::candump_file::{LogFileError, LogWriter};
use canopener_runtime::capture::{CaptureError, CaptureEvent, CaptureLimits, capture, interface_name};

use crate::bus::args::DumpArgs;
use crate::bus::monitor::Monitor;
use crate::bus_open::open_bus;
use crate::error::{CliError, CliResult, stdout_error};
use crate::stop::StopFlag;

pub(crate) fn run(args: DumpArgs) -> CliResult {
    let stop = StopFlag::install()?;
    if let Some(path) = args.log.as_deref() {
        LogWriter::check_free(path, args.overwrite).map_err(log_error)?;
    }
    let mut bus = open_bus(args.bus.spec.as_deref(), "bus dump")?;
    // Created only once the bus is open, so a bus error leaves no empty log file behind.
    let mut log = args
        .log
        .as_deref()
        .map(|path| LogWriter::create(path, args.overwrite))
        .transpose()
        .map_err(log_error)?;
    let interface = interface_name(bus.spec());
    let mut out = crate::output::buffered_stdout();
    let mut monitor = Monitor::new(args.format, args.raw);
    let limits = CaptureLimits {
        count: args.count,
        duration: args.duration,
    };
    let mut lost_total = 0u64;
    let captured = capture(
        &mut *bus,
        limits,
        log.as_mut(),
        &stop.token(),
        |event| match event {
            CaptureEvent::Frame(received) => {
                monitor.print_frame(&mut out, received.timestamp, &interface, &received.frame)
            }
            CaptureEvent::Lost(lost) => {
                lost_total += lost;
                // The monitor fell behind; say so in the output stream where the gap is, and carry on.
                eprintln!("warning: {lost} frames lost because the monitor did not keep up");
                Ok(())
            }
            CaptureEvent::Flush => out.flush(),
        },
    );
    // Also after a bus failure: frames lost before it are still worth knowing about.
    if lost_total > 0 {
        eprintln!("warning: {lost_total} frames were lost in total");
    }
    match captured {
        Ok(_) => Ok(()),
        Err(CaptureError::Bus(err)) => Err(CliError::Bus(err)),
        Err(CaptureError::Log(err)) => Err(log_error(err)),
        Err(CaptureError::Output(err)) => Err(stdout_error(err)),
    }
}

/// The log's trouble in the words `bus dump` has always used, as an output error (exit 5).
fn log_error(err: LogFileError) -> CliError {
    match err {
        LogFileError::Exists { path, source } => CliError::output(
            format!(
                "log file {} already exists; choose another name or pass --overwrite",
                path.display()
            ),
            source,
        ),
        LogFileError::Create { path, source } => {
            CliError::output(format!("cannot create log file {}", path.display()), source)
        }
        LogFileError::Write { path, source } => {
            CliError::output(format!("writing {}", path.display()), source)
        }
    }
}

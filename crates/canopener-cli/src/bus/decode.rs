//! `canopener bus decode`: decode a candump log offline, line for line as `bus dump` prints live traffic.

use std::io::Write;

use canopener_can::candump::parse_log;
use canopener_runtime::candump_file::read_log;

use crate::bus::args::DecodeArgs;
use crate::bus::monitor::Monitor;
use crate::error::{CliError, CliResult, stdout_error};

pub(crate) fn run(args: DecodeArgs) -> CliResult {
    let text = read_log(&args.file)?;
    let (records, errors) = parse_log(&text);
    let mut out = crate::output::buffered_stdout();
    let mut monitor = Monitor::new(args.format, false);
    for (_, record) in &records {
        monitor.print_record(&mut out, record).map_err(stdout_error)?;
    }
    out.flush().map_err(stdout_error)?;
    for err in &errors {
        eprintln!(
            "{}:{}:{}: {}",
            args.file.display(),
            err.line,
            err.column,
            err.message
        );
    }
    if errors.is_empty() {
        Ok(())
    } else {
        Err(CliError::InvalidInput(format!(
            "{}: {} of {} lines could not be read (listed above); the rest were decoded",
            args.file.display(),
            errors.len(),
            errors.len() + records.len()
        )))
    }
}

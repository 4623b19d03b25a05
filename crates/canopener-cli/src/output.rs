//! Writing to the terminal: whole blocks of text at once, flushed, with a closed pipe (`| head`) mapped to
//! the quiet error that ends a command successfully.

use std::io::{BufWriter, StdoutLock, Write};

use crate::error::{CliResult, stdout_error};

/// Writes `text` to stdout under one lock and flushes it, so it appears at once even when stdout is a pipe.
pub(crate) fn print_stdout(text: &str) -> CliResult {
    write_stdout(text.as_bytes())
}

/// Writes bytes to stdout as they are (a file in its own encoding), under one lock, flushed.
pub(crate) fn write_stdout(bytes: &[u8]) -> CliResult {
    let mut out = std::io::stdout().lock();
    out.write_all(bytes)
        .and_then(|()| out.flush())
        .map_err(stdout_error)
}

/// Stdout locked and buffered for a stream of lines (a monitor printing frame by frame); the caller
/// flushes where the reader must see the output at once.
pub(crate) fn buffered_stdout() -> BufWriter<StdoutLock<'static>> {
    BufWriter::new(std::io::stdout().lock())
}

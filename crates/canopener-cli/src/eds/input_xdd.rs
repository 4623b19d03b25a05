//! XDD/XDC (CiA 311) input and output for the `eds` commands, through `canopener-xdd`.

use std::path::Path;

use canopener_xdd::{WriteOptions, XddError};

use crate::eds::input::{Finding, Input, SourceFormat};
use crate::error::{CliError, CliResult};

/// Reads an XDD, XDC, XPD or a single-device CANopenEditor project; refused files are trouble (exit 2).
pub(crate) fn read(path: &Path, bytes: &[u8]) -> CliResult<Input> {
    let loaded = canopener_xdd::read(bytes).map_err(|e| refused(path, &e))?;
    let diagnostics = loaded
        .diagnostics
        .iter()
        .map(|d| Finding {
            line: d.span.line,
            column: d.span.column,
            severity: d.severity,
            code: d.code.as_str().to_owned(),
            message: d.message.clone(),
            help: None,
        })
        .collect();
    Ok(Input {
        path: path.to_owned(),
        format: SourceFormat::Xdd,
        eds: loaded.eds,
        document: None,
        diagnostics,
    })
}

/// CiA 311 v1.1 text as CANopenEditor writes it (an XDC when the model is a DCF).
pub(crate) fn write(eds: &canopener_eds::Eds) -> CliResult<String> {
    Ok(canopener_xdd::write(eds, &WriteOptions::CANOPEN_EDITOR))
}

fn refused(path: &Path, error: &XddError) -> CliError {
    CliError::EdsTrouble(format!("{}: {error}", path.display()))
}

//! XDD/XDC input and output for the `eds` commands. The CiA 311 reader and writer (`canopener-xdd`) are
//! being built; until they land, XML files are refused with a message saying so.

use std::path::Path;

use crate::eds_input::Input;
use crate::error::{CliError, CliResult};

pub(crate) fn read(path: &Path, _bytes: &[u8]) -> CliResult<Input> {
    Err(CliError::EdsTrouble(format!(
        "{} is XML (XDD/XDC); this build cannot read CiA 311 files yet",
        path.display()
    )))
}

pub(crate) fn write(_eds: &canopener_eds::Eds) -> CliResult<String> {
    Err(CliError::EdsTrouble(
        "this build cannot write CiA 311 XDD files yet".to_owned(),
    ))
}

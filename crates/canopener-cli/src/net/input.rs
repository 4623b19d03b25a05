//! Reading a topology file for the `net` commands: a file that cannot be read is trouble (exit 2, as
//! for `eds` commands).

use std::path::Path;

use canopener_files::same_file;

use canopener_sim::system::files::SystemFiles;

use crate::error::{CliError, CliResult};

/// Reads `path`; problems inside the file are in its diagnostics, not an error.
pub(crate) fn read_system(path: &Path) -> CliResult<SystemFiles> {
    SystemFiles::read(path).map_err(|err| CliError::EdsTrouble(err.to_string()))
}

/// Refuses to write a result over the input file.
pub(crate) fn refuse_overwrite(output: Option<&Path>, input: &Path) -> CliResult {
    match output {
        Some(out) if same_file(out, input) => Err(CliError::EdsTrouble(format!(
            "refusing to overwrite the input {} with -o; write elsewhere",
            input.display()
        ))),
        _ => Ok(()),
    }
}

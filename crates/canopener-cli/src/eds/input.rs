//! What the `eds` commands (and the master and sim commands that take a device description) are
//! given: a description in any format, rule packs and a check selection, read through
//! `canopener-runtime`; and the summary of what loading found, on stderr.

use std::io::Write;
use std::path::Path;

use canopener_description::{Checker, Description, Selection};
use canopener_eds::Severity;

use crate::eds::args::CheckSelectionArgs;
use crate::error::{CliError, CliResult};

/// Reads and loads a description (EDS/DCF, XDD/XDC or JSON); only unreadable or refused files are
/// errors (exit 2).
pub(crate) fn read_input(path: &Path) -> CliResult<Description> {
    Ok(canopener_runtime::description::read_description(path)?)
}

/// Reads a file's bytes as they are (for commands that compare or edit them).
pub(crate) fn read_bytes(path: &Path) -> CliResult<Vec<u8>> {
    Ok(canopener_runtime::description::read_bytes(path)?)
}

/// The checks in force: the rule packs read, `--only/--skip` names checked against every known
/// check, `--tag` as given.
pub(crate) fn checker(args: &CheckSelectionArgs) -> CliResult<Checker> {
    let packs = canopener_runtime::description::read_rule_packs(&args.rules)
        .map_err(|e| CliError::EdsTrouble(e.to_string()))?;
    let names = |list: &[String]| -> Vec<String> {
        list.iter()
            .map(|s| s.trim().to_owned())
            .filter(|s| !s.is_empty())
            .collect()
    };
    let selection = Selection {
        only: names(&args.only),
        skip: names(&args.skip),
        tags: args.tag.clone(),
    };
    Checker::new(packs, selection).map_err(|e| {
        CliError::EdsTrouble(format!(
            "{e} in --only/--skip; `canopener eds rules list` shows every code"
        ))
    })
}

/// Prints a summary of the loading diagnostics to stderr, or all of them with `all`.
pub(crate) fn report_diagnostics(path: &Path, description: &Description, all: bool) {
    let mut err = std::io::stderr().lock();
    let (errors, warnings, infos) = (
        description.count(Severity::Error),
        description.count(Severity::Warning),
        description.count(Severity::Info),
    );
    if all {
        for d in &description.diagnostics {
            let _ = writeln!(err, "{}:{d}", path.display());
            if let Some(help) = &d.help {
                let _ = writeln!(err, "  help: {help}");
            }
        }
    }
    if errors + warnings > 0 {
        let hint = if all { "" } else { " (--diagnostics lists them)" };
        let _ = writeln!(
            err,
            "{}: loaded with {errors} error(s), {warnings} warning(s), {infos} note(s){hint}",
            path.display()
        );
    }
}

//! `canopener eds fix`: apply the safe fixes, say what each one did, and re-check the result.

use std::io::Write;

use canopener_check::Context;
use canopener_check::fix::{self, Fix};
use canopener_eds::Severity;

use crate::eds::args::{DenyLevel, EdsFixArgs};
use crate::eds::check::count;
use crate::eds::check_inputs::Checks;
use crate::eds::input::print_stdout;
use crate::error::{CliError, CliResult, stdout_error};
use canopener_runtime::files::{backup_path, same_file, write_atomic};

pub(crate) fn run(args: EdsFixArgs) -> CliResult {
    if let Some(out) = &args.output
        && same_file(out, &args.file)
    {
        return Err(CliError::EdsTrouble(format!(
            "refusing to overwrite the input {} with -o; use --in-place (it keeps a .bak)",
            args.file.display()
        )));
    }
    let checks = Checks::from_args(&args.selection)?;
    let bytes = std::fs::read(&args.file)
        .map_err(|e| CliError::EdsTrouble(format!("cannot read {}: {e}", args.file.display())))?;
    let name = args.file.file_name().and_then(|n| n.to_str());
    let rule_fixes = |cx: &Context<'_>| -> Vec<Fix> {
        checks
            .packs
            .iter()
            .flat_map(|pack| pack.fixes(cx, &checks.selection))
            .collect()
    };
    let outcome = fix::fix_file(&bytes, name, &checks.selection, &rule_fixes);
    let path = args.file.display();
    for applied in &outcome.fixes {
        let note = if applied.changes_meaning {
            " (changes what the file says about the device)"
        } else {
            ""
        };
        eprintln!("{path}: fixed {}: {}{note}", applied.code, applied.description);
    }
    for (skipped, reason) in &outcome.skipped {
        eprintln!(
            "{path}: not fixed {}: {}: {reason}",
            skipped.code, skipped.description
        );
    }
    if args.dry_run {
        // git-style a/ b/ prefixes only for relative paths, so `patch -p1` applies the diff.
        let (old, new) = if args.file.is_relative() {
            (format!("a/{path}"), format!("b/{path}"))
        } else {
            (path.to_string(), path.to_string())
        };
        let diff = fix::unified_diff(&bytes, &outcome.bytes, &old, &new);
        print_stdout(&diff)?;
    } else if args.in_place {
        if outcome.changed {
            write_atomic(&args.file, &outcome.bytes, true)?;
            eprintln!(
                "{path}: rewritten (original kept as {})",
                backup_path(&args.file).display()
            );
        } else {
            eprintln!("{path}: nothing to fix, file left untouched");
        }
    } else if let Some(out) = &args.output {
        write_atomic(out, &outcome.bytes, false)?;
    } else {
        let mut stdout = std::io::stdout().lock();
        stdout.write_all(&outcome.bytes).map_err(stdout_error)?;
        stdout.flush().map_err(stdout_error)?;
    }
    let before = checks.check_bytes(&args.file, &bytes);
    let after = checks.check_bytes(&args.file, &outcome.bytes);
    let (errors, warnings) = (count(&after, Severity::Error), count(&after, Severity::Warning));
    eprintln!(
        "{path}: {} fix(es) applied{}; errors {} -> {errors}, {warnings} warning(s) remain \
         (`canopener eds check` lists them)",
        outcome.fixes.len(),
        if args.dry_run { " in the diff only" } else { "" },
        count(&before, Severity::Error),
    );
    if errors > 0 || (args.deny == Some(DenyLevel::Warnings) && warnings > 0) {
        return Err(CliError::Exit(1));
    }
    Ok(())
}

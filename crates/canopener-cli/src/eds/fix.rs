//! `canopener eds fix`: apply the safe fixes, say what each one did, and re-check the result.

use canopener_check::fix;
use canopener_description::Format;
use canopener_eds::Severity;
use canopener_files::{backup_path, same_file, write_atomic};
use canopener_runtime::batch::display_path;

use crate::eds::args::{DenyLevel, EdsFixArgs};
use crate::eds::input::{checker, read_bytes};
use crate::error::{CliError, CliResult};
use crate::output::{print_stdout, write_stdout};

pub(crate) fn run(args: EdsFixArgs) -> CliResult {
    if let Some(out) = &args.output
        && same_file(out, &args.file)
    {
        return Err(CliError::EdsTrouble(format!(
            "refusing to overwrite the input {} with -o; use --in-place (it keeps a .bak)",
            args.file.display()
        )));
    }
    let checker = checker(&args.selection)?;
    let bytes = read_bytes(&args.file)?;
    let name = args.file.file_name().and_then(|n| n.to_str());
    let extension = args.file.extension().and_then(|e| e.to_str());
    if Format::is_xml(extension, &bytes) {
        // The fixes are line edits on CiA 306 text; an XML file is checked, not fixed.
        return Err(CliError::EdsTrouble(format!(
            "{}: is CiA 311 XML (XDD/XDC); `eds fix` fixes EDS/DCF text only. \
             `canopener eds check` reports what to change; edit the XML, or convert it with \
             `canopener eds convert` and fix the EDS",
            args.file.display()
        )));
    }
    let outcome = checker.fix(name, &bytes);
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
        write_stdout(&outcome.bytes)?;
    }
    let shown = display_path(&args.file);
    let before = checker.check(&shown, name, &bytes);
    let after = checker.check(&shown, name, &outcome.bytes);
    let (errors, warnings) = (after.count(Severity::Error), after.count(Severity::Warning));
    eprintln!(
        "{path}: {} fix(es) applied{}; errors {} -> {errors}, {warnings} warning(s) remain \
         (`canopener eds check` lists them)",
        outcome.fixes.len(),
        if args.dry_run { " in the diff only" } else { "" },
        before.count(Severity::Error),
    );
    if errors > 0 || (args.deny == Some(DenyLevel::Warnings) && warnings > 0) {
        return Err(CliError::Exit(1));
    }
    Ok(())
}

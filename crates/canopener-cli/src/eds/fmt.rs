//! `canopener eds fmt`: canonical CiA 306 text.

use crate::eds::args::EdsFmtArgs;
use crate::eds::convert::canonical_bytes;
use crate::eds::input::{print_stdout, read_input, report_diagnostics};
use crate::error::{CliError, CliResult};
use canopener_runtime::files::{backup_path, same_file, write_atomic};

pub(crate) fn run(args: EdsFmtArgs) -> CliResult {
    if let Some(out) = &args.output
        && same_file(out, &args.file)
    {
        return Err(CliError::EdsTrouble(format!(
            "refusing to overwrite the input {} with -o; use --in-place (it keeps a .bak)",
            args.file.display()
        )));
    }
    let input = read_input(&args.file)?;
    report_diagnostics(&input, args.diagnostics)?;
    let dropped = input.diagnostics.iter().filter(|d| d.code == "P020").count();
    if dropped > 0 && !args.check {
        eprintln!(
            "warning: {dropped} repeated section(s) are not part of the model and are left out; \
             `canopener eds show --diagnostics` names them"
        );
    }
    let bytes = canonical_bytes(&input, &input.eds)?;
    if args.check {
        let original = std::fs::read(&args.file)
            .map_err(|e| CliError::EdsTrouble(format!("cannot read {}: {e}", args.file.display())))?;
        if original == bytes {
            return Ok(());
        }
        eprintln!(
            "{} is not in canonical form; `canopener eds fmt --in-place` rewrites it",
            args.file.display()
        );
        return Err(CliError::Exit(1));
    }
    if args.in_place {
        write_atomic(&args.file, &bytes, true)?;
        eprintln!(
            "rewrote {} (original kept as {})",
            args.file.display(),
            backup_path(&args.file).display()
        );
        return Ok(());
    }
    match &args.output {
        Some(out) => Ok(write_atomic(out, &bytes, false)?),
        None => print_stdout(&String::from_utf8_lossy(&bytes)),
    }
}

//! `canopener eds fmt`: canonical CiA 306 text.

use canopener_description::DescriptionCode;
use canopener_eds::Code;
use canopener_files::{backup_path, same_file, write_atomic};

use crate::eds::args::EdsFmtArgs;
use crate::eds::input::{read_bytes, read_input, report_diagnostics};
use crate::error::{CliError, CliResult};
use crate::output::print_stdout;

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
    report_diagnostics(&args.file, &input, args.diagnostics);
    let dropped = input
        .diagnostics
        .iter()
        .filter(|d| d.code == DescriptionCode::Eds(Code::DuplicateSection))
        .count();
    if dropped > 0 && !args.check {
        eprintln!(
            "warning: {dropped} repeated section(s) are not part of the model and are left out; \
             `canopener eds show --diagnostics` names them"
        );
    }
    let bytes = input
        .canonical_bytes(&input.eds)
        .map_err(|e| CliError::EdsTrouble(format!("{}: {e}", args.file.display())))?;
    if args.check {
        if read_bytes(&args.file)? == bytes {
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

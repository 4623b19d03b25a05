//! `canopener eds diff`: the semantic difference of two device descriptions; exits like diff(1).

use std::fmt::Write as _;

use canopener_eds::diff::{ChangeKind, diff};
use serde::Serialize;

use crate::eds::args::{EdsDiffArgs, ReportFormat};
use crate::eds::input::read_input;
use crate::error::{CliError, CliResult};
use crate::output::print_stdout;

#[derive(Serialize)]
struct DiffJson<'a> {
    version: u32,
    a: String,
    b: String,
    equivalent: bool,
    changes: &'a [canopener_eds::diff::Change],
}

pub(crate) fn run(args: EdsDiffArgs) -> CliResult {
    let a = read_input(&args.a)?;
    let b = read_input(&args.b)?;
    let result = diff(&a.eds, &b.eds);
    let equivalent = result.is_equivalent();
    match args.format {
        ReportFormat::Json => {
            let doc = DiffJson {
                version: 1,
                a: args.a.display().to_string(),
                b: args.b.display().to_string(),
                equivalent,
                changes: &result.changes,
            };
            let text = serde_json::to_string_pretty(&doc).map_err(|e| CliError::Internal(e.into()))?;
            print_stdout(&format!("{text}\n"))?;
        }
        ReportFormat::Human => {
            let mut out = String::new();
            let _ = writeln!(out, "--- {}\n+++ {}", args.a.display(), args.b.display());
            for change in result.significant() {
                let _ = writeln!(out, "{change}");
            }
            let metadata: Vec<_> = result.changes.iter().filter(|c| !c.significant).collect();
            if !metadata.is_empty() {
                let _ = writeln!(out, "file metadata (does not count as a difference):");
                for change in metadata {
                    let _ = writeln!(out, "  {change}");
                }
            }
            let count = |k: ChangeKind| result.significant().filter(|c| c.kind == k).count();
            let _ = writeln!(
                out,
                "{}",
                if equivalent {
                    "same device and object dictionary".to_owned()
                } else {
                    format!(
                        "{} added, {} removed, {} changed",
                        count(ChangeKind::Added),
                        count(ChangeKind::Removed),
                        count(ChangeKind::Changed)
                    )
                }
            );
            print_stdout(&out)?;
        }
    }
    if equivalent {
        Ok(())
    } else {
        Err(CliError::Exit(1))
    }
}

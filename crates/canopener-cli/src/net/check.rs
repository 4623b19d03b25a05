//! `canopener net check`: findings about topology files and the DCFs they name, in the report
//! formats of `eds check`.

use canopener_check::Finding;
use canopener_description::{Checker, Selection};
use canopener_report::{FileReport, HumanOptions, Report};
use canopener_sim::system::files::SystemFiles;

use crate::error::{CliError, CliResult};
use crate::net::args::{NetCheckArgs, NetCheckFormat};
use crate::output::print_stdout;

pub(crate) fn run(args: NetCheckArgs) -> CliResult {
    let checker = Checker::new(Vec::new(), Selection::default())
        .map_err(|e| CliError::Internal(anyhow::anyhow!("the built-in checks: {e}")))?;
    let files = args
        .files
        .iter()
        .map(|path| {
            let shown = path.display().to_string();
            match SystemFiles::read(path) {
                Ok(system) => report(&shown, &system, &checker),
                Err(err) => FileReport::unreadable(shown, err.to_string()),
            }
        })
        .collect();
    let report = Report {
        tool_version: env!("CARGO_PKG_VERSION").to_owned(),
        checks: Vec::new(),
        files,
    };
    let rendered = match args.format {
        NetCheckFormat::Human => canopener_report::human(
            &report,
            &HumanOptions {
                color: false,
                summary_table: true,
            },
        ),
        NetCheckFormat::Json => canopener_report::json(&report),
    };
    print_stdout(&rendered)?;
    let summary = report.summary();
    if summary.problems > 0 {
        Err(CliError::Exit(2))
    } else if summary.errors > 0 {
        Err(CliError::Exit(1))
    } else {
        Ok(())
    }
}

fn report(shown: &str, system: &SystemFiles, checker: &Checker) -> FileReport {
    let findings = system
        .check(checker)
        .into_iter()
        .map(|diagnostic| Finding {
            diagnostic: diagnostic.into_string_code(),
            fixable: false,
        })
        .collect();
    FileReport::from_text(shown, findings, system.source_text())
}

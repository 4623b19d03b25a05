//! `canopener eds explain CODE`: the explanation page of one check.

use crate::eds::args::{CheckSelectionArgs, EdsExplainArgs, ReportFormat};
use crate::eds::input::checker;
use crate::error::{CliError, CliResult};
use crate::output::print_stdout;

pub(crate) fn run(args: EdsExplainArgs) -> CliResult {
    let checker = checker(&CheckSelectionArgs {
        rules: args.rules.clone(),
        only: Vec::new(),
        skip: Vec::new(),
        tag: Vec::new(),
    })?;
    let wanted = args.code.trim();
    let Some(check) = checker.find(wanted) else {
        return Err(CliError::EdsTrouble(format!(
            "no check '{wanted}'; `canopener eds rules list` shows every code (add --rules PACK for rule ids)"
        )));
    };
    let text = match args.format {
        ReportFormat::Json => {
            let mut json = serde_json::to_string_pretty(&check)
                .map_err(|e| CliError::Internal(anyhow::anyhow!("cannot serialise the check: {e}")))?;
            json.push('\n');
            json
        }
        ReportFormat::Human => {
            let mut page = format!(
                "{} {} ({}, {})\n{}\n\n",
                check.code, check.slug, check.severity, check.group, check.title
            );
            if !check.spec.is_empty() {
                page.push_str(&format!("Specification: {}\n", check.spec));
            }
            page.push_str(&format!(
                "Fixable by `canopener eds fix`: {}\nDefined by: {}\n\n",
                if check.fixable { "yes" } else { "no" },
                check.origin
            ));
            page.push_str(check.explanation.trim_end());
            page.push('\n');
            page
        }
    };
    print_stdout(&text)
}

//! `canopener eds rules list`: every check, built-in and from rule packs.

use crate::eds::args::{EdsRulesListArgs, ReportFormat};
use crate::eds::input::checker;
use crate::error::{CliError, CliResult};
use crate::output::print_stdout;

pub(crate) fn list(args: EdsRulesListArgs) -> CliResult {
    let selected = checker(&args.selection)?.selected();
    let text = match args.format {
        ReportFormat::Json => {
            let mut json =
                serde_json::to_string_pretty(&serde_json::json!({ "version": 1, "checks": selected }))
                    .map_err(|e| CliError::Internal(anyhow::anyhow!("cannot serialise the checks: {e}")))?;
            json.push('\n');
            json
        }
        ReportFormat::Human => {
            let code_width = selected.iter().map(|c| c.code.len()).max().unwrap_or(4).max(4);
            let group_width = selected
                .iter()
                .map(|c| c.group.name().len())
                .max()
                .unwrap_or(5)
                .max(5);
            let mut out = format!(
                "{:<code_width$}  {:<8}  {:<group_width$}  fix  title\n",
                "code", "severity", "group"
            );
            for check in &selected {
                out.push_str(&format!(
                    "{:<code_width$}  {:<8}  {:<group_width$}  {:<3}  {}\n",
                    check.code,
                    check.severity.to_string(),
                    check.group.name(),
                    if check.fixable { "yes" } else { "" },
                    check.title
                ));
            }
            out.push_str(&format!(
                "{} checks ({} built-in, {} from rule packs); `canopener eds explain CODE` explains one\n",
                selected.len(),
                selected.iter().filter(|c| c.origin == "built-in").count(),
                selected.iter().filter(|c| c.origin != "built-in").count()
            ));
            out
        }
    };
    print_stdout(&text)
}

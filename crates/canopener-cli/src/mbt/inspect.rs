//! `mbt models`, `mbt check` and `mbt explore`.

use canopener_mbt::shipped;

use crate::error::{CliError, CliResult};
use crate::mbt::args::{ExploreArgs, Format, ModelArgs, ModelsArgs};
use crate::mbt::load::{description, load};
use crate::output::print_stdout;

pub(crate) fn models(args: ModelsArgs) -> CliResult {
    match args.format {
        Format::Human => {
            let mut text = String::new();
            for m in shipped::MODELS {
                text.push_str(&format!("{:<8} {}\n", m.name, m.covers));
            }
            print_stdout(&text)
        }
        Format::Json => {
            let list: Vec<serde_json::Value> = shipped::MODELS
                .iter()
                .map(|m| serde_json::json!({"name": m.name, "covers": m.covers}))
                .collect();
            print_stdout(&format!("{}\n", serde_json::Value::Array(list)))
        }
    }
}

pub(crate) fn check(args: ModelArgs) -> CliResult {
    let eds = description(args.eds.as_ref())?;
    let loaded = load(&args.models, args.node, eds.as_ref(), &args.set)?;
    eprint!("{}", loaded.warnings);
    let m = &loaded.model;
    print_stdout(&format!(
        "{}: {} processes, {} locations, {} transitions, {} gates, {} purposes; model hash {}\n",
        m.name(),
        m.processes.len(),
        m.location_count(),
        m.transitions.len(),
        m.gates.len(),
        m.purposes.len(),
        &m.hash[..16]
    ))
}

pub(crate) fn explore(args: ExploreArgs) -> CliResult {
    let eds = description(args.model.eds.as_ref())?;
    let loaded = load(&args.model.models, args.model.node, eds.as_ref(), &args.model.set)?;
    eprint!("{}", loaded.warnings);
    let (space, diagnostics) = canopener_mbt::explore::explore(&loaded.model, args.max_states);
    eprint!(
        "{}",
        canopener_mbt::diagnostics::render(&loaded.model.name(), &diagnostics)
    );
    if canopener_mbt::diagnostics::has_errors(&diagnostics) {
        return Err(CliError::InvalidInput("the model cannot be explored".into()));
    }
    if let Some(path) = &args.aut {
        canopener_runtime::files::write_atomic(path, canopener_mbt::aut::write(&space.lts).as_bytes(), false)
            .map_err(|e| {
                CliError::output(
                    format!("writing {}", path.display()),
                    std::io::Error::other(e.to_string()),
                )
            })?;
    }
    if let Some(path) = &args.dot {
        let dot = canopener_mbt::explore::to_dot(&loaded.model, &space);
        canopener_runtime::files::write_atomic(path, dot.as_bytes(), false).map_err(|e| {
            CliError::output(
                format!("writing {}", path.display()),
                std::io::Error::other(e.to_string()),
            )
        })?;
    }
    print_stdout(&format!(
        "{}: {} states, {} transitions{}\n",
        loaded.model.name(),
        space.lts.states,
        space.lts.transitions.len(),
        if space.truncated {
            " (stopped at --max-states)"
        } else {
            ""
        }
    ))
}

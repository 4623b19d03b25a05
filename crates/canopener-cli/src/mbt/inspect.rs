//! `mbt models`, `mbt check` and `mbt explore`.

use canopener_mbt::shipped;

use crate::error::{CliError, CliResult};
use crate::mbt::args::{ExploreArgs, Format, ModelArgs, ModelsArgs, SynthArgs};
use crate::mbt::load::{description, load, write};
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

/// How many states of a composition `check` explores for disagreements.
const AGREEMENT_STATES: usize = 50_000;

pub(crate) fn check(args: ModelArgs) -> CliResult {
    let eds = description(args.eds.as_ref())?;
    let loaded = load(&args.models, args.node, eds.as_ref(), &args.set)?;
    eprint!("{}", loaded.warnings);
    let m = &loaded.model;
    // Composed models: where one requires what another refuses (M043), resets that differ (M044).
    for (file, d) in canopener_mbt::agreement::check(m, AGREEMENT_STATES) {
        eprint!(
            "{}",
            canopener_mbt::diagnostics::render(&m.files[file].origin, &[d])
        );
    }
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
        canopener_files::write_atomic(path, canopener_mbt::aut::write(&space.lts).as_bytes(), false)
            .map_err(|e| {
                CliError::output(
                    format!("writing {}", path.display()),
                    std::io::Error::other(e.to_string()),
                )
            })?;
    }
    if let Some(path) = &args.dot {
        let dot = canopener_mbt::explore::to_dot(&loaded.model, &space);
        canopener_files::write_atomic(path, dot.as_bytes(), false).map_err(|e| {
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

pub(crate) fn synth(args: SynthArgs) -> CliResult {
    let eds = description(args.model.eds.as_ref())?;
    let loaded = load(&args.model.models, args.model.node, eds.as_ref(), &args.model.set)?;
    eprint!("{}", loaded.warnings);
    let purpose = match (&args.purpose, &args.purpose_aut) {
        (_, Some(path)) => {
            let lts = read_aut(path)?;
            let name = path
                .file_stem()
                .map_or_else(|| "purpose".to_owned(), |s| s.to_string_lossy().into_owned());
            canopener_mbt::purpose::from_aut(&name, &lts)
                .map_err(|e| CliError::InvalidInput(format!("{}: {e}", path.display())))?
        }
        (Some(name), None) => match loaded.model.purposes.iter().find(|p| &p.name == name) {
            Some(p) => p.clone(),
            None => {
                let names: Vec<&str> = loaded.model.purposes.iter().map(|p| p.name.as_str()).collect();
                return Err(CliError::Usage(format!(
                    "the models have no purpose `{name}`; they have: {}",
                    if names.is_empty() {
                        "none".to_owned()
                    } else {
                        names.join(", ")
                    }
                )));
            }
        },
        (None, None) => {
            return Err(CliError::Usage(
                "give --purpose NAME or --purpose-aut FILE".into(),
            ));
        }
    };
    let spec = match &args.spec_aut {
        Some(path) => read_aut(path)?,
        None => canopener_mbt::explore::explore(&loaded.model, 100_000).0.lts,
    };
    let Some(ctg) = canopener_mbt::synth::synthesize(&spec, &purpose) else {
        eprintln!(
            "the purpose `{}` cannot be reached in the specification",
            purpose.name
        );
        return Err(CliError::Exit(crate::error::exit_code::CHECK_FAILED));
    };
    let text = canopener_mbt::aut::write(&ctg);
    let untimed = untimed_note(&loaded.model, &purpose.name, args.spec_aut.is_some());
    match &args.aut {
        Some(path) => {
            write(path, &text)?;
            print_stdout(&format!(
                "{}: {} states, {} transitions\n{untimed}",
                purpose.name,
                ctg.states,
                ctg.transitions.len()
            ))
        }
        None => {
            // The graph alone on stdout (for .aut tools); what it cannot judge on stderr.
            eprint!("{untimed}");
            print_stdout(&text)
        }
    }
}

/// What an untimed test graph cannot judge, with the figures of these models: the graph keeps no
/// clock, so a late or early output and the length of a quiescence are not in it.
fn untimed_note(model: &canopener_mbt::model::Model, purpose: &str, from_aut: bool) -> String {
    if from_aut {
        return "untimed: an .aut specification has no clocks; the graph cannot judge when an output comes\n"
            .to_owned();
    }
    let timed = model
        .transitions
        .iter()
        .filter(|t| t.kind.is_output() && t.window.is_some())
        .count();
    if timed == 0 {
        return String::new();
    }
    format!(
        "untimed: the graph drops the windows of {timed} timed outputs (clocks {}); it cannot judge an output that comes too late or too early, nor how long QUIESCENCE must last. `canopener mbt run ... --purpose {purpose}` follows the purpose with the clocks: a late output is fail there.\n",
        model.clocks.join(", ")
    )
}

/// Reads an .aut file; errors are exit 3 with every diagnostic named by place.
fn read_aut(path: &std::path::Path) -> CliResult<canopener_mbt::explore::Lts> {
    let bytes = canopener_files::read(path).map_err(|e| CliError::read_file(path, e))?;
    let (lts, diagnostics) = canopener_mbt::aut::read(&String::from_utf8_lossy(&bytes));
    let text = canopener_mbt::diagnostics::render(&path.display().to_string(), &diagnostics);
    if canopener_mbt::diagnostics::has_errors(&diagnostics) {
        return Err(CliError::InvalidInput(format!(
            "{text}the .aut file does not read"
        )));
    }
    eprint!("{text}");
    Ok(lts)
}

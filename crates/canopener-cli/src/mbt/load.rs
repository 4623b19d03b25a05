//! Models by name or file, composed and compiled; their diagnostics rendered as FILE:LINE:COLUMN.

use std::path::{Path, PathBuf};

use canopener_eds::model::Eds;
use canopener_mbt::compile::{Options, Source, compile};
use canopener_mbt::diagnostics::{has_errors, render};
use canopener_mbt::model::Model;
use canopener_mbt::shipped;
use canopener_runtime::mbt_sim::model_settings;

use crate::error::{CliError, CliResult};

/// A compiled model with the diagnostics text (warnings) to show.
pub(crate) struct Loaded {
    pub(crate) model: Model,
    pub(crate) warnings: String,
}

/// The source of a model argument: a shipped model's name, else a file.
fn source(arg: &str) -> CliResult<Source> {
    if let Some(text) = shipped::text(arg) {
        return Ok(Source {
            origin: arg.to_owned(),
            text: text.to_owned(),
        });
    }
    let path = Path::new(arg);
    let bytes = canopener_files::read(path).map_err(|e| {
        let names: Vec<&str> = shipped::MODELS.iter().map(|m| m.name).collect();
        CliError::Usage(format!(
            "`{arg}` is neither a shipped model ({}) nor a readable file: {e}",
            names.join(", ")
        ))
    })?;
    let text = String::from_utf8(bytes)
        .map_err(|_| CliError::InvalidInput(format!("{arg}: the model file is not UTF-8")))?;
    Ok(Source {
        origin: arg.to_owned(),
        text,
    })
}

/// Reads `--eds FILE` if given.
pub(crate) fn description(path: Option<&PathBuf>) -> CliResult<Option<Eds>> {
    path.map(|p| Ok(canopener_runtime::description::read_description(p)?.eds))
        .transpose()
}

/// Loads, composes and compiles `models`; errors are exit 3 with every diagnostic named by place.
pub(crate) fn load(
    models: &[String],
    node: u8,
    eds: Option<&Eds>,
    set: &[(String, i64)],
) -> CliResult<Loaded> {
    let sources = models.iter().map(|m| source(m)).collect::<CliResult<Vec<_>>>()?;
    // `sdo-download` tests a long entry and a limited one only where it is told which: the
    // description names them; `--set` still wins.
    let settings = match eds {
        Some(eds) => model_settings(models, eds, node, set),
        None => set.to_vec(),
    };
    let options = Options {
        node_id: node,
        eds,
        set: settings,
    };
    let (model, report) = compile(&sources, &options, &|name| shipped::text(name).map(str::to_owned));
    let text: String = report.iter().map(|r| render(&r.origin, &r.diagnostics)).collect();
    let failed = report.iter().any(|r| has_errors(&r.diagnostics));
    match model {
        Some(model) if !failed => Ok(Loaded {
            model,
            warnings: text,
        }),
        _ => Err(CliError::InvalidInput(format!(
            "{}the model does not check",
            text
        ))),
    }
}

/// Writes a result file atomically (a reader never sees half of it).
pub(crate) fn write(path: &Path, text: &str) -> CliResult {
    canopener_files::write_atomic(path, text.as_bytes(), false).map_err(|e| {
        CliError::output(
            format!("writing {}", path.display()),
            std::io::Error::other(e.to_string()),
        )
    })
}

//! Reading a device description in any format canopener knows: EDS/DCF (CiA 306), XDD/XDC (CiA 311)
//! or canopener's JSON form, and reporting what loading found.

use std::io::Write;
use std::path::{Path, PathBuf};

use canopener_eds::{Diagnostic, Document, Eds, Severity};

use crate::error::{CliError, CliResult, stdout_error};

/// The format a file was read as.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SourceFormat {
    /// CiA 306 EDS or DCF text.
    Eds,
    /// CiA 311 XML.
    Xdd,
    /// canopener's JSON form.
    Json,
}

/// A loaded device description.
#[derive(Debug)]
pub(crate) struct Input {
    pub(crate) path: PathBuf,
    pub(crate) format: SourceFormat,
    pub(crate) eds: Eds,
    /// The lossless document, for EDS/DCF input.
    pub(crate) document: Option<Document>,
    /// What loading found, as `(line, column, severity, code, message, help)`.
    pub(crate) diagnostics: Vec<Finding>,
}

/// One loading diagnostic, whatever the format.
#[derive(Debug, Clone, serde::Serialize)]
pub(crate) struct Finding {
    pub(crate) line: u32,
    pub(crate) column: u32,
    pub(crate) severity: Severity,
    pub(crate) code: String,
    pub(crate) message: String,
    pub(crate) help: Option<String>,
}

impl From<&Diagnostic> for Finding {
    fn from(d: &Diagnostic) -> Self {
        Finding {
            line: d.span.line,
            column: d.span.column,
            severity: d.severity,
            code: d.code.as_str().to_owned(),
            message: d.message.clone(),
            help: d.help.clone(),
        }
    }
}

/// Reads and loads a file; only unreadable or refused files are errors (exit 2).
pub(crate) fn read_input(path: &Path) -> CliResult<Input> {
    let bytes = std::fs::read(path)
        .map_err(|e| CliError::EdsTrouble(format!("cannot read {}: {e}", path.display())))?;
    match sniff(path, &bytes) {
        SourceFormat::Json => {
            let text = String::from_utf8_lossy(&bytes);
            let eds = canopener_eds::json::from_json(&text)
                .map_err(|e| CliError::EdsTrouble(format!("{}: {e}", path.display())))?;
            Ok(Input {
                path: path.to_owned(),
                format: SourceFormat::Json,
                eds,
                document: None,
                diagnostics: Vec::new(),
            })
        }
        SourceFormat::Xdd => crate::eds::input_xdd::read(path, &bytes),
        SourceFormat::Eds => {
            let loaded = canopener_eds::load(&bytes);
            let diagnostics = loaded.diagnostics.iter().map(Finding::from).collect();
            Ok(Input {
                path: path.to_owned(),
                format: SourceFormat::Eds,
                eds: loaded.eds,
                document: Some(loaded.document),
                diagnostics,
            })
        }
    }
}

/// Decides the format by extension, then by the first character.
fn sniff(path: &Path, bytes: &[u8]) -> SourceFormat {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "json" => return SourceFormat::Json,
        "xdd" | "xdc" | "xpd" | "nxdd" | "xml" => return SourceFormat::Xdd,
        "eds" | "dcf" => return SourceFormat::Eds,
        _ => {}
    }
    let body = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    match body.iter().find(|b| !b.is_ascii_whitespace()) {
        Some(b'{') => SourceFormat::Json,
        Some(b'<') => SourceFormat::Xdd,
        _ => SourceFormat::Eds,
    }
}

/// Prints a summary of the loading diagnostics to stderr, or all of them with `all`.
pub(crate) fn report_diagnostics(input: &Input, all: bool) -> CliResult {
    let mut err = std::io::stderr().lock();
    let count = |s: Severity| input.diagnostics.iter().filter(|d| d.severity == s).count();
    let (errors, warnings, infos) = (
        count(Severity::Error),
        count(Severity::Warning),
        count(Severity::Info),
    );
    if all {
        for d in &input.diagnostics {
            let _ = writeln!(
                err,
                "{}:{}:{}: {}[{}]: {}",
                input.path.display(),
                d.line,
                d.column,
                d.severity,
                d.code,
                d.message
            );
            if let Some(help) = &d.help {
                let _ = writeln!(err, "  help: {help}");
            }
        }
    }
    if errors + warnings > 0 {
        let hint = if all { "" } else { " (--diagnostics lists them)" };
        let _ = writeln!(
            err,
            "{}: loaded with {errors} error(s), {warnings} warning(s), {infos} note(s){hint}",
            input.path.display()
        );
    }
    Ok(())
}

/// Writes text to stdout, ending quietly if the reader went away.
pub(crate) fn print_stdout(text: &str) -> CliResult {
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes()).map_err(stdout_error)?;
    out.flush().map_err(stdout_error)
}

//! What the master commands share in presenting results: JSON lines, milliseconds, object names,
//! the wording of SDO failures (exit status 7) and interruptions (130), and the progress bar of long
//! transfers. Protocol logic is in `canopener-master` and `canopener-link`.

use std::io::IsTerminal;
use std::path::Path;
use std::time::Duration;

use canopener_files::{self as files, WriteError, backup_path};
use canopener_link::sdo_session::SdoError;
use canopener_master::statistics::Spread;
use canopener_master::value::{DisplayValue, entry_label};
use canopener_wire::NmtState;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde_json::json;

use crate::error::{CliError, CliResult, exit_code};
use crate::output::print_stdout;

/// One JSON object on a line of stdout.
pub(crate) fn print_json(value: &serde_json::Value) -> CliResult {
    print_stdout(&format!("{value}\n"))
}

/// Milliseconds with microsecond resolution, for messages and JSON.
pub(crate) fn millis(duration: Duration) -> f64 {
    (duration.as_secs_f64() * 1e6).round() / 1e3
}

/// Min, median and max in milliseconds, as JSON.
pub(crate) fn spread_json(spread: &Spread) -> serde_json::Value {
    json!({"min": millis(spread.min), "median": millis(spread.median), "max": millis(spread.max)})
}

/// `1018h:01`, or `1018h:01 (Vendor-ID)` with a name.
pub(crate) fn object_name(index: u16, sub: u8, name: Option<&str>) -> String {
    match name.filter(|name| !name.is_empty()) {
        Some(name) => format!("{} ({name})", entry_label(index, sub)),
        None => entry_label(index, sub),
    }
}

/// Bytes as hex without separators (`BC0A0000`), the `raw` of JSON output.
pub(crate) fn raw_hex(data: &[u8]) -> String {
    data.iter().map(|byte| format!("{byte:02X}")).collect()
}

/// Bytes as spaced hex (`3C FB FF`).
pub(crate) fn hex_bytes(data: &[u8]) -> String {
    data.iter()
        .map(|byte| format!("{byte:02X}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// A decoded value as JSON: numbers and bools as such, strings as strings, bytes as hex text
/// (`"01 02 FF"`), REALs that JSON cannot hold (NaN, infinity) as text.
pub(crate) fn json_value(value: &DisplayValue) -> serde_json::Value {
    match value {
        DisplayValue::Bool(value) => json!(value),
        DisplayValue::Unsigned { value, .. } => json!(value),
        DisplayValue::Signed { value, .. } => json!(value),
        DisplayValue::Real32(value) => float_json(f64::from(*value), value.to_string()),
        DisplayValue::Real64(value) => float_json(*value, value.to_string()),
        DisplayValue::Text(bytes) => json!(String::from_utf8_lossy(bytes)),
        DisplayValue::Bytes(_) => json!(value.plain()),
    }
}

fn float_json(value: f64, text: String) -> serde_json::Value {
    serde_json::Number::from_f64(value).map_or(serde_json::Value::String(text), serde_json::Value::Number)
}

/// The lower-case CiA 301 name of a state, as JSON output writes it.
pub(crate) fn state_key(state: NmtState) -> &'static str {
    match state {
        NmtState::BootUp => "boot-up",
        NmtState::Stopped => "stopped",
        NmtState::Operational => "operational",
        NmtState::PreOperational => "pre-operational",
    }
}

/// A failed SDO transfer of `index`:`sub` with node `node`: the device's refusal or silence (exit
/// 7, naming the node, the object and the abort), an interruption (130), a transfer that could not
/// start (2) or the bus (4).
pub(crate) fn sdo_error(node: u8, index: u16, sub: u8, name: Option<&str>, err: SdoError) -> CliError {
    match err {
        SdoError::Transfer(error) => {
            CliError::Device(format!("node {node}, {}: {error}", object_name(index, sub, name)))
        }
        SdoError::Start(error) => {
            CliError::Usage(format!("node {node}, {}: {error}", object_name(index, sub, None)))
        }
        other => session_error(node, other),
    }
}

/// A session that stopped for another reason than the device: interrupted (the running transfer
/// was aborted on the bus), the bus failing, or a transfer that could not start.
pub(crate) fn session_error(node: u8, err: SdoError) -> CliError {
    match err {
        SdoError::Cancelled { index, sub } => {
            eprintln!(
                "interrupted: the transfer of node {node}, {} was aborted (0x08000000 sent to the device)",
                object_name(index, sub, None)
            );
            CliError::Exit(exit_code::INTERRUPTED)
        }
        SdoError::Link(err) => err.into(),
        SdoError::Transfer(error) => CliError::Device(format!("node {node}: {error}")),
        SdoError::Start(error) => CliError::Internal(anyhow::anyhow!("node {node}: {error}")),
    }
}

/// A progress bar for the bytes of one transfer on stderr, drawn only on a terminal.
#[derive(Debug)]
pub(crate) struct ByteProgress {
    bar: ProgressBar,
}

impl ByteProgress {
    /// A bar labelled `what` (e.g. "reading 2100h:00").
    pub(crate) fn new(what: &str) -> ByteProgress {
        let bar = if std::io::stderr().is_terminal() {
            ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr())
        } else {
            ProgressBar::hidden()
        };
        if let Ok(style) = ProgressStyle::with_template("{spinner} {msg} {bytes} {binary_bytes_per_sec}") {
            bar.set_style(style);
        }
        bar.set_message(what.to_owned());
        ByteProgress { bar }
    }

    /// Moves the bar to `done` of `total` bytes (a bar once the total is known, a counter before).
    pub(crate) fn update(&self, done: usize, total: Option<usize>) {
        if let Some(total) = total
            && self.bar.length().is_none()
        {
            self.bar.set_length(total as u64);
            if let Ok(style) = ProgressStyle::with_template(
                "{spinner} {msg} {bytes}/{total_bytes} {wide_bar} {binary_bytes_per_sec} {eta}",
            ) {
                self.bar.set_style(style);
            }
        }
        self.bar.set_position(done as u64);
    }

    /// Removes the bar.
    pub(crate) fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// A bar of `len` steps labelled by `template`, drawn only on a terminal and for two or more.
pub(crate) fn count_bar(len: u64, template: &str) -> ProgressBar {
    if len < 2 || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
    if let Ok(style) = ProgressStyle::with_template(template) {
        bar.set_style(style);
    }
    bar
}

/// A spinner on stderr with `template`, drawn only on a terminal.
pub(crate) fn spinner(template: &str) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
    if let Ok(style) = ProgressStyle::with_template(template) {
        bar.set_style(style);
    }
    bar
}

/// Throughput in kB/s (1000 bytes), as the final lines of upload and download report it.
pub(crate) fn kbytes_per_s(bytes: usize, elapsed: Duration) -> f64 {
    let secs = elapsed.as_secs_f64();
    if secs <= 0.0 {
        return 0.0;
    }
    bytes as f64 / 1000.0 / secs
}

/// Refuses to replace `path` without `--force` (before any bus traffic).
pub(crate) fn refuse_existing(path: &Path, force: bool) -> CliResult {
    if files::exists(path) && !force {
        return Err(CliError::Usage(format!(
            "{} exists; pass --force to replace it (the old file is kept as {})",
            path.display(),
            backup_path(path).display()
        )));
    }
    Ok(())
}

/// A result file that could not be written is an output error (exit 5).
pub(crate) fn output_error(path: &Path, err: WriteError) -> CliError {
    CliError::output(
        format!("writing {}", path.display()),
        std::io::Error::other(err.to_string()),
    )
}

#[cfg(test)]
mod tests {
    use canopener_master::sdo_client::SdoTransferError;
    use canopener_wire::abort;

    use super::*;

    #[test]
    fn failures_name_the_node_the_object_and_the_abort_text() {
        let abort = SdoTransferError::AbortedByServer {
            code: abort::SUB_INDEX_DOES_NOT_EXIST,
        };
        let err = sdo_error(5, 0x1018, 5, None, abort.into());
        assert_eq!(err.exit_code(), 7);
        assert_eq!(
            err.to_string(),
            "node 5, 1018h:05: SDO abort 0x06090011 from the server: Sub-index does not exist"
        );
        let timeout = SdoTransferError::TimedOut {
            waiting_for: "initiate upload response",
            after: Duration::from_millis(300),
        };
        let named = sdo_error(9, 0x1017, 0, Some("Producer heartbeat time"), timeout.into()).to_string();
        assert!(
            named
                .starts_with("node 9, 1017h:00 (Producer heartbeat time): timed out after 300ms waiting for"),
            "{named}"
        );
        let interrupted = sdo_error(
            9,
            0x1017,
            0,
            None,
            SdoError::Cancelled {
                index: 0x1017,
                sub: 0,
            },
        );
        assert_eq!(interrupted.exit_code(), exit_code::INTERRUPTED);
    }

    #[test]
    fn throughput_and_milliseconds() {
        assert_eq!(kbytes_per_s(10_000, Duration::from_secs(2)), 5.0);
        assert_eq!(kbytes_per_s(10, Duration::ZERO), 0.0);
        assert_eq!(millis(Duration::from_micros(1234)), 1.234);
        assert_eq!(millis(Duration::from_nanos(1_234_567)), 1.235);
    }

    #[test]
    fn json_values_keep_their_kind() {
        assert_eq!(
            json_value(&DisplayValue::Unsigned { value: 700, bits: 32 }),
            json!(700)
        );
        assert_eq!(
            json_value(&DisplayValue::Signed { value: -5, bits: 8 }),
            json!(-5)
        );
        assert_eq!(json_value(&DisplayValue::Bool(true)), json!(true));
        assert_eq!(json_value(&DisplayValue::Real32(1.5)), json!(1.5));
        assert_eq!(json_value(&DisplayValue::Real64(f64::NAN)), json!("NaN"));
        assert_eq!(json_value(&DisplayValue::Text(b"hi".to_vec())), json!("hi"));
        assert_eq!(json_value(&DisplayValue::Bytes(vec![1, 0xFF])), json!("01 FF"));
        assert_eq!(raw_hex(&[0xBC, 0x0A, 0, 0]), "BC0A0000");
        assert_eq!(hex_bytes(&[0x3C, 0xFB]), "3C FB");
        assert_eq!(state_key(NmtState::PreOperational), "pre-operational");
    }

    #[test]
    fn existing_outputs_need_force_and_write_errors_are_output_errors() {
        let existing = Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml");
        let err = refuse_existing(&existing, false).unwrap_err();
        assert_eq!(err.exit_code(), 2);
        assert!(err.to_string().contains("--force") && err.to_string().contains("Cargo.toml.bak"));
        assert!(refuse_existing(&existing, true).is_ok());
        assert!(refuse_existing(&existing.with_file_name("no-such-file.bin"), false).is_ok());
        let denied = WriteError {
            action: "create",
            path: existing.clone(),
            source: std::io::Error::from(std::io::ErrorKind::PermissionDenied),
        };
        assert_eq!(output_error(&existing, denied).exit_code(), 5);
    }
}

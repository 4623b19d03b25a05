//! Check-time measurement for `bench/eds_check.py`, which runs it side by side with python canopen's
//! `import_od` on the same files.
//!
//! ```text
//! cargo run --release -p canopener-check --example check_timing -- [--repeat N] [--list FILE|-] FILE...
//! ```
//!
//! Every file is read, loaded and checked with every built-in check `N` times (default 7) on one
//! thread; one JSON document gives per file the median time of the whole (read + load + check) and of
//! the load alone, in microseconds, and how many findings and errors the check produced.

// This is a measurement program, not library code: it reads the files it times and the clock, so the
// workspace's sans-IO bans and its no-printing rule do not apply here.
#![allow(clippy::disallowed_methods, clippy::print_stdout, clippy::print_stderr)]

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use canopener_check::Selection;
use canopener_eds::Severity;
use serde_json::{Value as Json, json};

const USAGE: &str = "usage: check_timing [--repeat N] [--list FILE|-] FILE...";

fn main() -> ExitCode {
    match parse(std::env::args().skip(1).collect()) {
        Ok((repeat, files)) => {
            let results: Vec<Json> = files.iter().map(|p| time_file(p, repeat)).collect();
            println!(
                "{}",
                json!({ "tool": "canopener", "repeat": repeat, "files": results })
            );
            ExitCode::SUCCESS
        }
        Err(message) => {
            eprintln!("check_timing: {message}\n{USAGE}");
            ExitCode::from(2)
        }
    }
}

fn parse(args: Vec<String>) -> Result<(usize, Vec<PathBuf>), String> {
    let mut repeat = 7;
    let mut files = Vec::new();
    let mut rest = args.into_iter();
    while let Some(arg) = rest.next() {
        match arg.as_str() {
            "--repeat" => {
                let text = rest.next().ok_or("--repeat needs a number")?;
                repeat = text
                    .parse()
                    .ok()
                    .filter(|&n| n > 0)
                    .ok_or_else(|| format!("--repeat {text:?} is not a positive whole number"))?;
            }
            "--list" => {
                let list = rest
                    .next()
                    .ok_or("--list needs a file of paths, or `-` for stdin")?;
                let text = if list == "-" {
                    std::io::read_to_string(std::io::stdin()).map_err(|e| format!("reading stdin: {e}"))?
                } else {
                    std::fs::read_to_string(&list).map_err(|e| format!("reading {list:?}: {e}"))?
                };
                files.extend(
                    text.lines()
                        .map(str::trim)
                        .filter(|l| !l.is_empty())
                        .map(PathBuf::from),
                );
            }
            flag if flag.starts_with("--") => return Err(format!("unknown option {flag:?}")),
            path => files.push(PathBuf::from(path)),
        }
    }
    if files.is_empty() {
        return Err("no files to check".to_owned());
    }
    Ok((repeat, files))
}

fn time_file(path: &Path, repeat: usize) -> Json {
    let shown = path.display().to_string();
    let name = path.file_name().and_then(|n| n.to_str());
    let selection = Selection::default();
    let mut whole = Vec::with_capacity(repeat);
    let mut load_only = Vec::with_capacity(repeat);
    let mut counts = (0, 0);
    for _ in 0..repeat {
        let start = Instant::now();
        let bytes = match std::fs::read(path) {
            Ok(bytes) => bytes,
            Err(e) => return json!({ "path": shown, "error": format!("cannot read the file: {e}") }),
        };
        let loaded = black_box(canopener_eds::load(black_box(&bytes)));
        let loaded_at = Instant::now();
        let findings = black_box(canopener_check::check(&loaded, name, &selection)).findings;
        let done = Instant::now();
        whole.push(done - start);
        load_only.push(loaded_at - start);
        counts = (
            findings.len(),
            findings
                .iter()
                .filter(|f| f.diagnostic.severity == Severity::Error)
                .count(),
        );
    }
    json!({
        "path": shown,
        "median_us": micros(median(&mut whole)),
        "load_median_us": micros(median(&mut load_only)),
        "findings": counts.0,
        "errors": counts.1,
    })
}

fn median(times: &mut [Duration]) -> Duration {
    times.sort_unstable();
    times.get(times.len() / 2).copied().unwrap_or_default()
}

fn micros(d: Duration) -> f64 {
    d.as_secs_f64() * 1e6
}

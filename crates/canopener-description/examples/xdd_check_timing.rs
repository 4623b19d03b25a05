//! XDD check-time measurement for `bench/xdd_check.py`: how long `eds check` takes on a CiA 311 file
//! against how long reading it takes.
//!
//! ```text
//! cargo run --release -p canopener-description --example xdd_check_timing -- [--repeat N] FILE...
//! ```
//!
//! Every file is read from disk once; then, `N` times each (default 7) on one thread, the XDD reader
//! alone (`canopener_xdd::read`: the model, diagnostics and locations) and the whole check
//! (`Checker::check`: reading, the model checks on the reader's model, placing findings in the
//! XML). One JSON document gives per file the median and fastest time of both in microseconds and
//! the finding count.

// This is a measurement program, not library code: it reads the files it times and the clock, so the
// workspace's sans-IO bans and its no-printing rule do not apply here.
#![allow(clippy::disallowed_methods, clippy::print_stdout, clippy::print_stderr)]

use std::hint::black_box;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use canopener_description::{Checker, Selection};
use serde_json::json;

const USAGE: &str = "usage: xdd_check_timing [--repeat N] FILE...";

fn main() -> ExitCode {
    let mut repeat = 7;
    let mut files = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        if arg == "--repeat" {
            match args
                .next()
                .and_then(|n| n.parse().ok())
                .filter(|&n: &usize| n > 0)
            {
                Some(n) => repeat = n,
                None => {
                    eprintln!("xdd_check_timing: --repeat needs a positive whole number\n{USAGE}");
                    return ExitCode::from(2);
                }
            }
        } else {
            files.push(PathBuf::from(arg));
        }
    }
    if files.is_empty() {
        eprintln!("xdd_check_timing: no files\n{USAGE}");
        return ExitCode::from(2);
    }
    let checker = Checker::new(Vec::new(), Selection::default()).expect("no names to check");
    let mut results = Vec::new();
    for path in &files {
        let shown = path.display().to_string();
        let bytes = match std::fs::read(path) {
            Ok(bytes) => bytes,
            Err(e) => {
                results.push(json!({ "path": shown, "error": format!("cannot read the file: {e}") }));
                continue;
            }
        };
        let name = path.file_name().and_then(|n| n.to_str());
        let (mut read, mut check) = (Vec::new(), Vec::new());
        let mut outcome = (0, None);
        for _ in 0..repeat {
            let start = Instant::now();
            let loaded = black_box(canopener_xdd::read(black_box(&bytes)));
            read.push(start.elapsed());
            drop(loaded);
            let start = Instant::now();
            let report = black_box(checker.check(&shown, name, black_box(&bytes)));
            check.push(start.elapsed());
            outcome = (report.findings.len(), report.problem);
        }
        results.push(json!({
            "path": shown,
            "bytes": bytes.len(),
            "read_median_us": micros(median(&mut read)),
            "check_median_us": micros(median(&mut check)),
            // The fastest run: on a shared machine the one least disturbed by other processes.
            "read_min_us": micros(read.iter().min().copied().unwrap_or_default()),
            "check_min_us": micros(check.iter().min().copied().unwrap_or_default()),
            "findings": outcome.0,
            "refused": outcome.1,
        }));
    }
    println!(
        "{}",
        json!({ "tool": "canopener", "repeat": repeat, "files": results })
    );
    ExitCode::SUCCESS
}

fn median(times: &mut [Duration]) -> Duration {
    times.sort_unstable();
    times.get(times.len() / 2).copied().unwrap_or_default()
}

fn micros(d: Duration) -> f64 {
    d.as_secs_f64() * 1e6
}

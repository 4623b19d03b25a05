//! Load-time measurement for `bench/eds_load.py`, which runs it side by side with python canopen's
//! `import_od` on the same files.
//!
//! ```text
//! cargo run --release -p canopener-eds --example load_timing -- [--repeat N] [--list FILE|-] FILE...
//! cargo run --release -p canopener-eds --example load_timing -- --generate OBJECTS OUT
//! ```
//!
//! The first form loads every file `N` times (default 7) and prints one JSON document: per file the
//! median and minimum time of one load in microseconds, and what the model holds (objects plus
//! sub-objects). Each timed load reads the file and parses it, as `import_od(path)` does on the
//! Python side; the parse alone is reported too. Files that cannot be read are listed with the error
//! and do not stop the run. The second form writes the synthetic EDS of `benches/support` (the one
//! generator both tools read), so the two sides time the identical file.

// This is a measurement program, not library code: it reads the files it times and the clock, so the
// workspace's sans-IO bans and its no-printing rule do not apply here.
#![allow(clippy::disallowed_methods, clippy::print_stdout, clippy::print_stderr)]

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use serde_json::{Value as Json, json};

#[path = "../benches/support/synthetic_eds.rs"]
mod synthetic_eds;

const USAGE: &str = "usage: load_timing [--repeat N] [--list FILE|-] FILE...
       load_timing --generate OBJECTS OUT
  --repeat N         loads of each file; the median is reported (default 7)
  --list FILE        also read file paths from FILE, one per line (`-` for stdin)
  --generate N OUT   write the synthetic EDS with N objects to OUT and print its counts";

const DEFAULT_REPEAT: usize = 7;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match Command::parse(&args).and_then(Command::run) {
        Ok(report) => {
            println!("{report}");
            ExitCode::SUCCESS
        }
        Err(message) => {
            eprintln!("load_timing: {message}\n{USAGE}");
            ExitCode::from(2)
        }
    }
}

/// What the command line asks for.
#[derive(Debug, PartialEq, Eq)]
enum Command {
    Time { repeat: usize, files: Vec<PathBuf> },
    Generate { objects: usize, out: PathBuf },
}

impl Command {
    fn parse(args: &[String]) -> Result<Command, String> {
        let mut repeat = DEFAULT_REPEAT;
        let mut files = Vec::new();
        let mut rest = args.iter();
        while let Some(arg) = rest.next() {
            match arg.as_str() {
                "--repeat" => {
                    let text = rest.next().ok_or("--repeat needs a number of loads per file")?;
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
                    files.extend(read_list(list)?);
                }
                "--generate" => {
                    let (Some(count), Some(out)) = (rest.next(), rest.next()) else {
                        return Err("--generate needs an object count and an output path".to_owned());
                    };
                    let objects = count
                        .parse::<usize>()
                        .ok()
                        .filter(|n| (1..=synthetic_eds::MAX_OBJECTS).contains(n))
                        .ok_or_else(|| {
                            format!(
                                "--generate {count:?}: the object count must be a whole number from 1 to {}",
                                synthetic_eds::MAX_OBJECTS
                            )
                        })?;
                    if let Some(extra) = rest.next() {
                        return Err(format!("unexpected argument {extra:?} after --generate N OUT"));
                    }
                    return Ok(Command::Generate {
                        objects,
                        out: PathBuf::from(out),
                    });
                }
                flag if flag.starts_with("--") => return Err(format!("unknown option {flag:?}")),
                path => files.push(PathBuf::from(path)),
            }
        }
        if files.is_empty() {
            return Err("no files to load; pass paths or --list".to_owned());
        }
        Ok(Command::Time { repeat, files })
    }

    fn run(self) -> Result<Json, String> {
        match self {
            Command::Generate { objects, out } => generate(objects, &out),
            Command::Time { repeat, files } => {
                let results: Vec<Json> = files.iter().map(|path| time_file(path, repeat)).collect();
                Ok(json!({ "tool": "canopener", "repeat": repeat, "files": results }))
            }
        }
    }
}

fn read_list(list: &str) -> Result<Vec<PathBuf>, String> {
    let text = if list == "-" {
        std::io::read_to_string(std::io::stdin())
            .map_err(|e| format!("reading the file list from stdin: {e}"))?
    } else {
        std::fs::read_to_string(list).map_err(|e| format!("reading the file list {list:?}: {e}"))?
    };
    Ok(text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .map(PathBuf::from)
        .collect())
}

fn generate(objects: usize, out: &Path) -> Result<Json, String> {
    let eds = synthetic_eds::synthetic_eds(objects);
    std::fs::write(out, &eds.text).map_err(|e| format!("writing {}: {e}", out.display()))?;
    Ok(json!({
        "path": out.display().to_string(),
        "bytes": eds.text.len(),
        "objects": eds.objects,
        "sub_objects": eds.sub_objects,
    }))
}

/// What one load of a file produced.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Counts {
    objects: usize,
    sub_objects: usize,
    diagnostics: usize,
    errors: usize,
}

fn count(loaded: &canopener_eds::Loaded) -> Counts {
    Counts {
        objects: loaded.eds.objects.len(),
        sub_objects: loaded.eds.objects.values().map(|o| o.subs.len()).sum(),
        diagnostics: loaded.diagnostics.len(),
        errors: loaded
            .diagnostics
            .iter()
            .filter(|d| d.severity == canopener_eds::Severity::Error)
            .count(),
    }
}

fn time_file(path: &Path, repeat: usize) -> Json {
    let shown = path.display().to_string();
    let mut total = Vec::with_capacity(repeat);
    let mut parse = Vec::with_capacity(repeat);
    let mut counts = None;
    let mut bytes_len = 0;
    for _ in 0..repeat {
        let start = Instant::now();
        let bytes = match std::fs::read(path) {
            Ok(bytes) => bytes,
            Err(e) => return json!({ "path": shown, "error": format!("cannot read the file: {e}") }),
        };
        let read = Instant::now();
        let loaded = black_box(canopener_eds::load(black_box(&bytes)));
        let done = Instant::now();
        total.push(done - start);
        parse.push(done - read);
        counts.get_or_insert_with(|| count(&loaded));
        bytes_len = bytes.len();
        // Freed outside the timed region, as the Python side drops its dictionary after timing.
        drop(loaded);
    }
    let counts = counts.unwrap_or(Counts {
        objects: 0,
        sub_objects: 0,
        diagnostics: 0,
        errors: 0,
    });
    json!({
        "path": shown,
        "bytes": bytes_len,
        "objects": counts.objects,
        "sub_objects": counts.sub_objects,
        "entries": counts.objects + counts.sub_objects,
        "diagnostics": counts.diagnostics,
        "error_diagnostics": counts.errors,
        "median_us": micros(median(&mut total)),
        "min_us": micros(total.iter().copied().min().unwrap_or_default()),
        "median_parse_us": micros(median(&mut parse)),
    })
}

/// The median of the samples (the mean of the middle two for an even count); zero for none.
fn median(samples: &mut [Duration]) -> Duration {
    samples.sort_unstable();
    let mid = samples.len() / 2;
    match (
        samples.len() % 2,
        samples.get(mid.wrapping_sub(1)),
        samples.get(mid),
    ) {
        (0, Some(&low), Some(&high)) => (low + high) / 2,
        (_, _, Some(&middle)) => middle,
        _ => Duration::ZERO,
    }
}

fn micros(duration: Duration) -> f64 {
    // Nanosecond resolution kept: small files load in a few microseconds.
    duration.as_nanos() as f64 / 1000.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(list: &[&str]) -> Vec<String> {
        list.iter().map(|s| (*s).to_owned()).collect()
    }

    #[test]
    fn parses_repeat_and_files() {
        assert_eq!(
            Command::parse(&args(&["--repeat", "3", "a.eds", "b.dcf"])),
            Ok(Command::Time {
                repeat: 3,
                files: vec![PathBuf::from("a.eds"), PathBuf::from("b.dcf")]
            })
        );
        assert_eq!(
            Command::parse(&args(&["a.eds"])),
            Ok(Command::Time {
                repeat: DEFAULT_REPEAT,
                files: vec![PathBuf::from("a.eds")]
            })
        );
    }

    #[test]
    fn parses_generate() {
        assert_eq!(
            Command::parse(&args(&["--generate", "1000", "out.eds"])),
            Ok(Command::Generate {
                objects: 1000,
                out: PathBuf::from("out.eds")
            })
        );
    }

    #[test]
    fn rejects_bad_command_lines() {
        for bad in [
            &[][..],
            &["--repeat", "0", "a.eds"],
            &["--repeat", "x", "a.eds"],
            &["--repeat"],
            &["--generate", "0", "out.eds"],
            &["--generate", "100"],
            &["--generate", "100000000", "out.eds"],
            &["--generate", "10", "out.eds", "extra"],
            &["--frobnicate", "a.eds"],
        ] {
            assert!(Command::parse(&args(bad)).is_err(), "{bad:?} was accepted");
        }
    }

    #[test]
    fn median_of_odd_even_and_empty_sample_sets() {
        let ms = Duration::from_millis;
        assert_eq!(median(&mut [ms(5), ms(1), ms(3)]), ms(3));
        assert_eq!(median(&mut [ms(4), ms(1), ms(2), ms(100)]), ms(3));
        assert_eq!(median(&mut [ms(7)]), ms(7));
        assert_eq!(median(&mut []), Duration::ZERO);
    }

    #[test]
    fn times_a_generated_file_and_reports_its_counts() {
        let dir = std::env::temp_dir().join(format!("canopener-load-timing-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("synthetic_50.eds");
        let generated = generate(50, &path).unwrap();
        let timed = time_file(&path, 3);
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(generated["objects"], 50);
        assert_eq!(timed["objects"], 50);
        assert_eq!(timed["sub_objects"], generated["sub_objects"]);
        assert_eq!(timed["bytes"], generated["bytes"]);
        assert_eq!(timed["error_diagnostics"], 0);
        assert!(timed["median_us"].as_f64().unwrap() > 0.0);
        assert!(timed["min_us"].as_f64().unwrap() <= timed["median_us"].as_f64().unwrap());
    }

    #[test]
    fn an_unreadable_file_is_reported_not_fatal() {
        let timed = time_file(Path::new("/nonexistent/canopener/missing.eds"), 3);
        assert!(
            timed["error"].as_str().unwrap().contains("cannot read the file"),
            "{timed}"
        );
        assert!(timed.get("median_us").is_none());
    }
}

//! Runs the built-in checks over every EDS/DCF of a directory and prints how often each code fires,
//! with up to N examples per code, so severities can be reviewed against real vendor files.
//!
//! `cargo run -p canopener-check --example corpus_findings -- [DIR] [--code CODE] [--examples N]`
//! (DIR defaults to the whole EDS corpus: the vendored `corpus/eds`, plus the extended corpus when
//! present).

// This is a developer tool, not library code: it reads the corpus it reports on, so the
// workspace's sans-IO bans and its no-printing rule do not apply here.
#![allow(clippy::disallowed_methods, clippy::print_stdout, clippy::print_stderr)]

use std::collections::BTreeMap;
use std::path::PathBuf;

use canopener_check::Selection;
use canopener_testkit::corpus::{self, Kind};

fn main() {
    let mut dir: Option<PathBuf> = None;
    let mut only: Option<String> = None;
    let mut examples = 3usize;
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--code" => only = args.next(),
            "--examples" => examples = args.next().and_then(|n| n.parse().ok()).unwrap_or(3),
            other => dir = Some(PathBuf::from(other)),
        }
    }
    let paths: Vec<PathBuf> = match &dir {
        Some(dir) => corpus::files_in(dir, Kind::Eds),
        None => corpus::eds_files().into_iter().map(|file| file.path).collect(),
    };
    let mut by_code: BTreeMap<String, (usize, usize, Vec<String>)> = BTreeMap::new();
    let mut severities: BTreeMap<String, String> = BTreeMap::new();
    for path in &paths {
        let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let loaded = canopener_eds::load(&bytes);
        let name = path.file_name().and_then(|n| n.to_str());
        let found = canopener_check::check(&loaded, name, &Selection::default()).findings;
        let mut seen_here = std::collections::BTreeSet::new();
        for f in found {
            if only
                .as_deref()
                .is_some_and(|c| !c.eq_ignore_ascii_case(&f.diagnostic.code))
            {
                continue;
            }
            severities.insert(f.diagnostic.code.clone(), f.diagnostic.severity.to_string());
            let entry = by_code.entry(f.diagnostic.code.clone()).or_default();
            entry.0 += 1;
            if seen_here.insert(f.diagnostic.code.clone()) {
                entry.1 += 1;
            }
            if entry.2.len() < examples {
                entry.2.push(format!(
                    "{}:{}:{} [{}] {}",
                    name.unwrap_or("?"),
                    f.diagnostic.span.line,
                    f.diagnostic.span.column,
                    f.diagnostic.section.as_deref().unwrap_or("-"),
                    f.diagnostic.message
                ));
            }
        }
    }
    let source = dir.map_or_else(|| "the corpus".to_owned(), |dir| dir.display().to_string());
    println!("{} files in {source}", paths.len());
    for (code, (count, files, samples)) in &by_code {
        println!(
            "{code} {:<7} {count:>5} findings in {files:>3} files",
            severities[code]
        );
        for s in samples {
            println!("    {s}");
        }
    }
}

//! Runs a rule pack over every EDS/DCF of a directory and prints how often each rule fires, with
//! examples, and how long checking took, so a pack can be reviewed against real vendor files.
//!
//! `cargo run -p canopener-rules --example corpus_rules -- [DIR] [--pack PACK] [--code ID]
//! [--examples N] [--fixes]` (DIR defaults to the whole EDS corpus: the vendored `corpus/eds`, plus
//! the extended corpus when present; PACK to the shipped `packs/seed-paper.toml`).

// This is a developer tool, not library code: it reads the corpus it reports on, so the
// workspace's sans-IO bans and its no-printing rule do not apply here.
#![allow(clippy::disallowed_methods, clippy::print_stdout, clippy::print_stderr)]

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use canopener_check::{Context, Selection};
use canopener_testkit::corpus::{self, Kind};

fn main() {
    let root = env!("CARGO_MANIFEST_DIR");
    let mut dir: Option<PathBuf> = None;
    let mut pack_path = PathBuf::from(format!("{root}/packs/seed-paper.toml"));
    let mut only: Option<String> = None;
    let mut examples = 3usize;
    let mut show_fixes = false;
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--pack" => pack_path = args.next().map(PathBuf::from).unwrap_or(pack_path),
            "--code" => only = args.next(),
            "--examples" => examples = args.next().and_then(|n| n.parse().ok()).unwrap_or(3),
            "--fixes" => show_fixes = true,
            other => dir = Some(PathBuf::from(other)),
        }
    }
    let text = std::fs::read_to_string(&pack_path).unwrap_or_else(|e| panic!("{}: {e}", pack_path.display()));
    let pack = canopener_rules::parse_pack(&text, &pack_path.display().to_string())
        .unwrap_or_else(|e| panic!("{e}"));
    let paths: Vec<PathBuf> = match dir {
        Some(dir) => corpus::files_in(&dir, Kind::Eds),
        None => corpus::eds_files().into_iter().map(|file| file.path).collect(),
    };
    let selection = Selection {
        only: only.iter().cloned().collect(),
        ..Selection::default()
    };
    let mut by_code: BTreeMap<String, (usize, usize, Vec<String>)> = BTreeMap::new();
    let mut fix_count = 0usize;
    let mut checking = Duration::ZERO;
    let mut slowest = (Duration::ZERO, String::new());
    for path in &paths {
        let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let loaded = canopener_eds::load(&bytes);
        let name = path.file_name().and_then(|n| n.to_str());
        let cx = Context::new(&loaded, name);
        let start = Instant::now();
        let found = pack.check(&cx, &selection);
        let took = start.elapsed();
        checking += took;
        if took > slowest.0 {
            slowest = (took, name.unwrap_or("?").to_owned());
        }
        if show_fixes {
            for fix in pack.fixes(&cx, &selection) {
                fix_count += 1;
                if fix_count <= examples {
                    println!("fix {}: {} {}", name.unwrap_or("?"), fix.code, fix.description);
                }
            }
        }
        let mut seen_here = std::collections::BTreeSet::new();
        for f in found {
            let entry = by_code
                .entry(format!("{} ({})", f.diagnostic.code, f.diagnostic.severity))
                .or_default();
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
    for (code, (count, files, samples)) in &by_code {
        println!("{code}: {count} findings in {files} files");
        for s in samples {
            println!("    {s}");
        }
    }
    if show_fixes {
        println!("fixes: {fix_count}");
    }
    println!(
        "{} files, rules took {:.1} ms in all, slowest {:.1} ms ({})",
        paths.len(),
        checking.as_secs_f64() * 1000.0,
        slowest.0.as_secs_f64() * 1000.0,
        slowest.1
    );
}

//! Prints the loading diagnostics of EDS files: `cargo run -p canopener-eds --example diagnose -- FILE...`.

// This is a developer tool, not library code: it reads the files it diagnoses, so the
// workspace's sans-IO bans and its no-printing rule do not apply here.
#![allow(clippy::disallowed_methods, clippy::print_stdout, clippy::print_stderr)]

fn main() {
    for path in std::env::args().skip(1) {
        let bytes = match std::fs::read(&path) {
            Ok(bytes) => bytes,
            Err(e) => {
                eprintln!("{path}: {e}");
                continue;
            }
        };
        for d in canopener_eds::load(&bytes).diagnostics {
            println!("{path}:{d}");
        }
    }
}

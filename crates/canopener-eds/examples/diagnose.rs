//! Prints the loading diagnostics of EDS files: `cargo run -p canopener-eds --example diagnose -- FILE...`.

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

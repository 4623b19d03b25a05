//! Project automation: `cargo xtask <command>`.
//!
//! - `setup`: create `.venv` with the Python peers the interop tests talk to (python-can, canopen).
//! - `test`: `setup`, then run every test of the workspace with the venv's interpreter. This is the README's
//!   test command and exactly what CI runs after installing.
//! - `bench`: build release binaries and run the benchmark suite (hub throughput, latency, bus capacity,
//!   python-can through the hub), writing JSON lines to `bench-results/`.
//! - `fuzz`: run every fuzz target for a while with cargo-fuzz on the nightly toolchain (never in CI).

use std::env;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

use anyhow::{Context, Result, bail};

const USAGE: &str = "usage: cargo xtask <setup | test | bench | fuzz [SECONDS]>";

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("xtask: {err:#}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<()> {
    let args: Vec<String> = env::args().skip(1).collect();
    let root = workspace_root();
    match args.first().map(String::as_str) {
        Some("setup") => setup_python(&root).map(|_| ()),
        Some("test") => test(&root),
        Some("bench") => bench(&root, &args[1..]),
        Some("fuzz") => fuzz(&root, args.get(1).map(String::as_str)),
        _ => bail!("{USAGE}"),
    }
}

fn workspace_root() -> PathBuf {
    // CARGO_MANIFEST_DIR is `<root>/xtask`.
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."))
}

fn requirements(root: &Path) -> PathBuf {
    root.join("crates/canopener-cli/tests/python/requirements.txt")
}

/// Creates `.venv` (once) and installs the pinned requirements (pip skips what is already there).
/// Returns the venv's Python interpreter.
fn setup_python(root: &Path) -> Result<PathBuf> {
    let venv = root.join(".venv");
    let python = venv.join("bin/python");
    if !python.exists() {
        let host_python = env::var("PYTHON").unwrap_or_else(|_| "python3".to_owned());
        eprintln!("xtask: creating {} with {host_python}", venv.display());
        run_cmd(Command::new(&host_python).args(["-m", "venv"]).arg(&venv))
            .with_context(|| format!("could not create a Python venv with `{host_python} -m venv`; install Python 3.9+ with the venv module, or set PYTHON"))?;
    }
    let stamp = venv.join(".requirements-installed");
    let wanted = std::fs::read_to_string(requirements(root)).context("reading the Python requirements")?;
    let installed = std::fs::read_to_string(&stamp).unwrap_or_default();
    if wanted != installed {
        eprintln!(
            "xtask: installing Python peers from {}",
            requirements(root).display()
        );
        run_cmd(
            Command::new(&python)
                .args([
                    "-m",
                    "pip",
                    "install",
                    "--quiet",
                    "--disable-pip-version-check",
                    "-r",
                ])
                .arg(requirements(root)),
        )
        .context(
            "pip could not install the Python peers (python-can, canopen); check network access to PyPI",
        )?;
        std::fs::write(&stamp, wanted).context("writing the venv stamp")?;
    }
    Ok(python)
}

fn test(root: &Path) -> Result<()> {
    let python = setup_python(root)?;
    run_cmd(
        Command::new(cargo())
            .current_dir(root)
            .env("CANOPENER_PYTHON", &python)
            .args(["test", "--workspace", "--all-targets", "--locked"]),
    )?;
    // Doc tests are not part of `--all-targets`.
    run_cmd(
        Command::new(cargo())
            .current_dir(root)
            .args(["test", "--workspace", "--doc", "--locked"]),
    )
}

fn bench(root: &Path, rest: &[String]) -> Result<()> {
    let python = setup_python(root)?;
    let script = root.join("bench/run.sh");
    run_cmd(
        Command::new("bash")
            .arg(script)
            .args(rest)
            .current_dir(root)
            .env("CANOPENER_PYTHON", python),
    )
}

fn fuzz(root: &Path, seconds: Option<&str>) -> Result<()> {
    let seconds = seconds.unwrap_or("60");
    let list = nightly_cargo(root).args(["fuzz", "list"]).output().context(
        "running `rustup run nightly cargo fuzz list`; install cargo-fuzz with `cargo install cargo-fuzz`",
    )?;
    if !list.status.success() {
        bail!(
            "`cargo fuzz list` on nightly failed (install the nightly toolchain and `cargo install cargo-fuzz`): {}",
            String::from_utf8_lossy(&list.stderr)
        );
    }
    for target in String::from_utf8_lossy(&list.stdout)
        .lines()
        .map(str::trim)
        .filter(|t| !t.is_empty())
    {
        eprintln!("xtask: fuzzing {target} for {seconds} s");
        run_cmd(nightly_cargo(root).args([
            "fuzz",
            "run",
            target,
            "--",
            &format!("-max_total_time={seconds}"),
        ]))?;
    }
    Ok(())
}

/// `cargo` on the nightly toolchain in `fuzz/`. `cargo +nightly` only works through the rustup proxy, and
/// inside `cargo run` the `CARGO` variable points at the real cargo, so go through rustup explicitly.
fn nightly_cargo(root: &Path) -> Command {
    let mut command = Command::new("rustup");
    command
        .current_dir(root.join("fuzz"))
        .args(["run", "nightly", "cargo"]);
    command
}

fn cargo() -> String {
    env::var("CARGO").unwrap_or_else(|_| "cargo".to_owned())
}

fn run_cmd(cmd: &mut Command) -> Result<()> {
    let status = cmd.status().with_context(|| format!("could not start {cmd:?}"))?;
    if !status.success() {
        bail!("{cmd:?} failed with {status}");
    }
    Ok(())
}

//! Project automation: `cargo xtask <command>`.
//!
//! - `setup`: install what the tests need besides Rust: headless Chromium for the HTML report test (with the
//!   system package manager, when this user may), and `.venv` with the Python peers the interop tests talk
//!   to (python-can, canopen).
//! - `test`: `setup`, then run every test of the workspace with the venv's interpreter. This is the README's
//!   test command and exactly what CI runs.
//! - `bench`: build release binaries and run the benchmark suite (hub throughput, latency, bus capacity,
//!   python-can through the hub), writing JSON lines to `bench-results/`.
//! - `fuzz`: run every fuzz target for a while with cargo-fuzz on the nightly toolchain (never in CI).

// A developer tool run from a terminal: it reports on stdout and stderr.
#![allow(clippy::print_stdout, clippy::print_stderr)]

use std::env;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};

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
        Some("setup") => setup(&root).map(|_| ()),
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

/// Everything the tests need besides Rust; returns the venv's Python interpreter. The browser comes first:
/// it is the one step that may need the user, and it should say so before minutes of building.
fn setup(root: &Path) -> Result<PathBuf> {
    setup_browser()?;
    setup_python(root)
}

/// Where the report's browser test looks for Chromium (Debian's `chromium` package).
const CHROMIUM: &str = "/usr/bin/chromium";
/// Set to `1`, the browser tests skip, and setup does not ask for Chromium.
const SKIP_BROWSER: &str = "CANOPENER_SKIP_BROWSER_TESTS";
const INSTALL_HINT: &str = "sudo apt-get install -y chromium";

/// What this machine offers for getting Chromium.
#[derive(Debug, Clone, Copy)]
struct BrowserFacts {
    skipped: bool,
    present: bool,
    root: bool,
    passwordless_sudo: bool,
    apt: bool,
}

/// What setup does about Chromium.
#[derive(Debug, PartialEq, Eq)]
enum BrowserPlan {
    Nothing,
    /// `apt-get install`, through `sudo -n` unless this is root.
    Install {
        sudo: bool,
    },
    /// Stop: the tests would fail, and this user cannot install it.
    Stop(String),
}

fn browser_plan(facts: BrowserFacts) -> BrowserPlan {
    if facts.skipped || facts.present {
        return BrowserPlan::Nothing;
    }
    if facts.apt && (facts.root || facts.passwordless_sudo) {
        return BrowserPlan::Install { sudo: !facts.root };
    }
    let how = if facts.apt {
        format!("install it with `{INSTALL_HINT}`")
    } else {
        format!("install Chromium so that {CHROMIUM} exists (on Debian or Ubuntu: `{INSTALL_HINT}`)")
    };
    BrowserPlan::Stop(format!(
        "the HTML report test needs headless Chromium at {CHROMIUM}, and this user cannot install it \
         (not root, no passwordless sudo{}): {how}, or set {SKIP_BROWSER}=1 to skip the browser tests knowingly",
        if facts.apt { "" } else { ", no apt-get" }
    ))
}

fn setup_browser() -> Result<()> {
    let skipped = env::var(SKIP_BROWSER).is_ok_and(|value| value == "1");
    let present = Path::new(CHROMIUM).exists();
    let root = is_root();
    let facts = BrowserFacts {
        skipped,
        present,
        root,
        // Only asked when it matters: a sudo probe on every run would fill the auth log.
        passwordless_sudo: !(skipped || present || root)
            && succeeds(Command::new("sudo").args(["-n", "true"])),
        apt: Path::new("/usr/bin/apt-get").exists(),
    };
    if skipped && !present {
        eprintln!("xtask: {SKIP_BROWSER}=1: not installing Chromium; the browser tests will skip");
    }
    match browser_plan(facts) {
        BrowserPlan::Nothing => Ok(()),
        BrowserPlan::Stop(message) => bail!("{message}"),
        BrowserPlan::Install { sudo } => {
            eprintln!(
                "xtask: installing headless Chromium (Debian's chromium package) for the HTML report test"
            );
            run_cmd(&mut apt_get(sudo, &["update", "-qq"]))?;
            run_cmd(&mut apt_get(sudo, &["install", "-y", "-qq", "chromium"]))
                .with_context(|| format!("installing Chromium failed; try `{INSTALL_HINT}`"))?;
            if !Path::new(CHROMIUM).exists() {
                bail!("apt-get installed chromium, but {CHROMIUM} does not exist");
            }
            Ok(())
        }
    }
}

/// `apt-get ARGS`, non-interactive, as root or through `sudo -n` (which would drop an `env` setting).
fn apt_get(sudo: bool, args: &[&str]) -> Command {
    let mut command = if sudo {
        let mut command = Command::new("sudo");
        command.args(["-n", "env", "DEBIAN_FRONTEND=noninteractive", "apt-get"]);
        command
    } else {
        let mut command = Command::new("apt-get");
        command.env("DEBIAN_FRONTEND", "noninteractive");
        command
    };
    command.args(args);
    command
}

fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|out| out.status.success() && String::from_utf8_lossy(&out.stdout).trim() == "0")
}

/// Whether `command` runs and exits 0, with its output discarded.
fn succeeds(command: &mut Command) -> bool {
    command
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|status| status.success())
}

fn test(root: &Path) -> Result<()> {
    let python = setup(root)?;
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

#[cfg(test)]
mod tests {
    use super::*;

    const NOTHING_THERE: BrowserFacts = BrowserFacts {
        skipped: false,
        present: false,
        root: false,
        passwordless_sudo: false,
        apt: true,
    };

    #[test]
    fn a_present_or_knowingly_skipped_browser_needs_nothing() {
        let present = BrowserFacts {
            present: true,
            ..NOTHING_THERE
        };
        let skipped = BrowserFacts {
            skipped: true,
            ..NOTHING_THERE
        };
        assert_eq!(browser_plan(present), BrowserPlan::Nothing);
        assert_eq!(browser_plan(skipped), BrowserPlan::Nothing);
    }

    #[test]
    fn root_installs_directly_and_a_sudoer_through_sudo() {
        let root = BrowserFacts {
            root: true,
            passwordless_sudo: true,
            ..NOTHING_THERE
        };
        let sudoer = BrowserFacts {
            passwordless_sudo: true,
            ..NOTHING_THERE
        };
        assert_eq!(browser_plan(root), BrowserPlan::Install { sudo: false });
        assert_eq!(browser_plan(sudoer), BrowserPlan::Install { sudo: true });
    }

    #[test]
    fn a_user_who_cannot_install_is_told_the_command_and_the_way_to_skip() {
        let BrowserPlan::Stop(message) = browser_plan(NOTHING_THERE) else {
            panic!("expected a stop");
        };
        assert!(
            message.contains("`sudo apt-get install -y chromium`"),
            "{message}"
        );
        assert!(message.contains("CANOPENER_SKIP_BROWSER_TESTS=1"), "{message}");
        let no_apt = BrowserFacts {
            root: true,
            apt: false,
            ..NOTHING_THERE
        };
        let BrowserPlan::Stop(message) = browser_plan(no_apt) else {
            panic!("without apt-get there is nothing to install with");
        };
        assert!(message.contains("no apt-get"), "{message}");
        assert!(message.contains("/usr/bin/chromium exists"), "{message}");
    }
}

//! Runs the user's stimulus program (`canopener test --stimulus CMD`), the hook that changes a
//! device's inputs on a test rig.
//!
//! The contract (docs/conformance.md, "cia401"): `CMD` is a shell command line, run as
//! `sh -c 'CMD "$@"' canopener-stimulus ARG…`, so the arguments reach it as positional parameters
//! and are never parsed by a shell; exit status 0 means the input is applied, anything else (or
//! no exit within the timeout, after which the program is killed) means it is not, with the
//! program's standard error as the reason.

use std::io::Read;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// How long the program may run unless the caller says otherwise.
pub const DEFAULT_TIMEOUT: Duration = Duration::from_secs(10);

/// How much of the program's standard error a reason quotes.
const STDERR_LIMIT: usize = 400;

/// The user's program (see the [module docs](self)).
#[derive(Debug, Clone)]
pub struct StimulusProgram {
    command: String,
    timeout: Duration,
}

impl StimulusProgram {
    /// The shell command line `command`, killed after [`DEFAULT_TIMEOUT`].
    pub fn new(command: impl Into<String>) -> StimulusProgram {
        StimulusProgram {
            command: command.into(),
            timeout: DEFAULT_TIMEOUT,
        }
    }

    /// The same program killed after `timeout`.
    pub fn with_timeout(mut self, timeout: Duration) -> StimulusProgram {
        self.timeout = timeout;
        self
    }

    /// The command line as the user gave it.
    pub fn command(&self) -> &str {
        &self.command
    }

    /// Runs the program with `arguments`; `Err` says why the input may not be applied.
    pub fn run(&self, arguments: &[String]) -> Result<(), String> {
        let script = format!("{} \"$@\"", self.command);
        let mut child = Command::new("sh")
            .arg("-c")
            .arg(&script)
            .arg("canopener-stimulus")
            .args(arguments)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|err| format!("the stimulus `{}` could not be started: {err}", self.command))?;
        // A reader thread drains standard error, so a chatty program never blocks on a full pipe.
        let stderr = child.stderr.take().map(|mut pipe| {
            std::thread::spawn(move || {
                let mut text = String::new();
                let _ = pipe.read_to_string(&mut text);
                text
            })
        });
        let called = format!("`{} {}`", self.command, arguments.join(" "));
        let status = match wait(&mut child, self.timeout) {
            Ok(Some(status)) => status,
            Ok(None) => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(format!(
                    "the stimulus {called} did not finish within {} s and was killed",
                    self.timeout.as_secs_f64()
                ));
            }
            Err(err) => return Err(format!("the stimulus {called} could not be waited for: {err}")),
        };
        let stderr = stderr.and_then(|reader| reader.join().ok()).unwrap_or_default();
        if status.success() {
            return Ok(());
        }
        let said = stderr.trim();
        let said = match said.char_indices().nth(STDERR_LIMIT) {
            Some((cut, _)) => format!("{}…", &said[..cut]),
            None => said.to_owned(),
        };
        let code = status.code().map_or_else(
            || "was killed by a signal".to_owned(),
            |c| format!("exited with {c}"),
        );
        Err(if said.is_empty() {
            format!("the stimulus {called} {code}")
        } else {
            format!("the stimulus {called} {code}: {said}")
        })
    }
}

/// The child's exit status, or `None` when it is still running at `timeout`.
fn wait(child: &mut Child, timeout: Duration) -> std::io::Result<Option<std::process::ExitStatus>> {
    let deadline = Instant::now() + timeout;
    loop {
        if let Some(status) = child.try_wait()? {
            return Ok(Some(status));
        }
        if Instant::now() >= deadline {
            return Ok(None);
        }
        // Polling keeps this free of a process-wait crate; 2 ms is well below any input filter.
        std::thread::sleep(Duration::from_millis(2));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(list: &[&str]) -> Vec<String> {
        list.iter().map(|s| (*s).to_owned()).collect()
    }

    #[test]
    fn exit_zero_is_applied_and_the_arguments_arrive_unparsed() {
        // The arguments are positional parameters: a `;` in one is data, not a second command.
        let program = StimulusProgram::new(r#"f() { [ "$1 $2 $3" = "6000 1 0x5A;false" ]; }; f"#);
        assert_eq!(program.run(&args(&["6000", "1", "0x5A;false"])), Ok(()));
        assert!(program.run(&args(&["6000", "1", "0x5B"])).is_err());
    }

    #[test]
    fn a_failure_names_the_call_the_status_and_the_programs_stderr() {
        let program = StimulusProgram::new("echo 'rig offline' >&2; exit 3; :");
        let err = program.run(&args(&["6401", "1", "-5"])).unwrap_err();
        assert!(err.contains("6401 1 -5"), "{err}");
        assert!(err.contains("exited with 3"), "{err}");
        assert!(err.contains("rig offline"), "{err}");
    }

    #[test]
    fn a_program_that_hangs_is_killed_at_the_timeout() {
        let program = StimulusProgram::new("sleep 30;:").with_timeout(Duration::from_millis(200));
        let started = Instant::now();
        let err = program.run(&args(&["6000", "1", "0x01"])).unwrap_err();
        assert!(err.contains("killed"), "{err}");
        // Generous: a loaded machine may take a while to start `sh`, but nowhere near 30 s.
        assert!(started.elapsed() < Duration::from_secs(20));
    }

    #[test]
    fn a_missing_program_is_an_error_not_a_panic() {
        let program = StimulusProgram::new("/nonexistent/stimulus-program");
        let err = program.run(&args(&["6000", "1", "0x01"])).unwrap_err();
        assert!(err.contains("exited with 127"), "{err}");
    }
}

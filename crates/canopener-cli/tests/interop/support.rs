//! Process plumbing for the interop tests: our binary as a hub or monitor, Python peers from the venv, JSON
//! lines over stdio, and bounded waits so that a broken peer fails a test instead of hanging it.

use std::io::{BufRead, BufReader, Write};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::sync::mpsc::{self, Receiver};
use std::thread;
use std::time::{Duration, Instant};

pub(crate) fn canopener() -> Command {
    Command::new(env!("CARGO_BIN_EXE_canopener"))
}

pub(crate) use canopener_testkit::corpus::workspace_root;

pub(crate) fn script(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/python")
        .join(name)
}

/// One vendored EDS of the corpus by name (`corpus/eds`).
pub(crate) use canopener_testkit::corpus::eds as corpus_eds;

/// The venv interpreter with python-can and canopen, or `None` when the caller opted out explicitly.
///
/// A missing venv fails the test: an interop suite that silently passes without its peers proves nothing.
pub(crate) fn python() -> Option<PathBuf> {
    if std::env::var_os("CANOPENER_SKIP_INTEROP").is_some() {
        eprintln!("skipped: CANOPENER_SKIP_INTEROP is set, so the Python interop peers are not run");
        return None;
    }
    let python = std::env::var_os("CANOPENER_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace_root().join(".venv/bin/python"));
    assert!(
        python.exists(),
        "no Python interop environment at {}: run `cargo xtask setup` (or use `cargo xtask test`, which does), \
         or set CANOPENER_SKIP_INTEROP=1 to skip these tests knowingly",
        python.display()
    );
    Some(python)
}

/// A child process that is killed when dropped, with its stdout delivered line by line on a channel and its
/// stderr kept for failure messages.
pub(crate) struct Proc {
    pub(crate) name: String,
    child: Child,
    stdin: Option<ChildStdin>,
    lines: Receiver<String>,
    stderr: std::sync::Arc<std::sync::Mutex<String>>,
    stderr_reader: thread::JoinHandle<()>,
}

impl Proc {
    pub(crate) fn spawn(name: &str, mut command: Command) -> Proc {
        command
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let mut child = command
            .spawn()
            .unwrap_or_else(|err| panic!("cannot start {name}: {err}"));
        let stdout: ChildStdout = child.stdout.take().expect("stdout was piped");
        let (tx, lines) = mpsc::channel();
        thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        let stderr = std::sync::Arc::new(std::sync::Mutex::new(String::new()));
        let stderr_sink = std::sync::Arc::clone(&stderr);
        let child_stderr = child.stderr.take().expect("stderr was piped");
        let stderr_reader = thread::spawn(move || {
            for line in BufReader::new(child_stderr).lines().map_while(Result::ok) {
                if let Ok(mut text) = stderr_sink.lock() {
                    // Keep the tail only: a chatty peer must not eat the test's memory.
                    if text.len() > 64 * 1024 {
                        let cut = text.len() - 32 * 1024;
                        let cut = (cut..text.len())
                            .find(|idx| text.is_char_boundary(*idx))
                            .unwrap_or(0);
                        text.drain(..cut);
                    }
                    text.push_str(&line);
                    text.push('\n');
                }
            }
        });
        let stdin = child.stdin.take();
        Proc {
            name: name.to_owned(),
            child,
            stdin,
            lines,
            stderr,
            stderr_reader,
        }
    }

    /// The process id (for its CPU time in /proc).
    #[allow(
        dead_code,
        reason = "only the web tests of the cli suite read a process's CPU time"
    )]
    pub(crate) fn id(&self) -> u32 {
        self.child.id()
    }

    pub(crate) fn stderr(&self) -> String {
        self.stderr.lock().map(|text| text.clone()).unwrap_or_default()
    }

    /// The next stdout line, or a panic naming the process and its stderr after `timeout`.
    pub(crate) fn line(&mut self, timeout: Duration) -> String {
        match self.lines.recv_timeout(timeout) {
            Ok(line) => line,
            Err(_) => panic!(
                "{} printed no line within {timeout:?} (exit status {:?}); its stderr:\n{}",
                self.name,
                self.child.try_wait().ok().flatten(),
                self.stderr()
            ),
        }
    }

    /// The next stdout line that parses as JSON.
    pub(crate) fn json(&mut self, timeout: Duration) -> serde_json::Value {
        let deadline = Instant::now() + timeout;
        loop {
            let line = self.line(deadline.saturating_duration_since(Instant::now()));
            if let Ok(value) = serde_json::from_str(&line) {
                return value;
            }
        }
    }

    pub(crate) fn send_line(&mut self, text: &str) {
        let name = self.name.clone();
        let stdin = self
            .stdin
            .as_mut()
            .unwrap_or_else(|| panic!("{name}: stdin already closed"));
        writeln!(stdin, "{text}")
            .and_then(|()| stdin.flush())
            .unwrap_or_else(|err| panic!("cannot write to {name}: {err}; its stderr:\n{}", self.stderr()));
    }

    pub(crate) fn close_stdin(&mut self) {
        self.stdin = None;
    }

    /// Sends SIGINT, as Ctrl-C would, so the process can finish cleanly.
    pub(crate) fn interrupt(&mut self) {
        let status = Command::new("kill")
            .args(["-INT", &self.child.id().to_string()])
            .status();
        assert!(
            status.is_ok_and(|status| status.success()),
            "could not send SIGINT to {}",
            self.name
        );
    }

    /// Waits for the process to exit; kills it and panics after `timeout`.
    pub(crate) fn wait(&mut self, timeout: Duration) -> std::process::ExitStatus {
        let deadline = Instant::now() + timeout;
        loop {
            if let Some(status) = self.child.try_wait().expect("try_wait") {
                return status;
            }
            if Instant::now() >= deadline {
                let _ = self.child.kill();
                panic!(
                    "{} did not exit within {timeout:?}; its stderr:\n{}",
                    self.name,
                    self.stderr()
                );
            }
            thread::sleep(Duration::from_millis(20));
        }
    }

    /// The whole stderr of a process that has exited: the reader thread may still be copying the last
    /// lines when `wait` returns (under load it was, and a failure showed an empty stderr), so this
    /// waits up to 2 s for the pipe's end before taking what was read.
    pub(crate) fn stderr_after_exit(&self) -> String {
        let deadline = Instant::now() + Duration::from_secs(2);
        while !self.stderr_reader.is_finished() && Instant::now() < deadline {
            thread::sleep(Duration::from_millis(5));
        }
        self.stderr()
    }

    /// All remaining stdout lines after the process exits.
    pub(crate) fn remaining_lines(&mut self) -> Vec<String> {
        let mut lines = Vec::new();
        while let Ok(line) = self.lines.recv_timeout(Duration::from_secs(2)) {
            lines.push(line);
        }
        lines
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// `canopener bus serve` on an ephemeral port; the address comes from its first stdout line.
pub(crate) struct HubProc {
    /// Held, not read: the hub runs until this is dropped.
    _process: Proc,
    pub(crate) addr: SocketAddr,
}

impl HubProc {
    pub(crate) fn start() -> HubProc {
        let mut command = canopener();
        command.args(["bus", "serve", "--listen", "127.0.0.1:0", "--stats-every", "5s"]);
        let mut proc = Proc::spawn("canopener bus serve", command);
        let first = proc.line(Duration::from_secs(10));
        let addr = first
            .rsplit("socketcand://")
            .next()
            .and_then(|rest| rest.trim().parse().ok())
            .unwrap_or_else(|| panic!("unexpected first line from the hub: {first:?}"));
        HubProc { _process: proc, addr }
    }

    pub(crate) fn spec(&self, bus: &str) -> String {
        format!("socketcand://{}/{bus}", self.addr)
    }
}

/// Starts a Python peer script with arguments.
pub(crate) fn python_peer(python: &PathBuf, name: &str, args: &[String]) -> Proc {
    let mut command = Command::new(python);
    command.arg("-u").arg(script(name)).args(args);
    Proc::spawn(name, command)
}

/// python canopen's `LocalNode` (tests/python/co_local_node.py) on the hub's `can0` as node `node`,
/// started and booted; `extra` goes to the script (`--bare`: LocalNode without the peer's additions).
pub(crate) fn local_node(
    python: &PathBuf,
    hub: &HubProc,
    node: &str,
    eds: &std::path::Path,
    extra: &[&str],
) -> Proc {
    let mut args = vec![
        hub.addr.ip().to_string(),
        hub.addr.port().to_string(),
        "can0".to_owned(),
        node.to_owned(),
        eds.display().to_string(),
    ];
    args.extend(extra.iter().map(|arg| (*arg).to_owned()));
    let mut peer = python_peer(python, "co_local_node.py", &args);
    let ready = peer.json(Duration::from_secs(30));
    assert_eq!(
        ready["ready"], true,
        "the python LocalNode did not start: {ready}"
    );
    peer
}

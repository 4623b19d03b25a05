//! What the tests that run `canopener` against a hub share: commands on a bus, simulators and other
//! long-running commands in the background, and a test client on the hub that sends frames and waits for
//! the ones it expects.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Output, Stdio};
use std::time::{Duration, Instant};

use canopener_can::CanFrame;
use canopener_can::candump::parse_compact_frame;
use canopener_transport::{BusSpec, CanBus, open};
use serde_json::Value;

use crate::support::{HubProc, canopener};
use crate::{run, stderr, stdout};

/// Generous: the machine running the tests may be loaded.
pub(crate) const WAIT: Duration = Duration::from_secs(10);

/// A bus nobody listens on: argument errors must be found before the bus is opened.
pub(crate) const NO_BUS: &str = "socketcand://127.0.0.1:9/can0";

/// The checker's base device: CiA 401, vendor ABCh, product 401h, revision 10002h.
pub(crate) fn base_eds() -> PathBuf {
    PathBuf::from(canopener_testkit::fixture::BASE_EDS)
}

/// `canopener ARGS --bus BUS`.
pub(crate) fn run_on(bus: &str, args: &[&str]) -> Output {
    let mut all = args.to_vec();
    all.extend(["--bus", bus]);
    run(&all)
}

/// [`run_on`], which must exit with `code`.
pub(crate) fn run_exiting(bus: &str, args: &[&str], code: i32) -> Output {
    let output = run_on(bus, args);
    assert_eq!(
        output.status.code(),
        Some(code),
        "canopener {args:?} --bus {bus}\nstdout:\n{}\nstderr:\n{}",
        stdout(&output),
        stderr(&output)
    );
    output
}

/// The one JSON object a command printed.
pub(crate) fn json_of(output: &Output) -> Value {
    let text = stdout(output);
    serde_json::from_str(text.trim()).unwrap_or_else(|err| {
        panic!(
            "stdout is not one JSON object ({err}):\n{text}\nstderr:\n{}",
            stderr(output)
        )
    })
}

/// One JSON value a line, as `--format json` prints events.
pub(crate) fn json_lines(text: &str) -> Vec<Value> {
    text.lines()
        .map(|line| serde_json::from_str(line).unwrap_or_else(|err| panic!("{err}: {line}")))
        .collect()
}

/// A `canopener` child with stdout and stderr in files (no pipe to fill up, nothing to read while it
/// runs), killed when dropped unless it already ended.
pub(crate) struct Background {
    name: String,
    child: Child,
    stdout: PathBuf,
    stderr: PathBuf,
}

impl Background {
    /// `canopener ARGS`, its output in `dir` as `NAME.stdout` and `NAME.stderr`.
    pub(crate) fn spawn(dir: &Path, name: &str, args: &[&str]) -> Background {
        let stdout = dir.join(format!("{name}.stdout"));
        let stderr = dir.join(format!("{name}.stderr"));
        let child = canopener()
            .args(args)
            .env_remove("CANOPENER_BUS")
            .stdin(Stdio::null())
            .stdout(std::fs::File::create(&stdout).expect("stdout file"))
            .stderr(std::fs::File::create(&stderr).expect("stderr file"))
            .spawn()
            .unwrap_or_else(|err| panic!("cannot start canopener {args:?}: {err}"));
        Background {
            name: name.to_owned(),
            child,
            stdout,
            stderr,
        }
    }

    /// `canopener sim ARGS --bus <hub>`, named `name`.
    pub(crate) fn sim(hub: &HubProc, dir: &Path, name: &str, args: &[&str]) -> Background {
        let spec = hub.spec("can0");
        let mut all = vec!["sim"];
        all.extend_from_slice(args);
        all.extend(["--bus", &spec]);
        Background::spawn(dir, name, &all)
    }

    pub(crate) fn stdout(&self) -> String {
        std::fs::read_to_string(&self.stdout).unwrap_or_default()
    }

    pub(crate) fn stderr(&self) -> String {
        std::fs::read_to_string(&self.stderr).unwrap_or_default()
    }

    /// Its stderr under its name, for failure messages (e.g. as the context of [`expect_frame`]).
    pub(crate) fn report(&self) -> String {
        format!("{} stderr:\n{}", self.name, self.stderr())
    }

    /// Waits for the child to end by itself; fails the test after `timeout`.
    pub(crate) fn wait(&mut self, timeout: Duration) -> ExitStatus {
        let deadline = Instant::now() + timeout;
        loop {
            if let Some(status) = self.child.try_wait().expect("try_wait") {
                return status;
            }
            assert!(
                Instant::now() < deadline,
                "{} did not end within {timeout:?}; {}",
                self.name,
                self.report()
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// SIGTERM, as a service manager stops it, then its exit status.
    pub(crate) fn terminate(&mut self) -> ExitStatus {
        let status = Command::new("kill")
            .args(["-TERM", &self.child.id().to_string()])
            .status()
            .expect("run kill");
        assert!(status.success(), "kill -TERM {} failed", self.name);
        self.wait(WAIT)
    }

    pub(crate) fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for Background {
    fn drop(&mut self) {
        self.kill();
    }
}

/// A test client on the hub's bus `can0`.
pub(crate) fn client(hub: &HubProc) -> Box<dyn CanBus> {
    let spec = BusSpec::Socketcand {
        host: hub.addr.ip().to_string(),
        port: hub.addr.port(),
        bus: "can0".into(),
    };
    open(&spec).expect("test client connects to the hub")
}

/// Sends a frame in candump's compact form (e.g. `"605#4018100100000000"`).
pub(crate) fn send(bus: &mut dyn CanBus, text: &str) {
    bus.send(&parse_compact_frame(text).expect("frame"))
        .expect("send");
}

/// The first frame received within [`WAIT`] whose text starts with `prefix` (e.g. `"585#"`); on failure
/// the message ends with `context()`, say the stderr of the device that should have sent it.
pub(crate) fn expect_frame(bus: &mut dyn CanBus, prefix: &str, context: &dyn Fn() -> String) -> String {
    let deadline = Instant::now() + WAIT;
    let mut seen = Vec::new();
    while Instant::now() < deadline {
        if let Some(received) = bus.recv(Duration::from_millis(100)).expect("recv") {
            let text = CanFrame::to_string(&received.frame);
            if text.starts_with(prefix) {
                return text;
            }
            seen.push(text);
        }
    }
    let tail = &seen[seen.len().saturating_sub(20)..];
    panic!(
        "no frame {prefix}… within {WAIT:?}; last seen {tail:?}; {}",
        context()
    );
}

/// Sends the CiA 305 LSS request "identify non-configured remote slave" and returns every frame
/// received in the 300 ms after it.
pub(crate) fn identify_unconfigured(bus: &mut dyn CanBus) -> Vec<String> {
    send(bus, "7E5#4C00000000000000");
    let window = Instant::now() + Duration::from_millis(300);
    let mut frames = Vec::new();
    while let Some(wait) = window.checked_duration_since(Instant::now()) {
        if let Some(received) = bus.recv(wait).expect("recv") {
            frames.push(CanFrame::to_string(&received.frame));
        }
    }
    frames
}

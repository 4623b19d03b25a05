//! SDO transfers of one client over a [`Link`]: the loop shared by `sdo read|write|upload|download` and
//! `node info|dump`, the progress bar of long transfers, and the wording of SDO failures.
//!
//! The client core ([`SdoClient`], CiA 301 §7.2.4.3) times out on its own when the server stops
//! answering. The loop here adds a watchdog on top, so that even a core that stopped asking for time
//! cannot keep a command waiting: every drive of the core ends after at most twice the SDO timeout
//! plus [`WATCHDOG_SLACK`] without progress.

use canopener_can::Core;
use std::io::IsTerminal;
use std::time::Duration;

use canopener_master::sdo_client::{
    DownloadMode, Protocol, SdoClient, SdoClientError, SdoClientEvent, SdoTransferError, UploadMode,
};
use canopener_wire::abort;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::error::{CliError, CliResult};
use crate::master::args::MasterArgs;
use canopener_runtime::link::{BusLink, Ended, Flow, Link, drive};

use crate::master::link::open_link;

/// Added to the watchdog of one drive, for a loaded machine between the core's timeout and ours.
const WATCHDOG_SLACK: Duration = Duration::from_millis(500);

/// A finished transfer.
#[derive(Debug)]
pub(crate) struct Transfer {
    /// The value read (empty after a download).
    pub(crate) data: Vec<u8>,
    /// The protocol the transfer used.
    pub(crate) protocol: Protocol,
    /// From the first request sent to the last answer received.
    pub(crate) elapsed: Duration,
}

/// One bus link and the SDO client of one node's default channel (600h/580h + node-ID).
#[derive(Debug)]
pub(crate) struct SdoSession {
    link: BusLink,
    client: SdoClient,
    node: u8,
    timeout: Duration,
}

/// How a drive of the core ended.
enum Step {
    Progress(usize, Option<usize>),
    Finished(Result<(Vec<u8>, Protocol), SdoTransferError>),
}

impl SdoSession {
    /// Opens `--bus` for `command` and sets up the client of `node` with `--timeout`.
    pub(crate) fn open(master: &MasterArgs, node: u8, command: &str) -> CliResult<SdoSession> {
        let timeout = checked_timeout(master.timeout)?;
        let client = SdoClient::new(node)
            .map_err(|err| CliError::Usage(format!("{err}; give --node 1..127, e.g. --node 5")))?
            .with_timeout(timeout);
        let link = open_link(master.bus.spec.as_deref(), command)?;
        Ok(SdoSession {
            link,
            client,
            node,
            timeout,
        })
    }

    /// The node-ID of the server.
    pub(crate) fn node(&self) -> u8 {
        self.node
    }

    /// The bus link, for waiting on other traffic between transfers.
    pub(crate) fn link_mut(&mut self) -> &mut BusLink {
        &mut self.link
    }

    /// Reads `index`:`sub` (CiA 301 §7.2.4.3.6 or, with `UploadMode::Block`, §7.2.4.3.13).
    /// `progress` hears of segmented and block progress. The outer error is the bus failing or the
    /// user interrupting; the inner one is the device refusing or not answering.
    pub(crate) fn upload(
        &mut self,
        index: u16,
        sub: u8,
        mode: UploadMode,
        progress: &mut dyn FnMut(usize, Option<usize>),
    ) -> CliResult<Result<Transfer, SdoTransferError>> {
        let now = self.link.now();
        let started = self.client.upload(now, index, sub, mode);
        self.run(index, sub, started, progress)
    }

    /// Writes `data` to `index`:`sub` (CiA 301 §7.2.4.3.3, or §7.2.4.3.9 with `DownloadMode::Block`).
    pub(crate) fn download(
        &mut self,
        index: u16,
        sub: u8,
        data: Vec<u8>,
        mode: DownloadMode,
        progress: &mut dyn FnMut(usize, Option<usize>),
    ) -> CliResult<Result<Transfer, SdoTransferError>> {
        let now = self.link.now();
        let started = self.client.download(now, index, sub, data, mode);
        self.run(index, sub, started, progress)
    }

    fn run(
        &mut self,
        index: u16,
        sub: u8,
        started: Result<(), SdoClientError>,
        progress: &mut dyn FnMut(usize, Option<usize>),
    ) -> CliResult<Result<Transfer, SdoTransferError>> {
        started.map_err(|err| {
            CliError::Usage(format!(
                "node {}, {}: {err}",
                self.node,
                object_name(index, sub, None)
            ))
        })?;
        let start = self.link.now();
        loop {
            let watchdog = self.link.now() + self.timeout * 2 + WATCHDOG_SLACK;
            let step =
                drive::<_, _, _, CliError>(&mut self.link, &mut self.client, Some(watchdog), |_, event| {
                    Ok(match event {
                        SdoClientEvent::Progress { done, total } => Flow::Done(Step::Progress(done, total)),
                        SdoClientEvent::Uploaded { data, protocol, .. } => {
                            Flow::Done(Step::Finished(Ok((data, protocol))))
                        }
                        SdoClientEvent::Downloaded { protocol, .. } => {
                            Flow::Done(Step::Finished(Ok((Vec::new(), protocol))))
                        }
                        SdoClientEvent::Failed { error, .. } => Flow::Done(Step::Finished(Err(error))),
                    })
                })?;
            match step {
                Ok(Step::Progress(done, total)) => progress(done, total),
                Ok(Step::Finished(result)) => {
                    let elapsed = self.link.now().saturating_duration_since(start);
                    return Ok(result.map(|(data, protocol)| Transfer {
                        data,
                        protocol,
                        elapsed,
                    }));
                }
                Err(Ended::Deadline) => {
                    self.abort(abort::PROTOCOL_TIMED_OUT)?;
                    return Ok(Err(SdoTransferError::TimedOut {
                        waiting_for: "server's next answer",
                        after: self.timeout * 2 + WATCHDOG_SLACK,
                    }));
                }
                Err(Ended::Cancelled) => {
                    self.abort(abort::GENERAL_ERROR)?;
                    eprintln!(
                        "interrupted: the transfer of node {}, {} was aborted (0x08000000 sent to the device)",
                        self.node,
                        object_name(index, sub, None)
                    );
                    return Err(CliError::Exit(crate::error::exit_code::INTERRUPTED));
                }
            }
        }
    }

    /// Ends the running transfer with an abort frame and forgets its events.
    fn abort(&mut self, code: u32) -> CliResult {
        let now = self.link.now();
        self.client.abort(now, code);
        while let Some(frame) = self.client.poll_transmit() {
            self.link.send(&frame)?;
        }
        while self.client.poll_event().is_some() {}
        Ok(())
    }
}

/// Refuses `--timeout 0`: the client core reads zero as "wait forever", which a command must not do.
pub(crate) fn checked_timeout(timeout: Duration) -> CliResult<Duration> {
    if timeout.is_zero() {
        return Err(CliError::Usage(
            "--timeout must be longer than 0, e.g. --timeout 500ms".to_owned(),
        ));
    }
    Ok(timeout)
}

/// `1018h:01`, or `1018h:01 (Vendor-ID)` with a name.
pub(crate) fn object_name(index: u16, sub: u8, name: Option<&str>) -> String {
    match name.filter(|name| !name.is_empty()) {
        Some(name) => format!("{index:04X}h:{sub:02X} ({name})"),
        None => format!("{index:04X}h:{sub:02X}"),
    }
}

/// The error of a failed transfer, naming the node and the object (exit status 7).
pub(crate) fn device_error(
    node: u8,
    index: u16,
    sub: u8,
    name: Option<&str>,
    error: &SdoTransferError,
) -> CliError {
    CliError::Device(format!("node {node}, {}: {error}", object_name(index, sub, name)))
}

/// Whether an abort says the object or sub-index is not there (CiA 301 §7.2.4.3.17: 0602 0000h, 0609 0011h).
pub(crate) fn is_absent(error: &SdoTransferError) -> bool {
    matches!(
        error,
        SdoTransferError::AbortedByServer {
            code: abort::OBJECT_DOES_NOT_EXIST | abort::SUB_INDEX_DOES_NOT_EXIST
        }
    )
}

/// A progress bar for the bytes of one transfer on stderr, drawn only on a terminal.
#[derive(Debug)]
pub(crate) struct ByteProgress {
    bar: ProgressBar,
}

impl ByteProgress {
    /// A bar labelled `what` (e.g. "reading 2100h:00").
    pub(crate) fn new(what: &str) -> ByteProgress {
        let bar = if std::io::stderr().is_terminal() {
            ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr())
        } else {
            ProgressBar::hidden()
        };
        if let Ok(style) = ProgressStyle::with_template("{spinner} {msg} {bytes} {binary_bytes_per_sec}") {
            bar.set_style(style);
        }
        bar.set_message(what.to_owned());
        ByteProgress { bar }
    }

    /// Moves the bar to `done` of `total` bytes (a bar once the total is known, a counter before).
    pub(crate) fn update(&self, done: usize, total: Option<usize>) {
        if let Some(total) = total
            && self.bar.length().is_none()
        {
            self.bar.set_length(total as u64);
            if let Ok(style) = ProgressStyle::with_template(
                "{spinner} {msg} {bytes}/{total_bytes} {wide_bar} {binary_bytes_per_sec} {eta}",
            ) {
                self.bar.set_style(style);
            }
        }
        self.bar.set_position(done as u64);
    }

    /// Removes the bar.
    pub(crate) fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// Throughput in kB/s (1000 bytes), as the final lines of upload and download report it.
pub(crate) fn kbytes_per_s(bytes: usize, elapsed: Duration) -> f64 {
    let secs = elapsed.as_secs_f64();
    if secs <= 0.0 {
        return 0.0;
    }
    bytes as f64 / 1000.0 / secs
}

/// Milliseconds with a fraction, for messages and JSON.
pub(crate) fn millis(elapsed: Duration) -> f64 {
    (elapsed.as_secs_f64() * 1e6).round() / 1e3
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failures_name_the_node_the_object_and_the_abort_text() {
        let abort = SdoTransferError::AbortedByServer {
            code: abort::SUB_INDEX_DOES_NOT_EXIST,
        };
        let err = device_error(5, 0x1018, 5, None, &abort);
        assert_eq!(err.exit_code(), 7);
        assert_eq!(
            err.to_string(),
            "node 5, 1018h:05: SDO abort 0x06090011 from the server: Sub-index does not exist"
        );
        assert!(is_absent(&abort));
        let timeout = SdoTransferError::TimedOut {
            waiting_for: "initiate upload response",
            after: Duration::from_millis(300),
        };
        assert!(!is_absent(&timeout));
        let named = device_error(9, 0x1017, 0, Some("Producer heartbeat time"), &timeout).to_string();
        assert!(
            named
                .starts_with("node 9, 1017h:00 (Producer heartbeat time): timed out after 300ms waiting for"),
            "{named}"
        );
    }

    #[test]
    fn zero_timeouts_are_refused_with_an_example() {
        let err = checked_timeout(Duration::ZERO).unwrap_err();
        assert_eq!(err.exit_code(), 2);
        assert!(err.to_string().contains("e.g. --timeout 500ms"));
        assert_eq!(
            checked_timeout(Duration::from_millis(1)).unwrap(),
            Duration::from_millis(1)
        );
    }

    #[test]
    fn throughput_and_milliseconds() {
        assert_eq!(kbytes_per_s(10_000, Duration::from_secs(2)), 5.0);
        assert_eq!(kbytes_per_s(10, Duration::ZERO), 0.0);
        assert_eq!(millis(Duration::from_micros(1234)), 1.234);
    }
}

//! Blocking SDO transfers with one server over a [`Link`]: the one session every front end uses.
//!
//! The client core ([`SdoClient`], CiA 301 §7.2.4.3) times out on its own when the server stops
//! answering (0504 0000h). The session adds a watchdog on top, so that even a core that stopped asking
//! for time cannot keep a caller waiting: every stretch without progress ends after at most twice the
//! SDO timeout plus [`WATCHDOG_SLACK`]. A cancelled link aborts the running transfer on the bus
//! (0800 0000h), so the device does not wait for the rest of it.

use std::time::Duration;

use canopener_can::{Core, Instant};
use canopener_master::sdo_client::{
    DownloadMode, Protocol, SdoClient, SdoClientError, SdoClientEvent, SdoTransferError, UploadMode,
};
use canopener_wire::abort;

use crate::link::{Ended, Flow, Link, LinkError, drive, flush};

/// Added to the watchdog of one stretch of a transfer, for a loaded machine between the core's
/// timeout and ours.
pub const WATCHDOG_SLACK: Duration = Duration::from_millis(500);

/// A finished transfer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Transfer {
    /// The value read (empty after a download).
    pub data: Vec<u8>,
    /// The protocol the transfer used.
    pub protocol: Protocol,
    /// From the request to the last answer, on the link's clock.
    pub elapsed: Duration,
}

/// Why a transfer did not finish.
#[derive(Debug, thiserror::Error)]
pub enum SdoError {
    /// The server refused (an abort from either side) or did not answer in time.
    #[error(transparent)]
    Transfer(#[from] SdoTransferError),
    /// The link was cancelled; the running transfer was aborted on the bus with 0800 0000h.
    #[error("cancelled: the transfer of {index:04X}h:{sub:02X} was aborted (0x08000000 sent to the device)")]
    Cancelled {
        /// The object of the transfer.
        index: u16,
        /// Its sub-index.
        sub: u8,
    },
    /// The transfer could not start (index 0, a transfer already running, data too long, ...).
    #[error(transparent)]
    Start(#[from] SdoClientError),
    /// The bus failed.
    #[error(transparent)]
    Link(#[from] LinkError),
}

impl SdoError {
    /// The transfer error, when the device refused or stayed silent.
    pub fn transfer(&self) -> Option<&SdoTransferError> {
        match self {
            SdoError::Transfer(error) => Some(error),
            _ => None,
        }
    }
}

/// Why a session could not be set up.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SessionError {
    /// The node-ID has no default SDO channel.
    #[error(transparent)]
    Client(#[from] SdoClientError),
    /// A timeout of zero would let the client wait forever.
    #[error("an SDO timeout of 0 would wait forever; give one longer than 0, e.g. 500ms")]
    ZeroTimeout,
}

/// How a transfer is progressing: bytes done and, once the server said, the total.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Progress {
    /// Bytes transferred so far.
    pub done: usize,
    /// The size of the value, once known.
    pub total: Option<usize>,
}

/// The SDO client of one node's default channel (600h/580h + node-ID) on a link.
#[derive(Debug)]
pub struct SdoSession<L: Link> {
    link: L,
    client: SdoClient,
    node: u8,
    timeout: Duration,
}

impl<L: Link> SdoSession<L> {
    /// A session with node `node` (1..=127) whose transfers time out after `timeout` without an answer.
    pub fn new(link: L, node: u8, timeout: Duration) -> Result<SdoSession<L>, SessionError> {
        if timeout.is_zero() {
            return Err(SessionError::ZeroTimeout);
        }
        let client = SdoClient::new(node)?.with_timeout(timeout);
        Ok(SdoSession {
            link,
            client,
            node,
            timeout,
        })
    }

    /// The session with its client set up by `configure` (CRC offered in block transfers, block size,
    /// protocol switch threshold, short frames), for callers that need a particular client; the
    /// session's timeout stays.
    pub fn configure(mut self, configure: impl FnOnce(SdoClient) -> SdoClient) -> SdoSession<L> {
        self.client = configure(self.client.clone()).with_timeout(self.timeout);
        self
    }

    /// Whether the block transfers that follow offer (and, when the server offers it too, check)
    /// the CRC: the `cc` flag of CiA 301 §7.2.4.3.9 and §7.2.4.3.13, on by default. Unlike
    /// [`SdoSession::configure`] this keeps the session, so a tester can ask for one block transfer
    /// without CRC (as the CCT's SDO 19-21 do) and switch back.
    pub fn set_block_crc(&mut self, crc: bool) {
        self.client = self.client.clone().with_crc(crc);
    }

    /// The server's node-ID.
    pub fn node(&self) -> u8 {
        self.node
    }

    /// The SDO timeout.
    pub fn timeout(&self) -> Duration {
        self.timeout
    }

    /// The link, for looking at it between transfers.
    pub fn link(&self) -> &L {
        &self.link
    }

    /// The link, for other traffic between transfers.
    pub fn link_mut(&mut self) -> &mut L {
        &mut self.link
    }

    /// The link, for what comes after the SDO transfers.
    pub fn into_link(self) -> L {
        self.link
    }

    /// Reads `index`:`sub` (CiA 301 §7.2.4.3.6 or, with [`UploadMode::Block`], §7.2.4.3.13), telling
    /// `progress` how segmented and block transfers advance.
    pub fn upload(
        &mut self,
        index: u16,
        sub: u8,
        mode: UploadMode,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<Transfer, SdoError> {
        let now = self.link.now();
        self.client.upload(now, index, sub, mode)?;
        self.run(index, sub, progress)
    }

    /// Writes `data` to `index`:`sub` (CiA 301 §7.2.4.3.3, §7.2.4.3.9 with [`DownloadMode::Block`]).
    pub fn download(
        &mut self,
        index: u16,
        sub: u8,
        data: Vec<u8>,
        mode: DownloadMode,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<Transfer, SdoError> {
        let now = self.link.now();
        self.client.download(now, index, sub, data, mode)?;
        self.run(index, sub, progress)
    }

    /// Reads `index`:`sub` with an initiate SDO upload and returns the value.
    pub fn read(&mut self, index: u16, sub: u8) -> Result<Vec<u8>, SdoError> {
        self.upload(index, sub, UploadMode::Normal, &mut |_| {})
            .map(|transfer| transfer.data)
    }

    /// Writes `data` to `index`:`sub`, expedited for up to 4 bytes, else segmented.
    pub fn write(&mut self, index: u16, sub: u8, data: Vec<u8>) -> Result<(), SdoError> {
        self.download(index, sub, data, DownloadMode::Auto, &mut |_| {})
            .map(drop)
    }

    fn run(&mut self, index: u16, sub: u8, progress: &mut dyn FnMut(Progress)) -> Result<Transfer, SdoError> {
        enum Step {
            Progress(Progress),
            Finished(Result<(Vec<u8>, Protocol), SdoTransferError>),
        }
        let start = self.link.now();
        let patience = self.timeout.saturating_mul(2) + WATCHDOG_SLACK;
        loop {
            let watchdog = self.link.now() + patience;
            let step = drive(
                &mut self.link,
                &mut self.client,
                Some(watchdog),
                |_, event| -> Result<_, LinkError> {
                    Ok(match event {
                        SdoClientEvent::Progress { done, total } => {
                            Flow::Done(Step::Progress(Progress { done, total }))
                        }
                        SdoClientEvent::Uploaded { data, protocol, .. } => {
                            Flow::Done(Step::Finished(Ok((data, protocol))))
                        }
                        SdoClientEvent::Downloaded { protocol, .. } => {
                            Flow::Done(Step::Finished(Ok((Vec::new(), protocol))))
                        }
                        SdoClientEvent::Failed { error, .. } => Flow::Done(Step::Finished(Err(error))),
                    })
                },
            )?;
            match step {
                Ok(Step::Progress(update)) => progress(update),
                Ok(Step::Finished(result)) => {
                    let (data, protocol) = result?;
                    return Ok(Transfer {
                        data,
                        protocol,
                        elapsed: self.link.now().saturating_duration_since(start),
                    });
                }
                Err(Ended::Deadline) => {
                    self.abort(abort::PROTOCOL_TIMED_OUT)?;
                    return Err(SdoTransferError::TimedOut {
                        waiting_for: "server's next answer",
                        after: patience,
                    }
                    .into());
                }
                Err(Ended::Cancelled) => {
                    self.abort(abort::GENERAL_ERROR)?;
                    return Err(SdoError::Cancelled { index, sub });
                }
            }
        }
    }

    /// Ends the running transfer with an abort frame and forgets its events.
    fn abort(&mut self, code: u32) -> Result<(), LinkError> {
        let now: Instant = self.link.now();
        self.client.abort(now, code);
        flush(&mut self.link, &mut self.client)?;
        while self.client.poll_event().is_some() {}
        Ok(())
    }
}

//! What a test works with: SDO transfers, raw frames, NMT commands and listening on the bus, all
//! through the recorded link, and the list of values to write back when the test ends.

use std::collections::BTreeMap;
use std::time::Duration;

use canopener_can::{CanFrame, CanId, Instant, StandardId};
use canopener_link::link::{Link, Timestamps};
use canopener_link::nmt_command;
use canopener_link::sdo_session::{SdoError, SdoSession};
use canopener_master::nmt_master::NmtTarget;
use canopener_master::sdo_client::{DownloadMode, SdoTransferError, UploadMode};
use canopener_wire::{NmtCommand, NodeId};

use crate::device_model::DeviceModel;
use crate::finding::Stop;
use crate::junk::{self, Junk};
use crate::model::{Direction, Measurement};
use crate::performance::Performance;
use crate::recorder::{Logged, Recorder};
use crate::requirements::code_meaning;
use crate::stimulus::{Hook, InputChange};

/// How a device answered an SDO request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Reply {
    /// The transfer completed: the value read (empty after a download).
    Done(Vec<u8>),
    /// The device aborted the transfer with this code.
    Refused(u32),
    /// The device did not answer in time.
    Silent,
    /// A raw request got this frame, which is no abort.
    Frame(Vec<u8>),
    /// The device broke the protocol (the reason says how); the tester aborted the transfer
    /// unless `code` is 0.
    Broken {
        /// The code the tester sent (0: none).
        code: u32,
        /// What was wrong.
        reason: String,
    },
}

impl Reply {
    /// The answer as an analysis states it.
    pub fn describe(&self) -> String {
        match self {
            Reply::Done(data) if data.is_empty() => "the transfer was confirmed".to_owned(),
            Reply::Done(data) => format!("the value {}", hex(data)),
            Reply::Refused(code) => format!("abort {}", code_meaning(*code)),
            Reply::Silent => "no answer within the SDO timeout".to_owned(),
            Reply::Frame(data) => format!("the frame {}", hex(data)),
            Reply::Broken { code: 0, reason } => format!("a protocol error: {reason}"),
            Reply::Broken { code, reason } => {
                format!(
                    "a protocol error; the tester aborted with {}: {reason}",
                    code_meaning(*code)
                )
            }
        }
    }
}

impl Reply {
    /// The answer to a raw SDO request ([`Ctx::raw_sdo`]): an abort frame is a refusal with its code.
    pub fn of_raw(answer: Option<Vec<u8>>) -> Reply {
        match answer {
            Some(data) if let [0x80, _, _, _, c0, c1, c2, c3] = *data.as_slice() => {
                Reply::Refused(u32::from_le_bytes([c0, c1, c2, c3]))
            }
            Some(data) => Reply::Frame(data),
            None => Reply::Silent,
        }
    }
}

/// `00 1F 02`: bytes as the logs show them.
pub fn hex(data: &[u8]) -> String {
    if data.is_empty() {
        return "(no bytes)".to_owned();
    }
    data.iter()
        .map(|b| format!("{b:02X}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The bytes of the first of `frames`, as [`hex`] shows them; `(no frame)` when there is none.
pub fn first_hex(frames: &[Logged]) -> String {
    frames
        .first()
        .map_or_else(|| "(no frame)".to_owned(), |first| hex(first.frame.data()))
}

/// How often a value is written back while the answers break the SDO protocol.
const WRITE_BACK_TRIES: usize = 3;
/// Whether writing `value` to `index`:`sub` switches a timed service off: the SYNC period 1006h, the
/// heartbeat producer time 1017h, the guard time 100Ch or a heartbeat consumer entry 1016h:xx set to
/// 0 (no monitoring, no production).
pub fn stops_a_timer(index: u16, sub: u8, value: &[u8]) -> bool {
    let zero = value.iter().all(|b| *b == 0);
    match index {
        0x1006 | 0x1017 | 0x100C => sub == 0 && zero,
        // A consumer entry is off when its time (bits 15..0) or node-ID (bits 23..16) is 0.
        0x1016 => sub != 0 && matches!(value, [t0, t1, n, _] if (*t0 == 0 && *t1 == 0) || *n == 0),
        _ => false,
    }
}

/// One value to write back.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Restore {
    index: u16,
    sub: u8,
    value: Vec<u8>,
    /// The device confirmed the write (else its answer broke the protocol: it may not have
    /// taken the value, and then refuses the write-back too).
    confirmed: bool,
}

/// The tester's side of one test (see the [module docs](self)).
pub struct Ctx<'r, 'l> {
    sdo: SdoSession<&'r mut Recorder<'l>>,
    model: &'r DeviceModel,
    eds_errors: Option<&'r [String]>,
    restores: Vec<Restore>,
    measurements: BTreeMap<String, Measurement>,
    performed: Vec<String>,
    performance: &'r Performance,
    stimulus: Option<Hook<'r>>,
    broken: Vec<Junk>,
    unanswered: Vec<String>,
    no_criterion: bool,
}

/// The settings of a run that does not choose its own.
static DEFAULT_PERFORMANCE: Performance = Performance::DEFAULT;

impl std::fmt::Debug for Ctx<'_, '_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Ctx")
            .field("node", &self.sdo.node())
            .field("restores", &self.restores)
            .finish()
    }
}

impl<'r, 'l> Ctx<'r, 'l> {
    /// A test's context on the session `sdo` with the device described by `model`; `eds_errors` are
    /// the errors canopener's EDS checks found in the file (`None` when it was not checked).
    pub fn new(
        sdo: SdoSession<&'r mut Recorder<'l>>,
        model: &'r DeviceModel,
        eds_errors: Option<&'r [String]>,
    ) -> Ctx<'r, 'l> {
        Ctx {
            sdo,
            model,
            eds_errors,
            restores: Vec::new(),
            measurements: BTreeMap::new(),
            performed: Vec::new(),
            performance: &DEFAULT_PERFORMANCE,
            stimulus: None,
            broken: Vec::new(),
            unanswered: Vec::new(),
            no_criterion: false,
        }
    }

    /// The same context with the user's stimulus hook (`--stimulus`).
    pub fn with_stimulus(mut self, stimulus: Option<Hook<'r>>) -> Ctx<'r, 'l> {
        self.stimulus = stimulus;
        self
    }

    /// Whether the user gave a stimulus hook.
    pub fn has_stimulus(&self) -> bool {
        self.stimulus.is_some()
    }

    /// Applies `change` through the stimulus hook, then listens for its settle time (the frames
    /// stay in the log, for [`Ctx::received_since`]). `Ok(Err(reason))` when there is no hook or
    /// the hook could not apply it.
    pub fn stimulate(&mut self, change: &InputChange) -> Result<Result<(), String>, Stop> {
        let Some(hook) = self.stimulus.as_mut() else {
            return Ok(Err("no stimulus hook was given (--stimulus)".to_owned()));
        };
        let settle = hook.settle;
        if let Err(reason) = hook.stimulus.apply(change) {
            return Ok(Err(reason));
        }
        self.listen(settle, |_| false)?;
        Ok(Ok(()))
    }

    /// The same context with the performance suite's criteria and repetitions.
    pub fn with_performance(mut self, performance: &'r Performance) -> Ctx<'r, 'l> {
        self.performance = performance;
        self
    }

    /// The performance suite's criteria and repetitions.
    pub fn performance(&self) -> &'r Performance {
        self.performance
    }

    /// Who stamps received frames, and how finely.
    pub fn timestamps(&self) -> Timestamps {
        self.link().timestamps()
    }

    /// What the EDS says.
    pub fn model(&self) -> &'r DeviceModel {
        self.model
    }

    /// The errors of canopener's EDS checks, when the file was checked.
    pub fn eds_errors(&self) -> Option<&'r [String]> {
        self.eds_errors
    }

    /// Whether the link was cancelled (Ctrl-C).
    pub fn link_cancelled(&self) -> bool {
        self.link().is_cancelled()
    }

    /// The node under test.
    pub fn node(&self) -> u8 {
        self.sdo.node()
    }

    /// The link's time.
    pub fn now(&self) -> Instant {
        self.link().now()
    }

    /// The SDO timeout.
    pub fn timeout(&self) -> Duration {
        self.sdo.timeout()
    }

    /// Reads `index`:`sub` with an initiate SDO upload.
    pub fn read(&mut self, index: u16, sub: u8) -> Result<Reply, Stop> {
        self.read_with(index, sub, UploadMode::Normal)
    }

    /// Reads `index`:`sub` in `mode`.
    pub fn read_with(&mut self, index: u16, sub: u8, mode: UploadMode) -> Result<Reply, Stop> {
        let mark = self.drain()?;
        let result = self.sdo.upload(index, sub, mode, &mut |_| {});
        self.reply(mark, (index, sub), result.map(|t| t.data))
    }

    /// Reads `index`:`sub` with a block upload, offering the CRC when `crc` (CiA 301 §7.2.4.3.13;
    /// the client checks it when the server offers it too). Later block transfers offer it again.
    pub fn read_block(&mut self, index: u16, sub: u8, crc: bool) -> Result<Reply, Stop> {
        self.sdo.set_block_crc(crc);
        let reply = self.read_with(index, sub, UploadMode::Block);
        self.sdo.set_block_crc(true);
        reply
    }

    /// Writes `data` to `index`:`sub` with a block download, with a CRC when `crc` (CiA 301
    /// §7.2.4.3.9; without, the end frame's CRC field is 0). Later block transfers use it again.
    pub fn write_block(&mut self, index: u16, sub: u8, data: Vec<u8>, crc: bool) -> Result<Reply, Stop> {
        self.sdo.set_block_crc(crc);
        let reply = self.write_with(index, sub, data, DownloadMode::Block);
        self.sdo.set_block_crc(true);
        reply
    }

    /// Writes `data` to `index`:`sub` without remembering the old value (for writes that must be
    /// refused, or that [`Ctx::modify`] already covers).
    pub fn write(&mut self, index: u16, sub: u8, data: Vec<u8>) -> Result<Reply, Stop> {
        self.write_with(index, sub, data, DownloadMode::Auto)
    }

    /// Writes `data` to `index`:`sub` in `mode`.
    pub fn write_with(
        &mut self,
        index: u16,
        sub: u8,
        data: Vec<u8>,
        mode: DownloadMode,
    ) -> Result<Reply, Stop> {
        let mark = self.drain()?;
        let result = self.sdo.download(index, sub, data, mode, &mut |_| {});
        self.reply(mark, (index, sub), result.map(|_| Vec::new()))
    }

    /// Reads `index`:`sub`, remembers its value to write back when the test ends, then writes
    /// `data`; a confirmed write (or one whose answer broke the protocol) is undone when the test
    /// ends. A value that cannot be read is not
    /// remembered (the write still goes out: the test then owns the consequence), except when the
    /// answer broke the protocol: then nothing is written, and that answer is the reply (a change
    /// nobody could undo would reach the tests that follow).
    pub fn modify(&mut self, index: u16, sub: u8, data: Vec<u8>) -> Result<Reply, Stop> {
        let old = self.read(index, sub)?;
        if let Reply::Broken { code, reason } = old {
            // Say which transfer broke: the request under test was never sent.
            return Ok(Reply::Broken {
                code,
                reason: format!(
                    "the upload of {index:04X}h:{sub:02X} that comes first (to write the value back after the test), so the download was not sent: {reason}"
                ),
            });
        }
        let reply = self.write(index, sub, data)?;
        // Only a confirmed write changed anything (a refused one is what many tests expect), or
        // one whose answer broke the protocol: the device may have taken it, and writing the old
        // value back costs nothing if it did not.
        if let (Reply::Done(old), Reply::Done(_) | Reply::Broken { .. }) = (old, &reply) {
            self.restores.push(Restore {
                index,
                sub,
                value: old,
                confirmed: matches!(reply, Reply::Done(_)),
            });
        }
        Ok(reply)
    }

    /// Writes back every value [`Ctx::modify`] changed, newest first (so a PDO's mapping is restored
    /// before its COB-ID enables it again), after first writing back, newest first, every value
    /// that switches a timed service off ([`stops_a_timer`]): CiA 301's rule for changing a running
    /// service (switch it off, change it, switch it on last) applied to the write-back, so that no
    /// service runs with half-restored parameters (a SYNC consumer with a period and no producer
    /// times out, EMCY 8100h on CANopenNode). Returns the entries that could not be written back.
    pub fn restore(&mut self) -> Result<Vec<String>, Stop> {
        let (first, rest): (Vec<Restore>, Vec<Restore>) = std::mem::take(&mut self.restores)
            .into_iter()
            .partition(|r| stops_a_timer(r.index, r.sub, &r.value));
        self.restores = rest;
        self.restores.extend(first);
        let mut left = Vec::new();
        while let Some(restore) = self.restores.pop() {
            let mut reply = self.write(restore.index, restore.sub, restore.value.clone())?;
            // An answer that broke the protocol says nothing about the write: try again.
            for _ in 1..WRITE_BACK_TRIES {
                let Reply::Broken { .. } = reply else { break };
                reply = self.write(restore.index, restore.sub, restore.value.clone())?;
            }
            match reply {
                Reply::Done(_) => {}
                // The unconfirmed write was refused as well: nothing changed.
                Reply::Refused(_) if !restore.confirmed => {}
                other => left.push(format!(
                    "{:04X}h:{:02X} (should be {}; writing it back got {})",
                    restore.index,
                    restore.sub,
                    hex(&restore.value),
                    other.describe()
                )),
            }
        }
        Ok(left)
    }

    /// Sends a raw SDO request (8 bytes on 600h + node-ID) and waits for the next frame on
    /// 580h + node-ID within the SDO timeout: for requests the SDO client would never make.
    pub fn raw_sdo(&mut self, request: [u8; 8]) -> Result<Option<Vec<u8>>, Stop> {
        let node = u16::from(self.node());
        self.drain()?;
        self.send(0x600 + node, &request)?;
        let response = self.id(0x580 + node);
        let deadline = self.now() + self.timeout();
        let frames = self.listen_until(
            deadline,
            |frame| frame.id() == response && !frame.is_remote(),
            true,
        )?;
        Ok(frames.first().map(|logged| logged.frame.data().to_vec()))
    }

    /// Sends a data frame on the standard CAN-ID `id`; data CAN cannot carry (more than 8 bytes)
    /// stops the test as inconclusive, not the run.
    pub fn send(&mut self, id: u16, data: &[u8]) -> Result<(), Stop> {
        let frame = CanFrame::new(self.id(id), data).map_err(|error| {
            Stop::Unsendable(format!(
                "the tester cannot send {} bytes on {id:#05X}: {error}",
                data.len()
            ))
        })?;
        self.send_frame(&frame)
    }

    /// Sends a remote frame on the standard CAN-ID `id` with `dlc`.
    pub fn send_remote(&mut self, id: u16, dlc: u8) -> Result<(), Stop> {
        let frame = CanFrame::remote(self.id(id), dlc).map_err(|error| {
            Stop::Unsendable(format!(
                "the tester cannot send a remote frame with DLC {dlc} on {id:#05X}: {error}"
            ))
        })?;
        self.send_frame(&frame)
    }

    /// Sends an NMT command to the node under test, or to all nodes.
    pub fn nmt(&mut self, command: NmtCommand, broadcast: bool) -> Result<(), Stop> {
        let target = if broadcast {
            NmtTarget::All
        } else {
            let node = self.node();
            NmtTarget::Node(
                NodeId::new(node)
                    .ok_or_else(|| Stop::Unsendable(format!("node-ID {node} cannot be addressed by NMT")))?,
            )
        };
        nmt_command::send(self.link_mut(), command, target)?;
        self.check_cancel()
    }

    /// Every frame received within `duration` that `keep` accepts.
    pub fn listen(
        &mut self,
        duration: Duration,
        keep: impl Fn(&CanFrame) -> bool,
    ) -> Result<Vec<Logged>, Stop> {
        let deadline = self.now() + duration;
        self.listen_until(deadline, keep, false)
    }

    /// The first frame within `duration` that `keep` accepts; returns as soon as it arrives.
    pub fn wait_for(
        &mut self,
        duration: Duration,
        keep: impl Fn(&CanFrame) -> bool,
    ) -> Result<Option<Logged>, Stop> {
        let deadline = self.now() + duration;
        Ok(self.listen_until(deadline, keep, true)?.into_iter().next())
    }

    /// The frames received since the mark [`Ctx::mark`] returned.
    pub fn received_since(&self, mark: usize) -> Vec<Logged> {
        self.link()
            .since(mark)
            .iter()
            .filter(|l| l.dir == Direction::Rx)
            .copied()
            .collect()
    }

    /// A mark in the telegram log.
    pub fn mark(&self) -> usize {
        self.link().mark()
    }

    /// Records a measurement under `name`.
    pub fn measure(&mut self, name: &str, measurement: Measurement) {
        self.measurements.insert(name.to_owned(), measurement);
    }

    /// The measurements taken.
    pub fn take_measurements(&mut self) -> BTreeMap<String, Measurement> {
        std::mem::take(&mut self.measurements)
    }

    /// The SDO requests of the test that got no answer within the SDO timeout
    /// (`SDO request for 1017h:00`).
    pub fn unanswered(&self) -> &[String] {
        &self.unanswered
    }

    /// The junk the test met so far ([`crate::junk`]): answers that broke an SDO transfer, and
    /// frames of the wrong length or state on the device's answer CAN-IDs, in order.
    pub fn junk(&self) -> Vec<Junk> {
        let received: Vec<Logged> = self.received_since(0);
        let mut found = junk::scan(
            self.node(),
            received.iter().map(|logged| (logged.link_time, &logged.frame)),
        );
        for broken in &self.broken {
            if !found.iter().any(|j| j.at == broken.at && j.frame == broken.frame) {
                found.push(broken.clone());
            }
        }
        found.sort_by_key(|j| j.at);
        found
    }

    /// Says that a measurement of the test was judged against no criterion: its `pass` is a
    /// measurement, not a conformance pass, and the summaries count it apart.
    pub fn judged_without_criterion(&mut self) {
        self.no_criterion = true;
    }

    /// Whether [`Ctx::judged_without_criterion`] was called.
    pub fn without_criterion(&self) -> bool {
        self.no_criterion
    }

    /// Records that the check of the CCT case `case` (`"SDO 19"`, as the case list names it) was
    /// performed: call it where that step has run and its answer was judged, not before (the
    /// report's `performed` then says what a run really checked; `tests/simulated.rs` holds the
    /// coverage table to it). A case recorded twice is listed once.
    pub fn performed(&mut self, case: &str) {
        if !self.performed.iter().any(|c| c == case) {
            self.performed.push(case.to_owned());
        }
    }

    /// The CCT cases performed so far, in order.
    pub fn take_performed(&mut self) -> Vec<String> {
        std::mem::take(&mut self.performed)
    }

    /// The standard CAN-ID `raw` (callers pass 11-bit values).
    pub fn id(&self, raw: u16) -> CanId {
        CanId::Standard(StandardId::new(raw & 0x7FF).unwrap_or(StandardId::ZERO))
    }

    fn listen_until(
        &mut self,
        deadline: Instant,
        keep: impl Fn(&CanFrame) -> bool,
        first_only: bool,
    ) -> Result<Vec<Logged>, Stop> {
        let mut kept = Vec::new();
        loop {
            let link = self.link_mut();
            let Some(stamped) = link.recv_stamped_until(deadline)? else {
                break;
            };
            if keep(&stamped.frame) {
                kept.push(Logged {
                    at: stamped.bus_time,
                    link_time: stamped.at,
                    dir: Direction::Rx,
                    frame: stamped.frame,
                });
                if first_only {
                    break;
                }
            }
        }
        self.check_cancel()?;
        Ok(kept)
    }

    /// Takes the frames that arrived before a request (late answers to an earlier one, or a second
    /// node's): they are logged, and no answer to the request that follows. Returns the mark after
    /// them.
    /// No cancellation point: the transfer that follows ends itself on the bus when cancelled.
    fn drain(&mut self) -> Result<usize, Stop> {
        let now = self.now();
        while self.link_mut().recv_stamped_until(now)?.is_some() {}
        Ok(self.mark())
    }

    /// The reply of the transfer of `entry` that started at `mark`. When the tester's client
    /// aborted it, the device's answer that made it do so is named in the reason and kept as junk;
    /// so is an abort that names another entry than the transfer's (CiA 301 §7.2.4.3.17: the abort
    /// carries the transfer's multiplexer), which is no refusal of this transfer.
    fn reply(
        &mut self,
        mark: usize,
        entry: (u16, u8),
        result: Result<Vec<u8>, SdoError>,
    ) -> Result<Reply, Stop> {
        let reply = reply_of(result)?;
        if reply == Reply::Silent {
            self.unanswered
                .push(format!("SDO request for {:04X}h:{:02X}", entry.0, entry.1));
        }
        let response = self.id(0x580 + u16::from(self.node()));
        let answer = self
            .link()
            .since(mark)
            .iter()
            .rev()
            .find(|l| l.dir == Direction::Rx && l.frame.id() == response && !l.frame.is_remote())
            .copied();
        let (code, reason) = match (reply, answer) {
            (Reply::Broken { code, reason }, Some(_)) => (code, reason),
            (Reply::Refused(code), Some(abort)) if !names(&abort.frame, entry) => (
                0,
                format!(
                    "an abort ({}) that names another entry than {:04X}h:{:02X}",
                    code_meaning(code),
                    entry.0,
                    entry.1
                ),
            ),
            (reply, _) => return Ok(reply),
        };
        let Some(answer) = answer else {
            return Ok(Reply::Broken { code, reason });
        };
        let text = answer.frame.to_string();
        self.broken.push(Junk {
            at: answer.link_time,
            frame: answer.frame,
            why: reason.clone(),
        });
        let reason = if reason.contains(&text) {
            reason
        } else {
            format!("{reason} (the answer {text})")
        };
        Ok(Reply::Broken { code, reason })
    }

    fn send_frame(&mut self, frame: &CanFrame) -> Result<(), Stop> {
        self.link_mut().send(frame)?;
        self.check_cancel()
    }

    fn check_cancel(&self) -> Result<(), Stop> {
        if self.link().is_cancelled() {
            Err(Stop::Cancelled)
        } else {
            Ok(())
        }
    }

    fn link(&self) -> &Recorder<'l> {
        self.sdo.link()
    }

    fn link_mut(&mut self) -> &mut Recorder<'l> {
        self.sdo.link_mut()
    }
}

/// Whether the SDO frame `frame` carries the multiplexer `entry` (bytes 1–3).
fn names(frame: &CanFrame, entry: (u16, u8)) -> bool {
    let [lo, hi] = entry.0.to_le_bytes();
    frame.data().get(1..4) == Some(&[lo, hi, entry.1][..])
}

fn reply_of(result: Result<Vec<u8>, SdoError>) -> Result<Reply, Stop> {
    match result {
        Ok(data) => Ok(Reply::Done(data)),
        Err(SdoError::Transfer(SdoTransferError::AbortedByServer { code })) => Ok(Reply::Refused(code)),
        Err(SdoError::Transfer(SdoTransferError::TimedOut { .. })) => Ok(Reply::Silent),
        Err(SdoError::Transfer(SdoTransferError::AbortedByClient { code, reason })) => {
            Ok(Reply::Broken { code, reason })
        }
        Err(SdoError::Cancelled { .. }) => Err(Stop::Cancelled),
        Err(SdoError::Link(error)) => Err(Stop::Link(error)),
        // The tests only start transfers the client accepts; one it refuses is the tester's bug,
        // reported as a broken exchange rather than a panic.
        Err(SdoError::Start(error)) => Ok(Reply::Broken {
            code: 0,
            reason: error.to_string(),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_values_that_switch_a_timed_service_off_are_known() {
        assert!(stops_a_timer(0x1006, 0, &[0; 4]));
        assert!(!stops_a_timer(0x1006, 0, &10_000u32.to_le_bytes()));
        assert!(stops_a_timer(0x1017, 0, &[0, 0]));
        assert!(stops_a_timer(0x100C, 0, &[0, 0]));
        // 1016h:01: node 6, 0 ms, or node 0: unused; node 6 with 250 ms: monitoring.
        assert!(stops_a_timer(0x1016, 1, &[0, 0, 6, 0]));
        assert!(stops_a_timer(0x1016, 1, &[0xFA, 0, 0, 0]));
        assert!(!stops_a_timer(0x1016, 1, &[0xFA, 0, 6, 0]));
        // 1005h without bit 30 makes a producer a consumer: not "off" while 1006h runs.
        assert!(!stops_a_timer(0x1005, 0, &0x80u32.to_le_bytes()));
        assert!(!stops_a_timer(0x1800, 5, &[0, 0]));
    }
}

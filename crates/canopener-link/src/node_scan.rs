//! Which node-IDs answer on a bus: every node asked for 1000h (device type, CiA 301 §7.5.2.1) and,
//! if it answered, its identity 1018h sub 1 to 4, by [`Fleet`], many SDO clients at once.

use std::time::Duration;

use canopener_master::node_scan::{Fleet, IDENTITY, ScanResult};
use canopener_master::sdo_client::SdoClientError;

use crate::link::{Ended, Flow, Link, LinkError, drive};
use crate::sdo_session::SessionError;

/// Added per round to the scan's deadline, for a loaded machine.
const ROUND_SLACK: Duration = Duration::from_millis(500);

/// What a scan heard.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Scan {
    /// Every upload's result, in the order they ended.
    pub results: Vec<ScanResult>,
    /// From the first request to the end, on the link's clock.
    pub elapsed: Duration,
    /// `None` when every node was asked everything; else why the scan ended early.
    pub ended: Option<Ended>,
}

/// Why a scan could not run.
#[derive(Debug, thiserror::Error)]
pub enum ScanError {
    /// A zero timeout or a node-ID without an SDO channel.
    #[error(transparent)]
    Setup(#[from] SessionError),
    /// The bus failed.
    #[error(transparent)]
    Link(#[from] LinkError),
}

/// Asks every node of `nodes` for 1000h and the identity of those that answer, with at most
/// `parallel` nodes busy at once and `timeout` per upload.
pub fn scan<L: Link + ?Sized>(
    link: &mut L,
    nodes: &[u8],
    parallel: usize,
    timeout: Duration,
) -> Result<Scan, ScanError> {
    if timeout.is_zero() {
        return Err(SessionError::ZeroTimeout.into());
    }
    let mut fleet = Fleet::new(nodes, (0x1000, 0), &IDENTITY, parallel, timeout)
        .map_err(|err: SdoClientError| ScanError::Setup(err.into()))?;
    let started = link.now();
    fleet.start(started);
    let mut results = Vec::new();
    // Every node runs at most five uploads of one timeout each, `parallel` nodes at a time; the
    // deadline only guards against a core that stops asking for time.
    let rounds = u32::try_from(nodes.len().div_ceil(parallel.max(1))).unwrap_or(u32::MAX);
    let deadline = started + (timeout * 5 + ROUND_SLACK) * rounds.max(1);
    let ended = drive::<_, _, _, LinkError>(link, &mut fleet, Some(deadline), |fleet, result| {
        results.push(result);
        Ok(if fleet.finished() {
            Flow::Done(())
        } else {
            Flow::Continue
        })
    })?;
    Ok(Scan {
        results,
        elapsed: link.now().saturating_duration_since(started),
        ended: ended.err(),
    })
}

//! Watching a node's TPDOs live (CiA 301 §7.2.2): finding their configuration over SDO
//! ([`discover`]) or from the EDS ([`from_eds`]), then receiving and decoding what they send
//! ([`receive`]). The decoding and statistics are [`canopener_master::pdo_watch`]'s.
//!
//! Discovery reads, per TPDO, the COB-ID (1800h+n sub 1), the transmission type (sub 2) and the
//! mapping (1A00h+n sub 0 and the entries). An abort from the device skips that TPDO (the EDS may
//! describe more than the device has); a timeout or a broken answer ends the discovery, since the
//! next reads would fare no better.

use std::collections::BTreeMap;
use std::time::Duration;

use canopener_can::{CanFrame, Instant};
use canopener_device::od_build::{OdBuildError, build_od};
use canopener_eds::Eds;
use canopener_master::pdo_config::{Direction, MAX_MAPPED_OBJECTS};
use canopener_master::pdo_decode::PdoLayout;
use canopener_master::pdo_watch::{Found, WatchedPdo, from_od, invalid};
use canopener_master::sdo_client::SdoTransferError;
use canopener_master::value::{entry_label, hex_value};

use crate::link::{Link, LinkError};
use crate::sdo_session::{SdoError, SdoSession};

/// How long one wait for a frame lasts when neither a duration nor a cancellation ends it sooner.
const RECV_SLICE: Duration = Duration::from_secs(1);

/// Why discovering the TPDOs over SDO stopped.
#[derive(Debug, thiserror::Error)]
pub enum DiscoverError {
    /// A read timed out or was aborted by the client (a broken answer).
    #[error("node {node}, reading {what} of TPDO{number} ({}): {error}", entry_label(*.index, *.sub))]
    Failed {
        /// The node.
        node: u8,
        /// What was read (`the COB-ID`).
        what: &'static str,
        /// The TPDO.
        number: u16,
        /// The object read.
        index: u16,
        /// Its sub-index.
        sub: u8,
        /// The timeout or client abort.
        error: SdoTransferError,
    },
    /// The session failed or was cancelled.
    #[error(transparent)]
    Session(SdoError),
}

/// Reads the TPDOs `numbers` over `session`, telling `on_progress` how many are done.
pub fn discover<L: Link>(
    session: &mut SdoSession<L>,
    numbers: &[u16],
    mut on_progress: impl FnMut(usize),
) -> Result<Vec<Found>, DiscoverError> {
    let mut found = Vec::with_capacity(numbers.len());
    for (done, &number) in numbers.iter().enumerate() {
        on_progress(done);
        found.push(discover_one(session, number)?);
    }
    on_progress(numbers.len());
    Ok(found)
}

/// The TPDOs `numbers` as the EDS/DCF values give them for `node`, `$NODEID` resolved.
pub fn from_eds(eds: &Eds, node: u8, numbers: &[u16]) -> Result<Vec<Found>, OdBuildError> {
    let built = build_od(eds, node)?;
    Ok(numbers.iter().map(|&number| from_od(&built.od, number)).collect())
}

fn discover_one<L: Link>(session: &mut SdoSession<L>, number: u16) -> Result<Found, DiscoverError> {
    let comm = Direction::Tpdo.comm_base() + number - 1;
    let mapping = Direction::Tpdo.mapping_base() + number - 1;
    let skip = |reason: String| Ok(Found::Skip { number, reason });
    let cob_id = match read(session, number, comm, 1, "the COB-ID")? {
        Ok(data) => match <[u8; 4]>::try_from(data.as_slice()) {
            Ok(bytes) => u32::from_le_bytes(bytes),
            Err(_) => {
                return skip(format!(
                    "COB-ID {} holds {} byte(s) ({}h), not an UNSIGNED32",
                    entry_label(comm, 1),
                    data.len(),
                    hex_value(&data)
                ));
            }
        },
        Err(reason) => return skip(reason),
    };
    if let Some(skip) = invalid(number, cob_id) {
        return Ok(skip);
    }
    let transmission_type = match read(session, number, comm, 2, "the transmission type")? {
        Ok(data) => match data.as_slice() {
            [value] => Some(*value),
            _ => None,
        },
        Err(_) => None,
    };
    let mut values = BTreeMap::new();
    let count = match read(session, number, mapping, 0, "the number of mapped objects")? {
        Ok(data) => {
            let count = data.first().copied();
            values.insert(0u8, data);
            count.unwrap_or(0)
        }
        Err(reason) => return skip(reason),
    };
    // More than 64 entries (or an MPDO's FEh/FFh) is refused below without reading them.
    let entries = if usize::from(count) <= MAX_MAPPED_OBJECTS {
        count
    } else {
        0
    };
    for sub in 1..=entries {
        match read(session, number, mapping, sub, "a mapping entry")? {
            Ok(data) => {
                values.insert(sub, data);
            }
            Err(reason) => return skip(reason),
        }
    }
    match PdoLayout::from_od_values(|sub| values.get(&sub).cloned()) {
        Ok(layout) => Ok(WatchedPdo::found(number, cob_id, transmission_type, layout)),
        Err(err) => skip(format!("mapping {mapping:04X}h: {err}")),
    }
}

/// Reads `what` of TPDO `number`, `index`:`sub`: the value, or why the device refused it.
fn read<L: Link>(
    session: &mut SdoSession<L>,
    number: u16,
    index: u16,
    sub: u8,
    what: &'static str,
) -> Result<Result<Vec<u8>, String>, DiscoverError> {
    match session.read(index, sub) {
        Ok(data) => Ok(Ok(data)),
        Err(SdoError::Transfer(error @ SdoTransferError::AbortedByServer { .. })) => {
            Ok(Err(format!("reading {}: {error}", entry_label(index, sub))))
        }
        Err(SdoError::Transfer(error)) => Err(DiscoverError::Failed {
            node: session.node(),
            what,
            number,
            index,
            sub,
            error,
        }),
        Err(other) => Err(DiscoverError::Session(other)),
    }
}

/// Receives until `count` frames of the watched TPDOs arrived, `duration` passed or the link is
/// cancelled, handing every frame of a watched TPDO to `on_frame` with the time since the watch
/// began (remote frames, which request a TPDO, carry nothing to decode and are passed over).
pub fn receive<L, E>(
    link: &mut L,
    watched: &mut [WatchedPdo],
    count: Option<u64>,
    duration: Option<Duration>,
    mut on_frame: impl FnMut(&mut WatchedPdo, Instant, Duration, &CanFrame) -> Result<(), E>,
) -> Result<(), E>
where
    L: Link + ?Sized,
    E: From<LinkError>,
{
    let started = link.now();
    let end = duration.map(|duration| started + duration);
    let mut received = 0u64;
    while count.is_none_or(|count| received < count) {
        let until = end.unwrap_or_else(|| link.now() + RECV_SLICE);
        let Some((at, frame)) = link.recv_until(until)? else {
            if link.is_cancelled() || end.is_some_and(|end| link.now() >= end) {
                break;
            }
            continue;
        };
        if frame.is_remote() {
            continue;
        }
        let Some(pdo) = watched.iter_mut().find(|pdo| pdo.can_id == frame.id()) else {
            continue;
        };
        received += 1;
        on_frame(pdo, at, at.saturating_duration_since(started), &frame)?;
    }
    Ok(())
}

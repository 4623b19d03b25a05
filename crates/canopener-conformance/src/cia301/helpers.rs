//! Pieces several CiA 301 tests share: refusal checks, entry choice, observing the NMT state.

use std::time::Duration;

use canopener_eds::AccessType;

use crate::context::{Ctx, Reply, hex};
use crate::device_model::EntryModel;
use crate::finding::{Evidence, Finding, Stop};
use crate::requirements::{Accepted, code_meaning};

/// The heartbeat period the tests configure: short enough for a quick run, long enough for any
/// device's timer resolution.
pub const TEST_HEARTBEAT_MS: u16 = 50;

/// The verdict on a request that CiA 301 requires the device to refuse with one of `accepted`.
pub fn expect_refusal(
    request: &str,
    reply: &Reply,
    accepted: Accepted,
    clause: &str,
    cause: &str,
) -> Finding {
    match reply {
        Reply::Refused(code) if accepted.accepts(*code) => {
            Finding::pass(format!("refused with {}", code_meaning(*code)))
        }
        other => Finding::fail(
            format!(
                "{request}: expected abort {}, got {}",
                accepted.list(),
                other.describe()
            ),
            Evidence {
                request: request.to_owned(),
                requirement: format!(
                    "{clause}: the server aborts with {} ({})",
                    accepted.list(),
                    accepted.source
                ),
                answer: other.describe(),
                cause: cause.to_owned(),
            },
        ),
    }
}

/// The failure of a request CiA 301 requires the device to carry out.
pub fn refused_unexpectedly(request: &str, reply: &Reply, clause: &str, cause: &str) -> Finding {
    Finding::fail(
        format!("{request}: {}", reply.describe()),
        Evidence {
            request: request.to_owned(),
            requirement: format!("{clause}: the server confirms the transfer"),
            answer: reply.describe(),
            cause: cause.to_owned(),
        },
    )
}

/// `SDO upload 1000h:00`.
pub fn upload_text(entry: (u16, u8)) -> String {
    format!("SDO upload {:04X}h:{:02X}", entry.0, entry.1)
}

/// `SDO download 1017h:00 = 64 00`.
pub fn download_text(entry: (u16, u8), data: &[u8]) -> String {
    format!("SDO download {:04X}h:{:02X} = {}", entry.0, entry.1, hex(data))
}

/// A writable numeric entry of `size` bytes the tests may change, communication objects first.
pub fn writable_of_size<'m>(ctx: &Ctx<'m, '_>, sizes: &[usize]) -> Option<&'m EntryModel> {
    let candidates = || {
        ctx.model().entries.values().filter(|e| {
            e.writable()
                && e.readable()
                && e.access != Some(AccessType::Wo)
                && e.data_type.is_some_and(|t| t.is_numeric())
                && e.size().is_some_and(|s| sizes.contains(&s))
                && !is_pdo_or_special(e.index)
        })
    };
    // 1017h first: every device has reason to accept it and it changes nothing else.
    candidates()
        .find(|e| e.index == 0x1017)
        .or_else(|| candidates().next())
}

/// Objects whose writing has side effects beyond the value (PDO parameters, store/restore,
/// the error history, SYNC objects (1019h only while 1006h is 0) and EMCY COB-IDs).
pub fn is_pdo_or_special(index: u16) -> bool {
    matches!(
        index,
        0x1400..=0x1BFF | 0x1010 | 0x1011 | 0x1003 | 0x1005 | 0x1006 | 0x1012 | 0x1014 | 0x1019 | 0x1F51
    )
}

/// Starts the heartbeat producer at [`TEST_HEARTBEAT_MS`] (written back after the test); `false`
/// when the device has no writable 1017h.
pub fn start_heartbeat(ctx: &mut Ctx<'_, '_>) -> Result<bool, Stop> {
    if !ctx.model().entry(0x1017, 0).is_some_and(EntryModel::writable) {
        return Ok(false);
    }
    Ok(matches!(
        ctx.modify(0x1017, 0, TEST_HEARTBEAT_MS.to_le_bytes().to_vec())?,
        Reply::Done(_)
    ))
}

/// The NMT state byte the device reports now: the last heartbeat within two and a half periods when
/// it produces heartbeats, else its answer to a node guarding request; `None` without an answer.
pub fn observed_state(ctx: &mut Ctx<'_, '_>, heartbeat: bool) -> Result<Option<u8>, Stop> {
    let id = ctx.id(0x700 + u16::from(ctx.node()));
    if heartbeat {
        // A heartbeat already on its way when the command went out may show the old state: skip
        // what arrives within the first 10 ms, then take the next one (due within a period).
        ctx.listen(Duration::from_millis(10), |_| false)?;
        let window = Duration::from_millis(u64::from(TEST_HEARTBEAT_MS) * 2);
        let frame = ctx.wait_for(window, |f| f.id() == id && !f.is_remote() && f.dlc() == 1)?;
        return Ok(frame.map(|l| l.frame.data()[0] & 0x7F));
    }
    ctx.send_remote(0x700 + u16::from(ctx.node()), 1)?;
    let frames = ctx.listen(ctx.timeout(), |f| f.id() == id && !f.is_remote() && f.dlc() == 1)?;
    Ok(frames.first().map(|l| l.frame.data()[0] & 0x7F))
}

/// `pre-operational (7Fh)`.
pub fn state_name(state: u8) -> String {
    let name = match state {
        0x00 => "boot-up",
        0x04 => "stopped",
        0x05 => "operational",
        0x7F => "pre-operational",
        _ => "no NMT state",
    };
    format!("{name} ({state:02X}h)")
}

/// A 4-byte value read as UNSIGNED32.
pub fn u32_of(reply: &Reply) -> Option<u32> {
    match reply {
        Reply::Done(d) if d.len() == 4 => Some(u32::from_le_bytes([d[0], d[1], d[2], d[3]])),
        _ => None,
    }
}

/// NMT enter pre-operational, and a moment for the device to get there.
pub fn back_to_pre_operational(ctx: &mut Ctx<'_, '_>) -> Result<(), Stop> {
    ctx.nmt(canopener_wire::NmtCommand::EnterPreOperational, false)?;
    ctx.listen(Duration::from_millis(20), |_| false).map(drop)
}

/// NMT reset node and the boot-up after it; `false` without one within
/// [`BOOT_UP_WAIT`](crate::cia301::nmt::BOOT_UP_WAIT).
pub fn reset_node(ctx: &mut Ctx<'_, '_>) -> Result<bool, Stop> {
    reset(ctx, canopener_wire::NmtCommand::ResetNode)
}

/// NMT reset communication and the boot-up after it; `false` without one within
/// [`BOOT_UP_WAIT`](crate::cia301::nmt::BOOT_UP_WAIT).
pub fn reset_communication(ctx: &mut Ctx<'_, '_>) -> Result<bool, Stop> {
    reset(ctx, canopener_wire::NmtCommand::ResetCommunication)
}

fn reset(ctx: &mut Ctx<'_, '_>, command: canopener_wire::NmtCommand) -> Result<bool, Stop> {
    ctx.nmt(command, false)?;
    let boot = ctx.id(0x700 + u16::from(ctx.node()));
    let heard = ctx
        .wait_for(crate::cia301::nmt::BOOT_UP_WAIT, |f| {
            f.id() == boot && f.data() == [0]
        })?
        .is_some();
    ctx.listen(Duration::from_millis(20), |_| false)?;
    Ok(heard)
}

/// The intervals between consecutive `frames` in ms (the bus's stamps), recorded as the measurement
/// `name` with their statistics.
pub fn measure_intervals(ctx: &mut Ctx<'_, '_>, name: &str, frames: &[crate::recorder::Logged]) -> Vec<f64> {
    let intervals: Vec<f64> = frames
        .windows(2)
        .map(|w| w[1].at.saturating_duration_since(w[0].at).as_secs_f64() * 1000.0)
        .collect();
    ctx.measure(name, crate::model::Measurement::new("ms", intervals.clone()));
    intervals
}

/// `96.0, 104.0, 100.0`: intervals as an analysis lists them.
pub fn intervals_text(intervals: &[f64]) -> String {
    intervals
        .iter()
        .map(|i| format!("{i:.1}"))
        .collect::<Vec<_>>()
        .join(", ")
}

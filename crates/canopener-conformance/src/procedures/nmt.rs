//! NMT commands with what follows them (boot-up, a settling moment) and observing the NMT state a
//! device reports (CiA 301 §7.3.2, §7.2.8.3).

use std::time::Duration;

use crate::context::{Ctx, Reply};
use crate::device_model::EntryModel;
use crate::finding::{Prepared, Stop};
use crate::procedures::sdo::{download_text, refused_unexpectedly};
use crate::requirements as req;

/// How long a device may take from a reset to its boot-up message. CiA 301 sets no bound; the CCT
/// waits a fixed time, canopener waits 2 s (documented in `docs/conformance.md`).
pub const BOOT_UP_WAIT: Duration = Duration::from_secs(2);

/// The heartbeat period the tests configure: short enough for a quick run, long enough for any
/// device's timer resolution.
pub const TEST_HEARTBEAT_MS: u16 = 50;

/// Starts the heartbeat producer at [`TEST_HEARTBEAT_MS`] (written back after the test): `false`
/// when the EDS has no writable 1017h; a failure when the device refuses (or does not answer) the
/// value its EDS makes writable (CiA 301 allows any producer time).
pub fn start_heartbeat(ctx: &mut Ctx<'_, '_>) -> Prepared<bool> {
    if !ctx.model().entry(0x1017, 0).is_some_and(EntryModel::writable) {
        return Ok(Ok(false));
    }
    let data = TEST_HEARTBEAT_MS.to_le_bytes().to_vec();
    Ok(match ctx.modify(0x1017, 0, data.clone())? {
        Reply::Done(_) => Ok(true),
        other => Err(refused_unexpectedly(
            &download_text((0x1017, 0), &data),
            &other,
            req::HEARTBEAT,
            "the heartbeat producer time the EDS makes writable is not taken",
        )),
    })
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
        return Ok(frame.and_then(|l| l.frame.data().first().map(|state| state & 0x7F)));
    }
    ctx.send_remote(0x700 + u16::from(ctx.node()), 1)?;
    let frames = ctx.listen(ctx.timeout(), |f| f.id() == id && !f.is_remote() && f.dlc() == 1)?;
    Ok(frames
        .first()
        .and_then(|l| l.frame.data().first().map(|state| state & 0x7F)))
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

/// How long a device gets to carry out an NMT state command before the tests look at it.
pub const SETTLE: Duration = Duration::from_millis(20);

/// NMT enter pre-operational, and a moment for the device to get there.
pub fn back_to_pre_operational(ctx: &mut Ctx<'_, '_>) -> Result<(), Stop> {
    enter(ctx, canopener_wire::NmtCommand::EnterPreOperational)
}

/// `command` to the node under test, and [`SETTLE`] for the device to carry it out.
pub fn enter(ctx: &mut Ctx<'_, '_>, command: canopener_wire::NmtCommand) -> Result<(), Stop> {
    ctx.nmt(command, false)?;
    ctx.listen(SETTLE, |_| false).map(drop)
}

/// NMT reset node and the boot-up after it; `false` without one within
/// [`BOOT_UP_WAIT`].
pub fn reset_node(ctx: &mut Ctx<'_, '_>) -> Result<bool, Stop> {
    reset(ctx, canopener_wire::NmtCommand::ResetNode)
}

/// NMT reset communication and the boot-up after it; `false` without one within
/// [`BOOT_UP_WAIT`].
pub fn reset_communication(ctx: &mut Ctx<'_, '_>) -> Result<bool, Stop> {
    reset(ctx, canopener_wire::NmtCommand::ResetCommunication)
}

fn reset(ctx: &mut Ctx<'_, '_>, command: canopener_wire::NmtCommand) -> Result<bool, Stop> {
    ctx.nmt(command, false)?;
    let boot = ctx.id(0x700 + u16::from(ctx.node()));
    let heard = ctx
        .wait_for(BOOT_UP_WAIT, |f| f.id() == boot && f.data() == [0])?
        .is_some();
    ctx.listen(Duration::from_millis(20), |_| false)?;
    Ok(heard)
}

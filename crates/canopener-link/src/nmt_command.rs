//! Sending one NMT module control command (CiA 301 §7.2.8.3.1) and, if asked, waiting for the nodes to
//! confirm it with their error control messages: the wait of
//! [`Confirmation`] on a link.

use std::time::Duration;

use canopener_can::Instant;
use canopener_master::error_control::{ConsumerTime, NodeMonitor};
use canopener_master::heartbeat_core::HeartbeatCore;
use canopener_master::nmt_confirmation::{Confirmation, NodeConfirmation};
use canopener_master::nmt_master::{NmtMaster, NmtTarget};
use canopener_wire::NmtCommand;

use crate::link::{Ended, Flow, Link, LinkError, drive};

/// Sends `command` to `target`; returns when it went out.
pub fn send<L: Link + ?Sized>(
    link: &mut L,
    command: NmtCommand,
    target: NmtTarget,
) -> Result<Instant, LinkError> {
    let mut master = NmtMaster::new();
    let sent_at = link.now();
    master.send(sent_at, command, target);
    while let Some(frame) = master.poll_transmit() {
        link.send(&frame)?;
    }
    Ok(sent_at)
}

/// Sends `command` to `target` and waits for the confirmation (see
/// [`canopener_master::nmt_confirmation`] for the rules). `on_extension` is called once when the wait
/// goes beyond `timeout` for nodes that reported their old state once and may confirm with their
/// next periodic heartbeat. The outcomes list every node heard (and a target not heard); a cancelled
/// wait reports the undecided ones as interrupted.
pub fn send_confirmed<L: Link + ?Sized>(
    link: &mut L,
    command: NmtCommand,
    target: NmtTarget,
    timeout: Duration,
    mut on_extension: impl FnMut(&Confirmation),
) -> Result<Vec<NodeConfirmation>, LinkError> {
    // The monitor is ready before the command goes out, so that no answer is missed.
    let mut core = HeartbeatCore::new(NodeMonitor::new(ConsumerTime::Off));
    let sent_at = send(link, command, target)?;
    let mut confirmation = Confirmation::new(command, target, sent_at, timeout);
    let mut told_extension = false;
    let interrupted = loop {
        let deadline = confirmation.deadline();
        let ended = drive::<_, _, _, LinkError>(link, &mut core, Some(deadline), |_, heard| {
            confirmation.on(&heard);
            let moved = confirmation.deadline() != deadline;
            Ok(if confirmation.finished(heard.at) || moved {
                Flow::Done(())
            } else {
                Flow::Continue
            })
        })?;
        if matches!(ended, Err(Ended::Cancelled)) {
            break true;
        }
        let now = link.now();
        if confirmation.finished(now) {
            break false;
        }
        if now >= confirmation.base_deadline() && !told_extension {
            told_extension = true;
            on_extension(&confirmation);
        }
    };
    Ok(confirmation.outcomes(interrupted))
}

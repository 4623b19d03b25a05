//! Periods: a TPDO on its event timer and on SYNC, and the heartbeat producer.

use std::time::Duration;

use canopener_wire::NmtCommand;

use super::{Clock, Criterion, Judged, judge, ms_between, standard_id};
use crate::context::{Ctx, Reply};
use crate::device_model::EntryModel;
use crate::finding::{Evidence, Finding, Outcome};
use crate::model::Measurement;
use crate::procedures::nmt::back_to_pre_operational;
use crate::procedures::sdo::u32_of;
use crate::procedures::tpdo::{Setting, set_up_tpdo};
use crate::requirements as req;

/// The event timer `cia313.perf.3` sets, in ms.
pub const EVENT_TIMER_MS: u16 = 10;
/// How many consecutive periods the cycle tests measure.
pub const PERIODS: usize = 100;
/// The SYNC period of `cia313.perf.4`.
pub const SYNC_PERIOD: Duration = Duration::from_millis(10);
/// The producer heartbeat time `cia313.perf.8` sets, in ms (the thesis's 100 ms, §4.2.2).
pub const HEARTBEAT_MS: u16 = 100;

pub(super) fn event_timer(ctx: &mut Ctx<'_, '_>) -> Outcome {
    // Type FFh: event-driven, device profile specific; the event timer alone triggers it here.
    let settings = [
        Setting::new(2, vec![0xFF], "event-driven transmission (type FFh)"),
        Setting::new(
            5,
            EVENT_TIMER_MS.to_le_bytes().to_vec(),
            "the event timer (18xxh:05) at this value",
        ),
    ];
    let (pdo, cob) = match set_up_tpdo(ctx, &settings, false)? {
        Ok(found) => found,
        Err(finding) => return Ok(finding),
    };
    let id = (cob & 0x7FF) as u16;
    let period = Duration::from_millis(u64::from(EVENT_TIMER_MS));
    ctx.nmt(NmtCommand::StartRemoteNode, false)?;
    // The TPDO sent on entering operational starts the count; each next one must come within two
    // timer periods.
    let mut stamps = Vec::new();
    while stamps.len() <= PERIODS {
        match ctx.wait_for(period * 2, |f| standard_id(f) == Some(id) && !f.is_remote())? {
            Some(logged) => stamps.push(logged.at),
            None => break,
        }
    }
    back_to_pre_operational(ctx)?;
    let request = format!(
        "TPDO{} ({id:#X}) with type FFh and event timer {EVENT_TIMER_MS} ms; NMT start, {PERIODS} periods",
        pdo.number
    );
    let periods: Vec<f64> = stamps
        .iter()
        .zip(stamps.iter().skip(1))
        .map(|(a, b)| ms_between(*a, *b))
        .collect();
    if periods.len() < PERIODS {
        ctx.measure("event_timer_period", Measurement::new("ms", periods.clone()));
        return Ok(Finding::fail(
            format!(
                "{} TPDO periods, then none within {} ms",
                periods.len(),
                2 * EVENT_TIMER_MS
            ),
            Evidence {
                request,
                requirement: format!(
                    "{}: an event-driven TPDO is sent whenever its event timer elapses",
                    req::PDO
                ),
                answer: format!("{} TPDOs", stamps.len()),
                cause: "the event timer 18xxh:05 is not applied, or stops".to_owned(),
            },
        ));
    }
    let percent = ctx.performance().criteria.event_timer_deviation_percent;
    let criterion = Criterion::around(
        ctx,
        "pdo.event_timer_deviation_percent",
        f64::from(EVENT_TIMER_MS),
        percent,
    );
    Ok(judge(
        ctx,
        Judged {
            name: "event_timer_period",
            what: format!("TPDO{} period at a {EVENT_TIMER_MS} ms event timer", pdo.number),
            request,
            clause: req::PDO,
            cause: "the event timer runs off its period, or the TPDO is also sent on other events",
            clock: Clock::Bus,
        },
        periods,
        Some(criterion),
    ))
}

pub(super) fn sync(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let settings = [Setting::new(
        2,
        vec![1],
        "cyclic synchronous transmission at this type",
    )];
    let (pdo, cob) = match set_up_tpdo(ctx, &settings, false)? {
        Ok(found) => found,
        Err(finding) => return Ok(finding),
    };
    let sync = match u32_of(&ctx.read(0x1005, 0)?) {
        Some(cob) => (cob & 0x7FF) as u16,
        None => 0x80,
    };
    let id = (cob & 0x7FF) as u16;
    ctx.nmt(NmtCommand::StartRemoteNode, false)?;
    ctx.listen(Duration::from_millis(20), |_| false)?;
    let mut delays = Vec::new();
    let mut stamps = Vec::new();
    let mut counts = Vec::new();
    for _ in 0..PERIODS {
        let sent = ctx.now();
        ctx.send(sync, &[])?;
        let frames = ctx.listen(SYNC_PERIOD, |f| standard_id(f) == Some(id) && !f.is_remote())?;
        if let Some(first) = frames.first() {
            delays.push(ms_between(sent, first.link_time));
            stamps.push(first.at);
        }
        counts.push(frames.len());
    }
    back_to_pre_operational(ctx)?;
    let periods: Vec<f64> = stamps
        .iter()
        .zip(stamps.iter().skip(1))
        .map(|(a, b)| ms_between(*a, *b))
        .collect();
    ctx.measure("tpdo_period", Measurement::new("ms", periods));
    let request = format!(
        "TPDO{} ({id:#X}) with transmission type 1; NMT start, {PERIODS} SYNCs on {sync:#X}, {} ms apart",
        pdo.number,
        SYNC_PERIOD.as_millis()
    );
    if let Some((wrong, count)) = counts.iter().enumerate().find(|(_, n)| **n != 1) {
        ctx.measure("sync_to_tpdo", Measurement::new("ms", delays));
        return Ok(Finding::fail(
            format!("SYNC {} was followed by {} TPDOs instead of 1", wrong + 1, count),
            Evidence {
                request,
                requirement: format!(
                    "{}: a TPDO of transmission type 1 is sent once after every SYNC",
                    req::PDO
                ),
                answer: format!(
                    "{} of {PERIODS} SYNCs followed by exactly one TPDO",
                    counts.iter().filter(|n| **n == 1).count()
                ),
                cause: "the SYNC is not consumed on this CAN-ID, or the TPDO is not sent on each".to_owned(),
            },
        ));
    }
    let criterion = Criterion::at_most(
        ctx,
        "pdo.sync_response_max_ms",
        ctx.performance().criteria.sync_response_max_ms,
    );
    Ok(judge(
        ctx,
        Judged {
            name: "sync_to_tpdo",
            what: format!("SYNC → TPDO{} time", pdo.number),
            request,
            clause: req::PDO,
            cause: "the device sends the synchronous TPDO later after the SYNC than the criterion allows",
            clock: Clock::Link,
        },
        delays,
        criterion,
    ))
}

pub(super) fn heartbeat(ctx: &mut Ctx<'_, '_>) -> Outcome {
    if !ctx.model().entry(0x1017, 0).is_some_and(EntryModel::writable) {
        return Ok(Finding::not_applicable("1017h is not writable"));
    }
    let reply = ctx.modify(0x1017, 0, HEARTBEAT_MS.to_le_bytes().to_vec())?;
    if !matches!(reply, Reply::Done(_)) {
        return Ok(super::unusable(
            &format!("SDO download 1017h:00 = {HEARTBEAT_MS} ms"),
            &reply,
        ));
    }
    let id = 0x700 + u16::from(ctx.node());
    let period = Duration::from_millis(u64::from(HEARTBEAT_MS));
    let is_heartbeat =
        |f: &canopener_can::CanFrame| standard_id(f) == Some(id) && !f.is_remote() && f.dlc() == 1;
    // A heartbeat already queued under the old setting may come first: the count starts with the
    // first one after a tenth of a period.
    ctx.listen(period / 10, |_| false)?;
    let mut stamps = Vec::new();
    while stamps.len() <= PERIODS {
        match ctx.wait_for(period * 2, is_heartbeat)? {
            Some(logged) => stamps.push(logged.at),
            None => break,
        }
    }
    let periods: Vec<f64> = stamps
        .iter()
        .zip(stamps.iter().skip(1))
        .map(|(a, b)| ms_between(*a, *b))
        .collect();
    let request = format!(
        "SDO download 1017h:00 = {HEARTBEAT_MS} ms; {PERIODS} consecutive heartbeat periods on {id:#X}"
    );
    if periods.len() < PERIODS {
        ctx.measure("heartbeat_period", Measurement::new("ms", periods.clone()));
        return Ok(Finding::fail(
            format!(
                "{} heartbeats, then none within {} ms",
                stamps.len(),
                2 * HEARTBEAT_MS
            ),
            Evidence {
                request,
                requirement: format!(
                    "{}: the heartbeat producer sends every producer heartbeat time (1017h)",
                    req::HEARTBEAT
                ),
                answer: format!(
                    "periods {}",
                    crate::procedures::intervals::intervals_text(&periods)
                ),
                cause: "the heartbeat producer stops or misses periods".to_owned(),
            },
        ));
    }
    let percent = ctx.performance().criteria.heartbeat_deviation_percent;
    let criterion = Criterion::around(
        ctx,
        "heartbeat.deviation_percent",
        f64::from(HEARTBEAT_MS),
        percent,
    );
    Ok(judge(
        ctx,
        Judged {
            name: "heartbeat_period",
            what: format!("heartbeat period at 1017h = {HEARTBEAT_MS} ms"),
            request,
            clause: req::HEARTBEAT,
            cause: "the heartbeat producer's timer deviates from 1017h, or sends extra heartbeats",
            clock: Clock::Bus,
        },
        periods,
        Some(criterion),
    ))
}

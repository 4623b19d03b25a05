//! TPDO transmission types (CCT "PDO 05–07, 11–13, 17–19"): the event timer and synchronous
//! transmission counted on SYNCs (CiA 301 §7.2.2.2.1, §7.5.2.35).

use std::time::Duration;

use canopener_wire::NmtCommand;

use crate::catalogue::TestDef;
use crate::cia301::helpers::{back_to_pre_operational, intervals_text, measure_intervals};
use crate::cia301::pdo::{configurable_tpdo, configure_tpdo};
use crate::context::Ctx;
use crate::finding::{Evidence, Finding, Outcome};
use crate::requirements as req;

/// The event timer the test sets, in ms.
pub const TEST_EVENT_TIMER_MS: u16 = 100;
/// The synchronous transmission type the test sets: every 3rd SYNC.
pub const TEST_SYNC_EVERY: u8 = 3;
/// SYNCs the tester sends (a multiple of [`TEST_SYNC_EVERY`]).
pub const TEST_SYNCS: usize = 12;
/// The time between the tester's SYNCs; a TPDO before the next SYNC belongs to the previous one
/// (without a synchronous window 1007h CiA 301 sets no tighter bound, and a hub adds latency).
pub const SYNC_SPACING: Duration = Duration::from_millis(20);
/// How far an event timer interval may stray: as for heartbeats, a tenth (canopener's choice).
pub const EVENT_TIMER_TOLERANCE: f64 = 0.1;

/// The transmission type tests.
pub fn tests() -> Vec<TestDef> {
    vec![
        TestDef {
            id: "cia301.pdo.6",
            suite: "cia301",
            group: "pdo",
            title: "Event timer: an event-driven TPDO with 100 ms in 18xxh:05 comes every 100 ms",
            references: &[
                req::PDO,
                req::PDO_PARAMETERS,
                "CCT PDO 05",
                "CCT PDO 11",
                "CCT PDO 17",
            ],
            precondition: "a TPDO with writable COB-ID, transmission type and event timer and mapped data; a refusal is not_applicable",
            tags: &["pdo", "timing", "writes", "nmt"],
            run: event_timer,
        },
        TestDef {
            id: "cia301.pdo.7",
            suite: "cia301",
            group: "pdo",
            title: "Synchronous type 3: one TPDO after every 3rd SYNC",
            references: &[req::PDO, req::SYNC, "CCT PDO 06", "CCT PDO 12", "CCT PDO 18"],
            precondition: "a TPDO with writable COB-ID and transmission type and mapped data; a refusal is not_applicable",
            tags: &["pdo", "sync", "writes", "nmt"],
            run: synchronous,
        },
    ]
}

fn event_timer(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let Some((pdo, cob)) = configurable_tpdo(ctx, &[1, 2, 5])? else {
        return Ok(Finding::not_applicable(
            "no TPDO with writable COB-ID, transmission type and event timer",
        ));
    };
    let settings = [(2u8, vec![0xFF]), (5, TEST_EVENT_TIMER_MS.to_le_bytes().to_vec())];
    if let Some(refused) = configure_tpdo(ctx, &pdo, cob, &settings, false)? {
        return Ok(Finding::not_applicable(format!(
            "TPDO{} cannot use an event timer: {refused}",
            pdo.number
        )));
    }
    let id = ctx.id((cob & 0x7FF) as u16);
    ctx.nmt(NmtCommand::StartRemoteNode, false)?;
    let frames = ctx.listen(
        Duration::from_millis(u64::from(TEST_EVENT_TIMER_MS) * 21 / 2),
        |f| f.id() == id && !f.is_remote(),
    )?;
    back_to_pre_operational(ctx)?;
    // The first TPDO may come at once on entering operational; the timer's intervals follow it.
    let intervals = measure_intervals(ctx, "event_timer_interval", &frames);
    let period = f64::from(TEST_EVENT_TIMER_MS);
    let request = format!(
        "TPDO{} ({:#X}) with type FFh and event timer {TEST_EVENT_TIMER_MS} ms; NMT start, 10.5 timer periods",
        pdo.number,
        cob & 0x7FF
    );
    let requirement = format!(
        "{}: an event-driven TPDO is sent when the event timer elapses (canopener allows ±{:.0} %)",
        req::PDO,
        EVENT_TIMER_TOLERANCE * 100.0
    );
    // Intervals shorter than the timer are allowed: an application event also triggers the TPDO.
    let late = intervals
        .iter()
        .copied()
        .find(|i| *i > period * (1.0 + EVENT_TIMER_TOLERANCE));
    Ok(if frames.len() < 9 {
        Finding::fail(
            format!(
                "{} TPDOs in 10.5 periods of a {TEST_EVENT_TIMER_MS} ms event timer",
                frames.len()
            ),
            Evidence {
                request,
                requirement,
                answer: format!("{} TPDOs", frames.len()),
                cause: "the event timer 18xxh:05 is not applied".to_owned(),
            },
        )
    } else if let Some(late) = late {
        Finding::fail(
            format!("a TPDO interval of {late:.1} ms with a {TEST_EVENT_TIMER_MS} ms event timer"),
            Evidence {
                request,
                requirement,
                answer: format!("intervals {}", intervals_text(&intervals)),
                cause: "the event timer runs late".to_owned(),
            },
        )
    } else {
        Finding::pass(format!("{} TPDOs, none later than the timer", frames.len()))
    })
}

fn synchronous(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let Some((pdo, cob)) = configurable_tpdo(ctx, &[1, 2])? else {
        return Ok(Finding::not_applicable(
            "no TPDO with writable COB-ID and transmission type",
        ));
    };
    if let Some(refused) = configure_tpdo(ctx, &pdo, cob, &[(2, vec![TEST_SYNC_EVERY])], false)? {
        return Ok(Finding::not_applicable(format!(
            "TPDO{} cannot be synchronous: {refused}",
            pdo.number
        )));
    }
    let sync = match crate::cia301::helpers::u32_of(&ctx.read(0x1005, 0)?) {
        Some(cob) => (cob & 0x7FF) as u16,
        None => 0x80,
    };
    let id = ctx.id((cob & 0x7FF) as u16);
    ctx.nmt(NmtCommand::StartRemoteNode, false)?;
    ctx.listen(Duration::from_millis(20), |_| false)?;
    // After each SYNC: did a TPDO follow before the next one?
    let mut after_sync = Vec::new();
    for _ in 0..TEST_SYNCS {
        ctx.send(sync, &[])?;
        let frames = ctx.listen(SYNC_SPACING, |f| f.id() == id && !f.is_remote())?;
        after_sync.push(frames.len());
    }
    back_to_pre_operational(ctx)?;
    let pattern: String = after_sync
        .iter()
        .map(|n| if *n > 0 { 'T' } else { '.' })
        .collect();
    let sent: Vec<usize> = after_sync
        .iter()
        .enumerate()
        .filter(|(_, n)| **n > 0)
        .map(|(i, _)| i)
        .collect();
    let evenly = sent
        .windows(2)
        .all(|w| w[1] - w[0] == usize::from(TEST_SYNC_EVERY));
    let expected = TEST_SYNCS / usize::from(TEST_SYNC_EVERY);
    Ok(
        if sent.len() == expected && evenly && after_sync.iter().all(|n| *n <= 1) {
            Finding::pass(format!("TPDOs after SYNCs {pattern}"))
        } else {
            Finding::fail(
                format!("TPDOs after {TEST_SYNCS} SYNCs: {pattern} (T: a TPDO followed)"),
                Evidence {
                    request: format!(
                        "TPDO{} ({:#X}) with transmission type {TEST_SYNC_EVERY}; NMT start, {TEST_SYNCS} SYNCs on {sync:#X}, {} ms apart",
                        pdo.number,
                        cob & 0x7FF,
                        SYNC_SPACING.as_millis()
                    ),
                    requirement: format!(
                        "{}: a synchronous TPDO of type n is sent after every n-th SYNC ({expected} here)",
                        req::PDO
                    ),
                    answer: format!("{pattern} ({} TPDOs)", after_sync.iter().sum::<usize>()),
                    cause: "the SYNCs are not counted, or the TPDO is not sent on the n-th".to_owned(),
                },
            )
        },
    )
}

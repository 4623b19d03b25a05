//! TPDO transmission types (CCT "PDO 05–07, 11–13, 17–19"): the event timer and synchronous
//! transmission counted on SYNCs (CiA 301 §7.2.2.2.1, §7.5.2.35).

use std::time::Duration;

use canopener_wire::NmtCommand;

use crate::context::{Ctx, Reply, first_hex};
use crate::finding::{Evidence, Finding, Outcome, Prepared, Stop};
use crate::procedures::intervals::{intervals_text, measure_intervals};
use crate::procedures::nmt::back_to_pre_operational;
use crate::procedures::sdo::{download_text, read_described, refused_unexpectedly, u32_of};
use crate::procedures::tpdo::{
    Setting, configurable_tpdo_at, configure_tpdo, none_configurable, not_writable, set_up_tpdo,
};
use crate::requirements as req;
use crate::test_def::TestDef;

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

/// The optional features the tests' settings stand for, as a "not applicable" reason names them.
const EVENT_DRIVEN: &str = "event-driven transmission (type FFh)";
const EVENT_TIMER: &str = "the event timer (18xxh:05) at this value";
const INHIBIT_TIME: &str = "the inhibit time (18xxh:03) at this value";
const SYNCHRONOUS_CYCLIC: &str = "cyclic synchronous transmission at this type";
const SYNCHRONOUS_ACYCLIC: &str = "acyclic synchronous transmission (type 0)";
const START_VALUE: &str = "the SYNC start value (18xxh:06) at this value";

/// The transmission type tests.
pub fn tests() -> Vec<TestDef> {
    vec![
        TestDef {
            id: "cia301.pdo.6",
            suite: "cia301",
            group: "pdo",
            title: "Event timer: an event-driven TPDO with 100 ms in 18xxh:05 comes every 100 ms in operational, never later, sooner only with new data, and never in stopped or pre-operational",
            references: &[
                req::NMT_STATES,
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
            title: "Synchronous type 3: one TPDO after every 3rd SYNC in operational, none in stopped or pre-operational",
            references: &[
                req::NMT_STATES,
                req::PDO,
                req::SYNC,
                "CCT PDO 06",
                "CCT PDO 12",
                "CCT PDO 18",
            ],
            precondition: "a TPDO with writable COB-ID and transmission type and mapped data; a refusal is not_applicable",
            tags: &["pdo", "sync", "writes", "nmt"],
            run: synchronous,
        },
        TestDef {
            id: "cia301.pdo.12",
            suite: "cia301",
            group: "pdo",
            title: "Event-driven TPDO (type FFh): in operational TPDOs follow the event timer but never within the inhibit time; none in stopped or pre-operational",
            references: &[
                req::NMT_STATES,
                req::PDO,
                req::PDO_PARAMETERS,
                "CCT PDO 04",
                "CCT PDO 10",
                "CCT PDO 16",
            ],
            precondition: "a TPDO with writable COB-ID, transmission type, inhibit time and event timer and mapped data; a refusal is not_applicable",
            tags: &["pdo", "timing", "writes", "nmt"],
            run: inhibit_time,
        },
        TestDef {
            id: "cia301.pdo.13",
            suite: "cia301",
            group: "pdo",
            title: "Synchronous acyclic (type 0): in operational a TPDO only right after a SYNC, at most one per SYNC; none in stopped or pre-operational",
            references: &[
                req::NMT_STATES,
                req::PDO,
                req::SYNC,
                "CCT PDO 07",
                "CCT PDO 13",
                "CCT PDO 19",
            ],
            precondition: "a TPDO with writable COB-ID and transmission type and mapped data; a refusal is not_applicable",
            tags: &["pdo", "sync", "writes", "nmt"],
            run: synchronous_acyclic,
        },
        TestDef {
            id: "cia301.pdo.14",
            suite: "cia301",
            group: "pdo",
            title: "SYNC start value: in operational a cyclic TPDO starts at the SYNC whose counter equals 18xxh:06; none in stopped or pre-operational",
            references: &[
                req::NMT_STATES,
                req::PDO,
                req::PDO_PARAMETERS,
                req::SYNC_OBJECTS,
                "CCT PDO 08",
                "CCT PDO 14",
                "CCT PDO 20",
            ],
            precondition: "a TPDO with writable COB-ID, transmission type and SYNC start value and mapped data, a writable 1019h, the device not a SYNC producer; a refusal is not_applicable",
            tags: &["pdo", "sync", "writes", "nmt"],
            run: sync_start_value,
        },
        TestDef {
            id: "cia301.sync.5",
            suite: "cia301",
            group: "sync",
            title: "SYNC consumer (1005h bit 30 clear, 1006h = 0): every TPDO set to type 1 follows every SYNC once",
            references: &[
                req::SYNC,
                req::SYNC_OBJECTS,
                req::PDO,
                "CCT Synchronization 03",
                "CCT Synchronization 04",
            ],
            precondition: "TPDOs with writable COB-ID and transmission type and mapped data (up to 8 are counted); 1005h/1006h are written only where the EDS makes them writable",
            tags: &["sync", "pdo", "writes", "nmt"],
            run: sync_consumer,
        },
    ]
}

fn event_timer(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let settings = [
        Setting::new(2, vec![0xFF], EVENT_DRIVEN),
        Setting::new(5, TEST_EVENT_TIMER_MS.to_le_bytes().to_vec(), EVENT_TIMER),
    ];
    let (pdo, cob) = match set_up_tpdo(ctx, &settings, false)? {
        Ok(found) => found,
        Err(finding) => return Ok(finding),
    };
    let id = ctx.id((cob & 0x7FF) as u16);
    ctx.nmt(NmtCommand::StartRemoteNode, false)?;
    let frames = ctx.listen(
        Duration::from_millis(u64::from(TEST_EVENT_TIMER_MS) * 13 / 2),
        |f| f.id() == id && !f.is_remote(),
    )?;
    let outside = silent_outside_operational(
        ctx,
        cob,
        Outside::Watch(NOT_OPERATIONAL_WATCH_EVENT_TIMER),
        ["PDO 11", "PDO 17"],
    )?;
    // The first TPDO may come at once on entering operational; the timer's intervals follow it.
    let intervals = measure_intervals(ctx, "event_timer_interval", &frames);
    let period = f64::from(TEST_EVENT_TIMER_MS);
    let request = format!(
        "TPDO{} ({:#X}) with type FFh and event timer {TEST_EVENT_TIMER_MS} ms; NMT start, 6.5 timer periods",
        pdo.number,
        cob & 0x7FF
    );
    let requirement = format!(
        "{}: an event-driven TPDO is sent when the event timer elapses (canopener allows ±{:.0} %)",
        req::PDO,
        EVENT_TIMER_TOLERANCE * 100.0
    );
    let late = intervals
        .iter()
        .copied()
        .find(|i| *i > period * (1.0 + EVENT_TIMER_TOLERANCE));
    // A shorter interval is an application event (CiA 301 §7.2.2.2.1: type FFh is also sent on the
    // profile's events, a change of the mapped data), so it must bring other data; the same data
    // sooner than the timer means the timer elapsed early.
    let early = intervals.iter().copied().enumerate().find(|(i, interval)| {
        *interval < period * (1.0 - EVENT_TIMER_TOLERANCE)
            && frames.get(i + 1).map(|l| l.frame.data()) == frames.get(*i).map(|l| l.frame.data())
    });
    let operational = if frames.len() < 5 {
        Finding::fail(
            format!(
                "{} TPDOs in 6.5 periods of a {TEST_EVENT_TIMER_MS} ms event timer",
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
    } else if let Some((i, early)) = early {
        Finding::fail(
            format!(
                "a TPDO {early:.1} ms after the previous one with the same data ({}) and a {TEST_EVENT_TIMER_MS} ms event timer",
                first_hex(frames.get(i + 1..).unwrap_or_default())
            ),
            Evidence {
                request,
                requirement: format!(
                    "{requirement}; an interval shorter than the timer is an application event, which changes the data"
                ),
                answer: format!("intervals {}", intervals_text(&intervals)),
                cause: "the event timer elapses early (its unit or its restart is wrong)".to_owned(),
            },
        )
    } else {
        Finding::pass(format!(
            "{} TPDOs, none later than the timer and none sooner with the same data",
            frames.len()
        ))
    };
    Ok(outside.with_operational(ctx, "PDO 05", operational))
}

fn synchronous(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let settings = [Setting::new(2, vec![TEST_SYNC_EVERY], SYNCHRONOUS_CYCLIC)];
    let (pdo, cob) = match set_up_tpdo(ctx, &settings, false)? {
        Ok(found) => found,
        Err(finding) => return Ok(finding),
    };
    let sync = sync_id(ctx)?;
    ctx.nmt(NmtCommand::StartRemoteNode, false)?;
    ctx.listen(Duration::from_millis(20), |_| false)?;
    let after_sync = tpdos_after_syncs(ctx, sync, cob, &[None; TEST_SYNCS])?;
    let outside = silent_outside_operational(
        ctx,
        cob,
        Outside::Syncs(sync, &[None; TEST_SYNC_EVERY as usize]),
        ["PDO 12", "PDO 18"],
    )?;
    let pattern = sync_pattern(&after_sync);
    let sent: Vec<usize> = after_sync
        .iter()
        .enumerate()
        .filter(|(_, n)| **n > 0)
        .map(|(i, _)| i)
        .collect();
    let evenly = sent
        .iter()
        .zip(sent.iter().skip(1))
        .all(|(before, after)| after - before == usize::from(TEST_SYNC_EVERY));
    let expected = TEST_SYNCS / usize::from(TEST_SYNC_EVERY);
    let operational = if sent.len() == expected && evenly && after_sync.iter().all(|n| *n <= 1) {
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
    };
    Ok(outside.with_operational(ctx, "PDO 06", operational))
}

/// The inhibit time `cia301.pdo.12` sets, in 100 µs: 50 ms.
pub const TEST_INHIBIT_100US: u16 = 500;
/// How much shorter than the inhibit time a measured interval may be: the jitter of time stamps
/// taken after the bus (a hub on a loaded host showed 6 ms); a device ignoring the inhibit time
/// sends at the 10 ms event timer.
pub const INHIBIT_SLACK_MS: f64 = 10.0;
/// The event timer `cia301.pdo.12` sets, shorter than the inhibit time, in ms.
pub const TEST_SHORT_EVENT_TIMER_MS: u16 = 10;
/// How long `cia301.pdo.12` watches the TPDOs.
pub const WATCH: Duration = Duration::from_millis(300);
/// How long `cia301.pdo.13` watches without SYNC.
pub const UNSYNCED_WATCH: Duration = Duration::from_millis(100);
/// SYNCs `cia301.pdo.13` sends.
pub const ACYCLIC_SYNCS: usize = 6;
/// The counter overflow value (1019h) `cia301.pdo.14` sets.
pub const TEST_OVERFLOW: u8 = 10;
/// The SYNC start value (18xxh:06) `cia301.pdo.14` sets.
pub const TEST_START_VALUE: u8 = 5;
/// The cyclic transmission type `cia301.pdo.14` sets: every 2nd SYNC.
pub const TEST_START_EVERY: u8 = 2;

fn inhibit_time(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let settings = [
        Setting::new(2, vec![0xFF], EVENT_DRIVEN),
        Setting::new(3, TEST_INHIBIT_100US.to_le_bytes().to_vec(), INHIBIT_TIME),
        Setting::new(5, TEST_SHORT_EVENT_TIMER_MS.to_le_bytes().to_vec(), EVENT_TIMER),
    ];
    let (pdo, cob) = match set_up_tpdo(ctx, &settings, false)? {
        Ok(found) => found,
        Err(finding) => return Ok(finding),
    };
    let id = ctx.id((cob & 0x7FF) as u16);
    ctx.nmt(NmtCommand::StartRemoteNode, false)?;
    let frames = ctx.listen(WATCH, |f| f.id() == id && !f.is_remote())?;
    let outside = silent_outside_operational(
        ctx,
        cob,
        Outside::Watch(NOT_OPERATIONAL_WATCH_SHORT_TIMER),
        ["PDO 10", "PDO 16"],
    )?;
    let intervals = measure_intervals(ctx, "inhibited_interval", &frames);
    let inhibit_ms = f64::from(TEST_INHIBIT_100US) / 10.0;
    let request = format!(
        "TPDO{} ({:#X}) with type FFh, inhibit time {inhibit_ms} ms, event timer {TEST_SHORT_EVENT_TIMER_MS} ms; NMT start, {} ms",
        pdo.number,
        cob & 0x7FF,
        WATCH.as_millis()
    );
    let requirement = format!(
        "{}: an event-driven TPDO is sent when its event timer elapses, and never twice within the inhibit time 18xxh:03 (canopener allows {INHIBIT_SLACK_MS} ms for time stamps)",
        req::PDO_PARAMETERS
    );
    // The event timer elapses every 10 ms: a TPDO is due at least at the end of every inhibit time
    // plus one timer period, so fewer than half of those periods means the timer is ignored.
    let least =
        (WATCH.as_secs_f64() * 1000.0 / (inhibit_ms + f64::from(TEST_SHORT_EVENT_TIMER_MS))) as usize / 2;
    let early = intervals
        .iter()
        .copied()
        .find(|i| *i < inhibit_ms - INHIBIT_SLACK_MS);
    let operational = if let Some(early) = early {
        Finding::fail(
            format!("two TPDOs {early:.1} ms apart with an inhibit time of {inhibit_ms} ms"),
            Evidence {
                request,
                requirement,
                answer: format!("intervals {}", intervals_text(&intervals)),
                cause: "the inhibit time 18xxh:03 is not applied".to_owned(),
            },
        )
    } else if frames.len() < least {
        Finding::fail(
            format!(
                "{} TPDOs in {} ms with a {TEST_SHORT_EVENT_TIMER_MS} ms event timer (at least {least} expected)",
                frames.len(),
                WATCH.as_millis()
            ),
            Evidence {
                request,
                requirement,
                answer: format!("{} TPDOs", frames.len()),
                cause: "an event inhibited by the inhibit time is dropped instead of deferred, or the event timer is not applied".to_owned(),
            },
        )
    } else {
        Finding::pass(format!(
            "{} TPDOs, none closer than the {inhibit_ms} ms inhibit time",
            frames.len()
        ))
    };
    Ok(outside.with_operational(ctx, "PDO 04", operational))
}

fn synchronous_acyclic(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let settings = [Setting::new(2, vec![0], SYNCHRONOUS_ACYCLIC)];
    let (pdo, cob) = match set_up_tpdo(ctx, &settings, false)? {
        Ok(found) => found,
        Err(finding) => return Ok(finding),
    };
    let sync = sync_id(ctx)?;
    let id = ctx.id((cob & 0x7FF) as u16);
    ctx.nmt(NmtCommand::StartRemoteNode, false)?;
    // Without SYNC a synchronous TPDO has no occasion to go out, whatever its events.
    let unsynced = ctx.listen(UNSYNCED_WATCH, |f| f.id() == id && !f.is_remote())?;
    let after_sync = tpdos_after_syncs(ctx, sync, cob, &[None; ACYCLIC_SYNCS])?;
    let outside =
        silent_outside_operational(ctx, cob, Outside::Syncs(sync, &[None; 2]), ["PDO 13", "PDO 19"])?;
    let pattern = sync_pattern(&after_sync);
    let request = format!(
        "TPDO{} ({:#X}) with transmission type 0; NMT start, {} ms without SYNC, then {ACYCLIC_SYNCS} SYNCs on {sync:#X}, {} ms apart",
        pdo.number,
        cob & 0x7FF,
        UNSYNCED_WATCH.as_millis(),
        SYNC_SPACING.as_millis()
    );
    let requirement = format!(
        "{}: a TPDO of type 0 is sent after a SYNC when an event occurred, so never without SYNC and at most once per SYNC",
        req::PDO
    );
    let operational = if !unsynced.is_empty() {
        Finding::fail(
            format!("{} TPDOs while no SYNC was sent", unsynced.len()),
            Evidence {
                request,
                requirement,
                answer: format!(
                    "{} TPDOs in {} ms without SYNC",
                    unsynced.len(),
                    UNSYNCED_WATCH.as_millis()
                ),
                cause: "type 0 is treated as event-driven".to_owned(),
            },
        )
    } else if after_sync.iter().any(|n| *n > 1) {
        Finding::fail(
            format!("more than one TPDO after a SYNC: {pattern}"),
            Evidence {
                request,
                requirement,
                answer: format!("TPDOs per SYNC {after_sync:?}"),
                cause: "events are sent as they occur instead of once at the next SYNC".to_owned(),
            },
        )
    } else {
        // Whether an event occurs is up to the application: no TPDO at all is allowed.
        Finding::pass(format!(
            "none without SYNC; after the SYNCs {pattern} (T: a TPDO followed; the application decides the events)"
        ))
    };
    Ok(outside.with_operational(ctx, "PDO 07", operational))
}

fn sync_start_value(ctx: &mut Ctx<'_, '_>) -> Outcome {
    if let Some(why) = not_writable(ctx, 0x1019, 0, Some(&[TEST_OVERFLOW])) {
        return Ok(Finding::not_applicable(format!(
            "{why}: the SYNC counter cannot be set to {TEST_OVERFLOW}"
        )));
    }
    if let Some(cob) = match described_u32(ctx, 0x1005, "the SYNC COB-ID")? {
        Ok(cob) => cob,
        Err(failed) => return Ok(failed),
    } && cob & 0x4000_0000 != 0
    {
        return Ok(Finding::not_applicable(
            "1005h bit 30 is set: the device is the SYNC producer, so the tester cannot send the counter",
        ));
    }
    // 1019h may change only while the SYNC period 1006h is 0 (CiA 301 §7.5.2.22, CCT Synchronization 09).
    if let Some(period) = match described_u32(ctx, 0x1006, "the communication cycle period")? {
        Ok(period) => period,
        Err(failed) => return Ok(failed),
    } && period != 0
    {
        if let Some(why) = not_writable(ctx, 0x1006, 0, Some(&[0; 4])) {
            return Ok(Finding::not_applicable(format!(
                "1006h = {period} µs and {why}: 1019h cannot change while the SYNC period runs"
            )));
        }
        let reply = ctx.modify(0x1006, 0, vec![0; 4])?;
        if !matches!(reply, Reply::Done(_)) {
            return Ok(refused_unexpectedly(
                &download_text((0x1006, 0), &[0; 4]),
                &reply,
                req::SYNC_OBJECTS,
                "1006h refuses 0 (no SYNC period), a value CiA 301 allows",
            ));
        }
    }
    let overflow = ctx.modify(0x1019, 0, vec![TEST_OVERFLOW])?;
    if !matches!(overflow, Reply::Done(_)) {
        // CiA 301 allows 2..240 in 1019h, and the EDS makes it writable.
        return Ok(refused_unexpectedly(
            &download_text((0x1019, 0), &[TEST_OVERFLOW]),
            &overflow,
            req::SYNC_OBJECTS,
            "1019h refuses a counter overflow value CiA 301 allows (2..240) while 1006h is 0",
        ));
    }
    let settings = [
        Setting::new(2, vec![TEST_START_EVERY], SYNCHRONOUS_CYCLIC),
        Setting::new(6, vec![TEST_START_VALUE], START_VALUE),
    ];
    let (pdo, cob) = match set_up_tpdo(ctx, &settings, false)? {
        Ok(found) => found,
        Err(finding) => return Ok(finding),
    };
    let sync = sync_id(ctx)?;
    ctx.nmt(NmtCommand::StartRemoteNode, false)?;
    ctx.listen(Duration::from_millis(20), |_| false)?;
    // The counter runs 1..=overflow and wraps to 1 (CiA 301 §7.2.5).
    let counters: Vec<Option<u8>> = (0..TEST_SYNCS)
        .map(|i| Some((i % usize::from(TEST_OVERFLOW)) as u8 + 1))
        .collect();
    let after_sync = tpdos_after_syncs(ctx, sync, cob, &counters)?;
    let outside = silent_outside_operational(
        ctx,
        cob,
        Outside::Syncs(sync, &START_VALUE_SYNCS_OUTSIDE),
        ["PDO 14", "PDO 20"],
    )?;
    let pattern = sync_pattern(&after_sync);
    // CiA 301 §7.5.2.35: the SYNC whose counter equals the start value "shall be regarded as the
    // first received SYNC". Stacks read that two ways for n > 1: CANopenNode transmits at that SYNC,
    // others count it as the first of n. Both are accepted; counting from the first SYNC sent
    // (ignoring the start value) puts the first TPDO before it and fails.
    let every = usize::from(TEST_START_EVERY);
    let expect_from = |first: usize| -> String {
        (0..TEST_SYNCS)
            .map(|i| {
                if i >= first && (i - first).is_multiple_of(every) {
                    'T'
                } else {
                    '.'
                }
            })
            .collect()
    };
    let at_start = expect_from(usize::from(TEST_START_VALUE) - 1);
    let counted = expect_from(usize::from(TEST_START_VALUE) - 1 + every - 1);
    let expected = format!("{at_start} or {counted}");
    let operational = if pattern == at_start || pattern == counted {
        Finding::pass(format!(
            "TPDOs after the SYNCs {pattern} (counters 1..{TEST_OVERFLOW})"
        ))
    } else {
        Finding::fail(
            format!("TPDOs after the SYNCs {pattern}, expected {expected} (T: a TPDO followed)"),
            Evidence {
                request: format!(
                    "1019h = {TEST_OVERFLOW}; TPDO{} ({:#X}) with type {TEST_START_EVERY} and SYNC start value {TEST_START_VALUE}; NMT start, {TEST_SYNCS} SYNCs with counters 1..{TEST_OVERFLOW} on {sync:#X}",
                    pdo.number,
                    cob & 0x7FF
                ),
                requirement: format!(
                    "{}: the SYNC whose counter equals the SYNC start value is the first SYNC the TPDO counts; then every {TEST_START_EVERY}nd SYNC",
                    req::PDO_PARAMETERS
                ),
                answer: format!("{pattern} ({} TPDOs)", after_sync.iter().sum::<usize>()),
                cause: "the SYNC start value 18xxh:06 is ignored, or the SYNC counter is not read".to_owned(),
            },
        )
    };
    Ok(outside.with_operational(ctx, "PDO 08", operational))
}

/// `index`:00 as UNSIGNED32 when the EDS describes it readable (`None` when it does not); a failure
/// when the device does not serve it.
fn described_u32(ctx: &mut Ctx<'_, '_>, index: u16, what: &str) -> Prepared<Option<u32>> {
    if !ctx.model().entry(index, 0).is_some_and(|e| e.readable()) {
        return Ok(Ok(None));
    }
    Ok(read_described(ctx, index, 0, what)?.map(|value| u32_of(&Reply::Done(value))))
}

/// The SYNC CAN-ID from 1005h (80h when it cannot be read).
fn sync_id(ctx: &mut Ctx<'_, '_>) -> Result<u16, Stop> {
    Ok(match u32_of(&ctx.read(0x1005, 0)?) {
        Some(cob) => (cob & 0x7FF) as u16,
        None => 0x80,
    })
}

/// Sends one SYNC per entry of `counters` (with the counter byte when `Some`), [`SYNC_SPACING`]
/// apart, and counts the TPDOs on `cob` that followed each before the next.
fn tpdos_after_syncs(
    ctx: &mut Ctx<'_, '_>,
    sync: u16,
    cob: u32,
    counters: &[Option<u8>],
) -> Result<Vec<usize>, Stop> {
    let per_sync = tpdo_counts_after_syncs(ctx, sync, &[(cob & 0x7FF) as u16], counters)?;
    Ok(per_sync
        .into_iter()
        .map(|counts| counts.first().copied().unwrap_or(0))
        .collect())
}

/// [`tpdos_after_syncs`] for several TPDOs: per SYNC, the number of frames on each of `ids`.
fn tpdo_counts_after_syncs(
    ctx: &mut Ctx<'_, '_>,
    sync: u16,
    ids: &[u16],
    counters: &[Option<u8>],
) -> Result<Vec<Vec<usize>>, Stop> {
    let wanted: Vec<_> = ids.iter().map(|id| ctx.id(*id)).collect();
    let mut per_sync = Vec::new();
    for counter in counters {
        match counter {
            Some(counter) => ctx.send(sync, &[*counter])?,
            None => ctx.send(sync, &[])?,
        }
        let frames = ctx.listen(SYNC_SPACING, |f| wanted.contains(&f.id()) && !f.is_remote())?;
        per_sync.push(
            wanted
                .iter()
                .map(|id| frames.iter().filter(|l| l.frame.id() == *id).count())
                .collect(),
        );
    }
    Ok(per_sync)
}

/// `..T..T`: `T` where a TPDO followed the SYNC.
fn sync_pattern(after_sync: &[usize]) -> String {
    after_sync
        .iter()
        .map(|n| if *n > 0 { 'T' } else { '.' })
        .collect()
}

/// The most TPDOs `cia301.sync.5` counts (each costs a handful of SDO transfers).
pub const MAX_COUNTED_TPDOS: usize = 8;
/// SYNCs `cia301.sync.5` sends.
pub const CONSUMER_SYNCS: usize = 5;

fn sync_consumer(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let writable = |ctx: &Ctx<'_, '_>, index: u16| ctx.model().entry(index, 0).is_some_and(|e| e.writable());
    // Make the device a SYNC consumer where the EDS allows it (CCT Synchronization 04): the period
    // off first, then the producer bit, so that the device is never a consumer with a period it
    // would monitor (a SYNC timeout EMCY); the write-back undoes it in the reverse order.
    let sync_cob = match described_u32(ctx, 0x1005, "the SYNC COB-ID")? {
        Ok(cob) => cob,
        Err(failed) => return Ok(failed),
    };
    let mut setup = Vec::new();
    if writable(ctx, 0x1006) {
        setup.push((0x1006u16, vec![0; 4]));
    }
    if writable(ctx, 0x1005) {
        let cob = sync_cob.unwrap_or(0x80) & !0x4000_0000;
        setup.push((0x1005, cob.to_le_bytes().to_vec()));
    }
    for (index, data) in setup {
        let reply = ctx.modify(index, 0, data.clone())?;
        if !matches!(reply, Reply::Done(_)) {
            return Ok(refused_unexpectedly(
                &download_text((index, 0), &data),
                &reply,
                req::SYNC_OBJECTS,
                "the device refuses to be a SYNC consumer",
            ));
        }
    }
    if !writable(ctx, 0x1005) && sync_cob.is_some_and(|cob| cob & 0x4000_0000 != 0) {
        return Ok(Finding::not_applicable(
            "1005h bit 30 is set (the device produces SYNC) and the EDS makes 1005h not writable (AccessType)",
        ));
    }
    let settings = [Setting::new(2, vec![1], SYNCHRONOUS_CYCLIC)];
    let mut ids: Vec<u16> = Vec::new();
    let mut names = Vec::new();
    let mut passed_over = Vec::new();
    for pdo in ctx.model().pdos(crate::device_model::PdoDirection::Transmit) {
        if ids.len() == MAX_COUNTED_TPDOS {
            break;
        }
        let cob = match configurable_tpdo_at(ctx, &pdo, &settings)? {
            Ok(Ok(cob)) => cob,
            Ok(Err(why)) => {
                passed_over.push(format!("TPDO{}: {why}", pdo.number));
                continue;
            }
            Err(failed) => return Ok(failed),
        };
        let id = (cob & 0x7FF) as u16;
        if ids.contains(&id) {
            continue;
        }
        match configure_tpdo(ctx, &pdo, cob, &settings, false)? {
            Ok(()) => {
                ids.push(id);
                names.push(format!("TPDO{} ({id:#X})", pdo.number));
            }
            Err(finding) if finding.verdict == crate::model::Verdict::NotApplicable => {
                passed_over.push(finding.reason);
            }
            Err(failed) => return Ok(failed),
        }
    }
    if ids.is_empty() {
        return Ok(none_configurable(&passed_over));
    }
    let counter = match ctx.read(0x1019, 0)? {
        Reply::Done(d) => d.first().copied().filter(|c| *c > 1),
        _ => None,
    };
    let counters: Vec<Option<u8>> = (0..CONSUMER_SYNCS)
        .map(|i| counter.map(|overflow| (i % usize::from(overflow)) as u8 + 1))
        .collect();
    let sync = sync_id(ctx)?;
    ctx.nmt(NmtCommand::StartRemoteNode, false)?;
    ctx.listen(Duration::from_millis(20), |_| false)?;
    let per_sync = tpdo_counts_after_syncs(ctx, sync, &ids, &counters)?;
    back_to_pre_operational(ctx)?;
    let wrong: Vec<String> = names
        .iter()
        .enumerate()
        .filter(|(i, _)| per_sync.iter().any(|counts| counts.get(*i) != Some(&1)))
        .map(|(i, name)| {
            let counts: Vec<usize> = per_sync.iter().filter_map(|c| c.get(i).copied()).collect();
            format!("{name}: {counts:?}")
        })
        .collect();
    ctx.performed("Synchronization 03");
    ctx.performed("Synchronization 04");
    Ok(if wrong.is_empty() {
        Finding::pass(format!(
            "{} followed each of {CONSUMER_SYNCS} SYNCs once",
            names.join(", ")
        ))
    } else {
        Finding::fail(
            format!("not one TPDO per SYNC: {}", wrong.join("; ")),
            Evidence {
                request: format!(
                    "{} with transmission type 1; NMT start, {CONSUMER_SYNCS} SYNCs on {sync:#X}, {} ms apart",
                    names.join(", "),
                    SYNC_SPACING.as_millis()
                ),
                requirement: format!("{}: a TPDO of type 1 is sent after every SYNC", req::PDO),
                answer: format!("TPDOs per SYNC: {}", wrong.join("; ")),
                cause: "the SYNC consumer misses SYNCs, or a TPDO is not served on every SYNC".to_owned(),
            },
        )
    })
}

/// How long an event-driven TPDO with the 100 ms event timer is watched in stopped and in
/// pre-operational: a timer period and its tolerance, in which a TPDO that kept running would come.
pub const NOT_OPERATIONAL_WATCH_EVENT_TIMER: Duration = Duration::from_millis(110);
/// The same for the 10 ms event timer of `cia301.pdo.12` (the 50 ms inhibit time, and more).
pub const NOT_OPERATIONAL_WATCH_SHORT_TIMER: Duration = Duration::from_millis(60);
/// After an NMT command, how long a TPDO already on its way may still arrive: a hub or a busy
/// device may have sent it before the command took effect.
pub const NMT_GRACE: Duration = Duration::from_millis(10);
/// The SYNC counters `cia301.pdo.14` sends in stopped and pre-operational: its start value (5) and
/// the next, at one of which a TPDO that ignored the state would be due (either reading of the
/// start value).
pub const START_VALUE_SYNCS_OUTSIDE: [Option<u8>; 2] = [Some(5), Some(6)];

/// What the TPDO is given in a state where it must stay silent.
#[derive(Debug, Clone, Copy)]
enum Outside<'a> {
    /// Nothing: watch this long.
    Watch(Duration),
    /// SYNCs on this CAN-ID with these counters, [`SYNC_SPACING`] apart.
    Syncs(u16, &'a [Option<u8>]),
}

/// The verdicts in stopped and in pre-operational, with their CCT cases.
struct OutsideOperational {
    stopped: (String, Finding),
    pre_operational: (String, Finding),
}

impl OutsideOperational {
    /// The test's verdict: the operational phase (`case`, recorded now that it is judged) and the
    /// two states after it.
    fn with_operational(self, ctx: &mut Ctx<'_, '_>, case: &str, operational: Finding) -> Finding {
        ctx.performed(case);
        let operational_name = format!("operational ({case})");
        let (stopped, stopped_finding) = self.stopped;
        let (pre_operational, pre_operational_finding) = self.pre_operational;
        Finding::of_steps(vec![
            (&operational_name, operational),
            (&stopped, stopped_finding),
            (&pre_operational, pre_operational_finding),
        ])
    }
}

/// CiA 301 §7.2.8.2: PDOs are served in operational only. The CCT runs its TPDO cases in
/// operational (PDO 04-08), stopped (10-14) and pre-operational (16-20); with the TPDO still set
/// up as for the operational phase, the device is stopped, then put into pre-operational, and in
/// each state the TPDO on `cob` must not come while the tester does `outside`. `cases` are the CCT
/// cases of the two states, recorded as each is judged. The device is left pre-operational.
fn silent_outside_operational(
    ctx: &mut Ctx<'_, '_>,
    cob: u32,
    outside: Outside<'_>,
    cases: [&str; 2],
) -> Result<OutsideOperational, Stop> {
    let id = ctx.id((cob & 0x7FF) as u16);
    let mut findings = Vec::new();
    for ((command, state), case) in [
        (NmtCommand::StopRemoteNode, "stopped"),
        (NmtCommand::EnterPreOperational, "pre-operational"),
    ]
    .into_iter()
    .zip(cases)
    {
        ctx.nmt(command, false)?;
        ctx.listen(NMT_GRACE, |_| false)?;
        let (sent, doing) = match outside {
            Outside::Watch(watch) => (
                ctx.listen(watch, |f| f.id() == id && !f.is_remote())?.len(),
                format!("{} ms", watch.as_millis()),
            ),
            Outside::Syncs(sync, counters) => (
                tpdos_after_syncs(ctx, sync, cob, counters)?.iter().sum(),
                format!(
                    "{} SYNCs on {sync:#X}, {} ms apart",
                    counters.len(),
                    SYNC_SPACING.as_millis()
                ),
            ),
        };
        ctx.performed(case);
        findings.push((
            format!("{state} ({case})"),
            if sent == 0 {
                Finding::pass(format!("no TPDO in {doing}"))
            } else {
                served_outside_operational(
                    format!("{sent} TPDOs on {:#X} in {state}", cob & 0x7FF),
                    format!(
                        "the TPDO as set up for operational; {}, then {doing}",
                        nmt_path(state)
                    ),
                    state,
                    format!("{sent} TPDOs"),
                )
            },
        ));
    }
    let not_run = || (String::new(), Finding::inconclusive("not run"));
    let pre_operational = findings.pop().unwrap_or_else(not_run);
    let stopped = findings.pop().unwrap_or_else(not_run);
    Ok(OutsideOperational {
        stopped,
        pre_operational,
    })
}

/// The NMT commands that lead from operational to `state` (stopped or pre-operational), as the
/// tests send them.
pub(crate) fn nmt_path(state: &str) -> &'static str {
    if state == "stopped" {
        "NMT stop"
    } else {
        "NMT stop, NMT enter pre-operational"
    }
}

/// The failure of a TPDO that went out in `state` (stopped or pre-operational).
pub(crate) fn served_outside_operational(
    reason: String,
    request: String,
    state: &str,
    answer: String,
) -> Finding {
    Finding::fail(
        reason,
        Evidence {
            request,
            requirement: format!(
                "{}: PDOs are served in operational only, not in {state}",
                req::NMT_STATES
            ),
            answer,
            cause: format!("PDO communication is not switched off in {state}"),
        },
    )
}

//! EMCY and SYNC per NMT state (CCT "State 02–04"), and the error register while an error is
//! active: CiA 301 runs EMCY and SYNC in pre-operational and operational, not in stopped (§7.2.8.2,
//! the table of services per NMT state); 1001h reflects the errors present (§7.5.2, 1001h).
//!
//! The error these tests provoke is a heartbeat consumer timeout (1016h), or on a device without a
//! writable 1016h a life guarding event (100Ch, 100Dh), both EMCY 8130h: error control runs in
//! every state, so the same error can be provoked in pre-operational, where its EMCY must come, and
//! in stopped, where it must not. The tests add entries to the device's error history 1003h on
//! purpose.

use std::time::Duration;

use canopener_wire::NmtCommand;

use crate::context::{Ctx, Reply, first_hex, hex};
use crate::finding::{Evidence, Finding, Outcome, Stop};
use crate::procedures::nmt::{SETTLE, back_to_pre_operational, enter};
use crate::procedures::sdo::{download_text, u32_of, upload_text};
use crate::requirements as req;
use crate::test_def::TestDef;

/// The consumer heartbeat time the tests set in 1016h:01, in ms.
pub const CONSUMER_MS: u16 = 100;
/// The SYNC period the producer test sets, in µs.
pub const TEST_SYNC_PERIOD_US: u32 = 10_000;
/// How long each state is watched for SYNCs: three and a half periods.
pub const SYNC_WATCH: Duration = Duration::from_micros(TEST_SYNC_PERIOD_US as u64 * 7 / 2);
/// EMCY error code 8130h (life guard or heartbeat error) as its first two bytes.
const EMCY_8130: [u8; 2] = [0x30, 0x81];

/// The EMCY, SYNC and error register tests.
pub fn tests() -> Vec<TestDef> {
    vec![
        TestDef {
            id: "cia301.nmt.8",
            suite: "cia301",
            group: "nmt",
            title: "EMCY per state: a heartbeat consumer timeout (or life guarding event) raises EMCY 8130h in pre-operational, no EMCY in stopped",
            references: &[
                req::NMT_STATES,
                req::EMCY,
                req::HEARTBEAT_CONSUMER,
                req::GUARDING,
                "CCT State 02",
                "CCT State 04",
            ],
            precondition: "an EMCY producer (1014h, bit 31 clear) and a writable 1016h:01, else writable 100Ch and 100Dh",
            tags: &["nmt", "emcy", "heartbeat", "writes", "states"],
            run: emcy_per_state,
        },
        TestDef {
            id: "cia301.nmt.9",
            suite: "cia301",
            group: "nmt",
            title: "SYNC producer per state: SYNCs in pre-operational and operational, none in stopped",
            references: &[
                req::NMT_STATES,
                req::SYNC,
                req::SYNC_OBJECTS,
                "CCT State 03",
                "CCT State 04",
            ],
            precondition: "writable 1005h and 1006h; a refusal to produce SYNC (optional) is not_applicable",
            tags: &["nmt", "sync", "writes", "states"],
            run: sync_producer_per_state,
        },
        TestDef {
            id: "cia301.emcy.6",
            suite: "cia301",
            group: "emcy",
            title: "1001h is not 00h while an error is active (a heartbeat consumer timeout or life guarding event)",
            references: &[req::ERROR_OBJECTS, req::EMCY, "CCT Emergency 05"],
            precondition: "a writable 1016h:01, else writable 100Ch and 100Dh, to provoke the error; 1001h reading 00h before it",
            tags: &["emcy", "heartbeat", "writes", "states"],
            run: register_while_error,
        },
    ]
}

/// What the device watches that the tester can make fail: a heartbeat it consumes (1016h), or
/// else life guarding (100Ch, 100Dh). Both are error control, which runs in every state.
enum Watchdog {
    /// The device consumes the heartbeat of node `producer` (not its own) for [`CONSUMER_MS`].
    Heartbeat { producer: u8 },
    /// Guard time [`GUARD_MS`], life time factor 3; the tester's guarding requests keep it alive.
    LifeGuarding,
}

/// The guard time of the life guarding watchdog, in ms (with a life time factor of 3).
pub const GUARD_MS: u16 = 50;

/// The tester as the other side of a watchdog, and where the device's EMCYs go.
struct Provoker {
    watchdog: Watchdog,
    /// The device's EMCY CAN-ID, when it has an enabled EMCY producer.
    emcy: Option<u16>,
}

impl Provoker {
    /// The watchdog set up (every value written back after the test); `Err` is the finding when
    /// the device offers none.
    fn set_up(ctx: &mut Ctx<'_, '_>) -> Result<Result<Provoker, Finding>, Stop> {
        let writable =
            |ctx: &Ctx<'_, '_>, index, sub| ctx.model().entry(index, sub).is_some_and(|e| e.writable());
        let emcy = if ctx.model().has(0x1014) {
            u32_of(&ctx.read(0x1014, 0)?)
                .filter(|c| c & 0x8000_0000 == 0)
                .map(|c| (c & 0x7FF) as u16)
        } else {
            None
        };
        let producer = ctx.node() % 127 + 1;
        let (watchdog, settings) = if writable(ctx, 0x1016, 1) {
            let entry = (u32::from(producer) << 16) | u32::from(CONSUMER_MS);
            (
                Watchdog::Heartbeat { producer },
                vec![(0x1016u16, 1u8, entry.to_le_bytes().to_vec())],
            )
        } else if writable(ctx, 0x100C, 0) && writable(ctx, 0x100D, 0) {
            let mut settings = Vec::new();
            // Life guarding runs while the heartbeat producer is off (CiA 301 §7.2.8.3.2).
            if writable(ctx, 0x1017, 0) {
                settings.push((0x1017u16, 0u8, vec![0, 0]));
            }
            settings.push((0x100C, 0, GUARD_MS.to_le_bytes().to_vec()));
            settings.push((0x100D, 0, vec![3]));
            (Watchdog::LifeGuarding, settings)
        } else {
            return Ok(Err(Finding::not_applicable(
                "neither a writable 1016h:01 (heartbeat consumer) nor writable 100Ch and 100Dh (life guarding): no error the tester can provoke",
            )));
        };
        for (index, sub, data) in settings {
            let reply = ctx.modify(index, sub, data.clone())?;
            if !matches!(reply, Reply::Done(_)) {
                return Ok(Err(Finding::inconclusive(format!(
                    "{} got {}: no watchdog to provoke an error with",
                    download_text((index, sub), &data),
                    reply.describe()
                ))));
            }
        }
        Ok(Ok(Provoker { watchdog, emcy }))
    }

    /// A heartbeat of the consumed node, or a guarding request: starts or feeds the watchdog.
    fn beat(&self, ctx: &mut Ctx<'_, '_>) -> Result<(), Stop> {
        match self.watchdog {
            Watchdog::Heartbeat { producer } => ctx.send(0x700 + u16::from(producer), &[0x05]),
            Watchdog::LifeGuarding => ctx.send_remote(0x700 + u16::from(ctx.node()), 1),
        }
    }

    /// How long after the last beat the EMCY 8130h must come: the consumer time or the life time,
    /// and 100 ms for the device to notice.
    fn window(&self) -> Duration {
        let ms = match self.watchdog {
            Watchdog::Heartbeat { .. } => CONSUMER_MS,
            Watchdog::LifeGuarding => GUARD_MS * 3,
        };
        Duration::from_millis(u64::from(ms) + 100)
    }

    /// A beat, then silence: the EMCY 8130h frames within [`Provoker::window`], the first one only
    /// (as soon as it comes) when `first`. Only 8130h counts: an error reset of an earlier error
    /// may still be on its way.
    fn lose(&self, ctx: &mut Ctx<'_, '_>, first: bool) -> Result<Vec<crate::recorder::Logged>, Stop> {
        self.beat(ctx)?;
        let window = self.window();
        let Some(emcy) = self.emcy.map(|id| ctx.id(id)) else {
            ctx.listen(window, |_| false)?;
            return Ok(Vec::new());
        };
        let keep = |f: &canopener_can::CanFrame| f.id() == emcy && f.data().starts_with(&EMCY_8130);
        if first {
            return Ok(ctx.wait_for(window, keep)?.into_iter().collect());
        }
        ctx.listen(window, keep)
    }

    /// The watchdog fed again: the error goes away (its error reset EMCY may follow).
    fn resume(&self, ctx: &mut Ctx<'_, '_>) -> Result<(), Stop> {
        self.beat(ctx)?;
        ctx.listen(SETTLE, |_| false).map(drop)
    }

    fn request(&self, ctx: &Ctx<'_, '_>) -> String {
        match self.watchdog {
            Watchdog::Heartbeat { producer } => format!(
                "1016h:01 = node {producer} / {CONSUMER_MS} ms, one heartbeat of node {producer} ({:03X}h), then none",
                0x700 + u16::from(producer)
            ),
            Watchdog::LifeGuarding => format!(
                "100Ch = {GUARD_MS} ms, 100Dh = 3, one guarding request on {:03X}h, then none",
                0x700 + u16::from(ctx.node())
            ),
        }
    }

    /// `heartbeat consumer timeout` or `life guarding event`.
    fn event(&self) -> &'static str {
        match self.watchdog {
            Watchdog::Heartbeat { .. } => "heartbeat consumer timeout",
            Watchdog::LifeGuarding => "life guarding event",
        }
    }
}

fn emcy_per_state(ctx: &mut Ctx<'_, '_>) -> Outcome {
    if !ctx.model().has(0x1014) {
        return Ok(Finding::not_applicable("the EDS has no EMCY producer (1014h)"));
    }
    let provoker = match Provoker::set_up(ctx)? {
        Ok(provoker) => provoker,
        Err(finding) => return Ok(finding),
    };
    let Some(emcy) = provoker.emcy else {
        return Ok(Finding::not_applicable(
            "the EMCY producer is disabled (1014h bit 31) or 1014h unreadable",
        ));
    };
    let request = provoker.request(ctx);
    let window = provoker.window();
    let event = provoker.event();
    let seen = provoker.lose(ctx, true)?;
    // 1029h may stop the device on the error: the stopped phase starts from pre-operational.
    back_to_pre_operational(ctx)?;
    // Without an EMCY, only the error register tells whether the device noticed the error at all.
    let register = match ctx.read(0x1001, 0)? {
        Reply::Done(ref d) if let [byte] = d.as_slice() => Some(*byte),
        _ => None,
    };
    provoker.resume(ctx)?;
    if seen.is_empty() && register.is_none_or(|r| r == 0) {
        return Ok(Finding::inconclusive(format!(
            "no EMCY 8130h after a {event} in pre-operational, and 1001h {}: the device may not have noticed the error (cia301.ec.6 and cia301.ec.7 judge the heartbeat consumer and life guarding)",
            register.map_or("unreadable".to_owned(), |r| format!("{r:02X}h"))
        )));
    }
    if seen.is_empty() {
        return Ok(Finding::fail(
            format!("no EMCY 8130h in pre-operational after a {event}"),
            Evidence {
                request: format!("pre-operational; {request}"),
                requirement: format!(
                    "{}: EMCY is served in pre-operational; {}, {}: a {event} is reported with EMCY 8130h",
                    req::NMT_STATES,
                    req::HEARTBEAT_CONSUMER,
                    req::GUARDING
                ),
                answer: format!(
                    "no EMCY 8130h on {emcy:03X}h within {} ms, though 1001h = {:02X}h shows the error",
                    window.as_millis(),
                    register.unwrap_or(0)
                ),
                cause: "EMCY is not sent in pre-operational".to_owned(),
            },
        ));
    }
    enter(ctx, NmtCommand::StopRemoteNode)?;
    let stopped = provoker.lose(ctx, false)?;
    back_to_pre_operational(ctx)?;
    // The error may be reported now that EMCY runs again; the heartbeat clears it.
    provoker.resume(ctx)?;
    if let Some(first) = stopped.first() {
        return Ok(Finding::fail(
            "EMCY sent in stopped",
            Evidence {
                request: format!("NMT stop; {request}"),
                requirement: format!(
                    "{}: in stopped only NMT and error control are served, no EMCY",
                    req::NMT_STATES
                ),
                answer: format!(
                    "EMCY {} on {emcy:03X}h within {} ms",
                    hex(first.frame.data()),
                    window.as_millis()
                ),
                cause: "the EMCY producer is not stopped in stopped".to_owned(),
            },
        ));
    }
    Ok(Finding::pass(format!(
        "{event}: EMCY {} in pre-operational, none in stopped within {} ms",
        first_hex(&seen),
        window.as_millis()
    )))
}

fn register_while_error(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let before = match ctx.read(0x1001, 0)? {
        Reply::Done(ref d) if let [byte] = d.as_slice() => *byte,
        other => {
            return Ok(Finding::inconclusive(format!(
                "{} got {} (cia301.emcy.2 judges 1001h)",
                upload_text((0x1001, 0)),
                other.describe()
            )));
        }
    };
    if before != 0 {
        return Ok(Finding::inconclusive(format!(
            "1001h is {before:02X}h before the test's error: an error is already active, so an update cannot be told apart"
        )));
    }
    let provoker = match Provoker::set_up(ctx)? {
        Ok(provoker) => provoker,
        Err(finding) => return Ok(finding),
    };
    let request = provoker.request(ctx);
    let seen = provoker.lose(ctx, true)?;
    // 1029h may stop the device on the error; the error stays active in pre-operational.
    back_to_pre_operational(ctx)?;
    let during = ctx.read(0x1001, 0)?;
    provoker.resume(ctx)?;
    let emcy = match (provoker.emcy, seen.first()) {
        (None, _) => "EMCY not watched: no enabled 1014h".to_owned(),
        (Some(_), None) => "no EMCY 8130h".to_owned(),
        (Some(_), Some(l)) => format!("EMCY {}", hex(l.frame.data())),
    };
    match during {
        Reply::Done(ref d)
            if let [register] = d.as_slice()
                && *register != 0 =>
        {
            Ok(Finding::pass(format!(
                "1001h {:02X}h during a {} ({emcy}), 00h before",
                register,
                provoker.event()
            )))
        }
        Reply::Done(d) if d == [0] && seen.is_empty() => Ok(Finding::inconclusive(format!(
            "{emcy} and 1001h stayed 00h: the device may not have detected the error (cia301.ec.6 and cia301.ec.7 judge the heartbeat consumer and life guarding)"
        ))),
        other => Ok(Finding::fail(
            format!(
                "1001h reads {} while an error is active ({emcy})",
                other.describe()
            ),
            Evidence {
                request: format!("{request}, then {}", upload_text((0x1001, 0))),
                requirement: format!(
                    "{}: while an error is present 1001h has its bit set (and the generic error bit 0), so it is not 00h",
                    req::ERROR_OBJECTS
                ),
                answer: format!("{}; {emcy}", other.describe()),
                cause: "the error register is not updated when an error occurs".to_owned(),
            },
        )),
    }
}

/// The SYNC producer test's setting that the device refused or did not answer: a refusal makes
/// the test not applicable (producing SYNC is optional), silence fails it.
fn producer_refused(entry: (u16, u8), data: &[u8], reply: &Reply) -> Finding {
    match reply {
        Reply::Silent => Finding::fail(
            format!("{}: no answer", download_text(entry, data)),
            Evidence {
                request: download_text(entry, data),
                requirement: format!("{}: the SDO server answers every request", req::SDO_DOWNLOAD),
                answer: reply.describe(),
                cause: "the SDO server does not answer this download".to_owned(),
            },
        ),
        other => Finding::not_applicable(format!(
            "the device does not produce SYNC as configured: {} got {}",
            download_text(entry, data),
            other.describe()
        )),
    }
}

fn sync_producer_per_state(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let writable = |ctx: &Ctx<'_, '_>, index| ctx.model().entry(index, 0).is_some_and(|e| e.writable());
    if !writable(ctx, 0x1005) || !writable(ctx, 0x1006) {
        return Ok(Finding::not_applicable(
            "1005h and 1006h are not both writable: SYNC production cannot be switched on",
        ));
    }
    let Some(cob) = u32_of(&ctx.read(0x1005, 0)?) else {
        return Ok(Finding::inconclusive("1005h could not be read"));
    };
    let period = u32_of(&ctx.read(0x1006, 0)?);
    // CiA 301's order: the period 0 while the producer bit changes, then the period. The
    // write-back, newest first, stops production before it clears the bit.
    let mut steps = Vec::new();
    if period != Some(0) {
        steps.push((0x1006u16, vec![0; 4]));
    }
    steps.push((0x1005, (cob | 0x4000_0000).to_le_bytes().to_vec()));
    steps.push((0x1006, TEST_SYNC_PERIOD_US.to_le_bytes().to_vec()));
    for (index, data) in steps {
        let reply = ctx.modify(index, 0, data.clone())?;
        if !matches!(reply, Reply::Done(_)) {
            return Ok(producer_refused((index, 0), &data, &reply));
        }
    }
    let id = ctx.id((cob & 0x7FF) as u16);
    let mut counts = Vec::new();
    for command in [
        None,
        Some(NmtCommand::StopRemoteNode),
        Some(NmtCommand::StartRemoteNode),
    ] {
        if let Some(command) = command {
            enter(ctx, command)?;
        }
        counts.push(ctx.listen(SYNC_WATCH, |f| f.id() == id && !f.is_remote())?.len());
    }
    back_to_pre_operational(ctx)?;
    let [pre_operational, stopped, operational] = <[usize; 3]>::try_from(counts).unwrap_or_default();
    let request = format!(
        "1005h = {:#010X}, 1006h = {TEST_SYNC_PERIOD_US} µs; SYNC frames in {} ms of pre-operational: {pre_operational}, then NMT stop: {stopped}, then NMT start: {operational}",
        cob | 0x4000_0000,
        SYNC_WATCH.as_millis()
    );
    if pre_operational == 0 && operational == 0 {
        return Ok(Finding::inconclusive(format!(
            "the producer sent no SYNC in pre-operational or operational either, so its silence in stopped proves nothing (cia301.sync.4 judges the producer): {request}"
        )));
    }
    // Three and a half periods hold three SYNCs; two allow for a late timer.
    let wrong = [
        (stopped > 0, "stopped", stopped),
        (pre_operational < 2, "pre-operational", pre_operational),
        (operational < 2, "operational", operational),
    ]
    .into_iter()
    .find(|(wrong, _, _)| *wrong);
    if let Some((_, state, count)) = wrong {
        let runs = state != "stopped";
        return Ok(Finding::fail(
            format!("{count} SYNC in {} ms of {state}", SYNC_WATCH.as_millis()),
            Evidence {
                request,
                requirement: if runs {
                    format!(
                        "{}: SYNC is served in {state}, so the producer sends one every 1006h",
                        req::NMT_STATES
                    )
                } else {
                    format!(
                        "{}: in stopped only NMT and error control are served, no SYNC",
                        req::NMT_STATES
                    )
                },
                answer: format!("{count} SYNC frames on {:03X}h in {state}", cob & 0x7FF),
                cause: if runs {
                    format!("the SYNC producer does not run in {state}")
                } else {
                    "the SYNC producer is not stopped in stopped".to_owned()
                },
            },
        ));
    }
    Ok(Finding::pass(format!(
        "SYNC frames in {} ms: pre-operational {pre_operational}, stopped {stopped}, operational {operational}",
        SYNC_WATCH.as_millis()
    )))
}

//! Heartbeat consumer tests (CCT "Heartbeat 04–06"): 1016h's rule against two entries for one node,
//! and the consumer's reaction to a heartbeat that stops: EMCY 8130h and the state change 1029h:01
//! asks for (CiA 301 §7.2.8.3.2.2, §7.5.2.32 consumer heartbeat time, §7.5.2.40 error behaviour).

use std::time::Duration;

use canopener_wire::NmtCommand;

use crate::context::{Ctx, Reply, first_hex, hex};
use crate::finding::{Evidence, Finding, Outcome, Stop};
use crate::procedures::emcy::emcy_producer;
use crate::procedures::nmt::{observed_state, start_heartbeat, state_name};
use crate::procedures::sdo::{download_text, expect_refusal, read_described};
use crate::requirements as req;
use crate::test_def::TestDef;

/// The consumer time the reaction test sets, in ms.
pub const TEST_CONSUMER_MS: u16 = 250;
/// The period the tester sends the consumed heartbeat at, in ms (well inside the consumer time).
pub const TESTER_PERIOD_MS: u64 = 100;

/// The heartbeat consumer tests.
pub fn tests() -> Vec<TestDef> {
    vec![
        TestDef {
            id: "cia301.ec.5",
            suite: "cia301",
            group: "ec",
            title: "1016h refuses a second consumer entry for the same node",
            references: &[req::HEARTBEAT_CONSUMER, "CCT Heartbeat 04"],
            precondition: "1016h with two writable entries",
            tags: &["heartbeat", "writes"],
            run: same_node_twice,
        },
        TestDef {
            id: "cia301.ec.6",
            suite: "cia301",
            group: "ec",
            title: "Heartbeat consumer: quiet while the heartbeat comes, EMCY 8130h and the 1029h reaction when it stops",
            references: &[
                req::HEARTBEAT_CONSUMER,
                req::EMCY,
                "CCT Heartbeat 05",
                "CCT Heartbeat 06",
            ],
            precondition: "a writable 1016h:01, an EMCY producer (1014h) and a writable 1017h to observe the state",
            tags: &["heartbeat", "emcy", "nmt", "timing", "writes"],
            run: consumer_reaction,
        },
        TestDef {
            id: "cia301.ec.10",
            suite: "cia301",
            group: "ec",
            title: "Heartbeat consumer across a reset node: 1016h:01 back at its default, and monitoring starts only with the first heartbeat",
            references: &[req::HEARTBEAT_CONSUMER, req::HEARTBEAT, "CCT Heartbeat 07"],
            precondition: "a writable 1016h:01 with a DefaultValue and an EMCY producer (1014h)",
            tags: &["heartbeat", "emcy", "nmt", "writes"],
            run: consumer_after_reset,
        },
        TestDef {
            id: "cia301.ec.7",
            suite: "cia301",
            group: "ec",
            title: "Life guarding: when guarding requests stop, EMCY 8130h and the 1029h reaction",
            references: &[
                req::GUARDING,
                req::HEARTBEAT_CONSUMER,
                "CCT Guarding 05",
                "CCT Guarding 06",
            ],
            precondition: "writable 100Ch/100Dh and an EMCY producer (1014h)",
            tags: &["guarding", "emcy", "nmt", "timing", "writes"],
            run: life_guarding,
        },
    ]
}

/// 1029h:01 and the state it asks for after a communication error in operational (CiA 301 §7.5.2.40:
/// 0, the default and the behaviour without 1029h, pre-operational; 1 no change; 2 stopped); a
/// finding when it cannot be judged.
fn error_behaviour(ctx: &mut Ctx<'_, '_>) -> Result<Result<(u8, u8), Finding>, Stop> {
    let behaviour = match ctx.model().entry(0x1029, 1) {
        Some(_) => match read_described(ctx, 0x1029, 1, "the error behaviour 1029h:01")? {
            // A longer expedited answer is cia301.sdo.14's to judge; the value is the first byte.
            Ok(d) => d.first().copied().unwrap_or(0),
            Err(failed) => return Ok(Err(failed)),
        },
        None => 0,
    };
    Ok(match behaviour {
        0 => Ok((0, 0x7F)),
        1 => Ok((1, 0x05)),
        2 => Ok((2, 0x04)),
        other => Err(Finding::not_applicable(format!(
            "1029h:01 = {other} is manufacturer-specific"
        ))),
    })
}

fn writable(ctx: &Ctx<'_, '_>, sub: u8) -> bool {
    ctx.model().entry(0x1016, sub).is_some_and(|e| e.writable())
}

/// A node-ID for the consumed producer: not the device's own.
fn producer_node(ctx: &Ctx<'_, '_>) -> u8 {
    if ctx.node() == 127 { 126 } else { ctx.node() + 1 }
}

fn entry(node: u8, ms: u16) -> Vec<u8> {
    ((u32::from(node) << 16) | u32::from(ms)).to_le_bytes().to_vec()
}

fn same_node_twice(ctx: &mut Ctx<'_, '_>) -> Outcome {
    if !writable(ctx, 1) || !writable(ctx, 2) {
        return Ok(Finding::not_applicable(
            "1016h has fewer than two writable entries",
        ));
    }
    let producer = producer_node(ctx);
    let first = entry(producer, 1000);
    if !matches!(ctx.modify(0x1016, 1, first.clone())?, Reply::Done(_)) {
        return Ok(Finding::inconclusive(format!(
            "{} was refused",
            download_text((0x1016, 1), &first)
        )));
    }
    let second = entry(producer, 2000);
    let reply = ctx.modify(0x1016, 2, second.clone())?;
    ctx.performed("Heartbeat 04");
    Ok(expect_refusal(
        &format!(
            "{}, then {}",
            download_text((0x1016, 1), &first),
            download_text((0x1016, 2), &second)
        ),
        &reply,
        req::INCOMPATIBLE,
        req::HEARTBEAT_CONSUMER,
        "1016h does not check for a node consumed twice",
    ))
}

/// Sends the consumed heartbeat (operational) `count` times, [`TESTER_PERIOD_MS`] apart, and returns
/// the EMCY frames on `emcy` meanwhile.
fn produce(ctx: &mut Ctx<'_, '_>, producer: u8, count: usize, emcy: u16) -> Result<Vec<Vec<u8>>, Stop> {
    let id = ctx.id(emcy);
    let mut seen = Vec::new();
    for _ in 0..count {
        ctx.send(0x700 + u16::from(producer), &[0x05])?;
        let frames = ctx.listen(Duration::from_millis(TESTER_PERIOD_MS), |f| f.id() == id)?;
        seen.extend(frames.iter().map(|l| l.frame.data().to_vec()));
    }
    Ok(seen)
}

fn consumer_reaction(ctx: &mut Ctx<'_, '_>) -> Outcome {
    if !writable(ctx, 1) {
        return Ok(Finding::not_applicable("no writable 1016h:01"));
    }
    let emcy = match emcy_producer(ctx)? {
        Ok(cob) => cob,
        Err(finding) => return Ok(finding),
    };
    match start_heartbeat(ctx)? {
        Ok(true) => {}
        Ok(false) => {
            return Ok(Finding::not_applicable(
                "the EDS has no writable 1017h to observe the state by",
            ));
        }
        Err(failed) => return Ok(failed),
    }
    let (behaviour, expected_state) = match error_behaviour(ctx)? {
        Ok(pair) => pair,
        Err(finding) => return Ok(finding),
    };
    let producer = producer_node(ctx);
    let consumer = entry(producer, TEST_CONSUMER_MS);
    if !matches!(ctx.modify(0x1016, 1, consumer.clone())?, Reply::Done(_)) {
        return Ok(Finding::inconclusive(format!(
            "{} was refused",
            download_text((0x1016, 1), &consumer)
        )));
    }
    ctx.nmt(NmtCommand::StartRemoteNode, false)?;
    let setup = format!(
        "{}, NMT start, heartbeats of node {producer} every {TESTER_PERIOD_MS} ms",
        download_text((0x1016, 1), &consumer)
    );
    // 400 ms of heartbeats: longer than the consumer time, so an early timeout shows.
    let while_alive = produce(ctx, producer, 4, emcy)?;
    if let Some(alarm) = while_alive.iter().find(|d| d.starts_with(&[0x30, 0x81])) {
        return Ok(Finding::fail(
            "EMCY 8130h while the consumed heartbeat came in time",
            Evidence {
                request: setup,
                requirement: format!(
                    "{}: a heartbeat within the consumer time {TEST_CONSUMER_MS} ms is no event",
                    req::HEARTBEAT_CONSUMER
                ),
                answer: format!("EMCY {}", hex(alarm)),
                cause: "the consumer times out too early (a unit or resolution error in 1016h)".to_owned(),
            },
        ));
    }
    // The heartbeat stops: the event is due TEST_CONSUMER_MS after the last one.
    let id = ctx.id(emcy);
    let after: Vec<_> = ctx
        .wait_for(Duration::from_millis(u64::from(TEST_CONSUMER_MS) * 2), |f| {
            f.id() == id && f.data().starts_with(&[0x30, 0x81])
        })?
        .into_iter()
        .collect();
    // A heartbeat built before the event may still be on its way (a late one is cia301.ec.1's
    // business): the state is judged from the heartbeats of the period after the event.
    ctx.listen(
        Duration::from_millis(u64::from(crate::procedures::nmt::TEST_HEARTBEAT_MS)),
        |_| false,
    )?;
    let state = observed_state(ctx, true)?;
    // The producer comes back, so the consumer's error goes before the write-back.
    produce(ctx, producer, 2, emcy)?;
    let request = format!("{setup}; then no heartbeat of node {producer}");
    if !after.iter().any(|l| l.frame.data().starts_with(&[0x30, 0x81])) {
        return Ok(Finding::fail(
            "no EMCY 8130h when the consumed heartbeat stopped",
            Evidence {
                request,
                requirement: format!(
                    "{}: a heartbeat missing for the consumer time is a heartbeat event, signalled with EMCY 8130h",
                    req::HEARTBEAT_CONSUMER
                ),
                answer: if after.is_empty() {
                    format!("no EMCY within {} ms", u64::from(TEST_CONSUMER_MS) * 2)
                } else {
                    format!("EMCY {}", first_hex(&after))
                },
                cause: "the heartbeat consumer does not watch 1016h, or the event sends no EMCY".to_owned(),
            },
        ));
    }
    let reaction = Reaction {
        behaviour,
        expected: expected_state,
        observed: state,
    };
    ctx.performed("Heartbeat 05");
    ctx.performed("Heartbeat 06");
    Ok(reaction.verdict(request, "heartbeat event", "heartbeat"))
}

/// The guard time the life guarding test sets, in ms; with a life time factor of 3.
pub const TEST_GUARD_MS: u16 = 50;

fn life_guarding(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let writable_var = |ctx: &Ctx<'_, '_>, index| ctx.model().entry(index, 0).is_some_and(|e| e.writable());
    if !writable_var(ctx, 0x100C) || !writable_var(ctx, 0x100D) {
        return Ok(Finding::not_applicable(
            "the EDS does not make 100Ch and 100Dh both writable (AccessType), or lacks them: life guarding cannot be set up",
        ));
    }
    let emcy = match emcy_producer(ctx)? {
        Ok(cob) => cob,
        Err(finding) => return Ok(finding),
    };
    let (behaviour, expected_state) = match error_behaviour(ctx)? {
        Ok(pair) => pair,
        Err(finding) => return Ok(finding),
    };
    // Node guarding applies while the heartbeat producer is off (CiA 301 §7.2.8.3.2).
    if writable_var(ctx, 0x1017) {
        ctx.modify(0x1017, 0, vec![0, 0])?;
    }
    for (index, data) in [
        (0x100Cu16, TEST_GUARD_MS.to_le_bytes().to_vec()),
        (0x100D, vec![3]),
    ] {
        let reply = ctx.modify(index, 0, data.clone())?;
        if !matches!(reply, Reply::Done(_)) {
            return Ok(Finding::inconclusive(format!(
                "{} got {}",
                download_text((index, 0), &data),
                reply.describe()
            )));
        }
    }
    ctx.nmt(NmtCommand::StartRemoteNode, false)?;
    let node = u16::from(ctx.node());
    let guard = ctx.id(0x700 + node);
    let mut answered = 0;
    for _ in 0..4 {
        ctx.send_remote(0x700 + node, 1)?;
        answered += ctx
            .listen(Duration::from_millis(u64::from(TEST_GUARD_MS)), |f| {
                f.id() == guard && !f.is_remote()
            })?
            .len();
    }
    let setup = format!(
        "100Ch = {TEST_GUARD_MS} ms, 100Dh = 3, NMT start, 4 guarding requests {TEST_GUARD_MS} ms apart"
    );
    if answered < 4 {
        return Ok(Finding::inconclusive(format!(
            "{answered} of 4 guarding requests answered (cia301.ec.4 judges guarding)"
        )));
    }
    // The life time is 300 ms from the last request.
    let id = ctx.id(emcy);
    let event = ctx.wait_for(Duration::from_millis(u64::from(TEST_GUARD_MS) * 6), |f| {
        f.id() == id && f.data().starts_with(&[0x30, 0x81])
    })?;
    let state = observed_state(ctx, false)?;
    let request = format!("{setup}; then no request");
    if event.is_none() {
        return Ok(Finding::fail(
            "no EMCY 8130h when the guarding requests stopped",
            Evidence {
                request,
                requirement: format!(
                    "{}: no guarding request within the life time (guard time × life time factor) is a life guarding event, signalled with EMCY 8130h",
                    req::GUARDING
                ),
                answer: format!("no EMCY 8130h within {} ms", u64::from(TEST_GUARD_MS) * 6),
                cause: "life guarding is not implemented, or its event sends no EMCY".to_owned(),
            },
        ));
    }
    let reaction = Reaction {
        behaviour,
        expected: expected_state,
        observed: state,
    };
    ctx.performed("Guarding 05");
    ctx.performed("Guarding 06");
    Ok(reaction.verdict(request, "life guarding event", "guarding answer"))
}

/// The state a communication error in operational asks for, and the one the device reported.
#[derive(Debug, Clone, Copy)]
struct Reaction {
    behaviour: u8,
    expected: u8,
    observed: Option<u8>,
}

impl Reaction {
    /// The verdict on the state after `event` (EMCY 8130h already seen), as `observer` reported it.
    fn verdict(self, request: String, event: &str, observer: &str) -> Finding {
        let Reaction {
            behaviour,
            expected,
            observed,
        } = self;
        if observed == Some(expected) {
            return Finding::pass(format!("EMCY 8130h, then {}", state_name(expected)));
        }
        Finding::fail(
            format!(
                "after the {event} the device is in {}, 1029h:01 = {behaviour} asks for {}",
                observed.map_or("no reported state".to_owned(), state_name),
                state_name(expected)
            ),
            Evidence {
                request,
                requirement: format!(
                    "{}: on a communication error in operational, 1029h:01 = {behaviour} means {}",
                    req::HEARTBEAT_CONSUMER,
                    state_name(expected)
                ),
                answer: observed.map_or(format!("no {observer}"), |s| {
                    format!("its {observer} reports {}", state_name(s))
                }),
                cause: format!("the error behaviour 1029h is not applied to the {event}"),
            },
        )
    }
}

/// The consumer time `cia301.ec.10` sets, in ms.
pub const RESET_CONSUMER_MS: u16 = 100;

fn consumer_after_reset(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let Some(default) = ctx
        .model()
        .entry(0x1016, 1)
        .filter(|e| e.writable())
        .and_then(|e| e.default.clone())
    else {
        return Ok(Finding::not_applicable(
            "no writable 1016h:01 with a DefaultValue",
        ));
    };
    let emcy = match emcy_producer(ctx)? {
        Ok(cob) => cob,
        Err(finding) => return Ok(finding),
    };
    let producer = producer_node(ctx);
    let consumer = entry(producer, RESET_CONSUMER_MS);
    if !matches!(ctx.modify(0x1016, 1, consumer.clone())?, Reply::Done(_)) {
        return Ok(Finding::inconclusive(format!(
            "{} was refused",
            download_text((0x1016, 1), &consumer)
        )));
    }
    if !crate::procedures::nmt::reset_node(ctx)? {
        return Ok(Finding::inconclusive("no boot-up after the reset node"));
    }
    let after_reset = ctx.read(0x1016, 1)?;
    if !matches!(&after_reset, Reply::Done(d) if *d == default) {
        return Ok(Finding::fail(
            "1016h:01 is not its default after a reset node",
            Evidence {
                request: format!(
                    "{}, NMT reset node, {}",
                    download_text((0x1016, 1), &consumer),
                    crate::procedures::sdo::upload_text((0x1016, 1))
                ),
                requirement: format!(
                    "{}: reset node sets every parameter to its power-on value ({} by the EDS)",
                    req::NMT_MODULE_CONTROL,
                    hex(&default)
                ),
                answer: after_reset.describe(),
                cause: "the consumer configuration survives a reset node".to_owned(),
            },
        ));
    }
    // Armed again, with no heartbeat from the producer at all: CiA 301 starts the monitoring with
    // the first heartbeat received, so three consumer times pass without an event.
    if !matches!(ctx.write(0x1016, 1, consumer.clone())?, Reply::Done(_)) {
        return Ok(Finding::inconclusive(format!(
            "{} was refused after the reset",
            download_text((0x1016, 1), &consumer)
        )));
    }
    let id = ctx.id(emcy);
    let alarm = ctx.wait_for(Duration::from_millis(u64::from(RESET_CONSUMER_MS) * 3), |f| {
        f.id() == id && f.data().starts_with(&[0x30, 0x81])
    })?;
    // Written back here: the test wrote it after the reset, outside `modify`.
    ctx.write(0x1016, 1, default.clone())?;
    ctx.performed("Heartbeat 07");
    Ok(match alarm {
        Some(alarm) => Finding::fail(
            "EMCY 8130h although the consumed node never sent a heartbeat",
            Evidence {
                request: format!(
                    "NMT reset node, {}, no heartbeat of node {producer}",
                    download_text((0x1016, 1), &consumer)
                ),
                requirement: format!(
                    "{}: heartbeat consuming starts with the first heartbeat received",
                    req::HEARTBEAT
                ),
                answer: format!("EMCY {}", hex(alarm.frame.data())),
                cause: "the consumer times out from the configuration instead of from the first heartbeat"
                    .to_owned(),
            },
        ),
        None => Finding::pass(format!(
            "default {} after the reset; no event in {} ms without a first heartbeat",
            hex(&default),
            u64::from(RESET_CONSUMER_MS) * 3
        )),
    })
}

//! SYNC tests (CCT group "Synchronization"): the SYNC COB-ID, the counter overflow value 1019h and
//! its rules, and the device as SYNC producer (CiA 301 §7.2.5, §7.5.2.6–7, §7.5.2.22).

use std::time::Duration;

use crate::context::{Ctx, Reply, hex};
use crate::finding::{Evidence, Finding, Outcome, Stop};
use crate::procedures::intervals::measure_intervals;
use crate::procedures::sdo::{download_text, expect_refusal, u32_of, upload_text};
use crate::requirements as req;
use crate::test_def::TestDef;

/// The SYNC period the producer test sets, in µs.
pub const TEST_SYNC_PERIOD_US: u32 = 10_000;
/// The counter overflow value the producer test sets.
pub const TEST_COUNTER: u8 = 5;

/// The SYNC tests.
pub fn tests() -> Vec<TestDef> {
    vec![
        TestDef {
            id: "cia301.sync.1",
            suite: "cia301",
            group: "sync",
            title: "1005h holds the default SYNC COB-ID 80h",
            references: &[req::SYNC_OBJECTS, "CCT Synchronization 01"],
            precondition: "the EDS has 1005h",
            tags: &["sync"],
            run: default_cob_id,
        },
        TestDef {
            id: "cia301.sync.2",
            suite: "cia301",
            group: "sync",
            title: "1019h refuses the reserved counter overflow values 1 and 241 and accepts 0",
            references: &[
                req::SYNC_OBJECTS,
                "CCT Synchronization 05",
                "CCT Synchronization 06",
            ],
            precondition: "a writable 1019h",
            tags: &["sync", "writes"],
            run: reserved_counter,
        },
        TestDef {
            id: "cia301.sync.3",
            suite: "cia301",
            group: "sync",
            title: "1019h cannot be written while the SYNC period 1006h is not 0",
            references: &[req::SYNC_OBJECTS, "CCT Synchronization 09"],
            precondition: "a writable 1019h and 1006h",
            tags: &["sync", "writes"],
            run: counter_while_running,
        },
        TestDef {
            id: "cia301.sync.4",
            suite: "cia301",
            group: "sync",
            title: "As SYNC producer: SYNC at the 1006h period, with the counter 1..1019h",
            references: &[
                req::SYNC,
                req::SYNC_OBJECTS,
                "CCT Synchronization 02",
                "CCT Synchronization 07",
            ],
            precondition: "writable 1005h, 1006h and 1019h; a device that refuses to produce SYNC is not_applicable",
            tags: &["sync", "timing", "writes"],
            run: producer,
        },
    ]
}

fn writable(ctx: &Ctx<'_, '_>, index: u16) -> bool {
    ctx.model().entry(index, 0).is_some_and(|e| e.writable())
}

fn default_cob_id(ctx: &mut Ctx<'_, '_>) -> Outcome {
    if !ctx.model().has(0x1005) {
        return Ok(Finding::not_applicable("the EDS has no 1005h"));
    }
    let reply = ctx.read(0x1005, 0)?;
    ctx.performed("Synchronization 01");
    Ok(match u32_of(&reply) {
        Some(cob) if cob & 0x1FFF_FFFF == 0x80 => Finding::pass(format!("{cob:#010X}")),
        _ => Finding::fail(
            format!("1005h: {}", reply.describe()),
            Evidence {
                request: upload_text((0x1005, 0)),
                requirement: format!("{}: the default SYNC COB-ID is 80h", req::SYNC_OBJECTS),
                answer: reply.describe(),
                cause: "1005h is not at its default".to_owned(),
            },
        ),
    })
}

/// Makes sure 1006h is 0 (written back after the test); `false` when it cannot be.
fn period_zero(ctx: &mut Ctx<'_, '_>) -> Result<bool, Stop> {
    match u32_of(&ctx.read(0x1006, 0)?) {
        Some(0) => Ok(true),
        Some(_) if writable(ctx, 0x1006) => Ok(matches!(ctx.modify(0x1006, 0, vec![0; 4])?, Reply::Done(_))),
        _ => Ok(!ctx.model().has(0x1006)),
    }
}

fn reserved_counter(ctx: &mut Ctx<'_, '_>) -> Outcome {
    if !writable(ctx, 0x1019) {
        return Ok(Finding::not_applicable("no writable 1019h"));
    }
    if !period_zero(ctx)? {
        return Ok(Finding::inconclusive(
            "1006h could not be set to 0, so 1019h may not be written",
        ));
    }
    for value in [1u8, 241] {
        let reply = ctx.modify(0x1019, 0, vec![value])?;
        let finding = expect_refusal(
            &download_text((0x1019, 0), &[value]),
            &reply,
            req::OUT_OF_RANGE,
            req::SYNC_OBJECTS,
            "1019h accepts the reserved values 1 and 241..255",
        );
        if finding.verdict != crate::model::Verdict::Pass {
            return Ok(finding);
        }
    }
    // 0 is valid: SYNC without a counter (CCT Synchronization 06).
    let reply = ctx.modify(0x1019, 0, vec![0])?;
    if !matches!(reply, Reply::Done(_)) {
        return Ok(crate::procedures::sdo::refused_unexpectedly(
            &download_text((0x1019, 0), &[0]),
            &reply,
            req::SYNC_OBJECTS,
            "1019h refuses 0 (SYNC without counter), a value CiA 301 allows",
        ));
    }
    ctx.performed("Synchronization 05");
    ctx.performed("Synchronization 06");
    Ok(Finding::pass("1 and 241 refused, 0 accepted"))
}

fn counter_while_running(ctx: &mut Ctx<'_, '_>) -> Outcome {
    if !writable(ctx, 0x1019) || !writable(ctx, 0x1006) {
        return Ok(Finding::not_applicable("1019h and 1006h are not both writable"));
    }
    let period = TEST_SYNC_PERIOD_US.to_le_bytes().to_vec();
    if !matches!(ctx.modify(0x1006, 0, period.clone())?, Reply::Done(_)) {
        return Ok(Finding::inconclusive(format!(
            "{} was refused",
            download_text((0x1006, 0), &period)
        )));
    }
    let reply = ctx.modify(0x1019, 0, vec![TEST_COUNTER])?;
    ctx.performed("Synchronization 09");
    Ok(expect_refusal(
        &format!(
            "{}, then {}",
            download_text((0x1006, 0), &period),
            download_text((0x1019, 0), &[TEST_COUNTER])
        ),
        &reply,
        req::DEVICE_STATE,
        req::SYNC_OBJECTS,
        "1019h is accepted while the SYNC period runs",
    ))
}

fn producer(ctx: &mut Ctx<'_, '_>) -> Outcome {
    if !(writable(ctx, 0x1005) && writable(ctx, 0x1006) && writable(ctx, 0x1019)) {
        return Ok(Finding::not_applicable(
            "1005h, 1006h and 1019h are not all writable",
        ));
    }
    let Some(cob) = u32_of(&ctx.read(0x1005, 0)?) else {
        return Ok(Finding::inconclusive("1005h could not be read"));
    };
    if !period_zero(ctx)? {
        return Ok(Finding::inconclusive("1006h could not be set to 0"));
    }
    let period = TEST_SYNC_PERIOD_US.to_le_bytes().to_vec();
    let producing = (cob | 0x4000_0000).to_le_bytes().to_vec();
    // The order CiA 301 allows: the counter while no period runs, then the period, then producing.
    for (index, data) in [
        (0x1019u16, vec![TEST_COUNTER]),
        (0x1006, period),
        (0x1005, producing),
    ] {
        let reply = ctx.modify(index, 0, data.clone())?;
        if !matches!(reply, Reply::Done(_)) {
            return Ok(Finding::not_applicable(format!(
                "the device does not produce SYNC as configured: {} got {}",
                download_text((index, 0), &data),
                reply.describe()
            )));
        }
    }
    let id = ctx.id((cob & 0x7FF) as u16);
    let frames = ctx.listen(Duration::from_millis(105), |f| f.id() == id && !f.is_remote())?;
    // Stop producing before the write-back, so the frames in the log end here.
    ctx.write(0x1005, 0, cob.to_le_bytes().to_vec())?;
    measure_intervals(ctx, "sync_interval", &frames);
    let counters: Vec<u8> = frames
        .iter()
        .map(|l| l.frame.data().first().copied().unwrap_or(0))
        .collect();
    let request = format!(
        "1019h = {TEST_COUNTER}, 1006h = {TEST_SYNC_PERIOD_US} µs, 1005h = {:#010X}",
        cob | 0x4000_0000
    );
    let lengths_right = frames.iter().all(|l| l.frame.dlc() == 1);
    // Each counter is the previous + 1, wrapping from the overflow value to 1.
    let counting = counters
        .windows(2)
        .all(|w| w[1] == if w[0] >= TEST_COUNTER { 1 } else { w[0] + 1 })
        && counters.iter().all(|c| (1..=TEST_COUNTER).contains(c));
    ctx.performed("Synchronization 02");
    ctx.performed("Synchronization 07");
    Ok(if frames.len() < 9 {
        Finding::fail(
            format!("{} SYNC in 105 ms at a 10 ms period", frames.len()),
            Evidence {
                request,
                requirement: format!("{}: a SYNC every communication cycle period 1006h", req::SYNC),
                answer: format!("{} SYNC frames", frames.len()),
                cause: "the SYNC producer does not run at 1006h".to_owned(),
            },
        )
    } else if !lengths_right || !counting {
        Finding::fail(
            "SYNC frames without the counter 1..1019h",
            Evidence {
                request,
                requirement: format!(
                    "{}: with 1019h > 1 every SYNC carries one byte, the counter 1..1019h",
                    req::SYNC
                ),
                answer: format!(
                    "SYNC data {}",
                    frames
                        .iter()
                        .map(|l| format!("[{}]", hex(l.frame.data())))
                        .collect::<Vec<_>>()
                        .join(" ")
                ),
                cause: "the SYNC producer leaves out or miscounts the counter".to_owned(),
            },
        )
    } else {
        Finding::pass(format!("{} SYNC, counters {}", frames.len(), hex(&counters)))
    })
}

//! SYNC tests (CCT group "Synchronization"): the SYNC COB-ID, the counter overflow value 1019h and
//! its rules, and the device as SYNC producer (CiA 301 §7.2.5, §7.5.2.6–7, §7.5.2.22).

use std::time::Duration;

use crate::context::{Ctx, Reply, hex};
use crate::finding::{Evidence, Finding, Outcome, Prepared, Stop};
use crate::procedures::intervals::{intervals_text, measure_intervals};
use crate::procedures::sdo::{
    download_text, expect_refusal, read_described, refused_unexpectedly, u32_of, upload_text,
};
use crate::procedures::tpdo::{NOT_SUPPORTED, not_writable};
use crate::requirements as req;
use crate::requirements::code_meaning;
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
            title: "As SYNC producer: SYNC at the 1006h period (the mean bounded on both sides), with the counter 1..1019h",
            references: &[
                req::SYNC,
                req::SYNC_OBJECTS,
                "CCT Synchronization 02",
                "CCT Synchronization 07",
            ],
            precondition: "writable 1005h, 1006h and 1019h; not_applicable only when the device refuses 1005h bit 30 or the 10 ms period with 0609 0030h/0031h/0032h (SYNC production is optional)",
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

/// Makes sure 1006h is 0 (written back after the test): CiA 301 allows 1019h to change only then.
/// A device without 1006h has no period; one whose EDS makes 1006h not writable while it is not 0
/// makes the test not applicable; a refused 0 fails.
fn period_zero(ctx: &mut Ctx<'_, '_>) -> Prepared<()> {
    if !ctx.model().entry(0x1006, 0).is_some_and(|e| e.readable()) {
        return Ok(Ok(()));
    }
    let period = match read_described(ctx, 0x1006, 0, "the communication cycle period")? {
        Ok(value) => u32_of(&Reply::Done(value)),
        Err(failed) => return Ok(Err(failed)),
    };
    if period == Some(0) {
        return Ok(Ok(()));
    }
    if let Some(why) = not_writable(ctx, 0x1006, 0, None) {
        return Ok(Err(Finding::not_applicable(format!(
            "1006h is not 0 and {why}: 1019h can change only while 1006h is 0"
        ))));
    }
    let reply = ctx.modify(0x1006, 0, vec![0; 4])?;
    Ok(match reply {
        Reply::Done(_) => Ok(()),
        other => Err(refused_unexpectedly(
            &download_text((0x1006, 0), &[0; 4]),
            &other,
            req::SYNC_OBJECTS,
            "1006h refuses 0 (no SYNC period), a value CiA 301 allows",
        )),
    })
}

fn reserved_counter(ctx: &mut Ctx<'_, '_>) -> Outcome {
    if !writable(ctx, 0x1019) {
        return Ok(Finding::not_applicable(
            "the EDS has no writable 1019h (AccessType)",
        ));
    }
    if let Err(finding) = period_zero(ctx)? {
        return Ok(finding);
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
        return Ok(refused_unexpectedly(
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
        return Ok(Finding::not_applicable(
            "the EDS does not make both 1019h and 1006h writable (AccessType)",
        ));
    }
    // 1006h runs with the device as SYNC producer where it can be one, so that it is never a
    // consumer with a period and no SYNC (a SYNC timeout EMCY on CANopenNode); as a consumer the
    // tester keeps the SYNC coming while the period is set.
    let producer = match start_producer(ctx, None, TEST_SYNC_PERIOD_US)? {
        Ok(_) => true,
        Err(finding) if finding.verdict == crate::model::Verdict::NotApplicable => false,
        Err(failed) => return Ok(failed),
    };
    let period = TEST_SYNC_PERIOD_US.to_le_bytes().to_vec();
    let sync = match u32_of(&ctx.read(0x1005, 0)?) {
        Some(cob) => (cob & 0x7FF) as u16,
        None => 0x80,
    };
    if !producer {
        if let Err(finding) = period_zero(ctx)? {
            return Ok(finding);
        }
        ctx.send(sync, &[])?;
        let reply = ctx.modify(0x1006, 0, period.clone())?;
        if !matches!(reply, Reply::Done(_)) {
            return Ok(refused_unexpectedly(
                &download_text((0x1006, 0), &period),
                &reply,
                req::SYNC_OBJECTS,
                "1006h refuses a communication cycle period its EDS makes writable",
            ));
        }
        ctx.send(sync, &[])?;
    }
    let reply = ctx.modify(0x1019, 0, vec![TEST_COUNTER])?;
    ctx.performed("Synchronization 09");
    if producer {
        stop_producer(ctx)?;
    } else {
        ctx.send(sync, &[])?;
        ctx.write(0x1006, 0, vec![0; 4])?;
    }
    Ok(expect_refusal(
        &format!(
            "{} ({}), then {}",
            download_text((0x1006, 0), &period),
            if producer {
                "as SYNC producer"
            } else {
                "as SYNC consumer"
            },
            download_text((0x1019, 0), &[TEST_COUNTER])
        ),
        &reply,
        req::DEVICE_STATE,
        req::SYNC_OBJECTS,
        "1019h is accepted while the SYNC period runs",
    ))
}

/// How far the mean SYNC interval may stray from 1006h: a tenth, as for heartbeats (canopener's
/// choice; CiA 301 sets none).
pub const SYNC_RATE_TOLERANCE: f64 = 0.1;
/// How long `cia301.sync.4` counts SYNC frames.
pub const SYNC_WATCH: Duration = Duration::from_millis(135);

/// The SYNC producer set up in the order that has no side effect (CiA 301 §7.5.2.6/7/22): the
/// counter while no period runs, the producer bit while the period is 0 (an idle producer), then
/// the period, which starts production. The write-back (newest first) stops the period before it
/// clears the producer bit, so the device is never a consumer with a period and no SYNC (which
/// CANopenNode reports as a SYNC timeout, EMCY 8100h, and records in 1003h). `counter` is the 1019h
/// value, if any. Returns the SYNC COB-ID as it was.
fn start_producer(ctx: &mut Ctx<'_, '_>, counter: Option<u8>, period_us: u32) -> Prepared<u32> {
    for index in [0x1005u16, 0x1006].into_iter().chain(counter.map(|_| 0x1019)) {
        if let Some(why) = not_writable(ctx, index, 0, None) {
            return Ok(Err(Finding::not_applicable(format!(
                "{why}: the device cannot be set up as SYNC producer"
            ))));
        }
    }
    let cob = match read_described(ctx, 0x1005, 0, "the SYNC COB-ID")? {
        Ok(value) => match u32_of(&Reply::Done(value.clone())) {
            Some(cob) => cob,
            None => {
                return Ok(Err(refused_unexpectedly(
                    &upload_text((0x1005, 0)),
                    &Reply::Done(value),
                    req::SYNC_OBJECTS,
                    "1005h does not read as 4 bytes",
                )));
            }
        },
        Err(failed) => return Ok(Err(failed)),
    };
    if let Err(failed) = period_zero(ctx)? {
        return Ok(Err(failed));
    }
    let producing = (cob | 0x4000_0000).to_le_bytes().to_vec();
    let period = period_us.to_le_bytes().to_vec();
    // (index, data, the optional feature a "not supported" refusal stands for)
    let mut steps: Vec<(u16, Vec<u8>, Option<&str>)> = Vec::new();
    if let Some(counter) = counter {
        // CiA 301 allows 2..240 in a writable 1019h while 1006h is 0: a refusal fails.
        steps.push((0x1019, vec![counter], None));
    }
    steps.push((
        0x1005,
        producing,
        Some("SYNC production (1005h bit 30), which CiA 301 leaves optional"),
    ));
    steps.push((0x1006, period, Some("this communication cycle period")));
    let mut done = Vec::new();
    for (index, data, feature) in steps {
        let request = download_text((index, 0), &data);
        let reply = ctx.modify(index, 0, data)?;
        done.push(request);
        match (&reply, feature) {
            (Reply::Done(_), _) => {}
            (Reply::Refused(code), Some(feature)) if NOT_SUPPORTED.contains(code) => {
                return Ok(Err(Finding::not_applicable(format!(
                    "{} was refused with {}: the device does not support {feature}",
                    done.join(", then "),
                    code_meaning(*code)
                ))));
            }
            (other, _) => {
                return Ok(Err(refused_unexpectedly(
                    &done.join(", then "),
                    other,
                    req::SYNC_OBJECTS,
                    "the device refuses a SYNC producer setting its EDS makes writable without saying the value is unsupported (0609 0030h would)",
                )));
            }
        }
    }
    Ok(Ok(cob))
}

/// Stops the SYNC period first (the write-back then restores 1005h without a period running).
fn stop_producer(ctx: &mut Ctx<'_, '_>) -> Result<(), Stop> {
    ctx.write(0x1006, 0, vec![0; 4]).map(drop)
}

fn producer(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let cob = match start_producer(ctx, Some(TEST_COUNTER), TEST_SYNC_PERIOD_US)? {
        Ok(cob) => cob,
        Err(finding) => return Ok(finding),
    };
    let id = ctx.id((cob & 0x7FF) as u16);
    let frames = ctx.listen(SYNC_WATCH, |f| f.id() == id && !f.is_remote())?;
    // Stop producing before the write-back, so the frames in the log end here.
    stop_producer(ctx)?;
    let intervals = measure_intervals(ctx, "sync_interval", &frames);
    let counters: Vec<u8> = frames
        .iter()
        .map(|l| l.frame.data().first().copied().unwrap_or(0))
        .collect();
    let request = format!(
        "1019h = {TEST_COUNTER}, 1005h = {:#010X}, 1006h = {TEST_SYNC_PERIOD_US} µs; {} ms of listening",
        cob | 0x4000_0000,
        SYNC_WATCH.as_millis()
    );
    let period_ms = f64::from(TEST_SYNC_PERIOD_US) / 1000.0;
    let watch_ms = SYNC_WATCH.as_secs_f64() * 1000.0;
    // The first SYNC comes within a period of the write; then one every period. One may be missed.
    let least = ((watch_ms - period_ms) / period_ms) as usize - 1;
    let mean = (intervals.len() > 1).then(|| intervals.iter().sum::<f64>() / intervals.len() as f64);
    let rate_requirement = format!(
        "{}: a SYNC every communication cycle period 1006h (canopener allows the mean interval ±{:.0} %, at least {least} SYNC in {} ms)",
        req::SYNC,
        SYNC_RATE_TOLERANCE * 100.0,
        SYNC_WATCH.as_millis()
    );
    let lengths_right = frames.iter().all(|l| l.frame.dlc() == 1);
    // Each counter is the previous + 1, wrapping from the overflow value to 1.
    let counting = counters
        .iter()
        .zip(counters.iter().skip(1))
        .all(|(before, after)| *after == if *before >= TEST_COUNTER { 1 } else { before + 1 })
        && counters.iter().all(|c| (1..=TEST_COUNTER).contains(c));
    ctx.performed("Synchronization 02");
    ctx.performed("Synchronization 07");
    Ok(if frames.len() < least {
        Finding::fail(
            format!(
                "{} SYNC in {} ms at a {period_ms} ms period",
                frames.len(),
                SYNC_WATCH.as_millis()
            ),
            Evidence {
                request,
                requirement: rate_requirement,
                answer: format!("{} SYNC frames", frames.len()),
                cause: "the SYNC producer does not run at 1006h".to_owned(),
            },
        )
    } else if let Some(mean) = mean.filter(|m| (m - period_ms).abs() > period_ms * SYNC_RATE_TOLERANCE) {
        Finding::fail(
            format!(
                "SYNC every {mean:.2} ms on average ({} in {} ms) at 1006h = {period_ms} ms",
                frames.len(),
                SYNC_WATCH.as_millis()
            ),
            Evidence {
                request,
                requirement: rate_requirement,
                answer: format!("intervals {}", intervals_text(&intervals)),
                cause: if mean < period_ms {
                    "the SYNC producer runs faster than 1006h (the period read in the wrong unit?)"
                } else {
                    "the SYNC producer runs slower than 1006h"
                }
                .to_owned(),
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
        Finding::pass(format!(
            "{} SYNC, mean interval {:.2} ms, counters {}",
            frames.len(),
            mean.unwrap_or(0.0),
            hex(&counters)
        ))
    })
}

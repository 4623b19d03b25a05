//! Emergency, heartbeat and node guarding tests (CCT groups "Emergency", "Guarding", "Heartbeat",
//! "Heartbeat versus guarding").

use std::time::Duration;

use canopener_wire::NmtCommand;

use crate::context::{Ctx, Reply, first_hex, hex};
use crate::finding::{Evidence, Finding, Outcome, Stop};
use crate::procedures::emcy::emcy_producer;
use crate::procedures::intervals::{intervals_text, measure_intervals};
use crate::procedures::nmt::{TEST_HEARTBEAT_MS, start_heartbeat};
use crate::procedures::sdo::{download_text, read_described, refused_unexpectedly, u32_of, upload_text};
use crate::requirements as req;
use crate::test_def::TestDef;

/// How far one heartbeat interval may stray from the period. CiA 301 sets no producer tolerance;
/// canopener allows a tenth of the period (a consumer is typically set to 1.5–2 periods), and
/// `docs/conformance.md` says so.
pub const HEARTBEAT_TOLERANCE: f64 = 0.1;

/// The heartbeat period the timing test sets, in ms: long enough that a tenth of it is well above
/// the timestamp resolution of any bus canopener reads.
pub const TIMING_HEARTBEAT_MS: u16 = 100;

/// The heartbeat period while `cia301.ec.3` sends guarding requests, in ms.
pub const GUARD_CHECK_HEARTBEAT_MS: u16 = 200;

/// Why the heartbeat tests do not apply.
const NO_WRITABLE_1017: &str = "the EDS has no writable 1017h (producer heartbeat time)";

/// The emergency tests.
pub fn emcy_tests() -> Vec<TestDef> {
    vec![
        TestDef {
            id: "cia301.emcy.1",
            suite: "cia301",
            group: "emcy",
            title: "1014h holds the EMCY COB-ID 80h + node-ID",
            references: &[req::EMCY, "CCT Emergency 01"],
            precondition: "the EDS has 1014h",
            tags: &["emcy"],
            run: emcy_cob_id,
        },
        TestDef {
            id: "cia301.emcy.2",
            suite: "cia301",
            group: "emcy",
            title: "1001h (error register) reads as one byte",
            references: &[req::ERROR_OBJECTS, "CCT Emergency 02"],
            precondition: "always (1001h is mandatory)",
            tags: &["emcy"],
            run: error_register,
        },
        TestDef {
            id: "cia301.emcy.3",
            suite: "cia301",
            group: "emcy",
            title: "A too short RPDO raises EMCY 8210h whose error register has the generic bit and equals 1001h read after it",
            references: &[
                req::EMCY,
                req::PDO,
                req::ERROR_REGISTER,
                "CCT Emergency 04",
                "CCT Emergency 05",
            ],
            precondition: "an enabled RPDO with mapped data, and an EMCY producer (1014h)",
            tags: &["emcy", "pdo", "nmt"],
            run: rpdo_length_emcy,
        },
        TestDef {
            id: "cia301.emcy.4",
            suite: "cia301",
            group: "emcy",
            title: "When the RPDO length error is gone, EMCY 0000h (error reset) follows with the error register 1001h holds",
            references: &[req::EMCY, req::ERROR_REGISTER, "CCT Emergency 04"],
            precondition: "as cia301.emcy.3, and the device raised 8210h",
            tags: &["emcy", "pdo", "nmt"],
            run: emcy_error_reset,
        },
        TestDef {
            id: "cia301.emcy.5",
            suite: "cia301",
            group: "emcy",
            title: "After EMCY 8210h, 1003h:01 holds 8210h and the entry after the last error has no data",
            references: &[req::ERROR_OBJECTS, "CCT Emergency 03", "CCT Emergency 06"],
            precondition: "as cia301.emcy.3, and the EDS has 1003h",
            tags: &["emcy", "pdo", "nmt"],
            run: emcy_history,
        },
    ]
}

/// The heartbeat and guarding tests.
pub fn tests() -> Vec<TestDef> {
    vec![
        TestDef {
            id: "cia301.ec.1",
            suite: "cia301",
            group: "ec",
            title: "Heartbeat producer: 1017h accepts a period and heartbeats follow it",
            references: &[req::HEARTBEAT, "CCT Heartbeat 01", "CCT Heartbeat 02"],
            precondition: "the EDS has a writable 1017h",
            tags: &["heartbeat", "timing"],
            run: heartbeat_period,
        },
        TestDef {
            id: "cia301.ec.2",
            suite: "cia301",
            group: "ec",
            title: "Heartbeat producer time 0 stops heartbeats",
            references: &[
                req::HEARTBEAT,
                "CCT Heartbeat 03",
                "CCT Heartbeat versus guarding 02",
            ],
            precondition: "the EDS has a writable 1017h",
            tags: &["heartbeat"],
            run: heartbeat_off,
        },
        TestDef {
            id: "cia301.ec.3",
            suite: "cia301",
            group: "ec",
            title: "While heartbeats run, node guarding requests are not answered",
            references: &[
                req::HEARTBEAT,
                req::GUARDING,
                "CCT Heartbeat versus guarding 05",
                "CCT Heartbeat versus guarding 07",
            ],
            precondition: "the EDS has a writable 1017h",
            tags: &["heartbeat", "guarding"],
            run: no_guarding_with_heartbeat,
        },
        TestDef {
            id: "cia301.ec.4",
            suite: "cia301",
            group: "ec",
            title: "Node guarding: each request answered with the state and an alternating toggle bit",
            references: &[
                req::GUARDING,
                "CCT Guarding 01",
                "CCT Guarding 02",
                "CCT Guarding 03",
                "CCT Heartbeat versus guarding 03",
            ],
            precondition: "the EDS has 100Ch and 100Dh",
            tags: &["guarding"],
            run: guarding_toggle,
        },
        TestDef {
            id: "cia301.ec.8",
            suite: "cia301",
            group: "ec",
            title: "Heartbeats follow 1017h with guarding off and with guard time and life time factor set",
            references: &[
                req::HEARTBEAT,
                req::GUARDING,
                "CCT Heartbeat versus guarding 01",
                "CCT Heartbeat versus guarding 04",
                "CCT Heartbeat versus guarding 06",
            ],
            precondition: "a writable 1017h; the guarding phases where 100Ch (and 100Dh) are writable",
            tags: &["heartbeat", "guarding", "writes"],
            run: heartbeat_over_guarding,
        },
        TestDef {
            id: "cia301.ec.9",
            suite: "cia301",
            group: "ec",
            title: "Node guarding: remote frames on other nodes' guarding IDs (700h–77Fh) are not answered, its own is",
            references: &[req::GUARDING, "CCT Guarding 04"],
            precondition: "the EDS has 100Ch and 100Dh",
            tags: &["guarding"],
            run: guarding_id_range,
        },
    ]
}

fn emcy_cob_id(ctx: &mut Ctx<'_, '_>) -> Outcome {
    if !ctx.model().has(0x1014) {
        return Ok(Finding::not_applicable("the EDS has no 1014h"));
    }
    let expected = 0x80 + u32::from(ctx.node());
    let reply = ctx.read(0x1014, 0)?;
    ctx.performed("Emergency 01");
    Ok(match u32_of(&reply) {
        Some(cob) if cob & 0x7FF == expected => Finding::pass(format!("{expected:#X}")),
        _ => Finding::fail(
            format!("1014h: {}", reply.describe()),
            Evidence {
                request: upload_text((0x1014, 0)),
                requirement: format!(
                    "{}: the default EMCY COB-ID is 80h + node-ID = {expected:#X}",
                    req::EMCY
                ),
                answer: reply.describe(),
                cause: "1014h is not filled from the node-ID".to_owned(),
            },
        ),
    })
}

fn error_register(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let reply = ctx.read(0x1001, 0)?;
    ctx.performed("Emergency 02");
    Ok(match reply {
        Reply::Done(ref d) if let [register] = d.as_slice() => {
            Finding::pass(format!("error register {register:02X}h"))
        }
        other => refused_unexpectedly(
            &upload_text((0x1001, 0)),
            &other,
            req::ERROR_OBJECTS,
            "1001h is mandatory",
        ),
    })
}

fn rpdo_length_emcy(ctx: &mut Ctx<'_, '_>) -> Outcome {
    rpdo_length(ctx, Look::Emcy)
}

fn emcy_error_reset(ctx: &mut Ctx<'_, '_>) -> Outcome {
    rpdo_length(ctx, Look::ErrorReset)
}

fn emcy_history(ctx: &mut Ctx<'_, '_>) -> Outcome {
    rpdo_length(ctx, Look::History)
}

/// What the RPDO length error tests look at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Look {
    /// EMCY 8210h.
    Emcy,
    /// EMCY 0000h once a correct RPDO follows.
    ErrorReset,
    /// 1003h: the error at sub-index 1, no data beyond the number of errors.
    History,
}

/// Sends a too short RPDO and looks for EMCY 8210h, then at what `look` says.
fn rpdo_length(ctx: &mut Ctx<'_, '_>, look: Look) -> Outcome {
    let error_reset = look == Look::ErrorReset;
    let emcy_cob = match emcy_producer(ctx)? {
        Ok(cob) => cob,
        Err(finding) => return Ok(finding),
    };
    // The first enabled RPDO with at least one byte mapped.
    let mut chosen = None;
    for pdo in ctx.model().pdos(crate::device_model::PdoDirection::Receive) {
        let Some(mapping) = pdo.mapping else { continue };
        let model = ctx.model();
        let readable = |index: u16, sub: u8| model.entry(index, sub).is_some_and(|e| e.readable());
        if !readable(pdo.comm, 1) || !readable(mapping, 0) {
            continue;
        }
        let cob = match read_described(ctx, pdo.comm, 1, "the RPDO's COB-ID")? {
            Ok(value) => u32_of(&Reply::Done(value)),
            Err(failed) => return Ok(failed),
        };
        let Some(cob) = cob.filter(|c| c & 0x8000_0000 == 0) else {
            continue;
        };
        let count = match read_described(ctx, mapping, 0, "the number of mapped objects")? {
            Ok(value) => value.first().copied().unwrap_or(0),
            Err(failed) => return Ok(failed),
        };
        // Every entry must read: a length summed over part of the mapping would make the "correct"
        // RPDO that clears the error too short as well, and leave the error to the next tests.
        let mut bits = Some(0u32);
        for sub in 1..=count {
            let entry = if readable(mapping, sub) {
                match read_described(ctx, mapping, sub, "a mapping entry")? {
                    Ok(d) => u32_of(&Reply::Done(d)),
                    Err(failed) => return Ok(failed),
                }
            } else {
                None
            };
            bits = bits.zip(entry).map(|(sum, entry)| sum + (entry & 0xFF));
        }
        let Some(bits) = bits else { continue };
        if bits >= 8 {
            chosen = Some((pdo.number, (cob & 0x7FF) as u16, bits.div_ceil(8) as usize));
            break;
        }
    }
    let Some((number, cob, bytes)) = chosen else {
        return Ok(Finding::not_applicable(
            "no RPDO is valid (14xxh:01 bit 31 clear) with at least 8 bits mapped (16xxh as read): no RPDO to send too short",
        ));
    };
    if bytes > 8 {
        // A PDO carries at most 64 bits (CiA 301 §7.5.2.36): no shorter PDO can be sent.
        return Ok(Finding::inconclusive(format!(
            "RPDO{number}'s mapping reads as {bytes} bytes, more than a PDO carries (8)"
        )));
    }
    ctx.nmt(NmtCommand::StartRemoteNode, false)?;
    ctx.listen(Duration::from_millis(50), |_| false)?;
    let short = vec![0u8; bytes - 1];
    ctx.send(cob, &short)?;
    let emcy = ctx.id(emcy_cob);
    // Waits for the EMCY itself, not the whole window: a run is as quick as the device.
    let seen: Vec<_> = ctx
        .wait_for(Duration::from_millis(500), |f| {
            f.id() == emcy && f.data().starts_with(&[0x10, 0x82])
        })?
        .into_iter()
        .collect();
    let request = format!(
        "NMT start, then RPDO{number} on {cob:#X} with {} bytes where {bytes} are mapped",
        bytes - 1
    );
    if look == Look::Emcy {
        ctx.performed("Emergency 04");
    }
    if error_reset {
        if !seen.iter().any(|l| l.frame.data().starts_with(&[0x10, 0x82])) {
            return Ok(Finding::inconclusive(
                "the device raised no EMCY 8210h, so there is no error to look at (cia301.emcy.3 judges that)",
            ));
        }
        ctx.send(cob, &vec![0u8; bytes])?;
        let after: Vec<_> = ctx
            .wait_for(Duration::from_millis(500), |f| {
                f.id() == emcy && f.data().starts_with(&[0, 0])
            })?
            .into_iter()
            .collect();
        let reset = format!("{request}, then RPDO{number} with {bytes} bytes");
        ctx.performed("Emergency 04");
        return Ok(
            match after.iter().find(|l| l.frame.data().starts_with(&[0x00, 0x00])) {
                Some(emcy) => match register_agrees(ctx, emcy.frame.data(), false, &reset)? {
                    Some(failed) => failed,
                    None => Finding::pass(format!(
                        "EMCY 0000h after a correct RPDO, error register {:02X}h as 1001h reads",
                        emcy.frame.data().get(2).copied().unwrap_or(0)
                    )),
                },
                None => Finding::fail(
                    "no EMCY 0000h (error reset) after the RPDO length error was gone",
                    Evidence {
                        request: format!("{request}, then RPDO{number} with {bytes} bytes"),
                        requirement: format!(
                            "{}: when an error is gone the device sends an EMCY with error code 0000h (error reset or no error)",
                            req::EMCY
                        ),
                        answer: if after.is_empty() {
                            "no EMCY within 500 ms".to_owned()
                        } else {
                            format!("EMCY {}", first_hex(&after))
                        },
                        cause: "the EMCY producer does not report that the error was cleared".to_owned(),
                    },
                ),
            },
        );
    }
    if look == Look::History {
        if !seen.iter().any(|l| l.frame.data().starts_with(&[0x10, 0x82])) {
            return Ok(Finding::inconclusive(
                "the device raised no EMCY 8210h, so there is no error to look at (cia301.emcy.3 judges that)",
            ));
        }
        let finding = error_history(ctx, &request)?;
        ctx.send(cob, &vec![0u8; bytes])?;
        ctx.listen(Duration::from_millis(50), |_| false)?;
        return Ok(finding);
    }
    // The error register byte of the EMCY, and 1001h read while the error is still there (CCT
    // Emergency 05).
    let register = match seen.iter().find(|l| l.frame.data().starts_with(&[0x10, 0x82])) {
        Some(emcy) => {
            ctx.performed("Emergency 05");
            register_agrees(ctx, emcy.frame.data(), true, &request)?
        }
        None => None,
    };
    // Leave no error behind for the next test: a PDO of the right length clears the condition.
    ctx.send(cob, &vec![0u8; bytes])?;
    ctx.listen(Duration::from_millis(50), |_| false)?;
    if let Some(failed) = register {
        return Ok(failed);
    }
    Ok(
        match seen.iter().find(|l| l.frame.data().starts_with(&[0x10, 0x82])) {
            Some(emcy) => Finding::pass(format!(
                "EMCY 8210h, error register {:02X}h (generic bit set) as 1001h reads after it",
                emcy.frame.data().get(2).copied().unwrap_or(0)
            )),
            None => Finding::fail(
                "no EMCY 8210h after a too short RPDO",
                Evidence {
                    request,
                    requirement: format!(
                        "{}: a PDO shorter than its mapping is an error reported with EMCY 8210h",
                        req::PDO
                    ),
                    answer: if seen.is_empty() {
                        "no EMCY within 500 ms".to_owned()
                    } else {
                        format!("EMCY {}", first_hex(&seen))
                    },
                    cause: "the RPDO length is not checked, or the EMCY producer is missing".to_owned(),
                },
            ),
        },
    )
}

/// The error register byte (D2) of the EMCY `emcy` against CiA 301 §7.5.2.2 and 1001h: its bit 0
/// (generic error) is set whenever any bit is, and, for an error (`error`: not an error reset), at
/// least bit 0 is set; 1001h, read right after the EMCY, holds the same byte. The failure, if any.
fn register_agrees(
    ctx: &mut Ctx<'_, '_>,
    emcy: &[u8],
    error: bool,
    request: &str,
) -> Result<Option<Finding>, Stop> {
    let code = emcy
        .get(..2)
        .and_then(|c| <[u8; 2]>::try_from(c).ok())
        .map_or(0, u16::from_le_bytes);
    let Some(&register) = emcy.get(2) else {
        return Ok(Some(Finding::fail(
            format!("EMCY {} carries no error register byte", hex(emcy)),
            Evidence {
                request: request.to_owned(),
                requirement: format!(
                    "{}: an EMCY carries the error register 1001h in byte 2",
                    req::EMCY
                ),
                answer: format!("EMCY {}", hex(emcy)),
                cause: "the EMCY frame is too short".to_owned(),
            },
        )));
    };
    let rule = format!(
        "{}: bit 0 (generic error) is set whenever any error is present, so whenever any other bit is; an EMCY carries 1001h as it is then",
        req::ERROR_REGISTER
    );
    if (register != 0 || error) && register & 0x01 == 0 {
        return Ok(Some(Finding::fail(
            format!(
                "EMCY {code:04X}h carries the error register {register:02X}h: the generic bit (bit 0) is clear"
            ),
            Evidence {
                request: request.to_owned(),
                requirement: rule,
                answer: format!("EMCY {}", hex(emcy)),
                cause: "the error register sets a class bit (or reports an error) without the generic bit"
                    .to_owned(),
            },
        )));
    }
    let read = ctx.read(0x1001, 0)?;
    match read {
        // A longer expedited answer is cia301.sdo.14's (and emcy.2's) to judge: the value is the
        // first byte.
        Reply::Done(ref d)
            if d.split_first()
                .is_some_and(|(first, rest)| *first == register && rest.iter().all(|b| *b == 0)) =>
        {
            Ok(None)
        }
        other => Ok(Some(Finding::fail(
            format!(
                "after EMCY {code:04X}h with error register {register:02X}h, 1001h reads {}",
                other.describe()
            ),
            Evidence {
                request: format!("{request}; after the EMCY, {}", upload_text((0x1001, 0))),
                requirement: rule,
                answer: format!("EMCY {}; 1001h: {}", hex(emcy), other.describe()),
                cause: "1001h and the EMCY's error register byte disagree (one of them is not updated)"
                    .to_owned(),
            },
        ))),
    }
}

/// After EMCY 8210h: 1003h:01 holds 8210h in its low 16 bits (the newest error first), and the
/// sub-index after the number of errors has no data (CiA 301 §7.5.2.4).
fn error_history(ctx: &mut Ctx<'_, '_>, request: &str) -> Result<Finding, Stop> {
    let Some(highest) = ctx.model().objects.get(&0x1003).map(|o| o.highest_sub()) else {
        return Ok(Finding::not_applicable("the EDS has no 1003h"));
    };
    ctx.performed("Emergency 03");
    ctx.performed("Emergency 06");
    let count = match ctx.read(0x1003, 0)? {
        Reply::Done(ref d) if let [byte] = d.as_slice() => *byte,
        other => {
            return Ok(refused_unexpectedly(
                &upload_text((0x1003, 0)),
                &other,
                req::ERROR_OBJECTS,
                "1003h is described",
            ));
        }
    };
    let newest = ctx.read(0x1003, 1)?;
    let holds = u32_of(&newest).is_some_and(|v| v & 0xFFFF == 0x8210);
    if count == 0 || !holds {
        return Ok(Finding::fail(
            format!(
                "after EMCY 8210h, 1003h:00 = {count} and 1003h:01 is {}",
                newest.describe()
            ),
            Evidence {
                request: format!(
                    "{request}, then {} and {}",
                    upload_text((0x1003, 0)),
                    upload_text((0x1003, 1))
                ),
                requirement: format!(
                    "{}: 1003h:01 holds the newest error, its code 8210h in the low 16 bits",
                    req::ERROR_OBJECTS
                ),
                answer: format!("1003h:00 = {count}, 1003h:01 = {}", newest.describe()),
                cause: "the pre-defined error field is not kept with the EMCY producer".to_owned(),
            },
        ));
    }
    if count >= highest {
        return Ok(Finding::pass(format!(
            "1003h:01 = 8210h; all {count} entries in use"
        )));
    }
    let beyond = ctx.read(0x1003, count + 1)?;
    Ok(
        match crate::procedures::sdo::expect_refusal(
            &upload_text((0x1003, count + 1)),
            &beyond,
            req::NO_DATA,
            req::ERROR_OBJECTS,
            "entries beyond the number of errors are served",
        ) {
            refused if refused.verdict == crate::model::Verdict::Pass => {
                Finding::pass(format!("1003h:01 = 8210h, 1003h:{:02X} has no data", count + 1))
            }
            failed => failed,
        },
    )
}

fn heartbeat_period(ctx: &mut Ctx<'_, '_>) -> Outcome {
    if !ctx.model().entry(0x1017, 0).is_some_and(|e| e.writable()) {
        return Ok(Finding::not_applicable(NO_WRITABLE_1017));
    }
    let reply = ctx.modify(0x1017, 0, TIMING_HEARTBEAT_MS.to_le_bytes().to_vec())?;
    if !matches!(reply, Reply::Done(_)) {
        return Ok(refused_unexpectedly(
            &download_text((0x1017, 0), &TIMING_HEARTBEAT_MS.to_le_bytes()),
            &reply,
            req::HEARTBEAT,
            "1017h is writable in the EDS",
        ));
    }
    let id = ctx.id(0x700 + u16::from(ctx.node()));
    // One period to settle, then seven.
    ctx.listen(Duration::from_millis(u64::from(TIMING_HEARTBEAT_MS)), |_| false)?;
    let frames = ctx.listen(
        Duration::from_millis(u64::from(TIMING_HEARTBEAT_MS) * 15 / 2),
        |f| f.id() == id && !f.is_remote(),
    )?;
    let period = f64::from(TIMING_HEARTBEAT_MS);
    let intervals = measure_intervals(ctx, "heartbeat_interval", &frames);
    // The same samples again, with the bound the verdict applies, so that reports can draw it.
    ctx.measure(
        "heartbeat_interval",
        crate::model::Measurement::new("ms", intervals.clone()).with_limits(crate::model::Limits {
            // As the verdict compares: |interval - period| > period × tolerance fails.
            low: Some(period - period * HEARTBEAT_TOLERANCE),
            high: Some(period + period * HEARTBEAT_TOLERANCE),
            criterion: format!(
                "every interval within ±{:.0} % of the {TIMING_HEARTBEAT_MS} ms producer time (canopener's bound)",
                HEARTBEAT_TOLERANCE * 100.0
            ),
        }),
    );
    let request = download_text((0x1017, 0), &TIMING_HEARTBEAT_MS.to_le_bytes());
    let worst = intervals
        .iter()
        .copied()
        .max_by(|a, b| (a - period).abs().total_cmp(&(b - period).abs()));
    ctx.performed("Heartbeat 01");
    ctx.performed("Heartbeat 02");
    Ok(match worst {
        _ if frames.len() < 7 => Finding::fail(
            format!(
                "{} heartbeats in 7.5 periods of {TIMING_HEARTBEAT_MS} ms",
                frames.len()
            ),
            Evidence {
                request,
                requirement: format!("{}: a heartbeat every producer time", req::HEARTBEAT),
                answer: format!(
                    "{} heartbeats in {} ms",
                    frames.len(),
                    u64::from(TIMING_HEARTBEAT_MS) * 15 / 2
                ),
                cause: "the producer does not run at the configured period".to_owned(),
            },
        ),
        Some(worst) if (worst - period).abs() > period * HEARTBEAT_TOLERANCE => Finding::fail(
            format!("a heartbeat interval of {worst:.1} ms at a {TIMING_HEARTBEAT_MS} ms period"),
            Evidence {
                request,
                requirement: format!(
                    "{}: a heartbeat every producer time (canopener allows ±{:.0} %)",
                    req::HEARTBEAT,
                    HEARTBEAT_TOLERANCE * 100.0
                ),
                answer: format!("intervals {}", intervals_text(&intervals)),
                cause: "the producer timer is late or sends extra heartbeats".to_owned(),
            },
        ),
        _ => Finding::pass(format!(
            "{} heartbeats, every interval within ±10 %",
            frames.len()
        )),
    })
}

fn heartbeat_off(ctx: &mut Ctx<'_, '_>) -> Outcome {
    match start_heartbeat(ctx)? {
        Ok(true) => {}
        Ok(false) => return Ok(Finding::not_applicable(NO_WRITABLE_1017)),
        Err(failed) => return Ok(failed),
    }
    let reply = ctx.write(0x1017, 0, vec![0, 0])?;
    if !matches!(reply, Reply::Done(_)) {
        return Ok(refused_unexpectedly(
            &download_text((0x1017, 0), &[0, 0]),
            &reply,
            req::HEARTBEAT,
            "1017h = 0 is always valid",
        ));
    }
    let id = ctx.id(0x700 + u16::from(ctx.node()));
    // A heartbeat already queued may still arrive right after the write.
    ctx.listen(Duration::from_millis(u64::from(TEST_HEARTBEAT_MS)), |_| false)?;
    let frames = ctx.listen(Duration::from_millis(u64::from(TEST_HEARTBEAT_MS) * 3), |f| {
        f.id() == id && !f.is_remote()
    })?;
    ctx.performed("Heartbeat 03");
    ctx.performed("Heartbeat versus guarding 02");
    Ok(if frames.is_empty() {
        Finding::pass("no heartbeat after 1017h = 0")
    } else {
        Finding::fail(
            format!("{} heartbeats after 1017h = 0", frames.len()),
            Evidence {
                request: download_text((0x1017, 0), &[0, 0]),
                requirement: format!("{}: producer time 0 disables the heartbeat", req::HEARTBEAT),
                answer: format!("{} heartbeats in {} ms", frames.len(), TEST_HEARTBEAT_MS * 3),
                cause: "the producer ignores 1017h = 0".to_owned(),
            },
        )
    })
}

fn no_guarding_with_heartbeat(ctx: &mut Ctx<'_, '_>) -> Outcome {
    if !ctx.model().entry(0x1017, 0).is_some_and(|e| e.writable()) {
        return Ok(Finding::not_applicable(NO_WRITABLE_1017));
    }
    // A long period: a heartbeat would have to come 90 % early to fall into the answer window.
    let reply = ctx.modify(0x1017, 0, GUARD_CHECK_HEARTBEAT_MS.to_le_bytes().to_vec())?;
    if !matches!(reply, Reply::Done(_)) {
        return Ok(refused_unexpectedly(
            &download_text((0x1017, 0), &GUARD_CHECK_HEARTBEAT_MS.to_le_bytes()),
            &reply,
            req::HEARTBEAT,
            "1017h is writable in the EDS",
        ));
    }
    let node = u16::from(ctx.node());
    let id = ctx.id(0x700 + node);
    let mut answers = 0;
    let period = Duration::from_millis(u64::from(GUARD_CHECK_HEARTBEAT_MS));
    for _ in 0..3 {
        // Right after a heartbeat the next one is a period away: whatever answers within 20 ms of
        // the request is a guarding answer, not the heartbeat.
        if ctx
            .wait_for(period * 2, |f| f.id() == id && !f.is_remote())?
            .is_none()
        {
            return Ok(Finding::inconclusive(
                "no heartbeat to time the guarding requests by",
            ));
        }
        // A duplicated heartbeat (a fault cia301.ec.1 judges) comes within a few milliseconds.
        ctx.listen(Duration::from_millis(5), |_| false)?;
        ctx.send_remote(0x700 + node, 1)?;
        answers += ctx
            .listen(Duration::from_millis(20), |f| f.id() == id && !f.is_remote())?
            .len();
    }
    ctx.performed("Heartbeat versus guarding 05");
    ctx.performed("Heartbeat versus guarding 07");
    Ok(if answers == 0 {
        Finding::pass("3 guarding requests, none answered")
    } else {
        Finding::fail(
            format!("{answers} answers within 20 ms of 3 guarding requests while heartbeats run"),
            Evidence {
                request: format!(
                    "1017h = {GUARD_CHECK_HEARTBEAT_MS} ms, then 3 remote frames on {:#X}",
                    0x700 + node
                ),
                requirement: format!(
                    "{}: with a producer time other than 0 the heartbeat protocol is used, not node guarding",
                    req::HEARTBEAT
                ),
                answer: format!(
                    "{answers} error control frames within 20 ms of the requests (the next heartbeat was due a period later)"
                ),
                cause: "the device answers guarding requests whatever 1017h says".to_owned(),
            },
        )
    })
}

fn guarding_toggle(ctx: &mut Ctx<'_, '_>) -> Outcome {
    if !ctx.model().has_guarding() {
        return Ok(Finding::not_applicable(
            "the EDS has no 100Ch and 100Dh (node guarding)",
        ));
    }
    if ctx.model().entry(0x1017, 0).is_some_and(|e| e.writable()) {
        ctx.modify(0x1017, 0, vec![0, 0])?;
    }
    let node = u16::from(ctx.node());
    let id = ctx.id(0x700 + node);
    let mut answers = Vec::new();
    for _ in 0..4 {
        ctx.send_remote(0x700 + node, 1)?;
        let frames = ctx.listen(Duration::from_millis(100), |f| f.id() == id && !f.is_remote())?;
        answers.push(
            frames
                .first()
                .map(|l| l.frame.data().first().copied().unwrap_or(0)),
        );
    }
    let request = format!("4 remote frames on {:#X}, 100 ms apart", 0x700 + node);
    let requirement = format!(
        "{}: each request answered with the NMT state and a toggle bit that alternates",
        req::GUARDING
    );
    let got: Vec<u8> = answers.iter().flatten().copied().collect();
    if got.len() < answers.len() {
        return Ok(Finding::fail(
            format!("{} of 4 guarding requests answered", got.len()),
            Evidence {
                request,
                requirement,
                answer: format!("answers {}", hex(&got)),
                cause: "node guarding is not served".to_owned(),
            },
        ));
    }
    let toggles_alternate = got
        .iter()
        .zip(got.iter().skip(1))
        .all(|(a, b)| (a ^ b) & 0x80 != 0);
    let state_right = got.iter().all(|b| b & 0x7F == 0x7F);
    ctx.performed("Guarding 01");
    ctx.performed("Guarding 02");
    ctx.performed("Guarding 03");
    ctx.performed("Heartbeat versus guarding 03");
    Ok(if toggles_alternate && state_right {
        Finding::pass(format!("answers {}", hex(&got)))
    } else {
        Finding::fail(
            format!("guarding answers {}", hex(&got)),
            Evidence {
                request,
                requirement: format!("{requirement}; the state is pre-operational (7Fh)"),
                answer: format!("answers {}", hex(&got)),
                cause: if toggles_alternate {
                    "the state byte is wrong"
                } else {
                    "the toggle bit does not alternate"
                }
                .to_owned(),
            },
        )
    })
}

/// The heartbeat period `cia301.ec.8` sets, in ms.
pub const PRECEDENCE_HEARTBEAT_MS: u16 = 50;
/// How long `cia301.ec.8` counts heartbeats in each phase: four periods.
pub const PRECEDENCE_WATCH: Duration = Duration::from_millis(200);

/// SDO writes of one phase: (index, value of sub-index 0).
type Writes = Vec<(u16, Vec<u8>)>;

fn heartbeat_over_guarding(ctx: &mut Ctx<'_, '_>) -> Outcome {
    // The objects hold their CiA 301 types (CCT Heartbeat versus guarding 01).
    for (index, size) in [(0x1017u16, 2usize), (0x100C, 2), (0x100D, 1)] {
        if ctx.model().entry(index, 0).is_none() {
            continue;
        }
        let reply = ctx.read(index, 0)?;
        if !matches!(&reply, Reply::Done(d) if d.len() == size) {
            return Ok(refused_unexpectedly(
                &upload_text((index, 0)),
                &reply,
                req::HEARTBEAT,
                &format!("{index:04X}h does not read as {size} byte(s)"),
            ));
        }
    }
    let writable = |ctx: &Ctx<'_, '_>, index: u16| ctx.model().entry(index, 0).is_some_and(|e| e.writable());
    if !writable(ctx, 0x1017) {
        return Ok(Finding::not_applicable(NO_WRITABLE_1017));
    }
    let mut phases: Vec<(&str, Writes)> = Vec::new();
    if writable(ctx, 0x100C) {
        phases.push(("guard time 100Ch = 0 (guarding off)", vec![(0x100C, vec![0, 0])]));
        if writable(ctx, 0x100D) {
            phases.push((
                "guard time 100Ch = 50 ms and life time factor 100Dh = 2 (guarding configured)",
                vec![(0x100C, 50u16.to_le_bytes().to_vec()), (0x100D, vec![2])],
            ));
        }
    } else {
        phases.push(("guarding parameters as they are", Vec::new()));
    }
    let period = PRECEDENCE_HEARTBEAT_MS.to_le_bytes().to_vec();
    let heartbeat = ctx.modify(0x1017, 0, period.clone())?;
    if !matches!(heartbeat, Reply::Done(_)) {
        return Ok(refused_unexpectedly(
            &download_text((0x1017, 0), &period),
            &heartbeat,
            req::HEARTBEAT,
            "1017h does not take a producer time",
        ));
    }
    // One period for the producer restarted by the write.
    ctx.listen(Duration::from_millis(u64::from(PRECEDENCE_HEARTBEAT_MS)), |_| {
        false
    })?;
    let id = ctx.id(0x700 + u16::from(ctx.node()));
    let least = (PRECEDENCE_WATCH.as_millis() / u128::from(PRECEDENCE_HEARTBEAT_MS)) as usize - 1;
    let mut seen = Vec::new();
    for (what, writes) in phases {
        for (index, data) in writes {
            let reply = ctx.modify(index, 0, data.clone())?;
            if !matches!(reply, Reply::Done(_)) {
                return Ok(Finding::inconclusive(format!(
                    "{} got {}",
                    download_text((index, 0), &data),
                    reply.describe()
                )));
            }
        }
        let frames = ctx.listen(PRECEDENCE_WATCH, |f| f.id() == id && !f.is_remote())?;
        if frames.len() < least {
            return Ok(Finding::fail(
                format!(
                    "{} heartbeats in {} ms with {what}",
                    frames.len(),
                    PRECEDENCE_WATCH.as_millis()
                ),
                Evidence {
                    request: format!(
                        "1017h = {PRECEDENCE_HEARTBEAT_MS} ms, {what}; {} ms of listening",
                        PRECEDENCE_WATCH.as_millis()
                    ),
                    requirement: format!(
                        "{}: with a producer heartbeat time set the device produces heartbeats, whatever the guarding parameters (at least {least} here)",
                        req::HEARTBEAT
                    ),
                    answer: format!("{} heartbeats", frames.len()),
                    cause: "the guarding parameters switch the heartbeat producer off".to_owned(),
                },
            ));
        }
        seen.push(format!("{} with {what}", frames.len()));
    }
    ctx.performed("Heartbeat versus guarding 01");
    ctx.performed("Heartbeat versus guarding 04");
    ctx.performed("Heartbeat versus guarding 06");
    Ok(Finding::pass(format!("heartbeats: {}", seen.join("; "))))
}

fn guarding_id_range(ctx: &mut Ctx<'_, '_>) -> Outcome {
    if !ctx.model().has_guarding() {
        return Ok(Finding::not_applicable(
            "the EDS has no 100Ch and 100Dh (node guarding)",
        ));
    }
    // Guarding is served while the heartbeat producer is off (CiA 301 §7.2.8.3.2).
    if ctx.model().entry(0x1017, 0).is_some_and(|e| e.writable()) {
        ctx.modify(0x1017, 0, vec![0, 0])?;
    }
    // A heartbeat the previous test's producer already had on its way is not an answer.
    ctx.listen(Duration::from_millis(100), |_| false)?;
    let node = ctx.node();
    // The ends of the range and the neighbours of the node under test.
    let mut others: Vec<u8> = [0u8, 1, node.wrapping_sub(1), node.saturating_add(1), 127]
        .into_iter()
        .filter(|n| *n != node && *n <= 127)
        .collect();
    others.dedup();
    for other in &others {
        ctx.send_remote(0x700 + u16::from(*other), 1)?;
    }
    let answers = ctx.listen(Duration::from_millis(100), |f| {
        !f.id().is_extended() && (0x700..=0x77F).contains(&f.id().as_raw()) && !f.is_remote()
    })?;
    let asked: Vec<String> = others
        .iter()
        .map(|n| format!("{:#X}", 0x700 + u16::from(*n)))
        .collect();
    if let Some(answer) = answers.first() {
        return Ok(Finding::fail(
            format!(
                "answered a guarding request for another node: {:#X} {}",
                answer.frame.id().as_raw(),
                hex(answer.frame.data())
            ),
            Evidence {
                request: format!("remote frames on {}", asked.join(", ")),
                requirement: format!(
                    "{}: the device answers only the guarding request on 700h + its node-ID ({:#X})",
                    req::GUARDING,
                    0x700 + u16::from(node)
                ),
                answer: format!("{} frame(s) in 100 ms", answers.len()),
                cause: "the guarding request's CAN-ID is not compared with the node-ID".to_owned(),
            },
        ));
    }
    let own = ctx.id(0x700 + u16::from(node));
    ctx.send_remote(0x700 + u16::from(node), 1)?;
    let answer = ctx.wait_for(Duration::from_millis(100), |f| f.id() == own && !f.is_remote())?;
    ctx.performed("Guarding 04");
    Ok(match answer {
        Some(answer) => Finding::pass(format!(
            "{} not answered; {:#X} answered {}",
            asked.join(", "),
            0x700 + u16::from(node),
            hex(answer.frame.data())
        )),
        None => Finding::fail(
            "its own guarding request was not answered",
            Evidence {
                request: format!("a remote frame on {:#X}", 0x700 + u16::from(node)),
                requirement: format!("{}: each guarding request is answered", req::GUARDING),
                answer: "no answer within 100 ms".to_owned(),
                cause: "node guarding is not served".to_owned(),
            },
        ),
    })
}

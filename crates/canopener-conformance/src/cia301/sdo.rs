//! SDO tests (CCT group "SDO"): expedited, segmented and block transfers, and the refusals CiA 301
//! §7.2.4.3.17 requires with their abort codes.

use canopener_master::sdo_client::DownloadMode;
use canopener_wire::abort;

use crate::context::{Ctx, Reply, hex};
use crate::device_model::{number_bytes, number_text, step_beyond};
use crate::finding::{Evidence, Finding, Outcome, Stop};
use crate::procedures::entries::writable_of_size;
use crate::procedures::sdo::{download_text, expect_refusal, refused_unexpectedly, upload_text};
use crate::requirements::{self as req, Accepted, code_meaning};
use crate::test_def::TestDef;

/// The SDO tests.
pub fn tests() -> Vec<TestDef> {
    vec![
        TestDef {
            id: "cia301.sdo.1",
            suite: "cia301",
            group: "sdo",
            title: "Read 1000h:00 (device type): the value the EDS states, and 4 bytes whether the server answers expedited or segmented",
            references: &[
                req::SDO_UPLOAD,
                req::SDO_UPLOAD_SEGMENT,
                "CCT SDO 01",
                "CCT SDO 13",
            ],
            precondition: "always (1000h is mandatory)",
            tags: &["sdo"],
            run: read_device_type,
        },
        TestDef {
            id: "cia301.sdo.2",
            suite: "cia301",
            group: "sdo",
            title: "Writing 1000h:00 (read-only) is refused",
            references: &[req::SDO_ABORT, "CCT SDO 03"],
            precondition: "1000h is not writable in the EDS",
            tags: &["sdo"],
            run: write_device_type,
        },
        TestDef {
            id: "cia301.sdo.3",
            suite: "cia301",
            group: "sdo",
            title: "Reading a write-only entry is refused",
            references: &[req::SDO_ABORT, "CCT SDO 04"],
            precondition: "the EDS has a wo entry",
            tags: &["sdo"],
            run: read_write_only,
        },
        TestDef {
            id: "cia301.sdo.4",
            suite: "cia301",
            group: "sdo",
            title: "Reading the absent sub-index 1000h:01 is refused",
            references: &[req::SDO_ABORT, "CCT SDO 05"],
            precondition: "always",
            tags: &["sdo"],
            run: read_absent_sub,
        },
        TestDef {
            id: "cia301.sdo.5",
            suite: "cia301",
            group: "sdo",
            title: "Reading an absent object is refused",
            references: &[req::SDO_ABORT, "CCT SDO 06"],
            precondition: "the EDS leaves an index of 1000h–1FFFh free",
            tags: &["sdo"],
            run: read_absent_object,
        },
        TestDef {
            id: "cia301.sdo.6",
            suite: "cia301",
            group: "sdo",
            title: "A request with an invalid command specifier is aborted",
            references: &[req::SDO_ABORT, "CCT SDO 07"],
            precondition: "always",
            tags: &["sdo"],
            run: bad_command,
        },
        TestDef {
            id: "cia301.sdo.7",
            suite: "cia301",
            group: "sdo",
            title: "Writing 4 bytes to an 8- or 16-bit entry is refused",
            references: &[req::SDO_DOWNLOAD, req::SDO_ABORT, "CCT SDO 08"],
            precondition: "the EDS has a writable UNSIGNED8/16 entry",
            tags: &["sdo", "writes"],
            run: too_long,
        },
        TestDef {
            id: "cia301.sdo.8",
            suite: "cia301",
            group: "sdo",
            title: "Writing 1 byte to a 16- or 32-bit entry is refused",
            references: &[req::SDO_DOWNLOAD, req::SDO_ABORT, "CCT SDO 09"],
            precondition: "the EDS has a writable 16/32-bit entry",
            tags: &["sdo", "writes"],
            run: too_short,
        },
        TestDef {
            id: "cia301.sdo.9",
            suite: "cia301",
            group: "sdo",
            title: "A value above CiA 301's range for the entry (1003h:00 takes only 0) or above its EDS HighLimit is refused",
            references: &[req::SDO_ABORT, req::ERROR_OBJECTS, req::EDS_OBJECTS, "CCT SDO 10"],
            precondition: "a writable entry that CiA 301's value ranges (canopener-check's rule table) or an EDS HighLimit bound below its type's maximum",
            tags: &["sdo", "writes", "limits"],
            run: above_high_limit,
        },
        TestDef {
            id: "cia301.sdo.10",
            suite: "cia301",
            group: "sdo",
            title: "A value below LowLimit is refused",
            references: &[req::SDO_ABORT, req::EDS_OBJECTS, "CCT SDO 11"],
            precondition: "the EDS has a writable entry with a LowLimit above its type's minimum",
            tags: &["sdo", "writes", "limits"],
            run: below_low_limit,
        },
        TestDef {
            id: "cia301.sdo.11",
            suite: "cia301",
            group: "sdo",
            title: "1200h:01/02 hold the default SDO COB-IDs 600h/580h + node-ID",
            references: &[req::SDO_SERVER_PARAMETER, "CCT SDO 12"],
            precondition: "the EDS has 1200h",
            tags: &["sdo"],
            run: server_parameter,
        },
        TestDef {
            id: "cia301.sdo.12",
            suite: "cia301",
            group: "sdo",
            title: "A value longer than 4 bytes reads segmented: the size indicated, alternating toggles, the last segment's unused bytes",
            references: &[
                req::SDO_UPLOAD,
                req::SDO_UPLOAD_SEGMENT,
                "CCT SDO 16",
                "CCT SDO 18",
            ],
            precondition: "the EDS has a readable entry longer than 4 bytes",
            tags: &["sdo"],
            run: segmented_read,
        },
        TestDef {
            id: "cia301.sdo.13",
            suite: "cia301",
            group: "sdo",
            title: "A segment request with the wrong toggle bit is aborted with 0503 0000h",
            references: &[req::SDO_UPLOAD_SEGMENT, req::SDO_ABORT, "CCT SDO 17"],
            precondition: "the EDS has a readable entry longer than 4 bytes",
            tags: &["sdo"],
            run: wrong_toggle,
        },
        TestDef {
            id: "cia301.sdo.14",
            suite: "cia301",
            group: "sdo",
            title: "An expedited upload indicates the entry's true size",
            references: &[req::SDO_UPLOAD],
            precondition: "the EDS has a readable 8- or 16-bit entry",
            tags: &["sdo"],
            run: expedited_size,
        },
        TestDef {
            id: "cia301.sdo.15",
            suite: "cia301",
            group: "sdo",
            title: "Block upload of 1000h:00 without CRC, and of a value longer than 4 bytes without and with CRC, reads what an ordinary upload reads",
            references: &[req::SDO_BLOCK_UPLOAD, "CCT SDO 19", "CCT SDO 22", "CCT SDO 23"],
            precondition: "block transfer is optional: a refusal of the first block upload with 0504 0001h is not_applicable; the longer value needs a readable entry longer than 4 bytes (else 1000h:00 with CRC)",
            tags: &["sdo", "block"],
            run: block_upload,
        },
        TestDef {
            id: "cia301.sdo.16",
            suite: "cia301",
            group: "sdo",
            title: "Block downloads of 100Ch and 1017h, each without and with CRC, read back the value written",
            references: &[
                req::SDO_BLOCK_DOWNLOAD,
                "CCT SDO 20",
                "CCT SDO 21",
                "CCT SDO 24",
                "CCT SDO 25",
            ],
            precondition: "a writable 2-byte 100Ch (guarding) or 1017h (heartbeat), each tried; block transfer optional (0504 0001h for the first block download → not_applicable)",
            tags: &["sdo", "block", "writes"],
            run: block_download,
        },
        TestDef {
            id: "cia301.sdo.17",
            suite: "cia301",
            group: "sdo",
            title: "Refusals carry CiA 301's specific abort code, not the general error",
            references: &[req::SDO_ABORT],
            precondition: "always",
            tags: &["sdo"],
            run: specific_abort_codes,
        },
        TestDef {
            id: "cia301.sdo.18",
            suite: "cia301",
            group: "sdo",
            title: "A block upload with block size 128 is aborted",
            references: &[req::SDO_BLOCK_UPLOAD, req::SDO_ABORT, "CCT SDO 26"],
            precondition: "always (a device without block transfer refuses with 0504 0001h, which is accepted)",
            tags: &["sdo", "block"],
            run: block_size_128,
        },
        TestDef {
            id: "cia301.sdo.19",
            suite: "cia301",
            group: "sdo",
            title: "A segmented download of 100Ch and 1017h is confirmed and reads back",
            references: &[req::SDO_DOWNLOAD_SEGMENT, "CCT SDO 14", "CCT SDO 15"],
            precondition: "a writable 2-byte 100Ch (guarding) or 1017h (heartbeat) in the EDS",
            tags: &["sdo", "writes"],
            run: segmented_download,
        },
        TestDef {
            id: "cia301.sdo.20",
            suite: "cia301",
            group: "sdo",
            title: "1201h–12FFh (further SDO servers, SDO clients) read with their types and hold their defaults after a reset communication",
            references: &[
                req::SDO_SERVER_PARAMETER,
                req::SDO_CLIENT_PARAMETER,
                "CCT SDO 28",
                "CCT SDO 29",
            ],
            precondition: "the EDS has one of 1201h–12FFh; the reset communication part changes a writable node-ID (sub-index 3) or valid COB-ID first",
            tags: &["sdo", "writes", "nmt"],
            run: further_sdo_channels,
        },
        TestDef {
            id: "cia301.sdo.21",
            suite: "cia301",
            group: "sdo",
            title: "A block upload acknowledged with sequence number 128 is aborted",
            references: &[req::SDO_BLOCK_UPLOAD, req::SDO_ABORT, "CCT SDO 27"],
            precondition: "always (a device without block transfer refuses the initiate with 0504 0001h: not_applicable)",
            tags: &["sdo", "block"],
            run: block_ack_sequence_128,
        },
    ]
}

fn read_device_type(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let reply = ctx.read(0x1000, 0)?;
    let request = upload_text((0x1000, 0));
    ctx.performed("SDO 01");
    let finding = match &reply {
        Reply::Done(data) if data.len() == 4 => match ctx
            .model()
            .entry(0x1000, 0)
            .and_then(|e| e.default.clone())
        {
            Some(expected) if expected != *data => Finding::fail(
                format!("1000h reads {}, the EDS says {}", hex(data), hex(&expected)),
                Evidence {
                    request,
                    requirement: format!("{}: 1000h holds the device type the EDS states", req::EDS_OBJECTS),
                    answer: reply.describe(),
                    cause: "the EDS and the firmware disagree on the device type / profile".to_owned(),
                },
            ),
            _ => Finding::pass(format!("device type {}", hex(data))),
        },
        Reply::Done(data) => Finding::fail(
            format!("1000h gave {} bytes, not 4", data.len()),
            Evidence {
                request,
                requirement: format!("{}: 1000h is UNSIGNED32 (4 bytes)", req::OBJECT_DICTIONARY),
                answer: reply.describe(),
                cause: "the size indicated in the upload response is wrong".to_owned(),
            },
        ),
        other => refused_unexpectedly(
            &request,
            other,
            req::SDO_UPLOAD,
            "1000h is mandatory in every device",
        ),
    };
    let Reply::Done(value) = reply else {
        return Ok(finding);
    };
    if finding.verdict != crate::model::Verdict::Pass {
        return Ok(finding);
    }
    // CCT SDO 13: the same request from a client that also takes a segmented answer.
    let either = device_type_either_way(ctx, &value)?;
    ctx.performed("SDO 13");
    Ok(either.unwrap_or(finding))
}

/// CCT SDO 13 ("read 1000h:00 with segmented transfer"): CiA 301 §7.2.4.3.6 lets the server answer
/// an initiate upload of 4 bytes expedited or segmented, so the tester sends the request and follows
/// whichever the server chooses. Either answer must give 4 bytes, `value` (what the ordinary read
/// got); a failure, or `None` when it does.
fn device_type_either_way(ctx: &mut Ctx<'_, '_>, value: &[u8]) -> Result<Option<Finding>, Stop> {
    let initiate = [0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0];
    let request = format!(
        "SDO upload 1000h:00 from a client ready for a segmented answer ({})",
        hex(&initiate)
    );
    let fail = |answer: String, requirement: &str, cause: &str| {
        Some(Finding::fail(
            format!("1000h:00: {answer}"),
            Evidence {
                request: request.clone(),
                requirement: format!("{}: {requirement}", req::SDO_UPLOAD),
                answer,
                cause: cause.to_owned(),
            },
        ))
    };
    let Some(answer) = ctx.raw_sdo(initiate)? else {
        return Ok(fail(
            "no answer".to_owned(),
            "the server answers an initiate upload",
            "the server did not answer a request it answered a moment before",
        ));
    };
    let command = answer.first().copied().unwrap_or(0);
    let mux_ok = answer.get(1..4) == Some(&[0x00, 0x10, 0x00][..]);
    if command >> 5 != 2 || !mux_ok || answer.len() != 8 {
        return Ok(fail(
            format!("the frame {}", hex(&answer)),
            "an initiate upload response (scs 2) for 1000h:00",
            "the server answers with another frame or multiplexer",
        ));
    }
    let expedited = command & 0x02 != 0;
    let sized = command & 0x01 != 0;
    if expedited {
        let size = if sized {
            4 - usize::from((command >> 2) & 0x03)
        } else {
            4
        };
        return Ok((size != 4 || answer.get(4..8) != Some(value)).then(|| {
            Finding::fail(
                format!(
                    "the expedited answer {} does not carry the 4 bytes {}",
                    hex(&answer),
                    hex(value)
                ),
                Evidence {
                    request: request.clone(),
                    requirement: format!(
                        "{}: n = 4 − size when s = 1; the value is 1000h's",
                        req::SDO_UPLOAD
                    ),
                    answer: format!("the frame {}", hex(&answer)),
                    cause: "the size or the value differs between two reads of 1000h".to_owned(),
                },
            )
        }));
    }
    // Segmented: the size (when indicated) is 4, and one segment with toggle 0, c = 1 and 3 unused
    // bytes carries the value (§7.2.4.3.7).
    if sized && answer.get(4..8) != Some(&4u32.to_le_bytes()[..]) {
        return Ok(fail(
            format!(
                "the segmented answer {} indicates another size than 4",
                hex(&answer)
            ),
            "a segmented upload indicates the size of the value, 4 bytes for 1000h",
            "the server indicates a wrong size",
        ));
    }
    let Some(segment) = ctx.raw_sdo([0x60, 0, 0, 0, 0, 0, 0, 0])? else {
        return Ok(fail(
            format!("{} and then no segment", hex(&answer)),
            "the server sends the segment the client asks for",
            "the segmented upload server stops after the initiate",
        ));
    };
    if segment.first().is_some_and(|c| c & 0xE1 == 0x00) {
        // Not the last segment: end the transfer the server still thinks is running.
        let [a, b, c, d] = abort::GENERAL_ERROR.to_le_bytes();
        ctx.send(
            0x600 + u16::from(ctx.node()),
            &[0x80, 0x00, 0x10, 0x00, a, b, c, d],
        )?;
    }
    let one_segment =
        segment.len() == 8 && segment.first() == Some(&0x07) && segment.get(1..5) == Some(value);
    Ok((!one_segment).then(|| {
        Finding::fail(
            format!("the one segment of 1000h is {}, not 07 {}", hex(&segment), hex(value)),
            Evidence {
                request: format!("{request}, then 60 00 00 00 00 00 00 00"),
                requirement: format!(
                    "{}: the last segment has c = 1, the unused bytes in n (3 for 4 bytes) and the toggle of the request",
                    req::SDO_UPLOAD_SEGMENT
                ),
                answer: format!("the frame {}", hex(&segment)),
                cause: "the segmented upload server frames a 4-byte value wrongly".to_owned(),
            },
        )
    }))
}

fn write_device_type(ctx: &mut Ctx<'_, '_>) -> Outcome {
    if ctx.model().entry(0x1000, 0).is_some_and(|e| e.writable()) {
        return Ok(Finding::not_applicable("the EDS makes 1000h writable"));
    }
    let current = match ctx.read(0x1000, 0)? {
        Reply::Done(data) => data,
        other => {
            return Ok(Finding::inconclusive(format!(
                "1000h could not be read: {}",
                other.describe()
            )));
        }
    };
    let reply = ctx.write(0x1000, 0, current.clone())?;
    ctx.performed("SDO 03");
    Ok(expect_refusal(
        &download_text((0x1000, 0), &current),
        &reply,
        req::WRITE_READ_ONLY,
        req::SDO_ABORT,
        "the server does not check the access type before writing",
    ))
}

fn read_write_only(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let Some(entry) = ctx
        .model()
        .entries
        .values()
        .find(|e| e.access == Some(canopener_eds::AccessType::Wo))
    else {
        return Ok(Finding::not_applicable("the EDS has no entry with AccessType=wo"));
    };
    let at = (entry.index, entry.sub);
    let reply = ctx.read(at.0, at.1)?;
    ctx.performed("SDO 04");
    Ok(expect_refusal(
        &upload_text(at),
        &reply,
        req::READ_WRITE_ONLY,
        req::SDO_ABORT,
        "the server does not check the access type before reading",
    ))
}

fn read_absent_sub(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let reply = ctx.read(0x1000, 1)?;
    ctx.performed("SDO 05");
    Ok(expect_refusal(
        &upload_text((0x1000, 1)),
        &reply,
        req::NO_SUB_INDEX,
        req::SDO_ABORT,
        "the server ignores the sub-index of a VAR",
    ))
}

/// An index of the communication area the EDS does not describe, 1004h (the CCT's) when free.
pub fn absent_index(ctx: &Ctx<'_, '_>) -> Option<u16> {
    std::iter::once(0x1004)
        .chain(0x1000..=0x1FFF)
        .find(|index| !ctx.model().has(*index))
}

fn read_absent_object(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let Some(index) = absent_index(ctx) else {
        return Ok(Finding::not_applicable(
            "the EDS describes every index of 1000h–1FFFh",
        ));
    };
    let reply = ctx.read(index, 0)?;
    ctx.performed("SDO 06");
    Ok(expect_refusal(
        &upload_text((index, 0)),
        &reply,
        req::NO_OBJECT,
        req::SDO_ABORT,
        "the object dictionary has an object the EDS does not describe, or the server answers for any index",
    ))
}

fn bad_command(ctx: &mut Ctx<'_, '_>) -> Outcome {
    // ccs 7 is not an SDO client command specifier (CiA 301 §7.2.4.3).
    let request = [0xE0, 0x00, 0x10, 0x00, 0, 0, 0, 0];
    let answer = ctx.raw_sdo(request)?;
    let text = format!("SDO request {} (client command specifier 7)", hex(&request));
    ctx.performed("SDO 07");
    Ok(expect_refusal(
        &text,
        &Reply::of_raw(answer),
        req::BAD_COMMAND,
        req::SDO_ABORT,
        "the server drops, misreads or wrongly aborts requests it does not know",
    ))
}

fn too_long(ctx: &mut Ctx<'_, '_>) -> Outcome {
    wrong_length(ctx, &[1, 2], "8- or 16-bit", 4, req::TOO_LONG, "SDO 08")
}

fn too_short(ctx: &mut Ctx<'_, '_>) -> Outcome {
    wrong_length(ctx, &[2, 4], "16- or 32-bit", 1, req::TOO_SHORT, "SDO 09")
}

/// Downloads `length` zero bytes to the first writable entry of one of `sizes` bytes: a length that
/// does not match the entry's type must be refused with the abort `requirement` names (CCT `case`).
fn wrong_length(
    ctx: &mut Ctx<'_, '_>,
    sizes: &[usize],
    sizes_text: &str,
    length: usize,
    requirement: Accepted,
    case: &str,
) -> Outcome {
    let Some(entry) = writable_of_size(ctx, sizes) else {
        return Ok(Finding::not_applicable(format!(
            "the EDS has no writable {sizes_text} entry"
        )));
    };
    let at = (entry.index, entry.sub);
    let data = vec![0; length];
    let reply = ctx.modify(at.0, at.1, data.clone())?;
    let bytes = if length == 1 {
        "1 byte".to_owned()
    } else {
        format!("{length} bytes")
    };
    ctx.performed(case);
    Ok(expect_refusal(
        &format!("{} ({bytes} for {})", download_text(at, &data), entry.label()),
        &reply,
        requirement,
        req::SDO_ABORT,
        "the server does not compare the length of the data with the entry's type",
    ))
}

fn above_high_limit(ctx: &mut Ctx<'_, '_>) -> Outcome {
    // CiA 301's own ranges first (the CCT's SDO 10 writes FFh to 1003h:00, which takes only 0),
    // then the EDS's HighLimit.
    let mut targets = value_rule_targets(ctx);
    targets.extend(eds_limit_target(ctx, true));
    if targets.is_empty() {
        return Ok(Finding::not_applicable(
            "neither CiA 301's value ranges (canopener-check's table) nor the EDS's HighLimits give a writable entry a value its type can hold above them",
        ));
    }
    let mut refused = Vec::new();
    for target in targets {
        let at = (target.index, target.sub);
        let reply = ctx.modify(at.0, at.1, target.data.clone())?;
        ctx.performed("SDO 10");
        let finding = expect_refusal(
            &format!("{} ({})", download_text(at, &target.data), target.why),
            &reply,
            req::TOO_HIGH,
            req::SDO_ABORT,
            &target.cause,
        );
        if finding.verdict != crate::model::Verdict::Pass {
            return Ok(finding);
        }
        refused.push(format!(
            "{:04X}h:{:02X} = {} {}",
            at.0, at.1, target.value, finding.reason
        ));
    }
    Ok(Finding::pass(refused.join("; ")))
}

fn below_low_limit(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let Some(target) = eds_limit_target(ctx, false) else {
        return Ok(Finding::not_applicable(
            "the EDS gives no writable entry a LowLimit its type can go below",
        ));
    };
    let at = (target.index, target.sub);
    let reply = ctx.modify(at.0, at.1, target.data.clone())?;
    ctx.performed("SDO 11");
    Ok(expect_refusal(
        &format!("{} ({})", download_text(at, &target.data), target.why),
        &reply,
        req::TOO_LOW,
        req::SDO_ABORT,
        &target.cause,
    ))
}

/// A value just beyond what an entry allows, and where the bound comes from.
struct LimitTarget {
    index: u16,
    sub: u8,
    data: Vec<u8>,
    value: String,
    why: String,
    cause: String,
}

/// The first writable entry with a LowLimit/HighLimit its type can exceed, and the value just
/// beyond it (HighLimit when `up`).
fn eds_limit_target(ctx: &Ctx<'_, '_>, up: bool) -> Option<LimitTarget> {
    let (entry, limit, data, value) = ctx.model().entries.values().find_map(|e| {
        let limit = if up { e.high } else { e.low }?;
        let data_type = e.data_type?;
        if !e.writable() || crate::procedures::entries::is_pdo_or_special(e.index) {
            return None;
        }
        let value = step_beyond(limit, up, data_type)?;
        Some((e, limit, number_bytes(value, data_type)?, value))
    })?;
    let name = if up { "HighLimit" } else { "LowLimit" };
    Some(LimitTarget {
        index: entry.index,
        sub: entry.sub,
        data,
        value: number_text(value),
        why: format!(
            "{} {}, {name} {} in the EDS",
            entry.label(),
            number_text(value),
            number_text(limit)
        ),
        cause: format!("the server does not check the value against the {name} its EDS states"),
    })
}

/// Writable entries with a CiA 301 value range (canopener-check's rule table) and the first value
/// above it their type can hold. PDO parameters, store/restore and SYNC objects are left to the
/// tests of their own procedures, whose refusals depend on the device's state.
fn value_rule_targets(ctx: &Ctx<'_, '_>) -> Vec<LimitTarget> {
    use canopener_eds::TypeKind;
    let model = ctx.model();
    let mut targets = Vec::new();
    for e in model.entries.values() {
        if !e.writable() || matches!(e.index, 0x1005 | 0x1010 | 0x1011 | 0x1019 | 0x1400..=0x1BFF) {
            continue;
        }
        let Some(data_type) = e.data_type else { continue };
        let (low, high, signed) = match data_type.kind() {
            Some(TypeKind::Unsigned(bits)) => (0, canopener_eds::value::range_of(bits, false).1, false),
            Some(TypeKind::Signed(bits)) => {
                let (low, high) = canopener_eds::value::range_of(bits, true);
                (low, high, true)
            }
            _ => continue,
        };
        let var = model.objects.get(&e.index).is_some_and(|o| !o.is_structured());
        for range in canopener_check::value_rules::ranges_for(e.index, e.sub, var) {
            let Some(value) = range.first_refused_above_allowed(low..=high) else {
                continue;
            };
            let number = if signed {
                canopener_od::Number::Signed(value as i64)
            } else {
                canopener_od::Number::Unsigned(value as u64)
            };
            let Some(data) = number_bytes(number, data_type) else {
                continue;
            };
            targets.push(LimitTarget {
                index: e.index,
                sub: e.sub,
                data,
                value: value.to_string(),
                why: format!("{} {value}: {} ({})", e.label(), range.text(), range.source()),
                cause: "the server does not check the value against the range CiA 301 gives the entry"
                    .to_owned(),
            });
        }
    }
    targets
}

fn server_parameter(ctx: &mut Ctx<'_, '_>) -> Outcome {
    if !ctx.model().has(0x1200) {
        return Ok(Finding::not_applicable("the EDS has no 1200h"));
    }
    let node = u32::from(ctx.node());
    for (sub, expected) in [(1u8, 0x600 + node), (2, 0x580 + node)] {
        let reply = ctx.read(0x1200, sub)?;
        ctx.performed("SDO 12");
        let request = upload_text((0x1200, sub));
        let got = match &reply {
            Reply::Done(data) if let Ok(bytes) = <[u8; 4]>::try_from(data.as_slice()) => {
                u32::from_le_bytes(bytes)
            }
            other => {
                return Ok(refused_unexpectedly(
                    &request,
                    other,
                    req::SDO_SERVER_PARAMETER,
                    "1200h is described by the EDS",
                ));
            }
        };
        if got & 0x7FF != expected {
            return Ok(Finding::fail(
                format!("1200h:{sub:02X} is {got:#010X}, not {expected:#X}"),
                Evidence {
                    request,
                    requirement: format!(
                        "{}: the default SDO uses {expected:#X}",
                        req::SDO_SERVER_PARAMETER
                    ),
                    answer: reply.describe(),
                    cause: "1200h is not filled from the node-ID".to_owned(),
                },
            ));
        }
    }
    Ok(Finding::pass(format!("600h/580h + {node}")))
}

/// A readable entry whose EDS default is longer than 4 bytes, preferring 1008h–100Ah.
pub fn long_entry(ctx: &Ctx<'_, '_>) -> Option<(u16, u8)> {
    let long = |e: &&crate::device_model::EntryModel| {
        e.readable() && e.default.as_ref().is_some_and(|d| d.len() > 4) && e.size().is_none()
    };
    let model = ctx.model();
    [0x1008u16, 0x1009, 0x100A]
        .iter()
        .filter_map(|i| model.entry(*i, 0))
        .find(long)
        .or_else(|| model.entries.values().find(long))
        .map(|e| (e.index, e.sub))
}

fn segmented_read(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let Some(at) = long_entry(ctx) else {
        return Ok(Finding::not_applicable(
            "the EDS has no readable entry longer than 4 bytes",
        ));
    };
    // The value as the client reads it, to compare the segments with.
    let expected = match ctx.read(at.0, at.1)? {
        Reply::Done(data) => data,
        other => {
            return Ok(refused_unexpectedly(
                &upload_text(at),
                &other,
                req::SDO_UPLOAD_SEGMENT,
                "a readable entry of the EDS cannot be read",
            ));
        }
    };
    let read = segments(ctx, at)?;
    ctx.performed("SDO 16");
    ctx.performed("SDO 18");
    let finding = match read {
        Ok(data) if data == expected => Finding::pass(format!(
            "{} bytes in {} segments, size indicated, toggles alternating",
            data.len(),
            data.len().div_ceil(7)
        )),
        Ok(data) => Finding::fail(
            format!(
                "{} read segment by segment differs from the same upload read by the client",
                upload_text(at)
            ),
            Evidence {
                request: upload_text(at),
                requirement: format!("{}: the segments carry the value", req::SDO_UPLOAD_SEGMENT),
                answer: format!("{} (the client read {})", hex(&data), hex(&expected)),
                cause: "the server sends different data in two reads of a constant value".to_owned(),
            },
        ),
        Err((frames, requirement, cause)) => Finding::fail(
            format!("{}: {requirement}", upload_text(at)),
            Evidence {
                request: format!("{} segment by segment", upload_text(at)),
                requirement: format!("{}: {requirement}", req::SDO_UPLOAD_SEGMENT),
                answer: frames,
                cause: cause.to_owned(),
            },
        ),
    };
    Ok(finding)
}

/// How a segmented upload went wrong: the frames, what CiA 301 requires, the likely cause.
type BrokenUpload = (String, &'static str, &'static str);

/// A segmented upload of `at` request by request (CiA 301 §7.2.4.3.6/7): the initiate response
/// must be segmented (e = 0); when it indicates the size, the segments must add up to it; each
/// segment response must carry the toggle of its request, the last one c = 1 and its unused bytes
/// in n. `Err` holds the frames, what was required and the likely cause.
fn segments(ctx: &mut Ctx<'_, '_>, at: (u16, u8)) -> Result<Result<Vec<u8>, BrokenUpload>, Stop> {
    let [lo, hi] = at.0.to_le_bytes();
    let Some(first) = ctx.raw_sdo([0x40, lo, hi, at.1, 0, 0, 0, 0])? else {
        return Ok(Err((
            "no answer".to_owned(),
            "the server answers the initiate upload",
            "the server does not answer",
        )));
    };
    let (command, size_bytes) = match *first.as_slice() {
        [command, _, _, _, s0, s1, s2, s3] if command & 0xE2 == 0x40 => (command, [s0, s1, s2, s3]),
        _ => {
            return Ok(Err((
                format!("the frame {}", hex(&first)),
                "a value longer than 4 bytes is answered with a segmented initiate response (e = 0)",
                "the server answers the initiate upload wrongly",
            )));
        }
    };
    let size = (command & 0x01 != 0).then(|| u32::from_le_bytes(size_bytes) as usize);
    let mut data = Vec::new();
    let mut frames = vec![hex(&first)];
    let mut toggle = 0u8;
    // Enough segments for the indicated size, or for any value a test reads.
    let most = size.map_or(1024, |n| n / 7 + 2);
    for _ in 0..most {
        let request = 0x60 | toggle;
        let Some(segment) = ctx.raw_sdo([request, 0, 0, 0, 0, 0, 0, 0])? else {
            return Ok(Err((
                format!("{}, then no answer", frames.join(", ")),
                "the server answers every segment request",
                "the segmented upload server stops",
            )));
        };
        frames.push(hex(&segment));
        let command = match segment.first() {
            Some(&command) if segment.len() == 8 && command >> 5 == 0 => command,
            _ => {
                return Ok(Err((
                    frames.join(", "),
                    "each segment request is answered with a segment (scs 0)",
                    "the server answers a segment request with another frame",
                )));
            }
        };
        if command & 0x10 != toggle {
            let [a, b, c, d] = abort::TOGGLE_BIT_NOT_ALTERNATED.to_le_bytes();
            ctx.send(0x600 + u16::from(ctx.node()), &[0x80, lo, hi, at.1, a, b, c, d])?;
            return Ok(Err((
                frames.join(", "),
                "each segment carries the toggle bit of the request it answers",
                "the server does not echo the toggle bit",
            )));
        }
        let last = command & 0x01 != 0;
        let unused = if last {
            usize::from((command >> 1) & 0x07)
        } else {
            0
        };
        data.extend_from_slice(segment.get(1..8 - unused).unwrap_or_default());
        if last {
            return Ok(match size {
                Some(size) if size != data.len() => Err((
                    frames.join(", "),
                    "the segments carry exactly the size the initiate response indicated",
                    "the size indicated or the unused bytes of the last segment are wrong",
                )),
                _ => Ok(data),
            });
        }
        toggle ^= 0x10;
    }
    let [a, b, c, d] = abort::GENERAL_ERROR.to_le_bytes();
    ctx.send(0x600 + u16::from(ctx.node()), &[0x80, lo, hi, at.1, a, b, c, d])?;
    Ok(Err((
        format!(
            "{} ... (no last segment)",
            frames.get(..3).unwrap_or(&frames).join(", ")
        ),
        "the last segment (c = 1) ends the transfer within the size indicated",
        "the server sends more segments than the size it indicated",
    )))
}

fn wrong_toggle(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let Some(at) = long_entry(ctx) else {
        return Ok(Finding::not_applicable(
            "the EDS has no readable entry longer than 4 bytes",
        ));
    };
    let [lo, hi] = at.0.to_le_bytes();
    let initiate = [0x40, lo, hi, at.1, 0, 0, 0, 0];
    let Some(first) = ctx.raw_sdo(initiate)? else {
        return Ok(Finding::inconclusive(format!(
            "{} got no answer",
            upload_text(at)
        )));
    };
    if first.first().is_none_or(|b| b & 0xE2 != 0x40) {
        return Ok(Finding::inconclusive(format!(
            "{} was not answered with a segmented initiate response: {}",
            upload_text(at),
            hex(&first)
        )));
    }
    // The first segment request must have toggle 0; send toggle 1.
    let segment = [0x70, 0, 0, 0, 0, 0, 0, 0];
    let answer = ctx.raw_sdo(segment)?;
    let text = format!(
        "{}, then the segment request {} (toggle 1 where 0 is due)",
        upload_text(at),
        hex(&segment)
    );
    let reply = Reply::of_raw(answer);
    ctx.performed("SDO 17");
    let finding = expect_refusal(
        &text,
        &reply,
        req::TOGGLE,
        req::SDO_UPLOAD_SEGMENT,
        "the server does not check the toggle bit of segment requests",
    );
    if !matches!(reply, Reply::Refused(_)) {
        // End the transfer the server still thinks is running.
        let [a, b, c, d] = abort::GENERAL_ERROR.to_le_bytes();
        ctx.send(0x600 + u16::from(ctx.node()), &[0x80, lo, hi, at.1, a, b, c, d])?;
    }
    Ok(finding)
}

fn expedited_size(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let model = ctx.model();
    let Some(entry) = model
        .entry(0x1001, 0)
        .filter(|e| e.readable() && e.size() == Some(1))
        .or_else(|| {
            model
                .entries
                .values()
                .find(|e| e.readable() && matches!(e.size(), Some(1 | 2)))
        })
    else {
        return Ok(Finding::not_applicable(
            "the EDS has no readable 8- or 16-bit entry",
        ));
    };
    let at = (entry.index, entry.sub);
    let size = entry.size().unwrap_or(1);
    let [lo, hi] = at.0.to_le_bytes();
    let Some(answer) = ctx.raw_sdo([0x40, lo, hi, at.1, 0, 0, 0, 0])? else {
        return Ok(Finding::inconclusive(format!(
            "{} got no answer",
            upload_text(at)
        )));
    };
    let command = answer.first().copied().unwrap_or(0);
    if command & 0xE0 != 0x40 || command & 0x02 == 0 {
        return Ok(Finding::inconclusive(format!(
            "not an expedited upload response: {}",
            hex(&answer)
        )));
    }
    // Size indicated (s = 1): n = 4 - size. Size not indicated (s = 0) is allowed.
    if command & 0x01 == 0 {
        return Ok(Finding::pass("expedited without size indication (allowed)"));
    }
    let indicated = 4 - usize::from((command >> 2) & 0x03);
    Ok(if indicated == size {
        Finding::pass(format!("{indicated} bytes indicated"))
    } else {
        Finding::fail(
            format!("the response indicates {indicated} bytes for a {size}-byte entry"),
            Evidence {
                request: upload_text(at),
                requirement: format!("{}: n = 4 − the size of the data when s = 1", req::SDO_UPLOAD),
                answer: format!("the frame {}", hex(&answer)),
                cause: "the server fills n without regard to the entry's size".to_owned(),
            },
        )
    })
}

fn block_upload(ctx: &mut Ctx<'_, '_>) -> Outcome {
    // CCT SDO 19: 1000h:00 without CRC; SDO 22: a value longer than 4 bytes without CRC (as the
    // CCT's log asks for it); SDO 23: the same with CRC. Without such a value, 1000h:00 with CRC.
    let mut steps = vec![("SDO 19", (0x1000u16, 0u8), false)];
    match long_entry(ctx) {
        Some(at) => steps.extend([("SDO 22", at, false), ("SDO 23", at, true)]),
        None => steps.push(("SDO 23", (0x1000, 0), true)),
    }
    let mut results = Vec::new();
    for (case, at, crc) in steps {
        let request = format!("SDO block upload {:04X}h:{:02X} {}", at.0, at.1, crc_text(crc));
        let expected = match ctx.read(at.0, at.1)? {
            Reply::Done(data) => data,
            other => {
                return Ok(Finding::inconclusive(format!(
                    "{} (to compare the block upload with) got {}",
                    upload_text(at),
                    other.describe()
                )));
            }
        };
        let reply = ctx.read_block(at.0, at.1, crc)?;
        let refused = reply == Reply::Refused(abort::COMMAND_SPECIFIER_INVALID);
        let finding = match reply {
            Reply::Done(data) if data == expected => {
                Finding::pass(format!("{case}: {} bytes {}", data.len(), crc_text(crc)))
            }
            Reply::Done(data) => Finding::fail(
                format!("{request} read {}, an ordinary upload {}", hex(&data), hex(&expected)),
                Evidence {
                    request,
                    requirement: format!("{}: the sub-blocks carry the value", req::SDO_BLOCK_UPLOAD),
                    answer: hex(&data),
                    cause: "the block upload server sends other data than the value".to_owned(),
                },
            ),
            other => Finding::fail(
                format!("{request}: {}", other.describe()),
                Evidence {
                    request,
                    requirement: format!(
                        "{}: the server sends the value in sub-blocks ({}), or refuses every block transfer with {}",
                        req::SDO_BLOCK_UPLOAD,
                        if crc {
                            "with a correct CRC, since the client offers it"
                        } else {
                            "the CRC field 0: the client asked for none"
                        },
                        req::NO_BLOCK_TRANSFER.list()
                    ),
                    answer: other.describe(),
                    cause: "the block upload server is broken (CRC, sequence numbers, end frame), or serves block \
                            transfers only with (or only without) CRC"
                        .to_owned(),
                },
            ),
        };
        results.push((case, refused, finding));
    }
    Ok(block_verdict(ctx, results))
}

/// `with CRC` / `without CRC`.
fn crc_text(crc: bool) -> &'static str {
    if crc { "with CRC" } else { "without CRC" }
}

/// The verdict on block transfer steps (CCT case, refused with 0504 0001h, finding): a device that
/// refuses every one with 0504 0001h has no block transfer (optional, not_applicable); one that
/// serves some must serve all, since CRC is negotiated and a client may ask for none. Records the
/// cases performed.
fn block_verdict(ctx: &mut Ctx<'_, '_>, results: Vec<(&str, bool, Finding)>) -> Finding {
    if results.iter().all(|(_, refused, _)| *refused) {
        return Finding::not_applicable(
            "the device has no block transfer: every block request was refused with 0504 0001h",
        );
    }
    for (case, _, _) in &results {
        ctx.performed(case);
    }
    let passed: Vec<String> = results
        .iter()
        .filter(|(_, _, f)| f.verdict == crate::model::Verdict::Pass)
        .map(|(_, _, f)| f.reason.clone())
        .collect();
    match results
        .into_iter()
        .find(|(_, _, f)| f.verdict != crate::model::Verdict::Pass)
    {
        Some((_, _, failed)) => failed,
        None => Finding::pass(passed.join("; ")),
    }
}

fn block_download(ctx: &mut Ctx<'_, '_>) -> Outcome {
    // CCT SDO 20/24: 100Ch (guarding) without and with CRC; SDO 21/25: 1017h (heartbeat).
    let model = ctx.model();
    let targets: Vec<((u16, u8), [&str; 2])> = [
        ((0x100Cu16, 0u8), ["SDO 20", "SDO 24"]),
        ((0x1017, 0), ["SDO 21", "SDO 25"]),
    ]
    .into_iter()
    .filter(|((i, s), _)| {
        model
            .entry(*i, *s)
            .is_some_and(|e| e.writable() && e.size() == Some(2))
    })
    .collect();
    if targets.is_empty() {
        return Ok(Finding::not_applicable(
            "the EDS has no writable 2-byte 100Ch or 1017h",
        ));
    }
    let mut results = Vec::new();
    for (at, cases) in targets {
        for (case, crc) in cases.into_iter().zip([false, true]) {
            let what = format!("block ({})", crc_text(crc));
            let value = 1234u16.to_le_bytes().to_vec();
            let mut refused = false;
            let finding = match download_and_read_back(
                ctx,
                at,
                value,
                Transfer::Block { crc },
                &what,
                req::SDO_BLOCK_DOWNLOAD,
            )? {
                Err(Reply::Refused(code)) => {
                    refused = code == abort::COMMAND_SPECIFIER_INVALID;
                    refused_unexpectedly(
                        &format!("SDO {what} download {:04X}h:{:02X}", at.0, at.1),
                        &Reply::Refused(code),
                        req::SDO_BLOCK_DOWNLOAD,
                        "the block download server is broken, or serves block transfers only with (or only without) CRC",
                    )
                }
                Err(other) => {
                    return Ok(Finding::inconclusive(format!(
                        "{} failed: {}",
                        upload_text(at),
                        other.describe()
                    )));
                }
                Ok(finding) => finding,
            };
            let finding = match finding.verdict {
                crate::model::Verdict::Pass => Finding::pass(format!("{case}: {:04X}h {what}", at.0)),
                _ => finding,
            };
            results.push((case, refused, finding));
        }
    }
    Ok(block_verdict(ctx, results))
}

fn segmented_download(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let model = ctx.model();
    let targets: Vec<((u16, u8), &str)> = [((0x100Cu16, 0u8), "SDO 14"), ((0x1017, 0), "SDO 15")]
        .into_iter()
        .filter(|((i, s), _)| {
            model
                .entry(*i, *s)
                .is_some_and(|e| e.writable() && e.size() == Some(2))
        })
        .collect();
    if targets.is_empty() {
        return Ok(Finding::not_applicable("the EDS has no writable 100Ch or 1017h"));
    }
    let mut done = Vec::new();
    for (at, case) in targets {
        let value = 1234u16.to_le_bytes().to_vec();
        match download_and_read_back(
            ctx,
            at,
            value,
            Transfer::Segmented,
            "segmented",
            req::SDO_DOWNLOAD_SEGMENT,
        )? {
            Err(other) => {
                return Ok(Finding::inconclusive(format!(
                    "{} failed: {}",
                    upload_text(at),
                    other.describe()
                )));
            }
            Ok(finding) => {
                ctx.performed(case);
                if finding.verdict != crate::model::Verdict::Pass {
                    return Ok(finding);
                }
                done.push(format!("{:04X}h", at.0));
            }
        }
    }
    Ok(Finding::pass(format!(
        "{} written by segmented download and read back",
        done.join(" and ")
    )))
}

/// How [`download_and_read_back`] writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Transfer {
    Segmented,
    Block { crc: bool },
}

/// Writes `value` to `at` by `transfer` (`what` names it), reads it back and writes the original
/// value back with an ordinary download (the test must not depend on the write path under test).
/// `Err` holds the answer to the first read when the entry cannot be read, or a block download's
/// refusal, which the caller judges (0504 0001h: no block transfer at all).
fn download_and_read_back(
    ctx: &mut Ctx<'_, '_>,
    at: (u16, u8),
    value: Vec<u8>,
    transfer: Transfer,
    what: &str,
    clause: &str,
) -> Result<Result<Finding, Reply>, Stop> {
    let original = match ctx.read(at.0, at.1)? {
        Reply::Done(data) => data,
        other => return Ok(Err(other)),
    };
    let reply = match transfer {
        Transfer::Segmented => ctx.write_with(at.0, at.1, value.clone(), DownloadMode::Segmented)?,
        Transfer::Block { crc } => ctx.write_block(at.0, at.1, value.clone(), crc)?,
    };
    let request = format!("SDO {what} download {:04X}h:{:02X} = {}", at.0, at.1, hex(&value));
    let finding = match reply {
        Reply::Refused(_) if matches!(transfer, Transfer::Block { .. }) => {
            return Ok(Err(reply));
        }
        Reply::Done(_) => match ctx.read(at.0, at.1)? {
            Reply::Done(back) if back == value => {
                Finding::pass(format!("written by {what} download and read back"))
            }
            other => Finding::fail(
                format!("the value written by {what} download does not read back"),
                Evidence {
                    request: format!("{request}, then {}", upload_text(at)),
                    requirement: format!("{clause}: a confirmed download stores the value"),
                    answer: other.describe(),
                    cause: format!("the {what} download server confirms without storing"),
                },
            ),
        },
        other => refused_unexpectedly(
            &request,
            &other,
            clause,
            &format!("the {what} download server is broken"),
        ),
    };
    ctx.write(at.0, at.1, original)?;
    Ok(Ok(finding))
}

fn specific_abort_codes(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let Some(index) = absent_index(ctx) else {
        return Ok(Finding::not_applicable(
            "the EDS describes every index of 1000h–1FFFh",
        ));
    };
    let reply = ctx.read(index, 0)?;
    Ok(match reply {
        Reply::Refused(abort::OBJECT_DOES_NOT_EXIST) => Finding::pass("0602 0000h for an absent object"),
        other => Finding::fail(
            format!("an absent object gave {}, not 0602 0000h", other.describe()),
            Evidence {
                request: upload_text((index, 0)),
                requirement: format!(
                    "{}: the abort code names the reason; {} for an object that does not exist",
                    req::SDO_ABORT,
                    code_meaning(abort::OBJECT_DOES_NOT_EXIST)
                ),
                answer: other.describe(),
                cause:
                    "the server answers every refusal with one code (typically the general error 0800 0000h)"
                        .to_owned(),
            },
        ),
    })
}

fn block_size_128(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let at = long_entry(ctx).unwrap_or((0x1000, 0));
    let [lo, hi] = at.0.to_le_bytes();
    // Initiate block upload (ccs 5, CRC offered) with blksize 128: CiA 301 allows 1..127.
    let request = [0xA4, lo, hi, at.1, 128, 0, 0, 0];
    let answer = ctx.raw_sdo(request)?;
    let text = format!(
        "SDO block upload initiate {} of {:04X}h:{:02X} (block size 128)",
        hex(&request),
        at.0,
        at.1
    );
    let reply = Reply::of_raw(answer);
    if !matches!(reply, Reply::Refused(_)) {
        // End whatever the server started.
        let [a, b, c, d] = abort::INVALID_BLOCK_SIZE.to_le_bytes();
        ctx.send(0x600 + u16::from(ctx.node()), &[0x80, lo, hi, at.1, a, b, c, d])?;
    }
    ctx.performed("SDO 26");
    Ok(expect_refusal(
        &text,
        &reply,
        req::BLOCK_SIZE,
        req::SDO_BLOCK_UPLOAD,
        "the server does not check the client's block size (1..127)",
    ))
}

fn further_sdo_channels(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let entries: Vec<_> = ctx
        .model()
        .entries
        .values()
        .filter(|e| (0x1201..=0x12FF).contains(&e.index) && e.readable())
        .cloned()
        .collect();
    if entries.is_empty() {
        return Ok(Finding::not_applicable("the EDS has none of 1201h–12FFh"));
    }
    let clause = |index: u16| {
        if index < 0x1280 {
            req::SDO_SERVER_PARAMETER
        } else {
            req::SDO_CLIENT_PARAMETER
        }
    };
    // CCT SDO 28: every entry reads with its type's size.
    let mut current = Vec::new();
    for e in &entries {
        let reply = ctx.read(e.index, e.sub)?;
        match (&reply, e.size()) {
            (Reply::Done(d), Some(size)) if d.len() != size => {
                return Ok(Finding::fail(
                    format!("{} reads as {} bytes, its type has {size}", e.label(), d.len()),
                    Evidence {
                        request: upload_text((e.index, e.sub)),
                        requirement: format!("{}: the entry has the type CiA 301 gives it", clause(e.index)),
                        answer: reply.describe(),
                        cause: "the SDO channel parameter has the wrong type".to_owned(),
                    },
                ));
            }
            (Reply::Done(d), _) => current.push((e, d.clone())),
            _ => {
                return Ok(refused_unexpectedly(
                    &upload_text((e.index, e.sub)),
                    &reply,
                    clause(e.index),
                    "a readable SDO channel parameter cannot be read",
                ));
            }
        }
    }
    ctx.performed("SDO 28");
    // CCT SDO 29: change one value, reset communication, and every default is back. A node-ID
    // (sub-index 3) or a valid COB-ID (made invalid) can always change (CiA 301 §7.5.2.33/34).
    let change = current.iter().find_map(|(e, d)| {
        if !e.writable() {
            return None;
        }
        match (e.sub, d.as_slice()) {
            (3, [node]) => Some((e.index, e.sub, vec![if *node == 1 { 2 } else { 1 }])),
            (1 | 2, [a, b, c, d]) if d & 0x80 == 0 => Some((e.index, e.sub, vec![*a, *b, *c, d | 0x80])),
            _ => None,
        }
    });
    let mut changed = None;
    if let Some((index, sub, value)) = change
        && matches!(ctx.modify(index, sub, value.clone())?, Reply::Done(_))
    {
        changed = Some(download_text((index, sub), &value));
    }
    if !crate::procedures::nmt::reset_communication(ctx)? {
        return Ok(Finding::inconclusive("no boot-up after the reset communication"));
    }
    ctx.performed("SDO 29");
    for e in &entries {
        let Some(default) = &e.default else { continue };
        let reply = ctx.read(e.index, e.sub)?;
        if !matches!(&reply, Reply::Done(d) if d == default) {
            return Ok(Finding::fail(
                format!("{} is not its default after a reset communication", e.label()),
                Evidence {
                    request: format!(
                        "{}NMT reset communication, {}",
                        changed.as_ref().map_or(String::new(), |c| format!("{c}, ")),
                        upload_text((e.index, e.sub))
                    ),
                    requirement: format!(
                        "{}: reset communication sets the communication parameters to their power-on values ({} by the EDS)",
                        req::NMT_MODULE_CONTROL,
                        hex(default)
                    ),
                    answer: reply.describe(),
                    cause: "the SDO channel parameters are not reset with the communication area".to_owned(),
                },
            ));
        }
    }
    Ok(Finding::pass(format!(
        "{} entries read with their types; defaults back after a reset communication{}",
        entries.len(),
        changed.map_or(String::new(), |c| format!(" (after {c})"))
    )))
}

/// The block size `cia301.sdo.21` asks for.
const ACK_TEST_BLOCK: u8 = 4;

fn block_ack_sequence_128(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let at = long_entry(ctx).unwrap_or((0x1000, 0));
    let [lo, hi] = at.0.to_le_bytes();
    let node = u16::from(ctx.node());
    // Initiate block upload (ccs 5, CRC offered, no protocol switch), block size 4.
    let initiate = [0xA4, lo, hi, at.1, ACK_TEST_BLOCK, 0, 0, 0];
    let text = format!(
        "SDO block upload initiate {} of {:04X}h:{:02X}",
        hex(&initiate),
        at.0,
        at.1
    );
    match Reply::of_raw(ctx.raw_sdo(initiate)?) {
        // scs 6 (block upload), ss 0 (initiate).
        Reply::Frame(d) if d.first().is_some_and(|b| b & 0xE1 == 0xC0) => {}
        Reply::Refused(abort::COMMAND_SPECIFIER_INVALID) => {
            return Ok(Finding::not_applicable(
                "the device has no block transfer (0504 0001h)",
            ));
        }
        other => {
            if matches!(other, Reply::Frame(_)) {
                // End whatever the server started.
                let [a, b, c, d] = abort::COMMAND_SPECIFIER_INVALID.to_le_bytes();
                ctx.send(0x600 + node, &[0x80, lo, hi, at.1, a, b, c, d])?;
            }
            return Ok(refused_unexpectedly(
                &text,
                &other,
                req::SDO_BLOCK_UPLOAD,
                "the block upload server is broken",
            ));
        }
    }
    // Start: the server sends sub-blocks with sequence numbers 1..block size, the last one of the
    // value with bit 7 set (CiA 301 §7.2.4.3.14).
    ctx.send(0x600 + node, &[0xA3, 0, 0, 0, 0, 0, 0, 0])?;
    let response = ctx.id(0x580 + node);
    let mut last_seq = 0;
    // At most one sub-block's segments, within one timeout per segment: a server that keeps
    // sending cannot keep the test waiting.
    let deadline = ctx.now() + ctx.timeout() * u32::from(ACK_TEST_BLOCK);
    for _ in 0..ACK_TEST_BLOCK {
        let timeout = deadline.saturating_duration_since(ctx.now());
        let Some(segment) = ctx.wait_for(timeout, |f| f.id() == response && !f.is_remote())? else {
            break;
        };
        let data = segment.frame.data();
        last_seq = data.first().map_or(0, |b| b & 0x7F);
        if data.first().is_some_and(|b| b & 0x80 != 0) || last_seq >= ACK_TEST_BLOCK {
            break;
        }
    }
    if last_seq == 0 {
        return Ok(Finding::inconclusive(format!(
            "no sub-block after the start of the block upload ({text})"
        )));
    }
    // Acknowledge sequence number 128: no sub-block has it (1..127, and the block size was 4).
    let ack = [0xA2, 128, ACK_TEST_BLOCK, 0, 0, 0, 0, 0];
    let reply = Reply::of_raw(ctx.raw_sdo(ack)?);
    if !matches!(reply, Reply::Refused(_)) {
        let [a, b, c, d] = abort::INVALID_SEQUENCE_NUMBER.to_le_bytes();
        ctx.send(0x600 + node, &[0x80, lo, hi, at.1, a, b, c, d])?;
    }
    ctx.performed("SDO 27");
    Ok(expect_refusal(
        &format!(
            "{text}, start, {last_seq} sub-block(s) received, block acknowledge {}",
            hex(&ack)
        ),
        &reply,
        req::SEQUENCE_NUMBER,
        req::SDO_BLOCK_UPLOAD,
        "the server does not check the acknowledged sequence number",
    ))
}

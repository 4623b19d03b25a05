//! Response times: SDO read and write of a type-I object, TPDO on RTR, boot-up after reset node, and
//! the confirmed LSS services.

use std::time::Duration;

use canopener_wire::NmtCommand;

use super::{BOOT_UPS, Clock, Criterion, Judged, Outgoing, Timed, exchange, judge, standard_id, unusable};
use crate::procedures::nmt::BOOT_UP_WAIT;
use crate::procedures::nmt::back_to_pre_operational;
use crate::procedures::sdo::{download_text, read_described, u32_of, upload_text};
use canopener_wire::{LSS_MASTER_TO_SLAVE_ID, LssAddress, LssAddressPart, LssRequest};

use crate::context::{Ctx, Reply};
use crate::device_model::PdoDirection;
use crate::finding::{Evidence, Finding, Outcome, Prepared, Stop};
use crate::procedures::lss::{answer_specifier, is_lss_answer};
use crate::requirements as req;

/// How long a TPDO may take to answer a remote frame before the test calls it missing (as
/// `cia301.pdo.3` does).
const RTR_WAIT: Duration = Duration::from_millis(100);

pub(super) fn sdo_read(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let Some((index, sub, _)) = (match type_one(ctx, [PdoDirection::Transmit, PdoDirection::Receive], false)?
    {
        Ok(found) => found,
        Err(failed) => return Ok(failed),
    }) else {
        return Ok(Finding::not_applicable(
            "no PDO mapping (1600h–17FFh, 1A00h–1BFFh as read) names an object the EDS makes readable with at most 4 bytes: no type-I object to read",
        ));
    };
    let [lo, hi] = index.to_le_bytes();
    let request = [0x40, lo, hi, sub, 0, 0, 0, 0];
    let criterion = Criterion::at_most(ctx, "sdo.read_max_ms", ctx.performance().criteria.sdo_read_max_ms);
    sdo_repeated(
        ctx,
        (index, sub),
        request,
        0x40,
        &upload_text((index, sub)),
        "sdo_read_response",
        criterion,
    )
}

pub(super) fn sdo_write(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let Some((index, sub, size)) =
        (match type_one(ctx, [PdoDirection::Receive, PdoDirection::Transmit], true)? {
            Ok(found) => found,
            Err(failed) => return Ok(failed),
        })
    else {
        return Ok(Finding::not_applicable(
            "no PDO mapping (1600h–17FFh, 1A00h–1BFFh as read) names an object the EDS makes writable with at most 4 bytes: no type-I object to write",
        ));
    };
    // The object's own value: the measurement changes nothing, and `modify` writes it back anyway.
    let value = match ctx.read(index, sub)? {
        Reply::Done(value) if !value.is_empty() && value.len() <= 4 => value,
        Reply::Done(value) if size > 0 && size <= 4 => {
            value.into_iter().chain(std::iter::repeat(0)).take(size).collect()
        }
        other => return Ok(unusable(&upload_text((index, sub)), &other)),
    };
    let reply = ctx.modify(index, sub, value.clone())?;
    if !matches!(reply, Reply::Done(_)) {
        return Ok(unusable(&download_text((index, sub), &value), &reply));
    }
    let [lo, hi] = index.to_le_bytes();
    // Expedited download with the size indicated: 23h, 27h, 2Bh or 2Fh for 4, 3, 2 or 1 bytes.
    let mut request = [0x23 | ((4 - value.len() as u8) << 2), lo, hi, sub, 0, 0, 0, 0];
    // The value has 1 to 4 bytes (above), so it fits D4..D7.
    for (slot, byte) in request.iter_mut().skip(4).zip(&value) {
        *slot = *byte;
    }
    let criterion = Criterion::at_most(
        ctx,
        "sdo.write_max_ms",
        ctx.performance().criteria.sdo_write_max_ms,
    );
    let text = download_text((index, sub), &value);
    sdo_repeated(
        ctx,
        (index, sub),
        request,
        0x60,
        &text,
        "sdo_write_response",
        criterion,
    )
}

/// Sends `request` to the SDO server as often as the run repeats; each answer must be the initiate
/// response `expected` (its command specifier's upper 3 bits), an abort stops the measurement.
fn sdo_repeated(
    ctx: &mut Ctx<'_, '_>,
    entry: (u16, u8),
    request: [u8; 8],
    expected: u8,
    text: &str,
    name: &str,
    criterion: Option<Criterion>,
) -> Outcome {
    let node = u16::from(ctx.node());
    let response = 0x580 + node;
    let timeout = ctx.timeout();
    let mut samples = Vec::new();
    for repetition in 0..ctx.performance().repetitions.max(1) {
        let answer = exchange(ctx, Outgoing::Data(0x600 + node, &request), timeout, |f| {
            standard_id(f) == Some(response) && !f.is_remote()
        })?;
        match answer {
            Some((ms, frame)) if frame.data().first().is_some_and(|cs| cs & 0xE0 == expected) => {
                samples.push(ms)
            }
            Some((_, frame)) => {
                return Ok(unusable(
                    &format!("{text} (repetition {})", repetition + 1),
                    &Reply::of_raw(Some(frame.data().to_vec())),
                ));
            }
            None => {
                return Ok(Finding::fail(
                    format!(
                        "no SDO response to repetition {} of {text} within {} ms",
                        repetition + 1,
                        timeout.as_millis()
                    ),
                    Evidence {
                        request: format!("{text}, repeated; {} answered", samples.len()),
                        requirement: format!("{}: the SDO server answers every request", req::SDO_UPLOAD),
                        answer: format!("nothing on {response:#X} within {} ms", timeout.as_millis()),
                        cause: "the SDO server lost a request, or answers slower than the SDO timeout"
                            .to_owned(),
                    },
                ));
            }
        }
    }
    let what = format!(
        "{} response time of {:04X}h:{:02X}",
        if expected == 0x40 {
            "SDO upload"
        } else {
            "SDO download"
        },
        entry.0,
        entry.1
    );
    Ok(judge(
        ctx,
        Judged {
            name,
            what,
            request: format!(
                "{text}, {} times, each after the previous response",
                samples.len()
            ),
            clause: req::SDO_UPLOAD,
            cause: "the SDO server's turnaround is slower than the criterion",
            clock: Clock::Link,
        },
        samples,
        criterion,
    ))
}

/// The first object a PDO of `directions` (in that order) maps that the EDS makes readable (or
/// writable) with at most 4 bytes: a type-I object (CiA 313; the thesis §4.2.2: objects mapped into
/// PDOs define what the device is for). The mapping is read from the device; a mapping parameter the
/// EDS describes and the device does not serve fails the test.
fn type_one(
    ctx: &mut Ctx<'_, '_>,
    directions: [PdoDirection; 2],
    writable: bool,
) -> Prepared<Option<(u16, u8, usize)>> {
    for direction in directions {
        for pdo in ctx.model().pdos(direction) {
            let Some(mapping) = pdo.mapping else { continue };
            if !ctx.model().entry(mapping, 0).is_some_and(|e| e.readable()) {
                continue;
            }
            let count = match read_described(ctx, mapping, 0, "the number of mapped objects")? {
                // A longer expedited answer is cia301.sdo.14's to judge; the count is the first byte.
                Ok(value) => value.first().copied().unwrap_or(0).min(64),
                Err(failed) => return Ok(Err(failed)),
            };
            for sub in 1..=count {
                if !ctx.model().entry(mapping, sub).is_some_and(|e| e.readable()) {
                    continue;
                }
                let entry = match read_described(ctx, mapping, sub, "a mapping entry")? {
                    Ok(value) => u32_of(&Reply::Done(value)),
                    Err(failed) => return Ok(Err(failed)),
                };
                let Some(entry) = entry else { continue };
                let (index, object_sub) = ((entry >> 16) as u16, (entry >> 8) as u8);
                let Some(model) = ctx.model().entry(index, object_sub) else {
                    continue;
                };
                let usable = if writable {
                    model.writable()
                } else {
                    model.readable()
                };
                let size = model.size().unwrap_or(usize::from((entry & 0xFF) as u8) / 8);
                // Dummy entries (below 1000h) map no object.
                if index >= 0x1000 && usable && (1..=4).contains(&size) {
                    return Ok(Ok(Some((index, object_sub, size))));
                }
            }
        }
    }
    Ok(Ok(None))
}

pub(super) fn rtr(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let Some((number, cob, kind)) = (match rtr_tpdo(ctx)? {
        Ok(found) => found,
        Err(failed) => return Ok(failed),
    }) else {
        return Ok(Finding::not_applicable(
            "no TPDO allows RTR as the device is configured: every one that maps data has 18xxh:01 bit 30 (no RTR, which CiA 301 allows) or bit 31 (not valid) set",
        ));
    };
    ctx.nmt(NmtCommand::StartRemoteNode, false)?;
    // A synchronous TPDO answers a remote request with the data sampled at the last SYNC (CiA 301
    // §7.2.2): one SYNC first, so that there is some.
    if kind <= 240 || kind == 252 {
        let sync = match u32_of(&ctx.read(0x1005, 0)?) {
            Some(sync) => (sync & 0x7FF) as u16,
            None => 0x80,
        };
        ctx.send(sync, &[])?;
    }
    ctx.listen(Duration::from_millis(20), |_| false)?;
    let mut samples = Vec::new();
    let mut missing = None;
    for repetition in 0..ctx.performance().repetitions.max(1) {
        match exchange(ctx, Outgoing::Remote(cob), RTR_WAIT, |f| {
            standard_id(f) == Some(cob) && !f.is_remote()
        })? {
            Some((ms, _)) => samples.push(ms),
            None => {
                missing = Some(repetition + 1);
                break;
            }
        }
    }
    back_to_pre_operational(ctx)?;
    let request = format!(
        "TPDO{number} as configured (transmission type {kind:02X}h, RTR allowed); NMT start, a SYNC for synchronous types, then remote frames on {cob:#X}"
    );
    if let Some(repetition) = missing {
        return Ok(Finding::fail(
            format!("TPDO{number} ({cob:#X}) did not answer remote frame {repetition}"),
            Evidence {
                request,
                requirement: format!(
                    "{}: a TPDO whose COB-ID allows RTR (bit 30 = 0) is sent on request",
                    req::PDO
                ),
                answer: format!(
                    "{} answers, then nothing within {} ms",
                    samples.len(),
                    RTR_WAIT.as_millis()
                ),
                cause: "remote requests on TPDOs are not served although 18xxh allows them".to_owned(),
            },
        ));
    }
    let criterion = Criterion::at_most(
        ctx,
        "pdo.rtr_response_max_ms",
        ctx.performance().criteria.rtr_response_max_ms,
    );
    Ok(judge(
        ctx,
        Judged {
            name: "rtr_response",
            what: format!("TPDO{number} RTR response time"),
            request,
            clause: req::PDO,
            cause: "the device samples and sends the TPDO slower than the criterion",
            clock: Clock::Link,
        },
        samples,
        criterion,
    ))
}

pub(super) fn boot_up(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let node = ctx.node();
    let boot = 0x700 + u16::from(node);
    let mut samples = Vec::new();
    for repetition in 0..ctx.performance().repetitions.clamp(1, BOOT_UPS) {
        let answer = exchange(ctx, Outgoing::Nmt(NmtCommand::ResetNode), BOOT_UP_WAIT, |f| {
            standard_id(f) == Some(boot) && f.data() == [0]
        })?;
        let Some((ms, _)) = answer else {
            return Ok(Finding::fail(
                format!(
                    "no boot-up within {} s of NMT reset node {}",
                    BOOT_UP_WAIT.as_secs(),
                    repetition + 1
                ),
                Evidence {
                    request: format!("NMT reset node {node} (000h: 81h {node:02X}h)"),
                    requirement: format!(
                        "{}: after reset node the device enters pre-operational and sends the boot-up message (700h + node-ID, 00h)",
                        req::BOOT_UP
                    ),
                    answer: format!("{} boot-ups, then none on {boot:#X}", samples.len()),
                    cause: "the boot-up message is not sent, or on another CAN-ID".to_owned(),
                },
            ));
        };
        samples.push(ms);
        // What the device sends right after booting (a TPDO, a heartbeat) is not measured.
        ctx.listen(Duration::from_millis(20), |_| false)?;
    }
    let criterion = Criterion::at_most(ctx, "boot_up.max_ms", ctx.performance().criteria.boot_up_max_ms);
    Ok(judge(
        ctx,
        Judged {
            name: "boot_up",
            what: "boot-up time".to_owned(),
            request: format!("NMT reset node {node}, {} times", samples.len()),
            clause: req::BOOT_UP,
            cause: "the device's initialisation is slower than the criterion",
            clock: Clock::Link,
        },
        samples,
        criterion,
    ))
}

/// The first valid TPDO (COB-ID bit 31 clear) that allows RTR (bit 30 clear, CiA 301 §7.5.2.37) and
/// maps data, as the device is configured: (number, CAN-ID, transmission type). Nothing is changed:
/// RTR is optional, and the test measures the device as it is set up. A parameter the EDS describes
/// and the device does not serve fails the test.
fn rtr_tpdo(ctx: &mut Ctx<'_, '_>) -> Prepared<Option<(u16, u16, u8)>> {
    for pdo in ctx.model().pdos(PdoDirection::Transmit) {
        let Some(mapping) = pdo.mapping else { continue };
        let model = ctx.model();
        let readable = |index: u16, sub: u8| model.entry(index, sub).is_some_and(|e| e.readable());
        if !(readable(pdo.comm, 1) && readable(pdo.comm, 2) && readable(mapping, 0)) {
            continue;
        }
        let mut values = Vec::new();
        for (index, sub, what) in [
            (pdo.comm, 1, "the TPDO's COB-ID"),
            (pdo.comm, 2, "the TPDO's transmission type"),
            (mapping, 0, "the number of mapped objects"),
        ] {
            match read_described(ctx, index, sub, what)? {
                Ok(value) => values.push(value),
                Err(failed) => return Ok(Err(failed)),
            }
        }
        let [cob, kind, mapped] = <[Vec<u8>; 3]>::try_from(values).unwrap_or_default();
        let cob = u32_of(&Reply::Done(cob));
        let kind = kind.first().copied();
        let mapped = mapped.first().is_some_and(|n| *n > 0);
        if let (Some(cob), Some(kind)) = (cob, kind)
            && cob & 0xC000_0000 == 0
            && cob & 0x7FF != 0
            && mapped
        {
            return Ok(Ok(Some((pdo.number, (cob & 0x7FF) as u16, kind))));
        }
    }
    Ok(Ok(None))
}

/// The inquire services measured (CiA 305: the answer has the request's command specifier), with
/// their measurement names.
const LSS_SERVICES: [(LssRequest, &str); 5] = [
    (
        LssRequest::InquireAddress(LssAddressPart::VendorId),
        "inquire_vendor_id",
    ),
    (
        LssRequest::InquireAddress(LssAddressPart::ProductCode),
        "inquire_product_code",
    ),
    (
        LssRequest::InquireAddress(LssAddressPart::RevisionNumber),
        "inquire_revision",
    ),
    (
        LssRequest::InquireAddress(LssAddressPart::SerialNumber),
        "inquire_serial",
    ),
    (LssRequest::InquireNodeId, "inquire_node_id"),
];

pub(super) fn lss(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let address = match crate::procedures::lss::prepare(ctx)? {
        Ok(address) => address,
        Err(finding) => return Ok(finding),
    };
    let repetitions = ctx.performance().repetitions.max(1);
    let timeout = ctx.timeout();
    let mut measured = Vec::new();
    let mut failure = None;
    switch_global(ctx, true)?;
    for (request, name) in LSS_SERVICES {
        let cs = answer_specifier(&request);
        match lss_samples(ctx, repetitions, &mut |ctx| {
            exchange(
                ctx,
                Outgoing::Data(LSS_MASTER_TO_SLAVE_ID, &request.encode()),
                timeout,
                |f| is_lss_answer(f, cs),
            )
        })? {
            Ok(samples) => measured.push((name, format!("{name} ({cs:02X}h)"), samples)),
            Err(answered) => {
                failure = Some((format!("{name} ({cs:02X}h) in configuration state"), answered));
                break;
            }
        }
    }
    switch_global(ctx, false)?;
    if failure.is_none() {
        match lss_samples(ctx, repetitions, &mut |ctx| selective(ctx, &address, timeout))? {
            Ok(samples) => measured.push((
                "switch_selective",
                "switch state selective (43h → 44h)".to_owned(),
                samples,
            )),
            Err(answered) => {
                failure = Some((
                    "switch state selective (40h–43h with the device's address)".to_owned(),
                    answered,
                ))
            }
        }
        switch_global(ctx, false)?;
    }
    if let Some((service, answered)) = failure {
        return Ok(Finding::fail(
            format!("no answer to {service} after {answered} answers"),
            Evidence {
                request: format!("{service}, repeated"),
                requirement: "CiA 305 v3.0: a confirmed LSS service is answered on 7E4h".to_owned(),
                answer: format!("nothing on 7E4h within {} ms", timeout.as_millis()),
                cause: "the LSS slave does not serve the service, or does not enter configuration state"
                    .to_owned(),
            },
        ));
    }
    let max = ctx.performance().criteria.lss_response_max_ms;
    let mut worst = Vec::new();
    let mut failed = None;
    for (name, what, samples) in measured {
        worst.push(format!(
            "{what} {:.3}",
            samples.iter().copied().fold(0.0, f64::max)
        ));
        let criterion = Criterion::at_most(ctx, "lss.response_max_ms", max);
        let finding = judge(
            ctx,
            Judged {
                name: &format!("lss_{name}"),
                what: format!("LSS {what} response time"),
                request: format!("LSS {what}, {} times", samples.len()),
                clause: "CiA 305 v3.0",
                cause: "the LSS slave answers slower than the criterion",
                clock: Clock::Link,
            },
            samples,
            criterion,
        );
        if finding.verdict == crate::model::Verdict::Fail && failed.is_none() {
            failed = Some(finding);
        }
    }
    let judged = match max {
        Some(max) => format!(
            "all within ≤ {max} ms ({})",
            ctx.performance().criteria.origin("lss.response_max_ms")
        ),
        None => "measured, no criterion".to_owned(),
    };
    Ok(failed.unwrap_or_else(|| {
        Finding::pass(format!(
            "LSS response times, {repetitions} of each service, max: {} ms; {judged}{}",
            worst.join(", "),
            super::stamps_note(
                ctx,
                Clock::Link,
                Criterion::at_most(ctx, "lss.response_max_ms", max).as_ref()
            )
        ))
    }))
}

/// `repetitions` samples of `one`, or how many answered before one did not.
fn lss_samples(
    ctx: &mut Ctx<'_, '_>,
    repetitions: usize,
    one: &mut dyn FnMut(&mut Ctx<'_, '_>) -> Timed,
) -> Result<Result<Vec<f64>, usize>, Stop> {
    let mut samples = Vec::new();
    for _ in 0..repetitions {
        match one(ctx)? {
            Some((ms, _)) => samples.push(ms),
            None => return Ok(Err(samples.len())),
        }
    }
    Ok(Ok(samples))
}

/// Switch state selective with `address`, timed from the last request (43h) to the 44h answer;
/// back to waiting first, so that each repetition switches again.
fn selective(ctx: &mut Ctx<'_, '_>, address: &LssAddress, timeout: Duration) -> Timed {
    switch_global(ctx, false)?;
    let [first @ .., last] = address.switch_selective();
    for request in first {
        ctx.send(LSS_MASTER_TO_SLAVE_ID, &request.encode())?;
    }
    exchange(
        ctx,
        Outgoing::Data(LSS_MASTER_TO_SLAVE_ID, &last.encode()),
        timeout,
        |f| is_lss_answer(f, answer_specifier(&last)),
    )
}

/// Switch state global (04h), unconfirmed.
fn switch_global(ctx: &mut Ctx<'_, '_>, configuration: bool) -> Result<(), Stop> {
    let request = LssRequest::SwitchStateGlobal {
        mode: u8::from(configuration),
    };
    ctx.send(LSS_MASTER_TO_SLAVE_ID, &request.encode())
}

//! PDO tests (CCT group "PDO" and "Testing other 10"): communication and mapping parameters, RTR,
//! the mapping procedure and restricted CAN-IDs.

use std::time::Duration;

use canopener_wire::NmtCommand;

use crate::cia301::pdo_transmission::{nmt_path, served_outside_operational};
use crate::context::{Ctx, Reply, first_hex, hex};
use crate::device_model::{PdoDirection, PdoModel};
use crate::finding::{Evidence, Finding, Outcome, Prepared, Stop};
use crate::procedures::nmt::back_to_pre_operational;
use crate::procedures::sdo::{download_text, expect_refusal, read_described, u32_of, upload_text};
use crate::procedures::tpdo::{Setting, Step, judge_step, set_up_tpdo};
use crate::requirements as req;
use crate::test_def::TestDef;

/// The PDO tests.
pub fn tests() -> Vec<TestDef> {
    vec![
        TestDef {
            id: "cia301.pdo.1",
            suite: "cia301",
            group: "pdo",
            title: "Every RPDO and TPDO communication parameter reads with a valid COB-ID and transmission type",
            references: &[req::PDO_PARAMETERS, "CCT PDO 01", "CCT PDO 02"],
            precondition: "the EDS has PDOs",
            tags: &["pdo"],
            run: communication_parameters,
        },
        TestDef {
            id: "cia301.pdo.2",
            suite: "cia301",
            group: "pdo",
            title: "Every mapping entry of every PDO names an object the dictionary has",
            references: &[req::PDO_PARAMETERS, "CCT PDO 21"],
            precondition: "the EDS has PDO mappings",
            tags: &["pdo"],
            run: default_mappings,
        },
        TestDef {
            id: "cia301.pdo.3",
            suite: "cia301",
            group: "pdo",
            title: "Operational: a TPDO that allows RTR answers a remote frame",
            references: &[req::PDO, "CCT PDO 03"],
            precondition: "a TPDO set up for RTR (type FCh/FDh, bit 30 = 0) or whose COB-ID and type the EDS makes writable; not_applicable only when the device refuses bit 30 = 0 or type FDh with 0609 0030h/0031h/0032h (RTR is optional); any other refusal or a timeout fails",
            tags: &["pdo", "nmt"],
            run: tpdo_rtr,
        },
        TestDef {
            id: "cia301.pdo.15",
            suite: "cia301",
            group: "pdo",
            title: "Stopped and pre-operational: a TPDO that answers a remote frame in operational does not answer it",
            references: &[req::PDO, req::NMT_STATES, "CCT PDO 09", "CCT PDO 15"],
            precondition: "as cia301.pdo.3; a TPDO that does not answer in operational makes it inconclusive",
            tags: &["pdo", "nmt"],
            run: tpdo_rtr_stopped,
        },
        TestDef {
            id: "cia301.pdo.4",
            suite: "cia301",
            group: "pdo",
            title: "A restricted CAN-ID (701h) is refused as a TPDO COB-ID",
            references: &[req::RESTRICTED_IDS, "CCT Testing other 10"],
            precondition: "a TPDO whose COB-ID the EDS makes writable",
            tags: &["pdo", "writes"],
            run: restricted_cob_id,
        },
        TestDef {
            id: "cia301.pdo.5",
            suite: "cia301",
            group: "pdo",
            title: "Mapping an object with PDOMapping=0 is refused during the mapping procedure: 1000h into a TPDO, a writable object into an RPDO",
            references: &[req::PDO_PARAMETERS, "CCT PDO 29", "CCT PDO 32"],
            precondition: "a TPDO with writable COB-ID and mapping and a 1000h with PDOMapping=0 (PDO 32); an RPDO with writable COB-ID and mapping and a writable 8/16/32-bit object with PDOMapping=0, 1017h first (PDO 29)",
            tags: &["pdo", "writes"],
            run: unmappable,
        },
    ]
}

fn all_pdos(ctx: &Ctx<'_, '_>) -> Vec<PdoModel> {
    let mut all = ctx.model().pdos(PdoDirection::Receive);
    all.extend(ctx.model().pdos(PdoDirection::Transmit));
    all
}

fn communication_parameters(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let pdos = all_pdos(ctx);
    if pdos.is_empty() {
        return Ok(Finding::not_applicable("the EDS has no PDOs"));
    }
    for pdo in &pdos {
        let cob = ctx.read(pdo.comm, 1)?;
        // CCT PDO 01 scans the RPDOs, PDO 02 the TPDOs.
        ctx.performed(match pdo.direction {
            PdoDirection::Receive => "PDO 01",
            PdoDirection::Transmit => "PDO 02",
        });
        let Some(cob_id) = u32_of(&cob) else {
            return Ok(fail_param(pdo, 1, &cob, "a 4-byte COB-ID"));
        };
        if cob_id & 0x8000_0000 == 0 && restricted(cob_id & 0x7FF) {
            return Ok(fail_param(
                pdo,
                1,
                &cob,
                "a valid COB-ID that is not a restricted CAN-ID (CiA 301 §7.3.5)",
            ));
        }
        if ctx.model().entry(pdo.comm, 2).is_some() {
            let kind = ctx.read(pdo.comm, 2)?;
            let reserved = match &kind {
                Reply::Done(d) if let [kind] = d.as_slice() => (0xF1..=0xFB).contains(kind),
                _ => true,
            };
            if reserved {
                return Ok(fail_param(
                    pdo,
                    2,
                    &kind,
                    "a 1-byte transmission type outside the reserved F1h–FBh",
                ));
            }
        }
    }
    Ok(Finding::pass(format!("{} PDOs", pdos.len())))
}

fn fail_param(pdo: &PdoModel, sub: u8, reply: &Reply, required: &str) -> Finding {
    Finding::fail(
        format!(
            "{}{} {:04X}h:{sub:02X}: {}",
            pdo.direction.name(),
            pdo.number,
            pdo.comm,
            reply.describe()
        ),
        Evidence {
            request: upload_text((pdo.comm, sub)),
            requirement: format!("{}: {required}", req::PDO_PARAMETERS),
            answer: reply.describe(),
            cause: "the PDO communication parameter is missing or holds a value CiA 301 does not allow"
                .to_owned(),
        },
    )
}

/// CiA 301 §7.3.5: CAN-IDs no configurable object may use.
pub fn restricted(id: u32) -> bool {
    matches!(id, 0x000 | 0x001..=0x07F | 0x101..=0x180 | 0x581..=0x5FF | 0x601..=0x67F | 0x6E0..=0x6FF | 0x701..=0x77F | 0x780..=0x7FF)
}

fn default_mappings(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let pdos: Vec<PdoModel> = all_pdos(ctx)
        .into_iter()
        .filter(|p| p.mapping.is_some())
        .collect();
    if pdos.is_empty() {
        return Ok(Finding::not_applicable("the EDS has no PDO mappings"));
    }
    let mut checked = 0;
    for pdo in &pdos {
        let Some(mapping) = pdo.mapping else { continue };
        let Reply::Done(count) = ctx.read(mapping, 0)? else {
            continue;
        };
        for sub in 1..=count.first().copied().unwrap_or(0) {
            let entry = ctx.read(mapping, sub)?;
            let Some(value) = u32_of(&entry) else {
                return Ok(fail_param(pdo, sub, &entry, "a 4-byte mapping entry"));
            };
            let (index, target_sub) = ((value >> 16) as u16, (value >> 8) as u8);
            // Dummy entries (0001h–0007h) map no object.
            if index < 0x0008 {
                continue;
            }
            checked += 1;
            let reply = ctx.read(index, target_sub)?;
            ctx.performed("PDO 21");
            if matches!(reply, Reply::Refused(code) if code == canopener_wire::abort::OBJECT_DOES_NOT_EXIST || code == canopener_wire::abort::SUB_INDEX_DOES_NOT_EXIST)
            {
                return Ok(Finding::fail(
                    format!(
                        "{mapping:04X}h:{sub:02X} maps {index:04X}h:{target_sub:02X}, which does not exist"
                    ),
                    Evidence {
                        request: format!(
                            "{}, then {}",
                            upload_text((mapping, sub)),
                            upload_text((index, target_sub))
                        ),
                        requirement: format!(
                            "{}: a mapping entry names an object of the dictionary",
                            req::PDO_PARAMETERS
                        ),
                        answer: reply.describe(),
                        cause: "the default mapping names an object the firmware does not have".to_owned(),
                    },
                ));
            }
        }
    }
    Ok(Finding::pass(format!("{checked} mapped objects exist")))
}

/// A TPDO that answers remote frames: (number, CAN-ID, transmission type).
type RtrTpdo = (u16, u16, u8);

/// A TPDO already set up for RTR-only transmission (FCh/FDh) with RTR allowed, else the first TPDO
/// whose parameters the EDS makes writable and that takes RTR-only transmission, configured so.
fn rtr_tpdo(ctx: &mut Ctx<'_, '_>) -> Prepared<RtrTpdo> {
    for pdo in ctx.model().pdos(PdoDirection::Transmit) {
        let readable = |sub: u8| ctx.model().entry(pdo.comm, sub).is_some_and(|e| e.readable());
        if !readable(1) || !readable(2) {
            continue;
        }
        let cob = match read_described(ctx, pdo.comm, 1, "the TPDO's COB-ID")? {
            Ok(value) => u32_of(&Reply::Done(value)),
            Err(failed) => return Ok(Err(failed)),
        };
        let kind = match read_described(ctx, pdo.comm, 2, "the TPDO's transmission type")? {
            Ok(value) => value.first().copied().filter(|_| value.len() == 1),
            Err(failed) => return Ok(Err(failed)),
        };
        if let (Some(cob), Some(kind)) = (cob, kind)
            && cob & 0xC000_0000 == 0
            && (kind == 0xFC || kind == 0xFD)
        {
            return Ok(Ok((pdo.number, (cob & 0x7FF) as u16, kind)));
        }
    }
    // RTR-only transmission and RTR on PDOs are optional (CiA 301 §7.2.2.2.1).
    let settings = [Setting::new(
        2,
        vec![0xFD],
        "RTR-only transmission (type FDh), which CiA 301 leaves optional",
    )];
    Ok(set_up_tpdo(ctx, &settings, true)?.map(|(pdo, cob)| (pdo.number, (cob & 0x7FF) as u16, 0xFD)))
}

/// Sends a remote frame on `cob` and returns the TPDO that answers within 100 ms.
fn ask_tpdo(ctx: &mut Ctx<'_, '_>, cob: u16) -> Result<Option<crate::recorder::Logged>, Stop> {
    ctx.send_remote(cob, 0)?;
    let id = ctx.id(cob);
    ctx.wait_for(Duration::from_millis(100), |f| f.id() == id && !f.is_remote())
}

fn tpdo_rtr(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let (number, cob, kind) = match rtr_tpdo(ctx)? {
        Ok(chosen) => chosen,
        Err(finding) => return Ok(finding),
    };
    ctx.nmt(NmtCommand::StartRemoteNode, false)?;
    ctx.listen(Duration::from_millis(20), |_| false)?;
    let answer: Vec<_> = ask_tpdo(ctx, cob)?.into_iter().collect();
    ctx.performed("PDO 03");
    back_to_pre_operational(ctx)?;
    Ok(if answer.is_empty() {
        Finding::fail(
            format!("TPDO{number} ({cob:#X}, type {kind:02X}h) did not answer a remote frame"),
            Evidence {
                request: format!(
                    "TPDO{number} with transmission type {kind:02X}h and RTR allowed; NMT start, then a remote frame on {cob:#X}"
                ),
                requirement: format!(
                    "{}: a TPDO of type FCh/FDh whose COB-ID allows RTR (bit 30 = 0) is sent on request",
                    req::PDO
                ),
                answer: "no TPDO within 100 ms".to_owned(),
                cause: "remote requests on TPDOs are not served although 18xxh allows them".to_owned(),
            },
        )
    } else {
        Finding::pass(format!("TPDO{number} answered: {}", first_hex(&answer)))
    })
}

/// The first TPDO whose COB-ID the EDS makes writable, with its current COB-ID; `Ok(Err(None))`
/// when the EDS has none, a failure when the device does not serve a COB-ID its EDS describes.
fn writable_tpdo(ctx: &mut Ctx<'_, '_>) -> Prepared<Option<(PdoModel, u32)>> {
    for pdo in ctx.model().pdos(PdoDirection::Transmit) {
        if !ctx
            .model()
            .entry(pdo.comm, 1)
            .is_some_and(|e| e.writable() && e.readable())
        {
            continue;
        }
        match read_described(ctx, pdo.comm, 1, "the TPDO's COB-ID")? {
            Ok(value) => {
                if let Some(cob) = u32_of(&Reply::Done(value)) {
                    return Ok(Ok(Some((pdo, cob))));
                }
            }
            Err(failed) => return Ok(Err(failed)),
        }
    }
    Ok(Ok(None))
}

const NO_WRITABLE_COB_ID: &str = "the EDS makes no TPDO COB-ID (18xxh:01) readable and writable (AccessType)";

fn restricted_cob_id(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let (pdo, cob) = match writable_tpdo(ctx)? {
        Ok(Some(found)) => found,
        Ok(None) => return Ok(Finding::not_applicable(NO_WRITABLE_COB_ID)),
        Err(failed) => return Ok(failed),
    };
    // Disable first: CiA 301 §7.5.2.37 forbids changing the CAN-ID of a valid PDO.
    let disabled = cob | 0x8000_0000;
    let disable = download_text((pdo.comm, 1), &disabled.to_le_bytes());
    let reply = ctx.modify(pdo.comm, 1, disabled.to_le_bytes().to_vec())?;
    if let Some(failed) = judge_step(&format!("TPDO{}", pdo.number), Step::Disable, &disable, &reply) {
        return Ok(failed);
    }
    // Keep bit 30 as it was: only the CAN-ID is under test.
    let value = (cob & 0x4000_0000) | 0x701;
    let data = value.to_le_bytes().to_vec();
    let reply = ctx.modify(pdo.comm, 1, data.clone())?;
    ctx.performed("Testing other 10");
    Ok(expect_refusal(
        &format!("{disable}, then {}", download_text((pdo.comm, 1), &data)),
        &reply,
        req::INVALID_VALUE,
        req::RESTRICTED_IDS,
        "the COB-ID is not checked against the restricted CAN-IDs",
    ))
}

fn unmappable(ctx: &mut Ctx<'_, '_>) -> Outcome {
    use crate::cia301::pdo_mapping::entry_value;
    // CCT PDO 32: 1000h:00 (never mappable) into a TPDO, as the CCT does.
    let tpdo = match ctx.model().entry(0x1000, 0).filter(|e| !e.pdo_mapping) {
        None => Finding::not_applicable(
            "the EDS gives 1000h PDOMapping=1 (or has no 1000h): no object with PDOMapping=0 to try",
        ),
        Some(_) => refused_alone(
            ctx,
            PdoDirection::Transmit,
            0x1000_0020,
            "1000h:00 (PDOMapping=0)",
            "PDO 32",
        )?,
    };
    // CCT PDO 29: a writable object with PDOMapping=0 into an RPDO (the CCT maps 1401h:05); a
    // writable one, so that only the mapping attribute forbids it.
    let candidate = {
        let model = ctx.model();
        let fits = |e: &&crate::device_model::EntryModel| {
            !e.pdo_mapping
                && e.writable()
                && !(0x1600..=0x17FF).contains(&e.index)
                && !(0x1A00..=0x1BFF).contains(&e.index)
        };
        model
            .entry(0x1017, 0)
            .filter(fits)
            .or_else(|| {
                model
                    .entries
                    .values()
                    .filter(fits)
                    .find(|e| entry_value(e).is_some())
            })
            .and_then(|e| entry_value(e).map(|v| (v, e.label())))
    };
    let rpdo = match candidate {
        None => Finding::not_applicable(
            "the EDS has no writable 8/16/32-bit object with PDOMapping=0 (AccessType, PDOMapping, DataType)",
        ),
        Some((entry, label)) => refused_alone(
            ctx,
            PdoDirection::Receive,
            entry,
            &format!("{label}, PDOMapping=0"),
            "PDO 29",
        )?,
    };
    Ok(Finding::of_steps(vec![
        ("TPDO (PDO 32)", tpdo),
        ("RPDO (PDO 29)", rpdo),
    ]))
}

/// Maps `entry` alone into the first PDO of `direction` with a writable mapping (the mapping
/// procedure of CiA 301 §7.5.2.38) and expects the refusal of a non-mappable object; records
/// `case` once the answer is judged.
fn refused_alone(
    ctx: &mut Ctx<'_, '_>,
    direction: PdoDirection,
    entry: u32,
    what: &str,
    case: &str,
) -> Result<Finding, Stop> {
    let (request, reply) = match crate::cia301::pdo_mapping::map_alone(ctx, direction, entry)? {
        Ok(done) => done,
        Err(finding) => return Ok(finding),
    };
    ctx.performed(case);
    Ok(expect_refusal(
        &format!("{request} ({what})"),
        &reply,
        req::NOT_MAPPABLE,
        req::PDO_PARAMETERS,
        "the mapping entry is not checked against the object's PDO mapping attribute",
    ))
}

fn tpdo_rtr_stopped(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let (number, cob, kind) = match rtr_tpdo(ctx)? {
        Ok(chosen) => chosen,
        Err(finding) => return Ok(finding),
    };
    ctx.nmt(NmtCommand::StartRemoteNode, false)?;
    ctx.listen(Duration::from_millis(20), |_| false)?;
    let operational = ask_tpdo(ctx, cob)?;
    if operational.is_none() {
        back_to_pre_operational(ctx)?;
        return Ok(Finding::inconclusive(format!(
            "TPDO{number} ({cob:#X}) did not answer a remote frame in operational either (see cia301.pdo.3)"
        )));
    }
    // CCT PDO 09 in stopped; PDO 15 read as the same request in pre-operational (the CCT runs
    // its PDO cases in operational, stopped and pre-operational in turn).
    let mut steps = Vec::new();
    for (command, state, case) in [
        (NmtCommand::StopRemoteNode, "stopped", "PDO 09"),
        (NmtCommand::EnterPreOperational, "pre-operational", "PDO 15"),
    ] {
        ctx.nmt(command, false)?;
        ctx.listen(Duration::from_millis(20), |_| false)?;
        let answer = ask_tpdo(ctx, cob)?;
        ctx.performed(case);
        let finding = match answer {
            Some(answer) => served_outside_operational(
                format!("TPDO{number} ({cob:#X}) answered a remote frame in {state}"),
                format!(
                    "TPDO{number} with transmission type {kind:02X}h and RTR allowed; NMT start, a remote frame (answered), {}, a remote frame on {cob:#X}",
                    nmt_path(state)
                ),
                state,
                format!("the TPDO {}", hex(answer.frame.data())),
            ),
            None => Finding::pass(format!("no answer in {state}")),
        };
        steps.push((case, finding));
    }
    back_to_pre_operational(ctx)?;
    Ok(Finding::of_steps(steps))
}

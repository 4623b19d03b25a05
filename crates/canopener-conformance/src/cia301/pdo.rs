//! PDO tests (CCT group "PDO" and "Testing other 10"): communication and mapping parameters, RTR,
//! the mapping procedure and restricted CAN-IDs.

use std::time::Duration;

use canopener_wire::NmtCommand;

use crate::context::{Ctx, Reply, hex};
use crate::device_model::{PdoDirection, PdoModel};
use crate::finding::{Evidence, Finding, Outcome, Prepared, Stop};
use crate::procedures::nmt::back_to_pre_operational;
use crate::procedures::sdo::{download_text, expect_refusal, read_described, u32_of, upload_text};
use crate::procedures::tpdo::{Setting, Step, judge_step, open_mapping, set_up_tpdo};
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
            references: &[req::PDO, "CCT PDO 03", "CCT PDO 15"],
            precondition: "a TPDO set up for RTR (type FCh/FDh, bit 30 = 0) or whose COB-ID and type the EDS makes writable; not_applicable only when the device refuses bit 30 = 0 or type FDh with 0609 0030h/0031h/0032h (RTR is optional); any other refusal or a timeout fails",
            tags: &["pdo", "nmt"],
            run: tpdo_rtr,
        },
        TestDef {
            id: "cia301.pdo.15",
            suite: "cia301",
            group: "pdo",
            title: "Stopped: a TPDO that answers a remote frame in operational does not answer it",
            references: &[req::PDO, req::NMT_STATES, "CCT PDO 09"],
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
            title: "Mapping an object with PDOMapping=0 is refused during the mapping procedure",
            references: &[req::PDO_PARAMETERS, "CCT PDO 29", "CCT PDO 32"],
            precondition: "a TPDO with a writable mapping and an object with PDOMapping=0 (1000h)",
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
                Reply::Done(d) if d.len() == 1 => (0xF1..=0xFB).contains(&d[0]),
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
        Finding::pass(format!("TPDO{number} answered: {}", hex(answer[0].frame.data())))
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
    Ok(expect_refusal(
        &format!("{disable}, then {}", download_text((pdo.comm, 1), &data)),
        &reply,
        req::INVALID_VALUE,
        req::RESTRICTED_IDS,
        "the COB-ID is not checked against the restricted CAN-IDs",
    ))
}

fn unmappable(ctx: &mut Ctx<'_, '_>) -> Outcome {
    if ctx.model().entry(0x1000, 0).is_none_or(|e| e.pdo_mapping) {
        return Ok(Finding::not_applicable(
            "the EDS gives 1000h PDOMapping=1 (or has no 1000h): no object with PDOMapping=0 to try",
        ));
    }
    let (pdo, cob) = match writable_tpdo(ctx)? {
        Ok(Some(found)) => found,
        Ok(None) => return Ok(Finding::not_applicable(NO_WRITABLE_COB_ID)),
        Err(failed) => return Ok(failed),
    };
    let writable = |m: u16, sub: u8| ctx.model().entry(m, sub).is_some_and(|e| e.writable());
    let Some(mapping) = pdo.mapping.filter(|m| writable(*m, 0) && writable(*m, 1)) else {
        return Ok(Finding::not_applicable(format!(
            "the EDS has no writable {:04X}h:00 and :01 (AccessType) for TPDO{}",
            pdo.comm + 0x200,
            pdo.number
        )));
    };
    // The mapping procedure (CiA 301 §7.5.2.38): disable the PDO, set 0 entries, write the entry.
    if let Err(failed) = open_mapping(ctx, &pdo, cob, mapping)? {
        return Ok(failed);
    }
    let entry = 0x1000_0020u32.to_le_bytes().to_vec();
    let reply = ctx.modify(mapping, 1, entry.clone())?;
    Ok(expect_refusal(
        &format!(
            "mapping procedure on TPDO{}: {} (1000h:00, 32 bits; PDOMapping=0)",
            pdo.number,
            download_text((mapping, 1), &entry)
        ),
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
    ctx.nmt(NmtCommand::StopRemoteNode, false)?;
    ctx.listen(Duration::from_millis(20), |_| false)?;
    let stopped = match operational {
        Some(_) => ask_tpdo(ctx, cob)?,
        None => None,
    };
    back_to_pre_operational(ctx)?;
    Ok(match (operational, stopped) {
        (None, _) => Finding::inconclusive(format!(
            "TPDO{number} ({cob:#X}) did not answer a remote frame in operational either (see cia301.pdo.3)"
        )),
        (Some(_), Some(answer)) => Finding::fail(
            format!("TPDO{number} ({cob:#X}) answered a remote frame in stopped"),
            Evidence {
                request: format!(
                    "TPDO{number} with transmission type {kind:02X}h and RTR allowed; NMT start, a remote frame (answered), NMT stop, a remote frame on {cob:#X}"
                ),
                requirement: format!(
                    "{}: in stopped only NMT and error control are served, no PDO",
                    req::NMT_STATES
                ),
                answer: format!("the TPDO {}", hex(answer.frame.data())),
                cause: "PDO communication is not switched off in stopped".to_owned(),
            },
        ),
        (Some(_), None) => Finding::pass(format!("TPDO{number} answered in operational, not in stopped")),
    })
}

//! Setting a TPDO up for a test the way CiA 301 §7.5.2.37 allows: disabled, changed, enabled again;
//! and what an answer other than a confirmation means for the test.
//!
//! A test that needs a TPDO configured says "not applicable" only for a reason CiA 301 gives: the EDS
//! does not make the parameter writable (its `AccessType`), its `LowLimit`/`HighLimit` exclude the
//! value, the TPDO maps nothing, or the device refuses exactly the value the test needs with a code
//! that says the value is not supported (0609 0030h, 0609 0031h, 0609 0032h). Everything else is a
//! failure: no answer (a timeout is a failure, not a missing feature), a refused disable or enable,
//! any other abort code. A lost link stops the test (`Stop::Link`), which the runner reports as
//! inconclusive.

use canopener_od::Number;
use canopener_wire::abort;

use crate::context::{Ctx, Reply};
use crate::device_model::{PdoDirection, PdoModel};
use crate::finding::{Evidence, Finding, Prepared};
use crate::procedures::sdo::{download_text, read_described, u32_of};
use crate::requirements::{self as req, code_meaning};

/// COB-ID bit 31: the PDO does not exist / is not valid (CiA 301 §7.5.2.35).
pub const COB_INVALID: u32 = 0x8000_0000;
/// COB-ID bit 30 of a TPDO: no RTR allowed.
pub const COB_NO_RTR: u32 = 0x4000_0000;

/// How many TPDOs a "not applicable" reason names before it summarises the rest.
const NAMED: usize = 4;

/// One parameter a test writes into a TPDO's communication parameter, with the optional feature
/// the value stands for (named when the device says it does not support it).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Setting {
    /// The sub-index of 18xxh.
    pub sub: u8,
    /// The value, as CiA 301 carries it.
    pub value: Vec<u8>,
    /// `RTR-only transmission (type FDh)`.
    pub feature: &'static str,
}

impl Setting {
    /// `value` into sub-index `sub`, standing for `feature`.
    pub fn new(sub: u8, value: Vec<u8>, feature: &'static str) -> Setting {
        Setting { sub, value, feature }
    }
}

/// The abort codes that say the value written is not supported: CiA 301's codes for a value out of
/// range. Only a refusal of the very value a test needs, with one of these, makes it not
/// applicable.
pub const NOT_SUPPORTED: [u32; 3] = [abort::INVALID_VALUE, abort::VALUE_TOO_HIGH, abort::VALUE_TOO_LOW];

/// A step of [`configure_tpdo`], for what a non-confirmation of it means.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Step {
    /// Setting bit 31 of 18xxh:01: always required (CiA 301 §7.5.2.37).
    Disable,
    /// Clearing bit 30 of 18xxh:01 (RTR allowed): RTR on TPDOs is optional.
    AllowRtr,
    /// A setting: its value may be one the device does not support.
    Setting(&'static str),
    /// Clearing bit 31 again: always required.
    Enable,
    /// Writing 0 to the mapping's sub-index 0, the mapping procedure's second step: always
    /// required (CiA 301 §7.5.2.38).
    OpenMapping,
}

/// What the answer `reply` to the request `request` (a step of configuring the PDO `pdo`, `TPDO1`)
/// means for the test: `None` for a confirmation, else the finding that ends the test (see the
/// [module docs](self)).
pub fn judge_step(pdo: &str, step: Step, request: &str, reply: &Reply) -> Option<Finding> {
    let optional = match step {
        Step::AllowRtr => Some("RTR on TPDOs (COB-ID bit 30 = 0), which CiA 301 leaves optional"),
        Step::Setting(feature) => Some(feature),
        Step::Disable | Step::Enable | Step::OpenMapping => None,
    };
    match (reply, optional) {
        (Reply::Done(_), _) => None,
        (Reply::Refused(code), Some(feature)) if NOT_SUPPORTED.contains(code) => {
            Some(Finding::not_applicable(format!(
                "{pdo}: {request} was refused with {}: the device does not support {feature}",
                code_meaning(*code)
            )))
        }
        (other, _) => {
            let cause = match (other, step) {
                (Reply::Silent, _) => {
                    "the SDO server does not answer a PDO configuration write: a timeout is a failure, not a missing feature"
                }
                (_, Step::Disable | Step::Enable) => {
                    "the device refuses to disable or enable a PDO whose COB-ID the EDS makes writable"
                }
                (_, Step::OpenMapping) => {
                    "the device refuses the mapping procedure's first steps on a mapping the EDS makes writable"
                }
                _ => {
                    "the device refuses a PDO parameter with a code that does not say the value is unsupported (0609 0030h, 0609 0031h or 0609 0032h would)"
                }
            };
            Some(Finding::fail(
                format!("{pdo}: {request} got {}", other.describe()),
                Evidence {
                    request: request.to_owned(),
                    requirement: format!(
                        "{}: a PDO is configured by setting bit 31 of its COB-ID, writing its parameters (a mapping after 0 to its sub-index 0) and clearing bit 31; the device confirms each step, or refuses a value it does not support with 0609 0030h, 0609 0031h or 0609 0032h",
                        req::PDO_PARAMETERS
                    ),
                    answer: other.describe(),
                    cause: cause.to_owned(),
                },
            ))
        }
    }
}

/// Why the EDS rules `index`:`sub` out for writing `value`: absent, not writable (its
/// `AccessType`), or `value` outside its `LowLimit`/`HighLimit`. `None` when it may be written.
pub fn not_writable(ctx: &Ctx<'_, '_>, index: u16, sub: u8, value: Option<&[u8]>) -> Option<String> {
    let Some(entry) = ctx.model().entry(index, sub) else {
        return Some(format!("the EDS has no {index:04X}h:{sub:02X}"));
    };
    if !entry.writable() {
        return Some(match entry.access {
            Some(access) => format!("the EDS gives {index:04X}h:{sub:02X} AccessType={access}"),
            None => format!("the EDS gives {index:04X}h:{sub:02X} no AccessType"),
        });
    }
    let number = value.and_then(|v| Number::decode(entry.data_type?, v))?;
    let below = entry.low.is_some_and(|low| number < low);
    let above = entry.high.is_some_and(|high| number > high);
    (below || above).then(|| {
        let limit = |n: Option<Number>| n.map_or("-".to_owned(), |n| n.to_string());
        format!(
            "the EDS limits {index:04X}h:{sub:02X} to LowLimit {} .. HighLimit {}, which excludes {number}",
            limit(entry.low),
            limit(entry.high)
        )
    })
}

/// `pdo` with its current COB-ID if the EDS lets the test write `settings` (and 18xxh:01), the
/// TPDO maps data and has a CAN-ID; `Ok(Err(reason))` says why not; a failure when the device does
/// not serve an entry the EDS describes.
pub fn configurable_tpdo_at(
    ctx: &mut Ctx<'_, '_>,
    pdo: &PdoModel,
    settings: &[Setting],
) -> Prepared<Result<u32, String>> {
    if let Some(why) = std::iter::once((1, None))
        .chain(settings.iter().map(|s| (s.sub, Some(s.value.as_slice()))))
        .find_map(|(sub, value)| not_writable(ctx, pdo.comm, sub, value))
    {
        return Ok(Ok(Err(why)));
    }
    let Some(mapping) = pdo.mapping else {
        return Ok(Ok(Err(format!(
            "the EDS has no mapping parameter {:04X}h",
            pdo.comm + 0x200
        ))));
    };
    if !ctx.model().entry(mapping, 0).is_some_and(|e| e.readable()) {
        return Ok(Ok(Err(format!("the EDS has no readable {mapping:04X}h:00"))));
    }
    let cob = match read_described(ctx, pdo.comm, 1, "the TPDO's COB-ID")? {
        Ok(value) => match u32_of(&Reply::Done(value.clone())) {
            Some(cob) => cob,
            None => {
                return Ok(Err(read_wrong_size(pdo.comm, 1, &value, 4)));
            }
        },
        Err(failed) => return Ok(Err(failed)),
    };
    // An expedited answer that indicates more bytes than the type has is `cia301.sdo.14`'s to judge:
    // the value is still little-endian in the first byte.
    let count = match read_described(ctx, mapping, 0, "the number of mapped objects")? {
        Ok(value) => match value.split_first() {
            Some((count, rest)) if rest.iter().all(|b| *b == 0) => *count,
            _ => return Ok(Err(read_wrong_size(mapping, 0, &value, 1))),
        },
        Err(failed) => return Ok(Err(failed)),
    };
    Ok(Ok(if count == 0 {
        Err(format!(
            "{mapping:04X}h:00 reads 0: the TPDO maps no object (CiA 301 §7.5.2.38)"
        ))
    } else if cob & 0x7FF == 0 {
        Err(format!("{:04X}h:01 = {cob:#010X} has no CAN-ID", pdo.comm))
    } else {
        Ok(cob)
    }))
}

fn read_wrong_size(index: u16, sub: u8, value: &[u8], size: usize) -> Finding {
    crate::procedures::sdo::refused_unexpectedly(
        &crate::procedures::sdo::upload_text((index, sub)),
        &Reply::Done(value.to_vec()),
        req::PDO_PARAMETERS,
        &format!("the entry is read with {} bytes instead of {size}", value.len()),
    )
}

/// Configures `pdo` (whose COB-ID is `cob`) the way CiA 301 §7.5.2.37 allows: disabled (bit 31 set),
/// RTR allowed first when `rtr` (bit 30 cleared, a write of its own, so that a device that checks
/// RTR-only types against bit 30 sees it cleared), `settings` written, enabled again. Every value is
/// written back after the test. The finding is what a non-confirmation means ([`judge_step`]).
pub fn configure_tpdo(
    ctx: &mut Ctx<'_, '_>,
    pdo: &PdoModel,
    cob: u32,
    settings: &[Setting],
    rtr: bool,
) -> Prepared<()> {
    let disabled = cob | COB_INVALID;
    let mut steps = vec![(Step::Disable, 1u8, disabled.to_le_bytes().to_vec())];
    let mut enabled = cob & !COB_INVALID;
    if rtr {
        enabled &= !COB_NO_RTR;
        if cob & COB_NO_RTR != 0 {
            steps.push((Step::AllowRtr, 1, (disabled & !COB_NO_RTR).to_le_bytes().to_vec()));
        }
    }
    steps.extend(
        settings
            .iter()
            .map(|s| (Step::Setting(s.feature), s.sub, s.value.clone())),
    );
    steps.push((Step::Enable, 1, enabled.to_le_bytes().to_vec()));
    let mut done: Vec<String> = Vec::new();
    for (step, sub, data) in steps {
        let request = download_text((pdo.comm, sub), &data);
        let reply = ctx.modify(pdo.comm, sub, data)?;
        let sequence = if done.is_empty() {
            request.clone()
        } else {
            format!("{}, then {request}", done.join(", "))
        };
        if let Some(finding) = judge_step(&format!("TPDO{}", pdo.number), step, &sequence, &reply) {
            return Ok(Err(finding));
        }
        done.push(request);
    }
    Ok(Ok(()))
}

/// The mapping procedure's first two steps on `pdo` (COB-ID `cob`, mapping parameter `mapping`):
/// the PDO disabled, its mapping set to 0 entries (CiA 301 §7.5.2.38), each written back after the
/// test. Both are required of a PDO whose COB-ID and mapping the EDS makes writable: any answer but a
/// confirmation fails the test.
pub fn open_mapping(ctx: &mut Ctx<'_, '_>, pdo: &PdoModel, cob: u32, mapping: u16) -> Prepared<()> {
    let label = format!("{}{}", pdo.direction.name(), pdo.number);
    let mut done: Vec<String> = Vec::new();
    for (step, index, sub, data) in [
        (
            Step::Disable,
            pdo.comm,
            1u8,
            (cob | COB_INVALID).to_le_bytes().to_vec(),
        ),
        (Step::OpenMapping, mapping, 0, vec![0]),
    ] {
        let request = download_text((index, sub), &data);
        let reply = ctx.modify(index, sub, data)?;
        done.push(request);
        if let Some(finding) = judge_step(&label, step, &done.join(", then "), &reply) {
            return Ok(Err(finding));
        }
    }
    Ok(Ok(()))
}

/// The first TPDO the EDS lets the test configure with `settings` (and RTR allowed when `rtr`) that
/// takes them: its model and its COB-ID as it was. A TPDO that refuses a value as unsupported is
/// passed over for the next; when none is left the test is not applicable, and the reason names, per
/// TPDO, the EDS key or abort code that ruled it out. Any other non-confirmation fails the test.
pub fn set_up_tpdo(ctx: &mut Ctx<'_, '_>, settings: &[Setting], rtr: bool) -> Prepared<(PdoModel, u32)> {
    let mut passed_over = Vec::new();
    for pdo in ctx.model().pdos(PdoDirection::Transmit) {
        let cob = match configurable_tpdo_at(ctx, &pdo, settings)? {
            Ok(Ok(cob)) => cob,
            Ok(Err(why)) => {
                passed_over.push(format!("TPDO{}: {why}", pdo.number));
                continue;
            }
            Err(failed) => return Ok(Err(failed)),
        };
        match configure_tpdo(ctx, &pdo, cob, settings, rtr)? {
            Ok(()) => return Ok(Ok((pdo, cob))),
            Err(finding) if finding.verdict == crate::model::Verdict::NotApplicable => {
                passed_over.push(finding.reason);
            }
            Err(finding) => return Ok(Err(finding)),
        }
    }
    Ok(Err(none_configurable(&passed_over)))
}

/// The "not applicable" finding when no TPDO could be set up: the reasons, per TPDO.
pub fn none_configurable(passed_over: &[String]) -> Finding {
    if passed_over.is_empty() {
        return Finding::not_applicable("the EDS describes no TPDO (1800h–19FFh)");
    }
    let mut named: Vec<String> = passed_over.iter().take(NAMED).cloned().collect();
    if passed_over.len() > NAMED {
        named.push(format!("{} more TPDOs likewise", passed_over.len() - NAMED));
    }
    Finding::not_applicable(format!("no TPDO can be set up: {}", named.join("; ")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Verdict;

    const REQUEST: &str = "SDO download 1800h:02 = FD";

    #[test]
    fn only_a_value_refused_as_unsupported_is_not_applicable() {
        let feature = Step::Setting("RTR-only transmission (type FDh)");
        for code in NOT_SUPPORTED {
            let finding = judge_step("TPDO1", feature, REQUEST, &Reply::Refused(code)).expect("a finding");
            assert_eq!(finding.verdict, Verdict::NotApplicable, "{code:08X}");
            assert!(
                finding.reason.contains(&crate::requirements::code_text(code)),
                "{}",
                finding.reason
            );
            assert!(
                finding.reason.contains("RTR-only transmission"),
                "{}",
                finding.reason
            );
        }
        // The general error, a hardware error, "read-only" against an EDS that says rw, an
        // incompatibility: none of them says the value is unsupported.
        for code in [
            abort::GENERAL_ERROR,
            abort::HARDWARE_ERROR,
            abort::WRITE_READ_ONLY,
            abort::UNSUPPORTED_ACCESS,
            abort::PARAMETER_INCOMPATIBLE,
            abort::CANNOT_TRANSFER_DEVICE_STATE,
        ] {
            let finding = judge_step("TPDO1", feature, REQUEST, &Reply::Refused(code)).expect("a finding");
            assert_eq!(finding.verdict, Verdict::Fail, "{code:08X}");
            assert!(
                finding.analysis.contains("Answer:   abort"),
                "{}",
                finding.analysis
            );
        }
    }

    #[test]
    fn a_timeout_or_a_broken_answer_is_a_failure_at_every_step() {
        for step in [
            Step::Disable,
            Step::AllowRtr,
            Step::Setting("the event timer"),
            Step::Enable,
            Step::OpenMapping,
        ] {
            for reply in [
                Reply::Silent,
                Reply::Broken {
                    code: abort::GENERAL_ERROR,
                    reason: "junk".to_owned(),
                },
                Reply::Frame(vec![0x60]),
            ] {
                let finding = judge_step("TPDO2", step, REQUEST, &reply).expect("a finding");
                assert_eq!(finding.verdict, Verdict::Fail, "{step:?} {reply:?}");
                assert!(finding.reason.starts_with("TPDO2: "), "{}", finding.reason);
            }
        }
        let silent = judge_step("TPDO2", Step::Setting("x"), REQUEST, &Reply::Silent).expect("a finding");
        assert!(
            silent.analysis.contains("a timeout is a failure"),
            "{}",
            silent.analysis
        );
    }

    #[test]
    fn a_refused_disable_or_enable_fails_whatever_the_code() {
        for step in [Step::Disable, Step::Enable, Step::OpenMapping] {
            for code in [abort::INVALID_VALUE, abort::GENERAL_ERROR] {
                let finding = judge_step("TPDO3", step, REQUEST, &Reply::Refused(code)).expect("a finding");
                assert_eq!(finding.verdict, Verdict::Fail, "{step:?} {code:08X}");
            }
        }
        // Clearing bit 30 is the RTR feature itself: 0609 0030h says the device has no RTR.
        let rtr = judge_step(
            "TPDO3",
            Step::AllowRtr,
            REQUEST,
            &Reply::Refused(abort::INVALID_VALUE),
        );
        assert_eq!(rtr.map(|f| f.verdict), Some(Verdict::NotApplicable));
        assert_eq!(
            judge_step("TPDO3", Step::Enable, REQUEST, &Reply::Done(Vec::new())),
            None
        );
    }

    #[test]
    fn the_not_applicable_reason_names_each_tpdo_and_summarises_many() {
        let reasons: Vec<String> = (1..=6)
            .map(|n| format!("TPDO{n}: the EDS gives 18{:02X}h:05 AccessType=ro", n - 1))
            .collect();
        let finding = none_configurable(&reasons);
        assert_eq!(finding.verdict, Verdict::NotApplicable);
        assert!(
            finding
                .reason
                .contains("TPDO1: the EDS gives 1800h:05 AccessType=ro"),
            "{}",
            finding.reason
        );
        assert!(
            finding.reason.ends_with("2 more TPDOs likewise"),
            "{}",
            finding.reason
        );
        assert!(none_configurable(&[]).reason.contains("no TPDO"));
    }
}

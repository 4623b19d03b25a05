//! The PDO mapping procedure (CCT "PDO 22–28, 30, 31"): a correct mapping written with the procedure
//! CiA 301 §7.5.2.38 describes, and the refusals of a mapping written without it, too long, or in
//! the wrong direction, with the abort codes the CCT accepts (reference §3.4).

use std::time::Duration;

use canopener_wire::NmtCommand;

use crate::context::{Ctx, Reply, hex};
use crate::device_model::{EntryModel, PdoDirection, PdoModel};
use crate::finding::{Evidence, Finding, Outcome, Prepared, Stop};
use crate::model::Verdict;
use crate::procedures::sdo::{download_text, expect_refusal, read_described, refused_unexpectedly, u32_of};
use crate::procedures::tpdo::{Setting, configure_tpdo, open_mapping};
use crate::requirements as req;
use crate::test_def::TestDef;

/// The mapping tests.
pub fn tests() -> Vec<TestDef> {
    vec![
        TestDef {
            id: "cia301.pdo.8",
            suite: "cia301",
            group: "pdo",
            title: "A different mapping written with the mapping procedure is accepted, reads back and is what the TPDO carries",
            references: &[req::PDO_PARAMETERS, "CCT PDO 22"],
            precondition: "a TPDO with writable COB-ID, transmission type and mapping, a CAN-ID, and a readable mappable object of another length than the TPDO has; a transmission type the tester can trigger (type 1, else FFh with an event timer, else FDh)",
            tags: &["pdo", "writes"],
            run: correct_mapping,
        },
        TestDef {
            id: "cia301.pdo.9",
            suite: "cia301",
            group: "pdo",
            title: "A mapping entry written without the mapping procedure is refused: PDO invalid but sub-index 0 not 0, and PDO valid",
            references: &[req::PDO_PARAMETERS, "CCT PDO 23", "CCT PDO 24"],
            precondition: "a TPDO with writable COB-ID and mapping and at least one mapped object; the valid-PDO step needs the TPDO valid or one that can be made valid",
            tags: &["pdo", "writes"],
            run: without_procedure,
        },
        TestDef {
            id: "cia301.pdo.10",
            suite: "cia301",
            group: "pdo",
            title: "A mapping with more objects than the mapping has entries, and one longer than 64 bits, are refused",
            references: &[req::PDO_PARAMETERS, "CCT PDO 25", "CCT PDO 26"],
            precondition: "a TPDO with writable COB-ID and mapping; too many objects: a mappable object whose length times the mapping's entries fits 64 bits; too long: one that exceeds 64 bits in fewer entries than the mapping has",
            tags: &["pdo", "writes"],
            run: too_long,
        },
        TestDef {
            id: "cia301.pdo.11",
            suite: "cia301",
            group: "pdo",
            title: "A read-only (process input) object is refused in an RPDO mapping",
            references: &[req::PDO_PARAMETERS, "CCT PDO 28"],
            precondition: "an RPDO with writable COB-ID and mapping, and a mappable ro object",
            tags: &["pdo", "writes"],
            run: wrong_direction,
        },
        TestDef {
            id: "cia301.pdo.16",
            suite: "cia301",
            group: "pdo",
            title: "A mappable process input (ro or rwr) is accepted in a TPDO mapping",
            references: &[req::PDO_PARAMETERS, "CCT PDO 30"],
            precondition: "a TPDO with writable COB-ID and mapping, and an ro/rwr object with PDOMapping=1",
            tags: &["pdo", "writes"],
            run: input_into_tpdo,
        },
        TestDef {
            id: "cia301.pdo.17",
            suite: "cia301",
            group: "pdo",
            title: "A write-only (process output) object is refused in a TPDO mapping",
            references: &[req::PDO_PARAMETERS, "CCT PDO 31"],
            precondition: "a TPDO with writable COB-ID and mapping, and a wo object with PDOMapping=1 (rww objects are readable: CiA 301 allows them in a TPDO, so they are not tried)",
            tags: &["pdo", "writes"],
            run: output_into_tpdo,
        },
        TestDef {
            id: "cia301.pdo.18",
            suite: "cia301",
            group: "pdo",
            title: "A dummy entry the EDS's [DummyUsage] enables is accepted in an RPDO mapping",
            references: &[req::PDO_PARAMETERS, "CCT PDO 33"],
            precondition: "[DummyUsage] enables one of 0002h–0007h, and an RPDO with writable COB-ID and mapping",
            tags: &["pdo", "writes"],
            run: dummy_into_rpdo,
        },
        TestDef {
            id: "cia301.pdo.19",
            suite: "cia301",
            group: "pdo",
            title: "A mappable process output (rww or wo, PDOMapping=1) is accepted in an RPDO mapping",
            references: &[req::PDO_PARAMETERS, "CCT PDO 27"],
            precondition: "an RPDO with writable COB-ID and mapping, and an rww or wo object with PDOMapping=1",
            tags: &["pdo", "writes"],
            run: output_into_rpdo,
        },
    ]
}

/// A PDO whose COB-ID and mapping (sub-indices 0 and 1) the EDS makes writable, with its COB-ID
/// and current mapping entries as read.
struct Mappable {
    pdo: PdoModel,
    mapping: u16,
    cob: u32,
    entries: Vec<u32>,
}

/// The first PDO of `direction` whose COB-ID and mapping (sub-indices 0 and 1) the EDS makes
/// writable (`also` more sub-indices of its communication parameter), read from the device; a
/// failure when the device does not serve what its EDS describes.
fn mappable_with(ctx: &mut Ctx<'_, '_>, direction: PdoDirection, also: &[u8]) -> Prepared<Option<Mappable>> {
    for pdo in ctx.model().pdos(direction) {
        let Some(mapping) = pdo.mapping else { continue };
        let model = ctx.model();
        let writable = |index: u16, sub: u8| model.entry(index, sub).is_some_and(EntryModel::writable);
        let readable = |index: u16, sub: u8| model.entry(index, sub).is_some_and(EntryModel::readable);
        let described = writable(pdo.comm, 1)
            && writable(mapping, 0)
            && writable(mapping, 1)
            && also.iter().all(|sub| writable(pdo.comm, *sub))
            && readable(pdo.comm, 1)
            && readable(mapping, 0);
        if !described {
            continue;
        }
        let cob = match read_described(ctx, pdo.comm, 1, "the PDO's COB-ID")? {
            Ok(value) => u32_of(&Reply::Done(value)),
            Err(failed) => return Ok(Err(failed)),
        };
        let Some(cob) = cob else { continue };
        // A longer expedited answer is cia301.sdo.14's to judge; the count is the first byte.
        let count = match read_described(ctx, mapping, 0, "the number of mapped objects")? {
            Ok(value) => value.first().copied().unwrap_or(0),
            Err(failed) => return Ok(Err(failed)),
        };
        let mut entries = Vec::new();
        for sub in 1..=count {
            if !readable(mapping, sub) {
                break;
            }
            match read_described(ctx, mapping, sub, "a mapping entry")? {
                Ok(value) => match u32_of(&Reply::Done(value)) {
                    Some(entry) => entries.push(entry),
                    None => break,
                },
                Err(failed) => return Ok(Err(failed)),
            }
        }
        return Ok(Ok(Some(Mappable {
            pdo,
            mapping,
            cob,
            entries,
        })));
    }
    Ok(Ok(None))
}

/// [`mappable_with`] needing only the COB-ID and the mapping.
fn mappable(ctx: &mut Ctx<'_, '_>, direction: PdoDirection) -> Prepared<Option<Mappable>> {
    mappable_with(ctx, direction, &[])
}

/// `Err(finding)` from a [`Prepared`] step, as an early return of a test.
macro_rules! prepared {
    ($step:expr) => {
        match $step {
            Ok(value) => value,
            Err(finding) => return Ok(finding),
        }
    };
}

/// No PDO of `direction` whose mapping the EDS makes writable: the keys that say so.
fn no_mappable(direction: PdoDirection) -> Finding {
    let (comm, mapping) = match direction {
        PdoDirection::Transmit => ("18xxh", "1Axxh"),
        PdoDirection::Receive => ("14xxh", "16xxh"),
    };
    Finding::not_applicable(format!(
        "the EDS makes no {}'s {comm}:01, {mapping}:00 and {mapping}:01 all writable (AccessType)",
        direction.name()
    ))
}

/// How `cia301.pdo.8` makes the remapped TPDO go out: the transmission type (and settings) it
/// writes, and whether it then sends a SYNC or a remote frame, or waits for the event timer.
struct Trigger {
    settings: Vec<Setting>,
    rtr: bool,
    how: How,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum How {
    Sync,
    EventTimer,
    Remote,
}

/// The event timer `cia301.pdo.8` sets when it observes the TPDO on its timer, in ms.
pub const MAPPING_EVENT_TIMER_MS: u16 = 100;

fn triggers() -> [Trigger; 3] {
    [
        Trigger {
            settings: vec![Setting::new(
                2,
                vec![1],
                "cyclic synchronous transmission (type 1)",
            )],
            rtr: false,
            how: How::Sync,
        },
        Trigger {
            settings: vec![
                Setting::new(2, vec![0xFF], "event-driven transmission (type FFh)"),
                Setting::new(
                    5,
                    MAPPING_EVENT_TIMER_MS.to_le_bytes().to_vec(),
                    "the event timer (18xxh:05) at this value",
                ),
            ],
            rtr: false,
            how: How::EventTimer,
        },
        Trigger {
            settings: vec![Setting::new(
                2,
                vec![0xFD],
                "RTR-only transmission (type FDh), which CiA 301 leaves optional",
            )],
            rtr: true,
            how: How::Remote,
        },
    ]
}

/// A readable object with PDOMapping=1 of 1, 2 or 4 bytes other than `bytes` long, as a mapping
/// entry, with its label: mapped alone it changes the TPDO's length, which shows on the bus whether
/// the device applies the new mapping.
fn other_length_object(ctx: &Ctx<'_, '_>, bytes: usize) -> Option<(u32, usize, String)> {
    use canopener_eds::AccessType;
    // Process inputs (ro, rwr) first, then rw; rww is a process output, which devices may refuse in
    // a TPDO.
    let candidates = |access: &'static [AccessType]| {
        ctx.model().entries.values().filter(move |e| {
            e.pdo_mapping
                && e.access.is_some_and(|a| access.contains(&a))
                && e.index >= 0x1000
                && e.size().is_some_and(|s| matches!(s, 1 | 2 | 4) && s != bytes)
        })
    };
    let inputs: &[AccessType] = &[AccessType::Ro, AccessType::Rwr];
    candidates(inputs)
        .find(|e| e.index >= 0x2000)
        .or_else(|| candidates(inputs).next())
        .or_else(|| candidates(&[AccessType::Rw]).next())
        .and_then(|e| Some((entry_value(e)?, e.size()?, e.label())))
}

fn correct_mapping(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let Some(m) = prepared!(mappable_with(ctx, PdoDirection::Transmit, &[2])?) else {
        return Ok(Finding::not_applicable(
            "the EDS makes no TPDO's 18xxh:01, 18xxh:02, 1Axxh:00 and 1Axxh:01 all writable (AccessType)",
        ));
    };
    if m.cob & 0x7FF == 0 {
        return Ok(Finding::not_applicable(format!(
            "{:04X}h:01 = {:#010X} has no CAN-ID",
            m.pdo.comm, m.cob
        )));
    }
    let old_bytes = m
        .entries
        .iter()
        .map(|e| (e & 0xFF) as usize)
        .sum::<usize>()
        .div_ceil(8);
    let Some((entry, bytes, label)) = other_length_object(ctx, old_bytes) else {
        return Ok(Finding::not_applicable(format!(
            "the EDS has no ro, rwr or rw object with PDOMapping=1 of 1, 2 or 4 bytes other than the {old_bytes} bytes TPDO{} carries now",
            m.pdo.number
        )));
    };
    prepared!(open_mapping(ctx, &m.pdo, m.cob, m.mapping)?);
    let steps = [
        (m.mapping, 1u8, entry.to_le_bytes().to_vec()),
        (m.mapping, 0, vec![1]),
    ];
    let mut requests = vec![
        download_text((m.pdo.comm, 1), &(m.cob | 0x8000_0000).to_le_bytes()),
        download_text((m.mapping, 0), &[0]),
    ];
    ctx.performed("PDO 22");
    for (index, sub, data) in steps {
        requests.push(download_text((index, sub), &data));
        let reply = ctx.modify(index, sub, data.clone())?;
        if !matches!(reply, Reply::Done(_)) {
            return Ok(Finding::fail(
                format!(
                    "the mapping procedure on TPDO{} was refused at {}",
                    m.pdo.number,
                    download_text((index, sub), &data)
                ),
                Evidence {
                    request: format!("{} ({label})", requests.join(", ")),
                    requirement: format!(
                        "{}: a correct mapping written with the mapping procedure is accepted",
                        req::PDO_PARAMETERS
                    ),
                    answer: reply.describe(),
                    cause: "the device refuses a mappable object its EDS marks PDOMapping=1, or a step of the procedure"
                        .to_owned(),
                },
            ));
        }
    }
    for (sub, expected) in [(1u8, entry), (0, 1)] {
        let back = ctx.read(m.mapping, sub)?;
        let value = match &back {
            Reply::Done(d) if sub == 0 => d.first().map(|b| u32::from(*b)),
            other => u32_of(other),
        };
        if value != Some(expected) {
            return Ok(Finding::fail(
                format!(
                    "{:04X}h:{sub:02X} reads {} after the mapping procedure",
                    m.mapping,
                    back.describe()
                ),
                Evidence {
                    request: requests.join(", "),
                    requirement: format!(
                        "{}: the mapping entries hold what was written",
                        req::PDO_PARAMETERS
                    ),
                    answer: back.describe(),
                    cause: "the mapping is confirmed but not stored".to_owned(),
                },
            ));
        }
    }
    // The new mapping must be what the TPDO carries: enabled with a transmission type the tester can
    // trigger (SYNC, else the event timer, else a remote frame).
    let mut passed_over = Vec::new();
    let mut chosen = None;
    for trigger in triggers() {
        match configure_tpdo(ctx, &m.pdo, m.cob, &trigger.settings, trigger.rtr)? {
            Ok(()) => {
                chosen = Some(trigger);
                break;
            }
            Err(finding) if finding.verdict == Verdict::NotApplicable => passed_over.push(finding.reason),
            Err(failed) => return Ok(failed),
        }
    }
    let Some(trigger) = chosen else {
        return Ok(Finding::not_applicable(format!(
            "the new mapping reads back, but TPDO{} takes no transmission type the tester can trigger: {}",
            m.pdo.number,
            passed_over.join("; ")
        )));
    };
    let value_before = ctx.read((entry >> 16) as u16, (entry >> 8) as u8)?;
    let cob = (m.cob & 0x7FF) as u16;
    let id = ctx.id(cob);
    ctx.nmt(NmtCommand::StartRemoteNode, false)?;
    let tpdo = match trigger.how {
        How::Sync => {
            ctx.listen(Duration::from_millis(20), |_| false)?;
            let sync = match u32_of(&ctx.read(0x1005, 0)?) {
                Some(cob) => (cob & 0x7FF) as u16,
                None => 0x80,
            };
            ctx.send(sync, &[])?;
            ctx.wait_for(Duration::from_millis(100), |f| f.id() == id && !f.is_remote())?
        }
        How::EventTimer => ctx.wait_for(
            Duration::from_millis(u64::from(MAPPING_EVENT_TIMER_MS) * 5 / 2),
            |f| f.id() == id && !f.is_remote(),
        )?,
        How::Remote => {
            ctx.listen(Duration::from_millis(20), |_| false)?;
            ctx.send_remote(cob, 0)?;
            ctx.wait_for(Duration::from_millis(100), |f| f.id() == id && !f.is_remote())?
        }
    };
    let value_after = ctx.read((entry >> 16) as u16, (entry >> 8) as u8)?;
    crate::procedures::nmt::back_to_pre_operational(ctx)?;
    let how = match trigger.how {
        How::Sync => "type 1 and a SYNC",
        How::EventTimer => "type FFh and its event timer",
        How::Remote => "type FDh and a remote frame",
    };
    let request = format!(
        "{}, then TPDO{} enabled with {how}; NMT start",
        requests.join(", "),
        m.pdo.number
    );
    let requirement = format!(
        "{}: once enabled, the TPDO carries the objects its mapping names (here {label} alone: {bytes} data bytes)",
        req::PDO_PARAMETERS
    );
    let Some(tpdo) = tpdo else {
        return Ok(Finding::fail(
            format!(
                "TPDO{} ({cob:#X}) did not come after the new mapping, with {how}",
                m.pdo.number
            ),
            Evidence {
                request,
                requirement,
                answer: "no TPDO".to_owned(),
                cause: "the PDO is not rebuilt from the new mapping, or not sent at all".to_owned(),
            },
        ));
    };
    let data = tpdo.frame.data();
    // The value on the bus must be the object's value when it did not change meanwhile.
    let stable = match (&value_before, &value_after) {
        (Reply::Done(a), Reply::Done(b)) if a == b => Some(a.clone()),
        _ => None,
    };
    if data.len() != bytes || stable.as_ref().is_some_and(|v| v.as_slice() != data) {
        return Ok(Finding::fail(
            format!(
                "TPDO{} ({cob:#X}) carries {} after mapping the {bytes}-byte {label} alone",
                m.pdo.number,
                if data.is_empty() {
                    "no data".to_owned()
                } else {
                    format!("{} ({} bytes)", hex(data), data.len())
                }
            ),
            Evidence {
                request,
                requirement,
                answer: format!(
                    "TPDO {}; the object reads {}",
                    hex(data),
                    stable
                        .as_deref()
                        .map_or("differently before and after".to_owned(), hex)
                ),
                cause: "the mapping is stored and confirmed but the PDO keeps the mapping it had".to_owned(),
            },
        ));
    }
    Ok(Finding::pass(format!(
        "TPDO{} mapped to {label} alone (was {old_bytes} bytes) reads back and carries {}",
        m.pdo.number,
        hex(data)
    )))
}

fn without_procedure(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let Some(m) = prepared!(mappable(ctx, PdoDirection::Transmit)?) else {
        return Ok(no_mappable(PdoDirection::Transmit));
    };
    let Some(first) = m.entries.first() else {
        return Ok(Finding::not_applicable(format!(
            "TPDO{} maps nothing ({:04X}h:00 = 0): no entry to write back while it is valid",
            m.pdo.number, m.mapping
        )));
    };
    let entry = first.to_le_bytes().to_vec();
    let pdo = format!("TPDO{}", m.pdo.number);
    // CCT PDO 23: the PDO made invalid (step 1 of the procedure), sub-index 0 left as it is
    // (step 2 skipped): the entry must be refused.
    let invalid = (m.cob | 0x8000_0000).to_le_bytes().to_vec();
    let disabled = ctx.modify(m.pdo.comm, 1, invalid.clone())?;
    let step_23 = if matches!(disabled, Reply::Done(_)) {
        let reply = ctx.modify(m.mapping, 1, entry.clone())?;
        ctx.performed("PDO 23");
        expect_refusal(
            &format!(
                "{}, then {} while sub-index 0 is {}",
                download_text((m.pdo.comm, 1), &invalid),
                download_text((m.mapping, 1), &entry),
                m.entries.len()
            ),
            &reply,
            req::MAPPING_SEQUENCE,
            req::PDO_PARAMETERS,
            "mapping entries can be changed while sub-index 0 is not 0 (step 2 of the procedure skipped)",
        )
    } else {
        Finding::inconclusive(format!(
            "{} got {}",
            download_text((m.pdo.comm, 1), &invalid),
            disabled.describe()
        ))
    };
    // CCT PDO 24: the PDO valid (step 1 skipped): 0 to sub-index 0, then the entry; the first of
    // them that the device takes must not be the last.
    let valid = (m.cob & !0x8000_0000).to_le_bytes().to_vec();
    let enabled = ctx.modify(m.pdo.comm, 1, valid.clone())?;
    let step_24 = if !matches!(enabled, Reply::Done(_)) {
        Finding::not_applicable(format!(
            "{pdo} cannot be made valid: {} got {}",
            download_text((m.pdo.comm, 1), &valid),
            enabled.describe()
        ))
    } else {
        let mut requests = vec![download_text((m.pdo.comm, 1), &valid)];
        let mut reply = Reply::Done(Vec::new());
        for (sub, data) in [(0u8, vec![0]), (1, entry.clone())] {
            requests.push(download_text((m.mapping, sub), &data));
            reply = ctx.modify(m.mapping, sub, data)?;
            if !matches!(reply, Reply::Done(_)) {
                break;
            }
        }
        ctx.performed("PDO 24");
        expect_refusal(
            &format!("{} while {pdo} is valid", requests.join(", ")),
            &reply,
            req::MAPPING_SEQUENCE,
            req::PDO_PARAMETERS,
            "the mapping can be changed while the PDO is valid (step 1 of the procedure skipped)",
        )
    };
    Ok(Finding::of_steps(vec![
        ("PDO invalid, sub-index 0 not 0 (PDO 23)", step_23),
        ("PDO valid (PDO 24)", step_24),
    ]))
}

/// A mappable object for `direction` of 8, 16 or 32 bits (the longest first, from 2000h on), as
/// a mapping entry value, with its size in bits.
fn mappable_object(ctx: &Ctx<'_, '_>, direction: PdoDirection) -> Option<(u32, u32)> {
    mappable_object_of(ctx, direction, [4, 2, 1], 0x2000)
}

/// The first object of the sizes `sizes` (bytes, in that order) from index `from` on that may be
/// mapped into a PDO of `direction`, as a mapping entry value with its length in bits.
fn mappable_object_of(
    ctx: &Ctx<'_, '_>,
    direction: PdoDirection,
    sizes: [usize; 3],
    from: u16,
) -> Option<(u32, u32)> {
    sizes.into_iter().find_map(|size| {
        ctx.model()
            .entries
            .values()
            .filter(|e| mappable_into(e, direction))
            .find(|e| e.size() == Some(size) && e.index >= from)
            .and_then(entry_value)
            .map(|value| (value, size as u32 * 8))
    })
}

fn too_long(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let Some(m) = prepared!(mappable(ctx, PdoDirection::Transmit)?) else {
        return Ok(no_mappable(PdoDirection::Transmit));
    };
    let entries = ctx.model().objects.get(&m.mapping).map_or(0, |o| o.highest_sub());
    let steps = vec![
        ("too many objects (PDO 25)", too_many_objects(ctx, &m, entries)?),
        ("longer than 64 bits (PDO 26)", longer_than_64(ctx, &m, entries)?),
    ];
    Ok(Finding::of_steps(steps))
}

/// CCT PDO 25: every entry of the mapping filled with objects short enough to fit 64 bits
/// together (the CCT: eight 8-bit objects), then sub-index 0 set to one more than the mapping has
/// entries.
fn too_many_objects(ctx: &mut Ctx<'_, '_>, m: &Mappable, entries: u8) -> Result<Finding, Stop> {
    let Some((entry, bits)) = mappable_object_of(ctx, PdoDirection::Transmit, [1, 2, 4], 0) else {
        return Ok(Finding::not_applicable(
            "no mappable 8/16/32-bit object for a TPDO",
        ));
    };
    if entries == 0 || u32::from(entries) * bits > 64 {
        return Ok(Finding::not_applicable(format!(
            "the mapping {:04X}h has {entries} entries: {bits}-bit objects in all of them exceed 64 bits, so one more object could not be told from too long",
            m.mapping
        )));
    }
    let (mut requests, last) = match fill_mapping(ctx, m, entry, entries)? {
        Ok(filled) => filled,
        Err(finding) => return Ok(finding),
    };
    if !matches!(last, Reply::Done(_)) {
        return Ok(Finding::inconclusive(format!(
            "{} (correct entries) got {}",
            requests.last().map_or("", String::as_str),
            last.describe()
        )));
    }
    let count = entries + 1;
    requests.push(download_text((m.mapping, 0), &[count]));
    let reply = ctx.modify(m.mapping, 0, vec![count])?;
    ctx.performed("PDO 25");
    Ok(expect_refusal(
        &format!(
            "mapping procedure on TPDO{}: {} ({count} objects, the mapping has {entries} entries)",
            m.pdo.number,
            requests.join(", ")
        ),
        &reply,
        req::MAPPING_LENGTH,
        req::PDO_PARAMETERS,
        "sub-index 0 is not checked against the number of entries the mapping has",
    ))
}

/// CCT PDO 26: objects whose lengths add up to more than 64 bits in fewer entries than the
/// mapping has.
fn longer_than_64(ctx: &mut Ctx<'_, '_>, m: &Mappable, entries: u8) -> Result<Finding, Stop> {
    let Some((entry, bits)) = mappable_object(ctx, PdoDirection::Transmit) else {
        return Ok(Finding::not_applicable(
            "no mappable 8/16/32-bit object for a TPDO",
        ));
    };
    let count = (64 / bits + 1) as u8;
    if entries < count {
        return Ok(Finding::not_applicable(format!(
            "the mapping {:04X}h has {entries} entries, {count} of {bits} bits are needed to exceed 64",
            m.mapping
        )));
    }
    // The refusal may come at the entry that exceeds 64 bits or at sub-index 0.
    let (mut requests, mut last) = match fill_mapping(ctx, m, entry, count)? {
        Ok(filled) => filled,
        Err(finding) => return Ok(finding),
    };
    if matches!(last, Reply::Done(_)) {
        requests.push(download_text((m.mapping, 0), &[count]));
        last = ctx.modify(m.mapping, 0, vec![count])?;
    }
    ctx.performed("PDO 26");
    Ok(expect_refusal(
        &format!(
            "mapping procedure on TPDO{}: {} ({} × {bits} bits = {} bits)",
            m.pdo.number,
            requests.join(", "),
            count,
            u32::from(count) * bits
        ),
        &last,
        req::MAPPING_LENGTH,
        req::PDO_PARAMETERS,
        "the total length of the mapping is not checked against 64 bits",
    ))
}

/// Starts the mapping procedure on `m` and writes `entry` to sub-indices 1..=`count`, stopping at
/// the first answer that is not a confirmation; the requests and that (or the last) answer, or the
/// finding when the procedure cannot start.
fn fill_mapping(
    ctx: &mut Ctx<'_, '_>,
    m: &Mappable,
    entry: u32,
    count: u8,
) -> Result<Result<(Vec<String>, Reply), Finding>, Stop> {
    if let Err(failed) = open_mapping(ctx, &m.pdo, m.cob, m.mapping)? {
        return Ok(Err(failed));
    }
    let data = entry.to_le_bytes().to_vec();
    let mut requests = Vec::new();
    let mut last = Reply::Done(Vec::new());
    for sub in 1..=count {
        requests.push(download_text((m.mapping, sub), &data));
        last = ctx.modify(m.mapping, sub, data.clone())?;
        if !matches!(last, Reply::Done(_)) {
            break;
        }
    }
    Ok(Ok((requests, last)))
}

/// Whether `e` may be mapped into a PDO of `direction`: PDOMapping=1 and readable for a TPDO,
/// writable for an RPDO.
fn mappable_into(e: &EntryModel, direction: PdoDirection) -> bool {
    e.pdo_mapping
        && match direction {
            PdoDirection::Transmit => e.readable(),
            PdoDirection::Receive => e.writable(),
        }
}

fn wrong_direction(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let input = ctx
        .model()
        .entries
        .values()
        .find(|e| {
            e.pdo_mapping
                && e.access == Some(canopener_eds::AccessType::Ro)
                && matches!(e.size(), Some(1 | 2 | 4))
        })
        .map(|e| {
            (
                (u32::from(e.index) << 16) | (u32::from(e.sub) << 8) | (e.size().unwrap_or(1) as u32 * 8),
                e.label(),
            )
        });
    let Some((entry, label)) = input else {
        return Ok(Finding::not_applicable(
            "the EDS has no object with AccessType=ro and PDOMapping=1",
        ));
    };
    let Some(m) = prepared!(mappable(ctx, PdoDirection::Receive)?) else {
        return Ok(no_mappable(PdoDirection::Receive));
    };
    prepared!(open_mapping(ctx, &m.pdo, m.cob, m.mapping)?);
    let data = entry.to_le_bytes().to_vec();
    let reply = ctx.modify(m.mapping, 1, data.clone())?;
    ctx.performed("PDO 28");
    Ok(expect_refusal(
        &format!(
            "mapping procedure on RPDO{}: {} ({label}, ro)",
            m.pdo.number,
            download_text((m.mapping, 1), &data)
        ),
        &reply,
        req::NOT_MAPPABLE,
        req::PDO_PARAMETERS,
        "the direction of a mapped object (process input into a receive PDO) is not checked",
    ))
}

/// The mapping entry value of `e` (index, sub-index, length in bits), for 1-, 2- and 4-byte entries.
pub(crate) fn entry_value(e: &EntryModel) -> Option<u32> {
    let size = e.size().filter(|s| matches!(s, 1 | 2 | 4))?;
    Some((u32::from(e.index) << 16) | (u32::from(e.sub) << 8) | (size as u32 * 8))
}

/// The first entry with PDOMapping=1 and one of `access`, as a mapping entry value, with its label.
fn mappable_with_access(ctx: &Ctx<'_, '_>, access: &[canopener_eds::AccessType]) -> Option<(u32, String)> {
    ctx.model()
        .entries
        .values()
        .filter(|e| e.pdo_mapping && e.access.is_some_and(|a| access.contains(&a)))
        .find_map(|e| entry_value(e).map(|v| (v, e.label())))
}

/// Runs the mapping procedure on the first PDO of `direction` with a writable mapping to map
/// `entry` alone (sub-index 1, then 1 to sub-index 0); every value written back after the test.
/// Returns the requests and the first answer that is not a confirmation (or the last one), or the
/// finding that ends the test first.
pub(crate) fn map_alone(
    ctx: &mut Ctx<'_, '_>,
    direction: PdoDirection,
    entry: u32,
) -> Result<Result<(String, Reply), Finding>, Stop> {
    let m = match mappable(ctx, direction)? {
        Ok(Some(m)) => m,
        Ok(None) => return Ok(Err(no_mappable(direction))),
        Err(failed) => return Ok(Err(failed)),
    };
    if let Err(failed) = open_mapping(ctx, &m.pdo, m.cob, m.mapping)? {
        return Ok(Err(failed));
    }
    let mut requests = Vec::new();
    let mut last = Reply::Done(Vec::new());
    for (sub, data) in [(1u8, entry.to_le_bytes().to_vec()), (0, vec![1])] {
        requests.push(download_text((m.mapping, sub), &data));
        last = ctx.modify(m.mapping, sub, data)?;
        if !matches!(last, Reply::Done(_)) {
            break;
        }
    }
    Ok(Ok((
        format!(
            "mapping procedure on {}{}: {}",
            direction.name(),
            m.pdo.number,
            requests.join(", ")
        ),
        last,
    )))
}

fn input_into_tpdo(ctx: &mut Ctx<'_, '_>) -> Outcome {
    use canopener_eds::AccessType;
    accepted_alone(
        ctx,
        PdoDirection::Transmit,
        &[AccessType::Ro, AccessType::Rwr],
        "PDO 30",
        "a process input (ro/rwr, PDOMapping=1)",
    )
}

/// Maps the first object with PDOMapping=1 and one of `access` alone into a PDO of `direction`,
/// where CiA 301 allows it, and expects the mapping procedure to be accepted; records `case` once
/// the answer is judged. `what` names such an object.
fn accepted_alone(
    ctx: &mut Ctx<'_, '_>,
    direction: PdoDirection,
    access: &[canopener_eds::AccessType],
    case: &str,
    what: &str,
) -> Outcome {
    let Some((entry, label)) = mappable_with_access(ctx, access) else {
        return Ok(Finding::not_applicable(format!(
            "the EDS has no object that is {what}"
        )));
    };
    let (request, reply) = match map_alone(ctx, direction, entry)? {
        Ok(done) => done,
        Err(finding) => return Ok(finding),
    };
    ctx.performed(case);
    Ok(match reply {
        Reply::Done(_) => Finding::pass(format!("{label} mapped into {}", direction.name())),
        other => refused_unexpectedly(
            &format!("{request} ({label})"),
            &other,
            req::PDO_PARAMETERS,
            &format!(
                "{what} cannot be mapped into {}, where CiA 301 allows it",
                direction.name()
            ),
        ),
    })
}

fn output_into_tpdo(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let Some((entry, label)) = mappable_with_access(ctx, &[canopener_eds::AccessType::Wo]) else {
        return Ok(Finding::not_applicable(
            "the EDS has no object with AccessType=wo and PDOMapping=1",
        ));
    };
    let (request, reply) = match map_alone(ctx, PdoDirection::Transmit, entry)? {
        Ok(done) => done,
        Err(finding) => return Ok(finding),
    };
    ctx.performed("PDO 31");
    Ok(expect_refusal(
        &format!("{request} ({label}, wo)"),
        &reply,
        req::NOT_MAPPABLE,
        req::PDO_PARAMETERS,
        "the direction of a mapped object (a write-only process output into a transmit PDO) is not checked",
    ))
}

fn dummy_into_rpdo(ctx: &mut Ctx<'_, '_>) -> Outcome {
    // Dummy entries 0002h–0007h: INTEGER8/16/32, UNSIGNED8/16/32 (CiA 301 §7.4.7.1); BOOLEAN (0001h)
    // is left out, a 1-bit entry some devices cannot place.
    let bits = |index: u16| match index {
        2 | 5 => 8u32,
        3 | 6 => 16,
        _ => 32,
    };
    let Some(index) = (2u16..=7).find(|i| ctx.model().dummies.get(usize::from(*i)) == Some(&true)) else {
        return Ok(Finding::not_applicable(
            "the EDS's [DummyUsage] enables none of 0002h–0007h",
        ));
    };
    let entry = (u32::from(index) << 16) | bits(index);
    let (request, reply) = match map_alone(ctx, PdoDirection::Receive, entry)? {
        Ok(done) => done,
        Err(finding) => return Ok(finding),
    };
    ctx.performed("PDO 33");
    Ok(match reply {
        Reply::Done(_) => Finding::pass(format!("dummy {index:04X}h mapped into an RPDO")),
        other => refused_unexpectedly(
            &request,
            &other,
            req::PDO_PARAMETERS,
            "[DummyUsage] enables the dummy entry but the device refuses it",
        ),
    })
}

fn output_into_rpdo(ctx: &mut Ctx<'_, '_>) -> Outcome {
    use canopener_eds::AccessType;
    accepted_alone(
        ctx,
        PdoDirection::Receive,
        &[AccessType::Rww, AccessType::Wo],
        "PDO 27",
        "a process output (rww/wo, PDOMapping=1)",
    )
}

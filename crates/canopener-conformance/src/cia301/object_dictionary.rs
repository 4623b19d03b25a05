//! Object dictionary tests (CCT group "Object dictionary"): walk every object of the EDS.

use canopener_eds::AccessType;

use crate::context::{Ctx, Reply, hex};
use crate::device_model::{EntryModel, OBJ_FLAG_REFUSE_WRITE, number_bytes, number_text, step_beyond};
use crate::finding::{Evidence, Finding, Outcome};
use crate::procedures::entries::is_pdo_or_special;
use crate::procedures::nmt::reset_node;
use crate::procedures::sdo::{download_text, expect_refusal, upload_text};
use crate::requirements as req;
use crate::test_def::TestDef;

/// The object dictionary tests.
pub fn tests() -> Vec<TestDef> {
    vec![
        TestDef {
            id: "cia301.od.1",
            suite: "cia301",
            group: "od",
            title: "Every readable entry of the EDS reads back within its type's size",
            references: &[req::OBJECT_DICTIONARY, "CCT OD 01", "CCT OD 07"],
            precondition: "always (entries with ObjFlags bit 1 are left out)",
            tags: &["od"],
            run: read_all,
        },
        TestDef {
            id: "cia301.od.2",
            suite: "cia301",
            group: "od",
            title: "Entries hold the EDS's DefaultValue after a reset",
            references: &[req::EDS_OBJECTS, "CCT OD 02", "CCT OD 08"],
            precondition: "entries with a DefaultValue; process inputs and values a device fills at run time are left out",
            tags: &["od"],
            run: defaults,
        },
        TestDef {
            id: "cia301.od.3",
            suite: "cia301",
            group: "od",
            title: "Writing every ro and const entry is refused",
            references: &[req::SDO_ABORT, "CCT OD 03"],
            precondition: "the EDS has ro/const entries",
            tags: &["od", "writes"],
            run: write_read_only,
        },
        TestDef {
            id: "cia301.od.4",
            suite: "cia301",
            group: "od",
            title: "Reading every wo entry is refused",
            references: &[req::SDO_ABORT, "CCT OD 04"],
            precondition: "the EDS has wo entries",
            tags: &["od"],
            run: read_write_only,
        },
        TestDef {
            id: "cia301.od.5",
            suite: "cia301",
            group: "od",
            title: "Low/HighLimit: just outside refused, the limit itself accepted, for every entry",
            references: &[req::SDO_ABORT, req::EDS_OBJECTS, "CCT OD 06"],
            precondition: "writable entries with limits",
            tags: &["od", "writes", "limits"],
            run: limits,
        },
        TestDef {
            id: "cia301.od.6",
            suite: "cia301",
            group: "od",
            title: "Sub-index 0 of arrays and records equals the EDS's highest sub-index",
            references: &[req::OBJECT_DICTIONARY],
            precondition: "arrays and records whose sub-index 0 is not a count of entries in use",
            tags: &["od"],
            run: highest_sub,
        },
        TestDef {
            id: "cia301.od.7",
            suite: "cia301",
            group: "od",
            title: "Reading a sub-index beyond the highest of every array and record is refused",
            references: &[req::SDO_ABORT],
            precondition: "arrays and records with fewer than 254 sub-indices",
            tags: &["od"],
            run: absent_subs,
        },
        TestDef {
            id: "cia301.od.8",
            suite: "cia301",
            group: "od",
            title: "Every rw entry accepts its own value written back",
            references: &[
                req::SDO_DOWNLOAD,
                "CCT OD 01",
                "CCT OD 07",
                "CCT OD 09",
                "CCT SDO 02",
            ],
            precondition: "rw entries without ObjFlags bit 0",
            tags: &["od", "writes"],
            run: write_back,
        },
        TestDef {
            id: "cia301.od.9",
            suite: "cia301",
            group: "od",
            title: "Sub-index FFh, where the device has it, gives the object code and data type the EDS states",
            references: &[req::OBJECT_DICTIONARY, "CCT OD 05"],
            precondition: "always; the structure sub-index is optional, so a device without it on every object is not_applicable, unless the EDS describes one",
            tags: &["od"],
            run: structure_subs,
        },
    ]
}

/// Collects the failures of a walk into one finding.
struct Walk {
    checked: usize,
    failures: Vec<(String, Evidence)>,
}

impl Walk {
    fn new() -> Walk {
        Walk {
            checked: 0,
            failures: Vec::new(),
        }
    }

    fn check(&mut self, label: String, finding: Finding) {
        self.checked += 1;
        if finding.verdict == crate::model::Verdict::Fail {
            self.failures.push((
                label,
                Evidence {
                    request: String::new(),
                    requirement: String::new(),
                    answer: finding.reason,
                    cause: finding.analysis,
                },
            ));
        }
    }

    /// Records the CCT `cases` as performed when the walk checked anything.
    fn record(&self, ctx: &mut Ctx<'_, '_>, cases: &[&str]) {
        if self.checked > 0 {
            for case in cases {
                ctx.performed(case);
            }
        }
    }

    fn fail(&mut self, label: String, evidence: Evidence) {
        self.checked += 1;
        self.failures.push((label, evidence));
    }

    fn finding(self, what: &str) -> Finding {
        if self.checked == 0 {
            return Finding::not_applicable(format!("the EDS has no {what}"));
        }
        let Some((first_label, first)) = self.failures.first().cloned() else {
            return Finding::pass(format!("{} {what} checked", self.checked));
        };
        let list: Vec<String> = self.failures.iter().map(|(label, _)| label.clone()).collect();
        let mut evidence = first.clone();
        if evidence.request.is_empty() {
            // A check that produced a whole finding: its analysis already names request and requirement.
            return Finding {
                verdict: crate::model::Verdict::Fail,
                reason: format!(
                    "{} of {} {what} failed: {}",
                    list.len(),
                    self.checked,
                    list.join(", ")
                ),
                analysis: format!("First failure, {first_label}:\n{}\n{}", first.answer, first.cause),
            };
        }
        evidence.answer = format!("{} (and {} more failures)", evidence.answer, list.len() - 1);
        Finding::fail(
            format!(
                "{} of {} {what} failed: {}",
                list.len(),
                self.checked,
                list.join(", ")
            ),
            evidence,
        )
    }
}

fn read_all(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let entries: Vec<EntryModel> = ctx.model().scannable().cloned().collect();
    let mut walk = Walk::new();
    for entry in entries {
        let at = (entry.index, entry.sub);
        let reply = ctx.read(at.0, at.1)?;
        let requirement = format!(
            "{}: a readable entry of the EDS can be read",
            req::OBJECT_DICTIONARY
        );
        match reply {
            Reply::Done(data) => match entry.size() {
                Some(size) if data.len() != size => walk.fail(
                    entry.label(),
                    Evidence {
                        request: upload_text(at),
                        requirement: format!(
                            "{}: a value of its type has {size} bytes",
                            req::OBJECT_DICTIONARY
                        ),
                        answer: format!("{} bytes: {}", data.len(), hex(&data)),
                        cause: "the entry's type in the firmware differs from the EDS".to_owned(),
                    },
                ),
                _ => walk.checked += 1,
            },
            // CiA 301 §7.5.2.4: 1003h's sub-indices beyond the number of errors hold no data.
            Reply::Refused(code) if entry.index == 0x1003 && entry.sub > 0 && req::NO_DATA.accepts(code) => {
                walk.checked += 1
            }
            other => walk.fail(
                entry.label(),
                Evidence {
                    request: upload_text(at),
                    requirement,
                    answer: other.describe(),
                    cause: "the EDS describes an entry the firmware does not have (or not as readable)"
                        .to_owned(),
                },
            ),
        }
    }
    walk.record(ctx, &["OD 01", "OD 07"]);
    Ok(walk.finding("readable entries"))
}

/// Entries whose value a device legitimately changes by itself, or that a test run changes.
fn runtime_value(entry: &EntryModel) -> bool {
    // Process inputs (mappable read-only), the error register and history, identity serial and
    // revision (set per unit), the manufacturer area's read-only values (measurements).
    (entry.pdo_mapping && entry.access == Some(AccessType::Ro))
        || matches!(
            entry.index,
            0x1001 | 0x1002 | 0x1003 | 0x1010 | 0x1011 | 0x1F50..=0x1F5F
        )
        || (entry.index == 0x1018 && entry.sub >= 3)
        || (entry.index >= 0x2000 && entry.access == Some(AccessType::Ro))
}

fn defaults(ctx: &mut Ctx<'_, '_>) -> Outcome {
    if !reset_node(ctx)? {
        return Ok(Finding::inconclusive(
            "no boot-up within 2 s of the reset node: defaults not compared",
        ));
    }
    let entries: Vec<EntryModel> = ctx
        .model()
        .scannable()
        .filter(|e| e.default.is_some() && !runtime_value(e))
        .cloned()
        .collect();
    let mut walk = Walk::new();
    for entry in entries {
        let at = (entry.index, entry.sub);
        let expected = entry.default.clone().unwrap_or_default();
        match ctx.read(at.0, at.1)? {
            Reply::Done(data) if data == expected => walk.checked += 1,
            // A string shorter than the EDS's is padded by some stacks; compare its text.
            Reply::Done(data) if entry.size().is_none() && trim(&data) == trim(&expected) => {
                walk.checked += 1
            }
            other => walk.fail(
                entry.label(),
                Evidence {
                    request: format!("NMT reset node, then {}", upload_text(at)),
                    requirement: format!(
                        "{}: after a reset the entry holds its DefaultValue {}",
                        req::EDS_OBJECTS,
                        hex(&expected)
                    ),
                    answer: other.describe(),
                    cause: "the EDS's DefaultValue and the firmware's default differ".to_owned(),
                },
            ),
        }
    }
    walk.record(ctx, &["OD 02", "OD 08"]);
    Ok(walk.finding("entries with a DefaultValue"))
}

fn trim(data: &[u8]) -> &[u8] {
    let end = data.iter().rposition(|b| *b != 0).map_or(0, |p| p + 1);
    data.get(..end).unwrap_or(data)
}

fn write_read_only(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let entries: Vec<EntryModel> = ctx
        .model()
        .entries
        .values()
        .filter(|e| matches!(e.access, Some(AccessType::Ro | AccessType::Const)))
        .cloned()
        .collect();
    let mut walk = Walk::new();
    for entry in entries {
        let at = (entry.index, entry.sub);
        let data = entry
            .default
            .clone()
            .unwrap_or_else(|| vec![0; entry.size().unwrap_or(1)]);
        let data = if data.is_empty() { vec![0] } else { data };
        let reply = ctx.modify(at.0, at.1, data.clone())?;
        walk.check(
            entry.label(),
            expect_refusal(
                &download_text(at, &data),
                &reply,
                req::WRITE_READ_ONLY,
                req::SDO_ABORT,
                "the server does not check the access type",
            ),
        );
    }
    walk.record(ctx, &["OD 03"]);
    Ok(walk.finding("ro/const entries"))
}

fn read_write_only(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let entries: Vec<EntryModel> = ctx
        .model()
        .entries
        .values()
        .filter(|e| e.access == Some(AccessType::Wo))
        .cloned()
        .collect();
    let mut walk = Walk::new();
    for entry in entries {
        let at = (entry.index, entry.sub);
        let reply = ctx.read(at.0, at.1)?;
        walk.check(
            entry.label(),
            expect_refusal(
                &upload_text(at),
                &reply,
                req::READ_WRITE_ONLY,
                req::SDO_ABORT,
                "the server does not check the access type",
            ),
        );
    }
    walk.record(ctx, &["OD 04"]);
    Ok(walk.finding("entries with AccessType=wo"))
}

fn limits(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let entries: Vec<EntryModel> = ctx
        .model()
        .entries
        .values()
        .filter(|e| e.writable() && e.readable() && e.has_limits() && !is_pdo_or_special(e.index))
        // 1016h packs a node-ID with a time: a value at the limit may be invalid for the node-ID.
        .filter(|e| e.index != 0x1016)
        // LowLimit above HighLimit is the EDS's contradiction (the EDS checks report it), not a
        // range to test the device with.
        .filter(|e| match (e.low, e.high) {
            (Some(low), Some(high)) => !matches!(low.partial_cmp(&high), Some(std::cmp::Ordering::Greater)),
            _ => true,
        })
        .cloned()
        .collect();
    let mut walk = Walk::new();
    for entry in entries {
        let Some(data_type) = entry.data_type else {
            continue;
        };
        let at = (entry.index, entry.sub);
        // A value outside its own limits could not be written back after the test: leave the
        // entry alone (its DefaultValue contradicts its limits, an EDS problem, not the device's).
        let Reply::Done(current) = ctx.read(at.0, at.1)? else {
            continue;
        };
        let inside = canopener_od::Number::decode(data_type, &current).is_some_and(|v| {
            entry
                .low
                .is_none_or(|low| !matches!(v.partial_cmp(&low), Some(std::cmp::Ordering::Less)))
                && entry
                    .high
                    .is_none_or(|high| !matches!(v.partial_cmp(&high), Some(std::cmp::Ordering::Greater)))
        });
        if !inside {
            continue;
        }
        for (limit, up) in [(entry.high, true), (entry.low, false)] {
            let Some(limit) = limit else { continue };
            let (accepted, name) = if up {
                (req::TOO_HIGH, "HighLimit")
            } else {
                (req::TOO_LOW, "LowLimit")
            };
            if let Some(inside) = number_bytes(limit, data_type) {
                let reply = ctx.modify(at.0, at.1, inside.clone())?;
                if !matches!(reply, Reply::Done(_)) {
                    walk.fail(
                        format!("{} = {name}", entry.label()),
                        Evidence {
                            request: download_text(at, &inside),
                            requirement: format!(
                                "{}: a value at the {name} {} is in range",
                                req::EDS_OBJECTS,
                                number_text(limit)
                            ),
                            answer: reply.describe(),
                            cause: format!("the firmware's range is narrower than the EDS's {name}"),
                        },
                    );
                    continue;
                }
            }
            let Some(outside) = step_beyond(limit, up, data_type) else {
                continue;
            };
            let Some(data) = number_bytes(outside, data_type) else {
                continue;
            };
            let reply = ctx.modify(at.0, at.1, data.clone())?;
            walk.check(
                format!("{} beyond {name}", entry.label()),
                expect_refusal(
                    &format!(
                        "{} ({}, {name} {})",
                        download_text(at, &data),
                        number_text(outside),
                        number_text(limit)
                    ),
                    &reply,
                    accepted,
                    req::SDO_ABORT,
                    &format!("the server does not check the {name} its EDS states"),
                ),
            );
        }
    }
    walk.record(ctx, &["OD 06"]);
    Ok(walk.finding("entries with LowLimit or HighLimit"))
}

fn highest_sub(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let objects: Vec<(u16, u8)> = ctx
        .model()
        .objects
        .values()
        .filter(|o| o.is_structured() && o.subs.contains(&0))
        .filter(|o| !matches!(o.index, 0x1003 | 0x1600..=0x17FF | 0x1A00..=0x1BFF))
        .filter(|o| ctx.model().entry(o.index, 0).is_some_and(EntryModel::readable))
        // Where the EDS's own DefaultValue of sub-index 0 contradicts its sub-indices, the EDS
        // checks report it; the device cannot be judged against a contradiction.
        .filter(|o| {
            ctx.model()
                .default_u32(o.index, 0)
                .is_none_or(|d| d == u32::from(o.highest_sub()))
        })
        .map(|o| (o.index, o.highest_sub()))
        .collect();
    let mut walk = Walk::new();
    for (index, highest) in objects {
        match ctx.read(index, 0)? {
            Reply::Done(data) if data.first() == Some(&highest) => walk.checked += 1,
            other => walk.fail(
                format!("{index:04X}h:00"),
                Evidence {
                    request: upload_text((index, 0)),
                    requirement: format!(
                        "{}: sub-index 0 holds the highest sub-index {highest}",
                        req::OBJECT_DICTIONARY
                    ),
                    answer: other.describe(),
                    cause: "the EDS and the firmware describe the object with different sub-indices"
                        .to_owned(),
                },
            ),
        }
    }
    Ok(walk.finding("arrays and records"))
}

fn absent_subs(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let objects: Vec<(u16, u8)> = ctx
        .model()
        .objects
        .values()
        .filter(|o| o.is_structured() && o.highest_sub() < 0xFE)
        .map(|o| (o.index, o.highest_sub() + 1))
        .collect();
    let mut walk = Walk::new();
    for at in objects {
        let reply = ctx.read(at.0, at.1)?;
        walk.check(
            format!("{:04X}h:{:02X}", at.0, at.1),
            expect_refusal(
                &upload_text(at),
                &reply,
                req::NO_SUB_INDEX,
                req::SDO_ABORT,
                "the server answers for sub-indices the object does not have",
            ),
        );
    }
    Ok(walk.finding("arrays and records"))
}

fn write_back(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let entries: Vec<EntryModel> = ctx
        .model()
        .entries
        .values()
        .filter(|e| e.access == Some(AccessType::Rw) && e.obj_flags & OBJ_FLAG_REFUSE_WRITE == 0)
        .filter(|e| !is_pdo_or_special(e.index) && e.index != 0x1017 && e.index != 0x100C)
        .cloned()
        .collect();
    let mut walk = Walk::new();
    for entry in entries {
        let at = (entry.index, entry.sub);
        let Reply::Done(value) = ctx.read(at.0, at.1)? else {
            continue;
        };
        let reply = ctx.write(at.0, at.1, value.clone())?;
        if !matches!(reply, Reply::Done(_)) {
            walk.fail(
                entry.label(),
                Evidence {
                    request: format!("{}, then {}", upload_text(at), download_text(at, &value)),
                    requirement: format!("{}: an rw entry accepts the value it holds", req::SDO_DOWNLOAD),
                    answer: reply.describe(),
                    cause: "the entry is not writable in the firmware, or its current value is outside its own range".to_owned(),
                },
            );
        } else {
            walk.checked += 1;
        }
        // CCT SDO 02 reads and writes back an rw entry of the communication area.
        if (0x1000..=0x1FFF).contains(&at.0) {
            ctx.performed("SDO 02");
        }
    }
    walk.record(ctx, &["OD 01", "OD 07", "OD 09"]);
    Ok(walk.finding("rw entries"))
}

/// Sub-index FFh of an object (CiA 301 §7.4.3): its object code in bits 0-7 and the data type
/// index in the bits above (8-23; the standard types all fit in bits 8-15, where some readings of
/// CiA 301 end the field), bits 24-31 reserved (0). The reference notes do not quote the layout;
/// for every type below 100h both readings give the same value. Read for every object: where the
/// device answers, the value must match the EDS's ObjectType and DataType (CCT OD 05); an absent
/// sub-index FFh (0609 0011h) is allowed unless the EDS describes one.
fn structure_subs(ctx: &mut Ctx<'_, '_>) -> Outcome {
    use crate::device_model::ObjectKind;
    let objects: Vec<_> = ctx.model().objects.values().cloned().collect();
    let mut walk = Walk::new();
    let mut absent = 0;
    for object in objects {
        let at = (object.index, 0xFF);
        let described = ctx.model().entry(at.0, at.1).is_some();
        let reply = ctx.read(at.0, at.1)?;
        let value = match &reply {
            Reply::Done(d) if let Ok(bytes) = <[u8; 4]>::try_from(d.as_slice()) => u32::from_le_bytes(bytes),
            Reply::Refused(code) if !described && req::NO_SUB_INDEX.accepts(*code) => {
                absent += 1;
                continue;
            }
            other => {
                walk.fail(
                    format!("{:04X}h:FF", at.0),
                    Evidence {
                        request: upload_text(at),
                        requirement: format!(
                            "{}: sub-index FFh is an UNSIGNED32 describing the object{}",
                            req::OBJECT_DICTIONARY,
                            if described {
                                ", and the EDS describes it"
                            } else {
                                ", or is absent (0609 0011h)"
                            }
                        ),
                        answer: other.describe(),
                        cause: "the structure sub-index is broken, or missing although the EDS describes it"
                            .to_owned(),
                    },
                );
                continue;
            }
        };
        let code = match object.kind {
            ObjectKind::Domain => 0x02,
            ObjectKind::Var => 0x07,
            ObjectKind::Array => 0x08,
            ObjectKind::Record => 0x09,
        };
        let element = |sub: u8| {
            ctx.model()
                .entry(object.index, sub)
                .and_then(|e| e.data_type)
                .map(|t| t.0)
        };
        let data_type = match object.kind {
            ObjectKind::Var => element(0),
            ObjectKind::Domain => Some(0x000F),
            ObjectKind::Array => object.data_type.or_else(|| element(1)),
            ObjectKind::Record => object.data_type,
        };
        let got_type = ((value >> 8) & 0xFFFF) as u16;
        let wrong =
            (value & 0xFF) as u8 != code || value >> 24 != 0 || data_type.is_some_and(|t| t != got_type);
        if wrong {
            walk.fail(
                format!("{:04X}h:FF", at.0),
                Evidence {
                    request: upload_text(at),
                    requirement: format!(
                        "{}: sub-index FFh holds the object code {code:02X}h{} (reserved bits 0)",
                        req::OBJECT_DICTIONARY,
                        data_type.map_or(String::new(), |t| format!(" and the data type {t:04X}h")),
                    ),
                    answer: format!("{value:#010X}"),
                    cause: "the device describes the object's structure otherwise than its EDS".to_owned(),
                },
            );
        } else {
            walk.checked += 1;
        }
    }
    if walk.checked == 0 && walk.failures.is_empty() {
        return Ok(Finding::not_applicable(format!(
            "no object has sub-index FFh (optional in CiA 301): {absent} answered 0609 0011h or 0800 0000h"
        )));
    }
    walk.record(ctx, &["OD 05"]);
    Ok(walk.finding("structure sub-indices (FFh)"))
}

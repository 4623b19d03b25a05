//! What the NMT resets keep and restore (CCT "State 01", "Transition 01"): reset node (reset
//! application) sets 2000h–9FFFh to their power-on values and then does a reset communication,
//! which sets 1000h–1FFFh to theirs and nothing else (CiA 301 §7.2.8.2). Values are changed over
//! SDO beforehand; "power-on value" is the EDS's DefaultValue, as for `cia301.od.2` (a device with
//! parameters saved before the run (1010h) has other power-on values).
//!
//! The resets are sent from the states nmt.1 does not reset from: reset communication from
//! stopped, reset node from operational, so every state meets both commands.

use canopener_eds::AccessType;
use canopener_wire::NmtCommand;

use crate::context::{Ctx, Reply, hex};
use crate::device_model::{EntryModel, OBJ_FLAG_REFUSE_READ, OBJ_FLAG_REFUSE_WRITE};
use crate::finding::{Evidence, Finding, Outcome, Stop};
use crate::procedures::entries::another_value;
use crate::procedures::nmt::{enter, reset_communication, reset_node};
use crate::procedures::sdo::{download_text, upload_text};
use crate::requirements as req;
use crate::test_def::TestDef;

/// Communication objects the tests change, in order of preference: each changes only its own
/// service's timing (heartbeat, guard time, EMCY inhibit time, a heartbeat consumer entry).
const COMMUNICATION: [(u16, u8); 4] = [(0x1017, 0), (0x100C, 0), (0x1015, 0), (0x1016, 1)];
/// How many application objects a test tries to change at most, and how many it changes.
const APPLICATION_TRIES: usize = 8;
const APPLICATION_CHANGED: usize = 3;

/// The reset tests.
pub fn tests() -> Vec<TestDef> {
    vec![
        TestDef {
            id: "cia301.nmt.10",
            suite: "cia301",
            group: "nmt",
            title: "Reset communication (sent in stopped) restores 1000h–1FFFh to their defaults and keeps 2000h–9FFFh as written",
            references: &[req::NMT_RESETS, req::NMT_STATES, "CCT Transition 01"],
            precondition: "writable communication (1017h, 100Ch, 1015h or 1016h:01) or application (2000h–9FFFh, integer) entries with a DefaultValue that hold what SDO writes",
            tags: &["nmt", "od", "writes", "states"],
            run: reset_communication_areas,
        },
        TestDef {
            id: "cia301.nmt.11",
            suite: "cia301",
            group: "nmt",
            title: "Reset node (sent in operational) restores changed communication and application entries to their DefaultValue",
            references: &[
                req::NMT_RESETS,
                req::EDS_OBJECTS,
                "CCT State 01",
                "CCT Transition 01",
            ],
            precondition: "as cia301.nmt.10",
            tags: &["nmt", "od", "writes", "states"],
            run: reset_node_areas,
        },
    ]
}

/// An entry a test changed: its default and the value written.
struct Changed {
    entry: EntryModel,
    default: Vec<u8>,
    value: Vec<u8>,
}

impl Changed {
    fn at(&self) -> (u16, u8) {
        (self.entry.index, self.entry.sub)
    }
}

/// The value a communication object gets: 1000 ms (or 100 ms for 1015h, in 100 µs units) where a
/// bit flip would make a timer run every millisecond, else a neighbour of the default.
fn communication_value(entry: &EntryModel, default: &[u8]) -> Option<Vec<u8>> {
    match (entry.index, default) {
        (0x1017 | 0x100C | 0x1015, [a, b]) => {
            let value = if u16::from_le_bytes([*a, *b]) == 1000 {
                2000u16
            } else {
                1000
            };
            Some(value.to_le_bytes().to_vec())
        }
        _ => another_value(entry, default),
    }
}

/// Whether the tests may change `entry` and read it back: readable and writable by SDO, with a
/// DefaultValue, and no ObjFlags against it.
fn changeable(entry: &EntryModel) -> bool {
    entry.readable()
        && entry.writable()
        && entry.access != Some(AccessType::Wo)
        && entry.default.is_some()
        && entry.obj_flags & (OBJ_FLAG_REFUSE_WRITE | OBJ_FLAG_REFUSE_READ) == 0
}

/// Words in an object's name that mark a setting a reset may act on beyond its value (a node-ID or
/// bit rate a device takes over at the reset, as maxon's 2000h/2001h) or a command: the reset
/// tests leave such objects alone, whatever their index.
const RISKY_NAMES: [&str; 16] = [
    "node",
    "baud",
    "bit rate",
    "bitrate",
    "bit timing",
    "lss",
    "address",
    "cob",
    "reset",
    "save",
    "store",
    "restore",
    "load",
    "factory",
    "password",
    "command",
];

fn risky(name: &str) -> bool {
    let name = name.to_lowercase();
    RISKY_NAMES.iter().any(|word| name.contains(word))
}

/// Writes `value` to `entry` if it holds its default now, and keeps it if it reads back; the old
/// value is written back after the test.
fn change(ctx: &mut Ctx<'_, '_>, entry: &EntryModel, value: Vec<u8>) -> Result<Option<Changed>, Stop> {
    let Some(default) = entry.default.clone() else {
        return Ok(None);
    };
    let at = (entry.index, entry.sub);
    // A value other than the EDS's default already is cia301.od.2's finding, not this test's.
    if ctx.read(at.0, at.1)? != Reply::Done(default.clone()) {
        return Ok(None);
    }
    if !matches!(ctx.modify(at.0, at.1, value.clone())?, Reply::Done(_)) {
        return Ok(None);
    }
    Ok(
        (ctx.read(at.0, at.1)? == Reply::Done(value.clone())).then(|| Changed {
            entry: entry.clone(),
            default,
            value,
        }),
    )
}

/// Up to `most` communication objects and up to [`APPLICATION_CHANGED`] application objects
/// (parameters before mappable objects) changed from their defaults.
fn change_both_areas(ctx: &mut Ctx<'_, '_>, most: usize) -> Result<(Vec<Changed>, Vec<Changed>), Stop> {
    let mut communication = Vec::new();
    for (index, sub) in COMMUNICATION {
        if communication.len() == most {
            break;
        }
        let Some(entry) = ctx.model().entry(index, sub).filter(|e| changeable(e)).cloned() else {
            continue;
        };
        let Some(value) = entry
            .default
            .as_deref()
            .and_then(|d| communication_value(&entry, d))
        else {
            continue;
        };
        communication.extend(change(ctx, &entry, value)?);
    }
    let mut candidates: Vec<EntryModel> = ctx
        .model()
        .entries
        .values()
        .filter(|e| (0x2000..=0x9FFF).contains(&e.index) && changeable(e) && !risky(&e.name))
        .cloned()
        .collect();
    // The profile area first (its objects are defined, none of them a node-ID or bit rate), and
    // parameters before mappable objects (process data the application may rewrite).
    candidates.sort_by_key(|e| (e.index < 0x6000, e.pdo_mapping));
    let mut application = Vec::new();
    for entry in candidates.iter().take(APPLICATION_TRIES) {
        if application.len() == APPLICATION_CHANGED {
            break;
        }
        let Some(value) = entry.default.as_deref().and_then(|d| another_value(entry, d)) else {
            continue;
        };
        application.extend(change(ctx, entry, value)?);
    }
    Ok((communication, application))
}

fn written(changed: &[&Changed]) -> String {
    changed
        .iter()
        .map(|c| download_text(c.at(), &c.value))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The first entry that does not read `expected(entry)` now, with what it read.
fn first_wrong<'c>(
    ctx: &mut Ctx<'_, '_>,
    changed: &[&'c Changed],
    expected: impl Fn(&Changed) -> &[u8],
) -> Result<Option<(&'c Changed, Reply)>, Stop> {
    for c in changed {
        let reply = ctx.read(c.entry.index, c.entry.sub)?;
        if reply != Reply::Done(expected(c).to_vec()) {
            return Ok(Some((c, reply)));
        }
    }
    Ok(None)
}

fn labels(changed: &[&Changed]) -> String {
    changed
        .iter()
        .map(|c| format!("{:04X}h:{:02X}", c.entry.index, c.entry.sub))
        .collect::<Vec<_>>()
        .join(", ")
}

fn reset_communication_areas(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let (communication, application) = change_both_areas(ctx, 1)?;
    if communication.is_empty() && application.is_empty() {
        return Ok(Finding::not_applicable(
            "no writable entry with a DefaultValue in 1000h–1FFFh (1017h, 100Ch, 1015h, 1016h:01) or 2000h–9FFFh holds a changed value",
        ));
    }
    let all: Vec<&Changed> = communication.iter().chain(&application).collect();
    enter(ctx, NmtCommand::StopRemoteNode)?;
    if !reset_communication(ctx)? {
        return Ok(Finding::inconclusive(
            "no boot-up within 2 s of the reset communication sent in stopped (cia301.nmt.1 judges the boot-up): values not compared",
        ));
    }
    let request = |c: &Changed| {
        format!(
            "{}, NMT stop, NMT reset communication, boot-up, {}",
            written(&all),
            upload_text(c.at())
        )
    };
    let comm: Vec<&Changed> = communication.iter().collect();
    if let Some((c, reply)) = first_wrong(ctx, &comm, |c| &c.default)? {
        return Ok(Finding::fail(
            format!(
                "after reset communication {} is not its default {}",
                c.entry.label(),
                hex(&c.default)
            ),
            Evidence {
                request: request(c),
                requirement: format!(
                    "{}: reset communication sets the communication area 1000h–1FFFh to its power-on values ({} for {:04X}h:{:02X}, the DefaultValue)",
                    req::NMT_RESETS,
                    hex(&c.default),
                    c.entry.index,
                    c.entry.sub
                ),
                answer: reply.describe(),
                cause: "reset communication restarts the services with the values they had instead of their power-on values".to_owned(),
            },
        ));
    }
    let app: Vec<&Changed> = application.iter().collect();
    if let Some((c, reply)) = first_wrong(ctx, &app, |c| &c.value)? {
        return Ok(Finding::fail(
            format!(
                "after reset communication the application object {} lost the value written ({})",
                c.entry.label(),
                hex(&c.value)
            ),
            Evidence {
                request: request(c),
                requirement: format!(
                    "{}: reset communication leaves the application area 2000h–9FFFh alone (only reset node restores it), so {} stays",
                    req::NMT_RESETS,
                    hex(&c.value)
                ),
                answer: reply.describe(),
                cause: "reset communication also restores the application objects, as reset node does"
                    .to_owned(),
            },
        ));
    }
    let mut parts = Vec::new();
    if !comm.is_empty() {
        parts.push(format!("{} back at the default", labels(&comm)));
    }
    if !app.is_empty() {
        parts.push(format!("{} kept", labels(&app)));
    }
    Ok(Finding::pass(format!(
        "after a reset communication in stopped: {}{}",
        parts.join(", "),
        if app.is_empty() {
            " (no application object could be changed)"
        } else if comm.is_empty() {
            " (no communication object could be changed)"
        } else {
            ""
        }
    )))
}

fn reset_node_areas(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let (communication, application) = change_both_areas(ctx, 2)?;
    if communication.is_empty() && application.is_empty() {
        return Ok(Finding::not_applicable(
            "no writable entry with a DefaultValue in 1000h–1FFFh (1017h, 100Ch, 1015h, 1016h:01) or 2000h–9FFFh holds a changed value",
        ));
    }
    let all: Vec<&Changed> = communication.iter().chain(&application).collect();
    enter(ctx, NmtCommand::StartRemoteNode)?;
    if !reset_node(ctx)? {
        return Ok(Finding::inconclusive(
            "no boot-up within 2 s of the reset node sent in operational (cia301.nmt.1 judges the boot-up): values not compared",
        ));
    }
    // CCT State 01: the boot-up, then the parameters back at their default values.
    let found = first_wrong(ctx, &all, |c| &c.default)?;
    ctx.performed("State 01");
    ctx.performed("Transition 01");
    if let Some((c, reply)) = found {
        let area = if c.entry.index < 0x2000 {
            "communication"
        } else {
            "application"
        };
        return Ok(Finding::fail(
            format!(
                "after reset node the {area} object {} is not its default {}",
                c.entry.label(),
                hex(&c.default)
            ),
            Evidence {
                request: format!(
                    "{}, NMT start, NMT reset node, boot-up, {}",
                    written(&all),
                    upload_text(c.at())
                ),
                requirement: format!(
                    "{}: reset node sets 2000h–9FFFh and then 1000h–1FFFh to their power-on values; {}: the DefaultValue {}",
                    req::NMT_RESETS,
                    req::EDS_OBJECTS,
                    hex(&c.default)
                ),
                answer: reply.describe(),
                cause: if area == "application" {
                    "reset node is carried out as a reset communication: the application area keeps its values".to_owned()
                } else {
                    "reset node does not restore the communication area".to_owned()
                },
            },
        ));
    }
    Ok(Finding::pass(format!(
        "after a reset node in operational {} are back at their defaults",
        labels(&all)
    )))
}

//! Store and restore parameters (CCT "Testing other 01–09"): the signatures of 1010h/1011h and what a
//! save and a restore do across a reset (CiA 301 §7.5.2.13, §7.5.2.14).
//!
//! These tests write the device's non-volatile memory: the save test ends with a restore of the
//! defaults ("load" to 1011h:01 and a reset node), so parameters a user had stored before are gone
//! afterwards. `--skip cia301.other` leaves the memory alone.

use crate::context::{Ctx, Reply, hex};
use crate::finding::{Evidence, Finding, Outcome, Prepared, Stop};
use crate::procedures::nmt::reset_node;
use crate::procedures::sdo::{download_text, expect_refusal, read_described, upload_text};
use crate::requirements as req;
use crate::test_def::TestDef;

/// The signature that saves ("save", CiA 301 §7.5.2.13).
pub const SAVE: &[u8] = b"save";
/// The signature that restores the defaults ("load", CiA 301 §7.5.2.14).
pub const LOAD: &[u8] = b"load";
/// The CCT's wrong signature: its log prints signatures as UNSIGNED32 read from the most
/// significant byte ('evas' is "save", 65766173h, sent 73 61 76 65), so its 'wron' is 77726F6Eh,
/// sent as the bytes 6E 6F 72 77 (CCT Testing other 01, 03, 05, 07).
pub const WRON: [u8; 4] = 0x7772_6F6Eu32.to_le_bytes();

/// The store/restore tests.
pub fn tests() -> Vec<TestDef> {
    vec![
        TestDef {
            id: "cia301.other.1",
            suite: "cia301",
            group: "other",
            title: "Every sub-index of 1010h and 1011h that saves/restores on command refuses the CCT's 'wron' (6E 6F 72 77) and the signature with its bytes reversed",
            references: &[
                req::STORE_RESTORE,
                "CCT Testing other 01",
                "CCT Testing other 03",
                "CCT Testing other 05",
                "CCT Testing other 07",
            ],
            precondition: "a sub-index of 1010h / 1011h in the EDS that reads with bit 0 set (the device saves/restores on command)",
            tags: &["store"],
            run: wrong_signatures,
        },
        TestDef {
            id: "cia301.other.2",
            suite: "cia301",
            group: "other",
            title: "A 1017h saved with \"save\" to 1010h:01 survives a reset node; \"load\" to 1011h:01 brings its default back",
            references: &[req::STORE_RESTORE, "CCT Testing other 02", "CCT Testing other 04"],
            precondition: "1010h:01 and 1011h:01 with bit 0 set, and a writable 1017h with a DefaultValue",
            tags: &["store", "writes", "nmt"],
            run: save_and_restore,
        },
        TestDef {
            id: "cia301.other.3",
            suite: "cia301",
            group: "other",
            title: "Saved SYNC settings (1019h, 1007h) survive a reset node; restoring the defaults brings them back",
            references: &[
                req::STORE_RESTORE,
                req::SYNC_OBJECTS,
                "CCT Synchronization 08",
                "CCT Synchronization 10",
            ],
            precondition: "1010h:01 and 1011h:01 with bit 0 set, and a writable 1019h (while 1006h = 0) or 1007h with a DefaultValue",
            tags: &["store", "sync", "writes", "nmt"],
            run: save_sync_settings,
        },
        TestDef {
            id: "cia301.other.4",
            suite: "cia301",
            group: "other",
            title: "A saved SDO channel parameter (1201h–12FFh) survives a reset communication; restoring the defaults brings it back",
            references: &[req::STORE_RESTORE, req::SDO_CLIENT_PARAMETER, "CCT SDO 30"],
            precondition: "1010h:01 and 1011h:01 with bit 0 set, and a writable node-ID or valid COB-ID with a DefaultValue in 1201h–12FFh",
            tags: &["store", "sdo", "writes", "nmt"],
            run: save_sdo_channel,
        },
        TestDef {
            id: "cia301.other.5",
            suite: "cia301",
            group: "other",
            title: "A 1017h saved with \"save\" to 1010h:02 (communication parameters) survives a reset node; \"load\" to 1011h:02 brings its default back",
            references: &[req::STORE_RESTORE, "CCT Testing other 06", "CCT Testing other 08"],
            precondition: "1010h:02 and 1011h:02 with bit 0 set, and a writable 1017h with a DefaultValue",
            tags: &["store", "writes", "nmt"],
            run: save_communication,
        },
        TestDef {
            id: "cia301.other.6",
            suite: "cia301",
            group: "other",
            title: "A configuration date and time written to 1020h and saved with 1010h:01 survive a reset node; \"load\" brings 1020h's defaults back",
            references: &[
                req::STORE_RESTORE,
                req::VERIFY_CONFIGURATION,
                "CCT Testing other 09",
            ],
            precondition: "1010h:01 and 1011h:01 with bit 0 set, and writable 1020h:01/02 with DefaultValues",
            tags: &["store", "writes", "nmt"],
            run: verify_configuration,
        },
    ]
}

/// Whether `index`:`sub` is described and reads with bit 0 set (the device saves/restores that
/// group of parameters on command, CiA 301 §7.5.2.13/14); a failure when the device does not serve
/// an entry its EDS describes.
fn on_command_at(ctx: &mut Ctx<'_, '_>, index: u16, sub: u8) -> Prepared<bool> {
    if !ctx.model().entry(index, sub).is_some_and(|e| e.readable()) {
        return Ok(Ok(false));
    }
    Ok(
        read_described(ctx, index, sub, "what the device saves or restores on command")?
            .map(|d| d.first().is_some_and(|b| b & 1 == 1)),
    )
}

fn wrong_signatures(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let mut checked = Vec::new();
    // The CCT's 'wron' and the right word in the wrong byte order (a device comparing the
    // signature as a big-endian number takes it; not a CCT case).
    let cases: [(u16, &str, [&[u8]; 2]); 2] = [
        (0x1010, "save", [&WRON, b"evas"]),
        (0x1011, "load", [&WRON, b"daol"]),
    ];
    for (index, what, wrongs) in cases {
        // Sub-index 1 is all parameters, 2 communication, 3 application, 4..7Fh manufacturer
        // groups (CiA 301 §7.5.2.13/14).
        for sub in 1..=0x7Fu8 {
            match on_command_at(ctx, index, sub)? {
                Ok(true) => {}
                Ok(false) => continue,
                Err(failed) => return Ok(failed),
            }
            for wrong in wrongs {
                let reply = ctx.write(index, sub, wrong.to_vec())?;
                if *wrong == WRON {
                    // CCT Testing other 01 (1010h:01), 03 (1011h:01), 05 (1010h:02), 07 (1011h:02).
                    match (index, sub) {
                        (0x1010, 1) => ctx.performed("Testing other 01"),
                        (0x1011, 1) => ctx.performed("Testing other 03"),
                        (0x1010, 2) => ctx.performed("Testing other 05"),
                        (0x1011, 2) => ctx.performed("Testing other 07"),
                        _ => {}
                    }
                }
                let finding = expect_refusal(
                    &format!("{} (not \"{what}\")", download_text((index, sub), wrong)),
                    &reply,
                    req::WRONG_SIGNATURE,
                    req::STORE_RESTORE,
                    "the signature is not checked, or compared in the wrong byte order",
                );
                if finding.verdict != crate::model::Verdict::Pass {
                    return Ok(finding);
                }
            }
            checked.push(format!("{index:04X}h:{sub:02X}"));
        }
    }
    Ok(if checked.is_empty() {
        Finding::not_applicable(
            "no sub-index of 1010h or 1011h is in the EDS and reads with bit 0 set: nothing is saved or restored on command",
        )
    } else {
        Finding::pass(format!("wrong signatures refused by {}", checked.join(", ")))
    })
}

fn save_and_restore(ctx: &mut Ctx<'_, '_>) -> Outcome {
    heartbeat_saved_in(ctx, ALL, ["Testing other 02", "Testing other 04"])
}

fn save_communication(ctx: &mut Ctx<'_, '_>) -> Outcome {
    heartbeat_saved_in(ctx, COMMUNICATION, ["Testing other 06", "Testing other 08"])
}

/// A new 1017h saved and restored with the parameter group `group` of 1010h/1011h (CCT `cases`:
/// the save, the restore).
fn heartbeat_saved_in(ctx: &mut Ctx<'_, '_>, group: u8, cases: [&str; 2]) -> Outcome {
    let Some(target) = stored_target(
        ctx,
        0x1017,
        1234u16.to_le_bytes().to_vec(),
        4321u16.to_le_bytes().to_vec(),
    ) else {
        return Ok(Finding::not_applicable("no writable 1017h with a DefaultValue"));
    };
    survives_reset(ctx, &[target], Reset::Node, group, cases)
}

/// 1020h (CiA 301 §7.5.2): a configuration tool writes the date (days since 1 January 1984) and
/// time (ms after midnight) of the configuration it downloaded, then saves with 1010h:01; after a
/// reset the device holds them (CCT Testing other 09), and after "load" its defaults again.
fn verify_configuration(ctx: &mut Ctx<'_, '_>) -> Outcome {
    // 2024-01-01 (14610 days after 1984-01-01), 12:00:00.000.
    let date = stored_target_at(
        ctx,
        0x1020,
        1,
        14_610u32.to_le_bytes().to_vec(),
        14_611u32.to_le_bytes().to_vec(),
    );
    let time = stored_target_at(
        ctx,
        0x1020,
        2,
        43_200_000u32.to_le_bytes().to_vec(),
        43_200_001u32.to_le_bytes().to_vec(),
    );
    let (Some(date), Some(time)) = (date, time) else {
        return Ok(Finding::not_applicable(
            "no writable 1020h:01 and 1020h:02 (verify configuration) with DefaultValues",
        ));
    };
    survives_reset(
        ctx,
        &[date, time],
        Reset::Node,
        ALL,
        ["Testing other 09", "Testing other 09"],
    )
}

fn save_sync_settings(ctx: &mut Ctx<'_, '_>) -> Outcome {
    // 1019h may only change while 1006h is 0 (CiA 301 §7.5.2.22): the test leaves 1006h alone.
    let running = !matches!(ctx.read(0x1006, 0)?, Reply::Done(d) if d.iter().all(|b| *b == 0));
    let mut targets = Vec::new();
    if !running && let Some(target) = stored_target(ctx, 0x1019, vec![5], vec![10]) {
        targets.push(target);
    }
    if let Some(target) = stored_target(
        ctx,
        0x1007,
        1000u32.to_le_bytes().to_vec(),
        2000u32.to_le_bytes().to_vec(),
    ) {
        targets.push(target);
    }
    if targets.is_empty() {
        return Ok(Finding::not_applicable(
            "no writable 1019h (with 1006h = 0) or 1007h with a DefaultValue",
        ));
    }
    survives_reset(
        ctx,
        &targets,
        Reset::Node,
        ALL,
        ["Synchronization 08", "Synchronization 10"],
    )
}

/// A value to save: `index`:00, its DefaultValue and a value other than the default (`value`, or
/// `other` when the default is `value`); `None` unless the EDS makes it writable with a default.
fn stored_target(ctx: &Ctx<'_, '_>, index: u16, value: Vec<u8>, other: Vec<u8>) -> Option<Stored> {
    stored_target_at(ctx, index, 0, value, other)
}

/// [`stored_target`] for `index`:`sub`.
fn stored_target_at(
    ctx: &Ctx<'_, '_>,
    index: u16,
    sub: u8,
    value: Vec<u8>,
    other: Vec<u8>,
) -> Option<Stored> {
    let default = ctx
        .model()
        .entry(index, sub)
        .filter(|e| e.writable() && e.size() == Some(value.len()))
        .and_then(|e| e.default.clone())?;
    let value = if default == value { other } else { value };
    Some(Stored {
        index,
        sub,
        default,
        value,
    })
}

/// An entry the save tests change, save and restore.
struct Stored {
    index: u16,
    sub: u8,
    default: Vec<u8>,
    value: Vec<u8>,
}

/// 1010h/1011h sub-index 1: all parameters.
const ALL: u8 = 1;
/// 1010h/1011h sub-index 2: the communication parameters (1000h-1FFFh).
const COMMUNICATION: u8 = 2;

/// Writes every target's value, saves the parameter group `group` ("save" to 1010h:`group`),
/// resets and expects the values back (the first of `cases`, recorded once judged); then restores
/// that group's defaults ("load" to 1011h:`group`), resets the node and expects the defaults (the
/// second case).
fn survives_reset(
    ctx: &mut Ctx<'_, '_>,
    targets: &[Stored],
    reset: Reset,
    group: u8,
    cases: [&str; 2],
) -> Outcome {
    for index in [0x1010, 0x1011] {
        match on_command_at(ctx, index, group)? {
            Ok(true) => {}
            Ok(false) => {
                return Ok(Finding::not_applicable(format!(
                    "{index:04X}h:{group:02X} is not in the EDS or reads with bit 0 clear: the device does not {} this parameter group on command",
                    if index == 0x1010 { "save" } else { "restore" }
                )));
            }
            Err(failed) => return Ok(failed),
        }
    }
    let written: Vec<String> = targets
        .iter()
        .map(|t| download_text((t.index, t.sub), &t.value))
        .collect();
    let read: Vec<String> = targets.iter().map(|t| upload_text((t.index, t.sub))).collect();
    let steps = format!(
        "{}, {}, NMT {}, {}",
        written.join(", "),
        download_text((0x1010, group), SAVE),
        reset.name(),
        read.join(", ")
    );
    for target in targets {
        if !matches!(
            ctx.write(target.index, target.sub, target.value.clone())?,
            Reply::Done(_)
        ) {
            // The verdict is already decided; the restore only puts the device back.
            let _ = restore_defaults(ctx, targets, group)?;
            return Ok(Finding::inconclusive(format!(
                "{:04X}h:{:02X} did not accept a new value",
                target.index, target.sub
            )));
        }
    }
    let saved = ctx.write(0x1010, group, SAVE.to_vec())?;
    if !matches!(saved, Reply::Done(_)) {
        let _ = restore_defaults(ctx, targets, group)?;
        ctx.performed(cases[0]);
        return Ok(Finding::fail(
            format!("\"save\" to 1010h:{group:02X} refused: {}", saved.describe()),
            Evidence {
                request: download_text((0x1010, group), SAVE),
                requirement: format!(
                    "{}: with bit 0 set the device saves on the signature \"save\"",
                    req::STORE_RESTORE
                ),
                answer: saved.describe(),
                cause: format!("1010h:{group:02X} claims saving on command but refuses the signature"),
            },
        ));
    }
    let reset_ok = match reset {
        Reset::Node => reset_node(ctx)?,
        Reset::Communication => crate::procedures::nmt::reset_communication(ctx)?,
    };
    if !reset_ok {
        let _ = restore_defaults(ctx, targets, group)?;
        return Ok(Finding::inconclusive(format!(
            "no boot-up after the {}",
            reset.name()
        )));
    }
    let mut lost = None;
    for target in targets {
        let after = ctx.read(target.index, target.sub)?;
        if !matches!(&after, Reply::Done(d) if *d == target.value) {
            lost = Some((target, after));
            break;
        }
    }
    ctx.performed(cases[0]);
    let restored = restore_defaults(ctx, targets, group)?;
    if let Some((target, after)) = lost {
        return Ok(Finding::fail(
            format!(
                "the saved {:04X}h:{:02X} did not survive a {}",
                target.index,
                target.sub,
                reset.name()
            ),
            Evidence {
                request: steps,
                requirement: format!(
                    "{}: saved parameters are applied at the next reset ({} expected)",
                    req::STORE_RESTORE,
                    hex(&target.value)
                ),
                answer: after.describe(),
                cause: "\"save\" is confirmed but nothing is stored".to_owned(),
            },
        ));
    }
    if !matches!(restored, Err((_, None))) {
        ctx.performed(cases[1]);
    }
    let names: Vec<String> = targets
        .iter()
        .map(|t| format!("{:04X}h:{:02X}", t.index, t.sub))
        .collect();
    Ok(match restored {
        Ok(()) => Finding::pass(format!(
            "{} saved with 1010h:{group:02X} across a {}, defaults back after \"load\" to 1011h:{group:02X}",
            names.join(" and "),
            reset.name()
        )),
        Err((target, other)) => Finding::fail(
            format!(
                "after \"load\" to 1011h:{group:02X} and a reset, {:04X}h:{:02X} is not its default",
                target.index, target.sub
            ),
            Evidence {
                request: format!(
                    "{}, NMT reset node, {}",
                    download_text((0x1011, group), LOAD),
                    upload_text((target.index, target.sub))
                ),
                requirement: format!(
                    "{}: restored defaults ({}) apply at the next reset",
                    req::STORE_RESTORE,
                    hex(&target.default)
                ),
                answer: other.map_or("no boot-up after the reset".to_owned(), |r| r.describe()),
                cause: "\"load\" is confirmed but the saved parameters stay".to_owned(),
            },
        ),
    })
}

/// "load" to 1011h:`group`, reset node, and the first target that then does not read its default,
/// with what it read (`None` without a boot-up).
fn restore_defaults<'t>(
    ctx: &mut Ctx<'_, '_>,
    targets: &'t [Stored],
    group: u8,
) -> Result<Result<(), (&'t Stored, Option<Reply>)>, Stop> {
    ctx.write(0x1011, group, LOAD.to_vec())?;
    if !reset_node(ctx)? {
        return Ok(targets.first().map_or(Ok(()), |t| Err((t, None))));
    }
    for target in targets {
        let reply = ctx.read(target.index, target.sub)?;
        if !matches!(&reply, Reply::Done(d) if *d == target.default) {
            return Ok(Err((target, Some(reply))));
        }
    }
    Ok(Ok(()))
}

/// The reset after which saved values must be back.
#[derive(Debug, Clone, Copy)]
enum Reset {
    Node,
    Communication,
}

impl Reset {
    fn name(self) -> &'static str {
        match self {
            Reset::Node => "reset node",
            Reset::Communication => "reset communication",
        }
    }
}

fn save_sdo_channel(ctx: &mut Ctx<'_, '_>) -> Outcome {
    // A node-ID (sub-index 3) or a valid COB-ID (made invalid) of 1201h–12FFh can always change.
    let target = ctx
        .model()
        .entries
        .values()
        .filter(|e| (0x1201..=0x12FF).contains(&e.index) && e.writable())
        .find_map(|e| {
            let default = e.default.clone()?;
            let value = match (e.sub, default.as_slice()) {
                (3, [node]) => vec![if *node == 1 { 2 } else { 1 }],
                (1 | 2, [a, b, c, d]) if d & 0x80 == 0 => vec![*a, *b, *c, d | 0x80],
                _ => return None,
            };
            Some(Stored {
                index: e.index,
                sub: e.sub,
                default,
                value,
            })
        });
    let Some(target) = target else {
        return Ok(Finding::not_applicable(
            "no writable node-ID or valid COB-ID with a DefaultValue in 1201h–12FFh",
        ));
    };
    survives_reset(ctx, &[target], Reset::Communication, ALL, ["SDO 30", "SDO 30"])
}

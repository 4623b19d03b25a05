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

/// The store/restore tests.
pub fn tests() -> Vec<TestDef> {
    vec![
        TestDef {
            id: "cia301.other.1",
            suite: "cia301",
            group: "other",
            title: "Every sub-index of 1010h and 1011h that saves/restores on command refuses \"wron\" and the reversed signature",
            references: &[
                req::STORE_RESTORE,
                "CCT Testing other 01",
                "CCT Testing other 03",
                "CCT Testing other 05",
                "CCT Testing other 06",
                "CCT Testing other 07",
                "CCT Testing other 08",
            ],
            precondition: "a sub-index of 1010h / 1011h in the EDS that reads with bit 0 set (the device saves/restores on command)",
            tags: &["store"],
            run: wrong_signatures,
        },
        TestDef {
            id: "cia301.other.2",
            suite: "cia301",
            group: "other",
            title: "A saved 1017h survives a reset node; restoring the defaults brings its default back",
            references: &[
                req::STORE_RESTORE,
                "CCT Testing other 02",
                "CCT Testing other 04",
                "CCT Testing other 09",
            ],
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
    ]
}

/// Whether `index`:01 is described and reads with bit 0 set.
fn on_command(ctx: &mut Ctx<'_, '_>, index: u16) -> Prepared<bool> {
    on_command_at(ctx, index, 1)
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
    // "wron" (CCT Testing other 07) and the right word in the wrong byte order (a device comparing
    // the signature as a big-endian number takes it).
    let cases: [(u16, &str, [&[u8]; 2]); 2] = [
        (0x1010, "save", [b"wron", b"evas"]),
        (0x1011, "load", [b"wron", b"daol"]),
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
                let finding = expect_refusal(
                    &format!("{} (not \"{what}\")", download_text((index, sub), wrong),),
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
    let Some(target) = stored_target(
        ctx,
        0x1017,
        1234u16.to_le_bytes().to_vec(),
        4321u16.to_le_bytes().to_vec(),
    ) else {
        return Ok(Finding::not_applicable("no writable 1017h with a DefaultValue"));
    };
    survives_reset(ctx, &[target], Reset::Node)
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
    survives_reset(ctx, &targets, Reset::Node)
}

/// A value to save: `index`:00, its DefaultValue and a value other than the default (`value`, or
/// `other` when the default is `value`); `None` unless the EDS makes it writable with a default.
fn stored_target(ctx: &Ctx<'_, '_>, index: u16, value: Vec<u8>, other: Vec<u8>) -> Option<Stored> {
    let default = ctx
        .model()
        .entry(index, 0)
        .filter(|e| e.writable() && e.size() == Some(value.len()))
        .and_then(|e| e.default.clone())?;
    let value = if default == value { other } else { value };
    Some(Stored {
        index,
        sub: 0,
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

/// Writes every target's value, saves all parameters ("save" to 1010h:01), resets the node and
/// expects the values back; then restores the defaults ("load" to 1011h:01), resets the node and
/// expects the defaults.
fn survives_reset(ctx: &mut Ctx<'_, '_>, targets: &[Stored], reset: Reset) -> Outcome {
    for index in [0x1010, 0x1011] {
        match on_command(ctx, index)? {
            Ok(true) => {}
            Ok(false) => {
                return Ok(Finding::not_applicable(format!(
                    "{index:04X}h:01 is not in the EDS or reads with bit 0 clear: the device does not {} all parameters on command",
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
        download_text((0x1010, 1), SAVE),
        reset.name(),
        read.join(", ")
    );
    for target in targets {
        if !matches!(
            ctx.write(target.index, target.sub, target.value.clone())?,
            Reply::Done(_)
        ) {
            // The verdict is already decided; the restore only puts the device back.
            let _ = restore_defaults(ctx, targets)?;
            return Ok(Finding::inconclusive(format!(
                "{:04X}h did not accept a new value",
                target.index
            )));
        }
    }
    let saved = ctx.write(0x1010, 1, SAVE.to_vec())?;
    if !matches!(saved, Reply::Done(_)) {
        let _ = restore_defaults(ctx, targets)?;
        return Ok(Finding::fail(
            format!("\"save\" to 1010h:01 refused: {}", saved.describe()),
            Evidence {
                request: download_text((0x1010, 1), SAVE),
                requirement: format!(
                    "{}: with bit 0 set the device saves on the signature \"save\"",
                    req::STORE_RESTORE
                ),
                answer: saved.describe(),
                cause: "1010h:01 claims saving on command but refuses the signature".to_owned(),
            },
        ));
    }
    let reset_ok = match reset {
        Reset::Node => reset_node(ctx)?,
        Reset::Communication => crate::procedures::nmt::reset_communication(ctx)?,
    };
    if !reset_ok {
        let _ = restore_defaults(ctx, targets)?;
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
    let restored = restore_defaults(ctx, targets)?;
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
    let names: Vec<String> = targets.iter().map(|t| format!("{:04X}h", t.index)).collect();
    Ok(match restored {
        Ok(()) => Finding::pass(format!(
            "{} saved across a reset, defaults back after \"load\"",
            names.join(" and ")
        )),
        Err((target, other)) => Finding::fail(
            format!(
                "after \"load\" to 1011h:01 and a reset, {:04X}h is not its default",
                target.index
            ),
            Evidence {
                request: format!(
                    "{}, NMT reset node, {}",
                    download_text((0x1011, 1), LOAD),
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

/// "load" to 1011h:01, reset node, and the first target that then does not read its default, with
/// what it read (`None` without a boot-up).
fn restore_defaults<'t>(
    ctx: &mut Ctx<'_, '_>,
    targets: &'t [Stored],
) -> Result<Result<(), (&'t Stored, Option<Reply>)>, Stop> {
    ctx.write(0x1011, 1, LOAD.to_vec())?;
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
    survives_reset(ctx, &[target], Reset::Communication)
}

//! PDOs per NMT state (CCT "State 02–04"): CiA 301 runs PDOs in operational only (§7.2.8.2, the
//! table of services per NMT state), so a TPDO that transmits on its own is silent in
//! pre-operational and stopped and an RPDO received there is not acted on; and a TPDO whose COB-ID
//! says "not valid" (18xxh:01 bit 31, §7.5.2.35) is never sent.
//!
//! Each test first shows that what it watches for really happens in operational: silence proves
//! nothing about a TPDO that never transmits, nor about an RPDO whose effect cannot be seen. An
//! RPDO's effect is seen by reading a mapped object back over SDO, so the RPDO test needs a valid
//! RPDO that maps an object SDO can read and write.

use std::time::Duration;

use canopener_wire::NmtCommand;

use crate::context::{Ctx, Reply, hex};
use crate::device_model::{PdoDirection, PdoModel};
use crate::finding::{Evidence, Finding, Outcome, Prepared, Stop};
use crate::model::Verdict;
use crate::procedures::entries::another_value;
use crate::procedures::nmt::{back_to_pre_operational, enter};
use crate::procedures::sdo::{download_text, u32_of, upload_text};
use crate::procedures::tpdo::{
    Setting, Step as ConfigStep, configurable_tpdo_at, configure_tpdo, judge_step, none_configurable,
    not_writable,
};
use crate::recorder::Logged;
use crate::requirements as req;
use crate::test_def::TestDef;

/// The event timer the tests set, in ms: short, so that a watch of a few periods is quick.
pub const TEST_EVENT_TIMER_MS: u16 = 20;
/// How long a state is watched for an event-timer TPDO: three periods.
pub const WATCH: Duration = Duration::from_millis(3 * TEST_EVENT_TIMER_MS as u64);
/// The time after each SYNC the tester sends in which the TPDO it triggers must come (or not).
pub const AFTER_SYNC: Duration = Duration::from_millis(20);
/// SYNCs sent per state to a TPDO of transmission type 1.
pub const SYNCS_PER_STATE: usize = 2;
/// How long an RPDO (and a SYNC, for a synchronous one) gets to take effect.
pub const RPDO_EFFECT: Duration = Duration::from_millis(20);

/// The PDO-per-state tests.
pub fn tests() -> Vec<TestDef> {
    vec![
        TestDef {
            id: "cia301.nmt.5",
            suite: "cia301",
            group: "nmt",
            title: "TPDOs only in operational: an event-timer TPDO and a SYNC-triggered TPDO (and remote requests) are silent in pre-operational and stopped",
            references: &[
                req::NMT_STATES,
                req::PDO,
                "CCT State 02",
                "CCT State 03",
                "CCT State 04",
            ],
            precondition: "a TPDO with writable COB-ID and transmission type and mapped data (the event-timer part needs a writable 18xxh:05, the SYNC part a SYNC consumer 1005h); a refusal to set it up is not_applicable",
            tags: &["nmt", "pdo", "sync", "writes", "states"],
            run: tpdo_per_state,
        },
        TestDef {
            id: "cia301.nmt.6",
            suite: "cia301",
            group: "nmt",
            title: "RPDOs only in operational: an RPDO received in pre-operational or stopped leaves its mapped object unchanged, in operational it writes it",
            references: &[
                req::NMT_STATES,
                req::PDO,
                "CCT State 02",
                "CCT State 03",
                "CCT State 04",
            ],
            precondition: "a valid RPDO mapping whole bytes of objects SDO can read, one of them an integer (else one mapped for the test with the mapping procedure); not_applicable when the EDS has no RPDO or no writable object with PDOMapping=1, inconclusive when nothing an RPDO writes can be read back",
            tags: &["nmt", "pdo", "writes", "states"],
            run: rpdo_per_state,
        },
        TestDef {
            id: "cia301.pdo.20",
            suite: "cia301",
            group: "pdo",
            title: "A TPDO whose 18xxh:01 bit 31 says \"not valid\" is never sent, also when made not valid in operational",
            references: &[req::PDO_PARAMETERS, req::PDO],
            precondition: "a TPDO with writable COB-ID and transmission type and mapped data, and a writable 18xxh:05 or a SYNC consumer (1005h)",
            tags: &["pdo", "writes", "nmt", "states"],
            run: invalid_tpdo,
        },
    ]
}

/// Where the tester's SYNCs go and the counter they carry.
struct SyncSource {
    id: u16,
    /// 1019h when it is above 1: the counter overflow value; the SYNCs then carry a counter.
    overflow: Option<u8>,
    next: u8,
}

impl SyncSource {
    /// The device's SYNC COB-ID (1005h) when it consumes SYNC; `None` when the EDS has no 1005h or
    /// the device produces SYNC itself (bit 30), since a second producer would break the bus's SYNC.
    fn of(ctx: &mut Ctx<'_, '_>) -> Result<Option<SyncSource>, Stop> {
        if !ctx.model().has(0x1005) {
            return Ok(None);
        }
        let Some(cob) = u32_of(&ctx.read(0x1005, 0)?) else {
            return Ok(None);
        };
        if cob & 0x4000_0000 != 0 {
            return Ok(None);
        }
        let overflow = if ctx.model().has(0x1019) {
            match ctx.read(0x1019, 0)? {
                Reply::Done(ref d)
                    if let [count] = d.as_slice()
                        && *count > 1 =>
                {
                    Some(*count)
                }
                _ => None,
            }
        } else {
            None
        };
        Ok(Some(SyncSource {
            id: (cob & 0x7FF) as u16,
            overflow,
            next: 1,
        }))
    }

    /// Sends one SYNC (with the next counter value when 1019h asks for one).
    fn send(&mut self, ctx: &mut Ctx<'_, '_>) -> Result<(), Stop> {
        match self.overflow {
            Some(overflow) => {
                let counter = self.next;
                self.next = if counter >= overflow { 1 } else { counter + 1 };
                ctx.send(self.id, &[counter])
            }
            None => ctx.send(self.id, &[]),
        }
    }
}

/// What makes the TPDO under test transmit by itself.
enum Trigger {
    /// Transmission type FFh with the event timer [`TEST_EVENT_TIMER_MS`].
    EventTimer,
    /// Transmission type 1, driven by the tester's SYNCs.
    Sync(SyncSource),
}

impl Trigger {
    fn name(&self) -> &'static str {
        match self {
            Trigger::EventTimer => "event timer",
            Trigger::Sync(_) => "SYNC",
        }
    }

    fn describe(&self, number: u16) -> String {
        match self {
            Trigger::EventTimer => {
                format!("TPDO{number} with transmission type FFh and event timer {TEST_EVENT_TIMER_MS} ms")
            }
            Trigger::Sync(_) => format!("TPDO{number} with transmission type 1 (every SYNC)"),
        }
    }

    fn settings(&self) -> Vec<Setting> {
        match self {
            Trigger::EventTimer => vec![
                Setting::new(2, vec![0xFF], "event-driven transmission (type FFh)"),
                Setting::new(
                    5,
                    TEST_EVENT_TIMER_MS.to_le_bytes().to_vec(),
                    "the event timer (18xxh:05) at this value",
                ),
            ],
            Trigger::Sync(_) => vec![Setting::new(
                2,
                vec![1],
                "cyclic synchronous transmission (type 1)",
            )],
        }
    }

    /// Watches the TPDO's CAN-ID `cob` for as long as the trigger needs to have fired; SYNCs are
    /// sent meanwhile, and a remote frame first when `rtr`. Returns the TPDOs seen.
    fn watch(&mut self, ctx: &mut Ctx<'_, '_>, cob: u16, rtr: bool) -> Result<Vec<Logged>, Stop> {
        let id = ctx.id(cob);
        if rtr {
            ctx.send_remote(cob, 0)?;
        }
        let tpdo = |f: &canopener_can::CanFrame| f.id() == id && !f.is_remote();
        match self {
            Trigger::EventTimer => ctx.listen(WATCH, tpdo),
            Trigger::Sync(source) => {
                let mut seen = Vec::new();
                for _ in 0..SYNCS_PER_STATE {
                    source.send(ctx)?;
                    seen.extend(ctx.listen(AFTER_SYNC, tpdo)?);
                }
                Ok(seen)
            }
        }
    }

    /// What the tester did in one watch, for an analysis.
    fn stimulus(&self, rtr: bool) -> String {
        let rtr = if rtr { "a remote frame, then " } else { "" };
        match self {
            Trigger::EventTimer => format!("{rtr}{} ms of listening", WATCH.as_millis()),
            Trigger::Sync(_) => format!("{rtr}{SYNCS_PER_STATE} SYNCs {} ms apart", AFTER_SYNC.as_millis()),
        }
    }
}

/// A state of the walk: the command that enters it (none for the first, pre-operational), its
/// name, and whether PDOs run there.
type Step = (Option<NmtCommand>, &'static str, bool);

/// Pre-operational, operational, stopped, pre-operational again: transitions 3, 5 and 7 of CiA
/// 301's state diagram, each state watched.
const WALK: [Step; 4] = [
    (None, "pre-operational", false),
    (Some(NmtCommand::StartRemoteNode), "operational", true),
    (Some(NmtCommand::StopRemoteNode), "stopped", false),
    (
        Some(NmtCommand::EnterPreOperational),
        "pre-operational (after stopped)",
        false,
    ),
];

/// A TPDO the state tests drive: its model, its COB-ID as read, and the triggers it can be set up for.
type TpdoUnderTest = (PdoModel, u32, Vec<Trigger>);

/// The TPDO the state tests drive, its COB-ID, and the triggers it can be set up for; when none
/// can be, the reasons per TPDO (the EDS key that rules each out).
fn tpdo_under_test(ctx: &mut Ctx<'_, '_>) -> Prepared<Result<TpdoUnderTest, Vec<String>>> {
    let mut passed_over = Vec::new();
    for pdo in ctx.model().pdos(PdoDirection::Transmit) {
        if let Some(why) = not_writable(ctx, pdo.comm, 2, None) {
            passed_over.push(format!("TPDO{}: {why}", pdo.number));
            continue;
        }
        let cob = match configurable_tpdo_at(ctx, &pdo, &[])? {
            Ok(Ok(cob)) => cob,
            Ok(Err(why)) => {
                passed_over.push(format!("TPDO{}: {why}", pdo.number));
                continue;
            }
            Err(failed) => return Ok(Err(failed)),
        };
        let mut triggers = Vec::new();
        if ctx.model().entry(pdo.comm, 5).is_some_and(|e| e.writable()) {
            triggers.push(Trigger::EventTimer);
        }
        if let Some(source) = SyncSource::of(ctx)? {
            triggers.push(Trigger::Sync(source));
        }
        return Ok(Ok(Ok((pdo, cob, triggers))));
    }
    Ok(Ok(Err(passed_over)))
}

/// Sets the TPDO up for `trigger`, with RTR allowed if the device takes it (`true`); `Ok(Err)` is
/// the reason the device does not support the trigger (a refusal CiA 301 allows, see
/// [`judge_step`]); any other refusal or a timeout fails the test.
fn set_up(
    ctx: &mut Ctx<'_, '_>,
    pdo: &PdoModel,
    cob: u32,
    trigger: &Trigger,
) -> Prepared<Result<bool, String>> {
    let settings = trigger.settings();
    match configure_tpdo(ctx, pdo, cob, &settings, true)? {
        Ok(()) => return Ok(Ok(Ok(true))),
        // RTR on PDOs is optional (CiA 301 §7.2.2.2.1): without it the remote frames are left out.
        Err(finding) if finding.verdict == Verdict::NotApplicable => {}
        Err(failed) => return Ok(Err(failed)),
    }
    Ok(match configure_tpdo(ctx, pdo, cob, &settings, false)? {
        Ok(()) => Ok(Ok(false)),
        Err(finding) if finding.verdict == Verdict::NotApplicable => Ok(Err(finding.reason)),
        Err(failed) => Err(failed),
    })
}

fn tpdo_per_state(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let (pdo, cob, triggers) = match tpdo_under_test(ctx)? {
        Ok(Ok(found)) => found,
        Ok(Err(passed_over)) => return Ok(none_configurable(passed_over.as_slice())),
        Err(failed) => return Ok(failed),
    };
    if triggers.is_empty() {
        return Ok(Finding::not_applicable(format!(
            "TPDO{} has no writable event timer (18xxh:05) and the device consumes no SYNC (no 1005h, or 1005h bit 30: it produces SYNC)",
            pdo.number
        )));
    }
    let can_id = (cob & 0x7FF) as u16;
    let mut done = Vec::new();
    let mut refusals = Vec::new();
    for mut trigger in triggers {
        let rtr = match set_up(ctx, &pdo, cob, &trigger)? {
            Ok(Ok(rtr)) => rtr,
            Ok(Err(refused)) => {
                refusals.push(format!("{}: {refused}", trigger.name()));
                continue;
            }
            Err(failed) => return Ok(failed),
        };
        let what = trigger.describe(pdo.number);
        let mut trail = Vec::new();
        for (command, state, runs) in WALK {
            if let Some(command) = command {
                enter(ctx, command)?;
            }
            // A remote frame where PDOs must not run: an answer there is a TPDO too.
            let seen = trigger.watch(ctx, can_id, rtr && !runs)?;
            trail.push(format!("{state}: {}", trigger.stimulus(rtr && !runs)));
            if !runs && let Some(first) = seen.first() {
                back_to_pre_operational(ctx)?;
                return Ok(Finding::fail(
                    format!("TPDO{} ({can_id:03X}h) sent in {state}", pdo.number),
                    Evidence {
                        request: format!("{what}; {}", trail.join("; ")),
                        requirement: format!(
                            "{}: PDOs are exchanged in operational only, so no TPDO in {state}",
                            req::NMT_STATES
                        ),
                        answer: format!("{} TPDOs, the first {}", seen.len(), hex(first.frame.data())),
                        cause: format!(
                            "the PDO service is not stopped in {state} (TPDOs by {}{})",
                            trigger.name(),
                            if rtr { " or remote request" } else { "" }
                        ),
                    },
                ));
            }
            if runs && seen.is_empty() {
                back_to_pre_operational(ctx)?;
                return Ok(Finding::inconclusive(format!(
                    "{what} sent nothing in operational either, so its silence elsewhere proves nothing (cia301.pdo.6 and cia301.sync.5 judge the triggers)"
                )));
            }
        }
        done.push(format!(
            "{}{}",
            trigger.name(),
            if rtr { " and remote requests" } else { "" }
        ));
    }
    if done.is_empty() {
        return Ok(Finding::not_applicable(format!(
            "TPDO{} cannot be set up to transmit by itself: {}",
            pdo.number,
            refusals.join("; ")
        )));
    }
    Ok(Finding::pass(format!(
        "TPDO{} ({}) sent in operational only",
        pdo.number,
        done.join("; ")
    )))
}

fn invalid_tpdo(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let (pdo, cob, mut triggers) = match tpdo_under_test(ctx)? {
        Ok(Ok(found)) => found,
        Ok(Err(passed_over)) => return Ok(none_configurable(passed_over.as_slice())),
        Err(failed) => return Ok(failed),
    };
    // One trigger is enough to show the bit is obeyed; the event timer needs no SYNCs.
    let Some(mut trigger) = (!triggers.is_empty()).then(|| triggers.remove(0)) else {
        return Ok(Finding::not_applicable(format!(
            "TPDO{} has no writable event timer (18xxh:05) and the device consumes no SYNC",
            pdo.number
        )));
    };
    let can_id = (cob & 0x7FF) as u16;
    let invalid = (cob | 0x8000_0000).to_le_bytes().to_vec();
    let valid = (cob & 0x7FFF_FFFF).to_le_bytes().to_vec();
    // Disabled first: CiA 301 §7.5.2.35 allows changing the parameters of a PDO that is not valid.
    let mut steps = vec![(ConfigStep::Disable, 1u8, invalid.clone())];
    steps.extend(
        trigger
            .settings()
            .into_iter()
            .map(|s| (ConfigStep::Setting(s.feature), s.sub, s.value)),
    );
    let mut done = Vec::new();
    for (step, sub, data) in steps {
        let request = download_text((pdo.comm, sub), &data);
        let reply = ctx.modify(pdo.comm, sub, data)?;
        done.push(request);
        if let Some(finding) = judge_step(
            &format!("TPDO{}", pdo.number),
            step,
            &done.join(", then "),
            &reply,
        ) {
            return Ok(finding);
        }
    }
    let what = trigger.describe(pdo.number);
    let fail = |phase: &str, seen: &[Logged]| {
        Finding::fail(
            format!(
                "TPDO{} ({can_id:03X}h) sent while 18xxh:01 bit 31 is set",
                pdo.number
            ),
            Evidence {
                request: format!("{what}, {phase}"),
                requirement: format!(
                    "{}: bit 31 of the COB-ID set means the PDO does not exist (is not valid): it is not sent",
                    req::PDO_PARAMETERS
                ),
                answer: format!(
                    "{} TPDOs on {can_id:03X}h, the first {}",
                    seen.len(),
                    seen.first().map_or(String::new(), |l| hex(l.frame.data()))
                ),
                cause: "the valid bit of the TPDO's COB-ID is ignored".to_owned(),
            },
        )
    };
    enter(ctx, NmtCommand::StartRemoteNode)?;
    let seen = trigger.watch(ctx, can_id, false)?;
    if !seen.is_empty() {
        back_to_pre_operational(ctx)?;
        return Ok(fail(
            &format!(
                "{} (not valid), NMT start, {}",
                download_text((pdo.comm, 1), &invalid),
                trigger.stimulus(false)
            ),
            &seen,
        ));
    }
    // The same TPDO made valid must transmit, or the silence above proves nothing.
    back_to_pre_operational(ctx)?;
    let reply = ctx.write(pdo.comm, 1, valid.clone())?;
    enter(ctx, NmtCommand::StartRemoteNode)?;
    let sent = trigger.watch(ctx, can_id, false)?;
    if !matches!(reply, Reply::Done(_)) || sent.is_empty() {
        back_to_pre_operational(ctx)?;
        return Ok(Finding::inconclusive(format!(
            "{what}, made valid ({} got {}), sent nothing in operational, so its silence while not valid proves nothing (cia301.pdo.6 and cia301.sync.5 judge the triggers)",
            download_text((pdo.comm, 1), &valid),
            reply.describe()
        )));
    }
    // Made not valid again while operational: it stops. A device may take no SDO downloads in
    // operational (0800 0022h, any refusal): then only the first part is judged.
    let reply = ctx.write(pdo.comm, 1, invalid.clone())?;
    let seen = trigger.watch(ctx, can_id, false)?;
    back_to_pre_operational(ctx)?;
    match reply {
        Reply::Done(_) => {}
        Reply::Refused(code) => {
            return Ok(Finding::pass(format!(
                "TPDO{} ({}) silent while not valid, sent while valid; made not valid in operational was refused with {} (only pre-operational changes were judged)",
                pdo.number,
                trigger.name(),
                crate::requirements::code_meaning(code)
            )));
        }
        other => {
            return Ok(Finding::inconclusive(format!(
                "{} in operational got {}",
                download_text((pdo.comm, 1), &invalid),
                other.describe()
            )));
        }
    }
    if !seen.is_empty() {
        return Ok(fail(
            &format!(
                "sending in operational, then {} (not valid), {}",
                download_text((pdo.comm, 1), &invalid),
                trigger.stimulus(false)
            ),
            &seen,
        ));
    }
    Ok(Finding::pass(format!(
        "TPDO{} ({}) silent while not valid, sent while valid, silent once made not valid in operational",
        pdo.number,
        trigger.name()
    )))
}

/// An RPDO whose effect can be read back: one mapped object takes `new` instead of `old`.
struct RpdoTarget {
    number: u16,
    cob: u16,
    /// Transmission type 0–F0h: the data is taken at the next SYNC.
    synchronous: bool,
    /// The RPDO's data with every mapped object's current value.
    data: Vec<u8>,
    /// Where the target object lies in `data`.
    offset: usize,
    entry: (u16, u8),
    old: Vec<u8>,
    new: Vec<u8>,
    /// SDO wrote `new` and read it back before (and the old value is written back after the
    /// test): the object holds what is written. Otherwise (ObjFlags bit 0, or not writable by SDO)
    /// only RPDOs write it, and an RPDO carrying `old` puts it back.
    sdo_checked: bool,
}

impl RpdoTarget {
    fn frame(&self, value: &[u8]) -> Vec<u8> {
        let mut data = self.data.clone();
        // The target's bytes lie inside the PDO: both come from the same mapping.
        if let Some(target) = data.get_mut(self.offset..self.offset + value.len()) {
            target.copy_from_slice(value);
        }
        data
    }
}

/// A mapped object of an RPDO: (index, sub-index, bytes), dummies with index below 8.
type MappedEntry = (u16, u8, usize);

/// The mapping of a valid RPDO in whole bytes, with its CAN-ID and transmission type.
fn rpdo_mapping(ctx: &mut Ctx<'_, '_>, pdo: &PdoModel) -> Result<Option<(u16, u8, Vec<MappedEntry>)>, Stop> {
    let Some(cob) = u32_of(&ctx.read(pdo.comm, 1)?) else {
        return Ok(None);
    };
    if cob & 0x8000_0000 != 0 || cob & 0x7FF == 0 {
        return Ok(None);
    }
    let kind = match ctx.read(pdo.comm, 2)? {
        Reply::Done(ref d) if let [byte] = d.as_slice() => *byte,
        _ => return Ok(None),
    };
    let Some(mapping) = pdo.mapping else {
        return Ok(None);
    };
    let count = match ctx.read(mapping, 0)? {
        Reply::Done(ref d) if let [byte] = d.as_slice() => *byte,
        _ => return Ok(None),
    };
    let mut entries = Vec::new();
    for sub in 1..=count {
        let Some(value) = u32_of(&ctx.read(mapping, sub)?) else {
            return Ok(None);
        };
        let bits = value & 0xFF;
        if bits == 0 || bits % 8 != 0 {
            return Ok(None);
        }
        entries.push(((value >> 16) as u16, (value >> 8) as u8, bits as usize / 8));
    }
    let bytes: usize = entries.iter().map(|e| e.2).sum();
    Ok((!entries.is_empty() && bytes <= 8).then_some(((cob & 0x7FF) as u16, kind, entries)))
}

/// Makes the valid RPDO `pdo` (on `cob`) event-driven: not valid, transmission type FFh, valid
/// again, every value written back after the test; `false` when the device refuses.
fn event_driven(ctx: &mut Ctx<'_, '_>, pdo: &PdoModel, cob: u16) -> Result<bool, Stop> {
    if !ctx.model().entry(pdo.comm, 2).is_some_and(|e| e.writable()) {
        return Ok(false);
    }
    let Some(value) = u32_of(&ctx.read(pdo.comm, 1)?).filter(|v| v & 0x7FF == u32::from(cob)) else {
        return Ok(false);
    };
    for (sub, data) in [
        (1u8, (value | 0x8000_0000).to_le_bytes().to_vec()),
        (2, vec![0xFF]),
        (1, value.to_le_bytes().to_vec()),
    ] {
        if !matches!(ctx.modify(pdo.comm, sub, data)?, Reply::Done(_)) {
            return Ok(false);
        }
    }
    Ok(true)
}

/// The first valid RPDO with an object SDO can read, write and read back, checked by writing
/// another value and then the old one again (the old value is written back after the test too);
/// else the first mapped integer SDO can read (which SDO may not write: ObjFlags bit 0, or an
/// access type only PDOs write).
fn rpdo_target(ctx: &mut Ctx<'_, '_>, sync: bool) -> Result<Option<RpdoTarget>, Stop> {
    let mut unchecked = None;
    for pdo in ctx.model().pdos(PdoDirection::Receive) {
        let Some((cob, mut kind, entries)) = rpdo_mapping(ctx, &pdo)? else {
            continue;
        };
        // A synchronous RPDO acts at a SYNC; without SYNCs from the tester it is made event-driven
        // (FFh), disabled while its type changes.
        if kind <= 0xF0 && !sync {
            if !event_driven(ctx, &pdo, cob)? {
                continue;
            }
            kind = 0xFF;
        }
        // The other objects carry their current values, so only the target changes.
        let mut data = Vec::new();
        let mut values = Vec::new();
        let mut readable = true;
        for &(index, sub, bytes) in &entries {
            if index < 0x0008 {
                data.extend(std::iter::repeat_n(0, bytes));
                values.push(None);
                continue;
            }
            match ctx.read(index, sub)? {
                Reply::Done(value) if value.len() == bytes => {
                    data.extend_from_slice(&value);
                    values.push(Some(value));
                }
                _ => {
                    readable = false;
                    break;
                }
            }
        }
        if !readable {
            continue;
        }
        let mut offset = 0;
        for (&(index, sub, bytes), value) in entries.iter().zip(&values) {
            let at = offset;
            offset += bytes;
            let Some(old) = value else { continue };
            let Some(model) = ctx.model().entry(index, sub) else {
                continue;
            };
            let Some(new) = another_value(model, old) else {
                continue;
            };
            let target = RpdoTarget {
                number: pdo.number,
                cob,
                synchronous: kind <= 0xF0,
                data: data.clone(),
                offset: at,
                entry: (index, sub),
                old: old.clone(),
                new: new.clone(),
                sdo_checked: false,
            };
            if !model.writable() || model.obj_flags & crate::device_model::OBJ_FLAG_REFUSE_WRITE != 0 {
                unchecked = unchecked.or(Some(target));
                continue;
            }
            // The object must hold what SDO writes, or an RPDO's effect could not be seen either.
            if !matches!(ctx.modify(index, sub, new.clone())?, Reply::Done(_)) {
                continue;
            }
            let holds = ctx.read(index, sub)? == Reply::Done(new.clone());
            let back = ctx.write(index, sub, old.clone())?;
            if !holds || !matches!(back, Reply::Done(_)) {
                continue;
            }
            return Ok(Some(RpdoTarget {
                sdo_checked: true,
                ..target
            }));
        }
    }
    Ok(unchecked)
}

/// Maps one object into an RPDO with the mapping procedure (CiA 301 §7.5.2.38) for a device whose
/// RPDOs map nothing readable: the first RPDO with a CAN-ID and writable COB-ID and mapping gets a
/// mappable integer SDO can read and write (profile objects first); every value is written back
/// after the test. `Err` is the finding when there is none to map or the device refuses.
fn map_rpdo(ctx: &mut Ctx<'_, '_>) -> Result<Result<(), Finding>, Stop> {
    let writable =
        |ctx: &Ctx<'_, '_>, index: u16, sub: u8| ctx.model().entry(index, sub).is_some_and(|e| e.writable());
    let mut objects: Vec<_> = ctx
        .model()
        .entries
        .values()
        .filter(|e| {
            e.pdo_mapping
                && e.readable()
                && e.writable()
                && e.obj_flags & crate::device_model::OBJ_FLAG_REFUSE_WRITE == 0
                && matches!(e.size(), Some(1 | 2 | 4))
                && e.default
                    .as_deref()
                    .is_some_and(|d| another_value(e, d).is_some())
        })
        .map(|e| (e.index, e.sub, e.size().unwrap_or(0)))
        .collect();
    objects.sort_by_key(|(index, _, _)| (*index < 0x6000, *index));
    let Some(&(index, sub, size)) = objects.first() else {
        // An RPDO writes objects with PDOMapping=1 and write access: without any, the EDS says no
        // RPDO can do anything.
        let writes_any = ctx
            .model()
            .entries
            .values()
            .any(|e| e.pdo_mapping && e.writable());
        return Ok(Err(if writes_any {
            Finding::inconclusive(
                "no valid RPDO maps an object SDO can read, and the EDS has no mappable integer SDO can read and write to map into one: an RPDO's effect cannot be observed",
            )
        } else {
            Finding::not_applicable(
                "no valid RPDO maps an object SDO can read, and the EDS has no writable object with PDOMapping=1: RPDOs cannot write anything",
            )
        }));
    };
    for pdo in ctx.model().pdos(PdoDirection::Receive) {
        let Some(mapping) = pdo.mapping else { continue };
        if !(writable(ctx, pdo.comm, 1) && writable(ctx, mapping, 0) && writable(ctx, mapping, 1)) {
            continue;
        }
        let Some(cob) = u32_of(&ctx.read(pdo.comm, 1)?) else {
            continue;
        };
        if cob & 0x7FF == 0 {
            continue;
        }
        let entry = (u32::from(index) << 16) | (u32::from(sub) << 8) | (size as u32 * 8);
        for (at, data) in [
            ((pdo.comm, 1u8), (cob | 0x8000_0000).to_le_bytes().to_vec()),
            ((mapping, 0), vec![0]),
            ((mapping, 1), entry.to_le_bytes().to_vec()),
            ((mapping, 0), vec![1]),
            ((pdo.comm, 1), (cob & 0x7FFF_FFFF).to_le_bytes().to_vec()),
        ] {
            let reply = ctx.modify(at.0, at.1, data.clone())?;
            if !matches!(reply, Reply::Done(_)) {
                return Ok(Err(Finding::inconclusive(format!(
                    "no valid RPDO maps an object SDO can read, and mapping {index:04X}h:{sub:02X} into RPDO{} failed: {} got {}",
                    pdo.number,
                    download_text(at, &data),
                    reply.describe()
                ))));
            }
        }
        return Ok(Ok(()));
    }
    Ok(Err(Finding::inconclusive(
        "no valid RPDO maps an object SDO can read, and no RPDO has a CAN-ID and a writable COB-ID and mapping to map one: an RPDO's effect cannot be observed",
    )))
}

fn rpdo_per_state(ctx: &mut Ctx<'_, '_>) -> Outcome {
    if ctx.model().pdos(PdoDirection::Receive).is_empty() {
        return Ok(Finding::not_applicable("the EDS describes no RPDO (1400h–15FFh)"));
    }
    let mut sync = SyncSource::of(ctx)?;
    let target = match rpdo_target(ctx, sync.is_some())? {
        Some(target) => target,
        None => match map_rpdo(ctx)? {
            Ok(()) => match rpdo_target(ctx, sync.is_some())? {
                Some(target) => target,
                None => {
                    return Ok(Finding::inconclusive(
                        "an RPDO mapped for the test maps no object SDO can read back: an RPDO's effect cannot be observed",
                    ));
                }
            },
            Err(finding) => return Ok(finding),
        },
    };
    if !target.synchronous {
        sync = None;
    }
    let mut rpdo = Rpdo { sync, target };
    let finding = rpdo.walk(ctx)?;
    // An object SDO may not write is put back the way it was changed: by an RPDO in operational.
    if !rpdo.target.sdo_checked {
        enter(ctx, NmtCommand::StartRemoteNode)?;
        let old = rpdo.target.old.clone();
        rpdo.send(ctx, &old)?;
        back_to_pre_operational(ctx)?;
    }
    Ok(finding)
}

/// The RPDO test's target and the SYNCs a synchronous RPDO needs.
struct Rpdo {
    target: RpdoTarget,
    sync: Option<SyncSource>,
}

impl Rpdo {
    /// Sends the RPDO with `value` for the target (and a SYNC for a synchronous one), and gives it
    /// [`RPDO_EFFECT`].
    fn send(&mut self, ctx: &mut Ctx<'_, '_>, value: &[u8]) -> Result<(), Stop> {
        ctx.send(self.target.cob, &self.target.frame(value))?;
        if let Some(sync) = self.sync.as_mut() {
            sync.send(ctx)?;
        }
        ctx.listen(RPDO_EFFECT, |_| false).map(drop)
    }

    /// `RPDO1 on 205h = 01 00 and a SYNC`.
    fn sent(&self) -> String {
        let t = &self.target;
        let sync = if self.sync.is_some() { " and a SYNC" } else { "" };
        format!(
            "RPDO{} on {:03X}h = {}{sync} carrying {} for {:04X}h:{:02X}",
            t.number,
            t.cob,
            hex(&t.frame(&t.new)),
            hex(&t.new),
            t.entry.0,
            t.entry.1
        )
    }

    /// Pre-operational and stopped: the object keeps its value; operational: it takes the RPDO's.
    fn walk(&mut self, ctx: &mut Ctx<'_, '_>) -> Outcome {
        let entry = self.target.entry;
        let (old, new) = (self.target.old.clone(), self.target.new.clone());
        for stopped in [false, true] {
            let state = if stopped { "stopped" } else { "pre-operational" };
            if stopped {
                enter(ctx, NmtCommand::StopRemoteNode)?;
            }
            self.send(ctx, &new)?;
            // Stopped serves no SDO: the object is read back in pre-operational.
            if stopped {
                back_to_pre_operational(ctx)?;
            }
            let after = ctx.read(entry.0, entry.1)?;
            if after != Reply::Done(old.clone()) {
                if !self.target.sdo_checked {
                    // Put back in the state that took it, before the operational write-back.
                    self.send(ctx, &old)?;
                }
                return Ok(Finding::fail(
                    format!(
                        "RPDO{} acted on in {state}: {:04X}h:{:02X} = {}",
                        self.target.number,
                        entry.0,
                        entry.1,
                        after.describe()
                    ),
                    Evidence {
                        request: format!(
                            "{}{}, {}{}",
                            if stopped { "NMT stop, " } else { "" },
                            self.sent(),
                            if stopped {
                                "NMT enter pre-operational, "
                            } else {
                                ""
                            },
                            upload_text(entry)
                        ),
                        requirement: format!(
                            "{}: PDOs are exchanged in operational only, so an RPDO in {state} does not change {:04X}h:{:02X} ({} before)",
                            req::NMT_STATES,
                            entry.0,
                            entry.1,
                            hex(&old)
                        ),
                        answer: after.describe(),
                        cause: format!("the PDO service is not stopped in {state}"),
                    },
                ));
            }
        }
        enter(ctx, NmtCommand::StartRemoteNode)?;
        self.send(ctx, &new)?;
        let after = ctx.read(entry.0, entry.1)?;
        back_to_pre_operational(ctx)?;
        if after == Reply::Done(new.clone()) {
            return Ok(Finding::pass(format!(
                "RPDO{} left {:04X}h:{:02X} at {} in pre-operational and stopped, wrote {} in operational{}",
                self.target.number,
                entry.0,
                entry.1,
                hex(&old),
                hex(&new),
                if self.target.sdo_checked {
                    ""
                } else {
                    " (SDO may not write it: an RPDO put it back)"
                }
            )));
        }
        if !self.target.sdo_checked {
            return Ok(Finding::inconclusive(format!(
                "{} in operational left {:04X}h:{:02X} at {}; SDO may not write the object (ObjFlags bit 0 or its access type), so whether it holds written values is unknown and its silence in pre-operational and stopped proves nothing",
                self.sent(),
                entry.0,
                entry.1,
                after.describe()
            )));
        }
        Ok(Finding::fail(
            format!(
                "RPDO{} not acted on in operational: {:04X}h:{:02X} = {}",
                self.target.number,
                entry.0,
                entry.1,
                after.describe()
            ),
            Evidence {
                request: format!(
                    "NMT start, {}, {} (SDO wrote and read back {} there before)",
                    self.sent(),
                    upload_text(entry),
                    hex(&new)
                ),
                requirement: format!(
                    "{}: an RPDO received in operational writes its mapped objects",
                    req::PDO
                ),
                answer: after.describe(),
                cause: "the RPDO is not processed in operational, or writes its data elsewhere".to_owned(),
            },
        ))
    }
}

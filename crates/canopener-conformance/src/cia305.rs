//! The CiA 305 (LSS) device test: every test designed from CiA 305 v3.0 (layer setting services),
//! each service with the frames of its clause (master → slave on 7E5h, slave → master on 7E4h, 8
//! data bytes, byte 0 the command specifier).
//!
//! Precondition: `[DeviceInfo]` `LSS_Supported=1` says the device is an LSS slave; `=0` makes every
//! test `not_applicable`. When the key is absent the suite asks the device (switch state global to
//! configuration, inquire vendor-ID, then identify remote slave with its own address): no answer to
//! either makes the tests `not_applicable` with that reason, an answer runs them. A device whose EDS
//! says `LSS_Supported=1` and answers neither fails.
//!
//! Every test leaves the device in LSS waiting state with its original node-ID; the two tests that
//! change the node-ID (`cia305.lss.8`, `cia305.lss.10`) configure it back, and store it back when they
//! stored another.

use canopener_wire::{LssAddress, LssAddressPart, LssRequest};

use crate::context::Ctx;
use crate::finding::{Evidence, Finding, Outcome};
use crate::procedures::lss::{Lss, answer_code, describe, listed_bit_rates, prepare, ranges_text};
use crate::requirements::lss::{
    CONFIGURE_BIT_TIMING, CONFIGURE_NODE_ID, FASTSCAN, IDENTIFY_NON_CONFIGURED, IDENTIFY_REMOTE, INQUIRE,
    STATES, STORE, SWITCH_GLOBAL, SWITCH_SELECTIVE,
};
use crate::test_def::TestDef;

/// The precondition every test states.
const PRECONDITION: &str = "EDS LSS_Supported=1, or (key absent) the device answers inquire or identify";

/// The LSS tests.
pub fn tests() -> Vec<TestDef> {
    let test = |id, title, references, tags, run| TestDef {
        id,
        suite: "cia305",
        group: "lss",
        title,
        references,
        precondition: PRECONDITION,
        tags,
        run,
    };
    vec![
        test(
            "cia305.lss.1",
            "Switch state global: configuration enables inquire node-ID, waiting disables it again",
            &[SWITCH_GLOBAL, STATES, INQUIRE],
            &["lss"],
            switch_global,
        ),
        test(
            "cia305.lss.2",
            "Switch state selective with the device's LSS address: 44h answer, then configuration state",
            &[SWITCH_SELECTIVE, STATES],
            &["lss"],
            switch_selective,
        ),
        test(
            "cia305.lss.3",
            "Switch state selective with a wrong vendor-ID, product code, revision or serial: no answer, still waiting",
            &[SWITCH_SELECTIVE, STATES],
            &["lss"],
            selective_wrong_address,
        ),
        test(
            "cia305.lss.4",
            "Inquire vendor-ID, product code, revision, serial number and node-ID: 1018h:01–04 and the node-ID",
            &[INQUIRE],
            &["lss"],
            inquire,
        ),
        test(
            "cia305.lss.5",
            "Configure node-ID: 0 and 80h refused with error 1, the device's own node-ID confirmed with 0",
            &[CONFIGURE_NODE_ID],
            &["lss"],
            configure_node_id,
        ),
        test(
            "cia305.lss.6",
            "Identify remote slave: ranges around the device's address answer 4Fh, ranges without it do not",
            &[IDENTIFY_REMOTE],
            &["lss"],
            identify_remote,
        ),
        test(
            "cia305.lss.7",
            "Identify non-configured remote slave: a device with a node-ID does not answer",
            &[IDENTIFY_NON_CONFIGURED],
            &["lss"],
            identify_configured,
        ),
        test(
            "cia305.lss.8",
            "Store configuration: a stored node-ID survives NMT reset node (the device boots with it), then restored",
            &[CONFIGURE_NODE_ID, STORE],
            &["lss", "writes"],
            stored_node_id,
        ),
        test(
            "cia305.lss.9",
            "Configure bit timing: a bit rate the EDS lists confirmed with 0, an undefined table index refused with 1",
            &[CONFIGURE_BIT_TIMING],
            &["lss"],
            configure_bit_timing,
        ),
        test(
            "cia305.lss.10",
            "Unconfigured device (node-ID FFh): identify non-configured answers 50h, fastscan finds its address",
            &[IDENTIFY_NON_CONFIGURED, FASTSCAN, CONFIGURE_NODE_ID],
            &["lss", "writes"],
            fastscan,
        ),
    ]
}

/// Runs `body` with the device's address when LSS applies.
fn with_lss(
    ctx: &mut Ctx<'_, '_>,
    body: impl FnOnce(&mut Lss<'_, '_, '_>, &LssAddress) -> Outcome,
) -> Outcome {
    match prepare(ctx)? {
        Ok(address) => {
            let mut lss = Lss::new(ctx);
            let finding = body(&mut lss, &address);
            // Back to waiting whatever happened: configuration state is the test's own business.
            lss.switch_global(false)?;
            finding
        }
        Err(finding) => Ok(finding),
    }
}

fn fail(reason: String, request: String, requirement: String, answer: String, cause: &str) -> Finding {
    Finding::fail(
        reason,
        Evidence {
            request,
            requirement,
            answer,
            cause: cause.to_owned(),
        },
    )
}

fn switch_global(ctx: &mut Ctx<'_, '_>) -> Outcome {
    with_lss(ctx, |lss, _| {
        let node = lss.node();
        lss.switch_global(true)?;
        let answer = lss.inquire_node_id()?;
        if answer_code(&answer) != Some(node) {
            return Ok(fail(
                "inquire node-ID after switch state global to configuration".to_owned(),
                "switch state global (04h 01), inquire node-ID (5Eh)".to_owned(),
                format!(
                    "{SWITCH_GLOBAL}: the slave enters configuration state; {INQUIRE}: it answers 5Eh with its node-ID {node}"
                ),
                describe(&answer),
                "switch state global ignored (the slave stays waiting), or inquire node-ID not served",
            ));
        }
        lss.switch_global(false)?;
        let answer = lss.inquire_node_id()?;
        if answer.is_some() {
            return Ok(fail(
                "inquire node-ID answered after switch state global to waiting".to_owned(),
                "switch state global (04h 00), inquire node-ID (5Eh)".to_owned(),
                format!("{STATES}: inquire services are served in configuration state only"),
                describe(&answer),
                "switch to waiting ignored",
            ));
        }
        Ok(Finding::pass(format!(
            "configuration answered inquire node-ID with {node}; waiting did not answer"
        )))
    })
}

fn switch_selective(ctx: &mut Ctx<'_, '_>) -> Outcome {
    with_lss(ctx, |lss, address| {
        let node = lss.node();
        let answer = lss.switch_selective(address)?;
        if answer.is_none() {
            return Ok(fail(
                "no 44h after switch state selective with the device's address".to_owned(),
                format!("switch state selective 40h–43h with {address}"),
                format!(
                    "{SWITCH_SELECTIVE}: the slave whose LSS address matches answers 44h and enters configuration state"
                ),
                describe(&answer),
                "switch state selective ignored, or the LSS address differs from 1018h",
            ));
        }
        let inquired = lss.inquire_node_id()?;
        if answer_code(&inquired) != Some(node) {
            return Ok(fail(
                "no configuration state after 44h".to_owned(),
                "inquire node-ID (5Eh) after switch state selective".to_owned(),
                format!("{STATES}: after 44h the slave is in configuration state and serves inquire node-ID"),
                describe(&inquired),
                "44h sent without changing state",
            ));
        }
        Ok(Finding::pass(
            "44h, then configuration state (inquire node-ID answered)",
        ))
    })
}

fn selective_wrong_address(ctx: &mut Ctx<'_, '_>) -> Outcome {
    with_lss(ctx, |lss, address| {
        for part in LssAddressPart::ALL {
            let wrong = address.with_part(part, address.part(part) ^ 1);
            // Inquire node-ID right behind the last part: one wait shows both a 44h and a state
            // change (inquire is served in configuration state only).
            let answers = lss.switch_selective_then_inquire(&wrong)?;
            if let Some(answer) = answers {
                return Ok(fail(
                    format!("switch state selective with a wrong {part} was obeyed"),
                    format!("switch state selective 40h–43h with {wrong}, then inquire node-ID"),
                    format!(
                        "{SWITCH_SELECTIVE}: only a slave whose whole LSS address matches answers and changes state"
                    ),
                    describe(&Some(answer)),
                    "the slave compares only part of its LSS address",
                ));
            }
        }
        Ok(Finding::pass(
            "no answer and no state change for each wrong address part",
        ))
    })
}

fn inquire(ctx: &mut Ctx<'_, '_>) -> Outcome {
    with_lss(ctx, |lss, address| {
        lss.switch_global(true)?;
        for (sub, part) in (1u8..).zip(LssAddressPart::ALL) {
            let request = LssRequest::InquireAddress(part);
            let cs = request.encode()[0];
            let answer = lss.ask(request)?;
            let value = answer
                .as_ref()
                .and_then(|d| d.get(1..5))
                .and_then(|bytes| <[u8; 4]>::try_from(bytes).ok())
                .map(u32::from_le_bytes);
            if value != Some(address.part(part)) {
                return Ok(fail(
                    format!("inquire {part} does not give 1018h:{sub:02X}"),
                    format!("inquire {part} ({cs:02X}h) in configuration state"),
                    format!(
                        "{INQUIRE}: the answer {cs:02X}h carries the {part}, 1018h:{sub:02X} = {:#010X}",
                        address.part(part)
                    ),
                    describe(&answer),
                    "inquire not served, or the LSS address differs from the identity object",
                ));
            }
        }
        let node = lss.node();
        let answer = lss.inquire_node_id()?;
        if answer_code(&answer) != Some(node) {
            return Ok(fail(
                "inquire node-ID does not give the node-ID".to_owned(),
                "inquire node-ID (5Eh) in configuration state".to_owned(),
                format!("{INQUIRE}: the answer 5Eh carries the active node-ID {node}"),
                describe(&answer),
                "inquire node-ID not served or wrong",
            ));
        }
        Ok(Finding::pass(format!("{address}, node-ID {node}")))
    })
}

fn configure_node_id(ctx: &mut Ctx<'_, '_>) -> Outcome {
    with_lss(ctx, |lss, _| {
        let node = lss.node();
        lss.switch_global(true)?;
        for (id, expected) in [(0x00, 1), (0x80, 1), (node, 0)] {
            let answer = lss.ask(LssRequest::ConfigureNodeId { node_id: id })?;
            if answer_code(&answer) != Some(expected) {
                return Ok(fail(
                    format!("configure node-ID {id:#04X}: expected error code {expected}"),
                    format!("configure node-ID (11h) with {id:#04X} in configuration state"),
                    format!(
                        "{CONFIGURE_NODE_ID}: error code 0 for 1–127 (and FFh), 1 (node-ID out of range) otherwise"
                    ),
                    describe(&answer),
                    "configure node-ID not served, or its range not checked",
                ));
            }
        }
        Ok(Finding::pass(
            "0 and 80h refused with 1; the device's own node-ID confirmed",
        ))
    })
}

fn identify_remote(ctx: &mut Ctx<'_, '_>) -> Outcome {
    with_lss(ctx, |lss, address| {
        let [vendor, product, revision, serial] = address.parts();
        let inside = [
            ("its exact address", address.exact_ranges()),
            (
                "revision and serial 0–FFFFFFFFh",
                [vendor, product, 0, u32::MAX, 0, u32::MAX],
            ),
        ];
        for (what, ranges) in inside {
            if !lss.identify_remote(&ranges)? {
                return Ok(fail(
                    format!("no 4Fh for identify remote slave with {what}"),
                    format!("identify remote slave 46h–4Bh: {}", ranges_text(&ranges)),
                    format!(
                        "{IDENTIFY_REMOTE}: every slave whose vendor-ID and product code match and whose revision and serial lie in the ranges answers 4Fh"
                    ),
                    "nothing on 7E4h".to_owned(),
                    "identify remote slave not served, or the ranges compared wrongly",
                ));
            }
        }
        let mut outside = vec![
            (
                "another vendor-ID",
                [vendor ^ 1, product, revision, revision, serial, serial],
            ),
            (
                "another product code",
                [vendor, product ^ 1, revision, revision, serial, serial],
            ),
        ];
        if serial < u32::MAX {
            outside.push((
                "serials above its own",
                [vendor, product, revision, revision, serial + 1, u32::MAX],
            ));
        }
        if revision > 0 {
            outside.push((
                "revisions below its own",
                [vendor, product, 0, revision - 1, serial, serial],
            ));
        }
        for (what, ranges) in outside {
            if lss.identify_remote(&ranges)? {
                return Ok(fail(
                    format!("4Fh for identify remote slave with {what}"),
                    format!("identify remote slave 46h–4Bh: {}", ranges_text(&ranges)),
                    format!("{IDENTIFY_REMOTE}: a slave outside the ranges does not answer"),
                    "7E4h 4F".to_owned(),
                    "the slave ignores part of the ranges",
                ));
            }
        }
        Ok(Finding::pass("answered inside the ranges, silent outside"))
    })
}

fn identify_configured(ctx: &mut Ctx<'_, '_>) -> Outcome {
    with_lss(ctx, |lss, _| {
        let answer = lss.ask(LssRequest::IdentifyNonConfiguredRemoteSlave)?;
        if answer.is_some() {
            return Ok(fail(
                "a device with a node-ID answered identify non-configured remote slave".to_owned(),
                "identify non-configured remote slave (4Ch)".to_owned(),
                format!("{IDENTIFY_NON_CONFIGURED}: only slaves whose node-ID is FFh answer 50h"),
                describe(&answer),
                "the slave answers whatever its node-ID",
            ));
        }
        Ok(Finding::pass("no 50h from a device with node-ID"))
    })
}

fn stored_node_id(ctx: &mut Ctx<'_, '_>) -> Outcome {
    with_lss(ctx, |lss, address| {
        let node = lss.node();
        // Another node-ID next to the device's; the suite assumes the device is alone on the bus
        // (docs/conformance.md).
        let other = node % 127 + 1;
        match lss.configure_and_store(address, other)? {
            Ok(true) => {}
            Ok(false) => {
                return Ok(Finding::not_applicable(
                    "store configuration answered 1 (storing not supported)",
                ));
            }
            Err(finding) => return Ok(finding),
        }
        lss.switch_global(false)?;
        let booted = lss.reset_node_and_inquire(node)?;
        // Restore whatever the reset showed: the device is on `other` if the store worked.
        let on = booted.filter(|&b| b != 0xFF).unwrap_or(node);
        let restore = lss.configure_and_store(address, node)?;
        lss.switch_global(false)?;
        let restored = if on == node {
            lss.active_node_id()?
        } else {
            lss.reset_node_and_inquire(on)?
        };
        if booted != Some(other) {
            return Ok(fail(
                format!(
                    "after storing node-ID {other} and NMT reset node the device runs on {}",
                    booted.map_or("an unknown node-ID".to_owned(), |b| b.to_string())
                ),
                format!(
                    "configure node-ID {other} (11h), store configuration (17h), switch state global to waiting, NMT reset node, inquire node-ID (5Eh)"
                ),
                format!("{STORE}: the stored node-ID is the one the device starts with; {CONFIGURE_NODE_ID}"),
                format!(
                    "inquire node-ID: {}",
                    booted.map_or("no answer".to_owned(), |b| b.to_string())
                ),
                "store configuration does not keep the node-ID, or reset node ignores it",
            ));
        }
        if !matches!(restore, Ok(true)) || restored != Some(node) {
            return Ok(Finding::inconclusive(format!(
                "the stored node-ID {other} worked, but node-ID {node} could not be stored back (the device runs on {})",
                restored.map_or("an unknown node-ID".to_owned(), |r| r.to_string())
            )));
        }
        Ok(Finding::pass(format!(
            "node-ID {other} after store and reset node; {node} stored back"
        )))
    })
}

fn configure_bit_timing(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let listed = listed_bit_rates(ctx);
    with_lss(ctx, |lss, _| {
        let Some(&((supported, kbit), _)) = listed.iter().find(|(_, on)| *on) else {
            return Ok(Finding::not_applicable(
                "the EDS lists no bit rate (BaudRate_*=1)",
            ));
        };
        lss.switch_global(true)?;
        // Table 0 defines indices 0–9 (CiA 305 table "bit timing table"); 0Ah is no bit rate at
        // all, so every slave must refuse it. A rate the EDS says is unsupported may still be
        // accepted: the EDS lists what is guaranteed, not everything the controller can do.
        let checks = [
            (supported, 0, format!("{kbit} kbit/s, which the EDS lists")),
            (
                0x0A,
                1,
                "table 0 index 0Ah, which CiA 305 does not define".to_owned(),
            ),
        ];
        for (index, expected, what) in &checks {
            let answer = lss.ask(LssRequest::ConfigureBitTiming {
                table: 0,
                index: *index,
            })?;
            if answer_code(&answer) != Some(*expected) {
                return Ok(fail(
                    format!("configure bit timing to {what}: expected error code {expected}"),
                    format!("configure bit timing (13h), table 0, index {index}"),
                    format!(
                        "{CONFIGURE_BIT_TIMING}: 0 for a supported bit rate, 1 (bit rate not supported) otherwise"
                    ),
                    describe(&answer),
                    "configure bit timing not served, or the supported rates differ from the EDS",
                ));
            }
        }
        Ok(Finding::pass(format!(
            "{kbit} kbit/s confirmed, index 0Ah refused"
        )))
    })
}

fn fastscan(ctx: &mut Ctx<'_, '_>) -> Outcome {
    with_lss(ctx, |lss, address| {
        let node = lss.node();
        // Unconfigure: node-ID FFh becomes active with the next reset communication.
        lss.switch_global(true)?;
        let answer = lss.ask(LssRequest::ConfigureNodeId { node_id: 0xFF })?;
        if answer_code(&answer) != Some(0) {
            return Ok(fail(
                "configure node-ID FFh refused".to_owned(),
                "configure node-ID (11h) with FFh in configuration state".to_owned(),
                format!("{CONFIGURE_NODE_ID}: FFh (not configured) is a valid node-ID to configure"),
                describe(&answer),
                "configure node-ID not served, or FFh not accepted",
            ));
        }
        lss.switch_global(false)?;
        lss.nmt_reset_communication()?;
        let finding = fastscan_unconfigured(lss, address)?;
        // Back to the node-ID: configuration state through the address just found (or global),
        // configure, and back to waiting, which CiA 305 makes a reset communication for a device
        // that had none.
        lss.switch_global(true)?;
        let answer = lss.ask(LssRequest::ConfigureNodeId { node_id: node })?;
        lss.switch_global(false)?;
        let active = lss.boot_and_inquire()?;
        if answer_code(&answer) != Some(0) || active != Some(node) {
            return Ok(fail(
                format!("node-ID {node} not back after the fastscan"),
                format!(
                    "switch state global, configure node-ID {node}, switch state global to waiting, inquire node-ID"
                ),
                format!(
                    "{CONFIGURE_NODE_ID}: a device without node-ID configured with one starts with it when switched to waiting"
                ),
                format!(
                    "{}; inquire node-ID: {}",
                    describe(&answer),
                    active.map_or("no answer".to_owned(), |a| a.to_string())
                ),
                "the configured node-ID does not become active",
            ));
        }
        Ok(finding)
    })
}

fn fastscan_unconfigured(lss: &mut Lss<'_, '_, '_>, address: &LssAddress) -> Outcome {
    let answer = lss.ask(LssRequest::IdentifyNonConfiguredRemoteSlave)?;
    if answer.is_none() {
        return Ok(fail(
            "no 50h from a device with node-ID FFh".to_owned(),
            "configure node-ID FFh, NMT reset communication, identify non-configured remote slave (4Ch)"
                .to_owned(),
            format!("{IDENTIFY_NON_CONFIGURED}: a slave whose node-ID is FFh answers 50h"),
            describe(&answer),
            "identify non-configured not served, or node-ID FFh not applied by reset communication",
        ));
    }
    if let Some(step) = lss.fastscan(address)? {
        return Ok(fail(
            format!("fastscan: {step}"),
            "fastscan (51h) with the device's address: reset (BitChecked 80h), a vendor-ID wrong in bit 0, then each part confirmed (BitChecked 0)".to_owned(),
            format!("{FASTSCAN}: the unconfigured slave answers 4Fh while the checked bits match, is silent otherwise, and enters configuration state after the serial number"),
            step,
            "the slave compares the wrong bits, or does not answer",
        ));
    }
    let inquired = lss.inquire_node_id()?;
    if answer_code(&inquired) != Some(0xFF) {
        return Ok(fail(
            "not in configuration state with node-ID FFh after the fastscan".to_owned(),
            "inquire node-ID (5Eh) after the last fastscan step".to_owned(),
            format!("{FASTSCAN}: the slave found enters configuration state; {INQUIRE}: node-ID FFh"),
            describe(&inquired),
            "the last fastscan step does not select the slave",
        ));
    }
    Ok(Finding::pass(format!(
        "50h, fastscan found {address}, then configuration state"
    )))
}

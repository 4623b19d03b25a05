//! `canopener lss scan|configure|inquire`: layer setting services (CiA 305) through
//! `canopener_link::lss_session`, which runs the sequences; this module reads the options and
//! prints the devices and the advice.
//!
//! Timing: `--timeout` is the LSS response timeout. LSS commands do not take the 1 s SDO default of
//! the other master commands: fastscan pays a whole timeout on every step no device answers (about
//! 65 per device), so without `--timeout` they use `LssConfig::DEFAULT` (100 ms, the reasoning is in
//! `canopener_master::lss_master`). The settle time after a first answer stays 20 ms, or the timeout
//! when that is shorter.
//!
//! `lss scan` without `--assign` lists the unconfigured devices without giving them node-IDs (see
//! `canopener_link::lss_session` for how); a device found twice ends the listing with a warning.

use std::collections::BTreeSet;
use std::time::Duration;

use canopener_link::link::{BusLink, Link};
use canopener_link::lss_session::{Found, LssError, LssSession, MAX_LISTED, ScanOutcome, node_id_text};
use canopener_master::lss_master::{KnownParts, LssConfig, ScanError, ScanPlan};
use canopener_wire::lss::UNCONFIGURED_NODE_ID;
use canopener_wire::{LssAddress, LssAddressPart, NodeId};
use serde_json::json;

use crate::args::OutputFormat;
use crate::error::{CliError, CliResult, exit_code};
use crate::grammar::parse_node_list;
use crate::master::args::{LssAddressArgs, LssConfigureArgs, LssInquireArgs, LssScanArgs, MasterArgs};
use crate::master::link::open_link;
use crate::master::output::{millis, spinner};
use crate::output::print_stdout;

const CONFIGURE_EXAMPLE: &str =
    "canopener lss configure --vendor 0x2F7 --product 0x1 --revision 0x10 --serial 0x12345 --node-id 5";
const INQUIRE_EXAMPLE: &str =
    "canopener lss inquire --vendor 0x2F7 --product 0x1 --revision 0x10 --serial 0x12345";

pub(crate) fn scan(args: LssScanArgs) -> CliResult {
    let node_ids = args.assign.as_deref().map(parse_assign).transpose()?;
    let mut session = open_session(&args.master, "lss scan")?;
    let started = session.link_mut().now();
    let progress = spinner("{spinner} LSS fastscan {elapsed}: {msg}");
    progress.set_message("0 found");
    progress.enable_steady_tick(Duration::from_millis(100));
    let format = args.master.format;
    let mut count = 0;
    let mut on_found = |device: &Found| -> CliResult {
        count += 1;
        progress.set_message(format!("{count} found"));
        print_found(format, device)
    };
    let result = match node_ids {
        Some(node_ids) => {
            let plan = ScanPlan {
                node_ids,
                store: args.store,
                known: KnownParts::NONE,
            };
            session
                .scan_all::<CliError>(plan, &mut on_found)
                .and_then(|started| {
                    started.map_err(|err| {
                        CliError::Usage(format!("{err}; e.g. `canopener lss scan --assign 10-20`"))
                    })
                })
        }
        None => session.list_all::<CliError>(&mut on_found),
    };
    progress.finish_and_clear();
    let elapsed = session.link_mut().now().saturating_duration_since(started);
    let (found, outcome) = result?;
    let stats = session.stats();
    let timeout = session.config().timeout;
    let assigned = args.assign.is_some();
    match args.master.format {
        OutputFormat::Json => {
            let devices: Vec<serde_json::Value> = found
                .iter()
                .map(|device| {
                    let mut value = address_json(&device.address);
                    value["node_id"] = json!(device.node_id.map(NodeId::get));
                    if assigned {
                        value["stored"] = json!(args.store && device.store_problem.is_none());
                    }
                    if let Some(problem) = &device.store_problem {
                        value["store_problem"] = json!(problem);
                    }
                    value
                })
                .collect();
            let value = json!({
                "devices": devices,
                "found": found.len(),
                "complete": matches!(outcome, ScanOutcome::Complete),
                "error": match &outcome {
                    ScanOutcome::Failed(error) => Some(error.to_string()),
                    _ => None,
                },
                "elapsed_ms": millis(elapsed),
                "frames_sent": stats.sent,
                "frames_received": stats.received,
                "timeouts": stats.timeouts,
                "timeout_ms": millis(timeout),
                "ignored_frames": session.ignored(),
            });
            print_stdout(&format!("{value}\n"))?;
        }
        OutputFormat::Text => {
            let mut text = format!(
                "{} device(s) found in {:.2} s: {} LSS frames sent, {} received, {} timeouts of {} ms\n",
                found.len(),
                elapsed.as_secs_f64(),
                stats.sent,
                stats.received,
                stats.timeouts,
                timeout.as_millis()
            );
            if !assigned && !found.is_empty() {
                text.push_str(
                    "They are unconfigured and back in LSS waiting state; give them node-IDs with e.g. \
                     `canopener lss scan --assign 10-20` or `canopener lss configure`.\n",
                );
            }
            print_stdout(&text)?;
        }
    }
    if session.ignored() > 0 {
        eprintln!(
            "warning: {} frames on 7E4h answered nothing the LSS master asked and were ignored",
            session.ignored()
        );
    }
    match outcome {
        ScanOutcome::Complete => Ok(()),
        ScanOutcome::Interrupted => {
            eprintln!("interrupted: the scan is incomplete");
            Err(CliError::Exit(exit_code::INTERRUPTED))
        }
        ScanOutcome::Repeated(address) => {
            eprintln!(
                "warning: the device with {address} was found twice: it takes part in fastscan in LSS \
                 configuration state, against CiA 305, so the list may be incomplete; use --assign to give \
                 node-IDs as devices are found"
            );
            Ok(())
        }
        ScanOutcome::TooMany => Err(CliError::Device(format!(
            "more than {MAX_LISTED} devices answered fastscan; the answers cannot come from CiA 305 slaves"
        ))),
        ScanOutcome::Failed(error) => {
            let advice = match error {
                ScanError::NoNodeIdLeft => "; give a longer --assign list, e.g. --assign 10-40",
                ScanError::ConfirmationFailed { .. } => {
                    "; answers may come later than --timeout: try e.g. --timeout 200ms"
                }
                _ => "",
            };
            Err(CliError::Device(format!(
                "the LSS scan stopped after {} device(s): {error}{advice}",
                found.len()
            )))
        }
    }
}

pub(crate) fn configure(args: LssConfigureArgs) -> CliResult {
    let address = parse_address(&args.address, CONFIGURE_EXAMPLE)?.ok_or_else(|| {
        CliError::Usage(format!(
            "lss configure needs the device's LSS address, all four parts: --vendor, --product, --revision \
             and --serial, e.g. `{CONFIGURE_EXAMPLE}`; `canopener lss inquire` shows the address of a single \
             device, `canopener lss scan` those of all unconfigured devices"
        ))
    })?;
    let node_id = match args.node_id {
        UNCONFIGURED_NODE_ID => None,
        raw => Some(NodeId::new(raw).ok_or_else(|| {
            CliError::Usage(format!(
                "--node-id {raw} is no node-ID: give 1 to 127, or 255 to make the device unconfigured, \
                 e.g. `{CONFIGURE_EXAMPLE}`"
            ))
        })?),
    };
    let bit_timing = args.bitrate.map(bit_timing_index).transpose()?;
    let mut session = open_session(&args.master, "lss configure")?;
    let timeout_ms = session.config().timeout.as_millis();
    session.select(address).map_err(lss_error)?;
    let steps = session.configure_selected(&address, node_id, bit_timing, args.store);
    session.back_to_waiting().map_err(lss_error)?;
    let previous = steps.map_err(lss_error)?;
    if session.extra_answers() > 0 {
        eprintln!(
            "warning: {} answers came from a second device: more than one device is in LSS configuration \
             state, for example two with the same LSS address",
            session.extra_answers()
        );
    }
    let new_raw = node_id.map_or(UNCONFIGURED_NODE_ID, NodeId::get);
    let effect = match previous {
        Some(UNCONFIGURED_NODE_ID) if node_id.is_some() => {
            format!("the device was unconfigured and now runs as node {new_raw}")
        }
        Some(old) if old == new_raw => "the node-ID is unchanged".to_owned(),
        Some(old) => format!(
            "node-ID {} becomes active at the device's next reset communication, e.g. \
             `canopener nmt reset-comm {old}`",
            node_id_text(new_raw)
        ),
        None => "the device did not say its previous node-ID; the new one is active after its next \
                 reset communication, or at once if it was unconfigured"
            .to_owned(),
    };
    match args.master.format {
        OutputFormat::Json => {
            let value = json!({
                "address": address_json(&address),
                "previous_node_id": previous,
                "node_id": new_raw,
                "bitrate_kbit": args.bitrate,
                "stored": args.store,
                "effect": effect,
                "timeout_ms": timeout_ms,
            });
            print_stdout(&format!("{value}\n"))
        }
        OutputFormat::Text => {
            let mut text = format!("configured the device with {address}\n");
            text.push_str(&format!("  node-ID {}\n", node_id_text(new_raw)));
            if let Some(kbit) = args.bitrate {
                // CiA 305: a configured bit rate is pending until activate bit timing, which would
                // leave this link on the old rate, or until a restart after store configuration.
                let when = if args.store {
                    "stored: active when the device restarts"
                } else {
                    "pending and not stored: add --store to keep it over a restart"
                };
                text.push_str(&format!("  bit rate {kbit} kbit/s ({when})\n"));
            }
            if args.store {
                text.push_str("  stored in the device\n");
            }
            text.push_str(&format!("{effect}\n"));
            print_stdout(&text)
        }
    }
}

pub(crate) fn inquire(args: LssInquireArgs) -> CliResult {
    let address = parse_address(&args.address, INQUIRE_EXAMPLE)?;
    let mut session = open_session(&args.master, "lss inquire")?;
    let timeout_ms = session.config().timeout.as_millis();
    match address {
        Some(address) => session.select(address),
        None => session.select_all(),
    }
    .map_err(lss_error)?;
    let answers = session.inquire_selected(address.is_none());
    session.back_to_waiting().map_err(lss_error)?;
    let (found, node_id) = answers.map_err(lss_error)?;
    let node_id = match node_id {
        Ok(node_id) => Some(node_id),
        Err(after) => {
            eprintln!(
                "warning: the device did not answer inquire node-ID within {} ms",
                after.as_millis()
            );
            None
        }
    };
    let several = session.extra_answers() > 0;
    if several {
        eprintln!(
            "warning: several devices are in LSS configuration state and answered together ({} extra answers); \
             the values shown are the first answers and may mix devices. List them with `canopener lss scan`, \
             or ask one by its address: `{INQUIRE_EXAMPLE}`",
            session.extra_answers()
        );
    }
    match args.master.format {
        OutputFormat::Json => {
            let mut value = address_json(&found);
            value["node_id"] = json!(node_id);
            value["selected"] = json!(if address.is_some() { "address" } else { "global" });
            value["several_answered"] = json!(several);
            value["timeout_ms"] = json!(timeout_ms);
            print_stdout(&format!("{value}\n"))
        }
        OutputFormat::Text => {
            let mut text = String::new();
            for part in LssAddressPart::ALL {
                text.push_str(&format!("{:<16} 0x{:08X}\n", part.to_string(), found.part(part)));
            }
            let node = node_id.map_or_else(|| "no answer".to_owned(), node_id_text);
            text.push_str(&format!("{:<16} {node}\n", "node-ID"));
            print_stdout(&text)
        }
    }
}

/// Opens `--bus` for `command` and an LSS session with the timing of the options.
fn open_session(master_args: &MasterArgs, command: &str) -> CliResult<LssSession<BusLink>> {
    let config = lss_config(master_args.timeout)?;
    let link = open_link(master_args.bus.spec.as_deref(), command)?;
    Ok(LssSession::new(link, config))
}

/// A failed LSS sequence as the user sees it: the device's refusal or silence (exit 7, with advice),
/// an interruption (130), the bus (4) or a bug (1).
fn lss_error(err: LssError) -> CliError {
    match err {
        LssError::Cancelled => {
            eprintln!("interrupted");
            CliError::Exit(exit_code::INTERRUPTED)
        }
        LssError::NotSelected { .. } => CliError::Device(format!(
            "{err}; `canopener lss inquire` shows the address of a single device, `canopener lss scan` those of \
             all unconfigured devices"
        )),
        LssError::NoDevice { .. } => CliError::Device(format!(
            "{err}: no LSS device is on the bus, or it serves LSS slower (try e.g. --timeout 500ms)"
        )),
        LssError::Refused { .. } | LssError::Silent { .. } | LssError::InquirySilent { .. } => {
            CliError::Device(err.to_string())
        }
        LssError::Link(err) => err.into(),
        LssError::Start(_) | LssError::Stuck { .. } | LssError::Unexpected(_) => {
            CliError::Internal(anyhow::Error::new(err))
        }
    }
}

impl From<LssError> for CliError {
    fn from(err: LssError) -> CliError {
        lss_error(err)
    }
}

/// The LSS timing: [`LssConfig::DEFAULT`] unless the user gave `--timeout` (see the module docs).
fn lss_config(timeout: Option<Duration>) -> CliResult<LssConfig> {
    let Some(timeout) = timeout else {
        return Ok(LssConfig::DEFAULT);
    };
    if timeout.is_zero() {
        return Err(CliError::Usage(
            "--timeout 0 leaves no time for an LSS answer; give e.g. `canopener lss scan --timeout 20ms`"
                .to_owned(),
        ));
    }
    Ok(LssConfig {
        timeout,
        settle: LssConfig::DEFAULT.settle.min(timeout),
    })
}

/// Prints each device as it is found (text), so that a long scan shows its progress on stdout too.
fn print_found(format: OutputFormat, device: &Found) -> CliResult {
    if format != OutputFormat::Text {
        return Ok(());
    }
    let mut line = format!("found {}", device.address);
    if let Some(node) = device.node_id {
        line.push_str(&format!(" -> node-ID {node}"));
    }
    if let Some(problem) = &device.store_problem {
        line.push_str(&format!(" (not stored: {problem})"));
    }
    line.push('\n');
    print_stdout(&line)
}

/// `--assign`: node-IDs in the order they are given, each once.
fn parse_assign(text: &str) -> CliResult<Vec<NodeId>> {
    let example = "canopener lss scan --assign 10-20";
    let node_ids = parse_node_list(text, "--assign", example)?;
    let mut seen = BTreeSet::new();
    if let Some(twice) = node_ids.iter().find(|node| !seen.insert(**node)) {
        return Err(CliError::Usage(format!(
            "--assign {text:?} gives node-ID {twice} twice; each device needs its own, e.g. `{example}`"
        )));
    }
    Ok(node_ids)
}

/// The LSS address from `--vendor --product --revision --serial`: all four, or none (`Ok(None)`).
fn parse_address(args: &LssAddressArgs, example: &str) -> CliResult<Option<LssAddress>> {
    let given = [
        ("--vendor", &args.vendor),
        ("--product", &args.product),
        ("--revision", &args.revision),
        ("--serial", &args.serial),
    ];
    let missing: Vec<&str> = given
        .iter()
        .filter(|(_, value)| value.is_none())
        .map(|(option, _)| *option)
        .collect();
    if missing.len() == given.len() {
        return Ok(None);
    }
    if !missing.is_empty() {
        return Err(CliError::Usage(format!(
            "an LSS address needs all four parts, but {} {} missing: a device is selected by vendor-ID, \
             product code, revision and serial number together, e.g. `{example}`",
            missing.join(", "),
            if missing.len() == 1 { "is" } else { "are" }
        )));
    }
    let mut values = [0u32; 4];
    for (slot, (option, value)) in values.iter_mut().zip(given) {
        *slot = parse_u32(value.as_deref().unwrap_or_default(), option, example)?;
    }
    let [vendor_id, product_code, revision_number, serial_number] = values;
    Ok(Some(LssAddress {
        vendor_id,
        product_code,
        revision_number,
        serial_number,
    }))
}

/// A 32-bit number of the one grammar, with the option and an example in the message.
fn parse_u32(text: &str, option: &str, example: &str) -> CliResult<u32> {
    crate::grammar::parse_u32(text)
        .map_err(|why| CliError::Usage(format!("{option}: {why}, as in `{example}`")))
}

/// The CiA 305 bit timing table index (table selector 0) of a bit rate in kbit/s.
fn bit_timing_index(kbit: u16) -> CliResult<u8> {
    canopener_wire::bit_timing_index(kbit).ok_or_else(|| {
        CliError::Usage(format!(
            "--bitrate {kbit} is not in the CiA 305 bit timing table: use 1000, 800, 500, 250, 125, 50, 20 \
                 or 10 (kbit/s; 100 is reserved), e.g. `{CONFIGURE_EXAMPLE} --bitrate 250`"
        ))
    })
}

fn address_json(address: &LssAddress) -> serde_json::Value {
    json!({
        "vendor_id": address.vendor_id,
        "product_code": address.product_code,
        "revision_number": address.revision_number,
        "serial_number": address.serial_number,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn address_args(parts: [Option<&str>; 4]) -> LssAddressArgs {
        let [vendor, product, revision, serial] = parts.map(|part| part.map(str::to_owned));
        LssAddressArgs {
            vendor,
            product,
            revision,
            serial,
        }
    }

    #[test]
    fn an_address_needs_all_four_parts_or_none() {
        assert_eq!(parse_address(&address_args([None; 4]), "x").unwrap(), None);
        let full = parse_address(
            &address_args([Some("0xABC"), Some("1025"), Some("10002h"), Some("0x55")]),
            "x",
        )
        .unwrap()
        .unwrap();
        assert_eq!(
            full,
            LssAddress {
                vendor_id: 0xABC,
                product_code: 1025,
                revision_number: 0x10002,
                serial_number: 0x55,
            }
        );
        let err = parse_address(&address_args([None, None, None, Some("1")]), CONFIGURE_EXAMPLE).unwrap_err();
        assert!(matches!(err, CliError::Usage(_)));
        let text = err.to_string();
        assert!(
            text.contains("--vendor, --product, --revision are missing"),
            "{text}"
        );
        assert!(text.contains(CONFIGURE_EXAMPLE), "{text}");
        let err = parse_address(
            &address_args([Some("1"), Some("2"), Some("3"), Some("0xZZ")]),
            INQUIRE_EXAMPLE,
        )
        .unwrap_err();
        assert!(
            err.to_string().contains("--serial: '0xZZ' is not a whole number"),
            "{err}"
        );
    }

    #[test]
    fn bit_rates_map_to_the_cia_305_table_and_100_is_refused() {
        assert_eq!(bit_timing_index(1000).unwrap(), 0);
        assert_eq!(bit_timing_index(250).unwrap(), 3);
        assert_eq!(bit_timing_index(50).unwrap(), 6);
        assert_eq!(bit_timing_index(10).unwrap(), 8);
        for bad in [100, 0, 333] {
            let err = bit_timing_index(bad).unwrap_err();
            assert!(err.to_string().contains("--bitrate 250"), "{err}");
        }
    }

    #[test]
    fn lss_timing_is_the_lss_default_unless_the_user_gave_a_timeout() {
        assert_eq!(lss_config(None).unwrap(), LssConfig::DEFAULT);
        let fast = lss_config(Some(Duration::from_millis(10))).unwrap();
        assert_eq!(fast.timeout, Duration::from_millis(10));
        assert_eq!(
            fast.settle,
            Duration::from_millis(10),
            "settle never exceeds the timeout"
        );
        let slow = lss_config(Some(Duration::from_millis(500))).unwrap();
        assert_eq!(slow.settle, LssConfig::DEFAULT.settle);
        assert!(matches!(
            lss_config(Some(Duration::ZERO)),
            Err(CliError::Usage(_))
        ));
    }

    #[test]
    fn assign_lists_keep_their_order_and_refuse_duplicates() {
        let raw: Vec<u8> = parse_assign("12,10-11")
            .unwrap()
            .iter()
            .map(|n| n.get())
            .collect();
        assert_eq!(raw, [12, 10, 11]);
        let err = parse_assign("10-12,11").unwrap_err();
        assert!(err.to_string().contains("node-ID 11 twice"), "{err}");
        assert!(err.to_string().contains("--assign 10-20"), "{err}");
    }

    #[test]
    fn lss_errors_map_to_exit_codes_with_advice() {
        let address = LssAddress {
            vendor_id: 0xABC,
            product_code: 1,
            revision_number: 2,
            serial_number: 3,
        };
        let not_selected = lss_error(LssError::NotSelected {
            address,
            after: Duration::from_millis(100),
        });
        assert_eq!(not_selected.exit_code(), exit_code::DEVICE);
        let text = not_selected.to_string();
        assert!(text.contains("vendor-id 0x00000ABC"), "{text}");
        assert!(
            text.contains("within 100 ms; `canopener lss inquire` shows"),
            "{text}"
        );
        assert_eq!(lss_error(LssError::Cancelled).exit_code(), exit_code::INTERRUPTED);
        assert_eq!(
            lss_error(LssError::Stuck {
                running: None,
                within: Duration::from_secs(1)
            })
            .exit_code(),
            exit_code::INTERNAL
        );
        assert_eq!(node_id_text(UNCONFIGURED_NODE_ID), "unconfigured (FFh)");
    }
}

//! `canopener pdo map`: configures one PDO with the dynamic mapping procedure of CiA 301 §7.2.2 on the
//! PDO parameter objects 1400h–1BFFh (§7.5.2.35–§7.5.2.38; reference §3.4), run by
//! `canopener_link::pdo_map` as `canopener_master::pdo_config` plans it; this module reads the
//! arguments and prints the steps, the report and the recovery advice.
//!
//! Refusals of the planner (too many bits, restricted CAN-IDs, ...) come before the bus is opened
//! whenever they do not depend on the device, so a typo never leaves a PDO half-configured.

use canopener_link::pdo_map::{ReadCobIdError, execute, read_cob_id};
use canopener_link::sdo_session::SdoError;
use canopener_master::pdo_config::{Direction, MappedObject, PdoConfig, PdoConfigError, SdoWrite};
use canopener_master::pdo_map_report::{MapReport, StepHint, StepOutcome};
use canopener_master::sdo_client::SdoTransferError;
use canopener_master::value::{ValueType, entry_label, hex_value, parse_mapping};
use canopener_wire::NodeId;
use serde_json::{Value, json};

use crate::args::OutputFormat;
use crate::error::{CliError, CliResult, exit_code};
use crate::master::args::PdoMapArgs;
use crate::master::link::open_session;
use crate::master::output::session_error;
use crate::output::print_stdout;

pub(crate) fn map(args: PdoMapArgs) -> CliResult {
    let request = MapRequest::from_args(&args)?;
    request.precheck()?;
    let mut session = open_session(&args.master, args.target.node, "pdo map")?;
    let format = args.master.format;
    let node = request.node;
    let current = match read_cob_id(&mut session, &request.config) {
        Ok(current) => current,
        Err(ReadCobIdError::Session(SdoError::Cancelled { .. })) => {
            eprintln!(
                "interrupted before anything was written: {} of node {node} is unchanged",
                request.config.name(),
            );
            return Err(CliError::Exit(exit_code::INTERRUPTED));
        }
        Err(ReadCobIdError::Session(err)) => return Err(session_error(node.get(), err)),
        Err(err) => return Err(CliError::Device(err.to_string())),
    };
    let writes = request.plan(current)?;
    let mut report = MapReport::new(node, &request.config, current, writes);
    if format == OutputFormat::Text {
        print_stdout(&format!(
            "{} of node {node}: COB-ID {:04X}h:01 reads {current:08X}h; {} SDO writes:\n",
            report.pdo,
            report.comm_index,
            report.steps.len()
        ))?;
    }
    let mut printed = Ok(());
    execute(&mut session, &mut report, |report, step| {
        if format == OutputFormat::Text && printed.is_ok() {
            printed = print_stdout(&format!("  {}\n", report.step_line(step)));
        }
    })
    .map_err(|err| session_error(node.get(), err))?;
    printed?;
    match format {
        OutputFormat::Text => {
            for step in report.first_not_run()..report.steps.len() {
                print_stdout(&format!("  {}\n", report.step_line(step)))?;
            }
            if report.failure().is_none() {
                print_stdout(&format!("{}\n", report.summary()))?;
            }
        }
        OutputFormat::Json => print_stdout(&format!("{}\n", report_json(&report)))?,
    }
    into_result(&report)
}

/// What `pdo map` was asked to do, checked as far as it can be without the device.
#[derive(Debug)]
struct MapRequest {
    node: NodeId,
    config: PdoConfig,
}

impl MapRequest {
    fn from_args(args: &PdoMapArgs) -> CliResult<MapRequest> {
        let node = NodeId::new(args.target.node).ok_or_else(|| {
            CliError::Usage(format!(
                "--node {} is not 1..127; e.g. --node 5",
                args.target.node
            ))
        })?;
        let (direction, number) = match (args.tpdo, args.rpdo) {
            (Some(number), None) => (Direction::Tpdo, number),
            (None, Some(number)) => (Direction::Rpdo, number),
            _ => {
                return Err(CliError::Usage(
                    "give exactly one of --tpdo N or --rpdo N, e.g. --tpdo 1".to_owned(),
                ));
            }
        };
        let mapping = args
            .mapping
            .iter()
            .map(|text| parse_mapping(text).map_err(|err| CliError::Usage(err.to_string())))
            .collect::<CliResult<Vec<MappedObject>>>()?;
        let cob_id = args
            .cob_id
            .as_deref()
            .map(|text| {
                ValueType::U32
                    .parse(text)
                    .ok()
                    .and_then(|bytes| <[u8; 4]>::try_from(bytes).ok())
                    .map(u32::from_le_bytes)
                    .ok_or_else(|| {
                        CliError::Usage(format!(
                            "--cob-id `{text}` is not a 32-bit COB-ID: write it in hex or decimal, e.g. \
                             --cob-id 0x1A5 (CAN-ID 1A5h), or 0x800001A5 to leave the PDO invalid"
                        ))
                    })
            })
            .transpose()?;
        let mut config = PdoConfig::new(direction, number, mapping);
        config.cob_id = cob_id;
        config.transmission_type = args.transmission_type;
        config.inhibit_time_100us = args.inhibit;
        config.event_timer_ms = args.event_timer;
        config.sync_start = args.sync_start;
        Ok(MapRequest { node, config })
    }

    /// Refuses what the planner refuses whatever the device holds. Only a missing COB-ID of a PDO
    /// outside the pre-defined connection set waits for the device: its current one may do.
    fn precheck(&self) -> CliResult {
        match self.config.plan(self.node, None) {
            Ok(_) | Err(PdoConfigError::NeedsCobId { .. }) => Ok(()),
            Err(err) => Err(self.refused(&err)),
        }
    }

    fn plan(&self, current_cob_id: u32) -> CliResult<Vec<SdoWrite>> {
        self.config
            .plan(self.node, Some(current_cob_id))
            .map_err(|err| self.refused(&err))
    }

    fn refused(&self, err: &PdoConfigError) -> CliError {
        let pdo = match self.config.direction {
            Direction::Tpdo => format!("--tpdo {}", self.config.number),
            Direction::Rpdo => format!("--rpdo {}", self.config.number),
        };
        let example = match (self.config.direction, err) {
            (_, PdoConfigError::NeedsCobId { .. } | PdoConfigError::RestrictedCanId { .. }) => {
                format!(
                    "canopener pdo map --node {} {pdo} --cob-id 0x1A5 6000:01:8",
                    self.node
                )
            }
            (Direction::Tpdo, _) => format!(
                "canopener pdo map --node {} {pdo} 6000:01:8 6401:01:16 --transmission-type 255 --event-timer 100ms",
                self.node
            ),
            (Direction::Rpdo, _) => {
                format!(
                    "canopener pdo map --node {} {pdo} 6200:01:8 --transmission-type 255",
                    self.node
                )
            }
        };
        CliError::Usage(format!("{err}\nexample: {example}"))
    }
}

fn report_json(report: &MapReport) -> Value {
    let steps: Vec<Value> = report
        .steps
        .iter()
        .enumerate()
        .map(|(step, (write, outcome))| {
            let mut value = json!({
                "step": step + 1,
                "index": format!("{:04X}", write.index),
                "sub": write.sub,
                "value": hex_value(&write.data),
                "why": match report.entry(write) {
                    Some(entry) => format!("map {entry}"),
                    None => write.why.to_owned(),
                },
            });
            let (name, error) = match outcome {
                StepOutcome::Ok => ("ok", None),
                StepOutcome::Failed(error @ SdoTransferError::TimedOut { .. }) => ("timed out", Some(error)),
                StepOutcome::Failed(error) => ("aborted", Some(error)),
                StepOutcome::Interrupted => ("interrupted", None),
                StepOutcome::NotRun => ("not run", None),
            };
            value["outcome"] = json!(name);
            if let Some(error) = error {
                value["abort_code"] = json!(format!("{:08X}", error.abort_code()));
                value["error"] = json!(error.to_string());
            }
            value
        })
        .collect();
    let mut value = json!({
        "node": report.node.get(),
        "pdo": report.pdo.to_string(),
        "communication_index": format!("{:04X}", report.comm_index),
        "mapping_index": format!("{:04X}", report.mapping_index),
        "current_cob_id": format!("{:08X}", report.current_cob_id),
        "mapping": report.config.mapping.iter().map(ToString::to_string).collect::<Vec<_>>(),
        "steps": steps,
        "configured": report.failure().is_none(),
    });
    if let Some(failed) = report.failure() {
        value["state"] = json!(report.left_state(failed));
        value["error"] = json!(failure_message(report, failed));
    }
    value
}

/// The error message of a failed plan: which step, why, the state left and how to recover.
fn failure_message(report: &MapReport, failed: usize) -> String {
    let (node, pdo, total) = (report.node, report.pdo, report.steps.len());
    let step = format!("step {} of {total}, {}", failed + 1, report.describe(failed));
    let state = report.left_state(failed);
    let recover = if failed == 0 {
        String::new()
    } else {
        format!(
            "; to recover, run this `canopener pdo map` again once the cause is fixed (it starts by making \
             the PDO invalid, so it can be repeated from any state), or `canopener nmt reset {node}` to go \
             back to the configuration the device saved"
        )
    };
    match &report.steps[failed].1 {
        StepOutcome::Interrupted => format!("{pdo} of node {node}: interrupted at {step}; {state}{recover}"),
        StepOutcome::Failed(error) => {
            let unsure = if matches!(error, SdoTransferError::TimedOut { .. }) {
                " (the device did not confirm this step, so it may have been applied)"
            } else {
                ""
            };
            let hint = report
                .hint(failed, error.abort_code())
                .map_or_else(String::new, |hint| hint_text(hint, node));
            format!("{pdo} of node {node}: {step}: {error}{hint}; {state}{unsure}{recover}")
        }
        StepOutcome::Ok | StepOutcome::NotRun => format!("{pdo} of node {node}: {step}"),
    }
}

/// What to tell the user an abort most likely means.
fn hint_text(hint: StepHint, node: NodeId) -> String {
    match hint {
        StepHint::NotMappable { entry, direction } => {
            let needs = match direction {
                Direction::Tpdo => "a TPDO needs a readable object",
                Direction::Rpdo => "an RPDO needs a writable object",
            };
            format!(
                " ({} cannot be mapped: PDOMapping=0 in the EDS, or an access type that does not fit: {needs})",
                entry_label(entry.index, entry.sub)
            )
        }
        StepHint::NoSuchEntry { entry, sub } => format!(
            " ({} does not exist on the device, or the mapping has fewer than {sub} sub-indices)",
            entry_label(entry.index, entry.sub)
        ),
        StepHint::TooLong => " (the device takes fewer bits or fewer entries in this PDO)".to_owned(),
        StepHint::DeviceState => format!(
            " (the device may refuse PDO changes in its NMT state: `canopener nmt preop {node}` first)"
        ),
    }
}

fn into_result(report: &MapReport) -> CliResult {
    let Some(failed) = report.failure() else {
        return Ok(());
    };
    let message = failure_message(report, failed);
    match report.steps[failed].1 {
        StepOutcome::Interrupted => {
            eprintln!("{message}");
            Err(CliError::Exit(exit_code::INTERRUPTED))
        }
        _ => Err(CliError::Device(message)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> CliResult<MapRequest> {
        use clap::Parser;
        let mut argv = vec!["canopener", "pdo", "map", "--bus", "virtual:x"];
        argv.extend_from_slice(args);
        let cli = crate::cli::Cli::try_parse_from(argv).expect("clap accepts it");
        match cli.command {
            crate::cli::Command::Pdo(crate::master::args::PdoCommand::Map(args)) => {
                let request = MapRequest::from_args(&args)?;
                request.precheck()?;
                Ok(request)
            }
            _ => panic!("not pdo map"),
        }
    }

    #[test]
    fn refusals_before_the_bus_exit_2_with_an_example() {
        let refused = |args: &[&str]| match parse(args) {
            Err(err @ CliError::Usage(_)) => err.to_string(),
            other => panic!("{args:?} should be refused: {other:?}"),
        };
        assert_eq!(
            refused(&[
                "--node",
                "5",
                "--tpdo",
                "1",
                "6401:01:32",
                "6401:02:32",
                "6000:01:1"
            ]),
            "the mapping takes 65 bits; a classical CAN PDO carries at most 64 (8 bytes)\n\
             example: canopener pdo map --node 5 --tpdo 1 6000:01:8 6401:01:16 --transmission-type 255 --event-timer 100ms"
        );
        assert_eq!(
            refused(&["--node", "5", "--rpdo", "2", "6200:01:8", "--inhibit", "1ms"]),
            "RPDO2 has no inhibit time: it applies to TPDOs only\n\
             example: canopener pdo map --node 5 --rpdo 2 6200:01:8 --transmission-type 255"
        );
        assert_eq!(
            refused(&["--node", "5", "--tpdo", "1", "6000:01:8", "--cob-id", "0x585"]),
            "CAN-ID 585h is restricted (default SDO, server to client) and cannot carry a PDO\n\
             example: canopener pdo map --node 5 --tpdo 1 --cob-id 0x1A5 6000:01:8"
        );
        assert!(
            refused(&["--node", "5", "--tpdo", "1", "6000:01"])
                .contains("write index:sub:bits like 6000:01:8")
        );
        assert!(
            refused(&["--node", "5", "--tpdo", "1", "6000:01:8", "--cob-id", "lots"])
                .contains("e.g. --cob-id 0x1A5")
        );
        assert!(refused(&["--node", "5", "--tpdo", "600", "6000:01:8"]).contains("numbered 1 to 512"));
        // A PDO outside the pre-defined connection set may keep the COB-ID the device gives it.
        let request =
            parse(&["--node", "5", "--tpdo", "9", "6000:01:8", "--cob-id", "1A5h"]).expect("accepted");
        assert_eq!(request.config.cob_id, Some(0x1A5));
        assert!(parse(&["--node", "5", "--tpdo", "9", "6000:01:8"]).is_ok());
    }

    /// The report of a TPDO1 mapping of 1017h:00, refused at its mapping entry (step 3 of 5).
    fn refused_report() -> MapReport {
        let request = parse(&["--node", "5", "--tpdo", "1", "1017:00:16"]).expect("accepted");
        let mut report = MapReport::new(request.node, &request.config, 0x185, request.plan(0x185).unwrap());
        report.steps[0].1 = StepOutcome::Ok;
        report.steps[1].1 = StepOutcome::Ok;
        report.steps[2].1 = StepOutcome::Failed(SdoTransferError::AbortedByServer {
            code: canopener_wire::abort::OBJECT_NOT_MAPPABLE,
        });
        report
    }

    #[test]
    fn the_json_report_has_every_step_and_the_failure() {
        let report = refused_report();
        let json = report_json(&report);
        assert_eq!(json["pdo"], "TPDO1");
        assert_eq!(json["current_cob_id"], "00000185");
        assert_eq!(json["configured"], false);
        let outcomes: Vec<&str> = json["steps"]
            .as_array()
            .unwrap()
            .iter()
            .map(|step| step["outcome"].as_str().unwrap())
            .collect();
        assert_eq!(outcomes, ["ok", "ok", "aborted", "not run", "not run"]);
        assert_eq!(json["steps"][2]["abort_code"], "06040041");
        assert_eq!(json["steps"][2]["why"], "map 1017:00:16");
        assert_eq!(json["steps"][2]["index"], "1A00");
        assert_eq!(json["steps"][2]["value"], "10170010");
        assert!(
            json["state"]
                .as_str()
                .unwrap()
                .starts_with("TPDO1 is left invalid")
        );
        assert!(json["error"].as_str().unwrap().contains("step 3 of 5"));
        assert_eq!(into_result(&report).unwrap_err().exit_code(), 7);
    }

    #[test]
    fn failures_say_what_the_abort_means_and_how_to_recover() {
        let message = failure_message(&refused_report(), 2);
        assert_eq!(
            message,
            "TPDO1 of node 5: step 3 of 5, 1A00h:01 = 10170010h (map 1017:00:16): SDO abort 0x06040041 from the \
             server: Object cannot be mapped to the PDO (1017h:00 cannot be mapped: PDOMapping=0 in the EDS, or an \
             access type that does not fit: a TPDO needs a readable object); TPDO1 is left invalid (COB-ID \
             80000185h) with its mapping disabled (1A00h:00 = 0, 0 of 1 entries written); to recover, run this \
             `canopener pdo map` again once the cause is fixed (it starts by making the PDO invalid, so it can be \
             repeated from any state), or `canopener nmt reset 5` to go back to the configuration the device saved"
        );
        let node = NodeId::new(5).unwrap();
        assert!(hint_text(StepHint::DeviceState, node).contains("`canopener nmt preop 5` first"));
        assert!(hint_text(StepHint::TooLong, node).contains("fewer bits"));
    }
}

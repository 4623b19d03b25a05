//! `canopener sim`: simulated CANopen devices built from EDS/DCF files, on a real bus, in real time.
//!
//! The runtime builds the devices and runs them on the bus
//! ([`canopener_sim`]); this module turns the options into that setup and prints what
//! the devices report: one line per event on stderr, or one JSON object per event on stdout with
//! `--format json`.

use std::time::Duration;

use canopener_device::energybus::station::{DeviceFault, EnergyBusFault};
use canopener_device::faults::Fault;
use canopener_sim::device::ApplicationKind;
use canopener_sim::event_log::{FieldValue, LogEntry};
use canopener_sim::host::{HostReport, SimHost};
use canopener_sim::simulation::Simulation;
use serde_json::{Map, Value, json};

use crate::bus_open::open_bus;
use crate::error::{CliError, CliResult};
use crate::output::print_stdout;
use crate::sim::args::{SimApp, SimArgs, SimFormat};
use crate::stop::StopFlag;

pub(crate) fn run(args: SimArgs) -> CliResult {
    if args.list_faults {
        return print_stdout(&fault_list());
    }
    if let Some(nodelist) = &args.nodelist {
        return crate::sim::nodelist::run(nodelist, &args);
    }
    if let Some(devices) = args.energybus {
        return crate::sim::energybus::run(devices, &args);
    }
    if args.buses.len() > 1 {
        return Err(CliError::Usage(
            "several --bus are for --nodelist systems; simulated devices from files share one bus".to_owned(),
        ));
    }
    let stop = StopFlag::install()?;
    let devices = Simulation::default()
        .files(&args.files)
        .first_node_id(args.node_id)
        .serial(args.serial)
        .application(match args.app {
            SimApp::Auto => ApplicationKind::Auto,
            SimApp::None => ApplicationKind::None,
            SimApp::Cia401 => ApplicationKind::Cia401,
        })
        .downloads_refused_in_operational(args.writes_only_pre_operational)
        .faults(catalogue_faults(&args.faults)?)
        .state_dir(args.state_dir.clone())
        .build()?;
    let bus = open_bus(args.buses.first().map(String::as_str), "sim")?;
    let mut host = SimHost::new(devices, bus, stop.token());
    host.run(|report| match report {
        HostReport::Entry { elapsed, entry } => match args.format {
            SimFormat::Human => {
                eprintln!("{}", human_line(elapsed, &entry));
                Ok(())
            }
            SimFormat::Json => print_stdout(&format!("{}\n", json_line(elapsed, entry))),
        },
        HostReport::FramesLost { lost } => {
            eprintln!("warning: {lost} frames lost because the simulator did not keep up");
            Ok(())
        }
    })
}

/// The faults of the catalogue; an EnergyBus fault is for `--energybus` devices only.
fn catalogue_faults(faults: &[DeviceFault]) -> CliResult<Vec<Fault>> {
    faults
        .iter()
        .map(|fault| match fault {
            DeviceFault::Catalogue(fault) => Ok(*fault),
            DeviceFault::EnergyBus(fault) => Err(CliError::Usage(format!(
                "{fault} is a fault of emulated EnergyBus devices; use it with --energybus N"
            ))),
        })
        .collect()
}

/// `--list-faults`: every fault of the catalogue with what it does, for choosing `--fault NAME`.
fn fault_list() -> String {
    let mut text = String::new();
    for fault in Fault::ALL {
        text.push_str(&format!("{}\n", fault.name()));
        for line in fault.description().lines() {
            text.push_str(&format!("    {line}\n"));
        }
    }
    for fault in EnergyBusFault::ALL {
        text.push_str(&format!("{} (EnergyBus devices, --energybus)\n", fault.name()));
        text.push_str(&format!("    {}\n", fault.description()));
    }
    text.push_str(&format!(
        "{} faults; give one or more with `canopener sim FILE --fault NAME`\n",
        Fault::ALL.len()
    ));
    text
}

/// `  12.345 node   5: boot-up message sent, now pre-operational`: seconds since the start, then the
/// entry as people read it.
fn human_line(elapsed: Duration, entry: &LogEntry) -> String {
    format!("{:9.3} {}", elapsed.as_secs_f64(), entry.human())
}

/// One JSON object: `time` (seconds, to the millisecond), `node` (when about a device), `event`, `text`
/// and the entry's fields.
fn json_line(elapsed: Duration, entry: LogEntry) -> Value {
    let mut object = Map::new();
    object.insert(
        "time".into(),
        json!((elapsed.as_secs_f64() * 1000.0).round() / 1000.0),
    );
    if let Some(node) = entry.node {
        object.insert("node".into(), json!(node));
    }
    object.insert("event".into(), json!(entry.kind));
    object.insert("text".into(), json!(entry.text));
    for (name, value) in entry.fields {
        let value = match value {
            FieldValue::Text(text) => Value::String(text),
            FieldValue::Number(number) => json!(number),
            FieldValue::Null => Value::Null,
        };
        object.insert(name.into(), value);
    }
    Value::Object(object)
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use canopener_device::device::UNCONFIGURED;

    use super::*;
    use crate::error::CliError;

    fn entry() -> LogEntry {
        LogEntry::new("node_id", "node-ID changed from FFh (unconfigured) to 12")
            .about(UNCONFIGURED)
            .with("from", FieldValue::Null)
            .with("to", 12u8)
    }

    #[test]
    fn human_lines_start_with_seconds_and_the_node() {
        let elapsed = Duration::from_millis(12_345);
        assert_eq!(
            human_line(elapsed, &entry()),
            "   12.345 node FFh: node-ID changed from FFh (unconfigured) to 12"
        );
        assert_eq!(
            human_line(elapsed, &entry().about(5)),
            "   12.345 node   5: node-ID changed from FFh (unconfigured) to 12"
        );
        assert_eq!(human_line(elapsed, &LogEntry::stopped(true)), "   12.345 stopped");
    }

    #[test]
    fn json_lines_carry_time_node_event_text_and_typed_fields() {
        let line = json_line(Duration::from_micros(1_234_567), entry());
        assert_eq!(
            line.to_string(),
            r#"{"event":"node_id","from":null,"node":255,"text":"node-ID changed from FFh (unconfigured) to 12","time":1.235,"to":12}"#
        );
        let stopped = json_line(Duration::ZERO, LogEntry::stopped(false));
        assert_eq!(stopped.get("node"), None);
        assert_eq!(stopped["text"], "stopped by an error");
    }

    #[test]
    fn the_fault_list_names_every_fault_with_its_description() {
        let text = fault_list();
        for fault in Fault::ALL {
            assert!(
                text.contains(&format!("{}\n    ", fault.name())),
                "{}",
                fault.name()
            );
        }
        assert!(text.ends_with(&format!(
            "{} faults; give one or more with `canopener sim FILE --fault NAME`\n",
            Fault::ALL.len()
        )));
    }

    #[test]
    fn setup_errors_keep_their_exit_codes() {
        let base = PathBuf::from(canopener_testkit::fixture::BASE_EDS);
        let setup = |simulation: Simulation| CliError::from(simulation.build().unwrap_err());
        let high = setup(
            Simulation::default()
                .files([&base, &base])
                .first_node_id(Some(127)),
        );
        assert_eq!(high.exit_code(), 2);
        assert!(
            high.to_string()
                .ends_with("would be above 127; start --node-id lower"),
            "{high}"
        );
        let missing = setup(Simulation::default().file(base.with_file_name("missing.eds")));
        assert_eq!(missing.exit_code(), 3);
        assert!(missing.to_string().contains("missing.eds"), "{missing}");
    }
}

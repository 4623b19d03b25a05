//! `canopener sim --energybus N`: the emulated EnergyBus system, the controller at node-ID 1 and N
//! devices. On the virtual bus (the default) its boot is shown telegram by telegram, decoded, until
//! every device is Operating; with `--bus` it runs on that bus in real time until Ctrl-C.

use std::time::Duration;

use canopener_can::{Bitrate, Instant};
use canopener_link::link::BusLink;
use canopener_sim::energybus::serve::serve;
use canopener_sim::energybus::system::{
    BOOT_LIMIT, BootReport, EnergyBusSystem, Station, StationEvent, SystemError, boot, controller,
};
use canopener_sim::energybus::telegrams::{Telegram, TelegramDecoder, line};
use canopener_wire::{NodeId, Service};
use serde_json::json;

use crate::bus_open::open_bus;
use crate::error::{CliError, CliResult, exit_code};
use crate::output::print_stdout;
use crate::sim::args::{SimArgs, SimFormat};
use crate::stop::StopFlag;

/// How long the virtual boot goes on after every device is Operating, to show the running system.
const LINGER: Duration = Duration::from_secs(1);

pub(crate) fn run(devices: usize, args: &SimArgs) -> CliResult {
    let options = &args.energybus_options;
    if args.buses.len() > 1 {
        return Err(CliError::Usage(
            "--energybus runs on one bus: give one --bus".into(),
        ));
    }
    // The virtual bus times every frame bit by bit at the rate the description supports.
    let mut system = EnergyBusSystem::new(devices).bit_accurate(Bitrate::K250);
    if let Some(path) = &options.energybus_eds {
        let eds = canopener_runtime::description::read_description(path)?.eds;
        system = system.description(eds);
    }
    if options.no_controller {
        if args.buses.is_empty() {
            return Err(CliError::Usage(
                "--no-controller leaves the devices to an LSS master on a real bus: give --bus".into(),
            ));
        }
        system = system.without_controller();
    }
    let faulty = match options.fault_node {
        Some(node) => match usize::from(node).checked_sub(2).filter(|i| *i < devices) {
            Some(index) => Some(index),
            None => {
                return Err(CliError::Usage(format!(
                    "--fault-node {node}: the devices get node-IDs 2 to {}",
                    devices + 1
                )));
            }
        },
        None => None,
    };
    for fault in &args.faults {
        system = system.fault(faulty, *fault);
    }
    let profile = system.profile().map_err(system_error)?;
    let mut decoder = TelegramDecoder::new(&system.eds(), profile);
    match args.buses.first() {
        None => virtual_boot(&system, devices, args, &mut decoder),
        Some(spec) => real_bus(&system, spec, args),
    }
}

fn system_error(err: SystemError) -> CliError {
    match err {
        SystemError::Link(err) => err.into(),
        other => CliError::InvalidInput(other.to_string()),
    }
}

/// One line of the boot, in bus order.
enum Entry {
    Telegram(Telegram),
    Event(Instant, String),
}

fn virtual_boot(
    system: &EnergyBusSystem,
    devices: usize,
    args: &SimArgs,
    decoder: &mut TelegramDecoder,
) -> CliResult {
    let options = &args.energybus_options;
    let mut bus = system.start().map_err(system_error)?;
    let (limit, linger) = match options.run_for {
        Some(run_for) => (Instant::ZERO + run_for, run_for),
        None => (Instant::ZERO + BOOT_LIMIT, LINGER),
    };
    let report = boot(&mut bus, limit, linger)?;
    if let Some(node) = options.hand_over.and_then(NodeId::new)
        && let Some((id, _)) = controller(&bus)
        && let Some(Station::Controller(c)) = bus.virtual_bus_mut().node_mut(id)
    {
        c.hand_over(node);
    }
    let telegrams: Vec<Telegram> = report
        .frames
        .iter()
        .map(|(at, frame)| decoder.decode(*at, frame))
        .collect();
    let mut entries: Vec<Entry> = Vec::new();
    if !options.summary {
        entries.extend(telegrams.iter().cloned().map(Entry::Telegram));
    }
    entries.extend(
        report
            .events
            .iter()
            .map(|(at, e)| Entry::Event(*at, e.to_string())),
    );
    // Stable: telegrams before the events they caused at the same instant.
    entries.sort_by_key(|e| match e {
        Entry::Telegram(t) => (t.at, 0),
        Entry::Event(at, _) => (*at, 1),
    });
    let summary = summary(&report, &telegrams, devices, system.has_controller());
    match args.format {
        SimFormat::Human => {
            let mut text = format!(
                "EnergyBus system on a virtual bus (250 kbit/s, bit-accurate): {} and {devices} device(s) (serial numbers 1..{devices})\n",
                if system.has_controller() {
                    "the controller (node 1)"
                } else {
                    "no controller"
                }
            );
            for entry in &entries {
                match entry {
                    Entry::Telegram(t) => text.push_str(&format!("{}\n", line(t))),
                    Entry::Event(at, e) => text.push_str(&format!("{:9.3}  controller: {e}\n", seconds(*at))),
                }
            }
            text.push_str(&summary.text);
            print_stdout(&text)?;
        }
        SimFormat::Json => {
            let mut text = String::new();
            for entry in &entries {
                let value = match entry {
                    Entry::Telegram(t) => json!({
                        "time": seconds(t.at),
                        "kind": "telegram",
                        "id": format!("{:#05x}", t.frame.id().as_raw()),
                        "data": t.frame.data().iter().map(|b| format!("{b:02X}")).collect::<String>(),
                        "decoded": t.decoded,
                        "ems": t.ems,
                    }),
                    Entry::Event(at, e) => json!({"time": seconds(*at), "kind": "event", "text": e}),
                };
                text.push_str(&format!("{value}\n"));
            }
            text.push_str(&format!("{}\n", summary.json));
            print_stdout(&text)?;
        }
    }
    if system.has_controller() && report.all_operating_at.is_none() && devices > 0 {
        eprintln!(
            "not every device reached Operating within {:.3} s of virtual time",
            seconds(limit)
        );
        return Err(CliError::Exit(exit_code::DEVICE));
    }
    Ok(())
}

/// The EnergyBus system's boot, as text for people and JSON for machines.
struct BootSummary {
    text: String,
    json: serde_json::Value,
}

/// Which devices got where, when, and the telegrams per service.
fn summary(report: &BootReport, telegrams: &[Telegram], devices: usize, controller: bool) -> BootSummary {
    let mut text = String::from("summary:\n");
    for w in &report.operating {
        text.push_str(&format!(
            "  node {:>3}: {} -> Operating at {:.3} s\n",
            w.node,
            w.address,
            seconds(w.at)
        ));
    }
    match report.all_operating_at {
        Some(at) => text.push_str(&format!(
            "  all {devices} device(s) found by fastscan and walked to Operating at {:.3} s\n",
            seconds(at)
        )),
        None if controller => text.push_str(&format!(
            "  {} of {devices} device(s) Operating\n",
            report.operating.len()
        )),
        None => {}
    }
    let mut by_service: Vec<(String, usize)> = Vec::new();
    for t in telegrams {
        let name = service_name(t.service);
        match by_service.iter_mut().find(|(n, _)| *n == name) {
            Some((_, count)) => *count += 1,
            None => by_service.push((name, 1)),
        }
    }
    let counts: Vec<String> = by_service.iter().map(|(n, c)| format!("{n} {c}")).collect();
    text.push_str(&format!(
        "  {} telegrams: {}\n",
        telegrams.len(),
        counts.join(", ")
    ));
    let json = json!({
        "kind": "summary",
        "devices": devices,
        "operating": report.operating.iter().map(|w| json!({
            "node": w.node.get(),
            "serial": w.address.serial_number,
            "at": seconds(w.at),
        })).collect::<Vec<_>>(),
        "all_operating_at": report.all_operating_at.map(seconds),
        "telegrams": telegrams.len(),
        "by_service": by_service.iter().map(|(n, c)| json!({"service": n, "count": c})).collect::<Vec<_>>(),
    });
    BootSummary { text, json }
}

fn service_name(service: Service) -> String {
    service.to_string()
}

fn seconds(at: Instant) -> f64 {
    at.as_nanos() as f64 / 1e9
}

/// The system on a real bus in real time, its controller's events as they come.
fn real_bus(system: &EnergyBusSystem, spec: &str, args: &SimArgs) -> CliResult {
    let options = &args.energybus_options;
    let stop = StopFlag::install()?;
    let mut link = BusLink::new(open_bus(Some(spec), "sim --energybus")?, stop.token())?;
    let mut bus = system.start().map_err(system_error)?;
    eprintln!(
        "EnergyBus system on {spec}: {} and {} device(s); Ctrl-C ends",
        if system.has_controller() {
            "the controller (node 1)"
        } else {
            "no controller"
        },
        system.device_count()
    );
    let hand_over = options.hand_over.and_then(NodeId::new);
    let mut failed = None;
    serve(
        &mut bus,
        &mut link,
        options.run_for,
        hand_over,
        |elapsed, event| {
            let StationEvent::Controller(event) = event else {
                return;
            };
            let text = event.to_string();
            let result = match args.format {
                SimFormat::Human => {
                    eprintln!("{:9.3} controller: {text}", elapsed.as_secs_f64());
                    Ok(())
                }
                SimFormat::Json => print_stdout(&format!(
                    "{}\n",
                    json!({"time": elapsed.as_secs_f64(), "kind": "event", "text": text})
                )),
            };
            if let Err(err) = result {
                failed.get_or_insert(err);
            }
        },
    )?;
    match failed {
        Some(err) => Err(err),
        None => Ok(()),
    }
}

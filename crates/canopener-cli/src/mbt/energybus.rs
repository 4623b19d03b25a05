//! `mbt run|replay|shrink --energybus N`: the device under test is one of an emulated EnergyBus
//! system on virtual time (or, with 0 devices, the system's controller itself).

use canopener_device::energybus::station::DeviceFault;
use canopener_device::faults::Fault;
use canopener_eds::Eds;
use canopener_sim::energybus::system::{EnergyBusBus, EnergyBusSystem, SystemError, ready_for_test};
use canopener_wire::NodeId;

use crate::error::{CliError, CliResult};
use crate::mbt::args::DeviceArgs;

/// The description the models read with `--energybus` (unless `--eds` says otherwise): the shipped
/// EnergyBus one.
pub(crate) fn description() -> Eds {
    canopener_eds::load(canopener_device::energybus::EDS.as_bytes()).eds
}

/// The device faults of the catalogue, for a device that is no EnergyBus one (`--sim`).
pub(crate) fn catalogue_faults(faults: &[DeviceFault]) -> CliResult<Vec<Fault>> {
    faults
        .iter()
        .map(|fault| match fault {
            DeviceFault::Catalogue(fault) => Ok(*fault),
            DeviceFault::EnergyBus(fault) => Err(CliError::Usage(format!(
                "{fault} is a fault of emulated EnergyBus devices; use --energybus N instead of --sim"
            ))),
        })
        .collect()
}

/// The system `device` asks for, with `node` the node under test.
fn system(device: &DeviceArgs, count: usize, node: u8) -> CliResult<(EnergyBusSystem, Option<NodeId>)> {
    let mut system = EnergyBusSystem::new(count);
    if device.no_controller {
        system = system.without_controller();
        for fault in &device.faults {
            system = system.fault(None, *fault);
        }
        return Ok((system, None));
    }
    if count == 0 {
        if !device.faults.is_empty() {
            return Err(CliError::Usage(
                "--energybus 0 tests the controller alone: there is no device to give --fault".into(),
            ));
        }
        return Ok((system, None));
    }
    // Fastscan finds the lowest LSS address first: device i gets node-ID 2 + i.
    let index = usize::from(node).checked_sub(2).filter(|i| *i < count);
    let (Some(index), Some(under_test)) = (index, NodeId::new(node)) else {
        return Err(CliError::Usage(format!(
            "the controller gives the {count} device(s) node-IDs 2 to {}; test one of them with --node",
            count + 1
        )));
    };
    for fault in &device.faults {
        system = system.fault(Some(index), *fault);
    }
    Ok((system, Some(under_test)))
}

/// The system booted and ready for the tester on its tap (a fresh one per call, so shrinking starts
/// every run from power-on).
pub(crate) fn link(device: &DeviceArgs, count: usize, node: u8) -> CliResult<EnergyBusBus> {
    let (system, under_test) = system(device, count, node)?;
    let (bus, report) = ready_for_test(&system, under_test).map_err(system_error)?;
    if let (Some(report), Some(node)) = (report, under_test) {
        let at = report
            .all_operating_at
            .map(|t| format!(" at {:.3} s", t.as_nanos() as f64 / 1e9))
            .unwrap_or_default();
        eprintln!(
            "EnergyBus system: {} of {count} device(s) Operating{at} (virtual time); the controller hands node \
             {node} over to the tester",
            report.operating.len()
        );
    }
    Ok(bus)
}

/// A system that cannot be built is the description's fault (exit 3); one whose device under test
/// never reached Operating is a device error (exit 7).
pub(crate) fn system_error(err: SystemError) -> CliError {
    match err {
        SystemError::Link(err) => err.into(),
        SystemError::NotBooted { .. } => {
            CliError::Device(format!("the EnergyBus system did not boot: {err}"))
        }
        SystemError::Description(_) | SystemError::Device { .. } => CliError::InvalidInput(err.to_string()),
    }
}

//! A whole system simulated from its topology: every device from its DCF, one simulated bus per
//! network, a gateway on each of its networks, and the wiring's faults applied to the buses.
//!
//! A fault changes the buses exactly as the wiring says ([`Wiring::partition`]): a cut cable splits a
//! network's bus into segments (the devices beyond the cut lose the monitor but keep hearing each
//! other), a dead device or a supply domain off unplugs the devices it takes down, a dead hub splits
//! the bus at the hub. A device that comes back on boots again (boot-up, then its heartbeats).
//! The caller's endpoint on each network (the monitor) sits where the wiring is rooted.

use std::path::PathBuf;

use canopener_bus_engine::virtual_bus::{StationId, Timing};
use canopener_network::wiring::{Faults, Wiring};
use canopener_network::{Topology, VertexKind};

use crate::simulation::{SimulatedBus, Simulation};
use crate::system::files::{SystemError, SystemFiles};
use canopener_link::link::Link;

/// The segment the monitor's endpoint is put on when its own coupler is off: nobody's.
const NOBODY: u32 = u32::MAX;

/// One network of a simulated system.
#[derive(Debug)]
pub struct SimNet {
    /// The network number.
    pub net: u32,
    /// The bus; its tap is the monitor's endpoint.
    pub link: SimulatedBus,
    wiring: Wiring,
    /// The station of each device of `wiring`, in its order.
    stations: Vec<StationId>,
    /// Whether each device was off at the last [`SimulatedSystem::set_faults`].
    off: Vec<bool>,
}

/// A simulated system (see the [module docs](self)).
#[derive(Debug)]
pub struct SimulatedSystem {
    topology: Topology,
    nets: Vec<SimNet>,
    faults: Faults,
}

impl SimulatedSystem {
    /// Builds and powers on every present device of every network of `files` at virtual time zero;
    /// the monitor's endpoints sit at vertex `at` (else each network's default position).
    pub fn new(
        files: &SystemFiles,
        at: Option<usize>,
        timing: Timing,
    ) -> Result<SimulatedSystem, SystemError> {
        let topology = files.topology().clone();
        let mut nets = Vec::new();
        for net in topology.network_numbers() {
            let Some(wiring) = Wiring::new(&topology, net, at) else {
                continue;
            };
            let mut devices: Vec<(PathBuf, u8)> = Vec::new();
            for device in wiring.devices() {
                devices.push((files.dcf_of(device.vertex, net)?, device.node_id));
            }
            let link = Simulation::new(timing).devices(&devices).start()?;
            let stations: Vec<StationId> = link.virtual_bus().nodes().map(|(id, _)| id).collect();
            let off = vec![false; stations.len()];
            nets.push(SimNet {
                net,
                link,
                wiring,
                stations,
                off,
            });
        }
        Ok(SimulatedSystem {
            topology,
            nets,
            faults: Faults::none(),
        })
    }

    /// [`SimulatedSystem::new`] with frames delivered at the instant they are sent, as on a real bus that a
    /// tool watches from outside (the real bus brings its own timing).
    pub fn ideal(files: &SystemFiles, at: Option<usize>) -> Result<SimulatedSystem, SystemError> {
        SimulatedSystem::new(files, at, Timing::Ideal)
    }

    /// The system simulated.
    pub fn topology(&self) -> &Topology {
        &self.topology
    }

    /// The faults in force.
    pub fn faults(&self) -> &Faults {
        &self.faults
    }

    /// The networks, ascending.
    pub fn nets(&self) -> &[SimNet] {
        &self.nets
    }

    /// Every network's bus as a link for the monitor, with its number.
    pub fn links(&mut self) -> Vec<(u32, &mut dyn Link)> {
        self.nets
            .iter_mut()
            .map(|n| (n.net, &mut n.link as &mut dyn Link))
            .collect()
    }

    /// Puts exactly these faults in force, now.
    pub fn set_faults(&mut self, faults: Faults) {
        for sim in &mut self.nets {
            let partition = sim.wiring.partition(&faults);
            let now = sim.link.virtual_bus().now();
            let network = sim.link.virtual_bus_mut();
            // A station, a partition entry and an off flag per device of the wiring.
            let per_device = sim
                .stations
                .iter()
                .zip(&partition.devices)
                .zip(sim.off.iter_mut());
            for ((&station, segment), off) in per_device {
                match *segment {
                    None => {
                        network.disconnect(station);
                        *off = true;
                    }
                    Some(segment) => {
                        network.reconnect(station);
                        network.set_segment(station, segment as u32);
                        if std::mem::take(off)
                            && let Some(device) = network.node_mut(station)
                        {
                            device.boot(now);
                        }
                    }
                }
            }
            let tap = sim.link.station();
            let root = partition.root.map_or(NOBODY, |segment| segment as u32);
            sim.link.virtual_bus_mut().set_segment(tap, root);
        }
        self.faults = faults;
    }

    /// Applies one change given as text, the control language of `canopener sim --nodelist`:
    /// `cut CABLE`, `repair CABLE`, `kill DEVICE`, `revive DEVICE`, `power-off DOMAIN`,
    /// `power-on DOMAIN`, `repair-all`. Cables by CableName or edge id, devices (and hubs) by NodeName
    /// or vertex id.
    pub fn command(&mut self, line: &str) -> Result<(), SystemError> {
        let line = line.trim();
        let (verb, argument) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
        let argument = argument.trim();
        let mut faults = self.faults.clone();
        match verb {
            "cut" => {
                faults.cut.insert(self.cable(argument)?);
            }
            "repair" => {
                faults.cut.remove(&self.cable(argument)?);
            }
            "kill" => {
                faults.dead.insert(self.vertex(argument)?);
            }
            "revive" => {
                faults.dead.remove(&self.vertex(argument)?);
            }
            "power-off" => {
                faults.unpowered.insert(self.domain(argument)?);
            }
            "power-on" => {
                faults.unpowered.remove(&self.domain(argument)?);
            }
            "repair-all" => faults = Faults::none(),
            _ => {
                return Err(SystemError::UnknownFault(format!(
                    "unknown command {line:?}: use cut CABLE, repair CABLE, kill DEVICE, revive DEVICE, \
                     power-off DOMAIN, power-on DOMAIN or repair-all"
                )));
            }
        }
        self.set_faults(faults);
        Ok(())
    }

    /// The cable with this CableName or edge id.
    pub fn cable(&self, name: &str) -> Result<usize, SystemError> {
        self.topology
            .cables
            .iter()
            .position(|c| c.label() == name || c.id.as_deref() == Some(name))
            .ok_or_else(|| {
                let known: Vec<String> = self.topology.cables.iter().map(|c| c.label()).collect();
                SystemError::UnknownFault(format!("no cable {name:?}; the cables are {}", known.join(", ")))
            })
    }

    /// The device or active coupler with this NodeName or vertex id.
    pub fn vertex(&self, name: &str) -> Result<usize, SystemError> {
        self.topology
            .find_vertex(name)
            .filter(|&v| {
                self.topology
                    .vertices
                    .get(v)
                    .is_some_and(|v| v.is_device() || v.kind() == VertexKind::Active)
            })
            .ok_or_else(|| SystemError::UnknownFault(format!("no device or hub {name:?} in the topology")))
    }

    /// The supply domain with this name.
    pub fn domain(&self, name: &str) -> Result<String, SystemError> {
        let domains = self.topology.supply_domains();
        domains.get(name).map(|d| (*d).to_owned()).ok_or_else(|| {
            let known: Vec<&str> = domains.iter().copied().collect();
            SystemError::UnknownFault(format!(
                "no supply domain {name:?}; the domains are {}",
                known.join(", ")
            ))
        })
    }
}

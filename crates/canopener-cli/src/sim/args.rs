//! Options of `canopener sim`.

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use crate::args::parse_device_fault;
use crate::grammar::{parse_duration, parse_node_id, parse_u32, parse_usize};

#[derive(Debug, Args)]
pub(crate) struct SimArgs {
    /// EDS or DCF files: one simulated device each.
    #[arg(
        required_unless_present_any = ["list_faults", "nodelist", "energybus"],
        conflicts_with_all = ["nodelist", "energybus"],
        value_name = "FILE"
    )]
    pub(crate) files: Vec<PathBuf>,
    /// Simulate an EnergyBus system: the EnergyBus controller at node-ID 1 and N emulated EnergyBus
    /// devices that start without a node-ID. On a virtual bus (the default) the boot is shown
    /// telegram by telegram until every device is Operating; with --bus the system runs on that bus
    /// in real time. docs/energybus.md.
    #[arg(long, value_name = "N", value_parser = parse_usize, conflicts_with = "nodelist")]
    pub(crate) energybus: Option<usize>,
    #[command(flatten)]
    pub(crate) energybus_options: EnergyBusOptions,
    /// Simulate a whole system: every device of a nodelist.cpj or Nodelist.graphml from its DCF, one bus
    /// per network (`--bus N=SPEC`), wired as the file says.
    #[arg(long, value_name = "FILE")]
    pub(crate) nodelist: Option<PathBuf>,
    /// With --nodelist: start with this cable cut (CableName or edge id); repeatable.
    #[arg(long = "cut", value_name = "CABLE", requires = "nodelist")]
    pub(crate) cuts: Vec<String>,
    /// With --nodelist: start with this supply domain off; repeatable.
    #[arg(long = "power-off", value_name = "DOMAIN", requires = "nodelist")]
    pub(crate) power_off: Vec<String>,
    /// With --nodelist: where the real bus meets the simulated wiring (GraphML node id or NodeName;
    /// default: the master, else the device with the lowest node-ID).
    #[arg(long, value_name = "VERTEX", requires = "nodelist")]
    pub(crate) at: Option<String>,
    /// Give every simulated device this defect (repeatable); `--list-faults` names them.
    #[arg(long = "fault", value_name = "NAME", value_parser = parse_device_fault)]
    pub(crate) faults: Vec<canopener_device::energybus::station::DeviceFault>,
    /// Describe every fault `--fault` accepts and exit.
    #[arg(long)]
    pub(crate) list_faults: bool,
    /// CAN bus to use [env: CANOPENER_BUS]; with --nodelist, N=SPEC for network N (a plain SPEC is the
    /// network of --at) and repeatable. Forms: socketcand://HOST:PORT/BUS, socketcan:IFACE,
    /// udp-multicast://GROUP:PORT
    #[arg(long = "bus", value_name = "SPEC")]
    pub(crate) buses: Vec<String>,
    /// Node-ID of the devices (several files: N, N+1, ... in order); it wins over a DCF's own
    /// DeviceComissioning NodeID. Without it a DCF runs at its own node-ID and other devices start
    /// LSS-unconfigured (node-ID FFh) and wait for an LSS master. The start line says which applies.
    #[arg(long, value_parser = parse_node_id, value_name = "N")]
    pub(crate) node_id: Option<u8>,
    /// Serial number 1018h:04 of the devices (several files: S, S+1, ... in order), so that devices from
    /// one EDS have distinct LSS addresses. Decimal or 0x-hex.
    #[arg(long, value_parser = parse_u32, value_name = "S")]
    pub(crate) serial: Option<u32>,
    /// Keep what devices store in this directory, so it survives restarts: saved parameters (1010h
    /// "save", 1011h "load") and the LSS configuration (store configuration: the node-ID to start with).
    #[arg(long, value_name = "DIR")]
    pub(crate) state_dir: Option<PathBuf>,
    /// The application behind each device's object dictionary; `auto` runs CiA 401 I/O on a device whose
    /// 1000h says profile 401 and that has 6000h or 6200h. The start line of each device says which runs.
    #[arg(long, value_enum, default_value_t = SimApp::Auto)]
    pub(crate) app: SimApp,
    /// Refuse SDO downloads while Operational (abort 0800 0022h, "because of the present device state"), as
    /// devices do that take parameters only in Pre-operational.
    #[arg(long)]
    pub(crate) writes_only_pre_operational: bool,
    #[arg(long, value_enum, default_value_t = SimFormat::Human)]
    pub(crate) format: SimFormat,
}

/// What runs behind a simulated device's object dictionary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum SimApp {
    /// CiA 401 I/O when the file describes a CiA 401 I/O device (1000h profile 401, 6000h or 6200h), else none.
    Auto,
    /// Nothing: the device only holds its object dictionary.
    None,
    /// CiA 401 generic I/O (6000h/6200h/6401h, factory test registers 2000h-2002h); objects the file lacks
    /// are added.
    Cia401,
}

/// How `sim` logs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum SimFormat {
    /// One line per event on stderr.
    Human,
    /// One JSON object per event on stdout.
    Json,
}

/// The options of `sim --energybus`.
#[derive(Debug, Args)]
pub(crate) struct EnergyBusOptions {
    /// With --energybus: the devices from this EnergyBus description (an EDS with the
    /// EnergyBusAssumptions section) instead of the shipped one.
    #[arg(long, value_name = "FILE", requires = "energybus")]
    pub(crate) energybus_eds: Option<PathBuf>,
    /// With --energybus and --bus: no controller; the devices wait for an LSS master on the bus.
    #[arg(long, requires = "energybus")]
    pub(crate) no_controller: bool,
    /// With --energybus: give the --fault defects only to the device that gets this node-ID (the
    /// devices get 2, 3, ... in the order of their serial numbers 1, 2, ...).
    #[arg(long, value_parser = parse_node_id, value_name = "N", requires = "energybus")]
    pub(crate) fault_node: Option<u8>,
    /// With --energybus: once every device is Operating, the controller leaves this node to someone
    /// else on the bus (a tester: `mbt run ... --bus SPEC --node N`).
    #[arg(long, value_parser = parse_node_id, value_name = "N", requires = "energybus")]
    pub(crate) hand_over: Option<u8>,
    /// With --energybus: run this long (virtual bus: of virtual time, default until every device is
    /// Operating and one second more; real bus: default until Ctrl-C).
    #[arg(long = "for", value_parser = parse_duration, value_name = "DURATION", requires = "energybus")]
    pub(crate) run_for: Option<std::time::Duration>,
    /// With --energybus on the virtual bus: print the controller's events and the summary, not every
    /// telegram.
    #[arg(long, requires = "energybus")]
    pub(crate) summary: bool,
}

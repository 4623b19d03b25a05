//! Command-line grammar: the command tree. Each family's options live beside its commands
//! (`bus/args.rs`, `eds/args.rs`, `master/args.rs`, `sim/args.rs`).

use clap::{Parser, Subcommand};

use crate::bus::args::BusCommand;
use crate::demo::args::DemoArgs;
use crate::eds::args::EdsCommand;
use crate::master::args::{
    HeartbeatCommand, LssCommand, NmtArgs, NodeCommand, PdoCommand, SdoCommand, SyncArgs,
};
use crate::mbt::args::MbtCommand;
use crate::net::args::NetCommand;
use crate::serve::args::ServeArgs;
use crate::sim::args::SimArgs;
use crate::test::args::TestArgs;

/// canopener: verify CANopen devices, their EDS files and whole networks.
#[derive(Debug, Parser)]
#[command(
    name = "canopener",
    version,
    about,
    after_long_help = EXIT_CODES_HELP,
    after_help = "Run `canopener demo` to see a simulated device tested, with HTML reports, no hardware needed.\n\
                  Use `canopener help <command>` or `<command> --help` for examples."
)]
pub(crate) struct Cli {
    /// More log output on stderr (-v info, -vv debug, -vvv trace); RUST_LOG overrides.
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    pub(crate) verbose: u8,

    #[command(subcommand)]
    pub(crate) command: Command,
}

pub(crate) const EXIT_CODES_HELP: &str = "\
Exit codes:
  0  success
  1  internal error (a bug: please report it)
  2  usage error: bad command-line arguments, or a missing or malformed --bus
  3  invalid input: a file, frame or value could not be read (the message names file:line)
  4  bus error: the CAN bus could not be opened, or the connection was lost
  5  output error: a result could not be written (file exists, disk full, permission)
  6  check failed: the command ran and found a problem (a test or model verdict fail or
     inconclusive, frames lost in `demo --monitor`)
  7  device error: the device refused a request (SDO abort, LSS error) or did not answer in time
130  interrupted: Ctrl-C or SIGTERM while talking to a device (a running transfer is aborted
     on the bus)

`eds` commands and `net check|show|convert|draw` follow diff(1) instead:
  0  success (`eds diff`: both files describe the same device and object dictionary;
     `eds check`/`eds fix`: no errors, or no warnings either with --deny warnings)
  1  `eds diff`: the files differ; `eds fmt --check`: not canonical;
     `eds check`/`eds fix`/`net check`: errors found (or warnings with --deny warnings)
  2  any trouble: bad arguments, a file that cannot be read, refused or written
Why two rules: the file commands stand beside compilers and linters in CI scripts, which read
1 as \"found something\" and 2 as \"could not run\" (diff, grep, clippy). Commands that talk to a
bus can end in more ways (the bus, the device, an interruption), so they need the whole table,
where a failed verdict is 6.";

#[derive(Debug, Subcommand)]
pub(crate) enum Command {
    /// See the product with no hardware: a simulated CiA 401 device checked and conformance-tested, clean and
    /// with a fault, HTML reports written; `--monitor` watches a decoded CANopen session instead.
    #[command(after_help = "Examples:
  canopener demo                                  # the tour; reports in ./canopener-demo/ (clean.html, fault-*.html)
  canopener demo --dir /tmp/tour --fault no-emcy  # another fault, another directory
  canopener demo --format json | jq .runs         # one JSON summary for machines
  canopener demo --serve                          # the tour in a browser: http://127.0.0.1:8080/ (monitor, checks, runs)
  canopener demo --monitor                        # replay a 4-node session through an in-process hub, decoded
  canopener demo --monitor --speed 0              # as fast as possible
  canopener demo --monitor --bus 'virtual:demo?bitrate=500k'  # bit-accurate simulated 500 kbit/s bus, bus load
  canopener demo --monitor --format json | jq .text
Exit status: 0 the clean device passed and the faulty one failed as it should (with --monitor: no frame lost
or decoded as an anomaly), 6 otherwise, 5 a file could not be written, 130 interrupted.")]
    Demo(DemoArgs),
    /// Talk to CAN buses: serve a hub, monitor, send, replay, generate load, decode logs.
    #[command(subcommand)]
    Bus(BusCommand),
    /// Read, show, convert, format and compare EDS/DCF files (CiA 306) and XDD/XDC files (CiA 311).
    #[command(subcommand)]
    Eds(EdsCommand),
    /// CANopen systems (nodelist.cpj, Nodelist.graphml): check, show, convert, draw, and monitor which cable
    /// broke.
    #[command(subcommand)]
    Net(NetCommand),
    /// Run simulated CANopen devices built from EDS/DCF files on a bus, in real time, until Ctrl-C.
    #[command(after_help = "Examples:
  canopener bus serve &                                   # a hub on 127.0.0.1:29536
  canopener sim device.eds --node-id 5 --bus socketcand://127.0.0.1:29536/can0
  canopener sim node5.dcf                                 # the DCF's own node-ID
  canopener sim a.eds b.eds c.eds --node-id 10            # three devices: nodes 10, 11 and 12
  canopener sim io.eds --node-id 3 --app cia401           # CiA 401 I/O; inputs via 2000h=1 and 2001h
  canopener sim device.eds --node-id 5 --state-dir state/ # 1010h \"save\" survives restarts
  canopener sim io.eds io.eds io.eds --serial 100         # three LSS-unconfigured devices, serials 100-102
  canopener sim io.eds --serial 7 --state-dir state/      # LSS-stored node-ID used on the next start
  canopener sim device.eds --node-id 5 --format json | jq 'select(.event == \"nmt_state\")'
  canopener sim --nodelist Nodelist.graphml --bus 1=socketcand://127.0.0.1:29536/can0 --cut W3
      # a whole system, wiring-aware; type cut CABLE, repair CABLE, kill DEVICE, revive DEVICE,
      # power-off DOMAIN, power-on DOMAIN or repair-all on stdin (docs/networks.md)
  canopener sim --energybus 3                             # EnergyBus: controller + 3 devices, the boot decoded
  canopener sim --energybus 3 --bus socketcan:can0 --hand-over 3   # on a real bus; node 3 left to a tester
Logs boot-up, NMT state changes, SDO writes and aborts, EMCY and LSS (stderr, or JSON lines on stdout).
Exit status: 0 stopped by Ctrl-C or SIGTERM (--energybus on the virtual bus: every device reached Operating),
2 bad arguments, 3 a file is not a usable EDS/DCF, 4 bus error, 7 --energybus: a device never reached Operating.")]
    Sim(SimArgs),
    /// Test a device's conformance (CiA 301 device test with CCT coverage, CiA 401, LSS, CiA 313 performance, EDS check): verdicts with evidence.
    #[command(after_help = "Examples:
  canopener test --bus socketcan:can0 --node 5 --eds device.eds
  canopener test --bus socketcand://127.0.0.1:29536/can0 --node 0x20 --eds io.eds --format json -o report.json
  canopener test --bus socketcan:can0 --node 5 --eds device.eds --format html -o report.html  # plots, opens offline
  canopener test --bus socketcan:can0 --node 5 --eds device.eds --only cia301.sdo --skip cia301.sdo.15
  canopener test --bus socketcan:can0 --node 5 --eds device.eds --tag nmt --log logs/  # candump per test
  canopener test --list --suite cia301                 # ids, titles, CiA/CCT references, preconditions
  canopener test --bus socketcan:can0 --node 5 --eds device.eds --suite cia305  # LSS; device alone on the bus
  canopener test --bus socketcan:can0 --node 5 --eds device.eds --suite cia313 --criteria limits.toml --repetitions 200
  canopener test --bus socketcan:can0 --node 5 --eds io.eds --suite cia401 --stimulus ./set-input.sh --stimulus-settle 20ms
Each test resets what it changed and leaves the device pre-operational; the run starts with NMT reset node.
Exit status: 0 every applicable test passed, 6 a test failed or could not decide, 7 the device does not
answer at all, 2 bad arguments, 3 unreadable EDS or criteria file, 4 bus error, 130 interrupted (partial report written).")]
    Test(TestArgs),
    /// A local web application: the system monitor on the machine's drawing, EDS checks and conformance
    /// runs with their history, in a browser.
    #[command(after_help = "Examples:
  canopener serve                                          # http://127.0.0.1:8080/: /check and /test (simulated device)
  canopener serve --nodelist Nodelist.graphml --bus socketcand://127.0.0.1:29536/can0 --data runs/
  canopener serve --nodelist Nodelist.graphml --bus 1=socketcan:can0 --bus 2=socketcan:can1
  canopener serve --listen 0.0.0.0:8080 --token-file token.txt  # other machines: every request needs the token
  canopener demo --serve                                   # the tour: a simulated system, cables cut and repaired
Pages: / (monitor), /check, /test, /history; API: /api/state, /api/events (server-sent events: the JSON events of
`net monitor --format json`), docs/web.md. Exit status: 0 stopped by Ctrl-C, 2 bad arguments or address,
3 unreadable system or token file, 5 --data cannot be written.")]
    Serve(ServeArgs),
    /// Read and write objects of a device over SDO (expedited, segmented, block).
    #[command(subcommand)]
    Sdo(SdoCommand),
    /// Send an NMT command (start, stop, preop, reset, reset-comm) to one node or all.
    #[command(after_help = "Examples:
  canopener nmt start 5
  canopener nmt preop all
  canopener nmt reset 5 --confirm                     # wait for the boot-up message
Exit status: 0 sent (and confirmed with --confirm), 7 no confirmation, 2 bad arguments, 4 bus error.")]
    Nmt(NmtArgs),
    /// Inspect devices: identity and state of one node, scan for nodes, dump a node's objects into a DCF.
    #[command(subcommand)]
    Node(NodeCommand),
    /// Layer setting services (CiA 305): fastscan for unconfigured devices, configure node-ID and bit rate.
    #[command(subcommand)]
    Lss(LssCommand),
    /// Configure PDO mappings and watch PDOs decoded.
    #[command(subcommand)]
    Pdo(PdoCommand),
    /// Produce SYNC messages at a fixed period (with a counter if asked).
    #[command(after_help = "Examples:
  canopener sync --period 10ms
  canopener sync --period 1ms --counter 240 --count 1000")]
    Sync(SyncArgs),
    /// Watch heartbeats: every node's NMT state and heartbeat timing.
    #[command(subcommand)]
    Heartbeat(HeartbeatCommand),
    /// Model-based testing: check and explore behaviour models, test devices against them on the fly.
    #[command(subcommand)]
    Mbt(MbtCommand),
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn clap_definition_is_consistent() {
        Cli::command().debug_assert();
    }
}

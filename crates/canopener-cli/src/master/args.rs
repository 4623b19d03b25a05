//! Command-line grammar of the master-side commands: `sdo`, `nmt`, `node`, `lss`, `pdo`, `sync` and
//! `heartbeat`. Every one talks to devices on `--bus SPEC` and prints JSON with `--format json`; the
//! notations (node-IDs, integers, durations) are the shared ones of `crate::args`, documented in
//! `docs/master.md`, "One grammar".

use std::path::PathBuf;
use std::time::Duration;

use clap::{Args, Subcommand, ValueEnum};

use crate::args::{BusArg, OutputFormat};
use crate::grammar::{
    parse_cia_bitrate, parse_duration, parse_in_range, parse_node_id, parse_u8, parse_u16, parse_u64,
};

/// How long a device may take to answer one request unless `--timeout` says otherwise: CiA 301 leaves
/// the SDO timeout to the implementation; 1 s covers slow devices and loaded hubs.
pub(crate) const DEFAULT_TIMEOUT: Duration = Duration::from_secs(1);

/// Options every master command that waits for answers shares.
#[derive(Debug, Args)]
pub(crate) struct MasterArgs {
    #[command(flatten)]
    pub(crate) bus: BusArg,
    /// How long to wait for each answer (e.g. 500ms, 2s) [default: 1s; LSS commands: 100ms].
    #[arg(long, value_parser = parse_duration, value_name = "DURATION")]
    pub(crate) timeout: Option<Duration>,
    #[arg(long, value_enum, default_value_t = OutputFormat::Text)]
    pub(crate) format: OutputFormat,
}

impl MasterArgs {
    /// `--timeout`, or [`DEFAULT_TIMEOUT`]; the LSS commands have their own default and read the
    /// option itself.
    pub(crate) fn timeout(&self) -> Duration {
        self.timeout.unwrap_or(DEFAULT_TIMEOUT)
    }
}

/// Options of the commands that send or listen and wait for no answer (`sync`, `heartbeat watch`): no
/// `--timeout`, which they would accept and ignore; `--duration` and `--count` end them.
#[derive(Debug, Args)]
pub(crate) struct ListenArgs {
    #[command(flatten)]
    pub(crate) bus: BusArg,
    #[arg(long, value_enum, default_value_t = OutputFormat::Text)]
    pub(crate) format: OutputFormat,
}

#[derive(Debug, Subcommand)]
pub(crate) enum SdoCommand {
    /// Read one object over SDO and print its value (decimal and hex for numbers).
    #[command(after_help = "Examples:
  canopener sdo read --node 5 1018 1                     # vendor-ID, typed as u32 (the default for 4 bytes)
  canopener sdo read --node 5 0x1008 0 --type str        # device name
  canopener sdo read --node 5 6401h 1 --eds device.eds   # typed and named by the EDS
  canopener sdo read --node 5 1008 0 --block --format json
INDEX is hexadecimal unless written otherwise (1018, 0x1018 and 1018h are the same); SUB is hexadecimal too.
Exit status: 0 read, 7 the device aborted or did not answer, 2 bad arguments, 4 bus error.")]
    Read(SdoReadArgs),
    /// Write one object over SDO.
    #[command(after_help = "Examples:
  canopener sdo write --node 5 1017 0 1000 --type u16    # heartbeat every 1000 ms
  canopener sdo write --node 5 0x1017 0 0x3e8 --eds device.eds
  canopener sdo write --node 5 2000 1 '01 02 03 ff' --type hex --segmented
  canopener sdo write --node 5 1010 1 save --type str    # store all parameters (\"save\" signature)
Exit status: 0 written, 7 the device aborted or did not answer, 2 bad arguments, 4 bus error.")]
    Write(SdoWriteArgs),
    /// Read a (large) object into a file, with a progress bar on a terminal.
    #[command(after_help = "Examples:
  canopener sdo upload --node 5 1F50 1 -o firmware.bin
  canopener sdo upload --node 5 2100 0 -o dump.bin --block")]
    Upload(SdoUploadArgs),
    /// Write a file into a (large) object, with a progress bar on a terminal.
    #[command(after_help = "Examples:
  canopener sdo download --node 5 1F50 1 firmware.bin --block
  canopener sdo download --node 5 2100 0 data.bin")]
    Download(SdoDownloadArgs),
}

/// The device a command talks to.
#[derive(Debug, Args)]
pub(crate) struct NodeArg {
    /// Node-ID of the device (1..127, decimal or 0x hex).
    #[arg(long, value_parser = parse_node_id, value_name = "N")]
    pub(crate) node: u8,
}

/// One object of one device.
#[derive(Debug, Args)]
pub(crate) struct ObjectArgs {
    /// Node-ID of the device (1..127, decimal or 0x hex).
    #[arg(long, value_parser = parse_node_id, value_name = "N")]
    pub(crate) node: u8,
    /// Object index, hexadecimal unless written otherwise: 1018, 0x1018 or 1018h.
    #[arg(value_name = "INDEX")]
    pub(crate) index: String,
    /// Sub-index, hexadecimal: 1, 0x01 or 01h.
    #[arg(value_name = "SUB")]
    pub(crate) sub: String,
}

/// How a value is typed on the command line.
#[derive(Debug, Args)]
pub(crate) struct TypeArgs {
    /// The value's type: u8 u16 u32 u64 i8 i16 i32 i64 f32 f64 bool str hex.
    #[arg(long = "type", value_name = "TYPE", conflicts_with = "eds")]
    pub(crate) value_type: Option<String>,
    /// Type (and name) the object by this EDS or DCF.
    #[arg(long, value_name = "FILE")]
    pub(crate) eds: Option<PathBuf>,
}

#[derive(Debug, Args)]
pub(crate) struct SdoReadArgs {
    #[command(flatten)]
    pub(crate) object: ObjectArgs,
    #[command(flatten)]
    pub(crate) typing: TypeArgs,
    /// Use SDO block upload.
    #[arg(long)]
    pub(crate) block: bool,
    #[command(flatten)]
    pub(crate) master: MasterArgs,
}

#[derive(Debug, Args)]
pub(crate) struct SdoWriteArgs {
    #[command(flatten)]
    pub(crate) object: ObjectArgs,
    /// The value: decimal or 0x-hex numbers, true/false, text, or hex bytes ('01 02 ff') with --type hex.
    #[arg(value_name = "VALUE", allow_hyphen_values = true)]
    pub(crate) value: String,
    #[command(flatten)]
    pub(crate) typing: TypeArgs,
    /// Use a segmented download even for 4 bytes or fewer.
    #[arg(long, conflicts_with = "block")]
    pub(crate) segmented: bool,
    /// Use SDO block download.
    #[arg(long)]
    pub(crate) block: bool,
    #[command(flatten)]
    pub(crate) master: MasterArgs,
}

#[derive(Debug, Args)]
pub(crate) struct SdoUploadArgs {
    #[command(flatten)]
    pub(crate) object: ObjectArgs,
    /// Write the data here (refused if it exists, unless --force).
    #[arg(short, long, value_name = "FILE")]
    pub(crate) output: PathBuf,
    /// Replace an existing output file (a .bak copy is kept).
    #[arg(long)]
    pub(crate) force: bool,
    /// Use SDO block upload.
    #[arg(long)]
    pub(crate) block: bool,
    #[command(flatten)]
    pub(crate) master: MasterArgs,
}

#[derive(Debug, Args)]
pub(crate) struct SdoDownloadArgs {
    #[command(flatten)]
    pub(crate) object: ObjectArgs,
    /// The file whose bytes are written.
    #[arg(value_name = "FILE")]
    pub(crate) input: PathBuf,
    /// Use SDO block download.
    #[arg(long)]
    pub(crate) block: bool,
    #[command(flatten)]
    pub(crate) master: MasterArgs,
}

/// `canopener nmt`: one NMT command.
#[derive(Debug, Args)]
pub(crate) struct NmtArgs {
    /// start, stop, preop, reset (reset node) or reset-comm (reset communication).
    #[arg(value_enum, value_name = "COMMAND")]
    pub(crate) command: NmtVerb,
    /// A node-ID 1..127 (decimal or 0x hex), or `all`; `--node` says the same.
    #[arg(value_name = "NODE|all", required_unless_present = "node")]
    pub(crate) target: Option<String>,
    /// The node (1..127) or `all`, as every other command names its device.
    #[arg(long, value_name = "NODE|all", conflicts_with = "target")]
    pub(crate) node: Option<String>,
    /// Wait for the node's boot-up or heartbeat to confirm the new state (needs a heartbeat producer
    /// for start/stop/preop).
    #[arg(long)]
    pub(crate) confirm: bool,
    #[command(flatten)]
    pub(crate) master: MasterArgs,
}

impl NmtArgs {
    /// The node or `all`, from the positional argument or `--node` (clap requires exactly one).
    pub(crate) fn target(&self) -> &str {
        self.node
            .as_deref()
            .or(self.target.as_deref())
            .unwrap_or_default()
    }
}

/// The NMT module-control commands (CiA 301 §7.2.8.3.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum NmtVerb {
    /// Start remote node (01h): Operational.
    Start,
    /// Stop remote node (02h): Stopped.
    Stop,
    /// Enter pre-operational (80h).
    Preop,
    /// Reset node (81h): reset application, then communication, then boot-up.
    Reset,
    /// Reset communication (82h), then boot-up.
    ResetComm,
}

#[derive(Debug, Subcommand)]
pub(crate) enum NodeCommand {
    /// Identity, device type (decoded), error register, name and versions, heartbeat state of one node.
    #[command(after_help = "Examples:
  canopener node info --node 5
  canopener node info --node 5 --eds device.eds --format json")]
    Info(NodeInfoArgs),
    /// Which node-IDs answer (SDO upload of 1000h), with their identities.
    #[command(after_help = "Examples:
  canopener node scan
  canopener node scan --nodes 1-32 --timeout 50ms --format json")]
    Scan(NodeScanArgs),
    /// Read every readable object an EDS lists from a device into a DCF.
    #[command(after_help = "Examples:
  canopener node dump --node 5 --eds device.eds -o node5.dcf
  canopener node dump --node 5 --eds device.eds --bitrate 250 -o node5.dcf   # Baudrate=250 in the DCF
  canopener eds diff device.eds node5.dcf              # what the device holds that the EDS does not say")]
    Dump(NodeDumpArgs),
}

#[derive(Debug, Args)]
pub(crate) struct NodeInfoArgs {
    #[command(flatten)]
    pub(crate) target: NodeArg,
    /// Also name the device's objects by this EDS or DCF.
    #[arg(long, value_name = "FILE")]
    pub(crate) eds: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) master: MasterArgs,
}

#[derive(Debug, Args)]
pub(crate) struct NodeScanArgs {
    /// Node-IDs to try, e.g. 1-127 or 1-10,20,0x30.
    // `--range` was its name before one grammar: a hidden alias, so scripts keep working.
    #[arg(long = "nodes", alias = "range", default_value = "1-127", value_name = "LIST")]
    pub(crate) nodes: String,
    /// How many nodes are asked at once (SDO requests in flight).
    #[arg(long, default_value = "127", value_parser = |t: &str| parse_in_range(t, 1, 127, "--parallel").map(|v| v as u8))]
    pub(crate) parallel: u8,
    #[command(flatten)]
    pub(crate) master: MasterArgs,
}

#[derive(Debug, Args)]
pub(crate) struct NodeDumpArgs {
    #[command(flatten)]
    pub(crate) target: NodeArg,
    /// The EDS (or DCF) that lists the objects to read.
    #[arg(long, value_name = "FILE")]
    pub(crate) eds: PathBuf,
    /// Write the DCF here (stdout if not given; refused if it exists, unless --force).
    #[arg(short, long, value_name = "FILE")]
    pub(crate) output: Option<PathBuf>,
    /// Replace an existing output file (a .bak copy is kept).
    #[arg(long)]
    pub(crate) force: bool,
    /// The bus bit rate in kbit/s, for the DCF's Baudrate (the bus link does not tell it; without this
    /// option a DCF template's value is kept, else 0 "unknown").
    #[arg(long, value_name = "KBIT", value_parser = parse_cia_bitrate)]
    pub(crate) bitrate: Option<u16>,
    #[command(flatten)]
    pub(crate) master: MasterArgs,
}

#[derive(Debug, Subcommand)]
pub(crate) enum LssCommand {
    /// Find every LSS-unconfigured device by fastscan (CiA 305), optionally giving each a node-ID.
    #[command(after_help = "Examples:
  canopener lss scan                                   # list the unconfigured devices' LSS addresses
  canopener lss scan --assign 10-20 --store            # and give them node-IDs 10, 11, ... and store them
  canopener lss scan --timeout 20ms --format json")]
    Scan(LssScanArgs),
    /// Give the device with this LSS address a node-ID (and bit rate), optionally storing it.
    #[command(after_help = "Examples:
  canopener lss configure --vendor 0x2F7 --product 0x1 --revision 0x10 --serial 0x12345 --node-id 5 --store")]
    Configure(LssConfigureArgs),
    /// Ask the devices in LSS configuration state (or one LSS address) for their identity and node-ID.
    #[command(after_help = "Examples:
  canopener lss inquire                              # switches all to configuration state, asks, switches back
  canopener lss inquire --vendor 0x2F7 --product 1 --revision 0x10 --serial 0x12345")]
    Inquire(LssInquireArgs),
}

/// An LSS address (CiA 305: 1018h sub 1..4), each part decimal or 0x-hex.
#[derive(Debug, Args)]
pub(crate) struct LssAddressArgs {
    /// Vendor-ID (1018h:01).
    #[arg(long, value_name = "ID")]
    pub(crate) vendor: Option<String>,
    /// Product code (1018h:02).
    #[arg(long, value_name = "CODE")]
    pub(crate) product: Option<String>,
    /// Revision number (1018h:03).
    #[arg(long, value_name = "REV")]
    pub(crate) revision: Option<String>,
    /// Serial number (1018h:04).
    #[arg(long, value_name = "SERIAL")]
    pub(crate) serial: Option<String>,
}

#[derive(Debug, Args)]
pub(crate) struct LssScanArgs {
    /// Give the devices found node-IDs from this list (e.g. 10-20 or 5,7,9), in the order found.
    #[arg(long, value_name = "LIST")]
    pub(crate) assign: Option<String>,
    /// Store each assigned node-ID in the device (LSS store configuration).
    #[arg(long, requires = "assign")]
    pub(crate) store: bool,
    #[command(flatten)]
    pub(crate) master: MasterArgs,
}

#[derive(Debug, Args)]
pub(crate) struct LssConfigureArgs {
    #[command(flatten)]
    pub(crate) address: LssAddressArgs,
    /// The node-ID to give (1..127, or 255 for unconfigured; decimal or 0x hex).
    #[arg(long, value_name = "N", value_parser = parse_u8)]
    pub(crate) node_id: u8,
    /// Also set the bit rate in kbit/s (1000, 800, 500, 250, 125, 50, 20, 10; CiA 305 table 0).
    #[arg(long, value_name = "KBIT", value_parser = parse_cia_bitrate)]
    pub(crate) bitrate: Option<u16>,
    /// Store the configuration in the device (LSS store configuration).
    #[arg(long)]
    pub(crate) store: bool,
    #[command(flatten)]
    pub(crate) master: MasterArgs,
}

#[derive(Debug, Args)]
pub(crate) struct LssInquireArgs {
    #[command(flatten)]
    pub(crate) address: LssAddressArgs,
    #[command(flatten)]
    pub(crate) master: MasterArgs,
}

#[derive(Debug, Subcommand)]
pub(crate) enum PdoCommand {
    /// Map objects into a PDO with the CiA 301 procedure (invalidate, clear, map, count, validate).
    #[command(after_help = "Examples:
  canopener pdo map --node 5 --tpdo 1 6000:01:8 6401:01:16 --transmission-type 255 --event-timer 100ms
  canopener pdo map --node 5 --rpdo 1 6200:01:8
  canopener pdo map --node 5 --tpdo 2 6401:01:16 --transmission-type 1 --inhibit 5ms   # on every SYNC
Mapping entries are INDEX:SUB:BITS in hexadecimal index and sub-index, decimal bits.")]
    Map(PdoMapArgs),
    /// Print the PDOs of a node live, decoded by its mapping (read from the device, named by the EDS).
    #[command(after_help = "Examples:
  canopener pdo watch --node 5 --eds device.eds
  canopener pdo watch --node 5 --eds device.eds --format json --count 10
  canopener pdo watch --node 5                       # TPDO 1..4 read from the device, values in hex")]
    Watch(PdoWatchArgs),
}

#[derive(Debug, Args)]
pub(crate) struct PdoMapArgs {
    #[command(flatten)]
    pub(crate) target: NodeArg,
    /// Configure TPDO N (1..512).
    #[arg(
        long,
        value_name = "N",
        value_parser = parse_u16,
        conflicts_with = "rpdo",
        required_unless_present = "rpdo"
    )]
    pub(crate) tpdo: Option<u16>,
    /// Configure RPDO N (1..512).
    #[arg(long, value_name = "N", value_parser = parse_u16)]
    pub(crate) rpdo: Option<u16>,
    /// Mapping entries INDEX:SUB:BITS, in PDO order.
    #[arg(value_name = "INDEX:SUB:BITS", required = true)]
    pub(crate) mapping: Vec<String>,
    /// Transmission type (0 acyclic SYNC, 1-240 every n-th SYNC, 252/253 RTR, 254/255 event-driven).
    /// `--type` is the old spelling (`sdo`'s `--type` is a data type).
    #[arg(long = "transmission-type", alias = "type", value_name = "TYPE", value_parser = parse_u8)]
    pub(crate) transmission_type: Option<u8>,
    /// Event timer, whole milliseconds up to 65535ms (e.g. 100ms, 1s; 0ms = off). Holds 1800h+n sub 5's
    /// value in ms.
    #[arg(long, value_name = "DURATION", value_parser = parse_event_timer)]
    pub(crate) event_timer: Option<u16>,
    /// Inhibit time (TPDO), a multiple of 100us up to 6553.5ms (e.g. 500us, 10ms). Holds 1800h+n sub 3's
    /// value in units of 100 µs.
    #[arg(long, value_name = "DURATION", value_parser = parse_inhibit)]
    pub(crate) inhibit: Option<u16>,
    /// SYNC start value (TPDO, 0 = off).
    #[arg(long, value_name = "N", value_parser = parse_u8)]
    pub(crate) sync_start: Option<u8>,
    /// COB-ID (default: the pre-defined connection set's for PDO 1..4).
    #[arg(long, value_name = "ID")]
    pub(crate) cob_id: Option<String>,
    #[command(flatten)]
    pub(crate) master: MasterArgs,
}

/// A PDO event timer as a duration, in the unit of 1800h sub 5: whole milliseconds (CiA 301 §7.5.2.35).
fn parse_event_timer(text: &str) -> Result<u16, String> {
    duration_in_units(text, 1000).ok_or_else(|| {
        format!("the event timer counts whole milliseconds up to 65535ms; '{text}' is not one, e.g. --event-timer 100ms")
    })?
}

/// A PDO inhibit time as a duration, in the unit of 1800h sub 3: multiples of 100 µs (CiA 301 §7.5.2.35).
fn parse_inhibit(text: &str) -> Result<u16, String> {
    duration_in_units(text, 100).ok_or_else(|| {
        format!("the inhibit time counts multiples of 100us up to 6553.5ms; '{text}' is not one, e.g. --inhibit 500us")
    })?
}

/// A duration as a whole number of `unit_us` microseconds that fits an UNSIGNED16: `None` when it does
/// not, the duration's own error when it is none.
fn duration_in_units(text: &str, unit_us: u128) -> Option<Result<u16, String>> {
    let micros = match parse_duration(text) {
        Ok(duration) => duration.as_micros(),
        Err(err) => return Some(Err(err)),
    };
    if micros % unit_us != 0 {
        return None;
    }
    u16::try_from(micros / unit_us).ok().map(Ok)
}

#[derive(Debug, Args)]
pub(crate) struct PdoWatchArgs {
    #[command(flatten)]
    pub(crate) target: NodeArg,
    /// Watch the TPDOs this EDS or DCF describes, named and typed by it; without it, TPDO 1..4 (the
    /// pre-defined connection set) with their mapped bytes in hex.
    #[arg(long, value_name = "FILE")]
    pub(crate) eds: Option<PathBuf>,
    /// Take the mapping from the EDS/DCF defaults instead of reading it from the device over SDO.
    #[arg(long, requires = "eds")]
    pub(crate) offline: bool,
    /// Stop after this many PDOs.
    #[arg(long, value_name = "N", value_parser = parse_u64)]
    pub(crate) count: Option<u64>,
    /// Stop after this long (e.g. 10s).
    #[arg(long, value_parser = parse_duration, value_name = "DURATION")]
    pub(crate) duration: Option<Duration>,
    #[command(flatten)]
    pub(crate) master: MasterArgs,
}

/// `canopener sync`: produce SYNC.
#[derive(Debug, Args)]
pub(crate) struct SyncArgs {
    /// Time between SYNCs (e.g. 10ms).
    #[arg(long, value_parser = parse_duration, value_name = "DURATION")]
    pub(crate) period: Duration,
    /// SYNC counter overflow value 2..240 (1019h); none sends SYNC without a counter.
    #[arg(long, value_parser = |t: &str| parse_in_range(t, 2, 240, "--counter").map(|v| v as u8), value_name = "N")]
    pub(crate) counter: Option<u8>,
    /// Stop after this many SYNCs.
    #[arg(long, value_name = "N", value_parser = parse_u64)]
    pub(crate) count: Option<u64>,
    /// Stop after this long.
    #[arg(long, value_parser = parse_duration, value_name = "DURATION")]
    pub(crate) duration: Option<Duration>,
    #[command(flatten)]
    pub(crate) master: ListenArgs,
}

#[derive(Debug, Subcommand)]
pub(crate) enum HeartbeatCommand {
    /// Show the NMT state, heartbeat timing and EMCYs of every node, live; lost and resumed heartbeats
    /// stand out.
    #[command(after_help = "Examples:
  canopener heartbeat watch
  canopener heartbeat watch --consumer-time 300ms --duration 10s --format json
  canopener heartbeat watch --guard 5 --guard-time 200ms --life-time-factor 3   # node guarding
Exit status: 0 stopped by Ctrl-C or --duration, 6 a heartbeat was lost (with --fail-on-loss).")]
    Watch(HeartbeatWatchArgs),
}

#[derive(Debug, Args)]
pub(crate) struct HeartbeatWatchArgs {
    /// Report a node lost after this long without a heartbeat (default: 1.5 × the period it showed).
    #[arg(long, value_parser = parse_duration, value_name = "DURATION")]
    pub(crate) consumer_time: Option<Duration>,
    /// Only these nodes (e.g. 1-10,20).
    #[arg(long, value_name = "LIST")]
    pub(crate) nodes: Option<String>,
    /// Stop after this long.
    #[arg(long, value_parser = parse_duration, value_name = "DURATION")]
    pub(crate) duration: Option<Duration>,
    /// Guard these nodes (node guarding, CiA 301: a remote frame every --guard-time, the answer's
    /// toggle bit checked), e.g. 5 or 1-4; for devices without a heartbeat producer.
    #[arg(long, value_name = "LIST")]
    pub(crate) guard: Option<String>,
    /// How often a guarded node is asked (100Ch on the device).
    #[arg(long, default_value = "100ms", value_parser = parse_duration, value_name = "DURATION")]
    pub(crate) guard_time: Duration,
    /// A guarded node is lost after this many guard times without a correct answer (100Dh).
    #[arg(long, default_value = "3", value_parser = |t: &str| parse_in_range(t, 1, 255, "--life-time-factor").map(|v| v as u8), value_name = "N")]
    pub(crate) life_time_factor: u8,
    /// Exit with status 6 when a heartbeat (or a guarded node) was lost.
    #[arg(long)]
    pub(crate) fail_on_loss: bool,
    #[command(flatten)]
    pub(crate) master: ListenArgs,
}

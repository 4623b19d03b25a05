//! Command-line grammar: every subcommand, its options and its `--help` examples.

use std::net::SocketAddr;
use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

const BUS_HELP: &str = "CAN bus to use [env: CANOPENER_BUS]. Forms: virtual:NAME[?bitrate=500k], \
socketcand://HOST:PORT/BUS, socketcan:IFACE, udp-multicast://GROUP:PORT";

/// canopener: verify CANopen devices, their EDS files and whole networks.
#[derive(Debug, Parser)]
#[command(
    name = "canopener",
    version,
    about,
    after_long_help = EXIT_CODES_HELP,
    after_help = "Run `canopener demo` to watch a decoded CANopen session with no hardware.\n\
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
  2  usage error: bad command-line arguments
  3  invalid input: a file, frame or value could not be read (the message names file:line)
  4  bus error: the CAN bus could not be opened, or the connection was lost
  5  output error: a result could not be written (file exists, disk full, permission)
  6  check failed: the command ran and found a problem (e.g. frames lost in `demo`)
  7  device error: the device refused a request (SDO abort, LSS error) or did not answer in time
130  interrupted: Ctrl-C or SIGTERM while talking to a device (a running transfer is aborted on the bus)

`eds` commands follow diff(1) instead:
  0  success (`eds diff`: both files describe the same device and object dictionary;
     `eds check`/`eds fix`: no errors, or no warnings either with --deny warnings)
  1  `eds diff`: the files differ; `eds check`/`eds fix`: errors found (or warnings with --deny warnings)
  2  any trouble: bad arguments, a file that cannot be read, refused or written";

#[derive(Debug, Subcommand)]
pub(crate) enum Command {
    /// Watch a decoded CANopen session: an in-process hub, a traffic source and the bus monitor.
    #[command(after_help = "Examples:
  canopener demo                                  # hub on 127.0.0.1 (ephemeral port), real-time replay
  canopener demo --speed 0                        # as fast as possible
  canopener demo --bus 'virtual:demo?bitrate=500k'  # bit-accurate simulated 500 kbit/s bus, shows bus load
  canopener demo --format json | jq .text")]
    Demo(DemoArgs),
    /// Talk to CAN buses: serve a hub, monitor, send, replay, generate load, decode logs.
    #[command(subcommand)]
    Bus(BusCommand),
    /// Read, show, convert, format and compare EDS/DCF files (CiA 306) and XDD/XDC files (CiA 311).
    #[command(subcommand)]
    Eds(EdsCommand),
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
Logs boot-up, NMT state changes, SDO writes and aborts, EMCY and LSS (stderr, or JSON lines on stdout).
Exit status: 0 stopped by Ctrl-C or SIGTERM, 2 bad arguments, 3 a file is not a usable EDS/DCF, 4 bus error.")]
    Sim(SimArgs),
    /// Read and write objects of a device over SDO (expedited, segmented, block).
    #[command(subcommand)]
    Sdo(crate::cli_master::SdoCommand),
    /// Send an NMT command (start, stop, preop, reset, reset-comm) to one node or all.
    #[command(after_help = "Examples:
  canopener nmt start 5
  canopener nmt preop all
  canopener nmt reset 5 --confirm                     # wait for the boot-up message
Exit status: 0 sent (and confirmed with --confirm), 7 no confirmation, 2 bad arguments, 4 bus error.")]
    Nmt(crate::cli_master::NmtArgs),
    /// Inspect devices: identity and state of one node, scan for nodes, dump a node's objects into a DCF.
    #[command(subcommand)]
    Node(crate::cli_master::NodeCommand),
    /// Layer setting services (CiA 305): fastscan for unconfigured devices, configure node-ID and bit rate.
    #[command(subcommand)]
    Lss(crate::cli_master::LssCommand),
    /// Configure PDO mappings and watch PDOs decoded.
    #[command(subcommand)]
    Pdo(crate::cli_master::PdoCommand),
    /// Produce SYNC messages at a fixed period (with a counter if asked).
    #[command(after_help = "Examples:
  canopener sync --period 10ms
  canopener sync --period 1ms --counter 240 --count 1000")]
    Sync(crate::cli_master::SyncArgs),
    /// Watch heartbeats: every node's NMT state and heartbeat timing.
    #[command(subcommand)]
    Heartbeat(crate::cli_master::HeartbeatCommand),
}

#[derive(Debug, Subcommand)]
pub(crate) enum EdsCommand {
    /// Show the object dictionary of an EDS, DCF, XDD/XDC or canopener JSON file as a table.
    #[command(after_help = "Examples:
  canopener eds show device.eds
  canopener eds show device.eds --object 1018        # one object (0x1018, 1018h and 1018 all mean 1018h)
  canopener eds show device.eds --node-id 5          # also resolve $NODEID formulas for node 5
  canopener eds show device.xdd --format json | jq '.objects[] | select(.pdo_mapping)'")]
    Show(EdsShowArgs),
    /// Convert between EDS, DCF, XDD/XDC and canopener's JSON form.
    #[command(after_help = "Examples:
  canopener eds convert device.eds --to json -o device.json
  canopener eds convert device.eds --to dcf --node-id 5 --bitrate 250 -o node5.dcf
  canopener eds convert node5.dcf --to eds                # drop the DCF additions, print to stdout
  canopener eds convert device.eds --to xdd -o device.xdd # CiA 311 v1.1 (an XDC when the input is a DCF)
  canopener eds convert device.xdd --to eds -o device.eds")]
    Convert(EdsConvertArgs),
    /// Rewrite a file as canonical CiA 306 text (section order, key spelling, CR/LF; values and comments kept).
    #[command(after_help = "Examples:
  canopener eds fmt device.eds                   # canonical text on stdout
  canopener eds fmt device.eds -o clean.eds
  canopener eds fmt device.eds --in-place        # keeps device.eds.bak
  canopener eds fmt device.eds --check           # exit 1 if the file is not canonical")]
    Fmt(EdsFmtArgs),
    /// Semantic difference of two EDS/DCF/XDD files: objects and attributes added, removed or changed.
    #[command(after_help = "Examples:
  canopener eds diff firmware-1.2.eds firmware-1.3.eds
  canopener eds diff vendor.eds vendor.xdd             # formats may differ; notation and layout do not count
  canopener eds diff a.eds b.eds --format json | jq '.changes[] | select(.significant)'
Exit status: 0 same device and object dictionary ([FileInfo] metadata may differ), 1 different, 2 trouble.")]
    Diff(EdsDiffArgs),
    /// Check EDS/DCF files against CiA 306/301, reference profiles, tool portability and rule packs.
    #[command(after_help = "Examples:
  canopener eds check device.eds
  canopener eds check vendor/ 'more/*.dcf' --format sarif -o eds.sarif   # directories and globs, in parallel
  canopener eds check device.eds --deny warnings                  # CI: warnings fail too
  canopener eds check device.eds --rules project.toml --tag naming   # your own rules, only one tag
  canopener eds check device.eds --skip T001,T004 --format json | jq '.summary'
  canopener eds check vendor/ --format html -o report.html        # one self-contained page
Exit status: 0 no errors, 1 errors found (or warnings with --deny warnings), 2 a file could not be read,
or bad arguments.")]
    Check(EdsCheckArgs),
    /// Print the explanation of a check: what it verifies, why, the specification clause, how to fix it.
    #[command(after_help = "Examples:
  canopener eds explain C301
  canopener eds explain sub-number-mismatch          # slugs work too
  canopener eds explain paper/no-blank-names --rules seed-paper.toml")]
    Explain(EdsExplainArgs),
    /// List checks: built-in and from rule packs.
    #[command(subcommand)]
    Rules(EdsRulesCommand),
    /// Apply the safe fixes (SubNumber, object lists, sub-index 0, section names, key spelling, rule-pack fixes).
    #[command(after_help = "Examples:
  canopener eds fix device.eds --dry-run             # show a unified diff, write nothing
  canopener eds fix device.eds -o fixed.eds
  canopener eds fix device.eds --in-place            # keeps device.eds.bak
  canopener eds fix device.eds --in-place --only P045,P044
  canopener eds fix device.eds --rules seed-paper.toml --dry-run
Every untouched line stays byte-identical. Fixes that change what the file says about the device
(e.g. a sub-index 0 default) are marked as such. Exit status: 0 no errors remain, 1 errors remain
(or warnings with --deny warnings), 2 trouble.")]
    Fix(EdsFixArgs),
}

/// `eds rules` subcommands.
#[derive(Debug, Subcommand)]
pub(crate) enum EdsRulesCommand {
    /// Show every check, built-in and user, with its code, severity, tags and title.
    #[command(after_help = "Examples:
  canopener eds rules list
  canopener eds rules list --tag portability
  canopener eds rules list --rules seed-paper.toml --format json")]
    List(EdsRulesListArgs),
}

/// Which checks run: shared by `eds check`, `eds fix` and `eds rules list`.
#[derive(Debug, Clone, Args)]
pub(crate) struct CheckSelectionArgs {
    /// A rule pack (TOML, see crates/canopener-rules/README.md); repeatable.
    #[arg(long = "rules", value_name = "PACK")]
    pub(crate) rules: Vec<PathBuf>,
    /// Only these checks (codes, slugs or rule ids, comma-separated).
    #[arg(long, value_delimiter = ',', value_name = "CODES")]
    pub(crate) only: Vec<String>,
    /// Never these checks (codes, slugs or rule ids, comma-separated).
    #[arg(long, value_delimiter = ',', value_name = "CODES")]
    pub(crate) skip: Vec<String>,
    /// Only checks with this tag (built-ins are tagged with their group, e.g. cia301, portability); repeatable.
    #[arg(long, value_name = "TAG")]
    pub(crate) tag: Vec<String>,
}

/// What `eds check` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum CheckFormat {
    /// Compiler-style diagnostics with the source line, a caret and help.
    Human,
    /// One JSON document (docs/check-json.md).
    Json,
    /// SARIF 2.1.0 for GitHub/GitLab code scanning.
    Sarif,
    /// JUnit XML: one test case per check per file.
    Junit,
    /// One self-contained HTML page with filters and explanations.
    Html,
}

/// What else fails `eds check` besides errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum DenyLevel {
    /// Warnings fail too.
    Warnings,
}

/// When to color human output.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum ColorChoice {
    /// When writing to a terminal and NO_COLOR is not set.
    Auto,
    /// Always.
    Always,
    /// Never.
    Never,
}

#[derive(Debug, Args)]
pub(crate) struct EdsCheckArgs {
    /// Files, directories (every .eds/.dcf below) or glob patterns.
    #[arg(required = true, value_name = "FILE|DIR|GLOB")]
    pub(crate) inputs: Vec<String>,
    #[command(flatten)]
    pub(crate) selection: CheckSelectionArgs,
    #[arg(long, value_enum, default_value_t = CheckFormat::Human)]
    pub(crate) format: CheckFormat,
    /// Write the report here (atomically) instead of stdout.
    #[arg(short, long, value_name = "OUT")]
    pub(crate) output: Option<PathBuf>,
    /// Fail (exit 1) on warnings too.
    #[arg(long, value_enum, value_name = "LEVEL")]
    pub(crate) deny: Option<DenyLevel>,
    #[arg(long, value_enum, default_value_t = ColorChoice::Auto)]
    pub(crate) color: ColorChoice,
    /// No per-code summary table at the end of human output.
    #[arg(long)]
    pub(crate) no_summary: bool,
}

#[derive(Debug, Args)]
pub(crate) struct EdsExplainArgs {
    /// A code (C301, P020, T004), a slug (sub-number-mismatch) or a rule id from --rules.
    pub(crate) code: String,
    /// A rule pack whose rules can be explained too; repeatable.
    #[arg(long = "rules", value_name = "PACK")]
    pub(crate) rules: Vec<PathBuf>,
    #[arg(long, value_enum, default_value_t = ReportFormat::Human)]
    pub(crate) format: ReportFormat,
}

#[derive(Debug, Args)]
pub(crate) struct EdsRulesListArgs {
    #[command(flatten)]
    pub(crate) selection: CheckSelectionArgs,
    #[arg(long, value_enum, default_value_t = ReportFormat::Human)]
    pub(crate) format: ReportFormat,
}

#[derive(Debug, Args)]
pub(crate) struct EdsFixArgs {
    /// The EDS or DCF file.
    pub(crate) file: PathBuf,
    /// Write the fixed file here (atomically) instead of stdout; never the input file.
    #[arg(short, long, value_name = "OUT", conflicts_with = "in_place")]
    pub(crate) output: Option<PathBuf>,
    /// Rewrite the input file, keeping FILE.bak.
    #[arg(long)]
    pub(crate) in_place: bool,
    /// Print a unified diff of the fixes and write nothing.
    #[arg(long)]
    pub(crate) dry_run: bool,
    #[command(flatten)]
    pub(crate) selection: CheckSelectionArgs,
    /// Exit 1 when warnings remain too.
    #[arg(long, value_enum, value_name = "LEVEL")]
    pub(crate) deny: Option<DenyLevel>,
}

/// How `eds` commands report.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum ReportFormat {
    /// Text for people.
    Human,
    /// One JSON document for machines.
    Json,
}

/// What `eds convert` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum ConvertTarget {
    /// canopener's versioned JSON form of the model (docs/eds-json.md).
    Json,
    /// A CiA 306 EDS (from a DCF: the DCF additions removed).
    Eds,
    /// A CiA 306 DCF for one node (needs --node-id and --bitrate unless the input is a DCF).
    Dcf,
    /// A CiA 311 v1.1 XDD, or an XDC when the input is a DCF.
    Xdd,
}

#[derive(Debug, Args)]
pub(crate) struct EdsShowArgs {
    /// The file: EDS, DCF, XDD, XDC or canopener JSON.
    pub(crate) file: PathBuf,
    /// Show only this object (hexadecimal: 1018, 0x1018 or 1018h).
    #[arg(long, value_parser = parse_index, value_name = "INDEX")]
    pub(crate) object: Option<u16>,
    /// Resolve $NODEID formulas for this node-ID (a DCF's own node-ID is used by default).
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=127), value_name = "N")]
    pub(crate) node_id: Option<u8>,
    /// List every loading diagnostic, not just the summary.
    #[arg(long)]
    pub(crate) diagnostics: bool,
    #[arg(long, value_enum, default_value_t = ReportFormat::Human)]
    pub(crate) format: ReportFormat,
}

#[derive(Debug, Args)]
pub(crate) struct EdsConvertArgs {
    /// The file: EDS, DCF, XDD, XDC or canopener JSON.
    pub(crate) file: PathBuf,
    /// The format to write.
    #[arg(long, value_enum)]
    pub(crate) to: ConvertTarget,
    /// Write here (atomically) instead of stdout; never the input file.
    #[arg(short, long, value_name = "OUT")]
    pub(crate) output: Option<PathBuf>,
    /// Node-ID of the DCF (1..127).
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..=127), value_name = "N")]
    pub(crate) node_id: Option<u16>,
    /// Bit rate of the DCF in kbit/s (10, 20, 50, 125, 250, 500, 800, 1000).
    #[arg(long, value_name = "KBIT")]
    pub(crate) bitrate: Option<u16>,
    /// List every loading diagnostic, not just the summary.
    #[arg(long)]
    pub(crate) diagnostics: bool,
}

#[derive(Debug, Args)]
pub(crate) struct EdsFmtArgs {
    /// The EDS or DCF file.
    pub(crate) file: PathBuf,
    /// Write here (atomically) instead of stdout.
    #[arg(short, long, value_name = "OUT", conflicts_with_all = ["in_place", "check"])]
    pub(crate) output: Option<PathBuf>,
    /// Replace the file itself, keeping the original as FILE.bak.
    #[arg(long, conflicts_with = "check")]
    pub(crate) in_place: bool,
    /// Write nothing; exit 1 if the file is not in canonical form.
    #[arg(long)]
    pub(crate) check: bool,
    /// List every loading diagnostic, not just the summary.
    #[arg(long)]
    pub(crate) diagnostics: bool,
}

#[derive(Debug, Args)]
pub(crate) struct EdsDiffArgs {
    /// The first (old) file.
    pub(crate) a: PathBuf,
    /// The second (new) file.
    pub(crate) b: PathBuf,
    #[arg(long, value_enum, default_value_t = ReportFormat::Human)]
    pub(crate) format: ReportFormat,
}

/// Reads a fault name of the device fault catalogue; the error lists every name.
fn parse_fault(text: &str) -> Result<canopener_device::faults::Fault, String> {
    text.parse()
        .map_err(|e: canopener_device::faults::UnknownFault| e.to_string())
}

/// Reads an object index as CANopen tools write it: hexadecimal, with or without `0x` or `h`.
pub(crate) fn parse_index(text: &str) -> Result<u16, String> {
    let t = text.trim();
    let digits = t
        .strip_prefix("0x")
        .or_else(|| t.strip_prefix("0X"))
        .or_else(|| t.strip_suffix('h'))
        .or_else(|| t.strip_suffix('H'))
        .unwrap_or(t);
    u16::from_str_radix(digits, 16)
        .map_err(|_| format!("'{text}' is not an object index; write e.g. 1018, 0x1018 or 1018h"))
}

/// Reads an UNSIGNED32 in decimal or with a `0x` prefix in hexadecimal.
fn parse_u32_number(text: &str) -> Result<u32, String> {
    let t = text.trim();
    let parsed = match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(hex) => u32::from_str_radix(hex, 16),
        None => t.parse(),
    };
    parsed.map_err(|_| format!("'{text}' is not an UNSIGNED32; write e.g. 4660 or 0x1234"))
}

#[derive(Debug, Subcommand)]
pub(crate) enum BusCommand {
    /// Serve CAN buses over the socketcand protocol (python-can `interface="socketcand"` connects).
    #[command(after_help = "Examples:
  canopener bus serve                              # 127.0.0.1:29536, buses created on first `open`
  canopener bus serve --listen 0.0.0.0:29536       # reachable from other machines (no authentication!)
  python: can.Bus(interface=\"socketcand\", host=\"127.0.0.1\", port=29536, channel=\"can0\")
  canopener: --bus socketcand://127.0.0.1:29536/can0")]
    Serve(ServeArgs),
    /// Print frames live, decoded as CANopen (NMT, SDO, PDO, EMCY, heartbeat, LSS, SYNC, TIME).
    #[command(after_help = "Examples:
  canopener bus dump --bus socketcand://127.0.0.1:29536/can0
  canopener bus dump --bus socketcan:can0 --log session.log     # also write a candump log
  canopener bus dump --bus socketcan:can0 --raw                 # candump -L style lines, no decoding
  canopener bus dump --bus udp-multicast://239.74.163.2:43113 --format json --count 100")]
    Dump(DumpArgs),
    /// Send frames given in candump compact form (ID#DATA, ID#R for remote frames).
    #[command(after_help = "Examples:
  canopener bus send --bus socketcand://127.0.0.1:29536/can0 000#0100        # NMT start all nodes
  canopener bus send --bus socketcan:can0 601#4000100000000000              # SDO upload 1000h:00 from node 1
  canopener bus send --bus socketcan:can0 701#R 123#DEADBEEF --gap 10ms     # several frames, 10 ms apart")]
    Send(SendArgs),
    /// Replay a candump log file onto a bus, with its original timing unless --no-timing.
    #[command(after_help = "Examples:
  canopener bus replay session.log --bus socketcand://127.0.0.1:29536/can0
  canopener bus replay session.log --bus socketcan:can0 --no-timing
  canopener bus replay session.log --bus socketcan:can0 --speed 10 --interface can1   # only can1 lines")]
    Replay(ReplayArgs),
    /// Generate bus load like can-utils cangen: counting frames at a fixed rate or as fast as possible.
    #[command(after_help = "Examples:
  canopener bus gen --bus socketcand://127.0.0.1:29536/can0 --rate 1000 --count 5000
  canopener bus gen --bus socketcand://127.0.0.1:29536/can0 --duration 10s      # flood, unpaced")]
    Gen(GenArgs),
    /// Decode a candump log file offline, exactly as `bus dump` prints live traffic.
    #[command(after_help = "Examples:
  canopener bus decode session.log
  canopener bus decode session.log --format json > session.jsonl")]
    Decode(DecodeArgs),
}

#[derive(Debug, Args)]
pub(crate) struct BusArg {
    #[arg(long = "bus", value_name = "SPEC", help = BUS_HELP)]
    pub(crate) spec: Option<String>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum OutputFormat {
    /// Aligned text for people.
    Text,
    /// One JSON object per line for machines.
    Json,
}

#[derive(Debug, Args)]
pub(crate) struct ServeArgs {
    /// Address and port to listen on.
    #[arg(long, default_value = "127.0.0.1:29536", value_name = "ADDR:PORT")]
    pub(crate) listen: SocketAddr,
    /// Hold bus traffic back this long after a client's rawmode `< ok >` (python-can needs the reply alone).
    #[arg(long, default_value = "50ms", value_parser = parse_duration, value_name = "DURATION")]
    pub(crate) raw_grace: std::time::Duration,
    /// Drop a client that has not read its frames for this long (others are never held up longer).
    #[arg(long, default_value = "2s", value_parser = parse_duration, value_name = "DURATION")]
    pub(crate) stall_timeout: std::time::Duration,
    /// Also deliver each frame back to its sender (real socketcand does not).
    #[arg(long)]
    pub(crate) echo: bool,
    /// Print hub statistics every this often (0 = never).
    #[arg(long, default_value = "0s", value_parser = parse_duration, value_name = "DURATION")]
    pub(crate) stats_every: std::time::Duration,
}

#[derive(Debug, Args)]
pub(crate) struct DumpArgs {
    #[command(flatten)]
    pub(crate) bus: BusArg,
    /// Also write every frame to this candump log file (refuses to overwrite unless --overwrite).
    #[arg(long, value_name = "FILE")]
    pub(crate) log: Option<PathBuf>,
    /// Replace an existing --log file.
    #[arg(long, requires = "log")]
    pub(crate) overwrite: bool,
    /// Print raw frames (candump log lines) without CANopen decoding.
    #[arg(long)]
    pub(crate) raw: bool,
    #[arg(long, value_enum, default_value_t = OutputFormat::Text)]
    pub(crate) format: OutputFormat,
    /// Stop after this many frames.
    #[arg(long, value_name = "N")]
    pub(crate) count: Option<u64>,
    /// Stop after this long.
    #[arg(long, value_parser = parse_duration, value_name = "DURATION")]
    pub(crate) duration: Option<std::time::Duration>,
}

#[derive(Debug, Args)]
pub(crate) struct SendArgs {
    #[command(flatten)]
    pub(crate) bus: BusArg,
    /// Frames in candump compact form: 123#DEADBEEF, 1ABCDEF0#01, 701#R, 000#0100.
    #[arg(required = true, value_name = "FRAME")]
    pub(crate) frames: Vec<String>,
    /// Pause between frames.
    #[arg(long, default_value = "0s", value_parser = parse_duration, value_name = "DURATION")]
    pub(crate) gap: std::time::Duration,
    /// Send the whole list this many times.
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub(crate) repeat: u64,
}

#[derive(Debug, Args)]
pub(crate) struct ReplayArgs {
    /// candump log file (`(1436509052.249713) can0 123#DEADBEEF` lines).
    #[arg(value_name = "FILE")]
    pub(crate) file: PathBuf,
    #[command(flatten)]
    pub(crate) bus: BusArg,
    /// Send as fast as possible instead of keeping the recorded gaps.
    #[arg(long, conflicts_with = "speed")]
    pub(crate) no_timing: bool,
    /// Play faster (2 = twice as fast) or slower (0.5) than recorded.
    #[arg(long, default_value_t = 1.0, value_name = "FACTOR")]
    pub(crate) speed: f64,
    /// Only replay lines recorded on this interface (default: all).
    #[arg(long, value_name = "NAME")]
    pub(crate) interface: Option<String>,
    /// Skip lines that cannot be read (reported as warnings) instead of refusing the whole file.
    #[arg(long)]
    pub(crate) skip_invalid: bool,
    /// Replay the file this many times.
    #[arg(long = "loop", default_value_t = 1, value_name = "N")]
    pub(crate) loops: u64,
}

#[derive(Debug, Args)]
pub(crate) struct GenArgs {
    #[command(flatten)]
    pub(crate) bus: BusArg,
    /// CAN id of the generated frames (hex; 8 digits or > 7FF for an extended id).
    #[arg(long, default_value = "123", value_name = "HEXID")]
    pub(crate) id: String,
    /// Data length of each frame (0-8); bytes 0-3 carry a little-endian counter when DLC >= 4.
    #[arg(long, default_value_t = 8, value_name = "0-8")]
    pub(crate) dlc: u8,
    /// Frames per second (0 = as fast as the bus accepts them).
    #[arg(long, default_value_t = 0.0, value_name = "FRAMES_PER_S")]
    pub(crate) rate: f64,
    /// Stop after this many frames.
    #[arg(long, value_name = "N")]
    pub(crate) count: Option<u64>,
    /// Stop after this long.
    #[arg(long, value_parser = parse_duration, value_name = "DURATION")]
    pub(crate) duration: Option<std::time::Duration>,
}

#[derive(Debug, Args)]
pub(crate) struct DecodeArgs {
    /// candump log file to decode.
    #[arg(value_name = "FILE")]
    pub(crate) file: PathBuf,
    #[arg(long, value_enum, default_value_t = OutputFormat::Text)]
    pub(crate) format: OutputFormat,
}

#[derive(Debug, Args)]
pub(crate) struct SimArgs {
    /// EDS or DCF files: one simulated device each.
    #[arg(required_unless_present = "list_faults", value_name = "FILE")]
    pub(crate) files: Vec<PathBuf>,
    /// Give every simulated device this defect (repeatable); `--list-faults` names them.
    #[arg(long = "fault", value_name = "NAME", value_parser = parse_fault)]
    pub(crate) faults: Vec<canopener_device::faults::Fault>,
    /// Describe every fault `--fault` accepts and exit.
    #[arg(long)]
    pub(crate) list_faults: bool,
    #[command(flatten)]
    pub(crate) bus: BusArg,
    /// Node-ID of devices whose file is not a DCF with a node-ID (several files: N, N+1, ... in order).
    /// Without it such devices start LSS-unconfigured (node-ID FFh) and wait for an LSS master.
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=127), value_name = "N")]
    pub(crate) node_id: Option<u8>,
    /// Serial number 1018h:04 of the devices (several files: S, S+1, ... in order), so that devices from
    /// one EDS have distinct LSS addresses. Decimal or 0x-hex.
    #[arg(long, value_parser = parse_u32_number, value_name = "S")]
    pub(crate) serial: Option<u32>,
    /// Keep what devices store in this directory, so it survives restarts: saved parameters (1010h
    /// "save", 1011h "load") and the LSS configuration (store configuration: the node-ID to start with).
    #[arg(long, value_name = "DIR")]
    pub(crate) state_dir: Option<PathBuf>,
    /// The application behind each device's object dictionary.
    #[arg(long, value_enum, default_value_t = SimApp::None)]
    pub(crate) app: SimApp,
    #[arg(long, value_enum, default_value_t = SimFormat::Human)]
    pub(crate) format: SimFormat,
}

/// What runs behind a simulated device's object dictionary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum SimApp {
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

#[derive(Debug, Args)]
pub(crate) struct DemoArgs {
    /// Run the demo on this bus instead of an in-process hub.
    #[arg(long = "bus", value_name = "SPEC", help = BUS_HELP)]
    pub(crate) bus: Option<String>,
    /// Replay speed factor (0 = as fast as possible).
    #[arg(long, default_value_t = 1.0, value_name = "FACTOR")]
    pub(crate) speed: f64,
    #[arg(long, value_enum, default_value_t = OutputFormat::Text)]
    pub(crate) format: OutputFormat,
    /// Only print the summary, not every frame.
    #[arg(long, short)]
    pub(crate) quiet: bool,
}

/// Parses `250ms`, `2s`, `1.5s`, `10us`, `1m`, or a bare number of seconds.
pub(crate) fn parse_duration(text: &str) -> Result<std::time::Duration, String> {
    let text = text.trim();
    let split = text
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(text.len());
    let (number, unit) = text.split_at(split);
    let value: f64 = number
        .parse()
        .map_err(|_| format!("'{text}' is not a duration; write e.g. 250ms, 2s, 1.5s, 10us or 1m"))?;
    let seconds = match unit.trim() {
        "" | "s" => value,
        "ms" => value / 1e3,
        "us" | "µs" => value / 1e6,
        "ns" => value / 1e9,
        "m" | "min" => value * 60.0,
        "h" => value * 3600.0,
        other => {
            return Err(format!(
                "unknown duration unit '{other}' in '{text}'; use ns, us, ms, s, m or h"
            ));
        }
    };
    if !seconds.is_finite() || !(0.0..=1e9).contains(&seconds) {
        return Err(format!("duration '{text}' is out of range"));
    }
    Ok(std::time::Duration::from_secs_f64(seconds))
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;
    use std::time::Duration;

    #[test]
    fn clap_definition_is_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn durations_parse_with_units() {
        assert_eq!(parse_duration("250ms"), Ok(Duration::from_millis(250)));
        assert_eq!(parse_duration("2"), Ok(Duration::from_secs(2)));
        assert_eq!(parse_duration("1.5s"), Ok(Duration::from_millis(1500)));
        assert_eq!(parse_duration("10us"), Ok(Duration::from_micros(10)));
        assert_eq!(parse_duration("1m"), Ok(Duration::from_secs(60)));
        assert!(parse_duration("fast").unwrap_err().contains("not a duration"));
        assert!(
            parse_duration("3 parsecs")
                .unwrap_err()
                .contains("unknown duration unit")
        );
        assert!(parse_duration("").is_err());
    }
}

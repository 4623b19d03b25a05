//! Options of the `bus` commands and `demo`.

use std::net::SocketAddr;
use std::path::PathBuf;

use clap::{Args, Subcommand};

use crate::args::{BusArg, OutputFormat};
use crate::grammar::{parse_duration, parse_u8, parse_u64};

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
    #[arg(long, value_name = "N", value_parser = parse_u64)]
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
    #[arg(long, default_value = "1", value_name = "N", value_parser = parse_u64)]
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
    #[arg(long = "loop", default_value = "1", value_name = "N", value_parser = parse_u64)]
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
    #[arg(long, default_value = "8", value_name = "0-8", value_parser = parse_u8)]
    pub(crate) dlc: u8,
    /// Frames per second (0 = as fast as the bus accepts them).
    #[arg(long, default_value_t = 0.0, value_name = "FRAMES_PER_S")]
    pub(crate) rate: f64,
    /// Stop after this many frames.
    #[arg(long, value_name = "N", value_parser = parse_u64)]
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

/// What `canopener demo --monitor` was asked (`demo/args.rs` parses the `demo` command).
#[derive(Debug)]
pub(crate) struct SessionReplayArgs {
    /// The bus instead of an in-process hub.
    pub(crate) bus: Option<String>,
    /// Replay speed factor (0 = as fast as possible).
    pub(crate) speed: f64,
    pub(crate) format: OutputFormat,
    /// Only print the summary, not every frame.
    pub(crate) quiet: bool,
}

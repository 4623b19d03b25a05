//! `canopener node info|scan|dump`: what one node is (identity, device type, error register, names,
//! heartbeat state), which node-IDs answer, and everything readable of one node as a DCF
//! (`node_dump`).
//!
//! The objects read are the ones every CiA 301 device has or commonly has: 1000h device type and
//! 1001h error register (mandatory), 1018h identity (sub 1 mandatory), 1008h/1009h/100Ah names and
//! versions and 1017h producer heartbeat time (optional; an abort 0602 0000h or 0609 0011h there
//! means "not implemented", not an error).

use std::fmt::Write as _;
use std::time::Duration;

use canopener_can::Instant;
use canopener_eds::Eds;
use canopener_eds::model::int_of;
use canopener_master::sdo_client::{SdoTransferError, UploadMode};
use canopener_wire::NmtState;
use canopener_wire::error_register_text;
use serde_json::json;

use crate::args::OutputFormat;
use crate::eds::input::{print_stdout, read_input};
use crate::error::{CliError, CliResult};
use crate::master::args::{NodeDumpArgs, NodeInfoArgs, NodeScanArgs};
use canopener_runtime::link::{BusLink, Ended, Flow, Link, drive};

use crate::master::link::open_link;
use crate::master::node_list::parse_node_list;
use crate::master::node_scan::{Fleet, ScanResult};
use crate::master::sdo::print_json;
use crate::master::sdo_session::{SdoSession, checked_timeout, device_error, is_absent, millis, object_name};
use crate::master::sdo_typing::is_printable;

/// Heartbeat messages go out on 700h + node-ID (CiA 301 §7.2.8.3.2.2).
const HEARTBEAT_BASE: u16 = 0x700;

/// After this many timeouts in a row `node info` stops asking: the node is gone.
const TIMEOUTS_IN_A_ROW: u32 = 2;

pub(crate) fn info(args: NodeInfoArgs) -> CliResult {
    let eds = match &args.eds {
        Some(path) => Some((path.display().to_string(), read_input(path)?.eds)),
        None => None,
    };
    let mut reader = Reader {
        session: SdoSession::open(&args.master, args.target.node, "node info")?,
        timeouts_in_a_row: 0,
    };
    let node = args.target.node;
    // 1000h is mandatory: a node that does not give it is not worth asking more.
    let device_type = match reader.read(0x1000, 0)? {
        Ok(data) => number(&data, 4).map_err(|why| {
            CliError::Device(format!(
                "node {node}, {}: {why}",
                object_name(0x1000, 0, Some("Device type"))
            ))
        })?,
        Err(err) => return Err(device_error(node, 0x1000, 0, Some("Device type"), &err)),
    };
    let error_register = reader.number(0x1001, 0, 1)?;
    let mut identity = Vec::new();
    for sub in 1..=4 {
        identity.push(reader.number(0x1018, sub, 4)?);
    }
    let mut names = Vec::new();
    for index in [0x1008, 0x1009, 0x100A] {
        names.push(reader.text(index)?);
    }
    let heartbeat_time = reader.number(0x1017, 0, 2)?;
    let heartbeat = match &heartbeat_time {
        Field::Value(period) if *period > 0 => {
            Some(wait_heartbeat(reader.session.link_mut(), node, *period)?)
        }
        _ => None,
    };
    let report = InfoReport {
        node,
        device_type: describe_device_type(device_type as u32),
        error_register,
        identity,
        names,
        heartbeat_time,
        heartbeat,
        eds,
    };
    match args.master.format {
        OutputFormat::Json => print_json(&report.json()),
        OutputFormat::Text => print_stdout(&report.text()),
    }
}

pub(crate) fn scan(args: NodeScanArgs) -> CliResult {
    let mut nodes: Vec<u8> =
        parse_node_list(&args.range, "--range", "canopener node scan --range 1-10,20,30")?
            .into_iter()
            .map(|node| node.get())
            .collect();
    nodes.sort_unstable();
    nodes.dedup();
    let timeout = checked_timeout(args.master.timeout)?;
    let identity: Vec<(u16, u8)> = (1..=4).map(|sub| (0x1018, sub)).collect();
    let mut fleet = Fleet::new(
        &nodes,
        (0x1000, 0),
        &identity,
        usize::from(args.parallel),
        timeout,
    )?;
    let mut link = open_link(args.master.bus.spec.as_deref(), "node scan")?;
    let started = link.now();
    fleet.start(started);
    let mut results: Vec<ScanResult> = Vec::new();
    // Every node runs at most five uploads of one timeout each, `parallel` nodes at a time; the
    // deadline only guards against a core that stops asking for time.
    let rounds = nodes.len().div_ceil(usize::from(args.parallel)) as u32;
    let deadline = started + (timeout * 5 + Duration::from_millis(500)) * rounds.max(1);
    let ended = drive::<_, _, _, CliError>(&mut link, &mut fleet, Some(deadline), |fleet, result| {
        results.push(result);
        Ok(if fleet.finished() {
            Flow::Done(())
        } else {
            Flow::Continue
        })
    })?;
    match ended {
        Ok(()) => {}
        Err(Ended::Deadline) => {
            eprintln!("warning: the scan ran out of time; node-IDs not answered yet are not listed");
        }
        Err(Ended::Cancelled) => {
            eprintln!("interrupted: the scan stopped before every node-ID was asked");
            return Err(CliError::Exit(crate::error::exit_code::INTERRUPTED));
        }
    }
    let elapsed = link.now().saturating_duration_since(started);
    let found = found_nodes(&results);
    match args.master.format {
        OutputFormat::Json => print_json(&json!({
            "asked": nodes.len(),
            "answered": found.len(),
            "elapsed_ms": millis(elapsed),
            "nodes": found.iter().map(ScanRow::json).collect::<Vec<_>>(),
        })),
        OutputFormat::Text => print_stdout(&scan_table(&found, nodes.len(), elapsed)),
    }
}

pub(crate) fn dump(args: NodeDumpArgs) -> CliResult {
    crate::master::node_dump::run(args)
}

/// The SDO session of `node info`, giving up once the node has stopped answering.
struct Reader {
    session: SdoSession,
    timeouts_in_a_row: u32,
}

/// One optional object as `node info` shows it.
#[derive(Debug, Clone, PartialEq)]
enum Field<T> {
    Value(T),
    /// The device says the object or sub-index does not exist.
    Absent,
    /// Any other failure, as a message.
    Failed(String),
}

impl Reader {
    fn read(&mut self, index: u16, sub: u8) -> CliResult<Result<Vec<u8>, SdoTransferError>> {
        let outcome = self
            .session
            .upload(index, sub, UploadMode::Normal, &mut |_, _| {})?;
        match &outcome {
            Err(err @ SdoTransferError::TimedOut { .. }) => {
                self.timeouts_in_a_row += 1;
                if self.timeouts_in_a_row >= TIMEOUTS_IN_A_ROW {
                    return Err(CliError::Device(format!(
                        "node {} stopped answering: {}",
                        self.session.node(),
                        device_error(self.session.node(), index, sub, None, err)
                    )));
                }
            }
            _ => self.timeouts_in_a_row = 0,
        }
        Ok(outcome.map(|transfer| transfer.data))
    }

    fn number(&mut self, index: u16, sub: u8, width: usize) -> CliResult<Field<u64>> {
        Ok(match self.read(index, sub)? {
            Ok(data) => number(&data, width).map_or_else(Field::Failed, Field::Value),
            Err(err) if is_absent(&err) => Field::Absent,
            Err(err) => Field::Failed(err.to_string()),
        })
    }

    fn text(&mut self, index: u16) -> CliResult<Field<String>> {
        Ok(match self.read(index, 0)? {
            Ok(data) if data.is_empty() || is_printable(&data) => {
                let end = data
                    .iter()
                    .rposition(|byte| *byte != 0)
                    .map_or(0, |last| last + 1);
                Field::Value(String::from_utf8_lossy(&data[..end]).into_owned())
            }
            Ok(data) => Field::Failed(format!(
                "not text: {}",
                data.iter()
                    .map(|byte| format!("{byte:02X}"))
                    .collect::<Vec<_>>()
                    .join(" ")
            )),
            Err(err) if is_absent(&err) => Field::Absent,
            Err(err) => Field::Failed(err.to_string()),
        })
    }
}

/// A little-endian unsigned number of `width` bytes; shorter answers are zero-extended (an
/// expedited answer may carry fewer bytes), longer ones are wrong.
fn number(data: &[u8], width: usize) -> Result<u64, String> {
    if data.is_empty() || data.len() > width {
        return Err(format!(
            "the device answered with {} byte(s); UNSIGNED{} has {width}",
            data.len(),
            width * 8
        ));
    }
    Ok(data
        .iter()
        .rev()
        .fold(0, |acc, byte| (acc << 8) | u64::from(*byte)))
}

/// What one heartbeat said, or that none came.
#[derive(Debug, Clone, PartialEq)]
struct HeartbeatSeen {
    /// How long we waited at most.
    waited: Duration,
    /// The state and how long after we started waiting it arrived.
    state: Option<(NmtState, Duration)>,
    /// A heartbeat byte that is no NMT state.
    invalid: Option<u8>,
}

/// Waits up to 1.5 heartbeat periods for one heartbeat of `node` (CiA 301 §7.2.8.3.2.2).
fn wait_heartbeat(link: &mut BusLink, node: u8, period_ms: u64) -> CliResult<HeartbeatSeen> {
    let waited = Duration::from_millis(period_ms.saturating_mul(3) / 2);
    let start = link.now();
    let deadline: Instant = start + waited;
    let id = u32::from(HEARTBEAT_BASE + u16::from(node));
    while let Some((at, frame)) = link.recv_until(deadline)? {
        if frame.id().as_raw() != id || frame.is_remote() || frame.data().len() != 1 {
            continue;
        }
        let byte = frame.data()[0] & 0x7F;
        let after = at.saturating_duration_since(start);
        return Ok(match NmtState::from_raw(byte) {
            Some(state) => HeartbeatSeen {
                waited,
                state: Some((state, after)),
                invalid: None,
            },
            None => HeartbeatSeen {
                waited,
                state: None,
                invalid: Some(frame.data()[0]),
            },
        });
    }
    Ok(HeartbeatSeen {
        waited,
        state: None,
        invalid: None,
    })
}

/// 1000h decoded (CiA 301 §7.5.2.1): the device profile in bits 0..15, additional information in
/// bits 16..31, which CiA 401 splits into I/O functionality and specific functionality.
#[derive(Debug, Clone, PartialEq, Eq)]
struct DeviceType {
    raw: u32,
    profile: u16,
    additional: u16,
    profile_name: String,
    functions: Vec<String>,
}

fn describe_device_type(raw: u32) -> DeviceType {
    let profile = (raw & 0xFFFF) as u16;
    let additional = (raw >> 16) as u16;
    let profile_name = match profile {
        0 => "no standardized device profile".to_owned(),
        401 => "CiA 401 generic I/O".to_owned(),
        402 => "CiA 402 drives and motion control".to_owned(),
        404 => "CiA 404 measuring devices and closed-loop controllers".to_owned(),
        405 => "CiA 405 IEC 61131-3 programmable devices".to_owned(),
        406 => "CiA 406 encoders".to_owned(),
        408 => "CiA 408 fluid power technology".to_owned(),
        410 => "CiA 410 inclinometers".to_owned(),
        413 => "CiA 413 truck gateways".to_owned(),
        417 => "CiA 417 lift control".to_owned(),
        418 => "CiA 418 battery modules".to_owned(),
        419 => "CiA 419 battery chargers".to_owned(),
        443 => "CiA 443 SIIS level-2 devices".to_owned(),
        447 => "CiA 447 special-purpose car add-on devices".to_owned(),
        453 => "CiA 453 power supplies".to_owned(),
        other => format!("CiA {other} device profile"),
    };
    let mut functions = Vec::new();
    if profile == 401 {
        if additional == 0xFFFF {
            functions.push("multiple-device module (the device types are in 67FFh)".to_owned());
        } else {
            // CiA 401 §8.1 of the reference: bits 16..23 I/O functionality, 24..31 specific.
            for (bit, name) in [
                (16, "digital inputs"),
                (17, "digital outputs"),
                (18, "analogue inputs"),
                (19, "analogue outputs"),
            ] {
                if raw & (1 << bit) != 0 {
                    functions.push(name.to_owned());
                }
            }
            match raw >> 24 {
                0 => {}
                1 => functions.push("joystick".to_owned()),
                other => functions.push(format!("specific functionality {other:02X}h")),
            }
        }
    }
    DeviceType {
        raw,
        profile,
        additional,
        profile_name,
        functions,
    }
}

struct InfoReport {
    node: u8,
    device_type: DeviceType,
    error_register: Field<u64>,
    /// 1018h sub 1..4.
    identity: Vec<Field<u64>>,
    /// 1008h, 1009h, 100Ah.
    names: Vec<Field<String>>,
    heartbeat_time: Field<u64>,
    heartbeat: Option<HeartbeatSeen>,
    eds: Option<(String, Eds)>,
}

const IDENTITY_NAMES: [&str; 4] = ["Vendor-ID", "Product code", "Revision number", "Serial number"];
const IDENTITY_KEYS: [&str; 4] = ["vendor_id", "product_code", "revision_number", "serial_number"];
const NAME_LABELS: [&str; 3] = ["Device name", "Hardware version", "Software version"];
const NAME_KEYS: [&str; 3] = ["device_name", "hardware_version", "software_version"];

impl InfoReport {
    fn text(&self) -> String {
        let mut out = String::new();
        let _ = writeln!(out, "Node {}", self.node);
        let kind = &self.device_type;
        let mut described = kind.profile_name.clone();
        if !kind.functions.is_empty() {
            let _ = write!(described, ": {}", kind.functions.join(", "));
        } else if kind.additional != 0 && kind.profile != 401 {
            let _ = write!(described, ", additional information {:04X}h", kind.additional);
        }
        line(
            &mut out,
            "Device type",
            &format!("0x{:08X}  {described}", kind.raw),
        );
        let register = match &self.error_register {
            Field::Value(value) => {
                let text = error_register_text(*value as u8);
                if text.is_empty() {
                    format!("0x{value:02X}  no error")
                } else {
                    format!("0x{value:02X}  {text}")
                }
            }
            other => field_text(other, "not implemented (CiA 301 makes 1001h mandatory)"),
        };
        line(&mut out, "Error register", &register);
        for (name, field) in IDENTITY_NAMES.iter().zip(&self.identity) {
            let text = match field {
                Field::Value(value) => format!("0x{value:08X}  ({value})"),
                other => field_text(other, "absent"),
            };
            line(&mut out, name, &text);
        }
        for (label, field) in NAME_LABELS.iter().zip(&self.names) {
            let text = match field {
                Field::Value(text) => format!("{text:?}"),
                other => field_text(other, "not implemented"),
            };
            line(&mut out, label, &text);
        }
        line(&mut out, "Heartbeat", &self.heartbeat_text());
        if let Some((path, eds)) = &self.eds {
            line(&mut out, "EDS", &self.eds_text(path, eds));
        }
        out
    }

    fn heartbeat_text(&self) -> String {
        match (&self.heartbeat_time, &self.heartbeat) {
            (Field::Value(0), _) => "off (1017h = 0), so the NMT state is not known".to_owned(),
            (Field::Value(period), Some(seen)) => match (seen.state, seen.invalid) {
                (Some((state, after)), _) => format!(
                    "every {period} ms; state {state} (heartbeat {:.0} ms after asking)",
                    millis(after)
                ),
                (None, Some(byte)) => {
                    format!("every {period} ms; the heartbeat carried {byte:02X}h, no NMT state")
                }
                (None, None) => format!(
                    "every {period} ms, but none arrived within {} ms",
                    seen.waited.as_millis()
                ),
            },
            (Field::Value(period), None) => format!("every {period} ms"),
            (other, _) => field_text(other, "no heartbeat producer (1017h not implemented)"),
        }
    }

    /// Whether the identity the node gives is the one the EDS describes.
    fn eds_text(&self, path: &str, eds: &Eds) -> String {
        let info = &eds.device_info;
        let product = [info.vendor_name.as_deref(), info.product_name.as_deref()]
            .into_iter()
            .flatten()
            .collect::<Vec<_>>()
            .join(" ");
        let mut differences = Vec::new();
        for (key, field) in [
            ("VendorNumber", &self.identity[0]),
            ("ProductNumber", &self.identity[1]),
            ("RevisionNumber", &self.identity[2]),
        ] {
            let expected = info.get(key).and_then(int_of);
            if let (Some(expected), Field::Value(actual)) = (expected, field)
                && expected != i128::from(*actual)
            {
                differences.push(format!("{key}=0x{expected:X} but the device has 0x{actual:X}"));
            }
        }
        let verdict = if differences.is_empty() {
            "identity matches".to_owned()
        } else {
            differences.join("; ")
        };
        format!("{path} ({product}): {verdict}")
    }

    fn json(&self) -> serde_json::Value {
        let kind = &self.device_type;
        let mut identity = serde_json::Map::new();
        let mut problems = serde_json::Map::new();
        for (sub, (key, field)) in IDENTITY_KEYS.iter().zip(&self.identity).enumerate() {
            identity.insert(
                (*key).to_owned(),
                field_json(field, &mut problems, &format!("1018:{:02X}", sub + 1)),
            );
        }
        let mut names = serde_json::Map::new();
        for ((key, field), index) in NAME_KEYS.iter().zip(&self.names).zip(["1008", "1009", "100A"]) {
            let value = match field {
                Field::Value(text) => json!(text),
                Field::Absent => serde_json::Value::Null,
                Field::Failed(why) => {
                    problems.insert(format!("{index}:00"), json!(why));
                    serde_json::Value::Null
                }
            };
            names.insert((*key).to_owned(), value);
        }
        let error_register = field_json(&self.error_register, &mut problems, "1001:00");
        let heartbeat_time = field_json(&self.heartbeat_time, &mut problems, "1017:00");
        let heartbeat = self.heartbeat.as_ref().map(|seen| {
            json!({
                "state": seen.state.map(|(state, _)| state.to_string()),
                "after_ms": seen.state.map(|(_, after)| millis(after)),
                "waited_ms": millis(seen.waited),
                "invalid_byte": seen.invalid,
            })
        });
        let eds = self
            .eds
            .as_ref()
            .map(|(path, eds)| json!({"file": path, "check": self.eds_text(path, eds)}));
        json!({
            "node": self.node,
            "device_type": {
                "value": kind.raw,
                "raw": format!("{:08X}", kind.raw),
                "profile": kind.profile,
                "profile_name": kind.profile_name,
                "additional": format!("{:04X}", kind.additional),
                "functions": kind.functions,
            },
            "error_register": {
                "value": error_register,
                "text": match &self.error_register {
                    Field::Value(value) => json!(error_register_text(*value as u8)),
                    _ => serde_json::Value::Null,
                },
            },
            "identity": identity,
            "names": names,
            "heartbeat_time_ms": heartbeat_time,
            "heartbeat": heartbeat,
            "eds": eds,
            "problems": problems,
        })
    }
}

fn line(out: &mut String, label: &str, text: &str) {
    let _ = writeln!(out, "  {label:<17} {text}");
}

fn field_text<T>(field: &Field<T>, absent: &str) -> String {
    match field {
        Field::Value(_) => String::new(),
        Field::Absent => absent.to_owned(),
        Field::Failed(why) => format!("error: {why}"),
    }
}

fn field_json(
    field: &Field<u64>,
    problems: &mut serde_json::Map<String, serde_json::Value>,
    key: &str,
) -> serde_json::Value {
    match field {
        Field::Value(value) => json!(value),
        Field::Absent => serde_json::Value::Null,
        Field::Failed(why) => {
            problems.insert(key.to_owned(), json!(why));
            serde_json::Value::Null
        }
    }
}

/// One node that answered the scan.
#[derive(Debug, Clone, PartialEq)]
struct ScanRow {
    node: u8,
    /// 1000h, or why it is missing (an abort is an answer too).
    device_type: Result<u32, String>,
    /// 1018h sub 1..4.
    identity: [Option<u32>; 4],
}

impl ScanRow {
    fn json(&self) -> serde_json::Value {
        let id = |n: usize| {
            self.identity[n]
                .map(|v| json!(v))
                .unwrap_or(serde_json::Value::Null)
        };
        json!({
            "node": self.node,
            "device_type": self.device_type.as_ref().ok(),
            "device_type_error": self.device_type.as_ref().err(),
            "profile": self.device_type.as_ref().ok().map(|raw| describe_device_type(*raw).profile_name),
            "vendor_id": id(0),
            "product_code": id(1),
            "revision_number": id(2),
            "serial_number": id(3),
        })
    }
}

/// The nodes that gave any answer to 1000h, with what they said.
fn found_nodes(results: &[ScanResult]) -> Vec<ScanRow> {
    let mut rows: Vec<ScanRow> = Vec::new();
    for result in results {
        let as_u32 = |data: &[u8]| number(data, 4).ok().map(|v| v as u32);
        match (result.index, result.sub) {
            (0x1000, 0) => {
                let device_type = match &result.outcome {
                    Ok(data) => number(data, 4).map(|v| v as u32),
                    Err(SdoTransferError::TimedOut { .. }) => continue,
                    Err(err) => Err(err.to_string()),
                };
                rows.push(ScanRow {
                    node: result.node,
                    device_type,
                    identity: [None; 4],
                });
            }
            (0x1018, sub @ 1..=4) => {
                if let Some(row) = rows.iter_mut().find(|row| row.node == result.node)
                    && let Ok(data) = &result.outcome
                {
                    row.identity[usize::from(sub - 1)] = as_u32(data);
                }
            }
            _ => {}
        }
    }
    rows.sort_by_key(|row| row.node);
    rows
}

fn scan_table(rows: &[ScanRow], asked: usize, elapsed: Duration) -> String {
    let mut out = String::new();
    if !rows.is_empty() {
        let _ = writeln!(
            out,
            "{:>4}  {:<10}  {:<10}  {:<10}  {:<10}  {:<10}  Profile",
            "Node", "Type", "Vendor-ID", "Product", "Revision", "Serial"
        );
    }
    let hex = |value: Option<u32>| value.map_or_else(|| "-".to_owned(), |v| format!("0x{v:08X}"));
    for row in rows {
        let (kind, profile) = match &row.device_type {
            Ok(raw) => (format!("0x{raw:08X}"), describe_device_type(*raw).profile_name),
            Err(why) => ("-".to_owned(), format!("1000h: {why}")),
        };
        let _ = writeln!(
            out,
            "{:>4}  {kind:<10}  {:<10}  {:<10}  {:<10}  {:<10}  {profile}",
            row.node,
            hex(row.identity[0]),
            hex(row.identity[1]),
            hex(row.identity[2]),
            hex(row.identity[3]),
        );
    }
    let _ = writeln!(
        out,
        "{} of {asked} node-ID{} answered in {:.2} s",
        rows.len(),
        if asked == 1 { "" } else { "s" },
        elapsed.as_secs_f64()
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn device_types_decode_the_profile_and_cia_401_functions() {
        let io = describe_device_type(0x000F_0191);
        assert_eq!(io.profile, 401);
        assert_eq!(io.profile_name, "CiA 401 generic I/O");
        assert_eq!(
            io.functions,
            [
                "digital inputs",
                "digital outputs",
                "analogue inputs",
                "analogue outputs"
            ]
        );
        let joystick = describe_device_type(0x0102_0191);
        assert_eq!(joystick.functions, ["digital outputs", "joystick"]);
        let module = describe_device_type(0xFFFF_0191);
        assert!(module.functions[0].contains("67FFh"));
        let drive = describe_device_type(0x0002_0192);
        assert_eq!(
            (drive.profile_name.as_str(), drive.additional),
            ("CiA 402 drives and motion control", 2)
        );
        assert!(drive.functions.is_empty());
        assert_eq!(
            describe_device_type(0).profile_name,
            "no standardized device profile"
        );
        assert_eq!(describe_device_type(499).profile_name, "CiA 499 device profile");
    }

    #[test]
    fn numbers_are_little_endian_and_length_checked() {
        assert_eq!(number(&[0xBC, 0x0A, 0, 0], 4), Ok(0xABC));
        assert_eq!(number(&[0x05], 4), Ok(5));
        assert!(number(&[1, 2, 3], 2).unwrap_err().contains("UNSIGNED16 has 2"));
        assert!(number(&[], 1).is_err());
    }

    fn result(node: u8, index: u16, sub: u8, outcome: Result<Vec<u8>, SdoTransferError>) -> ScanResult {
        ScanResult {
            node,
            index,
            sub,
            outcome,
        }
    }

    #[test]
    fn scan_rows_list_the_answering_nodes_with_identities() {
        let silent = SdoTransferError::TimedOut {
            waiting_for: "initiate upload response",
            after: Duration::from_millis(100),
        };
        let refused = SdoTransferError::AbortedByServer { code: 0x0602_0000 };
        let results = [
            result(9, 0x1000, 0, Err(refused.clone())),
            result(5, 0x1000, 0, Ok(vec![0x91, 0x01, 0x0F, 0x00])),
            result(6, 0x1000, 0, Err(silent)),
            result(5, 0x1018, 1, Ok(vec![0xBC, 0x0A, 0, 0])),
            result(5, 0x1018, 4, Err(refused)),
            result(9, 0x1018, 1, Ok(vec![1, 0, 0, 0])),
        ];
        let rows = found_nodes(&results);
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[0].node, 5);
        assert_eq!(rows[0].device_type, Ok(0x000F_0191));
        assert_eq!(rows[0].identity, [Some(0xABC), None, None, None]);
        assert_eq!(rows[1].node, 9);
        assert!(rows[1].device_type.as_ref().unwrap_err().contains("0x06020000"));
        let table = scan_table(&rows, 127, Duration::from_millis(1020));
        assert!(table.contains("   5  0x000F0191  0x00000ABC  -"), "{table}");
        assert!(
            table.ends_with("2 of 127 node-IDs answered in 1.02 s\n"),
            "{table}"
        );
        let json = rows[0].json();
        assert_eq!(json["vendor_id"], 0xABC);
        assert_eq!(json["profile"], "CiA 401 generic I/O");
        assert!(json["serial_number"].is_null());
    }

    #[test]
    fn info_text_names_every_field() {
        let report = InfoReport {
            node: 5,
            device_type: describe_device_type(0x0003_0191),
            error_register: Field::Value(0x11),
            identity: vec![
                Field::Value(0xABC),
                Field::Value(0x401),
                Field::Absent,
                Field::Failed("x".to_owned()),
            ],
            names: vec![Field::Value("sim".to_owned()), Field::Absent, Field::Absent],
            heartbeat_time: Field::Value(100),
            heartbeat: Some(HeartbeatSeen {
                waited: Duration::from_millis(150),
                state: Some((NmtState::Operational, Duration::from_millis(42))),
                invalid: None,
            }),
            eds: None,
        };
        let text = report.text();
        for needle in [
            "Device type       0x00030191  CiA 401 generic I/O: digital inputs, digital outputs",
            "Error register    0x11  generic, communication",
            "Vendor-ID         0x00000ABC  (2748)",
            "Revision number   absent",
            "Serial number     error: x",
            "Device name       \"sim\"",
            "Hardware version  not implemented",
            "Heartbeat         every 100 ms; state OPERATIONAL (heartbeat 42 ms after asking)",
        ] {
            assert!(text.contains(needle), "{needle:?} missing in:\n{text}");
        }
        let json = report.json();
        assert_eq!(json["identity"]["vendor_id"], 0xABC);
        assert!(json["identity"]["revision_number"].is_null());
        assert_eq!(json["problems"]["1018:04"], "x");
        assert_eq!(json["heartbeat"]["state"], "OPERATIONAL");
        assert_eq!(json["device_type"]["profile"], 401);
    }
}

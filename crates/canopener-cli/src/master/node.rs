//! `canopener node info|scan`: what one node is (identity, device type, error register, names,
//! heartbeat state) and which node-IDs answer, read by `canopener_link::node_info` and
//! `node_scan`; this module prints them (`node dump` is `node_dump`).

use std::fmt::Write as _;
use std::time::Duration;

use canopener_eds::Eds;
use canopener_eds::model::int_of;
use canopener_link::link::Ended;
use canopener_link::node_info::NodeInfoError;
use canopener_link::node_scan::{ScanError, scan as scan_nodes};
use canopener_link::sdo_session::SessionError;
use canopener_master::node_info::{DeviceType, Field, NodeInfo};
use canopener_master::node_scan::{ScanRow, identify};
use canopener_wire::error_register_text;
use serde_json::json;

use crate::args::OutputFormat;
use crate::error::{CliError, CliResult, exit_code};
use crate::grammar::parse_node_list;
use crate::master::args::{NodeInfoArgs, NodeScanArgs};
use crate::master::link::{checked_timeout, open_link, open_session};
use crate::master::output::{millis, print_json, session_error};
use crate::output::print_stdout;
use canopener_runtime::description::read_description;

pub(crate) fn info(args: NodeInfoArgs) -> CliResult {
    let eds = match &args.eds {
        Some(path) => Some((path.display().to_string(), read_description(path)?.eds)),
        None => None,
    };
    let node = args.target.node;
    let mut session = open_session(&args.master, node, "node info")?;
    let info = canopener_link::node_info::read(&mut session).map_err(|err| match err {
        NodeInfoError::Session(err) => session_error(node, err),
        other => CliError::Device(other.to_string()),
    })?;
    let report = InfoReport { info, eds };
    match args.master.format {
        OutputFormat::Json => print_json(&report.json()),
        OutputFormat::Text => print_stdout(&report.text()),
    }
}

pub(crate) fn scan(args: NodeScanArgs) -> CliResult {
    let mut nodes: Vec<u8> =
        parse_node_list(&args.nodes, "--nodes", "canopener node scan --nodes 1-10,20,30")?
            .into_iter()
            .map(|node| node.get())
            .collect();
    nodes.sort_unstable();
    nodes.dedup();
    let timeout = checked_timeout(args.master.timeout())?;
    let mut link = open_link(args.master.bus.spec.as_deref(), "node scan")?;
    let scanned =
        scan_nodes(&mut link, &nodes, usize::from(args.parallel), timeout).map_err(|err| match err {
            ScanError::Setup(SessionError::Client(err)) => {
                CliError::Usage(format!("{err}; e.g. --nodes 1-127"))
            }
            ScanError::Setup(SessionError::ZeroTimeout) => {
                CliError::Usage("--timeout must be longer than 0, e.g. --timeout 500ms".to_owned())
            }
            ScanError::Link(err) => err.into(),
        })?;
    match scanned.ended {
        None => {}
        Some(Ended::Deadline) => {
            eprintln!("warning: the scan ran out of time; node-IDs not answered yet are not listed");
        }
        Some(Ended::Cancelled) => {
            eprintln!("interrupted: the scan stopped before every node-ID was asked");
            return Err(CliError::Exit(exit_code::INTERRUPTED));
        }
    }
    let found = identify(&scanned.results);
    match args.master.format {
        OutputFormat::Json => print_json(&json!({
            "asked": nodes.len(),
            "answered": found.len(),
            "elapsed_ms": millis(scanned.elapsed),
            "nodes": found.iter().map(row_json).collect::<Vec<_>>(),
        })),
        OutputFormat::Text => print_stdout(&scan_table(&found, nodes.len(), scanned.elapsed)),
    }
}

/// What `node info` read, and the EDS to compare the identity with.
struct InfoReport {
    info: NodeInfo,
    eds: Option<(String, Eds)>,
}

const IDENTITY_NAMES: [&str; 4] = ["Vendor-ID", "Product code", "Revision number", "Serial number"];
const IDENTITY_KEYS: [&str; 4] = ["vendor_id", "product_code", "revision_number", "serial_number"];
const NAME_LABELS: [&str; 3] = ["Device name", "Hardware version", "Software version"];
const NAME_KEYS: [&str; 3] = ["device_name", "hardware_version", "software_version"];

impl InfoReport {
    fn text(&self) -> String {
        let mut out = String::new();
        let _ = writeln!(out, "Node {}", self.info.node);
        let kind = &self.info.device_type;
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
        let register = match &self.info.error_register {
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
        for (name, field) in IDENTITY_NAMES.iter().zip(&self.info.identity) {
            let text = match field {
                Field::Value(value) => format!("0x{value:08X}  ({value})"),
                other => field_text(other, "absent"),
            };
            line(&mut out, name, &text);
        }
        for (label, field) in NAME_LABELS.iter().zip(&self.info.names) {
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
        match (&self.info.heartbeat_time, &self.info.heartbeat) {
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
            ("VendorNumber", &self.info.identity[0]),
            ("ProductNumber", &self.info.identity[1]),
            ("RevisionNumber", &self.info.identity[2]),
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
        let kind = &self.info.device_type;
        let mut identity = serde_json::Map::new();
        let mut problems = serde_json::Map::new();
        for (sub, (key, field)) in IDENTITY_KEYS.iter().zip(&self.info.identity).enumerate() {
            identity.insert(
                (*key).to_owned(),
                field_json(field, &mut problems, &format!("1018:{:02X}", sub + 1)),
            );
        }
        let mut names = serde_json::Map::new();
        for ((key, field), index) in NAME_KEYS
            .iter()
            .zip(&self.info.names)
            .zip(["1008", "1009", "100A"])
        {
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
        let error_register = field_json(&self.info.error_register, &mut problems, "1001:00");
        let heartbeat_time = field_json(&self.info.heartbeat_time, &mut problems, "1017:00");
        let heartbeat = self.info.heartbeat.as_ref().map(|seen| {
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
            "node": self.info.node,
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
                "text": match &self.info.error_register {
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

fn row_json(row: &ScanRow) -> serde_json::Value {
    let id = |n: usize| {
        row.identity[n]
            .map(|v| json!(v))
            .unwrap_or(serde_json::Value::Null)
    };
    json!({
        "node": row.node,
        "device_type": row.device_type.as_ref().ok(),
        "device_type_error": row.device_type.as_ref().err(),
        "profile": row.device_type.as_ref().ok().map(|raw| DeviceType::describe(*raw).profile_name),
        "vendor_id": id(0),
        "product_code": id(1),
        "revision_number": id(2),
        "serial_number": id(3),
    })
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
            Ok(raw) => (format!("0x{raw:08X}"), DeviceType::describe(*raw).profile_name),
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
    use canopener_master::node_info::HeartbeatSeen;
    use canopener_master::node_scan::ScanResult;
    use canopener_master::sdo_client::SdoTransferError;
    use canopener_wire::NmtState;

    use super::*;

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
        let rows = identify(&results);
        let table = scan_table(&rows, 127, Duration::from_millis(1020));
        assert!(table.contains("   5  0x000F0191  0x00000ABC  -"), "{table}");
        assert!(
            table.ends_with("2 of 127 node-IDs answered in 1.02 s\n"),
            "{table}"
        );
        let json = row_json(&rows[0]);
        assert_eq!(json["vendor_id"], 0xABC);
        assert_eq!(json["profile"], "CiA 401 generic I/O");
        assert!(json["serial_number"].is_null());
    }

    #[test]
    fn info_text_names_every_field() {
        let report = InfoReport {
            info: NodeInfo {
                node: 5,
                device_type: DeviceType::describe(0x0003_0191),
                error_register: Field::Value(0x11),
                identity: [
                    Field::Value(0xABC),
                    Field::Value(0x401),
                    Field::Absent,
                    Field::Failed("x".to_owned()),
                ],
                names: [Field::Value("sim".to_owned()), Field::Absent, Field::Absent],
                heartbeat_time: Field::Value(100),
                heartbeat: Some(HeartbeatSeen {
                    waited: Duration::from_millis(150),
                    state: Some((NmtState::Operational, Duration::from_millis(42))),
                    invalid: None,
                }),
            },
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

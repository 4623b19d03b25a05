//! `canopener pdo watch`: a node's TPDOs received live and decoded by their mapping (CiA 301 §7.2.2
//! PDO, the communication parameters 1800h–19FFh and mapping parameters 1A00h–1BFFh, §7.5.2.37 and
//! §7.5.2.38; reference §3.1 and §3.4).
//!
//! The TPDOs watched are those the EDS describes; `canopener_link::pdo_watch` finds their
//! configuration over SDO, or with `--offline` from the EDS/DCF values, and receives them;
//! `canopener_master::pdo_watch` decodes and counts. This module prints: a frame shorter than its
//! mapping is an error line (a device receiving it as an RPDO would not process it either, reference
//! §3.6) and watching goes on.

use std::io::IsTerminal;
use std::time::Duration;

use canopener_can::{CanFrame, Instant};
use canopener_link::link::Link;
use canopener_link::pdo_watch::{DiscoverError, discover, from_eds, receive};
use canopener_link::sdo_session::SdoError;
use canopener_master::pdo_decode::DecodedField;
use canopener_master::pdo_watch::{Found, WatchedPdo, eds_lookup, tpdo_numbers, transmission_text};
use canopener_master::value::DisplayValue;
use canopener_od::DataType;
use serde_json::{Value, json};

use crate::args::OutputFormat;
use crate::error::{CliError, CliResult, exit_code};
use crate::master::args::PdoWatchArgs;
use crate::master::link::{open_link, open_session};
use crate::master::output::{count_bar, hex_bytes, millis, session_error, spread_json};
use crate::output::print_stdout;
use canopener_runtime::description::read_description;

/// The TPDOs watched without an EDS: those of the pre-defined connection set (CiA 301 §7.3.5,
/// COB-IDs 180h/280h/380h/480h + node-ID), whose configuration is read from the device.
const PREDEFINED_TPDOS: [u16; 4] = [1, 2, 3, 4];

pub(crate) fn run(args: PdoWatchArgs) -> CliResult {
    let input = args.eds.as_deref().map(read_description).transpose()?;
    let eds = input.as_ref().map(|input| &input.eds);
    let numbers = eds.map_or_else(|| PREDEFINED_TPDOS.to_vec(), tpdo_numbers);
    if let (Some(path), true) = (&args.eds, numbers.is_empty()) {
        return Err(CliError::InvalidInput(format!(
            "{} describes no TPDO (no object 1800h to 19FFh), so there is nothing to watch; give the EDS of \
             the device, e.g. canopener pdo watch --node {} --eds device.eds",
            path.display(),
            args.target.node
        )));
    }
    let node = args.target.node;
    let format = args.master.format;
    let (mut link, found) = if let (true, Some(eds), Some(path)) = (args.offline, eds, &args.eds) {
        let found = from_eds(eds, node, &numbers).map_err(|err| {
            CliError::InvalidInput(format!(
                "{}: cannot build the object dictionary: {err}",
                path.display()
            ))
        })?;
        (open_link(args.master.bus.spec.as_deref(), "pdo watch")?, found)
    } else {
        let mut session = open_session(&args.master, node, "pdo watch")?;
        let progress = count_bar(
            numbers.len() as u64,
            "{spinner} reading TPDO {pos}/{len} {wide_bar} {eta}",
        );
        let found = discover(&mut session, &numbers, |done| progress.set_position(done as u64));
        progress.finish_and_clear();
        match found {
            Ok(found) => (session.into_link(), found),
            Err(DiscoverError::Session(SdoError::Cancelled { .. })) => {
                eprintln!("interrupted while reading the TPDOs of node {node}");
                return Err(CliError::Exit(exit_code::INTERRUPTED));
            }
            Err(DiscoverError::Session(err)) => return Err(session_error(node, err)),
            Err(err) => return Err(CliError::Device(err.to_string())),
        }
    };
    let source = if args.offline { "eds" } else { "device" };
    let mut watched = Vec::new();
    for found in found {
        match found {
            Found::Watch(mut pdo) => {
                // Without an EDS the fields stay untyped: their bytes are shown in hex.
                if let Some(eds) = eds {
                    pdo.layout = pdo.layout.typed(eds_lookup(eds));
                }
                print_line(format, &layout_text(&pdo), || layout_json(&pdo, source))?;
                watched.push(pdo);
            }
            Found::Skip { number, reason } => print_line(
                format,
                &format!("TPDO{number}  skipped: {reason}"),
                || json!({"event": "skipped", "pdo": format!("TPDO{number}"), "reason": reason}),
            )?,
        }
    }
    if watched.is_empty() {
        let whose = if args.offline {
            format!("the EDS gives node {node} no valid TPDO")
        } else {
            format!("node {node} has no valid TPDO")
        };
        return Err(CliError::Device(format!(
            "{whose}, so there is nothing to watch; map one, e.g. canopener pdo map --node {node} --tpdo 1 \
             6000:01:8 --transmission-type 255 --event-timer 100ms"
        )));
    }
    if std::io::stderr().is_terminal() {
        eprintln!(
            "watching {} TPDO(s) of node {node} on {}; Ctrl-C stops",
            watched.len(),
            link.describe()
        );
    }
    receive::<_, CliError>(
        &mut link,
        &mut watched,
        args.count,
        args.duration,
        |pdo, at, elapsed, frame| {
            let (text, json) = record(pdo, at, elapsed, frame);
            print_line(format, &text, || json)
        },
    )?;
    match format {
        OutputFormat::Text => {
            let lines: String = watched
                .iter()
                .map(|pdo| format!("{}\n", summary_text(pdo)))
                .collect();
            print_stdout(&lines)
        }
        OutputFormat::Json => {
            let pdos: Vec<Value> = watched.iter().map(summary_json).collect();
            print_stdout(&format!("{}\n", json!({"event": "summary", "pdos": pdos})))
        }
    }
}

/// `TPDO1  COB-ID 00000185h  type 255 (event-driven)  24 bits: 6000:01:8 Input, 6401:01:16 Input`.
fn layout_text(pdo: &WatchedPdo) -> String {
    let kind = pdo
        .transmission_type
        .map_or_else(String::new, |t| format!("  type {t} ({})", transmission_text(t)));
    let fields: Vec<String> = pdo
        .layout
        .fields()
        .iter()
        .map(|field| match &field.name {
            Some(name) => format!("{} {name}", field.mapped),
            None => field.mapped.to_string(),
        })
        .collect();
    let mapping = if fields.is_empty() {
        "nothing mapped".to_owned()
    } else {
        format!("{} bits: {}", pdo.layout.bits(), fields.join(", "))
    };
    format!("{}  COB-ID {:08X}h{kind}  {mapping}", pdo.name(), pdo.cob_id)
}

fn layout_json(pdo: &WatchedPdo, source: &str) -> Value {
    let mapping: Vec<Value> = pdo
        .layout
        .fields()
        .iter()
        .map(|field| {
            json!({
                "index": format!("{:04X}", field.mapped.index),
                "sub": field.mapped.sub,
                "bits": field.mapped.bits,
                "offset": field.offset,
                "name": field.name,
                "type": field.data_type.map(type_name),
            })
        })
        .collect();
    json!({
        "event": "layout",
        "pdo": pdo.name(),
        "cob_id": format!("{:08X}", pdo.cob_id),
        "can_id": pdo.can_id_text(),
        "transmission_type": pdo.transmission_type,
        "source": source,
        "bits": pdo.layout.bits(),
        "mapping": mapping,
    })
}

/// Decodes one frame of this TPDO received `elapsed` after the watch began, as a text line and
/// a JSON object; counts it.
fn record(pdo: &mut WatchedPdo, at: Instant, elapsed: Duration, frame: &CanFrame) -> (String, Value) {
    let seconds = elapsed.as_secs_f64();
    let data = frame.data();
    let head = format!("{seconds:8.3} {} {}", pdo.name(), pdo.can_id_text());
    let mut json = json!({
        "time": (seconds * 1e6).round() / 1e6,
        "pdo": pdo.name(),
        "can_id": pdo.can_id_text(),
        "data": hex_bytes(data),
    });
    match pdo.receive(at, frame) {
        Ok(fields) => {
            let text = if fields.is_empty() {
                "(nothing mapped)".to_owned()
            } else {
                fields
                    .iter()
                    .map(ToString::to_string)
                    .collect::<Vec<_>>()
                    .join("  ")
            };
            json["event"] = json!("pdo");
            json["fields"] = fields.iter().map(field_json).collect();
            (format!("{head}  {text}"), json)
        }
        Err(err) => {
            json["event"] = json!("error");
            json["error"] = json!(err.to_string());
            (format!("{head}  error: {err} (data {})", hex_bytes(data)), json)
        }
    }
}

/// `TPDO1 185: 30 received, 0 malformed, period min 99.8 ms, median 100.0 ms, max 100.3 ms`.
fn summary_text(pdo: &WatchedPdo) -> String {
    let periods = match pdo.stats.periods() {
        Some(spread) => format!(
            ", period min {:.1} ms, median {:.1} ms, max {:.1} ms",
            millis(spread.min),
            millis(spread.median),
            millis(spread.max)
        ),
        None => String::new(),
    };
    format!(
        "{} {}: {} received, {} malformed{periods}",
        pdo.name(),
        pdo.can_id_text(),
        pdo.stats.received,
        pdo.stats.malformed
    )
}

fn summary_json(pdo: &WatchedPdo) -> Value {
    let periods = pdo.stats.periods().map(|spread| spread_json(&spread));
    json!({
        "pdo": pdo.name(),
        "can_id": pdo.can_id_text(),
        "received": pdo.stats.received,
        "malformed": pdo.stats.malformed,
        "period_ms": periods,
    })
}

fn print_line(format: OutputFormat, text: &str, json: impl FnOnce() -> Value) -> CliResult {
    match format {
        OutputFormat::Text => print_stdout(&format!("{text}\n")),
        OutputFormat::Json => print_stdout(&format!("{}\n", json())),
    }
}

fn field_json(field: &DecodedField) -> Value {
    json!({
        "index": format!("{:04X}", field.index),
        "sub": field.sub,
        "name": field.name,
        "type": field.data_type.map(type_name),
        "bits": field.bits,
        "raw": field.raw,
        "value": value_json(&field.value),
        "text": field.value.to_string(),
    })
}

fn value_json(value: &DisplayValue) -> Value {
    match value {
        DisplayValue::Bool(value) => json!(value),
        DisplayValue::Unsigned { value, .. } => json!(value),
        DisplayValue::Signed { value, .. } => json!(value),
        // JSON has no NaN or infinity: those become null, the text keeps them.
        DisplayValue::Real32(value) => json!(f64::from(*value)),
        DisplayValue::Real64(value) => json!(value),
        DisplayValue::Text(_) => json!(value.plain()),
        DisplayValue::Bytes(bytes) => json!(hex_bytes(bytes)),
    }
}

fn type_name(data_type: DataType) -> String {
    data_type
        .name()
        .map_or_else(|| format!("{:04X}h", data_type.0), str::to_owned)
}

/// What a TPDO transmission type means (CiA 301 §7.2.2.1, reference §3.2).
#[cfg(test)]
mod tests {
    use canopener_master::pdo_config::MappedObject;
    use canopener_master::pdo_decode::PdoLayout;

    use super::*;

    fn watched(mapping: &[MappedObject]) -> WatchedPdo {
        let path = canopener_testkit::corpus::eds("CANopenNode__CANopenNode__example__IO.eds");
        let eds = canopener_eds::load(&canopener_files::read(&path).expect("EDS")).eds;
        let layout = PdoLayout::new(mapping).expect("layout").typed(eds_lookup(&eds));
        match WatchedPdo::found(1, 0x185, Some(255), layout) {
            Found::Watch(pdo) => pdo,
            Found::Skip { reason, .. } => panic!("{reason}"),
        }
    }

    #[test]
    fn frames_decode_into_named_values_and_short_ones_are_error_lines() {
        let mut pdo = watched(&[MappedObject::new(0x6000, 1, 8), MappedObject::new(0x6401, 1, 16)]);
        let id = canopener_can::CanId::standard(0x185).expect("id");
        let frame = |data: &[u8]| CanFrame::new(id, data).expect("frame");
        let trace: Vec<(String, Value)> = [
            (12_345, frame(&[0x3C, 0xFB, 0xFF])),
            (12_445, frame(&[0x3C])),
            (12_545, frame(&[0x01, 0x10, 0x00, 0xEE])),
        ]
        .into_iter()
        .map(|(ms, frame)| {
            let at = Instant::from_millis(ms);
            record(&mut pdo, at, at.saturating_duration_since(Instant::ZERO), &frame)
        })
        .collect();
        let text: Vec<&str> = trace.iter().map(|(text, _)| text.as_str()).collect();
        assert_eq!(
            text,
            [
                "  12.345 TPDO1 185  6000:01 Read input 8 bit = 60 (0x3C)  6401:01 Read analogue input 16 bit = -5 \
                 (0xFFFB)",
                "  12.445 TPDO1 185  error: the frame has 1 byte(s) but the mapping needs 3 (24 bits); a device \
                 receiving it as an RPDO would not process it (EMCY 8210h) (data 3C)",
                "  12.545 TPDO1 185  6000:01 Read input 8 bit = 1 (0x01)  6401:01 Read analogue input 16 bit = 16 \
                 (0x0010)",
            ]
        );
        let first = &trace[0].1;
        assert_eq!(first["event"], "pdo");
        assert_eq!(first["time"], 12.345);
        assert_eq!(first["data"], "3C FB FF");
        assert_eq!(first["fields"][0]["value"], 60);
        assert_eq!(first["fields"][0]["type"], "UNSIGNED8");
        assert_eq!(first["fields"][1]["value"], -5);
        assert_eq!(first["fields"][1]["raw"], 0xFFFB);
        assert_eq!(first["fields"][1]["name"], "Read analogue input 16 bit");
        assert_eq!(trace[1].1["event"], "error");
        assert_eq!(
            summary_text(&pdo),
            "TPDO1 185: 3 received, 1 malformed, period min 100.0 ms, median 100.0 ms, max 100.0 ms"
        );
        assert_eq!(summary_json(&pdo)["period_ms"]["median"], 100.0);
        assert_eq!(
            layout_text(&pdo),
            "TPDO1  COB-ID 00000185h  type 255 (event-driven)  24 bits: 6000:01:8 Read input 8 bit, 6401:01:16 \
             Read analogue input 16 bit"
        );
        assert_eq!(layout_json(&pdo, "eds")["source"], "eds");
    }
}

//! `canopener pdo watch`: a node's TPDOs received live and decoded by their mapping (CiA 301 §7.2.2
//! PDO, the communication parameters 1800h–19FFh and mapping parameters 1A00h–1BFFh, §7.5.2.37 and
//! §7.5.2.38; reference §3.1 and §3.4).
//!
//! The TPDOs watched are those the EDS describes. Their COB-ID (comm sub 1), transmission type
//! (sub 2) and mapping (sub 0 and the entries) come from the device over SDO, or with `--offline`
//! from the EDS/DCF values with `$NODEID` resolved; the EDS names and types the mapped objects. A
//! TPDO whose COB-ID has bit 31 set does not exist on the bus and is skipped, as is one whose
//! mapping cannot be decoded (an MPDO, more than 64 bits).
//!
//! Frames are untrusted: one shorter than its mapping is reported as an error line (a device
//! receiving it as an RPDO would not process it either, reference §3.6) and watching goes on.

use std::io::IsTerminal;
use std::time::Duration;

use canopener_can::{CanFrame, CanId, Instant};
use canopener_device::od_build::build_od;
use canopener_eds::{Eds, ObjectType};
use canopener_master::pdo_config::{COB_ID_EXTENDED, COB_ID_INVALID, Direction, MAX_MAPPED_OBJECTS};
use canopener_master::pdo_decode::{DecodedField, PdoLayout};
use canopener_master::sdo_client::SdoTransferError;
use canopener_master::value::DisplayValue;
use canopener_od::{DataType, DynamicOd, ObjectKey};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde_json::{Value, json};

use crate::args::OutputFormat;
use crate::eds::input::{print_stdout, read_input};
use crate::error::{CliError, CliResult};
use crate::master::args::PdoWatchArgs;
use canopener_runtime::link::{BusLink, Link};

use crate::master::link::open_link;
use crate::master::pdo::{INTERRUPTED_EXIT, LinkSdo, SdoAccess, Transfer, hex_value, object_name};

/// How long one wait for a frame lasts when neither --duration nor Ctrl-C ends it sooner.
const RECV_SLICE: Duration = Duration::from_secs(1);

pub(crate) fn run(args: PdoWatchArgs) -> CliResult {
    let input = read_input(&args.eds)?;
    let eds = &input.eds;
    let numbers = tpdo_numbers(eds);
    if numbers.is_empty() {
        return Err(CliError::InvalidInput(format!(
            "{} describes no TPDO (no object 1800h to 19FFh), so there is nothing to watch; give the EDS of \
             the device, e.g. canopener pdo watch --node {} --eds device.eds",
            args.eds.display(),
            args.target.node
        )));
    }
    let node = args.target.node;
    let format = args.master.format;
    let (mut link, found) = if args.offline {
        let built = build_od(eds, node).map_err(|err| {
            CliError::InvalidInput(format!(
                "{}: cannot build the object dictionary: {err}",
                args.eds.display()
            ))
        })?;
        let found = numbers.iter().map(|&n| from_od(&built.od, n)).collect();
        (open_link(args.master.bus.spec.as_deref(), "pdo watch")?, found)
    } else {
        let link = open_link(args.master.bus.spec.as_deref(), "pdo watch")?;
        let mut sdo = LinkSdo::new(link, node, args.master.timeout)?;
        let progress = progress_bar(numbers.len());
        let found = discover(&mut sdo, node, &numbers, |done| {
            progress.set_position(done as u64)
        });
        progress.finish_and_clear();
        match found? {
            Some(found) => (sdo.into_link(), found),
            None => {
                eprintln!("interrupted while reading the TPDOs of node {node}");
                return Err(CliError::Exit(INTERRUPTED_EXIT));
            }
        }
    };
    let source = if args.offline { "eds" } else { "device" };
    let mut watched = Vec::new();
    for found in found {
        match found {
            Found::Watch(mut pdo) => {
                pdo.layout = pdo.layout.typed(eds_lookup(eds));
                print_line(format, &pdo.layout_text(), || pdo.layout_json(source))?;
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
             6000:01:8 --type 255 --event-timer 100"
        )));
    }
    if std::io::stderr().is_terminal() {
        eprintln!(
            "watching {} TPDO(s) of node {node} on {}; Ctrl-C stops",
            watched.len(),
            link.describe()
        );
    }
    receive(&mut link, &mut watched, &args, format)?;
    match format {
        OutputFormat::Text => {
            let lines: String = watched
                .iter()
                .map(|pdo| format!("{}\n", pdo.summary_text()))
                .collect();
            print_stdout(&lines)
        }
        OutputFormat::Json => {
            let pdos: Vec<Value> = watched.iter().map(WatchedPdo::summary_json).collect();
            print_stdout(&format!("{}\n", json!({"event": "summary", "pdos": pdos})))
        }
    }
}

/// The TPDOs the EDS describes by their communication parameter, 1 to 512.
fn tpdo_numbers(eds: &Eds) -> Vec<u16> {
    let base = Direction::Tpdo.comm_base();
    (1..=512u16)
        .filter(|number| eds.object(base + number - 1).is_some())
        .collect()
}

/// A TPDO to watch, or why it is not watched.
#[derive(Debug)]
enum Found {
    Watch(WatchedPdo),
    Skip { number: u16, reason: String },
}

/// One TPDO being watched: where it arrives, how to decode it, what arrived so far.
#[derive(Debug)]
struct WatchedPdo {
    number: u16,
    cob_id: u32,
    can_id: CanId,
    transmission_type: Option<u8>,
    layout: PdoLayout,
    stats: Stats,
}

/// A TPDO whose COB-ID has bit 31 set: it does not exist on the bus (CiA 301 §7.5.2.37).
fn invalid(number: u16, cob_id: u32) -> Option<Found> {
    (cob_id & COB_ID_INVALID != 0).then(|| Found::Skip {
        number,
        reason: format!("not valid (COB-ID {cob_id:08X}h has bit 31 set)"),
    })
}

impl WatchedPdo {
    /// The TPDO with a valid COB-ID `cob_id`, or why it cannot be watched.
    fn found(number: u16, cob_id: u32, transmission_type: Option<u8>, layout: PdoLayout) -> Found {
        let can_id = if cob_id & COB_ID_EXTENDED != 0 {
            CanId::extended(cob_id & 0x1FFF_FFFF)
        } else {
            // Bits 28..11 of an 11-bit COB-ID should be 0; the device sends on the low 11 bits.
            CanId::standard((cob_id & 0x7FF) as u16)
        };
        match can_id {
            Ok(can_id) => Found::Watch(WatchedPdo {
                number,
                cob_id,
                can_id,
                transmission_type,
                layout,
                stats: Stats::default(),
            }),
            Err(err) => Found::Skip {
                number,
                reason: format!("COB-ID {cob_id:08X}h gives no CAN-ID: {err}"),
            },
        }
    }

    fn name(&self) -> String {
        format!("TPDO{}", self.number)
    }

    fn can_id_text(&self) -> String {
        match self.can_id {
            CanId::Standard(_) => format!("{:03X}", self.can_id.as_raw()),
            CanId::Extended(_) => format!("{:08X}", self.can_id.as_raw()),
        }
    }

    /// `TPDO1  COB-ID 00000185h  type 255 (event-driven)  24 bits: 6000:01:8 Input, 6401:01:16 Input`.
    fn layout_text(&self) -> String {
        let kind = self
            .transmission_type
            .map_or_else(String::new, |t| format!("  type {t} ({})", transmission_text(t)));
        let fields: Vec<String> = self
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
            format!("{} bits: {}", self.layout.bits(), fields.join(", "))
        };
        format!("{}  COB-ID {:08X}h{kind}  {mapping}", self.name(), self.cob_id)
    }

    fn layout_json(&self, source: &str) -> Value {
        let mapping: Vec<Value> = self
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
            "pdo": self.name(),
            "cob_id": format!("{:08X}", self.cob_id),
            "can_id": self.can_id_text(),
            "transmission_type": self.transmission_type,
            "source": source,
            "bits": self.layout.bits(),
            "mapping": mapping,
        })
    }

    /// Decodes one frame of this TPDO received `elapsed` after the watch began, as a text line and
    /// a JSON object; counts it.
    fn record(&mut self, at: Instant, elapsed: Duration, frame: &CanFrame) -> (String, Value) {
        let seconds = elapsed.as_secs_f64();
        let data = frame.data();
        let head = format!("{seconds:8.3} {} {}", self.name(), self.can_id_text());
        let mut json = json!({
            "time": (seconds * 1e6).round() / 1e6,
            "pdo": self.name(),
            "can_id": self.can_id_text(),
            "data": hex_bytes(data),
        });
        let decoded = self.layout.decode(data);
        self.stats.record(at, decoded.is_ok());
        match decoded {
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
    fn summary_text(&self) -> String {
        let periods = match self.stats.periods() {
            Some([min, median, max]) => format!(
                ", period min {:.1} ms, median {:.1} ms, max {:.1} ms",
                millis(min),
                millis(median),
                millis(max)
            ),
            None => String::new(),
        };
        format!(
            "{} {}: {} received, {} malformed{periods}",
            self.name(),
            self.can_id_text(),
            self.stats.received,
            self.stats.malformed
        )
    }

    fn summary_json(&self) -> Value {
        let periods = self.stats.periods().map(
            |[min, median, max]| json!({"min": millis(min), "median": millis(median), "max": millis(max)}),
        );
        json!({
            "pdo": self.name(),
            "can_id": self.can_id_text(),
            "received": self.stats.received,
            "malformed": self.stats.malformed,
            "period_ms": periods,
        })
    }
}

/// Arrivals of one TPDO.
#[derive(Debug, Default)]
struct Stats {
    received: u64,
    malformed: u64,
    last: Option<Instant>,
    /// Time between arrivals in µs; 4 bytes per frame keeps an hour at 1 kHz within 15 MB.
    periods_us: Vec<u32>,
}

impl Stats {
    fn record(&mut self, at: Instant, decoded: bool) {
        self.received += 1;
        if !decoded {
            self.malformed += 1;
        }
        if let Some(last) = self.last {
            let micros = at.saturating_duration_since(last).as_micros();
            self.periods_us.push(u32::try_from(micros).unwrap_or(u32::MAX));
        }
        self.last = Some(at);
    }

    /// The shortest, median (the upper one of an even count) and longest time between arrivals.
    fn periods(&self) -> Option<[Duration; 3]> {
        let mut sorted = self.periods_us.clone();
        sorted.sort_unstable();
        let micros = |value: Option<&u32>| value.map(|&us| Duration::from_micros(u64::from(us)));
        Some([
            micros(sorted.first())?,
            micros(sorted.get(sorted.len() / 2))?,
            micros(sorted.last())?,
        ])
    }
}

/// Reads the TPDOs `numbers` from node `node` over SDO; `None` after Ctrl-C.
///
/// An abort from the device skips that TPDO (the EDS may describe more than the device has); a
/// timeout or a broken answer ends the command, since the next reads would fare no better.
fn discover(
    sdo: &mut impl SdoAccess,
    node: u8,
    numbers: &[u16],
    mut on_progress: impl FnMut(usize),
) -> CliResult<Option<Vec<Found>>> {
    let mut found = Vec::with_capacity(numbers.len());
    for (done, &number) in numbers.iter().enumerate() {
        on_progress(done);
        let Some(pdo) = discover_one(sdo, node, number)? else {
            return Ok(None);
        };
        found.push(pdo);
    }
    on_progress(numbers.len());
    Ok(Some(found))
}

fn discover_one(sdo: &mut impl SdoAccess, node: u8, number: u16) -> CliResult<Option<Found>> {
    let comm = Direction::Tpdo.comm_base() + number - 1;
    let mapping = Direction::Tpdo.mapping_base() + number - 1;
    let skip = |reason: String| Ok(Some(Found::Skip { number, reason }));
    let cob_id = match read(sdo, node, number, comm, 1, "the COB-ID")? {
        Read::Value(data) => match <[u8; 4]>::try_from(data.as_slice()) {
            Ok(bytes) => u32::from_le_bytes(bytes),
            Err(_) => {
                return skip(format!(
                    "COB-ID {} holds {} byte(s) ({}h), not an UNSIGNED32",
                    object_name(comm, 1),
                    data.len(),
                    hex_value(&data)
                ));
            }
        },
        Read::Refused(reason) => return skip(reason),
        Read::Interrupted => return Ok(None),
    };
    if let Some(skip) = invalid(number, cob_id) {
        return Ok(Some(skip));
    }
    let transmission_type = match read(sdo, node, number, comm, 2, "the transmission type")? {
        Read::Value(data) => match data.as_slice() {
            [value] => Some(*value),
            _ => None,
        },
        Read::Refused(_) => None,
        Read::Interrupted => return Ok(None),
    };
    let mut values = std::collections::BTreeMap::new();
    let count = match read(sdo, node, number, mapping, 0, "the number of mapped objects")? {
        Read::Value(data) => {
            let count = data.first().copied();
            values.insert(0u8, data);
            count.unwrap_or(0)
        }
        Read::Refused(reason) => return skip(reason),
        Read::Interrupted => return Ok(None),
    };
    // More than 64 entries (or an MPDO's FEh/FFh) is refused below without reading them.
    let entries = if usize::from(count) <= MAX_MAPPED_OBJECTS {
        count
    } else {
        0
    };
    for sub in 1..=entries {
        match read(sdo, node, number, mapping, sub, "a mapping entry")? {
            Read::Value(data) => {
                values.insert(sub, data);
            }
            Read::Refused(reason) => return skip(reason),
            Read::Interrupted => return Ok(None),
        }
    }
    match PdoLayout::from_od_values(|sub| values.get(&sub).cloned()) {
        Ok(layout) => Ok(Some(WatchedPdo::found(number, cob_id, transmission_type, layout))),
        Err(err) => skip(format!("mapping {mapping:04X}h: {err}")),
    }
}

/// The value of one read, or why the device refused it.
enum Read {
    Value(Vec<u8>),
    Refused(String),
    Interrupted,
}

/// Reads `what` of TPDO `number`, `index`:`sub`.
fn read(sdo: &mut impl SdoAccess, node: u8, number: u16, index: u16, sub: u8, what: &str) -> CliResult<Read> {
    let object = object_name(index, sub);
    match sdo.upload(index, sub)? {
        Transfer::Done(data) => Ok(Read::Value(data)),
        Transfer::Failed(error @ SdoTransferError::AbortedByServer { .. }) => {
            Ok(Read::Refused(format!("reading {object}: {error}")))
        }
        Transfer::Failed(error) => Err(CliError::Device(format!(
            "node {node}, reading {what} of TPDO{number} ({object}): {error}"
        ))),
        Transfer::Interrupted => Ok(Read::Interrupted),
    }
}

/// A TPDO from a dictionary built from the EDS/DCF (`--offline`).
fn from_od(od: &DynamicOd, number: u16) -> Found {
    let comm = Direction::Tpdo.comm_base() + number - 1;
    let mapping = Direction::Tpdo.mapping_base() + number - 1;
    let value = |index: u16, sub: u8| {
        od.get(ObjectKey::new(index, sub))
            .map(|entry| entry.value().to_vec())
    };
    let Some(cob_id) = value(comm, 1)
        .and_then(|data| <[u8; 4]>::try_from(data.as_slice()).ok())
        .map(u32::from_le_bytes)
    else {
        return Found::Skip {
            number,
            reason: format!("the EDS has no UNSIGNED32 COB-ID {}", object_name(comm, 1)),
        };
    };
    if let Some(skip) = invalid(number, cob_id) {
        return skip;
    }
    let transmission_type = value(comm, 2).and_then(|data| data.first().copied());
    match PdoLayout::from_od(od, mapping) {
        Ok(layout) => WatchedPdo::found(number, cob_id, transmission_type, layout),
        Err(err) => Found::Skip {
            number,
            reason: format!("mapping {mapping:04X}h in the EDS: {err}"),
        },
    }
}

/// Names and types a mapped object by the EDS: a VAR or an ARRAY element by the object's name
/// (the sub-index tells elements apart), a RECORD member by the object's and the member's name.
fn eds_lookup(eds: &Eds) -> impl FnMut(u16, u8) -> Option<(String, DataType)> + '_ {
    move |index, sub| {
        let object = eds.object(index)?;
        let (attributes, name) = if object.subs.is_empty() {
            if sub != 0 {
                return None;
            }
            (&object.attributes, object.name().trim().to_owned())
        } else {
            let member = object.subs.get(&sub)?;
            let member_name = member.attributes.parameter_name.as_deref().unwrap_or("").trim();
            let object_name = object.name().trim();
            let name = match object.object_type() {
                Some(ObjectType::Record) if !member_name.is_empty() => {
                    format!("{object_name}: {member_name}")
                }
                _ if object_name.is_empty() => member_name.to_owned(),
                _ => object_name.to_owned(),
            };
            (&member.attributes, name)
        };
        Some((name, eds.resolve_data_type(attributes.data_type()?)))
    }
}

/// Receives until --count, --duration or Ctrl-C, printing every frame of a watched TPDO.
fn receive(
    link: &mut BusLink,
    watched: &mut [WatchedPdo],
    args: &PdoWatchArgs,
    format: OutputFormat,
) -> CliResult {
    let started = link.now();
    let end = args.duration.map(|duration| started + duration);
    let mut received = 0u64;
    while args.count.is_none_or(|count| received < count) {
        let until = end.unwrap_or_else(|| link.now() + RECV_SLICE);
        let Some((at, frame)) = link.recv_until(until)? else {
            if link.is_cancelled() || end.is_some_and(|end| link.now() >= end) {
                break;
            }
            continue;
        };
        // A remote frame on a TPDO's CAN-ID asks for it; it carries no data to decode.
        if frame.is_remote() {
            continue;
        }
        let Some(pdo) = watched.iter_mut().find(|pdo| pdo.can_id == frame.id()) else {
            continue;
        };
        received += 1;
        let (text, json) = pdo.record(at, at.saturating_duration_since(started), &frame);
        print_line(format, &text, || json)?;
    }
    Ok(())
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
fn transmission_text(value: u8) -> &'static str {
    match value {
        0 => "at the SYNC after an event",
        1 => "every SYNC",
        2..=240 => "every n-th SYNC",
        252 => "on RTR, sampled at SYNC",
        253 => "on RTR",
        254 | 255 => "event-driven",
        _ => "reserved",
    }
}

fn hex_bytes(data: &[u8]) -> String {
    data.iter()
        .map(|byte| format!("{byte:02X}"))
        .collect::<Vec<_>>()
        .join(" ")
}

fn millis(duration: Duration) -> f64 {
    (duration.as_secs_f64() * 1e4).round() / 10.0
}

fn progress_bar(len: usize) -> ProgressBar {
    if len < 2 || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(len as u64), ProgressDrawTarget::stderr());
    if let Ok(style) = ProgressStyle::with_template("{spinner} reading TPDO {pos}/{len} {wide_bar} {eta}") {
        bar.set_style(style);
    }
    bar
}

#[cfg(test)]
mod tests {
    use canopener_master::pdo_config::MappedObject;

    use super::*;
    use crate::master::pdo::testing::{BASE_EDS, Behaviour, IO_EDS, VirtualNode, eds};

    /// The layout lines `pdo watch` prints for what was found, typed by `eds`.
    fn layouts(found: Vec<Found>, eds: &Eds) -> Vec<String> {
        found
            .into_iter()
            .map(|found| match found {
                Found::Watch(mut pdo) => {
                    pdo.layout = pdo.layout.typed(eds_lookup(eds));
                    pdo.layout_text()
                }
                Found::Skip { number, reason } => format!("TPDO{number}  skipped: {reason}"),
            })
            .collect()
    }

    fn write(node: &mut VirtualNode, index: u16, sub: u8, data: &[u8]) {
        assert!(matches!(
            node.download(index, sub, data.to_vec()).expect("no bus error"),
            Transfer::Done(())
        ));
    }

    #[test]
    fn discovers_the_tpdos_the_eds_describes_from_the_device() {
        let eds = eds(&IO_EDS);
        let mut node = VirtualNode::new(&IO_EDS, Behaviour::Normal);
        // TPDO2: 6401h:01 and :02 on every SYNC; TPDO3 invalid.
        write(&mut node, 0x1801, 1, &0x8000_0285u32.to_le_bytes());
        write(&mut node, 0x1A01, 1, &0x6401_0110u32.to_le_bytes());
        write(&mut node, 0x1A01, 2, &0x6401_0210u32.to_le_bytes());
        write(&mut node, 0x1A01, 0, &[2]);
        write(&mut node, 0x1801, 2, &[1]);
        write(&mut node, 0x1801, 1, &0x285u32.to_le_bytes());
        write(&mut node, 0x1802, 1, &0x8000_0385u32.to_le_bytes());
        let mut progress = Vec::new();
        let found = discover(&mut node, 5, &tpdo_numbers(&eds), |done| progress.push(done))
            .expect("no bus error")
            .expect("not interrupted");
        assert_eq!(
            layouts(found, &eds),
            [
                "TPDO1  COB-ID 00000185h  type 255 (event-driven)  16 bits: 6000:01:8 Read input 8 bit, 6000:02:8 \
                 Read input 8 bit",
                "TPDO2  COB-ID 00000285h  type 1 (every SYNC)  32 bits: 6401:01:16 Read analogue input 16 bit, \
                 6401:02:16 Read analogue input 16 bit",
                "TPDO3  skipped: not valid (COB-ID 80000385h has bit 31 set)",
                "TPDO4  COB-ID 00000485h  type 254 (event-driven)  nothing mapped",
            ]
        );
        assert_eq!(progress, [0, 1, 2, 3, 4]);
    }

    #[test]
    fn offline_layouts_are_the_eds_values_and_match_a_fresh_device() {
        let io = eds(&IO_EDS);
        let built = build_od(&io, 5).expect("od");
        let numbers = tpdo_numbers(&io);
        assert_eq!(numbers, [1, 2, 3, 4]);
        let offline: Vec<Found> = numbers.iter().map(|&n| from_od(&built.od, n)).collect();
        let mut node = VirtualNode::new(&IO_EDS, Behaviour::Normal);
        let online = discover(&mut node, 5, &numbers, |_| {}).unwrap().unwrap();
        let offline = layouts(offline, &io);
        assert_eq!(offline, layouts(online, &io));
        assert_eq!(
            offline[0],
            "TPDO1  COB-ID 00000185h  type 255 (event-driven)  16 bits: 6000:01:8 Read input 8 bit, 6000:02:8 Read \
             input 8 bit"
        );
        // base.eds has TPDO1 only; $NODEID is resolved with the node-ID given.
        let base = eds(BASE_EDS);
        let built = build_od(&base, 0x22).expect("od");
        assert_eq!(
            layouts(vec![from_od(&built.od, 1)], &base),
            ["TPDO1  COB-ID 000001A2h  type 255 (event-driven)  8 bits: 6000:01:8 Read input 8-bit"]
        );
        assert!(matches!(from_od(&built.od, 2), Found::Skip { number: 2, .. }));
    }

    #[test]
    fn a_silent_device_ends_the_discovery_naming_the_object_and_the_wait() {
        let mut node = VirtualNode::new(&IO_EDS, Behaviour::SilentAfter(0));
        let err = discover(&mut node, 5, &[1, 2], |_| {}).expect_err("silent");
        assert_eq!(err.exit_code(), 7);
        assert_eq!(
            err.to_string(),
            "node 5, reading the COB-ID of TPDO1 (1800h:01): timed out after 1s waiting for the initiate upload response \
             (abort 0x05040000 sent to the server)"
        );
    }

    #[test]
    fn a_tpdo_the_device_lacks_is_skipped_with_the_abort() {
        // The EDS of a bigger device than the one answering.
        let mut node = VirtualNode::new(BASE_EDS, Behaviour::Normal);
        let found = discover(&mut node, 5, &[1, 2], |_| {}).unwrap().unwrap();
        assert_eq!(
            layouts(found, &eds(BASE_EDS)),
            [
                "TPDO1  COB-ID 00000185h  type 255 (event-driven)  8 bits: 6000:01:8 Read input 8-bit",
                "TPDO2  skipped: reading 1801h:01: SDO abort 0x06020000 from the server: Object does not exist in \
                 the object dictionary",
            ]
        );
    }

    fn watched(mapping: &[MappedObject]) -> WatchedPdo {
        let layout = PdoLayout::new(mapping)
            .expect("layout")
            .typed(eds_lookup(&eds(&IO_EDS)));
        match WatchedPdo::found(1, 0x185, Some(255), layout) {
            Found::Watch(pdo) => pdo,
            Found::Skip { reason, .. } => panic!("{reason}"),
        }
    }

    #[test]
    fn frames_decode_into_named_values_and_short_ones_are_error_lines() {
        let mut pdo = watched(&[MappedObject::new(0x6000, 1, 8), MappedObject::new(0x6401, 1, 16)]);
        let frame = |data: &[u8]| CanFrame::new(pdo_id(), data).expect("frame");
        let trace: Vec<(String, Value)> = [
            (12_345, frame(&[0x3C, 0xFB, 0xFF])),
            (12_445, frame(&[0x3C])),
            (12_545, frame(&[0x01, 0x10, 0x00, 0xEE])),
        ]
        .into_iter()
        .map(|(ms, frame)| {
            let at = Instant::from_millis(ms);
            pdo.record(at, at.saturating_duration_since(Instant::ZERO), &frame)
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
            pdo.summary_text(),
            "TPDO1 185: 3 received, 1 malformed, period min 100.0 ms, median 100.0 ms, max 100.0 ms"
        );
        assert_eq!(pdo.summary_json()["period_ms"]["median"], 100.0);
    }

    fn pdo_id() -> CanId {
        CanId::standard(0x185).expect("id")
    }

    #[test]
    fn periods_are_min_upper_median_and_max() {
        let mut stats = Stats::default();
        assert_eq!(stats.periods(), None);
        for ms in [0, 10, 30, 31, 131] {
            stats.record(Instant::from_millis(ms), true);
        }
        let ms = Duration::from_millis;
        assert_eq!(stats.periods(), Some([ms(1), ms(20), ms(100)]));
        assert_eq!((stats.received, stats.malformed), (5, 0));
    }

    #[test]
    fn cob_ids_give_standard_or_extended_can_ids() {
        let layout = || PdoLayout::new(&[]).expect("empty layout");
        let can_id = |cob_id: u32| match WatchedPdo::found(1, cob_id, None, layout()) {
            Found::Watch(pdo) => pdo.can_id_text(),
            Found::Skip { reason, .. } => reason,
        };
        assert_eq!(can_id(0x4000_0185), "185");
        assert_eq!(can_id(0x2012_3456), "00123456");
        assert!(matches!(
            invalid(3, 0x8000_0385),
            Some(Found::Skip { number: 3, .. })
        ));
        assert!(invalid(3, 0x385).is_none());
    }

    #[test]
    fn records_are_named_with_their_members_and_arrays_by_their_object() {
        let eds = eds(&IO_EDS);
        let mut lookup = eds_lookup(&eds);
        assert_eq!(
            lookup(0x1018, 1),
            Some(("Identity: Vendor-ID".to_owned(), DataType::UNSIGNED32))
        );
        assert_eq!(
            lookup(0x6401, 3),
            Some(("Read analogue input 16 bit".to_owned(), DataType::INTEGER16))
        );
        assert_eq!(lookup(0x6401, 0x40), None);
        assert_eq!(lookup(0x5FFF, 0), None);
        assert_eq!(transmission_text(0), "at the SYNC after an event");
        assert_eq!(transmission_text(245), "reserved");
    }
}

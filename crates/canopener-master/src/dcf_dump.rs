//! A node's dictionary as a DCF: which entries of an EDS to read from the device, and the values read
//! written into the EDS as a DCF (CiA 306 §5): the EDS's own text, edited line by line by the lossless writer, with
//! `ParameterValue` set to what the device holds, `[DeviceComissioning]` naming the node, and
//! `[FileInfo]` saying when and from what the DCF was made.
//!
//! Which entries are read: every VAR and every sub-object whose AccessType is ro, rw, rwr, rww or const
//! (a DOMAIN without AccessType counts as rw, as CiA 306 §4.6.3.2 says). Write-only entries, type
//! definitions (DEFTYPE, DEFSTRUCT) and entries generated from CompactPDO or the sub-index 0 of a
//! CompactSubObj (which have no section to hold a value) are skipped and counted. An abort is not a
//! failure of the dump: the entry gets a `;` comment naming the abort instead of a value.
//!
//! How values are written (CiA 306 §4.2 notations, chosen so that the file loads without new P-series
//! findings):
//! - integers in hexadecimal (`0x1F4`), negative signed ones in decimal (`-5`), BOOLEAN as 0 or 1;
//! - REAL32/REAL64 as decimals (`1.5`; the shortest text that reads back to the same bits), which
//!   python canopen and CANopenEditor read, unless the entry's DefaultValue is an IEEE 754 bit pattern
//!   (`0x3FC00000`, lely's notation): then as a bit pattern too, so the file keeps one notation;
//! - VISIBLE_STRING as it is, without the trailing NULs of a fixed-size buffer; text with control
//!   characters cannot be written on one line and gets a comment with its bytes instead;
//! - OCTET_STRING and DOMAIN (read by block upload where the device offers it) as hex digits (`01A2FF`); a DOMAIN too long for the 255 characters of a
//!   CiA 306 line goes to a file next to the DCF named by `UploadFile` (§5.3.2), or, when the DCF goes
//!   to stdout, to a comment saying how to read it with `canopener sdo upload`;
//! - TIME_OF_DAY and TIME_DIFFERENCE as their 48-bit value in hexadecimal.

use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

use canopener_eds::model::{Attributes, Eds, Origin, Properties};
use canopener_eds::section_name::{SectionKind, classify};
use canopener_eds::syntax::Document;
use canopener_eds::{AccessType, DataType, ObjectType, TypeKind};

use crate::sdo_client::SdoTransferError;
use crate::value::entry_label;
use crate::value_typing::without_trailing_zeros;

/// The longest value that fits a CiA 306 line (255 characters) after `ParameterValue=`.
pub const MAX_VALUE_CHARS: usize = 255 - "ParameterValue=".len();

/// `1018h:01 (Vendor-ID)`, or `1018h:01` without a name.
pub fn entry_name(index: u16, sub: u8, name: &str) -> String {
    if name.is_empty() {
        entry_label(index, sub)
    } else {
        format!("{} ({name})", entry_label(index, sub))
    }
}

/// What [`build_dcf`] needs besides the EDS and the readings.
#[derive(Debug, Clone, Copy)]
pub struct DcfOptions<'a> {
    /// The node read.
    pub node: u8,
    /// `Baudrate` of `[DeviceComissioning]` in kbit/s, if known.
    pub bitrate: Option<u16>,
    /// The EDS file the plan came from.
    pub eds_path: &'a Path,
    /// Where the DCF goes; `None` for a stream (long DOMAINs then get a comment instead of a file).
    pub output: Option<&'a Path>,
    /// The modification time the DCF states (UTC).
    pub now: SystemTime,
}

/// A DCF made from readings: its bytes, the files beside it, and what became of every entry.
#[derive(Debug, Clone)]
pub struct Dcf {
    /// The DCF in the EDS's encoding and line endings.
    pub bytes: Vec<u8>,
    /// DOMAIN values too long for a line, to be written beside the DCF (`UploadFile`).
    pub sidecars: Vec<(PathBuf, Vec<u8>)>,
    /// Counts and reasons.
    pub summary: DumpTally,
}

/// The DCF text could not be encoded (a value the EDS's encoding cannot hold).
#[derive(Debug, Clone, thiserror::Error)]
#[error("encoding the DCF: {0}")]
pub struct DcfEncodeError(String);

/// Writes `readings` of the entries `plan` into `eds` (with its lossless `document`, if it was read
/// from text) as the DCF of `options.node` (see the module docs for the notations).
pub fn build_dcf(
    eds: &Eds,
    document: Option<&Document>,
    plan: &[Planned],
    readings: &[Reading],
    options: DcfOptions<'_>,
) -> Result<Dcf, DcfEncodeError> {
    let node = options.node;
    let out_name = options
        .output
        .and_then(Path::file_name)
        .map(|name| name.to_string_lossy().into_owned());
    let mut sidecars: Vec<(PathBuf, Vec<u8>)> = Vec::new();
    let mut dcf = eds.clone();
    clear_values(&mut dcf);
    let mut comments: Vec<(SectionKind, String)> = Vec::new();
    let mut summary = DumpTally::default();
    for (entry, reading) in plan.iter().zip(readings) {
        match reading {
            Reading::Skipped => {
                summary
                    .skipped
                    .push((entry.label(), entry.skip.unwrap_or("not read").to_owned()));
            }
            Reading::Value(data) => match dcf_value(entry.data_type, data, entry.real_bits) {
                Ok(DcfValue::Text(text)) => {
                    set_value(&mut dcf, entry, text);
                    summary.read += 1;
                }
                Ok(DcfValue::LongDomain(bytes)) => match options.output {
                    Some(out) => {
                        let file = sidecar_path(out, entry.index, entry.sub);
                        let name = file
                            .file_name()
                            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
                        if let Some(attributes) = attributes_mut(&mut dcf, entry) {
                            attributes.upload_file = Some(name);
                        }
                        sidecars.push((file, bytes));
                        summary.read += 1;
                    }
                    None => {
                        comments.push((
                            entry.section(),
                            format!(
                                "{} bytes read, too long for one line; `canopener sdo upload --node {node} {:04X} {:X} -o FILE` saves them",
                                bytes.len(),
                                entry.index,
                                entry.sub
                            ),
                        ));
                        summary
                            .not_representable
                            .push((entry.label(), format!("{} bytes of DOMAIN", bytes.len())));
                    }
                },
                Err(why) => {
                    comments.push((entry.section(), format!("{}: {why}", entry.label())));
                    summary.not_representable.push((entry.label(), why));
                }
            },
            Reading::Failed(err) => {
                comments.push((entry.section(), format!("{} not read: {err}", entry.label())));
                summary
                    .aborted
                    .push((entry.label(), err.abort_code(), err.to_string()));
            }
        }
    }
    let node_name = node_name(readings, plan, eds, node);
    commission(&mut dcf, node, &node_name, options.bitrate, readings, plan);
    describe_file(&mut dcf, eds, options.eds_path, out_name, node, options.now);

    let document = match document {
        Some(document) => canopener_eds::write::write_lossless(document, &dcf),
        None => Document::parse(canopener_eds::write::to_canonical(&dcf, None).as_bytes()).0,
    };
    let header = format!(
        "DCF of node {node} made by canopener node dump from {}: {} entries read, {} aborted, {} skipped, {} without a CiA 306 notation",
        options
            .eds_path
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
        summary.read,
        summary.aborted.len(),
        summary.skipped.len(),
        summary.not_representable.len()
    );
    let document = add_comments(&document, &header, &comments);
    let bytes = document
        .to_bytes()
        .map_err(|err| DcfEncodeError(err.to_string()))?;
    Ok(Dcf {
        bytes,
        sidecars,
        summary,
    })
}

/// One entry of the EDS and what the dump does with it.
#[derive(Debug, Clone)]
pub struct Planned {
    /// The object index.
    pub index: u16,
    /// The sub-index.
    pub sub: u8,
    /// `ParameterName`.
    pub name: String,
    /// `DataType`, resolved through DEFTYPE objects.
    pub data_type: Option<DataType>,
    /// Where its value goes.
    pub place: Place,
    /// Why it is not read, if it is not.
    pub skip: Option<&'static str>,
    /// A REAL whose DefaultValue is an IEEE 754 bit pattern: its value is written the same way.
    pub real_bits: bool,
}

/// Where the value of an entry goes in the DCF.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Place {
    /// The object's own section (a VAR or DOMAIN).
    Object,
    /// The sub-object's section.
    Sub,
    /// `[<index>Value]` of a CompactSubObj object.
    Compact,
}

impl Planned {
    /// `1018h:01 (Vendor-ID)`.
    pub fn label(&self) -> String {
        entry_name(self.index, self.sub, &self.name)
    }

    /// The section a comment about this entry goes in.
    pub fn section(&self) -> SectionKind {
        match self.place {
            Place::Sub => SectionKind::Sub(self.index, self.sub),
            Place::Object | Place::Compact => SectionKind::Object(self.index),
        }
    }
}

/// Every entry of the EDS in index order, readable ones without a `skip`.
pub fn plan(eds: &Eds) -> Vec<Planned> {
    let mut out = Vec::new();
    for (&index, object) in &eds.objects {
        let object_type = object.object_type();
        let definition = matches!(
            object_type,
            Some(ObjectType::DefType | ObjectType::DefStruct | ObjectType::Null)
        );
        if object.subs.is_empty() {
            if object.origin != Origin::Explicit {
                continue;
            }
            let domain = object_type == Some(ObjectType::Domain);
            let mut entry = planned(eds, index, 0, &object.attributes, Place::Object, domain);
            if definition {
                entry.skip = Some("a type definition");
            }
            out.push(entry);
            continue;
        }
        for (&sub, sub_object) in &object.subs {
            let place = match sub_object.origin {
                Origin::Explicit => Place::Sub,
                Origin::CompactSubObj if sub > 0 => Place::Compact,
                _ => {
                    let mut entry = planned(eds, index, sub, &sub_object.attributes, Place::Sub, false);
                    entry.skip = Some("implied by CompactSubObj or CompactPDO, no section to hold its value");
                    out.push(entry);
                    continue;
                }
            };
            let mut entry = planned(eds, index, sub, &sub_object.attributes, place, false);
            if definition {
                entry.skip = Some("a type definition");
            }
            out.push(entry);
        }
    }
    out
}

fn planned(eds: &Eds, index: u16, sub: u8, attributes: &Attributes, place: Place, domain: bool) -> Planned {
    let data_type = attributes
        .data_type()
        .map(|t| eds.resolve_data_type(t))
        .or(domain.then_some(DataType::DOMAIN));
    let access = attributes.access_type().or_else(|| {
        // CiA 306 §4.6.3.2: a DOMAIN without AccessType is rw.
        (data_type == Some(DataType::DOMAIN) && attributes.access_type.is_none()).then_some(AccessType::Rw)
    });
    let skip = match access {
        Some(AccessType::Wo) => Some("write-only"),
        Some(_) => None,
        None => Some("no valid AccessType"),
    };
    let real_bits = matches!(
        (data_type, attributes.default_value.as_deref()),
        (Some(DataType::REAL32 | DataType::REAL64), Some(default)) if default.trim().to_ascii_lowercase().starts_with("0x")
    );
    Planned {
        index,
        sub,
        name: attributes.parameter_name.clone().unwrap_or_default(),
        data_type,
        place,
        skip,
        real_bits,
    }
}

/// What reading one planned entry gave.
#[derive(Debug)]
pub enum Reading {
    /// Not read (see [`Planned::skip`]).
    Skipped,
    /// The bytes the device answered with.
    Value(Vec<u8>),
    /// An abort or timeout.
    Failed(SdoTransferError),
}

impl Reading {
    /// The bytes read, if any.
    pub fn value(&self) -> Option<&[u8]> {
        match self {
            Reading::Value(data) => Some(data),
            _ => None,
        }
    }
}

/// A value as a DCF holds it.
#[derive(Debug, Clone, PartialEq, Eq)]
enum DcfValue {
    /// The `ParameterValue` text.
    Text(String),
    /// DOMAIN bytes too many for one line.
    LongDomain(Vec<u8>),
}

/// The CiA 306 text of a value of `data_type` (see the module docs), or why it has none.
fn dcf_value(data_type: Option<DataType>, data: &[u8], real_bits: bool) -> Result<DcfValue, String> {
    let Some(data_type) = data_type else {
        return Err(format!("no DataType to write {} as", hex(data)));
    };
    let Some(kind) = data_type.kind() else {
        return Err(format!(
            "DataType {data_type} has no value notation; the device holds {}",
            hex(data)
        ));
    };
    let sized = |len: usize| -> Result<u64, String> {
        if data.len() != len {
            return Err(format!(
                "the device answered with {} byte(s) for a {data_type} of {len}: {}",
                data.len(),
                hex(data)
            ));
        }
        Ok(data
            .iter()
            .rev()
            .fold(0, |acc, byte| (acc << 8) | u64::from(*byte)))
    };
    let text = match kind {
        TypeKind::Boolean => match sized(1)? {
            raw @ (0 | 1) => raw.to_string(),
            raw => return Err(format!("{raw:#04X} is not a BOOLEAN (0 or 1)")),
        },
        TypeKind::Unsigned(bits) => format!("0x{:X}", sized(bits as usize / 8)?),
        TypeKind::Signed(bits) => {
            let raw = sized(bits as usize / 8)?;
            let shift = 64 - bits;
            let value = ((raw << shift) as i64) >> shift;
            if value < 0 {
                value.to_string()
            } else {
                format!("0x{value:X}")
            }
        }
        TypeKind::Real32 if real_bits => format!("0x{:08X}", sized(4)?),
        TypeKind::Real64 if real_bits => format!("0x{:016X}", sized(8)?),
        TypeKind::Real32 => f32::from_bits(sized(4)? as u32).to_string(),
        TypeKind::Real64 => f64::from_bits(sized(8)?).to_string(),
        TypeKind::TimeOfDay | TypeKind::TimeDifference => format!("0x{:X}", sized(6)?),
        TypeKind::VisibleString => {
            let text = std::str::from_utf8(without_trailing_zeros(data))
                .ok()
                .filter(|text| !text.chars().any(char::is_control))
                .ok_or_else(|| {
                    format!(
                        "the text cannot be written on one line; its bytes are {}",
                        hex(data)
                    )
                })?;
            text.to_owned()
        }
        TypeKind::UnicodeString => {
            let units: Vec<u16> = data
                .chunks(2)
                .map(|pair| match *pair {
                    [low, high] => u16::from_le_bytes([low, high]),
                    _ => u16::from_le_bytes([pair.first().copied().unwrap_or(0), 0]),
                })
                .collect();
            String::from_utf16(without_trailing_zeros(&units))
                .ok()
                .filter(|text| data.len().is_multiple_of(2) && !text.chars().any(char::is_control))
                .ok_or_else(|| format!("not UTF-16 text on one line; its bytes are {}", hex(data)))?
        }
        TypeKind::OctetString | TypeKind::Domain => {
            let digits: String = data.iter().map(|byte| format!("{byte:02X}")).collect();
            if digits.len() > MAX_VALUE_CHARS && kind == TypeKind::Domain {
                return Ok(DcfValue::LongDomain(data.to_vec()));
            }
            digits
        }
        TypeKind::Structure => {
            return Err(format!(
                "a record type has no value; the device holds {}",
                hex(data)
            ));
        }
    };
    if text.len() > MAX_VALUE_CHARS {
        return Err(format!(
            "{} characters do not fit a CiA 306 line (255); the device holds {} bytes",
            text.len(),
            data.len()
        ));
    }
    Ok(DcfValue::Text(text))
}

fn hex(data: &[u8]) -> String {
    if data.is_empty() {
        return "(none)".to_owned();
    }
    let shown: Vec<String> = data.iter().take(32).map(|byte| format!("{byte:02X}")).collect();
    let more = if data.len() > 32 { " …" } else { "" };
    format!("{}{more}", shown.join(" "))
}

/// Drops the values and value files of the template, so every value in the DCF is the device's.
fn clear_values(eds: &mut Eds) {
    for object in eds.objects.values_mut() {
        object.attributes.parameter_value = None;
        object.attributes.upload_file = None;
        object.values = None;
        for sub in object.subs.values_mut() {
            sub.attributes.parameter_value = None;
            sub.attributes.upload_file = None;
        }
    }
}

fn attributes_mut<'a>(eds: &'a mut Eds, entry: &Planned) -> Option<&'a mut Attributes> {
    let object = eds.objects.get_mut(&entry.index)?;
    match entry.place {
        Place::Object => Some(&mut object.attributes),
        Place::Sub | Place::Compact => Some(&mut object.subs.get_mut(&entry.sub)?.attributes),
    }
}

fn set_value(eds: &mut Eds, entry: &Planned, text: String) {
    if entry.place == Place::Compact
        && let Some(object) = eds.objects.get_mut(&entry.index)
    {
        let count = object.subs.keys().filter(|sub| **sub > 0).count();
        let values = object.values.get_or_insert_with(Properties::default);
        values.set("NrOfEntries", count.to_string());
        values.set(&entry.sub.to_string(), text.clone());
    }
    if let Some(attributes) = attributes_mut(eds, entry) {
        attributes.parameter_value = Some(text);
    }
}

/// `NodeName`: the device name 1008h when read, else the EDS's product name.
fn node_name(readings: &[Reading], plan: &[Planned], eds: &Eds, node: u8) -> String {
    let device_name = plan
        .iter()
        .zip(readings)
        .find(|(entry, _)| entry.index == 0x1008 && entry.sub == 0)
        .and_then(|(_, reading)| reading.value())
        .and_then(
            |data| match dcf_value(Some(DataType::VISIBLE_STRING), data, false) {
                Ok(DcfValue::Text(text)) if !text.trim().is_empty() => Some(text),
                _ => None,
            },
        );
    device_name
        .or_else(|| eds.device_info.product_name.clone())
        .unwrap_or_else(|| format!("node {node}"))
}

/// `[DeviceComissioning]` (CiA 306 §5.3.1): NodeID and NodeName; Baudrate from `--bitrate`, else kept
/// from a DCF template, else 0 ("not known": the bus link does not tell the bit rate); LSS_SerialNumber
/// from 1018h sub 4.
fn commission(
    dcf: &mut Eds,
    node: u8,
    name: &str,
    bitrate: Option<u16>,
    readings: &[Reading],
    plan: &[Planned],
) {
    let mut commissioning = dcf.commissioning.take().unwrap_or_default();
    commissioning.node_id = Some(node.to_string());
    commissioning.node_name = Some(name.to_owned());
    if let Some(kbit) = bitrate {
        commissioning.baudrate = Some(kbit.to_string());
    } else if commissioning
        .baudrate
        .as_deref()
        .is_none_or(|b| b.trim().is_empty())
    {
        commissioning.baudrate = Some("0".to_owned());
    }
    let serial = plan
        .iter()
        .zip(readings)
        .find(|(entry, _)| entry.index == 0x1018 && entry.sub == 4)
        .and_then(|(_, reading)| reading.value())
        .and_then(|data| <[u8; 4]>::try_from(data).ok())
        .map(u32::from_le_bytes);
    if let Some(serial) = serial {
        commissioning.lss_serial_number = Some(serial.to_string());
    }
    dcf.commissioning = Some(commissioning);
}

/// `[FileInfo]`: the DCF's own file name (the `-o` name, else the EDS's with `.dcf`), LastEDS naming the
/// template, and the modification time now (UTC; CiA 306 gives no time zone).
fn describe_file(
    dcf: &mut Eds,
    eds: &Eds,
    eds_path: &Path,
    out_name: Option<String>,
    node: u8,
    now: SystemTime,
) {
    let template = eds
        .file_info
        .file_name
        .clone()
        .filter(|name| !name.trim().is_empty())
        .or_else(|| eds_path.file_name().map(|n| n.to_string_lossy().into_owned()));
    let file_name = out_name.unwrap_or_else(|| {
        let stem = template
            .as_deref()
            .and_then(|name| Path::new(name).file_stem())
            .map_or_else(|| "node".to_owned(), |s| s.to_string_lossy().into_owned());
        format!("{stem}_node{node}.dcf")
    });
    let info = &mut dcf.file_info;
    info.file_name = Some(file_name);
    if !eds.is_dcf() || info.last_eds.is_none() {
        info.last_eds = template;
    }
    let (date, time) = cia306_date_time(now);
    info.modification_date = Some(date);
    info.modification_time = Some(time);
    info.modified_by = Some("canopener node dump".to_owned());
}

/// `mm-dd-yyyy` and `hh:mmAM` (CiA 306 §4.4) of a UTC time.
fn cia306_date_time(now: SystemTime) -> (String, String) {
    let secs = now.duration_since(UNIX_EPOCH).map_or(0, |d| d.as_secs());
    let days = (secs / 86_400) as i64;
    let (year, month, day) = canopener_wire::civil_from_days(days);
    let minutes = (secs % 86_400) / 60;
    let (hour, minute) = (minutes / 60, minutes % 60);
    let (hour12, half) = match hour {
        0 => (12, "AM"),
        1..=11 => (hour, "AM"),
        12 => (12, "PM"),
        _ => (hour - 12, "PM"),
    };
    (
        format!("{month:02}-{day:02}-{year:04}"),
        format!("{hour12:02}:{minute:02}{half}"),
    )
}

/// Puts `header` before the first line and each comment at the end of its section (`;` in column 1,
/// cut to the 255 characters of a CiA 306 line).
fn add_comments(document: &Document, header: &str, comments: &[(SectionKind, String)]) -> Document {
    let ending = document.dominant_ending().as_str();
    let comment = |text: &str| -> String {
        let mut line = format!("; {}", text.replace(['\r', '\n'], " "));
        if line.len() > 255 {
            let mut cut = 252;
            while !line.is_char_boundary(cut) {
                cut -= 1;
            }
            line.truncate(cut);
            line.push_str("...");
        }
        line
    };
    let mut editor = document.editor();
    if document.lines().is_empty() {
        editor.append([comment(header)]);
    } else {
        let first = document.line_text(0).to_owned();
        editor.replace_line(0, &format!("{}{ending}{first}", comment(header)));
    }
    for (kind, text) in comments {
        let section = document
            .sections()
            .iter()
            .find(|section| classify(document.section_name(section)) == *kind);
        match section {
            Some(section) => {
                editor.append_to_section(section, [comment(text)]);
            }
            None => {
                editor.append([comment(text)]);
            }
        }
    }
    editor.apply()
}

/// `<dcf stem>_<index>sub<sub>.bin` beside the DCF, for a DOMAIN too long for a line.
fn sidecar_path(out: &Path, index: u16, sub: u8) -> PathBuf {
    let stem = out
        .file_stem()
        .map_or_else(|| "node".to_owned(), |s| s.to_string_lossy().into_owned());
    out.with_file_name(format!("{stem}_{index:04X}sub{sub:X}.bin"))
}

/// What became of the entries of a dump.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct DumpTally {
    /// Entries read and written.
    pub read: usize,
    /// Entry, abort code, message.
    pub aborted: Vec<(String, u32, String)>,
    /// Entry, reason.
    pub skipped: Vec<(String, String)>,
    /// Read, but with no CiA 306 text: entry, reason.
    pub not_representable: Vec<(String, String)>,
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use super::*;

    fn text(data_type: DataType, data: &[u8]) -> String {
        match dcf_value(Some(data_type), data, false) {
            Ok(DcfValue::Text(text)) => text,
            other => panic!("{data_type} {data:?}: {other:?}"),
        }
    }

    #[test]
    fn values_take_cia_306_notations_that_load_back() {
        assert_eq!(text(DataType::UNSIGNED32, &[0xBC, 0x0A, 0, 0]), "0xABC");
        assert_eq!(text(DataType::UNSIGNED8, &[0]), "0x0");
        assert_eq!(text(DataType::UNSIGNED24, &[1, 2, 3]), "0x30201");
        assert_eq!(text(DataType::INTEGER16, &[0xFB, 0xFF]), "-5");
        assert_eq!(text(DataType::INTEGER16, &[0x10, 0x00]), "0x10");
        assert_eq!(text(DataType::BOOLEAN, &[1]), "1");
        assert_eq!(text(DataType::REAL32, &1.5f32.to_le_bytes()), "1.5");
        assert_eq!(text(DataType::REAL64, &(-0.1f64).to_le_bytes()), "-0.1");
        assert_eq!(
            dcf_value(Some(DataType::REAL32), &1.5f32.to_le_bytes(), true),
            Ok(DcfValue::Text("0x3FC00000".to_owned()))
        );
        assert_eq!(text(DataType::VISIBLE_STRING, b"canopener\0\0"), "canopener");
        assert_eq!(text(DataType::VISIBLE_STRING, b""), "");
        assert_eq!(text(DataType::OCTET_STRING, &[1, 0xA2, 0xFF]), "01A2FF");
        assert_eq!(text(DataType::DOMAIN, &[]), "");
        assert_eq!(text(DataType::TIME_OF_DAY, &[1, 0, 0, 0, 2, 0]), "0x200000001");
        assert_eq!(text(DataType::UNICODE_STRING, &[b'h', 0, b'i', 0]), "hi");
        // Every text reads back, as the loader would, without findings and to the same value.
        for (data_type, data) in [
            (DataType::UNSIGNED32, vec![0xBC, 0x0A, 0, 0]),
            (DataType::INTEGER16, vec![0xFB, 0xFF]),
            (DataType::INTEGER64, vec![0xFF; 8]),
            (DataType::BOOLEAN, vec![0]),
            (DataType::OCTET_STRING, vec![1, 2]),
            (DataType::DOMAIN, vec![0xDE, 0xAD]),
            (DataType::TIME_DIFFERENCE, vec![1, 0, 0, 0, 2, 0]),
        ] {
            let written = text(data_type, &data);
            let parsed = canopener_eds::value::parse_value(&written, data_type);
            assert!(
                parsed.issues.is_empty(),
                "{data_type} {written}: {:?}",
                parsed.issues
            );
            assert!(parsed.value.is_some(), "{data_type} {written}");
        }
    }

    #[test]
    fn values_without_a_notation_say_why() {
        assert!(
            dcf_value(Some(DataType::UNSIGNED16), &[1], false)
                .unwrap_err()
                .contains("1 byte(s) for a UNSIGNED16 of 2")
        );
        assert!(
            dcf_value(Some(DataType::BOOLEAN), &[2], false)
                .unwrap_err()
                .contains("not a BOOLEAN")
        );
        assert!(
            dcf_value(Some(DataType::VISIBLE_STRING), b"a\nb", false)
                .unwrap_err()
                .contains("61 0A 62")
        );
        assert!(dcf_value(None, &[1], false).is_err());
        assert!(dcf_value(Some(DataType(0x0040)), &[1], false).is_err());
        let long = vec![0x55; 200];
        assert_eq!(
            dcf_value(Some(DataType::DOMAIN), &long, false),
            Ok(DcfValue::LongDomain(long.clone()))
        );
        assert!(
            dcf_value(Some(DataType::OCTET_STRING), &long, false)
                .unwrap_err()
                .contains("do not fit")
        );
    }

    #[test]
    fn dates_are_cia_306_in_utc() {
        let at = |secs: u64| cia306_date_time(UNIX_EPOCH + Duration::from_secs(secs));
        assert_eq!(at(0), ("01-01-1970".to_owned(), "12:00AM".to_owned()));
        // 2026-05-15 09:45 and 14:30 UTC.
        assert_eq!(at(1_778_838_300), ("05-15-2026".to_owned(), "09:45AM".to_owned()));
        assert_eq!(at(1_778_855_400).1, "02:30PM");
        assert_eq!(canopener_wire::civil_from_days(11_016), (2000, 2, 29));
    }

    const EDS: &str = "[FileInfo]\r\nFileName=dev.eds\r\n\r\n[DeviceInfo]\r\nProductName=Dev\r\n\r\n\
        [1000]\r\nParameterName=Device type\r\nDataType=0x0007\r\nAccessType=ro\r\nDefaultValue=0x191\r\n\r\n\
        [1010]\r\nParameterName=Store\r\nObjectType=0x8\r\nSubNumber=2\r\n\r\n\
        [1010sub0]\r\nParameterName=Highest\r\nDataType=0x0005\r\nAccessType=ro\r\nDefaultValue=1\r\n\r\n\
        [1010sub1]\r\nParameterName=Save all\r\nDataType=0x0007\r\nAccessType=wo\r\nDefaultValue=1\r\n\r\n\
        [2000]\r\nParameterName=Arr\r\nObjectType=0x8\r\nDataType=0x0006\r\nAccessType=rw\r\nDefaultValue=7\r\nCompactSubObj=2\r\n\r\n\
        [2001]\r\nParameterName=Blob\r\nObjectType=0x2\r\nDataType=0x000F\r\n";

    #[test]
    fn the_plan_reads_readable_entries_and_places_compact_values() {
        let eds = canopener_eds::load(EDS.as_bytes()).eds;
        let plan = plan(&eds);
        let summary: Vec<(u16, u8, Place, Option<&str>)> =
            plan.iter().map(|e| (e.index, e.sub, e.place, e.skip)).collect();
        assert_eq!(
            summary,
            [
                (0x1000, 0, Place::Object, None),
                (0x1010, 0, Place::Sub, None),
                (0x1010, 1, Place::Sub, Some("write-only")),
                (
                    0x2000,
                    0,
                    Place::Sub,
                    Some("implied by CompactSubObj or CompactPDO, no section to hold its value")
                ),
                (0x2000, 1, Place::Compact, None),
                (0x2000, 2, Place::Compact, None),
                (0x2001, 0, Place::Object, None),
            ]
        );
        let mut dcf = eds.clone();
        clear_values(&mut dcf);
        set_value(&mut dcf, &plan[0], "0xF0191".to_owned());
        set_value(&mut dcf, &plan[5], "0x9".to_owned());
        let mut readings = vec![Reading::Value(vec![0x91, 0x01, 0x0F, 0])];
        readings.extend((1..plan.len()).map(|_| Reading::Skipped));
        commission(&mut dcf, 5, "Dev", None, &readings, &plan);
        describe_file(&mut dcf, &eds, Path::new("dev.eds"), None, 5, UNIX_EPOCH);
        let loaded = canopener_eds::load(EDS.as_bytes());
        let document = canopener_eds::write::write_lossless(&loaded.document, &dcf);
        let document = add_comments(
            &document,
            "header",
            &[(SectionKind::Sub(0x1010, 0), "1010h:00 not read: abort".to_owned())],
        );
        let written = document.text().to_owned();
        assert!(
            written.starts_with("; header\r\n[FileInfo]\r\nFileName=dev_node5.dcf\r\n"),
            "{written}"
        );
        assert!(
            written.contains("DefaultValue=0x191\r\nParameterValue=0xF0191\r\n"),
            "{written}"
        );
        assert!(
            written.contains("DefaultValue=1\r\n; 1010h:00 not read: abort\r\n"),
            "{written}"
        );
        assert!(
            written.contains("[2000Value]\r\nNrOfEntries=2\r\n2=0x9\r\n"),
            "{written}"
        );
        assert!(
            written.contains("[DeviceComissioning]\r\nNodeID=5\r\nNodeName=Dev\r\nBaudrate=0\r\n"),
            "{written}"
        );
        assert!(written.contains("LastEDS=dev.eds\r\n") && written.contains("ModificationDate=01-01-1970"));
        let again = canopener_eds::load(written.as_bytes());
        assert_eq!(again.eds.node_id(), Some(5));
        assert_eq!(
            again.eds.objects[&0x2000].subs[&2]
                .attributes
                .parameter_value
                .as_deref(),
            Some("0x9")
        );
        // The template lacks object lists; the DCF has no error the template did not have.
        let errors = |diagnostics: &[canopener_eds::Diagnostic]| {
            let mut codes: Vec<&str> = diagnostics
                .iter()
                .filter(|d| d.severity == canopener_eds::Severity::Error)
                .map(|d| d.code.as_str())
                .collect();
            codes.sort_unstable();
            codes
        };
        assert_eq!(errors(&again.diagnostics), errors(&loaded.diagnostics));
    }

    #[test]
    fn sidecars_sit_beside_the_dcf() {
        assert_eq!(
            sidecar_path(Path::new("out/node5.dcf"), 0x1F50, 1),
            Path::new("out/node5_1F50sub1.bin")
        );
    }

    #[test]
    fn the_bitrate_option_sets_the_dcf_baudrate_else_it_is_unknown() {
        let mut dcf = canopener_eds::load(EDS.as_bytes()).eds;
        commission(&mut dcf, 5, "Dev", Some(250), &[], &[]);
        let baudrate = dcf.commissioning.as_ref().and_then(|c| c.baudrate.clone());
        assert_eq!(baudrate.as_deref(), Some("250"));
        let mut dcf = canopener_eds::load(EDS.as_bytes()).eds;
        commission(&mut dcf, 5, "Dev", None, &[], &[]);
        let baudrate = dcf.commissioning.as_ref().and_then(|c| c.baudrate.clone());
        assert_eq!(baudrate.as_deref(), Some("0"));
    }
}

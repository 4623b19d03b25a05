//! Rendering frames for people (aligned text) and machines (JSON lines), shared by `bus dump`, `bus decode`
//! and `demo`, so that a live capture and an offline decode of its log print the same lines.

use std::collections::BTreeMap;
use std::io::{self, Write};

use canopener_can::candump::{LogEvent, LogRecord};
use canopener_can::{CanFrame, Instant};
use canopener_wire::{Decoded, Decoder, Service};

use crate::args::OutputFormat;

/// Decodes frames in bus order and prints one line per frame.
#[derive(Debug)]
pub(crate) struct Monitor {
    decoder: Decoder,
    format: OutputFormat,
    raw: bool,
    stats: MonitorStats,
}

/// What a monitor has seen so far.
#[derive(Debug, Default, Clone)]
pub(crate) struct MonitorStats {
    pub(crate) frames: u64,
    pub(crate) error_frames: u64,
    pub(crate) frames_with_anomalies: u64,
    pub(crate) by_service: BTreeMap<Service, u64>,
}

impl Monitor {
    /// `raw` prints frames without CANopen decoding (candump log lines, or JSON without decoded fields).
    pub(crate) fn new(format: OutputFormat, raw: bool) -> Monitor {
        Monitor {
            decoder: Decoder::new(),
            format,
            raw,
            stats: MonitorStats::default(),
        }
    }

    pub(crate) fn stats(&self) -> &MonitorStats {
        &self.stats
    }

    pub(crate) fn print_record(
        &mut self,
        out: &mut (impl Write + ?Sized),
        record: &LogRecord,
    ) -> io::Result<()> {
        match &record.event {
            LogEvent::Frame(frame) => self.print_frame(out, record.timestamp, &record.interface, frame),
            LogEvent::ErrorFrame { class, data } => {
                self.stats.error_frames += 1;
                let hex = hex_upper(data);
                match self.format {
                    OutputFormat::Text => writeln!(
                        out,
                        "({}) {:<6} error frame class {class:#010X} data {hex}",
                        record.timestamp, record.interface
                    ),
                    OutputFormat::Json => writeln!(
                        out,
                        "{}",
                        serde_json::json!({
                            "timestamp": record.timestamp.to_string(),
                            "timestamp_ns": record.timestamp.as_nanos(),
                            "interface": record.interface,
                            "error_frame": true,
                            "class": class,
                            "data": hex,
                        })
                    ),
                }
            }
        }
    }

    pub(crate) fn print_frame(
        &mut self,
        out: &mut (impl Write + ?Sized),
        timestamp: Instant,
        interface: &str,
        frame: &CanFrame,
    ) -> io::Result<()> {
        self.stats.frames += 1;
        if self.raw {
            return match self.format {
                OutputFormat::Text => writeln!(out, "({timestamp}) {interface} {frame}"),
                OutputFormat::Json => writeln!(out, "{}", frame_json(timestamp, interface, frame, None)),
            };
        }
        let decoded = self.decoder.decode(frame);
        *self.stats.by_service.entry(decoded.service).or_default() += 1;
        if !decoded.anomalies.is_empty() {
            self.stats.frames_with_anomalies += 1;
        }
        match self.format {
            OutputFormat::Text => writeln!(out, "{}", text_line(timestamp, interface, frame, &decoded)),
            OutputFormat::Json => {
                writeln!(out, "{}", frame_json(timestamp, interface, frame, Some(&decoded)))
            }
        }
    }
}

/// `(1700000000.123456) can0        701   [1]  05                       Heartbeat node 1: OPERATIONAL`
pub(crate) fn text_line(timestamp: Instant, interface: &str, frame: &CanFrame, decoded: &Decoded) -> String {
    let data = if frame.is_remote() {
        "remote request".to_owned()
    } else {
        frame
            .data()
            .iter()
            .map(|byte| format!("{byte:02X}"))
            .collect::<Vec<_>>()
            .join(" ")
    };
    // Anomalies are part of the decoded text (`[anomaly: …]`), so a mistake on the wire is never a separate line.
    format!(
        "({timestamp}) {interface:<6} {:>8}  [{}]  {data:<23}  {decoded}",
        frame.id().to_string(),
        frame.dlc()
    )
}

fn frame_json(
    timestamp: Instant,
    interface: &str,
    frame: &CanFrame,
    decoded: Option<&Decoded>,
) -> serde_json::Value {
    let mut value = serde_json::json!({
        "timestamp": timestamp.to_string(),
        "timestamp_ns": timestamp.as_nanos(),
        "interface": interface,
        "id": frame.id().to_string(),
        "id_raw": frame.id().as_raw(),
        "extended": frame.id().is_extended(),
        "remote": frame.is_remote(),
        "dlc": frame.dlc(),
        "data": hex_upper(frame.data()),
    });
    if let (Some(decoded), Some(map)) = (decoded, value.as_object_mut()) {
        map.insert("service".into(), service_key(decoded.service).into());
        map.insert(
            "node".into(),
            decoded.node.map_or(serde_json::Value::Null, Into::into),
        );
        map.insert("text".into(), decoded.to_string().into());
        map.insert("anomalies".into(), decoded.anomalies.clone().into());
    }
    value
}

/// Stable machine names for services in JSON output (the `Display` text is for people and may change).
pub(crate) fn service_key(service: Service) -> String {
    match service {
        Service::Nmt => "nmt".into(),
        Service::Sync => "sync".into(),
        Service::Emcy => "emcy".into(),
        Service::Time => "time".into(),
        Service::Tpdo(n) => format!("tpdo{n}"),
        Service::Rpdo(n) => format!("rpdo{n}"),
        Service::SdoTx => "sdo_tx".into(),
        Service::SdoRx => "sdo_rx".into(),
        Service::ErrorControl => "error_control".into(),
        Service::Lss => "lss".into(),
        Service::Unknown => "unknown".into(),
    }
}

fn hex_upper(bytes: &[u8]) -> String {
    bytes.iter().map(|byte| format!("{byte:02X}")).collect()
}

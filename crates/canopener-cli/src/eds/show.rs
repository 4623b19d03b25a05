//! `canopener eds show`: the object dictionary as a table (or JSON).

use std::fmt::Write as _;

use canopener_description::DescriptionCode;
use canopener_eds::model::{Attributes, Eds, Origin};
use canopener_eds::{Diagnostic, ObjectType, Severity};
use serde::Serialize;

use crate::eds::args::{EdsShowArgs, ReportFormat};
use crate::eds::input::{read_input, report_diagnostics};
use crate::error::{CliError, CliResult};
use crate::output::print_stdout;

/// One row of the table: an object or a sub-object.
#[derive(Debug, Serialize)]
struct Row {
    index: String,
    sub: Option<String>,
    name: String,
    object_type: String,
    data_type: Option<String>,
    access: Option<String>,
    pdo_mapping: bool,
    default: Option<String>,
    /// The default with `$NODEID` resolved, when a node-ID is known and the value is a formula.
    resolved: Option<String>,
    low_limit: Option<String>,
    high_limit: Option<String>,
    value: Option<String>,
    origin: &'static str,
}

#[derive(Debug, Serialize)]
struct ShowJson<'a> {
    file: String,
    format: &'static str,
    dcf: bool,
    node_id: Option<u8>,
    file_info: Vec<(&'a str, &'a str)>,
    device_info: Vec<(&'a str, &'a str)>,
    objects: Vec<Row>,
    diagnostics: Vec<DiagnosticJson<'a>>,
}

/// A loading diagnostic as the JSON document shows it (flat: line and column, no span).
#[derive(Debug, Serialize)]
struct DiagnosticJson<'a> {
    line: u32,
    column: u32,
    severity: Severity,
    code: DescriptionCode,
    message: &'a str,
    help: Option<&'a str>,
}

impl<'a> From<&'a Diagnostic<DescriptionCode>> for DiagnosticJson<'a> {
    fn from(d: &'a Diagnostic<DescriptionCode>) -> Self {
        DiagnosticJson {
            line: d.span.line,
            column: d.span.column,
            severity: d.severity,
            code: d.code,
            message: &d.message,
            help: d.help.as_deref(),
        }
    }
}

pub(crate) fn run(args: EdsShowArgs) -> CliResult {
    let input = read_input(&args.file)?;
    let eds = &input.eds;
    if let Some(index) = args.object
        && !eds.objects.contains_key(&index)
    {
        return Err(CliError::EdsTrouble(format!(
            "{} has no object {index:X}h ({} objects; `canopener eds show {}` lists them)",
            args.file.display(),
            eds.objects.len(),
            args.file.display()
        )));
    }
    let node_id = args.node_id.or_else(|| eds.node_id());
    let rows = rows(eds, args.object, node_id);
    match args.format {
        ReportFormat::Json => {
            let doc = ShowJson {
                file: args.file.display().to_string(),
                format: input.format.name(),
                dcf: eds.is_dcf(),
                node_id,
                file_info: eds.file_info.entries(),
                device_info: eds.device_info.entries(),
                objects: rows,
                diagnostics: input.diagnostics.iter().map(DiagnosticJson::from).collect(),
            };
            let text = serde_json::to_string_pretty(&doc).map_err(|e| CliError::Internal(e.into()))?;
            print_stdout(&format!("{text}\n"))
        }
        ReportFormat::Human => {
            report_diagnostics(&args.file, &input, args.diagnostics);
            let mut out = String::new();
            if args.object.is_none() {
                header(eds, &mut out);
            }
            table(&rows, &mut out);
            print_stdout(&out)
        }
    }
}

fn header(eds: &Eds, out: &mut String) {
    let info = &eds.device_info;
    let get = |v: &Option<String>| v.clone().unwrap_or_else(|| "-".to_owned());
    let _ = writeln!(
        out,
        "File:     {} ({})",
        get(&eds.file_info.file_name),
        if eds.is_dcf() { "DCF" } else { "EDS" }
    );
    let _ = writeln!(
        out,
        "Vendor:   {} (vendor-ID {})",
        get(&info.vendor_name),
        get(&info.vendor_number)
    );
    let _ = writeln!(
        out,
        "Product:  {} (code {}, revision {})",
        get(&info.product_name),
        get(&info.product_number),
        get(&info.revision_number)
    );
    let rates: Vec<String> = canopener_eds::dcf::BITRATES_KBIT
        .iter()
        .filter(|k| canopener_eds::dcf::supports_bitrate(eds, **k))
        .map(|k| k.to_string())
        .collect();
    let _ = writeln!(
        out,
        "Bit rates: {} kbit/s; RPDOs {}, TPDOs {}",
        if rates.is_empty() {
            "none declared".to_owned()
        } else {
            rates.join(", ")
        },
        get(&info.nr_of_rx_pdo),
        get(&info.nr_of_tx_pdo)
    );
    if let Some(node) = eds.node_id() {
        let baud = eds
            .commissioning
            .as_ref()
            .and_then(|c| c.baudrate.clone())
            .unwrap_or_else(|| "-".to_owned());
        let _ = writeln!(out, "Node:     {node} at {baud} kbit/s");
    }
    let subs: usize = eds.objects.values().map(|o| o.subs.len()).sum();
    let _ = writeln!(out, "Objects:  {} with {subs} sub-objects\n", eds.objects.len());
}

fn rows(eds: &Eds, only: Option<u16>, node_id: Option<u8>) -> Vec<Row> {
    let mut rows = Vec::new();
    for (index, object) in &eds.objects {
        if only.is_some_and(|o| o != *index) {
            continue;
        }
        let structured = object.object_type().is_some_and(ObjectType::has_subs) || !object.subs.is_empty();
        rows.push(row(
            eds,
            *index,
            None,
            &object.attributes,
            object.origin,
            structured,
            node_id,
        ));
        for (sub, sub_object) in &object.subs {
            rows.push(row(
                eds,
                *index,
                Some(*sub),
                &sub_object.attributes,
                sub_object.origin,
                false,
                node_id,
            ));
        }
    }
    rows
}

fn row(
    eds: &Eds,
    index: u16,
    sub: Option<u8>,
    a: &Attributes,
    origin: Origin,
    structured: bool,
    node: Option<u8>,
) -> Row {
    let data_type = a.data_type().map(|t| eds.resolve_data_type(t));
    let resolved = match (node, data_type, a.default_value.as_deref()) {
        (Some(node), Some(t), Some(text)) if text.to_ascii_uppercase().contains("$NODEID") => {
            canopener_eds::value::parse_value(text, t)
                .value
                .and_then(|v| v.resolve(node))
                .map(|v| format!("0x{v:X}"))
        }
        _ => None,
    };
    let value_keys = !structured;
    Row {
        index: format!("{index:04X}"),
        sub: sub.map(|s| format!("{s:02X}")),
        name: a.parameter_name.clone().unwrap_or_default(),
        object_type: a
            .object_type()
            .map_or_else(|| a.object_type.clone().unwrap_or_default(), |t| t.to_string()),
        data_type: data_type.filter(|_| value_keys).map(|t| t.to_string()),
        access: a.access_type.clone().filter(|_| value_keys),
        pdo_mapping: a.pdo_mapping(),
        default: a.default_value.clone().filter(|_| value_keys),
        resolved,
        low_limit: a.low_limit.clone(),
        high_limit: a.high_limit.clone(),
        value: a.parameter_value.clone(),
        origin: match origin {
            Origin::Explicit => "explicit",
            Origin::CompactSubObj => "CompactSubObj",
            Origin::CompactPdo => "CompactPDO",
            Origin::Orphan => "orphan",
        },
    }
}

fn table(rows: &[Row], out: &mut String) {
    let has_values = rows.iter().any(|r| r.value.is_some());
    let mut lines: Vec<Vec<String>> = vec![
        [
            "Index", "Sub", "Name", "Object", "Type", "Access", "PDO", "Default",
        ]
        .map(str::to_owned)
        .to_vec(),
    ];
    if has_values {
        lines[0].push("Value".to_owned());
    }
    for r in rows {
        let mut name = if r.sub.is_some() {
            format!("  {}", r.name)
        } else {
            r.name.clone()
        };
        if name.chars().count() > 44 {
            name = name.chars().take(43).collect::<String>() + "…";
        }
        let mut default = r.default.clone().unwrap_or_default();
        if let Some(resolved) = &r.resolved {
            default = format!("{default} = {resolved}");
        }
        if r.origin != "explicit" {
            default = format!("{default} ({})", r.origin);
        }
        let mut line = vec![
            format!("{}h", r.index),
            r.sub.clone().unwrap_or_default(),
            name,
            if r.sub.is_some() && r.object_type == "VAR" {
                String::new()
            } else {
                r.object_type.clone()
            },
            r.data_type.clone().unwrap_or_default(),
            r.access.clone().unwrap_or_default(),
            if r.pdo_mapping {
                "yes".to_owned()
            } else {
                String::new()
            },
            default,
        ];
        if has_values {
            line.push(r.value.clone().unwrap_or_default());
        }
        lines.push(line);
    }
    let columns = lines.first().map_or(0, Vec::len);
    let widths: Vec<usize> = (0..columns)
        .map(|c| {
            lines
                .iter()
                .map(|l| l.get(c).map_or(0, |s| s.chars().count()))
                .max()
                .unwrap_or(0)
        })
        .collect();
    for line in &lines {
        let mut text = String::new();
        for (c, cell) in line.iter().enumerate() {
            let width = widths.get(c).copied().unwrap_or(0);
            let _ = write!(text, "{cell:<width$}  ");
        }
        out.push_str(text.trim_end());
        out.push('\n');
    }
}

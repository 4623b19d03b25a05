//! `canopener sdo read|write|upload|download`: one SDO transfer with one node (CiA 301 §7.2.4), typed by
//! `--type`, by an EDS, or (reads) by the length the device answered with.
//!
//! Every argument is checked before the bus is opened, so a typo costs no timeout. A device that aborts
//! or does not answer ends the command with exit status 7 and a message naming the node, the object
//! and the decoded abort code (see `sdo_session`).

use std::path::Path;

use canopener_eds::Eds;
use canopener_files::write_atomic;
use canopener_link::sdo_session::Progress;
use canopener_master::sdo_client::{DownloadMode, UploadMode};
use canopener_master::value::{ValueType, parse_index, parse_sub};
use canopener_master::value_typing::{
    EdsEntry, TypeSource, decode, eds_entry, expedited_value, guess_type, value_type_of, write_warnings,
};
use serde_json::json;

use crate::args::OutputFormat;
use crate::error::{CliError, CliResult};
use crate::master::args::{SdoDownloadArgs, SdoReadArgs, SdoUploadArgs, SdoWriteArgs};
use crate::master::link::open_session;
use crate::master::output::{
    ByteProgress, json_value, kbytes_per_s, millis, object_name, output_error, print_json, raw_hex,
    refuse_existing, sdo_error,
};
use crate::output::print_stdout;

pub(crate) fn read(args: SdoReadArgs) -> CliResult {
    let example = "canopener sdo read --node 5 1018 1";
    let (index, sub) = object_args(&args.object.index, &args.object.sub, example)?;
    let typing = Typing::from_args(args.typing.value_type.as_deref(), args.typing.eds.as_deref())?;
    let entry = typing.entry(index, sub);
    if let Typing::Eds { path, .. } = &typing
        && entry.is_none()
    {
        eprintln!(
            "warning: {path} does not list {}; the value is typed by its length",
            object_name(index, sub, None)
        );
    }
    let name = entry.as_ref().map(|entry| entry.name.clone());
    let mut session = open_session(&args.master, args.object.node, "sdo read")?;
    let mode = if args.block {
        UploadMode::Block
    } else {
        UploadMode::Normal
    };
    let transfer = session
        .upload(index, sub, mode, &mut |_| {})
        .map_err(|err| sdo_error(args.object.node, index, sub, name.as_deref(), err))?;
    let (ty, source) = match (&typing, &entry) {
        (Typing::Fixed(ty), _) => (*ty, TypeSource::Option),
        (_, Some(entry)) => (value_type_of(entry.data_type), TypeSource::Eds),
        _ => (guess_type(&transfer.data), TypeSource::Guessed),
    };
    let (bytes, padding) = expedited_value(ty, &transfer.data, transfer.protocol);
    if let Some(padding) = padding {
        eprintln!(
            "warning: node {}, {}: {padding}",
            args.object.node,
            object_name(index, sub, None)
        );
    }
    let (ty, value, warning) = decode(ty, bytes);
    if let Some(warning) = &warning {
        eprintln!(
            "warning: node {}, {}: {warning}",
            args.object.node,
            object_name(index, sub, None)
        );
    }
    match args.master.format {
        OutputFormat::Json => print_json(&json!({
            "node": args.object.node,
            "index": format!("{index:04X}"),
            "sub": sub,
            "name": name,
            "type": ty.name(),
            "type_source": source.as_str(),
            "raw": raw_hex(&transfer.data),
            "bytes": transfer.data.len(),
            "value": json_value(&value),
            "text": value.to_string(),
            "protocol": transfer.protocol.to_string(),
            "elapsed_ms": millis(transfer.elapsed),
        })),
        OutputFormat::Text => {
            if source == TypeSource::Guessed {
                eprintln!(
                    "note: typed as {ty} by its length ({} bytes); --type or --eds choose the type",
                    transfer.data.len()
                );
            }
            print_stdout(&format!("{} = {value}\n", labelled(index, sub, name.as_deref())))
        }
    }
}

pub(crate) fn write(args: SdoWriteArgs) -> CliResult {
    let example = "canopener sdo write --node 5 1017 0 1000 --type u16";
    let (index, sub) = object_args(&args.object.index, &args.object.sub, example)?;
    let typing = Typing::from_args(args.typing.value_type.as_deref(), args.typing.eds.as_deref())?;
    let object = object_name(index, sub, None);
    let (ty, entry) = match &typing {
        Typing::Fixed(ty) => (*ty, None),
        Typing::Eds { path, .. } => {
            let entry = typing.entry(index, sub).ok_or_else(|| {
                CliError::Usage(format!(
                    "{path} does not list {object}, so the value's type is unknown; give it with --type, e.g. {example}"
                ))
            })?;
            (value_type_of(entry.data_type), Some(entry))
        }
        Typing::Unknown => {
            return Err(CliError::Usage(format!(
                "sdo write needs the value's type to know how many bytes to send: add --type (u8 … u64, i8 … i64, \
                 f32, f64, bool, str, hex) or --eds FILE, e.g. {example}"
            )));
        }
    };
    let data = ty
        .parse(&args.value)
        .map_err(|err| CliError::Usage(format!("VALUE `{}` for {object} as {ty}: {err}", args.value)))?;
    let (_, value, _) = decode(ty, &data);
    let name = entry.as_ref().map(|entry| entry.name.clone());
    if let Some(entry) = &entry {
        for warning in write_warnings(entry, &value, args.object.node) {
            eprintln!(
                "warning: node {}, {}: {warning}; writing anyway, the device decides",
                args.object.node,
                object_name(index, sub, name.as_deref())
            );
        }
    }
    let mode = if args.block {
        DownloadMode::Block
    } else if args.segmented {
        DownloadMode::Segmented
    } else {
        DownloadMode::Auto
    };
    let mut session = open_session(&args.master, args.object.node, "sdo write")?;
    let bytes = data.len();
    let transfer = session
        .download(index, sub, data.clone(), mode, &mut |_| {})
        .map_err(|err| sdo_error(args.object.node, index, sub, name.as_deref(), err))?;
    match args.master.format {
        OutputFormat::Json => print_json(&json!({
            "node": args.object.node,
            "index": format!("{index:04X}"),
            "sub": sub,
            "name": name,
            "type": ty.name(),
            "type_source": if entry.is_some() { "eds" } else { "option" },
            "raw": raw_hex(&data),
            "bytes": bytes,
            "value": json_value(&value),
            "text": value.to_string(),
            "protocol": transfer.protocol.to_string(),
            "elapsed_ms": millis(transfer.elapsed),
            "confirmed": true,
        })),
        OutputFormat::Text => print_stdout(&format!(
            "{} = {value}: written, node {} confirmed ({} download, {bytes} byte{}, {:.1} ms)\n",
            labelled(index, sub, name.as_deref()),
            args.object.node,
            transfer.protocol,
            if bytes == 1 { "" } else { "s" },
            millis(transfer.elapsed)
        )),
    }
}

pub(crate) fn upload(args: SdoUploadArgs) -> CliResult {
    let example = "canopener sdo upload --node 5 1F50 1 -o firmware.bin";
    let (index, sub) = object_args(&args.object.index, &args.object.sub, example)?;
    refuse_existing(&args.output, args.force)?;
    let mut session = open_session(&args.master, args.object.node, "sdo upload")?;
    let mode = if args.block {
        UploadMode::Block
    } else {
        UploadMode::Normal
    };
    let object = object_name(index, sub, None);
    let bar = ByteProgress::new(&format!("reading {object}"));
    let outcome = session.upload(index, sub, mode, &mut |p: Progress| bar.update(p.done, p.total));
    bar.finish();
    let transfer = outcome.map_err(|err| sdo_error(args.object.node, index, sub, None, err))?;
    write_atomic(&args.output, &transfer.data, args.force).map_err(|err| output_error(&args.output, err))?;
    let bytes = transfer.data.len();
    let rate = kbytes_per_s(bytes, transfer.elapsed);
    match args.master.format {
        OutputFormat::Json => print_json(&json!({
            "node": args.object.node,
            "index": format!("{index:04X}"),
            "sub": sub,
            "file": args.output.display().to_string(),
            "bytes": bytes,
            "protocol": transfer.protocol.to_string(),
            "elapsed_ms": millis(transfer.elapsed),
            "kbytes_per_s": rate,
        })),
        OutputFormat::Text => print_stdout(&format!(
            "read {bytes} bytes from node {}, {object} into {} in {:.1} ms ({rate:.1} kB/s, {})\n",
            args.object.node,
            args.output.display(),
            millis(transfer.elapsed),
            transfer.protocol
        )),
    }
}

pub(crate) fn download(args: SdoDownloadArgs) -> CliResult {
    let example = "canopener sdo download --node 5 1F50 1 firmware.bin";
    let (index, sub) = object_args(&args.object.index, &args.object.sub, example)?;
    let data = canopener_files::read(&args.input).map_err(|err| CliError::read_file(&args.input, err))?;
    let mut session = open_session(&args.master, args.object.node, "sdo download")?;
    let mode = if args.block {
        DownloadMode::Block
    } else {
        DownloadMode::Auto
    };
    let object = object_name(index, sub, None);
    let bytes = data.len();
    let bar = ByteProgress::new(&format!("writing {object}"));
    let outcome = session.download(index, sub, data, mode, &mut |p: Progress| {
        bar.update(p.done, p.total)
    });
    bar.finish();
    let transfer = outcome.map_err(|err| sdo_error(args.object.node, index, sub, None, err))?;
    let rate = kbytes_per_s(bytes, transfer.elapsed);
    match args.master.format {
        OutputFormat::Json => print_json(&json!({
            "node": args.object.node,
            "index": format!("{index:04X}"),
            "sub": sub,
            "file": args.input.display().to_string(),
            "bytes": bytes,
            "protocol": transfer.protocol.to_string(),
            "elapsed_ms": millis(transfer.elapsed),
            "kbytes_per_s": rate,
        })),
        OutputFormat::Text => print_stdout(&format!(
            "wrote {bytes} bytes from {} to node {}, {object} in {:.1} ms ({rate:.1} kB/s, {})\n",
            args.input.display(),
            args.object.node,
            millis(transfer.elapsed),
            transfer.protocol
        )),
    }
}

/// INDEX and SUB as people write them (hexadecimal unless marked), or a usage error with an example.
pub(crate) fn object_args(index: &str, sub: &str, example: &str) -> CliResult<(u16, u8)> {
    let index = parse_index(index).map_err(|err| CliError::Usage(format!("INDEX: {err}; e.g. {example}")))?;
    let sub = parse_sub(sub).map_err(|err| CliError::Usage(format!("SUB: {err}; e.g. {example}")))?;
    Ok((index, sub))
}

/// The typing options of one command, checked before the bus is opened.
#[derive(Debug)]
enum Typing {
    /// `--type T`.
    Fixed(ValueType),
    /// `--eds FILE`, loaded.
    Eds { path: String, eds: Box<Eds> },
    /// Neither: reads guess by length, writes refuse.
    Unknown,
}

impl Typing {
    /// Reads `--type` or loads `--eds` (clap already refuses both at once).
    fn from_args(value_type: Option<&str>, eds: Option<&Path>) -> CliResult<Typing> {
        if let Some(text) = value_type {
            let ty = text
                .parse::<ValueType>()
                .map_err(|err| CliError::Usage(format!("--type {text}: {err}; e.g. --type u16")))?;
            return Ok(Typing::Fixed(ty));
        }
        if let Some(path) = eds {
            let input = canopener_runtime::description::read_description(path)?;
            return Ok(Typing::Eds {
                path: path.display().to_string(),
                eds: Box::new(input.eds),
            });
        }
        Ok(Typing::Unknown)
    }

    /// The EDS entry of `index`:`sub`, if an EDS was given and lists it.
    fn entry(&self, index: u16, sub: u8) -> Option<EdsEntry> {
        match self {
            Typing::Eds { eds, .. } => eds_entry(eds, index, sub),
            _ => None,
        }
    }
}

/// `1018h:01 Vendor-ID`, or `1018h:01` without a name.
fn labelled(index: u16, sub: u8, name: Option<&str>) -> String {
    match name.filter(|name| !name.is_empty()) {
        Some(name) => format!("{index:04X}h:{sub:02X} {name}"),
        None => format!("{index:04X}h:{sub:02X}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn object_arguments_are_hex_and_errors_give_an_example() {
        assert_eq!(object_args("1018", "1", "x").unwrap(), (0x1018, 1));
        assert_eq!(object_args("0x1A00", "0Ah", "x").unwrap(), (0x1A00, 0x0A));
        let err = object_args("10180", "1", "canopener sdo read --node 5 1018 1").unwrap_err();
        assert_eq!(err.exit_code(), 2);
        let text = err.to_string();
        assert!(
            text.starts_with("INDEX: `10180` is not an object index"),
            "{text}"
        );
        assert!(
            text.ends_with("e.g. canopener sdo read --node 5 1018 1"),
            "{text}"
        );
        let err = object_args("1018", "100", "x").unwrap_err();
        assert!(
            err.to_string().starts_with("SUB: `100` is not a sub-index"),
            "{err}"
        );
    }

    #[test]
    fn labels_show_the_name_when_known() {
        assert_eq!(labelled(0x1018, 1, Some("Vendor-ID")), "1018h:01 Vendor-ID");
        assert_eq!(labelled(0x1018, 1, Some("")), "1018h:01");
        assert_eq!(labelled(0x2000, 0x1F, None), "2000h:1F");
    }
}

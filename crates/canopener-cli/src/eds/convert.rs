//! `canopener eds convert`: EDS ⇄ DCF ⇄ XDD/XDC ⇄ JSON.

use canopener_eds::text::{Encoding, encode};
use canopener_eds::{dcf, json, write};

use crate::eds::args::{ConvertTarget, EdsConvertArgs};
use crate::eds::input::{Input, SourceFormat, print_stdout, read_input, report_diagnostics};
use crate::error::{CliError, CliResult};
use canopener_runtime::files::{same_file, write_atomic};

pub(crate) fn run(args: EdsConvertArgs) -> CliResult {
    if args.to != ConvertTarget::Dcf && (args.node_id.is_some() || args.bitrate.is_some()) {
        return Err(CliError::EdsTrouble(
            "--node-id and --bitrate only apply to `--to dcf`".to_owned(),
        ));
    }
    if let Some(out) = &args.output
        && same_file(out, &args.file)
    {
        return Err(CliError::EdsTrouble(format!(
            "refusing to overwrite the input {} with -o; write elsewhere, or use `canopener eds fmt --in-place`",
            args.file.display()
        )));
    }
    let input = read_input(&args.file)?;
    report_diagnostics(&input, args.diagnostics)?;
    let bytes = match args.to {
        ConvertTarget::Json => format!("{}\n", json::to_json(&input.eds)).into_bytes(),
        ConvertTarget::Eds => {
            let eds = if input.eds.is_dcf() {
                dcf::to_eds(&input.eds)
            } else {
                input.eds.clone()
            };
            canonical_bytes(&input, &eds)?
        }
        ConvertTarget::Dcf => {
            let node = args
                .node_id
                .or_else(|| input.eds.node_id().map(u16::from))
                .ok_or_else(|| {
                    CliError::EdsTrouble(
                        "--node-id is required to make a DCF (the input has no node-ID)".to_owned(),
                    )
                })?;
            let bitrate = args
                .bitrate
                .or_else(|| {
                    let c = input.eds.commissioning.as_ref()?;
                    u16::try_from(canopener_eds::model::int_of(c.baudrate.as_deref()?)?).ok()
                })
                .ok_or_else(|| {
                    CliError::EdsTrouble(
                        "--bitrate is required to make a DCF (the input has no bit rate)".to_owned(),
                    )
                })?;
            let dcf =
                dcf::to_dcf(&input.eds, node, bitrate).map_err(|e| CliError::EdsTrouble(e.to_string()))?;
            if !dcf::supports_bitrate(&input.eds, bitrate) {
                eprintln!(
                    "warning: {} does not declare BaudRate_{bitrate}=1; the device may not support {bitrate} kbit/s",
                    args.file.display()
                );
            }
            canonical_bytes(&input, &dcf)?
        }
        ConvertTarget::Xdd => crate::eds::input_xdd::write(&input.eds)?.into_bytes(),
    };
    match &args.output {
        Some(out) => Ok(write_atomic(out, &bytes, false)?),
        None => print_stdout(&String::from_utf8_lossy(&bytes)),
    }
}

/// Canonical CiA 306 text in the input's own encoding (a Windows-1252 file stays Windows-1252; no BOM).
pub(crate) fn canonical_bytes(input: &Input, eds: &canopener_eds::Eds) -> CliResult<Vec<u8>> {
    let text = write::to_canonical(eds, input.document.as_ref());
    let encoding = match input.document.as_ref().map(canopener_eds::Document::encoding) {
        Some(Encoding::Windows1252) if input.format == SourceFormat::Eds => Encoding::Windows1252,
        _ => Encoding::Utf8,
    };
    encode(&text, encoding).map_err(|e| CliError::EdsTrouble(format!("{}: {e}", input.path.display())))
}

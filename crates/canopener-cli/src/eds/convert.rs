//! `canopener eds convert`: EDS ⇄ DCF ⇄ XDD/XDC ⇄ JSON.

use canopener_description::convert::{ConvertError, Target, convert};
use canopener_files::{same_file, write_atomic};

use crate::eds::args::{ConvertTarget, EdsConvertArgs};
use crate::eds::input::{read_input, report_diagnostics};
use crate::error::{CliError, CliResult};
use crate::output::print_stdout;

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
    report_diagnostics(&args.file, &input, args.diagnostics);
    let target = match args.to {
        ConvertTarget::Json => Target::Json,
        ConvertTarget::Eds => Target::Eds,
        ConvertTarget::Dcf => Target::Dcf {
            node_id: args.node_id,
            bitrate: args.bitrate,
        },
        ConvertTarget::Xdd => Target::Xdd,
    };
    let converted = convert(&input, target).map_err(|e| match e {
        ConvertError::NoNodeId => {
            CliError::EdsTrouble("--node-id is required to make a DCF (the input has no node-ID)".to_owned())
        }
        ConvertError::NoBitrate => {
            CliError::EdsTrouble("--bitrate is required to make a DCF (the input has no bit rate)".to_owned())
        }
        ConvertError::Dcf(e) => CliError::EdsTrouble(e.to_string()),
        ConvertError::Encoding(e) => CliError::EdsTrouble(format!("{}: {e}", args.file.display())),
    })?;
    if let Some(bitrate) = converted.undeclared_bitrate {
        eprintln!(
            "warning: {} does not declare BaudRate_{bitrate}=1; the device may not support {bitrate} kbit/s",
            args.file.display()
        );
    }
    if !converted.dropped.is_empty() {
        eprintln!(
            "warning: {} is a configuration; an EDS carries none of it, so {} DCF {} dropped: {}; \
             `--to dcf` keeps them",
            args.file.display(),
            converted.dropped.len(),
            if converted.dropped.len() == 1 {
                "key was"
            } else {
                "keys were"
            },
            summary(&converted.dropped)
        );
    }
    match &args.output {
        Some(out) => Ok(write_atomic(out, &converted.bytes, false)?),
        None => print_stdout(&String::from_utf8_lossy(&converted.bytes)),
    }
}

/// The first few dropped keys, and how many more.
fn summary(keys: &[String]) -> String {
    const SHOWN: usize = 5;
    let mut text = keys.iter().take(SHOWN).cloned().collect::<Vec<_>>().join(", ");
    if keys.len() > SHOWN {
        text.push_str(&format!(" and {} more", keys.len() - SHOWN));
    }
    text
}

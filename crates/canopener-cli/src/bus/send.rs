//! `canopener bus send`: put frames given on the command line onto a bus.

use canopener_can::candump::parse_compact_frame;
use canopener_link::cancel::Cancel;
use canopener_runtime::send::send_frames;

use crate::bus::args::SendArgs;
use crate::bus_open::open_bus;
use crate::error::{CliError, CliResult};

pub(crate) fn run(args: SendArgs) -> CliResult {
    // Parse every frame before touching the bus, so a typo in the fifth frame doesn't send the first four.
    let frames = args
        .frames
        .iter()
        .enumerate()
        .map(|(idx, text)| {
            parse_compact_frame(text).map_err(|err| {
                CliError::InvalidInput(format!(
                    "frame {} '{text}' is not valid: {}",
                    idx + 1,
                    err.message
                ))
            })
        })
        .collect::<CliResult<Vec<_>>>()?;
    let mut bus = open_bus(args.bus.spec.as_deref(), "bus send")?;
    // No Ctrl-C handler: `bus send` has always ended at once on a signal, like any short shell command,
    // so its token is never cancelled.
    send_frames(&mut *bus, &frames, args.repeat, args.gap, &Cancel::new())?;
    Ok(())
}

//! `canopener bus send`: put frames given on the command line onto a bus.

use std::thread;

use canopener_can::candump::parse_compact_frame;

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
    let mut first = true;
    for _ in 0..args.repeat {
        for frame in &frames {
            if !first && !args.gap.is_zero() {
                thread::sleep(args.gap);
            }
            first = false;
            bus.send(frame)?;
        }
    }
    Ok(())
}

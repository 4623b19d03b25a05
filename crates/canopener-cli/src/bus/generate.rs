//! `canopener bus gen`: generate counting frames at a fixed rate or as fast as the bus takes them.

use canopener_can::CanId;
use canopener_runtime::generate::{GenerateError, Generator, generate};

use crate::bus::args::GenArgs;
use crate::bus_open::open_bus;
use crate::error::{CliError, CliResult};
use crate::stop::StopFlag;

pub(crate) fn run(args: GenArgs) -> CliResult {
    let generator = Generator {
        id: parse_hex_id(&args.id)?,
        dlc: args.dlc,
        rate: args.rate,
        count: args.count,
        duration: args.duration,
    };
    generator.validate().map_err(|err| generate_error(err, &args))?;
    let stop = StopFlag::install()?;
    let mut bus = open_bus(args.bus.spec.as_deref(), "bus gen")?;
    let summary = generate(&mut *bus, &generator, &stop.token()).map_err(|err| generate_error(err, &args))?;
    eprintln!(
        "sent {} frames in {:.3} s ({:.0} frames/s)",
        summary.sent,
        summary.elapsed.as_secs_f64(),
        summary.frames_per_second()
    );
    Ok(())
}

/// The generator's refusals in terms of the options the user gave.
fn generate_error(err: GenerateError, args: &GenArgs) -> CliError {
    match err {
        GenerateError::DlcTooLarge(_) => CliError::Usage(format!(
            "--dlc {} is above 8, the classical CAN maximum",
            args.dlc
        )),
        GenerateError::BadRate(_) => CliError::Usage(format!(
            "--rate {} must be a non-negative number of frames/s",
            args.rate
        )),
        GenerateError::Endless => CliError::Usage(
            "give --count N or --duration D (or both), so the generator knows when to stop".into(),
        ),
        GenerateError::Bus(err) => CliError::Bus(err),
    }
}

/// `123` is a standard id; 8 digits or a value above 0x7FF is an extended id.
pub(crate) fn parse_hex_id(text: &str) -> CliResult<CanId> {
    let digits = text.trim().trim_start_matches("0x").trim_start_matches("0X");
    let raw = u32::from_str_radix(digits, 16).map_err(|_| {
        CliError::Usage(format!(
            "--id '{text}' is not a hexadecimal CAN id (e.g. 123 or 1ABCDEF0)"
        ))
    })?;
    let id = if digits.len() == 8 || raw > 0x7FF {
        CanId::extended(raw)
    } else {
        CanId::standard(raw as u16)
    };
    id.map_err(|err| CliError::Usage(format!("--id '{text}': {err}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_follow_candump_digit_rules() {
        assert_eq!(parse_hex_id("123").unwrap(), CanId::standard(0x123).unwrap());
        assert_eq!(parse_hex_id("0x7FF").unwrap(), CanId::standard(0x7FF).unwrap());
        assert_eq!(parse_hex_id("00000123").unwrap(), CanId::extended(0x123).unwrap());
        assert_eq!(parse_hex_id("800").unwrap(), CanId::extended(0x800).unwrap());
        assert!(parse_hex_id("20000000").is_err());
        assert!(parse_hex_id("xyz").is_err());
    }
}

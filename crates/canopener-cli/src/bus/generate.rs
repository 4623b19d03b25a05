//! `canopener bus gen`: generate counting frames at a fixed rate or as fast as the bus takes them.

use std::time::{Duration, Instant};

use canopener_can::{CanFrame, CanId};

use crate::bus::args::GenArgs;
use crate::bus_open::open_bus;
use crate::error::{CliError, CliResult};
use crate::stop::StopFlag;

pub(crate) fn run(args: GenArgs) -> CliResult {
    let id = parse_hex_id(&args.id)?;
    if args.dlc > 8 {
        return Err(CliError::Usage(format!(
            "--dlc {} is above 8, the classical CAN maximum",
            args.dlc
        )));
    }
    if !args.rate.is_finite() || args.rate < 0.0 {
        return Err(CliError::Usage(format!(
            "--rate {} must be a non-negative number of frames/s",
            args.rate
        )));
    }
    if args.count.is_none() && args.duration.is_none() {
        return Err(CliError::Usage(
            "give --count N or --duration D (or both), so the generator knows when to stop".into(),
        ));
    }
    let stop = StopFlag::install()?;
    let mut bus = open_bus(args.bus.spec.as_deref(), "bus gen")?;
    let interval = (args.rate > 0.0).then(|| Duration::from_secs_f64(1.0 / args.rate));
    let started = Instant::now();
    let mut sent: u64 = 0;
    let mut data = [0u8; 8];
    while !stop.is_set() {
        if args.count.is_some_and(|count| sent >= count)
            || args
                .duration
                .is_some_and(|duration| started.elapsed() >= duration)
        {
            break;
        }
        if let Some(interval) = interval {
            // Absolute schedule: a late wake-up is caught up instead of lowering the average rate.
            let due = started + interval.mul_f64(sent as f64);
            let now = Instant::now();
            if due > now {
                std::thread::sleep(due - now);
            }
        }
        data[..4].copy_from_slice(&(sent as u32).to_le_bytes());
        data[4..].copy_from_slice(&((sent >> 32) as u32).to_le_bytes());
        let frame = CanFrame::new(id, &data[..usize::from(args.dlc)])
            .map_err(|err| CliError::Internal(anyhow::anyhow!("building a generated frame: {err}")))?;
        bus.send(&frame)?;
        sent += 1;
    }
    let elapsed = started.elapsed().as_secs_f64();
    eprintln!(
        "sent {sent} frames in {elapsed:.3} s ({:.0} frames/s)",
        if elapsed > 0.0 { sent as f64 / elapsed } else { 0.0 }
    );
    Ok(())
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

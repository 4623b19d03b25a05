//! Parsing and writing the fields that several elements share: identifiers, lengths, data and
//! timestamps (socketcand `doc/protocol.md`, "Mode RAW", and `src/state_raw.c`; the byte-exact forms
//! python-can accepts are in the interop reference §3).
//!
//! Writers append ASCII to a `Vec<u8>` without `format!`, because the hub writes every delivered
//! frame through them.

use canopener_can::{CanId, Instant, MAX_CLASSIC_DATA_LEN};

use crate::error::{CommandError, quote};

const HEX_UPPER: &[u8; 16] = b"0123456789ABCDEF";
const NANOS_PER_SEC: u64 = 1_000_000_000;

/// The tokens of an element: the text between `<` and `>`, split on ASCII whitespace.
///
/// socketcand parses with `sscanf` patterns whose spaces match any run of whitespace, so single,
/// double or missing spaces next to the brackets are all accepted; python-can's own
/// `< send 123 0  >` (two spaces) relies on that.
pub(crate) fn tokens(element: &str) -> Result<std::str::SplitAsciiWhitespace<'_>, CommandError> {
    let inner = element
        .strip_prefix('<')
        .and_then(|rest| rest.strip_suffix('>'))
        .ok_or_else(|| CommandError::NotAnElement {
            element: quote(element),
        })?;
    Ok(inner.split_ascii_whitespace())
}

/// The next token, or an error naming the missing field.
pub(crate) fn required<'a>(
    tokens: &mut impl Iterator<Item = &'a str>,
    element: &str,
    field: &'static str,
) -> Result<&'a str, CommandError> {
    tokens.next().ok_or_else(|| CommandError::MissingField {
        element: quote(element),
        field,
    })
}

/// Fails when tokens are left over.
pub(crate) fn finished<'a>(tokens: impl Iterator<Item = &'a str>, element: &str) -> Result<(), CommandError> {
    let junk: Vec<&str> = tokens.collect();
    if junk.is_empty() {
        Ok(())
    } else {
        Err(CommandError::TrailingJunk {
            element: quote(element),
            junk: quote(&junk.join(" ")),
        })
    }
}

fn hex_value(token: &str) -> Option<u32> {
    // `from_str_radix` alone would accept a leading '+'.
    if token.is_empty() || token.len() > 8 || !token.bytes().all(|b| b.is_ascii_hexdigit()) {
        return None;
    }
    u32::from_str_radix(token, 16).ok()
}

/// A client identifier as socketcand's `state_raw.c` reads it: extended iff exactly 8 characters.
pub(crate) fn parse_client_id(token: &str, element: &str) -> Result<CanId, CommandError> {
    let raw = hex_value(token).ok_or_else(|| CommandError::IdNotHex {
        element: quote(element),
        token: quote(token),
    })?;
    if token.len() == 8 {
        CanId::extended(raw).map_err(|_| CommandError::ExtendedIdTooLarge {
            element: quote(element),
            token: token.to_owned(),
        })
    } else {
        u16::try_from(raw)
            .ok()
            .and_then(|raw| CanId::standard(raw).ok())
            .ok_or_else(|| CommandError::StandardIdTooLarge {
                element: quote(element),
                token: token.to_owned(),
            })
    }
}

/// A server identifier: exactly 3 or 8 digits, since python-can takes any other width as extended.
pub(crate) fn parse_server_id(token: &str, element: &str) -> Result<CanId, CommandError> {
    if token.len() != 3 && token.len() != 8 {
        return Err(CommandError::IdWidth {
            element: quote(element),
            token: quote(token),
        });
    }
    parse_client_id(token, element)
}

/// A length or DLC: decimal 0–8 (socketcand `%hhu`; python-can's hex `{dlc:X}` is identical there).
pub(crate) fn parse_len(token: &str, element: &str) -> Result<u8, CommandError> {
    let bad = || CommandError::BadLength {
        element: quote(element),
        token: quote(token),
    };
    if token.is_empty() || token.len() > 2 || !token.bytes().all(|b| b.is_ascii_digit()) {
        return Err(bad());
    }
    match token.parse::<u8>() {
        Ok(len) if usize::from(len) <= MAX_CLASSIC_DATA_LEN => Ok(len),
        _ => Err(bad()),
    }
}

/// One data byte of a `send`: 1 or 2 hex digits, either case (socketcand `%hhx`).
pub(crate) fn parse_send_byte(token: &str, element: &str) -> Result<u8, CommandError> {
    let bad = || CommandError::BadDataByte {
        element: quote(element),
        token: quote(token),
    };
    if token.len() > 2 {
        return Err(bad());
    }
    hex_value(token)
        .and_then(|value| u8::try_from(value).ok())
        .ok_or_else(bad)
}

/// Contiguous frame data as `state_raw.c` writes it (`%02X` per byte), at most 8 bytes.
pub(crate) fn parse_frame_data(
    token: &str,
    element: &str,
) -> Result<([u8; MAX_CLASSIC_DATA_LEN], usize), CommandError> {
    let bad = || CommandError::BadFrameData {
        element: quote(element),
        token: quote(token),
    };
    let digits = token.as_bytes();
    if !digits.len().is_multiple_of(2) || digits.len() > 2 * MAX_CLASSIC_DATA_LEN {
        return Err(bad());
    }
    let mut data = [0; MAX_CLASSIC_DATA_LEN];
    for (slot, pair) in data.iter_mut().zip(digits.chunks_exact(2)) {
        let pair = std::str::from_utf8(pair).map_err(|_| bad())?;
        *slot = hex_value(pair)
            .and_then(|value| u8::try_from(value).ok())
            .ok_or_else(bad)?;
    }
    Ok((data, digits.len() / 2))
}

/// An error class: hex, at most 8 digits.
pub(crate) fn parse_error_class(token: &str, element: &str) -> Result<u32, CommandError> {
    hex_value(token).ok_or_else(|| CommandError::BadErrorClass {
        element: quote(element),
        token: quote(token),
    })
}

/// `SECS.FRACTION`: socketcand writes `%ld.%06ld`; 1 to 9 fraction digits are accepted.
pub(crate) fn parse_timestamp(token: &str, element: &str) -> Result<Instant, CommandError> {
    let bad = || CommandError::BadTimestamp {
        element: quote(element),
        token: quote(token),
    };
    let (secs, fraction) = token.split_once('.').ok_or_else(bad)?;
    let all_digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if !all_digits(secs) || !all_digits(fraction) || fraction.len() > 9 || secs.len() > 20 {
        return Err(bad());
    }
    let secs: u64 = secs.parse().map_err(|_| bad())?;
    let mut nanos: u64 = fraction.parse().map_err(|_| bad())?;
    for _ in fraction.len()..9 {
        nanos *= 10;
    }
    secs.checked_mul(NANOS_PER_SEC)
        .and_then(|whole| whole.checked_add(nanos))
        .map(Instant::from_nanos)
        .ok_or_else(bad)
}

/// Whether socketcand would open a bus of this name: 1–16 characters of `[A-Za-z0-9_.-]`.
///
/// socketcand limits names to 16 characters (`IFNAMSIZ`) and only opens interfaces it was given;
/// the character set keeps names safe to print in logs and to use as map keys.
pub fn is_valid_bus_name(name: &str) -> bool {
    (1..=16).contains(&name.len())
        && name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'.' || b == b'-')
}

/// `%03X` for standard, `%08X` for extended identifiers.
pub(crate) fn push_id(out: &mut Vec<u8>, id: CanId) {
    let (raw, width) = match id {
        CanId::Standard(id) => (u32::from(id.as_raw()), 3),
        CanId::Extended(id) => (id.as_raw(), 8),
    };
    for shift in (0..width).rev() {
        out.push(hex_digit(raw >> (4 * shift)));
    }
}

/// The upper-case hex digit of the low 4 bits of `value`.
#[allow(
    clippy::indexing_slicing,
    reason = "masked to 4 bits, the index is below the table's 16 entries"
)]
fn hex_digit(value: u32) -> u8 {
    HEX_UPPER[(value & 0xF) as usize]
}

/// `%02X`.
pub(crate) fn push_hex_byte(out: &mut Vec<u8>, byte: u8) {
    out.push(hex_digit(u32::from(byte >> 4)));
    out.push(hex_digit(u32::from(byte)));
}

/// A number in decimal.
#[allow(
    clippy::indexing_slicing,
    reason = "20 digits hold u64::MAX, so `start` stays inside `digits`"
)]
pub(crate) fn push_decimal(out: &mut Vec<u8>, mut value: u64) {
    // u64::MAX has 20 decimal digits, so `start` never goes below zero.
    let mut digits = [0u8; 20];
    let mut start = digits.len();
    loop {
        start -= 1;
        // `value % 10` is below 10, so the cast cannot truncate.
        digits[start] = b'0' + (value % 10) as u8;
        value /= 10;
        if value == 0 {
            break;
        }
    }
    out.extend_from_slice(digits.get(start..).unwrap_or_default());
}

/// `SECS.USECS` with six fraction digits (`%ld.%06ld`); sub-microsecond parts are truncated.
pub(crate) fn push_timestamp(out: &mut Vec<u8>, timestamp: Instant) {
    push_decimal(out, timestamp.secs());
    out.push(b'.');
    let micros = timestamp.subsec_micros();
    let mut divisor = 100_000;
    while divisor > 0 {
        // Each digit is below 10.
        out.push(b'0' + ((micros / divisor) % 10) as u8);
        divisor /= 10;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn client_id_width_decides_the_format() {
        assert_eq!(parse_client_id("12", "e"), Ok(CanId::standard(0x12).unwrap()));
        assert_eq!(parse_client_id("0123", "e"), Ok(CanId::standard(0x123).unwrap()));
        assert_eq!(
            parse_client_id("00000012", "e"),
            Ok(CanId::extended(0x12).unwrap())
        );
        assert!(matches!(
            parse_client_id("800", "e"),
            Err(CommandError::StandardIdTooLarge { .. })
        ));
        assert!(matches!(
            parse_client_id("20000000", "e"),
            Err(CommandError::ExtendedIdTooLarge { .. })
        ));
        assert!(matches!(
            parse_client_id("+12", "e"),
            Err(CommandError::IdNotHex { .. })
        ));
        assert!(matches!(
            parse_client_id("123456789", "e"),
            Err(CommandError::IdNotHex { .. })
        ));
    }

    #[test]
    fn server_ids_must_be_three_or_eight_digits() {
        assert!(matches!(
            parse_server_id("12", "e"),
            Err(CommandError::IdWidth { .. })
        ));
        assert_eq!(parse_server_id("7ff", "e"), Ok(CanId::standard(0x7FF).unwrap()));
    }

    #[test]
    fn lengths_are_decimal_zero_to_eight() {
        assert_eq!(parse_len("8", "e"), Ok(8));
        assert_eq!(parse_len("08", "e"), Ok(8));
        for bad in ["9", "A", "", "+1", "-0", "100"] {
            assert!(parse_len(bad, "e").is_err(), "{bad}");
        }
    }

    #[test]
    fn send_bytes_take_one_or_two_digits_of_either_case() {
        assert_eq!(parse_send_byte("f", "e"), Ok(0x0F));
        assert_eq!(parse_send_byte("aB", "e"), Ok(0xAB));
        for bad in ["", "100", "g", "+f", "0x"] {
            assert!(parse_send_byte(bad, "e").is_err(), "{bad}");
        }
    }

    #[test]
    fn frame_data_is_contiguous_even_hex() {
        assert_eq!(
            parse_frame_data("01F1", "e"),
            Ok(([1, 0xF1, 0, 0, 0, 0, 0, 0], 2))
        );
        for bad in ["1", "0G", "001122334455667788", "+1"] {
            assert!(parse_frame_data(bad, "e").is_err(), "{bad}");
        }
    }

    #[test]
    fn timestamps_parse_with_any_fraction_width_and_reject_overflow() {
        assert_eq!(parse_timestamp("1.5", "e"), Ok(Instant::from_millis(1500)));
        assert_eq!(
            parse_timestamp("1795335844.491054", "e"),
            Ok(Instant::from_micros(1_795_335_844_491_054))
        );
        assert_eq!(parse_timestamp("0.000000001", "e"), Ok(Instant::from_nanos(1)));
        for bad in [
            "1",
            ".5",
            "1.",
            "1.0000000001",
            "18446744074.000000",
            "1.-5",
            "1,5",
            "+1.0",
        ] {
            assert!(parse_timestamp(bad, "e").is_err(), "{bad}");
        }
    }

    #[test]
    fn writers_produce_fixed_width_uppercase() {
        let mut out = Vec::new();
        push_id(&mut out, CanId::standard(0x1).unwrap());
        out.push(b' ');
        push_id(&mut out, CanId::extended(0x1AAA_AAAA).unwrap());
        out.push(b' ');
        push_timestamp(&mut out, Instant::from_nanos(7_000_000_999));
        out.push(b' ');
        push_hex_byte(&mut out, 0xF);
        out.push(b' ');
        push_decimal(&mut out, u64::MAX);
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "001 1AAAAAAA 7.000000 0F 18446744073709551615"
        );
    }

    #[test]
    fn bus_names() {
        for good in ["can0", "a", "vcan-1.x_y", "0123456789abcdef"] {
            assert!(is_valid_bus_name(good), "{good}");
        }
        for bad in ["", "0123456789abcdefg", "can 0", "can/0", "cän"] {
            assert!(!is_valid_bus_name(bad), "{bad}");
        }
    }
}

//! The can-utils log format, as written by `candump -l` and read by `canplayer`.
//!
//! One frame per line: `(1436509052.249713) can0 123#DEADBEEF`. The frame part is the can-utils
//! compact form (`lib.c`): a 3-digit standard or 8-digit extended id, `#`, then the data as hex pairs
//! (optionally separated by `.`), or `R` with an optional DLC digit for a remote frame. An 8-digit id
//! with the SocketCAN error flag `0x20000000` set is an error frame, not a data frame. A trailing
//! `_<dlc>` after 8 data bytes carries a raw classical DLC of 9 to 15 (`len8_dlc`). CAN FD frames
//! (`123##<flags><data>`) are rejected with a clear error until canopener supports CAN FD.
//!
//! python-can and `asc2log` append a direction token (`R` or `T`) after the frame; it is accepted and
//! ignored, because the log format has no field for it.
//!
//! Everything here is pure text processing: no file or clock access. Parsing never panics, whatever
//! the input (non-UTF-8 callers convert lossily first), and [`parse_log`] never fails as a whole: it
//! keeps every good line and reports each bad one with its line and column.

use std::fmt;

use crate::frame::{CanFrame, MAX_CLASSIC_DATA_LEN};
use crate::id::{CanId, ExtendedId, StandardId};
use crate::time::Instant;

/// The SocketCAN flag (`CAN_ERR_FLAG`) that marks an error frame in the 32-bit id word.
pub const CAN_ERR_FLAG: u32 = 0x2000_0000;
/// The bits of an error frame's id word that hold the error class (`CAN_ERR_MASK`).
pub const CAN_ERR_MASK: u32 = 0x1FFF_FFFF;

/// What one log line carries.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum LogEvent {
    /// A classical CAN data or remote frame.
    Frame(CanFrame),
    /// A SocketCAN error frame: not a frame on the bus but the controller's report of a bus error.
    ErrorFrame {
        /// The error class bits (`can_id & CAN_ERR_MASK`, see linux/can/error.h).
        class: u32,
        /// The error details, at most 8 bytes.
        data: Vec<u8>,
    },
}

/// One line of a candump log.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct LogRecord {
    /// When the frame was seen. candump writes microseconds since the Unix epoch.
    pub timestamp: Instant,
    /// The interface name, e.g. `can0`. To be written back it must be a non-empty token without
    /// whitespace.
    pub interface: String,
    /// The frame or error frame.
    pub event: LogEvent,
}

/// A problem with one line of a log or with a compact frame.
///
/// `line` and `column` are 1-based; the column counts characters, not bytes. For a single line
/// ([`parse_record`]) or a single frame ([`parse_compact_frame`]) the line is 1.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("line {line}, column {column}: {message}")]
pub struct LogError {
    /// The 1-based line number.
    pub line: usize,
    /// The 1-based character column where the problem starts.
    pub column: usize,
    /// What is wrong and how to fix it.
    pub message: String,
}

/// Parses a whole log.
///
/// Returns every record with its 1-based line number, and every problem found. Blank lines and lines
/// starting with `#` are skipped. A bad line is reported and skipped; it never hides the good lines
/// around it. The problem list also contains notes about lines that were accepted with a loss of
/// information (a `_<dlc>` raw DLC suffix), so a caller can tell the user what was dropped.
pub fn parse_log(text: &str) -> (Vec<(usize, LogRecord)>, Vec<LogError>) {
    let mut records = Vec::new();
    let mut problems = Vec::new();
    for (line_idx, line) in text.split('\n').enumerate() {
        let line_no = line_idx + 1;
        match parse_line(line) {
            Ok(None) => {}
            Ok(Some(parsed)) => {
                if let Some(note) = parsed.note {
                    problems.push(note.at_line(line_no));
                }
                records.push((line_no, parsed.record));
            }
            Err(err) => problems.push(err.at_line(line_no)),
        }
    }
    (records, problems)
}

/// Parses one log line.
///
/// Returns `Ok(None)` for a blank line or a `#` comment. A trailing `\r` and trailing whitespace are
/// ignored. A raw DLC suffix (`_E`) is accepted silently here; use [`parse_log`] to be told about it.
pub fn parse_record(line: &str) -> Result<Option<LogRecord>, LogError> {
    parse_line(line).map(|parsed| parsed.map(|parsed| parsed.record))
}

/// Parses a frame in compact form, such as `601#4000100000000000`, `123#DE.AD.BE.EF`, `123#R` or
/// `1ABCDEF0#R8`, as given on a command line.
///
/// Surrounding whitespace is ignored. Error frames cannot be built from this form because they are
/// not CAN frames. A raw DLC suffix (`_E`) is accepted and dropped: the frame has DLC 8.
pub fn parse_compact_frame(text: &str) -> Result<CanFrame, LogError> {
    let bytes = text.as_bytes();
    let start = skip_blanks(bytes, 0);
    let end = bytes.len() - count_trailing_whitespace(bytes);
    if start >= end {
        return Err(LogError::new(
            bytes,
            start,
            "expected a frame such as 601#4000100000000000 (id, '#', data as hex pairs) or 701#R",
        ));
    }
    let (event, _note) = parse_frame_token(bytes, start, end)?;
    match event {
        LogEvent::Frame(frame) => Ok(frame),
        LogEvent::ErrorFrame { .. } => Err(LogError::new(
            bytes,
            start,
            "an 8-digit id with bit 0x20000000 set is a SocketCAN error frame, which cannot be sent; \
             extended ids go up to 1FFFFFFF",
        )),
    }
}

/// Appends `record` to `out` exactly as `candump -l` writes it, followed by a newline:
/// `(1436509052.249713) can0 123#DEADBEEF`.
///
/// The seconds are zero-padded to 10 digits and the fraction is written in microseconds, as candump
/// does; sub-microsecond precision is dropped. An error frame writes its class with the error flag as
/// an 8-digit id and at most 8 data bytes (extra bytes and class bits above 29 bits are dropped, so
/// that the line always reads back).
pub fn write_record(out: &mut String, record: &LogRecord) {
    use fmt::Write as _;
    // Writing into a String cannot fail.
    let _ = writeln!(out, "{record}");
}

/// The candump log line without the newline; see [`write_record`].
impl fmt::Display for LogRecord {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "({:010}.{:06}) {} ",
            self.timestamp.secs(),
            self.timestamp.subsec_micros(),
            self.interface
        )?;
        match &self.event {
            LogEvent::Frame(frame) => write!(f, "{frame}"),
            LogEvent::ErrorFrame { class, data } => {
                write!(f, "{:08X}#", CAN_ERR_FLAG | (class & CAN_ERR_MASK))?;
                for byte in data.iter().take(MAX_CLASSIC_DATA_LEN) {
                    write!(f, "{byte:02X}")?;
                }
                Ok(())
            }
        }
    }
}

impl LogError {
    /// An error at byte offset `at` of `line`; the line number is filled in by the caller.
    fn new(line: &[u8], at: usize, message: impl Into<String>) -> LogError {
        LogError {
            line: 1,
            column: char_column(line, at),
            message: message.into(),
        }
    }

    fn at_line(self, line: usize) -> LogError {
        LogError { line, ..self }
    }
}

/// A successfully parsed line, with an optional note about information that was dropped.
struct ParsedLine {
    record: LogRecord,
    note: Option<LogError>,
}

/// The most characters of a bad token quoted back in an error message, so that a megabyte-long line
/// does not produce a megabyte-long message.
const MAX_QUOTED_CHARS: usize = 24;

fn parse_line(line: &str) -> Result<Option<ParsedLine>, LogError> {
    let bytes = line.as_bytes();
    let end = bytes.len() - count_trailing_whitespace(bytes);
    let mut pos = skip_blanks(bytes, 0);
    if pos >= end || bytes.get(pos) == Some(&b'#') {
        return Ok(None);
    }

    let timestamp = parse_timestamp(bytes, &mut pos, end)?;

    let after_timestamp = pos;
    pos = skip_blanks(bytes, pos);
    if pos == after_timestamp || pos >= end {
        return Err(LogError::new(
            bytes,
            pos,
            "expected a space and an interface name after the timestamp, \
             as in (1436509052.249713) can0 123#DEADBEEF",
        ));
    }
    let interface_start = pos;
    pos = token_end(bytes, pos, end);
    // Both ends are at ASCII bytes or the end of the text, so the slice is on character boundaries.
    let interface = line.get(interface_start..pos).unwrap_or_default().to_owned();

    pos = skip_blanks(bytes, pos);
    if pos >= end {
        return Err(LogError::new(
            bytes,
            pos,
            "expected a frame such as 123#DEADBEEF after the interface name",
        ));
    }
    let frame_start = pos;
    pos = token_end(bytes, pos, end);
    let (event, note) = parse_frame_token(bytes, frame_start, pos)?;

    pos = skip_blanks(bytes, pos);
    if pos < end {
        let extra_end = token_end(bytes, pos, end);
        let is_direction = extra_end == pos + 1 && matches!(bytes.get(pos), Some(b'R' | b'T'));
        if !is_direction || skip_blanks(bytes, extra_end) < end {
            return Err(LogError::new(
                bytes,
                pos,
                format!(
                    "unexpected text {} after the frame; a log line is (SECONDS.FRACTION) INTERFACE ID#DATA, \
                     optionally followed by R or T",
                    quote(line, pos, end)
                ),
            ));
        }
    }

    Ok(Some(ParsedLine {
        record: LogRecord {
            timestamp,
            interface,
            event,
        },
        note,
    }))
}

/// Parses `(SECONDS.FRACTION)` with 1 to 9 fraction digits.
fn parse_timestamp(bytes: &[u8], pos: &mut usize, end: usize) -> Result<Instant, LogError> {
    const EXAMPLE: &str = "(1436509052.249713)";
    if bytes.get(*pos) != Some(&b'(') || *pos >= end {
        return Err(LogError::new(
            bytes,
            *pos,
            format!("expected '(' to open the timestamp, as in {EXAMPLE} can0 123#DEADBEEF"),
        ));
    }
    *pos += 1;

    let secs_start = *pos;
    let mut secs: u64 = 0;
    let mut secs_overflow = false;
    while *pos < end {
        let Some(digit) = bytes.get(*pos).and_then(|b| decimal_value(*b)) else {
            break;
        };
        match secs.checked_mul(10).and_then(|s| s.checked_add(u64::from(digit))) {
            Some(value) => secs = value,
            None => secs_overflow = true,
        }
        *pos += 1;
    }
    if *pos == secs_start {
        return Err(LogError::new(
            bytes,
            *pos,
            format!("expected the seconds of the timestamp as decimal digits, as in {EXAMPLE}"),
        ));
    }
    if bytes.get(*pos) != Some(&b'.') || *pos >= end {
        return Err(LogError::new(
            bytes,
            *pos,
            format!("expected '.' between the seconds and the fraction of the timestamp, as in {EXAMPLE}"),
        ));
    }
    *pos += 1;

    let frac_start = *pos;
    let mut frac_nanos: u32 = 0;
    while *pos < end {
        let Some(digit) = bytes.get(*pos).and_then(|b| decimal_value(*b)) else {
            break;
        };
        let n_digits = *pos - frac_start;
        if n_digits >= 9 {
            return Err(LogError::new(
                bytes,
                *pos,
                "the timestamp fraction has more than 9 digits; at most nanoseconds (9 digits) are supported",
            ));
        }
        frac_nanos += u32::from(digit) * 10u32.pow(8 - n_digits as u32);
        *pos += 1;
    }
    if *pos == frac_start {
        return Err(LogError::new(
            bytes,
            *pos,
            format!("expected the fraction of the timestamp as decimal digits after '.', as in {EXAMPLE}"),
        ));
    }
    if bytes.get(*pos) != Some(&b')') || *pos >= end {
        return Err(LogError::new(
            bytes,
            *pos,
            format!("expected ')' to close the timestamp, as in {EXAMPLE}"),
        ));
    }
    *pos += 1;

    let nanos = if secs_overflow {
        None
    } else {
        secs.checked_mul(1_000_000_000)
            .and_then(|n| n.checked_add(u64::from(frac_nanos)))
    };
    match nanos {
        Some(nanos) => Ok(Instant::from_nanos(nanos)),
        None => Err(LogError::new(
            bytes,
            secs_start,
            format!(
                "the timestamp is too large; at most {} seconds (about the year 2554) are supported",
                u64::MAX / 1_000_000_000
            ),
        )),
    }
}

/// Parses the compact frame in `bytes[start..end]`, a token without whitespace.
fn parse_frame_token(
    bytes: &[u8],
    start: usize,
    end: usize,
) -> Result<(LogEvent, Option<LogError>), LogError> {
    let text_for_quotes = String::from_utf8_lossy(bytes);
    let mut pos = start;
    let mut id_value: u32 = 0;
    while pos < end {
        let Some(nibble) = bytes.get(pos).and_then(|b| hex_value(*b)) else {
            break;
        };
        // At most 9 digits are accumulated before the length check below rejects the id, and
        // shifting out the top bits of a wrong id is harmless because it is rejected by length.
        id_value = (id_value << 4) | u32::from(nibble);
        pos += 1;
    }
    let n_id_digits = pos - start;
    if pos >= end || bytes.get(pos) != Some(&b'#') {
        let message = if n_id_digits == 0 && pos < end {
            format!(
                "expected a CAN id of 3 or 8 hex digits, found {}",
                quote(&text_for_quotes, pos, end)
            )
        } else if pos >= end {
            "expected '#' after the CAN id, as in 123#DEADBEEF (or 123#R for a remote frame)".to_owned()
        } else {
            format!(
                "expected '#' after the CAN id, found {}; ids are hex digits, as in 123#DEADBEEF",
                quote_char(&text_for_quotes, pos)
            )
        };
        return Err(LogError::new(bytes, pos, message));
    }
    let id = match n_id_digits {
        3 => {
            // Three hex digits are at most 0xFFF, so the value fits in u16.
            let raw = id_value as u16;
            match StandardId::new(raw) {
                Some(id) => IdKind::Frame(CanId::Standard(id)),
                None => {
                    return Err(LogError::new(
                        bytes,
                        start,
                        format!(
                            "standard id 0x{raw:03X} exceeds 0x7FF; write 8 hex digits for an extended id \
                             (0000{raw:04X})"
                        ),
                    ));
                }
            }
        }
        8 => {
            if id_value & !(CAN_ERR_FLAG | CAN_ERR_MASK) != 0 {
                return Err(LogError::new(
                    bytes,
                    start,
                    format!(
                        "extended id 0x{id_value:08X} exceeds 0x1FFFFFFF (29 bits); only the error-frame \
                         flag 0x20000000 may be set above it"
                    ),
                ));
            }
            if id_value & CAN_ERR_FLAG != 0 {
                IdKind::Error(id_value & CAN_ERR_MASK)
            } else {
                match ExtendedId::new(id_value) {
                    Some(id) => IdKind::Frame(CanId::Extended(id)),
                    // Unreachable: bits above 28 were rejected or diverted to error frames above.
                    None => {
                        return Err(LogError::new(
                            bytes,
                            start,
                            format!("extended id 0x{id_value:08X} exceeds 0x1FFFFFFF"),
                        ));
                    }
                }
            }
        }
        0 => {
            return Err(LogError::new(
                bytes,
                start,
                "expected a CAN id of 3 or 8 hex digits before '#', as in 123#DEADBEEF",
            ));
        }
        n => {
            return Err(LogError::new(
                bytes,
                start,
                format!(
                    "a CAN id has 3 hex digits (standard, up to 7FF) or 8 (extended, up to 1FFFFFFF), \
                     found {n}; pad it with leading zeros"
                ),
            ));
        }
    };
    pos += 1; // the '#'

    match bytes.get(pos) {
        Some(b'#') if pos < end => {
            return Err(LogError::new(
                bytes,
                pos - 1,
                "CAN FD frames are not supported yet ('##' marks a CAN FD frame); only classical frames \
                 with up to 8 data bytes can be read",
            ));
        }
        Some(b'R') if pos < end => {
            return parse_remote(bytes, id, pos + 1, end);
        }
        _ => {}
    }

    let mut data = Vec::with_capacity(MAX_CLASSIC_DATA_LEN);
    let mut note = None;
    while pos < end {
        let Some(&byte) = bytes.get(pos) else { break };
        if byte == b'.' {
            let next_is_hex = pos + 1 < end && bytes.get(pos + 1).and_then(|b| hex_value(*b)).is_some();
            if data.is_empty() || !next_is_hex {
                return Err(LogError::new(
                    bytes,
                    pos,
                    "'.' may only separate two data bytes, as in 123#DE.AD.BE.EF",
                ));
            }
            pos += 1;
            continue;
        }
        if byte == b'_' {
            note = Some(parse_raw_dlc_suffix(
                bytes,
                pos,
                end,
                data.len(),
                &text_for_quotes,
            )?);
            break;
        }
        let Some(high) = hex_value(byte) else {
            return Err(LogError::new(
                bytes,
                pos,
                format!(
                    "unexpected {} in the data; write the data as pairs of hex digits, as in 123#DEADBEEF",
                    quote_char(&text_for_quotes, pos)
                ),
            ));
        };
        let low = if pos + 1 < end {
            bytes.get(pos + 1).and_then(|b| hex_value(*b))
        } else {
            None
        };
        let Some(low) = low else {
            return Err(LogError::new(
                bytes,
                pos,
                "odd number of hex digits in the data; every byte needs two digits (write 0A, not A)",
            ));
        };
        if data.len() == MAX_CLASSIC_DATA_LEN {
            return Err(LogError::new(
                bytes,
                pos,
                "a classical CAN frame carries at most 8 data bytes; this one has more",
            ));
        }
        data.push((high << 4) | low);
        pos += 2;
    }

    let event = match id {
        IdKind::Error(class) => LogEvent::ErrorFrame { class, data },
        IdKind::Frame(id) => match CanFrame::new(id, &data) {
            Ok(frame) => LogEvent::Frame(frame),
            // Unreachable: the loop above stops at 8 bytes.
            Err(err) => return Err(LogError::new(bytes, start, err.to_string())),
        },
    };
    Ok((event, note))
}

/// What the id part of a compact frame says the line is.
enum IdKind {
    Frame(CanId),
    Error(u32),
}

/// Parses what follows `#R`: an optional DLC digit 0–8 and, after DLC 8, an optional raw DLC suffix.
fn parse_remote(
    bytes: &[u8],
    id: IdKind,
    mut pos: usize,
    end: usize,
) -> Result<(LogEvent, Option<LogError>), LogError> {
    let IdKind::Frame(id) = id else {
        return Err(LogError::new(
            bytes,
            pos - 1,
            "an error frame (id with 0x20000000 set) cannot be a remote frame; give its data bytes instead",
        ));
    };
    let mut dlc = 0u8;
    if pos < end
        && let Some(digit) = bytes.get(pos).and_then(|b| hex_value(*b))
    {
        if usize::from(digit) > MAX_CLASSIC_DATA_LEN {
            return Err(LogError::new(
                bytes,
                pos,
                format!(
                    "a remote frame's DLC is 0 to 8, got {digit:X}; \
                     for a raw DLC of 9 to 15 write R8_{digit:X}"
                ),
            ));
        }
        dlc = digit;
        pos += 1;
    }
    let mut note = None;
    if pos < end {
        if bytes.get(pos) == Some(&b'_') {
            let text_for_quotes = String::from_utf8_lossy(bytes);
            note = Some(parse_raw_dlc_suffix(
                bytes,
                pos,
                end,
                usize::from(dlc),
                &text_for_quotes,
            )?);
        } else {
            let text_for_quotes = String::from_utf8_lossy(bytes);
            return Err(LogError::new(
                bytes,
                pos,
                format!(
                    "unexpected {} after R; a remote frame is written ID#R \
                     or ID#R followed by a DLC digit 0-8",
                    quote_char(&text_for_quotes, pos)
                ),
            ));
        }
    }
    match CanFrame::remote(id, dlc) {
        Ok(frame) => Ok((LogEvent::Frame(frame), note)),
        // Unreachable: the DLC was checked above.
        Err(err) => Err(LogError::new(bytes, pos, err.to_string())),
    }
}

/// Checks `_<dlc>` at `bytes[pos]` and returns the note that the raw DLC is dropped.
fn parse_raw_dlc_suffix(
    bytes: &[u8],
    pos: usize,
    end: usize,
    n_data: usize,
    text_for_quotes: &str,
) -> Result<LogError, LogError> {
    if n_data != MAX_CLASSIC_DATA_LEN {
        return Err(LogError::new(
            bytes,
            pos,
            format!(
                "the _<dlc> raw DLC suffix is only valid after 8 data bytes (or R8), found it after {n_data}"
            ),
        ));
    }
    let digit = if pos + 1 < end {
        bytes.get(pos + 1).and_then(|b| hex_value(*b))
    } else {
        None
    };
    match digit {
        Some(raw_dlc @ 9..=15) if pos + 2 == end => Ok(LogError::new(
            bytes,
            pos,
            format!(
                "raw DLC {raw_dlc} (suffix _{raw_dlc:X}) is not preserved; the frame is kept as a classical \
                 frame with DLC 8"
            ),
        )),
        _ => Err(LogError::new(
            bytes,
            pos,
            format!(
                "expected one hex digit 9 to F after '_' (a raw DLC of 9 to 15), found {}",
                quote(text_for_quotes, pos, end)
            ),
        )),
    }
}

fn hex_value(byte: u8) -> Option<u8> {
    match byte {
        b'0'..=b'9' => Some(byte - b'0'),
        b'a'..=b'f' => Some(byte - b'a' + 10),
        b'A'..=b'F' => Some(byte - b'A' + 10),
        _ => None,
    }
}

fn decimal_value(byte: u8) -> Option<u8> {
    byte.is_ascii_digit().then(|| byte - b'0')
}

fn is_blank(byte: u8) -> bool {
    byte == b' ' || byte == b'\t'
}

fn skip_blanks(bytes: &[u8], mut pos: usize) -> usize {
    while bytes.get(pos).is_some_and(|b| is_blank(*b)) {
        pos += 1;
    }
    pos
}

/// The end of the whitespace-free token starting at `pos`.
fn token_end(bytes: &[u8], mut pos: usize, end: usize) -> usize {
    while pos < end && bytes.get(pos).is_some_and(|b| !b.is_ascii_whitespace()) {
        pos += 1;
    }
    pos
}

fn count_trailing_whitespace(bytes: &[u8]) -> usize {
    bytes.iter().rev().take_while(|b| b.is_ascii_whitespace()).count()
}

/// The 1-based character column of byte offset `at`: the number of characters that start before it,
/// plus one. Counting UTF-8 lead bytes works even for an offset inside a character.
fn char_column(bytes: &[u8], at: usize) -> usize {
    bytes.iter().take(at).filter(|b| (**b & 0xC0) != 0x80).count() + 1
}

/// The character at byte offset `at`, quoted for a message.
fn quote_char(text: &str, at: usize) -> String {
    match text.get(at..).and_then(|rest| rest.chars().next()) {
        Some(c) => format!("{c:?}"),
        None => "a non-UTF-8 byte".to_owned(),
    }
}

/// The text from byte offset `from` to `to`, quoted and shortened for a message.
fn quote(text: &str, from: usize, to: usize) -> String {
    let Some(slice) = text.get(from..to.min(text.len())) else {
        return "unreadable text".to_owned();
    };
    let mut chars = slice.chars();
    let shown: String = chars.by_ref().take(MAX_QUOTED_CHARS).collect();
    if chars.next().is_some() {
        format!("'{shown}...'")
    } else {
        format!("'{shown}'")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::strategy::any_frame;
    use proptest::prelude::*;

    fn std_frame(id: u16, data: &[u8]) -> CanFrame {
        CanFrame::new(StandardId::new(id).unwrap(), data).unwrap()
    }

    fn record(line: &str) -> LogRecord {
        parse_record(line).unwrap().unwrap()
    }

    fn error(line: &str) -> LogError {
        parse_record(line).unwrap_err()
    }

    #[test]
    fn golden_lines_parse() {
        let rec = record("(1436509052.249713) can0 123#DEADBEEF");
        assert_eq!(
            rec.timestamp,
            Instant::from_secs_nanos(1_436_509_052, 249_713_000)
        );
        assert_eq!(rec.interface, "can0");
        assert_eq!(
            rec.event,
            LogEvent::Frame(std_frame(0x123, &[0xDE, 0xAD, 0xBE, 0xEF]))
        );

        assert_eq!(
            record("(0.1) vcan0 123#").event,
            LogEvent::Frame(std_frame(0x123, &[]))
        );
        assert_eq!(
            record("(0.1) x 123#de.ad.be.ef").event,
            record("(0.1) x 123#DEADBEEF").event
        );
        let ext = record("(1.000000) can1 1ABCDEF0#0102").event;
        let expected = CanFrame::new(ExtendedId::new(0x1ABC_DEF0).unwrap(), &[1, 2]).unwrap();
        assert_eq!(ext, LogEvent::Frame(expected));
        let short_ext = record("(1.0) can1 00000123#").event;
        assert_eq!(
            short_ext,
            LogEvent::Frame(CanFrame::new(ExtendedId::new(0x123).unwrap(), &[]).unwrap())
        );
    }

    #[test]
    fn remote_frames_parse_with_and_without_dlc() {
        let remote = |dlc| CanFrame::remote(StandardId::new(0x701).unwrap(), dlc).unwrap();
        assert_eq!(record("(1.0) can0 701#R").event, LogEvent::Frame(remote(0)));
        assert_eq!(record("(1.0) can0 701#R1").event, LogEvent::Frame(remote(1)));
        assert_eq!(record("(1.0) can0 701#R8").event, LogEvent::Frame(remote(8)));
        assert_eq!(error("(1.0) can0 701#R9").column, 17);
        assert!(error("(1.0) can0 701#RX").message.contains("after R"));
    }

    #[test]
    fn error_frames_are_a_distinct_kind() {
        let rec = record("(1.5) can0 20000004#0004000000000000");
        assert_eq!(
            rec.event,
            LogEvent::ErrorFrame {
                class: 4,
                data: vec![0, 4, 0, 0, 0, 0, 0, 0]
            }
        );
        assert_eq!(
            rec.to_string(),
            "(0000000001.500000) can0 20000004#0004000000000000"
        );
        assert!(
            error("(1.5) can0 20000004#R")
                .message
                .contains("cannot be a remote frame")
        );
    }

    #[test]
    fn timestamps_accept_one_to_nine_fraction_digits() {
        assert_eq!(record("(12.5) c 123#").timestamp, Instant::from_millis(12_500));
        assert_eq!(
            record("(12.000000001) c 123#").timestamp,
            Instant::from_nanos(12_000_000_001)
        );
        assert_eq!(
            record("(0000000012.250000) c 123#").timestamp,
            Instant::from_millis(12_250)
        );
        let too_precise = error("(12.0000000001) c 123#");
        assert_eq!(too_precise.column, 14);
        assert!(too_precise.message.contains("more than 9 digits"));
        assert!(error("(12.) c 123#").message.contains("fraction"));
        assert!(error("(12) c 123#").message.contains("expected '.'"));
        assert!(
            error("(99999999999999999999.0) c 123#")
                .message
                .contains("too large")
        );
        assert!(error("(18446744074.0) c 123#").message.contains("too large"));
        assert_eq!(record("(18446744073.709551615) c 123#").timestamp, Instant::MAX);
    }

    #[test]
    fn writing_matches_candump() {
        let mut out = String::new();
        write_record(
            &mut out,
            &LogRecord {
                timestamp: Instant::from_secs_nanos(1_436_509_052, 249_713_999),
                interface: "can0".into(),
                event: LogEvent::Frame(std_frame(0x123, &[0xDE, 0xAD, 0xBE, 0xEF])),
            },
        );
        write_record(
            &mut out,
            &LogRecord {
                timestamp: Instant::from_micros(7),
                interface: "vcan1".into(),
                event: LogEvent::Frame(CanFrame::remote(ExtendedId::new(0x1F).unwrap(), 3).unwrap()),
            },
        );
        assert_eq!(
            out,
            "(1436509052.249713) can0 123#DEADBEEF\n(0000000000.000007) vcan1 0000001F#R3\n"
        );
    }

    #[test]
    fn blank_comment_crlf_and_trailing_space_lines() {
        assert_eq!(parse_record("").unwrap(), None);
        assert_eq!(parse_record("   \t \r").unwrap(), None);
        assert_eq!(parse_record("# written by candump").unwrap(), None);
        assert_eq!(parse_record("  # indented comment").unwrap(), None);
        let rec = record("(1.0) can0 123#11 \t\r");
        assert_eq!(rec.event, LogEvent::Frame(std_frame(0x123, &[0x11])));
    }

    #[test]
    fn direction_token_from_python_can_is_ignored() {
        assert_eq!(
            record("(1.0) can0 123#11 R").event,
            LogEvent::Frame(std_frame(0x123, &[0x11]))
        );
        assert_eq!(
            record("(1.0) can0 123#11 T").event,
            LogEvent::Frame(std_frame(0x123, &[0x11]))
        );
        let extra = error("(1.0) can0 123#11 Rx");
        assert_eq!(extra.column, 19);
        assert!(extra.message.contains("unexpected text 'Rx'"));
        assert!(error("(1.0) can0 123#11 R T").message.contains("unexpected text"));
    }

    #[test]
    fn id_errors_say_how_to_fix_them() {
        let too_big = error("(1.0) can0 800#00");
        assert_eq!(too_big.column, 12);
        assert_eq!(
            too_big.message,
            "standard id 0x800 exceeds 0x7FF; write 8 hex digits for an extended id (00000800)"
        );
        assert!(error("(1.0) can0 12#00").message.contains("found 2"));
        assert!(error("(1.0) can0 123456789#00").message.contains("found 9"));
        assert!(
            error("(1.0) can0 40000000#00")
                .message
                .contains("exceeds 0x1FFFFFFF")
        );
        assert!(
            error("(1.0) can0 123")
                .message
                .starts_with("expected '#' after the CAN id")
        );
        let bad_char = error("(1.0) can0 12G#00");
        assert_eq!(bad_char.column, 14);
        assert!(bad_char.message.contains("'G'"));
        assert!(error("(1.0) can0 #00").message.contains("expected a CAN id"));
    }

    #[test]
    fn data_errors_point_at_the_problem() {
        let odd = error("(1.0) can0 123#ABC");
        assert_eq!((odd.line, odd.column), (1, 18));
        assert!(odd.message.contains("odd number of hex digits"));
        let long = error("(1.0) can0 123#000102030405060708");
        assert_eq!(long.column, 32);
        assert!(long.message.contains("at most 8 data bytes"));
        assert!(
            error("(1.0) can0 123#.AB")
                .message
                .contains("'.' may only separate")
        );
        assert!(
            error("(1.0) can0 123#AB.")
                .message
                .contains("'.' may only separate")
        );
        assert!(
            error("(1.0) can0 123#AB..CD")
                .message
                .contains("'.' may only separate")
        );
        assert!(error("(1.0) can0 123#ZZ").message.contains("'Z'"));
    }

    #[test]
    fn can_fd_is_rejected_clearly() {
        let fd = error("(1.0) can0 123##1DEADBEEF");
        assert_eq!(fd.column, 15);
        assert!(fd.message.starts_with("CAN FD frames are not supported yet"));
    }

    #[test]
    fn raw_dlc_suffix_is_accepted_with_a_note() {
        let text = "(1.0) can0 123#0102030405060708_E\n(2.0) can0 123#R8_9\n";
        let (records, notes) = parse_log(text);
        assert_eq!(records.len(), 2);
        assert_eq!(
            records[0].1.event,
            LogEvent::Frame(std_frame(0x123, &[1, 2, 3, 4, 5, 6, 7, 8]))
        );
        assert_eq!(notes.len(), 2);
        assert_eq!((notes[0].line, notes[0].column), (1, 32));
        assert!(
            notes[0]
                .message
                .contains("raw DLC 14 (suffix _E) is not preserved")
        );
        assert_eq!(notes[1].line, 2);
        assert!(
            error("(1.0) can0 123#0102_E")
                .message
                .contains("only valid after 8 data bytes")
        );
        assert!(
            error("(1.0) can0 123#0102030405060708_8")
                .message
                .contains("9 to F")
        );
        assert!(
            error("(1.0) can0 123#0102030405060708_EE")
                .message
                .contains("9 to F")
        );
        assert_eq!(parse_compact_frame("123#0102030405060708_F").unwrap().dlc(), 8);
    }

    #[test]
    fn line_structure_errors() {
        assert!(
            error("1.0 can0 123#")
                .message
                .starts_with("expected '(' to open the timestamp")
        );
        assert!(error("(1.0 can0 123#").message.contains("expected ')'"));
        assert!(error("(1.0)can0 123#").message.contains("interface name"));
        assert!(error("(1.0)").message.contains("interface name"));
        assert!(error("(1.0) can0").message.contains("expected a frame"));
    }

    #[test]
    fn non_ascii_input_reports_character_columns() {
        let err = error("(1.0) cän0 12é#00");
        // The interface may hold any characters; the id may not.
        assert_eq!(err.column, 14);
        assert!(err.message.contains("'é'"));
        let rec = record("(1.0) интерфейс 123#01");
        assert_eq!(rec.interface, "интерфейс");
        assert!(error("(1.0) can0 123#0é").message.contains("odd number"));
    }

    #[test]
    fn very_long_lines_give_short_messages() {
        let line = format!("(1.0) can0 123#00 {}", "x".repeat(100_000));
        let err = error(&line);
        assert!(err.message.len() < 200, "message too long: {}", err.message.len());
        let long_data = format!("(1.0) can0 123#{}", "00".repeat(50_000));
        assert!(error(&long_data).message.contains("at most 8 data bytes"));
    }

    #[test]
    fn mixed_file_keeps_every_good_line() {
        let text = "# candump log\n\
                    (1.000000) can0 123#01\r\n\
                    (1.000100) can0 800#01\n\
                    \n\
                    (1.000200) can0 7FF#R\n\
                    garbage\n\
                    (1.000300) can0 123##0\n\
                    (1.000400) can1 1FFFFFFF#0102030405060708\n";
        let (records, errors) = parse_log(text);
        let lines: Vec<usize> = records.iter().map(|(line, _)| *line).collect();
        assert_eq!(lines, vec![2, 5, 8]);
        let error_lines: Vec<(usize, usize)> = errors.iter().map(|e| (e.line, e.column)).collect();
        assert_eq!(error_lines, vec![(3, 17), (6, 1), (7, 20)]);
        assert_eq!(errors[1].to_string().split(':').next(), Some("line 6, column 1"));
    }

    #[test]
    fn compact_frames_for_the_command_line() {
        let frame = parse_compact_frame("601#4000100000000000").unwrap();
        assert_eq!(frame, std_frame(0x601, &[0x40, 0, 0x10, 0, 0, 0, 0, 0]));
        assert_eq!(parse_compact_frame("  701#R \n").unwrap().to_string(), "701#R");
        assert_eq!(
            parse_compact_frame("601#40.00.10").unwrap().data(),
            &[0x40, 0x00, 0x10]
        );
        let err = parse_compact_frame("601#4000100").unwrap_err();
        assert_eq!((err.line, err.column), (1, 11));
        assert!(
            parse_compact_frame("")
                .unwrap_err()
                .message
                .contains("expected a frame")
        );
        assert!(
            parse_compact_frame("20000001#00")
                .unwrap_err()
                .message
                .contains("error frame")
        );
        assert!(
            parse_compact_frame("601#40 00")
                .unwrap_err()
                .message
                .contains("unexpected")
        );
    }

    fn any_event() -> impl Strategy<Value = LogEvent> {
        prop_oneof![
            4 => any_frame().prop_map(LogEvent::Frame),
            1 => (0u32..=CAN_ERR_MASK, proptest::collection::vec(any::<u8>(), 0..=8))
                .prop_map(|(class, data)| LogEvent::ErrorFrame { class, data }),
        ]
    }

    fn any_record(max_micros: u64) -> impl Strategy<Value = LogRecord> {
        (0..=max_micros, "[a-z][a-z0-9_.-]{0,14}", any_event()).prop_map(|(micros, interface, event)| {
            LogRecord {
                timestamp: Instant::from_micros(micros),
                interface,
                event,
            }
        })
    }

    proptest! {
        #[test]
        fn write_then_parse_round_trips(rec in any_record(u64::MAX / 1_000)) {
            let mut text = String::new();
            write_record(&mut text, &rec);
            prop_assert!(text.ends_with('\n'));
            prop_assert_eq!(parse_record(&text).unwrap(), Some(rec));
        }

        #[test]
        fn nanosecond_timestamps_round_trip_to_the_microsecond(nanos: u64, frame in any_frame()) {
            let rec = LogRecord { timestamp: Instant::from_nanos(nanos), interface: "can0".into(),
                                  event: LogEvent::Frame(frame) };
            let parsed = parse_record(&rec.to_string()).unwrap().unwrap();
            prop_assert_eq!(parsed.timestamp, Instant::from_micros(nanos / 1_000));
            prop_assert_eq!(parsed.event, rec.event);
        }

        #[test]
        fn dotted_data_parses_like_plain_data(frame in any_frame()) {
            prop_assume!(!frame.is_remote());
            let dotted = frame.data().iter().map(|b| format!("{b:02x}")).collect::<Vec<_>>().join(".");
            let text = format!("{}#{dotted}", frame.id());
            prop_assert_eq!(parse_compact_frame(&text).unwrap(), frame);
        }

        #[test]
        fn a_log_keeps_all_good_lines_among_bad_ones(
            recs in proptest::collection::vec(any_record(10_000_000_000_000_000), 0..20),
            bad in proptest::collection::vec("[^\n]{0,40}", 0..20),
        ) {
            let mut text = String::new();
            for (idx, rec) in recs.iter().enumerate() {
                write_record(&mut text, rec);
                if let Some(bad_line) = bad.get(idx) {
                    // Prefix garbage so that it can never be a valid or blank line.
                    text.push('!');
                    text.push_str(bad_line);
                    text.push('\n');
                }
            }
            let (parsed, errors) = parse_log(&text);
            let parsed: Vec<LogRecord> = parsed.into_iter().map(|(_, rec)| rec).collect();
            prop_assert_eq!(parsed, recs.clone());
            prop_assert_eq!(errors.len(), recs.len().min(bad.len()));
        }

        #[test]
        fn arbitrary_text_never_panics(text in "\\PC{0,200}") {
            let (records, errors) = parse_log(&text);
            for err in &errors {
                prop_assert!(err.line >= 1 && err.column >= 1);
            }
            prop_assert!(records.len() + errors.len() <= text.split('\n').count() * 2);
            let _ = parse_compact_frame(&text);
        }

        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
            let text = String::from_utf8_lossy(&bytes);
            let (_records, errors) = parse_log(&text);
            for err in errors {
                prop_assert!(err.column <= text.chars().count() + 1);
            }
        }
    }
}

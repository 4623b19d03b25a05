//! Messages a socketcand server sends to a client, and the writers a server uses to send them
//! (socketcand `doc/protocol.md` "Mode RAW" and `src/state_raw.c` for frames and error frames,
//! `src/state_nobus.c` for the handshake; python-can's parsing rules are in the interop reference §3).

use canopener_can::{CanFrame, Instant};

use crate::error::{CommandError, quote};
use crate::fields::{
    finished, parse_error_class, parse_frame_data, parse_len, parse_server_id, parse_timestamp, push_decimal,
    push_hex_byte, push_id, push_timestamp, required, tokens,
};

/// A message from a server.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ServerMessage {
    /// `< hi >`: the greeting on connect.
    Hi,
    /// `< ok >`: a command was accepted.
    Ok,
    /// `< echo >`: the answer to `< echo >`.
    Echo,
    /// `< frame ID SECS.USECS DATA >`, or `< rtr ID SECS.USECS DLC >` for a remote frame.
    Frame {
        /// The received frame.
        frame: CanFrame,
        /// The server's receive time (Unix epoch for real servers).
        timestamp: Instant,
    },
    /// `< error CLASS SECS.USECS >`: a CAN error frame, CLASS being the error class bits.
    ErrorFrame {
        /// The error class (`can_id & CAN_EFF_MASK` of the SocketCAN error frame).
        class: u32,
        /// The server's receive time.
        timestamp: Instant,
    },
    /// `< error TEXT >`: the server refused something, e.g. `could not open bus`.
    Error {
        /// The words after `error`, joined by single spaces.
        text: String,
    },
    /// A well-formed element with a verb this codec does not interpret (`fdframe`, BCM replies, …).
    Other {
        /// The first word of the element.
        verb: String,
    },
}

/// Parses one element (brackets included, as [`crate::ElementReader`] yields it) sent by a server.
///
/// Frame ids must have 3 or 8 digits: python-can takes any other width as extended, so a server
/// that writes `12` is broken and the error says so. `< error … >` is an error frame only when it is
/// exactly a hex class followed by a timestamp; anything else (`< error could not open bus >`) is
/// a text error.
pub fn parse_server_message(element: &str) -> Result<ServerMessage, CommandError> {
    let mut fields = tokens(element)?;
    let verb = fields.next().ok_or_else(|| CommandError::Empty {
        element: quote(element),
    })?;
    let message = match verb {
        "hi" => ServerMessage::Hi,
        "ok" => ServerMessage::Ok,
        "echo" => ServerMessage::Echo,
        "frame" => {
            let id = parse_server_id(required(&mut fields, element, "can id")?, element)?;
            let timestamp = parse_timestamp(required(&mut fields, element, "timestamp")?, element)?;
            let (data, len) = match fields.next() {
                Some(token) => parse_frame_data(token, element)?,
                None => Default::default(),
            };
            let frame = data
                .get(..len)
                .and_then(|data| CanFrame::new(id, data).ok())
                .ok_or_else(|| CommandError::BadFrameData {
                    element: quote(element),
                    token: String::new(),
                })?;
            ServerMessage::Frame { frame, timestamp }
        }
        "rtr" => {
            let id = parse_server_id(required(&mut fields, element, "can id")?, element)?;
            let timestamp = parse_timestamp(required(&mut fields, element, "timestamp")?, element)?;
            let dlc_token = required(&mut fields, element, "dlc")?;
            let dlc = parse_len(dlc_token, element)?;
            let frame = CanFrame::remote(id, dlc).map_err(|_| CommandError::BadLength {
                element: quote(element),
                token: quote(dlc_token),
            })?;
            ServerMessage::Frame { frame, timestamp }
        }
        "error" => {
            let words: Vec<&str> = fields.collect();
            return Ok(parse_error(&words, element));
        }
        other => {
            return Ok(ServerMessage::Other {
                verb: other.to_owned(),
            });
        }
    };
    finished(fields, element)?;
    Ok(message)
}

fn parse_error(words: &[&str], element: &str) -> ServerMessage {
    if let [class, timestamp] = words
        && let Ok(class) = parse_error_class(class, element)
        && let Ok(timestamp) = parse_timestamp(timestamp, element)
    {
        return ServerMessage::ErrorFrame { class, timestamp };
    }
    ServerMessage::Error {
        text: words.join(" "),
    }
}

/// `< hi >`.
pub fn write_hi(out: &mut Vec<u8>) {
    out.extend_from_slice(b"< hi >");
}

/// `< ok >`.
pub fn write_ok(out: &mut Vec<u8>) {
    out.extend_from_slice(b"< ok >");
}

/// `< error TEXT >`. Never send this to a client in raw mode: python-can parses every `error`
/// element as an error frame, fails on the text and its receive thread dies.
pub fn write_error(out: &mut Vec<u8>, text: &str) {
    out.extend_from_slice(b"< error ");
    out.extend_from_slice(text.as_bytes());
    out.extend_from_slice(b" >");
}

/// `< error CLASS SECS.USECS >` with CLASS as `%03X`, as socketcand writes error frames.
pub fn write_error_frame(out: &mut Vec<u8>, class: u32, timestamp: Instant) {
    out.extend_from_slice(b"< error ");
    let mut digits = Vec::with_capacity(8);
    for byte in class.to_be_bytes() {
        push_hex_byte(&mut digits, byte);
    }
    // `%03X`: drop leading zeros but keep at least three digits; `digits` always holds 8.
    let keep_from = digits
        .iter()
        .position(|&d| d != b'0')
        .unwrap_or(digits.len())
        .min(digits.len() - 3);
    out.extend_from_slice(digits.get(keep_from..).unwrap_or_default());
    out.push(b' ');
    push_timestamp(out, timestamp);
    out.extend_from_slice(b" >");
}

/// A frame from server to client, byte-exact with socketcand's `state_raw.c`.
///
/// A data frame is `< frame ID SECS.USECS DATA >`: the id as `%03X` or `%08X` (python-can decides
/// extended iff the id is not 3 characters), the timestamp as `%ld.%06ld`, and the data as
/// contiguous `%02X` with no spaces, since python-can splits the element only three times. With no
/// data the space before `>` stays: `< frame 123 1.000000  >`; without it python-can raises and its
/// receive thread dies.
///
/// A remote frame is `< rtr ID SECS.USECS DLC >` from socketcand's protocol description. python-can
/// logs a warning and ignores it (it has no RTR support over socketcand); our own client parses it
/// with [`parse_server_message`] into a remote [`CanFrame`], so canopener peers keep RTR.
pub fn write_frame(out: &mut Vec<u8>, frame: &CanFrame, timestamp: Instant) {
    if frame.is_remote() {
        out.extend_from_slice(b"< rtr ");
        push_id(out, frame.id());
        out.push(b' ');
        push_timestamp(out, timestamp);
        out.push(b' ');
        push_decimal(out, u64::from(frame.dlc()));
        out.extend_from_slice(b" >");
        return;
    }
    out.extend_from_slice(b"< frame ");
    push_id(out, frame.id());
    out.push(b' ');
    push_timestamp(out, timestamp);
    out.push(b' ');
    for &byte in frame.data() {
        push_hex_byte(out, byte);
    }
    out.extend_from_slice(b" >");
}

/// Writes any server message; [`ServerMessage::Other`] becomes `< VERB >`.
pub fn write_server_message(out: &mut Vec<u8>, message: &ServerMessage) {
    match message {
        ServerMessage::Hi => write_hi(out),
        ServerMessage::Ok => write_ok(out),
        ServerMessage::Echo => crate::client::write_echo(out),
        ServerMessage::Frame { frame, timestamp } => write_frame(out, frame, *timestamp),
        ServerMessage::ErrorFrame { class, timestamp } => write_error_frame(out, *class, *timestamp),
        ServerMessage::Error { text } => write_error(out, text),
        ServerMessage::Other { verb } => {
            out.extend_from_slice(b"< ");
            out.extend_from_slice(verb.as_bytes());
            out.extend_from_slice(b" >");
        }
    }
}

#[cfg(test)]
mod tests {
    use canopener_can::CanId;

    use super::*;

    /// An element and a check that its error is the expected variant.
    type Case = (&'static str, fn(&CommandError) -> bool);

    fn written(write: impl FnOnce(&mut Vec<u8>)) -> String {
        let mut out = Vec::new();
        write(&mut out);
        String::from_utf8(out).unwrap()
    }

    fn std_frame(id: u16, data: &[u8]) -> CanFrame {
        CanFrame::new(CanId::standard(id).unwrap(), data).unwrap()
    }

    #[test]
    fn golden_server_bytes() {
        let t = Instant::from_micros(1_795_335_844_491_054);
        assert_eq!(written(write_hi), "< hi >");
        assert_eq!(written(write_ok), "< ok >");
        assert_eq!(
            written(|o| write_error(o, "could not open bus")),
            "< error could not open bus >"
        );
        assert_eq!(
            written(|o| write_frame(o, &std_frame(0x123, &[]), t)),
            "< frame 123 1795335844.491054  >"
        );
        assert_eq!(
            written(|o| write_frame(o, &std_frame(0x581, &[0x43, 0, 0x10, 0, 0x92, 1, 2, 0]), t)),
            "< frame 581 1795335844.491054 4300100092010200 >"
        );
        let extended = CanFrame::new(CanId::extended(0x1AAA_AAAA).unwrap(), &[1, 0xF1]).unwrap();
        assert_eq!(
            written(|o| write_frame(o, &extended, t)),
            "< frame 1AAAAAAA 1795335844.491054 01F1 >"
        );
        assert_eq!(
            written(|o| write_frame(o, &std_frame(0x7, &[]), Instant::from_secs(1))),
            "< frame 007 1.000000  >"
        );
        let remote = CanFrame::remote(CanId::standard(0x701).unwrap(), 1).unwrap();
        assert_eq!(
            written(|o| write_frame(o, &remote, t)),
            "< rtr 701 1795335844.491054 1 >"
        );
        assert_eq!(
            written(|o| write_error_frame(o, 0x4, t)),
            "< error 004 1795335844.491054 >"
        );
        assert_eq!(
            written(|o| write_error_frame(o, 0x1FFF_FFFF, t)),
            "< error 1FFFFFFF 1795335844.491054 >"
        );
    }

    #[test]
    fn handshake_and_text_errors_parse() {
        assert_eq!(parse_server_message("< hi >"), Ok(ServerMessage::Hi));
        assert_eq!(parse_server_message("< ok >"), Ok(ServerMessage::Ok));
        assert_eq!(parse_server_message("< echo >"), Ok(ServerMessage::Echo));
        assert_eq!(
            parse_server_message("< error could not open bus >"),
            Ok(ServerMessage::Error {
                text: "could not open bus".into()
            })
        );
        assert_eq!(
            parse_server_message("< error unknown command >"),
            Ok(ServerMessage::Error {
                text: "unknown command".into()
            })
        );
        assert_eq!(
            parse_server_message("< error 004 1.5 >"),
            Ok(ServerMessage::ErrorFrame {
                class: 4,
                timestamp: Instant::from_millis(1500)
            })
        );
        assert_eq!(
            parse_server_message("< fdframe 123 0 1.0 00 >"),
            Ok(ServerMessage::Other {
                verb: "fdframe".into()
            })
        );
    }

    #[test]
    fn frames_parse_including_empty_data_and_remote() {
        assert_eq!(
            parse_server_message("< frame 123 1.000000  >"),
            Ok(ServerMessage::Frame {
                frame: std_frame(0x123, &[]),
                timestamp: Instant::from_secs(1)
            })
        );
        assert_eq!(
            parse_server_message("< frame 581 2.000001 43001000 >"),
            Ok(ServerMessage::Frame {
                frame: std_frame(0x581, &[0x43, 0, 0x10, 0]),
                timestamp: Instant::from_micros(2_000_001)
            })
        );
        assert_eq!(
            parse_server_message("< rtr 701 3.000000 1 >"),
            Ok(ServerMessage::Frame {
                frame: CanFrame::remote(CanId::standard(0x701).unwrap(), 1).unwrap(),
                timestamp: Instant::from_secs(3)
            })
        );
    }

    #[test]
    fn malformed_server_messages_are_rejected() {
        let cases: &[Case] = &[
            ("< frame 12 1.0 00 >", |e| {
                matches!(e, CommandError::IdWidth { .. })
            }),
            ("< frame 800 1.0 00 >", |e| {
                matches!(e, CommandError::StandardIdTooLarge { .. })
            }),
            ("< frame 123 1 00 >", |e| {
                matches!(e, CommandError::BadTimestamp { .. })
            }),
            ("< frame 123 1.0 0 >", |e| {
                matches!(e, CommandError::BadFrameData { .. })
            }),
            ("< frame 123 1.0 11 22 >", |e| {
                matches!(e, CommandError::TrailingJunk { .. })
            }),
            ("< frame 123 1.0 001122334455667788 >", |e| {
                matches!(e, CommandError::BadFrameData { .. })
            }),
            ("< frame 123 >", |e| {
                matches!(
                    e,
                    CommandError::MissingField {
                        field: "timestamp",
                        ..
                    }
                )
            }),
            ("< rtr 123 1.0 9 >", |e| {
                matches!(e, CommandError::BadLength { .. })
            }),
            ("< rtr 123 1.0 >", |e| {
                matches!(e, CommandError::MissingField { field: "dlc", .. })
            }),
            ("< hi there >", |e| matches!(e, CommandError::TrailingJunk { .. })),
            ("< >", |e| matches!(e, CommandError::Empty { .. })),
            ("hi", |e| matches!(e, CommandError::NotAnElement { .. })),
        ];
        for (element, is_expected) in cases {
            let error = parse_server_message(element).unwrap_err();
            assert!(is_expected(&error), "{element}: {error:?}");
            assert!(error.to_string().contains(element), "{error}");
        }
    }
}

//! Commands a client sends to a socketcand server, and the writers a client uses to send them
//! (socketcand `doc/protocol.md`: "Mode NO_BUS" for `open`, "Mode RAW" for `send`, "Mode BCM" and
//! "Mode CONTROL"/"Mode ISO-TP" for the mode switches; python-can's exact bytes are in the interop
//! reference §3).

use canopener_can::{CanFrame, MAX_CLASSIC_DATA_LEN};

use crate::error::{CommandError, quote};
use crate::fields::{
    finished, is_valid_bus_name, parse_client_id, parse_len, parse_send_byte, push_decimal, push_hex_byte,
    push_id, required, tokens,
};

/// A command from a client.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ClientCommand {
    /// `< open NAME >`: attach to the bus of that name.
    Open {
        /// The bus name, already checked with [`crate::is_valid_bus_name`].
        bus: String,
    },
    /// `< rawmode >`: receive every frame of the bus.
    RawMode,
    /// `< bcmmode >`: back to the broadcast-manager mode socketcand starts in after `open`.
    BcmMode,
    /// `< controlmode >`.
    ControlMode,
    /// `< isotpmode >`.
    IsotpMode,
    /// `< echo >`: the server answers `< echo >`.
    Echo,
    /// `< send ID LEN B0 … >` or `< sendrtr ID DLC >`: put a frame on the bus.
    Send(CanFrame),
    /// A well-formed element with a verb this codec does not interpret (BCM `add`, `fdsend`, …).
    Other {
        /// The first word of the element.
        verb: String,
    },
}

/// Parses one element (brackets included, as [`crate::ElementReader`] yields it) sent by a client.
///
/// `send` follows socketcand's `state_raw.c`: the id is extended iff it has exactly 8 hex digits, LEN
/// is decimal 0–8, each byte is 1–2 hex digits of either case, and the byte count must equal LEN.
/// The one exception is python-can's remote frame: python-can has no RTR syntax and writes a remote
/// frame with DLC n as `< send ID n  >`, a LEN above zero and no bytes at all. That shape is taken
/// as a remote frame with DLC = LEN, which keeps the request (and its DLC) instead of losing it as
/// socketcand does; no data frame can have that shape, so nothing is misread.
pub fn parse_client_command(element: &str) -> Result<ClientCommand, CommandError> {
    let mut fields = tokens(element)?;
    let verb = fields.next().ok_or_else(|| CommandError::Empty {
        element: quote(element),
    })?;
    let command = match verb {
        "open" => {
            let bus = required(&mut fields, element, "bus name")?;
            if !is_valid_bus_name(bus) {
                return Err(CommandError::InvalidBusName {
                    element: quote(element),
                    name: quote(bus),
                });
            }
            ClientCommand::Open { bus: bus.to_owned() }
        }
        "rawmode" => ClientCommand::RawMode,
        "bcmmode" => ClientCommand::BcmMode,
        "controlmode" => ClientCommand::ControlMode,
        "isotpmode" => ClientCommand::IsotpMode,
        "echo" => ClientCommand::Echo,
        "send" => return parse_send(fields, element),
        "sendrtr" => {
            let id = parse_client_id(required(&mut fields, element, "can id")?, element)?;
            let dlc = parse_len(required(&mut fields, element, "dlc")?, element)?;
            finished(fields, element)?;
            // `parse_len` only returns values up to 8.
            let frame = CanFrame::remote(id, dlc).map_err(|_| CommandError::BadLength {
                element: quote(element),
                token: dlc.to_string(),
            })?;
            return Ok(ClientCommand::Send(frame));
        }
        // Other verbs carry arguments this codec does not model; the verb is enough to log it.
        other => {
            return Ok(ClientCommand::Other {
                verb: other.to_owned(),
            });
        }
    };
    finished(fields, element)?;
    Ok(command)
}

fn parse_send<'a>(
    mut fields: impl Iterator<Item = &'a str>,
    element: &str,
) -> Result<ClientCommand, CommandError> {
    let id = parse_client_id(required(&mut fields, element, "can id")?, element)?;
    let len = parse_len(required(&mut fields, element, "length")?, element)?;
    let mut data = [0u8; MAX_CLASSIC_DATA_LEN];
    let mut given = 0usize;
    for token in fields {
        let byte = parse_send_byte(token, element)?;
        if let Some(slot) = data.get_mut(given) {
            *slot = byte;
        }
        given += 1;
    }
    let mismatch = || CommandError::ByteCountMismatch {
        element: quote(element),
        declared: len,
        given,
    };
    let frame = if given == 0 && len > 0 {
        CanFrame::remote(id, len)
    } else if given == usize::from(len) {
        CanFrame::new(id, data.get(..given).ok_or_else(mismatch)?)
    } else {
        return Err(mismatch());
    };
    frame.map(ClientCommand::Send).map_err(|_| mismatch())
}

/// `< open BUS >`. Check the name with [`crate::is_valid_bus_name`] first: servers refuse others.
pub fn write_open(out: &mut Vec<u8>, bus: &str) {
    out.extend_from_slice(b"< open ");
    out.extend_from_slice(bus.as_bytes());
    out.extend_from_slice(b" >");
}

/// `< rawmode >`.
pub fn write_rawmode(out: &mut Vec<u8>) {
    out.extend_from_slice(b"< rawmode >");
}

/// `< bcmmode >`.
pub fn write_bcmmode(out: &mut Vec<u8>) {
    out.extend_from_slice(b"< bcmmode >");
}

/// `< controlmode >`.
pub fn write_controlmode(out: &mut Vec<u8>) {
    out.extend_from_slice(b"< controlmode >");
}

/// `< isotpmode >`.
pub fn write_isotpmode(out: &mut Vec<u8>) {
    out.extend_from_slice(b"< isotpmode >");
}

/// `< echo >`, the same in both directions.
pub fn write_echo(out: &mut Vec<u8>) {
    out.extend_from_slice(b"< echo >");
}

/// A frame from client to server.
///
/// A data frame is `< send ID LEN B0 B1 … >` with the id as `%03X`/`%08X` (socketcand takes 8
/// digits as extended), LEN in decimal and each byte as `%02X`: `< send 601 8 40 00 10 00 00 00 00 00 >`,
/// `< send 123 0 >`. A remote frame is `< sendrtr ID DLC >`, socketcand's own RTR command.
pub fn write_send(out: &mut Vec<u8>, frame: &CanFrame) {
    if frame.is_remote() {
        out.extend_from_slice(b"< sendrtr ");
        push_id(out, frame.id());
        out.push(b' ');
        push_decimal(out, u64::from(frame.dlc()));
        out.extend_from_slice(b" >");
        return;
    }
    out.extend_from_slice(b"< send ");
    push_id(out, frame.id());
    out.push(b' ');
    push_decimal(out, u64::from(frame.dlc()));
    for &byte in frame.data() {
        out.push(b' ');
        push_hex_byte(out, byte);
    }
    out.extend_from_slice(b" >");
}

/// Writes any client command; [`ClientCommand::Other`] becomes `< VERB >`.
pub fn write_client_command(out: &mut Vec<u8>, command: &ClientCommand) {
    match command {
        ClientCommand::Open { bus } => write_open(out, bus),
        ClientCommand::RawMode => write_rawmode(out),
        ClientCommand::BcmMode => write_bcmmode(out),
        ClientCommand::ControlMode => write_controlmode(out),
        ClientCommand::IsotpMode => write_isotpmode(out),
        ClientCommand::Echo => write_echo(out),
        ClientCommand::Send(frame) => write_send(out, frame),
        ClientCommand::Other { verb } => {
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

    fn std_frame(id: u16, data: &[u8]) -> CanFrame {
        CanFrame::new(CanId::standard(id).unwrap(), data).unwrap()
    }

    fn written(write: impl FnOnce(&mut Vec<u8>)) -> String {
        let mut out = Vec::new();
        write(&mut out);
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn python_can_send_forms_parse() {
        // The exact bytes python-can 4.6.1 sends (interop reference §3).
        assert_eq!(
            parse_client_command("< send 123 0  >"),
            Ok(ClientCommand::Send(std_frame(0x123, &[])))
        );
        assert_eq!(
            parse_client_command("< send 601 8 40 0 10 0 0 0 0 0 >"),
            Ok(ClientCommand::Send(std_frame(
                0x601,
                &[0x40, 0, 0x10, 0, 0, 0, 0, 0]
            )))
        );
        assert_eq!(
            parse_client_command("< send 1AAAAAAA 2 1 f1 >"),
            Ok(ClientCommand::Send(
                CanFrame::new(CanId::extended(0x1AAA_AAAA).unwrap(), &[1, 0xF1]).unwrap()
            ))
        );
    }

    #[test]
    fn python_can_remote_frame_shape_is_a_remote_frame() {
        let remote = CanFrame::remote(CanId::standard(0x701).unwrap(), 1).unwrap();
        assert_eq!(
            parse_client_command("< send 701 1  >"),
            Ok(ClientCommand::Send(remote))
        );
        assert_eq!(
            parse_client_command("< sendrtr 701 1 >"),
            Ok(ClientCommand::Send(remote))
        );
    }

    #[test]
    fn mode_and_handshake_commands_parse() {
        assert_eq!(
            parse_client_command("< open can0 >"),
            Ok(ClientCommand::Open { bus: "can0".into() })
        );
        assert_eq!(parse_client_command("< rawmode >"), Ok(ClientCommand::RawMode));
        assert_eq!(parse_client_command("<bcmmode>"), Ok(ClientCommand::BcmMode));
        assert_eq!(
            parse_client_command("< controlmode >"),
            Ok(ClientCommand::ControlMode)
        );
        assert_eq!(
            parse_client_command("< isotpmode >"),
            Ok(ClientCommand::IsotpMode)
        );
        assert_eq!(parse_client_command("< echo >"), Ok(ClientCommand::Echo));
        assert_eq!(
            parse_client_command("< add 1 0 123 8 1 2 3 4 5 6 7 8 >"),
            Ok(ClientCommand::Other { verb: "add".into() })
        );
        assert_eq!(
            parse_client_command("< SEND 123 0 >"),
            Ok(ClientCommand::Other { verb: "SEND".into() })
        );
    }

    #[test]
    fn malformed_commands_are_rejected_with_the_reason() {
        let cases: &[Case] = &[
            ("send 123 0", |e| matches!(e, CommandError::NotAnElement { .. })),
            ("<  >", |e| matches!(e, CommandError::Empty { .. })),
            ("< send >", |e| {
                matches!(e, CommandError::MissingField { field: "can id", .. })
            }),
            ("< send 123 >", |e| {
                matches!(e, CommandError::MissingField { field: "length", .. })
            }),
            ("< send 800 0 >", |e| {
                matches!(e, CommandError::StandardIdTooLarge { .. })
            }),
            ("< send 3FFFFFFF 0 >", |e| {
                matches!(e, CommandError::ExtendedIdTooLarge { .. })
            }),
            ("< send xyz 0 >", |e| matches!(e, CommandError::IdNotHex { .. })),
            ("< send 123 9 >", |e| matches!(e, CommandError::BadLength { .. })),
            ("< send 123 40 0 >", |e| {
                matches!(e, CommandError::BadLength { .. })
            }),
            ("< send 123 2 1 >", |e| {
                matches!(
                    e,
                    CommandError::ByteCountMismatch {
                        declared: 2,
                        given: 1,
                        ..
                    }
                )
            }),
            ("< send 123 0 1 >", |e| {
                matches!(
                    e,
                    CommandError::ByteCountMismatch {
                        declared: 0,
                        given: 1,
                        ..
                    }
                )
            }),
            ("< send 123 1 1 2 3 4 5 6 7 8 9 >", |e| {
                matches!(
                    e,
                    CommandError::ByteCountMismatch {
                        declared: 1,
                        given: 9,
                        ..
                    }
                )
            }),
            ("< send 123 1 100 >", |e| {
                matches!(e, CommandError::BadDataByte { .. })
            }),
            ("< send 123 1 zz >", |e| {
                matches!(e, CommandError::BadDataByte { .. })
            }),
            ("< sendrtr 123 9 >", |e| {
                matches!(e, CommandError::BadLength { .. })
            }),
            ("< sendrtr 123 1 x >", |e| {
                matches!(e, CommandError::TrailingJunk { .. })
            }),
            ("< rawmode now >", |e| {
                matches!(e, CommandError::TrailingJunk { .. })
            }),
            ("< open >", |e| {
                matches!(
                    e,
                    CommandError::MissingField {
                        field: "bus name",
                        ..
                    }
                )
            }),
            ("< open can0 can1 >", |e| {
                matches!(e, CommandError::TrailingJunk { .. })
            }),
            ("< open 01234567890123456 >", |e| {
                matches!(e, CommandError::InvalidBusName { .. })
            }),
            ("< open ../x >", |e| {
                matches!(e, CommandError::InvalidBusName { .. })
            }),
        ];
        for (element, is_expected) in cases {
            let error = parse_client_command(element).unwrap_err();
            assert!(is_expected(&error), "{element}: {error:?}");
            let text = error.to_string();
            assert!(
                text.contains(element.trim()),
                "message must name the element: {text}"
            );
        }
    }

    #[test]
    fn golden_client_bytes() {
        assert_eq!(written(|o| write_open(o, "can0")), "< open can0 >");
        assert_eq!(written(write_rawmode), "< rawmode >");
        assert_eq!(written(write_bcmmode), "< bcmmode >");
        assert_eq!(written(write_controlmode), "< controlmode >");
        assert_eq!(written(write_isotpmode), "< isotpmode >");
        assert_eq!(written(write_echo), "< echo >");
        assert_eq!(
            written(|o| write_send(o, &std_frame(0x123, &[]))),
            "< send 123 0 >"
        );
        assert_eq!(
            written(|o| write_send(o, &std_frame(0x601, &[0x40, 0, 0x10, 0, 0, 0, 0, 0]))),
            "< send 601 8 40 00 10 00 00 00 00 00 >"
        );
        let extended = CanFrame::new(CanId::extended(0x12).unwrap(), &[0xAB]).unwrap();
        assert_eq!(written(|o| write_send(o, &extended)), "< send 00000012 1 AB >");
        let remote = CanFrame::remote(CanId::standard(0x701).unwrap(), 1).unwrap();
        assert_eq!(written(|o| write_send(o, &remote)), "< sendrtr 701 1 >");
        assert_eq!(
            written(|o| write_client_command(o, &ClientCommand::Other { verb: "bogus".into() })),
            "< bogus >"
        );
    }
}

//! Property tests: every frame and timestamp survives write → parse, element splitting does not
//! depend on where TCP cuts the stream, and no input makes the codec panic.

use canopener_can::strategy::any_frame;
use canopener_can::{CanFrame, CanId, Instant};
use canopener_socketcand::{
    ClientCommand, ElementReader, ServerMessage, parse_client_command, parse_server_message,
    write_client_command, write_frame, write_send, write_server_message,
};
use proptest::prelude::*;

fn micros_only(timestamp: u64) -> Instant {
    Instant::from_nanos(timestamp - timestamp % 1_000)
}

fn any_client_command() -> impl Strategy<Value = ClientCommand> {
    prop_oneof![
        "[A-Za-z0-9_.-]{1,16}".prop_map(|bus| ClientCommand::Open { bus }),
        Just(ClientCommand::RawMode),
        Just(ClientCommand::BcmMode),
        Just(ClientCommand::ControlMode),
        Just(ClientCommand::IsotpMode),
        Just(ClientCommand::Echo),
        any_frame().prop_map(ClientCommand::Send),
        "(add|update|delete|filter|subscribe|fdsend)".prop_map(|verb| ClientCommand::Other { verb }),
    ]
}

fn any_server_message() -> impl Strategy<Value = ServerMessage> {
    prop_oneof![
        Just(ServerMessage::Hi),
        Just(ServerMessage::Ok),
        Just(ServerMessage::Echo),
        (any_frame(), any::<u64>()).prop_map(|(frame, t)| ServerMessage::Frame {
            frame,
            timestamp: micros_only(t)
        }),
        (any::<u32>(), any::<u64>()).prop_map(|(class, t)| ServerMessage::ErrorFrame {
            class,
            timestamp: micros_only(t)
        }),
        "could not open bus|unknown command|[a-z]{1,8}( [a-z]{1,8}){0,3}"
            .prop_map(|text| ServerMessage::Error { text }),
        "(fdframe|add|stat)".prop_map(|verb| ServerMessage::Other { verb }),
    ]
}

/// Writes `elements` into one stream, cuts it at `cuts` and feeds the pieces one by one.
fn read_in_pieces(stream: &[u8], cuts: &[usize]) -> Vec<String> {
    let mut points: Vec<usize> = cuts.iter().map(|c| c % (stream.len() + 1)).collect();
    points.sort_unstable();
    let mut reader = ElementReader::new(256);
    let mut out = Vec::new();
    let mut last = 0;
    for point in points.into_iter().chain([stream.len()]) {
        reader.push(&stream[last..point]);
        last = point;
        while let Some(element) = reader.next_element() {
            out.push(element.unwrap());
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn server_frames_round_trip(frame in any_frame(), nanos in any::<u64>()) {
        let mut out = Vec::new();
        write_frame(&mut out, &frame, Instant::from_nanos(nanos));
        let text = String::from_utf8(out).unwrap();
        let parsed = parse_server_message(&text).unwrap();
        prop_assert_eq!(parsed, ServerMessage::Frame { frame, timestamp: micros_only(nanos) });
    }

    #[test]
    fn client_sends_round_trip(frame in any_frame()) {
        let mut out = Vec::new();
        write_send(&mut out, &frame);
        let parsed = parse_client_command(std::str::from_utf8(&out).unwrap()).unwrap();
        prop_assert_eq!(parsed, ClientCommand::Send(frame));
    }

    #[test]
    fn python_can_send_spelling_parses_to_the_same_frame(frame in any_frame()) {
        // python-can: `f"< send {id:X} {dlc:X} {' '.join(f'{b:x}' for b in data)} >"` with 3/8-digit ids;
        // a remote frame loses its flag and keeps only its dlc.
        let id = match frame.id() {
            CanId::Standard(id) => format!("{:03X}", id.as_raw()),
            CanId::Extended(id) => format!("{:08X}", id.as_raw()),
        };
        let bytes: Vec<String> = frame.data().iter().map(|b| format!("{b:x}")).collect();
        let element = format!("< send {id} {:X} {} >", frame.dlc(), bytes.join(" "));
        let expected = if frame.dlc() == 0 && frame.is_remote() {
            CanFrame::new(frame.id(), &[]).unwrap()
        } else {
            frame
        };
        prop_assert_eq!(parse_client_command(&element).unwrap(), ClientCommand::Send(expected));
    }

    #[test]
    fn every_client_command_round_trips(command in any_client_command()) {
        let mut out = Vec::new();
        write_client_command(&mut out, &command);
        prop_assert_eq!(parse_client_command(std::str::from_utf8(&out).unwrap()).unwrap(), command);
    }

    #[test]
    fn every_server_message_round_trips(message in any_server_message()) {
        let mut out = Vec::new();
        write_server_message(&mut out, &message);
        prop_assert_eq!(parse_server_message(std::str::from_utf8(&out).unwrap()).unwrap(), message);
    }

    #[test]
    fn elements_do_not_depend_on_push_boundaries(
        messages in prop::collection::vec(any_server_message(), 1..40),
        cuts in prop::collection::vec(any::<usize>(), 0..30),
        garbage in prop::collection::vec("[^<>]{0,5}", 40),
    ) {
        let mut stream = Vec::new();
        let mut expected = Vec::new();
        for (message, noise) in messages.iter().zip(&garbage) {
            stream.extend_from_slice(noise.as_bytes());
            let start = stream.len();
            write_server_message(&mut stream, message);
            expected.push(String::from_utf8(stream[start..].to_vec()).unwrap());
        }
        prop_assert_eq!(read_in_pieces(&stream, &cuts), expected);
    }

    #[test]
    fn random_bytes_never_panic_and_memory_stays_bounded(
        chunks in prop::collection::vec(prop::collection::vec(any::<u8>(), 0..300), 0..20),
        limit in 0usize..300,
    ) {
        let mut reader = ElementReader::new(limit);
        for chunk in &chunks {
            reader.push(chunk);
            while let Some(element) = reader.next_element() {
                if let Ok(element) = element {
                    prop_assert!(element.len() <= reader.max_element_len());
                    let _ = parse_client_command(&element);
                    let _ = parse_server_message(&element);
                }
            }
            prop_assert!(reader.pending_len() < reader.max_element_len());
        }
    }

    #[test]
    fn element_shaped_noise_never_panics(body in "[ -~]{0,80}") {
        let element = format!("<{body}>");
        let _ = parse_client_command(&element);
        let _ = parse_server_message(&element);
        let _ = parse_client_command(&body);
        let _ = parse_server_message(&body);
    }

    #[test]
    fn token_shaped_noise_never_panics(
        verb in "(send|sendrtr|frame|rtr|error|open)",
        args in prop::collection::vec("[0-9A-Fa-fx+.-]{0,12}", 0..12),
    ) {
        let element = format!("< {verb} {} >", args.join(" "));
        if let Err(error) = parse_client_command(&element) {
            prop_assert!(!error.to_string().is_empty());
        }
        if let Err(error) = parse_server_message(&element) {
            prop_assert!(!error.to_string().is_empty());
        }
    }
}

//! Arbitrary bytes from a socketcand server: the element reader and the message parser must never
//! panic, and a parsed message written back is a fixed point (timestamps are normalised to
//! microseconds on the first write, so the second round must reproduce the first byte for byte).

#![no_main]

use canopener_socketcand::{ElementReader, parse_server_message, write_server_message};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&control, stream)) = data.split_first() else {
        return;
    };
    let mut reader = ElementReader::new(usize::from(control) * 2);
    let chunk = usize::from(control % 13) + 1;
    for piece in stream.chunks(chunk) {
        reader.push(piece);
        while let Some(element) = reader.next_element() {
            let Ok(element) = element else { continue };
            if let Ok(message) = parse_server_message(&element) {
                let mut first = Vec::new();
                write_server_message(&mut first, &message);
                let text = std::str::from_utf8(&first).expect("writers emit ASCII/UTF-8");
                let reparsed = parse_server_message(text).unwrap_or_else(|e| panic!("{text:?}: {e}"));
                let mut second = Vec::new();
                write_server_message(&mut second, &reparsed);
                assert_eq!(first, second, "{element:?}");
            }
        }
    }
});

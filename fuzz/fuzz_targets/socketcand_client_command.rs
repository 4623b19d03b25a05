//! Arbitrary bytes from a socketcand client: the element reader and the command parser must never
//! panic, memory stays bounded, and whatever parses is written back in a form that parses to the
//! same command.

#![no_main]

use canopener_socketcand::{ElementReader, parse_client_command, write_client_command};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // The first byte picks the element limit and how the rest is cut into TCP reads.
    let Some((&control, stream)) = data.split_first() else {
        return;
    };
    let mut reader = ElementReader::new(usize::from(control) * 2);
    let chunk = usize::from(control % 13) + 1;
    for piece in stream.chunks(chunk) {
        reader.push(piece);
        while let Some(element) = reader.next_element() {
            let Ok(element) = element else { continue };
            assert!(element.len() <= reader.max_element_len());
            if let Ok(command) = parse_client_command(&element) {
                let mut written = Vec::new();
                write_client_command(&mut written, &command);
                let text = std::str::from_utf8(&written).expect("writers emit ASCII/UTF-8");
                assert_eq!(
                    parse_client_command(text).as_ref(),
                    Ok(&command),
                    "{element:?} -> {text:?}"
                );
            }
        }
        assert!(reader.pending_len() < reader.max_element_len());
    }
});

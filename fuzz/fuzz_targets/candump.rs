//! Arbitrary bytes as a candump log: the parser must never panic, every record it accepts must be
//! written back in a form that parses to the same record (timestamps to the microsecond), every
//! compact frame it accepts must print back to itself, and the CANopen decoder must take whatever
//! frames the log yields.

#![no_main]

use canopener_can::Instant;
use canopener_can::candump::{LogEvent, parse_compact_frame, parse_log, parse_record, write_record};
use canopener_wire::Decoder;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let (records, problems) = parse_log(&text);
    let n_lines = text.split('\n').count();
    for problem in &problems {
        assert!(problem.line >= 1 && problem.line <= n_lines, "{problem}");
        assert!(problem.column >= 1, "{problem}");
    }

    let mut decoder = Decoder::new();
    for (line, record) in &records {
        let mut written = String::new();
        write_record(&mut written, record);
        let reread = parse_record(&written)
            .expect("written records parse")
            .expect("written records are not blank");
        assert_eq!(reread.event, record.event, "line {line}: {written:?}");
        assert_eq!(reread.interface, record.interface, "line {line}: {written:?}");
        assert_eq!(
            reread.timestamp,
            Instant::from_micros(record.timestamp.as_micros()),
            "line {line}"
        );
        if let LogEvent::Frame(frame) = &record.event {
            let decoded = decoder.decode(frame);
            assert_eq!(decoded.id, frame.id());
            assert!(!decoded.to_string().is_empty());
        }
    }

    if let Ok(frame) = parse_compact_frame(&text) {
        assert_eq!(parse_compact_frame(&frame.to_string()), Ok(frame), "{text:?}");
    }
});

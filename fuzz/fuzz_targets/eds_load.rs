//! Arbitrary bytes as an EDS/DCF file: `canopener_eds::load` must never panic, the lossless syntax
//! layer must write the input back byte for byte (whatever the encoding, line endings or garbage),
//! and every diagnostic must point at a place that exists: a 1-based line no further than one past
//! the last line (a finding about the end of the file), and a 1-based column.

#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let loaded = canopener_eds::load(data);

    let written = loaded
        .document
        .to_bytes()
        .expect("an unedited document is always encodable");
    assert!(
        written == data,
        "lossless round trip changed the bytes: {} in, {} out",
        data.len(),
        written.len()
    );

    let line_count = loaded.document.lines().len();
    for diagnostic in &loaded.diagnostics {
        let line = usize::try_from(diagnostic.span.line).unwrap_or(usize::MAX);
        assert!(
            (1..=line_count + 1).contains(&line),
            "diagnostic outside the {line_count} lines of the file: {diagnostic:?}"
        );
        assert!(
            diagnostic.span.column >= 1,
            "diagnostic with a 0 column: {diagnostic:?}"
        );
    }
});

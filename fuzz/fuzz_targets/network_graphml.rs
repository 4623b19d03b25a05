//! Arbitrary bytes as Nodelist.graphml: reading never panics, every diagnostic points inside the
//! text, what is read writes back to a document that reads to the same model, and the checks, the
//! conversions, the drawing and the localiser take whatever model came out.

#![no_main]

use canopener_network::check::{DcfFound, check};
use canopener_network::convert::{Target, convert};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut bytes = b"<".to_vec();
    bytes.extend_from_slice(data);
    exercise(&bytes);
});

fn exercise(bytes: &[u8]) {
    let loaded = canopener_network::load(bytes);
    // CR, LF and CR LF all end a line: the count of CR and LF bytes bounds the lines from above.
    let lines = 1 + bytes.iter().filter(|b| matches!(b, b'\n' | b'\r')).count() as u32;
    for d in &loaded.diagnostics {
        assert!(d.span.line <= lines, "{d:?}");
    }
    let written = convert(&loaded, Target::Graphml).text;
    let again = canopener_network::load(written.as_bytes());
    assert_eq!(again.topology.vertices.len(), loaded.topology.vertices.len());
    assert_eq!(again.topology.cables.len(), loaded.topology.cables.len());
    let _ = check(&loaded, &mut |_| DcfFound::Missing);
    let _ = convert(&loaded, Target::Cpj);
    let _ = convert(&loaded, Target::Dot);
    let _ = canopener_network::draw::svg(&loaded.topology);
    for net in loaded.topology.network_numbers().into_iter().take(4) {
        if let Some(wiring) = canopener_network::wiring::Wiring::new(&loaded.topology, net, None) {
            let localiser = canopener_network::localise::Localiser::new(&loaded.topology, &wiring);
            let all: std::collections::BTreeSet<usize> = (0..wiring.devices().len()).collect();
            let _ = localiser.explain(&all, &all);
        }
    }
}

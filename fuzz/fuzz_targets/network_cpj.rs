//! Arbitrary bytes as nodelist.cpj: reading never panics, every diagnostic points inside the text,
//! the file converts to GraphML and back with every device kept, and the checks take the model.

#![no_main]

use canopener_network::check::{DcfFound, check};
use canopener_network::convert::{Target, convert};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if data.trim_ascii_start().starts_with(b"<") {
        return;
    }
    let loaded = canopener_network::load(data);
    // CR, LF and CR LF all end a line: the count of CR and LF bytes bounds the lines from above.
    let lines = 1 + data.iter().filter(|b| matches!(b, b'\n' | b'\r')).count() as u32;
    for d in &loaded.diagnostics {
        assert!(d.span.line <= lines, "{d:?}");
    }
    let _ = check(&loaded, &mut |_| DcfFound::Missing);
    let graphml = convert(&loaded, Target::Graphml).text;
    let from_graphml = canopener_network::load(graphml.as_bytes());
    let cpj = canopener_network::cpj::write(&from_graphml.topology);
    let back = canopener_network::load(cpj.as_bytes());
    let ids = |t: &canopener_network::Topology| {
        let mut ids: Vec<(u32, u8)> = t
            .network_numbers()
            .into_iter()
            .flat_map(|n| t.members(n).into_iter().filter_map(move |m| Some((n, m.attachment.valid_node_id()?))))
            .collect();
        ids.sort();
        ids
    };
    assert_eq!(ids(&back.topology), ids(&loaded.topology), "{cpj}");
});

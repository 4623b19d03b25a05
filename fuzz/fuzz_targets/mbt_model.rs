//! Arbitrary text as a model file: reading, compiling and (for models that check) exploring must
//! never panic or hang, and every diagnostic must point inside the text.

#![no_main]

use canopener_mbt::compile::{Options, Source, compile};
use canopener_mbt::explore::explore;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let lines = text.split('\n').count() as u32;
    let sources = [Source { origin: "fuzz".into(), text: text.to_string() }];
    let (model, report) = compile(&sources, &Options { node_id: 5, ..Options::default() }, &|_| None);
    for r in &report {
        for d in &r.diagnostics {
            assert!(d.span.line <= lines.max(1), "{d:?} beyond {lines} lines");
        }
    }
    if let Some(model) = model {
        let (space, _) = explore(&model, 2_000);
        assert!(space.lts.states <= 2_000);
        let aut = canopener_mbt::aut::write(&space.lts);
        let (back, diagnostics) = canopener_mbt::aut::read(&aut);
        assert!(diagnostics.is_empty(), "{diagnostics:?}");
        assert_eq!(back, space.lts);
    }
});

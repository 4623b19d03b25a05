//! Arbitrary text as an Aldebaran .aut file: the reader must never panic, every transition it keeps
//! must lie within the declared states, and what it keeps must write and read back unchanged; read
//! as a test purpose or as a specification for synthesis, it must not panic either.

#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let (lts, _) = canopener_mbt::aut::read(&text);
    for (from, _, to) in &lts.transitions {
        assert!(*from < lts.states && *to < lts.states);
    }
    if let Ok(purpose) = canopener_mbt::purpose::from_aut("fuzz", &lts) {
        let _ = canopener_mbt::synth::synthesize(&lts, &purpose);
    }
    if lts.transitions.iter().all(|(_, l, _)| !l.contains('"') && l.is_ascii() && !l.contains('\n') && !l.contains('\r')) {
        let (back, _) = canopener_mbt::aut::read(&canopener_mbt::aut::write(&lts));
        assert_eq!(back, lts);
    }
});

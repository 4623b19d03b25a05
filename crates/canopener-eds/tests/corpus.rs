//! Every file of the EDS corpus (the vendored `corpus/eds`, plus the extended corpus when present: 148
//! real files from many vendors): loads without panicking, writes back byte-identical, and keeps its
//! model through the writers.

use std::collections::BTreeMap;
use std::path::PathBuf;

use canopener_eds::{dcf, diff, json, load, write};
use canopener_testkit::corpus::{self, Kind};

fn corpus_files() -> Vec<PathBuf> {
    corpus::eds_files().into_iter().map(|file| file.path).collect()
}

#[test]
fn every_corpus_file_loads_and_round_trips_byte_identical() {
    let files = corpus_files();
    assert_eq!(
        files.len(),
        corpus::expected_count(Kind::Eds),
        "every EDS/DCF file of the corpus"
    );
    let mut counts: BTreeMap<&'static str, usize> = BTreeMap::new();
    for path in &files {
        let bytes = canopener_testkit::fixture::read(path).unwrap();
        let loaded = load(&bytes);
        assert_eq!(
            loaded.document.to_bytes().unwrap(),
            bytes,
            "{} does not round-trip",
            path.display()
        );
        assert!(
            bytes.is_empty() || !loaded.eds.objects.is_empty(),
            "{} has no objects",
            path.display()
        );
        for d in &loaded.diagnostics {
            *counts.entry(d.code.as_str()).or_default() += 1;
        }
    }
    for (code, n) in &counts {
        println!("{code} {n}");
    }
}

#[test]
fn writers_keep_the_model_on_every_corpus_file() {
    for path in corpus_files() {
        let bytes = canopener_testkit::fixture::read(&path).unwrap();
        let loaded = load(&bytes);
        let name = path.display();
        // Lossless writer: an unchanged model writes the identical bytes.
        let lossless = write::write_lossless(&loaded.document, &loaded.eds);
        assert_eq!(
            lossless.to_bytes().unwrap(),
            bytes,
            "{name}: lossless writer changed an unchanged model"
        );
        // Canonical formatting keeps the model and is idempotent.
        let canonical = write::to_canonical(&loaded.eds, Some(&loaded.document));
        let reloaded = load(canonical.as_bytes());
        assert_eq!(
            reloaded.eds, loaded.eds,
            "{name}: fmt then load differs from load"
        );
        let twice = write::to_canonical(&reloaded.eds, Some(&reloaded.document));
        assert_eq!(twice, canonical, "{name}: canonical formatting is not idempotent");
        // EDS -> JSON -> EDS keeps the model.
        let from_json = json::from_json(&json::to_json(&loaded.eds)).unwrap();
        assert_eq!(from_json, loaded.eds, "{name}: JSON round trip changed the model");
        let via_json = load(write::to_canonical(&from_json, None).as_bytes());
        assert_eq!(
            via_json.eds, loaded.eds,
            "{name}: EDS -> JSON -> EDS changed the model"
        );
        // EDS -> DCF -> EDS gives the same object dictionary back.
        if !loaded.eds.is_dcf() {
            let dcf = dcf::to_dcf(&loaded.eds, 5, 250).unwrap();
            let reloaded_dcf = load(write::to_canonical(&dcf, None).as_bytes());
            assert_eq!(reloaded_dcf.eds.node_id(), Some(5), "{name}");
            let back = dcf::to_eds(&reloaded_dcf.eds);
            // Files named .eds sometimes carry DCF values already; those are DCF additions too.
            let d = diff::diff(&dcf::to_eds(&loaded.eds), &back);
            assert!(
                d.is_equivalent(),
                "{name}: EDS -> DCF -> EDS: {:?}",
                d.significant().collect::<Vec<_>>()
            );
        }
    }
}

//! Arbitrary bytes as a CiA 311 XDD/XDC through `eds check`'s XML pipeline (the reader, the model
//! checks on its canonical EDS form, placing findings in the XML): no panic, no hang; a refused file
//! has no findings; every finding points at a line and column of the XML text.
//! Seed it with the corpus: `cargo +nightly fuzz run xdd_check /tmp/seeds` after copying `corpus/xdd`.

#![no_main]

use canopener_description::{Checker, Format, Selection};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if !Format::is_xml(Some("xdd"), data) {
        // Read as EDS text: the eds_check target's subject.
        return;
    }
    let checker = Checker::new(Vec::new(), Selection::default()).expect("no names to check");
    let report = checker.check("fuzz.xdd", Some("fuzz.xdd"), data);
    if report.problem.is_some() {
        assert!(report.findings.is_empty(), "a refused file has findings: {report:?}");
        return;
    }
    let text = canopener_xdd::decode(data).expect("a file the checker read decodes");
    let lines = text.lines().count().max(1);
    for finding in &report.findings {
        let line = usize::try_from(finding.diagnostic.span.line).unwrap_or(usize::MAX);
        assert!((1..=lines + 1).contains(&line), "finding outside the file: {finding:?}");
        assert!(finding.diagnostic.span.column >= 1, "finding with column 0: {finding:?}");
    }
});

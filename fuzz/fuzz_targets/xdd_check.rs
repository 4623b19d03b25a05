//! Arbitrary bytes as a CiA 311 XDD/XDC through `eds check`'s XML pipeline (the reader, the model
//! checks, placing findings in the XML): no panic, no hang; a refused file has no findings; every
//! finding points at a line and column of the XML text, and the source line the report shows under it
//! is that line, both counted by the one rule of `canopener_eds::lines` (a lone CR ends a line).
//! Seed it with the corpus: `cargo +nightly fuzz run xdd_check /tmp/seeds` after copying `corpus/xdd`.

#![no_main]

use canopener_description::{Checker, Format, Selection};
use libfuzzer_sys::fuzz_target;

#[path = "shared/report_lines.rs"]
mod report_lines;

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
    report_lines::assert_findings_on_their_lines(&report, &text);
});

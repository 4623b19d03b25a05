//! Arbitrary bytes as an EDS/DCF file through the whole checker: every built-in check must run
//! without panicking, every finding must point at a line of the file and the report must show that
//! line under it, both counted by the one rule of `canopener_eds::lines` (a lone CR ends a line), and
//! the safe fixes must leave a file that loads, never with more errors, and that a second fix leaves
//! unchanged.

#![no_main]

use canopener_check::{Selection, fix};
use canopener_description::Checker;
use canopener_eds::lines::LineIndex;
use libfuzzer_sys::fuzz_target;

#[path = "shared/report_lines.rs"]
mod report_lines;

fuzz_target!(|data: &[u8]| {
    let loaded = canopener_eds::load(data);
    let selection = Selection::default();
    let checker = Checker::new(Vec::new(), selection.clone()).expect("no names to check");
    let report = checker.check_loaded("fuzz.eds", Some("fuzz.eds"), &loaded);
    let lines = LineIndex::new(loaded.document.text());
    for (index, line) in loaded.document.lines().iter().enumerate() {
        let number = u32::try_from(index + 1).unwrap_or(u32::MAX);
        assert_eq!(
            Some(loaded.document.line_text(index)),
            lines.line(number),
            "the syntax layer and the line rule split line {number} differently: {line:?}"
        );
    }
    report_lines::assert_findings_on_their_lines(&report, loaded.document.text());
    let none = |_: &canopener_check::Context<'_>| Vec::new();
    let fixed = fix::fix_file(data, Some("fuzz.eds"), &selection, &none);
    assert!(
        fixed.errors_after <= fixed.errors_before,
        "fixing raised the errors: {fixed:?}"
    );
    let again = fix::fix_file(&fixed.bytes, Some("fuzz.eds"), &selection, &none);
    assert!(
        again.errors_after <= fixed.errors_after,
        "a second fix raised the errors"
    );
    // Without fixes left pending or refused, everything fixable was fixed: a second run changes nothing.
    if fixed.skipped.is_empty() {
        assert!(!again.changed, "fix is not idempotent: {:?}", again.fixes);
    }
});

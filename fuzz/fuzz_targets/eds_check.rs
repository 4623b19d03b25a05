//! Arbitrary bytes as an EDS/DCF file through the whole checker: every built-in check must run
//! without panicking, every finding must point at a line of the file, and the safe fixes must leave a
//! file that loads, never with more errors, and that a second fix leaves unchanged.

#![no_main]

use canopener_check::{Selection, check, fix};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let loaded = canopener_eds::load(data);
    let selection = Selection::default();
    let findings = check(&loaded, Some("fuzz.eds"), &selection).findings;
    let lines = loaded.document.lines().len();
    for finding in &findings {
        let line = usize::try_from(finding.diagnostic.span.line).unwrap_or(usize::MAX);
        assert!(
            (1..=lines + 1).contains(&line),
            "finding outside the file: {finding:?}"
        );
        assert!(
            finding.diagnostic.span.column >= 1,
            "finding with column 0: {finding:?}"
        );
    }
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

//! Arbitrary text as a cia313 criteria file (`canopener test --criteria`): parsing never panics, a
//! refusal points inside the text, and accepted criteria are usable (finite, in range).

#![no_main]

use canopener_conformance::cia313::Criteria;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match Criteria::parse(text, "fuzz.toml") {
        Ok(criteria) => {
            for percent in [criteria.heartbeat_deviation_percent, criteria.event_timer_deviation_percent] {
                assert!(percent > 0.0 && percent < 100.0);
            }
            for limit in [
                criteria.sync_response_max_ms,
                criteria.rtr_response_max_ms,
                criteria.sdo_read_max_ms,
                criteria.sdo_write_max_ms,
                criteria.boot_up_max_ms,
                criteria.lss_response_max_ms,
            ]
            .into_iter()
            .flatten()
            {
                assert!(limit.is_finite() && limit > 0.0);
            }
        }
        Err(err) => {
            assert!(err.line >= 1 && err.line <= text.lines().count() + 1);
            assert!(!err.message.is_empty());
        }
    }
});

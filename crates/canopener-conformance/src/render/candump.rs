//! A test's telegrams as a candump log (`(seconds.micros) can0 605#4000100000000000`), so that
//! `canopener bus replay`, `bus decode` and can-utils read it.

use canopener_can::candump::{LogEvent, LogRecord, write_record};

use crate::model::TestReport;

/// The interface name the logs carry.
pub const INTERFACE: &str = "can0";

/// The candump log of `test`, one line per telegram, on the link's clock.
pub fn log(test: &TestReport) -> String {
    let mut out = String::new();
    for telegram in &test.telegrams {
        write_record(
            &mut out,
            &LogRecord {
                timestamp: telegram.at,
                interface: INTERFACE.to_owned(),
                event: LogEvent::Frame(telegram.frame),
            },
        );
    }
    out
}

/// The file name of `test`'s log: its id with `.log`.
pub fn file_name(test: &TestReport) -> String {
    format!("{}.log", test.id)
}

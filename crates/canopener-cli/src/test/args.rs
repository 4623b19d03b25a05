//! Command-line grammar of `canopener test`.

use std::path::PathBuf;
use std::time::Duration;

use clap::{Args, ValueEnum};

use crate::args::BusArg;
use crate::grammar::{parse_duration, parse_in_range, parse_node_id};

/// How long the device may take to answer one SDO request unless `--timeout` says otherwise (CiA 301
/// leaves it to the implementation).
pub(crate) const DEFAULT_TIMEOUT: &str = "500ms";

/// `--stimulus-settle` unless given: `canopener_conformance::stimulus::DEFAULT_SETTLE`.
pub(crate) const DEFAULT_SETTLE: &str = "10ms";

/// A `--stimulus` command line: anything but blank.
fn parse_stimulus(text: &str) -> Result<String, String> {
    if text.trim().is_empty() {
        return Err("give the program that applies an input, e.g. --stimulus ./set-input.sh".to_owned());
    }
    Ok(text.to_owned())
}

/// The report formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum ReportFormat {
    /// A CCT-like summary per group, then each failure with its analysis and a log excerpt.
    Human,
    /// The version 1 JSON report.
    Json,
    /// JUnit XML: one test case per test, the telegram log as system-out.
    Junit,
    /// One self-contained HTML page (opens offline): summary, a table per suite, every test
    /// collapsible with its analysis, telegram log and plots of its measurements; write it with -o.
    Html,
}

#[derive(Debug, Args)]
pub(crate) struct TestArgs {
    #[command(flatten)]
    pub(crate) bus: BusArg,
    /// Node-ID of the device under test (1..127, decimal or 0x).
    #[arg(long, value_parser = parse_node_id, value_name = "N", required_unless_present = "list")]
    pub(crate) node: Option<u8>,
    /// The device's EDS/DCF (or XDD/XDC): preconditions and expected values come from it.
    #[arg(long, value_name = "FILE", required_unless_present = "list")]
    pub(crate) eds: Option<PathBuf>,
    /// Which suite: cia301 (the device test), cia401 (generic I/O), cia305 (LSS), cia313
    /// (performance), eds (the EDS check only) or all.
    #[arg(long, value_name = "SUITE", default_value = "all")]
    pub(crate) suite: String,
    /// Run only this test id, or every test under an id prefix (cia301.sdo); repeatable.
    #[arg(long, value_name = "ID")]
    pub(crate) only: Vec<String>,
    /// Skip this test id or id prefix; repeatable.
    #[arg(long, value_name = "ID")]
    pub(crate) skip: Vec<String>,
    /// Run only tests with this tag (sdo, nmt, heartbeat, writes, timing, ...); repeatable.
    #[arg(long, value_name = "TAG")]
    pub(crate) tag: Vec<String>,
    /// Report format.
    #[arg(long, value_enum, default_value_t = ReportFormat::Human)]
    pub(crate) format: ReportFormat,
    /// Write the report to this file instead of stdout.
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    pub(crate) output: Option<PathBuf>,
    /// Write each test's telegrams as a candump log DIR/ID.log (replay with `canopener bus replay`).
    #[arg(long, value_name = "DIR")]
    pub(crate) log: Option<PathBuf>,
    /// How long to wait for each SDO answer (e.g. 500ms, 2s).
    #[arg(long, default_value = DEFAULT_TIMEOUT, value_parser = parse_duration, value_name = "DURATION")]
    pub(crate) timeout: Duration,
    /// Pass criteria of the cia313 performance tests (TOML, see docs/conformance.md); without it the
    /// documented defaults apply (heartbeat and event-timer periods ±5 %, response times measured
    /// without a limit).
    #[arg(long, value_name = "FILE")]
    pub(crate) criteria: Option<PathBuf>,
    /// How often the cia313 tests measure each response time (SDO, RTR, each LSS service; boot-up
    /// at most 10).
    #[arg(long, default_value = "1000", value_name = "N",
          value_parser = |t: &str| parse_in_range(t, 1, 1_000_000, "--repetitions").map(|v| v as usize))]
    pub(crate) repetitions: usize,
    /// A program that applies an input on the device under test, for the cia401 input tests of a
    /// device without the factory test registers 2000h–2002h. Run through `sh -c` as `CMD OBJECT
    /// SUB VALUE` (e.g. `CMD 6000 1 0x5A`, `CMD 6401 1 -1234`); exit status 0 means applied,
    /// anything else makes the test inconclusive with the program's stderr; killed after 10 s
    /// (docs/conformance.md, "The stimulus hook").
    #[arg(long, value_name = "CMD", value_parser = parse_stimulus)]
    pub(crate) stimulus: Option<String>,
    /// How long the cia401 tests wait after --stimulus returned before they read the input or expect
    /// its TPDO (the input's filter time), e.g. 10ms, 50ms.
    #[arg(long, default_value = DEFAULT_SETTLE, value_parser = parse_duration, value_name = "DURATION",
          requires = "stimulus")]
    pub(crate) stimulus_settle: Duration,
    /// List the tests (ids, titles, CiA and CCT references, preconditions) instead of running them.
    #[arg(long)]
    pub(crate) list: bool,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_settle_time_is_the_librarys() {
        assert_eq!(
            parse_duration(DEFAULT_SETTLE),
            Ok(canopener_conformance::stimulus::DEFAULT_SETTLE)
        );
    }
}

//! The product tour `canopener demo` runs: a simulated CiA 401 I/O device from a bundled EDS on the
//! embedded virtual bus, its EDS checked, every suite of the catalogue run against it, and then the same
//! device with one fault switched on, so a user sees a clean report and what a failure looks like.
//!
//! Everything runs in-process on virtual time (`Simulation::ideal`), so the verdicts are the same on any
//! machine and the tour takes a few seconds of CPU. The caller reads the wall clock (the `started`
//! stamp), writes the files and draws the progress; this module only computes.

use std::time::Duration;

use canopener_check::Selection as CheckSelection;
use canopener_device::faults::Fault;
use canopener_eds::Severity;
use canopener_link::cancel::Cancel;
use canopener_sim::error::SimError;
use canopener_sim::simulation::Simulation;

use crate::catalogue::{Selection, catalogue};
use crate::device_model::DeviceModel;
use crate::runner::{self, FinishedRun, Progress, RunSpec};

/// The bundled EDS: the CANopenNode demo device (CiA 401) with every optional CiA 401 object, so that
/// each CiA 401 test applies.
pub const EDS: &[u8] = include_bytes!("../test_data/cia401_full_io.eds");
/// The file name the bundled EDS is written under and the reports name.
pub const EDS_NAME: &str = "cia401_full_io.eds";
/// The node-ID of the simulated device.
pub const NODE: u8 = 5;
/// The fault the second run switches on unless the user picks another: every second heartbeat is
/// 40 % of the period late, which `cia301.ec.1` catches and the report plots against its limits.
pub const DEFAULT_FAULT: Fault = Fault::HeartbeatJitter;
/// The SDO timeout of the runs (the simulated device answers at once; this bounds a broken one).
const SDO_TIMEOUT: Duration = Duration::from_millis(500);

/// What canopener's EDS checks (those `canopener eds check` runs by default) found in the bundled EDS.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EdsCheck {
    /// Error findings.
    pub errors: usize,
    /// Warning findings.
    pub warnings: usize,
    /// Informational findings.
    pub infos: usize,
    /// Objects in the object dictionary.
    pub objects: usize,
}

/// Why the tour could not run.
#[derive(Debug, thiserror::Error)]
pub enum TourError {
    /// The simulated device could not be built from the EDS (a build problem: the EDS is bundled).
    #[error("cannot simulate the bundled EDS: {0}")]
    Simulation(#[from] SimError),
    /// The runner refused the run.
    #[error(transparent)]
    Run(#[from] runner::RunError),
}

/// Runs canopener's EDS checks on the bundled EDS.
pub fn check_eds() -> EdsCheck {
    let loaded = canopener_eds::load(EDS);
    let findings = canopener_check::check(&loaded, Some(EDS_NAME), &CheckSelection::default()).findings;
    let count = |severity: Severity| {
        findings
            .iter()
            .filter(|f| f.diagnostic.severity == severity)
            .count()
    };
    EdsCheck {
        errors: count(Severity::Error),
        warnings: count(Severity::Warning),
        infos: count(Severity::Info),
        objects: loaded.eds.objects.len(),
    }
}

/// Runs every test of the catalogue (all suites, whichever exist) against the bundled device with
/// `faults` switched on, on virtual time. `started` is the report's start stamp; `cancel` stops the run
/// (the partial report comes back with `interrupted`); `on_progress` sees each test start. A fault that
/// silences the device (`sdo-slow` answers after the timeout) comes back as an outcome with `silent`.
pub fn run(
    faults: &[Fault],
    started: &str,
    cancel: Option<Cancel>,
    on_progress: impl FnMut(Progress<'_>),
) -> Result<FinishedRun, TourError> {
    let loaded = canopener_eds::load(EDS);
    let eds_errors = Some(crate::cia301::eds::errors(&loaded, Some(EDS_NAME)));
    let model = DeviceModel::new(&loaded.eds, NODE);
    let mut simulation = Simulation::ideal()
        .device(&loaded.eds, NODE)
        .faults(faults.iter().copied());
    if let Some(cancel) = &cancel {
        simulation = simulation.cancel(cancel.clone());
    }
    let mut bus = simulation.start()?;
    // Every suite the catalogue has: a suite added later joins the tour without a change here.
    let tests = Selection::default()
        .pick(&catalogue())
        .unwrap_or_else(|_| catalogue());
    let spec = RunSpec {
        node: NODE,
        model: &model,
        eds: format!("{EDS_NAME} (bundled)"),
        bus: "embedded virtual bus (ideal timing)".to_owned(),
        started: started.to_owned(),
        sdo_timeout: SDO_TIMEOUT,
        eds_errors,
        cancel,
    };
    Ok(runner::run(&mut bus, &spec, &tests, on_progress)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Verdict;

    #[test]
    fn the_bundled_eds_has_no_errors() {
        let check = check_eds();
        assert_eq!(check.errors, 0, "{check:?}");
        assert!(check.objects > 50, "{check:?}");
    }

    #[test]
    fn the_tour_runs_every_suite_of_the_catalogue() {
        let mut seen = 0;
        let mut finished = Vec::new();
        let outcome = run(&[], "2024-01-01T00:00:00Z", None, |p| {
            seen = seen.max(p.done);
            finished.extend(p.finished.map(|t| (t.id.clone(), t.verdict)));
        })
        .unwrap();
        assert!(outcome.passed());
        let report = outcome.report;
        assert_eq!(report.tests.len(), catalogue().len());
        assert_eq!(seen, report.tests.len());
        // Every verdict reached the progress callback once, in order, as the test ended.
        let reported: Vec<_> = report.tests.iter().map(|t| (t.id.clone(), t.verdict)).collect();
        assert_eq!(finished, reported);
        let mut suites: Vec<&str> = report.tests.iter().map(|t| t.suite.as_str()).collect();
        suites.dedup();
        for suite in crate::catalogue::SUITES.iter().filter(|s| **s != "eds") {
            assert!(suites.contains(suite), "{suite} missing from {suites:?}");
        }
        let undecided: Vec<_> = report
            .tests
            .iter()
            .filter(|t| matches!(t.verdict, Verdict::Fail | Verdict::Inconclusive))
            .map(|t| (&t.id, &t.reason))
            .collect();
        assert!(undecided.is_empty(), "the clean device: {undecided:?}");
    }

    #[test]
    fn the_default_fault_fails_a_test_with_a_plotted_measurement() {
        let report = run(&[DEFAULT_FAULT], "2024-01-01T00:00:00Z", None, |_| {})
            .unwrap()
            .report;
        let failed: Vec<_> = report
            .tests
            .iter()
            .filter(|t| t.verdict == Verdict::Fail)
            .collect();
        assert!(!failed.is_empty());
        assert!(
            failed
                .iter()
                .any(|t| t.measurements.values().any(|m| m.limits.is_some())),
            "{:?}",
            failed.iter().map(|t| &t.id).collect::<Vec<_>>()
        );
    }
}

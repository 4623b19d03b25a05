//! Running the CiA 301 suite against simulated devices on virtual time, shared by the integration
//! tests.

use std::time::Duration;

use canopener_can::{CanFrame, Instant};
use canopener_conformance::catalogue::{Selection, catalogue};
use canopener_conformance::device_model::DeviceModel;
use canopener_conformance::model::Report;
use canopener_conformance::performance::Performance;
use canopener_conformance::runner::{self, RunSpec};
use canopener_device::faults::Fault;
use canopener_link::cancel::Cancel;
use canopener_link::link::{Link, LinkError, Stamped, Timestamps};
use canopener_sim::simulation::Simulation;

/// The node every simulated device under test has.
pub(crate) const NODE: u8 = 5;

/// The start time the reports state (the only field that may differ between runs).
pub(crate) const STARTED: &str = "2024-01-01T00:00:00Z";

/// Runs the tests `only` selects (all when empty) against a simulated device from the vendored
/// corpus EDS `name` with `faults`.
pub(crate) fn run(name: &str, faults: &[Fault], only: &[&str]) -> Report {
    run_at(name, NODE, faults, only)
}

/// [`run`] with the device on `node` (an EDS whose defaults are written for one node-ID).
pub(crate) fn run_at(name: &str, node: u8, faults: &[Fault], only: &[&str]) -> Report {
    run_cancelled_at(name, node, faults, only, None)
}

/// [`run_at`], cancelling the link (as Ctrl-C does) when the test `cancel_at` starts.
pub(crate) fn run_cancelled_at(
    name: &str,
    node: u8,
    faults: &[Fault],
    only: &[&str],
    cancel_at: Option<&str>,
) -> Report {
    run_bytes(
        &Setup::default(),
        &read(&vendored(name)),
        name,
        node,
        faults,
        only,
        cancel_at,
        &|_| false,
        &|f, _| *f,
    )
}

/// Runs the tests `only` selects against a simulated device from the EDS at `path`, every frame
/// passed through `rewrite` (`true`: sent by the tester, `false`: received): a device that misreads
/// some requests, without a fault of its own.
#[allow(dead_code)]
pub(crate) fn run_rewriting(
    path: &std::path::Path,
    only: &[&str],
    rewrite: &dyn Fn(&CanFrame, bool) -> CanFrame,
) -> Report {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    run_bytes(
        &Setup::default(),
        &read(path),
        &name,
        NODE,
        &[],
        only,
        None,
        &|_| false,
        rewrite,
    )
}

/// [`run_at`], cancelling the link (as Ctrl-C does) when the tester receives a frame `on_frame`
/// accepts: in the middle of a test.
#[allow(dead_code)]
pub(crate) fn run_cancelled_on(name: &str, only: &[&str], on_frame: &dyn Fn(&CanFrame) -> bool) -> Report {
    run_bytes(
        &Setup::default(),
        &read(&vendored(name)),
        name,
        NODE,
        &[],
        only,
        None,
        on_frame,
        &|f, _| *f,
    )
}

/// A vendored corpus EDS, or this crate's own test data (`test_data/...`).
fn vendored(name: &str) -> std::path::PathBuf {
    match name.strip_prefix("test_data/") {
        Some(file) => std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("test_data")
            .join(file),
        None => canopener_testkit::corpus::eds(name),
    }
}

/// Runs every test against a simulated device from a file only the extended corpus holds (the
/// vendors whose licences forbid redistribution); `None` without an extended corpus.
#[allow(dead_code)]
pub(crate) fn run_extended(name: &str) -> Option<Report> {
    let path = canopener_testkit::corpus::extended_file(canopener_testkit::corpus::Kind::Eds, name)?;
    Some(run_bytes(
        &Setup::default(),
        &read(&path),
        name,
        NODE,
        &[],
        &[],
        None,
        &|_| false,
        &|f, _| *f,
    ))
}

/// Reads a corpus file the runs simulate.
fn read(path: &std::path::Path) -> Vec<u8> {
    canopener_testkit::fixture::read(path).expect("corpus file")
}

/// Runs the tests `only` selects against a simulated device from the EDS text `bytes` (a corpus
/// file edited by the test) on node [`NODE`].
#[allow(dead_code)]
pub(crate) fn run_edited(bytes: &[u8], name: &str, faults: &[Fault], only: &[&str]) -> Report {
    run_bytes(
        &Setup::default(),
        bytes,
        name,
        NODE,
        faults,
        only,
        None,
        &|_| false,
        &|f, _| *f,
    )
}

/// Runs the tests `only` selects against a simulated device from the vendored EDS `name` with
/// `faults`, as `setup` says (bus timing, SDO timeout, performance criteria).
#[allow(dead_code)]
pub(crate) fn run_setup(setup: &Setup, name: &str, faults: &[Fault], only: &[&str]) -> Report {
    run_bytes(
        setup,
        &read(&vendored(name)),
        name,
        NODE,
        faults,
        only,
        None,
        &|_| false,
        &|f, _| *f,
    )
}

/// How a run is set up besides its device and selection.
pub(crate) struct Setup {
    /// The simulated bus (its devices are added by the run).
    pub(crate) simulation: Simulation,
    /// The tester's SDO timeout.
    pub(crate) sdo_timeout: Duration,
    /// The performance suite's criteria and repetitions.
    pub(crate) performance: Performance,
}

impl Default for Setup {
    fn default() -> Setup {
        Setup {
            simulation: Simulation::ideal(),
            sdo_timeout: Duration::from_millis(500),
            performance: Performance::default(),
        }
    }
}

/// Runs every test except those `skip` names against a simulated device from the EDS text `bytes`,
/// then reads `entry` from the device over SDO on the same bus: what the run left behind. `None`
/// when the read failed.
#[allow(dead_code)]
pub(crate) fn run_then_read(
    bytes: &[u8],
    name: &str,
    skip: &[&str],
    entry: (u16, u8),
) -> (Report, Option<Vec<u8>>) {
    let mut left = None;
    let report = run_bytes_then(
        &Setup::default(),
        bytes,
        name,
        NODE,
        &[],
        &Selection {
            skip: skip.iter().map(|s| (*s).to_owned()).collect(),
            ..Selection::default()
        },
        None,
        &|_| false,
        &|f, _| *f,
        &mut |link| {
            let mut session =
                canopener_link::sdo_session::SdoSession::new(link, NODE, Duration::from_millis(500))
                    .expect("session");
            left = session.read(entry.0, entry.1).ok();
        },
    );
    (report, left)
}

#[allow(clippy::too_many_arguments)]
fn run_bytes(
    setup: &Setup,
    bytes: &[u8],
    name: &str,
    node: u8,
    faults: &[Fault],
    only: &[&str],
    cancel_at: Option<&str>,
    on_frame: &dyn Fn(&CanFrame) -> bool,
    rewrite: &dyn Fn(&CanFrame, bool) -> CanFrame,
) -> Report {
    let selection = Selection {
        only: only.iter().map(|s| (*s).to_owned()).collect(),
        ..Selection::default()
    };
    run_bytes_then(
        setup,
        bytes,
        name,
        node,
        faults,
        &selection,
        cancel_at,
        on_frame,
        rewrite,
        &mut |_| {},
    )
}

/// [`run_bytes`] with any selection, handing the bus to `after` once the run is over.
#[allow(clippy::too_many_arguments)]
fn run_bytes_then(
    setup: &Setup,
    bytes: &[u8],
    name: &str,
    node: u8,
    faults: &[Fault],
    selection: &Selection,
    cancel_at: Option<&str>,
    on_frame: &dyn Fn(&CanFrame) -> bool,
    rewrite: &dyn Fn(&CanFrame, bool) -> CanFrame,
    after: &mut dyn FnMut(&mut dyn Link),
) -> Report {
    let cancel = Cancel::new();
    let loaded = canopener_eds::load(bytes);
    let eds_errors = Some(canopener_conformance::cia301::eds::errors(&loaded, Some(name)));
    let eds = loaded.eds;
    let model = DeviceModel::new(&eds, node);
    let bus = setup
        .simulation
        .clone()
        .device(&eds, node)
        .faults(faults.iter().copied())
        .cancel(cancel.clone())
        .start()
        .expect("simulation");
    let mut bus = CancelOn {
        inner: bus,
        cancel: cancel.clone(),
        on_frame,
        rewrite,
    };
    let tests = selection.pick(&catalogue()).expect("selection");
    let spec = RunSpec {
        node,
        model: &model,
        eds: name.to_owned(),
        bus: bus.describe(),
        started: STARTED.to_owned(),
        sdo_timeout: setup.sdo_timeout,
        eds_errors,
        cancel: Some(cancel.clone()),
    };
    let report = runner::run_with(&mut bus, &spec, &setup.performance, &tests, |progress| {
        if progress.current.is_some_and(|t| Some(t.id) == cancel_at) {
            cancel.cancel();
        }
    })
    .expect("run")
    .report;
    after(&mut bus);
    report
}

/// A link that cancels `cancel` when it receives a frame `on_frame` accepts, and passes every frame
/// through `rewrite` (`true` when sent).
struct CancelOn<'f, L> {
    inner: L,
    cancel: Cancel,
    on_frame: &'f dyn Fn(&CanFrame) -> bool,
    rewrite: &'f dyn Fn(&CanFrame, bool) -> CanFrame,
}

impl<L: Link> Link for CancelOn<'_, L> {
    fn now(&self) -> Instant {
        self.inner.now()
    }

    fn send(&mut self, frame: &CanFrame) -> Result<(), LinkError> {
        self.inner.send(&(self.rewrite)(frame, true))
    }

    fn recv_until(&mut self, deadline: Instant) -> Result<Option<(Instant, CanFrame)>, LinkError> {
        Ok(self
            .recv_stamped_until(deadline)?
            .map(|stamped| (stamped.at, stamped.frame)))
    }

    fn recv_stamped_until(&mut self, deadline: Instant) -> Result<Option<Stamped>, LinkError> {
        let received = self.inner.recv_stamped_until(deadline)?.map(|mut stamped| {
            stamped.frame = (self.rewrite)(&stamped.frame, false);
            stamped
        });
        if received.as_ref().is_some_and(|s| (self.on_frame)(&s.frame)) {
            self.cancel.cancel();
        }
        Ok(received)
    }

    fn is_cancelled(&self) -> bool {
        self.inner.is_cancelled()
    }

    fn describe(&self) -> String {
        self.inner.describe()
    }

    fn timestamps(&self) -> Timestamps {
        self.inner.timestamps()
    }
}

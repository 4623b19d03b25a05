//! The whole conformance catalogue (`canopener test --suite all`) against the bundled demo device
//! (`canopener demo`'s CiA 401 EDS, node 5) whose every frame is chosen by the fuzzer's bytes:
//! canopener-testkit's `Hostile` with `Behaviour::Scripted` passes, drops, empties, shortens,
//! replaces, echoes, moves to another node's CAN-ID, repeats with the SDO toggle inverted, or adds
//! a frame, one input byte (or a few) per frame, and falls silent when the input runs out, so every
//! run ends.
//!
//! Whatever the device sends, the runner must not panic, hang (bounded virtual time and frames) or
//! cancel; every test gets a verdict unless the preparation found no device; the JSON report
//! parses; a test that met junk never passes and quotes a frame (`junk::unjudged`); a device that
//! fell silent (the input ran out) before the first test never passes (exit 6 or 7), and one whose
//! frames were never spoiled is the correct simulated device, which passes (exit 0).
//!
//! Short SDO timeout (20 ms of virtual time) and three repetitions of each cia313 measurement keep
//! an execution fast.

#![no_main]

use std::sync::OnceLock;
use std::time::Duration;

use canopener_bus_engine::virtual_bus::Timing;
use canopener_can::{CanFrame, Instant};
use canopener_conformance::catalogue::{TestDef, catalogue};
use canopener_conformance::device_model::DeviceModel;
use canopener_conformance::performance::Performance;
use canopener_conformance::runner::{self, RunSpec};
use canopener_eds::model::Eds;
use canopener_link::link::{Link, LinkError, Stamped, Timestamps};
use canopener_link::virtual_link::VirtualLink;
use canopener_sim::simulation::{Simulation, VIRTUAL_CALENDAR_START_UNIX_MILLIS};
use canopener_testkit::hostile::{Behaviour, Entropy, Hostile};
use libfuzzer_sys::fuzz_target;

const NODE: u8 = 5;
/// Far more virtual time than a run needs (every exchange waiting its timeout); a hang reaches it.
const LIMIT: Duration = Duration::from_secs(3600);
/// Far more frames than a run receives; a flood without end reaches it.
const MAX_FRAMES: usize = 1_000_000;

struct Fixed {
    eds: Eds,
    model: DeviceModel,
    tests: Vec<TestDef>,
}

fn fixed() -> &'static Fixed {
    static FIXED: OnceLock<Fixed> = OnceLock::new();
    FIXED.get_or_init(|| {
        let eds = canopener_eds::load(canopener_conformance::tour::EDS).eds;
        let model = DeviceModel::new(&eds, NODE);
        Fixed {
            eds,
            model,
            tests: catalogue(),
        }
    })
}

/// Cancelled once the run took [`LIMIT`] or received [`MAX_FRAMES`]: a hang shows as an
/// interrupted report, which the target rejects.
struct Bounded<L> {
    inner: L,
    limit: Instant,
    frames: usize,
}

impl<L: Link> Link for Bounded<L> {
    fn now(&self) -> Instant {
        self.inner.now()
    }

    fn send(&mut self, frame: &CanFrame) -> Result<(), LinkError> {
        self.inner.send(frame)
    }

    fn recv_until(&mut self, deadline: Instant) -> Result<Option<(Instant, CanFrame)>, LinkError> {
        Ok(self
            .recv_stamped_until(deadline)?
            .map(|stamped| (stamped.at, stamped.frame)))
    }

    fn recv_stamped_until(&mut self, deadline: Instant) -> Result<Option<Stamped>, LinkError> {
        let received = self.inner.recv_stamped_until(deadline.min(self.limit))?;
        self.frames += usize::from(received.is_some());
        Ok(received)
    }

    fn is_cancelled(&self) -> bool {
        self.inner.now() >= self.limit || self.frames >= MAX_FRAMES
    }

    fn describe(&self) -> String {
        self.inner.describe()
    }

    fn timestamps(&self) -> Timestamps {
        self.inner.timestamps()
    }
}

fuzz_target!(|data: &[u8]| {
    let fixed = fixed();
    let mut device = Simulation::ideal()
        .device(&fixed.eds, NODE)
        .build()
        .expect("the bundled EDS simulates")
        .pop()
        .expect("one device")
        .with_calendar_at_zero(VIRTUAL_CALENDAR_START_UNIX_MILLIS);
    device.boot(Instant::ZERO);
    let mut bus = VirtualLink::new(Timing::Ideal);
    let station = bus.attach(Hostile::new(
        device,
        NODE,
        Behaviour::Scripted,
        Entropy::script(data),
    ));
    let mut link = Bounded {
        inner: bus,
        limit: Instant::ZERO + LIMIT,
        frames: 0,
    };
    let spec = RunSpec {
        node: NODE,
        model: &fixed.model,
        eds: canopener_conformance::tour::EDS_NAME.to_owned(),
        bus: "fuzz".to_owned(),
        started: "2024-01-01T00:00:00Z".to_owned(),
        sdo_timeout: Duration::from_millis(20),
        eds_errors: Some(Vec::new()),
        cancel: None,
    };
    let performance = Performance {
        repetitions: 3,
        ..Performance::default()
    };
    let outcome = runner::run_with(&mut link, &spec, &performance, &fixed.tests, |_| {})
        .expect("the run starts");
    let report = &outcome.report;
    assert!(
        !report.interrupted,
        "hung or cancelled: {:?}",
        report.tests.last().map(|t| (&t.id, &t.reason))
    );
    if !outcome.silent {
        assert_eq!(report.tests.len(), fixed.tests.len(), "a verdict per test");
    }
    let json: serde_json::Value = serde_json::from_str(&report.to_json()).expect("the JSON report parses");
    assert_eq!(
        json["tests"].as_array().map(Vec::len),
        Some(report.tests.len())
    );
    let unjudged = canopener_conformance::junk::unjudged(NODE, report);
    assert!(unjudged.is_empty(), "{unjudged:#?}");
    let hostile = link.inner.virtual_bus().node(station).expect("the device");
    let first_test = report
        .tests
        .iter()
        .find_map(|t| t.telegrams.first())
        .map(|t| t.at);
    match (hostile.starved_since(), first_test) {
        // Silent from the preparation or the first test on: nothing can pass.
        (Some(starved), first) if first.is_none_or(|first| starved <= first) => {
            assert!(!outcome.passed(), "a device silent from {starved} on passed");
        }
        (None, _) if hostile.spoiled() == 0 => {
            let failed: Vec<_> = report
                .tests
                .iter()
                .filter(|t| !matches!(t.verdict.as_str(), "pass" | "not_applicable"))
                .map(|t| (&t.id, &t.reason))
                .collect();
            assert!(outcome.passed(), "the correct device did not pass: {failed:#?}");
        }
        _ => {}
    }
});

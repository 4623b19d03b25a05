//! A tester no device can crash: the whole catalogue (`test --suite all`) against hostile devices on
//! virtual time (canopener-testkit's `hostile`): answers with no data, cut short, random, echoed, on
//! another node's CAN-ID, babbling with SDO toggles out of order, buried in a flood, and a junk node
//! beside a correct device. Every run ends, within bounded virtual time, with a verdict per test,
//! the exit code the CLI gives is 6 or 7, the JSON report parses, and no test that met junk passes
//! or says "not applicable".

use std::collections::BTreeMap;
use std::time::Duration;

use canopener_can::{CanFrame, Core, Instant};
use canopener_conformance::catalogue::{Selection, TestDef, catalogue};
use canopener_conformance::context::Ctx;
use canopener_conformance::device_model::DeviceModel;
use canopener_conformance::finding::{Finding, Outcome as TestOutcome};
use canopener_conformance::junk;
use canopener_conformance::model::{Report, Verdict};
use canopener_conformance::performance::Performance;
use canopener_conformance::runner::{self, FinishedRun, RunSpec};
use canopener_eds::model::Eds;
use canopener_link::link::{Link, LinkError, Stamped, Timestamps};
use canopener_link::virtual_link::VirtualLink;
use canopener_sim::device::SimulatedDevice;
use canopener_sim::simulation::{Simulation, VIRTUAL_CALENDAR_START_UNIX_MILLIS};
use canopener_testkit::hostile::{Behaviour, Entropy, Hostile, JunkNode, Station};

/// The node of the device under test.
const NODE: u8 = 5;

/// The most virtual time a run may take: far beyond any run here (a hostile device makes every
/// SDO exchange wait its timeout), and what a hang would reach.
const LIMIT: Duration = Duration::from_secs(1800);

/// The most frames a run may receive before it counts as hung.
const MAX_FRAMES: usize = 2_000_000;

/// cia313's repetitions here: the hostile devices spoil the answers, not their number.
const REPETITIONS: usize = 20;

fn demo_eds() -> Eds {
    canopener_eds::load(canopener_conformance::tour::EDS).eds
}

/// The demo device (the bundled CiA 401 EDS) on node [`NODE`], powered on at virtual time zero.
fn device(eds: &Eds) -> SimulatedDevice {
    let mut device = Simulation::ideal()
        .device(eds, NODE)
        .build()
        .expect("the bundled EDS simulates")
        .pop()
        .expect("one device")
        .with_calendar_at_zero(VIRTUAL_CALENDAR_START_UNIX_MILLIS);
    device.boot(Instant::ZERO);
    device
}

/// A link that counts as cancelled once the run took [`LIMIT`] of virtual time or received
/// [`MAX_FRAMES`]: a hang ends as an interrupted report instead of a test that never ends.
struct Bounded<L> {
    inner: L,
    limit: Instant,
    frames: usize,
}

impl<L: Link> Bounded<L> {
    fn new(inner: L) -> Bounded<L> {
        let limit = inner.now() + LIMIT;
        Bounded {
            inner,
            limit,
            frames: 0,
        }
    }
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

/// Runs `tests` against whatever is on `link`, as `canopener test` does.
fn run_on(link: &mut dyn Link, eds: &Eds, tests: &[TestDef], sdo_timeout: Duration) -> FinishedRun {
    let model = DeviceModel::new(eds, NODE);
    let spec = RunSpec {
        node: NODE,
        model: &model,
        eds: canopener_conformance::tour::EDS_NAME.to_owned(),
        bus: link.describe(),
        started: "2024-01-01T00:00:00Z".to_owned(),
        sdo_timeout,
        eds_errors: Some(Vec::new()),
        cancel: None,
    };
    let performance = Performance {
        repetitions: REPETITIONS,
        ..Performance::default()
    };
    runner::run_with(link, &spec, &performance, tests, |_| {}).expect("the run starts")
}

/// The whole catalogue against `core` alone on a simulated bus.
fn run_all<C: Core>(core: C) -> FinishedRun {
    let eds = demo_eds();
    let mut bus = VirtualLink::new(canopener_bus_engine::virtual_bus::Timing::Ideal);
    bus.attach(core);
    run_on(
        &mut Bounded::new(bus),
        &eds,
        &catalogue(),
        Duration::from_millis(500),
    )
}

/// The exit code `canopener test` gives for `outcome` (crates/canopener-cli/src/test/command.rs).
fn exit_code(outcome: &FinishedRun) -> u8 {
    if outcome.report.interrupted {
        130
    } else if outcome.silent {
        7
    } else if outcome.passed() {
        0
    } else {
        6
    }
}

/// What every run against a hostile device must show (see the module docs); returns a line for
/// the test's output.
fn check(outcome: &FinishedRun, what: &str) -> String {
    let report = &outcome.report;
    // Junk and silence are never a reason for "not applicable": every test that is, is so on the
    // clean device too, for the same reason.
    let clean = clean_not_applicable();
    let extra: Vec<_> = not_applicable(report)
        .into_iter()
        .filter(|(id, reason)| clean.get(id) != Some(reason))
        .collect();
    assert!(extra.is_empty(), "{what}: not applicable only here: {extra:#?}");
    assert!(
        !report.interrupted,
        "{what}: the run was interrupted (hung past {LIMIT:?} or {MAX_FRAMES} frames): {:#?}",
        report.tests.last().map(|t| (&t.id, &t.reason))
    );
    let code = exit_code(outcome);
    assert!(code == 6 || code == 7, "{what}: exit code {code}");
    if !outcome.silent {
        assert_eq!(
            report.tests.len(),
            catalogue().len(),
            "{what}: a verdict per test"
        );
    }
    assert!(
        report.duration_s < LIMIT.as_secs_f64(),
        "{what}: {} s",
        report.duration_s
    );
    let json: serde_json::Value = serde_json::from_str(&report.to_json()).expect("the JSON report parses");
    assert_eq!(
        json["summary"]["fail"].as_u64(),
        Some(report.summary.fail as u64),
        "{what}"
    );
    for test in &report.tests {
        if matches!(test.verdict, Verdict::Fail | Verdict::Inconclusive) {
            assert!(
                !test.reason.trim().is_empty(),
                "{what}: {} has no reason",
                test.id
            );
        }
    }
    // Junk on the device's CAN-IDs: the test fails or is inconclusive, and quotes a frame.
    let unjudged = junk::unjudged(NODE, report);
    assert!(unjudged.is_empty(), "{what}: {unjudged:#?}");
    let s = &report.summary;
    format!(
        "{what}: exit {code}, {} pass, {} fail, {} inconclusive, {} not applicable, {:.1} s virtual; preparation: {}",
        s.pass,
        s.fail,
        s.inconclusive,
        s.not_applicable,
        report.duration_s,
        report.preparation.join("; ")
    )
}

/// Every behaviour of the hostile harness, spoiling every answer and 30 % of them, against the
/// whole catalogue.
#[test]
fn every_hostile_behaviour_ends_the_whole_catalogue_with_verdicts() {
    let eds = demo_eds();
    let mut lines = Vec::new();
    for behaviour in Behaviour::ALL {
        for percent in [100, 30] {
            if percent < 100 && matches!(behaviour, Behaviour::Flood | Behaviour::Scripted) {
                // Neither spoils a share: the flood leaves answers alone, a script decides each.
                continue;
            }
            let hostile = Hostile::new(device(&eds), NODE, behaviour, Entropy::seeded(22)).percent(percent);
            let outcome = run_all(hostile);
            lines.push(check(&outcome, &format!("{} {percent} %", behaviour.name())));
        }
    }
    for line in &lines {
        println!("{line}");
    }
}

/// A device whose every answer and heartbeat is a fuzzer-like script of random bytes, for several
/// scripts: the catalogue still ends.
#[test]
fn scripted_devices_of_random_bytes_end_with_verdicts() {
    let eds = demo_eds();
    for seed in 1..=4u64 {
        let mut state = Entropy::seeded(seed);
        let script = state.bytes(4000);
        let hostile = Hostile::new(device(&eds), NODE, Behaviour::Scripted, Entropy::script(script));
        let outcome = run_all(hostile);
        println!("{}", check(&outcome, &format!("script of seed {seed}")));
    }
}

/// The not-applicable tests of the clean demo device, with their reasons (run once).
fn clean_not_applicable() -> &'static BTreeMap<String, String> {
    static CLEAN: std::sync::OnceLock<BTreeMap<String, String>> = std::sync::OnceLock::new();
    CLEAN.get_or_init(|| not_applicable(&run_all(device(&demo_eds())).report))
}

/// The tests that are not applicable, with their reasons.
fn not_applicable(report: &Report) -> BTreeMap<String, String> {
    report
        .tests
        .iter()
        .filter(|t| t.verdict == Verdict::NotApplicable)
        .map(|t| (t.id.clone(), t.reason.clone()))
        .collect()
}

/// Issue 22's measurement: beside a correct device, a second node answers 30 % of the requests to
/// it first, with junk (empty, short or random frames, or echoes). Junk is never taken for "not
/// applicable": every test that is not applicable is so on the clean device too, for the same
/// reason ([`check`]), and the tests the junk reached fail or are inconclusive, quoting a frame.
#[test]
fn a_junk_node_beside_a_correct_device_adds_no_not_applicable_verdict() {
    let eds = demo_eds();
    let clean = run_all(device(&eds));
    assert!(!clean.report.interrupted && !clean.silent);
    assert_eq!(clean.report.summary.fail + clean.report.summary.inconclusive, 0);
    let clean_na = not_applicable(&clean.report);
    println!(
        "clean: {} pass, {} not applicable",
        clean.report.summary.pass,
        clean_na.len()
    );
    let seeds: u64 = std::env::var("JUNK_SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(5);
    for seed in 1..=seeds {
        let mut bus = VirtualLink::new(canopener_bus_engine::virtual_bus::Timing::Ideal);
        // The junk node first: at one instant its answer goes out before the device's.
        let junk = bus.attach(Station::Junk(JunkNode::new(NODE, 30, Entropy::seeded(seed))));
        bus.attach(Station::Device(device(&eds)));
        let mut link = Bounded::new(bus);
        let outcome = run_on(&mut link, &eds, &catalogue(), Duration::from_millis(500));
        let answered = match link.inner.virtual_bus().node(junk) {
            Some(Station::Junk(node)) => node.answered(),
            _ => 0,
        };
        let line = check(&outcome, &format!("junk node, seed {seed}"));
        if outcome.silent {
            // The junk answered the preparation's read of 1000h: nothing was tested (exit 7), and
            // the preparation says what came.
            assert!(
                outcome.report.preparation.iter().any(|p| p.contains("585#")),
                "seed {seed}: {:?}",
                outcome.report.preparation
            );
        } else {
            assert!(
                answered > 50,
                "seed {seed}: the junk node answered {answered} requests"
            );
        }
        println!("{line}; junk answers: {answered}");
    }
}

/// Sends a frame CAN cannot carry: the tester cannot build it.
fn nine_bytes(ctx: &mut Ctx<'_, '_>) -> TestOutcome {
    ctx.send(0x205, &[0; 9])?;
    Ok(Finding::pass("sent"))
}

/// A frame the tester cannot build makes its test inconclusive with the reason, and the run goes
/// on: it is not a cancellation ("interrupted (Ctrl-C)").
#[test]
fn a_frame_the_tester_cannot_build_is_inconclusive_and_the_run_goes_on() {
    let eds = demo_eds();
    let unsendable = TestDef {
        id: "hostile.unsendable",
        suite: "cia301",
        group: "pdo",
        title: "sends 9 bytes",
        references: &[],
        precondition: "",
        tags: &[],
        run: nine_bytes,
    };
    let selection = Selection {
        only: vec!["cia301.sdo.1".to_owned()],
        ..Selection::default()
    };
    let mut tests = vec![unsendable];
    tests.extend(selection.pick(&catalogue()).expect("sdo.1"));
    let mut bus = VirtualLink::new(canopener_bus_engine::virtual_bus::Timing::Ideal);
    bus.attach(device(&eds));
    let outcome = run_on(&mut Bounded::new(bus), &eds, &tests, Duration::from_millis(500));
    let report = &outcome.report;
    assert!(!report.interrupted);
    assert_eq!(report.tests.len(), 2);
    assert_eq!(report.tests[0].verdict, Verdict::Inconclusive);
    assert_eq!(
        report.tests[0].reason,
        "the tester cannot send 9 bytes on 0x205: a classical CAN frame carries at most 8 data bytes, got 9"
    );
    assert_eq!(
        report.tests[1].verdict,
        Verdict::Pass,
        "{}",
        report.tests[1].reason
    );
}

/// Answers the block upload start (A3h) of node 5 with block segments numbered 1 every millisecond,
/// forever: a server that never completes a sub-block.
#[derive(Debug)]
struct EndlessBlock {
    device: SimulatedDevice,
    next: Option<Instant>,
    out: Option<CanFrame>,
}

impl Core for EndlessBlock {
    type Event = <SimulatedDevice as Core>::Event;

    fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
        if frame.id().as_raw() == 0x605 && frame.data().first() == Some(&0xA3) {
            self.next = Some(now);
        } else {
            self.device.handle_frame(now, frame);
        }
    }

    fn handle_timeout(&mut self, now: Instant) {
        if self.next.is_some_and(|due| due <= now) {
            self.out = CanFrame::new(
                canopener_can::StandardId::new(0x585).expect("id"),
                &[0x01, 1, 2, 3, 4, 5, 6, 7],
            )
            .ok();
            self.next = Some(now + Duration::from_millis(1));
        }
        if self.device.poll_timeout().is_some_and(|due| due <= now) {
            self.device.handle_timeout(now);
        }
    }

    fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.out.take().or_else(|| self.device.poll_transmit())
    }

    fn poll_event(&mut self) -> Option<Self::Event> {
        self.device.poll_event()
    }

    fn poll_timeout(&self) -> Option<Instant> {
        [self.next, self.device.poll_timeout()]
            .into_iter()
            .flatten()
            .min()
    }
}

/// `cia301.sdo.21` reads one sub-block: a server that sends segments without end cannot keep it
/// waiting (it did: the test looped until the segments stopped).
#[test]
fn a_server_sending_block_segments_without_end_cannot_hold_up_a_test() {
    let eds = demo_eds();
    let selection = Selection {
        only: vec!["cia301.sdo.21".to_owned()],
        ..Selection::default()
    };
    let tests = selection.pick(&catalogue()).expect("sdo.21");
    let mut bus = VirtualLink::new(canopener_bus_engine::virtual_bus::Timing::Ideal);
    bus.attach(EndlessBlock {
        device: device(&eds),
        next: None,
        out: None,
    });
    let outcome = run_on(&mut Bounded::new(bus), &eds, &tests, Duration::from_millis(500));
    let report = &outcome.report;
    assert!(!report.interrupted, "hung");
    let test = &report.tests[0];
    assert!(test.duration_s < 5.0, "{} s: {}", test.duration_s, test.reason);
}

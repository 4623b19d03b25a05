//! The CiA 401 input tests through the user's stimulus hook: a simulated device whose factory test
//! registers the tester cannot reach (a device without them, as most are) is `inconclusive`
//! without a hook, passes io.2–io.6, io.8 and io.9 with a hook that really applies the inputs, and is
//! never passed by a hook that fails or only claims to apply them.
//!
//! The rig: a link between the tester and the simulated bus that answers the tester's SDO requests
//! to 2000h–2002h as if the objects did not exist, while the Rust [`Stimulus`] here applies each
//! input by its own SDO downloads to those registers, sent beside the tester's traffic and hidden
//! from it, as a wire to the terminals would be.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::rc::Rc;
use std::time::Duration;

use canopener_can::{CanFrame, CanId, Instant, StandardId};
use canopener_conformance::catalogue::{Selection, catalogue};
use canopener_conformance::device_model::DeviceModel;
use canopener_conformance::model::{Report, Verdict};
use canopener_conformance::performance::Performance;
use canopener_conformance::runner::{self, RunSpec};
use canopener_conformance::stimulus::{Hook, InputChange, Stimulus};
use canopener_link::link::{Link, LinkError};
use canopener_sim::simulation::Simulation;

const NODE: u8 = 5;
/// The index the tester's requests to the hidden registers are turned to: no device has it.
const NOWHERE: u16 = 0x2FFF;

fn full_io() -> Vec<u8> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("test_data/cia401_full_io.eds");
    canopener_testkit::fixture::read(&path).expect("fixture")
}

fn sdo_id(base: u16) -> CanId {
    CanId::Standard(StandardId::new(base + u16::from(NODE)).unwrap())
}

fn hidden(index: u16) -> bool {
    (0x2000..=0x2002).contains(&index)
}

/// The SDO downloads the stimulus wants on the bus.
type Pending = Rc<RefCell<VecDeque<CanFrame>>>;

/// See the module docs.
struct RigLink<L> {
    inner: L,
    pending: Pending,
    /// The index of the tester's request turned to [`NOWHERE`], until its answer comes back.
    turned: Option<u16>,
}

impl<L: Link> RigLink<L> {
    fn flush(&mut self) -> Result<(), LinkError> {
        let frames: Vec<_> = self.pending.borrow_mut().drain(..).collect();
        for frame in frames {
            self.inner.send(&frame)?;
        }
        Ok(())
    }
}

impl<L: Link> Link for RigLink<L> {
    fn now(&self) -> Instant {
        self.inner.now()
    }

    fn send(&mut self, frame: &CanFrame) -> Result<(), LinkError> {
        self.flush()?;
        let data = frame.data();
        if frame.id() == sdo_id(0x600) && data.len() == 8 {
            let index = u16::from_le_bytes([data[1], data[2]]);
            if hidden(index) {
                let mut turned = data.to_vec();
                turned[1..3].copy_from_slice(&NOWHERE.to_le_bytes());
                self.turned = Some(index);
                return self.inner.send(&CanFrame::new(frame.id(), &turned).unwrap());
            }
        }
        self.inner.send(frame)
    }

    fn recv_until(&mut self, deadline: Instant) -> Result<Option<(Instant, CanFrame)>, LinkError> {
        self.flush()?;
        loop {
            let Some((at, frame)) = self.inner.recv_until(deadline)? else {
                return Ok(None);
            };
            let data = frame.data();
            if frame.id() != sdo_id(0x580) || data.len() != 8 {
                return Ok(Some((at, frame)));
            }
            let index = u16::from_le_bytes([data[1], data[2]]);
            // The stimulus's confirmations are the rig's business, not the tester's.
            if hidden(index) {
                continue;
            }
            if let Some(original) = self.turned.take().filter(|_| index == NOWHERE) {
                let mut back = data.to_vec();
                back[1..3].copy_from_slice(&original.to_le_bytes());
                return Ok(Some((at, CanFrame::new(frame.id(), &back).unwrap())));
            }
            return Ok(Some((at, frame)));
        }
    }

    fn is_cancelled(&self) -> bool {
        self.inner.is_cancelled()
    }

    fn describe(&self) -> String {
        self.inner.describe()
    }
}

/// How the stimulus behaves.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Rig {
    /// Applies every input through the hidden factory test registers.
    Wired,
    /// Says each input is applied and does nothing.
    Claims,
    /// Reports every input as failed.
    Broken,
}

struct RigStimulus {
    rig: Rig,
    pending: Pending,
    applied: Vec<InputChange>,
}

impl Stimulus for RigStimulus {
    fn apply(&mut self, change: &InputChange) -> Result<(), String> {
        self.applied.push(*change);
        match self.rig {
            Rig::Broken => return Err("rig offline".to_owned()),
            Rig::Claims => return Ok(()),
            Rig::Wired => {}
        }
        let download = |index: u16, sub: u8, value: &[u8]| {
            let mut data = [0u8; 8];
            // Expedited download, size indicated (CiA 301 §7.2.4.3.3).
            data[0] = 0x23 | ((4 - value.len() as u8) << 2);
            data[1..3].copy_from_slice(&index.to_le_bytes());
            data[3] = sub;
            data[4..4 + value.len()].copy_from_slice(value);
            CanFrame::new(sdo_id(0x600), &data).unwrap()
        };
        let mut pending = self.pending.borrow_mut();
        pending.push_back(download(0x2000, 0, &[1]));
        pending.push_back(match *change {
            InputChange::Digital { value, .. } => download(0x2001, 0, &[value]),
            InputChange::Analog { channel, value } => download(0x2002, channel, &value.to_le_bytes()),
        });
        Ok(())
    }
}

/// Runs the cia401 suite against the full-I/O device behind the rig; the inputs each applied.
fn run(rig: Option<Rig>) -> (Report, Vec<InputChange>) {
    let eds = canopener_eds::load(&full_io()).eds;
    let model = DeviceModel::new(&eds, NODE);
    let bus = Simulation::ideal()
        .device(&eds, NODE)
        .start()
        .expect("simulation");
    let pending = Pending::default();
    let mut link = RigLink {
        inner: bus,
        pending: pending.clone(),
        turned: None,
    };
    let mut stimulus = rig.map(|rig| RigStimulus {
        rig,
        pending,
        applied: Vec::new(),
    });
    let hook = stimulus.as_mut().map(|s| Hook {
        stimulus: s as &mut dyn Stimulus,
        settle: Duration::from_millis(5),
    });
    let selection = Selection {
        suite: Some("cia401".to_owned()),
        ..Selection::default()
    };
    let tests = selection.pick(&catalogue()).expect("selection");
    let spec = RunSpec {
        node: NODE,
        model: &model,
        eds: "cia401_full_io.eds".to_owned(),
        bus: link.describe(),
        started: "2024-01-01T00:00:00Z".to_owned(),
        sdo_timeout: Duration::from_millis(500),
        eds_errors: None,
        cancel: None,
    };
    let report = runner::run_stimulated(&mut link, &spec, &Performance::default(), hook, &tests, |_| {})
        .expect("run")
        .report;
    (report, stimulus.map(|s| s.applied).unwrap_or_default())
}

fn verdict<'r>(report: &'r Report, id: &str) -> (Verdict, &'r str) {
    let test = report.tests.iter().find(|t| t.id == id).expect(id);
    (test.verdict, &test.reason)
}

const INPUT_TESTS: [&str; 7] = [
    "cia401.io.2",
    "cia401.io.3",
    "cia401.io.4",
    "cia401.io.5",
    "cia401.io.6",
    "cia401.io.8",
    "cia401.io.9",
];

#[test]
fn without_the_registers_or_a_hook_the_input_tests_are_inconclusive_and_say_why() {
    let (report, _) = run(None);
    for id in INPUT_TESTS {
        let (verdict, reason) = verdict(&report, id);
        assert_eq!(verdict, Verdict::Inconclusive, "{id}: {reason}");
        assert!(reason.contains("--stimulus"), "{id}: {reason}");
    }
    // The tests that need no input still run.
    assert_eq!(verdict(&report, "cia401.io.7").0, Verdict::Pass);
}

#[test]
fn a_hook_that_applies_the_inputs_makes_every_input_test_pass() {
    let (report, applied) = run(Some(Rig::Wired));
    for test in &report.tests {
        assert_eq!(test.verdict, Verdict::Pass, "{}: {}", test.id, test.reason);
    }
    for id in INPUT_TESTS {
        let (_, reason) = verdict(&report, id);
        assert!(reason.contains("stimulus hook"), "{id}: {reason}");
    }
    // The polarity test's inputs, the interrupt tests' edges, both analogue values, and the
    // restoring changes to 00h and 0.
    for change in [
        InputChange::Digital {
            block: 1,
            value: 0x5A,
        },
        InputChange::Digital {
            block: 1,
            value: 0x42,
        },
        InputChange::Digital {
            block: 1,
            value: 0x00,
        },
        InputChange::Analog {
            channel: 1,
            value: 1000,
        },
        InputChange::Analog {
            channel: 1,
            value: -1234,
        },
        InputChange::Analog { channel: 1, value: 0 },
    ] {
        assert!(applied.contains(&change), "{change} not applied: {applied:?}");
    }
    assert!(report.left_modified.is_empty(), "{:?}", report.left_modified);
}

#[test]
fn a_failing_hook_is_inconclusive_with_its_reason() {
    let (report, applied) = run(Some(Rig::Broken));
    for id in INPUT_TESTS {
        let (verdict, reason) = verdict(&report, id);
        assert_eq!(verdict, Verdict::Inconclusive, "{id}: {reason}");
        assert!(reason.contains("rig offline"), "{id}: {reason}");
    }
    // Each test stopped at its first failed change.
    assert_eq!(applied.len(), INPUT_TESTS.len(), "{applied:?}");
}

#[test]
fn a_hook_that_only_claims_to_apply_the_inputs_never_passes() {
    let (report, _) = run(Some(Rig::Claims));
    for id in INPUT_TESTS {
        let (verdict, reason) = verdict(&report, id);
        assert_ne!(verdict, Verdict::Pass, "{id}: {reason}");
    }
    let test = report.tests.iter().find(|t| t.id == "cia401.io.2").unwrap();
    assert_eq!(test.verdict, Verdict::Fail, "{}", test.reason);
    assert!(test.analysis.contains("stimulus hook"), "{}", test.analysis);
}

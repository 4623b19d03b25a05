//! Runs a selection of tests against one node and builds the [`Report`]: preparation (reset node,
//! boot-up, identity), then each test with its own telegram log, its values written back and the
//! device put into pre-operational afterwards.

use std::time::Duration;

use canopener_can::Instant;
use canopener_link::link::Link;
use canopener_link::sdo_session::SdoSession;
use canopener_wire::{Decoder, NmtCommand};

use crate::context::{Ctx, Reply};
use crate::device_model::DeviceModel;
use crate::finding::{Finding, Stop};
use crate::model::{
    BusInfo, DeviceInfo, Identity, REPORT_VERSION, Report, Telegram, TestReport, VerdictCounts,
};
use crate::performance::Performance;
use crate::recorder::{Logged, Recorder};
use crate::stimulus::Hook;
use crate::test_def::TestDef;

/// What a run needs besides the link.
#[derive(Debug, Clone)]
pub struct RunSpec<'a> {
    /// The node under test.
    pub node: u8,
    /// What the EDS says.
    pub model: &'a DeviceModel,
    /// The EDS as the user named it.
    pub eds: String,
    /// The bus as the user named it.
    pub bus: String,
    /// When the run started, RFC 3339 (the caller reads the clock).
    pub started: String,
    /// The SDO timeout.
    pub sdo_timeout: Duration,
    /// The errors of canopener's EDS checks on the file ([`crate::cia301::eds::errors`]); `None`
    /// when the description was not an EDS/DCF.
    pub eds_errors: Option<Vec<String>>,
    /// The token the link honours (the CLI's Ctrl-C). When it stops a test, the runner takes the
    /// cancellation back once to put the device into pre-operational and write back what the test
    /// changed (each SDO transfer bounded by the timeout), then cancels again; a second Ctrl-C
    /// stops the write-back too. `None`: nothing is written back after a cancellation.
    pub cancel: Option<canopener_link::cancel::Cancel>,
}

/// How far a run got, for a progress bar.
#[derive(Debug, Clone, Copy)]
pub struct Progress<'a> {
    /// Tests finished.
    pub done: usize,
    /// Tests selected.
    pub total: usize,
    /// The test starting now (`None` when all are done).
    pub current: Option<&'a TestDef>,
    /// The test that ended just before, with its verdict, so a display can show verdicts as they
    /// come (`None` before the first test).
    pub finished: Option<&'a TestReport>,
}

/// The run could not start.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The node-ID or the timeout cannot make an SDO session.
    #[error(transparent)]
    Session(#[from] canopener_link::sdo_session::SessionError),
}

/// The result of [`run`]: the report and whether the device answered at all.
#[derive(Debug, Clone)]
pub struct FinishedRun {
    /// The report (tests missing when interrupted).
    pub report: Report,
    /// The device did not answer the preparation's SDO read of 1000h: nothing was tested.
    pub silent: bool,
}

/// Runs `tests` against `spec.node` on `link` (see the [module docs](self)), the performance tests
/// with the documented default criteria and repetitions.
pub fn run(
    link: &mut dyn Link,
    spec: &RunSpec<'_>,
    tests: &[TestDef],
    on_progress: impl FnMut(Progress<'_>),
) -> Result<FinishedRun, RunError> {
    run_with(link, spec, &Performance::DEFAULT, tests, on_progress)
}

/// [`run`] with the performance tests' criteria and repetitions.
pub fn run_with(
    link: &mut dyn Link,
    spec: &RunSpec<'_>,
    performance: &Performance,
    tests: &[TestDef],
    on_progress: impl FnMut(Progress<'_>),
) -> Result<FinishedRun, RunError> {
    run_stimulated(link, spec, performance, None, tests, on_progress)
}

/// [`run_with`] with the user's stimulus hook, which the CiA 401 tests use to change inputs on a
/// device without the factory test registers.
pub fn run_stimulated(
    link: &mut dyn Link,
    spec: &RunSpec<'_>,
    performance: &Performance,
    mut stimulus: Option<Hook<'_>>,
    tests: &[TestDef],
    mut on_progress: impl FnMut(Progress<'_>),
) -> Result<FinishedRun, RunError> {
    let timestamps = link.timestamps();
    let mut recorder = Recorder::new(link);
    let start = recorder.now();
    let mut report = Report {
        version: REPORT_VERSION,
        device: DeviceInfo {
            node: Some(spec.node),
            eds: spec.eds.clone(),
            identity: None,
        },
        bus: BusInfo {
            spec: spec.bus.clone(),
            timestamps: timestamps.source.as_str().to_owned(),
            resolution_us: timestamps.resolution.as_secs_f64() * 1e6,
        },
        started: spec.started.clone(),
        duration_s: 0.0,
        interrupted: false,
        preparation: Vec::new(),
        left_modified: Vec::new(),
        tests: Vec::new(),
        summary: VerdictCounts::default(),
    };
    // The EDS check alone needs no device: nothing to reset, nobody to ask.
    let prepared = if tests.iter().all(|t| !t.needs_device()) {
        report
            .preparation
            .push("no device needed: only the EDS check runs".to_owned());
        Ok(true)
    } else {
        prepare(&mut recorder, spec, &mut report)?
    };
    recorder.clear();
    let silent = matches!(prepared, Ok(false));
    if let Err(Stop::Cancelled) | Err(Stop::Link(_)) = prepared {
        report.interrupted = true;
    }
    if matches!(prepared, Ok(true)) {
        for (done, test) in tests.iter().enumerate() {
            on_progress(Progress {
                done,
                total: tests.len(),
                current: Some(test),
                finished: report.tests.last(),
            });
            let test_start = recorder.now();
            let (finding, done, left, stopped) =
                run_one(&mut recorder, spec, performance, stimulus.as_mut(), test)?;
            report.left_modified.extend(left);
            // Each test's log is decoded on its own: what an earlier test left open (a guarding
            // request nobody answered) must not colour the next one's frames.
            let telegrams = telegrams(recorder.since(0), start, &mut Decoder::new());
            recorder.clear();
            report.tests.push(TestReport {
                id: test.id.to_owned(),
                suite: test.suite.to_owned(),
                group: test.group.to_owned(),
                title: test.title.to_owned(),
                references: test.references.iter().map(|r| (*r).to_owned()).collect(),
                verdict: finding.verdict,
                reason: finding.reason,
                analysis: finding.analysis,
                measurements: done.measurements,
                duration_s: recorder.now().saturating_duration_since(test_start).as_secs_f64(),
                performed: done.performed,
                telegrams,
                no_criterion: done.no_criterion,
            });
            if stopped {
                report.interrupted = true;
                break;
            }
        }
        on_progress(Progress {
            done: report.tests.len(),
            total: tests.len(),
            current: None,
            finished: report.tests.last(),
        });
    }
    report.duration_s = recorder.now().saturating_duration_since(start).as_secs_f64();
    report.summary = VerdictCounts::of(&report.tests);
    Ok(FinishedRun { report, silent })
}

/// How often the preparation reads 1000h when the answers break the SDO protocol.
const PREPARATION_READS: usize = 3;

/// Resets the node, waits for its boot-up and reads its identity; `Ok(false)` when it does not
/// answer an SDO read of 1000h.
fn prepare(
    recorder: &mut Recorder<'_>,
    spec: &RunSpec<'_>,
    report: &mut Report,
) -> Result<Result<bool, Stop>, RunError> {
    let session = SdoSession::new(&mut *recorder, spec.node, spec.sdo_timeout)?;
    let mut ctx = Ctx::new(session, spec.model, spec.eds_errors.as_deref());
    let result = (|| -> Result<bool, Stop> {
        ctx.nmt(NmtCommand::ResetNode, false)?;
        let boot = ctx.id(0x700 + u16::from(spec.node));
        let heard = ctx
            .wait_for(crate::procedures::nmt::BOOT_UP_WAIT, |f| {
                f.id() == boot && f.data() == [0]
            })?
            .is_some();
        report.preparation.push(format!(
            "NMT reset node {}: {}",
            spec.node,
            if heard {
                "boot-up received"
            } else {
                "no boot-up within 2 s"
            }
        ));
        let mut reply = ctx.read(0x1000, 0)?;
        // An answer that broke the protocol may be another node's: ask again, a few times.
        for _ in 1..PREPARATION_READS {
            let Reply::Broken { .. } = reply else { break };
            report
                .preparation
                .push(format!("SDO upload 1000h:00: {}; asked again", reply.describe()));
            reply = ctx.read(0x1000, 0)?;
        }
        if !matches!(reply, Reply::Done(_)) {
            let answer = match reply {
                Reply::Silent => "no answer".to_owned(),
                other => format!("no usable answer: {}", other.describe()),
            };
            report.preparation.push(format!("SDO upload 1000h:00: {answer}"));
            return Ok(false);
        }
        let mut field = |sub: u8| -> Result<Option<u32>, Stop> {
            Ok(match ctx.read(0x1018, sub)? {
                Reply::Done(d) => <[u8; 4]>::try_from(d.as_slice()).ok().map(u32::from_le_bytes),
                _ => None,
            })
        };
        report.device.identity = Some(Identity {
            vendor_id: field(1)?,
            product_code: field(2)?,
            revision: field(3)?,
            serial: field(4)?,
        });
        Ok(true)
    })();
    Ok(result)
}

/// What a test left besides its verdict: its measurements, whether one was judged against no
/// criterion, and the CCT cases it performed.
struct Done {
    measurements: std::collections::BTreeMap<String, crate::model::Measurement>,
    no_criterion: bool,
    performed: Vec<String>,
}

type OneResult = (Finding, Done, Vec<String>, bool);

fn run_one(
    recorder: &mut Recorder<'_>,
    spec: &RunSpec<'_>,
    performance: &Performance,
    stimulus: Option<&mut Hook<'_>>,
    test: &TestDef,
) -> Result<OneResult, RunError> {
    let session = SdoSession::new(&mut *recorder, spec.node, spec.sdo_timeout)?;
    let mut ctx = Ctx::new(session, spec.model, spec.eds_errors.as_deref())
        .with_performance(performance)
        .with_stimulus(stimulus.map(Hook::reborrow));
    let (finding, mut stopped) = match (test.run)(&mut ctx) {
        Ok(finding) => (finding, false),
        Err(Stop::Cancelled) => (
            Finding::inconclusive("interrupted (Ctrl-C) before a verdict"),
            true,
        ),
        Err(Stop::Link(error)) => (Finding::inconclusive(format!("the bus failed: {error}")), true),
        Err(Stop::Unsendable(reason)) => (Finding::inconclusive(reason), false),
    };
    let done = Done {
        measurements: ctx.take_measurements(),
        no_criterion: ctx.without_criterion(),
        performed: ctx.take_performed(),
    };
    // A test that put no frame on the bus (a precondition from the EDS alone said not_applicable)
    // changed nothing: no cleanup, which would cost each such test the settling time.
    let untouched = ctx.mark() == 0 && !stopped;
    if !test.needs_device() || untouched {
        return Ok((finding, done, Vec::new(), stopped));
    }
    let interrupted = stopped && ctx.link_cancelled();
    if let Some(cancel) = spec.cancel.as_ref().filter(|_| interrupted) {
        cancel.resume();
    }
    // Pre-operational first: a device left stopped would not serve the SDO writes that restore it.
    let cleanup = (|| -> Result<Vec<String>, Stop> {
        ctx.nmt(NmtCommand::EnterPreOperational, false)?;
        ctx.listen(Duration::from_millis(10), |_| false)?;
        let mut left = ctx.restore()?;
        if !left.is_empty() && !interrupted {
            // What could not be written back would reach the tests that follow (a mapping left
            // empty makes them "not applicable"): reset node brings back the power-on values
            // (CiA 301 §7.2.8.3.1), then pre-operational as after every test.
            let heard = crate::procedures::nmt::reset_node(&mut ctx)?;
            ctx.nmt(NmtCommand::EnterPreOperational, false)?;
            ctx.listen(Duration::from_millis(10), |_| false)?;
            left.push(format!(
                "after {}: NMT reset node sent to bring back the power-on values ({})",
                test.id,
                if heard {
                    "boot-up received"
                } else {
                    "no boot-up within 2 s"
                }
            ));
        }
        Ok(left)
    })();
    if let Some(cancel) = spec.cancel.as_ref().filter(|_| interrupted) {
        // The run still ends here, as the user asked.
        cancel.cancel();
    }
    // The write-back's frames are part of the test's log: junk there counts too.
    let finding = judged(finding, &ctx, stopped);
    let left = match cleanup {
        Ok(left) => left,
        Err(_) => {
            stopped = true;
            vec![format!(
                "{}: the values it changed could not be written back (interrupted)",
                test.id
            )]
        }
    };
    Ok((finding, done, left, stopped))
}

/// Whatever a test concluded, junk on the device's CAN-IDs keeps it from passing
/// ([`crate::junk::judge`]), and an unanswered SDO request from being not applicable
/// ([`crate::junk::judge_unanswered`]); a stopped run is judged no further.
fn judged(finding: Finding, ctx: &Ctx<'_, '_>, stopped: bool) -> Finding {
    if stopped {
        finding
    } else {
        let finding = crate::junk::judge(finding, &ctx.junk());
        crate::junk::judge_unanswered(finding, ctx.unanswered())
    }
}

fn telegrams(log: &[Logged], start: Instant, decoder: &mut Decoder) -> Vec<Telegram> {
    log.iter()
        .map(|logged| {
            let frame = logged.frame;
            Telegram {
                t: logged.link_time.saturating_duration_since(start).as_secs_f64(),
                dir: logged.dir,
                id: id_text(frame.id()),
                data: if frame.is_remote() {
                    String::new()
                } else {
                    frame
                        .data()
                        .iter()
                        .map(|b| format!("{b:02X}"))
                        .collect::<Vec<_>>()
                        .join(" ")
                },
                remote: frame.is_remote(),
                meaning: decoder.decode_at(logged.link_time, &frame).to_string(),
                at: logged.link_time,
                frame,
            }
        })
        .collect()
}

/// `0x605`, or eight digits for an extended CAN-ID.
pub fn id_text(id: canopener_can::CanId) -> String {
    if id.is_extended() {
        format!("0x{:08X}", id.as_raw())
    } else {
        format!("0x{:03X}", id.as_raw())
    }
}

impl FinishedRun {
    /// Whether every applicable test passed.
    pub fn passed(&self) -> bool {
        !self.silent && self.report.summary.all_passed() && !self.report.interrupted
    }
}

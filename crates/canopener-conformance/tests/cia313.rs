//! The CiA 313 performance suite against simulated devices on virtual time: on a 1 Mbit/s
//! bit-accurate bus every measured response time and period matches what the frames' exact lengths
//! and the device's turnaround predict, criteria decide verdicts and say so, and the default run
//! stays fast in wall time.

#[path = "shared/support.rs"]
mod support;

use std::time::Duration;

use canopener_can::bits::INTERMISSION_BITS;
use canopener_can::{Bitrate, CanFrame};
use canopener_conformance::cia313::cycle;
use canopener_conformance::model::{Direction, Report, Telegram, TestReport, Verdict};
use canopener_conformance::performance::{Criteria, DEFAULT_REPETITIONS, Performance};
use canopener_device::faults::{DEFAULT_SDO_DELAY, Fault};
use canopener_sim::simulation::Simulation;

/// A CiA 401 device: TPDO1 maps 6000h:01, RPDO1 6200h:01.
const CIA401: &str = "CANopenNode__CANopenDemo__demo__demoDevice.eds";
/// A device whose TPDO1 allows RTR.
const RTR_DEVICE: &str = "ros-industrial__ros_canopen__ipa_canopen_test__config__PRL120.eds";

fn bit_accurate(performance: Performance, sdo_timeout: Duration) -> support::Setup {
    support::Setup {
        simulation: Simulation::bit_accurate(Bitrate::M1),
        sdo_timeout,
        performance,
    }
}

fn test<'r>(report: &'r Report, id: &str) -> &'r TestReport {
    report
        .tests
        .iter()
        .find(|t| t.id == id)
        .unwrap_or_else(|| panic!("{id} did not run"))
}

/// The time from handing `request` to the bus to receiving `answer` on the 1 Mbit/s bus, from the
/// frames' exact durations (SOF through the 3 intermission bits, ISO 11898-1) and the device's
/// `turnaround`:
///
/// - the request starts when handed over, or when the bus is free again: `busy` after that (the
///   previous frame's intermission, when the tester sends the instant the previous answer arrived);
/// - the device has it at the end of its EOF (its duration less the intermission) and answers
///   `turnaround` later, but not before the request's intermission is over;
/// - the tester has the answer at the end of its EOF.
fn analytic(busy: Duration, request: &CanFrame, answer: &CanFrame, turnaround: Duration) -> f64 {
    let bus = Bitrate::M1;
    let intermission = bus.bits_duration(u64::from(INTERMISSION_BITS));
    let wire = busy + bus.frame_duration(request) - intermission
        + turnaround.max(intermission)
        + bus.frame_duration(answer)
        - intermission;
    wire.as_secs_f64() * 1000.0
}

/// The analytic time of every exchange of `test` (a frame it sent on `id`, then the first it received
/// on `answer_id`), the last `count` of them before the runner's clean-up (its NMT command, then the
/// write-back): the measured ones, after any set-up exchanges on the same CAN-IDs.
fn analytic_times(
    test: &TestReport,
    id: u16,
    answer_id: u16,
    turnaround: Duration,
    count: usize,
) -> Vec<f64> {
    let intermission = Bitrate::M1.bits_duration(u64::from(INTERMISSION_BITS));
    let raw = |t: &Telegram| t.frame.id().as_raw();
    let mut times = Vec::new();
    let mut request: Option<(&Telegram, Duration)> = None;
    let mut last_received: Option<&Telegram> = None;
    let cleanup = test
        .telegrams
        .iter()
        .rposition(|t| t.dir == Direction::Tx && raw(t) == 0)
        .unwrap_or(test.telegrams.len());
    for telegram in &test.telegrams[..cleanup] {
        match telegram.dir {
            Direction::Tx if raw(telegram) == u32::from(id) => {
                let busy = last_received.map_or(Duration::ZERO, |rx| {
                    (rx.at + intermission).saturating_duration_since(telegram.at)
                });
                request = Some((telegram, busy));
            }
            Direction::Rx => {
                if raw(telegram) == u32::from(answer_id)
                    && let Some((sent, busy)) = request.take()
                {
                    times.push(analytic(busy, &sent.frame, &telegram.frame, turnaround));
                }
                last_received = Some(telegram);
            }
            Direction::Tx => {}
        }
    }
    assert!(times.len() >= count, "{}: {} exchanges", test.id, times.len());
    times.split_off(times.len() - count)
}

/// Every sample of `test`'s measurement `name` within 1 % of the `expected` ms at its position;
/// returns the means of samples and expectations.
fn within_one_percent(test: &TestReport, name: &str, expected: &[f64]) -> (f64, f64) {
    let measurement = &test.measurements[name];
    assert_eq!(measurement.unit, "ms");
    assert_eq!(measurement.samples.len(), expected.len(), "{}: {name}", test.id);
    for (i, (sample, expected)) in measurement.samples.iter().zip(expected).enumerate() {
        assert!(
            (sample - expected).abs() <= expected * 0.01,
            "{} {name} #{}: {sample} ms against {expected} ms",
            test.id,
            i + 1
        );
    }
    let stats = measurement.statistics.expect("statistics");
    assert!(stats.min <= stats.p50 && stats.p99 <= stats.max);
    (stats.mean, expected.iter().sum::<f64>() / expected.len() as f64)
}

#[test]
fn on_a_bit_accurate_1_mbit_bus_response_times_and_periods_match_the_frame_times() {
    let setup = bit_accurate(Performance::default(), Duration::from_millis(500));
    let report = support::run_setup(&setup, CIA401, &[], &["cia313"]);
    for t in &report.tests {
        assert!(
            matches!(t.verdict, Verdict::Pass | Verdict::NotApplicable),
            "{} {}: {}\n{}",
            t.id,
            t.verdict.as_str(),
            t.reason,
            t.analysis
        );
    }
    let node = u16::from(support::NODE);
    let mut figures = Vec::new();
    for (id, name) in [
        ("cia313.perf.1", "sdo_read_response"),
        ("cia313.perf.2", "sdo_write_response"),
    ] {
        let t = test(&report, id);
        let expected = analytic_times(t, 0x600 + node, 0x580 + node, Duration::ZERO, DEFAULT_REPETITIONS);
        let (mean, analytic) = within_one_percent(t, name, &expected);
        figures.push(format!(
            "{id} {name}: mean {mean:.6} ms, analytic {analytic:.6} ms"
        ));
    }
    let sync = test(&report, "cia313.perf.4");
    let expected = analytic_times(sync, 0x80, 0x180 + node, Duration::ZERO, cycle::PERIODS);
    let (mean, analytic) = within_one_percent(sync, "sync_to_tpdo", &expected);
    figures.push(format!(
        "cia313.perf.4 sync_to_tpdo: mean {mean:.6} ms, analytic {analytic:.6} ms"
    ));
    let sync_period = cycle::SYNC_PERIOD.as_secs_f64() * 1000.0;
    let (mean, _) = within_one_percent(sync, "tpdo_period", &[sync_period; cycle::PERIODS - 1]);
    figures.push(format!(
        "cia313.perf.4 tpdo_period: mean {mean:.6} ms, SYNC period {sync_period} ms"
    ));
    let timer = f64::from(cycle::EVENT_TIMER_MS);
    let timed = test(&report, "cia313.perf.3");
    let (mean, _) = within_one_percent(timed, "event_timer_period", &[timer; cycle::PERIODS]);
    figures.push(format!(
        "cia313.perf.3 event_timer_period: mean {mean:.6} ms, event timer {timer} ms"
    ));
    let heartbeat = f64::from(cycle::HEARTBEAT_MS);
    let beats = test(&report, "cia313.perf.8");
    let (mean, _) = within_one_percent(beats, "heartbeat_period", &[heartbeat; cycle::PERIODS]);
    figures.push(format!(
        "cia313.perf.8 heartbeat_period: mean {mean:.6} ms, 1017h {heartbeat} ms"
    ));
    // The RTR response on a device that allows it.
    let report = support::run_setup(&setup, RTR_DEVICE, &[], &["cia313.perf.5"]);
    let rtr = test(&report, "cia313.perf.5");
    assert_eq!(rtr.verdict, Verdict::Pass, "{}", rtr.reason);
    let expected = analytic_times(
        rtr,
        0x180 + node,
        0x180 + node,
        Duration::ZERO,
        DEFAULT_REPETITIONS,
    );
    let (mean, analytic) = within_one_percent(rtr, "rtr_response", &expected);
    figures.push(format!(
        "cia313.perf.5 rtr_response: mean {mean:.6} ms, analytic {analytic:.6} ms"
    ));
    // The figures the closing note quotes.
    eprintln!("{}", figures.join("\n"));
}

#[test]
fn a_device_turnaround_adds_to_the_frame_times() {
    // The `sdo-slow` fault answers every SDO request DEFAULT_SDO_DELAY after it arrives: a
    // turnaround the measurement must show on top of the two frames.
    let performance = Performance {
        repetitions: 5,
        ..Performance::default()
    };
    let setup = bit_accurate(performance, DEFAULT_SDO_DELAY * 2);
    let report = support::run_setup(&setup, CIA401, &[Fault::SdoSlow], &["cia313.perf.1"]);
    let t = test(&report, "cia313.perf.1");
    let node = u16::from(support::NODE);
    let expected = analytic_times(t, 0x600 + node, 0x580 + node, DEFAULT_SDO_DELAY, 5);
    let (mean, analytic) = within_one_percent(t, "sdo_read_response", &expected);
    eprintln!("cia313.perf.1 with sdo-slow: mean {mean:.6} ms, analytic {analytic:.6} ms");
}

#[test]
fn a_criterion_decides_and_is_named_and_without_one_the_time_is_only_measured() {
    let judged = |text: &str| {
        let performance = Performance {
            criteria: Criteria::parse(text, "limits.toml").expect("criteria"),
            repetitions: 20,
        };
        let setup = bit_accurate(performance, Duration::from_millis(500));
        support::run_setup(&setup, CIA401, &[], &["cia313.perf.1"]).tests[0].clone()
    };
    let unjudged = judged("");
    assert_eq!(unjudged.verdict, Verdict::Pass);
    assert!(
        unjudged.reason.contains("measured, no criterion"),
        "{}",
        unjudged.reason
    );
    assert!(unjudged.measurements["sdo_read_response"].limits.is_none());
    assert!(
        unjudged.measured_no_criterion(),
        "a pass no criterion judged is marked so"
    );
    // Two 8-byte frames at 1 Mbit/s take about 0.22 ms: 1 ms passes, 0.1 ms fails.
    let loose = judged("[sdo]\nread_max_ms = 1\n");
    assert_eq!(loose.verdict, Verdict::Pass, "{}", loose.reason);
    assert!(!loose.no_criterion, "a criterion decided this pass");
    assert!(
        loose.reason.contains("sdo.read_max_ms from limits.toml"),
        "{}",
        loose.reason
    );
    let tight = judged("[sdo]\nread_max_ms = 0.1\n");
    assert_eq!(tight.verdict, Verdict::Fail, "{}", tight.reason);
    assert!(
        tight.reason.contains("20 of 20 outside ≤ 0.100 ms"),
        "{}",
        tight.reason
    );
    assert!(
        tight
            .analysis
            .contains("criterion sdo.read_max_ms from limits.toml"),
        "{}",
        tight.analysis
    );
    let limits = tight.measurements["sdo_read_response"]
        .limits
        .clone()
        .expect("limits");
    assert_eq!((limits.low, limits.high), (None, Some(0.1)));
    // Virtual stamps (1 ns) are fine enough for a 0.1 ms limit: no warning.
    assert!(!tight.reason.contains("WARNING"), "{}", tight.reason);
}

#[test]
fn heartbeat_faults_fail_the_deviation_test_with_the_numbers() {
    for (fault, outside) in [
        (Fault::HeartbeatTooFast, "1.000 ms"),
        (Fault::HeartbeatJitter, "140.000 ms"),
    ] {
        let report = support::run(CIA401, &[fault], &["cia313.perf.8"]);
        let t = &report.tests[0];
        assert_eq!(t.verdict, Verdict::Fail, "{}: {}", fault.name(), t.reason);
        assert!(t.reason.contains("outside 95.000–105.000 ms"), "{}", t.reason);
        assert!(
            t.reason
                .contains("heartbeat.deviation_percent (documented default) ±5 %"),
            "{}",
            t.reason
        );
        assert!(t.analysis.contains(outside), "{}: {}", fault.name(), t.analysis);
        let limits = t.measurements["heartbeat_period"].limits.clone().expect("limits");
        assert_eq!((limits.low, limits.high), (Some(95.0), Some(105.0)));
    }
}

/// The whole catalogue (all four suites and the EDS check) against one simulated device: cia313
/// takes 12.5 virtual seconds of the run's 26.6 (10 of them the heartbeat's 100 periods). Virtual
/// time costs no wall time: `cargo test -p canopener-conformance --test cia313` reports the wall time
/// of this test binary (under a second in a debug build), the default 1000 repetitions included.
#[test]
fn the_performance_suite_stays_within_fifteen_virtual_seconds_at_default_repetitions() {
    let report = support::run(RTR_DEVICE, &[], &[]);
    let performance: Vec<&TestReport> = report.tests.iter().filter(|t| t.suite == "cia313").collect();
    assert_eq!(performance.len(), 8);
    let virtual_s: f64 = performance.iter().map(|t| t.duration_s).sum();
    assert!(virtual_s < 15.0, "cia313 took {virtual_s} virtual seconds");
    let samples: usize = performance
        .iter()
        .flat_map(|t| t.measurements.values())
        .map(|m| m.samples.len())
        .sum();
    // 1000 each: SDO read, SDO write, RTR, six LSS services; 10 boot-ups; 100 + 100 + 99 + 100 periods.
    assert_eq!(samples, 9 * DEFAULT_REPETITIONS + 10 + 399);
    eprintln!(
        "cia313 on a simulated PRL120: {virtual_s:.1} of {:.1} virtual seconds, {samples} samples",
        report.duration_s
    );
}

#[test]
fn the_summaries_count_a_measurement_without_criterion_apart_from_the_passes() {
    let setup = bit_accurate(
        Performance {
            repetitions: 5,
            ..Performance::default()
        },
        Duration::from_millis(500),
    );
    // perf.1 without a criterion, perf.8 against the documented heartbeat default.
    let report = support::run_setup(&setup, CIA401, &[], &["cia313.perf.1", "cia313.perf.8"]);
    assert_eq!(report.summary.pass, 2);
    assert_eq!(report.summary.measured_no_criterion, 1);
    assert_eq!(report.summary.conformance_passes(), 1);
    let human = canopener_conformance::render::human::render(&report);
    assert!(
        human.contains("Performance Test (CiA 313) (2): 1 passed, 1 measured, no criterion"),
        "{human}"
    );
    assert!(
        human.contains("2 tests: 1 passed, 1 measured, no criterion, 0 failed"),
        "{human}"
    );
    assert!(human.contains("not conformance passes"), "{human}");
    let junit = canopener_conformance::render::junit::render(&report);
    let doc = roxmltree::Document::parse(&junit).expect("JUnit XML");
    let suite = doc.root_element();
    assert_eq!(suite.attribute("skipped"), Some("1"));
    let skipped: Vec<_> = doc
        .descendants()
        .filter(|n| n.has_tag_name("skipped"))
        .filter_map(|n| n.attribute("message"))
        .collect();
    assert_eq!(skipped.len(), 1);
    assert!(
        skipped[0].starts_with("measured, no criterion: "),
        "{}",
        skipped[0]
    );
    let property = |name: &str| {
        doc.descendants()
            .find(|n| n.has_tag_name("property") && n.attribute("name") == Some(name))
            .and_then(|n| n.attribute("value"))
    };
    assert_eq!(property("passed"), Some("1"));
    assert_eq!(property("measured_no_criterion"), Some("1"));
}

//! Model-based tests end to end: the shipped models against simulated devices on virtual time,
//! clean (never a failure) and with the faults each model is meant to catch (always a failure).

use std::time::Duration;

use canopener_can::Instant;
use canopener_device::faults::Fault;
use canopener_eds::model::Eds;
use canopener_mbt::compile::{Options, Source, compile};
use canopener_mbt::executor::{Outcome, RunConfig, Verdict};
use canopener_mbt::model::Model;
use canopener_mbt::shipped;
use canopener_runtime::mbt_run::{run, shrink};
use canopener_sim::simulation::Simulation;
use canopener_testkit::corpus;

/// CANopenNode's example I/O device: heartbeat every 1000 ms (1017h), the CiA 301 objects.
const IO: &str = "CANopenNode__CANopenNode__example__IO.eds";
const NODE: u8 = 5;

fn eds() -> Eds {
    canopener_eds::load(&std::fs::read(corpus::eds(IO)).expect("EDS file")).eds
}

fn model(names: &[&str], eds: &Eds) -> Model {
    model_for(names, eds, NODE)
}

/// The models for the device with `node_id` (FFh: LSS non-configured).
fn model_for(names: &[&str], eds: &Eds, node_id: u8) -> Model {
    let sources: Vec<Source> = names
        .iter()
        .map(|n| Source {
            origin: (*n).into(),
            text: shipped::text(n).expect("shipped model").into(),
        })
        .collect();
    let options = Options {
        node_id,
        eds: Some(eds),
        set: Vec::new(),
    };
    let (model, report) = compile(&sources, &options, &|n| shipped::text(n).map(str::to_owned));
    model.unwrap_or_else(|| panic!("{report:#?}"))
}

fn test(model: &Model, eds: &Eds, faults: &[Fault], seed: u64, steps: usize) -> Outcome {
    test_node(model, eds, NODE, faults, seed, steps)
}

fn test_node(model: &Model, eds: &Eds, node_id: u8, faults: &[Fault], seed: u64, steps: usize) -> Outcome {
    let mut bus = Simulation::ideal()
        .device(eds, node_id)
        .faults(faults.iter().copied())
        .start()
        .expect("simulation");
    // The device's power-on boot-up is history when the tester starts with its own reset.
    bus.run_until(Instant::from_millis(100)).expect("virtual time");
    let config = RunConfig {
        seed,
        steps,
        ..RunConfig::default()
    };
    run(&mut bus, model, config, Some(Duration::from_secs(3600))).expect("link")
}

fn show(o: &Outcome) -> String {
    let tail: Vec<String> = o
        .trace
        .iter()
        .rev()
        .take(8)
        .rev()
        .map(|s| format!("{:.3} {:?} {}", s.t, s.dir, s.label))
        .collect();
    format!(
        "{:?}: {}\n  {}\n  allowed: {:?}",
        o.verdict,
        o.reason,
        tail.join("\n  "),
        o.allowed
    )
}

#[test]
fn clean_devices_pass_every_shipped_model() {
    let eds = eds();
    for names in [
        &["nmt"][..],
        &["sdo"][..],
        &["sync"][..],
        &["lss"][..],
        &["emcy"][..],
        &["guarding"][..],
        &["heartbeat"][..],
    ] {
        let model = model(names, &eds);
        for seed in 1..=3 {
            let outcome = test(&model, &eds, &[], seed, 150);
            assert_eq!(
                outcome.verdict,
                Verdict::Pass,
                "{names:?} seed {seed}: {}",
                show(&outcome)
            );
            assert_eq!(outcome.steps, 150);
            assert!(outcome.coverage.transitions[0] > 5, "{:?}", outcome.coverage);
            eprintln!(
                "{names:?} seed {seed}: {:?} {:?}",
                outcome.coverage.transitions, outcome.coverage.locations
            );
            if names == ["sdo"] {
                // The segmented transfers ran: 1008h's upload in segments, 1005h's download.
                for label in ["!SDO_TX !0x41 !0x1008", "!SDO_TX !0x60 !0x1005", "!SDO_TX !0x20"] {
                    assert!(
                        outcome.trace.iter().any(|s| s.label.starts_with(label)),
                        "{label}: {}",
                        show(&outcome)
                    );
                }
            }
            if names == ["guarding"] {
                // Answers with the toggle set came: the toggle alternated.
                assert!(
                    outcome
                        .trace
                        .iter()
                        .any(|s| ["!EC !0x84", "!EC !0x85", "!EC !0xFF"].contains(&s.label.as_str())),
                    "{}",
                    show(&outcome)
                );
            }
            if names == ["heartbeat"] {
                // The event and the reaction (no 1029h: Pre-operational) were seen.
                assert!(
                    outcome.trace.iter().any(|s| s.label.starts_with("!EMCY !0x8130")),
                    "{}",
                    show(&outcome)
                );
            }
            if names == ["sync"] {
                let count = |prefix: &str| {
                    outcome
                        .trace
                        .iter()
                        .filter(|s| s.label.starts_with(prefix))
                        .count()
                };
                // TPDOs after the first SYNC the tester sent (before it, TPDO1 ran with the type it
                // starts with).
                let tpdos = outcome
                    .trace
                    .iter()
                    .skip_while(|s| !s.label.starts_with("?SYNC_IN"))
                    .filter(|s| s.label.starts_with("!TPDO"))
                    .count();
                let syncs_in = count("?SYNC_IN");
                // The producer part: the counter ran up to 5 and wrapped to 1.
                assert!(
                    count("!SYNC !0x05") >= 1 && count("!SYNC !0x01") >= 2,
                    "{}",
                    show(&outcome)
                );
                // The consumer part: TPDO1 of type 3 after every third SYNC the tester sent (the
                // run may end between the third SYNC and its TPDO).
                assert!(syncs_in > 9, "{}", show(&outcome));
                assert!(
                    (syncs_in / 3 - 1..=syncs_in / 3).contains(&tpdos),
                    "{syncs_in} SYNCs, {tpdos} TPDOs: {}",
                    show(&outcome)
                );
            }
        }
    }
}

#[test]
fn protocol_faults_are_caught() {
    let eds = eds();
    let cases: &[(&[&str], Fault)] = &[
        (&["nmt"], Fault::NoBootUp),
        (&["nmt"], Fault::BootUpWrongId),
        (&["nmt"], Fault::HeartbeatStateWrong),
        (&["nmt"], Fault::HeartbeatTooFast),
        (&["nmt"], Fault::HeartbeatJitter),
        (&["nmt"], Fault::IgnoresNmtStop),
        (&["nmt"], Fault::NmtBroadcastIgnored),
        (&["nmt"], Fault::GuardingAndHeartbeat),
        (&["sdo"], Fault::SdoSlow),
        (&["sdo"], Fault::SdoExpeditedSizeWrong),
        (&["sdo"], Fault::WrongAbortCode),
        (&["sdo"], Fault::SdoBadCommandSilent),
        (&["sdo"], Fault::SdoToggleIgnored),
        (&["sync"], Fault::SyncCounterMissing),
        (&["lss"], Fault::LssStateNotChanged),
        (&["lss"], Fault::NoLss),
        (&["emcy"], Fault::NoEmcy),
        (&["emcy"], Fault::EmcyNoErrorReset),
        (&["guarding"], Fault::HeartbeatStateWrong),
        (&["guarding"], Fault::IgnoresNmtStop),
        (&["heartbeat"], Fault::NoEmcy),
    ];
    for (names, fault) in cases {
        let model = model(names, &eds);
        let outcome = test(&model, &eds, &[*fault], 1, 400);
        assert_eq!(
            outcome.verdict,
            Verdict::Fail,
            "{fault} on {names:?}: {}",
            show(&outcome)
        );
        assert!(
            !outcome.allowed.is_empty() || outcome.reason.contains("unexpected"),
            "{}",
            show(&outcome)
        );
    }
}

/// LSS fastscan (CiA 305 §6.7) on a non-configured device (node-ID FFh): the clean device is found
/// part by part and selected; with the fault that drops the selecting step the model misses the
/// answer. A configured device is run by `clean_devices_pass_every_shipped_model` (it must keep
/// silent).
#[test]
fn fastscan_finds_a_non_configured_device_and_catches_a_lost_selection() {
    let eds = eds();
    let model = model_for(&["lss"], &eds, 0xFF);
    for seed in 1..=3 {
        let outcome = test_node(&model, &eds, 0xFF, &[], seed, 400);
        assert_eq!(outcome.verdict, Verdict::Pass, "seed {seed}: {}", show(&outcome));
    }
    // Guided by the shipped purpose: the whole address is confirmed and the slave answers the
    // selecting step.
    let purpose = model
        .purposes
        .iter()
        .find(|p| p.name == "fastscan_select")
        .expect("shipped purpose")
        .clone();
    for seed in 1..=3 {
        let mut bus = Simulation::ideal()
            .device(&eds, 0xFF)
            .start()
            .expect("simulation");
        let config = RunConfig {
            seed,
            steps: 2000,
            purpose: Some(purpose.clone()),
            ..RunConfig::default()
        };
        let outcome = run(&mut bus, &model, config, None).expect("link");
        assert_eq!(outcome.verdict, Verdict::Pass, "seed {seed}: {}", show(&outcome));
        assert_eq!(
            outcome.purpose,
            Some(("fastscan_select".to_owned(), true)),
            "seed {seed}: {}",
            show(&outcome)
        );
    }
    // The fault drops the selecting step (and switch state global to configuration): some guided
    // run fails on the missing answer to the selecting step.
    let mut caught = 0;
    for seed in 1..=5 {
        let mut bus = Simulation::ideal()
            .device(&eds, 0xFF)
            .fault(Fault::LssStateNotChanged)
            .start()
            .expect("simulation");
        let config = RunConfig {
            seed,
            steps: 2000,
            purpose: Some(purpose.clone()),
            ..RunConfig::default()
        };
        let outcome = run(&mut bus, &model, config, None).expect("link");
        assert_eq!(outcome.verdict, Verdict::Fail, "seed {seed}: {}", show(&outcome));
        let last_input = outcome.trace.iter().rev().find(|s| s.label.starts_with('?'));
        if outcome.reason.starts_with("missing output")
            && last_input.is_some_and(|s| {
                s.label.starts_with("?LSS_REQ !0x51") && s.label.ends_with("!0x00 !0x03 !0x00")
            })
        {
            caught += 1;
        }
    }
    assert!(caught > 0, "lss-state-not-changed on the fastscan selection");
}

/// The heartbeat consumer's reaction on a device whose description has no 1029h (CiA 301: it
/// behaves as 1029h:01 = 0): started, then the watched node falls silent, so after EMCY 8130h its
/// heartbeat must report Pre-operational (7Fh).
#[test]
fn heartbeat_event_without_1029h_moves_an_operational_device_to_pre_operational() {
    let file = "CANopenNode__CanOpenSTM32__Elcom e-RIO 8xx CANopen Profile.eds";
    let eds = canopener_eds::load(&std::fs::read(corpus::eds(file)).expect("EDS file")).eds;
    assert!(!eds.objects.contains_key(&0x1029), "the EDS must lack 1029h");
    let model = model(&["heartbeat"], &eds);
    let mut reactions = 0;
    for seed in 1..=3 {
        let outcome = test(&model, &eds, &[], seed, 300);
        assert_eq!(outcome.verdict, Verdict::Pass, "seed {seed}: {}", show(&outcome));
        // Each 8130h on a started device comes with 7Fh: the heartbeat sent on the state change
        // just before it (since the last beat of the tester's), or else the next heartbeat (unless
        // a reset comes first).
        let mut started = false;
        let mut after_event = false;
        let mut beat_since_peer: Option<&str> = None;
        for step in &outcome.trace {
            let label = step.label.as_str();
            if label.starts_with("?NMT !0x01") {
                started = true;
            } else if label.starts_with("?NMT !0x81") {
                (started, after_event) = (false, false);
            } else if label.starts_with("?PEER") {
                beat_since_peer = None;
            } else if label.starts_with("!EMCY !0x8130") && started {
                if beat_since_peer == Some("!EC !0x7F") {
                    reactions += 1;
                    started = false;
                } else {
                    after_event = true;
                }
            } else if label.starts_with("!EC ") {
                beat_since_peer = Some(label);
                if after_event {
                    assert_eq!(label, "!EC !0x7F", "seed {seed}: {}", show(&outcome));
                    reactions += 1;
                    (started, after_event) = (false, false);
                }
            }
        }
    }
    assert!(reactions > 0, "no run saw the event on a started device");
}

#[test]
fn failing_runs_shrink_to_one_minimal_scripts() {
    let eds = eds();
    for (names, fault) in [
        (&["nmt"][..], Fault::IgnoresNmtStop),
        (&["sdo"][..], Fault::WrongAbortCode),
        (&["lss"][..], Fault::LssStateNotChanged),
    ] {
        let model = model(names, &eds);
        let failing = test(&model, &eds, &[fault], 3, 400);
        assert_eq!(failing.verdict, Verdict::Fail, "{}", show(&failing));
        let config = RunConfig {
            seed: 3,
            steps: 400,
            ..RunConfig::default()
        };
        let mut new_bus = || {
            let mut bus = Simulation::ideal()
                .device(&eds, NODE)
                .fault(fault)
                .start()
                .expect("simulation");
            bus.run_until(Instant::from_millis(100))?;
            Ok::<_, canopener_link::link::LinkError>(bus)
        };
        let shrunk = shrink(&mut new_bus, &model, &config, &failing.script(), None)
            .unwrap()
            .expect("still fails");
        assert_eq!(shrunk.outcome.verdict, Verdict::Fail);
        assert!(shrunk.after.len() <= failing.inputs.len());
        assert!(
            !shrunk.after.is_empty(),
            "{fault}: a fault this needs a stimulus for"
        );
        // 1-minimal: leaving out any one input makes the run pass.
        for i in 0..shrunk.after.len() {
            let mut fewer = shrunk.after.clone();
            fewer.remove(i);
            let outcome = run(
                &mut new_bus().unwrap(),
                &model,
                RunConfig {
                    script: Some(fewer),
                    ..config.clone()
                },
                None,
            )
            .unwrap();
            assert_ne!(
                outcome.verdict,
                Verdict::Fail,
                "{fault}: input {i} of {:?} is not needed",
                shrunk.after
            );
        }
        eprintln!(
            "{fault}: {} inputs -> {} ({:?}) in {} runs",
            failing.inputs.len(),
            shrunk.after.len(),
            shrunk.after,
            shrunk.runs
        );
    }
}

#[test]
fn a_purpose_guides_the_run_and_ends_it_when_reached() {
    let eds = eds();
    let model = model(&["nmt"], &eds);
    let purpose = model
        .purposes
        .iter()
        .find(|p| p.name == "stop_and_start")
        .expect("shipped purpose")
        .clone();
    for seed in 1..=5 {
        let mut bus = Simulation::ideal()
            .device(&eds, NODE)
            .start()
            .expect("simulation");
        bus.run_until(Instant::from_millis(100)).expect("virtual time");
        let config = RunConfig {
            seed,
            steps: 400,
            purpose: Some(purpose.clone()),
            ..RunConfig::default()
        };
        let outcome = run(&mut bus, &model, config, None).expect("link");
        assert_eq!(outcome.verdict, Verdict::Pass, "seed {seed}: {}", show(&outcome));
        assert_eq!(outcome.purpose, Some(("stop_and_start".to_owned(), true)));
        // Guided: a stop and a start are all the inputs it takes.
        assert!(outcome.inputs.len() <= 4, "seed {seed}: {:?}", outcome.inputs);
    }
    let mut bus = Simulation::ideal()
        .device(&eds, NODE)
        .fault(Fault::IgnoresNmtStop)
        .start()
        .expect("simulation");
    bus.run_until(Instant::from_millis(100)).expect("virtual time");
    let config = RunConfig {
        steps: 400,
        purpose: Some(purpose),
        ..RunConfig::default()
    };
    let outcome = run(&mut bus, &model, config, None).expect("link");
    assert_eq!(outcome.verdict, Verdict::Fail, "{}", show(&outcome));
    assert_eq!(outcome.purpose, Some(("stop_and_start".to_owned(), false)));
}

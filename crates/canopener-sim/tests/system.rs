//! The system monitor's diagnoses end to end on virtual time: each fixture system simulated from its
//! DCFs (`crates/canopener-network/test_data`), one simulated bus per network, faults applied to the
//! buses as the wiring says, and the monitor listening where a master would. For every single cable
//! cut, dead device and supply domain off, the true cause must be among the candidates of an
//! explanation of the right kind, with exactly one fault diagnosed; repairs must bring `recovered`
//! events and an empty diagnosis; two cuts in different branches must give two faults. The time from
//! a fault to its diagnosis is measured against 3 heartbeat periods plus the silence threshold.

use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;
use std::time::Duration;

use canopener_bus_engine::virtual_bus::Timing;
use canopener_can::Instant;
use canopener_link::link::{Flow, LinkError};
use canopener_link::system_watch::SystemWatch;
use canopener_network::localise::Kind;
use canopener_network::monitor::{Event, MonitorConfig, NamedExplanation, SystemMonitor};
use canopener_sim::system::files::SystemFiles;
use canopener_sim::system::sim::SimulatedSystem;
use canopener_testkit::corpus::workspace_root;

/// The fixture DCFs' producer heartbeat time (1017h).
const PERIOD: Duration = Duration::from_millis(100);
/// The bound of the issue: 3 heartbeat periods plus the silence threshold (1.5 periods).
const BOUND: Duration = Duration::from_millis(3 * 100 + 150);

fn fixture(name: &str) -> PathBuf {
    workspace_root()
        .join("crates/canopener-network/test_data")
        .join(name)
}

/// A diagnosis as seen: its time, silent devices and explanations.
type Seen = (f64, Vec<String>, Vec<NamedExplanation>);

struct Run {
    sim: SimulatedSystem,
    watch: SystemWatch,
    now: Instant,
    at: Option<usize>,
}

impl Run {
    /// The system of `name` running for 1 s without fault: every device heard, nothing diagnosed.
    fn new(name: &str) -> Run {
        let files = SystemFiles::read(&fixture(name)).expect("fixture");
        let topology = files.topology().clone();
        // Where `canopener net monitor` sits without --at: the master of the first network.
        let at = topology
            .network_numbers()
            .first()
            .and_then(|&net| topology.default_monitor(net));
        let sim = SimulatedSystem::new(&files, at, Timing::Ideal).expect("simulated system");
        let config = MonitorConfig {
            at,
            networks: topology.network_numbers().into_iter().collect(),
            producer_times: files.producer_times(),
            fallback: None,
        };
        assert!(config.producer_times.values().all(|p| *p == PERIOD), "{config:?}");
        let watch = SystemWatch::new(SystemMonitor::new(&topology, &config));
        let mut run = Run {
            sim,
            watch,
            now: Instant::ZERO,
            at,
        };
        let events = run.advance(Duration::from_secs(1));
        assert!(
            !events.iter().any(|e| matches!(e, Event::Diagnosis { .. })),
            "{name} without faults: {events:?}"
        );
        assert!(run.watch.monitor().devices().iter().all(|d| !d.is_silent()));
        run
    }

    fn advance(&mut self, by: Duration) -> Vec<Event> {
        let mut events = Vec::new();
        let mut links = self.sim.links();
        self.now = self
            .watch
            .run(&mut links, Some(self.now + by), |_, _, mut slice| {
                events.append(&mut slice);
                Ok::<_, LinkError>(Flow::Continue)
            })
            .expect("watch");
        events
    }

    /// Applies `commands`, runs 1.5 s, and returns per network whose devices fell silent its diagnosis
    /// (explanations, silent devices) and the time from the fault to it.
    fn fault(&mut self, commands: &[&str]) -> BTreeMap<u32, (Vec<NamedExplanation>, Vec<String>, Duration)> {
        for command in commands {
            self.sim.command(command).expect("command");
        }
        let start = self.now;
        let events = self.advance(Duration::from_millis(1500));
        let started = start.saturating_duration_since(Instant::ZERO).as_secs_f64();
        let mut diagnoses: BTreeMap<u32, Vec<Seen>> = BTreeMap::new();
        for event in &events {
            if let Event::Diagnosis {
                time,
                network,
                silent,
                explanations,
            } = event
                && !silent.is_empty()
            {
                diagnoses
                    .entry(*network)
                    .or_default()
                    .push((*time, silent.clone(), explanations.clone()));
            }
        }
        assert!(!diagnoses.is_empty(), "{commands:?}: no diagnosis in {events:?}");
        diagnoses
            .into_iter()
            .map(|(net, list)| {
                // The first diagnosis already names every silent device (the monitor waits for the
                // silence to settle), so it is the only one.
                assert_eq!(list.len(), 1, "{commands:?}: network {net}: {list:?}");
                let (time, silent, explanations) = list.into_iter().next().expect("one");
                (
                    net,
                    (explanations, silent, Duration::from_secs_f64(time - started)),
                )
            })
            .collect()
    }

    /// [`Run::fault`] where one network falls silent.
    fn fault_on_one(&mut self, commands: &[&str]) -> (Vec<NamedExplanation>, Vec<String>) {
        let diagnoses = self.fault(commands);
        assert_eq!(diagnoses.len(), 1, "{diagnoses:?}");
        let (_, (explanations, silent, _)) = diagnoses.into_iter().next().expect("one");
        (explanations, silent)
    }

    /// Repairs everything; every silent device must be `recovered` and the silence cleared.
    fn repair(&mut self, silent: &[String]) {
        self.sim.command("repair-all").expect("repair");
        let events = self.advance(Duration::from_secs(1));
        let recovered: BTreeSet<&str> = events
            .iter()
            .filter_map(|e| match e {
                Event::Recovered { node, .. } => Some(node.as_str()),
                _ => None,
            })
            .collect();
        let expected: BTreeSet<&str> = silent.iter().map(String::as_str).collect();
        assert_eq!(recovered, expected, "{events:?}");
        assert!(
            events
                .iter()
                .any(|e| matches!(e, Event::Diagnosis { silent, .. } if silent.is_empty())),
            "{events:?}"
        );
        assert!(self.watch.monitor().devices().iter().all(|d| !d.is_silent()));
    }
}

/// The number of independent faults a diagnosis gives: its distinct `explains` sets.
fn faults(explanations: &[NamedExplanation]) -> usize {
    explanations
        .iter()
        .map(|e| e.explains.iter().collect::<BTreeSet<_>>())
        .collect::<BTreeSet<_>>()
        .len()
}

fn names(explanations: &[NamedExplanation], kind: Kind) -> BTreeSet<&str> {
    explanations
        .iter()
        .filter(|e| e.kind == kind)
        .flat_map(|e| e.candidates.iter().map(String::as_str))
        .collect()
}

/// Every single fault of a fixture: (command, kind, candidate).
fn single_faults(run: &Run) -> Vec<(String, Kind, String)> {
    let topology = run.sim.topology();
    let mut out = Vec::new();
    for cable in &topology.cables {
        out.push((format!("cut {}", cable.label()), Kind::Cable, cable.label()));
    }
    let monitors: BTreeSet<usize> = run.at.into_iter().collect();
    for (index, vertex) in topology.vertices.iter().enumerate() {
        let active = vertex.kind() == canopener_network::VertexKind::Active;
        if (vertex.is_device() && !monitors.contains(&index)) || active {
            out.push((
                format!("kill {}", vertex.label()),
                Kind::Device,
                vertex.label().to_owned(),
            ));
        }
    }
    for domain in topology.supply_domains() {
        // The monitor's own supply: the monitor is off with it, which it cannot report.
        let feeds_monitor = monitors
            .iter()
            .any(|&m| topology.vertices[m].supply_domains().contains(domain));
        if !feeds_monitor {
            out.push((format!("power-off {domain}"), Kind::Supply, domain.to_owned()));
        }
    }
    out
}

/// Runs every single fault of a fixture and returns the times to diagnosis (one per network that
/// fell silent).
fn every_single_fault(name: &str) -> Vec<Duration> {
    let mut run = Run::new(name);
    let mut times = Vec::new();
    for (i, (command, kind, candidate)) in single_faults(&run).into_iter().enumerate() {
        // Faults strike at every phase of the heartbeats, not just as one is sent.
        run.advance(Duration::from_millis(1 + (i as u64 * 37) % 100));
        let diagnoses = run.fault(&[&command]);
        assert!(
            diagnoses
                .values()
                .any(|(explanations, ..)| names(explanations, kind).contains(candidate.as_str())),
            "{name}: {command}: {candidate} is not a {kind:?} candidate of {diagnoses:?}"
        );
        let mut silent = BTreeSet::new();
        for (net, (explanations, silent_here, took)) in &diagnoses {
            assert_eq!(
                faults(explanations),
                1,
                "{name}: {command}: network {net}: {explanations:?}"
            );
            assert!(
                *took <= BOUND,
                "{name}: {command}: network {net} diagnosed after {took:?}"
            );
            times.push(*took);
            silent.extend(silent_here.iter().cloned());
        }
        run.repair(&silent.into_iter().collect::<Vec<_>>());
    }
    times
}

#[test]
fn a_line_of_daisy_chained_devices() {
    let times = every_single_fault("line.graphml");
    assert_eq!(times.len(), 5 + 5);
}

#[test]
fn a_trunk_with_drop_cables_and_junctions() {
    let times = every_single_fault("trunk.graphml");
    assert_eq!(times.len(), 11 + 6);
}

#[test]
fn a_tree_through_an_active_hub() {
    let times = every_single_fault("hub.graphml");
    // 5 cables, 4 devices and the hub, and the hub's supply F2 (F1 feeds the monitor).
    assert_eq!(times.len(), 5 + 5 + 1);
}

#[test]
fn two_networks_joined_by_a_gateway() {
    let times = every_single_fault("gateway.graphml");
    // 5 cables and 4 devices with one diagnosis each; the gateway's death silences it on both networks.
    assert_eq!(times.len(), 5 + 4 + 2);
}

#[test]
fn two_supply_domains() {
    let times = every_single_fault("supply.graphml");
    assert_eq!(times.len(), 6 + 6 + 2);
}

#[test]
fn a_cut_in_series_gives_the_ambiguity_group_and_its_device_as_alternatives() {
    let mut run = Run::new("trunk.graphml");
    let (explanations, silent) = run.fault_on_one(&["cut T4"]);
    assert_eq!(silent, ["Beacon"]);
    let cables: Vec<&NamedExplanation> = explanations.iter().filter(|e| e.kind == Kind::Cable).collect();
    assert_eq!(cables.len(), 1, "{explanations:?}");
    assert_eq!(cables[0].candidates, ["T4", "T5", "S7"]);
    assert_eq!(names(&explanations, Kind::Device), BTreeSet::from(["Beacon"]));
    assert_eq!(faults(&explanations), 1);
    run.repair(&silent);
}

#[test]
fn two_cuts_in_different_branches_are_two_faults_and_devices_beyond_keep_talking() {
    let mut run = Run::new("trunk.graphml");
    let (explanations, silent) = run.fault_on_one(&["cut T3", "cut S2"]);
    assert_eq!(silent, ["Pump", "Light", "Horn", "Beacon"]);
    assert_eq!(faults(&explanations), 2, "{explanations:?}");
    assert!(
        names(&explanations, Kind::Cable).contains("T3"),
        "{explanations:?}"
    );
    assert!(
        names(&explanations, Kind::Cable).contains("S2"),
        "{explanations:?}"
    );
    run.repair(&silent);
}

#[test]
fn the_exact_events_of_a_cut_and_its_repair() {
    let mut run = Run::new("line.graphml");
    run.sim.command("cut W4").expect("cut");
    let events: Vec<String> = run
        .advance(Duration::from_secs(1))
        .iter()
        .map(Event::to_json)
        .collect();
    insta::assert_snapshot!(events.join("\n"));
    run.sim.command("repair W4").expect("repair");
    let events: Vec<String> = run
        .advance(Duration::from_secs(1))
        .iter()
        .map(Event::to_json)
        .collect();
    insta::assert_snapshot!(events.join("\n"));
}

/// The distribution of the time from fault to diagnosis over every single fault of every fixture,
/// printed for the documentation (`cargo test -p canopener-sim --test system -- --nocapture
/// time_to_diagnosis`).
#[test]
fn time_to_diagnosis() {
    let mut all = Vec::new();
    let mut per_fixture = BTreeMap::new();
    let mut fault_count = 0;
    for name in [
        "line.graphml",
        "trunk.graphml",
        "hub.graphml",
        "gateway.graphml",
        "supply.graphml",
    ] {
        fault_count += single_faults(&Run::new(name)).len();
        let times = every_single_fault(name);
        per_fixture.insert(name, times.len());
        all.extend(times);
    }
    all.sort();
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let percentile = |p: f64| all[((all.len() - 1) as f64 * p).round() as usize];
    println!(
        "time from fault to diagnosis: {fault_count} single faults, {} diagnoses ({per_fixture:?}), heartbeat {} ms, \
         bound {} ms: min {:.0} ms, median {:.0} ms, p90 {:.0} ms, max {:.0} ms",
        all.len(),
        PERIOD.as_millis(),
        BOUND.as_millis(),
        ms(all[0]),
        ms(percentile(0.5)),
        ms(percentile(0.9)),
        ms(all[all.len() - 1])
    );
    assert!(all.iter().all(|t| *t <= BOUND));
}

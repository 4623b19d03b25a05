//! The tour behind `canopener demo --serve`: a small system shipped in the binary (a forestry
//! forwarder: a chassis network and a crane network behind a gateway, on a drawing of the machine)
//! written into the tour's folder, its devices simulated from their DCFs on in-process buses in real
//! time, a cable cut and repaired every few seconds so the first look shows the monitor at work, and
//! the tour's conformance runs (the bundled CiA 401 device, clean and with a fault) in the history.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::channel;
use std::time::Duration;

use canopener_conformance::tour::DEFAULT_FAULT;

use crate::backend::{self, Cancel, Target};
use crate::runs::{Runs, StartRun};
use crate::server::{Extra, ServeConfig, ServeError, SystemConfig};

/// The system's files: name and bytes.
const FILES: [(&str, &[u8]); 12] = [
    (
        "Nodelist.graphml",
        include_bytes!("../assets/demo/Nodelist.graphml"),
    ),
    ("background.svg", include_bytes!("../assets/demo/background.svg")),
    ("plc.svg", include_bytes!("../assets/demo/plc.svg")),
    ("ecu.svg", include_bytes!("../assets/demo/ecu.svg")),
    ("dcf/node1.dcf", include_bytes!("../assets/demo/dcf/node1.dcf")),
    ("dcf/node2.dcf", include_bytes!("../assets/demo/dcf/node2.dcf")),
    ("dcf/node3.dcf", include_bytes!("../assets/demo/dcf/node3.dcf")),
    ("dcf/node10.dcf", include_bytes!("../assets/demo/dcf/node10.dcf")),
    ("dcf/node20.dcf", include_bytes!("../assets/demo/dcf/node20.dcf")),
    ("dcf/node21.dcf", include_bytes!("../assets/demo/dcf/node21.dcf")),
    ("dcf/node22.dcf", include_bytes!("../assets/demo/dcf/node22.dcf")),
    ("dcf/node23.dcf", include_bytes!("../assets/demo/dcf/node23.dcf")),
];

/// The cables the tour cuts in turn, each for [`CUT_FOR`] and then repaired for as long.
pub const CUTS: [&str; 2] = ["C2", "W2"];
/// How long a cut lasts, and the pause after its repair.
pub const CUT_FOR: Duration = Duration::from_secs(6);

/// The in-process bus of each of the tour's networks.
fn buses() -> Vec<(u32, String)> {
    vec![
        (1, "virtual:tour-chassis".to_owned()),
        (2, "virtual:tour-crane".to_owned()),
    ]
}

/// Writes the tour's system into `dir/system/` (replacing an earlier tour's files) and returns the
/// server's configuration (history in `dir`) and what runs beside the server: the simulation, the
/// cable cuts and the conformance runs.
pub fn prepare(
    dir: &Path,
    listen: std::net::SocketAddr,
    token_file: Option<PathBuf>,
) -> Result<(ServeConfig, Extra), ServeError> {
    let system_dir = dir.join("system");
    let data_error = |source| ServeError::Data {
        path: dir.display().to_string(),
        source,
    };
    backend::create_dir(&system_dir.join("dcf")).map_err(data_error)?;
    for (name, bytes) in FILES {
        backend::write_file(&system_dir.join(name), bytes).map_err(data_error)?;
    }
    let file = system_dir.join("Nodelist.graphml");
    let config = ServeConfig {
        listen,
        system: Some(SystemConfig {
            file: file.clone(),
            at: None,
        }),
        buses: buses(),
        data: Some(dir.to_owned()),
        token_file,
        max_upload: crate::upload::DEFAULT_CAP,
    };
    let extra: Extra = Box::new(move |runs, cancel| tour(&file, &runs, &cancel));
    Ok((config, extra))
}

/// Simulates the system, runs the conformance tests once clean and once with a fault, and cuts and
/// repairs cables until `cancel`.
fn tour(file: &Path, runs: &Arc<Runs>, cancel: &Cancel) {
    let Ok(system) = backend::System::read(file) else {
        return;
    };
    let at = system.topology().default_position();
    let (commands, received) = channel::<String>();
    let sim_cancel = cancel.clone();
    let simulation = std::thread::Builder::new()
        .name("tour simulation".to_owned())
        .spawn(move || {
            let _ = backend::simulate_system(&system, at, &buses(), &received, &sim_cancel, |_| {});
        });
    for faults in [Vec::new(), vec![DEFAULT_FAULT]] {
        let start = runs.start(StartRun {
            target: Target::Simulated(faults),
            bus_label: "simulated".to_owned(),
            node: canopener_conformance::tour::NODE,
            eds_name: canopener_conformance::tour::EDS_NAME.to_owned(),
            eds_bytes: canopener_conformance::tour::EDS.to_vec(),
            suites: canopener_conformance::catalogue::SUITES
                .iter()
                .map(|s| (*s).to_owned())
                .collect(),
        });
        if let Ok(id) = start {
            while runs.running().iter().any(|r| r.id == id) && !cancel.is_cancelled() {
                std::thread::sleep(Duration::from_millis(100));
            }
        }
    }
    let mut cables = CUTS.iter().cycle();
    'tour: while !cancel.is_cancelled() {
        let Some(cable) = cables.next() else {
            break;
        };
        for command in [format!("cut {cable}"), format!("repair {cable}")] {
            if commands.send(command).is_err() {
                break 'tour;
            }
            let until = std::time::Instant::now() + CUT_FOR;
            while std::time::Instant::now() < until {
                if cancel.is_cancelled() {
                    break 'tour;
                }
                std::thread::sleep(Duration::from_millis(100));
            }
        }
    }
    drop(commands);
    if let Ok(simulation) = simulation {
        let _ = simulation.join();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_system_reads_without_findings_and_names_the_cables_the_tour_cuts() {
        let loaded = canopener_network::load(FILES[0].1);
        let errors: Vec<String> = loaded.diagnostics.iter().map(|d| d.to_string()).collect();
        assert!(errors.is_empty(), "{errors:?}");
        let topology = &loaded.topology;
        assert_eq!(topology.background.as_deref(), Some("background.svg"));
        assert_eq!(topology.network_numbers().into_iter().collect::<Vec<_>>(), [1, 2]);
        for cable in CUTS {
            assert!(topology.cables.iter().any(|c| c.label() == cable), "{cable}");
        }
        // Every DCF and picture the system names is shipped.
        let shipped: Vec<&str> = FILES.iter().map(|(name, _)| *name).collect();
        for vertex in &topology.vertices {
            for dcf in vertex.attachments.iter().filter_map(|a| a.dcf.as_deref()) {
                assert!(shipped.contains(&format!("dcf/{dcf}").as_str()), "{dcf}");
            }
            if let Some(fig) = &vertex.fig {
                assert!(shipped.contains(&fig.as_str()), "{fig}");
            }
        }
        for (net, spec) in buses() {
            assert!(
                spec.parse::<canopener_transport::BusSpec>().is_ok(),
                "network {net}: {spec}"
            );
        }
    }
}

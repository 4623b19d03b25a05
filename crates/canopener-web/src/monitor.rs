//! The system monitor behind `/`: the system's drawing with its pictures, the monitor thread that
//! watches the buses, and the live state every page follows: the numbered JSON events of `canopener
//! net monitor --format json` ([`EventRing`]) and the monitor's snapshot after the last of them.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, PoisonError};

use canopener_network::draw::{DrawOptions, svg_with};
use canopener_network::monitor::Snapshot;
use serde::Serialize;
use serde_json::{Value, json};

use crate::backend::{self, Cancel, System};
use crate::events::EventRing;

/// How many of the last events `/api/state` carries for the page's event log.
const RECENT: u64 = 50;

/// The extensions of pictures the server shows (the Background and NodeFig files).
const PICTURES: [&str; 7] = ["png", "jpg", "jpeg", "gif", "svg", "bmp", "webp"];

/// A system with its buses, ready to be drawn and watched.
#[derive(Debug)]
pub struct Watched {
    /// The system.
    pub system: System,
    /// Where the monitor listens (a vertex), `None` for the default position.
    pub at: Option<usize>,
    /// The bus of each watched network.
    pub buses: Vec<(u32, String)>,
    /// The file the topology was read from, as given.
    pub file: String,
    /// The Background picture, when the file names one that exists.
    pub background: Option<PathBuf>,
    /// The NodeFig picture of each vertex whose file exists.
    pub figures: BTreeMap<usize, PathBuf>,
    /// The drawing with live badges, pictures at the server's addresses.
    pub svg: String,
    /// The live state.
    pub live: Live,
}

impl Watched {
    /// Prepares `system` for watching `buses` from vertex `at`: finds its pictures (a picture that is
    /// missing, or not an image, leaves the plain drawing) and draws it.
    pub fn new(system: System, at: Option<usize>, buses: Vec<(u32, String)>, file: String) -> Watched {
        let folder = system.folder().to_owned();
        let picture = |name: &str| -> Option<PathBuf> {
            let name = name.trim();
            let extension = name.rsplit_once('.').map(|(_, e)| e.to_ascii_lowercase())?;
            let path = folder.join(name);
            (PICTURES.contains(&extension.as_str()) && path.is_file()).then_some(path)
        };
        let topology = system.topology();
        let background = topology.background.as_deref().and_then(picture);
        let figures: BTreeMap<usize, PathBuf> = topology
            .vertices
            .iter()
            .enumerate()
            .filter_map(|(i, v)| Some((i, picture(v.fig.as_deref()?)?)))
            .collect();
        let options = DrawOptions {
            background: background.as_ref().map(|_| "/system/background".to_owned()),
            figures: figures
                .keys()
                .map(|i| (*i, format!("/system/figure/{i}")))
                .collect(),
            live: true,
        };
        let svg = svg_with(topology, &options);
        Watched {
            system,
            at,
            buses,
            file,
            background,
            figures,
            svg,
            live: Live::default(),
        }
    }

    /// The supply domains of every device, by name (for drawing a supply explanation).
    pub fn supplies(&self) -> BTreeMap<String, Vec<String>> {
        self.system
            .topology()
            .vertices
            .iter()
            .filter(|v| v.is_device())
            .map(|v| {
                (
                    v.label().to_owned(),
                    v.supply_domains().into_iter().map(str::to_owned).collect(),
                )
            })
            .collect()
    }

    /// Runs the monitor on this thread until `cancel` (a bus that fails ends it; the pages say why).
    pub fn watch(self: &Arc<Self>, cancel: &Cancel) {
        self.live.set_status("watching");
        let result = backend::watch_buses(
            &self.system,
            self.at,
            &self.buses,
            cancel,
            |started| self.live.started(started),
            |events, snapshot| {
                let lines = events.iter().map(canopener_network::monitor::Event::to_json);
                self.live.publish(lines, snapshot);
            },
        );
        match result {
            Ok(()) => self.live.set_status("stopped"),
            Err(err) => self.live.set_status(&format!("failed: {err}")),
        }
    }

    /// What `/api/state` returns.
    pub fn state(&self) -> Value {
        let (seq, snapshot, started, status) = self.live.current();
        // The last events up to the snapshot, for the page's event log (not applied again).
        let recent: Vec<Value> = self
            .live
            .events()
            .after(seq.saturating_sub(RECENT))
            .unwrap_or_default()
            .into_iter()
            .filter(|(n, _)| *n <= seq)
            .filter_map(|(_, text)| serde_json::from_str(&text).ok())
            .collect();
        json!({
            "seq": seq,
            "recent": recent,
            "status": status,
            "started_unix_ms": started,
            "file": self.file,
            "networks": self.buses.iter().map(|(net, bus)| json!({
                "network": net,
                "name": self.system.topology().network_name(*net),
                "bus": bus,
            })).collect::<Vec<_>>(),
            "snapshot": snapshot,
            "supplies": self.supplies(),
        })
    }
}

/// The monitor's events and its snapshot after the last of them.
#[derive(Debug, Default)]
pub struct Live {
    events: EventRing,
    inner: Mutex<LiveInner>,
}

#[derive(Debug, Default, Serialize)]
struct LiveInner {
    /// The snapshot and the number of the last event it includes.
    seq: u64,
    snapshot: Option<Snapshot>,
    started: Option<f64>,
    status: String,
}

impl Live {
    /// The events.
    pub fn events(&self) -> &EventRing {
        &self.events
    }

    fn inner(&self) -> std::sync::MutexGuard<'_, LiveInner> {
        self.inner.lock().unwrap_or_else(PoisonError::into_inner)
    }

    fn set_status(&self, status: &str) {
        self.inner().status = status.to_owned();
    }

    fn started(&self, unix_ms: f64) {
        self.inner().started = Some(unix_ms);
    }

    /// Publishes a slice's events with the snapshot after them.
    pub fn publish(&self, events: impl IntoIterator<Item = String>, snapshot: Snapshot) {
        self.events.publish_with(events, |last| {
            let mut inner = self.inner();
            inner.seq = last;
            inner.snapshot = Some(snapshot);
        });
    }

    /// The number of the last event, the snapshot after it, the start and the status.
    pub fn current(&self) -> (u64, Option<Snapshot>, Option<f64>, String) {
        // Set together under the ring's lock: the snapshot includes exactly the events up to `seq`.
        let inner = self.inner();
        (
            inner.seq,
            inner.snapshot.clone(),
            inner.started,
            inner.status.clone(),
        )
    }
}

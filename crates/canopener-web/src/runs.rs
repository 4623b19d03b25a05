//! Conformance runs started from `/test`: each on a thread of its own (a browser that goes away
//! changes nothing), one run per node and bus at a time, progress published as JSON events that every
//! watching page follows (`/api/runs/events`), the report and the verdict counts kept in the
//! [`Store`] at the end. Stopping the server cancels every run as Ctrl-C cancels `canopener test`:
//! the running test's changes are written back, the report says `interrupted`.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;

use canopener_conformance::catalogue::{SUITES, TestDef, catalogue};
use canopener_conformance::render::html;
use canopener_device::faults::Fault;
use serde::Serialize;
use serde_json::json;

use crate::backend::{self, Cancel, RunRequest, Target};
use crate::events::EventRing;
use crate::store::{Ended, NewRun, Store, StoreError};

/// What a page asks to run.
#[derive(Debug, Clone)]
pub struct StartRun {
    /// Where the device is.
    pub target: Target,
    /// The bus as the page and the history name it (`simulated` for a simulated device).
    pub bus_label: String,
    /// The node under test.
    pub node: u8,
    /// The description's name and bytes.
    pub eds_name: String,
    /// Its bytes.
    pub eds_bytes: Vec<u8>,
    /// The suites (of [`SUITES`]).
    pub suites: Vec<String>,
}

/// Why a run did not start; the message is what the page shows.
#[derive(Debug, thiserror::Error)]
pub enum StartError {
    /// Another run is testing this node on this bus.
    #[error(
        "node {node} on {bus} is being tested by run {run} (started {started}); a node takes one run at a time: wait for it to end, or stop it"
    )]
    Busy {
        /// The node.
        node: u8,
        /// The bus.
        bus: String,
        /// The run testing it.
        run: i64,
        /// When that run started.
        started: String,
    },
    /// The request names no or unknown suites, or a bad node.
    #[error("{0}")]
    Invalid(String),
    /// The store failed.
    #[error(transparent)]
    Store(#[from] StoreError),
}

/// One verdict as the pages show it.
#[derive(Debug, Clone, Serialize)]
pub struct VerdictView {
    /// The test id.
    pub test: String,
    /// Its title.
    pub title: String,
    /// `pass`, `fail`, `inconclusive` or `not_applicable`.
    pub verdict: String,
    /// Why.
    pub reason: String,
}

/// A run as the pages show it while it runs and after.
#[derive(Debug, Clone, Serialize)]
pub struct RunView {
    /// Its number.
    pub id: i64,
    /// `running`, `done`, `interrupted`, `silent` or `failed`.
    pub status: String,
    /// Why it failed, or was interrupted.
    pub message: Option<String>,
    /// The node.
    pub node: u8,
    /// The bus.
    pub bus: String,
    /// The description.
    pub eds: String,
    /// When it started.
    pub started: String,
    /// Tests selected.
    pub total: usize,
    /// Tests done.
    pub done: usize,
    /// The test running now.
    pub current: Option<String>,
    /// The verdicts so far.
    pub verdicts: Vec<VerdictView>,
}

struct Active {
    key: (String, u8),
    cancel: Cancel,
}

/// Every run of this server (see the [module docs](self)).
#[derive(Debug)]
pub struct Runs {
    store: Arc<Store>,
    events: EventRing,
    state: Mutex<State>,
}

#[derive(Default)]
struct State {
    active: BTreeMap<i64, Active>,
    views: BTreeMap<i64, RunView>,
    threads: Vec<JoinHandle<()>>,
    stopping: bool,
}

impl std::fmt::Debug for State {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("State")
            .field("active", &self.active.keys())
            .finish_non_exhaustive()
    }
}

/// How many finished runs' live views are kept in memory (older ones come from the store).
const VIEWS_KEPT: usize = 200;

impl Runs {
    /// The runs of a server keeping its history in `store`.
    pub fn new(store: Arc<Store>) -> Runs {
        Runs {
            store,
            events: EventRing::default(),
            state: Mutex::new(State::default()),
        }
    }

    /// The store.
    pub fn store(&self) -> &Store {
        &self.store
    }

    /// The progress events every page follows.
    pub fn events(&self) -> &EventRing {
        &self.events
    }

    fn state(&self) -> std::sync::MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// The tests of `suites`, in catalogue order.
    pub fn tests_of(suites: &[String]) -> Result<Vec<TestDef>, StartError> {
        if suites.is_empty() {
            return Err(StartError::Invalid("choose at least one suite".to_owned()));
        }
        if let Some(unknown) = suites.iter().find(|s| !SUITES.contains(&s.as_str())) {
            return Err(StartError::Invalid(format!(
                "no suite {unknown:?}; the suites are {}",
                SUITES.join(", ")
            )));
        }
        Ok(catalogue()
            .into_iter()
            .filter(|t| suites.iter().any(|s| s == t.suite))
            .collect())
    }

    /// Starts a run on a thread of its own; returns its number.
    pub fn start(self: &Arc<Self>, request: StartRun) -> Result<i64, StartError> {
        if !(1..=127).contains(&request.node) {
            return Err(StartError::Invalid(format!(
                "node {} is not a node-ID (1 to 127)",
                request.node
            )));
        }
        let tests = Runs::tests_of(&request.suites)?;
        let extension = request.eds_name.rsplit_once('.').map(|(_, e)| e.to_owned());
        let description = canopener_description::Description::load(extension.as_deref(), &request.eds_bytes)
            .map_err(|e| StartError::Invalid(format!("{}: {e}", request.eds_name)))?;
        let is_eds = extension
            .as_deref()
            .is_some_and(|e| e.eq_ignore_ascii_case("eds") || e.eq_ignore_ascii_case("dcf"));
        let eds_errors = is_eds.then(|| {
            canopener_conformance::cia301::eds::errors(
                &canopener_eds::load(&request.eds_bytes),
                Some(&request.eds_name),
            )
        });
        let eds = description.eds;
        let info = |key| eds.device_info.get(key).map(str::trim).filter(|v| !v.is_empty());
        let device = match (info("ProductName"), info("VendorName")) {
            (Some(product), Some(vendor)) => format!("{product} ({vendor})"),
            (Some(product), None) => product.to_owned(),
            _ => request.eds_name.clone(),
        };
        let fault = match &request.target {
            Target::Simulated(faults) => {
                Some(faults.iter().map(|f| f.name()).collect::<Vec<_>>().join(",")).filter(|f| !f.is_empty())
            }
            Target::Bus(_) => None,
        };
        let key = (request.bus_label.clone(), request.node);
        let started = backend::now_rfc3339();
        let mut state = self.state();
        if state.stopping {
            return Err(StartError::Invalid("the server is stopping".to_owned()));
        }
        if let Some((run, _)) = state.active.iter().find(|(_, a)| a.key == key) {
            let started = state
                .views
                .get(run)
                .map(|v| v.started.clone())
                .unwrap_or_default();
            return Err(StartError::Busy {
                node: request.node,
                bus: request.bus_label,
                run: *run,
                started,
            });
        }
        let id = self.store.begin(&NewRun {
            started: &started,
            node: request.node,
            bus: &request.bus_label,
            eds: &request.eds_name,
            device: &device,
            fault: fault.as_deref(),
            suites: &request.suites.join(","),
        })?;
        let cancel = Cancel::new();
        state.active.insert(
            id,
            Active {
                key,
                cancel: cancel.clone(),
            },
        );
        let view = RunView {
            id,
            status: "running".to_owned(),
            message: None,
            node: request.node,
            bus: request.bus_label.clone(),
            eds: request.eds_name.clone(),
            started,
            total: tests.len(),
            done: 0,
            current: None,
            verdicts: Vec::new(),
        };
        self.events.publish([json!({
            "event": "started", "run": id, "node": view.node, "bus": view.bus, "eds": view.eds,
            "started": view.started, "total": view.total, "fault": fault,
        })
        .to_string()]);
        state.views.insert(id, view);
        while state.views.len() > VIEWS_KEPT {
            state.views.pop_first();
        }
        let runs = Arc::clone(self);
        let thread_device = device.clone();
        let handle = std::thread::Builder::new()
            .name(format!("run {id}"))
            .spawn(move || {
                let run = RunRequest {
                    eds: &eds,
                    eds_name: request.eds_name.clone(),
                    eds_errors,
                    node: request.node,
                    tests: &tests,
                    cancel,
                };
                let outcome = backend::run_tests(&request.target, &run, |progress| {
                    runs.progress(
                        id,
                        progress.done,
                        progress.current.map(|t| t.id),
                        progress.finished,
                    )
                });
                runs.finish(id, &thread_device, outcome);
            });
        match handle {
            Ok(handle) => state.threads.push(handle),
            Err(err) => {
                state.active.remove(&id);
                drop(state);
                self.finish(
                    id,
                    &device,
                    Err(backend::BackendError::Open {
                        spec: "thread".to_owned(),
                        reason: err.to_string(),
                    }),
                );
            }
        }
        Ok(id)
    }

    fn progress(
        &self,
        id: i64,
        done: usize,
        current: Option<&str>,
        finished: Option<&canopener_conformance::model::TestReport>,
    ) {
        let mut state = self.state();
        let Some(view) = state.views.get_mut(&id) else {
            return;
        };
        view.done = done;
        view.current = current.map(str::to_owned);
        let mut event =
            json!({"event": "progress", "run": id, "done": done, "total": view.total, "current": current});
        if let Some(test) = finished {
            let verdict = VerdictView {
                test: test.id.clone(),
                title: test.title.clone(),
                verdict: test.verdict.as_str().to_owned(),
                reason: test.reason.clone(),
            };
            // `event` is the object made above.
            if let Some(members) = event.as_object_mut() {
                members.insert(
                    "verdict".to_owned(),
                    serde_json::to_value(&verdict).unwrap_or_default(),
                );
            }
            view.verdicts.push(verdict);
        }
        self.events.publish([event.to_string()]);
    }

    fn finish(
        &self,
        id: i64,
        device: &str,
        outcome: Result<canopener_conformance::runner::FinishedRun, backend::BackendError>,
    ) {
        let (status, message, report) = match outcome {
            Ok(outcome) if outcome.silent => (
                "silent",
                Some("the device did not answer an SDO read of 1000h: nothing to test (is it on the bus, is the node-ID right?)".to_owned()),
                Some(outcome.report),
            ),
            Ok(outcome) if outcome.report.interrupted => (
                "interrupted",
                Some("stopped before the end (the server was asked to stop, or the run was stopped)".to_owned()),
                Some(outcome.report),
            ),
            Ok(outcome) => ("done", None, Some(outcome.report)),
            Err(err) => ("failed", Some(err.to_string()), None),
        };
        let counts = report.as_ref().map_or([0; 5], |r| {
            let s = r.summary;
            [
                s.pass.saturating_sub(s.measured_no_criterion),
                s.measured_no_criterion,
                s.fail,
                s.inconclusive,
                s.not_applicable,
            ]
        });
        let identity = report.as_ref().and_then(|r| r.device.identity);
        let with_identity = identity.and_then(|i| {
            Some(format!(
                "{device} · vendor {:#010x}, product {:#010x}",
                i.vendor_id?, i.product_code?
            ))
        });
        let revision = identity.and_then(|i| i.revision).map(|r| format!("{r:#010x}"));
        let rendered = report.as_ref().map(|r| (r.to_json(), html::render(r)));
        let stored = self.store.end(
            id,
            &Ended {
                status,
                message: message.as_deref(),
                device: with_identity.as_deref(),
                revision: revision.as_deref(),
                counts,
                report: rendered.as_ref().map(|(j, h)| (j.as_str(), h.as_str())),
            },
        );
        let message = match stored {
            Ok(()) => message,
            Err(err) => Some(format!(
                "{}; the run could not be kept: {err}",
                message.unwrap_or_default()
            )),
        };
        let mut state = self.state();
        state.active.remove(&id);
        if let Some(view) = state.views.get_mut(&id) {
            view.status = status.to_owned();
            view.message = message.clone();
            view.current = None;
        }
        self.events.publish([json!({
            "event": "finished", "run": id, "status": status, "message": message,
            "summary": report.as_ref().map(|r| r.summary),
        })
        .to_string()]);
    }

    /// A run as the pages show it: live while in memory, else rebuilt from the store.
    pub fn view(&self, id: i64) -> Result<Option<RunView>, StoreError> {
        if let Some(view) = self.state().views.get(&id) {
            return Ok(Some(view.clone()));
        }
        let Some(row) = self.store.get(id)? else {
            return Ok(None);
        };
        let report: Option<serde_json::Value> = self
            .store
            .report(id, false)?
            .and_then(|text| serde_json::from_str(&text).ok());
        let verdicts: Vec<VerdictView> = report
            .as_ref()
            .and_then(|r| r["tests"].as_array().cloned())
            .unwrap_or_default()
            .iter()
            .map(|t| VerdictView {
                test: t["id"].as_str().unwrap_or_default().to_owned(),
                title: t["title"].as_str().unwrap_or_default().to_owned(),
                verdict: t["verdict"].as_str().unwrap_or_default().to_owned(),
                reason: t["reason"].as_str().unwrap_or_default().to_owned(),
            })
            .collect();
        Ok(Some(RunView {
            id,
            status: row.status,
            message: row.message,
            node: row.node,
            bus: row.bus,
            eds: row.eds,
            started: row.started,
            total: verdicts.len(),
            done: verdicts.len(),
            current: None,
            verdicts,
        }))
    }

    /// The runs running now.
    pub fn running(&self) -> Vec<RunView> {
        let state = self.state();
        state
            .active
            .keys()
            .filter_map(|id| state.views.get(id).cloned())
            .collect()
    }

    /// Stops run `id`, as Ctrl-C would; false when it is not running.
    pub fn stop(&self, id: i64) -> bool {
        self.state().active.get(&id).map(|a| a.cancel.cancel()).is_some()
    }

    /// Stops every run and waits until each has written back what it changed and been recorded.
    pub fn stop_all(&self) {
        let threads = {
            let mut state = self.state();
            state.stopping = true;
            for active in state.active.values() {
                active.cancel.cancel();
            }
            std::mem::take(&mut state.threads)
        };
        for thread in threads {
            let _ = thread.join();
        }
    }
}

/// The faults a simulated device can be given, by name.
pub fn fault_named(name: &str) -> Option<Fault> {
    Fault::ALL.into_iter().find(|f| f.name() == name)
}

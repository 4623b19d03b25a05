//! The HTTP side: the routes, the server-sent-event streams and the start and orderly stop of the
//! whole server (monitor thread, runs, connections).

use std::convert::Infallible;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::Arc;

use axum::Router;
use axum::body::Body;
use axum::extract::{DefaultBodyLimit, Path, Query, Request, State};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{Html, IntoResponse, Json, Response};
use axum::routing::{get, post};
use futures_util::stream::{self, Stream, StreamExt};
use serde::Deserialize;
use serde_json::json;
use tokio::sync::watch;

use crate::access::{self, Access};
use crate::backend::{Cancel, Target};
use crate::events::EventRing;
use crate::monitor::Watched;
use crate::runs::{Runs, StartError, StartRun};
use crate::store::Store;
use crate::upload::{self, Refusal};
use crate::{assets, check, compare, pages};

/// Everything a handler may need.
#[derive(Debug, Clone)]
pub struct App {
    /// The watched system, if any.
    pub watched: Option<Arc<Watched>>,
    /// The configured buses (offered to runs).
    pub buses: Vec<(u32, String)>,
    /// The runs and the store.
    pub runs: Arc<Runs>,
    /// The upload cap.
    pub cap: usize,
    /// Where the history is kept, in words.
    pub kept: String,
    /// Becomes true when the server stops: streams end.
    pub stopping: watch::Receiver<bool>,
}

/// The routes (see `docs/web.md` for the page contract and the API).
pub fn router(app: App, access: Access) -> Router {
    let cap = app.cap;
    Router::new()
        .route("/", get(monitor_page))
        .route("/monitor", get(monitor_page))
        .route("/check", get(check_page))
        .route("/test", get(test_page))
        .route("/history", get(history_page))
        .route("/runs/{id}", get(run_page))
        .route("/runs/{id}/report", get(run_report))
        .route("/runs/{id}/report.json", get(run_report_json))
        .route("/compare", get(compare_page))
        .route("/assets/{name}", get(asset))
        .route("/system/background", get(background))
        .route("/system/figure/{vertex}", get(figure))
        .route("/api/state", get(api_state))
        .route("/api/events", get(api_events))
        .route("/api/check", post(api_check))
        .route("/api/fix", post(api_fix))
        .route("/api/eds", post(api_eds))
        .route("/api/runs", get(api_runs).post(api_start))
        .route("/api/runs/events", get(api_run_events))
        .route("/api/runs/{id}", get(api_run))
        .route("/api/runs/{id}/stop", post(api_stop))
        // The uploads read their body themselves, against the cap, to say how large is too large.
        .layer(DefaultBodyLimit::max(cap.saturating_add(1)))
        .layer(axum::middleware::from_fn(headers))
        .layer(axum::middleware::from_fn_with_state(access, access::check))
        .with_state(app)
}

/// Security headers on every answer: no framing by other sites, no sniffing, scripts only from here.
async fn headers(request: Request, next: axum::middleware::Next) -> Response {
    let mut response = next.run(request).await;
    let h = response.headers_mut();
    h.insert(
        header::CONTENT_SECURITY_POLICY,
        HeaderValue::from_static(
            "default-src 'self'; img-src 'self' data:; style-src 'self' 'unsafe-inline'; frame-ancestors 'self'",
        ),
    );
    h.insert(
        header::X_CONTENT_TYPE_OPTIONS,
        HeaderValue::from_static("nosniff"),
    );
    h.insert(header::REFERRER_POLICY, HeaderValue::from_static("no-referrer"));
    response
}

fn error(status: StatusCode, message: impl Into<String>) -> Response {
    (status, Json(json!({ "error": message.into() }))).into_response()
}

fn page_error(status: StatusCode, title: &str, message: &str) -> Response {
    (status, Html(pages::problem(title, message))).into_response()
}

async fn monitor_page(State(app): State<App>) -> Html<String> {
    Html(pages::monitor(app.watched.as_deref()))
}

async fn check_page(State(app): State<App>) -> Html<String> {
    Html(pages::check(app.cap))
}

async fn test_page(State(app): State<App>) -> Response {
    match app.runs.store().descriptions() {
        Ok(descriptions) => Html(pages::test(&app.buses, &descriptions, &app.runs.running())).into_response(),
        Err(err) => page_error(StatusCode::INTERNAL_SERVER_ERROR, "Test", &err.to_string()),
    }
}

async fn history_page(State(app): State<App>) -> Response {
    match app.runs.store().list() {
        Ok(rows) => Html(pages::history(&rows, &app.kept)).into_response(),
        Err(err) => page_error(StatusCode::INTERNAL_SERVER_ERROR, "History", &err.to_string()),
    }
}

async fn run_page(State(app): State<App>, Path(id): Path<i64>) -> Response {
    let view = app.runs.view(id);
    let previous = app.runs.store().previous(id);
    match (view, previous) {
        (Ok(Some(view)), Ok(previous)) => Html(pages::run(&view, previous)).into_response(),
        (Ok(None), _) => page_error(
            StatusCode::NOT_FOUND,
            "No such run",
            &format!("there is no run {id}"),
        ),
        (Err(err), _) | (_, Err(err)) => {
            page_error(StatusCode::INTERNAL_SERVER_ERROR, "Run", &err.to_string())
        }
    }
}

async fn run_report(State(app): State<App>, Path(id): Path<i64>) -> Response {
    match app.runs.store().report(id, true) {
        Ok(Some(html)) => Html(html).into_response(),
        Ok(None) => page_error(
            StatusCode::NOT_FOUND,
            "No report",
            &format!("run {id} has no report (yet)"),
        ),
        Err(err) => page_error(StatusCode::INTERNAL_SERVER_ERROR, "Report", &err.to_string()),
    }
}

async fn run_report_json(State(app): State<App>, Path(id): Path<i64>) -> Response {
    match app.runs.store().report(id, false) {
        Ok(Some(text)) => ([(header::CONTENT_TYPE, "application/json")], text).into_response(),
        Ok(None) => error(StatusCode::NOT_FOUND, format!("run {id} has no report (yet)")),
        Err(err) => error(StatusCode::INTERNAL_SERVER_ERROR, err.to_string()),
    }
}

#[derive(Debug, Deserialize)]
struct Pair {
    a: i64,
    b: i64,
}

async fn compare_page(State(app): State<App>, Query(pair): Query<Pair>) -> Response {
    let store = app.runs.store();
    let load = |id| -> Result<Option<(crate::store::RunRow, serde_json::Value)>, crate::store::StoreError> {
        let Some(row) = store.get(id)? else {
            return Ok(None);
        };
        let report = store
            .report(id, false)?
            .and_then(|t| serde_json::from_str(&t).ok());
        Ok(report.map(|r| (row, r)))
    };
    match (load(pair.a), load(pair.b)) {
        (Ok(Some((a, ra))), Ok(Some((b, rb)))) => {
            Html(pages::comparison(&a, &b, &compare::compare(&ra, &rb))).into_response()
        }
        (Err(err), _) | (_, Err(err)) => {
            page_error(StatusCode::INTERNAL_SERVER_ERROR, "Compare", &err.to_string())
        }
        _ => page_error(
            StatusCode::NOT_FOUND,
            "Compare",
            &format!("run {} or run {} has no report to compare", pair.a, pair.b),
        ),
    }
}

async fn asset(Path(name): Path<String>) -> Response {
    match assets::get(&name) {
        Some((content_type, bytes)) => ([(header::CONTENT_TYPE, content_type)], bytes).into_response(),
        None => error(StatusCode::NOT_FOUND, format!("no asset {name}")),
    }
}

async fn picture(path: Option<PathBuf>) -> Response {
    let Some(path) = path else {
        return error(StatusCode::NOT_FOUND, "the system has no such picture");
    };
    let content_type = assets::content_type(&path.to_string_lossy());
    match tokio::task::spawn_blocking(move || crate::backend::read_file(&path)).await {
        Ok(Ok(bytes)) => ([(header::CONTENT_TYPE, content_type)], bytes).into_response(),
        _ => error(StatusCode::NOT_FOUND, "the picture cannot be read"),
    }
}

async fn background(State(app): State<App>) -> Response {
    picture(app.watched.as_ref().and_then(|w| w.background.clone())).await
}

async fn figure(State(app): State<App>, Path(vertex): Path<usize>) -> Response {
    picture(app.watched.as_ref().and_then(|w| w.figures.get(&vertex).cloned())).await
}

async fn api_state(State(app): State<App>) -> Response {
    match &app.watched {
        Some(watched) => Json(watched.state()).into_response(),
        None => error(
            StatusCode::NOT_FOUND,
            "no system is watched: start the server with --nodelist",
        ),
    }
}

/// The number after which a reconnecting stream resumes (`Last-Event-ID`).
fn last_event_id(headers: &HeaderMap) -> Option<u64> {
    headers
        .get("last-event-id")
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.trim().parse().ok())
}

/// One server-sent event per published JSON event, numbered, from `resume` (when still kept) or
/// from now, until the server stops or the stream fell too far behind.
fn sse<T: Send + Sync + 'static>(
    owner: Arc<T>,
    ring: fn(&T) -> &EventRing,
    resume: Option<u64>,
    stopping: watch::Receiver<bool>,
) -> Sse<impl Stream<Item = Result<Event, Infallible>>> {
    let events = ring(&owner);
    let wake = events.subscribe();
    let from = match resume {
        Some(after) if events.can_resume(after) => after,
        _ => events.last(),
    };
    let stream = stream::unfold(
        (owner, from, wake, stopping),
        move |(owner, cursor, mut wake, mut stopping)| async move {
            loop {
                if *stopping.borrow_and_update() {
                    return None;
                }
                wake.borrow_and_update();
                let batch = ring(&owner).after(cursor).ok()?;
                if let Some((last, _)) = batch.last() {
                    let last = *last;
                    let items: Vec<Result<Event, Infallible>> = batch
                        .into_iter()
                        .map(|(n, text)| Ok(Event::default().id(n.to_string()).data(&*text)))
                        .collect();
                    return Some((items, (owner, last, wake, stopping)));
                }
                tokio::select! {
                    changed = wake.changed() => changed.ok()?,
                    changed = stopping.changed() => changed.ok()?,
                }
            }
        },
    )
    .flat_map(stream::iter);
    Sse::new(stream).keep_alive(KeepAlive::default())
}

async fn api_events(State(app): State<App>, headers: HeaderMap) -> Response {
    match app.watched {
        Some(watched) => sse(
            watched,
            |w| w.live.events(),
            last_event_id(&headers),
            app.stopping,
        )
        .into_response(),
        None => error(
            StatusCode::NOT_FOUND,
            "no system is watched: start the server with --nodelist",
        ),
    }
}

async fn api_run_events(State(app): State<App>, headers: HeaderMap) -> Response {
    sse(app.runs, Runs::events, last_event_id(&headers), app.stopping).into_response()
}

#[derive(Debug, Deserialize)]
struct Named {
    name: String,
}

fn refusal(refusal: &Refusal) -> Response {
    let status = match refusal {
        Refusal::TooLarge { .. } => StatusCode::PAYLOAD_TOO_LARGE,
        Refusal::Binary { .. } | Refusal::NotADescription(_) => StatusCode::UNSUPPORTED_MEDIA_TYPE,
        Refusal::PathInName(_) | Refusal::BadName(_) | Refusal::Empty(_) => StatusCode::BAD_REQUEST,
    };
    error(status, refusal.to_string())
}

/// An upload's bytes, or the refusal to show.
async fn receive(name: &str, headers: &HeaderMap, body: Body, cap: usize) -> Result<Vec<u8>, Response> {
    upload::check_name(name).map_err(|r| refusal(&r))?;
    let announced = headers
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.parse().ok());
    upload::check_announced(name, announced, cap).map_err(|r| refusal(&r))?;
    let bytes = axum::body::to_bytes(body, cap)
        .await
        .map_err(|_| refusal(&upload::too_large(name, cap)))?;
    upload::check_content(name, &bytes).map_err(|r| refusal(&r))?;
    Ok(bytes.to_vec())
}

async fn api_check(
    State(app): State<App>,
    Query(named): Query<Named>,
    headers: HeaderMap,
    body: Body,
) -> Response {
    let bytes = match receive(&named.name, &headers, body, app.cap).await {
        Ok(bytes) => bytes,
        Err(response) => return response,
    };
    let name = named.name;
    match tokio::task::spawn_blocking(move || check::check(&name, &bytes)).await {
        Ok(checked) => Json(checked).into_response(),
        Err(err) => error(
            StatusCode::INTERNAL_SERVER_ERROR,
            format!("the check failed: {err}"),
        ),
    }
}

async fn api_fix(
    State(app): State<App>,
    Query(named): Query<Named>,
    headers: HeaderMap,
    body: Body,
) -> Response {
    let bytes = match receive(&named.name, &headers, body, app.cap).await {
        Ok(bytes) => bytes,
        Err(response) => return response,
    };
    let name = named.name.clone();
    match tokio::task::spawn_blocking(move || check::fixed(&name, &bytes)).await {
        Ok(Ok(fixed)) => {
            // A header value, not a path: only the safe characters of the name are kept.
            let safe: String = named
                .name
                .chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() || "._-".contains(c) {
                        c
                    } else {
                        '_'
                    }
                })
                .collect();
            let disposition = format!("attachment; filename=\"fixed-{safe}\"");
            let mut response = fixed.into_response();
            response.headers_mut().insert(
                header::CONTENT_TYPE,
                HeaderValue::from_static("application/octet-stream"),
            );
            if let Ok(value) = HeaderValue::from_str(&disposition) {
                response.headers_mut().insert(header::CONTENT_DISPOSITION, value);
            }
            response
        }
        Ok(Err(reason)) => error(StatusCode::UNPROCESSABLE_ENTITY, reason),
        Err(err) => error(
            StatusCode::INTERNAL_SERVER_ERROR,
            format!("the fix failed: {err}"),
        ),
    }
}

async fn api_eds(
    State(app): State<App>,
    Query(named): Query<Named>,
    headers: HeaderMap,
    body: Body,
) -> Response {
    let bytes = match receive(&named.name, &headers, body, app.cap).await {
        Ok(bytes) => bytes,
        Err(response) => return response,
    };
    let runs = Arc::clone(&app.runs);
    let name = named.name;
    match tokio::task::spawn_blocking(move || {
        runs.store().put_description(&name, &bytes).map(|sha| (name, sha))
    })
    .await
    {
        Ok(Ok((name, sha))) => Json(json!({"eds": sha, "name": name})).into_response(),
        Ok(Err(err)) => error(StatusCode::INTERNAL_SERVER_ERROR, err.to_string()),
        Err(err) => error(StatusCode::INTERNAL_SERVER_ERROR, err.to_string()),
    }
}

async fn api_runs(State(app): State<App>) -> Response {
    match app.runs.store().list() {
        Ok(rows) => Json(json!({"running": app.runs.running(), "runs": rows})).into_response(),
        Err(err) => error(StatusCode::INTERNAL_SERVER_ERROR, err.to_string()),
    }
}

/// What `POST /api/runs` takes.
#[derive(Debug, Deserialize)]
struct StartBody {
    /// `simulated`, or the index of a configured bus.
    bus: String,
    node: u8,
    /// `bundled`, or the SHA-256 of a stored description.
    eds: String,
    suites: Vec<String>,
    #[serde(default)]
    fault: Option<String>,
}

async fn api_start(State(app): State<App>, Json(body): Json<StartBody>) -> Response {
    let target = if body.bus == "simulated" {
        let faults = match body.fault.as_deref().filter(|f| !f.is_empty()) {
            None => Vec::new(),
            Some(name) => match crate::runs::fault_named(name) {
                Some(fault) => vec![fault],
                None => {
                    return error(
                        StatusCode::BAD_REQUEST,
                        format!("no fault {name:?}; `canopener sim --list-faults` lists them"),
                    );
                }
            },
        };
        (Target::Simulated(faults), "simulated".to_owned())
    } else {
        match body.bus.parse::<usize>().ok().and_then(|i| app.buses.get(i)) {
            Some((_, spec)) => (Target::Bus(spec.clone()), spec.clone()),
            None => {
                return error(
                    StatusCode::BAD_REQUEST,
                    format!("no bus {:?}: choose one the server was started with", body.bus),
                );
            }
        }
    };
    let (eds_name, eds_bytes) = if body.eds == "bundled" {
        (
            canopener_conformance::tour::EDS_NAME.to_owned(),
            canopener_conformance::tour::EDS.to_vec(),
        )
    } else {
        match app.runs.store().description(&body.eds) {
            Ok(Some(found)) => found,
            Ok(None) => return error(StatusCode::BAD_REQUEST, "no such description: upload it again"),
            Err(err) => return error(StatusCode::INTERNAL_SERVER_ERROR, err.to_string()),
        }
    };
    let request = StartRun {
        target: target.0,
        bus_label: target.1,
        node: body.node,
        eds_name,
        eds_bytes,
        suites: body.suites,
    };
    let runs = Arc::clone(&app.runs);
    match tokio::task::spawn_blocking(move || runs.start(request)).await {
        Ok(Ok(id)) => Json(json!({"run": id})).into_response(),
        Ok(Err(err @ StartError::Busy { .. })) => error(StatusCode::CONFLICT, err.to_string()),
        Ok(Err(err @ StartError::Invalid(_))) => error(StatusCode::BAD_REQUEST, err.to_string()),
        Ok(Err(err)) => error(StatusCode::INTERNAL_SERVER_ERROR, err.to_string()),
        Err(err) => error(StatusCode::INTERNAL_SERVER_ERROR, err.to_string()),
    }
}

async fn api_run(State(app): State<App>, Path(id): Path<i64>) -> Response {
    let previous = app.runs.store().previous(id).ok().flatten();
    match app.runs.view(id) {
        Ok(Some(view)) => {
            let mut members = match serde_json::to_value(view) {
                Ok(serde_json::Value::Object(members)) => members,
                _ => serde_json::Map::new(),
            };
            members.insert("previous".to_owned(), json!(previous));
            Json(serde_json::Value::Object(members)).into_response()
        }
        Ok(None) => error(StatusCode::NOT_FOUND, format!("there is no run {id}")),
        Err(err) => error(StatusCode::INTERNAL_SERVER_ERROR, err.to_string()),
    }
}

async fn api_stop(State(app): State<App>, Path(id): Path<i64>) -> Response {
    if app.runs.stop(id) {
        Json(json!({"stopping": id})).into_response()
    } else {
        error(StatusCode::CONFLICT, format!("run {id} is not running"))
    }
}

/// How the server is started.
#[derive(Debug, Clone)]
pub struct ServeConfig {
    /// The address to listen on.
    pub listen: SocketAddr,
    /// The system to watch: topology file, buses by network, monitor position.
    pub system: Option<SystemConfig>,
    /// Every configured bus (offered to runs), by network.
    pub buses: Vec<(u32, String)>,
    /// `--data DIR`: history and uploaded descriptions are kept there.
    pub data: Option<PathBuf>,
    /// `--token-file`.
    pub token_file: Option<PathBuf>,
    /// The upload cap.
    pub max_upload: usize,
}

/// The system a server watches.
#[derive(Debug, Clone)]
pub struct SystemConfig {
    /// The topology file.
    pub file: PathBuf,
    /// The vertex the monitor listens at (`--at`), by id or NodeName.
    pub at: Option<String>,
}

/// Why the server could not start or failed.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// Bad configuration (a usage error).
    #[error("{0}")]
    Usage(String),
    /// The system or a bus.
    #[error(transparent)]
    Backend(#[from] crate::backend::BackendError),
    /// The token.
    #[error(transparent)]
    Token(#[from] access::TokenError),
    /// The store.
    #[error(transparent)]
    Store(#[from] crate::store::StoreError),
    /// The socket.
    #[error("cannot listen on {address}: {source}")]
    Listen {
        /// Where.
        address: SocketAddr,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A file under `--data`.
    #[error("--data {path}: {source}")]
    Data {
        /// The folder.
        path: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
}

/// Where the server listens, for the caller to print.
#[derive(Debug, Clone)]
pub struct Ready {
    /// The address to open, with the token when one is required.
    pub url: String,
    /// The address bound.
    pub address: SocketAddr,
    /// The token, when one is required.
    pub token: Option<String>,
}

/// Something the server does besides answering requests, started once it listens (the tour's fault
/// cycle and its conformance runs).
pub type Extra = Box<dyn FnOnce(Arc<Runs>, Cancel) + Send>;

/// Runs the server until `cancel` (Ctrl-C): builds the store and the monitor, listens, calls
/// `on_ready`, serves, and at the end stops the runs as Ctrl-C stops `canopener test`, and the
/// monitor.
pub fn serve(
    config: ServeConfig,
    cancel: Cancel,
    extra: Option<Extra>,
    on_ready: impl FnOnce(&Ready),
) -> Result<(), ServeError> {
    let access = Access::new(config.listen, config.token_file.as_deref())?;
    if let Some(data) = &config.data {
        crate::backend::create_dir(data).map_err(|source| ServeError::Data {
            path: data.display().to_string(),
            source,
        })?;
    }
    let store = Arc::new(Store::open(config.data.as_deref())?);
    let kept = match &config.data {
        Some(dir) => format!("Runs are kept in {}.", dir.join(crate::store::FILE).display()),
        None => "Runs are kept in memory until the server stops (start it with --data DIR to keep them)."
            .to_owned(),
    };
    let watched = match &config.system {
        Some(system) => {
            let read = crate::backend::System::read(&system.file)?;
            let at = match &system.at {
                Some(name) => Some(read.topology().find_vertex(name).ok_or_else(|| {
                    ServeError::Usage(format!(
                        "--at {name}: no vertex of the topology has this id or NodeName"
                    ))
                })?),
                None => read.topology().default_position(),
            };
            Some(Arc::new(Watched::new(
                read,
                at,
                config.buses.clone(),
                system.file.display().to_string(),
            )))
        }
        None => None,
    };
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .map_err(|source| ServeError::Listen {
            address: config.listen,
            source,
        })?;
    let runs = Arc::new(Runs::new(store));
    let (stop_streams, stopping) = watch::channel(false);
    let app = App {
        watched: watched.clone(),
        buses: config.buses.clone(),
        runs: Arc::clone(&runs),
        cap: config.max_upload,
        kept,
        stopping,
    };
    let monitor_thread = watched.map(|watched| {
        let cancel = cancel.clone();
        std::thread::Builder::new()
            .name("monitor".to_owned())
            .spawn(move || watched.watch(&cancel))
    });
    let result = runtime.block_on(async {
        let listener = tokio::net::TcpListener::bind(config.listen)
            .await
            .map_err(|source| ServeError::Listen {
                address: config.listen,
                source,
            })?;
        let address = listener.local_addr().map_err(|source| ServeError::Listen {
            address: config.listen,
            source,
        })?;
        let token = access.token().map(str::to_owned);
        let host = if address.ip().is_unspecified() {
            format!("127.0.0.1:{}", address.port())
        } else {
            address.to_string()
        };
        let url = match &token {
            Some(token) => format!("http://{host}/?token={token}"),
            None => format!("http://{host}/"),
        };
        on_ready(&Ready { url, address, token });
        if let Some(extra) = extra {
            let (runs, cancel) = (Arc::clone(&runs), cancel.clone());
            std::thread::spawn(move || extra(runs, cancel));
        }
        let stopped = {
            let cancel = cancel.clone();
            async move {
                // Cancel is a flag (set by the Ctrl-C handler): looked at every 50 ms.
                while !cancel.is_cancelled() {
                    tokio::time::sleep(std::time::Duration::from_millis(50)).await;
                }
            }
        };
        axum::serve(listener, router(app, access))
            .with_graceful_shutdown(async move {
                stopped.await;
                let _ = stop_streams.send(true);
            })
            .await
            .map_err(|source| ServeError::Listen {
                address: config.listen,
                source,
            })
    });
    // The runs end as `canopener test` ends on Ctrl-C: write-back done, report kept as interrupted.
    runs.stop_all();
    cancel.cancel();
    if let Some(Ok(thread)) = monitor_thread {
        let _ = thread.join();
    }
    result
}

//! `canopener serve` end to end, in headless Chromium driven through the DevTools protocol: the
//! monitor page on a `sim --nodelist` system with a cut typed into the simulator, `/check` against
//! `eds check --format json`, conformance runs from `/test` watched by ten sessions and compared, the
//! refusals of hostile uploads and foreign pages, Ctrl-C during a run, the tour, and 100 devices
//! changing state at 10 Hz. Screenshots of every page are left in `target/tmp/web-screenshots/`.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use serde_json::{Value, json};

use super::web_harness::{Server, browser, http, js, open, screenshot, wait_until};
use super::{canopener, temp_dir};
use crate::support::{HubProc, Proc};

fn network_fixture(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../canopener-network/test_data")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

/// The badge of `device` on `network` has `state`.
fn badge(device: &str, network: u32, state: &str) -> String {
    format!(
        r#"document.querySelector('.state[data-device="{device}"][data-network="{network}"]').dataset.state === '{state}'"#
    )
}

fn without_time(text: &str) -> Value {
    let mut value: Value = serde_json::from_str(text).unwrap_or_else(|e| panic!("{e}: {text}"));
    value.as_object_mut().expect("an event object").remove("time");
    value
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    let index = ((p * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len()) - 1;
    sorted[index]
}

#[test]
fn the_monitor_page_shows_a_cut_typed_into_the_simulator_and_the_repair() {
    let dir = temp_dir("web-monitor");
    let Some(browser) = browser(&dir) else { return };
    let hub = HubProc::start();
    let file = network_fixture("gateway.graphml");
    let (can0, can1) = (hub.spec("can0"), hub.spec("can1"));
    let (bus1, bus2) = (format!("1={can0}"), format!("2={can1}"));
    let mut sim_cmd = canopener();
    sim_cmd.args(["sim", "--nodelist", &file, "--bus", &bus1, "--bus", &bus2]);
    let mut sim = Proc::spawn("sim --nodelist", sim_cmd);
    let server = Server::start(
        "serve",
        &["serve", "--nodelist", &file, "--bus", &can0, "--bus", &bus2],
    );
    // `net monitor` on the same buses: the page must receive exactly its events.
    let mut monitor_cmd = canopener();
    monitor_cmd.args([
        "net", "monitor", &file, "--bus", &can0, "--bus", &bus2, "--format", "json",
    ]);
    let mut monitor = Proc::spawn("net monitor", monitor_cmd);
    let tab = open(&browser, &server.url("/"));
    // The contract: a badge per device and network, a cable element per cable.
    let badges = js(
        &tab,
        "[...document.querySelectorAll('[data-device]')].map(b => b.dataset.device + '@' + b.dataset.network)",
    );
    assert_eq!(
        badges,
        json!([
            "PLC@1",
            "Engine@1",
            "Gateway@1",
            "Gateway@2",
            "Boom1@2",
            "Boom2@2",
            "Boom3@2"
        ])
    );
    let cables = js(
        &tab,
        "[...document.querySelectorAll('[data-cable]')].map(c => c.dataset.cable + '=' + c.dataset.suspect)",
    );
    assert_eq!(
        cables,
        json!(["A1=false", "A2=false", "B1=false", "B2=false", "B3=false"])
    );
    wait_until(
        &tab,
        "[...document.querySelectorAll('.state:not([data-monitor])')].every(b => b.dataset.state === 'pre-operational')",
        Duration::from_secs(20),
    );
    // The master is where the monitor listens: not watched, its state unknown.
    assert_eq!(
        js(
            &tab,
            "[...document.querySelectorAll('.state[data-monitor=\"true\"]')].map(b => b.dataset.device + '=' + b.dataset.state)"
        ),
        json!(["PLC=unknown"])
    );
    sim.send_line("cut B2");
    let cut = format!(
        "{} && {} && {} && document.querySelector('[data-cable=\"B2\"]').dataset.suspect === 'true'",
        badge("Boom2", 2, "silent"),
        badge("Boom3", 2, "silent"),
        badge("Boom1", 2, "pre-operational")
    );
    let latency = wait_until(&tab, &cut, Duration::from_secs(5));
    eprintln!(
        "cable cut typed into the simulator -> page shows the silent devices and the suspect cable: {latency:?}"
    );
    assert!(latency < Duration::from_secs(1), "{latency:?}");
    let explanations = js(
        &tab,
        "[...document.querySelectorAll('#explanations [data-kind]')].map(e => [e.dataset.kind, e.dataset.candidates])",
    );
    assert!(
        explanations.as_array().unwrap().contains(&json!(["cable", "B2"])),
        "{explanations}"
    );
    assert_eq!(
        js(
            &tab,
            "document.querySelector('[data-cable=\"B1\"]').dataset.suspect"
        ),
        json!("false")
    );
    screenshot(&tab, "monitor-cut");
    sim.send_line("repair B2");
    let repaired = format!(
        "{} && {} && document.querySelector('[data-cable=\"B2\"]').dataset.suspect === 'false' \
         && document.querySelectorAll('#explanations [data-kind]').length === 0",
        badge("Boom2", 2, "pre-operational"),
        badge("Boom3", 2, "pre-operational")
    );
    let back = wait_until(&tab, &repaired, Duration::from_secs(5));
    eprintln!("repair -> page shows every device heard again: {back:?}");
    // The push: how long each event took from the monitor's clock to the page.
    let mut latencies: Vec<f64> = serde_json::from_value(js(&tab, "canopener.monitor.latencies")).unwrap();
    latencies.sort_by(f64::total_cmp);
    eprintln!(
        "monitor event -> browser: {} events, median {:.1} ms, p90 {:.1} ms, max {:.1} ms",
        latencies.len(),
        percentile(&latencies, 0.5),
        percentile(&latencies, 0.9),
        latencies[latencies.len() - 1]
    );
    assert!(percentile(&latencies, 0.5) < 100.0, "{latencies:?}");
    assert_eq!(js(&tab, "canopener.monitor.gaps"), json!(0));
    // /api/events carries the events of `net monitor --format json`: the same objects, written the
    // same way (key for key, in order). The two monitors are independent processes that started at
    // different moments (so times differ), and on a loaded machine either may see a late heartbeat as
    // a short silence the other did not: what both must have seen is the cut's own effect.
    std::thread::sleep(Duration::from_millis(500));
    monitor.interrupt();
    monitor.wait(Duration::from_secs(10));
    let cli_events = monitor.remaining_lines();
    let page_events: Vec<String> = serde_json::from_value(js(&tab, "canopener.monitor.raw")).unwrap();
    let cli: Vec<Value> = cli_events.iter().map(|e| without_time(e)).collect();
    let page: Vec<Value> = page_events.iter().map(|e| without_time(e)).collect();
    for (node, id) in [("Boom2", 22), ("Boom3", 23)] {
        let silent = json!({"event": "state", "network": 2, "node": node, "node_id": id, "state": "silent"});
        assert!(page.contains(&silent), "{node}: {page:?}");
        assert!(cli.contains(&silent), "{node}: {cli:?}");
    }
    assert!(
        page.iter().any(|e| e["event"] == "diagnosis"
            && e["explanations"]
                .as_array()
                .is_some_and(|list| list.iter().any(|x| x["candidates"] == json!(["B2"])))),
        "{page:?}"
    );
    // The keys of a JSON object in the order written.
    let keys = |text: &str| -> Vec<String> {
        let parts: Vec<&str> = text.split('"').collect();
        parts
            .windows(2)
            .filter(|w| w[1].starts_with(':'))
            .map(|w| w[0].to_owned())
            .collect()
    };
    for kind in ["state", "recovered"] {
        let tag = format!(r#"{{"event":"{kind}""#);
        let page = page_events
            .iter()
            .find(|e| e.starts_with(&tag))
            .expect("the page's event");
        let cli = cli_events
            .iter()
            .find(|e| e.starts_with(&tag))
            .expect("net monitor's event");
        assert_eq!(keys(page), keys(cli), "{page} / {cli}");
    }
    let state = server.get_json("/api/state");
    assert_eq!(
        js(&tab, "canopener.monitor.lastSeq"),
        state["seq"],
        "the page is up to date"
    );
}

/// `canopener eds check|fix ARGS` run in `dir`, its stdout.
fn eds_in(dir: &Path, args: &[&str]) -> Vec<u8> {
    let output = canopener()
        .current_dir(dir)
        .args(args)
        .output()
        .expect("run canopener");
    output.stdout
}

#[test]
fn a_corpus_eds_on_the_check_page_gives_the_findings_of_eds_check_and_its_fixes() {
    let dir = temp_dir("web-check");
    let Some(browser) = browser(&dir) else { return };
    let name = "SvanLeeuwen5__CANopen_laadpaal__V2G500V30A.eds";
    let path = dir.join(name);
    std::fs::copy(canopener_testkit::corpus::eds(name), &path).expect("copy the corpus file");
    let cli: Value =
        serde_json::from_slice(&eds_in(&dir, &["eds", "check", name, "--format", "json"])).unwrap();
    let server = Server::start("serve", &["serve"]);
    let tab = open(&browser, &server.url("/check"));
    tab.wait_for_element("#file")
        .expect("the file input")
        .set_input_files(&[path.to_str().unwrap()])
        .expect("choose the file");
    wait_until(&tab, "canopener.check.report !== null", Duration::from_secs(30));
    assert_eq!(
        js(&tab, "canopener.check.report"),
        cli,
        "the page's report is `eds check --format json`'s"
    );
    let findings = cli["files"][0]["findings"].as_array().unwrap();
    let expected: Vec<Value> = findings
        .iter()
        .map(|f| json!([f["code"], f["severity"], f["line"]]))
        .collect();
    let shown = js(
        &tab,
        "[...document.querySelectorAll('#findings .finding')].map(f => [f.dataset.code, f.dataset.severity, +f.dataset.line])",
    );
    assert_eq!(shown, Value::Array(expected));
    // Every finding shows its source line, as the HTML report does.
    let lines = js(
        &tab,
        "[...document.querySelectorAll('#findings .finding')].map(f => f.querySelector('pre') !== null)",
    );
    assert!(lines.as_array().unwrap().iter().all(|l| l == true), "{lines}");
    screenshot(&tab, "check");
    // Filters: warnings off, then one code only.
    js(
        &tab,
        "(() => { const w = document.querySelector('#severities input[value=warning]'); w.click(); return true; })()",
    );
    let visible = js(
        &tab,
        "[...document.querySelectorAll('#findings .finding')].filter(f => !f.hidden).map(f => f.dataset.severity)",
    );
    let not_warnings = findings.iter().filter(|f| f["severity"] != "warning").count();
    assert_eq!(visible.as_array().unwrap().len(), not_warnings);
    assert!(visible.as_array().unwrap().iter().all(|s| s != "warning"));
    let code = findings
        .iter()
        .find(|f| f["severity"] == "error")
        .expect("an error")["code"]
        .clone();
    js(
        &tab,
        &format!(
            "(() => {{ const s = document.getElementById('code'); s.value = {code}; s.dispatchEvent(new Event('change')); return true; }})()"
        ),
    );
    let codes = js(
        &tab,
        "[...document.querySelectorAll('#findings .finding')].filter(f => !f.hidden).map(f => f.dataset.code)",
    );
    assert!(
        !codes.as_array().unwrap().is_empty() && codes.as_array().unwrap().iter().all(|c| *c == code),
        "{codes}"
    );
    // The safe fixes: the diff of `eds fix --dry-run`, and the download is `eds fix -o`'s file.
    let diff = String::from_utf8(eds_in(&dir, &["eds", "fix", name, "--dry-run"])).unwrap();
    assert!(!diff.is_empty());
    assert_eq!(js(&tab, "canopener.check.checked.fixes.diff"), json!(diff));
    eds_in(&dir, &["eds", "fix", name, "-o", "fixed.eds"]);
    let fixed = std::fs::read(dir.join("fixed.eds")).unwrap();
    let downloaded = js(
        &tab,
        &format!(
            "fetch('/api/fix?name={name}', {{method: 'POST', body: canopener.check.file.blob}}).then(r => r.arrayBuffer()).then(b => [...new Uint8Array(b)])"
        ),
    );
    assert_eq!(downloaded, json!(fixed));
}

#[test]
fn hostile_uploads_and_foreign_pages_are_refused_with_their_reasons_and_nothing_is_written() {
    let dir = temp_dir("web-hostile");
    let Some(browser) = browser(&dir) else { return };
    let work = dir.join("work");
    std::fs::create_dir_all(&work).unwrap();
    let mut command = canopener();
    command
        .current_dir(&work)
        .args(["serve", "--listen", "127.0.0.1:0"])
        .env_remove("CANOPENER_BUS");
    let mut process = Proc::spawn("serve", command);
    let base = process
        .line(Duration::from_secs(60))
        .trim_end_matches('/')
        .to_owned();
    let tab = open(&browser, &format!("{base}/check"));
    let cases = [
        (
            "big.eds",
            "new Blob([new Uint8Array(17 * 1024 * 1024).fill(65)])",
            "big.eds: 17 MiB is more than this server accepts (16 MiB)",
        ),
        (
            "picture.eds",
            "new Blob([new Uint8Array([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0, 0, 0, 13])])",
            "picture.eds: binary content (a zero byte at offset 8); EDS, DCF and XDD files are text",
        ),
        (
            "../../etc/motor.eds",
            "new Blob(['[FileInfo]\\nFileName=motor.eds\\n'])",
            "\"../../etc/motor.eds\": a file name with a folder or `..` in it is refused",
        ),
        (
            "notes.txt",
            "new Blob(['hello'])",
            "notes.txt: not a device description",
        ),
    ];
    for (name, blob, message) in cases {
        let accepted = js(&tab, &format!("canopener.check.upload({}, {blob})", json!(name)));
        assert_eq!(accepted, json!(false), "{name}");
        let shown = js(
            &tab,
            "document.getElementById('refusal').hidden ? null : document.getElementById('refusal').textContent",
        );
        assert!(
            shown.as_str().is_some_and(|s| s.starts_with(message)),
            "{name}: {shown}"
        );
    }
    screenshot(&tab, "check-refused");
    // A page of another site cannot make the server do anything, and only loopback names reach it.
    let (status, body) = http(
        &base,
        "POST",
        "/api/check?name=a.eds",
        &[("Origin", "http://evil.example")],
        b"[FileInfo]\n",
    );
    assert_eq!(status, 403, "{body}");
    assert!(body.contains("came from another site's page"), "{body}");
    let (status, _) = http(
        &base,
        "POST",
        "/api/check?name=a.eds",
        &[("Origin", &base)],
        b"[FileInfo]\n",
    );
    assert_eq!(status, 200);
    let (status, body) = http(&base, "GET", "/api/runs", &[("Host", "rebound.example:80")], b"");
    assert!(status == 421 || status == 400, "{status} {body}");
    // Nothing was written: no --data, and the working directory is as it was.
    assert_eq!(std::fs::read_dir(&work).unwrap().count(), 0);
    drop(process);
    // Any other address needs the token, on every request.
    let mut command = canopener();
    command
        .args(["serve", "--listen", "0.0.0.0:0"])
        .env_remove("CANOPENER_BUS");
    let mut open_server = Proc::spawn("serve on all addresses", command);
    let url = open_server.line(Duration::from_secs(60));
    let (base, token) = url.split_once("/?token=").expect("the address carries the token");
    assert_eq!(token.len(), 32);
    assert!(open_server.stderr().contains(token) || open_server.stderr().is_empty());
    let (status, body) = http(base, "GET", "/api/runs", &[], b"");
    assert_eq!(status, 401, "{body}");
    assert!(body.contains("this server needs its token"));
    let bearer = format!("Bearer {token}");
    let (status, _) = http(base, "GET", "/api/runs", &[("Authorization", &bearer)], b"");
    assert_eq!(status, 200);
    let token_tab = open(&browser, &url);
    assert_eq!(
        js(&token_tab, "location.search"),
        json!(""),
        "the token left the address for a cookie"
    );
    assert_eq!(
        js(&token_tab, "fetch('/api/runs').then(r => r.status)"),
        json!(200)
    );
}

fn start_request(fault: &str) -> String {
    json!({"bus": "simulated", "node": 5, "eds": "bundled", "suites": ["cia301"], "fault": fault}).to_string()
}

#[test]
fn runs_from_the_test_page_are_watched_by_ten_sessions_kept_listed_and_compared() {
    let dir = temp_dir("web-test");
    let Some(browser) = browser(&dir) else { return };
    let data = dir.join("data");
    let server = Server::start("serve", &["serve", "--data", data.to_str().unwrap()]);
    let clock = Instant::now();
    // Ten sessions, each its own browser context (cookies, storage), all on /test.
    let contexts: Vec<_> = (0..10)
        .map(|_| browser.new_context().expect("a browser context"))
        .collect();
    let tabs: Vec<_> = contexts.iter().map(|c| c.new_tab().expect("tab")).collect();
    // Loaded side by side, as ten people would open the page.
    let page = server.url("/test");
    std::thread::scope(|scope| {
        for tab in &tabs {
            let page = &page;
            scope.spawn(move || {
                tab.set_default_timeout(Duration::from_secs(60));
                tab.navigate_to(page).unwrap().wait_until_navigated().unwrap();
            });
        }
    });
    for tab in &tabs {
        wait_until(tab, "canopener.runs.connected", Duration::from_secs(20));
    }
    eprintln!("ten sessions open: {:?}", clock.elapsed());
    let run = js(&tabs[0], &format!("canopener.runs.start({})", start_request("")));
    assert_eq!(run, json!(1));
    // A session that goes away mid-run disturbs nothing.
    tabs[9].close(true).expect("close a session");
    for tab in &tabs[..9] {
        wait_until(
            tab,
            "document.querySelector('#run .ended[data-status=\"done\"]') !== null",
            Duration::from_secs(120),
        );
    }
    eprintln!("run 1 seen done by nine sessions: {:?}", clock.elapsed());
    let view = server.get_json("/api/runs/1");
    let total = view["verdicts"].as_array().unwrap().len();
    assert!(total > 50, "{view}");
    assert_eq!(view["status"], "done");
    for (i, tab) in tabs[..9].iter().enumerate() {
        let rows = js(tab, "document.querySelectorAll('#run tbody tr').length");
        assert_eq!(rows, json!(total), "session {i} saw every verdict");
        let received = js(tab, "canopener.runs.received").as_u64().unwrap();
        assert!(
            received >= total as u64 + 2,
            "session {i} followed the run live: {received} events"
        );
    }
    // The HTML report opens at the end.
    wait_until(
        &tabs[0],
        "(() => { const f = document.querySelector('iframe.report'); return f && f.contentDocument && f.contentDocument.querySelectorAll('details.test').length > 0; })()",
        Duration::from_secs(20),
    );
    assert_eq!(
        js(
            &tabs[0],
            "document.querySelector('iframe.report').contentDocument.querySelectorAll('details.test').length"
        ),
        json!(total)
    );
    screenshot(&tabs[0], "test-run");
    // One run per node: the second of two starts on node 5 is refused, and the page says why.
    let both = js(
        &tabs[0],
        &format!(
            "Promise.all([canopener.runs.start({0}), canopener.runs.start({0})])",
            start_request("heartbeat-jitter")
        ),
    );
    let started: Vec<&Value> = both.as_array().unwrap().iter().filter(|r| !r.is_null()).collect();
    assert_eq!(started, [&json!(2)], "{both}");
    let refusal = js(&tabs[0], "document.getElementById('refusal').textContent");
    assert!(
        refusal
            .as_str()
            .unwrap()
            .starts_with("node 5 on simulated is being tested by run 2"),
        "{refusal}"
    );
    wait_until(
        &tabs[0],
        "document.querySelector('#run .ended[data-status=\"done\"]') !== null && canopener.runs.shown === 2",
        Duration::from_secs(120),
    );
    eprintln!("run 2 done: {:?}", clock.elapsed());
    // Kept in --data, listed by device and date.
    assert!(data.join("canopener.sqlite").is_file());
    let history = open(&browser, &server.url("/history"));
    let rows = js(
        &history,
        "[...document.querySelectorAll('tr[data-run]')].map(r => [+r.dataset.run, r.dataset.status])",
    );
    assert_eq!(rows, json!([[2, "done"], [1, "done"]]));
    assert_eq!(
        js(&history, "document.querySelectorAll('section.device').length"),
        json!(1)
    );
    // What changed from run 1 to run 2: the heartbeat test fails now, its intervals plotted twice.
    let compare = open(&browser, &server.url("/compare?a=1&b=2"));
    let changed = js(
        &compare,
        "[...document.querySelectorAll('.changed-verdict')].map(r => [r.dataset.test, r.dataset.before, r.dataset.after])",
    );
    assert!(
        changed
            .as_array()
            .unwrap()
            .contains(&json!(["cia301.ec.1", "pass", "fail"])),
        "{changed}"
    );
    let plots = js(
        &compare,
        "[...document.querySelectorAll('article.moved-measurement')].map(a => [a.dataset.test, a.querySelectorAll('figure.measurement').length])",
    );
    assert!(
        plots
            .as_array()
            .unwrap()
            .iter()
            .any(|p| p[0] == "cia301.ec.1" && p[1] == 2),
        "{plots}"
    );
}

#[test]
fn ctrl_c_stops_a_run_on_a_bus_cleanly_and_the_history_says_so() {
    let dir = temp_dir("web-ctrl-c");
    let hub = HubProc::start();
    let can0 = hub.spec("can0");
    let eds =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../canopener-conformance/test_data/cia401_full_io.eds");
    let mut sim_cmd = canopener();
    sim_cmd.args(["sim", eds.to_str().unwrap(), "--node-id", "5", "--bus", &can0]);
    let _sim = Proc::spawn("sim", sim_cmd);
    let data = dir.join("data");
    let mut server = Server::start(
        "serve",
        &["serve", "--bus", &can0, "--data", data.to_str().unwrap()],
    );
    // The description uploaded as the /test page uploads it, kept by content, offered on the page.
    let (status, stored) = http(
        &server.base,
        "POST",
        "/api/eds?name=io.eds",
        &[],
        &std::fs::read(&eds).unwrap(),
    );
    assert_eq!(status, 200, "{stored}");
    let stored: Value = serde_json::from_str(&stored).unwrap();
    let sha = stored["eds"].as_str().unwrap().to_owned();
    let (_, page) = http(&server.base, "GET", "/test", &[], b"");
    assert!(
        page.contains(&format!(r#"<option value="{sha}">io.eds ("#)),
        "{page}"
    );
    let body = json!({"bus": "0", "node": 5, "eds": sha, "suites": ["cia301"]}).to_string();
    let json_header = [("Content-Type", "application/json")];
    let (status, answer) = http(&server.base, "POST", "/api/runs", &json_header, body.as_bytes());
    assert_eq!(status, 200, "{answer}");
    // The same node on the same bus takes one run at a time.
    let (status, answer) = http(&server.base, "POST", "/api/runs", &json_header, body.as_bytes());
    assert_eq!(status, 409, "{answer}");
    assert!(
        answer.contains(&format!("node 5 on {can0} is being tested by run 1")),
        "{answer}"
    );
    let started = Instant::now();
    while server.get_json("/api/runs/1")["verdicts"]
        .as_array()
        .unwrap()
        .len()
        < 3
    {
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "the run made no progress"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    server.process.interrupt();
    let status = server.process.wait(Duration::from_secs(30));
    assert!(status.success(), "{status}: {}", server.process.stderr());
    // A new server on the same data: the run is kept, interrupted, with its partial report.
    let again = Server::start("serve again", &["serve", "--data", data.to_str().unwrap()]);
    let view = again.get_json("/api/runs/1");
    assert_eq!(view["status"], "interrupted", "{view}");
    let (status, report) = http(&again.base, "GET", "/runs/1/report.json", &[], b"");
    assert_eq!(status, 200);
    let report: Value = serde_json::from_str(&report).unwrap();
    assert_eq!(report["interrupted"], true);
    assert_eq!(report["device"]["eds"], "io.eds");
    assert!(report["tests"].as_array().unwrap().len() >= 3);
}

#[test]
fn the_tour_serves_a_working_monitor_and_its_runs_in_the_history() {
    let dir = temp_dir("web-tour");
    let Some(browser) = browser(&dir) else { return };
    let tour = dir.join("tour");
    let server = Server::start(
        "demo --serve",
        &["demo", "--serve", "--dir", tour.to_str().unwrap()],
    );
    assert!(tour.join("system/Nodelist.graphml").is_file() && tour.join("system/background.svg").is_file());
    let started = Instant::now();
    loop {
        let runs = server.get_json("/api/runs");
        let done = runs["runs"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|r| r["status"] == "done")
            .count();
        if done == 2 {
            break;
        }
        assert!(started.elapsed() < Duration::from_secs(120), "{runs}");
        std::thread::sleep(Duration::from_millis(200));
    }
    let tab = open(&browser, &server.url("/"));
    assert_eq!(
        js(
            &tab,
            "document.querySelector('image.background').getAttribute('href')"
        ),
        json!("/system/background")
    );
    assert_eq!(
        js(&tab, "document.querySelectorAll('image.node-fig').length"),
        json!(3)
    );
    let picture = js(
        &tab,
        "fetch('/system/background').then(r => [r.status, r.headers.get('content-type')])",
    );
    assert_eq!(picture, json!([200, "image/svg+xml"]));
    // The tour cuts a cable within a few seconds; the page shows it.
    wait_until(
        &tab,
        "document.querySelector('[data-cable=\"C2\"][data-suspect=\"true\"], [data-cable=\"W2\"][data-suspect=\"true\"]') !== null \
         && [...document.querySelectorAll('.state')].some(b => b.dataset.state === 'silent')",
        Duration::from_secs(30),
    );
    screenshot(&tab, "monitor-tour");
    let history = open(&browser, &server.url("/history"));
    assert_eq!(
        js(
            &history,
            "[...document.querySelectorAll('tr[data-run]')].map(r => +r.dataset.run)"
        ),
        json!([2, 1])
    );
    screenshot(&history, "history");
    let compare = open(&browser, &server.url("/compare?a=1&b=2"));
    let changed = js(
        &compare,
        "[...document.querySelectorAll('.changed-verdict')].map(r => r.dataset.test)",
    );
    assert!(
        changed.as_array().unwrap().contains(&json!("cia301.ec.1")),
        "{changed}"
    );
    screenshot(&compare, "compare");
    let run = open(&browser, &server.url("/runs/2"));
    wait_until(
        &run,
        "document.querySelector('iframe.report') !== null",
        Duration::from_secs(20),
    );
    screenshot(&run, "run");
}

/// CPU time (user + system) of process `pid` so far.
fn cpu_time(pid: u32) -> Duration {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).expect("/proc stat");
    // Fields after the command name (which may hold spaces) are space-separated; utime and stime
    // are fields 14 and 15, in clock ticks.
    let after = &stat[stat.rfind(')').expect("comm") + 2..];
    let fields: Vec<&str> = after.split(' ').collect();
    let ticks: u64 = fields[11].parse::<u64>().unwrap() + fields[12].parse::<u64>().unwrap();
    let output = std::process::Command::new("getconf")
        .arg("CLK_TCK")
        .output()
        .expect("getconf");
    let per_second: u64 = String::from_utf8_lossy(&output.stdout)
        .trim()
        .parse()
        .unwrap_or(100);
    Duration::from_secs_f64(ticks as f64 / per_second as f64)
}

/// A line of 100 devices behind a master, every device's DCF giving a 100 ms heartbeat.
fn hundred_devices(dir: &Path) -> PathBuf {
    std::fs::copy(network_fixture("dcf/node1.dcf"), dir.join("hb.dcf")).expect("copy the DCF");
    let mut nodes = String::from(
        r#"<node id="m"><data key="NodeName">Master</data><data key="NodeType">master</data><data key="NetNumberN1">1</data><data key="NodeIDN1">127</data><data key="NodeDCFNameN1">hb.dcf</data></node>"#,
    );
    let mut edges = String::new();
    for n in 1..=100 {
        nodes.push_str(&format!(
            r#"<node id="d{n}"><data key="NodeName">D{n}</data><data key="NetNumberN1">1</data><data key="NodeIDN1">{n}</data><data key="NodeDCFNameN1">hb.dcf</data></node>"#
        ));
        let from = if n == 1 {
            "m".to_owned()
        } else {
            format!("d{}", n - 1)
        };
        edges.push_str(&format!(
            r#"<edge source="{from}" target="d{n}"><data key="NetNumber">1</data><data key="CableName">W{n}</data></edge>"#
        ));
    }
    let keys: String = [
        ("NodeName", "node", "string"),
        ("NodeType", "node", "string"),
        ("NetNumberN1", "node", "long"),
        ("NodeIDN1", "node", "int"),
        ("NodeDCFNameN1", "node", "string"),
        ("NetNumber", "edge", "long"),
        ("CableName", "edge", "string"),
    ]
    .iter()
    .map(|(k, f, t)| format!(r#"<key id="{k}" for="{f}" attr.name="{k}" attr.type="{t}"/>"#))
    .collect();
    let path = dir.join("hundred.graphml");
    std::fs::write(
        &path,
        format!(
            r#"<?xml version="1.0" encoding="UTF-8"?><graphml xmlns="http://graphml.graphdrawing.org/xmlns">{keys}<graph id="g" edgedefault="undirected">{nodes}{edges}</graph></graphml>"#
        ),
    )
    .unwrap();
    path
}

#[test]
fn a_hundred_devices_changing_state_at_10_hz_reach_the_page_without_loss() {
    let dir = temp_dir("web-load");
    let Some(browser) = browser(&dir) else { return };
    let hub = HubProc::start();
    let can0 = hub.spec("can0");
    let file = hundred_devices(&dir);
    let server = Server::start(
        "serve",
        &["serve", "--nodelist", file.to_str().unwrap(), "--bus", &can0],
    );
    let tab = open(&browser, &server.url("/"));
    assert_eq!(
        js(&tab, "document.querySelectorAll('.state').length"),
        json!(101),
        "100 devices and the master"
    );
    wait_until(&tab, "canopener.monitor.ready", Duration::from_secs(20));
    // Unheard devices fall silent 150 ms after the start; let that and its diagnosis settle.
    std::thread::sleep(Duration::from_millis(1500));
    let mut bus = canopener_transport::open(&can0.parse().unwrap()).expect("open the hub");
    let before_events = server.get_json("/api/state")["seq"].as_u64().unwrap();
    let before_page = js(&tab, "canopener.monitor.received").as_u64().unwrap();
    let before_cpu = cpu_time(server.process.id());
    // 5 s: every device sends a heartbeat every 100 ms, each in the other state than the last.
    let start = Instant::now();
    for tick in 0..50u32 {
        for node in 1..=100u16 {
            let state = if (u32::from(node) + tick) % 2 == 0 {
                0x05
            } else {
                0x7F
            };
            let frame =
                canopener_can::CanFrame::new(canopener_can::StandardId::new(0x700 + node).unwrap(), &[state])
                    .unwrap();
            bus.send(&frame).expect("send a heartbeat");
        }
        let next = start + Duration::from_millis(100) * (tick + 1);
        std::thread::sleep(next.saturating_duration_since(Instant::now()));
    }
    // Then silence: every device times out; wait until the monitor has said so and settled.
    std::thread::sleep(Duration::from_millis(1500));
    let after_cpu = cpu_time(server.process.id());
    let after_events = server.get_json("/api/state")["seq"].as_u64().unwrap();
    wait_until(
        &tab,
        &format!("canopener.monitor.lastSeq === {after_events}"),
        Duration::from_secs(30),
    );
    let received = js(&tab, "canopener.monitor.received").as_u64().unwrap() - before_page;
    let sent = after_events - before_events;
    let cpu = after_cpu - before_cpu;
    eprintln!(
        "load: 100 devices at 10 Hz for 5 s: {sent} events sent, {received} received by the page, {} gaps; \
         server CPU {cpu:?} = {:.1} ms per 1000 events",
        js(&tab, "canopener.monitor.gaps"),
        cpu.as_secs_f64() * 1000.0 / (sent as f64 / 1000.0)
    );
    assert!(sent >= 4500, "{sent} events: the states did not change at 10 Hz");
    assert_eq!(received, sent, "no event lost");
    assert_eq!(js(&tab, "canopener.monitor.gaps"), json!(0));
    screenshot(&tab, "monitor-hundred");
}

//! The pages, rendered on the server from data (the scripts in `assets/` keep them live). Every text
//! goes through [`esc`]. The elements and attributes scripts and tests rely on are the page contract
//! of `docs/web.md`; the snapshot tests keep it from drifting.

use std::fmt::Write as _;

use canopener_conformance::catalogue::SUITES;
use canopener_conformance::render::html::{esc, measurement};
use canopener_device::faults::Fault;

use crate::compare::Comparison;
use crate::monitor::Watched;
use crate::runs::RunView;
use crate::store::{RunRow, StoredDescription};

/// Which page a layout shows as current.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tab {
    /// `/`.
    Monitor,
    /// `/check`.
    Check,
    /// `/test`.
    Test,
    /// `/history`.
    History,
}

/// The frame every page shares: head, navigation, `main`.
pub fn layout(tab: Tab, title: &str, body: &str, script: Option<&str>) -> String {
    let link = |t: Tab, href: &str, name: &str| {
        let current = if t == tab { r#" aria-current="page""# } else { "" };
        format!(r#"<a href="{href}"{current}>{name}</a>"#)
    };
    let script = script
        .map(|s| format!(r#"<script src="/assets/common.js"></script><script src="/assets/{s}"></script>"#))
        .unwrap_or_default();
    format!(
        r#"<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{} · canopener</title>
<link rel="stylesheet" href="/assets/style.css">
</head>
<body>
<header><span class="brand">canopener</span><nav>{}{}{}{}</nav></header>
<main>
{body}
</main>
{script}
</body>
</html>
"#,
        esc(title),
        link(Tab::Monitor, "/", "Monitor"),
        link(Tab::Check, "/check", "Check"),
        link(Tab::Test, "/test", "Test"),
        link(Tab::History, "/history", "History"),
    )
}

/// `/`: the drawing, the diagnosis panel and the event log. The script fills in the states.
pub fn monitor(watched: Option<&Watched>) -> String {
    let Some(watched) = watched else {
        let body = r#"<section class="empty"><h1>System monitor</h1>
<p>No system is watched: start the server with <code>canopener serve --nodelist Nodelist.graphml --bus SPEC</code>
(one <code>--bus N=SPEC</code> per network), or try <code>canopener demo --serve</code>.</p>
<p>Device descriptions can be checked under <a href="/check">Check</a>, devices tested under <a href="/test">Test</a>.</p></section>"#;
        return layout(Tab::Monitor, "System monitor", body, None);
    };
    let topology = watched.system.topology();
    let mut networks = String::new();
    for (net, bus) in &watched.buses {
        let name = topology
            .network_name(*net)
            .map(|n| format!(" {}", esc(n)))
            .unwrap_or_default();
        let _ = write!(
            networks,
            r#"<li data-network="{net}"><span class="swatch" style="background:{}"></span>network {net}{name} on <code>{}</code></li>"#,
            canopener_network::draw::network_colour(*net),
            esc(bus)
        );
    }
    let legend: String = [
        "boot-up",
        "pre-operational",
        "operational",
        "stopped",
        "silent",
        "unknown",
    ]
    .iter()
    .map(|s| format!(r#"<li><span class="dot" data-state="{s}"></span>{s}</li>"#))
    .collect();
    let body = format!(
        r#"<div class="monitor">
<section class="drawing" aria-label="system drawing">
{svg}</section>
<aside>
<section class="system"><h1>{file}</h1>
<p id="connection" data-connection="connecting">connecting…</p>
<ul class="networks">{networks}</ul>
<ul class="legend">{legend}</ul></section>
<section class="diagnosis"><h2>Diagnosis</h2>
<p id="all-heard" hidden>Every device is heard.</p>
<ul id="explanations"></ul></section>
<section class="log"><h2>Events</h2><ol id="events" reversed></ol></section>
</aside>
</div>"#,
        svg = watched.svg,
        file = esc(&watched.file),
    );
    layout(Tab::Monitor, "System monitor", &body, Some("monitor.js"))
}

/// `/check`: the drop zone; the script shows the findings.
pub fn check(cap: usize) -> String {
    let body = format!(
        r#"<h1>Check a device description</h1>
<div id="drop" class="drop" tabindex="0">
<p>Drop an EDS, DCF, XDD or XDC file here, or <label class="button">choose one<input id="file" type="file" accept=".eds,.dcf,.xdd,.xdc,.xpd" hidden></label>.</p>
<p class="hint">Checked as <code>canopener eds check --format json</code> checks it; up to {cap}; nothing is stored unless the server has <code>--data</code>.</p>
</div>
<p id="refusal" class="refusal" role="alert" hidden></p>
<section id="result" hidden>
<h2 id="checked-name"></h2>
<p id="summary"></p>
<div class="filters"><fieldset id="severities"><legend>Severity</legend>
<label><input type="checkbox" value="error" checked> errors</label>
<label><input type="checkbox" value="warning" checked> warnings</label>
<label><input type="checkbox" value="info" checked> notes</label></fieldset>
<label>Code <select id="code"><option value="">all codes</option></select></label></div>
<ol id="findings" class="findings"></ol>
<section id="fixes"><h2>Safe fixes</h2><p id="fix-summary"></p><ul id="fix-list"></ul>
<pre id="diff" class="diff"></pre>
<button id="download" type="button" hidden>Download the fixed file</button></section>
</section>"#,
        cap = crate::upload::size_words(cap)
    );
    layout(Tab::Check, "Check", &body, Some("check.js"))
}

/// `/test`: the form, the runs running now and the live view of the one started or chosen.
pub fn test(buses: &[(u32, String)], descriptions: &[StoredDescription], running: &[RunView]) -> String {
    let mut bus_options =
        String::from(r#"<option value="simulated">simulated device (no hardware; virtual time)</option>"#);
    for (index, (net, spec)) in buses.iter().enumerate() {
        let _ = write!(
            bus_options,
            r#"<option value="{index}">network {net}: {}</option>"#,
            esc(spec)
        );
    }
    let mut eds_options =
        String::from(r#"<option value="bundled">cia401_full_io.eds (bundled CiA 401 device)</option>"#);
    for d in descriptions {
        let _ = write!(
            eds_options,
            r#"<option value="{}">{} ({}…)</option>"#,
            esc(&d.sha256),
            esc(&d.name),
            esc(&d.sha256[..8.min(d.sha256.len())])
        );
    }
    let suites: String = SUITES
        .iter()
        .map(|s| {
            let checked = if *s == "cia301" { " checked" } else { "" };
            format!(r#"<label><input type="checkbox" name="suite" value="{s}"{checked}> {s}</label>"#)
        })
        .collect();
    let faults: String = Fault::ALL
        .iter()
        .map(|f| {
            format!(
                r#"<option value="{0}" title="{1}">{0}</option>"#,
                f.name(),
                esc(f.description())
            )
        })
        .collect();
    let running_rows: String = running
        .iter()
        .map(|r| {
            format!(
                r#"<li data-run="{0}"><a href="/runs/{0}">run {0}</a>: node {1} on {2}</li>"#,
                r.id,
                r.node,
                esc(&r.bus)
            )
        })
        .collect();
    let body = format!(
        r#"<h1>Run conformance tests</h1>
<form id="start" class="start">
<label>Bus <select id="bus" name="bus">{bus_options}</select></label>
<label>Node <input id="node" name="node" type="number" min="1" max="127" value="5" required></label>
<label>Description <select id="eds" name="eds">{eds_options}</select></label>
<label>or upload <input id="upload" type="file" accept=".eds,.dcf,.xdd,.xdc,.xpd"></label>
<fieldset class="suites"><legend>Suites</legend>{suites}</fieldset>
<label id="fault-label">Fault of the simulated device <select id="fault" name="fault"><option value="">none</option>{faults}</select></label>
<button type="submit">Start</button>
</form>
<p id="refusal" class="refusal" role="alert" hidden></p>
<section><h2>Running now</h2><ul id="running">{running_rows}</ul></section>
<section id="run" class="run" hidden></section>"#
    );
    layout(Tab::Test, "Test", &body, Some("test.js"))
}

/// `/runs/ID`: one run, live while it runs, with its report at the end.
pub fn run(view: &RunView, previous: Option<i64>) -> String {
    let compare = previous
        .map(|p| {
            format!(
                r#" · <a class="compare" href="/compare?a={p}&amp;b={}">compare with run {p}</a>"#,
                view.id
            )
        })
        .unwrap_or_default();
    let body = format!(
        r#"<h1>Run {id}</h1>
<section id="run" class="run" data-run="{id}"></section>
<p class="links"><a href="/history">history</a>{compare}</p>"#,
        id = view.id
    );
    layout(Tab::Test, &format!("Run {}", view.id), &body, Some("test.js"))
}

/// `/history`: every run by device, newest first.
pub fn history(rows: &[RunRow], kept: &str) -> String {
    let mut body = format!("<h1>Run history</h1>\n<p class=\"hint\">{}</p>\n", esc(kept));
    if rows.is_empty() {
        body.push_str("<p>No runs yet: start one under <a href=\"/test\">Test</a>.</p>");
    }
    let mut device: Option<&str> = None;
    for (i, row) in rows.iter().enumerate() {
        if device != Some(row.device.as_str()) {
            if device.is_some() {
                body.push_str("</tbody></table></section>\n");
            }
            device = Some(&row.device);
            let _ = write!(
                body,
                r#"<section class="device" data-device="{0}"><h2>{0}</h2><table class="runs"><thead><tr><th>run</th><th>started</th><th>revision</th><th>node</th><th>bus</th><th>description</th><th>fault</th><th>status</th><th>pass</th><th>measured, no criterion</th><th>fail</th><th>inconcl.</th><th>n/a</th><th></th></tr></thead><tbody>"#,
                esc(&row.device)
            );
        }
        // The next row of the same device is the run before this one.
        let previous = rows
            .get(i + 1)
            .filter(|p| p.device == row.device)
            .map(|p| {
                format!(
                    r#"<a href="/compare?a={}&amp;b={}">compare with run {}</a>"#,
                    p.id, row.id, p.id
                )
            })
            .unwrap_or_default();
        let _ = write!(
            body,
            r#"<tr data-run="{id}" data-status="{status}"><td><a href="/runs/{id}">{id}</a></td><td>{started}</td><td>{revision}</td><td>{node}</td><td>{bus}</td><td>{eds}</td><td>{fault}</td><td class="status">{status}</td><td class="n">{pass}</td><td class="n">{measured}</td><td class="n">{fail}</td><td class="n">{inconclusive}</td><td class="n">{na}</td><td>{previous}</td></tr>"#,
            id = row.id,
            status = esc(&row.status),
            started = esc(&row.started),
            revision = esc(row.revision.as_deref().unwrap_or("")),
            node = row.node,
            bus = esc(&row.bus),
            eds = esc(&row.eds),
            fault = esc(row.fault.as_deref().unwrap_or("")),
            pass = row.pass,
            measured = row.measured,
            fail = row.fail,
            inconclusive = row.inconclusive,
            na = row.not_applicable,
        );
    }
    if device.is_some() {
        body.push_str("</tbody></table></section>\n");
    }
    layout(Tab::History, "History", &body, None)
}

/// `/compare?a=&b=`: what changed from run `a` to run `b`.
pub fn comparison(a: &RunRow, b: &RunRow, comparison: &Comparison) -> String {
    let run_line = |r: &RunRow| {
        format!(
            "run {} of {} ({}), revision {}, {} passed, {} failed",
            r.id,
            esc(&r.started),
            esc(&r.device),
            esc(r.revision.as_deref().unwrap_or("unknown")),
            r.pass,
            r.fail
        )
    };
    let mut body = format!(
        r#"<link rel="stylesheet" href="/assets/report.css">
<h1>What changed from run {} to run {}</h1>
<ul class="runs-compared"><li>before: <a href="/runs/{}">{}</a></li><li>after: <a href="/runs/{}">{}</a></li></ul>
<section class="changed"><h2>Changed verdicts</h2>"#,
        a.id,
        b.id,
        a.id,
        run_line(a),
        b.id,
        run_line(b)
    );
    if comparison.verdicts.is_empty() {
        let _ = write!(
            body,
            "<p id=\"no-change\">No verdict changed ({} tests the same).</p>",
            comparison.unchanged
        );
    } else {
        let _ = write!(
            body,
            "<p>{} changed, {} the same.</p><table class=\"verdicts\"><thead><tr><th>test</th><th>title</th><th>before</th><th>after</th><th>why (after)</th></tr></thead><tbody>",
            comparison.verdicts.len(),
            comparison.unchanged
        );
        for v in &comparison.verdicts {
            let word = |w: &Option<String>| w.as_deref().unwrap_or("not run").to_owned();
            let _ = write!(
                body,
                r#"<tr class="changed-verdict" data-test="{id}" data-before="{b}" data-after="{a}"><td class="mono">{id}</td><td>{title}</td><td><span class="verdict {b}">{b}</span></td><td><span class="verdict {a}">{a}</span></td><td>{reason}</td></tr>"#,
                id = esc(&v.id),
                title = esc(&v.title),
                b = esc(&word(&v.before)),
                a = esc(&word(&v.after)),
                reason = esc(&v.reason)
            );
        }
        body.push_str("</tbody></table>");
    }
    body.push_str("</section>\n<section class=\"moved\"><h2>Measurements that moved</h2>");
    if comparison.moved.is_empty() {
        body.push_str(
            "<p id=\"none-moved\">No measurement moved (median within 5 %, same side of its limits).</p>",
        );
    }
    for m in &comparison.moved {
        let (before, after) = m.medians();
        let median = |v: Option<f64>| v.map_or("–".to_owned(), |v| format!("{v:.3}"));
        let _ = write!(
            body,
            r#"<article class="moved-measurement" data-test="{test}" data-name="{name}"><h3><span class="mono">{test}</span> {name}: median {b} → {a} {unit}</h3><div class="side-by-side"><div><h4>run {ra}</h4>{plot_b}</div><div><h4>run {rb}</h4>{plot_a}</div></div></article>"#,
            test = esc(&m.test),
            name = esc(&m.name),
            b = median(before),
            a = median(after),
            unit = esc(&m.after.unit),
            ra = a.id,
            rb = b.id,
            plot_b = measurement(&m.name, &m.before),
            plot_a = measurement(&m.name, &m.after),
        );
    }
    body.push_str("</section>");
    layout(
        Tab::History,
        &format!("Run {} against run {}", a.id, b.id),
        &body,
        None,
    )
}

/// A page that says what is wrong, with the status the server answers with.
pub fn problem(title: &str, message: &str) -> String {
    let body = format!("<h1>{}</h1><p class=\"refusal\">{}</p>", esc(title), esc(message));
    layout(Tab::Monitor, title, &body, None)
}

#[cfg(test)]
mod tests {
    use canopener_conformance::model::Measurement;

    use super::*;
    use crate::compare::{Moved, VerdictChange};

    fn row(id: i64, device: &str, fault: Option<&str>, fail: i64) -> RunRow {
        RunRow {
            id,
            started: format!("2026-01-0{id}T10:00:00Z"),
            status: "done".to_owned(),
            message: None,
            node: 5,
            bus: "simulated".to_owned(),
            eds: "io.eds".to_owned(),
            device: device.to_owned(),
            revision: Some("0x00010002".to_owned()),
            fault: fault.map(str::to_owned),
            suites: "cia301".to_owned(),
            pass: 70 - fail,
            measured: 2,
            fail,
            inconclusive: 0,
            not_applicable: 6,
        }
    }

    #[test]
    fn the_monitor_page_carries_the_contract_on_the_drawing() {
        let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../canopener-network/test_data/gateway.graphml");
        let system = crate::backend::System::read(&file).unwrap();
        let watched = Watched::new(
            system,
            None,
            vec![
                (1, "socketcand://127.0.0.1:29536/can0".to_owned()),
                (2, "socketcan:can1".to_owned()),
            ],
            "gateway.graphml".to_owned(),
        );
        let page = monitor(Some(&watched));
        assert!(page.contains(r#"data-device="Boom2" data-network="2" data-state="unknown""#));
        assert!(page.contains(r#"data-cable="B2""#));
        insta::assert_snapshot!("monitor", page);
        insta::assert_snapshot!("monitor_without_system", monitor(None));
    }

    #[test]
    fn the_check_test_and_run_pages() {
        insta::assert_snapshot!("check", check(crate::upload::DEFAULT_CAP));
        let descriptions = [StoredDescription {
            sha256: "ab".repeat(32),
            name: "motor.eds".to_owned(),
        }];
        let buses = [(1, "socketcan:can0".to_owned())];
        insta::assert_snapshot!("test", test(&buses, &descriptions, &[]));
        let view = RunView {
            id: 3,
            status: "done".to_owned(),
            message: None,
            node: 5,
            bus: "simulated".to_owned(),
            eds: "io.eds".to_owned(),
            started: "2026-01-03T10:00:00Z".to_owned(),
            total: 0,
            done: 0,
            current: None,
            verdicts: Vec::new(),
        };
        insta::assert_snapshot!("run", run(&view, Some(2)));
    }

    #[test]
    fn the_history_groups_runs_by_device_and_offers_the_comparison_with_the_run_before() {
        let rows = [
            row(2, "Motor (ACME)", Some("heartbeat-jitter"), 1),
            row(1, "Motor (ACME)", None, 0),
            row(3, "Valve", None, 0),
        ];
        let page = history(&rows, "Runs are kept in data/canopener.sqlite.");
        assert!(page.contains(r#"href="/compare?a=1&amp;b=2""#));
        insta::assert_snapshot!("history", page);
    }

    #[test]
    fn the_comparison_shows_changed_verdicts_and_both_plots_of_a_moved_measurement() {
        let comparison = Comparison {
            verdicts: vec![VerdictChange {
                id: "cia301.ec.1".to_owned(),
                title: "Heartbeat producer".to_owned(),
                before: Some("pass".to_owned()),
                after: Some("fail".to_owned()),
                reason: "an interval of 140 ms".to_owned(),
            }],
            moved: vec![Moved {
                test: "cia301.ec.1".to_owned(),
                name: "heartbeat interval".to_owned(),
                before: Measurement::new("ms", vec![100.0, 100.0, 100.0]),
                after: Measurement::new("ms", vec![100.0, 140.0, 60.0, 140.0]),
            }],
            unchanged: 70,
        };
        let page = comparison_page(&comparison);
        assert_eq!(page.matches("<figure class=\"measurement\"").count(), 2);
        insta::assert_snapshot!("comparison", page);
    }

    fn comparison_page(c: &Comparison) -> String {
        comparison(
            &row(1, "Motor", None, 0),
            &row(2, "Motor", Some("heartbeat-jitter"), 1),
            c,
        )
    }
}

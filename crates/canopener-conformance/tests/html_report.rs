//! The HTML report of real runs against simulated devices on virtual time, rendered by headless
//! Chromium: every test is a collapsible `<details>` with a collapsible telegram log, every test with
//! measurements has exactly one histogram and one time series per measurement, and the failure of a
//! device with a jittering heartbeat is open with its limits drawn. Screenshots are left in
//! `CARGO_TARGET_TMPDIR` for people to look at.

use canopener_conformance::model::{Report, Verdict, VerdictCounts};
use canopener_conformance::render::html;
use canopener_conformance::tour;
use canopener_device::faults::Fault;
use canopener_testkit::browser::{self, png_size, tags};
use canopener_testkit::fixture::{self, ScratchDir};

/// A run of every suite against the demo's device (`test_data/cia401_full_io.eds`, so every suite
/// applies) with `faults`, as `canopener demo` runs it.
fn run(faults: &[Fault]) -> Report {
    tour::run(faults, "2024-01-01T00:00:00Z", None, |_| {})
        .expect("the demo device runs")
        .report
}

/// The dumped DOM cut into one piece per test `<details>` (tests are not nested, so each piece
/// runs from one test's opening tag to the next).
fn test_pieces(dom: &str) -> Vec<&str> {
    let marker = "<details class=\"test\"";
    let mut starts: Vec<usize> = dom.match_indices(marker).map(|(at, _)| at).collect();
    starts.push(dom.len());
    starts.windows(2).map(|w| &dom[w[0]..w[1]]).collect()
}

fn attribute<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let start = tag.find(&key)? + key.len();
    Some(&tag[start..start + tag[start..].find('"')?])
}

/// Checks the page Chromium parsed against the report it was rendered from.
fn check_dom(dom: &str, report: &Report) {
    let pieces = test_pieces(dom);
    assert_eq!(pieces.len(), report.tests.len(), "one <details> per test");
    let mut plotted = 0;
    for (piece, test) in pieces.iter().zip(&report.tests) {
        let open = tags(piece, "details")[0];
        assert_eq!(attribute(open, "id"), Some(html::anchor(&test.id).as_str()));
        assert_eq!(attribute(open, "data-verdict"), Some(test.verdict.as_str()));
        assert_eq!(
            open.contains(" open="),
            matches!(test.verdict, Verdict::Fail | Verdict::Inconclusive),
            "{}: failures are open, the rest closed",
            test.id
        );
        let logs: Vec<_> = tags(piece, "details")
            .into_iter()
            .filter(|t| t.contains("class=\"log\""))
            .collect();
        assert_eq!(logs.len(), 1, "{}: one collapsible log", test.id);
        assert!(!logs[0].contains(" open"), "{}: logs start closed", test.id);
        let plots = tags(piece, "svg");
        let histograms = plots.iter().filter(|t| t.contains("plot histogram")).count();
        let series = plots.iter().filter(|t| t.contains("plot series")).count();
        assert_eq!(
            (histograms, series),
            (test.measurements.len(), test.measurements.len()),
            "{}: one plot pair per measurement",
            test.id
        );
        if !test.measurements.is_empty() {
            plotted += 1;
        }
    }
    assert!(plotted > 0, "the run measured something");
}

fn shoot(chromium: &std::path::Path, dir: &ScratchDir, url: &str, name: &str, size: (u32, u32)) {
    let shot = dir.join(name);
    browser::run(
        chromium,
        &dir.join("profile"),
        url,
        &[
            &format!("--screenshot={}", shot.display()),
            &format!("--window-size={},{}", size.0, size.1),
        ],
    );
    let bytes = fixture::read(&shot).expect("chromium wrote the screenshot");
    assert_eq!(png_size(&bytes), size);
    // A blank page of this size compresses to a few kilobytes; a rendered report does not.
    assert!(bytes.len() > 20_000, "{name} is only {} bytes", bytes.len());
    fixture::write(
        std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(name),
        &bytes,
    )
    .expect("keep the screenshot");
}

#[test]
fn reports_of_a_clean_and_a_faulty_device_render_in_chromium() {
    let clean = run(&[]);
    let faulty = run(&[Fault::HeartbeatJitter]);
    let failed: Vec<_> = faulty
        .tests
        .iter()
        .filter(|t| t.verdict == Verdict::Fail)
        .collect();
    assert!(!failed.is_empty(), "the jittering heartbeat is caught");
    let drawn = failed
        .iter()
        .find(|t| t.measurements.values().any(|m| m.limits.is_some()))
        .unwrap_or_else(|| {
            panic!(
                "a failure with limits to draw: {:?}",
                failed.iter().map(|t| &t.id).collect::<Vec<_>>()
            )
        });
    let Some(chromium) = browser::chromium() else {
        return;
    };
    let dir = ScratchDir::new("conformance-html");
    for (name, report) in [("clean", &clean), ("faulty", &faulty)] {
        let page = dir.write(format!("{name}.html"), html::render(report));
        let url = format!("file://{}", page.display());
        let dom = browser::run(chromium, &dir.join("profile"), &url, &["--dump-dom"]);
        assert!(
            dom.contains("id=\"summary\""),
            "{name}: the page did not load:\n{dom:.2000}"
        );
        check_dom(&dom, report);
        shoot(
            chromium,
            &dir,
            &url,
            &format!("conformance-{name}.png"),
            (1280, 900),
        );
    }
    // The failure with its plots and limits. (Headless Chromium paints a blank viewport when it scrolls to
    // a fragment far down a long page, so the failing test gets a page of its own.)
    let mut alone = faulty.clone();
    alone.tests.retain(|t| t.id == drawn.id);
    alone.summary = VerdictCounts::of(&alone.tests);
    let page = dir.write("failure.html", html::render(&alone));
    let url = format!("file://{}", page.display());
    shoot(chromium, &dir, &url, "conformance-failure.png", (1280, 1600));
    shoot(chromium, &dir, &url, "conformance-failure-phone.png", (390, 1600));
}

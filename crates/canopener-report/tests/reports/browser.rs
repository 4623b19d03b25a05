//! The HTML report rendered by headless Chromium (Debian's `chromium` package): filters applied
//! from the URL hash, explanation anchors, and a screenshot written to `target/`.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use canopener_report::html;

use crate::fixture::report;

const CHROMIUM: &str = "/usr/bin/chromium";
const SKIP_VAR: &str = "CANOPENER_SKIP_BROWSER_TESTS";

/// The browser, or `None` when the tests are skipped on purpose. Fails when it is missing otherwise.
fn chromium() -> Option<&'static Path> {
    if std::env::var(SKIP_VAR).is_ok_and(|v| v == "1") {
        eprintln!("skipped: {SKIP_VAR}=1");
        return None;
    }
    let path = Path::new(CHROMIUM);
    assert!(
        path.exists(),
        "{CHROMIUM} not found: install Debian's chromium package (`apt-get install -y chromium`), \
         or set {SKIP_VAR}=1 to skip the browser tests"
    );
    Some(path)
}

/// A fresh directory under the system temp dir, removed on drop.
struct TempDir(PathBuf);

impl TempDir {
    fn new(tag: &str) -> Self {
        let nanos = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos());
        let dir = std::env::temp_dir().join(format!("canopener-report-{tag}-{}-{nanos}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("create the temp dir");
        Self(dir)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Runs Chromium headless on `url` with `extra` arguments and returns its stdout.
fn run_chromium(browser: &Path, profile: &Path, url: &str, extra: &[&str]) -> String {
    let mut child = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--hide-scrollbars",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg("--virtual-time-budget=2000")
        .args(extra)
        .arg(url)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start chromium");
    let started = Instant::now();
    loop {
        match child.try_wait().expect("wait for chromium") {
            Some(_) => break,
            None if started.elapsed() > Duration::from_secs(120) => {
                let _ = child.kill();
                panic!("chromium did not finish within 120 s");
            }
            None => std::thread::sleep(Duration::from_millis(50)),
        }
    }
    let output = child.wait_with_output().expect("chromium output");
    assert!(
        output.status.success(),
        "chromium failed: {}\n{}",
        output.status,
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// The page written into `dir`, as a file URL.
fn write_page(dir: &Path) -> String {
    let page = dir.join("report.html");
    std::fs::write(&page, html(&report())).expect("write the page");
    format!("file://{}", page.display())
}

/// Every opening tag `<tag ...>` of the dumped DOM.
fn tags<'a>(dom: &'a str, tag: &str) -> Vec<&'a str> {
    let open = format!("<{tag} ");
    let mut found = Vec::new();
    let mut rest = dom;
    while let Some(at) = rest.find(&open) {
        rest = &rest[at..];
        let end = rest.find('>').map_or(rest.len(), |e| e + 1);
        found.push(&rest[..end]);
        rest = &rest[end..];
    }
    found
}

/// The text of the element with this id (up to the next tag).
fn text_of<'a>(dom: &'a str, id: &str) -> &'a str {
    let marker = format!("id=\"{id}\">");
    let start = dom
        .find(&marker)
        .map(|at| at + marker.len())
        .unwrap_or_else(|| panic!("no #{id}"));
    let rest = &dom[start..];
    &rest[..rest.find('<').unwrap_or(rest.len())]
}

fn is_hidden(tag: &str) -> bool {
    tag.contains(" hidden=\"\"") || tag.contains(" hidden>") || tag.ends_with(" hidden")
}

#[test]
fn filters_from_the_hash_and_anchors_work_in_chromium() {
    let Some(browser) = chromium() else { return };
    let dir = TempDir::new("dom");
    let url = write_page(&dir.0);
    let profile = dir.0.join("profile");

    let dom = run_chromium(
        browser,
        &profile,
        &format!("{url}#severity=error"),
        &["--dump-dom"],
    );
    assert!(
        dom.contains("data-ready=\"true\""),
        "the script did not run:\n{dom}"
    );
    assert_eq!(text_of(&dom, "count-errors"), "3");
    assert_eq!(text_of(&dom, "count-warnings"), "3");
    assert_eq!(text_of(&dom, "count-infos"), "2");
    assert_eq!(text_of(&dom, "count-files"), "4");
    assert_eq!(text_of(&dom, "count-problems"), "1");
    assert_eq!(text_of(&dom, "shown-count"), "3", "three errors are shown");
    let findings = tags(&dom, "article");
    assert_eq!(findings.len(), 8);
    for tag in &findings {
        let error = tag.contains("data-severity=\"error\"");
        assert_eq!(is_hidden(tag), !error, "only errors are shown: {tag}");
    }
    let form = tags(&dom, "form").into_iter().next().expect("the filter form");
    assert!(!is_hidden(form), "the script shows the filters: {form}");
    for code in ["C301", "C412", "T004", "naming.no-blanks", "P020"] {
        assert!(
            dom.contains(&format!("id=\"check-{code}\"")),
            "explanation anchor for {code}"
        );
        assert!(dom.contains(&format!("href=\"#check-{code}\"")), "link to {code}");
    }

    let dom = run_chromium(
        browser,
        &profile,
        &format!("{url}#severity=error,warning&code=naming.no-blanks"),
        &["--dump-dom"],
    );
    assert_eq!(text_of(&dom, "shown-count"), "1");
    for tag in tags(&dom, "article") {
        assert_eq!(
            is_hidden(tag),
            !tag.contains("data-code=\"naming.no-blanks\""),
            "{tag}"
        );
    }
    // The sections of files without a shown finding are hidden; the unreadable file too (code filter).
    let files = tags(&dom, "section")
        .into_iter()
        .filter(|t| t.contains("class=\"file\""))
        .collect::<Vec<_>>();
    assert_eq!(files.iter().filter(|t| !is_hidden(t)).count(), 1, "{files:?}");

    let dom = run_chromium(browser, &profile, &format!("{url}#check-C301"), &["--dump-dom"]);
    let details = tags(&dom, "details")
        .into_iter()
        .find(|t| t.contains("id=\"check-C301\""))
        .expect("C301");
    assert!(
        details.contains(" open"),
        "the linked explanation is opened: {details}"
    );
    assert_eq!(text_of(&dom, "shown-count"), "8", "an anchor is not a filter");
}

/// Checks the PNG signature and returns (width, height) from its IHDR chunk.
fn png_size(bytes: &[u8]) -> (u32, u32) {
    assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"), "not a PNG");
    let word = |at: usize| {
        let b: [u8; 4] = bytes
            .get(at..at + 4)
            .and_then(|s| s.try_into().ok())
            .expect("IHDR");
        u32::from_be_bytes(b)
    };
    assert_eq!(bytes.get(12..16), Some(&b"IHDR"[..]));
    (word(16), word(20))
}

#[test]
fn screenshot_is_rendered() {
    let Some(browser) = chromium() else { return };
    let dir = TempDir::new("shot");
    let url = write_page(&dir.0);
    let profile = dir.0.join("profile");
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target"));
    std::fs::create_dir_all(&target).expect("target dir");
    for (size, name) in [
        ("1280,900", "report-screenshot.png"),
        ("390,844", "report-screenshot-phone.png"),
    ] {
        let shot = dir.0.join(name);
        run_chromium(
            browser,
            &profile,
            &url,
            &[
                &format!("--screenshot={}", shot.display()),
                &format!("--window-size={size}"),
            ],
        );
        let bytes = std::fs::read(&shot).expect("chromium wrote the screenshot");
        let (width, height) = png_size(&bytes);
        let expected: Vec<u32> = size.split(',').filter_map(|n| n.parse().ok()).collect();
        assert_eq!(vec![width, height], expected);
        // A blank page of this size compresses to a few kilobytes; a rendered report does not.
        assert!(
            bytes.len() > 20_000,
            "screenshot {name} is only {} bytes",
            bytes.len()
        );
        std::fs::write(target.join(name), &bytes).expect("copy the screenshot to target/");
    }
}

//! The HTML report rendered by headless Chromium (Debian's `chromium` package): filters applied
//! from the URL hash, explanation anchors, and a screenshot written to `target/`.

use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

use canopener_report::html;
use canopener_testkit::browser::{chromium, png_size, run as run_chromium, tags};

use crate::fixture::report;

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

/// The page written into `dir`, as a file URL.
fn write_page(dir: &Path) -> String {
    let page = dir.join("report.html");
    std::fs::write(&page, html(&report())).expect("write the page");
    format!("file://{}", page.display())
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

//! Headless Chromium (Debian's `chromium` package) for the tests of HTML pages: find the browser or skip
//! on purpose (`CANOPENER_SKIP_BROWSER_TESTS=1`), dump a page's DOM after its scripts ran, take a
//! screenshot, and pick elements out of the dumped DOM.

use std::io::Read;
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

/// Where the tests expect the browser (`cargo xtask setup` installs it there).
pub const CHROMIUM: &str = "/usr/bin/chromium";
/// Set to `1` to skip the browser tests knowingly.
pub const SKIP_VAR: &str = "CANOPENER_SKIP_BROWSER_TESTS";
/// How long one browser run may take before the test calls it hung (a loaded 2-core machine
/// starts Chromium in a few seconds).
pub const RUN_LIMIT: Duration = Duration::from_secs(120);

/// The browser, or `None` when the tests are skipped on purpose.
///
/// # Panics
/// When the browser is missing and the tests were not skipped on purpose: a missing browser must not
/// turn the tests green.
pub fn chromium() -> Option<&'static Path> {
    if std::env::var(SKIP_VAR).is_ok_and(|v| v == "1") {
        eprintln!("skipped: {SKIP_VAR}=1");
        return None;
    }
    let path = Path::new(CHROMIUM);
    assert!(
        path.exists(),
        "{CHROMIUM} not found: `cargo xtask setup` installs Debian's chromium package \
         (`apt-get install -y chromium`), or set {SKIP_VAR}=1 to skip the browser tests"
    );
    Some(path)
}

/// The flags every headless Chromium of the tests gets: no sandbox (root in CI), no GPU, and none of
/// the background connections this machine's closed network refuses.
pub const FLAGS: [&str; 8] = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
];

/// Headless Chromium under the DevTools protocol (`headless_chrome`), with [`FLAGS`], a fresh
/// profile in `profile` and a window of `width` × `height`; `None` when the browser tests are
/// skipped on purpose ([`chromium`]).
///
/// # Panics
/// When the browser is missing (see [`chromium`]) or does not start.
#[cfg(feature = "cdp")]
pub fn devtools(profile: &Path, width: u32, height: u32) -> Option<headless_chrome::Browser> {
    let path = chromium()?;
    let mut args: Vec<&std::ffi::OsStr> = FLAGS[1..].iter().map(std::ffi::OsStr::new).collect();
    args.push(std::ffi::OsStr::new("--hide-scrollbars"));
    let options = headless_chrome::LaunchOptions::default_builder()
        .path(Some(path.to_owned()))
        .headless(true)
        .sandbox(false)
        .window_size(Some((width, height)))
        .user_data_dir(Some(profile.to_owned()))
        .idle_browser_timeout(RUN_LIMIT * 5)
        .args(args)
        .build()
        .expect("chromium launch options");
    Some(headless_chrome::Browser::new(options).expect("start chromium under the DevTools protocol"))
}

/// Runs `browser` headless on `url` with a fresh profile in `profile` and the `extra` arguments
/// (`--dump-dom`, `--screenshot=FILE`, `--window-size=W,H`), and returns what it printed.
///
/// # Panics
/// When Chromium cannot start, fails, or runs longer than [`RUN_LIMIT`] (it is killed then).
pub fn run(browser: &Path, profile: &Path, url: &str, extra: &[&str]) -> String {
    let mut child = Command::new(browser)
        .args(FLAGS)
        .arg("--hide-scrollbars")
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg("--virtual-time-budget=2000")
        .args(extra)
        .arg(url)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start chromium");
    // A large DOM is more than a pipe holds: both streams are read while Chromium runs, and the end of
    // its stdout (it exits) is awaited with a deadline instead of a clock.
    let stderr = child.stderr.take().map(|mut err| {
        std::thread::spawn(move || {
            let mut text = String::new();
            let _ = err.read_to_string(&mut text);
            text
        })
    });
    let mut stdout = child.stdout.take().expect("chromium's stdout");
    let (done, finished) = mpsc::channel();
    std::thread::spawn(move || {
        let mut text = String::new();
        let _ = stdout.read_to_string(&mut text);
        let _ = done.send(text);
    });
    let Ok(dom) = finished.recv_timeout(RUN_LIMIT) else {
        let _ = child.kill();
        panic!("chromium did not finish within {RUN_LIMIT:?}");
    };
    let status = child.wait().expect("wait for chromium");
    let stderr = stderr.and_then(|t| t.join().ok()).unwrap_or_default();
    assert!(status.success(), "chromium failed: {status}\n{stderr}");
    dom
}

/// Every opening tag `<tag ...>` of a dumped DOM, attributes included.
pub fn tags<'a>(dom: &'a str, tag: &str) -> Vec<&'a str> {
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

/// The width and height of a PNG, from its IHDR chunk.
///
/// # Panics
/// When `bytes` are not a PNG.
pub fn png_size(bytes: &[u8]) -> (u32, u32) {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tags_are_found_with_their_attributes() {
        let dom =
            "<div><details class=\"a\" open=\"\"><summary>x</summary></details><details id=\"b\"></details>";
        assert_eq!(
            tags(dom, "details"),
            vec!["<details class=\"a\" open=\"\">", "<details id=\"b\">"]
        );
        assert!(tags(dom, "svg").is_empty());
    }

    #[test]
    fn png_sizes_come_from_the_header() {
        let mut png = b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR".to_vec();
        png.extend(640u32.to_be_bytes());
        png.extend(480u32.to_be_bytes());
        assert_eq!(png_size(&png), (640, 480));
    }
}

//! What the end-to-end tests of `canopener serve` share: the server as a child process on an
//! ephemeral port, headless Chromium under the DevTools protocol (`headless_chrome`), JavaScript
//! evaluated in a page with its result as JSON, waiting for a condition in the page, screenshots.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use headless_chrome::protocol::cdp::Page::CaptureScreenshotFormatOption;
use headless_chrome::{Browser, Tab};
use serde_json::Value;

use crate::support::{Proc, canopener};

/// `canopener ARGS --listen 127.0.0.1:0`, its address read from the first stdout line.
pub(crate) struct Server {
    pub(crate) process: Proc,
    /// `http://127.0.0.1:PORT` (no trailing slash).
    pub(crate) base: String,
}

impl Server {
    pub(crate) fn start(name: &str, args: &[&str]) -> Server {
        let mut command = canopener();
        command
            .args(args)
            .args(["--listen", "127.0.0.1:0"])
            .env_remove("CANOPENER_BUS");
        let mut process = Proc::spawn(name, command);
        let url = process.line(Duration::from_secs(60));
        assert!(url.starts_with("http://127.0.0.1:"), "{name} printed {url:?}");
        Server {
            process,
            base: url.trim_end_matches('/').to_owned(),
        }
    }

    pub(crate) fn url(&self, path: &str) -> String {
        format!("{}{path}", self.base)
    }

    /// A GET of `path` as JSON, through a plain socket (no browser).
    pub(crate) fn get_json(&self, path: &str) -> Value {
        let (status, body) = http(&self.base, "GET", path, &[], b"");
        assert_eq!(status, 200, "GET {path}: {body}");
        serde_json::from_str(&body).unwrap_or_else(|e| panic!("GET {path}: {e}: {body}"))
    }
}

/// One HTTP/1.1 request through a socket: the status and the body (the server closes after it).
pub(crate) fn http(
    base: &str,
    method: &str,
    path: &str,
    headers: &[(&str, &str)],
    body: &[u8],
) -> (u16, String) {
    use std::io::{Read, Write};
    let authority = base.trim_start_matches("http://");
    let mut stream = std::net::TcpStream::connect(authority).expect("connect to the server");
    stream
        .set_read_timeout(Some(Duration::from_secs(30)))
        .expect("timeout");
    let mut request = format!(
        "{method} {path} HTTP/1.1\r\nConnection: close\r\nContent-Length: {}\r\n",
        body.len()
    );
    if !headers.iter().any(|(name, _)| name.eq_ignore_ascii_case("host")) {
        request.push_str(&format!("Host: {authority}\r\n"));
    }
    for (name, value) in headers {
        request.push_str(&format!("{name}: {value}\r\n"));
    }
    request.push_str("\r\n");
    stream.write_all(request.as_bytes()).expect("send");
    stream.write_all(body).expect("send body");
    let mut answer = Vec::new();
    let _ = stream.read_to_end(&mut answer);
    let text = String::from_utf8_lossy(&answer).into_owned();
    let status = text
        .split_whitespace()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no HTTP status in {text:?}"));
    let body = text
        .split_once("\r\n\r\n")
        .map(|(_, b)| b.to_owned())
        .unwrap_or_default();
    (status, body)
}

/// Headless Chromium, or `None` when the browser tests are skipped on purpose.
pub(crate) fn browser(dir: &Path) -> Option<Browser> {
    canopener_testkit::browser::devtools(&dir.join("profile"), 1440, 900)
}

/// A tab on `url`, loaded.
pub(crate) fn open(browser: &Browser, url: &str) -> Arc<Tab> {
    let tab = browser.new_tab().expect("new tab");
    tab.set_default_timeout(Duration::from_secs(60));
    tab.navigate_to(url)
        .expect("navigate")
        .wait_until_navigated()
        .expect("loaded");
    tab
}

/// `expression` evaluated in the page (awaited when it is a promise), as JSON.
pub(crate) fn js(tab: &Tab, expression: &str) -> Value {
    let wrapped = format!("(async () => JSON.stringify(await ({expression})))()");
    let result = tab
        .evaluate(&wrapped, true)
        .unwrap_or_else(|e| panic!("{expression}: {e}"));
    match result.value {
        Some(Value::String(text)) => serde_json::from_str(&text).unwrap_or(Value::Null),
        _ => Value::Null,
    }
}

/// Polls `condition` (JavaScript, truthy when done) every 5 ms; returns how long it took.
pub(crate) fn wait_until(tab: &Tab, condition: &str, within: Duration) -> Duration {
    let started = Instant::now();
    loop {
        if js(tab, &format!("!!({condition})")) == Value::Bool(true) {
            return started.elapsed();
        }
        assert!(
            started.elapsed() < within,
            "not within {within:?}: {condition}\npage: {}",
            js(tab, "document.querySelector('main').innerText.slice(0, 3000)")
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Where the screenshots go: `target/tmp/web-screenshots/NAME.png`.
pub(crate) fn screenshot(tab: &Tab, name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("web-screenshots");
    std::fs::create_dir_all(&dir).expect("screenshot dir");
    let png = tab
        .capture_screenshot(CaptureScreenshotFormatOption::Png, None, None, true)
        .expect("screenshot");
    let (width, height) = canopener_testkit::browser::png_size(&png);
    assert!(width >= 800 && height >= 500, "{name}: {width}×{height}");
    let path = dir.join(format!("{name}.png"));
    std::fs::write(&path, png).expect("write screenshot");
    eprintln!("screenshot: {}", path.display());
    path
}

//! Report format tests: snapshots, SARIF schema validation, JUnit and JSON structure, the HTML page
//! in headless Chromium, and the whole pipeline from EDS text to reports.

// The browser test drives a real Chromium: it starts a process, waits for it and reads the screenshot it
// writes, which the sans-IO bans of this crate do not allow anywhere else.
#[allow(clippy::disallowed_methods, clippy::print_stderr)]
mod browser;
mod fixture;
mod formats;
mod pipeline;
mod sarif;

//! Report format tests: snapshots, SARIF schema validation, JUnit and JSON structure, the HTML page
//! in headless Chromium, and the whole pipeline from EDS text to reports.

mod browser;
mod fixture;
mod formats;
mod pipeline;
mod sarif;

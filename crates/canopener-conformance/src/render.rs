//! The report as people and other tools read it: the CCT-like human summary, a self-contained HTML
//! page with plots of the measurements, JUnit XML and a candump telegram log per test. (JSON is [`Report::to_json`](crate::model::Report::to_json).)

pub mod candump;
pub mod html;
pub mod human;
pub mod junit;

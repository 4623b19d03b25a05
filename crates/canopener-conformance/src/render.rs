//! The report as people and other tools read it: the CCT-like human summary, JUnit XML and a candump
//! telegram log per test. (JSON is [`Report::to_json`](crate::model::Report::to_json).)

pub mod candump;
pub mod human;
pub mod junit;

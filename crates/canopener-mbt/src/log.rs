//! Run logs as JSON Lines: a `run` line (models, model hash, seed and configuration), one `step`
//! line per trace step, and a `verdict` line with the inputs to replay. Read back for `replay` and
//! `shrink`.

use serde::{Deserialize, Serialize};

use crate::executor::{RunConfig, RunResult, ScriptStep, Strategy};

/// The log format's version.
pub const VERSION: u32 = 1;

/// What a run was made with: enough to make it again.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunHeader {
    /// [`VERSION`].
    pub version: u32,
    /// The models composed: shipped names or file paths, as given.
    pub models: Vec<String>,
    /// The compiled model's hash ([`crate::model::Model::hash`]).
    pub model_hash: String,
    /// The node-ID under test.
    pub node: u8,
    /// The master seed.
    pub seed: u64,
    /// The step budget.
    pub steps: usize,
    /// Window tolerance, µs.
    pub tolerance_us: i64,
    /// Settling time after an output, µs.
    pub settle_us: i64,
    /// Percent of decisions that send an input.
    pub input_percent: u8,
    /// `uniform` or `coverage`.
    pub strategy: String,
    /// The test purpose the run followed, by name, if any.
    #[serde(default)]
    pub purpose: Option<String>,
}

impl RunHeader {
    /// The header of a run of `models` with `config`.
    pub fn new(models: &[String], model_hash: &str, node: u8, config: &RunConfig) -> RunHeader {
        RunHeader {
            version: VERSION,
            models: models.to_vec(),
            model_hash: model_hash.to_owned(),
            node,
            seed: config.seed,
            steps: config.steps,
            tolerance_us: config.tolerance_us,
            settle_us: config.settle_us,
            input_percent: config.input_percent,
            strategy: match config.strategy {
                Strategy::Uniform => "uniform".into(),
                Strategy::Coverage => "coverage".into(),
            },
            purpose: config.purpose.as_ref().map(|p| p.name.clone()),
        }
    }

    /// The configuration to run again with, replaying `script` if given.
    pub fn config(&self, script: Option<Vec<ScriptStep>>) -> RunConfig {
        RunConfig {
            seed: self.seed,
            steps: self.steps,
            tolerance_us: self.tolerance_us,
            strategy: if self.strategy == "uniform" {
                Strategy::Uniform
            } else {
                Strategy::Coverage
            },
            input_percent: self.input_percent,
            settle_us: self.settle_us,
            script,
            purpose: None,
        }
    }
}

/// A log read back.
#[derive(Debug, Clone, PartialEq)]
pub struct Log {
    /// How the run was made.
    pub header: RunHeader,
    /// The verdict it had.
    pub verdict: String,
    /// The inputs the tester chose, with their times when the log has them.
    pub script: Vec<ScriptStep>,
    /// How many steps the log records.
    pub steps: usize,
}

/// Why a log cannot be read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("line {line}: {message}")]
pub struct LogError {
    /// 1-based line.
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

/// `value`'s members (none unless it is an object) and `kind` after them.
fn with_kind(value: serde_json::Value, kind: &str) -> serde_json::Value {
    let mut members = match value {
        serde_json::Value::Object(members) => members,
        _ => serde_json::Map::new(),
    };
    members.insert("kind".to_owned(), kind.into());
    serde_json::Value::Object(members)
}

/// The log of a run as JSON Lines.
pub fn write(header: &RunHeader, outcome: &RunResult) -> String {
    let mut out = String::new();
    let mut line = |value: serde_json::Value| {
        out.push_str(&value.to_string());
        out.push('\n');
    };
    line(with_kind(serde_json::to_value(header).unwrap_or_default(), "run"));
    for step in &outcome.trace {
        line(with_kind(serde_json::to_value(step).unwrap_or_default(), "step"));
    }
    line(serde_json::json!({
        "kind": "verdict",
        "verdict": outcome.verdict,
        "reason": outcome.reason,
        "allowed": outcome.allowed,
        "inputs": outcome.inputs,
        "input_times_us": outcome.input_times_us,
        "steps": outcome.steps,
        "coverage": outcome.coverage,
    }));
    out
}

/// Reads a log written by [`write()`].
pub fn read(text: &str) -> Result<Log, LogError> {
    let mut header: Option<RunHeader> = None;
    let mut verdict = None;
    let mut steps = 0;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        if raw.trim().is_empty() {
            continue;
        }
        let err = |message: String| LogError { line, message };
        let value: serde_json::Value =
            serde_json::from_str(raw).map_err(|e| err(format!("not JSON: {e}")))?;
        match value.get("kind").and_then(|k| k.as_str()) {
            Some("run") => {
                let h: RunHeader = serde_json::from_value(value.clone())
                    .map_err(|e| err(format!("a `run` line without {e}")))?;
                if h.version != VERSION {
                    return Err(err(format!("log version {} is not {VERSION}", h.version)));
                }
                header = Some(h);
            }
            Some("step") => steps += 1,
            Some("verdict") => {
                let inputs: Vec<String> = value
                    .get("inputs")
                    .and_then(|v| serde_json::from_value(v.clone()).ok())
                    .ok_or_else(|| err("the `verdict` line has no `inputs` list".into()))?;
                let times: Vec<i64> = value
                    .get("input_times_us")
                    .and_then(|v| serde_json::from_value(v.clone()).ok())
                    .unwrap_or_default();
                let script: Vec<ScriptStep> = inputs
                    .into_iter()
                    .enumerate()
                    .map(|(i, label)| ScriptStep {
                        label,
                        at_us: times.get(i).copied(),
                    })
                    .collect();
                let v = value
                    .get("verdict")
                    .and_then(|v| v.as_str())
                    .unwrap_or("")
                    .to_owned();
                verdict = Some((v, script));
            }
            _ => {
                return Err(err(
                    "each line needs \"kind\": \"run\", \"step\" or \"verdict\"".into()
                ));
            }
        }
    }
    let header = header.ok_or(LogError {
        line: 1,
        message: "no `run` line: is this an mbt log?".into(),
    })?;
    let (verdict, script) = verdict.ok_or(LogError {
        line: text.lines().count(),
        message: "no `verdict` line: the run did not finish".into(),
    })?;
    Ok(Log {
        header,
        verdict,
        script,
        steps,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::executor::{Coverage, Dir, TraceStep, Verdict};

    #[test]
    fn a_log_reads_back_its_header_and_inputs() {
        let config = RunConfig {
            seed: 42,
            steps: 10,
            ..RunConfig::default()
        };
        let header = RunHeader::new(&["nmt".into()], "abc", 5, &config);
        let outcome = RunResult {
            verdict: Verdict::Fail,
            reason: "r".into(),
            trace: vec![TraceStep {
                t: 0.5,
                dir: Dir::In,
                label: "?NMT !0x01 !0x05".into(),
                frame: None,
            }],
            allowed: vec!["EC !0x05".into()],
            inputs: vec!["?NMT !0x01 !0x05".into()],
            input_times_us: vec![500_000],
            steps: 1,
            outputs_seen: 0,
            coverage: Coverage {
                locations: [1, 2],
                transitions: [1, 3],
                taken: vec![0],
                states_seen: 1,
            },
            purpose: None,
        };
        let text = write(&header, &outcome);
        assert_eq!(text.lines().count(), 3);
        let log = read(&text).unwrap();
        assert_eq!(log.header, header);
        assert_eq!(log.header.config(None).seed, 42);
        assert_eq!((log.verdict.as_str(), log.steps), ("fail", 1));
        assert_eq!(log.script, outcome.script());
        assert_eq!(log.script[0].at_us, Some(500_000));
        assert_eq!(read("{\"kind\":\"step\"}\nnot json").unwrap_err().line, 2);
        assert_eq!(
            read(&text.replace("\"version\":1", "\"version\":9"))
                .unwrap_err()
                .line,
            1
        );
        assert!(
            read(text.lines().next().unwrap())
                .unwrap_err()
                .message
                .contains("no `verdict`")
        );
    }
}

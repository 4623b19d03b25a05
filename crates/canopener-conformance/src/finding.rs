//! What one test concludes, and the evidence of a failure: the request, what CiA 301 requires (with
//! the clause), what came back, and the likely cause.

use canopener_link::link::LinkError;

use crate::model::Verdict;

/// A test's verdict with its one-line reason and, for a failure, the analysis.
#[derive(Debug, Clone, PartialEq)]
pub struct Finding {
    /// The verdict.
    pub verdict: Verdict,
    /// One line: why.
    pub reason: String,
    /// The analysis of a failure (empty otherwise).
    pub analysis: String,
}

impl Finding {
    /// The device did what is required.
    pub fn pass(reason: impl Into<String>) -> Finding {
        Finding::new(Verdict::Pass, reason)
    }

    /// The test does not apply to this device.
    pub fn not_applicable(reason: impl Into<String>) -> Finding {
        Finding::new(Verdict::NotApplicable, reason)
    }

    /// The test could not decide.
    pub fn inconclusive(reason: impl Into<String>) -> Finding {
        Finding::new(Verdict::Inconclusive, reason)
    }

    /// The device broke a requirement; `evidence` says which and how.
    pub fn fail(reason: impl Into<String>, evidence: Evidence) -> Finding {
        Finding {
            analysis: evidence.text(),
            ..Finding::new(Verdict::Fail, reason)
        }
    }

    /// The verdict of a test made of steps, each `(name, finding)`: the first failure, else the first
    /// undecided step, else a pass naming what each step found (and which steps did not apply),
    /// or not_applicable when no step applied.
    pub fn of_steps(steps: Vec<(&str, Finding)>) -> Finding {
        for verdict in [Verdict::Fail, Verdict::Inconclusive] {
            if let Some((name, finding)) = steps.iter().find(|(_, f)| f.verdict == verdict) {
                return Finding {
                    reason: format!("{name}: {}", finding.reason),
                    ..finding.clone()
                };
            }
        }
        let named = |verdict: Verdict| -> Vec<String> {
            steps
                .iter()
                .filter(|(_, f)| f.verdict == verdict)
                .map(|(name, f)| format!("{name}: {}", f.reason))
                .collect()
        };
        let (passed, skipped) = (named(Verdict::Pass), named(Verdict::NotApplicable));
        if passed.is_empty() {
            return Finding::not_applicable(skipped.join("; "));
        }
        let mut reason = passed.join("; ");
        if !skipped.is_empty() {
            reason.push_str(&format!(" (not applicable: {})", skipped.join("; ")));
        }
        Finding::pass(reason)
    }

    fn new(verdict: Verdict, reason: impl Into<String>) -> Finding {
        Finding {
            verdict,
            reason: reason.into(),
            analysis: String::new(),
        }
    }
}

/// The evidence of a failure.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Evidence {
    /// What the tester sent (`SDO download 1017h:00 = 0x00000064 (4 bytes)`).
    pub request: String,
    /// What the specification requires, with the clause.
    pub requirement: String,
    /// What came back.
    pub answer: String,
    /// The most likely cause in the device.
    pub cause: String,
}

impl Evidence {
    /// The analysis as the reports print it, one labelled line each.
    pub fn text(&self) -> String {
        format!(
            "Request:  {}\nRequired: {}\nAnswer:   {}\nCause:    {}",
            self.request, self.requirement, self.answer, self.cause
        )
    }
}

/// Why a test stopped before reaching a verdict of its own.
#[derive(Debug, thiserror::Error)]
pub enum Stop {
    /// The run was cancelled (Ctrl-C); a running SDO transfer was aborted on the bus.
    #[error("interrupted")]
    Cancelled,
    /// The bus failed.
    #[error(transparent)]
    Link(#[from] LinkError),
    /// The test asked for a frame CAN cannot carry (more than 8 bytes, say, from a mapping the
    /// device reported): the test is inconclusive with this reason, and the run goes on.
    #[error("{0}")]
    Unsendable(String),
}

/// What a test function returns.
pub type Outcome = Result<Finding, Stop>;

/// What a step before the measurement returns: what the test goes on with, or the finding that
/// ends it there (not applicable, a failure, inconclusive).
pub type Prepared<T> = Result<Result<T, Finding>, Stop>;
#[cfg(test)]
mod tests {
    use super::*;

    fn failure() -> Finding {
        Finding::fail(
            "refused nothing",
            Evidence {
                request: "r".into(),
                requirement: "q".into(),
                answer: "a".into(),
                cause: "c".into(),
            },
        )
    }

    #[test]
    fn steps_fail_first_then_undecided_then_pass_with_what_did_not_apply() {
        let all = Finding::of_steps(vec![
            ("PDO 32", Finding::pass("refused")),
            ("PDO 29", Finding::inconclusive("no answer")),
            ("x", failure()),
        ]);
        assert_eq!(all.verdict, Verdict::Fail);
        assert_eq!(all.reason, "x: refused nothing");
        assert!(all.analysis.contains("Request:  r"));
        let undecided = Finding::of_steps(vec![
            ("PDO 32", Finding::pass("refused")),
            ("PDO 29", Finding::inconclusive("no answer")),
        ]);
        assert_eq!(undecided.verdict, Verdict::Inconclusive);
        let passed = Finding::of_steps(vec![
            ("PDO 32", Finding::pass("refused")),
            ("PDO 29", Finding::not_applicable("no RPDO")),
        ]);
        assert_eq!(passed.verdict, Verdict::Pass);
        assert_eq!(passed.reason, "PDO 32: refused (not applicable: PDO 29: no RPDO)");
        let none = Finding::of_steps(vec![
            ("a", Finding::not_applicable("x")),
            ("b", Finding::not_applicable("y")),
        ]);
        assert_eq!(
            (none.verdict, none.reason.as_str()),
            (Verdict::NotApplicable, "a: x; b: y")
        );
    }
}

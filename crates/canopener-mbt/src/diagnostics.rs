//! What the model reader, the static checks, the `.aut` reader and exploration report, in the
//! diagnostic shape every canopener reader shares ([`canopener_eds::diag::Diagnostic`]): a stable code
//! of the `M` series (model files) or the `A` series (`.aut` files), a severity, a message, a span
//! (line and column) and help.

use canopener_eds::diag::{Diagnostic, Severity, Span};

canopener_eds::diagnostic_codes! {
    /// The stable identity of a model-based-testing diagnostic.
    pub enum MbtCode {
    /// A character or token the model language does not have here.
    Syntax = "M001", "syntax-error", Error;
    /// A string that is not closed before the end of the line.
    UnterminatedString = "M002", "unterminated-string", Error;
    /// A number that does not fit 63 bits or has a unit the language does not know.
    BadNumber = "M003", "bad-number", Error;
    /// The file has no `model NAME` line.
    NoModelName = "M004", "no-model-name", Error;
    /// A name that is not defined where it is used.
    UnknownName = "M010", "unknown-name", Error;
    /// A name defined twice.
    Duplicate = "M011", "duplicate-definition", Error;
    /// An expression of the wrong type (a number where a condition belongs, or the reverse).
    TypeMismatch = "M012", "type-mismatch", Error;
    /// A function called with the wrong number of arguments, or a function the language does not have.
    BadCall = "M013", "bad-call", Error;
    /// A value, domain or input whose values are not bounded (an input field without a value or set,
    /// a range that is empty or too wide).
    Unbounded = "M020", "unbounded-domain", Error;
    /// Internal transitions that can follow each other forever (a τ-cycle): the device could stay
    /// busy without ever being observable.
    TauCycle = "M021", "tau-cycle", Error;
    /// An input gate used as an output or the reverse.
    GateDirection = "M022", "gate-direction", Error;
    /// An output or internal transition without a time window: a missing output could never fail.
    NoTimeBound = "M023", "no-time-bound", Error;
    /// A variable assigned by a process that does not own it.
    NotOwner = "M024", "not-owner", Error;
    /// An internal transition that resets a clock: its firing time is not observed, so the clock
    /// would not be known.
    TauResetsClock = "M025", "internal-resets-clock", Error;
    /// A guard of an output that reads the output's own fields (write the value in the pattern).
    OutputGuardReadsField = "M026", "output-guard-reads-field", Error;
    /// A parameter that cannot be evaluated (it needs `--eds`, or divides by zero).
    ParamUnresolved = "M030", "param-unresolved", Error;
    /// A value outside its variable's domain, or a field value that does not fit its bytes.
    OutOfDomain = "M031", "out-of-domain", Error;
    /// A gate whose frame cannot exist: more than 8 data bytes, or a COB-ID above 7FFh.
    BadGate = "M032", "bad-gate", Error;
    /// Two gates on the same COB-ID that a received frame cannot tell apart.
    AmbiguousGates = "M033", "ambiguous-gates", Error;
    /// A `use` that names no shipped model and no readable file, or that includes itself.
    BadUse = "M034", "bad-use", Error;
    /// Two models composed on the command line that declare the same gate differently.
    GateClash = "M035", "gate-clash", Error;
    /// Processes of different models that both take the same input: both would expect their own
    /// answer, which the device gives once.
    OverlappingInputs = "M040", "overlapping-inputs", Warning;
    /// Composed models that disagree in a reachable state: one requires an output (or a hidden
    /// event) that another, which holds the same frame, refuses. No device can satisfy both; the
    /// executor never sends the input that leads there.
    Disagreement = "M043", "models-disagree", Warning;
    /// Composed models whose `reset` stimuli differ on a shared gate: each model's initial state
    /// assumes only its own.
    ResetsDiffer = "M044", "resets-differ", Warning;
    /// A location no transition leads to.
    UnreachableLocation = "M041", "unreachable-location", Warning;
    /// A process without locations.
    NoLocations = "M042", "no-locations", Error;
    /// Exploration stopped at its bound: the exported state space is a prefix of the real one.
    StateBound = "M050", "state-bound", Warning;
    /// An expression that cannot be evaluated in a reachable state (division by zero, an update
    /// leaving its variable's domain).
    EvalError = "M051", "evaluation-error", Error;
    /// More simultaneous internal steps than the bound allows (a τ-cycle through data).
    Divergence = "M052", "divergence", Error;
    /// A test purpose that is not deterministic, marks a state both accepting and refusing, or names
    /// labels the specification does not have.
    BadPurpose = "M060", "bad-purpose", Error;
    /// A purpose whose accepting states cannot be reached in the specification.
    PurposeUnreachable = "M061", "purpose-unreachable", Warning;
    /// The `des` header of an `.aut` file is missing or malformed.
    AutHeader = "A001", "aut-header", Error;
    /// A transition line of an `.aut` file that is not `(from, label, to)`.
    AutTransition = "A002", "aut-transition", Error;
    /// A state number outside the range the header declares.
    AutStateRange = "A003", "aut-state-range", Error;
    /// The header's transition or state count disagrees with the file.
    AutCount = "A004", "aut-count", Warning;
    /// A label that is not 7-bit ASCII or is longer than 5000 characters.
    AutLabel = "A005", "aut-label", Warning;
    /// An `.aut` specification label whose direction cannot be told (`?` input, `!` output, `i`/`tau`
    /// internal).
    AutDirection = "A006", "aut-direction", Error;
    }
}

/// A diagnostic of the model reader, the checks, exploration or the `.aut` reader.
pub type MbtDiagnostic = Diagnostic<MbtCode>;

/// A diagnostic with help text.
pub(crate) fn diag(code: MbtCode, span: Span, message: impl Into<String>) -> MbtDiagnostic {
    Diagnostic::new(code, span, message)
}

/// Whether any of `diagnostics` is an error (a model with errors does not run).
pub fn has_errors(diagnostics: &[MbtDiagnostic]) -> bool {
    diagnostics.iter().any(|d| d.severity == Severity::Error)
}

/// `file:line:column: severity[code]: message` lines, with help indented below, as compilers print.
pub fn render(file: &str, diagnostics: &[MbtDiagnostic]) -> String {
    let mut out = String::new();
    for d in diagnostics {
        out.push_str(&format!(
            "{file}:{}:{}: {}[{}]: {}\n",
            d.span.line, d.span.column, d.severity, d.code, d.message
        ));
        if let Some(help) = &d.help {
            out.push_str(&format!("  help: {help}\n"));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_unique_and_rendered_with_their_place() {
        let mut seen = std::collections::BTreeSet::new();
        for code in MbtCode::ALL {
            assert!(seen.insert(code.as_str()), "{code} twice");
            assert_eq!(MbtCode::from_name(code.slug()), Some(*code));
        }
        let mut d = diag(MbtCode::TauCycle, Span::new(3, 5, 2), "internal steps loop");
        d.help = Some("give one of them an input".into());
        assert_eq!(
            render("nmt.mbt", &[d.clone()]),
            "nmt.mbt:3:5: error[M021]: internal steps loop\n  help: give one of them an input\n"
        );
        assert!(has_errors(&[d]));
        assert!(!has_errors(&[diag(MbtCode::StateBound, Span::default(), "x")]));
    }
}

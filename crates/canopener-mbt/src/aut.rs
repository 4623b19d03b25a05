//! Aldebaran `.aut`: the LTS format of CADP (and mCRL2's `ltsconvert`), so that explored models and
//! synthesised test graphs can be cross-checked with those tools, and their results read back.
//!
//! ```text
//! des (0, 3, 3)
//! (0, "?NMT !0x01 !0x05", 1)
//! (1, "!EC !0x05", 2)
//! (2, i, 0)
//! ```
//! The header gives the initial state, the number of transitions and of states. Labels are quoted
//! or bare; this crate writes inputs as `?GATE !v..`, outputs as `!GATE !v..` and internal steps as
//! `i` (CADP's τ), and reads `tau` as `i` too.

use canopener_eds::diag::Span;

use crate::diagnostics::{MbtCode, MbtDiagnostic, diag};
use crate::explore::Lts;

/// Longest label CADP accepts.
const MAX_LABEL: usize = 5000;

/// The LTS as `.aut` text.
pub fn write(lts: &Lts) -> String {
    let mut out = format!(
        "des ({}, {}, {})\n",
        lts.initial,
        lts.transitions.len(),
        lts.states
    );
    for (from, label, to) in &lts.transitions {
        if label == "i" {
            out.push_str(&format!("({from}, i, {to})\n"));
        } else {
            out.push_str(&format!("({from}, \"{}\", {to})\n", label.replace('"', "'")));
        }
    }
    out
}

/// Reads `.aut` text: the LTS and what was wrong with the file. Never panics; transition lines that
/// cannot be read are reported and skipped.
pub fn read(text: &str) -> (Lts, Vec<MbtDiagnostic>) {
    let mut diagnostics = Vec::new();
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty());
    let mut lts = Lts::default();
    let span = |line: usize, len: usize| Span::new(line as u32 + 1, 1, len as u32);
    let header = lines.next();
    let declared = header.and_then(|(_, l)| parse_header(l));
    let Some((initial, transitions, states)) = declared else {
        let (line, len) = header.map_or((0, 0), |(n, l)| (n, l.chars().count()));
        diagnostics.push(diag(
            MbtCode::AutHeader,
            span(line, len),
            "an .aut file starts with `des (INITIAL, TRANSITIONS, STATES)`",
        ));
        return (lts, diagnostics);
    };
    lts.initial = initial;
    lts.states = states;
    if initial >= states.max(1) {
        diagnostics.push(diag(
            MbtCode::AutStateRange,
            span(0, 0),
            format!("the initial state {initial} is not below the state count {states}"),
        ));
    }
    for (n, line) in lines {
        let Some((from, label, to)) = parse_transition(line) else {
            diagnostics.push(diag(
                MbtCode::AutTransition,
                span(n, line.chars().count()),
                "a transition is written `(FROM, \"LABEL\", TO)`",
            ));
            continue;
        };
        if from >= states || to >= states {
            diagnostics.push(diag(
                MbtCode::AutStateRange,
                span(n, line.chars().count()),
                format!("state {} is not below the declared count {states}", from.max(to)),
            ));
            continue;
        }
        if label.len() > MAX_LABEL || !label.is_ascii() {
            diagnostics.push(diag(
                MbtCode::AutLabel,
                span(n, line.chars().count()),
                "labels are 7-bit ASCII of at most 5000 characters",
            ));
        }
        lts.transitions.push((from, label, to));
    }
    if lts.transitions.len() != transitions {
        diagnostics.push(diag(
            MbtCode::AutCount,
            span(0, 0),
            format!(
                "the header declares {transitions} transitions, the file has {}",
                lts.transitions.len()
            ),
        ));
    }
    (lts, diagnostics)
}

fn parse_header(line: &str) -> Option<(usize, usize, usize)> {
    let rest = line
        .trim()
        .strip_prefix("des")?
        .trim()
        .strip_prefix('(')?
        .strip_suffix(')')?;
    let mut numbers = rest.split(',').map(|n| n.trim().parse::<usize>().ok());
    let parsed = (numbers.next()??, numbers.next()??, numbers.next()??);
    numbers.next().is_none().then_some(parsed)
}

fn parse_transition(line: &str) -> Option<(usize, String, usize)> {
    let inner = line.trim().strip_prefix('(')?.strip_suffix(')')?;
    let (from, rest) = inner.split_once(',')?;
    let (label, to) = rest.rsplit_once(',')?;
    let label = label.trim();
    let label = match label.strip_prefix('"') {
        Some(quoted) => quoted.strip_suffix('"')?.to_owned(),
        None if label == "tau" => "i".to_owned(),
        None if !label.is_empty() => label.to_owned(),
        None => return None,
    };
    Some((from.trim().parse().ok()?, label, to.trim().parse().ok()?))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn reads_what_cadp_writes_and_reports_the_rest() {
        let (lts, d) =
            read("des (0, 3, 3)\n(0, \"?NMT !0x01 !0x05\", 1)\n(1, \"!EC, !0x05\", 2)\n(2, tau, 0)\n");
        assert!(d.is_empty(), "{d:?}");
        assert_eq!(lts.transitions[1], (1, "!EC, !0x05".to_owned(), 2));
        assert_eq!(lts.transitions[2].1, "i");
        let (_, d) = read("des (0, 2, 2)\n(0, \"a\", 5)\nnot a transition\n");
        let codes: Vec<(u32, &str)> = d.iter().map(|d| (d.span.line, d.code.as_str())).collect();
        assert_eq!(codes, [(2, "A003"), (3, "A002"), (1, "A004")]);
        assert_eq!(read("(0, a, 1)").1[0].code, MbtCode::AutHeader);
        assert_eq!(read("").1[0].code, MbtCode::AutHeader);
    }

    fn lts() -> impl Strategy<Value = Lts> {
        (1usize..20).prop_flat_map(|states| {
            let label = prop_oneof![Just("i".to_owned()), "[?!][A-Z_]{1,6}( ![0-9a-fx_]{1,6}){0,3}"];
            (
                0..states,
                proptest::collection::vec((0..states, label, 0..states), 0..40),
            )
                .prop_map(move |(initial, transitions)| Lts {
                    initial,
                    states,
                    transitions,
                })
        })
    }

    proptest! {
        #[test]
        fn write_then_read_is_the_identity(lts in lts()) {
            let (back, d) = read(&write(&lts));
            prop_assert!(d.is_empty(), "{:?}", d);
            prop_assert_eq!(back, lts);
        }

        #[test]
        fn any_text_reads_without_panicking(text in "\\PC{0,200}") {
            let _ = read(&text);
        }
    }
}

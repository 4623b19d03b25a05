//! The EDS check the CiA 301 suite starts with (CCT "EDS checker"): canopener's own EDS checks
//! (`canopener eds check`) on the file; any error fails `cia301.eds.1`.

use canopener_check::Selection;
use canopener_eds::{Loaded, Severity};

use crate::context::Ctx;
use crate::finding::{Evidence, Finding, Outcome};
use crate::requirements as req;
use crate::test_def::TestDef;

/// The EDS tests.
pub fn tests() -> Vec<TestDef> {
    vec![TestDef {
        id: "cia301.eds.1",
        suite: "cia301",
        group: "eds",
        title: "The EDS passes canopener's EDS checks without errors",
        references: &[req::EDS_FORMAT, "CCT EDS checker"],
        precondition: "the description is an EDS or DCF",
        tags: &["eds"],
        run: eds_check,
    }]
}

/// The error-level findings of canopener's EDS checks on `loaded`, one line each
/// (`line 12: C301 …`).
pub fn errors(loaded: &Loaded, file_name: Option<&str>) -> Vec<String> {
    canopener_check::check(loaded, file_name, &Selection::default())
        .findings
        .into_iter()
        .filter(|f| f.diagnostic.severity == Severity::Error)
        .map(|f| {
            format!(
                "line {}: {} {}",
                f.diagnostic.span.line, f.diagnostic.code, f.diagnostic.message
            )
        })
        .collect()
}

fn eds_check(ctx: &mut Ctx<'_, '_>) -> Outcome {
    let Some(errors) = ctx.eds_errors() else {
        return Ok(Finding::not_applicable("the description is not an EDS/DCF"));
    };
    ctx.performed("EDS checker");
    Ok(match errors {
        [] => Finding::pass("no errors"),
        [first, ..] => Finding::fail(
            format!("{} EDS errors; the first: {first}", errors.len()),
            Evidence {
                request: "canopener eds check on the file".to_owned(),
                requirement: format!("{}: the file follows CiA 306", req::EDS_FORMAT),
                answer: errors.join("\n          "),
                cause: "the EDS departs from CiA 306; `canopener eds check` explains each finding and `eds fix` corrects the safe ones".to_owned(),
            },
        ),
    })
}

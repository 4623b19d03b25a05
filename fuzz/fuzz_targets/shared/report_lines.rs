//! The invariant every checking target shares: each finding of a report points at a line and column
//! of the checked text, and the source line the report shows under it is that line, both counted by
//! the one rule of `canopener_eds::lines` (LF, CR LF and a lone CR end a line).

use canopener_eds::lines::LineIndex;
use canopener_report::FileReport;

pub fn assert_findings_on_their_lines(report: &FileReport, text: &str) {
    let lines = LineIndex::new(text);
    for finding in &report.findings {
        let line = finding.diagnostic.span.line;
        let inside = usize::try_from(line).is_ok_and(|l| (1..=lines.count()).contains(&l));
        assert!(inside, "finding outside the file's {} lines: {finding:?}", lines.count());
        assert!(finding.diagnostic.span.column >= 1, "finding with column 0: {finding:?}");
        assert_eq!(
            report.source.get(&line).map(String::as_str),
            lines.line(line),
            "the source line shown is not the line the position counts: {finding:?}"
        );
    }
}

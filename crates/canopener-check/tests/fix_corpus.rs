//! `canopener eds fix` over every real file of the corpus: it never panics, never raises the number
//! of errors, is idempotent, and leaves every line it does not edit byte-identical.
//!
//! `cargo test -p canopener-check --test fix_corpus -- --nocapture` prints the fixes per code.

use std::collections::{BTreeMap, HashSet};
use std::panic::{AssertUnwindSafe, catch_unwind};

use canopener_check::fix::{self, Edit, Fix};
use canopener_check::{Context, Selection};
use canopener_testkit::corpus::{self, Kind};

fn corpus() -> Vec<(String, Vec<u8>)> {
    corpus::eds_files()
        .into_iter()
        .map(|file| {
            let bytes = canopener_testkit::fixture::read(&file.path)
                .unwrap_or_else(|e| panic!("{}: {e}", file.path.display()));
            (file.name, bytes)
        })
        .collect()
}

fn no_extra(_: &Context<'_>) -> Vec<Fix> {
    Vec::new()
}

/// Lines with their endings (`\n`, `\r\n` or a bare `\r`), as the loader splits them.
fn lines(bytes: &[u8]) -> Vec<&[u8]> {
    let mut out = Vec::new();
    let mut start = 0;
    let mut i = 0;
    while i < bytes.len() {
        let end = match (bytes[i], bytes.get(i + 1)) {
            (b'\r', Some(b'\n')) => Some(i + 2),
            (b'\n' | b'\r', _) => Some(i + 1),
            _ => None,
        };
        match end {
            Some(end) => {
                out.push(&bytes[start..end]);
                start = end;
                i = end;
            }
            None => i += 1,
        }
    }
    if start < bytes.len() {
        out.push(&bytes[start..]);
    }
    out
}

fn ends_without_newline(bytes: &[u8]) -> bool {
    bytes.last().is_some_and(|&b| b != b'\n' && b != b'\r')
}

/// (lines edited or deleted, lines inserted) by a set of fixes.
fn edit_counts(fixes: &[Fix]) -> (usize, usize) {
    let (mut edited, mut inserted) = (0, 0);
    for edit in fixes.iter().flat_map(|f| &f.edits) {
        match edit {
            Edit::SetValue { .. } | Edit::ReplaceLine { .. } => {
                edited += 1;
                inserted += 1;
            }
            Edit::DeleteLine { .. } => edited += 1,
            Edit::AppendEntry { .. } => inserted += 1,
            Edit::AppendLines { lines } => inserted += lines.len(),
        }
    }
    (edited, inserted)
}

/// Whatever rounds `fix_file` took, a minimal line diff between input and output deletes no more
/// old lines than the fixes edited (every other old line is kept byte for byte) and inserts no more
/// lines than they wrote. Myers' diff is minimal, so this bounds the real edit script.
fn check_untouched_lines(name: &str, old: &[u8], new: &[u8], fixes: &[Fix]) -> Result<(), String> {
    let (old_lines, new_lines) = (lines(old), lines(new));
    let ops = similar::capture_diff_slices(similar::Algorithm::Myers, &old_lines, &new_lines);
    let (mut deleted, mut inserted) = (0, 0);
    for op in ops {
        match op {
            similar::DiffOp::Equal { .. } => {}
            similar::DiffOp::Delete { old_len, .. } => deleted += old_len,
            similar::DiffOp::Insert { new_len, .. } => inserted += new_len,
            similar::DiffOp::Replace { old_len, new_len, .. } => {
                deleted += old_len;
                inserted += new_len;
            }
        }
    }
    let (edited, wrote) = edit_counts(fixes);
    // Appending after a last line without a newline gives that line one (its content is kept).
    let slack = usize::from(ends_without_newline(old) && wrote > 0);
    if deleted > edited + slack || inserted > wrote + slack {
        return Err(format!(
            "{name}: the diff deletes {deleted} and inserts {inserted} lines, the fixes edit {edited} and write {wrote}"
        ));
    }
    Ok(())
}

/// One round through `plan` and `apply`, checked line by line: every line no applied edit names
/// appears in the output unchanged and in order, and the line count adds up.
fn check_first_round(name: &str, bytes: &[u8]) -> Result<(), String> {
    let loaded = canopener_eds::load(bytes);
    let cx = Context::new(&loaded, Some(name));
    let fixes = fix::plan(&cx, &Selection::default());
    let applied = fix::apply(&loaded.document, &fixes);
    let Ok(new) = applied.document.to_bytes() else {
        return Err(format!("{name}: the applied fixes cannot be encoded"));
    };
    let mut touched = HashSet::new();
    let (mut deleted, mut added) = (0usize, 0usize);
    for edit in applied
        .applied
        .iter()
        .filter_map(|&i| fixes.get(i))
        .flat_map(|f| &f.edits)
    {
        match edit {
            Edit::SetValue { line, .. } | Edit::ReplaceLine { line, .. } => {
                touched.insert(*line);
            }
            Edit::DeleteLine { line } => {
                touched.insert(*line);
                deleted += 1;
            }
            Edit::AppendEntry { .. } => added += 1,
            Edit::AppendLines { lines } => added += lines.len(),
        }
    }
    let (old_lines, new_lines) = (lines(bytes), lines(&new));
    if new_lines.len() != old_lines.len() - deleted + added {
        return Err(format!(
            "{name}: {} lines became {} with {deleted} deleted and {added} added",
            old_lines.len(),
            new_lines.len()
        ));
    }
    let last = old_lines.len().saturating_sub(1);
    let mut next = new_lines.iter().copied();
    for (i, old) in old_lines.iter().enumerate() {
        if touched.contains(&i) {
            continue;
        }
        let same = |new: &[u8]| {
            if i == last && ends_without_newline(bytes) {
                new.strip_suffix(b"\r\n")
                    .or_else(|| new.strip_suffix(b"\n"))
                    .unwrap_or(new)
                    == *old
            } else {
                new == *old
            }
        };
        if !next.any(same) {
            return Err(format!(
                "{name}: untouched line {} `{}` is not kept byte for byte",
                i + 1,
                String::from_utf8_lossy(old).trim_end()
            ));
        }
    }
    Ok(())
}

#[test]
fn fixing_the_corpus_is_safe_idempotent_and_keeps_untouched_lines() {
    let files = corpus();
    assert_eq!(
        files.len(),
        corpus::expected_count(Kind::Eds),
        "every EDS/DCF file of the corpus"
    );
    let mut per_code: BTreeMap<String, (usize, usize)> = BTreeMap::new();
    let mut failures = Vec::new();
    let (mut changed, mut errors_before, mut errors_after, mut skipped) = (0, 0, 0, 0);
    for (name, bytes) in &files {
        let run = catch_unwind(AssertUnwindSafe(|| {
            fix::fix_file(bytes, Some(name), &Selection::default(), &no_extra)
        }));
        let outcome = match run {
            Ok(outcome) => outcome,
            Err(_) => {
                failures.push(format!("{name}: fix_file panicked"));
                continue;
            }
        };
        changed += usize::from(outcome.changed);
        errors_before += outcome.errors_before;
        errors_after += outcome.errors_after;
        skipped += outcome.skipped.len();
        let mut codes_here = HashSet::new();
        for f in &outcome.fixes {
            let entry = per_code.entry(f.code.clone()).or_default();
            entry.0 += 1;
            if codes_here.insert(f.code.clone()) {
                entry.1 += 1;
            }
        }
        if outcome.errors_after > outcome.errors_before {
            failures.push(format!(
                "{name}: errors went from {} to {}",
                outcome.errors_before, outcome.errors_after
            ));
        }
        if outcome.changed != (outcome.bytes != *bytes) || outcome.changed == outcome.fixes.is_empty() {
            failures.push(format!(
                "{name}: changed={} with {} fixes applied",
                outcome.changed,
                outcome.fixes.len()
            ));
        }
        if let Err(e) = check_untouched_lines(name, bytes, &outcome.bytes, &outcome.fixes) {
            failures.push(e);
        }
        match catch_unwind(AssertUnwindSafe(|| check_first_round(name, bytes))) {
            Ok(Err(e)) => failures.push(e),
            Err(_) => failures.push(format!("{name}: plan/apply panicked")),
            Ok(Ok(())) => {}
        }
        let again = fix::fix_file(&outcome.bytes, Some(name), &Selection::default(), &no_extra);
        if again.changed || !again.fixes.is_empty() {
            let what: Vec<String> = again
                .fixes
                .iter()
                .map(|f| format!("{} {}", f.code, f.description))
                .collect();
            failures.push(format!("{name}: fixing again is not a no-op: {what:?}"));
        }
    }
    println!(
        "fixed {changed} of {} files; errors {errors_before} -> {errors_after}; {skipped} fix(es) skipped",
        files.len()
    );
    println!("code   fixes  files");
    for (code, (fixes, in_files)) in &per_code {
        println!("{code:<6} {fixes:>5}  {in_files:>5}");
    }
    assert!(
        failures.is_empty(),
        "{} failure(s):\n{}",
        failures.len(),
        failures.join("\n")
    );
}

//! Safe fixes: line edits that correct a finding and leave every other line byte-identical.
//!
//! A [`Fix`] is planned against one [`Document`] (it names lines and sections by their index in it)
//! and applied with [`apply`]. Built-in checks plan fixes in [`plan`]; rule packs build their own
//! `Fix` values with the same edits. [`fix_file`] runs the whole `canopener eds fix` cycle: plan,
//! apply, reload, repeat until nothing is left, re-check; it never keeps a round of fixes that
//! raises the number of errors.
//!
//! Built-in fixes ([`BUILTIN_FIXES`]):
//! - `P031`: a section header rewritten to the name CiA 306 gives it (`[1018sub01]` → `[1018sub1]`);
//! - `P032`: a key rewritten to CiA 306's spelling (`Parametername` → `ParameterName`);
//! - `P042`: object list entries naming objects without a section removed, the list renumbered;
//! - `P043`: objects no list names added to the list CiA 306 §4.6.3.1 assigns them;
//! - `P044`: an object list renumbered 1..N, duplicates removed, `SupportedObjects` recounted;
//! - `P045`: `SubNumber` set to the number of sub-object sections present;
//! - `C537`: sub 0's `DefaultValue` set to the highest sub-index (changes what the device reports).

mod lists;
mod names;
mod values;

use std::collections::HashMap;

use canopener_eds::syntax::LineKind;
use canopener_eds::text::{Encoding, encode};
use canopener_eds::{Document, Loaded, Severity};

use crate::context::Context;
use crate::registry;
use crate::run::{Selection, check};

/// One correction, made of line edits, with what it does in words.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Fix {
    /// The code of the finding it corrects.
    pub code: String,
    /// What it does, naming section, key, old and new value (e.g. `[1018] SubNumber: 4 -> 5`).
    pub description: String,
    /// True when the fix changes what the file says about the device (a default value, a name),
    /// not just how it is written; such fixes are always reported as such.
    pub changes_meaning: bool,
    /// The edits, applied together or not at all.
    pub edits: Vec<Edit>,
}

/// A line edit against the document the fix was planned on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Edit {
    /// Replace the value of the entry on this line (index into [`Document::lines`]), keeping the key
    /// and whatever surrounds the value as written.
    SetValue {
        /// The entry line.
        line: usize,
        /// The new value.
        value: String,
    },
    /// Replace a whole line's content (its line ending is kept).
    ReplaceLine {
        /// The line.
        line: usize,
        /// The new content.
        content: String,
    },
    /// Delete a line.
    DeleteLine {
        /// The line.
        line: usize,
    },
    /// Add `key=value` after the last entry of a section (index into [`Document::sections`]).
    AppendEntry {
        /// The section.
        section: usize,
        /// The key.
        key: String,
        /// The value.
        value: String,
    },
    /// Add whole lines at the end of the file (e.g. a missing section).
    AppendLines {
        /// The lines, without line endings.
        lines: Vec<String>,
    },
}

/// The codes the built-in fixes correct; the registry marks exactly these as fixable.
pub const BUILTIN_FIXES: &[&str] = &["P031", "P032", "P042", "P043", "P044", "P045", "C537"];

/// The result of [`apply`].
#[derive(Debug, Clone)]
pub struct Applied {
    /// The edited document (a copy of the input when nothing was applied).
    pub document: Document,
    /// Indices into the fixes of those applied, in order.
    pub applied: Vec<usize>,
    /// Indices into the fixes of those not applied, with the reason.
    pub skipped: Vec<(usize, String)>,
}

/// The result of [`fix_file`].
#[derive(Debug, Clone)]
pub struct FixOutcome {
    /// The fixed file (the input bytes when nothing was applied).
    pub bytes: Vec<u8>,
    /// The fixes applied, in the order they were applied (later rounds after earlier ones).
    pub fixes: Vec<Fix>,
    /// Fixes that were planned but not applied in the end, with the reason.
    pub skipped: Vec<(Fix, String)>,
    /// Error findings of all built-in checks before fixing.
    pub errors_before: usize,
    /// Error findings of all built-in checks after fixing (never more than `errors_before`).
    pub errors_after: usize,
    /// Whether `bytes` differs from the input.
    pub changed: bool,
}

/// Rounds of plan–apply–reload in [`fix_file`]. Fixes of one object list touch the same
/// `SupportedObjects` line, so P042, P044 and P043 on one list take a round each; the bound only
/// stops rule-pack fixes that keep undoing each other.
const MAX_ROUNDS: usize = 8;

/// The built-in fixes for the selected codes, in a fixed order (names, keys, counts, lists, values).
/// Fixes of one object list all edit its `SupportedObjects` line, so [`apply`] takes one per round.
pub fn plan(cx: &Context<'_>, selection: &Selection) -> Vec<Fix> {
    planned(cx, selection).fixes
}

/// Applies fixes in order. A fix is applied whole or not at all; it is skipped, with the reason,
/// when an edit names a line or section the document does not have, when its text cannot be
/// written in the file's encoding or holds a line break, when it changes nothing, or when it
/// touches a line (or appends to a section) that an earlier applied fix already touched.
pub fn apply(document: &Document, fixes: &[Fix]) -> Applied {
    let mut editor = document.editor();
    let mut owners: HashMap<Touch, usize> = HashMap::new();
    let mut applied = Vec::new();
    let mut skipped = Vec::new();
    for (i, fix) in fixes.iter().enumerate() {
        let touches = match validate(document, fix) {
            Ok(touches) => touches,
            Err(reason) => {
                skipped.push((i, reason));
                continue;
            }
        };
        let clash = touches
            .iter()
            .find_map(|t| owners.get(t).map(|&owner| (*t, owner)));
        if let Some((touch, owner)) = clash {
            let other = fixes
                .get(owner)
                .map_or_else(String::new, |f| format!(" by {} fix `{}`", f.code, f.description));
            skipped.push((
                i,
                format!("{} is already changed{other}", touch.describe(document)),
            ));
            continue;
        }
        for touch in touches {
            owners.insert(touch, i);
        }
        for edit in &fix.edits {
            perform(&mut editor, document, edit);
        }
        applied.push(i);
    }
    let document = if applied.is_empty() {
        document.clone()
    } else {
        editor.apply()
    };
    Applied {
        document,
        applied,
        skipped,
    }
}

/// Fixes a file: plans the built-in fixes of the selected codes plus `extra` (rule-pack) fixes,
/// applies them, reloads and repeats until nothing is left to fix, then re-checks.
///
/// A round whose fixes together raise the number of error findings is redone fix by fix, keeping
/// only fixes that do not; the others are reported as skipped. Errors are counted over all
/// built-in checks, whatever the selection, so a fix cannot trade one error for a new one elsewhere.
pub fn fix_file(
    bytes: &[u8],
    file_name: Option<&str>,
    selection: &Selection,
    extra: &dyn Fn(&Context<'_>) -> Vec<Fix>,
) -> FixOutcome {
    let mut loaded = canopener_eds::load(bytes);
    let errors_before = errors(&loaded, file_name);
    let mut state = Round {
        bytes: bytes.to_vec(),
        errors: errors_before,
    };
    let mut fixes = Vec::new();
    let mut skipped = Vec::new();
    let mut finished = false;
    for _ in 0..MAX_ROUNDS {
        let cx = Context::new(&loaded, file_name);
        let Planned {
            fixes: mut planned_fixes,
            refused,
        } = planned(&cx, selection);
        planned_fixes.extend(extra(&cx));
        skipped = refused;
        if planned_fixes.is_empty() {
            finished = true;
            break;
        }
        let (next, kept, round_skipped) = run_round(&loaded, file_name, &planned_fixes, &state);
        skipped.extend(round_skipped);
        let Some(next) = next else {
            finished = true;
            break;
        };
        fixes.extend(kept);
        loaded = canopener_eds::load(&next.bytes);
        state = next;
    }
    if !finished {
        // Whatever is still planned after the last round could not be applied in time.
        let cx = Context::new(&loaded, file_name);
        let Planned {
            fixes: mut pending,
            refused,
        } = planned(&cx, selection);
        pending.extend(extra(&cx));
        let reason = format!("still pending after {MAX_ROUNDS} rounds of fixes; run the fix again");
        skipped = refused;
        skipped.extend(pending.into_iter().map(|f| (f, reason.clone())));
    }
    let changed = state.bytes != bytes;
    FixOutcome {
        bytes: state.bytes,
        fixes,
        skipped,
        errors_before,
        errors_after: state.errors,
        changed,
    }
}

/// A unified diff of two versions of a file (`canopener eds fix --dry-run`), decoded as the
/// loader decodes them (UTF-8, else Windows-1252). Empty when the files are equal.
pub fn unified_diff(old: &[u8], new: &[u8], old_name: &str, new_name: &str) -> String {
    if old == new {
        return String::new();
    }
    let (old_text, _) = canopener_eds::text::decode(old);
    let (new_text, _) = canopener_eds::text::decode(new);
    let diff = similar::TextDiff::from_lines(old_text.as_str(), new_text.as_str());
    let mut unified = diff.unified_diff();
    unified.context_radius(3).header(old_name, new_name);
    let out = unified.to_string();
    if out.is_empty() {
        // Only the byte order mark or the encoding differs; the text diff shows nothing.
        format!(
            "--- {old_name}\n+++ {new_name}\n(the files differ only in their encoding or byte order mark)\n"
        )
    } else {
        out
    }
}

/// What the planners produce: fixes to apply, and fixes that would be wrong to apply now.
#[derive(Debug, Default)]
struct Planned {
    fixes: Vec<Fix>,
    refused: Vec<(Fix, String)>,
}

/// The state between rounds: the file and its error count.
#[derive(Debug, Clone)]
struct Round {
    bytes: Vec<u8>,
    errors: usize,
}

/// Something an edit changes, for conflicts between fixes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Touch {
    Line(usize),
    SectionEnd(usize),
}

impl Touch {
    fn describe(self, document: &Document) -> String {
        match self {
            Touch::Line(line) => format!("line {}", line + 1),
            Touch::SectionEnd(section) => {
                let name = document
                    .sections()
                    .get(section)
                    .map_or("?", |s| document.section_name(s));
                format!("the end of section [{name}]")
            }
        }
    }
}

fn planned(cx: &Context<'_>, selection: &Selection) -> Planned {
    let mut out = Planned::default();
    if selected(selection, "P031") {
        names::section_names(cx, &mut out);
    }
    if selected(selection, "P032") {
        names::key_case(cx, &mut out);
    }
    if selected(selection, "P045") {
        values::sub_number(cx, &mut out);
    }
    // Removing entries for missing objects first often makes a list's count right by itself.
    if selected(selection, "P042") {
        lists::missing(cx, &mut out);
    }
    if selected(selection, "P044") {
        lists::malformed(cx, &mut out);
    }
    if selected(selection, "P043") {
        lists::unlisted(cx, &mut out);
    }
    if selected(selection, "C537") {
        values::sub0_highest(cx, &mut out);
    }
    out
}

/// Whether a built-in fix's code is selected. Codes the registry does not (yet) list are selected
/// by code, slug and the group they belong to.
fn selected(selection: &Selection, code: &str) -> bool {
    if *selection == Selection::default() {
        return true;
    }
    if let Some(info) = registry::lookup(code) {
        return selection.selects_builtin(info);
    }
    let (slug, group) = match code {
        "C537" => ("sub0-not-highest-sub-index", registry::Group::Objects),
        "P031" | "P032" => ("", registry::Group::Syntax),
        "P045" => ("", registry::Group::Objects),
        _ => ("", registry::Group::ObjectLists),
    };
    let slug = canopener_eds::Code::from_name(code).map_or(slug, canopener_eds::Code::slug);
    selection.selects(code, slug, &[group.name()])
}

/// Applies one round's fixes, keeping the error count from rising. Returns the new state (`None`
/// when nothing changed), the fixes kept and those skipped with the reason.
fn run_round(
    loaded: &Loaded,
    file_name: Option<&str>,
    fixes: &[Fix],
    state: &Round,
) -> (Option<Round>, Vec<Fix>, Vec<(Fix, String)>) {
    let named = |list: Vec<(usize, String)>| -> Vec<(Fix, String)> {
        list.into_iter()
            .filter_map(|(i, reason)| Some((fixes.get(i)?.clone(), reason)))
            .collect()
    };
    let result = apply(&loaded.document, fixes);
    let mut skipped = named(result.skipped);
    if result.applied.is_empty() {
        return (None, Vec::new(), skipped);
    }
    let next = match evaluate(&result.document, file_name) {
        Ok(next) if next.errors <= state.errors => Some((next, result.applied.clone())),
        Ok(_) => None,
        Err(reason) => {
            skipped.extend(named(
                result.applied.iter().map(|&i| (i, reason.clone())).collect(),
            ));
            return (None, Vec::new(), skipped);
        }
    };
    let (next, kept) = match next {
        Some(found) => found,
        None => one_by_one(loaded, file_name, fixes, &result.applied, state, &mut skipped),
    };
    if next.bytes == state.bytes || kept.is_empty() {
        return (None, Vec::new(), skipped);
    }
    let kept = kept.iter().filter_map(|&i| fixes.get(i).cloned()).collect();
    (Some(next), kept, skipped)
}

/// Adds the fixes of a round one at a time, dropping each one that raises the error count.
fn one_by_one(
    loaded: &Loaded,
    file_name: Option<&str>,
    fixes: &[Fix],
    candidates: &[usize],
    state: &Round,
    skipped: &mut Vec<(Fix, String)>,
) -> (Round, Vec<usize>) {
    let mut kept: Vec<usize> = Vec::new();
    let mut best = state.clone();
    for &i in candidates {
        let Some(fix) = fixes.get(i) else { continue };
        let trial: Vec<Fix> = kept
            .iter()
            .chain(std::iter::once(&i))
            .filter_map(|&k| fixes.get(k).cloned())
            .collect();
        let result = apply(&loaded.document, &trial);
        if result.applied.len() != trial.len() {
            skipped.push((
                fix.clone(),
                "conflicts with the fixes kept in this round".to_owned(),
            ));
            continue;
        }
        match evaluate(&result.document, file_name) {
            Ok(next) if next.errors <= state.errors => {
                kept.push(i);
                best = next;
            }
            Ok(next) => skipped.push((
                fix.clone(),
                format!(
                    "would raise the number of errors from {} to {}",
                    state.errors, next.errors
                ),
            )),
            Err(reason) => skipped.push((fix.clone(), reason)),
        }
    }
    (best, kept)
}

/// Encodes an edited document and counts its errors.
fn evaluate(document: &Document, file_name: Option<&str>) -> Result<Round, String> {
    let bytes = document.to_bytes().map_err(|e| e.to_string())?;
    let errors = errors(&canopener_eds::load(&bytes), file_name);
    Ok(Round { bytes, errors })
}

fn errors(loaded: &Loaded, file_name: Option<&str>) -> usize {
    check(loaded, file_name, &Selection::default())
        .findings
        .iter()
        .filter(|f| f.diagnostic.severity == Severity::Error)
        .count()
}

/// Checks that a fix can be applied to this document and lists what it touches.
fn validate(document: &Document, fix: &Fix) -> Result<Vec<Touch>, String> {
    if fix.edits.is_empty() {
        return Err("the fix has no edits".to_owned());
    }
    let encoding = document.encoding();
    let mut touches: Vec<Touch> = Vec::new();
    let mut changes = false;
    for edit in &fix.edits {
        let touch = match edit {
            Edit::SetValue { line, value } => {
                let Some((_, old)) = document.entry(*line) else {
                    return Err(format!("line {} is not a `key=value` entry", line + 1));
                };
                writable(value, encoding)?;
                changes |= old != value;
                Touch::Line(*line)
            }
            Edit::ReplaceLine { line, content } => {
                line_exists(document, *line)?;
                writable(content, encoding)?;
                changes |= document.line_text(*line) != content;
                Touch::Line(*line)
            }
            Edit::DeleteLine { line } => {
                line_exists(document, *line)?;
                changes = true;
                Touch::Line(*line)
            }
            Edit::AppendEntry { section, key, value } => {
                if document.sections().get(*section).is_none() {
                    return Err(format!("the document has no section number {section}"));
                }
                let bad_key = key.trim().is_empty()
                    || key.trim() != key
                    || key.contains('=')
                    || key.starts_with(['[', ';', '#']);
                if bad_key {
                    return Err(format!("`{key}` cannot be written as a key"));
                }
                writable(key, encoding)?;
                writable(value, encoding)?;
                changes = true;
                Touch::SectionEnd(*section)
            }
            Edit::AppendLines { lines } => {
                for line in lines {
                    writable(line, encoding)?;
                }
                changes |= !lines.is_empty();
                // Whole lines appended at the end of the file never overlap another fix's edits.
                continue;
            }
        };
        if touch_is_line(touch) && touches.contains(&touch) {
            return Err(format!(
                "two edits of the fix change {}",
                touch.describe(document)
            ));
        }
        if !touches.contains(&touch) {
            touches.push(touch);
        }
    }
    if !changes {
        return Err("the fix changes nothing".to_owned());
    }
    Ok(touches)
}

fn touch_is_line(touch: Touch) -> bool {
    matches!(touch, Touch::Line(_))
}

fn line_exists(document: &Document, line: usize) -> Result<(), String> {
    if line < document.lines().len() {
        Ok(())
    } else {
        Err(format!("line {} does not exist", line + 1))
    }
}

/// New text must stay on one line and be writable in the file's encoding.
fn writable(text: &str, encoding: Encoding) -> Result<(), String> {
    if text.contains(['\n', '\r']) {
        return Err(format!("the new text {text:?} contains a line break"));
    }
    encode(text, encoding).map(|_| ()).map_err(|e| e.to_string())
}

fn perform(editor: &mut canopener_eds::syntax::Editor<'_>, document: &Document, edit: &Edit) {
    match edit {
        Edit::SetValue { line, value } => {
            editor.set_value(*line, value);
        }
        Edit::ReplaceLine { line, content } => {
            editor.replace_line(*line, content);
        }
        Edit::DeleteLine { line } => {
            editor.delete_line(*line);
        }
        Edit::AppendEntry { section, key, value } => {
            if let Some(section) = document.sections().get(*section) {
                // After the last entry, not the last non-blank line: a comment that closes a
                // section usually introduces the next one.
                let anchor = document
                    .entries(section)
                    .last()
                    .copied()
                    .unwrap_or(section.header_line);
                editor.insert_after(anchor, [format!("{key}={value}")]);
            }
        }
        Edit::AppendLines { lines } => {
            editor.append(lines.iter().cloned());
        }
    }
}

/// A line's content with the byte range `range` (inside the line) replaced.
fn splice(document: &Document, line: usize, range: &std::ops::Range<usize>, with: &str) -> Option<String> {
    let l = document.lines().get(line)?;
    let text = document.text();
    Some(format!(
        "{}{with}{}",
        text.get(l.start..range.start)?,
        text.get(range.end..l.end)?
    ))
}

/// The line with its key replaced, keeping the value and the spacing as written.
fn with_key(document: &Document, line: usize, key: &str) -> Option<String> {
    match &document.lines().get(line)?.kind {
        LineKind::Entry { key: range, .. } => splice(document, line, range, key),
        _ => None,
    }
}

/// At most `max` items joined with `, `, then how many more there are.
fn shorten(items: &[String], max: usize) -> String {
    let shown = items.get(..max.min(items.len())).unwrap_or(items).join(", ");
    match items.len().saturating_sub(max) {
        0 => shown,
        rest => format!("{shown} and {rest} more"),
    }
}

/// `n` written in the notation of `old` (hex with the same prefix, digit case and width, else
/// decimal), keeping any inline comment after the number.
fn number_like(old: &str, n: u64) -> String {
    let head_len = old
        .find(';')
        .map_or(old.len(), |p| old.get(..p).map_or(p, |h| h.trim_end().len()));
    let (head, tail) = (
        old.get(..head_len).unwrap_or(old),
        old.get(head_len..).unwrap_or(""),
    );
    let new = match head.get(..2) {
        Some(prefix @ ("0x" | "0X")) => {
            let digits = head.get(2..).unwrap_or("");
            let width = if digits.bytes().all(|b| b.is_ascii_hexdigit()) {
                digits.len()
            } else {
                0
            };
            let lower = digits.bytes().any(|b| b.is_ascii_lowercase())
                && !digits.bytes().any(|b| b.is_ascii_uppercase());
            if lower {
                format!("{prefix}{n:0width$x}")
            } else {
                format!("{prefix}{n:0width$X}")
            }
        }
        _ => n.to_string(),
    };
    format!("{new}{tail}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_keep_their_notation() {
        assert_eq!(number_like("5", 3), "3");
        assert_eq!(number_like("0x05", 3), "0x03");
        assert_eq!(number_like("0x5", 0x12), "0x12");
        assert_eq!(number_like("0x0a", 0x1b), "0x1b");
        assert_eq!(number_like("0X0A", 0x1b), "0X1B");
        assert_eq!(number_like("5 ; five", 4), "4 ; five");
        assert_eq!(number_like("", 4), "4");
        assert_eq!(number_like("05", 4), "4");
    }

    #[test]
    fn long_lists_are_shortened() {
        let items: Vec<String> = (1..=5).map(|n| n.to_string()).collect();
        assert_eq!(shorten(&items, 8), "1, 2, 3, 4, 5");
        assert_eq!(shorten(&items, 3), "1, 2, 3 and 2 more");
        assert_eq!(shorten(&[], 3), "");
    }
}

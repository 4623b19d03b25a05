//! What the checker commands share: expanding files, directories and globs, loading rule packs,
//! turning `--only/--skip/--tag` into a selection, and checking one file.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use canopener_check::{CheckDescription, Context, Selection};
use canopener_report::FileReport;
use canopener_rules::RulePack;

use crate::eds::args::CheckSelectionArgs;
use crate::error::{CliError, CliResult};

/// One file to check: a path, or what went wrong finding it (reported as a problem, exit 2).
#[derive(Debug, Clone)]
pub(crate) struct Target {
    pub(crate) path: PathBuf,
    pub(crate) problem: Option<String>,
}

/// The checks in force: rule packs and the selection over built-ins and rules.
#[derive(Debug)]
pub(crate) struct Checks {
    pub(crate) packs: Vec<RulePack>,
    pub(crate) selection: Selection,
}

impl Checks {
    /// Reads the rule packs and validates `--only/--skip` names against every known check.
    pub(crate) fn from_args(args: &CheckSelectionArgs) -> CliResult<Checks> {
        let mut packs = Vec::new();
        for path in &args.rules {
            let text = std::fs::read_to_string(path).map_err(|e| {
                CliError::EdsTrouble(format!("cannot read rule pack {}: {e}", path.display()))
            })?;
            let pack = canopener_rules::parse_pack(&text, &path.display().to_string())
                .map_err(|e| CliError::EdsTrouble(e.to_string()))?;
            packs.push(pack);
        }
        let checks = Checks {
            packs,
            selection: Selection {
                only: args
                    .only
                    .iter()
                    .map(|s| s.trim().to_owned())
                    .filter(|s| !s.is_empty())
                    .collect(),
                skip: args
                    .skip
                    .iter()
                    .map(|s| s.trim().to_owned())
                    .filter(|s| !s.is_empty())
                    .collect(),
                tags: args.tag.clone(),
            },
        };
        let known = checks.all();
        for name in checks.selection.only.iter().chain(&checks.selection.skip) {
            if !known
                .iter()
                .any(|c| c.code.eq_ignore_ascii_case(name) || &c.slug == name)
            {
                return Err(CliError::EdsTrouble(format!(
                    "unknown check '{name}' in --only/--skip; `canopener eds rules list` shows every code"
                )));
            }
        }
        Ok(checks)
    }

    /// Every check, built-in and from the packs, selected or not, in code order (built-ins first).
    pub(crate) fn all(&self) -> Vec<CheckDescription> {
        let mut all: Vec<CheckDescription> = canopener_check::registry::builtin()
            .iter()
            .map(|c| c.describe())
            .collect();
        for pack in &self.packs {
            all.extend(pack.describe());
        }
        all
    }

    /// The checks the selection keeps.
    pub(crate) fn selected(&self) -> Vec<CheckDescription> {
        self.all()
            .into_iter()
            .filter(|c| {
                let tags: Vec<&str> = c.tags.iter().map(String::as_str).collect();
                self.selection.selects(&c.code, &c.slug, &tags)
            })
            .collect()
    }

    /// Checks one file's bytes: built-in checks and rule packs; the source lines findings point at.
    pub(crate) fn check_bytes(&self, path: &Path, bytes: &[u8]) -> FileReport {
        let loaded = canopener_eds::load(bytes);
        let name = path.file_name().and_then(|n| n.to_str());
        let mut findings = canopener_check::check(&loaded, name, &self.selection).findings;
        if !self.packs.is_empty() {
            let cx = Context::new(&loaded, name);
            for pack in &self.packs {
                findings.extend(pack.check(&cx, &self.selection));
            }
            canopener_check::sort_by_position(&mut findings);
        }
        let lines: BTreeSet<u32> = findings.iter().map(|f| f.diagnostic.span.line).collect();
        let source: BTreeMap<u32, String> = lines
            .into_iter()
            .filter(|&l| l >= 1)
            .map(|l| (l, loaded.document.line_text(l as usize - 1).to_owned()))
            .collect();
        FileReport {
            path: display_path(path),
            findings,
            source,
            problem: None,
        }
    }

    /// Reads and checks one target; an unreadable file becomes a report with a problem.
    pub(crate) fn check_target(&self, target: &Target) -> FileReport {
        let problem = |message: String| FileReport {
            path: display_path(&target.path),
            findings: Vec::new(),
            source: BTreeMap::new(),
            problem: Some(message),
        };
        if let Some(message) = &target.problem {
            return problem(message.clone());
        }
        match std::fs::read(&target.path) {
            Ok(bytes) => self.check_bytes(&target.path, &bytes),
            Err(e) => problem(format!("cannot read the file: {e}")),
        }
    }
}

/// Expands files, directories (every `.eds`/`.dcf` below, case-insensitive, sorted) and glob patterns,
/// without duplicates, in the order given. A name that matches nothing becomes a problem target so the
/// other files are still checked.
pub(crate) fn expand(inputs: &[String]) -> Vec<Target> {
    let mut targets = Vec::new();
    let mut seen = BTreeSet::new();
    let mut push = |path: PathBuf, problem: Option<String>, targets: &mut Vec<Target>| {
        if seen.insert(path.clone()) {
            targets.push(Target { path, problem });
        }
    };
    for input in inputs {
        let path = PathBuf::from(input);
        if path.is_dir() {
            let found = walk(&path);
            if found.is_empty() {
                // Checking nothing must not look like a clean result.
                push(
                    path,
                    Some("no .eds or .dcf file below this directory".to_owned()),
                    &mut targets,
                );
            }
            for file in found {
                push(file, None, &mut targets);
            }
        } else if path.exists() || !is_pattern(input) {
            let problem = (!path.exists()).then(|| "no such file or directory".to_owned());
            push(path, problem, &mut targets);
        } else {
            match glob::glob(input) {
                Err(e) => push(path, Some(format!("not a valid glob pattern: {e}")), &mut targets),
                Ok(matches) => {
                    let mut any = false;
                    for entry in matches {
                        any = true;
                        match entry {
                            Ok(found) if found.is_dir() => {
                                for inner in walk(&found) {
                                    push(inner, None, &mut targets);
                                }
                            }
                            Ok(found) => push(found, None, &mut targets),
                            Err(e) => {
                                let at = e.path().to_owned();
                                push(at, Some(format!("cannot read: {}", e.error())), &mut targets);
                            }
                        }
                    }
                    if !any {
                        push(path, Some("the pattern matches no file".to_owned()), &mut targets);
                    }
                }
            }
        }
    }
    targets
}

/// A path as users typed it, with forward slashes so reports are the same on every OS.
pub(crate) fn display_path(path: &Path) -> String {
    path.to_string_lossy().replace('\\', "/")
}

fn is_pattern(text: &str) -> bool {
    text.contains(['*', '?', '['])
}

/// Every EDS/DCF file below a directory, sorted; unreadable subdirectories are skipped (the files
/// that can be read are still checked).
fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    let mut pending = vec![dir.to_owned()];
    while let Some(current) = pending.pop() {
        let Ok(entries) = std::fs::read_dir(&current) else {
            continue;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                pending.push(path);
            } else if is_eds_or_dcf(&path) {
                found.push(path);
            }
        }
    }
    found.sort();
    found
}

fn is_eds_or_dcf(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("eds") || e.eq_ignore_ascii_case("dcf"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expands_directories_globs_and_reports_missing_names() {
        let dir = std::env::temp_dir().join(format!("canopener-expand-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        for name in ["a.eds", "b.DCF", "notes.txt", "sub/c.eds"] {
            std::fs::write(dir.join(name), "").unwrap();
        }
        let d = dir.display().to_string();
        let targets = expand(&[
            d.clone(),
            format!("{d}/*.eds"),
            format!("{d}/nothing*.eds"),
            format!("{d}/gone.eds"),
        ]);
        let names: Vec<(String, bool)> = targets
            .iter()
            .map(|t| {
                (
                    t.path.strip_prefix(&dir).unwrap_or(&t.path).display().to_string(),
                    t.problem.is_some(),
                )
            })
            .collect();
        assert_eq!(
            names,
            vec![
                ("a.eds".to_owned(), false),
                ("b.DCF".to_owned(), false),
                ("sub/c.eds".to_owned(), false),
                ("nothing*.eds".to_owned(), true),
                ("gone.eds".to_owned(), true),
            ]
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

//! Checking many description files: expanding the names a user gave (files, directories, glob
//! patterns) into files, and checking them in parallel.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use canopener_description::Checker;
use canopener_report::FileReport;
use rayon::prelude::*;

/// One file to check: a path, or what went wrong finding it (reported as a problem of that name, so
/// the other files are still checked).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Target {
    /// The file, or the name as given when nothing was found.
    pub path: PathBuf,
    /// Why the name stands for no file to check.
    pub problem: Option<String>,
}

/// Expands files, directories (every `.eds`, `.dcf`, `.xdd`, `.xdc` and `.xpd` below, case-insensitive,
/// sorted) and glob
/// patterns the shell did not expand, without duplicates, in the order given. A name that matches
/// nothing becomes a problem target: checking nothing must not look like a clean result.
pub fn expand(inputs: &[String]) -> Vec<Target> {
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
                push(
                    path,
                    Some("no .eds, .dcf, .xdd, .xdc or .xpd file below this directory".to_owned()),
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
pub fn display_path(path: &Path) -> String {
    path.to_string_lossy().replace('\\', "/")
}

/// Reads and checks one target; a file that cannot be read becomes a report with a problem.
pub fn check_target(checker: &Checker, target: &Target) -> FileReport {
    let path = display_path(&target.path);
    if let Some(message) = &target.problem {
        return FileReport::unreadable(path, message.clone());
    }
    match std::fs::read(&target.path) {
        Ok(bytes) => {
            let name = target.path.file_name().and_then(|n| n.to_str());
            checker.check(&path, name, &bytes)
        }
        Err(e) => FileReport::unreadable(path, format!("cannot read the file: {e}")),
    }
}

/// Checks every target on all cores, calling `done` after each file (for a progress bar); the
/// reports come back in the order of the targets.
pub fn check_all(checker: &Checker, targets: &[Target], done: impl Fn() + Sync) -> Vec<FileReport> {
    targets
        .par_iter()
        .map(|target| {
            let report = check_target(checker, target);
            done();
            report
        })
        .collect()
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
            } else if is_description(&path) {
                found.push(path);
            }
        }
    }
    found.sort();
    found
}

/// A description file a directory walk checks: CiA 306 text or CiA 311 XML (CANopenEditor projects,
/// `.nxdd`, are left to be named explicitly: they may hold several devices).
fn is_description(path: &Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| {
        ["eds", "dcf", "xdd", "xdc", "xpd"]
            .iter()
            .any(|x| e.eq_ignore_ascii_case(x))
    })
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicUsize, Ordering};

    use canopener_description::Selection;

    use super::*;
    use crate::test_support::ScratchDir;

    #[test]
    fn expands_directories_globs_and_reports_missing_names() {
        let dir = ScratchDir::new("expand");
        for name in [
            "a.eds",
            "b.DCF",
            "notes.txt",
            "p.nxdd",
            "sub/c.eds",
            "sub/d.XDD",
            "x.xdc",
        ] {
            dir.write(name, b"");
        }
        let d = dir.path().display().to_string();
        let targets = expand(&[
            d.clone(),
            format!("{d}/*.eds"),
            format!("{d}/nothing*.eds"),
            format!("{d}/gone.eds"),
        ]);
        let names: Vec<(String, bool)> = targets
            .iter()
            .map(|t| {
                let relative = t.path.strip_prefix(dir.path()).unwrap_or(&t.path);
                (relative.display().to_string(), t.problem.is_some())
            })
            .collect();
        assert_eq!(
            names,
            vec![
                ("a.eds".to_owned(), false),
                ("b.DCF".to_owned(), false),
                ("sub/c.eds".to_owned(), false),
                ("sub/d.XDD".to_owned(), false),
                ("x.xdc".to_owned(), false),
                ("nothing*.eds".to_owned(), true),
                ("gone.eds".to_owned(), true),
            ]
        );
        let empty = ScratchDir::new("expand-empty");
        let none = expand(&[empty.path().display().to_string()]);
        assert_eq!(
            none.first().and_then(|t| t.problem.as_deref()),
            Some("no .eds, .dcf, .xdd, .xdc or .xpd file below this directory")
        );
    }

    #[test]
    fn checks_every_target_in_order_and_reports_problems() {
        let dir = ScratchDir::new("check-all");
        let good = dir.write("dev.eds", b"[FileInfo]\nFileName=dev.eds\n");
        let targets = vec![
            Target {
                path: dir.path().join("gone.eds"),
                problem: None,
            },
            Target {
                path: good.clone(),
                problem: None,
            },
            Target {
                path: PathBuf::from("x*.eds"),
                problem: Some("the pattern matches no file".to_owned()),
            },
        ];
        let checker = Checker::new(Vec::new(), Selection::default()).expect("no names to check");
        let calls = AtomicUsize::new(0);
        let reports = check_all(&checker, &targets, || {
            calls.fetch_add(1, Ordering::Relaxed);
        });
        assert_eq!(calls.load(Ordering::Relaxed), 3);
        let paths: Vec<&str> = reports.iter().map(|r| r.path.as_str()).collect();
        assert_eq!(paths[1], display_path(&good));
        assert!(
            reports[0]
                .problem
                .as_deref()
                .is_some_and(|p| p.starts_with("cannot read the file: "))
        );
        assert!(reports[1].problem.is_none() && !reports[1].findings.is_empty());
        assert_eq!(reports[2].problem.as_deref(), Some("the pattern matches no file"));
    }

    #[test]
    fn display_paths_use_forward_slashes() {
        assert_eq!(display_path(Path::new(r"vendor\sub/a.eds")), "vendor/sub/a.eds");
    }
}

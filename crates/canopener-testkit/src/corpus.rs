//! The one place that knows where the EDS/XDD corpus is.
//!
//! Two sources, each a directory holding `eds/` and `xdd/`:
//! - the **vendored** corpus, `corpus/` in the repository: the real files whose source licence allows
//!   redistribution (origin and licence per file in `corpus/*/MANIFEST.tsv`). Always there: a fresh
//!   clone tests against it.
//! - the **extended** corpus: `CANOPENER_CORPUS` when set, else `../shared/corpus` next to the checkout
//!   when it exists. It adds the files that cannot be redistributed; tests use it when present and do
//!   not need it otherwise.
//!
//! A file present in both is taken from the vendored corpus (they are byte-identical copies).
//!
//! `corpus/README.md` says where the files come from and why some are not vendored.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The environment variable naming the extended corpus root (a directory with `eds/` and `xdd/`).
pub const CORPUS_ENV: &str = "CANOPENER_CORPUS";

/// The two kinds of description files the corpus holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// CiA 306 EDS and DCF files (`eds/`).
    Eds,
    /// CiA 311 XDD, XDC and XPD files (`xdd/`).
    Xdd,
}

impl Kind {
    /// How many files of this kind the repository vendors (the rows of `corpus/<kind>/MANIFEST.tsv`).
    pub const fn vendored_count(self) -> usize {
        match self {
            Kind::Eds => 110,
            Kind::Xdd => 20,
        }
    }

    /// How many files of this kind the whole corpus holds: the vendored files plus those only the
    /// extended corpus has.
    pub const fn full_count(self) -> usize {
        match self {
            Kind::Eds => 148,
            Kind::Xdd => 26,
        }
    }

    fn dir(self) -> &'static str {
        match self {
            Kind::Eds => "eds",
            Kind::Xdd => "xdd",
        }
    }

    fn holds(self, path: &Path) -> bool {
        let ext = path
            .extension()
            .map(|ext| ext.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        match self {
            Kind::Eds => matches!(ext.as_str(), "eds" | "dcf"),
            Kind::Xdd => matches!(ext.as_str(), "xdd" | "xdc" | "xpd" | "nxdd"),
        }
    }
}

/// One corpus file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CorpusFile {
    /// The file name, unique within a kind (`CANopenNode__CANopenNode__example__IO.eds`).
    pub name: String,
    /// Where it is.
    pub path: PathBuf,
    /// Whether it comes from the vendored corpus (else from the extended one).
    pub vendored: bool,
}

/// The repository root (the workspace holding `crates/`).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .ancestors()
        .nth(2)
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."))
}

/// The vendored corpus root, `corpus/` in the repository.
pub fn vendored_root() -> PathBuf {
    workspace_root().join("corpus")
}

/// The extended corpus root: `CANOPENER_CORPUS`, else `../shared/corpus` next to the checkout when it
/// exists; `None` when there is none.
///
/// # Panics
/// When `CANOPENER_CORPUS` is set to a directory that does not exist: a typo must not silently shrink
/// the tests to the vendored files.
pub fn extended_root() -> Option<PathBuf> {
    if let Some(root) = std::env::var_os(CORPUS_ENV).filter(|root| !root.is_empty()) {
        let root = PathBuf::from(root);
        assert!(
            root.is_dir(),
            "{CORPUS_ENV}={} is not a directory; point it at a corpus root holding eds/ and xdd/, or unset it",
            root.display()
        );
        return Some(root);
    }
    let beside = workspace_root().join("../shared/corpus");
    beside.is_dir().then_some(beside)
}

/// Every file of `kind`: the vendored ones plus those only the extended corpus has, sorted by name.
pub fn files(kind: Kind) -> Vec<CorpusFile> {
    let mut by_name = BTreeMap::new();
    if let Some(root) = extended_root() {
        for (name, path) in list(&root.join(kind.dir()), kind) {
            by_name.insert(
                name.clone(),
                CorpusFile {
                    name,
                    path,
                    vendored: false,
                },
            );
        }
    }
    for (name, path) in list(&vendored_root().join(kind.dir()), kind) {
        by_name.insert(
            name.clone(),
            CorpusFile {
                name,
                path,
                vendored: true,
            },
        );
    }
    by_name.into_values().collect()
}

/// Every EDS/DCF file (see [`files`]).
pub fn eds_files() -> Vec<CorpusFile> {
    files(Kind::Eds)
}

/// Every XDD/XDC/XPD file (see [`files`]).
pub fn xdd_files() -> Vec<CorpusFile> {
    files(Kind::Xdd)
}

/// How many files [`files`] returns when the corpus is complete: every vendored file, and with an
/// extended corpus the whole corpus. Tests over the whole corpus assert it, so that a file the locator
/// lost fails them instead of shrinking them.
pub fn expected_count(kind: Kind) -> usize {
    if extended_root().is_some() {
        kind.full_count()
    } else {
        kind.vendored_count()
    }
}

/// The vendored files of `kind` only: what every checkout has.
pub fn vendored_files(kind: Kind) -> Vec<CorpusFile> {
    files(kind).into_iter().filter(|file| file.vendored).collect()
}

/// One file by name, from the vendored corpus or else the extended one; `None` when neither has it.
pub fn find(kind: Kind, name: &str) -> Option<PathBuf> {
    [Some(vendored_root()), extended_root()]
        .into_iter()
        .flatten()
        .map(|root| root.join(kind.dir()).join(name))
        .find(|path| path.is_file())
}

/// One vendored EDS/DCF file by name, for tests that need a particular real device.
///
/// # Panics
/// When the repository does not carry it: such a test must use a vendored file, so that a fresh clone
/// runs it.
pub fn eds(name: &str) -> PathBuf {
    vendored(Kind::Eds, name)
}

/// One vendored XDD/XDC/XPD file by name (see [`eds`]).
///
/// # Panics
/// When the repository does not carry it.
pub fn xdd(name: &str) -> PathBuf {
    vendored(Kind::Xdd, name)
}

/// One file that only the extended corpus has, for the few tests built around a device that cannot be
/// redistributed: `None` without an extended corpus, and the caller skips, saying so.
///
/// # Panics
/// When there is an extended corpus and it lacks the file, or when the repository vendors the file
/// (then the test must use [`eds`]/[`xdd`] and run everywhere).
pub fn extended_file(kind: Kind, name: &str) -> Option<PathBuf> {
    assert!(
        !vendored_root().join(kind.dir()).join(name).is_file(),
        "{name} is vendored: use corpus::eds/xdd so that every checkout runs the test"
    );
    let Some(root) = extended_root() else {
        eprintln!(
            "skipped: {name} is not vendored (no licence lets us redistribute it; see corpus/README.md); \
             set {CORPUS_ENV} to a corpus root holding it, or put the corpus at ../shared/corpus"
        );
        return None;
    };
    let path = root.join(kind.dir()).join(name);
    assert!(
        path.is_file(),
        "the extended corpus {} lacks {name}",
        root.display()
    );
    Some(path)
}

fn vendored(kind: Kind, name: &str) -> PathBuf {
    let path = vendored_root().join(kind.dir()).join(name);
    assert!(
        path.is_file(),
        "{} is not in the vendored corpus; tests that every checkout runs must use a file listed in {}",
        path.display(),
        vendored_root().join(kind.dir()).join("MANIFEST.tsv").display()
    );
    path
}

/// The files of `kind` in `dir` (not below it), sorted: what the corpus would take from that directory.
/// For tools that run over a directory a user names instead of the corpus.
///
/// # Panics
/// When `dir` cannot be read.
pub fn files_in(dir: &Path, kind: Kind) -> Vec<PathBuf> {
    assert!(dir.is_dir(), "{} is not a directory", dir.display());
    let mut paths: Vec<PathBuf> = list(dir, kind).into_iter().map(|(_, path)| path).collect();
    paths.sort();
    paths
}

fn list(dir: &Path, kind: Kind) -> Vec<(String, PathBuf)> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    entries
        .filter_map(Result::ok)
        .map(|entry| entry.path())
        .filter(|path| path.is_file() && kind.holds(path))
        .filter_map(|path| Some((path.file_name()?.to_string_lossy().into_owned(), path)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_are_told_apart_by_extension() {
        assert!(Kind::Eds.holds(Path::new("a/b.EDS")));
        assert!(Kind::Eds.holds(Path::new("b.dcf")));
        assert!(!Kind::Eds.holds(Path::new("MANIFEST.tsv")));
        assert!(Kind::Xdd.holds(Path::new("x.xpd")));
        assert!(Kind::Xdd.holds(Path::new("x.XDC")));
        assert!(Kind::Xdd.holds(Path::new("x.nxdd")));
        assert!(!Kind::Xdd.holds(Path::new("x.eds")));
    }

    #[test]
    fn the_workspace_root_holds_the_crates() {
        assert!(workspace_root().join("crates/canopener-testkit").is_dir());
    }

    #[test]
    fn the_whole_corpus_is_every_vendored_file_and_with_the_extended_one_every_file() {
        for kind in [Kind::Eds, Kind::Xdd] {
            let all = files(kind);
            assert_eq!(all.len(), expected_count(kind), "{kind:?}");
            let vendored = vendored_files(kind);
            assert_eq!(vendored.len(), kind.vendored_count(), "{kind:?}");
            assert!(vendored.iter().all(|file| file.path.starts_with(vendored_root())));
            if extended_root().is_none() {
                assert_eq!(
                    all, vendored,
                    "{kind:?}: without an extended corpus only vendored files"
                );
            }
        }
    }

    #[test]
    fn a_named_file_is_found_where_it_is() {
        let vendored = "CANopenNode__CANopenNode__example__IO.eds";
        assert_eq!(find(Kind::Eds, vendored), Some(eds(vendored)));
        assert!(eds(vendored).starts_with(vendored_root()));
        assert_eq!(find(Kind::Eds, "no-such-file.eds"), None);
        // Not vendored (no licence at its source): only the extended corpus can have it.
        let extended = "BLUESINK__canopentools__genslave__test.eds";
        assert_eq!(extended_file(Kind::Eds, extended), find(Kind::Eds, extended));
    }

    #[test]
    fn a_directory_lists_its_files_of_one_kind_sorted() {
        let eds = files_in(&vendored_root().join("eds"), Kind::Eds);
        assert_eq!(
            eds.len(),
            Kind::Eds.vendored_count(),
            "MANIFEST.tsv is not an EDS"
        );
        assert!(eds.is_sorted());
        assert!(files_in(&vendored_root().join("eds"), Kind::Xdd).is_empty());
    }

    #[test]
    #[should_panic(expected = "is not in the vendored corpus")]
    fn a_test_cannot_ask_for_a_file_the_repository_does_not_vendor() {
        eds("BLUESINK__canopentools__genslave__test.eds");
    }
}

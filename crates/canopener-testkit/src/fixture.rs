//! The file system as tests of sans-IO crates may use it: reading fixture and corpus files, writing
//! what a test produces for people to look at, scratch directories.
//!
//! The workspace's `clippy.toml` bans file access in every sans-IO crate, tests included, so that a
//! library can never start reading files by accident; tests go through these functions instead, which
//! keeps every file a test touches visible in one place. They mirror `std::fs` and return its errors.

use std::fs;
use std::io;
use std::path::{Path, PathBuf};

/// The checker's base fixture (`crates/canopener-check/test_data/checks/base.eds`): a complete, clean
/// CiA 301 device description (TPDO1 with a one-entry mapping) that the tests of many crates build
/// devices from. Every crate names it through this one constant.
pub const BASE_EDS: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../canopener-check/test_data/checks/base.eds"
);

/// `std::fs::read`: a fixture or corpus file's bytes.
pub fn read(path: impl AsRef<Path>) -> io::Result<Vec<u8>> {
    fs::read(path)
}

/// `std::fs::read_to_string`: a fixture file's text.
pub fn read_to_string(path: impl AsRef<Path>) -> io::Result<String> {
    fs::read_to_string(path)
}

/// `std::fs::write`, creating the parent directories first: output a test leaves for people (rendered
/// reports, screenshots) or a scratch file it feeds to the code under test.
pub fn write(path: impl AsRef<Path>, bytes: impl AsRef<[u8]>) -> io::Result<()> {
    let path = path.as_ref();
    if let Some(parent) = path.parent().filter(|parent| !parent.as_os_str().is_empty()) {
        fs::create_dir_all(parent)?;
    }
    fs::write(path, bytes)
}

/// The entries of a directory, sorted, for tests that go over every fixture of a kind.
pub fn list(dir: impl AsRef<Path>) -> io::Result<Vec<PathBuf>> {
    let mut entries = fs::read_dir(dir)?
        .map(|entry| entry.map(|entry| entry.path()))
        .collect::<io::Result<Vec<_>>>()?;
    entries.sort();
    Ok(entries)
}

/// `std::path::Path::is_dir`: whether a listed entry is a directory to descend into.
pub fn is_dir(path: impl AsRef<Path>) -> bool {
    path.as_ref().is_dir()
}

/// A fresh, empty directory of its own for one test, removed again when dropped.
#[derive(Debug)]
pub struct ScratchDir {
    path: PathBuf,
}

impl ScratchDir {
    /// `<temp>/canopener-<name>-<process id>`, emptied if a previous run left it behind.
    ///
    /// # Panics
    /// When the directory cannot be made: the test could not run anyway.
    pub fn new(name: &str) -> ScratchDir {
        let path = std::env::temp_dir().join(format!("canopener-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&path);
        fs::create_dir_all(&path)
            .unwrap_or_else(|err| panic!("cannot create the scratch directory {}: {err}", path.display()));
        ScratchDir { path }
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Writes a file below the directory (creating its parents) and returns its path.
    ///
    /// # Panics
    /// When the file cannot be written: the test could not run anyway.
    pub fn write(&self, relative: impl AsRef<Path>, bytes: impl AsRef<[u8]>) -> PathBuf {
        let path = self.path.join(relative);
        write(&path, bytes).unwrap_or_else(|err| panic!("cannot write {}: {err}", path.display()));
        path
    }
}

/// The directory's path, so a scratch directory goes wherever a `&Path` does.
impl std::ops::Deref for ScratchDir {
    type Target = Path;

    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for ScratchDir {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.path);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scratch_files_are_written_listed_read_and_removed() {
        let dir = ScratchDir::new("fixture-selftest");
        assert_eq!(dir.write("sub/b.txt", "b"), dir.join("sub/b.txt"));
        write(dir.join("a.txt"), "a").unwrap();
        assert_eq!(list(dir.path()).unwrap(), [dir.join("a.txt"), dir.join("sub")]);
        assert_eq!(read_to_string(dir.join("sub/b.txt")).unwrap(), "b");
        assert_eq!(read(dir.join("a.txt")).unwrap(), b"a");
        let kept = dir.path().to_owned();
        drop(dir);
        assert!(!kept.exists());
    }
}

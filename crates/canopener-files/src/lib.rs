//! Writing result files without losing data: a temporary file in the same directory, then a rename,
//! so a crash or a full disk never leaves a half-written file; optionally the old file kept as `.bak`.

// A file or a frame must never panic this library: no unwrap, expect or unchecked index outside tests
// (as rustls does).
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)
)]

use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// A file could not be written (or its backup kept); nothing was lost: the old file is untouched.
#[derive(Debug, thiserror::Error)]
#[error("cannot {action} {}: {source}", path.display())]
pub struct WriteError {
    /// What was being done (`create`, `write`, `keep a backup as`, `replace`, ...).
    pub action: &'static str,
    /// The file it was done to.
    pub path: PathBuf,
    /// The operating system's reason.
    #[source]
    pub source: io::Error,
}

/// Writes `bytes` to `path` atomically. With `backup`, an existing `path` is first copied to `path.bak`.
///
/// A `path` that exists and is no regular file (`/dev/null`, `/dev/stdout`, a FIFO) is written in place:
/// renaming a temporary file over it would replace the device with a plain file, and nothing of it can be
/// lost or half-written the way a regular file can.
pub fn write_atomic(path: &Path, bytes: &[u8], backup: bool) -> Result<(), WriteError> {
    let trouble = |action: &'static str, target: &Path, source: io::Error| WriteError {
        action,
        path: target.to_owned(),
        source,
    };
    if fs::metadata(path).is_ok_and(|meta| !meta.is_file() && !meta.is_dir()) {
        let mut file = fs::OpenOptions::new()
            .write(true)
            .open(path)
            .map_err(|e| trouble("open", path, e))?;
        return file.write_all(bytes).map_err(|e| trouble("write", path, e));
    }
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".to_owned());
    let temp = dir.join(format!(".{name}.canopener-{}.tmp", std::process::id()));
    let result = (|| {
        let mut file = fs::File::create(&temp).map_err(|e| trouble("create", &temp, e))?;
        file.write_all(bytes).map_err(|e| trouble("write", &temp, e))?;
        file.sync_all().map_err(|e| trouble("flush", &temp, e))?;
        if backup && path.exists() {
            let bak = backup_path(path);
            fs::copy(path, &bak).map_err(|e| trouble("keep a backup as", &bak, e))?;
        }
        fs::rename(&temp, path).map_err(|e| trouble("replace", path, e))
    })();
    if result.is_err() {
        let _ = fs::remove_file(&temp);
    }
    result
}

/// Creates `dir` and its missing parents (a directory of per-test logs); an existing directory is fine.
pub fn create_dir_all(dir: &Path) -> Result<(), WriteError> {
    fs::create_dir_all(dir).map_err(|source| WriteError {
        action: "create the directory",
        path: dir.to_owned(),
        source,
    })
}

/// Reads a whole file given as input (a firmware image to download, ...).
pub fn read(path: &Path) -> io::Result<Vec<u8>> {
    fs::read(path)
}

/// `FILE.bak` next to `FILE`.
pub fn backup_path(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(".bak");
    PathBuf::from(name)
}

/// Whether `path` names something that exists (a result file the caller would replace).
pub fn exists(path: &Path) -> bool {
    path.exists()
}

/// Whether `path` names an existing regular file (a description or image a system file refers to).
pub fn is_file(path: &Path) -> bool {
    path.is_file()
}

/// Whether two paths name the same existing file.
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (fs::canonicalize(a), fs::canonicalize(b)) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[cfg(unix)]
    #[test]
    fn a_device_file_is_written_in_place_not_replaced() {
        use std::os::unix::fs::FileTypeExt;
        write_atomic(Path::new("/dev/null"), b"discarded", false).unwrap();
        let meta = fs::metadata("/dev/null").unwrap();
        assert!(meta.file_type().is_char_device(), "/dev/null must stay a device");
        assert_eq!(meta.len(), 0);
    }

    #[test]
    fn writes_atomically_and_keeps_a_backup() {
        let dir = canopener_testkit::fixture::ScratchDir::new("runtime-files");
        let path = dir.join("a.eds");
        fs::write(&path, "old").unwrap();
        write_atomic(&path, b"new", true).unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"new");
        assert_eq!(fs::read(backup_path(&path)).unwrap(), b"old");
        assert!(same_file(&path, &dir.join("./a.eds")));
        let leftovers: Vec<_> = fs::read_dir(&*dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
            .collect();
        assert!(leftovers.is_empty());
        let missing_dir = dir.join("no/such/dir/x.eds");
        let err = write_atomic(&missing_dir, b"x", false).unwrap_err();
        assert_eq!(err.action, "create");
        assert!(err.to_string().starts_with("cannot create "), "{err}");
    }
}

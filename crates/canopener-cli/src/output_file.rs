//! Writing result files without losing data: a temporary file in the same directory, then a rename,
//! so a crash or a full disk never leaves a half-written file; optionally the old file kept as `.bak`.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{CliError, CliResult};

/// Writes `bytes` to `path` atomically. With `backup`, an existing `path` is first copied to `path.bak`.
pub(crate) fn write_atomic(path: &Path, bytes: &[u8], backup: bool) -> CliResult {
    let trouble = |what: &str, target: &Path, e: std::io::Error| {
        CliError::EdsTrouble(format!("cannot {what} {}: {e}", target.display()))
    };
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

/// `FILE.bak` next to `FILE`.
pub(crate) fn backup_path(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(".bak");
    PathBuf::from(name)
}

/// Whether two paths name the same existing file.
pub(crate) fn same_file(a: &Path, b: &Path) -> bool {
    match (fs::canonicalize(a), fs::canonicalize(b)) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_atomically_and_keeps_a_backup() {
        let dir = std::env::temp_dir().join(format!("canopener-output-file-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.eds");
        fs::write(&path, "old").unwrap();
        write_atomic(&path, b"new", true).unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"new");
        assert_eq!(fs::read(backup_path(&path)).unwrap(), b"old");
        assert!(same_file(&path, &dir.join("./a.eds")));
        let leftovers: Vec<_> = fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
            .collect();
        assert!(leftovers.is_empty());
        let missing_dir = dir.join("no/such/dir/x.eds");
        assert!(matches!(
            write_atomic(&missing_dir, b"x", false),
            Err(CliError::EdsTrouble(_))
        ));
        fs::remove_dir_all(&dir).unwrap();
    }
}

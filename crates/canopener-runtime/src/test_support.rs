//! What the unit tests share: endpoints on a private in-process bus, and scratch directories.

use std::path::{Path, PathBuf};

use canopener_transport::{BusSpec, CanBus, open};

/// Two endpoints on the ideal virtual bus `name` (at most 16 characters; unique per test, since virtual
/// buses are shared by name within the process).
pub(crate) fn virtual_pair(name: &str) -> (Box<dyn CanBus>, Box<dyn CanBus>) {
    let spec: BusSpec = format!("virtual:{name}")
        .parse()
        .expect("a valid virtual bus name");
    (
        open(&spec).expect("a virtual endpoint"),
        open(&spec).expect("a virtual endpoint"),
    )
}

/// A directory for one test's files, removed when the test ends: a fresh directory under the system's
/// temporary directory, unique to this process and name.
#[derive(Debug)]
pub(crate) struct ScratchDir(PathBuf);

impl ScratchDir {
    /// Creates (or empties) `canopener-runtime-NAME-PID` in the temporary directory.
    pub(crate) fn new(name: &str) -> ScratchDir {
        let dir = std::env::temp_dir().join(format!("canopener-runtime-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("create a scratch directory");
        ScratchDir(dir)
    }

    /// The directory.
    pub(crate) fn path(&self) -> &Path {
        &self.0
    }

    /// Writes a file below the directory (creating its parents) and returns its path.
    pub(crate) fn write(&self, relative: &str, bytes: &[u8]) -> PathBuf {
        let path = self.0.join(relative);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).expect("create a scratch subdirectory");
        }
        std::fs::write(&path, bytes).expect("write a scratch file");
        path
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

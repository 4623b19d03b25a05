//! Reading device descriptions and rule packs from files: the file system side of
//! `canopener-description`.

use std::io;
use std::path::{Path, PathBuf};

use canopener_description::{Description, LoadError};
use canopener_rules::{PackError, RulePack};

/// A description file that could not be read or is not a description canopener can read.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        #[source]
        source: io::Error,
    },
    /// The file was read but is not a description (JSON or XML that cannot be loaded).
    #[error("{}: {source}", path.display())]
    Load {
        /// The file.
        path: PathBuf,
        /// Why it cannot be loaded.
        #[source]
        source: LoadError,
    },
}

/// A rule pack that could not be read or is not a valid pack.
#[derive(Debug, thiserror::Error)]
pub enum PackReadError {
    /// The file could not be read.
    #[error("cannot read rule pack {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        #[source]
        source: io::Error,
    },
    /// The pack has a problem; the error names the pack, line and column.
    #[error(transparent)]
    Pack(#[from] PackError),
}

/// Reads a file's bytes.
pub fn read_bytes(path: &Path) -> Result<Vec<u8>, ReadError> {
    canopener_files::read(path).map_err(|source| ReadError::Io {
        path: path.to_owned(),
        source,
    })
}

/// Reads a description in any format, chosen by the file's extension and content
/// ([`canopener_description::Format::detect`]).
pub fn read_description(path: &Path) -> Result<Description, ReadError> {
    let bytes = read_bytes(path)?;
    let extension = path.extension().map(|e| e.to_string_lossy());
    Description::load(extension.as_deref(), &bytes).map_err(|source| ReadError::Load {
        path: path.to_owned(),
        source,
    })
}

/// Reads and parses rule packs, each named by its path in its errors and findings.
pub fn read_rule_packs(paths: &[PathBuf]) -> Result<Vec<RulePack>, PackReadError> {
    paths
        .iter()
        .map(|path| {
            let text = std::fs::read_to_string(path).map_err(|source| PackReadError::Io {
                path: path.clone(),
                source,
            })?;
            Ok(canopener_rules::parse_pack(&text, &path.display().to_string())?)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use canopener_description::Format;

    use super::*;
    use crate::test_support::ScratchDir;

    #[test]
    fn descriptions_are_read_by_extension_and_errors_name_the_file() {
        let dir = ScratchDir::new("read-description");
        let eds = dir.write("a.eds", b"[FileInfo]\nFileName=a.eds\n");
        let xml = dir.write("b.xdd", b"<notxdd/>");
        let d = read_description(&eds).expect("EDS text loads");
        assert_eq!(d.format, Format::Eds);
        let refused = read_description(&xml).expect_err("not a device description");
        assert!(matches!(refused, ReadError::Load { .. }));
        assert!(
            refused.to_string().starts_with(&format!("{}: ", xml.display())),
            "{refused}"
        );
        let missing = read_description(&dir.path().join("gone.eds")).expect_err("no such file");
        assert!(missing.to_string().starts_with("cannot read "), "{missing}");
    }

    #[test]
    fn rule_packs_are_read_and_their_problems_reported() {
        let dir = ScratchDir::new("read-packs");
        let good = dir.write(
            "good.toml",
            b"[pack]\nname = \"t\"\n\n[[rule]]\nid = \"t/named\"\ndescription = \"d\"\nseverity = \"info\"\n\
              select = \"objects\"\nassert = \"item.name != ''\"\nmessage = \"m\"\n",
        );
        let bad = dir.write("bad.toml", b"[pack\n");
        let packs = read_rule_packs(std::slice::from_ref(&good)).expect("a valid pack");
        assert_eq!(packs.first().map(|p| p.rule_ids()), Some(vec!["t/named"]));
        let error = read_rule_packs(&[good, bad.clone()]).expect_err("the second pack is broken");
        assert!(
            error.to_string().starts_with(&bad.display().to_string()),
            "{error}"
        );
        let gone = read_rule_packs(&[dir.path().join("gone.toml")]).expect_err("no such file");
        assert!(gone.to_string().starts_with("cannot read rule pack "), "{gone}");
    }
}

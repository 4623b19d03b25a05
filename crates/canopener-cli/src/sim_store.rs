//! `canopener sim --state-dir DIR`: saved parameters (1010h "save", 1011h "load") kept in one file per
//! simulated device, so store/restore survives restarts of the simulator.
//!
//! The file `DIR/node-NNN.params` (NNN the node-ID the device started with, in decimal) is plain text, one
//! saved entry per line, `GROUP INDEX SUB HEX`: the group (`communication`, `application`,
//! `manufacturer`), the index and sub-index in hex, and the value's little-endian bytes in hex (nothing for
//! an empty value). Lines starting with `#` are comments. Every change rewrites the whole file atomically
//! (`output_file::write_atomic`), so a crash leaves the old or the new state, never half of one.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use canopener_device::store::{ParameterGroup, ParameterStore, Snapshot, StorageError};
use canopener_od::ObjectKey;

use crate::error::{CliError, CliResult};
use crate::output_file::write_atomic;

/// A [`ParameterStore`] backed by one file.
#[derive(Debug)]
pub(crate) struct FileStore {
    path: PathBuf,
    groups: BTreeMap<ParameterGroup, Snapshot>,
}

impl FileStore {
    /// The store of node `node_id` in `dir` (created if missing), with what its file holds. A file that
    /// does not parse is invalid input (exit 3), named with the line.
    pub(crate) fn open(dir: &Path, node_id: u8) -> CliResult<FileStore> {
        std::fs::create_dir_all(dir).map_err(|err| {
            CliError::output(format!("creating the state directory {}", dir.display()), err)
        })?;
        let path = dir.join(format!("node-{node_id:03}.params"));
        let groups = match std::fs::read_to_string(&path) {
            Ok(text) => parse(&text).map_err(|(line, message)| {
                CliError::InvalidInput(format!(
                    "{}:{line}: {message}; fix or delete the file to start from the defaults",
                    path.display()
                ))
            })?,
            Err(err) if err.kind() == std::io::ErrorKind::NotFound => BTreeMap::new(),
            Err(err) => return Err(CliError::read_file(&path, err)),
        };
        Ok(FileStore { path, groups })
    }

    /// The file this store writes.
    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    fn write(&self, groups: &BTreeMap<ParameterGroup, Snapshot>) -> Result<(), StorageError> {
        write_atomic(&self.path, render(groups).as_bytes(), false)
            .map_err(|err| StorageError::new(err.to_string()))
    }
}

impl ParameterStore for FileStore {
    fn save(&mut self, group: ParameterGroup, values: &[(ObjectKey, Vec<u8>)]) -> Result<(), StorageError> {
        let mut groups = self.groups.clone();
        groups.insert(group, values.to_vec());
        self.write(&groups)?;
        self.groups = groups;
        Ok(())
    }

    fn load(&mut self, group: ParameterGroup) -> Result<Option<Snapshot>, StorageError> {
        Ok(self.groups.get(&group).cloned())
    }

    fn clear(&mut self, group: ParameterGroup) -> Result<(), StorageError> {
        if !self.groups.contains_key(&group) {
            return Ok(());
        }
        let mut groups = self.groups.clone();
        groups.remove(&group);
        self.write(&groups)?;
        self.groups = groups;
        Ok(())
    }
}

fn group_name(group: ParameterGroup) -> &'static str {
    match group {
        ParameterGroup::All => "all",
        ParameterGroup::Communication => "communication",
        ParameterGroup::Application => "application",
        ParameterGroup::Manufacturer => "manufacturer",
    }
}

fn group_of(name: &str) -> Option<ParameterGroup> {
    ParameterGroup::STORED
        .into_iter()
        .find(|g| group_name(*g) == name)
}

/// The file's text. A group saved with no entries still has a line (`GROUP -`), so "saved, empty" and
/// "nothing saved" stay apart.
fn render(groups: &BTreeMap<ParameterGroup, Snapshot>) -> String {
    let mut text =
        String::from("# canopener sim: saved parameters (1010h/1011h); GROUP INDEX SUB VALUE-HEX\n");
    for (group, values) in groups {
        let name = group_name(*group);
        if values.is_empty() {
            let _ = writeln!(text, "{name} -");
        }
        for (key, value) in values {
            let _ = write!(text, "{name} {:04X} {:02X} ", key.index, key.sub);
            for byte in value {
                let _ = write!(text, "{byte:02X}");
            }
            text.push('\n');
        }
    }
    text
}

/// The groups in `text`, or the 1-based line and what is wrong with it.
fn parse(text: &str) -> Result<BTreeMap<ParameterGroup, Snapshot>, (usize, String)> {
    let mut groups: BTreeMap<ParameterGroup, Snapshot> = BTreeMap::new();
    for (number, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split_whitespace().collect();
        let fail = |message: String| (number + 1, message);
        let group = group_of(fields[0]).ok_or_else(|| {
            fail(format!(
                "unknown parameter group '{}' (communication, application or manufacturer)",
                fields[0]
            ))
        })?;
        let values = groups.entry(group).or_default();
        match fields.as_slice() {
            [_, "-"] => {}
            [_, index, sub, rest @ ..] if rest.len() <= 1 => {
                let index = u16::from_str_radix(index, 16)
                    .map_err(|_| fail(format!("index '{index}' is not 4 hex digits")))?;
                let sub = u8::from_str_radix(sub, 16)
                    .map_err(|_| fail(format!("sub-index '{sub}' is not 2 hex digits")))?;
                let value = match rest.first() {
                    Some(hex) => {
                        parse_hex(hex).ok_or_else(|| fail(format!("value '{hex}' is not hex bytes")))?
                    }
                    None => Vec::new(),
                };
                values.push((ObjectKey::new(index, sub), value));
            }
            _ => return Err(fail("expected GROUP INDEX SUB VALUE-HEX".to_owned())),
        }
    }
    for values in groups.values_mut() {
        values.sort_by_key(|(key, _)| *key);
    }
    Ok(groups)
}

fn parse_hex(hex: &str) -> Option<Vec<u8>> {
    if !hex.len().is_multiple_of(2) || !hex.is_ascii() {
        return None;
    }
    (0..hex.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&hex[i..i + 2], 16).ok())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("canopener-sim-store-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    #[test]
    fn saved_groups_survive_reopening_and_clear_forgets_one() {
        let dir = temp_dir("roundtrip");
        let mut store = FileStore::open(&dir, 5).unwrap();
        assert_eq!(store.load(ParameterGroup::Communication).unwrap(), None);
        let comm = vec![
            (ObjectKey::new(0x1017, 0), vec![0x64, 0x00]),
            (ObjectKey::new(0x1008, 0), Vec::new()),
        ];
        store.save(ParameterGroup::Communication, &comm).unwrap();
        store.save(ParameterGroup::Manufacturer, &[]).unwrap();
        assert!(store.path().ends_with("node-005.params"));

        let mut again = FileStore::open(&dir, 5).unwrap();
        let mut sorted = comm.clone();
        sorted.sort_by_key(|(key, _)| *key);
        assert_eq!(again.load(ParameterGroup::Communication).unwrap(), Some(sorted));
        assert_eq!(
            again.load(ParameterGroup::Manufacturer).unwrap(),
            Some(Vec::new())
        );
        assert_eq!(again.load(ParameterGroup::Application).unwrap(), None);

        again.clear(ParameterGroup::Communication).unwrap();
        let mut third = FileStore::open(&dir, 5).unwrap();
        assert_eq!(third.load(ParameterGroup::Communication).unwrap(), None);
        assert_eq!(
            third.load(ParameterGroup::Manufacturer).unwrap(),
            Some(Vec::new())
        );
        // Another node has its own file.
        let mut other = FileStore::open(&dir, 6).unwrap();
        assert_eq!(other.load(ParameterGroup::Manufacturer).unwrap(), None);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_corrupt_file_is_invalid_input_naming_the_line() {
        let dir = temp_dir("corrupt");
        std::fs::create_dir_all(&dir).unwrap();
        for (text, needle) in [
            (
                "# c\ncommunication 1017 00 64\nbogus 1 2 3\n",
                "node-007.params:3: unknown parameter group",
            ),
            ("communication 10170 00 6400\n", ":1: index"),
            ("application 6000 1FF 00\n", ":1: sub-index"),
            ("application 6000 01 0\n", ":1: value '0'"),
            ("application 6000 01 00 11\n", ":1: expected"),
        ] {
            std::fs::write(dir.join("node-007.params"), text).unwrap();
            let err = FileStore::open(&dir, 7).unwrap_err();
            assert_eq!(err.exit_code(), 3);
            assert!(err.to_string().contains(needle), "{err}");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_write_failure_is_a_storage_error_and_keeps_the_old_state() {
        let dir = temp_dir("readonly");
        let mut store = FileStore::open(&dir, 9).unwrap();
        store
            .save(
                ParameterGroup::Application,
                &[(ObjectKey::new(0x6200, 1), vec![1])],
            )
            .unwrap();
        // Point the store at a directory that does not exist: the rename cannot happen.
        store.path = dir.join("missing").join("node-009.params");
        let err = store
            .save(
                ParameterGroup::Application,
                &[(ObjectKey::new(0x6200, 1), vec![2])],
            )
            .unwrap_err();
        assert!(err.message.contains("cannot"), "{err}");
        assert_eq!(
            store.load(ParameterGroup::Application).unwrap(),
            Some(vec![(ObjectKey::new(0x6200, 1), vec![1])])
        );
        assert!(store.clear(ParameterGroup::Application).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}

//! The state directory of simulated devices (`canopener sim --state-dir DIR`): what a real device keeps
//! in non-volatile memory, in files per simulated device, so that it survives restarts of the simulator:
//! saved parameters (CiA 301 §7.5.2.13 1010h "save", §7.5.2.14 1011h "load") and the LSS configuration
//! (CiA 305 store configuration: node-ID and bit rate).
//!
//! A device whose node-ID is fixed (a DCF's, or `--node-id`) keeps its parameters in
//! `DIR/node-NNN.params` (NNN in decimal). A device that gets its node-ID by LSS is known by its LSS
//! address instead: `DIR/lss-VVVVVVVV-PPPPPPPP-RRRRRRRR-SSSSSSSS.params` for the parameters and `.lss`
//! for the stored LSS configuration, from which it starts with the stored node-ID next time.
//!
//! A `.params` file is plain text, one saved entry per line, `GROUP INDEX SUB HEX`: the group (`communication`, `application`,
//! `manufacturer`), the index and sub-index in hex, and the value's little-endian bytes in hex (nothing for
//! an empty value). Lines starting with `#` are comments. Every change rewrites the whole file atomically
//! ([`write_atomic`]), so a crash leaves the old or the new state, never half of one.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use canopener_device::lss_slave::{BitTiming, LssStorage, LssStoreError, StoredConfiguration};
use canopener_device::store::{ParameterGroup, ParameterStore, Snapshot, StorageError};
use canopener_od::ObjectKey;
use canopener_wire::LssAddress;
use canopener_wire::NodeId;

use canopener_files::write_atomic;

/// Why a state file could not be opened. Writing later is reported to the device (it answers the
/// 1010h write or the LSS store with an error), not here.
#[derive(Debug, thiserror::Error)]
pub enum StateStoreError {
    /// The state directory could not be created.
    #[error("creating the state directory {}: {source}", dir.display())]
    CreateDir {
        /// The directory.
        dir: PathBuf,
        /// The operating system's reason.
        #[source]
        source: std::io::Error,
    },
    /// A state file exists but could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        #[source]
        source: std::io::Error,
    },
    /// A state file does not say what this store writes.
    #[error("{}:{line}: {message}; fix or delete the file to {remedy}", path.display())]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// The 1-based line.
        line: usize,
        /// What is wrong with the line.
        message: String,
        /// What deleting the file leads to (`start from the defaults`, `start unconfigured`).
        remedy: &'static str,
    },
}

/// A [`ParameterStore`] backed by one file.
#[derive(Debug)]
pub struct FileStore {
    path: PathBuf,
    groups: BTreeMap<ParameterGroup, Snapshot>,
}

impl FileStore {
    /// The store of node `node_id` in `dir` (created if missing), with what its file holds; a file that
    /// does not parse is refused, naming the line.
    pub fn open(dir: &Path, node_id: u8) -> Result<FileStore, StateStoreError> {
        FileStore::open_named(dir, &format!("node-{node_id:03}"))
    }

    /// The store of the device with LSS address `address` in `dir`.
    pub fn open_lss(dir: &Path, address: &LssAddress) -> Result<FileStore, StateStoreError> {
        FileStore::open_named(dir, &lss_stem(address))
    }

    fn open_named(dir: &Path, stem: &str) -> Result<FileStore, StateStoreError> {
        create_state_dir(dir)?;
        let path = dir.join(format!("{stem}.params"));
        let groups = match std::fs::read_to_string(&path) {
            Ok(text) => parse(&text).map_err(|(line, message)| StateStoreError::Corrupt {
                path: path.clone(),
                line,
                message,
                remedy: "start from the defaults",
            })?,
            Err(err) if err.kind() == std::io::ErrorKind::NotFound => BTreeMap::new(),
            Err(source) => return Err(StateStoreError::Read { path, source }),
        };
        Ok(FileStore { path, groups })
    }

    /// The file this store writes.
    pub fn path(&self) -> &Path {
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

/// The LSS configuration a device stored (CiA 305 store configuration), in `DIR/lss-ADDRESS.lss`:
/// lines `node-id N` (decimal, or `none` for unconfigured) and `bit-timing TABLE INDEX`.
#[derive(Debug)]
pub struct LssFile {
    path: PathBuf,
    /// Whether the file holds a `node-id` line: something was stored.
    stored: bool,
    node_id: Option<NodeId>,
    bit_timing: Option<BitTiming>,
}

impl LssFile {
    /// The stored LSS configuration of the device with LSS address `address` (none stored yet if the
    /// file does not exist); a file that does not parse is refused, naming the line.
    pub fn open(dir: &Path, address: &LssAddress) -> Result<LssFile, StateStoreError> {
        create_state_dir(dir)?;
        let path = dir.join(format!("{}.lss", lss_stem(address)));
        let mut file = LssFile {
            path,
            stored: false,
            node_id: None,
            bit_timing: None,
        };
        let text = match std::fs::read_to_string(&file.path) {
            Ok(text) => text,
            Err(err) if err.kind() == std::io::ErrorKind::NotFound => return Ok(file),
            Err(source) => {
                return Err(StateStoreError::Read {
                    path: file.path,
                    source,
                });
            }
        };
        for (number, line) in (1..).zip(text.lines()) {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let words: Vec<&str> = line.split_whitespace().collect();
            match words.as_slice() {
                ["node-id", "none"] => {
                    file.stored = true;
                    file.node_id = None;
                }
                ["node-id", id] => {
                    file.stored = true;
                    file.node_id = Some(id.parse().ok().and_then(NodeId::new).ok_or_else(|| {
                        bad_lss_line(&file.path, number, "the node-ID must be 1 to 127 or `none`")
                    })?);
                }
                ["bit-timing", table, index] => {
                    let (Ok(table), Ok(index)) = (table.parse(), index.parse()) else {
                        return Err(bad_lss_line(
                            &file.path,
                            number,
                            "write `bit-timing TABLE INDEX`, e.g. `bit-timing 0 4`",
                        ));
                    };
                    file.bit_timing = Some(BitTiming { table, index });
                }
                _ => {
                    return Err(bad_lss_line(
                        &file.path,
                        number,
                        "expected `node-id N`, `node-id none` or `bit-timing TABLE INDEX`",
                    ));
                }
            }
        }
        Ok(file)
    }

    /// The node-ID stored, if any.
    pub fn node_id(&self) -> Option<NodeId> {
        self.node_id
    }
}

impl LssStorage for LssFile {
    fn store(&mut self, node_id: Option<NodeId>, bit_timing: Option<BitTiming>) -> Result<(), LssStoreError> {
        let mut text = String::from(
            "# LSS configuration stored by the simulated device (CiA 305 store configuration)\n",
        );
        match node_id {
            Some(node) => {
                let _ = writeln!(text, "node-id {}", node.get());
            }
            None => text.push_str("node-id none\n"),
        }
        if let Some(timing) = bit_timing {
            let _ = writeln!(text, "bit-timing {} {}", timing.table, timing.index);
        }
        write_atomic(&self.path, text.as_bytes(), false).map_err(|_| LssStoreError::MediaAccess)?;
        self.stored = true;
        self.node_id = node_id;
        self.bit_timing = bit_timing;
        Ok(())
    }

    fn stored(&self) -> Option<StoredConfiguration> {
        self.stored.then_some(StoredConfiguration {
            node_id: self.node_id,
            bit_timing: self.bit_timing,
        })
    }
}

fn bad_lss_line(path: &Path, line: usize, message: &str) -> StateStoreError {
    StateStoreError::Corrupt {
        path: path.to_owned(),
        line,
        message: message.to_owned(),
        remedy: "start unconfigured",
    }
}

fn lss_stem(address: &LssAddress) -> String {
    format!(
        "lss-{:08X}-{:08X}-{:08X}-{:08X}",
        address.vendor_id, address.product_code, address.revision_number, address.serial_number
    )
}

fn create_state_dir(dir: &Path) -> Result<(), StateStoreError> {
    std::fs::create_dir_all(dir).map_err(|source| StateStoreError::CreateDir {
        dir: dir.to_owned(),
        source,
    })
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
        // A line that is not blank has a first field.
        let Some(&first) = fields.first() else {
            continue;
        };
        let fail = |message: String| (number + 1, message);
        let group = group_of(first).ok_or_else(|| {
            fail(format!(
                "unknown parameter group '{first}' (communication, application or manufacturer)"
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

    fn temp_dir(name: &str) -> canopener_testkit::fixture::ScratchDir {
        canopener_testkit::fixture::ScratchDir::new(&format!("state-store-{name}"))
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
    }

    #[test]
    fn a_corrupt_file_is_refused_naming_the_line() {
        let dir = temp_dir("corrupt");
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
            canopener_testkit::fixture::write(dir.join("node-007.params"), text).unwrap();
            let err = FileStore::open(&dir, 7).unwrap_err();
            assert!(matches!(err, StateStoreError::Corrupt { .. }), "{err:?}");
            assert!(err.to_string().contains(needle), "{err}");
        }
    }

    #[test]
    fn a_stored_lss_configuration_is_read_back_per_lss_address() {
        let dir = temp_dir("lss-file");
        let address = LssAddress {
            vendor_id: 0xABC,
            product_code: 0x401,
            revision_number: 0x10002,
            serial_number: 7,
        };
        let mut file = LssFile::open(&dir, &address).unwrap();
        assert_eq!(file.node_id(), None, "nothing stored yet");
        assert_eq!(file.stored(), None);
        let timing = BitTiming { table: 0, index: 4 };
        file.store(NodeId::new(12), Some(timing)).unwrap();
        let path = dir.join("lss-00000ABC-00000401-00010002-00000007.lss");
        assert_eq!(
            std::fs::read_to_string(&path)
                .unwrap()
                .lines()
                .skip(1)
                .collect::<Vec<_>>(),
            ["node-id 12", "bit-timing 0 4"]
        );
        let again = LssFile::open(&dir, &address).unwrap();
        assert_eq!(again.node_id(), NodeId::new(12));
        assert_eq!(again.bit_timing, Some(timing));
        let stored = StoredConfiguration {
            node_id: NodeId::new(12),
            bit_timing: Some(timing),
        };
        assert_eq!((file.stored(), again.stored()), (Some(stored), Some(stored)));
        // Storing "unconfigured" (FFh) is kept as such.
        file.store(None, None).unwrap();
        let unconfigured = LssFile::open(&dir, &address).unwrap();
        assert_eq!(unconfigured.node_id(), None);
        assert_eq!(
            unconfigured.stored(),
            Some(StoredConfiguration {
                node_id: None,
                bit_timing: None
            })
        );
        // Another serial number is another device.
        let other = LssAddress {
            serial_number: 8,
            ..address
        };
        assert_eq!(LssFile::open(&dir, &other).unwrap().node_id(), None);
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
    }
}

//! Store parameters 1010h and restore default parameters 1011h (CiA 301, object 1010h and object
//! 1011h).
//!
//! Each sub-index from 1 names a parameter group ([`ParameterGroup`]): 1 all parameters, 2
//! communication parameters (1000h–1FFFh), 3 application parameters (6000h–9FFFh), 4
//! manufacturer-specific parameters (2000h–5FFFh). (CiA 301 fixes sub-indices 1..3; the ranges of 3
//! and 4 vary between vendors, these are the common ones.)
//!
//! - Writing the signature `save` ([`SAVE_SIGNATURE`], 65766173h, bytes `73 61 76 65`) to 1010h:x
//!   takes a snapshot of the group's parameters (the readable and writable entries of its ranges,
//!   without 1003h, 1010h and 1011h) and hands it to the [`ParameterStore`] the `Device` or CLI
//!   provides. Saved values become the power-on values: they survive resets and power-off.
//! - Writing the signature `load` ([`LOAD_SIGNATURE`], 64616F6Ch, bytes `6C 6F 61 64`) to 1011h:x
//!   forgets the group's saved values. The defaults take effect after the next reset, not at once:
//!   reset node for every group, reset communication for the communication group (CiA 301, and the
//!   CCT writes `load`, resets the node, then expects the defaults). Until then the group is
//!   reported as pending ([`StoreRestore::pending_restore`], [`StoreEvent::RestorePending`]).
//! - Any other value is refused with 0800 0020h and nothing is stored or restored (the CCT writes
//!   "wron" to 1011h:01 and expects exactly that); a storage failure is refused with 0606 0000h.
//! - Reading 1010h:x gives the capability bits (bit 0: saves on command), 1011h:x bit 0 (can restore
//!   defaults); [`StoreRestore::sync_od`] puts them into the dictionary.
//!
//! The `Device` calls [`StoreRestore::check_download`] from its
//! [`SdoHooks::check_download`](crate::sdo_server::SdoHooks), [`StoreRestore::sync_od`] after each
//! download (so the dictionary shows capability bits, not the signature written), and, when the NMT
//! slave reports a reset, reloads the defaults of the groups concerned and then applies the saved
//! values with [`StoreRestore::apply_saved`]: on `ResetApplication` for the application and
//! manufacturer groups, on `ResetCommunication` for the communication group.

use std::collections::{BTreeMap, VecDeque};

use canopener_od::{Access, DynamicOd, ObjectKey};
use canopener_wire::abort;

/// The signature that saves parameters: "save" read as a little-endian UNSIGNED32.
pub const SAVE_SIGNATURE: u32 = 0x6576_6173;
/// The signature that restores default parameters: "load" read as a little-endian UNSIGNED32.
pub const LOAD_SIGNATURE: u32 = 0x6461_6F6C;
/// The store parameters object.
pub const STORE_PARAMETERS: u16 = 0x1010;
/// The restore default parameters object.
pub const RESTORE_DEFAULT_PARAMETERS: u16 = 0x1011;
/// 1010h:x capability bit 0: the device saves parameters on command.
pub const SAVES_ON_COMMAND: u32 = 0x0000_0001;
/// 1010h:x capability bit 1: the device saves parameters autonomously.
pub const SAVES_AUTONOMOUSLY: u32 = 0x0000_0002;
/// 1011h:x capability bit 0: the device restores default parameters.
pub const RESTORES_DEFAULTS: u32 = 0x0000_0001;

/// Entries never saved: the error history 1003h (a runtime record) and the command objects 1010h
/// and 1011h themselves.
const NEVER_SAVED: [u16; 3] = [0x1003, STORE_PARAMETERS, RESTORE_DEFAULT_PARAMETERS];

/// A group of parameters saved and restored together; the sub-index of 1010h/1011h that names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ParameterGroup {
    /// Sub-index 1: all parameters (the three groups below).
    All,
    /// Sub-index 2: communication parameters, 1000h–1FFFh.
    Communication,
    /// Sub-index 3: application parameters, 6000h–9FFFh.
    Application,
    /// Sub-index 4: manufacturer-specific parameters, 2000h–5FFFh.
    Manufacturer,
}

impl ParameterGroup {
    /// The groups a [`ParameterStore`] keeps: every group but [`ParameterGroup::All`].
    pub const STORED: [ParameterGroup; 3] = [
        ParameterGroup::Communication,
        ParameterGroup::Application,
        ParameterGroup::Manufacturer,
    ];

    /// The group of 1010h/1011h sub-index `sub`, if it is one of 1..=4.
    pub const fn from_sub(sub: u8) -> Option<ParameterGroup> {
        match sub {
            1 => Some(ParameterGroup::All),
            2 => Some(ParameterGroup::Communication),
            3 => Some(ParameterGroup::Application),
            4 => Some(ParameterGroup::Manufacturer),
            _ => None,
        }
    }

    /// The 1010h/1011h sub-index of the group.
    pub const fn sub(self) -> u8 {
        match self {
            ParameterGroup::All => 1,
            ParameterGroup::Communication => 2,
            ParameterGroup::Application => 3,
            ParameterGroup::Manufacturer => 4,
        }
    }

    /// Whether object `index` belongs to the group.
    pub const fn contains(self, index: u16) -> bool {
        match self {
            ParameterGroup::All => matches!(index, 0x1000..=0x9FFF),
            ParameterGroup::Communication => matches!(index, 0x1000..=0x1FFF),
            ParameterGroup::Application => matches!(index, 0x6000..=0x9FFF),
            ParameterGroup::Manufacturer => matches!(index, 0x2000..=0x5FFF),
        }
    }

    /// The stored groups this group stands for: itself, or the three for [`ParameterGroup::All`].
    pub fn parts(self) -> &'static [ParameterGroup] {
        match self {
            ParameterGroup::All => &ParameterGroup::STORED,
            ParameterGroup::Communication => &ParameterGroup::STORED[0..1],
            ParameterGroup::Application => &ParameterGroup::STORED[1..2],
            ParameterGroup::Manufacturer => &ParameterGroup::STORED[2..3],
        }
    }
}

/// Saved values: entries and their little-endian bytes, in ascending key order.
pub type Snapshot = Vec<(ObjectKey, Vec<u8>)>;

/// A failure of the storage behind a [`ParameterStore`] (a file that cannot be written, say). SDO
/// answers it with 0606 0000h (access failed due to a hardware error).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("parameter storage failed: {message}")]
pub struct StorageError {
    /// What went wrong, for the log.
    pub message: String,
}

impl StorageError {
    /// A storage error saying `message`.
    pub fn new(message: impl Into<String>) -> StorageError {
        StorageError {
            message: message.into(),
        }
    }
}

/// Where saved parameters live: a file per simulated device (the CLI), memory (tests), flash on a
/// real device. Groups passed are always one of [`ParameterGroup::STORED`].
pub trait ParameterStore {
    /// Replaces the saved values of `group` with `values`.
    fn save(&mut self, group: ParameterGroup, values: &[(ObjectKey, Vec<u8>)]) -> Result<(), StorageError>;

    /// The saved values of `group`, or `None` if none are saved (the defaults apply).
    fn load(&mut self, group: ParameterGroup) -> Result<Option<Snapshot>, StorageError>;

    /// Forgets the saved values of `group`, so the defaults apply from the next reset on.
    fn clear(&mut self, group: ParameterGroup) -> Result<(), StorageError>;
}

/// A [`ParameterStore`] in memory, for tests and for devices whose saved values need not outlive
/// the process. It can be told to fail, to test the 0606 0000h path.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct MemoryStore {
    groups: BTreeMap<ParameterGroup, Snapshot>,
    failing: bool,
}

impl MemoryStore {
    /// An empty store.
    pub fn new() -> MemoryStore {
        MemoryStore::default()
    }

    /// Makes every later call fail (or succeed again).
    pub fn set_failing(&mut self, failing: bool) {
        self.failing = failing;
    }

    /// The saved values of `group`, if any.
    pub fn saved(&self, group: ParameterGroup) -> Option<&Snapshot> {
        self.groups.get(&group)
    }

    fn check(&self) -> Result<(), StorageError> {
        if self.failing {
            return Err(StorageError::new("the memory store was told to fail"));
        }
        Ok(())
    }
}

impl ParameterStore for MemoryStore {
    fn save(&mut self, group: ParameterGroup, values: &[(ObjectKey, Vec<u8>)]) -> Result<(), StorageError> {
        self.check()?;
        self.groups.insert(group, values.to_vec());
        Ok(())
    }

    fn load(&mut self, group: ParameterGroup) -> Result<Option<Snapshot>, StorageError> {
        self.check()?;
        Ok(self.groups.get(&group).cloned())
    }

    fn clear(&mut self, group: ParameterGroup) -> Result<(), StorageError> {
        self.check()?;
        self.groups.remove(&group);
        Ok(())
    }
}

/// Why a 1010h/1011h write was refused; [`StoreError::abort_code`] is the SDO abort code.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum StoreError {
    /// Not the `save` signature on 1010h or not the `load` signature on 1011h (0800 0020h).
    #[error("{key}: {value:#010X} is not the signature {expected:#010X}; nothing was stored or restored")]
    WrongSignature {
        /// The entry written.
        key: ObjectKey,
        /// The value written.
        value: u32,
        /// The signature that entry takes.
        expected: u32,
    },
    /// A sub-index above 4: the dictionary has it but this device does not know which parameters it
    /// stands for (0800 0020h).
    #[error("{key}: this device saves and restores sub-indices 1 to 4 only")]
    UnsupportedGroup {
        /// The entry written.
        key: ObjectKey,
    },
    /// The storage failed (0606 0000h).
    #[error(transparent)]
    Storage(#[from] StorageError),
}

impl StoreError {
    /// The SDO abort code an SDO server sends for this error.
    pub fn abort_code(&self) -> u32 {
        match self {
            StoreError::WrongSignature { .. } | StoreError::UnsupportedGroup { .. } => abort::CANNOT_TRANSFER,
            StoreError::Storage(_) => abort::HARDWARE_ERROR,
        }
    }
}

/// What [`StoreRestore`] reports to the `Device`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StoreEvent {
    /// The parameters of the group were saved.
    Saved {
        /// The group (as written: [`ParameterGroup::All`] for 1010h:01).
        group: ParameterGroup,
    },
    /// The saved values of the group were forgotten; its defaults take effect at the next reset.
    RestorePending {
        /// The group (as written).
        group: ParameterGroup,
    },
    /// A reset brought a pending group back to its defaults.
    RestoreTookEffect {
        /// The stored group.
        group: ParameterGroup,
    },
    /// A saved value could not be applied (the entry no longer exists or its length changed, say
    /// after the EDS changed); the entry keeps its default.
    SavedValueSkipped {
        /// The entry.
        key: ObjectKey,
    },
}

/// The store/restore service of one node.
#[derive(Debug, Clone, Default)]
pub struct StoreRestore {
    /// Stored groups whose defaults take effect at the next reset.
    pending: Vec<ParameterGroup>,
    events: VecDeque<StoreEvent>,
}

impl StoreRestore {
    /// The service, with nothing pending.
    pub fn new() -> StoreRestore {
        StoreRestore::default()
    }

    /// The value reading 1010h:`sub` or 1011h:`sub` gives: the capability bits for sub-indices 1..=4
    /// ([`SAVES_ON_COMMAND`], [`RESTORES_DEFAULTS`]), 0 above, `None` for other objects and for
    /// sub-index 0 (the dictionary's highest sub-index).
    pub fn capability(&self, key: ObjectKey) -> Option<u32> {
        let supported = ParameterGroup::from_sub(key.sub).is_some();
        match key.index {
            _ if key.sub == 0 => None,
            STORE_PARAMETERS => Some(if supported { SAVES_ON_COMMAND } else { 0 }),
            RESTORE_DEFAULT_PARAMETERS => Some(if supported { RESTORES_DEFAULTS } else { 0 }),
            _ => None,
        }
    }

    /// Sets 1010h:01.. and 1011h:01.. in `od` to their capability bits (as the application, whatever
    /// the access type), so SDO uploads read them; entries missing from `od` are skipped. Call it
    /// after building the dictionary and after every download to 1010h/1011h.
    pub fn sync_od(&self, od: &mut DynamicOd) {
        for index in [STORE_PARAMETERS, RESTORE_DEFAULT_PARAMETERS] {
            let keys: Vec<ObjectKey> = od.object(index).iter().map(|e| e.key()).collect();
            for key in keys {
                if let Some(value) = self.capability(key) {
                    let _ = od.set_value(key, &value.to_le_bytes());
                }
            }
        }
    }

    /// Stored groups whose defaults take effect at the next reset.
    pub fn pending_restore(&self) -> &[ParameterGroup] {
        &self.pending
    }

    /// Carries out an SDO download of `data` to `key`, before the dictionary stores it (called
    /// from the `Device`'s [`SdoHooks::check_download`](crate::sdo_server::SdoHooks)): `save` on
    /// 1010h:01..04 saves a snapshot of `od`, `load` on 1011h:01..04 forgets saved values. Keys other
    /// than 1010h/1011h sub 1.., and data that is not 4 bytes (the dictionary refuses it), pass
    /// untouched.
    pub fn check_download(
        &mut self,
        key: ObjectKey,
        data: &[u8],
        od: &DynamicOd,
        store: &mut dyn ParameterStore,
    ) -> Result<(), StoreError> {
        let &[a, b, c, d] = data else { return Ok(()) };
        let value = u32::from_le_bytes([a, b, c, d]);
        let expected = match key.index {
            STORE_PARAMETERS => SAVE_SIGNATURE,
            RESTORE_DEFAULT_PARAMETERS => LOAD_SIGNATURE,
            _ => return Ok(()),
        };
        if key.sub == 0 {
            return Ok(());
        }
        if value != expected {
            return Err(StoreError::WrongSignature { key, value, expected });
        }
        let group = ParameterGroup::from_sub(key.sub).ok_or(StoreError::UnsupportedGroup { key })?;
        if key.index == STORE_PARAMETERS {
            // Take every snapshot first, so a failure half-way leaves no group half-saved in memory.
            let snapshots: Vec<(ParameterGroup, Snapshot)> = group
                .parts()
                .iter()
                .map(|&part| (part, snapshot(od, part)))
                .collect();
            for (part, values) in &snapshots {
                store.save(*part, values)?;
            }
            self.events.push_back(StoreEvent::Saved { group });
        } else {
            for &part in group.parts() {
                store.clear(part)?;
                if !self.pending.contains(&part) {
                    self.pending.push(part);
                }
            }
            self.events.push_back(StoreEvent::RestorePending { group });
        }
        Ok(())
    }

    /// Applies the saved values of the stored `group` to `od` (as the application, whatever the
    /// access type) after the `Device` has reloaded the group's defaults on a reset; a pending
    /// restore of the group has now taken effect. Saved values that no longer fit are skipped and
    /// reported. Returns the number of values applied.
    pub fn apply_saved(
        &mut self,
        group: ParameterGroup,
        od: &mut DynamicOd,
        store: &mut dyn ParameterStore,
    ) -> Result<usize, StorageError> {
        let mut applied = 0;
        for &part in group.parts() {
            if let Some(position) = self.pending.iter().position(|&g| g == part) {
                self.pending.remove(position);
                self.events
                    .push_back(StoreEvent::RestoreTookEffect { group: part });
            }
            for (key, value) in store.load(part)?.unwrap_or_default() {
                if part.contains(key.index) && od.set_value(key, &value).is_ok() {
                    applied += 1;
                } else {
                    self.events.push_back(StoreEvent::SavedValueSkipped { key });
                }
            }
        }
        Ok(applied)
    }

    /// The next event for the `Device`.
    pub fn poll_event(&mut self) -> Option<StoreEvent> {
        self.events.pop_front()
    }
}

/// The parameters of `group` in `od`: every readable and writable entry (`rw`, `rwr`, `rww`) of the
/// group's ranges except 1003h, 1010h and 1011h, with its current value, in key order.
pub fn snapshot(od: &DynamicOd, group: ParameterGroup) -> Snapshot {
    od.iter()
        .filter(|e| group.contains(e.key().index) && !NEVER_SAVED.contains(&e.key().index))
        .filter(|e| matches!(e.access(), Access::Rw | Access::Rwr | Access::Rww))
        .map(|e| (e.key(), e.value().to_vec()))
        .collect()
}

/// Sets every value of `values` in `od` (as the application, whatever the access type). Returns the
/// keys that could not be set (missing entry, wrong length).
pub fn restore(od: &mut DynamicOd, values: &[(ObjectKey, Vec<u8>)]) -> Vec<ObjectKey> {
    values
        .iter()
        .filter(|(key, value)| od.set_value(*key, value).is_err())
        .map(|(key, _)| *key)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sdo_server::SdoHooks;
    use canopener_od::{DataType, Entry};

    const SAVE: [u8; 4] = *b"save";
    const LOAD: [u8; 4] = *b"load";

    fn u32_entry(index: u16, sub: u8, access: Access, value: u32) -> Entry {
        Entry::new(
            ObjectKey::new(index, sub),
            DataType::UNSIGNED32,
            access,
            &value.to_le_bytes(),
        )
        .unwrap()
    }

    fn u8_entry(index: u16, sub: u8, access: Access, value: u8) -> Entry {
        Entry::new(ObjectKey::new(index, sub), DataType::UNSIGNED8, access, &[value]).unwrap()
    }

    /// Defaults of a small device: 1010h/1011h with sub-indices 1..4, some communication,
    /// manufacturer and application parameters, and entries that are never saved.
    fn defaults() -> DynamicOd {
        let mut od = DynamicOd::with_capacity(32);
        for entry in [
            u32_entry(0x1000, 0, Access::Ro, 0x0003_0191),
            u8_entry(0x1003, 0, Access::Rw, 0),
            u8_entry(0x1010, 0, Access::Ro, 4),
            u8_entry(0x1011, 0, Access::Ro, 4),
            u32_entry(0x1017, 0, Access::Rw, 0),
            u32_entry(0x1800, 1, Access::Rw, 0x185),
            u32_entry(0x2000, 0, Access::Rw, 7),
            u8_entry(0x6000, 1, Access::Ro, 0),
            u8_entry(0x6200, 1, Access::Rww, 0),
            u32_entry(0x1F51, 1, Access::Wo, 0),
        ] {
            od.insert(entry).unwrap();
        }
        for sub in 1..=5 {
            od.insert(u32_entry(0x1010, sub, Access::Rw, 0)).unwrap();
            od.insert(u32_entry(0x1011, sub, Access::Rw, 0)).unwrap();
        }
        od
    }

    /// A device's use of the service: the hook before the SDO server stores, `sync_od` after.
    struct Hooks<'a> {
        service: &'a mut StoreRestore,
        store: &'a mut MemoryStore,
    }

    impl SdoHooks for Hooks<'_> {
        fn check_download(&mut self, key: ObjectKey, data: &[u8], od: &DynamicOd) -> Result<(), u32> {
            self.service
                .check_download(key, data, od, self.store)
                .map_err(|e| e.abort_code())
        }
    }

    /// Writes `data` to `key` through a real SDO server (expedited download) and returns the
    /// response's command byte and abort code.
    fn sdo_write(
        service: &mut StoreRestore,
        store: &mut MemoryStore,
        od: &mut DynamicOd,
        key: ObjectKey,
        data: [u8; 4],
    ) -> Result<(), u32> {
        use crate::sdo_server::SdoServer;
        let mut server = SdoServer::default_for_node(5).unwrap();
        let [i0, i1] = key.index.to_le_bytes();
        let [d0, d1, d2, d3] = data;
        let request = [0x23, i0, i1, key.sub, d0, d1, d2, d3];
        let mut hooks = Hooks { service, store };
        server.handle_request_with(canopener_can::Instant::ZERO, &request, od, &mut hooks);
        hooks.service.sync_od(od);
        let reply = server.poll_transmit().unwrap();
        match reply.data() {
            [0x60, ..] => Ok(()),
            [0x80, _, _, _, a, b, c, d] => Err(u32::from_le_bytes([*a, *b, *c, *d])),
            other => panic!("unexpected reply {other:02X?}"),
        }
    }

    fn value(od: &DynamicOd, index: u16, sub: u8) -> Vec<u8> {
        od.read(ObjectKey::new(index, sub)).unwrap().to_vec()
    }

    #[test]
    fn signatures_are_the_documented_numbers() {
        assert_eq!(u32::from_le_bytes(SAVE), SAVE_SIGNATURE);
        assert_eq!(u32::from_le_bytes(LOAD), LOAD_SIGNATURE);
    }

    #[test]
    fn reading_gives_capability_bits() {
        let mut od = defaults();
        let service = StoreRestore::new();
        service.sync_od(&mut od);
        for sub in 1..=4 {
            assert_eq!(value(&od, 0x1010, sub), [1, 0, 0, 0], "1010h:{sub}");
            assert_eq!(value(&od, 0x1011, sub), [1, 0, 0, 0], "1011h:{sub}");
        }
        assert_eq!(value(&od, 0x1010, 5), [0; 4], "sub-index 5 is not supported");
        assert_eq!(value(&od, 0x1010, 0), [4], "sub-index 0 untouched");
        assert_eq!(service.capability(ObjectKey::new(0x1017, 0)), None);
    }

    #[test]
    fn snapshot_takes_writable_parameters_of_the_group() {
        let od = defaults();
        let keys = |group| {
            snapshot(&od, group)
                .into_iter()
                .map(|(k, _)| k)
                .collect::<Vec<_>>()
        };
        let k = ObjectKey::new;
        assert_eq!(keys(ParameterGroup::Communication), [k(0x1017, 0), k(0x1800, 1)]);
        assert_eq!(keys(ParameterGroup::Manufacturer), [k(0x2000, 0)]);
        assert_eq!(keys(ParameterGroup::Application), [k(0x6200, 1)]);
        assert_eq!(
            keys(ParameterGroup::All),
            [k(0x1017, 0), k(0x1800, 1), k(0x2000, 0), k(0x6200, 1)]
        );
    }

    #[test]
    fn saved_values_survive_reset() {
        let mut od = defaults();
        let (mut service, mut store) = (StoreRestore::new(), MemoryStore::new());
        od.write(ObjectKey::new(0x1017, 0), &100u32.to_le_bytes())
            .unwrap();
        od.write(ObjectKey::new(0x2000, 0), &9u32.to_le_bytes()).unwrap();
        let save_comm = ObjectKey::new(0x1010, 2);
        assert_eq!(
            sdo_write(&mut service, &mut store, &mut od, save_comm, SAVE),
            Ok(())
        );
        assert_eq!(
            value(&od, 0x1010, 2),
            [1, 0, 0, 0],
            "reads back capability bits, not 'save'"
        );
        assert_eq!(
            service.poll_event(),
            Some(StoreEvent::Saved {
                group: ParameterGroup::Communication
            })
        );
        assert_eq!(
            store.saved(ParameterGroup::Communication).unwrap(),
            &vec![
                (ObjectKey::new(0x1017, 0), 100u32.to_le_bytes().to_vec()),
                (ObjectKey::new(0x1800, 1), 0x185u32.to_le_bytes().to_vec())
            ]
        );
        assert_eq!(store.saved(ParameterGroup::Manufacturer), None);
        // Reset node: the Device reloads the defaults, then applies what was saved.
        let mut od = defaults();
        for group in [
            ParameterGroup::Manufacturer,
            ParameterGroup::Application,
            ParameterGroup::Communication,
        ] {
            service.apply_saved(group, &mut od, &mut store).unwrap();
        }
        assert_eq!(value(&od, 0x1017, 0), 100u32.to_le_bytes());
        assert_eq!(value(&od, 0x2000, 0), 7u32.to_le_bytes(), "2000h was not saved");
        assert_eq!(service.poll_event(), None);
    }

    #[test]
    fn save_all_saves_every_group() {
        let mut od = defaults();
        let (mut service, mut store) = (StoreRestore::new(), MemoryStore::new());
        od.write(ObjectKey::new(0x2000, 0), &9u32.to_le_bytes()).unwrap();
        od.write(ObjectKey::new(0x6200, 1), &[0x5A]).unwrap();
        assert_eq!(
            sdo_write(&mut service, &mut store, &mut od, ObjectKey::new(0x1010, 1), SAVE),
            Ok(())
        );
        for group in ParameterGroup::STORED {
            assert!(store.saved(group).is_some(), "{group:?}");
        }
        let mut od = defaults();
        let applied = service
            .apply_saved(ParameterGroup::All, &mut od, &mut store)
            .unwrap();
        assert_eq!(applied, 4);
        assert_eq!(value(&od, 0x2000, 0), 9u32.to_le_bytes());
        assert_eq!(value(&od, 0x6200, 1), [0x5A]);
    }

    #[test]
    fn restore_takes_effect_after_the_next_reset() {
        let mut od = defaults();
        let (mut service, mut store) = (StoreRestore::new(), MemoryStore::new());
        od.write(ObjectKey::new(0x1017, 0), &100u32.to_le_bytes())
            .unwrap();
        od.write(ObjectKey::new(0x2000, 0), &9u32.to_le_bytes()).unwrap();
        sdo_write(&mut service, &mut store, &mut od, ObjectKey::new(0x1010, 1), SAVE).unwrap();
        service.poll_event();
        // The CCT's frame: 23 11 10 01 6C 6F 61 64.
        assert_eq!(
            sdo_write(&mut service, &mut store, &mut od, ObjectKey::new(0x1011, 1), LOAD),
            Ok(())
        );
        assert_eq!(value(&od, 0x1011, 1), [1, 0, 0, 0]);
        assert_eq!(
            value(&od, 0x1017, 0),
            100u32.to_le_bytes(),
            "nothing changes before the reset"
        );
        assert_eq!(service.pending_restore(), ParameterGroup::STORED);
        assert_eq!(
            service.poll_event(),
            Some(StoreEvent::RestorePending {
                group: ParameterGroup::All
            })
        );
        // Reset communication: only the communication group returns to its defaults.
        let mut comm_defaults = defaults();
        service
            .apply_saved(ParameterGroup::Communication, &mut comm_defaults, &mut store)
            .unwrap();
        assert_eq!(
            service.poll_event(),
            Some(StoreEvent::RestoreTookEffect {
                group: ParameterGroup::Communication
            })
        );
        assert_eq!(
            service.pending_restore(),
            [ParameterGroup::Application, ParameterGroup::Manufacturer]
        );
        // Reset node: the rest too.
        let mut od = defaults();
        service
            .apply_saved(ParameterGroup::All, &mut od, &mut store)
            .unwrap();
        assert_eq!(value(&od, 0x1017, 0), 0u32.to_le_bytes());
        assert_eq!(value(&od, 0x2000, 0), 7u32.to_le_bytes());
        assert!(service.pending_restore().is_empty());
        assert_eq!(
            service.poll_event(),
            Some(StoreEvent::RestoreTookEffect {
                group: ParameterGroup::Application
            })
        );
        assert_eq!(
            service.poll_event(),
            Some(StoreEvent::RestoreTookEffect {
                group: ParameterGroup::Manufacturer
            })
        );
        assert_eq!(service.poll_event(), None);
    }

    #[test]
    fn wrong_signatures_are_refused_with_0800_0020() {
        let mut od = defaults();
        let (mut service, mut store) = (StoreRestore::new(), MemoryStore::new());
        let cases = [
            (ObjectKey::new(0x1011, 1), *b"wron"), // the CCT's test
            (ObjectKey::new(0x1010, 1), LOAD),
            (ObjectKey::new(0x1011, 2), SAVE),
            (ObjectKey::new(0x1010, 4), *b"SAVE"),
        ];
        for (key, data) in cases {
            assert_eq!(
                sdo_write(&mut service, &mut store, &mut od, key, data),
                Err(0x0800_0020),
                "{key}"
            );
        }
        let err = service
            .check_download(ObjectKey::new(0x1011, 1), b"wron", &od, &mut store)
            .unwrap_err();
        assert_eq!(
            err,
            StoreError::WrongSignature {
                key: ObjectKey::new(0x1011, 1),
                value: 0x6E6F_7277,
                expected: LOAD_SIGNATURE
            }
        );
        assert_eq!(store, MemoryStore::new(), "nothing stored");
        assert!(service.pending_restore().is_empty(), "nothing restored");
        assert_eq!(service.poll_event(), None);
    }

    #[test]
    fn unsupported_sub_index_and_sub_index_zero() {
        let mut od = defaults();
        let (mut service, mut store) = (StoreRestore::new(), MemoryStore::new());
        let key = ObjectKey::new(0x1010, 5);
        assert_eq!(
            sdo_write(&mut service, &mut store, &mut od, key, SAVE),
            Err(0x0800_0020)
        );
        assert_eq!(
            service.check_download(key, &SAVE, &od, &mut store),
            Err(StoreError::UnsupportedGroup { key })
        );
        // Sub-index 0 is read-only: the dictionary refuses it.
        let key = ObjectKey::new(0x1010, 0);
        assert_eq!(
            sdo_write(&mut service, &mut store, &mut od, key, SAVE),
            Err(0x0601_0002)
        );
        // Wrong length: the dictionary refuses it.
        assert_eq!(
            service.check_download(ObjectKey::new(0x1010, 1), &[0x73], &od, &mut store),
            Ok(())
        );
        assert_eq!(store, MemoryStore::new());
    }

    #[test]
    fn storage_failure_is_refused_with_0606_0000() {
        let mut od = defaults();
        let (mut service, mut store) = (StoreRestore::new(), MemoryStore::new());
        store.set_failing(true);
        for (key, data) in [
            (ObjectKey::new(0x1010, 1), SAVE),
            (ObjectKey::new(0x1011, 3), LOAD),
        ] {
            assert_eq!(
                sdo_write(&mut service, &mut store, &mut od, key, data),
                Err(0x0606_0000)
            );
        }
        let err = service
            .check_download(ObjectKey::new(0x1010, 2), &SAVE, &od, &mut store)
            .unwrap_err();
        assert_eq!(err.abort_code(), 0x0606_0000);
        assert!(matches!(err, StoreError::Storage(_)));
        assert!(
            service
                .apply_saved(ParameterGroup::All, &mut od, &mut store)
                .is_err(),
            "load fails too"
        );
        assert_eq!(service.poll_event(), None);
    }

    #[test]
    fn saved_values_that_no_longer_fit_are_skipped() {
        let mut store = MemoryStore::new();
        store
            .save(
                ParameterGroup::Communication,
                &[
                    (ObjectKey::new(0x1017, 0), vec![1, 2]), // wrong length
                    (ObjectKey::new(0x1800, 1), 0x1A5u32.to_le_bytes().to_vec()),
                    (ObjectKey::new(0x1801, 1), vec![0; 4]), // gone
                    (ObjectKey::new(0x2000, 0), vec![0; 4]), // not in this group
                ],
            )
            .unwrap();
        let mut od = defaults();
        let mut service = StoreRestore::new();
        let applied = service
            .apply_saved(ParameterGroup::Communication, &mut od, &mut store)
            .unwrap();
        assert_eq!(applied, 1);
        assert_eq!(value(&od, 0x1800, 1), 0x1A5u32.to_le_bytes());
        let skipped: Vec<_> = std::iter::from_fn(|| service.poll_event()).collect();
        assert_eq!(
            skipped,
            [0x1017, 0x1801, 0x2000].map(|index| StoreEvent::SavedValueSkipped {
                key: ObjectKey::new(index, if index == 0x1801 { 1 } else { 0 })
            })
        );
    }

    #[test]
    fn snapshot_and_restore_round_trip() {
        let mut od = defaults();
        od.write(ObjectKey::new(0x1800, 1), &0x1A5u32.to_le_bytes())
            .unwrap();
        let values = snapshot(&od, ParameterGroup::All);
        let mut fresh = defaults();
        assert_eq!(restore(&mut fresh, &values), []);
        assert_eq!(snapshot(&fresh, ParameterGroup::All), values);
        let bad = [(ObjectKey::new(0x3000, 0), vec![1])];
        assert_eq!(restore(&mut fresh, &bad), [ObjectKey::new(0x3000, 0)]);
    }

    #[test]
    fn group_sub_indices_and_ranges() {
        for sub in 1..=4 {
            assert_eq!(ParameterGroup::from_sub(sub).map(ParameterGroup::sub), Some(sub));
        }
        assert_eq!(ParameterGroup::from_sub(0), None);
        assert_eq!(ParameterGroup::from_sub(5), None);
        assert!(ParameterGroup::Communication.contains(0x1FFF));
        assert!(!ParameterGroup::Communication.contains(0x2000));
        assert!(ParameterGroup::Manufacturer.contains(0x5FFF));
        assert!(!ParameterGroup::Application.contains(0x5FFF));
        assert!(ParameterGroup::Application.contains(0x9FFF));
        assert!(!ParameterGroup::All.contains(0xA000));
        assert!(!ParameterGroup::All.contains(0x0FFF));
    }

    proptest::proptest! {
        /// Arbitrary downloads to 1010h/1011h never panic; only the two signatures change anything.
        #[test]
        fn arbitrary_writes_never_panic(writes in proptest::collection::vec(
            (0x100Fu16..=0x1012, 0u8..8, proptest::collection::vec(proptest::prelude::any::<u8>(), 0..6)), 0..30)) {
            let od = defaults();
            let mut service = StoreRestore::new();
            let mut store = MemoryStore::new();
            for (index, sub, data) in writes {
                let key = ObjectKey::new(index, sub);
                let result = service.check_download(key, &data, &od, &mut store);
                if let Err(e) = result {
                    proptest::prop_assert!(matches!(e.abort_code(), 0x0800_0020 | 0x0606_0000));
                }
            }
            let mut od = defaults();
            service.apply_saved(ParameterGroup::All, &mut od, &mut store).unwrap();
            while service.poll_event().is_some() {}
        }
    }
}

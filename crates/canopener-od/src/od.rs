//! The dynamic object dictionary: a sorted array of entries with a capacity fixed up front.
//!
//! Entries are kept in ascending [`ObjectKey`] order, so a lookup is a binary search and all
//! sub-indices of one object sit next to each other. Inserting shifts the entries behind the new
//! one (O(n)), which suits a dictionary that is built once and then read and written far more
//! often than it changes shape. The memory for `capacity` entries is reserved when the dictionary
//! is made, so a device never allocates for its dictionary again.
//!
//! The binary search runs over a separate array of packed 32-bit keys rather than over the entries:
//! the keys of a 10,000-entry dictionary fill 40 KB, against several hundred KB of entries, so the
//! search touches far fewer cache lines (`benches/od.rs` measures both).

use std::fmt;

use crate::entry::{Entry, EntryMut};
use crate::error::OdError;
use crate::key::ObjectKey;

/// The largest useful capacity: one entry for every index and sub-index.
///
/// Larger requests are clamped to it, since no dictionary can hold more distinct keys.
pub const MAX_ENTRIES: usize = 1 << 24;

/// A runtime object dictionary with a fixed capacity, ordered by index and sub-index.
///
/// Built for a sans-IO CANopen device: an SDO server calls [`read`](DynamicOd::read) and
/// [`write`](DynamicOd::write), whose errors carry the SDO abort code to send; the application sets
/// process values with [`set_value`](DynamicOd::set_value); a PDO reads [`Entry::value`] directly.
///
/// ```
/// use canopener_od::{Access, DataType, DynamicOd, Entry, ObjectKey};
///
/// let heartbeat = ObjectKey::new(0x1017, 0);
/// let mut od = DynamicOd::with_capacity(16);
/// od.insert(Entry::new(heartbeat, DataType::UNSIGNED16, Access::Rw, &[0, 0])?)?;
///
/// od.write(heartbeat, &1000u16.to_le_bytes())?;
/// assert_eq!(od.read(heartbeat)?, [0xE8, 0x03]);
///
/// let err = od.write(heartbeat, &[1, 2, 3]).unwrap_err();
/// assert_eq!(err.abort_code(), 0x0607_0012); // length too high
/// let err = od.read(ObjectKey::new(0x1017, 1)).unwrap_err();
/// assert_eq!(err.abort_code(), 0x0609_0011); // sub-index does not exist
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct DynamicOd {
    /// `keys[i] == entries[i].key().packed()`, strictly ascending; both vectors always have the
    /// same length.
    keys: Vec<u32>,
    entries: Vec<Entry>,
    capacity: usize,
}

impl DynamicOd {
    /// An empty dictionary that holds up to `capacity` entries (at most [`MAX_ENTRIES`]), with the
    /// memory for all of them reserved now.
    pub fn with_capacity(capacity: usize) -> DynamicOd {
        let capacity = capacity.min(MAX_ENTRIES);
        DynamicOd {
            keys: Vec::with_capacity(capacity),
            entries: Vec::with_capacity(capacity),
            capacity,
        }
    }

    /// A dictionary of `capacity` entries filled with `entries` in any order, in O(n log n)
    /// rather than the O(n²) of inserting unsorted entries one by one.
    ///
    /// The result equals inserting the entries in the given order: when a key repeats, the last
    /// entry wins. Fails with [`OdError::Full`] when there are more distinct keys than `capacity`.
    pub fn from_entries(
        capacity: usize,
        entries: impl IntoIterator<Item = Entry>,
    ) -> Result<DynamicOd, OdError> {
        let mut sorted: Vec<Entry> = entries.into_iter().collect();
        // A stable sort keeps entries with equal keys in insertion order, so the last one of each
        // run is the one a sequence of inserts would have kept.
        sorted.sort_by_key(Entry::key);
        let mut od = DynamicOd::with_capacity(capacity);
        for entry in sorted {
            let key = entry.key();
            if let Some(last) = od.entries.last_mut()
                && last.key() == key
            {
                *last = entry;
                continue;
            }
            if od.entries.len() >= od.capacity {
                return Err(OdError::Full {
                    capacity: od.capacity,
                    key,
                });
            }
            od.keys.push(key.packed());
            od.entries.push(entry);
        }
        Ok(od)
    }

    /// Adds `entry`, or replaces the entry with the same key and returns it.
    ///
    /// Replacing works even when the dictionary is full. Adding to a full dictionary fails with
    /// [`OdError::Full`] and changes nothing.
    pub fn insert(&mut self, entry: Entry) -> Result<Option<Entry>, OdError> {
        let key = entry.key();
        match self.keys.binary_search(&key.packed()) {
            #[allow(
                clippy::indexing_slicing,
                reason = "`position < keys.len() == entries.len()`, as a successful `binary_search` promises"
            )]
            Ok(position) => Ok(Some(std::mem::replace(&mut self.entries[position], entry))),
            Err(position) => {
                if self.entries.len() >= self.capacity {
                    return Err(OdError::Full {
                        capacity: self.capacity,
                        key,
                    });
                }
                // `position <= keys.len() == entries.len()`, as `binary_search` promises, and the
                // capacity check above means neither vector reallocates.
                self.keys.insert(position, key.packed());
                self.entries.insert(position, entry);
                Ok(None)
            }
        }
    }

    /// Removes and returns the entry at `key`, if there is one.
    pub fn remove(&mut self, key: ObjectKey) -> Option<Entry> {
        let position = self.keys.binary_search(&key.packed()).ok()?;
        // `position < keys.len() == entries.len()`, as a successful `binary_search` promises.
        self.keys.remove(position);
        Some(self.entries.remove(position))
    }

    /// The entry at `key`.
    pub fn get(&self, key: ObjectKey) -> Option<&Entry> {
        let position = self.keys.binary_search(&key.packed()).ok()?;
        self.entries.get(position)
    }

    /// A handle that changes the entry at `key` in place.
    pub fn get_mut(&mut self, key: ObjectKey) -> Option<EntryMut<'_>> {
        let position = self.keys.binary_search(&key.packed()).ok()?;
        self.entries.get_mut(position).map(EntryMut::new)
    }

    /// Whether there is an entry at `key`.
    pub fn contains(&self, key: ObjectKey) -> bool {
        self.keys.binary_search(&key.packed()).is_ok()
    }

    /// All entries of object `index` (its sub-indices in ascending order), empty if there are none.
    pub fn object(&self, index: u16) -> &[Entry] {
        let first = ObjectKey::new(index, 0).packed();
        let last = ObjectKey::new(index, u8::MAX).packed();
        let start = self.keys.partition_point(|&key| key < first);
        let end = self.keys.partition_point(|&key| key <= last);
        self.entries.get(start..end).unwrap_or_default()
    }

    /// The value at `key` as an SDO upload reads it.
    ///
    /// Fails with [`OdError::ObjectDoesNotExist`], [`OdError::SubIndexDoesNotExist`] or
    /// [`OdError::WriteOnly`].
    pub fn read(&self, key: ObjectKey) -> Result<&[u8], OdError> {
        self.locate(key)?.read()
    }

    /// Stores `data` at `key` as an SDO download does: the entry must exist and be writable, the
    /// length must suit its type and a number must lie within its limits. Nothing changes on error.
    pub fn write(&mut self, key: ObjectKey, data: &[u8]) -> Result<(), OdError> {
        EntryMut::new(self.locate_mut(key)?).write(data)
    }

    /// Stores `data` at `key` as the device's application does, whatever the access type and
    /// limits; the entry must exist and the length must suit its type. Nothing changes on error.
    pub fn set_value(&mut self, key: ObjectKey, data: &[u8]) -> Result<(), OdError> {
        EntryMut::new(self.locate_mut(key)?).set_value(data)
    }

    /// The number of entries.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether the dictionary has no entries.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The most entries the dictionary holds.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// The entries in ascending key order.
    pub fn iter(&self) -> std::slice::Iter<'_, Entry> {
        self.entries.iter()
    }

    /// The entries in ascending key order, as one slice.
    pub fn entries(&self) -> &[Entry] {
        &self.entries
    }

    fn position(&self, key: ObjectKey) -> Result<usize, OdError> {
        self.keys.binary_search(&key.packed()).map_err(|position| {
            // Sub-indices of one object are contiguous, so if the object has any entry, one sits
            // right before or right at the position where `key` would go.
            let same_object = |packed: &u32| ObjectKey::from_packed(*packed).index == key.index;
            let before = position.checked_sub(1).and_then(|before| self.keys.get(before));
            if self.keys.get(position).is_some_and(same_object) || before.is_some_and(same_object) {
                OdError::SubIndexDoesNotExist { key }
            } else {
                OdError::ObjectDoesNotExist { key }
            }
        })
    }

    fn locate(&self, key: ObjectKey) -> Result<&Entry, OdError> {
        let position = self.position(key)?;
        self.entries
            .get(position)
            .ok_or(OdError::ObjectDoesNotExist { key })
    }

    fn locate_mut(&mut self, key: ObjectKey) -> Result<&mut Entry, OdError> {
        let position = self.position(key)?;
        self.entries
            .get_mut(position)
            .ok_or(OdError::ObjectDoesNotExist { key })
    }
}

impl<'a> IntoIterator for &'a DynamicOd {
    type Item = &'a Entry;
    type IntoIter = std::slice::Iter<'a, Entry>;

    fn into_iter(self) -> std::slice::Iter<'a, Entry> {
        self.entries.iter()
    }
}

/// A clone has the same capacity reserved, so it never allocates for entries either.
impl Clone for DynamicOd {
    fn clone(&self) -> DynamicOd {
        let mut keys = Vec::with_capacity(self.capacity);
        keys.extend_from_slice(&self.keys);
        let mut entries = Vec::with_capacity(self.capacity);
        entries.extend_from_slice(&self.entries);
        DynamicOd {
            keys,
            entries,
            capacity: self.capacity,
        }
    }
}

/// Two dictionaries are equal when they have the same capacity and the same entries.
impl PartialEq for DynamicOd {
    fn eq(&self, other: &DynamicOd) -> bool {
        self.capacity == other.capacity && self.entries == other.entries
    }
}

impl fmt::Debug for DynamicOd {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("DynamicOd")
            .field("capacity", &self.capacity)
            .field("entries", &self.entries)
            .finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::access::Access;
    use crate::data_type::DataType;

    fn u8_entry(index: u16, sub: u8, value: u8) -> Entry {
        match Entry::new(
            ObjectKey::new(index, sub),
            DataType::UNSIGNED8,
            Access::Rw,
            &[value],
        ) {
            Ok(entry) => entry,
            Err(err) => panic!("{err}"),
        }
    }

    fn od_of(capacity: usize, keys: &[(u16, u8)]) -> DynamicOd {
        let mut od = DynamicOd::with_capacity(capacity);
        for &(index, sub) in keys {
            assert_eq!(od.insert(u8_entry(index, sub, sub)), Ok(None));
        }
        od
    }

    fn keys_of(od: &DynamicOd) -> Vec<(u16, u8)> {
        od.iter()
            .map(|entry| (entry.key().index, entry.key().sub))
            .collect()
    }

    #[test]
    fn keeps_entries_in_key_order_whatever_the_insert_order() {
        let od = od_of(
            8,
            &[
                (0x2000, 1),
                (0x1000, 0),
                (0x1018, 4),
                (0x1018, 1),
                (0x2000, 0),
                (0x1017, 0),
            ],
        );
        assert_eq!(
            keys_of(&od),
            [
                (0x1000, 0),
                (0x1017, 0),
                (0x1018, 1),
                (0x1018, 4),
                (0x2000, 0),
                (0x2000, 1)
            ]
        );
        assert_eq!(od.len(), 6);
        assert_eq!(od.keys.len(), od.entries.len());
        assert!(od.keys.windows(2).all(|pair| pair[0] < pair[1]));
    }

    #[test]
    fn binary_search_finds_every_entry_and_nothing_else() {
        let keys: Vec<(u16, u8)> = (0..200u16).map(|i| (0x2000 + i / 7, (i % 7 * 3) as u8)).collect();
        let od = od_of(200, &keys);
        for &(index, sub) in &keys {
            let key = ObjectKey::new(index, sub);
            assert_eq!(od.get(key).map(Entry::key), Some(key));
            assert!(od.contains(key));
            assert!(!od.contains(ObjectKey::new(index, sub + 1)));
        }
        assert_eq!(od.get(ObjectKey::new(0x1FFF, 0)), None);
        assert_eq!(od.get(ObjectKey::new(0xFFFF, 0xFF)), None);
        assert_eq!(DynamicOd::with_capacity(0).get(ObjectKey::new(0, 0)), None);
    }

    #[test]
    fn insert_replaces_an_existing_key_and_returns_the_old_entry() {
        let mut od = od_of(2, &[(0x1000, 0), (0x1001, 0)]);
        let old = od.insert(u8_entry(0x1001, 0, 99));
        assert_eq!(old.map(|old| old.map(|e| e.value().to_vec())), Ok(Some(vec![0])));
        assert_eq!(od.read(ObjectKey::new(0x1001, 0)), Ok(&[99][..]));
        assert_eq!(od.len(), 2);
    }

    #[test]
    fn full_dictionary_refuses_new_keys_and_stays_unchanged() {
        let mut od = od_of(3, &[(0x1000, 0), (0x2000, 0), (0x3000, 0)]);
        let before = od.clone();
        let err = od.insert(u8_entry(0x1800, 1, 0));
        assert_eq!(
            err,
            Err(OdError::Full {
                capacity: 3,
                key: ObjectKey::new(0x1800, 1)
            })
        );
        assert_eq!(err.map_err(|err| err.abort_code()), Err(0x0800_0023));
        assert_eq!(od, before);
        assert_eq!(keys_of(&od), [(0x1000, 0), (0x2000, 0), (0x3000, 0)]);
        // Replacing needs no room and still works.
        assert_eq!(
            od.insert(u8_entry(0x2000, 0, 5)).map(|old| old.is_some()),
            Ok(true)
        );
        // Removing makes room again.
        assert!(od.remove(ObjectKey::new(0x1000, 0)).is_some());
        assert_eq!(od.insert(u8_entry(0x1800, 1, 0)), Ok(None));
    }

    #[test]
    fn zero_capacity_holds_nothing() {
        let mut od = DynamicOd::with_capacity(0);
        assert!(od.insert(u8_entry(0x1000, 0, 0)).is_err());
        assert!(od.is_empty());
        assert_eq!(od.capacity(), 0);
    }

    #[test]
    fn capacity_is_clamped_to_the_number_of_keys() {
        // Reserving is lazy in the allocator, so this stays cheap; nothing is inserted.
        assert_eq!(DynamicOd::with_capacity(usize::MAX).capacity(), MAX_ENTRIES);
    }

    #[test]
    fn remove_takes_out_exactly_one_entry() {
        let mut od = od_of(4, &[(0x1000, 0), (0x1018, 1), (0x1018, 2)]);
        assert_eq!(
            od.remove(ObjectKey::new(0x1018, 1)).map(|e| e.key()),
            Some(ObjectKey::new(0x1018, 1))
        );
        assert_eq!(od.remove(ObjectKey::new(0x1018, 1)), None);
        assert_eq!(keys_of(&od), [(0x1000, 0), (0x1018, 2)]);
        assert_eq!(od.keys.len(), od.entries.len());
    }

    #[test]
    fn object_is_the_contiguous_run_of_one_index() {
        let od = od_of(
            8,
            &[
                (0x1017, 0),
                (0x1018, 0),
                (0x1018, 1),
                (0x1018, 4),
                (0x1019, 0),
                (0x1018, 0xFF),
            ],
        );
        let subs: Vec<u8> = od.object(0x1018).iter().map(|e| e.key().sub).collect();
        assert_eq!(subs, [0, 1, 4, 0xFF]);
        assert_eq!(od.object(0x1017).len(), 1);
        assert!(od.object(0x1016).is_empty());
        assert!(od.object(0xFFFF).is_empty());
        assert!(od.object(0).is_empty());
        let edges = od_of(4, &[(0, 0), (0xFFFF, 0xFF)]);
        assert_eq!(edges.object(0).len(), 1);
        assert_eq!(edges.object(0xFFFF).len(), 1);
    }

    #[test]
    fn missing_object_and_missing_sub_index_are_told_apart() {
        let od = od_of(8, &[(0x1000, 0), (0x1018, 1), (0x1018, 3), (0x2000, 0)]);
        let code = |index, sub| {
            od.read(ObjectKey::new(index, sub))
                .map_err(|err| err.abort_code())
        };
        assert_eq!(code(0x1018, 0), Err(0x0609_0011)); // before the first sub-index
        assert_eq!(code(0x1018, 2), Err(0x0609_0011)); // between sub-indices
        assert_eq!(code(0x1018, 4), Err(0x0609_0011)); // after the last sub-index
        assert_eq!(code(0x1000, 1), Err(0x0609_0011));
        assert_eq!(code(0x2000, 0xFF), Err(0x0609_0011));
        assert_eq!(code(0x1001, 0), Err(0x0602_0000));
        assert_eq!(code(0x0FFF, 0), Err(0x0602_0000));
        assert_eq!(code(0x2001, 0), Err(0x0602_0000));
        assert_eq!(code(0x1017, 0xFF), Err(0x0602_0000));
        assert_eq!(
            od.read(ObjectKey::new(0x1018, 2)),
            Err(OdError::SubIndexDoesNotExist {
                key: ObjectKey::new(0x1018, 2)
            })
        );
    }

    #[test]
    fn read_write_and_set_value_enforce_the_entry_rules() {
        let mut od = DynamicOd::with_capacity(4);
        let device_type = ObjectKey::new(0x1000, 0);
        let command = ObjectKey::new(0x2000, 0);
        let entries = [
            Entry::new(
                device_type,
                DataType::UNSIGNED32,
                Access::Ro,
                &[0x91, 0x01, 0x0F, 0x00],
            ),
            Entry::new(command, DataType::UNSIGNED16, Access::Wo, &[0, 0]),
        ];
        for entry in entries {
            match entry {
                Ok(entry) => assert_eq!(od.insert(entry), Ok(None)),
                Err(err) => panic!("{err}"),
            }
        }
        assert_eq!(od.read(device_type), Ok(&[0x91, 0x01, 0x0F, 0x00][..]));
        assert_eq!(
            od.write(device_type, &[0; 4]).map_err(|e| e.abort_code()),
            Err(0x0601_0002)
        );
        assert_eq!(od.read(command).map_err(|e| e.abort_code()), Err(0x0601_0001));
        assert_eq!(
            od.write(command, &[1]).map_err(|e| e.abort_code()),
            Err(0x0607_0013)
        );
        assert_eq!(
            od.write(command, &[1, 0, 0]).map_err(|e| e.abort_code()),
            Err(0x0607_0012)
        );
        assert_eq!(od.write(command, &[1, 0]), Ok(()));
        assert_eq!(od.get(command).map(Entry::value), Some(&[1, 0][..]));
        // The application may change a read-only value; the network may not.
        assert_eq!(od.set_value(device_type, &[1, 2, 3, 4]), Ok(()));
        assert_eq!(od.read(device_type), Ok(&[1, 2, 3, 4][..]));
        assert_eq!(
            od.set_value(device_type, &[1]).map_err(|e| e.abort_code()),
            Err(0x0607_0013)
        );
        assert_eq!(
            od.write(ObjectKey::new(0x3000, 0), &[1])
                .map_err(|e| e.abort_code()),
            Err(0x0602_0000)
        );
        assert_eq!(
            od.set_value(ObjectKey::new(0x2000, 1), &[1])
                .map_err(|e| e.abort_code()),
            Err(0x0609_0011)
        );
    }

    #[test]
    fn get_mut_changes_entries_in_place_but_never_their_key() {
        let mut od = od_of(4, &[(0x1000, 0), (0x2000, 0)]);
        let key = ObjectKey::new(0x2000, 0);
        match od.get_mut(key) {
            Some(mut entry) => {
                entry.set_access(Access::Ro);
                assert_eq!(entry.write(&[1]).map_err(|e| e.abort_code()), Err(0x0601_0002));
                assert_eq!(entry.set_value(&[42]), Ok(()));
            }
            None => panic!("0x2000:00 must exist"),
        }
        assert_eq!(
            od.get(key).map(|e| (e.access(), e.value().to_vec())),
            Some((Access::Ro, vec![42]))
        );
        assert!(od.get_mut(ObjectKey::new(0x2000, 1)).is_none());
    }

    #[test]
    fn from_entries_sorts_and_keeps_the_last_duplicate() {
        let entries = vec![
            u8_entry(0x2000, 0, 1),
            u8_entry(0x1000, 0, 2),
            u8_entry(0x2000, 0, 3),
        ];
        let mut by_insert = DynamicOd::with_capacity(2);
        for entry in entries.clone() {
            assert!(by_insert.insert(entry).is_ok());
        }
        let built = DynamicOd::from_entries(2, entries);
        assert_eq!(built.as_ref(), Ok(&by_insert));
        assert_eq!(
            built.map(|od| od.get(ObjectKey::new(0x2000, 0)).map(|e| e.value().to_vec())),
            Ok(Some(vec![3]))
        );
    }

    #[test]
    fn from_entries_refuses_more_keys_than_capacity() {
        let entries = [
            u8_entry(0x3000, 0, 0),
            u8_entry(0x1000, 0, 0),
            u8_entry(0x2000, 0, 0),
        ];
        assert_eq!(
            DynamicOd::from_entries(2, entries),
            Err(OdError::Full {
                capacity: 2,
                key: ObjectKey::new(0x3000, 0)
            })
        );
    }

    #[test]
    fn clone_keeps_the_reserved_capacity() {
        let od = od_of(100, &[(0x1000, 0)]);
        let copy = od.clone();
        assert!(copy.keys.capacity() >= 100);
        assert!(copy.entries.capacity() >= 100);
        assert_eq!(copy, od);
    }

    #[test]
    fn iterates_in_order_by_reference() {
        let od = od_of(4, &[(0x2000, 0), (0x1000, 0)]);
        let mut seen = Vec::new();
        for entry in &od {
            seen.push(entry.key().index);
        }
        assert_eq!(seen, [0x1000, 0x2000]);
        assert_eq!(od.entries().len(), 2);
    }
}

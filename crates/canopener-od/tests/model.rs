//! Property tests: random sequences of inserts, removes and lookups against a `BTreeMap` model.

use std::collections::BTreeMap;

use canopener_od::{Access, DataType, DynamicOd, Entry, ObjectKey, OdError};
use proptest::prelude::*;

#[derive(Clone, Debug)]
enum Op {
    Insert(ObjectKey, u8),
    Remove(ObjectKey),
    Read(ObjectKey),
}

/// Keys from a small space (8 indices × 8 sub-indices), so replacements, misses and removals of
/// present keys all happen often.
fn key() -> impl Strategy<Value = ObjectKey> {
    (0u16..8, 0u8..8).prop_map(|(index, sub)| ObjectKey::new(0x2000 + index * 0x100, sub))
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        3 => (key(), any::<u8>()).prop_map(|(key, value)| Op::Insert(key, value)),
        1 => key().prop_map(Op::Remove),
        1 => key().prop_map(Op::Read),
    ]
}

fn entry(key: ObjectKey, value: u8) -> Entry {
    Entry::new(key, DataType::UNSIGNED8, Access::Rw, &[value]).unwrap()
}

fn contents(od: &DynamicOd) -> Vec<(ObjectKey, u8)> {
    od.iter().map(|e| (e.key(), e.value()[0])).collect()
}

proptest! {
    #[test]
    fn behaves_like_a_btree_map_with_a_capacity(capacity in 0usize..24, ops in prop::collection::vec(op(), 0..200)) {
        let mut od = DynamicOd::with_capacity(capacity);
        let mut model: BTreeMap<ObjectKey, u8> = BTreeMap::new();
        for op in ops {
            match op {
                Op::Insert(key, value) => {
                    let result = od.insert(entry(key, value)).map(|old| old.map(|e| e.value()[0]));
                    if model.contains_key(&key) || model.len() < capacity {
                        prop_assert_eq!(result, Ok(model.insert(key, value)));
                    } else {
                        prop_assert_eq!(result, Err(OdError::Full { capacity, key }));
                    }
                }
                Op::Remove(key) => {
                    prop_assert_eq!(od.remove(key).map(|e| e.value()[0]), model.remove(&key));
                }
                Op::Read(key) => {
                    let expected = match model.get(&key) {
                        Some(value) => Ok(vec![*value]),
                        None if model.keys().any(|k| k.index == key.index) => {
                            Err(OdError::SubIndexDoesNotExist { key })
                        }
                        None => Err(OdError::ObjectDoesNotExist { key }),
                    };
                    prop_assert_eq!(od.read(key).map(<[u8]>::to_vec), expected);
                    prop_assert_eq!(od.contains(key), model.contains_key(&key));
                }
            }
            prop_assert!(od.len() <= capacity);
            prop_assert_eq!(od.len(), model.len());
            prop_assert_eq!(contents(&od), model.iter().map(|(k, v)| (*k, *v)).collect::<Vec<_>>());
        }
        for index in (0u16..8).map(|i| 0x2000 + i * 0x100) {
            let object: Vec<ObjectKey> = od.object(index).iter().map(Entry::key).collect();
            let expected: Vec<ObjectKey> =
                model.range(ObjectKey::new(index, 0)..=ObjectKey::new(index, u8::MAX)).map(|(k, _)| *k).collect();
            prop_assert_eq!(object, expected);
        }
    }

    #[test]
    fn from_entries_equals_inserting_one_by_one(
        capacity in 0usize..24,
        entries in prop::collection::vec((key(), any::<u8>()), 0..40),
    ) {
        let mut by_insert = DynamicOd::with_capacity(capacity);
        let mut first_full = None;
        for &(key, value) in &entries {
            if let Err(err) = by_insert.insert(entry(key, value)) {
                first_full.get_or_insert(err);
            }
        }
        let built = DynamicOd::from_entries(capacity, entries.iter().map(|&(key, value)| entry(key, value)));
        match (built, first_full) {
            (Ok(built), None) => prop_assert_eq!(built, by_insert),
            (Err(OdError::Full { capacity: reported, .. }), Some(OdError::Full { .. })) => {
                prop_assert_eq!(reported, capacity);
            }
            (built, first_full) => prop_assert!(false, "from_entries gave {built:?}, inserts gave {first_full:?}"),
        }
    }
}

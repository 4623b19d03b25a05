//! Lookups and inserts on the dynamic object dictionary at 100, 1,000 and 10,000 entries.
//!
//! Lookups run 1,024 random keys per iteration (criterion reports elements per second; divide the
//! time by 1,024 for one lookup) and are repeated on the entry slice searched directly (what the
//! separate key array saves), a `BTreeMap` and a std `HashMap`. `od_insert` times one insert into
//! a dictionary that already holds n entries, freshly cloned and so cold in the cache: at the end,
//! at a random place, and at the front (the worst case, which shifts every entry). `od_build` times
//! building n entries from empty in ascending, random and descending key order. `od_value_storage`
//! measures what inline values save against one heap allocation per value.

use std::collections::{BTreeMap, HashMap};
use std::hint::black_box;

use canopener_od::{Access, DataType, DynamicOd, Entry, ObjectKey};
use criterion::{BatchSize, BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

const SIZES: [usize; 3] = [100, 1_000, 10_000];
const LOOKUPS: usize = 1_024;

/// The i-th key present in a benchmark dictionary: 64 even sub-indices per object, so every odd
/// sub-index in between is a miss and a free slot for inserts.
fn present_key(i: usize) -> ObjectKey {
    ObjectKey::new(0x2000 + (i / 64) as u16, (i % 64 * 2) as u8)
}

fn missing_key(i: usize) -> ObjectKey {
    let present = present_key(i);
    ObjectKey::new(present.index, present.sub + 1)
}

fn entry(key: ObjectKey) -> Entry {
    Entry::new(key, DataType::UNSIGNED32, Access::Rw, &[1, 2, 3, 4]).unwrap()
}

/// A small deterministic generator, so every run probes the same keys.
struct XorShift(u64);

impl XorShift {
    fn below(&mut self, bound: usize) -> usize {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 % bound as u64) as usize
    }
}

fn dictionary(n: usize, spare: usize) -> DynamicOd {
    DynamicOd::from_entries(n + spare, (0..n).map(|i| entry(present_key(i)))).unwrap()
}

fn bench_lookups(c: &mut Criterion, group_name: &str, probe: fn(usize) -> ObjectKey) {
    let mut group = c.benchmark_group(group_name);
    group.throughput(Throughput::Elements(LOOKUPS as u64));
    for n in SIZES {
        let od = dictionary(n, 0);
        let btree: BTreeMap<ObjectKey, Entry> = od.iter().map(|e| (e.key(), e.clone())).collect();
        let hash: HashMap<ObjectKey, Entry> = od.iter().map(|e| (e.key(), e.clone())).collect();
        let mut rng = XorShift(0x9E37_79B9_7F4A_7C15 ^ n as u64);
        let probes: Vec<ObjectKey> = (0..LOOKUPS).map(|_| probe(rng.below(n))).collect();

        // Each lookup touches the found entry's value, as an SDO upload would.
        group.bench_with_input(BenchmarkId::new("dynamic_od", n), &probes, |b, probes| {
            b.iter(|| {
                probes
                    .iter()
                    .filter_map(|&key| od.get(black_box(key)))
                    .map(value_len)
                    .sum::<usize>()
            })
        });
        group.bench_with_input(BenchmarkId::new("entry_slice_search", n), &probes, |b, probes| {
            let entries = od.entries();
            b.iter(|| {
                probes
                    .iter()
                    .filter_map(|&key| entries.binary_search_by_key(&black_box(key), Entry::key).ok())
                    .filter_map(|position| entries.get(position))
                    .map(value_len)
                    .sum::<usize>()
            })
        });
        group.bench_with_input(BenchmarkId::new("btree_map", n), &probes, |b, probes| {
            b.iter(|| {
                probes
                    .iter()
                    .filter_map(|key| btree.get(black_box(key)))
                    .map(value_len)
                    .sum::<usize>()
            })
        });
        group.bench_with_input(BenchmarkId::new("hash_map", n), &probes, |b, probes| {
            b.iter(|| {
                probes
                    .iter()
                    .filter_map(|key| hash.get(black_box(key)))
                    .map(value_len)
                    .sum::<usize>()
            })
        });
    }
    group.finish();
}

fn value_len(entry: &Entry) -> usize {
    entry.value().len()
}

fn bench_lookup_hit(c: &mut Criterion) {
    bench_lookups(c, "od_lookup_hit", present_key);
}

fn bench_lookup_miss(c: &mut Criterion) {
    bench_lookups(c, "od_lookup_miss", missing_key);
}

fn bench_insert(c: &mut Criterion) {
    let mut group = c.benchmark_group("od_insert");
    for n in SIZES {
        let base = dictionary(n, 1);
        // Keep the clones a batch sets up within about 32 MB.
        let batch = (32_000_000 / (n * (size_of::<Entry>() + 4))).clamp(8, 1_024) as u64;
        let at_end = ObjectKey::new(0xFFFF, 0);
        let at_front = ObjectKey::new(0x1000, 0);
        let mut rng = XorShift(0xD1B5_4A32_D192_ED03 ^ n as u64);

        for (name, mut next_key) in [
            (
                "append",
                Box::new(move || at_end) as Box<dyn FnMut() -> ObjectKey>,
            ),
            ("random", Box::new(move || missing_key(rng.below(n)))),
            ("front", Box::new(move || at_front)),
        ] {
            group.bench_function(BenchmarkId::new(name, n), |b| {
                b.iter_batched(
                    || (base.clone(), entry(next_key())),
                    |(mut od, new_entry)| {
                        black_box(od.insert(new_entry)).unwrap();
                        od
                    },
                    BatchSize::NumIterations(batch),
                )
            });
        }
    }
    group.finish();
}

/// Builds a dictionary of n entries from empty, the way a device sets up its dictionary at start-up:
/// keys in ascending order (every insert appends), in random order, and in descending order (every
/// insert goes to the front and shifts all entries), next to `from_entries` on the random order.
fn bench_build(c: &mut Criterion) {
    let mut group = c.benchmark_group("od_build");
    // Descending builds of 10,000 entries take a good part of a second each.
    group.sample_size(10);
    for n in SIZES {
        group.throughput(Throughput::Elements(n as u64));
        let ascending: Vec<ObjectKey> = (0..n).map(present_key).collect();
        let descending: Vec<ObjectKey> = ascending.iter().rev().copied().collect();
        let mut random = ascending.clone();
        let mut rng = XorShift(0x2545_F491_4F6C_DD1D ^ n as u64);
        for i in (1..random.len()).rev() {
            random.swap(i, rng.below(i + 1));
        }
        for (name, keys) in [
            ("ascending", &ascending),
            ("random", &random),
            ("descending", &descending),
        ] {
            group.bench_with_input(BenchmarkId::new(name, n), keys, |b, keys| {
                b.iter_batched(
                    || keys.iter().map(|&key| entry(key)).collect::<Vec<_>>(),
                    |entries| {
                        let mut od = DynamicOd::with_capacity(n);
                        for new_entry in entries {
                            od.insert(new_entry).unwrap();
                        }
                        od
                    },
                    BatchSize::LargeInput,
                )
            });
        }
        group.bench_with_input(BenchmarkId::new("from_entries_random", n), &random, |b, keys| {
            b.iter_batched(
                || keys.iter().map(|&key| entry(key)).collect::<Vec<_>>(),
                |entries| DynamicOd::from_entries(n, entries).unwrap(),
                BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

fn bench_value_storage(c: &mut Criterion) {
    const ENTRIES: usize = 10_000;
    const SHORT: &[u8] = &[1; 4];
    // One byte longer than the inline buffer, so every value lives on the heap.
    const LONG: &[u8] = &[1; 23];

    let mut group = c.benchmark_group("od_value_storage");
    group.throughput(Throughput::Elements(ENTRIES as u64));
    for (name, value) in [("inline_4_bytes", SHORT), ("heap_23_bytes", LONG)] {
        let keys: Vec<ObjectKey> = (0..ENTRIES).map(present_key).collect();
        group.bench_function(BenchmarkId::new("build_entries", name), |b| {
            b.iter(|| {
                keys.iter()
                    .map(|&key| Entry::new(key, DataType::DOMAIN, Access::Rw, black_box(value)).unwrap())
                    .collect::<Vec<_>>()
            })
        });
        let od = DynamicOd::from_entries(
            ENTRIES,
            keys.iter()
                .map(|&key| Entry::new(key, DataType::DOMAIN, Access::Rw, value).unwrap()),
        )
        .unwrap();
        group.bench_function(BenchmarkId::new("read_all_values", name), |b| {
            b.iter(|| {
                od.iter()
                    .map(|e| u64::from(e.value().first().copied().unwrap_or(0)))
                    .sum::<u64>()
            })
        });
    }
    group.finish();
}

criterion_group!(
    benches,
    bench_lookup_hit,
    bench_lookup_miss,
    bench_insert,
    bench_build,
    bench_value_storage
);
criterion_main!(benches);

//! P042, P043 and P044: the object lists `[MandatoryObjects]`, `[OptionalObjects]` and
//! `[ManufacturerObjects]` (CiA 306 V1.3 §4.6.3.1: `SupportedObjects=n`, then entries numbered
//! decimally 1..n, each naming one object index).

use std::collections::{BTreeMap, HashMap, HashSet};

use canopener_eds::model::{ObjectListKind, decimal_key, int_of};
use canopener_eds::section_name::SectionKind;
use canopener_eds::syntax::LineKind;
use canopener_eds::{Code, Origin};

use super::{Edit, Fix, Planned, number_like, shorten, with_key};
use crate::context::Context;

/// How many entries a description names before it says how many more there are.
const LISTED: usize = 8;

/// P044: renumbers a flagged list 1..N in file order, removes entries that repeat an index (a
/// repeat in another list goes from the list CiA 306 §4.6.3.1 does not assign the index to) and
/// sets `SupportedObjects` to the number of entries. Entries whose value is not an index are kept:
/// what they meant is not ours to guess.
pub(super) fn malformed(cx: &Context<'_>, out: &mut Planned) {
    let flagged = flagged_lists(cx, Code::MalformedObjectList);
    if flagged.is_empty() {
        return;
    }
    let lists = views(cx);
    let mut holders: HashMap<u16, Vec<ObjectListKind>> = HashMap::new();
    for list in &lists {
        for index in list.entries.iter().filter_map(|e| e.index) {
            let kinds = holders.entry(index).or_default();
            if !kinds.contains(&list.kind) {
                kinds.push(list.kind);
            }
        }
    }
    let keeper = |index: u16| -> Option<ObjectListKind> {
        let kinds = holders.get(&index)?;
        let assigned = ObjectListKind::for_index(index);
        if kinds.contains(&assigned) {
            Some(assigned)
        } else {
            kinds.first().copied()
        }
    };
    for list in &lists {
        let shares_flagged_index = list.entries.iter().filter_map(|e| e.index).any(|i| {
            holders
                .get(&i)
                .is_some_and(|k| k.len() > 1 && k.iter().any(|k| flagged.contains(k)))
        });
        if !flagged.contains(&list.kind) && !shares_flagged_index {
            continue;
        }
        let mut seen = HashSet::new();
        let mut keep = Vec::new();
        let mut removed = Vec::new();
        for entry in &list.entries {
            match entry.index {
                Some(index) if keeper(index) != Some(list.kind) => {
                    let elsewhere = keeper(index).map_or("", ObjectListKind::section_name);
                    removed.push(format!("{}={} (also in [{elsewhere}])", entry.key, entry.value));
                }
                Some(index) if !seen.insert(index) => {
                    removed.push(format!("{}={} (repeats {index:X}h)", entry.key, entry.value));
                }
                _ => keep.push(*entry),
            }
        }
        let (edits, changes) = list.rewrite(cx, &keep, &[], true);
        if edits.is_empty() {
            continue;
        }
        let mut parts = Vec::new();
        if !removed.is_empty() {
            parts.push(format!("remove {}", shorten(&removed, LISTED)));
        }
        parts.extend(changes);
        out.fixes.push(Fix {
            code: "P044".to_owned(),
            description: format!("[{}] {}", list.name, parts.join("; ")),
            changes_meaning: false,
            edits,
        });
    }
}

/// P042: removes from a flagged list the entries naming an index without an object section (as
/// the loader decides: an object only described by orphan sub-objects does not count), then
/// renumbers and recounts the list. The object dictionary the file describes stays the same.
pub(super) fn missing(cx: &Context<'_>, out: &mut Planned) {
    let flagged = flagged_lists(cx, Code::ListedObjectMissing);
    if flagged.is_empty() {
        return;
    }
    let exists = |index: u16| {
        cx.eds
            .objects
            .get(&index)
            .is_some_and(|o| o.origin != Origin::Orphan)
    };
    for list in views(cx) {
        if !flagged.contains(&list.kind) {
            continue;
        }
        let (keep, gone): (Vec<ListEntry<'_>>, Vec<ListEntry<'_>>) =
            list.entries.iter().partition(|e| e.index.is_none_or(exists));
        if gone.is_empty() {
            continue;
        }
        let (edits, changes) = list.rewrite(cx, &keep, &[], false);
        let names: Vec<String> = gone.iter().map(|e| format!("{}={}", e.key, e.value)).collect();
        let mut parts = vec![format!(
            "remove {} (no such object section)",
            shorten(&names, LISTED)
        )];
        parts.extend(changes);
        out.fixes.push(Fix {
            code: "P042".to_owned(),
            description: format!("[{}] {}", list.name, parts.join("; ")),
            changes_meaning: false,
            edits,
        });
    }
}

/// P043: adds every object no list names to the list CiA 306 §4.6.3.1 assigns it (1000h, 1001h,
/// 1018h mandatory; 2000h-5FFFh manufacturer; others optional), after the list's last entry, and
/// recounts; a missing list section is created at the end of the file. A list whose numbering is
/// already off (P044) is refused: a new entry number could collide with an existing one.
pub(super) fn unlisted(cx: &Context<'_>, out: &mut Planned) {
    if !cx.diagnostics.iter().any(|d| d.code == Code::UnlistedObject) {
        return;
    }
    // The loader's view: the first section of each list, the first of repeated keys.
    let listed: HashSet<u16> = cx
        .eds
        .object_lists
        .values()
        .flat_map(|list| list.0.numbered().map(|(_, v)| v))
        .filter_map(|v| u16::try_from(int_of(v)?).ok())
        .collect();
    let mut wanted: BTreeMap<ObjectListKind, Vec<u16>> = BTreeMap::new();
    for (&index, object) in &cx.eds.objects {
        if object.origin == Origin::Explicit && !listed.contains(&index) {
            wanted
                .entry(ObjectListKind::for_index(index))
                .or_default()
                .push(index);
        }
    }
    let lists = views(cx);
    for (kind, indices) in wanted {
        let shown: Vec<String> = indices.iter().map(|i| format!("{i:X}h")).collect();
        match lists.iter().find(|l| l.kind == kind) {
            Some(list) if list.is_regular() => {
                let (edits, changes) = list.rewrite(cx, &list.entries, &indices, false);
                out.fixes.push(Fix {
                    code: "P043".to_owned(),
                    description: format!("[{}] {}", list.name, changes.join("; ")),
                    changes_meaning: false,
                    edits,
                });
            }
            Some(list) => out.refused.push((
                Fix {
                    code: "P043".to_owned(),
                    description: format!("[{}] add {}", list.name, shorten(&shown, LISTED)),
                    changes_meaning: false,
                    edits: Vec::new(),
                },
                format!(
                    "[{}] is not numbered 1..SupportedObjects; fix that first (P044)",
                    list.name
                ),
            )),
            None => {
                let name = kind.section_name();
                let mut lines = Vec::new();
                if cx
                    .document
                    .lines()
                    .last()
                    .is_some_and(|l| l.kind != LineKind::Blank)
                {
                    lines.push(String::new());
                }
                lines.push(format!("[{name}]"));
                lines.push(format!("SupportedObjects={}", indices.len()));
                lines.extend(
                    indices
                        .iter()
                        .enumerate()
                        .map(|(n, i)| format!("{}=0x{i:04X}", n + 1)),
                );
                out.fixes.push(Fix {
                    code: "P043".to_owned(),
                    description: format!("create [{name}] listing {}", shorten(&shown, LISTED)),
                    changes_meaning: false,
                    edits: vec![Edit::AppendLines { lines }],
                });
            }
        }
    }
}

/// The lists named by diagnostics of this code.
fn flagged_lists(cx: &Context<'_>, code: Code) -> HashSet<ObjectListKind> {
    cx.diagnostics
        .iter()
        .filter(|d| d.code == code)
        .filter_map(|d| {
            let name = d.section.as_deref()?;
            ObjectListKind::ALL
                .into_iter()
                .find(|k| k.section_name().eq_ignore_ascii_case(name))
        })
        .collect()
}

/// One object list section as written.
#[derive(Debug)]
struct ListView<'a> {
    kind: ObjectListKind,
    /// Index into the document's sections.
    section: usize,
    /// The name as written.
    name: &'a str,
    /// The first `SupportedObjects` entry: line and value.
    count: Option<(usize, &'a str)>,
    /// Entries whose key is made of digits, in file order (`01` included, so it gets renumbered).
    entries: Vec<ListEntry<'a>>,
}

#[derive(Debug, Clone, Copy)]
struct ListEntry<'a> {
    line: usize,
    key: &'a str,
    value: &'a str,
    index: Option<u16>,
}

/// The first section of each list, as the loader reads them.
fn views<'a>(cx: &Context<'a>) -> Vec<ListView<'a>> {
    let doc = cx.document;
    let mut out = Vec::new();
    for kind in ObjectListKind::ALL {
        let Some(&section) = cx.sections_of(SectionKind::ObjectList(kind)).first() else {
            continue;
        };
        let Some(s) = doc.sections().get(section) else {
            continue;
        };
        let mut view = ListView {
            kind,
            section,
            name: doc.section_name(s),
            count: None,
            entries: Vec::new(),
        };
        for &line in doc.entries(s) {
            let Some((key, value)) = doc.entry(line) else {
                continue;
            };
            if key.eq_ignore_ascii_case("SupportedObjects") {
                view.count.get_or_insert((line, value));
            } else if !key.is_empty() && key.bytes().all(|b| b.is_ascii_digit()) {
                view.entries.push(ListEntry {
                    line,
                    key,
                    value,
                    index: int_of(value).and_then(|v| u16::try_from(v).ok()),
                });
            }
        }
        out.push(view);
    }
    out
}

impl ListView<'_> {
    /// Numbered 1..N in order with `SupportedObjects=N`: new entries can go after the last one.
    fn is_regular(&self) -> bool {
        let numbered = self
            .entries
            .iter()
            .enumerate()
            .all(|(n, e)| decimal_key(e.key).is_some_and(|k| k as usize == n + 1));
        numbered
            && self
                .count
                .is_some_and(|(_, c)| int_of(c) == Some(self.entries.len() as i128))
    }

    /// The edits that turn this list into `keep` (a subsequence of its entries) followed by new
    /// entries for `add`, numbered 1..N, with `SupportedObjects=N` (added when missing only if
    /// `add_count`). Returns the edits and what they do in words.
    fn rewrite(
        &self,
        cx: &Context<'_>,
        keep: &[ListEntry<'_>],
        add: &[u16],
        add_count: bool,
    ) -> (Vec<Edit>, Vec<String>) {
        let doc = cx.document;
        let mut edits = Vec::new();
        let mut words = Vec::new();
        let kept: HashSet<usize> = keep.iter().map(|e| e.line).collect();
        for entry in &self.entries {
            if !kept.contains(&entry.line) {
                edits.push(Edit::DeleteLine { line: entry.line });
            }
        }
        let mut renumbered = Vec::new();
        for (n, entry) in keep.iter().enumerate() {
            let key = (n + 1).to_string();
            if entry.key == key {
                continue;
            }
            if let Some(content) = with_key(doc, entry.line, &key) {
                renumbered.push(format!("{} -> {key}", entry.key));
                edits.push(Edit::ReplaceLine {
                    line: entry.line,
                    content,
                });
            }
        }
        if !renumbered.is_empty() {
            words.push(format!("renumber entries {}", shorten(&renumbered, 3)));
        }
        let style = self.entries.first().map_or("0x1000", |e| e.value);
        let mut added = Vec::new();
        for (n, &index) in add.iter().enumerate() {
            let key = (keep.len() + n + 1).to_string();
            let value = index_like(style, index);
            added.push(format!("{key}={value}"));
            edits.push(Edit::AppendEntry {
                section: self.section,
                key,
                value,
            });
        }
        if !added.is_empty() {
            words.push(format!("add {}", shorten(&added, LISTED)));
        }
        let total = keep.len() + add.len();
        match self.count {
            Some((line, old)) if int_of(old) != Some(total as i128) => {
                let new = number_like(old, total as u64);
                let key = doc.entry(line).map_or("SupportedObjects", |(k, _)| k);
                words.push(format!("{key}: {old} -> {new}"));
                edits.push(Edit::SetValue { line, value: new });
            }
            // Unchanged, but claimed: two fixes of one list in one round would each count the
            // entries without the other's changes. The line is written back byte for byte.
            Some((line, old)) if !edits.is_empty() => edits.push(Edit::SetValue {
                line,
                value: old.to_owned(),
            }),
            None if add_count => {
                words.push(format!("add SupportedObjects={total}"));
                edits.push(Edit::AppendEntry {
                    section: self.section,
                    key: "SupportedObjects".to_owned(),
                    value: total.to_string(),
                });
            }
            _ => {}
        }
        (edits, words)
    }
}

/// An index written like the list's first entry (`0x1a00` stays lower case), `0x1000` style otherwise.
fn index_like(style: &str, index: u16) -> String {
    let digits = style
        .strip_prefix("0x")
        .or_else(|| style.strip_prefix("0X"))
        .unwrap_or("");
    let prefix = style.get(..2).filter(|p| *p == "0X").unwrap_or("0x");
    if digits.bytes().any(|b| b.is_ascii_lowercase()) && !digits.bytes().any(|b| b.is_ascii_uppercase()) {
        format!("{prefix}{index:04x}")
    } else {
        format!("{prefix}{index:04X}")
    }
}

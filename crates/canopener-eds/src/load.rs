//! Building the [`Eds`] model from a [`Document`], with diagnostics for every departure from CiA 306.
//!
//! Loading never fails. Duplicate sections and keys keep their first occurrence (as CANopenEditor
//! does) and are reported with both line numbers; sections canopener does not know are kept in
//! [`Eds::other_sections`]; compact forms (CiA 306 §4.6.3.4) are expanded into generated objects and
//! sub-objects marked with their [`Origin`], which the writers do not emit again.

use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};
use std::hash::{BuildHasherDefault, Hash, Hasher};

use crate::diag::{Code, Diagnostic, Span};
use crate::model::{
    Attributes, CommissioningSpelling, DeviceCommissioning, DeviceInfo, Eds, FileInfo, Module, ModuleInfo,
    Object, ObjectList, ObjectListKind, Origin, Properties, Property, RawSection, SubObject, int_of,
};
use crate::section_name::{self, Companion, ModulePart, SectionKind};
use crate::syntax::{Document, Section};
use crate::types::{DataType, ObjectType, TypeKind};
use crate::value;

/// Where a finding points when it has no section of its own (a generated object, a missing key): the
/// start of the file, so every span names a real line.
const FILE_START: Span = Span {
    line: 1,
    column: 1,
    len: 0,
};

/// A loaded file: the lossless document, the model and what was found on the way.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// The lossless syntax tree (writes back byte-identical).
    pub document: Document,
    /// The object dictionary model.
    pub eds: Eds,
    /// Diagnostics, sorted by position.
    pub diagnostics: Vec<Diagnostic>,
}

/// Loads an EDS or DCF from its bytes. Never panics, never fails.
pub fn load(bytes: &[u8]) -> Loaded {
    let (document, mut diagnostics) = Document::parse(bytes);
    let eds = build(&document, &mut diagnostics);
    diagnostics.sort_by_key(|d| (d.span.line, d.span.column));
    Loaded {
        document,
        eds,
        diagnostics,
    }
}

/// Builds the model from an already parsed document, appending diagnostics.
pub fn build(document: &Document, diagnostics: &mut Vec<Diagnostic>) -> Eds {
    let mut loader = Loader {
        doc: document,
        diags: diagnostics,
        eds: Eds::default(),
        key_case_seen: HashSet::new(),
        list_sections: BTreeMap::new(),
        seen_buffer: Vec::new(),
    };
    loader.run();
    loader.eds
}

struct Loader<'a> {
    doc: &'a Document,
    diags: &'a mut Vec<Diagnostic>,
    eds: Eds,
    key_case_seen: HashSet<String>,
    /// Section index of each object list, to point at its entries without a name lookup.
    list_sections: BTreeMap<ObjectListKind, usize>,
    /// Reused between sections, so reading a section allocates nothing but the values it keeps.
    seen_buffer: Vec<(&'a str, usize)>,
}

/// Where an object's sections are, to point diagnostics at them. Looked up once or twice per section
/// and never iterated, so hash maps with [`IndexHasher`] serve better than ordered maps.
#[derive(Default)]
struct Places {
    objects: HashMap<u16, usize, BuildHasherDefault<IndexHasher>>,
    subs: HashMap<(u16, u8), usize, BuildHasherDefault<IndexHasher>>,
}

/// A multiplicative hash for the small keys of [`Places`] and [`KeysSeen`]: SipHash's resistance to
/// chosen keys buys nothing here and costs more than the rest of the lookup.
#[derive(Default)]
struct IndexHasher(u64);

impl IndexHasher {
    fn add(&mut self, n: u64) {
        self.0 = (self.0.rotate_left(16) ^ n).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

impl Hasher for IndexHasher {
    fn write(&mut self, bytes: &[u8]) {
        bytes.iter().for_each(|&b| self.add(u64::from(b)));
    }

    fn write_u8(&mut self, n: u8) {
        self.add(u64::from(n));
    }

    fn write_u16(&mut self, n: u16) {
        self.add(u64::from(n));
    }

    fn finish(&self) -> u64 {
        // The product's high bits are the well-mixed ones; the table indexes with the low bits.
        self.0.rotate_left(32)
    }
}

impl<'a> Loader<'a> {
    fn run(&mut self) {
        let doc = self.doc;
        // Objects and sub-objects (nearly every section) are told apart through `places`; the rest here.
        let mut first_of: HashMap<(SectionKind, String), usize> = HashMap::new();
        let mut places = Places::default();
        let mut subs: Vec<(u16, u8, usize)> = Vec::new();
        let mut companions: Vec<(u16, Companion, usize)> = Vec::new();
        let mut module_parts: Vec<(u32, ModulePart, usize)> = Vec::new();
        for (i, section) in doc.sections().iter().enumerate() {
            let name = doc.section_name(section);
            let kind = section_name::classify(name);
            // Unknown sections are told apart by name; known ones by meaning (`[1018]` = `[01018]`).
            let identity = match kind {
                SectionKind::Object(_) | SectionKind::Sub(..) => None,
                SectionKind::Unknown => Some((kind, name.to_ascii_lowercase())),
                _ => Some((kind.identity(), String::new())),
            };
            let first = match (kind, &identity) {
                (SectionKind::Object(index), _) => places.objects.get(&index).copied(),
                (SectionKind::Sub(index, sub), _) => places.subs.get(&(index, sub)).copied(),
                (_, Some(identity)) => first_of.get(identity).copied(),
                _ => None,
            };
            if let Some(first) = first {
                let first_line = doc.sections().get(first).map_or(0, |s| s.header_line + 1);
                self.push(
                    Diagnostic::new(
                        Code::DuplicateSection,
                        doc.line_span(section.header_line),
                        format!("section [{name}] repeats the section on line {first_line}; its entries are ignored"),
                    )
                    .at(Some(name), None)
                    .with_help(
                        "merge the two sections; python canopen and lely crash on duplicates, CANopenEditor keeps the first",
                    ),
                );
                continue;
            }
            match (kind, identity) {
                (SectionKind::Object(index), _) => {
                    places.objects.insert(index, i);
                }
                (SectionKind::Sub(index, sub), _) => {
                    places.subs.insert((index, sub), i);
                }
                (_, Some(identity)) => {
                    first_of.insert(identity, i);
                }
                _ => {}
            }
            self.check_section_spelling(section, kind);
            match kind {
                SectionKind::FileInfo => self.eds.file_info = self.keyed::<FileInfoKeys>(section),
                SectionKind::DeviceInfo => self.eds.device_info = self.keyed::<DeviceInfoKeys>(section),
                SectionKind::DummyUsage => self.eds.dummy_usage = Some(self.properties(section)),
                SectionKind::Comments => self.eds.comments = Some(self.properties(section)),
                SectionKind::ObjectList(list) => {
                    self.list_sections.insert(list, i);
                    let props = self.properties(section);
                    self.eds.object_lists.insert(list, ObjectList(props));
                }
                SectionKind::Commissioning(spelling) => {
                    self.eds.commissioning = Some(self.keyed::<CommissioningKeys>(section));
                    self.eds.commissioning_spelling = spelling;
                }
                SectionKind::Tools => self.eds.tools = Some(self.properties(section)),
                SectionKind::Tool(n) => {
                    let props = self.properties(section);
                    self.eds.tool_sections.insert(n, props);
                }
                SectionKind::DynamicChannels => self.eds.dynamic_channels = Some(self.properties(section)),
                SectionKind::SupportedModules => self.eds.supported_modules = Some(self.properties(section)),
                SectionKind::ConnectedModules => self.eds.connected_modules = Some(self.properties(section)),
                SectionKind::Object(index) => {
                    let attributes = self.keyed::<AttributeKeys>(section);
                    self.eds.objects.insert(
                        index,
                        Object {
                            attributes,
                            ..Object::default()
                        },
                    );
                }
                SectionKind::Sub(index, sub) => subs.push((index, sub, i)),
                SectionKind::Companion(index, companion) => companions.push((index, companion, i)),
                SectionKind::Module(x, part) => module_parts.push((x, part, i)),
                SectionKind::Unknown => {
                    let why = if section_name::is_sub_index_out_of_range(name) {
                        "names a sub-index above FFh, which CiA 301 does not have"
                    } else {
                        "is not defined by CiA 306"
                    };
                    self.push(
                        Diagnostic::new(
                            Code::UnknownSection,
                            doc.line_span(section.header_line),
                            format!("section [{name}] {why}; it is kept as it is"),
                        )
                        .at(Some(name), None),
                    );
                    let entries = self.properties(section);
                    self.eds.other_sections.push(RawSection {
                        name: name.to_owned(),
                        entries,
                    });
                }
            }
        }
        self.check_mandatory_sections(&first_of);
        self.attach_subs(subs);
        self.attach_companions(companions);
        self.load_modules(module_parts);
        self.expand_compact_sub_obj(&places);
        self.expand_compact_pdo();
        self.check_object_lists(&places);
        self.check_objects(&places);
        self.check_pdo_pairs(&places);
    }

    /// CiA 306 §4.1: `[FileInfo]`, `[DeviceInfo]` and the object lists (at least `[MandatoryObjects]`).
    fn check_mandatory_sections(&mut self, present: &HashMap<(SectionKind, String), usize>) {
        let end = Span::new(
            u32::try_from(self.doc.lines().len().max(1)).unwrap_or(u32::MAX),
            1,
            0,
        );
        if self.doc.lines().is_empty() {
            self.push(
                Diagnostic::new(Code::MissingSection, Span::new(1, 1, 0), "the file is empty")
                    .with_help("an EDS needs at least [FileInfo], [DeviceInfo], [MandatoryObjects] and objects 1000h, 1001h, 1018h"),
            );
            return;
        }
        for (kind, name) in [
            (SectionKind::FileInfo, "FileInfo"),
            (SectionKind::DeviceInfo, "DeviceInfo"),
            (
                SectionKind::ObjectList(ObjectListKind::Mandatory),
                "MandatoryObjects",
            ),
        ] {
            if !present.contains_key(&(kind, String::new())) {
                self.push(
                    Diagnostic::new(
                        Code::MissingSection,
                        end,
                        format!("the file has no [{name}] section"),
                    )
                    .with_help(format!(
                        "CiA 306 makes [{name}] mandatory; CANopenEditor throws on a file without it"
                    )),
                );
            }
        }
    }

    fn push(&mut self, diagnostic: Diagnostic) {
        self.diags.push(diagnostic);
    }

    fn section_at(&self, i: usize) -> Option<&'a Section> {
        self.doc.sections().get(i)
    }

    fn check_section_spelling(&mut self, section: &Section, kind: SectionKind) {
        let name = self.doc.section_name(section);
        if section_name::is_canonical_object_name(name, kind) == Some(true) {
            return;
        }
        let Some(canonical) = section_name::canonical_name(kind) else {
            return;
        };
        if name.eq_ignore_ascii_case(&canonical) {
            if kind == SectionKind::Commissioning(CommissioningSpelling::DeviceCommissioning) {
                self.push(
                    Diagnostic::new(
                        Code::NonCanonicalSectionName,
                        self.doc.line_span(section.header_line),
                        "CiA 306 spells this section [DeviceComissioning] (one `m`)",
                    )
                    .at(Some(name), None)
                    .with_help("python canopen, lely and CANopenEditor accept both; CiA's tools expect the spec spelling"),
                );
            }
            let is_sub_with_upper = matches!(
                kind,
                SectionKind::Sub(..) | SectionKind::Module(_, ModulePart::FixedSub(..))
            ) && !name.contains("sub");
            if is_sub_with_upper {
                self.push(
                    Diagnostic::new(
                        Code::NonCanonicalSectionName,
                        self.doc.line_span(section.header_line),
                        format!("[{name}] does not write `sub` in lower case; python canopen and CANopenEditor lose it"),
                    )
                    .at(Some(name), None)
                    .with_help(format!("rename the section to [{canonical}]")),
                );
            }
            return;
        }
        if matches!(
            kind,
            SectionKind::Object(_)
                | SectionKind::Sub(..)
                | SectionKind::Companion(..)
                | SectionKind::Module(..)
        ) {
            self.push(
                Diagnostic::new(
                    Code::NonCanonicalSectionName,
                    self.doc.line_span(section.header_line),
                    format!("[{name}] has leading zeros; CiA 306 writes it [{canonical}] and lely does not find it"),
                )
                .at(Some(name), None)
                .with_help(format!("rename the section to [{canonical}]")),
            );
        }
    }

    /// Reads a section with a fixed key set.
    fn keyed<K: KeySet>(&mut self, section: &Section) -> K::Target {
        let doc = self.doc;
        let section_name = doc.section_name(section);
        let mut target = K::Target::default();
        let mut seen = KeysSeen {
            keys: std::mem::take(&mut self.seen_buffer),
            index: None,
        };
        seen.keys.clear();
        for &line in doc.entries(section) {
            let Some((key, value)) = doc.entry(line) else {
                continue;
            };
            if !self.first_key(&mut seen, section_name, key, line) {
                continue;
            }
            match K::slot(&mut target, key) {
                Some((slot, canonical)) => {
                    *slot = Some(value.to_owned());
                    if key != canonical && self.key_case_seen.insert(key.to_owned()) {
                        self.push(
                            Diagnostic::new(
                                Code::KeyCase,
                                doc.key_span(line),
                                format!("key `{key}` is spelt `{canonical}` in CiA 306 (first of possibly several)"),
                            )
                            .at(Some(section_name), Some(key))
                            .with_help("python canopen matches keys case-sensitively and will not find it"),
                        );
                    }
                }
                None => {
                    let reserved = K::RESERVED.iter().any(|r| r.eq_ignore_ascii_case(key));
                    let (code, message) = if reserved {
                        (
                            Code::ReservedKey,
                            format!("key `{key}` is reserved by CiA 306 for compatibility"),
                        )
                    } else {
                        (
                            Code::UnknownKey,
                            format!("key `{key}` is not defined by CiA 306 for [{section_name}]; kept"),
                        )
                    };
                    self.push(
                        Diagnostic::new(code, doc.key_span(line), message).at(Some(section_name), Some(key)),
                    );
                    K::extra(&mut target).push(Property {
                        key: key.to_owned(),
                        value: value.to_owned(),
                    });
                }
            }
        }
        self.seen_buffer = seen.keys;
        target
    }

    /// Reads a section with free keys (lists, comments, ...).
    fn properties(&mut self, section: &Section) -> Properties {
        let doc = self.doc;
        let section_name = doc.section_name(section);
        let mut seen = KeysSeen {
            keys: std::mem::take(&mut self.seen_buffer),
            index: None,
        };
        seen.keys.clear();
        let mut out = Vec::with_capacity(section.entries.len());
        for &line in doc.entries(section) {
            let Some((key, value)) = doc.entry(line) else {
                continue;
            };
            if self.first_key(&mut seen, section_name, key, line) {
                out.push(Property {
                    key: key.to_owned(),
                    value: value.to_owned(),
                });
            }
        }
        self.seen_buffer = seen.keys;
        Properties(out)
    }

    /// Records a key; reports it and returns false when it repeats an earlier key of the section.
    fn first_key(&mut self, seen: &mut KeysSeen<'a>, section: &str, key: &'a str, line: usize) -> bool {
        match seen.first(key) {
            Some(first) => {
                let kept = self.doc.entry(first).map_or("", |(_, v)| v);
                self.push(
                    Diagnostic::new(
                        Code::DuplicateKey,
                        self.doc.key_span(line),
                        format!(
                            "key `{key}` repeats line {} in [{section}]; the first value `{kept}` is used",
                            first + 1
                        ),
                    )
                    .at(Some(section), Some(key))
                    .with_help(
                        "delete one of the two lines; python canopen and lely crash on duplicate keys",
                    ),
                );
                false
            }
            None => {
                seen.insert(key, line);
                true
            }
        }
    }

    fn attach_subs(&mut self, subs: Vec<(u16, u8, usize)>) {
        for (index, sub, i) in subs {
            let Some(section) = self.section_at(i) else {
                continue;
            };
            let attributes = self.keyed::<AttributeKeys>(section);
            if !self.eds.objects.contains_key(&index) {
                let name = self.doc.section_name(section).to_owned();
                self.push(
                    Diagnostic::new(
                        Code::OrphanSubObject,
                        self.doc.line_span(section.header_line),
                        format!("[{name}] has no object section [{index:X}]; kept as an orphan"),
                    )
                    .at(Some(&name), None)
                    .with_help(format!(
                        "add a [{index:X}] section or delete [{name}]; python canopen crashes on it"
                    )),
                );
                self.eds.objects.insert(
                    index,
                    Object {
                        origin: Origin::Orphan,
                        ..Object::default()
                    },
                );
            }
            if let Some(object) = self.eds.objects.get_mut(&index) {
                object.subs.insert(
                    sub,
                    SubObject {
                        attributes,
                        origin: Origin::Explicit,
                    },
                );
            }
        }
    }

    fn attach_companions(&mut self, companions: Vec<(u16, Companion, usize)>) {
        for (index, companion, i) in companions {
            let Some(section) = self.section_at(i) else {
                continue;
            };
            let props = self.properties(section);
            if !self.eds.objects.contains_key(&index) {
                let name = self.doc.section_name(section).to_owned();
                self.push(
                    Diagnostic::new(
                        Code::OrphanCompanion,
                        self.doc.line_span(section.header_line),
                        format!("[{name}] belongs to object {index:X}h, which has no section"),
                    )
                    .at(Some(&name), None),
                );
                self.eds.objects.insert(
                    index,
                    Object {
                        origin: Origin::Orphan,
                        ..Object::default()
                    },
                );
            }
            let Some(object) = self.eds.objects.get_mut(&index) else {
                continue;
            };
            let slot = match companion {
                Companion::Name => &mut object.names,
                Companion::Value => &mut object.values,
                Companion::Denotation => &mut object.denotations,
                Companion::ObjectLinks => &mut object.object_links,
            };
            *slot = Some(props);
        }
    }

    fn load_modules(&mut self, parts: Vec<(u32, ModulePart, usize)>) {
        let declared = self
            .eds
            .supported_modules
            .as_ref()
            .and_then(|p| p.get("NrOfEntries"))
            .and_then(int_of);
        let mut reported = HashSet::new();
        let mut fixed_subs = Vec::new();
        for (x, part, i) in parts {
            let Some(section) = self.section_at(i) else {
                continue;
            };
            if declared.is_none_or(|n| i128::from(x) > n || x == 0) && reported.insert(x) {
                let name = self.doc.section_name(section).to_owned();
                self.push(
                    Diagnostic::new(
                        Code::UnlistedModule,
                        self.doc.line_span(section.header_line),
                        format!(
                            "[{name}] describes module {x}, but [SupportedModules] declares {}",
                            match declared {
                                Some(n) => format!("{n} module(s)"),
                                None => "none".to_owned(),
                            }
                        ),
                    )
                    .at(Some(&name), None),
                );
            }
            match part {
                ModulePart::FixedSub(index, sub) | ModulePart::SubExtSub(index, sub) => {
                    fixed_subs.push((x, part, index, sub, section));
                    continue;
                }
                _ => {}
            }
            match part {
                ModulePart::Info => {
                    let info = self.keyed::<ModuleInfoKeys>(section);
                    self.module(x).info = info;
                }
                ModulePart::Comments => {
                    let p = self.properties(section);
                    self.module(x).comments = Some(p);
                }
                ModulePart::FixedObjects => {
                    let p = self.properties(section);
                    self.module(x).fixed_objects = Some(p);
                }
                ModulePart::SubExtends => {
                    let p = self.properties(section);
                    self.module(x).sub_extends = Some(p);
                }
                ModulePart::Fixed(index) => {
                    let attributes = self.keyed::<AttributeKeys>(section);
                    self.module(x).fixed.insert(
                        index,
                        Object {
                            attributes,
                            ..Object::default()
                        },
                    );
                }
                ModulePart::SubExt(index) => {
                    let attributes = self.keyed::<AttributeKeys>(section);
                    self.module(x).sub_ext.insert(
                        index,
                        Object {
                            attributes,
                            ..Object::default()
                        },
                    );
                }
                ModulePart::FixedSub(..) | ModulePart::SubExtSub(..) => {}
            }
        }
        for (x, part, index, sub, section) in fixed_subs {
            let attributes = self.keyed::<AttributeKeys>(section);
            let module = self.module(x);
            let map = if matches!(part, ModulePart::FixedSub(..)) {
                &mut module.fixed
            } else {
                &mut module.sub_ext
            };
            let object = map.entry(index).or_insert_with(|| Object {
                origin: Origin::Orphan,
                ..Object::default()
            });
            object.subs.insert(
                sub,
                SubObject {
                    attributes,
                    origin: Origin::Explicit,
                },
            );
        }
    }

    fn module(&mut self, x: u32) -> &mut Module {
        self.eds.modules.entry(x).or_default()
    }

    /// CiA 306 §4.6.3.4.2: `CompactSubObj=n` implies sub 0 `NrOfObjects` and subs 1..=n.
    fn expand_compact_sub_obj(&mut self, places: &Places) {
        let indices: Vec<u16> = self.eds.objects.keys().copied().collect();
        for index in indices {
            let Some(object) = self.eds.objects.get(&index) else {
                continue;
            };
            let Some(raw) = object.attributes.compact_sub_obj.clone() else {
                continue;
            };
            let section = places.objects.get(&index).and_then(|&i| self.section_at(i));
            let line = section
                .as_ref()
                .and_then(|s| self.doc.find_entry(s, "CompactSubObj"));
            let span = line.map_or(FILE_START, |l| self.doc.value_span(l));
            let at = section.as_ref().map(|s| self.doc.section_name(s).to_owned());
            let n = match int_of(&raw) {
                Some(n) => n,
                None if raw.trim().is_empty() => continue,
                None => {
                    self.push(
                        Diagnostic::new(
                            Code::InvalidCompactSubObj,
                            span,
                            format!("CompactSubObj `{raw}` is not a number"),
                        )
                        .at(at.as_deref(), Some("CompactSubObj")),
                    );
                    continue;
                }
            };
            if n == 0 {
                continue;
            }
            let object_type = object.object_type();
            if matches!(object_type, Some(ObjectType::Var | ObjectType::Domain)) {
                self.push(
                    Diagnostic::new(
                        Code::InvalidCompactSubObj,
                        span,
                        "CompactSubObj on a VAR or DOMAIN is ignored",
                    )
                    .at(at.as_deref(), Some("CompactSubObj")),
                );
                continue;
            }
            if object.attributes.sub_number().is_some_and(|s| s != 0) {
                self.push(
                    Diagnostic::new(
                        Code::InvalidCompactSubObj,
                        span,
                        "both SubNumber and CompactSubObj are given; CiA 306 allows only one",
                    )
                    .at(at.as_deref(), Some("CompactSubObj")),
                );
            }
            let count = match u8::try_from(n) {
                Ok(c) if c <= 254 => c,
                _ => {
                    self.push(
                        Diagnostic::new(
                            Code::InvalidCompactSubObj,
                            span,
                            format!("CompactSubObj {n} exceeds 254; using 254"),
                        )
                        .at(at.as_deref(), Some("CompactSubObj")),
                    );
                    254
                }
            };
            self.check_compact_companions(index, count);
            let Some(object) = self.eds.objects.get_mut(&index) else {
                continue;
            };
            let main = object.attributes.clone();
            let base_name = main.parameter_name.clone().unwrap_or_default();
            object.subs.entry(0).or_insert_with(|| SubObject {
                attributes: Attributes {
                    parameter_name: Some("NrOfObjects".to_owned()),
                    object_type: Some("0x7".to_owned()),
                    data_type: Some("0x0005".to_owned()),
                    access_type: Some("ro".to_owned()),
                    default_value: Some(count.to_string()),
                    pdo_mapping: Some("0".to_owned()),
                    ..Attributes::default()
                },
                origin: Origin::CompactSubObj,
            });
            for sub in 1..=count {
                let key = sub.to_string();
                let name = object
                    .names
                    .as_ref()
                    .and_then(|p| p.get(&key))
                    .map_or_else(|| format!("{base_name}{sub}"), str::to_owned);
                let parameter_value = object
                    .values
                    .as_ref()
                    .and_then(|p| p.get(&key))
                    .map(str::to_owned);
                let denotation = object
                    .denotations
                    .as_ref()
                    .and_then(|p| p.get(&key))
                    .map(str::to_owned);
                object.subs.entry(sub).or_insert_with(|| SubObject {
                    attributes: Attributes {
                        parameter_name: Some(name),
                        object_type: Some("0x7".to_owned()),
                        data_type: main.data_type.clone(),
                        access_type: main.access_type.clone(),
                        default_value: main.default_value.clone(),
                        pdo_mapping: main.pdo_mapping.clone(),
                        parameter_value,
                        denotation,
                        ..Attributes::default()
                    },
                    origin: Origin::CompactSubObj,
                });
            }
        }
    }

    fn check_compact_companions(&mut self, index: u16, count: u8) {
        let Some(object) = self.eds.objects.get(&index) else {
            return;
        };
        let mut findings = Vec::new();
        for (companion, props) in [
            (Companion::Name, &object.names),
            (Companion::Value, &object.values),
            (Companion::Denotation, &object.denotations),
        ] {
            let Some(props) = props else { continue };
            for p in &props.0 {
                if p.key.eq_ignore_ascii_case("NrOfEntries") {
                    continue;
                }
                let ok = crate::model::decimal_key(&p.key).is_some_and(|n| n >= 1 && n <= u32::from(count));
                if !ok {
                    findings.push((companion, p.key.clone()));
                }
            }
        }
        for (companion, key) in findings {
            let section_name = format!("{index:X}{}", companion.suffix());
            let span = self.find_key_span(&section_name, &key);
            self.push(
                Diagnostic::new(
                    Code::CompactEntryOutOfRange,
                    span,
                    format!(
                        "entry `{key}` of [{section_name}] is not a sub-index 1..={count} in decimal; ignored"
                    ),
                )
                .at(Some(&section_name), Some(&key)),
            );
        }
    }

    fn list_key_span(&self, list: ObjectListKind, key: &str) -> Span {
        self.list_sections
            .get(&list)
            .and_then(|&i| self.doc.sections().get(i))
            .and_then(|s| self.doc.find_entry(s, key))
            .map_or(FILE_START, |l| self.doc.key_span(l))
    }

    fn find_key_span(&self, section: &str, key: &str) -> Span {
        self.doc
            .section(section)
            .and_then(|s| self.doc.find_entry(s, key))
            .map_or(FILE_START, |l| self.doc.key_span(l))
    }

    /// CiA 306 §4.6.3.4.1: with `CompactPDO`, the PDOs `NrOfRXPDO`/`NrOfTXPDO` promise but the file does
    /// not describe are implied, filling the lowest free PDO numbers.
    fn expand_compact_pdo(&mut self) {
        let Some(mask) = self.eds.device_info.compact_pdo.as_deref().and_then(int_of) else {
            return;
        };
        if mask == 0 {
            return;
        }
        let info = &self.eds.device_info;
        let rx = info
            .nr_of_rx_pdo
            .as_deref()
            .and_then(int_of)
            .unwrap_or(0)
            .clamp(0, 512);
        let tx = info
            .nr_of_tx_pdo
            .as_deref()
            .and_then(int_of)
            .unwrap_or(0)
            .clamp(0, 512);
        for (count, comm_base, map_base, receive) in
            [(rx, 0x1400u16, 0x1600u16, true), (tx, 0x1800, 0x1A00, false)]
        {
            let explicit = self.eds.objects.range(comm_base..comm_base + 0x200).count();
            let mut implied = usize::try_from(count).unwrap_or(0).saturating_sub(explicit);
            let mut n = 0u16;
            while implied > 0 && n < 512 {
                if let std::collections::btree_map::Entry::Vacant(slot) =
                    self.eds.objects.entry(comm_base + n)
                {
                    slot.insert(implied_comm(n, receive, mask));
                    self.eds
                        .objects
                        .entry(map_base + n)
                        .or_insert_with(|| implied_mapping(n, receive));
                    implied -= 1;
                }
                n += 1;
            }
        }
    }

    fn check_object_lists(&mut self, places: &Places) {
        let mut listed: HashMap<u16, ObjectListKind> = HashMap::new();
        let lists: Vec<(ObjectListKind, ObjectList)> = self
            .eds
            .object_lists
            .iter()
            .map(|(k, v)| (*k, v.clone()))
            .collect();
        for (kind, list) in lists {
            let section_name = kind.section_name();
            let entries: Vec<(u32, String)> = list.0.numbered().map(|(n, v)| (n, v.to_owned())).collect();
            match list.declared_count().map(|c| (c, int_of(c))) {
                Some((_, Some(count))) if count != entries.len() as i128 => {
                    let span = self.list_key_span(kind, "SupportedObjects");
                    self.push(
                        Diagnostic::new(
                            Code::MalformedObjectList,
                            span,
                            format!(
                                "SupportedObjects={count} but [{section_name}] has {} numbered entries",
                                entries.len()
                            ),
                        )
                        .at(Some(section_name), Some("SupportedObjects")),
                    );
                }
                Some((raw, None)) => {
                    let span = self.list_key_span(kind, "SupportedObjects");
                    self.push(
                        Diagnostic::new(
                            Code::MalformedObjectList,
                            span,
                            format!("SupportedObjects `{raw}` is not a number"),
                        )
                        .at(Some(section_name), Some("SupportedObjects")),
                    );
                }
                _ => {}
            }
            for p in &list.0.0 {
                if p.key.eq_ignore_ascii_case("SupportedObjects")
                    || crate::model::decimal_key(&p.key).is_some()
                {
                    continue;
                }
                let span = self.list_key_span(kind, &p.key);
                self.push(
                    Diagnostic::new(
                        Code::MalformedObjectList,
                        span,
                        format!(
                            "entry `{}` of [{section_name}] is not numbered 1, 2, ... in decimal",
                            p.key
                        ),
                    )
                    .at(Some(section_name), Some(&p.key)),
                );
            }
            for (n, value) in entries {
                let key = n.to_string();
                let Some(index) = int_of(&value).and_then(|v| u16::try_from(v).ok()) else {
                    let span = self.list_key_span(kind, &key);
                    self.push(
                        Diagnostic::new(
                            Code::MalformedObjectList,
                            span,
                            format!("`{value}` is not an object index"),
                        )
                        .at(Some(section_name), Some(&key)),
                    );
                    continue;
                };
                if listed.insert(index, kind).is_some() {
                    let span = self.list_key_span(kind, &key);
                    self.push(
                        Diagnostic::new(
                            Code::MalformedObjectList,
                            span,
                            format!("object {index:X}h is listed more than once"),
                        )
                        .at(Some(section_name), Some(&key)),
                    );
                }
                let exists = self
                    .eds
                    .objects
                    .get(&index)
                    .is_some_and(|o| o.origin != Origin::Orphan);
                if !exists {
                    let span = self.list_key_span(kind, &key);
                    self.push(
                        Diagnostic::new(
                            Code::ListedObjectMissing,
                            span,
                            format!("[{section_name}] lists {index:X}h, but there is no [{index:X}] section"),
                        )
                        .at(Some(section_name), Some(&key))
                        .with_help(format!("add a [{index:X}] section or remove the entry")),
                    );
                }
            }
        }
        let unlisted: Vec<u16> = self
            .eds
            .objects
            .iter()
            .filter(|(i, o)| o.origin == Origin::Explicit && !listed.contains_key(i))
            .map(|(i, _)| *i)
            .collect();
        for index in unlisted {
            let span = places
                .objects
                .get(&index)
                .and_then(|&i| self.section_at(i))
                .map_or(FILE_START, |s| self.doc.line_span(s.header_line));
            let list = ObjectListKind::for_index(index).section_name();
            self.push(
                Diagnostic::new(
                    Code::UnlistedObject,
                    span,
                    format!("object {index:X}h has a section but no object list names it"),
                )
                .at(Some(&format!("{index:X}")), None)
                .with_help(format!(
                    "add it to [{list}]; lely's loader ignores unlisted objects"
                )),
            );
        }
    }

    fn check_objects(&mut self, places: &Places) {
        // The map is moved out while it is checked, so no object is cloned; it goes back unchanged.
        let objects = std::mem::take(&mut self.eds.objects);
        let mut checker = Checker {
            objects: &objects,
            diags: &mut *self.diags,
        };
        for (&index, object) in &objects {
            if object.origin != Origin::Explicit {
                continue;
            }
            if let Some(section) = places
                .objects
                .get(&index)
                .and_then(|&i| self.doc.sections().get(i))
            {
                let (name, at) = (self.doc.section_name(section), text_placer(self.doc, section));
                checker.check_attributes(&object.attributes, name, &at, None);
                checker.check_sub_number(object, name, &at);
            }
            for (sub, sub_object) in &object.subs {
                if sub_object.origin != Origin::Explicit {
                    continue;
                }
                if let Some(section) = places
                    .subs
                    .get(&(index, *sub))
                    .and_then(|&i| self.doc.sections().get(i))
                {
                    let (name, at) = (self.doc.section_name(section), text_placer(self.doc, section));
                    checker.check_attributes(&sub_object.attributes, name, &at, Some(object));
                }
            }
        }
        self.eds.objects = objects;
    }

    fn check_pdo_pairs(&mut self, places: &Places) {
        let doc = self.doc;
        let header = |index: u16| {
            places
                .objects
                .get(&index)
                .and_then(|&i| doc.sections().get(i))
                .map_or(FILE_START, |s| doc.line_span(s.header_line))
        };
        pdo_pairs(&self.eds, self.diags, &header);
    }
}

/// PDOs with a communication object and no mapping object, or the reverse (`P080`), each placed at the
/// object that is there by `header`.
fn pdo_pairs(eds: &Eds, diags: &mut Vec<Diagnostic>, header: &dyn Fn(u16) -> Span) {
    for (comm_base, map_base, what) in [(0x1400u16, 0x1600u16, "RPDO"), (0x1800, 0x1A00, "TPDO")] {
        // Only PDO numbers some object uses are looked at; scanning all 512 costs small files dearly.
        let present = |base: u16| -> BTreeSet<u16> {
            eds.objects
                .range(base..base + 0x200)
                .filter(|(_, o)| o.origin != Origin::Orphan)
                .map(|(i, _)| i - base)
                .collect()
        };
        let (comms, maps) = (present(comm_base), present(map_base));
        for n in comms.union(&maps).copied().collect::<Vec<u16>>() {
            let (comm, map) = (comm_base + n, map_base + n);
            let (has_comm, has_map) = (comms.contains(&n), maps.contains(&n));
            if has_comm == has_map {
                continue;
            }
            let (present, missing, kind) = if has_comm {
                (comm, map, "mapping")
            } else {
                (map, comm, "communication")
            };
            diags.push(
                Diagnostic::new(
                    Code::PdoPairIncomplete,
                    header(present),
                    format!("{what}{} has object {present:X}h but no {kind} object {missing:X}h", n + 1),
                )
                .at(Some(&format!("{present:X}")), None)
                .with_help("CiA 301 PDOs need both their communication and mapping objects; lely's dcfchk crashes here"),
            );
        }
    }
}

/// Per-section checks that read the object map while the loader owns it.
struct Checker<'a, 'd> {
    objects: &'a BTreeMap<u16, Object>,
    diags: &'d mut Vec<Diagnostic>,
}

/// Where a section's diagnostics point: the span of one of its keys' values, or with `None` the
/// section itself (its header in EDS text).
type Placer<'p> = dyn Fn(Option<&str>) -> Span + 'p;

/// The span of `key`'s value in a section of `doc`, else the section's header.
fn text_placer<'p>(doc: &'p Document, section: &'p Section) -> impl Fn(Option<&str>) -> Span + 'p {
    move |key| {
        let header = doc.line_span(section.header_line);
        key.and_then(|k| doc.find_entry(section, k))
            .map_or(header, |l| doc.value_span(l))
    }
}

/// The diagnostics loading gives about a model's objects, for a model read from another format (CiA
/// 311 XML): values that are not valid for their data type, `$NODEID` on non-integers, unknown object
/// and data types, missing keys, `SubNumber`, and PDOs without their other object (the codes
/// `check_objects` and `check_pdo_pairs` report on EDS text). Every explicit object and sub-object is
/// named canonically (`1018`, `1018sub1`) and placed by `place(section, key)`.
pub fn model_diagnostics(eds: &Eds, place: &dyn Fn(&str, Option<&str>) -> Span) -> Vec<Diagnostic> {
    let mut diags = Vec::new();
    let mut checker = Checker {
        objects: &eds.objects,
        diags: &mut diags,
    };
    for (&index, object) in &eds.objects {
        if object.origin != Origin::Explicit {
            continue;
        }
        let name = format!("{index:X}");
        let at = |key: Option<&str>| place(&name, key);
        checker.check_attributes(&object.attributes, &name, &at, None);
        checker.check_sub_number(object, &name, &at);
        for (sub, sub_object) in &object.subs {
            if sub_object.origin != Origin::Explicit {
                continue;
            }
            let name = format!("{index:X}sub{sub:X}");
            let at = |key: Option<&str>| place(&name, key);
            checker.check_attributes(&sub_object.attributes, &name, &at, Some(object));
        }
    }
    pdo_pairs(eds, &mut diags, &|index| place(&format!("{index:X}"), None));
    diags
}

impl Checker<'_, '_> {
    fn push(&mut self, diagnostic: Diagnostic) {
        self.diags.push(diagnostic);
    }

    /// `SubNumber` counts the sub-objects present, sub 0 included and FFh excluded (CiA 306 §4.6.3.2).
    fn check_sub_number(&mut self, object: &Object, name: &str, place: &Placer<'_>) {
        let explicit = object
            .subs
            .iter()
            .filter(|(s, sub)| sub.origin == Origin::Explicit && **s != 0xFF)
            .count();
        if let Some(declared) = object.attributes.sub_number()
            && object.attributes.compact_sub_obj() == 0
            && declared != explicit as u64
        {
            let span = place(Some("SubNumber"));
            self.push(
                Diagnostic::new(
                    Code::SubNumberMismatch,
                    span,
                    format!("SubNumber={declared} but {explicit} sub-object section(s) are present"),
                )
                .at(Some(name), Some("SubNumber")),
            );
        }
    }

    /// Key obligations (CiA 306 §4.6.3.2 table) and typed values of one section.
    fn check_attributes(&mut self, a: &Attributes, name: &str, place: &Placer<'_>, parent: Option<&Object>) {
        let header = place(None);
        let value_span = |key: &str| place(Some(key));
        for (key, text) in [
            ("ObjectType", &a.object_type),
            ("DataType", &a.data_type),
            ("AccessType", &a.access_type),
            ("PDOMapping", &a.pdo_mapping),
            ("SubNumber", &a.sub_number),
            ("CompactSubObj", &a.compact_sub_obj),
            ("ObjFlags", &a.obj_flags),
        ] {
            let Some(text) = text.as_deref() else { continue };
            if let Some(head) = crate::model::strip_inline_comment(text) {
                self.push(
                    Diagnostic::new(
                        Code::InlineComment,
                        value_span(key),
                        format!(
                            "{key}: `{}` after the value was ignored; CiA 306 has no inline comments",
                            &text[head.len()..].trim()
                        ),
                    )
                    .at(Some(name), Some(key)),
                );
            }
        }
        let object_type = a.object_type();
        if object_type.is_none() {
            let raw = a.object_type.clone().unwrap_or_default();
            self.push(
                Diagnostic::new(Code::UnknownObjectType, value_span("ObjectType"), format!("ObjectType `{raw}` is not defined"))
                    .at(Some(name), Some("ObjectType"))
                    .with_help("use 0x7 (VAR), 0x8 (ARRAY), 0x9 (RECORD), 0x2 (DOMAIN), 0x5 (DEFTYPE) or 0x6 (DEFSTRUCT)"),
            );
        }
        let compact = a.compact_sub_obj() != 0;
        // Each key with its field: what `a.get(key)` finds, without matching the key against every field.
        let name_key = ("ParameterName", &a.parameter_name);
        let type_key = ("DataType", &a.data_type);
        let access_key = ("AccessType", &a.access_type);
        let required: &[(&str, &Option<String>)] = match object_type {
            Some(ObjectType::Var | ObjectType::DefType) => &[name_key, type_key, access_key],
            Some(ObjectType::Array | ObjectType::Record | ObjectType::DefStruct) if parent.is_none() => {
                if compact {
                    &[name_key, type_key, access_key]
                } else {
                    &[name_key, ("SubNumber", &a.sub_number)]
                }
            }
            _ => &[name_key],
        };
        for &(key, text) in required {
            if text.as_deref().is_none_or(|v| value::trim(v).is_empty()) {
                let kind = object_type.map_or("object".to_owned(), |t| t.to_string());
                self.push(
                    Diagnostic::new(Code::MissingKey, header, format!("{kind} [{name}] has no `{key}`"))
                        .at(Some(name), Some(key))
                        .with_help(format!(
                            "CiA 306 §4.6.3.2 makes `{key}` mandatory here; python canopen and lely fail without it"
                        )),
                );
            }
        }
        if let Some(raw) = a.access_type.as_deref()
            && !value::trim(raw).is_empty()
            && a.access_type().is_none()
        {
            self.push(
                Diagnostic::new(
                    Code::UnknownAccessType,
                    value_span("AccessType"),
                    format!("AccessType `{raw}` is not defined"),
                )
                .at(Some(name), Some("AccessType"))
                .with_help("use ro, wo, rw, rwr, rww or const"),
            );
        }
        let data_type = match (a.data_type.as_deref(), a.data_type()) {
            (Some(raw), None) if !value::trim(raw).is_empty() => {
                self.push(
                    Diagnostic::new(
                        Code::UnknownDataType,
                        value_span("DataType"),
                        format!("DataType `{raw}` is not a number"),
                    )
                    .at(Some(name), Some("DataType")),
                );
                None
            }
            (_, Some(t)) => {
                let resolved = crate::model::resolve_data_type_in(self.objects, t);
                if resolved.kind().is_none() && object_type != Some(ObjectType::DefType) {
                    self.push(
                        Diagnostic::new(
                            Code::UnknownDataType,
                            value_span("DataType"),
                            format!(
                                "DataType 0x{:04X} is neither a CiA 301 type nor defined in this file",
                                t.0
                            ),
                        )
                        .at(Some(name), Some("DataType")),
                    );
                }
                Some(resolved)
            }
            _ => None,
        };
        let Some(data_type) = data_type else { return };
        for (key, text) in [
            ("DefaultValue", &a.default_value),
            ("LowLimit", &a.low_limit),
            ("HighLimit", &a.high_limit),
            ("ParameterValue", &a.parameter_value),
        ] {
            let Some(text) = text.as_deref() else { continue };
            if value::mentions_nodeid(text) && !data_type.is_integer() {
                self.push(
                    Diagnostic::new(
                        Code::NodeIdOnNonInteger,
                        value_span(key),
                        format!(
                            "`{text}` uses $NODEID on a {data_type} entry; CiA 306 allows it only on integers"
                        ),
                    )
                    .at(Some(name), Some(key)),
                );
                continue;
            }
            // Strings of DOMAIN type are often file names or empty placeholders; only check non-empty octets.
            if matches!(data_type.kind(), Some(TypeKind::Domain)) && key != "ParameterValue" {
                continue;
            }
            let parsed = value::parse_value(text, data_type);
            for issue in parsed.issues {
                self.push(
                    Diagnostic::new(issue.code, value_span(key), format!("{key}: {}", issue.message))
                        .at(Some(name), Some(key)),
                );
            }
        }
    }
}

fn implied_comm(n: u16, receive: bool, mask: i128) -> Object {
    let default_cob = match (receive, n) {
        (true, 0..=3) => format!("$NODEID+0x{:X}", 0x200 + 0x100 * n),
        (false, 0..=3) => format!("$NODEID+0x{:X}", 0x180 + 0x100 * n),
        _ => "0x80000000".to_owned(),
    };
    let mut subs = BTreeMap::new();
    let max_sub = if receive { 5 } else { 6 };
    let mut highest = 0u8;
    let entries: [(u8, &str, DataType, String); 6] = [
        (1, "COB-ID", DataType::UNSIGNED32, default_cob),
        (
            2,
            "Transmission type",
            DataType::UNSIGNED8,
            if receive { "0xFF" } else { "0xFE" }.to_owned(),
        ),
        (3, "Inhibit time", DataType::UNSIGNED16, "0".to_owned()),
        (4, "Reserved", DataType::UNSIGNED8, "0".to_owned()),
        (5, "Event timer", DataType::UNSIGNED16, "0".to_owned()),
        (6, "SYNC start value", DataType::UNSIGNED8, "0".to_owned()),
    ];
    for (sub, name, t, default) in entries {
        if sub > max_sub || mask & (1 << (sub - 1)) == 0 {
            continue;
        }
        highest = sub;
        subs.insert(sub, generated_sub(name, t, "rw", &default, Origin::CompactPdo));
    }
    subs.insert(
        0,
        generated_sub(
            "Highest sub-index supported",
            DataType::UNSIGNED8,
            "ro",
            &highest.to_string(),
            Origin::CompactPdo,
        ),
    );
    let what = if receive { "RPDO" } else { "TPDO" };
    Object {
        attributes: Attributes {
            parameter_name: Some(format!("{what} communication parameter {}", n + 1)),
            object_type: Some("0x9".to_owned()),
            data_type: Some("0x0020".to_owned()),
            sub_number: Some((subs.len()).to_string()),
            ..Attributes::default()
        },
        subs,
        origin: Origin::CompactPdo,
        ..Object::default()
    }
}

fn implied_mapping(n: u16, receive: bool) -> Object {
    let mut subs = BTreeMap::new();
    subs.insert(
        0,
        generated_sub(
            "Number of mapped objects",
            DataType::UNSIGNED8,
            "rw",
            "0",
            Origin::CompactPdo,
        ),
    );
    for sub in 1..=64u8 {
        subs.insert(
            sub,
            generated_sub(
                &format!("Mapped object {sub}"),
                DataType::UNSIGNED32,
                "rw",
                "0",
                Origin::CompactPdo,
            ),
        );
    }
    let what = if receive { "RPDO" } else { "TPDO" };
    Object {
        attributes: Attributes {
            parameter_name: Some(format!("{what} mapping parameter {}", n + 1)),
            object_type: Some("0x9".to_owned()),
            data_type: Some("0x0021".to_owned()),
            sub_number: Some("65".to_owned()),
            ..Attributes::default()
        },
        subs,
        origin: Origin::CompactPdo,
        ..Object::default()
    }
}

fn generated_sub(name: &str, t: DataType, access: &str, default: &str, origin: Origin) -> SubObject {
    SubObject {
        attributes: Attributes {
            parameter_name: Some(name.to_owned()),
            object_type: Some("0x7".to_owned()),
            data_type: Some(format!("0x{:04X}", t.0)),
            access_type: Some(access.to_owned()),
            default_value: Some(default.to_owned()),
            pdo_mapping: Some("0".to_owned()),
            ..Attributes::default()
        },
        origin,
    }
}

/// The keys already read in a section, to find repeats without allocating for the usual short section.
#[derive(Default)]
struct KeysSeen<'a> {
    keys: Vec<(&'a str, usize)>,
    /// The keys by case-insensitive hash, built once a section is long (object lists with thousands of
    /// entries).
    index: Option<HashMap<Caseless<'a>, usize, BuildHasherDefault<IndexHasher>>>,
}

impl<'a> KeysSeen<'a> {
    const LINEAR_LIMIT: usize = 24;

    fn first(&self, key: &str) -> Option<usize> {
        match &self.index {
            Some(index) => index.get(&Caseless(key)).copied(),
            None => self
                .keys
                .iter()
                .find(|(k, _)| k.eq_ignore_ascii_case(key))
                .map(|(_, line)| *line),
        }
    }

    fn insert(&mut self, key: &'a str, line: usize) {
        if let Some(index) = &mut self.index {
            index.insert(Caseless(key), line);
            return;
        }
        self.keys.push((key, line));
        if self.keys.len() > Self::LINEAR_LIMIT {
            self.index = Some(self.keys.drain(..).map(|(k, l)| (Caseless(k), l)).collect());
        }
    }
}

/// A key compared and hashed ignoring ASCII case, so long sections index their keys without
/// allocating a lower-cased copy of each.
struct Caseless<'a>(&'a str);

impl PartialEq for Caseless<'_> {
    fn eq(&self, other: &Self) -> bool {
        self.0.eq_ignore_ascii_case(other.0)
    }
}

impl Eq for Caseless<'_> {}

impl Hash for Caseless<'_> {
    fn hash<H: Hasher>(&self, state: &mut H) {
        // Lower-cased one stack buffer at a time: the bytes `to_ascii_lowercase` would give.
        let mut buffer = [0u8; 32];
        for chunk in self.0.as_bytes().chunks(buffer.len()) {
            // Chunks are at most the buffer's length, so the prefix always exists.
            if let Some(lower) = buffer.get_mut(..chunk.len()) {
                lower.copy_from_slice(chunk);
                lower.make_ascii_lowercase();
                state.write(lower);
            }
        }
    }
}

/// A section type with a fixed set of known keys.
trait KeySet {
    type Target: Default;
    const RESERVED: &'static [&'static str] = &[];
    fn slot<'t>(target: &'t mut Self::Target, key: &str) -> Option<(&'t mut Option<String>, &'static str)>;
    fn extra(target: &mut Self::Target) -> &mut Vec<Property>;
}

macro_rules! key_set {
    ($name:ident, $target:ty $(, reserved = $reserved:expr)?) => {
        struct $name;
        impl KeySet for $name {
            type Target = $target;
            $(const RESERVED: &'static [&'static str] = $reserved;)?
            fn slot<'t>(target: &'t mut $target, key: &str) -> Option<(&'t mut Option<String>, &'static str)> {
                target.slot_with_key(key)
            }
            fn extra(target: &mut $target) -> &mut Vec<Property> {
                &mut target.extra
            }
        }
    };
}

key_set!(FileInfoKeys, FileInfo);
key_set!(
    DeviceInfoKeys,
    DeviceInfo,
    reserved = &[
        "ProductVersion",
        "ProductRevision",
        "LMT_ManufacturerName",
        "LMT_ProductName",
        "ExtendedBootUpMaster",
        "ExtendedBootUpSlave"
    ]
);
key_set!(CommissioningKeys, DeviceCommissioning);
key_set!(ModuleInfoKeys, ModuleInfo);
key_set!(AttributeKeys, Attributes);

#[cfg(test)]
mod tests {
    use super::*;

    fn codes(text: &str) -> Vec<Code> {
        load(text.as_bytes()).diagnostics.iter().map(|d| d.code).collect()
    }

    const BASE: &str = "[FileInfo]\nFileName=x.eds\n[DeviceInfo]\nVendorName=v\n\
        [MandatoryObjects]\nSupportedObjects=1\n1=0x1000\n\
        [1000]\nParameterName=Device type\nObjectType=0x7\nDataType=0x0007\nAccessType=ro\nDefaultValue=0x191\nPDOMapping=0\n";

    #[test]
    fn clean_file_has_no_diagnostics() {
        let loaded = load(BASE.as_bytes());
        assert_eq!(loaded.diagnostics, []);
        assert_eq!(loaded.eds.objects[&0x1000].name(), "Device type");
        assert_eq!(
            loaded.eds.default_value(0x1000, None).and_then(|v| v.resolve(1)),
            Some(0x191)
        );
    }

    #[test]
    fn duplicates_keep_the_first_and_name_both_lines() {
        let text = format!("{BASE}[1000]\nParameterName=Again\nDefaultValue=1\nDefaultValue=2\n");
        let loaded = load(text.as_bytes());
        assert_eq!(loaded.eds.objects[&0x1000].name(), "Device type");
        let dup = &loaded.diagnostics[0];
        assert_eq!(dup.code, Code::DuplicateSection);
        assert!(dup.message.contains("line 8"), "{}", dup.message);
        let text = format!("{BASE}DefaultValue=0x192\n");
        let loaded = load(text.as_bytes());
        assert_eq!(
            loaded.eds.objects[&0x1000].attributes.default_value.as_deref(),
            Some("0x191")
        );
        assert_eq!(loaded.diagnostics[0].code, Code::DuplicateKey);
        assert_eq!(loaded.diagnostics[0].span.line, 15);
    }

    #[test]
    fn compact_sub_obj_expands_with_sparse_names() {
        let text = format!(
            "{BASE}[OptionalObjects]\nSupportedObjects=0\n[ManufacturerObjects]\nSupportedObjects=1\n1=0x2000\n\
             [2000]\nParameterName=Compact array\nObjectType=0x8\nDataType=0x0005\nAccessType=rw\nDefaultValue=7\nCompactSubObj=3\n\
             [2000Name]\nNrOfEntries=2\n1=First\n3=Third\n"
        );
        let loaded = load(text.as_bytes());
        assert_eq!(loaded.diagnostics, []);
        let object = &loaded.eds.objects[&0x2000];
        let names: Vec<&str> = object
            .subs
            .values()
            .map(|s| s.attributes.parameter_name.as_deref().unwrap())
            .collect();
        assert_eq!(names, ["NrOfObjects", "First", "Compact array2", "Third"]);
        assert_eq!(
            loaded
                .eds
                .default_value(0x2000, Some(0))
                .and_then(|v| v.resolve(0)),
            Some(3)
        );
        assert_eq!(
            loaded
                .eds
                .default_value(0x2000, Some(2))
                .and_then(|v| v.resolve(0)),
            Some(7)
        );
        assert!(object.subs.values().all(|s| s.origin == Origin::CompactSubObj));
    }

    #[test]
    fn orphans_and_list_mismatches_are_reported_and_kept() {
        let text = format!(
            "{BASE}[3000sub1]\nParameterName=x\nDataType=0x0005\nAccessType=ro\n[OptionalObjects]\nSupportedObjects=1\n1=0x1017\n"
        );
        let loaded = load(text.as_bytes());
        assert_eq!(
            loaded.diagnostics.iter().map(|d| d.code).collect::<Vec<_>>(),
            [Code::OrphanSubObject, Code::ListedObjectMissing]
        );
        assert_eq!(loaded.eds.objects[&0x3000].origin, Origin::Orphan);
        assert!(loaded.eds.objects[&0x3000].subs.contains_key(&1));
    }

    #[test]
    fn missing_access_type_and_bad_values() {
        let text = BASE
            .replace("AccessType=ro\n", "")
            .replace("DefaultValue=0x191", "DefaultValue=FEh");
        assert_eq!(codes(&text), [Code::MissingKey, Code::HexSuffix]);
        let text = BASE.replace("AccessType=ro", "AccessType=readwrite");
        assert_eq!(codes(&text), [Code::UnknownAccessType]);
    }

    /// A model from another format gets the object diagnostics loading gives EDS text: the same codes,
    /// messages, sections and keys, placed by the caller.
    #[test]
    fn model_diagnostics_are_the_object_diagnostics_of_loading() {
        let text = format!(
            "{BASE}[2000]\nParameterName=a\nObjectType=0x7\nDataType=0x0005\nAccessType=rw\nDefaultValue=300\n\
             [2001]\nParameterName=b\nObjectType=0x3\n[2002]\nParameterName=c\nDataType=0x0009\nAccessType=ro\n\
             DefaultValue=$NODEID+1\n[1800]\nParameterName=TPDO1\nObjectType=0x9\nSubNumber=1\n\
             [1800sub0]\nParameterName=n\nDataType=0x0005\nAccessType=ro\nDefaultValue=0\n"
        );
        let loaded = load(text.as_bytes());
        let of_model = |d: &Diagnostic| (d.code, d.message.clone(), d.section.clone(), d.key.clone());
        let placed = |_section: &str, key: Option<&str>| Span::new(7, 7, u32::from(key.is_some()));
        let from_model: Vec<_> = model_diagnostics(&loaded.eds, &placed)
            .iter()
            .map(of_model)
            .collect();
        let model_codes: BTreeSet<Code> = from_model.iter().map(|d| d.0).collect();
        let mut from_text: Vec<_> = loaded
            .diagnostics
            .iter()
            .filter(|d| model_codes.contains(&d.code))
            .map(of_model)
            .collect();
        let mut sorted = from_model.clone();
        sorted.sort();
        from_text.sort();
        assert_eq!(sorted, from_text);
        let codes: BTreeSet<Code> = model_codes;
        for code in [
            Code::OutOfRange,
            Code::UnknownObjectType,
            Code::NodeIdOnNonInteger,
            Code::PdoPairIncomplete,
        ] {
            assert!(codes.contains(&code), "{code:?} in {from_model:?}");
        }
        assert!(
            model_diagnostics(&loaded.eds, &placed)
                .iter()
                .all(|d| d.span.line == 7)
        );
    }

    #[test]
    fn compact_pdo_implies_missing_pdos() {
        let text = BASE.replace("VendorName=v\n", "VendorName=v\nNrOfRXPDO=2\nCompactPDO=0x3\n");
        let loaded = load(text.as_bytes());
        assert_eq!(loaded.diagnostics, []);
        let rpdo2 = &loaded.eds.objects[&0x1401];
        assert_eq!(rpdo2.origin, Origin::CompactPdo);
        assert_eq!(rpdo2.subs.keys().copied().collect::<Vec<_>>(), [0, 1, 2]);
        assert_eq!(
            loaded
                .eds
                .default_value(0x1401, Some(1))
                .and_then(|v| v.resolve(5)),
            Some(0x305)
        );
        assert_eq!(loaded.eds.objects[&0x1601].subs.len(), 65);
    }
}

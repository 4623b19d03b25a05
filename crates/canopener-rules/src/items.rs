//! What rules see of a file: one `item` per object and sub-object, and the `eds` value.

use std::collections::HashMap;
use std::sync::Arc;

use canopener_check::Context;
use canopener_eds::model::{Properties, typed};
use canopener_eds::section_name::{SectionKind, canonical_name};
use canopener_eds::{Attributes, ObjectType, Origin};
use cel::common::traits::{Container, Indexer, Iterable, Sizer, Zeroer};
use cel::common::types::{
    CelBool, CelInt, CelList, CelMap, CelMapKey as CelKey, CelNull, CelString, MAP_TYPE, Type,
};
use cel::common::value::{Builtin, BuiltinRef, Val};

use crate::functions::FileIndex;

/// The fields of an `item` (checked when a rule is parsed, so a typo is an error, not a miss).
pub(crate) const ITEM_FIELDS: &[&str] = &[
    "index",
    "sub",
    "kind",
    "name",
    "object_name",
    "object_type",
    "data_type",
    "data_type_name",
    "access",
    "pdo_mapping",
    "default",
    "value",
    "nodeid_relative",
    "low_limit",
    "high_limit",
    "parameter_value",
    "sub_number",
    "subs",
    "section",
    "keys",
    "origin",
    "written",
];

/// The fields of `eds`.
pub(crate) const EDS_FIELDS: &[&str] = &[
    "file_info",
    "device_info",
    "dummy_usage",
    "commissioning",
    "objects",
    "is_dcf",
    "node_id",
    "file_name",
];

/// A CEL value that may borrow the file's text.
pub(crate) type Cel<'a> = Box<dyn Val + 'a>;

/// A CEL map shared by reference counting.
///
/// CEL copies a value whenever it binds one to a variable: every step of `eds.objects.filter(o, ..)`
/// copies an item. With this wrapper the copy is a reference-count increment instead of a copy of
/// some thirty fields. To the interpreter it is a plain `map`: it reports the built-in map through
/// `as_builtin` (which is how `cel` recognises its own map type), so conversions, equality and
/// downcasts behave as for any map.
#[derive(Debug, Clone)]
pub(crate) struct SharedMap<'v>(Arc<CelMap<'v>>);

impl<'v> Val for SharedMap<'v> {
    fn get_type(&self) -> &Type {
        <Self as Val>::cel_type()
    }

    fn cel_type() -> &'static Type {
        &MAP_TYPE
    }

    fn as_container(&self) -> Option<&dyn Container> {
        self.0.as_container()
    }

    fn as_indexer<'b, 'w>(&'b self) -> Option<&'b (dyn Indexer + 'w)>
    where
        Self: 'w,
    {
        self.0.as_indexer()
    }

    fn as_iterable<'b, 'w>(&'b self) -> Option<&'b (dyn Iterable + 'w)>
    where
        Self: 'w,
    {
        self.0.as_iterable()
    }

    fn as_sizer(&self) -> Option<&dyn Sizer> {
        self.0.as_sizer()
    }

    fn as_zeroer(&self) -> Option<&dyn Zeroer> {
        self.0.as_zeroer()
    }

    fn equals(&self, other: &dyn Val) -> bool {
        self.0.equals(other)
    }

    fn clone_as_boxed<'w>(&self) -> Box<dyn Val + 'w>
    where
        Self: 'w,
    {
        Box::new(self.clone())
    }

    fn as_builtin<'b, 'w>(&'b self) -> BuiltinRef<'b, 'w>
    where
        Self: 'w,
    {
        BuiltinRef::Map(&self.0)
    }

    fn into_builtin<'w>(self: Box<Self>) -> Option<Builtin<'w>>
    where
        Self: 'w,
    {
        // `cel` requires `into_builtin` to answer whenever `as_builtin` does.
        Some(Builtin::Map(Arc::unwrap_or_clone(self.0)))
    }
}

/// One object or sub-object as rules see it, and where it is written.
#[derive(Debug)]
pub(crate) struct Item {
    pub(crate) index: u16,
    pub(crate) sub: Option<u8>,
    /// The section kind (`[1018]` or `[1018sub1]`).
    pub(crate) kind: SectionKind,
    /// The index of its section in the document, when it has its own section.
    pub(crate) section: Option<usize>,
    /// Whether the file writes it as its own section (not generated from `CompactSubObj`,
    /// `CompactPDO`, or a placeholder for orphan sub-objects).
    pub(crate) written: bool,
}

/// Every item of a file, in index and sub-index order, the `eds` value that holds their CEL values
/// (`eds.objects`, in the same order), and the lookups functions use.
pub(crate) struct FileItems<'a> {
    pub(crate) items: Vec<Item>,
    pub(crate) eds: Cel<'a>,
    pub(crate) index: Arc<FileIndex>,
}

impl std::fmt::Debug for FileItems<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FileItems")
            .field("items", &self.items)
            .finish_non_exhaustive()
    }
}

impl<'a> FileItems<'a> {
    /// Builds every item once; strings borrow the file.
    pub(crate) fn build(cx: &Context<'a>) -> Self {
        let eds: &'a canopener_eds::Eds = cx.eds;
        // CiA 306 §4.6.3.2: `$NODEID` is the node-ID of the device; an EDS has none, so rules see the
        // DCF's NodeID or node 1 (the lowest valid one).
        let node_id = eds.node_id().unwrap_or(1);
        let mut items = Vec::new();
        let mut values: Vec<Cel<'a>> = Vec::new();
        let mut index = FileIndex {
            node_id,
            ..FileIndex::default()
        };
        for (&object_index, object) in &eds.objects {
            let object_name = object.name();
            let kind = SectionKind::Object(object_index);
            let section = cx.sections_of(kind).first().copied();
            let written = object.origin.is_written() && cx.has_section(kind);
            let subs: Vec<u8> = object.subs.keys().copied().collect();
            index.positions.insert((object_index, None), values.len());
            values.push(item_value(
                cx,
                ItemSource {
                    index: object_index,
                    sub: None,
                    kind,
                    section,
                    written,
                    origin: object.origin,
                    attributes: &object.attributes,
                    object_name,
                    subs: &subs,
                    node_id,
                },
            ));
            items.push(Item {
                index: object_index,
                sub: None,
                kind,
                section,
                written,
            });
            for (&sub_index, sub) in &object.subs {
                let kind = SectionKind::Sub(object_index, sub_index);
                let section = cx.sections_of(kind).first().copied();
                let written = sub.origin.is_written() && cx.has_section(kind);
                index
                    .positions
                    .insert((object_index, Some(sub_index)), values.len());
                values.push(item_value(
                    cx,
                    ItemSource {
                        index: object_index,
                        sub: Some(sub_index),
                        kind,
                        section,
                        written,
                        origin: sub.origin,
                        attributes: &sub.attributes,
                        object_name,
                        subs: &[],
                        node_id,
                    },
                ));
                items.push(Item {
                    index: object_index,
                    sub: Some(sub_index),
                    kind,
                    section,
                    written,
                });
            }
            index.subs.insert(object_index, subs);
        }
        let pairs = |entries: Vec<(&'a str, &'a str)>| map_of(entries.into_iter().map(|(k, v)| (k, text(v))));
        let properties = |p: Option<&'a Properties>| {
            map_of(
                p.into_iter()
                    .flat_map(|p| p.0.iter())
                    .map(|p| (p.key.as_str(), text(&p.value))),
            )
        };
        let commissioning = eds
            .commissioning
            .as_ref()
            .map_or_else(|| pairs(Vec::new()), |c| pairs(c.entries()));
        let eds_value = map_of([
            ("file_info", pairs(eds.file_info.entries())),
            ("device_info", pairs(eds.device_info.entries())),
            ("dummy_usage", properties(eds.dummy_usage.as_ref())),
            ("commissioning", commissioning),
            ("objects", Box::new(CelList::from(values)) as Cel<'a>),
            ("is_dcf", boolean(eds.is_dcf())),
            ("node_id", int(i64::from(node_id))),
            ("file_name", cx.file_name.map_or_else(null, text)),
        ]);
        Self {
            items,
            eds: eds_value,
            index: Arc::new(index),
        }
    }

    /// The CEL values of the items, in the order of [`FileItems::items`].
    pub(crate) fn values(&self) -> &[Cel<'a>] {
        objects_of(self.eds.as_ref()).unwrap_or(&[])
    }
}

/// `eds.objects` of an `eds` value.
pub(crate) fn objects_of<'b, 'v>(eds: &'b (dyn Val + 'v)) -> Option<&'b [Box<dyn Val + 'v>]> {
    let map = eds.downcast_ref::<CelMap<'v>>()?;
    let objects = map.inner().get(&CelKey::from("objects"))?;
    Some(objects.downcast_ref::<CelList<'v>>()?.inner())
}

struct ItemSource<'a, 's> {
    index: u16,
    sub: Option<u8>,
    kind: SectionKind,
    section: Option<usize>,
    written: bool,
    origin: Origin,
    attributes: &'a Attributes,
    object_name: &'a str,
    subs: &'s [u8],
    node_id: u8,
}

fn item_value<'a>(cx: &Context<'a>, s: ItemSource<'a, '_>) -> Cel<'a> {
    let a = s.attributes;
    let opt_text = |t: Option<&'a String>| t.map_or_else(null, |t| text(t));
    let opt_int = |i: Option<i128>| i.and_then(|i| i64::try_from(i).ok()).map_or_else(null, int);
    let data_type = a.data_type();
    let resolved = data_type.map(|t| cx.eds.resolve_data_type(t));
    let typed_int = |t: Option<&String>| {
        typed(t.map(String::as_str), resolved)
            .value
            .and_then(|v| v.resolve(s.node_id))
    };
    let document = cx.document;
    let section = s.section.and_then(|i| document.sections().get(i));
    let section_name: Cel<'a> = match section {
        Some(section) => text(document.section_name(section)),
        None => Box::new(CelString::from(canonical_name(s.kind).unwrap_or_default())),
    };
    let keys = match section {
        Some(section) if s.written => {
            let mut keys: Vec<(&'a str, Cel<'a>)> = Vec::new();
            for &line in document.entries(section) {
                if let Some((k, v)) = document.entry(line) {
                    keys.push((k, text(v)));
                }
            }
            map_of(keys)
        }
        _ => map_of(a.entries().into_iter().map(|(k, v)| (k, text(v)))),
    };
    let origin = match s.origin {
        Origin::Explicit => "explicit",
        Origin::CompactSubObj => "compact-sub-obj",
        Origin::CompactPdo => "compact-pdo",
        Origin::Orphan => "orphan",
    };
    let object_type = a.object_type().map(|t| match t {
        ObjectType::Null => "NULL",
        ObjectType::Domain => "DOMAIN",
        ObjectType::DefType => "DEFTYPE",
        ObjectType::DefStruct => "DEFSTRUCT",
        ObjectType::Var => "VAR",
        ObjectType::Array => "ARRAY",
        ObjectType::Record => "RECORD",
    });
    let subs: Vec<Cel<'a>> = s.subs.iter().map(|v| int(i64::from(*v))).collect();
    Box::new(SharedMap(Arc::new(plain_map([
        ("index", int(i64::from(s.index))),
        ("sub", s.sub.map_or_else(null, |v| int(i64::from(v)))),
        ("kind", text(if s.sub.is_some() { "sub" } else { "object" })),
        ("name", text(a.parameter_name.as_deref().unwrap_or(""))),
        ("object_name", text(s.object_name)),
        ("object_type", object_type.map_or_else(null, text)),
        ("data_type", data_type.map_or_else(null, |t| int(i64::from(t.0)))),
        (
            "data_type_name",
            resolved.and_then(|t| t.name()).map_or_else(null, text),
        ),
        ("access", a.access_type().map_or_else(null, |t| text(t.as_str()))),
        ("pdo_mapping", boolean(a.pdo_mapping())),
        ("default", opt_text(a.default_value.as_ref())),
        ("value", opt_int(typed_int(a.default_value.as_ref()))),
        (
            "nodeid_relative",
            boolean(
                a.default_value
                    .as_deref()
                    .is_some_and(canopener_eds::value::mentions_nodeid),
            ),
        ),
        ("low_limit", opt_int(typed_int(a.low_limit.as_ref()))),
        ("high_limit", opt_int(typed_int(a.high_limit.as_ref()))),
        ("parameter_value", opt_text(a.parameter_value.as_ref())),
        (
            "sub_number",
            if s.sub.is_none() {
                opt_int(a.sub_number().map(i128::from))
            } else {
                null()
            },
        ),
        ("subs", Box::new(CelList::from(subs))),
        ("section", section_name),
        ("keys", keys),
        ("origin", text(origin)),
        ("written", boolean(s.written)),
    ]))))
}

fn text(t: &str) -> Cel<'_> {
    Box::new(CelString::from(t))
}

fn int<'a>(i: i64) -> Cel<'a> {
    Box::new(CelInt::from(i))
}

fn boolean<'a>(b: bool) -> Cel<'a> {
    Box::new(CelBool::from(b))
}

fn null<'a>() -> Cel<'a> {
    Box::new(CelNull)
}

/// A map of string keys; the first occurrence of a key wins, as in the model (the loader reports
/// duplicates).
fn map_of<'a>(entries: impl IntoIterator<Item = (&'a str, Cel<'a>)>) -> Cel<'a> {
    Box::new(plain_map(entries))
}

fn plain_map<'a>(entries: impl IntoIterator<Item = (&'a str, Cel<'a>)>) -> CelMap<'a> {
    let mut map: HashMap<CelKey<'a>, Cel<'a>> = HashMap::new();
    for (k, v) in entries {
        map.entry(CelKey::from(k)).or_insert(v);
    }
    CelMap::from(map)
}

#[cfg(test)]
mod tests {
    use cel::Value;
    use cel::objects::Key;

    use super::*;

    fn value(v: &Cel<'_>) -> Value {
        Value::try_from(v.as_ref()).unwrap_or(Value::Null)
    }

    fn field<'a>(item: &'a Value, name: &str) -> &'a Value {
        match item {
            Value::Map(m) => m.get(&Key::from(name)).unwrap_or(&Value::Null),
            _ => &Value::Null,
        }
    }

    const TEXT: &str = "[FileInfo]\nFileName=t.eds\n[DeviceInfo]\nVendorNumber=0x12\n\
        [OptionalObjects]\nSupportedObjects=2\n1=0x1800\n2=0x2000\n\
        [1800]\nParameterName=TPDO1\nObjectType=0x9\nSubNumber=2\n\
        [1800sub0]\nParameterName=Highest\nDataType=0x0005\nAccessType=RO\nDefaultValue=1\n\
        [1800sub1]\nParameterName=COB-ID\nDataType=0x0007\nAccessType=rw\nDefaultValue=$NODEID+0x180\n\
        LowLimit=0x181\nhighlimit=0x1FF\nPDOMapping=0\n\
        [2000]\nParameterName=Gains\nObjectType=0x8\nDataType=0x0003\nAccessType=rw\nCompactSubObj=2\n\
        DefaultValue=-4\n";

    #[test]
    fn items_carry_what_rules_need() {
        let loaded = canopener_eds::load(TEXT.as_bytes());
        let cx = Context::new(&loaded, Some("t.eds"));
        let file = FileItems::build(&cx);
        let keys: Vec<_> = file.items.iter().map(|i| (i.index, i.sub, i.written)).collect();
        assert_eq!(
            keys,
            [
                (0x1800, None, true),
                (0x1800, Some(0), true),
                (0x1800, Some(1), true),
                (0x2000, None, true),
                (0x2000, Some(0), false),
                (0x2000, Some(1), false),
                (0x2000, Some(2), false),
            ]
        );
        let values: Vec<Value> = file.values().iter().map(value).collect();
        let cob = &values[2];
        assert_eq!(field(cob, "name"), &Value::from("COB-ID"));
        assert_eq!(field(cob, "object_name"), &Value::from("TPDO1"));
        assert_eq!(
            field(cob, "value"),
            &Value::Int(0x181),
            "$NODEID resolves with node 1"
        );
        assert_eq!(field(cob, "nodeid_relative"), &Value::Bool(true));
        assert_eq!(field(cob, "access"), &Value::from("rw"));
        assert_eq!(field(cob, "data_type"), &Value::Int(7));
        assert_eq!(field(cob, "data_type_name"), &Value::from("UNSIGNED32"));
        assert_eq!(field(cob, "low_limit"), &Value::Int(0x181));
        assert_eq!(field(cob, "high_limit"), &Value::Int(0x1FF));
        assert_eq!(field(cob, "section"), &Value::from("1800sub1"));
        assert_eq!(field(cob, "kind"), &Value::from("sub"));
        assert_eq!(field(cob, "sub"), &Value::Int(1));
        let written_keys = field(cob, "keys");
        assert_eq!(
            field(written_keys, "highlimit"),
            &Value::from("0x1FF"),
            "keys as written"
        );
        let highest = &values[1];
        assert_eq!(
            field(highest, "access"),
            &Value::from("ro"),
            "access is normalised"
        );
        let object = &values[0];
        assert_eq!(field(object, "sub"), &Value::Null);
        assert_eq!(field(object, "object_type"), &Value::from("RECORD"));
        assert_eq!(field(object, "sub_number"), &Value::Int(2));
        assert_eq!(
            field(object, "subs"),
            &Value::List(Arc::new(vec![Value::Int(0), Value::Int(1)]))
        );
        let generated = &values[5];
        assert_eq!(field(generated, "origin"), &Value::from("compact-sub-obj"));
        assert_eq!(field(generated, "value"), &Value::Int(-4));
        assert_eq!(field(generated, "section"), &Value::from("2000sub1"));
        assert_eq!(file.index.subs.get(&0x2000), Some(&vec![0, 1, 2]));
    }

    #[test]
    fn the_eds_value_has_file_sections_and_every_item() {
        let loaded = canopener_eds::load(TEXT.as_bytes());
        let cx = Context::new(&loaded, Some("t.eds"));
        let file = FileItems::build(&cx);
        let eds = value(&file.eds);
        assert_eq!(
            field(field(&eds, "device_info"), "VendorNumber"),
            &Value::from("0x12")
        );
        assert_eq!(field(field(&eds, "file_info"), "FileName"), &Value::from("t.eds"));
        assert_eq!(field(&eds, "is_dcf"), &Value::Bool(false));
        assert_eq!(field(&eds, "node_id"), &Value::Int(1));
        assert_eq!(field(&eds, "file_name"), &Value::from("t.eds"));
        match field(&eds, "objects") {
            Value::List(l) => assert_eq!(l.len(), 7),
            other => panic!("objects is {other:?}"),
        }
        for name in EDS_FIELDS {
            assert!(
                matches!(&eds, Value::Map(m) if m.get(&Key::from(*name)).is_some()),
                "{name}"
            );
        }
        for name in ITEM_FIELDS {
            let item = &value(&file.values()[0]);
            assert!(
                matches!(item, Value::Map(m) if m.get(&Key::from(*name)).is_some()),
                "{name}"
            );
        }
    }

    #[test]
    fn a_dcf_resolves_nodeid_with_its_node() {
        let text = format!("{TEXT}[DeviceComissioning]\nNodeID=0x10\n");
        let loaded = canopener_eds::load(text.as_bytes());
        let cx = Context::new(&loaded, None);
        let file = FileItems::build(&cx);
        assert_eq!(field(&value(&file.values()[2]), "value"), &Value::Int(0x190));
        let eds = value(&file.eds);
        assert_eq!(field(&eds, "is_dcf"), &Value::Bool(true));
        assert_eq!(
            field(field(&eds, "commissioning"), "NodeID"),
            &Value::from("0x10")
        );
        assert_eq!(field(&eds, "file_name"), &Value::Null);
    }
}

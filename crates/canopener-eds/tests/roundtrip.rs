//! Generated object dictionaries survive write → read, through every writer.

use std::collections::BTreeMap;

use canopener_eds::model::{Attributes, Eds, Object, ObjectList, ObjectListKind, SubObject};
use canopener_eds::{json, load, write};
use proptest::prelude::*;

fn integer_text(value: i64, style: u8) -> String {
    match style % 3 {
        0 => value.to_string(),
        1 if value >= 0 => format!("0x{value:X}"),
        2 if value > 0 => format!("0{value:o}"),
        _ => value.to_string(),
    }
}

fn var_attributes() -> impl Strategy<Value = Attributes> {
    (
        "[A-Za-z][A-Za-z0-9 _#;()/-]{0,30}[A-Za-z0-9)]",
        prop::sample::select(vec![
            0x0002u16, 0x0003, 0x0004, 0x0005, 0x0006, 0x0007, 0x0008, 0x0009, 0x001B,
        ]),
        prop::sample::select(vec!["ro", "wo", "rw", "rwr", "rww", "const"]),
        any::<i32>(),
        any::<u8>(),
        any::<bool>(),
        prop::option::of(0u8..=127),
    )
        .prop_map(|(name, data_type, access, raw, style, mapping, node_offset)| {
            let default = match data_type {
                0x0008 => format!("{}.5", raw % 1000),
                0x0009 => format!("text {raw}"),
                0x0002 => integer_text(i64::from(raw % 128), style),
                0x0005 => integer_text(i64::from(raw.unsigned_abs() % 256), style),
                _ => match node_offset {
                    Some(offset) if data_type == 0x0007 => {
                        format!("$NODEID+0x{:X}", u32::from(offset) * 0x80)
                    }
                    _ => integer_text(i64::from(raw.unsigned_abs() % 32768), style),
                },
            };
            Attributes {
                parameter_name: Some(name.trim().to_owned()),
                object_type: Some("0x7".to_owned()),
                data_type: Some(format!("0x{data_type:04X}")),
                access_type: Some(access.to_owned()),
                default_value: Some(default),
                pdo_mapping: Some(u8::from(mapping).to_string()),
                ..Attributes::default()
            }
        })
}

fn object() -> impl Strategy<Value = Object> {
    prop_oneof![
        var_attributes().prop_map(|attributes| Object {
            attributes,
            ..Object::default()
        }),
        (
            "[A-Z][a-z]{1,12}",
            prop::collection::btree_map(0u8..=254, var_attributes(), 1..6)
        )
            .prop_map(|(name, subs)| {
                let subs: BTreeMap<u8, SubObject> = subs
                    .into_iter()
                    .map(|(s, attributes)| {
                        (
                            s,
                            SubObject {
                                attributes,
                                ..SubObject::default()
                            },
                        )
                    })
                    .collect();
                Object {
                    attributes: Attributes {
                        parameter_name: Some(name),
                        object_type: Some("0x9".to_owned()),
                        sub_number: Some(subs.len().to_string()),
                        ..Attributes::default()
                    },
                    subs,
                    ..Object::default()
                }
            }),
    ]
}

fn model() -> impl Strategy<Value = Eds> {
    prop::collection::btree_map(0x1000u16..=0xFFFF, object(), 0..25).prop_map(|objects| {
        let mut eds = Eds::default();
        eds.file_info.set("FileName", "generated.eds");
        eds.device_info.set("VendorName", "proptest");
        for kind in ObjectListKind::ALL {
            let indices = objects
                .keys()
                .copied()
                .filter(|i| ObjectListKind::for_index(*i) == kind);
            eds.object_lists.insert(kind, ObjectList::from_indices(indices));
        }
        eds.objects = objects;
        eds
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn canonical_write_then_read_gives_the_model_back(eds in model()) {
        let text = write::to_canonical(&eds, None);
        let loaded = load(text.as_bytes());
        prop_assert_eq!(&loaded.eds, &eds);
        prop_assert_eq!(loaded.document.to_bytes().unwrap(), text.as_bytes());
    }

    #[test]
    fn json_write_then_read_gives_the_model_back(eds in model()) {
        prop_assert_eq!(json::from_json(&json::to_json(&eds)).unwrap(), eds);
    }

    #[test]
    fn lossless_edits_change_only_edited_lines(eds in model(), pick in any::<prop::sample::Index>()) {
        let text = write::to_canonical(&eds, None);
        let loaded = load(text.as_bytes());
        let mut edited = loaded.eds.clone();
        let vars: Vec<u16> = edited.objects.iter().filter(|(_, o)| o.subs.is_empty()).map(|(i, _)| *i).collect();
        prop_assume!(!vars.is_empty());
        let index = vars[pick.index(vars.len())];
        let object = edited.objects.get_mut(&index).unwrap();
        object.attributes.parameter_name = Some("Edited name".to_owned());
        let written = write::write_lossless(&loaded.document, &edited);
        let before: Vec<&str> = text.split("\r\n").collect();
        let after: Vec<&str> = written.text().split("\r\n").collect();
        prop_assert_eq!(before.len(), after.len());
        let changed = before.iter().zip(&after).filter(|(a, b)| a != b).count();
        let original_name = loaded.eds.objects[&index].name().to_owned();
        prop_assert_eq!(changed, usize::from(original_name != "Edited name"));
        prop_assert_eq!(load(written.text().as_bytes()).eds, edited);
    }
}

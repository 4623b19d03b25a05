//! Generated object dictionaries survive EDS → XDD → EDS in both object styles, hand-written EDS
//! corners (compact forms, object links, orphans, modules, odd characters) keep every section, and
//! no input makes the reader panic.

use canopener_eds::diff::{diff, diff_objects};
use canopener_eds::{Eds, Origin};
use canopener_xdd::{ObjectStyle, WriteOptions, XddKind, read, write};
use proptest::prelude::*;

fn load(text: &str) -> Eds {
    canopener_eds::load(text.as_bytes()).eds
}

fn through_xdd(eds: &Eds, style: ObjectStyle) -> Eds {
    let xml = write(
        eds,
        &WriteOptions {
            style,
            ..WriteOptions::CANOPEN_EDITOR
        },
    );
    match read(xml.as_bytes()) {
        Ok(back) => back.eds,
        Err(e) => panic!("canopener cannot read its own XDD: {e}\n{xml}"),
    }
}

fn changes(a: &Eds, b: &Eds) -> Vec<String> {
    diff(a, b).changes.iter().map(ToString::to_string).collect()
}

const CORNERS: &str = "[FileInfo]\nFileName=corner.eds\nFileVersion=2\nFileRevision=7\nEDSVersion=4.2\nCreationTime=9:05AM\n\
    CreationDate=02-29-2024\nCreatedBy=A & B <c>\nVendorTool=x\n\
    [DeviceInfo]\nVendorName=Ünïcode \"GmbH\"\nVendorNumber=327\nProductNumber=0x1234\nRevisionNumber=0x00010002\nOrderCode=ORD-1\n\
    BaudRate_125=1\nBaudRate_1000=1\nGranularity=0\nNrOfRXPDO=1\nNrOfTXPDO=1\nCompactPDO=0x3\nLSS_Supported=1\nNG_Slave=1\n\
    [DummyUsage]\nDummy0002=1\nDummy0010=1\n\
    [Comments]\nLines=2\nLine1=first; with semicolon\nLine2=100% second\n\
    [Tools]\nItems=1\nTool1=Editor\n[Tool1]\nName=Editor\nCommand=edit.exe\n\
    [MandatoryObjects]\nSupportedObjects=1\n1=0x1000\n\
    [OptionalObjects]\nSupportedObjects=3\n1=0x6000\n2=0x1400\n3=0x1800\n\
    [ManufacturerObjects]\nSupportedObjects=2\n1=0x2000\n2=0x2001\n\
    [1000]\nParameterName=Device type\nObjectType=0x7\nDataType=0x0007\nAccessType=ro\nDefaultValue=0x00020192\nPDOMapping=0\nObjFlags=0x3\n\
    [2000]\nParameterName=Compact array\nObjectType=0x8\nDataType=0x0016\nAccessType=rww\nDefaultValue=0x123456\nPDOMapping=1\nCompactSubObj=3\n\
    [2000Name]\nNrOfEntries=1\n2=Second <one>\n\
    [2000ObjectLinks]\nObjectLinks=1\n1=0x6000\n\
    [2001]\nParameterName=Time\nDataType=0x000C\nAccessType=rw\nDefaultValue=0 0\nUploadFile=up.bin\nDownloadFile=down.bin\nVendorKey=v\n\
    [2002sub1]\nParameterName=orphan sub\nDataType=0x0005\nAccessType=ro\n\
    [6000]\nParameterName=Read inputs\nObjectType=0x8\nSubNumber=2\n\
    [6000sub0]\nParameterName=Count\nDataType=0x0005\nAccessType=ro\nDefaultValue=1\n\
    [6000sub1]\nParameterName=Input\nDataType=0x000A\nAccessType=ro\nDefaultValue=C83DBB\nLowLimit=00\n\
    [SupportedModules]\nNrOfEntries=1\n1=1\n[M1ModuleInfo]\nProductName=Module\n[M1FixedObjects]\nNrOfEntries=1\n1=0x3000\n\
    [M1Fixed3000]\nParameterName=Fixed\nDataType=0x0007\nAccessType=ro\n\
    [VendorSpecific]\nAnything=goes\n";

#[test]
fn eds_corners_keep_every_section() {
    let original = load(CORNERS);
    assert_eq!(
        original.objects.get(&0x2002).map(|o| o.origin),
        Some(Origin::Orphan)
    );
    assert!(
        original.objects.contains_key(&0x1400),
        "CompactPDO gives implied PDO objects"
    );
    for style in [ObjectStyle::Reference, ObjectStyle::ReferenceAndInline] {
        let back = through_xdd(&original, style);
        assert_eq!(changes(&original, &back), Vec::<String>::new(), "{style:?}");
        assert_eq!(back.comments, original.comments);
        assert_eq!(back.tools, original.tools);
        assert_eq!(back.tool_sections, original.tool_sections);
        assert_eq!(back.modules, original.modules);
        assert_eq!(
            back.object_lists, original.object_lists,
            "lists as written, even with 1400/1800 misfiled"
        );
        assert_eq!(
            back.objects[&0x2000].object_links,
            original.objects[&0x2000].object_links
        );
        assert_eq!(back.objects[&0x2002].origin, Origin::Orphan);
        assert_eq!(
            back.objects[&0x2000].subs[&2]
                .attributes
                .parameter_name
                .as_deref(),
            Some("Second <one>")
        );
        assert_eq!(
            back.objects[&0x2000].subs[&3].attributes.access_type.as_deref(),
            Some("rww")
        );
        assert_eq!(back.device_info.get("NG_Slave"), Some("1"));
        assert_eq!(back.file_info.creation_time.as_deref(), Some("9:05AM"));
    }
}

#[test]
fn a_dcf_written_as_xdd_loses_only_its_configuration() {
    let dcf = format!(
        "{CORNERS}[DeviceComissioning]\nNodeID=0x22\nNodeName=left\nBaudrate=250\nNetNumber=1\nNetworkName=net\nCANopenManager=0\n\
         LSS_SerialNumber=0x99\n"
    )
    .replace("ObjFlags=0x3\n", "ObjFlags=0x3\nParameterValue=0x00020193\nDenotation=the type\n");
    let original = load(&dcf);
    let xdc = write(&original, &WriteOptions::CANOPEN_EDITOR);
    let back = read(xdc.as_bytes())
        .map(|l| (l.kind, l.eds))
        .expect("own XDC reads");
    assert_eq!(back.0, XddKind::Xdc);
    assert_eq!(changes(&original, &back.1), Vec::<String>::new());
    let xdd = write(
        &original,
        &WriteOptions {
            kind: Some(XddKind::Xdd),
            ..WriteOptions::CANOPEN_EDITOR
        },
    );
    let plain = read(xdd.as_bytes())
        .map(|l| (l.kind, l.eds))
        .expect("own XDD reads");
    assert_eq!(plain.0, XddKind::Xdd);
    assert_eq!(plain.1.commissioning, None);
    let lost: Vec<String> = diff_objects(&original, &plain.1)
        .significant()
        .map(ToString::to_string)
        .collect();
    assert_eq!(
        lost,
        [
            "- [1000] Denotation: the type",
            "- [1000] ParameterValue: 0x00020193"
        ]
    );
}

/// One generated object: index, EDS section text (object and sub-objects).
fn object() -> impl Strategy<Value = (u16, String)> {
    let data_type = prop::sample::select(vec![
        "0x0001", "0x0002", "0x0003", "0x0004", "0x0005", "0x0006", "0x0007", "0x0008", "0x0009", "0x000A",
        "0x000B", "0x000C", "0x000D", "0x000F", "0x0010", "0x0011", "0x0015", "0x0016", "0x001B", "0x0040",
        "7", "junk",
    ]);
    let access = prop::sample::select(vec!["ro", "wo", "rw", "rwr", "rww", "const", "RW", "UNKNOWN", ""]);
    let pdo = prop::sample::select(vec!["0", "1", "", "2"]);
    let text = "[ -~äöü€µ\u{1}]{0,16}";
    let value = prop_oneof![
        "-?[0-9]{1,6}",
        "0x[0-9A-F]{1,8}",
        Just("$NODEID+0x180".to_owned()),
        "[ -~äµ\u{7}]{0,12}"
    ];
    let extra = prop::option::of(prop::sample::select(vec![
        "UploadFile=x.bin",
        "ParamRefd=1",
        "Unit=mV",
        "Factor=0.1",
    ]));
    let shape = 0u8..4;
    (
        0x1000u16..0xA000,
        shape,
        (text, data_type, access, pdo),
        (prop::option::of(value.clone()), prop::option::of(value.clone()), prop::option::of(value.clone())),
        (prop::option::of(value), prop::option::of("0x[0-9]{1,2}"), extra, 1u8..5),
    )
        .prop_map(|(index, shape, (name, data_type, access, pdo), (default, low, high), (pv, flags, extra, n))| {
            let mut keys = vec![format!("ParameterName={name}")];
            let mut push = |k: &str, v: Option<&str>| {
                if let Some(v) = v {
                    keys.push(format!("{k}={v}"));
                }
            };
            let var_keys = |push: &mut dyn FnMut(&str, Option<&str>)| {
                push("DataType", Some(data_type));
                push("AccessType", Some(access).filter(|a| !a.is_empty()));
                push("PDOMapping", Some(pdo).filter(|p| !p.is_empty()));
                push("DefaultValue", default.as_deref());
                push("LowLimit", low.as_deref());
                push("HighLimit", high.as_deref());
                push("ParameterValue", pv.as_deref());
            };
            let mut text = String::new();
            match shape {
                0 => {
                    push("ObjectType", Some("0x7"));
                    var_keys(&mut push);
                    push("ObjFlags", flags.as_deref());
                    if let Some(e) = extra {
                        keys.push(e.to_owned());
                    }
                }
                1 => {
                    push("ObjectType", Some("0x8"));
                    var_keys(&mut push);
                    push("CompactSubObj", Some(&n.to_string()));
                }
                _ => {
                    push("ObjectType", Some(if shape == 2 { "0x8" } else { "0x9" }));
                    push("SubNumber", Some(&(n + 1).to_string()));
                    for sub in 0..=n {
                        text.push_str(&format!(
                            "[{index:X}sub{sub:X}]\nParameterName={name}{sub}\nDataType={data_type}\nAccessType={}\nDefaultValue={}\n",
                            if access.is_empty() { "ro" } else { access },
                            default.as_deref().unwrap_or("0")
                        ));
                        if let Some(e) = extra.filter(|_| sub == 1) {
                            text.push_str(&format!("{e}\n"));
                        }
                    }
                }
            }
            (index, format!("[{index:X}]\n{}\n{text}", keys.join("\n")))
        })
}

fn eds_text() -> impl Strategy<Value = String> {
    let device = (
        "[ -~ä]{0,12}",
        prop::option::of("0x[0-9A-F]{1,8}|[0-9]{1,6}"),
        prop::collection::vec(
            prop::sample::select(vec![
                "BaudRate_125=1",
                "BaudRate_250=0",
                "Granularity=8",
                "NrOfRXPDO=2",
                "LSS_Supported=1",
            ]),
            0..4,
        ),
        prop::bool::ANY,
    );
    (device, prop::collection::vec(object(), 1..12)).prop_map(|((vendor, number, keys, dcf), objects)| {
        let mut text = format!("[FileInfo]\nFileName=gen.eds\n[DeviceInfo]\nVendorName={vendor}\n");
        if let Some(n) = number {
            text.push_str(&format!("VendorNumber={n}\n"));
        }
        for k in keys {
            text.push_str(&format!("{k}\n"));
        }
        if dcf {
            text.push_str("[DeviceComissioning]\nNodeID=5\nBaudrate=500\n");
        }
        let mut seen = std::collections::BTreeSet::new();
        for (index, section) in objects {
            if seen.insert(index) {
                text.push_str(&section);
            }
        }
        text
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn generated_object_dictionaries_survive_eds_to_xdd_to_eds(text in eds_text()) {
        let original = load(&text);
        for style in [ObjectStyle::Reference, ObjectStyle::ReferenceAndInline] {
            let back = through_xdd(&original, style);
            prop_assert_eq!(changes(&original, &back), Vec::<String>::new(), "{:?}\n{}", style, text);
            prop_assert!(diff_objects(&original, &back).is_equivalent());
        }
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..512)) {
        let _ = read(&bytes);
        let _ = canopener_xdd::read_project(&bytes);
    }

    #[test]
    fn damaged_xdd_never_panics(cut in 0usize..4000, flips in prop::collection::vec((0usize..4000, any::<u8>()), 0..6)) {
        let mut bytes = write(&load(CORNERS), &WriteOptions::CANOPEN_EDITOR).into_bytes();
        for (at, byte) in flips {
            let at = at % bytes.len();
            bytes[at] = byte;
        }
        bytes.truncate(bytes.len().saturating_sub(cut));
        if let Ok(loaded) = read(&bytes) {
            prop_assert!(loaded.diagnostics.windows(2).all(|w| (w[0].span.line, w[0].span.column) <= (w[1].span.line, w[1].span.column)));
        }
    }
}

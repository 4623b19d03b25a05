//! Issue 18 item 1: for every EDS/XDD pair of the corpus (the same device, written by the same
//! project in both formats: `corpus/*/MANIFEST.tsv`), `eds check` finds the same C-series findings
//! in both, except where the two files really say different things; each such difference is written
//! down here with what differs, so a new disagreement fails the test.

use std::collections::BTreeSet;

use canopener_description::{Checker, Selection, applies_to_xml};
use canopener_testkit::corpus::{self, Kind};

/// The pairs: XDD (or XPD, NXDD) and EDS file names, and the findings only one of them has, each
/// because the two files say different things (`only XML`, `only EDS`, why).
type Pair = (
    &'static str,
    &'static str,
    &'static [&'static str],
    &'static [&'static str],
    &'static str,
);

const PAIRS: &[Pair] = &[
    (
        "CANopenNode__CANopenNode__example__DS301_profile.xpd",
        "CANopenNode__CANopenNode__example__DS301_profile.eds",
        &[
            "C309 DEVICEINFO",
            "C518 1013",
            "C518 1026SUB1",
            "C518 1026SUB2",
            "C518 1026SUB3",
            "C518 1201SUB1",
            "C518 1201SUB2",
        ],
        &[],
        "the XPD describes RPDO5/TPDO5 (1404h, 1804h) and still says nrOfRxPDO/nrOfTxPDO 4; the EDS describes four of each; CO_disabled objects (X040), which the XML keeps and canopener checks and CANopenEditor leaves out of the EDS export, are rw with PDOmapping optional (C518): 1013h, 1026h, 1201h",
    ),
    (
        "CANopenNode__CANopenDemo__demo__demoDevice.xdd",
        "CANopenNode__CANopenDemo__demo__demoDevice.eds",
        &["C518 1280SUB1", "C518 1280SUB2"],
        &[],
        "the SDO client 1280h is CO_disabled (X040): the XML keeps it and canopener checks it (rw, PDOmapping optional: C518), the EDS export leaves it out",
    ),
    (
        "CANopenNode__CANopenSocket__examples__basicDevice__basicDevice.xdd",
        "CANopenNode__CANopenSocket__examples__basicDevice__basicDevice.eds",
        &[],
        &[],
        "",
    ),
    (
        "CANopenNode__CanOpenSTM32__Elcom_e-RIO_8xx_CANopen_Profile.xdd",
        "CANopenNode__CanOpenSTM32__Elcom e-RIO 8xx CANopen Profile.eds",
        &[
            "C518 1013",
            "C518 1026SUB1",
            "C518 1026SUB2",
            "C518 1026SUB3",
            "C518 1201SUB1",
            "C518 1201SUB2",
        ],
        &["C903 6000SUB2"],
        "the EDS describes 6000sub2 (INTEGER8), the XDD only 6000sub0 and sub1; CO_disabled objects (X040), which the XML keeps and canopener checks and CANopenEditor leaves out of the EDS export, are rw with PDOmapping optional (C518): 1013h, 1026h, 1201h",
    ),
    (
        "CANopenNode__CanOpenSTM32__Elcom_e-RIO_8xx_CANopen_Profile.nxdd",
        "CANopenNode__CanOpenSTM32__Elcom e-RIO 8xx CANopen Profile.eds",
        &[
            "C518 1013",
            "C518 1026SUB1",
            "C518 1026SUB2",
            "C518 1026SUB3",
            "C518 1201SUB1",
            "C518 1201SUB2",
            "C710 1800SUB1",
            "C713 1800SUB1",
            "C880 1F80",
            "C901 6000",
        ],
        &[
            "C304 DEVICEINFO",
            "C903 6000SUB1",
            "C903 6000SUB2",
            "C903 6410SUB1",
        ],
        "the project is another revision of the device: TPDO1 COB-ID 0x180 without $NODEID, 6000h a VAR, other identity numbers and 6000h/6410h types; its 1F80h (NMT startup) is 0x80, a reserved bit, where the EDS has none; CO_disabled objects (X040), which the XML keeps and canopener checks and CANopenEditor leaves out of the EDS export, are rw with PDOmapping optional (C518): 1013h, 1026h, 1201h",
    ),
    (
        "canopen-python__canopen__test__sample.xdd",
        "canopen-python__canopen__test__sample.eds",
        &["C601 2020"],
        &["C502 3003", "C502 3063", "C502 3064SUB1", "C509 3010SUB0"],
        "2020h is DINT in the XDD (so its limits 3 > 1 are compared) and data type 0x40 in the EDS; the EDS puts DataType/AccessType/PDOMapping on ARRAY 3003h and PDOMapping on DOMAINs 3063h/3064h, which the XDD does not (X025 reports such attributes on XML); 3010sub0 is REAL32 in the EDS, USINT in the XDD",
    ),
    (
        "iota2__CANopen-tools-suite__eds_files__sample_node_0x01.xdd",
        "iota2__CANopen-tools-suite__eds_files__sample_node_0x01.eds",
        &[],
        &["C304 DEVICEINFO"],
        "the EDS says RevisionNumber=0 against 1018sub3 = 1; CiA 311 DeviceIdentity has no revision number, so the XDD cannot disagree",
    ),
    (
        "samkwok-hkclr__canopen_module__CANopenNode_STM32__canopen_module.xpd",
        "samkwok-hkclr__canopen_module__CANopenNode_STM32__canopen_module.eds",
        &[
            "C518 1013",
            "C518 1026SUB1",
            "C518 1026SUB2",
            "C518 1026SUB3",
            "C518 1201SUB1",
            "C518 1201SUB2",
        ],
        &[],
        "CO_disabled objects (X040), which the XML keeps and canopener checks and CANopenEditor leaves out of the EDS export, are rw with PDOmapping optional (C518): 1013h, 1026h, 1201h",
    ),
    (
        "wdfk-prog__canopennode-rtt__examples__demo_device__project.xdd",
        "wdfk-prog__canopennode-rtt__examples__demo_device__project.eds",
        &[
            "C518 1026SUB1",
            "C518 1026SUB2",
            "C518 1026SUB3",
            "C518 1201SUB1",
            "C518 1201SUB2",
        ],
        &["C304 DEVICEINFO"],
        "the EDS says RevisionNumber=0 against 1018sub3 = 0x00010000; CiA 311 DeviceIdentity has no revision number; CO_disabled objects (X040), which the XML keeps and canopener checks and CANopenEditor leaves out of the EDS export, are rw with PDOmapping optional (C518): 1026h, 1201h",
    ),
];

/// The C-series findings of a file that XML files can have too, as `code section` (the section
/// in upper case, as both formats name the same object).
fn c_findings(kind: Kind, name: &str) -> Option<BTreeSet<String>> {
    let path = corpus::find(kind, name)?;
    let bytes = canopener_testkit::fixture::read(&path).expect("a corpus file is readable");
    let checker = Checker::new(Vec::new(), Selection::default()).expect("no names");
    let report = checker.check(name, None, &bytes);
    Some(
        report
            .findings
            .iter()
            .filter(|f| f.diagnostic.code.starts_with('C') && applies_to_xml(&f.diagnostic.code))
            .map(|f| {
                format!(
                    "{} {}",
                    f.diagnostic.code,
                    f.diagnostic
                        .section
                        .as_deref()
                        .unwrap_or("-")
                        .to_ascii_uppercase()
                )
            })
            .collect(),
    )
}

#[test]
fn eds_and_xdd_of_the_same_device_have_the_same_c_findings_except_where_they_differ() {
    let mut compared = 0;
    let mut failures = Vec::new();
    for &(xdd, eds, only_xml, only_eds, why) in PAIRS {
        let (Some(xml), Some(text)) = (c_findings(Kind::Xdd, xdd), c_findings(Kind::Eds, eds)) else {
            // Only in the extended corpus, which a fresh clone does not have.
            assert!(
                corpus::extended_root().is_none(),
                "{xdd} or {eds} is missing from the corpus"
            );
            continue;
        };
        compared += 1;
        let found_xml: Vec<&str> = xml.difference(&text).map(String::as_str).collect();
        let found_eds: Vec<&str> = text.difference(&xml).map(String::as_str).collect();
        if found_xml != only_xml || found_eds != only_eds {
            failures.push(format!(
                "{xdd} / {eds}:\n  only in the XML: {found_xml:?} (expected {only_xml:?})\n  \
                 only in the EDS: {found_eds:?} (expected {only_eds:?}: {why})"
            ));
        }
        assert_eq!(
            only_xml.is_empty() && only_eds.is_empty(),
            why.is_empty(),
            "{xdd}: a difference needs its reason, and only a difference has one"
        );
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let vendored = PAIRS
        .iter()
        .filter(|(xdd, ..)| corpus::vendored_files(Kind::Xdd).iter().any(|f| f.name == *xdd))
        .count();
    assert!(
        compared >= vendored,
        "{compared} pairs compared, {vendored} are vendored"
    );
}

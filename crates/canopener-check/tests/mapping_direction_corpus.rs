//! Issue 22 item 7: the two CANchkEDS-equivalent checks on the whole EDS corpus. C518 (an rw entry with
//! PDOMapping=1 has no clear mapping direction; CANchkEDS warning 4) and C727 (a default PDO mapping
//! maps such an entry; warning 5) are reported per file exactly as reviewed: every finding is an entry
//! with AccessType=rw and PDOMapping=1, and for C727 an active entry (1..sub 0) of a default mapping
//! that maps one. On CANopenNode's demoDevice.eds they are CANchkEDS's 36 and 6 warnings of the
//! published CCT 3.0.3.10 run, section for section.

use std::collections::BTreeMap;

use canopener_check::{Selection, check};
use canopener_testkit::corpus::{self, Kind};

/// Per file with findings: (C518, C727). A file not listed has none.
const REVIEWED: &[(&str, usize, usize)] = &[
    ("CANopenNode__CANopenDemo__demo__demoDevice.eds", 36, 6),
    ("CANopenNode__CANopenNode__example__DS301_profile.eds", 2, 0),
    (
        "CANopenNode__CANopenSocket__canopend__objDict__CANopenSocket.eds",
        253,
        2,
    ),
    (
        "CANopenNode__CANopenSocket__examples__basicDevice__basicDevice.eds",
        38,
        6,
    ),
    (
        "CANopenNode__CanOpenSTM32__Elcom e-RIO 8xx CANopen Profile.dcf",
        2,
        0,
    ),
    (
        "CANopenNode__CanOpenSTM32__Elcom e-RIO 8xx CANopen Profile.eds",
        2,
        0,
    ),
    ("Daxbot__node-canopen__test__common__test.eds", 16, 16),
    ("Javask__modm-canopen__examples__src__cia402-test__test.eds", 2, 0),
    ("WMT-GmbH__canopen__tests__sample.eds", 6, 0),
    ("ZeroErrControl__eRob_CANopen_Linux__src__master.dcf", 1, 0),
    ("atomi-ai__canopen-rust__tests__fixtures__sample.eds", 6, 0),
    (
        "b-robotized__diff_canopen_system__config__custom_mapping_canopen_system__fake_motor_controller.eds",
        2,
        2,
    ),
    ("brtiberio__Sevcon_gen4__Gen4.eds", 32, 0),
    (
        "brtiberio__Sevcon_gen4__documents__2019-06-13-ME0913-0705-0013-GEN4-110V-300A-PARINAUTES-Ok-a-vide-19h39.dcf",
        32,
        1,
    ),
    (
        "brtiberio__Sevcon_gen4__documents__2019-06-24-MOTEUR-UK0319-55-110V-300A-S4-GEN4-Config-origine.dcf",
        23,
        0,
    ),
    ("canopen-python__canopen__test__sample.eds", 6, 0),
    (
        "chenyurong22__stm32_canopen_reference__ObjectDictionary__stm32f767_canopen_reference.eds",
        9,
        0,
    ),
    (
        "chenyurong22__stm32_canopen_reference__ObjectDictionary__stm32f767_cia418_reference.eds",
        2,
        0,
    ),
    (
        "chenyurong22__stm32_canopen_reference__ObjectDictionary__stm32f767_inventus_battery_test.eds",
        2,
        0,
    ),
    ("christiansandberg__canopen__cog.eds", 5, 0),
    ("christiansandberg__canopen__test__all_datatypes.eds", 22, 0),
    ("christiansandberg__canopen__test__datatypes.eds", 22, 0),
    ("christiansandberg__canopen__test__receiver.eds", 4, 0),
    ("christiansandberg__canopen__test__sample.eds", 6, 0),
    ("christiansandberg__canopen__test__sender.eds", 4, 0),
    (
        "davidsenoner__emec-drv-canopen-tester__app__resources__Slave_06__emecdrv5.eds",
        4,
        0,
    ),
    (
        "davidsenoner__emec-drv-canopen-tester__app__resources__eds__emecdrv5_01.eds",
        4,
        0,
    ),
    (
        "davidsenoner__emec-drv-canopen-tester__app__resources__eds__emecdrv5_rev09.eds",
        5,
        0,
    ),
    ("dereklu76__Emtas_CANopen_28069__slave1.eds", 2, 3),
    (
        "dianhuaeven__Eyou_Canopen_master__config__YiyouServo_V1.4.dcfgen.eds",
        43,
        7,
    ),
    (
        "dianhuaeven__Eyou_Canopen_master__config__YiyouServo_V1.4.eds",
        42,
        7,
    ),
    ("heig-vd-iai__canopen-stack__od.eds", 7, 0),
    (
        "hhz0328__ros1_canopen_maxon_control__maxon_epos4_ros_canopen__config__epos4_50_15_can_ec90flat_gp52c_mile800_node1_demo.dcf",
        1,
        1,
    ),
    (
        "huxitech__canopen_sensor__canopen__object__CNS-MGS-160N V1.6.eds",
        11,
        1,
    ),
    (
        "iota2__CANopen-tools-suite__eds_files__sample_device_rpdo.eds",
        13,
        8,
    ),
    (
        "iota2__CANopen-tools-suite__eds_files__sample_device_tpdo.eds",
        13,
        8,
    ),
    (
        "iota2__CANopen-tools-suite__eds_files__sample_node_0x02.eds",
        5,
        0,
    ),
    (
        "kaver06__ZLAC8015D-CANOpen-Motor-Controller-simulator__src__backend__zlac8015d.eds",
        15,
        0,
    ),
    ("lely-industries__lely-core__test__coapp-fiber-slave.dcf", 3, 2),
    ("lely-industries__lely-core__test__gw_txt-master.dcf", 6, 0),
    ("lely-industries__lely-core__test__gw_txt-slave.dcf", 17, 0),
    ("lely-industries__lely-core__test__pdo-receive.dcf", 2, 2),
    ("lely-industries__lely-core__test__pdo-transmit.dcf", 2, 2),
    ("lely-industries__lely-core__tools__coctl.dcf", 17, 0),
    (
        "ljessendk__CanFestival__examples__DS401_Slave_Gui__DS401_Slave_Gui.eds",
        26,
        5,
    ),
    ("nnarain__canopen-device-simulator__device__device.eds", 1, 1),
    (
        "ololoshka2871__canopen-bbb__tests-app__SCTB_CANopenPressureSensor0xC001.eds",
        7,
        0,
    ),
    (
        "ros-industrial__ros2_canopen__canopen_tests__config__cia402__cia402_slave.eds",
        1,
        1,
    ),
    (
        "ros-industrial__ros2_canopen__canopen_tests__config__robot_control__prbt_0_1.dcf",
        4,
        0,
    ),
    (
        "ros-industrial__ros_canopen__canopen_test_utils__config__Schunk.eds",
        16,
        3,
    ),
    (
        "ros-industrial__ros_canopen__ipa_canopen_test__config__PRL120.eds",
        4,
        2,
    ),
    (
        "ros-industrial__ros_canopen__ipa_canopen_test__config__Schunk_0_63.dcf",
        4,
        0,
    ),
    (
        "ros-industrial__ros_canopen__ipa_canopen_test__config__Schunk_0_63.eds",
        4,
        0,
    ),
    (
        "samkwok-hkclr__canopen_module__CANopenNode_STM32__canopen_module.eds",
        3,
        2,
    ),
    ("samsamfire__gocanopen__base.eds", 6, 1),
    ("samsamfire__gocanopen__pkg__od__base.eds", 14, 7),
    ("samsamfire__gocanopen__testdata__base.eds", 14, 1),
    ("samsamfire__gocanopen__testdata__test_zipped_format.eds", 14, 1),
    (
        "wdfk-prog__canopen-slave-tester__config__generated__master.dcf",
        1,
        0,
    ),
    (
        "wdfk-prog__canopen-slave-tester__config__generated__project.dcfgen.eds",
        3,
        0,
    ),
    ("wdfk-prog__canopen-slave-tester__config__project.eds", 3, 0),
    (
        "wdfk-prog__canopen-switches-modbus-gateway__other__can od__ASDA-A3_v04.eds",
        516,
        0,
    ),
    (
        "wdfk-prog__canopennode-rtt__examples__demo_device__project.eds",
        3,
        0,
    ),
    (
        "xrswnw__CanOpen_CanFestival_Stu__CanFestival__driver__AnyId_Canopen_Client.eds",
        4,
        3,
    ),
    (
        "xrswnw__CanOpen_CanFestival_Stu__CanFestival__driver__AnyId_Canopen_Slave.eds",
        3,
        3,
    ),
];

const DEMO_DEVICE: &str = "CANopenNode__CANopenDemo__demo__demoDevice.eds";

/// The number of C518 and C727 findings of a file, and for each C727 the entry it maps and the mapping
/// entry it is reported at (`6200sub1`, `1600sub1`).
fn counts(name: &str, bytes: &[u8]) -> (usize, usize, Vec<(String, String)>) {
    let loaded = canopener_eds::load(bytes);
    let findings = check(&loaded, Some(name), &Selection::default()).findings;
    let direction = findings.iter().filter(|f| f.diagnostic.code == "C518").count();
    let pairs: Vec<(String, String)> = findings
        .iter()
        .filter(|f| f.diagnostic.code == "C727")
        .map(|f| {
            let mapped = f
                .diagnostic
                .message
                .split("maps ")
                .nth(1)
                .and_then(|m| m.split(',').next());
            let section = f.diagnostic.section.clone().unwrap_or_default();
            (mapped.unwrap_or_default().to_owned(), section)
        })
        .collect();
    (direction, pairs.len(), pairs)
}

#[test]
fn every_corpus_file_has_the_reviewed_mapping_direction_findings() {
    let files = corpus::files(Kind::Eds);
    assert_eq!(
        files.len(),
        corpus::expected_count(Kind::Eds),
        "every EDS/DCF of the corpus"
    );
    let mut found: BTreeMap<String, (usize, usize)> = BTreeMap::new();
    for file in &files {
        let bytes = canopener_testkit::fixture::read(&file.path).expect("a corpus file is readable");
        let (c518, c727, _) = counts(&file.name, &bytes);
        if c518 + c727 > 0 {
            found.insert(file.name.clone(), (c518, c727));
        }
    }
    let expected: BTreeMap<String, (usize, usize)> = REVIEWED
        .iter()
        .filter(|(name, _, _)| files.iter().any(|f| f.name == *name))
        .map(|&(name, c518, c727)| (name.to_owned(), (c518, c727)))
        .collect();
    let mut differences: Vec<String> = found
        .keys()
        .chain(expected.keys())
        .filter(|name| found.get(*name) != expected.get(*name))
        .map(|name| {
            format!(
                "{name}: found {:?}, reviewed {:?}",
                found.get(name),
                expected.get(name)
            )
        })
        .collect();
    differences.dedup();
    assert!(differences.is_empty(), "{}", differences.join("\n"));
    if files.len() == Kind::Eds.full_count() {
        let total = |pick: fn(&(&str, usize, usize)) -> usize| REVIEWED.iter().map(pick).sum::<usize>();
        // The numbers the explanations of C518 and C727 quote.
        assert_eq!((total(|r| r.1), total(|r| r.2)), (1398, 104));
        assert_eq!(REVIEWED.iter().filter(|r| r.1 > 0).count(), 65);
        assert_eq!(REVIEWED.iter().filter(|r| r.2 > 0).count(), 28);
    }
}

/// CANchkEDS 2.4.15.0 in the CCT 3.0.3.10 run of CANopenDemo (`test/test_report_CCT.md`): warning 4 on
/// 6200sub1-8, 6411sub1-8, 2110sub1-10 and 2120sub1-4; warning 5 on 6200sub1-2 concerning 1600sub1-2
/// and 6411sub1-4 concerning 1601sub1-4.
#[test]
fn demo_device_gets_canchkeds_warnings_4_and_5_section_for_section() {
    let path = corpus::eds(DEMO_DEVICE);
    let bytes = canopener_testkit::fixture::read(&path).expect("demoDevice.eds is vendored");
    let (c518, c727, pairs) = counts(DEMO_DEVICE, &bytes);
    assert_eq!((c518, c727), (36, 6));
    let expected: Vec<(String, String)> = (1..=2)
        .map(|s| (format!("6200sub{s}"), format!("1600sub{s}")))
        .chain((1..=4).map(|s| (format!("6411sub{s}"), format!("1601sub{s}"))))
        .collect();
    assert_eq!(pairs, expected);
}

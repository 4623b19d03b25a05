//! Issue 18 item 1: `eds check` on every XDD/XDC/XPD of the corpus. No file panics; the one
//! POWERLINK file is refused as what it is; and every error-severity finding is one the review in
//! `docs/xdd-check.md` justifies by a clause: the errors expected per file and code are written down
//! here, so a new error (or a lost one) fails the test.

use std::collections::BTreeMap;

use canopener_description::{Checker, Selection};
use canopener_eds::Severity;
use canopener_testkit::corpus::{self, Kind};

/// Files `eds check` refuses (the report's `problem`), with a word of the reason.
const REFUSED: &[(&str, &str)] = &[("gdamion__grad_project__gen_xdd__ROS_CNPLC.xdd", "POWERLINK")];

/// Per file, the error-severity findings by code and count (files without errors are not listed).
const ERRORS: &[(&str, &[(&str, usize)])] = &[
    (
        "CANopenNode__CANopenEditor__EDSEditorGUI__Profiles__DS301_profile.xpd",
        &[("C309", 2)],
    ),
    (
        "CANopenNode__CANopenEditor__EDSEditorGUI__Profiles__DS301_profile_old.xpd",
        &[("C304", 2), ("C720", 4)],
    ),
    (
        "CANopenNode__CANopenEditor__EDSEditorGUI__Profiles__DSP302-NMTMaster.xpd",
        &[("C404", 2), ("C405", 1), ("C703", 1)],
    ),
    (
        "CANopenNode__CANopenEditor__Tests__minimal_project.xdd",
        &[("C404", 1), ("C405", 1)],
    ),
    (
        "CANopenNode__CANopenNode__example__DS301_profile.xpd",
        &[("C309", 2)],
    ),
    (
        "CANopenNode__CanOpenSTM32__Elcom_e-RIO_8xx_CANopen_Profile.nxdd",
        &[("C710", 1), ("C901", 1), ("C903", 8)],
    ),
    (
        "CANopenNode__CanOpenSTM32__Elcom_e-RIO_8xx_CANopen_Profile.xdd",
        &[("C304", 1), ("C903", 10)],
    ),
    ("PortiaLabiata__Proba_stepper_HAL__project.xdd", &[("C304", 1)]),
    (
        "Wizcat22__CANopenESP32__Desaster4.xdd",
        &[("C304", 2), ("C802", 1), ("C901", 4), ("C903", 9)],
    ),
    (
        "Wizcat22__CANopenESP32__Gyro-Dictionary.xdd",
        &[("C304", 1), ("C714", 7), ("C802", 1)],
    ),
    (
        "canopen-python__canopen__test__sample.xdd",
        &[("C601", 1), ("C720", 14)],
    ),
    ("catompiler__slcan_canopen__OD.xdd", &[("C304", 2), ("C309", 2)]),
    (
        "dborgards__eds-dcf-net__tests__EdsDcfNet.Tests__Fixtures__minimal.xdc",
        &[("C405", 1), ("C703", 1)],
    ),
    (
        "dborgards__eds-dcf-net__tests__EdsDcfNet.Tests__Fixtures__sample_device.xdd",
        &[("C309", 2), ("C537", 2), ("C703", 1), ("P080", 2)],
    ),
    ("jiujiujiur0000__CANopenEditor__project.xdd", &[("C802", 1)]),
    ("jrholand__EagleEyePhotography__Node1.config.xdc", &[("C537", 2)]),
    (
        "oresat__CANopen-monitor__canopen_monitor__assets__dcfs__gps.xdd",
        &[("C714", 2), ("C730", 2), ("C908", 1)],
    ),
    (
        "samkwok-hkclr__canopen_module__CANopenNode_STM32__canopen_module.xpd",
        &[("C304", 2), ("C710", 1)],
    ),
    (
        "sicrisembay__CANopenNode_C2000_Motor__controller__controller__controller.xdd",
        &[("C309", 2)],
    ),
    (
        "zylos146__CANFuck__linmot.xdd",
        &[("C309", 1), ("C537", 4), ("C706", 4)],
    ),
];

fn errors_by_file() -> BTreeMap<String, BTreeMap<String, usize>> {
    let checker = Checker::new(Vec::new(), Selection::default()).expect("no names to check");
    let mut found = BTreeMap::new();
    for file in corpus::files(Kind::Xdd) {
        let bytes = canopener_testkit::fixture::read(&file.path).expect("a corpus file is readable");
        let report = checker.check(&file.name, Some(&file.name), &bytes);
        if let Some(problem) = &report.problem {
            let expected = REFUSED.iter().find(|(name, _)| *name == file.name);
            assert!(
                expected.is_some_and(|(_, why)| problem.contains(why)),
                "{} is refused: {problem}",
                file.name
            );
            continue;
        }
        let mut errors: BTreeMap<String, usize> = BTreeMap::new();
        for f in report
            .findings
            .iter()
            .filter(|f| f.diagnostic.severity == Severity::Error)
        {
            *errors.entry(f.diagnostic.code.clone()).or_default() += 1;
        }
        if !errors.is_empty() {
            found.insert(file.name.clone(), errors);
        }
    }
    found
}

#[test]
fn every_corpus_xml_file_is_checked_and_its_errors_are_the_reviewed_ones() {
    let files = corpus::files(Kind::Xdd);
    assert_eq!(
        files.len(),
        corpus::expected_count(Kind::Xdd),
        "every XML file of the corpus"
    );
    let found = errors_by_file();
    let expected: BTreeMap<String, BTreeMap<String, usize>> = ERRORS
        .iter()
        .filter(|(name, _)| files.iter().any(|f| f.name == *name))
        .map(|(name, codes)| {
            let codes = codes.iter().map(|(c, n)| ((*c).to_owned(), *n)).collect();
            ((*name).to_owned(), codes)
        })
        .collect();
    let mut differences = Vec::new();
    for name in found.keys().chain(expected.keys()) {
        if found.get(name) != expected.get(name) {
            differences.push(format!(
                "{name}: found {:?}, reviewed {:?}",
                found.get(name),
                expected.get(name)
            ));
        }
    }
    differences.dedup();
    assert!(differences.is_empty(), "{}", differences.join("\n"));
}

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
        &[("C710", 1), ("C880", 1), ("C901", 1), ("C903", 8)],
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
        &[("C601", 1), ("C720", 14), ("C872", 2)],
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
    (
        "jrholand__EagleEyePhotography__Node1.config.xdc",
        &[("C537", 2), ("X030", 2)],
    ),
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

/// Per file, the error counts by code; and over the corpus, per code and severity, how many
/// findings in how many files.
type Counts = BTreeMap<(String, String), (usize, usize)>;

fn errors_by_file() -> BTreeMap<String, BTreeMap<String, usize>> {
    check_corpus().0
}

fn check_corpus() -> (BTreeMap<String, BTreeMap<String, usize>>, Counts) {
    let checker = Checker::new(Vec::new(), Selection::default()).expect("no names to check");
    let mut found = BTreeMap::new();
    let mut counts = Counts::new();
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
        let mut in_file: BTreeMap<(String, String), usize> = BTreeMap::new();
        for f in &report.findings {
            let key = (f.diagnostic.code.clone(), f.diagnostic.severity.to_string());
            *in_file.entry(key).or_default() += 1;
        }
        for (key, n) in in_file {
            let entry = counts.entry(key).or_default();
            entry.0 += n;
            entry.1 += 1;
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
    (found, counts)
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

/// `docs/xdd-check.md` shows the findings per code on the whole corpus between these markers; the
/// table is this test's, regenerated with `CANOPENER_UPDATE_DOCS=1` (and only comparable when the
/// extended corpus is present, as in CI).
#[test]
fn the_counts_per_code_in_the_docs_are_this_corpus_run() {
    const START: &str = "<!-- counts:start -->\n";
    const END: &str = "<!-- counts:end -->";
    let files = corpus::files(Kind::Xdd);
    if files.len() != Kind::Xdd.full_count() {
        return;
    }
    let (_, counts) = check_corpus();
    let mut table = format!(
        "{} files, {} refused. Findings per code (all severities) on the whole corpus:\n\n\
         | code | severity | findings | files |\n|---|---|---:|---:|\n",
        files.len(),
        REFUSED.len()
    );
    for ((code, severity), (findings, in_files)) in &counts {
        table.push_str(&format!("| {code} | {severity} | {findings} | {in_files} |\n"));
    }
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/xdd-check.md");
    let current = canopener_testkit::fixture::read_to_string(path).expect("docs/xdd-check.md");
    let (Some(start), Some(end)) = (current.find(START), current.find(END)) else {
        panic!("docs/xdd-check.md lacks the counts markers");
    };
    let wanted = format!("{}{START}{table}{}", &current[..start], &current[end..]);
    if std::env::var_os("CANOPENER_UPDATE_DOCS").is_some() {
        canopener_testkit::fixture::write(path, &wanted).expect("write docs/xdd-check.md");
    }
    let current = canopener_testkit::fixture::read_to_string(path).unwrap_or_default();
    assert!(
        current == wanted,
        "docs/xdd-check.md's counts are stale; run \
         `CANOPENER_UPDATE_DOCS=1 cargo test -p canopener-description --test xdd_check_corpus`"
    );
}

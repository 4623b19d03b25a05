//! The CiA 401 suite against simulated devices on virtual time: the clean CiA 401 demo device passes
//! every test, a device that is no CiA 401 device gets `not_applicable`, and a device that applies
//! a mask to the wrong edge, ignores a global interrupt enable or mixes up the analogue interrupt
//! settings fails the tests written for it.

#[path = "shared/support.rs"]
#[allow(dead_code)]
mod support;

use canopener_can::{CanFrame, CanId, StandardId};
use canopener_conformance::model::{Report, Verdict};

const DEMO: &str = "CANopenNode__CANopenDemo__demo__demoDevice.eds";
/// The demo device with the optional CiA 401 objects (polarity, interrupt enable and masks, output
/// parameters) added, so that every test applies.
fn full_io() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("test_data/cia401_full_io.eds")
}

const NOT_401: &str = "YamamotoSoya__maxon_epos4compact50-5can_ros2__maxon_epos4_ros2__config__bus_config_cia402_epos4_pos__maxon_epos4_0x1018.eds";

fn verdicts(report: &Report) -> Vec<(String, Verdict, String)> {
    report
        .tests
        .iter()
        .map(|t| (t.id.clone(), t.verdict, t.reason.clone()))
        .collect()
}

fn failed(report: &Report) -> Vec<String> {
    report
        .tests
        .iter()
        .filter(|t| t.verdict == Verdict::Fail)
        .map(|t| t.id.clone())
        .collect()
}

#[test]
fn clean_cia401_device_passes_every_test() {
    let report = support::run_rewriting(&full_io(), &["cia401"], &|f, _| *f);
    assert_eq!(report.tests.len(), 9);
    for (id, verdict, reason) in verdicts(&report) {
        assert_eq!(verdict, Verdict::Pass, "{id}: {reason}");
    }
    assert!(report.left_modified.is_empty(), "{:?}", report.left_modified);
    eprintln!(
        "cia401 suite, clean device: {:.2} virtual seconds",
        report.duration_s
    );
    let io9 = report.tests.iter().find(|t| t.id == "cia401.io.9").unwrap();
    eprintln!("cia401.io.9: {}", io9.reason);
}

#[test]
fn the_vendored_demo_device_passes_what_its_eds_makes_applicable() {
    let report = support::run(DEMO, &[], &["cia401"]);
    let expected = [
        ("cia401.io.1", Verdict::Pass),
        ("cia401.io.2", Verdict::Pass),
        // Its EDS has no 6005h, 6006h, 6007h or 6008h.
        ("cia401.io.3", Verdict::NotApplicable),
        ("cia401.io.4", Verdict::NotApplicable),
        ("cia401.io.5", Verdict::NotApplicable),
        ("cia401.io.6", Verdict::NotApplicable),
        ("cia401.io.7", Verdict::Pass),
        ("cia401.io.8", Verdict::Pass),
        // Nor 6421h, 6423h or 6426h.
        ("cia401.io.9", Verdict::NotApplicable),
    ];
    let got: Vec<_> = report.tests.iter().map(|t| (t.id.as_str(), t.verdict)).collect();
    assert_eq!(got, expected, "{:#?}", verdicts(&report));
}

#[test]
fn a_device_of_another_profile_is_not_applicable() {
    let report = support::run(NOT_401, &[], &["cia401"]);
    for (id, verdict, reason) in verdicts(&report) {
        assert_eq!(verdict, Verdict::NotApplicable, "{id}: {reason}");
        assert!(reason.contains("not a CiA 401 device"), "{id}: {reason}");
    }
}

/// SDO downloads to `index` land in `to` (and `to_sub`, else the same sub-index), and the device's
/// confirmation names `index` again, so the tester cannot tell: a firmware that files one setting
/// under another.
fn redirect(index: u16, to: u16) -> impl Fn(&CanFrame, bool) -> CanFrame {
    redirect_to(index, to, None)
}

/// Downloads to `index` land in 6207h:01 (error value output, which no input test reads): the
/// device confirms them and ignores them.
fn ignore(index: u16) -> impl Fn(&CanFrame, bool) -> CanFrame {
    redirect_to(index, 0x6207, Some(1))
}

fn redirect_to(index: u16, to: u16, to_sub: Option<u8>) -> impl Fn(&CanFrame, bool) -> CanFrame {
    let node = u16::from(support::NODE);
    let sdo = move |base: u16| CanId::Standard(StandardId::new(base + node).unwrap());
    // The sub-index of the download redirected last, until its confirmation comes back.
    let pending = std::cell::Cell::new(None::<u8>);
    move |frame: &CanFrame, sent: bool| {
        let data = frame.data();
        if data.len() != 8 {
            return *frame;
        }
        let mux = (u16::from_le_bytes([data[1], data[2]]), data[3]);
        let mut moved = data.to_vec();
        if sent && frame.id() == sdo(0x600) {
            if data[0] & 0xE0 != 0x20 || mux.0 != index {
                pending.set(None);
                return *frame;
            }
            pending.set(Some(mux.1));
            moved[1..3].copy_from_slice(&to.to_le_bytes());
            moved[3] = to_sub.unwrap_or(mux.1);
        } else if let Some(sub) = pending
            .get()
            .filter(|_| !sent && frame.id() == sdo(0x580) && data[0] == 0x60)
        {
            pending.set(None);
            moved[1..3].copy_from_slice(&index.to_le_bytes());
            moved[3] = sub;
        } else {
            return *frame;
        }
        CanFrame::new(frame.id(), &moved).unwrap()
    }
}

#[test]
fn a_mask_on_the_wrong_edge_is_caught() {
    // 6007h written lands in 6008h: the device fires on falling edges when told rising.
    let report = support::run_rewriting(&full_io(), &["cia401"], &redirect(0x6007, 0x6008));
    assert!(
        failed(&report).contains(&"cia401.io.5".to_owned()),
        "{:#?}",
        verdicts(&report)
    );
    let io5 = report.tests.iter().find(|t| t.id == "cia401.io.5").unwrap();
    assert!(
        io5.reason.contains("input 02h should give a TPDO1, got no TPDO"),
        "{}",
        io5.reason
    );
    // 6008h written lands in 6007h.
    let report = support::run_rewriting(&full_io(), &["cia401"], &redirect(0x6008, 0x6007));
    assert!(
        failed(&report).contains(&"cia401.io.6".to_owned()),
        "{:#?}",
        verdicts(&report)
    );
    let io6 = report.tests.iter().find(|t| t.id == "cia401.io.6").unwrap();
    assert!(
        io6.reason.contains("input 02h should not give a TPDO1"),
        "{}",
        io6.reason
    );
    // The any-change mask ignored: the device keeps FFh and reports the masked input too.
    let report = support::run_rewriting(&full_io(), &["cia401.io.4"], &ignore(0x6006));
    assert_eq!(failed(&report), ["cia401.io.4"], "{:#?}", verdicts(&report));
    assert!(
        report.tests[0]
            .reason
            .contains("input 40h should not give a TPDO1"),
        "{}",
        report.tests[0].reason
    );
}

#[test]
fn an_ignored_global_interrupt_enable_is_caught() {
    // Writes to 6005h are confirmed and ignored: interrupts stay enabled.
    let report = support::run_rewriting(&full_io(), &["cia401.io.3"], &ignore(0x6005));
    assert_eq!(failed(&report), ["cia401.io.3"], "{:#?}", verdicts(&report));
    let reason = &report.tests[0].reason;
    assert!(reason.contains("input 01h should not give a TPDO1"), "{reason}");
    assert!(
        report.tests[0].analysis.contains("6005h"),
        "{}",
        report.tests[0].analysis
    );
}

#[test]
fn ignored_polarity_is_caught() {
    let report = support::run_rewriting(&full_io(), &["cia401.io.2"], &ignore(0x6002));
    assert_eq!(failed(&report), ["cia401.io.2"], "{:#?}", verdicts(&report));
    assert!(
        report.tests[0].reason.contains("input 5Ah with polarity FFh"),
        "{}",
        report.tests[0].reason
    );
}

#[test]
fn wrong_analogue_interrupt_handling_is_caught() {
    let io9 = |report: &Report| {
        let test = report.tests.iter().find(|t| t.id == "cia401.io.9").unwrap();
        (test.verdict, test.reason.clone())
    };
    // 6423h written TRUE is ignored: it stays FALSE, no analogue event at all.
    let report = support::run_rewriting(&full_io(), &["cia401.io.9"], &ignore(0x6423));
    let (verdict, reason) = io9(&report);
    assert_eq!(verdict, Verdict::Fail, "{reason}");
    assert!(reason.contains("value 600 should give a TPDO2"), "{reason}");
    // 6421h ignored: the default 07h stays, so a value under the upper limit still triggers (delta 0).
    let report = support::run_rewriting(&full_io(), &["cia401.io.9"], &ignore(0x6421));
    let (verdict, reason) = io9(&report);
    assert_eq!(verdict, Verdict::Fail, "{reason}");
    assert!(reason.contains("value 500 should not give a TPDO2"), "{reason}");
    // The upper limit lands in the lower limit: 500 is "above" the upper limit 0.
    let report = support::run_rewriting(&full_io(), &["cia401.io.9"], &redirect(0x6424, 0x6425));
    let (verdict, reason) = io9(&report);
    assert_eq!(verdict, Verdict::Fail, "{reason}");
    assert!(reason.contains("upper limit"), "{reason}");
    // The delta lands in the upper limit (unused by then) and stays 0: every change triggers.
    let report = support::run_rewriting(&full_io(), &["cia401.io.9"], &redirect(0x6426, 0x6424));
    let (verdict, reason) = io9(&report);
    assert_eq!(verdict, Verdict::Fail, "{reason}");
    assert!(reason.contains("value 450 should not give a TPDO2"), "{reason}");
}

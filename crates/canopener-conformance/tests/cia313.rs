//! The CiA 313 performance suite against simulated devices on virtual time.

#[path = "shared/support.rs"]
mod support;

#[test]
fn explore() {
    for name in [
        "CANopenNode__CANopenDemo__demo__demoDevice.eds",
        "ros-industrial__ros_canopen__ipa_canopen_test__config__PRL120.eds",
    ] {
        let start = std::time::Instant::now();
        let report = support::run(name, &[], &["cia313"]);
        eprintln!("{name}: {:?} wall", start.elapsed());
        for t in &report.tests {
            eprintln!(
                "{} {} {:.3}s: {}\n{}",
                t.id,
                t.verdict.as_str(),
                t.duration_s,
                t.reason,
                t.analysis
            );
        }
    }
}

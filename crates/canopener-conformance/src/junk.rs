//! Junk: frames on the device's own answer CAN-IDs that no correct device sends, and what a test
//! that met some may conclude. A tester cannot tell who sent a frame (a second node may answer
//! in the device's place), so a test that met junk never passes and is never "not applicable": it
//! fails on its own evidence or is inconclusive, and its reason quotes the frame.
//!
//! Junk is a frame the tester received during the test that
//! - broke an SDO transfer: the tester's SDO client aborted it (wrong command specifier, toggle,
//!   multiplexer, size, CRC; [`crate::context::Reply::Broken`]);
//! - has the wrong length for its service: an SDO answer (580h + node-ID) or an LSS answer (7E4h)
//!   without 8 bytes (CiA 301 §7.2.4.3, CiA 305 §4.3), an EMCY (80h + node-ID) without 8 bytes (CiA
//!   301 §7.2.7.3.1), a heartbeat, boot-up or guarding answer (700h + node-ID) without exactly 1
//!   byte (CiA 301 §7.2.8.3.2);
//! - reports an NMT state CiA 301 does not have (700h + node-ID, bits 0–6 not 00h, 04h, 05h or 7Fh).

use canopener_can::{CanFrame, CanId, Instant};
use canopener_wire::NmtState;

use crate::finding::Finding;
use crate::model::{Direction, Report, Verdict};

/// A frame no correct device sends, and why.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Junk {
    /// When the tester received it (the link's clock).
    pub at: Instant,
    /// The frame.
    pub frame: CanFrame,
    /// What is wrong with it.
    pub why: String,
}

impl Junk {
    /// `585#0102 (an SDO answer has 8 bytes, this one 2)`.
    pub fn describe(&self) -> String {
        format!("{} ({})", self.frame, self.why)
    }
}

/// Why `frame`, received from the bus, cannot come from a correct device with node-ID `node`;
/// `None` when it may (or is not on one of the device's answer CAN-IDs).
pub fn malformed(node: u8, frame: &CanFrame) -> Option<String> {
    let CanId::Standard(id) = frame.id() else {
        return None;
    };
    if frame.is_remote() {
        return None;
    }
    let raw = id.as_raw();
    let node = u16::from(node);
    let len = frame.data().len();
    let wrong_length = |service: &str, wanted: usize| {
        (len != wanted).then(|| format!("{service} has {wanted} bytes, this one {len}"))
    };
    if raw == 0x580 + node {
        wrong_length("an SDO answer", 8)
    } else if raw == 0x080 + node {
        wrong_length("an EMCY", 8)
    } else if raw == canopener_wire::LSS_SLAVE_TO_MASTER_ID {
        wrong_length("an LSS answer", 8)
    } else if raw == 0x700 + node {
        if let Some(why) = wrong_length("a heartbeat, boot-up or guarding answer", 1) {
            return Some(why);
        }
        let state = frame.data().first().copied().unwrap_or(0) & 0x7F;
        NmtState::from_raw(state)
            .is_none()
            .then(|| format!("{state:02X}h is no NMT state"))
    } else {
        None
    }
}

/// Every frame among `received` that [`malformed`] names, in order.
pub fn scan<'a>(node: u8, received: impl IntoIterator<Item = (Instant, &'a CanFrame)>) -> Vec<Junk> {
    received
        .into_iter()
        .filter_map(|(at, frame)| {
            malformed(node, frame).map(|why| Junk {
                at,
                frame: *frame,
                why,
            })
        })
        .collect()
}

/// What a test may conclude after it met `junk` (see the [module docs](self)): a pass or "not
/// applicable" becomes inconclusive, quoting the first junk and saying what the verdict would have
/// been; a failure or an inconclusive verdict stays, with the junk added to its reason unless the
/// reason or the analysis already quotes it.
pub fn judge(finding: Finding, junk: &[Junk]) -> Finding {
    let Some(first) = junk.first() else {
        return finding;
    };
    let more = match junk.len() {
        1 => String::new(),
        n => format!(" and {} more", n - 1),
    };
    let quoted = junk.iter().any(|j| {
        let text = j.frame.to_string();
        finding.reason.contains(&text) || finding.analysis.contains(&text)
    });
    match finding.verdict {
        Verdict::Pass | Verdict::NotApplicable => Finding {
            analysis: finding.analysis,
            ..Finding::inconclusive(format!(
                "the device's CAN-IDs carried junk no correct device sends: {}{more}; not judged (without it: {}, {})",
                first.describe(),
                finding.verdict.as_str(),
                finding.reason
            ))
        },
        Verdict::Fail | Verdict::Inconclusive if quoted => finding,
        Verdict::Fail | Verdict::Inconclusive => Finding {
            reason: format!(
                "{}; the device's CAN-IDs also carried junk: {}{more}",
                finding.reason,
                first.describe()
            ),
            ..finding
        },
    }
}

/// What a test may conclude after SDO requests of it got no answer (`unanswered`): "not
/// applicable" only for a reason the EDS or an abort code gives (CiA 301 §7.2.4.3.17: a server that
/// does not serve a request aborts it), never for silence, so it becomes inconclusive, naming the
/// request; other verdicts stay.
pub fn judge_unanswered(finding: Finding, unanswered: &[String]) -> Finding {
    match unanswered.first() {
        Some(first) if finding.verdict == Verdict::NotApplicable => Finding::inconclusive(format!(
            "{first} got no answer within the SDO timeout; silence is no reason for not applicable (without it: not_applicable, {})",
            finding.reason
        )),
        _ => finding,
    }
}

/// The tests of `report` (a run against node `node`) that break the rule of this module: their
/// log holds junk and they passed, were not applicable, or quote no frame they received in their
/// reason or analysis. Empty for every report the runner makes; hostile-device tests and the
/// fuzz target check it.
pub fn unjudged(node: u8, report: &Report) -> Vec<String> {
    let mut broken = Vec::new();
    for test in &report.tests {
        let received: Vec<String> = test
            .telegrams
            .iter()
            .filter(|t| t.dir == Direction::Rx)
            .map(|t| t.frame.to_string())
            .collect();
        let junk: Vec<String> = test
            .telegrams
            .iter()
            .filter(|t| t.dir == Direction::Rx && malformed(node, &t.frame).is_some())
            .map(|t| t.frame.to_string())
            .collect();
        if junk.is_empty() {
            continue;
        }
        if matches!(test.verdict, Verdict::Pass | Verdict::NotApplicable) {
            broken.push(format!(
                "{} met junk {junk:?} and says {}: {}",
                test.id,
                test.verdict.as_str(),
                test.reason
            ));
        } else if !received
            .iter()
            .any(|f| test.reason.contains(f.as_str()) || test.analysis.contains(f.as_str()))
        {
            broken.push(format!(
                "{} met junk {junk:?} but quotes no frame it received: {}",
                test.id, test.reason
            ));
        }
    }
    broken
}

#[cfg(test)]
mod tests {
    use canopener_can::StandardId;

    use super::*;
    use crate::finding::Evidence;

    fn frame(id: u16, data: &[u8]) -> CanFrame {
        CanFrame::new(StandardId::new(id).unwrap(), data).unwrap()
    }

    #[test]
    fn answers_of_the_wrong_length_or_state_are_junk() {
        assert_eq!(
            malformed(5, &frame(0x585, &[0x43, 0])).as_deref(),
            Some("an SDO answer has 8 bytes, this one 2")
        );
        assert!(malformed(5, &frame(0x585, &[0; 8])).is_none());
        assert!(
            malformed(5, &frame(0x586, &[])).is_none(),
            "another node's channel"
        );
        assert!(malformed(5, &frame(0x085, &[0; 3])).is_some());
        assert!(malformed(5, &frame(0x7E4, &[])).is_some());
        assert!(malformed(5, &frame(0x705, &[])).is_some());
        assert!(malformed(5, &frame(0x705, &[0x05, 0])).is_some());
        assert_eq!(
            malformed(5, &frame(0x705, &[0x33])).as_deref(),
            Some("33h is no NMT state")
        );
        for state in [0x00, 0x04, 0x05, 0x7F, 0x85, 0xFF] {
            assert!(malformed(5, &frame(0x705, &[state])).is_none(), "{state:02X}");
        }
        let remote = CanFrame::remote(StandardId::new(0x705).unwrap(), 1).unwrap();
        assert!(malformed(5, &remote).is_none());
    }

    #[test]
    fn junk_turns_a_pass_or_not_applicable_into_inconclusive_quoting_the_frame() {
        let junk = scan(5, [(Instant::ZERO, &frame(0x585, &[]))]);
        for finding in [Finding::pass("confirmed"), Finding::not_applicable("refused")] {
            let judged = judge(finding.clone(), &junk);
            assert_eq!(judged.verdict, Verdict::Inconclusive);
            assert!(
                judged
                    .reason
                    .contains("585# (an SDO answer has 8 bytes, this one 0)"),
                "{}",
                judged.reason
            );
            assert!(judged.reason.contains(&finding.reason), "{}", judged.reason);
        }
        assert_eq!(judge(Finding::pass("ok"), &[]), Finding::pass("ok"));
    }

    #[test]
    fn silence_is_no_reason_for_not_applicable() {
        let unanswered = ["SDO request for 1800h:02".to_owned()];
        let judged = judge_unanswered(Finding::not_applicable("TPDO1 cannot be set up"), &unanswered);
        assert_eq!(judged.verdict, Verdict::Inconclusive);
        assert!(
            judged
                .reason
                .starts_with("SDO request for 1800h:02 got no answer"),
            "{}",
            judged.reason
        );
        assert_eq!(
            judge_unanswered(Finding::pass("silent in Stopped"), &unanswered).verdict,
            Verdict::Pass
        );
        let na = Finding::not_applicable("the EDS has no 1003h");
        assert_eq!(judge_unanswered(na.clone(), &[]), na);
    }

    #[test]
    fn a_failure_keeps_its_verdict_and_quotes_the_junk_once() {
        let junk = scan(5, [(Instant::ZERO, &frame(0x705, &[9]))]);
        let evidence = Evidence {
            request: "r".into(),
            requirement: "q".into(),
            answer: "a".into(),
            cause: "c".into(),
        };
        let judged = judge(Finding::fail("wrong", evidence.clone()), &junk);
        assert_eq!(judged.verdict, Verdict::Fail);
        assert_eq!(
            judged.reason,
            "wrong; the device's CAN-IDs also carried junk: 705#09 (09h is no NMT state)"
        );
        let quoting = Finding::fail("heartbeat 705#09", evidence);
        assert_eq!(judge(quoting.clone(), &junk), quoting);
    }
}

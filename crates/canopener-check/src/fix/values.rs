//! P045 and C537: values that follow from the sub-objects present.

use canopener_eds::section_name::{self, SectionKind};
use canopener_eds::value::mentions_nodeid;
use canopener_eds::{Code, Object, Origin};

use super::{Edit, Fix, Planned, number_like};
use crate::context::Context;

/// P045: `SubNumber` is the number of sub-indices implemented, sub 0 included and FFh excluded
/// (CiA 306 V1.3 §4.6.3.2); the fix counts the sub-object sections the file has, as the loader does.
/// It only changes how the file describes itself: no value a device reports depends on it.
pub(super) fn sub_number(cx: &Context<'_>, out: &mut Planned) {
    let doc = cx.document;
    for diagnostic in cx.diagnostics {
        if diagnostic.code != Code::SubNumberMismatch {
            continue;
        }
        let Some(name) = diagnostic.section.as_deref() else {
            continue;
        };
        let kind = section_name::classify(name);
        let SectionKind::Object(index) = kind else {
            continue;
        };
        let Some(object) = cx.eds.objects.get(&index) else {
            continue;
        };
        let present = object
            .subs
            .iter()
            .filter(|&(&sub, s)| s.origin == Origin::Explicit && sub != 0xFF)
            .count();
        let Some(section) = cx.section(kind) else { continue };
        let Some(line) = doc.find_entry(section, "SubNumber") else {
            continue;
        };
        let Some((key, old)) = doc.entry(line) else {
            continue;
        };
        let new = number_like(old, present as u64);
        if new == old {
            continue;
        }
        out.fixes.push(Fix {
            code: "P045".to_owned(),
            description: format!(
                "[{}] {key}: {old} -> {new} (the number of sub-object sections present)",
                doc.section_name(section)
            ),
            changes_meaning: false,
            edits: vec![Edit::SetValue { line, value: new }],
        });
    }
}

/// C537: sub 0 of an ARRAY or RECORD holds the highest sub-index supported (CiA 301). The
/// fix sets sub 0's `DefaultValue` to the highest sub-index described (FFh, the structure entry,
/// excluded), as the check computes it. A device reports this value, so the fix is marked as
/// changing meaning. Only a sub 0 below the highest sub-index described is raised: the sections
/// show the device has those entries. A sub 0 above it is more likely a file that leaves entries
/// out than a device that lacks them, so that fix is refused with the reason.
pub(super) fn sub0_highest(cx: &Context<'_>, out: &mut Planned) {
    let mut findings = Vec::new();
    crate::checks::objects::run(cx, &mut findings);
    let doc = cx.document;
    let mut done = std::collections::HashSet::new();
    // Findings marked not fixable are on objects whose sub 0 counts entries in use (1003h, PDO
    // mappings): lowering it would change what the device does, so they are left alone.
    for finding in findings
        .iter()
        .filter(|f| f.diagnostic.code == "C537" && f.fixable)
    {
        let Some(name) = finding.diagnostic.section.as_deref() else {
            continue;
        };
        let index = match section_name::classify(name) {
            SectionKind::Object(index) | SectionKind::Sub(index, 0) => index,
            _ => continue,
        };
        if !done.insert(index) {
            continue;
        }
        let Some(object) = cx.eds.objects.get(&index) else {
            continue;
        };
        let Some(highest) = highest_sub(object) else {
            continue;
        };
        let Some(section) = cx.section(SectionKind::Sub(index, 0)) else {
            continue;
        };
        let Some(line) = doc.find_entry(section, "DefaultValue") else {
            continue;
        };
        let Some((key, old)) = doc.entry(line) else {
            continue;
        };
        if mentions_nodeid(old) {
            continue;
        }
        let Some(current) = canopener_eds::model::int_of(old) else {
            continue;
        };
        let new = number_like(old, u64::from(highest));
        if new == old || current == i128::from(highest) {
            continue;
        }
        let fix = Fix {
            code: "C537".to_owned(),
            description: format!(
                "[{}] {key}: {old} -> {new} (the highest sub-index present; changes the value the device reports in sub 0)",
                doc.section_name(section)
            ),
            changes_meaning: true,
            edits: vec![Edit::SetValue { line, value: new }],
        };
        if current > i128::from(highest) {
            out.refused.push((
                fix,
                format!(
                    "sub 0 says {old}, but sub-objects are described only up to {highest:X}h: lowering it \
                     would hide sub-indices the device may have; describe the missing sub-objects, or \
                     lower sub 0 by hand"
                ),
            ));
        } else {
            out.fixes.push(fix);
        }
    }
}

/// The highest sub-index described (written or implied by a compact form), FFh excluded.
fn highest_sub(object: &Object) -> Option<u8> {
    object.subs.keys().copied().rfind(|&sub| sub != 0xFF)
}

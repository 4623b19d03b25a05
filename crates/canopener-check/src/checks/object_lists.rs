//! Group E of the check catalogue (`docs/check-catalogue.md`): the object lists `[MandatoryObjects]`,
//! `[OptionalObjects]` and `[ManufacturerObjects]` (checks 22-27).
//!
//! The loader already reports most list problems: a count that disagrees with the entries or is not
//! a number, keys that are not decimal, values that are not indices, an index listed twice (P044), a
//! listed index without a section (P042) and a section no list names (P043). The checks here add
//! what it does not: a missing `SupportedObjects`, entry numbers that leave gaps while the count
//! still matches, indices in the wrong list, and the always-mandatory objects.

use std::collections::BTreeSet;

use canopener_eds::model::{ObjectListKind, int_of};
use canopener_eds::section_name::SectionKind;
use canopener_eds::{Origin, Severity};

use crate::check_info::{CheckInfo, Group};
use crate::context::Context;
use crate::finding::Finding;

const SUPPORTED_OBJECTS_MISSING: CheckInfo = CheckInfo {
    code: "C401",
    slug: "supported-objects-missing",
    severity: Severity::Error,
    group: Group::ObjectLists,
    title: "every object list gives its length in SupportedObjects",
    reference: &[22],
    spec: "CiA 306 V1.3 §4.6.3.1",
    explanation: "\
An object list section ([MandatoryObjects], [OptionalObjects], [ManufacturerObjects]) starts with \
SupportedObjects=<n>, the number of entries 1..n that follow. This check reports a list section \
that has no SupportedObjects entry, or an empty one.

Without the count a reader cannot tell how many entries to read. lely's dcfchk rejects the list, \
and the CiA conformance tool reports a missing mandatory entry. python canopen ignores the lists \
entirely, so the problem goes unnoticed until the file meets a stricter tool.

It is an error because CiA 306 §4.6.3.1 defines SupportedObjects as the first, mandatory entry of \
every list, and §4.2 makes every entry mandatory unless stated otherwise.

Fix: add SupportedObjects=<n> with n the number of numbered entries of the list.",
    fixable: false,
};

const OBJECT_LIST_NUMBERING: CheckInfo = CheckInfo {
    code: "C402",
    slug: "object-list-numbering",
    severity: Severity::Error,
    group: Group::ObjectLists,
    title: "object list entries are numbered 1..SupportedObjects without gaps",
    reference: &[22],
    spec: "CiA 306 V1.3 §4.6.3.1",
    explanation: "\
The entries of an object list are numbered in decimal from 1 up to SupportedObjects: 1=0x1000, \
2=0x1001, ... This check reports entry numbers above SupportedObjects and numbers missing below \
it, when the count itself matches the number of entries (a count that does not match is reported \
as P044).

A reader that walks the list from 1 to SupportedObjects, as lely does, skips an entry numbered \
above the count and stops at the gap, so an object described in the file silently disappears from \
the device model.

It is an error because CiA 306 §4.6.3.1 numbers the entries 1..SupportedObjects.

Fix: renumber the entries consecutively from 1.",
    fixable: false,
};

const OBJECT_LIST_CLASSIFICATION: CheckInfo = CheckInfo {
    code: "C403",
    slug: "object-in-wrong-list",
    severity: Severity::Warning,
    group: Group::ObjectLists,
    title: "each index is listed in the object list CiA 306 assigns to its range",
    reference: &[26],
    spec: "CiA 306 V1.3 §4.6.3.1",
    explanation: "\
CiA 306 §4.6.3.1 assigns every index to one list: [MandatoryObjects] holds only the objects every \
device has (1000h, 1001h and, since CANopen 4.0, 1018h); [ManufacturerObjects] holds 2000h-5FFFh; \
[OptionalObjects] holds every other index in 1000h-1FFFh and 6000h-FFFFh. Indices below 1000h \
(data type definitions) belong in no list. This check reports an index listed in another list.

lely's dcfchk reports a misplaced index; tools that build their model from the lists (lely, the \
CiA conformance tool) read the object anyway, and python canopen and CANopenEditor ignore the \
lists. Reviewers of a device description rely on the lists to tell standard from \
manufacturer-specific objects.

It is a warning, not an error: the file departs from §4.6.3.1, but every tool still finds the \
object, so nothing is lost. Files written before CANopen 4.0 may list 1018h as optional; that is \
accepted.

Fix: move the entry to the list named in the message and renumber both lists.",
    fixable: false,
};

const MANDATORY_OBJECT_MISSING: CheckInfo = CheckInfo {
    code: "C404",
    slug: "mandatory-object-missing",
    severity: Severity::Error,
    group: Group::ObjectLists,
    title: "the device type 1000h and the error register 1001h are described",
    reference: &[27],
    spec: "CiA 306 V1.3 §4.6.3.1, CiA 301-§7.5.2.2",
    explanation: "\
Every CANopen device implements object 1000h (device type) and 1001h (error register); CiA 306 \
§4.6.3.1 lists them in [MandatoryObjects]. This check reports a file that neither describes nor \
lists one of them (a listed object without a section is reported as P042 instead).

A master reads 1000h during boot-up to identify the device profile, and the error register is \
part of every emergency message. lely's loader warns about the missing object, and the CiA \
conformance test fails on it.

It is an error because CiA 301 makes both objects mandatory for every device.

Fix: describe the object as a VAR (1000h: UNSIGNED32 ro; 1001h: UNSIGNED8 ro) and list it in \
[MandatoryObjects].",
    fixable: false,
};

const IDENTITY_OBJECT_MISSING: CheckInfo = CheckInfo {
    code: "C405",
    slug: "identity-object-missing",
    severity: Severity::Error,
    group: Group::ObjectLists,
    title: "the identity object 1018h is described",
    reference: &[27],
    spec: "CiA 306 V1.3 §4.6.3.1, CiA 301",
    explanation: "\
CiA 301 (since CANopen 4.0) makes the identity object 1018h mandatory, with at least the vendor-ID \
in sub 1; CiA 306 §4.6.3.1 lists it in [MandatoryObjects] for such devices. This check reports a \
file that neither describes nor lists 1018h.

Masters identify a device by 1018h (CiA 302 boot-up compares vendor-ID, product code and \
revision), LSS needs it, and the [DeviceInfo] cross-checks have nothing to compare with.

It is an error for files that declare EDSVersion 4.0 or later; for older files (EDSVersion below \
4.0 or missing, which means 3.0) it is a warning, because 1018h was optional before CANopen 4.0.

Fix: describe 1018h as a RECORD with sub 0 (UNSIGNED8, highest sub-index) and sub 1 vendor-ID \
(UNSIGNED32 ro), optionally subs 2-4, and list it in [MandatoryObjects].",
    fixable: false,
};

/// The checks of this group.
pub(crate) const CHECKS: &[CheckInfo] = &[
    SUPPORTED_OBJECTS_MISSING,
    OBJECT_LIST_NUMBERING,
    OBJECT_LIST_CLASSIFICATION,
    MANDATORY_OBJECT_MISSING,
    IDENTITY_OBJECT_MISSING,
];

/// Runs the checks of this group.
pub(crate) fn run(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let pre_v4 = is_pre_v4(cx);
    for kind in ObjectListKind::ALL {
        let Some(list) = cx.eds.object_lists.get(&kind) else {
            continue;
        };
        let section = SectionKind::ObjectList(kind);
        let name = kind.section_name();
        let numbered: Vec<(u32, &str)> = list.0.numbered().collect();
        match list.declared_count().map(str::trim) {
            None | Some("") => out.push(
                cx.finding(
                    &SUPPORTED_OBJECTS_MISSING,
                    section,
                    None,
                    format!(
                        "[{name}] has no SupportedObjects count for its {} numbered {}",
                        numbered.len(),
                        if numbered.len() == 1 { "entry" } else { "entries" }
                    ),
                )
                .with_help(format!("add SupportedObjects={} to [{name}]", numbered.len())),
            ),
            Some(raw) => check_numbering(cx, out, kind, raw, &numbered),
        }
        for &(n, value) in &numbered {
            let Some(index) = int_of(value).and_then(|v| u16::try_from(v).ok()) else {
                continue;
            };
            if let Some(right) = misplaced(index, kind, pre_v4) {
                let key = n.to_string();
                out.push(
                    cx.finding(
                        &OBJECT_LIST_CLASSIFICATION,
                        section,
                        Some(&key),
                        format!("[{name}] lists {index:04X}h, which {right}"),
                    )
                    .with_help("move the entry to the right list and renumber both lists"),
                );
            }
        }
    }
    let listed: BTreeSet<u16> = cx
        .eds
        .object_lists
        .values()
        .flat_map(|list| list.indices())
        .collect();
    let described = |index: u16| {
        cx.eds
            .objects
            .get(&index)
            .is_some_and(|o| o.origin != Origin::Orphan)
    };
    // Missing objects have no line of their own; the list that should name them is the place to look.
    let mandatory_list = SectionKind::ObjectList(ObjectListKind::Mandatory);
    for (index, what) in [(0x1000u16, "device type"), (0x1001, "error register")] {
        if !described(index) && !listed.contains(&index) {
            out.push(
                cx.finding(
                    &MANDATORY_OBJECT_MISSING,
                    mandatory_list,
                    None,
                    format!(
                        "the file does not describe object {index:04X}h ({what}), which every device has"
                    ),
                )
                .with_help(format!(
                    "add a [{index:X}] section and list {index:04X}h in [MandatoryObjects]"
                )),
            );
        }
    }
    if !described(0x1018) && !listed.contains(&0x1018) {
        let finding = cx
            .finding(
                &IDENTITY_OBJECT_MISSING,
                mandatory_list,
                None,
                "the file does not describe the identity object 1018h",
            )
            .with_help("add [1018] with sub 0 and sub 1 (vendor-ID) and list it in [MandatoryObjects]");
        out.push(if pre_v4 {
            finding.with_severity(Severity::Warning)
        } else {
            finding
        });
    }
}

/// Entry numbers must run 1..=SupportedObjects. Only checked when the count matches the number of
/// numbered entries: a count that does not match is already P044.
fn check_numbering(
    cx: &Context<'_>,
    out: &mut Vec<Finding>,
    kind: ObjectListKind,
    raw_count: &str,
    numbered: &[(u32, &str)],
) {
    let Some(count) = int_of(raw_count) else {
        return;
    };
    if count != numbered.len() as i128 {
        return;
    }
    let section = SectionKind::ObjectList(kind);
    let present: BTreeSet<u32> = numbered.iter().map(|&(n, _)| n).collect();
    let missing: Vec<String> = (1..=numbered.len() as u32)
        .filter(|n| !present.contains(n))
        .map(|n| n.to_string())
        .collect();
    for &(n, value) in numbered {
        if n == 0 || i128::from(n) > count {
            let key = n.to_string();
            out.push(
                cx.finding(
                    &OBJECT_LIST_NUMBERING,
                    section,
                    Some(&key),
                    format!("entry {n}={value} is outside 1..={count} (SupportedObjects={raw_count})"),
                )
                .with_help(if missing.is_empty() {
                    "number the entries 1, 2, ... up to SupportedObjects".to_owned()
                } else {
                    format!(
                        "number missing: {}; renumber the entries consecutively",
                        missing.join(", ")
                    )
                }),
            );
        }
    }
}

/// Why an index does not belong in this list, or `None` if it does (CiA 306 V1.3 §4.6.3.1).
fn misplaced(index: u16, list: ObjectListKind, pre_v4: bool) -> Option<&'static str> {
    if index < 0x1000 {
        return Some("is a data type definition and belongs in no object list");
    }
    let mandatory = matches!(index, 0x1000 | 0x1001 | 0x1018);
    match list {
        ObjectListKind::Mandatory if !mandatory => Some(match index {
            0x2000..=0x5FFF => "is manufacturer-specific and belongs in [ManufacturerObjects]",
            _ => "is not mandatory for every device and belongs in [OptionalObjects]",
        }),
        ObjectListKind::Optional if index == 0x1018 && pre_v4 => None,
        ObjectListKind::Optional if mandatory => Some("is mandatory and belongs in [MandatoryObjects]"),
        ObjectListKind::Optional if (0x2000..=0x5FFF).contains(&index) => {
            Some("is manufacturer-specific and belongs in [ManufacturerObjects]")
        }
        ObjectListKind::Manufacturer if !(0x2000..=0x5FFF).contains(&index) => Some(if mandatory {
            "is mandatory and belongs in [MandatoryObjects]"
        } else {
            "is outside 2000h-5FFFh and belongs in [OptionalObjects]"
        }),
        _ => None,
    }
}

/// Whether the file was written for CiA 306 before EDSVersion 4.0 (a missing EDSVersion means 3.0,
/// CiA 306 V1.3 §4.4).
fn is_pre_v4(cx: &Context<'_>) -> bool {
    let version = cx.eds.file_info.eds_version.as_deref().map_or("", str::trim);
    if version.is_empty() {
        return true;
    }
    let major = version.split('.').next().unwrap_or("");
    major.parse::<u32>().is_ok_and(|m| m < 4)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::findings_with_code as findings;

    const MINIMAL: &str = "[FileInfo]\nEDSVersion=4.0\n\
        [MandatoryObjects]\nSupportedObjects=2\n1=0x1000\n2=0x1001\n\
        [1000]\nParameterName=Device type\nDataType=0x0007\nAccessType=ro\n\
        [1001]\nParameterName=Error register\nDataType=0x0005\nAccessType=ro\n";

    #[test]
    fn a_missing_identity_object_is_an_error_from_cia306_v4_and_a_warning_before() {
        let found = findings(MINIMAL, "C405");
        assert_eq!(found.len(), 1);
        assert_eq!(found[0].diagnostic.severity, Severity::Error);
        for older in ["EDSVersion=3.0", "EDSVersion="] {
            let text = MINIMAL.replace("EDSVersion=4.0", older);
            let found = findings(&text, "C405");
            assert_eq!(found.len(), 1, "{older}");
            assert_eq!(found[0].diagnostic.severity, Severity::Warning, "{older}");
        }
        assert!(findings(MINIMAL, "C404").is_empty());
    }

    #[test]
    fn each_range_has_its_list() {
        use ObjectListKind::{Mandatory, Manufacturer, Optional};
        for (index, list, pre_v4, wrong) in [
            (0x1000, Mandatory, false, false),
            (0x1018, Mandatory, true, false),
            (0x1017, Mandatory, false, true),
            (0x6000, Mandatory, false, true),
            (0x1018, Optional, true, false),
            (0x1018, Optional, false, true),
            (0x1001, Optional, true, true),
            (0x1FFF, Optional, false, false),
            (0x2000, Optional, false, true),
            (0x6000, Optional, false, false),
            (0xFFFF, Optional, false, false),
            (0x2000, Manufacturer, false, false),
            (0x5FFF, Manufacturer, false, false),
            (0x6000, Manufacturer, false, true),
            (0x1000, Manufacturer, false, true),
            (0x0023, Optional, false, true),
        ] {
            assert_eq!(
                misplaced(index, list, pre_v4).is_some(),
                wrong,
                "{index:04X}h in {list:?}"
            );
        }
    }

    #[test]
    fn numbering_gaps_are_reported_only_when_the_count_matches() {
        let gap = MINIMAL.replace("1=0x1000\n2=0x1001", "1=0x1000\n3=0x1001");
        let found = findings(&gap, "C402");
        assert_eq!(found.len(), 1);
        assert!(
            found[0].diagnostic.message.contains("3=0x1001"),
            "{}",
            found[0].diagnostic.message
        );
        // A count that disagrees is P044's finding, not this one's.
        let short = gap.replace("SupportedObjects=2", "SupportedObjects=3");
        assert!(findings(&short, "C402").is_empty());
    }
}

//! Group K of the check catalogue (`docs/check-catalogue.md`): standard objects against the shipped reference
//! profiles (check 65).
//!
//! CiA 301 applies to every file; the device profile is chosen by 1000h bits 0-15 (CiA 401 for
//! 0191h). Only what a profile states is compared (see [`crate::profile`]). 1000h, 1001h and 1018h
//! are left to group H (C701, C702), which checks them more closely; sub 0 being missing is check 36
//! (group F).

use canopener_eds::{Attributes, Object, ObjectType, Origin, Severity};

use super::reading::{Int, entry_name, live_object, object_finding, reading, type_name, written};
use crate::check_info::{CheckInfo, Group};
use crate::context::Context;
use crate::finding::Finding;
use crate::profile::{self, EntrySpec, PdoMapping, Profile, ProfileObject};

const OBJECT_TYPE: CheckInfo = CheckInfo {
    code: "C901",
    slug: "profile-object-type",
    severity: Severity::Error,
    group: Group::Profiles,
    title: "Standard objects are VARs or structured objects as their profile defines",
    reference: &[65],
    spec: "CiA 301 / CiA 401 object definitions; CiA 306 V1.3 §4.6.3.2 (ObjectType)",
    explanation: "\
CiA 301 and the device profiles define each standard object as a VAR (one value) or as an ARRAY or \
RECORD (sub-indices). This check compares the ObjectType of standard objects with the shipped \
reference data (canopener's data/cia301.toml and data/cia401.toml, which name their sources) and \
reports a VAR where the profile has sub-indices, or the reverse.

Masters and tools address standard objects by the profile's layout: a VAR 6000h cannot be read at \
sub-index 1, and a structured 1017h answers an SDO upload of sub-index 0 with the highest sub-index \
instead of the heartbeat time.

It is an error: the object no longer is the standard object whose index it uses.

Fix: describe the object with the profile's object type; manufacturer variants belong in \
2000h-5FFFh.",
    fixable: false,
};

const ARRAY_RECORD: CheckInfo = CheckInfo {
    code: "C902",
    slug: "profile-array-record",
    severity: Severity::Warning,
    group: Group::Profiles,
    title: "Standard ARRAYs and RECORDs are not swapped",
    reference: &[65],
    spec: "CiA 301 / CiA 401 object definitions",
    explanation: "\
This check reports a standard object written as an ARRAY where its profile defines a RECORD, or the \
reverse (e.g. 1003h, 1010h or 6000h as RECORD, PDO mapping objects as ARRAY).

On the bus the two look alike (sub-indices with their own types), so the device works. But code \
generators build different data structures from them (CANopenEditor's exporter enforces equal \
types in an ARRAY), and profile-aware tools that compare with the CiA database report the object as \
non-standard.

It is a warning because the difference does not change what a master reads or writes.

Fix: use the object type the profile gives (0x8 ARRAY, 0x9 RECORD).",
    fixable: false,
};

const DATA_TYPE: CheckInfo = CheckInfo {
    code: "C903",
    slug: "profile-data-type",
    severity: Severity::Error,
    group: Group::Profiles,
    title: "Standard objects have the data types their profile defines",
    reference: &[65],
    spec: "CiA 301 / CiA 401 object definitions; CiA 306 V1.3 §4.6.3.2 (DataType)",
    explanation: "\
This check compares the DataType of standard objects and sub-objects (1000h-1FFFh from CiA 301, \
6000h-6FFFh from CiA 401 when 1000h names profile 0191h) with the shipped reference data and \
reports every difference, e.g. a 1017h of UNSIGNED32 or 6401h entries of UNSIGNED16 where CiA 401 \
defines INTEGER16.

A master reads and writes standard objects with the profile's types without looking at the EDS: the \
SDO length then does not match (0607 0010h), and values are decoded with the wrong size or sign. \
Profile-based tools compare the types too.

It is an error: a standard object's data type is fixed by its profile.

Fix: write the profile's DataType, or move a device-specific variant to a manufacturer index.",
    fixable: false,
};

const ACCESS_WRITABLE: CheckInfo = CheckInfo {
    code: "C904",
    slug: "profile-access-widened",
    severity: Severity::Warning,
    group: Group::Profiles,
    title: "Standard objects do not allow accesses their profile does not",
    reference: &[65],
    spec: "CiA 301 / CiA 401 object definitions; CiA 306 V1.3 §4.6.3.2 (AccessType)",
    explanation: "\
This check reports a standard object whose AccessType allows an access its profile does not, \
typically rw where the profile says ro (for example the COB-IDs of the default SDO server 1200h). \
ro and const count as the same, as do rw, rwr and rww (those two only add a PDO direction).

Masters and configuration tools that trust the EDS offer to write the object, while the CiA \
conformance test writes read-only objects and expects a refusal (SDO 03).

It is a warning: the object still works as the profile describes for everyone who follows the \
profile, but the file advertises a behaviour the profile does not have.

Fix: write the profile's access type.",
    fixable: false,
};

const ACCESS_RESTRICTED: CheckInfo = CheckInfo {
    code: "C905",
    slug: "profile-access-restricted",
    severity: Severity::Info,
    group: Group::Profiles,
    title: "Standard objects offer the accesses their profile defines",
    reference: &[65],
    spec: "CiA 301 / CiA 401 object definitions; CiA 306 V1.3 §4.6.3.2 (AccessType)",
    explanation: "\
This check reports a standard object whose AccessType is narrower than its profile's, e.g. ro or \
const where the profile says rw.

A manufacturer may implement a configurable object with a fixed value, and CiA 306 asks the EDS to \
describe the device as it is, so this is legitimate; but a master that configures the object as the \
profile allows gets an SDO abort (0601 0002h), which is worth knowing before commissioning.

It is information only.

Fix: nothing if the restriction is intended; otherwise write the profile's access type.",
    fixable: false,
};

const PDO_MAPPING: CheckInfo = CheckInfo {
    code: "C906",
    slug: "profile-pdo-mapping",
    severity: Severity::Warning,
    group: Group::Profiles,
    title: "PDOMapping of standard objects follows their profile",
    reference: &[65],
    spec: "CiA 401 object definitions; CiA 306 V1.3 §4.6.3.2 (PDOMapping)",
    explanation: "\
Profiles say whether an object may be mapped into PDOs: CiA 401 maps its process data (6000h, \
6200h, 6401h, 6411h, …) in the default PDOs and forbids mapping 6005h, the global interrupt enable. \
This check reports PDOMapping=0 (or missing) where the profile makes the object mappable and \
PDOMapping=1 where it forbids mapping. Objects whose mapping the profile leaves to the device are \
not checked.

A master that sets up the profile's default PDOs, or a tool that offers mappable objects from the \
EDS, then disagrees with the device.

It is a warning: the object still works over SDO.

Fix: write the profile's PDOMapping value.",
    fixable: false,
};

const SUB_MISSING: CheckInfo = CheckInfo {
    code: "C907",
    slug: "profile-sub-missing",
    severity: Severity::Error,
    group: Group::Profiles,
    title: "Standard structured objects have the sub-indices their profile makes mandatory",
    reference: &[65],
    spec: "CiA 301 object definitions (1200h-12FFh, 1400h-15FFh, 1800h-19FFh)",
    explanation: "\
Some sub-indices are part of every instance of a standard object: the COB-IDs (sub 1 and 2) of SDO \
server and client parameters, the COB-ID (sub 1) and transmission type (sub 2) of PDO communication \
parameters. This check reports such a sub-index that the file does not describe. (A missing sub 0 \
is check 36, group F; 1018h sub 1 is C702.)

A master configuring the object writes these sub-indices and gets 0609 0011h (sub-index does not \
exist); the object cannot be used.

It is an error: the object is incomplete.

Fix: describe the missing sub-object.",
    fixable: false,
};

const SUB_UNDEFINED: CheckInfo = CheckInfo {
    code: "C908",
    slug: "profile-sub-undefined",
    severity: Severity::Error,
    group: Group::Profiles,
    title: "Standard structured objects have no sub-indices their profile does not define",
    reference: &[65],
    spec: "CiA 301 / CiA 401 object definitions",
    explanation: "\
This check reports sub-objects of standard objects that the profile does not define, e.g. a sub 3 \
on the default SDO server 1200h, a sub 6 (SYNC start value) on an RPDO, or more than 64 mapping \
entries. Sub-index FFh, the structure descriptor CiA 301 allows on every structured object, is not \
reported.

Tools that handle standard objects by their profile layout ignore or reject the extra entries, \
and a master cannot tell what they mean.

It is an error: the standard object's layout is fixed by its profile.

Fix: remove the sub-object; manufacturer data belongs in 2000h-5FFFh.",
    fixable: false,
};

/// The checks of this group.
pub(crate) const CHECKS: &[CheckInfo] = &[
    OBJECT_TYPE,
    ARRAY_RECORD,
    DATA_TYPE,
    ACCESS_WRITABLE,
    ACCESS_RESTRICTED,
    PDO_MAPPING,
    SUB_MISSING,
    SUB_UNDEFINED,
];

/// Objects group H checks against CiA 301 itself (C701, C702).
const LEFT_TO_GROUP_H: [u16; 3] = [0x1000, 0x1001, 0x1018];

/// Runs the checks of this group.
pub(crate) fn run(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let device_type = live_object(cx, 0x1000)
        .and_then(|o| reading(cx, &o.attributes))
        .and_then(|r| match r.value {
            Int::Literal(v) => u32::try_from(v).ok(),
            Int::NodeRelative(_) => None,
        });
    let profiles = device_type.map_or_else(|| vec![profile::cia301()], profile::for_device_type);
    for profile in profiles {
        for (&index, object) in cx.eds.objects.range(profile.first..=profile.last) {
            if object.origin == Origin::Orphan || LEFT_TO_GROUP_H.contains(&index) {
                continue;
            }
            if let Some(reference) = profile.object(index) {
                compare(
                    &Compare {
                        cx,
                        profile,
                        reference,
                        index,
                    },
                    object,
                    out,
                );
            }
        }
    }
}

/// One standard object being compared with its profile description.
struct Compare<'c, 'a> {
    cx: &'c Context<'a>,
    profile: &'c Profile,
    reference: &'c ProfileObject,
    index: u16,
}

impl Compare<'_, '_> {
    fn finding(&self, info: &CheckInfo, sub: Option<u8>, key: Option<&str>, message: String) -> Finding {
        object_finding(self.cx, info, self.index, sub, key, message)
    }

    /// "CiA 301's Producer heartbeat time".
    fn defined_as(&self) -> String {
        format!("CiA {} {}", self.profile.number, self.reference.name)
    }
}

fn compare(c: &Compare<'_, '_>, object: &Object, out: &mut Vec<Finding>) {
    let file_type = object.object_type();
    let structured = |t: ObjectType| t.has_subs();
    if let (Some(expected), Some(actual)) = (c.reference.object_type, file_type)
        && expected != actual
    {
        let message = format!(
            "{:X}h is written as {actual} (ObjectType {}); {} is {} {expected}",
            c.index,
            written(object.attributes.object_type.as_deref()),
            c.defined_as(),
            if expected == ObjectType::Array { "an" } else { "a" }
        );
        if structured(expected) && structured(actual) {
            out.push(
                c.finding(&ARRAY_RECORD, None, Some("ObjectType"), message)
                    .with_help(format!("write ObjectType=0x{:X}", expected.code())),
            );
        } else {
            out.push(
                c.finding(&OBJECT_TYPE, None, Some("ObjectType"), message)
                    .with_help(format!(
                        "write ObjectType=0x{:X} with the profile's layout",
                        expected.code()
                    )),
            );
            return;
        }
    }
    if object.subs.is_empty() {
        // A VAR where the profile states a layout was reported above; a layout-less description
        // (object type not stated) applies to the VAR itself.
        if !c.reference.has_layout() {
            compare_entry(c, None, &object.attributes, c.reference.spec_for(None), out);
        }
        return;
    }
    if file_type.is_some_and(|t| !structured(t)) {
        return;
    }
    for (&sub, sub_object) in &object.subs {
        if sub_object.origin == Origin::Orphan {
            continue;
        }
        if !c.reference.allows_sub(sub) {
            out.push(
                c.finding(
                    &SUB_UNDEFINED,
                    Some(sub),
                    None,
                    format!(
                        "{} is not defined: {} has no sub-index {sub:X}",
                        entry_name(c.index, Some(sub)),
                        c.defined_as()
                    ),
                )
                .with_help("remove the sub-object; manufacturer data belongs in 2000h-5FFFh"),
            );
            continue;
        }
        if sub == 0xFF {
            continue;
        }
        compare_entry(
            c,
            Some(sub),
            &sub_object.attributes,
            c.reference.spec_for(Some(sub)),
            out,
        );
    }
    for required in c.reference.required_subs() {
        if required == 0
            || object
                .subs
                .get(&required)
                .is_some_and(|s| s.origin != Origin::Orphan)
        {
            continue;
        }
        let name = c.reference.sub(required).map_or("", |s| s.name.as_str());
        out.push(
            c.finding(
                &SUB_MISSING,
                None,
                None,
                format!(
                    "{:X}h has no sub-index {required:X} ({name}), which {} requires",
                    c.index,
                    c.defined_as()
                ),
            )
            .with_help(format!("describe [{:X}sub{required:X}]", c.index)),
        );
    }
}

fn compare_entry(
    c: &Compare<'_, '_>,
    sub: Option<u8>,
    attributes: &Attributes,
    spec: EntrySpec,
    out: &mut Vec<Finding>,
) {
    // The texts are only needed for a finding, and most entries match: build them on demand.
    let name = || entry_name(c.index, sub);
    let what = || match sub.and_then(|s| c.reference.sub(s)) {
        Some(described) if described.first == described.last => {
            format!("{} {}", c.defined_as(), described.name)
        }
        _ => c.defined_as(),
    };
    if let (Some(expected), Some(declared)) = (spec.data_type, attributes.data_type()) {
        let actual = c.cx.eds.resolve_data_type(declared);
        if actual != expected {
            out.push(
                c.finding(
                    &DATA_TYPE,
                    sub,
                    Some("DataType"),
                    format!(
                        "{} DataType {} is {}; {} is {}",
                        name(),
                        written(attributes.data_type.as_deref()),
                        type_name(actual),
                        what(),
                        type_name(expected)
                    ),
                )
                .with_help(format!("write DataType=0x{:04X}", expected.0)),
            );
        }
    }
    if let (Some(expected), Some(actual)) = (spec.access, attributes.access_type()) {
        let (read, write) = (actual.readable(), actual.writable());
        let (may_read, may_write) = (expected.readable(), expected.writable());
        let message = || {
            format!(
                "{} AccessType {}; {} is {}",
                name(),
                written(attributes.access_type.as_deref()),
                what(),
                expected
            )
        };
        if (read && !may_read) || (write && !may_write) {
            out.push(
                c.finding(&ACCESS_WRITABLE, sub, Some("AccessType"), message())
                    .with_help(format!("write AccessType={expected}")),
            );
        } else if (!read && may_read) || (!write && may_write) {
            out.push(
                c.finding(&ACCESS_RESTRICTED, sub, Some("AccessType"), message())
                    .with_help("nothing to do if the device really restricts the access"),
            );
        }
    }
    match (spec.pdo_mapping, attributes.pdo_mapping()) {
        (Some(PdoMapping::No), true) => out.push(
            c.finding(
                &PDO_MAPPING,
                sub,
                Some("PDOMapping"),
                format!(
                    "{} PDOMapping {}; {} is not PDO-mappable",
                    name(),
                    written(attributes.pdo_mapping.as_deref()),
                    what()
                ),
            )
            .with_help("write PDOMapping=0"),
        ),
        (Some(PdoMapping::Yes), false) => out.push(
            c.finding(
                &PDO_MAPPING,
                sub,
                Some("PDOMapping"),
                format!(
                    "{} PDOMapping {}; {} is PDO-mappable",
                    name(),
                    written(attributes.pdo_mapping.as_deref()),
                    what()
                ),
            )
            .with_help("write PDOMapping=1"),
        ),
        _ => {}
    }
}

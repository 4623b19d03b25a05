//! Group J of the check catalogue (`docs/check-catalogue.md`): modular devices (checks 62-64, CiA 306 §6).
//!
//! The loader reads the `M<x>` sections into [`canopener_eds::model::Module`]s and reports module
//! numbers `[SupportedModules]` does not declare (P090, the second half of check 62). It checks
//! nothing inside the module descriptions, and the object checks of the other groups only look at
//! the device's own objects, so everything about the modules' objects is checked here.

use std::collections::{BTreeMap, BTreeSet};

use canopener_eds::model::{Attributes, Module, Properties};
use canopener_eds::section_name::{ModulePart, SectionKind};
use canopener_eds::{ObjectType, Origin, Severity};

use super::numbered_list::check_numbered_list;
use super::reading::{present, strict_int};
use crate::check_info::{CheckInfo, Group};
use crate::context::Context;
use crate::finding::Finding;

const MODULE_INFO_MISSING: CheckInfo = CheckInfo {
    code: "C851",
    slug: "module-info-missing",
    severity: Severity::Error,
    group: Group::Modules,
    title: "every module type 1..NrOfEntries has an [M<x>ModuleInfo] section",
    reference: &[62],
    spec: "CiA 306 V1.3 §6.2",
    explanation: "\
[SupportedModules] NrOfEntries=<n> says the file describes n module types, each in sections \
prefixed M1 ... Mn, starting with [M<x>ModuleInfo] (ProductName, ProductVersion, ProductRevision, \
OrderCode). This check reports each x in 1..n without [M<x>ModuleInfo]. Module sections with x \
outside 1..n are reported as P090.

A configuration tool offers the module types by their ModuleInfo; a type without it cannot be \
selected, and a DCF whose [ConnectedModules] names it cannot be built.

It is an error because CiA 306 §6.2 requires the section for every declared module type.

Fix: add [M<x>ModuleInfo], or lower NrOfEntries to the number of module types described.",
    fixable: false,
};

const SUPPORTED_MODULES_INVALID: CheckInfo = CheckInfo {
    code: "C852",
    slug: "supported-modules-invalid",
    severity: Severity::Error,
    group: Group::Modules,
    title: "[SupportedModules] NrOfEntries is an Unsigned16 number",
    reference: &[62],
    spec: "CiA 306 V1.3 §6.1",
    explanation: "\
[SupportedModules] has one entry, NrOfEntries, the number of module types described (Unsigned16). \
This check reports the entry missing, empty, not a number, or above 65535.

Without the count no reader knows which M<x> sections to read; canopener then treats every module \
section as undeclared (P090).

It is an error because CiA 306 §6.1 defines the entry as the section's content.

Fix: write NrOfEntries=<number of module types>.",
    fixable: false,
};

const MODULE_INFO_INCOMPLETE: CheckInfo = CheckInfo {
    code: "C853",
    slug: "module-info-incomplete",
    severity: Severity::Warning,
    group: Group::Modules,
    title: "[M<x>ModuleInfo] gives ProductName, ProductVersion, ProductRevision and OrderCode",
    reference: &[62],
    spec: "CiA 306 V1.3 §6.2",
    explanation: "\
[M<x>ModuleInfo] identifies a module type by ProductName, ProductVersion, ProductRevision and \
OrderCode; CiA 306 §6.2 marks none of them optional. This check reports each one that is missing \
or empty.

A user picks modules by name and order code when configuring a bus coupler; a module without \
them appears as \"module 3\".

It is a warning, not an error: the entries identify the module for people, and the objects the \
module adds are fully described without them.

Fix: add the missing entries from the module's data sheet.",
    fixable: false,
};

const MODULE_INFO_VALUE_INVALID: CheckInfo = CheckInfo {
    code: "C854",
    slug: "module-info-value-invalid",
    severity: Severity::Error,
    group: Group::Modules,
    title: "ProductVersion and ProductRevision of a module are Unsigned8 numbers",
    reference: &[62],
    spec: "CiA 306 V1.3 §6.2",
    explanation: "\
ProductVersion and ProductRevision of [M<x>ModuleInfo] are Unsigned8 numbers (0-255) in CiA 306 \
notation. This check reports values such as 1.0 or V2 and numbers outside 0-255.

Tools that compare module versions (to pick the right description for a plugged module) read \
them as numbers and fail or compare wrongly.

It is an error because the value does not have the type CiA 306 §6.2 defines.

Fix: write plain numbers, e.g. ProductVersion=1, ProductRevision=0.",
    fixable: false,
};

const MODULE_LIST_MALFORMED: CheckInfo = CheckInfo {
    code: "C855",
    slug: "module-object-list-malformed",
    severity: Severity::Error,
    group: Group::Modules,
    title: "[M<x>FixedObjects] and [M<x>SubExtends] list indices numbered 1..NrOfEntries",
    reference: &[63],
    spec: "CiA 306 V1.3 §6.2",
    explanation: "\
[M<x>FixedObjects] and [M<x>SubExtends] are object lists: NrOfEntries=<n>, then 1=0x6000 ... n=... \
in decimal, each an object index listed once. This check reports a missing or wrong NrOfEntries, \
misnumbered entries, entries that are not an index, and an index listed twice.

A reader walks the entries 1..NrOfEntries and builds the module's objects from them; misnumbered \
or unreadable entries drop objects, so the objects a plugged module adds are incomplete.

It is an error because the list departs from the layout CiA 306 §6.2 defines.

Fix: set NrOfEntries to the number of entries and number them 1, 2, ... with one index each.",
    fixable: false,
};

const MODULE_LIST_MISMATCH: CheckInfo = CheckInfo {
    code: "C856",
    slug: "module-object-list-mismatch",
    severity: Severity::Error,
    group: Group::Modules,
    title: "module object lists and [M<x>Fixed<index>]/[M<x>SubExt<index>] sections match",
    reference: &[63],
    spec: "CiA 306 V1.3 §6.2",
    explanation: "\
Every index of [M<x>FixedObjects] is described in [M<x>Fixed<index>] (with [M<x>Fixed<index>sub<n>] \
for its sub-objects), every index of [M<x>SubExtends] in [M<x>SubExt<index>], and every such \
section is listed. This check reports a listed index without its section, a section that no list \
names, and a sub-object section without its object section.

Readers build the module's objects from the lists: an unlisted section is ignored, a listed index \
without a section leaves a hole the device fills at run time with an object no tool knows.

It is an error because the file contradicts itself about the objects a module adds (CiA 306 §6.2).

Fix: add the missing section or list entry, or delete the stray one.",
    fixable: false,
};

const COUNT_INVALID: CheckInfo = CheckInfo {
    code: "C857",
    slug: "module-count-invalid",
    severity: Severity::Error,
    group: Group::Modules,
    title: "[M<x>SubExt<index>] Count is n or 0;n",
    reference: &[63],
    spec: "CiA 306 V1.3 §6.2",
    explanation: "\
Count says how many sub-indices one module of this type adds to the extended object: Count=<n> \
(Unsigned8), or Count=0;<bits> when several modules share one sub-index, each taking <bits> bits \
of it (0;2: four 2-bit modules per 8-bit sub-index). This check reports a missing or empty Count, \
other forms (2;8, 1.5, two), numbers above 255, and 0;<bits> with zero bits or more bits than the \
extended object's data type has.

The sub-index layout of every plugged module follows from Count; a wrong value shifts every \
later module's objects and the PDO mappings referring to them.

It is an error because the value does not have the form CiA 306 §6.2 defines.

Fix: write Count=<sub-indices per module>, or Count=0;<bits per module> for shared sub-indices.",
    fixable: false,
};

const OBJ_EXTEND_INVALID: CheckInfo = CheckInfo {
    code: "C858",
    slug: "module-obj-extend-invalid",
    severity: Severity::Error,
    group: Group::Modules,
    title: "[M<x>SubExt<index>] ObjExtend is an Unsigned8 sub-index",
    reference: &[63],
    spec: "CiA 306 V1.3 §6.2",
    explanation: "\
ObjExtend is the highest sub-index of the extended object; further modules continue in the next \
index (ObjExtend=128 on 6000h: the 129th 8-bit input module goes to 6001h sub 1). 0 or a missing \
entry means no continuation. This check reports values that are not an Unsigned8 number, and 255, \
which is not an ordinary sub-index.

A wrong value moves where the objects of the later modules are, so the tool's object dictionary \
and the device's disagree.

It is an error because the value does not have the type CiA 306 §6.2 defines.

Fix: write the highest sub-index before continuation (at most 254), or 0.",
    fixable: false,
};

const OBJECT_CONFLICT: CheckInfo = CheckInfo {
    code: "C859",
    slug: "module-object-conflict",
    severity: Severity::Error,
    group: Group::Modules,
    title: "the same object is described alike in every module that adds it",
    reference: &[64],
    spec: "CiA 306 V1.3 §6.2",
    explanation: "\
Several module types may add the same object: a fixed object ([M<x>Fixed<index>]) is created once \
when any module with it is plugged, so all its descriptions must be identical (CiA 306 §6.2); an \
extended object ([M<x>SubExt<index>]) grows with the sub-indices of several module types, which \
therefore must agree on the object's type. This check compares the descriptions: fixed objects in \
every key and sub-object, extended objects in ObjectType, DataType, AccessType, PDOMapping, \
LowLimit, HighLimit, ObjFlags and ObjExtend (Count, names and defaults may differ).

Which description a tool uses then depends on which module happens to be plugged first, and the \
device has only one: mappings and limits are checked against the wrong one.

It is an error because CiA 306 §6.2 requires identical descriptions.

Fix: make the descriptions identical, or give the objects different indices.",
    fixable: false,
};

const OBJECT_KEY_MISSING: CheckInfo = CheckInfo {
    code: "C860",
    slug: "module-object-key-missing",
    severity: Severity::Error,
    group: Group::Modules,
    title: "module object sections give the keys their object type requires",
    reference: &[30, 63],
    spec: "CiA 306 V1.3 §4.6.3.2, §6.2",
    explanation: "\
The objects a module adds are described \"with the normal object keys\" (CiA 306 §6.2), so the \
obligations of §4.6.3.2 apply: every section has ParameterName; a VAR (or DEFTYPE) has DataType \
and AccessType; an ARRAY or RECORD without CompactSubObj has SubNumber, which counts its \
sub-object sections; an [M<x>SubExt<index>] describes the sub-objects it adds like a VAR. This \
check reports missing or empty required keys and a SubNumber that differs from the sub-object \
sections, in module sections (the device's own objects are checked by P073 and P045).

A tool that builds the object dictionary of a plugged module from an incomplete description \
cannot type the objects: values, limits and PDO mappings of the module stay unchecked.

It is an error because a required key is missing (CiA 306 §4.6.3.2).

Fix: add the missing key, or correct SubNumber.",
    fixable: false,
};

/// The checks of this group.
pub(crate) const CHECKS: &[CheckInfo] = &[
    MODULE_INFO_MISSING,
    SUPPORTED_MODULES_INVALID,
    MODULE_INFO_INCOMPLETE,
    MODULE_INFO_VALUE_INVALID,
    MODULE_LIST_MALFORMED,
    MODULE_LIST_MISMATCH,
    COUNT_INVALID,
    OBJ_EXTEND_INVALID,
    OBJECT_CONFLICT,
    OBJECT_KEY_MISSING,
];

/// Keys of an extended object that every module adding sub-indices to it must agree on.
const SHARED_EXT_KEYS: [&str; 8] = [
    "ObjectType",
    "DataType",
    "AccessType",
    "PDOMapping",
    "LowLimit",
    "HighLimit",
    "ObjFlags",
    "ObjExtend",
];

/// Runs the checks of this group.
pub(crate) fn run(cx: &Context<'_>, out: &mut Vec<Finding>) {
    if let Some(supported) = &cx.eds.supported_modules {
        check_supported(cx, out, supported);
    }
    for (&x, module) in &cx.eds.modules {
        let info_kind = SectionKind::Module(x, ModulePart::Info);
        if cx.has_section(info_kind) {
            check_module_info(cx, out, x, module);
        }
        check_lists(cx, out, x, module);
        for (&index, object) in &module.sub_ext {
            if object.origin == Origin::Explicit {
                check_sub_ext(cx, out, x, index, &object.attributes);
            }
        }
        check_object_keys(cx, out, x, module);
    }
    check_conflicts(cx, out);
}

fn check_supported(cx: &Context<'_>, out: &mut Vec<Finding>, supported: &Properties) {
    let section = SectionKind::SupportedModules;
    let text = present(supported.get("NrOfEntries"));
    let count = text.and_then(strict_int).filter(|n| (0..=0xFFFF).contains(n));
    let Some(count) = count else {
        let message = match text {
            Some(t) => format!("[SupportedModules] NrOfEntries `{t}` is not an Unsigned16 number"),
            None => "[SupportedModules] gives no NrOfEntries".to_owned(),
        };
        out.push(
            cx.finding(&SUPPORTED_MODULES_INVALID, section, Some("NrOfEntries"), message)
                .with_help("write NrOfEntries=<number of module types described>"),
        );
        return;
    };
    // `count` is at most 0xFFFF, checked above.
    let missing: Vec<u32> = (1..=u32::try_from(count).unwrap_or(0))
        .filter(|&x| !cx.has_section(SectionKind::Module(x, ModulePart::Info)))
        .collect();
    // A count far above the modules described would give thousands of findings; a few name the
    // problem, one more sums up the rest.
    const SHOWN: usize = 8;
    for &x in missing.iter().take(SHOWN) {
        out.push(
            cx.finding(
                &MODULE_INFO_MISSING,
                section,
                Some("NrOfEntries"),
                format!("[SupportedModules] declares {count} module types, but there is no [M{x}ModuleInfo]"),
            )
            .with_help(format!("add [M{x}ModuleInfo], or lower NrOfEntries")),
        );
    }
    if missing.len() > SHOWN {
        out.push(
            cx.finding(
                &MODULE_INFO_MISSING,
                section,
                Some("NrOfEntries"),
                format!(
                    "{} more of the {count} declared module types have no [M<x>ModuleInfo]",
                    missing.len() - SHOWN
                ),
            )
            .with_help("lower NrOfEntries to the number of module types described"),
        );
    }
}

fn check_module_info(cx: &Context<'_>, out: &mut Vec<Finding>, x: u32, module: &Module) {
    let kind = SectionKind::Module(x, ModulePart::Info);
    let info = &module.info;
    for key in ["ProductName", "ProductVersion", "ProductRevision", "OrderCode"] {
        if present(info.get(key)).is_none() {
            let what = if info.get(key).is_some() {
                "is empty"
            } else {
                "is missing"
            };
            out.push(
                cx.finding(
                    &MODULE_INFO_INCOMPLETE,
                    kind,
                    Some(key),
                    format!("M{x} {key} {what}"),
                )
                .with_help(format!("add {key}=<value> to [M{x}ModuleInfo]")),
            );
        }
    }
    for key in ["ProductVersion", "ProductRevision"] {
        if let Some(text) = present(info.get(key))
            && !strict_int(text).is_some_and(|v| (0..=255).contains(&v))
        {
            out.push(
                cx.finding(
                    &MODULE_INFO_VALUE_INVALID,
                    kind,
                    Some(key),
                    format!("M{x} {key} `{text}` is not an Unsigned8 number (0-255)"),
                )
                .with_help(format!("write a plain number, e.g. {key}=1")),
            );
        }
    }
}

fn check_lists(cx: &Context<'_>, out: &mut Vec<Finding>, x: u32, module: &Module) {
    for (list, part, objects, object_part) in [
        (
            &module.fixed_objects,
            ModulePart::FixedObjects,
            &module.fixed,
            ModulePart::Fixed as fn(u16) -> ModulePart,
        ),
        (
            &module.sub_extends,
            ModulePart::SubExtends,
            &module.sub_ext,
            ModulePart::SubExt,
        ),
    ] {
        let list_kind = SectionKind::Module(x, part);
        let list_name = cx.display_name(list_kind);
        let mut listed = BTreeSet::new();
        if let Some(list) = list {
            check_numbered_list(cx, out, list_kind, list, &MODULE_LIST_MALFORMED);
            for (n, value) in list.numbered() {
                let key = n.to_string();
                let Some(index) = strict_int(value).and_then(|v| u16::try_from(v).ok()) else {
                    out.push(
                        cx.finding(
                            &MODULE_LIST_MALFORMED,
                            list_kind,
                            Some(&key),
                            format!("entry {n}=`{value}` of [{list_name}] is not an object index"),
                        )
                        .with_help("write the index as a number, e.g. 0x6000"),
                    );
                    continue;
                };
                if !listed.insert(index) {
                    out.push(
                        cx.finding(
                            &MODULE_LIST_MALFORMED,
                            list_kind,
                            Some(&key),
                            format!("[{list_name}] lists {index:04X}h more than once"),
                        )
                        .with_help("delete the repeated entry and renumber the list"),
                    );
                    continue;
                }
                if objects.get(&index).is_none_or(|o| o.origin == Origin::Orphan) {
                    let section = cx.display_name(SectionKind::Module(x, object_part(index)));
                    out.push(
                        cx.finding(
                            &MODULE_LIST_MISMATCH,
                            list_kind,
                            Some(&key),
                            format!("[{list_name}] lists {index:04X}h, but there is no [{section}] section"),
                        )
                        .with_help(format!("add [{section}], or remove the entry")),
                    );
                }
            }
        }
        for (&index, object) in objects {
            let kind = SectionKind::Module(x, object_part(index));
            let section = cx.display_name(kind);
            if object.origin == Origin::Orphan {
                for &sub in object.subs.keys() {
                    let sub_part = match part {
                        ModulePart::FixedObjects => ModulePart::FixedSub(index, sub),
                        _ => ModulePart::SubExtSub(index, sub),
                    };
                    let sub_kind = SectionKind::Module(x, sub_part);
                    out.push(
                        cx.finding(
                            &MODULE_LIST_MISMATCH,
                            sub_kind,
                            None,
                            format!(
                                "[{}] has no object section [{section}]",
                                cx.display_name(sub_kind)
                            ),
                        )
                        .with_help(format!("add [{section}], or delete the sub-object section")),
                    );
                }
                continue;
            }
            if !listed.contains(&index) {
                out.push(
                    cx.finding(
                        &MODULE_LIST_MISMATCH,
                        kind,
                        None,
                        format!("[{section}] is not listed in [{list_name}], so readers ignore it"),
                    )
                    .with_help(format!(
                        "list 0x{index:04X} in [{list_name}], or delete the section"
                    )),
                );
            }
        }
    }
}

fn check_sub_ext(cx: &Context<'_>, out: &mut Vec<Finding>, x: u32, index: u16, a: &Attributes) {
    let kind = SectionKind::Module(x, ModulePart::SubExt(index));
    let name = cx.display_name(kind);
    let bits = a.data_type().and_then(|t| cx.eds.resolve_data_type(t).bit_size());
    let problem = match present(a.count.as_deref()) {
        None => Some(format!(
            "[{name}] has {} Count",
            if a.count.is_some() { "an empty" } else { "no" }
        )),
        Some(text) => count_problem(text, bits).map(|why| format!("Count `{text}` {why}")),
    };
    if let Some(message) = problem {
        out.push(
            cx.finding(&COUNT_INVALID, kind, Some("Count"), message)
                .with_help("write Count=<sub-indices per module>, or Count=0;<bits per module>"),
        );
    }
    if let Some(text) = present(a.obj_extend.as_deref())
        && !strict_int(text).is_some_and(|v| (0..=254).contains(&v))
    {
        out.push(
            cx.finding(
                &OBJ_EXTEND_INVALID,
                kind,
                Some("ObjExtend"),
                format!("ObjExtend `{text}` is not a sub-index 0..254"),
            )
            .with_help("write the highest sub-index before continuation, or 0"),
        );
    }
}

/// Why a `Count` value is not `n` or `0;n` (CiA 306 §6.2), or `None` if it is fine. `bits` is the
/// size of the extended object's data type, when known.
fn count_problem(text: &str, bits: Option<u32>) -> Option<String> {
    let Some((head, tail)) = text.split_once(';') else {
        return match strict_int(text) {
            Some(n) if (0..=255).contains(&n) => None,
            Some(_) => Some("is above 255, the range of Unsigned8".to_owned()),
            None => Some("is not a number n or 0;n".to_owned()),
        };
    };
    if strict_int(head.trim()) != Some(0) {
        return Some("is not of the form 0;<bits>: sub-indices are shared only with 0 first".to_owned());
    }
    match strict_int(tail.trim()) {
        Some(0) => Some("shares sub-indices among modules of 0 bits".to_owned()),
        Some(n) if !(1..=255).contains(&n) => Some("gives bits per module outside 1..255".to_owned()),
        Some(n) => match bits {
            Some(size) if n > i128::from(size) => Some(format!(
                "gives {n} bits per module, more than the {size} bits of the object's data type"
            )),
            _ => None,
        },
        None => Some("is not of the form 0;<bits>".to_owned()),
    }
}

fn check_object_keys(cx: &Context<'_>, out: &mut Vec<Finding>, x: u32, module: &Module) {
    for (&index, object) in &module.fixed {
        if object.origin == Origin::Explicit {
            let kind = SectionKind::Module(x, ModulePart::Fixed(index));
            let compact = object.attributes.compact_sub_obj() != 0;
            required_keys(cx, out, kind, &object.attributes, false);
            let has_subs = object.object_type().is_some_and(ObjectType::has_subs);
            if has_subs
                && !compact
                && let Some(declared) = object.attributes.sub_number()
            {
                let described = object.subs.keys().filter(|&&s| s != 0xFF).count() as u64;
                if declared != described {
                    out.push(
                        cx.finding(
                            &OBJECT_KEY_MISSING,
                            kind,
                            Some("SubNumber"),
                            format!("SubNumber={declared} but {described} sub-object section(s) are present"),
                        )
                        .with_help("set SubNumber to the number of sub-object sections"),
                    );
                }
            }
        }
        for (&sub, sub_object) in &object.subs {
            let kind = SectionKind::Module(x, ModulePart::FixedSub(index, sub));
            required_keys(cx, out, kind, &sub_object.attributes, true);
        }
    }
    for (&index, object) in &module.sub_ext {
        if object.origin == Origin::Explicit {
            let kind = SectionKind::Module(x, ModulePart::SubExt(index));
            required_keys(cx, out, kind, &object.attributes, true);
        }
    }
}

/// The key obligations of CiA 306 §4.6.3.2 for one module section; `as_var` for sections that
/// describe single values (sub-objects, sub-extensions).
fn required_keys(cx: &Context<'_>, out: &mut Vec<Finding>, kind: SectionKind, a: &Attributes, as_var: bool) {
    let object_type = a.object_type();
    let keys: &[&str] = match object_type {
        // An unknown ObjectType tells nothing about the other keys; only the name is required.
        None => &["ParameterName"],
        Some(ObjectType::Var | ObjectType::DefType) => &["ParameterName", "DataType", "AccessType"],
        Some(_) if as_var => &["ParameterName", "DataType", "AccessType"],
        Some(ObjectType::Array | ObjectType::Record | ObjectType::DefStruct) if a.compact_sub_obj() != 0 => {
            &["ParameterName", "DataType", "AccessType"]
        }
        Some(ObjectType::Array | ObjectType::Record | ObjectType::DefStruct) => {
            &["ParameterName", "SubNumber"]
        }
        Some(ObjectType::Domain | ObjectType::Null) => &["ParameterName"],
    };
    let name = cx.display_name(kind);
    for &key in keys {
        if present(a.get(key)).is_none() {
            let what = object_type.map_or("section".to_owned(), |t| t.to_string());
            out.push(
                cx.finding(
                    &OBJECT_KEY_MISSING,
                    kind,
                    Some(key),
                    format!("{what} [{name}] has no {key}"),
                )
                .with_help(format!("add {key}=<value>; CiA 306 §4.6.3.2 requires it here")),
            );
        }
    }
}

fn check_conflicts(cx: &Context<'_>, out: &mut Vec<Finding>) {
    // index -> the first module (by number) describing it, for fixed and extended objects.
    let mut fixed_first: BTreeMap<u16, u32> = BTreeMap::new();
    let mut ext_first: BTreeMap<u16, u32> = BTreeMap::new();
    for (&x, module) in &cx.eds.modules {
        for (&index, object) in &module.fixed {
            if object.origin != Origin::Explicit {
                continue;
            }
            let Some(&first) = fixed_first.get(&index) else {
                fixed_first.insert(index, x);
                continue;
            };
            let Some(other) = cx.eds.modules.get(&first).and_then(|m| m.fixed.get(&index)) else {
                continue;
            };
            let here = SectionKind::Module(x, ModulePart::Fixed(index));
            let there = SectionKind::Module(first, ModulePart::Fixed(index));
            for key in Attributes::KEYS {
                compare(
                    cx,
                    out,
                    key,
                    (here, &object.attributes),
                    (there, &other.attributes),
                );
            }
            let subs: BTreeSet<u8> = object.subs.keys().chain(other.subs.keys()).copied().collect();
            for sub in subs {
                let here = SectionKind::Module(x, ModulePart::FixedSub(index, sub));
                let there = SectionKind::Module(first, ModulePart::FixedSub(index, sub));
                match (object.subs.get(&sub), other.subs.get(&sub)) {
                    (Some(a), Some(b)) => {
                        for key in Attributes::KEYS {
                            compare(cx, out, key, (here, &a.attributes), (there, &b.attributes));
                        }
                    }
                    (a, _) => {
                        let (missing_in, present_in) =
                            if a.is_some() { (there, here) } else { (here, there) };
                        let at = if a.is_some() {
                            here
                        } else {
                            SectionKind::Module(x, ModulePart::Fixed(index))
                        };
                        out.push(
                            cx.finding(
                                &OBJECT_CONFLICT,
                                at,
                                None,
                                format!(
                                    "[{}] exists but [{}] does not; the fixed object differs between modules",
                                    cx.display_name(present_in),
                                    cx.display_name(missing_in)
                                ),
                            )
                            .with_help("describe the fixed object identically in every module"),
                        );
                    }
                }
            }
        }
        for (&index, object) in &module.sub_ext {
            if object.origin != Origin::Explicit {
                continue;
            }
            let Some(&first) = ext_first.get(&index) else {
                ext_first.insert(index, x);
                continue;
            };
            let Some(other) = cx.eds.modules.get(&first).and_then(|m| m.sub_ext.get(&index)) else {
                continue;
            };
            let here = SectionKind::Module(x, ModulePart::SubExt(index));
            let there = SectionKind::Module(first, ModulePart::SubExt(index));
            for key in SHARED_EXT_KEYS {
                compare(
                    cx,
                    out,
                    key,
                    (here, &object.attributes),
                    (there, &other.attributes),
                );
            }
        }
    }
}

/// Reports `key` when two module sections describe it differently. Missing keys take their CiA 306
/// defaults (ObjectType VAR, PDOMapping 0, ObjFlags 0); numbers compare by value, AccessType
/// ignoring case.
fn compare(
    cx: &Context<'_>,
    out: &mut Vec<Finding>,
    key: &str,
    (here, a): (SectionKind, &Attributes),
    (there, b): (SectionKind, &Attributes),
) {
    let same = match key {
        "ObjectType" => a.object_type() == b.object_type(),
        "PDOMapping" => a.pdo_mapping() == b.pdo_mapping(),
        "ObjFlags" => a.obj_flags() == b.obj_flags(),
        "AccessType" => match (present(a.get(key)), present(b.get(key))) {
            (Some(x), Some(y)) => x.eq_ignore_ascii_case(y),
            (x, y) => x == y,
        },
        _ => match (present(a.get(key)), present(b.get(key))) {
            (Some(x), Some(y)) => x == y || strict_int(x).is_some_and(|v| strict_int(y) == Some(v)),
            (x, y) => x == y,
        },
    };
    if same {
        return;
    }
    let show = |v: Option<&str>| present(v).map_or("(none)".to_owned(), str::to_owned);
    out.push(
        cx.finding(
            &OBJECT_CONFLICT,
            here,
            Some(key),
            format!(
                "{key} {} in [{}] differs from {} in [{}]",
                show(a.get(key)),
                cx.display_name(here),
                show(b.get(key)),
                cx.display_name(there)
            ),
        )
        .with_help("describe the object identically in every module that adds it"),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn count_is_n_or_zero_semicolon_bits() {
        assert_eq!(count_problem("1", Some(8)), None);
        assert_eq!(count_problem("0x02", None), None);
        assert_eq!(count_problem("0;2", Some(8)), None);
        assert_eq!(count_problem("0; 8", Some(8)), None);
        for bad in ["2;8", "0;0", "0;9", "1.5", "two", "256", "0;x"] {
            assert!(count_problem(bad, Some(8)).is_some(), "{bad}");
        }
    }
    #[test]
    fn a_huge_module_count_gives_a_few_findings_and_a_summary() {
        let loaded = canopener_eds::load(b"[SupportedModules]\nNrOfEntries=0xFFFF\n");
        let cx = Context::new(&loaded, Some("x.eds"));
        let mut out = Vec::new();
        run(&cx, &mut out);
        assert_eq!(out.len(), 9);
        assert!(out.iter().all(|f| f.diagnostic.code == "C851"));
        assert_eq!(
            out.last().map(|f| f.diagnostic.message.as_str()),
            Some("65527 more of the 65535 declared module types have no [M<x>ModuleInfo]")
        );
    }
}

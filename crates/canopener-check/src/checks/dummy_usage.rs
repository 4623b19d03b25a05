//! Group D of the check catalogue (`docs/check-catalogue.md`): `[DummyUsage]` (check 21).
//!
//! The loader keeps `[DummyUsage]` as free entries without looking at them, so everything about
//! the section is checked here: its presence, the `Dummy<index>` keys, their 0/1 values, and
//! whether an enabled index is a type a dummy mapping entry can stand for.

use canopener_eds::section_name::SectionKind;
use canopener_eds::{DataType, Severity};

use super::reading::present;
use crate::check_info::{CheckInfo, Group};
use crate::context::Context;
use crate::finding::Finding;

const KEY_INVALID: CheckInfo = CheckInfo {
    code: "C351",
    slug: "dummy-usage-key-invalid",
    severity: Severity::Error,
    group: Group::DummyUsage,
    title: "[DummyUsage] keys are Dummy followed by a four-digit data type index",
    reference: &[21],
    spec: "CiA 306 V1.3 §4.6.2",
    explanation: "\
Each entry of [DummyUsage] is Dummy<index>=<0|1>, where <index> is the data type index as four \
hexadecimal digits without 0x (Dummy0005 for UNSIGNED8). This check reports keys of another form \
(Dummy5, Dummy0x0005, Dummy00005, Unsigned8) and indices of 1000h and above, which are not data \
types.

Tools look the entries up by their exact name: python canopen asks for Dummy0001 ... Dummy0007, \
lely for Dummy0000 ... Dummy001F. An entry under another name is never found, so the dummy it was \
meant to enable stays disabled.

It is an error because the key does not have the form CiA 306 §4.6.2 defines and no reader \
understands it.

Fix: write the key as Dummy followed by exactly four hex digits, e.g. Dummy0005=1.",
    fixable: false,
};

const VALUE_INVALID: CheckInfo = CheckInfo {
    code: "C352",
    slug: "dummy-usage-value-invalid",
    severity: Severity::Error,
    group: Group::DummyUsage,
    title: "[DummyUsage] values are 0 or 1",
    reference: &[21],
    spec: "CiA 306 V1.3 §4.6.2",
    explanation: "\
A Dummy<index> entry is 1 if the data type may be used as a dummy entry in PDO mappings and 0 if \
not. This check reports any other value, including empty values and 0 or 1 written in another \
notation (0x1, 01).

python canopen reads Dummy0001 ... Dummy0007 with configparser's getint, which aborts the whole \
import on 0x1 or an empty value; CANopenEditor takes everything but 1 as 0.

It is an error because CiA 306 §4.6.2 allows only 0 and 1, and the most used reader fails on \
anything else.

Fix: write Dummy<index>=0 or Dummy<index>=1.",
    fixable: false,
};

const TYPE_NOT_FIXED: CheckInfo = CheckInfo {
    code: "C353",
    slug: "dummy-type-not-fixed-length",
    severity: Severity::Warning,
    group: Group::DummyUsage,
    title: "dummy mapping is enabled only for fixed-length basic types",
    reference: &[21],
    spec: "CiA 306 V1.3 §4.6.2, CiA 301",
    explanation: "\
A dummy mapping entry (index = data type, e.g. 0x00050008) only reserves bits in a PDO, so only \
the length of the type matters. This check reports Dummy<index>=1 for an index that is not a \
basic type of fixed length: VISIBLE_STRING (0009), OCTET_STRING (000A), UNICODE_STRING (000B), \
DOMAIN (000F), the reserved 0000, 000E and 0017, and structures or types the file does not \
define. Types the file defines as DEFTYPE with a fixed-length base type are accepted.

A mapping tool cannot tell how many bits such a dummy occupies; python canopen creates dummy \
objects only for 0001-0007 and lely only for 0000-001F.

It is a warning: CiA 306 does not restrict the indices, but a dummy of variable length cannot be \
mapped.

Fix: set the entry to 0, or use a fixed-length type (0001-0008, 0010-001B) for dummy mapping.",
    fixable: false,
};

const SECTION_MISSING: CheckInfo = CheckInfo {
    code: "C354",
    slug: "dummy-usage-missing",
    severity: Severity::Warning,
    group: Group::DummyUsage,
    title: "the file has a [DummyUsage] section",
    reference: &[21],
    spec: "CiA 306 V1.3 §4.1, §4.6.2",
    explanation: "\
[DummyUsage] says which data types the device accepts as dummy entries in its PDO mappings. CiA \
306 §4.6.2 does not mark the section optional, so by the rule of §4.1 every EDS and DCF has it. \
This check reports a file without it.

Without the section a configuration tool cannot tell whether the device accepts dummy mapping \
entries, which masters use to skip bytes of a PDO they do not need. python canopen, lely and \
CANopenEditor then assume none are supported.

It is a warning, not an error: the absence has only one sensible reading (no dummies), and every \
tool reads the file.

Fix: add [DummyUsage] with Dummy0001 ... Dummy0007, each 1 if the device accepts that type as a \
dummy and 0 if not.",
    fixable: false,
};

/// The checks of this group.
pub(crate) const CHECKS: &[CheckInfo] = &[KEY_INVALID, VALUE_INVALID, TYPE_NOT_FIXED, SECTION_MISSING];

/// Runs the checks of this group.
pub(crate) fn run(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let Some(entries) = &cx.eds.dummy_usage else {
        // An empty document is P029 already; a file without objects says nothing about dummies.
        if !cx.document.sections().is_empty() {
            out.push(
                cx.file_finding(&SECTION_MISSING, "the file has no [DummyUsage] section")
                    .at(Some("DummyUsage"), None)
                    .with_help("add [DummyUsage] with Dummy0001=0 ... Dummy0007=1 as the device supports"),
            );
        }
        return;
    };
    for entry in &entries.0 {
        let key = entry.key.as_str();
        let Some(index) = dummy_index(key) else {
            out.push(
                cx.finding(
                    &KEY_INVALID,
                    SectionKind::DummyUsage,
                    Some(key),
                    format!("`{key}` is not Dummy followed by a four-digit data type index"),
                )
                .with_help("write the key as Dummy<4 hex digits>, e.g. Dummy0005"),
            );
            continue;
        };
        let value = present(Some(entry.value.as_str()));
        match value {
            Some("0") => {}
            Some("1") => check_type(cx, out, key, index),
            _ => out.push(
                cx.finding(
                    &VALUE_INVALID,
                    SectionKind::DummyUsage,
                    Some(key),
                    match value {
                        Some(v) => format!("{key} `{v}` is not 0 or 1"),
                        None => format!("{key} has no value"),
                    },
                )
                .with_help(format!("write {key}=0 or {key}=1")),
            ),
        }
    }
}

/// The data type index of a `Dummy<xxxx>` key (CiA 306 §4.6.2: four hex digits, below 1000h).
fn dummy_index(key: &str) -> Option<u16> {
    let head = key.get(..5)?;
    let digits = key.get(5..)?;
    if !head.eq_ignore_ascii_case("Dummy")
        || digits.len() != 4
        || !digits.bytes().all(|b| b.is_ascii_hexdigit())
    {
        return None;
    }
    u16::from_str_radix(digits, 16).ok().filter(|&i| i < 0x1000)
}

fn check_type(cx: &Context<'_>, out: &mut Vec<Finding>, key: &str, index: u16) {
    let resolved = cx.eds.resolve_data_type(DataType(index));
    if resolved.bit_size().is_some() {
        return;
    }
    let what = match resolved.kind() {
        Some(_) => format!("{resolved}, which has no fixed length"),
        None => "not a type of known length".to_owned(),
    };
    out.push(
        cx.finding(
            &TYPE_NOT_FIXED,
            SectionKind::DummyUsage,
            Some(key),
            format!("{key}=1 enables data type {index:04X}h as a dummy, but it is {what}"),
        )
        .with_help(format!(
            "set {key}=0; dummies stand for fixed-length types 0001-0008, 0010-001B"
        )),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dummy_keys_name_a_data_type() {
        assert_eq!(dummy_index("Dummy0005"), Some(5));
        assert_eq!(dummy_index("dummy001b"), Some(0x1B));
        for bad in [
            "Dummy5",
            "Dummy0x05",
            "Dummy00005",
            "Dummy2000",
            "Unsigned8",
            "Dummy",
        ] {
            assert_eq!(dummy_index(bad), None, "{bad}");
        }
    }
}

//! The descriptive sections: `[DeviceInfo]`, `[DummyUsage]` and a DCF's `[DeviceComissioning]`,
//! which python canopen and CANopenEditor read with narrower rules than CiA 306 §4.2.

use canopener_eds::model::{DeviceInfo, int_of};
use canopener_eds::section_name::SectionKind;

use super::checks::{DCF_BAUDRATE, DUMMY_USAGE_PARTIAL, INFO_BOOLEAN, VENDOR_NUMBER};
use super::tools::{DCFCHK, EDITOR, HOST, PY, at_header, at_value, exact_entry, python_int0, python_int10};
use crate::context::Context;
use crate::finding::Finding;

pub(super) fn run(cx: &Context<'_>, out: &mut Vec<Finding>) {
    dummy_usage(cx, out);
    device_info(cx, out);
    baudrate(cx, out);
}

/// T006: python canopen reads Dummy0001..Dummy0007 with `getint`, case-sensitively, no fallback.
fn dummy_usage(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let Some(section) = cx.section(SectionKind::DummyUsage) else {
        return;
    };
    let others = format!("Lely, {HOST} and {EDITOR} read the file");
    for n in 1..=7 {
        let key = format!("Dummy{n:04}");
        match exact_entry(cx, section, &key) {
            None => {
                let spelt = cx
                    .document
                    .find_entry(section, &key)
                    .and_then(|l| cx.document.entry(l))
                    .map_or_else(String::new, |(k, _)| {
                        format!(" (only `{k}`, and python compares keys case-sensitively)")
                    });
                out.push(at_header(
                    cx,
                    &DUMMY_USAGE_PARTIAL,
                    section,
                    Some(&key),
                    format!(
                        "[DummyUsage] has no `{key}`{spelt}: {PY} reads Dummy0001 to Dummy0007 without a \
                         fallback and crashes (NoOptionError); {others}"
                    ),
                ));
                return;
            }
            Some(line) => {
                let value = cx.document.entry(line).map_or("", |(_, v)| v);
                if !python_int10(value) {
                    let name = cx.document.section_name(section);
                    out.push(at_value(
                        cx,
                        &DUMMY_USAGE_PARTIAL,
                        name,
                        line,
                        format!(
                            "{key} `{value}` is not a plain decimal number: {PY} reads it with getint and \
                             crashes (ValueError); {others}"
                        ),
                    ));
                    return;
                }
            }
        }
    }
}

/// T028 and T036.
fn device_info(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let Some(section) = cx.section(SectionKind::DeviceInfo) else {
        return;
    };
    let name = cx.document.section_name(section);
    let booleans = DeviceInfo::BAUD_RATE_KEYS
        .map(|(_, key)| key)
        .into_iter()
        .chain(DeviceInfo::FLAG_KEYS);
    for key in booleans {
        let Some(line) = cx.document.find_entry(section, key) else {
            continue;
        };
        let Some((written, value)) = cx.document.entry(line) else {
            continue;
        };
        if value != "1" && int_of(value) == Some(1) {
            out.push(at_value(
                cx,
                &INFO_BOOLEAN,
                name,
                line,
                format!(
                    "{written}={value} means 1 (true), but {EDITOR} treats only the literal `1` as true and \
                     silently reads it as false"
                ),
            ));
        }
    }
    // python canopen looks the key up case-sensitively in a section it finds case-sensitively.
    if name != "DeviceInfo" {
        return;
    }
    let Some(line) = exact_entry(cx, section, "VendorNumber") else {
        return;
    };
    let value = cx.document.entry(line).map_or("", |(_, v)| v);
    if python_int0(value) {
        return;
    }
    let dcfchk = if value.is_empty() {
        format!("; {DCFCHK} accepts it")
    } else {
        String::new()
    };
    out.push(at_value(
        cx,
        &VENDOR_NUMBER,
        name,
        line,
        format!(
            "VendorNumber {}: {PY} reads it with int(x, 0), which raises ValueError, so the import \
             crashes{dcfchk}",
            if value.is_empty() {
                "is empty".to_owned()
            } else {
                format!("`{value}`")
            }
        ),
    ));
}

/// T025: python canopen reads a DCF's Baudrate with `getint`, decimal only.
fn baudrate(cx: &Context<'_>, out: &mut Vec<Finding>) {
    for &i in cx.sections_of(SectionKind::Commissioning(
        canopener_eds::model::CommissioningSpelling::DeviceComissioning,
    )) {
        let Some(section) = cx.document.sections().get(i) else {
            continue;
        };
        let name = cx.document.section_name(section);
        if name != "DeviceComissioning" {
            continue;
        }
        let Some(line) = exact_entry(cx, section, "Baudrate") else {
            return;
        };
        let value = cx.document.entry(line).map_or("", |(_, v)| v);
        if !python_int10(value) {
            out.push(at_value(
                cx,
                &DCF_BAUDRATE,
                name,
                line,
                format!(
                    "Baudrate `{value}` is not plain decimal: {PY} reads it with getint and fails \
                     (ValueError)"
                ),
            ));
        }
        return;
    }
}

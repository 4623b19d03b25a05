//! Group C of the check catalogue (`docs/check-catalogue.md`): `[DeviceInfo]` and its cross-checks (checks
//! 13-20).
//!
//! The loader reads `[DeviceInfo]` into the model and reports reserved keys (P034), unknown keys
//! (P033) and a missing section (P029), which is all of check 20. The checks here look at the
//! values: mandatory keys, numbers and Booleans, the identity against 1018h, the bit rates,
//! `Granularity`, the PDO counts against the PDO objects, and `[DynamicChannels]`.

use canopener_eds::model::DeviceInfo;
use canopener_eds::section_name::SectionKind;
use canopener_eds::value::mentions_nodeid;
use canopener_eds::{Origin, Severity};

use super::reading::{lenient_int, present, strict_int};
use crate::check_info::{CheckInfo, Group};
use crate::context::Context;
use crate::finding::Finding;

const KEY_MISSING: CheckInfo = CheckInfo {
    code: "C301",
    slug: "device-info-key-missing",
    severity: Severity::Error,
    group: Group::DeviceInfo,
    title: "[DeviceInfo] gives every capability and identity entry CiA 306 defines",
    reference: &[13],
    spec: "CiA 306 V1.3 §4.1, §4.5",
    explanation: "\
[DeviceInfo] tells a configuration tool what the device is and what it can do: VendorNumber, \
ProductNumber, RevisionNumber, the eight BaudRate_* entries, SimpleBootUpMaster, \
SimpleBootUpSlave, Granularity, DynamicChannelsSupported, GroupMessaging, NrOfRXPDO, NrOfTXPDO \
and LSS_Supported. CiA 306 §4.5 marks none of them optional, and an empty value counts as missing \
(§4.2). This check reports each one that is missing or empty; CompactPDO and \
CANopenSafetySupported are optional and not reported. The names VendorName, ProductName and \
OrderCode are checked by C302; a missing [DeviceInfo] is P029.

A missing entry leaves the tool guessing: without NrOfRXPDO/NrOfTXPDO the PDO count and CompactPDO \
expansion are unknown, without Granularity the mapping rules, without BaudRate_* the bit rates a \
network may use. An empty number is worse: python canopen reads VendorNumber= with int('', 0) and \
fails to import the file (CANopenEditor's DS301 profile writes exactly that).

It is an error because the file departs from §4.5 in a way that loses facts about the device.

Fix: add the entry; a capability the device lacks is written as 0 (e.g. LSS_Supported=0).",
    fixable: false,
};

const NAME_MISSING: CheckInfo = CheckInfo {
    code: "C302",
    slug: "device-info-name-missing",
    severity: Severity::Warning,
    group: Group::DeviceInfo,
    title: "[DeviceInfo] names the vendor, the product and its order code",
    reference: &[13],
    spec: "CiA 306 V1.3 §4.1, §4.5",
    explanation: "\
VendorName, ProductName and OrderCode are the human-readable identity of the device. CiA 306 §4.5 \
makes them mandatory like every entry not stated otherwise (§4.1). This check reports each one \
that is missing or empty.

Configuration tools list devices by vendor and product name; without them a user picks a device \
from a list of file names, and the order code is what purchasing needs.

It is a warning, not an error: the texts are descriptive. Every tool reads the device without \
them and nothing about the object dictionary is lost.

Fix: add VendorName=, ProductName= and OrderCode= with the values from the data sheet.",
    fixable: false,
};

const NUMBER_INVALID: CheckInfo = CheckInfo {
    code: "C303",
    slug: "device-info-number-invalid",
    severity: Severity::Error,
    group: Group::DeviceInfo,
    title: "[DeviceInfo] numbers are CiA 306 integers of their type",
    reference: &[13, 17, 18],
    spec: "CiA 306 V1.3 §4.2, §4.5",
    explanation: "\
VendorNumber, ProductNumber and RevisionNumber are Unsigned32; Granularity, \
DynamicChannelsSupported and CompactPDO are Unsigned8; NrOfRXPDO and NrOfTXPDO are Unsigned16. \
Each is written in CiA 306 notation: decimal, 0x hexadecimal or octal with a leading 0. This \
check reports values that are not such a number (a product name in ProductNumber, FEh, 1.0) or \
that do not fit the type.

python canopen reads these entries with int(value, 0) and aborts the whole import on anything \
else; tools that match a device to its EDS by vendor and product number cannot match it.

It is an error because the value does not have the type CiA 306 §4.5 defines.

Fix: write the number, e.g. VendorNumber=0x00000ABC.",
    fixable: false,
};

const IDENTITY_MISMATCH: CheckInfo = CheckInfo {
    code: "C304",
    slug: "identity-mismatch",
    severity: Severity::Error,
    group: Group::DeviceInfo,
    title: "VendorNumber, ProductNumber and RevisionNumber equal 1018h sub 1-3",
    reference: &[14],
    spec: "CiA 306 V1.3 §4.5, CiA 301",
    explanation: "\
[DeviceInfo] repeats the identity the device reports in object 1018h: VendorNumber is the \
vendor-ID (1018sub1), ProductNumber the product code (1018sub2), RevisionNumber the revision \
number (1018sub3). This check compares each with the DefaultValue of the sub-object, as numbers \
(0x00000ABC equals 2748); values with $NODEID and sub-objects without a DefaultValue are skipped.

A CANopen manager checks a device during boot-up by reading 1018h and comparing it with the \
configuration (CiA 302); a configuration tool picks the EDS by the [DeviceInfo] numbers. When the \
two disagree the device is rejected, or the wrong EDS is used. lely's dcfchk warns about it.

It is an error because the file contradicts itself about which device it describes.

Fix: correct whichever of the two is wrong; usually [DeviceInfo] was not updated for a new \
revision.",
    fixable: false,
};

const BOOLEAN_INVALID: CheckInfo = CheckInfo {
    code: "C305",
    slug: "device-info-boolean-invalid",
    severity: Severity::Error,
    group: Group::DeviceInfo,
    title: "[DeviceInfo] Booleans are 0 or 1",
    reference: &[15],
    spec: "CiA 306 V1.3 §4.5",
    explanation: "\
The BaudRate_* entries, SimpleBootUpMaster, SimpleBootUpSlave, GroupMessaging, LSS_Supported and \
CANopenSafetySupported are Booleans: 0 = not supported, 1 = supported. This check reports any \
other value as an error (yes, true, 2), and 0 or 1 written in another notation (0x1, 01) as a \
warning.

CANopenEditor treats everything but the literal 1 as false, so BaudRate_500=0x1 silently becomes \
\"500 kbit/s not supported\"; python canopen aborts the import on yes or true.

An unreadable value is an error because the capability is unknown; 0x1 is a warning because it \
means 1 under the integer notation of CiA 306 §4.2 but one of the common tools misreads it.

Fix: write 0 or 1.",
    fixable: false,
};

const NO_BAUD_RATE: CheckInfo = CheckInfo {
    code: "C306",
    slug: "no-baud-rate",
    severity: Severity::Warning,
    group: Group::DeviceInfo,
    title: "at least one BaudRate_* entry is 1",
    reference: &[16],
    spec: "CiA 306 V1.3 §4.5",
    explanation: "\
The BaudRate_10 ... BaudRate_1000 entries say which bit rates the device supports. This check \
reports a [DeviceInfo] in which none of them is 1 (missing entries are C301).

A configuration tool offers only supported bit rates; with none, the device cannot be placed in \
any network, and a DCF for it fails C804.

It is a warning: CiA 306 does not state that one rate must be set, but a CANopen device without a \
bit rate cannot communicate, so the entries are almost certainly wrong.

Fix: set BaudRate_<kbit/s>=1 for every bit rate the device supports.",
    fixable: false,
};

const GRANULARITY_RANGE: CheckInfo = CheckInfo {
    code: "C307",
    slug: "granularity-out-of-range",
    severity: Severity::Error,
    group: Group::DeviceInfo,
    title: "Granularity is 0..64",
    reference: &[17],
    spec: "CiA 306 V1.3 §4.5",
    explanation: "\
Granularity is the PDO mapping granularity in bits: 0 means the mapping cannot be changed, 1-64 \
the step in which mapped lengths may be chosen (most devices 8). This check reports values above \
64.

A classic CAN PDO has 64 bits; a larger granularity cannot be met by any mapping, so a tool that \
builds mappings from it fails or produces invalid ones. EdsDcfNet rejects such files.

It is an error because CiA 306 §4.5 defines the range 0-64.

Fix: write the real granularity, normally Granularity=8 (byte-wise mapping) or 1 (bit-wise).",
    fixable: false,
};

const GRANULARITY_ZERO_WRITABLE: CheckInfo = CheckInfo {
    code: "C308",
    slug: "granularity-zero-writable-mapping",
    severity: Severity::Warning,
    group: Group::DeviceInfo,
    title: "Granularity=0 (fixed mapping) goes with read-only mapping objects",
    reference: &[17],
    spec: "CiA 306 V1.3 §4.5, CiA 301",
    explanation: "\
Granularity=0 says the PDO mappings cannot be changed. This check reports such a file in which a \
PDO mapping object (1600h-17FFh, 1A00h-1BFFh) has a writable sub-object (rw, wo, rwr or rww).

The two statements contradict each other: a configuration tool that trusts Granularity never \
offers mapping changes, while one that trusts the access types writes new mappings the device \
may refuse.

It is a warning: either statement may be the wrong one, and a device may accept a write of the \
same mapping it already has.

Fix: give the real granularity (usually 8), or make the mapping sub-objects ro/const.",
    fixable: false,
};

const PDO_COUNT_MISMATCH: CheckInfo = CheckInfo {
    code: "C309",
    slug: "pdo-count-mismatch",
    severity: Severity::Error,
    group: Group::DeviceInfo,
    title: "NrOfRXPDO and NrOfTXPDO match the PDO communication objects",
    reference: &[18],
    spec: "CiA 306 V1.3 §4.5, §4.6.3.4.1",
    explanation: "\
NrOfRXPDO and NrOfTXPDO give the number of receive and transmit PDOs, each described by a \
communication object 1400h-15FFh (RPDO) or 1800h-19FFh (TPDO). This check reports a count that \
differs from the number of communication objects described. With CompactPDO (CiA 306 \
§4.6.3.4.1) PDOs may be left out, the count then includes the implied ones: only a count below \
the number described is reported. A count above 512 is always reported, CANopen has 512 PDOs of \
each kind.

Tools present these counts as the device's PDO capacity (python canopen's device information, \
CANopenEditor), and CompactPDO readers (lely, canopener) create exactly NrOf... minus the \
described PDOs. A wrong count makes PDOs disappear or appear from nowhere.

It is an error because the file contradicts itself about the device's PDOs.

Fix: set NrOfRXPDO/NrOfTXPDO to the number of 1400h/1800h objects, or describe the missing PDOs.",
    fixable: false,
};

const DYNAMIC_CHANNELS_MISSING: CheckInfo = CheckInfo {
    code: "C310",
    slug: "dynamic-channels-missing",
    severity: Severity::Error,
    group: Group::DeviceInfo,
    title: "DynamicChannelsSupported other than 0 comes with a [DynamicChannels] section",
    reference: &[19],
    spec: "CiA 306 V1.3 §4.5, §4.6.3.4.3",
    explanation: "\
DynamicChannelsSupported other than 0 says the device creates network variables dynamically \
(CiA 302-4, CiA 405); CiA 306 §4.5 then requires the [DynamicChannels] section that describes \
their segments (NrOfSeg, Type<n>, Dir<n>, Range<n>, PPOffset<n>). This check reports the entry \
without the section.

A programming tool (IEC 61131-3 per CiA 405) needs the segments to place variables; without them \
the announced capability cannot be used.

It is an error because the section the entry makes mandatory is missing.

Fix: add [DynamicChannels], or set DynamicChannelsSupported=0.",
    fixable: false,
};

const DYNAMIC_CHANNELS_UNANNOUNCED: CheckInfo = CheckInfo {
    code: "C311",
    slug: "dynamic-channels-unannounced",
    severity: Severity::Warning,
    group: Group::DeviceInfo,
    title: "a [DynamicChannels] section goes with DynamicChannelsSupported other than 0",
    reference: &[19],
    spec: "CiA 306 V1.3 §4.5",
    explanation: "\
[DynamicChannels] describes dynamically created network variables; [DeviceInfo] announces them \
with DynamicChannelsSupported other than 0. This check reports the section when the entry is 0 or \
missing.

Tools look at DynamicChannelsSupported first, so the section is ignored and the dynamic channels \
are not offered.

It is a warning: the section does no harm, but one of the two statements is wrong.

Fix: set DynamicChannelsSupported to the number of dynamic channels (at least 1), or delete the \
section.",
    fixable: false,
};

/// The checks of this group.
pub(crate) const CHECKS: &[CheckInfo] = &[
    KEY_MISSING,
    NAME_MISSING,
    NUMBER_INVALID,
    IDENTITY_MISMATCH,
    BOOLEAN_INVALID,
    NO_BAUD_RATE,
    GRANULARITY_RANGE,
    GRANULARITY_ZERO_WRITABLE,
    PDO_COUNT_MISMATCH,
    DYNAMIC_CHANNELS_MISSING,
    DYNAMIC_CHANNELS_UNANNOUNCED,
];

const CAPABILITY_KEYS: [&str; 9] = [
    "VendorNumber",
    "ProductNumber",
    "RevisionNumber",
    "SimpleBootUpMaster",
    "SimpleBootUpSlave",
    "Granularity",
    "DynamicChannelsSupported",
    "GroupMessaging",
    "NrOfRXPDO",
];

const MORE_CAPABILITY_KEYS: [&str; 2] = ["NrOfTXPDO", "LSS_Supported"];

const NAME_KEYS: [&str; 3] = ["VendorName", "ProductName", "OrderCode"];

/// Runs the checks of this group.
pub(crate) fn run(cx: &Context<'_>, out: &mut Vec<Finding>) {
    // A missing [DeviceInfo] is P029; its keys are not reported again one by one.
    if !cx.has_section(SectionKind::DeviceInfo) {
        return;
    }
    let info = &cx.eds.device_info;
    let capability = CAPABILITY_KEYS
        .iter()
        .chain(&MORE_CAPABILITY_KEYS)
        .copied()
        .chain(DeviceInfo::BAUD_RATE_KEYS.map(|(_, key)| key));
    for key in capability {
        if present(info.get(key)).is_none() {
            out.push(missing(cx, &KEY_MISSING, info, key));
        }
    }
    for key in NAME_KEYS {
        if present(info.get(key)).is_none() {
            out.push(missing(cx, &NAME_MISSING, info, key));
        }
    }
    for (key, bits) in DeviceInfo::NUMBER_KEYS {
        let Some(text) = present(info.get(key)) else {
            continue;
        };
        let max = (1i128 << bits) - 1;
        if !strict_int(text).is_some_and(|v| (0..=max).contains(&v)) {
            out.push(
                cx.finding(
                    &NUMBER_INVALID,
                    SectionKind::DeviceInfo,
                    Some(key),
                    format!("{key} `{text}` is not an Unsigned{bits} number"),
                )
                .with_help(format!("write a number in 0..={max}, decimal or 0x hexadecimal")),
            );
        }
    }
    check_booleans(cx, out, info);
    check_identity(cx, out, info);
    check_granularity(cx, out, info);
    check_pdo_counts(cx, out, info);
    check_dynamic_channels(cx, out, info);
}

fn missing(cx: &Context<'_>, check: &CheckInfo, info: &DeviceInfo, key: &str) -> Finding {
    let what = if info.get(key).is_some() {
        "is empty"
    } else {
        "is missing"
    };
    cx.finding(check, SectionKind::DeviceInfo, Some(key), format!("{key} {what}"))
        .with_help(format!("add {key}=<value> to [DeviceInfo]"))
}

fn check_booleans(cx: &Context<'_>, out: &mut Vec<Finding>, info: &DeviceInfo) {
    let keys = DeviceInfo::FLAG_KEYS
        .into_iter()
        .chain(DeviceInfo::BAUD_RATE_KEYS.map(|(_, key)| key));
    for key in keys {
        let Some(text) = present(info.get(key)) else {
            continue;
        };
        if text == "0" || text == "1" {
            continue;
        }
        let finding = match strict_int(text) {
            Some(v @ (0 | 1)) => cx
                .finding(
                    &BOOLEAN_INVALID,
                    SectionKind::DeviceInfo,
                    Some(key),
                    format!("{key} `{text}` means {v}, but CANopenEditor reads only a literal 1 as true"),
                )
                .with_severity(Severity::Warning),
            _ => cx.finding(
                &BOOLEAN_INVALID,
                SectionKind::DeviceInfo,
                Some(key),
                format!("{key} `{text}` is not a Boolean (0 or 1)"),
            ),
        };
        out.push(finding.with_help(format!("write {key}=0 or {key}=1")));
    }
    let rates: Vec<Option<i128>> = DeviceInfo::BAUD_RATE_KEYS
        .iter()
        .filter_map(|&(_, key)| present(info.get(key)))
        .map(strict_int)
        .collect();
    if !rates.is_empty() && !rates.contains(&Some(1)) {
        out.push(
            cx.finding(
                &NO_BAUD_RATE,
                SectionKind::DeviceInfo,
                None,
                "no BaudRate_* entry is 1, so the device supports no bit rate",
            )
            .with_help("set BaudRate_<kbit/s>=1 for each supported bit rate"),
        );
    }
}

fn check_identity(cx: &Context<'_>, out: &mut Vec<Finding>, info: &DeviceInfo) {
    let Some(identity) = cx.eds.objects.get(&0x1018) else {
        return;
    };
    for (key, sub) in [("VendorNumber", 1u8), ("ProductNumber", 2), ("RevisionNumber", 3)] {
        let Some(text) = present(info.get(key)) else {
            continue;
        };
        let Some(number) = strict_int(text) else { continue };
        // Only a written sub-object says what the device reports; a CompactSubObj copy does not.
        let Some(sub_object) = identity.subs.get(&sub).filter(|s| s.origin == Origin::Explicit) else {
            continue;
        };
        let Some(default) = present(sub_object.attributes.default_value.as_deref()) else {
            continue;
        };
        if mentions_nodeid(default) || mentions_nodeid(text) {
            continue;
        }
        let Some(expected) = lenient_int(default) else {
            continue;
        };
        if number != expected {
            let sub_name = cx.display_name(SectionKind::Sub(0x1018, sub));
            out.push(
                cx.finding(
                    &IDENTITY_MISMATCH,
                    SectionKind::DeviceInfo,
                    Some(key),
                    format!("{key} {text} differs from {sub_name} DefaultValue {default}"),
                )
                .with_help(format!(
                    "make {key} and [{sub_name}] DefaultValue the same number"
                )),
            );
        }
    }
}

fn check_granularity(cx: &Context<'_>, out: &mut Vec<Finding>, info: &DeviceInfo) {
    let Some(text) = present(info.granularity.as_deref()) else {
        return;
    };
    match strict_int(text) {
        Some(g) if (65..=255).contains(&g) => out.push(
            cx.finding(
                &GRANULARITY_RANGE,
                SectionKind::DeviceInfo,
                Some("Granularity"),
                format!("Granularity {text} is above 64 bits, the size of a CAN PDO"),
            )
            .with_help("write the real granularity, normally Granularity=8"),
        ),
        Some(0) => {
            let writable = cx
                .eds
                .objects
                .range(0x1600..=0x17FF)
                .chain(cx.eds.objects.range(0x1A00..=0x1BFF))
                .filter(|(_, o)| o.origin == Origin::Explicit)
                .find_map(|(&index, o)| {
                    o.subs
                        .iter()
                        .find(|(_, s)| {
                            s.origin == Origin::Explicit
                                && s.attributes.access_type().is_some_and(|a| a.writable())
                        })
                        .map(|(&sub, s)| (index, sub, s.attributes.access_type.clone().unwrap_or_default()))
                });
            if let Some((index, sub, access)) = writable {
                let name = cx.display_name(SectionKind::Sub(index, sub));
                out.push(
                    cx.finding(
                        &GRANULARITY_ZERO_WRITABLE,
                        SectionKind::DeviceInfo,
                        Some("Granularity"),
                        format!(
                            "Granularity 0 says the PDO mapping is fixed, but [{name}] is AccessType={access}"
                        ),
                    )
                    .with_help("give the real granularity (usually 8), or make the mapping sub-objects ro"),
                );
            }
        }
        _ => {}
    }
}

fn check_pdo_counts(cx: &Context<'_>, out: &mut Vec<Finding>, info: &DeviceInfo) {
    let compact = present(info.compact_pdo.as_deref())
        .and_then(strict_int)
        .is_some_and(|mask| mask != 0);
    for (key, text, range, what) in [
        (
            "NrOfRXPDO",
            &info.nr_of_rx_pdo,
            0x1400u16..=0x15FF,
            "RPDO communication objects (1400h-15FFh)",
        ),
        (
            "NrOfTXPDO",
            &info.nr_of_tx_pdo,
            0x1800..=0x19FF,
            "TPDO communication objects (1800h-19FFh)",
        ),
    ] {
        let Some(text) = present(text.as_deref()) else {
            continue;
        };
        let Some(declared) = strict_int(text) else {
            continue;
        };
        let described = cx
            .eds
            .objects
            .range(range)
            .filter(|(_, o)| o.origin == Origin::Explicit)
            .count() as i128;
        let message = if declared > 512 {
            format!("{key} {text} is above 512, the number of PDOs CANopen has")
        } else if compact && described > declared {
            format!("{key} {text} is below the {described} {what} described; CompactPDO can only add PDOs")
        } else if !compact && described != declared {
            format!("{key} {text} but the file describes {described} {what}")
        } else {
            continue;
        };
        out.push(
            cx.finding(&PDO_COUNT_MISMATCH, SectionKind::DeviceInfo, Some(key), message)
                .with_help(format!("set {key}={described}, or describe the missing PDOs")),
        );
    }
}

fn check_dynamic_channels(cx: &Context<'_>, out: &mut Vec<Finding>, info: &DeviceInfo) {
    let text = present(info.dynamic_channels_supported.as_deref());
    let announced = text.and_then(strict_int).is_some_and(|n| n != 0);
    let described = cx.has_section(SectionKind::DynamicChannels);
    if announced && !described {
        out.push(
            cx.finding(
                &DYNAMIC_CHANNELS_MISSING,
                SectionKind::DeviceInfo,
                Some("DynamicChannelsSupported"),
                format!(
                    "DynamicChannelsSupported={} but the file has no [DynamicChannels] section",
                    text.unwrap_or_default()
                ),
            )
            .with_help("add [DynamicChannels] describing the segments, or set DynamicChannelsSupported=0"),
        );
    } else if described && !announced && text.is_none_or(|t| strict_int(t).is_some()) {
        out.push(
            cx.finding(
                &DYNAMIC_CHANNELS_UNANNOUNCED,
                SectionKind::DynamicChannels,
                None,
                format!(
                    "[DynamicChannels] is present but DynamicChannelsSupported is {}",
                    text.map_or("missing".to_owned(), |t| format!("`{t}`"))
                ),
            )
            .with_help("set DynamicChannelsSupported to the number of channels, or delete the section"),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn findings(text: &str) -> Vec<Finding> {
        let loaded = canopener_eds::load(text.as_bytes());
        let cx = Context::new(&loaded, Some("x.eds"));
        let mut out = Vec::new();
        run(&cx, &mut out);
        out
    }

    const DEVICE: &str = "[DeviceInfo]\nVendorName=v\nVendorNumber=0x00000ABC\nProductName=p\n\
        ProductNumber=1\nRevisionNumber=1\nOrderCode=o\nBaudRate_10=0\nBaudRate_20=0\nBaudRate_50=0\n\
        BaudRate_125=0\nBaudRate_250=1\nBaudRate_500=0\nBaudRate_800=0\nBaudRate_1000=0\n\
        SimpleBootUpMaster=0\nSimpleBootUpSlave=1\nGranularity=8\nDynamicChannelsSupported=0\n\
        GroupMessaging=0\nNrOfRXPDO=0\nNrOfTXPDO=0\nLSS_Supported=0\n\
        [1018]\nParameterName=Identity\nObjectType=0x9\nSubNumber=2\n\
        [1018sub0]\nParameterName=n\nDataType=0x0005\nAccessType=ro\nDefaultValue=1\n\
        [1018sub1]\nParameterName=Vendor-ID\nDataType=0x0007\nAccessType=ro\nDefaultValue=2748\n";

    #[test]
    fn a_complete_device_info_is_clean_and_numbers_compare_by_value() {
        assert_eq!(findings(DEVICE), []);
    }

    #[test]
    fn booleans_in_another_notation_are_warnings_and_garbage_is_an_error() {
        let found = findings(&DEVICE.replace("BaudRate_250=1", "BaudRate_250=0x1"));
        let severities: Vec<(&str, Severity)> = found
            .iter()
            .map(|f| (f.diagnostic.code.as_str(), f.diagnostic.severity))
            .collect();
        // 0x1 still reads as 1, so the device supports a bit rate and C306 stays quiet.
        assert_eq!(severities, [("C305", Severity::Warning)]);
        let found = findings(&DEVICE.replace("GroupMessaging=0", "GroupMessaging=no"));
        assert_eq!(found.len(), 1);
        assert_eq!(
            (found[0].diagnostic.code.as_str(), found[0].diagnostic.severity),
            ("C305", Severity::Error)
        );
        assert_eq!(found[0].diagnostic.key.as_deref(), Some("GroupMessaging"));
    }

    #[test]
    fn identity_mismatch_names_both_values_as_written() {
        let found = findings(&DEVICE.replace("DefaultValue=2748", "DefaultValue=0x00000ABD"));
        assert_eq!(found.len(), 1);
        assert_eq!(
            found[0].diagnostic.message,
            "VendorNumber 0x00000ABC differs from 1018sub1 DefaultValue 0x00000ABD"
        );
        let found = findings(&DEVICE.replace("DefaultValue=2748", "DefaultValue=$NODEID+0xABC"));
        assert_eq!(found, []);
    }
}

//! Group I of the check catalogue (`docs/check-catalogue.md`): what a DCF adds (checks 59-61).
//!
//! The loader reads `[DeviceComissioning]` in both spellings (a second one is P020, which covers the
//! "both spellings" part of check 59) and reports a spelling other than CiA 306's (P031); it does
//! not look at the values. The checks here do: node-ID and bit rate, the LSS serial number against
//! 1018h sub 4, `UploadFile`/`DownloadFile`, and `[ConnectedModules]`.

use canopener_eds::model::{Attributes, CommissioningSpelling, DeviceCommissioning, DeviceInfo};
use canopener_eds::section_name::SectionKind;
use canopener_eds::value::mentions_nodeid;
use canopener_eds::{AccessType, ObjectType, Origin, Severity, TypeKind};

use super::numbered_list::check_numbered_list;
use super::reading::{is_dcf_file, present, strict_int};
use crate::check_info::{CheckInfo, Group};
use crate::context::{Context, object_kind};
use crate::finding::Finding;

const COMMISSIONING_MISSING: CheckInfo = CheckInfo {
    code: "C801",
    slug: "dcf-commissioning-missing",
    severity: Severity::Error,
    group: Group::Dcf,
    title: "a DCF has a [DeviceComissioning] section",
    reference: &[59],
    spec: "CiA 306 V1.3 §5.3.1",
    explanation: "\
A DCF describes one configured device, and [DeviceComissioning] (CiA's spelling, one m) says \
which: its node-ID, bit rate, network number and names. This check reports a DCF without the \
section. A file counts as a DCF when its name ends in .dcf, or when it names no .eds file and \
[FileInfo] gives LastEDS.

Without the section the node-ID and bit rate come from nowhere: $NODEID formulas cannot be \
resolved (lely's dcfchk stops with \"$NODEID not defined\"), and a configuration tool cannot tell \
which node the DCF configures.

It is an error because CiA 306 §5.3.1 makes the section part of every DCF.

Fix: add [DeviceComissioning] with at least NodeID=<1..127> and Baudrate=<kbit/s>; if the file is \
meant as an EDS, name it .eds and drop LastEDS.",
    fixable: false,
};

const NODE_ID_INVALID: CheckInfo = CheckInfo {
    code: "C802",
    slug: "dcf-node-id-invalid",
    severity: Severity::Error,
    group: Group::Dcf,
    title: "[DeviceComissioning] NodeID is 1..127",
    reference: &[59],
    spec: "CiA 306 V1.3 §5.3.1, CiA 301",
    explanation: "\
NodeID is the node-ID the DCF configures, an Unsigned8 in 1..127. This check reports a missing or \
empty NodeID, a value that is not a number, and numbers outside 1..127 (0, or lely's 0xFF for a \
node that LSS has not configured yet).

Every $NODEID formula in the DCF is resolved with this value; python canopen aborts the import \
without it, and with a node-ID outside 1..127 the formulas yield COB-IDs no node can have.

It is an error because CiA 301 defines node-IDs 1..127 and CiA 306 §5.3.1 requires the entry.

Fix: write the node-ID of the device, e.g. NodeID=5.",
    fixable: false,
};

const BAUDRATE_INVALID: CheckInfo = CheckInfo {
    code: "C803",
    slug: "dcf-baudrate-invalid",
    severity: Severity::Error,
    group: Group::Dcf,
    title: "[DeviceComissioning] Baudrate is a CiA 301 bit rate in kbit/s",
    reference: &[59],
    spec: "CiA 306 V1.3 §5.3.1, CiA 301",
    explanation: "\
Baudrate is the bit rate the device is configured for, in kbit/s: one of 10, 20, 50, 125, 250, \
500, 800 or 1000. This check reports a missing or empty Baudrate, a value that is not a number, \
and rates CiA 301 does not define (0, 100, 500000).

python canopen reads the entry with int() and aborts without it; a tool that downloads the DCF \
cannot set up the device, and a value in bit/s instead of kbit/s (500000) is a common mistake.

It is an error because CiA 306 §5.3.1 requires the entry and its value must be one of the bit \
rates [DeviceInfo] can declare. Baudrate=0 is reported as a warning: configuration tools \
(CANopenEditor, maxon's EPOS4 tools, EdsDcfNet) write it for \"not configured yet\", and readers \
take it as that instead of misreading it.

Fix: write the bit rate in kbit/s, e.g. Baudrate=250.",
    fixable: false,
};

const BAUDRATE_UNSUPPORTED: CheckInfo = CheckInfo {
    code: "C804",
    slug: "dcf-baudrate-unsupported",
    severity: Severity::Error,
    group: Group::Dcf,
    title: "the DCF bit rate is one [DeviceInfo] declares as supported",
    reference: &[59],
    spec: "CiA 306 V1.3 §4.5, §5.3.1",
    explanation: "\
The Baudrate of [DeviceComissioning] must be a bit rate the device supports, i.e. the matching \
BaudRate_<kbit/s> entry of [DeviceInfo] is 1. This check reports a configured bit rate whose \
entry is 0 (a missing entry is reported as C301).

A device configured for a bit rate it cannot run never joins the network; the configuration tool \
that wrote the DCF ignored the device's own description.

It is an error because the DCF contradicts the device description it is based on.

Fix: choose a supported bit rate, or correct BaudRate_<kbit/s> if the device does support it.",
    fixable: false,
};

const LSS_SERIAL_MISMATCH: CheckInfo = CheckInfo {
    code: "C805",
    slug: "dcf-lss-serial-mismatch",
    severity: Severity::Warning,
    group: Group::Dcf,
    title: "LSS_SerialNumber equals 1018h sub 4",
    reference: &[59],
    spec: "CiA 306 V1.3 §5.3.1, CiA 301",
    explanation: "\
LSS_SerialNumber names the physical device the DCF belongs to, by the serial number it reports \
in 1018h sub 4. This check compares the two as numbers: with the ParameterValue of 1018sub4 when \
the DCF gives one, otherwise with its DefaultValue. LSS_SerialNumber=0 (not set) and values with \
$NODEID are not compared.

An LSS master identifies the device by vendor-ID, product code, revision and serial number before \
it assigns the node-ID; with two different serial numbers it configures the wrong device or none. \
lely's dcfchk warns about the mismatch.

It is a warning: the EDS default of 1018sub4 is often a placeholder (0), and which of the two \
values is right can only be told at the device.

Fix: write the device's serial number in both places.",
    fixable: false,
};

const COMMISSIONING_VALUE_INVALID: CheckInfo = CheckInfo {
    code: "C806",
    slug: "dcf-commissioning-value-invalid",
    severity: Severity::Error,
    group: Group::Dcf,
    title: "NetNumber, LSS_SerialNumber and CANopenManager have their CiA 306 types",
    reference: &[59],
    spec: "CiA 306 V1.3 §5.3.1",
    explanation: "\
NetNumber and LSS_SerialNumber are Unsigned32 numbers, CANopenManager is a Boolean (1: this \
device is the CANopen manager). This check reports values that are not of these types; empty \
values are accepted, CiA 306 gives these entries defaults.

Network tools tell networks apart by NetNumber and find the manager by CANopenManager; an \
unreadable value leaves them guessing which network the device is on and who manages it.

It is an error because the value does not have the type CiA 306 §5.3.1 defines.

Fix: write a number (NetNumber=1, LSS_SerialNumber=0x12345678) or 0/1 for CANopenManager.",
    fixable: false,
};

const FILE_NOT_DOMAIN: CheckInfo = CheckInfo {
    code: "C807",
    slug: "upload-download-file-not-domain",
    severity: Severity::Error,
    group: Group::Dcf,
    title: "UploadFile and DownloadFile appear only on DOMAIN objects",
    reference: &[60],
    spec: "CiA 306 V1.3 §5.3.2",
    explanation: "\
UploadFile and DownloadFile let a DCF keep the value of a DOMAIN (ObjectType=0x2, or DataType \
0x000F) in a separate file: UploadFile receives the data read from the device, DownloadFile \
provides the data written to it. This check reports either key on any other object or \
sub-object.

CiA 306 defines the files for DOMAIN values only; what a tool does with them on another object \
is undefined, so the value meant for the device may never be written (the object's \
ParameterValue, if any, is what tools download).

It is an error because CiA 306 §5.3.2 defines the keys for DOMAIN objects only.

Fix: give the value as ParameterValue, or make the object a DOMAIN if it really is one.",
    fixable: false,
};

const FILE_ACCESS: CheckInfo = CheckInfo {
    code: "C808",
    slug: "upload-download-file-access",
    severity: Severity::Warning,
    group: Group::Dcf,
    title: "UploadFile goes with a readable DOMAIN, DownloadFile with a writable one",
    reference: &[60],
    spec: "CiA 306 V1.3 §5.3.2",
    explanation: "\
UploadFile stores data read from the device, so the DOMAIN must be readable (not wo); \
DownloadFile provides data written to the device, so it must be writable (wo, rw, rwr or rww, not \
ro or const). A DOMAIN without AccessType is rw (CiA 306 §4.6.3.2). This check reports the \
combinations that cannot work.

A tool following the DCF tries an SDO transfer the device refuses (SDO abort 0601 0001h or \
0601 0002h). lely's DCF loader is stricter still: it expects ro/const with UploadFile and wo with \
DownloadFile and changes the access type otherwise.

It is a warning: the file is well-formed, but the transfer it asks for fails.

Fix: use the key that matches the access type, or correct the AccessType.",
    fixable: false,
};

const CONNECTED_MODULE_OUT_OF_RANGE: CheckInfo = CheckInfo {
    code: "C809",
    slug: "connected-module-out-of-range",
    severity: Severity::Error,
    group: Group::Dcf,
    title: "[ConnectedModules] entries name module types 1..SupportedModules NrOfEntries",
    reference: &[61],
    spec: "CiA 306 V1.3 §6.3",
    explanation: "\
[ConnectedModules] lists the modules plugged into a modular device in physical order: \
1=<module type>, 2=<module type>, ... where each module type is a number 1..NrOfEntries of \
[SupportedModules]. This check reports entries that are not such a number, including every entry \
when the file has no [SupportedModules].

The device's object dictionary is built from the M<x> descriptions of the connected modules; an \
entry naming no described module type leaves the tool without the objects that module adds, so \
its PDO mappings and parameters cannot be configured.

It is an error because the entry refers to a module type the file does not describe.

Fix: use the number of the module's [M<x>ModuleInfo], or add the missing module description.",
    fixable: false,
};

const CONNECTED_MODULES_MALFORMED: CheckInfo = CheckInfo {
    code: "C810",
    slug: "connected-modules-malformed",
    severity: Severity::Error,
    group: Group::Dcf,
    title: "[ConnectedModules] gives NrOfEntries and entries numbered 1..NrOfEntries",
    reference: &[61],
    spec: "CiA 306 V1.3 §6.3",
    explanation: "\
[ConnectedModules] starts with NrOfEntries=<n>, followed by the entries 1=... to n=... in \
decimal. This check reports a missing or unreadable NrOfEntries, a count that differs from the \
number of entries, entry numbers outside 1..n or missing in between, and keys that are neither.

The position of an entry is the slot of the module; a reader that walks 1..NrOfEntries skips \
misnumbered entries, so the modules it assumes are not the ones plugged in.

It is an error because the section departs from the layout CiA 306 §6.3 defines.

Fix: set NrOfEntries to the number of modules and number the entries 1, 2, ... in slot order.",
    fixable: false,
};

const CONNECTED_MODULES_IN_EDS: CheckInfo = CheckInfo {
    code: "C811",
    slug: "connected-modules-in-eds",
    severity: Severity::Warning,
    group: Group::Dcf,
    title: "[ConnectedModules] appears only in DCFs",
    reference: &[61],
    spec: "CiA 306 V1.3 §6.3",
    explanation: "\
[ConnectedModules] records which modules are plugged into one configured device, so it belongs in \
a DCF; an EDS describes the device type with the modules it supports ([SupportedModules]). This \
check reports the section in a file that is not a DCF (not named .dcf, no [DeviceComissioning]).

A configuration tool that loads the EDS as a template takes the module list of one installation \
for the device's default, and every DCF made from it starts with modules that may not be there.

It is a warning: the section is well-defined, only in the wrong kind of file.

Fix: delete [ConnectedModules] from the EDS, or turn the file into a DCF.",
    fixable: false,
};

/// The checks of this group.
pub(crate) const CHECKS: &[CheckInfo] = &[
    COMMISSIONING_MISSING,
    NODE_ID_INVALID,
    BAUDRATE_INVALID,
    BAUDRATE_UNSUPPORTED,
    LSS_SERIAL_MISMATCH,
    COMMISSIONING_VALUE_INVALID,
    FILE_NOT_DOMAIN,
    FILE_ACCESS,
    CONNECTED_MODULE_OUT_OF_RANGE,
    CONNECTED_MODULES_MALFORMED,
    CONNECTED_MODULES_IN_EDS,
];

/// The section kind of `[DeviceComissioning]` (either spelling; the context treats both as one).
const COMMISSIONING: SectionKind = SectionKind::Commissioning(CommissioningSpelling::DeviceComissioning);

/// Runs the checks of this group.
pub(crate) fn run(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let dcf = is_dcf_file(cx);
    match &cx.eds.commissioning {
        Some(commissioning) => check_commissioning(cx, out, commissioning),
        None if dcf => out.push(
            cx.file_finding(
                &COMMISSIONING_MISSING,
                "this DCF has no [DeviceComissioning] section",
            )
            .at(Some("DeviceComissioning"), None)
            .with_help("add [DeviceComissioning] with NodeID=<1..127> and Baudrate=<kbit/s>"),
        ),
        None => {}
    }
    check_files(cx, out);
    check_connected_modules(cx, out, dcf);
}

fn check_commissioning(cx: &Context<'_>, out: &mut Vec<Finding>, c: &DeviceCommissioning) {
    let node_id = present(c.node_id.as_deref());
    let problem = match node_id.map(|t| (t, strict_int(t))) {
        None => Some(
            if c.node_id.is_some() {
                "NodeID is empty"
            } else {
                "NodeID is missing"
            }
            .to_owned(),
        ),
        Some((text, None)) => Some(format!("NodeID `{text}` is not a number")),
        Some((text, Some(id))) if !(1..=127).contains(&id) => {
            Some(format!("NodeID {text} is outside the node-IDs 1..127"))
        }
        Some(_) => None,
    };
    if let Some(message) = problem {
        out.push(
            cx.finding(&NODE_ID_INVALID, COMMISSIONING, Some("NodeID"), message)
                .with_help("write the node-ID of the device in 1..127, e.g. NodeID=5"),
        );
    }
    let baudrate = present(c.baudrate.as_deref());
    let rate = baudrate.and_then(strict_int);
    let standard = DeviceInfo::BAUD_RATE_KEYS
        .iter()
        .find(|&&(kbit, _)| rate == Some(i128::from(kbit)));
    let problem = match (baudrate, rate) {
        (None, _) => Some(
            if c.baudrate.is_some() {
                "Baudrate is empty"
            } else {
                "Baudrate is missing"
            }
            .to_owned(),
        ),
        (Some(text), None) => Some(format!("Baudrate `{text}` is not a number")),
        (Some(text), Some(0)) => Some(format!("Baudrate {text}: the bit rate is not configured")),
        (Some(text), Some(_)) if standard.is_none() => {
            Some(format!("Baudrate {text} is not a CiA 301 bit rate in kbit/s"))
        }
        _ => None,
    };
    if let Some(message) = problem {
        let finding = cx
            .finding(&BAUDRATE_INVALID, COMMISSIONING, Some("Baudrate"), message)
            .with_help("write one of 10, 20, 50, 125, 250, 500, 800, 1000 (kbit/s)");
        // 0 is what configuration tools write for "not configured yet" (CANopenEditor, maxon's tools,
        // EdsDcfNet); readers take it as such rather than misreading it.
        out.push(if rate == Some(0) {
            finding.with_severity(Severity::Warning)
        } else {
            finding
        });
    }
    if let Some(&(kbit, key)) = standard
        && present(cx.eds.device_info.get(key)).and_then(strict_int) == Some(0)
    {
        out.push(
            cx.finding(
                &BAUDRATE_UNSUPPORTED,
                COMMISSIONING,
                Some("Baudrate"),
                format!(
                    "Baudrate {kbit} kbit/s, but [DeviceInfo] {key}=0 says the device does not support it"
                ),
            )
            .with_help("choose a bit rate the device supports, or correct [DeviceInfo]"),
        );
    }
    for (key, text, boolean) in [
        ("NetNumber", &c.net_number, false),
        ("LSS_SerialNumber", &c.lss_serial_number, false),
        ("CANopenManager", &c.canopen_manager, true),
    ] {
        let Some(text) = present(text.as_deref()) else {
            continue;
        };
        let valid = if boolean {
            text == "0" || text == "1"
        } else {
            strict_int(text).is_some_and(|v| (0..=i128::from(u32::MAX)).contains(&v))
        };
        if !valid {
            let want = if boolean { "0 or 1" } else { "an Unsigned32 number" };
            out.push(
                cx.finding(
                    &COMMISSIONING_VALUE_INVALID,
                    COMMISSIONING,
                    Some(key),
                    format!("{key} `{text}` is not {want}"),
                )
                .with_help(format!("write {key} as {want}")),
            );
        }
    }
    check_lss_serial(cx, out, c);
}

fn check_lss_serial(cx: &Context<'_>, out: &mut Vec<Finding>, c: &DeviceCommissioning) {
    let Some(text) = present(c.lss_serial_number.as_deref()) else {
        return;
    };
    let Some(serial) = strict_int(text).filter(|&s| s != 0) else {
        return;
    };
    let Some(sub) = cx
        .eds
        .objects
        .get(&0x1018)
        .and_then(|o| o.subs.get(&4))
        .filter(|s| s.origin == Origin::Explicit)
    else {
        return;
    };
    let a = &sub.attributes;
    let (key, value) = match present(a.parameter_value.as_deref()) {
        Some(v) => ("ParameterValue", v),
        None => match present(a.default_value.as_deref()) {
            Some(v) => ("DefaultValue", v),
            None => return,
        },
    };
    if mentions_nodeid(value) {
        return;
    }
    if strict_int(value).is_some_and(|v| v != serial) {
        let name = cx.display_name(SectionKind::Sub(0x1018, 4));
        out.push(
            cx.finding(
                &LSS_SERIAL_MISMATCH,
                COMMISSIONING,
                Some("LSS_SerialNumber"),
                format!("LSS_SerialNumber {text} differs from {name} {key} {value}"),
            )
            .with_help(format!(
                "write the device's serial number in LSS_SerialNumber and [{name}]"
            )),
        );
    }
}

fn check_files(cx: &Context<'_>, out: &mut Vec<Finding>) {
    for (&index, object) in &cx.eds.objects {
        if object.origin != Origin::Explicit {
            continue;
        }
        check_file_keys(cx, out, index, None, &object.attributes);
        for (&sub, sub_object) in &object.subs {
            if sub_object.origin == Origin::Explicit {
                check_file_keys(cx, out, index, Some(sub), &sub_object.attributes);
            }
        }
    }
}

fn check_file_keys(cx: &Context<'_>, out: &mut Vec<Finding>, index: u16, sub: Option<u8>, a: &Attributes) {
    let upload = present(a.upload_file.as_deref());
    let download = present(a.download_file.as_deref());
    if upload.is_none() && download.is_none() {
        return;
    }
    let kind = object_kind(index, sub);
    let domain = a.object_type() == Some(ObjectType::Domain)
        || a.data_type()
            .is_some_and(|t| cx.eds.resolve_data_type(t).kind() == Some(TypeKind::Domain));
    for (key, file) in [("UploadFile", upload), ("DownloadFile", download)] {
        let Some(file) = file else { continue };
        if !domain {
            out.push(
                cx.finding(
                    &FILE_NOT_DOMAIN,
                    kind,
                    Some(key),
                    format!(
                        "{key}={file} on [{}], which is not a DOMAIN",
                        cx.display_name(kind)
                    ),
                )
                .with_help("give the value as ParameterValue, or make the object a DOMAIN"),
            );
            continue;
        }
        // A DOMAIN without AccessType is rw (CiA 306 §4.6.3.2); an unknown token is P072.
        let access = match present(a.access_type.as_deref()) {
            None => AccessType::Rw,
            Some(_) => match a.access_type() {
                Some(access) => access,
                None => continue,
            },
        };
        let (fits, need) = if key == "UploadFile" {
            (access.readable(), "a readable DOMAIN (ro, rw, rwr, rww, const)")
        } else {
            (access.writable(), "a writable DOMAIN (wo, rw, rwr, rww)")
        };
        if !fits {
            out.push(
                cx.finding(
                    &FILE_ACCESS,
                    kind,
                    Some(key),
                    format!(
                        "{key} needs {need}, but [{}] is AccessType={access}",
                        cx.display_name(kind)
                    ),
                )
                .with_help(if key == "UploadFile" {
                    "use DownloadFile for data written to the device, or correct the AccessType"
                } else {
                    "use UploadFile for data read from the device, or correct the AccessType"
                }),
            );
        }
    }
}

fn check_connected_modules(cx: &Context<'_>, out: &mut Vec<Finding>, dcf: bool) {
    let Some(connected) = &cx.eds.connected_modules else {
        return;
    };
    let section = SectionKind::ConnectedModules;
    if !dcf {
        out.push(
            cx.finding(
                &CONNECTED_MODULES_IN_EDS,
                section,
                None,
                "[ConnectedModules] records one installation and belongs in a DCF, not in an EDS",
            )
            .with_help("delete [ConnectedModules] from the EDS, or make the file a DCF"),
        );
    }
    check_numbered_list(cx, out, section, connected, &CONNECTED_MODULES_MALFORMED);
    let supported = cx
        .eds
        .supported_modules
        .as_ref()
        .and_then(|p| present(p.get("NrOfEntries")))
        .and_then(strict_int);
    for (n, value) in connected.numbered() {
        let module = strict_int(value);
        if module.is_some_and(|m| m >= 1 && supported.is_some_and(|s| m <= s)) {
            continue;
        }
        let declared = match supported {
            Some(s) => format!("[SupportedModules] describes module types 1..{s}"),
            None => "the file has no readable [SupportedModules] NrOfEntries".to_owned(),
        };
        let key = n.to_string();
        out.push(
            cx.finding(
                &CONNECTED_MODULE_OUT_OF_RANGE,
                section,
                Some(&key),
                format!("slot {n} holds module type `{value}`, but {declared}"),
            )
            .with_help("use the number x of the module's [M<x>ModuleInfo]"),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn findings(text: &str, name: Option<&str>) -> Vec<Finding> {
        let loaded = canopener_eds::load(text.as_bytes());
        let cx = Context::new(&loaded, name);
        let mut out = Vec::new();
        run(&cx, &mut out);
        out
    }

    fn codes(found: &[Finding]) -> Vec<(&str, Severity)> {
        found
            .iter()
            .map(|f| (f.diagnostic.code.as_str(), f.diagnostic.severity))
            .collect()
    }

    const DCF: &str = "[FileInfo]\nLastEDS=x.eds\n[DeviceInfo]\nBaudRate_250=1\nBaudRate_500=0\n\
        [DeviceComissioning]\nNodeID=5\nBaudrate=250\n";

    #[test]
    fn what_counts_as_a_dcf() {
        let plain = "[FileInfo]\nLastEDS=x.eds\n";
        for (name, dcf) in [
            (Some("a.dcf"), true),
            (Some("A.DCF"), true),
            (Some("a.eds"), false),
            (Some("a.txt"), true),
            (None, true),
        ] {
            let loaded = canopener_eds::load(plain.as_bytes());
            assert_eq!(is_dcf_file(&Context::new(&loaded, name)), dcf, "{name:?}");
        }
        let loaded = canopener_eds::load(b"[FileInfo]\nLastEDS=\n");
        assert!(!is_dcf_file(&Context::new(&loaded, None)));
        assert!(is_dcf_file(&Context::new(&loaded, Some("a.dcf"))));
    }

    #[test]
    fn a_commissioned_dcf_is_clean() {
        assert_eq!(findings(DCF, Some("x.dcf")), []);
        assert_eq!(findings(DCF, Some("x.eds")), []);
    }

    #[test]
    fn an_unconfigured_bit_rate_is_a_warning_an_unknown_one_an_error() {
        let found = findings(&DCF.replace("Baudrate=250", "Baudrate=0"), Some("x.dcf"));
        assert_eq!(codes(&found), [("C803", Severity::Warning)]);
        let found = findings(&DCF.replace("Baudrate=250", "Baudrate=500000"), Some("x.dcf"));
        assert_eq!(codes(&found), [("C803", Severity::Error)]);
        let found = findings(&DCF.replace("Baudrate=250", "Baudrate=500"), Some("x.dcf"));
        assert_eq!(codes(&found), [("C804", Severity::Error)]);
    }

    #[test]
    fn a_dcf_by_name_needs_commissioning_an_eds_does_not() {
        let text = DCF.replace("[DeviceComissioning]\nNodeID=5\nBaudrate=250\n", "");
        assert_eq!(
            codes(&findings(&text, Some("x.dcf"))),
            [("C801", Severity::Error)]
        );
        assert_eq!(findings(&text, Some("x.eds")), []);
    }
}

//! A fixed report used by every format test: several files, every severity, a rule-pack check, a
//! code without a description, a file that could not be read, and file content that needs escaping.

use std::collections::BTreeMap;

use canopener_check::{CheckDescription, Finding, Group};
use canopener_eds::{Diagnostic, Severity, Span};
use canopener_report::{FileReport, Report};

pub(crate) fn check(
    code: &str,
    slug: &str,
    severity: Severity,
    group: Group,
    title: &str,
    explanation: &str,
) -> CheckDescription {
    CheckDescription {
        code: code.into(),
        slug: slug.into(),
        severity,
        group,
        title: title.into(),
        spec: if group == Group::Rules {
            String::new()
        } else {
            "CiA 306 V1.3 §4.6".into()
        },
        explanation: explanation.into(),
        fixable: false,
        tags: vec![group.name().into()],
        origin: if group == Group::Rules {
            "rules/naming.toml".into()
        } else {
            "built-in".into()
        },
    }
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn finding(
    code: &str,
    severity: Severity,
    message: &str,
    (line, column, len): (u32, u32, u32),
    section: Option<&str>,
    key: Option<&str>,
    help: Option<&str>,
    fixable: bool,
) -> Finding {
    Finding {
        diagnostic: Diagnostic {
            code: code.into(),
            severity,
            message: message.into(),
            span: Span::new(line, column, len),
            section: section.map(Into::into),
            key: key.map(Into::into),
            help: help.map(Into::into),
        },
        fixable,
    }
}

fn source(lines: &[(u32, &str)]) -> BTreeMap<u32, String> {
    lines.iter().map(|(n, t)| (*n, (*t).to_owned())).collect()
}

pub(crate) fn checks() -> Vec<CheckDescription> {
    let mut fixable = check(
        "C412",
        "supported-objects-count",
        Severity::Warning,
        Group::ObjectLists,
        "SupportedObjects matches the listed entries",
        "SupportedObjects must equal the number of entries of the object list.\n\nTools that trust the \
         count skip objects or read past the list.\n\nFix: run canopener eds fix.",
    );
    fixable.fixable = true;
    vec![
        check(
            "C301",
            "vendor-number-mismatch",
            Severity::Error,
            Group::DeviceInfo,
            "VendorNumber agrees with 1018sub1",
            "VendorNumber in [DeviceInfo] must equal the DefaultValue of 1018sub1.\n\nA master that \
             identifies devices by 1018h rejects the device when the two differ.\n\nFix: make both the \
             same.",
        ),
        fixable,
        check(
            "C520",
            "parameter-name-present",
            Severity::Error,
            Group::Objects,
            "Every object has a ParameterName",
            "ParameterName is mandatory for every object and sub-object (CiA 306 V1.3 §4.6.3).",
        ),
        check(
            "C801",
            "dcf-node-id",
            Severity::Error,
            Group::Dcf,
            "A DCF sets NodeID in [DeviceComissioning]",
            "A DCF describes one configured device, so it must name its node-ID.",
        ),
        check(
            "C999",
            "never-found",
            Severity::Warning,
            Group::Values,
            "A check that finds nothing here",
            "Shown as a passing test case.",
        ),
        check(
            "T004",
            "python-canopen-angle-brackets",
            Severity::Info,
            Group::Portability,
            "Names python canopen shows differently <rpm> & \"quoted\"",
            "python canopen 2.4 keeps the name as written.\n\nNothing breaks; shown for information.",
        ),
        check(
            "naming.no-blanks",
            "no-blanks",
            Severity::Warning,
            Group::Rules,
            "ParameterName has no blanks",
            "Project rule: names are used as identifiers by the code generator.",
        ),
    ]
}

pub(crate) fn report() -> Report {
    let motor = FileReport {
        path: "eds/motor drive.eds".into(),
        findings: vec![
            finding(
                "C301",
                Severity::Error,
                "VendorNumber 0x123 differs from 1018sub1 DefaultValue 0x124",
                (12, 14, 5),
                Some("DeviceInfo"),
                Some("VendorNumber"),
                Some("set VendorNumber to 0x124, or correct 1018sub1"),
                false,
            ),
            finding(
                "P020",
                Severity::Warning,
                "inline comment after the value",
                (20, 16, 13),
                Some("1000"),
                Some("DataType"),
                None,
                false,
            ),
            finding(
                "C412",
                Severity::Warning,
                "SupportedObjects=3 but 4 entries are listed",
                (30, 1, 0),
                Some("OptionalObjects"),
                None,
                Some("set SupportedObjects=4"),
                true,
            ),
            finding(
                "T004",
                Severity::Info,
                "ParameterName \"Speed <rpm> & 'max'\" has markup characters",
                (45, 15, 21),
                Some("2000"),
                Some("ParameterName"),
                None,
                false,
            ),
            finding(
                "naming.no-blanks",
                Severity::Warning,
                "ParameterName \"Drehzahl Größe\" contains a blank",
                (60, 15, 14),
                Some("2001"),
                Some("ParameterName"),
                Some("write DrehzahlGröße"),
                false,
            ),
            finding(
                "C520",
                Severity::Error,
                "ParameterName is missing in [2001sub1] \u{1}]]>",
                (64, 1, 9),
                Some("2001sub1"),
                None,
                None,
                false,
            ),
        ],
        source: source(&[
            (12, "VendorNumber=0x123"),
            (20, "DataType=0x0007\t; UNSIGNED32"),
            (30, "[OptionalObjects]"),
            (45, "ParameterName=Speed <rpm> & 'max'"),
            (60, "ParameterName=Drehzahl Größe"),
            (64, "[2001sub1]"),
        ]),
        problem: None,
    };
    let dcf = FileReport {
        path: "dcf\\node5.dcf".into(),
        findings: vec![
            finding(
                "C801",
                Severity::Error,
                "[DeviceComissioning] has no NodeID",
                (1, 1, 0),
                None,
                None,
                Some("add NodeID=5 to [DeviceComissioning]"),
                false,
            ),
            finding(
                "T004",
                Severity::Info,
                "ParameterName \"A&B\" has markup characters",
                (9, 15, 3),
                Some("2000"),
                Some("ParameterName"),
                None,
                false,
            ),
        ],
        source: source(&[(1, "[FileInfo]"), (9, "ParameterName=A&B")]),
        problem: None,
    };
    Report {
        tool_version: "0.1.0".into(),
        checks: checks(),
        files: vec![
            motor,
            FileReport {
                path: "eds/clean.eds".into(),
                ..FileReport::default()
            },
            dcf,
            FileReport::unreadable("eds/missing.eds", "No such file or directory (os error 2)"),
        ],
    }
}

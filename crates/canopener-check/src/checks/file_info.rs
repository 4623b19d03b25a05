//! Group B of the check catalogue (`docs/check-catalogue.md`): `[FileInfo]` (checks 8-12).
//!
//! The loader only reads `[FileInfo]` (unknown keys are P033, a missing section P029); the checks
//! here look at the values: mandatory keys, `FileVersion`/`FileRevision` as Unsigned8, `EDSVersion`,
//! the CiA 306 date and time notation, `FileName` against the real name, and `LastEDS` in DCFs.
//!
//! The string length limits of check 11 (Description 243, CreatedBy 245, ModifiedBy 244 characters)
//! are exactly the 255-character line limit of CiA 306 §4.2 minus the key and `=`, so the line
//! length check of group A (check 1) already reports them; they are not repeated here.

use canopener_eds::Severity;
use canopener_eds::section_name::SectionKind;

use super::reading::{is_dcf_file, present, strict_int};
use crate::check_info::{CheckInfo, Group};
use crate::context::Context;
use crate::finding::Finding;

const KEY_MISSING: CheckInfo = CheckInfo {
    code: "C201",
    slug: "file-info-key-missing",
    severity: Severity::Warning,
    group: Group::FileInfo,
    title: "[FileInfo] has every key CiA 306 defines, each with a value",
    reference: &[8],
    spec: "CiA 306 V1.3 §4.1, §4.4",
    explanation: "\
[FileInfo] describes the file itself: FileName, FileVersion, FileRevision, Description, \
CreationTime, CreationDate, CreatedBy, ModificationTime, ModificationDate and ModifiedBy. CiA 306 \
§4.4 marks none of them optional, and §4.1 makes every entry mandatory unless stated otherwise; \
an empty value counts as missing (§4.2). This check reports each such key that is missing or \
empty. EDSVersion has a stated default (3.0) and is checked by C203/C204; a missing [FileInfo] \
section is P029.

Without these entries nobody can tell which revision of a device description is at hand or who \
changed it last; the CiA conformance tool lists them as missing entries.

It is a warning, not an error: the entries are metadata. python canopen only stores them, \
CANopenEditor shows them, and the object dictionary the file describes is complete without them. \
A certification review will still ask for them.

Fix: add the key with a value, e.g. FileVersion=1, CreationDate=05-15-2026, CreatedBy=<name>.",
    fixable: false,
};

const VERSION_NOT_UNSIGNED8: CheckInfo = CheckInfo {
    code: "C202",
    slug: "file-version-not-unsigned8",
    severity: Severity::Error,
    group: Group::FileInfo,
    title: "FileVersion and FileRevision are Unsigned8 integers",
    reference: &[8],
    spec: "CiA 306 V1.3 §4.4",
    explanation: "\
FileVersion and FileRevision are Unsigned8 numbers (0-255) in CiA 306 notation: decimal, 0x \
hexadecimal or octal with a leading 0. This check reports values such as 1.0, 1.0.0, V1.0 or -, \
and numbers outside 0-255.

Tools that read the version as a number choke on these forms: CANopenEditor failed on \
FileVersion=- written by old CANopenNode tools (libedssharp issue #72), and EdsDcfNet rejects \
1.0 in strict mode and keeps only the major part otherwise, so two tools disagree on the version.

It is an error because the value is not of the type CiA 306 §4.4 defines.

Fix: write the version as a plain number (FileVersion=1, FileRevision=0); keep a dotted product \
version in Description instead.",
    fixable: false,
};

const EDS_VERSION_INVALID: CheckInfo = CheckInfo {
    code: "C203",
    slug: "eds-version-invalid",
    severity: Severity::Warning,
    group: Group::FileInfo,
    title: "EDSVersion names a CiA 306 version in the form x.y",
    reference: &[9],
    spec: "CiA 306 V1.3 §4.4",
    explanation: "\
EDSVersion is the version of the EDS specification the file follows, three characters x.y; files \
written to CiA 306 V1.3 and later say 4.0, older ones 3.0. This check reports values that are not \
of the form x.y (4, 402, 4.0.1) and well-formed versions that CiA 306 never had (4.2, which python \
canopen writes, 1.5, 5.0).

Readers use the version to decide which rules apply (for example whether 1018h is mandatory); \
CANopenEditor warns \"Unable to parse EDS version\" and falls back to defaults.

It is a warning, not an error: every tool still reads the objects, only the rule set they assume \
may be wrong.

Fix: write EDSVersion=4.0 for a file that follows CiA 306 V1.3 or CiA 306-1.",
    fixable: false,
};

const EDS_VERSION_MISSING: CheckInfo = CheckInfo {
    code: "C204",
    slug: "eds-version-missing",
    severity: Severity::Info,
    group: Group::FileInfo,
    title: "EDSVersion is given (missing means 3.0)",
    reference: &[9],
    spec: "CiA 306 V1.3 §4.4",
    explanation: "\
CiA 306 §4.4 says a missing EDSVersion means version 3.0, the format before CiA 306 V1.3. This \
check reports a [FileInfo] without EDSVersion (or with an empty one).

A file without it is read under the pre-4.0 rules: for example the identity object 1018h is \
optional there, and checks that depend on the version (such as C405) are relaxed.

It is only information: a missing EDSVersion is allowed and has a defined meaning. Most files \
without it were nevertheless written for 4.0 and should say so.

Fix: add EDSVersion=4.0 if the file follows CiA 306 V1.3 or later.",
    fixable: false,
};

const DATE_TIME_INVALID: CheckInfo = CheckInfo {
    code: "C205",
    slug: "file-info-date-time-invalid",
    severity: Severity::Warning,
    group: Group::FileInfo,
    title: "creation and modification dates are mm-dd-yyyy and times hh:mm(AM|PM)",
    reference: &[10],
    spec: "CiA 306 V1.3 §3.2, §4.4",
    explanation: "\
CiA 306 writes dates as mm-dd-yyyy (05-15-2026) and times on the 12-hour clock as hh:mm followed \
by AM or PM (09:45AM, hours 01-12). This check reports CreationDate, ModificationDate, \
CreationTime and ModificationTime values in another notation (2016-03-25, 07-07-16, 17:24:43, \
13:51, CANFestival's 05-15-1995AM) or that are not a real date or time (02-30-2020, 00:01PM, \
21:37PM).

Tools that parse the dates fail on other notations: CANopenEditor parses them with the CiA \
pattern and warns when that fails, and a reader cannot tell 03-04-2020 in another convention \
from the CiA one.

It is a warning rather than an error because the dates are metadata: every tool still reads the \
device description. A certification tool may treat the notation as an error; the file does \
depart from §4.4.

Fix: write the date as mm-dd-yyyy and the time as hh:mmAM or hh:mmPM.",
    fixable: false,
};

const DATE_TIME_SPELLING: CheckInfo = CheckInfo {
    code: "C206",
    slug: "file-info-date-time-spelling",
    severity: Severity::Info,
    group: Group::FileInfo,
    title: "dates and times use two digits and upper-case AM/PM without a space",
    reference: &[10],
    spec: "CiA 306 V1.3 §3.2, §4.4",
    explanation: "\
The CiA 306 notation has two-digit fields: 02:07AM, 05-01-2026. This check reports dates and \
times that mean a valid date or time but are spelt loosely: a one-digit hour, month or day \
(2:07AM, which CANopenEditor writes), lower-case am/pm, or a space before AM/PM (08:55 PM).

Every tool that parses the dates understands these forms, so nothing is misread.

It is only information: the meaning is unambiguous, only the spelling departs from §4.4.

Fix: pad the fields to two digits and write AM or PM directly after the minutes.",
    fixable: false,
};

const MODIFIED_BEFORE_CREATED: CheckInfo = CheckInfo {
    code: "C207",
    slug: "modified-before-created",
    severity: Severity::Warning,
    group: Group::FileInfo,
    title: "the modification date is not earlier than the creation date",
    reference: &[10],
    spec: "CiA 306 V1.3 §4.4",
    explanation: "\
ModificationDate and ModificationTime give the last change of the file, CreationDate and \
CreationTime its creation. This check reports a modification that lies before the creation (dates \
compared first, times when the dates are equal); only readable dates are compared.

Such a file was usually edited by a tool that wrote a placeholder (01-01-0001) or kept the \
creation date of a template, so the metadata does not say which revision this is.

It is a warning: the device description is unaffected, but the history is wrong.

Fix: set ModificationDate/ModificationTime to the time of the last change.",
    fixable: false,
};

const FILE_NAME_MISMATCH: CheckInfo = CheckInfo {
    code: "C208",
    slug: "file-name-mismatch",
    severity: Severity::Info,
    group: Group::FileInfo,
    title: "FileName is the name the file is stored under",
    reference: &[11],
    spec: "CiA 306 V1.3 §4.4",
    explanation: "\
FileName is the name of the file itself. This check compares it, ignoring letter case and any \
directory written in front of it, with the name the file was read from; files read from standard \
input are not checked.

A different name usually means the file was renamed or copied from another device description \
without updating [FileInfo]; a DCF whose FileName still names the EDS was written by a tool that \
copied [FileInfo] unchanged. A DCF's LastEDS and project files refer to files by name, so stale \
names make the trail hard to follow.

It is only information: nothing in CiA 306 can stop a file from being stored under another name \
(download portals add versions, repositories add prefixes), and no tool reads FileName to find the \
file.

Fix: set FileName to the file's name, or rename the file.",
    fixable: false,
};

const LAST_EDS_MISSING: CheckInfo = CheckInfo {
    code: "C209",
    slug: "last-eds-missing",
    severity: Severity::Warning,
    group: Group::FileInfo,
    title: "a DCF names the EDS it was made from in LastEDS",
    reference: &[12],
    spec: "CiA 306 V1.3 §5.2",
    explanation: "\
A DCF adds LastEDS to [FileInfo]: the file name of the EDS it was created from (CiA 306 §5.2). \
This check reports a DCF (a .dcf file, or one with [DeviceComissioning]) whose [FileInfo] has no \
LastEDS or an empty one.

Without it a configuration cannot be traced back to the device description it configures, and a \
tool cannot regenerate the DCF from a newer EDS.

It is a warning, not an error: tools that download a DCF use its object sections and never read \
LastEDS, and DCFs are also written without any template (lely's dcfgen builds the master's DCF \
from a YAML description), where there is no EDS to name.

Fix: add LastEDS=<name of the EDS>.",
    fixable: false,
};

const LAST_EDS_IN_EDS: CheckInfo = CheckInfo {
    code: "C210",
    slug: "last-eds-in-eds",
    severity: Severity::Info,
    group: Group::FileInfo,
    title: "an EDS carries no LastEDS entry",
    reference: &[12],
    spec: "CiA 306 V1.3 §4.4, §5.2",
    explanation: "\
LastEDS belongs to DCFs only (CiA 306 §5.2). This check reports a LastEDS entry in a file named \
.eds that has no [DeviceComissioning] section; CANopenNode's tools write an empty LastEDS= into \
every EDS.

CiA's CANchkEDS reports it as \"Unknown or not used entry LastEDS in section [FileInfo]\" (seen in \
the published CCT run on CANopenNode's demo device), and a non-empty LastEDS makes some readers, \
canopener's model included, take the file for a DCF.

It is only information: the entry changes nothing in the device description.

Fix: delete the LastEDS line from the EDS.",
    fixable: false,
};

/// The checks of this group.
pub(crate) const CHECKS: &[CheckInfo] = &[
    KEY_MISSING,
    VERSION_NOT_UNSIGNED8,
    EDS_VERSION_INVALID,
    EDS_VERSION_MISSING,
    DATE_TIME_INVALID,
    DATE_TIME_SPELLING,
    MODIFIED_BEFORE_CREATED,
    FILE_NAME_MISMATCH,
    LAST_EDS_MISSING,
    LAST_EDS_IN_EDS,
];

/// The keys CiA 306 §4.4 defines without a default (EDSVersion defaults to 3.0, LastEDS is DCF only).
const MANDATORY: [&str; 10] = [
    "FileName",
    "FileVersion",
    "FileRevision",
    "Description",
    "CreationTime",
    "CreationDate",
    "CreatedBy",
    "ModificationTime",
    "ModificationDate",
    "ModifiedBy",
];

/// The EDSVersion values CiA 306 has defined: 3.0 before V1.3, 4.0 since.
const KNOWN_EDS_VERSIONS: [&str; 2] = ["3.0", "4.0"];

/// Runs the checks of this group.
pub(crate) fn run(cx: &Context<'_>, out: &mut Vec<Finding>) {
    // A missing [FileInfo] is P029; reporting each of its keys again would only repeat it.
    if !cx.has_section(SectionKind::FileInfo) {
        return;
    }
    let info = &cx.eds.file_info;
    for key in MANDATORY {
        if present(info.get(key)).is_none() {
            let what = if info.get(key).is_some() {
                "is empty"
            } else {
                "is missing"
            };
            out.push(
                cx.finding(
                    &KEY_MISSING,
                    SectionKind::FileInfo,
                    Some(key),
                    format!("{key} {what}"),
                )
                .with_help(format!("add {key}=<value> to [FileInfo]")),
            );
        }
    }
    for key in ["FileVersion", "FileRevision"] {
        if let Some(text) = present(info.get(key))
            && !strict_int(text).is_some_and(|v| (0..=255).contains(&v))
        {
            out.push(
                cx.finding(
                    &VERSION_NOT_UNSIGNED8,
                    SectionKind::FileInfo,
                    Some(key),
                    format!("{key} `{text}` is not an Unsigned8 number (0-255)"),
                )
                .with_help(format!("write a plain number, e.g. {key}=1")),
            );
        }
    }
    check_eds_version(cx, out);
    check_dates(cx, out);
    check_file_name(cx, out);
    check_last_eds(cx, out);
}

fn check_eds_version(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let Some(version) = present(cx.eds.file_info.eds_version.as_deref()) else {
        out.push(
            cx.finding(
                &EDS_VERSION_MISSING,
                SectionKind::FileInfo,
                Some("EDSVersion"),
                "EDSVersion is not given, so the file is read as CiA 306 version 3.0",
            )
            .with_help("add EDSVersion=4.0 if the file follows CiA 306 V1.3 or later"),
        );
        return;
    };
    let well_formed = matches!(version.as_bytes(), [a, b'.', b] if a.is_ascii_digit() && b.is_ascii_digit());
    let message = if !well_formed {
        format!("EDSVersion `{version}` is not of the form x.y")
    } else if !KNOWN_EDS_VERSIONS.contains(&version) {
        format!("EDSVersion {version} is not a CiA 306 version (3.0 or 4.0)")
    } else {
        return;
    };
    out.push(
        cx.finding(
            &EDS_VERSION_INVALID,
            SectionKind::FileInfo,
            Some("EDSVersion"),
            message,
        )
        .with_help("write EDSVersion=4.0 for a file that follows CiA 306 V1.3 or later"),
    );
}

/// A date or time and how it departs from the CiA 306 notation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Reading<T> {
    /// Exactly the CiA 306 notation.
    Exact(T),
    /// A valid value in a looser spelling; the text says what differs.
    Loose(T, &'static str),
    /// Not a CiA 306 date or time; the text says why.
    Invalid(&'static str),
}

impl<T: Copy> Reading<T> {
    fn value(self) -> Option<T> {
        match self {
            Self::Exact(v) | Self::Loose(v, _) => Some(v),
            Self::Invalid(_) => None,
        }
    }
}

/// (year, month, day).
type Date = (u32, u32, u32);
/// Minutes after midnight.
type Time = u32;

fn check_dates(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let info = &cx.eds.file_info;
    let mut read_date = |key: &str, text: Option<&str>| -> Option<Date> {
        let text = present(text)?;
        let reading = parse_date(text);
        report_reading(cx, out, key, text, reading, "mm-dd-yyyy", "05-15-2026");
        reading.value()
    };
    let created = read_date("CreationDate", info.creation_date.as_deref());
    let modified = read_date("ModificationDate", info.modification_date.as_deref());
    let mut read_time = |key: &str, text: Option<&str>| -> Option<Time> {
        let text = present(text)?;
        let reading = parse_time(text);
        report_reading(cx, out, key, text, reading, "hh:mm(AM|PM)", "09:45AM");
        reading.value()
    };
    let created_at = read_time("CreationTime", info.creation_time.as_deref());
    let modified_at = read_time("ModificationTime", info.modification_time.as_deref());
    let (Some(created), Some(modified)) = (created, modified) else {
        return;
    };
    let earlier = match (created_at, modified_at) {
        (Some(c), Some(m)) if created == modified => m < c,
        _ => modified < created,
    };
    if earlier {
        let when = |date: &str, time: &str| {
            [date, time]
                .into_iter()
                .filter_map(|key| present(info.get(key)))
                .collect::<Vec<_>>()
                .join(" ")
        };
        out.push(
            cx.finding(
                &MODIFIED_BEFORE_CREATED,
                SectionKind::FileInfo,
                Some("ModificationDate"),
                format!(
                    "modified {} before it was created {}",
                    when("ModificationDate", "ModificationTime"),
                    when("CreationDate", "CreationTime"),
                ),
            )
            .with_help("set ModificationDate and ModificationTime to the last change of the file"),
        );
    }
}

fn report_reading<T>(
    cx: &Context<'_>,
    out: &mut Vec<Finding>,
    key: &str,
    text: &str,
    reading: Reading<T>,
    notation: &str,
    example: &str,
) {
    let (info, why) = match reading {
        Reading::Exact(_) => return,
        Reading::Loose(_, why) => (&DATE_TIME_SPELLING, why),
        Reading::Invalid(why) => (&DATE_TIME_INVALID, why),
    };
    out.push(
        cx.finding(
            info,
            SectionKind::FileInfo,
            Some(key),
            format!("{key} `{text}` {why}"),
        )
        .with_help(format!("write {key} as {notation}, e.g. {key}={example}")),
    );
}

/// Splits `text` into runs of ASCII digits separated by `sep`; `None` if anything else occurs.
fn digit_fields(text: &str, sep: char) -> Option<Vec<&str>> {
    let fields: Vec<&str> = text.split(sep).collect();
    fields
        .iter()
        .all(|f| !f.is_empty() && f.bytes().all(|b| b.is_ascii_digit()))
        .then_some(fields)
}

/// Reads a CiA 306 date `mm-dd-yyyy` (CiA 306 V1.3 §3.2).
fn parse_date(text: &str) -> Reading<Date> {
    let Some(fields) = digit_fields(text, '-') else {
        return Reading::Invalid("is not a date of the form mm-dd-yyyy");
    };
    let [m, d, y] = fields.as_slice() else {
        return Reading::Invalid("is not a date of the form mm-dd-yyyy");
    };
    if m.len() == 4 {
        return Reading::Invalid("is written year first; CiA 306 writes mm-dd-yyyy");
    }
    if y.len() != 4 {
        return Reading::Invalid("does not give the year with four digits (mm-dd-yyyy)");
    }
    if m.len() > 2 || d.len() > 2 {
        return Reading::Invalid("is not a date of the form mm-dd-yyyy");
    }
    // Every field is 1-4 ASCII digits here, so the parses cannot fail.
    let (Ok(month), Ok(day), Ok(year)) = (m.parse::<u32>(), d.parse::<u32>(), y.parse::<u32>()) else {
        return Reading::Invalid("is not a date of the form mm-dd-yyyy");
    };
    if !(1..=12).contains(&month) {
        return Reading::Invalid("has no month of that number (mm-dd-yyyy: the month comes first)");
    }
    if day == 0 || day > days_in_month(year, month) {
        return Reading::Invalid("is not a day of the calendar");
    }
    let date = (year, month, day);
    if m.len() < 2 || d.len() < 2 {
        return Reading::Loose(date, "writes the month or day with one digit (mm-dd-yyyy)");
    }
    Reading::Exact(date)
}

fn days_in_month(year: u32, month: u32) -> u32 {
    match month {
        2 if (year.is_multiple_of(4) && !year.is_multiple_of(100)) || year.is_multiple_of(400) => 29,
        2 => 28,
        4 | 6 | 9 | 11 => 30,
        _ => 31,
    }
}

/// Reads a CiA 306 time `hh:mm(AM|PM)` on the 12-hour clock (CiA 306 V1.3 §3.2).
fn parse_time(text: &str) -> Reading<Time> {
    let upper = text.to_ascii_uppercase();
    let (clock, pm) = match (upper.strip_suffix("AM"), upper.strip_suffix("PM")) {
        (Some(c), _) => (c, false),
        (_, Some(c)) => (c, true),
        _ => {
            return Reading::Invalid(if digit_fields(text, ':').is_some() {
                "is on the 24-hour clock; CiA 306 writes hh:mm followed by AM or PM"
            } else {
                "is not a time of the form hh:mm(AM|PM)"
            });
        }
    };
    let spaced = clock.ends_with(' ');
    let clock = clock.trim_end();
    let Some(fields) = digit_fields(clock, ':') else {
        return Reading::Invalid("is not a time of the form hh:mm(AM|PM)");
    };
    let [h, m] = fields.as_slice() else {
        return Reading::Invalid("gives seconds or more fields; CiA 306 writes hh:mm(AM|PM)");
    };
    if h.len() > 2 || m.len() != 2 {
        return Reading::Invalid("is not a time of the form hh:mm(AM|PM)");
    }
    // One or two ASCII digits each, so the parses cannot fail.
    let (Ok(hour), Ok(minute)) = (h.parse::<u32>(), m.parse::<u32>()) else {
        return Reading::Invalid("is not a time of the form hh:mm(AM|PM)");
    };
    if !(1..=12).contains(&hour) {
        return Reading::Invalid(
            "has an hour outside 01-12, which the 12-hour clock with AM/PM does not have",
        );
    }
    if minute > 59 {
        return Reading::Invalid("has minutes above 59");
    }
    let time = (hour % 12 + if pm { 12 } else { 0 }) * 60 + minute;
    if h.len() < 2 {
        Reading::Loose(time, "writes the hour with one digit (hh:mm)")
    } else if spaced {
        Reading::Loose(time, "has a space before AM/PM")
    } else if !text.ends_with("AM") && !text.ends_with("PM") {
        Reading::Loose(time, "writes am/pm in lower case")
    } else {
        Reading::Exact(time)
    }
}

fn check_file_name(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let (Some(actual), Some(written)) = (cx.file_name, present(cx.eds.file_info.file_name.as_deref())) else {
        return;
    };
    // Tools write absolute paths (`C:/DCF/x.dcf`); only the last component names the file.
    let base = written.rsplit(['/', '\\']).next().unwrap_or(written).trim();
    if base.eq_ignore_ascii_case(actual) {
        return;
    }
    out.push(
        cx.finding(
            &FILE_NAME_MISMATCH,
            SectionKind::FileInfo,
            Some("FileName"),
            format!("FileName `{written}` is not the name the file was read from, `{actual}`"),
        )
        .with_help(format!("set FileName={actual}, or rename the file")),
    );
}

fn check_last_eds(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let last_eds = cx.eds.file_info.last_eds.as_deref();
    if is_dcf_file(cx) {
        if present(last_eds).is_none() {
            out.push(
                cx.finding(
                    &LAST_EDS_MISSING,
                    SectionKind::FileInfo,
                    Some("LastEDS"),
                    "this DCF does not name the EDS it was made from (LastEDS)",
                )
                .with_help("add LastEDS=<file name of the EDS> to [FileInfo]"),
            );
        }
    } else if last_eds.is_some() {
        out.push(
            cx.finding(
                &LAST_EDS_IN_EDS,
                SectionKind::FileInfo,
                Some("LastEDS"),
                "LastEDS belongs to DCFs; this EDS carries it",
            )
            .with_help("delete the LastEDS line"),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_follow_the_cia_notation() {
        assert_eq!(parse_date("05-15-2026"), Reading::Exact((2026, 5, 15)));
        assert_eq!(parse_date("02-29-2020").value(), Some((2020, 2, 29)));
        assert!(matches!(parse_date("5-1-2026"), Reading::Loose((2026, 5, 1), _)));
        for bad in [
            "02-29-2019",
            "2016-03-25",
            "07-07-16",
            "13-01-2020",
            "05-15-1995AM",
            "",
            "04-31-2020",
        ] {
            assert!(matches!(parse_date(bad), Reading::Invalid(_)), "{bad}");
        }
    }

    #[test]
    fn times_are_on_the_twelve_hour_clock() {
        assert_eq!(parse_time("09:45AM"), Reading::Exact(9 * 60 + 45));
        assert_eq!(parse_time("12:00AM"), Reading::Exact(0));
        assert_eq!(parse_time("12:30PM"), Reading::Exact(12 * 60 + 30));
        assert_eq!(parse_time("01:05PM"), Reading::Exact(13 * 60 + 5));
        assert!(matches!(parse_time("2:07AM"), Reading::Loose(127, _)));
        assert!(matches!(parse_time("08:55 PM"), Reading::Loose(_, _)));
        assert!(matches!(parse_time("03:46pm"), Reading::Loose(_, _)));
        for bad in [
            "17:24:43", "13:51", "00:01PM", "21:37PM", "10:60AM", "9.45AM", "AM",
        ] {
            assert!(matches!(parse_time(bad), Reading::Invalid(_)), "{bad}");
        }
    }
}

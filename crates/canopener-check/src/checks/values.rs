//! Group G of the check catalogue (`docs/check-catalogue.md`): values (checks 45-50).
//!
//! The loader already reads every DefaultValue, LowLimit, HighLimit and ParameterValue with its data
//! type and reports what does not parse (P050, P059-P061), what leaves the type's range, including
//! `$NODEID` formulas that leave it for some node-ID 1..=127 (P054), `$NODEID` in the wrong place or
//! on non-integers (P056, P057), spelling variants (P062), REAL notation (P058) and signed values
//! written as unsigned hex (P055). The checks here compare values with each other: limits with each
//! other and with the values, strings with the escapes other tools apply, and a DCF's configured
//! values with the defaults of entries nobody can write.

use std::cmp::Ordering;

use canopener_eds::diag::Code;
use canopener_eds::model::Attributes;
use canopener_eds::section_name::SectionKind;
use canopener_eds::value::{Parsed, parse_value};
use canopener_eds::{AccessType, DataType, ObjectType, Origin, Severity, TypeKind, Value};

use crate::check_info::{CheckInfo, Group};
use crate::context::{Context, object_kind};
use crate::finding::Finding;

const LOW_ABOVE_HIGH: CheckInfo = CheckInfo {
    code: "C601",
    slug: "low-limit-above-high-limit",
    severity: Severity::Error,
    group: Group::Values,
    title: "LowLimit is not above HighLimit",
    reference: &[46],
    spec: "CiA 306 V1.3 §4.6.3.2",
    explanation: "\
LowLimit and HighLimit bound the values an entry accepts (CiA 306 §4.6.3.2). This check reports a \
LowLimit above the HighLimit, compared as values of the entry's data type (so LowLimit=0xFFFF on an \
INTEGER16 is -1).

No value satisfies both limits: a configuration tool refuses every value the user enters, and a \
device or simulator generated from the file rejects every SDO download (abort 0x06090036 or \
0x06090032). lely warns \"LowLimit exceeds HighLimit\".

It is an error because the limits describe an empty range.

Fix: swap the limits or correct the one that is wrong; remember that limits of signed types are \
signed.",
    fixable: false,
};

const VALUE_OUTSIDE_LIMITS: CheckInfo = CheckInfo {
    code: "C602",
    slug: "value-outside-limits",
    severity: Severity::Error,
    group: Group::Values,
    title: "DefaultValue and ParameterValue lie within LowLimit..HighLimit",
    reference: &[46],
    spec: "CiA 306 V1.3 §4.6.3.2, §5.3.2",
    explanation: "\
When an entry has LowLimit or HighLimit, its DefaultValue and (in a DCF) ParameterValue must lie \
within them. This check compares them as values of the entry's data type. A `$NODEID+offset` value \
must lie within the limits for every node-ID 1..127 (as lely checks it); in a DCF the node-ID of \
[DeviceComissioning] is used.

The device cannot hold its own default: a configuration tool that downloads the defaults gets an \
SDO abort (0x06090031 value too high, 0x06090032 too low), and a DCF whose ParameterValue is outside \
the limits fails during configuration. lely warns \"DefaultValue underflow/overflow\".

It is an error because the file contradicts itself.

Fix: correct the value or widen the limits.",
    fixable: false,
};

const STRING_BACKSLASH: CheckInfo = CheckInfo {
    code: "C603",
    slug: "string-backslash",
    severity: Severity::Warning,
    group: Group::Values,
    title: "VISIBLE_STRING values without backslashes",
    reference: &[48],
    spec: "CiA 306 V1.3 §4.2",
    explanation: "\
CiA 306 stores strings as they are, without quotes or escapes (§4.2). This check reports a \
VISIBLE_STRING DefaultValue or ParameterValue that contains a backslash.

Tools disagree on what the backslash means: lely's lexer reads C escape sequences in strings (so \
`C:\\new` becomes C:, a newline and `ew`), CANopenEditor unescapes them when it sizes the string, \
python canopen keeps them. The device then gets a different string or a different length depending \
on the tool.

It is a warning: the file is valid, but its meaning depends on the reader.

Fix: avoid backslashes in string values, e.g. write paths with `/`.",
    fixable: false,
};

const READ_ONLY_VALUE_DIFFERS: CheckInfo = CheckInfo {
    code: "C604",
    slug: "read-only-parameter-value-differs",
    severity: Severity::Warning,
    group: Group::Values,
    title: "DCF: ro and const entries configure their DefaultValue",
    reference: &[50],
    spec: "CiA 306 V1.3 §5.3.2",
    explanation: "\
In a DCF, ParameterValue is the value a configuration tool downloads to the device (CiA 306 \
§5.3.2). Entries with AccessType ro or const cannot be written, so a ParameterValue that differs \
from the DefaultValue cannot be configured. This check reports such entries.

Either the value was read back from a device (a firmware revision) and the DCF now describes one \
particular device, or the DCF is inconsistent with its EDS. The serial number (1018h sub 4) is not \
reported: a DCF describes one device, whose serial number differs from the EDS default by design. A configuration manager \
that compares the device with the DCF (CiA 302 boot-up checks 1F84h-1F88h) reports a mismatch, or \
tries the download and gets SDO abort 0x06010002 (attempt to write a read-only object).

It is a warning: CiA 306 does not forbid it, and ObjFlags bit 0 tells tools not to download the \
entry.

Fix: set ParameterValue to the DefaultValue, or leave ParameterValue out for read-only entries.",
    fixable: false,
};

const LIMITS_ON_NON_NUMERIC: CheckInfo = CheckInfo {
    code: "C605",
    slug: "limits-on-non-numeric-type",
    severity: Severity::Warning,
    group: Group::Values,
    title: "LowLimit and HighLimit only on integer and REAL entries",
    reference: &[46],
    spec: "CiA 306 V1.3 §4.6.3.2",
    explanation: "\
LowLimit and HighLimit are given \"where applicable\" (CiA 306 §4.6.3.2): for entries whose values \
are ordered numbers, the INTEGER, UNSIGNED and REAL types. This check reports limits on BOOLEAN, \
string, octet string, time and DOMAIN entries.

Tools cannot apply them: lely's dcfchk rejects limits on non-numeric types, python canopen drops \
them, and a user who expects a length limit on a string gets none.

It is a warning: nothing is misread, but the limit has no effect.

Fix: delete the limits; describe a maximum string length in the device manual.",
    fixable: false,
};

/// The checks of this group.
pub(crate) const CHECKS: &[CheckInfo] = &[
    LOW_ABOVE_HIGH,
    VALUE_OUTSIDE_LIMITS,
    STRING_BACKSLASH,
    READ_ONLY_VALUE_DIFFERS,
    LIMITS_ON_NON_NUMERIC,
];

/// Runs the checks of this group.
pub(crate) fn run(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let node_id = cx.eds.node_id();
    for (&index, object) in &cx.eds.objects {
        if object.origin == Origin::Explicit {
            check_entry(cx, out, object_kind(index, None), &object.attributes, node_id);
        }
        for (&sub, sub_object) in &object.subs {
            if sub_object.origin == Origin::Explicit {
                check_entry(
                    cx,
                    out,
                    object_kind(index, Some(sub)),
                    &sub_object.attributes,
                    node_id,
                );
            }
        }
    }
}

/// A numeric value, or the values a `$NODEID` formula takes over node-IDs 1..=127.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Spread {
    low: Number,
    high: Number,
}

/// A value of an integer or REAL entry; integers stay exact when compared with each other.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Number {
    Int(i128),
    Real(f64),
}

impl Number {
    fn compare(self, other: Number) -> Option<Ordering> {
        match (self, other) {
            (Number::Int(a), Number::Int(b)) => Some(a.cmp(&b)),
            (a, b) => a.as_f64().partial_cmp(&b.as_f64()),
        }
    }

    /// Only used to compare with REAL values, which are f64 themselves.
    fn as_f64(self) -> f64 {
        match self {
            Number::Int(v) => v as f64,
            Number::Real(v) => v,
        }
    }
}

/// A value as the check sees it: its text as written, and its numeric span if it has one.
struct Read<'a> {
    key: &'static str,
    text: &'a str,
    parsed: Parsed,
}

impl Read<'_> {
    /// The numeric span, `None` when the value is not a number or the loader already reported it out
    /// of its type's range (comparing it again would report one mistake twice).
    fn span(&self, node_id: Option<u8>) -> Option<Spread> {
        if self.parsed.issues.iter().any(|i| i.code == Code::OutOfRange) {
            return None;
        }
        let single = |n| Some(Spread { low: n, high: n });
        match self.parsed.value.as_ref()? {
            Value::Integer { value, .. } => single(Number::Int(*value)),
            Value::Real { value, .. } if value.is_finite() => single(Number::Real(*value)),
            Value::NodeRelative { offset, .. } => match node_id {
                Some(id) => single(Number::Int(offset.saturating_add(i128::from(id)))),
                None => Some(Spread {
                    low: Number::Int(offset.saturating_add(1)),
                    high: Number::Int(offset.saturating_add(127)),
                }),
            },
            _ => None,
        }
    }

    /// A limit as written and its value; limits written as `$NODEID` formulas only have a value once
    /// the node-ID is known.
    fn limit(&self, node_id: Option<u8>) -> Option<(String, Number)> {
        let span = self.span(node_id)?;
        (span.low == span.high).then(|| (self.shown(), span.low))
    }

    /// The value as written, with the value it was read as when that is not obvious: a signed value
    /// written as an unsigned bit pattern is read as two's complement (P055).
    fn shown(&self) -> String {
        let wrapped = self.parsed.issues.iter().any(|i| i.code == Code::TwosComplement);
        match &self.parsed.value {
            Some(Value::Integer { value, .. }) if wrapped => format!("{} (read as {value})", self.text),
            _ => self.text.to_owned(),
        }
    }
}

fn check_entry(
    cx: &Context<'_>,
    out: &mut Vec<Finding>,
    kind: SectionKind,
    a: &Attributes,
    node_id: Option<u8>,
) {
    let structured = matches!(
        a.object_type(),
        Some(ObjectType::Array | ObjectType::Record | ObjectType::DefStruct)
    );
    if structured && a.compact_sub_obj() == 0 {
        // Values are "not supported" on such an object (C502); its sub-objects carry them.
        return;
    }
    let Some(data_type) = a.data_type().map(|t| cx.eds.resolve_data_type(t)) else {
        return;
    };
    let Some(type_kind) = data_type.kind() else {
        return;
    };
    let values: Vec<Read<'_>> = [
        ("LowLimit", a.low_limit.as_deref()),
        ("HighLimit", a.high_limit.as_deref()),
        ("DefaultValue", a.default_value.as_deref()),
        ("ParameterValue", a.parameter_value.as_deref()),
    ]
    .into_iter()
    .filter_map(|(key, text)| {
        let text = text?.trim();
        (!text.is_empty()).then(|| Read {
            key,
            text,
            parsed: parse_value(text, data_type),
        })
    })
    .collect();
    let get = |key: &str| find(&values, key);
    let refuse_write = a.obj_flags().is_some_and(|f| f & 1 != 0);
    check_limits(cx, out, kind, data_type, &values, node_id, refuse_write);
    if type_kind == TypeKind::VisibleString {
        for r in values
            .iter()
            .filter(|r| matches!(r.key, "DefaultValue" | "ParameterValue"))
        {
            if r.text.contains('\\') {
                out.push(
                    cx.finding(
                        &STRING_BACKSLASH,
                        kind,
                        Some(r.key),
                        format!(
                            "{}={} contains a backslash, which lely reads as a C escape",
                            r.key, r.text
                        ),
                    )
                    .with_help("avoid backslashes in string values; CiA 306 strings have no escapes"),
                );
            }
        }
    }
    if cx.is_dcf()
        && kind != SERIAL_NUMBER
        && matches!(a.access_type(), Some(AccessType::Ro | AccessType::Const))
        && let (Some(default), Some(parameter)) = (get("DefaultValue"), get("ParameterValue"))
        && !same_value(default, parameter, node_id)
    {
        let access = a.access_type.as_deref().unwrap_or("").trim();
        let resolved = |r: &Read<'_>| match (&r.parsed.value, node_id) {
            (Some(v @ Value::NodeRelative { .. }), Some(id)) => resolve(v, id).map_or_else(
                || r.text.to_owned(),
                |n| format!("{} (0x{n:X} for node-ID {id})", r.text),
            ),
            _ => r.text.to_owned(),
        };
        out.push(
            cx.finding(
                &READ_ONLY_VALUE_DIFFERS,
                kind,
                Some("ParameterValue"),
                format!(
                    "ParameterValue {} differs from DefaultValue {} on an entry with AccessType={access}",
                    resolved(parameter),
                    resolved(default)
                ),
            )
            .with_help(
                "a configuration tool cannot download it; set ParameterValue to the DefaultValue or omit it",
            ),
        );
    }
}

/// 1018h sub 4, the serial number: a DCF describes one device, so its serial number read back from
/// that device differs from the EDS default by design (CiA 306 §5; issue 18) and is not a C604.
const SERIAL_NUMBER: SectionKind = SectionKind::Sub(0x1018, 4);

/// The value of an entry with this key, if written.
fn find<'v, 'a>(values: &'v [Read<'a>], key: &str) -> Option<&'v Read<'a>> {
    values.iter().find(|r| r.key == key)
}

fn check_limits(
    cx: &Context<'_>,
    out: &mut Vec<Finding>,
    kind: SectionKind,
    data_type: DataType,
    values: &[Read<'_>],
    node_id: Option<u8>,
    refuse_write: bool,
) {
    let (low, high) = (find(values, "LowLimit"), find(values, "HighLimit"));
    if low.is_none() && high.is_none() {
        return;
    }
    // BOOLEAN values are ordered too (0 < 1); limits there are redundant but harmless.
    if !data_type.is_numeric() && data_type != DataType::BOOLEAN {
        let key = if low.is_some() { "LowLimit" } else { "HighLimit" };
        out.push(
            cx.finding(
                &LIMITS_ON_NON_NUMERIC,
                kind,
                Some(key),
                format!("{key} on a {data_type} entry, which has no ordered values to limit"),
            )
            .with_help("delete LowLimit and HighLimit from this entry"),
        );
        return;
    }
    let (low, high) = (
        low.and_then(|r| r.limit(node_id)),
        high.and_then(|r| r.limit(node_id)),
    );
    if let (Some((low_text, low)), Some((high_text, high))) = (&low, &high)
        && low.compare(*high) == Some(Ordering::Greater)
    {
        out.push(
            cx.finding(
                &LOW_ABOVE_HIGH,
                kind,
                Some("LowLimit"),
                format!("LowLimit {low_text} is above HighLimit {high_text}"),
            )
            .with_help("swap the limits or correct the wrong one; limits of signed types are signed"),
        );
        return;
    }
    for key in ["DefaultValue", "ParameterValue"] {
        // ObjFlags bit 0 (CiA 306 §4.6.3.2): tools never download this entry, so its ParameterValue is
        // a value read back from a device, not one that is configured.
        if key == "ParameterValue" && refuse_write {
            continue;
        }
        let Some(r) = find(values, key) else { continue };
        let Some(span) = r.span(node_id) else { continue };
        let formula = span.low != span.high;
        let below = low
            .as_ref()
            .filter(|(_, l)| span.low.compare(*l) == Some(Ordering::Less));
        let above = high
            .as_ref()
            .filter(|(_, h)| span.high.compare(*h) == Some(Ordering::Greater));
        let shown = r.shown();
        let message = match (below, above) {
            (Some((l, _)), _) if formula => format!("{key} {shown} is below LowLimit {l} for node-ID 1"),
            (_, Some((h, _))) if formula => format!("{key} {shown} is above HighLimit {h} for node-ID 127"),
            (Some((l, _)), _) => format!("{key} {shown} is below LowLimit {l}"),
            (_, Some((h, _))) => format!("{key} {shown} is above HighLimit {h}"),
            (None, None) => continue,
        };
        out.push(
            cx.finding(&VALUE_OUTSIDE_LIMITS, kind, Some(key), message)
                .with_help("correct the value or widen the limits"),
        );
    }
}

/// Whether two values of one entry mean the same thing (`$NODEID` resolved when the node-ID is
/// known); values that do not parse are compared as written.
fn same_value(a: &Read<'_>, b: &Read<'_>, node_id: Option<u8>) -> bool {
    let (Some(x), Some(y)) = (&a.parsed.value, &b.parsed.value) else {
        return a.text == b.text;
    };
    if x.same_meaning(y) {
        return true;
    }
    if let Some(id) = node_id {
        let (x, y) = (resolve(x, id), resolve(y, id));
        return x.is_some() && x == y;
    }
    // Without a node-ID a formula matches a number it gives for some node-ID 1..=127.
    match (x, y) {
        (Value::NodeRelative { offset, .. }, Value::Integer { value, .. })
        | (Value::Integer { value, .. }, Value::NodeRelative { offset, .. }) => {
            (1..=127).contains(&value.saturating_sub(*offset))
        }
        _ => false,
    }
}

/// The integer a value has for a node-ID, like [`Value::resolve`] but saturating, since a formula's
/// offset may be any 128-bit number the file writes.
fn resolve(value: &Value, node_id: u8) -> Option<i128> {
    match value {
        Value::Integer { value, .. } => Some(*value),
        Value::NodeRelative { offset, .. } => Some(offset.saturating_add(i128::from(node_id))),
        Value::Boolean { value } => Some(i128::from(*value)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::findings_with_code as findings;

    fn var(data_type: &str, keys: &str) -> String {
        format!("[2000]\nParameterName=Value\nObjectType=0x7\nDataType={data_type}\nAccessType=rw\n{keys}")
    }

    #[test]
    fn reals_are_compared_as_reals() {
        let text = var("0x0008", "LowLimit=-1.5\nHighLimit=2.5\nDefaultValue=2.75\n");
        let found = findings(&text, "C602");
        assert_eq!(found.len(), 1);
        assert_eq!(
            found[0].diagnostic.message,
            "DefaultValue 2.75 is above HighLimit 2.5"
        );
        assert!(
            findings(
                &var("0x0008", "LowLimit=-1.5\nHighLimit=2.5\nDefaultValue=-1.5\n"),
                "C602"
            )
            .is_empty()
        );
        assert_eq!(
            findings(&var("0x0008", "LowLimit=3\nHighLimit=2.5\n"), "C601").len(),
            1
        );
    }

    #[test]
    fn values_out_of_their_type_are_left_to_the_loader() {
        // 300 does not fit UNSIGNED8 (P054); comparing it with the limits would report it twice.
        let text = var("0x0005", "LowLimit=0\nHighLimit=200\nDefaultValue=300\n");
        assert!(findings(&text, "C602").is_empty());
    }

    #[test]
    fn a_dcf_resolves_nodeid_with_its_node_id() {
        let dcf = |node: u8| {
            format!(
                "[FileInfo]\nLastEDS=x.eds\n[DeviceComissioning]\nNodeID={node}\n{}",
                var(
                    "0x0007",
                    "LowLimit=0x181\nHighLimit=0x1BF\nDefaultValue=$NODEID+0x180\n"
                )
            )
        };
        assert!(findings(&dcf(63), "C602").is_empty());
        let found = findings(&dcf(64), "C602");
        assert_eq!(found.len(), 1, "{found:?}");
        // In an EDS every node-ID 1..=127 must fit.
        let eds = var(
            "0x0007",
            "LowLimit=0x181\nHighLimit=0x1BF\nDefaultValue=$NODEID+0x180\n",
        );
        assert!(
            findings(&eds, "C602")[0]
                .diagnostic
                .message
                .contains("node-ID 127")
        );
    }

    #[test]
    fn read_only_values_are_only_compared_in_a_dcf() {
        let keys = "DefaultValue=1\nParameterValue=2\n";
        let eds = var("0x0005", keys).replace("AccessType=rw", "AccessType=ro");
        assert!(findings(&eds, "C604").is_empty());
        let dcf = format!("[FileInfo]\nLastEDS=x.eds\n{eds}");
        assert_eq!(findings(&dcf, "C604").len(), 1);
        let writable = format!("[FileInfo]\nLastEDS=x.eds\n{}", var("0x0005", keys));
        assert!(findings(&writable, "C604").is_empty());
    }

    #[test]
    fn a_dcf_may_carry_the_serial_number_of_its_device() {
        let identity = |sub: u8| {
            format!(
                "[FileInfo]\nLastEDS=x.eds\n[1018]\nParameterName=Identity\nObjectType=0x9\nSubNumber=2\n\
                 [1018sub0]\nParameterName=n\nObjectType=0x7\nDataType=0x0005\nAccessType=ro\nDefaultValue={sub}\n\
                 [1018sub{sub}]\nParameterName=x\nObjectType=0x7\nDataType=0x0007\nAccessType=ro\n\
                 DefaultValue=0\nParameterValue=0x1234\n"
            )
        };
        assert!(findings(&identity(4), "C604").is_empty(), "the serial number");
        assert_eq!(findings(&identity(2), "C604").len(), 1, "the product code");
    }

    #[test]
    fn huge_offsets_do_not_overflow() {
        let value = Value::NodeRelative {
            offset: i128::MAX,
            radix: canopener_eds::value::Radix::Decimal,
        };
        assert_eq!(resolve(&value, 127), Some(i128::MAX));
        assert_eq!(Number::Int(2).compare(Number::Real(2.5)), Some(Ordering::Less));
        assert_eq!(Number::Real(f64::NAN).compare(Number::Int(0)), None);
    }
}

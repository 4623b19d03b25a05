//! How the checks read what a file says: values present or blank, integers in CiA 306 notation,
//! the value a device uses for an entry, whether the file is a DCF, names for entries and types,
//! and where a finding about an object points. Shared by the check modules, which never import
//! each other.

use canopener_eds::model::strip_inline_comment;
use canopener_eds::section_name::{Companion, SectionKind};
use canopener_eds::value::{self, Value};
use canopener_eds::{Attributes, Code, DataType, Origin};

use crate::check_info::CheckInfo;
use crate::context::Context;
use crate::finding::Finding;

/// A value that is present and not blank (CiA 306 §4.2: an empty value means the key is missing).
pub(crate) fn present(value: Option<&str>) -> Option<&str> {
    value.map(str::trim).filter(|v| !v.is_empty())
}

/// Reads a CiA 306 §4.2 integer: decimal, `0x` hexadecimal or octal with a leading `0`, optionally
/// signed. The lenient forms the value parser also accepts (`FEh`, `08` read as decimal) are
/// refused; an inline `; comment` is ignored, since group A reports it.
pub(crate) fn strict_int(text: &str) -> Option<i128> {
    let read = |t: &str| {
        let mut issues = Vec::new();
        let literal = value::parse_integer(t, &mut issues)?;
        let lenient = issues
            .iter()
            .any(|i| matches!(i.code, Code::HexSuffix | Code::InvalidNumber));
        (!lenient).then_some(literal.value)
    };
    read(text).or_else(|| read(strip_inline_comment(text)?))
}

/// Reads an integer the way the loader does (accepting `FEh`); for values whose notation other
/// checks already report.
pub(crate) fn lenient_int(text: &str) -> Option<i128> {
    canopener_eds::model::int_of(text)
}

/// Whether the file is a DCF: named `.dcf`, or with `[DeviceComissioning]`, or (named neither
/// `.eds` nor `.dcf`) naming its template in `LastEDS` (CiA 306 §5). An `.eds` file with `LastEDS`
/// but no commissioning is an EDS that a tool stamped with LastEDS (C210).
pub(crate) fn is_dcf_file(cx: &Context<'_>) -> bool {
    if cx.eds.commissioning.is_some() {
        return true;
    }
    let extension = cx
        .file_name
        .and_then(|n| n.rsplit_once('.'))
        .map(|(_, e)| e.to_ascii_lowercase());
    match extension.as_deref() {
        Some("dcf") => true,
        Some("eds") => false,
        _ => cx.is_dcf(),
    }
}

/// An integer value as written: a number, or `$NODEID` plus an offset that may carry flag bits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Int {
    /// A plain number.
    Literal(i128),
    /// `$NODEID+offset`.
    NodeRelative(i128),
}

impl Int {
    /// The value for a node-ID.
    pub(crate) fn at(self, node: u8) -> i128 {
        match self {
            Self::Literal(v) => v,
            Self::NodeRelative(offset) => offset + i128::from(node),
        }
    }
}

/// The value a check reads from an entry, with the key it came from and the text as written.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Reading<'a> {
    /// `ParameterValue` or `DefaultValue`.
    pub(crate) key: &'static str,
    /// The value as written.
    pub(crate) text: &'a str,
    /// The value.
    pub(crate) value: Int,
}

impl Reading<'_> {
    /// The value as written, followed by its hexadecimal form when it was written in decimal:
    /// COB-IDs and mapping entries are bit fields that read in hex (`1614807056 (0x60400010)`).
    pub(crate) fn shown(&self) -> String {
        match self.value {
            Int::Literal(v) if v > 9 && !self.text.to_ascii_lowercase().contains("0x") => {
                format!("{} (0x{v:X})", self.text)
            }
            _ => self.text.to_owned(),
        }
    }
}

/// The value the device uses: in a DCF the configured `ParameterValue` when there is one, otherwise
/// `DefaultValue` (CiA 306 §5.3.2), or `ParameterValue` when it is all there is. `None` when empty or
/// not an integer (the loader reports those).
pub(crate) fn reading<'a>(cx: &Context<'_>, attributes: &'a Attributes) -> Option<Reading<'a>> {
    let non_empty = |v: &'a Option<String>| v.as_deref().map(str::trim).filter(|t| !t.is_empty());
    let configured = non_empty(&attributes.parameter_value);
    let (key, text) = match (configured, non_empty(&attributes.default_value)) {
        (Some(text), _) if cx.is_dcf() => ("ParameterValue", text),
        (_, Some(text)) => ("DefaultValue", text),
        // Files that give only ParameterValue are DCFs in all but name (lely writes them).
        (Some(text), None) => ("ParameterValue", text),
        (None, None) => return None,
    };
    let value = match value::parse_value(text, DataType::UNSIGNED64).value? {
        Value::Integer { value, .. } => Int::Literal(value),
        Value::NodeRelative { offset, .. } => Int::NodeRelative(offset),
        _ => return None,
    };
    Some(Reading { key, text, value })
}

/// An object of the device (written or implied), not a placeholder for orphaned sub-sections.
pub(crate) fn live_object<'a>(cx: &Context<'a>, index: u16) -> Option<&'a canopener_eds::Object> {
    cx.eds.object(index).filter(|o| o.origin != Origin::Orphan)
}

/// `1018sub1` or `1000h`.
pub(crate) fn entry_name(index: u16, sub: Option<u8>) -> String {
    match sub {
        Some(sub) => format!("{index:X}sub{sub:X}"),
        None => format!("{index:X}h"),
    }
}

/// A value as written, or `missing`.
pub(crate) fn written(text: Option<&str>) -> &str {
    text.map_or("missing", str::trim)
}

/// `UNSIGNED16` or `type 0x0042`.
pub(crate) fn type_name(data_type: DataType) -> String {
    data_type
        .name()
        .map_or_else(|| format!("type 0x{:04X}", data_type.0), str::to_owned)
}

/// A finding about an object (`sub` = `None`) or sub-object, pointing at what is written: the
/// sub-object's section; for a `CompactSubObj` entry the object's section (or its `[xxxxValue]`
/// entry for a DCF value); for objects implied by `CompactPDO` the `[DeviceInfo] CompactPDO` entry.
pub(crate) fn object_finding(
    cx: &Context<'_>,
    info: &CheckInfo,
    index: u16,
    sub: Option<u8>,
    key: Option<&str>,
    message: impl Into<String>,
) -> Finding {
    let object = cx.eds.object(index);
    let sub_object = sub.and_then(|s| object?.subs.get(&s));
    let origin = sub_object.map_or(object.map(|o| o.origin), |s| Some(s.origin));
    if origin == Some(Origin::CompactPdo) || object.is_some_and(|o| o.origin == Origin::CompactPdo) {
        return cx.finding(info, SectionKind::DeviceInfo, Some("CompactPDO"), message);
    }
    if let Some(s) = sub {
        let kind = SectionKind::Sub(index, s);
        if cx.has_section(kind) {
            return cx.finding(info, kind, key, message);
        }
        if origin == Some(Origin::CompactSubObj) {
            let value_kind = SectionKind::Companion(index, Companion::Value);
            let entry = s.to_string();
            if key == Some("ParameterValue") && cx.entry(value_kind, &entry).is_some() {
                return cx.finding(info, value_kind, Some(&entry), message);
            }
            return cx.finding(info, SectionKind::Object(index), key, message);
        }
    }
    let kind = SectionKind::Object(index);
    if cx.has_section(kind) {
        return cx.finding(info, kind, if sub.is_none() { key } else { None }, message);
    }
    cx.file_finding(info, message)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strict_integers_follow_cia_306() {
        assert_eq!(strict_int("0x00000ABC"), Some(2748));
        assert_eq!(strict_int("2748"), Some(2748));
        assert_eq!(strict_int("012"), Some(10));
        assert_eq!(strict_int("0"), Some(0));
        assert_eq!(strict_int("8 ; bits"), Some(8));
        for bad in ["FEh", "08", "1.0", "", "e-RIO 8xx", "0x"] {
            assert_eq!(strict_int(bad), None, "{bad}");
        }
    }
}

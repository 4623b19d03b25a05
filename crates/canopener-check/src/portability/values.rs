//! Values the tools read differently: numbers with leading zeros or an `h` suffix, `$NODEID`
//! formulas, out-of-range unsigned values, two's complement limits, REAL notations, backslashes in
//! strings, and AccessType tokens.

use canopener_eds::value::{self, Radix, RealNotation, Value, range_of};
use canopener_eds::{DataType, TypeKind};

use super::checks::{
    ACCESS_TYPE_TOKEN, HEX_SUFFIX, LEADING_ZERO, NODEID_COMPOUND, NODEID_SUFFIX, REAL_BIT_PATTERN,
    REAL_DECIMAL, SIGNED_LIMIT_BITS, STRING_BACKSLASH, UNSIGNED_OVERFLOW,
};
use super::tools::{DCFCHK, EDITOR, HOST, Key, PY, Site, at_value, lely_value, views};
use crate::context::Context;
use crate::finding::Finding;

/// The typed value keys of an object or sub-object section.
const VALUE_KEYS: [Key; 4] = [
    Key::DefaultValue,
    Key::ParameterValue,
    Key::LowLimit,
    Key::HighLimit,
];

/// Integer attribute keys python canopen reads with `int(x, 0)` (SubNumber, CompactSubObj and
/// ObjFlags it does not read as numbers, so every tool agrees on them).
const PYTHON_INT_KEYS: [Key; 3] = [Key::DataType, Key::ObjectType, Key::PdoMapping];

/// The checks of one object or sub-object section.
pub(super) fn site(cx: &Context<'_>, site: &Site<'_>, out: &mut Vec<Finding>) {
    let data_type = site.data_type;
    for key in VALUE_KEYS {
        let Some((line, text)) = site.entry(key) else {
            continue;
        };
        let key = key.name();
        // The inline comment is T020's business; judge the number the writer meant.
        let text = lely_value(text);
        if text.is_empty() {
            continue;
        }
        let at = |message: String| at_value(cx, &LEADING_ZERO, site.name, line, message);
        match data_type.and_then(DataType::kind) {
            Some(kind @ (TypeKind::Signed(_) | TypeKind::Unsigned(_) | TypeKind::Boolean)) => {
                if let Some(message) = leading_zero(text, key) {
                    out.push(at(message));
                }
                integer_checks(cx, site, line, key, text, kind, data_type, out);
            }
            Some(TypeKind::Real32 | TypeKind::Real64) if is_value_key(key) => {
                real_checks(cx, site, line, text, data_type, out);
            }
            Some(TypeKind::VisibleString) if is_value_key(key) && text.contains('\\') => {
                out.push(at_value(
                    cx,
                    &STRING_BACKSLASH,
                    site.name,
                    line,
                    format!(
                        "{key} `{text}` contains a backslash: Lely processes it as a C escape sequence, so \
                         the string changes there; {EDITOR} unescapes it when sizing the string; {PY} keeps \
                         it"
                    ),
                ));
            }
            _ => {}
        }
    }
    for key in PYTHON_INT_KEYS {
        if key == Key::ObjectType && site.sub.is_some() {
            continue;
        }
        let Some((line, text)) = site.entry(key) else {
            continue;
        };
        let key = key.name();
        if let Some(message) = leading_zero(lely_value(text), key) {
            out.push(at_value(cx, &LEADING_ZERO, site.name, line, message));
        }
    }
    access_type(cx, site, out);
}

fn is_value_key(key: &str) -> bool {
    key == "DefaultValue" || key == "ParameterValue"
}

/// T003: what each tool makes of `0254`, or `None` when the text has no leading zero.
fn leading_zero(text: &str, key: &str) -> Option<String> {
    let (negative, digits) = match text.strip_prefix('-') {
        Some(rest) => (true, rest),
        None => (false, text.strip_prefix('+').unwrap_or(text)),
    };
    let zero_padded = digits.len() > 1
        && digits.len() <= 30
        && digits.starts_with('0')
        && digits.bytes().all(|b| b.is_ascii_digit())
        && !digits.bytes().all(|b| b == b'0');
    if !zero_padded {
        return None;
    }
    let sign = if negative { -1 } else { 1 };
    let decimal = digits.parse::<i128>().ok()? * sign;
    let octal = i128::from_str_radix(digits, 8).ok().map(|v| v * sign);
    let is_value = is_value_key(key);
    let python = if is_value {
        format!("{PY} silently reads None (int(x, 0) rejects leading zeros)")
    } else if key == "LowLimit" || key == "HighLimit" {
        format!("{PY} cannot read it (int(x, 0) raises ValueError on leading zeros)")
    } else {
        format!("{PY} fails to import the file (int(x, 0) raises ValueError on leading zeros)")
    };
    let dcfchk = if is_value {
        format!("{DCFCHK} crashes (ValueError)")
    } else {
        String::new()
    };
    let readers = match (octal, is_value) {
        (Some(o), true) if o == decimal => format!("Lely's loader, {EDITOR} and {HOST} read {decimal}"),
        (Some(o), false) if o == decimal => format!("Lely's loader and {EDITOR} read {decimal}"),
        (Some(o), true) => {
            format!("CiA 306, Lely's loader and {EDITOR} read octal {o}, but {HOST} reads decimal {decimal}")
        }
        (Some(o), false) => format!("CiA 306, Lely's loader and {EDITOR} read octal {o}"),
        (None, true) => {
            format!("{HOST} reads decimal {decimal}; it is not octal, so CiA 306 does not define it")
        }
        (None, false) => "it is not octal, so CiA 306 does not define it".to_owned(),
    };
    Some(format!(
        "{key} `{text}` has a leading zero: {}",
        views(&[readers, python, dcfchk])
    ))
}

#[allow(clippy::too_many_arguments)]
fn integer_checks(
    cx: &Context<'_>,
    site: &Site<'_>,
    line: usize,
    key: &str,
    text: &str,
    kind: TypeKind,
    data_type: Option<DataType>,
    out: &mut Vec<Finding>,
) {
    let at = |info, message: String| at_value(cx, info, site.name, line, message);
    if value::mentions_nodeid(text) {
        if let Some((suffix, message)) = nodeid_formula(text) {
            out.push(at(
                if suffix { &NODEID_SUFFIX } else { &NODEID_COMPOUND },
                message,
            ));
        }
        return;
    }
    let is_value = is_value_key(key);
    if is_value && is_h_suffixed(text) {
        out.push(at(
            &HEX_SUFFIX,
            format!(
                "{key} `{text}` uses an h suffix: {PY} silently reads None; {DCFCHK} reports it; {HOST} \
                 rejects the whole file; {EDITOR} keeps the text"
            ),
        ));
        return;
    }
    let Some(literal) = value::parse_integer(text, &mut Vec::new()) else {
        return;
    };
    let type_name = data_type.map_or_else(String::new, |t| t.to_string());
    match kind {
        TypeKind::Unsigned(bits) if is_value && bits <= 64 => {
            let (_, max) = range_of(bits, false);
            if literal.value > max {
                let truncated = literal.value & max;
                out.push(at(
                    &UNSIGNED_OVERFLOW,
                    format!(
                        "{key} `{text}` is above the {type_name} maximum {max}: {HOST} silently truncates it \
                         to {truncated}; {PY} accepts {}; {DCFCHK} reports an overflow; {EDITOR} keeps the \
                         text",
                        literal.value
                    ),
                ));
            }
        }
        TypeKind::Signed(bits) if !is_value && bits <= 64 && literal.radix != Radix::Decimal => {
            let (_, max) = range_of(bits, true);
            if literal.value > max && literal.value < (1i128 << bits) {
                let wrapped = literal.value - (1i128 << bits);
                out.push(at(
                    &SIGNED_LIMIT_BITS,
                    format!(
                        "{key} `{text}` of an {type_name} is an unsigned bit pattern: {PY} reads two's \
                         complement {wrapped}; {DCFCHK} range-checks it as +{} and reports a false overflow",
                        literal.value
                    ),
                ));
            }
        }
        _ => {}
    }
}

/// `FEh`: hex digits followed by `h`, without a `0x` prefix.
fn is_h_suffixed(text: &str) -> bool {
    text.strip_suffix(['h', 'H'])
        .is_some_and(|digits| !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_hexdigit()))
}

/// T004/T005: `(is_suffix, message)` for a formula that is not `$NODEID+offset`.
fn nodeid_formula(text: &str) -> Option<(bool, String)> {
    let terms: Vec<&str> = text.split('+').map(str::trim).collect();
    let node_terms = terms.iter().filter(|t| t.eq_ignore_ascii_case("$NODEID")).count();
    if node_terms != 1 || terms.iter().any(|t| t.is_empty()) {
        return None;
    }
    let node_last = terms.last().is_some_and(|t| t.eq_ignore_ascii_case("$NODEID"));
    match terms.len() {
        2 if node_last => Some((
            true,
            format!(
                "`{text}` puts $NODEID last: {PY} and {EDITOR} accept it as node-ID + {}; {DCFCHK} rejects \
                 it as an invalid value (CiA 306 wants $NODEID first)",
                terms.first().copied().unwrap_or_default()
            ),
        )),
        n if n >= 3 => Some((
            false,
            format!(
                "`{text}` has {} terms: {PY} silently reads None; Lely rejects it; {HOST} adds all terms; \
                 {EDITOR} keeps the text and would reject it when exporting",
                n
            ),
        )),
        _ => None,
    }
}

fn real_checks(
    cx: &Context<'_>,
    site: &Site<'_>,
    line: usize,
    text: &str,
    data_type: Option<DataType>,
    out: &mut Vec<Finding>,
) {
    let Some(data_type) = data_type else { return };
    let Some(Value::Real { value, notation }) = value::parse_value(text, data_type).value else {
        return;
    };
    let key = cx.document.entry(line).map_or("", |(k, _)| k);
    let at = |info, message: String| at_value(cx, info, site.name, line, message);
    let is32 = data_type == DataType::REAL32;
    match notation {
        RealNotation::BitPattern => {
            // A REAL32 value is an f32; printing it as one avoids digits the pattern does not hold.
            let shown = if is32 {
                format!("{:?}", value as f32)
            } else {
                format!("{value:?}")
            };
            out.push(at(
                &REAL_BIT_PATTERN,
                format!(
                    "{key} `{text}` is an IEEE 754 bit pattern ({shown}): Lely reads {shown}; {PY} silently \
                     reads None; {HOST} rejects the file; {EDITOR} keeps the text"
                ),
            ));
        }
        RealNotation::Decimal if text.contains(['.', 'e', 'E']) => out.push(at(
            &REAL_DECIMAL,
            format!(
                "{key} `{text}` is decimal: {PY} and {HOST} read {text}; {DCFCHK} reports it as invalid, \
                 since Lely reads REAL values as IEEE 754 bit patterns; {EDITOR} keeps the text"
            ),
        )),
        RealNotation::Decimal => {
            let Ok(bits) = text.parse::<u64>() else { return };
            if bits == 0 {
                return;
            }
            let lely = if is32 {
                u32::try_from(bits)
                    .ok()
                    .map(|b| format!("{:e}", f32::from_bits(b)))
            } else {
                Some(format!("{:e}", f64::from_bits(bits)))
            };
            let lely = lely.map_or_else(
                || "does not fit a 32-bit pattern".to_owned(),
                |v| format!("is the bit pattern 0x{bits:X} = {v}"),
            );
            out.push(at(
                &REAL_DECIMAL,
                format!(
                    "{key} `{text}` is an integer text: {PY} and {HOST} read {bits}.0, but Lely reads REAL \
                     values as IEEE 754 bit patterns, where it {lely}"
                ),
            ));
        }
    }
}

/// T016: an AccessType token none of the tools agree on.
fn access_type(cx: &Context<'_>, site: &Site<'_>, out: &mut Vec<Finding>) {
    let Some(raw) = site.attributes.access_type.as_deref() else {
        return;
    };
    if raw.trim().is_empty() || site.attributes.access_type().is_some() {
        return;
    }
    let Some(line) = site.line(Key::AccessType) else {
        return;
    };
    out.push(at_value(
        cx,
        &ACCESS_TYPE_TOKEN,
        site.name,
        line,
        format!(
            "AccessType `{raw}` is not a CiA 306 token: {PY} accepts it verbatim; {DCFCHK} reports it; \
             {HOST} rejects the file; {EDITOR} leaves the entry with an empty value and only prints a \
             console line"
        ),
    ));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn leading_zero_messages_name_each_reading() {
        let m = leading_zero("0254", "DefaultValue").unwrap_or_default();
        assert!(
            m.contains("octal 172") && m.contains("decimal 254") && m.contains("None"),
            "{m}"
        );
        let m = leading_zero("007", "DataType").unwrap_or_default();
        assert!(m.contains("read 7") && m.contains("fails to import"), "{m}");
        let m = leading_zero("089", "DefaultValue").unwrap_or_default();
        assert!(m.contains("decimal 89") && m.contains("not octal"), "{m}");
        assert_eq!(leading_zero("00", "DefaultValue"), None);
        assert_eq!(leading_zero("0", "DefaultValue"), None);
        assert_eq!(leading_zero("0x0A", "DefaultValue"), None);
    }

    #[test]
    fn nodeid_forms() {
        assert!(matches!(nodeid_formula("0x180+$NODEID"), Some((true, _))));
        assert!(matches!(
            nodeid_formula("0x40000000+$NODEID+0x180"),
            Some((false, _))
        ));
        assert!(matches!(nodeid_formula("$NODEID+0x100+0x80"), Some((false, _))));
        assert_eq!(nodeid_formula("$NODEID+0x180"), None);
        assert_eq!(nodeid_formula("$NODEID + 0x180"), None);
        assert_eq!(nodeid_formula("$NODEID+$NODEID"), None);
    }

    #[test]
    fn h_suffix() {
        assert!(is_h_suffixed("FEh") && is_h_suffixed("10H"));
        assert!(!is_h_suffixed("h") && !is_h_suffixed("0xFE") && !is_h_suffixed("Gh"));
    }
}

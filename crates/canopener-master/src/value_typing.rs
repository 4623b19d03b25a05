//! How a master types the value of an SDO transfer: by a type the user chose, by the entry's
//! `DataType` in an EDS, or (reads only) by the length the device answered with; and what an EDS says
//! about an entry (name, access type, limits) that a write should warn about. The device decides;
//! these are warnings.

use canopener_eds::value::{Value, parse_value};
use canopener_eds::{AccessType, DataType, Eds};

use crate::sdo_client::Protocol;
use crate::value::{DisplayValue, ValueType};

/// What an EDS says about one entry (a VAR, or one sub-object of an ARRAY or RECORD).
#[derive(Debug, Clone)]
pub struct EdsEntry {
    /// `ParameterName`.
    pub name: String,
    /// `DataType`, resolved through DEFTYPE objects.
    pub data_type: Option<DataType>,
    /// `AccessType`.
    pub access: Option<AccessType>,
    /// `LowLimit` as written.
    pub low_limit: Option<String>,
    /// `HighLimit` as written.
    pub high_limit: Option<String>,
}

/// Where the type of a value came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TypeSource {
    /// Chosen by the user.
    Option,
    /// The entry's `DataType` in an EDS.
    Eds,
    /// The length of the value read.
    Guessed,
}

impl TypeSource {
    /// `option`, `eds` or `guessed`, as reports say it.
    pub fn as_str(self) -> &'static str {
        match self {
            TypeSource::Option => "option",
            TypeSource::Eds => "eds",
            TypeSource::Guessed => "guessed",
        }
    }
}

/// The entry `index`:`sub` of an EDS: a VAR or DOMAIN object is sub-index 0, otherwise the sub-object.
pub fn eds_entry(eds: &Eds, index: u16, sub: u8) -> Option<EdsEntry> {
    let object = eds.object(index)?;
    let attributes = if object.subs.is_empty() {
        (sub == 0).then_some(&object.attributes)?
    } else {
        &object.subs.get(&sub)?.attributes
    };
    Some(EdsEntry {
        name: attributes.parameter_name.clone().unwrap_or_default(),
        data_type: attributes.data_type().map(|t| eds.resolve_data_type(t)),
        access: attributes.access_type(),
        low_limit: attributes.low_limit.clone(),
        high_limit: attributes.high_limit.clone(),
    })
}

/// The type to read and write values of an EDS data type as; types without a text form
/// (TIME_OF_DAY, UNICODE_STRING, records, unknown) as hex bytes.
pub fn value_type_of(data_type: Option<DataType>) -> ValueType {
    data_type
        .and_then(ValueType::from_data_type)
        .unwrap_or(ValueType::Bytes)
}

/// The type of a value read without a type chosen or an EDS: 1, 2, 4 or 8 bytes are an unsigned number of
/// that width, printable text is a string, anything else hex bytes.
pub fn guess_type(data: &[u8]) -> ValueType {
    match data.len() {
        1 => ValueType::U8,
        2 => ValueType::U16,
        4 => ValueType::U32,
        8 => ValueType::U64,
        _ if is_printable(data) => ValueType::Str,
        _ => ValueType::Bytes,
    }
}

/// Text a person can read: UTF-8 without control characters other than tab, CR and LF; trailing NULs
/// (a fixed-size string buffer's padding) allowed.
pub fn is_printable(data: &[u8]) -> bool {
    let text = without_trailing_zeros(data);
    !text.is_empty()
        && std::str::from_utf8(text).is_ok_and(|text| {
            text.chars()
                .all(|c| !c.is_control() || matches!(c, '\t' | '\r' | '\n'))
        })
}

/// `items` without the zeros at its end: a fixed-size string buffer's padding.
pub(crate) fn without_trailing_zeros<T: Default + PartialEq>(items: &[T]) -> &[T] {
    let mut rest = items;
    while let [head @ .., last] = rest
        && *last == T::default()
    {
        rest = head;
    }
    rest
}

/// Decodes `data` as `ty`; a length the type does not take gives hex bytes and a warning for stderr.
pub fn decode(ty: ValueType, data: &[u8]) -> (ValueType, DisplayValue, Option<String>) {
    match ty.decode(data) {
        Ok(value) => (ty, value, None),
        Err(err) => (
            ValueType::Bytes,
            DisplayValue::Bytes(data.to_vec()),
            Some(format!("{err}; shown as hex bytes")),
        ),
    }
}

/// The bytes of a fixed-size value in an expedited answer that indicates more bytes than the type has
/// (a server that always says 4, as some do, CiA 301 §7.2.4.3.6): the type's bytes, and a warning
/// about the rest.
pub fn expedited_value(ty: ValueType, data: &[u8], protocol: Protocol) -> (&[u8], Option<String>) {
    match ty.byte_len() {
        Some(len) if protocol == Protocol::Expedited && len < data.len() => {
            let (value, padding) = data.split_at_checked(len).unwrap_or((data, &[]));
            (
                value,
                Some(format!(
                    "the device sent {} bytes for a {ty} of {len}; the rest ({}) is taken as padding",
                    data.len(),
                    padding
                        .iter()
                        .map(|byte| format!("{byte:02X}"))
                        .collect::<String>()
                )),
            )
        }
        _ => (data, None),
    }
}

/// What the EDS says against writing `value` to `entry`: read-only access, or a value outside
/// LowLimit..HighLimit. The device decides; these are warnings.
pub fn write_warnings(entry: &EdsEntry, value: &DisplayValue, node: u8) -> Vec<String> {
    let mut warnings = Vec::new();
    if let Some(access) = entry.access
        && !access.writable()
    {
        warnings.push(format!(
            "the EDS gives AccessType={}: the device will probably refuse the write",
            access.as_str()
        ));
    }
    let Some(data_type) = entry.data_type else {
        return warnings;
    };
    for (key, limit, below) in [
        ("LowLimit", entry.low_limit.as_deref(), true),
        ("HighLimit", entry.high_limit.as_deref(), false),
    ] {
        let Some(text) = limit.filter(|text| !text.trim().is_empty()) else {
            continue;
        };
        let Some(limit) = parse_value(text, data_type).value else {
            continue;
        };
        let outside = match compare(value, &limit, node) {
            Some(std::cmp::Ordering::Less) => below,
            Some(std::cmp::Ordering::Greater) => !below,
            _ => false,
        };
        if outside {
            warnings.push(format!(
                "{} is {} the EDS's {key}={text}",
                value.plain(),
                if below { "below" } else { "above" }
            ));
        }
    }
    warnings
}

/// How a value compares with an EDS limit, if both are numbers.
fn compare(value: &DisplayValue, limit: &Value, node: u8) -> Option<std::cmp::Ordering> {
    match limit {
        Value::Real { value: limit, .. } => value.as_f64()?.partial_cmp(limit),
        _ => {
            let limit = limit.resolve(node)?;
            let value = match value {
                DisplayValue::Unsigned { value, .. } => i128::from(*value),
                DisplayValue::Signed { value, .. } => i128::from(*value),
                DisplayValue::Bool(value) => i128::from(*value),
                _ => return None,
            };
            Some(value.cmp(&limit))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const EDS: &str = "[FileInfo]\nFileName=t.eds\n[1017]\nParameterName=Producer heartbeat time\n\
        DataType=0x0006\nAccessType=rw\nDefaultValue=0\n\
        [1018]\nParameterName=Identity\nObjectType=0x9\nSubNumber=2\n\
        [1018sub0]\nParameterName=Highest\nDataType=0x0005\nAccessType=ro\nDefaultValue=1\n\
        [1018sub1]\nParameterName=Vendor-ID\nDataType=0x0007\nAccessType=ro\nDefaultValue=0x2BC\n\
        [2000]\nParameterName=Filter\nDataType=0x0003\nAccessType=rw\nLowLimit=-10\nHighLimit=$NODEID+0x10\n\
        DefaultValue=0\n[2001]\nParameterName=Gain\nDataType=0x0008\nAccessType=rw\nLowLimit=0.5\nDefaultValue=1.0\n";

    fn eds() -> Eds {
        canopener_eds::load(EDS.as_bytes()).eds
    }

    #[test]
    fn entries_are_vars_at_sub_0_or_sub_objects() {
        let eds = eds();
        let heartbeat = eds_entry(&eds, 0x1017, 0).unwrap();
        assert_eq!(heartbeat.name, "Producer heartbeat time");
        assert_eq!(heartbeat.data_type, Some(DataType::UNSIGNED16));
        assert_eq!(value_type_of(heartbeat.data_type), ValueType::U16);
        assert!(eds_entry(&eds, 0x1017, 1).is_none());
        let vendor = eds_entry(&eds, 0x1018, 1).unwrap();
        assert_eq!(vendor.name, "Vendor-ID");
        assert_eq!(vendor.access, Some(AccessType::Ro));
        assert!(eds_entry(&eds, 0x1018, 2).is_none());
        assert!(eds_entry(&eds, 0x6000, 0).is_none());
        assert_eq!(value_type_of(Some(DataType::TIME_OF_DAY)), ValueType::Bytes);
    }

    #[test]
    fn lengths_guess_the_type() {
        assert_eq!(guess_type(&[1]), ValueType::U8);
        assert_eq!(guess_type(&[1, 2]), ValueType::U16);
        assert_eq!(guess_type(b"abcd"), ValueType::U32);
        assert_eq!(guess_type(&[0; 8]), ValueType::U64);
        assert_eq!(guess_type(b"canopener"), ValueType::Str);
        assert_eq!(guess_type(b"dev\0\0\0"), ValueType::Str);
        assert_eq!(guess_type(&[1, 2, 3]), ValueType::Bytes);
        assert_eq!(guess_type(&[]), ValueType::Bytes);
        assert_eq!(guess_type(&[0xFF, 0xFE, 0x41]), ValueType::Bytes);
    }

    #[test]
    fn wrong_lengths_decode_as_bytes_with_a_warning() {
        let (ty, value, warning) = decode(ValueType::U16, &[0xE8, 0x03]);
        assert_eq!(
            (ty, value.to_string(), warning),
            (ValueType::U16, "1000 (0x03E8)".to_owned(), None)
        );
        let (ty, value, warning) = decode(ValueType::U16, &[1, 2, 3]);
        assert_eq!(ty, ValueType::Bytes);
        assert_eq!(value.to_string(), "01 02 03");
        assert!(warning.unwrap().contains("u16 takes 2 byte(s), got 3"));
    }

    #[test]
    fn expedited_padding_beyond_the_type_is_dropped_with_a_warning() {
        let data = [0x2A, 0, 0, 0];
        let (bytes, warning) = expedited_value(ValueType::U8, &data, Protocol::Expedited);
        assert_eq!(bytes, [0x2A]);
        assert!(
            warning
                .unwrap()
                .contains("4 bytes for a u8 of 1; the rest (000000)")
        );
        assert_eq!(
            expedited_value(ValueType::U8, &data, Protocol::Segmented),
            (&data[..], None)
        );
        assert_eq!(
            expedited_value(ValueType::U32, &data, Protocol::Expedited),
            (&data[..], None)
        );
        assert_eq!(
            expedited_value(ValueType::Str, &data, Protocol::Expedited),
            (&data[..], None)
        );
    }

    #[test]
    fn writes_warn_about_read_only_entries_and_limits() {
        let eds = eds();
        let vendor = eds_entry(&eds, 0x1018, 1).unwrap();
        let warnings = write_warnings(&vendor, &DisplayValue::Unsigned { value: 1, bits: 32 }, 5);
        assert_eq!(warnings.len(), 1);
        assert!(warnings[0].contains("AccessType=ro"), "{warnings:?}");

        let filter = eds_entry(&eds, 0x2000, 0).unwrap();
        let at = |value: i64| write_warnings(&filter, &DisplayValue::Signed { value, bits: 16 }, 5);
        assert!(at(0).is_empty());
        assert!(
            at(-11)[0].contains("below the EDS's LowLimit=-10"),
            "{:?}",
            at(-11)
        );
        // HighLimit $NODEID+0x10 is 21 for node 5.
        assert!(at(21).is_empty());
        assert!(at(22)[0].contains("above the EDS's HighLimit=$NODEID+0x10"));

        let gain = eds_entry(&eds, 0x2001, 0).unwrap();
        assert!(write_warnings(&gain, &DisplayValue::Real32(0.25), 5)[0].contains("below"));
        assert!(write_warnings(&gain, &DisplayValue::Real32(0.75), 5).is_empty());
    }
}

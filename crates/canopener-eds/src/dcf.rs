//! EDS → DCF for one node, and DCF → EDS (CiA 306 §5).
//!
//! A DCF is the EDS of a device plus its configuration: `[DeviceComissioning]` with the node-ID and bit
//! rate, `LastEDS` naming the template, and a `ParameterValue` on every entry with a value. Values in a
//! DCF are concrete: `$NODEID` formulas are resolved for the node (the `DefaultValue` keeps the formula,
//! so the EDS can be regenerated). Going back drops exactly the DCF additions.

use crate::model::{Attributes, DeviceCommissioning, DeviceInfo, Eds, Origin};
use crate::types::DataType;
use crate::value::{Radix, Value, parse_value};

/// The bit rates CiA 306 names in `[DeviceInfo] BaudRate_*` and `[DeviceComissioning] Baudrate`, in kbit/s:
/// those of [`DeviceInfo::BAUD_RATE_KEYS`].
#[allow(
    clippy::indexing_slicing,
    reason = "const evaluation: an index out of bounds fails the build, it cannot panic at run time"
)]
pub const BITRATES_KBIT: [u16; 8] = {
    let keys = DeviceInfo::BAUD_RATE_KEYS;
    let mut rates = [0; 8];
    let mut i = 0;
    while i < rates.len() {
        rates[i] = keys[i].0;
        i += 1;
    }
    rates
};

/// Why an EDS cannot become a DCF as asked.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DcfError {
    /// The node-ID is outside 1..=127.
    #[error("node-ID {0} is outside 1..=127 (CiA 301 §7.3.1)")]
    NodeId(u16),
    /// The bit rate is not one CiA 306 can express.
    #[error("bit rate {0} kbit/s is not one of 10, 20, 50, 125, 250, 500, 800 or 1000")]
    Bitrate(u16),
}

/// A DCF of `eds` for node `node_id` at `bitrate_kbit`.
///
/// `ParameterValue` is set on every explicit entry that has a `DefaultValue` and no value yet, with
/// `$NODEID` resolved; existing parameter values are kept. Returns the DCF and the bit rates the EDS
/// does not claim to support (`BaudRate_<k>=1` missing), for the caller to warn about.
pub fn to_dcf(eds: &Eds, node_id: u16, bitrate_kbit: u16) -> Result<Eds, DcfError> {
    let node = u8::try_from(node_id)
        .ok()
        .filter(|n| (1..=127).contains(n))
        .ok_or(DcfError::NodeId(node_id))?;
    if !BITRATES_KBIT.contains(&bitrate_kbit) {
        return Err(DcfError::Bitrate(bitrate_kbit));
    }
    let mut dcf = eds.clone();
    if dcf.file_info.last_eds.is_none() {
        dcf.file_info.last_eds = eds.file_info.file_name.clone();
    }
    let mut commissioning = dcf.commissioning.take().unwrap_or_default();
    commissioning.node_id = Some(node.to_string());
    commissioning.baudrate = Some(bitrate_kbit.to_string());
    dcf.commissioning = Some(commissioning);
    let types: Vec<(u16, Option<DataType>)> = dcf
        .objects
        .iter()
        .map(|(i, o)| (*i, o.attributes.data_type().map(|t| eds.resolve_data_type(t))))
        .collect();
    for (index, object_type) in types {
        let Some(object) = dcf.objects.get_mut(&index) else {
            continue;
        };
        if object.origin != Origin::Explicit {
            continue;
        }
        if object.subs.is_empty() {
            configure(&mut object.attributes, object_type, node);
        }
        for sub in object.subs.values_mut().filter(|s| s.origin == Origin::Explicit) {
            let t = sub.attributes.data_type().map(|t| eds.resolve_data_type(t));
            configure(&mut sub.attributes, t, node);
        }
    }
    Ok(dcf)
}

/// Whether a description already is a configuration: a DCF ([`Eds::is_dcf`]), or any entry carries a
/// `ParameterValue` or `Denotation` (an XDC read back, an EDS with DCF keys).
pub fn is_configuration(eds: &Eds) -> bool {
    let configured = |a: &Attributes| {
        [&a.parameter_value, &a.denotation]
            .into_iter()
            .any(|v| v.as_deref().is_some_and(|v| !v.trim().is_empty()))
    };
    eds.is_dcf()
        || eds
            .objects
            .values()
            .any(|o| configured(&o.attributes) || o.subs.values().any(|s| configured(&s.attributes)))
}

/// A configuration ([`is_configuration`]) written as a DCF again: its values exactly as they are (an
/// entry without `ParameterValue` stays without one: the configuration did not set it), with the
/// node-ID and bit rate replaced only where given. [`to_dcf`] instead makes a configuration from a
/// template, filling every value from its default.
pub fn recommission(dcf: &Eds, node_id: Option<u16>, bitrate_kbit: Option<u16>) -> Result<Eds, DcfError> {
    let mut dcf = dcf.clone();
    if let Some(node_id) = node_id {
        if !(1..=127).contains(&node_id) {
            return Err(DcfError::NodeId(node_id));
        }
        dcf.commissioning
            .get_or_insert_with(DeviceCommissioning::default)
            .node_id = Some(node_id.to_string());
    }
    if let Some(bitrate) = bitrate_kbit {
        if !BITRATES_KBIT.contains(&bitrate) {
            return Err(DcfError::Bitrate(bitrate));
        }
        dcf.commissioning
            .get_or_insert_with(DeviceCommissioning::default)
            .baudrate = Some(bitrate.to_string());
    }
    Ok(dcf)
}

/// Whether the EDS marks a bit rate as supported (`BaudRate_<k>=1`).
pub fn supports_bitrate(eds: &Eds, bitrate_kbit: u16) -> bool {
    eds.device_info
        .get(&format!("BaudRate_{bitrate_kbit}"))
        .and_then(crate::model::int_of)
        == Some(1)
}

/// The EDS a DCF was made from: the DCF additions removed (commissioning, `LastEDS`, parameter values,
/// denotations, upload/download files, `[xxxxValue]`, `[xxxxDenotation]`, `[ConnectedModules]`).
pub fn to_eds(dcf: &Eds) -> Eds {
    let mut eds = dcf.clone();
    eds.commissioning = None;
    eds.connected_modules = None;
    eds.file_info.last_eds = None;
    let strip = |a: &mut Attributes| {
        a.parameter_value = None;
        a.denotation = None;
        a.upload_file = None;
        a.download_file = None;
    };
    for object in eds.objects.values_mut() {
        strip(&mut object.attributes);
        object.values = None;
        object.denotations = None;
        for sub in object.subs.values_mut() {
            strip(&mut sub.attributes);
        }
    }
    for module in eds.modules.values_mut() {
        for object in module.fixed.values_mut().chain(module.sub_ext.values_mut()) {
            strip(&mut object.attributes);
            for sub in object.subs.values_mut() {
                strip(&mut sub.attributes);
            }
        }
    }
    eds
}

/// What [`to_eds`] removes from `dcf`, one item per key or section as `eds diff` names them
/// (`[1017] ParameterValue`, `[DeviceComissioning]`), in object order: for a message that says what
/// a conversion to EDS dropped instead of dropping it silently.
pub fn configuration_keys(dcf: &Eds) -> Vec<String> {
    let mut keys = Vec::new();
    if dcf.commissioning.is_some() {
        keys.push("[DeviceComissioning]".to_owned());
    }
    if dcf
        .file_info
        .last_eds
        .as_deref()
        .is_some_and(|s| !s.trim().is_empty())
    {
        keys.push("[FileInfo] LastEDS".to_owned());
    }
    if dcf.connected_modules.is_some() {
        keys.push("[ConnectedModules]".to_owned());
    }
    let mut named = |section: String, a: &Attributes| {
        let values = [
            ("ParameterValue", &a.parameter_value),
            ("Denotation", &a.denotation),
            ("UploadFile", &a.upload_file),
            ("DownloadFile", &a.download_file),
        ];
        for (key, value) in values {
            if value.is_some() {
                keys.push(format!("[{section}] {key}"));
            }
        }
    };
    for (index, object) in &dcf.objects {
        named(format!("{index:04X}"), &object.attributes);
        for (sub, entry) in &object.subs {
            named(format!("{index:04X}sub{sub:X}"), &entry.attributes);
        }
    }
    for (index, object) in &dcf.objects {
        if object.values.is_some() {
            keys.push(format!("[{index:04X}Value]"));
        }
        if object.denotations.is_some() {
            keys.push(format!("[{index:04X}Denotation]"));
        }
    }
    keys
}

fn configure(a: &mut Attributes, data_type: Option<DataType>, node: u8) {
    if a.parameter_value.is_some() {
        return;
    }
    let Some(default) = a.default_value.as_deref().filter(|d| !d.trim().is_empty()) else {
        return;
    };
    let value = match data_type.map(|t| parse_value(default, t).value) {
        Some(Some(Value::NodeRelative { .. })) => {
            let resolved = data_type
                .and_then(|t| parse_value(default, t).value)
                .and_then(|v| v.resolve(node));
            match resolved {
                Some(v) => Value::Integer {
                    value: v,
                    radix: Radix::Hex,
                }
                .to_string(),
                None => default.to_owned(),
            }
        }
        _ => default.to_owned(),
    };
    a.parameter_value = Some(value);
}

/// Makes a default commissioning section (node-ID and bit rate only).
pub fn commissioning(node_id: u8, bitrate_kbit: u16) -> DeviceCommissioning {
    DeviceCommissioning {
        node_id: Some(node_id.to_string()),
        baudrate: Some(bitrate_kbit.to_string()),
        ..DeviceCommissioning::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::load;

    const EDS: &str = "[FileInfo]\nFileName=dev.eds\n[DeviceInfo]\nBaudRate_250=1\n\
        [1800]\nParameterName=TPDO1\nObjectType=0x9\nSubNumber=2\n\
        [1800sub0]\nParameterName=n\nDataType=0x0005\nAccessType=ro\nDefaultValue=1\n\
        [1800sub1]\nParameterName=COB-ID\nDataType=0x0007\nAccessType=rw\nDefaultValue=$NODEID+0x180\n\
        [1017]\nParameterName=HB\nDataType=0x0006\nAccessType=rw\nDefaultValue=0\nParameterValue=100\n";

    /// A configuration written as a DCF again keeps its values as they are (issue 13: every default
    /// became a ParameterValue), takes a node-ID or bit rate only when given, and is what it was.
    #[test]
    fn a_configuration_is_recommissioned_not_refilled() {
        let eds = load(EDS.as_bytes()).eds;
        assert!(is_configuration(&eds), "1017h has a ParameterValue");
        let same = recommission(&eds, None, None).unwrap();
        assert_eq!(same, eds);
        assert_eq!(same.objects[&0x1800].subs[&1].attributes.parameter_value, None);
        let moved = recommission(&eds, Some(9), Some(500)).unwrap();
        let commissioning = moved.commissioning.clone().unwrap();
        assert_eq!(
            (
                commissioning.node_id.as_deref(),
                commissioning.baudrate.as_deref()
            ),
            (Some("9"), Some("500"))
        );
        assert_eq!(recommission(&eds, Some(128), None), Err(DcfError::NodeId(128)));
        assert_eq!(recommission(&eds, None, Some(100)), Err(DcfError::Bitrate(100)));
        let template = load(b"[1000]\nParameterName=t\nDataType=0x0007\nAccessType=ro\nDefaultValue=1\n").eds;
        assert!(!is_configuration(&template));
        assert!(configuration_keys(&template).is_empty());
        let made = to_dcf(&eds, 5, 250).unwrap();
        let keys = configuration_keys(&made);
        assert_eq!(keys.first().map(String::as_str), Some("[DeviceComissioning]"));
        assert!(keys.contains(&"[1800sub1] ParameterValue".to_owned()), "{keys:?}");
        assert!(keys.contains(&"[1017] ParameterValue".to_owned()), "{keys:?}");
    }

    #[test]
    fn eds_to_dcf_resolves_nodeid_and_keeps_existing_values() {
        let eds = load(EDS.as_bytes()).eds;
        let dcf = to_dcf(&eds, 5, 250).unwrap();
        assert!(dcf.is_dcf());
        assert_eq!(dcf.node_id(), Some(5));
        assert_eq!(dcf.file_info.last_eds.as_deref(), Some("dev.eds"));
        let sub1 = &dcf.objects[&0x1800].subs[&1].attributes;
        assert_eq!(sub1.parameter_value.as_deref(), Some("0x185"));
        assert_eq!(sub1.default_value.as_deref(), Some("$NODEID+0x180"));
        assert_eq!(
            dcf.objects[&0x1017].attributes.parameter_value.as_deref(),
            Some("100")
        );
        assert!(supports_bitrate(&eds, 250) && !supports_bitrate(&eds, 500));
        assert_eq!(to_dcf(&eds, 0, 250), Err(DcfError::NodeId(0)));
        assert_eq!(to_dcf(&eds, 5, 100), Err(DcfError::Bitrate(100)));
    }

    #[test]
    fn dcf_to_eds_removes_exactly_the_dcf_additions() {
        let eds = load(EDS.replace("ParameterValue=100\n", "").as_bytes()).eds;
        let dcf = to_dcf(&eds, 5, 250).unwrap();
        assert_eq!(to_eds(&dcf), eds);
    }
}

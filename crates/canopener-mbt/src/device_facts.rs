//! What a model's parameters may read from the device description (`od`, `exists`, `pdo_bytes`):
//! default values as a device with that node-ID starts with them.

use canopener_eds::model::{Attributes, Eds, typed};

/// The attributes of `index:sub` (a VAR's own section for sub-index 0).
fn entry(eds: &Eds, index: u16, sub: u8) -> Option<&Attributes> {
    let object = eds.objects.get(&index)?;
    match object.subs.get(&sub) {
        Some(s) => Some(&s.attributes),
        None if sub == 0 && object.subs.is_empty() => Some(&object.attributes),
        None => None,
    }
}

/// Whether the description has `index:sub`.
pub(crate) fn exists(eds: &Eds, index: u16, sub: u8) -> bool {
    entry(eds, index, sub).is_some()
}

/// The value `index:sub` starts with on node `node_id`: a DCF's `ParameterValue`, else the
/// `DefaultValue`, `$NODEID` resolved.
pub(crate) fn value(eds: &Eds, node_id: u8, index: u16, sub: u8) -> Result<i64, String> {
    let attrs =
        entry(eds, index, sub).ok_or_else(|| format!("the description has no {index:04X}h:{sub:02X}"))?;
    let text = attrs
        .parameter_value
        .as_deref()
        .or(attrs.default_value.as_deref());
    let parsed = typed(text, attrs.data_type());
    parsed
        .value
        .and_then(|v| v.resolve(node_id))
        .and_then(|v| i64::try_from(v).ok())
        .ok_or_else(|| format!("{index:04X}h:{sub:02X} has no integer default value in the description"))
}

/// The data length in bytes of the PDO whose mapping parameter is `mapping_index` (1600h.., 1A00h..),
/// from the mapping entries it starts with; 0 if an entry maps an object the description does not
/// have (the description's PDO cannot be sent as described, so a model must not expect it). Entries
/// of the data-type area (index 0001h..001Fh) are dummy mappings and count with their length.
pub(crate) fn pdo_bytes(eds: &Eds, node_id: u8, mapping_index: u16) -> Result<i64, String> {
    let count = value(eds, node_id, mapping_index, 0)?;
    let mut bits = 0;
    for sub in 1..=u8::try_from(count).unwrap_or(0).min(64) {
        let entry = value(eds, node_id, mapping_index, sub)?;
        let (index, mapped_sub) = ((entry >> 16) as u16, (entry >> 8) as u8);
        if index >= 0x20 && !exists(eds, index, mapped_sub) {
            return Ok(0);
        }
        bits += entry & 0xFF;
    }
    Ok((bits + 7) / 8)
}

//! What the EDS says the device under test is: every entry of its object dictionary with the value
//! it must hold at power-on, its access type, limits, PDO mapping attribute and ObjFlags, the PDOs,
//! and which optional services it claims. Tests take their preconditions and expectations from here.
//!
//! This is canopener's own reading of CiA 306 (defaults resolved for the node-ID under test, `$NODEID`
//! formulas, DEFTYPE data types, CompactSubObj and CompactPDO entries), kept apart from the simulated
//! device's dictionary builder so that a misreading there cannot hide behind the same misreading here.

use std::collections::BTreeMap;

use canopener_eds::model::{Attributes, typed};
use canopener_eds::value::{Value, range_of};
use canopener_eds::{AccessType, DataType, Eds, ObjectType, Origin, TypeKind};
use canopener_od::Number;

/// ObjFlags bit 0 (CiA 306 §4.6.3.2): a configuration tool must not write the entry.
pub const OBJ_FLAG_REFUSE_WRITE: u32 = 0x1;
/// ObjFlags bit 1: a configuration tool must not read the entry when scanning the device.
pub const OBJ_FLAG_REFUSE_READ: u32 = 0x2;

/// One entry (a VAR, DOMAIN, or sub-object of an ARRAY or RECORD) as the EDS describes it.
#[derive(Debug, Clone, PartialEq)]
pub struct EntryModel {
    /// The index.
    pub index: u16,
    /// The sub-index (0 for a VAR).
    pub sub: u8,
    /// `ParameterName`.
    pub name: String,
    /// The data type, resolved through DEFTYPE objects; `None` when the EDS gives none usable.
    pub data_type: Option<DataType>,
    /// The access type; a DOMAIN without one is rw (CiA 306 §4.6.3.2).
    pub access: Option<AccessType>,
    /// `PDOMapping=1`.
    pub pdo_mapping: bool,
    /// `ObjFlags` (0 when absent).
    pub obj_flags: u32,
    /// The value the device must hold at power-on, encoded as CiA 301 carries it; `None` without a
    /// usable `DefaultValue` (or `ParameterValue` in a DCF).
    pub default: Option<Vec<u8>>,
    /// `LowLimit`, when given and readable.
    pub low: Option<Number>,
    /// `HighLimit`, when given and readable.
    pub high: Option<Number>,
}

impl EntryModel {
    /// `1017h:00 (Producer heartbeat time)`.
    pub fn label(&self) -> String {
        if self.name.is_empty() {
            format!("{:04X}h:{:02X}", self.index, self.sub)
        } else {
            format!("{:04X}h:{:02X} ({})", self.index, self.sub, self.name)
        }
    }

    /// Whether an SDO upload may read it.
    pub fn readable(&self) -> bool {
        self.access.is_some_and(AccessType::readable)
    }

    /// Whether an SDO download may write it.
    pub fn writable(&self) -> bool {
        self.access.is_some_and(AccessType::writable)
    }

    /// The size of a value of its type in bytes, `None` for variable-length types.
    pub fn size(&self) -> Option<usize> {
        self.data_type.and_then(DataType::byte_size)
    }

    /// Whether it has a numeric type with LowLimit or HighLimit.
    pub fn has_limits(&self) -> bool {
        self.low.is_some() || self.high.is_some()
    }
}

/// The shape of an object.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ObjectKind {
    /// A single value.
    Var,
    /// A DOMAIN.
    Domain,
    /// Sub-objects of one type.
    Array,
    /// Sub-objects of different types.
    Record,
}

/// One object as the EDS describes it.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjectModel {
    /// The index.
    pub index: u16,
    /// `ParameterName`.
    pub name: String,
    /// VAR, DOMAIN, ARRAY or RECORD.
    pub kind: ObjectKind,
    /// The sub-indices present (0 only for a VAR).
    pub subs: Vec<u8>,
    /// The data type code of the object itself (an ARRAY's element type, a RECORD's definition).
    pub data_type: Option<u16>,
}

impl ObjectModel {
    /// The highest sub-index present, other than FFh (which describes the structure).
    pub fn highest_sub(&self) -> u8 {
        self.subs
            .iter()
            .copied()
            .filter(|sub| *sub != 0xFF)
            .max()
            .unwrap_or(0)
    }

    /// Whether the object has sub-objects.
    pub fn is_structured(&self) -> bool {
        matches!(self.kind, ObjectKind::Array | ObjectKind::Record)
    }
}

/// A PDO the EDS describes (its communication parameter and, if present, its mapping).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PdoModel {
    /// Receive or transmit.
    pub direction: PdoDirection,
    /// 1-based PDO number.
    pub number: u16,
    /// 1400h + n or 1800h + n.
    pub comm: u16,
    /// 1600h + n or 1A00h + n, if the EDS has it.
    pub mapping: Option<u16>,
}

/// Receive or transmit PDO.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PdoDirection {
    /// RPDO (1400h/1600h).
    Receive,
    /// TPDO (1800h/1A00h).
    Transmit,
}

impl PdoDirection {
    /// `RPDO` or `TPDO`.
    pub fn name(self) -> &'static str {
        match self {
            PdoDirection::Receive => "RPDO",
            PdoDirection::Transmit => "TPDO",
        }
    }
}

/// Everything the tests need from the EDS, for one node-ID.
#[derive(Debug, Clone)]
pub struct DeviceModel {
    /// The node-ID under test (defaults with `$NODEID` are resolved with it).
    pub node: u8,
    /// Every entry, by (index, sub-index).
    pub entries: BTreeMap<(u16, u8), EntryModel>,
    /// Every data object (type definitions excluded), by index.
    pub objects: BTreeMap<u16, ObjectModel>,
    /// Which dummy entries 0001h–0007h the EDS says the device supports in PDO mappings.
    pub dummies: [bool; 8],
    /// What `[DeviceInfo]` `LSS_Supported` says (`None` when the key is absent or not 0/1).
    pub lss_supported: Option<bool>,
    /// The bit rates (kbit/s) `[DeviceInfo]` `BaudRate_*` mentions, with whether it says supported
    /// (`=1`).
    pub bit_rates: Vec<(u16, bool)>,
}

impl DeviceModel {
    /// The model of `eds` for node `node`.
    pub fn new(eds: &Eds, node: u8) -> DeviceModel {
        let mut model = DeviceModel {
            node,
            entries: BTreeMap::new(),
            objects: BTreeMap::new(),
            dummies: dummies(eds),
            lss_supported: match eds
                .device_info
                .lss_supported
                .as_deref()
                .and_then(canopener_eds::model::int_of)
            {
                Some(0) => Some(false),
                Some(1) => Some(true),
                _ => None,
            },
            bit_rates: bit_rates(eds),
        };
        for (&index, object) in &eds.objects {
            let kind = match object.object_type() {
                Some(ObjectType::Var) => ObjectKind::Var,
                Some(ObjectType::Domain) => ObjectKind::Domain,
                Some(ObjectType::Array) => ObjectKind::Array,
                Some(ObjectType::Record) => ObjectKind::Record,
                // Type definitions and unknown object codes describe no data of the device.
                _ => continue,
            };
            if object.origin == Origin::Orphan {
                continue;
            }
            let mut subs = Vec::new();
            if object.subs.is_empty() && matches!(kind, ObjectKind::Var | ObjectKind::Domain) {
                let entry = entry(
                    eds,
                    node,
                    index,
                    0,
                    &object.attributes,
                    kind == ObjectKind::Domain,
                );
                model.entries.insert((index, 0), entry);
                subs.push(0);
            } else {
                for (&sub, sub_object) in &object.subs {
                    if sub_object.origin == Origin::Orphan {
                        continue;
                    }
                    let entry = entry(eds, node, index, sub, &sub_object.attributes, false);
                    model.entries.insert((index, sub), entry);
                    subs.push(sub);
                }
            }
            model.objects.insert(
                index,
                ObjectModel {
                    index,
                    name: object.name().to_owned(),
                    kind,
                    subs,
                    data_type: object.attributes.data_type().map(|t| t.0),
                },
            );
        }
        model
    }

    /// The entry `index`:`sub`, if the EDS has it.
    pub fn entry(&self, index: u16, sub: u8) -> Option<&EntryModel> {
        self.entries.get(&(index, sub))
    }

    /// Whether the EDS has the object `index`.
    pub fn has(&self, index: u16) -> bool {
        self.objects.contains_key(&index)
    }

    /// The power-on value of `index`:`sub` as an unsigned integer, if the EDS gives one that fits.
    pub fn default_u32(&self, index: u16, sub: u8) -> Option<u32> {
        let bytes = self.entry(index, sub)?.default.as_ref()?;
        let mut wide = [0u8; 4];
        for (slot, byte) in wide.iter_mut().zip(bytes) {
            *slot = *byte;
        }
        Some(u32::from_le_bytes(wide))
    }

    /// Every PDO of one direction the EDS describes, in number order.
    pub fn pdos(&self, direction: PdoDirection) -> Vec<PdoModel> {
        let (comm_base, map_base) = match direction {
            PdoDirection::Receive => (0x1400u16, 0x1600u16),
            PdoDirection::Transmit => (0x1800, 0x1A00),
        };
        (0..0x200u16)
            .filter(|n| self.has(comm_base + n))
            .map(|n| PdoModel {
                direction,
                number: n + 1,
                comm: comm_base + n,
                mapping: self.has(map_base + n).then_some(map_base + n),
            })
            .collect()
    }

    /// Node guarding is described: 100Ch and 100Dh are both present.
    pub fn has_guarding(&self) -> bool {
        self.entry(0x100C, 0).is_some() && self.entry(0x100D, 0).is_some()
    }

    /// The heartbeat producer 1017h is described.
    pub fn has_heartbeat(&self) -> bool {
        self.entry(0x1017, 0).is_some()
    }

    /// Every entry whose value the walk may read: readable and not flagged "refuse read on scan".
    pub fn scannable(&self) -> impl Iterator<Item = &EntryModel> {
        self.entries
            .values()
            .filter(|e| e.readable() && e.obj_flags & OBJ_FLAG_REFUSE_READ == 0)
    }
}

fn bit_rates(eds: &Eds) -> Vec<(u16, bool)> {
    [1000, 800, 500, 250, 125, 50, 20, 10]
        .into_iter()
        .filter_map(|kbit| {
            let flag = eds.device_info.get(&format!("BaudRate_{kbit}"))?;
            Some((kbit, canopener_eds::model::int_of(flag) == Some(1)))
        })
        .collect()
}

fn dummies(eds: &Eds) -> [bool; 8] {
    let mut out = [false; 8];
    if let Some(usage) = &eds.dummy_usage {
        for (slot, flag) in out.iter_mut().enumerate().skip(1) {
            let key = format!("Dummy{slot:04X}");
            *flag = usage
                .get(&key)
                .and_then(canopener_eds::model::int_of)
                .is_some_and(|v| v == 1);
        }
    }
    out
}

fn entry(eds: &Eds, node: u8, index: u16, sub: u8, attributes: &Attributes, domain: bool) -> EntryModel {
    let data_type = attributes
        .data_type()
        .map(|t| eds.resolve_data_type(t))
        .or(domain.then_some(DataType::DOMAIN));
    let access = attributes.access_type().or_else(|| {
        // CiA 306 §4.6.3.2: a DOMAIN without AccessType is rw.
        (data_type == Some(DataType::DOMAIN) && attributes.access_type.is_none()).then_some(AccessType::Rw)
    });
    // A DCF describes a configured device: its ParameterValue is what the device holds.
    let value_text = attributes
        .parameter_value
        .as_deref()
        .filter(|v| !v.trim().is_empty())
        .or(attributes.default_value.as_deref());
    let default = data_type.and_then(|t| {
        let value = typed(value_text, Some(t)).value?;
        encode(&value, t, node)
    });
    let limit = |text: Option<&str>| {
        let t = data_type.filter(|t| t.is_numeric())?;
        let value = typed(text, Some(t)).value?;
        Number::decode(t, &encode(&value, t, node)?)
    };
    EntryModel {
        index,
        sub,
        name: attributes.parameter_name.clone().unwrap_or_default(),
        data_type,
        access,
        pdo_mapping: attributes.pdo_mapping(),
        obj_flags: attributes.obj_flags().unwrap_or(0),
        default,
        low: limit(attributes.low_limit.as_deref()),
        high: limit(attributes.high_limit.as_deref()),
    }
}

/// A typed EDS value as the bytes CiA 301 §7.1 carries for `data_type`, `None` when it does not fit
/// the type (an EDS out of range is the EDS suite's finding, not a value to test the device with).
pub fn encode(value: &Value, data_type: DataType, node: u8) -> Option<Vec<u8>> {
    match (value, data_type.kind()?) {
        (_, TypeKind::Boolean) => {
            let v = value.resolve(node)?;
            (0..=1).contains(&v).then(|| vec![v as u8])
        }
        (_, TypeKind::Signed(bits) | TypeKind::Unsigned(bits)) => {
            let signed = matches!(data_type.kind(), Some(TypeKind::Signed(_)));
            let v = value.resolve(node)?;
            let (min, max) = range_of(bits, signed);
            if v < min || v > max {
                return None;
            }
            Some(v.to_le_bytes().get(..data_type.byte_size()?)?.to_vec())
        }
        (Value::Real { value, .. }, TypeKind::Real32) => Some((*value as f32).to_le_bytes().to_vec()),
        (Value::Real { value, .. }, TypeKind::Real64) => Some(value.to_le_bytes().to_vec()),
        (Value::Text { value }, TypeKind::VisibleString) => Some(value.as_bytes().to_vec()),
        (Value::Text { value }, TypeKind::UnicodeString) => {
            Some(value.encode_utf16().flat_map(u16::to_le_bytes).collect())
        }
        (Value::Octets { value }, TypeKind::OctetString | TypeKind::Domain) => Some(value.clone()),
        (Value::Time { days, ms }, TypeKind::TimeOfDay | TypeKind::TimeDifference) => {
            let mut bytes = (ms & 0x0FFF_FFFF).to_le_bytes().to_vec();
            bytes.extend_from_slice(&days.to_le_bytes());
            Some(bytes)
        }
        _ => None,
    }
}

/// The value `number` of `data_type` as CiA 301 bytes, `None` when it does not fit.
pub fn number_bytes(number: Number, data_type: DataType) -> Option<Vec<u8>> {
    let size = data_type.byte_size()?;
    match (number, data_type.kind()?) {
        (Number::Real(v), TypeKind::Real32) => Some((v as f32).to_le_bytes().to_vec()),
        (Number::Real(v), TypeKind::Real64) => Some(v.to_le_bytes().to_vec()),
        (Number::Signed(v), TypeKind::Signed(bits)) => {
            let (min, max) = range_of(bits, true);
            (min..=max)
                .contains(&i128::from(v))
                .then(|| v.to_le_bytes().get(..size).map(<[u8]>::to_vec))
                .flatten()
        }
        (Number::Unsigned(v), TypeKind::Unsigned(bits)) => (i128::from(v) <= range_of(bits, false).1)
            .then(|| v.to_le_bytes().get(..size).map(<[u8]>::to_vec))
            .flatten(),
        (Number::Unsigned(v), TypeKind::Boolean) => (v <= 1).then(|| vec![v as u8]),
        _ => None,
    }
}

/// The number just beyond `limit` in the direction `up`, if the type can hold it (REALs step by a
/// thousandth of the magnitude, at least 1).
pub fn step_beyond(limit: Number, up: bool, data_type: DataType) -> Option<Number> {
    let stepped = match limit {
        Number::Signed(v) => Number::Signed(if up { v.checked_add(1)? } else { v.checked_sub(1)? }),
        Number::Unsigned(v) => Number::Unsigned(if up { v.checked_add(1)? } else { v.checked_sub(1)? }),
        Number::Real(v) => {
            let step = (v.abs() / 1000.0).max(1.0);
            Number::Real(if up { v + step } else { v - step })
        }
    };
    number_bytes(stepped, data_type).map(|_| stepped)
}

/// `1000` or `-5` or `1.5`: a number as a person reads it.
pub fn number_text(number: Number) -> String {
    match number {
        Number::Signed(v) => v.to_string(),
        Number::Unsigned(v) => v.to_string(),
        Number::Real(v) => v.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model(text: &str) -> DeviceModel {
        DeviceModel::new(&canopener_eds::load(text.as_bytes()).eds, 5)
    }

    const EDS: &str = "[1017]\nParameterName=Producer heartbeat time\nObjectType=0x7\nDataType=0x0006\n\
AccessType=rw\nDefaultValue=0\nLowLimit=0\nHighLimit=1000\nPDOMapping=0\n\
[1800]\nParameterName=TPDO1\nObjectType=0x9\nSubNumber=2\n\
[1800sub0]\nParameterName=n\nObjectType=0x7\nDataType=0x0005\nAccessType=ro\nDefaultValue=2\nPDOMapping=0\n\
[1800sub1]\nParameterName=COB-ID\nObjectType=0x7\nDataType=0x0007\nAccessType=rw\nDefaultValue=$NODEID+0x180\nPDOMapping=0\n\
[2000]\nParameterName=Name\nObjectType=0x7\nDataType=0x0009\nAccessType=ro\nDefaultValue=abc\nObjFlags=2\nPDOMapping=0\n";

    #[test]
    fn defaults_resolve_the_node_id_and_limits_read_as_numbers() {
        let model = model(EDS);
        assert_eq!(
            model.entry(0x1800, 1).unwrap().default,
            Some(vec![0x85, 0x01, 0, 0])
        );
        let hb = model.entry(0x1017, 0).unwrap();
        assert_eq!(hb.default, Some(vec![0, 0]));
        assert_eq!(
            (hb.low, hb.high),
            (Some(Number::Unsigned(0)), Some(Number::Unsigned(1000)))
        );
        assert_eq!(model.objects[&0x1800].highest_sub(), 1);
        assert!(model.has_heartbeat() && !model.has_guarding());
        assert_eq!(model.pdos(PdoDirection::Transmit).len(), 1);
        // ObjFlags bit 1 keeps 2000h out of the scan.
        assert!(model.scannable().all(|e| e.index != 0x2000));
    }

    #[test]
    fn stepping_beyond_a_limit_respects_the_type() {
        let u16t = DataType::UNSIGNED16;
        assert_eq!(
            step_beyond(Number::Unsigned(1000), true, u16t),
            Some(Number::Unsigned(1001))
        );
        assert_eq!(step_beyond(Number::Unsigned(0), false, u16t), None);
        assert_eq!(step_beyond(Number::Unsigned(65535), true, u16t), None);
        assert_eq!(
            number_bytes(Number::Signed(-2), DataType::INTEGER16),
            Some(vec![0xFE, 0xFF])
        );
    }
}

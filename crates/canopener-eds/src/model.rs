//! The object dictionary model of an EDS or DCF file (CiA 306 §4–§6).
//!
//! Every value is kept as the text written in the file (trimmed), so nothing is lost and the file can
//! be rewritten faithfully; typed views ([`Attributes::data_type`], [`Eds::default_value`], ...)
//! interpret that text on demand. Keys canopener does not know are kept in `extra`, sections it does
//! not know in [`Eds::other_sections`].

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::types::{AccessType, DataType, ObjectType};
use crate::value::{self, IntLiteral, Parsed, Value};

/// A `key=value` pair as written.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Property {
    /// The key as written.
    pub key: String,
    /// The value as written (trimmed).
    pub value: String,
}

/// An ordered list of entries of a section whose keys CiA 306 does not fix (lists, comments, ...).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Properties(pub Vec<Property>);

impl Properties {
    /// The first value for a key (case-insensitive).
    pub fn get(&self, key: &str) -> Option<&str> {
        self.0
            .iter()
            .find(|p| p.key.eq_ignore_ascii_case(key))
            .map(|p| p.value.as_str())
    }

    /// Sets a key, replacing the first entry with that key or appending.
    pub fn set(&mut self, key: &str, value: impl Into<String>) {
        match self.0.iter_mut().find(|p| p.key.eq_ignore_ascii_case(key)) {
            Some(p) => p.value = value.into(),
            None => self.0.push(Property {
                key: key.to_owned(),
                value: value.into(),
            }),
        }
    }

    /// Entries whose key is a decimal number (`1=0x1000`), with that number.
    pub fn numbered(&self) -> impl Iterator<Item = (u32, &str)> {
        self.0
            .iter()
            .filter_map(|p| Some((decimal_key(&p.key)?, p.value.as_str())))
    }

    /// Entries `<prefix><decimal>` (`Line1`, `Type2`), with that number.
    pub fn numbered_with_prefix<'a>(&'a self, prefix: &'a str) -> impl Iterator<Item = (u32, &'a str)> + 'a {
        self.0.iter().filter_map(move |p| {
            let head = p.key.get(..prefix.len())?;
            if !head.eq_ignore_ascii_case(prefix) {
                return None;
            }
            Some((decimal_key(p.key.get(prefix.len()..)?)?, p.value.as_str()))
        })
    }

    /// Whether there are no entries.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

/// Reads a key made only of decimal digits (CiA 306: such keys are strings; `01` is not `1`).
pub fn decimal_key(key: &str) -> Option<u32> {
    if key.is_empty() || !key.bytes().all(|b| b.is_ascii_digit()) || (key.len() > 1 && key.starts_with('0')) {
        return None;
    }
    key.parse().ok()
}

macro_rules! keyed_section {
    ($(#[$doc:meta])* $name:ident { $($(#[$fdoc:meta])* $field:ident => $key:literal,)* }) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
        #[serde(rename_all = "PascalCase")]
        pub struct $name {
            $(
                $(#[$fdoc])*
                #[serde(rename = $key, default, skip_serializing_if = "Option::is_none")]
                pub $field: Option<String>,
            )*
            /// Keys CiA 306 does not define for this section, in file order.
            #[serde(default, skip_serializing_if = "Vec::is_empty")]
            pub extra: Vec<Property>,
        }

        impl $name {
            /// The known keys in canonical spelling and order.
            pub const KEYS: &'static [&'static str] = &[$($key),*];

            /// The slot for a known key (case-insensitive), or `None` for an unknown key.
            pub fn slot_mut(&mut self, key: &str) -> Option<&mut Option<String>> {
                $(if key.eq_ignore_ascii_case($key) { return Some(&mut self.$field); })*
                None
            }

            /// The slot for a known key and the key's canonical spelling, in one pass.
            pub fn slot_with_key(&mut self, key: &str) -> Option<(&mut Option<String>, &'static str)> {
                // Nearly every key is spelt canonically: exact comparisons (a length test, then
                // `memcmp`) find it sooner than case-folding comparisons byte by byte.
                match key {
                    $($key => return Some((&mut self.$field, $key)),)*
                    _ => {}
                }
                $(if key.eq_ignore_ascii_case($key) { return Some((&mut self.$field, $key)); })*
                None
            }

            /// The value of a key, known or extra (case-insensitive).
            pub fn get(&self, key: &str) -> Option<&str> {
                // Exact spelling first, as in `slot_with_key`.
                match key {
                    $($key => return self.$field.as_deref(),)*
                    _ => {}
                }
                $(if key.eq_ignore_ascii_case($key) { return self.$field.as_deref(); })*
                self.extra.iter().find(|p| p.key.eq_ignore_ascii_case(key)).map(|p| p.value.as_str())
            }

            /// Sets a key: a known one in its slot, any other one in `extra`.
            pub fn set(&mut self, key: &str, value: impl Into<String>) {
                let value = value.into();
                if let Some(slot) = self.slot_mut(key) {
                    *slot = Some(value);
                } else if let Some(p) = self.extra.iter_mut().find(|p| p.key.eq_ignore_ascii_case(key)) {
                    p.value = value;
                } else {
                    self.extra.push(Property { key: key.to_owned(), value });
                }
            }

            /// Every present entry: known keys in canonical spelling and order, then `extra`.
            pub fn entries(&self) -> Vec<(&str, &str)> {
                let mut out = Vec::new();
                $(if let Some(v) = &self.$field { out.push(($key, v.as_str())); })*
                out.extend(self.extra.iter().map(|p| (p.key.as_str(), p.value.as_str())));
                out
            }
        }
    };
}

keyed_section! {
    /// `[FileInfo]` (CiA 306 §4.4, DCF §5.2).
    FileInfo {
        /// `FileName`
        file_name => "FileName",
        /// `FileVersion` (Unsigned8)
        file_version => "FileVersion",
        /// `FileRevision` (Unsigned8)
        file_revision => "FileRevision",
        /// `EDSVersion` (`x.y`; missing means 3.0)
        eds_version => "EDSVersion",
        /// `Description`
        description => "Description",
        /// `CreationTime` (`hh:mm(AM|PM)`)
        creation_time => "CreationTime",
        /// `CreationDate` (`mm-dd-yyyy`)
        creation_date => "CreationDate",
        /// `CreatedBy`
        created_by => "CreatedBy",
        /// `ModificationTime`
        modification_time => "ModificationTime",
        /// `ModificationDate`
        modification_date => "ModificationDate",
        /// `ModifiedBy`
        modified_by => "ModifiedBy",
        /// `LastEDS` (DCF only)
        last_eds => "LastEDS",
    }
}

keyed_section! {
    /// `[DeviceInfo]` (CiA 306 §4.5).
    DeviceInfo {
        /// `VendorName`
        vendor_name => "VendorName",
        /// `VendorNumber` (must equal 1018h sub 1)
        vendor_number => "VendorNumber",
        /// `ProductName`
        product_name => "ProductName",
        /// `ProductNumber` (must equal 1018h sub 2)
        product_number => "ProductNumber",
        /// `RevisionNumber` (must equal 1018h sub 3)
        revision_number => "RevisionNumber",
        /// `OrderCode`
        order_code => "OrderCode",
        /// `BaudRate_10`
        baud_rate_10 => "BaudRate_10",
        /// `BaudRate_20`
        baud_rate_20 => "BaudRate_20",
        /// `BaudRate_50`
        baud_rate_50 => "BaudRate_50",
        /// `BaudRate_125`
        baud_rate_125 => "BaudRate_125",
        /// `BaudRate_250`
        baud_rate_250 => "BaudRate_250",
        /// `BaudRate_500`
        baud_rate_500 => "BaudRate_500",
        /// `BaudRate_800`
        baud_rate_800 => "BaudRate_800",
        /// `BaudRate_1000`
        baud_rate_1000 => "BaudRate_1000",
        /// `SimpleBootUpMaster`
        simple_boot_up_master => "SimpleBootUpMaster",
        /// `SimpleBootUpSlave`
        simple_boot_up_slave => "SimpleBootUpSlave",
        /// `Granularity` (0 = mapping not modifiable, 1..=64 bits)
        granularity => "Granularity",
        /// `DynamicChannelsSupported`
        dynamic_channels_supported => "DynamicChannelsSupported",
        /// `GroupMessaging`
        group_messaging => "GroupMessaging",
        /// `NrOfRXPDO`
        nr_of_rx_pdo => "NrOfRXPDO",
        /// `NrOfTXPDO`
        nr_of_tx_pdo => "NrOfTXPDO",
        /// `LSS_Supported`
        lss_supported => "LSS_Supported",
        /// `CompactPDO` (bit mask of implied communication parameter sub-indices)
        compact_pdo => "CompactPDO",
        /// `CANopenSafetySupported` (CiA 306-1 v1.4)
        canopen_safety_supported => "CANopenSafetySupported",
    }
}

/// What the `[DeviceInfo]` keys hold (CiA 306 §4.5): the one list every reader and checker of the
/// section uses.
impl DeviceInfo {
    /// The Boolean keys that declare a supported bit rate, with that bit rate in kbit/s.
    pub const BAUD_RATE_KEYS: [(u16, &'static str); 8] = [
        (10, "BaudRate_10"),
        (20, "BaudRate_20"),
        (50, "BaudRate_50"),
        (125, "BaudRate_125"),
        (250, "BaudRate_250"),
        (500, "BaudRate_500"),
        (800, "BaudRate_800"),
        (1000, "BaudRate_1000"),
    ];

    /// The Boolean keys besides the bit rates: capabilities the device has or lacks
    /// (`CANopenSafetySupported` from CiA 306-1 V1.4).
    pub const FLAG_KEYS: [&'static str; 5] = [
        "SimpleBootUpMaster",
        "SimpleBootUpSlave",
        "GroupMessaging",
        "LSS_Supported",
        "CANopenSafetySupported",
    ];

    /// The numeric keys, all unsigned, with their width in bits.
    pub const NUMBER_KEYS: [(&'static str, u32); 8] = [
        ("VendorNumber", 32),
        ("ProductNumber", 32),
        ("RevisionNumber", 32),
        ("Granularity", 8),
        ("DynamicChannelsSupported", 8),
        ("CompactPDO", 8),
        ("NrOfRXPDO", 16),
        ("NrOfTXPDO", 16),
    ];
}

keyed_section! {
    /// `[DeviceComissioning]` of a DCF (CiA 306 §5.3.1).
    DeviceCommissioning {
        /// `NodeID` (1..=127)
        node_id => "NodeID",
        /// `NodeName`
        node_name => "NodeName",
        /// `Baudrate` (kbit/s)
        baudrate => "Baudrate",
        /// `NetNumber`
        net_number => "NetNumber",
        /// `NetworkName`
        network_name => "NetworkName",
        /// `CANopenManager`
        canopen_manager => "CANopenManager",
        /// `LSS_SerialNumber` (must equal 1018h sub 4)
        lss_serial_number => "LSS_SerialNumber",
        /// `NodeRefd`
        node_refd => "NodeRefd",
        /// `NetRefd`
        net_refd => "NetRefd",
    }
}

keyed_section! {
    /// `[M<x>ModuleInfo]` (CiA 306 §6.2).
    ModuleInfo {
        /// `ProductName`
        product_name => "ProductName",
        /// `ProductVersion`
        product_version => "ProductVersion",
        /// `ProductRevision`
        product_revision => "ProductRevision",
        /// `OrderCode`
        order_code => "OrderCode",
    }
}

keyed_section! {
    /// The keys of an object or sub-object section (CiA 306 §4.6.3.2, DCF §5.3.2, modules §6).
    Attributes {
        /// `SubNumber`: sub-indices implemented, including sub 0
        sub_number => "SubNumber",
        /// `ParameterName`
        parameter_name => "ParameterName",
        /// `ObjectType` (missing means VAR)
        object_type => "ObjectType",
        /// `DataType`
        data_type => "DataType",
        /// `LowLimit`
        low_limit => "LowLimit",
        /// `HighLimit`
        high_limit => "HighLimit",
        /// `AccessType`
        access_type => "AccessType",
        /// `DefaultValue`
        default_value => "DefaultValue",
        /// `PDOMapping`
        pdo_mapping => "PDOMapping",
        /// `ObjFlags`
        obj_flags => "ObjFlags",
        /// `CompactSubObj`
        compact_sub_obj => "CompactSubObj",
        /// `ParameterValue` (DCF)
        parameter_value => "ParameterValue",
        /// `Denotation` (DCF)
        denotation => "Denotation",
        /// `UploadFile` (DCF, DOMAIN)
        upload_file => "UploadFile",
        /// `DownloadFile` (DCF, DOMAIN)
        download_file => "DownloadFile",
        /// `ParamRefd`
        param_refd => "ParamRefd",
        /// `Count` (module sub-extension)
        count => "Count",
        /// `ObjExtend` (module sub-extension)
        obj_extend => "ObjExtend",
    }
}

impl Attributes {
    /// The object type; a missing `ObjectType` means VAR (CiA 306 §4.6.3.2). `None` if unreadable.
    pub fn object_type(&self) -> Option<ObjectType> {
        match self.object_type.as_deref().map(value::trim) {
            None | Some("") => Some(ObjectType::Var),
            Some(text) => ObjectType::from_code(u64::try_from(int_of(text)?).ok()?),
        }
    }

    /// The `DataType` index, if present and a number.
    pub fn data_type(&self) -> Option<DataType> {
        u16::try_from(int_of(self.data_type.as_deref()?)?)
            .ok()
            .map(DataType)
    }

    /// The access type, if present and valid.
    pub fn access_type(&self) -> Option<AccessType> {
        let raw = value::trim(self.access_type.as_deref()?);
        AccessType::parse(raw).or_else(|| AccessType::parse(strip_inline_comment(raw)?))
    }

    /// `PDOMapping` as a boolean (missing means 0).
    pub fn pdo_mapping(&self) -> bool {
        self.pdo_mapping.as_deref().and_then(int_of) == Some(1)
    }

    /// `CompactSubObj` as a number (0 when missing or unreadable).
    pub fn compact_sub_obj(&self) -> u64 {
        self.compact_sub_obj
            .as_deref()
            .and_then(int_of)
            .and_then(|v| u64::try_from(v).ok())
            .unwrap_or(0)
    }

    /// `SubNumber` as a number, if present and readable.
    pub fn sub_number(&self) -> Option<u64> {
        self.sub_number
            .as_deref()
            .and_then(int_of)
            .and_then(|v| u64::try_from(v).ok())
    }

    /// `ObjFlags` as a number (0 when missing).
    pub fn obj_flags(&self) -> Option<u32> {
        match self.obj_flags.as_deref().map(value::trim) {
            None | Some("") => Some(0),
            Some(text) => u32::try_from(int_of(text)?).ok(),
        }
    }
}

/// Keys that only say how a file is written, not what the dictionary contains: `SubNumber` follows from
/// the sub-objects present, `CompactSubObj` is a compact form of them (CiA 306 §4.6.3.2, §4.6.3.4.2).
pub const REPRESENTATION_KEYS: &[&str] = &["SubNumber", "CompactSubObj"];

/// Keys an ARRAY/RECORD object carries only for its sub-objects (a compact array writes them on the
/// object; an explicit one on each sub-object).
pub const SUB_CARRIED_KEYS: &[&str] = &[
    "DataType",
    "AccessType",
    "DefaultValue",
    "PDOMapping",
    "LowLimit",
    "HighLimit",
];

/// Reads an integer without reporting issues (the loader reports them once). Text after a `;`
/// is ignored when the whole does not read, as `0x0006 ; UNSIGNED16` is meant as 6.
pub fn int_of(text: &str) -> Option<i128> {
    let read = |t: &str| value::parse_integer(t, &mut Vec::new()).map(|IntLiteral { value, .. }| value);
    read(text).or_else(|| read(strip_inline_comment(text)?))
}

/// The text before an inline `;` comment, if there is one (CiA 306 has none, tools write them).
pub fn strip_inline_comment(text: &str) -> Option<&str> {
    let head = text[..text.find(';')?].trim_end();
    (!head.is_empty()).then_some(head)
}

/// Where a sub-object came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Origin {
    /// Described by its own section in the file.
    #[default]
    Explicit,
    /// Generated from `CompactSubObj` (CiA 306 §4.6.3.4.2).
    CompactSubObj,
    /// Generated from `[DeviceInfo] CompactPDO` (CiA 306 §4.6.3.4.1).
    CompactPdo,
    /// A placeholder for sub-object or companion sections whose object section is missing.
    Orphan,
}

impl Origin {
    /// Whether writers emit this item as its own section.
    pub fn is_written(self) -> bool {
        matches!(self, Self::Explicit)
    }
}

/// A sub-object `[<index>sub<sub>]`.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SubObject {
    /// The keys of the section.
    pub attributes: Attributes,
    /// Where the sub-object came from.
    #[serde(default, skip_serializing_if = "is_explicit")]
    pub origin: Origin,
}

/// An object `[<index>]` with its sub-objects and companion sections.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Object {
    /// The keys of the section.
    pub attributes: Attributes,
    /// Sub-objects by sub-index (explicit and generated).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty", with = "hex_sub_keys")]
    pub subs: BTreeMap<u8, SubObject>,
    /// `[<index>Name]`: names of CompactSubObj entries.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub names: Option<Properties>,
    /// `[<index>Value]`: DCF values of CompactSubObj entries.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub values: Option<Properties>,
    /// `[<index>Denotation]`: DCF denotations of CompactSubObj entries.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub denotations: Option<Properties>,
    /// `[<index>ObjectLinks]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub object_links: Option<Properties>,
    /// Where the object came from.
    #[serde(default, skip_serializing_if = "is_explicit")]
    pub origin: Origin,
}

fn is_explicit(origin: &Origin) -> bool {
    *origin == Origin::Explicit
}

impl Object {
    /// `ParameterName`, or an empty string.
    pub fn name(&self) -> &str {
        self.attributes.parameter_name.as_deref().unwrap_or("")
    }

    /// The object type (`None` if the file gives an unknown code).
    pub fn object_type(&self) -> Option<ObjectType> {
        self.attributes.object_type()
    }

    /// The highest sub-index present, if the object has sub-objects.
    pub fn highest_sub(&self) -> Option<u8> {
        self.subs.keys().next_back().copied()
    }
}

/// The default value of an object or sub-object, typed by `data_type`.
pub fn typed(text: Option<&str>, data_type: Option<DataType>) -> Parsed {
    match (text, data_type) {
        (Some(text), Some(t)) => value::parse_value(text, t),
        _ => Parsed::default(),
    }
}

/// A module type of a modular device (`M<x>` sections, CiA 306 §6).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Module {
    /// `[M<x>ModuleInfo]`.
    pub info: ModuleInfo,
    /// `[M<x>Comments]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub comments: Option<Properties>,
    /// `[M<x>FixedObjects]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fixed_objects: Option<Properties>,
    /// `[M<x>Fixed<index>]` with their `sub` sections.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub fixed: BTreeMap<u16, Object>,
    /// `[M<x>SubExtends]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sub_extends: Option<Properties>,
    /// `[M<x>SubExt<index>]`.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub sub_ext: BTreeMap<u16, Object>,
}

/// A section canopener does not interpret, kept as written.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct RawSection {
    /// The name as written.
    pub name: String,
    /// The entries.
    pub entries: Properties,
}

/// Which spelling a DCF used for its commissioning section.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default, Serialize, Deserialize)]
pub enum CommissioningSpelling {
    /// `[DeviceComissioning]`, the spelling of CiA 306.
    #[default]
    DeviceComissioning,
    /// `[DeviceCommissioning]`, the dictionary spelling many tools also accept.
    DeviceCommissioning,
}

impl CommissioningSpelling {
    /// The section name.
    pub fn section_name(self) -> &'static str {
        match self {
            Self::DeviceComissioning => "DeviceComissioning",
            Self::DeviceCommissioning => "DeviceCommissioning",
        }
    }
}

/// The three object lists of CiA 306 §4.6.3.1.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum ObjectListKind {
    /// `[MandatoryObjects]`
    Mandatory,
    /// `[OptionalObjects]`
    Optional,
    /// `[ManufacturerObjects]`
    Manufacturer,
}

impl ObjectListKind {
    /// All three, in canonical order.
    pub const ALL: [ObjectListKind; 3] = [Self::Mandatory, Self::Optional, Self::Manufacturer];

    /// The section name.
    pub fn section_name(self) -> &'static str {
        match self {
            Self::Mandatory => "MandatoryObjects",
            Self::Optional => "OptionalObjects",
            Self::Manufacturer => "ManufacturerObjects",
        }
    }

    /// The list an index belongs in (CiA 306 §4.6.3.1).
    pub fn for_index(index: u16) -> Self {
        match index {
            0x1000 | 0x1001 | 0x1018 => Self::Mandatory,
            0x2000..=0x5FFF => Self::Manufacturer,
            _ => Self::Optional,
        }
    }
}

/// An object list section: `SupportedObjects=n` then `1=0x1000`, ...
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct ObjectList(pub Properties);

impl ObjectList {
    /// A list of these indices with a matching count.
    pub fn from_indices(indices: impl IntoIterator<Item = u16>) -> Self {
        let mut entries = Vec::new();
        for (n, index) in indices.into_iter().enumerate() {
            entries.push(Property {
                key: (n + 1).to_string(),
                value: format!("0x{index:04X}"),
            });
        }
        let count = Property {
            key: "SupportedObjects".to_owned(),
            value: entries.len().to_string(),
        };
        ObjectList(Properties(std::iter::once(count).chain(entries).collect()))
    }

    /// The indices listed, in entry order (entries that are not numbers are skipped).
    pub fn indices(&self) -> Vec<u16> {
        self.0
            .numbered()
            .filter_map(|(_, v)| u16::try_from(int_of(v)?).ok())
            .collect()
    }

    /// `SupportedObjects` as written.
    pub fn declared_count(&self) -> Option<&str> {
        self.0.get("SupportedObjects")
    }
}

/// An EDS or DCF file: device description and object dictionary.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Eds {
    /// `[FileInfo]`.
    pub file_info: FileInfo,
    /// `[DeviceInfo]`.
    pub device_info: DeviceInfo,
    /// `[DummyUsage]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dummy_usage: Option<Properties>,
    /// `[Comments]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub comments: Option<Properties>,
    /// `[MandatoryObjects]`, `[OptionalObjects]`, `[ManufacturerObjects]` as written.
    #[serde(default)]
    pub object_lists: BTreeMap<ObjectListKind, ObjectList>,
    /// Objects by index (explicit and generated by CompactPDO).
    #[serde(default, with = "hex_keys")]
    pub objects: BTreeMap<u16, Object>,
    /// `[DeviceComissioning]` of a DCF.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub commissioning: Option<DeviceCommissioning>,
    /// The spelling of the commissioning section.
    #[serde(default)]
    pub commissioning_spelling: CommissioningSpelling,
    /// `[Tools]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tools: Option<Properties>,
    /// `[Tool<n>]` by n.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub tool_sections: BTreeMap<u32, Properties>,
    /// `[DynamicChannels]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dynamic_channels: Option<Properties>,
    /// `[SupportedModules]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub supported_modules: Option<Properties>,
    /// `M<x>` module descriptions by x.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub modules: BTreeMap<u32, Module>,
    /// `[ConnectedModules]` of a DCF.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub connected_modules: Option<Properties>,
    /// Sections canopener does not interpret, in file order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub other_sections: Vec<RawSection>,
}

impl PartialOrd for ObjectListKind {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for ObjectListKind {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        let rank = |k: &Self| Self::ALL.iter().position(|x| x == k);
        rank(self).cmp(&rank(other))
    }
}

impl Eds {
    /// Whether this is a DCF (it has a commissioning section or `LastEDS`).
    pub fn is_dcf(&self) -> bool {
        // CANopenNode writes an empty `LastEDS=` into plain EDS files; only a named template counts.
        self.commissioning.is_some()
            || self
                .file_info
                .last_eds
                .as_deref()
                .is_some_and(|s| !s.trim().is_empty())
    }

    /// The node-ID of a DCF, if given and valid.
    pub fn node_id(&self) -> Option<u8> {
        let id = int_of(self.commissioning.as_ref()?.node_id.as_deref()?)?;
        u8::try_from(id).ok().filter(|id| (1..=127).contains(id))
    }

    /// An object by index.
    pub fn object(&self, index: u16) -> Option<&Object> {
        self.objects.get(&index)
    }

    /// Resolves a data type to a basic CiA 301 type, following `DEFTYPE` objects in the file
    /// (CANFestival writes custom types that way; their sub 1 or value names the base type).
    pub fn resolve_data_type(&self, data_type: DataType) -> DataType {
        resolve_data_type_in(&self.objects, data_type)
    }

    /// The typed default value of an object (sub `None`) or sub-object.
    pub fn default_value(&self, index: u16, sub: Option<u8>) -> Option<Value> {
        let object = self.objects.get(&index)?;
        let attributes = match sub {
            None => &object.attributes,
            Some(s) => &object.subs.get(&s)?.attributes,
        };
        let data_type = attributes.data_type().map(|t| self.resolve_data_type(t));
        typed(attributes.default_value.as_deref(), data_type).value
    }
}

/// [`Eds::resolve_data_type`] over an object map (the loader checks objects while it owns the map).
pub(crate) fn resolve_data_type_in(objects: &BTreeMap<u16, Object>, data_type: DataType) -> DataType {
    if data_type.kind().is_some() {
        return data_type;
    }
    let Some(def) = objects.get(&data_type.0) else {
        return data_type;
    };
    let base = def
        .attributes
        .default_value
        .as_deref()
        .or_else(|| {
            def.subs
                .get(&1)
                .and_then(|s| s.attributes.default_value.as_deref())
        })
        .and_then(int_of)
        .and_then(|v| u16::try_from(v).ok());
    match base.map(DataType) {
        Some(t) if t.kind().is_some() => t,
        _ => data_type,
    }
}

mod hex_sub_keys {
    //! Sub-object maps serialise with two-digit hex keys (`"0A"`), as in `[1A00subA]`.
    use std::collections::BTreeMap;

    use serde::de::Error;
    use serde::{Deserialize, Deserializer, Serializer};

    use super::SubObject;

    pub(super) fn serialize<S: Serializer>(map: &BTreeMap<u8, SubObject>, s: S) -> Result<S::Ok, S::Error> {
        s.collect_map(map.iter().map(|(k, v)| (format!("{k:02X}"), v)))
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<BTreeMap<u8, SubObject>, D::Error> {
        let raw = BTreeMap::<String, SubObject>::deserialize(d)?;
        raw.into_iter()
            .map(|(k, v)| {
                u8::from_str_radix(&k, 16).map(|k| (k, v)).map_err(|_| {
                    D::Error::custom(format!("sub-object key `{k}` is not a hexadecimal sub-index"))
                })
            })
            .collect()
    }
}

mod hex_keys {
    //! Object maps serialise with `"1018"`-style keys, as EDS section names read.
    use std::collections::BTreeMap;

    use serde::de::Error;
    use serde::{Deserialize, Deserializer, Serializer};

    use super::Object;

    pub(super) fn serialize<S: Serializer>(map: &BTreeMap<u16, Object>, s: S) -> Result<S::Ok, S::Error> {
        s.collect_map(map.iter().map(|(k, v)| (format!("{k:04X}"), v)))
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<BTreeMap<u16, Object>, D::Error> {
        let raw = BTreeMap::<String, Object>::deserialize(d)?;
        raw.into_iter()
            .map(|(k, v)| {
                u16::from_str_radix(&k, 16)
                    .map(|k| (k, v))
                    .map_err(|_| D::Error::custom(format!("object key `{k}` is not a hexadecimal index")))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn device_info_key_lists_name_known_keys_once() {
        let keys: Vec<&str> = DeviceInfo::BAUD_RATE_KEYS
            .map(|(_, key)| key)
            .into_iter()
            .chain(DeviceInfo::FLAG_KEYS)
            .chain(DeviceInfo::NUMBER_KEYS.map(|(key, _)| key))
            .collect();
        let mut info = DeviceInfo::default();
        for key in &keys {
            assert!(info.slot_mut(key).is_some(), "{key} is not a [DeviceInfo] key");
        }
        let unique: std::collections::BTreeSet<&str> = keys.iter().copied().collect();
        assert_eq!(unique.len(), keys.len(), "a key is in two lists");
        assert_eq!(crate::dcf::BITRATES_KBIT, [10, 20, 50, 125, 250, 500, 800, 1000]);
    }

    #[test]
    fn keyed_sections_match_keys_case_insensitively() {
        let mut info = DeviceInfo::default();
        info.set("nrofrxpdo", "4");
        info.set("NG_Slave", "1");
        assert_eq!(info.nr_of_rx_pdo.as_deref(), Some("4"));
        assert_eq!(info.get("NrOfRXPDO"), Some("4"));
        assert_eq!(info.get("ng_slave"), Some("1"));
        assert_eq!(info.entries(), [("NrOfRXPDO", "4"), ("NG_Slave", "1")]);
    }

    #[test]
    fn decimal_keys_are_textual() {
        assert_eq!(decimal_key("1"), Some(1));
        assert_eq!(decimal_key("01"), None);
        assert_eq!(decimal_key("0x1"), None);
        let list = ObjectList::from_indices([0x1000, 0x1018]);
        assert_eq!(list.indices(), [0x1000, 0x1018]);
        assert_eq!(list.declared_count(), Some("2"));
    }

    #[test]
    fn attribute_views() {
        let mut a = Attributes::default();
        assert_eq!(a.object_type(), Some(ObjectType::Var));
        a.set("ObjectType", "0x9");
        a.set("DataType", "0x0007");
        a.set("AccessType", "RO");
        assert_eq!(a.object_type(), Some(ObjectType::Record));
        assert_eq!(a.data_type(), Some(DataType::UNSIGNED32));
        assert_eq!(a.access_type(), Some(AccessType::Ro));
        a.set("ObjectType", "3");
        assert_eq!(a.object_type(), None);
    }
}

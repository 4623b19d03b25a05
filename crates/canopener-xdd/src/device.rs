//! The device-level content of an XDD (ProfileBody file attributes, DeviceIdentity, baud rates,
//! general and master features, dummy usage, dynamic channels, commissioning) and its mapping to the
//! CiA 306 sections `[FileInfo]`, `[DeviceInfo]`, `[DummyUsage]`, `[DynamicChannels]` and
//! `[DeviceComissioning]` (reference §5–§7, §11.1, §11.2, §11.5, §11.6).
//!
//! As with objects, [`XmlDevice`] holds what the XML says and [`to_eds`] interprets it, so the writer
//! predicts what a reader will get back and keeps the rest in the side channel ([`side_channel_for`]).

use std::collections::BTreeMap;

use canopener_eds::model::{
    CommissioningSpelling, DeviceCommissioning, DeviceInfo, FileInfo, Module, ObjectList, ObjectListKind,
    Properties, Property, RawSection, int_of,
};
use canopener_eds::section_name::{SectionKind, classify};
use canopener_eds::{Eds, Object};

use crate::diag::{Note, XddCode};
use crate::entry::{nonempty, single_line};
use crate::notation::{
    BaudRate, date_to_eds, date_to_xsd, parse_baud_rate, parse_unsigned, time_to_eds, time_to_xsd,
};
use crate::side_channel::{self, Control};
use crate::xml::sanitize;

/// What the XML says about the device as a whole.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct XmlDevice {
    pub file_name: Option<String>,
    pub file_version: Option<String>,
    pub file_creator: Option<String>,
    pub file_creation_date: Option<String>,
    pub file_creation_time: Option<String>,
    pub file_modified_by: Option<String>,
    pub file_modification_date: Option<String>,
    pub file_modification_time: Option<String>,
    /// `DeviceIdentity/productText/description`.
    pub description: Option<String>,
    pub vendor_name: Option<String>,
    pub vendor_id: Option<String>,
    pub product_name: Option<String>,
    pub product_id: Option<String>,
    pub order_number: Option<String>,
    /// `supportedBaudRate@value`s; `None` without a `baudRate` element.
    pub baud_rates: Option<Vec<BaudRate>>,
    /// Whether there is a `NetworkManagement` element.
    pub network_management: bool,
    pub general: Option<GeneralFeatures>,
    pub master: Option<MasterFeatures>,
    /// `dummy@entry` split into `Dummy000n` and its value; `None` without `dummyUsage`.
    pub dummies: Option<Vec<(String, String)>>,
    pub dynamic_channels: Option<Vec<DynamicChannel>>,
    pub commissioning: Option<Commissioning>,
}

/// `CANopenGeneralFeatures`; `None` fields were not written (schema defaults apply) or could not be
/// read (named in `unreadable`: their keys are left out, no default stands in for them).
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct GeneralFeatures {
    /// Attributes whose value is not of their schema type and could not be read.
    pub unreadable: Vec<&'static str>,
    pub granularity: Option<u64>,
    pub nr_of_rx_pdo: Option<u64>,
    pub nr_of_tx_pdo: Option<u64>,
    pub boot_up_slave: Option<bool>,
    pub layer_setting_service_slave: Option<bool>,
    pub group_messaging: Option<bool>,
    pub dynamic_channels: Option<u64>,
    /// CANopenEditor's non-standard `ngSlave` (CiA 306 `NG_Slave`).
    pub ng_slave: Option<bool>,
    /// CANopenEditor's non-standard `ngMaster` (CiA 306 `NG_Master`).
    pub ng_master: Option<bool>,
    /// CANopenEditor's non-standard `NrOfNG_MonitoredNodes`.
    pub nr_of_ng_monitored_nodes: Option<u64>,
}

/// `CANopenMasterFeatures` (only `bootUpMaster` has an EDS key).
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct MasterFeatures {
    pub boot_up_master: Option<bool>,
    /// `bootUpMaster` is there but not an xsd:boolean: SimpleBootUpMaster is left out.
    pub boot_up_master_unreadable: bool,
}

/// `dynamicChannel` (CiA 311 §7.1) ↔ `[DynamicChannels]` segment (CiA 306-3).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct DynamicChannel {
    pub data_type: u16,
    /// `readOnly`, `writeOnly` or `readWriteOutput`.
    pub access_type: String,
    pub start_index: u16,
    pub end_index: u16,
    pub max_number: u64,
    pub address_offset: u64,
}

/// `deviceCommissioning` (XDC), values as written.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Commissioning {
    pub node_id: Option<String>,
    pub node_name: Option<String>,
    pub actual_baud_rate: Option<String>,
    pub network_number: Option<String>,
    pub network_name: Option<String>,
    pub canopen_manager: Option<bool>,
}

/// The CiA 306 sections an XDD describes.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Header {
    pub file_info: FileInfo,
    pub device_info: DeviceInfo,
    pub dummy_usage: Option<Properties>,
    pub dynamic_channels: Option<Properties>,
    pub commissioning: Option<DeviceCommissioning>,
}

/// The EDS format version written for a converted file (reference §11.1).
const EDS_VERSION: &str = "4.0";

/// Interprets the device-level content, applying schema defaults explicitly (P2): with a
/// `CANopenGeneralFeatures` element, every general-feature key is set (booleans `0`, counts `0`).
pub(crate) fn to_eds(d: &XmlDevice, notes: &mut Vec<Note>) -> Header {
    let mut h = Header::default();
    let fi = &mut h.file_info;
    fi.file_name = text(&d.file_name);
    fi.file_version = text(&d.file_version);
    fi.eds_version = Some(EDS_VERSION.to_owned());
    fi.created_by = text(&d.file_creator);
    fi.creation_date = text(&d.file_creation_date).map(|t| date_to_eds(&t).unwrap_or(t));
    fi.creation_time = text(&d.file_creation_time).map(|t| time_to_eds(&t).map_or(t, |(e, _)| e));
    fi.modified_by = text(&d.file_modified_by);
    fi.modification_date = text(&d.file_modification_date).map(|t| date_to_eds(&t).unwrap_or(t));
    fi.modification_time = text(&d.file_modification_time).map(|t| time_to_eds(&t).map_or(t, |(e, _)| e));
    let di = &mut h.device_info;
    if let Some(description) = text(&d.description) {
        let description = single_line("productText description", &description, notes);
        match unpack_description(&description) {
            Some(pairs) => {
                notes.push(Note::new(
                    XddCode::PackedDescription,
                    "productText holds `key=value|...` pairs (a Faulhaber/libedssharp convention); mapped to EDS keys".to_owned(),
                ));
                for (key, value) in pairs {
                    match key.to_ascii_lowercase().as_str() {
                        "filedescription" => h.file_info.description = Some(value),
                        "edsversion" => h.file_info.eds_version = Some(value),
                        "filerevision" | "filerevison" => h.file_info.file_revision = Some(value),
                        "revisionnum" | "revisionnumber" => di.revision_number = Some(value),
                        _ => h.file_info.set(&key, value),
                    }
                }
            }
            None => h.file_info.description = Some(description),
        }
    }
    di.vendor_name = text(&d.vendor_name);
    di.vendor_number = text(&d.vendor_id).map(|t| normalize_id("vendorID", &t, notes));
    di.product_name = text(&d.product_name);
    di.product_number = text(&d.product_id).map(|t| normalize_id("productID", &t, notes));
    di.order_code = text(&d.order_number);
    if let Some(rates) = &d.baud_rates {
        for (kbps, key) in DeviceInfo::BAUD_RATE_KEYS {
            let supported = rates.contains(&BaudRate::Kbps(u32::from(kbps)));
            di.set(key, flag(supported));
        }
    }
    if let Some(g) = &d.general {
        // An attribute that is absent takes its schema default; one that could not be read, none.
        let read = |name: &str| !g.unreadable.contains(&name);
        let boolean = |name, v: Option<bool>| read(name).then(|| flag(v.unwrap_or(false)));
        let count = |name, v: Option<u64>| read(name).then(|| v.unwrap_or(0).to_string());
        di.simple_boot_up_slave = boolean("bootUpSlave", g.boot_up_slave);
        di.granularity = g.granularity.map(|n| n.to_string());
        di.dynamic_channels_supported = count("dynamicChannels", g.dynamic_channels);
        di.group_messaging = boolean("groupMessaging", g.group_messaging);
        di.nr_of_rx_pdo = count("nrOfRxPDO", g.nr_of_rx_pdo);
        di.nr_of_tx_pdo = count("nrOfTxPDO", g.nr_of_tx_pdo);
        di.lss_supported = boolean("layerSettingServiceSlave", g.layer_setting_service_slave);
        if let Some(v) = g.ng_slave {
            di.set("NG_Slave", flag(v));
        }
        if let Some(v) = g.ng_master {
            di.set("NG_Master", flag(v));
        }
        if let Some(v) = g.nr_of_ng_monitored_nodes {
            di.set("NrOfNG_MonitoredNodes", v.to_string());
        }
    }
    if d.network_management && !d.master.as_ref().is_some_and(|m| m.boot_up_master_unreadable) {
        let master = d.master.as_ref().and_then(|m| m.boot_up_master).unwrap_or(false);
        di.simple_boot_up_master = Some(flag(master));
    }
    h.dummy_usage = d.dummies.as_ref().filter(|d| !d.is_empty()).map(|dummies| {
        Properties(
            dummies
                .iter()
                .map(|(k, v)| Property {
                    key: k.clone(),
                    value: v.clone(),
                })
                .collect(),
        )
    });
    h.dynamic_channels = d.dynamic_channels.as_ref().map(|channels| {
        let mut p = Properties::default();
        p.0.push(Property {
            key: "NrOfSeg".into(),
            value: channels.len().to_string(),
        });
        for (i, c) in channels.iter().enumerate() {
            let n = i + 1;
            let dir = match c.access_type.as_str() {
                "readOnly" => "ro",
                "writeOnly" => "wo",
                _ => "rww",
            };
            p.0.push(Property {
                key: format!("Type{n}"),
                value: format!("0x{:04X}", c.data_type),
            });
            p.0.push(Property {
                key: format!("Dir{n}"),
                value: dir.into(),
            });
            p.0.push(Property {
                key: format!("Range{n}"),
                value: format!("0x{:04X}-0x{:04X}", c.start_index, c.end_index),
            });
            p.0.push(Property {
                key: format!("PPOffset{n}"),
                value: c.address_offset.to_string(),
            });
        }
        p
    });
    h.commissioning = d.commissioning.as_ref().map(|c| {
        let mut dc = DeviceCommissioning {
            node_id: text(&c.node_id).map(|t| parse_unsigned(&t).map_or(t, |(v, _)| v.to_string())),
            node_name: text(&c.node_name),
            network_name: text(&c.network_name),
            net_number: text(&c.network_number),
            canopen_manager: c.canopen_manager.map(flag),
            ..DeviceCommissioning::default()
        };
        dc.baudrate = text(&c.actual_baud_rate).map(|t| match parse_baud_rate(&t) {
            Some((BaudRate::Kbps(k), _)) => k.to_string(),
            _ => t,
        });
        dc
    });
    h
}

/// Describes the device-level content of a model as XDD facts.
pub(crate) fn from_eds(eds: &Eds, file_name: &str, with_values: bool) -> XmlDevice {
    let fi = &eds.file_info;
    let di = &eds.device_info;
    let s = |v: &Option<String>| nonempty(v.as_deref()).map(sanitize);
    let mut d = XmlDevice {
        file_name: Some(sanitize(file_name)),
        file_version: s(&fi.file_version),
        file_creator: s(&fi.created_by),
        file_creation_date: fi.creation_date.as_deref().and_then(date_to_xsd),
        file_creation_time: fi.creation_time.as_deref().and_then(time_to_xsd),
        file_modified_by: s(&fi.modified_by),
        file_modification_date: fi.modification_date.as_deref().and_then(date_to_xsd),
        file_modification_time: fi.modification_time.as_deref().and_then(time_to_xsd),
        description: s(&fi.description),
        vendor_name: s(&di.vendor_name),
        vendor_id: id_text(di.vendor_number.as_deref()),
        product_name: s(&di.product_name),
        product_id: id_text(di.product_number.as_deref()),
        order_number: s(&di.order_code),
        network_management: true,
        ..XmlDevice::default()
    };
    let is_one = |v: Option<&str>| v.and_then(int_of) == Some(1);
    d.baud_rates = Some(
        DeviceInfo::BAUD_RATE_KEYS
            .iter()
            .filter(|(_, key)| is_one(di.get(key)))
            .map(|&(kbps, _)| BaudRate::Kbps(u32::from(kbps)))
            .collect(),
    );
    let count = |v: &Option<String>| v.as_deref().and_then(int_of).and_then(|n| u64::try_from(n).ok());
    let set = |v: &Option<String>| is_one(v.as_deref()).then_some(true);
    d.general = Some(GeneralFeatures {
        granularity: count(&di.granularity).filter(|&g| g <= 255),
        nr_of_rx_pdo: count(&di.nr_of_rx_pdo).filter(|&n| n > 0 && n <= 0xFFFF),
        nr_of_tx_pdo: count(&di.nr_of_tx_pdo).filter(|&n| n > 0 && n <= 0xFFFF),
        boot_up_slave: set(&di.simple_boot_up_slave),
        layer_setting_service_slave: set(&di.lss_supported),
        group_messaging: set(&di.group_messaging),
        dynamic_channels: count(&di.dynamic_channels_supported).filter(|&n| n > 0 && n <= 255),
        ..GeneralFeatures::default()
    });
    d.master = Some(MasterFeatures {
        boot_up_master: set(&di.simple_boot_up_master),
        boot_up_master_unreadable: false,
    });
    d.dummies = eds.dummy_usage.as_ref().map(|p| {
        p.0.iter()
            .filter_map(|e| {
                let n = dummy_number(&e.key)?;
                let value = int_of(&e.value).filter(|v| *v == 0 || *v == 1)?;
                Some((format!("Dummy{n:04X}"), value.to_string()))
            })
            .collect()
    });
    d.dynamic_channels = eds.dynamic_channels.as_ref().and_then(channels_from_eds);
    if with_values {
        d.commissioning = eds.commissioning.as_ref().map(|c| Commissioning {
            node_id: c.node_id.as_deref().and_then(int_of).map(|n| n.to_string()),
            node_name: Some(s(&c.node_name).unwrap_or_default()),
            actual_baud_rate: c
                .baudrate
                .as_deref()
                .and_then(int_of)
                .map(|k| format!("{k} Kbps")),
            network_number: c.net_number.as_deref().and_then(int_of).map(|n| n.to_string()),
            network_name: Some(s(&c.network_name).unwrap_or_default()),
            canopen_manager: Some(is_one(c.canopen_manager.as_deref())),
        });
    }
    d
}

/// The file-level side-channel properties that turn what a reader gets from `device` (and the
/// computed object lists) back into `eds`.
pub(crate) fn side_channel_for(eds: &Eds, device: &XmlDevice, with_values: bool) -> Vec<(String, String)> {
    let predicted = to_eds(device, &mut Vec::new());
    let mut out = Vec::new();
    let file_info: Vec<(&str, &str)> = eds
        .file_info
        .entries()
        .into_iter()
        .filter(|(k, _)| with_values || !k.eq_ignore_ascii_case("LastEDS"))
        .collect();
    keyed("FileInfo", &file_info, &predicted.file_info.entries(), &mut out);
    keyed(
        "DeviceInfo",
        &eds.device_info.entries(),
        &predicted.device_info.entries(),
        &mut out,
    );
    if let (true, Some(original)) = (with_values, &eds.commissioning) {
        let predicted = predicted.commissioning.unwrap_or_default();
        keyed(
            "DeviceComissioning",
            &original.entries(),
            &predicted.entries(),
            &mut out,
        );
    }
    if !same_properties(eds.dummy_usage.as_ref(), predicted.dummy_usage.as_ref()) {
        section("DummyUsage", eds.dummy_usage.as_ref(), &mut out);
    }
    if !same_properties(eds.dynamic_channels.as_ref(), predicted.dynamic_channels.as_ref()) {
        section("DynamicChannels", eds.dynamic_channels.as_ref(), &mut out);
    }
    section("Comments", eds.comments.as_ref(), &mut out);
    section("Tools", eds.tools.as_ref(), &mut out);
    for (n, tool) in &eds.tool_sections {
        section(&format!("Tool{n}"), Some(tool), &mut out);
    }
    section("SupportedModules", eds.supported_modules.as_ref(), &mut out);
    if with_values {
        section("ConnectedModules", eds.connected_modules.as_ref(), &mut out);
    }
    let computed = object_lists(&eds.objects);
    let same_lists = ObjectListKind::ALL.iter().all(|k| {
        let indices = |lists: &BTreeMap<ObjectListKind, ObjectList>| {
            lists.get(k).map(ObjectList::indices).unwrap_or_default()
        };
        indices(&eds.object_lists) == indices(&computed)
    });
    if !same_lists {
        for kind in ObjectListKind::ALL {
            match eds.object_lists.get(&kind) {
                Some(list) => section(kind.section_name(), Some(&list.0), &mut out),
                None => out.push(side_channel::property(Control::Absent, kind.section_name())),
            }
        }
    }
    for raw in &eds.other_sections {
        section(&raw.name, Some(&raw.entries), &mut out);
    }
    if !eds.modules.is_empty()
        && let Ok(json) = serde_json::to_string(&eds.modules)
    {
        out.push(side_channel::property(Control::Modules, &json));
    }
    if with_values
        && eds.commissioning.is_some()
        && eds.commissioning_spelling != CommissioningSpelling::default()
    {
        out.push(side_channel::property(
            Control::Spelling,
            eds.commissioning_spelling.section_name(),
        ));
    }
    if !out.is_empty() {
        out.insert(0, side_channel::property(Control::Version, side_channel::VERSION));
    }
    out
}

/// Applies the file-level side channel to a model built from an XDD.
pub(crate) fn apply_side_channel(properties: &[(String, String)], eds: &mut Eds, notes: &mut Vec<Note>) {
    let mut current: Option<(String, Properties)> = None;
    let mut lists: Option<BTreeMap<ObjectListKind, ObjectList>> = None;
    for (name, value) in properties {
        let Some((control, value)) = side_channel::decode(name, value) else {
            continue;
        };
        if control != Control::Entry
            && let Some((section, props)) = current.take()
        {
            restore_section(&section, props, eds, &mut lists, notes);
        }
        match control {
            Control::Version => {
                if value != side_channel::VERSION {
                    notes.push(Note::new(
                        XddCode::SideChannel,
                        format!(
                            "side-channel version `{value}` is newer than this reader (1); read as version 1"
                        ),
                    ));
                }
            }
            Control::Set => match value
                .split_once(':')
                .and_then(|(s, rest)| Some((s, rest.split_once('=')?)))
            {
                Some((section, (key, v))) if !key.is_empty() && set_key(eds, section, key, v) => {}
                _ => bad(name, &value, notes),
            },
            Control::Absent => match (value.split_once(':'), classify(&value)) {
                (Some((section, key)), _) if remove_key(eds, section, key) => {}
                (None, SectionKind::ObjectList(_)) => {
                    // The lists as written follow; none of this kind.
                    lists.get_or_insert_with(BTreeMap::new);
                }
                _ => bad(name, &value, notes),
            },
            Control::Section => current = Some((value, Properties::default())),
            Control::Entry => match (current.as_mut(), value.split_once('=')) {
                (Some((_, props)), Some((k, v))) => props.0.push(Property {
                    key: k.to_owned(),
                    value: v.to_owned(),
                }),
                _ => bad(name, &value, notes),
            },
            Control::Modules => match serde_json::from_str::<BTreeMap<u32, Module>>(&value) {
                Ok(modules) => eds.modules = modules,
                Err(e) => notes.push(Note::new(
                    XddCode::SideChannel,
                    format!("side-channel modules are not valid: {e}; ignored"),
                )),
            },
            Control::Spelling if value == CommissioningSpelling::DeviceCommissioning.section_name() => {
                eds.commissioning_spelling = CommissioningSpelling::DeviceCommissioning;
            }
            _ => bad(name, &value, notes),
        }
    }
    if let Some((section, props)) = current.take() {
        restore_section(&section, props, eds, &mut lists, notes);
    }
    if let Some(lists) = lists {
        eds.object_lists = lists;
    }
}

/// The object lists CiA 306 §4.6.3.1 gives these objects; kinds without objects have no list.
pub(crate) fn object_lists(objects: &BTreeMap<u16, Object>) -> BTreeMap<ObjectListKind, ObjectList> {
    ObjectListKind::ALL
        .iter()
        .filter_map(|&kind| {
            let indices: Vec<u16> = objects
                .keys()
                .copied()
                .filter(|&i| ObjectListKind::for_index(i) == kind)
                .collect();
            (!indices.is_empty()).then(|| (kind, ObjectList::from_indices(indices)))
        })
        .collect()
}

/// `DummyNNNN` with NNNN in 0001..=0007 (the only entries CiA 311 can express, P16).
pub(crate) fn dummy_number(key: &str) -> Option<u16> {
    let digits = key
        .get(..5)
        .filter(|p| p.eq_ignore_ascii_case("dummy"))
        .and(key.get(5..))?;
    let n = u16::from_str_radix(digits, 16).ok()?;
    (digits.len() == 4 && (1..=7).contains(&n)).then_some(n)
}

fn keyed(
    section: &str,
    original: &[(&str, &str)],
    predicted: &[(&str, &str)],
    out: &mut Vec<(String, String)>,
) {
    for (key, value) in original {
        if !same_value(Some(value), find(predicted, key)) {
            out.push(side_channel::property(
                Control::Set,
                &format!("{section}:{key}={value}"),
            ));
        }
    }
    for (key, value) in predicted {
        if find(original, key).is_none() && !same_value(None, Some(value)) {
            out.push(side_channel::property(
                Control::Absent,
                &format!("{section}:{key}"),
            ));
        }
    }
}

fn find<'a>(list: &[(&str, &'a str)], key: &str) -> Option<&'a str> {
    list.iter()
        .find(|(k, _)| k.eq_ignore_ascii_case(key))
        .map(|(_, v)| *v)
}

fn section(name: &str, props: Option<&Properties>, out: &mut Vec<(String, String)>) {
    let Some(props) = props else { return };
    out.push(side_channel::property(Control::Section, name));
    for p in &props.0 {
        out.push(side_channel::property(
            Control::Entry,
            &format!("{}={}", p.key, p.value),
        ));
    }
}

/// Values of a keyed section compare as in `canopener_eds::diff`: as text, or as numbers when both are.
fn same_value(a: Option<&str>, b: Option<&str>) -> bool {
    let (a, b) = (nonempty(a), nonempty(b));
    a == b || matches!((a.and_then(int_of), b.and_then(int_of)), (Some(x), Some(y)) if x == y)
}

fn same_properties(a: Option<&Properties>, b: Option<&Properties>) -> bool {
    let empty = Properties::default();
    let (a, b) = (a.unwrap_or(&empty), b.unwrap_or(&empty));
    a.0.len() == b.0.len()
        && a.0
            .iter()
            .zip(&b.0)
            .all(|(x, y)| x.key.eq_ignore_ascii_case(&y.key) && same_value(Some(&x.value), Some(&y.value)))
}

fn set_key(eds: &mut Eds, section: &str, key: &str, value: &str) -> bool {
    match section {
        "FileInfo" => eds.file_info.set(key, value),
        "DeviceInfo" => eds.device_info.set(key, value),
        "DeviceComissioning" => eds
            .commissioning
            .get_or_insert_with(DeviceCommissioning::default)
            .set(key, value),
        _ => return false,
    }
    true
}

fn remove_key(eds: &mut Eds, section: &str, key: &str) -> bool {
    macro_rules! remove {
        ($keyed:expr) => {{
            let keyed = $keyed;
            match keyed.slot_mut(key) {
                Some(slot) => *slot = None,
                None => keyed.extra.retain(|p| !p.key.eq_ignore_ascii_case(key)),
            }
        }};
    }
    match section {
        "FileInfo" => remove!(&mut eds.file_info),
        "DeviceInfo" => remove!(&mut eds.device_info),
        "DeviceComissioning" => {
            if let Some(c) = eds.commissioning.as_mut() {
                remove!(c);
            }
        }
        _ => return false,
    }
    true
}

fn restore_section(
    name: &str,
    props: Properties,
    eds: &mut Eds,
    lists: &mut Option<BTreeMap<ObjectListKind, ObjectList>>,
    notes: &mut Vec<Note>,
) {
    match classify(name) {
        SectionKind::DummyUsage => eds.dummy_usage = Some(props),
        SectionKind::DynamicChannels => eds.dynamic_channels = Some(props),
        SectionKind::Comments => eds.comments = Some(props),
        SectionKind::Tools => eds.tools = Some(props),
        SectionKind::Tool(n) => {
            eds.tool_sections.insert(n, props);
        }
        SectionKind::SupportedModules => eds.supported_modules = Some(props),
        SectionKind::ConnectedModules => eds.connected_modules = Some(props),
        SectionKind::ObjectList(kind) => {
            lists
                .get_or_insert_with(BTreeMap::new)
                .insert(kind, ObjectList(props));
        }
        SectionKind::Unknown => eds.other_sections.push(RawSection {
            name: name.to_owned(),
            entries: props,
        }),
        _ => notes.push(Note::new(
            XddCode::SideChannel,
            format!("side-channel section [{name}] cannot be restored this way; ignored"),
        )),
    }
}

fn bad(name: &str, value: &str, notes: &mut Vec<Note>) {
    notes.push(Note::new(
        XddCode::SideChannel,
        format!("side-channel property `{name}` = `{value}` is not understood; ignored"),
    ));
}

fn text(value: &Option<String>) -> Option<String> {
    nonempty(value.as_deref()).map(str::to_owned)
}

fn flag(value: bool) -> String {
    if value { "1" } else { "0" }.to_owned()
}

/// CiA 306 reads `0x…` as hex and bare digits as decimal (P9); an ID with hex letters but no `0x`
/// can only be hex, so it gets the prefix.
fn normalize_id(what: &str, text: &str, notes: &mut Vec<Note>) -> String {
    let is_decimal = text.bytes().all(|b| b.is_ascii_digit());
    if text.starts_with("0x") || text.starts_with("0X") || is_decimal {
        return text.to_owned();
    }
    if text.bytes().all(|b| b.is_ascii_hexdigit()) {
        notes.push(Note::new(
            XddCode::IdNotation,
            format!("{what} `{text}` has hex digits but no `0x`; read as 0x{text}"),
        ));
        return format!("0x{text}");
    }
    notes.push(Note::new(
        XddCode::IdNotation,
        format!("{what} `{text}` is not a number; kept as written"),
    ));
    text.to_owned()
}

/// `0x%08X` for a number (P9), the text itself otherwise.
fn id_text(value: Option<&str>) -> Option<String> {
    let value = nonempty(value)?;
    Some(match int_of(value).and_then(|n| u32::try_from(n).ok()) {
        Some(n) => format!("0x{n:08X}"),
        None => sanitize(value),
    })
}

/// `FileDescription=…|EdsVersion=4.0|FileRevison=1|RevisionNum=…` (reference §11.6).
fn unpack_description(text: &str) -> Option<Vec<(String, String)>> {
    const KNOWN: [&str; 6] = [
        "filedescription",
        "edsversion",
        "filerevision",
        "filerevison",
        "revisionnum",
        "revisionnumber",
    ];
    if !text.contains('|') {
        return None;
    }
    let mut pairs = Vec::new();
    for part in text.split('|').map(str::trim).filter(|p| !p.is_empty()) {
        let (key, value) = part.split_once('=')?;
        let key = key.trim();
        if key.is_empty() || !key.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_') {
            return None;
        }
        pairs.push((key.to_owned(), value.trim().to_owned()));
    }
    pairs
        .iter()
        .any(|(k, _)| KNOWN.contains(&k.to_ascii_lowercase().as_str()))
        .then_some(pairs)
}

/// Reads `[DynamicChannels]` (`NrOfSeg`, `Type<n>`, `Dir<n>`, `Range<n>`, `PPOffset<n>`); `None` when
/// any segment cannot be expressed as a `dynamicChannel` (the side channel keeps it then).
fn channels_from_eds(p: &Properties) -> Option<Vec<DynamicChannel>> {
    let count = usize::try_from(int_of(p.get("NrOfSeg")?)?).ok()?;
    let mut out = Vec::new();
    for n in 1..=count.min(255) {
        let data_type = u16::try_from(int_of(p.get(&format!("Type{n}"))?)?).ok()?;
        let access_type = match p.get(&format!("Dir{n}"))?.trim() {
            "ro" => "readOnly",
            "wo" => "writeOnly",
            "rww" => "readWriteOutput",
            _ => return None,
        };
        let (start, end) = p.get(&format!("Range{n}"))?.split_once('-')?;
        let start_index = u16::try_from(int_of(start)?).ok()?;
        let end_index = u16::try_from(int_of(end)?).ok()?;
        let address_offset = u64::try_from(int_of(p.get(&format!("PPOffset{n}"))?)?).ok()?;
        let max_number = u64::from(end_index.checked_sub(start_index)?) + 1;
        out.push(DynamicChannel {
            data_type,
            access_type: access_type.into(),
            start_index,
            end_index,
            max_number,
            address_offset,
        });
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eds(text: &str) -> Eds {
        canopener_eds::load(text.as_bytes()).eds
    }

    #[test]
    fn defaults_of_general_features_are_explicit() {
        let d = XmlDevice {
            network_management: true,
            general: Some(GeneralFeatures {
                granularity: Some(8),
                nr_of_rx_pdo: Some(4),
                ..GeneralFeatures::default()
            }),
            master: Some(MasterFeatures::default()),
            baud_rates: Some(vec![BaudRate::Kbps(125), BaudRate::Kbps(100), BaudRate::Auto]),
            ..XmlDevice::default()
        };
        let h = to_eds(&d, &mut Vec::new());
        let di = &h.device_info;
        assert_eq!(di.granularity.as_deref(), Some("8"));
        assert_eq!(di.nr_of_rx_pdo.as_deref(), Some("4"));
        assert_eq!(di.nr_of_tx_pdo.as_deref(), Some("0"));
        assert_eq!(di.simple_boot_up_slave.as_deref(), Some("0"));
        assert_eq!(di.simple_boot_up_master.as_deref(), Some("0"));
        assert_eq!(di.lss_supported.as_deref(), Some("0"));
        assert_eq!(di.baud_rate_125.as_deref(), Some("1"));
        assert_eq!(di.baud_rate_250.as_deref(), Some("0"));
        assert_eq!(h.file_info.eds_version.as_deref(), Some("4.0"));
    }

    #[test]
    fn packed_descriptions_and_ids_are_recognised() {
        let d = XmlDevice {
            description: Some(
                "FileDescription=Faulhaber MC|EdsVersion=4.0|FileRevison=1|RevisionNum=0x00010000|".into(),
            ),
            vendor_id: Some("327".into()),
            product_id: Some("046A".into()),
            ..XmlDevice::default()
        };
        let mut notes = Vec::new();
        let h = to_eds(&d, &mut notes);
        assert_eq!(h.file_info.description.as_deref(), Some("Faulhaber MC"));
        assert_eq!(h.file_info.file_revision.as_deref(), Some("1"));
        assert_eq!(h.device_info.revision_number.as_deref(), Some("0x00010000"));
        assert_eq!(
            h.device_info.vendor_number.as_deref(),
            Some("327"),
            "bare digits are decimal (P9)"
        );
        assert_eq!(h.device_info.product_number.as_deref(), Some("0x046A"));
        let codes: Vec<XddCode> = notes.iter().map(|n| n.code).collect();
        assert_eq!(codes, [XddCode::PackedDescription, XddCode::IdNotation]);
        assert_eq!(unpack_description("a | b"), None);
        assert_eq!(unpack_description("Size=3|Color=red"), None, "no known key");
    }

    #[test]
    fn commissioning_values_are_normalised() {
        let d = XmlDevice {
            commissioning: Some(Commissioning {
                node_id: Some("0x05".into()),
                actual_baud_rate: Some("500 Kbps".into()),
                canopen_manager: Some(false),
                node_name: Some(String::new()),
                ..Commissioning::default()
            }),
            ..XmlDevice::default()
        };
        let c = to_eds(&d, &mut Vec::new()).commissioning.unwrap_or_default();
        assert_eq!(
            c.entries(),
            [("NodeID", "5"), ("Baudrate", "500"), ("CANopenManager", "0")]
        );
    }

    #[test]
    fn dynamic_channels_map_both_ways() {
        let e =
            eds("[DynamicChannels]\nNrOfSeg=1\nType1=0x0007\nDir1=rww\nRange1=0xA080-0xA0BF\nPPOffset1=0\n");
        let channels = e
            .dynamic_channels
            .as_ref()
            .and_then(channels_from_eds)
            .unwrap_or_default();
        assert_eq!(channels.len(), 1);
        assert_eq!(channels.first().map(|c| c.max_number), Some(64));
        let d = XmlDevice {
            dynamic_channels: Some(channels),
            ..XmlDevice::default()
        };
        assert_eq!(to_eds(&d, &mut Vec::new()).dynamic_channels, e.dynamic_channels);
    }

    #[test]
    fn side_channel_restores_what_xdd_cannot_say() {
        let text = "[FileInfo]\nFileName=dev.eds\nFileRevision=3\nCreationDate=1-2-2020\nCreationTime=10:00AM\n\
            [DeviceInfo]\nVendorNumber=0x10\nRevisionNumber=0x2\nBaudRate_250=1\nCompactPDO=0x0\nNG_Slave=1\n\
            [DummyUsage]\nDummy0001=0\nDummy0008=1\n[Comments]\nLines=1\nLine1=100% made here\n\
            [Tool1]\nName=x\n[Vendor]\nKey=Value\n[MandatoryObjects]\nSupportedObjects=1\n1=0x1000\n\
            [OptionalObjects]\nSupportedObjects=1\n1=0x1000\n[1000]\nParameterName=Device type\n";
        let original = eds(text);
        let device = from_eds(&original, "dev.xdd", true);
        let props = side_channel_for(&original, &device, true);
        assert_eq!(props.first().map(|p| p.0.as_str()), Some("EDS:version"));
        let header = to_eds(&device, &mut Vec::new());
        let mut back = Eds {
            file_info: header.file_info,
            device_info: header.device_info,
            dummy_usage: header.dummy_usage,
            object_lists: object_lists(&original.objects),
            ..Eds::default()
        };
        let mut notes = Vec::new();
        apply_side_channel(&props, &mut back, &mut notes);
        assert!(notes.is_empty(), "{notes:?}");
        let entries = |e: &Eds| {
            e.file_info
                .entries()
                .into_iter()
                .map(|(k, v)| format!("{k}={v}"))
                .collect::<Vec<_>>()
        };
        assert_eq!(entries(&back), entries(&original));
        for (k, v) in original.device_info.entries() {
            assert!(same_value(Some(v), back.device_info.get(k)), "{k}");
        }
        assert_eq!(
            back.device_info.entries().len(),
            original.device_info.entries().len()
        );
        assert_eq!(back.dummy_usage, original.dummy_usage);
        assert_eq!(back.comments, original.comments);
        assert_eq!(back.tool_sections, original.tool_sections);
        assert_eq!(back.other_sections, original.other_sections);
        assert_eq!(
            back.object_lists, original.object_lists,
            "lists as written, even when wrong"
        );
    }

    #[test]
    fn dummy_numbers() {
        assert_eq!(dummy_number("Dummy0007"), Some(7));
        assert_eq!(dummy_number("dummy0001"), Some(1));
        assert_eq!(dummy_number("Dummy0008"), None);
        assert_eq!(dummy_number("Dummy07"), None);
        assert_eq!(dummy_number("Dμmmy0001"), None);
    }
}

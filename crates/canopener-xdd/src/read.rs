//! Reading an XDD/XDC into the EDS model (CiA 311 v1.0 and v1.1, reference §2–§9, §11).
//!
//! Elements and attributes are matched by local name, so the three namespace styles of §2 read the
//! same. Everything is lenient where the intent is clear and reported where a file departs from
//! CiA 311; only text that is not a CANopen XDD at all is an [`XddError`].

use std::collections::{BTreeMap, HashMap};

use canopener_eds::dcf::BITRATES_KBIT;
use canopener_eds::lines::LineIndex;
use canopener_eds::model::{Properties, int_of};
use canopener_eds::{Eds, Object, Origin, Span, SubObject};
use roxmltree::{Attribute, Document, Node};

use crate::device::{
    self, Commissioning, DynamicChannel, GeneralFeatures, MasterFeatures, XmlDevice, dummy_number,
};
use crate::diag::{Note, XddCode, XddDiagnostic};
use crate::entry::{self, Param, XmlEntry};
use crate::error::XddError;
use crate::locations::{Locations, SectionLocation};
use crate::notation::{
    BaudRate, Iec, ParamAccess, PdoMapping, Reading, UNSIGNED_BYTE, UNSIGNED_LONG, UNSIGNED_SHORT, Unsigned,
    hex_width_remark, is_ncname, parse_baud_rate, parse_hex, parse_unsigned, read_access_type, read_bool,
    read_hex, read_unsigned,
};
use crate::side_channel::{FILE_PARAMETER_ID, is_side_channel};
use crate::{XddKind, XddLoaded, XddVersion};

const XSI: &str = "http://www.w3.org/2001/XMLSchema-instance";
const CANOPEN_1_0: &str = "http://www.canopen.org/xml/1.0";
const CANOPEN_1_1: &str = "http://www.canopen.org/xml/1.1";
/// CANopenEditor's project wrappers (P20): `.nxdd` of CiA 311 v1.1 and the libedssharp v1.0 one.
const PROJECT_WRAPPERS: [&str; 2] = ["CanOpenProject_1_1", "OpenEDSProject"];
/// What happens to a key whose attribute could not be read: nothing stands in for it.
const LEFT_OUT: &str = "its key is left out (no default stands in for a value that cannot be read)";
/// How deep `dataTypeIDRef` chains are followed (a loop must not hang the reader).
const MAX_TYPE_DEPTH: usize = 8;
/// CANopenObject/CANopenSubObject attributes and the CiA 306 keys read from them.
const ENTRY_KEYS: &[(&str, &str)] = &[
    ("name", "ParameterName"),
    ("objectType", "ObjectType"),
    ("dataType", "DataType"),
    ("lowLimit", "LowLimit"),
    ("highLimit", "HighLimit"),
    ("accessType", "AccessType"),
    ("defaultValue", "DefaultValue"),
    ("actualValue", "ParameterValue"),
    ("denotation", "Denotation"),
    ("PDOmapping", "PDOMapping"),
    ("objFlags", "ObjFlags"),
    ("subNumber", "SubNumber"),
];
/// ProfileBody attributes and the `[FileInfo]` keys read from them.
const FILE_INFO_KEYS: &[(&str, &str)] = &[
    ("fileName", "FileName"),
    ("fileVersion", "FileVersion"),
    ("fileCreator", "CreatedBy"),
    ("fileCreationDate", "CreationDate"),
    ("fileCreationTime", "CreationTime"),
    ("fileModificationDate", "ModificationDate"),
    ("fileModificationTime", "ModificationTime"),
    ("fileModifiedBy", "ModifiedBy"),
];
/// DeviceIdentity elements and the `[DeviceInfo]` keys read from them.
const DEVICE_IDENTITY_KEYS: &[(&str, &str)] = &[
    ("vendorName", "VendorName"),
    ("vendorID", "VendorNumber"),
    ("productName", "ProductName"),
    ("productID", "ProductNumber"),
    ("orderNumber", "OrderCode"),
    ("productText", "Description"),
];
/// CANopenGeneralFeatures attributes and the `[DeviceInfo]` keys read from them.
const GENERAL_FEATURE_KEYS: &[(&str, &str)] = &[
    ("granularity", "Granularity"),
    ("nrOfRxPDO", "NrOfRXPDO"),
    ("nrOfTxPDO", "NrOfTXPDO"),
    ("bootUpSlave", "SimpleBootUpSlave"),
    ("layerSettingServiceSlave", "LSS_Supported"),
    ("groupMessaging", "GroupMessaging"),
    ("dynamicChannels", "DynamicChannelsSupported"),
    ("ngSlave", "NG_Slave"),
    ("ngMaster", "NG_Master"),
    ("NrOfNG_MonitoredNodes", "NrOfNG_MonitoredNodes"),
];
/// deviceCommissioning attributes and the `[DeviceComissioning]` keys read from them.
const COMMISSIONING_KEYS: &[(&str, &str)] = &[
    ("nodeID", "NodeID"),
    ("NodeID", "NodeID"),
    ("nodeName", "NodeName"),
    ("actualBaudRate", "Baudrate"),
    ("networkNumber", "NetNumber"),
    ("networkName", "NetworkName"),
    ("CANopenManager", "CANopenManager"),
];

/// Reads one device. A CANopenEditor project wrapper with exactly one device is read too.
pub(crate) fn read(bytes: &[u8]) -> Result<XddLoaded, XddError> {
    let text = decode(bytes)?;
    let doc = parse(&text)?;
    let positions = LineIndex::new(&text);
    let Containers {
        devices: containers,
        wrapper,
    } = containers(&doc, &positions)?;
    match containers.as_slice() {
        [only] => {
            let mut loaded = read_container(*only, &positions)?;
            if let Some(root) = wrapper {
                let (line, column) = positions.position(doc.root_element().range().start);
                loaded.diagnostics.insert(
                    0,
                    XddDiagnostic::new(
                        XddCode::ProjectWrapper,
                        Span::new(line, column, 0),
                        format!(
                            "`{root}` is a CANopenEditor project, not an XDD; the device inside was read"
                        ),
                    ),
                );
            }
            Ok(loaded)
        }
        [] => Err(XddError::EmptyProject {
            root: wrapper.unwrap_or_default(),
        }),
        more => Err(XddError::SeveralDevices {
            root: wrapper.unwrap_or_default(),
            count: more.len(),
        }),
    }
}

/// Reads every device of a CANopenEditor project wrapper (or the one device of a plain XDD).
pub(crate) fn read_project(bytes: &[u8]) -> Result<Vec<XddLoaded>, XddError> {
    let text = decode(bytes)?;
    let doc = parse(&text)?;
    let positions = LineIndex::new(&text);
    let Containers {
        devices: containers,
        wrapper,
    } = containers(&doc, &positions)?;
    if containers.is_empty() {
        return Err(XddError::EmptyProject {
            root: wrapper.unwrap_or_default(),
        });
    }
    containers
        .into_iter()
        .map(|c| read_container(c, &positions))
        .collect()
}

/// Decodes the bytes: UTF-8 (with or without BOM), UTF-16 with BOM, or Latin-1/Windows-1252 when
/// the XML declaration says so.
pub(crate) fn decode(bytes: &[u8]) -> Result<String, XddError> {
    if let Some(rest) = bytes.strip_prefix(&[0xEF, 0xBB, 0xBF]) {
        return utf8(rest, "UTF-8");
    }
    for (bom, big_endian) in [([0xFFu8, 0xFE], false), ([0xFE, 0xFF], true)] {
        if let Some(rest) = bytes.strip_prefix(&bom) {
            let units: Vec<u16> = rest
                .chunks(2)
                .map(|c| match (c, big_endian) {
                    ([a, b], false) => u16::from_le_bytes([*a, *b]),
                    ([a, b], true) => u16::from_be_bytes([*a, *b]),
                    // An odd trailing byte cannot be UTF-16: a lone high surrogate makes decoding fail below.
                    _ => 0xD800,
                })
                .collect();
            return char::decode_utf16(units)
                .collect::<Result<String, _>>()
                .map_err(|_| XddError::Encoding {
                    encoding: "UTF-16".into(),
                    line: 1,
                    column: 1,
                });
        }
    }
    let head =
        String::from_utf8_lossy(bytes.get(..bytes.len().min(200)).unwrap_or_default()).to_ascii_lowercase();
    let declared = head
        .find("encoding=")
        .and_then(|at| head.get(at + 10..))
        .and_then(|rest| rest.split(['"', '\'']).next())
        .map(str::to_owned);
    match declared.as_deref() {
        Some("iso-8859-1" | "latin1" | "latin-1" | "windows-1252" | "cp1252" | "iso-8859-15") => {
            Ok(canopener_eds::text::decode(bytes).0)
        }
        _ => utf8(bytes, declared.as_deref().unwrap_or("UTF-8")),
    }
}

fn utf8(bytes: &[u8], encoding: &str) -> Result<String, XddError> {
    match std::str::from_utf8(bytes) {
        Ok(text) => Ok(text.to_owned()),
        Err(e) => {
            let valid =
                String::from_utf8_lossy(bytes.get(..e.valid_up_to()).unwrap_or_default()).into_owned();
            let (line, column) = LineIndex::new(&valid).position(valid.len());
            Err(XddError::Encoding {
                encoding: encoding.to_owned(),
                line,
                column,
            })
        }
    }
}

fn parse(text: &str) -> Result<Document<'_>, XddError> {
    Document::parse(text).map_err(|e| {
        let pos = e.pos();
        let message = e.to_string();
        let suffix = format!(" at {}:{}", pos.row, pos.col);
        let message = message.strip_suffix(&suffix).unwrap_or(&message).to_owned();
        // roxmltree counts only LF as a line break; every other position of the file counts a lone CR too.
        let (line, column) = LineIndex::new(text).position_of_lf_counted(pos.row, pos.col);
        XddError::Xml {
            message,
            line,
            column,
        }
    })
}

/// The device containers of a document, and the project wrapper holding them if there is one.
struct Containers<'a, 'input> {
    devices: Vec<Node<'a, 'input>>,
    wrapper: Option<String>,
}

fn containers<'a, 'input>(
    doc: &'a Document<'input>,
    positions: &LineIndex<'_>,
) -> Result<Containers<'a, 'input>, XddError> {
    let root = doc.root_element();
    let name = root.tag_name().name();
    if name == "ISO15745ProfileContainer" {
        return Ok(Containers {
            devices: vec![root],
            wrapper: None,
        });
    }
    if PROJECT_WRAPPERS.contains(&name) {
        let inner = root
            .descendants()
            .filter(|n| n.is_element() && n.tag_name().name() == "ISO15745ProfileContainer")
            .filter(|n| {
                !n.ancestors()
                    .skip(1)
                    .any(|a| a.tag_name().name() == "ISO15745ProfileContainer")
            })
            .collect();
        return Ok(Containers {
            devices: inner,
            wrapper: Some(name.to_owned()),
        });
    }
    let (line, column) = positions.position(root.range().start);
    Err(XddError::NotXdd {
        root: name.to_owned(),
        line,
        column,
    })
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    Device,
    Network,
}

/// The device and communication network `ProfileBody` elements.
struct Bodies<'a, 'input> {
    device: Option<Node<'a, 'input>>,
    network: Option<Node<'a, 'input>>,
}

struct Reader<'a, 'input> {
    positions: &'a LineIndex<'a>,
    ids: HashMap<&'a str, Node<'a, 'input>>,
    diagnostics: Vec<XddDiagnostic>,
    /// Attributes CiA 311 does not define, by (element, attribute): count and first offset.
    unknown_attributes: BTreeMap<(String, String), (usize, usize)>,
    /// `property` names without a CiA 306 key: count each, and the first offset of any.
    unmapped_properties: (BTreeMap<String, usize>, usize),
    /// Where each part of the model came from.
    locations: Locations,
}

fn read_container(container: Node<'_, '_>, positions: &LineIndex<'_>) -> Result<XddLoaded, XddError> {
    let version = match container.tag_name().namespace() {
        Some(ns) if ns.contains("ethernet-powerlink") => {
            return Err(XddError::Powerlink {
                evidence: format!("namespace `{ns}`"),
            });
        }
        Some(CANOPEN_1_0) => Some(XddVersion::V1_0),
        Some(CANOPEN_1_1) => Some(XddVersion::V1_1),
        Some(ns) => {
            return Err(XddError::ForeignNamespace {
                namespace: ns.to_owned(),
            });
        }
        None => None,
    };
    let mut reader = Reader {
        positions,
        ids: HashMap::new(),
        diagnostics: Vec::new(),
        unknown_attributes: BTreeMap::new(),
        unmapped_properties: (BTreeMap::new(), 0),
        locations: Locations::default(),
    };
    if version.is_none() {
        reader.push(
            container.range().start,
            XddCode::NoNamespace,
            "the root element has no namespace (CiA 311 uses http://www.canopen.org/xml/1.0 or 1.1); read by local names".into(),
        );
    }
    let Bodies { device, network } = reader.profiles(container)?;
    reader.locations.file = reader.span(device.or(network).unwrap_or(container).range().start);
    reader.index_ids(container);
    let xml_device = reader.device(device, network);
    let mut notes = Vec::new();
    let header = device::to_eds(&xml_device, &mut notes);
    let at = device
        .or(network)
        .map_or(container.range().start, |n| n.range().start);
    reader.place(at, notes);
    let mut eds = Eds {
        file_info: header.file_info,
        device_info: header.device_info,
        dummy_usage: header.dummy_usage,
        dynamic_channels: header.dynamic_channels,
        commissioning: header.commissioning,
        ..Eds::default()
    };
    match network {
        Some(network) => eds.objects = reader.objects(network),
        None => reader.push(
            container.range().start,
            XddCode::MissingPart,
            "no ProfileBody_CommunicationNetwork_CANopen profile, so there is no object dictionary".into(),
        ),
    }
    eds.object_lists = device::object_lists(&eds.objects);
    if let Some(&param) = reader.ids.get(FILE_PARAMETER_ID) {
        let properties = reader.properties(param);
        let mut notes = Vec::new();
        device::apply_side_channel(&properties, &mut eds, &mut notes);
        reader.place(param.range().start, notes);
    }
    reader.report_unknown_attributes();
    reader.report_unmapped_properties();
    let has_values = eds.objects.values().any(|o| {
        std::iter::once(&o.attributes)
            .chain(o.subs.values().map(|s| &s.attributes))
            .any(|a| {
                entry::nonempty(a.parameter_value.as_deref()).is_some()
                    || entry::nonempty(a.denotation.as_deref()).is_some()
            })
    });
    let kind = if eds.commissioning.is_some() || has_values {
        XddKind::Xdc
    } else {
        XddKind::Xdd
    };
    let mut diagnostics = reader.diagnostics;
    diagnostics.sort_by_key(|d| (d.span.line, d.span.column));
    Ok(XddLoaded {
        eds,
        kind,
        version,
        diagnostics,
        locations: reader.locations,
    })
}

impl<'a, 'input> Reader<'a, 'input> {
    fn span(&self, offset: usize) -> Span {
        let (line, column) = self.positions.position(offset);
        Span::new(line, column, 0)
    }

    /// Records the element a device-level section was read from, and the attributes its keys were.
    fn locate_section(&mut self, section: &str, node: Node<'a, 'input>, keys: &[(&str, &str)]) {
        let element = self.span(node.range().start);
        let spans: Vec<(&str, Span)> = keys
            .iter()
            .filter_map(|&(attribute, key)| {
                Some((key, self.span(node.attribute_node(attribute)?.range().start)))
            })
            .collect();
        let location = self.locations.section(section, element);
        for (key, span) in spans {
            location.key(key, span);
        }
    }

    fn push(&mut self, offset: usize, code: XddCode, message: String) {
        let (line, column) = self.positions.position(offset);
        self.diagnostics
            .push(XddDiagnostic::new(code, Span::new(line, column, 0), message));
    }

    fn place(&mut self, offset: usize, notes: Vec<Note>) {
        for Note { code, message } in notes {
            self.push(offset, code, message);
        }
    }

    /// The device and communication network profile bodies, by `xsi:type` (not position).
    fn profiles(&mut self, container: Node<'a, 'input>) -> Result<Bodies<'a, 'input>, XddError> {
        let (mut device, mut network) = (None, None);
        for profile in elements(container, "ISO15745Profile") {
            let header = child(profile, "ProfileHeader");
            if let Some(tech) = header
                .and_then(|h| child(h, "ISO15745Reference"))
                .and_then(|r| child(r, "ProfileTechnology"))
            {
                let technology = text_of(tech);
                let technology = technology.trim();
                if technology.to_ascii_lowercase().contains("powerlink") {
                    return Err(XddError::Powerlink {
                        evidence: format!("ProfileTechnology `{technology}`"),
                    });
                }
                if !technology.is_empty() && !technology.eq_ignore_ascii_case("CANopen") {
                    let (line, column) = self.positions.position(tech.range().start);
                    return Err(XddError::NotCanopen {
                        technology: technology.to_owned(),
                        line,
                        column,
                    });
                }
            }
            let Some(body) = child(profile, "ProfileBody") else {
                continue;
            };
            let declared = body
                .attribute((XSI, "type"))
                .map(|t| t.rsplit(':').next().unwrap_or(t).to_owned());
            let role = match declared.as_deref() {
                Some(t) if t.contains("Powerlink") => {
                    return Err(XddError::Powerlink {
                        evidence: format!("ProfileBody type `{t}`"),
                    });
                }
                Some("ProfileBody_Device_CANopen") => Some(Role::Device),
                Some("ProfileBody_CommunicationNetwork_CANopen") => Some(Role::Network),
                Some(other) => {
                    let (line, column) = self.positions.position(body.range().start);
                    return Err(XddError::NotCanopen {
                        technology: other.to_owned(),
                        line,
                        column,
                    });
                }
                None => {
                    let class = header.and_then(|h| child(h, "ProfileClassID")).map(text_of);
                    let role = match class.as_deref().map(str::trim) {
                        Some("Device") => Some(Role::Device),
                        Some("CommunicationNetwork") => Some(Role::Network),
                        _ if child(body, "ApplicationLayers").is_some() => Some(Role::Network),
                        _ if child(body, "DeviceIdentity").is_some() => Some(Role::Device),
                        _ => None,
                    };
                    let what = match role {
                        Some(Role::Device) => "taken as the device profile",
                        Some(Role::Network) => "taken as the communication network profile",
                        None => "ignored",
                    };
                    self.push(
                        body.range().start,
                        XddCode::ProfileType,
                        format!("ProfileBody has no xsi:type; {what}"),
                    );
                    role
                }
            };
            let slot = match role {
                Some(Role::Device) => &mut device,
                Some(Role::Network) => &mut network,
                None => continue,
            };
            if slot.is_some() {
                self.push(
                    body.range().start,
                    XddCode::ProfileType,
                    "a second profile of the same kind; ignored".into(),
                );
            } else {
                *slot = Some(body);
            }
        }
        if device.is_none() {
            self.push(
                container.range().start,
                XddCode::MissingPart,
                "no ProfileBody_Device_CANopen profile; file and device information come from the network profile".into(),
            );
        }
        Ok(Bodies { device, network })
    }

    fn index_ids(&mut self, container: Node<'a, 'input>) {
        for node in container.descendants().filter(Node::is_element) {
            let Some(attr) = node.attribute_node("uniqueID") else {
                continue;
            };
            let id = attr.value();
            if !is_ncname(id) {
                self.push(
                    attr.range().start,
                    XddCode::SchemaType,
                    format!(
                        "{}: uniqueID `{id}` is not an xsd:ID (a name starting with a letter or `_`, \
                         without spaces or colons); references to it are resolved anyway",
                        node.tag_name().name()
                    ),
                );
            }
            if self.ids.contains_key(id) {
                self.push(
                    node.range().start,
                    XddCode::DuplicateUniqueId,
                    format!("uniqueID `{id}` is used before; this one is ignored"),
                );
            } else {
                self.ids.insert(id, node);
            }
        }
    }

    fn device(&mut self, device: Option<Node<'a, 'input>>, network: Option<Node<'a, 'input>>) -> XmlDevice {
        let mut d = XmlDevice::default();
        let body_attr = |name: &str| {
            device
                .and_then(|b| b.attribute(name))
                .or_else(|| network.and_then(|b| b.attribute(name)))
        };
        d.file_name = body_attr("fileName").map(str::to_owned);
        d.file_version = body_attr("fileVersion").map(str::to_owned);
        d.file_creator = body_attr("fileCreator").map(str::to_owned);
        d.file_modified_by = body_attr("fileModifiedBy").map(str::to_owned);
        for body in [device, network].into_iter().flatten() {
            self.locate_section("fileinfo", body, FILE_INFO_KEYS);
        }
        for (name, is_date) in [
            ("fileCreationDate", true),
            ("fileCreationTime", false),
            ("fileModificationDate", true),
            ("fileModificationTime", false),
        ] {
            let node = [device, network]
                .into_iter()
                .flatten()
                .find(|b| b.attribute(name).is_some());
            let value = node.and_then(|b| b.attribute_node(name));
            if let Some(attr) = value {
                self.check_date_time(name, attr.value(), is_date, attr.range().start);
            }
            let value = value.map(|a| a.value().to_owned());
            match name {
                "fileCreationDate" => d.file_creation_date = value,
                "fileCreationTime" => d.file_creation_time = value,
                "fileModificationDate" => d.file_modification_date = value,
                _ => d.file_modification_time = value,
            }
        }
        if let Some(identity) = device.and_then(|b| child(b, "DeviceIdentity")) {
            let element = self.span(identity.range().start);
            let spans: Vec<(&str, Span)> = DEVICE_IDENTITY_KEYS
                .iter()
                .filter_map(|&(name, key)| Some((key, self.span(child(identity, name)?.range().start))))
                .collect();
            let location = self.locations.section("deviceinfo", element);
            for (key, span) in spans {
                location.key(key, span);
            }
            let text = |name: &str| child(identity, name).map(text_of);
            d.vendor_name = text("vendorName");
            d.vendor_id = text("vendorID");
            d.product_name = text("productName");
            d.product_id = text("productID");
            d.order_number = text("orderNumber");
            d.description = child(identity, "productText")
                .and_then(|t| child(t, "description").or_else(|| child(t, "label")))
                .map(text_of);
        }
        let layers = network.and_then(|n| child(n, "ApplicationLayers"));
        if let Some(identity) = layers.and_then(|l| child(l, "identity")) {
            for (name, slot) in [("vendorID", &mut d.vendor_id), ("productID", &mut d.product_id)] {
                let Some(node) = child(identity, name) else {
                    continue;
                };
                let value = text_of(node);
                match slot.as_deref().map(str::trim).filter(|v| !v.is_empty()) {
                    None => *slot = Some(value),
                    Some(first) if !same_id(first, value.trim()) => {
                        let message = format!(
                            "ApplicationLayers identity {name} `{}` differs from DeviceIdentity `{first}`; DeviceIdentity is used",
                            value.trim()
                        );
                        self.push(node.range().start, XddCode::IdNotation, message);
                    }
                    Some(_) => {}
                }
            }
        }
        if let Some(layers) = layers {
            for (name, section) in [
                ("dummyUsage", "dummyusage"),
                ("dynamicChannels", "dynamicchannels"),
            ] {
                if let Some(node) = child(layers, name) {
                    self.locate_section(section, node, &[]);
                }
            }
            d.dummies = child(layers, "dummyUsage").map(|u| self.dummies(u));
            d.dynamic_channels = child(layers, "dynamicChannels").map(|c| self.dynamic_channels(c));
        }
        let physical = network
            .and_then(|n| child(n, "TransportLayers"))
            .and_then(|t| child(t, "PhysicalLayer"));
        if let Some(baud) = physical.and_then(|p| child(p, "baudRate")) {
            let at = self.span(baud.range().start);
            let location = self.locations.section("deviceinfo", at);
            for kbit in BITRATES_KBIT {
                location.key(&format!("BaudRate_{kbit}"), at);
            }
            d.baud_rates = Some(self.baud_rates(baud));
        }
        if let Some(management) = network.and_then(|n| child(n, "NetworkManagement")) {
            d.network_management = true;
            match child(management, "CANopenGeneralFeatures") {
                Some(g) => {
                    self.locate_section("deviceinfo", g, GENERAL_FEATURE_KEYS);
                    d.general = Some(self.general_features(g));
                }
                None => self.push(
                    management.range().start,
                    XddCode::MissingPart,
                    "NetworkManagement without CANopenGeneralFeatures".into(),
                ),
            }
            d.master = child(management, "CANopenMasterFeatures").map(|m| {
                let boot_up_master = self.boolean("CANopenMasterFeatures", m, "bootUpMaster");
                MasterFeatures {
                    boot_up_master: boot_up_master.flatten(),
                    boot_up_master_unreadable: boot_up_master == Some(None),
                }
            });
            if let Some(m) = child(management, "CANopenMasterFeatures") {
                self.locate_section("deviceinfo", m, &[("bootUpMaster", "SimpleBootUpMaster")]);
                self.note_attributes(
                    m,
                    &[
                        "bootUpMaster",
                        "flyingMaster",
                        "SDOManager",
                        "configurationManager",
                        "layerSettingServiceMaster",
                    ],
                );
            }
            if let Some(c) = child(management, "deviceCommissioning") {
                self.locate_section("devicecomissioning", c, COMMISSIONING_KEYS);
            }
            d.commissioning = child(management, "deviceCommissioning").map(|c| self.commissioning(c));
        }
        d
    }

    fn check_date_time(&mut self, name: &str, value: &str, is_date: bool, offset: usize) {
        if value.trim().is_empty() {
            return;
        }
        let message = if is_date {
            crate::notation::date_to_eds(value)
                .is_none()
                .then(|| format!("{name} `{value}` is not an xsd:date (YYYY-MM-DD); kept as written"))
        } else {
            match crate::notation::time_to_eds(value) {
                None => Some(format!(
                    "{name} `{value}` is not an xsd:time (hh:mm:ss); kept as written"
                )),
                Some((eds, true)) => Some(format!(
                    "{name} `{value}` is not an xsd:time (hh:mm:ss); read as {eds}"
                )),
                Some(_) => None,
            }
        };
        if let Some(message) = message {
            self.push(offset, XddCode::DateTimeNotation, message);
        }
    }

    fn dummies(&mut self, usage: Node<'a, 'input>) -> Vec<(String, String)> {
        let mut out = Vec::new();
        for dummy in elements(usage, "dummy") {
            let entry = dummy.attribute("entry").unwrap_or("");
            let Some((key, value)) = entry.split_once('=') else {
                self.push(
                    dummy.range().start,
                    XddCode::InvalidDummy,
                    format!("dummy entry `{entry}` is not `DummyNNNN=0|1`; ignored"),
                );
                continue;
            };
            let (key, value) = (key.trim(), value.trim());
            if dummy_number(key).is_none() || !matches!(value, "0" | "1") {
                self.push(
                    dummy.range().start,
                    XddCode::InvalidDummy,
                    format!("dummy entry `{entry}` is outside Dummy0001=0 ... Dummy0007=1 (CiA 311 P16); kept as written"),
                );
            }
            out.push((key.to_owned(), value.to_owned()));
        }
        out
    }

    fn dynamic_channels(&mut self, channels: Node<'a, 'input>) -> Vec<DynamicChannel> {
        let mut out = Vec::new();
        for c in elements(channels, "dynamicChannel") {
            let hex = |name: &str| c.attribute(name).and_then(parse_hex).map(|h| h.value);
            let parsed = (|| {
                Some(DynamicChannel {
                    data_type: u16::try_from(hex("dataType")?).ok()?,
                    access_type: c
                        .attribute("accessType")
                        .filter(|a| matches!(*a, "readOnly" | "writeOnly" | "readWriteOutput"))?
                        .to_owned(),
                    start_index: u16::try_from(hex("startIndex")?).ok()?,
                    end_index: u16::try_from(hex("endIndex")?).ok()?,
                    max_number: c.attribute("maxNumber").and_then(parse_unsigned)?.0,
                    address_offset: hex("addressOffset")?,
                })
            })();
            match parsed {
                Some(channel) => out.push(channel),
                None => self.push(
                    c.range().start,
                    XddCode::UnknownToken,
                    "dynamicChannel lacks or misspells dataType, accessType, startIndex, endIndex, maxNumber or addressOffset; ignored".into(),
                ),
            }
        }
        out
    }

    fn baud_rates(&mut self, baud: Node<'a, 'input>) -> Vec<BaudRate> {
        let mut out = Vec::new();
        for rate in elements(baud, "supportedBaudRate") {
            let value = rate.attribute("value").unwrap_or("");
            match parse_baud_rate(value) {
                Some((r, lenient)) => {
                    if lenient {
                        self.push(
                            rate.range().start,
                            XddCode::UnknownToken,
                            format!(
                                "baud rate `{value}` is not spelt as CiA 311 does (`250 Kbps`); read as {r:?}"
                            ),
                        );
                    }
                    if matches!(r, BaudRate::Auto | BaudRate::Kbps(100)) {
                        self.push(
                            rate.range().start,
                            XddCode::BaudRateWithoutKey,
                            format!(
                                "baud rate `{value}` has no CiA 306 BaudRate_ key; not carried into the EDS"
                            ),
                        );
                    } else if matches!(r, BaudRate::Kbps(k) if !BITRATES_KBIT.iter().any(|&b| u32::from(b) == k))
                    {
                        self.push(
                            rate.range().start,
                            XddCode::UnknownToken,
                            format!("baud rate `{value}` is not one CANopen defines; ignored"),
                        );
                    }
                    out.push(r);
                }
                None => self.push(
                    rate.range().start,
                    XddCode::UnknownToken,
                    format!("baud rate `{value}` is not a CiA 311 baud rate; ignored"),
                ),
            }
        }
        out
    }

    fn general_features(&mut self, g: Node<'a, 'input>) -> GeneralFeatures {
        self.note_attributes(
            g,
            &[
                "groupMessaging",
                "dynamicChannels",
                "selfStartingDevice",
                "SDORequestingDevice",
                "granularity",
                "nrOfRxPDO",
                "nrOfTxPDO",
                "bootUpSlave",
                "layerSettingServiceSlave",
                "ngSlave",
                "ngMaster",
                "NrOfNG_MonitoredNodes",
            ],
        );
        for name in ["ngSlave", "ngMaster", "NrOfNG_MonitoredNodes"] {
            if let Some(a) = g.attribute_node(name) {
                self.push(
                    a.range().start,
                    XddCode::NonStandardAttribute,
                    format!("`{name}` is a CANopenEditor extension, not CiA 311; read into the CiA 306 node-guarding keys"),
                );
            }
        }
        let mut unreadable = Vec::new();
        let mut number = |reader: &mut Self, name: &'static str, ty: Unsigned| {
            let read = reader.number("CANopenGeneralFeatures", g, name, ty);
            if read == Some(None) {
                unreadable.push(name);
            }
            read.flatten()
        };
        let granularity = number(self, "granularity", UNSIGNED_BYTE);
        let nr_of_rx_pdo = number(self, "nrOfRxPDO", UNSIGNED_SHORT);
        let nr_of_tx_pdo = number(self, "nrOfTxPDO", UNSIGNED_SHORT);
        let dynamic_channels = number(self, "dynamicChannels", UNSIGNED_BYTE);
        let nr_of_ng_monitored_nodes = number(self, "NrOfNG_MonitoredNodes", UNSIGNED_BYTE);
        if g.attribute("granularity").is_none() {
            self.push(
                g.range().start,
                XddCode::MissingPart,
                "CANopenGeneralFeatures lacks the required granularity; Granularity is left out".into(),
            );
        }
        let mut boolean = |reader: &mut Self, name: &'static str| {
            let read = reader.boolean("CANopenGeneralFeatures", g, name);
            if read == Some(None) {
                unreadable.push(name);
            }
            read.flatten()
        };
        let boot_up_slave = boolean(self, "bootUpSlave");
        let layer_setting_service_slave = boolean(self, "layerSettingServiceSlave");
        let group_messaging = boolean(self, "groupMessaging");
        let ng_slave = boolean(self, "ngSlave");
        let ng_master = boolean(self, "ngMaster");
        GeneralFeatures {
            unreadable,
            granularity,
            nr_of_rx_pdo,
            nr_of_tx_pdo,
            boot_up_slave,
            layer_setting_service_slave,
            group_messaging,
            dynamic_channels,
            ng_slave,
            ng_master,
            nr_of_ng_monitored_nodes,
        }
    }

    fn commissioning(&mut self, c: Node<'a, 'input>) -> Commissioning {
        self.note_attributes(
            c,
            &[
                "nodeID",
                "NodeID",
                "nodeName",
                "actualBaudRate",
                "networkNumber",
                "networkName",
                "CANopenManager",
            ],
        );
        let node_id = match (c.attribute_node("nodeID"), c.attribute_node("NodeID")) {
            (Some(a), _) => Some(a),
            (None, Some(a)) => {
                self.push(
                    a.range().start,
                    XddCode::NonStandardAttribute,
                    "`NodeID` is CANopenEditor's spelling; CiA 311 writes `nodeID` (P8)".into(),
                );
                Some(a)
            }
            (None, None) => None,
        };
        if let Some(a) = node_id {
            // A clear number written otherwise than as an xsd:unsignedByte breaks the schema (X016); whether
            // the value is a node-ID at all is X035, which `eds check` leaves to C802, the DCF rule.
            let id = match read_unsigned(a.value(), UNSIGNED_BYTE) {
                Reading::Valid(id) => Some(id),
                Reading::Lenient(id, why) => {
                    let message = format!("deviceCommissioning: {} `{}` {why}", a.name(), a.value());
                    self.push(a.range().start, XddCode::SchemaType, message);
                    Some(id)
                }
                Reading::Unreadable(_) => None,
            };
            if !id.is_some_and(|id| (1..=127).contains(&id)) {
                self.push(
                    a.range().start,
                    XddCode::Commissioning,
                    format!(
                        "nodeID `{}` is not a CANopen node-ID (1..=127); kept as written",
                        a.value()
                    ),
                );
            }
        }
        if let Some(a) = c.attribute_node("networkNumber") {
            let reading = read_unsigned(a.value(), UNSIGNED_LONG);
            let codes = (XddCode::SchemaType, XddCode::SchemaType);
            self.typed("deviceCommissioning", a, reading, codes, "kept as written");
        }
        if let Some(a) = c.attribute_node("actualBaudRate") {
            let usable = matches!(parse_baud_rate(a.value()), Some((BaudRate::Kbps(k), _)) if k > 0);
            if !usable {
                self.push(
                    a.range().start,
                    XddCode::Commissioning,
                    format!(
                        "actualBaudRate `{}` is not a bit rate; kept as written",
                        a.value()
                    ),
                );
            }
        }
        Commissioning {
            node_id: node_id.map(|a| a.value().to_owned()),
            node_name: c.attribute("nodeName").map(str::to_owned),
            actual_baud_rate: c.attribute("actualBaudRate").map(str::to_owned),
            network_number: c.attribute("networkNumber").map(str::to_owned),
            network_name: c.attribute("networkName").map(str::to_owned),
            canopen_manager: self.boolean("deviceCommissioning", c, "CANopenManager").flatten(),
        }
    }

    /// An xsd:boolean attribute of an `element`: `None` when it is absent, `Some(None)` when it is
    /// not a boolean (X023; its key is left out, the schema default does not stand in for it).
    fn boolean(&mut self, element: &str, node: Node<'a, 'input>, name: &str) -> Option<Option<bool>> {
        let attr = node.attribute_node(name)?;
        let codes = (XddCode::UnknownToken, XddCode::UnknownToken);
        Some(self.typed(element, attr, read_bool(attr.value()), codes, LEFT_OUT))
    }

    /// An unsigned integer attribute of an `element`, of the schema type `ty`: `None` when it is
    /// absent, `Some(None)` when it is not a number of the type (X016; its key is left out).
    fn number(
        &mut self,
        element: &str,
        node: Node<'a, 'input>,
        name: &str,
        ty: Unsigned,
    ) -> Option<Option<u64>> {
        let attr = node.attribute_node(name)?;
        let codes = (XddCode::SchemaType, XddCode::SchemaType);
        Some(self.typed(element, attr, read_unsigned(attr.value(), ty), codes, LEFT_OUT))
    }

    /// Reports how an attribute of `subject` (the element, as messages name it) departs from its schema
    /// type: a value read leniently is `codes.0`, saying what it was read as; an unreadable one is
    /// `codes.1` with its `consequence`. The value, if one could be read.
    fn typed<T>(
        &mut self,
        subject: &str,
        attr: Attribute<'a, 'input>,
        reading: Reading<T>,
        codes: (XddCode, XddCode),
        consequence: &str,
    ) -> Option<T> {
        let (name, value, at) = (attr.name(), attr.value(), attr.range().start);
        match reading {
            Reading::Valid(v) => Some(v),
            Reading::Lenient(v, why) => {
                self.push(at, codes.0, format!("{subject}: {name} `{value}` {why}"));
                Some(v)
            }
            Reading::Unreadable(why) => {
                let message = format!("{subject}: {name} `{value}` {why}; {consequence}");
                self.push(at, codes.1, message);
                None
            }
        }
    }

    /// Records attributes CiA 311 does not define for an element (reported once per kind).
    fn note_attributes(&mut self, node: Node<'a, 'input>, known: &[&str]) {
        for attr in node.attributes() {
            if attr.namespace().is_some() || known.contains(&attr.name()) {
                continue;
            }
            let key = (node.tag_name().name().to_owned(), attr.name().to_owned());
            let slot = self
                .unknown_attributes
                .entry(key)
                .or_insert((0, attr.range().start));
            slot.0 += 1;
        }
    }

    fn report_unknown_attributes(&mut self) {
        let unknown = std::mem::take(&mut self.unknown_attributes);
        for ((element, attribute), (count, offset)) in unknown {
            let times = if count == 1 {
                String::new()
            } else {
                format!(" ({count} times)")
            };
            self.push(
                offset,
                XddCode::NonStandardAttribute,
                format!("`{attribute}` is not a CiA 311 attribute of {element}{times}; ignored"),
            );
        }
    }

    fn objects(&mut self, network: Node<'a, 'input>) -> BTreeMap<u16, Object> {
        let mut objects = BTreeMap::new();
        let lists: Vec<Node<'a, 'input>> = child(network, "ApplicationLayers")
            .map(|l| elements(l, "CANopenObjectList").collect())
            .unwrap_or_default();
        if lists.is_empty() {
            self.push(
                network.range().start,
                XddCode::MissingPart,
                "no ApplicationLayers/CANopenObjectList, so there is no object dictionary".into(),
            );
        }
        for list in lists {
            self.note_attributes(
                list,
                &["mandatoryObjects", "optionalObjects", "manufacturerObjects"],
            );
            for node in elements(list, "CANopenObject") {
                let index = self
                    .index(node, "CANopenObject", "index", 0xFFFF, &[4])
                    .and_then(|i| u16::try_from(i).ok());
                let Some(index) = index else { continue };
                if objects.contains_key(&index) {
                    self.push(
                        node.range().start,
                        XddCode::DuplicateEntry,
                        format!("object {index:04X} appears before; this one is ignored"),
                    );
                    continue;
                }
                let object = self.object(node, index);
                objects.insert(index, object);
            }
        }
        objects
    }

    fn object(&mut self, node: Node<'a, 'input>, index: u16) -> Object {
        const KNOWN: [&str; 15] = [
            "index",
            "name",
            "objectType",
            "dataType",
            "lowLimit",
            "highLimit",
            "accessType",
            "defaultValue",
            "actualValue",
            "denotation",
            "PDOmapping",
            "objFlags",
            "uniqueIDRef",
            "subNumber",
            "rangeSelector",
        ];
        self.note_attributes(node, &KNOWN);
        self.locate_entry((index, None), node);
        let xml = self.entry(node, &format!("CANopenObject {index:04X}"));
        let disabled = xml.param.as_ref().is_some_and(|p| {
            p.properties
                .iter()
                .any(|(n, v)| n == "CO_disabled" && v == "true")
        });
        if disabled {
            self.push(
                node.range().start,
                XddCode::DisabledObject,
                format!("object {index:04X} is marked CO_disabled: CANopenEditor leaves it out of the device and its EDS export; kept"),
            );
        }
        let mut notes = Vec::new();
        let mapped = entry::to_eds(&xml, &mut notes);
        self.place(node.range().start, notes);
        let mut subs = BTreeMap::new();
        for sub_node in elements(node, "CANopenSubObject") {
            const SUB_KNOWN: [&str; 14] = [
                "subIndex",
                "name",
                "objectType",
                "dataType",
                "lowLimit",
                "highLimit",
                "accessType",
                "defaultValue",
                "actualValue",
                "denotation",
                "PDOmapping",
                "objFlags",
                "uniqueIDRef",
                "rangeSelector",
            ];
            self.note_attributes(sub_node, &SUB_KNOWN);
            let sub = self
                .index(
                    sub_node,
                    &format!("CANopenSubObject of {index:04X}"),
                    "subIndex",
                    0xFF,
                    &[2],
                )
                .and_then(|s| u8::try_from(s).ok());
            let Some(sub) = sub else { continue };
            if subs.contains_key(&sub) {
                self.push(
                    sub_node.range().start,
                    XddCode::DuplicateEntry,
                    format!("sub-index {sub:02X} of {index:04X} appears before; this one is ignored"),
                );
                continue;
            }
            self.locate_entry((index, Some(sub)), sub_node);
            let xml = self.entry(sub_node, &format!("CANopenSubObject {index:04X}sub{sub:X}"));
            let mut notes = Vec::new();
            let mapped = entry::to_eds(&xml, &mut notes);
            self.place(sub_node.range().start, notes);
            subs.insert(
                sub,
                SubObject {
                    attributes: mapped.attributes,
                    origin: Origin::Explicit,
                },
            );
        }
        // SubNumber counts the sub-objects without FFh, which holds the object's structure (CiA 306
        // §4.6.3.2); subNumber is read as that count.
        let counted = subs.keys().filter(|&&s| s != 0xFF).count();
        if let Some(attr) = node.attribute_node("subNumber") {
            let subject = format!("CANopenObject {index:04X}");
            let reading = read_unsigned(attr.value(), UNSIGNED_BYTE);
            let codes = (XddCode::SchemaType, XddCode::SchemaType);
            match self.typed(&subject, attr, reading, codes, "ignored; the elements count") {
                Some(n) if usize::try_from(n).is_ok_and(|n| n == counted) => {}
                Some(n) => self.push(
                    attr.range().start,
                    XddCode::SubNumberMismatch,
                    format!(
                        "subNumber {n} but object {index:04X} has {counted} CANopenSubObject elements{}; the elements count",
                        if counted == subs.len() { "" } else { " besides sub-index FFh" }
                    ),
                ),
                None => {}
            }
        }
        let mut attributes = mapped.attributes;
        if !subs.is_empty() {
            attributes.sub_number = Some(counted.to_string());
        }
        Object {
            attributes,
            subs,
            object_links: mapped.object_links.map(Properties),
            origin: if mapped.orphan {
                Origin::Orphan
            } else {
                Origin::Explicit
            },
            ..Object::default()
        }
    }

    /// Records where an object's or sub-object's values come from: its own attributes first (they
    /// win, as in [`Self::entry`]), then the elements of the parameter it references.
    fn locate_entry(&mut self, at: (u16, Option<u8>), node: Node<'a, 'input>) {
        let mut location = SectionLocation {
            element: self.span(node.range().start),
            ..SectionLocation::default()
        };
        for &(attribute, key) in ENTRY_KEYS {
            if let Some(a) = node.attribute_node(attribute) {
                location.key(key, self.span(a.range().start));
            }
        }
        let param = node
            .attribute("uniqueIDRef")
            .and_then(|id| self.ids.get(id).copied())
            .filter(|p| p.tag_name().name() == "parameter");
        if let Some(param) = param {
            if let Some(a) = param.attribute_node("access") {
                location.key("AccessType", self.span(a.range().start));
            }
            let range = child(param, "allowedValues").and_then(|a| child(a, "range"));
            let elements = [
                (child(param, "defaultValue"), "DefaultValue"),
                (child(param, "actualValue"), "ParameterValue"),
                (child(param, "denotation"), "Denotation"),
                (range.and_then(|r| child(r, "minValue")), "LowLimit"),
                (range.and_then(|r| child(r, "maxValue")), "HighLimit"),
                (
                    param.children().find(|c| {
                        c.is_element()
                            && (Iec::from_name(c.tag_name().name()).is_some()
                                || c.tag_name().name() == "dataTypeIDRef")
                    }),
                    "DataType",
                ),
            ];
            for (element, key) in elements {
                if let Some(e) = element {
                    location.key(key, self.span(e.range().start));
                }
            }
            location.key("ParameterName", self.span(param.range().start));
        }
        self.locations.entries.insert(at, location);
    }

    /// Reads the `index`/`subIndex` hexBinary of `subject`; `None` (X010) when it is missing, not a hex
    /// number or out of range. A clear number that is not xsd:hexBinary is read (X016).
    fn index(
        &mut self,
        node: Node<'a, 'input>,
        subject: &str,
        name: &str,
        max: u64,
        widths: &[usize],
    ) -> Option<u64> {
        let Some(attr) = node.attribute_node(name) else {
            self.push(
                node.range().start,
                XddCode::InvalidIndex,
                format!("{subject} without {name}; skipped"),
            );
            return None;
        };
        let codes = (XddCode::SchemaType, XddCode::InvalidIndex);
        let value = self.typed(subject, attr, read_hex(attr.value(), max), codes, "skipped")?;
        self.hex_width(subject, attr, widths);
        Some(value)
    }

    /// X012 for a valid hexBinary of another width than CiA 311 writes.
    fn hex_width(&mut self, subject: &str, attr: Attribute<'a, 'input>, widths: &[usize]) {
        if let Some(remark) = hex_width_remark(attr.name(), attr.value(), widths) {
            self.push(
                attr.range().start,
                XddCode::HexNotation,
                format!("{subject}: {remark}"),
            );
        }
    }

    fn entry(&mut self, node: Node<'a, 'input>, what: &str) -> XmlEntry {
        let mut e = XmlEntry {
            name: node.attribute("name").map(str::to_owned),
            ..XmlEntry::default()
        };
        if e.name.is_none() {
            self.push(
                node.range().start,
                XddCode::MissingName,
                format!(
                    "{what} has no name (required by CiA 311); the parameter label is used if there is one"
                ),
            );
        }
        match node.attribute_node("objectType") {
            None => self.push(
                node.range().start,
                XddCode::InvalidObjectType,
                format!("{what} has no objectType; ObjectType is left out"),
            ),
            Some(attr) => {
                let reading = read_unsigned(attr.value(), UNSIGNED_BYTE);
                let codes = (XddCode::SchemaType, XddCode::InvalidObjectType);
                e.object_type = self
                    .typed(what, attr, reading, codes, "ObjectType is left out")
                    .and_then(|code| u8::try_from(code).ok());
            }
        }
        // Empty dataType, accessType and objFlags are libedssharp's way of saying "not set" (P12).
        let stated = |name: &str| node.attribute_node(name).filter(|a| !a.value().trim().is_empty());
        if let Some(attr) = stated("dataType") {
            let codes = (XddCode::SchemaType, XddCode::InvalidDataType);
            let reading = read_hex(attr.value(), 0xFFFF);
            e.data_type = self
                .typed(what, attr, reading, codes, "ignored")
                .and_then(|t| u16::try_from(t).ok());
            if e.data_type.is_some() {
                self.hex_width(what, attr, &[2, 4]);
            }
        }
        if let Some(attr) = stated("accessType") {
            let codes = (XddCode::UnknownToken, XddCode::UnknownToken);
            let reading = read_access_type(attr.value());
            e.access = self.typed(what, attr, reading, codes, "the object's access is not known");
            e.access_unreadable = e.access.is_none();
        }
        if let Some(attr) = node.attribute_node("PDOmapping") {
            let codes = (XddCode::UnknownToken, XddCode::UnknownToken);
            let reading = PdoMapping::read(attr.value());
            e.pdo_mapping = self.typed(what, attr, reading, codes, "PDOMapping is left out");
        }
        if let Some(attr) = stated("objFlags") {
            let codes = (XddCode::SchemaType, XddCode::SchemaType);
            let reading = read_hex(attr.value(), u64::from(u32::MAX));
            e.obj_flags = self
                .typed(what, attr, reading, codes, "ObjFlags is left out")
                .and_then(|f| u32::try_from(f).ok());
            if e.obj_flags.is_some() {
                self.hex_width(what, attr, &[4]);
            }
        }
        let value = |name: &str| node.attribute(name).map(str::to_owned);
        e.default_value = value("defaultValue");
        e.low_limit = value("lowLimit");
        e.high_limit = value("highLimit");
        e.actual_value = value("actualValue");
        e.denotation = value("denotation");
        if let Some(attr) = node.attribute_node("uniqueIDRef") {
            let id = attr.value();
            match self.ids.get(id).copied() {
                Some(param) if param.tag_name().name() == "parameter" => {
                    e.param = Some(self.parameter(param));
                    self.check_allowed_values(node, param, what);
                }
                Some(other) => self.push(
                    attr.range().start,
                    XddCode::UnresolvedReference,
                    format!(
                        "{what}: uniqueIDRef `{id}` names a {}, not a parameter; ignored",
                        other.tag_name().name()
                    ),
                ),
                None => self.push(
                    attr.range().start,
                    XddCode::UnresolvedReference,
                    format!("{what}: uniqueIDRef `{id}` names no parameter; its data is missing"),
                ),
            }
        }
        e
    }

    /// `X101`: the default and actual values against a parameter's `allowedValues`, when those are
    /// more than the one range the model carries as LowLimit/HighLimit. The object's own attribute
    /// wins over the parameter's element, as when reading.
    fn check_allowed_values(&mut self, node: Node<'a, 'input>, param: Node<'a, 'input>, what: &str) {
        let Some(allowed) = child(param, "allowedValues") else {
            return;
        };
        let listed: Vec<&str> = elements(allowed, "value")
            .filter_map(|v| v.attribute("value"))
            .collect();
        let ranges: Vec<(Option<&str>, Option<&str>)> = elements(allowed, "range")
            .map(|r| {
                let bound = |name: &str| child(r, name).and_then(|v| v.attribute("value"));
                (bound("minValue"), bound("maxValue"))
            })
            .collect();
        if listed.is_empty() && ranges.len() < 2 {
            return;
        }
        for (attribute, element, role) in [
            ("defaultValue", "defaultValue", "default"),
            ("actualValue", "actualValue", "actual"),
        ] {
            let source = node
                .attribute_node(attribute)
                .map(|a| (a.value(), a.range().start))
                .or_else(|| {
                    let e = child(param, element)?;
                    Some((e.attribute("value")?, e.range().start))
                });
            let Some((value, offset)) = source else {
                continue;
            };
            if let Some(verdict) = allowed_verdict(value, &listed, &ranges)
                && !verdict
            {
                let mut parts: Vec<String> = listed.iter().map(|v| format!("`{v}`")).collect();
                parts.extend(
                    ranges
                        .iter()
                        .map(|(lo, hi)| format!("{}..{}", lo.unwrap_or(""), hi.unwrap_or(""))),
                );
                self.push(
                    offset,
                    XddCode::ValueNotAllowed,
                    format!(
                        "{role} value `{value}` of {what} is not among the allowedValues of its parameter ({})",
                        parts.join(", ")
                    ),
                );
            }
        }
    }

    fn parameter(&mut self, node: Node<'a, 'input>) -> Param {
        let mut p = Param::default();
        let subject = format!("parameter {}", node.attribute("uniqueID").unwrap_or_default());
        if let Some(attr) = node.attribute_node("access") {
            let codes = (XddCode::UnknownToken, XddCode::UnknownToken);
            let consequence = "AccessType is left out (the default `read` does not stand in for it)";
            p.access = self.typed(
                &subject,
                attr,
                ParamAccess::read(attr.value()),
                codes,
                consequence,
            );
            p.access_unreadable = p.access.is_none();
        }
        p.label = label(node);
        for c in node.children().filter(Node::is_element) {
            let name = c.tag_name().name();
            if let Some(iec) = Iec::from_name(name) {
                p.simple_type.get_or_insert(iec);
            } else if name == "dataTypeIDRef" {
                let Some(id) = c.attribute("uniqueIDRef") else {
                    self.push(
                        c.range().start,
                        XddCode::UnresolvedReference,
                        format!(
                            "{subject}: dataTypeIDRef without the required uniqueIDRef names no data type"
                        ),
                    );
                    continue;
                };
                let resolved = self.resolve_type(id, c, 0);
                if p.simple_type.is_none() {
                    p.simple_type = resolved;
                }
            }
        }
        p.denotation = child(node, "denotation").and_then(label);
        p.actual_value = self.value_of(&subject, node, "actualValue");
        p.default_value = self.value_of(&subject, node, "defaultValue");
        if let Some(allowed) = child(node, "allowedValues") {
            (p.min, p.max) = limits(allowed);
        }
        p.properties = self.properties(node);
        for property in elements(node, "property") {
            let name = property.attribute("name").unwrap_or("");
            if !is_side_channel(name) {
                let (names, first) = &mut self.unmapped_properties;
                if names.is_empty() {
                    *first = property.range().start;
                }
                *names.entry(name.to_owned()).or_default() += 1;
            }
        }
        p
    }

    /// The required `value` attribute of a parameter's `defaultValue` or `actualValue` element; an
    /// element without it is X003 and gives no value.
    fn value_of(&mut self, subject: &str, node: Node<'a, 'input>, element: &str) -> Option<String> {
        let e = child(node, element)?;
        let value = e.attribute("value");
        if value.is_none() {
            self.push(
                e.range().start,
                XddCode::MissingPart,
                format!("{subject}: {element} without the required value attribute; no value is read"),
            );
        }
        value.map(str::to_owned)
    }

    fn report_unmapped_properties(&mut self) {
        let (names, first) = std::mem::take(&mut self.unmapped_properties);
        if names.is_empty() {
            return;
        }
        let total: usize = names.values().sum();
        let list = names
            .iter()
            .map(|(n, c)| format!("{n} ×{c}"))
            .collect::<Vec<_>>()
            .join(", ");
        self.push(
            first,
            XddCode::UnmappedProperties,
            format!("{total} property elements have no CiA 306 key and are not carried: {list}"),
        );
    }

    fn properties(&self, node: Node<'a, 'input>) -> Vec<(String, String)> {
        elements(node, "property")
            .filter_map(|p| {
                Some((
                    p.attribute("name")?.to_owned(),
                    p.attribute("value").unwrap_or("").to_owned(),
                ))
            })
            .collect()
    }

    /// The simple type behind a `dataTypeIDRef` (through `enum` and `derived`); `None` for `array` and
    /// `struct`, which describe ARRAY/RECORD objects.
    fn resolve_type(&mut self, id: &str, at: Node<'a, 'input>, depth: usize) -> Option<Iec> {
        let Some(target) = self.ids.get(id).copied() else {
            self.push(
                at.range().start,
                XddCode::UnresolvedReference,
                format!("dataTypeIDRef `{id}` names no data type"),
            );
            return None;
        };
        if !matches!(target.tag_name().name(), "enum" | "derived") || depth >= MAX_TYPE_DEPTH {
            return None;
        }
        for c in target.children().filter(Node::is_element) {
            if let Some(iec) = Iec::from_name(c.tag_name().name()) {
                return Some(iec);
            }
            if c.tag_name().name() == "dataTypeIDRef" {
                let next = c.attribute("uniqueIDRef")?;
                return self.resolve_type(next, c, depth + 1);
            }
        }
        None
    }
}

/// A range bound as a number and as written.
type Bound<'a> = (i128, &'a String);

/// LowLimit and HighLimit from `allowedValues`: the one range's bounds; with several ranges the
/// lowest minimum and the highest maximum (CiA 306 limits can only say the hull; `X101` checks the
/// gaps), or the first range's when a bound is not a number.
fn limits(allowed: Node<'_, '_>) -> (Option<String>, Option<String>) {
    let bound = |range: Node<'_, '_>, name: &str| {
        child(range, name)
            .and_then(|v| v.attribute("value"))
            .map(str::to_owned)
    };
    let ranges: Vec<(Option<String>, Option<String>)> = elements(allowed, "range")
        .map(|r| (bound(r, "minValue"), bound(r, "maxValue")))
        .collect();
    let first = ranges.first().cloned().unwrap_or_default();
    if ranges.len() < 2 {
        return first;
    }
    // Each bound with its number; the hull is the written text of the lowest and highest.
    let numbered: Option<Vec<(Bound<'_>, Bound<'_>)>> = ranges
        .iter()
        .map(|(lo, hi)| {
            let (lo, hi) = (lo.as_ref()?, hi.as_ref()?);
            Some(((int_of(lo)?, lo), (int_of(hi)?, hi)))
        })
        .collect();
    let Some(numbered) = numbered else {
        return first;
    };
    let lowest = numbered.iter().map(|r| r.0).min_by_key(|b| b.0);
    let highest = numbered.iter().map(|r| r.1).max_by_key(|b| b.0);
    (lowest.map(|b| b.1.clone()), highest.map(|b| b.1.clone()))
}

/// Whether `value` is one of `listed` or inside one of `ranges`; `None` when that cannot be told
/// (a `$NODEID` formula, or a value or bound that is not a number where a number is needed).
fn allowed_verdict(value: &str, listed: &[&str], ranges: &[(Option<&str>, Option<&str>)]) -> Option<bool> {
    let value = value.trim();
    if value.is_empty() || value.to_ascii_uppercase().contains("$NODEID") {
        return None;
    }
    let number = |t: &str| -> Option<f64> {
        match int_of(t.trim()) {
            // Above 2^53 neighbouring integers compare equal; allowedValues of such width are
            // not seen in the corpus, and a bound rounds the same way as the value.
            Some(i) => Some(i as f64),
            None => t.trim().parse::<f64>().ok().filter(|f| f.is_finite()),
        }
    };
    let own = number(value);
    let same = |v: &str| v.trim() == value || matches!((own, number(v)), (Some(a), Some(b)) if a == b);
    if listed.iter().any(|v| same(v)) {
        return Some(true);
    }
    if ranges.is_empty() {
        return Some(false);
    }
    let own = own?;
    let mut undecided = false;
    for (lo, hi) in ranges {
        let bound = |b: &Option<&str>| b.map(number);
        match (bound(lo), bound(hi)) {
            (Some(None), _) | (_, Some(None)) => undecided = true,
            (lo, hi) => {
                let above = lo.flatten().is_none_or(|l| own >= l);
                let below = hi.flatten().is_none_or(|h| own <= h);
                if above && below {
                    return Some(true);
                }
            }
        }
    }
    (!undecided).then_some(false)
}

fn same_id(a: &str, b: &str) -> bool {
    let read = |t: &str| int_of(t).or_else(|| parse_hex(t).map(|h| i128::from(h.value)));
    a == b || matches!((read(a), read(b)), (Some(x), Some(y)) if x == y)
}

fn elements<'a, 'input: 'a>(
    node: Node<'a, 'input>,
    name: &'a str,
) -> impl Iterator<Item = Node<'a, 'input>> + 'a {
    node.children()
        .filter(move |c| c.is_element() && c.tag_name().name() == name)
}

fn child<'a, 'input>(node: Node<'a, 'input>, name: &str) -> Option<Node<'a, 'input>> {
    node.children()
        .find(|c| c.is_element() && c.tag_name().name() == name)
}

/// All text inside an element (comments and child elements left out).
fn text_of(node: Node<'_, '_>) -> String {
    node.descendants()
        .filter(Node::is_text)
        .filter_map(|t| t.text())
        .collect()
}

/// The first `label`, preferring English, else the first `description` (g_labels).
fn label(node: Node<'_, '_>) -> Option<String> {
    let labels: Vec<Node<'_, '_>> = elements(node, "label").collect();
    let english = labels.iter().find(|l| {
        l.attribute(("http://www.w3.org/XML/1998/namespace", "lang"))
            .or(l.attribute("lang"))
            .is_some_and(|lang| lang.starts_with("en"))
    });
    english
        .or(labels.first())
        .map(|l| text_of(*l))
        .or_else(|| child(node, "description").map(text_of))
}

#[cfg(test)]
mod tests {
    use super::*;

    const V11: &str = r#"<?xml version="1.0" encoding="utf-8"?>
<ISO15745ProfileContainer xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xmlns="http://www.canopen.org/xml/1.1">
  <ISO15745Profile>
    <ProfileHeader xmlns=""><ProfileClassID>Device</ProfileClassID><ISO15745Reference><ProfileTechnology>CANopen</ProfileTechnology></ISO15745Reference></ProfileHeader>
    <ProfileBody xmlns:q1="http://www.canopen.org/xml/1.1" xsi:type="q1:ProfileBody_Device_CANopen" fileName="t.xdd" fileCreationDate="2024-07-22" fileVersion="1" xmlns="">
      <q1:DeviceIdentity><q1:vendorName>ACME &amp; Co</q1:vendorName><q1:vendorID>0x000000FB</q1:vendorID><q1:productName>T</q1:productName></q1:DeviceIdentity>
      <q1:ApplicationProcess><q1:parameterList>
        <q1:parameter uniqueID="UID_OBJ_1001"><label lang="en">Error register</label><USINT /><q1:defaultValue value="0" /></q1:parameter>
        <q1:parameter uniqueID="UID_OBJ_1017" access="readWrite"><label lang="en">HB</label><UINT /><q1:defaultValue value="1000" /></q1:parameter>
      </q1:parameterList></q1:ApplicationProcess>
    </ProfileBody>
  </ISO15745Profile>
  <ISO15745Profile>
    <ProfileHeader xmlns=""><ProfileClassID>CommunicationNetwork</ProfileClassID></ProfileHeader>
    <ProfileBody xmlns:q2="http://www.canopen.org/xml/1.1" xsi:type="q2:ProfileBody_CommunicationNetwork_CANopen" fileName="t.xdd" xmlns="">
      <ApplicationLayers><q2:CANopenObjectList>
        <CANopenObject index="1001" name="Error register" objectType="7" PDOmapping="TPDO" uniqueIDRef="UID_OBJ_1001" />
        <CANopenObject index="1017" name="Producer heartbeat time" objectType="7" PDOmapping="no" uniqueIDRef="UID_OBJ_1017" />
      </q2:CANopenObjectList></ApplicationLayers>
      <TransportLayers><PhysicalLayer><baudRate><supportedBaudRate value="250 Kbps" /></baudRate></PhysicalLayer></TransportLayers>
      <NetworkManagement><CANopenGeneralFeatures granularity="8" /><CANopenMasterFeatures /></NetworkManagement>
    </ProfileBody>
  </ISO15745Profile>
</ISO15745ProfileContainer>"#;

    fn v10(text: &str) -> String {
        text.replace("http://www.canopen.org/xml/1.1", "http://www.canopen.org/xml/1.0")
            .replace(" xmlns=\"\"", "")
            .replace(" xmlns:q1=\"http://www.canopen.org/xml/1.0\"", "")
            .replace(" xmlns:q2=\"http://www.canopen.org/xml/1.0\"", "")
            .replace("q1:", "")
            .replace("q2:", "")
    }

    fn read_ok(text: &str) -> XddLoaded {
        match read(text.as_bytes()) {
            Ok(loaded) => loaded,
            Err(e) => panic!("read failed: {e}"),
        }
    }

    #[test]
    fn the_three_namespace_styles_read_the_same() {
        let style1 = read_ok(V11);
        let style2_text = v10(V11);
        assert!(!style2_text.contains("q1:") && style2_text.contains("xml/1.0"));
        let style2 = read_ok(&style2_text);
        let style3_text = style2_text.replace(" xmlns=\"http://www.canopen.org/xml/1.0\"", "");
        let style3 = read_ok(&style3_text);
        assert_eq!(style1.version, Some(XddVersion::V1_1));
        assert_eq!(style2.version, Some(XddVersion::V1_0));
        assert_eq!(style3.version, None);
        assert_eq!(
            style3.diagnostics.first().map(|d| d.code),
            Some(XddCode::NoNamespace)
        );
        for other in [&style2, &style3] {
            assert_eq!(other.eds.objects, style1.eds.objects);
            assert_eq!(other.eds.device_info, style1.eds.device_info);
        }
        let heartbeat = &style1.eds.objects[&0x1017].attributes;
        assert_eq!(heartbeat.access_type.as_deref(), Some("rw"));
        assert_eq!(heartbeat.data_type.as_deref(), Some("0x0006"));
        assert_eq!(heartbeat.default_value.as_deref(), Some("1000"));
        let error_register = &style1.eds.objects[&0x1001].attributes;
        assert_eq!(
            error_register.access_type.as_deref(),
            Some("ro"),
            "schema default read (P2)"
        );
        assert_eq!(error_register.pdo_mapping.as_deref(), Some("1"));
        assert_eq!(style1.eds.device_info.vendor_name.as_deref(), Some("ACME & Co"));
        assert_eq!(style1.eds.device_info.baud_rate_250.as_deref(), Some("1"));
        assert_eq!(style1.eds.device_info.baud_rate_500.as_deref(), Some("0"));
        assert_eq!(style1.eds.file_info.creation_date.as_deref(), Some("07-22-2024"));
        assert_eq!(style1.kind, XddKind::Xdd);
        assert!(style1.diagnostics.is_empty(), "{:?}", style1.diagnostics);
    }

    #[test]
    fn unresolved_references_are_reported_with_a_position() {
        let text = V11.replace(r#"uniqueIDRef="UID_OBJ_1017""#, r#"uniqueIDRef="UID_NOPE""#);
        let loaded = read_ok(&text);
        let d = loaded
            .diagnostics
            .iter()
            .find(|d| d.code == XddCode::UnresolvedReference)
            .map(|d| (d.span.line, d.span.column));
        let line = text.lines().position(|l| l.contains("UID_NOPE")).map(|l| l + 1);
        assert_eq!(d.map(|d| d.0), line.and_then(|l| u32::try_from(l).ok()));
        assert!(d.is_some_and(|d| d.1 > 1));
        assert_eq!(loaded.eds.objects[&0x1017].attributes.data_type, None);
    }

    #[test]
    fn data_type_references_resolve_through_enums() {
        let text = V11
            .replace("<q1:parameterList>", r#"<q1:dataTypeList><q1:enum name="Mode" uniqueID="T_MODE"><USINT /></q1:enum></q1:dataTypeList><q1:parameterList>"#)
            .replace(r#"<label lang="en">HB</label><UINT />"#, r#"<label lang="en">HB</label><q1:dataTypeIDRef uniqueIDRef="T_MODE" />"#);
        let loaded = read_ok(&text);
        assert_eq!(
            loaded.eds.objects[&0x1017].attributes.data_type.as_deref(),
            Some("0x0005")
        );
    }

    #[test]
    fn malformed_xml_is_an_error_with_a_position() {
        let text = "<ISO15745ProfileContainer>\n  <ISO15745Profile>\n</ISO15745ProfileContainer>";
        match read(text.as_bytes()) {
            Err(XddError::Xml {
                line,
                column,
                message,
            }) => {
                assert_eq!((line, column), (3, 1));
                assert_eq!(
                    message,
                    "expected 'ISO15745Profile' tag, not 'ISO15745ProfileContainer'"
                );
            }
            other => panic!("expected a malformed-XML error, got {other:?}"),
        }
        // A lone CR ends a line here as everywhere (canopener_eds::lines), though the XML parser
        // counts only LF.
        let old_mac = text.replace('\n', "\r");
        assert!(
            matches!(
                read(old_mac.as_bytes()),
                Err(XddError::Xml {
                    line: 3,
                    column: 1,
                    ..
                })
            ),
            "{:?}",
            read(old_mac.as_bytes()).err()
        );
        assert!(matches!(read(b""), Err(XddError::Xml { .. })));
        assert!(matches!(
            read(&[0xFF, 0x00, 0x41]),
            Err(XddError::Encoding { .. })
        ));
    }

    #[test]
    fn look_alikes_are_refused() {
        let powerlink = V11.replace(
            "http://www.canopen.org/xml/1.1\">",
            "http://www.ethernet-powerlink.org\">",
        );
        let err = read(powerlink.as_bytes())
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            err.starts_with(
                "this is an Ethernet POWERLINK XDD (EPSG DS 311), not a CANopen CiA 311 device description"
            ),
            "{err}"
        );
        let dialect = V11.replace(
            "http://www.canopen.org/xml/1.1\">",
            "http://www.canopen.org/xml/CANopenDeviceProfile\">",
        );
        assert!(matches!(
            read(dialect.as_bytes()),
            Err(XddError::ForeignNamespace { .. })
        ));
        assert!(matches!(
            read(b"<html><body/></html>"),
            Err(XddError::NotXdd { .. })
        ));
        let ethercat = V11.replace("<ProfileTechnology>CANopen", "<ProfileTechnology>EtherCAT");
        assert!(matches!(
            read(ethercat.as_bytes()),
            Err(XddError::NotCanopen { .. })
        ));
    }

    #[test]
    fn project_wrappers_hold_devices() {
        let inner = V11.trim_start_matches(r#"<?xml version="1.0" encoding="utf-8"?>"#);
        let one = format!(r#"<CanOpenProject_1_1 version="1.1">{inner}</CanOpenProject_1_1>"#);
        let loaded = read_ok(&one);
        assert_eq!(
            loaded.diagnostics.first().map(|d| d.code),
            Some(XddCode::ProjectWrapper)
        );
        assert_eq!(loaded.eds.objects.len(), 2);
        let two = format!(r#"<CanOpenProject_1_1 version="1.1">{inner}{inner}</CanOpenProject_1_1>"#);
        assert!(matches!(
            read(two.as_bytes()),
            Err(XddError::SeveralDevices { count: 2, .. })
        ));
        assert_eq!(read_project(two.as_bytes()).map(|v| v.len()), Ok(2));
        assert!(matches!(
            read(b"<CanOpenProject_1_1/>"),
            Err(XddError::EmptyProject { .. })
        ));
    }

    #[test]
    fn lenient_hex_and_sub_numbers() {
        let text = V11.replace(
            r#"<CANopenObject index="1017" name="Producer heartbeat time" objectType="7" PDOmapping="no" uniqueIDRef="UID_OBJ_1017" />"#,
            r#"<CANopenObject index="0x1018" name="Identity" objectType="9" subNumber="3">
                 <CANopenSubObject subIndex="0000" name="n" objectType="7" dataType="05" accessType="ro" defaultValue="1" />
                 <CANopenSubObject subIndex="1" name="Vendor" objectType="7" dataType="0x0007" accessType="ro" objFlags="3" />
               </CANopenObject>"#,
        );
        let loaded = read_ok(&text);
        let identity = &loaded.eds.objects[&0x1018];
        assert_eq!(identity.subs.len(), 2);
        assert_eq!(identity.attributes.sub_number.as_deref(), Some("2"));
        assert_eq!(identity.subs[&1].attributes.data_type.as_deref(), Some("0x0007"));
        assert_eq!(identity.subs[&1].attributes.obj_flags.as_deref(), Some("0x3"));
        let count = |code| loaded.diagnostics.iter().filter(|d| d.code == code).count();
        // `0x1018`, sub `1`, `0x0007` and objFlags `3` are not xsd:hexBinary; `0000` is, of an odd width.
        assert_eq!(count(XddCode::SchemaType), 4, "{:#?}", loaded.diagnostics);
        assert_eq!(count(XddCode::HexNotation), 1, "{:#?}", loaded.diagnostics);
        assert_eq!(count(XddCode::SubNumberMismatch), 1);
        assert!(loaded.eds.commissioning.is_none());
    }

    /// Issue 22: a value outside its schema type is an error naming element and attribute; the model
    /// gets the value when it is clear and nothing otherwise, never the schema default.
    #[test]
    fn values_outside_their_schema_type_are_errors_and_never_defaults() {
        let read_with = |from: &str, to: &str| {
            assert!(V11.contains(from), "{from}");
            read_ok(&V11.replace(from, to))
        };
        let errors = |loaded: &XddLoaded| -> Vec<(XddCode, String)> {
            loaded
                .diagnostics
                .iter()
                .filter(|d| d.severity == canopener_eds::Severity::Error)
                .map(|d| (d.code, d.message.clone()))
                .collect()
        };
        let hb = r#"uniqueID="UID_OBJ_1017" access="readWrite""#;
        let rw = read_with(hb, r#"uniqueID="UID_OBJ_1017" access="rw""#);
        assert_eq!(
            rw.eds.objects[&0x1017].attributes.access_type.as_deref(),
            Some("rw")
        );
        assert_eq!(
            errors(&rw),
            [(
                XddCode::UnknownToken,
                "parameter UID_OBJ_1017: access `rw` is not a CiA 311 parameter access (const, read, write, \
                 readWrite, readWriteInput, readWriteOutput, noAccess); read as readWrite"
                    .to_owned()
            )]
        );
        let bogus = read_with(hb, r#"uniqueID="UID_OBJ_1017" access="full""#);
        assert_eq!(
            bogus.eds.objects[&0x1017].attributes.access_type, None,
            "not `read`"
        );
        assert_eq!(errors(&bogus).len(), 1);
        let yes = read_with(r#"PDOmapping="no""#, r#"PDOmapping="yes""#);
        assert_eq!(
            yes.eds.objects[&0x1017].attributes.pdo_mapping, None,
            "neither 0 nor 1"
        );
        assert!(
            errors(&yes)[0]
                .1
                .starts_with("CANopenObject 1017: PDOmapping `yes` is not")
        );
        let odd = read_with(r#"index="1017""#, r#"index="201""#);
        assert!(odd.eds.objects.contains_key(&0x0201));
        assert_eq!(errors(&odd)[0].0, XddCode::SchemaType);
        let wide = read_with(
            r#"index="1017" name="Producer heartbeat time" objectType="7""#,
            r#"index="1017" name="Producer heartbeat time" objectType="300""#,
        );
        assert_eq!(wide.eds.objects[&0x1017].attributes.object_type, None);
        assert_eq!(errors(&wide)[0].0, XddCode::InvalidObjectType);
        let slave = read_with(
            r#"granularity="8""#,
            r#"granularity="8" bootUpSlave="yes" nrOfRxPDO="0x2""#,
        );
        let info = &slave.eds.device_info;
        assert_eq!(info.simple_boot_up_slave, None, "not the default 0");
        assert_eq!(info.nr_of_rx_pdo.as_deref(), Some("2"));
        assert_eq!(
            info.group_messaging.as_deref(),
            Some("0"),
            "absent: the schema default"
        );
        let codes: Vec<XddCode> = errors(&slave).into_iter().map(|(c, _)| c).collect();
        assert_eq!(codes, [XddCode::UnknownToken, XddCode::SchemaType]);
    }

    #[test]
    fn locations_name_the_attribute_or_parameter_element_of_each_value() {
        let eds = canopener_eds::load(
            b"[DeviceInfo]\nVendorNumber=5\n[1017]\nParameterName=Producer heartbeat time\nObjectType=0x7\n\
              DataType=0x0006\nAccessType=rw\nDefaultValue=1000\nPDOMapping=0\n",
        )
        .eds;
        let text = crate::write(&eds, &crate::WriteOptions::CANOPEN_EDITOR);
        let loaded = read_ok(&text);
        let line_of = |needle: &str| {
            text.lines()
                .position(|l| l.contains(needle))
                .and_then(|i| u32::try_from(i + 1).ok())
                .unwrap_or_else(|| panic!("{needle} not written"))
        };
        let at = |section: &str, key: Option<&str>| loaded.locations.find(Some(section), key).line;
        assert_eq!(
            at("1017", Some("DefaultValue")),
            line_of("<q1:defaultValue value=\"1000\"")
        );
        assert_eq!(
            at("1017", Some("AccessType")),
            line_of(r#"uniqueID="UID_OBJ_1017""#)
        );
        assert_eq!(
            at("1017", Some("PDOMapping")),
            line_of(r#"<CANopenObject index="1017""#)
        );
        assert_eq!(at("1017sub3", None), line_of(r#"<CANopenObject index="1017""#));
        assert_eq!(at("DeviceInfo", Some("VendorNumber")), line_of("<q1:vendorID>"));
        assert_eq!(loaded.locations.find(None, None), loaded.locations.file);
        assert_eq!(loaded.locations.file.line, line_of("ProfileBody_Device_CANopen"));
    }

    #[test]
    fn values_outside_allowed_values_are_reported_and_ranges_give_their_hull() {
        let text = r#"<ISO15745ProfileContainer xmlns="http://www.canopen.org/xml/1.1"><ISO15745Profile>
<ProfileBody xsi:type="ProfileBody_Device_CANopen" xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"><ApplicationProcess><parameterList>
<parameter uniqueID="P1" access="readWrite"><UINT/><defaultValue value="50"/>
<allowedValues><range><minValue value="1"/><maxValue value="10"/></range><range><minValue value="100"/><maxValue value="0x3E8"/></range></allowedValues></parameter>
<parameter uniqueID="P2" access="readWrite"><USINT/><defaultValue value="3"/>
<allowedValues><value value="1"/><value value="0x3"/></allowedValues></parameter>
</parameterList></ApplicationProcess></ProfileBody></ISO15745Profile><ISO15745Profile>
<ProfileBody xsi:type="ProfileBody_CommunicationNetwork_CANopen" xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"><ApplicationLayers><CANopenObjectList>
<CANopenObject index="2000" name="a" objectType="7" uniqueIDRef="P1"/>
<CANopenObject index="2001" name="b" objectType="7" uniqueIDRef="P2"/>
<CANopenObject index="2002" name="c" objectType="7" uniqueIDRef="P2" defaultValue="2"/>
</CANopenObjectList></ApplicationLayers></ProfileBody></ISO15745Profile></ISO15745ProfileContainer>"#;
        let loaded = read_ok(text);
        let not_allowed: Vec<u32> = loaded
            .diagnostics
            .iter()
            .filter(|d| d.code == XddCode::ValueNotAllowed)
            .map(|d| d.span.line)
            .collect();
        // 2000: 50 lies between the ranges; 2001: 3 is listed as 0x3; 2002: its own 2 is not listed.
        assert_eq!(not_allowed, [3, 11], "{:?}", loaded.diagnostics);
        let a = &loaded.eds.objects[&0x2000].attributes;
        assert_eq!(
            (a.low_limit.as_deref(), a.high_limit.as_deref()),
            (Some("1"), Some("0x3E8"))
        );
        assert_eq!(allowed_verdict("$NODEID+1", &["1"], &[]), None);
        assert_eq!(
            allowed_verdict("5", &[], &[(Some("x"), Some("9")), (Some("20"), None)]),
            None
        );
        assert_eq!(
            allowed_verdict("25", &[], &[(Some("x"), Some("9")), (Some("20"), None)]),
            Some(true)
        );
        assert_eq!(allowed_verdict("abc", &["abc"], &[]), Some(true));
    }

    #[test]
    fn configured_values_make_an_xdc() {
        let text = V11
            .replace(r#"<q1:defaultValue value="1000" />"#, r#"<q1:denotation><label lang="en">hb</label></q1:denotation><q1:actualValue value="500" /><q1:defaultValue value="1000" />"#)
            .replace("<CANopenMasterFeatures />", r#"<CANopenMasterFeatures /><deviceCommissioning NodeID="5" nodeName="n" actualBaudRate="250" networkNumber="1" networkName="net" CANopenManager="false" />"#);
        let loaded = read_ok(&text);
        assert_eq!(loaded.kind, XddKind::Xdc);
        let hb = &loaded.eds.objects[&0x1017].attributes;
        assert_eq!(
            (hb.parameter_value.as_deref(), hb.denotation.as_deref()),
            (Some("500"), Some("hb"))
        );
        let c = loaded.eds.commissioning.clone().unwrap_or_default();
        assert_eq!(
            c.entries(),
            [
                ("NodeID", "5"),
                ("NodeName", "n"),
                ("Baudrate", "250"),
                ("NetNumber", "1"),
                ("NetworkName", "net"),
                ("CANopenManager", "0")
            ]
        );
        assert!(
            loaded
                .diagnostics
                .iter()
                .any(|d| d.code == XddCode::NonStandardAttribute && d.message.contains("NodeID"))
        );
    }

    #[test]
    fn utf16_and_latin1_are_decoded() {
        let mut utf16 = vec![0xFF, 0xFE];
        utf16.extend(
            V11.replace("utf-8", "utf-16")
                .encode_utf16()
                .flat_map(u16::to_le_bytes),
        );
        assert_eq!(read(&utf16).map(|l| l.eds.objects.len()), Ok(2));
        let latin1: Vec<u8> = V11
            .replace("utf-8", "ISO-8859-1")
            .replace("ACME &amp; Co", "Müller")
            .chars()
            .map(|c| u8::try_from(u32::from(c)).unwrap_or(b'?'))
            .collect();
        assert_eq!(
            read(&latin1).ok().and_then(|l| l.eds.device_info.vendor_name),
            Some("Müller".to_owned())
        );
    }
}

//! CiA 311 XDD/XDC (XML device description and configuration) read into and written from the
//! canopener EDS model ([`canopener_eds::Eds`]), so that every tool built on the model handles XDD too.
//!
//! This crate performs no IO: [`read`] takes bytes and returns the model with diagnostics, [`write()`]
//! takes the model and returns the XML text. It does not validate against the CiA 311 schema and does
//! not model what CiA 306 cannot hold (see "What does not survive").
//!
//! ```
//! let eds = canopener_eds::load(b"[FileInfo]\nFileName=demo.eds\n[1017]\nParameterName=Producer heartbeat time\n\
//!     ObjectType=0x7\nDataType=0x0006\nAccessType=rw\nDefaultValue=1000\nPDOMapping=0\n").eds;
//! let xml = canopener_xdd::write(&eds, &canopener_xdd::WriteOptions::CANOPEN_EDITOR);
//! let back = canopener_xdd::read(xml.as_bytes()).expect("canopener reads what it writes");
//! assert!(canopener_eds::diff::diff_objects(&eds, &back.eds).is_equivalent());
//! assert_eq!(back.kind, canopener_xdd::XddKind::Xdd);
//! ```
//!
//! # Reading
//!
//! - **Namespaces.** Elements and attributes are matched by local name, so the three styles in use read
//!   alike: v1.1 with unqualified local elements (CANopenEditor), v1.0 with every element in the
//!   default namespace (vendors, libedssharp), and no namespace at all (EdsDcfNet; diagnostic `X001`).
//!   The version comes from the root namespace, never from `formatVersion`. Profiles are told apart
//!   by `xsi:type`, not by position.
//! - **Refused** ([`XddError`]): malformed XML (with line and column), text that is not XDD, a root in
//!   another namespace (invented dialects, P19), a profile technology other than CANopen, and Ethernet
//!   POWERLINK files (EPSG DS 311), which share the root element.
//! - **CANopenEditor projects** (`.nxdd`, `CanOpenProject_1_1`, and the v1.0 `OpenEDSProject`): [`read`]
//!   reads the device inside when there is exactly one (`X002`) and refuses several;
//!   [`read_project`] reads them all.
//! - **uniqueIDRef** is followed into the ApplicationProcess `parameter`: data type (IEC element, or a
//!   `dataTypeIDRef` through `enum`/`derived`), `access`, `defaultValue`, `allowedValues/range` as
//!   LowLimit/HighLimit (several ranges: their hull), `actualValue`, `denotation`, the first label.
//!   A default or actual value outside `allowedValues` that the limits cannot express (a `value`
//!   list, the gaps between ranges) is reported (`X101`). When the object also carries
//!   the value inline, the object wins and a disagreement is reported (`X021`, P18).
//! - **Schema defaults are applied explicitly** (P2): a parameter without `access` is `read` (`ro`);
//!   with a `CANopenGeneralFeatures` element every general-feature key is written (`0` for absent
//!   booleans and counts); with `NetworkManagement`, `SimpleBootUpMaster` is written. A default
//!   stands in only for an absent attribute, never for one that is there but unreadable.
//! - **Schema types.** Every attribute the reader interprets is read by its CiA 311 type
//!   (xsd:hexBinary, unsignedByte/Short/Long, boolean, ID, the enumerations). A value outside its type
//!   is an error naming element and attribute: `X016` for numbers, hexBinary and IDs, `X023` for
//!   tokens. A clear value is read and the message says as what (`0x2000` and `201` as hexBinary,
//!   `rw` as the parameter access readWrite, `rwr` as an inline accessType); any other leaves its key
//!   out of the model. A valid hexBinary of an unusual width (`0000` for a subIndex) is `X012`.
//!   `objectType` decimal becomes `0x7`, `dataType` becomes `0x0007`. Vendor and product IDs follow
//!   CiA 306: `0x…` is hex, bare digits are decimal (Faulhaber's `327`), bare hex with letters gets a
//!   `0x` (`X031`, P9).
//! - **Access and PDO mapping.** `read`/`write`/`readWrite`/`const` → ro/wo/rw/const,
//!   `readWriteInput` → rwr, `readWriteOutput` → rww, `noAccess` → no AccessType (`X022`). An inline
//!   `rw` with PDOmapping `TPDO`/`RPDO` is rwr/rww (libedssharp #128). PDOmapping `no` → 0, the other
//!   four tokens → 1.
//! - **BITSTRING** without an inline `dataType` is OCTET_STRING, or DOMAIN when the parameter has no
//!   default (CANopenEditor's convention, `X024`); OCTET_STRING values written as `C8 3D BB` become
//!   `C83DBB` (`X026`, P7). CHAR is read as VISIBLE_STRING (the schema's one-character string).
//! - **ARRAY/RECORD objects** keep name, object type, ObjFlags and configured values; a data type,
//!   access, default, limits or PDO mapping on the object itself describe its sub-objects in CiA 306
//!   and are not carried (`X025`, P21). `SubNumber` is the number of `CANopenSubObject` children
//!   other than sub-index FFh (which holds the structure, CiA 306 §4.6.3.2); a different `subNumber`
//!   is reported (`X013`, P13).
//! - **Object lists** are rebuilt by index (CiA 306 §4.6.3.1: 1000h, 1001h, 1018h mandatory;
//!   2000h–5FFFh manufacturer; the rest optional, P15).
//! - **Device level.** File attributes → `[FileInfo]` (xsd:date/time converted to `MM-DD-YYYY` and
//!   `hh:mmAM`, `EDSVersion=4.0`); `productText/description` → `Description` (Faulhaber's packed
//!   `FileDescription=…|EdsVersion=…` is unpacked, `X037`); DeviceIdentity → VendorName, VendorNumber,
//!   ProductName, ProductNumber, OrderCode (`ApplicationLayers/identity` fills in missing IDs);
//!   `supportedBaudRate` → all eight `BaudRate_*` keys (`100 Kbps` and `auto-baudRate` have none,
//!   `X032`); general and master features → Granularity, NrOfRXPDO/TXPDO, SimpleBootUpSlave/Master,
//!   LSS_Supported, GroupMessaging, DynamicChannelsSupported, and CANopenEditor's `ngSlave`, `ngMaster`,
//!   `NrOfNG_MonitoredNodes` → NG_Slave, NG_Master, NrOfNG_MonitoredNodes (`X034`); `dummyUsage` →
//!   `[DummyUsage]`; `dynamicChannels` → `[DynamicChannels]`.
//! - **XDC.** `actualValue` → ParameterValue, `denotation` → Denotation, `deviceCommissioning` →
//!   `[DeviceComissioning]` (both `nodeID` and CANopenEditor's `NodeID`; `actualBaudRate` as `250` or
//!   `250 Kbps`; a node-ID outside 1..=127 is kept and reported, `X035`). A file with
//!   `deviceCommissioning` or configured values is an [`XddKind::Xdc`] (libedssharp's placeholder
//!   `deviceCommissioning nodeID="0"` makes its `.xdd` files XDCs too).
//! - **CANopenNode properties.** `CO_*` `property` elements have no EDS key (`X039`). Objects marked
//!   `CO_disabled` are kept, as CiA 311 describes them, and reported (`X040`): CANopenEditor leaves them
//!   out of the device and of its EDS export.
//!
//! - **Locations.** [`XddLoaded::locations`] records where every object, sub-object and
//!   device-level section was read from, and per CiA 306 key the attribute or parameter element that
//!   gave its value, so `eds check` can place a finding about the model in the XML.
//!
//! # Writing
//!
//! - **Style.** CiA 311 v1.1 exactly as CANopenEditor writes it: default namespace v1.1 on the root,
//!   `xmlns=""` on ProfileHeader and ProfileBody, global elements prefixed `q1:` (device profile) and
//!   `q2:` (network profile), local elements unqualified, `xsi:type="q1:ProfileBody_Device_CANopen"`.
//!   Objects reference parameters (`UID_OBJ_xxxx`, `UID_SUB_xxxxyy`); ARRAY/RECORD parameters
//!   reference an `array` (`UID_ARR_xxxx`) or `struct` (`UID_REC_xxxx`) in `dataTypeList`.
//! - **Data types** ([`ObjectStyle`]). The default, [`ObjectStyle::Reference`], is CANopenEditor's
//!   reference style, plus an inline `dataType` (two hex digits, which CANopenEditor's reader accepts)
//!   only where no IEC element says the type exactly: OCTET_STRING and DOMAIN (both BITSTRING),
//!   INTEGER24/40/48/56, UNSIGNED24/40/48/56, TIME_OF_DAY, TIME_DIFFERENCE, record and
//!   manufacturer types. That keeps every CANopen type without CANopenEditor's lossy rewrite of them
//!   as byte strings. [`ObjectStyle::ReferenceAndInline`] also repeats data type, access, values and
//!   limits on every object, for readers that ignore `uniqueIDRef` (EdsDcfNet 1.12).
//! - **Values.** rwr/rww → `readWriteInput`/`readWriteOutput`; a missing or unreadable AccessType →
//!   `noAccess`. `PDOMapping=1` → `TPDO` for ro/const/rwr, `RPDO` for wo/rww, `optional` for rw;
//!   `PDOMapping=0` → `no`. Limits go into `allowedValues/range` when both exist, else inline
//!   `lowLimit`/`highLimit`. Vendor and product IDs are written `0x%08X`.
//! - **Compact forms.** XDD has none, so CompactSubObj sub-objects and CompactPDO objects are written
//!   explicitly (their content survives, the compact form does not).
//! - **XDC** when [`WriteOptions::kind`] asks for it or, by default, when the model is a DCF or carries
//!   ParameterValue/Denotation: `actualValue`, `denotation` and `deviceCommissioning` are written.
//!   Asking for an [`XddKind::Xdd`] leaves all configuration out.
//! - **Nothing is invented.** Content CiA 311 requires but the EDS does not give (Granularity, the
//!   creation date) is left out; canopener's reader reports it (`X003`) and reads on.
//! - **Escaping** is done by a small function (the writer only emits known names); characters XML 1.0
//!   cannot carry become U+FFFD in the document and are kept exactly in the side channel.
//!
//! # The side channel
//!
//! What CiA 311 has no element for is written as `property` elements named `EDS:*` (CiA 311's own
//! extension point, so the file stays schema-valid and other tools ignore them): per object on its
//! parameter (keys without an XDD home such as `UploadFile`, `ParamRefd`, unknown keys, values the XDD
//! form would change, keys the XDD form would add, `[xxxxObjectLinks]`), and for the file on a parameter
//! `UID_CANOPENER_EDS` that no object references (`FileRevision`, `LastEDS`, `RevisionNumber`,
//! `CompactPDO`, `[Comments]`, `[Tools]`, module sections, object lists as written when they differ
//! from CiA 306's, unknown sections, ...). The writer computes what a reader will make of the XDD and
//! records only the differences, so an ordinary EDS needs no side channel for its objects.
//!
//! # What does not survive
//!
//! EDS → XDD → EDS keeps the object dictionary as [`canopener_eds::diff::diff_objects`] compares it,
//! and every section of the model, except: the text layout (comments, key order and spelling, number
//! notation, line endings); the CompactSubObj/CompactPDO form (expanded); `[xxxxName]`, `[xxxxValue]`,
//! `[xxxxDenotation]` (their content is in the expanded sub-objects); `SubNumber` as written (derived);
//! data type, access, default, limits and PDO mapping on ARRAY/RECORD objects themselves; empty
//! object-list sections; and, when writing an XDD from a DCF, the configuration.
//!
//! XDD → EDS cannot keep what CiA 306 has no key for: the ProfileHeader, multilingual and long
//! descriptions, DeviceManager (LEDs), DeviceFunction, `dataTypeList` (struct, enum, derived),
//! units, scaling, value lists beyond one range, substituteValue, parameter groups, templates,
//! CANopenNode `CO_*` properties, vendorText/deviceFamily/productFamily/version/buildDate, the
//! PDOmapping `default`/`TPDO`/`RPDO` distinction, `noAccess`, `100 Kbps`, `auto-baudRate`, the
//! master features other than `bootUpMaster`, `selfStartingDevice`, `SDORequestingDevice`,
//! `moduleManagement` and `rangeSelector`.

#![warn(missing_docs)]
// A file or a frame must never panic this library: no unwrap, expect or unchecked index outside tests
// (as rustls does); each exception names, where it stands, why it cannot fail.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)
)]

mod device;
pub mod diag;
mod entry;
pub mod error;
pub mod locations;
mod notation;
mod read;
mod side_channel;
mod write;
mod xml;

use canopener_eds::Eds;

pub use diag::{XddCode, XddDiagnostic};
pub use error::XddError;
pub use locations::Locations;

/// Whether a file describes a device (XDD) or a configured device (XDC).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum XddKind {
    /// A device description, the counterpart of an EDS.
    Xdd,
    /// A device configuration (`actualValue`, `denotation`, `deviceCommissioning`), the counterpart of a DCF.
    Xdc,
}

/// The CiA 311 version, from the root element's namespace.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum XddVersion {
    /// `http://www.canopen.org/xml/1.0`.
    V1_0,
    /// `http://www.canopen.org/xml/1.1`.
    V1_1,
}

/// A read XDD/XDC: the EDS model and what was found on the way.
#[derive(Debug, Clone)]
pub struct XddLoaded {
    /// The device description as a CiA 306 model.
    pub eds: Eds,
    /// XDD or XDC (configured values or `deviceCommissioning` make an XDC).
    pub kind: XddKind,
    /// The CiA 311 version; `None` when the root element has no namespace (not schema-valid).
    pub version: Option<XddVersion>,
    /// Diagnostics, sorted by position.
    pub diagnostics: Vec<XddDiagnostic>,
    /// Where each object, sub-object, device-level section and value was read from, so findings
    /// about the model can point into the XML.
    pub locations: Locations,
}

/// How objects are described.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ObjectStyle {
    /// CANopenEditor's reference style; inline `dataType` only for types without an exact IEC element.
    Reference,
    /// Reference style plus data type, access, values and limits repeated on every object.
    ReferenceAndInline,
}

/// What [`write()`] produces.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WriteOptions {
    /// XDD or XDC; `None` writes an XDC for a DCF (or a model with configured values), else an XDD.
    pub kind: Option<XddKind>,
    /// How objects are described.
    pub style: ObjectStyle,
    /// The `fileName` attribute; `None` takes the EDS `FileName` with the extension `.xdd`/`.xdc`.
    pub file_name: Option<String>,
}

impl WriteOptions {
    /// Reference style as CANopenEditor writes it, XDC for a DCF, file name from the EDS.
    pub const CANOPEN_EDITOR: WriteOptions = WriteOptions {
        kind: None,
        style: ObjectStyle::Reference,
        file_name: None,
    };
}

/// Reads an XDD, XDC or XPD (or a CANopenEditor project holding exactly one device). Never panics.
pub fn read(bytes: &[u8]) -> Result<XddLoaded, XddError> {
    read::read(bytes)
}

/// The text of an XDD file as the reader decodes it (UTF-8, UTF-16 with a byte order mark, or the
/// encoding the XML declaration names), for showing the lines findings point at.
pub fn decode(bytes: &[u8]) -> Result<String, XddError> {
    read::decode(bytes)
}

/// Reads every device of a CANopenEditor project (`.nxdd`), or the one device of a plain XDD.
pub fn read_project(bytes: &[u8]) -> Result<Vec<XddLoaded>, XddError> {
    read::read_project(bytes)
}

/// Writes a model as CiA 311 v1.1 XDD or XDC text.
pub fn write(eds: &Eds, options: &WriteOptions) -> String {
    write::write(eds, options)
}

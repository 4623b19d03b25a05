//! Layer setting services (CiA 305): frames between an LSS master and LSS slaves.
//!
//! Master to slave on CAN-ID 7E5h, slave to master on 7E4h, always 8 bytes: D0 is the command
//! specifier, unused bytes are reserved and sent as 0 (CiA 305). The LSS address is the 128-bit
//! identity 1018h:01..04: vendor-id, product code, revision number, serial number.

use std::fmt;

/// The command specifiers of CiA 305, as sent in D0.
pub mod cs {
    /// Switch state global.
    pub const SWITCH_STATE_GLOBAL: u8 = 0x04;
    /// Switch state selective: vendor-id.
    pub const SWITCH_STATE_SELECTIVE_VENDOR_ID: u8 = 0x40;
    /// Switch state selective: product code.
    pub const SWITCH_STATE_SELECTIVE_PRODUCT_CODE: u8 = 0x41;
    /// Switch state selective: revision number.
    pub const SWITCH_STATE_SELECTIVE_REVISION_NUMBER: u8 = 0x42;
    /// Switch state selective: serial number.
    pub const SWITCH_STATE_SELECTIVE_SERIAL_NUMBER: u8 = 0x43;
    /// Switch state selective response from the slave whose whole address matched.
    pub const SWITCH_STATE_SELECTIVE_RESPONSE: u8 = 0x44;
    /// Configure node-id.
    pub const CONFIGURE_NODE_ID: u8 = 0x11;
    /// Configure bit timing parameters.
    pub const CONFIGURE_BIT_TIMING: u8 = 0x13;
    /// Activate bit timing parameters.
    pub const ACTIVATE_BIT_TIMING: u8 = 0x15;
    /// Store configuration.
    pub const STORE_CONFIGURATION: u8 = 0x17;
    /// Identify remote slave: vendor-id.
    pub const IDENTIFY_REMOTE_SLAVE_VENDOR_ID: u8 = 0x46;
    /// Identify remote slave: product code.
    pub const IDENTIFY_REMOTE_SLAVE_PRODUCT_CODE: u8 = 0x47;
    /// Identify remote slave: revision number, low bound.
    pub const IDENTIFY_REMOTE_SLAVE_REVISION_LOW: u8 = 0x48;
    /// Identify remote slave: revision number, high bound.
    pub const IDENTIFY_REMOTE_SLAVE_REVISION_HIGH: u8 = 0x49;
    /// Identify remote slave: serial number, low bound.
    pub const IDENTIFY_REMOTE_SLAVE_SERIAL_LOW: u8 = 0x4A;
    /// Identify remote slave: serial number, high bound; slaves inside all ranges answer.
    pub const IDENTIFY_REMOTE_SLAVE_SERIAL_HIGH: u8 = 0x4B;
    /// Identify non-configured remote slave.
    pub const IDENTIFY_NON_CONFIGURED_REMOTE_SLAVE: u8 = 0x4C;
    /// Identify slave: the answer to identify remote slave and to fastscan.
    pub const IDENTIFY_SLAVE: u8 = 0x4F;
    /// Identify non-configured slave: the answer of a slave without node-id.
    pub const IDENTIFY_NON_CONFIGURED_SLAVE: u8 = 0x50;
    /// Fastscan.
    pub const FASTSCAN: u8 = 0x51;
    /// Inquire identity vendor-id.
    pub const INQUIRE_VENDOR_ID: u8 = 0x5A;
    /// Inquire identity product code.
    pub const INQUIRE_PRODUCT_CODE: u8 = 0x5B;
    /// Inquire identity revision number.
    pub const INQUIRE_REVISION_NUMBER: u8 = 0x5C;
    /// Inquire identity serial number.
    pub const INQUIRE_SERIAL_NUMBER: u8 = 0x5D;
    /// Inquire node-id.
    pub const INQUIRE_NODE_ID: u8 = 0x5E;
}

/// The node-id value meaning "not configured".
pub const UNCONFIGURED_NODE_ID: u8 = 0xFF;

/// Fastscan's `bit_checked` value that restarts the scan.
pub const FASTSCAN_RESET: u8 = 0x80;

/// One of the four parts of the LSS address.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LssAddressPart {
    /// 1018h:01.
    VendorId,
    /// 1018h:02.
    ProductCode,
    /// 1018h:03.
    RevisionNumber,
    /// 1018h:04.
    SerialNumber,
}

impl LssAddressPart {
    /// The four parts in fastscan order (LSSSub 0 to 3), which is also their order in 1018h.
    pub const ALL: [LssAddressPart; 4] = [
        LssAddressPart::VendorId,
        LssAddressPart::ProductCode,
        LssAddressPart::RevisionNumber,
        LssAddressPart::SerialNumber,
    ];

    /// The part at fastscan position `offset` (LSSSub/LSSNext 0 to 3).
    pub fn from_offset(offset: u8) -> Option<LssAddressPart> {
        LssAddressPart::ALL.get(usize::from(offset)).copied()
    }

    const fn offset(self) -> u8 {
        match self {
            LssAddressPart::VendorId => 0,
            LssAddressPart::ProductCode => 1,
            LssAddressPart::RevisionNumber => 2,
            LssAddressPart::SerialNumber => 3,
        }
    }
}

impl fmt::Display for LssAddressPart {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            LssAddressPart::VendorId => "vendor-id",
            LssAddressPart::ProductCode => "product code",
            LssAddressPart::RevisionNumber => "revision number",
            LssAddressPart::SerialNumber => "serial number",
        })
    }
}

/// The 128-bit LSS address of a device: its identity object 1018h:01..04 (CiA 305 §4, CiA 301
/// §7.5.2.21). Master and slave cores share this one type.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct LssAddress {
    /// 1018h:01.
    pub vendor_id: u32,
    /// 1018h:02.
    pub product_code: u32,
    /// 1018h:03.
    pub revision_number: u32,
    /// 1018h:04.
    pub serial_number: u32,
}

impl LssAddress {
    /// The address from its four parts in fastscan order.
    pub fn from_parts([vendor_id, product_code, revision_number, serial_number]: [u32; 4]) -> LssAddress {
        LssAddress {
            vendor_id,
            product_code,
            revision_number,
            serial_number,
        }
    }

    /// One part of the address.
    pub fn part(&self, part: LssAddressPart) -> u32 {
        match part {
            LssAddressPart::VendorId => self.vendor_id,
            LssAddressPart::ProductCode => self.product_code,
            LssAddressPart::RevisionNumber => self.revision_number,
            LssAddressPart::SerialNumber => self.serial_number,
        }
    }

    /// The four parts in fastscan order.
    pub fn parts(&self) -> [u32; 4] {
        LssAddressPart::ALL.map(|part| self.part(part))
    }

    /// This address with one part replaced (a tester's "wrong in one part" address).
    pub fn with_part(&self, part: LssAddressPart, value: u32) -> LssAddress {
        let mut parts = self.parts();
        if let Some(slot) = parts.get_mut(usize::from(part.offset())) {
            *slot = value;
        }
        LssAddress::from_parts(parts)
    }

    /// The identify remote slave bounds (vendor-id, product code, revision low and high, serial low
    /// and high) that hold exactly this address.
    pub fn exact_ranges(&self) -> [u32; 6] {
        let [vendor, product, revision, serial] = self.parts();
        [vendor, product, revision, revision, serial, serial]
    }

    /// The switch state selective requests (40h–43h) that address this slave.
    pub fn switch_selective(&self) -> [LssRequest; 4] {
        LssAddressPart::ALL.map(|part| LssRequest::SwitchStateSelective {
            part,
            value: self.part(part),
        })
    }
}

/// `vendor-id 0x0000031A, product code 0x00000001, revision number 0x00010000, serial number 0x00000007`.
impl fmt::Display for LssAddress {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (idx, part) in LssAddressPart::ALL.into_iter().enumerate() {
            let separator = if idx == 0 { "" } else { ", " };
            write!(f, "{separator}{part} 0x{:08X}", self.part(part))?;
        }
        Ok(())
    }
}

/// One bound of an identify remote slave request (vendor-id and product code match exactly, revision
/// and serial number are ranges).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum IdentifyField {
    /// 46h.
    VendorId,
    /// 47h.
    ProductCode,
    /// 48h.
    RevisionLow,
    /// 49h.
    RevisionHigh,
    /// 4Ah.
    SerialLow,
    /// 4Bh.
    SerialHigh,
}

impl IdentifyField {
    /// The six bounds in the order a master sends them (46h to 4Bh).
    pub const ALL: [IdentifyField; 6] = [
        IdentifyField::VendorId,
        IdentifyField::ProductCode,
        IdentifyField::RevisionLow,
        IdentifyField::RevisionHigh,
        IdentifyField::SerialLow,
        IdentifyField::SerialHigh,
    ];

    const fn offset(self) -> u8 {
        match self {
            IdentifyField::VendorId => 0,
            IdentifyField::ProductCode => 1,
            IdentifyField::RevisionLow => 2,
            IdentifyField::RevisionHigh => 3,
            IdentifyField::SerialLow => 4,
            IdentifyField::SerialHigh => 5,
        }
    }
}

impl fmt::Display for IdentifyField {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            IdentifyField::VendorId => "vendor-id",
            IdentifyField::ProductCode => "product code",
            IdentifyField::RevisionLow => "revision low",
            IdentifyField::RevisionHigh => "revision high",
            IdentifyField::SerialLow => "serial low",
            IdentifyField::SerialHigh => "serial high",
        })
    }
}

/// A frame from the LSS master (7E5h).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LssRequest {
    /// 04h: all slaves go to waiting (`mode` 0) or configuration (`mode` 1).
    SwitchStateGlobal {
        /// 0 = waiting, 1 = configuration.
        mode: u8,
    },
    /// 40h–43h: one part of the address of the slave that shall enter configuration state.
    SwitchStateSelective {
        /// Which part.
        part: LssAddressPart,
        /// Its value.
        value: u32,
    },
    /// 11h: the slave in configuration state takes this node-id (FFh = unconfigured).
    ConfigureNodeId {
        /// 1 to 127, or FFh.
        node_id: u8,
    },
    /// 13h: the pending bit rate, as an index into a bit timing table.
    ConfigureBitTiming {
        /// 0 = the CiA 305 table.
        table: u8,
        /// The entry, see [`bit_timing_text`].
        index: u8,
    },
    /// 15h: switch to the pending bit rate after `delay_ms`.
    ActivateBitTiming {
        /// The switch delay in milliseconds.
        delay_ms: u16,
    },
    /// 17h: store the pending node-id and bit rate.
    StoreConfiguration,
    /// 46h–4Bh: one bound of an identify remote slave request.
    IdentifyRemoteSlave {
        /// Which bound.
        field: IdentifyField,
        /// Its value.
        value: u32,
    },
    /// 4Ch: slaves without a node-id answer.
    IdentifyNonConfiguredRemoteSlave,
    /// 51h: one step of the fastscan search.
    Fastscan {
        /// The bits of the address part found so far.
        id_number: u32,
        /// The lowest bit compared (0–31), or 80h to restart.
        bit_checked: u8,
        /// The address part being scanned (0 = vendor-id … 3 = serial number).
        lss_sub: u8,
        /// The part the matching slaves move on to.
        lss_next: u8,
    },
    /// 5Ah–5Dh: the slave in configuration state answers with this part of its address.
    InquireAddress(LssAddressPart),
    /// 5Eh: the slave in configuration state answers with its node-id.
    InquireNodeId,
}

impl LssRequest {
    /// The identify remote slave requests (46h–4Bh) for `bounds` in [`IdentifyField::ALL`] order.
    pub fn identify_remote_slave(bounds: [u32; 6]) -> [LssRequest; 6] {
        let mut bounds = bounds.into_iter();
        IdentifyField::ALL.map(|field| LssRequest::IdentifyRemoteSlave {
            field,
            value: bounds.next().unwrap_or(0),
        })
    }
}

/// A frame from an LSS slave (7E4h).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LssResponse {
    /// 44h: the addressed slave is now in configuration state.
    SwitchStateSelective,
    /// 11h: the result of configure node-id.
    ConfigureNodeId {
        /// 0 = success, 1 = node-id out of range, FFh = implementation-specific.
        error: u8,
        /// The implementation-specific error when `error` is FFh.
        spec_error: u8,
    },
    /// 13h: the result of configure bit timing.
    ConfigureBitTiming {
        /// 0 = success, 1 = bit rate not supported, FFh = implementation-specific.
        error: u8,
        /// The implementation-specific error when `error` is FFh.
        spec_error: u8,
    },
    /// 17h: the result of store configuration.
    StoreConfiguration {
        /// 0 = success, 1 = storing not supported, 2 = storage media access error, FFh =
        /// implementation-specific.
        error: u8,
        /// The implementation-specific error when `error` is FFh.
        spec_error: u8,
    },
    /// 4Fh: answer to identify remote slave and fastscan.
    IdentifySlave,
    /// 50h: answer of a slave without node-id.
    IdentifyNonConfiguredSlave,
    /// 5Ah–5Dh: one part of the slave's address.
    InquireAddress {
        /// Which part.
        part: LssAddressPart,
        /// Its value.
        value: u32,
    },
    /// 5Eh: the slave's node-id (FFh = unconfigured).
    InquireNodeId {
        /// 1 to 127, or FFh.
        node_id: u8,
    },
}

/// Why bytes are not an LSS frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum LssError {
    /// D0 is not a command specifier this direction uses.
    #[error("unknown LSS command specifier {specifier:#04X} in a {direction} frame")]
    UnknownCommand {
        /// The command specifier.
        specifier: u8,
        /// "master to slave" or "slave to master".
        direction: &'static str,
    },
}

fn u32_at(data: &[u8; 8], offset: usize) -> u32 {
    let mut bytes = [0; 4];
    for (idx, slot) in bytes.iter_mut().enumerate() {
        *slot = data.get(offset + idx).copied().unwrap_or(0);
    }
    u32::from_le_bytes(bytes)
}

fn with_u32(cs: u8, value: u32) -> [u8; 8] {
    let [v0, v1, v2, v3] = value.to_le_bytes();
    [cs, v0, v1, v2, v3, 0, 0, 0]
}

impl LssRequest {
    /// Reads a master frame.
    pub fn parse(data: &[u8; 8]) -> Result<LssRequest, LssError> {
        let [command, d1, d2, d3, d4, d5, d6, d7] = *data;
        Ok(match command {
            cs::SWITCH_STATE_GLOBAL => LssRequest::SwitchStateGlobal { mode: d1 },
            cs::SWITCH_STATE_SELECTIVE_VENDOR_ID..=cs::SWITCH_STATE_SELECTIVE_SERIAL_NUMBER => {
                let part = LssAddressPart::from_offset(command - cs::SWITCH_STATE_SELECTIVE_VENDOR_ID);
                let part = part.ok_or(LssError::UnknownCommand {
                    specifier: command,
                    direction: MASTER,
                })?;
                LssRequest::SwitchStateSelective {
                    part,
                    value: u32_at(data, 1),
                }
            }
            cs::CONFIGURE_NODE_ID => LssRequest::ConfigureNodeId { node_id: d1 },
            cs::CONFIGURE_BIT_TIMING => LssRequest::ConfigureBitTiming { table: d1, index: d2 },
            cs::ACTIVATE_BIT_TIMING => LssRequest::ActivateBitTiming {
                delay_ms: u16::from_le_bytes([d1, d2]),
            },
            cs::STORE_CONFIGURATION => LssRequest::StoreConfiguration,
            cs::IDENTIFY_REMOTE_SLAVE_VENDOR_ID..=cs::IDENTIFY_REMOTE_SLAVE_SERIAL_HIGH => {
                let offset = command - cs::IDENTIFY_REMOTE_SLAVE_VENDOR_ID;
                let field = IdentifyField::ALL.get(usize::from(offset)).copied();
                let field = field.ok_or(LssError::UnknownCommand {
                    specifier: command,
                    direction: MASTER,
                })?;
                LssRequest::IdentifyRemoteSlave {
                    field,
                    value: u32_at(data, 1),
                }
            }
            cs::IDENTIFY_NON_CONFIGURED_REMOTE_SLAVE => LssRequest::IdentifyNonConfiguredRemoteSlave,
            cs::FASTSCAN => LssRequest::Fastscan {
                id_number: u32::from_le_bytes([d1, d2, d3, d4]),
                bit_checked: d5,
                lss_sub: d6,
                lss_next: d7,
            },
            cs::INQUIRE_VENDOR_ID..=cs::INQUIRE_SERIAL_NUMBER => {
                let part = LssAddressPart::from_offset(command - cs::INQUIRE_VENDOR_ID);
                LssRequest::InquireAddress(part.ok_or(LssError::UnknownCommand {
                    specifier: command,
                    direction: MASTER,
                })?)
            }
            cs::INQUIRE_NODE_ID => LssRequest::InquireNodeId,
            specifier => {
                return Err(LssError::UnknownCommand {
                    specifier,
                    direction: MASTER,
                });
            }
        })
    }

    /// The 8 data bytes, reserved bytes 0.
    pub fn encode(&self) -> [u8; 8] {
        match *self {
            LssRequest::SwitchStateGlobal { mode } => [cs::SWITCH_STATE_GLOBAL, mode, 0, 0, 0, 0, 0, 0],
            LssRequest::SwitchStateSelective { part, value } => {
                with_u32(cs::SWITCH_STATE_SELECTIVE_VENDOR_ID + part.offset(), value)
            }
            LssRequest::ConfigureNodeId { node_id } => [cs::CONFIGURE_NODE_ID, node_id, 0, 0, 0, 0, 0, 0],
            LssRequest::ConfigureBitTiming { table, index } => {
                [cs::CONFIGURE_BIT_TIMING, table, index, 0, 0, 0, 0, 0]
            }
            LssRequest::ActivateBitTiming { delay_ms } => {
                let [lo, hi] = delay_ms.to_le_bytes();
                [cs::ACTIVATE_BIT_TIMING, lo, hi, 0, 0, 0, 0, 0]
            }
            LssRequest::StoreConfiguration => [cs::STORE_CONFIGURATION, 0, 0, 0, 0, 0, 0, 0],
            LssRequest::IdentifyRemoteSlave { field, value } => {
                with_u32(cs::IDENTIFY_REMOTE_SLAVE_VENDOR_ID + field.offset(), value)
            }
            LssRequest::IdentifyNonConfiguredRemoteSlave => {
                [cs::IDENTIFY_NON_CONFIGURED_REMOTE_SLAVE, 0, 0, 0, 0, 0, 0, 0]
            }
            LssRequest::Fastscan {
                id_number,
                bit_checked,
                lss_sub,
                lss_next,
            } => {
                let [v0, v1, v2, v3] = id_number.to_le_bytes();
                [cs::FASTSCAN, v0, v1, v2, v3, bit_checked, lss_sub, lss_next]
            }
            LssRequest::InquireAddress(part) => [cs::INQUIRE_VENDOR_ID + part.offset(), 0, 0, 0, 0, 0, 0, 0],
            LssRequest::InquireNodeId => [cs::INQUIRE_NODE_ID, 0, 0, 0, 0, 0, 0, 0],
        }
    }

    /// How many leading bytes carry fields; the rest are reserved and must be 0.
    pub fn used_len(&self) -> usize {
        match self {
            LssRequest::StoreConfiguration
            | LssRequest::IdentifyNonConfiguredRemoteSlave
            | LssRequest::InquireAddress(_)
            | LssRequest::InquireNodeId => 1,
            LssRequest::SwitchStateGlobal { .. } | LssRequest::ConfigureNodeId { .. } => 2,
            LssRequest::ConfigureBitTiming { .. } | LssRequest::ActivateBitTiming { .. } => 3,
            LssRequest::SwitchStateSelective { .. } | LssRequest::IdentifyRemoteSlave { .. } => 5,
            LssRequest::Fastscan { .. } => 8,
        }
    }
}

const MASTER: &str = "master to slave";
const SLAVE: &str = "slave to master";

impl LssResponse {
    /// Reads a slave frame.
    pub fn parse(data: &[u8; 8]) -> Result<LssResponse, LssError> {
        let [command, d1, d2, ..] = *data;
        Ok(match command {
            cs::SWITCH_STATE_SELECTIVE_RESPONSE => LssResponse::SwitchStateSelective,
            cs::CONFIGURE_NODE_ID => LssResponse::ConfigureNodeId {
                error: d1,
                spec_error: d2,
            },
            cs::CONFIGURE_BIT_TIMING => LssResponse::ConfigureBitTiming {
                error: d1,
                spec_error: d2,
            },
            cs::STORE_CONFIGURATION => LssResponse::StoreConfiguration {
                error: d1,
                spec_error: d2,
            },
            cs::IDENTIFY_SLAVE => LssResponse::IdentifySlave,
            cs::IDENTIFY_NON_CONFIGURED_SLAVE => LssResponse::IdentifyNonConfiguredSlave,
            cs::INQUIRE_VENDOR_ID..=cs::INQUIRE_SERIAL_NUMBER => {
                let part = LssAddressPart::from_offset(command - cs::INQUIRE_VENDOR_ID);
                let part = part.ok_or(LssError::UnknownCommand {
                    specifier: command,
                    direction: SLAVE,
                })?;
                LssResponse::InquireAddress {
                    part,
                    value: u32_at(data, 1),
                }
            }
            cs::INQUIRE_NODE_ID => LssResponse::InquireNodeId { node_id: d1 },
            specifier => {
                return Err(LssError::UnknownCommand {
                    specifier,
                    direction: SLAVE,
                });
            }
        })
    }

    /// The 8 data bytes, reserved bytes 0.
    pub fn encode(&self) -> [u8; 8] {
        match *self {
            LssResponse::SwitchStateSelective => [cs::SWITCH_STATE_SELECTIVE_RESPONSE, 0, 0, 0, 0, 0, 0, 0],
            LssResponse::ConfigureNodeId { error, spec_error } => {
                [cs::CONFIGURE_NODE_ID, error, spec_error, 0, 0, 0, 0, 0]
            }
            LssResponse::ConfigureBitTiming { error, spec_error } => {
                [cs::CONFIGURE_BIT_TIMING, error, spec_error, 0, 0, 0, 0, 0]
            }
            LssResponse::StoreConfiguration { error, spec_error } => {
                [cs::STORE_CONFIGURATION, error, spec_error, 0, 0, 0, 0, 0]
            }
            LssResponse::IdentifySlave => [cs::IDENTIFY_SLAVE, 0, 0, 0, 0, 0, 0, 0],
            LssResponse::IdentifyNonConfiguredSlave => {
                [cs::IDENTIFY_NON_CONFIGURED_SLAVE, 0, 0, 0, 0, 0, 0, 0]
            }
            LssResponse::InquireAddress { part, value } => {
                with_u32(cs::INQUIRE_VENDOR_ID + part.offset(), value)
            }
            LssResponse::InquireNodeId { node_id } => [cs::INQUIRE_NODE_ID, node_id, 0, 0, 0, 0, 0, 0],
        }
    }

    /// How many leading bytes carry fields; the rest are reserved and must be 0.
    pub fn used_len(&self) -> usize {
        match self {
            LssResponse::SwitchStateSelective
            | LssResponse::IdentifySlave
            | LssResponse::IdentifyNonConfiguredSlave => 1,
            LssResponse::InquireNodeId { .. } => 2,
            LssResponse::ConfigureNodeId { .. }
            | LssResponse::ConfigureBitTiming { .. }
            | LssResponse::StoreConfiguration { .. } => 3,
            LssResponse::InquireAddress { .. } => 5,
        }
    }
}

/// One entry of the CiA 305 bit timing table (table selector 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BitTiming {
    /// The table index sent in configure bit timing.
    pub index: u8,
    /// The bit rate in kbit/s; `None` for the reserved entry 5 and for automatic detection (9).
    pub kbit: Option<u16>,
    /// How the entry reads in a decoded frame.
    pub text: &'static str,
}

/// The CiA 305 bit timing table (table selector 0), the one copy every crate reads. Index 5
/// (formerly 100 kbit/s) is reserved.
pub const BIT_TIMING_TABLE: [BitTiming; 10] = [
    BitTiming {
        index: 0,
        kbit: Some(1000),
        text: "1000 kbit/s",
    },
    BitTiming {
        index: 1,
        kbit: Some(800),
        text: "800 kbit/s",
    },
    BitTiming {
        index: 2,
        kbit: Some(500),
        text: "500 kbit/s",
    },
    BitTiming {
        index: 3,
        kbit: Some(250),
        text: "250 kbit/s",
    },
    BitTiming {
        index: 4,
        kbit: Some(125),
        text: "125 kbit/s",
    },
    BitTiming {
        index: 5,
        kbit: None,
        text: "reserved, formerly 100 kbit/s",
    },
    BitTiming {
        index: 6,
        kbit: Some(50),
        text: "50 kbit/s",
    },
    BitTiming {
        index: 7,
        kbit: Some(20),
        text: "20 kbit/s",
    },
    BitTiming {
        index: 8,
        kbit: Some(10),
        text: "10 kbit/s",
    },
    BitTiming {
        index: 9,
        kbit: None,
        text: "automatic bit rate detection",
    },
];

/// The bit rate of an entry of the CiA 305 bit timing table, as a decoded frame says it.
pub fn bit_timing_text(index: u8) -> Option<&'static str> {
    BIT_TIMING_TABLE.get(usize::from(index)).map(|entry| entry.text)
}

/// The CiA 305 bit timing table index of a bit rate in kbit/s; `None` when the table has none.
pub fn bit_timing_index(kbit: u16) -> Option<u8> {
    BIT_TIMING_TABLE
        .iter()
        .find(|entry| entry.kbit == Some(kbit))
        .map(|entry| entry.index)
}

fn node_id_text(node_id: u8) -> String {
    if node_id == UNCONFIGURED_NODE_ID {
        "unconfigured (FFh)".to_owned()
    } else {
        node_id.to_string()
    }
}

/// `configure node-id 5`, `inquire vendor-id`, …
impl fmt::Display for LssRequest {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            LssRequest::SwitchStateGlobal { mode: 0 } => f.write_str("switch state global -> waiting"),
            LssRequest::SwitchStateGlobal { mode: 1 } => f.write_str("switch state global -> configuration"),
            LssRequest::SwitchStateGlobal { mode } => write!(f, "switch state global -> mode {mode:#04X}"),
            LssRequest::SwitchStateSelective { part, value } => {
                write!(f, "switch state selective {part} 0x{value:08X}")
            }
            LssRequest::ConfigureNodeId { node_id } => {
                write!(f, "configure node-id {}", node_id_text(node_id))
            }
            LssRequest::ConfigureBitTiming { table: 0, index } => match bit_timing_text(index) {
                Some(rate) => write!(f, "configure bit timing table 0 index {index} ({rate})"),
                None => write!(f, "configure bit timing table 0 index {index} (not in the table)"),
            },
            LssRequest::ConfigureBitTiming { table, index } => {
                write!(f, "configure bit timing table {table} index {index}")
            }
            LssRequest::ActivateBitTiming { delay_ms } => {
                write!(f, "activate bit timing delay {delay_ms} ms")
            }
            LssRequest::StoreConfiguration => f.write_str("store configuration"),
            LssRequest::IdentifyRemoteSlave { field, value } => {
                write!(f, "identify remote slave {field} 0x{value:08X}")
            }
            LssRequest::IdentifyNonConfiguredRemoteSlave => {
                f.write_str("identify non-configured remote slave")
            }
            LssRequest::Fastscan {
                bit_checked: FASTSCAN_RESET,
                ..
            } => f.write_str("fastscan reset"),
            LssRequest::Fastscan {
                id_number,
                bit_checked,
                lss_sub,
                lss_next,
            } => write!(
                f,
                "fastscan id=0x{id_number:08X} bit-checked={bit_checked} sub={lss_sub} next={lss_next}"
            ),
            LssRequest::InquireAddress(part) => write!(f, "inquire {part}"),
            LssRequest::InquireNodeId => f.write_str("inquire node-id"),
        }
    }
}

fn result_text(service: &str, error: u8, spec_error: u8, texts: &[&str]) -> String {
    match (error, texts.get(usize::from(error))) {
        (0, _) => format!("{service}: success"),
        (0xFF, _) => format!("{service}: implementation-specific error {spec_error:#04X}"),
        (_, Some(text)) => format!("{service}: error {error} ({text})"),
        (_, None) => format!("{service}: error {error} (reserved)"),
    }
}

/// `vendor-id = 0x0000031A`, `configure node-id: success`, …
impl fmt::Display for LssResponse {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            LssResponse::SwitchStateSelective => {
                f.write_str("switch state selective: slave in configuration")
            }
            LssResponse::ConfigureNodeId { error, spec_error } => f.write_str(&result_text(
                "configure node-id",
                error,
                spec_error,
                &["success", "node-id out of range"],
            )),
            LssResponse::ConfigureBitTiming { error, spec_error } => f.write_str(&result_text(
                "configure bit timing",
                error,
                spec_error,
                &["success", "bit rate not supported"],
            )),
            LssResponse::StoreConfiguration { error, spec_error } => f.write_str(&result_text(
                "store configuration",
                error,
                spec_error,
                &["success", "storing not supported", "storage media access error"],
            )),
            LssResponse::IdentifySlave => f.write_str("identify slave"),
            LssResponse::IdentifyNonConfiguredSlave => f.write_str("identify non-configured slave"),
            LssResponse::InquireAddress { part, value } => write!(f, "{part} = 0x{value:08X}"),
            LssResponse::InquireNodeId { node_id } => write!(f, "node-id = {}", node_id_text(node_id)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn bit_timing_table_is_indexed_by_position_and_round_trips_every_rate() {
        for (position, entry) in BIT_TIMING_TABLE.iter().enumerate() {
            assert_eq!(usize::from(entry.index), position);
            if let Some(kbit) = entry.kbit {
                assert_eq!(bit_timing_index(kbit), Some(entry.index));
            }
        }
        assert_eq!(bit_timing_index(100), None, "100 kbit/s is reserved in CiA 305");
        assert_eq!(bit_timing_text(10), None);
    }

    #[test]
    fn address_requests_carry_every_part_in_order() {
        let address = LssAddress::from_parts([1, 2, 3, 4]);
        assert_eq!(address.parts(), [1, 2, 3, 4]);
        assert_eq!(
            address.with_part(LssAddressPart::RevisionNumber, 9).parts(),
            [1, 2, 9, 4]
        );
        let selective: Vec<u8> = address.switch_selective().iter().map(|r| r.encode()[0]).collect();
        assert_eq!(selective, [0x40, 0x41, 0x42, 0x43]);
        let identify: Vec<[u8; 8]> = LssRequest::identify_remote_slave(address.exact_ranges())
            .iter()
            .map(LssRequest::encode)
            .collect();
        assert_eq!(identify[2], [0x48, 3, 0, 0, 0, 0, 0, 0]);
        assert_eq!(identify[3], [0x49, 3, 0, 0, 0, 0, 0, 0]);
        assert_eq!(identify[5], [0x4B, 4, 0, 0, 0, 0, 0, 0]);
    }

    #[test]
    fn inquire_identity_exchange() {
        let request = LssRequest::parse(&[0x5A, 0, 0, 0, 0, 0, 0, 0]).unwrap();
        assert_eq!(request, LssRequest::InquireAddress(LssAddressPart::VendorId));
        assert_eq!(request.to_string(), "inquire vendor-id");
        let response = LssResponse::parse(&[0x5A, 0x1A, 0x03, 0, 0, 0, 0, 0]).unwrap();
        assert_eq!(
            response,
            LssResponse::InquireAddress {
                part: LssAddressPart::VendorId,
                value: 0x31A
            }
        );
        assert_eq!(response.to_string(), "vendor-id = 0x0000031A");
    }

    #[test]
    fn configuration_services() {
        let global = LssRequest::parse(&[0x04, 0x01, 0, 0, 0, 0, 0, 0]).unwrap();
        assert_eq!(global.to_string(), "switch state global -> configuration");
        let timing = LssRequest::parse(&[0x13, 0x00, 0x03, 0, 0, 0, 0, 0]).unwrap();
        assert_eq!(
            timing.to_string(),
            "configure bit timing table 0 index 3 (250 kbit/s)"
        );
        let node = LssResponse::parse(&[0x11, 0x01, 0x00, 0, 0, 0, 0, 0]).unwrap();
        assert_eq!(
            node.to_string(),
            "configure node-id: error 1 (node-id out of range)"
        );
        let store = LssResponse::parse(&[0x17, 0xFF, 0x12, 0, 0, 0, 0, 0]).unwrap();
        assert_eq!(
            store.to_string(),
            "store configuration: implementation-specific error 0x12"
        );
        let fastscan = LssRequest::parse(&[0x51, 0, 0, 0, 0, 0x80, 0, 0]).unwrap();
        assert_eq!(fastscan.to_string(), "fastscan reset");
    }

    #[test]
    fn unknown_specifiers_are_errors_per_direction() {
        assert_eq!(
            LssRequest::parse(&[0x44, 0, 0, 0, 0, 0, 0, 0]),
            Err(LssError::UnknownCommand {
                specifier: 0x44,
                direction: "master to slave"
            })
        );
        assert!(LssResponse::parse(&[0x04, 0, 0, 0, 0, 0, 0, 0]).is_err());
        assert_eq!(bit_timing_text(10), None);
    }

    fn any_request() -> impl Strategy<Value = LssRequest> {
        let part = prop::sample::select(LssAddressPart::ALL.to_vec());
        let field = prop::sample::select(IdentifyField::ALL.to_vec());
        prop_oneof![
            any::<u8>().prop_map(|mode| LssRequest::SwitchStateGlobal { mode }),
            (part.clone(), any::<u32>())
                .prop_map(|(part, value)| LssRequest::SwitchStateSelective { part, value }),
            any::<u8>().prop_map(|node_id| LssRequest::ConfigureNodeId { node_id }),
            (any::<u8>(), any::<u8>())
                .prop_map(|(table, index)| LssRequest::ConfigureBitTiming { table, index }),
            any::<u16>().prop_map(|delay_ms| LssRequest::ActivateBitTiming { delay_ms }),
            Just(LssRequest::StoreConfiguration),
            (field, any::<u32>()).prop_map(|(field, value)| LssRequest::IdentifyRemoteSlave { field, value }),
            Just(LssRequest::IdentifyNonConfiguredRemoteSlave),
            (any::<u32>(), any::<u8>(), any::<u8>(), any::<u8>()).prop_map(
                |(id_number, bit_checked, lss_sub, lss_next)| {
                    LssRequest::Fastscan {
                        id_number,
                        bit_checked,
                        lss_sub,
                        lss_next,
                    }
                }
            ),
            part.prop_map(LssRequest::InquireAddress),
            Just(LssRequest::InquireNodeId),
        ]
    }

    fn any_response() -> impl Strategy<Value = LssResponse> {
        let part = prop::sample::select(LssAddressPart::ALL.to_vec());
        prop_oneof![
            Just(LssResponse::SwitchStateSelective),
            (any::<u8>(), any::<u8>())
                .prop_map(|(error, spec_error)| LssResponse::ConfigureNodeId { error, spec_error }),
            (any::<u8>(), any::<u8>())
                .prop_map(|(error, spec_error)| LssResponse::ConfigureBitTiming { error, spec_error }),
            (any::<u8>(), any::<u8>())
                .prop_map(|(error, spec_error)| LssResponse::StoreConfiguration { error, spec_error }),
            Just(LssResponse::IdentifySlave),
            Just(LssResponse::IdentifyNonConfiguredSlave),
            (part, any::<u32>()).prop_map(|(part, value)| LssResponse::InquireAddress { part, value }),
            any::<u8>().prop_map(|node_id| LssResponse::InquireNodeId { node_id }),
        ]
    }

    proptest! {
        #[test]
        fn requests_round_trip(request in any_request()) {
            let bytes = request.encode();
            prop_assert!(bytes.iter().skip(request.used_len()).all(|b| *b == 0));
            prop_assert_eq!(LssRequest::parse(&bytes), Ok(request));
        }

        #[test]
        fn responses_round_trip(response in any_response()) {
            let bytes = response.encode();
            prop_assert!(bytes.iter().skip(response.used_len()).all(|b| *b == 0));
            prop_assert_eq!(LssResponse::parse(&bytes), Ok(response));
        }
    }
}

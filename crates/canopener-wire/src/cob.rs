//! Which CANopen service a CAN-ID belongs to, by the predefined connection set (CiA 301 §7.3.5).
//!
//! Devices may move PDOs, EMCY, SYNC and TIME to other CAN-IDs through their COB-ID objects; a
//! monitor without the devices' configuration can only assume the predefined set, so that is what
//! this module does. CAN-IDs outside the set, and every extended (29-bit) id, are "not CANopen".

use std::fmt;

use canopener_can::CanId;

/// CAN-ID of NMT module control.
pub const NMT_ID: u16 = 0x000;
/// CAN-ID of SYNC; EMCY of node n is `SYNC_ID + n` (same function code).
pub const SYNC_ID: u16 = 0x080;
/// Base of the EMCY CAN-IDs (80h + node-id).
pub const EMCY_BASE: u16 = 0x080;
/// CAN-ID of TIME.
pub const TIME_ID: u16 = 0x100;
/// Bases of TPDO1 to TPDO4 (plus node-id).
pub const TPDO_BASES: [u16; 4] = [0x180, 0x280, 0x380, 0x480];
/// Bases of RPDO1 to RPDO4 (plus node-id).
pub const RPDO_BASES: [u16; 4] = [0x200, 0x300, 0x400, 0x500];
/// Base of the default SDO server-to-client CAN-IDs (580h + node-id).
pub const SDO_TX_BASE: u16 = 0x580;
/// Base of the default SDO client-to-server CAN-IDs (600h + node-id).
pub const SDO_RX_BASE: u16 = 0x600;
/// Base of the NMT error control CAN-IDs (700h + node-id): boot-up, heartbeat, node guarding.
pub const ERROR_CONTROL_BASE: u16 = 0x700;
/// CAN-ID of LSS frames from slaves to the master (CiA 305).
pub const LSS_SLAVE_TO_MASTER_ID: u16 = 0x7E4;
/// CAN-ID of LSS frames from the master to slaves (CiA 305).
pub const LSS_MASTER_TO_SLAVE_ID: u16 = 0x7E5;

/// A CANopen service.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Service {
    /// NMT module control, 000h.
    Nmt,
    /// SYNC, 080h.
    Sync,
    /// Emergency, 081h–0FFh.
    Emcy,
    /// TIME, 100h.
    Time,
    /// Transmit PDO 1 to 4 (seen from the device that sends it).
    Tpdo(u8),
    /// Receive PDO 1 to 4 (seen from the device that receives it).
    Rpdo(u8),
    /// SDO server to client (the server's transmit SDO), 581h–5FFh.
    SdoTx,
    /// SDO client to server (the server's receive SDO), 601h–67Fh.
    SdoRx,
    /// NMT error control: boot-up, heartbeat and node guarding, 701h–77Fh.
    ErrorControl,
    /// Layer setting services, 7E4h and 7E5h.
    Lss,
    /// Not in the predefined connection set.
    Unknown,
}

/// `NMT`, `TPDO1`, `SDO tx`, …
impl fmt::Display for Service {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Service::Nmt => f.write_str("NMT"),
            Service::Sync => f.write_str("SYNC"),
            Service::Emcy => f.write_str("EMCY"),
            Service::Time => f.write_str("TIME"),
            Service::Tpdo(n) => write!(f, "TPDO{n}"),
            Service::Rpdo(n) => write!(f, "RPDO{n}"),
            Service::SdoTx => f.write_str("SDO tx"),
            Service::SdoRx => f.write_str("SDO rx"),
            Service::ErrorControl => f.write_str("NMT error control"),
            Service::Lss => f.write_str("LSS"),
            Service::Unknown => f.write_str("not CANopen (predefined set)"),
        }
    }
}

/// A CAN-ID's place in the predefined connection set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CobClass {
    /// The service.
    pub service: Service,
    /// The node-id in a node-addressed range (0 to 127; 0 is a mistake), `None` otherwise.
    pub node: Option<u8>,
}

/// Classifies a CAN-ID by the predefined connection set.
pub fn classify(id: CanId) -> CobClass {
    let CanId::Standard(id) = id else {
        return CobClass {
            service: Service::Unknown,
            node: None,
        };
    };
    let raw = id.as_raw();
    // The low 7 bits are the node-id in every node-addressed range.
    let node = (raw & 0x7F) as u8;
    let addressed = |service| CobClass {
        service,
        node: Some(node),
    };
    let plain = |service| CobClass { service, node: None };
    match raw {
        NMT_ID => plain(Service::Nmt),
        SYNC_ID => plain(Service::Sync),
        0x081..=0x0FF => addressed(Service::Emcy),
        TIME_ID => plain(Service::Time),
        0x180..=0x57F => {
            // Function codes 3 to 10 alternate TPDOn, RPDOn for n = 1 to 4 (§7.3.5, table 71).
            let function = (raw >> 7) - 3;
            // `function` is 0 to 7 in this range, so the PDO number is 1 to 4.
            let number = (function / 2 + 1) as u8;
            if function % 2 == 0 {
                addressed(Service::Tpdo(number))
            } else {
                addressed(Service::Rpdo(number))
            }
        }
        0x580..=0x5FF => addressed(Service::SdoTx),
        0x600..=0x67F => addressed(Service::SdoRx),
        0x700..=0x77F => addressed(Service::ErrorControl),
        LSS_SLAVE_TO_MASTER_ID | LSS_MASTER_TO_SLAVE_ID => plain(Service::Lss),
        _ => plain(Service::Unknown),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_can::{ExtendedId, StandardId};

    fn class(raw: u16) -> (Service, Option<u8>) {
        let class = classify(CanId::Standard(StandardId::new(raw).unwrap()));
        (class.service, class.node)
    }

    #[test]
    fn predefined_connection_set() {
        assert_eq!(class(0x000), (Service::Nmt, None));
        assert_eq!(class(0x080), (Service::Sync, None));
        assert_eq!(class(0x081), (Service::Emcy, Some(1)));
        assert_eq!(class(0x0FF), (Service::Emcy, Some(127)));
        assert_eq!(class(0x100), (Service::Time, None));
        assert_eq!(class(0x185), (Service::Tpdo(1), Some(5)));
        assert_eq!(class(0x205), (Service::Rpdo(1), Some(5)));
        assert_eq!(class(0x285), (Service::Tpdo(2), Some(5)));
        assert_eq!(class(0x305), (Service::Rpdo(2), Some(5)));
        assert_eq!(class(0x385), (Service::Tpdo(3), Some(5)));
        assert_eq!(class(0x405), (Service::Rpdo(3), Some(5)));
        assert_eq!(class(0x485), (Service::Tpdo(4), Some(5)));
        assert_eq!(class(0x57F), (Service::Rpdo(4), Some(127)));
        assert_eq!(class(0x5A2), (Service::SdoTx, Some(34)));
        assert_eq!(class(0x622), (Service::SdoRx, Some(34)));
        assert_eq!(class(0x705), (Service::ErrorControl, Some(5)));
        assert_eq!(class(0x7E4), (Service::Lss, None));
        assert_eq!(class(0x7E5), (Service::Lss, None));
    }

    #[test]
    fn node_id_zero_and_unassigned_ids() {
        assert_eq!(class(0x180), (Service::Tpdo(1), Some(0)));
        assert_eq!(class(0x580), (Service::SdoTx, Some(0)));
        assert_eq!(class(0x700), (Service::ErrorControl, Some(0)));
        for raw in [
            0x001, 0x07F, 0x101, 0x17F, 0x680, 0x6FF, 0x780, 0x7E3, 0x7E6, 0x7FF,
        ] {
            assert_eq!(class(raw), (Service::Unknown, None), "{raw:#X}");
        }
        let extended = classify(CanId::Extended(ExtendedId::new(0x605).unwrap()));
        assert_eq!(extended.service, Service::Unknown);
        assert_eq!(Service::Tpdo(3).to_string(), "TPDO3");
    }
}

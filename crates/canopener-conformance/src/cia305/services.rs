//! The LSS master services the tests use, as raw frames (CiA 305 §5): the tests need requests the
//! LSS master procedure of the runtime never makes (wrong addresses, out-of-range node-IDs).

use canopener_can::{CanFrame, CanId};
use canopener_wire::NmtCommand;

use super::{first_boot_up, is_lss_answer};
use crate::context::Ctx;
use crate::finding::{Evidence, Finding, Stop};

/// The names of the four parts of the LSS address, in order.
pub const PART_NAMES: [&str; 4] = ["vendor-ID", "product code", "revision number", "serial number"];

const REQUEST_ID: u16 = 0x7E5;
const RESPONSE_ID: u16 = 0x7E4;

/// The LSS address (CiA 305 §3: 1018h:01–04).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Address([u32; 4]);

impl Address {
    /// 1018h:01–04 read over SDO; `None` when one of them cannot be read as 4 bytes.
    pub fn read(ctx: &mut Ctx<'_, '_>) -> Result<Option<Address>, Stop> {
        let mut parts = [0; 4];
        for (sub, part) in (1..).zip(parts.iter_mut()) {
            match ctx.read(0x1018, sub)? {
                crate::context::Reply::Done(data) if data.len() == 4 => {
                    *part = u32::from_le_bytes([data[0], data[1], data[2], data[3]]);
                }
                _ => return Ok(None),
            }
        }
        Ok(Some(Address(parts)))
    }

    /// Vendor-ID, product code, revision, serial.
    pub fn parts(&self) -> [u32; 4] {
        self.0
    }

    /// Part `part` (0 vendor-ID … 3 serial number).
    pub fn part(&self, part: usize) -> u32 {
        self.0[part]
    }

    /// This address with part `part` replaced by `value`.
    pub fn with_part(&self, part: usize, value: u32) -> Address {
        let mut parts = self.0;
        parts[part] = value;
        Address(parts)
    }

    /// Identify remote slave ranges holding exactly this address.
    pub fn ranges(&self) -> [u32; 6] {
        let [vendor, product, revision, serial] = self.0;
        [vendor, product, revision, revision, serial, serial]
    }
}

impl std::fmt::Display for Address {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [vendor, product, revision, serial] = self.0;
        write!(
            f,
            "vendor {vendor:#010X}, product {product:#010X}, revision {revision:#010X}, serial {serial:#010X}"
        )
    }
}

/// Identify remote slave ranges as the analysis states them.
pub fn ranges_text(ranges: &[u32; 6]) -> String {
    format!(
        "vendor {:#010X}, product {:#010X}, revision {:#010X}–{:#010X}, serial {:#010X}–{:#010X}",
        ranges[0], ranges[1], ranges[2], ranges[3], ranges[4], ranges[5]
    )
}

/// The CAN-ID LSS slaves answer on.
pub fn lss_response_id() -> CanId {
    CanId::Standard(canopener_can::StandardId::new(RESPONSE_ID).unwrap_or(canopener_can::StandardId::ZERO))
}

/// The 11-bit identifier of a standard frame (0 for an extended one).
pub fn standard(frame: &CanFrame) -> u16 {
    match frame.id() {
        CanId::Standard(id) => id.as_raw(),
        CanId::Extended(_) => 0,
    }
}

/// The CiA 305 bit timing table 0 entries for the rates an EDS can list, with whether the EDS lists
/// each (`BaudRate_*=1`); rates the EDS does not mention are left out.
pub fn listed_bit_rates(ctx: &Ctx<'_, '_>) -> Vec<((u8, u16), bool)> {
    ctx.model()
        .bit_rates
        .iter()
        .map(|&(kbit, on)| {
            let index = match kbit {
                1000 => 0,
                800 => 1,
                500 => 2,
                250 => 3,
                125 => 4,
                50 => 6,
                20 => 7,
                _ => 8,
            };
            ((index, kbit), on)
        })
        .collect()
}

/// An LSS master on the test's context.
#[derive(Debug)]
pub struct Lss<'c, 'r, 'l> {
    ctx: &'c mut Ctx<'r, 'l>,
}

impl<'c, 'r, 'l> Lss<'c, 'r, 'l> {
    /// The LSS master of `ctx`.
    pub fn new(ctx: &'c mut Ctx<'r, 'l>) -> Self {
        Lss { ctx }
    }

    /// The node-ID under test.
    pub fn node(&self) -> u8 {
        self.ctx.node()
    }

    /// Sends `request` and returns the first answer with command specifier `cs` within the timeout.
    pub fn ask(&mut self, request: [u8; 8], cs: u8) -> Result<Option<Vec<u8>>, Stop> {
        self.ctx.send(REQUEST_ID, &request)?;
        let timeout = self.ctx.timeout();
        Ok(self
            .ctx
            .wait_for(timeout, |f| is_lss_answer(f, cs) && f.data().len() == 8)?
            .map(|l| l.frame.data().to_vec()))
    }

    /// Switch state global (04h) to configuration (`true`) or waiting; unconfirmed.
    pub fn switch_global(&mut self, configuration: bool) -> Result<(), Stop> {
        self.ctx
            .send(REQUEST_ID, &[0x04, u8::from(configuration), 0, 0, 0, 0, 0, 0])
    }

    /// Switch state selective (40h–43h) with `address`: the 44h answer.
    pub fn switch_selective(&mut self, address: &Address) -> Result<Option<Vec<u8>>, Stop> {
        for (cs, part) in (0x40..).zip(address.parts()) {
            let [a, b, c, d] = part.to_le_bytes();
            if cs < 0x43 {
                self.ctx.send(REQUEST_ID, &[cs, a, b, c, d, 0, 0, 0])?;
            } else {
                return self.ask([cs, a, b, c, d, 0, 0, 0], 0x44);
            }
        }
        Ok(None)
    }

    /// Switch state selective with `address` and inquire node-ID at once: the first 44h or 5Eh
    /// answer within one timeout.
    pub fn switch_selective_then_inquire(&mut self, address: &Address) -> Result<Option<Vec<u8>>, Stop> {
        for (cs, part) in (0x40..).zip(address.parts()) {
            let [a, b, c, d] = part.to_le_bytes();
            self.ctx.send(REQUEST_ID, &[cs, a, b, c, d, 0, 0, 0])?;
        }
        self.ctx.send(REQUEST_ID, &[0x5E, 0, 0, 0, 0, 0, 0, 0])?;
        let timeout = self.ctx.timeout();
        Ok(self
            .ctx
            .wait_for(timeout, |f| {
                (is_lss_answer(f, 0x44) || is_lss_answer(f, 0x5E)) && f.data().len() == 8
            })?
            .map(|l| l.frame.data().to_vec()))
    }

    /// Inquire node-ID (5Eh).
    pub fn inquire_node_id(&mut self) -> Result<Option<Vec<u8>>, Stop> {
        self.ask([0x5E, 0, 0, 0, 0, 0, 0, 0], 0x5E)
    }

    /// Identify remote slave (46h–4Bh) with `ranges`: whether a 4Fh came back.
    pub fn identify_remote(&mut self, ranges: &[u32; 6]) -> Result<bool, Stop> {
        for (cs, value) in (0x46..).zip(ranges) {
            let [a, b, c, d] = value.to_le_bytes();
            if cs < 0x4B {
                self.ctx.send(REQUEST_ID, &[cs, a, b, c, d, 0, 0, 0])?;
            } else {
                return Ok(self.ask([cs, a, b, c, d, 0, 0, 0], 0x4F)?.is_some());
            }
        }
        Ok(false)
    }

    /// Switch state selective to `address`, configure `node`, store: `Ok(true)` stored,
    /// `Ok(false)` storing not supported, `Err` a failure with its evidence.
    pub fn configure_and_store(
        &mut self,
        address: &Address,
        node: u8,
    ) -> Result<Result<bool, Finding>, Stop> {
        let selected = self.switch_selective(address)?;
        let configured = self.ask([0x11, node, 0, 0, 0, 0, 0, 0], 0x11)?;
        if selected.is_none() || configured.as_ref().map(|d| d[1]) != Some(0) {
            return Ok(Err(Finding::fail(
                format!("configure node-ID {node} after switch state selective failed"),
                Evidence {
                    request: format!("switch state selective with {address}, configure node-ID {node}"),
                    requirement: format!(
                        "{}: 44h, then configure node-ID answered with 0",
                        super::CONFIGURE_NODE_ID
                    ),
                    answer: format!(
                        "{} / {}",
                        super::describe(&selected),
                        super::describe(&configured)
                    ),
                    cause: "no configuration state, or configure node-ID not served".to_owned(),
                },
            )));
        }
        let stored = self.ask([0x17, 0, 0, 0, 0, 0, 0, 0], 0x17)?;
        match stored.as_ref().map(|d| d[1]) {
            Some(0) => Ok(Ok(true)),
            Some(1) => Ok(Ok(false)),
            _ => Ok(Err(Finding::fail(
                "store configuration not confirmed".to_owned(),
                Evidence {
                    request: "store configuration (17h) in configuration state".to_owned(),
                    requirement: format!(
                        "{}: 17h with error code 0 (stored), 1 (not supported) or 2 (media error)",
                        super::STORE
                    ),
                    answer: super::describe(&stored),
                    cause: "store configuration not served, or storing failed".to_owned(),
                },
            ))),
        }
    }

    /// NMT reset node to `node`, then the node-ID the device runs with, as inquire node-ID says
    /// (not the boot-up message: a device may boot silently, which is CiA 301's business).
    pub fn reset_node_and_inquire(&mut self, node: u8) -> Result<Option<u8>, Stop> {
        // NMT reset node (81h) to `node`, which need not be the node-ID under test.
        self.ctx.send(0x000, &[0x81, node])?;
        first_boot_up(self.ctx)?;
        self.active_node_id()
    }

    /// The node-ID inquire node-ID gives in configuration state; leaves the slave waiting.
    pub fn active_node_id(&mut self) -> Result<Option<u8>, Stop> {
        self.switch_global(true)?;
        let answer = self.inquire_node_id()?;
        self.switch_global(false)?;
        Ok(answer.map(|d| d[1]))
    }

    /// NMT reset communication to the node under test (no boot-up expected: it may have no node-ID).
    pub fn nmt_reset_communication(&mut self) -> Result<(), Stop> {
        self.ctx.nmt(NmtCommand::ResetCommunication, false)?;
        self.ctx.listen(std::time::Duration::from_millis(50), |_| false)?;
        Ok(())
    }

    /// Waits for the boot-up of a device leaving initialisation (any node-ID), then the node-ID
    /// inquire node-ID gives.
    pub fn boot_and_inquire(&mut self) -> Result<Option<u8>, Stop> {
        first_boot_up(self.ctx)?;
        self.active_node_id()
    }

    /// Fastscan (CiA 305 §5.6.4) for a slave whose address is known (each part confirmed at once,
    /// as a master does for parts it knows, instead of 32 bit steps whose silences each cost a
    /// timeout); `Some(what went wrong)` or `None` when every step was answered as required.
    pub fn fastscan(&mut self, address: &Address) -> Result<Option<String>, Stop> {
        if self.ask([0x51, 0, 0, 0, 0, 0x80, 0, 0], 0x4F)?.is_none() {
            return Ok(Some("no 4Fh to the reset step (BitChecked 80h)".to_owned()));
        }
        let [a, b, c, d] = (address.part(0) ^ 1).to_le_bytes();
        if self.ask([0x51, a, b, c, d, 0, 0, 0], 0x4F)?.is_some() {
            return Ok(Some("4Fh to a vendor-ID wrong in bit 0".to_owned()));
        }
        for sub in 0..4u8 {
            let [a, b, c, d] = address.part(usize::from(sub)).to_le_bytes();
            let next = (sub + 1) % 4;
            if self.ask([0x51, a, b, c, d, 0, sub, next], 0x4F)?.is_none() {
                return Ok(Some(format!(
                    "no 4Fh when confirming the {}",
                    PART_NAMES[usize::from(sub)]
                )));
            }
        }
        Ok(None)
    }
}

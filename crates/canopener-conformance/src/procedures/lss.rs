//! A small LSS master on the test's context (CiA 305 §5), built from canopener-wire's requests: the
//! tests send requests the runtime's LSS session never makes (wrong addresses, out-of-range
//! node-IDs, table index 0Ah), and read every answer as it came, so a wrong answer is evidence.

use canopener_can::{CanFrame, CanId};
use canopener_wire::lss::cs;
use canopener_wire::{
    LSS_MASTER_TO_SLAVE_ID, LSS_SLAVE_TO_MASTER_ID, LssAddress, LssAddressPart, LssRequest, NmtCommand,
};

use crate::context::{Ctx, Reply, hex};
use crate::finding::{Evidence, Finding, Stop};
use crate::procedures::nmt::BOOT_UP_WAIT;
use crate::requirements::lss::{CONFIGURE_NODE_ID, IDENTIFY_REMOTE, INQUIRE, STORE};

/// 1018h:01–04 read over SDO (CiA 305 §3: the LSS address is the identity object); `None` when one of
/// them cannot be read as 4 bytes.
pub fn read_address(ctx: &mut Ctx<'_, '_>) -> Result<Option<LssAddress>, Stop> {
    let mut parts = [0; 4];
    for (sub, part) in (1..).zip(parts.iter_mut()) {
        match ctx.read(0x1018, sub)? {
            Reply::Done(data) => match <[u8; 4]>::try_from(data.as_slice()) {
                Ok(bytes) => *part = u32::from_le_bytes(bytes),
                Err(_) => return Ok(None),
            },
            _ => return Ok(None),
        }
    }
    Ok(Some(LssAddress::from_parts(parts)))
}

/// Identify remote slave bounds as the analysis states them.
pub fn ranges_text(bounds: &[u32; 6]) -> String {
    format!(
        "vendor {:#010X}, product {:#010X}, revision {:#010X}–{:#010X}, serial {:#010X}–{:#010X}",
        bounds[0], bounds[1], bounds[2], bounds[3], bounds[4], bounds[5]
    )
}

/// The CiA 305 bit timing table entries of the rates the EDS mentions, with whether the EDS lists
/// each (`BaudRate_*=1`); rates outside the table are left out.
pub fn listed_bit_rates(ctx: &Ctx<'_, '_>) -> Vec<((u8, u16), bool)> {
    ctx.model()
        .bit_rates
        .iter()
        .filter_map(|&(kbit, on)| canopener_wire::bit_timing_index(kbit).map(|index| ((index, kbit), on)))
        .collect()
}

/// Whether `frame` is an LSS answer (7E4h, 8 bytes) with command specifier `cs`.
pub fn is_lss_answer(frame: &CanFrame, cs: u8) -> bool {
    matches!(frame.id(), CanId::Standard(id) if id.as_raw() == LSS_SLAVE_TO_MASTER_ID)
        && !frame.is_remote()
        && frame.data().len() == 8
        && frame.data().first() == Some(&cs)
}

/// `7E4h 4F 00 …` or `nothing on 7E4h`.
pub fn describe(answer: &Option<Vec<u8>>) -> String {
    match answer {
        Some(data) => format!("7E4h {}", hex(data)),
        None => "nothing on 7E4h".to_owned(),
    }
}

/// The byte after the command specifier (error code, node-ID) of an answer.
pub fn answer_code(answer: &Option<Vec<u8>>) -> Option<u8> {
    answer.as_ref().and_then(|d| d.get(1).copied())
}

/// The device's LSS address, or the verdict when LSS does not apply or cannot be tested: the EDS
/// says `LSS_Supported=0`, or (key absent) the device answers neither inquire nor identify.
pub fn prepare(ctx: &mut Ctx<'_, '_>) -> Result<Result<LssAddress, Finding>, Stop> {
    if ctx.model().lss_supported == Some(false) {
        return Ok(Err(Finding::not_applicable("the EDS says LSS_Supported=0")));
    }
    let Some(address) = read_address(ctx)? else {
        return Ok(Err(Finding::inconclusive(
            "1018h:01–04 (the LSS address) cannot be read over SDO",
        )));
    };
    let mut lss = Lss::new(ctx);
    lss.switch_global(true)?;
    let inquired = lss.ask(LssRequest::InquireAddress(LssAddressPart::VendorId))?;
    lss.switch_global(false)?;
    if inquired.is_some() || lss.identify_remote(&address.exact_ranges())? {
        return Ok(Ok(address));
    }
    let request = "switch state global to configuration, inquire vendor-ID (5Ah), identify remote slave \
                   with the device's own address"
        .to_owned();
    Ok(Err(match ctx.model().lss_supported {
        Some(true) => Finding::fail(
            "no answer to any LSS service although the EDS says LSS_Supported=1",
            Evidence {
                request,
                requirement: format!("{INQUIRE} and {IDENTIFY_REMOTE}: an LSS slave answers on 7E4h"),
                answer: format!("nothing on 7E4h within {} ms each", ctx.timeout().as_millis()),
                cause: "no LSS slave, or it listens on another CAN-ID".to_owned(),
            },
        ),
        _ => Finding::not_applicable(
            "the EDS does not say LSS_Supported and the device answers neither inquire nor identify",
        ),
    }))
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

    /// Sends `request` unconfirmed.
    pub fn send(&mut self, request: LssRequest) -> Result<(), Stop> {
        self.ctx.send(LSS_MASTER_TO_SLAVE_ID, &request.encode())
    }

    /// Sends `request` and returns the first answer with the command specifier CiA 305 gives its
    /// confirmation within the timeout.
    pub fn ask(&mut self, request: LssRequest) -> Result<Option<Vec<u8>>, Stop> {
        let answer_cs = answer_specifier(&request);
        self.send(request)?;
        let timeout = self.ctx.timeout();
        Ok(self
            .ctx
            .wait_for(timeout, |f| is_lss_answer(f, answer_cs))?
            .map(|l| l.frame.data().to_vec()))
    }

    /// Switch state global (04h) to configuration (`true`) or waiting; unconfirmed.
    pub fn switch_global(&mut self, configuration: bool) -> Result<(), Stop> {
        self.send(LssRequest::SwitchStateGlobal {
            mode: u8::from(configuration),
        })
    }

    /// Switch state selective (40h–43h) with `address`: the 44h answer.
    pub fn switch_selective(&mut self, address: &LssAddress) -> Result<Option<Vec<u8>>, Stop> {
        let [first @ .., last] = address.switch_selective();
        for request in first {
            self.send(request)?;
        }
        self.ask(last)
    }

    /// Switch state selective with `address` and inquire node-ID at once: the first 44h or 5Eh
    /// answer within one timeout.
    pub fn switch_selective_then_inquire(&mut self, address: &LssAddress) -> Result<Option<Vec<u8>>, Stop> {
        for request in address.switch_selective() {
            self.send(request)?;
        }
        self.send(LssRequest::InquireNodeId)?;
        let timeout = self.ctx.timeout();
        Ok(self
            .ctx
            .wait_for(timeout, |f| {
                is_lss_answer(f, cs::SWITCH_STATE_SELECTIVE_RESPONSE) || is_lss_answer(f, cs::INQUIRE_NODE_ID)
            })?
            .map(|l| l.frame.data().to_vec()))
    }

    /// Inquire node-ID (5Eh).
    pub fn inquire_node_id(&mut self) -> Result<Option<Vec<u8>>, Stop> {
        self.ask(LssRequest::InquireNodeId)
    }

    /// Identify remote slave (46h–4Bh) with `bounds` (vendor-ID, product code, revision low and
    /// high, serial low and high): whether a 4Fh came back.
    pub fn identify_remote(&mut self, bounds: &[u32; 6]) -> Result<bool, Stop> {
        let [first @ .., last] = LssRequest::identify_remote_slave(*bounds);
        for request in first {
            self.send(request)?;
        }
        Ok(self.ask(last)?.is_some())
    }

    /// Switch state selective to `address`, configure `node`, store: `Ok(true)` stored,
    /// `Ok(false)` storing not supported, `Err` a failure with its evidence.
    pub fn configure_and_store(
        &mut self,
        address: &LssAddress,
        node: u8,
    ) -> Result<Result<bool, Finding>, Stop> {
        let selected = self.switch_selective(address)?;
        let configured = self.ask(LssRequest::ConfigureNodeId { node_id: node })?;
        if selected.is_none() || answer_code(&configured) != Some(0) {
            return Ok(Err(Finding::fail(
                format!("configure node-ID {node} after switch state selective failed"),
                Evidence {
                    request: format!("switch state selective with {address}, configure node-ID {node}"),
                    requirement: format!("{CONFIGURE_NODE_ID}: 44h, then configure node-ID answered with 0"),
                    answer: format!("{} / {}", describe(&selected), describe(&configured)),
                    cause: "no configuration state, or configure node-ID not served".to_owned(),
                },
            )));
        }
        let stored = self.ask(LssRequest::StoreConfiguration)?;
        match answer_code(&stored) {
            Some(0) => Ok(Ok(true)),
            Some(1) => Ok(Ok(false)),
            _ => Ok(Err(Finding::fail(
                "store configuration not confirmed".to_owned(),
                Evidence {
                    request: "store configuration (17h) in configuration state".to_owned(),
                    requirement: format!(
                        "{STORE}: 17h with error code 0 (stored), 1 (not supported) or 2 (media error)"
                    ),
                    answer: describe(&stored),
                    cause: "store configuration not served, or storing failed".to_owned(),
                },
            ))),
        }
    }

    /// NMT reset node to `node`, then the node-ID the device runs with, as inquire node-ID says
    /// (not the boot-up message: a device may boot silently, which is CiA 301's business).
    pub fn reset_node_and_inquire(&mut self, node: u8) -> Result<Option<u8>, Stop> {
        // NMT reset node (81h) to `node`, which need not be the node-ID under test.
        self.ctx
            .send(canopener_wire::NMT_ID, &[NmtCommand::ResetNode.as_raw(), node])?;
        self.first_boot_up()?;
        self.active_node_id()
    }

    /// The node-ID inquire node-ID gives in configuration state; leaves the slave waiting.
    pub fn active_node_id(&mut self) -> Result<Option<u8>, Stop> {
        self.switch_global(true)?;
        let answer = self.inquire_node_id()?;
        self.switch_global(false)?;
        Ok(answer_code(&answer))
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
        self.first_boot_up()?;
        self.active_node_id()
    }

    /// The node-ID of the first boot-up message (700h + node-ID, one byte 0) within the boot-up wait.
    pub fn first_boot_up(&mut self) -> Result<Option<u8>, Stop> {
        let node_of = |frame: &CanFrame| match frame.id() {
            CanId::Standard(id) if frame.data() == [0] && !frame.is_remote() => {
                let node = id.as_raw().checked_sub(canopener_wire::ERROR_CONTROL_BASE)?;
                u8::try_from(node).ok().filter(|n| (1..=127).contains(n))
            }
            _ => None,
        };
        Ok(self
            .ctx
            .wait_for(BOOT_UP_WAIT, |f| node_of(f).is_some())?
            .and_then(|l| node_of(&l.frame)))
    }

    /// Fastscan (CiA 305 §5.6.4) for a slave whose address is known (each part confirmed at once,
    /// as a master does for parts it knows, instead of 32 bit steps whose silences each cost a
    /// timeout); `Some(what went wrong)` or `None` when every step was answered as required.
    pub fn fastscan(&mut self, address: &LssAddress) -> Result<Option<String>, Stop> {
        let step = |id_number, bit_checked, lss_sub, lss_next| LssRequest::Fastscan {
            id_number,
            bit_checked,
            lss_sub,
            lss_next,
        };
        if self
            .ask(step(0, canopener_wire::lss::FASTSCAN_RESET, 0, 0))?
            .is_none()
        {
            return Ok(Some("no 4Fh to the reset step (BitChecked 80h)".to_owned()));
        }
        if self.ask(step(address.vendor_id ^ 1, 0, 0, 0))?.is_some() {
            return Ok(Some("4Fh to a vendor-ID wrong in bit 0".to_owned()));
        }
        for (sub, part) in (0u8..).zip(LssAddressPart::ALL) {
            let next = (sub + 1) % 4;
            if self.ask(step(address.part(part), 0, sub, next))?.is_none() {
                return Ok(Some(format!("no 4Fh when confirming the {part}")));
            }
        }
        Ok(None)
    }
}

/// The command specifier of the slave's confirmation of `request` (CiA 305 §5: identify and fastscan
/// are answered with 4Fh or 50h, switch state selective with 44h, the rest with their own).
pub fn answer_specifier(request: &LssRequest) -> u8 {
    match request {
        LssRequest::SwitchStateSelective { .. } => cs::SWITCH_STATE_SELECTIVE_RESPONSE,
        LssRequest::IdentifyRemoteSlave { .. } | LssRequest::Fastscan { .. } => cs::IDENTIFY_SLAVE,
        LssRequest::IdentifyNonConfiguredRemoteSlave => cs::IDENTIFY_NON_CONFIGURED_SLAVE,
        other => other.encode()[0],
    }
}

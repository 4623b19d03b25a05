//! Layer setting services (CiA 305) on a link: one [`LssMaster`] and the sequences the master commands
//! run with it: select a device by its address and configure it, inquire the address of the device
//! in configuration state, fastscan and assign node-IDs to all unconfigured devices, or list them.
//!
//! Every sequence leaves no device in configuration state: on success the commands end with switch
//! state global to waiting, on cancellation [`LssSession::abandon`] sends it whatever the master was
//! doing.
//!
//! Listing without assigning: each device fastscan finds stays in LSS configuration state, where CiA
//! 305 slaves take no part in fastscan, so the next fastscan finds the next device; at the end one
//! switch state global sends all back to waiting. A device found twice (one that answers fastscan in
//! configuration state against CiA 305) ends the listing instead of looping.

use std::collections::BTreeSet;
use std::time::Duration;

use canopener_can::{CanFrame, Instant, StandardId};
use canopener_master::lss_master::{
    KnownParts, LssCommandError, LssConfig, LssEvent, LssMaster, LssMode, LssService, LssServiceError,
    LssStats, ScanError, ScanPlan,
};
use canopener_wire::lss::UNCONFIGURED_NODE_ID;
use canopener_wire::{LSS_MASTER_TO_SLAVE_ID, LssAddress, LssAddressPart, LssRequest, NodeId};

use crate::link::{Ended, Flow, Link, LinkError, drive};

/// More devices than this in one listing means something answers that is no CiA 305 slave.
pub const MAX_LISTED: usize = 1024;

/// Added to a service's own timeout and settle time before the session gives up on the core.
const SERVICE_SLACK: Duration = Duration::from_secs(1);

/// Why an LSS sequence failed.
#[derive(Debug, thiserror::Error)]
pub enum LssError {
    /// The link was cancelled; switch state global to waiting went out.
    #[error("interrupted")]
    Cancelled,
    /// No device with this address answered switch state selective.
    #[error("no device with {address} answered switch state selective within {} ms", .after.as_millis())]
    NotSelected {
        /// The address.
        address: LssAddress,
        /// The timeout.
        after: Duration,
    },
    /// The selected device refused a configuration.
    #[error("the device with {address} refused {service} ({what}): {error}")]
    Refused {
        /// The device.
        address: LssAddress,
        /// The service.
        service: LssService,
        /// What was configured (`node-ID 5`).
        what: String,
        /// The device's error code.
        error: LssServiceError,
    },
    /// The selected device did not answer a configuration.
    #[error("the device with {address} did not answer {service} ({what}) within {} ms", .after.as_millis())]
    Silent {
        /// The device.
        address: LssAddress,
        /// The service.
        service: LssService,
        /// What was configured.
        what: String,
        /// The timeout.
        after: Duration,
    },
    /// No device answered the first inquiry after switch state global.
    #[error("no device answered {service} within {} ms after switch state global", .after.as_millis())]
    NoDevice {
        /// The service.
        service: LssService,
        /// The timeout.
        after: Duration,
    },
    /// The device in configuration state stopped answering inquiries.
    #[error("the device in LSS configuration state did not answer {service} within {} ms", .after.as_millis())]
    InquirySilent {
        /// The service.
        service: LssService,
        /// The timeout.
        after: Duration,
    },
    /// The master core refused to start a service (a bug of the sequence).
    #[error("LSS master: {0}")]
    Start(#[from] LssCommandError),
    /// The master core did not end a service in time (a bug of the core).
    #[error("the LSS master did not end {running:?} within {} ms", .within.as_millis())]
    Stuck {
        /// The service running.
        running: Option<LssService>,
        /// The wait.
        within: Duration,
    },
    /// An event the sequence does not expect at this point.
    #[error("unexpected LSS master event: {0}")]
    Unexpected(LssEvent),
    /// The bus failed.
    #[error(transparent)]
    Link(#[from] LinkError),
}

/// A device a scan found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Found {
    /// Its LSS address.
    pub address: LssAddress,
    /// The node-ID it was given, when assigning.
    pub node_id: Option<NodeId>,
    /// Why storing its configuration failed, when asked to store.
    pub store_problem: Option<String>,
}

/// How a scan ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ScanOutcome {
    /// Every unconfigured device was found.
    Complete,
    /// Cancelled; switch state global to waiting went out.
    Interrupted,
    /// The master's scan failed.
    Failed(ScanError),
    /// Listing without assigning found a device a second time.
    Repeated(LssAddress),
    /// More than [`MAX_LISTED`] devices answered.
    TooMany,
}

/// One LSS master on one link, and what it saw besides the answers it waited for.
#[derive(Debug)]
pub struct LssSession<L: Link> {
    link: L,
    master: LssMaster,
    extra_answers: u64,
    ignored: u64,
}

impl<L: Link> LssSession<L> {
    /// A session with the timing `config`.
    pub fn new(link: L, config: LssConfig) -> LssSession<L> {
        LssSession {
            link,
            master: LssMaster::new(config),
            extra_answers: 0,
            ignored: 0,
        }
    }

    /// The link.
    pub fn link_mut(&mut self) -> &mut L {
        &mut self.link
    }

    /// The timing.
    pub fn config(&self) -> LssConfig {
        self.master.config()
    }

    /// The master's frame and timeout counts.
    pub fn stats(&self) -> LssStats {
        self.master.stats()
    }

    /// Answers from a second device where one was expected (several in configuration state).
    pub fn extra_answers(&self) -> u64 {
        self.extra_answers
    }

    /// Frames on 7E4h that answered nothing pending (late answers, garbage).
    pub fn ignored(&self) -> u64 {
        self.ignored
    }

    /// Starts one service and drives it to its end event. The core ends every service within its
    /// timeout and settle time; the deadline here only guards against a core that would not.
    pub fn service(
        &mut self,
        start: impl FnOnce(&mut LssMaster, Instant) -> Result<(), LssCommandError>,
    ) -> Result<LssEvent, LssError> {
        let now = self.link.now();
        start(&mut self.master, now)?;
        let config = self.master.config();
        let deadline = now + config.timeout * 2 + config.settle + SERVICE_SLACK;
        let (extra, ignored) = (&mut self.extra_answers, &mut self.ignored);
        let ended =
            drive::<_, _, _, LinkError>(&mut self.link, &mut self.master, Some(deadline), |_, event| {
                Ok(match event {
                    LssEvent::ExtraAnswer { .. } => {
                        *extra += 1;
                        Flow::Continue
                    }
                    LssEvent::Ignored { .. } => {
                        *ignored += 1;
                        Flow::Continue
                    }
                    LssEvent::Found { .. } | LssEvent::SwitchBitRate => Flow::Continue,
                    end => Flow::Done(end),
                })
            })?;
        match ended {
            Ok(event) => Ok(event),
            Err(Ended::Cancelled) => {
                self.abandon();
                Err(LssError::Cancelled)
            }
            Err(Ended::Deadline) => Err(LssError::Stuck {
                running: self.master.running(),
                within: deadline.saturating_duration_since(now),
            }),
        }
    }

    /// Switch state global to waiting (CiA 305): every device leaves configuration state, and one
    /// that was unconfigured makes a node-ID it was given active.
    pub fn back_to_waiting(&mut self) -> Result<(), LssError> {
        self.service(|master, _| master.switch_state_global(LssMode::Waiting))
            .map(drop)
    }

    /// Sends switch state global to waiting whatever the master is doing: the sequence ends, and no
    /// device may be left in configuration state.
    pub fn abandon(&mut self) {
        let request = LssRequest::SwitchStateGlobal { mode: 0 };
        if let Some(id) = StandardId::new(LSS_MASTER_TO_SLAVE_ID)
            && let Ok(frame) = CanFrame::new(id, &request.encode())
        {
            // Best effort on the way out: the link may be what failed.
            let _ = self.link.send(&frame);
        }
    }

    /// Switch state selective: the device with `address` enters configuration state.
    pub fn select(&mut self, address: LssAddress) -> Result<(), LssError> {
        match self.service(|master, now| master.switch_state_selective(now, address))? {
            LssEvent::Done { .. } => Ok(()),
            LssEvent::TimedOut { after, .. } => Err(LssError::NotSelected { address, after }),
            other => Err(LssError::Unexpected(other)),
        }
    }

    /// Switch state global to configuration: every device enters configuration state.
    pub fn select_all(&mut self) -> Result<(), LssError> {
        self.service(|master, _| master.switch_state_global(LssMode::Configuration))
            .map(drop)
    }

    /// Inquires the previous node-ID, then configures the selected device with `address`: its
    /// node-ID (`None` makes it unconfigured), its bit timing index, and stores the configuration.
    /// Returns the previous node-ID when the device told it.
    pub fn configure_selected(
        &mut self,
        address: &LssAddress,
        node_id: Option<NodeId>,
        bit_timing: Option<u8>,
        store: bool,
    ) -> Result<Option<u8>, LssError> {
        let previous = match self.service(|master, now| master.inquire_node_id(now))? {
            LssEvent::NodeIdInquired { node_id } => Some(node_id),
            _ => None,
        };
        let what = format!(
            "node-ID {}",
            node_id_text(node_id.map_or(UNCONFIGURED_NODE_ID, NodeId::get))
        );
        let event = self.service(|master, now| master.configure_node_id(now, node_id))?;
        confirmed(address, &what, event)?;
        if let Some(index) = bit_timing {
            let what = format!(
                "bit timing {}",
                canopener_wire::bit_timing_text(index).unwrap_or("?")
            );
            let event = self.service(|master, now| master.configure_bit_timing(now, index))?;
            confirmed(address, &what, event)?;
        }
        if store {
            let event = self.service(|master, now| master.store_configuration(now))?;
            confirmed(address, "the configuration", event)?;
        }
        Ok(previous)
    }

    /// Inquires the four address parts and the node-ID of the device in configuration state
    /// (`global`: selected by switch state global, so silence means no device). The node-ID is
    /// `Err(timeout)` when the device did not answer that inquiry.
    pub fn inquire_selected(&mut self, global: bool) -> Result<(LssAddress, Result<u8, Duration>), LssError> {
        let mut values = [0u32; 4];
        for (idx, (slot, part)) in values.iter_mut().zip(LssAddressPart::ALL).enumerate() {
            match self.service(|master, now| master.inquire_address(now, part))? {
                LssEvent::Inquired { value, .. } => *slot = value,
                LssEvent::TimedOut { service, after } if idx == 0 && global => {
                    return Err(LssError::NoDevice { service, after });
                }
                LssEvent::TimedOut { service, after } => {
                    return Err(LssError::InquirySilent { service, after });
                }
                other => return Err(LssError::Unexpected(other)),
            }
        }
        let [vendor_id, product_code, revision_number, serial_number] = values;
        let address = LssAddress {
            vendor_id,
            product_code,
            revision_number,
            serial_number,
        };
        let node_id = match self.service(|master, now| master.inquire_node_id(now))? {
            LssEvent::NodeIdInquired { node_id } => Ok(node_id),
            LssEvent::TimedOut { after, .. } => Err(after),
            other => return Err(LssError::Unexpected(other)),
        };
        Ok((address, node_id))
    }

    /// Fastscan and node-ID assignment of every unconfigured device ([`LssMaster::scan_all`]),
    /// telling `on_found` of each device as it is configured.
    pub fn scan_all<E: From<LinkError>>(
        &mut self,
        plan: ScanPlan,
        mut on_found: impl FnMut(&Found) -> Result<(), E>,
    ) -> Result<Result<(Vec<Found>, ScanOutcome), LssCommandError>, E> {
        let now = self.link.now();
        if let Err(err) = self.master.scan_all(now, plan) {
            return Ok(Err(err));
        }
        let mut found = Vec::new();
        let mut store_problem = None;
        let (extra, ignored) = (&mut self.extra_answers, &mut self.ignored);
        let ended = drive::<_, _, _, E>(&mut self.link, &mut self.master, None, |_, event| {
            match event {
                LssEvent::Found { address, node_id } => {
                    let device = Found {
                        address,
                        node_id,
                        store_problem: store_problem.take(),
                    };
                    on_found(&device)?;
                    found.push(device);
                }
                LssEvent::Configured {
                    service: LssService::StoreConfiguration,
                    result: Err(err),
                } => store_problem = Some(format!("store configuration: {err}")),
                LssEvent::TimedOut {
                    service: LssService::StoreConfiguration,
                    after,
                } => {
                    store_problem = Some(format!(
                        "store configuration: no answer within {} ms",
                        after.as_millis()
                    ));
                }
                LssEvent::ExtraAnswer { .. } => *extra += 1,
                LssEvent::Ignored { .. } => *ignored += 1,
                LssEvent::ScanFinished { .. } => return Ok(Flow::Done(ScanOutcome::Complete)),
                LssEvent::ScanFailed { error, .. } => return Ok(Flow::Done(ScanOutcome::Failed(error))),
                _ => {}
            }
            Ok(Flow::Continue)
        })?;
        let outcome = match ended {
            Ok(outcome) => outcome,
            // Without a deadline only a cancellation ends the drive.
            Err(_) => {
                self.abandon();
                ScanOutcome::Interrupted
            }
        };
        Ok(Ok((found, outcome)))
    }

    /// Lists the unconfigured devices without configuring them (see the module docs), telling
    /// `on_found` of each as it is found.
    pub fn list_all<E: From<LinkError> + From<LssError>>(
        &mut self,
        mut on_found: impl FnMut(&Found) -> Result<(), E>,
    ) -> Result<(Vec<Found>, ScanOutcome), E> {
        let mut found: Vec<Found> = Vec::new();
        let mut seen = BTreeSet::new();
        let outcome = loop {
            if found.len() >= MAX_LISTED {
                break ScanOutcome::TooMany;
            }
            let now = self.link.now();
            self.master
                .fastscan(now, KnownParts::NONE)
                .map_err(LssError::from)?;
            let (extra, ignored) = (&mut self.extra_answers, &mut self.ignored);
            let mut this = None;
            let ended = drive::<_, _, _, E>(&mut self.link, &mut self.master, None, |_, event| {
                match event {
                    LssEvent::Found { address, .. } => this = Some(address),
                    LssEvent::ExtraAnswer { .. } => *extra += 1,
                    LssEvent::Ignored { .. } => *ignored += 1,
                    LssEvent::ScanFinished { .. } => return Ok(Flow::Done(Ok(()))),
                    LssEvent::ScanFailed { error, .. } => return Ok(Flow::Done(Err(error))),
                    _ => {}
                }
                Ok(Flow::Continue)
            })?;
            match ended {
                Err(_) => {
                    self.abandon();
                    break ScanOutcome::Interrupted;
                }
                Ok(Err(error)) => break ScanOutcome::Failed(error),
                Ok(Ok(())) => {}
            }
            let Some(address) = this else {
                break ScanOutcome::Complete;
            };
            if !seen.insert(address) {
                break ScanOutcome::Repeated(address);
            }
            let device = Found {
                address,
                node_id: None,
                store_problem: None,
            };
            on_found(&device)?;
            found.push(device);
        };
        if !matches!(outcome, ScanOutcome::Interrupted) {
            self.back_to_waiting()?;
        }
        Ok((found, outcome))
    }
}

/// The answer to configure node-ID, bit timing or store configuration as a result.
pub fn confirmed(address: &LssAddress, what: &str, event: LssEvent) -> Result<(), LssError> {
    match event {
        LssEvent::Configured { result: Ok(()), .. } => Ok(()),
        LssEvent::Configured {
            service,
            result: Err(error),
        } => Err(LssError::Refused {
            address: *address,
            service,
            what: what.to_owned(),
            error,
        }),
        LssEvent::TimedOut { service, after } => Err(LssError::Silent {
            address: *address,
            service,
            what: what.to_owned(),
            after,
        }),
        other => Err(LssError::Unexpected(other)),
    }
}

/// A node-ID as the LSS messages write it; FFh is "unconfigured".
pub fn node_id_text(raw: u8) -> String {
    if raw == UNCONFIGURED_NODE_ID {
        "unconfigured (FFh)".to_owned()
    } else {
        raw.to_string()
    }
}

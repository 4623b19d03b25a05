//! Configuring one PDO over an SDO session with the dynamic mapping procedure of CiA 301 §7.2.2 on
//! the PDO parameter objects 1400h–1BFFh (§7.5.2.35–§7.5.2.38), as
//! [`pdo_config`](canopener_master::pdo_config) plans it: [`read_cob_id`] reads the current COB-ID
//! (communication parameter sub 1) the plan starts from, [`execute`] sends the writes one by one as
//! expedited SDO downloads (§7.2.4.3.3), stopping at the first one the device refuses or leaves
//! unanswered; the [`MapReport`] then says in which state the PDO was left.

use canopener_master::pdo_config::PdoConfig;
use canopener_master::pdo_map_report::{MapReport, StepOutcome};
use canopener_master::sdo_client::SdoTransferError;
use canopener_master::value::{entry_label, hex_value};
use canopener_wire::{NodeId, abort};

use crate::link::Link;
use crate::sdo_session::{SdoError, SdoSession};

/// Why the current COB-ID could not be read; nothing was written.
#[derive(Debug, thiserror::Error)]
pub enum ReadCobIdError {
    /// The device answered with something that is no UNSIGNED32.
    #[error(
        "node {node}, reading the COB-ID of {pdo} ({}): the device answered {} byte(s) ({}), but a COB-ID is \
         UNSIGNED32; nothing was written",
        entry_label(*.index, 1),
        .data.len(),
        hex_value(.data)
    )]
    NotUnsigned32 {
        /// The node.
        node: NodeId,
        /// `TPDO1`.
        pdo: String,
        /// The communication parameter object.
        index: u16,
        /// What the device sent.
        data: Vec<u8>,
    },
    /// The device refused or did not answer.
    #[error(
        "node {node}, reading the COB-ID of {pdo} ({}): {error}{}; nothing was written",
        entry_label(*.index, 1),
        match .error.abort_code() {
            abort::OBJECT_DOES_NOT_EXIST | abort::SUB_INDEX_DOES_NOT_EXIST => format!(" (the device has no {pdo})"),
            _ => String::new(),
        }
    )]
    Refused {
        /// The node.
        node: NodeId,
        /// `TPDO1`.
        pdo: String,
        /// The communication parameter object.
        index: u16,
        /// The abort or timeout.
        error: SdoTransferError,
    },
    /// The session failed or was cancelled.
    #[error(transparent)]
    Session(SdoError),
}

/// The COB-ID the PDO of `config` has now (communication parameter sub 1).
pub fn read_cob_id<L: Link>(session: &mut SdoSession<L>, config: &PdoConfig) -> Result<u32, ReadCobIdError> {
    let index = config.comm_index().unwrap_or(config.direction.comm_base());
    let node = NodeId::new(session.node()).unwrap_or(NodeId::MIN);
    let pdo = config.name().to_string();
    match session.read(index, 1) {
        Ok(data) => match <[u8; 4]>::try_from(data.as_slice()) {
            Ok(bytes) => Ok(u32::from_le_bytes(bytes)),
            Err(_) => Err(ReadCobIdError::NotUnsigned32 {
                node,
                pdo,
                index,
                data,
            }),
        },
        Err(SdoError::Transfer(error)) => Err(ReadCobIdError::Refused {
            node,
            pdo,
            index,
            error,
        }),
        Err(other) => Err(ReadCobIdError::Session(other)),
    }
}

/// Sends the writes of `report` in order until one fails or the link is cancelled, calling `on_step`
/// after each one that was sent. Only a failing link or a write the client cannot start ends it with
/// an error; refusals, timeouts and cancellation are recorded in the report.
pub fn execute<L: Link>(
    session: &mut SdoSession<L>,
    report: &mut MapReport,
    mut on_step: impl FnMut(&MapReport, usize),
) -> Result<(), SdoError> {
    for step in 0..report.steps.len() {
        let Some((write, _)) = report.steps.get(step) else {
            break;
        };
        let outcome = match session.write(write.index, write.sub, write.data.clone()) {
            Ok(()) => StepOutcome::Ok,
            Err(SdoError::Transfer(error)) => StepOutcome::Failed(error),
            Err(SdoError::Cancelled { .. }) => StepOutcome::Interrupted,
            Err(other) => return Err(other),
        };
        let stop = outcome != StepOutcome::Ok;
        if let Some((_, recorded)) = report.steps.get_mut(step) {
            *recorded = outcome;
        }
        on_step(report, step);
        if stop {
            break;
        }
    }
    Ok(())
}

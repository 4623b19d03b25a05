//! Reading every readable entry of an EDS from a device into a DCF (CiA 306 §5): [`read_entries`]
//! reads what [`plan`](canopener_master::dcf_dump::plan) chose, [`dcf_time`] is the modification
//! time the DCF states, [`write_dcf`] writes it with the value files beside it. Building the DCF from
//! the readings is [`canopener_master::dcf_dump::build_dcf`].

use std::path::{Path, PathBuf};
use std::time::SystemTime;

use canopener_eds::DataType;
use canopener_master::dcf_dump::{Dcf, Planned, Reading};
use canopener_master::sdo_client::{SdoTransferError, UploadMode};

use crate::link::Link;
use crate::sdo_session::{SdoError, SdoSession, Transfer};
use canopener_files::{WriteError, write_atomic};

/// After this many timeouts in a row the device is taken to be gone and the dump stops.
const TIMEOUTS_IN_A_ROW: usize = 3;

/// Why the dump stopped reading.
#[derive(Debug, thiserror::Error)]
pub enum DumpError {
    /// The very first entry read timed out: nothing answers.
    #[error("node {node}, {}: {error}", .entry.label())]
    Silent {
        /// The node.
        node: u8,
        /// The entry.
        entry: Box<Planned>,
        /// The timeout.
        error: SdoTransferError,
    },
    /// Several reads in a row timed out after the device had answered.
    #[error("node {node} stopped answering: node {node}, {}: {error}", .entry.label())]
    StoppedAnswering {
        /// The node.
        node: u8,
        /// The last entry.
        entry: Box<Planned>,
        /// The timeout.
        error: SdoTransferError,
    },
    /// The session failed or was cancelled.
    #[error(transparent)]
    Session(#[from] SdoError),
}

/// Reads every entry of `plan` that is not skipped; `on_entry` hears of each before it is read.
/// An abort is no failure of the dump: it is recorded as the entry's reading.
pub fn read_entries<L: Link>(
    session: &mut SdoSession<L>,
    plan: &[Planned],
    mut on_entry: impl FnMut(&Planned),
) -> Result<Vec<Reading>, DumpError> {
    let mut readings = Vec::with_capacity(plan.len());
    let mut answered = false;
    let mut timeouts_in_a_row = 0;
    for entry in plan {
        if entry.skip.is_some() {
            readings.push(Reading::Skipped);
            continue;
        }
        on_entry(entry);
        let outcome = read_one(session, entry)?;
        match &outcome {
            Err(error @ SdoTransferError::TimedOut { .. }) => {
                timeouts_in_a_row += 1;
                if !answered {
                    return Err(DumpError::Silent {
                        node: session.node(),
                        entry: Box::new(entry.clone()),
                        error: error.clone(),
                    });
                }
                if timeouts_in_a_row >= TIMEOUTS_IN_A_ROW {
                    return Err(DumpError::StoppedAnswering {
                        node: session.node(),
                        entry: Box::new(entry.clone()),
                        error: error.clone(),
                    });
                }
            }
            _ => {
                answered = true;
                timeouts_in_a_row = 0;
            }
        }
        readings.push(match outcome {
            Ok(transfer) => Reading::Value(transfer.data),
            Err(err) => Reading::Failed(err),
        });
    }
    Ok(readings)
}

/// One entry: DOMAINs (bulk data) by block upload first, which is many times faster; a device without
/// block transfer refuses it with an abort, and then the normal upload decides.
fn read_one<L: Link>(
    session: &mut SdoSession<L>,
    entry: &Planned,
) -> Result<Result<Transfer, SdoTransferError>, SdoError> {
    if entry.data_type == Some(DataType::DOMAIN) {
        match session.upload(entry.index, entry.sub, UploadMode::Block, &mut |_| {}) {
            Err(SdoError::Transfer(
                SdoTransferError::AbortedByServer { .. } | SdoTransferError::AbortedByClient { .. },
            )) => {}
            other => return transfer_result(other),
        }
    }
    transfer_result(session.upload(entry.index, entry.sub, UploadMode::Normal, &mut |_| {}))
}

fn transfer_result(
    outcome: Result<Transfer, SdoError>,
) -> Result<Result<Transfer, SdoTransferError>, SdoError> {
    match outcome {
        Ok(transfer) => Ok(Ok(transfer)),
        Err(SdoError::Transfer(error)) => Ok(Err(error)),
        Err(other) => Err(other),
    }
}

/// The modification time a DCF made now states.
pub fn dcf_time() -> SystemTime {
    SystemTime::now()
}

/// A file of the DCF could not be written.
#[derive(Debug, thiserror::Error)]
#[error("writing {}: {source}", .file.display())]
pub struct DcfWriteError {
    /// The file (the DCF or a value file beside it).
    pub file: PathBuf,
    /// Why.
    #[source]
    pub source: WriteError,
}

/// Writes the files beside the DCF, then the DCF to `out`, each loss-free (temporary file and
/// rename), keeping a replaced file as `.bak` when `backup`.
pub fn write_dcf(out: &Path, dcf: &Dcf, backup: bool) -> Result<(), DcfWriteError> {
    let files = dcf
        .sidecars
        .iter()
        .map(|(file, data)| (file.as_path(), data.as_slice()))
        .chain([(out, dcf.bytes.as_slice())]);
    for (file, data) in files {
        write_atomic(file, data, backup).map_err(|source| DcfWriteError {
            file: file.to_path_buf(),
            source,
        })?;
    }
    Ok(())
}

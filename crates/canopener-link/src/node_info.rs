//! Reading what one node is over SDO: [`read`] fills a [`NodeInfo`] from 1000h, 1001h, 1018h,
//! 1008h/1009h/100Ah and 1017h, and waits for one heartbeat when 1017h says the node sends one (CiA
//! 301 §7.2.8.3.2.2). Optional objects the node does not have are recorded as absent, not as errors.

use canopener_master::node_info::{
    DeviceType, Field, HeartbeatSeen, IDENTITY_SUBS, NAME_INDICES, NodeInfo, WidthError, heartbeat_state,
    heartbeat_wait, unsigned,
};
use canopener_master::sdo_client::SdoTransferError;
use canopener_master::value::entry_label;

use crate::link::{Link, LinkError};
use crate::sdo_session::{SdoError, SdoSession};

/// After this many timeouts in a row the node is taken to be gone.
const TIMEOUTS_IN_A_ROW: u32 = 2;

/// Why the node could not be described.
#[derive(Debug, thiserror::Error)]
pub enum NodeInfoError {
    /// The mandatory 1000h was refused or not answered: the node is not worth asking more.
    #[error("node {node}, 1000h:00 (Device type): {error}")]
    DeviceType {
        /// The node.
        node: u8,
        /// The abort or timeout.
        error: SdoTransferError,
    },
    /// 1000h is no UNSIGNED32.
    #[error("node {node}, 1000h:00 (Device type): {error}")]
    DeviceTypeWidth {
        /// The node.
        node: u8,
        /// What was wrong.
        error: WidthError,
    },
    /// The node stopped answering in the middle.
    #[error("node {node} stopped answering: node {node}, {}: {error}", entry_label(*.index, *.sub))]
    StoppedAnswering {
        /// The node.
        node: u8,
        /// The object of the last timeout.
        index: u16,
        /// Its sub-index.
        sub: u8,
        /// The timeout.
        error: SdoTransferError,
    },
    /// The session failed or was cancelled.
    #[error(transparent)]
    Session(#[from] SdoError),
}

impl From<LinkError> for NodeInfoError {
    fn from(err: LinkError) -> NodeInfoError {
        NodeInfoError::Session(err.into())
    }
}

/// Reads what the node of `session` is.
pub fn read<L: Link>(session: &mut SdoSession<L>) -> Result<NodeInfo, NodeInfoError> {
    let node = session.node();
    let mut reader = Reader {
        session,
        timeouts_in_a_row: 0,
    };
    let device_type = match reader.read(0x1000, 0)? {
        Ok(data) => unsigned(&data, 4).map_err(|error| NodeInfoError::DeviceTypeWidth { node, error })?,
        Err(error) => return Err(NodeInfoError::DeviceType { node, error }),
    };
    let error_register = Field::unsigned(reader.read(0x1001, 0)?, 1);
    let mut identity = [const { Field::Absent }; 4];
    for (slot, sub) in identity.iter_mut().zip(IDENTITY_SUBS) {
        *slot = Field::unsigned(reader.read(0x1018, sub)?, 4);
    }
    let mut names = [const { Field::Absent }; 3];
    for (slot, index) in names.iter_mut().zip(NAME_INDICES) {
        *slot = Field::text(reader.read(index, 0)?);
    }
    let heartbeat_time = Field::unsigned(reader.read(0x1017, 0)?, 2);
    let heartbeat = match heartbeat_time {
        Field::Value(period) if period > 0 => Some(wait_heartbeat(reader.session.link_mut(), node, period)?),
        _ => None,
    };
    Ok(NodeInfo {
        node,
        device_type: DeviceType::describe(device_type as u32),
        error_register,
        identity,
        names,
        heartbeat_time,
        heartbeat,
    })
}

/// The session, giving up once the node has stopped answering.
struct Reader<'a, L: Link> {
    session: &'a mut SdoSession<L>,
    timeouts_in_a_row: u32,
}

impl<L: Link> Reader<'_, L> {
    fn read(&mut self, index: u16, sub: u8) -> Result<Result<Vec<u8>, SdoTransferError>, NodeInfoError> {
        let outcome = match self.session.read(index, sub) {
            Ok(data) => Ok(data),
            Err(SdoError::Transfer(error)) => Err(error),
            Err(other) => return Err(other.into()),
        };
        match &outcome {
            Err(error @ SdoTransferError::TimedOut { .. }) => {
                self.timeouts_in_a_row += 1;
                if self.timeouts_in_a_row >= TIMEOUTS_IN_A_ROW {
                    return Err(NodeInfoError::StoppedAnswering {
                        node: self.session.node(),
                        index,
                        sub,
                        error: error.clone(),
                    });
                }
            }
            _ => self.timeouts_in_a_row = 0,
        }
        Ok(outcome)
    }
}

/// Waits up to 1.5 heartbeat periods for one heartbeat of `node`.
fn wait_heartbeat<L: Link + ?Sized>(
    link: &mut L,
    node: u8,
    period_ms: u64,
) -> Result<HeartbeatSeen, LinkError> {
    let waited = heartbeat_wait(period_ms);
    let start = link.now();
    let deadline = start + waited;
    while let Some((at, frame)) = link.recv_until(deadline)? {
        let Some(state) = heartbeat_state(&frame, node) else {
            continue;
        };
        let after = at.saturating_duration_since(start);
        return Ok(match state {
            Ok(state) => HeartbeatSeen {
                waited,
                state: Some((state, after)),
                invalid: None,
            },
            Err(byte) => HeartbeatSeen {
                waited,
                state: None,
                invalid: Some(byte),
            },
        });
    }
    Ok(HeartbeatSeen {
        waited,
        state: None,
        invalid: None,
    })
}

//! Why a simulation could not start or stopped.

use std::path::PathBuf;

use canopener_transport::TransportError;

use crate::state_store::StateStoreError;
use canopener_link::link::LinkError;

/// Why simulated devices could not be set up or run. The messages name the file and say what to do.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A description file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        #[source]
        source: std::io::Error,
    },
    /// A description describes no objects: nothing to simulate. `errors` quotes the loader's first
    /// errors, one per line.
    #[error("{name} is not a usable EDS/DCF: it describes no objects{}{errors}", if *looks_like_xml {
        "; it looks like XML: convert an XDD/XDC first with `canopener eds convert FILE --to eds`"
    } else {
        "; run `canopener eds check` on it for details"
    })]
    NoObjects {
        /// The file (or the name of a description given as a model).
        name: String,
        /// Whether the file starts like XML (an XDD/XDC given where an EDS/DCF is expected).
        looks_like_xml: bool,
        /// The loader's first errors, each on its own line starting with a newline.
        errors: String,
    },
    /// Counting node-IDs up from the first one went past 127.
    #[error("{name}: node-ID {node_id} would be above 127")]
    NodeIdAbove127 {
        /// The description that would get it.
        name: String,
        /// The node-ID it would get.
        node_id: u16,
    },
    /// A node-ID given for one device is not 1 to 127 (or FFh for LSS-unconfigured).
    #[error("{name}: node-ID {node_id} is not 1 to 127 (or 255 for an LSS-unconfigured start)")]
    InvalidNodeId {
        /// The description it was given for.
        name: String,
        /// The node-ID.
        node_id: u8,
    },
    /// Two devices would have the same node-ID.
    #[error(
        "{first} and {second} would both be node {node_id}; two devices on one bus need different node-IDs"
    )]
    NodeIdClash {
        /// The earlier description.
        first: String,
        /// The later one.
        second: String,
        /// The node-ID both would have.
        node_id: u8,
    },
    /// The device side refused the description (see `canopener_device::device::DeviceError`).
    #[error("{name}: cannot build the device: {reason}")]
    Build {
        /// The description.
        name: String,
        /// What the device side said.
        reason: String,
    },
    /// The serial number could not be written to 1018h:04.
    #[error(
        "{name}: cannot set the serial number 1018h:04 to {serial}: {reason}; a serial number needs an \
         identity object with sub-index 4 (UNSIGNED32)"
    )]
    Serial {
        /// The description.
        name: String,
        /// The serial number.
        serial: u32,
        /// What the object dictionary said.
        reason: String,
    },
    /// A state file could not be opened.
    #[error(transparent)]
    StateStore(#[from] StateStoreError),
    /// The bus failed while the devices ran.
    #[error(transparent)]
    Bus(#[from] TransportError),
    /// The simulated bus failed.
    #[error(transparent)]
    Link(#[from] LinkError),
}

//! Which descriptions become which devices: loading EDS/DCF files and giving every device its node-ID.
//!
//! The rules (those of `canopener sim`): what the caller asks for wins over what a file says. A node-ID
//! given for one device wins; else the next of a counter started at the first node-ID the caller gave
//! (N, N+1, ... in order: `--node-id`), whatever the file says; else a DCF's own node-ID (CiA 306-3
//! `[DeviceComissioning] NodeID`); else none: the device starts LSS-unconfigured (node-ID FFh, CiA 305)
//! and waits for an LSS master. Node-IDs above 127 and two devices on one node-ID are refused.
//! [`NodeIdFrom`] records which rule gave the node-ID, for the line a simulation starts with.

use std::path::{Path, PathBuf};

use canopener_device::device::UNCONFIGURED;
use canopener_eds::{Eds, Severity};

use crate::error::SimError;

/// How many loader errors a refused file's message quotes.
const QUOTED_ERRORS: usize = 3;

/// Where a simulated device's object dictionary comes from.
#[derive(Debug, Clone)]
pub enum Description {
    /// An EDS or DCF file, read when the simulation starts.
    File(PathBuf),
    /// A description already loaded, with the name messages call it by.
    Model {
        /// What messages call it (a file name, `IO device`).
        name: String,
        /// The description.
        eds: Box<Eds>,
    },
}

impl Description {
    /// A loaded description that messages call `name`.
    pub fn model(name: impl Into<String>, eds: Eds) -> Description {
        Description::Model {
            name: name.into(),
            eds: Box::new(eds),
        }
    }

    /// What messages call it: the file's path, or the model's name.
    pub fn name(&self) -> String {
        match self {
            Description::File(path) => path.display().to_string(),
            Description::Model { name, .. } => name.clone(),
        }
    }

    /// The description, reading the file if it is one.
    pub fn load(self) -> Result<Eds, SimError> {
        match self {
            Description::File(path) => load(&path),
            Description::Model { name, eds } => {
                if eds.objects.is_empty() {
                    return Err(SimError::NoObjects {
                        name,
                        looks_like_xml: false,
                        errors: String::new(),
                    });
                }
                Ok(*eds)
            }
        }
    }
}

impl From<PathBuf> for Description {
    fn from(path: PathBuf) -> Description {
        Description::File(path)
    }
}

impl From<&PathBuf> for Description {
    fn from(path: &PathBuf) -> Description {
        Description::File(path.clone())
    }
}

impl From<&Path> for Description {
    fn from(path: &Path) -> Description {
        Description::File(path.to_owned())
    }
}

/// A loaded model, called by its `[FileInfo] FileName` in messages (`EDS model` without one).
impl From<&Eds> for Description {
    fn from(eds: &Eds) -> Description {
        let name = eds
            .file_info
            .file_name
            .clone()
            .filter(|name| !name.is_empty())
            .unwrap_or_else(|| "EDS model".to_owned());
        Description::model(name, eds.clone())
    }
}

/// Where a device's node-ID comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeIdFrom {
    /// Asked for by the caller (for this device, or counted from the first node-ID given), winning
    /// over the node-ID the file configures, if it has one (`file`).
    Asked {
        /// The file's own `[DeviceComissioning] NodeID`, not used.
        file: Option<u8>,
    },
    /// The file's `[DeviceComissioning] NodeID`.
    File,
    /// None asked for and none in the file: LSS-unconfigured.
    Unconfigured,
    /// The node-ID an LSS master configured and stored in the state directory before.
    Stored,
}

impl NodeIdFrom {
    /// The short name a JSON log gives it: `asked`, `file`, `unconfigured`, `stored`.
    pub fn name(self) -> &'static str {
        match self {
            NodeIdFrom::Asked { .. } => "asked",
            NodeIdFrom::File => "file",
            NodeIdFrom::Unconfigured => "unconfigured",
            NodeIdFrom::Stored => "stored",
        }
    }
}

/// One device to simulate: its description, loaded, and the node-ID it starts with.
#[derive(Debug, Clone)]
pub struct Plan {
    /// What messages call the description (the file's path).
    pub name: String,
    /// The description.
    pub eds: Eds,
    /// The node-ID it starts with; [`UNCONFIGURED`] (FFh) for an LSS-unconfigured start.
    pub node_id: u8,
    /// Which rule gave it.
    pub node_id_from: NodeIdFrom,
}

/// Loads every description and gives each device its node-ID by the [module's rules](self):
/// `fixed` is a node-ID given for that device alone, `first_node_id` the start of the counter for the
/// devices that have none.
pub fn plan(
    descriptions: impl IntoIterator<Item = (Description, Option<u8>)>,
    first_node_id: Option<u8>,
) -> Result<Vec<Plan>, SimError> {
    let mut plans: Vec<Plan> = Vec::new();
    let mut next = first_node_id.map(u16::from);
    for (description, fixed) in descriptions {
        let name = description.name();
        let eds = description.load()?;
        let file = eds.node_id();
        let asked = NodeIdFrom::Asked { file };
        let (node_id, node_id_from) = match (fixed, next, file) {
            (Some(node_id), _, _) => {
                if !(1..=127).contains(&node_id) && node_id != UNCONFIGURED {
                    return Err(SimError::InvalidNodeId { name, node_id });
                }
                (node_id, asked)
            }
            (None, Some(node_id), _) => {
                next = Some(node_id + 1);
                let node_id = u8::try_from(node_id)
                    .ok()
                    .filter(|id| *id <= 127)
                    .ok_or_else(|| SimError::NodeIdAbove127 {
                        name: name.clone(),
                        node_id,
                    })?;
                (node_id, asked)
            }
            (None, None, Some(node_id)) => (node_id, NodeIdFrom::File),
            (None, None, None) => (UNCONFIGURED, NodeIdFrom::Unconfigured),
        };
        if node_id != UNCONFIGURED
            && let Some(other) = plans.iter().find(|p| p.node_id == node_id)
        {
            return Err(SimError::NodeIdClash {
                first: other.name.clone(),
                second: name,
                node_id,
            });
        }
        plans.push(Plan {
            name,
            eds,
            node_id,
            node_id_from,
        });
    }
    Ok(plans)
}

/// Reads an EDS/DCF. A file that cannot be read or describes no objects is refused, quoting the loader's
/// first errors; a usable file with errors runs as well as the device side can take it.
pub fn load(path: &Path) -> Result<Eds, SimError> {
    let bytes = std::fs::read(path).map_err(|source| SimError::Read {
        path: path.to_owned(),
        source,
    })?;
    let loaded = canopener_eds::load(&bytes);
    if loaded.eds.objects.is_empty() {
        let errors: Vec<String> = loaded
            .diagnostics
            .iter()
            .filter(|d| d.severity == Severity::Error)
            .take(QUOTED_ERRORS)
            .map(|d| format!("\n  {}:{d}", path.display()))
            .collect();
        return Err(SimError::NoObjects {
            name: path.display().to_string(),
            looks_like_xml: bytes.trim_ascii_start().starts_with(b"<"),
            errors: errors.concat(),
        });
    }
    Ok(loaded.eds)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn test_data(name: &str) -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../canopener-check/test_data/checks")
            .join(name)
    }

    fn files(paths: &[PathBuf]) -> Vec<(Description, Option<u8>)> {
        paths.iter().map(|path| (Description::from(path), None)).collect()
    }

    #[test]
    fn node_ids_come_from_the_first_one_in_order_and_must_differ() {
        let eds = test_data("base.eds");
        let plans = plan(files(&[eds.clone(), eds.clone(), eds.clone()]), Some(10)).unwrap();
        let ids: Vec<u8> = plans.iter().map(|p| p.node_id).collect();
        assert_eq!(ids, [10, 11, 12]);

        // Without a node-ID the devices start LSS-unconfigured; any number of them may.
        let none = plan(files(&[eds.clone(), eds.clone()]), None).unwrap();
        let ids: Vec<u8> = none.iter().map(|p| p.node_id).collect();
        assert_eq!(ids, [UNCONFIGURED, UNCONFIGURED]);

        let high = plan(files(&[eds.clone(), eds]), Some(127)).unwrap_err();
        assert!(
            matches!(high, SimError::NodeIdAbove127 { node_id: 128, .. }),
            "{high:?}"
        );
        assert!(high.to_string().contains("above 127"), "{high}");
    }

    /// Issue 22: `sim FILE --node-id 5` ran node 16 when FILE configured 16. What is asked for wins.
    #[test]
    fn a_node_id_asked_for_wins_over_the_dcf_and_a_clash_is_refused() {
        let dcf = test_data("base.dcf");
        let own = load(&dcf).unwrap().node_id().expect("base.dcf has a node-ID");
        let asked = if own == 100 { 101 } else { 100 };
        let plans = plan(files(&[dcf.clone(), test_data("base.eds")]), Some(asked)).unwrap();
        let got: Vec<(u8, NodeIdFrom)> = plans.iter().map(|p| (p.node_id, p.node_id_from)).collect();
        assert_eq!(
            got,
            [
                (asked, NodeIdFrom::Asked { file: Some(own) }),
                (asked + 1, NodeIdFrom::Asked { file: None })
            ]
        );
        let plans = plan(files(&[dcf.clone(), test_data("base.eds")]), None).unwrap();
        let got: Vec<(u8, NodeIdFrom)> = plans.iter().map(|p| (p.node_id, p.node_id_from)).collect();
        assert_eq!(
            got,
            [(own, NodeIdFrom::File), (UNCONFIGURED, NodeIdFrom::Unconfigured)]
        );
        let clash = plan(
            [
                (Description::from(&dcf), None),
                (Description::from(&test_data("base.eds")), Some(own)),
            ],
            None,
        )
        .unwrap_err();
        assert!(matches!(clash, SimError::NodeIdClash { node_id, .. } if node_id == own));
        assert!(clash.to_string().contains("both be node"), "{clash}");
    }

    #[test]
    fn a_node_id_given_for_one_device_wins_over_the_dcf_and_is_checked() {
        let dcf = test_data("base.dcf");
        let eds = load(&dcf).unwrap();
        let own = eds.node_id().expect("base.dcf has a node-ID");
        let other = if own == 100 { 101 } else { 100 };
        let plans = plan([(Description::from(&eds), Some(other))], None).unwrap();
        assert_eq!(plans[0].node_id, other);
        let unconfigured = plan([(Description::from(&dcf), Some(UNCONFIGURED))], None).unwrap();
        assert_eq!(unconfigured[0].node_id, UNCONFIGURED);
        for bad in [0, 128] {
            let err = plan([(Description::from(&eds), Some(bad))], None).unwrap_err();
            assert!(
                matches!(err, SimError::InvalidNodeId { node_id, .. } if node_id == bad),
                "{err:?}"
            );
        }
    }

    #[test]
    fn files_without_objects_are_refused_naming_the_file() {
        let dir = canopener_testkit::fixture::ScratchDir::new("runtime-plan");
        let junk = dir.join("junk.eds");
        canopener_testkit::fixture::write(&junk, "this is not\x00 an EDS [at all\n").unwrap();
        let err = load(&junk).unwrap_err();
        assert!(
            matches!(
                err,
                SimError::NoObjects {
                    looks_like_xml: false,
                    ..
                }
            ),
            "{err:?}"
        );
        assert!(
            err.to_string().contains("junk.eds is not a usable EDS/DCF"),
            "{err}"
        );
        let xml = dir.join("device.xdd");
        canopener_testkit::fixture::write(&xml, "<?xml version=\"1.0\"?><ISO15745ProfileContainer/>")
            .unwrap();
        assert!(load(&xml).unwrap_err().to_string().contains("eds convert"));
        let missing = load(&dir.join("missing.eds")).unwrap_err();
        assert!(matches!(missing, SimError::Read { .. }), "{missing:?}");
        assert!(missing.to_string().contains("missing.eds"));
        let empty = plan([(Description::model("empty", Eds::default()), Some(5))], None).unwrap_err();
        assert!(
            empty.to_string().starts_with("empty is not a usable EDS/DCF"),
            "{empty}"
        );
    }
}

//! A topology file and the DCFs it names, read from disk: the file side of `canopener-network`.
//!
//! DCFs are looked up relative to the topology file's folder, under the network's (else the
//! system's) `EDSBaseName` first, then beside the topology file
//! ([`canopener_network::check::dcf_candidates`]).

use std::collections::BTreeMap;
use std::io;
use std::path::{Path, PathBuf};
use std::time::Duration;

use canopener_description::Checker;
use canopener_eds::Severity;
use canopener_network::check::{DcfFound, DcfSummary, check, dcf_candidates};
use canopener_network::{Loaded, NetDiagnostic, Topology};

/// Why a system cannot be read or used.
#[derive(Debug, thiserror::Error)]
pub enum SystemError {
    /// The topology file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        #[source]
        source: io::Error,
    },
    /// A device names no DCF, or its DCF is not where the topology says.
    #[error("{topology}: {device} on network {net}: {reason}")]
    Dcf {
        /// The topology file.
        topology: String,
        /// The device (NodeName or vertex id).
        device: String,
        /// The network.
        net: u32,
        /// What is wrong and where it was looked for.
        reason: String,
    },
    /// A DCF was found but could not be made into a simulated device.
    #[error(transparent)]
    Sim(#[from] crate::error::SimError),
    /// The monitor's position names no vertex.
    #[error("--at {0}: no vertex of the topology has this id or NodeName")]
    UnknownVertex(String),
    /// A cut names no cable, or a power-off no supply domain.
    #[error("{0}")]
    UnknownFault(String),
    /// A bus failed.
    #[error(transparent)]
    Link(#[from] canopener_link::link::LinkError),
}

/// A topology file read, with the folder its DCFs are looked up from.
#[derive(Debug, Clone)]
pub struct SystemFiles {
    /// The topology file as given.
    pub path: PathBuf,
    /// What reading it gave.
    pub loaded: Loaded,
    dir: PathBuf,
    text: String,
}

impl SystemFiles {
    /// Reads a nodelist.cpj or Nodelist.graphml. Only a file that cannot be read fails: what is wrong
    /// inside is in [`Loaded::diagnostics`].
    pub fn read(path: &Path) -> Result<SystemFiles, SystemError> {
        let bytes = canopener_files::read(path).map_err(|source| SystemError::Read {
            path: path.to_owned(),
            source,
        })?;
        Ok(SystemFiles::from_bytes(path, &bytes))
    }

    /// A topology given as bytes, its DCFs looked up beside `path`.
    pub fn from_bytes(path: &Path, bytes: &[u8]) -> SystemFiles {
        SystemFiles {
            path: path.to_owned(),
            loaded: canopener_network::load(bytes),
            dir: path.parent().map(Path::to_owned).unwrap_or_default(),
            text: String::from_utf8_lossy(bytes).into_owned(),
        }
    }

    /// The file's text as read (invalid UTF-8 replaced), for showing the lines findings point at.
    pub fn source_text(&self) -> &str {
        &self.text
    }

    /// The system.
    pub fn topology(&self) -> &Topology {
        &self.loaded.topology
    }

    /// Where the DCF `name` of a device on network `net` is, if anywhere.
    pub fn find_dcf(&self, net: u32, name: &str) -> Option<PathBuf> {
        dcf_candidates(self.topology(), net, name)
            .into_iter()
            .map(|candidate| self.dir.join(candidate))
            .find(|path| canopener_files::is_file(path))
    }

    /// The DCF of vertex `vertex` on network `net`, or why there is none.
    pub fn dcf_of(&self, vertex: usize, net: u32) -> Result<PathBuf, SystemError> {
        let Some(v) = self.topology().vertices.get(vertex) else {
            return Err(SystemError::Dcf {
                topology: self.path.display().to_string(),
                device: format!("vertex {vertex}"),
                net,
                reason: "the topology has no such vertex".to_owned(),
            });
        };
        let error = |reason: String| SystemError::Dcf {
            topology: self.path.display().to_string(),
            device: v.label().to_owned(),
            net,
            reason,
        };
        let name = v
            .attachment(net)
            .and_then(|a| a.dcf.as_deref())
            .filter(|d| !d.trim().is_empty())
            .ok_or_else(|| error("no DCF named".to_owned()))?;
        self.find_dcf(net, name).ok_or_else(|| {
            error(format!(
                "DCF {name:?} not found (looked for {})",
                dcf_candidates(self.topology(), net, name).join(", ")
            ))
        })
    }

    /// Every finding of `canopener net check`: the topology's own and, per DCF, whether it exists,
    /// agrees with the topology and passes `checker`.
    pub fn check(&self, checker: &Checker) -> Vec<NetDiagnostic> {
        let mut lookup = |candidates: &[String]| {
            let Some((shown, path)) = candidates
                .iter()
                .map(|c| (c.clone(), self.dir.join(c)))
                .find(|(_, path)| canopener_files::is_file(path))
            else {
                return DcfFound::Missing;
            };
            let Ok(bytes) = canopener_files::read(&path) else {
                return DcfFound::Missing;
            };
            let loaded = canopener_eds::load(&bytes);
            let commissioning = loaded.eds.commissioning.as_ref();
            let report = checker.check(&shown, path.file_name().and_then(|n| n.to_str()), &bytes);
            let errors: Vec<_> = report
                .findings
                .iter()
                .filter(|f| f.diagnostic.severity == Severity::Error)
                .collect();
            DcfFound::Found(DcfSummary {
                path: shown,
                node_id: commissioning.and_then(|c| c.node_id.clone()),
                net_number: commissioning.and_then(|c| c.net_number.clone()),
                errors: errors.len(),
                first_error: errors.first().map(|f| {
                    let d = &f.diagnostic;
                    format!("{}:{}: {} {}", d.span.line, d.span.column, d.code, d.message)
                }),
            })
        };
        check(&self.loaded, &mut lookup)
    }

    /// Producer heartbeat times (1017h: `ParameterValue`, else `DefaultValue`) by (network, vertex),
    /// for every present device whose DCF can be read; zero where the DCF says 0.
    pub fn producer_times(&self) -> BTreeMap<(u32, usize), Duration> {
        let mut times = BTreeMap::new();
        for net in self.topology().network_numbers() {
            for member in self.topology().members(net) {
                let Ok(path) = self.dcf_of(member.index, net) else {
                    continue;
                };
                let Ok(bytes) = canopener_files::read(&path) else {
                    continue;
                };
                let node_id = member.attachment.valid_node_id().unwrap_or(1);
                if let Some(ms) = producer_time_ms(&canopener_eds::load(&bytes).eds, node_id) {
                    times.insert((net, member.index), Duration::from_millis(ms));
                }
            }
        }
        times
    }
}

/// 1017h of a DCF in milliseconds: its `ParameterValue`, else its `DefaultValue`.
pub fn producer_time_ms(eds: &canopener_eds::Eds, node_id: u8) -> Option<u64> {
    let attributes = &eds.object(0x1017)?.attributes;
    let data_type = attributes.data_type().map(|t| eds.resolve_data_type(t));
    [
        attributes.parameter_value.as_deref(),
        attributes.default_value.as_deref(),
    ]
    .into_iter()
    .flatten()
    .find_map(|text| {
        canopener_eds::model::typed(Some(text), data_type)
            .value?
            .resolve(node_id)
    })
    .and_then(|ms| u64::try_from(ms).ok())
}

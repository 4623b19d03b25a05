//! The system model every format reads into: networks, vertices (devices, gateways, junctions,
//! couplers) with their attachments to networks, and cables.
//!
//! One vertex is one physical thing. A device in several networks (a gateway) is one vertex with one
//! [`Attachment`] per network, as in Nodelist.graphml's `NetNumberNx`/`NodeIDNx` keys; a cable belongs
//! to one network (`NetNumber`). nodelist.cpj has no cables and no gateways: read from cpj, every node
//! of every `[Topology]` section is a vertex of its own.

use std::collections::BTreeSet;

use canopener_eds::Span;
use serde::Serialize;

/// Which format a topology was read from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Format {
    /// CiA 306-3 nodelist.cpj.
    Cpj,
    /// Nodelist.graphml.
    Graphml,
}

/// A CANopen system: networks, vertices and cables.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct Topology {
    /// The graph's id (GraphML), if any.
    pub id: Option<String>,
    /// `EDSBaseName`: where the device descriptions are, relative to the topology file.
    pub eds_base_name: Option<String>,
    /// `Background`: a picture of the machine to draw the devices on.
    pub background: Option<String>,
    /// Every network the file names, by number.
    pub networks: Vec<Network>,
    /// Every vertex, in file order.
    pub vertices: Vec<Vertex>,
    /// Every cable, in file order.
    pub cables: Vec<Cable>,
    /// Graph-level data the vocabulary does not know, kept.
    pub extra: Vec<Extra>,
}

/// One CAN network of the system.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct Network {
    /// The network number (GraphML `NetNumberNx`; cpj: the section's number, 1 for `[Topology]`).
    pub number: u32,
    /// `NetName` (cpj) or the `NetworkNameNx` of its devices.
    pub name: Option<String>,
    /// `NetRefd` (cpj).
    pub refd: Option<String>,
    /// The section's own `EDSBaseName` when it differs from the system's (cpj with several sections).
    pub eds_base_name: Option<String>,
    /// cpj keys of the section the vocabulary does not know, kept in order.
    pub extra: Vec<Extra>,
}

/// A datum outside the vocabulary, kept as text.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Extra {
    /// The key's name as written.
    pub name: String,
    /// The value as text (markup as its source text).
    pub value: String,
}

/// What a vertex is, from its `NodeType` (see [`VertexKind::parse`]).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum VertexKind {
    /// A CANopen device (the default for a vertex with a node-ID).
    Device,
    /// A device where a monitor may sit: `master`, `manager` or `monitor`.
    Manager,
    /// A device in two or more networks.
    Gateway,
    /// A passive wiring element without node-ID: `junction`, `connector`, `tpiece`, `terminator`.
    Passive,
    /// An active, powered wiring element without node-ID: `hub`, `repeater`, `coupler`. When it dies or
    /// loses its supply, everything behind it goes silent.
    Active,
}

impl VertexKind {
    /// The kind a `NodeType` value names (case-insensitive), or `None` outside the vocabulary.
    pub fn parse(node_type: &str) -> Option<VertexKind> {
        match node_type.trim().to_ascii_lowercase().as_str() {
            "device" => Some(VertexKind::Device),
            "master" | "manager" | "monitor" => Some(VertexKind::Manager),
            "gateway" => Some(VertexKind::Gateway),
            "junction" | "connector" | "tpiece" | "t-piece" | "terminator" => Some(VertexKind::Passive),
            "hub" | "repeater" | "coupler" => Some(VertexKind::Active),
            _ => None,
        }
    }
}

/// A vertex of the system graph.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct Vertex {
    /// The GraphML node id (cpj: `N<net>_<node-ID>`).
    pub id: String,
    /// `NodeName` (cpj `Node<X>Name`).
    pub name: Option<String>,
    /// `NodeType` as written.
    pub node_type: Option<String>,
    /// `NodeFig`: a picture of the device.
    pub fig: Option<String>,
    /// `X` on the background.
    pub x: Option<f64>,
    /// `Y` on the background.
    pub y: Option<f64>,
    /// `NumOfNets` as written.
    pub num_of_nets: Option<i64>,
    /// The centre another tool drew it at (yEd's `y:Geometry`), for drawings when `X`/`Y` are absent;
    /// never written as `X`/`Y`.
    #[serde(skip)]
    pub drawn_at: Option<(f64, f64)>,
    /// Its attachments to networks, by slot (the x of `NetNumberNx`).
    pub attachments: Vec<Attachment>,
    /// Data the vocabulary does not know, kept.
    pub extra: Vec<Extra>,
    /// Where it is written.
    #[serde(skip)]
    pub span: Span,
}

impl Vertex {
    /// What messages and events call it: `NodeName`, else the id.
    pub fn label(&self) -> &str {
        self.name.as_deref().filter(|n| !n.is_empty()).unwrap_or(&self.id)
    }

    /// Where drawings put it: `X`/`Y`, else where another tool drew it.
    pub fn position(&self) -> Option<(f64, f64)> {
        self.x.zip(self.y).or(self.drawn_at)
    }

    /// What it is: its `NodeType` when in the vocabulary; else a gateway when attached to two or more
    /// networks, a device when it has a node-ID, a passive junction otherwise.
    pub fn kind(&self) -> VertexKind {
        let nets = self.networks().len();
        match self.node_type.as_deref().and_then(VertexKind::parse) {
            Some(VertexKind::Device) if nets >= 2 => VertexKind::Gateway,
            Some(kind) => kind,
            None if nets >= 2 => VertexKind::Gateway,
            None if self.attachments.iter().any(|a| a.node_id.is_some()) => VertexKind::Device,
            None => VertexKind::Passive,
        }
    }

    /// Whether it is a CANopen device (device, manager or gateway) rather than a wiring element.
    pub fn is_device(&self) -> bool {
        matches!(
            self.kind(),
            VertexKind::Device | VertexKind::Manager | VertexKind::Gateway
        )
    }

    /// The networks it is attached to.
    pub fn networks(&self) -> BTreeSet<u32> {
        self.attachments.iter().filter_map(|a| a.net).collect()
    }

    /// Its attachment to network `net`.
    pub fn attachment(&self, net: u32) -> Option<&Attachment> {
        self.attachments.iter().find(|a| a.net == Some(net))
    }

    /// The supply domains feeding it.
    pub fn supply_domains(&self) -> BTreeSet<&str> {
        self.attachments
            .iter()
            .filter_map(|a| a.supply_domain.as_deref())
            .filter(|d| !d.is_empty())
            .collect()
    }
}

/// A vertex's attachment to one network (Nodelist.graphml's `…Nx` keys, or one `<port>`).
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct Attachment {
    /// The x of the `Nx` keys (1-based), or the port's position.
    pub slot: u32,
    /// `NetNumberNx`.
    pub net: Option<u32>,
    /// `NetworkNameNx`.
    pub network_name: Option<String>,
    /// `NodeIDNx`, as written (validity is a check's business).
    pub node_id: Option<i64>,
    /// `NodeDCFNameNx` (cpj `Node<X>DCFName`).
    pub dcf: Option<String>,
    /// `SupplyDomainNx`.
    pub supply_domain: Option<String>,
    /// `SupplyPointNx`.
    pub supply_point: Option<String>,
    /// `NodeRefdNx` (cpj `Node<X>Refd`).
    pub refd: Option<String>,
    /// cpj `Node<X>Present=0x01` (`false` for a node listed as not present); always true in GraphML
    /// unless `NodePresentNx` says otherwise.
    pub present: bool,
    /// Where its first key is written.
    #[serde(skip)]
    pub span: Span,
}

impl Attachment {
    /// The node-ID when it is a valid one (1 to 127).
    pub fn valid_node_id(&self) -> Option<u8> {
        self.node_id
            .and_then(|id| u8::try_from(id).ok())
            .filter(|id| (1..=127).contains(id))
    }
}

/// A cable: an edge of the system graph.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct Cable {
    /// The edge id, if any.
    pub id: Option<String>,
    /// One end (a vertex id).
    pub source: String,
    /// The other end.
    pub target: String,
    /// `NetNumber`.
    pub net: Option<u32>,
    /// `CableName`.
    pub name: Option<String>,
    /// `Length` (metres).
    pub length: Option<f64>,
    /// `LineType` (trunk, drop, …).
    pub line_type: Option<String>,
    /// `LineParams`.
    pub line_params: Option<String>,
    /// Data the vocabulary does not know, kept.
    pub extra: Vec<Extra>,
    /// Where it is written.
    #[serde(skip)]
    pub span: Span,
}

impl Cable {
    /// What diagnoses call it: `CableName`, else the edge id, else `source-target`.
    pub fn label(&self) -> String {
        match (&self.name, &self.id) {
            (Some(name), _) if !name.is_empty() => name.clone(),
            (_, Some(id)) if !id.is_empty() => id.clone(),
            _ => format!("{}-{}", self.source, self.target),
        }
    }
}

/// A device on one network: the vertex and its attachment there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Member<'a> {
    /// The vertex's index in [`Topology::vertices`].
    pub index: usize,
    /// The vertex.
    pub vertex: &'a Vertex,
    /// Its attachment to the network.
    pub attachment: &'a Attachment,
}

impl Topology {
    /// Every network number in use (declared networks, attachments and cables), ascending.
    pub fn network_numbers(&self) -> BTreeSet<u32> {
        let mut numbers: BTreeSet<u32> = self.networks.iter().map(|n| n.number).collect();
        numbers.extend(self.vertices.iter().flat_map(Vertex::networks));
        numbers.extend(self.cables.iter().filter_map(|c| c.net));
        numbers
    }

    /// The network with this number, if declared.
    pub fn network(&self, number: u32) -> Option<&Network> {
        self.networks.iter().find(|n| n.number == number)
    }

    /// The name of network `number`: its declared name, else the first `NetworkNameNx` of a device on it.
    pub fn network_name(&self, number: u32) -> Option<&str> {
        self.network(number).and_then(|n| n.name.as_deref()).or_else(|| {
            self.vertices
                .iter()
                .filter_map(|v| v.attachment(number))
                .find_map(|a| a.network_name.as_deref())
        })
    }

    /// The present devices of network `net` that have a node-ID, in vertex order.
    pub fn members(&self, net: u32) -> Vec<Member<'_>> {
        self.vertices
            .iter()
            .enumerate()
            .filter(|(_, v)| v.is_device())
            .filter_map(|(index, vertex)| {
                let attachment = vertex.attachment(net)?;
                (attachment.present && attachment.node_id.is_some()).then_some(Member {
                    index,
                    vertex,
                    attachment,
                })
            })
            .collect()
    }

    /// The vertex with this id, or else with this `NodeName`.
    pub fn find_vertex(&self, name: &str) -> Option<usize> {
        self.vertices
            .iter()
            .position(|v| v.id == name)
            .or_else(|| self.vertices.iter().position(|v| v.name.as_deref() == Some(name)))
    }

    /// The vertex indices each cable joins, by cable index (`None` when an end is no vertex).
    pub fn cable_ends(&self) -> Vec<Option<(usize, usize)>> {
        let index: std::collections::BTreeMap<&str, usize> = self
            .vertices
            .iter()
            .enumerate()
            .map(|(i, v)| (v.id.as_str(), i))
            .collect();
        self.cables
            .iter()
            .map(|c| Some((*index.get(c.source.as_str())?, *index.get(c.target.as_str())?)))
            .collect()
    }

    /// The cables of network `net`. In a system with one network, cables without `NetNumber` are
    /// on it.
    pub fn cables_of(&self, net: u32) -> Vec<usize> {
        let single = self.network_numbers().len() <= 1;
        self.cables
            .iter()
            .enumerate()
            .filter(|(_, c)| c.net == Some(net) || (single && c.net.is_none()))
            .map(|(index, _)| index)
            .collect()
    }

    /// Every supply domain named, sorted.
    pub fn supply_domains(&self) -> BTreeSet<&str> {
        self.vertices.iter().flat_map(Vertex::supply_domains).collect()
    }

    /// Where a monitor sits when not told: the vertex typed master/manager/monitor, else the device
    /// with the lowest node-ID of the lowest network.
    pub fn default_position(&self) -> Option<usize> {
        self.vertices
            .iter()
            .position(|v| v.node_type.as_deref().and_then(VertexKind::parse) == Some(VertexKind::Manager))
            .or_else(|| self.default_monitor(self.network_numbers().into_iter().next()?))
    }

    /// Where a monitor on network `net` sits by default: the vertex on `net` typed
    /// master/manager/monitor, else the device with the lowest node-ID on `net`.
    pub fn default_monitor(&self, net: u32) -> Option<usize> {
        let members = self.members(net);
        members
            .iter()
            .find(|m| m.vertex.node_type.as_deref().and_then(VertexKind::parse) == Some(VertexKind::Manager))
            .or_else(|| members.iter().min_by_key(|m| m.attachment.node_id))
            .map(|m| m.index)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vertex(id: &str, node_type: Option<&str>, nets: &[(u32, i64)]) -> Vertex {
        Vertex {
            id: id.into(),
            node_type: node_type.map(str::to_owned),
            attachments: nets
                .iter()
                .zip(1..)
                .map(|(&(net, node_id), slot)| Attachment {
                    slot,
                    net: Some(net),
                    node_id: Some(node_id),
                    present: true,
                    ..Attachment::default()
                })
                .collect(),
            ..Vertex::default()
        }
    }

    #[test]
    fn kinds_follow_the_vocabulary_and_the_attachments() {
        assert_eq!(vertex("a", None, &[(1, 5)]).kind(), VertexKind::Device);
        assert_eq!(vertex("a", None, &[(1, 5), (2, 5)]).kind(), VertexKind::Gateway);
        assert_eq!(
            vertex("a", Some("device"), &[(1, 5), (2, 5)]).kind(),
            VertexKind::Gateway
        );
        assert_eq!(
            vertex("a", Some("Master"), &[(1, 5), (2, 5)]).kind(),
            VertexKind::Manager
        );
        assert_eq!(vertex("j", None, &[]).kind(), VertexKind::Passive);
        assert_eq!(vertex("h", Some("HUB"), &[]).kind(), VertexKind::Active);
        assert!(!vertex("h", Some("repeater"), &[]).is_device());
    }

    #[test]
    fn the_default_monitor_is_the_manager_else_the_lowest_node_id() {
        let mut topology = Topology {
            vertices: vec![vertex("a", None, &[(1, 9)]), vertex("b", None, &[(1, 3)])],
            ..Topology::default()
        };
        assert_eq!(topology.default_monitor(1), Some(1));
        topology.vertices.push(vertex("m", Some("monitor"), &[(1, 20)]));
        assert_eq!(topology.default_monitor(1), Some(2));
        assert_eq!(topology.default_monitor(2), None);
    }
}

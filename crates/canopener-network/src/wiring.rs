//! One network's cables as a graph in which every device is a leaf, rooted where the monitor listens;
//! what the monitor hears under a set of faults; and how faults split the bus into segments.
//!
//! The model (`../shared/reference/topology-formats.md` §5.3): the bus runs through *connector*
//! vertices; each device's core is a leaf joined to its connector by an internal edge, so "device dead"
//! and "drop cable cut" are both the cut of a leaf's edge, and a daisy-chained device whose bus passes
//! through its housing keeps the line whole when it dies. Passive vertices (junctions, connectors,
//! T-pieces, terminators) always conduct; active ones (hubs, repeaters, couplers) conduct only while
//! alive and powered. Devices a network's cables do not reach (every device of a cpj, which has no
//! wiring) are joined to the root by wiring canopener cannot see, which no cable fault breaks.

use std::collections::{BTreeMap, BTreeSet, VecDeque};

use crate::model::{Cable, Topology, VertexKind};

/// What is broken: cut cables, dead vertices (devices or active couplers), supply domains off.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Faults {
    /// Cut cables, by index in [`Topology::cables`].
    pub cut: BTreeSet<usize>,
    /// Dead vertices, by index in [`Topology::vertices`].
    pub dead: BTreeSet<usize>,
    /// Supply domains that are off.
    pub unpowered: BTreeSet<String>,
}

impl Faults {
    /// No fault.
    pub fn none() -> Faults {
        Faults::default()
    }

    /// Whether nothing is broken.
    pub fn is_empty(&self) -> bool {
        self.cut.is_empty() && self.dead.is_empty() && self.unpowered.is_empty()
    }
}

/// A device on the network: a leaf of the wiring graph.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Device {
    /// Its vertex in [`Topology::vertices`].
    pub vertex: usize,
    /// Its node-ID on this network.
    pub node_id: u8,
    /// What events call it (`NodeName`, else the vertex id).
    pub name: String,
    /// The supply domain feeding it on this network, if named.
    pub supply: Option<String>,
    /// Whether it is the monitor's own vertex (never reported silent).
    pub is_monitor: bool,
    core: Node,
}

/// A vertex of the wiring graph, as numbered by [`Wiring::add_vertex`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Node(usize);

/// One value per vertex of a wiring graph, made when the graph had as many vertices as it has now or
/// fewer: vertices are only ever added, so a [`Node`] the graph handed out before the table was made
/// has its entry.
#[derive(Debug, Clone)]
struct PerNode<T>(Vec<T>);

impl<T: Clone> PerNode<T> {
    fn filled(value: T, count: usize) -> PerNode<T> {
        PerNode(vec![value; count])
    }
}

impl<T> PerNode<T> {
    #[allow(
        clippy::indexing_slicing,
        reason = "a Node is only made by Wiring::add_vertex, which pushes one entry to every per-vertex vector of the graph, and a per-fault table is sized to the vertex count when made"
    )]
    fn at(&self, node: Node) -> &T {
        &self.0[node.0]
    }

    #[allow(
        clippy::indexing_slicing,
        reason = "a Node is only made by Wiring::add_vertex, which pushes one entry to every per-vertex vector of the graph, and a per-fault table is sized to the vertex count when made"
    )]
    fn at_mut(&mut self, node: Node) -> &mut T {
        &mut self.0[node.0]
    }

    fn push(&mut self, value: T) {
        self.0.push(value);
    }

    fn len(&self) -> usize {
        self.0.len()
    }

    fn iter(&self) -> impl Iterator<Item = (Node, &T)> {
        self.0.iter().enumerate().map(|(n, value)| (Node(n), value))
    }
}

/// One network's wiring (see the [module docs](self)).
#[derive(Debug, Clone)]
pub struct Wiring {
    net: u32,
    /// Per graph vertex: its neighbours, each with the cable between (`None`: a device's internal
    /// edge or wiring the file does not show).
    adjacency: PerNode<Vec<(Node, Option<usize>)>>,
    /// Per edge: its cable.
    edges: Vec<Option<usize>>,
    /// For every graph vertex: the topology vertex it stands for (cores: the device's).
    owner: PerNode<usize>,
    /// Active graph vertices, with their supply domains.
    active: PerNode<Option<BTreeSet<String>>>,
    devices: Vec<Device>,
    root: Node,
    has_cables: bool,
    reachable_without_faults: PerNode<bool>,
}

impl Wiring {
    /// The wiring of network `net`, rooted where a monitor at vertex `at` listens: `at` itself when it
    /// is on `net`, else the vertex of `net` closest to it over the system's cables, else the default
    /// monitor position ([`Topology::default_monitor`]). `None` when the network has no device.
    pub fn new(topology: &Topology, net: u32, at: Option<usize>) -> Option<Wiring> {
        let members = topology.members(net);
        if members.is_empty() {
            return None;
        }
        let mut wiring = Wiring {
            net,
            adjacency: PerNode(Vec::new()),
            edges: Vec::new(),
            owner: PerNode(Vec::new()),
            active: PerNode(Vec::new()),
            devices: Vec::new(),
            root: Node(0),
            has_cables: false,
            reachable_without_faults: PerNode(Vec::new()),
        };
        // One graph vertex (the connector) per topology vertex that is on this network.
        let cables: Vec<(usize, &Cable)> = topology
            .cables_of(net)
            .into_iter()
            .filter_map(|index| Some((index, topology.cables.get(index)?)))
            .collect();
        let mut on_net: BTreeSet<usize> = members.iter().map(|m| m.index).collect();
        for (_, cable) in &cables {
            for end in [&cable.source, &cable.target] {
                if let Some(index) = topology.vertices.iter().position(|v| &v.id == end) {
                    on_net.insert(index);
                }
            }
        }
        let mut connector: BTreeMap<usize, Node> = BTreeMap::new();
        for &index in &on_net {
            let Some(vertex) = topology.vertices.get(index) else {
                continue;
            };
            let active = (vertex.kind() == VertexKind::Active).then(|| {
                vertex
                    .supply_domains()
                    .into_iter()
                    .map(str::to_owned)
                    .collect::<BTreeSet<String>>()
            });
            connector.insert(index, wiring.add_vertex(index, active));
        }
        for &(cable, c) in &cables {
            let ends = (
                topology.vertices.iter().position(|v| v.id == c.source),
                topology.vertices.iter().position(|v| v.id == c.target),
            );
            // Both ends were put on the network above, so both have a connector.
            if let (Some(a), Some(b)) = ends
                && a != b
                && let (Some(&a), Some(&b)) = (connector.get(&a), connector.get(&b))
            {
                wiring.add_edge(a, b, Some(cable));
                wiring.has_cables = true;
            }
        }
        let root_vertex = at
            .filter(|at| on_net.contains(at))
            .or_else(|| at.and_then(|at| nearest_on(topology, at, &on_net)))
            .or_else(|| topology.default_monitor(net))?;
        wiring.root = connector.get(&root_vertex).copied()?;
        for member in &members {
            // Every member was put on the network above, so it has a connector.
            let (Some(node_id), Some(&connected)) =
                (member.attachment.valid_node_id(), connector.get(&member.index))
            else {
                continue;
            };
            let core = wiring.add_vertex(member.index, None);
            wiring.add_edge(connected, core, None);
            let supply = member
                .attachment
                .supply_domain
                .clone()
                .filter(|d| !d.is_empty())
                .or_else(|| {
                    member
                        .vertex
                        .supply_domains()
                        .into_iter()
                        .next()
                        .map(str::to_owned)
                });
            wiring.devices.push(Device {
                vertex: member.index,
                node_id,
                name: member.vertex.label().to_owned(),
                supply,
                is_monitor: member.index == root_vertex && at.is_none_or(|at| at == root_vertex),
                core,
            });
        }
        // Devices the cables do not reach hang on wiring the file does not show.
        let reach = wiring.reach(&Faults::none());
        let unreached: Vec<Node> = wiring
            .devices
            .iter()
            .filter(|d| !reach.at(d.core))
            .filter_map(|d| connector.get(&d.vertex).copied())
            .collect();
        for node in unreached {
            if !wiring.reach(&Faults::none()).at(node) {
                wiring.add_edge(wiring.root, node, None);
            }
        }
        wiring.reachable_without_faults = wiring.reach(&Faults::none());
        Some(wiring)
    }

    /// The network number.
    pub fn net(&self) -> u32 {
        self.net
    }

    /// The devices, in vertex order.
    pub fn devices(&self) -> &[Device] {
        &self.devices
    }

    /// The topology vertex where the monitor listens.
    pub fn root_vertex(&self) -> usize {
        *self.owner.at(self.root)
    }

    /// Whether the network has cables (a cpj has none: only device faults can be told then).
    pub fn has_cables(&self) -> bool {
        self.has_cables
    }

    /// The cables of this network, by index in [`Topology::cables`].
    pub fn cables(&self) -> BTreeSet<usize> {
        self.edges.iter().filter_map(|&cable| cable).collect()
    }

    /// The active couplers of this network, by vertex.
    pub fn active_vertices(&self) -> Vec<usize> {
        self.active
            .iter()
            .filter(|(_, active)| active.is_some())
            .map(|(n, _)| *self.owner.at(n))
            .collect()
    }

    /// Whether a device is off under `faults` (dead, or its supply off).
    pub fn is_off(&self, device: &Device, faults: &Faults) -> bool {
        faults.dead.contains(&device.vertex)
            || device
                .supply
                .as_ref()
                .is_some_and(|d| faults.unpowered.contains(d))
    }

    /// The devices (indices into [`Wiring::devices`]) the monitor cannot hear under `faults`: those that
    /// are off and those the faults cut off from the monitor. Never the monitor's own device.
    pub fn silent_under(&self, faults: &Faults) -> BTreeSet<usize> {
        let reach = self.reach(faults);
        self.devices
            .iter()
            .enumerate()
            .filter(|(_, d)| !d.is_monitor)
            .filter(|(_, d)| {
                self.is_off(d, faults) || (*self.reachable_without_faults.at(d.core) && !reach.at(d.core))
            })
            .map(|(index, _)| index)
            .collect()
    }

    /// How `faults` split the bus: per device (indices into [`Wiring::devices`]) the segment it is on,
    /// `None` when it is off; and the segment where the monitor listens. Devices on one segment hear
    /// each other; segments do not hear each other.
    pub fn partition(&self, faults: &Faults) -> Partition {
        let blocked = self.blocked(faults);
        let mut segment: PerNode<Option<usize>> = PerNode::filled(None, self.owner.len());
        let mut next = 0;
        for (start, _) in self.owner.iter() {
            if segment.at(start).is_some() || *blocked.at(start) {
                continue;
            }
            let mut queue = VecDeque::from([start]);
            *segment.at_mut(start) = Some(next);
            while let Some(at) = queue.pop_front() {
                for &(to, cable) in self.adjacency.at(at) {
                    if !is_cut(cable, faults) && !blocked.at(to) && segment.at(to).is_none() {
                        *segment.at_mut(to) = Some(next);
                        queue.push_back(to);
                    }
                }
            }
            next += 1;
        }
        let devices = self
            .devices
            .iter()
            .map(|d| (!self.is_off(d, faults)).then_some(*segment.at(d.core)).flatten())
            .collect();
        let root = *segment.at(self.root);
        Partition { devices, root }
    }

    fn add_vertex(&mut self, owner: usize, active: Option<BTreeSet<String>>) -> Node {
        self.adjacency.push(Vec::new());
        self.owner.push(owner);
        self.active.push(active);
        Node(self.owner.len() - 1)
    }

    fn add_edge(&mut self, a: Node, b: Node, cable: Option<usize>) {
        self.edges.push(cable);
        self.adjacency.at_mut(a).push((b, cable));
        self.adjacency.at_mut(b).push((a, cable));
    }

    /// Which graph vertices `faults` switch off.
    fn blocked(&self, faults: &Faults) -> PerNode<bool> {
        let mut blocked = PerNode::filled(false, self.owner.len());
        for (node, active) in self.active.iter() {
            if let Some(domains) = active {
                *blocked.at_mut(node) = faults.dead.contains(self.owner.at(node))
                    || domains.iter().any(|d| faults.unpowered.contains(d));
            }
        }
        for device in &self.devices {
            *blocked.at_mut(device.core) = self.is_off(device, faults);
        }
        blocked
    }

    /// Which graph vertices are reachable from the root under `faults`.
    fn reach(&self, faults: &Faults) -> PerNode<bool> {
        let blocked = self.blocked(faults);
        let mut seen = PerNode::filled(false, self.owner.len());
        if *blocked.at(self.root) {
            return seen;
        }
        *seen.at_mut(self.root) = true;
        let mut queue = VecDeque::from([self.root]);
        while let Some(at) = queue.pop_front() {
            for &(to, cable) in self.adjacency.at(at) {
                if !seen.at(to) && !is_cut(cable, faults) && !blocked.at(to) {
                    *seen.at_mut(to) = true;
                    queue.push_back(to);
                }
            }
        }
        seen
    }

    /// The ends of a cable in this graph, for tests of the leaf convention.
    #[cfg(test)]
    fn edge_count(&self) -> usize {
        self.edges.len()
    }
}

/// How faults split a network's bus (see [`Wiring::partition`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Partition {
    /// Per device: its segment, or `None` when it is off.
    pub devices: Vec<Option<usize>>,
    /// The segment where the monitor listens (`None` when its own coupler is off).
    pub root: Option<usize>,
}

/// Whether an edge carrying `cable` is cut under `faults`.
fn is_cut(cable: Option<usize>, faults: &Faults) -> bool {
    cable.is_some_and(|c| faults.cut.contains(&c))
}

/// The vertex of `targets` closest to `from` over all cables of the system (any network).
fn nearest_on(topology: &Topology, from: usize, targets: &BTreeSet<usize>) -> Option<usize> {
    let mut seen = vec![false; topology.vertices.len()];
    let mut queue = VecDeque::from([from]);
    *seen.get_mut(from)? = true;
    while let Some(at) = queue.pop_front() {
        if targets.contains(&at) {
            return Some(at);
        }
        // Only positions in the vertex list are queued.
        let Some(vertex) = topology.vertices.get(at) else {
            continue;
        };
        let id = &vertex.id;
        for cable in &topology.cables {
            let other = if &cable.source == id {
                &cable.target
            } else if &cable.target == id {
                &cable.source
            } else {
                continue;
            };
            if let Some(next) = topology.vertices.iter().position(|v| &v.id == other)
                && let Some(seen) = seen.get_mut(next)
                && !*seen
            {
                *seen = true;
                queue.push_back(next);
            }
        }
    }
    None
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::model::{Attachment, Cable, Vertex};

    /// A system built from a compact description: `devices` as (id, node-ID, supply), passive or active
    /// vertices as (id, NodeType), cables as (name, a, b); everything on network 1.
    pub(crate) fn system(
        devices: &[(&str, i64, Option<&str>)],
        others: &[(&str, &str)],
        cables: &[(&str, &str, &str)],
    ) -> Topology {
        let mut vertices: Vec<Vertex> = devices
            .iter()
            .map(|(id, node_id, supply)| Vertex {
                id: (*id).into(),
                attachments: vec![Attachment {
                    slot: 1,
                    net: Some(1),
                    node_id: Some(*node_id),
                    supply_domain: supply.map(str::to_owned),
                    present: true,
                    ..Attachment::default()
                }],
                ..Vertex::default()
            })
            .collect();
        vertices.extend(others.iter().map(|(id, node_type)| Vertex {
            id: (*id).into(),
            node_type: Some((*node_type).into()),
            ..Vertex::default()
        }));
        Topology {
            vertices,
            cables: cables
                .iter()
                .map(|(name, a, b)| Cable {
                    name: Some((*name).into()),
                    source: (*a).into(),
                    target: (*b).into(),
                    net: Some(1),
                    ..Cable::default()
                })
                .collect(),
            ..Topology::default()
        }
    }

    fn names(wiring: &Wiring, set: &BTreeSet<usize>) -> Vec<String> {
        set.iter().map(|&d| wiring.devices()[d].name.clone()).collect()
    }

    #[test]
    fn a_cut_silences_what_lies_behind_it_and_a_dead_in_line_device_only_itself() {
        let topology = system(
            &[("m", 1, None), ("a", 2, None), ("b", 3, None), ("c", 4, None)],
            &[],
            &[("W1", "m", "a"), ("W2", "a", "b"), ("W3", "b", "c")],
        );
        let wiring = Wiring::new(&topology, 1, Some(0)).unwrap();
        assert_eq!(wiring.edge_count(), 3 + 4);
        let cut = Faults {
            cut: [1].into(),
            ..Faults::none()
        };
        assert_eq!(names(&wiring, &wiring.silent_under(&cut)), ["b", "c"]);
        let dead = Faults {
            dead: [2].into(),
            ..Faults::none()
        };
        assert_eq!(names(&wiring, &wiring.silent_under(&dead)), ["b"]);
        let partition = wiring.partition(&cut);
        assert_eq!(partition.devices[0], partition.root);
        assert_eq!(partition.devices[1], partition.root);
        assert_eq!(
            partition.devices[2], partition.devices[3],
            "b and c still hear each other"
        );
        assert_ne!(partition.devices[2], partition.root);
        assert_eq!(wiring.partition(&dead).devices[2], None);
    }

    #[test]
    fn a_dead_hub_silences_its_spokes_and_a_cpj_device_only_itself() {
        let topology = system(
            &[("m", 1, None), ("a", 2, None), ("b", 3, Some("F2"))],
            &[("hub", "hub")],
            &[("W1", "m", "hub"), ("W2", "hub", "a"), ("W3", "hub", "b")],
        );
        let wiring = Wiring::new(&topology, 1, None).unwrap();
        let hub_dead = Faults {
            dead: [3].into(),
            ..Faults::none()
        };
        assert_eq!(names(&wiring, &wiring.silent_under(&hub_dead)), ["a", "b"]);
        let f2 = Faults {
            unpowered: ["F2".to_owned()].into(),
            ..Faults::none()
        };
        assert_eq!(names(&wiring, &wiring.silent_under(&f2)), ["b"]);

        let cpj = system(&[("m", 1, None), ("a", 2, None)], &[], &[]);
        let wiring = Wiring::new(&cpj, 1, None).unwrap();
        assert!(!wiring.has_cables());
        assert!(wiring.silent_under(&Faults::none()).is_empty());
        let dead = Faults {
            dead: [1].into(),
            ..Faults::none()
        };
        assert_eq!(names(&wiring, &wiring.silent_under(&dead)), ["a"]);
    }
}

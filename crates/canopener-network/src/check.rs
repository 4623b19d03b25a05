//! The checks of `canopener net check`: what a topology says about its networks, devices and cables,
//! and whether the DCFs it names exist and agree with it.
//!
//! Pure: the caller finds and reads the DCF files ([`DcfLookup`]), so the same checks run on files,
//! in a browser or in a test. Every finding points at the topology file (the DCF problems that matter
//! to the topology — missing, other node-ID or network — are findings on the line naming the DCF).

use std::collections::{BTreeMap, BTreeSet};

use crate::codes::{NetCode, NetDiagnostic};
use crate::model::{Format, Topology, VertexKind};
use crate::read::Loaded;

/// What the caller found for one DCF a device names.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum DcfFound {
    /// None of the candidate paths exists.
    Missing,
    /// The file was read and checked.
    Found(DcfSummary),
}

/// What the checks need to know about one DCF.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct DcfSummary {
    /// Where it was found (as shown in messages).
    pub path: String,
    /// `[DeviceComissioning] NodeID`, as written.
    pub node_id: Option<String>,
    /// `[DeviceComissioning] NetNumber`, as written.
    pub net_number: Option<String>,
    /// How many errors `canopener eds check` finds in it.
    pub errors: usize,
    /// The first of them, as `line:column: message`.
    pub first_error: Option<String>,
}

/// Finds a DCF: given the candidate paths (relative to the topology file's folder, best first, see
/// [`dcf_candidates`]), what is there.
pub type DcfLookup<'a> = dyn FnMut(&[String]) -> DcfFound + 'a;

/// Where a DCF named `name` on network `net` may be, relative to the topology file's folder, best
/// first: under the network's (else the system's) `EDSBaseName`, then beside the topology file.
pub fn dcf_candidates(topology: &Topology, net: u32, name: &str) -> Vec<String> {
    let base = topology
        .network(net)
        .and_then(|n| n.eds_base_name.as_deref())
        .or(topology.eds_base_name.as_deref())
        .map(|b| b.trim().trim_end_matches(['/', '\\']))
        .filter(|b| !b.is_empty() && *b != ".");
    let name = name.trim().replace('\\', "/");
    let mut candidates = Vec::new();
    if let Some(base) = base {
        candidates.push(format!("{}/{name}", base.replace('\\', "/")));
    }
    candidates.push(name);
    candidates
}

/// Every finding about a topology read by [`crate::load`]: what reading found, then the checks,
/// ordered by position.
pub fn check(loaded: &Loaded, lookup: &mut DcfLookup<'_>) -> Vec<NetDiagnostic> {
    let mut out = loaded.diagnostics.clone();
    let topology = &loaded.topology;
    ids(topology, &mut out);
    attachments(topology, &mut out);
    node_ids(topology, &mut out);
    cables(topology, &mut out);
    for net in topology.network_numbers() {
        tree(topology, net, &mut out);
    }
    if loaded.format() == Format::Graphml {
        positions(topology, &mut out);
    }
    dcfs(topology, lookup, &mut out);
    out.sort_by_key(|d| (d.span.line, d.span.column));
    out
}

fn ids(topology: &Topology, out: &mut Vec<NetDiagnostic>) {
    let mut seen: BTreeMap<&str, u32> = BTreeMap::new();
    for vertex in &topology.vertices {
        if vertex.id.is_empty() {
            out.push(NetDiagnostic::new(
                NetCode::MissingId,
                vertex.span,
                "a node without an id",
            ));
        } else if let Some(first) = seen.insert(&vertex.id, vertex.span.line) {
            out.push(NetDiagnostic::new(
                NetCode::DuplicateId,
                vertex.span,
                format!(
                    "node id {:?} is used again (first on line {first}); ids must be unique",
                    vertex.id
                ),
            ));
        }
    }
    let mut edge_ids: BTreeMap<&str, u32> = BTreeMap::new();
    for cable in &topology.cables {
        if let Some(id) = cable.id.as_deref().filter(|id| !id.is_empty())
            && let Some(first) = edge_ids.insert(id, cable.span.line)
        {
            out.push(NetDiagnostic::new(
                NetCode::DuplicateId,
                cable.span,
                format!("edge id {id:?} is used again (first on line {first})"),
            ));
        }
        for end in [&cable.source, &cable.target] {
            if end.is_empty() {
                out.push(NetDiagnostic::new(
                    NetCode::MissingId,
                    cable.span,
                    "an edge end without a node id",
                ));
            } else if !seen.contains_key(end.as_str()) {
                out.push(
                    NetDiagnostic::new(
                        NetCode::DanglingEdge,
                        cable.span,
                        format!(
                            "cable {} ends at {end:?}, which is no node of the graph",
                            cable.label()
                        ),
                    )
                    .with_help("add the node or correct the edge's source/target"),
                );
            }
        }
        if !cable.source.is_empty() && cable.source == cable.target {
            out.push(NetDiagnostic::new(
                NetCode::SelfLoop,
                cable.span,
                format!("cable {} joins {:?} to itself", cable.label(), cable.source),
            ));
        }
    }
}

fn attachments(topology: &Topology, out: &mut Vec<NetDiagnostic>) {
    for vertex in &topology.vertices {
        let kind = vertex.kind();
        if let Some(node_type) = vertex.node_type.as_deref()
            && VertexKind::parse(node_type).is_none()
        {
            out.push(
                NetDiagnostic::new(
                    NetCode::UnknownNodeType,
                    vertex.span,
                    format!(
                        "{}: NodeType {node_type:?} is not in canopener's vocabulary",
                        vertex.label()
                    ),
                )
                .with_help(
                    "use device, master, manager, monitor, gateway, junction, connector, tpiece, terminator, \
                     hub, repeater or coupler",
                ),
            );
        }
        let nets = vertex.networks().len();
        if let Some(declared) = vertex.num_of_nets
            && declared != vertex.attachments.len() as i64
        {
            out.push(NetDiagnostic::new(
                NetCode::NumOfNets,
                vertex.span,
                format!(
                    "{}: NumOfNets is {declared} but it has {} network attachment(s)",
                    vertex.label(),
                    vertex.attachments.len()
                ),
            ));
        }
        let typed_gateway = vertex
            .node_type
            .as_deref()
            .map(str::trim)
            .map(str::to_ascii_lowercase);
        if typed_gateway.as_deref() == Some("gateway") && nets < 2 {
            out.push(NetDiagnostic::new(
                NetCode::NodeTypeMismatch,
                vertex.span,
                format!("{} is typed gateway but is in {nets} network(s)", vertex.label()),
            ));
        }
        if matches!(kind, VertexKind::Passive | VertexKind::Active)
            && vertex.attachments.iter().any(|a| a.node_id.is_some())
        {
            out.push(NetDiagnostic::new(
                NetCode::NodeTypeMismatch,
                vertex.span,
                format!("{} is a wiring element but has a node-ID", vertex.label()),
            ));
        }
        for attachment in &vertex.attachments {
            let missing = match (attachment.net, attachment.node_id) {
                (None, _) => Some("NetNumberN"),
                (Some(_), None) if vertex.is_device() => Some("NodeIDN"),
                _ => None,
            };
            if let Some(key) = missing {
                out.push(NetDiagnostic::new(
                    NetCode::IncompleteAttachment,
                    attachment.span,
                    format!(
                        "{}: attachment {} has no {key}{}",
                        vertex.label(),
                        attachment.slot,
                        attachment.slot
                    ),
                ));
            }
        }
    }
}

fn node_ids(topology: &Topology, out: &mut Vec<NetDiagnostic>) {
    let mut seen: BTreeMap<(u32, i64), &str> = BTreeMap::new();
    for vertex in &topology.vertices {
        for attachment in vertex.attachments.iter().filter(|a| a.present) {
            let Some(id) = attachment.node_id else { continue };
            if !(1..=127).contains(&id) {
                out.push(NetDiagnostic::new(
                    NetCode::NodeIdRange,
                    attachment.span,
                    format!(
                        "{}: node-ID {id} is outside 1 to 127 (CiA 301 §7.3.1)",
                        vertex.label()
                    ),
                ));
                continue;
            }
            let Some(net) = attachment.net else { continue };
            if let Some(first) = seen.insert((net, id), vertex.label()) {
                out.push(NetDiagnostic::new(
                    NetCode::DuplicateNodeId,
                    attachment.span,
                    format!(
                        "{} and {first} both have node-ID {id} on network {net}",
                        vertex.label()
                    ),
                ));
            }
            if vertex.is_device() && attachment.dcf.as_deref().is_none_or(|d| d.trim().is_empty()) {
                out.push(
                    NetDiagnostic::new(
                        NetCode::NoDcf,
                        attachment.span,
                        format!(
                            "{} (node-ID {id} on network {net}) names no DCF: canopener cannot check, simulate or \
                             monitor it",
                            vertex.label()
                        ),
                    )
                    .with_help("add NodeDCFNameNx (GraphML) or Node<X>DCFName (cpj)"),
                );
            }
        }
    }
}

fn cables(topology: &Topology, out: &mut Vec<NetDiagnostic>) {
    let several = topology.network_numbers().len() > 1;
    for cable in &topology.cables {
        let Some(net) = cable.net else {
            if several {
                out.push(NetDiagnostic::new(
                    NetCode::CableWithoutNetwork,
                    cable.span,
                    format!(
                        "cable {} has no NetNumber in a system of several networks",
                        cable.label()
                    ),
                ));
            }
            continue;
        };
        for end in [&cable.source, &cable.target] {
            let Some(vertex) = topology.vertices.iter().find(|v| &v.id == end) else {
                continue;
            };
            if !vertex.attachments.is_empty() && vertex.is_device() && vertex.attachment(net).is_none() {
                out.push(NetDiagnostic::new(
                    NetCode::CableNetwork,
                    cable.span,
                    format!(
                        "cable {} is on network {net} but {} is not attached to it",
                        cable.label(),
                        vertex.label()
                    ),
                ));
            }
        }
    }
}

/// A CAN line must be a tree: a ring is an error unless an active coupler (which separates the
/// physical segments) lies on it. Active vertices are split per cable, so only rings of passive
/// elements and devices close.
fn tree(topology: &Topology, net: u32, out: &mut Vec<NetDiagnostic>) {
    let ends = topology.cable_ends();
    let cables = topology.cables_of(net);
    // Union-find over the vertices and, per cable, its two ends at an active vertex; an element
    // without an entry is its own root.
    let mut parent: BTreeMap<usize, usize> = BTreeMap::new();
    fn find(parent: &mut BTreeMap<usize, usize>, mut x: usize) -> usize {
        while let Some(&up) = parent.get(&x).filter(|&&up| up != x) {
            let grand = parent.get(&up).copied().unwrap_or(up);
            parent.insert(x, grand);
            x = grand;
        }
        x
    }
    let mut degree: BTreeMap<usize, usize> = BTreeMap::new();
    let cables = cables
        .iter()
        .filter_map(|&c| Some((topology.cables.get(c)?, *ends.get(c)?)));
    for (n, (cable, ends)) in cables.enumerate() {
        let Some((a, b)) = ends else { continue };
        if a == b {
            continue;
        }
        *degree.entry(a).or_default() += 1;
        *degree.entry(b).or_default() += 1;
        let node = |v: usize, slot: usize| {
            if topology
                .vertices
                .get(v)
                .is_some_and(|v| v.kind() == VertexKind::Active)
            {
                topology.vertices.len() + 2 * n + slot
            } else {
                v
            }
        };
        let (ra, rb) = (find(&mut parent, node(a, 0)), find(&mut parent, node(b, 1)));
        if ra == rb {
            out.push(
                NetDiagnostic::new(
                    NetCode::NotATree,
                    cable.span,
                    format!(
                        "cable {} closes a ring on network {net}: a CAN line must be a tree (no active coupler \
                         splits this ring)",
                        cable.label()
                    ),
                )
                .with_help("remove the cable, or mark the element that separates the segments as NodeType coupler"),
            );
        } else {
            parent.insert(ra, rb);
        }
    }
    if degree.is_empty() {
        return;
    }
    for member in topology.members(net) {
        if !degree.contains_key(&member.index) {
            out.push(NetDiagnostic::new(
                NetCode::Unconnected,
                member.vertex.span,
                format!(
                    "{} is on network {net} but no cable of that network reaches it",
                    member.vertex.label()
                ),
            ));
        }
    }
}

fn positions(topology: &Topology, out: &mut Vec<NetDiagnostic>) {
    for vertex in topology.vertices.iter().filter(|v| v.is_device()) {
        if vertex.position().is_none() {
            out.push(NetDiagnostic::new(
                NetCode::NoPosition,
                vertex.span,
                format!("{} has no X/Y: drawings place it automatically", vertex.label()),
            ));
        }
    }
}

fn dcfs(topology: &Topology, lookup: &mut DcfLookup<'_>, out: &mut Vec<NetDiagnostic>) {
    let mut checked: BTreeSet<(String, Option<u32>, Option<i64>)> = BTreeSet::new();
    for vertex in topology.vertices.iter().filter(|v| v.is_device()) {
        for attachment in vertex.attachments.iter().filter(|a| a.present) {
            let Some(name) = attachment.dcf.as_deref().map(str::trim).filter(|d| !d.is_empty()) else {
                continue;
            };
            let net = attachment.net.unwrap_or(1);
            let candidates = dcf_candidates(topology, net, name);
            // The candidates always end with the name itself.
            let Some(first) = candidates.first() else {
                continue;
            };
            if !checked.insert((first.clone(), attachment.net, attachment.node_id)) {
                continue;
            }
            let summary = match lookup(&candidates) {
                DcfFound::Missing => {
                    out.push(
                        NetDiagnostic::new(
                            NetCode::DcfMissing,
                            attachment.span,
                            format!(
                                "{}: DCF {name:?} not found (looked for {})",
                                vertex.label(),
                                candidates.join(", ")
                            ),
                        )
                        .with_help("put the DCF beside the topology file or under its EDSBaseName"),
                    );
                    continue;
                }
                DcfFound::Found(summary) => summary,
            };
            let number =
                |text: &Option<String>| text.as_deref().and_then(crate::graphml::read::parse_integer);
            if let Some(id) = attachment.node_id
                && let Some(written) = &summary.node_id
                && number(&summary.node_id) != Some(id)
            {
                out.push(NetDiagnostic::new(
                    NetCode::DcfNodeId,
                    attachment.span,
                    format!(
                        "{}: {} says [DeviceComissioning] NodeID={written}, the topology says {id}",
                        vertex.label(),
                        summary.path
                    ),
                ));
            }
            if let Some(net) = attachment.net
                && let Some(written) = &summary.net_number
                && number(&summary.net_number) != Some(i64::from(net))
            {
                out.push(NetDiagnostic::new(
                    NetCode::DcfNetNumber,
                    attachment.span,
                    format!(
                        "{}: {} says [DeviceComissioning] NetNumber={written}, the topology says network {net}",
                        vertex.label(),
                        summary.path
                    ),
                ));
            }
            if summary.errors > 0 {
                out.push(
                    NetDiagnostic::new(
                        NetCode::DcfErrors,
                        attachment.span,
                        format!(
                            "{}: {} has {} error(s) of its own{}",
                            vertex.label(),
                            summary.path,
                            summary.errors,
                            summary
                                .first_error
                                .as_deref()
                                .map(|e| format!(", first at {e}"))
                                .unwrap_or_default()
                        ),
                    )
                    .with_help(format!("run `canopener eds check {}`", summary.path)),
                );
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn codes(text: &str, lookup: &mut DcfLookup<'_>) -> Vec<(&'static str, u32)> {
        check(&crate::load(text.as_bytes()), lookup)
            .iter()
            .map(|d| (d.code.as_str(), d.span.line))
            .collect()
    }

    fn found(node_id: &str) -> DcfFound {
        DcfFound::Found(DcfSummary {
            path: "x.dcf".into(),
            node_id: Some(node_id.into()),
            ..DcfSummary::default()
        })
    }

    const RING: &str = r#"<?xml version="1.0"?>
<graphml xmlns="http://graphml.graphdrawing.org/xmlns">
<key id="id" for="node" attr.name="NodeIDN1" attr.type="int"/>
<key id="net" for="node" attr.name="NetNumberN1" attr.type="long"/>
<key id="dcf" for="node" attr.name="NodeDCFNameN1" attr.type="string"/>
<key id="t" for="node" attr.name="NodeType" attr.type="string"/>
<graph edgedefault="undirected">
<node id="a"><data key="id">1</data><data key="net">1</data><data key="dcf">a.dcf</data></node>
<node id="b"><data key="id">2</data><data key="net">1</data><data key="dcf">b.dcf</data></node>
<node id="c"><data key="id">2</data><data key="net">1</data></node>
<node id="h"><data key="t">TYPE</data></node>
<edge source="a" target="b"/>
<edge source="b" target="h"/>
<edge source="h" target="a"/>
<edge source="a" target="zz"/>
</graph>
</graphml>
"#;

    #[test]
    fn a_passive_ring_duplicates_missing_dcfs_and_dangling_edges_are_found_where_they_are() {
        let mut lookup = |c: &[String]| {
            if c[0] == "a.dcf" {
                found("1")
            } else {
                DcfFound::Missing
            }
        };
        let found = codes(&RING.replace("TYPE", "junction"), &mut lookup);
        assert!(found.contains(&("N031", 10)), "{found:?}");
        assert!(found.contains(&("N044", 10)), "{found:?}");
        assert!(found.contains(&("N040", 9)), "{found:?}");
        assert!(found.contains(&("N036", 14)), "{found:?}");
        assert!(found.contains(&("N021", 15)), "{found:?}");
        assert!(found.contains(&("N050", 8)), "{found:?}");
        assert!(!found.iter().any(|(c, _)| *c == "N041"), "{found:?}");
    }

    #[test]
    fn a_ring_through_an_active_coupler_is_allowed_and_dcf_mismatches_are_errors() {
        let mut lookup = |_: &[String]| found("0x05");
        let found = codes(&RING.replace("TYPE", "coupler"), &mut lookup);
        assert!(!found.iter().any(|(c, _)| *c == "N036"), "{found:?}");
        assert!(found.contains(&("N041", 8)), "{found:?}");
    }

    #[test]
    fn dcfs_are_looked_up_under_the_base_name_first() {
        let topology = Topology {
            eds_base_name: Some("dcf\\".into()),
            ..Topology::default()
        };
        assert_eq!(dcf_candidates(&topology, 1, "a.dcf"), ["dcf/a.dcf", "a.dcf"]);
        assert_eq!(dcf_candidates(&Topology::default(), 1, "a.dcf"), ["a.dcf"]);
    }
}

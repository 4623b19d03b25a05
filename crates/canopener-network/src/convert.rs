//! Conversion between the formats: nodelist.cpj → GraphML loses nothing (canopener's extra keys carry
//! what cpj says besides the proposal's keys); GraphML → cpj keeps every device of every network
//! with its node-ID, name and DCF and names what cpj cannot hold; DOT for Graphviz.

use std::fmt::Write as _;

use crate::graphml::document::{Data, GraphMl};
use crate::model::{Format, Topology};
use crate::read::{Loaded, Source};

/// A target format of `canopener net convert`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    /// Nodelist.graphml.
    Graphml,
    /// nodelist.cpj.
    Cpj,
    /// Graphviz DOT.
    Dot,
}

/// A converted file and what the target format could not hold.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Converted {
    /// The file's text.
    pub text: String,
    /// What was dropped, one phrase each (empty when nothing was).
    pub dropped: Vec<String>,
}

/// Converts a file read by [`crate::load`]. A file converted to its own format is written back as it
/// was read (every byte of a cpj; every element of a GraphML, with the two quirks N011 and N012
/// resolved as they were read).
pub fn convert(loaded: &Loaded, target: Target) -> Converted {
    let text = match (target, &loaded.source) {
        (Target::Cpj, Source::Cpj(document)) => document.text().to_owned(),
        (Target::Graphml, Source::Graphml(document)) => as_read(document).write(),
        (Target::Graphml, Source::Cpj(_)) => crate::graphml::build::document(&loaded.topology).write(),
        (Target::Cpj, Source::Graphml(_)) => crate::cpj::write(&loaded.topology),
        (Target::Dot, _) => dot(&loaded.topology),
    };
    let dropped = match (target, loaded.format()) {
        (Target::Cpj, Format::Graphml) => dropped_by_cpj(&loaded.topology),
        _ => Vec::new(),
    };
    Converted { text, dropped }
}

/// The document as canopener read it: every `<data key>` that matches a declared key only when case
/// is ignored (warning N011, as in the paper's own `EdsBaseName`) points at the declared key, and of
/// repeated data elements (N012) only the first, which is the one read, is kept. Other GraphML
/// readers refuse an undeclared key (networkx) or take the last of repeated values.
fn as_read(document: &GraphMl) -> GraphMl {
    let mut document = document.clone();
    let ids: Vec<String> = document.keys.iter().map(|k| k.id.clone()).collect();
    let resolve = |data: &mut Vec<Data>| {
        for datum in data.iter_mut() {
            if !ids.contains(&datum.key)
                && let Some(id) = ids.iter().find(|id| id.eq_ignore_ascii_case(&datum.key))
            {
                datum.key = id.clone();
            }
        }
        let mut seen = std::collections::BTreeSet::new();
        data.retain(|datum| seen.insert(datum.key.clone()));
    };
    let graph = &mut document.graph;
    resolve(&mut graph.data);
    for node in &mut graph.nodes {
        resolve(&mut node.data);
        for port in &mut node.ports {
            resolve(&mut port.data);
        }
    }
    for edge in &mut graph.edges {
        resolve(&mut edge.data);
    }
    document
}

/// What nodelist.cpj cannot hold of a topology.
pub fn dropped_by_cpj(topology: &Topology) -> Vec<String> {
    let mut dropped = Vec::new();
    let mut count = |what: &str, n: usize| {
        if n > 0 {
            dropped.push(format!("{n} {what}"));
        }
    };
    count("cable(s) (cpj has no wiring)", topology.cables.len());
    count(
        "wiring element(s) without node-ID (junctions, hubs, couplers)",
        topology.vertices.iter().filter(|v| !v.is_device()).count(),
    );
    count(
        "position(s) X/Y",
        topology
            .vertices
            .iter()
            .filter(|v| v.x.is_some() || v.y.is_some())
            .count(),
    );
    count(
        "NodeType value(s)",
        topology.vertices.iter().filter(|v| v.node_type.is_some()).count(),
    );
    count(
        "NodeFig picture(s)",
        topology.vertices.iter().filter(|v| v.fig.is_some()).count(),
    );
    count(
        "supply domain/point value(s)",
        topology
            .vertices
            .iter()
            .flat_map(|v| &v.attachments)
            .filter(|a| a.supply_domain.is_some() || a.supply_point.is_some())
            .count(),
    );
    count(
        "gateway(s) (written as one node per network)",
        topology
            .vertices
            .iter()
            .filter(|v| v.is_device() && v.networks().len() > 1)
            .count(),
    );
    count(
        "unknown node or graph datum/data",
        topology.vertices.iter().map(|v| v.extra.len()).sum::<usize>() + topology.extra.len(),
    );
    if topology.background.is_some() {
        dropped.push("the Background picture".to_owned());
    }
    dropped
}

/// The topology as an undirected Graphviz graph: one cluster per network is not possible for gateways
/// (a node is in one cluster), so networks are edge colours and gateways double circles.
pub fn dot(topology: &Topology) -> String {
    let mut out = String::from("graph canopen {\n  node [shape=box, fontname=\"sans-serif\"];\n");
    for vertex in &topology.vertices {
        let ids: Vec<String> = vertex
            .attachments
            .iter()
            .filter_map(|a| Some(format!("{}:{}", a.net?, a.node_id?)))
            .collect();
        let label = if ids.is_empty() {
            vertex.label().to_owned()
        } else {
            format!("{}\n{}", vertex.label(), ids.join(" "))
        };
        let shape = match vertex.kind() {
            crate::model::VertexKind::Gateway => "doublecircle",
            crate::model::VertexKind::Passive => "point",
            crate::model::VertexKind::Active => "diamond",
            _ => "box",
        };
        let _ = writeln!(
            out,
            "  {} [label={}, shape={shape}];",
            quote(&vertex.id),
            quote(&label)
        );
    }
    for cable in &topology.cables {
        let mut label = cable.name.clone().unwrap_or_default();
        if let Some(length) = cable.length {
            label = format!("{label} {length} m").trim().to_owned();
        }
        let colour = crate::draw::network_colour(cable.net.unwrap_or(1));
        let _ = writeln!(
            out,
            "  {} -- {} [label={}, color=\"{colour}\"];",
            quote(&cable.source),
            quote(&cable.target),
            quote(&label)
        );
    }
    out.push_str("}\n");
    out
}

/// A DOT string literal.
fn quote(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const CPJ: &str = "[Topology]\nNetName=Line\nNodes=0x02\nNode1Present=0x01\nNode1Name=PLC\nNode1DCFName=plc.dcf\n\
                       Node5Present=0x01\nNode5Name=Drive\nNode5DCFName=drive.dcf\nEDSBaseName=dcf\n\n\
                       [Topology2]\nNodes=0x01\nNode3Present=0x01\nNode3DCFName=io.dcf\n";

    fn devices(topology: &Topology) -> Vec<(u32, u8, Option<String>, Option<String>)> {
        let mut out: Vec<_> = topology
            .vertices
            .iter()
            .flat_map(|v| {
                v.attachments.iter().map(|a| {
                    (
                        a.net.unwrap_or(0),
                        a.valid_node_id().unwrap_or(0),
                        v.name.clone(),
                        a.dcf.clone(),
                    )
                })
            })
            .collect();
        out.sort();
        out
    }

    #[test]
    fn cpj_to_graphml_to_cpj_keeps_every_device_node_id_name_and_dcf() {
        let cpj = crate::load(CPJ.as_bytes());
        let graphml = convert(&cpj, Target::Graphml);
        assert!(graphml.dropped.is_empty());
        let back = crate::load(graphml.text.as_bytes());
        assert!(back.diagnostics.is_empty(), "{:?}", back.diagnostics);
        let again = convert(&back, Target::Cpj);
        assert_eq!(again.dropped, Vec::<String>::new());
        let reread = crate::load(again.text.as_bytes());
        assert_eq!(devices(&reread.topology), devices(&cpj.topology));
        assert_eq!(reread.topology.network_name(1), Some("Line"));
        assert_eq!(reread.topology.eds_base_name.as_deref(), Some("dcf"));
    }

    #[test]
    fn graphml_to_cpj_names_the_cables_it_drops_and_dot_quotes_names() {
        let text = r#"<graphml><key id="n" for="node" attr.name="NodeIDN1" attr.type="int"/>
<key id="t" for="node" attr.name="NodeType" attr.type="string"/>
<key id="net" for="node" attr.name="NetNumberN1" attr.type="long"/><graph>
<node id="a&quot;b"><data key="n">1</data><data key="net">1</data></node><node id="j"><data key="t">junction</data></node>
<edge source="a&quot;b" target="j"/></graph></graphml>"#;
        let loaded = crate::load(text.as_bytes());
        let cpj = convert(&loaded, Target::Cpj);
        assert!(
            cpj.dropped.iter().any(|d| d.starts_with("1 cable")),
            "{:?}",
            cpj.dropped
        );
        assert!(
            cpj.dropped.iter().any(|d| d.starts_with("1 wiring element")),
            "{:?}",
            cpj.dropped
        );
        assert!(cpj.text.contains("Node1Present=0x01"), "{}", cpj.text);
        let dot = convert(&loaded, Target::Dot).text;
        assert!(dot.contains(r#""a\"b" -- "j""#), "{dot}");
    }
}

//! From the GraphML layer to the system model: keys resolved (also against the paper's own spelling
//! mistakes), values typed, attachments gathered from `…Nx` keys or `<port>`s.

use std::collections::{BTreeMap, BTreeSet};

use canopener_eds::Span;

use crate::codes::{NetCode, NetDiagnostic};
use crate::graphml::document::{Data, GraphMl, Key};
use crate::model::{Attachment, Cable, Extra, Format, Network, Topology, Vertex};
use crate::vocabulary::{self, ATTACHMENT_KEYS, CPJ_KEY_PREFIX, ValueClass, class_of, split_attachment_key};

/// The model of a GraphML document, with what reading it found.
pub fn topology(doc: &GraphMl, diagnostics: &mut Vec<NetDiagnostic>) -> Topology {
    let keys = Keys::new(doc, diagnostics);
    let graph = &doc.graph;
    let mut topology = Topology {
        id: graph.id.clone(),
        ..Topology::default()
    };
    let mut per_network: BTreeMap<u32, Network> = BTreeMap::new();
    for (name, _, value) in keys.values("graph", &graph.data, &[], diagnostics) {
        match name.as_str() {
            vocabulary::EDS_BASE_NAME => topology.eds_base_name = Some(value),
            vocabulary::BACKGROUND => topology.background = Some(value),
            _ => {
                if !network_datum(&name, &value, &mut per_network) {
                    topology.extra.push(Extra { name, value });
                }
            }
        }
    }
    for node in &graph.nodes {
        let mut vertex = Vertex {
            id: node.id.clone(),
            span: node.span,
            ..Vertex::default()
        };
        let defaults = keys.defaults("node");
        let mut slots: BTreeMap<u32, Attachment> = BTreeMap::new();
        let mut nets_by_default = false;
        for (name, data, value) in keys.values("node", &node.data, &defaults, diagnostics) {
            let span = data.map_or(node.span, |d| d.span);
            match name.as_str() {
                "NodeName" => vertex.name = Some(value),
                "NodeType" => vertex.node_type = Some(value),
                "NodeFig" => vertex.fig = Some(value),
                "X" => vertex.x = real(&name, &value, span, diagnostics),
                "Y" => vertex.y = real(&name, &value, span, diagnostics),
                "NumOfNets" => {
                    nets_by_default = data.is_none();
                    vertex.num_of_nets = integer(&name, &value, span, diagnostics);
                }
                _ => match split_attachment_key(&name) {
                    Some((base, slot)) => {
                        let attachment = slots.entry(slot).or_insert_with(|| Attachment {
                            slot,
                            present: true,
                            span,
                            ..Attachment::default()
                        });
                        attachment_datum(attachment, base, &name, value, span, diagnostics);
                    }
                    None => {
                        vertex.drawn_at = vertex.drawn_at.or_else(|| drawn_at(&value));
                        vertex.extra.push(Extra { name, value });
                    }
                },
            }
        }
        for (position, port) in node.ports.iter().enumerate() {
            let slot = u32::try_from(position + 1).unwrap_or(u32::MAX);
            let mut attachment = Attachment {
                slot,
                present: true,
                span: port.span,
                ..Attachment::default()
            };
            let mut known = false;
            for (name, data, value) in keys.values("port", &port.data, &[], diagnostics) {
                let span = data.map_or(port.span, |d| d.span);
                if ATTACHMENT_KEYS.iter().any(|(k, _)| *k == name) {
                    known = true;
                    let base = ATTACHMENT_KEYS
                        .iter()
                        .find(|(k, _)| *k == name)
                        .map_or("", |(k, _)| k);
                    attachment_datum(&mut attachment, base, &name, value, span, diagnostics);
                }
            }
            if known {
                slots.insert(slot, attachment);
            }
        }
        vertex.attachments = slots.into_values().collect();
        // A `<key>`'s default NumOfNets is the file's common case for the devices on its networks; it
        // says nothing about a junction, T-piece or terminator, which is on no network (issue 22: such
        // a file got N032 on every junction).
        if nets_by_default && vertex.attachments.is_empty() {
            vertex.num_of_nets = None;
        }
        topology.vertices.push(vertex);
    }
    for edge in &graph.edges {
        let mut cable = Cable {
            id: edge.id.clone(),
            source: edge.source.clone(),
            target: edge.target.clone(),
            span: edge.span,
            ..Cable::default()
        };
        let defaults = keys.defaults("edge");
        for (name, data, value) in keys.values("edge", &edge.data, &defaults, diagnostics) {
            let span = data.map_or(edge.span, |d| d.span);
            match name.as_str() {
                "NetNumber" => cable.net = net_number(&name, &value, span, diagnostics),
                "CableName" => cable.name = Some(value),
                "Length" => cable.length = real(&name, &value, span, diagnostics),
                "LineType" => cable.line_type = Some(value),
                "LineParams" => cable.line_params = Some(value),
                // networkx keeps an edge's id as its data `id` and writes it back as such.
                "id" if cable.id.is_none() => cable.id = Some(value),
                _ => cable.extra.push(Extra { name, value }),
            }
        }
        topology.cables.push(cable);
    }
    for number in topology.vertices.iter().flat_map(Vertex::networks) {
        per_network.entry(number).or_insert_with(|| Network {
            number,
            ..Network::default()
        });
    }
    for network in per_network.values_mut() {
        if network.name.is_none() {
            network.name = topology
                .vertices
                .iter()
                .filter_map(|v| v.attachment(network.number))
                .find_map(|a| a.network_name.clone());
        }
    }
    topology.networks = per_network.into_values().collect();
    topology
}

/// The centre of the first yEd `<y:Geometry x y width height>` in a datum's markup.
fn drawn_at(markup: &str) -> Option<(f64, f64)> {
    if !markup.contains("Geometry") {
        return None;
    }
    let wrapped = format!("<r xmlns:y=\"http://www.yworks.com/xml/graphml\">{markup}</r>");
    let document = roxmltree::Document::parse(&wrapped).ok()?;
    let geometry = document
        .descendants()
        .find(|n| n.tag_name().name() == "Geometry")?;
    let number = |name: &str| {
        geometry
            .attribute(name)
            .and_then(|v| v.trim().parse::<f64>().ok())
            .filter(|v| v.is_finite())
    };
    let (x, y) = (number("x")?, number("y")?);
    Some((
        x + number("width").unwrap_or(0.0) / 2.0,
        y + number("height").unwrap_or(0.0) / 2.0,
    ))
}

/// Which format [`topology`] produces.
pub const FORMAT: Format = Format::Graphml;

/// A graph datum canopener writes for a cpj section (`NetName.2`, `Cpj.2.Vendor`); false for others.
fn network_datum(name: &str, value: &str, networks: &mut BTreeMap<u32, Network>) -> bool {
    fn entry<'n>(networks: &'n mut BTreeMap<u32, Network>, number: &str) -> Option<&'n mut Network> {
        let number: u32 = number.parse().ok()?;
        Some(networks.entry(number).or_insert_with(|| Network {
            number,
            ..Network::default()
        }))
    }
    if let Some(rest) = name.strip_prefix(CPJ_KEY_PREFIX) {
        let Some((number, key)) = rest.split_once('.') else {
            return false;
        };
        let Some(network) = entry(networks, number) else {
            return false;
        };
        network.extra.push(Extra {
            name: key.to_owned(),
            value: value.to_owned(),
        });
        return true;
    }
    for (prefix, field) in [("NetName.", 0), ("NetRefd.", 1), ("EDSBaseName.", 2)] {
        if let Some(number) = name.strip_prefix(prefix)
            && let Some(network) = entry(networks, number)
        {
            let slot = match field {
                0 => &mut network.name,
                1 => &mut network.refd,
                _ => &mut network.eds_base_name,
            };
            *slot = Some(value.to_owned());
            return true;
        }
    }
    false
}

fn attachment_datum(
    attachment: &mut Attachment,
    base: &str,
    name: &str,
    value: String,
    span: Span,
    diagnostics: &mut Vec<NetDiagnostic>,
) {
    match base {
        "NetNumber" => attachment.net = net_number(name, &value, span, diagnostics),
        "NetworkName" => attachment.network_name = Some(value),
        "NodeID" => attachment.node_id = integer(name, &value, span, diagnostics),
        "NodeDCFName" => attachment.dcf = Some(value),
        "SupplyDomain" => attachment.supply_domain = Some(value),
        "SupplyPoint" => attachment.supply_point = Some(value),
        "NodeRefd" => attachment.refd = Some(value),
        "NodePresent" => match parse_bool(&value) {
            Some(present) => attachment.present = present,
            None => diagnostics.push(invalid(name, &value, span, "true or false")),
        },
        _ => {}
    }
}

/// The keys of a document, looked up the way the paper's own example needs.
struct Keys<'a> {
    doc: &'a GraphMl,
    by_id: BTreeMap<&'a str, &'a Key>,
}

impl<'a> Keys<'a> {
    fn new(doc: &'a GraphMl, diagnostics: &mut Vec<NetDiagnostic>) -> Keys<'a> {
        let mut by_id: BTreeMap<&str, &Key> = BTreeMap::new();
        for key in &doc.keys {
            if key.id.is_empty() {
                diagnostics.push(NetDiagnostic::new(
                    NetCode::KeyDeclaration,
                    key.span,
                    "a <key> without an id: no <data> can use it",
                ));
                continue;
            }
            if by_id.contains_key(key.id.as_str()) {
                diagnostics.push(
                    NetDiagnostic::new(
                        NetCode::KeyDeclaration,
                        key.span,
                        format!(
                            "the key id `{}` is declared twice; the first declaration is used",
                            key.id
                        ),
                    )
                    .at(None, Some(&key.id)),
                );
                continue;
            }
            by_id.insert(&key.id, key);
            let declared = key.kind.as_deref().map(|t| (t, ValueClass::of_attr_type(t)));
            if let Some((text, None)) = declared {
                diagnostics.push(
                    NetDiagnostic::new(
                        NetCode::KeyDeclaration,
                        key.span,
                        format!(
                            "attr.type `{text}` of key `{}` is not a GraphML type; read as string",
                            key.id
                        ),
                    )
                    .with_help("GraphML types are boolean, int, long, float, double and string"),
                );
            }
            let scopes: Vec<&str> = match key.scope.as_deref() {
                None | Some("all") => vec!["graph", "node", "edge", "port"],
                Some(scope) => vec![scope],
            };
            let expected = scopes.iter().find_map(|scope| class_of(scope, key.name()));
            let declared_class = declared.map_or(Some(ValueClass::Text), |(_, class)| class);
            match (expected, declared_class) {
                (Some(expected), Some(declared)) if !expected.accepts(declared) => {
                    diagnostics.push(
                        NetDiagnostic::new(
                            NetCode::KeyType,
                            key.span,
                            format!(
                                "key `{}` is declared {} but Nodelist.graphml's {} is {}; values are read by \
                                 the proposal's type",
                                key.id,
                                key.kind.as_deref().unwrap_or("string (no attr.type)"),
                                key.name(),
                                expected.attr_type(key.name())
                            ),
                        )
                        .at(None, Some(&key.id)),
                    );
                }
                (None, _) if !is_canopener_key(key.name()) => diagnostics.push(
                    NetDiagnostic::new(
                        NetCode::UnknownKey,
                        key.span,
                        format!(
                            "key `{}` is not part of Nodelist.graphml; kept and written back",
                            key.name()
                        ),
                    )
                    .at(None, Some(&key.id)),
                ),
                _ => {}
            }
        }
        Keys { doc, by_id }
    }

    /// The key a `<data key=…>` refers to: by id, else by id ignoring case (warned), else none (an error).
    fn resolve(&self, data: &Data, diagnostics: &mut Vec<NetDiagnostic>) -> Option<&'a Key> {
        if let Some(key) = self.by_id.get(data.key.as_str()) {
            return Some(key);
        }
        let folded: Vec<&&Key> = self
            .by_id
            .values()
            .filter(|key| key.id.eq_ignore_ascii_case(&data.key))
            .collect();
        if let [key] = folded.as_slice() {
            diagnostics.push(
                NetDiagnostic::new(
                    NetCode::KeyCase,
                    data.span,
                    format!(
                        "data key `{}` matches the declared key `{}` only when letter case is ignored; read as `{}`",
                        data.key, key.id, key.id
                    ),
                )
                .at(None, Some(&data.key))
                .with_help(format!("write key=\"{}\"", key.id)),
            );
            return Some(key);
        }
        diagnostics.push(
            NetDiagnostic::new(
                NetCode::UndeclaredKey,
                data.span,
                format!("no <key> declares `{}`; its value is read by that name", data.key),
            )
            .at(None, Some(&data.key))
            .with_help(format!(
                "declare it: <key id=\"{}\" for=\"…\" attr.name=\"{}\" attr.type=\"string\"/>",
                data.key, data.key
            )),
        );
        None
    }

    /// The keys with a default for `element`, as (name, default).
    fn defaults(&self, element: &str) -> Vec<(&'a Key, String)> {
        self.doc
            .keys
            .iter()
            .filter(|key| {
                key.allows(element)
                    && self
                        .by_id
                        .get(key.id.as_str())
                        .is_some_and(|k| std::ptr::eq(*k, *key))
            })
            .filter_map(|key| key.default.clone().map(|d| (key, d)))
            .collect()
    }

    /// Every datum of one element as (name, data, value): the first of repeated keys (the others
    /// warned), then the defaults of keys the element has no data for. Markup values are kept as
    /// their source text.
    fn values(
        &self,
        element: &str,
        data: &'a [Data],
        defaults: &[(&'a Key, String)],
        diagnostics: &mut Vec<NetDiagnostic>,
    ) -> Vec<(String, Option<&'a Data>, String)> {
        let mut seen: BTreeMap<String, &Data> = BTreeMap::new();
        let mut out = Vec::new();
        let mut used: BTreeSet<&str> = BTreeSet::new();
        for datum in data {
            let key = self.resolve(datum, diagnostics);
            let id = key.map_or(datum.key.as_str(), |k| k.id.as_str());
            let name = key.map_or_else(|| datum.key.clone(), |k| k.name().to_owned());
            if let Some(key) = key
                && element != "port"
                && !key.allows(element)
            {
                diagnostics.push(
                    NetDiagnostic::new(
                        NetCode::KeyScope,
                        datum.span,
                        format!(
                            "key `{}` is declared for={} but used in a <{element}>; read anyway",
                            key.id,
                            key.scope.as_deref().unwrap_or("all")
                        ),
                    )
                    .at(None, Some(&datum.key)),
                );
            }
            let value = match &datum.value {
                crate::graphml::document::DataValue::Text(text) => text.clone(),
                crate::graphml::document::DataValue::Markup(markup) => markup.clone(),
            };
            if let Some(first) = seen.get(id) {
                let first_value = first.value.text().unwrap_or("…");
                let same = datum.value == first.value;
                diagnostics.push(
                    NetDiagnostic::new(
                        NetCode::DuplicateData,
                        datum.span,
                        format!(
                            "`{}` is given again in this <{element}> (first at line {}){}; the first value `{first_value}` is used",
                            datum.key,
                            first.span.line,
                            if same { " with the same value" } else { " with another value" }
                        ),
                    )
                    .at(None, Some(&datum.key))
                    .with_help("remove the repeated <data>"),
                );
                continue;
            }
            seen.insert(id.to_owned(), datum);
            used.insert(key.map_or("", |k| k.id.as_str()));
            out.push((name, Some(datum), value));
        }
        for (key, default) in defaults {
            if !used.contains(key.id.as_str()) {
                out.push((key.name().to_owned(), None, default.clone()));
            }
        }
        out
    }
}

fn is_canopener_key(name: &str) -> bool {
    name.starts_with(CPJ_KEY_PREFIX)
        || vocabulary::NETWORK_KEY_PREFIXES.iter().any(|prefix| {
            name.strip_prefix(prefix)
                .is_some_and(|n| n.parse::<u32>().is_ok())
        })
}

fn parse_bool(text: &str) -> Option<bool> {
    match text.trim().to_ascii_lowercase().as_str() {
        "true" | "1" => Some(true),
        "false" | "0" => Some(false),
        _ => None,
    }
}

fn invalid(name: &str, value: &str, span: Span, expected: &str) -> NetDiagnostic {
    NetDiagnostic::new(
        NetCode::InvalidValue,
        span,
        format!("`{name}` is `{value}`, which is not {expected}; the value is ignored"),
    )
    .at(None, Some(name))
}

/// An integer written as GraphML writes one (`5`), or as a real without fraction (`5.0`).
pub(crate) fn parse_integer(text: &str) -> Option<i64> {
    let text = text.trim();
    text.parse::<i64>().ok().or_else(|| {
        let real: f64 = text.parse().ok()?;
        (real.is_finite() && real.fract() == 0.0 && real.abs() < 9.0e15).then_some(real as i64)
    })
}

fn integer(name: &str, value: &str, span: Span, diagnostics: &mut Vec<NetDiagnostic>) -> Option<i64> {
    let parsed = parse_integer(value);
    if parsed.is_none() {
        diagnostics.push(invalid(name, value, span, "an integer"));
    }
    parsed
}

fn net_number(name: &str, value: &str, span: Span, diagnostics: &mut Vec<NetDiagnostic>) -> Option<u32> {
    let parsed = parse_integer(value).and_then(|n| u32::try_from(n).ok());
    if parsed.is_none() {
        diagnostics.push(invalid(name, value, span, "a network number (0 or more)"));
    }
    parsed
}

fn real(name: &str, value: &str, span: Span, diagnostics: &mut Vec<NetDiagnostic>) -> Option<f64> {
    let parsed = value.trim().parse::<f64>().ok().filter(|v| v.is_finite());
    if parsed.is_none() {
        diagnostics.push(invalid(name, value, span, "a number"));
    }
    parsed
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> (Topology, Vec<NetDiagnostic>) {
        let (doc, mut diagnostics) = GraphMl::parse(text);
        let topology = topology(&doc, &mut diagnostics);
        (topology, diagnostics)
    }

    #[test]
    fn a_data_key_in_other_case_is_resolved_with_a_warning_and_repeats_keep_the_first() {
        let (topology, diagnostics) = read(
            r#"<graphml xmlns="http://graphml.graphdrawing.org/xmlns">
<key id="EDSBaseName" for="graph" attr.name="EDSBaseName" attr.type="string"/>
<key id="Y" for="node" attr.name="Y" attr.type="double"/>
<graph edgedefault="undirected"><data key="EdsBaseName">EDS</data>
<node id="a"><data key="Y">20</data><data key="Y">30</data></node></graph></graphml>"#,
        );
        assert_eq!(topology.eds_base_name.as_deref(), Some("EDS"));
        assert_eq!(topology.vertices[0].y, Some(20.0));
        let codes: Vec<(NetCode, u32)> = diagnostics.iter().map(|d| (d.code, d.span.line)).collect();
        assert_eq!(codes, [(NetCode::KeyCase, 4), (NetCode::DuplicateData, 5)]);
    }

    #[test]
    fn networkx_key_ids_defaults_and_edge_ids_are_understood() {
        let (topology, diagnostics) = read(
            r#"<graphml xmlns="http://graphml.graphdrawing.org/xmlns">
<key id="d0" for="node" attr.name="NodeIDN1" attr.type="long"/>
<key id="d1" for="node" attr.name="NetNumberN1" attr.type="long"/>
<key id="d2" for="node" attr.name="NumOfNets" attr.type="int"><default>1</default></key>
<key id="d3" for="edge" attr.name="id" attr.type="string"/>
<graph edgedefault="undirected"><node id="a"><data key="d0">5</data><data key="d1">2</data></node>
<node id="b"/><edge source="a" target="b"><data key="d3">W1</data></edge></graph></graphml>"#,
        );
        assert!(
            diagnostics.iter().all(|d| d.code == NetCode::UnknownKey),
            "{diagnostics:?}"
        );
        let a = &topology.vertices[0];
        assert_eq!(
            (a.num_of_nets, a.attachments[0].node_id, a.attachments[0].net),
            (Some(1), Some(5), Some(2))
        );
        assert_eq!(topology.cables[0].id.as_deref(), Some("W1"));
        assert_eq!(
            topology.networks.iter().map(|n| n.number).collect::<Vec<_>>(),
            [2]
        );
    }

    #[test]
    fn a_yed_geometry_gives_the_drawing_position_but_not_x_and_y() {
        let text = r#"<graphml xmlns:y="http://www.yworks.com/xml/graphml">
<key for="node" id="d6" yfiles.type="nodegraphics"/><graph>
<node id="n0"><data key="d6"><y:ShapeNode><y:Geometry height="30.0" width="60.0" x="100.0" y="50.0"/></y:ShapeNode></data></node>
</graph></graphml>"#;
        let topology = crate::load(text.as_bytes()).topology;
        assert_eq!(topology.vertices[0].drawn_at, Some((130.0, 65.0)));
        assert_eq!((topology.vertices[0].x, topology.vertices[0].y), (None, None));
        assert_eq!(topology.vertices[0].position(), Some((130.0, 65.0)));
    }

    #[test]
    fn the_port_variant_gives_one_attachment_per_port() {
        let (topology, diagnostics) = read(
            r#"<graphml xmlns="http://graphml.graphdrawing.org/xmlns">
<key id="NetNumber" for="all" attr.name="NetNumber" attr.type="long"/>
<key id="NodeID" for="all" attr.name="NodeID" attr.type="int"/>
<graph edgedefault="undirected"><node id="gw">
<port id="P01"><data key="NetNumber">1</data><data key="NodeID">4</data></port>
<port id="P02"><data key="NetNumber">7</data><data key="NodeID">six</data></port>
</node></graph></graphml>"#,
        );
        let nets: Vec<(Option<u32>, Option<i64>)> = topology.vertices[0]
            .attachments
            .iter()
            .map(|a| (a.net, a.node_id))
            .collect();
        assert_eq!(nets, [(Some(1), Some(4)), (Some(7), None)]);
        assert_eq!(diagnostics.len(), 1, "{diagnostics:?}");
        assert_eq!(diagnostics[0].code, NetCode::InvalidValue);
        assert_eq!(diagnostics[0].span.line, 6);
    }
}

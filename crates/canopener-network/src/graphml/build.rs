//! From the system model to a GraphML document: the proposal's keys (declared with the id equal to
//! the name, as the paper does), canopener's additions for what cpj says besides, and every datum the
//! vocabulary does not know as a string key.

use std::collections::BTreeMap;

use canopener_eds::Span;

use crate::graphml::document::{Data, DataValue, Edge, Graph, GraphMl, Key, Node};
use crate::model::{Attachment, Topology};
use crate::vocabulary::{ATTACHMENT_KEYS, CPJ_KEY_PREFIX, EDGE_KEYS, GRAPH_KEYS, NODE_KEYS, ValueClass};

/// The GraphML document of a topology.
pub fn document(topology: &Topology) -> GraphMl {
    let mut keys = KeyList::default();
    let mut graph = Graph {
        id: topology.id.clone(),
        edge_default: Some("undirected".to_owned()),
        ..Graph::default()
    };
    let mut graph_data = Vec::new();
    if let Some(base) = &topology.eds_base_name {
        graph_data.push((GRAPH_KEYS[0].0.to_owned(), base.clone()));
    }
    if let Some(background) = &topology.background {
        graph_data.push((GRAPH_KEYS[1].0.to_owned(), background.clone()));
    }
    for network in &topology.networks {
        let n = network.number;
        for (prefix, value) in [
            ("NetName", &network.name),
            ("NetRefd", &network.refd),
            ("EDSBaseName", &network.eds_base_name),
        ] {
            if let Some(value) = value {
                graph_data.push((format!("{prefix}.{n}"), value.clone()));
            }
        }
        for extra in &network.extra {
            graph_data.push((format!("{CPJ_KEY_PREFIX}{n}.{}", extra.name), extra.value.clone()));
        }
    }
    graph_data.extend(topology.extra.iter().map(|e| (e.name.clone(), e.value.clone())));
    graph.data = keys.data("graph", graph_data);

    for vertex in &topology.vertices {
        let mut data: Vec<(String, String)> = Vec::new();
        let mut push = |name: &str, value: Option<String>| {
            if let Some(value) = value {
                data.push((name.to_owned(), value));
            }
        };
        push(NODE_KEYS[0].0, vertex.name.clone());
        push(NODE_KEYS[1].0, vertex.node_type.clone());
        push(NODE_KEYS[2].0, vertex.fig.clone());
        push(NODE_KEYS[3].0, vertex.x.map(|v| v.to_string()));
        push(NODE_KEYS[4].0, vertex.y.map(|v| v.to_string()));
        push(NODE_KEYS[5].0, vertex.num_of_nets.map(|v| v.to_string()));
        for attachment in &vertex.attachments {
            for (base, value) in attachment_values(attachment) {
                data.push((format!("{base}N{}", attachment.slot), value));
            }
        }
        data.extend(vertex.extra.iter().map(|e| (e.name.clone(), e.value.clone())));
        graph.nodes.push(Node {
            id: vertex.id.clone(),
            data: keys.data("node", data),
            ..Node::default()
        });
    }
    for cable in &topology.cables {
        let mut data: Vec<(String, String)> = Vec::new();
        for (name, value) in [
            (EDGE_KEYS[0].0, cable.net.map(|n| n.to_string())),
            (EDGE_KEYS[1].0, cable.name.clone()),
            (EDGE_KEYS[2].0, cable.length.map(|l| l.to_string())),
            (EDGE_KEYS[3].0, cable.line_type.clone()),
            (EDGE_KEYS[4].0, cable.line_params.clone()),
        ] {
            if let Some(value) = value {
                data.push((name.to_owned(), value));
            }
        }
        data.extend(cable.extra.iter().map(|e| (e.name.clone(), e.value.clone())));
        graph.edges.push(Edge {
            id: cable.id.clone(),
            source: cable.source.clone(),
            target: cable.target.clone(),
            data: keys.data("edge", data),
            ..Edge::default()
        });
    }
    GraphMl {
        keys: keys.into_keys(),
        graph,
        ..GraphMl::empty()
    }
}

/// The per-network values of an attachment, by the base name of their key, in the proposal's order.
fn attachment_values(attachment: &Attachment) -> Vec<(&'static str, String)> {
    let values = [
        attachment.net.map(|n| n.to_string()),
        attachment.network_name.clone(),
        attachment.node_id.map(|n| n.to_string()),
        attachment.dcf.clone(),
        attachment.supply_domain.clone(),
        attachment.supply_point.clone(),
        attachment.refd.clone(),
        (!attachment.present).then(|| "false".to_owned()),
    ];
    ATTACHMENT_KEYS
        .iter()
        .zip(values)
        .filter_map(|((base, _), value)| value.map(|v| (*base, v)))
        .collect()
}

/// The keys a document needs, declared once per (scope, name) in the order first used.
#[derive(Default)]
struct KeyList {
    keys: Vec<Key>,
    index: BTreeMap<(String, String), usize>,
}

impl KeyList {
    fn data(&mut self, scope: &str, values: Vec<(String, String)>) -> Vec<Data> {
        values
            .into_iter()
            .map(|(name, value)| Data {
                key: self.declare(scope, &name),
                value: DataValue::Text(value),
                attributes: Vec::new(),
                span: Span::default(),
            })
            .collect()
    }

    /// The id of the key for `name` on `scope`: the name itself, unless another scope already uses
    /// that id for a key of another type (`NetNumber` on nodes of the port variant never happens here,
    /// but an unknown datum may share a name across scopes).
    fn declare(&mut self, scope: &str, name: &str) -> String {
        if let Some(key) = self
            .index
            .get(&(scope.to_owned(), name.to_owned()))
            .and_then(|&at| self.keys.get(at))
        {
            return key.id.clone();
        }
        let class = crate::vocabulary::class_of(scope, name)
            .or_else(|| crate::vocabulary::class_of("node", name).filter(|_| scope == "node"))
            .unwrap_or(ValueClass::Text);
        let mut id = name.to_owned();
        if self.keys.iter().any(|k| k.id == id) {
            id = format!("{scope}.{name}");
        }
        self.keys.push(Key {
            id: id.clone(),
            scope: Some(scope.to_owned()),
            name: Some(name.to_owned()),
            kind: Some(class.attr_type(name).to_owned()),
            ..Key::default()
        });
        self.index
            .insert((scope.to_owned(), name.to_owned()), self.keys.len() - 1);
        id
    }

    fn into_keys(self) -> Vec<Key> {
        let order = |scope: &Option<String>| match scope.as_deref() {
            Some("graph") => 0,
            Some("node") => 1,
            _ => 2,
        };
        let mut keys = self.keys;
        keys.sort_by_key(|k| order(&k.scope));
        keys
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graphml::read::topology;
    use crate::model::{Cable, Vertex};

    #[test]
    fn a_model_written_and_read_back_is_the_same_model() {
        let original = Topology {
            id: Some("system".into()),
            eds_base_name: Some("dcf".into()),
            vertices: vec![
                Vertex {
                    id: "plc".into(),
                    name: Some("Main PLC".into()),
                    x: Some(10.5),
                    y: Some(-3.0),
                    num_of_nets: Some(2),
                    attachments: vec![
                        Attachment {
                            slot: 1,
                            net: Some(1),
                            node_id: Some(1),
                            present: true,
                            ..Attachment::default()
                        },
                        Attachment {
                            slot: 2,
                            net: Some(2),
                            node_id: Some(1),
                            present: false,
                            refd: Some("=A1".into()),
                            ..Attachment::default()
                        },
                    ],
                    ..Vertex::default()
                },
                Vertex {
                    id: "j1".into(),
                    node_type: Some("junction".into()),
                    ..Vertex::default()
                },
            ],
            cables: vec![Cable {
                source: "plc".into(),
                target: "j1".into(),
                net: Some(1),
                name: Some("W101".into()),
                length: Some(4.5),
                ..Cable::default()
            }],
            ..Topology::default()
        };
        let written = document(&original).write();
        let (doc, mut diagnostics) = GraphMl::parse(&written);
        let mut back = topology(&doc, &mut diagnostics);
        assert!(diagnostics.is_empty(), "{diagnostics:?}\n{written}");
        for v in &mut back.vertices {
            v.span = Span::default();
            v.attachments.iter_mut().for_each(|a| a.span = Span::default());
        }
        back.cables.iter_mut().for_each(|c| c.span = Span::default());
        back.networks.clear();
        assert_eq!(back, original, "{written}");
    }
}

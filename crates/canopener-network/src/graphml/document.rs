//! The GraphML layer: every element, attribute and data value of a GraphML file as it was written, so
//! that a file read and written again keeps what other tools put into it (yEd's graphics, Gephi's
//! attributes, keys canopener does not know), and spans for the diagnostics.
//!
//! What is not kept: the XML declaration's details, comments, processing instructions and the white
//! space between elements (the writer indents). Everything else is: unknown elements and the content
//! of `<data>` that is markup (yEd's `<y:ShapeNode>`) are kept as the source text and written back
//! verbatim, with the root's namespace declarations they rely on.

use canopener_eds::Span;
use canopener_eds::lines::LineIndex;
use canopener_eds::xml_text::{XmlPlace, XmlStyle, escape};

use crate::codes::{NetCode, NetDiagnostic};

/// The GraphML namespace.
pub const GRAPHML_NS: &str = "http://graphml.graphdrawing.org/xmlns";
const XSI_NS: &str = "http://www.w3.org/2001/XMLSchema-instance";
const XML_NS: &str = "http://www.w3.org/XML/1998/namespace";
const SCHEMA_LOCATION: &str =
    "http://graphml.graphdrawing.org/xmlns http://graphml.graphdrawing.org/xmlns/1.0/graphml.xsd";

/// Elements a document may hold before the reader gives up (a guard against memory exhaustion by a
/// hostile file; a 127-device system has a few thousand).
pub const MAX_NODES: u32 = 2_000_000;

/// An attribute as written: its qualified name (`xsi:schemaLocation`, `yfiles.type`) and value.
pub type Attribute = (String, String);

/// A GraphML document (see the [module docs](self)).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct GraphMl {
    /// The attributes of `<graphml>`, namespace declarations included, in source order.
    pub root_attributes: Vec<Attribute>,
    /// The `<key>` declarations, in order.
    pub keys: Vec<Key>,
    /// The first `<graph>`.
    pub graph: Graph,
    /// Other children of `<graphml>` (`<desc>`, further graphs), as source text.
    pub extra: Vec<String>,
}

/// A `<key>` declaration.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Key {
    /// `id`, referenced by `<data key=…>`.
    pub id: String,
    /// `for` as written (`node`, `edge`, `graph`, `all`, …); `None` means `all`.
    pub scope: Option<String>,
    /// `attr.name`.
    pub name: Option<String>,
    /// `attr.type` as written.
    pub kind: Option<String>,
    /// The `<default>` value.
    pub default: Option<String>,
    /// Other attributes (`yfiles.type`, …).
    pub attributes: Vec<Attribute>,
    /// Other children (`<desc>`), as source text.
    pub extra: Vec<String>,
    /// Where the declaration is.
    pub span: Span,
}

impl Key {
    /// The name data of this key goes by: `attr.name`, else the id.
    pub fn name(&self) -> &str {
        self.name.as_deref().unwrap_or(&self.id)
    }

    /// Whether the key may be used on this kind of element (`for` absent or `all` allows every kind).
    pub fn allows(&self, element: &str) -> bool {
        match self.scope.as_deref() {
            None | Some("all") => true,
            Some(scope) => scope == element,
        }
    }
}

/// A `<data>` element.
#[derive(Debug, Clone, PartialEq)]
pub struct Data {
    /// The key id as written.
    pub key: String,
    /// The content.
    pub value: DataValue,
    /// Other attributes (`xml:space`).
    pub attributes: Vec<Attribute>,
    /// Where the element is.
    pub span: Span,
}

/// What a `<data>` holds.
#[derive(Debug, Clone, PartialEq)]
pub enum DataValue {
    /// Text (entities resolved).
    Text(String),
    /// Markup, as the source text between the tags.
    Markup(String),
}

impl DataValue {
    /// The text, or `None` for markup.
    pub fn text(&self) -> Option<&str> {
        match self {
            DataValue::Text(text) => Some(text),
            DataValue::Markup(_) => None,
        }
    }
}

/// A `<graph>`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Graph {
    /// `id`.
    pub id: Option<String>,
    /// `edgedefault`.
    pub edge_default: Option<String>,
    /// Other attributes (`parse.*`).
    pub attributes: Vec<Attribute>,
    /// Its data, in order.
    pub data: Vec<Data>,
    /// Its nodes, in order.
    pub nodes: Vec<Node>,
    /// Its edges, in order.
    pub edges: Vec<Edge>,
    /// Other children (`<desc>`, hyperedges), as source text.
    pub extra: Vec<String>,
    /// Where the element is.
    pub span: Span,
}

/// A `<node>`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Node {
    /// `id` (empty when missing).
    pub id: String,
    /// Other attributes.
    pub attributes: Vec<Attribute>,
    /// Its data, in order.
    pub data: Vec<Data>,
    /// Its ports, in order.
    pub ports: Vec<Port>,
    /// Other children (`<desc>`, a nested graph), as source text.
    pub extra: Vec<String>,
    /// Where the element is.
    pub span: Span,
}

/// A `<port>`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Port {
    /// `name` (GraphML), or `id` as the Nodelist.graphml paper writes it.
    pub name: String,
    /// Other attributes.
    pub attributes: Vec<Attribute>,
    /// Its data, in order.
    pub data: Vec<Data>,
    /// Nested ports and other children, as source text.
    pub extra: Vec<String>,
    /// Where the element is.
    pub span: Span,
}

/// An `<edge>`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Edge {
    /// `id`.
    pub id: Option<String>,
    /// `source`.
    pub source: String,
    /// `target`.
    pub target: String,
    /// Other attributes (`directed`, `sourceport`, …).
    pub attributes: Vec<Attribute>,
    /// Its data, in order.
    pub data: Vec<Data>,
    /// Other children, as source text.
    pub extra: Vec<String>,
    /// Where the element is.
    pub span: Span,
}

impl GraphMl {
    /// Parses GraphML text. Never fails: XML that is not well-formed gives an [`NetCode::MalformedXml`]
    /// diagnostic at the parser's position and an empty document.
    pub fn parse(text: &str) -> (GraphMl, Vec<NetDiagnostic>) {
        let mut diagnostics = Vec::new();
        let options = roxmltree::ParsingOptions {
            allow_dtd: false,
            nodes_limit: MAX_NODES,
        };
        let document = match roxmltree::Document::parse_with_options(text, options) {
            Ok(document) => document,
            Err(err) => {
                let pos = err.pos();
                // roxmltree counts only LF as a line break; positions count a lone CR too.
                let (line, column) = LineIndex::new(text).position_of_lf_counted(pos.row, pos.col);
                diagnostics.push(
                    NetDiagnostic::new(
                        NetCode::MalformedXml,
                        Span::new(line, column, 0),
                        format!("the file is not well-formed XML: {err}"),
                    )
                    .with_help("fix the XML at this position; nothing after it was read"),
                );
                return (GraphMl::default(), diagnostics);
            }
        };
        let reader = Reader {
            text,
            lines: LineIndex::new(text),
            document: &document,
        };
        let graphml = reader.read(&mut diagnostics);
        (graphml, diagnostics)
    }

    /// The key declared with this id.
    pub fn key(&self, id: &str) -> Option<&Key> {
        self.keys.iter().find(|key| key.id == id)
    }

    /// Writes the document as indented GraphML (UTF-8, with an XML declaration).
    pub fn write(&self) -> String {
        let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<graphml");
        let mut root = self.root_attributes.clone();
        if !root.iter().any(|(name, _)| name == "xmlns") {
            root.insert(0, ("xmlns".to_owned(), GRAPHML_NS.to_owned()));
        }
        write_attributes(&mut out, &root);
        out.push_str(">\n");
        for key in &self.keys {
            out.push_str("  <key");
            write_attribute(&mut out, "id", &key.id);
            if let Some(scope) = &key.scope {
                write_attribute(&mut out, "for", scope);
            }
            if let Some(name) = &key.name {
                write_attribute(&mut out, "attr.name", name);
            }
            if let Some(kind) = &key.kind {
                write_attribute(&mut out, "attr.type", kind);
            }
            write_attributes(&mut out, &key.attributes);
            if key.default.is_none() && key.extra.is_empty() {
                out.push_str("/>\n");
                continue;
            }
            out.push('>');
            for extra in &key.extra {
                out.push_str(extra);
            }
            if let Some(default) = &key.default {
                out.push_str("<default>");
                out.push_str(&content(default));
                out.push_str("</default>");
            }
            out.push_str("</key>\n");
        }
        let graph = &self.graph;
        out.push_str("  <graph");
        if let Some(id) = &graph.id {
            write_attribute(&mut out, "id", id);
        }
        write_attribute(
            &mut out,
            "edgedefault",
            graph.edge_default.as_deref().unwrap_or("undirected"),
        );
        write_attributes(&mut out, &graph.attributes);
        out.push_str(">\n");
        write_children(&mut out, "    ", &graph.data, &graph.extra);
        for node in &graph.nodes {
            out.push_str("    <node");
            write_attribute(&mut out, "id", &node.id);
            write_attributes(&mut out, &node.attributes);
            if node.data.is_empty() && node.ports.is_empty() && node.extra.is_empty() {
                out.push_str("/>\n");
                continue;
            }
            out.push_str(">\n");
            write_children(&mut out, "      ", &node.data, &node.extra);
            for port in &node.ports {
                write_port(&mut out, "      ", port);
            }
            out.push_str("    </node>\n");
        }
        for edge in &graph.edges {
            out.push_str("    <edge");
            if let Some(id) = &edge.id {
                write_attribute(&mut out, "id", id);
            }
            write_attribute(&mut out, "source", &edge.source);
            write_attribute(&mut out, "target", &edge.target);
            write_attributes(&mut out, &edge.attributes);
            if edge.data.is_empty() && edge.extra.is_empty() {
                out.push_str("/>\n");
                continue;
            }
            out.push_str(">\n");
            write_children(&mut out, "      ", &edge.data, &edge.extra);
            out.push_str("    </edge>\n");
        }
        out.push_str("  </graph>\n");
        for extra in &self.extra {
            out.push_str("  ");
            out.push_str(extra);
            out.push('\n');
        }
        out.push_str("</graphml>\n");
        out
    }

    /// A new document with the standard root attributes and no content.
    pub fn empty() -> GraphMl {
        GraphMl {
            root_attributes: vec![
                ("xmlns".to_owned(), GRAPHML_NS.to_owned()),
                ("xmlns:xsi".to_owned(), XSI_NS.to_owned()),
                ("xsi:schemaLocation".to_owned(), SCHEMA_LOCATION.to_owned()),
            ],
            ..GraphMl::default()
        }
    }
}

fn write_port(out: &mut String, indent: &str, port: &Port) {
    out.push_str(indent);
    out.push_str("<port");
    write_attribute(out, "name", &port.name);
    write_attributes(out, &port.attributes);
    if port.data.is_empty() && port.extra.is_empty() {
        out.push_str("/>\n");
        return;
    }
    out.push_str(">\n");
    let inner = format!("{indent}  ");
    write_children(out, &inner, &port.data, &port.extra);
    out.push_str(indent);
    out.push_str("</port>\n");
}

fn write_children(out: &mut String, indent: &str, data: &[Data], extra: &[String]) {
    for item in data {
        out.push_str(indent);
        out.push_str("<data");
        write_attribute(out, "key", &item.key);
        write_attributes(out, &item.attributes);
        match &item.value {
            DataValue::Text(text) if text.is_empty() => out.push_str("/>\n"),
            DataValue::Text(text) => {
                out.push('>');
                out.push_str(&content(text));
                out.push_str("</data>\n");
            }
            DataValue::Markup(markup) => {
                out.push('>');
                out.push_str(markup);
                out.push_str("</data>\n");
            }
        }
    }
    for item in extra {
        out.push_str(indent);
        out.push_str(item);
        out.push('\n');
    }
}

fn write_attributes(out: &mut String, attributes: &[Attribute]) {
    for (name, value) in attributes {
        write_attribute(out, name, value);
    }
}

fn write_attribute(out: &mut String, name: &str, value: &str) {
    out.push(' ');
    out.push_str(name);
    out.push_str("=\"");
    out.push_str(&escape(value, XmlPlace::Attribute, XmlStyle::DECIMAL));
    out.push('"');
}

fn content(text: &str) -> String {
    escape(text, XmlPlace::Content, XmlStyle::DECIMAL)
}

struct Reader<'a, 'input> {
    text: &'a str,
    lines: LineIndex<'a>,
    document: &'a roxmltree::Document<'input>,
}

impl Reader<'_, '_> {
    fn read(&self, diagnostics: &mut Vec<NetDiagnostic>) -> GraphMl {
        let root = self.document.root_element();
        let mut graphml = GraphMl::default();
        if root.tag_name().name() != "graphml" {
            diagnostics.push(
                NetDiagnostic::new(
                    NetCode::NotGraphml,
                    self.span(root),
                    format!(
                        "the root element is <{}>, not <graphml>",
                        root.tag_name().name()
                    ),
                )
                .with_help("a Nodelist.graphml file starts with <graphml xmlns=\"http://graphml.graphdrawing.org/xmlns\">"),
            );
            return graphml;
        }
        graphml.root_attributes = self.root_attributes(root);
        let mut graphs = 0;
        for child in root.children().filter(roxmltree::Node::is_element) {
            match child.tag_name().name() {
                "key" if is_graphml(child) => graphml.keys.push(self.key(child)),
                "graph" if is_graphml(child) && graphs == 0 => {
                    graphs += 1;
                    graphml.graph = self.graph(child, diagnostics);
                }
                "graph" if is_graphml(child) => {
                    diagnostics.push(NetDiagnostic::new(
                        NetCode::UnsupportedGraphml,
                        self.span(child),
                        "a second <graph> in the document: kept, but only the first one is read",
                    ));
                    graphml.extra.push(self.source(child).to_owned());
                }
                _ => graphml.extra.push(self.source(child).to_owned()),
            }
        }
        if graphs == 0 {
            diagnostics.push(NetDiagnostic::new(
                NetCode::NotGraphml,
                self.span(root),
                "the document has no <graph>",
            ));
        }
        graphml
    }

    fn root_attributes(&self, root: roxmltree::Node<'_, '_>) -> Vec<Attribute> {
        let mut attributes: Vec<Attribute> = root
            .namespaces()
            .filter(|ns| ns.uri() != XML_NS)
            .map(|ns| match ns.name() {
                Some(prefix) => (format!("xmlns:{prefix}"), ns.uri().to_owned()),
                None => ("xmlns".to_owned(), ns.uri().to_owned()),
            })
            .collect();
        attributes.extend(self.attributes(root, &[]));
        attributes
    }

    /// The attributes of `node` other than those in `skip`, with the prefixes they were written with.
    fn attributes(&self, node: roxmltree::Node<'_, '_>, skip: &[&str]) -> Vec<Attribute> {
        node.attributes()
            .filter(|a| a.namespace().is_some() || !skip.contains(&a.name()))
            .map(|a| {
                let name = match a.namespace() {
                    Some(XML_NS) => format!("xml:{}", a.name()),
                    Some(uri) => match node.lookup_prefix(uri) {
                        Some(prefix) => format!("{prefix}:{}", a.name()),
                        None => a.name().to_owned(),
                    },
                    None => a.name().to_owned(),
                };
                (name, a.value().to_owned())
            })
            .collect()
    }

    fn key(&self, node: roxmltree::Node<'_, '_>) -> Key {
        let mut key = Key {
            id: node.attribute("id").unwrap_or_default().to_owned(),
            scope: node.attribute("for").map(str::to_owned),
            name: node.attribute("attr.name").map(str::to_owned),
            kind: node.attribute("attr.type").map(str::to_owned),
            attributes: self.attributes(node, &["id", "for", "attr.name", "attr.type"]),
            span: self.span(node),
            ..Key::default()
        };
        for child in node.children().filter(roxmltree::Node::is_element) {
            if child.tag_name().name() == "default" && is_graphml(child) && key.default.is_none() {
                key.default = Some(child.text().unwrap_or_default().to_owned());
            } else {
                key.extra.push(self.source(child).to_owned());
            }
        }
        key
    }

    fn graph(&self, node: roxmltree::Node<'_, '_>, diagnostics: &mut Vec<NetDiagnostic>) -> Graph {
        let mut graph = Graph {
            id: node.attribute("id").map(str::to_owned),
            edge_default: node.attribute("edgedefault").map(str::to_owned),
            attributes: self.attributes(node, &["id", "edgedefault"]),
            span: self.span(node),
            ..Graph::default()
        };
        for child in node.children().filter(roxmltree::Node::is_element) {
            if !is_graphml(child) {
                graph.extra.push(self.source(child).to_owned());
                continue;
            }
            match child.tag_name().name() {
                "data" => graph.data.push(self.data(child)),
                "node" => graph.nodes.push(self.node(child, diagnostics)),
                "edge" => graph.edges.push(Edge {
                    id: child.attribute("id").map(str::to_owned),
                    source: child.attribute("source").unwrap_or_default().to_owned(),
                    target: child.attribute("target").unwrap_or_default().to_owned(),
                    attributes: self.attributes(child, &["id", "source", "target"]),
                    data: self.data_children(child),
                    extra: self.other_children(child, &["data"]),
                    span: self.span(child),
                }),
                "hyperedge" => {
                    diagnostics.push(NetDiagnostic::new(
                        NetCode::UnsupportedGraphml,
                        self.span(child),
                        "a <hyperedge>: kept, but a cable joins two vertices; model a bus as \
                         junction vertices and edges",
                    ));
                    graph.extra.push(self.source(child).to_owned());
                }
                _ => graph.extra.push(self.source(child).to_owned()),
            }
        }
        graph
    }

    fn node(&self, node: roxmltree::Node<'_, '_>, diagnostics: &mut Vec<NetDiagnostic>) -> Node {
        let mut ports = Vec::new();
        let mut extra = Vec::new();
        for child in node.children().filter(roxmltree::Node::is_element) {
            match child.tag_name().name() {
                "data" if is_graphml(child) => {}
                "port" if is_graphml(child) => ports.push(self.port(child)),
                "graph" if is_graphml(child) => {
                    diagnostics.push(NetDiagnostic::new(
                        NetCode::UnsupportedGraphml,
                        self.span(child),
                        "a nested <graph> (a group node): kept, but its vertices are not part of \
                         the system",
                    ));
                    extra.push(self.source(child).to_owned());
                }
                _ => extra.push(self.source(child).to_owned()),
            }
        }
        Node {
            id: node.attribute("id").unwrap_or_default().to_owned(),
            attributes: self.attributes(node, &["id"]),
            data: self.data_children(node),
            ports,
            extra,
            span: self.span(node),
        }
    }

    fn port(&self, node: roxmltree::Node<'_, '_>) -> Port {
        let (name, skip): (String, &[&str]) = match node.attribute("name") {
            Some(name) => (name.to_owned(), &["name"]),
            None => (node.attribute("id").unwrap_or_default().to_owned(), &["id"]),
        };
        Port {
            name,
            attributes: self.attributes(node, skip),
            data: self.data_children(node),
            extra: self.other_children(node, &["data"]),
            span: self.span(node),
        }
    }

    fn data_children(&self, node: roxmltree::Node<'_, '_>) -> Vec<Data> {
        node.children()
            .filter(|c| c.is_element() && is_graphml(*c) && c.tag_name().name() == "data")
            .map(|c| self.data(c))
            .collect()
    }

    fn other_children(&self, node: roxmltree::Node<'_, '_>, known: &[&str]) -> Vec<String> {
        node.children()
            .filter(|c| c.is_element() && !(is_graphml(*c) && known.contains(&c.tag_name().name())))
            .map(|c| self.source(c).to_owned())
            .collect()
    }

    fn data(&self, node: roxmltree::Node<'_, '_>) -> Data {
        let value = if node.children().any(|c| c.is_element()) {
            let inner = node
                .first_child()
                .zip(node.last_child())
                .map(|(first, last)| first.range().start..last.range().end)
                .and_then(|range| self.text.get(range))
                .unwrap_or_default();
            DataValue::Markup(inner.to_owned())
        } else {
            let text: String = node.children().filter_map(|c| c.text()).collect();
            DataValue::Text(text)
        };
        Data {
            key: node.attribute("key").unwrap_or_default().to_owned(),
            value,
            attributes: self.attributes(node, &["key"]),
            span: self.span(node),
        }
    }

    fn source(&self, node: roxmltree::Node<'_, '_>) -> &str {
        self.text.get(node.range()).unwrap_or_default()
    }

    fn span(&self, node: roxmltree::Node<'_, '_>) -> Span {
        let (line, column) = self.lines.position(node.range().start);
        let name = node.tag_name().name();
        let len = u32::try_from(name.chars().count() + 1).unwrap_or(u32::MAX);
        Span::new(line, column, len)
    }
}

fn is_graphml(node: roxmltree::Node<'_, '_>) -> bool {
    matches!(node.tag_name().namespace(), None | Some(GRAPHML_NS))
}

#[cfg(test)]
mod tests {
    use super::*;

    const YED: &str = r#"<?xml version="1.0" encoding="UTF-8" standalone="no"?>
<graphml xmlns="http://graphml.graphdrawing.org/xmlns" xmlns:y="http://www.yworks.com/xml/graphml">
  <key for="node" id="d6" yfiles.type="nodegraphics"/>
  <key attr.name="NodeName" attr.type="string" for="node" id="d7"><default>x &amp; y</default></key>
  <graph edgedefault="undirected" id="G">
    <node id="n0">
      <data key="d6"><y:ShapeNode><y:Geometry x="1.5" y="2"/></y:ShapeNode></data>
      <data key="d7" xml:space="preserve">PLC &lt;main&gt;</data>
    </node>
    <edge id="e0" source="n0" target="n0" sourceport="a"/>
  </graph>
</graphml>"#;

    #[test]
    fn markup_and_attributes_survive_a_write_and_read() {
        let (first, diagnostics) = GraphMl::parse(YED);
        assert!(diagnostics.is_empty(), "{diagnostics:?}");
        let node = &first.graph.nodes[0];
        assert_eq!(
            node.data[0].value,
            DataValue::Markup(r#"<y:ShapeNode><y:Geometry x="1.5" y="2"/></y:ShapeNode>"#.into())
        );
        assert_eq!(node.data[1].value, DataValue::Text("PLC <main>".into()));
        assert_eq!(
            node.data[1].attributes,
            [("xml:space".to_owned(), "preserve".to_owned())]
        );
        assert_eq!(
            first.keys[0].attributes,
            [("yfiles.type".to_owned(), "nodegraphics".to_owned())]
        );
        assert_eq!(first.keys[1].default.as_deref(), Some("x & y"));
        assert_eq!(
            first.graph.edges[0].attributes,
            [("sourceport".to_owned(), "a".to_owned())]
        );
        let written = first.write();
        let (second, diagnostics) = GraphMl::parse(&written);
        assert!(diagnostics.is_empty(), "{diagnostics:?}\n{written}");
        assert_eq!(strip_spans(first), strip_spans(second));
    }

    #[test]
    fn malformed_xml_is_a_finding_at_the_parser_position() {
        let (doc, diagnostics) = GraphMl::parse("<graphml>\n  <graph>\n  </grph>\n</graphml>");
        assert_eq!(doc, GraphMl::default());
        assert_eq!(diagnostics.len(), 1);
        assert_eq!(diagnostics[0].code, NetCode::MalformedXml);
        assert_eq!((diagnostics[0].span.line, diagnostics[0].span.column), (3, 3));
        // A lone CR ends a line as everywhere (canopener_eds::lines), though the parser counts only LF.
        let (_, diagnostics) = GraphMl::parse("<graphml>\r  <graph>\r  </grph>\n</graphml>");
        assert_eq!((diagnostics[0].span.line, diagnostics[0].span.column), (3, 3));
    }

    #[test]
    fn element_positions_count_a_lone_cr_as_a_line_break() {
        let (doc, _) = GraphMl::parse(&YED.replace('\n', "\r"));
        assert_eq!(
            (doc.graph.nodes[0].span.line, doc.graph.nodes[0].span.column),
            (6, 5)
        );
    }

    #[test]
    fn a_document_type_declaration_is_refused_not_expanded() {
        let bomb = "<?xml version=\"1.0\"?><!DOCTYPE g [<!ENTITY a \"aaaa\">]><graphml/>";
        let (_, diagnostics) = GraphMl::parse(bomb);
        assert_eq!(diagnostics[0].code, NetCode::MalformedXml);
    }

    fn strip_spans(mut doc: GraphMl) -> GraphMl {
        for key in &mut doc.keys {
            key.span = Span::default();
        }
        doc.graph.span = Span::default();
        for node in &mut doc.graph.nodes {
            node.span = Span::default();
            node.data.iter_mut().for_each(|d| d.span = Span::default());
        }
        for edge in &mut doc.graph.edges {
            edge.span = Span::default();
            edge.data.iter_mut().for_each(|d| d.span = Span::default());
        }
        doc
    }
}

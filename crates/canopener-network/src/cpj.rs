//! CiA 306-3 nodelist.cpj: `[Topology]` sections listing each network's nodes and their DCFs.
//!
//! Read through the EDS syntax layer ([`canopener_eds::syntax::Document`]), so every diagnostic has
//! its line and column and the file itself can be written back unchanged. Several networks are read in
//! both layouts implementations use: `[Topology]`, `[Topology2]`, … (EdsDcfNet; the number is the
//! network number) and repeated `[TOPOLOGY]` sections (CANFestival; numbered 1, 2, … in file order).
//! [`write()`] writes `[Topology]` for network 1 and `[Topology<n>]` for the others.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use canopener_eds::syntax::{Document, Section};
use canopener_eds::{Code, Span};

use crate::codes::{NetCode, NetDiagnostic};
use crate::model::{Attachment, Extra, Network, Topology, Vertex};

/// The id a cpj node's vertex gets: `n<network>_<node-ID>`.
pub fn vertex_id(network: u32, node_id: u8) -> String {
    format!("n{network}_{node_id}")
}

/// Reads a nodelist.cpj: the lossless document, the model, and what reading found.
pub fn read(bytes: &[u8]) -> (Document, Topology, Vec<NetDiagnostic>) {
    let (document, syntax) = Document::parse(bytes);
    let mut diagnostics: Vec<NetDiagnostic> = syntax
        .into_iter()
        // Repeated `[TOPOLOGY]` sections are CANFestival's way of listing several networks.
        .filter(|d| d.code != Code::DuplicateSection)
        .map(|d| {
            let message = format!("{} ({})", d.message, d.code);
            let mut mapped = NetDiagnostic::from_parts(NetCode::CpjSyntax, d.severity, d.span, message);
            mapped.help = d.help;
            mapped
        })
        .collect();
    let mut topology = Topology::default();
    let mut plain_sections = 0u32;
    let mut seen_networks: BTreeMap<u32, Span> = BTreeMap::new();
    for section in document.sections() {
        let name = document.section_name(section);
        let header = document.line_span(section.header_line);
        let lower = name.to_ascii_lowercase();
        let number = if lower == "topology" {
            plain_sections += 1;
            Some(plain_sections)
        } else {
            lower
                .strip_prefix("topology")
                .filter(|rest| !rest.is_empty() && rest.bytes().all(|b| b.is_ascii_digit()))
                .and_then(|rest| rest.parse::<u32>().ok())
        };
        let Some(number) = number else {
            diagnostics.push(
                NetDiagnostic::new(
                    NetCode::UnknownSection,
                    header,
                    format!("[{name}] is not a [Topology] section; kept as it is"),
                )
                .at(Some(name), None),
            );
            continue;
        };
        if let Some(first) = seen_networks.get(&number) {
            diagnostics.push(
                NetDiagnostic::new(
                    NetCode::DuplicateData,
                    header,
                    format!(
                        "[{name}] describes network {number} again (first at line {}); the first one is used",
                        first.line
                    ),
                )
                .at(Some(name), None),
            );
            continue;
        }
        seen_networks.insert(number, header);
        read_section(&document, section, number, &mut topology, &mut diagnostics);
    }
    if seen_networks.is_empty() {
        diagnostics.push(
            NetDiagnostic::new(
                NetCode::NoTopologySection,
                Span::new(1, 1, 0),
                "the file has no [Topology] section: it lists no network",
            )
            .with_help("a nodelist.cpj has a [Topology] section with Nodes= and Node<X>Present= entries"),
        );
    }
    // A base path the sections share is the system's; a section's own differing one stays with it.
    let bases: Vec<Option<String>> = topology
        .networks
        .iter()
        .map(|n| n.eds_base_name.clone())
        .collect();
    if let Some(Some(first)) = bases.first() {
        topology.eds_base_name = Some(first.clone());
        for network in &mut topology.networks {
            if network.eds_base_name.as_deref() == Some(first.as_str()) {
                network.eds_base_name = None;
            }
        }
    }
    (document, topology, diagnostics)
}

/// One node of a section while it is read.
#[derive(Default)]
struct Entry {
    present: Option<bool>,
    present_line: Option<usize>,
    name: Option<String>,
    refd: Option<String>,
    dcf: Option<String>,
    first_line: usize,
}

fn read_section(
    document: &Document,
    section: &Section,
    number: u32,
    topology: &mut Topology,
    diagnostics: &mut Vec<NetDiagnostic>,
) {
    let section_name = document.section_name(section);
    let mut network = Network {
        number,
        ..Network::default()
    };
    let mut nodes: BTreeMap<u8, Entry> = BTreeMap::new();
    let mut keys_seen: BTreeMap<String, usize> = BTreeMap::new();
    let mut nodes_entry: Option<(usize, Option<u32>)> = None;
    for &line in document.entries(section) {
        let Some((key, value)) = document.entry(line) else {
            continue;
        };
        let folded = key.to_ascii_lowercase();
        if let Some(first) = keys_seen.get(&folded) {
            diagnostics.push(
                NetDiagnostic::new(
                    NetCode::DuplicateData,
                    document.key_span(line),
                    format!(
                        "`{key}` is given again (first at line {}); the first value is used",
                        first + 1
                    ),
                )
                .at(Some(section_name), Some(key)),
            );
            continue;
        }
        keys_seen.insert(folded.clone(), line);
        match folded.as_str() {
            "nodes" => {
                let parsed = parse_nodes(value);
                if parsed.is_none() {
                    diagnostics.push(
                        NetDiagnostic::new(
                            NetCode::NodesEntry,
                            document.value_span(line),
                            format!("Nodes={value} is not a hexadecimal count 0x00 to 0x7F"),
                        )
                        .at(Some(section_name), Some(key))
                        .with_help("CiA 306-3 codes the number of nodes in hexadecimal, e.g. Nodes=0x03"),
                    );
                }
                nodes_entry = Some((line, parsed));
            }
            "netname" => network.name = Some(value.to_owned()),
            "netrefd" => network.refd = Some(value.to_owned()),
            "edsbasename" => network.eds_base_name = Some(value.to_owned()),
            _ => match node_key(&folded) {
                NodeKey::Node(id, field) => {
                    let entry = nodes.entry(id).or_insert_with(|| Entry {
                        first_line: line,
                        ..Entry::default()
                    });
                    match field {
                        Field::Present => {
                            entry.present_line = Some(line);
                            entry.present = Some(match parse_present(value) {
                                Some(present) => present,
                                None => {
                                    diagnostics.push(
                                        NetDiagnostic::new(
                                            NetCode::PresentValue,
                                            document.value_span(line),
                                            format!(
                                                "{key}={value}: only 0x01 (present) and 0x00 (not present) are \
                                                 defined, other values are reserved; read as not present"
                                            ),
                                        )
                                        .at(Some(section_name), Some(key)),
                                    );
                                    false
                                }
                            });
                        }
                        Field::Name => entry.name = Some(value.to_owned()),
                        Field::Refd => entry.refd = Some(value.to_owned()),
                        Field::DcfName => entry.dcf = Some(value.to_owned()),
                    }
                }
                NodeKey::Malformed => {
                    diagnostics.push(
                        NetDiagnostic::new(
                            NetCode::NodeKey,
                            document.key_span(line),
                            format!(
                                "`{key}` looks like a node key but X is not a node-ID 1 to 127 written in \
                                 decimal without leading zeros; kept as an unknown key"
                            ),
                        )
                        .at(Some(section_name), Some(key)),
                    );
                    network.extra.push(Extra {
                        name: key.to_owned(),
                        value: value.to_owned(),
                    });
                }
                NodeKey::Other => {
                    diagnostics.push(
                        NetDiagnostic::new(
                            NetCode::UnknownKey,
                            document.key_span(line),
                            format!("`{key}` is not a CiA 306-3 [Topology] key; kept"),
                        )
                        .at(Some(section_name), Some(key)),
                    );
                    network.extra.push(Extra {
                        name: key.to_owned(),
                        value: value.to_owned(),
                    });
                }
            },
        }
    }
    let header = document.line_span(section.header_line);
    match nodes_entry {
        None => diagnostics.push(
            NetDiagnostic::new(
                NetCode::NodesEntry,
                header,
                format!("[{section_name}] has no Nodes= entry, which CiA 306-3 makes mandatory"),
            )
            .at(Some(section_name), None)
            .with_help(format!(
                "add Nodes=0x{:02X}",
                nodes.values().filter(|e| e.present.is_some()).count()
            )),
        ),
        Some((line, Some(count))) => {
            let listed = nodes.values().filter(|e| e.present.is_some()).count();
            if usize::try_from(count).ok() != Some(listed) {
                diagnostics.push(
                    NetDiagnostic::new(
                        NetCode::NodesCount,
                        document.value_span(line),
                        format!(
                            "Nodes=0x{count:02X} but the section has {listed} Node<X>Present entries \
                             (counted whether present or not)"
                        ),
                    )
                    .at(Some(section_name), Some("Nodes"))
                    .with_help(format!("write Nodes=0x{listed:02X}")),
                );
            }
        }
        Some((_, None)) => {}
    }
    for (id, entry) in nodes {
        let span = document.line_span(entry.present_line.unwrap_or(entry.first_line));
        if entry.present.is_none() {
            diagnostics.push(
                NetDiagnostic::new(
                    NetCode::NotPresent,
                    document.line_span(entry.first_line),
                    format!(
                        "node {id} has a name, reference or DCF but no Node{id}Present: valid but incomplete, \
                         read as not present"
                    ),
                )
                .at(Some(section_name), None)
                .with_help(format!("add Node{id}Present=0x01 if the node exists")),
            );
        }
        topology.vertices.push(Vertex {
            id: vertex_id(number, id),
            name: entry.name,
            num_of_nets: Some(1),
            attachments: vec![Attachment {
                slot: 1,
                net: Some(number),
                network_name: network.name.clone(),
                node_id: Some(i64::from(id)),
                dcf: entry.dcf,
                refd: entry.refd,
                present: entry.present.unwrap_or(false),
                span,
                ..Attachment::default()
            }],
            span,
            ..Vertex::default()
        });
    }
    topology.networks.push(network);
}

enum Field {
    Present,
    Name,
    Refd,
    DcfName,
}

enum NodeKey {
    Node(u8, Field),
    /// `Node01Name`, `Node200Present`: the shape of a node key with an X that is not a node-ID.
    Malformed,
    Other,
}

/// Classifies a lower-cased key.
fn node_key(folded: &str) -> NodeKey {
    let Some(rest) = folded.strip_prefix("node") else {
        return NodeKey::Other;
    };
    let digits = rest.bytes().take_while(u8::is_ascii_digit).count();
    let (number, field) = rest.split_at(digits);
    let field = match field {
        "present" => Field::Present,
        "name" => Field::Name,
        "refd" => Field::Refd,
        "dcfname" => Field::DcfName,
        _ => return NodeKey::Other,
    };
    if digits == 0 {
        return NodeKey::Other;
    }
    match number.parse::<u8>() {
        Ok(id) if (1..=127).contains(&id) && !number.starts_with('0') => NodeKey::Node(id, field),
        _ => NodeKey::Malformed,
    }
}

fn parse_nodes(value: &str) -> Option<u32> {
    let hex = value
        .trim()
        .strip_prefix("0x")
        .or_else(|| value.trim().strip_prefix("0X"))?;
    u32::from_str_radix(hex, 16).ok().filter(|n| *n <= 0x7F)
}

fn parse_present(value: &str) -> Option<bool> {
    match value.trim().to_ascii_lowercase().as_str() {
        "0x01" | "0x1" | "1" | "true" | "yes" => Some(true),
        "0x00" | "0x0" | "0" | "false" | "no" => Some(false),
        _ => None,
    }
}

/// Writes the topology as nodelist.cpj: `[Topology]` for network 1, `[Topology<n>]` for the others,
/// each with `NetName`, `NetRefd`, `Nodes` (every node listed, present or not), the node keys in
/// node-ID order, `EDSBaseName` and the section's other keys. Vertices without a valid node-ID on a
/// network are not nodes of it.
pub fn write(topology: &Topology) -> String {
    let mut out = String::new();
    for number in topology.network_numbers() {
        let network = topology.network(number);
        let header = if number == 1 {
            "Topology".to_owned()
        } else {
            format!("Topology{number}")
        };
        if !out.is_empty() {
            out.push('\n');
        }
        let _ = writeln!(out, "[{header}]");
        if let Some(name) = network
            .and_then(|n| n.name.as_deref())
            .or_else(|| topology.network_name(number))
        {
            let _ = writeln!(out, "NetName={name}");
        }
        if let Some(refd) = network.and_then(|n| n.refd.as_deref()) {
            let _ = writeln!(out, "NetRefd={refd}");
        }
        let mut nodes: BTreeMap<u8, (&Vertex, &Attachment)> = BTreeMap::new();
        for vertex in &topology.vertices {
            if let Some(attachment) = vertex.attachment(number)
                && let Some(id) = attachment.valid_node_id()
            {
                nodes.entry(id).or_insert((vertex, attachment));
            }
        }
        let _ = writeln!(out, "Nodes=0x{:02X}", nodes.len());
        for (id, (vertex, attachment)) in &nodes {
            let present = if attachment.present { "0x01" } else { "0x00" };
            let _ = writeln!(out, "Node{id}Present={present}");
            if let Some(name) = &vertex.name {
                let _ = writeln!(out, "Node{id}Name={name}");
            }
            if let Some(refd) = &attachment.refd {
                let _ = writeln!(out, "Node{id}Refd={refd}");
            }
            if let Some(dcf) = &attachment.dcf {
                let _ = writeln!(out, "Node{id}DCFName={dcf}");
            }
        }
        if let Some(base) = network
            .and_then(|n| n.eds_base_name.as_deref())
            .or(topology.eds_base_name.as_deref())
        {
            let _ = writeln!(out, "EDSBaseName={base}");
        }
        for extra in network.map(|n| n.extra.as_slice()).unwrap_or_default() {
            let _ = writeln!(out, "{}={}", extra.name, extra.value);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn codes(diagnostics: &[NetDiagnostic]) -> Vec<(NetCode, u32)> {
        diagnostics.iter().map(|d| (d.code, d.span.line)).collect()
    }

    #[test]
    fn the_cia_306_3_minimal_example_reads_cleanly() {
        let text = "[Topology]\nNodes=0x03\nNode2Present=0x01\nNode2DCFName=demo_plc.dcf\nNode3Present=0x01\n\
                    Node3DCFName=demodeva.dcf\nNode4Present=0x01\nNode4DCFName=demodevb.dcf\n";
        let (_, topology, diagnostics) = read(text.as_bytes());
        assert!(diagnostics.is_empty(), "{diagnostics:?}");
        let ids: Vec<(&str, Option<i64>, Option<&str>)> = topology
            .vertices
            .iter()
            .map(|v| {
                (
                    v.id.as_str(),
                    v.attachments[0].node_id,
                    v.attachments[0].dcf.as_deref(),
                )
            })
            .collect();
        assert_eq!(
            ids,
            [
                ("n1_2", Some(2), Some("demo_plc.dcf")),
                ("n1_3", Some(3), Some("demodeva.dcf")),
                ("n1_4", Some(4), Some("demodevb.dcf"))
            ]
        );
    }

    #[test]
    fn both_multi_network_layouts_read_and_the_writer_round_trips() {
        let canfestival = "[TOPOLOGY]\nNetName=A\nNodes=0x01\nNode2Present=0x01\nNode2Name=Drive\nNode2DCFName=drive.eds\n\
                           EDSBaseName=eds\n[TOPOLOGY]\nNetName=B\nNodes=0x01\nNode5Present=0x01\nNode5DCFName=io.eds\n\
                           EDSBaseName=eds\n";
        let (_, topology, diagnostics) = read(canfestival.as_bytes());
        assert!(diagnostics.is_empty(), "{diagnostics:?}");
        assert_eq!(topology.network_numbers().into_iter().collect::<Vec<_>>(), [1, 2]);
        assert_eq!(topology.eds_base_name.as_deref(), Some("eds"));
        let written = write(&topology);
        assert!(written.contains("[Topology2]\nNetName=B\n"), "{written}");
        let (_, again, diagnostics) = read(written.as_bytes());
        assert!(diagnostics.is_empty(), "{diagnostics:?}");
        assert_eq!(
            again
                .vertices
                .iter()
                .map(|v| (&v.id, &v.name, &v.attachments[0].dcf))
                .collect::<Vec<_>>(),
            topology
                .vertices
                .iter()
                .map(|v| (&v.id, &v.name, &v.attachments[0].dcf))
                .collect::<Vec<_>>()
        );
        let numbered =
            "[Topology]\nNodes=0x00\n[Topology7]\nNodes=0x01\nNode3Present=0x01\nNode3DCFName=x.dcf\n";
        let (_, topology, _) = read(numbered.as_bytes());
        assert_eq!(topology.vertices[0].attachments[0].net, Some(7));
    }

    #[test]
    fn the_quirks_are_reported_where_they_are() {
        let text = "[Topology]\nNodes=3\nNode2Present=0x02\nNode3Name=lonely\nNode01Name=x\nNode4Present=0x01\n\
                    Node4Present=0x00\nVendorKey=1\n[Other]\n";
        let (_, topology, diagnostics) = read(text.as_bytes());
        assert_eq!(
            codes(&diagnostics),
            [
                (NetCode::NodesEntry, 2),
                (NetCode::PresentValue, 3),
                (NetCode::NodeKey, 5),
                (NetCode::DuplicateData, 7),
                (NetCode::UnknownKey, 8),
                (NetCode::NotPresent, 4),
                (NetCode::UnknownSection, 9),
            ]
        );
        assert_eq!(topology.networks[0].extra.len(), 2);
        let present: Vec<bool> = topology
            .vertices
            .iter()
            .map(|v| v.attachments[0].present)
            .collect();
        assert_eq!(present, [false, false, true]);
        let (_, _, diagnostics) = read(b"garbage\n");
        assert_eq!(
            codes(&diagnostics),
            [(NetCode::CpjSyntax, 1), (NetCode::NoTopologySection, 1)]
        );
    }
}

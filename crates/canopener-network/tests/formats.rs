//! Every fixture of `test_data` read, written back and converted: GraphML → GraphML gives the same
//! model, cpj → GraphML → cpj keeps every device, node-ID, name and DCF, and proptest does the same
//! for generated systems.

use std::path::PathBuf;

use canopener_eds::Severity;
use canopener_network::convert::{Target, convert};
use canopener_network::model::{Attachment, Cable, Network, Topology, Vertex};
use canopener_testkit::fixture;
use proptest::prelude::*;

fn test_data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("test_data")
        .join(name)
}

const GRAPHML: [&str; 9] = [
    "line.graphml",
    "trunk.graphml",
    "trunk-num-of-nets-default.graphml",
    "hub.graphml",
    "gateway.graphml",
    "supply.graphml",
    "networkx-written.graphml",
    "yed-style.graphml",
    "paper/Nodelist.graphml",
];

/// The model without positions in the file (spans), for comparing what two readings say.
fn unspanned(mut topology: Topology) -> Topology {
    for vertex in &mut topology.vertices {
        vertex.span = Default::default();
        for attachment in &mut vertex.attachments {
            attachment.span = Default::default();
        }
    }
    for cable in &mut topology.cables {
        cable.span = Default::default();
    }
    topology
}

/// (network, node-ID, name, DCF) of every device, sorted.
fn devices(topology: &Topology) -> Vec<(u32, u8, Option<String>, Option<String>)> {
    let mut out: Vec<_> = topology
        .network_numbers()
        .into_iter()
        .flat_map(|net| {
            topology.members(net).into_iter().map(move |m| {
                (
                    net,
                    m.attachment.valid_node_id().unwrap_or(0),
                    m.vertex.name.clone(),
                    m.attachment.dcf.clone(),
                )
            })
        })
        .collect();
    out.sort();
    out
}

#[test]
fn every_graphml_fixture_reads_without_errors_and_writes_back_to_the_same_model() {
    for name in GRAPHML {
        let bytes = fixture::read(test_data(name)).expect("fixture");
        let loaded = canopener_network::load(&bytes);
        let errors: Vec<_> = loaded
            .diagnostics
            .iter()
            .filter(|d| d.severity == Severity::Error)
            .collect();
        assert!(errors.is_empty(), "{name}: {errors:?}");
        assert!(!loaded.topology.vertices.is_empty(), "{name}");
        let written = convert(&loaded, Target::Graphml).text;
        let again = canopener_network::load(written.as_bytes());
        assert_eq!(
            unspanned(again.topology.clone()),
            unspanned(loaded.topology.clone()),
            "{name}"
        );
        assert_eq!(
            convert(&again, Target::Graphml).text,
            written,
            "{name}: not a fixed point"
        );
    }
}

/// A `<key>`'s default NumOfNets counts for the devices on a network, not for junctions on none: the
/// file reads as trunk.graphml, which writes NumOfNets=1 on each device and nothing on the junctions.
#[test]
fn a_num_of_nets_default_applies_to_the_devices_only() {
    let read = |name: &str| {
        let bytes = fixture::read(test_data(name)).expect("fixture");
        let loaded = canopener_network::load(&bytes);
        assert!(loaded.diagnostics.is_empty(), "{name}: {:?}", loaded.diagnostics);
        unspanned(loaded.topology)
    };
    let explicit = read("trunk.graphml");
    let by_default = read("trunk-num-of-nets-default.graphml");
    let nets = |t: &Topology| -> Vec<Option<i64>> { t.vertices.iter().map(|v| v.num_of_nets).collect() };
    assert_eq!(nets(&by_default), nets(&explicit));
    assert!(nets(&explicit).contains(&None) && nets(&explicit).contains(&Some(1)));
}

#[test]
fn the_papers_example_has_the_warnings_it_deserves_and_its_two_networks() {
    let bytes = fixture::read(test_data("paper/Nodelist.graphml")).expect("fixture");
    let loaded = canopener_network::load(&bytes);
    let codes: Vec<&str> = loaded.diagnostics.iter().map(|d| d.code.as_str()).collect();
    assert_eq!(codes.iter().filter(|c| **c == "N011").count(), 1, "{codes:?}");
    assert_eq!(codes.iter().filter(|c| **c == "N012").count(), 8, "{codes:?}");
    let topology = &loaded.topology;
    assert_eq!(topology.eds_base_name.as_deref(), Some("EDS"));
    assert_eq!(topology.network_numbers().into_iter().collect::<Vec<_>>(), [1, 7]);
    let gateway = &topology.vertices[topology.find_vertex("DemoNode_C").expect("N003")];
    assert_eq!(gateway.kind(), canopener_network::VertexKind::Gateway);
    assert_eq!(gateway.attachment(7).and_then(|a| a.node_id), Some(6));
    // The first of repeated values wins.
    assert_eq!(
        gateway.attachment(7).and_then(|a| a.supply_domain.as_deref()),
        Some("Primary")
    );
    let cpj = convert(&loaded, Target::Cpj);
    assert!(
        cpj.dropped.iter().any(|d| d.contains("cable")),
        "{:?}",
        cpj.dropped
    );
    let back = canopener_network::load(cpj.text.as_bytes());
    assert_eq!(devices(&back.topology), devices(topology));
    let dot = convert(&loaded, Target::Dot).text;
    assert!(dot.contains("\"N003\" -- \"N004\""), "{dot}");
    let svg = canopener_network::draw::svg(topology);
    for name in [
        "DemoPLC",
        "DemoNode_A",
        "DemoNode_C",
        "DemoNode_D",
        "W5002 500 m",
        "lin_back.bmp",
    ] {
        assert!(svg.contains(name), "{name} not in the drawing");
    }
}

#[test]
fn cpj_to_graphml_to_cpj_keeps_every_device_of_every_graphml_fixture() {
    for name in GRAPHML {
        let bytes = fixture::read(test_data(name)).expect("fixture");
        let original = canopener_network::load(&bytes);
        let cpj = convert(&original, Target::Cpj).text;
        let from_cpj = canopener_network::load(cpj.as_bytes());
        let graphml = convert(&from_cpj, Target::Graphml);
        assert!(graphml.dropped.is_empty(), "{name}");
        let back = canopener_network::load(
            convert(&canopener_network::load(graphml.text.as_bytes()), Target::Cpj)
                .text
                .as_bytes(),
        );
        assert_eq!(devices(&back.topology), devices(&from_cpj.topology), "{name}");
        // Gateways become one node per network in cpj; every (network, node-ID) survives.
        let ids = |t: &Topology| {
            devices(t)
                .into_iter()
                .map(|(n, id, ..)| (n, id))
                .collect::<Vec<_>>()
        };
        assert_eq!(ids(&back.topology), ids(&original.topology), "{name}");
    }
}

/// A system with `nets` networks: devices with names, node-IDs and DCFs, some absent.
fn system() -> impl Strategy<Value = Topology> {
    let device = (
        1u32..=3,
        1u8..=127,
        "[A-Za-z][A-Za-z0-9_ ]{0,12}",
        proptest::option::of("[a-z0-9_]{1,8}\\.dcf"),
        any::<bool>(),
    );
    (
        proptest::collection::vec(device, 1..12),
        proptest::option::of("[a-z]{1,6}"),
        proptest::option::of("[A-Za-z ]{1,10}"),
    )
        .prop_map(|(devices, base, net_name)| {
            let mut seen = std::collections::BTreeSet::new();
            let vertices: Vec<Vertex> = devices
                .into_iter()
                .filter(|(net, id, ..)| seen.insert((*net, *id)))
                .map(|(net, id, name, dcf, present)| Vertex {
                    id: canopener_network::cpj::vertex_id(net, id),
                    name: Some(name.trim().to_owned()).filter(|n| !n.is_empty()),
                    attachments: vec![Attachment {
                        slot: 1,
                        net: Some(net),
                        node_id: Some(i64::from(id)),
                        dcf,
                        present,
                        ..Attachment::default()
                    }],
                    ..Vertex::default()
                })
                .collect();
            let nets: std::collections::BTreeSet<u32> = vertices.iter().flat_map(|v| v.networks()).collect();
            Topology {
                eds_base_name: base,
                networks: nets
                    .into_iter()
                    .map(|number| Network {
                        number,
                        name: net_name
                            .clone()
                            .map(|n| n.trim().to_owned())
                            .filter(|n| !n.is_empty()),
                        ..Network::default()
                    })
                    .collect(),
                vertices,
                cables: Vec::<Cable>::new(),
                ..Topology::default()
            }
        })
}

proptest! {
    #[test]
    fn cpj_and_graphml_round_trip_generated_systems(topology in system()) {
        let cpj = canopener_network::cpj::write(&topology);
        let from_cpj = canopener_network::load(cpj.as_bytes());
        prop_assert!(from_cpj.diagnostics.iter().all(|d| d.severity != Severity::Error), "{:?}\n{cpj}", from_cpj.diagnostics);
        prop_assert_eq!(devices(&from_cpj.topology), devices(&topology));
        let graphml = convert(&from_cpj, Target::Graphml).text;
        let from_graphml = canopener_network::load(graphml.as_bytes());
        prop_assert!(from_graphml.diagnostics.iter().all(|d| d.severity != Severity::Error), "{:?}", from_graphml.diagnostics);
        prop_assert_eq!(unspanned(from_graphml.topology.clone()), unspanned(from_cpj.topology.clone()));
        let back = canopener_network::load(convert(&from_graphml, Target::Cpj).text.as_bytes());
        prop_assert_eq!(devices(&back.topology), devices(&topology));
        for net in topology.network_numbers() {
            prop_assert_eq!(back.topology.network_name(net), topology.network(net).and_then(|n| n.name.as_deref()));
        }
    }
}

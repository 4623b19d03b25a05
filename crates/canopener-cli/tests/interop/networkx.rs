//! GraphML interop with networkx (pinned in tests/python/requirements.txt): every GraphML canopener
//! writes reads in networkx with the same nodes, edges and data as canopener's model, and what
//! networkx writes reads in canopener the same way — including a file networkx rewrote from ours.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use canopener_network::Topology;
use canopener_testkit::fixture::ScratchDir;
use serde_json::{Value, json};

use crate::support::{canopener, python, workspace_root};

fn test_data(name: &str) -> PathBuf {
    workspace_root()
        .join("crates/canopener-network/test_data")
        .join(name)
}

fn nx(python: &Path, args: &[&str]) -> String {
    let output = Command::new(python)
        .arg(workspace_root().join("crates/canopener-cli/tests/python/nx_graphml.py"))
        .args(args)
        .output()
        .expect("run python");
    assert!(
        output.status.success(),
        "nx_graphml.py {args:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8_lossy(&output.stdout).into_owned()
}

fn to_arg(path: &Path) -> &str {
    path.to_str().expect("UTF-8 paths")
}

/// What networkx should see of a topology: per node and edge, the proposal's keys with their values.
fn expected(topology: &Topology) -> Value {
    let mut nodes = serde_json::Map::new();
    for v in &topology.vertices {
        let mut data = serde_json::Map::new();
        let mut put = |key: String, value: Value| {
            data.insert(key, value);
        };
        if let Some(n) = &v.name {
            put("NodeName".into(), json!(n));
        }
        if let Some(t) = &v.node_type {
            put("NodeType".into(), json!(t));
        }
        if let Some(f) = &v.fig {
            put("NodeFig".into(), json!(f));
        }
        if let Some(x) = v.x {
            put("X".into(), json!(x));
        }
        if let Some(y) = v.y {
            put("Y".into(), json!(y));
        }
        if let Some(n) = v.num_of_nets {
            put("NumOfNets".into(), json!(n));
        }
        for a in &v.attachments {
            let s = a.slot;
            if let Some(n) = a.net {
                put(format!("NetNumberN{s}"), json!(n));
            }
            if let Some(n) = &a.network_name {
                put(format!("NetworkNameN{s}"), json!(n));
            }
            if let Some(n) = a.node_id {
                put(format!("NodeIDN{s}"), json!(n));
            }
            if let Some(n) = &a.dcf {
                put(format!("NodeDCFNameN{s}"), json!(n));
            }
            if let Some(n) = &a.supply_domain {
                put(format!("SupplyDomainN{s}"), json!(n));
            }
            if let Some(n) = &a.supply_point {
                put(format!("SupplyPointN{s}"), json!(n));
            }
        }
        nodes.insert(v.id.clone(), Value::Object(data));
    }
    let mut edges: Vec<Value> = topology
        .cables
        .iter()
        .map(|c| {
            let mut data = serde_json::Map::new();
            if let Some(n) = c.net {
                data.insert("NetNumber".into(), json!(n));
            }
            if let Some(n) = &c.name {
                data.insert("CableName".into(), json!(n));
            }
            if let Some(n) = c.length {
                data.insert("Length".into(), json!(n));
            }
            if let Some(n) = &c.line_type {
                data.insert("LineType".into(), json!(n));
            }
            if let Some(n) = &c.line_params {
                data.insert("LineParams".into(), json!(n));
            }
            let (a, b) = if c.source <= c.target {
                (&c.source, &c.target)
            } else {
                (&c.target, &c.source)
            };
            json!([a, b, data])
        })
        .collect();
    edges.sort_by_key(|e| (e[0].as_str().map(str::to_owned), e[1].as_str().map(str::to_owned)));
    json!({"nodes": nodes, "edges": edges})
}

/// networkx's view of a file, restricted to the proposal's keys (networkx also reports the keys of
/// other tools and canopener's additions), numbers compared as numbers.
fn seen_by_networkx(python: &Path, file: &Path, topology: &Topology) -> Value {
    let dump: Value = serde_json::from_str(&nx(python, &["dump", to_arg(file)])).expect("json");
    let known = |key: &str| {
        let base = key.trim_end_matches(|c: char| c.is_ascii_digit());
        let base = base.strip_suffix('N').filter(|_| base != key).unwrap_or(key);
        [
            "NodeName",
            "NodeType",
            "NodeFig",
            "X",
            "Y",
            "NumOfNets",
            "NetNumber",
            "NetworkName",
            "NodeID",
            "NodeDCFName",
            "SupplyDomain",
            "SupplyPoint",
            "CableName",
            "Length",
            "LineType",
            "LineParams",
        ]
        .contains(&base)
    };
    let filter = |data: &Value| -> Value {
        Value::Object(
            data.as_object()
                .expect("data")
                .iter()
                .filter(|(k, _)| known(k))
                .map(|(k, v)| {
                    (
                        k.clone(),
                        v.as_f64()
                            .filter(|f| f.fract() != 0.0 || v.is_f64())
                            .map_or(v.clone(), |f| json!(f)),
                    )
                })
                .collect(),
        )
    };
    let nodes: serde_json::Map<String, Value> = dump["nodes"]
        .as_object()
        .expect("nodes")
        .iter()
        .map(|(id, data)| (id.clone(), filter(data)))
        .collect();
    let mut edges: Vec<Value> = dump["edges"]
        .as_array()
        .expect("edges")
        .iter()
        .map(|e| {
            let (a, b) = (e[0].as_str().unwrap_or(""), e[1].as_str().unwrap_or(""));
            let (a, b) = if a <= b { (a, b) } else { (b, a) };
            json!([a, b, filter(&e[2])])
        })
        .collect();
    edges.sort_by_key(|e| (e[0].as_str().map(str::to_owned), e[1].as_str().map(str::to_owned)));
    let _ = topology;
    json!({"nodes": nodes, "edges": edges})
}

/// Numbers as networkx and serde see them may differ in kind (2 vs 2.0): compare them as f64.
fn normalised(value: &Value) -> Value {
    match value {
        Value::Number(n) => json!(n.as_f64()),
        Value::Array(items) => Value::Array(items.iter().map(normalised).collect()),
        Value::Object(map) => Value::Object(map.iter().map(|(k, v)| (k.clone(), normalised(v))).collect()),
        other => other.clone(),
    }
}

fn read(path: &Path) -> Topology {
    canopener_network::load(&std::fs::read(path).expect("read")).topology
}

#[test]
fn networkx_reads_every_graphml_canopener_writes_with_the_same_nodes_edges_and_data() {
    let Some(python) = python() else { return };
    let dir = ScratchDir::new("networkx-written");
    let mut checked = BTreeMap::new();
    let sources = [
        "line.graphml",
        "trunk.graphml",
        "hub.graphml",
        "gateway.graphml",
        "supply.graphml",
        "networkx-written.graphml",
        "yed-style.graphml",
        "paper/Nodelist.graphml",
    ];
    for source in sources {
        for via_cpj in [false, true] {
            let mut input = test_data(source);
            if via_cpj {
                // What canopener writes from a nodelist.cpj (the builder, not the lossless writer).
                let cpj = dir.join(format!("{}.cpj", source.replace('/', "_")));
                let out = canopener()
                    .args([
                        "net",
                        "convert",
                        to_arg(&input),
                        "--to",
                        "cpj",
                        "-o",
                        to_arg(&cpj),
                    ])
                    .output()
                    .expect("run");
                assert!(out.status.success());
                input = cpj;
            }
            let written = dir.join(format!("{}-{via_cpj}.graphml", source.replace('/', "_")));
            let out = canopener()
                .args([
                    "net",
                    "convert",
                    to_arg(&input),
                    "--to",
                    "graphml",
                    "-o",
                    to_arg(&written),
                ])
                .output()
                .expect("run");
            assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
            let ours = read(&written);
            let theirs = seen_by_networkx(&python, &written, &ours);
            assert_eq!(
                normalised(&theirs),
                normalised(&expected(&ours)),
                "{source} (via cpj: {via_cpj})"
            );

            // networkx writes it again; canopener reads the same system from that.
            let rewritten = dir.join(format!("{}-{via_cpj}-nx.graphml", source.replace('/', "_")));
            nx(&python, &["rewrite", to_arg(&written), to_arg(&rewritten)]);
            let back = read(&rewritten);
            assert_eq!(
                normalised(&expected(&back)),
                normalised(&expected(&ours)),
                "{source} rewritten by networkx"
            );
            checked.insert(format!("{source} via cpj {via_cpj}"), ours.vertices.len());
        }
    }
    assert_eq!(checked.len(), sources.len() * 2);
}

#[test]
fn canopener_reads_what_networkx_builds_and_writes() {
    let Some(python) = python() else { return };
    let dir = ScratchDir::new("networkx-made");
    let file = dir.join("made.graphml");
    nx(&python, &["make", to_arg(&file)]);
    let loaded = canopener_network::load(&std::fs::read(&file).expect("read"));
    assert!(loaded.diagnostics.is_empty(), "{:?}", loaded.diagnostics);
    let topology = &loaded.topology;
    assert_eq!(
        normalised(&seen_by_networkx(&python, &file, topology)),
        normalised(&expected(topology))
    );
    let gateway = &topology.vertices[topology.find_vertex("Gateway").expect("gateway")];
    assert_eq!(gateway.networks().into_iter().collect::<Vec<_>>(), [1, 2]);
    assert_eq!(
        topology.cables.iter().map(|c| c.label()).collect::<Vec<_>>(),
        ["W1", "W2", "W3"]
    );
    let _ = std::fs::remove_dir_all(&dir);
}

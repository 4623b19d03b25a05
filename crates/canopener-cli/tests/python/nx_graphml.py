"""networkx as the other side of canopener's GraphML interop tests.

    nx_graphml.py dump FILE          print {"graph": {...}, "nodes": {id: {...}}, "edges": [[u, v, {...}], ...]}
                                     as networkx reads FILE (read_graphml)
    nx_graphml.py rewrite IN OUT     read IN with networkx and write it again with write_graphml (key
                                     defaults written out on each element: networkx drops them)
    nx_graphml.py make OUT           write a two-network system built with networkx's own API
"""

import json
import sys

import networkx as nx


def dump(path):
    graph = nx.read_graphml(path)
    # networkx keeps a key's <default> aside (graph["node_default"]); GraphML says it is the value of
    # every element without a <data> for the key, as canopener reads it.
    node_default = graph.graph.pop("node_default", {})
    edge_default = graph.graph.pop("edge_default", {})
    out = {
        "graph": dict(graph.graph),
        "nodes": {node: {**node_default, **data} for node, data in graph.nodes(data=True)},
        "edges": sorted([[u, v, {**edge_default, **data}] for u, v, data in graph.edges(data=True)],
                        key=lambda e: (e[0], e[1])),
    }
    print(json.dumps(out, sort_keys=True))


def make(path):
    graph = nx.Graph(EDSBaseName="dcf")
    graph.add_node("plc", NodeName="PLC", NodeType="master", X=10.0, Y=20.0, NumOfNets=1,
                   NetNumberN1=1, NodeIDN1=1, NodeDCFNameN1="node1.dcf", SupplyDomainN1="F1")
    graph.add_node("gw", NodeName="Gateway", NumOfNets=2, X=200.0, Y=20.0,
                   NetNumberN1=1, NodeIDN1=10, NodeDCFNameN1="node10.dcf",
                   NetNumberN2=2, NodeIDN2=20, NodeDCFNameN2="node20.dcf")
    graph.add_node("j1", NodeName="J1", NodeType="junction", X=100.0, Y=20.0)
    graph.add_node("io", NodeName="IO", NumOfNets=1, X=300.0, Y=20.0, NetNumberN1=2, NodeIDN1=21,
                   NodeDCFNameN1="node21.dcf")
    graph.add_edge("plc", "j1", NetNumber=1, CableName="W1", Length=2.5, LineType="trunk")
    graph.add_edge("j1", "gw", NetNumber=1, CableName="W2", Length=1.0, LineType="trunk")
    graph.add_edge("gw", "io", NetNumber=2, CableName="W3", Length=4.0, LineType="trunk")
    nx.write_graphml(graph, path)


if __name__ == "__main__":
    command = sys.argv[1]
    if command == "dump":
        dump(sys.argv[2])
    elif command == "rewrite":
        graph = nx.read_graphml(sys.argv[2])
        # write_graphml does not write key defaults back: give every element its defaulted values.
        for node_or_edge, key in ((graph.nodes, "node_default"), (graph.edges, "edge_default")):
            defaults = graph.graph.pop(key, {})
            for item in node_or_edge:
                for name, value in defaults.items():
                    node_or_edge[item].setdefault(name, value)
        nx.write_graphml(graph, sys.argv[3])
    elif command == "make":
        make(sys.argv[2])
    else:
        sys.exit(f"unknown command {command}")

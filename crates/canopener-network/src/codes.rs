//! The stable codes of everything the topology readers and checks report (the `N` series), in the
//! shared diagnostic shape of `canopener_eds::diag`.

use canopener_eds::Diagnostic;

/// A diagnostic about a topology file.
pub type NetDiagnostic = Diagnostic<NetCode>;

canopener_eds::diagnostic_codes! {
    /// The stable identity of a topology diagnostic.
    pub enum NetCode {
    /// The XML is not well-formed; reported at the parser's position, nothing after it was read.
    MalformedXml = "N001", "malformed-xml", Error;
    /// The document is XML but not GraphML (no `<graphml>` root, or no `<graph>`).
    NotGraphml = "N002", "not-graphml", Error;
    /// A line of a nodelist.cpj that the INI reader cannot read (the CiA 306 syntax rules).
    CpjSyntax = "N003", "cpj-syntax", Error;
    /// A nodelist.cpj without any `[Topology]` section.
    NoTopologySection = "N004", "no-topology-section", Error;
    /// A cpj section that is not a `[Topology]` section; kept as it is.
    UnknownSection = "N005", "unknown-section", Warning;
    /// GraphML content canopener keeps but does not interpret (hyperedges, nested graphs, several graphs).
    UnsupportedGraphml = "N006", "unsupported-graphml", Warning;
    /// A `<data>` whose key no `<key>` declares.
    UndeclaredKey = "N010", "undeclared-key", Error;
    /// A `<data>` whose key matches a declared key only when letter case is ignored; resolved to it.
    KeyCase = "N011", "key-case", Warning;
    /// The same key twice in one element (or the same cpj key twice in a section); the first wins.
    DuplicateData = "N012", "duplicate-data", Warning;
    /// A value that does not fit its declared type or the key's meaning.
    InvalidValue = "N013", "invalid-value", Error;
    /// A `<data>` whose key is declared for another kind of element.
    KeyScope = "N014", "key-scope", Warning;
    /// A `<key>` without an id, declared twice, or with an `attr.type` GraphML does not define.
    KeyDeclaration = "N015", "key-declaration", Error;
    /// A key of the proposal declared with another type than the proposal's (kept, read as written).
    KeyType = "N016", "key-type", Warning;
    /// Two vertices (or two edges) with the same id.
    DuplicateId = "N020", "duplicate-id", Error;
    /// An edge whose end is no vertex of the graph.
    DanglingEdge = "N021", "dangling-edge", Error;
    /// A vertex or edge end without an id.
    MissingId = "N022", "missing-id", Error;
    /// An edge from a vertex to itself.
    SelfLoop = "N023", "self-loop", Warning;
    /// A node-ID outside 1 to 127.
    NodeIdRange = "N030", "node-id-range", Error;
    /// Two devices with the same node-ID on one network.
    DuplicateNodeId = "N031", "duplicate-node-id", Error;
    /// `NumOfNets` disagrees with the per-network keys of the vertex.
    NumOfNets = "N032", "num-of-nets", Error;
    /// Per-network keys of attachment x without its `NetNumberNx` or `NodeIDNx`.
    IncompleteAttachment = "N033", "incomplete-attachment", Error;
    /// A cable on a network its device end is not attached to.
    CableNetwork = "N034", "cable-network", Error;
    /// A cable without `NetNumber` in a system of several networks.
    CableWithoutNetwork = "N035", "cable-without-network", Warning;
    /// The cables of a network form a ring that no active coupler splits: a CAN line must be a tree.
    NotATree = "N036", "not-a-tree", Error;
    /// Devices of a network that no cable joins to the others, while the network has cables.
    Unconnected = "N037", "unconnected", Warning;
    /// A vertex typed `gateway` in fewer than two networks, or a passive vertex with a node-ID.
    NodeTypeMismatch = "N038", "node-type-mismatch", Warning;
    /// The DCF a device names does not exist (looked up beside the topology file and under `EDSBaseName`).
    DcfMissing = "N040", "dcf-missing", Error;
    /// The DCF's `[DeviceComissioning] NodeID` differs from the topology's node-ID.
    DcfNodeId = "N041", "dcf-node-id", Error;
    /// The DCF's `[DeviceComissioning] NetNumber` differs from the topology's network number.
    DcfNetNumber = "N042", "dcf-net-number", Error;
    /// The DCF has errors of its own (`canopener eds check`), summarised.
    DcfErrors = "N043", "dcf-errors", Error;
    /// A present device without a DCF: canopener cannot check, simulate or monitor it.
    NoDcf = "N044", "no-dcf", Error;
    /// A device without `X`/`Y`: drawings place it automatically.
    NoPosition = "N050", "no-position", Warning;
    /// A cpj `Node<X>Name`, `Refd` or `DCFName` without `Node<X>Present`.
    NotPresent = "N051", "not-present", Warning;
    /// A `NodeType` outside canopener's vocabulary.
    UnknownNodeType = "N052", "unknown-node-type", Warning;
    /// A cpj `Nodes` entry that is missing or not a hexadecimal number 0 to 0x7F.
    NodesEntry = "N053", "nodes-entry", Error;
    /// A cpj `Nodes` count that differs from the number of `Node<X>Present` entries.
    NodesCount = "N054", "nodes-count", Warning;
    /// A cpj `Node<X>Present` value other than 0x00 and 0x01 (reserved); read as not present.
    PresentValue = "N055", "present-value", Error;
    /// A cpj key that looks like a node key but is not one (`Node01Name`, `Node200Present`); kept.
    NodeKey = "N056", "node-key", Warning;
    /// A key outside the vocabulary of the format; kept and written back.
    UnknownKey = "N057", "unknown-key", Info;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_unique_sorted_and_slugs_unique() {
        let codes: Vec<&str> = NetCode::ALL.iter().map(|c| c.as_str()).collect();
        let mut sorted = codes.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(codes, sorted);
        let mut slugs: Vec<&str> = NetCode::ALL.iter().map(|c| c.slug()).collect();
        slugs.sort_unstable();
        let before = slugs.len();
        slugs.dedup();
        assert_eq!(before, slugs.len());
        assert_eq!(NetCode::from_name("key-case"), Some(NetCode::KeyCase));
    }
}

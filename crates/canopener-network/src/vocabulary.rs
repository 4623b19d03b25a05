//! The keys of Nodelist.graphml (the TUT/Sandvik proposal of 2011, as in the iCC 2012 paper) with the
//! GraphML type canopener writes them with, and the keys canopener adds so that nodelist.cpj converts
//! to GraphML without losing anything.

/// What kind of value a key holds, for the declared-type check (`int` and `long` are one class, as
/// are `float` and `double`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ValueClass {
    /// `string`.
    Text,
    /// `int` or `long`.
    Integer,
    /// `float` or `double` (integers are accepted too).
    Real,
    /// `boolean`.
    Boolean,
}

impl ValueClass {
    /// The class of a GraphML `attr.type` (`None` for a type GraphML does not define). networkx also
    /// reads `integer` (a Gephi bug), so it counts as an integer here too.
    pub fn of_attr_type(attr_type: &str) -> Option<ValueClass> {
        match attr_type {
            "string" => Some(ValueClass::Text),
            "int" | "long" | "integer" => Some(ValueClass::Integer),
            "float" | "double" => Some(ValueClass::Real),
            "boolean" => Some(ValueClass::Boolean),
            _ => None,
        }
    }

    /// The `attr.type` canopener declares this class with.
    pub fn attr_type(self, name: &str) -> &'static str {
        match self {
            ValueClass::Text => "string",
            // The proposal writes network numbers as long, node-IDs and counts as int.
            ValueClass::Integer if name.starts_with("NetNumber") => "long",
            ValueClass::Integer => "int",
            ValueClass::Real => "double",
            ValueClass::Boolean => "boolean",
        }
    }

    /// Whether a declared class agrees with the expected one (an integer where a real is expected is
    /// fine).
    pub fn accepts(self, declared: ValueClass) -> bool {
        self == declared || (self == ValueClass::Real && declared == ValueClass::Integer)
    }
}

/// `EDSBaseName`.
pub const EDS_BASE_NAME: &str = "EDSBaseName";
/// `Background`.
pub const BACKGROUND: &str = "Background";

/// The graph keys.
pub const GRAPH_KEYS: [(&str, ValueClass); 2] =
    [(EDS_BASE_NAME, ValueClass::Text), (BACKGROUND, ValueClass::Text)];

/// The node keys that are not per network.
pub const NODE_KEYS: [(&str, ValueClass); 6] = [
    ("NodeName", ValueClass::Text),
    ("NodeType", ValueClass::Text),
    ("NodeFig", ValueClass::Text),
    ("X", ValueClass::Real),
    ("Y", ValueClass::Real),
    ("NumOfNets", ValueClass::Integer),
];

/// The per-network node keys, without their `Nx` suffix (the same names are used inside `<port>`s).
/// `NodeRefd` and `NodePresent` are canopener's, for cpj's `Node<X>Refd` and `Node<X>Present=0x00`.
pub const ATTACHMENT_KEYS: [(&str, ValueClass); 8] = [
    ("NetNumber", ValueClass::Integer),
    ("NetworkName", ValueClass::Text),
    ("NodeID", ValueClass::Integer),
    ("NodeDCFName", ValueClass::Text),
    ("SupplyDomain", ValueClass::Text),
    ("SupplyPoint", ValueClass::Text),
    ("NodeRefd", ValueClass::Text),
    ("NodePresent", ValueClass::Boolean),
];

/// The edge keys.
pub const EDGE_KEYS: [(&str, ValueClass); 5] = [
    ("NetNumber", ValueClass::Integer),
    ("CableName", ValueClass::Text),
    ("Length", ValueClass::Real),
    ("LineType", ValueClass::Text),
    ("LineParams", ValueClass::Text),
];

/// Graph keys canopener adds for what a cpj section says about its network: `NetName.<n>`,
/// `NetRefd.<n>`, `EDSBaseName.<n>`, and `Cpj.<n>.<key>` for a key of the section canopener does not
/// know.
pub const NETWORK_KEY_PREFIXES: [&str; 3] = ["NetName.", "NetRefd.", "EDSBaseName."];
/// The prefix of the graph keys that carry unknown cpj keys (`Cpj.<n>.<key>`).
pub const CPJ_KEY_PREFIX: &str = "Cpj.";

/// Splits a per-network key `NodeIDN2` into (`NodeID`, 2); `None` for any other name.
pub fn split_attachment_key(name: &str) -> Option<(&'static str, u32)> {
    ATTACHMENT_KEYS.iter().find_map(|(base, _)| {
        let rest = name.strip_prefix(base)?.strip_prefix('N')?;
        let slot: u32 = rest
            .parse()
            .ok()
            .filter(|_| rest.bytes().all(|b| b.is_ascii_digit()))?;
        (slot >= 1).then_some((*base, slot))
    })
}

/// The class a known key expects on this kind of element (`graph`, `node`, `edge`, `port`).
pub fn class_of(element: &str, name: &str) -> Option<ValueClass> {
    let find = |keys: &[(&str, ValueClass)]| keys.iter().find(|(k, _)| *k == name).map(|(_, c)| *c);
    match element {
        "graph" => find(&GRAPH_KEYS),
        "node" => find(&NODE_KEYS).or_else(|| {
            let (base, _) = split_attachment_key(name)?;
            ATTACHMENT_KEYS.iter().find(|(k, _)| *k == base).map(|(_, c)| *c)
        }),
        "edge" => find(&EDGE_KEYS),
        "port" => find(&ATTACHMENT_KEYS),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn per_network_keys_split_into_base_and_slot() {
        assert_eq!(split_attachment_key("NodeIDN2"), Some(("NodeID", 2)));
        assert_eq!(split_attachment_key("NetNumberN10"), Some(("NetNumber", 10)));
        assert_eq!(split_attachment_key("NodeDCFNameN1"), Some(("NodeDCFName", 1)));
        assert_eq!(split_attachment_key("NodeIDN0"), None);
        assert_eq!(split_attachment_key("NodeIDN"), None);
        assert_eq!(split_attachment_key("NodeIDN+1"), None);
        assert_eq!(split_attachment_key("NodeName"), None);
        assert_eq!(class_of("node", "NodeIDN3"), Some(ValueClass::Integer));
        assert_eq!(class_of("node", "X"), Some(ValueClass::Real));
        assert_eq!(class_of("edge", "NodeIDN3"), None);
        assert_eq!(class_of("port", "NodeID"), Some(ValueClass::Integer));
    }
}

//! CANopen node-ids (CiA 301 §7.3.5 predefined connection set: node-ID 1 to 127).

use std::fmt;

/// A CANopen node-id, 1 to 127.
///
/// Node-id 0 is not a node: in an NMT command it addresses all nodes, and in a node-addressed COB-ID
/// (for example 580h) it is a configuration mistake.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeId(u8);

impl NodeId {
    /// The smallest node-id.
    pub const MIN: NodeId = NodeId(1);
    /// The largest node-id.
    pub const MAX: NodeId = NodeId(127);

    /// A node-id, or `None` unless `raw` is 1 to 127.
    pub const fn new(raw: u8) -> Option<NodeId> {
        if raw >= 1 && raw <= 127 {
            Some(NodeId(raw))
        } else {
            None
        }
    }

    /// The node-id as a number.
    pub const fn get(self) -> u8 {
        self.0
    }
}

impl fmt::Display for NodeId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

impl fmt::Debug for NodeId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "NodeId({})", self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_1_to_127_are_node_ids() {
        assert_eq!(NodeId::new(0), None);
        assert_eq!(NodeId::new(1), Some(NodeId::MIN));
        assert_eq!(NodeId::new(127), Some(NodeId::MAX));
        assert_eq!(NodeId::new(128), None);
        assert_eq!(NodeId::new(42).map(NodeId::get), Some(42));
        assert_eq!(NodeId::new(5).unwrap().to_string(), "5");
    }
}

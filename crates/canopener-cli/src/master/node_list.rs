//! Lists of node-IDs on the command line: `1-10,20,0x7F` (decimal or 0x-hex, ranges inclusive).

use canopener_wire::NodeId;

use crate::error::{CliError, CliResult};

/// Reads a node list: node-IDs 1..127 and ranges, comma-separated (`1-10,20`), in the order given.
/// `option` and `example` go into the message of a bad list.
pub(crate) fn parse_node_list(text: &str, option: &str, example: &str) -> CliResult<Vec<NodeId>> {
    let bad = |why: String| {
        CliError::Usage(format!(
            "{option} {text:?}: {why}; give node-IDs 1 to 127 and ranges, e.g. `{example}`"
        ))
    };
    let node = |part: &str| -> CliResult<NodeId> {
        let part = part.trim();
        let raw = match part.strip_prefix("0x").or_else(|| part.strip_prefix("0X")) {
            Some(hex) => u8::from_str_radix(hex, 16).ok(),
            None => part.parse::<u8>().ok(),
        };
        raw.and_then(NodeId::new)
            .ok_or_else(|| bad(format!("{part:?} is not a node-ID")))
    };
    let mut nodes = Vec::new();
    for part in text.split(',') {
        match part.split_once('-') {
            Some((first, last)) => {
                let (first, last) = (node(first)?, node(last)?);
                if first > last {
                    return Err(bad(format!("the range {first}-{last} runs backwards")));
                }
                nodes.extend((first.get()..=last.get()).filter_map(NodeId::new));
            }
            None => nodes.push(node(part)?),
        }
    }
    Ok(nodes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_lists_keep_their_order_and_refuse_nonsense_with_an_example() {
        let list = parse_node_list("10-12, 5,0x7F", "--nodes", "x").unwrap();
        let raw: Vec<u8> = list.iter().map(|node| node.get()).collect();
        assert_eq!(raw, [10, 11, 12, 5, 127]);
        for bad in ["", "0", "128", "5-", "12-10", "a", "1,,2"] {
            let err = parse_node_list(bad, "--nodes", "canopener heartbeat watch --nodes 1-10").unwrap_err();
            assert!(matches!(err, CliError::Usage(_)), "{bad:?}");
            let text = err.to_string();
            assert!(
                text.contains("--nodes") && text.contains("e.g. `canopener heartbeat watch --nodes 1-10`"),
                "{text}"
            );
        }
    }
}

//! `canopener net show`: what a topology says, per network.

use std::fmt::Write as _;

use canopener_network::Topology;
use serde_json::json;

use crate::error::CliResult;
use crate::net::args::{NetCheckFormat, NetShowArgs};
use crate::net::input::read_system;
use crate::output::print_stdout;

pub(crate) fn run(args: NetShowArgs) -> CliResult {
    let system = read_system(&args.file)?;
    let topology = system.topology();
    let text = match args.format {
        NetCheckFormat::Human => human(topology),
        NetCheckFormat::Json => format!("{:#}\n", document(topology)),
    };
    print_stdout(&text)
}

/// `{"format","eds_base_name","background","networks":[{"number","name","devices":[…],"cables":[…]}],
/// "supply_domains":[…],"wiring":[…]}`: one entry per device and network.
fn document(topology: &Topology) -> serde_json::Value {
    let networks: Vec<_> = topology
        .network_numbers()
        .into_iter()
        .map(|net| {
            let devices: Vec<_> = topology
                .members(net)
                .iter()
                .map(|m| {
                    json!({
                        "name": m.vertex.label(),
                        "id": m.vertex.id,
                        "kind": m.vertex.kind(),
                        "node_id": m.attachment.node_id,
                        "dcf": m.attachment.dcf,
                        "supply_domain": m.attachment.supply_domain,
                        "present": m.attachment.present,
                    })
                })
                .collect();
            let cables: Vec<_> = topology
                .cables_of(net)
                .into_iter()
                .map(|c| {
                    let cable = &topology.cables[c];
                    json!({
                        "name": cable.label(),
                        "source": cable.source,
                        "target": cable.target,
                        "length": cable.length,
                        "line_type": cable.line_type,
                    })
                })
                .collect();
            json!({
                "number": net,
                "name": topology.network_name(net),
                "devices": devices,
                "cables": cables,
            })
        })
        .collect();
    let wiring: Vec<_> = topology
        .vertices
        .iter()
        .filter(|v| !v.is_device())
        .map(|v| json!({"name": v.label(), "id": v.id, "kind": v.kind(), "node_type": v.node_type}))
        .collect();
    json!({
        "eds_base_name": topology.eds_base_name,
        "background": topology.background,
        "networks": networks,
        "wiring": wiring,
        "supply_domains": topology.supply_domains(),
    })
}

fn human(topology: &Topology) -> String {
    let mut out = String::new();
    if let Some(base) = &topology.eds_base_name {
        let _ = writeln!(out, "EDSBaseName: {base}");
    }
    for net in topology.network_numbers() {
        let name = topology
            .network_name(net)
            .map(|n| format!(" ({n})"))
            .unwrap_or_default();
        let _ = writeln!(out, "network {net}{name}");
        let _ = writeln!(
            out,
            "  {:>7}  {:<24} {:<9} {:<24} supply",
            "node-ID", "device", "kind", "DCF"
        );
        for m in topology.members(net) {
            let kind = serde_json::to_value(m.vertex.kind())
                .ok()
                .and_then(|v| v.as_str().map(str::to_owned))
                .unwrap_or_default();
            let absent = if m.attachment.present {
                ""
            } else {
                " (not present)"
            };
            let _ = writeln!(
                out,
                "  {:>7}  {:<24} {:<9} {:<24} {}{absent}",
                m.attachment.node_id.map(|id| id.to_string()).unwrap_or_default(),
                m.vertex.label(),
                kind,
                m.attachment.dcf.as_deref().unwrap_or("-"),
                m.attachment.supply_domain.as_deref().unwrap_or("-"),
            );
        }
        let cables = topology.cables_of(net);
        if !cables.is_empty() {
            let _ = writeln!(out, "  cables:");
            for c in cables {
                let cable = &topology.cables[c];
                let length = cable.length.map(|l| format!(" {l} m")).unwrap_or_default();
                let line = cable
                    .line_type
                    .as_deref()
                    .map(|t| format!(" {t}"))
                    .unwrap_or_default();
                let _ = writeln!(
                    out,
                    "    {}: {} - {}{length}{line}",
                    cable.label(),
                    cable.source,
                    cable.target
                );
            }
        }
    }
    let domains = topology.supply_domains();
    if !domains.is_empty() {
        let _ = writeln!(
            out,
            "supply domains: {}",
            domains.into_iter().collect::<Vec<_>>().join(", ")
        );
    }
    out
}

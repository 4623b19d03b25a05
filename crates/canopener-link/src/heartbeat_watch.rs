//! Watching every node's NMT state, heartbeat timing and EMCYs on a link (CiA 301 §7.2.8.3.2 heartbeat
//! and node guarding, §7.2.7 EMCY) with [`HeartbeatCore`], and counting per node what was heard.

use std::collections::{BTreeMap, BTreeSet};
use std::time::Duration;

use canopener_master::error_control::{ConsumerTime, GuardingConfig, GuardingConfigError, NodeMonitor};
use canopener_master::heartbeat_core::{HeardKind, HeartbeatCore, NodeStats};
use canopener_wire::NodeId;

use crate::link::{Ended, Flow, Link, LinkError, drive};

/// What to watch.
#[derive(Debug, Clone)]
pub struct WatchConfig {
    /// How long a heartbeat may stay away: fixed, learned from the first periods, or not checked.
    pub consumer: ConsumerTime,
    /// Nodes to guard (node guarding instead of heartbeat, CiA 301 §7.2.8.3.2.1), with `guarding`.
    pub guarded: Vec<NodeId>,
    /// Guard time and life time factor of the guarded nodes.
    pub guarding: GuardingConfig,
    /// Only these nodes are reported and counted; `None` for all.
    pub only: Option<BTreeSet<NodeId>>,
    /// How long to watch; `None` until cancelled.
    pub duration: Option<Duration>,
}

/// What a watch saw.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WatchSummary {
    /// How long it watched.
    pub elapsed: Duration,
    /// Per node heard, with its state at the end.
    pub nodes: BTreeMap<NodeId, NodeStats>,
}

/// Watches until `config.duration` passes or the link is cancelled (neither is a failure of a
/// watch), handing every event of a watched node to `on_heard` with the time since the start.
pub fn watch<L, E>(
    link: &mut L,
    config: WatchConfig,
    mut on_heard: impl FnMut(Duration, &HeardKind) -> Result<(), E>,
) -> Result<WatchSummary, E>
where
    L: Link + ?Sized,
    E: From<LinkError> + From<GuardingConfigError>,
{
    let mut monitor = NodeMonitor::new(config.consumer);
    let started = link.now();
    for node in &config.guarded {
        monitor.start_guarding(started, *node, config.guarding)?;
    }
    let mut core = HeartbeatCore::new(monitor);
    let deadline = config.duration.map(|duration| started + duration);
    let mut nodes: BTreeMap<NodeId, NodeStats> = BTreeMap::new();
    let ended = drive::<_, _, _, E>(link, &mut core, deadline, |_, heard| {
        let node = heard.node();
        if config.only.as_ref().is_some_and(|only| !only.contains(&node)) {
            return Ok(Flow::<()>::Continue);
        }
        nodes.entry(node).or_default().record(&heard.kind);
        on_heard(heard.at.saturating_duration_since(started), &heard.kind)?;
        Ok(Flow::Continue)
    })?;
    let _: Result<(), Ended> = ended;
    let elapsed = link.now().saturating_duration_since(started);
    for (node, status) in core.monitor().nodes() {
        if let Some(stats) = nodes.get_mut(&node) {
            stats.state = status.state;
            stats.lost_now = status.heartbeat_lost;
        }
    }
    Ok(WatchSummary { elapsed, nodes })
}

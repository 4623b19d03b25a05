//! `nmt_command` and `heartbeat_watch`: NMT commands confirmed by heartbeats, and watching them.

use std::collections::BTreeSet;
use std::time::Duration;

use canopener_link::heartbeat_watch::{WatchConfig, watch};
use canopener_link::link::LinkError;
use canopener_link::nmt_command::send_confirmed;
use canopener_link::sdo_session::SdoSession;
use canopener_link::virtual_link::VirtualLink;
use canopener_master::error_control::{ConsumerTime, GuardingConfig, GuardingConfigError};
use canopener_master::heartbeat_core::HeardKind;
use canopener_master::nmt_confirmation::Unconfirmed;
use canopener_master::nmt_master::NmtTarget;
use canopener_wire::{NmtCommand, NmtState, NodeId};

use crate::common::{IO_EDS, Node, bus, device};

fn node(raw: u8) -> NodeId {
    NodeId::new(raw).expect("node")
}

/// Nodes 5 and 6 with a heartbeat every 100 ms.
fn heartbeating() -> VirtualLink<Node> {
    let (mut link, _) = bus(vec![
        Node::Device(Box::new(device(IO_EDS, 5))),
        Node::Device(Box::new(device(IO_EDS, 6))),
    ]);
    for id in [5, 6] {
        let mut session = SdoSession::new(&mut link, id, Duration::from_millis(500)).expect("session");
        session
            .write(0x1017, 0, 100u16.to_le_bytes().to_vec())
            .expect("heartbeat on");
    }
    link
}

#[test]
fn stop_is_confirmed_by_the_next_heartbeat_and_reset_by_the_boot_up() {
    let mut link = heartbeating();
    let mut extended = false;
    let outcomes = send_confirmed(
        &mut link,
        NmtCommand::StopRemoteNode,
        NmtTarget::Node(node(5)),
        Duration::from_millis(500),
        |_| extended = true,
    )
    .expect("no bus error");
    assert_eq!(outcomes.len(), 1);
    assert!(outcomes[0].confirmed(), "{outcomes:?}");
    assert_eq!(outcomes[0].state, Some(NmtState::Stopped));
    assert!(!extended);

    let outcomes = send_confirmed(
        &mut link,
        NmtCommand::ResetNode,
        NmtTarget::Node(node(6)),
        Duration::from_millis(500),
        |_| {},
    )
    .expect("no bus error");
    assert!(outcomes[0].confirmed() && outcomes[0].boot_up, "{outcomes:?}");
    assert_eq!(outcomes[0].after, Some(Duration::ZERO));
}

#[test]
fn a_node_without_heartbeat_is_not_heard_within_the_timeout() {
    let (mut link, _) = bus(vec![Node::Device(Box::new(device(IO_EDS, 5)))]);
    let start = canopener_link::link::Link::now(&link);
    let outcomes = send_confirmed(
        &mut link,
        NmtCommand::StartRemoteNode,
        NmtTarget::Node(node(9)),
        Duration::from_millis(300),
        |_| {},
    )
    .expect("no bus error");
    assert_eq!(
        outcomes[0].unconfirmed,
        Some(Unconfirmed::NotHeard {
            reset: false,
            within: Duration::from_millis(300)
        })
    );
    assert_eq!(
        canopener_link::link::Link::now(&link).saturating_duration_since(start),
        Duration::from_millis(300)
    );
}

#[derive(Debug)]
enum Error {
    Link,
    Guarding,
}

impl From<LinkError> for Error {
    fn from(_: LinkError) -> Error {
        Error::Link
    }
}

impl From<GuardingConfigError> for Error {
    fn from(_: GuardingConfigError) -> Error {
        Error::Guarding
    }
}

fn config(only: Option<BTreeSet<NodeId>>) -> WatchConfig {
    WatchConfig {
        consumer: ConsumerTime::Fixed(Duration::from_millis(250)),
        guarded: Vec::new(),
        guarding: GuardingConfig {
            guard_time: Duration::from_millis(100),
            life_time_factor: 3,
        },
        only,
        duration: Some(Duration::from_millis(1_050)),
    }
}

#[test]
fn a_watch_counts_heartbeats_and_periods_per_node() {
    let mut link = heartbeating();
    let mut heard = 0;
    let summary = watch::<_, Error>(&mut link, config(None), |_, kind| {
        if matches!(kind, HeardKind::Heartbeat { .. }) {
            heard += 1;
        }
        Ok(())
    })
    .expect("watched");
    assert_eq!(summary.elapsed, Duration::from_millis(1_050));
    assert_eq!(summary.nodes.len(), 2);
    let five = &summary.nodes[&node(5)];
    assert_eq!(five.heartbeats, 10);
    assert_eq!(five.losses, 0);
    let spread = five.period_spread().expect("periods");
    assert_eq!(
        (spread.min, spread.max),
        (Duration::from_millis(100), Duration::from_millis(100))
    );
    assert_eq!(heard, 20);
    assert!(five.state.is_some());

    let only: BTreeSet<NodeId> = [node(6)].into();
    let summary = watch::<_, Error>(&mut link, config(Some(only)), |_, _| Ok(())).expect("watched");
    assert_eq!(summary.nodes.keys().copied().collect::<Vec<_>>(), [node(6)]);
}

#[test]
fn guarding_with_a_zero_guard_time_is_refused_before_watching() {
    let mut link = heartbeating();
    let mut config = config(None);
    config.guarded = vec![node(5)];
    config.guarding.guard_time = Duration::ZERO;
    assert!(matches!(
        watch::<_, Error>(&mut link, config, |_, _| Ok(())),
        Err(Error::Guarding)
    ));
}

/// `heartbeat-state-wrong` is heard as a node in the wrong state, not as a lost heartbeat: the
/// state byte it sends is a valid one (a consumer drops an invalid one and then reports the node
/// lost, which hides the defect a tester is looking for).
#[test]
fn a_wrong_heartbeat_state_is_heard_as_a_state_not_as_a_loss() {
    use canopener_device::faults::Fault;
    let faulty = device(IO_EDS, 5).with_faults(Fault::HeartbeatStateWrong.into());
    let (mut link, _) = bus(vec![Node::Device(Box::new(faulty))]);
    SdoSession::new(&mut link, 5, Duration::from_millis(500))
        .expect("session")
        .write(0x1017, 0, 100u16.to_le_bytes().to_vec())
        .expect("heartbeat on");
    let summary = watch::<_, Error>(&mut link, config(None), |_, _| Ok(())).expect("watched");
    let five = &summary.nodes[&node(5)];
    assert_eq!(five.heartbeats, 10);
    assert_eq!(five.losses, 0);
    assert!(!five.lost_now);
    // The I/O device starts on its own (1F80h), so it is operational; the fault reports stopped.
    assert_eq!(five.state, Some(NmtState::Stopped));
}

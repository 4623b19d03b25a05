//! `pdo_watch`: finding a node's TPDOs over SDO or in the EDS, and receiving them.

use std::time::Duration;

use canopener_eds::Eds;
use canopener_link::link::{Link, LinkError};
use canopener_link::nmt_command::send;
use canopener_link::pdo_watch::{DiscoverError, discover, from_eds, receive};
use canopener_link::sdo_session::SdoSession;
use canopener_link::virtual_link::VirtualLink;
use canopener_master::nmt_master::NmtTarget;
use canopener_master::pdo_watch::{Found, eds_lookup, tpdo_numbers};
use canopener_wire::{NmtCommand, NodeId};

use crate::common::{BASE_EDS, IO_EDS, Node, bus, device, eds};

/// The layout lines of what was found, typed by `eds`.
fn layouts(found: Vec<Found>, eds: &Eds) -> Vec<String> {
    found
        .into_iter()
        .map(|found| match found {
            Found::Watch(pdo) => {
                let layout = pdo.layout.typed(eds_lookup(eds));
                let fields: Vec<String> = layout
                    .fields()
                    .iter()
                    .map(|field| format!("{} {}", field.mapped, field.name.as_deref().unwrap_or("?")))
                    .collect();
                format!(
                    "TPDO{} {:08X}h type {:?}: {}",
                    pdo.number,
                    pdo.cob_id,
                    pdo.transmission_type,
                    fields.join(", ")
                )
            }
            Found::Skip { number, reason } => format!("TPDO{number} skipped: {reason}"),
        })
        .collect()
}

fn session(link: &mut VirtualLink<Node>) -> SdoSession<&mut VirtualLink<Node>> {
    SdoSession::new(link, 5, Duration::from_secs(1)).expect("session")
}

#[test]
fn discovers_the_tpdos_the_eds_describes_from_the_device() {
    let io = eds(IO_EDS);
    let (mut link, _) = bus(vec![Node::Device(Box::new(device(IO_EDS, 5)))]);
    let mut session = session(&mut link);
    // TPDO2: 6401h:01 and :02 on every SYNC; TPDO3 invalid.
    for (index, sub, data) in [
        (0x1801, 1, 0x8000_0285u32.to_le_bytes().to_vec()),
        (0x1A01, 1, 0x6401_0110u32.to_le_bytes().to_vec()),
        (0x1A01, 2, 0x6401_0210u32.to_le_bytes().to_vec()),
        (0x1A01, 0, vec![2]),
        (0x1801, 2, vec![1]),
        (0x1801, 1, 0x285u32.to_le_bytes().to_vec()),
        (0x1802, 1, 0x8000_0385u32.to_le_bytes().to_vec()),
    ] {
        session.write(index, sub, data).expect("write");
    }
    let mut progress = Vec::new();
    let found = discover(&mut session, &tpdo_numbers(&io), |done| progress.push(done)).expect("found");
    assert_eq!(
        layouts(found, &io),
        [
            "TPDO1 00000185h type Some(255): 6000:01:8 Read input 8 bit, 6000:02:8 Read input 8 bit",
            "TPDO2 00000285h type Some(1): 6401:01:16 Read analogue input 16 bit, 6401:02:16 Read analogue \
             input 16 bit",
            "TPDO3 skipped: not valid (COB-ID 80000385h has bit 31 set)",
            "TPDO4 00000485h type Some(254): ",
        ]
    );
    assert_eq!(progress, [0, 1, 2, 3, 4]);
}

#[test]
fn offline_layouts_are_the_eds_values_and_match_a_fresh_device() {
    let io = eds(IO_EDS);
    let numbers = tpdo_numbers(&io);
    assert_eq!(numbers, [1, 2, 3, 4]);
    let offline = from_eds(&io, 5, &numbers).expect("dictionary");
    let (mut link, _) = bus(vec![Node::Device(Box::new(device(IO_EDS, 5)))]);
    let online = discover(&mut session(&mut link), &numbers, |_| {}).expect("found");
    assert_eq!(layouts(offline, &io), layouts(online, &io));
    // base.eds has TPDO1 only; $NODEID is resolved with the node-ID given.
    let base = eds(BASE_EDS);
    assert_eq!(
        layouts(from_eds(&base, 0x22, &[1, 2]).expect("dictionary"), &base),
        [
            "TPDO1 000001A2h type Some(255): 6000:01:8 Read input 8-bit",
            "TPDO2 skipped: the EDS has no UNSIGNED32 COB-ID 1801h:01",
        ]
    );
}

#[test]
fn a_silent_device_ends_the_discovery_naming_the_object_and_the_wait() {
    let silent = Node::SilentAfter {
        device: Box::new(device(IO_EDS, 5)),
        answered: 0,
    };
    let (mut link, _) = bus(vec![silent]);
    let err = discover(&mut session(&mut link), &[1, 2], |_| {}).expect_err("silent");
    assert!(matches!(err, DiscoverError::Failed { number: 1, .. }));
    assert_eq!(
        err.to_string(),
        "node 5, reading the COB-ID of TPDO1 (1800h:01): timed out after 1s waiting for the initiate upload \
         response (abort 0x05040000 sent to the server)"
    );
}

#[test]
fn a_tpdo_the_device_lacks_is_skipped_with_the_abort() {
    // The EDS of a bigger device than the one answering.
    let (mut link, _) = bus(vec![Node::Device(Box::new(device(BASE_EDS, 5)))]);
    let found = discover(&mut session(&mut link), &[1, 2], |_| {}).expect("found");
    assert_eq!(
        layouts(found, &eds(BASE_EDS)),
        [
            "TPDO1 00000185h type Some(255): 6000:01:8 Read input 8-bit",
            "TPDO2 skipped: reading 1801h:01: SDO abort 0x06020000 from the server: Object does not exist in \
             the object dictionary",
        ]
    );
}

#[test]
fn received_tpdos_are_decoded_and_timed_on_virtual_time() {
    let (mut link, _) = bus(vec![Node::Device(Box::new(device(IO_EDS, 5)))]);
    // TPDO1 every 100 ms by its event timer, once the node is operational.
    let mut session = session(&mut link);
    session
        .write(0x1800, 5, 100u16.to_le_bytes().to_vec())
        .expect("event timer");
    let mut found = discover(&mut session, &[1], |_| {}).expect("found");
    let Some(Found::Watch(pdo)) = found.pop() else {
        panic!("TPDO1 is watched");
    };
    send(
        &mut link,
        NmtCommand::StartRemoteNode,
        NmtTarget::Node(NodeId::new(5).expect("node")),
    )
    .expect("start");
    let mut watched = [pdo];
    let mut seen = Vec::new();
    receive::<_, LinkError>(
        &mut link,
        &mut watched,
        Some(4),
        None,
        |pdo, _, elapsed, frame| {
            seen.push((
                elapsed,
                frame.data().len(),
                pdo.receive(elapsed_at(elapsed), frame).is_ok(),
            ));
            Ok(())
        },
    )
    .expect("received");
    assert_eq!(seen.len(), 4);
    assert!(
        seen.iter().all(|(_, len, decoded)| *len == 2 && *decoded),
        "{seen:?}"
    );
    let stats = &watched[0].stats;
    assert_eq!((stats.received, stats.malformed), (4, 0));
    let periods = stats.periods().expect("periods");
    assert_eq!(
        (periods.min, periods.max),
        (Duration::from_millis(100), Duration::from_millis(100))
    );
    assert!(link.now() >= canopener_can::Instant::from_millis(300));
}

/// The arrival time of a frame `elapsed` after a watch that began at virtual time zero.
fn elapsed_at(elapsed: Duration) -> canopener_can::Instant {
    canopener_can::Instant::ZERO + elapsed
}

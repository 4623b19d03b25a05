//! The EnergyBus system on a real bus, in real time: the simulated bus's virtual time follows the
//! wall clock, every frame a station sends goes onto the real bus, and every frame of the real bus
//! (a tester, a monitor, other devices) reaches every station, as `canopener sim --nodelist` does for
//! a whole system.

use std::time::Duration;

use canopener_can::Instant;

use canopener_master::energybus_controller::ControllerEvent;
use canopener_wire::NodeId;

use crate::energybus::system::{EnergyBusBus, Station, StationEvent, controller};
use canopener_link::link::{BusLink, Link, LinkError};

/// The longest the real bus is read before the simulation catches up with the wall clock.
const POLL: Duration = Duration::from_millis(2);

/// Runs `system` (started at virtual time zero) against `bus` until `bus` is cancelled or `limit`
/// (of the wall clock since the start) passes, reporting each station event with the time since the
/// start. Once the controller reports `hand_over` Operating, it hands that node over (to a tester on
/// the real bus).
pub fn serve(
    system: &mut EnergyBusBus,
    bus: &mut BusLink,
    limit: Option<Duration>,
    hand_over: Option<NodeId>,
    mut on_event: impl FnMut(Duration, StationEvent),
) -> Result<(), LinkError> {
    let started = bus.now();
    loop {
        let elapsed = bus.now().saturating_duration_since(started);
        if bus.is_cancelled() || limit.is_some_and(|limit| elapsed >= limit) {
            return Ok(());
        }
        // What the stations said by now, onto the real bus.
        while let Some((_, frame)) = system.recv_until(Instant::ZERO + elapsed)? {
            bus.send(&frame)?;
        }
        while let Some(event) = system.virtual_bus_mut().poll_event() {
            let operating = match &event.event {
                StationEvent::Controller(ControllerEvent::Operating { node }) => Some(*node),
                _ => None,
            };
            on_event(event.at - Instant::ZERO, event.event);
            if operating.is_some() && operating == hand_over {
                hand(system, operating);
            }
        }
        system.virtual_bus_mut().take_recording();
        let until = bus.now() + POLL;
        while let Some((_, frame)) = bus.recv_until(until)? {
            system.send(&frame)?;
        }
    }
}

/// Hands `node` over to whoever else is on the bus.
fn hand(system: &mut EnergyBusBus, node: Option<NodeId>) {
    let (Some(node), Some((id, _))) = (node, controller(system)) else {
        return;
    };
    if let Some(Station::Controller(c)) = system.virtual_bus_mut().node_mut(id) {
        c.hand_over(node);
    }
}

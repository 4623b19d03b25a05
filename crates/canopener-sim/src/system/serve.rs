//! A simulated system ([`SimulatedSystem`]) on real buses, in real time: each bridged network's simulated bus
//! meets the real bus where the monitor would be connected (the wiring's root), so a tool on the real
//! bus sees exactly what a monitor there would: devices beyond a cut vanish from it while they keep
//! talking among themselves on their own segment. Faults change while running through commands
//! ([`SimulatedSystem::command`]), for example from standard input ([`stdin_commands`]).

use std::sync::mpsc::{Receiver, TryRecvError, channel};
use std::time::Duration;

use canopener_can::Instant;

use crate::system::files::SystemError;
use crate::system::sim::SimulatedSystem;
use canopener_link::link::{BusLink, Link};

/// The longest the real buses are read before the simulation catches up with the wall clock.
const POLL: Duration = Duration::from_millis(2);

/// What [`serve`] reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ServeReport {
    /// A command was applied.
    Applied {
        /// The command as given.
        command: String,
    },
    /// A command was refused: why.
    Refused {
        /// The command as given.
        command: String,
        /// What is wrong with it.
        reason: String,
    },
}

/// Lines of standard input as commands, read on a thread of their own; the channel closes at the end
/// of the input.
pub fn stdin_commands() -> Receiver<String> {
    let (sender, receiver) = channel();
    std::thread::spawn(move || {
        for line in std::io::stdin().lines() {
            let Ok(line) = line else { break };
            if !line.trim().is_empty() && sender.send(line).is_err() {
                break;
            }
        }
    });
    receiver
}

/// Runs `sim` against `buses` (network number, real bus) until a bus link is cancelled, applying the
/// `commands` as they come and reporting each to `on_report`.
pub fn serve(
    sim: &mut SimulatedSystem,
    mut buses: Vec<(u32, BusLink)>,
    commands: &Receiver<String>,
    mut on_report: impl FnMut(ServeReport),
) -> Result<(), SystemError> {
    let Some(first) = buses.first() else {
        return Ok(());
    };
    let started = first.1.now();
    let slice = POLL / u32::try_from(buses.len()).unwrap_or(u32::MAX);
    let mut commands_open = true;
    loop {
        if buses.iter().any(|(_, bus)| bus.is_cancelled()) {
            return Ok(());
        }
        while commands_open {
            match commands.try_recv() {
                Ok(command) => on_report(match sim.command(&command) {
                    Ok(()) => ServeReport::Applied { command },
                    Err(err) => ServeReport::Refused {
                        command,
                        reason: err.to_string(),
                    },
                }),
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => commands_open = false,
            }
        }
        // `buses` is not empty (checked above); its first bus's clock is the simulation's.
        let elapsed = buses
            .first()
            .map_or(started, |(_, bus)| bus.now())
            .saturating_duration_since(started);
        let virtual_now = Instant::ZERO + elapsed;
        let mut links = sim.links();
        for (net, link) in links.iter_mut() {
            // What the simulated devices said by now, onto the real bus of their network.
            while let Some((_, frame)) = link.recv_until(virtual_now)? {
                if let Some((_, bus)) = buses.iter_mut().find(|(n, _)| n == net) {
                    bus.send(&frame)?;
                }
            }
        }
        for (net, bus) in buses.iter_mut() {
            let until = bus.now() + slice;
            while let Some((_, frame)) = bus.recv_until(until)? {
                if let Some((_, link)) = links.iter_mut().find(|(n, _)| n == net) {
                    link.send(&frame)?;
                }
            }
        }
    }
}

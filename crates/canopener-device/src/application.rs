//! The application behind a device's object dictionary (e.g. CiA 401 generic I/O): what it does when
//! the network writes an entry, and which entries it changes on its own.

use canopener_can::Instant;
use canopener_od::{DynamicOd, ObjectKey};
use canopener_wire::NodeId;

/// What an application did to the object dictionary, for the device to act on: mapped entries that
/// changed (TPDOs with event-driven transmission types send them) and TPDOs to send at once (CiA 401
/// input interrupts).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct AppChanges {
    /// Entries whose value the application changed.
    pub changed: Vec<ObjectKey>,
    /// TPDO numbers (1-based) to send now, whatever their mapping changes say.
    pub trigger_tpdos: Vec<u16>,
}

impl AppChanges {
    /// Nothing changed.
    pub fn none() -> AppChanges {
        AppChanges::default()
    }

    /// Whether there is nothing to act on.
    pub fn is_empty(&self) -> bool {
        self.changed.is_empty() && self.trigger_tpdos.is_empty()
    }
}

/// The application side of a device. The device calls it with the current time (sans-IO, like every
/// core): after an entry was written from the network, when its deadline passes, and when it starts.
pub trait Application {
    /// The device (re)started its application (power-on or NMT reset application): set up the
    /// entries the application owns.
    fn reset(&mut self, now: Instant, od: &mut DynamicOd) -> AppChanges;

    /// An entry was written from the network (SDO download or RPDO).
    fn on_write(&mut self, now: Instant, key: ObjectKey, od: &mut DynamicOd) -> AppChanges;

    /// The deadline from [`Application::poll_timeout`] passed.
    fn handle_timeout(&mut self, now: Instant, od: &mut DynamicOd) -> AppChanges;

    /// When the application next wants [`Application::handle_timeout`], if ever.
    fn poll_timeout(&self) -> Option<Instant>;

    /// An SDO download of `data` to `key` passed the dictionary's own checks and is about to be
    /// stored: `Err` refuses it with that SDO abort code (an application whose objects take only
    /// some values in some states). By default every download is taken.
    fn check_write(&self, _key: ObjectKey, _data: &[u8], _od: &DynamicOd) -> Result<(), u32> {
        Ok(())
    }

    /// The device reset its communication (after power-on and reset node too, and when LSS made a
    /// new node-ID active): it now runs with `node_id`, `None` while it has none (LSS
    /// unconfigured). By default nothing happens.
    fn reset_communication(
        &mut self,
        _now: Instant,
        _node_id: Option<NodeId>,
        _od: &mut DynamicOd,
    ) -> AppChanges {
        AppChanges::none()
    }
}

/// An application that does nothing: a device that only holds its object dictionary.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NoApplication;

impl Application for NoApplication {
    fn reset(&mut self, _now: Instant, _od: &mut DynamicOd) -> AppChanges {
        AppChanges::none()
    }

    fn on_write(&mut self, _now: Instant, _key: ObjectKey, _od: &mut DynamicOd) -> AppChanges {
        AppChanges::none()
    }

    fn handle_timeout(&mut self, _now: Instant, _od: &mut DynamicOd) -> AppChanges {
        AppChanges::none()
    }

    fn poll_timeout(&self) -> Option<Instant> {
        None
    }
}

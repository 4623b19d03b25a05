//! A numbered stream of JSON events that many browsers follow at their own pace: the producer (a
//! monitor or run thread) appends, every server-sent-event stream reads what came after the last
//! number it sent. The last [`RING`] events are kept, so a browser that reconnects with
//! `Last-Event-ID` misses nothing that is still kept, and one that fell further behind is told to
//! start over (its stream ends; the page reloads the state) instead of slowing the producer down.

use std::collections::VecDeque;
use std::sync::{Arc, Mutex, PoisonError};

use tokio::sync::watch;

/// How many events are kept for streams that are behind or reconnect.
pub const RING: usize = 16_384;

/// One event: its number (from 1) and its JSON text.
pub type Numbered = (u64, Arc<str>);

/// A stream fell so far behind that events it has not sent are no longer kept.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Lagged;

/// The stream (see the [module docs](self)).
#[derive(Debug)]
pub struct EventRing {
    kept: Mutex<VecDeque<Numbered>>,
    last: watch::Sender<u64>,
}

impl Default for EventRing {
    fn default() -> Self {
        EventRing {
            kept: Mutex::new(VecDeque::new()),
            last: watch::channel(0).0,
        }
    }
}

impl EventRing {
    /// Appends events (from any thread) and wakes the streams; returns the number of the last.
    pub fn publish(&self, events: impl IntoIterator<Item = String>) -> u64 {
        self.publish_with(events, |last| last)
    }

    /// Like [`EventRing::publish`], running `also` under the same lock, so that what it records
    /// (a snapshot) is consistent with the number returned.
    pub fn publish_with<T>(
        &self,
        events: impl IntoIterator<Item = String>,
        also: impl FnOnce(u64) -> T,
    ) -> T {
        let mut kept = self.kept.lock().unwrap_or_else(PoisonError::into_inner);
        let mut last = *self.last.borrow();
        for text in events {
            last += 1;
            kept.push_back((last, Arc::from(text)));
            if kept.len() > RING {
                kept.pop_front();
            }
        }
        let result = also(last);
        self.last.send_replace(last);
        result
    }

    /// The number of the last event (0 before the first): how many were published.
    pub fn last(&self) -> u64 {
        *self.last.borrow()
    }

    /// The events after number `after`, or [`Lagged`] when some of them are no longer kept.
    pub fn after(&self, after: u64) -> Result<Vec<Numbered>, Lagged> {
        let kept = self.kept.lock().unwrap_or_else(PoisonError::into_inner);
        let Some(first) = kept.front().map(|(n, _)| *n) else {
            return Ok(Vec::new());
        };
        if after + 1 < first {
            return Err(Lagged);
        }
        let skip = usize::try_from(after + 1 - first).unwrap_or(usize::MAX);
        Ok(kept.iter().skip(skip).cloned().collect())
    }

    /// Whether events after `after` are still kept (a reconnecting stream can resume there).
    pub fn can_resume(&self, after: u64) -> bool {
        after <= self.last() && self.after(after).is_ok()
    }

    /// A receiver woken at every publication.
    pub fn subscribe(&self) -> watch::Receiver<u64> {
        self.last.subscribe()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texts(events: &[Numbered]) -> Vec<(u64, &str)> {
        events.iter().map(|(n, t)| (*n, &**t)).collect()
    }

    #[test]
    fn streams_read_what_came_after_their_last_number() {
        let ring = EventRing::default();
        assert_eq!(ring.after(0), Ok(Vec::new()));
        assert_eq!(ring.publish(["a".to_owned(), "b".to_owned()]), 2);
        assert_eq!(ring.publish(["c".to_owned()]), 3);
        assert_eq!(texts(&ring.after(0).unwrap()), [(1, "a"), (2, "b"), (3, "c")]);
        assert_eq!(texts(&ring.after(2).unwrap()), [(3, "c")]);
        assert!(ring.after(3).unwrap().is_empty());
        assert_eq!(ring.last(), 3);
    }

    #[test]
    fn a_stream_behind_the_kept_events_is_told_it_lagged() {
        let ring = EventRing::default();
        ring.publish((0..RING + 10).map(|i| i.to_string()));
        assert_eq!(ring.after(5), Err(Lagged));
        assert!(!ring.can_resume(5));
        assert!(ring.can_resume(10));
        let tail = ring.after(ring.last() - 1).unwrap();
        assert_eq!(texts(&tail), [(ring.last(), &*(RING + 9).to_string())]);
    }

    #[test]
    fn a_snapshot_taken_under_the_lock_carries_the_number_of_its_last_event() {
        let ring = EventRing::default();
        let seen = ring.publish_with(vec!["x".to_owned(), "y".to_owned()], |last| last);
        assert_eq!(seen, 2);
        assert_eq!(ring.last(), 2);
    }
}

//! The hand-over of twin re-fit requests from the analysis thread to the re-fit thread: one
//! slot per channel, served in the order the channels asked.
//!
//! Why not a plain queue: every channel asks at the same sample times (every
//! `twin.refit_period_s`), so a short queue turns most of a burst away (66 channels: 62 of 132
//! fits dropped) while a long one could hold many stale requests of one channel. Here a channel
//! waiting for its fit keeps its place in line; a newer request of the same channel replaces
//! the waiting one (the older fit would be worthless next to it), and that replacement is the
//! only way a fit is dropped: it is counted and reported by the caller. Bounded by the number
//! of channels.

use super::TwinRequest;
use crate::messages::ChannelId;
use std::collections::{BTreeMap, VecDeque};
use std::sync::{Arc, Condvar, Mutex, PoisonError};

#[derive(Default)]
struct State {
    /// Channels with a waiting request, in the order they first asked.
    order: VecDeque<ChannelId>,
    waiting: BTreeMap<ChannelId, TwinRequest>,
    closed: bool,
}

#[derive(Default)]
struct Shared {
    state: Mutex<State>,
    ready: Condvar,
}

/// The analysis thread's end.
pub struct TwinRequests {
    shared: Arc<Shared>,
}

/// The re-fit thread's end.
pub struct TwinRequestQueue {
    shared: Arc<Shared>,
}

/// A new, empty hand-over.
pub fn twin_requests() -> (TwinRequests, TwinRequestQueue) {
    let shared = Arc::new(Shared::default());
    (
        TwinRequests {
            shared: shared.clone(),
        },
        TwinRequestQueue { shared },
    )
}

impl TwinRequests {
    /// Puts `request` in line; returns the request of the same channel it replaced (a dropped
    /// fit), if one was still waiting.
    pub fn put(&self, request: TwinRequest) -> Option<TwinRequest> {
        let mut state = self
            .shared
            .state
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        let channel = request.channel.clone();
        let replaced = state.waiting.insert(channel.clone(), request);
        if replaced.is_none() {
            state.order.push_back(channel);
        }
        drop(state);
        self.shared.ready.notify_one();
        replaced
    }
}

impl Drop for TwinRequests {
    fn drop(&mut self) {
        let mut state = self
            .shared
            .state
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        state.closed = true;
        drop(state);
        self.shared.ready.notify_all();
    }
}

impl TwinRequestQueue {
    /// The next request in line, waiting for one; `None` once the analysis end is gone and
    /// nothing waits.
    pub fn take(&self) -> Option<TwinRequest> {
        let mut state = self
            .shared
            .state
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        loop {
            while let Some(channel) = state.order.pop_front() {
                if let Some(request) = state.waiting.remove(&channel) {
                    return Some(request);
                }
            }
            if state.closed {
                return None;
            }
            state = self
                .shared
                .ready
                .wait(state)
                .unwrap_or_else(PoisonError::into_inner);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::Band;
    use crate::bearing::FaultFrequencies;

    fn request(sensor: &str, end_sample: u64) -> TwinRequest {
        let f = FaultFrequencies {
            shaft: 1.0,
            ftf: 0.4,
            bpfo: 3.0,
            bpfi: 5.0,
            bsf: 2.0,
            two_bsf: 4.0,
        };
        TwinRequest {
            channel: ChannelId {
                sensor: sensor.into(),
                axis: "radial".into(),
            },
            end_sample,
            fs_hz: 1000.0,
            freqs: f,
            bands: [Band::new(100.0, 200.0); 3],
            samples: Vec::new(),
            flagged: None,
            agreed: None,
        }
    }

    #[test]
    fn channels_are_served_in_turn_and_only_a_newer_request_drops_one() {
        let (tx, rx) = twin_requests();
        for sensor in ["a", "b", "c"] {
            assert!(tx.put(request(sensor, 10)).is_none());
        }
        // "a" asks again before its turn: its waiting request is replaced, it keeps its place.
        let dropped = tx.put(request("a", 20)).unwrap();
        assert_eq!(dropped.end_sample, 10);
        let served: Vec<(String, u64)> = (0..3)
            .map(|_| {
                let r = rx.take().unwrap();
                (r.channel.sensor, r.end_sample)
            })
            .collect();
        assert_eq!(
            served,
            [("a".into(), 20), ("b".into(), 10), ("c".into(), 10)]
        );
        drop(tx);
        assert!(rx.take().is_none());
    }

    #[test]
    fn the_queue_ends_after_the_last_request_is_served() {
        let (tx, rx) = twin_requests();
        let worker = std::thread::spawn(move || {
            let mut served = 0;
            while rx.take().is_some() {
                served += 1;
            }
            served
        });
        for i in 0..100 {
            tx.put(request(&format!("s{i}"), 1));
        }
        drop(tx);
        assert_eq!(worker.join().unwrap(), 100);
    }
}

//! A bounded queue from a blocking thread (the iceoryx2 port thread) to the async side.
//!
//! std's `sync_channel` and tokio's `mpsc` can only refuse or wait when full; a live sensor
//! wants the opposite, the newest data, so this queue can also drop the *oldest* item. Which
//! policy applies is the caller's choice ([`WhenFull`]): `DropOldest` for live sensors (every
//! drop counted, and since whole transport batches are dropped before the sequence tracker,
//! the loss also shows as exact gaps), `Block` for tests and replay, where the producer waits
//! and pushes back into the transport instead.
//!
//! Synchronisation: one `Mutex` around the deque (held for a push or a pop only); a `Condvar`
//! wakes a producer waiting for room; a tokio `Notify` wakes the async consumer.

use std::collections::VecDeque;
use std::sync::{Arc, Condvar, Mutex};
use tokio::sync::Notify;

/// What a push does when the queue is full.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WhenFull {
    /// Drop the oldest item, count it, push.
    DropOldest,
    /// Wait until the consumer takes an item.
    Block,
}

#[derive(Debug)]
struct State<T> {
    items: VecDeque<T>,
    dropped: u64,
    closed: bool,
}

#[derive(Debug)]
struct Shared<T> {
    state: Mutex<State<T>>,
    room: Condvar,
    ready: Notify,
    capacity: usize,
    when_full: WhenFull,
}

/// The producing end (blocking).
#[derive(Debug)]
pub struct Producer<T> {
    shared: Arc<Shared<T>>,
}

/// The consuming end (async).
#[derive(Debug)]
pub struct Consumer<T> {
    shared: Arc<Shared<T>>,
}

/// A queue of at most `capacity` (≥ 1) items.
pub fn bounded<T>(capacity: usize, when_full: WhenFull) -> (Producer<T>, Consumer<T>) {
    let shared = Arc::new(Shared {
        state: Mutex::new(State {
            items: VecDeque::with_capacity(capacity.max(1)),
            dropped: 0,
            closed: false,
        }),
        room: Condvar::new(),
        ready: Notify::new(),
        capacity: capacity.max(1),
        when_full,
    });
    (
        Producer {
            shared: shared.clone(),
        },
        Consumer { shared },
    )
}

impl<T> Producer<T> {
    /// Pushes `item` by the queue's policy. Returns `false` if the consumer is gone.
    pub fn push(&self, item: T) -> bool {
        let shared = &*self.shared;
        let Ok(mut state) = shared.state.lock() else {
            return false;
        };
        loop {
            if state.closed {
                return false;
            }
            if state.items.len() < shared.capacity {
                break;
            }
            match shared.when_full {
                WhenFull::DropOldest => {
                    state.items.pop_front();
                    state.dropped += 1;
                    break;
                }
                WhenFull::Block => match shared.room.wait(state) {
                    Ok(guard) => state = guard,
                    Err(_) => return false,
                },
            }
        }
        state.items.push_back(item);
        drop(state);
        shared.ready.notify_one();
        true
    }
}

impl<T> Producer<T> {
    /// Whether a push now would find the queue full.
    pub fn is_full(&self) -> bool {
        self.shared
            .state
            .lock()
            .map_or(true, |state| state.items.len() >= self.shared.capacity)
    }
}

impl<T> Drop for Producer<T> {
    fn drop(&mut self) {
        if let Ok(mut state) = self.shared.state.lock() {
            state.closed = true;
        }
        self.shared.ready.notify_one();
    }
}

impl<T> Consumer<T> {
    /// The next item and the number of items dropped since the previous call; `None` once the
    /// producer is gone and the queue is empty.
    pub async fn pop(&self) -> Option<(T, u64)> {
        loop {
            // Register interest before checking, so a push between the check and the await
            // is not missed.
            let notified = self.shared.ready.notified();
            {
                let mut state = self.shared.state.lock().ok()?;
                if let Some(item) = state.items.pop_front() {
                    let dropped = std::mem::take(&mut state.dropped);
                    drop(state);
                    self.shared.room.notify_one();
                    return Some((item, dropped));
                }
                if state.closed {
                    return None;
                }
            }
            notified.await;
        }
    }
}

impl<T> Drop for Consumer<T> {
    fn drop(&mut self) {
        if let Ok(mut state) = self.shared.state.lock() {
            state.closed = true;
        }
        self.shared.room.notify_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn drop_oldest_counts_and_keeps_the_newest() {
        let (tx, rx) = bounded(2, WhenFull::DropOldest);
        for i in 0..5 {
            assert!(tx.push(i));
        }
        assert_eq!(rx.pop().await, Some((3, 3)));
        assert_eq!(rx.pop().await, Some((4, 0)));
        drop(tx);
        assert_eq!(rx.pop().await, None);
    }

    #[tokio::test]
    async fn block_waits_for_room_and_loses_nothing() {
        let (tx, rx) = bounded(1, WhenFull::Block);
        let producer = std::thread::spawn(move || {
            for i in 0..1000u32 {
                assert!(tx.push(i));
            }
        });
        let mut expected = 0;
        while let Some((item, dropped)) = rx.pop().await {
            assert_eq!((item, dropped), (expected, 0));
            expected += 1;
        }
        producer.join().unwrap();
        assert_eq!(expected, 1000);
    }

    #[test]
    fn push_after_consumer_is_gone_returns_false() {
        let (tx, rx) = bounded::<u8>(1, WhenFull::Block);
        assert!(tx.push(1));
        drop(rx);
        assert!(!tx.push(2));
    }
}

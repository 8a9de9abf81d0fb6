//! A bounded queue from a blocking thread (the iceoryx2 port thread) to the async side.
//!
//! std's `sync_channel` and tokio's `mpsc` can only refuse or wait when full; a live sensor
//! wants the opposite, the newest data, so this queue can also drop the *oldest* item. Which
//! policy applies is the caller's choice ([`WhenFull`]): `DropOldest` for live sensors (every
//! drop counted, and since whole transport batches are dropped before the sequence tracker,
//! the loss also shows as exact gaps), `Block` for tests and replay, where the producer waits
//! and pushes back into the transport instead.
//!
//! Storage: a `VecDeque` of fixed capacity (allocated once, never grown) under a mutex, held
//! for a push or a pop only; an item is a whole transport batch, so the lock is taken per
//! batch, never per sample. A producer that must `Block` waits on a `Condvar`
//! of that mutex, signalled after each pop; a tokio `Notify` wakes the async consumer.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};
use std::time::Duration;
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
struct Shared<T> {
    items: Mutex<VecDeque<T>>,
    capacity: usize,
    /// Items dropped since the consumer last looked.
    dropped: AtomicU64,
    /// Either end is gone.
    closed: AtomicBool,
    /// A blocked producer waits here (on `items`) for room.
    room: Condvar,
    ready: Notify,
    when_full: WhenFull,
}

impl<T> Shared<T> {
    /// The items, locked. A panic while the lock was held cannot have left a `VecDeque`
    /// half-changed, so a poisoned lock is used as it is.
    fn items(&self) -> MutexGuard<'_, VecDeque<T>> {
        self.items.lock().unwrap_or_else(PoisonError::into_inner)
    }

    fn close(&self) {
        self.closed.store(true, Ordering::Release);
        // Taking the lock orders this with a producer between its check and its wait.
        drop(self.items());
        self.room.notify_all();
        self.ready.notify_one();
    }
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
    let capacity = capacity.max(1);
    let shared = Arc::new(Shared {
        items: Mutex::new(VecDeque::with_capacity(capacity)),
        capacity,
        dropped: AtomicU64::new(0),
        closed: AtomicBool::new(false),
        room: Condvar::new(),
        ready: Notify::new(),
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
        if shared.closed.load(Ordering::Acquire) {
            return false;
        }
        let mut items = shared.items();
        if items.len() >= shared.capacity {
            match shared.when_full {
                WhenFull::DropOldest => {
                    items.pop_front();
                    shared.dropped.fetch_add(1, Ordering::Relaxed);
                }
                WhenFull::Block => {
                    while items.len() >= shared.capacity {
                        if shared.closed.load(Ordering::Acquire) {
                            return false;
                        }
                        // The consumer signals after each pop; the timeout is only a second
                        // guard.
                        items = shared
                            .room
                            .wait_timeout(items, Duration::from_millis(50))
                            .unwrap_or_else(PoisonError::into_inner)
                            .0;
                    }
                }
            }
        }
        items.push_back(item);
        drop(items);
        shared.ready.notify_one();
        true
    }

    /// Whether a push now would find the queue full.
    pub fn is_full(&self) -> bool {
        self.shared.items().len() >= self.shared.capacity
    }
}

impl<T> Drop for Producer<T> {
    fn drop(&mut self) {
        self.shared.close();
    }
}

impl<T> Consumer<T> {
    /// The next item and the number of items dropped since the previous call; `None` once the
    /// producer is gone and the queue is empty.
    pub async fn pop(&self) -> Option<(T, u64)> {
        let shared = &*self.shared;
        loop {
            // Register interest before checking, so a push between the check and the await
            // is not missed.
            let notified = shared.ready.notified();
            // Read `closed` before popping: an item pushed before the close is still taken.
            let closed = shared.closed.load(Ordering::Acquire);
            let popped = shared.items().pop_front();
            if let Some(item) = popped {
                let dropped = shared.dropped.swap(0, Ordering::Relaxed);
                if shared.when_full == WhenFull::Block {
                    shared.room.notify_one();
                }
                return Some((item, dropped));
            }
            if closed {
                return None;
            }
            notified.await;
        }
    }
}

impl<T> Drop for Consumer<T> {
    fn drop(&mut self) {
        self.shared.close();
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

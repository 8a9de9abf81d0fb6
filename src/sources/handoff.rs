//! A bounded queue from a blocking thread (the iceoryx2 port thread) to the async side.
//!
//! std's `sync_channel` and tokio's `mpsc` can only refuse or wait when full; a live sensor
//! wants the opposite, the newest data, so this queue can also drop the *oldest* item. Which
//! policy applies is the caller's choice ([`WhenFull`]): `DropOldest` for live sensors (every
//! drop counted, and since whole transport batches are dropped before the sequence tracker,
//! the loss also shows as exact gaps), `Block` for tests and replay, where the producer waits
//! and pushes back into the transport instead.
//!
//! Storage: crossbeam's lock-free `ArrayQueue` (fixed capacity, allocated once); its
//! `force_push` hands back the oldest item, which `DropOldest` counts. A producer that must
//! `Block` waits on a `Condvar` that the consumer signals after each pop; a tokio `Notify` wakes
//! the async consumer.

use crossbeam_queue::ArrayQueue;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex};
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
    items: ArrayQueue<T>,
    /// Items dropped since the consumer last looked.
    dropped: AtomicU64,
    /// Either end is gone.
    closed: AtomicBool,
    /// A blocked producer waits here for room (the mutex guards nothing but the wait).
    room_lock: Mutex<()>,
    room: Condvar,
    ready: Notify,
    when_full: WhenFull,
}

impl<T> Shared<T> {
    fn close(&self) {
        self.closed.store(true, Ordering::Release);
        // Taking the lock orders this with a producer between its check and its wait.
        drop(self.room_lock.lock());
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
    let shared = Arc::new(Shared {
        items: ArrayQueue::new(capacity.max(1)),
        dropped: AtomicU64::new(0),
        closed: AtomicBool::new(false),
        room_lock: Mutex::new(()),
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
        match shared.when_full {
            WhenFull::DropOldest => {
                if shared.items.force_push(item).is_some() {
                    shared.dropped.fetch_add(1, Ordering::Relaxed);
                }
            }
            WhenFull::Block => {
                let mut item = item;
                while let Err(back) = shared.items.push(item) {
                    item = back;
                    let Ok(guard) = shared.room_lock.lock() else {
                        return false;
                    };
                    if shared.closed.load(Ordering::Acquire) {
                        return false;
                    }
                    if shared.items.is_full() {
                        // The consumer signals under the lock after a pop; the timeout is only
                        // a second guard.
                        if shared
                            .room
                            .wait_timeout(guard, Duration::from_millis(50))
                            .is_err()
                        {
                            return false;
                        }
                    }
                }
            }
        }
        shared.ready.notify_one();
        true
    }
}

impl<T> Producer<T> {
    /// Whether a push now would find the queue full.
    pub fn is_full(&self) -> bool {
        self.shared.items.is_full()
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
            if let Some(item) = shared.items.pop() {
                let dropped = shared.dropped.swap(0, Ordering::Relaxed);
                if shared.when_full == WhenFull::Block {
                    drop(shared.room_lock.lock());
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

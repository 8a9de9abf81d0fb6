//! iceoryx2 source: [`FrameBatch`]es from the publish-subscribe service
//! `bearingd/accel/<sensor>`, decoded on a thread of its own straight out of shared memory.
//!
//! Why a thread: iceoryx2 ports are not `Send` and have no async API, so they must not live on
//! a tokio worker. The thread waits on the event service `bearingd/accel/<sensor>/wake` (the
//! publisher notifies after sending; a timed wait also polls, so a lost wake-up costs at most
//! [`POLL_PERIOD`]), and feeds every received sample's frames to the [`Assembler`] while the
//! sample is still loaned from shared memory: no copy of a batch is ever made (the publisher
//! wrote it in place too). Only the assembler's events (sample blocks, gaps, …) cross to the
//! async side, through a bounded [`handoff`](super::handoff) queue. The silence watch runs on
//! the thread as well; the async side only asks for the counters at the stats interval.
//!
//! Back-pressure ([`ShmSourceConfig::when_full`]): with `Block` a full hand-off makes the
//! thread stop taking samples, the subscriber's iceoryx2 buffer fills, and the publisher then
//! decides by its own strategy: wait (lossless; `firmware-sim` by default) or discard (a live
//! node; the receiver's sequence tracker reports the exact gap). With `DropOldest` the thread
//! keeps taking samples while the hand-off is full and drops them undecoded, counted as
//! `handoff_dropped` and seen as exact gaps. Nothing is ever dropped after the assembler.
//!
//! Ready handshake: a subscriber connects to a publisher only inside `receive()`; samples sent
//! before that can be lost. So, while it has received nothing, the thread notifies the event
//! service `bearingd/accel/<sensor>/ready` every [`POLL_PERIOD`] once the service has a
//! publisher and `receive()` has run; a publisher that must lose nothing waits for it.
//!
//! iceoryx2's own signal handling is disabled (tokio owns signals). The root path and the
//! file prefix are configurable ([`IoxSettings`]) so tests are isolated and so the files are
//! not put under a systemd `PrivateTmp=`.

use super::handoff::{self, WhenFull};
use super::{
    node_of, Assembler, EventSender, IngestEvent, SilenceWatch, SourceSummary, StatsTimer,
};
use crate::iox::{
    create_node, open_data_service, open_event_service, IoxSettings, ServiceNames, ShmError,
};
use iceoryx2::prelude::*;
use std::future::Future;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;
use tokio::time::Instant;

/// Longest wait of the port thread between checks.
pub const POLL_PERIOD: Duration = Duration::from_millis(20);

/// How the iceoryx2 source is set up.
#[derive(Debug, Clone)]
pub struct ShmSourceConfig {
    pub sensor: String,
    pub iox: IoxSettings,
    pub silence_timeout: Duration,
    /// Events (sample blocks and the like) between the port thread and the async side.
    pub handoff_capacity: usize,
    /// `Block`: back-pressure into iceoryx2 (the daemon); `DropOldest`: drop the batches
    /// waiting in iceoryx2 undecoded while the hand-off is full (see the module docs).
    pub when_full: WhenFull,
    /// Report the counters ([`IngestEvent::Stats`]) this often and when stopping; `None`: never.
    pub stats_interval: Option<Duration>,
}

/// Flags between the async side and the port thread.
#[derive(Default)]
struct Control {
    stop: AtomicBool,
    stats_wanted: AtomicBool,
}

/// Starts the port thread, waits until its ports exist, then runs until `shutdown`, the
/// consumer dropping `events`, or the thread failing.
pub async fn run(
    config: ShmSourceConfig,
    events: EventSender,
    shutdown: impl Future<Output = ()>,
) -> Result<SourceSummary, ShmError> {
    // The queue itself always waits: after the assembler nothing may be dropped.
    let (producer, consumer) =
        handoff::bounded::<IngestEvent>(config.handoff_capacity, WhenFull::Block);
    let control = Arc::new(Control::default());
    let (started_tx, started_rx) = tokio::sync::oneshot::channel::<Result<(), ShmError>>();
    let thread = {
        let control = control.clone();
        let config = config.clone();
        std::thread::Builder::new()
            .name(format!("iox2-{}", config.sensor))
            .spawn(move || port_thread(&config, producer, &control, started_tx))
            .map_err(|e| ShmError::Thread(e.to_string()))?
    };
    let join = |thread: std::thread::JoinHandle<SourceSummary>| async move {
        tokio::task::spawn_blocking(move || thread.join())
            .await
            .map_err(|e| ShmError::Thread(e.to_string()))?
            .map_err(|_| ShmError::Thread("the port thread panicked".into()))
    };
    match started_rx.await {
        Ok(Ok(())) => {}
        Ok(Err(e)) => {
            let _ = join(thread).await;
            return Err(e);
        }
        Err(_) => {
            let _ = join(thread).await;
            return Err(ShmError::Thread("port thread ended before starting".into()));
        }
    }
    let mut stats = StatsTimer::new(config.stats_interval);
    let mut consumer_gone = false;
    tokio::pin!(shutdown);
    loop {
        tokio::select! {
            biased;
            () = &mut shutdown => break,
            item = consumer.pop() => {
                let Some((event, _)) = item else { break };
                if events.send(event).await.is_err() {
                    consumer_gone = true;
                    break;
                }
            }
            () = stats.tick() => control.stats_wanted.store(true, Ordering::Relaxed),
        }
    }
    control.stop.store(true, Ordering::Relaxed);
    // What the thread has decoded still goes out (it stops within a poll period).
    if !consumer_gone {
        while let Some((event, _)) = consumer.pop().await {
            if events.send(event).await.is_err() {
                break;
            }
        }
    }
    drop(consumer);
    let summary = join(thread).await?;
    if stats.enabled() && !consumer_gone {
        // The final counters.
        let _ = events.send(IngestEvent::Stats(summary.stats)).await;
    }
    Ok(summary)
}

fn summary(assembler: &Assembler) -> SourceSummary {
    SourceSummary {
        stats: assembler.stats(),
        streams: assembler.streams(),
    }
}

/// The port thread: receives, decodes in place, hands the events over; returns the counters.
fn port_thread(
    config: &ShmSourceConfig,
    producer: handoff::Producer<IngestEvent>,
    control: &Control,
    started: tokio::sync::oneshot::Sender<Result<(), ShmError>>,
) -> SourceSummary {
    let names = ServiceNames::for_sensor(&config.sensor);
    let setup = (|| {
        let node = create_node(&config.iox)?;
        let data = open_data_service(&node, &names)?;
        let subscriber = data
            .subscriber_builder()
            .create()
            .map_err(|e| ShmError::Service {
                service: names.data.clone(),
                detail: format!("create subscriber: {e:?}"),
            })?;
        let wake = open_event_service(&node, &names.wake)?
            .listener_builder()
            .create()
            .map_err(|e| ShmError::Service {
                service: names.wake.clone(),
                detail: format!("create listener: {e:?}"),
            })?;
        let ready = open_event_service(&node, &names.ready)?
            .notifier_builder()
            .create()
            .map_err(|e| ShmError::Service {
                service: names.ready.clone(),
                detail: format!("create notifier: {e:?}"),
            })?;
        Ok((node, data, subscriber, wake, ready))
    })();
    let (_node, data, subscriber, wake, ready) = match setup {
        Ok(ports) => {
            let _ = started.send(Ok(()));
            ports
        }
        Err(e) => {
            let _ = started.send(Err(e));
            return summary(&Assembler::new());
        }
    };
    let mut assembler = Assembler::new();
    let mut watch = SilenceWatch::new(config.silence_timeout);
    let mut out: Vec<IngestEvent> = Vec::with_capacity(64);
    let service = format!("service {}", names.data);
    let mut received_any = false;
    let stopped = || control.stop.load(Ordering::Relaxed);
    // Hands the events over, waiting for room; `false` once the async side is gone.
    let hand_over = |out: &mut Vec<IngestEvent>| out.drain(..).all(|event| producer.push(event));
    while !stopped() {
        // Woken by the publisher, or after POLL_PERIOD at the latest; the wake-ups themselves
        // carry nothing.
        let _ = wake.timed_wait(|_| {}, POLL_PERIOD);
        while !stopped() {
            let Ok(Some(sample)) = subscriber.receive() else {
                break;
            };
            received_any = true;
            if config.when_full == WhenFull::DropOldest && producer.is_full() {
                assembler.count_handoff_drop(1);
                continue;
            }
            let now = Instant::now();
            // Decoded in place: the frames are read from the loaned shared-memory sample.
            match sample.payload().valid_frames() {
                Ok(frames) => {
                    for frame in frames {
                        if let Some(node) = node_of(frame.can_id) {
                            watch.heard(node, now);
                        }
                        assembler.push(frame.can_id, frame.bytes(), &mut out);
                    }
                }
                Err(e) => assembler.refuse_batch(format!("{service}: {e}"), &mut out),
            }
            drop(sample);
            if !hand_over(&mut out) {
                return summary(&assembler);
            }
        }
        watch.check(Instant::now(), &mut assembler, &mut out);
        if control.stats_wanted.swap(false, Ordering::Relaxed) {
            out.push(IngestEvent::Stats(assembler.stats()));
        }
        if !hand_over(&mut out) {
            break;
        }
        if !received_any && data.dynamic_config().number_of_publishers() > 0 {
            let _ = ready.notify();
        }
    }
    summary(&assembler)
}

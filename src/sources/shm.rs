//! iceoryx2 source: [`FrameBatch`]es from the publish-subscribe service
//! `bearingd/accel/<sensor>`, on a thread of its own.
//!
//! Why a thread: iceoryx2 ports are not `Send` and have no async API, so they must not live on
//! a tokio worker. The thread waits on the event service `bearingd/accel/<sensor>/wake` (the
//! publisher notifies after sending; a timed wait also polls, so a lost wake-up costs at most
//! [`POLL_PERIOD`]), drains the subscriber and hands the batches to the async side through a
//! bounded [`handoff`](super::handoff) queue, where the shared assembler decodes them.
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
    create_node, open_data_service, open_event_service, FrameBatch, IoxSettings, ServiceNames,
    ShmError,
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
    /// Batches between the port thread and the async side.
    pub handoff_capacity: usize,
    /// `DropOldest` for live sensors; `Block` to push back into iceoryx2 instead.
    pub when_full: WhenFull,
    /// Report the counters ([`IngestEvent::Stats`]) this often and when stopping; `None`: never.
    pub stats_interval: Option<Duration>,
}

/// Starts the port thread, waits until its ports exist, then runs until `shutdown`, the
/// consumer dropping `events`, or the thread failing.
pub async fn run(
    config: ShmSourceConfig,
    events: EventSender,
    shutdown: impl Future<Output = ()>,
) -> Result<SourceSummary, ShmError> {
    let (producer, consumer) =
        handoff::bounded::<Box<FrameBatch>>(config.handoff_capacity, config.when_full);
    let stop = Arc::new(AtomicBool::new(false));
    let (started_tx, started_rx) = tokio::sync::oneshot::channel::<Result<(), ShmError>>();
    let thread = {
        let stop = stop.clone();
        let config = config.clone();
        std::thread::Builder::new()
            .name(format!("iox2-{}", config.sensor))
            .spawn(move || port_thread(&config, producer, &stop, started_tx))
            .map_err(|e| ShmError::Thread(e.to_string()))?
    };
    let stop_thread = || {
        stop.store(true, Ordering::Relaxed);
    };
    match started_rx.await {
        Ok(Ok(())) => {}
        Ok(Err(e)) => {
            let _ = thread.join();
            return Err(e);
        }
        Err(_) => {
            let _ = thread.join();
            return Err(ShmError::Thread("port thread ended before starting".into()));
        }
    }
    let mut assembler = Assembler::new();
    let mut watch = SilenceWatch::new(config.silence_timeout);
    let mut out: Vec<IngestEvent> = Vec::with_capacity(64);
    let mut tick = tokio::time::interval((watch.timeout() / 4).max(Duration::from_millis(10)));
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    let mut stats = StatsTimer::new(config.stats_interval);
    tokio::pin!(shutdown);
    loop {
        tokio::select! {
            biased;
            () = &mut shutdown => break,
            item = consumer.pop() => {
                let Some((batch, dropped)) = item else { break };
                assembler.count_handoff_drop(dropped);
                let now = Instant::now();
                match batch.valid_frames() {
                    Ok(frames) => {
                        for frame in frames {
                            if let Some(node) = node_of(frame.can_id) {
                                watch.heard(node, now);
                            }
                            assembler.push(frame.can_id, frame.bytes(), &mut out);
                        }
                    }
                    Err(e) => assembler.refuse_batch(format!("service bearingd/accel/{}: {e}", config.sensor), &mut out),
                }
            }
            _ = tick.tick() => watch.check(Instant::now(), &mut assembler, &mut out),
            () = stats.tick() => out.push(IngestEvent::Stats(assembler.stats())),
        }
        for event in out.drain(..) {
            if events.send(event).await.is_err() {
                stop_thread();
                drop(consumer);
                let _ = thread.join();
                return Ok(summary(&assembler));
            }
        }
    }
    stop_thread();
    drop(consumer);
    let _ = tokio::task::spawn_blocking(move || thread.join()).await;
    if stats.enabled() {
        // The final counters; a consumer already gone needs none.
        let _ = events.send(IngestEvent::Stats(assembler.stats())).await;
    }
    Ok(summary(&assembler))
}

fn summary(assembler: &Assembler) -> SourceSummary {
    SourceSummary {
        stats: assembler.stats(),
        streams: assembler.streams(),
    }
}

fn port_thread(
    config: &ShmSourceConfig,
    producer: handoff::Producer<Box<FrameBatch>>,
    stop: &AtomicBool,
    started: tokio::sync::oneshot::Sender<Result<(), ShmError>>,
) {
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
            return;
        }
    };
    let mut received_any = false;
    while !stop.load(Ordering::Relaxed) {
        // Woken by the publisher, or after POLL_PERIOD at the latest; the wake-ups themselves
        // carry nothing.
        let _ = wake.timed_wait(|_| {}, POLL_PERIOD);
        loop {
            match subscriber.receive() {
                Ok(Some(sample)) => {
                    received_any = true;
                    if !producer.push(Box::new(*sample.payload())) {
                        return;
                    }
                }
                Ok(None) => break,
                Err(_) => break,
            }
        }
        if !received_any && data.dynamic_config().number_of_publishers() > 0 {
            let _ = ready.notify();
        }
    }
}

//! The iceoryx2 ends of the alert service: the daemon's publisher and the subscriber that
//! `bearingd alerts` and the tests use.
//!
//! Service shape (the publisher creates it; subscribers only open it, so a subscriber started
//! first cannot create it with a shape the daemon would then refuse):
//! - publish-subscribe `<alerts_service>` with payload [`Alert`], a history of
//!   [`history_size_for`](super::tracker::history_size_for) the daemon's channels (a late
//!   subscriber receives the active alerts), a subscriber buffer of [`SUBSCRIBER_BUFFER`]
//!   alerts, and safe overflow: a subscriber that does not keep up loses its oldest alerts,
//!   never the newest, and sees the loss as a gap in `sequence` ([`Received::Lost`]);
//!   one publisher at most, the daemon's;
//! - event `<alerts_service>/wake`, notified after every alert, so a subscriber sleeps in the
//!   kernel instead of polling; one notifier at most.
//!
//! Authenticity (issue 32, docs/ALERTS.md "Trust model"): the daemon creates both exclusively
//! and never opens a service another process created ([`AlertError::Taken`] names its owner);
//! the subscriber checks that the root, both services and the publisher belong to the
//! expected user (`verify.rs`) and judges sequence numbers with `sequence.rs`.
//!
//! The daemon publishes on the thread that decides the alert (the analysis thread): iceoryx2's
//! send and notify never block, and no other thread has to wake up before the alert leaves.
//! Its ports are therefore of the `ipc_threadsafe` variant (the same shared memory as the
//! subscribers' `ipc`), shared with a keeper thread: iceoryx2 hands the history to a new
//! subscriber when the publisher next updates its connections, and the keeper does that every
//! [`CONNECTION_PERIOD`], also while no alert is sent. The keeper runs in SCHED_IDLE, so on a
//! busy machine it may not run for a while; the publisher updates its connections once more
//! when it finishes, so that a subscriber that connected meanwhile still gets the history
//! before the service closes.

use super::payload::Alert;
pub use super::sequence::Received;
use super::sequence::SequenceCheck;
use super::verify::verify_service;
use super::PublisherSummary;
use crate::iox::owner::{claim, inspect, Claim, Taken};
use crate::iox::{create_node, wake_service, IoxSettings};
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::event::PortFactory as EventFactory;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;
use iceoryx2::service::static_config::StaticConfig;
use std::sync::mpsc;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Alerts a subscriber's buffer holds before the oldest is overwritten.
pub const SUBSCRIBER_BUFFER: usize = 256;
/// How often the publisher looks for new subscribers (to hand them the history).
pub const CONNECTION_PERIOD: Duration = Duration::from_millis(50);

/// The publisher's iceoryx2 variant: ports shared between the analysis and keeper threads.
type Shared = ipc_threadsafe::Service;

/// Why the alert service could not be used. Messages name the service and the root path.
#[derive(Debug, thiserror::Error)]
pub enum AlertError {
    #[error("alert service {service}: {detail}")]
    Service { service: String, detail: String },
    /// The service (or its wake event) exists and is not this daemon's to use.
    #[error("alert service {service} (iceoryx2 root {root}): {why}; {owners}. bearingd never opens a service another process created: stop that process, or give this daemon its own outputs.alerts_service")]
    Taken {
        service: String,
        root: String,
        why: String,
        owners: String,
    },
    /// A subscriber's check of the service or of its publisher failed.
    #[error("alert service {service} (iceoryx2 root {root}) is not to be trusted: {why}")]
    Untrusted {
        service: String,
        root: String,
        why: String,
    },
    #[error("alert keeper thread: {0}")]
    Thread(String),
    #[error("alert #{sequence} could not be published on {service}: {detail}")]
    Publish {
        sequence: u64,
        service: String,
        detail: String,
    },
}

/// Where the alert service is.
#[derive(Debug, Clone)]
pub struct AlertServiceSettings {
    /// The publish-subscribe service name (`outputs.alerts_service`).
    pub service: String,
    pub iox: IoxSettings,
}

impl AlertServiceSettings {
    fn wake_name(&self) -> String {
        wake_service(&self.service)
    }

    fn error(&self, detail: impl Into<String>) -> AlertError {
        AlertError::Service {
            service: self.service.clone(),
            detail: format!("{} (iceoryx2 root {})", detail.into(), self.iox.root_name()),
        }
    }

    fn untrusted(&self, why: String) -> AlertError {
        AlertError::Untrusted {
            service: self.service.clone(),
            root: self.iox.root_name().to_string(),
            why,
        }
    }

    fn taken(&self, name: &str, taken: Taken) -> AlertError {
        AlertError::Taken {
            service: name.to_string(),
            root: self.iox.root_name().to_string(),
            why: taken.why,
            owners: taken.owners.to_string(),
        }
    }

    /// [`claim`] for `name`, a refusal as [`AlertError::Taken`].
    fn claim(
        &self,
        name: &str,
        pattern: MessagingPattern,
        fits: impl Fn(&StaticConfig) -> bool,
    ) -> Result<Claim, AlertError> {
        claim(&self.iox, name, pattern, fits)
            .map_err(|e| self.error(e.to_string()))?
            .map_err(|taken| self.taken(name, taken))
    }

    /// What to say when iceoryx2 refuses an exclusive creation: someone made it in between.
    fn lost_race(&self, name: &str, pattern: MessagingPattern, detail: String) -> AlertError {
        match inspect(&self.iox, name, pattern) {
            Ok(Some((_, owners))) => self.taken(
                name,
                Taken {
                    owners,
                    why: format!("another process created it at the same time ({detail})"),
                },
            ),
            _ => self.error(format!("create: {detail}")),
        }
    }

    fn service_name(&self) -> Result<ServiceName, AlertError> {
        ServiceName::new(&self.service).map_err(|e| self.error(format!("invalid name: {e:?}")))
    }
}

/// The daemon's side: [`send`](Self::send) publishes at once, on the caller's thread.
pub struct AlertPublisher {
    /// The service was a previous run's of this user, kept alive by its subscribers (see
    /// [`create_owned_alerts`]): reopened, not created.
    pub reopened: bool,
    settings: AlertServiceSettings,
    publisher: Arc<iceoryx2::port::publisher::Publisher<Shared, Alert, ()>>,
    wake: iceoryx2::port::notifier::Notifier<Shared>,
    published: u64,
    failed: u64,
    in_service: super::delay::PublishDelays,
    /// Closing it ends the keeper thread.
    stop_keeper: mpsc::SyncSender<()>,
    keeper: std::thread::JoinHandle<()>,
    // Declared after the ports: fields drop in order, the ports before their service and node.
    _service: iceoryx2::service::port_factory::publish_subscribe::PortFactory<Shared, Alert, ()>,
    _node: Node<Shared>,
}

impl AlertPublisher {
    /// Creates the services, the publisher and its keeper thread; or says why it could not.
    pub fn start(
        settings: AlertServiceSettings,
        history_size: usize,
    ) -> Result<AlertPublisher, AlertError> {
        let node =
            create_node::<Shared>(&settings.iox).map_err(|e| settings.error(e.to_string()))?;
        let (service, reopened) = create_owned_alerts(&node, &settings, history_size)?;
        let publisher = Arc::new(service.publisher_builder().create().map_err(|e| {
            // Only a second publisher can be refused here (max_publishers 1).
            match inspect(
                &settings.iox,
                &settings.service,
                MessagingPattern::PublishSubscribe,
            ) {
                Ok(Some((_, owners))) => settings.taken(
                    &settings.service,
                    Taken {
                        owners,
                        why: format!("another process publishes on it ({e:?})"),
                    },
                ),
                _ => settings.error(format!("create publisher: {e:?}")),
            }
        })?);
        let wake = create_owned_wake(&node, &settings)?
            .notifier_builder()
            .create()
            .map_err(|e| {
                settings.error(format!(
                    "create notifier: {e:?} (another process notifies on {})",
                    settings.wake_name()
                ))
            })?;
        let (stop_keeper, stopped) = mpsc::sync_channel::<()>(0);
        let keeper = {
            let publisher = Arc::clone(&publisher);
            std::thread::Builder::new()
                .name("bearingd-alerts".into())
                .spawn(move || {
                    crate::pipeline::priority::idle_this_thread();
                    while let Err(mpsc::RecvTimeoutError::Timeout) =
                        stopped.recv_timeout(CONNECTION_PERIOD)
                    {
                        let _ = publisher.update_connections();
                    }
                })
                .map_err(|e| AlertError::Thread(e.to_string()))?
        };
        Ok(AlertPublisher {
            reopened,
            settings,
            publisher,
            wake,
            published: 0,
            failed: 0,
            in_service: Default::default(),
            stop_keeper,
            keeper,
            _service: service,
            _node: node,
        })
    }

    /// Publishes one alert, wakes the subscribers and lets one woken on this CPU read it at
    /// once; the error names the alert and why. How long after its input the alert was in the
    /// service is recorded before the wake-up.
    pub fn send(&mut self, alert: Alert) -> Result<(), AlertError> {
        match self.publisher.send_copy(alert) {
            Ok(_) => {
                let in_service_ns = crate::clock::wall_clock_now_ns();
                self.in_service
                    .record(in_service_ns.saturating_sub(alert.wall_time_ns));
                self.published += 1;
                let _ = self.wake.notify();
                // (why) Linux often runs the woken subscriber on this thread's CPU (a Unix
                // socket wakes its reader as if the writer were about to sleep), where it would
                // wait for the rest of the input's analysis, the input's later alerts included:
                // on one CPU a bearing fault's alerts reached the subscriber p99 5.2 ms after
                // their block, 0.3 ms with this (docs/PERFORMANCE.md). With nothing else
                // waiting for the CPU, the call returns at once.
                std::thread::yield_now();
                Ok(())
            }
            Err(e) => {
                self.failed += 1;
                Err(AlertError::Publish {
                    sequence: alert.sequence,
                    service: self.settings.service.clone(),
                    detail: format!("{e:?}"),
                })
            }
        }
    }

    /// Stops the keeper, hands the history to any subscriber the keeper has not served yet,
    /// closes the ports and reports.
    pub fn finish(self) -> PublisherSummary {
        drop(self.stop_keeper);
        let _ = self.keeper.join();
        if self.publisher.update_connections().is_ok() {
            let _ = self.wake.notify();
        }
        PublisherSummary {
            published: self.published,
            failed: self.failed,
            in_service: self.in_service.spread(),
        }
    }
}

/// The alert service, created exclusively: iceoryx2 refuses a second creator, and one
/// publisher at most (`max_publishers(1)`), so no other process, even of this user, can
/// publish beside the daemon. The one service reopened is a previous run's of this user of the
/// same shape, kept alive by connected subscribers (a restart under `bearingd alerts`); its
/// single publisher slot still refuses a live one. Returns whether it was reopened.
fn create_owned_alerts(
    node: &Node<Shared>,
    settings: &AlertServiceSettings,
    history_size: usize,
) -> Result<(PubSubFactory<Shared, Alert, ()>, bool), AlertError> {
    let claim = settings.claim(
        &settings.service,
        MessagingPattern::PublishSubscribe,
        |config| fits_alerts(config, history_size),
    )?;
    let builder = node
        .service_builder(&settings.service_name()?)
        .publish_subscribe::<Alert>();
    match claim {
        Claim::Create => builder
            .history_size(history_size)
            .subscriber_max_buffer_size(SUBSCRIBER_BUFFER.max(history_size))
            .enable_safe_overflow(true)
            .max_publishers(1)
            .max_subscribers(16)
            .create()
            .map(|service| (service, false))
            .map_err(|e| {
                settings.lost_race(
                    &settings.service,
                    MessagingPattern::PublishSubscribe,
                    format!("{e:?}"),
                )
            }),
        Claim::Reopen(_) => builder
            .open()
            .map(|service| (service, true))
            .map_err(|e| settings.error(format!("reopen our previous service: {e:?}"))),
    }
}

/// Whether a found service has the shape [`create_owned_alerts`] gives: our payload, one
/// publisher, safe overflow and a history of at least `history_size`.
fn fits_alerts(config: &StaticConfig, history_size: usize) -> bool {
    use iceoryx2::service::static_config::messaging_pattern::MessagingPattern as Shape;
    let Shape::PublishSubscribe(ps) = config.messaging_pattern() else {
        return false;
    };
    let payload = &ps.message_type_details().payload;
    ps.max_publishers() == 1
        && ps.has_safe_overflow()
        && ps.history_size() >= history_size
        && *payload.type_name() == ALERT_TYPE_NAME
        && payload.size() == std::mem::size_of::<Alert>()
}

/// The payload's iceoryx2 type name (`type_name(...)` on [`Alert`]).
const ALERT_TYPE_NAME: &str = "bearingd::Alert";

/// The wake event of the alert service, by the same rule: created with one notifier at most,
/// or reopened when it is this user's of that shape.
fn create_owned_wake(
    node: &Node<Shared>,
    settings: &AlertServiceSettings,
) -> Result<EventFactory<Shared>, AlertError> {
    use iceoryx2::service::static_config::messaging_pattern::MessagingPattern as Shape;
    let name = settings.wake_name();
    let claim = settings.claim(
        &name,
        MessagingPattern::Event,
        |config| matches!(config.messaging_pattern(), Shape::Event(e) if e.max_notifiers() == 1),
    )?;
    let service_name =
        crate::iox::service_name(&name).map_err(|e| settings.error(e.to_string()))?;
    let builder = node.service_builder(&service_name).event();
    match claim {
        Claim::Create => builder
            .max_notifiers(1)
            .create()
            .map_err(|e| settings.lost_race(&name, MessagingPattern::Event, format!("{e:?}"))),
        Claim::Reopen(_) => builder
            .open()
            .map_err(|e| settings.error(format!("reopen our previous {name}: {e:?}"))),
    }
}

/// The subscriber's side of the service.
pub struct AlertSubscriber {
    settings: AlertServiceSettings,
    /// The user the service and its publisher must belong to.
    expected_uid: u32,
    /// The number of publishers when last verified: a change is verified again.
    publishers: usize,
    subscriber: iceoryx2::port::subscriber::Subscriber<ipc::Service, Alert, ()>,
    wake: iceoryx2::port::listener::Listener<ipc::Service>,
    service: PubSubFactory<ipc::Service, Alert, ()>,
    _node: Node<ipc::Service>,
    sequence: SequenceCheck,
    pending: std::collections::VecDeque<Received>,
    /// The service's history size: how many alerts a new subscriber is handed.
    pub history_size: usize,
}

impl AlertSubscriber {
    /// Opens the service and checks that it, its wake event and its publisher belong to
    /// `expected_uid` (see `verify.rs`): [`AlertError::Untrusted`] when not; another error when
    /// the root or the service does not exist (yet).
    pub fn open(
        settings: &AlertServiceSettings,
        expected_uid: u32,
    ) -> Result<AlertSubscriber, AlertError> {
        if let Some(root) = &settings.iox.root_path {
            match crate::fsafe::check_private_root(std::path::Path::new(root), expected_uid) {
                Ok(()) => {}
                Err(crate::fsafe::UnsafeDir::Io { source, .. })
                    if source.kind() == std::io::ErrorKind::NotFound =>
                {
                    return Err(settings.error("the iceoryx2 root does not exist (yet)"));
                }
                Err(e) => return Err(settings.untrusted(e.to_string())),
            }
        }
        let node = create_node(&settings.iox).map_err(|e| settings.error(e.to_string()))?;
        let service = node
            .service_builder(&settings.service_name()?)
            .publish_subscribe::<Alert>()
            .open()
            .map_err(|e| {
                settings.error(format!(
                    "cannot open it ({e:?}): is bearingd running with this config? (the root \
                     path and service name must be the daemon's)"
                ))
            })?;
        // Opened, never created: the daemon makes it with its one notifier.
        let wake_name = settings.wake_name();
        let wake = node
            .service_builder(
                &crate::iox::service_name(&wake_name).map_err(|e| settings.error(e.to_string()))?,
            )
            .event()
            .open()
            .map_err(|e| settings.error(format!("cannot open {wake_name} ({e:?})")))?
            .listener_builder()
            .create()
            .map_err(|e| settings.error(format!("create listener: {e:?}")))?;
        let publishers = service.dynamic_config().number_of_publishers();
        verify_service(
            &settings.iox,
            &settings.service,
            &wake_name,
            &service,
            expected_uid,
        )
        .map_err(|why| settings.untrusted(why))?;
        let history_size = service.static_config().history_size();
        let buffer = service.static_config().subscriber_max_buffer_size();
        let subscriber = service
            .subscriber_builder()
            .buffer_size(buffer)
            .history_request(history_size.min(buffer))
            .create()
            .map_err(|e| settings.error(format!("create subscriber: {e:?}")))?;
        Ok(AlertSubscriber {
            settings: settings.clone(),
            expected_uid,
            publishers,
            subscriber,
            wake,
            service,
            _node: node,
            sequence: SequenceCheck::new(buffer),
            pending: Default::default(),
            history_size,
        })
    }

    /// What the service's history hands a new subscriber, waiting `wait` for it: the alerts
    /// of this run, oldest first (the active ones among them). An empty history means the
    /// daemon has published nothing yet, so its next alert must be number 1.
    pub fn take_history(&mut self, wait: Duration) -> Result<Vec<Received>, AlertError> {
        let end = Instant::now() + wait;
        let mut history = Vec::new();
        while let Some(received) = self.next(end.saturating_duration_since(Instant::now()))? {
            history.push(received);
        }
        if history.is_empty() {
            self.sequence.expect_first();
        }
        Ok(history)
    }

    /// The next alert (or loss, restart, untrusted number), waiting at most `timeout`; `None`
    /// if nothing came; an error when the service or its publisher no longer passes the check
    /// (made again when the number of publishers changes and at each new run).
    pub fn next(&mut self, timeout: Duration) -> Result<Option<Received>, AlertError> {
        let deadline = Instant::now() + timeout;
        loop {
            if let Some(received) = self.pending.pop_front() {
                if matches!(received, Received::NewRun { .. }) {
                    self.verify()?;
                }
                return Ok(Some(received));
            }
            let publishers = self.service.dynamic_config().number_of_publishers();
            if publishers != self.publishers {
                self.verify()?;
                self.publishers = publishers;
            }
            self.drain();
            if !self.pending.is_empty() {
                continue;
            }
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Ok(None);
            }
            // Woken by the publisher; the timed wait bounds a missed wake-up.
            let _ = self
                .wake
                .timed_wait(|_| {}, left.min(CONNECTION_PERIOD * 4));
        }
    }

    fn verify(&self) -> Result<(), AlertError> {
        let wake = self.settings.wake_name();
        let settings = &self.settings;
        verify_service(
            &settings.iox,
            &settings.service,
            &wake,
            &self.service,
            self.expected_uid,
        )
        .map_err(|why| settings.untrusted(why))
    }

    /// Takes what arrived, one pass, and judges its sequence numbers ([`SequenceCheck`]).
    fn drain(&mut self) {
        let mut pass = Vec::new();
        while let Ok(Some(sample)) = self.subscriber.receive() {
            pass.push(*sample.payload());
        }
        self.sequence.pass(&pass, &mut self.pending);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sinks::alerts::payload::test_alert;
    use bearingd_testdata::scratch_dir;

    fn alert(sequence: u64) -> Alert {
        test_alert(42, sequence)
    }

    fn settings(test: &str) -> AlertServiceSettings {
        let root = scratch_dir(test).join("iox");
        AlertServiceSettings {
            service: "bearingd/alerts".into(),
            iox: IoxSettings {
                prefix: Some(format!("bdunit{}_{test}_", std::process::id())),
                root_path: Some(root.display().to_string()),
            },
        }
    }

    fn drain(subscriber: &mut AlertSubscriber) -> Vec<Received> {
        let mut all = Vec::new();
        while let Some(r) = subscriber.next(Duration::from_millis(300)).unwrap() {
            all.push(r);
        }
        all
    }

    #[test]
    fn a_subscriber_that_falls_behind_is_told_which_alerts_it_lost() {
        let settings = settings("lost");
        let mut publisher = AlertPublisher::start(settings.clone(), 16).unwrap();
        let mut subscriber =
            AlertSubscriber::open(&settings, crate::fsafe::effective_uid()).unwrap();
        assert!(subscriber
            .take_history(Duration::from_millis(300))
            .unwrap()
            .is_empty());
        let total = SUBSCRIBER_BUFFER as u64 + 44;
        for sequence in 1..=total {
            publisher.send(alert(sequence)).unwrap();
        }
        let summary = publisher.finish();
        assert_eq!(summary.published, total);
        assert_eq!(summary.failed, 0);
        assert_eq!(
            summary.in_service.map(|d| d.alerts),
            Some(total),
            "each published alert's time to the service counted"
        );
        let received = drain(&mut subscriber);
        // The buffer kept the newest alerts; the oldest were overwritten and are reported.
        assert_eq!(
            received.first(),
            Some(&Received::Lost {
                run_id: 42,
                first: 1,
                last: 44
            })
        );
        let sequences: Vec<u64> = received[1..]
            .iter()
            .map(|r| match r {
                Received::Alert(a) => a.sequence,
                other => panic!("unexpected {other:?}"),
            })
            .collect();
        assert_eq!(sequences, (45..=total).collect::<Vec<_>>());
    }

    #[test]
    fn a_late_subscriber_receives_the_history_then_live_alerts_and_restarts() {
        let settings = settings("history");
        let mut publisher = AlertPublisher::start(settings.clone(), 16).unwrap();
        for sequence in 1..=20 {
            publisher.send(alert(sequence)).unwrap();
        }
        std::thread::sleep(Duration::from_millis(200));
        let mut subscriber =
            AlertSubscriber::open(&settings, crate::fsafe::effective_uid()).unwrap();
        let history = subscriber.take_history(Duration::from_millis(500)).unwrap();
        let sequences: Vec<u64> = history
            .iter()
            .filter_map(|r| match r {
                Received::Alert(a) => Some(a.sequence),
                _ => None,
            })
            .collect();
        assert_eq!(sequences, (5..=20).collect::<Vec<_>>(), "{history:?}");
        publisher.send(alert(21)).unwrap();
        assert_eq!(
            subscriber.next(Duration::from_secs(5)).unwrap(),
            Some(Received::Alert(alert(21)))
        );
        // The daemon restarts: a new run id, numbers from 1 again.
        publisher.finish();
        let mut publisher = AlertPublisher::start(settings.clone(), 16).unwrap();
        let restarted = Alert {
            run_id: 43,
            ..alert(1)
        };
        publisher.send(restarted).unwrap();
        assert_eq!(
            subscriber.next(Duration::from_secs(5)).unwrap(),
            Some(Received::NewRun { run_id: 43 })
        );
        assert_eq!(
            subscriber.next(Duration::from_secs(5)).unwrap(),
            Some(Received::Alert(restarted))
        );
        publisher.finish();
    }
}

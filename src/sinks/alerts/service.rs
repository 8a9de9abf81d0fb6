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
//! - event `<alerts_service>/wake`, notified after every alert, so a subscriber sleeps in the
//!   kernel instead of polling.
//!
//! The daemon publishes on the thread that decides the alert (the analysis thread): iceoryx2's
//! send and notify never block, and no other thread has to wake up before the alert leaves.
//! Its ports are therefore of the `ipc_threadsafe` variant (the same shared memory as the
//! subscribers' `ipc`), shared with a keeper thread: iceoryx2 hands the history to a new
//! subscriber when the publisher next updates its connections, and the keeper does that every
//! [`CONNECTION_PERIOD`], also while no alert is sent.

use super::payload::Alert;
use super::PublisherSummary;
use crate::iox::{create_node, open_event_service, wake_service, IoxSettings};
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::*;
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

    fn service_name(&self) -> Result<ServiceName, AlertError> {
        ServiceName::new(&self.service).map_err(|e| self.error(format!("invalid name: {e:?}")))
    }
}

/// The daemon's side: [`send`](Self::send) publishes at once, on the caller's thread.
pub struct AlertPublisher {
    settings: AlertServiceSettings,
    publisher: Arc<iceoryx2::port::publisher::Publisher<Shared, Alert, ()>>,
    wake: iceoryx2::port::notifier::Notifier<Shared>,
    published: u64,
    failed: u64,
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
        let service = node
            .service_builder(&settings.service_name()?)
            .publish_subscribe::<Alert>()
            .history_size(history_size)
            .subscriber_max_buffer_size(SUBSCRIBER_BUFFER.max(history_size))
            .enable_safe_overflow(true)
            .max_publishers(2)
            .max_subscribers(16)
            .open_or_create()
            .map_err(|e| {
                settings.error(format!(
                    "open or create: {e:?}; if another bearingd uses this service name, give \
                     each its own outputs.alerts_service"
                ))
            })?;
        let publisher = Arc::new(
            service
                .publisher_builder()
                .create()
                .map_err(|e| settings.error(format!("create publisher: {e:?}")))?,
        );
        let wake = open_event_service(&node, &settings.wake_name())
            .map_err(|e| settings.error(e.to_string()))?
            .notifier_builder()
            .create()
            .map_err(|e| settings.error(format!("create notifier: {e:?}")))?;
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
            settings,
            publisher,
            wake,
            published: 0,
            failed: 0,
            stop_keeper,
            keeper,
            _service: service,
            _node: node,
        })
    }

    /// Publishes one alert and wakes the subscribers; the error names the alert and why.
    pub fn send(&mut self, alert: Alert) -> Result<(), AlertError> {
        match self.publisher.send_copy(alert) {
            Ok(_) => {
                self.published += 1;
                let _ = self.wake.notify();
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

    /// Stops the keeper, closes the ports and reports.
    pub fn finish(self) -> PublisherSummary {
        drop(self.stop_keeper);
        let _ = self.keeper.join();
        PublisherSummary {
            published: self.published,
            failed: self.failed,
        }
    }
}

/// What a subscriber takes from the service.
#[derive(Debug, Clone, PartialEq)]
pub enum Received {
    Alert(Alert),
    /// Alerts `first..=last` of the run never arrived: the subscriber's buffer overflowed.
    Lost {
        run_id: u64,
        first: u64,
        last: u64,
    },
    /// The daemon restarted (a new run id); sequence numbers start again.
    NewRun {
        run_id: u64,
    },
}

/// The subscriber's side of the service.
pub struct AlertSubscriber {
    _node: Node<ipc::Service>,
    subscriber: iceoryx2::port::subscriber::Subscriber<ipc::Service, Alert, ()>,
    wake: iceoryx2::port::listener::Listener<ipc::Service>,
    last: Option<(u64, u64)>,
    /// The next alert of a run is expected to be its first (sequence 1): the history was
    /// empty when we subscribed, or a new run began.
    expect_first: bool,
    pending: std::collections::VecDeque<Received>,
    /// The service's history size: how many alerts a new subscriber is handed.
    pub history_size: usize,
}

impl AlertSubscriber {
    /// Opens the service; fails if the daemon has not created it (yet).
    pub fn open(settings: &AlertServiceSettings) -> Result<AlertSubscriber, AlertError> {
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
        let history_size = service.static_config().history_size();
        let buffer = service.static_config().subscriber_max_buffer_size();
        let subscriber = service
            .subscriber_builder()
            .buffer_size(buffer)
            .history_request(history_size.min(buffer))
            .create()
            .map_err(|e| settings.error(format!("create subscriber: {e:?}")))?;
        let wake = open_event_service(&node, &settings.wake_name())
            .map_err(|e| settings.error(e.to_string()))?
            .listener_builder()
            .create()
            .map_err(|e| settings.error(format!("create listener: {e:?}")))?;
        Ok(AlertSubscriber {
            _node: node,
            subscriber,
            wake,
            last: None,
            expect_first: false,
            pending: Default::default(),
            history_size,
        })
    }

    /// What the service's history hands a new subscriber, waiting `wait` for it: the alerts
    /// of this run, oldest first (the active ones among them). An empty history means the
    /// daemon has published nothing yet, so its next alert must be number 1; a higher one
    /// is reported as lost alerts.
    pub fn take_history(&mut self, wait: Duration) -> Vec<Received> {
        let end = Instant::now() + wait;
        let mut history = Vec::new();
        while let Some(received) = self.next(end.saturating_duration_since(Instant::now())) {
            history.push(received);
        }
        if history.is_empty() {
            self.expect_first = true;
        }
        history
    }

    /// The next alert (or loss, or restart), waiting at most `timeout`; `None` if nothing came.
    pub fn next(&mut self, timeout: Duration) -> Option<Received> {
        let deadline = Instant::now() + timeout;
        loop {
            if let Some(received) = self.pending.pop_front() {
                return Some(received);
            }
            self.drain();
            if !self.pending.is_empty() {
                continue;
            }
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return None;
            }
            // Woken by the publisher; the timed wait bounds a missed wake-up.
            let _ = self
                .wake
                .timed_wait(|_| {}, left.min(CONNECTION_PERIOD * 4));
        }
    }

    fn drain(&mut self) {
        while let Ok(Some(sample)) = self.subscriber.receive() {
            let alert = *sample.payload();
            let expected = match self.last {
                Some((run, seq)) if run == alert.run_id => Some(seq + 1),
                Some(_) => {
                    self.pending.push_back(Received::NewRun {
                        run_id: alert.run_id,
                    });
                    Some(1)
                }
                None => self.expect_first.then_some(1),
            };
            if let Some(expected) = expected {
                if alert.sequence < expected {
                    continue; // already seen (history handed again)
                }
                if alert.sequence > expected {
                    self.pending.push_back(Received::Lost {
                        run_id: alert.run_id,
                        first: expected,
                        last: alert.sequence - 1,
                    });
                }
            }
            self.last = Some((alert.run_id, alert.sequence));
            self.pending.push_back(Received::Alert(alert));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sinks::alerts::payload::{name_field, AlertState, ALERT_VERSION};
    use bearingd_testdata::scratch_dir;

    fn alert(sequence: u64) -> Alert {
        Alert {
            sequence,
            run_id: 42,
            end_sample: sequence * 100,
            wall_time_ns: 0,
            sample_rate_hz: 12_000.0,
            fault_frequency_hz: 107.0,
            score: 30.0,
            confidence: 0.9,
            twin_error: 0.25, // not NaN: the tests compare alerts with ==
            version: ALERT_VERSION,
            state: AlertState::Raised as u8,
            fault: 1,
            severity: 1,
            previous_severity: 0,
            sensor: name_field("s"),
            axis: name_field("radial"),
        }
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
        while let Some(r) = subscriber.next(Duration::from_millis(300)) {
            all.push(r);
        }
        all
    }

    #[test]
    fn a_subscriber_that_falls_behind_is_told_which_alerts_it_lost() {
        let settings = settings("lost");
        let mut publisher = AlertPublisher::start(settings.clone(), 16).unwrap();
        let mut subscriber = AlertSubscriber::open(&settings).unwrap();
        assert!(subscriber
            .take_history(Duration::from_millis(300))
            .is_empty());
        let total = SUBSCRIBER_BUFFER as u64 + 44;
        for sequence in 1..=total {
            publisher.send(alert(sequence)).unwrap();
        }
        let summary = publisher.finish();
        assert_eq!(summary.published, total);
        assert_eq!(summary.failed, 0);
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
        let mut subscriber = AlertSubscriber::open(&settings).unwrap();
        let history = subscriber.take_history(Duration::from_millis(500));
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
            subscriber.next(Duration::from_secs(5)),
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
            subscriber.next(Duration::from_secs(5)),
            Some(Received::NewRun { run_id: 43 })
        );
        assert_eq!(
            subscriber.next(Duration::from_secs(5)),
            Some(Received::Alert(restarted))
        );
        publisher.finish();
    }
}

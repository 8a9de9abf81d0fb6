//! The bridge's I/O: one thread with its own single-threaded tokio runtime, an MQTT 5 client
//! (rumqttc) over TCP or TLS (rustls, with the `tls` feature), the disk queue, and the edge
//! node's session.
//!
//! Why a thread of its own: the daemon's sink thread must never wait on a network, and the
//! queue's fsyncs must not run on the daemon's tokio workers. The sink hands observations over
//! a bounded channel (`INTAKE`, the sink waits when it is full: the same back-pressure as the
//! log's); everything else happens here.
//!
//! Why MQTT 5 and not 3.1.1: a broker that refuses a publish (an ACL) says so in the PUBACK's
//! reason code under MQTT 5; under 3.1.1 mosquitto acknowledges and drops it silently, and the
//! bridge would believe it delivered. Refusals of the connection (a wrong password) come as a
//! CONNACK reason code under both.
//!
//! The loop (every step is in `Bridge`):
//! 1. observations → [`MetricBook`] → records → appended to the queue;
//! 2. the queue's appends are fsynced before anything appended is published (its
//!    acknowledgements once a second);
//! 3. while a session is up, records are published in order from the first unacknowledged,
//!    at most `WINDOW` unacknowledged at a time; a PUBACK acknowledges its record;
//! 4. a lost connection ends the session: what was not acknowledged is sent again in the next
//!    one (with the next `bdSeq`, a fresh NBIRTH/DBIRTH and new `seq` numbers), after a pause
//!    that doubles from 1 s up to 4 s (30 s after the broker refused the node). rumqttc's own replay of unacknowledged packets is not
//!    used (a new client per session): its packets would carry the old session's `seq`;
//! 5. with a primary host (`fleet.primary_host_id`), the births and step 3 wait until its STATE
//!    says online, and stop while it says offline; the records wait in the queue meanwhile
//!    (`host_state.rs`, [`super::primary`]).

use super::metrics::{MetricBook, Observation};
use super::node::{decode_record, encode_record, Command, EdgeNode, Publish, Qos};
use super::primary::{HostStats, PrimaryHost};
use super::queue::{DiskQueue, QueueError, QueueStats};
use super::sparkplug::Value;
use crate::config::FleetConfig;
use rumqttc::v5::mqttbytes::v5::{LastWill, Packet, PubAckReason};
use rumqttc::v5::mqttbytes::QoS;
use rumqttc::v5::{AsyncClient, ConnectionError, Event, MqttOptions};
use rumqttc::Outgoing;
use std::collections::{BTreeSet, HashMap, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::mpsc;
use tokio::time::Instant;

mod host_state;
mod refusals;
use refusals::{puback_code, refusal};

/// Where the bridge's notices go (a connection, a refusal, a full queue, the summary at the
/// stop), one line each without the `bearingd: ` prefix; called from the bridge thread. The
/// bridge never prints: the daemon turns them into its events and the command line decides how
/// they read.
pub type Notices = Arc<dyn Fn(String) + Send + Sync>;

/// Observations waiting for the bridge thread.
pub const INTAKE: usize = 1024;
/// Records published and not yet acknowledged, at most.
const WINDOW: usize = 64;
/// How long a stop waits for the queue to drain and for acknowledgements.
const STOP_GRACE: Duration = Duration::from_secs(3);
const FIRST_RETRY: Duration = Duration::from_secs(1);
/// The longest pause between attempts on an unreachable broker (drawn between half and all of
/// it): a broker that returns is used within about 4 s (issue 33: within 5 s), while a plant's
/// nodes still spread their reconnects over 2 s.
const MAX_RETRY: Duration = Duration::from_secs(4);
/// The pause after the broker refused the connection (credentials, a client id it will not
/// take): the config must change first, and trying faster only fills the broker's log.
const REFUSED_RETRY: Duration = Duration::from_secs(30);
const BD_SEQ_FILE: &str = "bdseq";
/// How often the acknowledgements are recorded on disk.
const HEAD_SYNC_EVERY: Duration = Duration::from_secs(1);

/// Why the bridge could not start; each names the file or setting.
#[derive(Debug, thiserror::Error)]
pub enum BridgeError {
    #[error("fleet queue: {0}")]
    Queue(#[from] QueueError),
    #[error("fleet.password_file {path}: cannot read it: {source}")]
    Password {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("fleet.{key} {path}: {problem}")]
    Tls {
        key: &'static str,
        path: PathBuf,
        problem: String,
    },
    #[error("fleet: cannot start the bridge thread: {0}")]
    Thread(std::io::Error),
}

/// What the bridge did, for the summary at the stop.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct BridgeSummary {
    pub queue: QueueStats,
    /// Records published (resends included).
    pub published: u64,
    /// Publishes the broker refused (PUBACK reason code), e.g. an ACL.
    pub refused: u64,
    /// Sessions (accepted CONNECTs).
    pub sessions: u64,
    /// Records of devices no longer configured, found in the queue and skipped.
    pub stale_records: u64,
    /// Queued metrics no birth of this version declares, left out of their DDATA.
    pub left_out_metrics: u64,
    pub bd_seq: u64,
    /// What the primary host's STATE messages did (`fleet.primary_host_id` set).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub primary_host: Option<HostStats>,
}

/// The running bridge: the sending end of its intake and its thread.
pub struct BridgeHandle {
    pub intake: mpsc::Sender<Observation>,
    pub thread: std::thread::JoinHandle<BridgeSummary>,
}

/// Opens the queue, reads the secrets and certificates (so that a mistake stops the daemon at
/// its start, naming the file), and starts the bridge thread.
pub fn start(
    config: FleetConfig,
    devices: Vec<String>,
    notices: Notices,
) -> Result<BridgeHandle, BridgeError> {
    let (queue, opened) = DiskQueue::open(&config.queue_dir, config.queue_max_bytes())?;
    for (path, bytes) in &opened.truncated {
        notices(format!(
            "fleet: {}: {bytes} bytes of a torn record cut (a crash while writing)",
            path.display()
        ));
    }
    if opened.pending > 0 {
        notices(format!(
            "fleet: {} records from before the restart wait in {}",
            opened.pending,
            config.queue_dir.display()
        ));
    }
    let options = mqtt_options(&config)?;
    let bd_seq = read_bd_seq(&config.queue_dir).map_or(0, |last| (last + 1) % 256);
    let period_ms = (config.publish_period_s * 1000.0).round().max(1.0) as u64;
    let book = MetricBook::new(devices, period_ms);
    let mut node = EdgeNode::new(
        &config.group_id,
        &config.node_id,
        book.device_ids().count(),
        bd_seq,
    );
    node.set_properties(vec![(
        "Properties/bearingd version".into(),
        Value::String(env!("CARGO_PKG_VERSION").into()),
    )]);
    let (intake, intake_rx) = mpsc::channel(INTAKE);
    let primary = config.primary_host_id.as_deref().map(PrimaryHost::new);
    let bridge = Bridge {
        primary,
        config,
        options,
        book,
        node,
        queue,
        session: None,
        summary: BridgeSummary::default(),
        last_report: String::new(),
        retry_after: FIRST_RETRY,
        notices: notices.clone(),
    };
    let thread = std::thread::Builder::new()
        .name("bearingd-fleet".into())
        .spawn(move || {
            let runtime = tokio::runtime::Builder::new_current_thread()
                .enable_all()
                .build();
            match runtime {
                Ok(runtime) => runtime.block_on(bridge.run(intake_rx)),
                Err(e) => {
                    notices(format!("fleet: cannot start the bridge's runtime: {e}"));
                    BridgeSummary::default()
                }
            }
        })
        .map_err(BridgeError::Thread)?;
    Ok(BridgeHandle { intake, thread })
}

/// The MQTT options of every session but the Will (which carries the session's `bdSeq`).
fn mqtt_options(config: &FleetConfig) -> Result<MqttOptions, BridgeError> {
    let mut options = MqttOptions::new(
        config.client_id.clone(),
        config.broker.host.clone(),
        config.broker.port,
    );
    options
        .set_keep_alive(Duration::from_secs_f64(config.keep_alive_s))
        .set_clean_start(true)
        .set_connection_timeout(10)
        .set_request_channel_capacity(2 * WINDOW + 64)
        .set_outgoing_inflight_upper_limit(WINDOW as u16);
    if let Some(user) = &config.username {
        let password = match &config.password_file {
            Some(path) => std::fs::read_to_string(path)
                .map_err(|source| BridgeError::Password {
                    path: path.clone(),
                    source,
                })?
                .lines()
                .next()
                .unwrap_or_default()
                .to_string(),
            None => String::new(),
        };
        options.set_credentials(user.clone(), password);
    }
    if config.broker.tls {
        #[cfg(feature = "tls")]
        {
            let tls = super::tls::client_config(config).map_err(|p| BridgeError::Tls {
                key: p.key,
                path: p.path,
                problem: p.problem,
            })?;
            options.set_transport(rumqttc::Transport::tls_with_config(
                rumqttc::TlsConfiguration::Rustls(Arc::new(tls)),
            ));
        }
        // The config's check says so first (`fleet.broker`); a FleetConfig built in code
        // without it still stops here rather than speaking plain MQTT to a TLS port.
        #[cfg(not(feature = "tls"))]
        return Err(BridgeError::Tls {
            key: "broker",
            path: PathBuf::from(config.broker.to_string()),
            problem: crate::config::TLS_NOT_BUILT.into(),
        });
    }
    Ok(options)
}

fn read_bd_seq(dir: &Path) -> Option<u64> {
    std::fs::read_to_string(dir.join(BD_SEQ_FILE))
        .ok()?
        .trim()
        .parse()
        .ok()
}

/// Records the `bdSeq` of an accepted CONNECT, so that a restarted daemon uses the next one.
fn write_bd_seq(dir: &Path, bd_seq: u64) -> std::io::Result<()> {
    crate::fsafe::replace(&dir.join(BD_SEQ_FILE), format!("{bd_seq}\n").as_bytes())
}

fn now_ms() -> u64 {
    crate::clock::wall_clock_now_ns() / 1_000_000
}

/// What the client's event-loop task reports.
enum SessionEvent {
    Mqtt(Box<Event>),
    Down(ConnectionError),
}

/// One connection to the broker.
struct Session {
    client: AsyncClient,
    events: mpsc::Receiver<SessionEvent>,
    task: tokio::task::JoinHandle<()>,
    /// CONNACK received and births sent.
    up: bool,
    /// Records made before this number were made before the session: historical.
    first_live: u64,
    /// The next record to publish.
    cursor: u64,
    /// Per publish handed to the client, in order: the record it carries (QoS 1 data).
    expected: VecDeque<Option<u64>>,
    /// Packet id → record, for publishes awaiting their PUBACK.
    by_packet: HashMap<u16, u64>,
    /// Records published in this session and not acknowledged.
    in_flight: BTreeSet<u64>,
    /// The broker refused something: close the session.
    refused: bool,
    /// Per subscription handed to the client, in order: whether it is the primary host's STATE.
    subscribes: VecDeque<bool>,
    /// The packet id of the STATE subscription, for its SUBACK.
    state_subscription: Option<u16>,
}

struct Bridge {
    config: FleetConfig,
    options: MqttOptions,
    book: MetricBook,
    node: EdgeNode,
    queue: DiskQueue,
    session: Option<Session>,
    /// `fleet.primary_host_id`: births and data only while its STATE says online.
    primary: Option<PrimaryHost>,
    summary: BridgeSummary,
    /// The last problem reported, so that a retry loop says it once.
    last_report: String,
    retry_after: Duration,
    notices: Notices,
}

impl Bridge {
    async fn run(mut self, mut intake: mpsc::Receiver<Observation>) -> BridgeSummary {
        let mut retry_at = Instant::now();
        let mut stopping: Option<Instant> = None;
        let mut head_synced = Instant::now();
        loop {
            if stopping.is_none() && self.session.is_none() && Instant::now() >= retry_at {
                self.connect();
            }
            tokio::select! {
                observation = intake.recv(), if stopping.is_none() => match observation {
                    Some(o) => {
                        self.take(o);
                        // Take whatever else waits, then one fsync for the lot.
                        while let Ok(o) = intake.try_recv() {
                            self.take(o);
                        }
                    }
                    None => stopping = Some(Instant::now() + STOP_GRACE),
                },
                event = async {
                    match self.session.as_mut() {
                        Some(s) => s.events.recv().await,
                        None => std::future::pending().await,
                    }
                } => match event {
                    Some(SessionEvent::Mqtt(event)) => self.on_event(*event),
                    Some(SessionEvent::Down(error)) => {
                        retry_at = Instant::now() + self.on_down(Some(error));
                    }
                    None => {
                        retry_at = Instant::now() + self.on_down(None);
                    }
                },
                _ = tokio::time::sleep_until(retry_at), if self.session.is_none() && stopping.is_none() => {},
                _ = tokio::time::sleep_until(stopping.unwrap_or_else(Instant::now)), if stopping.is_some() => break,
            }
            // Appends are made durable before anything is published; the acknowledgements
            // (two fsyncs and a rename) once a second: a crash resends at most that second's
            // acknowledged records, with their record numbers (at-least-once).
            let synced = if head_synced.elapsed() >= HEAD_SYNC_EVERY {
                head_synced = Instant::now();
                self.queue.sync()
            } else {
                self.queue.sync_appends()
            };
            if let Err(e) = synced {
                self.report(format!("fleet: queue: {e}"));
            }
            self.pump();
            if stopping.is_some() && self.drained() {
                break;
            }
        }
        self.stop().await
    }

    /// Takes one observation; a record it completes goes to the queue.
    fn take(&mut self, observation: Observation) {
        let Some(record) = self.book.observe(observation) else {
            return;
        };
        match self.queue.push(&encode_record(&record)) {
            Ok((_, 0)) => {}
            Ok((number, dropped)) => (self.notices)(format!(
                "fleet: queue full ({} MiB): the {dropped} oldest unsent records \
                 dropped to make room for record {number} ({} dropped so far); raise \
                 fleet.queue_max_mb to keep more",
                self.config.queue_max_mb,
                self.queue.stats().dropped
            )),
            Err(e) => self.report(format!("fleet: cannot queue a record: {e}")),
        }
    }

    /// Nothing left to send, nothing awaiting an acknowledgement, or no session to send on. A
    /// session still connecting is waited for (within the stop's grace), so that a short run
    /// delivers what it made.
    fn drained(&self) -> bool {
        // With the primary host offline nothing more would be sent within the grace.
        let open = self.may_publish();
        match &self.session {
            Some(s) if s.up => {
                s.refused
                    || (s.in_flight.is_empty() && (!open || s.cursor >= self.queue.next_number()))
            }
            Some(_) => false,
            None => true,
        }
    }

    fn report(&mut self, message: String) {
        if message != self.last_report {
            (self.notices)(message.clone());
            self.last_report = message;
        }
    }

    /// Starts a session: a new client whose Will is the NDEATH of the next `bdSeq`.
    fn connect(&mut self) {
        let mut options = self.options.clone();
        let will = self.node.death(now_ms());
        options.set_last_will(LastWill::new(
            will.topic,
            will.payload,
            QoS::AtLeastOnce,
            false,
            None,
        ));
        let (client, mut eventloop) = AsyncClient::new(options, 2 * WINDOW + 64);
        let (events_tx, events) = mpsc::channel(8 * WINDOW + 256);
        let task = tokio::spawn(async move {
            loop {
                match eventloop.poll().await {
                    Ok(event) => {
                        if events_tx
                            .send(SessionEvent::Mqtt(Box::new(event)))
                            .await
                            .is_err()
                        {
                            return;
                        }
                    }
                    Err(error) => {
                        let _ = events_tx.send(SessionEvent::Down(error)).await;
                        return;
                    }
                }
            }
        });
        self.session = Some(Session {
            client,
            events,
            task,
            up: false,
            first_live: self.queue.next_number(),
            cursor: self.queue.first_pending(),
            expected: VecDeque::new(),
            by_packet: HashMap::new(),
            in_flight: BTreeSet::new(),
            refused: false,
            subscribes: VecDeque::new(),
            state_subscription: None,
        });
    }

    /// The session ended; returns the pause before the next attempt.
    fn on_down(&mut self, error: Option<ConnectionError>) -> Duration {
        let Some(session) = self.session.take() else {
            return self.retry_after;
        };
        session.task.abort();
        let broker = &self.config.broker;
        let pending = self.queue.pending();
        let why = match &error {
            Some(ConnectionError::ConnectionRefused(code)) => refusal(*code, &self.config),
            Some(ConnectionError::Io(e)) => format!("cannot reach it: {e}"),
            #[cfg(feature = "tls")]
            Some(ConnectionError::Tls(e)) => format!(
                "TLS failed: {e}; check fleet.ca_file (the CA that signed the broker's \
                 certificate) and that the broker's certificate names {}",
                broker.host
            ),
            Some(ConnectionError::Timeout(_)) => "no answer within 10 s".to_string(),
            Some(e) => e.to_string(),
            None => "the client stopped".to_string(),
        };
        let was_up = session.up;
        if was_up {
            // The broker published (or will publish) this session's NDEATH; the next CONNECT
            // takes the next bdSeq.
            self.node.next_session();
            self.retry_after = FIRST_RETRY;
        }
        let pause = jitter(if session.refused {
            REFUSED_RETRY
        } else {
            self.retry_after
        });
        self.report(format!(
            "fleet: broker {broker}: {why}; {pending} records wait in the queue, retrying in \
             {:.0} s",
            pause.as_secs_f64()
        ));
        self.retry_after = (self.retry_after * 2).min(MAX_RETRY);
        pause
    }

    fn on_event(&mut self, event: Event) {
        match event {
            Event::Incoming(Packet::ConnAck(_)) => self.on_connected(),
            Event::Incoming(Packet::PubAck(ack)) => {
                let Some(session) = self.session.as_mut() else {
                    return;
                };
                let Some(number) = session.by_packet.remove(&ack.pkid) else {
                    return;
                };
                session.in_flight.remove(&number);
                match ack.reason {
                    PubAckReason::Success | PubAckReason::NoMatchingSubscribers => {
                        self.queue.ack(number)
                    }
                    reason => {
                        session.refused = true;
                        let _ = session.client.try_disconnect();
                        self.summary.refused += 1;
                        let topic = format!(
                            "spBv1.0/{}/DDATA/{}/…",
                            self.config.group_id, self.config.node_id
                        );
                        self.report(format!(
                            "fleet: broker {} REFUSED a publish to {topic}: {reason:?} (MQTT 5 \
                             reason code {}); nothing is delivered, records stay queued; check \
                             the broker's ACL for user {} and fleet.node_id",
                            self.config.broker,
                            puback_code(reason),
                            self.config.username.as_deref().unwrap_or("(anonymous)")
                        ));
                    }
                }
            }
            Event::Incoming(Packet::Publish(publish))
                if publish.topic.as_ref() == self.node.command_topic().as_bytes()
                    && self.node.command(&publish.payload) == Some(Command::Rebirth)
                    // With the primary host offline the births wait for it to be online.
                    && self.may_publish() =>
            {
                (self.notices)("fleet: rebirth requested (NCMD): births sent again".into());
                let births = self.node.births(&self.book, now_ms());
                self.send(births);
            }
            Event::Incoming(Packet::Publish(publish))
                if self
                    .primary
                    .as_ref()
                    .is_some_and(|p| publish.topic.as_ref() == p.topic().as_bytes()) =>
            {
                self.on_state(&publish.payload);
            }
            Event::Outgoing(Outgoing::Subscribe(packet)) => {
                if let Some(session) = self.session.as_mut() {
                    if session.subscribes.pop_front() == Some(true) {
                        session.state_subscription = Some(packet);
                    }
                }
            }
            Event::Incoming(Packet::SubAck(ack))
                if self
                    .session
                    .as_ref()
                    .is_some_and(|s| s.state_subscription == Some(ack.pkid)) =>
            {
                self.on_state_suback(&ack.return_codes);
            }
            Event::Incoming(Packet::Disconnect(d)) => {
                self.report(format!(
                    "fleet: broker {} disconnected us: {:?}",
                    self.config.broker, d.reason_code
                ));
            }
            Event::Outgoing(Outgoing::Publish(packet)) => {
                if let Some(session) = self.session.as_mut() {
                    if let Some(Some(number)) = session.expected.pop_front() {
                        session.by_packet.insert(packet, number);
                    }
                }
            }
            _ => {}
        }
    }

    fn on_connected(&mut self) {
        let Some(session) = self.session.as_mut() else {
            return;
        };
        session.up = true;
        session.first_live = self.queue.next_number();
        session.cursor = self.queue.first_pending();
        let topic = self.node.command_topic();
        let _ = session.client.try_subscribe(topic, QoS::AtLeastOnce);
        session.subscribes.push_back(false);
        // The primary host's STATE before any birth: offline until it says otherwise.
        let mut waiting = String::new();
        if let Some(primary) = self.primary.as_mut() {
            primary.new_session();
            let _ = session
                .client
                .try_subscribe(primary.topic(), QoS::AtLeastOnce);
            session.subscribes.push_back(true);
            waiting = format!(
                "; waiting for primary host {} to be online ({}) before the births",
                primary.id(),
                primary.topic()
            );
        }
        self.summary.sessions += 1;
        self.summary.bd_seq = self.node.bd_seq();
        if let Err(e) = write_bd_seq(&self.config.queue_dir, self.node.bd_seq()) {
            (self.notices)(format!("fleet: cannot record bdSeq: {e}"));
        }
        let backlog = self.queue.pending();
        self.last_report = String::new();
        (self.notices)(format!(
            "fleet: connected to {} as {}/{} (bdSeq {}); {backlog} queued records to \
             send{waiting}",
            self.config.broker,
            self.config.group_id,
            self.config.node_id,
            self.node.bd_seq()
        ));
        if self.may_publish() {
            let births = self.node.births(&self.book, now_ms());
            self.send(births);
        }
    }

    /// Hands publishes to the client in order; `false` if the client's queue is full.
    fn send(&mut self, publishes: Vec<Publish>) -> bool {
        let Some(session) = self.session.as_mut() else {
            return false;
        };
        for p in publishes {
            let qos = match p.qos {
                Qos::AtMostOnce => QoS::AtMostOnce,
                Qos::AtLeastOnce => QoS::AtLeastOnce,
            };
            if session
                .client
                .try_publish(p.topic, qos, false, p.payload)
                .is_err()
            {
                return false;
            }
            session
                .expected
                .push_back(p.record.filter(|_| qos == QoS::AtLeastOnce));
            if let Some(number) = p.record {
                session.in_flight.insert(number);
                self.summary.published += 1;
            }
        }
        true
    }

    /// Publishes queued records in order while the window has room.
    fn pump(&mut self) {
        loop {
            let open = self.may_publish();
            let Some(session) = self.session.as_mut() else {
                return;
            };
            if !open || !session.up || session.refused || session.in_flight.len() >= WINDOW {
                return;
            }
            let number = session.cursor.max(self.queue.first_pending());
            if number >= self.queue.next_number() {
                session.cursor = number;
                return;
            }
            session.cursor = number + 1;
            let historical = number < session.first_live;
            let bytes = match self.queue.read(number) {
                Ok(Some(bytes)) => bytes,
                Ok(None) => continue,
                Err(e) => {
                    self.report(format!("fleet: queue: {e}"));
                    return;
                }
            };
            let publishes = decode_record(&bytes)
                .and_then(|r| self.node.data(&self.book, &r, number, historical, now_ms()));
            match publishes {
                Some(p) => {
                    if !self.send(p) {
                        // The client's queue is full: take it up again later.
                        if let Some(s) = self.session.as_mut() {
                            s.cursor = number;
                        }
                        return;
                    }
                }
                None => {
                    // A record of a device no longer configured (or unreadable): skipped,
                    // counted.
                    self.summary.stale_records += 1;
                    self.queue.ack(number);
                }
            }
        }
    }

    /// A clean stop: the deaths, a DISCONNECT, the queue synced; what is left stays queued.
    async fn stop(mut self) -> BridgeSummary {
        if self.session.as_ref().is_some_and(|s| s.up) {
            let deaths = self.node.stop(&self.book, now_ms());
            self.send(deaths);
            if let Some(session) = self.session.as_mut() {
                let _ = session.client.try_disconnect();
                // Let the event loop write the deaths and the DISCONNECT.
                let deadline = Instant::now() + Duration::from_secs(1);
                while let Ok(Some(event)) =
                    tokio::time::timeout_at(deadline, session.events.recv()).await
                {
                    let done = match &event {
                        SessionEvent::Mqtt(e) => {
                            matches!(**e, Event::Outgoing(Outgoing::Disconnect))
                        }
                        SessionEvent::Down(_) => true,
                    };
                    if done {
                        break;
                    }
                }
            }
        }
        if let Some(session) = self.session.take() {
            session.task.abort();
        }
        if let Err(e) = self.queue.sync() {
            (self.notices)(format!("fleet: queue: {e}"));
        }
        self.summary.queue = self.queue.stats();
        self.summary.left_out_metrics = self.node.left_out_metrics();
        if self.summary.stale_records + self.summary.left_out_metrics > 0 {
            (self.notices)(format!(
                "fleet: from the queue, {} records of devices no longer configured skipped and \
                 {} metrics this version does not declare left out of their DDATA (records of \
                 another config or bearingd version)",
                self.summary.stale_records, self.summary.left_out_metrics
            ));
        }
        if let Some(primary) = &self.primary {
            let h = primary.stats();
            (self.notices)(format!(
                "fleet: primary host {}: online {} times, offline {} times; {} STATE messages \
                 ignored ({} unreadable, {} older than the newest)",
                h.host_id,
                h.came_online,
                h.went_offline,
                h.unreadable + h.stale,
                h.unreadable,
                h.stale
            ));
            self.summary.primary_host = Some(h.clone());
        }
        let s = &self.summary;
        (self.notices)(format!(
            "fleet: {} records made, {} acknowledged by the broker, {} left in the \
             queue (sent after the restart), {} dropped (queue full), {} refused by the broker, \
             {} sessions",
            s.queue.appended,
            s.queue.acknowledged,
            s.queue.pending,
            s.queue.dropped,
            s.refused,
            s.sessions
        ));
        self.summary
    }
}

/// Between 50 % and 100 % of `pause`, so that the nodes of a plant do not all reconnect in
/// the same instant after their broker restarts.
fn jitter(pause: Duration) -> Duration {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.subsec_nanos());
    pause.mul_f64(0.5 + 0.5 * f64::from(nanos % 1000) / 1000.0)
}

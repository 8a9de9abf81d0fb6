//! The fleet bridge's numbers for docs/FLEET.md: message sizes, the bridge's publish
//! throughput against a real mosquitto, and a load test of N simulated Sparkplug nodes against
//! that broker (how many one broker holds on this machine).
//!
//!     cargo bench --bench fleet
//!     FLEET_LOAD_NODES=100,1000,3000 FLEET_LOAD_SECONDS=20 cargo bench --bench fleet
//!
//! Needs mosquitto, mosquitto_passwd and openssl (Debian packages); the broker is the tests'
//! (TLS, passwords, ACL), started in a temporary directory.
#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "../tests/suite/fleet/broker.rs"]
mod broker;
#[path = "../tests/suite/fleet/sizes.rs"]
mod sizes;

use bearingd::config::{Broker, FleetConfig};
use bearingd::sinks::fleet::bridge;
use bearingd::sinks::fleet::metrics::MetricBook;
use bearingd::sinks::fleet::node::EdgeNode;
use bearingd::sinks::fleet::sparkplug::Payload;
use broker::{Mosquitto, LOAD_PASSWORD, LOAD_USER};
use rumqttc::v5::mqttbytes::v5::Packet;
use rumqttc::v5::mqttbytes::QoS;
use rumqttc::v5::{AsyncClient, Event, MqttOptions};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

fn now_ms() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_millis() as u64)
}

fn sizes() {
    let t0 = now_ms();
    let s = sizes::measure(t0);
    println!("## message sizes (payload bytes, protobuf)");
    println!(
        "NBIRTH                      {} ({} without the version)",
        s.nbirth, s.nbirth_bare
    );
    println!("DBIRTH (one channel)        {}", s.dbirth);
    println!("DDATA first (all metrics)   {}", s.ddata_first);
    println!("DDATA typical (one window)  {}", s.ddata_typical);
    println!("DDATA flag change           {}", s.ddata_flag);
    println!("DDATA twin fit              {}", s.ddata_twin);
    println!("NDEATH                      {}", s.ndeath);
    println!("topic (DDATA)               {}", s.topic);
    let (mut book, mut node) = sizes::book_and_node();
    node.births(&book, t0);
    let started = Instant::now();
    let n = 20_000u64;
    let mut bytes = 0;
    for i in 0..n {
        bytes += sizes::typical_ddata(&mut book, &mut node, t0 + 10_000 + i * 1000).len();
    }
    let per = started.elapsed().as_secs_f64() / n as f64;
    println!(
        "make + encode a typical DDATA: {:.1} µs ({} bytes avg)\n",
        per * 1e6,
        bytes as u64 / n
    );
}

fn fleet_config(broker: &Mosquitto, dir: &std::path::Path) -> FleetConfig {
    let password = dir.join("load-password");
    std::fs::write(&password, LOAD_PASSWORD).unwrap();
    FleetConfig {
        broker: Broker {
            tls: true,
            host: "localhost".into(),
            port: broker.port,
        },
        group_id: "load".into(),
        node_id: "bridge-bench".into(),
        client_id: "bridge-bench".into(),
        username: Some(LOAD_USER.into()),
        password_file: Some(password),
        ca_file: Some(broker.ca()),
        client_cert_file: None,
        client_key_file: None,
        publish_period_s: 1.0,
        keep_alive_s: 30.0,
        queue_dir: dir.join("bench-queue"),
        queue_max_mb: 256.0,
        primary_host_id: None,
    }
}

/// The real bridge (queue with fsync, QoS 1, 64 in flight, TLS) fed as fast as it takes.
fn bridge_throughput(broker: &Mosquitto, dir: &std::path::Path) {
    let devices: Vec<String> = (0..8).map(|i| format!("m{i}.radial")).collect();
    let notices = std::sync::Arc::new(|line: String| eprintln!("bearingd: {line}"));
    let handle =
        bridge::start(fleet_config(broker, dir), devices.clone(), notices).expect("bridge");
    // Let it connect first: the number is the steady state, not the connect.
    std::thread::sleep(Duration::from_secs(2));
    let n = 40_000u64;
    let t0 = now_ms();
    let started = Instant::now();
    for i in 0..n {
        let device = (i % devices.len() as u64) as usize;
        let at = t0 + (i / devices.len() as u64) * 1000;
        if handle
            .intake
            .blocking_send(sizes::window(device, at, (i % 13) as f64))
            .is_err()
        {
            break;
        }
    }
    drop(handle.intake);
    let summary = handle.thread.join().expect("bridge thread");
    let seconds = started.elapsed().as_secs_f64();
    println!("## bridge publish throughput (TLS, QoS 1, fsynced queue)");
    println!(
        "{} records made, {} acknowledged in {seconds:.1} s: {:.0} records/s acknowledged",
        summary.queue.appended,
        summary.queue.acknowledged,
        summary.queue.acknowledged as f64 / seconds
    );
    println!(
        "one channel makes 1 record/s at the default period: {:.0} channels per bridge\n",
        summary.queue.acknowledged as f64 / seconds
    );
}

fn tls_options(broker: &Mosquitto, client_id: String) -> MqttOptions {
    use rustls::pki_types::pem::PemObject;
    use rustls::pki_types::CertificateDer;
    let mut roots = rustls::RootCertStore::empty();
    for cert in CertificateDer::pem_file_iter(broker.ca()).unwrap() {
        roots.add(cert.unwrap()).unwrap();
    }
    let provider = Arc::new(rustls::crypto::ring::default_provider());
    let tls = rustls::ClientConfig::builder_with_provider(provider)
        .with_safe_default_protocol_versions()
        .unwrap()
        .with_root_certificates(roots)
        .with_no_client_auth();
    let mut options = MqttOptions::new(client_id, "localhost", broker.port);
    options
        .set_keep_alive(Duration::from_secs(60))
        .set_credentials(LOAD_USER, LOAD_PASSWORD)
        .set_connection_timeout(30)
        .set_transport(rumqttc::Transport::tls_with_config(
            rumqttc::TlsConfiguration::Rustls(Arc::new(tls)),
        ));
    options
}

/// CPU seconds (user + system) of a process, from /proc.
fn cpu_seconds(pid: u32) -> f64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
    let after = stat.rsplit_once(')').map_or("", |(_, rest)| rest);
    let fields: Vec<&str> = after.split_whitespace().collect();
    let ticks = |i: usize| {
        fields
            .get(i)
            .and_then(|f| f.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    // After the command: state is 0, utime 11, stime 12.
    (ticks(11) + ticks(12)) / 100.0
}

fn rss_mib(pid: u32) -> f64 {
    std::fs::read_to_string(format!("/proc/{pid}/status"))
        .unwrap_or_default()
        .lines()
        .find(|l| l.starts_with("VmRSS:"))
        .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        .map_or(0.0, |kib| kib / 1024.0)
}

#[derive(Default)]
struct Received {
    count: u64,
    latencies_ms: Vec<u64>,
}

/// N simulated nodes, each one channel publishing a typical DDATA (QoS 1) every second, and
/// one subscriber to all of them.
async fn load(broker: &Mosquitto, nodes: usize, seconds: u64) {
    let pid = broker.pid().expect("broker running");
    let received = Arc::new(Mutex::new(Received::default()));
    let measuring = Arc::new(std::sync::atomic::AtomicBool::new(false));
    // The subscriber.
    let (sub, mut sub_loop) =
        AsyncClient::new(tls_options(broker, format!("load-sub-{nodes}")), 64);
    let sub_task = {
        let received = received.clone();
        let measuring = measuring.clone();
        tokio::spawn(async move {
            loop {
                let event = match sub_loop.poll().await {
                    Ok(event) => event,
                    Err(e) => {
                        eprintln!("load subscriber: {e}; reconnecting");
                        tokio::time::sleep(Duration::from_millis(500)).await;
                        continue;
                    }
                };
                if let Event::Incoming(Packet::ConnAck(_)) = event {
                    let _ = sub.try_subscribe("spBv1.0/load/#", QoS::AtMostOnce);
                }
                if let Event::Incoming(Packet::Publish(p)) = event {
                    if !measuring.load(Ordering::Relaxed) {
                        continue;
                    }
                    let now = now_ms();
                    let stamp = Payload::from_bytes(&p.payload)
                        .ok()
                        .and_then(|p| p.timestamp)
                        .unwrap_or(now);
                    let mut r = received.lock().unwrap();
                    r.count += 1;
                    r.latencies_ms.push(now.saturating_sub(stamp));
                }
            }
        })
    };
    let sent = Arc::new(AtomicU64::new(0));
    let acked = Arc::new(AtomicU64::new(0));
    let errors = Arc::new(AtomicU64::new(0));
    let connected = Arc::new(AtomicU64::new(0));
    let connecting = Arc::new(tokio::sync::Semaphore::new(32));
    let connect_started = Instant::now();
    let mut tasks = Vec::new();
    for i in 0..nodes {
        let mut options = tls_options(broker, format!("load-{nodes}-{i}"));
        // A simulated node has at most one DDATA a second in flight. Unset, rumqttc v5 sizes
        // its inflight table for the broker's receive maximum (65 535 with mosquitto), about
        // 5 MB per client: 2 000 clients ran this 24 GiB machine out of memory.
        options.set_outgoing_inflight_upper_limit(16);
        let (sent, acked, errors, connected, measuring, connecting) = (
            sent.clone(),
            acked.clone(),
            errors.clone(),
            connected.clone(),
            measuring.clone(),
            connecting.clone(),
        );
        tasks.push(tokio::spawn(async move {
            let (client, mut events) = AsyncClient::new(options, 16);
            let permit = connecting.acquire_owned().await.unwrap();
            let mut permit = Some(permit);
            let publisher = {
                let client = client.clone();
                let sent = sent.clone();
                tokio::spawn(async move {
                    let mut book = MetricBook::new(vec!["motor.radial".into()], 1000);
                    let mut node = EdgeNode::new("load", &format!("n{i}"), 1, 0);
                    let topic = format!("spBv1.0/load/DDATA/n{i}/motor.radial");
                    // Spread the nodes over the second.
                    tokio::time::sleep(Duration::from_millis((i as u64 * 997) % 1000)).await;
                    let mut tick = tokio::time::interval(Duration::from_secs(1));
                    let mut last = 0u64;
                    loop {
                        tick.tick().await;
                        // Stamped now (the subscriber's latency), at least a period after the
                        // last (the book makes one record per period).
                        last = now_ms().max(last + 1000);
                        let payload = sizes::typical_ddata(&mut book, &mut node, last);
                        if client
                            .publish(topic.clone(), QoS::AtLeastOnce, false, payload)
                            .await
                            .is_err()
                        {
                            return;
                        }
                        if measuring.load(Ordering::Relaxed) {
                            sent.fetch_add(1, Ordering::Relaxed);
                        }
                    }
                })
            };
            loop {
                match events.poll().await {
                    Ok(Event::Incoming(Packet::ConnAck(_))) => {
                        connected.fetch_add(1, Ordering::Relaxed);
                        permit.take();
                    }
                    Ok(Event::Incoming(Packet::PubAck(_))) => {
                        acked.fetch_add(1, Ordering::Relaxed);
                    }
                    Ok(_) => {}
                    Err(_) => {
                        errors.fetch_add(1, Ordering::Relaxed);
                        permit.take();
                        tokio::time::sleep(Duration::from_secs(1)).await;
                        if publisher.is_finished() {
                            return;
                        }
                    }
                }
            }
        }));
    }
    while (connected.load(Ordering::Relaxed) as usize) < nodes
        && connect_started.elapsed() < Duration::from_secs(120)
    {
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let connect_s = connect_started.elapsed().as_secs_f64();
    tokio::time::sleep(Duration::from_secs(3)).await;
    let cpu0 = cpu_seconds(pid);
    let t0 = Instant::now();
    measuring.store(true, Ordering::Relaxed);
    tokio::time::sleep(Duration::from_secs(seconds)).await;
    measuring.store(false, Ordering::Relaxed);
    let window = t0.elapsed().as_secs_f64();
    let cpu = cpu_seconds(pid) - cpu0;
    let rss = rss_mib(pid);
    for t in &tasks {
        t.abort();
    }
    sub_task.abort();
    let (count, mut latencies) = {
        let mut r = received.lock().unwrap();
        (r.count, std::mem::take(&mut r.latencies_ms))
    };
    latencies.sort_unstable();
    let pct = |q: f64| {
        latencies
            .get(((latencies.len() as f64 - 1.0) * q).round() as usize)
            .copied()
            .unwrap_or(0)
    };
    println!(
        "| {nodes} | {}/{nodes} in {connect_s:.1} s | {:.0} | {:.0} | {} / {} / {} | {:.0} % | {rss:.0} | {} |",
        connected.load(Ordering::Relaxed),
        sent.load(Ordering::Relaxed) as f64 / window,
        count as f64 / window,
        pct(0.5),
        pct(0.99),
        latencies.last().copied().unwrap_or(0),
        100.0 * cpu / window,
        errors.load(Ordering::Relaxed),
    );
    // Let the broker notice the departures before the next round.
    tokio::time::sleep(Duration::from_secs(3)).await;
}

fn main() {
    // `cargo bench` passes --bench; a filter that does not name this bench skips it.
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    if args
        .iter()
        .any(|a| !a.starts_with('-') && !"fleet".contains(a.as_str()))
    {
        return;
    }
    sizes();
    let dir = tempfile::tempdir().expect("a temporary directory");
    let broker = Mosquitto::start(dir.path());
    bridge_throughput(&broker, dir.path());
    let nodes: Vec<usize> = std::env::var("FLEET_LOAD_NODES")
        .unwrap_or_else(|_| "100,500,1000,2000".into())
        .split(',')
        .filter_map(|n| n.trim().parse().ok())
        .collect();
    let seconds: u64 = std::env::var("FLEET_LOAD_SECONDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20);
    println!(
        "## load test: N nodes × 1 channel, one DDATA/s each (QoS 1, TLS), one subscriber to all"
    );
    println!("| nodes | connected | published/s | delivered/s | latency p50 / p99 / max (ms) | broker CPU | broker RSS (MiB) | client errors |");
    println!("|---|---|---|---|---|---|---|---|");
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    for n in nodes {
        runtime.block_on(load(&broker, n, seconds));
    }
}

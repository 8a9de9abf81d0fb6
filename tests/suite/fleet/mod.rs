//! The fleet bridge against a real broker (issue 15): `bearingd run` processes publishing to a
//! mosquitto started by the test (TLS, passwords, client certificates, an ACL), checked by a
//! Python Sparkplug B host (`tests/python/sparkplug_subscriber.py`: paho-mqtt, protobuf from
//! `proto/sparkplug_b.proto`).
//!
//! The slow cases (a 60 s outage in real time) run beside the others: every test has its own
//! broker on its own ports, its own node processes and scratch directory.

mod broker;
mod host;
mod node;
mod sizes;

use broker::{Mosquitto, GROUP, NODES};
use host::Host;
use node::{NodeProcess, NodeSetup};
use serde_json::Value;
use std::path::Path;
use std::time::{Duration, Instant};

fn metric<'a>(message: &'a Value, name: &str) -> Option<&'a Value> {
    message["metrics"].get(name).map(|m| &m["value"])
}

fn of_type<'a>(messages: &'a [Value], kind: &str) -> Vec<&'a Value> {
    messages.iter().filter(|m| m["type"] == kind).collect()
}

/// The bdSeq of every NBIRTH of `node`, in order.
fn births_of(summary: &Value, node: &str) -> Vec<u64> {
    summary["births"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|b| b[0] == node)
        .filter_map(|b| b[1].as_u64())
        .collect()
}

fn assert_no_violations(summary: &Value) {
    assert_eq!(
        summary["violations"],
        serde_json::json!([]),
        "Sparkplug rules broken; summary: {}",
        summary["counts"]
    );
}

/// Metric aliases (issue 33): the host's violations hold the breaks (a birth metric without an
/// alias, an alias declared twice in a node, a DDATA metric with a name or an alias its DBIRTH
/// did not declare); this holds that the checks ran over every birth and every DDATA metric,
/// three sessions' worth here (the first, the rebirth, the restart).
fn assert_aliases_checked(summary: &Value, messages: &[Value]) {
    let aliases = &summary["aliases"];
    let counts = &summary["counts"];
    let births = counts["NBIRTH"].as_u64().unwrap_or(0) + counts["DBIRTH"].as_u64().unwrap_or(0);
    assert!(births >= 6, "{counts}");
    assert_eq!(
        aliases["births"], births,
        "births with every metric aliased: {aliases}"
    );
    let data = of_type(messages, "DDATA");
    let mut by_alias = 0;
    for d in &data {
        for (name, m) in d["metrics"].as_object().unwrap() {
            assert!(
                m["name"].is_null() && m["alias"].is_u64() && !name.starts_with('#'),
                "a DDATA metric not carried by a declared alias alone: {name} {m} in {d}"
            );
            by_alias += 1;
        }
    }
    assert!(data.len() >= 6, "{counts}");
    assert!(
        aliases["ddata_metrics"].as_u64() >= Some(by_alias),
        "{aliases}"
    );
}

#[test]
fn birth_data_rebirth_and_death_on_kill_9_then_a_restart_and_a_clean_stop() {
    let Some(setup) = NodeSetup::prepare("fleet-life") else {
        return;
    };
    let broker = Mosquitto::start(&setup.dir);
    let host = Host::start(&broker, &setup.dir, 3);
    let config = setup.config(&broker, &NODES[0], |_| {});
    let mut node = NodeProcess::start(&setup, &config, &[]);

    // Births, data, the rebirth asked for after 3 DDATA, and a raised flag with its confidence.
    let messages = host.wait_for("a second NBIRTH (rebirth) and a raised flag", 120, |m| {
        of_type(m, "NBIRTH").len() >= 2
            && m.iter().any(|x| {
                x["type"] == "DDATA"
                    && metric(x, "Fault/outer_race/Flag").is_some_and(|f| f != "ok")
            })
    });
    let nbirth = of_type(&messages, "NBIRTH")[0];
    assert_eq!(nbirth["topic"], format!("spBv1.0/{GROUP}/NBIRTH/press-7"));
    assert_eq!(nbirth["seq"], 0);
    let dbirth = of_type(&messages, "DBIRTH")[0];
    assert_eq!(
        dbirth["topic"],
        format!("spBv1.0/{GROUP}/DBIRTH/press-7/motor-de.radial")
    );
    for name in [
        "Sensor/Lost",
        "Health/Stage",
        "Speed/RPM",
        "Vibration/RMS_g",
        "Vibration/Kurtosis",
        "ISO20816/Zone",
        "Twin/Error",
        "Fault/outer_race/Flag",
        "Fault/outer_race/Confidence",
        "Fault/inner_race/Score",
        "Fault/ball/Score",
        "Fault/cage/Score",
    ] {
        assert!(
            dbirth["metrics"].get(name).is_some(),
            "DBIRTH lacks {name}: {dbirth}"
        );
    }
    let data = of_type(&messages, "DDATA");
    let rms: Vec<f64> = data
        .iter()
        .filter_map(|d| metric(d, "Vibration/RMS_g")?.as_f64())
        .collect();
    assert!(
        rms.len() >= 3 && rms.iter().all(|r| *r > 0.0 && *r < 100.0),
        "{rms:?}"
    );
    // The ISO 10816-3 velocity zone and its velocity (issue 16 item 4), from the pipeline.
    let zoned = data
        .iter()
        .find(|d| metric(d, "ISO20816/Zone").is_some_and(Value::is_string))
        .unwrap_or_else(|| panic!("no DDATA with ISO20816/Zone: {data:?}"));
    let zone = metric(zoned, "ISO20816/Zone").and_then(Value::as_str);
    assert!(matches!(zone, Some("A" | "B" | "C" | "D")), "{zoned}");
    let velocity = metric(zoned, "ISO20816/VelocityRMS_mm_s").and_then(Value::as_f64);
    assert!(velocity.is_some_and(|v| v > 0.0 && v < 100.0), "{zoned}");
    let raised = data
        .iter()
        .find(|d| metric(d, "Fault/outer_race/Flag").is_some_and(|f| f != "ok"))
        .unwrap();
    let confidence = metric(raised, "Fault/outer_race/Confidence")
        .and_then(Value::as_f64)
        .unwrap_or(f64::NAN);
    assert!(confidence > 0.0 && confidence <= 1.0, "{raised}");
    assert!(
        metric(raised, "Fault/outer_race/Score")
            .and_then(Value::as_f64)
            .is_some(),
        "{raised}"
    );
    // DDATA every publish period of sample time (1 s), and at once on the flag change.
    let stamps: Vec<u64> = data
        .iter()
        .filter(|d| d["device"] == "motor-de.radial")
        .filter_map(|d| d["timestamp"].as_u64())
        .collect();
    assert!(stamps.windows(2).all(|w| w[1] >= w[0]), "{stamps:?}");

    // kill -9: the broker publishes the Will, the NDEATH of this session's bdSeq.
    node.kill_9();
    let messages = host.wait_for("the NDEATH (Will) after kill -9", 60, |m| {
        !of_type(m, "NDEATH").is_empty()
    });
    let death = of_type(&messages, "NDEATH")[0];
    assert_eq!(metric(death, "bdSeq"), metric(nbirth, "bdSeq"));

    // A restart: the next bdSeq, then a clean stop: DDEATH and NDEATH.
    let node = NodeProcess::start(&setup, &config, &[]);
    host.wait_for("a third NBIRTH after the restart and data", 60, |m| {
        of_type(m, "NBIRTH").len() >= 3
            && m.iter()
                .rev()
                .take_while(|x| x["type"] != "NBIRTH")
                .any(|x| x["type"] == "DDATA")
    });
    let stopped = node.terminate();
    assert!(stopped.success, "{}", stopped.stderr);
    assert!(
        stopped.stderr.contains("left in the queue") && stopped.stderr.contains("0 dropped"),
        "{}",
        stopped.stderr
    );
    let messages = host.wait_for("the DDEATH and NDEATH of the clean stop", 30, |m| {
        of_type(m, "NDEATH").len() >= 2
    });
    assert!(!of_type(&messages, "DDEATH").is_empty());
    let host_messages = messages;

    let summary = host.finish();
    assert_no_violations(&summary);
    assert_aliases_checked(&summary, &host_messages);
    let births = births_of(&summary, "press-7");
    assert_eq!(births.len(), 3, "{}", summary["births"]);
    assert_eq!(births[1], births[0], "a rebirth keeps the bdSeq");
    assert_eq!(
        births[2],
        (births[0] + 1) % 256,
        "a new process, the next bdSeq"
    );
    let deaths = summary["deaths"].as_array().unwrap();
    assert_eq!(deaths.len(), 2, "{deaths:?}");
    assert!(
        deaths.iter().all(|d| d[2] == true),
        "each NDEATH carries its session's bdSeq: {deaths:?}"
    );
    // Across the kill, nothing the queue held is missing.
    assert_records_complete_in_order(&summary["records"], 0);
    drop(broker);
}

#[test]
fn a_wrong_password_a_foreign_node_id_and_a_wrong_ca_are_refused_and_said_clearly() {
    let Some(setup) = NodeSetup::prepare("fleet-security") else {
        return;
    };
    let broker = Mosquitto::start(&setup.dir);
    let host = Host::start(&broker, &setup.dir, 0);
    let [press7, press8] = &NODES;

    let wrong_password = setup.config(&broker, press7, |c| {
        c.password = "not-the-password".into();
        c.name = "wrong-password".into();
    });
    // press-8's user publishing as node press-7: the ACL allows it its own node id only.
    let foreign_node = setup.config(&broker, press8, |c| {
        c.node_id = "press-7".into();
        c.name = "foreign-node".into();
    });
    let wrong_ca = setup.config(&broker, press7, |c| {
        c.ca_file = broker.dir.join("other-ca.pem");
        c.name = "wrong-ca".into();
    });
    // A node authenticated by its client certificate (CN press-9) on the second listener.
    let by_certificate = setup.config(&broker, press7, |c| {
        c.node_id = broker.client_cn.clone();
        c.port = broker.cert_port;
        c.username = None;
        c.client_cert = Some((broker.dir.join("client.pem"), broker.dir.join("client.key")));
        c.name = "certificate".into();
    });
    let nodes: Vec<NodeProcess> = [&wrong_password, &foreign_node, &wrong_ca, &by_certificate]
        .into_iter()
        .map(|c| NodeProcess::start(&setup, c, &[]))
        .collect();

    let expectations = [
        (
            &nodes[0],
            vec![
                "REFUSED the connection",
                "fleet.username (press-7)",
                "fleet.password_file",
            ],
        ),
        (&nodes[1], vec!["REFUSED", "ACL", "fleet.node_id"]),
        (&nodes[2], vec!["TLS failed", "fleet.ca_file"]),
    ];
    for (node, phrases) in &expectations {
        node.wait_for_stderr(&phrases.join(" + "), 60, |text| {
            phrases.iter().all(|p| text.contains(p))
        });
    }
    let messages = host.wait_for("the certificate node's birth and data", 60, |m| {
        m.iter()
            .any(|x| x["type"] == "DDATA" && x["node"] == broker.client_cn.as_str())
    });
    for node in nodes {
        let out = node.terminate();
        assert!(out.success, "{}", out.stderr);
    }
    let summary = host.finish();
    assert_no_violations(&summary);
    assert!(
        messages
            .iter()
            .all(|m| m["node"] == broker.client_cn.as_str()),
        "only the certificate node got through: {:?}",
        messages.iter().map(|m| &m["topic"]).collect::<Vec<_>>()
    );
    let log = broker.log();
    assert!(
        log.contains("not authorised") || log.contains("Denied PUBLISH"),
        "{log}"
    );
}

#[test]
fn store_and_forward_through_a_broker_restart_a_60_s_outage_and_a_kill_9() {
    let Some(setup) = NodeSetup::prepare("fleet-outage") else {
        return;
    };
    let mut broker = Mosquitto::start(&setup.dir);
    let host = Host::start(&broker, &setup.dir, 0);
    let config = setup.config(&broker, &NODES[0], |_| {});
    let mut node = NodeProcess::start(&setup, &config, &[]);
    let records_seen = |m: &[Value]| of_type(m, "DDATA").len();

    host.wait_for("5 DDATA", 60, |m| records_seen(m) >= 5);
    // The broker restarted mid-run.
    broker.down();
    broker.up();
    let before = records_seen(&host.messages());
    host.wait_for("5 more DDATA after the broker's restart", 60, |m| {
        records_seen(m) >= before + 5
    });

    // Down for 60 s of (real-time) simulated data; the node is killed half-way and restarted.
    broker.down();
    let down_ms = host::now_ms();
    std::thread::sleep(Duration::from_secs(30));
    node.kill_9();
    let node = NodeProcess::start(&setup, &config, &[]);
    std::thread::sleep(Duration::from_secs(30));
    broker.up();
    let up_ms = host::now_ms();
    let restarted = node.wait_for_stderr("the records from before the restart", 10, |t| {
        t.contains("records from before the restart wait")
    });
    assert!(restarted.contains("wait in"), "{restarted}");

    // The backlog goes first, in order; then live data again.
    host.wait_for("a live DDATA after the backlog", 90, |m| {
        m.iter().any(|x| {
            x["type"] == "DDATA"
                && x["received_ms"].as_u64() > Some(up_ms)
                && x["timestamp"].as_u64() > Some(up_ms)
        })
    });
    let stopped = node.terminate();
    assert!(stopped.success, "{}", stopped.stderr);
    let summary = host.finish();
    assert_no_violations(&summary);
    let records = &summary["records"];
    // The node had retried for 30 s when the broker came back, so its pauses were at their
    // longest: the broker is used within 5 s all the same (issue 33).
    let first_back_ms = summary["record_list"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|r| r["received_ms"].as_u64())
        .filter(|&t| t >= up_ms)
        .min()
        .expect("records arrived after the broker came back");
    eprintln!(
        "the returning broker was used {} ms after it came back",
        first_back_ms - up_ms
    );
    assert!(
        first_back_ms - up_ms <= 5_000,
        "the returning broker was used only {} ms after it came back (at most 5 s)",
        first_back_ms - up_ms
    );
    assert_records_complete_in_order(records, 0);
    let list = summary["record_list"].as_array().unwrap();
    let during_outage: Vec<&Value> = list
        .iter()
        .filter(|r| {
            let t = r["timestamp"].as_u64().unwrap();
            t > down_ms + 1000 && t < up_ms - 1000
        })
        .collect();
    // A record at the first window hop (0.64 s here) at least 1 s after the previous one: one
    // per 1.28 s, 47 in 60 s, less the seconds the restarted node spent starting and filling
    // its first window.
    assert!(
        during_outage.len() >= 38,
        "{} records of the 60 s outage arrived: {records}",
        during_outage.len()
    );
    for r in &during_outage {
        assert_eq!(r["historical"], true, "{r}");
        assert!(
            r["received_ms"].as_u64() >= Some(up_ms),
            "sent after the broker came back, with its original time: {r}"
        );
    }
    let stamps: Vec<u64> = during_outage
        .iter()
        .map(|r| r["timestamp"].as_u64().unwrap())
        .collect();
    let gaps: Vec<u64> = stamps.windows(2).map(|w| w[1] - w[0]).collect();
    let long_gaps = gaps.iter().filter(|g| **g > 2000).count();
    assert!(
        long_gaps <= 1,
        "only the kill -9 and restart may leave a gap in the data: {gaps:?}"
    );
}

#[test]
fn a_full_queue_drops_the_oldest_counts_them_and_sends_the_rest_in_order() {
    let Some(setup) = NodeSetup::prepare("fleet-full") else {
        return;
    };
    let mut broker = Mosquitto::start(&setup.dir);
    broker.down();
    let config = setup.config(&broker, &NODES[0], |c| c.queue_max_mb = 0.02);
    // 300 s of sample time, as fast as the analysis goes, while the broker is down.
    let first = NodeProcess::start(&setup, &config, &["--fast", "--duration", "300"]).wait(120);
    assert!(first.success, "{}", first.stderr);
    assert!(first.stderr.contains("queue full"), "{}", first.stderr);
    let dropped = summary_count(&first.stderr, " dropped (queue full)");
    let left = summary_count(&first.stderr, " left in the queue");
    assert!(dropped > 100, "{}", first.stderr);
    assert!(left > 5, "{}", first.stderr);

    broker.up();
    let host = Host::start(&broker, &setup.dir, 0);
    let started = Instant::now();
    // In real time, so that the bridge is connected for 10 s before the stop: a `--fast` run
    // of a few seconds of sample time ended after about a second, and under load the stop's
    // 3 s grace did not always deliver the whole backlog (the test failed with 42 of them).
    let second = NodeProcess::start(&setup, &config, &["--duration", "10"]).wait(60);
    assert!(second.success, "{}", second.stderr);
    assert!(
        second
            .stderr
            .contains(&format!("{left} records from before the restart wait")),
        "{}",
        second.stderr
    );
    host.wait_for("the queued records", 30, |m| {
        of_type(m, "DDATA").len() as u64 >= left
    });
    let summary = host.finish();
    assert_no_violations(&summary);
    let records = &summary["records"];
    // The oldest were dropped: what arrives starts right after them, without a hole.
    assert_eq!(records["first"], dropped, "{records}");
    assert_eq!(records["missing"], serde_json::json!([]), "{records}");
    // In time order within each run; `--fast` maps 300 s of sample time from the first run's
    // start, so the second run's first record (number dropped + left) is stamped before the
    // first run's last ones.
    let order = records["out_of_order"].as_array().unwrap();
    assert!(
        order.is_empty() || order == &[serde_json::json!(dropped + left)],
        "{records}"
    );
    assert!(records["historical"].as_u64() >= Some(left), "{records}");
    eprintln!(
        "full queue: {dropped} dropped, {left} kept and delivered in {:.1} s",
        started.elapsed().as_secs_f64()
    );
}

/// Each message's topic and seq, for a failure's message.
fn topics(messages: &[Value]) -> Vec<String> {
    messages
        .iter()
        .map(|m| format!("{} seq {}", m["topic"], m["seq"]))
        .collect()
}

/// The Sparkplug 3.0 STATE payload of a primary host.
fn state(online: bool, timestamp: u64) -> String {
    format!("{{\"online\": {online}, \"timestamp\": {timestamp}}}")
}

#[test]
fn with_a_primary_host_nothing_is_published_while_it_is_offline_and_nothing_is_lost() {
    const PRIMARY: &str = "scada-1";
    let Some(setup) = NodeSetup::prepare("fleet-primary") else {
        return;
    };
    let broker = Mosquitto::start(&setup.dir);
    let mut host = Host::start(&broker, &setup.dir, 0);
    let from_node = |m: &[Value]| -> Vec<Value> {
        m.iter()
            .filter(|x| x["node"] == "press-7")
            .cloned()
            .collect()
    };
    let t0 = host::now_ms();
    // The host is offline (its retained STATE) when the node connects.
    host.publish_state(PRIMARY, true, &state(false, t0));
    let config = setup.config(&broker, &NODES[0], |c| {
        c.primary_host_id = Some(PRIMARY.into());
    });
    let node = NodeProcess::start(&setup, &config, &[]);
    node.wait_for_stderr("the connection, waiting for the primary host", 60, |t| {
        t.contains("waiting for primary host scada-1 to be online (spBv1.0/STATE/scada-1)")
    });
    // Connected and making records (one per 1.28 s): nothing published, all queued.
    std::thread::sleep(Duration::from_secs(4));
    let early = from_node(&host.messages());
    assert!(
        early.is_empty(),
        "published while the host is offline: {:?}",
        topics(&early)
    );

    // Online: NBIRTH, DBIRTH, then the queued records in order, then live data.
    let online_ms = host::now_ms();
    host.publish_state(PRIMARY, true, &state(true, t0 + 1));
    let messages = host.wait_for("births and 6 DDATA after the host came online", 60, |m| {
        of_type(&from_node(m), "DDATA").len() >= 6
    });
    let messages = from_node(&messages);
    let kinds: Vec<&str> = messages.iter().filter_map(|m| m["type"].as_str()).collect();
    assert_eq!(kinds[..3], ["NBIRTH", "DBIRTH", "DDATA"], "{kinds:?}");
    let first = &messages[2];
    assert_eq!(
        metric(first, "bearingd/Record"),
        Some(&Value::from(0)),
        "{first}"
    );
    assert!(
        first["timestamp"].as_u64() < Some(online_ms),
        "the first record is from the offline time: {first}"
    );
    let said = node.wait_for_stderr("the births notice", 10, |t| {
        t.contains("primary host scada-1 is online: births sent, then")
    });
    let queued = said
        .split("births sent, then ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .and_then(|n| n.parse::<u64>().ok())
        .unwrap_or(0);
    assert!(queued >= 1, "records were queued while offline: {said}");

    // Offline again: publishing stops at once, the session stays up.
    host.publish_state(PRIMARY, true, &state(false, t0 + 2));
    node.wait_for_stderr("the pause", 30, |t| {
        t.contains("primary host scada-1 is offline")
    });
    std::thread::sleep(Duration::from_millis(500)); // what was on its way
    let paused = from_node(&host.messages()).len();
    // An online STATE older than the offline one, and a payload that is no STATE: both said,
    // counted, ignored.
    host.publish_state(PRIMARY, false, &state(true, t0 + 1));
    host.publish_state(PRIMARY, false, "bogus");
    node.wait_for_stderr("the two ignored STATEs", 30, |t| {
        t.contains("older than the newest seen") && t.contains("\"bogus\": neither")
    });
    std::thread::sleep(Duration::from_secs(3));
    let later = from_node(&host.messages());
    assert_eq!(
        later.len(),
        paused,
        "published while the host is offline: {:?}",
        topics(&later[paused..])
    );

    // Online again: a rebirth (same bdSeq, seq from 0), then what waited, then live data.
    host.publish_state(PRIMARY, true, &state(true, t0 + 3));
    host.wait_for("the rebirth and 3 DDATA after it", 60, |m| {
        let m = from_node(m);
        of_type(&m, "NBIRTH").len() >= 2
            && m.iter()
                .rev()
                .take_while(|x| x["type"] != "NBIRTH")
                .filter(|x| x["type"] == "DDATA")
                .count()
                >= 3
    });
    let stopped = node.terminate();
    assert!(stopped.success, "{}", stopped.stderr);
    assert!(
        stopped.stderr.contains(
            "primary host scada-1: online 2 times, offline 1 times; 2 STATE messages ignored \
             (1 unreadable, 1 older than the newest)"
        ),
        "{}",
        stopped.stderr
    );
    let summary = host.finish();
    assert_no_violations(&summary);
    let births = births_of(&summary, "press-7");
    assert_eq!(births.len(), 2, "{}", summary["births"]);
    assert_eq!(
        births[1], births[0],
        "one MQTT session: the rebirth keeps the bdSeq"
    );
    let records = &summary["records"];
    assert_records_complete_in_order(records, 0);
    assert_eq!(records["resent"], serde_json::json!([]), "{records}");
    // What waited for the host is marked historical, both times.
    assert!(
        records["historical"].as_u64() >= Some(queued + 1),
        "{records}"
    );
}

/// The number before `what` in the bridge's summary line.
fn summary_count(stderr: &str, what: &str) -> u64 {
    let line = stderr
        .lines()
        .rev()
        .find(|l| l.contains("records made"))
        .unwrap_or_else(|| panic!("no fleet summary in {stderr}"));
    let before = &line[..line
        .find(what)
        .unwrap_or_else(|| panic!("no {what:?} in {line}"))];
    before
        .rsplit(|c: char| !c.is_ascii_digit())
        .next()
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no number before {what:?} in {line}"))
}

/// docs/FLEET.md's table of message sizes against the messages the edge node makes now (no
/// broker needed): a metric added to the catalog changes the DBIRTH, and the table must say so.
#[test]
fn the_documented_message_sizes_are_the_measured_ones() {
    // A fixed stamp of today's length (6-byte varints until 2039), so that the sizes are fixed.
    let s = sizes::measure(1_795_000_000_000);
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/FLEET.md");
    let doc = std::fs::read_to_string(&path).unwrap();
    let section: Vec<&str> = doc
        .lines()
        .skip_while(|l| !l.starts_with("**Message sizes**"))
        .take_while(|l| !l.starts_with("Making and encoding"))
        .collect();
    assert!(
        !section.is_empty(),
        "no **Message sizes** in {}",
        path.display()
    );
    let numbers = |text: &str| -> Vec<usize> {
        text.split(|c: char| !c.is_ascii_digit())
            .filter_map(|n| n.parse().ok())
            .collect()
    };
    let expected = [
        ("NBIRTH", vec![s.nbirth, s.nbirth_bare]),
        ("DBIRTH", vec![s.dbirth]),
        ("DDATA, first", vec![s.ddata_first]),
        ("DDATA, typical", vec![s.ddata_typical]),
        ("DDATA, flag change", vec![s.ddata_flag]),
        ("DDATA, twin fit", vec![s.ddata_twin]),
        ("NDEATH", vec![s.ndeath]),
    ];
    let mut wrong = Vec::new();
    for (label, measured) in &expected {
        let row = section
            .iter()
            .find(|l| l.starts_with(&format!("| {label}")))
            .unwrap_or_else(|| panic!("no row {label:?} in the table of {}", path.display()));
        let said = numbers(row.rsplit('|').nth(1).unwrap_or(""));
        if &said != measured {
            wrong.push(format!(
                "{label}: the table says {said:?}, measured {measured:?}"
            ));
        }
    }
    let heading = section.join(" ");
    if !heading.contains(&format!("{}` {} bytes", sizes::DEVICE, s.topic)) {
        wrong.push(format!("the DDATA topic: measured {} bytes", s.topic));
    }
    let births = format!(
        "({:.1} KB per channel)",
        (s.nbirth + s.dbirth) as f64 / 1000.0
    );
    if !doc.contains(&births) {
        wrong.push(format!("births per channel: measured {births}"));
    }
    assert!(
        wrong.is_empty(),
        "docs/FLEET.md's message sizes are stale; write the measured ones (cargo bench --bench \
         fleet prints them too):\n{}",
        wrong.join("\n")
    );
}

/// The test host's `records` summary: numbered from `first`, none missing, none out of order.
fn assert_records_complete_in_order(records: &Value, first: u64) {
    assert_eq!(records["first"], first, "{records}");
    assert_eq!(
        records["missing"],
        serde_json::json!([]),
        "records lost: {records}"
    );
    assert_eq!(records["out_of_order"], serde_json::json!([]), "{records}");
}

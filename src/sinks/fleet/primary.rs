//! Sparkplug B 3.0 primary host awareness, sans-IO: the STATE payload read, and whether the
//! edge node may publish now (`fleet.primary_host_id`, docs/FLEET.md "The primary host").
//!
//! A primary host (the SCADA or historian that must not miss data) publishes its state, retained
//! and at QoS 1, on `spBv1.0/STATE/<host_id>`: `{"online": true|false, "timestamp": <ms>}`
//! (Sparkplug 3.0), with the offline one as its MQTT Will. An edge node configured with that
//! host subscribes to the topic before its births and publishes births and data only while the
//! latest STATE says online; meanwhile its records stay in the store-and-forward queue.
//!
//! Rules kept here:
//! - until a STATE arrives in a session the host counts as offline (the retained STATE comes
//!   right after the subscription);
//! - a STATE whose `timestamp` is older than the newest one seen by this process is ignored
//!   (an old retained message from a broker replica, a late Will); the newest timestamp is kept
//!   across sessions;
//! - Sparkplug 2.2's plain `ONLINE` / `OFFLINE` (no timestamp) is read as a courtesy and is
//!   never stale;
//! - anything else is unreadable: reported, counted, and changes nothing.

use super::node::NAMESPACE;

/// The longest piece of an unreadable payload quoted in a notice.
const QUOTE_BYTES: usize = 48;

/// A STATE message, read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HostState {
    pub online: bool,
    /// Milliseconds since the epoch; `None` for Sparkplug 2.2's plain text.
    pub timestamp: Option<u64>,
}

/// Why a STATE payload was not read; says what was expected.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum StateError {
    #[error("an empty payload (the retained STATE was cleared)")]
    Empty,
    #[error(
        "{quote}: neither Sparkplug 3.0 JSON {{\"online\": true|false, \"timestamp\": <ms>}} nor \
         Sparkplug 2.2 ONLINE/OFFLINE ({why})"
    )]
    Unreadable { quote: String, why: String },
}

/// Reads a STATE payload: Sparkplug 3.0 JSON, or Sparkplug 2.2's plain `ONLINE`/`OFFLINE`.
pub fn parse_state(payload: &[u8]) -> Result<HostState, StateError> {
    let unreadable = |why: &str| StateError::Unreadable {
        quote: quote(payload),
        why: why.to_string(),
    };
    let text = payload.trim_ascii();
    if text.is_empty() {
        return Err(StateError::Empty);
    }
    match text {
        b"ONLINE" => {
            return Ok(HostState {
                online: true,
                timestamp: None,
            })
        }
        b"OFFLINE" => {
            return Ok(HostState {
                online: false,
                timestamp: None,
            })
        }
        _ => {}
    }
    let value: serde_json::Value =
        serde_json::from_slice(text).map_err(|e| unreadable(&format!("not JSON: {e}")))?;
    let object = value
        .as_object()
        .ok_or_else(|| unreadable("JSON, but not an object"))?;
    let online = match object.get("online") {
        Some(serde_json::Value::Bool(b)) => *b,
        Some(_) => return Err(unreadable("\"online\" is not true or false")),
        None => return Err(unreadable("no \"online\"")),
    };
    let timestamp = match object.get("timestamp") {
        Some(t) => t
            .as_u64()
            .ok_or_else(|| unreadable("\"timestamp\" is not a whole number of milliseconds"))?,
        None => return Err(unreadable("no \"timestamp\"")),
    };
    Ok(HostState {
        online,
        timestamp: Some(timestamp),
    })
}

/// The start of a payload, printable, for a notice.
fn quote(payload: &[u8]) -> String {
    let shown = &payload[..payload.len().min(QUOTE_BYTES)];
    let more = if payload.len() > QUOTE_BYTES {
        "…"
    } else {
        ""
    };
    format!("{:?}{more}", String::from_utf8_lossy(shown))
}

/// What a STATE message changed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum StateChange {
    /// Offline (or not yet known) → online: the births, then the queued records.
    CameOnline,
    /// Online → offline: publishing stops; the records wait in the queue.
    WentOffline,
    /// The same state again.
    Unchanged,
    /// Older than the newest STATE seen: ignored.
    Stale { timestamp: u64, newest: u64 },
    /// Not a STATE payload: ignored.
    Unreadable(StateError),
}

/// What the STATE messages did, for the bridge's summary.
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize)]
pub struct HostStats {
    pub host_id: String,
    /// Offline → online transitions (each followed by births).
    pub came_online: u64,
    pub went_offline: u64,
    /// STATE payloads that were neither form, ignored.
    pub unreadable: u64,
    /// STATE messages older than the newest seen, ignored.
    pub stale: u64,
}

/// The primary host as this edge node knows it.
#[derive(Debug, Clone)]
pub struct PrimaryHost {
    topic: String,
    online: bool,
    newest: Option<u64>,
    stats: HostStats,
}

impl PrimaryHost {
    /// `host_id`: the validated `fleet.primary_host_id` (no `/`, `+`, `#`).
    pub fn new(host_id: &str) -> Self {
        PrimaryHost {
            topic: format!("{NAMESPACE}/STATE/{host_id}"),
            online: false,
            newest: None,
            stats: HostStats {
                host_id: host_id.to_string(),
                ..HostStats::default()
            },
        }
    }

    pub fn id(&self) -> &str {
        &self.stats.host_id
    }

    /// The topic to subscribe to (QoS 1) before anything is published.
    pub fn topic(&self) -> &str {
        &self.topic
    }

    /// Whether births and data may be published now.
    pub fn is_online(&self) -> bool {
        self.online
    }

    pub fn stats(&self) -> &HostStats {
        &self.stats
    }

    /// A new MQTT session: offline until its first STATE (the retained one) says otherwise.
    pub fn new_session(&mut self) {
        self.online = false;
    }

    /// Takes a STATE payload received on [`Self::topic`].
    pub fn on_state(&mut self, payload: &[u8]) -> StateChange {
        let state = match parse_state(payload) {
            Ok(state) => state,
            Err(e) => {
                self.stats.unreadable += 1;
                return StateChange::Unreadable(e);
            }
        };
        if let (Some(timestamp), Some(newest)) = (state.timestamp, self.newest) {
            if timestamp < newest {
                self.stats.stale += 1;
                return StateChange::Stale { timestamp, newest };
            }
        }
        if state.timestamp.is_some() {
            self.newest = state.timestamp;
        }
        match (self.online, state.online) {
            (false, true) => {
                self.online = true;
                self.stats.came_online += 1;
                StateChange::CameOnline
            }
            (true, false) => {
                self.online = false;
                self.stats.went_offline += 1;
                StateChange::WentOffline
            }
            _ => StateChange::Unchanged,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn json(online: bool, timestamp: u64) -> Vec<u8> {
        format!("{{\"online\": {online}, \"timestamp\": {timestamp}}}").into_bytes()
    }

    #[test]
    fn the_3_0_json_and_the_2_2_text_are_read() {
        assert_eq!(
            parse_state(&json(true, 1668114759262)),
            Ok(HostState {
                online: true,
                timestamp: Some(1668114759262)
            })
        );
        assert_eq!(
            parse_state(br#"{"timestamp":5,"online":false,"extra":"ignored"}"#),
            Ok(HostState {
                online: false,
                timestamp: Some(5)
            })
        );
        for (text, online) in [
            (&b"ONLINE"[..], true),
            (b"OFFLINE", false),
            (b" ONLINE\n", true),
        ] {
            assert_eq!(
                parse_state(text),
                Ok(HostState {
                    online,
                    timestamp: None
                })
            );
        }
    }

    #[test]
    fn anything_else_is_unreadable_and_says_why() {
        assert_eq!(parse_state(b""), Err(StateError::Empty));
        assert_eq!(parse_state(b" \n"), Err(StateError::Empty));
        let cases: [(&[u8], &str); 10] = [
            (b"online", "not JSON"),
            (b"Online", "not JSON"),
            (b"\xff\xfe\x00", "not JSON"),
            (b"[true, 1]", "not an object"),
            (b"true", "not an object"),
            (
                br#"{"online": "true", "timestamp": 1}"#,
                "\"online\" is not",
            ),
            (br#"{"timestamp": 1}"#, "no \"online\""),
            (br#"{"online": true}"#, "no \"timestamp\""),
            (br#"{"online": true, "timestamp": -1}"#, "whole number"),
            (br#"{"online": true, "timestamp": 1.5}"#, "whole number"),
        ];
        for (payload, why) in cases {
            let error = parse_state(payload).unwrap_err().to_string();
            assert!(error.contains(why), "{payload:?}: {error}");
            assert!(error.contains("Sparkplug 3.0 JSON"), "{error}");
        }
        // A long payload is quoted in part.
        let long = vec![b'x'; 10_000];
        let error = parse_state(&long).unwrap_err().to_string();
        assert!(error.len() < 300, "{error}");
        assert!(error.contains('…'), "{error}");
    }

    #[test]
    fn offline_until_the_first_online_then_each_transition_once() {
        let mut host = PrimaryHost::new("scada-1");
        assert_eq!(host.topic(), "spBv1.0/STATE/scada-1");
        assert!(!host.is_online(), "unknown counts as offline");
        assert_eq!(host.on_state(&json(false, 10)), StateChange::Unchanged);
        assert!(!host.is_online());
        assert_eq!(host.on_state(&json(true, 11)), StateChange::CameOnline);
        assert!(host.is_online());
        // A repeat (the same retained message again) changes nothing.
        assert_eq!(host.on_state(&json(true, 11)), StateChange::Unchanged);
        assert_eq!(host.on_state(&json(false, 12)), StateChange::WentOffline);
        assert!(!host.is_online());
        assert_eq!(host.on_state(&json(true, 13)), StateChange::CameOnline);
        assert_eq!(host.stats().came_online, 2);
        assert_eq!(host.stats().went_offline, 1);
    }

    #[test]
    fn an_older_state_is_ignored_and_counted() {
        let mut host = PrimaryHost::new("h");
        assert_eq!(host.on_state(&json(true, 100)), StateChange::CameOnline);
        // The old host's Will, delivered late: older than the online, ignored.
        assert_eq!(
            host.on_state(&json(false, 99)),
            StateChange::Stale {
                timestamp: 99,
                newest: 100
            }
        );
        assert!(host.is_online());
        assert_eq!(host.stats().stale, 1);
        // Equal is not older.
        assert_eq!(host.on_state(&json(false, 100)), StateChange::WentOffline);
    }

    #[test]
    fn a_new_session_waits_for_its_state_and_keeps_the_newest_timestamp() {
        let mut host = PrimaryHost::new("h");
        host.on_state(&json(true, 100));
        host.new_session();
        assert!(!host.is_online(), "no births before the session's STATE");
        // A broker replica's older retained STATE is not believed in the new session either.
        assert!(matches!(
            host.on_state(&json(true, 50)),
            StateChange::Stale { .. }
        ));
        assert!(!host.is_online());
        assert_eq!(host.on_state(&json(true, 100)), StateChange::CameOnline);
    }

    #[test]
    fn unreadable_payloads_change_nothing_and_are_counted() {
        let mut host = PrimaryHost::new("h");
        host.on_state(&json(true, 100));
        for payload in [&b"garbage"[..], b"", b"{\"online\": false}"] {
            assert!(matches!(host.on_state(payload), StateChange::Unreadable(_)));
            assert!(host.is_online());
        }
        assert_eq!(host.stats().unreadable, 3);
        // The 2.2 text is never stale (it has no timestamp) and keeps the newest one.
        assert_eq!(host.on_state(b"OFFLINE"), StateChange::WentOffline);
        assert_eq!(host.on_state(b"ONLINE"), StateChange::CameOnline);
        assert!(matches!(
            host.on_state(&json(false, 99)),
            StateChange::Stale { .. }
        ));
    }
}
